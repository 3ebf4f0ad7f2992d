"""The command line: simulate writes a trace, errors are clear, the demo detects its fault."""

import numpy as np
from typer.testing import CliRunner

from fdikit.cli import app
from fdikit.trace import Trace

runner = CliRunner()


def test_simulate_writes_parquet(tmp_path):
    out = tmp_path / "t.parquet"
    res = runner.invoke(app, ["simulate", "path12", "-f", "bias:yaw_rate:0.02@10", "--duration", "20",
                              "--noise-std", "0.001", "--out", str(out)])
    assert res.exit_code == 0, res.output
    tr = Trace.load(out)
    assert len(tr) == 2001
    assert (tr.fault[tr.t >= 10] == "yaw_rate_sensor").all() and (tr.fault[tr.t < 10] == "none").all()
    assert tr.meta["plant_name"] == "path12"


def test_simulate_single_track_param(tmp_path):
    out = tmp_path / "s.parquet"
    res = runner.invoke(app, ["simulate", "single-track", "-p", "speed=20", "-f", "scale:steering:0.8@1",
                              "--duration", "2", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert Trace.load(out).outputs == ("yaw_rate", "lateral_error", "heading_error")


def test_simulate_text_param_and_atomic_overwrite(tmp_path):
    """A parameter annotated ``str`` is passed as text; a refused run leaves an existing trace intact."""
    out = tmp_path / "t.parquet"
    res = runner.invoke(app, ["simulate", "path14", "-p", "tiny=midpoint", "--duration", "1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    before = out.read_bytes()
    res = runner.invoke(app, ["simulate", "path14", "-p", "tiny=midpoint", "--duration", "1", "--dt", "nan",
                              "--out", str(out)])
    assert res.exit_code == 2 and "dt (--dt)" in res.output
    assert out.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["t.parquet"]


def test_simulate_bad_input():
    res = runner.invoke(app, ["simulate", "path12", "-f", "bias:nope:1@1"])
    assert res.exit_code == 2 and "no signal named 'nope'" in res.output
    res = runner.invoke(app, ["simulate", "nosuchplant"])
    assert res.exit_code == 2 and "path12" in res.output
    res = runner.invoke(app, ["simulate", "path12", "-f", "gremlin:yaw_rate:1"])
    assert res.exit_code == 2 and "gremlin" in res.output and "kind" in res.output


def test_demo_vehicle(tmp_path):
    """The default demo: on the nonlinear car at realistic noise the game bank + MHSSPRT isolate both faults."""
    res = runner.invoke(app, ["demo", "--out", str(tmp_path)], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "yaw_rate_sensor" in res.output and "throttle_actuator" in res.output
    assert res.output.count("True") == 2
    assert (tmp_path / "report.png").stat().st_size > 10_000
    tr = Trace.load(tmp_path / "trace_throttle_actuator.parquet")
    assert np.isclose(tr.fault_onset, 10.0) and set(tr.fault) == {"none", "throttle_actuator"}


def test_demo_bank(tmp_path):
    """The linear demo: the PATH Beard–Jones bank isolates a yaw-rate gyro bias and a throttle fault."""
    res = runner.invoke(app, ["demo", "--method", "bank", "--out", str(tmp_path)], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "yaw_rate_sensor" in res.output and "throttle_actuator" in res.output
    assert res.output.count("True") == 2
    for name in ("report.png", "structure.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    tr = Trace.load(tmp_path / "trace_throttle.parquet")
    assert np.isclose(tr.fault_onset, 10.0) and set(tr.fault) == {"none", "throttle_actuator"}


def test_demo_kalman(tmp_path):
    res = runner.invoke(app, ["demo", "--method", "kalman", "--out", str(tmp_path)], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "yaw_rate_sensor" in res.output
    assert (tmp_path / "report.png").stat().st_size > 10_000
    tr = Trace.load(tmp_path / "trace.parquet")
    assert np.isclose(tr.fault_onset, 10.0)
    res = runner.invoke(app, ["demo", "--method", "nope"])
    assert res.exit_code == 2 and "unknown method" in res.output


def test_help_everywhere():
    for cmd in ([], ["demo"], ["simulate"], ["plants"], ["compare-evaluators"], ["target-tracking"],
                ["multiple-model"]):
        res = runner.invoke(app, [*cmd, "--help"])
        assert res.exit_code == 0 and "Usage" in res.output


def test_compare_evaluators_command(tmp_path):
    """One command produces the side-by-side table (markdown) and the per-run scores."""
    res = runner.invoke(app, ["compare-evaluators", "--runs-per-fault", "1", "--healthy-runs", "1", "--no-bnn",
                              "--out", str(tmp_path)], terminal_width=250)
    assert res.exit_code == 0, res.output
    md = (tmp_path / "comparison.md").read_text()
    names = ("threshold (5 of 10)", "CUSUM", "GLR (M = 50)", "SPRT", "CUSUM, whitened", "GLR, whitened",
             "SPRT, whitened", "MHSSPRT", "Gaussian ML")
    for name in names:
        assert f"| {name} |" in md
    rows = (tmp_path / "scores.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + 16 * len(names)  # header + (15 faulty + 1 healthy runs) x evaluators
    # the calibrated threshold bank isolates every fault with no false alarm (as in tests/studies/path1996)
    assert "| threshold (5 of 10) | 16 | 1 | 0 |" in md


def test_target_tracking_command(tmp_path):
    out = tmp_path / "tt"
    res = runner.invoke(app, ["target-tracking", "--runs", "2", "--out", str(out)])
    assert res.exit_code == 0, res.output
    summary = (out / "summary.md").read_text()
    assert summary.count("\n") == 2 + 3  # header, rule, one row per filter
    assert "imm" in summary and "ekf" in summary
    assert (out / "rmse.png").stat().st_size > 1000


def test_multiple_model_command(tmp_path):
    """One command runs items 17–20 and writes the summary and three plots (tiny sizes here)."""
    out = tmp_path / "mm"
    res = runner.invoke(app, ["multiple-model", "--runs", "2", "--msd-dt", "0.02", "--model-sets", "3",
                              "--out", str(out)])
    assert res.exit_code == 0, res.output
    text = (out / "summary.md").read_text()
    for part in ("Item 17", "Item 18", "Item 19", "Item 20", "Table 3.4"):
        assert part in text
    for png in ("target_tracking.png", "b747.png", "msd.png"):
        assert (out / png).stat().st_size > 10_000


def test_b747_command_reduced_run_and_resume(tmp_path):
    """`fdikit b747` on a reduced sweep (rudder at −25, −5, 15 deg; no fault-free hour): tables, plots, HTML."""
    out = tmp_path / "b747"
    args = ["b747", "--step", "20", "--hours", "0", "--surfaces", "rudder", "--out", str(out)]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    rows = (out / "rows.csv").read_text().strip().splitlines()
    assert [r.split(",")[1] for r in rows[1:]] == ["-25.0", "-5.0", "15.0"]
    table = (out / "table.md").read_text()
    assert "rudder (thesis)" in table and "75.2 %" in table  # side by side with Table 4.8
    assert "Table 4.7 decision" in (out / "table_4_6.md").read_text()
    for png in ("sweep.png", "table_4_6.png"):
        assert (out / png).stat().st_size > 10_000
    assert "<table>" in (out / "report.html").read_text()
    again = runner.invoke(app, args)  # every run read back
    assert again.exit_code == 0 and (out / "rows.csv").read_text().strip().splitlines() == rows


def test_b747_command_refuses_bad_arguments(tmp_path):
    for bad, word in ((["--surfaces", "spoiler"], "--surfaces"), (["--noise", "datasheet"], "--noise"),
                      (["--turbulence", "9"], "--turbulence"), (["--step", "0"], "--step")):
        res = runner.invoke(app, ["b747", "--out", str(tmp_path / "x"), *bad])
        assert res.exit_code == 2 and word in res.output, res.output


def test_simulate_reports_a_fault_that_never_acts_as_one_warning_line(tmp_path):
    res = runner.invoke(app, ["simulate", "path12", "-f", "bias:yaw_rate:0.02@50", "--duration", "5",
                                   "--out", str(tmp_path / "t.parquet")])
    assert res.exit_code == 0, res.output
    assert "warning:" in res.output and "never acts" in res.output and "warnings.warn" not in res.output
    assert (tmp_path / "t.parquet").is_file()


def test_ftc_command_writes_the_msd_figures_and_table(tmp_path, monkeypatch):
    # The experiment itself takes minutes (docs/methods/ftc.md); here its result is replaced by a small one of
    # the same structure so that the command's files and printed table are checked.
    import fdikit.studies.hallouzi2008.spc_msd as spc_msd

    n = 50
    y, u = np.ones((n, 3)), np.zeros((n, 2))
    rmse = {"0-50": 1.5, "50-200": 0.05}
    fake = {"tracking": {"spc": {"y": y, "u": u}, "mpc": {"y": y, "u": u}, "rmse": {"spc": rmse, "mpc": rmse}},
            "pe": {k: {"y": y, "u": u, "rcond": np.full(n, 1e-3), "rmse": 0.1} for k in ("with", "without")}}
    monkeypatch.setattr(spc_msd, "run_msd_spc", lambda **kw: fake)
    out = tmp_path / "ftc"
    res = runner.invoke(app, ["ftc", "--out", str(out), "--quick", "--no-b747"])
    assert res.exit_code == 0, res.output
    assert {p.name for p in out.iterdir()} == {"msd_ftc_outputs.png", "msd_ftc_inputs.png", "msd_ftc_rcond.png",
                                              "msd_ftc_rmse.csv", "msd_ftc_rmse.md"}
    assert "| spc | 1.5 | 0.05 |" in res.output
    assert (out / "msd_ftc_rmse.csv").read_text().splitlines()[1] == "spc,1.5,0.05"


def _fake_flight(scenario, controller, n=400):
    from fdikit.studies.hallouzi2008.b747_ftc import FtcRun

    t = np.arange(n) * 0.1
    y = np.tile([0.0, -2.0, 0.0, 92.6, -2.0, 0.0, 980.0], (n, 1))
    ref = np.tile([0.0, -2.0, 92.6, 0.0, 0.0, 975.0], (n, 1))
    spc = controller == "spc"
    return FtcRun(t=t, y=y, reference=ref, surfaces=np.zeros((n, 4)), throttles=np.full((n, 4), 0.5),
                  mu=np.full((n, 8), 0.125) if spc else np.zeros((n, 0)), configuration=np.array(["nominal"] * n),
                  declared=("rudder", "rudder_lip_+25", 22.5) if spc and scenario == "rudder" else None, lost=None,
                  qp={"solved": n} if spc else {}, step_seconds=np.full(n, 1e-3) if spc else np.zeros(0),
                  rcond=np.full(40, 1e-5) if spc else np.zeros(0), scenario=scenario, controller=controller)


def test_ftc_command_flies_the_b747_and_resumes(tmp_path, monkeypatch):
    # The flights take minutes (docs/methods/ftc.md); here each is a small fake of the same structure, so the
    # files, the printed table and the resumption are checked.
    import fdikit.studies.hallouzi2008.b747_ftc as b747_ftc
    import fdikit.studies.hallouzi2008.b747_ftc_flight as b747_ftc_flight
    from fdikit.studies.hallouzi2008.b747_ftc_report import FLIGHTS

    calls = []

    def fly(setup, scenario, *, controller, reconfigure, duration, seed):
        calls.append((scenario, controller, reconfigure, duration, seed))
        return _fake_flight(scenario, controller)

    monkeypatch.setattr(b747_ftc, "ftc_setup", lambda **kw: object())
    monkeypatch.setattr(b747_ftc_flight, "fly_ftc", fly)
    out = tmp_path / "ftc"
    res = runner.invoke(app, ["ftc", "--out", str(out), "--quick", "--no-msd", "--seed", "3"])
    assert res.exit_code == 0, res.output
    assert len(calls) == len(FLIGHTS) and {c[3:] for c in calls} == {(120.0, 3)}
    names = {p.name for p in (out / "b747").iterdir()}
    assert {"ftc_b747.md", "ftc_b747.csv", "report.html", "rudder_responses.png", "rudder_modes.png",
            "bijlmer_surfaces.png", "rcond.png"} <= names
    assert "rudder (rudder_lip_+25) at 22.5 s (22 s)" in res.output and "max |h−h_ref| [m]" in res.output
    assert "rudder (rudder_lip_+25) at 22.5 s (22 s)" in (out / "b747" / "ftc_b747.md").read_text()
    res = runner.invoke(app, ["ftc", "--out", str(out), "--quick", "--no-msd", "--seed", "3"])
    assert res.exit_code == 0 and len(calls) == len(FLIGHTS)          # every flight reused
    res = runner.invoke(app, ["ftc", "--out", str(out), "--no-msd", "--no-b747"])
    assert res.exit_code != 0 and "leave nothing to run" in res.output
