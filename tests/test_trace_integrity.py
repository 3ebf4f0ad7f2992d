"""Trace files: atomic saves, page checksums, the content digest, corrupted and truncated files.

The corruption tests locate every page of a saved file from the column-chunk metadata and the
Thrift page headers (parsed here independently of pyarrow), damage one page at a time with a
seeded generator and require :meth:`Trace.load` to refuse the file with a ``DataError``.
"""

from __future__ import annotations

import errno
import hashlib
import json
from dataclasses import dataclass, replace

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from fdikit.errors import DataError
from fdikit.trace import Trace

SEED = 20261201


def _trace(n: int = 400, seed: int = 3) -> Trace:
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    y = rng.standard_normal((n, 3))
    y[17, 1] = np.nan
    return Trace(
        t=0.01 * k, u=np.column_stack([np.sin(0.1 * k), np.round(rng.random(n), 1)]), y=y,
        x=rng.standard_normal((n, 2)), d=np.zeros((n, 1)), controls=["steer", "throttle"],
        outputs=["yaw_rate", "speed", "lateral_error"], states=["v", "r"], disturbances=["gust"],
        fault=np.select([k >= 300, k >= 150], ["steer_bias+speed_scale", "steer_bias"], "none"),
        meta={"plant": "toy", "seed": seed, "faults": ["Bias('steer', 0.1)"]},
        valid=(k % 37) != 5,
    )


def _same(a: Trace, b: Trace) -> bool:
    """Bitwise equality of every array, equal names, labels and meta."""
    return (
        all(getattr(a, k).shape == getattr(b, k).shape
            and np.array_equal(getattr(a, k).view(np.uint64), getattr(b, k).view(np.uint64)) for k in "tuyxd")
        and np.array_equal(a.fault, b.fault) and a.meta == b.meta and np.array_equal(a.valid, b.valid)
        and all(getattr(a, k) == getattr(b, k) for k in ("controls", "outputs", "states", "disturbances"))
    )


# ---------------------------------------------------------------------- Thrift compact protocol (page headers)
def _varint(buf: bytes, pos: int) -> tuple[int, int]:
    shift = out = 0
    while True:
        b = buf[pos]
        pos += 1
        out |= (b & 0x7F) << shift
        if not b & 0x80:
            return out, pos
        shift += 7


def _zigzag(v: int) -> int:
    return (v >> 1) ^ -(v & 1)


def _skip(buf: bytes, pos: int, typ: int) -> int:
    if typ in (1, 2):  # bool inside a struct: the value is the type
        return pos
    if typ == 3:
        return pos + 1
    if typ in (4, 5, 6):
        return _varint(buf, pos)[1]
    if typ == 7:
        return pos + 8
    if typ == 8:
        size, pos = _varint(buf, pos)
        return pos + size
    if typ in (9, 10):
        head = buf[pos]
        pos += 1
        size, elem = head >> 4, head & 0x0F
        if size == 15:
            size, pos = _varint(buf, pos)
        for _ in range(size):
            pos = pos + 1 if elem in (1, 2) else _skip(buf, pos, elem)
        return pos
    if typ == 11:
        size, pos = _varint(buf, pos)
        if size:
            kv = buf[pos]
            pos += 1
            for _ in range(size):
                pos = _skip(buf, _skip(buf, pos, kv >> 4), kv & 0x0F)
        return pos
    if typ == 12:
        return _struct(buf, pos)[1]
    raise ValueError(f"unknown thrift compact type {typ}")


def _struct(buf: bytes, pos: int) -> tuple[dict[int, int], int]:
    """Parse one struct; returns its integer fields by id and the position after it."""
    fields: dict[int, int] = {}
    last = 0
    while True:
        head = buf[pos]
        pos += 1
        if head == 0:
            return fields, pos
        delta, typ = head >> 4, head & 0x0F
        if delta:
            fid = last + delta
        else:
            raw, pos = _varint(buf, pos)
            fid = _zigzag(raw)
        last = fid
        if typ in (4, 5, 6):
            raw, pos = _varint(buf, pos)
            fields[fid] = _zigzag(raw)
        else:
            pos = _skip(buf, pos, typ)


@dataclass(frozen=True)
class Page:
    column: str
    kind: str  # "data", "dictionary" or "data_v2"
    header: int  # file offset of the page header
    body: int  # file offset of the (compressed) page data
    end: int
    has_crc: bool


_KINDS = {0: "data", 2: "dictionary", 3: "data_v2"}


