"""The PATH four-filter bank (Douglas et al. 1996, §4.1–4.2, §5.1.1): properties R-FDF-1, 3, 4, 6, 7 and the
single-fault isolation of all 15 faults in linear simulation."""

import numpy as np
import pytest

from fdikit.decision import ThresholdEvaluator
from fdikit.fault_maps import sensor_fault_map
from fdikit.faults import Bias, FaultScenario
from fdikit.metrics import score
from fdikit.model import sensor_fault_name
from fdikit.plants import path_vehicle_12, path_vehicle_14
from fdikit.simulate import simulate
from fdikit.studies.path1996 import FILTER_GROUPS, path_bank, path_fault_model
from fdikit.studies.path1996.bank import EIGENVALUES

W = np.logspace(-2, 3, 60)


@pytest.fixture(scope="module")
def bank():
    return path_bank()


def _design_model(name):
    base = path_vehicle_14("midpoint") if name == "filter4" else path_vehicle_12("midpoint")
    m = base.with_sensor_faults(base.outputs)
    if name != "filter4":
        return m
    # the air-mass fault of filter 4 is designed on its bias (magnitude) direction A F¹ only
    return m.with_actuator_faults(base.controls).add_faults(
        ["air_mass_bias_direction"], sensor_fault_map(base, "air_mass", "magnitude"), np.zeros((12, 1)))


def test_spectra_are_the_assigned_sets(bank):
    """R-FDF-1: eig(A − LC) (the report's A + LC) = Ξ_0 ∪ Ξ_1 ∪ … to 1e-8 relative (filter 4: throttle {−4, −9},
    steering {−6} ...)."""
    for name, d in bank.designs.items():
        sets, comp = EIGENVALUES[name]
        want = np.sort(np.concatenate([np.concatenate(sets), comp]))
        np.testing.assert_allclose(np.sort(d.poles.real), want, rtol=1e-8, atol=1e-8 * np.abs(want).max())
        assert np.abs(d.poles.imag).max() < 1e-8 * np.abs(want).max()


def test_each_residual_sees_only_its_fault(bank):
    """R-FDF-3: design fault j → residual i below −150 dB (relative) for i ≠ j over 1e-2…1e3 rad/s."""
    for name, d in bank.designs.items():
        m = _design_model(name)
        R = d.generator.internal_form(m)
        G = np.abs(R.freqresp(W, "f"))
        iso = np.array(d.generator.isolates)
        for fault in dict.fromkeys(d.generator.isolates):
            j = m.faults.index("air_mass_bias_direction" if name == "filter4" and fault == "air_mass_sensor" else fault)
            own, other = G[:, iso == fault, j].max(), G[:, iso != fault, j].max()
            assert other < 10 ** (-150 / 20) * own, f"{name}: {fault} leaks {20 * np.log10(other / own):.0f} dB"


def test_air_mass_and_throttle_in_filter4(bank):
    """R-FDF-4 (Fig. 4.4, Fig. 5.5): a throttle fault never reaches the air-mass residual; an air-mass sensor bias
    (both directions) reaches the throttle residual only transiently — zero at DC, present at high frequency."""
    d = bank.designs["filter4"]
    m = _design_model("filter4")
    R = d.generator.internal_form(m)
    iso = np.array(d.generator.isolates)
    thr, air = m.faults.index("throttle_actuator"), m.faults.index("air_mass_sensor")
    G = np.abs(R.freqresp(np.concatenate([[0.0], W]), "f"))
    assert G[:, iso == "air_mass_sensor", thr].max() < 1e-7 * G[:, iso == "throttle_actuator", thr].max()
    leak = G[:, iso == "throttle_actuator", air].max(axis=1)
    assert leak[0] < 1e-7 * leak.max()  # steady state: none
    assert leak[-1] > 1e-3 * G[:, iso == "throttle_actuator", thr].max()  # high frequency: the F¹ rate leaks in
    assert {k: T.shape[1] for k, T in d.detection_spaces.items()} == {
        "throttle_actuator": 2, "brake_actuator": 2, "steering_actuator": 1, "air_mass_sensor": 1}


