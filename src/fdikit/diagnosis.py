"""The result of residual evaluation: alarms, isolated faults and hypothesis probabilities over time."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fdikit.faults import NO_FAULT

__all__ = ["Alarm", "Diagnosis", "StepDecision", "UNKNOWN_FAULT", "alarm_events", "isolate"]

#: Isolation label of an alarm whose residual pattern points to no single fault.
UNKNOWN_FAULT = "unknown"


@dataclass(frozen=True)
class Alarm:
    """One alarm: the sample at which the decision switched on, and what it isolated.

    Attributes
    ----------
    time : float
        Time of the alarm's first sample [s].
    index : int
        Sample index of that sample.
    fault : str
        The fault isolated at that sample (``'unknown'`` when the pattern points to no single fault).
    residuals : tuple of str
        The residuals (or hypotheses) that fired at that sample.

    Examples
    --------
    >>> from fdikit.diagnosis import Alarm
    >>> Alarm(0.1, 1, "fa", ("ra",)).fault
    'fa'
    """

    time: float
    index: int
    fault: str
    residuals: tuple[str, ...]


@dataclass(frozen=True)
class StepDecision:
    """Decision for one sample from an evaluator's ``step``.

    ``fired`` are the per-residual (or per-hypothesis) decisions, ``probabilities`` the
    per-hypothesis probabilities when the evaluator has them, ``valid`` False when the
    sample was bad or passed with ``valid=False`` (recovering) and the previous decision was held.

    Attributes
    ----------
    alarm : bool
        The decision "a fault is present".
    fault : str
        The isolated fault: ``'none'``, a fault name or ``'unknown'``.
    fired : (q,) bool ndarray
        Per-residual (or per-hypothesis) decisions.
    valid : bool
        Whether the sample was used (False: the previous decision was held).
    probabilities : (H,) ndarray or None
        Per-hypothesis probabilities, for evaluators that have them.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import StepDecision
    >>> s = StepDecision(True, "fa", np.array([True, False]), True)
    >>> s.alarm, s.fault, s.probabilities is None
    (True, 'fa', True)
    """

    alarm: bool
    fault: str
    fired: np.ndarray
    valid: bool
    probabilities: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """Per-sample decisions of an evaluator.

    Attributes
    ----------
    t : (N,) ndarray
        Sample times [s].
    alarm : (N,) bool ndarray
        The decision "a fault is present".
    fired : (N, q) bool ndarray
        The per-residual (or per-hypothesis) decisions.
    names : tuple of str
        Names of the columns of ``fired``.
    isolated : (N,) str ndarray
        The isolated fault per sample: ``'none'`` without alarm,
        ``'unknown'`` when the pattern of fired residuals points to no single fault.
    alarms : tuple of Alarm
        The rising edges of ``alarm``; computed by :func:`alarm_events` when not given.
    probabilities : (N, H) ndarray or None
        Per-hypothesis probabilities, or None.
    hypotheses : tuple of str
        Names of the columns of ``probabilities``.
    valid : (N,) bool ndarray
        False where the evaluator did not use the sample — a NaN/inf residual (a gap) or
        a residual marked not valid (``Residuals.valid``: e.g. recovering after a gap) — and held the
        previous decision; default all True.
    meta : dict
        Evaluator details (name, thresholds, statistics …).
    detected : bool
        Whether any sample alarms.
    invalid_count : int
        Number of samples not used.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> fired = np.array([[False, False], [True, False], [True, False], [False, False], [False, True]])
    >>> d = Diagnosis(np.arange(5) * 0.1, fired.any(axis=1), fired, ("ra", "rb"), isolate(fired, ("fa", "fb")))
    >>> d.detected, len(d.alarms), d.first_alarm().fault, d.first_alarm(after=0.25).fault
    (True, 2, 'fa', 'fb')
    """

    t: np.ndarray
    alarm: np.ndarray
    fired: np.ndarray
    names: tuple[str, ...]
    isolated: np.ndarray
    alarms: tuple[Alarm, ...] = ()
    probabilities: np.ndarray | None = None
    hypotheses: tuple[str, ...] = ()
    valid: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = np.asarray(self.t).size
        object.__setattr__(self, "valid", np.ones(n, bool) if self.valid is None else np.asarray(self.valid, bool))
        if not self.alarms:
            object.__setattr__(self, "alarms", alarm_events(self.t, self.alarm, self.fired, self.names, self.isolated))

    @property
    def detected(self) -> bool:
        return bool(np.any(self.alarm))

    def first_alarm(self, after: float | None = None) -> Alarm | None:
        """The first alarm at or after time ``after`` (any time when None)."""
        for a in self.alarms:
            if after is None or a.time >= after:
                return a
        return None

    @property
    def invalid_count(self) -> int:
        return int((~self.valid).sum())

    def to_pandas(self):
        import pandas as pd

        df = pd.DataFrame(self.fired, columns=[f"fired:{n}" for n in self.names], index=pd.Index(self.t, name="t"))
        df["alarm"] = self.alarm
        df["isolated"] = self.isolated
        df["valid"] = self.valid
        if self.probabilities is not None:
            for j, h in enumerate(self.hypotheses):
                df[f"p:{h}"] = self.probabilities[:, j]
        return df

    def plot(self, ax=None, **kwargs):
        """Draw the decisions over time (:func:`fdikit.plots.plot_diagnosis`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw into it; default a new figure.
        **kwargs
            ``title`` and ``path`` of :func:`~fdikit.plots.plot_diagnosis`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> fired = np.array([[False], [True]])
        >>> d = Diagnosis(np.arange(2.0), fired[:, 0], fired, ("r",), np.array(["none", "f"]))
        >>> fig, ax = plt.subplots()
        >>> d.plot(ax=ax) is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_diagnosis

        return plot_diagnosis(self, ax=ax, **kwargs)


def alarm_events(t, alarm, fired, names, isolated) -> tuple[Alarm, ...]:
    """The rising edges of ``alarm`` as :class:`Alarm` records.

    Parameters
    ----------
    t : (N,) array_like
        Sample times [s].
    alarm : (N,) bool array_like
        The alarm per sample.
    fired : (N, q) bool array_like
        Per-residual decisions (the fired names are recorded with each alarm).
    names : sequence of str
        Names of the columns of ``fired``.
    isolated : (N,) array_like of str
        The isolated fault per sample.

    Returns
    -------
    tuple of Alarm
        One record per sample where ``alarm`` switches on (a first sample that alarms counts).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import alarm_events
    >>> fired = np.array([[False], [True], [True], [False], [True]])
    >>> [(a.index, a.fault) for a in alarm_events(np.arange(5) * 0.1, fired[:, 0], fired, ("r",), ["none"] + ["f"] * 4)]
    [(1, 'f'), (4, 'f')]
    """
    alarm = np.asarray(alarm, bool)
    rises = np.flatnonzero(alarm & ~np.concatenate([[False], alarm[:-1]]))
    return tuple(
        Alarm(float(t[k]), int(k), str(isolated[k]), tuple(n for n, f in zip(names, fired[k]) if f)) for k in rises
    )


def isolate(
    fired: np.ndarray, isolates: tuple[str | None, ...], groups: tuple[str, ...] | None = None
) -> np.ndarray:
    """Per-sample isolated fault from per-residual decisions.

    Single-fault logic of Douglas et al. 1996, §1 ("no announcement when more than one
    residual crosses"): the fault is named when every fired residual is tied to the
    same fault; other patterns are ``'unknown'``; no fired residual is ``'none'``.

    With ``groups`` (the filter of each residual, for a bank of filters) the bank logic
    of §1 applies: a filter whose fired residuals point to two or more faults is
    discarded (the fault is outside its design set); the fault is named when the
    remaining filters that point to one fault all point to the same one.

    A fault that fires residuals tied to *different* faults (one actuator seen by two
    observer groups) is thus ``'unknown'`` here; a fault-signature table names it
    (:class:`fdikit.decision.signature.SignatureTable`, the evaluators' ``signatures=``).

    Parameters
    ----------
    fired : (N, q) bool array_like
        Per-sample, per-residual decisions.
    isolates : sequence of str or None
        The fault tied to each residual; an untied (None) residual that fires alone gives ``'unknown'``.
    groups : sequence of str, optional
        The filter of each residual (bank logic); default all residuals in one filter.

    Returns
    -------
    (N,) str ndarray
        ``'none'``, a fault name, or ``'unknown'`` per sample.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.diagnosis import isolate
    >>> fired = np.array([[False, False, False], [True, False, False], [True, True, True]])
    >>> isolate(fired, ("fa", "fb", "fa")).tolist()
    ['none', 'fa', 'unknown']
    >>> isolate(fired, ("fa", "fb", "fa"), groups=("F1", "F1", "F2")).tolist()
    ['none', 'fa', 'fa']
    """
    fired = np.asarray(fired, bool)
    N = fired.shape[0]
    out = np.full(N, NO_FAULT, dtype=object)
    any_ = fired.any(axis=1)
    out[any_] = UNKNOWN_FAULT
    if groups is None:
        groups = ("",) * len(isolates)
    # per filter: which of its faults fired (an untied residual counts as a fault of its own)
    candidate = np.full(N, "", dtype=object)
    conflict = np.zeros(N, bool)
    for g in dict.fromkeys(groups):
        cols = [k for k, gg in enumerate(groups) if gg == g]
        keys = sorted({isolates[k] if isolates[k] is not None else f"?{k}" for k in cols})
        per = np.column_stack([
            fired[:, [k for k in cols if (isolates[k] if isolates[k] is not None else f"?{k}") == key]].any(axis=1)
            for key in keys
        ])
        single = per.sum(axis=1) == 1
        which = per.argmax(axis=1)
        name = np.array(keys, dtype=object)[which]
        vote = single & ~np.array([key.startswith("?") for key in keys])[which]  # per key, not per sample
        unknown_vote = single & ~vote
        conflict |= unknown_vote | (vote & (candidate != "") & (candidate != name))
        candidate = np.where(vote & (candidate == ""), name, candidate)
    ok = any_ & (candidate != "") & ~conflict
    out[ok] = candidate[ok]
    return out.astype(str)
