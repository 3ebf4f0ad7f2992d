"""The §6.5.1 flight plan: turn the short way at the set rate, descend at γ to the floor, airspeed steps."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.ftc.references import nominal_plan


def test_turn_profile():
    plan = nominal_plan()
    assert plan.heading(74.0) == pytest.approx(np.pi)
    # 180° → 60° is 120° to the left at 3 °/s: 40 s.
    assert np.degrees(plan.heading(95.0)) == pytest.approx(120.0)
    assert np.degrees(plan.heading(115.0)) == pytest.approx(60.0)
    assert np.degrees(plan.heading(300.0)) == pytest.approx(60.0)
    wrap = nominal_plan(heading=170.0, new_heading=-170.0)       # short way: 20° through 180°
    assert abs(np.degrees(wrap.heading(80.0)) - 185.0 + 360.0) < 1e-9


def test_descent_profile():
    plan = nominal_plan()
    rate = 92.6 * np.sin(np.radians(-5.0))
    assert plan.altitude(150.0) == 980.0
    assert plan.altitude(170.0) == pytest.approx(980.0 + 20.0 * rate)
    t_floor = 150.0 + (100.0 - 980.0) / rate
    assert plan.altitude(t_floor + 1.0) == 100.0
    with pytest.raises(ParameterError, match="negative angle to descend"):
        nominal_plan(flight_path_angle=5.0)


def test_airspeed_step():
    plan = nominal_plan().with_airspeed(30.0, 100.0)
    assert plan.airspeed_at(29.9) == 92.6 and plan.airspeed_at(30.0) == 100.0
