"""Analysis of fault models and residual generators: fault-to-residual gains, structure matrices and
the FDI geometry report.

* :mod:`fdikit.analysis.gains` — Analysis of fault models and residual generators: gain maps, structure matrices,
  FDI geometry reports.
* :mod:`fdikit.analysis.channels` — Transfer channels of internal forms: filters and banks, minimal channels,
  H∞ and H2 norms, frequency responses.
* :mod:`fdikit.analysis.performance` — Performance metrics of filters (Varga 2017): H∞− index, fault
  sensitivity condition ``fdiscond``, fault-to-noise gap ``fdif2ngap``, model matching ``fdimmperf``.
* :mod:`fdikit.analysis.hminus` — The classical H− index ``inf_ω σ_m(G)`` by a frequency search.
* :mod:`fdikit.analysis.structure` — Weak and strong structure matrices ``fditspec``, ``fdisspec``.
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
        "channels": [
            "Channel", "InternalForms", "internal_forms", "minimal_channel", "hinf_norm", "h2_norm",
        ],
        "performance": [
            "ColumnNorm", "NormRatio", "fdhinfminus", "fdhinfmax", "fdiscond", "fdif2ngap", "fdimmperf", "as_spec",
            "static_reference",
        ],
        "hminus": ["hminus_index"],
        "structure": ["StructureMatrix", "fditspec", "fdisspec"],
        "geometry": [
            "FaultGeometry", "FdiReport", "fdi_report",
        ],
    },
)
