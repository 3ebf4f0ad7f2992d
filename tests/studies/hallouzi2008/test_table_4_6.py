"""Hallouzi 2008, §4.4.1, Table 4.6 / Fig. 4.3: augmented EKF with model set I on the JSBSim B747 models.

One run (seed 0, 115 s at 100 Hz) is shared by the tests.  Tolerances are derived from the run's own noise
floor: with ``Q^μ = 1e-4 I`` the seven weights that the true plant does not involve keep a random-walk floor
of ≈ 0.02 each against the positivity constraint, so the weights that it does involve can fall short of their
exact values by the mass of that floor, ``floor = 1 − mean μ(8)`` over the first fault-free interval (no fault
before it; ≈ 0.14 here), plus two standard deviations of μ(8) there (its fluctuation, σ ≈ 0.04): tol ≈ 0.22
(0.19–0.30 over seeds 0–3).
The assertions hold for seeds 0–3 (checked once); seed 0 is the one kept.
"""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.metrics import vaf
from fdikit.studies.hallouzi2008.b747_report import plot_table_4_6
from fdikit.studies.hallouzi2008.table_4_6 import (
    NOMINAL,
    Q_S_THESIS,
    R_S_THESIS,
    Table46Result,
    build_table_4_6,
    equivalent_lip_weight,
    model_set_i_logic,
    noise_covariances,
    run_table_4_6,
    simulate_table_4_6,
    table_4_6_isolation,
)

D2R = (np.pi / 180.0) ** 2
INTERVALS = {"none_1": (0.0, 15.0), "elevator": (15.0, 20.0), "none_2": (20.0, 35.0), "alpha_sensor": (35.0, 40.0),
             "none_3": (40.0, 52.5), "rudder": (52.5, 60.0), "none_4": (60.0, 75.0), "hydraulic": (75.0, 80.0),
             "none_5": (80.0, 95.0), "engine": (95.0, 115.0)}


@pytest.fixture(scope="module")
def scenario():
    return build_table_4_6()


@pytest.fixture(scope="module")
def result(scenario):
    return run_table_4_6(scenario, seed=0)


def weights(res, name, settle=1.0):
    """Mean weights over an interval after ``settle`` seconds (the transient)."""
    a, b = INTERVALS[name]
    rows = (res.t >= a + settle - 1e-9) & (res.t < b - 1e-9)
    return res.mu[rows].mean(axis=0), res.mu[rows].std(axis=0)


@pytest.fixture(scope="module")
def tol(result):
    mean, std = weights(result, "none_1")
    return (1.0 - mean[NOMINAL]) + 2.0 * std[NOMINAL]


def test_noise_in_si_units():
    # (4.3)-(4.4) in rad: the deg entries times (pi/180)^2; Q_s read as an intensity, times T = 0.01 s
    Q, R = noise_covariances()
    np.testing.assert_allclose(np.diag(Q)[[0, 4, 5, 6]], np.array([1e-8, 1e-4, 1e-4, 1e-4]) * D2R * 0.01)
    np.testing.assert_allclose(np.diag(Q)[[3, 9]], [1e-3, 1e-3])
    np.testing.assert_allclose(np.diag(R), np.where([1, 1, 1, 0, 1, 1, 1, 0], R_S_THESIS * D2R, R_S_THESIS))
    assert Q_S_THESIS.size == 10 and R_S_THESIS.size == 8


def test_lqr_stabilises_every_plant(scenario):
    # the fault models are open-loop unstable (the reason for the LQ loop, §4.4.1); with the nominal gain
    # every model of set I and every simulated fault plant is stable
    for m in (*scenario.models, *scenario.truths.values()):
        A, B = m.linearization.model.A, m.linearization.model.B
        assert np.linalg.eigvals(A - B @ scenario.K).real.max() < 0, m.name
    assert np.linalg.eigvals(scenario.models[0].linearization.model.A).real.max() > 0


def test_elevator_lock_weight(result, tol):
    # Thesis: mu(3) ~ 0.7 (0.7*17 = 11.9 deg for a true 10 deg).  The convex weight of a lock affine in its
    # position is (10 - u_e)/(17 - u_e) with u_e the commanded elevator: 10/17 = 0.59 for u_e = 0, the
    # thesis's 0.7 for u_e = -6.3 deg.  Here the LQ loop drives the dead elevator's command to its -23 deg
    # limit (mean -21 deg), so the exact weight is ~0.82, and the EKF finds it.
    u_e = np.degrees(result.u[result.labels == "elevator", 1].mean())
    assert u_e < -15.0
    mu_eq = equivalent_lip_weight(result, "elevator")
    assert mu_eq == pytest.approx((10 - u_e) / (17 - u_e))
    mean, _ = weights(result, "elevator")
    assert abs(mean[2] - mu_eq) < tol
    assert mean[2] > 10 / 17 + 0.1  # not the zero-command weight
    assert np.argmax(mean) == 2


