"""Descriptor state-space models ``E x' = A x + B u``, ``y = C x + D u`` with grouped inputs, their reductions and
the Kronecker structure of their pencils.

* :mod:`fdikit.descriptor.model` — :class:`DescriptorModel` (groups u, d, f, w, aux), ``G(λ)``, poles,
  conversion to and from :class:`fdikit.model.FaultModel`.
* :mod:`fdikit.descriptor.reduction` — removal of non-dynamic modes (``gir``-like) and minimal realisations
  (``gminreal``-like: uncontrollable/unobservable finite and infinite eigenvalues).
* :mod:`fdikit.descriptor.staircase` — Kronecker structure of a pencil by orthogonal staircase reductions
  (finite eigenvalues, Jordan blocks at infinity, left/right Kronecker indices, normal rank), and the
  controllability staircase of a pair ``(A, B)``.
* :mod:`fdikit.descriptor.zeros` — the system pencil ``[[A − λE, B], [C, D]]``: zeros, normal rank, indices.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "model": ["DescriptorModel", "DESCRIPTOR_GROUPS"],
        "reduction": ["remove_nondynamic", "minimal_realization", "nondynamic_count"],
        "staircase": ["KroneckerStructure", "controllability_staircase", "pencil_structure", "split_infinite"],
        "zeros": ["system_pencil", "system_structure", "system_zeros", "normal_rank"],
    },
)
