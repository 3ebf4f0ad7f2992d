"""Numerical linearisation against analytic Jacobians (Douglas et al. 1996, Ch. 8 §8.3.1, Fig. 8.21)."""

import numpy as np
import pytest

from fdikit.errors import FdiWarning, ModelError, ParameterError
from fdikit.nonlinear import jacobian, linearization, linearize
from fdikit.simulate import NonlinearPlant


def close(num, exact, rtol=1e-7, col_scale=None):
    """Entrywise |num − exact| <= rtol · max(|exact_ij|, size of row i's terms / |scale_j|)."""
    num, exact = np.asarray(num), np.asarray(exact)
    s = np.ones(exact.shape[1]) if col_scale is None else np.maximum(1.0, np.abs(col_scale))
    row = np.max(np.abs(exact) * s, axis=1, initial=0.0)
    bound = rtol * np.maximum(np.abs(exact), row[:, None] / s[None, :])
    worst = float(np.max(np.abs(num - exact) / np.where(bound > 0, bound, 1)))
    return bool(np.all(np.abs(num - exact) <= bound)), worst


# --- pendulum: θ'' = -(g/l) sin θ - c θ' + τ/(m l²), y = (l sin θ, θ')
G, L, C, M = 9.81, 0.7, 0.3, 1.3
pend = NonlinearPlant(
    f=lambda t, x, u: np.array([x[1], -G / L * np.sin(x[0]) - C * x[1] + u[0] / (M * L**2)]),
    h=lambda t, x, u: np.array([L * np.sin(x[0]), x[1]]),
    states=("theta", "omega"), outputs=("tip_x", "rate"), controls=("torque",))


def pend_exact(x, u):
    A = [[0, 1], [-G / L * np.cos(x[0]), -C]]
    B = [[0], [1 / (M * L**2)]]
    Cm = [[L * np.cos(x[0]), 0], [0, 1]]
    return np.array(A, float), np.array(B, float), np.array(Cm, float), np.zeros((2, 1))


# --- Van der Pol
MU = 1.7
vdp = NonlinearPlant(
    f=lambda t, x, u: np.array([x[1], MU * (1 - x[0] ** 2) * x[1] - x[0] + u[0]]),
    h=lambda t, x, u: np.array([x[0] * x[1] + u[0] ** 2]),
    states=("x1", "x2"), outputs=("y",), controls=("u",))


def vdp_exact(x, u):
    A = [[0, 1], [-2 * MU * x[0] * x[1] - 1, MU * (1 - x[0] ** 2)]]
    return np.array(A), np.array([[0.0], [1.0]]), np.array([[x[1], x[0]]]), np.array([[2 * u[0]]])


# --- bicycle-like plant with trig nonlinearities: states vx, vy, r, psi; controls force, delta
MASS, IZ, LF, LR, CF, CR, CD = 1500.0, 2500.0, 1.2, 1.6, 8e4, 9e4, 0.4


def bike_f(t, x, u):
    vx, vy, r, psi = x
    F, d = u
    af = d - np.arctan2(vy + LF * r, vx)
    ar = -np.arctan2(vy - LR * r, vx)
    Ff, Fr = CF * np.sin(af), CR * np.sin(ar)
    return np.array([(F - Ff * np.sin(d) - CD * vx**2) / MASS + vy * r,
                     (Ff * np.cos(d) + Fr) / MASS - vx * r,
                     (LF * Ff * np.cos(d) - LR * Fr) / IZ,
                     r])


def bike_h(t, x, u):
    vx, vy, r, psi = x
    return np.array([r, np.cos(psi) * vx - np.sin(psi) * vy, np.sin(psi) * vx + np.cos(psi) * vy])


bike = NonlinearPlant(f=bike_f, h=bike_h, states=("vx", "vy", "r", "psi"), outputs=("yaw_rate", "xdot", "ydot"),
                      controls=("force", "delta"))


def bike_exact(x, u):
    vx, vy, r, psi = x
    F, d = u
    # α_f = d - atan((vy + LF r)/vx), α_r = -atan((vy - LR r)/vx)
    qf, qr = vy + LF * r, vy - LR * r
    nf, nr = vx**2 + qf**2, vx**2 + qr**2
    daf = np.array([qf / nf, -vx / nf, -LF * vx / nf, 0.0])       # ∂α_f/∂(vx, vy, r, psi)
    dar = np.array([qr / nr, -vx / nr, LR * vx / nr, 0.0])
    af, ar = d - np.arctan2(qf, vx), -np.arctan2(qr, vx)
    Ff = CF * np.sin(af)
    dFf, dFr = CF * np.cos(af) * daf, CR * np.cos(ar) * dar
    A = np.zeros((4, 4))
    A[0] = -dFf * np.sin(d) / MASS + np.array([-2 * CD * vx / MASS, r, vy, 0])
    A[1] = (dFf * np.cos(d) + dFr) / MASS + np.array([-r, 0, -vx, 0])
    A[2] = (LF * dFf * np.cos(d) - LR * dFr) / IZ
    A[3] = [0, 0, 1, 0]
    dFf_dd = CF * np.cos(af)
    B = np.zeros((4, 2))
    B[0] = [1 / MASS, (-dFf_dd * np.sin(d) - Ff * np.cos(d)) / MASS]
    B[1] = [0, (dFf_dd * np.cos(d) - Ff * np.sin(d)) / MASS]
    B[2] = [0, LF * (dFf_dd * np.cos(d) - Ff * np.sin(d)) / IZ]
    Cm = np.array([[0, 0, 1, 0],
                   [np.cos(psi), -np.sin(psi), 0, -np.sin(psi) * vx - np.cos(psi) * vy],
                   [np.sin(psi), np.cos(psi), 0, np.cos(psi) * vx - np.sin(psi) * vy]])
    return A, B, Cm, np.zeros((3, 2))


