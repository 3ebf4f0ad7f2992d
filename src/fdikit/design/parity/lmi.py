"""The LTI LMI form of 𝒫₂ in the robust parity design (Varrier et al. 2014, §4.4.1, (27)–(31)).

𝒫₂ (24) ``min W₂ᵀ Γ_κ W₂`` with ``Γ_κ = Γ₁ − κ²Γ₂ ≻ 0`` (:func:`~fdikit.design.parity.criteria.gamma_kappa`)
is solved as the LMI ``min γ s.t. [[Γ_κ⁻¹, W₂], [W₂ᵀ, γ]] ⪰ 0`` (27), (31) with cvxpy; the closed form with
``cᵀW₂ = 1`` is :func:`~fdikit.design.parity.criteria.p2_solution`.

* The normalisation ``trace|diag W₂| > ε`` (29)–(30), i.e. ``‖W₂‖₁ ≥ ε``, is not convex.
  :func:`lti_lmi` solves it exactly by sign enumeration (``‖w‖₁ ≥ ε ⇔ σᵀw ≥ ε`` for some
  ``σ ∈ {±1}^q``, one SDP per σ) or replaces it by the linear ``cᵀW₂ = 1``, whose optimum is
  ``Γ_κ⁻¹c / (cᵀΓ_κ⁻¹c)``.  (31) is printed with one block row; the full block of (27) is used.

The polytopic LMI of the LPV design (39)–(40) is :func:`fdikit.design.parity.polytope.polytopic_lmi`.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from fdikit.design.parity.criteria import gamma_kappa
from fdikit.design.parity.polytope import lmi_block, solver_options
from fdikit.errors import DesignError, ParameterError

__all__ = ["LmiDesign", "lti_lmi"]


@dataclass(frozen=True)
class LmiDesign:
    """Solution of the LTI LMI (27)/(31): ``W2``, ``gamma`` = ``W₂ᵀΓ_κW₂`` attained (checked against the
    solver's γ), the smallest eigenvalue of the scaled LMI block at ``γ(1 + 1e-8)``, the ratio ``J``, the
    normalisation and (for ``"l1"``) the sign vector.

    Attributes
    ----------
    W2 : (q,) array; gamma : float, ``W₂ᵀΓ_κW₂``; min_eig : float; J : float, ``W₂ᵀΓ₁W₂ / W₂ᵀΓ₂W₂``.
    normalization : str, ``"linear"`` or ``"l1"``; sign : (q,) array or None; status : str, the solver status.

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> r = lti_lmi(G1, G2, 0.5)
    >>> round(r.gamma, 4), round(r.J, 4), r.status
    (0.4286, 0.6538, 'optimal')

    References
    ----------
    Varrier et al. 2014, §4.4.1, (27)–(31).
    """

    W2: np.ndarray
    gamma: float
    min_eig: float
    J: float
    normalization: str
    sign: np.ndarray | None = None
    status: str = ""


def lti_lmi(gamma1: np.ndarray, gamma2: np.ndarray, kappa: float, *, normalization: str = "linear",
            c: np.ndarray | None = None, eps: float = 1.0, solver: str = "CLARABEL") -> LmiDesign:
    """LTI 𝒫₂ as the LMI ``min γ s.t. [[Γ_κ⁻¹, W₂], [W₂ᵀ, γ]] ⪰ 0`` (Varrier et al. 2014, (27), (31)) with cvxpy.

    ``normalization="linear"``: ``cᵀW₂ = 1`` (default ``c = 𝟙``).  ``"l1"``: ``‖W₂‖₁ ≥ ε`` (30),
    exactly, by enumerating ``σ ∈ {±1}^q`` with ``σ₁ = +1`` (``±W₂`` are equivalent) and
    keeping the best SDP.  The returned matrices are checked: the LMI block's smallest
    eigenvalue and the normalisation, not only the solver status.

    Parameters
    ----------
    gamma1, gamma2 : (q, q) array_like, ``Γ₁`` and ``Γ₂``; kappa : float, ``0 <= κ < κ_max``.
    normalization : ``"linear"`` (default) or ``"l1"``; c : (q,) array_like, default ``𝟙``; eps : float, ``ε``.
    solver : str, cvxpy solver name (default ``"CLARABEL"``).

    Returns
    -------
    LmiDesign

    Raises
    ------
    ParameterError
        An unknown ``normalization``, or ``"l1"`` with q > 12.
    DesignError
        ``Γ_κ`` not positive definite (κ too large), no solution, or a solution that fails the checks.

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> lti_lmi(G1, G2, 0.5).W2.round(4).tolist()
    [0.5714, 0.4286]

    References
    ----------
    Varrier et al. 2014, §4.4.1, (27), (29)–(31).
    """
    import cvxpy as cp

    Gk = gamma_kappa(gamma1, gamma2, kappa)
    q = Gk.shape[0]
    Ginv = np.linalg.inv(Gk)
    Ginv = (Ginv + Ginv.T) / 2
    sc = np.linalg.norm(Ginv, 2)
    M = Ginv / sc  # [[M, w],[wᵀ, g]] ⪰ 0  ⇔  g ≥ sc · wᵀΓ_κw
    Li = np.linalg.inv(np.linalg.cholesky(M))  # solved after the congruence diag(L⁻¹, 1), M = L Lᵀ
    if normalization == "linear":
        cs = [np.ones(q) if c is None else np.asarray(c, dtype=float)]
        rhs = 1.0
    elif normalization == "l1":
        if q > 12:
            raise ParameterError(f"normalization='l1' enumerates 2^(q-1) sign vectors; q = {q} is too large, "
                             "use normalization='linear'")
        cs = [np.array((1.0,) + sg) for sg in product((1.0, -1.0), repeat=q - 1)]
        rhs = float(eps)
    else:
        raise ParameterError(f"unknown normalization {normalization!r}; use 'linear' (cᵀW₂ = 1) or 'l1' (‖W₂‖₁ ≥ ε)")
    best = None
    for ci in cs:
        w, g = cp.Variable(q), cp.Variable()
        x = Li @ w
        blk = cp.bmat([[np.eye(q), cp.reshape(x, (q, 1), order="F")],
                       [cp.reshape(x, (1, q), order="F"), cp.reshape(g, (1, 1), order="F")]])
        cons = [(blk + blk.T) / 2 >> 0, ci @ w == rhs] if normalization == "linear" else [(blk + blk.T) / 2 >> 0,
                                                                                          ci @ w >= rhs]
        prob = cp.Problem(cp.Minimize(g), cons)
        prob.solve(solver=solver, **solver_options(solver))
        if w.value is None:
            continue
        if best is None or g.value < best[1]:
            best = (np.asarray(w.value, dtype=float), float(g.value), ci, prob.status)
    if best is None:
        raise DesignError(f"the LMI solver ({solver}) returned no solution; check Γ_κ's conditioning")
    wv, g_solver, ci, status = best
    gv = float(wv @ Gk @ wv)  # the bound the returned W₂ attains
    min_eig = float(np.linalg.eigvalsh(lmi_block(M, wv, gv * sc * (1 + 1e-8)))[0])
    norm_ok = abs(ci @ wv - rhs) <= 1e-6 * max(1.0, abs(rhs)) if normalization == "linear" else ci @ wv >= rhs * (
        1 - 1e-6)
    if min_eig < 0 or gv > g_solver / sc * (1 + 1e-5) or not norm_ok:
        raise DesignError(f"the LMI solution is not feasible (smallest eigenvalue {min_eig:.3g}, attained γ {gv:.6g} "
                          f"vs solver {g_solver / sc:.6g}, normalisation {ci @ wv:.6g} vs {rhs}); status {status!r}")
    J = float(wv @ gamma1 @ wv / (wv @ gamma2 @ wv))
    return LmiDesign(wv, gv, min_eig, J, normalization, ci if normalization == "l1" else None, status)
