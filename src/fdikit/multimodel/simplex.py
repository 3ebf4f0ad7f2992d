"""Projection of convex-model weights on the simplex (Hallouzi 2008, (2.37)–(2.38)).

The constrained weight ``μ^c = argmin (μ^c − μ̂)ᵀ W (μ^c − μ̂)`` subject to ``1ᵀμ^c = 1`` and ``μ^c ≥ 0``
(Simon & Chia 2002 for the equality, Simon & Simon 2006 for the inequalities, as §2.3.2 cites).  The
thesis chooses ``W = I``; Simon & Chia show that ``W = P⁻¹``, the inverse error covariance of the
unconstrained estimate, gives the minimum-variance constrained estimate.  For the dual CMF's RLS weight
step that is ``W = T_kᵀ T_k`` (the information matrix), and it matters when the weight regressors are
strongly correlated: with ``W = I`` an error in the well-determined sum ``1ᵀμ̂`` is spread evenly over
the weights instead of along the poorly determined directions (see
:func:`fdikit.multimodel.convex_filter.dual_convex_filter`).
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import DataError, ParameterError

__all__ = ["project_to_simplex", "project_to_simplex_weighted", "project_to_affine", "constrain_weights"]


def project_to_simplex(mu, ordering: str = "michelot") -> np.ndarray:
    """Project weights on ``{μ ≥ 0, 1ᵀμ = 1}`` (Hallouzi 2008, (2.37)–(2.38), W = I).

    Equality projection ``μ^c = μ̂ − 1(1ᵀμ̂ − 1)/N`` then an active-set loop fixing negative weights at 0.
    ``ordering="michelot"`` (default) checks the signs *after* each equality projection (Michelot 1986): the
    result is the Euclidean projection on the simplex.  ``"thesis"`` first zeroes the negatives of the
    unconstrained μ̂, as §2.3.2 words it; it can differ when ``1ᵀμ̂ < 1`` (``tests/multimodel/test_convex.py``
    shows a case).

    Parameters
    ----------
    mu : array_like
        Unconstrained weights μ̂ (N), finite.
    ordering : {"michelot", "thesis"}
        When the negative weights are fixed at 0 (see above); default ``"michelot"``.

    Returns
    -------
    ndarray
        Constrained weights ``μ^c`` (N), non-negative and summing to 1.

    Raises
    ------
    ParameterError
        On an unknown ``ordering``.
    DataError
        If ``mu`` is empty or not finite.

    Examples
    --------
    >>> project_to_simplex([0.9, 0.5, -0.2]).round(3).tolist()
    [0.7, 0.3, 0.0]

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.37)–(2.38) and the inequality step that follows them.
    """
    if ordering not in ("michelot", "thesis"):
        raise ParameterError(f"ordering must be 'michelot' or 'thesis', got {ordering!r}")
    y = _weights(mu)
    free = np.ones(y.size, dtype=bool)
    if ordering == "thesis":
        free &= y >= 0
        if not free.any():
            free[:] = True
    while True:
        out = np.zeros_like(y)
        out[free] = y[free] - (y[free].sum() - 1.0) / free.sum()
        neg = free & (out < 0)
        if not neg.any():
            return out
        free &= ~neg


def project_to_simplex_weighted(mu, W, ridge: float = 1e-9) -> np.ndarray:
    """``argmin (m − μ)ᵀ W (m − μ)`` over the simplex, for a symmetric ``W ⪰ 0`` (Hallouzi 2008, (2.37)).

    Primal active-set method (Nocedal & Wright 2006, Alg. 16.3), started from the Euclidean projection:
    the equality-constrained problem (2.38) is solved on the free weights with the others fixed at 0 (the
    added equalities ``μ^(i) = 0`` of §2.3.2); a step toward it stops at the first weight that reaches 0,
    and a fixed weight is released when its KKT multiplier is negative.  A singular ``W`` (weights the data
    do not determine) is regularised by ``ridge · tr(W)/N · I``, so the projection moves along the
    undetermined directions first.  With ``W = I`` this is the Euclidean projection.

    Parameters
    ----------
    mu : array_like
        Unconstrained weights μ̂ (N), finite.
    W : array_like
        Symmetric positive semidefinite metric (N x N), e.g. the RLS information ``TᵀT``.
    ridge : float, optional
        Relative regularisation of a singular ``W`` (default 1e-9).

    Returns
    -------
    ndarray
        Constrained weights (N), non-negative and summing to 1.

    Raises
    ------
    ParameterError
        If ``W`` is not a finite N x N matrix, or the active-set loop does not converge (``W`` not PSD).
    DataError
        If ``mu`` is empty or not finite.

    Examples
    --------
    >>> W = np.array([[1.0, 0.0], [0.0, 100.0]])   # the second weight is 100x better determined
    >>> project_to_simplex_weighted([0.6, 0.6], W).round(4).tolist()
    [0.402, 0.598]

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.37)–(2.38) with a general W.
    """
    y = _weights(mu)
    N = y.size
    W = _metric(W, N, ridge)
    m = project_to_simplex(y)
    free = m > 0
    for _ in range(10 * N + 10):
        target, nu = _equality_projection(y, W, free)
        step = target - m
        if np.abs(step).max() <= 1e-14:
            # KKT: 2W(m − y) + ν1 − λ = 0 with λ ≥ 0 on the weights held at 0
            lam = 2.0 * W @ (m - y) + nu
            release = ~free & (lam < -1e-12 * max(1.0, np.abs(lam).max()))
            if not release.any():
                return m
            free[np.argmin(np.where(release, lam, np.inf))] = True
            continue
        shrinking = free & (step < 0)
        ratios = np.where(shrinking, -m / np.where(shrinking, step, -1.0), np.inf)
        alpha = min(1.0, ratios.min())
        m = np.maximum(m + alpha * step, 0.0)
        if alpha < 1.0:
            block = int(np.argmin(ratios))
            m[block], free[block] = 0.0, False
    raise ParameterError("the weighted simplex projection did not converge; check that W is positive semidefinite")


def project_to_affine(mu, W=None, ridge: float = 1e-9) -> np.ndarray:
    """The equality projection (2.38) alone: ``argmin (m − μ)ᵀ W (m − μ)`` subject to ``1ᵀm = 1``.

    For model sets that represent the large set *affinely*, such as the OD sets of (3.21), whose weights
    may be negative.  ``W`` defaults to ``I``: ``m = μ − 1 (1ᵀμ − 1)/N``.

    Parameters
    ----------
    mu : array_like
        Unconstrained weights (N), finite.
    W : array_like, optional
        Symmetric PSD metric (N x N); the identity if omitted.
    ridge : float, optional
        Relative regularisation of a singular ``W`` (default 1e-9).

    Returns
    -------
    ndarray
        Weights (N) summing to 1 (possibly negative).

    Examples
    --------
    >>> project_to_affine([0.9, 0.5, -0.2]).round(4).tolist()
    [0.8333, 0.4333, -0.2667]

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.38); §3.3.2, (3.21) (the affine OD sets).
    """
    y = _weights(mu)
    N = y.size
    W = _metric(np.eye(N) if W is None else W, N, ridge)
    return _equality_projection(y, W, np.ones(N, dtype=bool))[0]


def _equality_projection(y: np.ndarray, W: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, float]:
    """(2.38) on the free weights, the others fixed at 0: ``min (m − y)ᵀW(m − y)``, ``1ᵀm = 1``."""
    idx = np.flatnonzero(free)
    fixed = np.flatnonzero(~free)
    Wff = W[np.ix_(idx, idx)]
    # stationarity on the free block: 2 Wff (m_f − y_f) − 2 Wfz y_z + ν 1 = 0
    rhs = Wff @ y[idx] + W[np.ix_(idx, fixed)] @ y[fixed]
    a = np.linalg.solve(Wff, rhs)
    b = np.linalg.solve(Wff, np.ones(idx.size))
    half_nu = (a.sum() - 1.0) / b.sum()
    m = np.zeros_like(y)
    m[idx] = a - half_nu * b
    return m, 2.0 * half_nu


def _metric(W, N: int, ridge: float) -> np.ndarray:
    """Symmetrised ``W`` plus ``ridge · tr(W)/N · I`` (so a singular information matrix still has an inverse)."""
    W = np.asarray(W, dtype=float)
    if W.shape != (N, N) or not np.all(np.isfinite(W)):
        raise ParameterError(f"the projection metric W must be a finite {N} x {N} matrix, got shape {W.shape}")
    W = 0.5 * (W + W.T)
    return W + ridge * max(np.trace(W) / N, np.finfo(float).tiny) * np.eye(N)


def _weights(mu) -> np.ndarray:
    y = np.asarray(mu, dtype=float).ravel()
    if y.size == 0 or not np.all(np.isfinite(y)):
        raise DataError("weights to project must be a non-empty finite vector")
    return y


def constrain_weights(mu, constrain, W=None, ordering: str = "michelot") -> np.ndarray:
    """Apply a weight constraint of the convex-model filters (Hallouzi 2008, §2.3.2, (2.37)–(2.38)).

    ``constrain``: ``True`` or ``"simplex"`` (μ ≥ 0, 1ᵀμ = 1; with ``W`` the weighted projection, else the
    Euclidean one with the given ``ordering``), ``"affine"`` (1ᵀμ = 1 only, for OD sets), ``"box"``
    (each μ_j clipped to [0, 1], for limit-value sets, (3.39)) or ``False`` (unchanged).

    Parameters
    ----------
    mu : array_like
        Unconstrained weights (N), finite.
    constrain : bool or {"simplex", "affine", "box"}
        The constraint, as above.
    W : array_like, optional
        Projection metric (N x N) for ``"simplex"``/``"affine"``; the identity if omitted.
    ordering : {"michelot", "thesis"}
        Ordering of the Euclidean simplex projection (:func:`project_to_simplex`).

    Returns
    -------
    ndarray
        Constrained weights (N).

    Raises
    ------
    ParameterError
        On an unknown ``constrain`` (or as the projections).

    Examples
    --------
    >>> constrain_weights([1.2, -0.1], "box").tolist(), constrain_weights([0.7, 0.5], "affine").tolist()
    ([1.0, 0.0], [0.6, 0.4])

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.37)–(2.38); §3.5, (3.39)–(3.40) (weights in [0, 1]).
    """
    if constrain is False:
        return _weights(mu)
    if constrain is True or constrain == "simplex":
        return project_to_simplex(mu, ordering) if W is None else project_to_simplex_weighted(mu, W)
    if constrain == "affine":
        return project_to_affine(mu, W)
    if constrain == "box":
        return np.clip(_weights(mu), 0.0, 1.0)
    raise ParameterError(f"constrain must be True/'simplex', 'affine', 'box' or False, got {constrain!r}")
