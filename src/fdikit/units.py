"""Physical units of imported signals, converted to SI with pint.

:func:`to_si` turns the values of one logged signal, recorded in a unit such as ``"deg/s"``,
``"kt"``, ``"ft"``, ``"km/h"``, ``"g0"``, ``"rpm"``, ``"%"`` or ``"degC"``, into SI base units
(``rad/s``, ``m/s``, ``m``, ``m/s``, ``m/s**2``, ``rad/s``, ``1``, ``K``).  The unit text is
read by pint (any unit pint knows, with prefixes and products: ``"lbf*ft"``, ``"m/s^2"``).
Angles stay angles: SI here is pint's base units, in which the radian is kept.

Two spellings are refused because pint reads them differently from what a flight or vehicle
log usually means: ``"g"`` (pint: gram; write ``"g0"`` or ``"gravity"`` for the standard
gravity 9.80665 m/s², ``"gram"`` for the mass) and ``"G"`` (pint: gauss; write ``"g0"`` or
``"gauss"``).  An offset unit (``degC``, ``degF``) converts with its offset (0 °C = 273.15 K); in a
rate (``"degC/s"``) pint reads it as a difference (1 °C/s = 1 K/s); a product that pint cannot
convert is refused with a hint to write the difference unit (``"delta_degC"``).

pint is imported, and its registry built, on the first call only: importing this module is light.

Examples
--------
>>> to_si([0.0, 90.0], "deg")[1]
'rad'
>>> values, unit = to_si([10.0], "kt")
>>> round(float(values[0]), 6), unit
(5.144444, 'm/s')
"""

from __future__ import annotations

import functools
import re

import numpy as np

from fdikit.errors import ParameterError

__all__ = ["si_unit", "to_si", "unit_registry"]

_AMBIGUOUS = {
    "g": "pint reads 'g' as gram; write 'g0' (or 'gravity') for the standard gravity 9.80665 m/s^2, "
         "or 'gram' for the mass",
    "G": "pint reads 'G' as gauss; write 'g0' (or 'gravity') for the standard gravity 9.80665 m/s^2, "
         "or 'gauss' for the magnetic flux density",
}
_TOKEN = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


@functools.cache
def unit_registry():
    """The one pint :class:`~pint.UnitRegistry` of fdikit, created on the first call.

    Returns
    -------
    pint.UnitRegistry
        The same registry on every call (quantities of one registry combine; of two, they do not).

    Examples
    --------
    >>> unit_registry() is unit_registry()
    True
    """
    import pint

    return pint.UnitRegistry()


def _units(unit: str):
    """The pint unit of ``unit``, after the checks of the module docstring."""
    if not isinstance(unit, str):
        raise ParameterError(f"a unit must be a string such as 'deg/s' or 'kt', got {unit!r} ({type(unit).__name__})")
    if not unit.strip():
        raise ParameterError(
            "a unit is the empty string; write '1' (or 'dimensionless') for a pure number, or leave the signal "
            "out of units= when it is recorded in SI already"
        )
    for token in _TOKEN.findall(unit):
        if token in _AMBIGUOUS:
            raise ParameterError(f"the unit {unit!r} is ambiguous: {_AMBIGUOUS[token]}")
    import pint

    ureg = unit_registry()
    try:
        return ureg.parse_units(unit)
    except pint.UndefinedUnitError as exc:
        raise ParameterError(
            f"unknown unit {unit!r} ({exc}); write it as pint spells units, e.g. 'deg/s', 'kt', 'ft', 'km/h', "
            "'g0', 'rpm', 'percent', 'degC', 'm/s^2'"
        ) from None
    except Exception as exc:  # noqa: BLE001 - pint's parser raises many kinds (even AssertionError for 'm/s/')
        raise ParameterError(
            f"cannot read the unit {unit!r} ({type(exc).__name__}: {exc}); write e.g. 'deg/s' or 'm/s^2'"
        ) from None


def _si_text(units) -> str:
    text = format(units, "~C")
    return text if text else "1"


def to_si(values, unit: str) -> tuple[np.ndarray, str]:
    """Convert values recorded in ``unit`` to SI base units.

    Parameters
    ----------
    values : array_like of float
        The recorded values (NaN stays NaN).
    unit : str
        The unit they are recorded in, as pint spells it (see the module docstring): ``"deg/s"``,
        ``"kt"``, ``"ft"``, ``"km/h"``, ``"g0"``, ``"rpm"``, ``"%"``, ``"degC"`` ...

    Returns
    -------
    values : numpy.ndarray of float
        The values in SI base units, a new array of the same shape.
    si_unit : str
        The SI unit, compact (``"rad/s"``, ``"m/s**2"``, ``"K"``; ``"1"`` for a pure number).

    Raises
    ------
    ParameterError
        For a unit that is not a string, empty, unknown to pint, ambiguous (``"g"``, ``"G"``), or an
        offset unit in a product pint cannot convert (write the difference unit ``"delta_degC"``).

    Examples
    --------
    >>> v, u = to_si([0.0, 100.0], "degC")
    >>> v.tolist(), u
    ([273.15, 373.15], 'K')
    >>> to_si([1.0], "g0")
    (array([9.80665]), 'm/s**2')
    >>> to_si([50.0], "%")
    (array([0.5]), '1')
    >>> to_si([1.0], "g")
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: the unit 'g' is ambiguous: pint reads 'g' as gram; write 'g0' ...
    """
    import pint

    units = _units(unit)
    arr = np.array(values, dtype=float)
    try:
        q = unit_registry().Quantity(arr, units).to_base_units()
    except pint.OffsetUnitCalculusError:
        raise ParameterError(
            f"the unit {unit!r} combines an offset unit (degC, degF) with others; for a difference or a rate "
            "write the difference unit, e.g. 'delta_degC/s'"
        ) from None
    return np.array(q.magnitude, dtype=float).reshape(arr.shape), _si_text(q.units)


def si_unit(unit: str) -> str:
    """The SI unit that :func:`to_si` converts ``unit`` to, without converting values.

    Parameters
    ----------
    unit : str
        A unit as for :func:`to_si`.

    Returns
    -------
    str
        The compact SI unit (``"1"`` for a pure number).

    Raises
    ------
    ParameterError
        As :func:`to_si`.

    Examples
    --------
    >>> si_unit("ft/min"), si_unit("rpm"), si_unit("percent")
    ('m/s', 'rad/s', '1')
    """
    return to_si(np.zeros(0), unit)[1]
