"""Convex-model filters of Hallouzi 2008 (§2.3.2 dual CMF, §2.3.3 augmented EKF, (3.51)–(3.57)).

Oracles: the conventional Kalman filter (filterpy), batch weighted least squares (numpy lstsq),
a sort-based Euclidean simplex projection, finite differences, and values derived in the research
note (§3.5: μ_k1 = 0.5 at k1 = 1, μ_m3 = 0.1 at m3 = 1).
"""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.multimodel.convex import convex_model_set
from fdikit.multimodel.convex_ekf import augmented_ekf, augmented_jacobians
from fdikit.multimodel.convex_filter import dual_convex_filter, rls_weight_step, weight_regressors
from fdikit.multimodel.kalman_steps import srcf_step
from fdikit.multimodel.model_set import nearest_model
from fdikit.multimodel.reconstruction import (
    estimated_model_vector,
    fault_size_from_weights,
    lv_parameter,
    lv_reciprocal_parameter,
)
from fdikit.multimodel.simplex import project_to_simplex


def _random_set(rng, N=3, n=3, m=2, p=2):
    A = 0.5 * rng.standard_normal((N, n, n)) / np.sqrt(n)
    B = rng.standard_normal((N, n, m))
    C = rng.standard_normal((N, p, n))
    D = rng.standard_normal((N, p, m))
    G = rng.standard_normal((n, n))
    H = rng.standard_normal((p, p))
    return convex_model_set(A, B, C, D, Q=G @ G.T + 0.1 * np.eye(n), R=H @ H.T + 0.1 * np.eye(p))


def _sort_simplex(v):
    """Euclidean projection on the probability simplex by sorting (Held et al. 1974 / Duchi et al. 2008)."""
    s = np.sort(v)[::-1]
    css = np.cumsum(s) - 1.0
    rho = np.nonzero(s - css / np.arange(1, v.size + 1) > 0)[0][-1]
    return np.maximum(v - css[rho] / (rho + 1), 0.0)


def test_srcf_step_equals_conventional_kalman_filter():
    """Hallouzi 2008, (2.29)–(2.32) = KF (filtered and predicted mean and covariance) to ~1e-12."""
    rng = np.random.default_rng(0)
    ms = _random_set(rng)
    mu = np.array([0.2, 0.5, 0.3])
    A, B, C, D = ms.blend(mu)
    P = np.cov(rng.standard_normal((3, 20))) + 0.1 * np.eye(3)
    x, u, y = rng.standard_normal(3), rng.standard_normal(2), rng.standard_normal(2)
    x_filt, S_filt, x_free, S_next, e, Re, _ = srcf_step(x, np.linalg.cholesky(P), y, A, C, D=D, u=u,
                                                         Q_sqrt=np.linalg.cholesky(ms.Q),
                                                         R_sqrt=np.linalg.cholesky(ms.R))
    kf = KalmanFilter(dim_x=3, dim_z=2, dim_u=2)
    kf.x, kf.P, kf.F, kf.H, kf.Q, kf.R, kf.B = x.copy(), P.copy(), A, C, ms.Q, ms.R, B
    kf.update(y - D @ u)
    Sig = C @ P @ C.T + ms.R
    assert np.allclose(Re @ Re.T, Sig, atol=1e-12)
    assert np.allclose(e, y - C @ x - D @ u, atol=1e-12)
    assert np.allclose(x_filt, kf.x, atol=1e-12)
    assert np.allclose(S_filt @ S_filt.T, kf.P, atol=1e-12)
    kf.predict(u=u)
    assert np.allclose(x_free + B @ u, kf.x, atol=1e-12)  # the dual filter adds B u after the weight step
    assert np.allclose(S_next @ S_next.T, kf.P, atol=1e-12)


