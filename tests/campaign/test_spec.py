"""The campaign spec: every mistake reported at once, by its place; the shipped specs load; the plan is reproducible."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fdikit.campaign.plan import plan_run, plan_runs
from fdikit.campaign.spec import CampaignSpec, load_campaign, spec_fingerprint, sweep_levels
from fdikit.campaign.studies import shipped_specs
from fdikit.errors import DataError, ParameterError

BASE = {
    "name": "t", "study": "path-linear", "seed": 3, "duration": 20.0, "plants": [{"name": "linear"}],
    "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor", "roll_rate_sensor"], "size": {"values": [0.5, 1.0]},
                "onset": {"uniform": [4.0, 8.0]}}],
    "healthy": 3, "designs": [{"name": "kalman", "kind": "kalman"}], "evaluators": [{"name": "threshold"}],
    "chunk_size": 4,
}


def _with(**changes) -> dict:
    return {**BASE, **changes}


def test_every_error_reported_at_once_by_its_place():
    bad = _with(duration=-1, faults=[{"kind": "bias", "size": {"uniform": [2.0, 1.0]}, "onset": {"values": []}}],
                designs=[{"name": "a b"}], evaluators=[{"name": "t", "kind": "threshold", "param": {}}])
    with pytest.raises(ParameterError) as exc:
        load_campaign(bad)
    msg = str(exc.value)
    for where in ("duration: Input should be greater than 0", "faults.0.size: ", "low 2.0 is above high 1.0",
                  "faults.0.onset: ", "values is empty", "designs.0.name: ", "evaluators.0.param: unknown entry"):
        assert where in msg, (where, msg)


def test_study_checks_names_and_parameters():
    bad = _with(plants=[{"name": "linear", "params": {"noise": "loud", "speed": 3}}],
                faults=[{"kind": "stuck", "targets": ["yaw_rate"]}],
                designs=[{"name": "b", "kind": "beard-jonse"}],
                evaluators=[{"name": "t", "kind": "threshold", "params": {"persistence": [11, 10]}},
                            {"name": "c", "kind": "cumsum"}])
    with pytest.raises(ParameterError) as exc:
        load_campaign(bad)
    msg = str(exc.value)
    for where in ("plants.0.params.noise: 'loud' is neither realistic nor report",
                  "plants.0.params.speed: unknown parameter", "faults.0.kind: unknown fault kind 'stuck'",
                  "faults.0.targets: unknown fault 'yaw_rate'", "designs.0.kind: unknown design 'beard-jonse'",
                  "evaluators.0.params.persistence: must be [k, n] with 1 <= k <= n",
                  "evaluators.1.kind: unknown evaluator 'cumsum'"):
        assert where in msg, (where, msg)


@pytest.mark.parametrize("change, text", [
    ({"faults": [{"kind": "bias", "onset": {"values": [25.0]}}]}, "not before the end of the run"),
    ({"faults": [], "healthy": 0}, "no runs"),
    ({"sampling": {"random": {"runs": 5}}, "healthy": 2}, "0 <= healthy < 1"),
    ({"healthy": 1.5}, "a number of runs per plant"),
    ({"designs": [{"name": "k", "kind": "kalman"}, {"name": "k", "kind": "kalman"}]}, "['k'] appear more than once"),
    ({"sweep": {"low": 1.5, "high": 3.0}}, "must contain 1"),
    ({"study": "nope"}, "study 'nope' is not registered"),
])
def test_bad_entries(change, text):
    with pytest.raises(ParameterError, match=None) as exc:
        load_campaign(_with(**change))
    assert text in str(exc.value)


def test_files(tmp_path):
    with pytest.raises(DataError, match="does not exist; give a YAML file or one of the shipped specs: .*path-linear"):
        load_campaign(tmp_path / "missing.yaml")
    (tmp_path / "bad.yaml").write_text("name: [unclosed\n")
    with pytest.raises(DataError, match="is not valid YAML"):
        load_campaign(tmp_path / "bad.yaml")
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(DataError, match="must be a YAML mapping"):
        load_campaign(tmp_path / "list.yaml")
    (tmp_path / "typo.yaml").write_text("name: x\nstudy: path-linear\nduration: 1\nplants: [{name: a}]\nhealthy: 1\n"
                                        "designs: [{name: kalman}]\nevaluators: [{name: threshold}]\nseeed: 3\n")
    with pytest.raises(ParameterError, match=r"typo.yaml is not valid:\n  seeed: unknown entry"):
        load_campaign(tmp_path / "typo.yaml")


def test_shipped_specs_load():
    specs = shipped_specs()
    assert "path-linear" in specs
    for name, path in specs.items():
        spec = load_campaign(path)
        assert spec.name == name
        assert plan_runs(spec)


def test_sweep_levels_log_spaced_with_one():
    levels = sweep_levels(CampaignSpec.model_validate(BASE).sweep)
    assert levels[0] == 0.5 and levels[-1] == 4.0 and 1.0 in levels
    ratios = np.diff(np.log(levels))
    assert np.all(ratios > 0)


def test_grid_plan_counts_order_and_seeds():
    spec = CampaignSpec.model_validate(_with(sampling={"grid": {"repeats": 2}}))
    plan = plan_runs(spec)
    assert len(plan) == 3 + 2 * 2 * 2  # healthy + targets × sizes × repeats (onset drawn per run)
    assert [p.fault for p in plan[:3]] == ["none"] * 3 and all(math.isnan(p.onset) for p in plan[:3])
    assert [(p.fault, p.size) for p in plan[3:7]] == [("yaw_rate_sensor", 0.5)] * 2 + [("yaw_rate_sensor", 1.0)] * 2
    assert all(4.0 <= p.onset <= 8.0 for p in plan[3:])
    assert [p.chunk for p in plan] == [k // 4 for k in range(len(plan))]
    assert len({p.seed for p in plan}) == len(plan)
    # each run derives from the spec and its index alone: its own SeedSequence stream
    for k in (0, 5, len(plan) - 1):
        assert plan_run(spec, k) == plan[k]
        rng = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(k,)))
        if not plan[k].healthy:
            assert plan[k].onset == rng.uniform(4.0, 8.0)
        assert plan[k].seed == int(rng.integers(2**63))


def test_random_plan_is_prefix_stable_and_fractions_hold():
    spec = CampaignSpec.model_validate(_with(sampling={"random": {"runs": 2000}}, healthy=0.25))
    plan = plan_runs(spec)
    more = plan_runs(CampaignSpec.model_validate(_with(sampling={"random": {"runs": 2100}}, healthy=0.25)))
    assert more[:2000] == plan  # adding runs never changes the earlier ones
    healthy = sum(p.healthy for p in plan)
    # binomial(2000, 0.25): sd = 19.4; 5 sd
    assert abs(healthy - 500) < 5 * math.sqrt(2000 * 0.25 * 0.75)
    sizes = {p.size for p in plan if not p.healthy}
    assert sizes <= {0.5, 1.0}


def test_fingerprint_changes_with_the_spec():
    a = CampaignSpec.model_validate(BASE)
    b = CampaignSpec.model_validate(_with(seed=4))
    assert spec_fingerprint(a) != spec_fingerprint(b)
    assert spec_fingerprint(a) == spec_fingerprint(CampaignSpec.model_validate(BASE))


def test_plan_run_out_of_range():
    spec = CampaignSpec.model_validate(BASE)
    with pytest.raises(ParameterError, match="run 99 is not in the campaign: it has 7 runs"):
        plan_run(spec, 99)
