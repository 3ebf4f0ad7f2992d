"""Argument checks, the memory check and the non-finite-trace diagnosis of :mod:`fdikit.simulate`.

An internal module: :func:`fdikit.simulate.simulate`, :func:`~fdikit.simulate.simulate_scheduled`
and :func:`~fdikit.simulate.time_grid` call these helpers; import the simulators from
:mod:`fdikit.simulate`.  It holds

* the argument checks, run before any work: bad arguments (duration, dt, x0, noise levels, seeds,
  the scenario) raise :class:`~fdikit.errors.ParameterError`, bad signal data (u, d, t)
  :class:`~fdikit.errors.DataError`, and a fault that acts on no sample of the run gives an
  :class:`~fdikit.errors.FdiWarning`;
* the memory check: the bytes a run's arrays need (:func:`simulation_bytes`) against the memory
  available (``MemAvailable`` of ``/proc/meminfo``, else ``os.sysconf``), refused at once with a
  ParameterError that gives both (:func:`check_memory`, :func:`sample_count`);
* the non-finite-trace diagnosis: the DataError naming the first non-finite sample (index and
  time) and signal of a run (:func:`refuse_non_finite`), and the likely cause — the unstable
  eigenvalue (Re λ > 0, or |λ| > 1 when discrete) of the plant (:func:`linear_cause`), of the
  Jacobian of a nonlinear plant (:func:`jacobian_text`) or of the most unstable frozen model of a
  schedule (:func:`scheduled_cause`), or inputs too large for the float range.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Sequence

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, FdiWarning, ParameterError
from fdikit.faults import FaultScenario
from fdikit.model import FaultModel

__all__ = [
    "check_noise",
    "check_duration",
    "check_initial_state",
    "check_memory",
    "check_rng",
    "check_sample_time",
    "check_scenario",
    "check_signal",
    "check_times",
    "jacobian_text",
    "linear_cause",
    "refuse_non_finite",
    "sample_count",
    "scheduled_cause",
    "simulation_bytes",
    "warn_inactive",
]


# ---------------------------------------------------------------------------------------------- argument checks

def _number(name: str, value) -> float:
    """A finite float from a real number argument (ParameterError otherwise)."""
    return validate.number(f"simulate: {name}", value)


def check_sample_time(dt) -> float:
    """The sample time ``dt`` as a float: a finite number > 0 (ParameterError otherwise)."""
    dt = _number("dt (the sample time)", dt)
    if not dt > 0:
        raise ParameterError(f"simulate: dt (the sample time) must be > 0, got {dt}")
    return dt


def check_duration(duration) -> float:
    """The ``duration`` of a run as a float: a finite number >= 0 (ParameterError otherwise)."""
    duration = _number("duration", duration)
    if not duration >= 0:
        raise ParameterError(f"simulate: duration must be >= 0, got {duration}")
    return duration


def check_times(t) -> np.ndarray:
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


def check_rng(rng) -> tuple[np.random.Generator, int | None]:
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


def check_scenario(scenario) -> FaultScenario:
    """The scenario, an empty :class:`FaultScenario` for None (ParameterError for another type)."""
    if scenario is None:
        return FaultScenario()
    if not isinstance(scenario, FaultScenario):
        raise ParameterError(f"simulate: scenario must be a FaultScenario (e.g. FaultScenario([Bias(...)])) or None, "
                             f"got {type(scenario).__name__} {scenario!r:.60}")
    return scenario


def check_signal(name: str, value, t: np.ndarray, names: Sequence[str]) -> np.ndarray:
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


def check_noise(std_name: str, std, cov_name: str, cov, k: int, what: str) -> np.ndarray | None:
    """Covariance of ``k`` noise signals from ``std`` (standard deviations) or ``cov`` (a covariance), or None.

    Parameters
    ----------
    std_name, std, cov_name, cov, k, what :
        As for :func:`fdikit.validate.noise_covariance` (the std/cov convention), which does the check.

    Returns
    -------
    (k, k) ndarray or None

    Raises
    ------
    ParameterError
        Noise given for no signal (``k == 0``: the model has no noise inputs), or as
        :func:`fdikit.validate.noise_covariance`.

    Examples
    --------
    >>> check_noise("noise_std", 0.5, "noise_cov", None, 2, "state").tolist()
    [[0.25, 0.0], [0.0, 0.25]]
    """
    if (std is not None or cov is not None) and k == 0:
        name = std_name if std is not None else cov_name
        raise ParameterError(f"{name} was given but there is no signal for it (the model has no noise inputs w); "
                             "add a noise group (FaultModel(..., Bw=..., noise=[...])) or omit it")
    return validate.noise_covariance(std_name, std, cov_name, cov, k, what)


def check_initial_state(x0, states: Sequence[str]) -> np.ndarray | None:
    """``x0`` as one finite float per state, or None when not given (ParameterError otherwise)."""
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


def warn_inactive(scenario: FaultScenario, t: np.ndarray) -> None:
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


# ---------------------------------------------------------------------------------------------- memory

def _human(nbytes: float) -> str:
    """``nbytes`` in KiB … EiB, three significant digits."""
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


def check_memory(nbytes: float, what: str) -> None:
    """Refuse (ParameterError) a run whose arrays need more than the available memory."""
    available, source = _available_memory()
    if nbytes > available:
        raise ParameterError(
            f"{what} needs about {nbytes:.3g} bytes ({_human(nbytes)}) of memory for its arrays, but only "
            f"{_human(available)} are available ({source}); shorten the duration, use a larger dt, "
            "or simulate in pieces (pass x0 = the last state of the previous piece)"
        )


def sample_count(duration: float, dt: float) -> int:
    """``round(duration / dt) + 1`` samples, refusing counts that no memory holds before computing them."""
    ratio = duration / dt
    if not math.isfinite(ratio) or ratio > 2.0**62:
        check_memory(math.inf if not math.isfinite(ratio) else 8.0 * ratio,
                      f"duration={duration:g} s at dt={dt:g} s ({ratio:.3g} samples)")
    return int(round(ratio)) + 1


def simulation_bytes(N: int, n: int, p: int, m: int, nd: int, nv: int, label_chars: int) -> float:
    """Bytes of the arrays a simulation of N samples allocates (a lower bound of the peak).

    Per sample: times (1), commanded and faulty controls and their copies (3 m), disturbances (2 nd),
    the stacked and block-padded solver input (2 nv), states from the block solver and the trace
    (3 n), outputs with noise, faults and the trace copy (6 p), all float64; plus the truth labels
    (an object array and a str array of ``label_chars`` characters).
    """
    floats = 1 + 3 * m + 2 * nd + 2 * nv + 3 * n + 6 * p
    return float(N) * (8.0 * floats + 8.0 + 4.0 * max(label_chars, 4))


# ---------------------------------------------------------------------------------------------- non-finite results

_FLOAT_RANGE_LOG = math.log(np.finfo(float).max)  # ln(1.8e308): a state growing like e^{at} overflows at a t ≈ 709.8


def _eig_text(lam: complex) -> str:
    """An eigenvalue as text: the real part alone when it is real."""
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


def refuse_non_finite(t, blocks, cause: Callable[[], str]) -> None:
    """DataError naming the first non-finite sample and signal of the blocks and the likely cause."""
    hit = _first_bad(t, blocks)
    if hit is None:
        return
    k, what = hit
    raise DataError(f"simulate would return a non-finite trace: {what} at sample {k} (t={t[k]:g} s) and after. "
                    f"Likely cause: {cause()}")


def linear_cause(model: FaultModel, v: np.ndarray) -> str:
    """Why a linear run overflowed: the unstable eigenvalue, or inputs too large for the float range."""
    text = _instability(model.A, model.is_discrete, "A" if not model.is_discrete else "the discrete A")
    if text is not None:
        return text + "; stabilise the plant (close a loop) or simulate a shorter run"
    big = float(np.abs(v).max()) if v.size else 0.0
    return (f"the plant is stable, so its inputs are too large for the float range (largest |input| = {big:.3g}, "
            "faults included); scale the inputs or fault sizes down")


def jacobian_text(f, tk: float, xk: np.ndarray, uk: np.ndarray) -> str:
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


def scheduled_cause(frozen_A: Callable[[np.ndarray], np.ndarray], rho: np.ndarray, x: np.ndarray) -> str:
    """Why a scheduled run overflowed: the most unstable frozen model ``A(ρ)`` on the schedule before it did.

    ``frozen_A(values)`` is the stack of the frozen ``A(ρ)`` at the distinct schedule ``values``
    (sorted); ``x`` holds the run's states, one row per sample of ``rho``.
    """
    bad = np.flatnonzero(~np.all(np.isfinite(x), axis=1))
    upto = rho[: int(bad[0])] if bad.size and bad[0] > 0 else rho
    values = np.unique(upto)
    try:
        A = frozen_A(values)
        radius = np.abs(np.linalg.eigvals(A)).max(axis=1)
    except Exception:  # noqa: BLE001 - only a diagnosis
        return "the inputs or the frozen models; check the family"
    i = int(np.argmax(radius))
    text = _instability(A[i], True, f"the frozen model A(ρ = {values[i]:g})")
    if text is None:
        return (f"every frozen model on the schedule is stable (largest |λ| = {radius[i]:.6g}), so the schedule's "
                "variation or the inputs drive the growth; check the schedule rate and the inputs")
    return text + "; stabilise the plant or simulate a shorter schedule"
