"""CP model-set design: an enclosing convex polytope (Hallouzi 2008, §3.4, (3.25)–(3.33)), after Kanev (2006).

:func:`cp_model_set` reduces the large model set to its SVD coordinates (3.31)–(3.32) and encloses them with a
polytope whose vertices become the local models (3.33).  The thesis minimises ``J_CP = Σ_j d²(v^(j), conv(M̄))``
(3.29) subject to ``conv(M̄) ⊆ conv({v^(j)})`` (3.30) with Kanev's non-convex QCQP, which it does not give.  The
substitute here starts from a feasible enclosing simplex and solves the same problem locally as the smooth,
bilinearly constrained program (:func:`fit_enclosing_polytope`, with the hull points ``H`` of the samples)

    min_{V, Λ, Β}  Σ_j ‖v_j − H β_j‖²
    s.t.  V Λ = H,  Λ ≥ 0,  1ᵀΛ = 1ᵀ      (every hull point is a convex combination of the vertices, (3.30))
          Β ≥ 0,  1ᵀΒ = 1ᵀ                (H β_j is a point of the hull: min over β_j gives d(v_j, conv H), (3.27))

by SLSQP.  The enclosure of every sample is rechecked (LP: :func:`convex_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.spatial

from fdikit import validate
from fdikit.errors import DesignError
from fdikit.multimodel.model_set import as_model_matrix, gap_rank

__all__ = ["CPModelSet", "cp_model_set", "convex_weights", "fit_enclosing_polytope"]


@dataclass(frozen=True)
class CPModelSet:
    """Result of :func:`cp_model_set` (Hallouzi 2008, §3.4).

    Attributes
    ----------
    basis : numpy.ndarray
        ``U¹`` of (3.31), ``n_q × n_g``.
    coordinates : numpy.ndarray
        ``M̄_ℓ = Σ¹ V¹ᵀ`` (3.32), ``n_g × N_ℓ``.
    vertices : numpy.ndarray
        Polytope vertices ``v^{(i)}`` in reduced coordinates, ``n_g × N_h``.
    models : numpy.ndarray
        Model vectors ``U¹ v^{(i)}`` (3.33), ``n_q × N_h``.
    weights : numpy.ndarray
        Convex (barycentric) weights of every large-set model, ``N_h × N_ℓ``.
    cost : float
        ``J_CP = Σ d²(v, conv(M̄_ℓ))`` (3.29) of the vertices.

    Examples
    --------
    >>> M = np.array([[0.0, 1.0, 0.0, 0.3], [0.0, 0.0, 1.0, 0.3], [1.0, 1.0, 1.0, 1.0]])
    >>> cp = cp_model_set(M)                  # a triangle of models and one point inside it
    >>> cp.basis.shape, cp.models.shape, cp.weights.shape, round(cp.cost, 6)
    ((3, 3), (3, 3), (3, 4), 0.0)

    References
    ----------
    Hallouzi 2008, §3.4, (3.25)–(3.33).
    """

    basis: np.ndarray
    coordinates: np.ndarray
    vertices: np.ndarray
    models: np.ndarray
    weights: np.ndarray
    cost: float


def convex_weights(vertices, point) -> np.ndarray | None:
    """Weights ``λ ≥ 0, Σλ = 1`` with ``V λ = x`` by a linear program, or ``None`` if ``x ∉ conv(V)``.

    Used to check polytope enclosure (Hallouzi 2008, (3.30)); solved with ``scipy.optimize.linprog``
    (HiGHS), minimising the ℓ1 equality violation with a tolerance of ``1e-9 · scale``.

    Parameters
    ----------
    vertices : array_like
        ``V`` (d x k), one vertex per column.
    point : array_like
        ``x`` (d).

    Returns
    -------
    ndarray or None
        The weights ``λ`` (k), or None when ``x`` is outside the polytope.

    Examples
    --------
    >>> V = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    >>> convex_weights(V, [0.25, 0.25]).round(6).tolist(), convex_weights(V, [1.0, 1.0])
    ([0.5, 0.25, 0.25], None)

    References
    ----------
    Hallouzi 2008, §3.4, (3.30).
    """
    V = np.atleast_2d(np.asarray(vertices, float))
    x = np.asarray(point, float).ravel()
    d, k = V.shape
    # variables λ (k), slack s+ (d), s- (d): V λ + s+ − s- = x, Σλ = 1, minimise Σ s
    A_eq = np.block([[V, np.eye(d), -np.eye(d)], [np.ones((1, k)), np.zeros((1, 2 * d))]])
    b_eq = np.concatenate([x, [1.0]])
    c = np.concatenate([np.zeros(k), np.ones(2 * d)])
    res = scipy.optimize.linprog(c, A_eq=A_eq, b_eq=b_eq, bounds=(0, None), method="highs")
    scale = max(1.0, float(np.abs(V).max()), float(np.abs(x).max()))
    if res.status != 0 or res.fun > 1e-9 * scale:
        return None
    return res.x[:k]


def _barycentric(V: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of the columns of ``X`` (d × K) in the simplex ``V`` (d × (d+1))."""
    return np.linalg.solve(np.vstack([V, np.ones(V.shape[1])]), np.vstack([X, np.ones(X.shape[1])]))


