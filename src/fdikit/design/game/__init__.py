"""Game-theoretic detection filters (Murray 2012): problem set-up, Riccati equations, continuous,
discrete and time-varying filters, and the γ → 0 limit (Goh transformation, reduced-order detector).

* :mod:`fdikit.design.game.setup` — Target/nuisance partition, complementary faults and projectors of the game-
  theoretic filters.
* :mod:`fdikit.design.game.riccati` — Indefinite (H∞-type) algebraic Riccati equations of the game-theoretic
  detection filters.
* :mod:`fdikit.design.game.single_fault` — Single-fault game-theoretic detection filter (GTFDF) and the bank of them
  (steady state; a discrete model runs Murray 2012, Ch. 5).
* :mod:`fdikit.design.game.multi_fault` — Multiple-fault game-theoretic detection filter (GTMFDF): one gain for all
  targets (steady state; a discrete model runs Murray 2012, Ch. 5).
* :mod:`fdikit.design.game.discrete_setup` — Building blocks of the discrete game-theoretic detection filters
  (Murray 2012, Ch. 5): setup, DARI propagation, secondary cost, gain formula (5.41), residual generator.
* :mod:`fdikit.design.game.discrete` — Discrete-time game-theoretic detection filters: DGTFDF and DGTMFDF (Murray
  2012, Ch. 5).
* :mod:`fdikit.design.game.ltv_filter` — Time-varying detection filter with projected residuals (Murray 2012,
  (3.7), (3.9)–(3.10)): the runner of the finite-horizon filters.
* :mod:`fdikit.design.game.time_varying` — Finite-horizon, time-varying game-theoretic detection filters (Murray
  2012, Ch. 3).
* :mod:`fdikit.design.game.goh` — The γ → 0 limit of the game filter: Goh transformation (Algorithm 4.1) and the Goh
  Riccati equation.
* :mod:`fdikit.design.game.reduced_order` — Reduced-order detection filters from the γ → 0 limit of the game filter
  (the "Goh filter").
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "setup": [
            "GameProblem", "game_problem", "per_target", "weight",
        ],
        "riccati": [
            "RiccatiSolution", "game_cost", "game_riccati", "hamiltonian_margin", "solve_game_are",
        ],
        "single_fault": [
            "GameBankDesign", "SingleFaultGameDesign", "game_filter_bank", "single_fault_game_filter",
        ],
        "multi_fault": [
            "GameDesign", "game_filter",
        ],
        "discrete_setup": [
            "DiscreteGameSetup", "GameRiccatiSolution", "discrete_game_generator", "discrete_game_riccati",
            "discrete_game_setup", "gain_update", "secondary_cost",
        ],
        "discrete": [
            "DiscreteGtfdfDesign", "DiscreteGtmfdfDesign", "dgtfdf", "dgtmfdf",
        ],
        "ltv_filter": [
            "LTVDetectionFilter", "ltv_detection_filter", "ltv_labels",
        ],
        "time_varying": [
            "LTVFeasibility", "LTVGameDesign", "ltv_feasibility", "ltv_game_filter",
        ],
        "goh": [
            "GohRiccatiSolution", "GohTransformation", "goh_riccati", "goh_riccati_rhs", "goh_riccati_transient",
            "goh_transformation", "oblique_projector",
        ],
        "reduced_order": [
            "GohFilterDesign", "goh_detector", "goh_filter",
        ],
    },
)
