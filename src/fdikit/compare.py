"""Run several residual evaluators on the same residuals and tabulate their scores side by side.

Every evaluator sees exactly the same residual series; each run is scored with
:func:`fdikit.metrics.score` (:func:`score_run`) and the table aggregates with
:func:`fdikit.metrics.summarize` (:func:`tabulate`).  The per-run scores CSV is written
atomically once every run is scored, so an earlier file is never truncated; the resumable
comparison that stores each run's scores as it finishes is
:func:`fdikit.studies.path1996.compare.path_evaluator_comparison` (``fdikit compare-evaluators``).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from fdikit.errors import DataError
from fdikit.metrics import Score, score, summarize
from fdikit.residuals import Residuals
from fdikit.trace import Trace

__all__ = ["Comparison", "compare_evaluators", "score_run", "tabulate", "scores_csv_text", "SCORE_COLUMNS"]

#: Columns of the per-run scores CSV.
SCORE_COLUMNS = ("run", "evaluator", *Score.__dataclass_fields__, "false_alarm_rate")


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


def score_run(evaluators: Mapping[str, object], trace: Trace, residuals: Residuals) -> dict[str, Score]:
    """Score every evaluator on one run: ``{name: fdikit.metrics.score(trace, evaluator.run(residuals))}``."""
    return {name: score(trace, ev.run(residuals)) for name, ev in evaluators.items()}


def scores_csv_text(scores: Mapping[str, Sequence[Score]]) -> str:
    """The per-run scores CSV (columns :data:`SCORE_COLUMNS`; rows by run, then evaluator)."""
    buf = io.StringIO(newline="")
    writer = csv.writer(buf)
    writer.writerow(SCORE_COLUMNS)
    n = max((len(v) for v in scores.values()), default=0)
    for k in range(n):
        for name, ss in scores.items():
            s = ss[k]
            writer.writerow([k, name, *asdict(s).values(), s.false_alarm_rate])
    return buf.getvalue()


def tabulate(scores: Mapping[str, Sequence[Score]]) -> Comparison:
    """The side-by-side table of per-run scores (one row per evaluator)."""
    import pandas as pd

    rows = {}
    for name, ss in scores.items():
        summ = summarize(list(ss))
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
    return Comparison({k: list(v) for k, v in scores.items()}, pd.DataFrame.from_dict(rows, orient="index"))


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
    scores_csv : when given, one line per (run, evaluator) is written there, atomically, once
        every run is scored (an existing file stays intact until then).
    progress : show a rich progress bar.

    Returns
    -------
    Comparison with columns: runs, detection rate, missed rate, mean and median delay [s],
    false alarms, false-alarm rate [1/h], isolation accuracy.
    """
    from fdikit.atomic import write_text

    runs = list(runs)
    if not runs or not evaluators:
        raise DataError("compare_evaluators needs at least one evaluator and one run")
    scores: dict[str, list[Score]] = {name: [] for name in evaluators}
    items = runs
    if progress:
        from rich.progress import track

        items = track(runs, description="scoring evaluators")
    for trace, residuals in items:
        for name, s in score_run(evaluators, trace, residuals).items():
            scores[name].append(s)
    if scores_csv is not None:
        write_text(scores_csv, scores_csv_text(scores))
    return tabulate(scores)