# --- badly scaled: states of 1e3 and 1e-3
def scaled_f(t, x, u):
    big, small = x
    return np.array([-1e-3 * big**2 / 1e3 + 5e5 * small * u[0], -small**3 * 1e6 + 1e-6 * np.sqrt(big) + u[0] * 1e-3])


scaled = NonlinearPlant(f=scaled_f, h=lambda t, x, u: np.array([np.log(x[0]) + x[1] * 1e3]),
                        states=("big", "small"), outputs=("y",), controls=("u",))


def scaled_exact(x, u):
    big, small = x
    A = [[-2e-6 * big, 5e5 * u[0]], [0.5e-6 / np.sqrt(big), -3e6 * small**2]]
    B = [[5e5 * small], [1e-3]]
    return np.array(A), np.array(B), np.array([[1 / big, 1e3]]), np.zeros((1, 1))


CASES = [
    ("pendulum-hanging", pend, pend_exact, [0.0, 0.0], [0.0]),
    ("pendulum-off", pend, pend_exact, [2.3, -1.1], [0.4]),
    ("vdp", vdp, vdp_exact, [1.3, -0.8], [0.25]),
    ("bicycle", bike, bike_exact, [27.0, 0.3, 0.12, 0.7], [450.0, 0.02]),
    ("badly-scaled", scaled, scaled_exact, [1.7e3, 2.3e-3], [0.8]),
]


@pytest.mark.parametrize("name, plant, exact, x, u", CASES, ids=[c[0] for c in CASES])
def test_central_differences_match_the_analytic_jacobians(name, plant, exact, x, u):
    lin = linearization(plant, x, u, t=0.0)
    A, B, Cm, D = exact(np.array(x, float), np.array(u, float))
    for got, want, scale in ((lin.model.A, A, x), (lin.model.Bu, B, u), (lin.model.C, Cm, x), (lin.model.Du, D, u)):
        ok, worst = close(got, want, 1e-7, scale)
        assert ok, (name, worst, got, want)
    assert lin.model.states == plant.states and lin.model.outputs == plant.outputs
    assert lin.model.controls == plant.controls and lin.model.dt is None
    np.testing.assert_array_equal(lin.f0, plant.f(0.0, np.array(x, float), np.array(u, float)))
    # the steps lie on the ladder 1e-1 … 1e-9 times max(1, |z_j|)
    for block, cols in (("A", x), ("Bu", u)):
        rel = lin.steps[block] / np.maximum(1.0, np.abs(np.asarray(cols)))[None, :]
        assert np.all((rel >= 1e-9 * (1 - 1e-12)) & (rel <= 1e-1 * (1 + 1e-12)))


def test_analytic_jacobian_bypasses_the_differences():
    x, u = np.array([1.3, -0.8]), np.array([0.25])
    calls = []

    def dfdx(t, x, u):
        calls.append(1)
        return vdp_exact(x, u)[0]

    lin = linearization(vdp, x, u, jacobian={"A": dfdx})
    assert len(calls) == 1
    np.testing.assert_array_equal(lin.model.A, vdp_exact(x, u)[0])
    assert np.all(lin.steps["A"] == 0) and np.all(lin.error["A"] == 0)
    assert close(lin.model.C, vdp_exact(x, u)[2], 1e-7, x)[0]


def test_error_estimate_bounds_the_actual_error():
    x, u = np.array([27.0, 0.3, 0.12, 0.7]), np.array([450.0, 0.02])
    lin = linearization(bike, x, u)
    A = bike_exact(x, u)[0]
    assert np.all(np.abs(lin.model.A - A) <= 10 * lin.error["A"] + 1e-14 * np.abs(A).max())


def test_fixed_step_is_plain_central_differences():
    est = jacobian(lambda z: np.array([np.exp(z[0])]), [0.0], step=0.1)
    assert est.J[0, 0] == pytest.approx((np.exp(0.1) - np.exp(-0.1)) / 0.2, rel=1e-14)
    assert est.steps[0, 0] == 0.1


def test_a_kink_gives_a_warning():
    with pytest.warns(FdiWarning, match="no flat region"):
        jacobian(lambda z: np.array([np.abs(z[0]) + 1e-3 * np.sign(z[0])]), [0.0])


def test_bad_input_is_refused_clearly():
    with pytest.raises(ParameterError, match="x"):
        linearize(pend, [0.0], [0.0])
    with pytest.raises(ParameterError, match="NonlinearPlant"):
        linearize("plant", [0.0, 0.0], [0.0])
    with pytest.raises(ParameterError, match="step"):
        linearize(pend, [0.0, 0.0], [0.0], step=-1.0)
    with pytest.raises(ParameterError, match="unknown block"):
        linearize(pend, [0.0, 0.0], [0.0], jacobian={"B": lambda t, x, u: 0})
    wrong = NonlinearPlant(f=lambda t, x, u: np.zeros(3), h=lambda t, x, u: x, states=("a", "b"),
                           outputs=("a", "b"), controls=())
    with pytest.raises(ModelError, match=r"shape \(3,\), need \(2,\)"):
        linearize(wrong, [0.0, 0.0], [])
    with pytest.raises(ModelError, match="returned shape"):
        linearize(pend, [0.0, 0.0], [0.0], jacobian={"A": lambda t, x, u: np.eye(3)})
    nan = NonlinearPlant(f=lambda t, x, u: np.sqrt(x - 1), h=lambda t, x, u: x, states=("a",), outputs=("a",),
                         controls=())
    with np.errstate(invalid="ignore"), pytest.raises(ModelError, match="not finite"):
        linearize(nan, [0.0], [])
