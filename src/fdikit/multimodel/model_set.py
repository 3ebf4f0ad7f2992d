"""Model vectors of a large model set and the helpers every model-set design shares: Hallouzi 2008, Ch. 3 and App. B.

A local model ``{A, B, C, D}`` is the vector ``𝔐 = vec([A B; C D])`` (3.14); a large model set is
the matrix ``M_ℓ`` of such columns (3.15).  Three designs reduce it to a few local models:

* :func:`~fdikit.multimodel.od_design.od_model_set` — orthogonal decomposition, §3.3.2, (3.19)–(3.23) (module
  :mod:`fdikit.multimodel.od_design`).
* :func:`~fdikit.multimodel.cp_design.cp_model_set` — an enclosing convex polytope in SVD coordinates, §3.4,
  (3.31)–(3.33) (module :mod:`fdikit.multimodel.cp_design`).
* :func:`~fdikit.multimodel.lv_design.limit_value_model_set` — limit values of the varying entries, §3.5,
  (3.34)–(3.40) (module :mod:`fdikit.multimodel.lv_design`).

This module holds what they share: :func:`vectorize` / :func:`unvectorize` (3.14), (3.24),
:func:`first_order_discretize` and :func:`taylor_remainder_bound` (App. B), :func:`gap_rank` (§3.3.2),
:func:`affine_weights` (3.21) and :func:`nearest_model` (3.51)–(3.52).  The observability comparison of model sets
(Def. 3.1, §3.6.4) is in :mod:`fdikit.multimodel.observability`.
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import DesignError, ModelError, ParameterError

__all__ = [
    "vectorize",
    "unvectorize",
    "first_order_discretize",
    "taylor_remainder_bound",
    "gap_rank",
    "affine_weights",
    "nearest_model",
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
