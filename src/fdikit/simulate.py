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

What the simulators promise (issue 12):

* every argument is checked before any work: bad arguments (duration, dt, x0, noise levels,
  seeds, options, fault targets) raise :class:`~fdikit.errors.ParameterError`, bad signal data
  (u, d, t, the schedule) :class:`~fdikit.errors.DataError`;
* a run whose arrays would not fit in the available memory (``MemAvailable`` of
  ``/proc/meminfo``, else ``os.sysconf``) is refused at once, with the bytes it needs;
* no trace is non-finite: a run that overflows raises a DataError naming the first bad sample
  (index and time), the signal and the likely cause (the unstable eigenvalue, Re λ > 0 or
  |λ| > 1, or an input or fault size too large for the float range);
* a fault changes no sample before its onset (bit for bit, against the fault-free run with the
  same seed), a fault that acts on no sample gives an :class:`~fdikit.errors.FdiWarning`, and the
  same seed gives the same trace, bit for bit.

The argument checks and the memory check live in :mod:`fdikit.simulate_checks`, the
non-finite diagnosis in :mod:`fdikit.simulate_diagnosis`; this module holds the plants' simulators.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.faults import FaultScenario
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.simulate_checks import (
    check_duration,
    check_initial_state,
    check_memory,
    check_noise,
    check_rng,
    check_sample_time,
    check_scenario,
    check_signal,
    check_times,
    sample_count,
    simulation_bytes,
    warn_inactive,
)
from fdikit.simulate_diagnosis import jacobian_text, linear_cause, refuse_non_finite, scheduled_cause
from fdikit.simulate_varying import frozen_A, simulate_varying
from fdikit.trace import Trace

__all__ = ["NonlinearPlant", "apply_faults", "simulate", "simulate_scheduled", "time_grid"]


@dataclass(frozen=True)
class NonlinearPlant:
    """A nonlinear plant ``x' = f(t, x, u)``, ``y = h(t, x, u)`` with named signals.

    ``f`` and ``h`` take and return 1-D arrays (``f`` one derivative per state, ``h`` one value
    per output).  ``x0`` is the default initial state (finite).

    Attributes
    ----------
    f : callable ``f(t, x, u) -> (n,)``
        State derivative; ``t`` [s], ``x`` (n,), ``u`` (m,) the held controls.
    h : callable ``h(t, x, u) -> (p,)``
        Outputs.
    states, outputs, controls : tuple of str
        Signal names (a sequence is stored as a tuple); their lengths fix n, p, m.
    x0 : (n,) ndarray
        Default initial state (zeros when omitted).

    Raises
    ------
    ModelError
        When ``f`` or ``h`` is not callable, a name is not a non-empty str, or ``x0`` is not finite, one per state.

    Examples
    --------
    >>> plant = NonlinearPlant(f=lambda t, x, u: -x + u, h=lambda t, x, u: x**2,
    ...                        states=("x",), outputs=("x_squared",), controls=("u",))
    >>> tr = simulate(plant, duration=1.0, dt=0.1, u=lambda t: [1.0], x0=[2.0])
    >>> tr.y.shape, round(float(tr.y[-1, 0]), 4)  # (1 + e^-1)^2 = 1.8711
    ((11, 1), 1.8711)
    """

    f: Callable[[float, np.ndarray, np.ndarray], np.ndarray]
    h: Callable[[float, np.ndarray, np.ndarray], np.ndarray]
    states: tuple[str, ...]
    outputs: tuple[str, ...]
    controls: tuple[str, ...]
    x0: np.ndarray | None = None

    def __post_init__(self) -> None:
        for attr in ("f", "h"):
            if not callable(getattr(self, attr)):
                raise ModelError(f"NonlinearPlant: {attr} must be callable {attr}(t, x, u), "
                                 f"got {type(getattr(self, attr)).__name__}")
        for attr in ("states", "outputs", "controls"):
            names = getattr(self, attr)
            if isinstance(names, str) or not all(isinstance(n, str) and n for n in names):
                raise ModelError(f"NonlinearPlant: {attr} must be a sequence of non-empty names, got {names!r}")
            object.__setattr__(self, attr, tuple(names))
        try:
            x0 = np.zeros(len(self.states)) if self.x0 is None else np.asarray(self.x0, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"NonlinearPlant: x0 must hold numbers, got {self.x0!r:.80}") from None
        if x0.shape != (len(self.states),):
            raise ModelError(f"x0 has shape {x0.shape}, need ({len(self.states)},) — one value per state")
        if not np.all(np.isfinite(x0)):
            raise ModelError(f"NonlinearPlant: x0 must be finite, got {x0.tolist()}")
        object.__setattr__(self, "x0", x0)


