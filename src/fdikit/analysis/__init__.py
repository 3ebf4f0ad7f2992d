"""Analysis of fault models and residual generators: fault-to-residual gains, structure matrices and
the FDI geometry report.

* :mod:`fdikit.analysis.gains` — Analysis of fault models and residual generators: gain maps, structure matrices,
  FDI geometry reports.
* :mod:`fdikit.analysis.geometry` — FDI geometry report of a fault model, before any design (Douglas et al. 1996,
  §4.1 and App. A; Murray 2012, §2.3).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "gains": [
            "GainTable", "default_freqs", "fault_to_residual_gain", "structure_matrix",
        ],
        "geometry": [
            "FaultGeometry", "FdiReport", "fdi_report",
        ],
    },
)
