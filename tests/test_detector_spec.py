"""fdikit design / fdikit diagnose: a spec -> a calibrated detector file -> a diagnosis of a CSV log."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fdikit.cli import app
from fdikit.detector import Detector
from fdikit.detector_spec import build_detector, load_spec
from fdikit.errors import ParameterError
from fdikit.faults import Bias, FaultScenario
from fdikit.model import FaultModel
from fdikit.simulate import simulate

DT = 0.1
A = [[0.9, 0.05], [0.1, 0.8]]
B = [[0.1], [0.2]]
U0, Y0 = 5.0, (20.0, -3.0)   # absolute operating point [deg]
NOISE = 0.01                 # sensor noise [rad] per sample
OP = {"u0": {"steer": float(np.deg2rad(U0))}, "y0": {"y1": float(np.deg2rad(Y0[0])), "y2": float(np.deg2rad(Y0[1]))}}
SPEC = f"""
name: two-sensor
description: two filters, each reading one sensor
model:
  A: {A}
  B: {B}
  C: [[1.0, 0.0], [0.0, 1.0]]
  dt: {DT}
  controls: [steer]
  outputs: [y1, y2]
  operating_point: {OP}
filters:
  - {{name: A, outputs: [y1], process_noise_cov: 1.0e-6, measurement_noise_std: {NOISE}}}
  - {{name: B, outputs: [y2], process_noise_cov: 1.0e-6, measurement_noise_std: {NOISE}}}
log:
  time: time
  columns: {{steer: steer_deg, y1: y1_deg, y2: y2_deg}}
  units: {{steer: deg, y1: deg, y2: deg}}
calibration: {{false_alarms_per_hour: 1.0, persistence: [3, 5]}}
"""


def _log(path, duration, fault=None, seed=0, drop=()):
    m = FaultModel(A, np.eye(2), Bu=B, controls=["steer"], outputs=["y1", "y2"], dt=DT)
    rng = np.random.default_rng(seed)
    n = int(round(duration / DT)) + 1
    u = 0.05 * np.repeat(rng.standard_normal(n // 20 + 1), 20)[:n]
    tr = simulate(m, FaultScenario([fault]) if fault else None, duration=duration, u=u[:, None],
                  measurement_noise_std=NOISE, rng=seed)
    clock = pd.Timestamp("2026-01-01T00:00:00Z") + pd.to_timedelta(tr.t, unit="s")
    df = pd.DataFrame({"time": clock.strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
                       "steer_deg": np.rad2deg(tr.u[:, 0]) + U0,
                       "y1_deg": np.rad2deg(tr.y[:, 0]) + Y0[0], "y2_deg": np.rad2deg(tr.y[:, 1]) + Y0[1]})
    df.drop(index=list(drop)).to_csv(path, index=False)
    return path


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    d = tmp_path_factory.mktemp("spec")
    (d / "spec.yaml").write_text(SPEC)
    healthy = [_log(d / f"healthy{i}.csv", 1800.0, seed=i) for i in (1, 2)]
    faulty = {
        "y2_sensor": _log(d / "y2_bias.csv", 120.0, Bias("y2", 0.1, onset=60.0), seed=3, drop=(100, 101, 500)),
        "steer_actuator": _log(d / "steer_offset.csv", 120.0, Bias("steer", 0.3, onset=60.0), seed=4),
    }
    return d, healthy, faulty


def test_design_and_diagnose_on_the_command_line(setup):
    d, healthy, faulty = setup
    runner = CliRunner()
    args = ["design", str(d / "spec.yaml"), "--out", str(d / "det.json")]
    for h in healthy:
        args += ["--healthy", str(h)]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    det = Detector.load(d / "det.json")
    # signatures: a sensor fault fires only the filter reading that sensor, the actuator fault both filters
    sig = det.evaluator.signatures
    assert sig.signature("y2_sensor") == ("B:y2",) and sig.signature("y1_sensor") == ("A:y1",)
    assert set(sig.signature("steer_actuator")) == {"A:y1", "B:y2"}
    for fault, log in faulty.items():
        out = d / f"out_{fault}"
        res = runner.invoke(app, ["diagnose", str(d / "det.json"), str(log), "--out", str(out)])
        assert res.exit_code == 0, res.output
        table = pd.read_csv(out / "diagnosis.csv")
        after = table[table["t"] >= 70.0]           # 10 s after the onset (filter time constants < 2 s)
        assert (after["fault"] == fault).mean() > 0.9
        assert not table.loc[table["t"] < 60.0, "alarm"].any()
        html = (out / "report.html").read_text()
        assert "data:image/png;base64," in html and fault in html
    gap = pd.read_csv(d / "out_y2_sensor" / "diagnosis.csv")
    assert (~gap["valid"]).sum() >= 3               # the three dropped rows are invalid samples


def test_calibration_on_the_runs_reports_the_achieved_rate(setup):
    d, healthy, _ = setup
    det = build_detector(load_spec(d / "spec.yaml"), healthy)
    cal = det.evaluator.calibration
    assert cal.runs == 2 and cal.target_rate == 1.0
    assert cal.hours == pytest.approx(2 * 1800.0 / 3600.0, rel=1e-3)
    # the thresholds give per-sample probability α = rate·dt, so the expected number of 3-of-5 alarm onsets in the
    # hour is at most about 1 (white Gaussian innovations of the exact model); P(Poisson(1) >= 7) < 1e-4
    assert cal.alarms <= 6
    lo, hi = cal.interval
    assert lo <= cal.rate <= hi and cal.min_resolvable_rate == pytest.approx(3.689 / cal.hours, rel=1e-3)


def test_bad_specs_are_refused(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("model: {A: [[0.9]], C: [[1.0]], dt: 0.1}\nfilters: [{name: 'a:b'}]\n")
    with pytest.raises(ParameterError, match="filters.0.name"):
        load_spec(p)
    p.write_text("model: {A: [[0.9]], C: [[1.0]], dt: 0.1}\nunknown: 1\n")
    with pytest.raises(ParameterError, match="unknown"):
        load_spec(p)
    runner = CliRunner()
    res = runner.invoke(app, ["design", str(p), "--healthy", str(tmp_path / "none.csv")])
    assert res.exit_code == 2 and "error:" in res.output
