"""Residual-generator synthesis: plain functions that return a design (generator + report)."""

from fdikit.design.beard_jones import (
    BeardJonesDesign,
    RestrictedDiagonalDesign,
    beard_jones,
    resolve_faults,
    restricted_diagonal,
)
from fdikit.design.observer import ObserverDesign, kalman, observer, observer_generator, unobservable_modes
from fdikit.design.uio import UIODesign, uio, uio_bank, unknown_input_matrix

__all__ = [
    "BeardJonesDesign",
    "ObserverDesign",
    "RestrictedDiagonalDesign",
    "UIODesign",
    "beard_jones",
    "kalman",
    "observer",
    "observer_generator",
    "resolve_faults",
    "restricted_diagonal",
    "uio",
    "uio_bank",
    "unknown_input_matrix",
    "unobservable_modes",
]
