"""Simulate a plant under a fault scenario, with seeded noise, into a :class:`Trace`.

Linear plants (:class:`FaultModel`) are propagated exactly at the sample time
(zero-order hold on every input); nonlinear plants (:class:`NonlinearPlant`) are
integrated between samples by fixed-step RK4 or :func:`scipy.integrate.solve_ivp`
with the inputs held.  Actuator faults change the commanded control before the
plant, sensor faults change the measurement after the sensor noise (a stuck sensor
reads a frozen, noise-free value).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DataError, ModelError
from fdikit.faults import FaultScenario
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.trace import Trace

__all__ = ["NonlinearPlant", "simulate", "time_grid"]


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
    u_act = u_cmd.copy()
    for f, rf in zip(scenario, rng_f):
        if f.location == "actuator":
            j = controls.index(f.target)
            u_act[:, j] = f.apply(t, u_act[:, j], rf)
    d_arr = _signal("d", d, t, dists)
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (len(states),):
            raise DataError(f"x0 has shape {x0.shape}; need ({len(states)},), one value per state {list(states)}")

    if isinstance(plant, FaultModel):
        W = _covariance("noise_cov", noise_cov, len(plant.noise))
        y, x = _simulate_linear(plant, h, t, u_act, d_arr, x0, W, rng_w)
    else:
        W = _covariance("noise_cov", noise_cov, len(states))
        y, x = _simulate_nonlinear(plant, t, h, u_act, x0, W, rng_w, method, substeps)

    R = _covariance("measurement_noise", measurement_noise, len(outputs))
    if R is not None:
        y = y + _gaussian(rng_v, R, N)
    for f, rf in zip(scenario, rng_f):
        if f.location == "sensor":
            j = outputs.index(f.target)
            y[:, j] = f.apply(t, y[:, j], rf)

    info = {"plant": repr(plant), "seed": None if seed is None else int(seed), "scenario": scenario.label,
            "faults": [repr(f) for f in scenario]}
    info.update(meta or {})
    return Trace(t=t, u=u_cmd, y=y, x=x, d=d_arr, controls=controls, outputs=outputs, states=states,
                 disturbances=dists, fault=scenario.truth(t), meta=info)


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
