"""Subspaces: numerical rank, orthonormal bases of ranges and null spaces, sums, intersections, membership.

Orthonormal bases and SVD rank decisions throughout; every tolerance scales with the data
(``1e3 · max(shape) · eps · σ_max`` by default, or a caller's relative tolerance ``rtol · σ_max``).
The geometry of detection filters built on them (CAISA, invariant zeros, detection spaces) is
:mod:`fdikit.linalg.geometry`.
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["rank", "orth", "null", "intersect", "span_sum", "contains", "as_2d", "checked_rtol", "EPS"]

#: Double-precision machine epsilon, the unit of the default rank tolerances.
EPS = np.finfo(float).eps


def as_2d(name: str, M) -> np.ndarray:
    """``M`` as a finite real or complex 2-D array (a vector is one row); ParameterError otherwise.

    Parameters
    ----------
    name : str
        The argument's name, as the error message quotes it.
    M : array_like
        A matrix, or a vector (read as one row).

    Returns
    -------
    numpy.ndarray
        ``M`` as a 2-D float or complex array.

    Raises
    ------
    ParameterError
        For a non-numeric or non-finite ``M`` or one with more than two dimensions.

    Examples
    --------
    >>> as_2d("W", [1.0, 2.0]).shape
    (1, 2)
    """
    return validate.as_matrix(name, M, promote=True, complex_ok=True)


def checked_rtol(rtol: float | None) -> float | None:
    """A relative rank tolerance: ``None`` (the default of :func:`rank`) or a number >= 0.

    Parameters
    ----------
    rtol : float or None
        The tolerance to check.

    Returns
    -------
    float or None
        ``rtol`` as a float, or None.

    Raises
    ------
    ParameterError
        For a negative or non-numeric ``rtol``.

    Examples
    --------
    >>> checked_rtol(1e-9), checked_rtol(None)
    (1e-09, None)
    """
    if rtol is None:
        return None
    return validate.non_negative("rtol", rtol)


def _tol(M: np.ndarray, s: np.ndarray, rtol: float | None) -> float:
    smax = s[0] if s.size else 0.0
    return (rtol if rtol is not None else max(M.shape) * EPS * 1e3) * max(smax, 0.0)


def rank(M: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank: singular values above ``rtol · σ_max`` (default ``1e3 · max(shape) · eps``).

    Parameters
    ----------
    M : array_like
        Real or complex matrix (a vector is one row).
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    int
        The number of singular values above the tolerance (0 for an empty or zero matrix).

    Raises
    ------
    ParameterError
        If ``M`` is not a finite numeric matrix or ``rtol`` is negative.

    Examples
    --------
    >>> rank(np.array([[1.0, 2.0], [2.0, 4.0]]))
    1
    """
    M, rtol = as_2d("M", M), checked_rtol(rtol)
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0


