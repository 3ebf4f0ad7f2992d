"""Statistics of a campaign's results table: rates with exact intervals, delay distributions, the trade-off curve.

Everything is computed from the stored columns of :data:`fdikit.campaign.schema.SCHEMA` (one row per
run × design × evaluator); nothing is re-simulated.  A *faulty* row has ``fault != 'none'``.

* **Detection rate** of a group: detected faulty rows / faulty rows, with the exact binomial
  (Clopper & Pearson 1934) interval of :func:`clopper_pearson`.
* **Isolation rate**: faulty rows with ``isolation_correct`` / faulty rows (a missed run counts as not
  isolated, so this is the end-to-end rate, not :attr:`fdikit.metrics.Summary.isolation_accuracy`, which
  divides by the detected runs), with the Clopper–Pearson interval.
* **Delay distributions**: count, median, mean, 10th and 90th percentile (linear interpolation,
  ``numpy.percentile``) and maximum of the finite delays; NaN when there are none.
* **False alarms**: the fault-free runs and those with at least one false alarm (fraction with its
  Clopper–Pearson interval); the false alarms over *all* fault-free time — the fault-free runs and the
  pre-onset part of the faulty ones (columns ``false_alarms``, ``fault_free_hours``) — per hour, with the
  exact Poisson interval of Garwood 1936 (:func:`fdikit.metrics.rate_interval`).  Without fault-free time
  the rate and its interval are NaN.
* **Confusion matrix**: true fault (rows) against the outcome of :attr:`fdikit.metrics.Score.outcome`
  (columns): the isolated fault, ``'missed'``, or ``'none'``; for a fault-free run ``'none'`` without a false
  alarm, else the fault its first false alarm isolated.
* **Trade-off curve** at each sweep level (a scale factor of the evaluator's nominal threshold): false
  alarms per hour = the sum of ``sweep_false_alarms[level]`` over all rows / the total fault-free hours
  (Garwood interval); detection rate = faulty rows with a finite ``sweep_delay[level]`` / faulty rows
  (Clopper–Pearson); median and 90th percentile of those finite delays.

A rate without runs (an empty group) is NaN with a NaN interval.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["CampaignStatistics", "campaign_statistics", "clopper_pearson", "metric_summary", "REQUIRED_COLUMNS"]

#: The columns :func:`campaign_statistics` reads.
REQUIRED_COLUMNS = ("fault", "design", "evaluator", "detected", "missed", "detection_delay", "isolated",
                    "isolation_correct", "isolation_delay", "false_alarms", "fault_free_hours", "sweep_delay",
                    "sweep_false_alarms")

_NONE = "none"
_MISSED = "missed"
_KEY = ["design", "evaluator"]
_DETECTION = ["runs", "detected", "missed", "detection_rate", "detection_low", "detection_high",
              "delay_count", "delay_median", "delay_mean", "delay_p10", "delay_p90", "delay_max",
              "isolated_correct", "isolation_rate", "isolation_low", "isolation_high",
              "isolation_delay_count", "isolation_delay_median", "isolation_delay_mean", "isolation_delay_p10",
              "isolation_delay_p90", "isolation_delay_max"]
_FALSE = ["fault_free_runs", "runs_with_false_alarm", "false_alarm_run_fraction", "false_alarm_run_low",
          "false_alarm_run_high", "false_alarms", "fault_free_hours", "false_alarm_rate", "false_alarm_rate_low",
          "false_alarm_rate_high"]
_TRADEOFF = ["level", "false_alarms", "fault_free_hours", "false_alarm_rate", "false_alarm_rate_low",
             "false_alarm_rate_high", "faulty_runs", "detected", "detection_rate", "detection_low",
             "detection_high", "delay_median", "delay_p90"]


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact binomial (Clopper & Pearson 1934) confidence interval of a proportion ``k / n``.

    With ``a = 1 − confidence`` and ``B(p; α, β)`` the ``p`` quantile of the beta distribution:
    ``lower = B(a/2; k, n − k + 1)`` (0 for ``k = 0``), ``upper = B(1 − a/2; k + 1, n − k)`` (1 for ``k = n``).
    The interval covers the true proportion with probability at least ``confidence``.

    Parameters
    ----------
    k : int
        Successes, ``0 <= k <= n``.
    n : int
        Trials, ``>= 0``; with none the interval is ``(nan, nan)``.
    confidence : float, default 0.95
        Two-sided level, in (0, 1).

    Returns
    -------
    (float, float)
        Lower and upper end.

    Raises
    ------
    ParameterError
        When ``k`` or ``n`` is not a non-negative integer, ``k > n``, or ``confidence`` is not in (0, 1).

    Examples
    --------
    >>> [round(x, 4) for x in clopper_pearson(0, 10)]
    [0.0, 0.3085]
    >>> [round(x, 4) for x in clopper_pearson(5, 10)]
    [0.1871, 0.8129]
    """
    from scipy.stats import beta

    k = validate.integer("k", k, minimum=0)
    n = validate.integer("n", n, minimum=0)
    c = validate.in_range("confidence", confidence, 0.0, 1.0, closed="neither")
    if k > n:
        raise ParameterError(f"k = {k} successes exceed n = {n} trials")
    if n == 0:
        return float("nan"), float("nan")
    a = 1.0 - c
    lower = float(beta.ppf(a / 2, k, n - k + 1)) if k > 0 else 0.0
    upper = float(beta.ppf(1 - a / 2, k + 1, n - k)) if k < n else 1.0
    return lower, upper