@pytest.mark.parametrize("form", ["corrected", "thesis"])
def test_dual_filter_with_frozen_weights_is_a_kalman_filter(form):
    """Item 2 over a run: with identical local models (any weights) the state path is the KF's, in both forms."""
    rng = np.random.default_rng(1)
    ms = _random_set(rng, N=2)
    ms1 = convex_model_set(ms.A[[0, 0]], ms.B[[0, 0]], ms.C[[0, 0]], ms.D[[0, 0]], Q=ms.Q, R=ms.R)
    K = 60
    u, y = rng.standard_normal((K, 2)), rng.standard_normal((K, 2))
    res = dual_convex_filter(ms1, y, u, np.zeros(3), np.eye(3), mu0=[0.5, 0.5], lam=0.9, form=form)
    kf = KalmanFilter(dim_x=3, dim_z=2, dim_u=2)
    kf.x, kf.P, kf.F, kf.H, kf.Q, kf.R, kf.B = np.zeros(3), np.eye(3), ms.A[0], ms.C[0], ms.Q, ms.R, ms.B[0]
    for k in range(K):
        if k:
            kf.predict(u=u[k - 1])
        kf.update(y[k] - ms.D[0] @ u[k])
        assert np.allclose(res.x[k], kf.x, atol=1e-10) and np.allclose(res.P[k], kf.P, atol=1e-10)
    assert np.allclose(res.mu.sum(axis=1), 1.0)


def test_sri_rls_equals_batch_weighted_least_squares():
    """Hallouzi 2008, (2.35)–(2.36) = batch LS with weights λ^{k−τ} and the T_0 regularisation."""
    rng = np.random.default_rng(2)
    N, lam, delta = 3, 0.9, 1e-3
    mu0 = np.full(N, 1 / N)
    T, xi = delta * np.eye(N), delta * mu0
    rows, rhs = [], []
    K = 25
    for _ in range(K):
        Phi, Gam = rng.standard_normal((4, N)), rng.standard_normal(4)
        T, xi, mu = rls_weight_step(T, xi, Phi, Gam, lam)
        rows.append(Phi)
        rhs.append(Gam)
    w = [np.sqrt(lam ** (K - 1 - j)) for j in range(K)]
    Abig = np.vstack([np.sqrt(lam**K) * delta * np.eye(N)] + [wi * r for wi, r in zip(w, rows)])
    bbig = np.concatenate([np.sqrt(lam**K) * delta * mu0] + [wi * g for wi, g in zip(w, rhs)])
    assert np.allclose(mu, np.linalg.lstsq(Abig, bbig, rcond=None)[0], atol=1e-12)
    assert np.allclose(np.triu(T), T)


def test_weight_regressors_give_the_cost_2_27():
    """‖Φμ − Γ‖² equals (2.21)/(2.27) with the whitened weights; 'inverse' uses Q^{-1}, R^{-1} as printed."""
    rng = np.random.default_rng(3)
    ms = _random_set(rng)
    xp, up, x, u, y = (rng.standard_normal(s) for s in (3, 2, 3, 2, 2))
    mu = np.array([0.1, 0.6, 0.3])
    A, B, C, D = ms.blend(mu)
    ex, ey = x - A @ xp - B @ up, y - C @ x - D @ u
    J = ex @ np.linalg.solve(ms.Q, ex) + ey @ np.linalg.solve(ms.R, ey)
    Phi, Gam = weight_regressors(ms, xp, up, x, u, y)
    assert np.isclose(np.sum((Phi @ mu - Gam) ** 2), J, rtol=1e-12)
    Phi2, Gam2 = weight_regressors(ms, xp, up, x, u, y, weighting="inverse")
    assert np.allclose(Phi2[:3] @ mu - Gam2[:3], -np.linalg.solve(ms.Q, ex))
    with pytest.raises(ParameterError, match="weighting"):
        weight_regressors(ms, xp, up, x, u, y, weighting="Q^-1/4")