def orth(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the range of ``M`` (n x r).

    Parameters
    ----------
    M : array_like
        (n, k) real or complex matrix (a vector is one row).
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (n, r) matrix with orthonormal columns spanning ``Im M``, ``r = rank(M)`` (left singular vectors).

    Raises
    ------
    ParameterError
        If ``M`` is not a finite numeric matrix or ``rtol`` is negative.

    Examples
    --------
    >>> orth(np.array([[1.0, 2.0], [2.0, 4.0]])).shape
    (2, 1)
    """
    M, rtol = as_2d("M", M), checked_rtol(rtol)
    if M.size == 0:
        return np.zeros((M.shape[0], 0), dtype=M.dtype)
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    r = int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0
    return U[:, :r]


def null(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the null space of ``M`` (columns).

    Parameters
    ----------
    M : array_like
        (m, n) real or complex matrix (a vector is one row); ``m = 0`` gives the identity.
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (n, n − rank(M)) matrix with orthonormal columns spanning ``Ker M``.

    Raises
    ------
    ParameterError
        If ``M`` is not a finite numeric matrix or ``rtol`` is negative.

    Examples
    --------
    >>> N = null(np.array([[1.0, 1.0]]))
    >>> N.shape, np.round(np.abs(N.ravel()), 6).tolist()
    ((2, 1), [0.707107, 0.707107])
    """
    M, rtol = as_2d("M", M), checked_rtol(rtol)
    if M.shape[0] == 0:
        return np.eye(M.shape[1], dtype=M.dtype)
    _, s, Vh = np.linalg.svd(M, full_matrices=True)
    r = int((s > _tol(M, s, rtol)).sum()) if s.size and s[0] > 0 else 0
    return Vh[r:].conj().T


def span_sum(*bases: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U₁ + Im U₂ + …``.

    Parameters
    ----------
    *bases : array_like
        Matrices with the same number of rows n whose columns span the subspaces; empty ones are skipped.
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (n, r) orthonormal basis of the sum (:func:`orth` of the side-by-side bases).

    Raises
    ------
    ParameterError
        If every basis is empty, the bases have different numbers of rows, or one is not a finite matrix.

    Examples
    --------
    >>> e = np.eye(3)
    >>> span_sum(e[:, [0]], e[:, [1]], e[:, [0]]).shape
    (3, 2)
    """
    bases = [as_2d(f"basis {i}", b) for i, b in enumerate(bases) if np.size(b)]
    if not bases:
        raise ParameterError("span_sum needs at least one non-empty basis")
    rows = {b.shape[0] for b in bases}
    if len(rows) > 1:
        raise ParameterError(f"span_sum: the bases have different numbers of rows {sorted(rows)}; "
                             "every basis must live in the same space")
    return orth(np.hstack(bases), rtol)


def intersect(U: np.ndarray, V: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U ∩ Im V``.

    From the null space of ``[U, −V]`` with ``U``, ``V`` first made orthonormal.

    Parameters
    ----------
    U, V : array_like
        (n, k) and (n, l) matrices whose columns span the two subspaces.
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (n, r) orthonormal basis of the intersection (r = 0 when it is the zero subspace).

    Raises
    ------
    ParameterError
        If ``U`` and ``V`` have different numbers of rows, or one is not a finite matrix.

    Examples
    --------
    >>> e = np.eye(3)
    >>> np.round(np.abs(intersect(e[:, :2], e[:, 1:])).ravel(), 6).tolist()
    [0.0, 1.0, 0.0]
    """
    U, V = orth(U, rtol), orth(V, rtol)
    if U.shape[0] != V.shape[0]:
        raise ParameterError(f"intersect: U has {U.shape[0]} rows but V has {V.shape[0]}; both bases must live in "
                             "the same space")
    if U.shape[1] == 0 or V.shape[1] == 0:
        return np.zeros((U.shape[0], 0))
    N = null(np.hstack([U, -V]), rtol)
    return orth(U @ N[: U.shape[1]], rtol)


def contains(U: np.ndarray, x: np.ndarray, rtol: float = 1e-8) -> bool:
    """Whether every column of ``x`` lies in ``Im U`` (relative residual below ``rtol``).

    Parameters
    ----------
    U : array_like
        (n, k) matrix whose columns span the subspace.
    x : array_like
        A vector of length n or an (n, m) matrix of vectors.
    rtol : float, default 1e-8
        Bound on ``‖x − Q Qᴴ x‖ / ‖x‖`` (Frobenius norms; ``Q = orth(U)``).

    Returns
    -------
    bool
        True when the projection residual of ``x`` on ``Im U`` is below ``rtol`` relative to ``‖x‖``.

    Raises
    ------
    ParameterError
        If ``x`` does not have n rows, or ``U`` or ``x`` is not a finite matrix.

    Examples
    --------
    >>> e = np.eye(3)
    >>> contains(e[:, :2], [1.0, 2.0, 0.0]), contains(e[:, :2], [0.0, 0.0, 1.0])
    (True, False)
    """
    Q = orth(U)
    x = np.asarray(x)
    x = as_2d("x", x.reshape(-1, 1) if x.ndim == 1 else x)
    if x.shape[0] != Q.shape[0]:
        raise ParameterError(f"x has {x.shape[0]} rows but U has {Q.shape[0]}; pass vectors of length {Q.shape[0]}")
    res = x - Q @ (Q.conj().T @ x)
    return bool(np.linalg.norm(res) <= rtol * max(np.linalg.norm(x), EPS))