# ---------------------------------------------------------------------------------------------- sample times


def time_grid(duration: float, dt: float) -> np.ndarray:
    """``0, dt, 2 dt, …`` up to and including ``duration`` (rounded to whole samples).

    Parameters
    ----------
    duration, dt : float
        Length [s] (>= 0) and sample time [s] (> 0).

    Returns
    -------
    (N,) ndarray
        ``N = round(duration / dt) + 1`` sample times [s].

    Raises
    ------
    ParameterError
        For a ``dt`` that is not a finite number > 0, a ``duration`` that is not a finite number
        >= 0, or a grid that would not fit in memory.

    Examples
    --------
    >>> time_grid(0.5, 0.1).round(6).tolist()
    [0.0, 0.1, 0.2, 0.3, 0.4, 0.5]
    """
    dt, duration = check_sample_time(dt), check_duration(duration)
    N = sample_count(duration, dt)
    check_memory(8.0 * N, f"time_grid(duration={duration:g}, dt={dt:g}) of {N} samples")
    return np.arange(N) * dt


# ---------------------------------------------------------------------------------------------- noise and faults


def _gaussian(rng: np.random.Generator, cov: np.ndarray, N: int) -> np.ndarray:
    # eigen-factor: works for semidefinite covariances (a zero std is allowed)
    w, V = np.linalg.eigh(cov)
    L = V * np.sqrt(np.clip(w, 0.0, None))
    return rng.standard_normal((N, cov.shape[0])) @ L.T


def apply_faults(scenario: FaultScenario, location: str, t: np.ndarray, signals: np.ndarray,
                 names: Sequence[str], streams: Sequence[np.random.Generator]) -> np.ndarray:
    """``signals`` (N, k) with the scenario's ``location`` faults applied in scenario order, one stream per fault.

    What :func:`simulate` does to the commands (``"actuator"``) before the plant and to the
    measurements (``"sensor"``) after the noise; public so that other simulators (the compiled
    car of :mod:`fdikit.vehicle`) inject faults the same way.

    Parameters
    ----------
    scenario : FaultScenario
        Resolved against ``names`` (:meth:`FaultScenario.resolve`).
    location : {"actuator", "sensor"}
        Which faults to apply.
    t : (N,) ndarray
        Sample times [s].
    signals : (N, k) ndarray
        The clean signals, one column per name.
    names : sequence of str
        Column names (controls or outputs).
    streams : sequence of numpy.random.Generator
        One random stream per fault of the scenario (in scenario order).

    Returns
    -------
    (N, k) ndarray
        A copy with the faults applied.

    Raises
    ------
    DataError
        When a fault makes a finite signal non-finite (the message names the fault, signal and first bad sample).

    Examples
    --------
    >>> from fdikit.faults import Bias
    >>> sc = FaultScenario([Bias("y", 2.0, onset=0.5)]).resolve(["y"], [])
    >>> apply_faults(sc, "sensor", np.array([0.0, 1.0]), np.zeros((2, 1)), ["y"],
    ...              np.random.default_rng(0).spawn(1)).ravel().tolist()
    [0.0, 2.0]
    """
    out = signals.copy()
    for f, rf in zip(scenario, streams):
        if f.location == location:
            j = names.index(f.target)
            with np.errstate(over="ignore", invalid="ignore"):
                col = f.apply(t, out[:, j], rf)
            bad = np.flatnonzero(~np.isfinite(col) & np.isfinite(out[:, j]))
            if bad.size:
                k = int(bad[0])
                raise DataError(
                    f"the {type(f).__name__} fault {f!r} makes the {location} signal {f.target!r} non-finite "
                    f"({col[k]}) at sample {k} (t={t[k]:g} s): its size is too large for the signal; "
                    "give a smaller fault size"
                )
            out[:, j] = col
    return out