@dataclass(frozen=True)
class CampaignStatistics:
    """The statistics of a campaign (module docstring for the definitions); every table a pandas DataFrame.

    Attributes
    ----------
    levels : tuple of float
        The sweep levels (scale factors of the nominal threshold).
    confidence : float
        Two-sided level of every interval.
    detection : pandas.DataFrame
        One row per design × evaluator × fault (faulty runs only; columns ``design``, ``evaluator``, ``fault``):
        ``runs``, ``detected``, ``missed``, ``detection_rate`` with ``detection_low`` / ``detection_high``, the
        detection delay ``delay_count``, ``delay_median``, ``delay_mean``, ``delay_p10``, ``delay_p90``,
        ``delay_max`` [s], ``isolated_correct``, ``isolation_rate`` with ``isolation_low`` /
        ``isolation_high``, and the isolation delay ``isolation_delay_count`` … ``isolation_delay_max`` [s].
    overall : pandas.DataFrame
        The same columns per design × evaluator over all faults pooled, joined with :attr:`false_alarms`.
    false_alarms : pandas.DataFrame
        One row per design × evaluator: ``fault_free_runs``, ``runs_with_false_alarm``,
        ``false_alarm_run_fraction`` with ``false_alarm_run_low`` / ``false_alarm_run_high``, ``false_alarms``
        and ``fault_free_hours`` over all rows, ``false_alarm_rate`` [1/h] with ``false_alarm_rate_low`` /
        ``false_alarm_rate_high`` (NaN without fault-free time).
    confusion : pandas.DataFrame
        Long form: ``design``, ``evaluator``, ``true``, ``diagnosed``, ``count`` (the non-zero cells);
        :meth:`confusion_matrix` gives one design × evaluator's matrix.
    tradeoff : pandas.DataFrame
        One row per design × evaluator × sweep level: ``level``, ``false_alarms``, ``fault_free_hours``,
        ``false_alarm_rate`` with ``false_alarm_rate_low`` / ``false_alarm_rate_high``, ``faulty_runs``,
        ``detected``, ``detection_rate`` with ``detection_low`` / ``detection_high``, ``delay_median``,
        ``delay_p90`` [s].

    Examples
    --------
    >>> from fdikit.campaign.stats import campaign_statistics
    >>> import pandas as pd
    >>> st = campaign_statistics(pd.DataFrame(columns=REQUIRED_COLUMNS), levels=[1.0])
    >>> len(st.detection), list(st.tradeoff.columns[:3])
    (0, ['design', 'evaluator', 'level'])
    """

    levels: tuple[float, ...]
    confidence: float
    detection: Any
    overall: Any
    false_alarms: Any
    confusion: Any
    tradeoff: Any

    def pairs(self) -> list[tuple[str, str]]:
        """The (design, evaluator) pairs of the table, sorted.

        Returns
        -------
        list of (str, str)
            Every design × evaluator with at least one row.

        Examples
        --------
        >>> import pandas as pd
        >>> campaign_statistics(pd.DataFrame(columns=REQUIRED_COLUMNS), levels=[1.0]).pairs()
        []
        """
        return [(str(d), str(e)) for d, e in self.false_alarms[_KEY].itertuples(index=False)]

    def confusion_matrix(self, design: str, evaluator: str):
        """The confusion matrix of one design × evaluator, shaped as :func:`fdikit.metrics.confusion_matrix`.

        Parameters
        ----------
        design, evaluator : str
            The pair.

        Returns
        -------
        pandas.DataFrame
            Integer counts; index ``true`` (sorted labels), columns ``diagnosed`` (the outcomes and the labels,
            sorted).

        Raises
        ------
        DataError
            When the pair has no rows.

        Examples
        --------
        >>> import pandas as pd
        >>> st = campaign_statistics(pd.DataFrame(columns=REQUIRED_COLUMNS), levels=[1.0])
        >>> try:
        ...     st.confusion_matrix("bank", "threshold")
        ... except DataError as exc:
        ...     print(exc)
        no rows for design 'bank' × evaluator 'threshold'
        """
        import pandas as pd

        c = self.confusion
        part = c[(c["design"] == design) & (c["evaluator"] == evaluator)]
        if part.empty:
            raise DataError(f"no rows for design {design!r} × evaluator {evaluator!r}")
        rows = sorted(set(part["true"]))
        cols = sorted(set(part["diagnosed"]) | set(rows))
        m = part.pivot_table(index="true", columns="diagnosed", values="count", aggfunc="sum", fill_value=0)
        m = m.reindex(index=rows, columns=cols, fill_value=0).astype(int)
        m.index, m.columns = pd.Index(rows, name="true"), pd.Index(cols, name="diagnosed")
        return m


