"""Import a recorded log (a pandas DataFrame or a CSV file) into a :class:`~fdikit.trace.Trace`.

Use :meth:`Trace.from_pandas <fdikit.trace.Trace.from_pandas>` and
:meth:`Trace.from_csv <fdikit.trace.Trace.from_csv>`, which call :func:`from_pandas` and
:func:`from_csv`.

What the import does, and what it refuses
-----------------------------------------
* **Signals.** ``controls`` and ``outputs`` name the columns to read: a list of column names
  (the signal takes the column's name) or a mapping signal name -> column name.  ``units``
  maps a signal name to the unit it is recorded in; its values are converted to SI base units
  with :func:`fdikit.units.to_si` (``deg/s`` -> ``rad/s``, ``kt`` -> ``m/s``, ``degC`` -> ``K`` ...).
  A signal left out of ``units`` is taken as recorded in SI.  A NaN in a signal stays: it
  marks a dropout of that signal.  Text in a signal column is refused, never coerced.
* **Time.** The index (``time=None``) or a column: numbers (seconds, or ``time_unit``),
  datetimes (naive or tz-aware, also as ISO 8601 text, as a CSV holds them) or durations.
  The trace's time is float seconds from the first sample; the first timestamp is kept in
  ``meta`` as ISO text.  A missing time is refused.
* **Sampling grid.** The sample time ``dt`` is the given one or the median spacing.  Every
  sample must sit on the grid ``t0 + k dt`` within ``jitter`` (default ``dt / 100``); the
  trace's time is the grid time ``k dt``.  A grid point without a row (a gap, e.g. left by
  ``dropna``) becomes an *inserted* sample: NaN in every signal, ``valid = False``, the fault
  label of the sample before it.  A sample off the grid, a duplicate time or a time that goes
  back is refused with a :class:`~fdikit.errors.DataError` naming the first such row and what
  to do: the import never resamples, reorders or merges samples.
* **Flags and labels.** ``valid`` names a boolean status column (False: the source flagged the
  sample invalid); ``fault`` a column of true fault labels (text; an empty cell reads
  ``'none'``).

What ``meta["import"]`` records
-------------------------------
JSON values that let a saved detector re-read a log the same way (:func:`import_arguments`):
``source``, ``time`` (``column``, ``kind``: ``seconds``/``datetime``/``timedelta``, ``unit``,
``timezone``, ``start``), ``dt``, ``dt_given``, ``jitter``, ``max_deviation`` (the largest
distance of a sample from its grid point, s), ``signals`` (``controls`` and ``outputs``:
signal name -> ``column``, ``unit`` (as recorded, None for SI), ``si_unit``), ``fault``,
``valid``, ``rows`` (read) and ``inserted`` (gap samples added).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT

if TYPE_CHECKING:
    from fdikit.trace import Trace

__all__ = ["from_csv", "from_pandas", "import_arguments"]

_JITTER = 0.01  # default jitter tolerance, as a fraction of dt
_MAX_GROWTH = 10  # refuse a grid more than this many times longer than the log (a mis-estimated dt?)
_OFFSET = re.compile(r"(Z|[+-]\d\d(:?\d\d)?)$")


# ---------------------------------------------------------------------- arguments
def _signals(block: str, spec, columns) -> list[tuple[str, object]]:
    """(signal name, column) pairs of ``controls`` or ``outputs``."""
    if spec is None:
        return []
    if isinstance(spec, str | bytes):
        raise ParameterError(f"{block} must be a list of column names or a mapping signal -> column, got the "
                             f"single string {spec!r}; write [{spec!r}]")
    if isinstance(spec, Mapping):
        pairs = list(spec.items())
    elif isinstance(spec, Sequence):
        pairs = [(col, col) for col in spec]
    else:
        raise ParameterError(f"{block} must be a list of column names or a mapping signal -> column, got "
                             f"{type(spec).__name__}")
    for name, col in pairs:
        if not isinstance(col, str):
            raise ParameterError(f"{block}: the column {col!r} must be named by a string (give the DataFrame text "
                                 "column names, e.g. df.columns = df.columns.map(str))")
        if not isinstance(name, str) or not name:
            raise ParameterError(f"{block}: the signal name {name!r} must be a non-empty string (rename the column "
                                 f"with a mapping, e.g. {block}={{'yaw_rate': {name!r}}})")
        if col not in columns:
            raise DataError(f"{block}: the log has no column {col!r} (for signal {name!r}); its columns are "
                            f"{list(columns)}")
    return pairs


def _units(units, pairs: dict[str, list]) -> dict[str, str]:
    if units is None:
        return {}
    if not isinstance(units, Mapping):
        raise ParameterError(f"units must be a mapping signal name -> unit (e.g. {{'r': 'deg/s'}}), got "
                             f"{type(units).__name__}")
    names = {nm for block in pairs.values() for nm, _ in block}
    columns = {col: nm for block in pairs.values() for nm, col in block}
    for key in units:
        if key not in names:
            hint = f" (it is the column of signal {columns[key]!r}: key units by signal name)" if key in columns else ""
            raise ParameterError(f"units names {key!r}, which is not a signal read{hint}; the signals are "
                                 f"{sorted(names)}")
    return dict(units)


def _float_column(what: str, series) -> np.ndarray:
    """A column as floats: numbers and booleans pass (pandas NA -> NaN), text is refused."""
    import pandas as pd

    dtype = series.dtype
    if pd.api.types.is_bool_dtype(dtype) or pd.api.types.is_numeric_dtype(dtype):
        if pd.api.types.is_complex_dtype(dtype):
            raise DataError(f"{what} holds complex numbers; a signal must hold real numbers")
        return series.to_numpy(dtype=float, na_value=np.nan)
    values = series.to_numpy(dtype=object)
    for k, v in enumerate(values):
        if v is None or (isinstance(v, float) and np.isnan(v)) or v is pd.NA:
            continue
        if not isinstance(v, int | float | np.number) or isinstance(v, complex | np.complexfloating):
            raise DataError(f"{what} holds {v!r} ({type(v).__name__}) at row {k}; a signal must hold numbers (an "
                            "empty cell or NaN marks a dropout). Clean the column or convert it explicitly")
    return series.to_numpy(dtype=float, na_value=np.nan)


# ---------------------------------------------------------------------- time
def _parse_text_times(what: str, values: np.ndarray):
    import pandas as pd

    texts = [v for v in values if v is not None and not (isinstance(v, float) and np.isnan(v))]
    if len(texts) < len(values):
        k = next(i for i, v in enumerate(values) if v is None or (isinstance(v, float) and np.isnan(v)))
        raise DataError(f"{what} is missing at row {k}; every sample needs a time (drop rows without one first)")
    bad = next(((k, v) for k, v in enumerate(values) if not isinstance(v, str)), None)
    if bad is not None:
        raise DataError(f"{what} holds {bad[1]!r} ({type(bad[1]).__name__}) at row {bad[0]}; give times as ISO 8601 "
                        "text, datetimes or numbers of seconds")
    try:
        return pd.DatetimeIndex(pd.to_datetime(pd.Index(values, dtype=object), format="ISO8601"))
    except ValueError as exc:
        if "Mixed timezones" not in str(exc):
            raise DataError(f"{what} holds text that is not ISO 8601 date and time ({exc}); write times as "
                            "'2024-05-01T12:00:00.250' (optionally with an offset '+02:00'), or as seconds") from None
    naive = next((k for k, v in enumerate(values) if not _OFFSET.search(v.strip())), None)
    if naive is not None:
        raise DataError(f"{what} mixes times with and without a UTC offset (row {naive}: {values[naive]!r}); "
                        "give every time an offset, or none")
    return pd.DatetimeIndex(pd.to_datetime(pd.Index(values, dtype=object), format="ISO8601", utc=True))


def _times(what: str, values, time_unit: str):
    """(integer ns offsets or None, float seconds offsets, kind, timezone, start, row -> time text)."""
    import pandas as pd

    from fdikit.units import to_si

    values = pd.Index(values)
    dtype = values.dtype
    if isinstance(dtype, pd.DatetimeTZDtype) or pd.api.types.is_datetime64_dtype(dtype):
        idx = pd.DatetimeIndex(values)
    elif pd.api.types.is_timedelta64_dtype(dtype):
        idx = pd.TimedeltaIndex(values)
    elif pd.api.types.is_bool_dtype(dtype):
        raise DataError(f"{what} holds booleans; give times as seconds, datetimes or ISO 8601 text")
    elif pd.api.types.is_numeric_dtype(dtype):
        seconds, si = to_si(values.to_numpy(dtype=float, na_value=np.nan), time_unit)
        if si != "s":
            raise ParameterError(f"time_unit {time_unit!r} is not a unit of time (it converts to {si!r}); use 's', "
                                 "'ms', 'min' ...")
        if seconds.size and not np.all(np.isfinite(seconds)):
            k = int(np.flatnonzero(~np.isfinite(seconds))[0])
            raise DataError(f"{what} is missing or not finite at row {k}; every sample needs a time (drop rows "
                            "without one first)")
        start = float(seconds[0]) if seconds.size else 0.0
        return None, seconds - start, "seconds", None, start, lambda i: f"{seconds[i]:g} s"
    else:
        idx = _parse_text_times(what, values.to_numpy(dtype=object))
    if idx.hasnans:
        k = int(np.flatnonzero(idx.isna())[0])
        raise DataError(f"{what} is missing (NaT) at row {k}; every sample needs a time (drop rows without one first)")
    ns = idx.as_unit("ns").asi8
    offsets = ns - ns[0] if ns.size else ns
    if isinstance(idx, pd.TimedeltaIndex):
        start = float(ns[0]) / 1e9 if ns.size else 0.0
        return offsets, offsets / 1e9, "timedelta", None, start, lambda i: str(idx[i])
    tz = None if idx.tz is None else str(idx.tz)
    start = idx[0].isoformat() if ns.size else None
    return offsets, offsets / 1e9, "datetime", tz, start, lambda i: idx[i].isoformat()


def _grid(rel: np.ndarray, rel_ns, dt, jitter, label) -> tuple[np.ndarray, float, float, float]:
    """Grid index k of each sample, the sample time, the tolerance used and the largest deviation."""
    n = rel.size
    diffs = np.diff(rel_ns) if rel_ns is not None else np.diff(rel)
    back = np.flatnonzero(diffs <= 0)
    if back.size:
        i = int(back[0]) + 1
        what = "repeats the time of" if diffs[i - 1] == 0 else "goes back in time from"
        raise DataError(
            f"the log's time is not strictly increasing: row {i} (t = {label(i)}) {what} row {i - 1} "
            f"(t = {label(i - 1)}). Sort the rows by time and remove the duplicates (deciding which one is right) "
            "before importing; the import never reorders or merges samples"
        )
    given = dt is not None
    if given:
        dt = validate.positive("dt", dt)
    elif n < 2:
        raise DataError("a log with fewer than 2 samples has no sample time to estimate; pass dt=")
    else:
        dt = float(np.median(diffs)) / (1e9 if rel_ns is not None else 1.0)
    tol = _JITTER * dt if jitter is None else validate.non_negative("jitter", jitter)
    if tol >= dt / 2:
        raise ParameterError(f"jitter = {tol:g} s must be below half the sample time dt = {dt:g} s, or a sample "
                             "could belong to two grid points")
    slack = 8 * np.finfo(float).eps * max(float(rel[-1]) if n else 0.0, dt)  # float rounding of k dt, not jitter
    k = np.rint(rel / dt)
    dev = np.abs(rel - k * dt)
    if not given and n > 2 and np.any(dev > tol + slack):  # the median of a rounded clock is off: fit the slope
        steps = np.concatenate(([0.0], np.cumsum(np.maximum(np.rint(np.diff(rel) / dt), 1.0))))  # no drift
        fit = float(np.dot(steps, rel) / np.dot(steps, steps))
        tol_fit = _JITTER * fit if jitter is None else tol
        k_fit = np.rint(rel / fit)
        dev_fit = np.abs(rel - k_fit * fit)
        if np.all(dev_fit <= tol_fit + slack):
            k, dt, tol, dev = k_fit, fit, tol_fit, dev_fit
    off = np.flatnonzero(dev > tol + slack)
    if off.size:
        i = int(off[0])
        raise DataError(
            f"row {i} (t = {label(i)}) is off the sampling grid t0 + k dt by {dev[i]:.3g} s = {dev[i] / dt:.3g} dt "
            f"(dt = {dt:.6g} s {'as given' if given else 'estimated as the median spacing'}, tolerance jitter = "
            f"{tol:.3g} s; {off.size} rows off the grid, the largest deviation {dev.max():.3g} s). Pass the true "
            "dt= (the median spacing is too long when most steps are gaps), a larger jitter= if the clock jitters, "
            "or resample the log yourself (e.g. df.resample(...).mean()): the import never resamples"
        )
    k = k.astype(np.int64)
    same = np.flatnonzero(np.diff(k) == 0)
    if same.size:
        i = int(same[0]) + 1
        raise DataError(f"rows {i - 1} and {i} (t = {label(i - 1)}, {label(i)}) fall on the same grid point at "
                        f"dt = {dt:.6g} s; pass the true dt= or remove one of them")
    if n and k[-1] + 1 > _MAX_GROWTH * n + 100:
        i = int(np.argmax(np.diff(k))) + 1
        raise DataError(
            f"the log's {n} rows span {k[-1] + 1} samples of dt = {dt:.6g} s: the longest gap, before row {i} "
            f"(t = {label(i)}), lasts {(k[i] - k[i - 1]) * dt:g} s. Check dt=, or split the log at its long gaps "
            "and import each part"
        )
    return k, dt, tol, float(dev.max()) if n else 0.0


# ---------------------------------------------------------------------- flags and labels
def _valid_rows(valid, df) -> tuple[np.ndarray, object]:
    import pandas as pd

    n = len(df)
    if valid is None:
        return np.ones(n, dtype=bool), None
    if isinstance(valid, str):
        if valid not in df.columns:
            raise DataError(f"valid: the log has no column {valid!r}; its columns are {list(df.columns)}")
        series, source = df[valid], valid
    else:
        series, source = pd.Series(np.asarray(valid)), "given"
        if len(series) != n:
            raise ParameterError(f"valid has {len(series)} flags for {n} rows; give one per row or a column name")
    if series.isna().any():
        k = int(np.flatnonzero(series.isna().to_numpy())[0])
        raise DataError(f"the valid flags are missing at row {k}; every row needs True or False")
    if not pd.api.types.is_bool_dtype(series.dtype):
        raise DataError(f"the valid flags must be booleans (True where the sample is valid), got dtype "
                        f"{series.dtype}; convert a status code explicitly, e.g. df['ok'] = df['status'] == 0")
    return series.to_numpy(dtype=bool), source


def _labels(fault, df) -> np.ndarray:
    import pandas as pd

    n = len(df)
    if fault is None:
        return np.full(n, NO_FAULT, dtype=object)
    if not isinstance(fault, str):
        raise ParameterError(f"fault must be the name of the column of true fault labels, got {fault!r}")
    if fault not in df.columns:
        raise DataError(f"fault: the log has no column {fault!r}; its columns are {list(df.columns)}")
    out = df[fault].to_numpy(dtype=object)
    for k, v in enumerate(out):
        if v is None or v is pd.NA or (isinstance(v, float) and np.isnan(v)) or (isinstance(v, str) and not v):
            out[k] = NO_FAULT
        elif not isinstance(v, str):
            raise DataError(f"fault label column {fault!r} holds {v!r} ({type(v).__name__}) at row {k}; labels must "
                            f"be text ({NO_FAULT!r} or an empty cell where healthy)")
    return out


# ---------------------------------------------------------------------- the import
def from_pandas(df, *, time=None, controls=None, outputs=None, units=None, fault=None, valid=None, dt=None,
                jitter=None, time_unit: str = "s", meta=None, cls: type[Trace] | None = None,
                _source=None) -> Trace:
    """Build a :class:`~fdikit.trace.Trace` from a recorded log; the implementation of :meth:`Trace.from_pandas`.

    Parameters
    ----------
    df : pandas.DataFrame
        One row per sample.
    time : str, optional
        The time column; default the index.  Numbers (seconds, see ``time_unit``), datetimes (naive or
        tz-aware), ISO 8601 text or durations.  A default ``RangeIndex`` is refused (it is no clock).
    controls, outputs : list of str or mapping str -> str, optional
        The columns to read as controls and outputs: column names, or signal name -> column name.
    units : mapping str -> str, optional
        Signal name -> recorded unit (pint spelling, see :mod:`fdikit.units`); converted to SI.
    fault : str, optional
        The column of true fault labels (text, an empty cell is ``'none'``); default every sample ``'none'``.
    valid : str or array_like of bool, optional
        The boolean status column (or one flag per row): False marks a sample the source flagged invalid.
    dt : float, optional
        The sample time (s); default the median spacing of the times.
    jitter : float, optional
        How far (s) a sample may sit from its grid point ``t0 + k dt``; default ``dt / 100``.
    time_unit : str, default "s"
        The unit of a numeric time (``"ms"``, ``"min"`` ...).
    meta : dict, optional
        More metadata for the trace (JSON values); ``meta["import"]`` is set by the import.
    cls : type, optional
        The class to build (default :class:`~fdikit.trace.Trace`).

    Returns
    -------
    Trace
        Time in seconds from the first sample on the grid ``k dt``, signals in SI, gap samples inserted with
        NaN and ``valid = False``, and ``meta["import"]`` as the module docstring describes.

    Raises
    ------
    ParameterError
        For a bad argument: not a DataFrame, an unknown, ambiguous or non-SI-convertible unit, a ``units`` key
        that is no signal, ``jitter`` of half ``dt`` or more.
    DataError
        For a missing column, text in a signal, a missing time, times that repeat or go back, a sample off the
        grid, non-boolean or missing valid flags, a non-text fault label; the message names the first such row.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({"time": ["2024-05-01T12:00:00.0", "2024-05-01T12:00:00.5", "2024-05-01T12:00:01.5",
    ...                             "2024-05-01T12:00:02.0"],
    ...                    "r_dps": [0.0, 90.0, 180.0, 90.0], "delta": [1.0, 2.0, 3.0, 4.0]})
    >>> tr = from_pandas(df, time="time", controls=["delta"], outputs={"r": "r_dps"}, units={"r": "deg/s"})
    >>> tr.t.tolist(), tr.valid.tolist(), tr.gaps
    ([0.0, 0.5, 1.0, 1.5, 2.0], [True, True, False, True, True], [(1.0, 1.0)])
    >>> tr.y[:, 0].round(4).tolist()
    [0.0, 1.5708, nan, 3.1416, 1.5708]
    >>> tr.meta["import"]["time"]["start"], tr.meta["import"]["signals"]["outputs"]["r"]
    ('2024-05-01T12:00:00', {'column': 'r_dps', 'unit': 'deg/s', 'si_unit': 'rad/s'})
    """
    import pandas as pd

    from fdikit.trace import Trace, json_meta
    from fdikit.units import si_unit, to_si

    if not isinstance(df, pd.DataFrame):
        raise ParameterError(f"df must be a pandas DataFrame, got {type(df).__name__}")
    cls = Trace if cls is None else cls
    pairs = {block: _signals(block, spec, df.columns) for block, spec in (("controls", controls), ("outputs", outputs))}
    if not pairs["controls"] and not pairs["outputs"]:
        raise ParameterError("give the columns to read: controls=[...] and/or outputs=[...]")
    units = _units(units, pairs)
    for unit in units.values():
        si_unit(unit)  # refuse a bad unit before reading any data
    dup = sorted({str(c) for c in df.columns[df.columns.duplicated()]})
    if dup:
        raise DataError(f"the log has duplicate column names {dup}; rename them so that each column is unique")
    if meta is not None and (not isinstance(meta, Mapping) or "import" in meta):
        raise ParameterError("meta must be a dict without the key 'import' (the import writes it)")

    if time is None:
        if isinstance(df.index, pd.RangeIndex):
            raise DataError("the log's index is a plain row number (RangeIndex), not a time; pass time='<column>' "
                            "or set the time column as the index (df.set_index(...))")
        what, values = "the time (the index)", df.index
    else:
        if not isinstance(time, str):
            raise ParameterError(f"time must be the name (str) of the time column, or None for the index; got {time!r}")
        if time not in df.columns:
            raise DataError(f"time: the log has no column {time!r}; its columns are {list(df.columns)}")
        what, values = f"the time column {time!r}", df[time]
    rel_ns, rel, kind, tz, start, label = _times(what, values, time_unit)
    dt_given = dt is not None
    k, dt, tol, max_dev = _grid(rel, rel_ns, dt, jitter, label)

    n = len(df)
    size = int(k[-1]) + 1 if n else 0
    present = np.zeros(size, dtype=bool)
    present[k] = True
    blocks, record = {}, {}
    for block, block_pairs in pairs.items():
        arr = np.full((size, len(block_pairs)), np.nan)
        record[block] = {}
        for j, (name, col) in enumerate(block_pairs):
            values = _float_column(f"column {col!r} (signal {name!r})", df[col])
            unit = units.get(name)
            si = None
            if unit is not None:
                values, si = to_si(values, unit)
            arr[k, j] = values
            record[block][name] = {"column": col, "unit": unit, "si_unit": si}
        blocks[block] = arr
    flags, valid_source = _valid_rows(valid, df)
    valid_all = np.zeros(size, dtype=bool)
    valid_all[k] = flags
    labels_rows = _labels(fault, df)
    # an inserted sample takes the label of the sample before it (the truth goes on through a gap)
    labels_all = labels_rows[np.cumsum(present) - 1] if size else labels_rows

    info = {
        "source": _source or {"kind": "pandas"},
        "time": {"column": time, "kind": kind, "unit": time_unit if kind == "seconds" else None, "timezone": tz,
                 "start": start},
        "dt": dt, "dt_given": dt_given, "jitter": tol, "max_deviation": max_dev, "signals": record, "fault": fault,
        "valid": valid_source, "rows": n, "inserted": size - n,
    }
    out_meta = {**json_meta(meta or {}), "import": info}
    names = {block: [nm for nm, _ in block_pairs] for block, block_pairs in pairs.items()}
    return cls(t=np.arange(size) * dt, u=blocks["controls"], y=blocks["outputs"], controls=names["controls"],
               outputs=names["outputs"], fault=labels_all.astype(str) if size else None, valid=valid_all,
               meta=out_meta)


def from_csv(path, *, read_csv: Mapping | None = None, **options) -> Trace:
    """Read a CSV log with :func:`pandas.read_csv` and import it; the implementation of :meth:`Trace.from_csv`.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file: a header row of column names, one row per sample.  Times may be numbers (seconds) or
        ISO 8601 text such as ``2024-05-01T12:00:00.250+02:00``.
    read_csv : mapping, optional
        More keyword arguments of :func:`pandas.read_csv` (``sep``, ``decimal``, ``comment`` ...).
    **options
        The keyword arguments of :func:`from_pandas` (``time``, ``controls``, ``outputs``, ``units``, ``fault``,
        ``valid``, ``dt``, ``jitter``, ``time_unit``, ``meta``, ``cls``).

    Returns
    -------
    Trace
        As :func:`from_pandas`; ``meta["import"]["source"]`` is ``{"kind": "csv", "path": <path>}``.

    Raises
    ------
    ParameterError
        When ``path`` is not a str or path, and as :func:`from_pandas`.
    DataError
        When the file is missing or cannot be parsed as CSV, and as :func:`from_pandas`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "log.csv"
    >>> _ = path.write_text("t,speed_kmh\\n0.0,36\\n0.5,72\\n")
    >>> tr = from_csv(path, time="t", outputs={"speed": "speed_kmh"}, units={"speed": "km/h"})
    >>> tr.y[:, 0].tolist(), tr.dt
    ([10.0, 20.0], 0.5)
    """
    import pandas as pd

    if not isinstance(path, str | os.PathLike):
        raise ParameterError(f"path must be a file name (str or pathlib.Path), got {type(path).__name__}")
    if read_csv is not None and not isinstance(read_csv, Mapping):
        raise ParameterError(f"read_csv must be a dict of pandas.read_csv arguments, got {type(read_csv).__name__}")
    path = Path(path)
    if not path.is_file():
        raise DataError(f"no CSV file at {path}" + (" (it is a folder)" if path.is_dir() else ""))
    try:
        df = pd.read_csv(path, **dict(read_csv or {}))
    except (ValueError, OSError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataError(f"cannot read the CSV file {path}: {exc}") from None
    try:
        return from_pandas(df, _source={"kind": "csv", "path": str(path)}, **options)
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None


def import_arguments(meta: Mapping) -> dict:
    """The arguments that re-read a log the way the trace with this ``meta`` was read.

    Parameters
    ----------
    meta : mapping
        ``trace.meta`` of an imported trace (or the ``meta["import"]`` dict itself).

    Returns
    -------
    dict
        ``time``, ``controls`` and ``outputs`` (signal -> column), ``units``, ``fault``, ``valid``, ``dt``,
        ``jitter`` and ``time_unit``: pass them to :func:`from_pandas` or :func:`from_csv`.  ``dt`` is the sample
        time found then, so a log at another rate is refused.  Flags given as an array are not stored:
        ``valid`` is None then.

    Raises
    ------
    DataError
        When ``meta`` does not hold an import record.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({"t": [0.0, 0.1], "r": [0.0, 1.0]})
    >>> tr = from_pandas(df, time="t", outputs=["r"], units={"r": "deg/s"})
    >>> args = import_arguments(tr.meta)
    >>> args["outputs"], args["units"], args["dt"]
    ({'r': 'r'}, {'r': 'deg/s'}, 0.1)
    >>> from_pandas(df, **args).y.tolist() == tr.y.tolist()
    True
    """
    info = meta.get("import", meta) if isinstance(meta, Mapping) else None
    try:
        signals = info["signals"]
        out = {
            "time": info["time"]["column"],
            "controls": {nm: rec["column"] for nm, rec in signals["controls"].items()},
            "outputs": {nm: rec["column"] for nm, rec in signals["outputs"].items()},
            "units": {nm: rec["unit"] for block in ("controls", "outputs") for nm, rec in signals[block].items()
                      if rec["unit"] is not None},
            "fault": info["fault"],
            "valid": info["valid"] if info["valid"] != "given" else None,
            "dt": info["dt"],
            "jitter": info["jitter"],
            "time_unit": info["time"]["unit"] or "s",
        }
    except (KeyError, TypeError, AttributeError):
        raise DataError("meta holds no import record (meta['import'] written by Trace.from_pandas or "
                        "Trace.from_csv)") from None
    return out
