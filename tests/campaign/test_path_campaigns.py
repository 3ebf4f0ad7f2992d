"""The PATH studies as campaigns: ``compare-evaluators``' processors on ``path-linear`` and ``path-nonlinear``.

Each campaign row must equal what the existing study code computes for the same trace and the same fitted
evaluator, both built from the campaign's seeds: ``fit_comparison_evaluator`` / ``fdikit.compare.score_run``
(``fdikit compare-evaluators``), and the nonlinear table's fits (``whitened_mhsprt``, the threshold of
``path_evaluation_table``) with ``fault_run`` and ``metrics.score``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fdikit.campaign.plan import plan_runs
from fdikit.campaign.spec import CampaignSpec, load_campaign, sweep_levels
from fdikit.campaign.studies import get_study

LINEAR = {
    "name": "compare-tiny", "study": "path-linear", "seed": 5, "duration": 10.0,
    "plants": [{"name": "report", "params": {"noise": "report"}}],
    "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor"], "size": {"values": [1.0]}, "onset": {"values": [5.0]}}],
    "healthy": 1, "designs": [{"name": "bank", "kind": "beard-jones"}],
    "evaluators": [{"name": "glr", "kind": "glr", "params": {"calibration": 60.0}},
                   {"name": "sprt-w", "kind": "sprt-whitened", "params": {"calibration": 60.0}},
                   {"name": "mhsprt", "kind": "mhsprt", "params": {"calibration": 60.0}},
                   {"name": "ml", "kind": "gaussian-ml"}],
    "sweep": {"low": 0.5, "high": 2.0, "points": 3}, "chunk_size": 5,
}

NONLINEAR = {
    "name": "nonlinear-tiny", "study": "path-nonlinear", "seed": 3, "duration": 4.0,
    "plants": [{"name": "rough", "params": {"road": "rough"}}],
    "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor"], "size": {"values": [1.0]}, "onset": {"values": [2.0]}}],
    "healthy": 1, "designs": [{"name": "game", "kind": "game"}],
    "evaluators": [{"name": "threshold", "kind": "threshold", "params": {"calibration": 30.0, "drop": 2.0}},
                   {"name": "mhsprt-w", "kind": "mhsprt-whitened", "params": {"calibration": 30.0, "drop": 2.0}}],
    "sweep": {"low": 0.5, "high": 2.0, "points": 3}, "chunk_size": 5,
}


def _same(row, s):
    """The campaign row holds the Score ``s`` (NaN for None)."""
    def nan(x):
        return math.nan if x is None else float(x)

    assert (row["detected"], row["missed"], row["isolated"], row["isolation_correct"], row["false_alarms"]) == (
        bool(s.detected), bool(s.missed), s.isolated, s.isolation_correct, int(s.false_alarms))
    for col, v in (("detection_delay", s.detection_delay), ("isolation_delay", s.isolation_delay),
                   ("correct_fraction", s.correct_fraction), ("fault_free_hours", s.fault_free_hours)):
        np.testing.assert_equal(row[col], nan(v))


def test_linear_rows_equal_compare_evaluators():
    from fdikit.compare import score_run
    from fdikit.faults import Bias, FaultScenario
    from fdikit.simulate import simulate
    from fdikit.studies.path1996.compare import fit_comparison_evaluator

    spec = load_campaign(LINEAR)
    study = get_study("path-linear")
    setup = study.setup(spec)
    runs = plan_runs(spec)
    levels = sweep_levels(spec.sweep)
    rows = study.run_chunk(setup, spec, runs, levels)
    assert [(r["run"], r["evaluator"]) for r in rows] == [(k, e["name"]) for k in (0, 1) for e in LINEAR["evaluators"]]

    # the study's side, from the campaign's seeds: calibration (spawn key (0, 1)), training runs (0, 2)
    plant = setup["plants"]["report"]
    gen, groups = plant.designs["bank"]
    nominal = setup["nominal"]
    calib = simulate(plant.model, duration=60.0, measurement_noise_std=plant.noise,
                     rng=np.random.default_rng(np.random.SeedSequence(5, spawn_key=(0, 1))))
    healthy = gen.run(calib).slice(start=10.0, stop=60.0)
    labels = [None, *plant.model.faults]
    seeds = np.random.default_rng(np.random.SeedSequence(5, spawn_key=(0, 2))).integers(2**31, size=len(labels))
    labelled = []
    for f, s in zip(labels, seeds):
        faults = [] if f is None else [Bias(f.rsplit("_", 1)[0], nominal[f], onset=5.0, location=f.rsplit("_", 1)[1])]
        tr = simulate(plant.model, FaultScenario(faults), duration=20.0, measurement_noise_std=plant.noise, rng=int(s))
        labelled.append((tr, gen.run(tr)))
    keys = {"glr": "glr", "sprt-w": "sprt-whitened", "mhsprt": "mhsprt", "ml": "gaussian-ml"}
    fitted = {name: fit_comparison_evaluator(key, healthy, groups, labelled, onset=5.0) for name, key in keys.items()}
    for run in runs:
        faults = [] if run.healthy else [Bias("yaw_rate", nominal["yaw_rate_sensor"], onset=5.0, location="sensor")]
        trace = simulate(plant.model, FaultScenario(faults), duration=10.0, measurement_noise_std=plant.noise,
                         rng=run.seed)
        scores = score_run(fitted, trace, gen.run(trace))
        mine = {r["evaluator"]: r for r in rows if r["run"] == run.run}
        for name in keys:
            _same(mine[name], scores[name])
    faulty = {r["evaluator"]: r for r in rows if r["run"] == 1}
    assert faulty["glr"]["detected"] and faulty["mhsprt"]["isolation_correct"]
    # GLR: its statistic over each block's threshold; level 1 is the nominal test, so the delay is the detection's
    assert faulty["glr"]["sweep_delay"][levels.index(1.0)] == pytest.approx(faulty["glr"]["detection_delay"], abs=1e-12)
    # SPRT (restarts) and the learned ones: no scalable statistic, NaN delays and zero counts
    for name in ("sprt-w", "mhsprt", "ml"):
        assert np.isnan(faulty[name]["sweep_delay"]).all() and faulty[name]["sweep_false_alarms"] == [0, 0, 0]


def test_nonlinear_rows_equal_the_nonlinear_table():
    from fdikit.decision import ThresholdEvaluator
    from fdikit.metrics import score
    from fdikit.studies.path1996.nonlinear_evaluation import fault_run
    from fdikit.studies.path1996.nonlinear_table import FAULTS, whitened_mhsprt

    spec = load_campaign(NONLINEAR)
    study = get_study("path-nonlinear")
    setup = study.setup(spec)
    runs = plan_runs(spec)
    rows = study.run_chunk(setup, spec, runs, sweep_levels(spec.sweep))
    from dataclasses import replace

    from fdikit.batch import run_generator_batch
    from fdikit.residuals import Residuals

    es = setup["evaluation"]
    gen = es.generators["game"]
    one, bare = replace(es, generators={"game": gen}), replace(es, generators={})  # fault_run runs the set-up's banks
    # path_evaluation_table's fits (threshold 5 of 10 at 1/h; whitened MHSSPRT) on the campaign's calibration hour
    # (here 30 s, spawn key (0, 1); cut where the campaign cuts it) and training runs (spawn key (0, 2); their
    # residuals batched, as the campaign computes them: a ResidualGenerator.run of the game bank costs ~1 s of set-up
    # per call, and the batch equals it to rounding — checked below on the test runs)
    calib = fault_run(one, None, "rough", duration=30.0, rng=np.random.SeedSequence(3, spawn_key=(0, 1)))
    healthy = calib.residuals["game"].slice(start=2.0, stop=30.0)
    seeds = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(0, 2))).integers(2**31, size=len(FAULTS))
    traces = [fault_run(bare, f, "rough", duration=4.0, rng=int(s)).trace for f, s in zip(FAULTS, seeds)]
    batch = run_generator_batch(gen, traces)
    labelled = [(f, Residuals(tr.t, r, gen.residuals, gen.isolates)) for f, tr, r in zip(FAULTS, traces, batch)]
    fitted = {"threshold": ThresholdEvaluator(groups=es.banks["game"].groups, persistence=(5, 10)).fit(
        healthy, false_alarms_per_hour=1), "mhsprt-w": whitened_mhsprt(healthy, labelled)}
    for run in runs:
        fault = None if run.healthy else run.fault
        done = fault_run(one, fault, "rough", duration=4.0, rng=run.seed)
        scale = np.abs(done.residuals["game"].r).max()
        np.testing.assert_allclose(run_generator_batch(gen, [done.trace])[0], done.residuals["game"].r, rtol=0,
                                   atol=1e-9 * scale)
        mine = {r["evaluator"]: r for r in rows if r["run"] == run.run}
        for name, ev in fitted.items():
            _same(mine[name], score(done.trace, ev.run(done.residuals["game"])))
    assert [r["fault"] for r in rows] == ["none", "none", "yaw_rate_sensor", "yaw_rate_sensor"]
    assert any(r["detected"] for r in rows if r["run"] == 1)


def _problems(spec: dict) -> list[str]:
    return get_study(spec["study"]).check(CampaignSpec.model_validate(spec))


def test_check_reports_bad_evaluators_designs_roads():
    bad = dict(LINEAR, evaluators=[{"name": "a", "kind": "glrr"}, {"name": "b", "kind": "glr", "params": {"window": 0}},
                                   {"name": "c", "kind": "sprt", "params": {"alpha": 0.7, "shfit": 1}},
                                   {"name": "d", "kind": "mhsprt-whitened"},
                                   {"name": "e", "kind": "threshold", "params": {"calibration": 60.0, "drop": 40.0}}])
    got = _problems(bad)
    assert got[0].startswith("evaluators.0.kind: unknown evaluator 'glrr'; choose from: threshold, cusum, glr")
    assert "evaluators.1.params.window: must be an integer >= 1, got 0" in got
    assert any(p.startswith("evaluators.2.params.shfit: unknown parameter; sprt takes: shift, alpha") for p in got)
    assert any(p.startswith("evaluators.3.kind: path-linear has no evaluator 'mhsprt-whitened'") for p in got)
    assert any(p.startswith("evaluators.4.params.calibration: 60.0 s leaves too little") for p in got)
    bad = dict(NONLINEAR, plants=[{"name": "gravel"}], designs=[{"name": "uio"}],
               evaluators=[{"name": "bnn"}, {"name": "s", "kind": "sprt", "params": {"alpha": 0.7}}])
    got = _problems(bad)
    road = "plants.0.params.road: unknown road 'gravel'; choose from: smooth, rough (or name the plant after its road)"
    assert road in got
    assert "designs.0.kind: unknown design 'uio'; choose from: beard-jones, game, kalman" in got
    assert any(p.startswith("evaluators.0.kind: path-nonlinear has no evaluator 'bnn'") for p in got)
    assert "evaluators.1.params.alpha: must be a probability in (0, 0.5), got 0.7" in got
    assert _problems(LINEAR) == [] and _problems(NONLINEAR) == []


def test_shipped_specs_load():
    compare = load_campaign("compare-evaluators")
    assert [p.params["noise"] for p in compare.plants] == ["realistic", "report"]
    assert [e.kind for e in compare.evaluators] == ["threshold", "cusum", "glr", "sprt", "cusum-whitened",
                                                    "glr-whitened", "sprt-whitened", "mhsprt", "gaussian-ml", "bnn"]
    assert len(plan_runs(compare)) == 2 * (5 + 2 * 15)
    nonlinear = load_campaign("path-nonlinear")
    assert [p.params["road"] for p in nonlinear.plants] == ["smooth", "rough"]
    assert [d.kind for d in nonlinear.designs] == ["beard-jones", "game", "kalman"]
    assert len(plan_runs(nonlinear)) == 2 * (180 + 15) and nonlinear.healthy * nonlinear.duration == 3600.0


@pytest.mark.parametrize("criterion, noise", [(None, "report"), ("gap", "realistic")])
def test_linear_campaign_runs_the_nullspace_bank(criterion, noise):
    # the efdisyn bank as a design kind: the set-up's generator is path_nullspace_bank's for the plant's noise.
    # criterion 'gap' at realistic noise (at the report's 1e-4 of a nominal fault afdsyn's rank test, 1e-7 in the
    # model's units, counts the yaw-rate row's noise as absent and the gap design is refused)
    from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14
    from fdikit.studies.path1996.nullspace_bank import path_nullspace_bank

    design = {"name": "ns", "kind": "nullspace", **({"params": {"criterion": criterion}} if criterion else {})}
    spec = load_campaign({**LINEAR, "plants": [{"name": "p", "params": {"noise": noise}}], "designs": [design],
                          "evaluators": [{"name": "glr", "kind": "glr", "params": {"calibration": 60.0}}]})
    study = get_study("path-linear")
    assert study.check(spec) == []
    setup = study.setup(spec)
    plant = setup["plants"]["p"]
    gen, groups = plant.designs["ns"]
    std = dict(zip(plant.model.outputs, plant.noise))
    ref = path_nullspace_bank((path_vehicle_12("midpoint"), path_vehicle_14("midpoint")), setup["nominal"],
                              noise_std=std, dt=0.01, criterion=criterion or "variance")
    assert gen.residuals == ref.generator.residuals and groups == ref.groups
    np.testing.assert_allclose(gen.D, ref.generator.discretize(0.01).D, rtol=1e-12, atol=1e-12)
    if criterion is None:
        rows = study.run_chunk(setup, spec, plan_runs(spec), sweep_levels(spec.sweep))
        assert len(rows) == 2 and all(r["design"] == "ns" for r in rows)
