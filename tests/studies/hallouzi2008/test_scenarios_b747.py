"""B747 linear FDI benchmark (Hallouzi 2008, §2.4.1, Table 2.6)."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.plants.b747 import B747_NOISE
from fdikit.studies.hallouzi2008.b747 import (
    INTERVALS,
    b747_convex_set,
    b747_lq_gain,
    b747_monte_carlo,
    b747_snr,
    b747_trace,
    b747_weight_profile,
)


def test_weight_profile_is_table_2_6():
    """Table 2.6: 30 % α-sensor [200,300], 40 % δ_s [400,500], 50 % δ_c [600,700], 20 % V [800,900]."""
    mu, lab = b747_weight_profile()
    assert mu.shape == (1000, 5)
    np.testing.assert_allclose(mu.sum(axis=1), 1.0)
    np.testing.assert_allclose(mu[199], [1, 0, 0, 0, 0])
    np.testing.assert_allclose(mu[200], [0.7, 0, 0, 0, 0.3])
    np.testing.assert_allclose(mu[300], [0.7, 0, 0, 0, 0.3])
    np.testing.assert_allclose(mu[301], [1, 0, 0, 0, 0])
    np.testing.assert_allclose(mu[450], [0.6, 0, 0.4, 0, 0])
    np.testing.assert_allclose(mu[650], [0.5, 0.5, 0, 0, 0])
    np.testing.assert_allclose(mu[850], [0.8, 0, 0, 0.2, 0])
    assert lab[250] == "alpha_sensor" and lab[850] == "V_TAS_sensor" and lab[0] == "none"
    assert sum(b - a + 1 for a, b in INTERVALS.values()) == 1000


def test_partial_fault_blend_equals_scaled_matrix():
    """A 40 % LOE of δ_s is 0.6·nominal + 0.4·model 3: δ_s column of B scaled by 0.6, C unchanged."""
    ms = b747_convex_set()
    _, B, C, _ = ms.blend([0.6, 0, 0.4, 0, 0])
    np.testing.assert_allclose(B[:, 1], 0.6 * ms.B[0][:, 1])
    np.testing.assert_allclose(B[:, [0, 2, 3, 4, 5]], ms.B[0][:, [0, 2, 3, 4, 5]])
    _, _, C, _ = ms.blend([0.7, 0, 0, 0, 0.3])
    assert C[2, 2] == pytest.approx(0.7)


def test_lq_gain_is_riccati_optimal():
    """u = −Kx stabilises the nominal ZOH model; K satisfies the DARE stationarity (independent check)."""
    from scipy.linalg import solve_discrete_are

    ms = b747_convex_set()
    A, B = ms.A[0], ms.B[0]
    K = b747_lq_gain()
    rho = np.max(np.abs(np.linalg.eigvals(A - B @ K)))
    assert rho < 0.9999
    R = np.diag([1.0, 1.0] + [1e-10] * 4)
    P = solve_discrete_are(A, B, np.eye(5), R)
    np.testing.assert_allclose((R + B.T @ P @ B) @ K, B.T @ P @ A, rtol=1e-8, atol=1e-10)


def test_trace_reproduces_noise_and_model():
    """y − C_μk x has the covariance R of §2.4.1 (within 10 %), and the state obeys the blended model."""
    tr = b747_trace(3)
    ms = b747_convex_set()
    mu, _ = b747_weight_profile()
    ybar = np.stack([ms.blend(m)[2] @ x for m, x in zip(mu, tr.x)])
    np.testing.assert_allclose((tr.y - ybar).var(axis=0), np.diag(B747_NOISE["R"]), rtol=0.1)
    k = 650  # inside the 50 % δ_c fault
    _, Bk, _, _ = ms.blend(mu[k])
    w = tr.x[k + 1] - ms.A[0] @ tr.x[k] - Bk @ tr.u[k]
    assert np.abs(w).max() < 5e-3  # only process noise (std 1e-3) remains
    snr = b747_snr(tr)
    assert np.all(snr > 31), snr  # thesis ≈ 35 dB on all four; measured (mean of 5 runs) 43 / 47 / 34 / 57 dB
    white = b747_snr(b747_trace(3, input_tau=None, input_std=[0.3, 0.3, 2e3, 2e3, 2e3, 2e3]))
    assert white[2] < 15  # white control noise leaves α at about 9 dB


def test_state_rmse_within_thesis_bound_until_the_v_sensor_fault_not_in_it():
    """Item 18, state RMSE (2.64) on the full 1000-sample run, 10 runs (seed 0, the docs' seed; 12 s).

    Thesis: all state RMSE ≲ 10^−0.85 = 0.14.  On 100 runs (docs) it holds for all three filters in every
    interval before the V-sensor fault (at most 0.109, EKF in [701, 799]) and **not** in the V-sensor fault
    [800, 900]: the IMM has no model for a 20 % sensor loss and its V estimate goes wrong (2.22), the dual
    CMF reaches 0.67, the EKF 0.125.  The CM filters' errors grow over the run and are heavy-tailed over
    the runs, so a 10-run estimate is noisier: here IMM ≤ 0.052 and dual CMF ≤ 0.117 before 800, the EKF
    0.119 up to 700 but 0.161 in [701, 799]; in the V fault IMM 2.22, dual CMF 0.62, EKF 0.18.  Asserted:
    the bound where these 10 runs reproduce it (IMM, dual CMF before 800; EKF before 701) and, in the V
    fault, that it fails for the IMM (> 0.5) and the dual CMF while the EKF stays the lowest.
    """
    r = b747_monte_carlo(runs=10, seed=0)
    s = r.summary
    assert r.rmse_weights["imm"].shape == (1000,)
    before = [k for k, (a, b) in INTERVALS.items() if b < 800]
    assert len(before) == 7
    for f in ("dual_cmf", "imm"):
        assert max(s[f][k]["state"] for k in before) < 0.14, (f, s[f])  # thesis: ≲ 10^−0.85
    assert max(s["ekf"][k]["state"] for k, (a, b) in INTERVALS.items() if b <= 700) < 0.14, s["ekf"]
    v = {f: s[f]["V_TAS_20"]["state"] for f in r.filters}
    assert v["imm"] > 0.5 and v["dual_cmf"] > 0.14, v  # the thesis bound does not hold in the V fault
    assert v["ekf"] < min(v["dual_cmf"], v["imm"]), v
    # weights stay on the simplex
    for f in r.filters:
        np.testing.assert_allclose(r.mean_weights[f].sum(axis=1), 1.0, atol=1e-8)
        assert r.mean_weights[f].min() >= -1e-12


def test_bad_input_raises():
    with pytest.raises(ParameterError, match="unknown filters"):
        b747_monte_carlo(runs=1, filters=("kalman",))
    with pytest.raises(ParameterError, match="runs must be at least 1"):
        b747_monte_carlo(runs=0)
    with pytest.raises(ParameterError, match="input_std must be 6"):
        b747_trace(0, input_std=[0.1, 0.1])


def test_euclidean_projection_lets_the_ekf_altitude_drift():
    """The thesis's EKF projection (W = I, P unchanged) keeps variance along 1ᵀμ, coupled to h through the
    common altitude row of C: the altitude estimate drifts (measured RMSE 0.97 m on this run) while the
    covariance projection (Simon & Chia, W = P⁻¹) keeps it at 0.017 m (R_h = 1e-3, std 0.032 m)."""
    from fdikit.multimodel.convex_ekf import augmented_ekf

    ms = b747_convex_set()
    tr = b747_trace(np.random.default_rng(1))
    err = {}
    for proj in ("euclidean", "covariance"):
        r = augmented_ekf(ms, tr.y, tr.u, np.zeros(5), 1e-4 * np.eye(5), mu0=np.eye(5)[0], Q_mu=1e-2 * np.eye(5),
                          projection=proj)
        err[proj] = np.sqrt(((tr.x[:, 4] - r.x[:, 4]) ** 2).mean())
        np.testing.assert_allclose(r.mu.sum(axis=1), 1.0, atol=1e-9)
        assert r.mu.min() >= 0
    assert err["covariance"] < 0.05 and err["euclidean"] > 10 * err["covariance"], err


def test_item_18_reproduced_claims():
    """Item 18, the claims that hold with the substitute data (4 runs; the 100-run table is in the docs):
    both CM filters beat the IMM in all four fault intervals, and the IMM beats both in the fault-free
    intervals between the faults, where the dual CMF beats the EKF.

    Measured (seed 2): fault weight RMSE dual CMF 0.12–0.17, EKF 0.23–0.32, IMM 0.29–0.65; fault-free
    [301, 799] IMM 0.07–0.08, dual CMF 0.13–0.25, EKF 0.23–0.41.
    """
    s = b747_monte_carlo(runs=4, seed=2).summary
    for k in ("alpha_30", "delta_s_40", "delta_c_50", "V_TAS_20"):
        assert s["dual_cmf"][k]["weights"] < s["imm"][k]["weights"], k
        assert s["ekf"][k]["weights"] < 0.9 * s["imm"][k]["weights"], k
    for k in ("nominal_2", "nominal_3", "nominal_4"):
        assert s["imm"][k]["weights"] < s["dual_cmf"][k]["weights"] < s["ekf"][k]["weights"], k
