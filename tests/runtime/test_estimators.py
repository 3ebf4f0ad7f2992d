"""The compiled Kalman filter step and IMM cycle (fdikit.runtime.estimators) against their references.

Oracles: the reference online steps (KalmanFilter.step, IMMStepper.step) sample by sample, the reference batch runs
(kalman_filter, IMMFilter.run), and filterpy's IMMEstimator on the set-up of tests/multimodel/test_imm.py
(``_filterpy_pair``, rebuilt here: the test modules are not importable from each other).
"""

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator
from filterpy.kalman import KalmanFilter as FpKF

from fdikit.errors import DataError, ParameterError
from fdikit.gaussian import LinearGaussianModel
from fdikit.multimodel.imm import IMMFilter
from fdikit.multimodel.kalman import KalmanFilter, kalman_filter
from fdikit.runtime.estimators import CompiledIMM, CompiledKalman, compile_imm, compile_kalman

KF_FIELDS = ("x_filt", "P_filt", "x_pred", "P_pred", "innovation", "S", "log_likelihood")
IMM_FIELDS = ("x", "P", "mu", "x_modes", "P_modes", "log_likelihood")


def _close(ref, got, what):
    """Equal to 1e-12 relative to the data's magnitude; NaN exactly where the reference has NaN."""
    ref, got = np.asarray(ref, float), np.asarray(got, float)
    assert np.array_equal(np.isnan(ref), np.isnan(got)), what
    scale = np.nanmax(np.abs(ref)) if np.isfinite(ref).any() else 1.0
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * scale, err_msg=what)


def _spd(rng, n, scale):
    G = rng.normal(size=(n, n))
    return scale * (G @ G.T / n + 0.5 * np.eye(n))


def _model(seed=0, n=6, m=2, p=3):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= 0.95 / max(abs(np.linalg.eigvals(A)))
    return LinearGaussianModel(A, rng.normal(size=(p, n)), _spd(rng, n, 0.02), _spd(rng, p, 0.1),
                               B=rng.normal(size=(n, m)), D=rng.normal(size=(p, m)))


