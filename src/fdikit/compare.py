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
    """Scores per evaluator and the side-by-side table (one row per evaluator).

    Attributes
    ----------
    scores : dict of str to list of Score
        Per evaluator, one :class:`~fdikit.metrics.Score` per run, in run order.
    table : pandas.DataFrame
        One row per evaluator (index: the names); columns ``runs``, ``detection rate``, ``missed rate``,
        ``mean delay [s]``, ``median delay [s]``, ``false alarms``, ``false alarms [1/h]``,
        ``isolation accuracy``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import CusumEvaluator, ThresholdEvaluator
    >>> r = np.zeros((200, 1)); r[100:, 0] = 1.0
    >>> res = Residuals(np.arange(200) * 0.1, r, ("r",), ("f",))
    >>> truth = np.array(["none"] * 100 + ["f"] * 100)
    >>> evaluators = {"threshold": ThresholdEvaluator(thresholds=3.0),
    ...               "cusum": CusumEvaluator(drift=0.5, threshold=4.0)}
    >>> from fdikit.compare import compare_evaluators
    >>> comp = compare_evaluators(evaluators, [(truth, res)])
    >>> comp.table["detection rate"].to_dict(), len(comp.scores["cusum"])
    ({'threshold': 0.0, 'cusum': 1.0}, 1)
    >>> comp.to_markdown().splitlines()[0][:37]
    '| evaluator | runs | detection rate |'
    """

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
    """Score every evaluator on one run: ``{name: fdikit.metrics.score(trace, evaluator.run(residuals))}``.

    Parameters
    ----------
    evaluators : mapping of str to evaluator
        Name → fitted evaluator (anything with ``run(residuals) -> Diagnosis``).
    trace : Trace
        The run's truth: the trace, or its per-sample fault labels (as :func:`fdikit.metrics.score` takes).
    residuals : Residuals
        The residuals of that run, the same for every evaluator.

    Returns
    -------
    dict of str to Score
        One score per evaluator, in the order of ``evaluators``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import CusumEvaluator, ThresholdEvaluator
    >>> r = np.zeros((200, 1)); r[100:, 0] = 1.0
    >>> res = Residuals(np.arange(200) * 0.1, r, ("r",), ("f",))
    >>> truth = np.array(["none"] * 100 + ["f"] * 100)
    >>> evaluators = {"threshold": ThresholdEvaluator(thresholds=3.0),
    ...               "cusum": CusumEvaluator(drift=0.5, threshold=4.0)}
    >>> from fdikit.compare import score_run
    >>> {k: (s.detected, None if s.detection_delay is None else round(s.detection_delay, 6))
    ...  for k, s in score_run(evaluators, truth, res).items()}
    {'threshold': (False, None), 'cusum': (True, 0.8)}
    """
    return {name: score(trace, ev.run(residuals)) for name, ev in evaluators.items()}


def scores_csv_text(scores: Mapping[str, Sequence[Score]]) -> str:
    """The per-run scores CSV (columns ``SCORE_COLUMNS``; rows by run, then evaluator).

    Parameters
    ----------
    scores : mapping of str to sequence of Score
        Per evaluator, one score per run (all evaluators the same number of runs).

    Returns
    -------
    str
        The CSV text, a header line and one line per (run, evaluator): the run index, the evaluator's name,
        every :class:`~fdikit.metrics.Score` field and the false-alarm rate.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import CusumEvaluator, ThresholdEvaluator
    >>> r = np.zeros((200, 1)); r[100:, 0] = 1.0
    >>> res = Residuals(np.arange(200) * 0.1, r, ("r",), ("f",))
    >>> truth = np.array(["none"] * 100 + ["f"] * 100)
    >>> evaluators = {"threshold": ThresholdEvaluator(thresholds=3.0),
    ...               "cusum": CusumEvaluator(drift=0.5, threshold=4.0)}
    >>> from fdikit.compare import score_run, scores_csv_text
    >>> one = score_run(evaluators, truth, res)
    >>> lines = scores_csv_text({k: [s] for k, s in one.items()}).splitlines()
    >>> len(lines), lines[0].split(",")[:4], lines[2].split(",")[:3]
    (3, ['run', 'evaluator', 'label', 'onset'], ['0', 'cusum', 'f'])
    """
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
    """The side-by-side table of per-run scores (one row per evaluator).

    Parameters
    ----------
    scores : mapping of str to sequence of Score
        Per evaluator, the scores of its runs (aggregated with :func:`fdikit.metrics.summarize`).

    Returns
    -------
    Comparison
        The scores and the table (columns as in :class:`Comparison`).

    Raises
    ------
    DataError
        When an evaluator has no scores (from :func:`~fdikit.metrics.summarize`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import CusumEvaluator, ThresholdEvaluator
    >>> r = np.zeros((200, 1)); r[100:, 0] = 1.0
    >>> res = Residuals(np.arange(200) * 0.1, r, ("r",), ("f",))
    >>> truth = np.array(["none"] * 100 + ["f"] * 100)
    >>> evaluators = {"threshold": ThresholdEvaluator(thresholds=3.0),
    ...               "cusum": CusumEvaluator(drift=0.5, threshold=4.0)}
    >>> from fdikit.compare import score_run, tabulate
    >>> one = score_run(evaluators, truth, res)
    >>> tabulate({k: [s] for k, s in one.items()}).table["missed rate"].to_dict()
    {'threshold': 1.0, 'cusum': 0.0}
    """
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
    evaluators : mapping of str to evaluator
        Name → fitted evaluator (anything with ``run(residuals) -> Diagnosis``).
    runs : iterable of (Trace, Residuals)
        The traces (truth; per-sample fault labels also do) with their residuals.
    scores_csv : str or Path, optional
        When given, one line per (run, evaluator) is written there (:func:`scores_csv_text`), atomically, once
        every run is scored (an existing file stays intact until then).
    progress : bool, default False
        Show a rich progress bar.

    Returns
    -------
    Comparison
        The scores and the table with columns: runs, detection rate, missed rate, mean and median delay [s],
        false alarms, false-alarm rate [1/h], isolation accuracy.

    Raises
    ------
    DataError
        When there is no evaluator or no run (and, from :func:`~fdikit.metrics.score`, when a run's truth does not
        match its residuals).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import CusumEvaluator, ThresholdEvaluator
    >>> r = np.zeros((200, 1)); r[100:, 0] = 1.0
    >>> res = Residuals(np.arange(200) * 0.1, r, ("r",), ("f",))
    >>> truth = np.array(["none"] * 100 + ["f"] * 100)
    >>> evaluators = {"threshold": ThresholdEvaluator(thresholds=3.0),
    ...               "cusum": CusumEvaluator(drift=0.5, threshold=4.0)}
    >>> from fdikit.compare import compare_evaluators
    >>> compare_evaluators(evaluators, [(truth, res), (truth, res)]).table["runs"].to_dict()
    {'threshold': 2, 'cusum': 2}
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
