"""Observer and Kalman residual generators.

Oracles: python-control's ``dlqe``/``lqe`` (a-priori / continuous Riccati solution), the
decorrelated-noise transformation for the cross-covariance case, a brute-force Riccati iteration,
and the innovation sequence of a simulated run (white, covariance ``C P Cᵀ + R̄``).
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg

from fdikit import DesignError, FaultModel, ParameterError
from fdikit.design import kalman, observer, observer_generator, unobservable_modes
from fdikit.simulate import simulate


def _model(dt: float | None = None, seed: int = 0, noise: bool = True, dw: bool = False) -> FaultModel:
    rng = np.random.default_rng(seed)
    n, p = 4, 2
    M = rng.standard_normal((n, n))
    A = M - (np.max(scipy.linalg.eigvals(M).real) + 0.2) * np.eye(n)
    kw = {}
    if noise:
        kw = {"Bw": rng.standard_normal((n, 2)), "noise": ["w1", "w2"]}
        if dw:
            kw["Dw"] = 0.5 * rng.standard_normal((p, 2))
    m = FaultModel(A=A, C=rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 1)),
                   Du=0.1 * rng.standard_normal((p, 1)), outputs=["s", "r"], controls=["u"], **kw)
    return m if dt is None else m.discretize(dt)


def _sorted(z):
    z = np.asarray(z, dtype=complex)
    return z[np.lexsort((np.round(z.imag, 8), np.round(z.real, 8)))]


Q = np.array([[0.4, 0.1], [0.1, 0.3]])
R = np.array([[0.02, 0.005], [0.005, 0.05]])


# ---------------------------------------------------------------------------------------------- pole placement


@pytest.mark.filterwarnings("ignore::slycot.exceptions.SlycotResultWarning")
@pytest.mark.parametrize("method", ["place", "varga"])
@pytest.mark.parametrize(
    ("dt", "poles"),
    [(None, [-2.0, -3.0, -4.0 + 1.5j, -4.0 - 1.5j]), (0.1, [0.3, 0.45, 0.5 + 0.2j, 0.5 - 0.2j])],
)
def test_observer_places_the_poles(dt, poles, method):
    m = _model(dt)
    d = observer(m, poles, method=method)
    scale = max(1.0, np.abs(poles).max())
    np.testing.assert_allclose(_sorted(d.poles), _sorted(poles), rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(_sorted(scipy.linalg.eigvals(m.A - d.gain @ m.C)), _sorted(poles), atol=1e-8 * scale)
    assert d.gain.shape == (4, 2) and d.covariance is None and d.innovation_covariance is None
    g = d.generator
    assert g.dt == m.dt and g.controls == ("u",) and g.outputs == ("s", "r") and g.residuals == ("s", "r")
    # the generator is the observer of eq. (3.2): z' = (A - LC) z + (Bu - L Du) u + L y, r = y - C z - Du u
    np.testing.assert_allclose(g.A, m.A - d.gain @ m.C, atol=1e-14)
    np.testing.assert_allclose(g.B, np.hstack([m.Bu - d.gain @ m.Du, d.gain]), atol=1e-14)
    np.testing.assert_array_equal(g.C, -m.C)
    np.testing.assert_array_equal(g.D, np.hstack([-m.Du, np.eye(2)]))


def test_observer_generator_custom_residual_names():
    m = _model()
    g = observer_generator(m, np.zeros((4, 2)), outputs=["e1", "e2"])
    assert g.residuals == ("e1", "e2")


def test_unobservable_model_names_the_mode():
    A = np.diag([-1.0, -2.5, -3.0])
    m = FaultModel(A=A, C=[[1.0, 0.0, 1.0]], Bu=np.ones((3, 1)))
    np.testing.assert_allclose(unobservable_modes(m.A, m.C), [-2.5])
    with pytest.raises(DesignError, match=r"not observable: modes \[\(-2\.5\+0j\)\]"):
        observer(m, [-5.0, -6.0, -7.0])
    # observable after a small coupling: no mode reported
    assert unobservable_modes(m.A, np.array([[1.0, 0.1, 1.0]])).size == 0


def test_observer_bad_requests():
    m = _model(0.1)
    with pytest.raises(ParameterError, match="need 4 observer poles"):
        observer(m, [0.1, 0.2])
    with pytest.raises(ParameterError, match="unknown placement method"):
        observer(m, [0.1, 0.2, 0.3, 0.4], method="ackermann")
    with pytest.raises(DesignError, match="not stable"):
        observer(m, [0.1, 0.2, 0.3, 1.2])
    with pytest.raises(DesignError, match="not stable"):
        observer(_model(), [-1.0, -2.0, -3.0, 0.5])


# ------------------------------------------------------------------------------------ Kalman vs python-control


def test_kalman_discrete_matches_dlqe():
    m = _model(0.1)
    d = kalman(m, Q, R)
    L_ref, P_ref, E_ref = control.dlqe(m.A, m.Bw, m.C, Q, R)
    scale = np.abs(P_ref).max()
    np.testing.assert_allclose(d.covariance, P_ref, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(d.gain, L_ref, rtol=0, atol=1e-9 * np.abs(L_ref).max())
    np.testing.assert_allclose(d.innovation_covariance, m.C @ P_ref @ m.C.T + R, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(_sorted(d.poles), _sorted(E_ref), atol=1e-9)
    assert np.all(np.abs(d.poles) < 1)


def test_kalman_continuous_matches_lqe():
    m = _model()
    d = kalman(m, Q, R)
    L_ref, P_ref, E_ref = control.lqe(m.A, m.Bw, m.C, Q, R)
    np.testing.assert_allclose(d.covariance, P_ref, rtol=0, atol=1e-9 * np.abs(P_ref).max())
    np.testing.assert_allclose(d.gain, L_ref, rtol=0, atol=1e-9 * np.abs(L_ref).max())
    np.testing.assert_array_equal(d.innovation_covariance, R)
    np.testing.assert_allclose(_sorted(d.poles), _sorted(E_ref), atol=1e-9 * np.abs(E_ref).max())
    assert np.all(d.poles.real < 0)


@pytest.mark.parametrize("dt", [None, 0.1])
def test_kalman_without_noise_group_uses_identity_noise_input(dt):
    m0 = _model(dt, noise=False)
    Qx = np.diag([0.3, 0.1, 0.2, 0.05])
    d = kalman(m0, Qx, R)
    lqe = control.lqe if dt is None else control.dlqe
    L_ref, P_ref, _ = lqe(m0.A, np.eye(4), m0.C, Qx, R)
    np.testing.assert_allclose(d.covariance, P_ref, rtol=0, atol=1e-9 * np.abs(P_ref).max())
    np.testing.assert_allclose(d.gain, L_ref, rtol=0, atol=1e-9 * np.abs(L_ref).max())
    # the same as a noise group with Bw = I
    mw = FaultModel(A=m0.A, C=m0.C, Bu=m0.Bu, Du=m0.Du, Bw=np.eye(4), noise=["a", "b", "c", "e"], dt=dt)
    dw = kalman(mw, Qx, R)
    np.testing.assert_allclose(dw.covariance, d.covariance, rtol=0, atol=1e-12 * np.abs(P_ref).max())
    np.testing.assert_allclose(dw.gain, d.gain, rtol=0, atol=1e-12 * np.abs(L_ref).max())
    # a 1x1 Q is a scaled identity
    ds = kalman(m0, [[0.2]], R)
    L_s, P_s, _ = lqe(m0.A, np.eye(4), m0.C, 0.2 * np.eye(4), R)
    np.testing.assert_allclose(ds.covariance, P_s, rtol=0, atol=1e-9 * np.abs(P_s).max())


def _decorrelated(m, Q, R):
    """Equivalent problem without cross-covariance: A' = A - S R̄⁻¹ C, Q' = Qx - S R̄⁻¹ Sᵀ."""
    G, H = m.Bw, m.Dw
    Qx, Rbar, S = G @ Q @ G.T, R + H @ Q @ H.T, G @ Q @ H.T
    K = S @ np.linalg.inv(Rbar)
    return m.A - K @ m.C, Qx - K @ S.T, Rbar, S


@pytest.mark.parametrize("dt", [None, 0.1])
def test_kalman_with_noise_feedthrough_matches_decorrelated_problem(dt):
    m = _model(dt, dw=True)
    d = kalman(m, Q, R)
    A2, Q2, Rbar, S = _decorrelated(m, Q, R)
    Q2 = (Q2 + Q2.T) / 2
    if dt is None:
        _, P_ref, _ = control.lqe(A2, np.eye(4), m.C, Q2, Rbar)
        L_ref = (P_ref @ m.C.T + S) @ np.linalg.inv(Rbar)
        innov = Rbar
    else:
        _, P_ref, _ = control.dlqe(A2, np.eye(4), m.C, Q2, Rbar)
        innov = m.C @ P_ref @ m.C.T + Rbar
        L_ref = (m.A @ P_ref @ m.C.T + S) @ np.linalg.inv(innov)
    np.testing.assert_allclose(d.covariance, P_ref, rtol=0, atol=1e-9 * np.abs(P_ref).max())
    np.testing.assert_allclose(d.gain, L_ref, rtol=0, atol=1e-9 * np.abs(L_ref).max())
    np.testing.assert_allclose(d.innovation_covariance, innov, rtol=0, atol=1e-9 * np.abs(innov).max())


def test_kalman_discrete_cross_covariance_by_riccati_iteration():
    m = _model(0.1, dw=True)
    d = kalman(m, Q, R)
    G, H, A, C = m.Bw, m.Dw, m.A, m.C
    Qx, Rbar, S = G @ Q @ G.T, R + H @ Q @ H.T, G @ Q @ H.T
    P = np.zeros((4, 4))
    for _ in range(5000):  # a-priori covariance recursion of the predictor x̂[k+1|k]
        Sk = C @ P @ C.T + Rbar
        K = (A @ P @ C.T + S) @ np.linalg.inv(Sk)
        P_next = A @ P @ A.T + Qx - K @ Sk @ K.T
        if np.abs(P_next - P).max() < 1e-15 * np.abs(P_next).max():
            P = P_next
            break
        P = P_next
    np.testing.assert_allclose(d.covariance, P, rtol=0, atol=1e-9 * np.abs(P).max())
    np.testing.assert_allclose(d.gain, K, rtol=0, atol=1e-8 * np.abs(K).max())


# ---------------------------------------------------------------------------------------------- innovation whiteness


@pytest.mark.parametrize("dw", [False, True])
def test_innovations_are_white_with_the_predicted_covariance(dw):
    m = _model(0.1, dw=dw)
    d = kalman(m, Q, R)
    N, burn = 30_000, 500
    tr = simulate(m, duration=(N + burn - 1) * 0.1, u=lambda t: [np.sin(0.3 * t)], noise_cov=Q,
                  measurement_noise_cov=R, rng=2024)
    e = d.generator.run(tr).r[burn:]
    assert e.shape == (N, 2)
    Sig = d.innovation_covariance
    # sample covariance entry std for Gaussian data: sqrt((S_ii S_jj + S_ij^2) / N)
    sd = np.sqrt((np.outer(np.diag(Sig), np.diag(Sig)) + Sig**2) / N)
    assert np.all(np.abs(np.cov(e.T) - Sig) < 5 * sd)
    assert np.all(np.abs(e.mean(axis=0)) < 5 * np.sqrt(np.diag(Sig) / N))
    # whitened innovations: every lag-k cross-correlation ~ N(0, 1/N)
    v = np.linalg.solve(np.linalg.cholesky(Sig), e.T).T
    for lag in range(1, 6):
        corr = v[lag:].T @ v[:-lag] / (N - lag)
        assert np.all(np.abs(corr) < 5 / np.sqrt(N)), (lag, corr)
    # a wrong gain (pole placement) leaves correlated residuals: the test can tell
    bad = observer(m, [0.1, 0.15, 0.2, 0.25]).generator.run(tr).r[burn:]
    vb = bad / bad.std(axis=0)
    assert np.abs(vb[1:].T @ vb[:-1] / N).max() > 10 / np.sqrt(N)


# ---------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("Qv", "Rv", "pattern"),
    [
        (np.eye(3), R, r"Q must be a 2x2 covariance"),
        (Q, np.eye(3), r"R must be a 2x2 covariance"),
        (np.ones(3), R, r"Q must be a 2x2"),
        (np.array([[1.0, 0.5], [0.0, 1.0]]), R, "Q must be symmetric"),
        (Q, np.array([[1.0, 2.0], [2.0, 1.0]]), "R must be positive semidefinite"),
        (-np.eye(2), R, "Q must be positive semidefinite"),
    ],
)
def test_kalman_bad_covariances(Qv, Rv, pattern):
    with pytest.raises(ParameterError, match=pattern):
        kalman(_model(0.1), Qv, Rv)


def test_kalman_without_noise_group_needs_n_by_n_Q():
    with pytest.raises(ParameterError, match=r"Q must be a 4x4"):
        kalman(_model(noise=False), np.eye(2), R)


def test_kalman_undetectable_model_is_a_design_error():
    A = np.diag([-1.0, 0.7, -2.0])
    m = FaultModel(A=A, C=[[1.0, 0.0, 1.0]], Bu=np.ones((3, 1)))
    with pytest.raises(DesignError, match=r"0\.7"):
        kalman(m, np.eye(3), [[0.1]])
