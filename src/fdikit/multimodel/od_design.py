"""Orthogonal-decomposition (OD) model-set design: Hallouzi 2008, §3.3.2, (3.19)–(3.23).

:func:`od_model_set` selects members of the large model set ``M_ℓ`` (model vectors of
:func:`~fdikit.multimodel.model_set.vectorize`) by a pivoted QR with a documented tie rule (:func:`pivoted_qr`)
followed by an affine projection (3.21).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ParameterError
from fdikit.multimodel.model_set import affine_weights, as_model_matrix, gap_rank

__all__ = ["pivoted_qr", "ODModelSet", "od_model_set"]


# ------------------------------------------------------------------------------------ OD
@dataclass(frozen=True)
class ODModelSet:
    """Result of :func:`od_model_set` (Hallouzi 2008, §3.3.2).

    Attributes
    ----------
    indices : tuple of int
        Columns of ``M_ℓ`` selected, in the pivot order of (3.22) ("most influential first").
    models : numpy.ndarray
        ``M̃_r = M_ℓ[:, indices]`` (3.23).
    rank : int
        ``N_r``, the numerical rank from the gap in ``|diag R|`` of (3.19).
    diag_r : numpy.ndarray
        ``|diag R_{M_ℓ}|`` of the pivoted QR (3.19).
    singular_values : numpy.ndarray
        Singular values of ``M_ℓ`` (for comparison with ``diag_r``).
    weights : numpy.ndarray
        Affine weights (3.21) of every large-set model on the final set, ``(N_r+1) × N_ℓ``.
    residual : numpy.ndarray
        ``‖M̃_r w_j − 𝔐_j‖₂`` per large-set model (0 when the set represents it exactly).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> od = od_model_set(rng.normal(size=(2, 1000)) + [[3.0], [1.0]])
    >>> od.rank, od.models.shape, od.weights.shape
    (2, (2, 3), (3, 1000))

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.19)–(3.23).
    """

    indices: tuple[int, ...]
    models: np.ndarray
    rank: int
    diag_r: np.ndarray
    singular_values: np.ndarray
    weights: np.ndarray
    residual: np.ndarray


def pivoted_qr(matrix, tie_tol: float = 1e-10, priority=None) -> tuple[np.ndarray, np.ndarray]:
    """Column-pivoted QR (Businger–Golub) with a rounding-proof tie rule; returns ``(pivots, |diag R|)``.

    Step ``k`` takes the column with the largest residual norm, the norm of its component orthogonal to
    the ``k`` columns already taken (modified Gram–Schmidt, the new direction re-orthogonalised twice).
    Residual norms are compared on the scale of the criterion, ``s = max_j ‖a_j‖`` (``= |R_11|``): columns
    within ``tie_tol · s`` of the largest **tie**, and the tie goes to the smallest ``priority`` (then the
    smallest column index).  A computed residual norm is off by ``O(k ε s)`` at step ``k``, so with the
    default ``1e-10`` ties that rounding would break — exact ties of a symmetric grid, and every column
    once the residual is numerically zero (steps beyond the numerical rank) — are decided by the key
    alone, identically on every BLAS, while genuine differences of a model set (≥ 1e-6 s here) are kept.
    LAPACK's ``geqp3`` (``scipy.linalg.qr(pivoting=True)``) breaks such ties by its rounding, which
    differs between OpenBLAS kernels.

    Parameters
    ----------
    matrix : array_like
        ``(m, n)`` finite matrix.
    tie_tol : float
        Relative tie tolerance, in ``[0, 1)``.
    priority : array_like, optional
        ``(n,)`` secondary key, lower wins among tied columns; default the column order.

    Returns
    -------
    pivots : ndarray of int
        (n,) the column order ``Π``.
    diag_r : ndarray
        (min(m, n),) ``|diag R|``.

    Raises
    ------
    ParameterError
        If ``tie_tol`` is not in [0, 1) or ``priority`` is not n finite numbers.

    Examples
    --------
    >>> piv, d = pivoted_qr([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    >>> piv.tolist(), d.round(6).tolist()   # column 2 is the longest; 0 and 1 then tie: column order decides
    ([2, 0, 1], [1.414214, 0.707107])
    >>> pivoted_qr([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], priority=[1, 0, 2])[0].tolist()
    [2, 1, 0]

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.19), (3.22) (the pivoted QR of the OD method).
    """
    M = as_model_matrix(matrix)
    m, n = M.shape
    tie_tol = float(tie_tol) if isinstance(tie_tol, (int, float, np.floating, np.integer)) else np.nan
    if not 0.0 <= tie_tol < 1.0:
        raise ParameterError(f"tie_tol must be a number in [0, 1), got {tie_tol!r}")
    if priority is None:
        key = np.arange(n, dtype=float)
    else:
        try:
            key = np.asarray(priority, dtype=float).ravel()
        except (TypeError, ValueError):
            raise ParameterError(f"priority must be {n} numbers (one per column), got {priority!r}") from None
        if key.shape != (n,) or not np.all(np.isfinite(key)):
            raise ParameterError(f"priority must be {n} finite numbers (one per column), got shape {key.shape}")
    W = M.copy()
    norms = np.linalg.norm(W, axis=0)
    scale = norms.max()
    free = np.ones(n, bool)
    pivots, diag = [], []
    Q = np.zeros((m, 0))
    for _ in range(min(m, n)):
        cand = np.where(free, norms, -np.inf)
        tied = np.flatnonzero(free & (cand >= cand.max() - tie_tol * scale))
        p = int(tied[np.lexsort((tied, key[tied]))[0]])
        pivots.append(p)
        diag.append(norms[p])
        free[p] = False
        if norms[p] > 0:
            q = W[:, p] / norms[p]
            for _ in range(2):
                q = q - Q @ (Q.T @ q)
                q = q / np.linalg.norm(q)
            Q = np.column_stack([Q, q])
            W[:, free] -= np.outer(q, q @ W[:, free])
        norms = np.linalg.norm(W, axis=0)
    pivots.extend(int(j) for j in np.flatnonzero(free)[np.lexsort((np.flatnonzero(free), key[free]))])
    return np.array(pivots), np.array(diag)


def od_model_set(models, rank: int | None = None, min_gap: float = 10.0, *, tie_tol: float = 1e-10,
                 priority=None) -> ODModelSet:
    """Orthogonal-decomposition model-set design, Hallouzi 2008, §3.3.2, (3.19)–(3.23).

    1. Pivoted QR ``M_ℓ Π = Q R`` (:func:`pivoted_qr`); ``N_r`` from the gap in ``|diag R|``
       (:func:`gap_rank`) unless ``rank`` is given.
    2. ``M_r`` = the first ``N_r + 1`` pivoted columns (one more for the sum-to-one constraint).
    3. ``M̃_ℓ = [M_r; 1]^† [M_ℓ; 1]`` (affine projection).
    4. Pivoted QR of ``M̃_ℓ``; the final set is the first ``N_r + 1`` pivoted columns of ``M_ℓ``.

    **Tie rule.**  The thesis leaves ties of the pivoting criterion open, and they are common: a grid
    sampled symmetrically over the parameter box gives columns of exactly equal residual norm, and
    the ``(N_r + 1)``-th pivot of both decompositions is taken where every residual is numerically zero
    (the extra model lies in the span of the first ``N_r``).  LAPACK decides those by rounding, so the
    set changed with the BLAS kernel.  Here residual norms within ``tie_tol`` times the largest column
    norm tie, and ties go to the smallest ``priority`` (default: the first column of ``M_ℓ``); see
    :func:`pivoted_qr`.  The design is then the same on every machine.

    Parameters
    ----------
    models : array_like
        ``M_ℓ``, one model vector per column (see :func:`~fdikit.multimodel.model_set.vectorize`).
    rank : int, optional
        ``N_r``; the set then has ``N_r + 1`` models.
    min_gap : float
        Smallest ratio counted as a significant gap (> 0).
    tie_tol : float
        Relative tie tolerance of the pivoting (:func:`pivoted_qr`).
    priority : array_like, optional
        ``(N_ℓ,)`` secondary key among tied columns (lower wins), e.g. one that prefers models at the
        limits of a parameter range; default the column order.

    Returns
    -------
    ODModelSet
        The selected models, their indices in ``M_ℓ``, the rank and the affine weights of every large-set model.

    Raises
    ------
    DesignError
        If ``N_r + 1`` exceeds the number of models.
    ParameterError
        On a non-positive ``min_gap``, a ``rank`` that is not a positive integer, a bad ``tie_tol`` or ``priority``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> od = od_model_set(rng.normal(size=(2, 1000)) + [[3.0], [1.0]])
    >>> len(od.indices), bool(od.residual.max() < 1e-10)
    (3, True)

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.19)–(3.23).
    """
    M = as_model_matrix(models)
    if not isinstance(min_gap, (int, float, np.floating, np.integer)) or not min_gap > 0 or not np.isfinite(min_gap):
        raise ParameterError(f"min_gap must be a positive number (a ratio of successive |diag R|), got {min_gap!r}")
    if rank is not None and (isinstance(rank, bool) or not isinstance(rank, (int, np.integer)) or rank < 1):
        raise ParameterError(f"rank must be a positive integer N_r (the set has N_r + 1 models), got {rank!r}")
    piv, diag_r = pivoted_qr(M, tie_tol, priority)
    sv = np.linalg.svd(M, compute_uv=False)
    n_r = gap_rank(diag_r, min_gap) if rank is None else int(rank)
    if n_r + 1 > M.shape[1]:
        raise DesignError(f"N_r + 1 = {n_r + 1} models requested but the large set has {M.shape[1]}; "
                          "lower the rank or add models")
    Mr = M[:, piv[: n_r + 1]]
    projected = affine_weights(Mr, M)
    piv2, _ = pivoted_qr(projected, tie_tol, priority)
    indices = tuple(int(i) for i in piv2[: n_r + 1])
    final = M[:, list(indices)]
    weights = affine_weights(final, M)
    residual = np.linalg.norm(final @ weights - M, axis=0)
    return ODModelSet(indices, final, n_r, diag_r, sv, weights, residual)