def _spread(values: np.ndarray, prefix: str) -> dict:
    """Count, median, mean, p10, p90, max of the finite values (NaN when none)."""
    v = values[np.isfinite(values)]
    nan = float("nan")
    if v.size == 0:
        return {f"{prefix}_count": 0, f"{prefix}_median": nan, f"{prefix}_mean": nan, f"{prefix}_p10": nan,
                f"{prefix}_p90": nan, f"{prefix}_max": nan}
    p10, p50, p90 = (float(x) for x in np.percentile(v, [10, 50, 90]))
    return {f"{prefix}_count": int(v.size), f"{prefix}_median": p50, f"{prefix}_mean": float(v.mean()),
            f"{prefix}_p10": p10, f"{prefix}_p90": p90, f"{prefix}_max": float(v.max())}


def _rate(count: int, hours: float, confidence: float) -> tuple[float, float, float]:
    """Events per hour and its Garwood interval; NaN without time."""
    from fdikit.metrics import rate_interval

    if not hours > 0:
        return float("nan"), float("nan"), float("nan")
    lo, hi = rate_interval(int(count), float(hours), confidence)
    return count / hours, lo, hi


def _detection_row(g, confidence: float) -> dict:
    n = len(g)
    k = int(g["detected"].sum())
    iso = int(g["_iso"].sum())
    lo, hi = clopper_pearson(k, n, confidence)
    ilo, ihi = clopper_pearson(iso, n, confidence)
    nan = float("nan")
    out = {"runs": n, "detected": k, "missed": int(g["missed"].sum()), "detection_rate": k / n if n else nan,
           "detection_low": lo, "detection_high": hi}
    out.update(_spread(g.loc[g["detected"], "detection_delay"].to_numpy(float), "delay"))
    out.update({"isolated_correct": iso, "isolation_rate": iso / n if n else nan, "isolation_low": ilo,
                "isolation_high": ihi})
    out.update(_spread(g["isolation_delay"].to_numpy(float), "isolation_delay"))
    return out


