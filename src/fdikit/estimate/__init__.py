"""Fault estimation: sizes of faults from residuals.

* :mod:`fdikit.estimate.steering` — Additive vs multiplicative steering-fault isolation by moving-window least
  squares.
* :mod:`fdikit.estimate.steering_bound` — Guaranteed error bounds of the steering-fault isolation filters (van der
  Ploeg 2018, Thm 3-1.3, Thm 3-2.1).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "steering": [
            "FaultMap", "IsolatorStep", "SteeringFaultEstimate", "SteeringFaultIsolator", "fault_map_coefficients",
            "isolate_steering_faults", "lateral_fault_map",
        ],
        "steering_bound": [
            "IsolationErrorBound", "isolation_error_bound", "restricted_matrices",
        ],
    },
)
