"""Property tests of :class:`Trace`: the Parquet round trip is exact, bad labels and names are refused.

Random shapes (0 to 30 samples, 0 to 3 columns per block), Unicode names and labels, NaN/±inf
and signed zeros in the signals (NaN payloads included), nested JSON meta:
``Trace.load(trace.save(path))`` equals the trace bit for bit.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fdikit.errors import DataError
from fdikit.trace import Trace

_TEXT = st.characters(exclude_categories=("Cs",))  # every code point but lone surrogates (not UTF-8)
NAMES = st.text(_TEXT, min_size=1, max_size=8)
# a trailing NUL is refused (numpy str arrays drop it); any other code point may occur, NUL inside included
LABELS = st.text(_TEXT, min_size=1, max_size=12).filter(lambda s: not s.endswith("\x00"))
FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)
JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=10,
)


@st.composite
def traces(draw) -> Trace:
    n = draw(st.integers(0, 30))
    t = draw(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=n, max_size=n, unique=True).map(sorted))
    kw = {"t": np.array(t, dtype=float)}
    for kind, attr in (("u", "controls"), ("y", "outputs"), ("x", "states"), ("d", "disturbances")):
        names = draw(st.lists(NAMES, max_size=3, unique=True))
        kw[attr] = names
        kw[kind] = draw(arrays(np.float64, (n, len(names)), elements=FLOATS))
    pool = draw(st.lists(LABELS, min_size=1, max_size=4)) + ["none"]
    kw["fault"] = draw(st.lists(st.sampled_from(pool), min_size=n, max_size=n))
    kw["meta"] = draw(st.dictionaries(st.text(max_size=6), JSON, max_size=4))
    return Trace(**kw)


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def assert_same(a: Trace, b: Trace) -> None:
    for k in "tuyxd":
        x, y = getattr(a, k), getattr(b, k)
        assert x.shape == y.shape and y.dtype == np.float64, k
        assert np.array_equal(_bits(x), _bits(y)), k  # bit for bit: NaN payloads, signed zeros, infinities
    assert a.fault.tolist() == b.fault.tolist()
    for attr in ("controls", "outputs", "states", "disturbances"):
        assert getattr(a, attr) == getattr(b, attr)
    assert a.meta == b.meta


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory(prefix="fdikit-trace-prop-") as d:
        yield Path(d)


@settings(max_examples=120)
@given(tr=traces())
def test_parquet_round_trip_is_exact(tr, folder):
    back = Trace.load(tr.save(folder / "round.parquet"))
    assert_same(tr, back)
    assert np.array_equal(np.isnan(back.y), np.isnan(tr.y)) and np.array_equal(np.isnan(back.u), np.isnan(tr.u))
    assert back.fault_onset == tr.fault_onset and len(back) == len(tr)


@given(tr=traces())
def test_reconstructing_from_the_fields_gives_the_same_trace(tr):
    again = Trace(t=tr.t, u=tr.u, y=tr.y, x=tr.x, d=tr.d, controls=tr.controls, outputs=tr.outputs, states=tr.states,
                  disturbances=tr.disturbances, fault=tr.fault, meta=tr.meta)
    assert_same(tr, again)


BAD_LABELS = (st.none() | st.integers() | st.floats() | st.binary(max_size=4) | st.just("") | st.booleans()
              | st.text(max_size=3).map(lambda s: s + "\x00"))


@given(n=st.integers(1, 25), data=st.data())
def test_a_non_string_or_empty_label_is_refused_not_coerced(n, data):
    labels = data.draw(st.lists(st.sampled_from(["none", "f1", "ünïcode"]), min_size=n, max_size=n))
    k = data.draw(st.integers(0, n - 1))
    bad = data.draw(BAD_LABELS)
    labels[k] = bad
    with pytest.raises(DataError, match=f"fault label at sample {k} "):
        Trace(t=np.arange(n, dtype=float), u=np.zeros((n, 0)), y=np.zeros((n, 1)), controls=[], outputs=["y"],
              fault=labels)


@given(names=st.lists(NAMES, min_size=1, max_size=4, unique=True), data=st.data())
def test_a_duplicate_name_within_a_block_is_refused(names, data):
    dup = data.draw(st.sampled_from(names))
    names = [*names, dup]
    kind, attr = data.draw(st.sampled_from([("u", "controls"), ("y", "outputs"), ("x", "states"),
                                            ("d", "disturbances")]))
    kw = {"t": np.arange(3.0), "u": np.zeros((3, 0)), "y": np.zeros((3, 0)), "controls": [], "outputs": []}
    kw[kind], kw[attr] = np.zeros((3, len(names))), names
    with pytest.raises(DataError, match=f"duplicate name .* in trace {attr}"):
        Trace(**kw)


@pytest.fixture(scope="module")
def saved(folder):
    rng = np.random.default_rng(0)
    n = 40
    tr = Trace(t=np.arange(n) * 0.5, u=rng.standard_normal((n, 1)), y=rng.standard_normal((n, 2)), controls=["ü"],
               outputs=["a", "b"], fault=np.where(np.arange(n) > 20, "φ", "none"), meta={"k": [1, "x"]})
    return tr, tr.save(folder / "byte_good.parquet").read_bytes()


@settings(max_examples=200)
@given(data=st.data())
def test_a_changed_byte_never_loads_a_different_trace(data, folder, saved):
    """One byte anywhere in a saved file changed to another value: refused, or the very same trace."""
    tr, good = saved
    at = data.draw(st.integers(0, len(good) - 1))
    value = data.draw(st.integers(0, 255).filter(lambda v: v != good[at]))
    path = folder / "byte_bad.parquet"
    path.write_bytes(good[:at] + bytes([value]) + good[at + 1:])
    try:
        back = Trace.load(path)
    except DataError as exc:
        assert str(path) in str(exc)
        return
    assert_same(tr, back)