def test_simplex_projection_michelot_equals_sort_based_projection():
    """Item 3: equality projection sums to 1, active set gives ≥ 0, Michelot = Euclidean projection."""
    rng = np.random.default_rng(4)
    worst = 0.0
    differ = 0
    for _ in range(500):
        v = rng.normal(0.2, 1.0, rng.integers(2, 7))
        pm, pt = project_to_simplex(v), project_to_simplex(v, ordering="thesis")
        worst = max(worst, np.abs(pm - _sort_simplex(v)).max())
        assert np.isclose(pt.sum(), 1.0) and pt.min() >= 0
        differ += not np.allclose(pm, pt)
    assert worst < 1e-14
    assert differ > 0  # the thesis' ordering is not the Euclidean projection in general
    assert np.allclose(project_to_simplex([0.75, 0.25]), [0.75, 0.25])
    assert np.allclose(project_to_simplex([1.2, 0.2]), [1.0, 0.0])


def test_ekf_jacobians_match_finite_differences():
    """Item 4: (2.52)–(2.53) equal central differences of f(x, μ) = A_μ x + B_μ u and h = C_μ x + D_μ u."""
    rng = np.random.default_rng(5)
    ms = _random_set(rng)
    x, mu, u = rng.standard_normal(3), np.array([0.3, 0.3, 0.4]), rng.standard_normal(2)

    def f(z):
        A, B, C, D = ms.blend(z[3:])
        return np.concatenate([A @ z[:3] + B @ u, z[3:]]), C @ z[:3] + D @ u

    z0, h = np.concatenate([x, mu]), 1e-6
    Jf = np.column_stack([(f(z0 + h * e)[0] - f(z0 - h * e)[0]) / (2 * h) for e in np.eye(6)])
    Jh = np.column_stack([(f(z0 + h * e)[1] - f(z0 - h * e)[1]) / (2 * h) for e in np.eye(6)])
    Abar, Cbar = augmented_jacobians(ms, x, mu, u)
    assert np.allclose(Abar, Jf, atol=1e-8) and np.allclose(Cbar, Jh, atol=1e-8)


def test_ekf_is_a_linear_kf_on_x_mu_when_only_b_varies():
    """Item 4 / §2.4.2: with only B switching the EKF is exactly the linear KF on [x; μ]."""
    rng = np.random.default_rng(6)
    n, N, K = 2, 2, 40
    A = np.array([[1.0, 1.0], [0.0, 1.0]])
    ms = convex_model_set(A, rng.standard_normal((N, n, 1)), np.eye(n), Q=0.01 * np.eye(n), R=np.eye(n))
    u, y = rng.standard_normal((K, 1)), rng.standard_normal((K, n))
    Qmu = 1e-2 * np.eye(N)
    res = augmented_ekf(ms, y, u, np.zeros(n), np.eye(n), mu0=[0.5, 0.5], Q_mu=Qmu, P_mu0=0.1 * np.eye(N),
                        constrain=False)
    kf = KalmanFilter(dim_x=n + N, dim_z=n)
    kf.x = np.array([0.0, 0.0, 0.5, 0.5])
    kf.P = np.diag([1.0, 1.0, 0.1, 0.1])
    kf.H = np.hstack([np.eye(n), np.zeros((n, N))])
    kf.Q, kf.R = np.diag([0.01, 0.01, 0.01, 0.01]), np.eye(n)
    for k in range(K):
        if k:
            F = np.eye(n + N)
            F[:n, :n], F[:n, n:] = A, (ms.B @ u[k - 1]).T
            kf.F = F
            kf.predict()
        kf.update(y[k])
        assert np.allclose(res.x[k], kf.x[:n], atol=1e-10), k
        assert np.allclose(res.mu[k], kf.x[n:], atol=1e-10), k
        assert np.allclose(res.P[k], kf.P[:n, :n], atol=1e-10)


