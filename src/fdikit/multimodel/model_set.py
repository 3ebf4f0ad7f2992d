"""Model-set design for multiple-model estimation: Hallouzi 2008, Ch. 3 and App. B.

A local model ``{A, B, C, D}`` is the vector ``𝔐 = vec([A B; C D])`` (3.14); a large model set is
the matrix ``M_ℓ`` of such columns (3.15).  Three designs reduce it to a few local models:

* :func:`od_model_set` — orthogonal decomposition (pivoted QR with a documented tie rule,
  :func:`pivoted_qr`) with affine projection, §3.3.2, (3.19)–(3.23); selects members of ``M_ℓ``.
* :func:`~fdikit.multimodel.cp_design.cp_model_set` — an enclosing convex polytope in SVD coordinates, §3.4,
  (3.31)–(3.33) (module :mod:`fdikit.multimodel.cp_design`).
* :func:`limit_value_model_set` — limit values of the varying entries, §3.5, (3.34)–(3.40).

Helpers: :func:`first_order_discretize` and :func:`taylor_remainder_bound` (App. B),
:func:`affine_weights` (3.21), :func:`nearest_model` (3.51)–(3.52),
:func:`minimum_mismatch_points` (Li et al. 2005, §3.6.4) and :func:`observability_condition`
(Def. 3.1, (3.7)–(3.9)).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ModelError, ParameterError

__all__ = [
    "vectorize",
    "unvectorize",
    "first_order_discretize",
    "taylor_remainder_bound",
    "gap_rank",
    "affine_weights",
    "pivoted_qr",
    "ODModelSet",
    "od_model_set",
    "LimitValueModelSet",
    "limit_value_model_set",
    "nearest_model",
    "minimum_mismatch_points",
    "observability_condition",
    "pair_observability",
]


# ---------------------------------------------------------------------------------------------- vec
def vectorize(A, B, C, D=None) -> np.ndarray:
    """``vec([A B; C D])`` (column stacking), Hallouzi 2008, (3.14).

    Parameters
    ----------
    A, B, C : array_like
        State (n x n), input (n x m) and output (p x n) matrices.
    D : array_like, optional
        Feedthrough (p x m); zero if omitted.

    Returns
    -------
    ndarray
        The model vector ``𝔐`` ((n + p)(n + m),).

    Raises
    ------
    ModelError
        If the shapes are inconsistent.

    Examples
    --------
    >>> vectorize([[1.0]], [[2.0]], [[3.0]]).tolist()
    [1.0, 3.0, 2.0, 0.0]

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.14)–(3.15).
    """
    A, B, C = (np.atleast_2d(np.asarray(M, float)) for M in (A, B, C))
    D = np.zeros((C.shape[0], B.shape[1])) if D is None else np.atleast_2d(np.asarray(D, float))
    if A.shape[0] != A.shape[1] or B.shape[0] != A.shape[0] or C.shape[1] != A.shape[0] or \
            D.shape != (C.shape[0], B.shape[1]):
        raise ModelError(f"inconsistent shapes A {A.shape}, B {B.shape}, C {C.shape}, D {D.shape}; "
                         "need A n×n, B n×m, C p×n, D p×m")
    return np.block([[A, B], [C, D]]).ravel(order="F")


def unvectorize(vector, n: int, m: int, p: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`vectorize`: ``(A, B, C, D)`` from a model vector, Hallouzi 2008, (3.24).

    Parameters
    ----------
    vector : array_like
        Model vector of ``(n + p)(n + m)`` entries.
    n, m, p : int
        Numbers of states, inputs and outputs.

    Returns
    -------
    A, B, C, D : ndarray
        (n x n), (n x m), (p x n), (p x m).

    Raises
    ------
    ModelError
        If the vector has another length than ``(n + p)(n + m)``.

    Examples
    --------
    >>> [M.tolist() for M in unvectorize([1.0, 3.0, 2.0, 0.0], 1, 1, 1)]
    [[[1.0]], [[2.0]], [[3.0]], [[0.0]]]

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.14), (3.24).
    """
    vector = np.asarray(vector, float).ravel()
    if vector.size != (n + p) * (n + m):
        raise ModelError(f"a model vector for n={n}, m={m}, p={p} has {(n + p) * (n + m)} entries, got {vector.size}")
    M = vector.reshape((n + p, n + m), order="F")
    return M[:n, :n].copy(), M[:n, n:].copy(), M[n:, :n].copy(), M[n:, n:].copy()


