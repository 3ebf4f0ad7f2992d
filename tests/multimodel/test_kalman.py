"""Kalman filter (covariance / square-root) and EKF building blocks (Hallouzi 2008, Table 2.1 step 2, (2.12),
(2.29)–(2.32), (2.46)–(2.51)).

Oracles: filterpy 1.4.5 (KalmanFilter, ExtendedKalmanFilter), scipy.linalg.solve_discrete_are, python-control dlqe,
brute-force joint Gaussian likelihood, and statistical whiteness of the innovations with fixed seeds.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.stats
from filterpy.kalman import ExtendedKalmanFilter as FpEKF
from filterpy.kalman import KalmanFilter as FpKF

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.gaussian import LinearGaussianModel, NonlinearGaussianModel
from fdikit.model import FaultModel
from fdikit.multimodel.ekf import (
    ExtendedKalmanFilter,
    ekf_update,
    extended_kalman_filter,
    numerical_jacobian,
)
from fdikit.multimodel.kalman import KalmanFilter, kalman_filter
from fdikit.multimodel.kalman_steps import kf_predict, kf_update, psd_sqrt, srcf_step, srkf_predict, srkf_update


def random_model(seed: int, n: int = 4, m: int = 2, p: int = 2) -> LinearGaussianModel:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= 0.95 / max(abs(np.linalg.eigvals(A)))
    G = rng.standard_normal((n, n))
    H = rng.standard_normal((p, p))
    return LinearGaussianModel(
        A=A,
        C=rng.standard_normal((p, n)),
        Q=0.1 * G @ G.T + 0.01 * np.eye(n),
        R=0.5 * H @ H.T + 0.1 * np.eye(p),
        B=rng.standard_normal((n, m)),
        D=rng.standard_normal((p, m)),
    )


def simulate(model: LinearGaussianModel, N: int, x0, P0, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.multivariate_normal(x0, P0)
    u = rng.standard_normal((N, model.m))
    y = np.empty((N, model.p))
    for k in range(N):
        y[k] = model.C @ x + model.D @ u[k] + rng.multivariate_normal(np.zeros(model.p), model.R)
        x = model.A @ x + model.B @ u[k] + rng.multivariate_normal(np.zeros(model.n), model.Q)
    return u, y


@pytest.fixture(scope="module")
def case():
    model = random_model(1)
    x0, P0 = np.array([1.0, -1.0, 0.5, 0.0]), np.diag([2.0, 1.0, 0.5, 1.5])
    u, y = simulate(model, 200, x0, P0, seed=2)
    return model, x0, P0, u, y


def test_covariance_and_square_root_forms_agree_over_200_steps(case):
    model, x0, P0, u, y = case
    cov = kalman_filter(model, u, y, x0, P0, form="covariance")
    sqr = kalman_filter(model, u, y, x0, P0, form="square_root")
    for name in ("x_filt", "P_filt", "x_pred", "P_pred", "innovations", "S", "log_likelihood"):
        a, b = getattr(cov, name), getattr(sqr, name)
        assert np.max(np.abs(a - b)) < 1e-10 * max(1.0, np.max(np.abs(a))), name
    assert cov.valid.all() and cov.x_filt.shape == (200, 4) and cov.S.shape == (200, 2, 2)


def test_srcf_step_2_29_equals_update_then_predict(case):
    """Hallouzi 2008, Table 2.2 step 1: one QR of (2.29) + (2.31) reproduces a KF step to rounding."""
    model, x0, P0, u, y = case
    S = psd_sqrt(P0)
    Qs, Rs = psd_sqrt(model.Q), psd_sqrt(model.R)
    x, P = x0, P0
    for k in range(50):
        xf, Sf, xn, Sn, e, Re, ll = srcf_step(x, S, y[k], model.A, model.C, model.B, model.D, u[k], Qs, Rs)
        xf2, Pf2, e2, S2, ll2 = kf_update(x, P, y[k], model.C, model.D, u[k], model.R)
        xn2, Pn2 = kf_predict(xf2, Pf2, model.A, model.B, u[k], model.Q)
        np.testing.assert_allclose(xf, xf2, atol=1e-11)
        np.testing.assert_allclose(Sf @ Sf.T, Pf2, atol=1e-11)
        np.testing.assert_allclose(xn, xn2, atol=1e-11)
        np.testing.assert_allclose(Sn @ Sn.T, Pn2, atol=1e-11)
        np.testing.assert_allclose(Re @ Re.T, S2, atol=1e-11)
        np.testing.assert_allclose(e, e2, atol=1e-12)
        assert abs(ll - ll2) < 1e-10
        assert np.allclose(np.triu(Sn, 1), 0) and np.all(np.diag(Sn) >= 0)
        x, S, P = xn, Sn, Pn2


def test_equals_filterpy_kalman_filter(case):
    model, x0, P0, u, y = case
    res = kalman_filter(model, u, y, x0, P0)
    fp = FpKF(dim_x=model.n, dim_z=model.p, dim_u=model.m)
    fp.x, fp.P, fp.F, fp.B, fp.H = x0.reshape(-1, 1), P0.copy(), model.A, model.B, model.C
    fp.Q, fp.R = model.Q, model.R
    worst = 0.0
    for k in range(len(y)):
        fp.update((y[k] - model.D @ u[k]).reshape(-1, 1))  # filterpy has no feedthrough: subtract D u
        worst = max(
            worst,
            np.max(np.abs(fp.x.ravel() - res.x_filt[k])),
            np.max(np.abs(fp.P - res.P_filt[k])),
            np.max(np.abs(fp.y.ravel() - res.innovations[k])),
            np.max(np.abs(fp.S - res.S[k])),
            abs(fp.log_likelihood - res.log_likelihood[k]),
        )
        fp.predict(u=u[k].reshape(-1, 1))
        worst = max(worst, np.max(np.abs(fp.x.ravel() - res.x_pred[k])), np.max(np.abs(fp.P - res.P_pred[k])))
    assert worst < 1e-10


def test_steady_state_matches_dare_and_dlqe(case):
    model = case[0]
    N = 400
    u, y = np.zeros((N, model.m)), np.zeros((N, model.p))  # P(k) does not depend on the data
    res = kalman_filter(model, u, y, np.zeros(4), 10.0 * np.eye(4))
    P_dare = scipy.linalg.solve_discrete_are(model.A.T, model.C.T, model.Q, model.R)
    assert np.max(np.abs(res.P_pred[-1] - P_dare)) < 1e-10 * np.max(np.abs(P_dare))
    L_dlqe, P_dlqe, poles = control.dlqe(model.A, np.eye(4), model.C, model.Q, model.R)
    np.testing.assert_allclose(res.P_pred[-1], P_dlqe, atol=1e-10)
    # filter gain K = P Cᵀ S⁻¹ recovered from kf_update with unit innovations (x = 0, y = e_i)
    P = res.P_pred[-1]
    K = np.column_stack([kf_update(np.zeros(4), P, np.eye(2)[i], model.C, R=model.R)[0] for i in range(2)])
    np.testing.assert_allclose(K, P @ model.C.T @ np.linalg.inv(model.C @ P @ model.C.T + model.R), atol=1e-12)
    # python-control 0.10.2 dlqe returns the one-step predictor gain A P Cᵀ (C P Cᵀ + R)⁻¹ = A K
    np.testing.assert_allclose(model.A @ K, L_dlqe, atol=1e-10)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(model.A - model.A @ K @ model.C)),
                               np.sort_complex(poles), atol=1e-8)


def test_sum_of_log_likelihoods_is_the_joint_gaussian_density():
    """Prediction-error decomposition: Σ log N(e_k; 0, S_k) = log p(y_0..y_{N−1}) (brute force, stacked)."""
    model = random_model(7, n=3, m=1, p=2)
    N, x0, P0 = 6, np.array([0.5, 0.0, -1.0]), np.diag([1.0, 2.0, 0.3])
    u, y = simulate(model, N, x0, P0, seed=8)
    res = kalman_filter(model, u, y, x0, P0, form="square_root")
    n, p = model.n, model.p
    O = np.vstack([model.C @ np.linalg.matrix_power(model.A, k) for k in range(N)])
    Tw = np.zeros((N * p, N * n))
    mean = O @ x0
    for k in range(N):
        mean[k * p:(k + 1) * p] += model.D @ u[k]
        for j in range(k):
            blk = model.C @ np.linalg.matrix_power(model.A, k - 1 - j)
            Tw[k * p:(k + 1) * p, j * n:(j + 1) * n] = blk
            mean[k * p:(k + 1) * p] += blk @ model.B @ u[j]
    cov = O @ P0 @ O.T + Tw @ np.kron(np.eye(N), model.Q) @ Tw.T + np.kron(np.eye(N), model.R)
    joint = scipy.stats.multivariate_normal(mean, cov).logpdf(y.ravel())
    assert abs(res.log_likelihood.sum() - joint) < 1e-9 * abs(joint)


def _whiteness(res: np.ndarray, S: np.ndarray, lags: int = 10) -> tuple[float, float, float]:
    """Max |sample cov − I| of normalised innovations, max |autocorrelation| at lags 1..lags, mean NIS."""
    z = np.array([scipy.linalg.solve_triangular(np.linalg.cholesky(Sk), ek, lower=True) for ek, Sk in zip(res, S)])
    N = len(z)
    cov_err = np.max(np.abs(z.T @ z / N - np.eye(z.shape[1])))
    auto = max(np.max(np.abs(z[k:].T @ z[:-k] / N)) for k in range(1, lags + 1))
    return cov_err, auto, float(np.mean(np.sum(z**2, axis=1)))


def test_innovations_of_a_correct_filter_are_white_with_covariance_S():
    model = random_model(3, n=4, m=1, p=2)
    N = 4000
    x0, P0 = np.zeros(4), np.eye(4)
    u, y = simulate(model, N, x0, P0, seed=4)
    res = kalman_filter(model, u, y, x0, P0)
    cov_err, auto, nis = _whiteness(res.innovations, res.S)
    # standard errors: diagonal of the sample covariance sqrt(2/N) = 0.022, cross terms 1/sqrt(N) = 0.016
    assert cov_err < 5 * np.sqrt(2 / N)
    assert auto < 5 / np.sqrt(N)
    assert abs(nis - 2) < 5 * np.sqrt(2 * 2 / N)  # NIS ~ chi2(2): mean 2, std of the mean sqrt(4/N)
    # the same test rejects a filter with the wrong dynamics (shows it can fail)
    wrong = LinearGaussianModel(0.5 * model.A, model.C, model.Q, model.R, B=model.B, D=model.D)
    res_w = kalman_filter(wrong, u, y, x0, P0)
    cov_w, auto_w, _ = _whiteness(res_w.innovations, res_w.S)
    assert auto_w > 5 / np.sqrt(N) or cov_w > 5 * np.sqrt(2 / N)


@pytest.mark.parametrize("form", ["covariance", "square_root"])
def test_nan_measurement_skips_the_update_and_marks_the_sample_invalid(case, form):
    model, x0, P0, u, y = case
    kf = KalmanFilter(model, x0, P0, form=form)
    for k in range(5):
        kf.step(u[k], y[k])
    x_before, P_before = kf.x.copy(), kf.P.copy()
    np.testing.assert_allclose(kf.P_sqrt @ kf.P_sqrt.T, P_before, atol=1e-13)
    step = kf.step(u[5], [np.nan, y[5, 1]])
    assert not step.valid and np.isnan(step.innovation).all() and np.isnan(step.log_likelihood)
    np.testing.assert_allclose(step.x_filt, x_before, atol=1e-14)
    np.testing.assert_allclose(step.x_pred, model.A @ x_before + model.B @ u[5], atol=1e-12)
    np.testing.assert_allclose(step.P_pred, model.A @ P_before @ model.A.T + model.Q, atol=1e-12)
    # afterwards the filter continues from the pure prediction: equals the step functions run by hand
    nxt = kf.step(u[6], y[6])
    xf, Pf, e, S, ll = kf_update(step.x_pred, step.P_pred, y[6], model.C, model.D, u[6], model.R)
    assert nxt.valid
    np.testing.assert_allclose(nxt.x_filt, xf, atol=1e-11)
    np.testing.assert_allclose(nxt.P_filt, Pf, atol=1e-11)
    y_bad = y.copy()
    y_bad[3, 0] = np.nan
    with pytest.raises(DataError, match="KalmanFilter.step"):
        kalman_filter(model, u, y_bad, x0, P0, form=form)


def test_square_root_form_accepts_a_singular_prior(case):
    model, _, _, u, y = case
    P0 = np.zeros((4, 4))
    P0[0, 0] = 1.0  # rank 1: Cholesky fails, the QR fallback is used
    S = psd_sqrt(P0)
    np.testing.assert_allclose(S @ S.T, P0, atol=1e-15)
    a = kalman_filter(model, u[:50], y[:50], np.zeros(4), P0)
    b = kalman_filter(model, u[:50], y[:50], np.zeros(4), P0, form="square_root")
    assert np.max(np.abs(a.x_filt - b.x_filt)) < 1e-10
    assert np.max(np.abs(a.P_pred - b.P_pred)) < 1e-10


def test_discrete_fault_model_input(case):
    model, x0, P0, u, y = case
    fm = FaultModel(A=model.A, C=model.C, Bu=model.B, Du=model.D, dt=0.1).with_sensor_faults(["y0"])
    a = kalman_filter(fm, u, y, x0, P0, Q=model.Q, R=model.R)
    b = kalman_filter(model, u, y, x0, P0)
    np.testing.assert_array_equal(a.x_filt, b.x_filt)
    with pytest.raises(ModelError, match="discretize"):
        kalman_filter(fm.replace(dt=None), u, y, x0, P0, Q=model.Q, R=model.R)
    with pytest.raises(ParameterError, match="pass Q"):
        kalman_filter(fm, u, y, x0, P0)


def test_bad_input_errors(case):
    model, x0, P0, u, y = case
    with pytest.raises(ModelError, match="Q must be positive semidefinite"):
        LinearGaussianModel(model.A, model.C, Q=-np.eye(4), R=model.R)
    with pytest.raises(ModelError, match="R must be symmetric"):
        LinearGaussianModel(model.A, model.C, Q=model.Q, R=[[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(ModelError, match="R must be positive definite"):
        LinearGaussianModel(model.A, model.C, Q=model.Q, R=np.zeros((2, 2)))
    with pytest.raises(ModelError, match=r"C has 3 columns but must have 4 \(shape \(2, 3\)\)"):
        LinearGaussianModel(model.A, np.ones((2, 3)), Q=model.Q, R=model.R)
    with pytest.raises(ParameterError, match="P0 must be positive semidefinite"):
        KalmanFilter(model, x0, -P0)
    with pytest.raises(ParameterError, match="x0 has 3 entries"):
        KalmanFilter(model, x0[:3], P0)
    with pytest.raises(DataError, match="y must be an N x 2"):
        kalman_filter(model, u, y[:, :1], x0, P0)
    with pytest.raises(DataError, match="u must be an N x 2"):
        kalman_filter(model, u[:10], y, x0, P0)
    with pytest.raises(ParameterError, match="form must be"):
        KalmanFilter(model, x0, P0, form="information")
    with pytest.raises(ModelError, match="Q must be positive semidefinite"):
        NonlinearGaussianModel(f=lambda x, u: x, h=lambda x, u: x, Q=[[-1.0]], R=[[1.0]])


# ------------------------------------------------------------------------------------------------ EKF
def test_ekf_on_a_linear_model_equals_the_kalman_filter(case):
    model, x0, P0, u, y = case
    kf = kalman_filter(model, u, y, x0, P0)

    def f(x, uk):
        return model.A @ x + model.B @ uk

    def h(x, uk):
        return model.C @ x + model.D @ uk

    exact = NonlinearGaussianModel(f, h, model.Q, model.R, n_inputs=2,
                                   f_jacobian=lambda x, uk: model.A, h_jacobian=lambda x, uk: model.C)
    fd = NonlinearGaussianModel(f, h, model.Q, model.R, n_inputs=2)
    r_exact = extended_kalman_filter(exact, u, y, x0, P0)
    r_fd = extended_kalman_filter(fd, u, y, x0, P0)
    for name in ("x_filt", "P_filt", "x_pred", "P_pred", "innovations", "S", "log_likelihood"):
        ref = getattr(kf, name)
        assert np.max(np.abs(getattr(r_exact, name) - ref)) < 1e-13 * max(1.0, np.max(np.abs(ref))), name
        assert np.max(np.abs(getattr(r_fd, name) - getattr(kf, name))) < 1e-8, name


def pendulum(dt: float = 0.05):
    g_l, c = 9.81, 0.3

    def f(x, u):
        return np.array([x[0] + dt * x[1], x[1] + dt * (-g_l * np.sin(x[0]) - c * x[1] + u[0])])

    def F(x, u):
        return np.array([[1.0, dt], [-dt * g_l * np.cos(x[0]), 1.0 - dt * c]])

    def h(x, u):
        return np.array([np.sin(x[0]), x[0] * x[1]])

    def H(x, u):
        return np.array([[np.cos(x[0]), 0.0], [x[1], x[0]]])

    return f, F, h, H


def test_finite_difference_jacobians_match_analytic_ones():
    f, F, h, H = pendulum()
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(20):
        x, u = rng.uniform(-3, 3, 2) * [1.0, 10.0], rng.standard_normal(1)
        worst = max(worst, np.max(np.abs(numerical_jacobian(f, x, u) - F(x, u))) / np.max(np.abs(F(x, u))),
                    np.max(np.abs(numerical_jacobian(h, x, u) - H(x, u))) / np.max(np.abs(H(x, u))))
    assert worst < 1e-9  # measured 1.9e-10 (step ε^{1/3} max(1, |x_i|), |x_2| up to 30)


def test_ekf_equals_filterpy_extended_kalman_filter_on_a_pendulum():
    f, F, h, H = pendulum()
    Q, R = np.diag([1e-4, 1e-3]), np.diag([0.01, 0.02])
    model = NonlinearGaussianModel(f, h, Q, R, n_inputs=1, f_jacobian=F, h_jacobian=H)
    rng = np.random.default_rng(6)
    N, x = 300, np.array([1.0, 0.0])
    u = 0.5 * rng.standard_normal((N, 1))
    y, angle = np.empty((N, 2)), np.empty(N)
    for k in range(N):
        angle[k] = x[0]
        y[k] = h(x, u[k]) + rng.multivariate_normal(np.zeros(2), R)
        x = f(x, u[k]) + rng.multivariate_normal(np.zeros(2), Q)
    x0, P0 = np.array([0.8, 0.1]), np.diag([0.1, 0.1])
    ours = extended_kalman_filter(model, u, y, x0, P0)

    class PendulumEKF(FpEKF):
        def predict_x(self, uk=0):
            self.x = f(self.x.ravel(), uk).reshape(-1, 1)

    fp = PendulumEKF(dim_x=2, dim_z=2, dim_u=1)
    fp.x, fp.P, fp.Q, fp.R = x0.reshape(-1, 1), P0.copy(), Q, R
    worst = 0.0
    for k in range(N):
        fp.update(y[k].reshape(-1, 1), lambda xx, uk=u[k]: H(xx.ravel(), uk),
                  lambda xx, uk=u[k]: h(xx.ravel(), uk).reshape(-1, 1))
        worst = max(worst, np.max(np.abs(fp.x.ravel() - ours.x_filt[k])), np.max(np.abs(fp.P - ours.P_filt[k])),
                    np.max(np.abs(fp.y.ravel() - ours.innovations[k])))
        fp.F = F(fp.x.ravel(), u[k])
        fp.predict(u[k])
        worst = max(worst, np.max(np.abs(fp.x.ravel() - ours.x_pred[k])), np.max(np.abs(fp.P - ours.P_pred[k])))
    assert worst < 1e-10
    # and the EKF tracks: RMS angle error after 50 samples below the std 0.1 of the sin(angle) sensor
    rms = np.sqrt(np.mean((ours.x_filt[50:, 0] - angle[50:]) ** 2))
    assert rms < 0.05, rms


def test_online_ekf_nan_handling_and_update_oracle():
    f, F, h, H = pendulum()
    model = NonlinearGaussianModel(f, h, np.eye(2) * 1e-3, np.eye(2) * 0.01, n_inputs=1, f_jacobian=F, h_jacobian=H)
    ekf = ExtendedKalmanFilter(model, [0.3, 0.0], np.eye(2) * 0.1)
    s1 = ekf.step([0.0], [np.nan, 0.0])
    assert not s1.valid and np.isnan(s1.log_likelihood)
    np.testing.assert_allclose(s1.x_pred, f(np.array([0.3, 0.0]), [0.0]))
    np.testing.assert_allclose(s1.P_pred, F([0.3, 0.0], [0.0]) @ (np.eye(2) * 0.1) @ F([0.3, 0.0], [0.0]).T
                               + np.eye(2) * 1e-3, atol=1e-15)
    s2 = ekf.step([0.0], [0.3, 0.0])
    xf, Pf, e, S, ll = ekf_update(s1.x_pred, s1.P_pred, [0.3, 0.0], h, [0.0], model.R, H)
    assert s2.valid
    np.testing.assert_allclose(s2.x_filt, xf, atol=1e-15)
    np.testing.assert_allclose(ll, scipy.stats.multivariate_normal(np.zeros(2), S).logpdf(e), atol=1e-12)
    with pytest.raises(ModelError, match="Jacobian H = dh/dx has shape"):
        ekf_update([0.0, 0.0], np.eye(2), [0.0, 0.0], h, [0.0], model.R, lambda x, u: np.eye(3))


def test_srkf_update_identities():
    """Hallouzi 2008 (2.29): R_e R_eᵀ = C P Cᵀ + R and S⁺S⁺ᵀ = P − P Cᵀ (C P Cᵀ + R)⁻¹ C P."""
    rng = np.random.default_rng(9)
    M = rng.standard_normal((3, 3))
    P, C, R = M @ M.T + np.eye(3), rng.standard_normal((2, 3)), np.diag([0.2, 0.4])
    x, S, e, Re, ll = srkf_update(np.zeros(3), psd_sqrt(P), np.ones(2), C, R_sqrt=psd_sqrt(R))
    Sig = C @ P @ C.T + R
    np.testing.assert_allclose(Re @ Re.T, Sig, atol=1e-12)
    np.testing.assert_allclose(S @ S.T, P - P @ C.T @ np.linalg.solve(Sig, C @ P), atol=1e-12)
    np.testing.assert_allclose(x, P @ C.T @ np.linalg.solve(Sig, np.ones(2)), atol=1e-12)
    xp, Sp = srkf_predict(x, S, np.eye(3) * 0.5, Q_sqrt=np.eye(3))
    np.testing.assert_allclose(Sp @ Sp.T, 0.25 * S @ S.T + np.eye(3), atol=1e-12)


@pytest.mark.parametrize("inputs", [0, 1])
def test_batch_runner_switches_to_the_steady_state_filter_exactly(inputs):
    """Once P(k+1|k) has settled the batch runner uses the LTI steady-state filter (blocked solver);
    every output equals the step-by-step recursion to round-off (measured ≤ 7e-16 relative)."""
    from fdikit.multimodel.kalman import KalmanFilter

    rng = np.random.default_rng(7)
    n, p, N = 4, 2, 3000
    A = rng.normal(size=(n, n))
    A *= 0.9 / np.abs(np.linalg.eigvals(A)).max()
    B = rng.normal(size=(n, inputs))
    D = rng.normal(size=(p, inputs))
    mdl = LinearGaussianModel(A, rng.normal(size=(p, n)), 0.1 * np.eye(n), 0.5 * np.eye(p), B=B, D=D)
    u = rng.normal(size=(N, inputs)) if inputs else None
    y = rng.normal(size=(N, p))
    fast = kalman_filter(mdl, u, y, np.zeros(n), np.eye(n))
    kf = KalmanFilter(mdl, np.zeros(n), np.eye(n))
    steps = [kf.step(None if u is None else u[k], y[k]) for k in range(N)]
    for field in ("x_filt", "x_pred", "P_filt", "P_pred", "innovations", "S"):
        ref = np.array([getattr(s, field if field != "innovations" else "innovation") for s in steps])
        got = getattr(fast, field)
        assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max(), field
    ll = np.array([s.log_likelihood for s in steps])
    np.testing.assert_allclose(fast.log_likelihood, ll, rtol=1e-12, atol=1e-12)
    assert fast.valid.all()


def test_online_step_switches_to_the_steady_filter_and_back():
    """Once P(k+1|k) has settled the online step uses the constant gain: same numbers as the recursion to
    round-off; a NaN sample (skipped update) sends it back to the recursion."""
    from fdikit.gaussian import LinearGaussianModel
    from fdikit.multimodel.kalman import KalmanFilter

    rng = np.random.default_rng(3)
    A = np.array([[0.9, 0.2], [0.0, 0.8]])
    md = LinearGaussianModel(A=A, C=np.array([[1.0, 0.0]]), Q=0.01 * np.eye(2), R=np.array([[0.1]]),
                             B=np.array([[0.0], [1.0]]))
    u, y = rng.standard_normal((400, 1)), rng.standard_normal((400, 1))
    y[300] = np.nan
    fast, ref = KalmanFilter(md, np.zeros(2), np.eye(2)), KalmanFilter(md, np.zeros(2), np.eye(2))
    ref._track_settling = lambda *a: None  # the plain recursion throughout
    switched = []
    for k in range(400):
        a, b = fast.step(u[k], y[k]), ref.step(u[k], y[k])
        switched.append(fast._steady is not None)
        np.testing.assert_allclose(a.x_filt, b.x_filt, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a.P_pred, b.P_pred, rtol=1e-12, atol=1e-14)
        if b.valid:
            assert abs(a.log_likelihood - b.log_likelihood) < 1e-10
    assert switched[299] and not switched[300] and switched[-1]