def test_filters_recover_constant_interior_weights():
    """Both CM filters estimate the weights (0.3, 0.7) of an interior convex combination (A and B vary)."""
    rng = np.random.default_rng(7)
    A = np.array([[[0.9, 0.2], [0.0, 0.7]], [[0.5, -0.3], [0.2, 0.8]]])
    B = np.array([[[1.0], [0.0]], [[0.0], [1.0]]])
    ms = convex_model_set(A, B, np.eye(2), Q=1e-4 * np.eye(2), R=1e-4 * np.eye(2))
    At, Bt, _, _ = ms.blend([0.3, 0.7])
    K = 400
    u = rng.standard_normal((K, 1))
    x, ys = np.zeros(2), []
    for k in range(K):
        ys.append(x + 1e-2 * rng.standard_normal(2))
        x = At @ x + Bt @ u[k] + 1e-2 * rng.standard_normal(2)
    ys = np.array(ys)
    dual = dual_convex_filter(ms, ys, u, np.zeros(2), np.eye(2), lam=0.98)
    ekf = augmented_ekf(ms, ys, u, np.zeros(2), np.eye(2), Q_mu=1e-5 * np.eye(2))
    assert np.abs(dual.mu[200:].mean(axis=0) - [0.3, 0.7]).max() < 0.03
    assert np.abs(ekf.mu[200:].mean(axis=0) - [0.3, 0.7]).max() < 0.03


def test_lv_maps_3_54_to_3_57():
    """Note §3.5 [DERIVED]: k1 = 1 ↔ μ_k1 = 0.5, m3 = 1 ↔ μ_m3 = 0.1; 1/m3 is affine in μ (LV matrices)."""
    assert np.isclose(lv_parameter(0.5, 1.75, 0.25), 1.0)
    assert np.isclose(lv_reciprocal_parameter(0.1, 1.8, 0.2), 1.0)
    mu = np.linspace(0, 1, 11)
    inv_m3 = 1 / lv_reciprocal_parameter(mu, 1.8, 0.2)
    assert np.allclose(inv_m3, 1 / 1.8 + mu * (1 / 0.2 - 1 / 1.8), atol=1e-12)  # A^+ + μ A^{m3} entries
    assert np.allclose(lv_parameter(mu, 1.0, 0.0), 1 - mu)  # (3.56)–(3.57)
    with pytest.raises(ParameterError, match="positive"):
        lv_reciprocal_parameter(0.5, 1.8, 0.0)


def test_fault_size_and_nearest_model_reconstruction():
    """(3.51)–(3.52) and Fig. 3.9: f1 = 1 − (μ2 + μ4); the nearest grid model recovers a blended parameter."""
    mu = np.array([[0.0, 0.25, 0.5, 0.25, 0.0, 0.0], [0.1, 0.0, 0.4, 0.0, 0.4, 0.1]])
    assert np.allclose(fault_size_from_weights(mu, [1, 3]), [0.5, 1.0])
    assert np.allclose(fault_size_from_weights(mu, [0, 5]), [1.0, 0.8])
    # a 1-parameter family vec(M(θ)) = a + θ b sampled on a grid; local models at θ = 0 and 1
    a, b = np.array([1.0, 2.0, 0.0]), np.array([0.5, -1.0, 2.0])
    grid = np.linspace(0, 1, 21)
    large = a[:, None] + b[:, None] * grid
    est = estimated_model_vector(np.column_stack([a, a + b]), np.array([[0.7, 0.3], [0.26, 0.74]]))
    assert np.allclose(grid[nearest_model(large, est)], [0.3, 0.75])
    with pytest.raises(ParameterError, match="indices"):
        fault_size_from_weights(mu, [6])


