"""The campaign engine: bit-identical results for 1, 2 and 4 workers and both backends; kill and resume."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from fdikit.campaign.engine import replay, run_campaign
from fdikit.campaign.plan import plan_runs
from fdikit.campaign.spec import load_campaign
from fdikit.campaign.store import load_results
from fdikit.errors import DataError, ParameterError

SPEC = {
    "name": "engine-test", "study": "path-linear", "seed": 11, "duration": 10.0,
    "plants": [{"name": "linear", "params": {"noise": "realistic"}}],
    "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor", "accel_x_sensor", "throttle_actuator"],
                "size": {"loguniform": [0.5, 2.0]}, "onset": {"uniform": [3.0, 6.0]}}],
    "healthy": 3, "designs": [{"name": "kalman", "kind": "kalman"}],
    "evaluators": [{"name": "threshold", "params": {"calibration": 60.0}},
                   {"name": "cusum", "params": {"calibration": 60.0}}],
    "sweep": {"low": 0.5, "high": 2.0, "points": 5}, "chunk_size": 1,
}


def _digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted((folder / "runs").glob("*.parquet"))}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ref")
    done = run_campaign(load_campaign(SPEC), folder, workers=1)
    return folder, done


def test_results_complete_and_consistent(reference):
    folder, done = reference
    spec = load_campaign(SPEC)
    assert (done.runs, done.chunks, done.computed, done.reused) == (6, 6, 6, 0)
    manifest, table = load_results(folder)
    assert manifest["runs"] == 6
    np.testing.assert_allclose(manifest["levels"], [0.5, 2**-0.5, 1.0, 2**0.5, 2.0], rtol=1e-11)
    assert len(table) == 6 * 2 and not table.duplicated(["run", "design", "evaluator"]).any()
    plan = plan_runs(spec)
    assert table.groupby("run")["seed"].first().tolist() == [p.seed for p in plan]
    healthy = table[table.fault == "none"]
    assert healthy.detection_delay.isna().all() and healthy.isolation_correct.isna().all()
    assert np.isnan(np.vstack(healthy.sweep_delay)).all()
    # the sweep's level 1 is the nominal threshold: a threshold row's first crossing after the onset is its
    # detection (the persistence statistic > 1 exactly where the evaluator alarms)
    faulty = table[(table.fault != "none") & (table.evaluator == "threshold")]
    at_one = np.vstack(faulty.sweep_delay)[:, 2]
    np.testing.assert_array_equal(np.isfinite(at_one), faulty.detected.to_numpy())
    np.testing.assert_allclose(at_one[faulty.detected], faulty.detection_delay[faulty.detected], rtol=0, atol=1e-9)
    # a higher level is crossed later, if at all (up-crossing counts need not be monotone in the level)
    d = np.vstack(faulty.sweep_delay)
    finite = np.isfinite(d)
    assert np.all(finite[:, :-1] >= finite[:, 1:])
    both = finite[:, :-1] & finite[:, 1:]
    assert np.all(d[:, :-1][both] <= d[:, 1:][both])


@pytest.mark.parametrize("workers, backend", [(2, "local"), (4, "local"), (2, "dask")])
def test_bit_identical_across_workers_and_backends(reference, tmp_path, workers, backend):
    folder, _ = reference
    done = run_campaign(load_campaign(SPEC), tmp_path, workers=workers, backend=backend)
    assert done.computed == 6 and done.backend == backend
    assert _digests(tmp_path) == _digests(folder)


def test_dask_cluster_by_address(reference, tmp_path):
    """--scheduler ADDRESS: a cluster started elsewhere (here a LocalCluster of the test) computes the same bytes."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        messages = []
        done = run_campaign(load_campaign(SPEC), tmp_path, scheduler=cluster.scheduler_address, say=messages.append)
    assert done.backend == "dask" and done.workers == 2
    assert any(m.startswith("Dask dashboard: http") for m in messages)
    assert _digests(tmp_path) == _digests(reference[0])


