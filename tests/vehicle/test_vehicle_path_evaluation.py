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
    mags = group_magnitudes(run.residuals["beard-jones"])  # the report's filters, as §5.1.1 checks them
    own = [g for g in mags if g.endswith(":" + fault)]
    for g in own:
        # scaled on the linear model to 1; the car is nonlinear, the fault small: within 10 %
        assert abs(mags[g][-200:].mean() - 1.0) < 0.10, g
        # the other residuals of the same filter stay below the report's 0.25 (the isolation it relies on)
        filt = g.split(":")[0]
        others = [h for h in mags if h.startswith(filt + ":") and h not in own]
        assert max(mags[h][-200:].mean() for h in others) < 0.25


def test_off_nominal_throttle_against_the_report(setup):
    peaks = off_nominal_peaks(setup, bank="beard-jones")
    # the report: every scaled residual < 0.25 in the +2° off-nominal run.  Met by filters 2 and 3, filter 1's
    # engine-speed and pitch-rate groups and filter 4's throttle group; not met by filter 1's lateral (0.26) and
    # vertical (2.6) accelerometer groups and filter 4's brake, steering and air-mass groups: the numbers are in
    # docs/methods/nonlinear_vehicle.md.
    met = [g for g in peaks if g.split(":")[0] in ("filter2", "filter3")] + [
        "filter1:engine_speed_sensor", "filter1:pitch_rate_sensor", "filter4:throttle_actuator"]
    assert max(peaks[g] for g in met) < 0.25
    assert len(peaks) == 16


def test_reduced_table_all_banks(setup):
    # the same runs through the three banks
    faults = ["yaw_rate_sensor", "pitch_rate_sensor", "accel_x_sensor", "throttle_actuator"]
    table = path_evaluation_table(setup, roads=("rough",), faults=faults, fault_free_hours=0.1, seed=3,
                                  processors=["threshold", "mhsprt-whitened"])
    rows = {(r.bank, r.fault, r.processor): r for r in table.rows}
    for bank in ("game", "kalman"):
        for f in faults:
            r = rows[(bank, f, "MHSSPRT, whitened")]
            assert r.detected and r.isolated, r
    # thresholds for 1 false alarm per hour: over 0.1 h a Poisson count of mean 0.1 exceeds 2 with p ≈ 1.5e-4; the
    # whitened MHSSPRT's F_T is set on a fault-free run of the same length, so it is held to the same bound
    for bank in ("beard-jones", "game", "kalman"):
        for proc in ("threshold (5 of 10)", "MHSSPRT, whitened"):
            n, hours = table.false_alarms[("rough", bank, proc)]
            assert 0.09 < hours <= 0.101 and n <= 2, (bank, proc, n)
    # at realistic noise the report's Beard–Jones bank with thresholds misses the pitch-rate and accelerometer biases
    assert not rows[("beard-jones", "pitch_rate_sensor", "threshold (5 of 10)")].detected
    assert table.counts()[("rough", "game", "MHSSPRT, whitened")] == (4, 4, 4)
    assert table.counts()[("rough", "kalman", "MHSSPRT, whitened")] == (4, 4, 4)


def test_game_bank_attenuates_the_noise_the_beard_jones_bank_amplifies(setup):
    # fault-free rms of each scaled residual group (nominal fault = 1) on the smooth road with sensor noise
    run = fault_run(setup, None, "smooth", duration=60.0, rng=5)
    rms = {b: {g: float(np.sqrt(np.mean(m[500:] ** 2))) for g, m in group_magnitudes(run.residuals[b]).items()}
           for b in ("beard-jones", "game")}
    # the pitch-rate and vertical-accelerometer groups: measured ≈ 22 and ≈ 150 (Beard–Jones) against ≈ 0.2 and ≈ 4.5
    # (game); asserted with a factor-2 margin on each side
    assert rms["beard-jones"]["filter1:pitch_rate_sensor"] > 10 > 0.5 > rms["game"]["filter1:pitch_rate_sensor"]
    assert rms["beard-jones"]["filter1:accel_z_sensor"] > 75 > 10 > rms["game"]["filter1:accel_z_sensor"]


def test_hinf_bank_has_no_steady_state_on_the_car(setup):
    # The H∞-bounded filter of App. C on filter 1's group, outputs in units of their noise (unit-weight noise
    # inputs √Δt, actuator process noise): the Hamiltonian of (c.18) without its extra term has no eigenvalue
    # near the imaginary axis (|Re λ| ≥ 1.2, checked here independently), so the design gets past that test —
    # and the modified differential Riccati equation then escapes to infinity from the ARE start: no H∞-bounded
    # bank exists for these models and weights (docs/methods/nonlinear_vehicle.md).
    import scipy.linalg

    from fdikit.design.observers import detection_gain_family, hinf_detection_filter
    from fdikit.errors import DesignError
    from fdikit.fault_maps import resolve_faults
    from fdikit.model import FaultModel
    from fdikit.studies.path1996.bank import FILTER_GROUPS
    from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD

    base, dt = setup.models.model12, 0.01
    scale = np.array([1.0 / NOISE_STD[o] for o in base.outputs])
    model = FaultModel(A=base.A, Bu=base.Bu, C=scale[:, None] * base.C, Du=scale[:, None] * base.Du,
                       Bw=np.hstack([np.zeros((base.n, 12)), base.Bu]),
                       Dw=np.hstack([np.eye(12) * np.sqrt(dt), np.zeros((12, 3))]), states=base.states,
                       outputs=base.outputs, controls=base.controls,
                       noise=[f"v_{o}" for o in base.outputs] + [f"w_{c}" for c in base.controls])
    maps = resolve_faults(model, FILTER_GROUPS["filter1"])
    fam = detection_gain_family(model, maps)
    # (c.17)–(c.18) data by hand (corrected form, γ = 10): Â = A + L̂C, B̂ = B + L̂D, the Hamiltonian of the ARE
    g2, T = 10.0 ** -2, fam.coordinates
    Lh = -fam.base_gain
    Ah, Bh = model.A + Lh @ model.C, model.Bw + Lh @ model.Dw
    C2, D21 = T @ model.C, T @ model.Dw
    k = sum(H.shape[0] for H in fam.residual_maps.values())
    Cz, Dz = C2[:k], D21[:k]
    Vt = D21 @ D21.T + g2 * D21 @ Dz.T @ Dz @ D21.T
    Ct = C2 + g2 * D21 @ Dz.T @ Cz
    Bt = Bh @ (D21.T + g2 * Dz.T @ Dz @ D21.T)
    Vi = np.linalg.inv(Vt)
    At = Ah + g2 * Bh @ Dz.T @ Cz - Bt @ Vi @ Ct
    Qt = Bh @ Bh.T + g2 * Bh @ Dz.T @ Dz @ Bh.T - Bt @ Vi @ Bt.T
    Rt = Ct.T @ Vi @ Ct - g2 * Cz.T @ Cz
    ham = np.block([[At.T, -Rt], [-Qt, -At]])
    assert np.abs(scipy.linalg.eigvals(ham).real).min() > 1.0
    with pytest.raises(DesignError, match="escapes to infinity"):
        hinf_detection_filter(model, maps, gamma=10.0)
