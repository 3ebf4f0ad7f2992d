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
    """One alarm: the sample at which the decision switched on, and what it isolated."""

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
    t : (N,) times.
    alarm : (N,) bool, the decision "a fault is present".
    fired : (N, q) bool, the per-residual (or per-hypothesis) decisions.
    names : names of the columns of ``fired``.
    isolated : (N,) str, the isolated fault per sample: ``'none'`` without alarm,
        ``'unknown'`` when the pattern of fired residuals points to no single fault.
    alarms : the rising edges of ``alarm``.
    probabilities : (N, H) per-hypothesis probabilities, or None.
    hypotheses : names of the columns of ``probabilities``.
    valid : (N,) bool, False where the evaluator did not use the sample — a NaN/inf residual (a gap) or
        a residual marked not valid (``Residuals.valid``: e.g. recovering after a gap) — and held the
        previous decision.
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
        name = np.array(keys, dtype=object)[per.argmax(axis=1)]
        vote = single & np.array([not str(x).startswith("?") for x in name])
        unknown_vote = single & ~vote
        conflict |= unknown_vote | (vote & (candidate != "") & (candidate != name))
        candidate = np.where(vote & (candidate == ""), name, candidate)
    ok = any_ & (candidate != "") & ~conflict
    out[ok] = candidate[ok]
    return out.astype(str)
