"""Linear algebra of fault detection: subspaces and the geometry of detection filters.

* :mod:`fdikit.linalg.subspaces` — numerical rank, orthonormal bases of ranges and null spaces, sums,
  intersections, membership (SVD rank decisions with tolerances scaled to the data);
* :mod:`fdikit.linalg.geometry` — CAISA, invariant zeros and directions, detection spaces ``T* = W* ⊕ V``,
  output separability, mutual detectability, the output projector ``Ĥ`` (Douglas et al. 1996, §4.1, App. A;
  Murray 2012, §2.1.2).

Both are imported here (they need only numpy and scipy.linalg): ``from fdikit import linalg; linalg.orth(W)``.
The fault maps ``F`` these functions take are built by :mod:`fdikit.fault_maps`.
"""

from fdikit.linalg.geometry import (  # noqa: F401 - the package namespace
    caisa,
    detection_space,
    invariant_zeros,
    mutually_detectable,
    output_projector,
    output_separable,
)
from fdikit.linalg.subspaces import (  # noqa: F401 - the package namespace
    EPS,
    as_2d,
    checked_rtol,
    contains,
    intersect,
    null,
    orth,
    rank,
    span_sum,
)

__all__ = [
    "rank",
    "orth",
    "null",
    "intersect",
    "span_sum",
    "contains",
    "as_2d",
    "checked_rtol",
    "EPS",
    "output_projector",
    "caisa",
    "invariant_zeros",
    "detection_space",
    "output_separable",
    "mutually_detectable",
]