def _data(md, N, seed=1, bad=True):
    """Simulated record with a sensor bias (k ≥ N/2), an actuator loss (k ≥ 3N/4) and, if ``bad``, NaN/inf samples."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(N, md.m))
    x, y = np.zeros(md.n), np.empty((N, md.p))
    Lq, Lr = np.linalg.cholesky(md.Q), np.linalg.cholesky(md.R)
    for k in range(N):
        gain = 0.3 if k >= 3 * N // 4 else 1.0
        y[k] = md.C @ x + md.D @ u[k] + Lr @ rng.normal(size=md.p)
        x = md.A @ x + gain * (md.B @ u[k]) + Lq @ rng.normal(size=md.n)
    y[N // 2:, 0] += 2.0
    if bad:
        y[[3, 4, 500, N // 2, N - 2]] = np.nan      # gaps before, during and after settling, at the fault onset
        y[1000, 1] = np.inf
        y[7000 % N, 0] = -np.inf
    return u, y


def _steps(ref_step, compiled, u, y):
    ref = {f: [] for f in KF_FIELDS + ("valid",)}
    got = {f: [] for f in KF_FIELDS + ("valid",)}
    for k in range(len(y)):
        s = ref_step(u[k], y[k])
        compiled.step(u[k], y[k])
        c = compiled.result()
        for f in ref:
            ref[f].append(getattr(s, f))
            got[f].append(getattr(c, f))
    return ref, got


# ---------------------------------------------------------------------------------------- Kalman filter
def test_kalman_equals_reference_over_a_long_faulty_run_with_bad_samples_and_after_reset():
    md = _model()
    N = 20000
    u, y = _data(md, N)
    ck = compile_kalman(KalmanFilter(md, np.ones(md.n), 2 * np.eye(md.n)))
    for _ in range(2):  # the second pass after reset()
        kf = KalmanFilter(md, np.ones(md.n), 2 * np.eye(md.n))
        steady = []

        def ref_step(uk, yk, kf=kf, steady=steady):
            s = kf.step(uk, yk)
            steady.append((kf._steady is not None, ck.steady))
            return s

        ref, got = _steps(ref_step, ck, u, y)
        for f in KF_FIELDS:
            _close(np.array(ref[f]), np.array(got[f]), f)
        assert ref["valid"] == got["valid"] and sum(not v for v in got["valid"]) == 7
        assert np.mean([a == b for a, b in steady]) > 0.99 and np.mean([b for _, b in steady]) > 0.9
        _close(kf.x, ck.x, "x")
        _close(kf.P, ck.P, "P")
        ck.reset()
    assert ck.x.tolist() == [1.0] * md.n and not ck.valid


def test_kalman_equals_the_batch_filter_and_the_gain_is_the_steady_one():
    md = _model(seed=3)
    u, y = _data(md, 3000, bad=False)
    res = kalman_filter(md, u, y, np.zeros(md.n), np.eye(md.n))
    ck = compile_kalman(KalmanFilter(md, np.zeros(md.n), np.eye(md.n)))
    rows = []
    for k in range(len(y)):
        ck.step(u[k], y[k])
        rows.append((ck.x_filt, ck.x, ck.P_filt, ck.P, ck.innovation, ck.S, ck.log_likelihood))
    for i, f in enumerate(("x_filt", "x_pred", "P_filt", "P_pred", "innovations", "S", "log_likelihood")):
        _close(getattr(res, f), np.array([r[i] for r in rows]), f)
    assert ck.steady
    P, S = ck.P, ck.S
    _close(P @ md.C.T @ np.linalg.inv(S), ck.gain, "gain")


def test_square_root_form_equals_reference():
    md = _model(seed=5, n=4, m=1, p=2)
    u, y = _data(md, 1500)
    kf = KalmanFilter(md, np.zeros(4), np.eye(4), form="square_root")
    ck = compile_kalman(KalmanFilter(md, np.zeros(4), np.eye(4), form="square_root"))
    ref, got = _steps(kf.step, ck, u, y)
    for f in KF_FIELDS:
        _close(np.array(ref[f]), np.array(got[f]), f)
    assert ref["valid"] == got["valid"] and not ck.steady
    _close(kf.P_sqrt @ kf.P_sqrt.T, ck.P_sqrt @ ck.P_sqrt.T, "P_sqrt")


def test_kalman_inputs_are_converted_as_the_reference_and_bad_ones_raise_data_errors():
    md = _model(seed=2, n=3, m=2, p=2)
    u, y = _data(md, 20, bad=False)
    a = compile_kalman(KalmanFilter(md, np.zeros(3), np.eye(3)))
    b = CompiledKalman(KalmanFilter(md, np.zeros(3), np.eye(3)))
    ro = y[0].copy()
    ro.setflags(write=False)
    a.step(u[0], ro)                                            # read-only arrays take the fast path
    b.step(u[0].tolist(), y[0].reshape(2, 1))
    _close(a.x, b.x, "list / column input")
    b.step(u[1].astype(np.float32), list(y[1]))
    a.step(u[1].astype(np.float32).astype(float), y[1])
    _close(a.x, b.x, "float32 input")
    x = a.x
    with pytest.raises(DataError, match="u has 3 entries but must have 2"):
        a.step(np.zeros(3), y[2])
    with pytest.raises(DataError, match="y has 1 entries but must have 2"):
        a.step(u[2], [1.0])
    with pytest.raises(DataError, match="1-D vector"):
        a.step(u[2], np.zeros((2, 2)))
    with pytest.raises(DataError, match="NaN/inf entry"):
        a.step(np.array([np.nan, 0.0]), y[2])
    assert np.array_equal(a.x, x)                               # refused samples leave the state as it was
    with pytest.raises(DataError):
        a.step(u[2], ["a", "b"])
    m0 = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    c = compile_kalman(KalmanFilter(m0, [0.0], [[1.0]]))
    with pytest.raises(ParameterError, match="no sample yet"):
        c.result()
    assert c.step(None, [1.0]).tolist() == [0.5] and c.result().x_pred.tolist() == [0.45]
    with pytest.raises(ParameterError, match="KalmanFilter"):
        compile_kalman(m0)


# ---------------------------------------------------------------------------------------- IMM
def _switching(N, seed=42):
    """Two modes (nominal, 80 % actuator loss) with Markov switches, as tests/multimodel/test_imm.py."""
    rng = np.random.default_rng(seed)
    A = np.array([[0.95, 0.1], [0.0, 0.9]])
    B = np.array([[0.0], [1.0]])
    Q, R = 0.01 * np.eye(2), 0.01 * np.eye(1)
    modes = [LinearGaussianModel(A=A, B=g * B, C=[[1.0, 0.0]], Q=Q, R=R, name=nm)
             for g, nm in ((1.0, "nominal"), (0.2, "actuator loss"))]
    Pi = np.array([[0.99, 0.01], [0.01, 0.99]])
    s = np.zeros(N, int)
    for k in range(1, N):
        s[k] = rng.choice(2, p=Pi[s[k - 1]])
    u = np.sign(np.sin(0.1 * np.arange(N)))[:, None]
    x, y = np.zeros(2), np.empty((N, 1))
    for k in range(N):
        md = modes[s[k]]
        y[k] = md.C @ x + rng.normal(0, 0.1)
        x = md.A @ x + md.B @ u[k] + rng.multivariate_normal(np.zeros(2), Q)
    if N > 5000:
        y[[10, 11, 400, 3000]] = np.nan
        y[5000] = 50.0                                          # an outlier
    return IMMFilter(modes, Pi, x0=np.zeros(2), P0=0.1 * np.eye(2)), u, y, s


def _three_modes(seed=5):
    """Three modes (different A, B, C, Q, R) as ``_filterpy_pair`` of tests/multimodel/test_imm.py."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(4, 4))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    B, C = rng.normal(size=(4, 1)), rng.normal(size=(2, 4))
    return [LinearGaussianModel(A=A + 0.05 * i * np.eye(4), B=B * (1 + i), C=C * (1.0 - 0.3 * i), D=np.zeros((2, 1)),
                                Q=(0.02 + 0.03 * i) * np.eye(4), R=(0.1 + 0.05 * i) * np.eye(2), name=f"m{i}")
            for i in range(3)]


