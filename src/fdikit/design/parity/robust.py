"""Robust parity design for uncertain LPV systems (Varrier et al. 2014, §4).

The residual ``r = W₂ᵀ P(ρ) (Y_s − H_us U_s)`` (16) is decoupled from the state by
``P H_os = 0`` for every ``W₂``; ``W₂`` is chosen to trade the uncertainty and unknown-input
maps ``G = [H̃_os, H̃_us, H_ds, H̃_ds]`` (18) against the fault map ``H_fs``::

    Γ₁ = P G Gᵀ Pᵀ,   Γ₂ = P H_fs H_fsᵀ Pᵀ,   J(W₂) = W₂ᵀΓ₁W₂ / W₂ᵀΓ₂W₂                (19)–(20)

* LPV (32)–(46), :func:`robust_lpv_parity`: ``W₂(ρ) = Σ_j α̃_j(ρ) W_j`` from the polytopic
  machinery of :mod:`fdikit.design.parity.polytope` (adjugate polynomial of ``Γ_κ(ρ)``, Property 1
  vertices, vertex repair (41)–(42), one vertex LMI (39)–(40) with ``cᵀW_j = 1``).
* ``method="adjugate"`` (beyond the paper, an fdikit option): ``W_j = Γ̃_j c`` unrepaired, so
  ``W₂(ρ) = adj Γ_κ(ρ) c ∝ Γ_κ(ρ)⁻¹ c``, the pointwise optimum of 𝒫₂ with ``cᵀW₂ = 1``.

The stacked and δ-expanded matrices (14) come from :mod:`fdikit.lpv`, the parity matrix
and the LPV residual from :mod:`fdikit.design.parity.state_space`.

The criteria Γ₁, Γ₂, Theorem 1, κ and the closed form of 𝒫₂ are in :mod:`fdikit.design.parity.criteria`;
the LTI LMI (27)–(31) and its normalisations in :mod:`fdikit.design.parity.lmi`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit.design.labels import residual_labels
from fdikit.design.parity.criteria import robust_criteria, theorem1, theorem1_batch
from fdikit.design.parity.polytope import (
    adjugate,
    polynomial_coefficients,
    polytopic_lmi,
    repair_vertex,
    scheduling_weights,
)
from fdikit.design.parity.state_space import lpv_parity_residuals, regular_rows
from fdikit.errors import DesignError, ParameterError
from fdikit.lpv import LPVModel, Uncertainty, lpv_stacked_matrices
from fdikit.protocols import no_internal_form
from fdikit.residuals import Residuals
from fdikit.trace import Trace

__all__ = ["RobustParityDesign", "robust_lpv_parity"]


# ---------------------------------------------------------------------------------------------- LPV design
@dataclass(frozen=True, eq=False)
class RobustParityDesign:
    """A scheduled robust parity vector ``W₂(ρ) = Σ_j α̃_j(ρ) W_j`` (Varrier et al. 2014, (37), (49)) and its report.

    Attributes
    ----------
    W_vertices : (N+1, q) vertex solutions; vertices / repaired : the adjugate vertex matrices
    ``Γ̃_j`` before and after the repair; n_repaired : replaced eigenvalues per vertex;
    gamma : LMI bound(s) (None for ``method="adjugate"``); c : the normalisation vector;
    kappa, kappa_max : κ and the largest valid κ on the design grid; degrees : ρ-degrees of
    Γ₁, Γ₂, det Γ_κ and adj Γ_κ (the paper's "products", §5.3); box_vertices : 2^(adj degree);
    truncation_error : sup over the grid of ‖adj − truncated adj‖ / ‖adj‖.
    lpv, uncertainties, s, rows, rho_min, rho_max, order, method, criteria_kw : the design's arguments.
    names, isolates : the residual's name (default ``('robust_parity',)``) and the fault it isolates (default
    ``(None,)``), used by :meth:`residuals` (keyword-only).

    Examples
    --------
    >>> from fdikit.plants import varrier_lateral_lpv, varrier_uncertainty
    >>> lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    >>> d = robust_lpv_parity(lpv, unc, 3, kappa=0.1, rho_max=0.2, rho_nominal=0.048, method="adjugate")
    >>> d.W_vertices.shape, d.w2(0.05).shape, d.gamma is None
    ((6, 6), (6,), True)

    References
    ----------
    Varrier et al. 2014, §4.5, (37); §5.3, (49).
    """

    lpv: LPVModel
    uncertainties: tuple[Uncertainty, ...]
    s: int
    rows: tuple[int, ...]
    kappa: float
    kappa_max: float
    rho_min: float
    rho_max: float
    order: int
    method: str
    c: np.ndarray
    W_vertices: np.ndarray
    vertices: np.ndarray
    repaired: np.ndarray
    n_repaired: tuple[int, ...]
    gamma: np.ndarray | None
    degrees: dict[str, int]
    box_vertices: int
    truncation_error: float
    criteria_kw: dict = field(default_factory=dict)
    names: tuple[str, ...] = field(default=("robust_parity",), kw_only=True)
    isolates: tuple[str | None, ...] = field(default=(None,), kw_only=True)

    def weights(self, rho) -> np.ndarray:
        """``α̃_j(ρ)`` (..., N+1)."""
        return scheduling_weights(rho, self.order, self.rho_min, self.rho_max)

    def w2(self, rho) -> np.ndarray:
        """Scheduled ``W₂(ρ)`` (..., q)."""
        return self.weights(rho) @ self.W_vertices

    def criterion(self, rho) -> tuple[np.ndarray, np.ndarray]:
        """``J(W₂(ρ), ρ)`` and the optimum ``λ_min(ρ)`` of Theorem 1 at each ρ (1-D)."""
        rho = np.atleast_1d(np.asarray(rho, dtype=float))
        cr = robust_criteria(self.lpv, self.uncertainties, rho, self.s, rows=self.rows, **self.criteria_kw)
        w = self.w2(rho)
        J = np.einsum("ki,kij,kj->k", w, cr.gamma1, w) / np.einsum("ki,kij,kj->k", w, cr.gamma2, w)
        return J, theorem1_batch(cr.gamma1, cr.gamma2)[0]

    def residuals(self, trace: Trace, rho, *, mode: str = "frozen", name: str | None = None) -> Residuals:
        """The U-LPV residual (16) of a trace (see :func:`lpv_parity_residuals`), named ``name`` (default
        ``names[0]``) and tied to ``isolates[0]``."""
        return lpv_parity_residuals(self.lpv, trace, rho, self.s, W2=self.w2, mode=mode, rows=self.rows,
                                    names=[name or self.names[0]], isolates=self.isolates)

    @property
    def generator(self) -> RobustParityDesign:
        """The design itself: a ρ-scheduled parity vector, run with :meth:`residuals` ``(trace, rho)``."""
        return self

    def internal_form(self):
        """Not available: raises :class:`~fdikit.errors.DesignError` (the parity vector varies with ρ)."""
        no_internal_form(self, "the parity vector W2(rho) is scheduled on the LPV parameter, so plant and filter "
                               "in series are not an LTI FaultModel; use residuals(trace, rho) and criterion(rho)")

    def report(self) -> dict:
        """``method``, ``s``, ``rows``, ``order``, ``kappa`` and ``kappa_max`` (κ and its largest valid value),
        ``gamma`` (LMI bounds or None), ``W_vertices``, ``n_repaired`` (replaced eigenvalues per vertex),
        ``degrees`` (ρ-degrees), ``box_vertices`` and ``truncation_error``."""
        return {"method": self.method, "s": self.s, "rows": self.rows, "order": self.order, "kappa": self.kappa,
                "kappa_max": self.kappa_max, "gamma": self.gamma, "W_vertices": self.W_vertices,
                "n_repaired": self.n_repaired, "degrees": self.degrees, "box_vertices": self.box_vertices,
                "truncation_error": self.truncation_error}


def robust_lpv_parity(
    lpv: LPVModel,
    uncertainties: Sequence[Uncertainty],
    s: int,
    *,
    kappa: float,
    rho_max: float,
    rho_min: float = 0.0,
    rho_nominal: float | None = None,
    order: int = 5,
    method: str = "lmi",
    objective: str = "common",
    repair: str = "inverse",
    repair_factor: float = 10.0,
    c: np.ndarray | None = None,
    rows: Sequence[int] | None = None,
    grid: int = 41,
    points: int = 64,
    solver: str = "CLARABEL",
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
    **criteria_kw,
) -> RobustParityDesign:
    """Polytopic robust parity design for an uncertain LPV model (Varrier et al. 2014, §4.5–4.6, (32)–(46)).

    Steps: Γ₁, Γ₂ on a ρ grid and the κ check (refusal with ``κ_max``); ``adj Γ_κ(ρ)`` as a
    polynomial in ``t``; truncation to degree ``order`` (N+1 = ``order+1`` vertices, Property 1);
    vertex repair; one LMI (39)–(40) with ``cᵀW_j = 1`` (``method="lmi"``), or ``W_j = Γ̃_j c``
    (``method="adjugate"``).  ``c`` defaults to Theorem 1's ``W₂*`` at ``rho_nominal``
    (default the middle of the range).  ``criteria_kw`` go to :func:`robust_criteria`.

    Parameters
    ----------
    lpv, uncertainties, s : as in :func:`robust_criteria`.
    kappa : float, ``0 <= κ < κ_max`` (checked on the grid).
    rho_min, rho_max : float, the scheduling range (``0 <= rho_min < rho_max``; default ``rho_min = 0``).
    rho_nominal : float or None, where ``c`` and the rows are computed (default the middle of the range).
    order : int, the truncation degree N (default 5).
    method : ``"lmi"`` (default) or ``"adjugate"``; objective : ``"common"`` or ``"sum"`` (see polytopic_lmi).
    repair, repair_factor : the vertex repair (``"inverse"`` or ``"paper"``; default factor 10).
    c : (q,) array_like or None, the normalisation vector; rows : rows of ``H_os1``.
    grid, points : ρ grid size for the checks (41) and FFT points of the polynomial fit (64).
    solver : str, cvxpy solver (default ``"CLARABEL"``); **criteria_kw : keywords of :func:`robust_criteria`.
    names, isolates : the residual's name (default ``robust_parity``) and the fault it isolates (default None),
        as :func:`~fdikit.design.labels.residual_labels`; :meth:`RobustParityDesign.residuals` uses them.

    Returns
    -------
    RobustParityDesign

    Raises
    ------
    ParameterError
        A bad range, ``method``, ``order`` (or an argument :func:`robust_criteria` refuses).
    DesignError
        If Γ_κ is not positive definite somewhere on the grid (the message gives κ_max), or an
        LMI is infeasible.

    Examples
    --------
    >>> from fdikit.plants import varrier_lateral_lpv, varrier_uncertainty
    >>> lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    >>> d = robust_lpv_parity(lpv, unc, 3, kappa=0.1, rho_max=0.2, rho_nominal=0.048, method="adjugate")
    >>> d.order, round(d.kappa_max, 4), len(d.n_repaired), d.method
    (5, 0.149, 6, 'adjugate')

    References
    ----------
    Varrier et al. 2014, §4.5–4.6, (32)–(46).
    """
    if not (0 <= rho_min < rho_max) or not np.isfinite(rho_max):
        raise ParameterError(f"need 0 <= rho_min < rho_max < inf, got [{rho_min}, {rho_max}]")
    if method not in ("lmi", "adjugate"):
        raise ParameterError(f"unknown method {method!r}; use 'lmi' (paper, (40)) or 'adjugate'")
    if not (isinstance(order, int) and order >= 0):
        raise ParameterError(f"order must be an integer >= 0, got {order!r}")
    res, iso = residual_labels(lpv, 1, names, isolates, default_names=("robust_parity",))
    unc = tuple(uncertainties)
    rho_nominal = (rho_min + rho_max) / 2 if rho_nominal is None else float(rho_nominal)
    if rows is None:
        rows = regular_rows(lpv_stacked_matrices(lpv, rho_nominal, s, groups=()).H_os)
    rows = tuple(int(i) for i in rows)

    def crit(rho):
        return robust_criteria(lpv, unc, rho, s, rows=rows, **criteria_kw)

    rho_grid = np.linspace(rho_min, rho_max, grid)
    cg = crit(rho_grid)
    lam = theorem1_batch(cg.gamma1, cg.gamma2)[0]
    k_max = float(np.sqrt(lam.min()))
    if not (np.isfinite(kappa) and 0 <= kappa < k_max):
        worst = rho_grid[np.argmin(lam)]
        raise DesignError(
            f"Γ_κ(ρ) = Γ₁ − κ²Γ₂ is not positive definite for κ = {kappa:g} on ρ ∈ [{rho_min:g}, {rho_max:g}]: "
            f"it needs κ² < min_ρ λ_min(Γ₁, Γ₂) = {lam.min():.6g} (at ρ = {worst:.4g}); the largest valid κ is "
            f"{k_max:.6g}. Choose κ < {k_max:.6g} (Remark 4; the paper's κ = 27 fails this test)"
        )
    if c is None:
        cn = crit(np.array([rho_nominal]))
        c = theorem1(cn.gamma1[0], cn.gamma2[0], sign_ref=cn.fault_direction[0].ravel()).W2
    c = np.asarray(c, dtype=float)

    def gk(rho):
        cr = crit(rho)
        return cr.gamma1 - kappa**2 * cr.gamma2

    def fit(fun):
        return polynomial_coefficients(fun, rho_min, rho_max, points=points)

    M, deg_adj = fit(lambda r: adjugate(gk(r)))
    def count(fun):  # ρ-degree on the unit circle |ρ| = 1 (the paper's ρ < 1)
        return polynomial_coefficients(fun, 0.0, 1.0, points=points)[1]

    degrees = {"gamma1": count(lambda r: crit(r).gamma1), "gamma2": count(lambda r: crit(r).gamma2),
               "det": count(lambda r: np.linalg.det(gk(r))), "adjugate": count(lambda r: adjugate(gk(r)))}
    N = min(order, deg_adj)
    t = (rho_grid - rho_min) / (rho_max - rho_min)
    exact = adjugate(cg.gamma1 - kappa**2 * cg.gamma2)
    trunc = np.einsum("kj,jab->kab", t[:, None] ** np.arange(N + 1), M[: N + 1])
    err = float(np.max(np.linalg.norm(exact - trunc, 2, axis=(1, 2)) / np.linalg.norm(exact, 2, axis=(1, 2))))
    vertices = np.cumsum(M[: N + 1], axis=0)
    fixed = [repair_vertex(Vj, repair, repair_factor) for Vj in vertices]
    repaired = np.array([f[0] for f in fixed])
    n_rep = tuple(f[1] for f in fixed)
    if method == "lmi":
        sol = polytopic_lmi(repaired, c, objective=objective, solver=solver)
        Wv, gamma = sol.W, sol.gamma
    else:
        Wv = vertices @ c
        Wv = Wv / np.abs(Wv).max()
        gamma = None
    return RobustParityDesign(
        lpv, unc, s, rows, float(kappa), k_max, float(rho_min), float(rho_max), N, method, c, Wv, vertices,
        repaired, n_rep, gamma, degrees, 2 ** degrees["adjugate"], err, dict(criteria_kw), names=res, isolates=iso,
    )
