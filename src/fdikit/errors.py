"""Exceptions raised by fdikit.

Every message says what was wrong and how to fix it (scipy style).

``FdiError`` is the root; catch it to catch everything fdikit raises on purpose.
"""

from __future__ import annotations

__all__ = ["FdiError", "ModelError", "DesignError", "DataError"]


class FdiError(Exception):
    """Base class of every error fdikit raises deliberately."""


class ModelError(FdiError, ValueError):
    """A model is malformed: wrong shapes, duplicate or unknown names, non-finite entries."""


class DesignError(FdiError):
    """A synthesis specification cannot be met (infeasible, ill-conditioned, not detectable ...)."""


class DataError(FdiError, ValueError):
    """Data are unusable: NaN/inf, gaps, missing or unexpected signals in a trace."""