def _false_alarm_row(g, confidence: float) -> dict:
    free = g[g["fault"] == _NONE]
    n = len(free)
    k = int((free["false_alarms"] > 0).sum())
    lo, hi = clopper_pearson(k, n, confidence)
    fa, hours = int(g["false_alarms"].sum()), float(g["fault_free_hours"].sum())
    rate, rlo, rhi = _rate(fa, hours, confidence)
    return {"fault_free_runs": n, "runs_with_false_alarm": k, "false_alarm_run_fraction": k / n if n else float("nan"),
            "false_alarm_run_low": lo, "false_alarm_run_high": hi, "false_alarms": fa, "fault_free_hours": hours,
            "false_alarm_rate": rate, "false_alarm_rate_low": rlo, "false_alarm_rate_high": rhi}


def _sweep(df, column: str, n_levels: int, dtype) -> np.ndarray:
    """The list column as an (N, levels) array; DataError when a row's list has another length."""
    out = np.empty((len(df), n_levels), dtype=dtype)
    for i, v in enumerate(df[column]):
        arr = np.asarray([] if v is None else v, dtype=dtype)
        if arr.shape != (n_levels,):
            raise DataError(f"row {i}: {column} has {arr.size} entries for {n_levels} sweep levels; "
                            "pass the campaign's levels (campaign.json)")
        out[i] = arr
    return out


def _tradeoff_rows(faulty: np.ndarray, hours: float, delay: np.ndarray, fas: np.ndarray, levels,
                   confidence: float) -> list[dict]:
    """One trade-off row per level from one group's faulty mask, fault-free hours and sweep arrays."""
    rows = []
    for j, level in enumerate(levels):
        fa = int(fas[:, j].sum())
        rate, lo, hi = _rate(fa, hours, confidence)
        d = delay[faulty, j]
        d = d[np.isfinite(d)]
        n, k = int(faulty.sum()), int(d.size)
        dlo, dhi = clopper_pearson(k, n, confidence)
        rows.append({"level": float(level), "false_alarms": fa, "fault_free_hours": hours, "false_alarm_rate": rate,
                     "false_alarm_rate_low": lo, "false_alarm_rate_high": hi, "faulty_runs": n, "detected": k,
                     "detection_rate": k / n if n else float("nan"), "detection_low": dlo, "detection_high": dhi,
                     "delay_median": float(np.median(d)) if k else float("nan"),
                     "delay_p90": float(np.percentile(d, 90)) if k else float("nan")})
    return rows


def _outcomes(df):
    """:attr:`fdikit.metrics.Score.outcome` of every row."""
    free = df["fault"] == _NONE
    out = np.where(df["missed"], _MISSED, df["isolated"].astype(str))
    return np.where(free, np.where(df["false_alarms"] > 0, df["isolated"].astype(str), _NONE), out)


def _prepare(table, levels):
    """The table as a DataFrame with typed columns and the sweep lists as arrays (checked)."""
    import pandas as pd

    if hasattr(table, "to_pandas") and not isinstance(table, pd.DataFrame):  # a pyarrow Table
        table = table.to_pandas()
    if not isinstance(table, pd.DataFrame):
        raise ParameterError(f"table must be a pandas DataFrame (or pyarrow Table), got {type(table).__name__}")
    missing = [c for c in REQUIRED_COLUMNS if c not in table.columns]
    if missing:
        raise DataError(f"the results table lacks the columns {missing}; read it with "
                        "pandas.read_parquet(OUT / 'runs') (schema fdikit.campaign.schema.SCHEMA)")
    df = pd.DataFrame({
        "design": table["design"].astype(str).to_numpy(), "evaluator": table["evaluator"].astype(str).to_numpy(),
        "fault": table["fault"].astype(str).to_numpy(), "isolated": table["isolated"].astype(str).to_numpy(),
        "detected": pd.array(table["detected"], dtype="boolean").fillna(False).to_numpy(bool),
        "missed": pd.array(table["missed"], dtype="boolean").fillna(False).to_numpy(bool),
        "_iso": pd.array(table["isolation_correct"], dtype="boolean").fillna(False).to_numpy(bool),
        "detection_delay": pd.to_numeric(table["detection_delay"]).to_numpy(float),
        "isolation_delay": pd.to_numeric(table["isolation_delay"]).to_numpy(float),
        "false_alarms": pd.to_numeric(table["false_alarms"]).to_numpy(np.int64),
        "fault_free_hours": pd.to_numeric(table["fault_free_hours"]).to_numpy(float),
    })
    return df, _sweep(table, "sweep_delay", len(levels), float), _sweep(table, "sweep_false_alarms", len(levels),
                                                                       np.int64)


