"""PID: the three terms against hand computation and scipy.signal.lfilter; anti-windup against a plain PI."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.ftc.pid import PID


def test_proportional_and_integral_terms_by_hand():
    pid = PID(2.0, 0.5, 0.0, dt=0.1)
    e = [1.0, 1.0, -0.5, 0.25]
    got = [pid.step(x) for x in e]
    integral = np.concatenate([[0.0], np.cumsum(0.5 * 0.1 * np.array(e))[:-1]])   # forward Euler
    assert got == pytest.approx(2.0 * np.array(e) + integral, abs=1e-15)


def test_filtered_derivative_equals_lfilter():
    import scipy.signal

    kd, tf, dt = 0.7, 0.3, 0.05
    rng = np.random.default_rng(0)
    e = rng.standard_normal(200)
    pid = PID(0.0, 0.0, kd, dt=dt, derivative_filter=tf)
    got = np.array([pid.step(x) for x in e])
    # D(z) = kd (1 − z⁻¹) / ((tf + dt) − tf z⁻¹); the first sample's difference is zero (e_{−1} = e_0).
    want = scipy.signal.lfilter([kd], [tf + dt, -tf], np.diff(np.r_[e[0], e]))
    assert got == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize("scheme", ["clamp", "back_calculation"])
def test_anti_windup_stops_the_integrator_and_removes_the_overshoot(scheme):
    # A plant x' = u with |u| ≤ 1 and a far set point: a plain PI winds up and overshoots by the wound-up
    # integral; with anti-windup the overshoot is far smaller.
    def run(anti_windup):
        dt, x, xs = 0.01, 0.0, []
        if anti_windup is None:
            pid = PID(-2.0, -1.0, 0.0, dt=dt)
        else:
            pid = PID(-2.0, -1.0, 0.0, dt=dt, output_min=-1.0, output_max=1.0, anti_windup=anti_windup)
        for _ in range(3000):
            u = float(np.clip(pid.step(x - 10.0), -1.0, 1.0))
            x += dt * u
            xs.append(x)
        return np.max(xs) - 10.0, pid.integral

    plain_overshoot, plain_integral = run(None)
    overshoot, integral = run(scheme)
    assert plain_overshoot > 2.0
    assert overshoot < 0.25 * plain_overshoot
    assert abs(integral) < abs(plain_integral)


def test_output_is_limited_and_bad_settings_are_refused():
    pid = PID(10.0, 0.0, 0.0, dt=0.1, output_min=-1.0, output_max=1.0)
    assert pid.step(5.0) == 1.0 and pid.step(-5.0) == -1.0
    with pytest.raises(ParameterError, match="output_min"):
        PID(1.0, dt=0.1, output_min=1.0, output_max=0.0)
    with pytest.raises(ParameterError):
        PID(1.0, dt=0.1).step(float("nan"))
    with pytest.raises(ParameterError):
        PID(1.0, dt=0.1, anti_windup="none")
