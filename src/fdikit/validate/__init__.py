"""Argument validation: the one module of argument checks every public entry point uses.

Each check takes the argument's name and value, returns the value in canonical form (a float, an int, a read-only
float array …) and otherwise raises an :mod:`fdikit.errors` class whose message names the argument, says what is
wrong and how to fix it.  The class defaults to :class:`~fdikit.errors.ParameterError` (a bad argument); model
constructors pass ``error=ModelError`` and data readers ``error=DataError``.

* :mod:`fdikit.validate.arrays` — arrays, matrices, vectors, complex spectra, covariances, noise std/cov pairs;
* :mod:`fdikit.validate.scalars` — numbers, positive and non-negative numbers, integers, ranges, choices, types.

Both are imported here: ``from fdikit import validate; validate.positive("dt", dt)``.
"""

from fdikit.validate import arrays, scalars
from fdikit.validate.arrays import *  # noqa: F403 - the package namespace is its modules' names
from fdikit.validate.scalars import *  # noqa: F403 - the package namespace is its modules' names

__all__ = [*arrays.__all__, *scalars.__all__]