# ---------------------------------------------------------------------------------------------- simulate


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
    noise_std=None,
    noise_cov=None,
    measurement_noise_std=None,
    measurement_noise_cov=None,
    rng: np.random.Generator | int | None = None,
    method: str = "rk4",
    substeps: int = 4,
    meta: dict | None = None,
) -> Trace:
    """Simulate ``plant`` under ``scenario`` and return a :class:`Trace`.

    Every argument is checked before any work, and the trace is never non-finite: a run that
    overflows (an unstable plant, inputs or fault sizes too large for the float range) raises a
    :class:`DataError` naming the first bad sample and signal and the likely cause (for an
    unstable plant, its eigenvalue with Re λ > 0, or |λ| > 1 when discrete).  A fault changes no
    sample before its onset: those samples equal, bit for bit, the fault-free run with the same
    seed.  The same seed gives the same trace, bit for bit.

    Parameters
    ----------
    plant : FaultModel or NonlinearPlant
        A continuous FaultModel is discretised exactly (ZOH) at the sample time; a
        discrete one runs at its own ``dt``.
    scenario : FaultScenario, optional
        Faults on the plant's named sensors (outputs) and actuators (controls).  A fault that
        acts on no sample (its onset after the end of the run) gives an :class:`FdiWarning`.
    duration, dt, t :
        Either ``t`` (uniform, strictly increasing sample times) or ``duration`` (>= 0) and
        ``dt`` (> 0); ``dt`` may be omitted for a discrete plant.
    u, d : array (N, m) or callable ``t -> (m,)``, optional
        Commanded controls and disturbances (zero when omitted); finite.
    x0 : array, optional
        Initial state, one finite value per state.
    noise_std, noise_cov : optional, at most one of them
        Linear plants: the model's noise group ``w``, drawn every sample and held over it.
        Nonlinear plants: an additive state increment per sample.  ``noise_std`` is a standard
        deviation (a scalar or one per signal, finite and >= 0); ``noise_cov`` a covariance (a
        symmetric positive semidefinite matrix, or a scalar/vector of variances meaning ``σ² I`` /
        ``diag``).  A std of ``s`` and a cov of ``s**2`` give the same trace, bit for bit.
    measurement_noise_std, measurement_noise_cov : optional, at most one of them
        Additive output noise: standard deviations (scalar or one per output) or a covariance
        (p x p matrix, or a scalar/vector of variances), as for the process noise.
    rng : numpy.random.Generator or int seed (>= 0), optional
        Source of the noise and of random fault signals (None: fresh entropy, not reproducible).
    method : {'rk4', 'solve_ivp'}, default 'rk4'
        Nonlinear plants only: fixed-step RK4 (``substeps`` steps per sample) or
        :func:`scipy.integrate.solve_ivp` (RK45, rtol 1e-8, atol 1e-10) between samples.
    substeps : int >= 1, default 4
        RK4 steps per sample.
    meta : dict, optional
        Extra metadata stored in the trace.

    Returns
    -------
    Trace
        ``t`` (N,), commanded ``u`` (N, m), measured ``y`` (N, p) with noise and sensor faults, ``x`` (N, n),
        ``d``, the fault truth label per sample (``"none"`` before an onset) and ``meta`` (plant, seed, scenario).

    Raises
    ------
    ParameterError
        For a bad argument: a plant of another type, a duration, dt, x0, noise level, seed,
        method or substeps out of range or not a number, an unknown fault target, or a run whose
        arrays would not fit in the available memory (the message gives the bytes it needs).
    DataError
        For unusable signal data (u, d or t of the wrong shape, non-numeric or non-finite), and
        for a run that would return non-finite samples.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.faults import Bias, FaultScenario
    >>> from fdikit.plants import msd
    >>> plant = msd(dt=0.01)  # discrete: dt is the plant's
    >>> faulty = simulate(plant, FaultScenario([Bias("y1", 0.5, onset=1.0)]), duration=2.0,
    ...                   measurement_noise_std=0.01, rng=1)
    >>> clean = simulate(plant, duration=2.0, measurement_noise_std=0.01, rng=1)
    >>> faulty.y.shape, str(faulty.fault[0]), str(faulty.fault[-1])
    ((201, 3), 'none', 'y1_sensor')
    >>> bool(np.array_equal(faulty.y[:100], clean.y[:100])), np.round(faulty.y[-1] - clean.y[-1], 6).tolist()
    (True, [0.5, 0.0, 0.0])
    """
    if not isinstance(plant, FaultModel | NonlinearPlant):
        raise ParameterError(f"cannot simulate a {type(plant).__name__}; pass a FaultModel or a NonlinearPlant "
                             "as plant (e.g. fdikit.plants.get_plant(name))")
    scenario = check_scenario(scenario)
    rng, seed = check_rng(rng)
    if method not in ("rk4", "solve_ivp"):
        raise ParameterError(f"unknown integration method {method!r}; use method='rk4' or method='solve_ivp'")
    if isinstance(substeps, bool) or not isinstance(substeps, int | np.integer):
        raise ParameterError(f"simulate: substeps must be an integer >= 1, got {substeps!r}")
    if substeps < 1:
        raise ParameterError(f"simulate: substeps must be >= 1, got {substeps}")
    if meta is not None and not isinstance(meta, dict):
        raise ParameterError(f"simulate: meta must be a dict of metadata, got {type(meta).__name__}")
    dt_given = dt
    if isinstance(plant, FaultModel):
        outputs, controls, states, dists = plant.outputs, plant.controls, plant.states, plant.disturbances
        n_drive = len(controls) + len(dists) + len(plant.faults) + len(plant.noise)
        if plant.is_discrete:
            if dt is not None and not np.isclose(check_sample_time(dt), plant.dt):
                raise ParameterError(f"dt={dt} differs from the discrete plant's dt={plant.dt}; omit dt")
            dt = plant.dt
    else:
        outputs, controls, states, dists = plant.outputs, plant.controls, plant.states, ()
        n_drive = len(controls) + len(states)
        if d is not None:
            raise ParameterError("d: a NonlinearPlant takes no separate disturbance input; model it inside f")
    scenario = scenario.resolve(outputs, controls)
    label_chars = sum(len(f.name) + 1 for f in scenario)
    if t is None:
        if duration is None or dt is None:
            raise ParameterError("simulate: give either t, or both duration and dt (dt may be omitted for a "
                                 "discrete plant)")
        h, duration = check_sample_time(dt), check_duration(duration)
        N = sample_count(duration, h)
        need = simulation_bytes(N, len(states), len(outputs), len(controls), len(dists), n_drive, label_chars)
        check_memory(need, f"simulate(duration={duration:g} s, dt={h:g} s) of {N} samples")
        t = np.arange(N) * h
    else:
        if duration is not None:
            raise ParameterError("simulate: give either t or duration (with dt), not both")
        t = check_times(t)
        N = t.size
        need = simulation_bytes(N, len(states), len(outputs), len(controls), len(dists), n_drive, label_chars)
        check_memory(need, f"simulate of {N} samples")
        h = float(t[1] - t[0]) if N > 1 else float(check_sample_time(dt) if dt is not None else 1.0)
        if N > 1 and dt_given is not None and not np.isclose(check_sample_time(dt_given), h, rtol=1e-9):
            raise ParameterError(f"simulate: dt={dt_given} differs from the spacing {h:g} s of t; omit dt")
    if isinstance(plant, FaultModel) and plant.is_discrete and N > 1 and not np.isclose(h, plant.dt, rtol=1e-9):
        raise DataError(f"t is spaced {h:g} s but the discrete plant runs at dt={plant.dt:g} s; give t at its dt")
    x0 = check_initial_state(x0, states)
    if isinstance(plant, FaultModel):
        W = check_noise("noise_std", noise_std, "noise_cov", noise_cov, len(plant.noise), "noise input w")
    else:
        W = check_noise("noise_std", noise_std, "noise_cov", noise_cov, len(states), "state")
    R = check_noise("measurement_noise_std", measurement_noise_std, "measurement_noise_cov", measurement_noise_cov,
                    len(outputs), "output")
    u_cmd = check_signal("u", u, t, controls)
    d_arr = check_signal("d", d, t, dists)
    warn_inactive(scenario, t)

    # independent streams: adding a fault or a noise source never shifts the others' draws
    rng_w, rng_v, *rng_f = rng.spawn(2 + len(scenario))
    u_act = apply_faults(scenario, "actuator", t, u_cmd, controls, rng_f)
    if isinstance(plant, FaultModel):
        y, x = _simulate_linear(plant, h, t, u_act, d_arr, x0, W, rng_w)
    else:
        y, x = _simulate_nonlinear(plant, t, h, u_act, x0, W, rng_w, method, substeps)

    if R is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            y = y + _gaussian(rng_v, R, N)
        refuse_non_finite(t, [("output", y, outputs)], lambda: "the measurement noise is too large for the outputs")
    y = apply_faults(scenario, "sensor", t, y, outputs, rng_f)

    info = {"plant": repr(plant), "seed": seed, "scenario": scenario.label, "faults": [repr(f) for f in scenario]}
    info.update(meta or {})
    return Trace(t=t, u=u_cmd, y=y, x=x, d=d_arr, controls=controls, outputs=outputs, states=states,
                 disturbances=dists, fault=scenario.truth(t), meta=info)