def test_alpha_sensor_weights(result, tol):
    # 50 % alpha sensor: C's alpha row x 0.5 = 0.5 * model 6 (row zero) + 0.5 * model 8, exactly
    # (every other model has the full alpha row, so the blended alpha gain is 1 - mu(6) whatever the split of the
    # rest).  Thesis: mu(6) ~ mu(8) ~ 0.5.  Measured (seeds 0-3): mu(6) 0.43-0.52, mu(8) 0.30-0.42, the floor
    # taking the rest.
    mean, _ = weights(result, "alpha_sensor")
    assert abs(mean[5] - 0.5) < tol
    assert np.argsort(mean)[-2:].tolist() in ([5, NOMINAL], [NOMINAL, 5])
    assert mean[5] + mean[NOMINAL] > 1.0 - 1.5 * tol


def test_rudder_lock_weight(result, tol):
    # Thesis: mu(2) ~ 0.55.  Exact weight (-15 - u_r)/(-25 - u_r): the loop saturates the rudder command at
    # +25 deg (mean ~ +24 deg), giving ~0.8 (the thesis's 0.55 means u_r = -2.8 deg).  Measured mu(2) 0.66-0.69
    # (seeds 0-3), with 0.25-0.30 on the engine-separation model, which is trimmed with rudder against the
    # asymmetric thrust and so explains part of a yawing rudder offset.
    u_r = np.degrees(result.u[result.labels == "rudder", 3].mean())
    assert u_r > 20.0
    mu_eq = equivalent_lip_weight(result, "rudder")
    mean, _ = weights(result, "rudder")
    assert abs(mean[1] - mu_eq) < tol
    assert np.argmax(mean) == 1


def test_hydraulic_weight(result, tol):
    # the plant is model 7 itself: thesis mu(7) -> 1.  Measured 0.56-0.78 (seeds 0-3), still rising at the end of
    # the 5-s interval: model 7 differs from the nominal one only in the surface columns of B (x 3/4, 1/2, 3/4),
    # seen through the ~1-deg surface activity alone.  Asserted: model 7 dominates with more than half the weight.
    mean, _ = weights(result, "hydraulic")
    assert np.argmax(mean) == 6
    assert mean[6] > 0.5


def test_engine_separation_weight(result, tol):
    # Thesis: mu(5) -> ~1.  Measured 0.89-0.91 after 100 s (seeds 0-3).
    mean, _ = weights(result, "engine", settle=5.0)
    assert np.argmax(mean) == 4
    assert mean[4] > 1.0 - tol


def test_nominal_weight_in_fault_free_intervals(result, tol):
    # Thesis: mu(8) back to ~1.  Measured 0.69-0.87 (seeds 0-3): the floor of the other seven weights (module
    # docstring of the test); after a fault mu(8) recovers within a few seconds, so the intervals after the
    # alpha-sensor and hydraulic faults sit lower.  Asserted: nominal dominates, within two floors of 1.
    for name in ("none_1", "none_2", "none_3", "none_4", "none_5"):
        mean, _ = weights(result, name)
        assert np.argmax(mean) == NOMINAL, name
        assert mean[NOMINAL] > 1.0 - 2 * tol, name


