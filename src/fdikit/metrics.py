"""Scores of a diagnosis against the truth: detection delay, false alarms, missed detection, isolation.

Definitions (one trace):

* the **fault label** is the first faulty truth label of the trace (``'none'`` if healthy);
* a **false alarm** is an alarm that switches on at a sample whose truth is ``'none'``;
  the rate is their number per hour of fault-free time;
* **detection** is the first sample at or after the onset where the fault is active
  and the alarm is on; the **delay** is its time minus the onset;
* a **missed detection** is a faulty trace never detected while the fault is active;
* the **isolated** fault is the label named most often while the fault is active and the alarm
  on, ``'unknown'`` included (the earliest on a tie) — a transient confusion, such as the air-mass
  fault rate leaking into the throttle residual (Douglas et al. 1996, Fig. 5.5), does not decide the
  isolation, but an alarm that is ``'unknown'`` most of the time is not a correct isolation;
  isolation is correct when it equals the fault label (``'unknown'`` never counts as correct);
* the **correct fraction** is the fraction of those alarmed samples on which the right fault is named;
* the **faulty interval** runs from the onset to the last sample of the first unbroken stretch of the
  fault label; the **isolation delay** is the time from the onset to the first sample at which the
  right fault is named *and held*: named on every valid sample (``Diagnosis.valid``) from then to the
  end of the faulty interval — or, with ``hold=`` seconds, on every valid sample from then until
  ``hold`` seconds later or the end of the faulty interval, whichever comes first.  None when the
  right fault is never named and held.

The false-alarm rate of a count observed over a given time has the exact Poisson (Garwood)
interval of :func:`rate_interval`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.diagnosis import UNKNOWN_FAULT, Diagnosis
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.trace import Trace

__all__ = ["Score", "Summary", "score", "summarize", "confusion_matrix", "rate_interval", "vaf", "MISSED"]

#: Column of the confusion matrix for a faulty trace that was never detected.
MISSED = "missed"


@dataclass(frozen=True)
class Score:
    """Scores of one trace (see the module docstring for the definitions).

    Attributes
    ----------
    label : str
        The trace's fault label (``'none'`` for a healthy trace).
    onset : float or None
        Time of the first faulty sample [s] (None when healthy).
    detected : bool
        Whether the alarm was on at a sample at or after the onset where the fault is active.
    detection_delay : float or None
        Detection time minus onset [s] (None when not detected).
    false_alarms : int
        Alarms switching on at fault-free samples.
    fault_free_hours : float
        Fault-free time of the trace [h] (fault-free samples times the median sample time).
    missed : bool
        A faulty trace never detected while the fault is active.
    isolated : str
        The isolated fault: the most frequent label (``'unknown'`` included) while detected, or ``'none'``
        (missed); for a healthy trace the isolation of its first false alarm (``'none'`` without one).
    isolation_correct : bool or None
        ``isolated == label`` for a faulty trace (False when missed or ``'unknown'``); None for a healthy one.
    isolation_delay : float or None
        Time from the onset until the right fault is named and held [s] (module docstring); None when it
        never is, or for a healthy trace.
    correct_fraction : float or None
        Fraction of the alarmed samples while the fault is active that name the right fault; None when not
        detected, or for a healthy trace.
    false_alarm_rate : float
        False alarms per hour of fault-free time (NaN without fault-free time).
    outcome : str
        Column of the confusion matrix: the isolated fault, ``'missed'``, or ``'none'``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.metrics import score, summarize
    >>> fired = np.array([[0, 0], [1, 0], [0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [1, 0]], dtype=bool)
    >>> d = Diagnosis(np.arange(8) * 0.5, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> s = score(np.array(["none"] * 4 + ["fa"] * 4), d)
    >>> s.detected, s.detection_delay, s.false_alarms, s.isolated, s.outcome, s.isolation_delay
    (True, 0.5, 1, 'fa', 'fa', 0.5)
    """

    label: str
    onset: float | None
    detected: bool
    detection_delay: float | None
    false_alarms: int
    fault_free_hours: float
    missed: bool
    isolated: str
    isolation_correct: bool | None
    isolation_delay: float | None = None
    correct_fraction: float | None = None

    @property
    def false_alarm_rate(self) -> float:
        """False alarms per hour of fault-free time (NaN without fault-free time)."""
        return self.false_alarms / self.fault_free_hours if self.fault_free_hours > 0 else float("nan")

    @property
    def outcome(self) -> str:
        """Column of the confusion matrix: the isolated fault, ``'missed'``, or ``'none'``."""
        if self.label == NO_FAULT:
            return NO_FAULT if self.false_alarms == 0 else self.isolated
        return MISSED if self.missed else self.isolated


def score(truth: Trace | np.ndarray, diagnosis: Diagnosis, hold: float | None = None) -> Score:
    """Score one diagnosis against a trace (or its per-sample truth labels).

    Parameters
    ----------
    truth : Trace or (N,) array of str
        The trace the diagnosis was run on (its ``fault`` labels), or the per-sample true fault labels
        (``'none'`` where healthy).
    diagnosis : Diagnosis
        An evaluator's decisions on that trace, sample for sample.
    hold : float, optional
        How long [s] the right fault must stay named for the isolation delay (module docstring); default
        to the end of the faulty interval.

    Returns
    -------
    Score
        Detection, delay, false alarms, missed detection, isolation and isolation delay of the trace.

    Raises
    ------
    ParameterError
        When ``diagnosis`` is not a :class:`~fdikit.diagnosis.Diagnosis`, or ``hold`` is negative.
    DataError
        When the labels are not strings, not one-dimensional, or not as many as the diagnosis's samples.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.metrics import score, summarize
    >>> fired = np.array([[0, 0], [1, 0], [0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [1, 0]], dtype=bool)
    >>> d = Diagnosis(np.arange(8) * 0.5, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> s = score(np.array(["none"] * 4 + ["fa"] * 4), d)
    >>> s.label, s.onset, s.detection_delay, round(s.false_alarm_rate, 6)
    ('fa', 2.0, 0.5, 1800.0)
    """
    validate.instance("diagnosis", diagnosis, Diagnosis, "pass the Diagnosis an evaluator's run() returned")
    if hold is not None:
        hold = validate.non_negative("hold", hold)
    if isinstance(truth, Trace):
        labels = truth.fault
    else:
        raw = np.asarray(truth)
        if raw.dtype.kind not in "UO":
            raise DataError(f"truth must be per-sample fault labels (strings) or a Trace, got an array of {raw.dtype}")
        if raw.dtype.kind == "O" and not all(isinstance(v, str) for v in raw.ravel()):
            raise DataError("truth labels must all be strings (e.g. 'none'); found a non-string label such as None")
        labels = raw.astype(str)
    if labels.ndim != 1:
        raise DataError(f"truth must be a 1-D array of per-sample labels, got shape {labels.shape}")
    t = diagnosis.t
    if labels.shape != t.shape:
        raise DataError(f"truth has {labels.size} samples but the diagnosis {t.size}; score the trace it was run on")
    healthy = labels == NO_FAULT
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    rises = np.array([a.index for a in diagnosis.alarms], dtype=int)
    false_alarms = int(healthy[rises].sum()) if rises.size else 0
    hours = float(healthy.sum() * dt / 3600.0)
    faulty = np.flatnonzero(~healthy)
    if faulty.size == 0:
        first_fa = next((a for a in diagnosis.alarms if healthy[a.index]), None)
        return Score(NO_FAULT, None, False, None, false_alarms, hours, False,
                     first_fa.fault if first_fa else NO_FAULT, None)
    label, onset_idx = str(labels[faulty[0]]), int(faulty[0])
    onset = float(t[onset_idx])
    hit = (~healthy) & diagnosis.alarm
    hit[:onset_idx] = False
    det = np.flatnonzero(hit)
    end = onset_idx + int(np.argmax(np.append(labels[onset_idx:] != label, True)))  # one past the interval
    right = (np.asarray(diagnosis.isolated) == label) & (label != UNKNOWN_FAULT)  # 'unknown' is never right
    iso_delay = _isolation_delay(t, right, diagnosis.valid, onset_idx, end, hold)
    if det.size == 0:
        return Score(label, onset, False, None, false_alarms, hours, True, NO_FAULT, False, iso_delay, None)
    said = np.asarray(diagnosis.isolated)[det].astype(str)
    names, first, counts = np.unique(said, return_index=True, return_counts=True)
    isolated = str(names[np.lexsort((first, -counts))[0]])
    correct = isolated == label and label != UNKNOWN_FAULT
    return Score(label, onset, True, float(t[det[0]] - onset), false_alarms, hours, False, isolated,
                 correct, iso_delay, float(np.mean(right[det])))


def _isolation_delay(t, right, valid, start: int, end: int, hold: float | None) -> float | None:
    """Onset to the first valid sample in ``[start, end)`` naming the fault and holding it (module docstring)."""
    idx = np.arange(start, end)
    use = idx[valid[start:end]]
    if use.size == 0:
        return None
    ok = right[use]
    bad = use[~ok]
    cand = use[ok]
    if cand.size == 0:
        return None
    if hold is None:
        if bad.size and bad[-1] > cand[-1]:
            return None
        k = cand[cand > bad[-1]][0] if bad.size else cand[0]
    else:
        nxt = np.searchsorted(bad, cand)  # the first wrong valid sample after each candidate
        clear = np.ones(cand.size, bool)
        has = nxt < bad.size
        clear[has] = t[bad[nxt[has]]] > t[cand[has]] + hold
        if not clear.any():
            return None
        k = cand[np.argmax(clear)]
    return float(t[k] - t[start])


@dataclass(frozen=True)
class Summary:
    """Aggregate over many traces.

    Attributes
    ----------
    runs : int
        Number of traces.
    faulty_runs : int
        Traces with a fault.
    detection_rate : float
        Detected faulty traces / faulty traces (NaN without faulty traces).
    missed_rate : float
        Missed faulty traces / faulty traces.
    mean_delay, median_delay : float
        Of the detection delays of the detected traces [s] (NaN when none).
    false_alarms : int
        False alarms over all traces.
    false_alarm_rate : float
        False alarms per hour of fault-free time pooled over all traces [1/h].
    isolation_accuracy : float
        Correctly isolated / detected faulty traces (``'unknown'`` is never correct).
    mean_isolation_delay, median_isolation_delay : float
        Of the isolation delays of the faulty traces whose fault was named and held [s] (NaN when none).
    isolation_held_rate : float
        Faulty traces whose fault was named and held / faulty traces (NaN without faulty traces).
    mean_correct_fraction : float
        Mean over the detected faulty traces of the fraction of alarmed samples correctly named (NaN when none).
    confusion : pandas.DataFrame
        :func:`confusion_matrix` of the scores.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.metrics import score, summarize
    >>> fired = np.array([[0, 0], [1, 0], [0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [1, 0]], dtype=bool)
    >>> d = Diagnosis(np.arange(8) * 0.5, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> s = score(np.array(["none"] * 4 + ["fa"] * 4), d)
    >>> summarize([s]).as_dict()["detection_rate"], summarize([s]).runs
    (1.0, 1)
    """

    runs: int
    faulty_runs: int
    detection_rate: float
    missed_rate: float
    mean_delay: float
    median_delay: float
    false_alarms: int
    false_alarm_rate: float
    isolation_accuracy: float
    confusion: object  # pandas.DataFrame
    mean_isolation_delay: float = float("nan")
    median_isolation_delay: float = float("nan")
    isolation_held_rate: float = float("nan")
    mean_correct_fraction: float = float("nan")

    def as_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "confusion"}
        return d


def _scores(scores) -> list[Score]:
    """The scores as a non-empty list of :class:`Score` (DataError if empty, ParameterError if not scores)."""
    try:
        scores = list(scores)
    except TypeError:
        raise ParameterError(f"scores must be an iterable of Score, got {type(scores).__name__}") from None
    if not scores:
        raise DataError("no scores to summarise; score at least one trace")
    bad = next((s for s in scores if not isinstance(s, Score)), None)
    if bad is not None:
        raise ParameterError(f"scores must be Score objects (from metrics.score), got a {type(bad).__name__}")
    return scores


def confusion_matrix(scores: Iterable[Score]):
    """Counts of true label (rows) vs outcome (columns: isolated fault, ``'unknown'``, ``'missed'``, ``'none'``).

    Parameters
    ----------
    scores : iterable of Score
        One score per trace (:func:`score`).

    Returns
    -------
    pandas.DataFrame
        Integer counts; index ``true`` (the labels, sorted), columns ``diagnosed`` (the outcomes and the labels,
        sorted).

    Raises
    ------
    DataError
        When there are no scores.
    ParameterError
        When ``scores`` is not an iterable of :class:`Score`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.metrics import score, summarize
    >>> fired = np.array([[0, 0], [1, 0], [0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [1, 0]], dtype=bool)
    >>> d = Diagnosis(np.arange(8) * 0.5, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> s = score(np.array(["none"] * 4 + ["fa"] * 4), d)
    >>> confusion_matrix([s, score(np.array(["none"] * 8), d)]).to_dict()
    {'fa': {'fa': 1, 'none': 1}, 'none': {'fa': 0, 'none': 0}}
    """
    import pandas as pd

    scores = _scores(scores)
    rows = sorted({s.label for s in scores})
    cols = sorted({s.outcome for s in scores} | set(rows))
    df = pd.DataFrame(0, index=pd.Index(rows, name="true"), columns=pd.Index(cols, name="diagnosed"))
    for s in scores:
        df.loc[s.label, s.outcome] += 1
    return df


def summarize(scores: Iterable[Score]) -> Summary:
    """Rates and means over traces; the false-alarm rate pools fault-free time over all runs.

    Parameters
    ----------
    scores : iterable of Score
        One score per trace (:func:`score`).

    Returns
    -------
    Summary
        Detection and missed rates, mean and median delay, false alarms and their rate, isolation accuracy and
        the confusion matrix.

    Raises
    ------
    DataError
        When there are no scores.
    ParameterError
        When ``scores`` is not an iterable of :class:`Score`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.metrics import score, summarize
    >>> fired = np.array([[0, 0], [1, 0], [0, 0], [0, 0], [0, 0], [1, 0], [1, 0], [1, 0]], dtype=bool)
    >>> d = Diagnosis(np.arange(8) * 0.5, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> s = score(np.array(["none"] * 4 + ["fa"] * 4), d)
    >>> sm = summarize([s, score(np.array(["none"] * 8), d)])
    >>> sm.runs, sm.faulty_runs, sm.detection_rate, sm.false_alarms, round(sm.false_alarm_rate, 6)
    (2, 1, 1.0, 3, 1800.0)
    """
    scores = _scores(scores)
    faulty = [s for s in scores if s.label != NO_FAULT]
    delays = np.array([s.detection_delay for s in faulty if s.detected], dtype=float)
    hours = sum(s.fault_free_hours for s in scores)
    fa = sum(s.false_alarms for s in scores)
    detected = [s for s in faulty if s.detected]
    iso = np.array([s.isolation_delay for s in faulty if s.isolation_delay is not None], dtype=float)
    frac = np.array([s.correct_fraction for s in detected if s.correct_fraction is not None], dtype=float)
    nan = float("nan")
    return Summary(
        runs=len(scores),
        faulty_runs=len(faulty),
        detection_rate=len(detected) / len(faulty) if faulty else nan,
        missed_rate=sum(s.missed for s in faulty) / len(faulty) if faulty else nan,
        mean_delay=float(delays.mean()) if delays.size else nan,
        median_delay=float(np.median(delays)) if delays.size else nan,
        false_alarms=fa,
        false_alarm_rate=fa / hours if hours > 0 else nan,
        isolation_accuracy=sum(bool(s.isolation_correct) for s in detected) / len(detected) if detected else nan,
        confusion=confusion_matrix(scores),
        mean_isolation_delay=float(iso.mean()) if iso.size else nan,
        median_isolation_delay=float(np.median(iso)) if iso.size else nan,
        isolation_held_rate=iso.size / len(faulty) if faulty else nan,
        mean_correct_fraction=float(np.mean(frac)) if frac.size else nan,
    )


def rate_interval(count: int, hours: float, confidence: float = 0.95) -> tuple[float, float]:
    """Exact Poisson (Garwood) confidence interval of an event rate from a count over a time.

    For ``k`` events in ``T`` hours, with ``a = 1 − confidence``:

        ``lower = χ²_{a/2}(2k) / (2T)`` (0 for ``k = 0``),  ``upper = χ²_{1−a/2}(2k + 2) / (2T)``,

    ``χ²_p(ν)`` the ``p`` quantile of the chi-square distribution with ``ν`` degrees of freedom (the exact interval
    of Garwood 1936).
    The interval is conservative: it covers the true rate with probability at least ``confidence``.  With no
    events, the upper end ``−ln(a/2) / T`` (``≈ 3.69 / T`` at 95 %) is the smallest rate the data can resolve.

    Parameters
    ----------
    count : int
        Number of events (false alarms), ``>= 0``.
    hours : float
        Observed time [h], positive.
    confidence : float, default 0.95
        Two-sided level, in (0, 1).

    Returns
    -------
    (float, float)
        Lower and upper end of the rate [1/h].

    Raises
    ------
    ParameterError
        When ``count`` is not a non-negative integer, ``hours`` is not positive, or ``confidence`` is not in (0, 1).

    Examples
    --------
    >>> from fdikit.metrics import rate_interval
    >>> [round(x, 4) for x in rate_interval(3, 2.0)]
    [0.3093, 4.3836]
    >>> round(rate_interval(0, 10.0)[1], 4)
    0.3689
    """
    from scipy.stats import chi2

    k = validate.integer("count", count, minimum=0)
    T = validate.positive("hours", hours)
    c = validate.in_range("confidence", confidence, 0.0, 1.0, closed="neither")
    a = 1.0 - c
    lower = float(chi2.ppf(a / 2, 2 * k)) / (2 * T) if k > 0 else 0.0
    upper = float(chi2.ppf(1 - a / 2, 2 * k + 2)) / (2 * T)
    return lower, upper


def vaf(reference, estimate):
    """Variance accounted for, ``max(0, 1 − var(y − ŷ)/var(y)) · 100 %`` (Hallouzi 2008, (3.53); the fit
    measure of van der Ploeg 2018, Sec. 4-3-4, after Verhaegen & Verdult).

    ``reference`` and ``estimate`` have the same shape: (N,) gives a float, (N, k) one value per column.

    Parameters
    ----------
    reference : (N,) or (N, k) array_like
        The measured signal ``y``.
    estimate : (N,) or (N, k) array_like
        Its estimate ``ŷ``, same shape.

    Returns
    -------
    float or (k,) ndarray
        The VAF in percent, in [0, 100].

    Raises
    ------
    DataError
        If the shapes differ, there are fewer than 2 samples, a value is not a finite number, or a
        reference column is constant.

    Examples
    --------
    >>> float(vaf([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0, 4.0]))
    85.0
    """
    y = validate.as_array("reference", reference, error=DataError)
    yh = validate.as_array("estimate", estimate, error=DataError)
    if y.shape != yh.shape or y.ndim == 0 or y.shape[0] < 2:
        raise DataError(f"vaf needs two equally long signals of 2+ samples, got shapes {y.shape} and {yh.shape}")
    y2, e2 = y.reshape(y.shape[0], -1), (y - yh).reshape(y.shape[0], -1)
    var = y2.var(axis=0)
    if np.any(var == 0):
        raise DataError("vaf is undefined for a constant reference signal (zero variance)")
    out = np.maximum(1.0 - e2.var(axis=0) / var, 0.0) * 100.0
    return float(out[0]) if y.ndim == 1 else out