def test_bad_input_is_named():
    ms = convex_model_set(np.eye(2), np.ones((2, 2, 1)), np.eye(2), Q=np.eye(2), R=np.eye(2))
    with pytest.raises(ParameterError, match="Q_mu"):
        augmented_ekf(ms, np.zeros((3, 2)), np.zeros((3, 1)), np.zeros(2), np.eye(2))
    with pytest.raises(DataError, match="y must be"):
        dual_convex_filter(ms, np.zeros((3, 3)), np.zeros((3, 1)), np.zeros(2), np.eye(2))
    with pytest.raises(ParameterError, match="lambda"):
        dual_convex_filter(ms, np.zeros((3, 2)), np.zeros((3, 1)), np.zeros(2), np.eye(2), lam=1.5)
    with pytest.raises(ModelError, match="positive definite"):
        convex_model_set(np.eye(2), np.ones((2, 2, 1)), np.eye(2), Q=np.eye(2), R=np.zeros((2, 2)))
    with pytest.raises(ModelError, match="no model varies"):
        convex_model_set(np.eye(2), np.ones((2, 1)), np.eye(2), Q=np.eye(2), R=np.eye(2))


def _brute_force_weighted_simplex(y, W):
    """Exact QP optimum by enumerating the supports (each solved by its KKT system)."""
    import itertools

    N, best, best_cost = y.size, None, np.inf
    for r in range(1, N + 1):
        for S in itertools.combinations(range(N), r):
            S = list(S)
            K = np.zeros((r + 1, r + 1))
            K[:r, :r], K[:r, r], K[r, :r] = 2 * W[np.ix_(S, S)], 1.0, 1.0
            rhs = np.concatenate([2 * W[S] @ y, [1.0]])
            m = np.zeros(N)
            m[S] = np.linalg.lstsq(K, rhs, rcond=None)[0][:r]
            cost = (m - y) @ W @ (m - y)
            if m.min() >= -1e-12 and abs(m.sum() - 1) < 1e-9 and cost < best_cost - 1e-15:
                best, best_cost = m, cost
    return best, best_cost


def test_weighted_simplex_projection_is_the_qp_optimum():
    """(2.37) with W = TᵀT: the active-set result equals the exact optimum over all supports; W = I gives the
    Euclidean (sort-based) projection."""
    from fdikit.multimodel.simplex import project_to_simplex_weighted

    rng = np.random.default_rng(3)
    for t in range(200):
        N = int(rng.integers(2, 6))
        G = rng.standard_normal((N, N))
        W = G @ G.T + 1e-3 * np.eye(N) if t % 4 else np.diag(rng.uniform(0.1, 10, N))
        y = 2 * rng.standard_normal(N)
        m = project_to_simplex_weighted(y, W, ridge=0.0)
        ref, cost = _brute_force_weighted_simplex(y, W)
        assert m.min() >= 0 and abs(m.sum() - 1) < 1e-12
        assert (m - y) @ W @ (m - y) <= cost * (1 + 1e-9) + 1e-12
        assert np.allclose(m, ref, atol=1e-7)
        assert np.allclose(project_to_simplex_weighted(y, np.eye(N)), _sort_simplex(y), atol=1e-12)


def test_affine_projection_is_the_equality_projection_2_38():
    """(2.38) with D = 1ᵀ, d = 1: μ^c = μ̂ − W⁻¹1 (1ᵀμ̂ − 1)/(1ᵀW⁻¹1); negative weights are allowed."""
    from fdikit.multimodel.simplex import project_to_affine

    rng = np.random.default_rng(4)
    G = rng.standard_normal((4, 4))
    W = G @ G.T + 0.1 * np.eye(4)
    y = rng.standard_normal(4)
    Wi1 = np.linalg.solve(W, np.ones(4))
    assert np.allclose(project_to_affine(y, W, ridge=0.0), y - Wi1 * (y.sum() - 1) / Wi1.sum(), atol=1e-12)
    assert np.allclose(project_to_affine(y), y - (y.sum() - 1) / 4, atol=1e-15)


