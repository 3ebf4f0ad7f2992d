"""compare_evaluators: same residuals for every evaluator, scores streamed to CSV, table agrees with metrics."""

import csv

import numpy as np
import pytest

from fdikit.compare import compare_evaluators
from fdikit.decision import ThresholdEvaluator
from fdikit.errors import DataError
from fdikit.metrics import score, summarize
from fdikit.residuals import Residuals
from fdikit.trace import Trace


def _run(seed, fault):
    rng = np.random.default_rng(seed)
    t = np.arange(1000) * 0.01
    r = rng.standard_normal((1000, 2))
    truth = np.full(1000, "none")
    if fault is not None:
        r[500:, fault] += 6.0
        truth[500:] = f"f{fault}"
    trace = Trace(t=t, u=np.zeros((1000, 0)), y=np.zeros((1000, 0)), controls=(), outputs=(), fault=truth)
    return trace, Residuals(t, r, ("a", "b"), ("f0", "f1"))


def test_compare_matches_direct_scoring(tmp_path):
    runs = [_run(0, None), _run(1, 0), _run(2, 1), _run(3, 0)]
    evs = {"tight": ThresholdEvaluator(thresholds=[2.0, 2.0]), "loose": ThresholdEvaluator(thresholds=[4.0, 4.0],
                                                                                            persistence=(3, 5))}
    out = tmp_path / "scores.csv"
    c = compare_evaluators(evs, runs, scores_csv=out)
    for name, ev in evs.items():
        direct = summarize([score(tr, ev.run(r)) for tr, r in runs])
        row = c.table.loc[name]
        assert row["runs"] == 4 and row["false alarms"] == direct.false_alarms
        assert row["isolation accuracy"] == pytest.approx(direct.isolation_accuracy)
        assert row["mean delay [s]"] == pytest.approx(direct.mean_delay)
    # the tight threshold (2σ) raises false alarms on noise; the loose one with persistence does not
    assert c.table.loc["tight", "false alarms"] > 0 and c.table.loc["loose", "false alarms"] == 0
    # 3 of 5 persistence: at least two samples after the onset, and a 6σ shift rarely needs more than two more
    assert 0.02 - 1e-9 <= c.table.loc["loose", "mean delay [s]"] <= 0.04
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 8 and {r["evaluator"] for r in rows} == {"tight", "loose"}
    assert "| loose | 4 |" in c.to_markdown()
    with pytest.raises(DataError):
        compare_evaluators({}, runs)


def test_scores_csv_is_not_truncated_when_scoring_fails(tmp_path):
    """The CSV is written atomically once every run is scored: a failure mid-way leaves the old file intact."""
    out = tmp_path / "scores.csv"
    out.write_text("earlier results\n")

    class Broken:
        calls = 0

        def run(self, residuals):
            Broken.calls += 1
            if Broken.calls == 2:
                raise RuntimeError("killed")
            return ThresholdEvaluator(thresholds=[2.0, 2.0]).run(residuals)

    with pytest.raises(RuntimeError):
        compare_evaluators({"broken": Broken()}, [_run(0, None), _run(1, 0)], scores_csv=out)
    assert out.read_text() == "earlier results\n"
    assert [p.name for p in tmp_path.iterdir()] == ["scores.csv"]  # no temporary file left


def test_path_comparison_test_runs_are_those_of_path_runs():
    """The resumable comparison simulates each test run on its own, exactly as path_runs does in one go."""
    from fdikit.studies.path1996.bank import path_bank, path_runs
    from fdikit.studies.path1996.compare import _test_run, _test_specs

    full = path_runs(path_bank(), runs_per_fault=1, healthy_runs=1, onset=5.0, seed=12)
    specs = _test_specs(1, 1, 12)
    assert len(specs) == len(full) == 16
    for k in (0, 1, 9, 15):
        trace, res = _test_run(specs[k], 1e-4)
        assert np.array_equal(trace.y, full[k][0].y) and np.array_equal(trace.fault, full[k][0].fault)
        assert np.array_equal(res.r, full[k][1].r, equal_nan=True) and res.names == full[k][1].names
