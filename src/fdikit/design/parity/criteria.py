"""Robustness criteria of the uncertain-LPV parity design: Γ₁, Γ₂, Theorem 1, κ and 𝒫₂ (Varrier et al. 2014,
§4.1–4.4).

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

The stacked and δ-expanded matrices (14) come from :mod:`fdikit.lpv`, the parity matrix from
:mod:`fdikit.design.parity.state_space`.  The LMI form of 𝒫₂ is in :mod:`fdikit.design.parity.lmi`, the
LPV design that schedules ``W₂(ρ)`` in :mod:`fdikit.design.parity.robust`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.design.parity.state_space import parity_matrix, regular_rows
from fdikit.errors import DesignError, ParameterError
from fdikit.lpv import LPVModel, Uncertainty, lpv_stacked_matrices, uncertain_stacked_matrices

__all__ = [
    "RobustCriteria", "robust_criteria", "EigenDesign", "theorem1", "theorem1_batch", "pointwise_theorem1",
    "kappa_max", "gamma_kappa", "p2_solution",
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
    response ``W₂ᵀ P H_fs 𝟙`` is ≥ 0; pass it as ``W2=`` to
    :func:`~fdikit.design.parity.state_space.lpv_parity_residuals`.

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
