"""A result row of the campaign table from a run's plan and its :class:`~fdikit.metrics.Score`."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence

from fdikit.campaign.plan import RunPlan
from fdikit.metrics import Score

__all__ = ["score_row"]


def _nan(x) -> float:
    return math.nan if x is None else float(x)


def score_row(plan: RunPlan, design: str, evaluator: str, score: Score, sweep_delay: Sequence[float],
              sweep_false_alarms: Sequence[int], metrics: Mapping[str, float] | None = None) -> dict:
    """The row of :data:`fdikit.campaign.schema.SCHEMA` for one run × design × evaluator.

    Parameters
    ----------
    plan : RunPlan
        The run.
    design, evaluator : str
        Names from the spec.
    score : Score
        :func:`fdikit.metrics.score` of the evaluator's diagnosis on the run.
    sweep_delay, sweep_false_alarms : sequence
        Per sweep level: the first-crossing delay after the onset (NaN when none) and the up-crossings at
        fault-free samples.
    metrics : mapping, optional
        Study-specific figures (stored as JSON).

    Returns
    -------
    dict

    Examples
    --------
    >>> s = Score("none", None, False, None, 0, 20 / 3600, False, "none", None)
    >>> p = RunPlan(3, 0, "linear", "none", "none", float("nan"), float("nan"), 11)
    >>> row = score_row(p, "bank", "threshold", s, [float("nan")], [0])
    >>> row["run"], row["isolation_correct"], row["metrics"]
    (3, None, '{}')
    """
    return {
        "run": plan.run, "chunk": plan.chunk, "plant": plan.plant, "fault": plan.fault, "kind": plan.kind,
        "size": plan.size, "onset": plan.onset, "seed": plan.seed, "design": design, "evaluator": evaluator,
        "detected": bool(score.detected), "missed": bool(score.missed), "detection_delay": _nan(score.detection_delay),
        "isolated": score.isolated, "isolation_correct": score.isolation_correct,
        "isolation_delay": _nan(score.isolation_delay), "correct_fraction": _nan(score.correct_fraction),
        "false_alarms": int(score.false_alarms), "fault_free_hours": float(score.fault_free_hours),
        "sweep_delay": [float(v) for v in sweep_delay], "sweep_false_alarms": [int(v) for v in sweep_false_alarms],
        "metrics": json.dumps(dict(metrics or {}), sort_keys=True),
    }