def as_model_matrix(models) -> np.ndarray:
    M = np.asarray(models, float)
    if M.ndim != 2 or M.shape[1] < 1:
        raise ModelError(f"the large model set must be a 2-D array with one model vector per column, got {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ModelError("the large model set contains NaN or inf; remove or repair those models")
    return M


# ------------------------------------------------------------------------------------ App. B
def first_order_discretize(A, B, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """First-order Taylor discretisation ``(I + T A, T B)``, Hallouzi 2008, App. B, (B.8)–(B.9).

    Unlike ZOH it is linear in ``(A, B)``, so for weights summing to one the discretised convex
    combination of local models equals the combination of the discretised local models (B.9).

    Parameters
    ----------
    A, B : array_like
        Continuous-time state (n x n) and input (n x m) matrices.
    dt : float
        Sample time ``T`` [s], positive.

    Returns
    -------
    Ad, Bd : ndarray
        ``I + T A`` and ``T B``.

    Raises
    ------
    ModelError
        If ``dt`` is not positive and finite, or the shapes do not fit.

    Examples
    --------
    >>> Ad, Bd = first_order_discretize([[-2.0]], [[1.0]], 0.1)
    >>> Ad.tolist(), Bd.tolist()
    ([[0.8]], [[0.1]])

    References
    ----------
    Hallouzi 2008, App. B, (B.8)–(B.9); §4.3.1.
    """
    A = np.atleast_2d(np.asarray(A, float))
    B = np.atleast_2d(np.asarray(B, float))
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise ParameterError(f"the sample time must be positive, got {dt}")
    if A.shape[0] != A.shape[1] or B.shape[0] != A.shape[0]:
        raise ModelError(f"A must be square and B must have as many rows, got A {A.shape}, B {B.shape}")
    return np.eye(A.shape[0]) + dt * A, dt * B


def taylor_remainder_bound(A, dt: float, order: int = 1) -> float:
    """Entrywise bound on the remainder of the order-``M`` Taylor series of ``expm(A T)``.

    Hallouzi 2008, (B.5)–(B.7) (after Moler & Van Loan 2003):
    ``|r_ij| ≤ (‖A‖T)^{M+1}/(M+1)! · 1/(1 − ‖A‖T/(M+2))`` with ``‖A‖ = Σ|a_ij|``.  ``A`` may be a
    matrix or the norm itself (a scalar).

    Parameters
    ----------
    A : array_like or float
        The matrix (n x n), or ``‖A‖`` itself.
    dt : float
        Sample time ``T`` [s].
    order : int, optional
        Taylor order ``M`` (default 1, the first-order discretisation).

    Returns
    -------
    float
        The bound on every entry of ``expm(A T) − Σ_{k≤M} (A T)^k / k!``.

    Raises
    ------
    DesignError
        If ``‖A‖T ≥ M + 2`` (the geometric tail does not converge): take a smaller ``T``.

    Examples
    --------
    >>> round(taylor_remainder_bound(3.0, 0.01), 7)   # B747, §4.3.1: "in the order of 1e-4"
    0.0004545

    References
    ----------
    Hallouzi 2008, App. B, (B.5)–(B.7); §4.3.1.
    """
    A = np.asarray(A, float)
    norm = float(A) if A.ndim == 0 else float(np.abs(A).sum())
    if order < 0:
        raise DesignError(f"the Taylor order M must be >= 0, got {order}")
    x = norm * float(dt)
    if x >= order + 2:
        raise DesignError(f"‖A‖T = {x:.3g} >= M + 2 = {order + 2}: the bound (B.5) does not hold; reduce the "
                          "sample time or raise the order")
    return x ** (order + 1) / float(np.prod(np.arange(1, order + 2))) / (1.0 - x / (order + 2))


# ------------------------------------------------------------------------------------ rank
def gap_rank(values, min_gap: float = 10.0) -> int:
    """Numerical rank as the position of the largest gap in non-increasing values (σ or |diag R|).

    Hallouzi 2008, §3.3.2 asks for "the first significant gap" without a rule for it.
    Here: values at or below ``max · len · eps`` count as zero (the rank is then at most the number
    of nonzero values); the rank is the index of the largest ratio ``v_i / v_{i+1}`` if that ratio is
    at least ``min_gap``, else all values count.

    Parameters
    ----------
    values : array_like
        Non-increasing non-negative values (singular values or ``|diag R|``).
    min_gap : float, optional
        Smallest ratio counted as a significant gap (default 10).

    Returns
    -------
    int
        The numerical rank (0 for an empty or all-zero sequence).

    Examples
    --------
    >>> gap_rank([3.0, 1.0, 0.5, 1e-6, 1e-7])
    3

    References
    ----------
    Hallouzi 2008, §3.3.2, step 2 of the OD method, (3.19)–(3.20).
    """
    v = np.abs(np.asarray(values, float).ravel())
    if v.size == 0 or v[0] == 0:
        return 0
    floor = v[0] * v.size * np.finfo(float).eps
    w = np.maximum(v, floor)
    if v.size == 1:
        return 1
    ratios = w[:-1] / w[1:]
    k = int(np.argmax(ratios))
    return k + 1 if ratios[k] >= min_gap else int(v.size)


def affine_weights(reduced, models) -> np.ndarray:
    """Affine (sum-to-one) least-squares weights of ``models`` on ``reduced``, Hallouzi 2008, (3.21).

    ``W = [M_r; 1]^† [M; 1]``; column ``j`` holds the weights of model ``j``.  As in the thesis the
    sum-to-one condition is one more least-squares row: it holds exactly for models in the affine hull
    of ``M_r`` (e.g. every large-set model once OD has found the rank) and approximately otherwise.

    Parameters
    ----------
    reduced : array_like
        ``M_r`` (n_q x N_r), one model vector per column.
    models : array_like
        Models to represent (n_q x N).

    Returns
    -------
    ndarray
        Weights (N_r x N), one column per model.

    Raises
    ------
    ModelError
        If the two sets have model vectors of different lengths (or contain NaN/inf).

    Examples
    --------
    >>> affine_weights([[0.0, 2.0]], [[0.5, 1.0, 3.0]]).round(6).tolist()
    [[0.75, 0.5, -0.5], [0.25, 0.5, 1.5]]

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.21).
    """
    Mr = as_model_matrix(reduced)
    M = as_model_matrix(models)
    if Mr.shape[0] != M.shape[0]:
        raise ModelError(f"reduced set vectors have {Mr.shape[0]} entries, the models {M.shape[0]}")
    return np.linalg.pinv(np.vstack([Mr, np.ones(Mr.shape[1])])) @ np.vstack([M, np.ones(M.shape[1])])


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
        ``M_ℓ``, one model vector per column (see :func:`vectorize`).
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


# ------------------------------------------------------------------------------------ CP
# ------------------------------------------------------------------------------------ LV
Quadruple = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class LimitValueModelSet:
    """Limit-value model ``M(μ) = M⁺ + Σ_j μ_j M^Δ_j`` with ``μ_j ∈ [0, 1]``, Hallouzi 2008, (3.39)–(3.40).

    Attributes
    ----------
    names : tuple of str
        One weight per varying parameter (entries varying through the same parameter share it, §3.6.1).
    offset : tuple of arrays
        ``(A⁺, B⁺, C⁺, D⁺)``: the model at the "+" limits of all parameters.
    deltas : tuple of tuples of arrays
        ``(A^Δ_j, B^Δ_j, C^Δ_j, D^Δ_j)``: change when parameter ``j`` moves to its other limit.
    dt : float or None
        First-order sample time if discretised (3.44)–(3.45), else ``None``.

    Examples
    --------
    >>> lv = limit_value_model_set(lambda a: ([[a]], [[1.0]], [[1.0]]), {"a": -1.0}, {"a": -3.0})
    >>> lv.names, lv.offset[0].tolist(), lv.deltas[0][0].tolist(), lv.model([0.5])[0].tolist()
    (('a',), [[-1.0]], [[-2.0]], [[-2.0]])

    References
    ----------
    Hallouzi 2008, §3.5, (3.34)–(3.40); §3.6.1, (3.44)–(3.45).
    """

    names: tuple[str, ...]
    offset: Quadruple
    deltas: tuple[Quadruple, ...]
    dt: float | None = None

    def model(self, weights) -> Quadruple:
        """``(A, B, C, D)`` at the given weights (one per name, each in ``[0, 1]``)."""
        mu = np.asarray(weights, float).ravel()
        if mu.shape != (len(self.names),):
            raise DesignError(f"expected {len(self.names)} weights for {self.names}, got shape {mu.shape}")
        if np.any(mu < -1e-12) or np.any(mu > 1 + 1e-12):
            raise DesignError(f"limit-value weights must lie in [0, 1], got {mu.tolist()}")
        return tuple(self.offset[k] + sum(m * delta[k] for m, delta in zip(mu, self.deltas)) for k in range(4))


def limit_value_model_set(matrices: Callable[..., Sequence], upper: Mapping[str, float], lower: Mapping[str, float],
                          dt: float | None = None) -> LimitValueModelSet:
    """Limit-value model set, Hallouzi 2008, §3.5, (3.34)–(3.40), with one weight per parameter.

    ``matrices(**params)`` returns ``(A, B, C)`` or ``(A, B, C, D)``.  The offset is the model with
    every parameter at its ``upper`` ("+") limit; ``M^Δ_j`` is the change when parameter ``j`` alone
    moves to its ``lower`` limit, so ``a = a⁺ + μ a^Δ`` with ``a^Δ = a⁻ − a⁺`` (3.36).  The
    representation is exact when every entry is affine in one (possibly transformed) parameter,
    as in the MSD (``1/m3``); :meth:`LimitValueModelSet.model` then reproduces ``matrices`` for all
    parameter values.  With ``dt`` the blocks are first-order discretised (3.44): ``A⁺ → I + T A⁺``,
    ``A^Δ → T A^Δ``, ``B → T B``.

    Parameters
    ----------
    matrices : callable
        ``matrices(**params) -> (A, B, C)`` or ``(A, B, C, D)``, continuous-time if ``dt`` is given.
    upper, lower : mapping of str to float
        The "+" and "−" limit of every varying parameter (the same names in both).
    dt : float, optional
        Sample time [s] of a first-order discretisation; None keeps the matrices as returned.

    Returns
    -------
    LimitValueModelSet
        The offset model and one change per parameter.

    Raises
    ------
    DesignError
        If ``upper`` and ``lower`` name different parameters.
    ParameterError
        If ``matrices`` is not callable or does not return 3 or 4 numeric arrays.

    Examples
    --------
    >>> lv = limit_value_model_set(lambda k: ([[-k]], [[1.0]], [[1.0]]), {"k": 1.0}, {"k": 3.0}, dt=0.1)
    >>> lv.offset[0].round(6).tolist(), lv.deltas[0][0].round(6).tolist(), lv.dt
    ([[0.9]], [[-0.2]], 0.1)

    References
    ----------
    Hallouzi 2008, §3.5, (3.34)–(3.40); §3.6.1, (3.44).
    """
    if set(upper) != set(lower) or not upper:
        raise DesignError(f"upper and lower limits must name the same parameters, got {sorted(upper)} and "
                          f"{sorted(lower)}")
    names = tuple(upper)
    if not callable(matrices):
        raise ParameterError(f"matrices must be a callable params -> (A, B, C[, D]), got {type(matrices).__name__}")

    def quad(params) -> list[np.ndarray]:
        out = matrices(**params)
        try:
            mats = [np.atleast_2d(np.asarray(M, float)) for M in out]
        except (TypeError, ValueError):
            raise ParameterError(f"matrices(**{params}) must return (A, B, C) or (A, B, C, D) numeric arrays, "
                                 f"got {type(out).__name__}") from None
        if len(mats) not in (3, 4):
            raise ParameterError(f"matrices(**{params}) must return (A, B, C) or (A, B, C, D), got {len(mats)} arrays")
        if len(mats) == 3:
            mats.append(np.zeros((mats[2].shape[0], mats[1].shape[1])))
        return mats

    plus = quad(dict(upper))
    deltas = []
    for name in names:
        q = quad({**upper, name: lower[name]})
        deltas.append([qk - pk for qk, pk in zip(q, plus)])
    if dt is not None:
        Ad, Bd = first_order_discretize(plus[0], plus[1], dt)
        plus = [Ad, Bd, plus[2], plus[3]]
        deltas = [[dt * d[0], dt * d[1], d[2], d[3]] for d in deltas]
    return LimitValueModelSet(names, tuple(plus), tuple(tuple(d) for d in deltas), None if dt is None else float(dt))


# ------------------------------------------------------------------------------------ reconstruction
def nearest_model(models, estimate):
    """Index ``n_s = argmin_i ‖𝔐^{(i)} − M̂‖₂`` of the large-set model nearest an estimate, (3.52).

    ``estimate`` is a model vector (n_q,), e.g. ``M̃_r μ̂`` (OD) or ``U¹ V μ̂`` (CP, (3.51)), or a sequence of
    them (K, n_q); returns an int, or an int array (K,).  The reported parameters are those of model
    ``n_s``, hence quantised to the grid of the large set.

    Parameters
    ----------
    models : array_like
        The large model set ``M_ℓ`` (n_q x N_ℓ).
    estimate : array_like
        One model vector (n_q,) or several (K, n_q).

    Returns
    -------
    int or ndarray of int
        Column index of the nearest model (one per estimate for a 2-D ``estimate``).

    Raises
    ------
    ModelError
        If the estimate's length differs from that of the model vectors.

    Examples
    --------
    >>> M = [[0.0, 1.0, 2.0, 3.0], [1.0, 1.0, 1.0, 1.0]]
    >>> nearest_model(M, [1.2, 1.0]), nearest_model(M, [[1.2, 1.0], [2.9, 1.0]]).tolist()
    (1, [1, 3])

    References
    ----------
    Hallouzi 2008, §3.6.2, (3.51)–(3.52).
    """
    M = as_model_matrix(models)
    E = np.atleast_2d(np.asarray(estimate, float))
    if E.shape[1] != M.shape[0]:
        raise ParameterError(f"the estimate has {E.shape[1]} entries, the model vectors {M.shape[0]}")
    d2 = ((E[:, :, None] - M[None, :, :]) ** 2).sum(axis=1)
    idx = d2.argmin(axis=1)
    return idx if np.ndim(estimate) == 2 else int(idx[0])


def minimum_mismatch_points(distribution, n_models: int) -> np.ndarray:
    """Parameter values of Li et al.'s (2005) "minimum-mismatch" set, Hallouzi 2008, §3.6.4, (3.58).

    The CDF is split into ``n_models`` equiprobable regions; each model sits at the probability
    centre of its region, ``F⁻¹((i − ½)/N)``.  ``distribution`` is a frozen ``scipy.stats``
    distribution (anything with ``ppf``).

    Parameters
    ----------
    distribution : scipy.stats frozen distribution
        Distribution of the parameter (anything with ``ppf``).
    n_models : int
        Number of models, at least 1.

    Returns
    -------
    ndarray
        (n_models,) parameter values, increasing.

    Raises
    ------
    DesignError
        If ``n_models < 1`` or ``distribution`` has no ``ppf``.

    Examples
    --------
    >>> from scipy.stats import norm
    >>> minimum_mismatch_points(norm(1.0, 0.2), 2).round(4).tolist()   # §3.6.4: 0.865 and 1.135
    [0.8651, 1.1349]

    References
    ----------
    Hallouzi 2008, §3.6.4, (3.58), Table 3.4 (after Li et al. 2005).
    """
    if int(n_models) < 1:
        raise DesignError(f"n_models must be >= 1, got {n_models}")
    if not hasattr(distribution, "ppf"):
        raise DesignError("distribution must have a ppf (inverse CDF), e.g. scipy.stats.norm(1.0, 0.2)")
    q = (np.arange(int(n_models)) + 0.5) / int(n_models)
    return np.asarray(distribution.ppf(q), float)


# ------------------------------------------------------------------------------------ observability
def observability_condition(step: Callable[[np.ndarray, np.ndarray], np.ndarray],
                            output: Callable[[np.ndarray], np.ndarray], state, inputs,
                            rel_step: float = 1e-6) -> tuple[float, np.ndarray]:
    """Condition number (3.9) of the nonlinear observability matrix ``∂hⁿ/∂x`` of Def. 3.1, (3.7)–(3.8).

    ``hⁿ(x) = [h(x); h(f(x, u_k)); …; h(f^{n−1}(x))]`` with ``f(x, u) = step(x, u)``, ``h = output``
    and ``u_k … u_{k+n−2}`` the first ``n − 1`` rows of ``inputs``.  The Jacobian is taken by
    central differences (exact for systems quadratic in ``x``, such as the MM system with the
    weights appended to the state, (3.10)).  Returns ``(cond, jacobian)``; ``cond`` is ``inf`` if
    the matrix is rank deficient.

    Parameters
    ----------
    step : callable
        ``step(x, u) -> x_next``, the state transition ``f``.
    output : callable
        ``output(x) -> y``, the measurement ``h``.
    state : array_like
        The point ``x`` (n) where the matrix is evaluated.
    inputs : array_like
        Inputs ``u_k, …`` (at least n − 1 rows).
    rel_step : float, optional
        Relative central-difference step (default 1e-6).

    Returns
    -------
    cond : float
        ``σ_max / σ_min`` of the observability matrix, (3.9); ``inf`` when it is rank deficient.
    jacobian : ndarray
        ``∂hⁿ/∂x`` (n·p x n).

    Raises
    ------
    DesignError
        If fewer than n − 1 input samples are given.

    Examples
    --------
    >>> step = lambda z, u: np.array([z[1] * z[0], z[1]])     # x⁺ = μ x with the weight μ as a state
    >>> cond, J = observability_condition(step, lambda z: z[:1], [1.0, 0.5], np.zeros((1, 1)))
    >>> round(cond, 4), J.round(6).tolist()
    (1.6404, [[1.0, 0.0], [0.5, 1.0]])

    References
    ----------
    Hallouzi 2008, §3.3.1, Definition 3.1, (3.7)–(3.10).
    """
    x0 = np.asarray(state, float).ravel()
    n = x0.size
    U = np.atleast_2d(np.asarray(inputs, float))
    if U.shape[0] < n - 1:
        raise DesignError(f"need n − 1 = {n - 1} input samples, got {U.shape[0]}")

    def stacked(x):
        out = [np.atleast_1d(output(x))]
        for k in range(n - 1):
            x = np.asarray(step(x, U[k]), float)
            out.append(np.atleast_1d(output(x)))
        return np.concatenate(out)

    J = np.empty((stacked(x0).size, n))
    for i in range(n):
        h = rel_step * max(1.0, abs(x0[i]))
        e = np.zeros(n)
        e[i] = h
        J[:, i] = (stacked(x0 + e) - stacked(x0 - e)) / (2 * h)
    sv = np.linalg.svd(J, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 and sv.size >= n else float("inf")
    return cond, J


def pair_observability(first, second, C, states, weights, u) -> float:
    """Mean condition number (3.9) of the observability matrix of a 2-model MM along a state realization.

    The MM is ``x⁺ = μ (A₁x + B₁u) + (1 − μ)(A₂x + B₂u)``, ``y = C x``, with the weight appended to the state as a
    constant (``z = [x; μ]``, one free weight; the thesis does not say how the weights enter (3.8)); ``first``,
    ``second`` are ``(A, B)``;
    ``states`` (K, n) and ``weights`` (K,) are the points ``(x_k, μ_k)`` where the matrix is evaluated; the
    input ``u`` (m,) is held constant over the ``n`` steps of (3.8).  Used for Example 3.1 and Table 3.4.

    Parameters
    ----------
    first, second : tuple of array_like
        ``(A, B)`` of the two models, (n x n) and (n x m).
    C : array_like
        Common output matrix (p x n).
    states : array_like
        (K, n) states ``x_k``.
    weights : array_like
        (K,) weights ``μ_k`` of the first model.
    u : array_like
        (m,) input held constant.

    Returns
    -------
    float
        Mean of the condition numbers over the K points.

    Examples
    --------
    >>> c = pair_observability(([[0.5]], [[1.0]]), ([[0.9]], [[1.0]]), [[1.0]], [[1.0]], [0.5], [0.0])
    >>> round(c, 3)
    3.866

    References
    ----------
    Hallouzi 2008, §3.3.1, Example 3.1, (3.8)–(3.9), Table 3.1; §3.6.4, Table 3.4.
    """
    (A1, B1), (A2, B2) = [(np.asarray(A, float), np.atleast_2d(np.asarray(B, float))) for A, B in (first, second)]
    C = np.atleast_2d(np.asarray(C, float))
    n = A1.shape[0]
    u = np.atleast_1d(np.asarray(u, float))
    B1 = B1.reshape(n, -1)
    B2 = B2.reshape(n, -1)

    def step(z, uk):
        x, m = z[:n], z[n]
        return np.concatenate([m * (A1 @ x + B1 @ uk) + (1 - m) * (A2 @ x + B2 @ uk), z[n:]])

    U = np.tile(u, (n, 1))
    conds = [observability_condition(step, lambda z: C @ z[:n], np.append(x, m), U)[0]
             for x, m in zip(np.asarray(states, float), np.asarray(weights, float))]
    return float(np.mean(conds))