def test_unreachable_scheduler(tmp_path, monkeypatch):
    monkeypatch.setattr("fdikit.campaign.engine.CONNECT_TIMEOUT", "1s")
    with pytest.raises(ParameterError, match=r"scheduler \(--scheduler\): cannot connect to tcp://127.0.0.1:9"):
        run_campaign(load_campaign(SPEC), tmp_path, scheduler="tcp://127.0.0.1:9")


def test_rerun_resumes_and_other_spec_refused(reference, tmp_path):
    folder, _ = reference
    again = run_campaign(load_campaign(SPEC), folder, workers=1)
    assert (again.computed, again.reused) == (0, 6)
    with pytest.raises(ParameterError, match="holds the results of another campaign spec .*entries that differ: seed"):
        run_campaign(load_campaign({**SPEC, "seed": 12}), folder, workers=1)


def test_fresh_replaces_only_when_complete(reference, tmp_path):
    import shutil

    folder = tmp_path / "out"
    shutil.copytree(reference[0], folder)
    before = _digests(folder)
    other = load_campaign({**SPEC, "seed": 12, "healthy": 1})
    done = run_campaign(other, folder, workers=1, fresh=True)
    assert done.computed == 4
    manifest, table = load_results(folder)
    assert manifest["spec"]["seed"] == 12 and len(table) == 8
    assert _digests(folder) != before and not (folder / "runs.next").exists()


def test_replay_reproduces_a_stored_run(reference):
    folder, _ = reference
    _, table = load_results(folder)
    row = table[(table.fault != "none") & (table.evaluator == "threshold")].iloc[0]
    trace, residuals, diagnosis = replay(folder, int(row.run), "kalman", "threshold")
    from fdikit.metrics import score

    s = score(trace, diagnosis)
    assert s.detected == row.detected and s.false_alarms == row.false_alarms
    if s.detected:
        assert s.detection_delay == pytest.approx(row.detection_delay, abs=1e-12)
    with pytest.raises(ParameterError, match="design 'bank' is not in the campaign; choose from: kalman"):
        replay(folder, 0, "bank", "threshold")


def test_bad_arguments(tmp_path):
    spec = load_campaign(SPEC)
    with pytest.raises(ParameterError, match=r"backend \(--backend\) must be one of"):
        run_campaign(spec, tmp_path, backend="spark")
    with pytest.raises(ParameterError, match=r"workers \(--workers\) must be a whole number >= 1"):
        run_campaign(spec, tmp_path, workers=0)
    (tmp_path / "file").write_text("x")
    with pytest.raises(ParameterError, match="is a file"):
        run_campaign(spec, tmp_path / "file", workers=1)
    with pytest.raises(DataError, match="holds no campaign results"):
        load_results(tmp_path)


def test_kill_and_resume_loses_and_duplicates_nothing(reference, tmp_path):
    """SIGKILL the command mid-campaign; the rerun completes it, identical to the uninterrupted run."""
    spec_file = tmp_path / "spec.yaml"
    spec_file.write_text(yaml.safe_dump({**SPEC, "healthy": 3 + 24}))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "fdikit.cli", "campaign", "run", str(spec_file), "--out", str(out), "--workers", "1",
           "--no-progress", "--no-report"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if len(list((out / "runs").glob("chunk-*.parquet"))) >= 3 if (out / "runs").is_dir() else False:
            break
        time.sleep(0.01)
    assert proc.poll() is None, f"the campaign ended before it could be killed: {proc.stderr.read().decode()}"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    kept = _digests(out)
    assert 3 <= len(kept) < 30
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert f"{30 - len(kept)} computed, {len(kept)} resumed" in result.stdout
    final = _digests(out)
    assert len(final) == 30 and all(final[k] == v for k, v in kept.items())
    assert not [p.name for p in (out / "runs").iterdir() if not p.name.startswith("chunk-")]  # no temporary file
    _, table = load_results(out)
    assert len(table) == 60 and not table.duplicated(["run", "design", "evaluator"]).any()
    assert table.groupby("run")["seed"].first().tolist() == [p.seed for p in plan_runs(load_campaign(spec_file))]
