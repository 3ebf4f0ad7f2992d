"""The Parquet file format of a :class:`~fdikit.trace.Trace`: writing, the content digest, loading.

An internal module: use :meth:`Trace.save <fdikit.trace.Trace.save>` and
:meth:`Trace.load <fdikit.trace.Trace.load>`, which call :func:`write_trace` and
:func:`read_trace`.

Columns
-------
One Parquet file holds, in this order, the float64 (double) columns ``t``, ``u:<name>`` for
each control, ``y:<name>`` for each output, ``x:<name>`` for each state, ``d:<name>`` for each
disturbance (:data:`COLUMN_PREFIX`), the string column ``fault`` with one label per sample and
the boolean column ``valid`` (:attr:`Trace.valid <fdikit.trace.Trace.valid>`).  Floats are
stored as they are: NaN (with its payload), infinities and signed zeros, never null.  A file
without the ``valid`` column (written before it existed) loads with every sample valid.

Schema metadata
---------------
``fdikit``
    ASCII JSON object with the lists ``controls``, ``outputs``, ``states``, ``disturbances``
    (the signal names, in column order) and the dict ``meta``.
``fdikit.sha256``
    Hex SHA-256 content digest: over a version tag, the ``fdikit`` bytes, every float column
    (its name, its length and its values as little-endian float64) and the fault labels (their
    distinct values in order of first appearance, UTF-8 with lengths, and the per-sample index
    into them as little-endian int64), then, when the file has the ``valid`` column, the name
    ``valid``, its length and its flags as one byte each (0 or 1).  Every piece is preceded by
    its length.

Integrity
---------
* The file is written atomically (:func:`fdikit.atomic.atomic_path`: a temporary file in the
  same folder, ``fsync``, rename), so a crash or an error leaves the previous file or the new
  one, never a truncated mix.
* Every Parquet page carries a CRC-32 checksum, written on save and verified on load
  (pyarrow ≥ 15).
* The content digest covers what the page checksums do not: page headers and the footer
  metadata (names, ``meta``), so a damaged file is refused even where a damaged byte would
  still decode.

What loading verifies
---------------------
:func:`read_trace` raises :class:`~fdikit.errors.DataError` naming the file and the problem for
a folder, a missing, unreadable, non-regular or empty file; a file pyarrow cannot read (not
Parquet, truncated, a page checksum that does not match); no ``fdikit`` metadata, or metadata
that is not UTF-8 JSON object text, lacks a names list or ``meta``, or holds bad names;
duplicate, missing or unexpected columns, a signal column that is not float64, a ``fault``
column that is not text or holds a null or a label ending with NUL; a ``valid`` column that
is not boolean or holds a null; a missing digest (unless
``verify=False``); a null in a signal column of a file with a digest; a digest that does not
match; and anything the :class:`~fdikit.trace.Trace` constructor refuses.  Files without a
digest (read only with ``verify=False``) may hold nulls, read as NaN.  The round trip is exact:
floats bit for bit, labels and names as the same Unicode strings, ``meta`` as the same JSON
values.

Example
-------
>>> import tempfile
>>> import pyarrow.parquet as pq
>>> from fdikit.trace import Trace
>>> trace = Trace(t=[0.0, 0.1], u=[[1.0], [2.0]], y=[[0.5], [float("nan")]], controls=["u1"], outputs=["y1"],
...               meta={"seed": 1})
>>> with tempfile.TemporaryDirectory() as folder:
...     path = write_trace(trace, Path(folder) / "run.parquet")
...     schema = pq.read_schema(path)
...     back = read_trace(path)
>>> schema.names, sorted(schema.metadata)
(['t', 'u:u1', 'y:y1', 'fault', 'valid'], [b'fdikit', b'fdikit.sha256'])
>>> back.y.tolist(), back.fault.tolist(), back.meta
([[0.5], [nan]], ['none', 'none'], {'seed': 1})
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fdikit.atomic import atomic_path
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT

if TYPE_CHECKING:
    from fdikit.trace import Trace

__all__ = ["COLUMN_PREFIX", "read_trace", "write_trace"]

COLUMN_PREFIX = {"u": "u:", "y": "y:", "x": "x:", "d": "d:"}
"""Column-name prefix of each signal kind (also the column names of :meth:`Trace.to_pandas`)."""

_BLOCKS = (("u", "controls"), ("y", "outputs"), ("x", "states"), ("d", "disturbances"))
_META_KEY = b"fdikit"
_DIGEST_KEY = b"fdikit.sha256"
_DIGEST_TAG = b"fdikit-trace-sha256-v1\x00"
_VALID = "valid"


def _as_path(path) -> Path:
    if not isinstance(path, str | os.PathLike):
        raise ParameterError(f"path must be a file name (str or pathlib.Path), got {type(path).__name__}")
    try:
        return Path(path)
    except TypeError as exc:  # a PathLike whose __fspath__ returns bytes
        raise ParameterError(f"path must be a file name (str or pathlib.Path): {exc}") from None


def _digest(info: bytes, columns: Sequence[tuple[str, np.ndarray]], labels: Sequence[str], codes,
            valid: np.ndarray | None = None) -> str:
    """SHA-256 over the fdikit metadata bytes, the float64 columns (little-endian), the fault labels and the flags.

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
    if valid is not None:  # absent from files written before the valid flags: their digest stays as it was
        h.update(len(_VALID).to_bytes(8, "little"))
        h.update(_VALID.encode("ascii"))
        h.update(len(valid).to_bytes(8, "little"))
        h.update(np.ascontiguousarray(valid, dtype=np.uint8))
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


