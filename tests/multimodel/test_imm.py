"""IMM filter (Hallouzi 2008, §2.3.1, Table 2.1 with the corrections stated in fdikit.multimodel.imm).

Oracles: a plain Kalman filter written here, filterpy 1.4.5's IMMEstimator on the same data, the
prior μ0 Πᵏ, and a simulated two-mode jump-Markov system (fixed seed).
"""

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator, KalmanFilter

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.gaussian import LinearGaussianModel
from fdikit.multimodel.imm import IMMFilter
from fdikit.trace import Trace


def _system(seed=0, n=3, m=1, p=2, scale=1.0):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    return dict(A=A, B=rng.normal(size=(n, m)), C=rng.normal(size=(p, n)), D=rng.normal(size=(p, m)),
                Q=0.05 * scale * np.eye(n), R=0.1 * np.eye(p))


def _simulate(A, B, C, D, Q, R, N, seed=1):
    rng = np.random.default_rng(seed)
    n, m = B.shape
    u = rng.normal(size=(N, m))
    x = np.zeros(n)
    y = np.empty((N, C.shape[0]))
    for k in range(N):
        y[k] = C @ x + D @ u[k] + rng.multivariate_normal(np.zeros(len(R)), R)
        x = A @ x + B @ u[k] + rng.multivariate_normal(np.zeros(n), Q)
    return u, y


def _kf(A, B, C, D, Q, R, u, y, x0, P0):
    """Reference KF in predictor form: update with y_k, then predict with u_k; NaN rows skip the update."""
    x, P = np.array(x0, float), np.array(P0, float)
    xs, Ps = [], []
    for k in range(len(y)):
        if np.all(np.isfinite(y[k])):
            S = C @ P @ C.T + R
            K = P @ C.T @ np.linalg.inv(S)
            x = x + K @ (y[k] - C @ x - D @ u[k])
            P = (np.eye(len(x)) - K @ C) @ P
        xs.append(x)
        Ps.append(P)
        x, P = A @ x + B @ u[k], A @ P @ A.T + Q
    return np.array(xs), np.array(Ps)


def test_one_mode_equals_kalman_filter():
    s = _system()
    u, y = _simulate(**s, N=200)
    imm = IMMFilter([LinearGaussianModel(**s)], [[1.0]], x0=np.ones(3), P0=2 * np.eye(3))
    res = imm.run(u, y)
    xk, Pk = _kf(**s, u=u, y=y, x0=np.ones(3), P0=2 * np.eye(3))
    assert np.max(abs(res.x - xk)) < 1e-10
    assert np.max(abs(res.P - Pk)) < 1e-10
    assert np.all(res.mu == 1.0)


def test_identical_modes_equal_kf_and_mu_follows_prior_through_pi():
    s = _system(seed=3)
    u, y = _simulate(**s, N=100)
    Pi = np.array([[0.7, 0.2, 0.1], [0.05, 0.9, 0.05], [0.3, 0.3, 0.4]])
    mu0 = np.array([0.6, 0.3, 0.1])
    modes = [LinearGaussianModel(**s, name=f"m{i}") for i in range(3)]
    res = IMMFilter(modes, Pi, mu0=mu0, x0=np.zeros(3), P0=np.eye(3)).run(u, y)
    xk, Pk = _kf(**s, u=u, y=y, x0=np.zeros(3), P0=np.eye(3))
    assert np.max(abs(res.x - xk)) < 1e-10
    assert np.max(abs(res.P - Pk)) < 1e-10
    prior = np.array([mu0 @ np.linalg.matrix_power(Pi, k) for k in range(100)])   # μ_k = μ0 Πᵏ
    assert np.max(abs(res.mu - prior)) < 1e-12


