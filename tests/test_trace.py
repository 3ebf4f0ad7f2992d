"""Trace: validation, access by name, pandas export and the exact Parquet round trip."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit import DataError
from fdikit.trace import Trace

N = 64


def _trace(seed: int = 0, **changes) -> Trace:
    rng = np.random.default_rng(seed)
    kw = {
        "t": 3.0 + np.arange(N) * 0.01 + 1e-3 * rng.random(),
        "u": rng.standard_normal((N, 2)),
        "y": rng.standard_normal((N, 3)) * 1e5,
        "x": rng.standard_normal((N, 2)) * 1e-7,
        "d": rng.standard_normal((N, 1)),
        "controls": ["throttle", "steer"],
        "outputs": ["yaw_rate", "speed", "t"],
        "states": ["v", "r"],
        "disturbances": ["gust"],
        "fault": np.where(np.arange(N) >= 40, "speed_sensor+steer_actuator", "none"),
        "meta": {"plant": "toy", "seed": 7, "scenario": "s", "faults": ["Bias(...)"], "nested": {"k": [1, 2.5, None]}},
    }
    kw.update(changes)
    return Trace(**kw)


def test_parquet_round_trip_is_exact(tmp_path):
    tr = _trace()
    y = tr.y.copy()
    y[5, 1] = np.nan  # a logged dropout must survive too
    y[6, 0] = -np.inf
    tr = _trace(y=y)
    path = tr.save(tmp_path / "sub" / "run.parquet")
    assert path.exists()
    back = Trace.load(path)
    for attr in ("t", "u", "x", "d"):
        a, b = getattr(tr, attr), getattr(back, attr)
        assert b.dtype == np.float64 and b.shape == a.shape
        assert np.array_equal(a, b), attr
    assert np.array_equal(tr.y, back.y, equal_nan=True)
    assert np.array_equal(tr.fault, back.fault)
    for attr in ("controls", "outputs", "states", "disturbances"):
        assert getattr(back, attr) == getattr(tr, attr)
    assert back.meta == tr.meta
    assert back.fault_onset == tr.fault_onset == tr.t[40]


def test_parquet_round_trip_without_optional_blocks(tmp_path):
    tr = Trace(t=np.arange(5.0), u=np.zeros((5, 0)), y=np.arange(5.0), controls=[], outputs=["a"])
    back = Trace.load(tr.save(tmp_path / "t.parquet"))
    assert back.u.shape == (5, 0) and back.x.shape == (5, 0) and back.d.shape == (5, 0)
    assert np.array_equal(back.y[:, 0], np.arange(5.0))
    assert back.fault.tolist() == ["none"] * 5 and back.fault_onset is None


def test_load_errors(tmp_path):
    with pytest.raises(DataError, match="no trace file"):
        Trace.load(tmp_path / "missing.parquet")
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({"a": [1.0, 2.0]}), tmp_path / "plain.parquet")
    with pytest.raises(DataError, match="not an fdikit trace"):
        Trace.load(tmp_path / "plain.parquet")


def test_to_pandas_columns_and_values():
    tr = _trace()
    df = tr.to_pandas()
    assert list(df.columns) == [
        "u:throttle", "u:steer", "y:yaw_rate", "y:speed", "y:t", "x:v", "x:r", "d:gust", "fault", "valid",
    ]
    assert df["valid"].dtype == bool and df["valid"].all()
    assert df.index.name == "t"
    np.testing.assert_array_equal(df.index.to_numpy(), tr.t)
    np.testing.assert_array_equal(df["y:speed"].to_numpy(), tr.y[:, 1])
    np.testing.assert_array_equal(df["x:r"].to_numpy(), tr.x[:, 1])
    assert df["fault"].tolist() == tr.fault.tolist()


def test_signal_and_columns_by_name():
    tr = _trace()
    np.testing.assert_array_equal(tr.signal("speed"), tr.y[:, 1])
    np.testing.assert_array_equal(tr.signal("steer", "u"), tr.u[:, 1])
    np.testing.assert_array_equal(tr.signal("r", "x"), tr.x[:, 1])
    np.testing.assert_array_equal(tr.columns("y", ["t", "yaw_rate"]), tr.y[:, [2, 0]])
    assert tr.columns("u", []).shape == (N, 0)
    assert len(tr) == N
    assert tr.dt == pytest.approx(0.01, rel=1e-9)


def test_unknown_names_are_data_errors():
    tr = _trace()
    with pytest.raises(DataError, match=r"no y-signal named 'roll'.*\['yaw_rate', 'speed', 't'\]"):
        tr.signal("roll")
    with pytest.raises(DataError, match=r"no u-signal named 'speed'"):
        tr.signal("speed", "u")
    with pytest.raises(DataError, match=r"no x-signal named 'q'"):
        tr.columns("x", ["v", "q"])


def test_unknown_signal_kind_is_a_data_error():
    """``signal(name, kind)`` with a kind other than u/y/x/d should say so, not raise a bare KeyError."""
    with pytest.raises(DataError):
        _trace().signal("speed", kind="z")


@pytest.mark.parametrize(
    "t",
    [
        np.array([0.0, 0.1, 0.1, 0.3]),
        np.array([0.0, 0.2, 0.1, 0.3]),
        np.array([0.0, 0.1, np.nan, 0.3]),
        np.array([0.0, 0.1, 0.2, np.inf]),
    ],
)
def test_time_must_be_finite_and_strictly_increasing(t):
    with pytest.raises(DataError, match="strictly increasing"):
        Trace(t=t, u=np.zeros((4, 1)), y=np.zeros((4, 1)), controls=["a"], outputs=["b"])


@pytest.mark.parametrize(
    ("block", "value", "pattern"),
    [
        ("u", np.zeros((4, 3)), r"'u' has shape \(4, 3\) but must be \(4, 2\)"),
        ("y", np.zeros((5, 1)), r"'y' has shape \(5, 1\) but must be \(4, 1\)"),
        ("x", np.zeros((4, 1)), r"'x' has shape \(4, 1\) but must be \(4, 0\)"),
        ("d", np.zeros(4), r"'d' has shape \(4,\) but must be \(4, 0\)"),
        ("fault", np.array(["none"] * 3), r"fault labels have shape \(3,\)"),
    ],
)
def test_wrong_block_shapes(block, value, pattern):
    kw = {"t": np.arange(4.0), "u": np.zeros((4, 2)), "y": np.zeros(4), "controls": ["a", "b"], "outputs": ["c"]}
    kw[block] = value
    with pytest.raises(DataError, match=pattern):
        Trace(**kw)


def test_one_dimensional_single_column_is_accepted():
    tr = Trace(t=np.arange(4.0), u=np.ones(4), y=np.arange(4.0), controls=["a"], outputs=["c"])
    assert tr.u.shape == (4, 1) and tr.y.shape == (4, 1)


def test_check_finite_names_signal_and_sample():
    tr = _trace()
    tr.check_finite()  # clean data pass
    y = tr.y.copy()
    y[17, 2] = np.nan
    y[30, 0] = np.inf
    bad = _trace(y=y)
    with pytest.raises(DataError, match=r"y-signal 't' at sample 17 \(t=3\.17\d*\).*2 bad values"):
        bad.check_finite()
    bad.check_finite(signals=("u",))  # only the blocks asked for are checked
    x = tr.x.copy()
    x[3, 1] = np.nan
    with pytest.raises(DataError, match=r"x-signal 'r' at sample 3"):
        _trace(x=x).check_finite(signals=("u", "y", "x"))


def test_dt_needs_two_samples():
    tr = Trace(t=[1.0], u=np.zeros((1, 0)), y=np.zeros((1, 1)), controls=[], outputs=["a"])
    with pytest.raises(DataError, match="fewer than 2 samples"):
        _ = tr.dt


def test_a_null_label_is_refused_not_truncating_the_others():
    """Issue 12, item 1: ``np.asarray(labels, dtype=str)`` with a None cut every label to 1 character."""
    labels = ["none"] * 10 + ["steer_bias"] * 5
    labels[3] = None
    with pytest.raises(DataError, match=r"fault label at sample 3 is None \(NoneType\)"):
        Trace(t=np.arange(15.0), u=np.zeros((15, 0)), y=np.zeros(15), controls=[], outputs=["a"], fault=labels)
    labels[3] = "none"
    tr = Trace(t=np.arange(15.0), u=np.zeros((15, 0)), y=np.zeros(15), controls=[], outputs=["a"], fault=labels)
    assert tr.fault.tolist() == labels and tr.fault_onset == 10.0


def test_labels_from_a_list_or_an_object_array_are_kept_exactly():
    labels = ["none", "ünï+cödé", "f\x00inner", "none"]
    for given in (labels, np.array(labels, dtype=object)):
        tr = Trace(t=np.arange(4.0), u=np.zeros((4, 0)), y=np.zeros(4), controls=[], outputs=["a"], fault=given)
        assert tr.fault.tolist() == labels


def test_a_name_may_recur_in_another_block(tmp_path):
    """An output that measures a state of the same name (the Varrier scenario has y- and x-'yaw_rate')."""
    tr = _trace(outputs=["yaw_rate", "speed", "v"])
    back = Trace.load(tr.save(tmp_path / "same_names.parquet"))
    np.testing.assert_array_equal(back.signal("v", "y"), tr.y[:, 2])
    np.testing.assert_array_equal(back.signal("v", "x"), tr.x[:, 0])


def test_meta_is_kept_as_plain_json():
    tr = _trace(meta={"rows": (1, 2), "seed": np.int64(7), "gain": np.float32(0.5), "on": np.bool_(True),
                      "poles": np.array([-1.0, -2.0]), "nested": {"k": (None, "a")}})
    assert tr.meta == {"rows": [1, 2], "seed": 7, "gain": 0.5, "on": True, "poles": [-1.0, -2.0],
                       "nested": {"k": [None, "a"]}}
    assert type(tr.meta["seed"]) is int and type(tr.meta["on"]) is bool
    with pytest.raises(DataError, match=r"meta\['nested'\]\['f'\] is of type builtin_function"):
        _trace(meta={"nested": {"f": len}})
    with pytest.raises(DataError, match=r"key 3 \(int\)"):
        _trace(meta={3: "x"})


def test_meta_changed_after_construction_is_checked_on_save(tmp_path):
    tr = _trace()
    tr.meta["lateral_acceleration"] = np.float64(2.5)  # fine: a float
    back = Trace.load(tr.save(tmp_path / "ok.parquet"))
    assert back.meta["lateral_acceleration"] == 2.5
    tr.meta["model"] = object()
    with pytest.raises(DataError, match=r"meta\['model'\] is of type object"):
        tr.save(tmp_path / "bad.parquet")
    assert not (tmp_path / "bad.parquet").exists()


def test_loaded_arrays_are_writable(tmp_path):
    back = Trace.load(_trace().save(tmp_path / "w.parquet"))
    for attr in ("t", "u", "y", "x", "d"):
        assert getattr(back, attr).flags.writeable, attr


def test_valid_defaults_to_all_true_and_is_checked():
    tr = _trace()
    assert tr.valid.dtype == bool and tr.valid.shape == (N,) and tr.valid.all() and tr.gaps == []
    flags = np.ones(N, dtype=bool)
    flags[[3, 4, 5, 20, N - 1]] = False
    tr = _trace(valid=flags)
    flags[0] = False  # the trace holds its own copy
    assert tr.valid[0]
    assert tr.gaps == [(tr.t[3], tr.t[5]), (tr.t[20], tr.t[20]), (tr.t[N - 1], tr.t[N - 1])]
    assert repr(tr).endswith(", invalid=5)") and "invalid" not in repr(_trace())
    assert _trace(valid=[True] * N).valid.all()
    with pytest.raises(DataError, match=rf"valid flags have shape \(3,\), need \({N},\)"):
        _trace(valid=[True, False, True])
    with pytest.raises(DataError, match="valid flags must be booleans.*dtype int64"):
        _trace(valid=np.ones(N, dtype=np.int64))
    with pytest.raises(DataError, match="valid flags must be booleans.*dtype object"):
        _trace(valid=[True] * (N - 1) + [None])


@pytest.mark.parametrize(
    "t",
    [
        np.array(["2024-01-01T00:00:00", "2024-01-01T00:00:01"], dtype="datetime64[ns]"),
        np.array([0, 1], dtype="timedelta64[s]"),
        np.array([0.0, 1.0], dtype=object),
        np.array(["0.0", "1.0"]),
    ],
    ids=["datetime64", "timedelta64", "object", "text"],
)
def test_clock_times_are_refused_with_the_importer_named(t):
    # (datetime64 read as float would give nanoseconds: a step of 1e9 "seconds")
    with pytest.raises(DataError, match=r"trace time t holds .*Trace\.from_pandas"):
        Trace(t=t, u=np.zeros((2, 0)), y=np.zeros((2, 0)), controls=[], outputs=[])


def test_pandas_datetimes_are_refused_too():
    pd = pytest.importorskip("pandas")
    for t in (pd.date_range("2024-01-01", periods=3, freq="100ms"),
              pd.date_range("2024-01-01", periods=3, freq="100ms", tz="Europe/Paris"),
              pd.Series(pd.date_range("2024-01-01", periods=3, freq="100ms"))):
        with pytest.raises(DataError, match=r"Trace\.from_pandas"):
            Trace(t=t, u=np.zeros((3, 0)), y=np.zeros((3, 0)), controls=[], outputs=[])
