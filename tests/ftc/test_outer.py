"""Outer loops (6.1)–(6.2): signs, the ±180° heading wrap, the flight-path feed-forward and the limits."""

import numpy as np
import pytest

from fdikit.ftc.outer import outer_loops
from fdikit.ftc.references import nominal_plan

PLAN = nominal_plan(heading=0.0, new_heading=-120.0)


def test_heading_error_is_wrapped():
    loops = outer_loops(0.1, 2.0, heading_gains=(-1.5, 0.0, 0.0))
    # ψ = 179°, ψ_ref = −179° (PLAN's 0° shifted): the short way is 2° to the right, so bank right.
    plan = nominal_plan(heading=-179.0, new_heading=-179.0)
    phi, *_ = loops.references(0.0, plan, altitude=980.0, heading=np.radians(179.0))
    assert phi == pytest.approx(3.0, abs=1e-9)


def test_altitude_error_pitches_towards_the_reference():
    loops = outer_loops(0.1, 2.0, altitude_gains=(-0.05, 0.0, 0.0))
    _, theta, v, beta = loops.references(0.0, PLAN, altitude=960.0, heading=0.0)
    assert theta == pytest.approx(2.0 + 0.05 * 20.0, abs=1e-12)     # 20 m low: 1° more pitch
    assert (v, beta) == (92.6, 0.0)


def test_descent_feeds_the_flight_path_angle_forward():
    loops = outer_loops(0.1, 2.0, altitude_gains=(-0.05, 0.0, 0.0))
    t = 160.0
    _, theta, *_ = loops.references(t, PLAN, altitude=PLAN.altitude(t), heading=PLAN.heading(t))
    assert theta == pytest.approx(2.0 - 5.0, abs=1e-6)     # γ = −5°; the reference ramp is linear in t


def test_limits_hold():
    loops = outer_loops(0.1, 2.0, pitch_range=10.0, roll_limit=30.0)
    phi, theta, *_ = loops.references(0.0, PLAN, altitude=0.0, heading=np.radians(90.0))
    assert theta == pytest.approx(12.0) and phi == pytest.approx(-30.0)
