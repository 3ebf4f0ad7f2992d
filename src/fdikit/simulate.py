"""Simulate a plant under a fault scenario, with seeded noise, into a :class:`Trace`.

Linear plants (:class:`FaultModel`) are propagated exactly at the sample time
(zero-order hold on every input); nonlinear plants (:class:`NonlinearPlant`) are
integrated between samples by fixed-step RK4 or :func:`scipy.integrate.solve_ivp`
with the inputs held.  Actuator faults change the commanded control before the
plant, sensor faults change the measurement after the sensor noise (a stuck sensor
reads a frozen, noise-free value).

Parameter-varying plants (a family ``ρ -> discrete FaultModel`` and a measured schedule ρ)
are simulated by :func:`simulate_scheduled` with ρ frozen over each sample, the "complete
discretisation" of van der Ploeg 2018, Sec. 4-3-4; faults act as in :func:`simulate`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from fdikit.errors import DataError, ModelError
from fdikit.faults import FaultScenario
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.trace import Trace

__all__ = ["NonlinearPlant", "simulate", "simulate_scheduled", "time_grid"]


@dataclass(frozen=True)
class NonlinearPlant:
    """A nonlinear plant ``x' = f(t, x, u)``, ``y = h(t, x, u)`` with named signals.

    ``f`` and ``h`` take and return 1-D arrays.  ``x0`` is the default initial state.
    """

    f: Callable[[float, np.ndarray, np.ndarray], np.ndarray]
    h: Callable[[float, np.ndarray, np.ndarray], np.ndarray]
    states: tuple[str, ...]
    outputs: tuple[str, ...]
    controls: tuple[str, ...]
    x0: np.ndarray | None = None

    def __post_init__(self) -> None:
        for attr in ("states", "outputs", "controls"):
            object.__setattr__(self, attr, tuple(getattr(self, attr)))
        x0 = np.zeros(len(self.states)) if self.x0 is None else np.asarray(self.x0, dtype=float)
        if x0.shape != (len(self.states),):
            raise ModelError(f"x0 has shape {x0.shape}, need ({len(self.states)},) — one value per state")
        object.__setattr__(self, "x0", x0)


def time_grid(duration: float, dt: float) -> np.ndarray:
    """``0, dt, 2 dt, …`` up to and including ``duration`` (rounded to whole samples)."""
    if not (np.isfinite(dt) and dt > 0):
        raise DataError(f"sample time dt must be positive, got {dt}")
    if not (np.isfinite(duration) and duration >= 0):
        raise DataError(f"duration must be >= 0, got {duration}")
    return np.arange(int(round(duration / dt)) + 1) * dt


def _signal(name: str, value, t: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """(N, k) block from None (zeros), an array, or a callable ``t -> (k,)``."""
    k, N = len(names), t.size
    if value is None:
        return np.zeros((N, k))
    if callable(value):
        value = np.array([np.atleast_1d(value(tk)) for tk in t], dtype=float)
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and k == 1:
        arr = arr.reshape(-1, 1)
    if arr.shape != (N, k):
        raise DataError(f"{name} has shape {arr.shape}; need ({N}, {k}): one row per sample, columns {list(names)}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name} has non-finite values; inputs to a simulation must be finite")
    return arr


def _covariance(name: str, value, k: int) -> np.ndarray | None:
    """Covariance from None, a scalar/vector of standard deviations, or a k x k matrix."""
    if value is None:
        return None
    if k == 0:
        raise DataError(f"{name} was given but there is no signal for it (the model has no noise inputs w); "
                        "add a noise group (FaultModel(..., Bw=..., noise=[...])) or omit it")
    arr = np.asarray(value, dtype=float)
    if arr.ndim <= 1:
        std = np.broadcast_to(arr, (k,)) if arr.size in (1, k) else None
        if std is None:
            raise DataError(f"{name} has {arr.size} standard deviations; need 1 or {k}")
        arr = np.diag(np.asarray(std) ** 2)
    if arr.shape != (k, k) or not np.allclose(arr, arr.T) or np.linalg.eigvalsh(arr).min() < -1e-12 * max(
        1.0, np.abs(arr).max()
    ):
        raise DataError(f"{name} must be a symmetric positive semidefinite {k}x{k} covariance (or std vector)")
    return arr


def _gaussian(rng: np.random.Generator, cov: np.ndarray, N: int) -> np.ndarray:
    # eigen-factor: works for semidefinite covariances (a zero std is allowed)
    w, V = np.linalg.eigh(cov)
    L = V * np.sqrt(np.clip(w, 0.0, None))
    return rng.standard_normal((N, cov.shape[0])) @ L.T


def simulate(
    plant: FaultModel | NonlinearPlant,
    scenario: FaultScenario | None = None,
    *,
    duration: float | None = None,
    dt: float | None = None,
    t: np.ndarray | None = None,
    u=None,
    d=None,
    x0=None,
    noise_cov=None,
    measurement_noise=None,
    rng: np.random.Generator | int | None = None,
    method: str = "rk4",
    substeps: int = 4,
    meta: dict | None = None,
) -> Trace:
    """Simulate ``plant`` under ``scenario`` and return a :class:`Trace`.

    Parameters
    ----------
    plant : FaultModel or NonlinearPlant
        A continuous FaultModel is discretised exactly (ZOH) at the sample time; a
        discrete one runs at its own ``dt``.
    scenario : FaultScenario, optional
        Faults on the plant's named sensors (outputs) and actuators (controls).
    duration, dt, t :
        Either ``t`` (uniform sample times) or ``duration`` and ``dt``.
    u, d : array (N, m) or callable ``t -> (m,)``, optional
        Commanded controls and disturbances (zero when omitted).
    x0 : array, optional
        Initial state.
    noise_cov : optional
        Linear plants: covariance (or std vector) of the model's noise group ``w``, drawn
        every sample and held over it.  Nonlinear plants: covariance of an additive
        state increment per sample.
    measurement_noise : optional
        Standard deviations (scalar or one per output) or a p x p covariance.
    rng : numpy.random.Generator or int seed
    method : ``'rk4'`` (fixed step, ``substeps`` per sample) or ``'solve_ivp'`` (RK45), nonlinear plants only.
    """
    seed = rng if isinstance(rng, int | np.integer) else None
    rng = np.random.default_rng(rng)
    if isinstance(plant, FaultModel):
        outputs, controls, states, dists = plant.outputs, plant.controls, plant.states, plant.disturbances
        if plant.is_discrete:
            if dt is not None and not np.isclose(dt, plant.dt):
                raise DataError(f"dt={dt} differs from the discrete plant's dt={plant.dt}; omit dt")
            dt = plant.dt
    elif isinstance(plant, NonlinearPlant):
        outputs, controls, states, dists = plant.outputs, plant.controls, plant.states, ()
        if d is not None:
            raise DataError("a NonlinearPlant takes no separate disturbance input; model it inside f")
    else:
        raise ModelError(f"cannot simulate a {type(plant).__name__}; pass a FaultModel or a NonlinearPlant")
    if t is None:
        if duration is None or dt is None:
            raise DataError("give either t, or both duration and dt")
        t = time_grid(duration, dt)
    else:
        t = np.asarray(t, dtype=float)
        if t.size > 1 and not np.allclose(np.diff(t), t[1] - t[0], rtol=1e-9, atol=0):
            raise DataError("simulation times t must be uniformly spaced")
    N = t.size
    h = float(t[1] - t[0]) if N > 1 else float(dt or 1.0)
    if isinstance(plant, FaultModel) and plant.is_discrete and N > 1 and not np.isclose(h, plant.dt, rtol=1e-9):
        raise DataError(f"t is spaced {h:g} s but the discrete plant runs at dt={plant.dt:g} s; give t at its dt")
    scenario = (scenario or FaultScenario()).resolve(outputs, controls)
    # independent streams: adding a fault or a noise source never shifts the others' draws
    rng_w, rng_v, *rng_f = rng.spawn(2 + len(scenario))

    u_cmd = _signal("u", u, t, controls)
    u_act = _apply_faults(scenario, "actuator", t, u_cmd, controls, rng_f)
    d_arr = _signal("d", d, t, dists)
    x0 = _initial_state(x0, states)

    if isinstance(plant, FaultModel):
        W = _covariance("noise_cov", noise_cov, len(plant.noise))
        y, x = _simulate_linear(plant, h, t, u_act, d_arr, x0, W, rng_w)
    else:
        W = _covariance("noise_cov", noise_cov, len(states))
        y, x = _simulate_nonlinear(plant, t, h, u_act, x0, W, rng_w, method, substeps)

    R = _covariance("measurement_noise", measurement_noise, len(outputs))
    if R is not None:
        y = y + _gaussian(rng_v, R, N)
    y = _apply_faults(scenario, "sensor", t, y, outputs, rng_f)

    info = {"plant": repr(plant), "seed": None if seed is None else int(seed), "scenario": scenario.label,
            "faults": [repr(f) for f in scenario]}
    info.update(meta or {})
    return Trace(t=t, u=u_cmd, y=y, x=x, d=d_arr, controls=controls, outputs=outputs, states=states,
                 disturbances=dists, fault=scenario.truth(t), meta=info)


def _apply_faults(scenario: FaultScenario, location: str, t: np.ndarray, signals: np.ndarray,
                  names: Sequence[str], streams: Sequence[np.random.Generator]) -> np.ndarray:
    """``signals`` (N, k) with the scenario's ``location`` faults applied in scenario order, one stream per fault."""
    out = signals.copy()
    for f, rf in zip(scenario, streams):
        if f.location == location:
            j = names.index(f.target)
            out[:, j] = f.apply(t, out[:, j], rf)
    return out


