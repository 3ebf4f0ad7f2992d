"""simulate(): exact ZOH for linear plants, RK4/solve_ivp for nonlinear ones, seeded noise, input checks.

Oracles: ``scipy.signal.cont2discrete`` + a plain Python loop, ``control.forced_response``,
``scipy.integrate.solve_ivp`` at tight tolerance, and sampling distributions for the noise.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.signal
import scipy.stats

from fdikit import DataError, FaultModel, ModelError, ParameterError
from fdikit.faults import Bias, FaultScenario
from fdikit.simulate import NonlinearPlant, simulate, time_grid
from reference import state_space_loop

A_C = np.array([[0.0, 1.0, 0.0], [-4.0, -0.6, 0.8], [0.0, 0.3, -2.0]])
BU_C = np.array([[0.0, 0.0], [1.0, -0.5], [0.2, 1.0]])
BD_C = np.array([[0.1], [0.0], [0.5]])
C_C = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])
DU_C = np.array([[0.0, 0.1], [0.0, 0.0]])
DD_C = np.array([[0.0], [0.3]])
X0 = np.array([0.4, -0.2, 0.1])


def _continuous() -> FaultModel:
    return FaultModel(A=A_C, C=C_C, Bu=BU_C, Du=DU_C, Bd=BD_C, Dd=DD_C, outputs=["pos", "rate"],
                      controls=["u1", "u2"], disturbances=["gust"], states=["p", "v", "q"])


def _u(t):
    return np.column_stack([np.sin(1.1 * t), np.sign(np.sin(0.4 * t))])


def _d(t):
    return 0.5 * np.cos(2.3 * t)


def _zoh_loop(A, B, C, D, v, x0, dt=None):
    """Independent exact recursion: scipy's ZOH (when dt given) and a plain Python loop."""
    if dt is not None:
        A, B, C, D, _ = scipy.signal.cont2discrete((A, B, C, D), dt, method="zoh")
    y, x, _ = state_space_loop(A, B, C, D, v, x0)
    return y, x


# ---------------------------------------------------------------------------------------------- linear plants


@pytest.mark.parametrize("dt", [0.01, 0.05, 0.3])
def test_continuous_linear_equals_exact_zoh_recursion(dt):
    t = time_grid(8.0, dt)
    tr = simulate(_continuous(), duration=8.0, dt=dt, u=_u(t), d=_d, x0=X0)
    np.testing.assert_array_equal(tr.t, t)
    v = np.hstack([_u(t), _d(t)[:, None]])
    y_ref, x_ref = _zoh_loop(A_C, np.hstack([BU_C, BD_C]), C_C, np.hstack([DU_C, DD_C]), v, X0, dt=dt)
    np.testing.assert_allclose(tr.x, x_ref, rtol=0, atol=1e-12 * np.abs(x_ref).max())
    np.testing.assert_allclose(tr.y, y_ref, rtol=0, atol=1e-12 * np.abs(y_ref).max())
    np.testing.assert_array_equal(tr.u, _u(t))
    np.testing.assert_array_equal(tr.d[:, 0], _d(t))
    assert tr.states == ("p", "v", "q") and tr.disturbances == ("gust",)


def test_given_times_set_the_sample_time_of_a_continuous_plant():
    t = 2.0 + np.arange(101) * 0.04
    tr = simulate(_continuous(), t=t, u=_u(t), x0=X0)
    y_ref, x_ref = _zoh_loop(A_C, BU_C, C_C, DU_C, _u(t), X0, dt=0.04)
    np.testing.assert_allclose(tr.x, x_ref, rtol=0, atol=1e-12 * np.abs(x_ref).max())
    np.testing.assert_allclose(tr.y, y_ref, rtol=0, atol=1e-12 * np.abs(y_ref).max())


def _discrete() -> FaultModel:
    return _continuous().discretize(0.05)


