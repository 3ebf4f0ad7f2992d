"""Complete health monitors built from the design functions (filter banks with their scaling)."""

from fdikit.monitors.path_bank import (
    FILTER_GROUPS,
    PathBank,
    nominal_fault_sizes,
    path_bank,
    path_fault_model,
    path_runs,
)

__all__ = ["FILTER_GROUPS", "PathBank", "nominal_fault_sizes", "path_bank", "path_fault_model", "path_runs"]