def _nnls_convex_weights(V: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, float]:
    """Convex weights ``W ≥ 0``, ``1ᵀW = 1ᵀ`` with ``V W ≈ X`` by NNLS (sum row weighted 1e6); worst residual."""
    scale = 1e6 * max(1.0, float(np.abs(V).max()))
    Aa = np.vstack([V, np.full((1, V.shape[1]), scale)])
    W = np.empty((V.shape[1], X.shape[1]))
    for j in range(X.shape[1]):
        W[:, j] = scipy.optimize.nnls(Aa, np.concatenate([X[:, j], [scale]]))[0]
    W /= W.sum(axis=0, keepdims=True)
    return W, float(np.abs(V @ W - X).max())


def _distance_to_hull(points: np.ndarray, v: np.ndarray) -> float:
    """``d(v, conv(points))`` (3.27)–(3.28) by a small simplex-constrained least squares (SLSQP)."""
    k = points.shape[1]
    res = scipy.optimize.minimize(lambda lam: float(np.sum((points @ lam - v) ** 2)), np.full(k, 1.0 / k),
                                  jac=lambda lam: 2 * points.T @ (points @ lam - v), method="SLSQP",
                                  bounds=[(0, 1)] * k, constraints=[{"type": "eq", "fun": lambda lam: lam.sum() - 1}])
    return float(np.sqrt(max(res.fun, 0.0)))