def pages(path) -> list[Page]:
    """Every page of every column chunk of a Parquet file."""
    buf = path.read_bytes()
    md = pq.ParquetFile(path).metadata
    out = []
    for g in range(md.num_row_groups):
        for c in range(md.num_columns):
            col = md.row_group(g).column(c)
            start = col.dictionary_page_offset if col.has_dictionary_page else col.data_page_offset
            pos, end = start, start + col.total_compressed_size
            while pos < end:
                fields, body = _struct(buf, pos)
                stop = body + fields[3]  # compressed_page_size
                kind = _KINDS.get(fields[1], str(fields[1]))
                out.append(Page(col.path_in_schema, kind, pos, body, stop, 4 in fields))
                pos = stop
            assert pos == end, "page headers do not add up to the column chunk"
    return out


def _load_outcome(path, original: Trace) -> str:
    try:
        back = Trace.load(path)
    except DataError as exc:
        msg = str(exc)
        assert str(path) in msg, msg
        return "checksum" if "checksum" in msg else "digest" if "digest" in msg else "refused"
    return "identical" if _same(back, original) else "silent"


# ---------------------------------------------------------------------- what save writes
def test_every_page_has_a_checksum_and_the_file_a_digest(tmp_path):
    path = _trace().save(tmp_path / "run.parquet")
    found = pages(path)
    kinds = {p.kind for p in found}
    assert {"data", "dictionary"} <= kinds
    assert {p.column for p in found} == set(pq.ParquetFile(path).schema_arrow.names)
    assert all(p.has_crc for p in found)
    md = pq.ParquetFile(path).schema_arrow.metadata
    assert len(md[b"fdikit.sha256"]) == 64
    assert json.loads(md[b"fdikit"])["outputs"] == ["yaw_rate", "speed", "lateral_error"]


def test_empty_and_single_sample_traces_round_trip(tmp_path):
    for n in (0, 1):
        tr = Trace(t=np.arange(n) + 0.5, u=np.zeros((n, 1)), y=np.full((n, 1), np.nan), controls=["u"],
                   outputs=["y"], fault=np.full(n, "f"), meta={"n": n})
        assert _same(Trace.load(tr.save(tmp_path / f"n{n}.parquet")), tr)


# ---------------------------------------------------------------------- corruption and truncation
def test_100_random_single_page_corruptions_are_all_refused(tmp_path):
    """1 to 200 random bytes overwritten inside one data or dictionary page: 100 DataErrors, 0 silent loads."""
    tr = _trace()
    good = tr.save(tmp_path / "good.parquet").read_bytes()
    found = pages(tmp_path / "good.parquet")
    rng = np.random.default_rng(SEED)
    path = tmp_path / "bad.parquet"
    outcomes = []
    for _ in range(100):
        page = found[rng.integers(len(found))]
        size = page.end - page.body
        where = page.body + rng.choice(size, size=int(rng.integers(1, min(size, 200) + 1)), replace=False)
        data = np.frombuffer(good, dtype=np.uint8).copy()
        data[where] ^= rng.integers(1, 256, size=where.size, dtype=np.uint8)  # every chosen byte changes
        path.write_bytes(data.tobytes())
        outcomes.append(_load_outcome(path, tr))
    assert outcomes.count("silent") == 0 and outcomes.count("identical") == 0
    assert len(outcomes) == 100 and all(o in ("checksum", "digest", "refused") for o in outcomes)


def test_random_corruptions_anywhere_never_load_a_different_trace(tmp_path):
    """Bytes changed anywhere in the file, page headers and footer included: refused or (harmless) identical."""
    tr = _trace()
    good = tr.save(tmp_path / "good.parquet").read_bytes()
    rng = np.random.default_rng(SEED + 1)
    path = tmp_path / "bad.parquet"
    outcomes = []
    for _ in range(150):
        data = np.frombuffer(good, dtype=np.uint8).copy()
        at = int(rng.integers(len(good)))
        span = data[at: at + int(rng.integers(1, 9))]
        span ^= rng.integers(1, 256, size=span.size, dtype=np.uint8)
        path.write_bytes(data.tobytes())
        outcomes.append(_load_outcome(path, tr))
    # "identical": the damaged bytes were ones no reader uses (page statistics, for one): the trace is intact
    assert outcomes.count("silent") == 0, outcomes
    assert len(outcomes) == 150 and outcomes.count("identical") < len(outcomes)


