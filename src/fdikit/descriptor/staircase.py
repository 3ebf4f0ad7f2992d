"""Kronecker structure of a matrix pencil by orthogonal staircase reductions.

A pencil ``M − λN`` (any shape) is brought by orthogonal transformations ``Qᵀ (M − λN) Z`` to a Kronecker-like
form whose blocks give its right (column) Kronecker indices ``ε``, its left (row) indices ``η``, the sizes of its
Jordan blocks at infinity and a regular pencil ``Mf − λNf`` with ``Nf`` invertible whose generalised eigenvalues
are the finite eigenvalues of ``M − λN`` (Van Dooren 1979; Varga 2017, §9.1.5 and §10.1.6).

The algorithm is Van Dooren's two-pass staircase.  Pass one, on ``M − λN``: repeatedly compress the columns of
``N`` (an SVD: its right null space first, ``sᵢ`` columns), compress the rows of the first ``sᵢ`` columns of ``M``
(an SVD: rank ``rᵢ``) and deflate those ``rᵢ`` rows and ``sᵢ`` columns, until ``N`` has full column rank.  Then
``sᵢ − rᵢ`` blocks ``L_{i−1}`` (right index ``i − 1``) and ``rᵢ − sᵢ₊₁`` Jordan blocks of size ``i`` at infinity
were split off.  Pass two repeats this on the transpose of what is left and gives the left indices.  Every rank
decision is an SVD with the tolerance ``tol · max(‖M‖_F, ‖N‖_F)``, every transformation orthogonal, so the
structure returned is the exact one of a pencil within that distance (backward stability).

The *system pencil* of a descriptor model is ``S(λ) = [[A − λE, B], [C, D]]``; its finite eigenvalues are the
finite (Smith) zeros of the system, its normal rank is the normal rank of the transfer matrix plus the order
``n`` (for a regular ``A − λE``), Jordan blocks of size ``k > 1`` at infinity are infinite zeros of order
``k − 1``, and its left / right Kronecker indices are the left / right minimal indices of the transfer matrix
(SLICOT ``AG08BD`` computes the same quantities).

:func:`controllability_staircase` is the same kind of reduction on a pair ``(A, B)`` with an absolute threshold
(slycot's ``AB01ND`` decides rank relative to each block, which counts a ``B`` that is zero to rounding as full
rank).

References
----------
Van Dooren (1979), "The computation of Kronecker's canonical form of a singular pencil", Linear Algebra Appl. 27.
Varga (2017), §9.1.5 (the Kronecker form), §10.1.6 (its computation; the reference's ``gzero``, ``gnrank``,
``gpole``).  ``fdtools`` (FaultDetectionTools.jl, through DescriptorSystems.jl ``pzeros``, ``pkstruct``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["KroneckerStructure", "controllability_staircase", "pencil_structure", "split_infinite"]

_EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class KroneckerStructure:
    """The Kronecker structure of a pencil ``M − λN``.

    Attributes
    ----------
    finite_eigenvalues : numpy.ndarray
        The finite eigenvalues (complex, sorted by real part then imaginary part); for a system pencil the finite
        zeros of the system.
    infinite_blocks : tuple of int
        Sizes of the Jordan blocks at infinity (SLICOT's ``INFE``), descending.
    right_indices : tuple of int
        Right (column) Kronecker indices ``ε`` (SLICOT's ``KRONR``), ascending.
    left_indices : tuple of int
        Left (row) Kronecker indices ``η`` (SLICOT's ``KRONL``), ascending.
    normal_rank : int
        The rank of ``M − λN`` for almost every ``λ``.
    shape : tuple of int
        The pencil's (rows, columns).

    Examples
    --------
    >>> import numpy as np
    >>> s = pencil_structure(np.array([[0.0, 1.0]]), np.array([[1.0, 0.0]]))  # the block L_1 = [−λ, 1]
    >>> s.right_indices, s.left_indices, s.normal_rank
    ((1,), (), 1)
    """

    finite_eigenvalues: np.ndarray
    infinite_blocks: tuple[int, ...]
    right_indices: tuple[int, ...]
    left_indices: tuple[int, ...]
    normal_rank: int
    shape: tuple[int, int]

    @property
    def infinite_zeros(self) -> tuple[int, ...]:
        """Orders of the infinite zeros: ``k − 1`` for every Jordan block of size ``k > 1`` at infinity."""
        return tuple(k - 1 for k in self.infinite_blocks if k > 1)

    @property
    def n_infinite_zeros(self) -> int:
        """Number of infinite zeros counted with their orders (SLICOT's ``NIZ``)."""
        return int(sum(self.infinite_zeros))

    @property
    def is_regular(self) -> bool:
        """Whether the pencil is square with ``det(M − λN) ≢ 0``."""
        rows, cols = self.shape
        return rows == cols and self.normal_rank == rows


def _rank(S: np.ndarray, thresh: float) -> int:
    return int(np.sum(S > thresh))


def _staircase(M: np.ndarray, N: np.ndarray, thresh: float):
    """One pass: split the ε and infinite structure off ``M − λN``.

    Returns the (s, r) lists, the rest ``(Mr, Nr)`` and the accumulated ``Q``, ``Z`` with ``Qᵀ M Z`` block upper
    triangular: the split-off part in the leading ``Σr`` rows and ``Σs`` columns, the rest trailing.
    """
    s_list: list[int] = []
    r_list: list[int] = []
    Q, Z = np.eye(M.shape[0]), np.eye(M.shape[1])
    i0 = j0 = 0
    while M.shape[1] > 0:
        rows, cols = M.shape
        if rows == 0:
            s_list.append(cols)
            r_list.append(0)
            M, N = M[:, cols:], N[:, cols:]
            break
        _, S, Vt = scipy.linalg.svd(N, lapack_driver="gesvd")
        rn = _rank(S, thresh)
        s = cols - rn
        if s == 0:
            break
        Zi = np.hstack([Vt[rn:].T, Vt[:rn].T])
        Mz, Nz = M @ Zi, N @ Zi
        Nz[:, :s] = 0.0
        U1, S1, _ = scipy.linalg.svd(Mz[:, :s], lapack_driver="gesvd")
        r = _rank(S1, thresh)
        Mq, Nq = U1.T @ Mz, U1.T @ Nz
        Q[:, i0:] = Q[:, i0:] @ U1
        Z[:, j0:] = Z[:, j0:] @ Zi
        s_list.append(s)
        r_list.append(r)
        M, N = Mq[r:, s:], Nq[r:, s:]
        i0, j0 = i0 + r, j0 + s
    return s_list, r_list, M, N, Q, Z


def _indices(s_list: list[int], r_list: list[int]) -> tuple[list[int], list[int]]:
    """Kronecker indices (``sᵢ − rᵢ`` blocks of index ``i − 1``) and infinite block sizes (``rᵢ − sᵢ₊₁`` of size i)."""
    kron: list[int] = []
    inf: list[int] = []
    for i, (s, r) in enumerate(zip(s_list, r_list, strict=True)):
        kron += [i] * (s - r)
        s_next = s_list[i + 1] if i + 1 < len(s_list) else 0
        inf += [i + 1] * (r - s_next)
    return kron, inf


def _checked(M, N, tol):
    """Validated pencil, the absolute rank threshold and the relative tolerance."""
    M = validate.as_matrix("M (pencil M − λN)", M, promote=True)
    N = validate.as_matrix("N (pencil M − λN)", N, M.shape, promote=True)
    rows, cols = M.shape
    if tol is None:
        tol = max(rows, 1) * max(cols, 1) * _EPS
    tol = validate.number("tol (relative rank tolerance)", tol)
    if not 0.0 <= tol < 1.0:
        raise ParameterError(f"tol (relative rank tolerance) must be in [0, 1), got {tol}")
    scale = max(np.linalg.norm(M), np.linalg.norm(N))
    return M, N, (tol * scale if scale > 0 else 0.0), tol


def pencil_structure(M, N, *, tol: float | None = None) -> KroneckerStructure:
    """The Kronecker structure of the pencil ``M − λN`` by orthogonal staircase reductions.

    Parameters
    ----------
    M, N : array_like
        The pencil's matrices (same shape, any number of rows and columns).
    tol : float, optional
        Relative rank tolerance: singular values below ``tol · max(‖M‖_F, ‖N‖_F)`` count as zero.  Default
        ``rows · cols · ε`` (SLICOT ``AG08BD``'s default ``(L+P)(N+M) ε``).

    Returns
    -------
    KroneckerStructure
        Finite eigenvalues, Jordan blocks at infinity, left and right Kronecker indices, normal rank.

    Raises
    ------
    ParameterError
        For matrices of different shapes, non-finite entries or a tolerance outside ``[0, 1)``.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # a nilpotent Jordan block at infinity
    >>> N = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    >>> s = pencil_structure(M, N)
    >>> s.infinite_blocks, s.finite_eigenvalues.size, s.is_regular
    ((3,), 0, True)

    References
    ----------
    Van Dooren (1979); Varga (2017), §10.1.6.
    """
    M, N, thresh, tol = _checked(M, N, tol)
    rows, cols = M.shape
    s1, r1, Mr, Nr, _, _ = _staircase(M.astype(float, copy=True), N.astype(float, copy=True), thresh)
    right, inf = _indices(s1, r1)
    s2, r2, Mt, Nt, _, _ = _staircase(Mr.T.copy(), Nr.T.copy(), thresh)
    left, inf2 = _indices(s2, r2)
    Mf, Nf = Mt.T, Nt.T
    if Mf.shape[0] != Mf.shape[1]:  # cannot happen in exact arithmetic; a rank decision at the tolerance edge
        raise ParameterError(f"the staircase left a {Mf.shape} non-square regular part; the rank decisions are "
                             f"ambiguous at tol={tol:g}; pass a larger tol")
    finite = scipy.linalg.eigvals(Mf, Nf) if Mf.size else np.zeros(0, complex)
    finite = np.sort_complex(np.asarray(finite, dtype=complex))
    normal_rank = cols - len(right)
    return KroneckerStructure(
        finite_eigenvalues=finite,
        infinite_blocks=tuple(sorted(inf + inf2, reverse=True)),
        right_indices=tuple(sorted(right)),
        left_indices=tuple(sorted(left)),
        normal_rank=int(normal_rank),
        shape=(rows, cols),
    )


def split_infinite(A, E, *, tol: float | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Orthogonal ``Q``, ``Z`` that put the infinite eigenvalues of a regular ``A − λE`` first.

    ``Qᵀ (A − λE) Z = [[A∞ − λE∞, A₁₂ − λE₁₂], [0, Af − λEf]]`` with ``A∞`` invertible and ``E∞`` nilpotent-like
    (only infinite eigenvalues, ``n∞`` of them) and ``Ef`` invertible (only finite ones): pass one of
    :func:`pencil_structure`'s staircase with the transformations kept.

    Parameters
    ----------
    A, E : array_like
        Square matrices of a regular pencil.
    tol : float, optional
        Relative rank tolerance, as in :func:`pencil_structure`.

    Returns
    -------
    Q, Z : numpy.ndarray
        Orthogonal transformations.
    n_inf : int
        The number of infinite eigenvalues (the size of the leading block).

    Raises
    ------
    ParameterError
        If the pencil is not square or is singular (a right Kronecker block was found).

    Examples
    --------
    >>> import numpy as np
    >>> Q, Z, k = split_infinite(np.eye(2), np.diag([1.0, 0.0]))
    >>> k, np.round(np.abs(Q.T @ np.diag([1.0, 0.0]) @ Z), 12).tolist()
    (1, [[0.0, 0.0], [0.0, 1.0]])
    """
    A, E, thresh, _ = _checked(A, E, tol)
    if A.shape[0] != A.shape[1]:
        raise ParameterError(f"split_infinite needs a square pencil, got shape {A.shape}")
    s_list, r_list, _, _, Q, Z = _staircase(A.astype(float, copy=True), E.astype(float, copy=True), thresh)
    if sum(s_list) != sum(r_list):
        raise ParameterError("the pencil A − λE is singular (det(λE − A) ≡ 0): it has right Kronecker indices "
                             f"{_indices(s_list, r_list)[0]}")
    return Q, Z, int(sum(s_list))


def controllability_staircase(A, B, thresh: float) -> tuple[np.ndarray, int]:
    """Orthogonal ``Q`` and ``k`` with ``QᵀAQ = [[A11, A12], [0, A22]]``, ``QᵀB = [[B1], [0]]``, (A11, B1) controllable.

    The controllability staircase: a rank decision by SVD at each step, singular values at or below the absolute
    threshold ``thresh`` counted as zero (callers scale it to their problem).

    Parameters
    ----------
    A : array_like
        ``(n, n)``.
    B : array_like
        ``(n, m)``.
    thresh : float
        Absolute rank threshold.

    Returns
    -------
    Q : numpy.ndarray
        ``(n, n)`` orthogonal; its first ``k`` columns span the controllable subspace.
    k : int
        The dimension of the controllable subspace.

    Examples
    --------
    The second state of ``diag(−1, −2)`` is not reached from ``B = [1; 0]``:

    >>> Q, k = controllability_staircase(np.diag([-1.0, -2.0]), np.array([[1.0], [0.0]]), 1e-12)
    >>> k, np.round(np.abs(Q[:, 0]), 12).tolist()
    (1, [1.0, 0.0])

    References
    ----------
    Van Dooren (1981); Varga (2017), §7.3 (the controllability staircase form).
    """
    At, block = np.array(A, dtype=float), np.array(B, dtype=float)
    n = At.shape[0]
    Q, k = np.eye(n), 0
    while k < n and block.size:
        U, s, _ = np.linalg.svd(block)
        rank = int(np.sum(s > thresh))
        if rank == 0:
            break
        T = np.eye(n)
        T[k:, k:] = U
        At, Q = T.T @ At @ T, Q @ T
        block, k = At[k + rank:, k:k + rank], k + rank
    return Q, k
