"""fdikit.units: SI conversion of logged signals against the exact definitions of the units.

Tolerances: pint multiplies by a factor it composed itself from its definitions (e.g. knot =
nautical_mile / hour with nautical_mile = 1852 m), so the result may differ from the reference
product by a few roundings of float64, each at most 2**-53 relative: rtol = 1e-15 (~4.5 ulp).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.units import si_unit, to_si, unit_registry

X = np.array([-3.5, 0.0, 1.0, 12.25, 1e4, np.nan])
RTOL = 1e-15


@pytest.mark.parametrize(
    ("unit", "factor", "si"),
    [
        ("deg", math.pi / 180, "rad"),
        ("deg/s", math.pi / 180, "rad/s"),
        ("kt", 1852 / 3600, "m/s"),
        ("ft", 0.3048, "m"),
        ("km/h", 1000 / 3600, "m/s"),
        ("g0", 9.80665, "m/s**2"),
        ("gravity", 9.80665, "m/s**2"),
        ("rpm", 2 * math.pi / 60, "rad/s"),
        ("%", 0.01, "1"),
        ("percent", 0.01, "1"),
        ("ft/min", 0.3048 / 60, "m/s"),
        ("m/s^2", 1.0, "m/s**2"),
    ],
)
def test_multiplicative_units_convert_by_their_defining_factor(unit, factor, si):
    values, unit_si = to_si(X, unit)
    assert unit_si == si
    np.testing.assert_allclose(values, X * factor, rtol=RTOL, atol=0)
    assert np.isnan(values[-1]) and values.shape == X.shape
    assert si_unit(unit) == si


def test_offset_units_convert_with_their_offset():
    # 0 degC = 273.15 K exactly; degF: K = (F - 32) * 5/9 + 273.15
    values, si = to_si(X, "degC")
    assert si == "K"
    np.testing.assert_allclose(values, X + 273.15, rtol=RTOL, atol=0)
    values, si = to_si(X, "degF")
    np.testing.assert_allclose(values, (X - 32) * 5 / 9 + 273.15, rtol=4 * RTOL, atol=1e-12)
    # a rate of temperature is a difference: no offset
    np.testing.assert_allclose(to_si(X, "degC/s")[0], X, rtol=RTOL)


def test_ambiguous_g_is_refused_with_the_spellings_to_use():
    for unit in ("g", "g/s", "G", "m/s + g"):
        with pytest.raises(ParameterError, match=r"ambiguous.*'g0'"):
            to_si(X, unit)
    with pytest.raises(ParameterError, match=r"'gram' for the mass"):
        to_si(X, "g")
    np.testing.assert_allclose(to_si(X, "gram")[0], X * 1e-3, rtol=RTOL)  # the mass, explicitly
    np.testing.assert_allclose(to_si(X, "kg")[0], X, rtol=RTOL)  # 'kg' is not the token 'g'


@pytest.mark.parametrize("unit", ["furlongs_per_fortnite", "m/s/", "", "  ", 3, None])
def test_unknown_or_malformed_units_are_parameter_errors(unit):
    with pytest.raises(ParameterError, match=r"unit"):
        to_si(X, unit)


def test_the_registry_is_created_once():
    assert unit_registry() is unit_registry()
    values, _ = to_si([[1.0, 2.0]], "ft")
    assert values.shape == (1, 2)