def _simulate_linear(model, h, t, u, d, x0, W, rng):
    """Exact sampled response; refuses (DataError) a non-finite result with the unstable eigenvalue.

    The block solver (:func:`fdikit.lti.dlsim_blocked`) multiplies each block of 32 samples
    with a lifted matrix whose entries for later samples are exact zeros; ``0 * v`` is an exact
    zero for every finite ``v`` but NaN for ``v = ±inf``, so a non-finite input would leak into
    the samples before it.  The inputs are therefore checked finite here (they are validated
    upstream, so this is a guard), and ``+ 0.0`` maps any ``-0.0`` to ``+0.0`` so that samples
    before a fault's onset are bit-identical to the fault-free run.
    """
    dm = model if model.is_discrete else model.discretize(h)
    N = t.size
    w = np.zeros((N, len(model.noise))) if W is None else _gaussian(rng, W, N)
    v = np.hstack([u, d, np.zeros((N, len(model.faults))), w])
    if not np.all(np.isfinite(v)):  # pragma: no cover - inputs and faults are checked before
        raise DataError("simulate: a non-finite input reached the solver; check u, d and the fault sizes")
    with np.errstate(over="ignore", invalid="ignore"):
        y, x, _ = dlsim_blocked(dm.A, dm.B, dm.C, dm.D, v, x0)
    refuse_non_finite(t, [("state", x, model.states), ("output", y, model.outputs)],
                      lambda: linear_cause(model, v))
    np.add(y, 0.0, out=y)
    np.add(x, 0.0, out=x)
    return y, x