def test_state_vaf_against_a_kalman_filter_that_knows_the_plant(scenario, result):
    # independent bound: a linear KF run with the *true* model of every sample on the same data (seed 0
    # reproduces the same simulation).  The EKF cannot beat it by more than chance; it should come within a
    # few percent of it.  Thesis: beta, phi > 90 %, measured states > 99 %.
    sim = simulate_table_4_6(scenario, seed=0)
    disc = {k: m.discrete(scenario.dt) for k, m in scenario.truths.items()}
    key = np.where(sim["labels"] == "none", "nominal", sim["labels"])
    x, P = scenario.x_trim.copy(), 100.0 * scenario.Q
    xs = np.zeros_like(sim["x"])
    for k in range(key.size):
        if k:
            Ad, Bd, _ = disc[key[k - 1]]
            x = Ad @ x + Bd[:, :5] @ sim["u"][k - 1] + Bd[:, 5]
            P = Ad @ P @ Ad.T + scenario.Q
        C = disc[key[k]][2]
        G = np.linalg.solve(C @ P @ C.T + scenario.R, C @ P).T
        x = x + G @ (sim["y"][k] - C @ x)
        P = (np.eye(10) - G @ C) @ P
        xs[k] = x
    np.testing.assert_allclose(sim["x"], result.x)
    oracle = dict(zip(result.vaf, vaf(sim["x"], xs)))
    # measured oracle (seed 0): every state > 98.9 % (V 98.9 %: V is the noisiest state)
    for s, v in result.vaf.items():
        assert v <= oracle[s] + 0.5, s
        # measured (seeds 0-3): phi 3.5-6.9 points below (unmeasured, it drifts with the weight errors), alpha
        # 2.3-3.7, the others within 1
        assert v >= oracle[s] - (10.0 if s == "roll" else 5.0), s
    # thesis: beta, phi > 90 %, measured states > 99 %.  Measured (seeds 0-3): beta 99.6-99.8 %, phi 93-96 %,
    # p q r theta psi h > 99.8 %; V 98.1-98.9 % (as the oracle: the V process noise) and alpha 96.3-97.7 %
    # (below the thesis's 99 %: the weight errors, mostly around the alpha-sensor interval).
    assert result.vaf["beta"] > 90.0
    assert result.vaf["roll"] > 90.0
    for s in ("roll_rate", "pitch_rate", "yaw_rate", "pitch", "heading", "altitude"):
        assert result.vaf[s] > 99.0, s
    assert result.vaf["alpha"] > 95.0


def test_table_4_7_logic_isolates_every_fault(result):
    iso = table_4_6_isolation(result)
    for name in ("elevator", "alpha_sensor", "rudder", "hydraulic", "engine"):
        declared, fraction = iso[name]
        assert declared == name
        assert fraction > 0.9, name  # measured 1.0 after the 1-s settle
    # fault-free: mu(8) hovers near 1 - T_f = 0.8 (thesis: ~1), so part of the samples are false alarms.
    # Fraction declared 'none' after the 1-s settle, measured over seeds 0-3: none_1 0.59-0.95, none_2 0.72-0.97,
    # none_3 0.33-0.74, none_4 0.51-0.77, none_5 (after the hydraulic outage, whose weight decays slowly)
    # 0.30-0.68, where 'hydraulic' can be the most frequent decision.
    decided = model_set_i_logic().isolate(result.mu)
    for name, least in (("none_1", 0.5), ("none_2", 0.5), ("none_3", 0.25), ("none_4", 0.25), ("none_5", 0.25)):
        a, b = INTERVALS[name]
        rows = (result.t >= a + 1.0 - 1e-9) & (result.t < b - 1e-9)
        assert (decided[rows] == "none").mean() > least, name
    assert iso["none_1"] == ("none", pytest.approx((decided[(result.t >= 1.0 - 1e-9) & (result.t < 15.0 - 1e-9)]
                                                    == "none").mean()))


def test_logic_groups():
    logic = model_set_i_logic()
    assert logic.isolate([[0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.7], [0.0, 0.0, 0.1, 0.2, 0, 0, 0, 0.7],
                          [0, 0, 0, 0, 0, 0, 0.9, 0.1]]).tolist() == ["rudder", "elevator", "hydraulic"]


def test_true_weights(result):
    rows = result.labels == "elevator"
    np.testing.assert_allclose(result.true_mu[rows][0], [0, 0, 10 / 17, 0, 0, 0, 0, 7 / 17])
    np.testing.assert_allclose(result.true_mu[result.labels == "engine"][0], np.eye(8)[4])
    np.testing.assert_allclose(result.true_mu.sum(axis=1), 1.0)


def test_plot(result):
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    assert plot_table_4_6(result, ax=ax) is ax  # the plot convention: the caller's axes back
    assert len(ax.lines) == 8
    plt.close(fig)


def test_bad_arguments(scenario):
    with pytest.raises(ParameterError):
        build_table_4_6(aircraft=object())
    with pytest.raises(ParameterError):
        run_table_4_6(scenario, q_mu=0.0)
    with pytest.raises(ParameterError):
        noise_covariances(dt=-1.0)
    short = Table46Result(np.zeros(2), np.array(["none", "none"]), None, None, None, None, np.zeros((2, 5)), {})
    with pytest.raises(ParameterError):
        equivalent_lip_weight(short, "rudder")
    with pytest.raises(ParameterError):
        equivalent_lip_weight(short, "aileron")
