"""Linear algebra of fault detection: subspaces and the geometry of detection filters.

* :mod:`fdikit.linalg.subspaces` — numerical rank, orthonormal bases of ranges and null spaces, sums,
  intersections, membership (SVD rank decisions with tolerances scaled to the data);
* :mod:`fdikit.linalg.geometry` — CAISA, invariant zeros and directions, detection spaces ``T* = W* ⊕ V``,
  output separability, mutual detectability, the output projector ``Ĥ`` (Douglas et al. 1996, §4.1, App. A;
  Murray 2012, §2.1.2).

Both are imported here (they need only numpy and scipy.linalg): ``from fdikit import linalg; linalg.orth(W)``.
The fault maps ``F`` these functions take are built by :mod:`fdikit.fault_maps`.
"""

from fdikit.linalg import geometry, subspaces
from fdikit.linalg.geometry import *  # noqa: F403 - the package namespace is its modules' names
from fdikit.linalg.subspaces import *  # noqa: F403 - the package namespace is its modules' names

__all__ = [*subspaces.__all__, *geometry.__all__]
