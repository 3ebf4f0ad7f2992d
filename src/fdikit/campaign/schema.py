"""The results table of a campaign: one row per run × design × evaluator.

A campaign's results folder holds a partitioned Parquet dataset, ``runs/chunk-NNNNNN.parquet``, one file
per chunk of runs (each written atomically as the chunk finishes).  Every file has the columns of
:data:`SCHEMA`, in this order; :func:`empty_table` and :func:`table_from_rows` build one.  The sweep
levels (the scale factors of the evaluator's nominal threshold at which ``sweep_delay`` and
``sweep_false_alarms`` are recorded) are the campaign's, stored in ``campaign.json`` next to ``runs/``.

Columns
-------
run : int64
    Index of the run in the campaign's plan (0-based); with ``design`` and ``evaluator`` the row's key.
chunk : int64
    The chunk (file) the run belongs to.
plant : str
    The plant or operating point of the run (a name from the spec).
fault : str
    The fault label of the run (the fault name, e.g. ``yaw_rate_sensor``), ``'none'`` for a fault-free run.
kind : str
    Fault kind (``bias``, ``drift``, ``lock``, ...) or ``'none'``.
size : float64
    Fault size in the spec's unit (relative to the fault's nominal size for the PATH studies); NaN if none.
onset : float64
    Fault onset [s]; NaN for a fault-free run.
seed : uint64
    The run's own simulation seed, derived from the campaign seed and ``run``.
design : str
    The residual generator (or model bank) of the row.
evaluator : str
    The residual evaluator (decision rule) of the row.
detected, missed : bool
    As :class:`fdikit.metrics.Score`.
detection_delay : float64
    Detection time minus onset [s]; NaN when not detected or fault-free.
isolated : str
    As :class:`fdikit.metrics.Score` (the most frequent label while detected, ``'none'`` when missed).
isolation_correct : bool, nullable
    As :class:`fdikit.metrics.Score` (null for a fault-free run).
isolation_delay : float64
    Onset until the right fault is named and held [s]; NaN when never.
correct_fraction : float64
    Fraction of alarmed faulty samples naming the right fault; NaN when not detected or fault-free.
false_alarms : int64
    Alarms switching on at fault-free samples.
fault_free_hours : float64
    Fault-free time of the run [h].
sweep_delay : list<float64>
    Per sweep level: first time at or after the onset when the decision statistic exceeds the level,
    minus the onset [s]; NaN when it never does (and for fault-free runs).
sweep_false_alarms : list<int64>
    Per sweep level: up-crossings of the level by the decision statistic at fault-free samples.
metrics : str
    JSON object of study-specific figures (e.g. an RMSE), ``"{}"`` when none.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

__all__ = ["SCHEMA", "COLUMNS", "empty_table", "table_from_rows"]  # noqa: F822 - SCHEMA is built lazily (pyarrow)


def _schema():
    import pyarrow as pa

    return pa.schema([
        ("run", pa.int64()), ("chunk", pa.int64()), ("plant", pa.string()), ("fault", pa.string()),
        ("kind", pa.string()), ("size", pa.float64()), ("onset", pa.float64()), ("seed", pa.uint64()),
        ("design", pa.string()), ("evaluator", pa.string()),
        ("detected", pa.bool_()), ("missed", pa.bool_()), ("detection_delay", pa.float64()),
        ("isolated", pa.string()), ("isolation_correct", pa.bool_()), ("isolation_delay", pa.float64()),
        ("correct_fraction", pa.float64()), ("false_alarms", pa.int64()), ("fault_free_hours", pa.float64()),
        ("sweep_delay", pa.list_(pa.float64())), ("sweep_false_alarms", pa.list_(pa.int64())),
        ("metrics", pa.string()),
    ])


def __getattr__(name):
    if name == "SCHEMA":
        return _schema()
    raise AttributeError(name)


#: Column names of :data:`SCHEMA`, in order.
COLUMNS = ("run", "chunk", "plant", "fault", "kind", "size", "onset", "seed", "design", "evaluator",
           "detected", "missed", "detection_delay", "isolated", "isolation_correct", "isolation_delay",
           "correct_fraction", "false_alarms", "fault_free_hours", "sweep_delay", "sweep_false_alarms", "metrics")


def empty_table():
    """A table with the campaign columns and no rows.

    Returns
    -------
    pyarrow.Table
        Zero rows, schema :data:`SCHEMA`.

    Examples
    --------
    >>> from fdikit.campaign.schema import empty_table, COLUMNS
    >>> t = empty_table()
    >>> t.num_rows, tuple(t.column_names) == COLUMNS
    (0, True)
    """
    return _schema().empty_table()


def table_from_rows(rows: Iterable[Mapping]):
    """A table of campaign rows (mappings with every column of :data:`COLUMNS`), in the given order.

    Parameters
    ----------
    rows : iterable of mapping
        One mapping per row; NaN stands for a missing float, None for a missing ``isolation_correct``.

    Returns
    -------
    pyarrow.Table
        Schema :data:`SCHEMA`.

    Raises
    ------
    DataError
        When a row lacks a column or has one the schema does not know.

    Examples
    --------
    >>> from fdikit.campaign.schema import table_from_rows
    >>> row = dict(run=0, chunk=0, plant="linear", fault="none", kind="none", size=float("nan"),
    ...            onset=float("nan"), seed=7, design="bank", evaluator="threshold", detected=False,
    ...            missed=False, detection_delay=float("nan"), isolated="none", isolation_correct=None,
    ...            isolation_delay=float("nan"), correct_fraction=float("nan"), false_alarms=0,
    ...            fault_free_hours=20 / 3600, sweep_delay=[float("nan")] * 3, sweep_false_alarms=[0, 0, 0],
    ...            metrics="{}")
    >>> table_from_rows([row]).num_rows
    1
    """
    from fdikit.errors import DataError

    rows = list(rows)
    known = set(COLUMNS)
    for k, row in enumerate(rows):
        keys = set(row)
        if keys != known:
            missing, extra = sorted(known - keys), sorted(keys - known)
            raise DataError(f"campaign row {k}: missing columns {missing}, unknown columns {extra}")
    import pyarrow as pa

    return pa.Table.from_pydict({c: [row[c] for row in rows] for c in COLUMNS}, schema=_schema())
