"""Residual-generator synthesis: plain functions that return a design (generator + report)."""

from fdikit.design.beard_jones import (
    BeardJonesDesign,
    RestrictedDiagonalDesign,
    beard_jones,
    resolve_faults,
    restricted_diagonal,
)
from fdikit.design.dae_parity import DAEModel, PolynomialParityDesign, dae_form, minimal_degree, parity_filter
from fdikit.design.detection_gain import DetectionGainFamily, detection_gain_family
from fdikit.design.game import (
    GameBankDesign,
    GameDesign,
    SingleFaultGameDesign,
    game_filter,
    game_filter_bank,
    single_fault_game_filter,
)
from fdikit.design.game_discrete import dgtfdf, dgtmfdf, discrete_game_setup
from fdikit.design.game_ltv import LTVGameDesign, ltv_feasibility, ltv_game_filter
from fdikit.design.game_riccati import game_riccati, solve_game_are
from fdikit.design.game_setup import GameProblem, game_problem
from fdikit.design.hinf import Enhancement, HinfDesign, enhancement_direction, hinf_detection_filter
from fdikit.design.lpv import LPVModel, stacked_matrices
from fdikit.design.ltv import LTVModel
from fdikit.design.observer import ObserverDesign, kalman, observer, observer_generator, unobservable_modes
from fdikit.design.parity import ParityDesign, lpv_parity_residuals, parity_design
from fdikit.design.reduced_order import GohFilterDesign, goh_detector, goh_filter
from fdikit.design.robust_parity import RobustParityDesign, robust_lpv_parity, theorem1
from fdikit.design.scheduled import ScheduledResidualGenerator, scheduled_parity_filter
from fdikit.design.uio import UIODesign, uio, uio_bank, unknown_input_matrix

__all__ = [
    "BeardJonesDesign",
    "DAEModel",
    "DetectionGainFamily",
    "Enhancement",
    "GameBankDesign",
    "GameDesign",
    "GameProblem",
    "GohFilterDesign",
    "HinfDesign",
    "LPVModel",
    "LTVGameDesign",
    "LTVModel",
    "ObserverDesign",
    "ParityDesign",
    "PolynomialParityDesign",
    "RestrictedDiagonalDesign",
    "RobustParityDesign",
    "ScheduledResidualGenerator",
    "SingleFaultGameDesign",
    "UIODesign",
    "beard_jones",
    "dae_form",
    "detection_gain_family",
    "dgtfdf",
    "dgtmfdf",
    "discrete_game_setup",
    "enhancement_direction",
    "game_filter",
    "game_filter_bank",
    "game_problem",
    "game_riccati",
    "goh_detector",
    "goh_filter",
    "hinf_detection_filter",
    "kalman",
    "lpv_parity_residuals",
    "ltv_feasibility",
    "ltv_game_filter",
    "minimal_degree",
    "observer",
    "observer_generator",
    "parity_design",
    "parity_filter",
    "resolve_faults",
    "restricted_diagonal",
    "robust_lpv_parity",
    "scheduled_parity_filter",
    "single_fault_game_filter",
    "solve_game_are",
    "stacked_matrices",
    "theorem1",
    "uio",
    "uio_bank",
    "unknown_input_matrix",
    "unobservable_modes",
]
