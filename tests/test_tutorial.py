"""docs/tutorial.md runs as written and its quoted numbers hold ("bring your own plant and data")."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fdikit.errors import FdiWarning

ROOT = Path(__file__).resolve().parents[1]
TEXT = (ROOT / "docs" / "tutorial.md").read_text()


def _section(title: str) -> str:
    start = TEXT.index(title)
    nxt = TEXT.find("\n## ", start + 1)
    return TEXT[start: nxt if nxt > 0 else None]


def _python(section: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", section, re.S)


def _user_lines(code: str) -> int:
    return sum(1 for line in code.splitlines() if line.strip() and not line.strip().startswith("#"))


@pytest.fixture()
def workdir(tmp_path, monkeypatch):
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _run(code: str) -> dict:
    ns: dict = {}
    exec(compile(code, "docs/tutorial.md", "exec"), ns)
    return ns


def test_the_car_part_runs_in_under_30_lines_and_gives_the_quoted_numbers(workdir):
    from fdikit.analysis import fault_to_residual_gain

    (code,) = _python(_section("## 1. A car, its model identified from a log"))
    assert _user_lines(code) <= 30
    ns = _run(code)
    assert len(ns["train"].gaps) == 5 and (~ns["train"].valid).sum() == 5
    ident, report = ns["ident"], ns["report"]
    assert ident.order == 6
    np.testing.assert_allclose(report.fit, [88.7, 84.8], atol=0.05)
    assert not report.whiteness.passed.any()
    with pytest.warns(FdiWarning, match="feedthrough|D "):       # the quoted ill-conditioned feedthrough
        with_d = ns["subspace_id"](ns["train"], feedthrough=True)
    assert with_d.model.Du[1, 0] == pytest.approx(-3355, rel=0.05)
    table = ns["detector"].evaluator.signatures
    assert table.signature("yaw_rate_sensor") == ("yaw_rate_filter",)
    assert table.signature("accel_y_sensor") == ("accel_y_filter",)
    assert table.signature("steering_actuator") == ("yaw_rate_filter", "accel_y_filter")
    # detection limits: threshold / steady fault gain into each residual
    ev, bank, model = ns["evaluator"], ns["bank"], ns["model"]
    G = fault_to_residual_gain(bank, model, [1e-4]).peak()
    limits = ev.thresholds / np.where(G > 1e-9, G, np.nan)
    assert np.rad2deg(limits[0, 0]) == pytest.approx(0.6, abs=0.05)                  # yaw-rate bias [deg/s]
    assert np.rad2deg(np.nanmax(limits[2])) == pytest.approx(0.13, abs=0.01)         # steering offset [deg]
    yaw, steer = ns["car_scores"]
    assert yaw.detected and yaw.detection_delay == pytest.approx(0.04) and yaw.isolated == "yaw_rate_sensor"
    assert yaw.isolation_delay == pytest.approx(0.04) and yaw.correct_fraction == 1.0 and yaw.false_alarms == 0
    assert steer.detected and steer.detection_delay == pytest.approx(0.05) and steer.isolated == "steering_actuator"
    assert steer.isolation_delay == pytest.approx(0.09) and steer.correct_fraction > 0.995 and steer.false_alarms == 0
    cal = ev.calibration
    assert cal.alarms == 0 and cal.min_resolvable_rate == pytest.approx(22.1, abs=0.1)


def test_the_tank_part_runs_in_under_30_lines_and_gives_the_quoted_numbers(workdir):
    (code,) = _python(_section("## 2. A plant written as a Python function"))
    assert _user_lines(code) <= 30
    ns = _run(code)
    op = ns["lin"].model.operating_point
    assert op.u0["pump"] * 60_000 == pytest.approx(21.3, abs=0.05)     # L/min
    assert op.y0["level1"] * 100 == pytest.approx(16.0, abs=0.05) and op.y0["level2"] == pytest.approx(0.25)
    table = ns["table"]
    assert table.signature("level1_sensor") == ("tank1",) and table.signature("level2_sensor") == ("tank2",)
    assert table.signature("pump_actuator") == ("tank1", "tank2") and not table.indistinguishable
    cal = ns["evaluator"].calibration
    assert cal.min_resolvable_rate == pytest.approx(3.69, abs=0.01)
    s = ns["tanks_score"]
    assert s.detected and s.detection_delay == pytest.approx(2.0) and s.false_alarms == 0
    assert s.isolated == "level2_sensor" and s.isolation_delay == pytest.approx(2.0) and s.correct_fraction == 1.0
    faulty, detector = ns["faulty"], ns["Detector"].load("tanks_detector.json")
    after = detector.run(faulty).alarm[faulty.t >= 1200.0].mean()
    assert after == pytest.approx(0.87, abs=0.01)
    # the quoted effect of a larger Q: the filter absorbs the bias within seconds
    kalman, stack, model = ns["kalman"], ns["stack_generators"], ns["model"]
    loose = stack([kalman(model.submodel(outputs=[y]), Q=1e-8, R=0.002**2, names=[f"tank{i}"]).generator
                   for i, y in enumerate(model.outputs, start=1)])
    ev = ns["ThresholdEvaluator"](persistence=(3, 5), signatures=ns["SignatureTable"].from_generator(loose, model))
    ev.fit([loose.run(ns["healthy"])], false_alarms_per_hour=1.0)
    assert ev.run(loose.run(faulty)).alarm[faulty.t >= 1200.0].mean() == pytest.approx(0.01, abs=0.005)
    # the deployment block: the saved detector online, at the trim
    (deploy,) = _python(_section("## Deploying the detector"))
    assert _run(deploy)["decision"].fault == "none"


def test_the_command_line_part(workdir):
    from fdikit.cli import app

    block = re.search(r"```\n(fdikit design .*?)```", _section("## 3. The same from the command line"), re.S).group(1)
    runner = CliRunner()
    for line in block.strip().splitlines():
        args = shlex.split(line)[1:]
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
    table = np.genfromtxt(workdir / "out" / "tanks" / "diagnosis.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")
    assert not table["alarm"][table["t"] < 1200.0].any()
    named = table["fault"][(table["t"] >= 1200.0) & table["alarm"]]
    assert named.size and set(named) == {"level2_sensor"}
    assert "data:image/png;base64," in (workdir / "out" / "tanks" / "report.html").read_text()