# ---------------------------------------------------------------------- writing
def _float_columns(trace: Trace) -> list[tuple[str, np.ndarray]]:
    cols = [("t", trace.t)]
    for kind, attr in _BLOCKS:
        block = getattr(trace, kind)
        cols += [(COLUMN_PREFIX[kind] + nm, block[:, j]) for j, nm in enumerate(getattr(trace, attr))]
    return [(name, np.ascontiguousarray(col, dtype=np.float64)) for name, col in cols]


def _info_bytes(trace: Trace) -> bytes:
    from fdikit.trace import json_meta

    info = {attr: list(getattr(trace, attr)) for _, attr in _BLOCKS}
    info["meta"] = json_meta(trace.meta)  # again: meta is a mutable dict
    return json.dumps(info, ensure_ascii=True, allow_nan=True).encode("ascii")


def write_trace(trace: Trace, path: str | Path) -> Path:
    """Write ``trace`` to the Parquet file ``path`` atomically; the implementation of :meth:`Trace.save`.

    Parameters
    ----------
    trace : Trace
        The run to store (every field, its metadata and the per-sample fault labels).
    path : str or Path
        Destination ``.parquet`` file; written through :func:`fdikit.atomic.atomic_path`, with page checksums and
        the content digest of the module docstring.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    DataError
        When a fault label is not valid UTF-8 text, or the file cannot be written (the previous file is then
        unchanged).

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> from fdikit.trace import Trace
    >>> tr = Trace(t=np.arange(4) * 0.5, u=np.zeros((4, 0)), y=np.arange(4.0)[:, None], controls=[], outputs=["y"])
    >>> path = write_trace(tr, pathlib.Path(tempfile.mkdtemp()) / "run.parquet")
    >>> read_trace(path).y[:, 0].tolist()
    [0.0, 1.0, 2.0, 3.0]
    """
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    path = _as_path(path)
    info = _info_bytes(trace)
    columns = _float_columns(trace)
    try:
        labels = pa.array(trace.fault.tolist(), type=pa.string())  # (from the numpy array, a NUL would cut a label)
    except (UnicodeError, pa.ArrowException):
        for k, label in enumerate(trace.fault.tolist()):
            try:
                label.encode("utf-8")
            except UnicodeEncodeError:
                raise DataError(
                    f"cannot save the trace to {path}: fault label at sample {k} ({label!r}) is not valid UTF-8 "
                    "text (it holds a lone surrogate)"
                ) from None
        raise
    valid = np.ascontiguousarray(trace.valid, dtype=bool)
    digest = _digest(info, columns, *_encode_labels(labels, pa, pc), valid)
    table = pa.Table.from_arrays(
        [pa.array(col, type=pa.float64()) for _, col in columns] + [labels, pa.array(valid, type=pa.bool_())],
        names=[name for name, _ in columns] + ["fault", _VALID],
        metadata={_META_KEY: info, _DIGEST_KEY: digest.encode()},
    )
    with atomic_path(path, suffix=".parquet") as tmp:  # its own failures are DataErrors naming the file
        try:
            pq.write_table(table, tmp, write_page_checksum=True)
        except (OSError, pa.ArrowException) as exc:
            raise DataError(f"cannot write trace file {path}: {exc}") from exc
    return path


