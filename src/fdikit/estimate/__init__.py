"""Fault estimation: sizes of faults from residuals.

:mod:`fdikit.estimate.steering` separates an additive steering offset from a multiplicative gain
fault by moving-window least squares (van der Ploeg 2018, Ch. 3), with the pre-filter of Sec. 3-2;
:mod:`fdikit.estimate.steering_bound` evaluates the error bounds of Thm 3-1.3 / 3-2.1.
"""

from fdikit.estimate.steering import (
    SteeringFaultEstimate,
    SteeringFaultIsolator,
    isolate_steering_faults,
    lateral_fault_map,
)
from fdikit.estimate.steering_bound import IsolationErrorBound, isolation_error_bound

__all__ = [
    "IsolationErrorBound",
    "SteeringFaultEstimate",
    "SteeringFaultIsolator",
    "isolate_steering_faults",
    "isolation_error_bound",
    "lateral_fault_map",
]
