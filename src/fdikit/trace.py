"""One logged run: time, controls, measurements, states and the true fault per sample.

A :class:`Trace` is what :func:`fdikit.simulate.simulate` returns and what residual
generators and evaluators consume.  It exports to pandas and saves to Parquet; a recorded log
comes in through :meth:`Trace.from_pandas` and :meth:`Trace.from_csv` (:mod:`fdikit.trace_import`).

File format and integrity
-------------------------
:meth:`Trace.save` writes one Parquet file with a float64 column per time and signal and a
string column ``fault``; the names and ``meta`` are JSON in the schema metadata, with a SHA-256
digest of the content.  The file is written atomically, every page carries a CRC-32 checksum,
and :meth:`Trace.load` verifies both and the structure of the file: every malformed or damaged
file makes it raise :class:`DataError` naming the file and the problem; it never returns a
trace that differs from the one saved.  The round trip is exact.  The format and its checks
are in :mod:`fdikit.trace_io`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fdikit.errors import DataError
from fdikit.faults import NO_FAULT
from fdikit.trace_io import COLUMN_PREFIX, read_trace, write_trace

__all__ = ["Trace", "check_signals"]


# ---------------------------------------------------------------------- validation helpers
def _numbers(what: str, value) -> np.ndarray:
    """``value`` as a float array; refuses strings, complex numbers, None and other non-numbers."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise DataError(f"{what} is not a rectangular array of numbers ({exc})") from None
    kind = arr.dtype.kind
    if kind in "biuf":
        return arr.astype(float, copy=False)
    if kind == "c":
        raise DataError(f"{what} holds complex numbers (dtype {arr.dtype}); it must hold real numbers")
    if kind in "US":
        raise DataError(f"{what} holds strings (dtype {arr.dtype}); it must hold numbers (float)")
    if kind == "O":
        flat = arr.ravel()
        for k, v in enumerate(flat):
            if v is None:
                raise DataError(
                    f"{what} holds None at flat position {k}; it must hold numbers (mark a missing sample with NaN)"
                )
            if isinstance(v, complex | str | bytes):
                raise DataError(f"{what} holds {v!r} ({type(v).__name__}) at flat position {k}; it must hold numbers")
        try:
            return arr.astype(float)
        except (TypeError, ValueError) as exc:
            raise DataError(f"{what} must hold numbers: {exc}") from None
    raise DataError(f"{what} has dtype {arr.dtype}; it must hold numbers (float)")