def _imm_run(ref, ci, u, y):
    out = {f: ([], []) for f in IMM_FIELDS + ("log_mu",)}
    valid = ([], [])
    for k in range(len(y)):
        s = ref.step(u[k], y[k])
        ci.step(u[k], y[k])
        c = ci.result()
        for f in IMM_FIELDS:
            out[f][0].append(getattr(s, f))
            out[f][1].append(getattr(c, f))
        out["log_mu"][0].append(ref.log_mu.copy())
        out["log_mu"][1].append(ci.log_mu)
        valid[0].append(s.valid)
        valid[1].append(c.valid)
    for f, (a, b) in out.items():
        _close(np.array(a), np.array(b), f)
    assert valid[0] == valid[1]
    return valid[1]


def test_imm_equals_reference_with_mode_switches_gaps_outliers_and_after_reset():
    imm, u, y, s = _switching(6000)
    ci = compile_imm(imm)
    for _ in range(2):
        valid = _imm_run(imm.online(), ci, u, y)
        assert sum(not v for v in valid) == 4
        ci.reset()
    res = imm.run(u, y)                                         # and the batch run
    mus, xs, lls = [], [], []
    for k in range(len(y)):
        mus.append(ci.step(u[k], y[k]).copy())
        xs.append(ci.x)
        lls.append(ci.log_likelihood)
    _close(res.mu, np.array(mus), "mu")
    _close(res.x, np.array(xs), "x")
    _close(res.log_likelihood, np.array(lls), "log_likelihood")
    assert np.mean(np.argmax(res.mu[1:], axis=1) == s[:-1]) > 0.9   # the filter does track the mode


def test_imm_three_modes_with_a_probability_floor_and_a_zero_transition():
    modes = _three_modes()
    Pi = np.array([[0.95, 0.05, 0.0], [0.05, 0.9, 0.05], [0.1, 0.1, 0.8]])
    rng = np.random.default_rng(9)
    N = 4000
    u = rng.normal(size=(N, 1))
    x, y = np.zeros(4), np.empty((N, 2))
    for k in range(N):  # data of m0, then m1 (k ≥ 1500), then m2 (k ≥ 3000)
        md = modes[(k >= 1500) + (k >= 3000)]
        y[k] = md.C @ x + rng.multivariate_normal(np.zeros(2), md.R)
        x = md.A @ x + md.B @ u[k] + rng.multivariate_normal(np.zeros(4), md.Q)
    y[[5, 6, 2000]] = np.nan
    # (on data no mode explains, e.g. white noise, μ is sensitive at 1e-11 to a 1-ulp change of y in the reference
    # itself, so 1e-12 agreement is asked on data of the modes)
    imm = IMMFilter(modes, Pi, mu0=[0.5, 0.3, 0.2], min_probability=1e-4)
    ci = compile_imm(imm)
    _imm_run(imm.online(), ci, u, y)
    assert np.argmax(ci.mu) == 2 and ci.log_mu.min() >= np.log(1e-4) - 1e-9


