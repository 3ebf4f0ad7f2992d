"""Argument checks and the memory check of :mod:`fdikit.simulate`.

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
* (the non-finite-trace diagnosis is :mod:`fdikit.simulate_diagnosis`).

Examples
--------
>>> from fdikit.simulate_checks import check_sample_time
>>> check_sample_time(0.01)
0.01
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, FdiWarning, ParameterError
from fdikit.faults import FaultScenario

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
    "sample_count",
    "simulation_bytes",
    "warn_inactive",
]


# ---------------------------------------------------------------------------------------------- argument checks

def _number(name: str, value) -> float:
    """A finite float from a real number argument (ParameterError otherwise)."""
    return validate.number(f"simulate: {name}", value)


def check_sample_time(dt) -> float:
    """The sample time ``dt`` as a float: a finite number > 0 (ParameterError otherwise).

    Parameters
    ----------
    dt : float
        Sample time [s].

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        For a non-number, NaN, ±inf, zero or a negative ``dt``.

    Examples
    --------
    >>> check_sample_time(0.01)
    0.01
    """
    dt = _number("dt (the sample time)", dt)
    if not dt > 0:
        raise ParameterError(f"simulate: dt (the sample time) must be > 0, got {dt}")
    return dt


def check_duration(duration) -> float:
    """The ``duration`` of a run as a float: a finite number >= 0 (ParameterError otherwise).

    Parameters
    ----------
    duration : float
        Length of the run [s] (0 gives one sample).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        For a non-number, NaN, ±inf or a negative ``duration``.

    Examples
    --------
    >>> check_duration(2)
    2.0
    """
    duration = _number("duration", duration)
    if not duration >= 0:
        raise ParameterError(f"simulate: duration must be >= 0, got {duration}")
    return duration


def check_times(t) -> np.ndarray:
    """Given sample times: 1-D, non-empty, finite, strictly increasing and uniformly spaced (DataError).

    Parameters
    ----------
    t : (N,) array_like
        Sample times [s]; steps equal to a relative 1e-9.

    Returns
    -------
    (N,) ndarray

    Raises
    ------
    DataError
        For non-numbers, an array that is not 1-D, an empty one, a non-finite time, or times that
        are not strictly increasing or not uniformly spaced.

    Examples
    --------
    >>> check_times([0, 0.1, 0.2]).tolist()
    [0.0, 0.1, 0.2]
    """
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
    """``numpy.random.default_rng(rng)`` and the integer seed (when one was given).

    Parameters
    ----------
    rng : numpy.random.Generator, int or None
        A generator (used as is), a seed >= 0, or None (fresh entropy).

    Returns
    -------
    generator : numpy.random.Generator
    seed : int or None
        The seed, or None when ``rng`` was not an integer (stored in the trace's metadata).

    Raises
    ------
    ParameterError
        For a bool, str, bytes, float, a negative seed or anything ``default_rng`` refuses.

    Examples
    --------
    >>> gen, seed = check_rng(7)
    >>> type(gen).__name__, seed
    ('Generator', 7)
    """
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
    """The scenario, an empty :class:`~fdikit.faults.FaultScenario` for None (ParameterError for another type).

    Parameters
    ----------
    scenario : FaultScenario or None
        The faults of a run.

    Returns
    -------
    FaultScenario

    Raises
    ------
    ParameterError
        When ``scenario`` is neither a FaultScenario nor None.

    Examples
    --------
    >>> check_scenario(None)
    FaultScenario([], label='none')
    """
    if scenario is None:
        return FaultScenario()
    if not isinstance(scenario, FaultScenario):
        raise ParameterError(f"simulate: scenario must be a FaultScenario (e.g. FaultScenario([Bias(...)])) or None, "
                             f"got {type(scenario).__name__} {scenario!r:.60}")
    return scenario


def check_signal(name: str, value, t: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """(N, k) block from None (zeros), an array, or a callable ``t -> (k,)`` (DataError when unusable).

    Parameters
    ----------
    name : str
        The argument's name (``"u"``, ``"d"``), as the messages quote it.
    value : None, (N, k) array_like or callable ``t -> (k,)``
        The signal; with ``k == 1`` a 1-D array of N samples is accepted too.
    t : (N,) ndarray
        Sample times [s] (the callable is evaluated at each).
    names : sequence of str
        The ``k`` signal names (one column each).

    Returns
    -------
    (N, k) ndarray

    Raises
    ------
    DataError
        When the callable raises or returns the wrong shape, the array holds non-numbers or has
        the wrong shape, or an entry is not finite (the message gives signal, sample and time).

    Examples
    --------
    >>> import numpy as np
    >>> check_signal("u", lambda t: [t, 1.0], np.arange(3) * 0.5, ("a", "b")).tolist()
    [[0.0, 1.0], [0.5, 1.0], [1.0, 1.0]]
    """
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
    """``x0`` as one finite float per state, or None when not given (ParameterError otherwise).

    Parameters
    ----------
    x0 : (n,) array_like or None
        Initial state.
    states : sequence of str
        The plant's ``n`` state names.

    Returns
    -------
    (n,) ndarray or None

    Raises
    ------
    ParameterError
        For non-numbers, the wrong shape or a non-finite entry.

    Examples
    --------
    >>> check_initial_state([1, 2], ("pos", "vel")).tolist()
    [1.0, 2.0]
    """
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
    """An FdiWarning for each fault that acts on no sample of the run (its onset after the end, say).

    Parameters
    ----------
    scenario : FaultScenario
        The run's faults.
    t : (N,) ndarray
        Sample times [s].

    Examples
    --------
    >>> import warnings
    >>> import numpy as np
    >>> from fdikit.faults import Bias, FaultScenario
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_inactive(FaultScenario([Bias("y", 1.0, onset=5.0)]), np.arange(3.0))
    >>> caught[0].category.__name__
    'FdiWarning'
    """
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
    """Refuse (ParameterError) a run whose arrays need more than the available memory.

    Parameters
    ----------
    nbytes : float
        Bytes the run's arrays need (:func:`simulation_bytes`).
    what : str
        The run, as the message names it.

    Raises
    ------
    ParameterError
        When ``nbytes`` exceeds the memory available (``MemAvailable`` of ``/proc/meminfo``, else
        ``os.sysconf``); the message gives both and how to shorten the run.

    Examples
    --------
    >>> check_memory(2.0**70, "a test run")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: a test run needs about 1.18e+21 bytes (1.02e+03 EiB) of memory ...
    """
    available, source = _available_memory()
    if nbytes > available:
        raise ParameterError(
            f"{what} needs about {nbytes:.3g} bytes ({_human(nbytes)}) of memory for its arrays, but only "
            f"{_human(available)} are available ({source}); shorten the duration, use a larger dt, "
            "or simulate in pieces (pass x0 = the last state of the previous piece)"
        )


def sample_count(duration: float, dt: float) -> int:
    """``round(duration / dt) + 1`` samples, refusing counts that no memory holds before computing them.

    Parameters
    ----------
    duration : float
        Length of the run [s], checked (:func:`check_duration`).
    dt : float
        Sample time [s], checked (:func:`check_sample_time`).

    Returns
    -------
    int

    Examples
    --------
    >>> sample_count(1.0, 0.01)
    101
    """
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

    Parameters
    ----------
    N : int
        Number of samples.
    n, p, m, nd, nv : int
        Numbers of states, outputs, controls, disturbances and stacked solver inputs.
    label_chars : int
        Characters of one sample's fault-truth label.

    Returns
    -------
    float
        Bytes.

    Examples
    --------
    >>> simulation_bytes(101, 2, 1, 1, 0, 1, 0)
    16968.0
    """
    floats = 1 + 3 * m + 2 * nd + 2 * nv + 3 * n + 6 * p
    return float(N) * (8.0 * floats + 8.0 + 4.0 * max(label_chars, 4))
