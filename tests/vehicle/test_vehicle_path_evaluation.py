"""The Ch. 5 evaluation on the nonlinear car (Douglas et al. 1996, §5.1): setup, scaling, a reduced table."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.studies.path1996.nonlinear_evaluation import (
    evaluation_setup,
    fault_run,
    group_magnitudes,
    off_nominal_peaks,
)
from fdikit.studies.path1996.nonlinear_table import path_evaluation_table


@pytest.fixture(scope="module")
def setup():
    return evaluation_setup()


def test_nominal_sizes_follow_section_5_1_1(setup):
    n = setup.nominal
    assert len(n) == 15
    assert (n["throttle_actuator"], n["steering_actuator"], n["yaw_rate_sensor"]) == (2.0, 0.001, 0.02)
    assert n["accel_x_sensor"] == n["accel_y_sensor"] == n["accel_z_sensor"] > 0
    # the brake torque that slows the car from 25 to 21 m/s: checked by trimming with it
    car, op = setup.car, setup.operating_point
    at25 = car.operating_point(speed=25.0, steering=op.u[2])
    braked = car.operating_point(throttle=at25.u[0], brake=n["brake_actuator"], steering=op.u[2])
    assert abs(braked.speed - 21.0) < 1e-3


@pytest.mark.parametrize("fault", ["yaw_rate_sensor", "accel_z_sensor", "engine_speed_sensor"])
def test_a_nominal_sensor_fault_drives_its_own_residual_to_one_on_the_nonlinear_car(setup, fault):
    run = fault_run(setup, fault, "smooth", duration=12.0, noise=False)
    mags = group_magnitudes(run.residuals, setup.bank)
    own = [g for g in mags if g.endswith(":" + fault)]
    for g in own:
        # scaled on the linear model to 1; the car is nonlinear, the fault small: within 10 %
        assert abs(mags[g][-200:].mean() - 1.0) < 0.10, g
        # the other residuals of the same filter stay below the report's 0.25 (the isolation it relies on)
        filt = g.split(":")[0]
        others = [h for h in mags if h.startswith(filt + ":") and h not in own]
        assert max(mags[h][-200:].mean() for h in others) < 0.25


def test_off_nominal_throttle_against_the_report(setup):
    peaks = off_nominal_peaks(setup, duration=30.0)
    # the report: every scaled residual < 0.25 in the +2° off-nominal run.  Met by the sensor filters except the
    # vertical accelerometer of filter 1; not met in filter 4 (brake, steering, air mass): docs/methods/
    # nonlinear_vehicle.md gives the numbers.
    met = [g for g in peaks if g.split(":")[0] in ("filter2", "filter3")] + [
        "filter1:engine_speed_sensor", "filter1:accel_y_sensor", "filter1:pitch_rate_sensor",
        "filter4:throttle_actuator"]
    assert max(peaks[g] for g in met) < 0.25
    assert len(peaks) == 16


def test_reduced_table_runs_and_scores(setup):
    table = path_evaluation_table(setup, roads=("smooth",), faults=["yaw_rate_sensor", "engine_speed_sensor"],
                                  fault_free_hours=0.1, seed=3)
    rows = {(r.fault, r.processor): r for r in table.rows}
    for f in ("yaw_rate_sensor", "engine_speed_sensor"):
        assert rows[(f, "MHSSPRT")].detected and rows[(f, "MHSSPRT")].isolated
        assert rows[(f, "threshold (5 of 10)")].detected
    # thresholds set for 1 false alarm per hour: over 0.1 h a Poisson count of mean 0.1 exceeds 2 with p ≈ 1.5e-4
    n, hours = table.false_alarms[("smooth", "threshold (5 of 10)")]
    assert 0.09 < hours <= 0.101 and n <= 2
    assert np.isfinite(table.rate("smooth", "MHSSPRT"))
