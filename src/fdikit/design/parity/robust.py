"""Robust parity design for uncertain LPV systems (Varrier et al. 2014, §4).

The residual ``r = W₂ᵀ P(ρ) (Y_s − H_us U_s)`` (16) is decoupled from the state by
``P H_os = 0`` for every ``W₂``; ``W₂`` is chosen to trade the uncertainty and unknown-input
maps ``G = [H̃_os, H̃_us, H_ds, H̃_ds]`` (18) against the fault map ``H_fs``::

    Γ₁ = P G Gᵀ Pᵀ,   Γ₂ = P H_fs H_fsᵀ Pᵀ,   J(W₂) = W₂ᵀΓ₁W₂ / W₂ᵀΓ₂W₂                (19)–(20)

* Theorem 1 (21)–(23): ``min J = λ_min(Γ₁, Γ₂)`` at its generalised eigenvector, solved
  here as ``eigh(Γ₂, Γ₁)`` (Γ₂ is singular: rank ≤ (s+1)·#faults) taking ``1/μ_max``.
* 𝒫₂ (24): ``min W₂ᵀ Γ_κ W₂`` with ``Γ_κ = Γ₁ − κ²Γ₂``.  ``Γ_κ ≻ 0`` (needed for the Schur
  step, Remark 4) holds **iff** ``κ² < λ_min(Γ₁, Γ₂)`` (Γ₁ ≻ 0): ``wᵀΓ₁w > κ² wᵀΓ₂w`` for all
  ``w ≠ 0`` is exactly ``κ² < min J``.  The paper's κ = 27 violates this for the vehicle
  (λ_min ≈ 0.02–0.04, so κ_max ≈ 0.15–0.2); it is refused with the largest valid κ.
  (27 is consistent with ``Γ₁ − κ⁻²Γ₂``; that reading is not implemented.)
* The normalisation ``trace|diag W₂| > ε`` (29)–(30), i.e. ``‖W₂‖₁ ≥ ε``, is not convex.
  :func:`lti_lmi` solves it exactly by sign enumeration (``‖w‖₁ ≥ ε ⇔ σᵀw ≥ ε`` for some
  ``σ ∈ {±1}^q``, one SDP per σ) or replaces it by the linear ``cᵀW₂ = 1``, whose optimum is
  ``Γ_κ⁻¹c / (cᵀΓ_κ⁻¹c)``.  (31) is printed with one block row; the full block of (27) is used.
* LPV (32)–(46), :func:`robust_lpv_parity`: ``W₂(ρ) = Σ_j α̃_j(ρ) W_j`` from the polytopic
  machinery of :mod:`fdikit.design.parity.polytope` (adjugate polynomial of ``Γ_κ(ρ)``, Property 1
  vertices, vertex repair (41)–(42), one vertex LMI (39)–(40) with ``cᵀW_j = 1``).
* ``method="adjugate"`` (beyond the paper, an fdikit option): ``W_j = Γ̃_j c`` unrepaired, so
  ``W₂(ρ) = adj Γ_κ(ρ) c ∝ Γ_κ(ρ)⁻¹ c``, the pointwise optimum of 𝒫₂ with ``cᵀW₂ = 1``.

The stacked and δ-expanded matrices (14) come from :mod:`fdikit.lpv`, the parity matrix
and the LPV residual from :mod:`fdikit.design.parity.state_space`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import product

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.design.parity.polytope import (
    adjugate,
    lmi_block,
    polynomial_coefficients,
    polytopic_lmi,
    repair_vertex,
    scheduling_weights,
    solver_options,
)
from fdikit.design.parity.state_space import lpv_parity_residuals, parity_matrix, regular_rows
from fdikit.errors import DesignError, ParameterError
from fdikit.lpv import LPVModel, Uncertainty, lpv_stacked_matrices, uncertain_stacked_matrices
from fdikit.protocols import no_internal_form
from fdikit.residuals import Residuals
from fdikit.trace import Trace

__all__ = [
    "RobustCriteria", "robust_criteria", "EigenDesign", "theorem1", "theorem1_batch", "pointwise_theorem1",
    "kappa_max", "gamma_kappa", "p2_solution", "LmiDesign", "lti_lmi", "RobustParityDesign", "robust_lpv_parity",
]

_T = np.swapaxes  # plain (not conjugate) transpose keeps Γ analytic in a complex ρ


# ---------------------------------------------------------------------------------------------- criteria
@dataclass(frozen=True, eq=False)
class RobustCriteria:
    """``Γ₁ = P G Gᵀ Pᵀ``, ``Γ₂ = P H_F H_Fᵀ Pᵀ`` (Varrier et al. 2014, (18)–(20)); batch axes allowed.

    ``fault_direction`` is ``P H_fs 𝟙``, the image of a constant fault (per target fault).

    Attributes
    ----------
    gamma1, gamma2 : (..., q, q) arrays, ``Γ₁`` and ``Γ₂``.
    P : (..., q, (s+1)p) array, the parity basis at each ρ.
    G : (..., (s+1)p, k) array, the uncertainty and unknown-input map (18), weighted.
    H_fs : (..., (s+1)p, (s+1)n_f) array, the nominal fault map of the target faults.
    fault_direction : (..., q, n_f) array, ``P H_fs 𝟙`` per target fault (summed when there is one).
    rows : tuple of int, the rows of ``H_os1``.

    Examples
    --------
    >>> from fdikit.plants import varrier_lateral_lpv, varrier_uncertainty
    >>> lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    >>> cr = robust_criteria(lpv, unc, 0.048, 3)
    >>> cr.gamma1.shape, cr.P.shape, cr.rows
    ((6, 6), (6, 8), (0, 1))

    References
    ----------
    Varrier et al. 2014, §4.2, (16)–(20).
    """

    gamma1: np.ndarray
    gamma2: np.ndarray
    P: np.ndarray
    G: np.ndarray
    H_fs: np.ndarray
    fault_direction: np.ndarray
    rows: tuple[int, ...]


def robust_criteria(lpv: LPVModel, uncertainties: Sequence[Uncertainty], rho, s: int, *, mode: str = "frozen",
                    fault_model: str = "sequence", weights: Mapping[str, float] | None = None,
                    nuisance: Sequence[str] | str = (), rows: Sequence[int] | None = None) -> RobustCriteria:
    """Γ₁ and Γ₂ of the uncertain LPV model at ρ (Varrier et al. 2014, (14), (18)–(20)).

    Parameters
    ----------
    lpv : LPVModel, with disturbance (unknown-input) and fault groups.
    uncertainties : sequence of :class:`~fdikit.lpv.Uncertainty`, the δ-blocks of (14).
    rho : float or array, scheduling value(s) (batch axes allowed; ``mode="exact"``: windows of s+1).
    s : int, the horizon.
    mode : ``"frozen"`` (default) or ``"exact"`` stacking (see :func:`fdikit.lpv.lpv_stacked_matrices`).
    fault_model : ``"sequence"`` (the paper: ``H_F = H_fs``, the fault an arbitrary sequence over
        the window) or ``"constant"`` (``H_F = H_fs (𝟙 ⊗ I)``, a fault constant over the window,
        an fdikit option; Γ₂ then has rank ≤ #faults).
    weights : per-block weights of G, keys ``"os", "us", "ds", "ds_tilde"`` (default 1, as printed).
    nuisance : fault names moved into the unknown inputs (§2.4, (4)); ``()`` (default) none.  The
        faults of the model not listed are the targets.  (The paper's sentence after (4) swaps f₁
        and f₂; the construction is followed.)
    rows : rows of ``H_os1``; default :func:`regular_rows` at the mean of ``Re ρ``.

    Returns
    -------
    RobustCriteria

    Raises
    ------
    ParameterError
        Bad ``weights`` keys, ``nuisance='others'`` or unknown nuisance names, an unknown ``fault_model``.
    DesignError
        No target fault left; ``H_os`` of rank < n or ``H_os1`` ill-conditioned.

    Examples
    --------
    >>> from fdikit.plants import varrier_lateral_lpv, varrier_uncertainty
    >>> lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    >>> cr = robust_criteria(lpv, unc, [0.04, 0.05], 3)
    >>> cr.gamma1.shape, cr.gamma2.shape
    ((2, 6, 6), (2, 6, 6))

    References
    ----------
    Varrier et al. 2014, §2.4, (4); §4.1–4.2, (14), (18)–(20).
    """
    w = {"os": 1.0, "us": 1.0, "ds": 1.0, "ds_tilde": 1.0} | dict(weights or {})
    if set(w) != {"os", "us", "ds", "ds_tilde"}:
        raise ParameterError(f"weights keys must be 'os', 'us', 'ds', 'ds_tilde'; got {sorted(weights or {})}")
    if isinstance(nuisance, str) and nuisance == "others":
        raise ParameterError("robust_criteria's targets are the faults not in nuisance, so nuisance='others' leaves "
                             "none; list the nuisance faults by name")
    nuisance = (nuisance,) if isinstance(nuisance, str) else tuple(nuisance)
    unknown = [f for f in nuisance if f not in lpv.faults]
    if unknown:
        raise ParameterError(f"no fault named {unknown}; the model's faults are {list(lpv.faults)}")
    target = [i for i, f in enumerate(lpv.faults) if f not in nuisance]
    if not target:
        raise DesignError("no target fault left: every fault is a nuisance; keep at least one fault to detect")
    st = uncertain_stacked_matrices(lpv, uncertainties, rho, s, mode=mode, groups=("u", "d", "f"))
    if rows is None:
        ref = np.mean(np.asarray(rho).real) if mode == "frozen" else np.mean(np.asarray(rho).real, axis=tuple(
            range(np.ndim(rho) - 1)))
        rows = regular_rows(lpv_stacked_matrices(lpv, ref, s, mode=mode, groups=()).H_os.real)
    rows = tuple(int(i) for i in rows)
    P = parity_matrix(st.nominal.H_os, rows)
    nf, s1 = len(lpv.faults), s + 1
    tcols = [j * nf + i for j in range(s1) for i in target]
    ncols = [j * nf + i for j in range(s1) for i in range(nf) if i not in target]
    H_fs = st.nominal.H_fs[..., tcols]
    blocks = [np.sqrt(w["os"]) * st.tilde["os"][e] for e in st.monomials("os")]
    blocks += [np.sqrt(w["us"]) * st.tilde["u"][e] for e in st.monomials("u")]
    blocks += [np.sqrt(w["ds"]) * st.nominal.H_ds]
    blocks += [np.sqrt(w["ds_tilde"]) * st.tilde["d"][e] for e in st.monomials("d")]
    blocks += [st.nominal.H_fs[..., ncols]] + [st.tilde["f"][e][..., ncols] for e in st.monomials("f")]
    G = np.concatenate(blocks, axis=-1)
    ones = np.kron(np.ones((s1, 1)), np.eye(len(target)))
    Hc = H_fs @ ones
    if fault_model == "sequence":
        HF = H_fs
    elif fault_model == "constant":
        HF = Hc
    else:
        raise ParameterError(f"unknown fault_model {fault_model!r}; use 'sequence' (paper) or 'constant'")
    PG, PF = P @ G, P @ HF
    return RobustCriteria(PG @ _T(PG, -1, -2), PF @ _T(PF, -1, -2), P, G, H_fs, (P @ Hc).sum(axis=-1), rows)


# ---------------------------------------------------------------------------------------------- Theorem 1
@dataclass(frozen=True)
class EigenDesign:
    """Theorem 1: ``W2`` (unit norm) attains ``J = lambda_min``; ``eigenvalues`` are the finite λ(Γ₁, Γ₂).

    Attributes
    ----------
    lambda_min : float, the minimum of ``J``.
    W2 : (q,) array, the unit parity parameter attaining it.
    eigenvalues : array, the finite generalised eigenvalues, ascending.

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> theorem1(G1, G2).eigenvalues.round(6).tolist()
    [0.5, 1.0]

    References
    ----------
    Varrier et al. 2014, §4.3, Theorem 1, (21)–(23).
    """

    lambda_min: float
    W2: np.ndarray
    eigenvalues: np.ndarray


def theorem1(gamma1: np.ndarray, gamma2: np.ndarray, *, sign_ref: np.ndarray | None = None) -> EigenDesign:
    """Minimise ``W₂ᵀΓ₁W₂ / W₂ᵀΓ₂W₂`` by the generalised eigenproblem (Varrier et al. 2014, Theorem 1, (21)–(23)).

    ``scipy.linalg.eigh(Γ₂, Γ₁)`` gives ``μ``; ``λ = 1/μ`` and ``λ_min = 1/μ_max``.  If Γ₁ is
    singular the residual can decouple the uncertainty exactly: ``λ_min = 0`` and ``W₂``
    maximises Γ₂ on ``null Γ₁``.  The sign makes ``sign_ref · W₂ ≥ 0``.

    Parameters
    ----------
    gamma1, gamma2 : (q, q) array_like, ``Γ₁`` (positive semidefinite) and ``Γ₂``.
    sign_ref : (q,) array_like or None, the reference of the sign of ``W₂``.

    Returns
    -------
    EigenDesign

    Raises
    ------
    ParameterError
        ``Γ₁`` not square, or ``Γ₁`` and ``Γ₂`` of different sizes.
    DesignError
        ``Γ₂ = 0`` on the parity space (or on ``null Γ₁``): the fault is not detectable.

    Examples
    --------
    >>> import numpy as np
    >>> round(theorem1(np.diag([1.0, 2.0]), np.diag([1.0, 4.0])).lambda_min, 12)
    0.5

    References
    ----------
    Varrier et al. 2014, §4.3, Theorem 1, (21)–(23).
    """
    G1 = validate.as_square("gamma1 (Γ₁)", gamma1)
    G2 = validate.as_matrix("gamma2 (Γ₂)", gamma2)
    if G1.shape != G2.shape:
        raise ParameterError(f"Γ₁ and Γ₂ must be square matrices of one size, got gamma1 shape {G1.shape} and "
                             f"gamma2 shape {G2.shape}")
    G1, G2 = (G1 + G1.T) / 2, (G2 + G2.T) / 2
    scale = max(np.linalg.norm(G1, 2), np.finfo(float).tiny)
    e1 = np.linalg.eigvalsh(G1)
    if e1[0] > 1e-12 * scale:
        mu, V = scipy.linalg.eigh(G2, G1)
        if mu[-1] <= 1e-14 * np.linalg.norm(G2, 2) / scale or mu[-1] <= 0:
            raise DesignError("Γ₂ = 0 on the parity space: the fault does not reach the residual; it is not detectable")
        finite = np.sort(1.0 / mu[mu > 1e-12 * mu[-1]])
        lam, w = 1.0 / mu[-1], V[:, -1]
    else:
        N = scipy.linalg.null_space(G1, rcond=1e-12)
        mu, V = np.linalg.eigh(N.T @ G2 @ N)
        if mu[-1] <= 1e-14 * max(np.linalg.norm(G2, 2), np.finfo(float).tiny):
            raise DesignError("the fault is invisible on the null space of Γ₁ and Γ₂ = 0 there; not detectable")
        lam, w, finite = 0.0, N @ V[:, -1], np.array([0.0])
    w = w / np.linalg.norm(w)
    if sign_ref is not None and float(np.dot(sign_ref, w)) < 0:
        w = -w
    return EigenDesign(float(lam), w, finite)


def theorem1_batch(gamma1: np.ndarray, gamma2: np.ndarray, sign_ref: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Theorem 1 for a batch (..., q, q) by Cholesky whitening ``Γ₁ = L Lᵀ``: ``λ_min`` (...) and unit ``W₂`` (..., q).

    Same result as :func:`theorem1` (``eigh(L⁻¹Γ₂L⁻ᵀ)``); falls back to it when some Γ₁ is not
    positive definite.

    Parameters
    ----------
    gamma1, gamma2 : (..., q, q) array_like, stacks of ``Γ₁`` and ``Γ₂``.
    sign_ref : (..., q) array_like or None, per element the reference of the sign of ``W₂``.

    Returns
    -------
    lambda_min : (...) array
    W2 : (..., q) array, unit vectors.

    Raises
    ------
    DesignError
        From the :func:`theorem1` fallback, for a fault that is not detectable (the Cholesky path's
        ``LinAlgError`` is caught internally).

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> theorem1_batch(np.stack([G1, G1]), np.stack([G2, 2 * G2]))[0].round(6).tolist()
    [0.5, 0.25]

    References
    ----------
    Varrier et al. 2014, §4.3, Theorem 1, (21)–(23).
    """
    G1, G2 = np.asarray(gamma1, dtype=float), np.asarray(gamma2, dtype=float)
    shape, q = G1.shape[:-2], G1.shape[-1]
    G1, G2 = G1.reshape(-1, q, q), G2.reshape(-1, q, q)
    ref = None if sign_ref is None else np.asarray(sign_ref, dtype=float).reshape(-1, q)
    try:
        Li = np.linalg.inv(np.linalg.cholesky((G1 + _T(G1, 1, 2)) / 2))
        mu, V = np.linalg.eigh(Li @ ((G2 + _T(G2, 1, 2)) / 2) @ _T(Li, 1, 2))
        if np.any(mu[:, -1] <= 0):
            raise np.linalg.LinAlgError
        lam, w = 1.0 / mu[:, -1], np.einsum("kji,kj->ki", Li, V[:, :, -1])
        w /= np.linalg.norm(w, axis=1, keepdims=True)
        if ref is not None:
            w *= np.where(np.einsum("ki,ki->k", w, ref) < 0, -1.0, 1.0)[:, None]
    except np.linalg.LinAlgError:
        res = [theorem1(a, b, sign_ref=None if ref is None else ref[i]) for i, (a, b) in enumerate(zip(G1, G2))]
        lam, w = np.array([r.lambda_min for r in res]), np.array([r.W2 for r in res])
    return lam.reshape(shape), w.reshape(shape + (q,))


def pointwise_theorem1(lpv: LPVModel, uncertainties: Sequence[Uncertainty], s: int, *, rows: Sequence[int],
                       **criteria_kw) -> Callable[[np.ndarray], np.ndarray]:
    """``ρ ↦ W₂*(ρ)`` of Theorem 1 evaluated numerically per sample (the reference the paper avoids, §4.3).

    Returns a function of a 1-D array of ρ giving (N, q), signed so that the constant-fault
    response ``W₂ᵀ P H_fs 𝟙`` is ≥ 0; pass it as ``W2=`` to :func:`lpv_parity_residuals`.

    Parameters
    ----------
    lpv, uncertainties, s : as in :func:`robust_criteria`.
    rows : sequence of int, the rows of ``H_os1`` (fixed, so that ``P(ρ)`` is continuous in ρ).
    **criteria_kw : further keywords of :func:`robust_criteria`.

    Returns
    -------
    callable, ``rho (N,) -> W₂ (N, q)``.

    Examples
    --------
    >>> from fdikit.plants import varrier_lateral_lpv, varrier_uncertainty
    >>> lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    >>> w2 = pointwise_theorem1(lpv, unc, 3, rows=(0, 1))
    >>> w2([0.04, 0.05]).shape
    (2, 6)

    References
    ----------
    Varrier et al. 2014, §4.3, Theorem 1; (16).
    """
    def w2(rho: np.ndarray) -> np.ndarray:
        cr = robust_criteria(lpv, uncertainties, np.asarray(rho, dtype=float), s, rows=rows, **criteria_kw)
        return theorem1_batch(cr.gamma1, cr.gamma2, cr.fault_direction.reshape(len(cr.gamma1), -1))[1]

    return w2


# ---------------------------------------------------------------------------------------------- P2 and κ
def kappa_max(gamma1: np.ndarray, gamma2: np.ndarray) -> float:
    """Largest κ with ``Γ₁ − κ²Γ₂ ≻ 0``: ``sqrt(min λ_min(Γ₁, Γ₂))`` over the batch (Remark 4, re-derived).

    Parameters
    ----------
    gamma1, gamma2 : (..., q, q) array_like, ``Γ₁`` and ``Γ₂`` (one pair or a stack).

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> round(kappa_max(G1, G2), 6)
    0.707107

    References
    ----------
    Varrier et al. 2014, §4.4.1, Remark 4.
    """
    return float(np.sqrt(np.min(theorem1_batch(gamma1, gamma2)[0])))


def gamma_kappa(gamma1: np.ndarray, gamma2: np.ndarray, kappa: float) -> np.ndarray:
    """``Γ_κ = Γ₁ − κ²Γ₂`` (Varrier et al. 2014, (25)); DesignError unless it is positive definite.

    Parameters
    ----------
    gamma1, gamma2 : (..., q, q) array_like, ``Γ₁`` and ``Γ₂``.
    kappa : float, ``κ >= 0``.

    Returns
    -------
    (..., q, q) array

    Raises
    ------
    DesignError
        If ``κ² ≥ λ_min(Γ₁, Γ₂)``; the message gives the largest valid κ.

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> gamma_kappa(G1, G2, 0.5).tolist()
    [[0.75, 0.0], [0.0, 1.0]]

    References
    ----------
    Varrier et al. 2014, §4.4.1, (24)–(25), Remark 4.
    """
    k_max = kappa_max(gamma1, gamma2)
    if not (np.isfinite(kappa) and 0 <= kappa < k_max):
        raise DesignError(
            f"Γ_κ = Γ₁ − κ²Γ₂ is not positive definite for κ = {kappa:g}: it needs κ² < λ_min(Γ₁, Γ₂), "
            f"so κ < κ_max = {k_max:.6g} (Remark 4). Choose κ below {k_max:.6g}"
        )
    return np.asarray(gamma1) - kappa**2 * np.asarray(gamma2)


def p2_solution(gamma1: np.ndarray, gamma2: np.ndarray, kappa: float, c: np.ndarray) -> np.ndarray:
    """Closed form of 𝒫₂ (24) with ``cᵀW₂ = 1``: ``W₂ = Γ_κ⁻¹c / (cᵀΓ_κ⁻¹c)`` (Lagrange; re-derived).

    Parameters
    ----------
    gamma1, gamma2 : (q, q) array_like, ``Γ₁`` and ``Γ₂``.
    kappa : float, ``0 <= κ < κ_max``.
    c : (q,) array_like, the normalisation vector.

    Returns
    -------
    (q,) array, ``W₂`` with ``cᵀW₂ = 1``.

    Examples
    --------
    >>> import numpy as np
    >>> G1, G2 = np.diag([1.0, 2.0]), np.diag([1.0, 4.0])
    >>> p2_solution(G1, G2, 0.5, np.ones(2)).round(6).tolist()
    [0.571429, 0.428571]

    References
    ----------
    Varrier et al. 2014, §4.4, (24); §4.4.1, (28).
    """
    Gk = gamma_kappa(gamma1, gamma2, kappa)
    x = np.linalg.solve(Gk, np.asarray(c, dtype=float))
    return x / float(np.dot(c, x))


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

    def residuals(self, trace: Trace, rho, *, mode: str = "frozen", name: str = "robust_parity") -> Residuals:
        """The U-LPV residual (16) of a trace (see :func:`lpv_parity_residuals`)."""
        return lpv_parity_residuals(self.lpv, trace, rho, self.s, W2=self.w2, mode=mode, rows=self.rows,
                                    names=[name])

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
        repaired, n_rep, gamma, degrees, 2 ** degrees["adjugate"], err, dict(criteria_kw),
    )