def test_wheel_speed_projector_structure(bank):
    """R-FDF-7: Ĥ_fr of filter 3 is a symmetric projector of trace 12 − 6 = 6 whose rows/columns for the other three
    wheel speeds vanish (App. E, (e.2b)); the air-mass output is untouched (Ĥ(1,1) = 1)."""
    H = bank.designs["filter3"].projectors["wheel_speed_fr_sensor"]
    np.testing.assert_allclose(H, H.T, atol=1e-12)
    np.testing.assert_allclose(H @ H, H, atol=1e-10)
    assert np.trace(H) == pytest.approx(6.0, abs=1e-9)
    others = [8, 10, 11]  # fl, rl, rr
    assert np.abs(H[others]).max() < 1e-9 and np.abs(H[:, others]).max() < 1e-9
    assert H[0, 0] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("fault", ["yaw_rate_sensor", "wheel_speed_rl_sensor", "throttle_actuator",
                                   "steering_actuator"])
def test_nominal_fault_gives_scaled_residual_one(bank, fault):
    """R-FDF-6 (§5.1.1): a nominal fault in the linear model settles at scaled residual magnitude 1 (simulated)."""
    plant = path_fault_model(14).discretize(0.01)
    signal, loc = fault.rsplit("_", 1)
    loc = "sensor" if loc == "sensor" else "actuator"
    tr = simulate(plant, FaultScenario([Bias(signal, bank.nominal[fault], onset=0.0, location=loc)]), duration=40.0)
    r = bank.generator.run(tr)
    own = [k for k, (g, iso) in enumerate(zip(bank.groups, r.isolates)) if iso == fault]
    for g in {bank.groups[k] for k in own}:
        cols = [k for k in own if bank.groups[k] == g]
        assert np.linalg.norm(r.r[-1, cols]) == pytest.approx(1.0, rel=2e-3)


def test_all_fifteen_faults_detected_and_isolated_but_roll_and_pitch_rate_on_the_boundary(bank):
    """All 12 sensor and 3 actuator faults of the report, nominal size, onset 5 s, on the 14-state linear plant
    with sensor noise at 1e-4 of each sensor's nominal fault; thresholds for 1 false alarm/h, persistence 5 of 10,
    bank logic (filters pointing to two or more faults are discarded)."""
    plant = path_fault_model(14).discretize(0.01)
    noise = 1e-4 * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    healthy = bank.generator.run(simulate(plant, duration=600, measurement_noise_std=noise, rng=1)).slice(start=10)
    ev = ThresholdEvaluator(groups=bank.groups, persistence=(5, 10)).fit(healthy, false_alarms_per_hour=1)
    faults = [f for specs in FILTER_GROUPS.values() for f in specs]
    assert len({f.partition(":")[0] for f in faults}) == 15
    for k, fault in enumerate(plant.faults):
        signal, loc = fault.rsplit("_", 1)
        scenario = FaultScenario([Bias(signal, bank.nominal[fault], onset=5.0, location=loc)])
        tr = simulate(plant, scenario, duration=20.0, measurement_noise_std=noise, rng=10 + k)
        s = score(tr, ev.run(bank.generator.run(tr)))
        assert s.detected and s.detection_delay < 0.5, fault
        assert s.false_alarms == 0, fault
        if fault in ("roll_rate_sensor", "pitch_rate_sensor"):
            # on the decision boundary: on each alarmed sample the pattern is either named or 'unknown' (another
            # filter's residual fires too), and the share moves with the design's rounding (the left-eigenvector
            # design has σ_min(V) ≈ 1e-3): roll rate 79 / 96 / 17 %, pitch rate 99.7 / 2 / 97 % named under the
            # Prescott / Haswell / SkylakeX kernels (docs/methods/beard_jones.md).  So the test asks only that
            # it is never misnamed.
            assert s.isolated in (fault, "unknown"), (fault, s.isolated)
        else:
            assert s.isolated == fault, (fault, s.isolated)


def test_conditioning_report_against_bounds(bank):
    """R-FDF-5 (soft, report (4.3)/(4.8)): each admissible block V_ij is the v-part of an orthonormal null-space
    basis of the stacked [v; w] system, so σ_max([V_ij]) ≤ √(number of blocks) (the report's repeated top value
    √12 = 3.4641 for group 3, √14 for group 4); the selected unit eigenvectors have σ_max(𝒱) ≤ √n; σ_min(𝒱) is of
    the report's order (group 3: 1.0e-3, group 4: 5e-4), well away from 0."""
    for name, d in bank.designs.items():
        n = d.left_eigenvectors.shape[0]
        assert d.sigma_bound[0] <= np.sqrt(n) * (1 + 1e-12)
        assert d.sigma[0] <= np.sqrt(n) * (1 + 1e-12)
        assert 1e-4 < d.sigma[-1] < 1.0, (name, d.sigma[-1])
    assert bank.designs["filter3"].sigma[-1] == pytest.approx(1.2e-3, rel=0.5)
