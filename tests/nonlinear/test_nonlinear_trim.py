"""Operating points: equilibria and steady turns (Douglas et al. 1996, Ch. 2 §2.2, Ch. 8 §8.3), against closed
forms and python-control's find_eqpt."""

import control
import numpy as np
import pytest

from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.nonlinear import trim
from fdikit.simulate import NonlinearPlant

G = 9.81
pend = NonlinearPlant(f=lambda t, x, u: np.array([x[1], -G * np.sin(x[0]) - 0.2 * x[1] + u[0]]),
                      h=lambda t, x, u: x[:1], states=("theta", "omega"), outputs=("angle",), controls=("torque",))


@pytest.mark.parametrize("guess, want", [([0.4, 0.3], 0.0), ([2.8, -0.1], np.pi)])
def test_pendulum_hanging_and_upright(guess, want):
    op = trim(pend, guess, [0.0])
    assert op.success and op.free == ("theta", "omega")
    assert op.x == pytest.approx([want, 0.0], abs=1e-12)
    assert op.residual <= 1e-12 and op.iterations >= 1 and np.all(np.abs(op.dx) <= 1e-12)


def test_first_order_plant_with_an_output_target():
    # x' = -a x + b u, y = c x: y = 3 needs x = 3/c, u = a x / b
    a, b, c = 2.0, 0.5, 4.0
    plant = NonlinearPlant(f=lambda t, x, u: -a * x + b * u, h=lambda t, x, u: c * x, states=("x",),
                           outputs=("y",), controls=("u",))
    op = trim(plant, [0.0], [0.0], y0={"y": 3.0})
    assert op.x[0] == pytest.approx(3 / c, rel=1e-12) and op.u[0] == pytest.approx(a * 3 / c / b, rel=1e-12)
    assert op.y[0] == pytest.approx(3.0, rel=1e-12)


# linear single-track ("bicycle") model with speed dynamics: states vx, vy, r, psi; controls force, delta
MASS, IZ, LF, LR, CF, CR, CD = 1500.0, 2500.0, 1.2, 1.6, 8e4, 9e4, 0.4
WB = LF + LR


def track_f(t, x, u):
    vx, vy, r, psi = x
    F, d = u
    return np.array([(F - CD * vx**2) / MASS,
                     -(CF + CR) / (MASS * vx) * vy + ((CR * LR - CF * LF) / (MASS * vx) - vx) * r + CF / MASS * d,
                     (CR * LR - CF * LF) / (IZ * vx) * vy - (CF * LF**2 + CR * LR**2) / (IZ * vx) * r
                     + CF * LF / IZ * d,
                     r])


track = NonlinearPlant(f=track_f, h=lambda t, x, u: np.array([x[2], x[2] / x[0], x[1]]),
                       states=("vx", "vy", "r", "psi"), outputs=("yaw_rate", "curvature", "vy_out"),
                       controls=("force", "delta"))


def test_steady_turn_of_given_radius_at_fixed_speed():
    v, R = 27.0, 638.73
    op = trim(track, [v, 0.0, 0.0, 0.3], [0.0, 0.0], ix=["vx", "psi"], idx=["vx", "vy", "r"],
              y0={"curvature": 1 / R})
    assert op.x[0] == v and op.x[3] == 0.3                           # held states
    assert op.x[2] == pytest.approx(v / R, rel=1e-10)                # r = v / R
    assert op.dx[3] == pytest.approx(v / R, rel=1e-10)               # the heading keeps turning (free)
    assert op.u[0] == pytest.approx(CD * v**2, rel=1e-10)            # drag balanced
    k_us = MASS / WB * (LR / CF - LF / CR)                           # understeer gradient [rad s²/m]
    assert op.u[1] == pytest.approx(WB / R + k_us * v**2 / R, rel=1e-9)
    assert set(op.free) == {"vy", "r", "force", "delta"}


def test_steady_turn_agrees_with_find_eqpt():
    v, R = 27.0, 400.0
    sys = control.NonlinearIOSystem(lambda t, x, u, params: track_f(t, x, u),
                                    lambda t, x, u, params: np.array([x[2], x[2] / x[0], x[1]]),
                                    states=4, inputs=2, outputs=3)
    x0, u0, y0 = [v, 0.0, 0.0, 0.0], [0.0, 0.0], [0.0, 1 / R, 0.0]
    xe, ue = control.find_eqpt(sys, x0, u0, y0, ix=[0, 3], iy=[1], idx=[0, 1, 2])
    op = trim(track, x0, u0, ix=[0, 3], y0=y0, iy=[1], idx=[0, 1, 2])
    np.testing.assert_allclose(op.x, xe, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(op.u, ue, rtol=1e-8, atol=1e-12)


def test_pendulum_agrees_with_find_eqpt_with_fixed_input():
    sys = control.NonlinearIOSystem(lambda t, x, u, params: pend.f(t, x, u), lambda t, x, u, params: x[:1],
                                    states=2, inputs=1, outputs=1)
    xe, ue = control.find_eqpt(sys, [0.3, 0.0], [2.0])
    op = trim(pend, [0.3, 0.0], [2.0])
    np.testing.assert_allclose(op.x, xe, rtol=1e-9, atol=1e-12)
    assert op.x[0] == pytest.approx(np.arcsin(2.0 / G), rel=1e-12)


def test_unreachable_target_is_a_design_error_with_the_residual():
    # |torque| <= nothing: torque fixed at 20 > g, no equilibrium (sin θ = 20/9.81)
    with pytest.raises(DesignError, match=r"residual [0-9.e+-]+ > tol"):
        trim(pend, [0.3, 0.0], [20.0])


def test_bad_input_is_refused_clearly():
    with pytest.raises(ParameterError, match="unknown state 'speed'"):
        trim(track, [27, 0, 0, 0], [0, 0], ix=["speed"])
    with pytest.raises(ParameterError, match="out of range"):
        trim(pend, [0, 0], [0], ix=[5])
    with pytest.raises(ParameterError, match="x0"):
        trim(pend, [0, 0, 0], [0])
    with pytest.raises(ParameterError, match="iy"):
        trim(pend, [0, 0], [0], y0={"angle": 1.0}, iy=[0])
    with pytest.raises(ParameterError, match="nothing to solve"):
        trim(pend, [0, 0], [0], idx=[])
    wrong = NonlinearPlant(f=lambda t, x, u: np.zeros(3), h=lambda t, x, u: x, states=("a", "b"),
                           outputs=("a", "b"), controls=())
    with pytest.raises(ModelError, match="shape"):
        trim(wrong, [0.0, 0.0], [])
