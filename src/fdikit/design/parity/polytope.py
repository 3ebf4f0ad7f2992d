"""Polytopic machinery of the robust LPV parity design (Varrier et al. 2014, §4.5–4.6, (32)–(46)).

The pointwise optimum of 𝒫₂ involves ``Γ_κ(ρ)⁻¹ = adj Γ_κ(ρ) / det Γ_κ(ρ)``
(:mod:`fdikit.design.parity.criteria`); this module holds the steps that turn it into a
finite set of vertex LMIs:

* (32)–(36): ``adj Γ_κ(ρ) = Σ_j t^j M_j`` is a matrix polynomial (``t = (ρ − ρ_min)/(ρ_max − ρ_min)``),
  computed exactly by FFT on the unit circle in ``t`` (:func:`adjugate`,
  :func:`polynomial_coefficients`).
* §4.6.2, Property 1 (46): treating ``t, t², …, t^N`` as parameters, only the ``N+1`` vertices
  ``ω_j = (1, …, 1, 0, …, 0)`` (j ones) of the ``2^N`` box (:func:`box_vertices`) are needed
  (:func:`property1_vertices`, :func:`is_admissible`) — (46) as printed takes coordinates in
  ``{0, ρ_max}``; the coordinate of ``ρ^j`` must be in ``{0, ρ_max^j}``.  The weights (derived
  here; not in the paper) are ``α̃₀ = 1 − t``, ``α̃_j = t^j − t^{j+1}``, ``α̃_N = t^N``
  (:func:`scheduling_weights`), and the vertex matrices are the prefix sums
  ``Γ̃_j = Σ_{i≤j} M_i``, so that ``Σ α̃_j Γ̃_j`` equals the adjugate truncated at degree N exactly.
* (37)–(40): the LMI (39) per vertex with the common normalisation ``cᵀW_j = 1``
  (:func:`polytopic_lmi`) makes ``cᵀW₂(ρ) = 1`` for every ρ (per-vertex ``‖W_j‖₁ ≥ ε`` would
  not prevent ``Σ α̃_j W_j = 0``).
* Remark 6, (41)–(42): non-PD vertices have their negative eigenvalues replaced
  (:func:`repair_vertex`).  ``repair="paper"`` uses ``factor × max positive eigenvalue`` (as
  printed, "large"); ``repair="inverse"`` (default) uses ``min positive eigenvalue / factor``,
  large in ``Γ̃⁻¹`` as Remark 7 asks ("lowest eigenvalue of the inverse"): the LMI minimises
  ``W_jᵀ Γ̌_j⁻¹ W_j``, so directions made large in ``Γ̌_j`` would attract the optimum.  Any
  positive replacement gives ``Γ̌_j ⪰ Γ̃_j``, so after a repair the vertex LMIs no longer certify
  the bound at the physical ρ; :meth:`~fdikit.design.parity.robust.RobustParityDesign.criterion`
  reports the attained ``J(ρ)``.

The design that chains these steps is :func:`fdikit.design.parity.robust.robust_lpv_parity`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from itertools import product

import numpy as np

from fdikit.errors import DesignError, ParameterError

__all__ = [
    "adjugate", "polynomial_coefficients", "box_vertices", "is_admissible", "property1_vertices",
    "scheduling_weights", "repair_vertex", "PolytopicLmi", "polytopic_lmi",
]


# ---------------------------------------------------------------------------------------------- LMI helpers
def solver_options(solver: str) -> dict:
    """Tight tolerances: the vertex LMIs are badly scaled (adjugate entries span ~1e7)."""
    return {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10} if solver == "CLARABEL" else {}


def lmi_block(Ginv_scaled: np.ndarray, w: np.ndarray, g: float) -> np.ndarray:
    """The Schur block ``[[M, w], [wᵀ, g]]`` of the LMIs (27) and (39), for checking a returned solution."""
    return np.block([[Ginv_scaled, w[:, None]], [w[None, :], np.array([[g]])]])


# ---------------------------------------------------------------------------------------------- polytope
def adjugate(M: np.ndarray) -> np.ndarray:
    """Adjugate (transposed cofactor matrix) of square matrices, batch axes allowed, real or complex.

    Parameters
    ----------
    M : (..., q, q) array_like
        Square matrices.

    Returns
    -------
    (..., q, q) array
        ``adj M`` (``M adj M = det M · I``); ones for ``q = 1``.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(adjugate(np.array([[1.0, 2.0], [3.0, 4.0]])), 6).tolist()
    [[4.0, -2.0], [-3.0, 1.0]]

    References
    ----------
    Varrier et al. 2014, §4.5, (32)–(33).
    """
    M = np.asarray(M)
    q = M.shape[-1]
    out = np.empty_like(M)
    if q == 1:
        return np.ones_like(M)
    for i in range(q):
        for j in range(q):
            minor = np.delete(np.delete(M, i, axis=-2), j, axis=-1)
            out[..., j, i] = (-1) ** (i + j) * np.linalg.det(minor)
    return out


def polynomial_coefficients(fun: Callable[[np.ndarray], np.ndarray], rho_min: float, rho_max: float, *,
                            points: int = 64, rtol: float = 1e-8) -> tuple[np.ndarray, int]:
    """Coefficients ``M_j`` of ``fun(ρ) = Σ_j t^j M_j``, ``t = (ρ − ρ_min)/(ρ_max − ρ_min)``, and the degree.

    ``fun`` is evaluated on ``points`` complex ρ with ``|t| = 1``; the DFT gives the coefficients
    exactly for a polynomial of degree < ``points`` (well conditioned, no Vandermonde fit).  The
    degree is the last coefficient above 100 × the round-off floor (the largest of the upper
    half of the spectrum); it depends on the interval's scale, so count ρ-degrees on [0, 1].

    Parameters
    ----------
    fun : callable
        Maps a 1-D complex array of ρ to an array whose first axis runs over those ρ.
    rho_min, rho_max : float
        The scheduling interval (``t = 0`` and ``t = 1``).
    points : int
        Number of points on the circle (default 64; degrees below ``points / 2`` are resolved).
    rtol : float
        Largest accepted tail of the spectrum relative to its peak (default 1e-8).

    Returns
    -------
    coefficients : (degree + 1, ...) array
        ``M_0 … M_degree`` (real parts).
    degree : int
        The polynomial degree in ``t``.

    Raises
    ------
    ParameterError
        ``rho_min``, ``rho_max`` not finite with ``rho_min < rho_max``.
    DesignError
        If the coefficients do not die out (``fun`` is not a polynomial of degree < points/2).

    Examples
    --------
    >>> import numpy as np
    >>> M, degree = polynomial_coefficients(lambda r: (1 + 2 * r + r**2)[:, None, None], 0.0, 1.0)
    >>> degree, np.round(M.ravel(), 6).tolist()
    (2, [1.0, 2.0, 1.0])

    References
    ----------
    Varrier et al. 2014, §4.5, (32)–(36).
    """
    if not (np.isfinite(rho_min) and np.isfinite(rho_max) and rho_max > rho_min):
        raise ParameterError(f"need finite rho_min < rho_max, got [{rho_min}, {rho_max}]")
    t = np.exp(2j * np.pi * np.arange(points) / points)
    vals = np.asarray(fun(rho_min + (rho_max - rho_min) * t))
    coef = np.fft.fft(vals, axis=0) / points
    size = np.linalg.norm(coef.reshape(points, -1), axis=1)
    top, floor = size.max(), size[points // 2:].max()  # the tail of a polynomial of low degree is round-off
    keep = np.flatnonzero(size[: points // 2] > max(100 * floor, 1e-14 * top))
    degree = int(keep[-1]) if keep.size else 0
    if floor > rtol * top:
        raise DesignError(f"the function is not a polynomial of degree < {points // 2} in rho over "
                          f"[{rho_min}, {rho_max}] (e.g. H_os1(rho) has a rho-dependent determinant); "
                          "the polytopic design needs polynomial Γ_κ")
    return coef[: degree + 1].real.copy(), degree


def box_vertices(N: int, rho_max: float) -> np.ndarray:
    """The ``2^N`` corners of the box ``θ_j = ρ^j ∈ [0, ρ_max^j]`` (classical polytope, §4.6.2).

    Parameters
    ----------
    N : int
        Number of parameters ``ρ, ρ², …, ρ^N``.
    rho_max : float
        Upper end of the scheduling range.

    Returns
    -------
    (2^N, N) array
        The corners, in binary order.

    Examples
    --------
    >>> box_vertices(2, 0.5).tolist()
    [[0.0, 0.0], [0.0, 0.25], [0.5, 0.0], [0.5, 0.25]]

    References
    ----------
    Varrier et al. 2014, §4.6.2.
    """
    return np.array([[b * rho_max ** (j + 1) for j, b in enumerate(bits)] for bits in product((0, 1), repeat=N)],
                    dtype=float).reshape(-1, N)


def is_admissible(vertex: np.ndarray, rho_max: float) -> bool:
    """Property 1, (46): ``ν_{j+1} ≤ ρ_max ν_j`` for all j (coordinates ν_j ∈ {0, ρ_max^j}).

    Parameters
    ----------
    vertex : (N,) array_like
        A box corner (:func:`box_vertices`).
    rho_max : float
        Upper end of the scheduling range.

    Returns
    -------
    bool
        Whether the corner is one of the Property-1 vertices.

    Examples
    --------
    >>> is_admissible([0.5, 0.25], 0.5), is_admissible([0.0, 0.25], 0.5)
    (True, False)

    References
    ----------
    Varrier et al. 2014, §4.6.2, Property 1, (46).
    """
    v = np.asarray(vertex, dtype=float)
    return bool(np.all(v[1:] <= rho_max * v[:-1] * (1 + 1e-12) + 1e-300))


def property1_vertices(N: int, rho_max: float) -> np.ndarray:
    """The ``N+1`` admissible vertices ``ω_j = (ρ_max, …, ρ_max^j, 0, …, 0)``, j = 0..N (Property 1).

    Parameters
    ----------
    N : int
        Number of parameters ``ρ, ρ², …, ρ^N``.
    rho_max : float
        Upper end of the scheduling range.

    Returns
    -------
    (N + 1, N) array
        Row ``j`` is ``ω_j``.

    Examples
    --------
    >>> property1_vertices(2, 0.5).tolist()
    [[0.0, 0.0], [0.5, 0.0], [0.5, 0.25]]

    References
    ----------
    Varrier et al. 2014, §4.6.2, Property 1, (46).
    """
    return np.array([[rho_max ** (i + 1) if i < j else 0.0 for i in range(N)] for j in range(N + 1)])


def scheduling_weights(rho, N: int, rho_min: float, rho_max: float) -> np.ndarray:
    """Barycentric weights ``α̃_j(ρ)`` of the Property-1 simplex (derived; Remark 5: ≥ 0, sum 1).

    ``α̃₀ = 1 − t``, ``α̃_j = t^j − t^{j+1}`` (0 < j < N), ``α̃_N = t^N`` with ``t`` clipped to [0, 1];
    ``Σ_j α̃_j ω_j = (ρ', ρ'², …)`` in the scaled variable.

    Parameters
    ----------
    rho : float or array_like
        Scheduling values (any shape).
    N : int
        Polynomial degree (number of vertices minus one).
    rho_min, rho_max : float
        The scheduling interval.

    Returns
    -------
    (..., N + 1) array
        The weights ``α̃_0 … α̃_N`` per value of ``rho``.

    Examples
    --------
    >>> scheduling_weights(0.5, 2, 0.0, 1.0).tolist()
    [0.5, 0.25, 0.25]

    References
    ----------
    Varrier et al. 2014, §4.5, Remark 5; §4.6.2, Property 1 (the weights are derived here, not printed).
    """
    t = np.clip((np.asarray(rho, dtype=float) - rho_min) / (rho_max - rho_min), 0.0, 1.0)
    powers = t[..., None] ** np.arange(N + 2)
    w = powers[..., :-1] - powers[..., 1:]
    w[..., N] = powers[..., N]
    return w


def repair_vertex(M: np.ndarray, mode: str = "inverse", factor: float = 10.0) -> tuple[np.ndarray, int]:
    """Replace the non-positive eigenvalues of a symmetric vertex matrix (Varrier et al. 2014, (41)–(42)).

    ``mode="paper"``: by ``factor × max positive eigenvalue``; ``"inverse"``: by
    ``min positive eigenvalue / factor`` (large in the inverse, Remark 7).  Eigenvectors and
    positive eigenvalues are kept.

    Parameters
    ----------
    M : (q, q) array_like
        Vertex matrix (symmetrised).
    mode : str
        ``'inverse'`` (default) or ``'paper'``.
    factor : float
        The replacement factor (default 10).

    Returns
    -------
    matrix : (q, q) array
        The repaired (positive definite) matrix.
    replaced : int
        The number of replaced eigenvalues (0: ``M`` was positive definite and is returned symmetrised).

    Raises
    ------
    ParameterError
        An unknown ``mode`` (only checked when a repair is needed).

    Examples
    --------
    >>> import numpy as np
    >>> repair_vertex(np.diag([2.0, -1.0]))[0].tolist(), repair_vertex(np.diag([2.0, -1.0]), "paper")[0].tolist()
    ([[2.0, 0.0], [0.0, 0.2]], [[2.0, 0.0], [0.0, 20.0]])

    References
    ----------
    Varrier et al. 2014, §4.5, Remarks 6–7, (41)–(42).
    """
    M = (np.asarray(M, dtype=float) + np.asarray(M, dtype=float).T) / 2
    d, V = np.linalg.eigh(M)
    bad = d <= 1e-12 * np.max(np.abs(d))
    if not bad.any():
        return M, 0
    ref = d[~bad] if (~bad).any() else np.abs(d)
    if mode == "paper":
        new = factor * ref.max()
    elif mode == "inverse":
        new = ref.min() / factor
    else:
        raise ParameterError(f"unknown repair mode {mode!r}; use 'inverse' or 'paper'")
    d = np.where(bad, new, d)
    return (V * d) @ V.T, int(bad.sum())


@dataclass(frozen=True)
class PolytopicLmi:
    """Vertex solutions ``W`` (r, q); ``gamma`` (r,) the attained bounds ``W_iᵀΓ̃_i⁻¹W_i`` (common: their
    maximum), checked against the solver's γ'; ``min_eigs`` of the vertex LMI blocks at ``γ'(1 + 1e-8)``.

    Attributes
    ----------
    W : (r, q) array
        One parity vector per vertex, ``cᵀ W_i = 1``.
    gamma : (r,) array
        Attained bounds (objective ``'common'``: all equal to their maximum).
    min_eigs : (r,) array
        Smallest eigenvalue of each vertex LMI block (≥ 0).
    status : str
        The solver status (``'optimal'``).

    Examples
    --------
    >>> import numpy as np
    >>> res = polytopic_lmi(np.array([np.eye(2), 2 * np.eye(2)]), np.array([1.0, 1.0]))
    >>> np.round(res.gamma, 6).tolist(), res.status
    ([0.5, 0.5], 'optimal')

    References
    ----------
    Varrier et al. 2014, §4.5, (37)–(40).
    """

    W: np.ndarray
    gamma: np.ndarray
    min_eigs: np.ndarray
    status: str


def polytopic_lmi(vertices: np.ndarray, c: np.ndarray, *, objective: str = "common", solver: str = "CLARABEL"
                  ) -> PolytopicLmi:
    """``min γ'`` s.t. ``[[Γ̃_i, W_i], [W_iᵀ, γ'_i]] ⪰ 0``, ``cᵀW_i = 1`` per vertex (Varrier et al. 2014, (39)–(40)).

    ``objective="common"``: one γ' (as printed in (38)–(40)); ``"sum"``: γ'_i per vertex
    ("the same structure for γ'", (37)), minimising their sum.  Vertices are scaled by a
    common factor and each LMI is posed after the congruence ``diag(L_i⁻¹, 1)``,
    ``Γ̃_i = L_i L_iᵀ`` — the same LMI with an identity (1,1) block (posed directly, Clarabel's γ'
    was 3e-4 off the bound its W attains).  The solution is checked: vertices PD, attained
    bounds ``W_iᵀΓ̃_i⁻¹W_i`` ≤ solver γ' (1 + 1e-5), block eigenvalues ≥ 0, ``cᵀW_i = 1``.

    Parameters
    ----------
    vertices : (r, q, q) array_like
        Vertex matrices ``Γ̃_i`` (positive definite; see :func:`repair_vertex`).
    c : (q,) array_like
        Normalisation vector of ``cᵀ W_i = 1``.
    objective : str
        ``'common'`` (default) or ``'sum'``.
    solver : str
        cvxpy solver name (default ``'CLARABEL'``, with tight tolerances).

    Returns
    -------
    PolytopicLmi
        The vertex solutions, attained bounds, block eigenvalues and solver status.

    Raises
    ------
    ParameterError
        An unknown ``objective``.
    DesignError
        A vertex that is not positive definite, no solution, or a solution that fails the checks.

    Examples
    --------
    >>> import numpy as np
    >>> res = polytopic_lmi(np.array([np.eye(2), 2 * np.eye(2)]), np.array([1.0, 1.0]))
    >>> np.round(res.W[0], 6).tolist(), bool(np.allclose(res.W @ [1.0, 1.0], 1))
    ([0.5, 0.5], True)

    References
    ----------
    Varrier et al. 2014, §4.5, (37)–(40).
    """
    import cvxpy as cp

    if objective not in ("common", "sum"):
        raise ParameterError(f"unknown objective {objective!r}; use 'common' or 'sum'")
    V = np.asarray(vertices, dtype=float)
    r, q = V.shape[0], V.shape[1]
    sc = max(np.linalg.norm(Vi, 2) for Vi in V)
    c = np.asarray(c, dtype=float)
    W = cp.Variable((r, q))
    g = cp.Variable(1 if objective == "common" else r)
    cons = []
    for i in range(r):
        if np.linalg.eigvalsh(V[i])[0] <= 0:
            raise DesignError(f"vertex matrix {i} is not positive definite; repair it first (repair_vertex, (41)-(42))")
        # congruence diag(L⁻¹, 1) with V_i/sc = L Lᵀ: the same LMI, with an identity (1,1) block
        Li = np.linalg.inv(np.linalg.cholesky(V[i] / sc))
        gi = g[0] if objective == "common" else g[i]
        x = Li @ W[i]
        blk = cp.bmat([[np.eye(q), cp.reshape(x, (q, 1), order="F")],
                       [cp.reshape(x, (1, q), order="F"), cp.reshape(gi, (1, 1), order="F")]])
        cons += [(blk + blk.T) / 2 >> 0, c @ W[i] == 1]
    prob = cp.Problem(cp.Minimize(cp.sum(g)), cons)
    prob.solve(solver=solver, **solver_options(solver))
    if W.value is None:
        raise DesignError(f"the polytopic LMI has no solution ({solver}: {prob.status}); check the vertex repair")
    Wv = np.asarray(W.value)
    g_solver = np.broadcast_to(np.atleast_1d(g.value), (r,)).astype(float) / sc
    # the bound the returned W actually attains (Schur complement), in the vertices' own scale
    pd = all(np.linalg.eigvalsh(Vi)[0] > 0 for Vi in V)
    quad = np.array([Wv[i] @ np.linalg.solve(V[i], Wv[i]) for i in range(r)]) if pd else np.full(r, np.inf)
    gv = np.full(r, quad.max()) if objective == "common" else quad
    mins = np.array([np.linalg.eigvalsh(lmi_block(V[i] / sc, Wv[i], gv[i] * sc * (1 + 1e-8)))[0] for i in range(r)])
    if (not pd or np.any(gv > g_solver * (1 + 1e-5) + 1e-12) or np.any(mins < 0)
            or np.any(np.abs(Wv @ c - 1) > 1e-6)):
        raise DesignError(f"the polytopic LMI solution is not feasible (vertices PD: {pd}, attained bounds {gv} vs "
                          f"solver {g_solver}, min eigenvalues {mins}); status {prob.status}")
    return PolytopicLmi(Wv, gv, mins, prob.status)
