"""Scalar, option and type checks of :mod:`fdikit.validate` (numbers, integers, ranges, choices, instances).

Part of the package :mod:`fdikit.validate`, the import path to use (``validate.integer(...)``).  Each helper
checks one argument, returns it in canonical form (a float, an int, the value itself) and
otherwise raises ``error`` (default :class:`~fdikit.errors.ParameterError`) with a message that
names the argument and says what is wrong.

Examples
--------
>>> from fdikit.validate import integer
>>> integer("substeps", 4, minimum=1)
4
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from fdikit.errors import ParameterError

__all__ = ["number", "positive", "non_negative", "integer", "in_range", "choice", "instance", "shown"]


def shown(value) -> str:
    """``repr(value)``, cut to 60 characters: how an error message quotes a bad argument.

    Parameters
    ----------
    value : object
        The argument to quote.

    Returns
    -------
    str
        Its ``repr``, ending in ``...`` when longer than 60 characters.

    Examples
    --------
    >>> shown("x" * 100)[-5:]
    'xx...'
    """
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def number(name: str, value, *, error: type[Exception] = ParameterError, finite: bool = True) -> float:
    """A real number (not a bool, string or array) as float; NaN/inf refused when ``finite``.

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : real number
        An ``int``, ``float``, numpy scalar or 0-d numeric array.
    error : exception class, default ParameterError
        Raised on failure (``ModelError``, ``DataError`` ... for other callers).
    finite : bool, default True
        Refuse NaN and ±inf.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        (or ``error``) For a bool, string, array or other non-number, or a non-finite value when ``finite``.

    Examples
    --------
    >>> from fdikit.validate import number
    >>> number("gain", 3)
    3.0
    """
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()
        else:
            raise error(f"{name} must be a number, got {shown(value)} ({type(value).__name__})")
    out = float(value)
    if finite and not np.isfinite(out):
        raise error(f"{name} must be a finite number, got {out}")
    return out


def positive(name: str, value, *, error: type[Exception] = ParameterError) -> float:
    """A finite number > 0.

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : real number
        The number to check.
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        (or ``error``) For a non-number, NaN, ±inf, zero or a negative number.

    Examples
    --------
    >>> from fdikit.validate import positive
    >>> positive("dt", 0.01)
    0.01
    """
    if not isinstance(value, bool | np.bool_) and isinstance(value, numbers.Real) and not np.isfinite(float(value)):
        raise error(f"{name} must be a positive finite number, got {float(value)}")
    out = number(name, value, error=error)
    if not out > 0:
        raise error(f"{name} must be a positive number, got {out}")
    return out


def non_negative(name: str, value, *, error: type[Exception] = ParameterError) -> float:
    """A finite number >= 0.

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : real number
        The number to check.
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        (or ``error``) For a non-number, NaN, ±inf or a negative number.

    Examples
    --------
    >>> from fdikit.validate import non_negative
    >>> non_negative("onset", 0)
    0.0
    """
    out = number(name, value, error=error)
    if out < 0:
        raise error(f"{name} must be a non-negative number (>= 0), got {out}")
    return out


def integer(name: str, value, *, minimum: int | None = None, error: type[Exception] = ParameterError) -> int:
    """An integer (``int`` or integral numpy integer; not a bool or float) ``>= minimum``.

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : int or numpy integer
        The integer to check; a float such as ``3.0`` is refused.
    minimum : int, optional
        Smallest accepted value (no bound when omitted).
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        (or ``error``) For a bool, float or other non-integer, or a value below ``minimum``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.validate import integer
    >>> integer("horizon", np.int64(5), minimum=1)
    5
    """
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Integral):
        raise error(f"{name} must be an integer, got {shown(value)} ({type(value).__name__})")
    out = int(value)
    if minimum is not None and out < minimum:
        word = {0: "a non-negative integer", 1: "a positive integer"}.get(minimum, f"an integer >= {minimum}")
        raise error(f"{name} must be {word}, got {out}")
    return out


def in_range(name: str, value, low: float, high: float, *, closed: str = "both",
             error: type[Exception] = ParameterError) -> float:
    """A finite number in ``[low, high]`` (``closed`` = 'both', 'left', 'right' or 'neither').

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : real number
        The number to check.
    low, high : float
        The interval's ends.
    closed : {'both', 'left', 'right', 'neither'}, default 'both'
        Which ends belong to the interval.
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        (or ``error``) For a non-number or non-finite number, or one outside the interval.

    Examples
    --------
    >>> from fdikit.validate import in_range
    >>> in_range("alpha", 0.05, 0, 1, closed="neither")
    0.05
    """
    out = number(name, value, error=error)
    lo_ok = out >= low if closed in ("both", "left") else out > low
    hi_ok = out <= high if closed in ("both", "right") else out < high
    if not (lo_ok and hi_ok):
        left = "[" if closed in ("both", "left") else "("
        right = "]" if closed in ("both", "right") else ")"
        raise error(f"{name} must lie in {left}{low:g}, {high:g}{right}, got {out}")
    return out


def choice(name: str, value, options: Sequence, *, error: type[Exception] = ParameterError):
    """``value`` if it is one of ``options``; otherwise an error listing them.

    Parameters
    ----------
    name : str
        What the value is, as the message quotes it ("unknown method 'x'").
    value : object
        The value to check (compared with ``==``; ``True``/``False`` only match themselves).
    options : sequence
        The accepted values.
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    object
        ``value`` itself.

    Raises
    ------
    ParameterError
        (or ``error``) When ``value`` is not one of ``options``.

    Examples
    --------
    >>> from fdikit.validate import choice
    >>> choice("method", "rk4", ("rk4", "solve_ivp"))
    'rk4'
    """
    try:
        ok = value in options
    except TypeError:
        ok = False
    if not ok or isinstance(value, bool) and not any(o is value for o in options):
        listed = ", ".join(repr(o) for o in options)
        raise error(f"unknown {name} {shown(value)}; use one of {listed}")
    return value


def instance(name: str, value, cls: type | tuple[type, ...], hint: str = "", *,
             error: type[Exception] = ParameterError):
    """``value`` if it is an instance of ``cls``; otherwise an error naming the expected type.

    Parameters
    ----------
    name : str
        The argument's name, as the message quotes it.
    value : object
        The value to check.
    cls : type or tuple of types
        The accepted type(s), as for :func:`isinstance`.
    hint : str, optional
        Appended to the message after ``"; "`` (how to make one).
    error : exception class, default ParameterError
        Raised on failure.

    Returns
    -------
    object
        ``value`` itself.

    Raises
    ------
    ParameterError
        (or ``error``) When ``value`` is not an instance of ``cls``.

    Examples
    --------
    >>> from fdikit.validate import instance
    >>> instance("name", "yaw_rate", str)
    'yaw_rate'
    """
    if not isinstance(value, cls):
        want = cls.__name__ if isinstance(cls, type) else " or ".join(c.__name__ for c in cls)
        raise error(f"{name} must be a {want}, got {type(value).__name__}" + (f"; {hint}" if hint else ""))
    return value