def _filterpy_pair(seed=5, N=300):
    """Three modes (different A, B, C, Q, R), D = 0; our priors = filterpy's state after its first predict."""
    rng = np.random.default_rng(seed)
    base = _system(seed=seed, n=4, m=1, p=2)
    modes = []
    for i in range(3):
        A = base["A"] + 0.05 * i * np.eye(4)
        C = base["C"] * (1.0 - 0.3 * i)
        modes.append(LinearGaussianModel(A=A, B=base["B"] * (1 + i), C=C, D=np.zeros((2, 1)),
                                         Q=(0.02 + 0.03 * i) * np.eye(4), R=(0.1 + 0.05 * i) * np.eye(2), name=f"m{i}"))
    Pi = np.array([[0.95, 0.03, 0.02], [0.05, 0.9, 0.05], [0.1, 0.1, 0.8]])
    mu_init = np.array([0.5, 0.3, 0.2])
    x_init, P_init = rng.normal(size=4), 0.5 * np.eye(4)
    u = rng.normal(size=(N + 1, 1))
    true = modes[1]
    _, y = _simulate(true.A, true.B, true.C, true.D, true.Q, true.R, N, seed=seed + 1)
    kfs = []
    for md in modes:
        f = KalmanFilter(dim_x=4, dim_z=2, dim_u=1)
        f.F, f.H, f.B, f.Q, f.R = md.A, md.C, md.B, md.Q, md.R
        f.x, f.P = x_init.reshape(4, 1).copy(), P_init.copy()
        kfs.append(f)
    fp = IMMEstimator(kfs, mu_init, Pi)   # filterpy's M[i, j] = P(i → j), the same orientation as Π
    ours = IMMFilter(modes, Pi, mu0=mu_init @ Pi,
                     x0=np.array([md.A @ x_init + md.B @ u[0] for md in modes]),
                     P0=np.array([md.A @ P_init @ md.A.T + md.Q for md in modes])).online()
    return fp, ours, u, y


def test_matches_filterpy_imm_estimator():
    fp, ours, u, y = _filterpy_pair()
    dx, dmu, mus = 0.0, 0.0, []
    for k in range(len(y)):
        fp.predict(u[k].reshape(1, 1))       # filterpy mixes, then predicts, then updates
        fp.update(y[k].reshape(2, 1))
        st = ours.step(u[k + 1], y[k])       # ours updates with y_k, then mixes and predicts with the next input
        assert np.all(fp.likelihood > 1e-300)  # both in range: filterpy floors underflowed likelihoods
        dx = max(dx, np.max(abs(st.x - fp.x.ravel())) / max(1.0, np.max(abs(st.x))))
        dmu = max(dmu, np.max(abs(st.mu - fp.mu)))
        assert np.max(abs(st.P - fp.P)) < 1e-8
        mus.append(st.mu)
    assert dx < 1e-8 and dmu < 1e-8
    mus = np.array(mus)
    assert np.all(mus >= 0) and np.max(abs(mus.sum(axis=1) - 1)) < 1e-12


def test_switching_system_mode_probability_follows_true_mode():
    rng = np.random.default_rng(42)
    A = np.array([[0.95, 0.1], [0.0, 0.9]])
    B = np.array([[0.0], [1.0]])
    Q, R = 0.01 * np.eye(2), 0.01 * np.eye(1)
    nominal = LinearGaussianModel(A=A, B=B, C=[[1.0, 0.0]], Q=Q, R=R, name="nominal")
    fault = LinearGaussianModel(A=A, B=0.2 * B, C=[[1.0, 0.0]], Q=Q, R=R, name="actuator loss")  # 80 % loss
    Pi = np.array([[0.99, 0.01], [0.01, 0.99]])
    N = 2000
    s = np.zeros(N, int)
    for k in range(1, N):
        s[k] = rng.choice(2, p=Pi[s[k - 1]])
    u = np.sign(np.sin(0.1 * np.arange(N)))[:, None]
    x, y = np.zeros(2), np.empty((N, 1))
    for k in range(N):
        md = (nominal, fault)[s[k]]
        y[k] = md.C @ x + rng.normal(0, 0.1)
        x = md.A @ x + md.B @ u[k] + rng.multivariate_normal(np.zeros(2), Q)
    res = IMMFilter([nominal, fault], Pi, x0=np.zeros(2), P0=0.1 * np.eye(2)).run(u, y)
    # y_k reveals s_{k-1} (the mode that drove x_k), so compare the probability of that mode
    hit = np.argmax(res.mu[1:], axis=1) == s[:-1]
    assert 0 < s.sum() < N and hit.mean() > 0.9                   # measured 0.953
    assert res.mu[1:][np.arange(N - 1), s[:-1]].mean() > 0.85     # measured 0.920
    d = res.diagnosis()
    assert d.hypotheses == ("nominal", "actuator loss")
    assert np.array_equal(d.alarm[1:], np.argmax(res.mu[1:], axis=1) == 1)
    assert set(np.unique(d.isolated)) == {"none", "actuator loss"}