def _initial_state(x0, states: Sequence[str]) -> np.ndarray | None:
    if x0 is None:
        return None
    x0 = np.asarray(x0, dtype=float)
    if x0.shape != (len(states),):
        raise DataError(f"x0 has shape {x0.shape}; need ({len(states)},), one value per state {list(states)}")
    return x0


def _simulate_linear(model, h, t, u, d, x0, W, rng):
    dm = model if model.is_discrete else model.discretize(h)
    N = t.size
    w = np.zeros((N, len(model.noise))) if W is None else _gaussian(rng, W, N)
    v = np.hstack([u, d, np.zeros((N, len(model.faults))), w])
    y, x, _ = dlsim_blocked(dm.A, dm.B, dm.C, dm.D, v, x0)
    return y, x


def _simulate_nonlinear(plant, t, h, u, x0, W, rng, method, substeps):
    from scipy.integrate import solve_ivp

    if method not in ("rk4", "solve_ivp"):
        raise ModelError(f"unknown integration method {method!r}; use 'rk4' or 'solve_ivp'")
    N, n = t.size, len(plant.states)
    x = np.empty((N, n))
    y = np.empty((N, len(plant.outputs)))
    xk = plant.x0.copy() if x0 is None else x0.copy()
    noise = None if W is None else _gaussian(rng, W, N)
    f = plant.f
    hs = h / max(1, int(substeps))
    for k in range(N):
        x[k] = xk
        y[k] = plant.h(t[k], xk, u[k])
        if k == N - 1:
            break
        uk = u[k]
        if method == "rk4":
            tk = t[k]
            for _ in range(max(1, int(substeps))):
                k1 = f(tk, xk, uk)
                k2 = f(tk + hs / 2, xk + hs / 2 * k1, uk)
                k3 = f(tk + hs / 2, xk + hs / 2 * k2, uk)
                k4 = f(tk + hs, xk + hs * k3, uk)
                xk = xk + hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                tk += hs
        else:
            sol = solve_ivp(lambda tt, xx, uk=uk: f(tt, xx, uk), (t[k], t[k + 1]), xk, rtol=1e-8, atol=1e-10)
            if not sol.success:
                raise DataError(f"solve_ivp failed at t={t[k]:g}: {sol.message}")
            xk = sol.y[:, -1]
        if noise is not None:
            xk = xk + noise[k]
        if not np.all(np.isfinite(xk)):
            raise DataError(f"the nonlinear plant state became non-finite at t={t[k + 1]:g}; check f or the step size")
    return y, x