def cp_model_set(models, rank: int | None = None, min_gap: float = 10.0, n_vertices: int | None = None,
                 optimize: bool = True) -> CPModelSet:
    """Enclosing-simplex model-set design, a substitute for Kanev's optimiser in Hallouzi 2008, §3.4.

    Steps (3.31)–(3.33) as in the thesis: SVD ``M_ℓ = U Σ Vᵀ``, ``n_g`` from the singular-value gap
    (or ``rank``), reduced coordinates ``M̄_ℓ = Σ¹V¹ᵀ``; vertices mapped back by ``U¹ v``.

    The thesis minimises ``J_CP`` (3.29) subject to enclosure (3.30) with Kanev's (2006) non-convex
    QCQP, which it does not give.  Substitute (an fdikit construction, not from the thesis): work in the affine hull of
    ``M̄_ℓ`` (dimension ``d``; models that contain constant entries such as ``I + T A`` lie in a proper
    affine subspace, ``d = n_g − 1``), pick ``d + 1`` well-separated samples by pivoted QR of the
    homogeneous coordinates ``[M̄; 1]``, and replace this base simplex by the tightest simplex with
    facets parallel to it that contains every sample: with barycentric coordinates ``λ`` and
    ``a_j = min λ_j ≤ 0`` the new vertex ``j`` has ``λ_k = a_k`` (k ≠ j), ``λ_j = 1 − Σ_{k≠j} a_k``.
    Every facet touches a sample, every sample is inside (check: :func:`convex_weights`), and
    ``N_h = d + 1`` vertices (the thesis's ``N_h ≥ n_g + 1`` counts the linear rank).

    With ``optimize`` (default) this simplex is the feasible start of a local minimisation of ``J_CP`` over
    ``n_vertices`` vertices (default ``d + 1``) subject to the enclosure (3.30)
    (:func:`fit_enclosing_polytope`); the weights of the samples are then barycentric (a simplex) or
    non-negative least squares (more vertices).  If the optimiser loses the enclosure, the simplex is returned
    (with more than ``d + 1`` vertices requested: :class:`~fdikit.errors.DesignError`).

    Parameters
    ----------
    models : array_like
        The large model set ``M_ℓ`` (n_q x N_ℓ), one model vector per column
        (:func:`~fdikit.multimodel.model_set.vectorize`).
    rank : int, optional
        ``n_g``; default from the singular-value gap.
    min_gap : float, optional
        Smallest ratio counted as a significant gap (default 10; :func:`~fdikit.multimodel.model_set.gap_rank`).
    n_vertices : int, optional
        Number of vertices ``N_h`` (at least ``d + 1``; default ``d + 1``, a simplex).
    optimize : bool, optional
        Locally minimise ``J_CP`` from the enclosing simplex (default True).

    Returns
    -------
    CPModelSet
        Basis, coordinates, vertices, local models ``U¹ v^(i)``, weights of every sample and ``J_CP``.

    Raises
    ------
    DesignError
        If the samples are affinely degenerate (fewer than two distinct models), ``n_vertices < d + 1``, or a
        fit with more than ``d + 1`` vertices loses the enclosure.
    ParameterError
        On a non-positive ``min_gap`` or a ``rank``/``n_vertices`` that is not a positive integer.

    Examples
    --------
    >>> M = np.array([[0.0, 1.0, 0.0, 0.3], [0.0, 0.0, 1.0, 0.3], [1.0, 1.0, 1.0, 1.0]])
    >>> cp = cp_model_set(M, optimize=False)
    >>> cp.models.shape, all(convex_weights(cp.models, m) is not None for m in M.T)
    ((3, 3), True)

    References
    ----------
    Hallouzi 2008, §3.4, (3.29)–(3.33) (after Kanev 2006).
    """
    min_gap = validate.positive("min_gap", min_gap)
    if rank is not None:
        rank = validate.integer("rank", rank, minimum=1)
    if n_vertices is not None:
        n_vertices = validate.integer("n_vertices", n_vertices, minimum=1)
    M = as_model_matrix(models)
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    n_g = gap_rank(s, min_gap) if rank is None else int(rank)
    basis = U[:, :n_g]
    coords = s[:n_g, None] * Vt[:n_g]
    centre = coords.mean(axis=1, keepdims=True)
    Ua, sa, _ = np.linalg.svd(coords - centre, full_matrices=False)
    d = gap_rank(sa, min_gap)
    if d < 1:
        raise DesignError("the large model set has fewer than two distinct models; nothing to enclose")
    local = Ua[:, :d].T @ (coords - centre)  # d × N_ℓ coordinates in the affine hull
    _, _, piv = scipy.linalg.qr(np.vstack([local, np.ones(local.shape[1])]), mode="economic", pivoting=True)
    base = local[:, piv[: d + 1]]
    lam = _barycentric(base, local)  # (d+1) × N_ℓ
    a = np.minimum(lam.min(axis=1), 0.0)
    bary = np.tile(a[:, None], (1, d + 1))
    np.fill_diagonal(bary, 1.0 - (a.sum() - a))
    vertices_local = base @ bary
    vertices = centre + Ua[:, :d] @ vertices_local
    weights = (lam - a[:, None]) / (1.0 - a.sum())
    hull_points = local
    if 1 < d <= 8 and local.shape[1] > d + 1:
        try:
            hull_points = local[:, scipy.spatial.ConvexHull(local.T).vertices]
        except scipy.spatial.QhullError:  # pragma: no cover - degenerate hull, fall back to all samples
            hull_points = local
    n_h = d + 1 if n_vertices is None else int(n_vertices)
    if n_h < d + 1:
        raise DesignError(f"n_vertices must be at least d + 1 = {d + 1} to enclose a {d}-dimensional set, "
                          f"got {n_h}")
    if optimize or n_h > d + 1:
        V_opt, ok = fit_enclosing_polytope(hull_points, vertices_local, n_h)
        if n_h == d + 1:  # a simplex: barycentric coordinates, exact
            w_opt = _barycentric(V_opt, local)
            resid = max(0.0, -float(w_opt.min()))
            w_opt = np.clip(w_opt, 0.0, None)
        else:
            w_opt, resid = _nnls_convex_weights(V_opt, local)
        if ok and resid <= 1e-8 * max(1.0, float(np.abs(local).max())):
            vertices_local, weights = V_opt, w_opt
            vertices = centre + Ua[:, :d] @ vertices_local
        elif n_h > d + 1:
            raise DesignError(f"the polytope fit with {n_h} vertices lost the enclosure; try fewer vertices")
    cost = float(sum(_distance_to_hull(hull_points, vertices_local[:, j]) ** 2 for j in range(vertices_local.shape[1])))
    return CPModelSet(basis, coords, vertices, basis @ vertices, weights, cost)


