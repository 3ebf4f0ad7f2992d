"""Reduced §6.5 B747 flights: isolation, reconfiguration and the comparison with the fixed autopilot.

Flights of 34–50 s (the full 300-s plan is `fdikit ftc`; docs/methods/ftc.md has its figures). Each
comparison bound lies between the ranges measured over seeds 11–27 for the reconfigured flights and for the
fixed autopilot (docs/methods/ftc.md), not at one flight's value.
"""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.studies.hallouzi2008.b747_ftc import T_INJECT, ftc_setup, scenario_fault
from fdikit.studies.hallouzi2008.b747_ftc_flight import fly_ftc


@pytest.fixture(scope="module")
def setup():
    return ftc_setup(calibration_seconds=60.0)


def test_elevator_lock_is_isolated_and_the_stabilizer_takes_over(setup):
    ftc = fly_ftc(setup, "elevator", duration=50.0, seed=1)
    ap = fly_ftc(setup, "elevator", controller="autopilot", duration=50.0, seed=1)
    group, model, t_iso = ftc.declared
    assert group == "elevator" and T_INJECT < t_iso < 50.0         # thesis: 28 s; 17 seeds: 21–59 s, median 35
    assert ftc.configuration[-1] == "elevator" and ftc.lost is None
    # The stabilizer moved (the SPC's pitch input now); the fixed autopilot cannot counter the lock's moment.
    assert np.ptp(ftc.surfaces[ftc.t > t_iso, 2]) > 0.5
    e, e_ap = ftc.errors(40.0), ap.errors(40.0)
    assert e["pitch_rms"] < 8.0 < e_ap["pitch_rms"]               # 17 seeds: 0.2–5.8°; autopilot 10–11°
    assert ftc.errors()["beta_rms"] < 3.0
    assert ftc.qp.get("solved", 0) >= 0.9 * sum(ftc.qp.values())


def test_rudder_runaway_reconfigured_keeps_the_heading(setup):
    # The configuration switch apart from the isolation: at the thesis's 22 s, to the rudder +25° model.
    ftc = fly_ftc(setup, "rudder", duration=50.0, seed=1, isolation=("rudder_lip_+25", 22.0))
    ap = fly_ftc(setup, "rudder", controller="autopilot", duration=50.0, seed=1)
    assert ftc.declared[:2] == ("rudder", "rudder_lip_+25") and ftc.configuration[-1] == "rudder"
    assert ftc.surfaces[-1, 3] == pytest.approx(25.0, abs=0.1)    # the rudder stays hard over
    left, right = ftc.throttles[-100:, 0].mean(), ftc.throttles[-100:, 2].mean()
    # +25° rudder yaws the nose left (JSBSim: ∂ṙ/∂δr < 0); the left engines push it back to the right
    assert left - right > 0.3
    e, e_ap = ftc.errors(40.0), ap.errors(40.0)
    assert e["heading_max"] < 30.0 < e_ap["heading_max"]          # 11 correct isolations: 7–22°; autopilot 44–66°
    assert ftc.lost is None


def test_rudder_runaway_is_declared_by_the_imm(setup):
    # Declared in 8 of 8 seeds by 33 s, but named the elevator in 3 of them (docs/methods/ftc.md): the
    # group is not asserted.
    run = fly_ftc(setup, "rudder", duration=34.0, seed=1)
    assert run.declared is not None and T_INJECT < run.declared[2] < 34.0
    assert run.mu[0, -1] > 0.9                                     # the nominal model at the start


def test_bijlmerramp_flown_without_fdi(setup):
    run = fly_ftc(setup, "bijlmer", duration=35.0, seed=1)
    assert run.declared is None and set(run.configuration) == {"unanticipated"} and run.lost is None
    e = run.errors(25.0)                                            # thesis: control regained after ≈ 15 s
    assert e["altitude_max"] < 60.0 and e["beta_rms"] < 3.0 and np.abs(run.y[run.t >= 25.0, 0]).max() < 15.0


def test_bad_arguments(setup):
    with pytest.raises(ParameterError, match="scenario"):
        fly_ftc(setup, "spoiler")
    with pytest.raises(ParameterError, match="isolation"):
        fly_ftc(setup, "rudder", isolation=("rudder_lip_+3", 20.0))
    assert scenario_fault("nominal") == []
