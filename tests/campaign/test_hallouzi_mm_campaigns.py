"""The target-tracking and multiple-model campaign studies against the existing Hallouzi 2008 study code.

Each row of a run must be what the study's own functions compute for the run's plan seed: the same code
path, so the figures are compared exactly (the MSE metrics, squares of square roots, to a few ulps).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fdikit.campaign.plan import plan_runs
from fdikit.campaign.spec import CampaignSpec, load_campaign
from fdikit.campaign.studies import get_study, shipped_specs
from fdikit.errors import ParameterError

LEVELS = [0.5, 1.0, 2.0]


def _spec(data: dict) -> CampaignSpec:
    return CampaignSpec.model_validate(data)


# ------------------------------------------------------------------ target tracking (§2.4.2)
TT = {"name": "tt", "study": "target-tracking", "seed": 5, "duration": 160.0,
      "plants": [{"name": "target"}], "healthy": 2,
      "designs": [{"name": "imm", "kind": "imm"}], "evaluators": [{"name": "rmse"}]}


def test_target_tracking_rows_equal_the_study_monte_carlo():
    from fdikit.studies.hallouzi2008.target_tracking import INTERVALS, target_tracking_monte_carlo

    spec = load_campaign(TT)
    study = get_study("target-tracking")
    plan = plan_runs(spec)
    rows = study.run_chunk(study.setup(spec), spec, plan, LEVELS)
    assert [(r["run"], r["design"], r["evaluator"], r["fault"]) for r in rows] == [
        (0, "imm", "rmse", "none"), (1, "imm", "rmse", "none")]
    sq = {q: [] for q in ("position", "velocity", "B")}
    for row, p in zip(rows, plan):
        ref = target_tracking_monte_carlo(runs=1, seed=p.seed, n_samples=160, filters=("imm",))
        m = json.loads(row["metrics"])
        assert row["seed"] == p.seed and not row["detected"] and row["fault_free_hours"] == 0.0
        assert all(math.isnan(v) for v in row["sweep_delay"]) and row["sweep_false_alarms"] == [0, 0, 0]
        for name in ("straight_1", "left_half"):
            for q in ("position", "velocity", "B"):
                assert m[f"{q}_rmse_{name}"] == ref.summary["imm"][name][q]
        assert "position_rmse_straight_2" not in m  # interval beyond the 160-sample run
        assert m["chatter"] == ref.chatter["imm"]
        for q, c in (("position", ref.rmse_position), ("velocity", ref.rmse_velocity), ("B", ref.rmse_B)):
            sq[q].append(c["imm"] ** 2)
    # the campaign's mean of the MSE metrics = the interval mean of the squared Monte-Carlo RMSE of those runs
    for q, curves in sq.items():
        rmse2 = np.mean(curves, axis=0)  # RMSE_k² (2.64) over the two runs
        for name in ("straight_1", "left_half"):
            a, b = INTERVALS[name]
            mean = np.mean([json.loads(r["metrics"])[f"{q}_mse_{name}"] for r in rows])
            assert mean == pytest.approx(rmse2[a:b + 1].mean(), rel=1e-12)


def test_target_tracking_check_rejects_bad_names():
    bad = {**TT, "plants": [{"name": "target", "kind": "radar", "params": {"noise": 1}}],
           "faults": [{"kind": "bias"}], "duration": 160.5,
           "designs": [{"name": "x", "kind": "kalman"}, {"name": "c", "kind": "dual_cmf", "params": {"lam": 2.0}}],
           "evaluators": [{"name": "t", "kind": "threshold"}]}
    with pytest.raises(ParameterError) as exc:
        load_campaign(bad)
    text = str(exc.value)
    for where in ("plants.0.kind", "plants.0.params.noise", "faults.0", "duration", "designs.0.kind: unknown design "
                  "'kalman'", "designs.1.params.lam", "evaluators.0.kind: unknown evaluator 'threshold'"):
        assert where in text


# ------------------------------------------------------------------ multiple-model (§2.4.1, §3.3.1, §3.6.2)
MM = {"name": "mm", "study": "multiple-model", "seed": 3, "duration": 100.0,
      "plants": [{"name": "b747", "kind": "b747"}, {"name": "msd", "kind": "msd"},
                 {"name": "ex", "kind": "example-3-1"}],
      "faults": [{"kind": "table-2.6"}, {"kind": "loss", "size": {"values": [0.5]}}], "healthy": 1,
      "designs": [{"name": "imm", "kind": "imm"}, {"name": "lv", "kind": "lv"}, {"name": "pairs", "kind": "pairs"}],
      "evaluators": [{"name": "mp", "kind": "most-probable"}, {"name": "wt", "kind": "weight-threshold"},
                     {"name": "fs", "kind": "fault-size"}, {"name": "c", "kind": "conditioning"}]}


@pytest.fixture(scope="module")
def mm():
    spec = load_campaign(MM)
    study = get_study("multiple-model")
    return spec, study, study.setup(spec), plan_runs(spec)


def test_multiple_model_plan_puts_each_fault_on_its_plant(mm):
    spec, _, _, plan = mm
    assert [(p.plant, p.fault) for p in plan] == [
        ("b747", "none"), ("b747", "delta_c_loss"), ("b747", "delta_s_loss"), ("b747", "V_TAS_sensor"),
        ("b747", "alpha_sensor"), ("msd", "none"), ("msd", "u1_actuator"), ("msd", "x2_sensor"), ("ex", "none")]


def test_b747_row_equals_the_study(mm):
    from fdikit.metrics import score
    from fdikit.multimodel.isolation import GroupThresholdLogic, mode_diagnosis
    from fdikit.plants.b747 import B747_MODEL_NAMES
    from fdikit.studies.hallouzi2008.b747 import INTERVALS, b747_monte_carlo, b747_weight_profile

    spec, study, setup, plan = mm
    run = plan[2]  # delta_s_loss: scored on samples 301-500, onset 4.0 s
    rows = study.run_chunk(setup, spec, [run], LEVELS)
    assert [(r["design"], r["evaluator"]) for r in rows] == [("imm", "mp"), ("imm", "wt")]
    ref = b747_monte_carlo(runs=1, seed=run.seed, filters=("imm",))
    mu, labels = ref.mean_weights["imm"][301:501], b747_weight_profile()[1][301:501]
    t = ref.t[301:501]
    mp = score(labels, mode_diagnosis(t, mu, B747_MODEL_NAMES))
    logic = GroupThresholdLogic(groups={n: [i] for i, n in enumerate(B747_MODEL_NAMES) if i}, nominal=0)
    wt = score(labels, mode_diagnosis(t, mu, B747_MODEL_NAMES, logic=logic))
    for row, s in zip(rows, (mp, wt)):
        assert (row["size"], row["onset"], row["detected"], row["isolated"], row["false_alarms"]) == (
            0.4, 4.0, s.detected, s.isolated, s.false_alarms)
        assert row["detection_delay"] == pytest.approx(s.detection_delay if s.detected else math.nan, nan_ok=True)
        m = json.loads(row["metrics"])
        a, b = INTERVALS["delta_s_40"]
        assert m["weights_rmse_delta_s_40"] == ref.summary["imm"]["delta_s_40"]["weights"]
        assert m["state_mse_delta_s_40"] == pytest.approx(np.mean(ref.rmse_state["imm"][a:b + 1] ** 2), rel=1e-12)
    assert all(math.isnan(v) for v in rows[0]["sweep_delay"])  # the most probable model has no threshold
    # the weight-threshold sweep at level 1 is the evaluator's own alarm: same false alarms, same delay
    stat = np.abs(1 - mu[:, 0]) / 0.2
    assert rows[1]["sweep_false_alarms"][1] == wt.false_alarms
    if wt.detected:
        assert rows[1]["sweep_delay"][1] == pytest.approx(wt.detection_delay)
    assert rows[1]["sweep_false_alarms"][0] >= rows[1]["sweep_false_alarms"][2]
    assert (stat > 0).any()


def test_msd_and_example_rows_equal_the_study(mm):
    from fdikit.studies.hallouzi2008.example_3_1 import example_3_1
    from fdikit.studies.hallouzi2008.msd import simulate_msd
    from fdikit.studies.hallouzi2008.msd_model_sets import run_msd_model_set

    spec, study, setup, plan = mm
    run, ex = plan[7], plan[8]  # x2_sensor loss 0.5; one Example 3.1 model set
    rows = study.run_chunk(setup, spec, [run, ex], LEVELS)
    assert [(r["design"], r["evaluator"]) for r in rows] == [("lv", "fs"), ("pairs", "c")]
    sim = simulate_msd(seed=run.seed, duration=100.0, dt=0.01, f1_size=1.0, f2_size=0.5)
    ref = run_msd_model_set(sim, "lv")
    m = json.loads(rows[0]["metrics"])
    assert {k: m[f"vaf_{k}"] for k in ref.vaf} == ref.vaf
    assert m["f2_fault_mean"] == float(ref.params[(sim.t >= 70) & (sim.t < 80), 3].mean())
    loss = 1 - ref.params[:, 2:4]
    loss[sim.t < 5.0] = 0
    fired = (loss > 0.25).any(axis=1)
    first = sim.t[np.flatnonzero(fired & (sim.t >= 70) & (sim.t < 80))]
    assert rows[0]["onset"] == 70.0 and rows[0]["detected"] == bool(first.size)
    if first.size:
        assert rows[0]["detection_delay"] == pytest.approx(first[0] - 70.0)
    healthy = (sim.t < 70) | (sim.t >= 80)
    rises = np.flatnonzero(fired & ~np.append(False, fired[:-1]))
    assert rows[0]["false_alarms"] == int(healthy[rises].sum()) == rows[0]["sweep_false_alarms"][1]
    ref31 = example_3_1(model_sets=1, seed=ex.seed)
    m31 = json.loads(rows[1]["metrics"])
    assert m31["observability_24"] == ref31.observability[0, 4] and m31["basis_13"] == ref31.basis[0, 1]
    assert {k: m31[k] for k in ref31.frequency()} == ref31.frequency()
    assert rows[1]["fault_free_hours"] == 0.0 and not rows[1]["detected"]


def test_multiple_model_check_rejects_bad_names():
    bad = {**MM, "duration": 60.0,
           "plants": [{"name": "b747", "kind": "b474"}, {"name": "msd", "kind": "msd", "params": {"dt": 0.05}}],
           "faults": [{"kind": "stuck"}, {"kind": "table-2.6", "onset": {"values": [3.0]}},
                      {"kind": "loss", "targets": ["x3_sensor"]}],
           "designs": [{"name": "imm2", "kind": "imn"}, {"name": "cp", "kind": "cp", "params": {"grid": 3}}],
           "evaluators": [{"name": "wt", "kind": "weight-threshold", "params": {"threshold": 1.5}},
                          {"name": "c", "kind": "conditioning"}]}
    with pytest.raises(ParameterError) as exc:
        load_campaign(bad)
    text = str(exc.value)
    for where in ("plants.0.kind: unknown plant 'b474'", "plants.1.params.dt", "duration:",
                  "faults.0.kind: unknown fault kind 'stuck'", "faults.1.onset", "faults.2.targets: unknown loss "
                  "fault 'x3_sensor'", "designs.0.kind: unknown design 'imn'", "designs.1.params.grid",
                  "evaluators.0.params.threshold", "evaluators.1.kind: conditioning is for example-3-1 plants"):
        assert where in text, where


@pytest.mark.parametrize("name, runs", [("target-tracking", 100), ("multiple-model", 195)])
def test_shipped_specs_load(name, runs):
    assert name in shipped_specs()
    assert len(plan_runs(load_campaign(name))) == runs
