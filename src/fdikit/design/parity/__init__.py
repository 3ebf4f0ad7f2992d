"""Parity-space residual generators: state-space parity relations, polynomial (DAE) parity filters,
speed-scheduled parity filters and the robust LPV parity design.

* :mod:`fdikit.design.parity.state_space` — State-space parity space for discrete LTI and LPV models (Varrier,
  Koenig & Martinez 2014, §3).
* :mod:`fdikit.design.parity.polynomial` — Parity-space fault detection filters from the DAE (polynomial) form (van
  der Ploeg 2018, Ch. 2, Sec. 4-3-1).
* :mod:`fdikit.design.parity.polynomial_rank` — Polynomial-matrix tools and rank tests of the DAE parity filter (bar
  matrices, left null space, minimal degree, detectability and isolability; van der Ploeg 2018, Lemma 2-1.2, Sec. 2-3).
* :mod:`fdikit.design.parity.scheduled` — Speed-scheduled (LPV) parity fault detection filter (van der Ploeg 2018,
  Sec. 3-3, Thm 3-3.4; Sec. 4-3-4).
* :mod:`fdikit.design.parity.scheduled_window` — Time-indexed bar matrices, rank test and parity row of one LPV window
  (van der Ploeg 2018, Lemma 3-3.2, Fact 3-3.3, Thm 3-3.4).
* :mod:`fdikit.design.parity.scheduled_generator` — Runtime of the speed-scheduled parity filter: the scheduled
  residual generator and its online stepper (van der Ploeg 2018, Cor. 3-3.5).
* :mod:`fdikit.design.parity.robust` — Robust parity design for uncertain LPV systems (Varrier, Koenig & Martinez
  2014, §4).
* :mod:`fdikit.design.parity.criteria` — Robustness criteria of the uncertain-LPV parity design: Γ₁, Γ₂, Theorem 1,
  κ and 𝒫₂ (Varrier, Koenig & Martinez 2014, §4.1–4.4).
* :mod:`fdikit.design.parity.lmi` — The LTI LMI form of 𝒫₂ (Varrier, Koenig & Martinez 2014, §4.4.1, (27)–(31)).
* :mod:`fdikit.design.parity.polytope` — Polytopic machinery of the robust LPV parity design (Varrier, Koenig &
  Martinez 2014, §4.5–4.6, (32)–(46)).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "state_space": [
            "ParityDesign", "lpv_parity_residuals", "minimal_horizon", "parity_design", "parity_matrix",
            "regular_rows", "stacked_fault_map",
        ],
        "polynomial": ["PolynomialParityDesign", "parity_filter"],
        "polynomial_rank": [
            "RankTest", "bar", "bar_matrices", "detectability", "isolability", "left_null_space", "minimal_degree",
            "normal_rank", "target_fault", "time_varying_bar",
        ],
        "scheduled": ["scheduled_parity_filter"],
        "scheduled_window": ["lpv_bar_matrices", "lpv_parity_row", "lpv_rank_test"],
        "scheduled_generator": ["ScheduledResidualGenerator", "ScheduledStepper"],
        "robust": ["RobustParityDesign", "robust_lpv_parity"],
        "criteria": [
            "EigenDesign", "RobustCriteria", "gamma_kappa", "kappa_max", "p2_solution", "pointwise_theorem1",
            "robust_criteria", "theorem1", "theorem1_batch",
        ],
        "lmi": ["LmiDesign", "lti_lmi"],
        "polytope": [
            "PolytopicLmi", "adjugate", "box_vertices", "is_admissible", "polynomial_coefficients", "polytopic_lmi",
            "property1_vertices", "repair_vertex", "scheduling_weights",
        ],
    },
)