def _simulate_nonlinear(plant, t, h, u, x0, W, rng, method, substeps):
    from scipy.integrate import solve_ivp

    N, n, p = t.size, len(plant.states), len(plant.outputs)
    x = np.empty((N, n))
    y = np.empty((N, p))
    xk = plant.x0.copy() if x0 is None else x0.copy()
    noise = None if W is None else _gaussian(rng, W, N)

    def f(tt, xx, uu):
        dx = np.asarray(plant.f(tt, xx, uu), dtype=float)
        if dx.shape != (n,):
            raise ModelError(f"NonlinearPlant: f returned shape {dx.shape}; need ({n},), one derivative per state "
                             f"(the plant's states are {list(plant.states)})")
        return dx

    hs = h / substeps
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(N):
            x[k] = xk
            yk = np.asarray(plant.h(t[k], xk, u[k]), dtype=float)
            if yk.shape != (p,):
                raise ModelError(f"NonlinearPlant: h returned shape {yk.shape}; need ({p},), one value per output "
                                 f"(the plant's outputs are {list(plant.outputs)})")
            if not np.all(np.isfinite(yk)):
                j = int(np.flatnonzero(~np.isfinite(yk))[0])
                raise DataError(f"simulate would return a non-finite trace: output {plant.outputs[j]!r} is {yk[j]} "
                                f"at sample {k} (t={t[k]:g} s) although the state is finite; check h")
            y[k] = yk
            if k == N - 1:
                break
            uk = u[k]
            x_prev = xk
            if method == "rk4":
                tk = t[k]
                for _ in range(substeps):
                    k1 = f(tk, xk, uk)
                    k2 = f(tk + hs / 2, xk + hs / 2 * k1, uk)
                    k3 = f(tk + hs / 2, xk + hs / 2 * k2, uk)
                    k4 = f(tk + hs, xk + hs * k3, uk)
                    xk = xk + hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                    tk += hs
            else:
                sol = solve_ivp(lambda tt, xx, uk=uk: f(tt, xx, uk), (t[k], t[k + 1]), xk, rtol=1e-8, atol=1e-10)
                if not sol.success:
                    state = dict(zip(plant.states, np.round(xk, 6).tolist()))
                    raise DataError(f"solve_ivp failed between t={t[k]:g} and t={t[k + 1]:g} s (sample {k}) from "
                                    f"the state {state}: {sol.message}{jacobian_text(plant.f, t[k], xk, uk)}")
                xk = sol.y[:, -1]
            if noise is not None:
                xk = xk + noise[k]
            if not np.all(np.isfinite(xk)):
                j = int(np.flatnonzero(~np.isfinite(xk))[0])
                raise DataError(
                    f"the nonlinear plant state {plant.states[j]!r} became non-finite ({xk[j]}) at sample {k + 1} "
                    f"(t={t[k + 1]:g} s). Likely cause: the plant is unstable or escapes in finite time"
                    f"{jacobian_text(plant.f, t[k], x_prev, uk)}, or the step is too large for {method} "
                    f"(h = {hs:g} s); check f, reduce dt or raise substeps"
                )
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

    Returns
    -------
    Trace
        ``t`` (N,) at the family's ``dt``, commanded ``u``, outputs ``y`` (N, p + 1) with the schedule as the
        last column ``schedule_name``, states ``x``, ``d`` and the fault truth labels.

    Raises
    ------
    ParameterError
        For a family that is not callable, a bad ``schedule_name``, ``x0`` or seed, an unknown
        fault target, or a run that would not fit in memory.
    DataError
        For a schedule that is not 2+ finite numbers, bad ``u`` / ``d``, or a run that would
        return non-finite samples (the message names the most unstable frozen model ``A(ρ)``).
    ModelError
        When ``family`` does not return matching discrete FaultModels.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> tr = simulate_scheduled(single_track_lpv(), np.linspace(70, 120, 101) / 3.6, u=np.full(101, 1e-3))
    >>> tr.outputs
    ('yaw_rate', 'lateral_error', 'heading_error', 'speed')
    """
    if not callable(family):
        raise ParameterError(f"simulate_scheduled: family must be callable, ρ -> discrete FaultModel, "
                             f"got {type(family).__name__}")
    if not isinstance(schedule_name, str) or not schedule_name:
        raise ParameterError(f"simulate_scheduled: schedule_name must be a non-empty str, got {schedule_name!r}")
    scenario = check_scenario(scenario)
    gen, _ = check_rng(rng)
    try:
        rho = np.asarray(schedule, dtype=float).ravel()
    except (TypeError, ValueError):
        raise DataError(f"schedule must hold numbers, one parameter value per sample; got {schedule!r:.60}") from None
    if rho.size < 2 or not np.all(np.isfinite(rho)):
        where = "" if rho.size < 2 else f" (schedule[{int(np.flatnonzero(~np.isfinite(rho))[0])}] is not finite)"
        raise DataError(f"schedule must hold 2+ finite parameter values, one per sample; got {rho.size}{where}")
    m0 = family(float(rho[0]))
    if not isinstance(m0, FaultModel) or not m0.is_discrete:
        raise ModelError(f"family must return discrete FaultModels; family({rho[0]:g}) gave {m0!r}")
    if schedule_name in m0.outputs:
        raise ModelError(f"schedule_name {schedule_name!r} is already an output of the plant; choose another name")
    N, n, p = rho.size, m0.n, len(m0.outputs)
    scenario = scenario.resolve(m0.outputs, m0.controls)
    nv = len(m0.controls) + len(m0.disturbances)
    # the per-sample matrix gathers of simulate_varying: B, C, D (A is indexed sample by sample)
    need = simulation_bytes(N, n, p + 1, len(m0.controls), len(m0.disturbances), nv,
                             sum(len(f.name) + 1 for f in scenario)) + 8.0 * N * (n * nv + p * n + p * nv)
    check_memory(need, f"simulate_scheduled of {N} samples")
    t = np.arange(rho.size) * m0.dt
    x0 = check_initial_state(x0, m0.states)
    u_cmd = check_signal("u", u, t, m0.controls)
    d_arr = check_signal("d", d, t, m0.disturbances)
    warn_inactive(scenario, t)
    _, _, *rng_f = gen.spawn(2 + len(scenario))  # the fault streams of simulate()
    u_act = apply_faults(scenario, "actuator", t, u_cmd, m0.controls, rng_f)
    if np.all(rho == rho[0]):
        y, x = _simulate_linear(m0, m0.dt, t, u_act, d_arr, x0, None, None)
    else:
        y, x = simulate_varying(family, m0, rho, np.hstack([u_act, d_arr]), x0)
        with np.errstate(over="ignore", invalid="ignore"):
            refuse_non_finite(t, [("state", x, m0.states), ("output", y, m0.outputs)],
                              lambda: scheduled_cause(lambda values: frozen_A(family, m0, rho, values), rho, x))
        np.add(y, 0.0, out=y)
        np.add(x, 0.0, out=x)
    y = apply_faults(scenario, "sensor", t, y, m0.outputs, rng_f)
    return Trace(t=t, u=u_cmd, y=np.hstack([y, rho[:, None]]), controls=m0.controls,
                 outputs=m0.outputs + (schedule_name,), x=x, states=m0.states, d=d_arr,
                 disturbances=m0.disturbances, fault=scenario.truth(t),
                 meta={"plant": repr(m0), "scenario": scenario.label, "schedule": schedule_name})
