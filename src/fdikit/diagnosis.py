"""The result of residual evaluation: alarms, isolated faults and hypothesis probabilities over time."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fdikit.faults import NO_FAULT

__all__ = ["Alarm", "Diagnosis", "UNKNOWN_FAULT", "alarm_events", "isolate"]

#: Isolation label of an alarm whose residual pattern points to no single fault.
UNKNOWN_FAULT = "unknown"


@dataclass(frozen=True)
class Alarm:
    """One alarm: the sample at which the decision switched on, and what it isolated."""

    time: float
    index: int
    fault: str
    residuals: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """Per-sample decisions of an evaluator.

    Attributes
    ----------
    t : (N,) times.
    alarm : (N,) bool, the decision "a fault is present".
    fired : (N, q) bool, the per-residual (or per-hypothesis) decisions.
    names : names of the columns of ``fired``.
    isolated : (N,) str, the isolated fault per sample: ``'none'`` without alarm,
        ``'unknown'`` when the pattern of fired residuals points to no single fault.
    alarms : the rising edges of ``alarm``.
    probabilities : (N, H) per-hypothesis probabilities, or None.
    hypotheses : names of the columns of ``probabilities``.
    valid : (N,) bool, False where the input sample was bad (decision held).
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


def alarm_events(t, alarm, fired, names, isolated) -> tuple[Alarm, ...]:
    """The rising edges of ``alarm`` as :class:`Alarm` records."""
    alarm = np.asarray(alarm, bool)
    rises = np.flatnonzero(alarm & ~np.concatenate([[False], alarm[:-1]]))
    return tuple(
        Alarm(float(t[k]), int(k), str(isolated[k]), tuple(n for n, f in zip(names, fired[k]) if f)) for k in rises
    )


def isolate(fired: np.ndarray, isolates: tuple[str | None, ...]) -> np.ndarray:
    """Per-sample isolated fault from per-residual decisions.

    Single-fault logic of Douglas et al. 1996 §1 ("no announcement when more than one
    residual crosses"): the fault is named when every fired residual is tied to the
    same fault; other patterns are ``'unknown'``; no fired residual is ``'none'``.
    """
    fired = np.asarray(fired, bool)
    out = np.full(fired.shape[0], NO_FAULT, dtype=object)
    any_ = fired.any(axis=1)
    out[any_] = UNKNOWN_FAULT
    labels = sorted({f for f in isolates if f is not None})
    tied = np.array([[iso == f for iso in isolates] for f in labels], bool).reshape(len(labels), len(isolates))
    for f, cols in zip(labels, tied):
        only_f = any_ & ~(fired & ~cols).any(axis=1)
        out[only_f] = f
    return out.astype(str)