def test_discrete_plant_runs_at_its_own_dt():
    m = _discrete()
    tr = simulate(m, duration=3.0, u=lambda tk: [np.sin(tk), 1.0], x0=X0)
    assert len(tr) == 61
    np.testing.assert_allclose(np.diff(tr.t), 0.05, rtol=1e-12)
    u = np.column_stack([np.sin(tr.t), np.ones(61)])
    y_ref, x_ref = _zoh_loop(m.A, m.Bu, m.C, m.Du, u, X0)
    np.testing.assert_allclose(tr.x, x_ref, rtol=0, atol=1e-12 * np.abs(x_ref).max())
    np.testing.assert_allclose(tr.y, y_ref, rtol=0, atol=1e-12 * np.abs(y_ref).max())
    same = simulate(m, duration=3.0, dt=0.05, u=u, x0=X0)  # a matching dt is accepted
    np.testing.assert_array_equal(same.y, tr.y)
    with pytest.raises(ParameterError, match="differs from the discrete plant"):
        simulate(m, duration=3.0, dt=0.1)


def test_discrete_plant_rejects_times_at_another_spacing():
    """Times at 0.025 s for a plant sampled at 0.05 s would label every sample with the wrong time."""
    with pytest.raises(DataError):
        simulate(_discrete(), t=np.arange(40) * 0.025)


def test_discrete_agrees_with_control_forced_response():
    m = _discrete()
    t = time_grid(5.0, 0.05)
    v = np.hstack([_u(t), _d(t)[:, None]])
    tr = simulate(m, t=t, u=_u(t), d=_d(t), x0=X0)
    sys = control.ss(m.A, m.B[:, :3], m.C, m.D[:, :3], 0.05)
    resp = control.forced_response(sys, T=t, U=v.T, X0=X0, return_x=True)
    np.testing.assert_allclose(tr.y, resp.outputs.T, rtol=0, atol=1e-12 * np.abs(resp.outputs).max())
    np.testing.assert_allclose(tr.x, resp.states.T, rtol=0, atol=1e-12 * np.abs(resp.states).max())


# ---------------------------------------------------------------------------------------------- noise


def _noisy() -> FaultModel:
    rng = np.random.default_rng(2)
    return _continuous().replace(Bw=0.3 * rng.standard_normal((3, 2)), Dw=0.1 * rng.standard_normal((2, 2)),
                                 noise=["wa", "wb"])


def test_same_seed_same_trace_other_seed_other_noise():
    kw = {"duration": 4.0, "dt": 0.02, "noise_std": [0.5, 0.2], "measurement_noise_std": [0.01, 0.03]}
    a, b = simulate(_noisy(), rng=5, **kw), simulate(_noisy(), rng=np.random.default_rng(5), **kw)
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.meta["seed"] == 5 and b.meta["seed"] is None
    c = simulate(_noisy(), rng=6, **kw)
    assert np.all(a.y[1:] != c.y[1:])
    assert np.any(a.x[1:] != c.x[1:])


@pytest.mark.parametrize("std", [0.3, [0.5, 0.2]])
def test_a_std_and_its_square_as_a_covariance_give_the_same_trace_bit_for_bit(std):
    """The std/cov convention: ``*_std=s`` and ``*_cov=s**2`` (a scalar or vector of variances, or the diagonal
    matrix) draw the same noise with the same seed."""
    s = np.asarray(std, dtype=float)
    t = np.arange(201) * 0.02
    kw = {"t": t, "u": _u(t), "rng": 5}
    v = 0.1 * s  # the measurement noise std
    ref = simulate(_noisy(), noise_std=std, measurement_noise_std=v, **kw)
    variances = s**2 if s.ndim else float(s) ** 2
    for cov, meas in ((variances, v**2), (np.diag(np.broadcast_to(s**2, (2,))), np.diag(np.broadcast_to(v**2, (2,))))):
        got = simulate(_noisy(), noise_cov=cov, measurement_noise_cov=meas, **kw)
        np.testing.assert_array_equal(got.y, ref.y)
        np.testing.assert_array_equal(got.x, ref.x)
    assert np.abs(ref.y - simulate(_noisy(), **kw).y).max() > 0  # the noise is there