def test_footer_corruptions_are_caught_by_the_digest(tmp_path):
    """The footer (names, meta, schema) has no page checksum: the content digest refuses a changed one."""
    tr = _trace()
    path = tr.save(tmp_path / "run.parquet")
    table = pq.read_table(path)
    md = dict(table.schema.metadata)
    for edit in ("meta", "names"):
        info = json.loads(md[b"fdikit"])
        if edit == "meta":
            info["meta"]["seed"] += 1
        else:
            info["outputs"][0], info["outputs"][1] = info["outputs"][1], info["outputs"][0]
        bad = {**md, b"fdikit": json.dumps(info).encode()}
        pq.write_table(table.replace_schema_metadata(bad), path, write_page_checksum=True)
        with pytest.raises(DataError, match="content digest"):
            Trace.load(path)


def test_a_rewritten_file_with_one_changed_value_is_refused(tmp_path):
    """Valid pages (fresh checksums) around one changed sample: only the digest can tell, and does."""
    tr = _trace()
    path = tr.save(tmp_path / "run.parquet")
    table = pq.read_table(path)
    y = table.column("y:speed").to_numpy().copy()
    y[200] = np.nextafter(y[200], np.inf)  # one ulp
    table = table.set_column(table.schema.get_field_index("y:speed"), "y:speed", pa.array(y))
    pq.write_table(table, path, write_page_checksum=True)
    with pytest.raises(DataError, match=r"run\.parquet is corrupted: its content digest"):
        Trace.load(path)


def test_truncation_at_random_lengths_is_refused(tmp_path):
    good = _trace().save(tmp_path / "good.parquet").read_bytes()
    rng = np.random.default_rng(SEED + 2)
    lengths = sorted({0, 1, 4, 8, len(good) - 8, len(good) - 4, len(good) - 1,
                      *rng.integers(1, len(good), size=60).tolist()})
    path = tmp_path / "cut.parquet"
    for n in lengths:
        path.write_bytes(good[:n])
        with pytest.raises(DataError, match="cut.parquet") as err:
            Trace.load(path)
        assert ("empty" if n == 0 else "truncated") in str(err.value), (n, str(err.value))


# ---------------------------------------------------------------------- atomic saves
def _listing(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("exc", [OSError(errno.ENOSPC, "No space left on device"), pa.ArrowIOError("write failed"),
                                 KeyboardInterrupt()])
def test_a_failure_while_writing_keeps_the_old_file(tmp_path, monkeypatch, exc):
    old = _trace(seed=1)
    path = old.save(tmp_path / "run.parquet")
    before = path.read_bytes()
    real = pq.write_table

    def half_then_fail(table, where, **kw):
        real(table, where, **kw)
        with open(where, "r+b") as fh:  # a partial file on disk, as a crash mid-write leaves it
            fh.truncate(len(before) // 2)
        raise exc

    monkeypatch.setattr(pq, "write_table", half_then_fail)
    with pytest.raises(DataError if isinstance(exc, Exception) else type(exc)) as err:
        _trace(seed=2).save(path)
    if isinstance(exc, Exception):
        assert "run.parquet" in str(err.value) and "cannot write" in str(err.value)
    assert path.read_bytes() == before
    assert _listing(tmp_path) == ["run.parquet"]  # no temporary file left behind
    monkeypatch.undo()
    assert _same(Trace.load(path), old)


def test_a_failed_rename_keeps_the_old_file(tmp_path, monkeypatch):
    import os

    old = _trace(seed=1)
    path = old.save(tmp_path / "run.parquet")
    before = path.read_bytes()

    def no_replace(src, dst):
        raise OSError(errno.EXDEV, "Invalid cross-device link")

    monkeypatch.setattr(os, "replace", no_replace)
    with pytest.raises(DataError, match=r"cannot write .*run\.parquet.*cross-device"):
        _trace(seed=2).save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before and _listing(tmp_path) == ["run.parquet"]


def test_a_failed_first_write_leaves_no_file(tmp_path, monkeypatch):
    def fail(table, where, **kw):
        raise OSError(errno.EIO, "I/O error")

    monkeypatch.setattr(pq, "write_table", fail)
    with pytest.raises(DataError, match="cannot write trace file"):
        _trace().save(tmp_path / "new" / "run.parquet")
    assert _listing(tmp_path / "new") == []


def test_save_replaces_an_existing_file_with_the_new_trace(tmp_path):
    path = _trace(seed=1).save(tmp_path / "run.parquet")
    new = _trace(seed=2)
    new.save(path)
    assert _same(Trace.load(path), new) and _listing(tmp_path) == ["run.parquet"]


# ---------------------------------------------------------------------- files without a digest
def _old_format(tr: Trace, path) -> None:
    """The layout of fdikit before the digest: pandas columns and the 'fdikit' JSON, no checksums, no valid flags."""
    table = pa.Table.from_pandas(tr.to_pandas().drop(columns="valid").reset_index(), preserve_index=False)
    info = {"controls": list(tr.controls), "outputs": list(tr.outputs), "states": list(tr.states),
            "disturbances": list(tr.disturbances), "meta": tr.meta}
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), b"fdikit": json.dumps(info).encode()})
    pq.write_table(table, path)