def simulate_scheduled(
    family: Callable[[float], FaultModel],
    schedule: ArrayLike,
    scenario: FaultScenario | None = None,
    *,
    u=None,
    d=None,
    x0=None,
    schedule_name: str = "speed",
    rng: np.random.Generator | int | None = None,
) -> Trace:
    """Simulate the parameter-varying plant ``x(k+1) = A(ρ_k) x(k) + B(ρ_k) v(k)`` (ρ frozen over each sample).

    The "complete discretisation" of van der Ploeg 2018, Sec. 4-3-4: sample ``k`` uses the
    discrete model ``family(schedule[k])``.  A constant schedule is :func:`simulate` of that one
    model (same code path and random streams).  Faults act on signals as in :func:`simulate`
    (actuator faults before the plant, in scenario order — so ``[ScaleFactor, Bias]`` gives
    ``δ = f_m δ_set + f_a``, (1.3); sensor faults after).  The model's noise group is not simulated.

    Parameters
    ----------
    family : callable ``ρ -> FaultModel``
        Discrete models with the same names and ``dt`` for every ρ, e.g.
        :func:`fdikit.plants.single_track.single_track_lpv`.  A family with a vectorised
        ``state_space(rho) -> (A, B, C, D)`` (stacks over a 1-D array of ρ; ``B``, ``D`` over the
        controls then the disturbances) is evaluated in one call — needed when ρ changes every
        sample (a speed sweep); otherwise ``family`` is called once per distinct ρ.
    schedule : (N,) array_like
        ρ at each sample (2+ finite values); the trace carries it as the extra output ``schedule_name``.
    scenario : FaultScenario, optional
        Faults on the plant's named sensors and actuators.
    u, d : array (N, m) or callable ``t -> (m,)``, optional
        Commanded controls and disturbances (zero when omitted).
    x0 : array, optional
        Initial state (default zero).
    rng : numpy.random.Generator or int seed
        Source of random fault signals.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> tr = simulate_scheduled(single_track_lpv(), np.linspace(70, 120, 101) / 3.6, u=np.full(101, 1e-3))
    >>> tr.outputs
    ('yaw_rate', 'lateral_error', 'heading_error', 'speed')
    """
    rho = np.asarray(schedule, dtype=float).ravel()
    if rho.size < 2 or not np.all(np.isfinite(rho)):
        raise DataError("schedule must hold 2+ finite parameter values, one per sample")
    m0 = family(float(rho[0]))
    if not isinstance(m0, FaultModel) or not m0.is_discrete:
        raise ModelError(f"family must return discrete FaultModels; family({rho[0]:g}) gave {m0!r}")
    if schedule_name in m0.outputs:
        raise ModelError(f"schedule_name {schedule_name!r} is already an output of the plant; choose another name")
    t = np.arange(rho.size) * m0.dt
    scenario = (scenario or FaultScenario()).resolve(m0.outputs, m0.controls)
    _, _, *rng_f = np.random.default_rng(rng).spawn(2 + len(scenario))  # the fault streams of simulate()
    u_cmd = _signal("u", u, t, m0.controls)
    u_act = _apply_faults(scenario, "actuator", t, u_cmd, m0.controls, rng_f)
    d_arr = _signal("d", d, t, m0.disturbances)
    x0 = _initial_state(x0, m0.states)
    if np.all(rho == rho[0]):
        y, x = _simulate_linear(m0, m0.dt, t, u_act, d_arr, x0, None, None)
    else:
        y, x = _simulate_varying(family, m0, rho, np.hstack([u_act, d_arr]), x0)
    y = _apply_faults(scenario, "sensor", t, y, m0.outputs, rng_f)
    return Trace(t=t, u=u_cmd, y=np.hstack([y, rho[:, None]]), controls=m0.controls,
                 outputs=m0.outputs + (schedule_name,), x=x, states=m0.states, d=d_arr,
                 disturbances=m0.disturbances, fault=scenario.truth(t),
                 meta={"plant": repr(m0), "scenario": scenario.label, "schedule": schedule_name})