def test_log_space_survives_outliers_and_long_runs():
    # static modes (A = 0): y ~ N(D u, Q + R), so the states cannot adapt to the data
    far = LinearGaussianModel(A=[[0.0]], C=[[1.0]], B=[[0.0]], D=[[1.0]], Q=[[1e-6]], R=[[1e-4]], name="far")
    near = LinearGaussianModel(A=[[0.0]], C=[[1.0]], B=[[0.0]], D=[[0.0]], Q=[[1e-6]], R=[[1e-4]], name="near")
    N = 20000
    y = 1e-2 * np.random.default_rng(0).normal(size=(N, 1))
    y[5000] = 1e3                                       # every likelihood underflows: log L ≈ −5e9
    u = np.ones((N, 1))                                 # the 'far' mode predicts y ≈ 1: log L ≈ −5e3 per sample
    res = IMMFilter([near, far], np.eye(2), x0=[0.0], P0=[[1e-6]]).run(u, y, store_covariance=False)
    assert res.log_likelihood[5000] < -1e6 and np.isfinite(res.log_likelihood).all()
    assert np.all(np.isfinite(res.log_mu[:, 0])) and np.all(res.log_mu[-1, 0] > -1e-9)
    assert np.isfinite(res.log_mu[-1, 1]) and res.log_mu[-1, 1] < -1e7          # far below exp's range, still finite
    assert np.all(np.isfinite(res.mu)) and np.max(abs(res.mu.sum(axis=1) - 1)) < 1e-12
    # the naive linear-domain normalisation L/ΣL would give 0/0 at the outlier sample
    assert np.exp(res.log_likelihood[5000]) == 0.0


def test_nan_measurement_is_prediction_only_and_online_equals_batch():
    s = _system(seed=7)
    u, y = _simulate(**s, N=60)
    y[[10, 11, 30]] = np.nan
    y[40, 0] = np.nan
    imm = IMMFilter([LinearGaussianModel(**s)], [[1.0]], x0=np.zeros(3), P0=np.eye(3))
    res = imm.run(u, y)
    xk, Pk = _kf(**s, u=u, y=y, x0=np.zeros(3), P0=np.eye(3))
    assert np.max(abs(res.x - xk)) < 1e-10 and np.max(abs(res.P - Pk)) < 1e-10
    assert np.flatnonzero(~res.valid).tolist() == [10, 11, 30, 40]
    stepper = imm.online()
    xs = np.array([stepper.step(u[k], y[k]).x for k in range(60)])
    assert np.array_equal(xs, res.x)
    trace = Trace(t=0.1 * np.arange(60), u=u, y=y, controls=("u",), outputs=("y1", "y2"))
    assert np.array_equal(imm.run(trace).x, res.x) and imm.run(trace).t[1] == 0.1


def test_bad_input_raises_clear_errors():
    s = _system()
    md = LinearGaussianModel(**s)
    with pytest.raises(ParameterError, match="rows summing to 1"):
        IMMFilter([md, md], [[0.9, 0.2], [0.1, 0.9]])
    with pytest.raises(ModelError, match="share the state"):
        IMMFilter([md, LinearGaussianModel(A=np.eye(2), C=np.eye(2), Q=np.eye(2), R=np.eye(2))], np.eye(2))
    with pytest.raises(ModelError, match="R must be positive definite"):
        LinearGaussianModel(A=np.eye(2), C=np.eye(2), Q=np.eye(2), R=np.zeros((2, 2)))
    with pytest.raises(DataError, match="NaN"):
        IMMFilter([md], [[1.0]]).run(np.full((5, 1), np.nan), np.zeros((5, 2)))