# ------------------------------------------------------------------------------------ J_CP fit
def _nearest_hull_point(H: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Nearest hull sample to each vertex (a cheap stand-in for its projection on the hull), d × k."""
    idx = np.argmin(((V[:, :, None] - H[:, None, :]) ** 2).sum(axis=0), axis=1)
    return H[:, idx]


def fit_enclosing_polytope(hull: np.ndarray, start: np.ndarray, n_vertices: int, *, maxiter: int = 500,
                           tol: float = 1e-10) -> tuple[np.ndarray, bool]:
    """Locally minimise ``J_CP`` (3.29) over ``n_vertices`` vertices enclosing the points ``hull`` (d × h).

    ``start`` (d × k, k ≤ n_vertices) must enclose ``hull``; further vertices start as copies of the start
    vertices farthest from the hull, each taking the hull points on one side of the hull's principal direction.
    Returns ``(vertices, converged)``, the vertices d × n_vertices.

    Parameters
    ----------
    hull : ndarray
        Points to enclose (d x h), e.g. the convex-hull vertices of the samples.
    start : ndarray
        Enclosing start vertices (d x k), k ≤ ``n_vertices``.
    n_vertices : int
        Number of vertices of the result.
    maxiter : int, optional
        SLSQP iteration limit (default 500).
    tol : float, optional
        SLSQP ``ftol`` (default 1e-10).

    Returns
    -------
    vertices : ndarray
        (d x n_vertices).
    converged : bool
        Whether SLSQP converged with the enclosure constraints met to 1e-7.

    Raises
    ------
    DesignError
        If ``n_vertices`` is smaller than the number of start vertices.

    Examples
    --------
    >>> V, ok = fit_enclosing_polytope(np.array([[0.0, 1.0, 2.0]]), np.array([[-1.0, 3.0]]), 2)
    >>> (V.round(4) + 0.0).tolist(), ok     # the interval [0, 2] itself
    ([[0.0, 2.0]], True)

    References
    ----------
    Hallouzi 2008, §3.4, (3.27)–(3.30).
    """
    H = np.asarray(hull, dtype=float)
    d, h = H.shape
    V0 = np.asarray(start, dtype=float)
    k0 = V0.shape[1]
    if n_vertices < k0:
        raise DesignError(f"n_vertices ({n_vertices}) must be at least the {k0} vertices of the start polytope")
    centre = H.mean(axis=1, keepdims=True)
    scale = float(np.abs(H - centre).max()) or 1.0
    Hs, Vs = (H - centre) / scale, (V0 - centre) / scale
    lam0 = np.linalg.lstsq(np.vstack([Vs, np.ones(k0)]), np.vstack([Hs, np.ones(h)]), rcond=None)[0]
    lam0 = np.clip(lam0, 0.0, None)
    lam0 /= lam0.sum(axis=0, keepdims=True)
    # extra vertices: copies of the start vertices farthest from the hull, each copy taking the share of the
    # hull points on its side (split by the hull's principal direction), so that SLSQP can pull them apart
    V, lam = Vs.copy(), lam0.copy()
    dist = np.linalg.norm(Vs - _nearest_hull_point(Hs, Vs), axis=0)
    axis = np.linalg.svd(Hs, full_matrices=False)[0][:, 0]
    side = (axis @ Hs > np.median(axis @ Hs)).astype(float)
    for j in np.argsort(-dist)[: n_vertices - k0] if n_vertices > k0 else []:
        V = np.hstack([V, Vs[:, [j]]])
        moved = lam[j] * side
        lam[j] -= moved
        lam = np.vstack([lam, moved])
    while V.shape[1] < n_vertices:  # more extras than start vertices: zero-weight copies of the first
        V, lam = np.hstack([V, V[:, :1]]), np.vstack([lam, np.zeros(h)])
    beta = np.full((h, n_vertices), 1.0 / h)
    nv, nl = d * n_vertices, n_vertices * h

    def unpack(z):
        return z[:nv].reshape(d, n_vertices), z[nv:nv + nl].reshape(n_vertices, h), z[nv + nl:].reshape(h, n_vertices)

    def cost(z):
        V, _, B = unpack(z)
        r = V - Hs @ B
        return float(np.sum(r * r))

    def grad(z):
        V, _, B = unpack(z)
        r = V - Hs @ B
        return np.concatenate([2 * r.ravel(), np.zeros(nl), (-2 * Hs.T @ r).ravel()])

    def eq(z):
        V, L, B = unpack(z)
        return np.concatenate([(V @ L - Hs).ravel(), L.sum(axis=0) - 1.0, B.sum(axis=0) - 1.0])

    def eq_jac(z):
        V, L, _ = unpack(z)
        J = np.zeros((d * h + h + n_vertices, z.size))
        for a in range(d):  # rows (a, c) of V L − H, row-major like ravel()
            for c in range(h):
                row = a * h + c
                J[row, a * n_vertices:(a + 1) * n_vertices] = L[:, c]
                J[row, nv + np.arange(n_vertices) * h + c] = V[a]
        for c in range(h):
            J[d * h + c, nv + np.arange(n_vertices) * h + c] = 1.0
        for j in range(n_vertices):
            J[d * h + h + j, nv + nl + np.arange(h) * n_vertices + j] = 1.0
        return J

    z0 = np.concatenate([V.ravel(), lam.ravel(), beta.ravel()])
    bounds = [(None, None)] * nv + [(0.0, 1.0)] * (nl + h * n_vertices)
    res = scipy.optimize.minimize(cost, z0, jac=grad, method="SLSQP", bounds=bounds,
                                  constraints=[{"type": "eq", "fun": eq, "jac": eq_jac}],
                                  options={"maxiter": maxiter, "ftol": tol})
    V_opt = unpack(res.x)[0] * scale + centre
    return V_opt, bool(res.success and np.abs(eq(res.x)).max() < 1e-7)
