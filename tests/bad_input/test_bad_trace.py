"""Bad input for :class:`fdikit.trace.Trace`: construction, ``save`` and ``load`` of malformed files.

Every malformed file gives a :class:`~fdikit.errors.DataError` naming the file (its basename is a
fragment of each file case) and what is wrong; wrong argument types give a ``ParameterError``.
The files are made in a private temporary folder when a case runs.
"""

from __future__ import annotations

import atexit
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from harness import case, check, ids

from fdikit.errors import DataError, ParameterError
from fdikit.trace import Trace

N = 20
_DIR: list[Path] = []


def _dir() -> Path:
    if not _DIR:
        _DIR.append(Path(tempfile.mkdtemp(prefix="fdikit-bad-trace-")))
        atexit.register(shutil.rmtree, _DIR[0], True)
    return _DIR[0]


def _kw(**changes) -> dict:
    kw = {"t": np.arange(N) * 0.1, "u": np.ones((N, 1)), "y": np.zeros((N, 2)), "controls": ["u1"],
          "outputs": ["a", "b"], "fault": np.where(np.arange(N) >= 10, "f1", "none"), "meta": {"seed": 1}}
    kw.update(changes)
    return kw


def _tr(**changes) -> Trace:
    return Trace(**_kw(**changes))


def _labels(k: int, value) -> list:
    out: list = ["none"] * N
    out[k] = value
    return out


def _meta_with(key, value) -> Trace:
    tr = _tr()
    tr.meta[key] = value  # changed after construction: save must still refuse it
    return tr


def _saved(name: str) -> Path:
    return _tr().save(_dir() / name)


def _info(**changes) -> dict:
    info = {"controls": ["u1"], "outputs": ["a", "b"], "states": [], "disturbances": [], "meta": {"seed": 1}}
    info.update(changes)
    return info


def _columns(**changes) -> dict:
    cols = {"t": pa.array(np.arange(N) * 0.1), "u:u1": pa.array(np.ones(N)), "y:a": pa.array(np.zeros(N)),
            "y:b": pa.array(np.zeros(N)), "fault": pa.array(["none"] * 10 + ["f1"] * 10)}
    for k, v in changes.items():
        k = k.replace("__", ":")
        if v is None:
            del cols[k]
        else:
            cols[k] = v
    return cols


def _raw(name: str, columns: dict | None = None, info=None, names: list[str] | None = None) -> Path:
    """A Parquet file written directly with pyarrow (no digest): one thing wrong in it."""
    columns = _columns() if columns is None else columns
    info = _info() if info is None else info
    raw = info if isinstance(info, bytes) else json.dumps(info).encode()
    arrays = list(columns.values())
    table = pa.Table.from_arrays(arrays, names=names or list(columns))
    table = table.replace_schema_metadata({b"fdikit": raw})
    path = _dir() / name
    pq.write_table(table, path)
    return path


def _bytes(name: str, data: bytes) -> Path:
    path = _dir() / name
    path.write_bytes(data)
    return path


