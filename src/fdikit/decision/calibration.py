"""Calibration on a list of fault-free runs, and the report of the false-alarm rate the data support.

:func:`calibration_runs` pools the valid rows of one or several runs (the evaluators' ``fit`` take a list of
:class:`~fdikit.residuals.Residuals`), keeping the runs apart for everything that runs in time: each run is
evaluated on its own, so no persistence window, CUSUM sum or GLR window crosses a run boundary, and the
duration is the sum of the runs' durations (no glued times).  :func:`calibration_report` runs the calibrated
evaluator on those runs and states the achieved rate with its exact Poisson (Garwood) interval
(:func:`fdikit.metrics.rate_interval`) and the smallest rate the data length can resolve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.decision.common import checked_residuals
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["CalibrationReport", "CalibrationRuns", "calibration_report", "calibration_runs"]


@dataclass(frozen=True, eq=False)
class CalibrationRuns:
    """Fault-free calibration data from one or several runs (:func:`calibration_runs`).

    Attributes
    ----------
    runs : tuple of Residuals
        The runs, each evaluated on its own (no persistence window or test statistic crosses from one run
        into the next).
    rows : (M, q) ndarray
        The valid, finite rows of all runs, pooled (run order).
    names : tuple of str
        Residual names (the same in every run).
    isolates : tuple of (str or None)
        The fault tied to each residual (the same in every run).
    dt : float
        Sample time [s]: the median of the time steps within the runs (never across a boundary).
    hours : float
        Total duration [h]: every run's samples times its median time step (``dt`` for a one-sample run),
        as :func:`fdikit.metrics.score` counts fault-free hours.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.calibration import calibration_runs
    >>> a = Residuals(np.arange(3) * 0.5, np.zeros((3, 1)), ("r",), ("f",))
    >>> runs = calibration_runs([a, a], minimum=1)
    >>> runs.rows.shape, runs.dt, runs.hours * 3600
    ((6, 1), 0.5, 3.0)
    """

    runs: tuple
    rows: np.ndarray
    names: tuple
    isolates: tuple
    dt: float
    hours: float


def calibration_runs(residuals, minimum: int = 10) -> CalibrationRuns:
    """One fault-free :class:`~fdikit.residuals.Residuals`, or a list of runs, as pooled calibration data.

    Parameters
    ----------
    residuals : Residuals or sequence of Residuals
        Fault-free runs with the same residual names and tied faults (their times may restart; each run's
        times must increase).
    minimum : int, default 10
        Fewest valid, finite rows accepted over all runs.

    Returns
    -------
    CalibrationRuns
        The runs, the pooled rows, the sample time and the total duration.

    Raises
    ------
    DataError
        When a run is not a ``Residuals``, the list is empty, the runs' names or tied faults differ, no run has
        two samples (no sample time), or fewer than ``minimum`` rows are usable.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.calibration import calibration_runs
    >>> a = Residuals(np.arange(8) * 0.1, np.ones((8, 2)), ("a", "b"), ("fa", "fb"))
    >>> calibration_runs([a, a]).rows.shape
    (16, 2)
    """
    runs = (residuals,) if isinstance(residuals, Residuals) else residuals
    try:
        runs = tuple(runs)
    except TypeError:
        raise DataError(f"fit needs fault-free Residuals or a list of them, got {type(residuals).__name__}") from None
    if not runs:
        raise DataError("fit got an empty list of runs; give at least one fault-free Residuals")
    first = checked_residuals(runs[0], None)
    for k, run in enumerate(runs[1:], start=1):
        checked_residuals(run, first.names, f"run 0 of the list (checking run {k})")
        if tuple(run.isolates) != tuple(first.isolates):
            raise DataError(f"run {k} ties its residuals to {list(run.isolates)}, run 0 to {list(first.isolates)}; "
                            "calibrate on runs of the same generator")
    steps = [np.diff(np.asarray(run.t, float)) for run in runs]
    within = np.concatenate(steps) if steps else np.empty(0)
    if within.size == 0:
        raise DataError("no run has two samples, so there is no sample time; give runs of at least two samples")
    dt = float(np.median(within))
    hours = sum(len(run.t) * (float(np.median(d)) if d.size else dt) for run, d in zip(runs, steps)) / 3600.0
    rows = [run.r[run.valid] for run in runs]
    rows = np.vstack([r[np.all(np.isfinite(r), axis=1)] for r in rows])
    if rows.shape[0] < minimum:
        raise DataError(f"need at least {minimum} valid fault-free samples to calibrate, got {rows.shape[0]}")
    return CalibrationRuns(runs, rows, tuple(first.names), tuple(first.isolates), dt, hours)


@dataclass(frozen=True)
class CalibrationReport:
    """What the calibration data say about the false-alarm rate an evaluator achieves.

    Attributes
    ----------
    runs : int
        Number of calibration runs.
    samples : int
        Valid, finite samples used.
    hours : float
        Duration of the calibration data [h].
    alarms : int
        Alarms (rising edges) the calibrated evaluator raises on the calibration runs, each run evaluated on its
        own.
    target_rate : float or None
        The false-alarm rate asked for [1/h] (None when the calibration had no rate target).
    confidence : float
        Level of ``interval``.
    rate : float
        ``alarms / hours`` [1/h].
    interval : (float, float)
        Exact Poisson (Garwood) confidence interval of the rate [1/h] (:func:`fdikit.metrics.rate_interval`).
    min_resolvable_rate : float
        The smallest rate the data can resolve [1/h]: the upper end of the interval for zero alarms,
        ``χ²_{(1+c)/2}(2) / (2 T)`` (``≈ 3.69 / T`` at 95 %) — a rate below it cannot be told from zero.

    References
    ----------
    Douglas et al. 1996, Ch. 1 (thresholds set from empirical studies of the false-alarm rate); the interval is
    :func:`fdikit.metrics.rate_interval`.

    Examples
    --------
    >>> from fdikit.decision.calibration import CalibrationReport
    >>> rep = CalibrationReport(2, 72000, 2.0, 3, 1.0)
    >>> rep.rate, [round(x, 4) for x in rep.interval], round(rep.min_resolvable_rate, 4)
    (1.5, [0.3093, 4.3836], 1.8444)
    """

    runs: int
    samples: int
    hours: float
    alarms: int
    target_rate: float | None = None
    confidence: float = 0.95

    @property
    def rate(self) -> float:
        return self.alarms / self.hours if self.hours > 0 else float("nan")

    @property
    def interval(self) -> tuple[float, float]:
        from fdikit.metrics import rate_interval

        return rate_interval(self.alarms, self.hours, self.confidence)

    @property
    def min_resolvable_rate(self) -> float:
        from fdikit.metrics import rate_interval

        return rate_interval(0, self.hours, self.confidence)[1]


def calibration_report(evaluator, runs: CalibrationRuns, target_rate: float | None = None,
                       confidence: float = 0.95) -> CalibrationReport:
    """Run a calibrated ``evaluator`` on each calibration run (separately) and report its false-alarm rate.

    Parameters
    ----------
    evaluator : Evaluator
        The calibrated evaluator (its ``run`` is called once per run; its online state is reset after).
    runs : CalibrationRuns
        The calibration data (:func:`calibration_runs`).
    target_rate : float, optional
        The rate asked for [1/h], recorded in the report.
    confidence : float, default 0.95
        Level of the interval, in (0, 1).

    Returns
    -------
    CalibrationReport
        Hours, alarm count, rate interval and the smallest resolvable rate.

    Raises
    ------
    ParameterError
        When ``confidence`` is not in (0, 1).

    References
    ----------
    Douglas et al. 1996, Ch. 1 (thresholds set from empirical studies of the false-alarm rate).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.decision.calibration import calibration_runs, calibration_report
    >>> run = Residuals(np.arange(4) * 900.0, np.array([[0.0], [2.0], [0.0], [2.0]]), ("r",), ("f",))
    >>> calibration_report(ThresholdEvaluator(thresholds=1.0), calibration_runs([run], minimum=1)).alarms
    2
    """
    if not 0 < confidence < 1:
        raise ParameterError(f"confidence must be in (0, 1), got {confidence}")
    alarms = 0
    for run in runs.runs:
        alarms += len(evaluator.run(run).alarms)
    evaluator.reset()
    return CalibrationReport(len(runs.runs), int(runs.rows.shape[0]), float(runs.hours), int(alarms),
                             None if target_rate is None else float(target_rate), float(confidence))
