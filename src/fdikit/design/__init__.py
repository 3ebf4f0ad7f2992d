"""Residual-generator synthesis: plain functions that return a design (generator + report), by method family.

The most used designs are importable from here; every name of a family is in its subpackage.

* :mod:`fdikit.design.observers` — Observer-type residual generators: full-order observers, Beard–Jones and
  restricted-diagonal detection filters, unknown-input observers, detection-gain families and the H∞-bounded
  detection filter.
* :mod:`fdikit.design.game` — Game-theoretic detection filters (Murray 2012): problem set-up, Riccati equations,
  continuous, discrete and time-varying filters, and the γ → 0 limit (Goh transformation, reduced-order detector).
* :mod:`fdikit.design.parity` — Parity-space residual generators: state-space parity relations, polynomial (DAE)
  parity filters, speed-scheduled parity filters and the robust LPV parity design.
* :mod:`fdikit.design.nullspace` — Synthesis by the nullspace method (Varga 2017; FDITOOLS): least-degree
  nullspace bases, exact fault detection and isolation (``efdsyn``, ``efdisyn``), approximate synthesis maximising
  the fault-to-noise gap (``afdsyn``, ``afdisyn``) and the achievable specifications (``fdigenspec``, ``fdichkspec``).
* :mod:`fdikit.design.labels` — the ``names=`` / ``isolates=`` every design takes (what its residuals are called
  and which fault each one isolates), and the warning of a parity residual that responds to an unlisted fault.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submodules=["observers", "game", "parity", "nullspace", "labels"],
    submod_attrs={
        "labels": ["fault_label", "label_generator", "residual_labels", "warn_unlisted_faults"],
        "observers": [
            "BeardJonesDesign", "DetectionGainFamily", "Enhancement", "HinfDesign", "ObserverDesign",
            "RestrictedDiagonalDesign", "UIODesign", "beard_jones", "detection_gain_family", "enhancement_direction",
            "hinf_detection_filter", "kalman", "observer", "observer_generator", "restricted_diagonal", "uio",
            "uio_bank", "unknown_input_matrix", "unobservable_modes",
        ],
        "game": [
            "GameBankDesign", "GameDesign", "GameProblem", "GohFilterDesign", "LTVGameDesign",
            "SingleFaultGameDesign", "dgtfdf", "dgtmfdf", "discrete_game_setup", "game_filter", "game_filter_bank",
            "game_problem", "game_riccati", "goh_detector", "goh_filter", "ltv_feasibility", "ltv_game_filter",
            "single_fault_game_filter", "solve_game_are",
        ],
        "parity": [
            "ParityDesign", "PolynomialParityDesign", "RobustParityDesign", "ScheduledResidualGenerator",
            "lpv_parity_residuals", "minimal_degree", "parity_design", "parity_filter", "robust_lpv_parity",
            "scheduled_parity_filter", "theorem1",
        ],
        "nullspace": ["afdisyn", "afdsyn", "efdisyn", "efdsyn", "fdichkspec", "fdigenspec"],
    },
)
