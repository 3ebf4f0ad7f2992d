"""One logged run: time, controls, measurements, states and the true fault per sample.

A :class:`Trace` is what :func:`fdikit.simulate.simulate` returns and what residual
generators and evaluators consume.  It exports to pandas and saves to Parquet.

File format and integrity
-------------------------
:meth:`Trace.save` writes one Parquet file with the float64 columns ``t``, ``u:<name>``,
``y:<name>``, ``x:<name>``, ``d:<name>`` and the string column ``fault``; the signal names
and ``meta`` are JSON in the schema metadata key ``fdikit``, and ``fdikit.sha256`` holds a
SHA-256 digest over that JSON and every column's values.  The round trip with
:meth:`Trace.load` is exact: floats bit for bit (NaN payloads and signed zeros included),
labels and names as the same Unicode strings, ``meta`` as the same JSON values.

Three layers protect a saved trace:

* the file is written atomically (:func:`fdikit.atomic.atomic_path`: a temporary file in the
  same folder, ``fsync``, rename), so a crash or an error leaves the previous file or the new
  one, never a truncated mix;
* every Parquet page carries a CRC-32 checksum that is verified on load (pyarrow ≥ 15);
* the content digest covers what the page checksums do not: page headers and the footer
  metadata (names, ``meta``), so a damaged file is refused even where a damaged byte would
  still decode.

Every malformed or damaged file makes :meth:`Trace.load` raise :class:`DataError` naming the
file and the problem; it never returns a trace that differs from the one saved.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fdikit.atomic import atomic_path
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT

__all__ = ["Trace"]

_PREFIX = {"u": "u:", "y": "y:", "x": "x:", "d": "d:"}
_BLOCKS = (("u", "controls"), ("y", "outputs"), ("x", "states"), ("d", "disturbances"))
_META_KEY = b"fdikit"
_DIGEST_KEY = b"fdikit.sha256"
_DIGEST_TAG = b"fdikit-trace-sha256-v1\x00"


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


def _names(attr: str, names) -> tuple[str, ...]:
    """Signal names of one block: non-empty UTF-8 strings, unique within the block."""
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


def _json_meta(meta) -> dict:
    if not isinstance(meta, Mapping):
        raise DataError(f"trace meta must be a dict (JSON object), got {type(meta).__name__}")
    return _json_value(meta, "meta")


def _as_path(path) -> Path:
    if not isinstance(path, str | os.PathLike):
        raise ParameterError(f"path must be a file name (str or pathlib.Path), got {type(path).__name__}")
    try:
        return Path(path)
    except TypeError as exc:  # a PathLike whose __fspath__ returns bytes
        raise ParameterError(f"path must be a file name (str or pathlib.Path): {exc}") from None


def _digest(info: bytes, columns: Sequence[tuple[str, np.ndarray]], labels: Sequence[str], codes) -> str:
    """SHA-256 over the fdikit metadata bytes, the float64 columns (little-endian) and the fault labels.

    The labels enter as their distinct values in order of first appearance (UTF-8, each with its
    length) and the per-sample index into them, which is what :func:`pyarrow.compute.dictionary_encode`
    gives for the same label sequence on save and on load.
    """
    h = hashlib.sha256(_DIGEST_TAG)
    h.update(len(info).to_bytes(8, "little"))
    h.update(info)
    for name, col in columns:
        raw = name.encode("utf-8")
        h.update(len(raw).to_bytes(8, "little"))
        h.update(raw)
        h.update(len(col).to_bytes(8, "little"))
        h.update(np.ascontiguousarray(col, dtype="<f8"))
    h.update(len(labels).to_bytes(8, "little"))
    for label in labels:
        raw = label.encode("utf-8")
        h.update(len(raw).to_bytes(8, "little"))
        h.update(raw)
    h.update(np.ascontiguousarray(codes, dtype="<i8"))
    return h.hexdigest()


def _encode_labels(arr, pa, pc) -> tuple[list[str], np.ndarray]:
    """Distinct labels (first-appearance order) and the per-sample codes of a pyarrow string array."""
    enc = pc.dictionary_encode(arr)
    return enc.dictionary.to_pylist(), enc.indices.to_numpy(zero_copy_only=False)


def _read_error(path: Path, exc: BaseException) -> str:
    msg = " ".join(str(exc).split())
    if "CRC" in msg or "checksum" in msg.lower():
        return (f"trace file {path} is corrupted: a Parquet page checksum does not match its data ({msg}); "
                "restore the file from a copy or re-create it")
    return (f"cannot read trace file {path}: it is not a Parquet file, or it is truncated or corrupted "
            f"({type(exc).__name__}: {msg})")


@dataclass(frozen=True, eq=False)
class Trace:
    """A sampled run.

    Attributes
    ----------
    t : (N,) sample times, finite and strictly increasing.
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

    Raises
    ------
    DataError
        For anything above that does not hold; the message names the field, the sample or the
        name at fault.
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

    def __post_init__(self) -> None:
        t = _numbers("trace time t", self.t)
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
            set_(self, attr, _names(attr, getattr(self, attr)))
        set_(self, "u", _block("u", self.u, n, self.controls))
        set_(self, "y", _block("y", self.y, n, self.outputs))
        set_(self, "x", _block("x", np.zeros((n, 0)) if self.x is None else self.x, n, self.states))
        set_(self, "d", _block("d", np.zeros((n, 0)) if self.d is None else self.d, n, self.disturbances))
        set_(self, "fault", _fault(self.fault, n))
        set_(self, "meta", _json_meta(self.meta))

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
    def fault_onset(self) -> float | None:
        """Time of the first faulty sample, or None for a fault-free trace."""
        idx = np.flatnonzero(self.fault != NO_FAULT)
        return float(self.t[idx[0]]) if idx.size else None

    # ------------------------------------------------------------------ export and I/O
    def to_pandas(self):
        """A DataFrame indexed by time with columns ``u:<name>``, ``y:<name>``, ``x:...``, ``d:...``, ``fault``."""
        import pandas as pd

        data = {}
        for kind, names in (("u", self.controls), ("y", self.outputs), ("x", self.states), ("d", self.disturbances)):
            block = getattr(self, kind)
            for j, nm in enumerate(names):
                data[_PREFIX[kind] + nm] = block[:, j]
        data["fault"] = self.fault
        return pd.DataFrame(data, index=pd.Index(self.t, name="t"))

    def _float_columns(self) -> list[tuple[str, np.ndarray]]:
        cols = [("t", self.t)]
        for kind, attr in _BLOCKS:
            block = getattr(self, kind)
            cols += [(_PREFIX[kind] + nm, block[:, j]) for j, nm in enumerate(getattr(self, attr))]
        return [(name, np.ascontiguousarray(col, dtype=np.float64)) for name, col in cols]

    def _info_bytes(self) -> bytes:
        info = {attr: list(getattr(self, attr)) for _, attr in _BLOCKS}
        info["meta"] = _json_meta(self.meta)  # again: meta is a mutable dict
        return json.dumps(info, ensure_ascii=True, allow_nan=True).encode("ascii")

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
        import pyarrow as pa
        import pyarrow.compute as pc
        import pyarrow.parquet as pq

        path = _as_path(path)
        info = self._info_bytes()
        columns = self._float_columns()
        try:
            labels = pa.array(self.fault.tolist(), type=pa.string())  # (from the numpy array, a NUL would cut a label)
        except (UnicodeError, pa.ArrowException):
            for k, label in enumerate(self.fault.tolist()):
                try:
                    label.encode("utf-8")
                except UnicodeEncodeError:
                    raise DataError(
                        f"cannot save the trace to {path}: fault label at sample {k} ({label!r}) is not valid UTF-8 "
                        "text (it holds a lone surrogate)"
                    ) from None
            raise
        table = pa.Table.from_arrays(
            [pa.array(col, type=pa.float64()) for _, col in columns] + [labels],
            names=[name for name, _ in columns] + ["fault"],
            metadata={_META_KEY: info, _DIGEST_KEY: _digest(info, columns, *_encode_labels(labels, pa, pc)).encode()},
        )
        with atomic_path(path, suffix=".parquet") as tmp:  # its own failures are DataErrors naming the file
            try:
                pq.write_table(table, tmp, write_page_checksum=True)
            except (OSError, pa.ArrowException) as exc:
                raise DataError(f"cannot write trace file {path}: {exc}") from exc
        return path

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
        import pyarrow as pa
        import pyarrow.compute as pc
        import pyarrow.parquet as pq

        path = _as_path(path)
        if not isinstance(verify, bool):
            raise ParameterError(f"verify must be True or False, got {verify!r}")
        try:
            if path.is_dir():
                raise DataError(f"cannot read trace file {path}: it is a folder; give the .parquet file in it")
            if not path.exists():
                raise DataError(f"no trace file at {path}")
            if not path.is_file():
                raise DataError(f"cannot read trace file {path}: it is not a regular file (a pipe or a device?)")
            with open(path, "rb"):
                pass
            size = path.stat().st_size
        except (OSError, ValueError) as exc:
            raise DataError(f"cannot read trace file {path}: {getattr(exc, 'strerror', None) or exc}") from None
        if size == 0:
            raise DataError(f"trace file {path} is empty (0 bytes): it was never written completely; re-create it")
        try:
            table = pq.ParquetFile(path, page_checksum_verification=True).read()
        except Exception as exc:  # noqa: BLE001 - whatever a damaged file makes pyarrow raise
            raise DataError(_read_error(path, exc)) from exc

        md = table.schema.metadata or {}
        raw = md.get(_META_KEY)
        if raw is None:
            raise DataError(f"{path} is a Parquet file but not an fdikit trace (no 'fdikit' schema metadata)")
        names = cls._names_from_info(path, raw)
        meta = names.pop("meta")

        # ---- columns: exactly t, the listed signals and fault; float64 signals, string labels, no nulls
        present = table.schema.names
        dup = sorted(nm for nm, c in Counter(present).items() if c > 1)
        if dup:
            raise DataError(f"{path} has duplicate columns {dup}; a trace file holds each signal once")
        expected = ["t"] + [_PREFIX[k] + nm for k, attr in _BLOCKS for nm in names[attr]] + ["fault"]
        missing = [c for c in expected if c not in set(present)]
        if missing:
            raise DataError(f"{path} is missing the column(s) {missing} that its fdikit metadata lists")
        unexpected = [c for c in present if c not in set(expected)]
        if unexpected:
            raise DataError(f"{path} has unexpected column(s) {unexpected} that its fdikit metadata does not list")
        for c in expected[:-1]:
            if table.schema.field(c).type != pa.float64():
                raise DataError(f"{path}: column {c!r} has type {table.schema.field(c).type}; trace signals must be "
                                "float64 (double)")
        cls._check_label_column(path, table.column("fault"), pa, pc)

        # ---- integrity: the content digest must be there (unless verify=False) and match
        stored = md.get(_DIGEST_KEY)
        if stored is None and verify:
            raise DataError(
                f"{path} has no content digest ('fdikit.sha256' metadata): it was not written by Trace.save, "
                "or its metadata is damaged. Trace.load(path, verify=False) reads it without that check"
            )
        arrays: dict[str, np.ndarray] = {}
        for c in expected[:-1]:
            col = table.column(c)
            if col.null_count and stored is not None:
                first = int(np.flatnonzero(pc.is_null(col).to_numpy(zero_copy_only=False))[0])
                raise DataError(
                    f"trace file {path} is corrupted: column {c!r} has {col.null_count} null value(s), the first at "
                    f"sample {first}; Trace.save writes NaN, never null"
                )
            # nulls (only in files without a digest: fdikit before the digest stored NaN as null) read as NaN
            arrays[c] = np.asarray(col.to_numpy(), dtype=float)
        fault, labels, codes = cls._labels_from(path, table.column("fault"), pa, pc)
        if stored is not None and stored != _digest(raw, list(arrays.items()), labels, codes).encode("ascii"):
            raise DataError(
                f"trace file {path} is corrupted: its content digest (SHA-256 over the metadata and every column) "
                "does not match the stored one, so the file changed after it was written; restore it from a copy"
            )

        n = len(fault)
        blocks = {}
        for kind, attr in _BLOCKS:
            cols = [arrays[_PREFIX[kind] + nm] for nm in names[attr]]
            blocks[kind] = np.column_stack(cols) if cols else np.zeros((n, 0))
        try:
            return cls(t=np.array(arrays["t"]), u=blocks["u"], y=blocks["y"], x=blocks["x"], d=blocks["d"], fault=fault,
                       meta=meta, **names)
        except DataError as exc:
            raise DataError(f"trace file {path}: {exc}") from None

    @staticmethod
    def _names_from_info(path: Path, raw: bytes) -> dict:
        """The signal names and meta from the 'fdikit' metadata, checked."""
        try:
            info = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError:
            raise DataError(f"{path}: its 'fdikit' metadata is not UTF-8 text; the file is damaged") from None
        except ValueError as exc:
            raise DataError(f"{path}: its 'fdikit' metadata is not valid JSON ({exc}); the file is damaged") from None
        if not isinstance(info, dict):
            raise DataError(f"{path}: its 'fdikit' metadata must be a JSON object, got {type(info).__name__}")
        out = {}
        for _, attr in _BLOCKS:
            if attr not in info:
                raise DataError(f"{path}: the {attr!r} list is missing from its 'fdikit' metadata")
            try:
                out[attr] = _names(attr, info[attr])
            except DataError as exc:
                raise DataError(f"{path}: {exc}") from None
        if "meta" not in info:
            raise DataError(f"{path}: the 'meta' dict is missing from its 'fdikit' metadata")
        if not isinstance(info["meta"], dict):
            raise DataError(f"{path}: 'meta' in its 'fdikit' metadata is a {type(info['meta']).__name__}, not a dict")
        out["meta"] = info["meta"]
        return out

    @staticmethod
    def _check_label_column(path: Path, col, pa, pc) -> None:
        """The 'fault' column must hold strings and no null."""
        typ = col.type
        value_type = typ.value_type if pa.types.is_dictionary(typ) else typ
        is_text = pa.types.is_string(value_type) or pa.types.is_large_string(value_type) or (
            hasattr(pa.types, "is_string_view") and pa.types.is_string_view(value_type))
        if not is_text:
            raise DataError(f"{path}: column 'fault' has type {typ}; fault labels must be strings")
        if col.null_count:
            first = int(np.flatnonzero(pc.is_null(col).to_numpy(zero_copy_only=False))[0])
            raise DataError(
                f"{path}: column 'fault' has a null label at sample {first} ({col.null_count} nulls in all); "
                f"every sample needs a label ({NO_FAULT!r} where healthy)"
            )

    @staticmethod
    def _labels_from(path: Path, col, pa, pc) -> tuple[np.ndarray, list[str], np.ndarray]:
        """The (checked) 'fault' column as a numpy str array, with its distinct labels and codes."""
        arr = col.combine_chunks()
        if pa.types.is_dictionary(arr.type):
            arr = arr.cast(arr.type.value_type)
        labels, codes = _encode_labels(arr, pa, pc)
        bad = [s for s in labels if s.endswith("\x00")]
        if bad:
            raise DataError(f"{path}: the label {bad[0]!r} in column 'fault' ends with a NUL character")
        fault = np.asarray(labels, dtype=str)[codes] if labels else np.full(0, NO_FAULT)
        return fault, labels, codes

    def __repr__(self) -> str:
        span = f"{self.t[0]:g}..{self.t[-1]:g} s" if len(self) else "empty"
        return (
            f"Trace({len(self)} samples, {span}, u={len(self.controls)}, y={len(self.outputs)}, "
            f"x={len(self.states)}, faults={sorted(set(self.fault.tolist()) - {NO_FAULT})})"
        )