def test_a_std_and_a_covariance_of_the_same_noise_are_refused_together():
    with pytest.raises(ParameterError, match="give noise_std or noise_cov, not both"):
        simulate(_noisy(), duration=1.0, dt=0.1, noise_std=0.1, noise_cov=0.01)
    with pytest.raises(ParameterError, match="give measurement_noise_std or measurement_noise_cov, not both"):
        simulate(_noisy(), duration=1.0, dt=0.1, measurement_noise_std=[0.1, 0.2], measurement_noise_cov=np.eye(2))


def test_measurement_noise_covariance_statistics():
    R = np.array([[0.04, 0.012], [0.012, 0.09]])
    N = 40_000
    tr = simulate(_continuous(), t=np.arange(N) * 0.01, measurement_noise_cov=R, rng=11)
    assert not tr.x.any()  # zero input, zero state: y is the noise
    S = np.cov(tr.y.T)
    # std of a sample covariance entry of Gaussian data: sqrt((R_ii R_jj + R_ij^2) / N)
    sd = np.sqrt((np.outer(np.diag(R), np.diag(R)) + R**2) / N)
    assert np.all(np.abs(S - R) < 5 * sd)
    assert np.all(np.abs(tr.y.mean(axis=0)) < 5 * np.sqrt(np.diag(R) / N))


@pytest.mark.parametrize("std", [0.2, [0.1, 0.3]])
def test_measurement_noise_std_chi_square(std):
    N = 20_000
    tr = simulate(_continuous(), t=np.arange(N) * 0.01, measurement_noise_std=std, rng=3)
    sig2 = np.broadcast_to(np.asarray(std, float) ** 2, (2,))
    lo, hi = scipy.stats.chi2.ppf([1e-6, 1 - 1e-6], N - 1)
    for j in range(2):
        stat = (N - 1) * tr.y[:, j].var(ddof=1) / sig2[j]
        assert lo <= stat <= hi


def test_process_noise_enters_through_the_noise_group():
    # y = Dw w: the output covariance is Dw Q Dw^T
    Q = np.array([[0.5, 0.1], [0.1, 0.2]])
    Dw = np.array([[1.0, 0.0], [0.5, 2.0]])
    m = FaultModel(A=[[-1.0]], C=[[0.0], [0.0]], Dw=Dw, noise=["w1", "w2"])
    N = 40_000
    tr = simulate(m, t=np.arange(N) * 0.1, noise_cov=Q, rng=4)
    Y = Dw @ Q @ Dw.T
    sd = np.sqrt((np.outer(np.diag(Y), np.diag(Y)) + Y**2) / N)
    assert np.all(np.abs(np.cov(tr.y.T) - Y) < 5 * sd)
    # a scalar AR(1) x+ = a x + w has stationary variance q / (1 - a^2)
    a, q = 0.8, 0.3
    ar = FaultModel(A=[[a]], C=[[1.0]], Bw=[[1.0]], noise=["w"], dt=1.0)
    N = 100_000
    x = simulate(ar, duration=N - 1, noise_cov=[[q]], rng=8, x0=[0.0]).y[1000:, 0]
    var = q / (1 - a**2)
    # variance of the sample variance of a Gaussian AR(1): 2 var^2 (1 + a^2) / ((1 - a^2) N)
    tol = 5 * var * np.sqrt(2 * (1 + a**2) / ((1 - a**2) * x.size))
    assert abs(x.var() - var) < tol


# ---------------------------------------------------------------------------------------------- nonlinear plants


def _linear_as_nonlinear(x0=X0) -> NonlinearPlant:
    return NonlinearPlant(
        f=lambda t, x, u: A_C @ x + BU_C @ u,
        h=lambda t, x, u: C_C @ x + DU_C @ u,
        states=["p", "v", "q"], outputs=["pos", "rate"], controls=["u1", "u2"], x0=x0,
    )


