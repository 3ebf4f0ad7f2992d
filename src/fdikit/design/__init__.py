"""Residual-generator synthesis: plain functions that return a design (generator + report)."""

from fdikit.design.beard_jones import (
    BeardJonesDesign,
    RestrictedDiagonalDesign,
    beard_jones,
    resolve_faults,
    restricted_diagonal,
)
from fdikit.design.dae_parity import DAEModel, PolynomialParityDesign, dae_form, minimal_degree, parity_filter
from fdikit.design.lpv import LPVModel, stacked_matrices
from fdikit.design.observer import ObserverDesign, kalman, observer, observer_generator, unobservable_modes
from fdikit.design.parity import ParityDesign, lpv_parity_residuals, parity_design
from fdikit.design.robust_parity import RobustParityDesign, robust_lpv_parity, theorem1
from fdikit.design.scheduled import ScheduledResidualGenerator, scheduled_parity_filter
from fdikit.design.uio import UIODesign, uio, uio_bank, unknown_input_matrix

__all__ = [
    "BeardJonesDesign",
    "DAEModel",
    "LPVModel",
    "ObserverDesign",
    "ParityDesign",
    "PolynomialParityDesign",
    "RestrictedDiagonalDesign",
    "RobustParityDesign",
    "ScheduledResidualGenerator",
    "UIODesign",
    "beard_jones",
    "dae_form",
    "kalman",
    "lpv_parity_residuals",
    "minimal_degree",
    "observer",
    "observer_generator",
    "parity_design",
    "parity_filter",
    "resolve_faults",
    "restricted_diagonal",
    "robust_lpv_parity",
    "scheduled_parity_filter",
    "stacked_matrices",
    "theorem1",
    "uio",
    "uio_bank",
    "unknown_input_matrix",
    "unobservable_modes",
]