def _scheduled_matrices(family, m0: FaultModel, values: np.ndarray, i0: int) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D)`` stacks at the distinct schedule ``values`` (``values[i0]`` gave ``m0``); B, D over [u, d]."""
    ref = (m0.A, np.hstack([m0.Bu, m0.Bd]), m0.C, np.hstack([m0.Du, m0.Dd]))
    state_space = getattr(family, "state_space", None)
    if callable(state_space):
        mats = tuple(np.asarray(M, dtype=float) for M in state_space(values))
        ok = len(mats) == 4 and all(M.shape == (values.size,) + R.shape for M, R in zip(mats, ref))
        if not (ok and all(np.allclose(M[i0], R, rtol=1e-9, atol=1e-12) for M, R in zip(mats, ref))):
            raise ModelError(f"family.state_space disagrees with family({values[i0]:g}); it must return the stacks "
                             "(A, [Bu Bd], C, [Du Dd]) of the family's models, one per schedule value")
        return mats
    models = [m0 if i == i0 else family(float(r)) for i, r in enumerate(values)]
    for r, m in zip(values, models):
        if not isinstance(m, FaultModel) or m.dt != m0.dt or m.inputs != m0.inputs or m.outputs != m0.outputs \
                or m.n != m0.n:
            raise ModelError(f"family({r:g}) must be a discrete FaultModel with the names, sizes and dt of "
                             f"family({values[i0]:g})")
    return tuple(np.stack(M) for M in zip(*[(m.A, np.hstack([m.Bu, m.Bd]), m.C, np.hstack([m.Du, m.Dd]))
                                            for m in models]))


def _simulate_varying(family, m0: FaultModel, rho: np.ndarray, v: np.ndarray, x0: np.ndarray | None):
    """Outputs and states with the model of ``rho[k]`` at sample k; ``v`` = [u, d] per sample."""
    values, idx = np.unique(rho, return_inverse=True)
    A, B, C, D = _scheduled_matrices(family, m0, values, int(idx[0]))
    drive = np.einsum("kij,kj->ki", B[idx], v)
    Ak = A[idx]
    x = np.empty((rho.size, m0.n))
    xk = np.zeros(m0.n) if x0 is None else x0
    for k in range(rho.size):
        x[k] = xk
        xk = Ak[k] @ xk + drive[k]
    return np.einsum("kij,kj->ki", C[idx], x) + np.einsum("kij,kj->ki", D[idx], v), x