def test_innovation_regressors_are_the_whitened_prediction_error():
    """Corrected weight step: ‖Φμ − Γ‖² is the whitened one-step prediction error of the blended model at any μ
    when C, D are common (exact), and to first order in μ − μ̄ when C varies."""
    from fdikit.multimodel.convex_filter import innovation_regressors
    from fdikit.multimodel.kalman_steps import psd_sqrt

    rng = np.random.default_rng(5)
    ms = _random_set(rng)
    ms_ab = convex_model_set(ms.A, ms.B, ms.C[0], ms.D[0], Q=ms.Q, R=ms.R)
    x, u0, u1, y = rng.standard_normal(3), rng.standard_normal(2), rng.standard_normal(2), rng.standard_normal(2)
    S = np.linalg.cholesky(np.eye(3) * 0.3)
    Qs, Rs = psd_sqrt(ms.Q), np.linalg.cholesky(ms.R)
    mu_bar = np.array([0.2, 0.5, 0.3])
    for models, tol in ((ms_ab, 1e-12), (ms, 1e-5)):
        Phi, Gamma, F, x_bar, S_bar = innovation_regressors(models, x, S, u0, u1, y, mu_bar, Qs, Rs)
        _, _, C, D = models.blend(mu_bar)
        Re = np.linalg.cholesky(C @ S_bar @ S_bar.T @ C.T + models.R)
        for d in (np.zeros(3), 1e-3 * np.array([1.0, -2.0, 1.0])):
            mu = mu_bar + d
            A, B, C, D = models.blend(mu)
            e = y - C @ (A @ x + B @ u0) - D @ u1
            assert np.allclose(Phi @ mu - Gamma, -np.linalg.solve(Re, e), atol=tol)


def test_dual_cmf_options_and_prior():
    """The prior (regularised forgetting) keeps the weights near μ0 without data; bad options are named."""
    ms = convex_model_set(np.eye(2) * 0.9, [[[1.0], [0.0]], [[0.0], [1.0]]], np.eye(2), Q=1e-4 * np.eye(2),
                          R=1e-4 * np.eye(2))
    y, u = np.zeros((50, 2)), np.zeros((50, 1))  # no excitation: the weights are not identifiable
    r = dual_convex_filter(ms, y, u, np.zeros(2), np.eye(2), mu0=[1.0, 0.0], lam=0.9, prior_std=0.3)
    assert np.allclose(r.mu[-1], [1.0, 0.0], atol=1e-9)
    with pytest.raises(ParameterError, match="form"):
        dual_convex_filter(ms, y, u, np.zeros(2), np.eye(2), form="dual")
    with pytest.raises(ParameterError, match="metric"):
        dual_convex_filter(ms, y, u, np.zeros(2), np.eye(2), metric="euclid")
    with pytest.raises(ParameterError, match="constrain"):
        dual_convex_filter(ms, y, u, np.zeros(2), np.eye(2), constrain="cube")


def test_covariance_projection_is_a_perfect_measurement_update():
    """Simon & Chia (2002) with W = P⁻¹: the equality projection of z = [x; μ] equals a Kalman update with the
    noise-free measurement 1ᵀμ = 1 (independent formula), and leaves no variance along 1ᵀμ."""
    from fdikit.multimodel.convex_ekf import _covariance_projection

    rng = np.random.default_rng(7)
    n, N = 3, 3
    G = rng.standard_normal((n + N, n + N))
    P = G @ G.T + 0.1 * np.eye(n + N)
    z = np.concatenate([rng.standard_normal(n), [0.5, 0.4, 0.3]])
    zc, Pc = _covariance_projection(z, P, n, nonnegative=False)
    H = np.concatenate([np.zeros(n), np.ones(N)])[None, :]
    K = P @ H.T / (H @ P @ H.T + 1e-14)
    np.testing.assert_allclose(zc, z + (K * (1.0 - H @ z)).ravel(), atol=1e-9)
    np.testing.assert_allclose(Pc, P - K @ H @ P, atol=1e-9)
    assert abs(zc[n:].sum() - 1) < 1e-12 and np.abs(Pc @ H.T).max() < 1e-10
    zc, _ = _covariance_projection(np.concatenate([z[:n], [1.2, 0.3, -0.4]]), P, n, nonnegative=True)
    assert zc[n:].min() >= 0 and abs(zc[n:].sum() - 1) < 1e-9
