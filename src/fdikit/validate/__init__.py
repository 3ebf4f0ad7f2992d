"""Argument validation: the one module of argument checks every public entry point uses.

Each check takes the argument's name and value, returns the value in canonical form (a float, an int, a read-only
float array …) and otherwise raises an :mod:`fdikit.errors` class whose message names the argument, says what is
wrong and how to fix it.  The class defaults to :class:`~fdikit.errors.ParameterError` (a bad argument); model
constructors pass ``error=ModelError`` and data readers ``error=DataError``.

* :mod:`fdikit.validate.arrays` — arrays, matrices, vectors, complex spectra, covariances, noise std/cov pairs;
* :mod:`fdikit.validate.scalars` — numbers, positive and non-negative numbers, integers, ranges, choices, types.

Both are imported here: ``from fdikit import validate; validate.positive("dt", dt)``.
"""

from fdikit.validate.arrays import (  # noqa: F401 - the package namespace
    as_array,
    as_complex_vector,
    as_covariance,
    as_matrix,
    as_square,
    as_vector,
    noise_covariance,
    psd_part,
)
from fdikit.validate.scalars import (  # noqa: F401 - the package namespace
    choice,
    in_range,
    instance,
    integer,
    non_negative,
    number,
    positive,
    shown,
)

__all__ = [
    "as_array",
    "as_matrix",
    "as_square",
    "as_vector",
    "as_complex_vector",
    "as_covariance",
    "noise_covariance",
    "psd_part",
    "number",
    "positive",
    "non_negative",
    "integer",
    "in_range",
    "choice",
    "instance",
    "shown",
]
