"""Exceptions and warnings raised by fdikit.

Every message says what was wrong and how to fix it (scipy style).

``FdiError`` is the root; catch it to catch everything fdikit raises on purpose.

========================  ==========================================================
class                     raised for
========================  ==========================================================
``ModelError``            a malformed model: shapes, duplicate/unknown names, non-finite entries
``DesignError``           a synthesis specification that cannot be met (with the numbers)
``DataError``             unusable data: non-finite samples, gaps, signals that do not match,
                          malformed or corrupted files
``ParameterError``        a bad argument: wrong type, out of range, unknown method name
========================  ==========================================================

``FdiWarning`` is the category of every warning fdikit issues (for example a fault whose
onset lies after the end of the run).
"""

from __future__ import annotations

__all__ = ["FdiError", "ModelError", "DesignError", "DataError", "ParameterError", "FdiWarning"]


class FdiError(Exception):
    """Base class of every error fdikit raises deliberately.

    Examples
    --------
    >>> from fdikit.errors import FdiError, ParameterError
    >>> issubclass(ParameterError, FdiError)
    True
    """


class ModelError(FdiError, ValueError):
    """A model is malformed: wrong shapes, duplicate or unknown names, non-finite entries.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> try:
    ...     FaultModel(A=[[0.0, 1.0]], C=[[1.0]])
    ... except ModelError as exc:
    ...     print(type(exc).__name__)
    ModelError
    """


class DesignError(FdiError):
    """A synthesis specification cannot be met (infeasible, ill-conditioned, not detectable ...).

    The message gives the numbers (ranks, dimensions, margins) that make it infeasible.

    Examples
    --------
    >>> issubclass(DesignError, ValueError)
    False
    """


class DataError(FdiError, ValueError):
    """Data are unusable: NaN/inf, gaps, missing or unexpected signals, malformed or corrupted files.

    Examples
    --------
    >>> from fdikit.trace_io import read_trace
    >>> try:
    ...     read_trace("/nonexistent/run.parquet")
    ... except DataError as exc:
    ...     print(type(exc).__name__)
    DataError
    """


class ParameterError(FdiError, ValueError):
    """An argument is unusable: wrong type, out of range, unknown option or method name.

    Examples
    --------
    >>> from fdikit import validate
    >>> try:
    ...     validate.positive("dt", -0.01)
    ... except ParameterError as exc:
    ...     print(exc)
    dt must be a positive number, got -0.01
    """


class FdiWarning(UserWarning):
    """A result is computed but probably not what was meant (the message says why).

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", FdiWarning)  # turn fdikit's warnings into errors
    """
