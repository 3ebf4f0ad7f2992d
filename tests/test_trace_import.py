"""Trace.from_pandas / Trace.from_csv: time axes, the sampling grid, gaps, units, labels and flags.

Every expected value is built independently of the importer: the grid positions of the rows a
test removes, the defining factors of the units (1 kt = 1852/3600 m/s, 1 ft = 0.3048 m, ...).
Tolerances: a unit conversion is one or two float64 roundings away from the product with the
defining factor (relative 2**-53 each), so rtol = 1e-15.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.trace import Trace
from fdikit.trace_import import import_arguments

RTOL = 1e-15
N = 50
DT = 0.02


def _log(n: int = N, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({
        "delta_deg": rng.standard_normal(n),
        "speed_kt": 100 + rng.standard_normal(n),
        "alt_ft": 1e4 + rng.standard_normal(n),
        "v_kmh": 50 + rng.standard_normal(n),
        "oat_C": 15 + rng.standard_normal(n),
        "nz_g": 1 + 0.1 * rng.standard_normal(n),
    })


UNITS = {"delta": "deg", "speed": "kt", "alt": "ft", "v": "km/h", "oat": "degC", "nz": "g0"}
COLS = {"delta": "delta_deg", "speed": "speed_kt", "alt": "alt_ft", "v": "v_kmh", "oat": "oat_C", "nz": "nz_g"}


def _import(df, **kw):
    return Trace.from_pandas(df, controls={"delta": "delta_deg"},
                             outputs={k: v for k, v in COLS.items() if k != "delta"}, units=UNITS, **kw)


# ---------------------------------------------------------------------- time axes
def test_naive_datetime_index_with_dropped_rows_gives_invalid_samples_at_their_grid_points():
    df = _log()
    df.index = pd.date_range("2024-05-01 12:00", periods=N, freq=f"{int(DT * 1000)}ms")
    df.iloc[[7, 30], 1] = np.nan  # dropouts of one signal: kept as NaN, valid stays True
    removed = [3, 4, 5, 20, 41]  # as dropna would leave them
    tr = _import(df.drop(df.index[removed]))
    assert len(tr) == N and tr.dt == pytest.approx(DT, rel=1e-12)
    assert np.flatnonzero(~tr.valid).tolist() == removed
    assert tr.gaps == [(3 * DT, 5 * DT), (20 * DT, 20 * DT), (41 * DT, 41 * DT)]
    assert np.all(np.isnan(tr.y[removed])) and np.all(np.isnan(tr.u[removed]))
    np.testing.assert_array_equal(tr.t, np.arange(N) * DT)
    kept = np.setdiff1d(np.arange(N), removed)
    np.testing.assert_allclose(tr.u[kept, 0], df["delta_deg"].to_numpy()[kept] * math.pi / 180, rtol=RTOL)
    assert np.isnan(tr.signal("speed")[[7, 30]]).all() and tr.valid[[7, 30]].all()
    info = tr.meta["import"]
    assert info["time"] == {"column": None, "kind": "datetime", "unit": None, "timezone": None,
                            "start": "2024-05-01T12:00:00"}
    assert info["rows"] == N - 5 and info["inserted"] == 5 and info["dt_given"] is False


def test_tz_aware_datetimes_across_a_daylight_saving_change_stay_uniform():
    # Paris, 2024-03-31: 02:00 CET becomes 03:00 CEST; in UTC the clock runs on uniformly
    clock = pd.date_range("2024-03-31 01:59:59", periods=N, freq="100ms", tz="Europe/Paris")
    assert clock[-1].hour == 3  # the wall clock jumps by an hour within the log
    df = _log().assign(time=clock)
    tr = _import(df, time="time")
    np.testing.assert_allclose(tr.t, np.arange(N) * 0.1, rtol=0, atol=1e-12)
    assert tr.valid.all()
    assert tr.meta["import"]["time"]["timezone"] == "Europe/Paris"
    assert tr.meta["import"]["time"]["start"] == "2024-03-31T01:59:59+01:00"


def test_numeric_time_in_seconds_and_in_milliseconds():
    df = _log().assign(t=3.5 + DT * np.arange(N))
    tr = _import(df, time="t")
    np.testing.assert_allclose(tr.t, DT * np.arange(N), rtol=0, atol=1e-12)
    assert tr.meta["import"]["time"]["start"] == 3.5 and tr.meta["import"]["time"]["kind"] == "seconds"
    ms = _import(df.assign(t=df["t"] * 1000), time="t", time_unit="ms")
    assert ms.dt == pytest.approx(DT, rel=1e-12) and ms.meta["import"]["time"]["start"] == pytest.approx(3.5)
    with pytest.raises(ParameterError, match="not a unit of time"):
        _import(df, time="t", time_unit="m")


def test_a_timedelta_index_is_read_as_offsets():
    df = _log()
    df.index = pd.timedelta_range("10s", periods=N, freq="20ms")
    tr = _import(df)
    assert tr.meta["import"]["time"]["kind"] == "timedelta" and tr.meta["import"]["time"]["start"] == 10.0
    np.testing.assert_allclose(tr.t, DT * np.arange(N), atol=1e-12)


def test_csv_with_iso_times_round_trips(tmp_path):
    df = _log()
    clock = pd.date_range("2024-05-01 12:00", periods=N, freq="20ms", tz="UTC")
    df.insert(0, "time", clock.strftime("%Y-%m-%dT%H:%M:%S.%f+00:00"))
    df["phase"] = np.where(np.arange(N) >= 25, "speed_sensor", "")
    df = df.drop(index=[10, 11])
    path = tmp_path / "log.csv"
    df.to_csv(path, index=False)
    tr = Trace.from_csv(path, time="time", controls={"delta": "delta_deg"},
                        outputs={k: v for k, v in COLS.items() if k != "delta"}, units=UNITS, fault="phase")
    assert np.flatnonzero(~tr.valid).tolist() == [10, 11]
    assert tr.fault.tolist() == ["none"] * 25 + ["speed_sensor"] * 25
    assert tr.meta["import"]["source"] == {"kind": "csv", "path": str(path)}
    assert tr.meta["import"]["time"]["start"] == "2024-05-01T12:00:00+00:00"
    # the same log read from the DataFrame (CSV writes floats with repr: exact round trip)
    direct = Trace.from_pandas(df, time="time", controls={"delta": "delta_deg"},
                               outputs={k: v for k, v in COLS.items() if k != "delta"}, units=UNITS, fault="phase")
    for attr in ("t", "u", "y", "valid"):
        np.testing.assert_array_equal(getattr(tr, attr), getattr(direct, attr))
    back = Trace.load(tr.save(tmp_path / "run.parquet"))
    np.testing.assert_array_equal(back.valid, tr.valid)
    assert back.meta == tr.meta and np.array_equal(back.y, tr.y, equal_nan=True)
    # naive ISO text in a CSV
    path2 = tmp_path / "naive.csv"
    path2.write_text("stamp,h\n2024-05-01 12:00:00.00,1\n2024-05-01 12:00:00.25,2\n2024-05-01 12:00:00.75,3\n")
    tr2 = Trace.from_csv(path2, time="stamp", outputs=["h"], units={"h": "ft"}, dt=0.25)
    assert tr2.valid.tolist() == [True, True, False, True] and tr2.meta["import"]["time"]["timezone"] is None


def test_iso_text_with_changing_offsets_and_mixed_offsets(tmp_path):
    path = tmp_path / "dst.csv"
    path.write_text("time,x\n2024-03-31T01:59:59.5+01:00,1\n2024-03-31T03:00:00.0+02:00,2\n"
                    "2024-03-31T03:00:00.5+02:00,3\n")
    tr = Trace.from_csv(path, time="time", outputs=["x"])
    np.testing.assert_array_equal(tr.t, [0.0, 0.5, 1.0])  # one UTC clock through the change of offset
    assert tr.meta["import"]["time"]["timezone"] == "UTC"
    path.write_text("time,x\n2024-03-31T01:59:59.5+01:00,1\n2024-03-31T01:00:00.0,2\n")
    with pytest.raises(DataError, match=r"mixes times with and without a UTC offset \(row 1"):
        Trace.from_csv(path, time="time", outputs=["x"])
    path.write_text("time,x\nnoon,1\nlater,2\n")
    with pytest.raises(DataError, match=r"dst\.csv: .*not ISO 8601"):
        Trace.from_csv(path, time="time", outputs=["x"])
    with pytest.raises(DataError, match="no CSV file"):
        Trace.from_csv(tmp_path / "none.csv", time="time", outputs=["x"])


def test_re_reading_with_import_arguments_gives_the_same_trace(tmp_path):
    df = _log().assign(t=DT * np.arange(N)).drop(index=[5])
    tr = _import(df, time="t")
    args = import_arguments(tr.meta)
    assert args["controls"] == {"delta": "delta_deg"} and args["units"] == UNITS and args["dt"] == tr.dt
    again = Trace.from_pandas(df, **args)
    np.testing.assert_array_equal(again.y, tr.y)
    assert again.meta["import"] == {**tr.meta["import"], "dt_given": True}
    with pytest.raises(DataError, match="no import record"):
        import_arguments({"plant": "x"})


# ---------------------------------------------------------------------- the grid: refusals
def test_off_grid_duplicate_and_decreasing_times_are_refused_naming_the_row():
    t = DT * np.arange(N)
    off = t.copy()
    off[17] += 0.3 * DT
    with pytest.raises(DataError, match=r"row 17 \(t = 0\.346 s\) is off the sampling grid .* never resamples"):
        _import(_log().assign(t=off), time="t")
    dup = t.copy()
    dup[9] = dup[8]
    with pytest.raises(DataError, match=r"row 9 \(t = 0\.16 s\) repeats the time of row 8"):
        _import(_log().assign(t=dup), time="t")
    back = t.copy()
    back[[20, 21]] = back[[21, 20]]
    with pytest.raises(DataError, match=r"row 21 .* goes back in time from row 20.*never reorders"):
        _import(_log().assign(t=back), time="t")
    with pytest.raises(DataError, match=r"row 9 \(t = 2024-01-01T00:00:00\.160000\) repeats"):
        _import(_log().assign(t=pd.Timestamp("2024-01-01") + pd.to_timedelta(dup, unit="s")), time="t")


def test_jitter_within_the_tolerance_is_accepted_and_recorded():
    rng = np.random.default_rng(1)
    jit = rng.uniform(-0.004, 0.004, N) * DT  # 0.4 % of dt, under the default 1 %
    jit[0] = 0.0
    tr = _import(_log().assign(t=DT * np.arange(N) + jit), time="t")
    assert tr.valid.all() and tr.meta["import"]["max_deviation"] <= 0.004 * DT * 1.01
    with pytest.raises(DataError, match="off the sampling grid"):
        _import(_log().assign(t=DT * np.arange(N) + 5 * jit), time="t")  # 2 % of dt
    tr = _import(_log().assign(t=DT * np.arange(N) + 5 * jit), time="t", jitter=0.03 * DT)
    assert tr.valid.all()
    with pytest.raises(ParameterError, match="below half the sample time"):
        _import(_log().assign(t=DT * np.arange(N)), time="t", jitter=0.6 * DT)


def test_a_60_hz_clock_rounded_to_milliseconds_needs_its_jitter():
    # 60 Hz stamped in whole ms: each time is up to 0.5 ms = 3 % of dt off the 1/60 s grid
    n = 600
    stamps = np.round(np.arange(n) * 1000 / 60) / 1000
    df = _log(n).assign(t=stamps)
    with pytest.raises(DataError, match="off the sampling grid"):
        _import(df, time="t")
    tr = _import(df, time="t", jitter=0.0005)
    # the median spacing (17 ms) would drift by 0.2 s over the log; the fitted slope is 1/60 s: with
    # rounding errors |e_k| <= 0.5 ms, the least-squares slope errs by at most
    # 0.5 ms * sum(k) / sum(k^2) ~ 0.5 ms * (n^2/2) / (n^3/3) = 0.75 ms / n
    assert abs(tr.dt - 1 / 60) < 0.001 / n and tr.valid.all()


def test_a_plain_row_index_is_not_a_clock_and_a_too_long_grid_is_refused():
    with pytest.raises(DataError, match="RangeIndex"):
        _import(_log())
    t = DT * np.arange(N)
    t[-1] = 1e4
    with pytest.raises(DataError, match="split the log"):
        _import(_log().assign(t=t), time="t", dt=DT)
    with pytest.raises(DataError, match="missing .* at row 3"):
        _import(_log().assign(t=np.where(np.arange(N) == 3, np.nan, t)), time="t")


# ---------------------------------------------------------------------- signals, units, flags, labels
def test_units_convert_exactly_and_are_recorded():
    df = _log().assign(t=DT * np.arange(N))
    tr = _import(df, time="t")
    factors = {"speed": 1852 / 3600, "alt": 0.3048, "v": 1000 / 3600, "nz": 9.80665}
    for name, f in factors.items():
        np.testing.assert_allclose(tr.signal(name), df[COLS[name]].to_numpy() * f, rtol=RTOL)
    np.testing.assert_allclose(tr.signal("oat"), df["oat_C"].to_numpy() + 273.15, rtol=RTOL)
    np.testing.assert_allclose(tr.signal("delta", "u"), df["delta_deg"].to_numpy() * math.pi / 180, rtol=RTOL)
    rec = tr.meta["import"]["signals"]
    assert rec["outputs"]["oat"] == {"column": "oat_C", "unit": "degC", "si_unit": "K"}
    assert rec["outputs"]["nz"]["si_unit"] == "m/s**2" and rec["controls"]["delta"]["si_unit"] == "rad"


def test_list_form_signals_and_unit_errors():
    df = _log().assign(t=DT * np.arange(N))
    tr = Trace.from_pandas(df, time="t", controls=["delta_deg"], outputs=["alt_ft"])
    assert tr.controls == ("delta_deg",) and tr.outputs == ("alt_ft",)
    np.testing.assert_array_equal(tr.y[:, 0], df["alt_ft"].to_numpy())  # no unit given: read as SI
    assert tr.meta["import"]["signals"]["outputs"]["alt_ft"] == {"column": "alt_ft", "unit": None, "si_unit": None}
    with pytest.raises(ParameterError, match=r"ambiguous.*'g0'"):
        Trace.from_pandas(df, time="t", outputs={"nz": "nz_g"}, units={"nz": "g"})
    with pytest.raises(ParameterError, match="unknown unit"):
        Trace.from_pandas(df, time="t", outputs={"nz": "nz_g"}, units={"nz": "gees"})
    with pytest.raises(ParameterError, match="column of signal 'nz': key units by signal name"):
        Trace.from_pandas(df, time="t", outputs={"nz": "nz_g"}, units={"nz_g": "g0"})
    with pytest.raises(DataError, match="no column 'pitch'"):
        Trace.from_pandas(df, time="t", outputs=["pitch"])
    with pytest.raises(ParameterError, match=r"single string 'alt_ft'"):
        Trace.from_pandas(df, time="t", outputs="alt_ft")
    with pytest.raises(DataError, match=r"holds 'n/a!' \(str\) at row 2"):
        Trace.from_pandas(df.assign(alt_ft=df["alt_ft"].astype(object).where(df.index != 2, "n/a!")),
                          time="t", outputs=["alt_ft"])


def test_valid_column_and_fault_labels():
    df = _log().assign(t=DT * np.arange(N), ok=np.arange(N) % 10 != 4,
                       truth=np.where(np.arange(N) >= 30, "alt_sensor", None))
    tr = _import(df.drop(index=[31, 32]), time="t", valid="ok", fault="truth")
    assert np.flatnonzero(~tr.valid).tolist() == [4, 14, 24, 31, 32, 34, 44]
    # the inserted samples 31, 32 carry the label of sample 30; empty cells read 'none'
    assert tr.fault.tolist() == ["none"] * 30 + ["alt_sensor"] * 20
    assert tr.meta["import"]["valid"] == "ok" and tr.meta["import"]["fault"] == "truth"
    with pytest.raises(DataError, match=r"valid flags must be booleans.*df\['status'\] == 0"):
        _import(df.assign(ok=df["ok"].astype(int)), time="t", valid="ok")
    with pytest.raises(DataError, match=r"fault label column 'truth' holds 3"):
        _import(df.assign(truth=3), time="t", fault="truth")
    assert _import(df, time="t", valid=np.arange(N) != 0).valid.tolist() == [False] + [True] * (N - 1)