def _truncated(name: str) -> Path:
    data = _saved(name + ".src").read_bytes()
    return _bytes(name, data[: len(data) // 2])


def _page_corrupted(name: str) -> Path:
    """Overwrite 40 bytes in the middle of the first data page of column 'y:a'."""
    path = _saved(name)
    md = pq.ParquetFile(path).metadata
    col = md.row_group(0).column(md.schema.names.index("y:a"))
    start = col.data_page_offset
    end = (col.dictionary_page_offset or col.data_page_offset) + col.total_compressed_size
    data = bytearray(path.read_bytes())
    mid = (start + end) // 2
    data[mid - 20: mid + 20] = bytes((b + 0x5A) % 256 for b in data[mid - 20: mid + 20])
    path.write_bytes(bytes(data))
    return path


def _meta_edited(name: str) -> Path:
    """A saved trace whose fdikit metadata was edited afterwards (everything else kept)."""
    path = _saved(name)
    table = pq.read_table(path)
    md = dict(table.schema.metadata)
    info = json.loads(md[b"fdikit"])
    info["meta"]["seed"] = 2
    md[b"fdikit"] = json.dumps(info).encode()
    pq.write_table(table.replace_schema_metadata(md), path)
    return path


def _null_in_saved(name: str) -> Path:
    """A saved trace (with its digest) rewritten with one sample of 'y:b' null."""
    path = _saved(name)
    table = pq.read_table(path)
    j = table.schema.get_field_index("y:b")
    table = table.set_column(j, "y:b", pa.array([None] + [0.0] * (N - 1), pa.float64()))
    pq.write_table(table, path)
    return path


def _over_existing_folder() -> Path:
    folder = _dir() / "a_folder.parquet"
    folder.mkdir(exist_ok=True)
    return folder


def _under_a_file() -> Path:
    blocker = _dir() / "blocker.txt"
    blocker.write_text("x")
    return blocker / "sub" / "trace.parquet"


_BAD_FRAME = b"PAR1" + b"\x00" * 64 + b"PAR1"

CASES = [
    # ---------------------------------------------------------------- construction: fault labels
    case("fault-none-label", lambda: _tr(fault=_labels(3, None)), DataError, "fault", "sample 3", "None"),
    case("fault-int-label", lambda: _tr(fault=_labels(4, 7)), DataError, "fault", "sample 4", "int"),
    case("fault-nan-label", lambda: _tr(fault=_labels(5, float("nan"))), DataError, "fault", "sample 5", "float"),
    case("fault-object-array-none", lambda: _tr(fault=np.array(_labels(6, None), dtype=object)), DataError,
         "fault", "sample 6"),
    case("fault-bytes-array", lambda: _tr(fault=np.array([b"none"] * N)), DataError, "fault", "bytes"),
    case("fault-numeric-array", lambda: _tr(fault=np.zeros(N)), DataError, "fault", "string"),
    case("fault-bool-array", lambda: _tr(fault=np.zeros(N, dtype=bool)), DataError, "fault", "string"),
    case("fault-single-string", lambda: _tr(fault="none"), DataError, "fault", "single string"),
    case("fault-empty-label", lambda: _tr(fault=_labels(2, "")), DataError, "fault", "sample 2", "empty"),
    case("fault-empty-label-array", lambda: _tr(fault=np.array(_labels(8, ""))), DataError, "fault", "empty"),
    case("fault-nul-label", lambda: _tr(fault=_labels(1, "f\x00")), DataError, "fault", "NUL"),
    case("fault-wrong-length", lambda: _tr(fault=["none"] * (N - 1)), DataError, "fault", "shape"),
    case("fault-2d", lambda: _tr(fault=np.full((N, 2), "none")), DataError, "fault", "shape"),
    # ---------------------------------------------------------------- construction: names
    case("names-duplicate-outputs", lambda: _tr(outputs=["a", "a"]), DataError, "outputs", "duplicate", "'a'"),
    case("names-duplicate-controls", lambda: _tr(u=np.ones((N, 2)), controls=["c", "c"]), DataError,
         "controls", "duplicate", "'c'"),
    case("names-duplicate-states", lambda: _tr(x=np.ones((N, 2)), states=["s", "s"]), DataError,
         "states", "duplicate"),
    case("names-duplicate-disturbances", lambda: _tr(d=np.ones((N, 2)), disturbances=["w", "w"]), DataError,
         "disturbances", "duplicate"),
    case("names-empty-output", lambda: _tr(outputs=["a", ""]), DataError, "outputs", "empty"),
    case("names-int-control", lambda: _tr(controls=[1]), DataError, "controls", "int"),
    case("names-none-state", lambda: _tr(x=np.ones((N, 1)), states=[None]), DataError, "states", "None"),
    case("names-single-string", lambda: _tr(outputs="ab"), DataError, "outputs", "single string"),
    case("names-not-a-sequence", lambda: _tr(controls=5), DataError, "controls", "sequence"),
    case("names-lone-surrogate", lambda: _tr(outputs=["a", "b\ud800"]), DataError, "outputs", "UTF-8"),
    # ---------------------------------------------------------------- construction: meta and arrays
    case("meta-not-a-dict", lambda: _tr(meta=[1, 2]), DataError, "meta", "dict"),
    case("meta-object-value", lambda: _tr(meta={"bad": object()}), DataError, "meta['bad']", "JSON"),
    case("meta-int-key", lambda: _tr(meta={1: "a"}), DataError, "meta", "key", "string"),
    case("meta-nested-set", lambda: _tr(meta={"a": [{1, 2}]}), DataError, "meta['a'][0]", "JSON"),
    case("meta-bytes-value", lambda: _tr(meta={"raw": b"\x00"}), DataError, "meta['raw']", "bytes"),
    case("t-strings", lambda: _tr(t=["a"] * N), DataError, "t", "number"),
    case("t-2d", lambda: _tr(t=np.zeros((N, 2))), DataError, "t", "one-dimensional"),
    case("t-nan", lambda: _tr(t=np.r_[np.arange(N - 1) * 0.1, np.nan]), DataError, "t", "finite"),
    case("y-strings", lambda: _tr(y=np.full((N, 2), "x")), DataError, "'y'", "number"),
    case("u-complex", lambda: _tr(u=np.ones((N, 1)) * 1j), DataError, "'u'", "complex"),
    case("y-none-entries", lambda: _tr(y=[[None, 0.0]] * N), DataError, "'y'", "None"),
    case("columns-single-string", lambda: _tr().columns("y", "ab"), DataError, "names", "single string"),
    case("signal-unknown-kind", lambda: _tr().signal("a", kind="z"), DataError, "kind", "'z'"),
    # ---------------------------------------------------------------- save
    case("save-to-folder", lambda: _tr().save(_over_existing_folder()), DataError, "a_folder.parquet", "folder"),
    case("save-under-a-file", lambda: _tr().save(_under_a_file()), DataError, "blocker.txt", "folder"),
    case("save-path-none", lambda: _tr().save(None), ParameterError, "path", "NoneType"),
    case("save-path-int", lambda: _tr().save(123), ParameterError, "path", "int"),
    case("save-meta-mutated-object", lambda: _meta_with("late", object()).save(_dir() / "m.parquet"), DataError,
         "meta['late']", "JSON"),
    case("save-fault-surrogate", lambda: _tr(fault=_labels(0, "f\udc80")).save(_dir() / "s.parquet"), DataError,
         "fault", "UTF-8"),
    # ---------------------------------------------------------------- load: not a trace file
    case("load-missing", lambda: Trace.load(_dir() / "nope.parquet"), DataError, "nope.parquet", "no trace file"),
    case("load-folder", lambda: Trace.load(_dir()), DataError, "fdikit-bad-trace", "folder"),
    case("load-device", lambda: Trace.load("/dev/null"), DataError, "/dev/null", "not a regular file"),
    case("load-empty", lambda: Trace.load(_bytes("empty.parquet", b"")), DataError, "empty.parquet", "empty"),
    case("load-text", lambda: Trace.load(_bytes("text.parquet", b"t,y\n0,1\n")), DataError, "text.parquet",
         "not a Parquet"),
    case("load-bad-frame", lambda: Trace.load(_bytes("frame.parquet", _BAD_FRAME)), DataError, "frame.parquet",
         "not a Parquet"),
    case("load-truncated", lambda: Trace.load(_truncated("half.parquet")), DataError, "half.parquet", "truncated"),
    case("load-path-none", lambda: Trace.load(None), ParameterError, "path", "NoneType"),
    case("load-path-float", lambda: Trace.load(3.5), ParameterError, "path", "float"),
    case("load-verify-not-bool", lambda: Trace.load(_saved("v.parquet"), verify="yes"), ParameterError, "verify"),
    case("load-plain-parquet", lambda: Trace.load(_plain()), DataError,
         "plain.parquet", "not an fdikit trace"),
    # ---------------------------------------------------------------- load: bad metadata
    case("meta-not-json", lambda: Trace.load(_raw("nj.parquet", info=b"{not json")), DataError, "nj.parquet",
         "JSON"),
    case("meta-not-utf8", lambda: Trace.load(_raw("nu.parquet", info=b"\xff\xfe")), DataError, "nu.parquet",
         "UTF-8"),
    case("meta-json-list", lambda: Trace.load(_raw("jl.parquet", info=b"[1, 2]")), DataError, "jl.parquet",
         "object"),
    case("meta-missing-outputs", lambda: Trace.load(_raw("mo.parquet", info={k: v for k, v in _info().items()
                                                                             if k != "outputs"})),
         DataError, "mo.parquet", "outputs", "missing"),
    case("meta-outputs-not-strings", lambda: Trace.load(_raw("os.parquet", info=_info(outputs=["a", 2]))),
         DataError, "os.parquet", "outputs", "string"),
    case("meta-outputs-duplicate", lambda: Trace.load(_raw("od.parquet", info=_info(outputs=["a", "a"]))),
         DataError, "od.parquet", "duplicate"),
    case("meta-meta-not-dict", lambda: Trace.load(_raw("md.parquet", info=_info(meta=[1]))), DataError,
         "md.parquet", "meta", "dict"),
    # ---------------------------------------------------------------- load: bad columns
    case("col-missing-y", lambda: Trace.load(_raw("my.parquet", _columns(y__b=None))), DataError, "my.parquet",
         "y:b", "missing"),
    case("col-missing-t", lambda: Trace.load(_raw("mt.parquet", _columns(t=None))), DataError, "mt.parquet",
         "'t'", "missing"),
    case("col-missing-fault", lambda: Trace.load(_raw("mf.parquet", _columns(fault=None))), DataError,
         "mf.parquet", "fault", "missing"),
    case("col-unexpected", lambda: Trace.load(_raw("ux.parquet", _columns(y__c=pa.array(np.zeros(N))))),
         DataError, "ux.parquet", "y:c", "unexpected"),
    case("col-duplicate", lambda: Trace.load(_raw("dup.parquet", _columns(y__b=None) | {"y:a2": pa.array(
        np.ones(N))}, names=["t", "u:u1", "y:a", "fault", "y:a"])), DataError, "dup.parquet", "duplicate", "y:a"),
    case("col-y-strings", lambda: Trace.load(_raw("ys.parquet", _columns(y__a=pa.array(["1"] * N)))), DataError,
         "ys.parquet", "y:a", "float64"),
    case("col-t-int", lambda: Trace.load(_raw("ti.parquet", _columns(t=pa.array(np.arange(N))))), DataError,
         "ti.parquet", "'t'", "float64"),
    case("col-fault-int", lambda: Trace.load(_raw("fi.parquet", _columns(fault=pa.array(np.zeros(N, int))))),
         DataError, "fi.parquet", "fault", "string"),
    case("col-fault-null", lambda: Trace.load(_raw("fn.parquet", _columns(fault=pa.array(_labels(7, None))))),
         DataError, "fn.parquet", "fault", "null", "sample 7"),
    case("col-fault-empty", lambda: Trace.load(_raw("fe.parquet", _columns(fault=pa.array(_labels(7, "")))),
                                               verify=False), DataError, "fe.parquet", "fault", "empty"),
    case("col-y-null", lambda: Trace.load(_null_in_saved("yn.parquet")), DataError, "yn.parquet", "y:b", "null"),
    case("col-t-decreasing", lambda: Trace.load(_raw("td.parquet", _columns(t=pa.array(-np.arange(N) * 0.1))),
                                                verify=False), DataError, "td.parquet", "strictly increasing"),
    # ---------------------------------------------------------------- load: integrity
    case("digest-missing", lambda: Trace.load(_raw("nd.parquet")), DataError, "nd.parquet", "digest"),
    case("digest-mismatch-meta-edited", lambda: Trace.load(_meta_edited("me.parquet")), DataError, "me.parquet",
         "digest"),
    case("page-corrupted", lambda: Trace.load(_page_corrupted("pc.parquet")), DataError, "pc.parquet",
         "corrupt"),
]


def _plain() -> Path:
    path = _dir() / "plain.parquet"
    pq.write_table(pa.table({"a": [1.0, 2.0]}), path)
    return path


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