def campaign_statistics(table, levels: Sequence[float], confidence: float = 0.95) -> CampaignStatistics:
    """Detection, isolation, false-alarm and trade-off statistics of a results table (module docstring).

    Parameters
    ----------
    table : pandas.DataFrame or pyarrow.Table
        Rows of :data:`fdikit.campaign.schema.SCHEMA`, e.g. ``pandas.read_parquet(OUT / "runs")``; at least the
        columns :data:`REQUIRED_COLUMNS`.
    levels : sequence of float
        The campaign's sweep levels (``campaign.json``), increasing; every row's ``sweep_delay`` and
        ``sweep_false_alarms`` hold one entry per level.
    confidence : float, default 0.95
        Two-sided level of the Clopper–Pearson and Garwood intervals, in (0, 1).

    Returns
    -------
    CampaignStatistics
        The tables, sorted by design, evaluator (and fault or level).

    Raises
    ------
    DataError
        When the table lacks columns (named in the message) or a sweep list has not one entry per level.
    ParameterError
        When ``table`` is not a table, the levels are not finite, positive and increasing, or ``confidence``
        is not in (0, 1).

    Examples
    --------
    >>> import math
    >>> from fdikit.campaign.schema import table_from_rows
    >>> from fdikit.campaign.stats import campaign_statistics
    >>> def row(run, fault, detected, delay, fa, hours, sweep_delay, sweep_fa):
    ...     return dict(run=run, chunk=0, plant="p", fault=fault, kind="bias", size=1.0, onset=10.0, seed=run,
    ...                 design="bank", evaluator="threshold", detected=detected,
    ...                 missed=fault != "none" and not detected,
    ...                 detection_delay=delay, isolated=fault if detected else "none",
    ...                 isolation_correct=None if fault == "none" else detected, isolation_delay=delay,
    ...                 correct_fraction=math.nan, false_alarms=fa, fault_free_hours=hours,
    ...                 sweep_delay=sweep_delay, sweep_false_alarms=sweep_fa, metrics="{}")
    >>> nan = math.nan
    >>> rows = [row(0, "none", False, nan, 1, 1.0, [nan, nan], [3, 1]),
    ...         row(1, "f_sensor", True, 0.5, 0, 0.5, [0.2, 0.5], [0, 0]),
    ...         row(2, "f_sensor", False, nan, 0, 0.5, [1.0, nan], [1, 0])]
    >>> st = campaign_statistics(table_from_rows(rows), levels=[0.5, 1.0])
    >>> d = st.detection.iloc[0]
    >>> d["fault"], int(d["runs"]), float(d["detection_rate"]), float(d["delay_median"])
    ('f_sensor', 2, 0.5, 0.5)
    >>> fa = st.false_alarms.iloc[0]
    >>> int(fa["false_alarms"]), float(fa["fault_free_hours"]), float(fa["false_alarm_rate"])
    (1, 2.0, 0.5)
    >>> st.tradeoff[["level", "false_alarm_rate", "detection_rate", "delay_median"]].values.tolist()
    [[0.5, 2.0, 1.0, 0.6], [1.0, 0.5, 0.5, 0.5]]
    >>> st.confusion_matrix("bank", "threshold").to_dict()
    {'f_sensor': {'f_sensor': 1, 'none': 0}, 'missed': {'f_sensor': 1, 'none': 0}, 'none': {'f_sensor': 0, 'none': 1}}
    """
    import pandas as pd

    c = validate.in_range("confidence", confidence, 0.0, 1.0, closed="neither")
    try:
        lv = np.asarray(levels, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ParameterError(f"levels must be numbers (the campaign's sweep levels), got {levels!r}") from None
    if lv.size == 0 or not np.all(np.isfinite(lv)) or np.any(lv <= 0) or np.any(np.diff(lv) <= 0):
        raise ParameterError(f"levels must be finite, positive and increasing, got {lv.tolist()}")
    df, sweep_delay, sweep_fa = _prepare(table, lv)
    df["_outcome"] = _outcomes(df) if len(df) else np.array([], dtype=object)
    faulty = df[df["fault"] != _NONE]
    det_rows, all_rows, fa_rows, trade_rows, conf_rows = [], [], [], [], []
    for (design, evaluator, fault), g in faulty.groupby(["design", "evaluator", "fault"], sort=True):
        det_rows.append({"design": design, "evaluator": evaluator, "fault": fault, **_detection_row(g, c)})
    for (design, evaluator), g in df.groupby(_KEY, sort=True):
        key = {"design": design, "evaluator": evaluator}
        idx = g.index.to_numpy()
        fa_rows.append({**key, **_false_alarm_row(g, c)})
        all_rows.append({**key, **_detection_row(g[g["fault"] != _NONE], c)})
        trade_rows += [{**key, **r} for r in _tradeoff_rows((g["fault"] != _NONE).to_numpy(),
                                                            float(g["fault_free_hours"].sum()), sweep_delay[idx],
                                                            sweep_fa[idx], lv, c)]
        counts = g.groupby(["fault", "_outcome"], sort=True).size()
        conf_rows += [{**key, "true": t, "diagnosed": o, "count": int(n)} for (t, o), n in counts.items()]
    detection = pd.DataFrame(det_rows, columns=[*_KEY, "fault", *_DETECTION])
    false_alarms = pd.DataFrame(fa_rows, columns=[*_KEY, *_FALSE])
    overall = pd.DataFrame(all_rows, columns=[*_KEY, *_DETECTION]).merge(false_alarms, on=_KEY, how="left")
    tradeoff = pd.DataFrame(trade_rows, columns=[*_KEY, *_TRADEOFF])
    confusion = pd.DataFrame(conf_rows, columns=[*_KEY, "true", "diagnosed", "count"])
    return CampaignStatistics(tuple(float(x) for x in lv), c, detection, overall, false_alarms, confusion, tradeoff)


def metric_summary(table):
    """The study-specific figures (the ``metrics`` JSON column) per design × evaluator × fault × metric.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :data:`fdikit.campaign.schema.SCHEMA` (at least ``design``, ``evaluator``, ``fault`` and
        ``metrics``).

    Returns
    -------
    pandas.DataFrame
        Columns ``design``, ``evaluator``, ``fault``, ``metric``, ``runs`` (rows with a finite value), ``mean``,
        ``median``, ``p10``, ``p90``, ``min``, ``max``; empty when no row has a figure.

    Raises
    ------
    DataError
        When a column is missing or a ``metrics`` entry is not a JSON object of numbers.

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame({"design": ["a", "a"], "evaluator": ["e", "e"], "fault": ["none", "none"],
    ...                   "metrics": ['{"rmse": 1.0}', '{"rmse": 3.0}']})
    >>> metric_summary(t)[["metric", "runs", "mean", "max"]].to_dict("records")
    [{'metric': 'rmse', 'runs': 2, 'mean': 2.0, 'max': 3.0}]
    """
    import json

    import pandas as pd

    cols = ["design", "evaluator", "fault", "metrics"]
    missing = [c for c in cols if c not in table.columns]
    if missing:
        raise DataError(f"the results table lacks the columns {missing}; read it with "
                        "fdikit.campaign.store.load_results")
    values: dict[tuple, list[float]] = {}
    for design, evaluator, fault, text in table[cols].itertuples(index=False):
        try:
            figures = json.loads(text or "{}")
            items = [(str(k), float(v)) for k, v in figures.items()]
        except (ValueError, TypeError, AttributeError):
            raise DataError(f"metrics entry {text!r} is not a JSON object of numbers") from None
        for key, v in items:
            values.setdefault((design, evaluator, fault, key), []).append(v)
    rows = []
    for key, vals in sorted(values.items()):
        v = np.asarray(vals)
        v = v[np.isfinite(v)]
        stats = ([float(f(v)) for f in (np.mean, np.median)] + [float(x) for x in np.percentile(v, [10, 90])]
                 + [float(v.min()), float(v.max())]) if v.size else [np.nan] * 6
        rows.append([*key, int(v.size), *stats])
    return pd.DataFrame(rows, columns=["design", "evaluator", "fault", "metric", "runs", "mean", "median", "p10",
                                       "p90", "min", "max"])