def test_imm_from_a_stepper_continues_it_and_log_space_survives_underflow():
    imm, u, y, _ = _switching(600)
    st = imm.online()
    for k in range(300):
        st.step(u[k], y[k])
    ci = compile_imm(st)
    _imm_run(st, ci, u[300:], y[300:])
    far = LinearGaussianModel(A=[[0.0]], C=[[1.0]], B=[[0.0]], D=[[1.0]], Q=[[1e-6]], R=[[1e-4]], name="far")
    near = LinearGaussianModel(A=[[0.0]], C=[[1.0]], B=[[0.0]], D=[[0.0]], Q=[[1e-6]], R=[[1e-4]], name="near")
    yy = 1e-2 * np.random.default_rng(0).normal(size=(3000, 1))
    yy[1500] = 1e3                                              # every likelihood underflows
    two = IMMFilter([near, far], np.eye(2), x0=[0.0], P0=[[1e-6]])
    _imm_run(two.online(), ci := CompiledIMM(two), np.ones((3000, 1)), yy)
    assert ci.log_mu[1] < -1e6 and np.isfinite(ci.log_mu).all() and ci.mu[0] == 1.0


def test_imm_matches_filterpy_imm_estimator():
    modes = _three_modes()
    rng = np.random.default_rng(5)
    N = 300
    Pi = np.array([[0.95, 0.03, 0.02], [0.05, 0.9, 0.05], [0.1, 0.1, 0.8]])
    mu_init, x_init, P_init = np.array([0.5, 0.3, 0.2]), rng.normal(size=4), 0.5 * np.eye(4)
    u = rng.normal(size=(N + 1, 1))
    true = modes[1]
    sim = np.random.default_rng(6)
    x, y = np.zeros(4), np.empty((N, 2))
    for k in range(N):
        y[k] = true.C @ x + sim.multivariate_normal(np.zeros(2), true.R)
        x = true.A @ x + true.B @ u[k] + sim.multivariate_normal(np.zeros(4), true.Q)
    kfs = []
    for md in modes:
        f = FpKF(dim_x=4, dim_z=2, dim_u=1)
        f.F, f.H, f.B, f.Q, f.R = md.A, md.C, md.B, md.Q, md.R
        f.x, f.P = x_init.reshape(4, 1).copy(), P_init.copy()
        kfs.append(f)
    fp = IMMEstimator(kfs, mu_init, Pi)
    ci = compile_imm(IMMFilter(modes, Pi, mu0=mu_init @ Pi,   # our priors = filterpy's state after its first predict
                               x0=np.array([md.A @ x_init + md.B @ u[0] for md in modes]),
                               P0=np.array([md.A @ P_init @ md.A.T + md.Q for md in modes])))
    for k in range(N):
        fp.predict(u[k].reshape(1, 1))
        fp.update(y[k].reshape(2, 1))
        mu = ci.step(u[k + 1], y[k])
        assert np.all(fp.likelihood > 1e-300)
        assert np.max(abs(mu - fp.mu)) < 1e-8
        assert np.max(abs(ci.x - fp.x.ravel())) < 1e-8 * max(1.0, np.max(abs(ci.x)))
        assert np.max(abs(ci.P - fp.P)) < 1e-8
        assert np.max(abs(ci.x_modes - np.array([f.x.ravel() for f in kfs]))) < 1e-8 * max(1.0, np.max(abs(ci.x)))


def test_imm_bad_input_raises_data_errors_and_leaves_the_state():
    imm, u, y, _ = _switching(5)
    ci, ref = compile_imm(imm), imm.online()
    ci.step([1.0], [0.2])                                       # lists are converted as the reference does
    _close(ref.step([1.0], [0.2]).x, ci.x, "list input")
    with pytest.raises(ParameterError, match="no sample yet"):
        compile_imm(imm).result()
    state = ci.x_pred
    with pytest.raises(DataError, match="u_k must have 1 entries and y_k 1, got 2 and 1"):
        ci.step(np.zeros(2), np.zeros(1))
    with pytest.raises(DataError, match="u_k must have 1 entries and y_k 1, got 1 and 3"):
        ci.step(np.zeros(1), [0.0, 1.0, 2.0])
    with pytest.raises(DataError, match="NaN/inf"):
        ci.step(np.array([np.inf]), np.zeros(1))
    assert np.array_equal(ci.x_pred, state)
    with pytest.raises(ParameterError, match="IMMFilter or IMMStepper"):
        compile_imm(imm.modes[0])
