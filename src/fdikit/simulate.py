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
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from fdikit.errors import DataError, FdiWarning, ModelError, ParameterError
from fdikit.faults import FaultScenario, _real
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.trace import Trace

__all__ = ["NonlinearPlant", "simulate", "simulate_scheduled", "time_grid"]


@dataclass(frozen=True)
class NonlinearPlant:
    """A nonlinear plant ``x' = f(t, x, u)``, ``y = h(t, x, u)`` with named signals.

    ``f`` and ``h`` take and return 1-D arrays (``f`` one derivative per state, ``h`` one value
    per output).  ``x0`` is the default initial state (finite).

    Raises
    ------
    ModelError
        When ``f`` or ``h`` is not callable, or ``x0`` is not one finite number per state.
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


# ---------------------------------------------------------------------------------------------- argument checks

_FLOAT_RANGE_LOG = math.log(np.finfo(float).max)  # ln(1.8e308): a state growing like e^{at} overflows at a t ≈ 709.8


def _number(name: str, value) -> float:
    """A finite float from a real number argument (ParameterError otherwise)."""
    return _real("simulate", name, value)


def _sample_time(dt) -> float:
    dt = _number("dt (the sample time)", dt)
    if not dt > 0:
        raise ParameterError(f"simulate: dt (the sample time) must be > 0, got {dt}")
    return dt


def _duration(duration) -> float:
    duration = _number("duration", duration)
    if not duration >= 0:
        raise ParameterError(f"simulate: duration must be >= 0, got {duration}")
    return duration


def _human(nbytes: float) -> str:
    for unit, size in (("EiB", 2**60), ("PiB", 2**50), ("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20)):
        if nbytes >= size:
            return f"{nbytes / size:.3g} {unit}"
    return f"{nbytes / 1024:.3g} KiB"


def _available_memory(meminfo: str = "/proc/meminfo") -> tuple[float, str]:
    """Bytes of memory available to a new allocation, and where the figure comes from.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux), else ``os.sysconf`` free pages; when neither
    can be read, a ceiling of 1 PiB (no machine holds such an array).
    """
    try:
        with open(meminfo, encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024, f"MemAvailable in {meminfo}"
    except (OSError, ValueError, IndexError):
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")), "free pages (os.sysconf)"
    except (AttributeError, ValueError, OSError):
        return float(2**50), "no memory figure readable; a ceiling of 1 PiB"


def _check_memory(nbytes: float, what: str) -> None:
    """Refuse (ParameterError) a run whose arrays need more than the available memory."""
    available, source = _available_memory()
    if nbytes > available:
        raise ParameterError(
            f"{what} needs about {nbytes:.3g} bytes ({_human(nbytes)}) of memory for its arrays, but only "
            f"{_human(available)} are available ({source}); shorten the duration, use a larger dt, "
            "or simulate in pieces (pass x0 = the last state of the previous piece)"
        )


def _sample_count(duration: float, dt: float) -> int:
    """``round(duration / dt) + 1`` samples, refusing counts that no memory holds before computing them."""
    ratio = duration / dt
    if not math.isfinite(ratio) or ratio > 2.0**62:
        _check_memory(math.inf if not math.isfinite(ratio) else 8.0 * ratio,
                      f"duration={duration:g} s at dt={dt:g} s ({ratio:.3g} samples)")
    return int(round(ratio)) + 1


def _simulation_bytes(N: int, n: int, p: int, m: int, nd: int, nv: int, label_chars: int) -> float:
    """Bytes of the arrays a simulation of N samples allocates (a lower bound of the peak).

    Per sample: times (1), commanded and faulty controls and their copies (3 m), disturbances (2 nd),
    the stacked and block-padded solver input (2 nv), states from the block solver and the trace
    (3 n), outputs with noise, faults and the trace copy (6 p), all float64; plus the truth labels
    (an object array and a str array of ``label_chars`` characters).
    """
    floats = 1 + 3 * m + 2 * nd + 2 * nv + 3 * n + 6 * p
    return float(N) * (8.0 * floats + 8.0 + 4.0 * max(label_chars, 4))


def time_grid(duration: float, dt: float) -> np.ndarray:
    """``0, dt, 2 dt, …`` up to and including ``duration`` (rounded to whole samples).

    Raises
    ------
    ParameterError
        For a ``dt`` that is not a finite number > 0, a ``duration`` that is not a finite number
        >= 0, or a grid that would not fit in memory.
    """
    dt, duration = _sample_time(dt), _duration(duration)
    N = _sample_count(duration, dt)
    _check_memory(8.0 * N, f"time_grid(duration={duration:g}, dt={dt:g}) of {N} samples")
    return np.arange(N) * dt


def _times(t) -> np.ndarray:
    """Given sample times: 1-D, non-empty, finite, strictly increasing and uniformly spaced (DataError)."""
    try:
        t = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"simulate: t must hold numbers (sample times in s), got {t!r:.80}") from None
    if t.ndim != 1:
        raise DataError(f"simulate: t must be a 1-D array of sample times, got shape {t.shape}")
    if t.size == 0:
        raise DataError("simulate: t is empty; give at least one sample time")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise DataError(f"simulate: t must be finite; t[{bad[0]}] = {t[bad[0]]}")
    if t.size > 1:
        steps = np.diff(t)
        if not np.all(steps > 0):
            k = int(np.flatnonzero(steps <= 0)[0])
            raise DataError(f"simulate: t must be strictly increasing; t[{k + 1}] = {t[k + 1]:g} <= t[{k}] = {t[k]:g}")
        if not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
            raise DataError("simulation times t must be uniformly spaced")
    return t


def _generator(rng) -> tuple[np.random.Generator, int | None]:
    """``numpy.random.default_rng(rng)`` and the integer seed (when one was given)."""
    if isinstance(rng, bool) or isinstance(rng, str | bytes | float):
        raise ParameterError(f"simulate: rng must be a seed (an int >= 0) or a numpy.random.Generator, got {rng!r}")
    if isinstance(rng, int | np.integer) and rng < 0:
        raise ParameterError(f"simulate: rng, a seed, must be >= 0 (not negative), got {rng}")
    try:
        gen = np.random.default_rng(rng)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"simulate: rng must be a seed (an int >= 0) or a numpy.random.Generator, "
                             f"got {rng!r:.60} ({exc})") from None
    return gen, int(rng) if isinstance(rng, int | np.integer) else None


def _scenario(scenario) -> FaultScenario:
    if scenario is None:
        return FaultScenario()
    if not isinstance(scenario, FaultScenario):
        raise ParameterError(f"simulate: scenario must be a FaultScenario (e.g. FaultScenario([Bias(...)])) or None, "
                             f"got {type(scenario).__name__} {scenario!r:.60}")
    return scenario


def _signal(name: str, value, t: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """(N, k) block from None (zeros), an array, or a callable ``t -> (k,)`` (DataError when unusable)."""
    k, N = len(names), t.size
    if value is None:
        return np.zeros((N, k))
    if callable(value):
        rows = []
        for tk in t:
            try:
                row = np.atleast_1d(np.asarray(value(tk), dtype=float))
            except Exception as exc:  # noqa: BLE001 - a user's callable: say which signal and time failed
                raise DataError(f"{name}({tk:g}) raised {type(exc).__name__}: {exc}; the callable {name} must "
                                f"return {k} number(s), one per signal {list(names)}") from None
            if row.shape != (k,):
                raise DataError(f"{name}({tk:g}) returned shape {row.shape}; need ({k},), one value per signal "
                                f"{list(names)}")
            rows.append(row)
        arr = np.array(rows, dtype=float).reshape(N, k)
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise DataError(f"{name} must hold numbers (one row per sample, columns {list(names)}), "
                            f"got {value!r:.80}") from None
    if arr.ndim == 1 and k == 1:
        arr = arr.reshape(-1, 1)
    if arr.shape != (N, k):
        raise DataError(f"{name} has shape {arr.shape}; need ({N}, {k}): one row per sample, columns {list(names)}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        i, j = bad[0]
        raise DataError(f"{name} has a non-finite value {arr[i, j]} in signal {names[j]!r} at sample {i} "
                        f"(t={t[i]:g} s), {len(bad)} in all; inputs to a simulation must be finite")
    return arr


def _covariance(name: str, value, k: int, what: str) -> np.ndarray | None:
    """Covariance from None, a scalar/vector of standard deviations (>= 0), or a k x k PSD matrix."""
    if value is None:
        return None
    if k == 0:
        raise ParameterError(f"{name} was given but there is no signal for it (the model has no noise inputs w); "
                             "add a noise group (FaultModel(..., Bw=..., noise=[...])) or omit it")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number (a standard deviation), one per {what}, or a {k}x{k} "
                             f"covariance matrix; got {value!r:.60}") from None
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {arr.tolist()}")
    if arr.ndim <= 1:
        if arr.size not in (1, k):
            raise ParameterError(f"{name} has {arr.size} standard deviations; need 1 or {k} (one per {what})")
        if np.any(arr < 0):
            raise ParameterError(f"{name} holds standard deviations, which must be >= 0; got {arr.tolist()}")
        return np.diag(np.broadcast_to(arr, (k,)) ** 2)
    if arr.shape != (k, k):
        raise ParameterError(f"{name} has shape {arr.shape}; need a scalar, {k} standard deviations or a {k}x{k} "
                             "covariance matrix")
    if not np.allclose(arr, arr.T):
        raise ParameterError(f"{name} must be a symmetric positive semidefinite {k}x{k} covariance; it is not "
                             "symmetric")
    if np.linalg.eigvalsh(arr).min() < -1e-12 * max(1.0, np.abs(arr).max()):
        raise ParameterError(f"{name} must be a symmetric positive semidefinite {k}x{k} covariance (or std vector); "
                             f"its smallest eigenvalue is {np.linalg.eigvalsh(arr).min():.3g}")
    return arr


def _gaussian(rng: np.random.Generator, cov: np.ndarray, N: int) -> np.ndarray:
    # eigen-factor: works for semidefinite covariances (a zero std is allowed)
    w, V = np.linalg.eigh(cov)
    L = V * np.sqrt(np.clip(w, 0.0, None))
    return rng.standard_normal((N, cov.shape[0])) @ L.T


def _initial_state(x0, states: Sequence[str]) -> np.ndarray | None:
    if x0 is None:
        return None
    try:
        x0 = np.asarray(x0, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"x0 must hold numbers, one per state {list(states)}; got {x0!r:.60}") from None
    if x0.shape != (len(states),):
        raise ParameterError(f"x0 has shape {x0.shape}; need ({len(states)},), one value per state {list(states)}")
    if not np.all(np.isfinite(x0)):
        raise ParameterError(f"x0 must be finite, got {x0.tolist()} (states {list(states)})")
    return x0


def _warn_inactive(scenario: FaultScenario, t: np.ndarray) -> None:
    """An FdiWarning for each fault that acts on no sample of the run (its onset after the end, say)."""
    for f in scenario:
        if t.size and not f.active(t).any():
            if f.onset > t[-1]:
                why = f"its onset {f.onset:g} s lies after the end of the run (t = {t[0]:g} … {t[-1]:g} s)"
            elif f.end is not None and f.end <= t[0]:
                why = f"it ends at {f.end:g} s, before the run starts at t = {t[0]:g} s"
            else:
                why = f"no sample of the run (t = {t[0]:g} … {t[-1]:g} s) falls in its active intervals"
            warnings.warn(f"the fault {f!r} never acts: {why}; the run is fault-free", FdiWarning, stacklevel=3)


# ---------------------------------------------------------------------------------------------- non-finite results


def _eig_text(lam: complex) -> str:
    return f"{lam.real:.6g}" if lam.imag == 0 else f"{lam.real:.6g}{lam.imag:+.6g}j"


def _instability(A: np.ndarray, discrete: bool, what: str = "A") -> str | None:
    """The sentence naming the unstable eigenvalue of ``A``, or None when ``A`` is stable."""
    A = np.asarray(A, dtype=float)
    if A.size == 0 or not np.all(np.isfinite(A)):
        return None
    lam = np.linalg.eigvals(A)
    if discrete:
        i = int(np.argmax(np.abs(lam)))
        r = float(abs(lam[i]))
        if r <= 1.0:
            return None
        return (f"the plant is unstable: {what} has the eigenvalue λ = {_eig_text(lam[i])} with |λ| = {r:.6g} > 1, "
                f"so its state grows like |λ|^k and leaves the float range after about "
                f"{_FLOAT_RANGE_LOG / math.log(r):.4g} samples")
    i = int(np.argmax(lam.real))
    a = float(lam[i].real)
    if a <= 0.0:
        return None
    return (f"the plant is unstable: {what} has the eigenvalue λ = {_eig_text(lam[i])} with Re λ = {a:.6g} > 0, "
            f"so its state grows like exp({a:.3g} t) and leaves the float range after about "
            f"{_FLOAT_RANGE_LOG / a:.4g} s")


def _first_bad(t: np.ndarray, blocks: Sequence[tuple[str, np.ndarray, Sequence[str]]]) -> tuple[int, str] | None:
    """Earliest non-finite sample over the (kind, array, names) blocks: (index, description)."""
    best = None
    for kind, arr, names in blocks:
        if arr.size == 0:
            continue
        bad_rows = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad_rows.size and (best is None or bad_rows[0] < best[0]):
            k = int(bad_rows[0])
            j = int(np.flatnonzero(~np.isfinite(arr[k]))[0])
            best = (k, f"{kind} {names[j]!r} is {arr[k, j]}")
    return best


def _refuse_non_finite(t, blocks, cause: Callable[[], str]) -> None:
    """DataError naming the first non-finite sample and signal of the blocks and the likely cause."""
    hit = _first_bad(t, blocks)
    if hit is None:
        return
    k, what = hit
    raise DataError(f"simulate would return a non-finite trace: {what} at sample {k} (t={t[k]:g} s) and after. "
                    f"Likely cause: {cause()}")


def _linear_cause(model: FaultModel, v: np.ndarray) -> str:
    """Why a linear run overflowed: the unstable eigenvalue, or inputs too large for the float range."""
    text = _instability(model.A, model.is_discrete, "A" if not model.is_discrete else "the discrete A")
    if text is not None:
        return text + "; stabilise the plant (close a loop) or simulate a shorter run"
    big = float(np.abs(v).max()) if v.size else 0.0
    return (f"the plant is stable, so its inputs are too large for the float range (largest |input| = {big:.3g}, "
            "faults included); scale the inputs or fault sizes down")


def _apply_faults(scenario: FaultScenario, location: str, t: np.ndarray, signals: np.ndarray,
                  names: Sequence[str], streams: Sequence[np.random.Generator]) -> np.ndarray:
    """``signals`` (N, k) with the scenario's ``location`` faults applied in scenario order, one stream per fault.

    A fault that makes a finite signal non-finite (an overflow of a finite but huge size) is
    refused with a DataError naming the fault, the signal and the first bad sample.
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
    noise_cov=None,
    measurement_noise=None,
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
    noise_cov : optional
        Linear plants: covariance (or std vector) of the model's noise group ``w``, drawn
        every sample and held over it.  Nonlinear plants: covariance of an additive
        state increment per sample.
    measurement_noise : optional
        Standard deviations (scalar or one per output, finite and >= 0) or a p x p covariance.
    rng : numpy.random.Generator or int seed (>= 0)
    method : ``'rk4'`` (fixed step, ``substeps`` per sample) or ``'solve_ivp'`` (RK45), nonlinear plants only.
    substeps : int >= 1
    meta : dict, optional
        Extra metadata stored in the trace.

    Raises
    ------
    ParameterError
        For a bad argument: a plant of another type, a duration, dt, x0, noise level, seed,
        method or substeps out of range or not a number, an unknown fault target, or a run whose
        arrays would not fit in the available memory (the message gives the bytes it needs).
    DataError
        For unusable signal data (u, d or t of the wrong shape, non-numeric or non-finite), and
        for a run that would return non-finite samples.
    """
    if not isinstance(plant, FaultModel | NonlinearPlant):
        raise ParameterError(f"cannot simulate a {type(plant).__name__}; pass a FaultModel or a NonlinearPlant "
                             "as plant (e.g. fdikit.plants.get_plant(name))")
    scenario = _scenario(scenario)
    rng, seed = _generator(rng)
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
            if dt is not None and not np.isclose(_sample_time(dt), plant.dt):
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
        h, duration = _sample_time(dt), _duration(duration)
        N = _sample_count(duration, h)
        need = _simulation_bytes(N, len(states), len(outputs), len(controls), len(dists), n_drive, label_chars)
        _check_memory(need, f"simulate(duration={duration:g} s, dt={h:g} s) of {N} samples")
        t = np.arange(N) * h
    else:
        if duration is not None:
            raise ParameterError("simulate: give either t or duration (with dt), not both")
        t = _times(t)
        N = t.size
        need = _simulation_bytes(N, len(states), len(outputs), len(controls), len(dists), n_drive, label_chars)
        _check_memory(need, f"simulate of {N} samples")
        h = float(t[1] - t[0]) if N > 1 else float(_sample_time(dt) if dt is not None else 1.0)
        if N > 1 and dt_given is not None and not np.isclose(_sample_time(dt_given), h, rtol=1e-9):
            raise ParameterError(f"simulate: dt={dt_given} differs from the spacing {h:g} s of t; omit dt")
    if isinstance(plant, FaultModel) and plant.is_discrete and N > 1 and not np.isclose(h, plant.dt, rtol=1e-9):
        raise DataError(f"t is spaced {h:g} s but the discrete plant runs at dt={plant.dt:g} s; give t at its dt")
    x0 = _initial_state(x0, states)
    if isinstance(plant, FaultModel):
        W = _covariance("noise_cov", noise_cov, len(plant.noise), "noise input w")
    else:
        W = _covariance("noise_cov", noise_cov, len(states), "state")
    R = _covariance("measurement_noise", measurement_noise, len(outputs), "output")
    u_cmd = _signal("u", u, t, controls)
    d_arr = _signal("d", d, t, dists)
    _warn_inactive(scenario, t)

    # independent streams: adding a fault or a noise source never shifts the others' draws
    rng_w, rng_v, *rng_f = rng.spawn(2 + len(scenario))
    u_act = _apply_faults(scenario, "actuator", t, u_cmd, controls, rng_f)
    if isinstance(plant, FaultModel):
        y, x = _simulate_linear(plant, h, t, u_act, d_arr, x0, W, rng_w)
    else:
        y, x = _simulate_nonlinear(plant, t, h, u_act, x0, W, rng_w, method, substeps)

    if R is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            y = y + _gaussian(rng_v, R, N)
        _refuse_non_finite(t, [("output", y, outputs)], lambda: "the measurement noise is too large for the outputs")
    y = _apply_faults(scenario, "sensor", t, y, outputs, rng_f)

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
    _refuse_non_finite(t, [("state", x, model.states), ("output", y, model.outputs)],
                       lambda: _linear_cause(model, v))
    np.add(y, 0.0, out=y)
    np.add(x, 0.0, out=x)
    return y, x


def _jacobian_text(f, tk: float, xk: np.ndarray, uk: np.ndarray) -> str:
    """The largest-real-part eigenvalue of a central-difference Jacobian of ``f`` at ``xk`` (best effort)."""
    try:
        n = xk.size
        J = np.empty((n, n))
        with np.errstate(all="ignore"):
            for i in range(n):
                step = 1e-6 * max(1.0, abs(xk[i]))
                e = np.zeros(n)
                e[i] = step
                J[:, i] = (np.asarray(f(tk, xk + e, uk), dtype=float) - np.asarray(f(tk, xk - e, uk), dtype=float)) \
                    / (2 * step)
        text = _instability(J, False, "the Jacobian of f at the last finite state")
    except Exception:  # noqa: BLE001 - only a diagnosis
        return ""
    return f"; {text}" if text else ""


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
                                    f"the state {state}: {sol.message}{_jacobian_text(plant.f, t[k], xk, uk)}")
                xk = sol.y[:, -1]
            if noise is not None:
                xk = xk + noise[k]
            if not np.all(np.isfinite(xk)):
                j = int(np.flatnonzero(~np.isfinite(xk))[0])
                raise DataError(
                    f"the nonlinear plant state {plant.states[j]!r} became non-finite ({xk[j]}) at sample {k + 1} "
                    f"(t={t[k + 1]:g} s). Likely cause: the plant is unstable or escapes in finite time"
                    f"{_jacobian_text(plant.f, t[k], x_prev, uk)}, or the step is too large for {method} "
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
    scenario = _scenario(scenario)
    gen, _ = _generator(rng)
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
    # the per-sample matrix gathers of _simulate_varying: B, C, D (A is indexed sample by sample)
    need = _simulation_bytes(N, n, p + 1, len(m0.controls), len(m0.disturbances), nv,
                             sum(len(f.name) + 1 for f in scenario)) + 8.0 * N * (n * nv + p * n + p * nv)
    _check_memory(need, f"simulate_scheduled of {N} samples")
    t = np.arange(rho.size) * m0.dt
    x0 = _initial_state(x0, m0.states)
    u_cmd = _signal("u", u, t, m0.controls)
    d_arr = _signal("d", d, t, m0.disturbances)
    _warn_inactive(scenario, t)
    _, _, *rng_f = gen.spawn(2 + len(scenario))  # the fault streams of simulate()
    u_act = _apply_faults(scenario, "actuator", t, u_cmd, m0.controls, rng_f)
    if np.all(rho == rho[0]):
        y, x = _simulate_linear(m0, m0.dt, t, u_act, d_arr, x0, None, None)
    else:
        y, x = _simulate_varying(family, m0, rho, np.hstack([u_act, d_arr]), x0)
        with np.errstate(over="ignore", invalid="ignore"):
            _refuse_non_finite(t, [("state", x, m0.states), ("output", y, m0.outputs)],
                               lambda: _scheduled_cause(family, m0, rho, x))
        np.add(y, 0.0, out=y)
        np.add(x, 0.0, out=x)
    y = _apply_faults(scenario, "sensor", t, y, m0.outputs, rng_f)
    return Trace(t=t, u=u_cmd, y=np.hstack([y, rho[:, None]]), controls=m0.controls,
                 outputs=m0.outputs + (schedule_name,), x=x, states=m0.states, d=d_arr,
                 disturbances=m0.disturbances, fault=scenario.truth(t),
                 meta={"plant": repr(m0), "scenario": scenario.label, "schedule": schedule_name})


def _scheduled_cause(family, m0: FaultModel, rho: np.ndarray, x: np.ndarray) -> str:
    """Why a scheduled run overflowed: the most unstable frozen model ``A(ρ)`` on the schedule before it did."""
    bad = np.flatnonzero(~np.all(np.isfinite(x), axis=1))
    upto = rho[: int(bad[0])] if bad.size and bad[0] > 0 else rho
    values = np.unique(upto)
    try:
        A = _scheduled_matrices(family, m0, values, int(np.searchsorted(values, rho[0])))[0]
        radius = np.abs(np.linalg.eigvals(A)).max(axis=1)
    except Exception:  # noqa: BLE001 - only a diagnosis
        return "the inputs or the frozen models; check the family"
    i = int(np.argmax(radius))
    text = _instability(A[i], True, f"the frozen model A(ρ = {values[i]:g})")
    if text is None:
        return (f"every frozen model on the schedule is stable (largest |λ| = {radius[i]:.6g}), so the schedule's "
                "variation or the inputs drive the growth; check the schedule rate and the inputs")
    return text + "; stabilise the plant or simulate a shorter schedule"


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
    x = np.empty((rho.size, m0.n))
    xk = np.zeros(m0.n) if x0 is None else x0
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(rho.size):
            x[k] = xk
            xk = A[idx[k]] @ xk + drive[k]
        y = np.einsum("kij,kj->ki", C[idx], x) + np.einsum("kij,kj->ki", D[idx], v)
    return y, x