def _time(value) -> np.ndarray:
    """The sample times as floats; refuses clock times, durations and text, which need :meth:`Trace.from_pandas`."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        arr = None
    if arr is not None and arr.dtype.kind in "MmOUS":
        what = {"M": "datetimes", "m": "durations (timedelta64)", "O": "Python objects", "U": "text", "S": "bytes"}
        raise DataError(
            f"trace time t holds {what[arr.dtype.kind]} (dtype {arr.dtype}); Trace() takes numbers (float seconds). "
            "Import a log with clock times through Trace.from_pandas(df, time=...) or Trace.from_csv(path, time=...), "
            "which convert them to seconds from the first sample and check the sampling grid"
        )
    return _numbers("trace time t", value)


def _block(name: str, value, n: int, names: Sequence[str]) -> np.ndarray:
    arr = _numbers(f"trace signal block {name!r}", value)
    if arr.ndim == 1 and len(names) == 1:
        arr = arr.reshape(-1, 1)
    if arr.shape != (n, len(names)):
        raise DataError(
            f"trace signal block {name!r} has shape {arr.shape} but must be ({n}, {len(names)}): "
            f"one row per sample and one column per name {list(names)}"
        )
    return arr


def check_names(attr: str, names) -> tuple[str, ...]:
    """Signal names of one block: non-empty UTF-8 strings, unique within the block.

    Also checks the names read from a file (:mod:`fdikit.trace_io`).
    """
    if isinstance(names, str | bytes):
        raise DataError(
            f"trace {attr} must be a sequence of names, got the single string {names!r}; write [{names!r}] "
            "for one signal"
        )
    try:
        out = tuple(names)
    except TypeError:
        raise DataError(f"trace {attr} must be a sequence of names (strings), got {type(names).__name__}") from None
    seen: set[str] = set()
    for j, nm in enumerate(out):
        if not isinstance(nm, str):
            raise DataError(f"trace {attr}[{j}] is {nm!r} ({type(nm).__name__}); signal names must be strings")
        if not nm:
            raise DataError(f"trace {attr}[{j}] is an empty name; every signal needs a non-empty name")
        try:
            nm.encode("utf-8")
        except UnicodeEncodeError:
            raise DataError(
                f"trace {attr}[{j}] = {nm!r} is not valid UTF-8 text (it holds a lone surrogate); fix the name"
            ) from None
        if nm in seen:
            raise DataError(f"duplicate name {nm!r} in trace {attr} {list(out)}; the names of a block must be unique")
        seen.add(nm)
    return tuple(str(nm) for nm in out)


def _fault(fault, n: int) -> np.ndarray:
    """The per-sample labels as a numpy str array; never coerces a non-string label."""
    if fault is None:
        return np.full(n, NO_FAULT)
    if isinstance(fault, str | bytes):
        raise DataError(
            f"trace fault must be a sequence of labels, one per sample; got the single string {fault!r} "
            f"(write np.full({n}, {fault!r}) for a constant label)"
        )
    arr = fault if isinstance(fault, np.ndarray) else np.asarray(fault, dtype=object)
    if arr.shape != (n,):
        raise DataError(f"trace fault labels have shape {arr.shape}, need ({n},): one label per sample")
    kind = arr.dtype.kind
    if kind == "U":
        empty = np.flatnonzero(arr == "")
        if empty.size:
            raise DataError(
                f"trace fault label at sample {empty[0]} is empty ({empty.size} empty labels); "
                f"use {NO_FAULT!r} for a healthy sample"
            )
        return arr
    if kind == "S":
        raise DataError(f"trace fault labels are bytes (dtype {arr.dtype}); give str labels (decode them first)")
    if kind != "O":
        raise DataError(
            f"trace fault labels must be strings ({NO_FAULT!r} where healthy), got an array of dtype {arr.dtype}"
        )
    for k, v in enumerate(arr):
        if not isinstance(v, str):
            raise DataError(
                f"trace fault label at sample {k} is {v!r} ({type(v).__name__}); every label must be a string "
                f"({NO_FAULT!r} where healthy)"
            )
        if not v:
            raise DataError(f"trace fault label at sample {k} is empty; use {NO_FAULT!r} for a healthy sample")
        if v.endswith("\x00"):
            raise DataError(
                f"trace fault label at sample {k} ({v!r}) ends with a NUL character, which numpy string arrays "
                "drop; remove it"
            )
    return arr.astype(str) if n else np.full(0, NO_FAULT)


def _valid(valid, n: int) -> np.ndarray:
    """The per-sample validity flags as a bool array (all True when None); never coerces a number."""
    if valid is None:
        return np.ones(n, dtype=bool)
    arr = np.asarray(valid)
    if arr.shape != (n,):
        raise DataError(f"trace valid flags have shape {arr.shape}, need ({n},): one True/False per sample")
    if arr.dtype.kind == "O" and all(isinstance(v, bool | np.bool_) for v in arr.tolist()):
        arr = arr.astype(bool)
    if arr.dtype.kind != "b":
        raise DataError(
            f"trace valid flags must be booleans (True where the sample is valid), got an array of dtype {arr.dtype}; "
            "convert a status column explicitly, e.g. valid=(status == 0)"
        )
    return np.array(arr, dtype=bool)  # a copy: the trace owns its flags


def _json_value(v, where: str, depth: int = 0):
    """``v`` as plain JSON values (dict with str keys, list, str, int, float, bool, None)."""
    if depth > 64:
        raise DataError(f"{where} nests deeper than 64 levels (a reference cycle?); trace meta must be plain JSON")
    if v is None or isinstance(v, bool):
        return v
    if isinstance(v, np.generic) and not isinstance(v, np.str_ | np.bytes_ | np.void):
        v = v.item()
        if v is None or isinstance(v, bool):
            return v
    if isinstance(v, str):
        return str(v)
    if isinstance(v, int):
        return int(v)
    if isinstance(v, float):
        return float(v)
    if isinstance(v, np.ndarray):
        if v.dtype.kind not in "biuf":
            raise DataError(f"{where} is an array of dtype {v.dtype}; trace meta must be JSON-serialisable")
        v = v.tolist()
    if isinstance(v, list | tuple):
        return [_json_value(x, f"{where}[{i}]", depth + 1) for i, x in enumerate(v)]
    if isinstance(v, Mapping):
        out = {}
        for key, x in v.items():
            if not isinstance(key, str):
                raise DataError(
                    f"trace meta has the key {key!r} ({type(key).__name__}) in {where}; JSON object keys must be "
                    "strings"
                )
            out[str(key)] = _json_value(x, f"{where}[{key!r}]", depth + 1)
        return out
    raise DataError(
        f"{where} is of type {type(v).__name__} ({v!r:.60}); trace meta must be JSON-serialisable: str, int, float, "
        "bool, None, and lists and dicts of them"
    )


def json_meta(meta) -> dict:
    """``meta`` as plain JSON values; also re-checks it when a trace is saved (:mod:`fdikit.trace_io`)."""
    if not isinstance(meta, Mapping):
        raise DataError(f"trace meta must be a dict (JSON object), got {type(meta).__name__}")
    return _json_value(meta, "meta")


@dataclass(frozen=True, eq=False)
class Trace:
    """A sampled run.

    Attributes
    ----------
    t : (N,) sample times in seconds (float), finite and strictly increasing.  Datetimes,
        durations, text and object arrays are refused: :meth:`from_pandas` and :meth:`from_csv`
        convert clock times to seconds.
    u, y : (N, m) controls as commanded, (N, p) measurements as recorded (NaN marks a dropout).
    x : (N, n) true states, or an (N, 0) array when unknown.
    d : (N, nd) disturbances, or (N, 0).
    fault : (N,) str, the true active fault per sample (``'none'`` where healthy).  Every label
        must be a non-empty string that does not end with a NUL character (numpy drops those);
        a None, a number or bytes is refused, never converted.
    controls, outputs, states, disturbances : names of the columns: non-empty strings, unique
        within each block.  A name may recur in another block (an output measuring a state of
        the same name); the kind (``'u'``, ``'y'``, ``'x'``, ``'d'``) tells them apart.
    meta : dict of JSON-serialisable metadata (plant, seed, scenario label ...).  It is stored
        as plain JSON values: tuples become lists and numpy scalars and numeric arrays become
        numbers and lists; dict keys must be strings.
    valid : (N,) bool, default all True.  False marks a sample the source flagged invalid: a
        grid point missing from an imported log (inserted by :meth:`from_pandas` with NaN
        values) or a sample whose status column says invalid.  Residual generators treat such
        a sample as a dropout.  Numbers are refused, never converted.

    Raises
    ------
    DataError
        For anything above that does not hold; the message names the field, the sample or the
        name at fault.

    Examples
    --------
    >>> import numpy as np
    >>> tr = Trace(t=np.arange(3) * 0.1, u=np.zeros((3, 1)), y=np.ones((3, 1)), controls=["steer"], outputs=["r"])
    >>> tr.dt, tr.fault.tolist()
    (0.1, ['none', 'none', 'none'])
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    x: np.ndarray | None = None
    states: tuple[str, ...] = ()
    d: np.ndarray | None = None
    disturbances: tuple[str, ...] = ()
    fault: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    valid: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = _time(self.t)
        if t.ndim == 2 and 1 in t.shape:
            t = t.ravel()
        if t.ndim != 1:
            raise DataError(f"trace time t must be one-dimensional (one time per sample), got shape {t.shape}")
        n = t.size
        if n and (not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0)):
            raise DataError("trace time t must be finite and strictly increasing")
        set_ = object.__setattr__
        set_(self, "t", t)
        for attr in ("controls", "outputs", "states", "disturbances"):
            set_(self, attr, check_names(attr, getattr(self, attr)))
        set_(self, "u", _block("u", self.u, n, self.controls))
        set_(self, "y", _block("y", self.y, n, self.outputs))
        set_(self, "x", _block("x", np.zeros((n, 0)) if self.x is None else self.x, n, self.states))
        set_(self, "d", _block("d", np.zeros((n, 0)) if self.d is None else self.d, n, self.disturbances))
        set_(self, "fault", _fault(self.fault, n))
        set_(self, "meta", json_meta(self.meta))
        set_(self, "valid", _valid(self.valid, n))

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return self.t.size

    @property
    def dt(self) -> float:
        """Sample time (median spacing)."""
        if self.t.size < 2:
            raise DataError("a trace with fewer than 2 samples has no sample time")
        return float(np.median(np.diff(self.t)))

    def names_of(self, kind: str) -> tuple[str, ...]:
        """Column names of block ``kind`` (``'u'``, ``'y'``, ``'x'`` or ``'d'``)."""
        names = {"u": self.controls, "y": self.outputs, "x": self.states, "d": self.disturbances}.get(kind)
        if names is None:
            raise DataError(f"unknown signal kind {kind!r}; use 'u', 'y', 'x' or 'd'")
        return names

    def signal(self, name: str, kind: str = "y") -> np.ndarray:
        """One column by name; ``kind`` is ``'u'``, ``'y'``, ``'x'`` or ``'d'``."""
        names = self.names_of(kind)
        if name not in names:
            raise DataError(f"the trace has no {kind}-signal named {name!r}; it has {list(names)}")
        return getattr(self, kind)[:, names.index(name)]

    def columns(self, kind: str, names: Sequence[str]) -> np.ndarray:
        """(N, len(names)) block of ``kind`` signals in the order of ``names``."""
        if isinstance(names, str):
            raise DataError(f"names must be a sequence of names, got the single string {names!r}; write [{names!r}]")
        return np.column_stack([self.signal(nm, kind) for nm in names]) if names else np.zeros((len(self), 0))

    def check_finite(self, signals: Sequence[str] = ("u", "y")) -> None:
        """Raise :class:`DataError` naming the first NaN/inf sample of the given blocks."""
        for kind in signals:
            names = self.names_of(kind)
            block = getattr(self, kind)
            bad = np.argwhere(~np.isfinite(block))
            if bad.size:
                k, j = bad[0]
                raise DataError(
                    f"trace has a non-finite value in {kind}-signal {names[j]!r} at sample {k} (t={self.t[k]:g}); "
                    f"{int((~np.isfinite(block)).sum())} bad values in all. Clean or interpolate the data, or "
                    "process it online with step(), which skips bad samples"
                )

    @property
    def gaps(self) -> list[tuple[float, float]]:
        """The runs of invalid samples as ``(start, stop)`` times (first and last invalid sample of each run).

        Examples
        --------
        >>> tr = Trace(t=np.arange(6.0), u=np.zeros((6, 0)), y=np.zeros((6, 0)), controls=[], outputs=[],
        ...            valid=np.array([True, False, False, True, False, True]))
        >>> tr.gaps
        [(1.0, 2.0), (4.0, 4.0)]
        """
        bad = np.concatenate(([0], (~self.valid).astype(np.int8), [0]))
        edges = np.diff(bad)
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
        return [(float(self.t[a]), float(self.t[b])) for a, b in zip(starts, stops, strict=True)]

    @property
    def fault_onset(self) -> float | None:
        """Time of the first faulty sample, or None for a fault-free trace."""
        idx = np.flatnonzero(self.fault != NO_FAULT)
        return float(self.t[idx[0]]) if idx.size else None

    # ------------------------------------------------------------------ export and I/O
    def to_pandas(self):
        """A DataFrame indexed by time, columns ``u:<name>``, ``y:<name>``, ``x:..``, ``d:..``, ``fault``, ``valid``."""
        import pandas as pd

        data = {}
        for kind, names in (("u", self.controls), ("y", self.outputs), ("x", self.states), ("d", self.disturbances)):
            block = getattr(self, kind)
            for j, nm in enumerate(names):
                data[COLUMN_PREFIX[kind] + nm] = block[:, j]
        data["fault"] = self.fault
        data["valid"] = self.valid
        return pd.DataFrame(data, index=pd.Index(self.t, name="t"))

    @classmethod
    def from_pandas(cls, df, **options) -> Trace:
        """Import a recorded log: columns to signals in SI, clock times to seconds, gaps to invalid samples.

        Parameters
        ----------
        df : pandas.DataFrame
            One row per sample.
        **options
            ``time``, ``controls``, ``outputs``, ``units``, ``fault``, ``valid``, ``dt``, ``jitter``,
            ``time_unit``, ``meta``: see :func:`fdikit.trace_import.from_pandas`.

        Returns
        -------
        Trace
            On the grid ``k dt`` from the first sample; ``meta["import"]`` records how it was read.

        Raises
        ------
        ParameterError, DataError
            As :func:`fdikit.trace_import.from_pandas` (a sample off the grid, a repeated time ...).

        Examples
        --------
        >>> import pandas as pd
        >>> clock = pd.date_range("2024-01-01", periods=4, freq="100ms", tz="UTC").delete(2)  # a gap
        >>> df = pd.DataFrame({"r": [0.0, 180.0, 90.0]}, index=clock)
        >>> tr = Trace.from_pandas(df, outputs=["r"], units={"r": "deg"}, dt=0.1)
        >>> tr.valid.tolist(), tr.meta["import"]["time"]["start"]
        ([True, True, False, True], '2024-01-01T00:00:00+00:00')
        """
        from fdikit.trace_import import from_pandas

        return from_pandas(df, cls=cls, **options)

    @classmethod
    def from_csv(cls, path: str | Path, **options) -> Trace:
        """Import a CSV log as :meth:`from_pandas` does (``read_csv=`` passes arguments to pandas).

        Parameters
        ----------
        path : str or pathlib.Path
            The CSV file, with a header row.
        **options
            As :meth:`from_pandas`, and ``read_csv``: see :func:`fdikit.trace_import.from_csv`.

        Returns
        -------
        Trace
            As :meth:`from_pandas`.

        Raises
        ------
        ParameterError, DataError
            As :func:`fdikit.trace_import.from_csv`.

        Examples
        --------
        >>> import pathlib, tempfile
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "log.csv"
        >>> _ = path.write_text("time,h_ft\\n2024-01-01T00:00:00Z,0\\n2024-01-01T00:00:01Z,1000\\n")
        >>> Trace.from_csv(path, time="time", outputs={"h": "h_ft"}, units={"h": "ft"}).y[:, 0].round(6).tolist()
        [0.0, 304.8]
        """
        from fdikit.trace_import import from_csv

        return from_csv(path, cls=cls, **options)

    def plot(self, ax=None, **kwargs):
        """Draw the signals over time with the faulty samples shaded (:func:`fdikit.plots.plot_trace`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw into it; default a new figure.
        **kwargs
            ``signals``, ``kind``, ``title`` and ``path`` of :func:`~fdikit.plots.plot_trace`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> tr = Trace(t=np.arange(3) * 0.1, u=np.zeros((3, 1)), y=np.ones((3, 1)), controls=["steer"], outputs=["r"])
        >>> fig, ax = plt.subplots()
        >>> tr.plot(ax=ax, kind="u") is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_trace

        return plot_trace(self, ax=ax, **kwargs)

    def save(self, path: str | Path) -> Path:
        """Write the trace to a Parquet file, atomically; the round trip with :meth:`load` is exact.

        Parameters
        ----------
        path : str or pathlib.Path
            Destination file; its folder is created when missing.  An existing file is replaced
            only once the new one is complete and synced to disk.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ParameterError
            When ``path`` is not a str or path.
        DataError
            When ``path`` is a folder or cannot be written, or ``meta`` (changed since the trace
            was made) or a label cannot be stored.  The previous file, if any, is kept and no
            temporary file is left behind.

        Notes
        -----
        Every page is written with a CRC-32 checksum and the schema metadata holds a SHA-256
        digest of the content (see the module docstring).
        """
        return write_trace(self, path)

    @classmethod
    def load(cls, path: str | Path, *, verify: bool = True) -> Trace:
        """Read a trace written by :meth:`save`, checking its integrity.

        Parameters
        ----------
        path : str or pathlib.Path
            The Parquet file.
        verify : bool, default True
            Require the content digest that :meth:`save` writes.  ``False`` also accepts a file
            without one (written by another program or an older fdikit, which stored NaN as
            null: such nulls read as NaN); the page checksums, the structure and a digest that
            is present are checked either way.

        Returns
        -------
        Trace
            Equal to the saved trace: floats bit for bit, the same labels, names and meta.

        Raises
        ------
        ParameterError
            When ``path`` is not a str or path, or ``verify`` not a bool.
        DataError
            For a missing, empty, truncated, corrupted or malformed file (not Parquet, not an
            fdikit trace, bad metadata, a missing, duplicate, unexpected or mistyped column, a
            null or empty label, a digest that does not match ...); the message names the file
            and the problem.
        """
        return read_trace(path, verify=verify, cls=cls)

    def __repr__(self) -> str:
        span = f"{self.t[0]:g}..{self.t[-1]:g} s" if len(self) else "empty"
        return (
            f"Trace({len(self)} samples, {span}, u={len(self.controls)}, y={len(self.outputs)}, "
            f"x={len(self.states)}, faults={sorted(set(self.fault.tolist()) - {NO_FAULT})}"
            + (f", invalid={int((~self.valid).sum())})" if not self.valid.all() else ")")
        )


def check_signals(trace: Trace, controls: Sequence[str], outputs: Sequence[str]) -> None:
    """Refuse a trace that lacks signals a generator reads.

    Parameters
    ----------
    trace : Trace
        The trace to read.
    controls, outputs : sequence of str
        The signal names the generator reads.

    Raises
    ------
    DataError
        Naming each missing control/output, where a misplaced one was found instead (an output
        recorded as a control or the reverse), and the trace's signals the generator does not read.

    Examples
    --------
    >>> tr = Trace(t=np.arange(3) * 0.1, u=np.zeros((3, 1)), y=np.ones((3, 1)), controls=["steer"], outputs=["r"])
    >>> check_signals(tr, ["steer"], ["r"])
    >>> check_signals(tr, [], ["steer"])
    Traceback (most recent call last):
    ...
    fdikit.errors.DataError: the trace does not match the generator's signals: missing outputs ['steer'] ...
    """
    problems = []
    for kind, want, have, other, other_kind in (
        ("control", controls, trace.controls, trace.outputs, "output"),
        ("output", outputs, trace.outputs, trace.controls, "control"),
    ):
        missing = [nm for nm in want if nm not in have]
        if missing:
            moved = [nm for nm in missing if nm in other]
            text = f"missing {kind}s {missing}"
            if moved:
                text += f" ({moved} found as {other_kind}s)"
            extra = [nm for nm in have if nm not in want]
            if extra:
                text += f"; the trace's {kind}s not read: {extra}"
            problems.append(text)
    if problems:
        raise DataError(
            "the trace does not match the generator's signals: " + "; ".join(problems)
            + f". The generator reads controls {list(controls)} and outputs {list(outputs)}; rename the "
            "trace's columns or use the generator designed for this plant"
        )