def test_rk4_on_a_linear_f_converges_at_fourth_order():
    dt = 0.1
    t = time_grid(6.0, dt)
    u = _u(t)
    y_ref, x_ref = _zoh_loop(A_C, BU_C, C_C, DU_C, u, X0, dt=dt)
    errors = []
    for substeps in (1, 2, 4, 8):
        tr = simulate(_linear_as_nonlinear(), t=t, u=u, substeps=substeps)
        np.testing.assert_array_equal(tr.x[0], X0)
        errors.append(np.abs(tr.x - x_ref).max())
        np.testing.assert_allclose(tr.y, tr.x @ C_C.T + u @ DU_C.T, rtol=0, atol=1e-14)
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    # global error C h^4: halving the step divides it by 2^4 = 16 (leading-order, so within 12..20)
    assert np.all((ratios > 12) & (ratios < 20)), ratios
    assert errors[-1] < 1e-7 * np.abs(x_ref).max()


def test_solve_ivp_on_a_linear_f_matches_exact():
    dt = 0.1
    t = time_grid(6.0, dt)
    u = _u(t)
    y_ref, x_ref = _zoh_loop(A_C, BU_C, C_C, DU_C, u, X0, dt=dt)
    tr = simulate(_linear_as_nonlinear(), t=t, u=u, method="solve_ivp")
    # rtol=1e-8 per interval, 60 intervals: well inside 1e-6 of the state scale
    np.testing.assert_allclose(tr.x, x_ref, rtol=0, atol=1e-6 * np.abs(x_ref).max())
    np.testing.assert_allclose(tr.y, y_ref, rtol=0, atol=1e-6 * np.abs(y_ref).max())


def test_pendulum_energy_is_conserved_by_rk4():
    g_over_l = 9.81

    def f(t, x, u):
        return np.array([x[1], -g_over_l * np.sin(x[0]) + u[0]])

    plant = NonlinearPlant(f=f, h=lambda t, x, u: x[:1], states=["theta", "omega"], outputs=["theta"],
                           controls=["torque"], x0=[2.0, 0.0])
    tr = simulate(plant, duration=10.0, dt=0.01, substeps=4)
    energy = 0.5 * tr.x[:, 1] ** 2 + g_over_l * (1 - np.cos(tr.x[:, 0]))
    assert np.abs(energy - energy[0]).max() < 1e-8 * energy[0]
    np.testing.assert_array_equal(tr.y[:, 0], tr.x[:, 0])
    # large swing: theta stays within its initial amplitude and the motion is not trivially zero
    assert np.abs(tr.x[:, 0]).max() <= 2.0 + 1e-8 and tr.x[:, 0].min() < -1.9


def test_nonlinear_state_noise_increments_have_the_given_covariance():
    W = np.array([[0.01, 0.004], [0.004, 0.02]])
    plant = NonlinearPlant(f=lambda t, x, u: np.zeros(2), h=lambda t, x, u: x, states=["a", "b"],
                           outputs=["a", "b"], controls=[])
    N = 20_000
    tr = simulate(plant, duration=N - 1, dt=1.0, noise_cov=W, rng=9)
    inc = np.diff(tr.x, axis=0)
    sd = np.sqrt((np.outer(np.diag(W), np.diag(W)) + W**2) / inc.shape[0])
    assert np.all(np.abs(np.cov(inc.T) - W) < 5 * sd)


def test_nonlinear_plant_with_sensor_fault():
    t = time_grid(3.0, 0.05)
    clean = simulate(_linear_as_nonlinear(), t=t, u=_u(t))
    tr = simulate(_linear_as_nonlinear(), FaultScenario([Bias("rate", 0.5, onset=1.0)]), t=t, u=_u(t))
    np.testing.assert_array_equal(tr.x, clean.x)
    np.testing.assert_array_equal(tr.y[:, 0], clean.y[:, 0])
    np.testing.assert_array_equal(tr.y[:, 1], clean.y[:, 1] + 0.5 * (t >= 1.0))
    np.testing.assert_array_equal(tr.fault, np.where(t >= 1.0, "rate_sensor", "none"))


