"""Synthesis by the nullspace method (Varga 2017; the core of FDITOOLS / FaultDetectionTools.jl).

* :mod:`fdikit.design.nullspace.basis` — least-degree left nullspace bases of ``[Gu Gd; I 0]`` and their proper
  realisation with stable denominators.
* :mod:`fdikit.design.nullspace.detectability` — weak and strong fault detectability of basis rows.
* :mod:`fdikit.design.nullspace.exact` — ``efdsyn`` (exact fault detection, least order) and ``efdisyn`` (a bank
  for a structure matrix).
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
        "detectability": ["fault_response", "frequency_points", "row_structure"],
        "exact": ["NullspaceBankDesign", "NullspaceDesign", "efdisyn", "efdsyn", "split_faults"],
        "specs": ["SpecificationCheck", "fdichkspec", "fdigenspec", "joint_order"],
    },
)