# ---------------------------------------------------------------------- loading
def read_trace(path: str | Path, *, verify: bool = True, cls: type[Trace] | None = None) -> Trace:
    """Read and verify the trace file ``path``; the implementation of :meth:`Trace.load`.

    Parameters
    ----------
    path : str or Path
        A ``.parquet`` file written by :func:`write_trace`.
    verify : bool, optional
        Check the page checksums and the content digest (default); ``False`` skips the digest (faster, for files
        known to be intact).
    cls : type, optional
        The class to build (default :class:`~fdikit.trace.Trace`).

    Returns
    -------
    Trace
        The stored run, bit for bit.

    Raises
    ------
    DataError
        When the file is missing, not a regular file, empty, truncated, not a trace file, or its content does not
        match its checksums or digest (the message says which).
    ParameterError
        When ``verify`` is not a bool.

    Examples
    --------
    >>> try:
    ...     read_trace("/nonexistent/run.parquet")
    ... except DataError as exc:
    ...     print(exc)
    no trace file at /nonexistent/run.parquet
    """
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    if cls is None:
        from fdikit.trace import Trace

        cls = Trace
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
    except DataError:
        raise
    except (OSError, ValueError) as exc:  # unreadable (permissions), or a path the OS refuses (NUL byte)
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
    names = _names_from_info(path, raw)
    meta = names.pop("meta")

    # ---- columns: exactly t, the listed signals and fault; float64 signals, string labels, no nulls
    present = table.schema.names
    dup = sorted(nm for nm, c in Counter(present).items() if c > 1)
    if dup:
        raise DataError(f"{path} has duplicate columns {dup}; a trace file holds each signal once")
    expected = ["t"] + [COLUMN_PREFIX[k] + nm for k, attr in _BLOCKS for nm in names[attr]] + ["fault"]
    missing = [c for c in expected if c not in set(present)]
    if missing:
        raise DataError(f"{path} is missing the column(s) {missing} that its fdikit metadata lists")
    unexpected = [c for c in present if c not in set(expected) | {_VALID}]
    if unexpected:
        raise DataError(f"{path} has unexpected column(s) {unexpected} that its fdikit metadata does not list")
    for c in expected[:-1]:
        if table.schema.field(c).type != pa.float64():
            raise DataError(f"{path}: column {c!r} has type {table.schema.field(c).type}; trace signals must be "
                            "float64 (double)")
    _check_label_column(path, table.column("fault"), pa, pc)
    valid = _valid_from(path, table.column(_VALID), pa, pc) if _VALID in present else None

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
    fault, labels, codes = _labels_from(path, table.column("fault"), pa, pc)
    if stored is not None and stored != _digest(raw, list(arrays.items()), labels, codes, valid).encode("ascii"):
        raise DataError(
            f"trace file {path} is corrupted: its content digest (SHA-256 over the metadata and every column) "
            "does not match the stored one, so the file changed after it was written; restore it from a copy"
        )

    n = len(fault)
    blocks = {}
    for kind, attr in _BLOCKS:
        cols = [arrays[COLUMN_PREFIX[kind] + nm] for nm in names[attr]]
        blocks[kind] = np.column_stack(cols) if cols else np.zeros((n, 0))
    try:
        return cls(t=np.array(arrays["t"]), u=blocks["u"], y=blocks["y"], x=blocks["x"], d=blocks["d"], fault=fault,
                   meta=meta, valid=valid, **names)
    except DataError as exc:
        raise DataError(f"trace file {path}: {exc}") from None


def _names_from_info(path: Path, raw: bytes) -> dict:
    """The signal names and meta from the 'fdikit' metadata, checked."""
    from fdikit.trace import check_names

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
            out[attr] = check_names(attr, info[attr])
        except DataError as exc:
            raise DataError(f"{path}: {exc}") from None
    if "meta" not in info:
        raise DataError(f"{path}: the 'meta' dict is missing from its 'fdikit' metadata")
    if not isinstance(info["meta"], dict):
        raise DataError(f"{path}: 'meta' in its 'fdikit' metadata is a {type(info['meta']).__name__}, not a dict")
    out["meta"] = info["meta"]
    return out


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


def _valid_from(path: Path, col, pa, pc) -> np.ndarray:
    """The (checked) 'valid' column: boolean, no null."""
    if not pa.types.is_boolean(col.type):
        raise DataError(f"{path}: column 'valid' has type {col.type}; the validity flags must be booleans")
    if col.null_count:
        first = int(np.flatnonzero(pc.is_null(col).to_numpy(zero_copy_only=False))[0])
        raise DataError(
            f"{path}: column 'valid' has a null flag at sample {first} ({col.null_count} nulls in all); every "
            "sample needs True or False"
        )
    return np.asarray(col.to_numpy(zero_copy_only=False), dtype=bool)


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
