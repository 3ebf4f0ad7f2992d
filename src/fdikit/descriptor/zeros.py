"""The system pencil of a descriptor model and what its Kronecker structure says about the system.

``S(λ) = [[A − λE, B], [C, D]]`` (for the inputs chosen): its finite eigenvalues are the finite (Smith) zeros of
the system (invariant zeros; with decoupling zeros unless the model is minimal), ``rank S − n`` is the normal
rank of the transfer matrix ``G(λ)``, its Jordan blocks at infinity of size ``k > 1`` are the infinite zeros of
order ``k − 1``, and its right / left Kronecker indices are the right / left minimal indices of ``G`` (the degrees
of a minimal polynomial basis of the right / left nullspace; e.g. the least-order nullspace basis in ``efdsyn``).
SLICOT ``AG08BD`` computes the same quantities; :func:`fdikit.descriptor.staircase.pencil_structure` is the
orthogonal staircase used here.

References
----------
Varga (2017), §9.1.5 (zeros, normal rank, minimal indices via the system pencil), §10.1.6.
``fdtools`` (FaultDetectionTools.jl: ``gzero``, ``gnrank`` of DescriptorSystems.jl).
"""

from __future__ import annotations

import numpy as np

from fdikit.descriptor.model import DescriptorModel
from fdikit.descriptor.staircase import KroneckerStructure, pencil_structure
from fdikit.errors import ModelError, ParameterError
from fdikit.model import FaultModel

__all__ = ["system_pencil", "system_structure", "system_zeros", "normal_rank"]


def _descriptor(model) -> DescriptorModel:
    if isinstance(model, FaultModel):
        return DescriptorModel.from_fault_model(model)
    if not isinstance(model, DescriptorModel):
        raise ModelError(f"expected a DescriptorModel or a FaultModel, got {type(model).__name__}")
    return model


def system_pencil(model, groups=None) -> tuple[np.ndarray, np.ndarray]:
    """The matrices ``M``, ``N`` of the system pencil ``S(λ) = M − λN = [[A − λE, B], [C, D]]``.

    Parameters
    ----------
    model : DescriptorModel or FaultModel
        The model.
    groups : str or sequence of str, optional
        The input groups whose columns enter ``B`` and ``D`` (e.g. ``("u", "d")``); default all inputs.

    Returns
    -------
    M, N : numpy.ndarray
        ``(n + p) x (n + k)`` matrices.

    Raises
    ------
    ModelError
        If ``model`` is neither model type.
    ParameterError
        For an unknown group.

    Examples
    --------
    >>> m = DescriptorModel([[-1.0]], [[1.0]], Bu=[[1.0]])
    >>> M, N = system_pencil(m)
    >>> M.tolist(), N.tolist()
    ([[-1.0, 1.0], [1.0, 0.0]], [[1.0, 0.0], [0.0, 0.0]])
    """
    m = _descriptor(model)
    if groups is None:
        B, D = m.B, m.D
    else:
        groups = (groups,) if isinstance(groups, str) else tuple(groups)
        if not groups:
            raise ParameterError("groups is empty; name at least one input group or pass None for all inputs")
        B = np.hstack([m.b(g) for g in groups])
        D = np.hstack([m.d(g) for g in groups])
    n, k, p = m.n, B.shape[1], m.p
    M = np.block([[m.A, B], [m.C, D]]) if n + p else np.zeros((0, n + k))
    N = np.zeros_like(M)
    N[:n, :n] = m.E
    return M, N


def system_structure(model, groups=None, *, tol: float | None = None) -> KroneckerStructure:
    """The Kronecker structure of the system pencil (zeros, infinite structure, minimal indices, normal rank).

    Parameters
    ----------
    model : DescriptorModel or FaultModel
        The model.
    groups : str or sequence of str, optional
        Input groups (default all inputs).
    tol : float, optional
        Relative rank tolerance of the staircase.

    Returns
    -------
    KroneckerStructure
        Of ``[[A − λE, B], [C, D]]``; ``normal_rank`` is that of the pencil (``n +`` the rank of ``G``).

    Examples
    --------
    >>> m = DescriptorModel([[0.0, 1.0], [-2.0, -3.0]], [[1.0, 1.0]], Bu=[[0.0], [1.0]])  # (s+1)/((s+1)(s+2))
    >>> s = system_structure(m)
    >>> s.finite_eigenvalues.real.round(9).tolist(), s.n_infinite_zeros, s.normal_rank
    ([-1.0], 1, 3)

    References
    ----------
    Varga (2017), §9.1.5.
    """
    M, N = system_pencil(model, groups)
    return pencil_structure(M, N, tol=tol)


def system_zeros(model, groups=None, *, tol: float | None = None) -> np.ndarray:
    """The finite zeros of the system: finite eigenvalues of its system pencil.

    Parameters
    ----------
    model : DescriptorModel or FaultModel
        The model.
    groups : str or sequence of str, optional
        Input groups (default all inputs).
    tol : float, optional
        Relative rank tolerance.

    Returns
    -------
    numpy.ndarray
        Complex zeros, sorted.

    Examples
    --------
    >>> m = DescriptorModel([[0.0, 1.0], [-2.0, -3.0]], [[3.0, 1.0]], Bu=[[0.0], [1.0]])  # (s + 3)/((s+1)(s+2))
    >>> system_zeros(m).real.round(9).tolist()
    [-3.0]
    """
    return system_structure(model, groups, tol=tol).finite_eigenvalues


def normal_rank(model, groups=None, *, tol: float | None = None) -> int:
    """The normal rank of the transfer matrix ``G(λ)`` (the reference's ``gnrank``).

    Parameters
    ----------
    model : DescriptorModel or FaultModel
        The model (a regular pencil ``A − λE``).
    groups : str or sequence of str, optional
        Input groups (default all inputs).
    tol : float, optional
        Relative rank tolerance.

    Returns
    -------
    int
        ``rank S(λ) − n`` for almost every ``λ``.

    Examples
    --------
    >>> m = DescriptorModel([[-1.0]], [[1.0], [2.0]], Bu=[[1.0, 1.0]])  # two inputs, two outputs, rank one
    >>> normal_rank(m)
    1
    """
    m = _descriptor(model)
    return system_structure(m, groups, tol=tol).normal_rank - m.n
