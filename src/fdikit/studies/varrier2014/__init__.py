"""Varrier et al. 2014: the lateral-acceleration sensor fault and the ϖ score (§5).

* :mod:`fdikit.studies.varrier2014.scenarios` — The lateral-acceleration sensor fault of Varrier, Koenig & Martinez
  2014, §5.4–5.5, simulated.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "scenarios": [
            "VarrierComparison", "fault_window_masks", "min_max_ratio", "normalise_residual", "speed_profile",
            "steering_profile", "varrier_comparison", "varrier_trace",
        ],
    },
)
