"""Enclosing polytope of least vertex-to-hull distance (Hallouzi 2008, §3.4, (3.29)–(3.30)), after Kanev (2006).

The CP method asks for ``N_h`` vertices ``v^(j)`` minimising ``J_CP = Σ_j d²(v^(j), conv(M̄))`` subject to
``conv(M̄) ⊆ conv({v^(j)})``.  Kanev's non-convex QCQP is not given in the thesis; this is a documented
substitute that solves the same problem locally.  With the hull points ``H`` of the samples it is the smooth,
bilinearly constrained program

    min_{V, Λ, Β}  Σ_j ‖v_j − H β_j‖²
    s.t.  V Λ = H,  Λ ≥ 0,  1ᵀΛ = 1ᵀ      (every hull point is a convex combination of the vertices, (3.30))
          Β ≥ 0,  1ᵀΒ = 1ᵀ                (H β_j is a point of the hull: min over β_j gives d(v_j, conv H), (3.27))

solved by SLSQP from a feasible start (an enclosing simplex plus extra vertices of zero weight).  The result
is checked by an LP for every sample; if SLSQP does not keep the enclosure the start is returned.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

__all__ = ["fit_enclosing_polytope"]


def centre_local(H: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Nearest hull sample to each vertex (a cheap stand-in for its projection on the hull), d × k."""
    idx = np.argmin(((V[:, :, None] - H[:, None, :]) ** 2).sum(axis=0), axis=1)
    return H[:, idx]


def fit_enclosing_polytope(hull: np.ndarray, start: np.ndarray, n_vertices: int, *, maxiter: int = 500,
                           tol: float = 1e-10) -> tuple[np.ndarray, bool]:
    """Locally minimise ``J_CP`` (3.29) over ``n_vertices`` vertices enclosing the points ``hull`` (d × h).

    ``start`` (d × k, k ≤ n_vertices) must enclose ``hull``; further vertices start at the hull point farthest
    from the centroid with zero weight.  Returns ``(vertices, converged)``, the vertices d × n_vertices.
    """
    H = np.asarray(hull, dtype=float)
    d, h = H.shape
    V0 = np.asarray(start, dtype=float)
    k0 = V0.shape[1]
    if n_vertices < k0:
        raise ValueError(f"n_vertices ({n_vertices}) must be at least the start's {k0} vertices")
    centre = H.mean(axis=1, keepdims=True)
    scale = float(np.abs(H - centre).max()) or 1.0
    Hs, Vs = (H - centre) / scale, (V0 - centre) / scale
    lam0 = np.linalg.lstsq(np.vstack([Vs, np.ones(k0)]), np.vstack([Hs, np.ones(h)]), rcond=None)[0]
    lam0 = np.clip(lam0, 0.0, None)
    lam0 /= lam0.sum(axis=0, keepdims=True)
    # extra vertices: copies of the start vertices farthest from the hull, each copy taking the share of the
    # hull points on its side (split by the hull's principal direction), so that SLSQP can pull them apart
    V, lam = Vs.copy(), lam0.copy()
    dist = np.linalg.norm(Vs - centre_local(Hs, Vs), axis=0)
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
