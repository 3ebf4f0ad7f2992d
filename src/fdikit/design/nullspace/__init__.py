"""Synthesis by the nullspace method (Varga 2017; the core of FDITOOLS / FaultDetectionTools.jl).

* :mod:`fdikit.design.nullspace.basis` — least-degree left nullspace bases of ``[Gu Gd; I 0]`` and their proper
  realisation with stable denominators.
* :mod:`fdikit.design.nullspace.detectability` — weak and strong fault detectability of basis rows.
* :mod:`fdikit.design.nullspace.exact` — ``efdsyn`` (exact fault detection, least order) and ``efdisyn`` (a bank
  for a structure matrix).
* :mod:`fdikit.design.nullspace.factorization` — co-outer–co-inner factorisation (standard case by a Riccati
  equation), the quasi factor of one row, the regularised factor.
* :mod:`fdikit.design.nullspace.row_factors` — spectral data and Wiener–Hopf factors of one noise row (the
  reference's ``nonstd = 3, 4, 5``).
* :mod:`fdikit.design.nullspace.zero_steps` — removal of zeros at infinity and on the boundary by row operations.
* :mod:`fdikit.design.nullspace.wiener_hopf` — Wiener–Hopf factors of several noise rows or of discrete models.
* :mod:`fdikit.design.nullspace.noise_factors` — the noise factor to invert, standard or non-standard (``nonstd``).
* :mod:`fdikit.design.nullspace.model_distances` — ``mddist``: ν-gap, L∞ and L2 distances between models.
* :mod:`fdikit.design.nullspace.model_detection` — ``mdgenspec``, ``emdsyn`` (exact model detection, Procedure
  EMD) and ``mdmatch``.
* :mod:`fdikit.design.nullspace.model_matching` — ``emmsyn``: exact model matching of least order (Procedures
  EMM, EMMS), by the left nullspace of the plant with the reference appended.
* :mod:`fdikit.design.nullspace.matching_basis` — the annihilator model matching starts from: minimal or observer
  basis, least-degree covers of a selection.
* :mod:`fdikit.design.nullspace.nehari_ldp` — the H∞ least-distance problem by Chu–Doyle–Lee's γ-iteration and
  the optimal Nehari approximation (the reference's ``glinfldp``).
* :mod:`fdikit.design.nullspace.approximate_matching` — ``ammsyn``: H∞/H2 model matching (Procedure AMMS), the
  least-distance problem by SLICOT or the Nehari route.
* :mod:`fdikit.design.nullspace.approximate` — ``afdsyn`` / ``afdisyn``: the fault-to-noise gap maximised under
  ``‖R_w‖∞ = γ`` (Procedures AFD, AFDI).
* :mod:`fdikit.design.nullspace.specs` — ``fdigenspec`` (all achievable structure matrix rows) and ``fdichkspec``
  (feasibility, orders and least orders of given rows).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "basis": [
            "NullspaceBasis", "default_sdeg", "denominator", "left_nullspace", "minimal_realization", "realize_rows",
        ],
        "detectability": ["covered", "fault_response", "frequency_points", "row_structure"],
        "approximate": ["ApproximateBankDesign", "ApproximateDesign", "afdisyn", "afdsyn"],
        "factorization": [
            "CoOuterFactor", "boundary_zeros", "coouter_coinner", "inverse", "quasi_coouter", "quasi_coouter_row",
            "canonical_factor", "realization", "regularized_coouter", "series", "transfer",
        ],
        "zero_steps": ["ZeroStep", "remove_boundary_zeros", "zero_steps_inverse"],
        "noise_factors": ["NONSTD_OPTIONS", "noise_factor"],
        "wiener_hopf": ["WIENER_HOPF_JOBS_SEVERAL", "moebius", "wiener_hopf"],
        "model_distances": ["MODEL_DISTANCES", "ModelDistances", "check_models", "mddist", "nu_gap"],
        "model_detection": ["ModelDetectionDesign", "amdsyn", "difference_model", "emdsyn", "mdgenspec", "mdmatch"],
        "model_matching": [
            "ModelMatchingBankDesign", "ModelMatchingDesign", "NORMALIZE_OPTIONS", "emmsyn", "reference_bank",
            "reference_columns", "reference_model", "updated_reference",
        ],
        "matching_basis": ["matching_rows"],
        "observer_basis": ["ObserverReduction", "observer_reduction"],
        "nehari_ldp": ["distance_error", "nehari", "two_block_distance"],
        "approximate_matching": ["ApproximateMatchingDesign", "ammsyn", "least_distance"],
        "row_factors": ["RowSpectrum", "WIENER_HOPF_JOBS", "realize_biproper", "row_spectrum", "wiener_hopf_row"],
        "exact": ["NullspaceBankDesign", "NullspaceDesign", "bank_rows", "efdisyn", "efdsyn", "split_faults"],
        "specs": ["SpecificationCheck", "fdichkspec", "fdigenspec", "joint_order"],
    },
)