# ---------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("kwargs", "error", "pattern"),
    [
        ({"duration": 1.0, "dt": 0.1, "u": np.zeros((11, 3))}, DataError, r"u has shape \(11, 3\); need \(11, 2\)"),
        ({"duration": 1.0, "dt": 0.1, "u": np.zeros((10, 2))}, DataError, r"u has shape"),
        ({"duration": 1.0, "dt": 0.1, "u": np.full((11, 2), np.nan)}, DataError, "non-finite"),
        ({"duration": 1.0, "dt": 0.1, "d": np.zeros((11, 2))}, DataError, r"d has shape"),
        ({"dt": 0.1}, ParameterError, "give either t, or both duration and dt"),
        ({"duration": 1.0}, ParameterError, "give either t, or both duration and dt"),
        ({"duration": -1.0, "dt": 0.1}, ParameterError, "duration must be >= 0"),
        ({"duration": 1.0, "dt": 0.0}, ParameterError, r"dt \(the sample time\) must be > 0"),
        ({"t": np.array([0.0, 0.1, 0.25, 0.3])}, DataError, "uniformly spaced"),
        ({"duration": 1.0, "dt": 0.1, "measurement_noise_std": [0.1, 0.2, 0.3]}, ParameterError, "standard deviations"),
        ({"duration": 1.0, "dt": 0.1, "measurement_noise_cov": [[1.0, 2.0], [2.0, 1.0]]}, ParameterError,
         "semidefinite"),
        ({"duration": 1.0, "dt": 0.1, "scenario": FaultScenario([Bias("brake", 1.0)])}, ParameterError,
         r"no signal named 'brake'"),
        ({"duration": 1.0, "dt": 0.1, "scenario": FaultScenario([Bias("u1", 1.0, location="sensor")])}, ParameterError,
         r"no sensor named 'u1'"),
    ],
)
def test_bad_inputs_linear(kwargs, error, pattern):
    kwargs = dict(kwargs)
    scenario = kwargs.pop("scenario", None)
    with pytest.raises(error, match=pattern):
        simulate(_continuous(), scenario, **kwargs)


def test_wrong_initial_state_shape_is_a_parameter_error():
    with pytest.raises(ParameterError, match="x0 has shape"):
        simulate(_continuous(), duration=1.0, dt=0.1, x0=[1.0, 2.0])


def test_noise_cov_for_a_model_without_noise_inputs_is_a_parameter_error():
    """_continuous() has no noise group; simulate should say so rather than fail inside numpy."""
    with pytest.raises(ParameterError, match="no noise inputs"):
        simulate(_continuous(), duration=1.0, dt=0.1, noise_cov=0.1)


def test_bad_inputs_nonlinear_and_unknown_plant():
    plant = _linear_as_nonlinear()
    with pytest.raises(ParameterError, match="unknown integration method"):
        simulate(plant, duration=1.0, dt=0.1, method="euler")
    with pytest.raises(ParameterError, match="no separate disturbance"):
        simulate(plant, duration=1.0, dt=0.1, d=np.zeros((11, 1)))
    with pytest.raises(ParameterError, match="cannot simulate a StateSpace"):
        simulate(control.ss(-1, 1, 1, 0), duration=1.0, dt=0.1)
    with pytest.raises(ModelError, match="x0 has shape"):
        NonlinearPlant(f=plant.f, h=plant.h, states=["a"], outputs=["b"], controls=[], x0=[1.0, 2.0])
    blowup = NonlinearPlant(f=lambda t, x, u: x**3, h=lambda t, x, u: x, states=["a"], outputs=["a"], controls=[],
                            x0=[10.0])
    with np.errstate(over="ignore", invalid="ignore"), pytest.raises(DataError, match="non-finite"):
        simulate(blowup, duration=5.0, dt=0.5, substeps=1)
