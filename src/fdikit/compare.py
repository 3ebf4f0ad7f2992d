"""Run several residual evaluators on the same residuals and tabulate their scores side by side.

Every evaluator sees exactly the same residual series; each run is scored with
:func:`fdikit.metrics.score` and the table aggregates with
:func:`fdikit.metrics.summarize`.  Per-run scores are appended to a CSV as each run
finishes, so an interrupted comparison loses nothing done.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

from fdikit.errors import DataError
from fdikit.metrics import Score, score, summarize
from fdikit.residuals import Residuals
from fdikit.trace import Trace

__all__ = ["Comparison", "compare_evaluators"]


@dataclass(frozen=True, eq=False)
class Comparison:
    """Scores per evaluator and the side-by-side table (one row per evaluator)."""

    scores: dict[str, list[Score]]
    table: object  # pandas.DataFrame

    def to_markdown(self, digits: int = 3) -> str:
        """The table as GitHub markdown (no extra dependency)."""
        df = self.table
        cols = ["evaluator", *df.columns]
        lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
        for name, row in df.iterrows():
            cells = [f"{v:.{digits}g}" if isinstance(v, float) else str(v) for v in row]
            lines.append("| " + " | ".join([str(name), *cells]) + " |")
        return "\n".join(lines)


def compare_evaluators(
    evaluators: Mapping[str, object],
    runs: Iterable[tuple[Trace, Residuals]],
    *,
    scores_csv: str | Path | None = None,
    progress: bool = False,
) -> Comparison:
    """Score fitted evaluators on the same ``(trace, residuals)`` runs.

    Parameters
    ----------
    evaluators : name → fitted evaluator (anything with ``run(residuals) -> Diagnosis``).
    runs : the traces (truth) with their residuals.
    scores_csv : when given, one line per (run, evaluator) is appended as it is scored.
    progress : show a rich progress bar.

    Returns
    -------
    Comparison with columns: runs, detection rate, missed rate, mean and median delay [s],
    false alarms, false-alarm rate [1/h], isolation accuracy.
    """
    import pandas as pd

    runs = list(runs)
    if not runs or not evaluators:
        raise DataError("compare_evaluators needs at least one evaluator and one run")
    scores: dict[str, list[Score]] = {name: [] for name in evaluators}
    writer = handle = None
    if scores_csv is not None:
        path = Path(scores_csv)
        path.parent.mkdir(parents=True, exist_ok=True)
        handle = path.open("w", newline="")
        writer = csv.writer(handle)
        writer.writerow(["run", "evaluator", *Score.__dataclass_fields__, "false_alarm_rate"])
    steps = [(k, name, ev) for k in range(len(runs)) for name, ev in evaluators.items()]
    if progress:
        from rich.progress import track

        steps = track(steps, description="scoring evaluators")
    try:
        for k, name, ev in steps:
            trace, residuals = runs[k]
            s = score(trace, ev.run(residuals))
            scores[name].append(s)
            if writer is not None:
                writer.writerow([k, name, *asdict(s).values(), s.false_alarm_rate])
                handle.flush()
    finally:
        if handle is not None:
            handle.close()
    rows = {}
    for name, ss in scores.items():
        summ = summarize(ss)
        rows[name] = {
            "runs": summ.runs,
            "detection rate": summ.detection_rate,
            "missed rate": summ.missed_rate,
            "mean delay [s]": summ.mean_delay,
            "median delay [s]": summ.median_delay,
            "false alarms": summ.false_alarms,
            "false alarms [1/h]": summ.false_alarm_rate,
            "isolation accuracy": summ.isolation_accuracy,
        }
    return Comparison(scores, pd.DataFrame.from_dict(rows, orient="index"))