def test_a_file_without_digest_needs_verify_false(tmp_path):
    tr = _trace()
    path = tmp_path / "old.parquet"
    _old_format(tr, path)
    with pytest.raises(DataError, match=r"old\.parquet has no content digest.*verify=False"):
        Trace.load(path)
    back = Trace.load(path, verify=False)  # the old layout stored NaN as null: it reads as NaN again
    assert np.isnan(back.y[17, 1]) and _same(back, replace(tr, valid=None))
    assert back.valid.all()


def _v1_digest(info: bytes, table: pa.Table) -> str:
    """The content digest as the module docstring specifies it, for a file without the 'valid' column."""
    h = hashlib.sha256(b"fdikit-trace-sha256-v1\x00")
    h.update(len(info).to_bytes(8, "little") + info)
    for name in table.schema.names[:-1]:
        col = table.column(name).to_numpy()
        h.update(len(name.encode()).to_bytes(8, "little") + name.encode())
        h.update(len(col).to_bytes(8, "little") + np.ascontiguousarray(col, dtype="<f8").tobytes())
    labels = table.column("fault").to_pylist()
    distinct = list(dict.fromkeys(labels))
    h.update(len(distinct).to_bytes(8, "little"))
    for label in distinct:
        h.update(len(label.encode()).to_bytes(8, "little") + label.encode())
    h.update(np.array([distinct.index(x) for x in labels], dtype="<i8").tobytes())
    return h.hexdigest()


def test_a_file_with_digest_but_without_valid_flags_loads_all_valid(tmp_path):
    """Files saved before the 'valid' column existed: same digest (v1) without it; they load with every sample valid."""
    tr = _trace()
    path = tr.save(tmp_path / "new.parquet")
    table = pq.read_table(path)
    old = table.drop_columns(["valid"])
    info = table.schema.metadata[b"fdikit"]
    md = {b"fdikit": info, b"fdikit.sha256": _v1_digest(info, old).encode()}
    pq.write_table(old.replace_schema_metadata(md), tmp_path / "v1.parquet", write_page_checksum=True)
    back = Trace.load(tmp_path / "v1.parquet")  # verify=True: the v1 digest is checked and matches
    assert back.valid.dtype == bool and back.valid.all() and _same(back, replace(tr, valid=None))
    # dropping the column from a file saved WITH flags breaks its digest: never a silent "all valid"
    pq.write_table(old.replace_schema_metadata(table.schema.metadata), tmp_path / "cut.parquet")
    with pytest.raises(DataError, match="content digest"):
        Trace.load(tmp_path / "cut.parquet")


def test_valid_flags_round_trip_and_a_changed_flag_is_refused(tmp_path):
    tr = _trace()
    assert (~tr.valid).sum() == 11  # k % 37 == 5 for k in 0..399: 5, 42, ..., 375 -> 11 samples
    path = tr.save(tmp_path / "run.parquet")
    back = Trace.load(path)
    assert _same(back, tr) and np.array_equal(back.valid, tr.valid)
    table = pq.read_table(path)
    flipped = tr.valid.copy()
    flipped[0] = not flipped[0]
    bad = table.set_column(table.schema.get_field_index("valid"), "valid", pa.array(flipped))
    pq.write_table(bad, tmp_path / "bad.parquet")
    with pytest.raises(DataError, match="content digest"):
        Trace.load(tmp_path / "bad.parquet")
    ints = table.set_column(table.schema.get_field_index("valid"), "valid", pa.array(flipped.astype(np.int8)))
    pq.write_table(ints, tmp_path / "ints.parquet")
    with pytest.raises(DataError, match="column 'valid' has type int8"):
        Trace.load(tmp_path / "ints.parquet")
    nulls = table.set_column(table.schema.get_field_index("valid"), "valid",
                             pa.array([None] + tr.valid[1:].tolist(), type=pa.bool_()))
    pq.write_table(nulls, tmp_path / "nulls.parquet")
    with pytest.raises(DataError, match="null flag at sample 0"):
        Trace.load(tmp_path / "nulls.parquet", verify=False)
