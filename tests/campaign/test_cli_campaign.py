"""``fdikit campaign``: run (with the summary and the report), report, list; bad input answered with one line."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from fdikit.cli import app

runner = CliRunner()

SPEC = {
    "name": "cli-test", "study": "path-linear", "seed": 5, "duration": 10.0, "plants": [{"name": "linear"}],
    "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor", "wheel_speed_fl_sensor"], "onset": {"values": [4.0]}}],
    "healthy": 2, "designs": [{"name": "kalman", "kind": "kalman"}],
    "evaluators": [{"name": "threshold", "params": {"calibration": 60.0}}], "chunk_size": 2,
}


def test_run_then_report(tmp_path):
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(SPEC))
    out = tmp_path / "out"
    res = runner.invoke(app, ["campaign", "run", str(spec), "--out", str(out), "--workers", "1", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "4 runs in 2 chunks (2 computed, 0 resumed) on 1 local worker(s)" in res.output
    assert "campaign cli-test: 4 runs" in res.output and "kalman" in res.output
    page = out / "report.html"
    assert page.is_file() and "cli-test" in page.read_text()
    page.unlink()
    res = runner.invoke(app, ["campaign", "report", str(out), "--examples", "1"])
    assert res.exit_code == 0, res.output
    assert page.is_file() and list((out / "report-traces").glob("*.png"))
    res = runner.invoke(app, ["campaign", "run", str(spec), "--out", str(out), "--workers", "1", "--no-progress",
                              "--no-report"])
    assert res.exit_code == 0 and "(0 computed, 2 resumed)" in res.output


def test_bad_input_one_line(tmp_path):
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump({**SPEC, "designs": [{"name": "x", "kind": "luenberger"}]}))
    res = runner.invoke(app, ["campaign", "run", str(spec), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "error: the campaign spec" in res.output and "designs.0.kind: unknown design 'luenberger'" in res.output
    assert "Traceback" not in res.output
    res = runner.invoke(app, ["campaign", "report", str(tmp_path)])
    assert res.exit_code == 2 and "campaign.json not found" in res.output
    res = runner.invoke(app, ["campaign", "run", "no-such-spec"])
    assert res.exit_code == 2 and "does not exist; give a YAML file or one of the shipped specs" in res.output


def test_list_shows_shipped_specs():
    res = runner.invoke(app, ["campaign", "list"])
    assert res.exit_code == 0, res.output
    assert "path-linear" in res.output and "studies: path-linear" in res.output
