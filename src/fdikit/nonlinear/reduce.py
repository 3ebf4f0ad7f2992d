"""Model reduction of a FaultModel: exact minimal realisation, residualisation, balanced truncation.

Douglas et al. 1996, Ch. 2 §2.3 reduce the linearised vehicle model in three steps: the uncontrollable and
unobservable part is removed exactly (32 → 22 states), then either the fast modes are residualised ("method 1":
set their derivatives to zero, which keeps the static gain) or the balanced realisation is truncated ("method 2",
Moore 1981, with the error bound twice the sum of the discarded Hankel singular values); Table 2.1 compares the
eigenvalues of the two 14-state models.

Written on numpy/scipy rather than on python-control's ``minreal`` / ``balred`` (which the tests use as
references) because the results keep what those drop: the names and groups of every input and output, the bases
that map the reduced states back to the original ones, and the removed eigenvalues; and because the square-root
balancing here puts the Hankel singular values of a non-minimal model at rounding level (~1e-15 on the test model,
where ``control.hsvd`` gives ~1e-8), which the order checks rely on.

Every function keeps the names of the outputs and of the inputs of every group (``u``, ``d``, ``f``, ``w``); all
inputs of all groups count as inputs (controllability from every column of ``B``, Hankel singular values of the
map from every input). The states of a reduced model are new coordinates named ``z0, z1, …`` (the result gives
the basis that maps them to the original states), except in :func:`residualize` with named states kept, where the
kept physical states keep their names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import GROUPS, FaultModel

__all__ = ["MinimalResult", "ResidualizedResult", "BalancedResult", "minimal", "residualize",
           "balanced_truncation"]


# ---------------------------------------------------------------------------------------------- helpers
def _check_model(model) -> FaultModel:
    return validate.instance("model", model, FaultModel, "build one with FaultModel(A=..., C=..., Bu=...) or "
                             "FaultModel.from_control(sys)", error=ModelError)


def _rebuild(model: FaultModel, A, B, C, D, states) -> FaultModel:
    """The model with new matrices and state names, keeping output and input names and groups."""
    if A.shape[0] == 0 and model.p:
        raise DesignError("the reduced model would have no state (its transfer function is the constant D); a "
                          "FaultModel with outputs needs at least one state")
    kw = {"A": A, "C": C, "states": list(states)}
    start = 0
    for g in GROUPS:
        k = len(model.inputs[g])
        kw[f"B{g}"], kw[f"D{g}"] = B[:, start:start + k], D[:, start:start + k]
        start += k
    return model.replace(**kw)


def _z_names(r: int) -> list[str]:
    return [f"z{i}" for i in range(r)]


def _staircase(A: np.ndarray, B: np.ndarray, rtol: float) -> tuple[np.ndarray, int]:
    """Orthogonal ``Q`` and ``r`` with ``QᵀAQ = [[A11, A12], [0, A22]]``, ``QᵀB = [[B1], [0]]``, (A11, B1) controllable.

    The controllability staircase (Van Dooren 1981) with singular values below ``rtol · max(‖A‖₂, ‖B‖₂)`` counted
    as zero.
    """
    from fdikit.descriptor.staircase import controllability_staircase

    scale = max(np.linalg.norm(A, 2) if A.shape[0] else 0.0, np.linalg.norm(B, 2) if B.size else 0.0)
    return controllability_staircase(A, B, rtol * scale)


def _ordered_schur(A: np.ndarray, slow: np.ndarray, dt) -> tuple[np.ndarray, np.ndarray, int]:
    """Real Schur form with the ``slow`` eigenvalues first, then the block-diagonalising similarity.

    Returns ``V`` (n x n) and ``W = V⁻¹`` with ``W A V = diag(A11, A22)``, and the size of ``A11``.
    """
    n = A.shape[0]
    lam = scipy.linalg.eigvals(A)
    k = int(np.sum(slow))
    threshold = np.sort(_speed(lam, dt))[k - 1] if k else -np.inf
    # sort by speed with the tie rule of the caller: a mode is slow when its speed is <= threshold
    T, Z, sdim = scipy.linalg.schur(A, output="real", sort=lambda re, im: _speed(np.array([re + 1j * im]), dt)[0]
                                    <= threshold * (1 + 1e-12) + 1e-300)
    if sdim != k:
        raise DesignError(f"the split between kept and residualised modes cuts a complex pair or a cluster of equal "
                          f"speeds ({sdim} modes are at most as fast as the slowest kept one, asked {k}); keep "
                          f"{sdim} states or choose another cut")
    T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
    X = scipy.linalg.solve_sylvester(T11, -T22, -T12) if 0 < k < n else np.zeros((k, n - k))
    S = np.eye(n)
    S[:k, k:] = X
    Sinv = np.eye(n)
    Sinv[:k, k:] = -X
    return Z @ S, Sinv @ Z.T, k


def _speed(lam: np.ndarray, dt) -> np.ndarray:
    """Speed of a mode in rad/s: ``|λ|`` in continuous time, ``|ln λ| / dt`` in discrete time."""
    lam = np.asarray(lam, dtype=complex)
    if dt is None:
        return np.abs(lam)
    with np.errstate(divide="ignore"):
        return np.abs(np.log(lam)) / dt


# ---------------------------------------------------------------------------------------------- results
@dataclass(frozen=True)
class MinimalResult:
    """Minimal realisation of a FaultModel (exact: same transfer function from every input).

    Attributes
    ----------
    model : FaultModel
        The minimal model; states ``z0, …`` with ``z = basisᵀ x``.
    basis : numpy.ndarray
        Orthonormal n x r basis of the kept (controllable and observable) coordinates.
    uncontrollable : numpy.ndarray
        Eigenvalues of the part not reachable from any input of any group.
    unobservable : numpy.ndarray
        Eigenvalues of the controllable but unobservable part.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> res = minimal(FaultModel(A=[[-1.0, 0.0], [0.0, -2.0]], C=[[1.0, 1.0]], Bu=[[1.0], [0.0]]))
    >>> res.model.n, res.removed
    (1, array([-2.+0.j]))

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 (the exact 32 → 22 reduction before Table 2.1).
    """

    model: FaultModel
    basis: np.ndarray
    uncontrollable: np.ndarray
    unobservable: np.ndarray

    @property
    def removed(self) -> np.ndarray:
        """All removed eigenvalues (uncontrollable, then unobservable)."""
        return np.concatenate([self.uncontrollable, self.unobservable])


@dataclass(frozen=True)
class ResidualizedResult:
    """Singular-perturbation (residualised) model: fast states set to their quasi-steady state.

    Attributes
    ----------
    model : FaultModel
        The reduced model (same static gain as the full one).
    kept : numpy.ndarray
        Eigenvalues of the slow part ``A11`` before the correction (in the modal split, exactly the reduced model's
        eigenvalues).
    removed : numpy.ndarray
        Eigenvalues of the residualised fast part ``A22``.
    basis : numpy.ndarray
        n x r matrix whose columns span the kept coordinates: the slow invariant subspace of ``A`` in the modal
        split, the unit vectors of the kept states in the physical split.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> res = residualize(FaultModel(A=[[-1.0, 0.0], [0.0, -100.0]], C=[[1.0, 1.0]], Bu=[[1.0], [100.0]]), 1)
    >>> res.model.n, res.removed
    (1, array([-100.+0.j]))

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 ("method one"), Table 2.1.
    """

    model: FaultModel
    kept: np.ndarray
    removed: np.ndarray
    basis: np.ndarray


@dataclass(frozen=True)
class BalancedResult:
    """Balanced truncation of a stable FaultModel.

    Attributes
    ----------
    model : FaultModel
        The truncated balanced model; states ``z0, …`` (balanced coordinates, ``z = left @ x``).
    hankel : numpy.ndarray
        All Hankel singular values of the full model, decreasing.
    error_bound : float
        ``2 Σ`` of the discarded Hankel singular values, a bound on ``‖G − G_r‖∞`` (Moore 1981; Glover 1984).
    left, right : numpy.ndarray
        The projection: ``A_r = left @ A @ right`` with ``left @ right = I``.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> res = balanced_truncation(FaultModel(A=[[-1.0, 0.0], [0.0, -10.0]], C=[[1.0, 0.1]], Bu=[[1.0], [0.1]]), 1)
    >>> res.model.n, round(res.error_bound, 6)
    (1, 0.000669)

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 ("method two"), Table 2.1.
    """

    model: FaultModel
    hankel: np.ndarray
    error_bound: float
    left: np.ndarray
    right: np.ndarray

    @property
    def discarded(self) -> np.ndarray:
        """The discarded Hankel singular values."""
        return self.hankel[self.model.n:]


# ---------------------------------------------------------------------------------------------- minimal
def minimal(model: FaultModel, *, rtol: float = 1e-10) -> MinimalResult:
    """Remove the uncontrollable and the unobservable part exactly (Kalman decomposition, orthonormal bases).

    The controllable subspace (from all inputs of every group) is found by the orthogonal staircase, then the
    observable part of the controllable system by the same algorithm on the dual; both are orthonormal similarity
    transformations, so the transfer function is unchanged.

    Parameters
    ----------
    model : FaultModel
        Continuous or discrete model.
    rtol : float, default 1e-10
        Rank tolerance relative to the data: a singular value of a staircase block below
        ``rtol · max(‖A‖₂, ‖B‖₂)`` (or ``‖C‖₂`` on the dual) counts as zero.

    Returns
    -------
    MinimalResult
        The minimal model (states ``z0, …``), the basis and the removed eigenvalues.

    Raises
    ------
    ModelError
        If ``model`` is not a FaultModel.
    ParameterError
        If ``rtol`` is not in (0, 1).
    DesignError
        If no state is both controllable and observable (the transfer function is the constant ``D``).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=[[-1.0, 0.0], [0.0, -3.0]], C=[[1.0, 0.0]], Bu=[[1.0], [1.0]], outputs=["pos"])
    >>> res = minimal(m)
    >>> res.model.n, res.model.outputs, res.unobservable
    (1, ('pos',), array([-3.+0.j]))

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 (the exact reduction before Table 2.1); Van Dooren 1981 (staircase).
    """
    model = _check_model(model)
    validate.in_range("rtol (the rank tolerance)", rtol, 0.0, 1.0, closed="neither")
    A, B, C = model.A, model.B, model.C
    Q1, nc = _staircase(A, B, rtol)
    At = Q1.T @ A @ Q1
    unc = scipy.linalg.eigvals(At[nc:, nc:]) if nc < model.n else np.zeros(0, complex)
    Ac, Cc = At[:nc, :nc], C @ Q1[:, :nc]
    Q2, no = _staircase(Ac.T, Cc.T, rtol)
    Ao = Q2.T @ Ac @ Q2
    uno = scipy.linalg.eigvals(Ao[no:, no:]) if no < nc else np.zeros(0, complex)
    V = Q1[:, :nc] @ Q2[:, :no]
    reduced = _rebuild(model, V.T @ A @ V, V.T @ B, C @ V, model.D, _z_names(no))
    return MinimalResult(model=reduced, basis=V, uncontrollable=np.sort_complex(unc), unobservable=np.sort_complex(uno))


# ---------------------------------------------------------------------------------------------- residualize
def residualize(model: FaultModel, keep: int | Sequence[str] | None = None, *, cut: float | None = None
                ) -> ResidualizedResult:
    """Singular-perturbation reduction: set the fast states' derivatives to zero and eliminate them.

    With ``x = (x1, x2)`` and ``x2`` fast, ``ẋ2 = 0`` gives ``x2 = −A22⁻¹ (A21 x1 + B2 u)`` and

    ``A_r = A11 − A12 A22⁻¹ A21``, ``B_r = B1 − A12 A22⁻¹ B2``, ``C_r = C1 − C2 A22⁻¹ A21``,
    ``D_r = D − C2 A22⁻¹ B2``,

    which keeps the static gain ``G(0)`` exactly (Douglas et al. 1996, §2.3). A discrete model uses ``x2⁺ = x2``
    (``A22`` replaced by ``A22 − I``), which keeps ``G(1)``.

    The split is either physical — ``keep`` a sequence of state names, the others residualised (as the report's
    method 1 drops the wheel speeds and suspension forces) — or modal: ``keep`` the number of slowest modes kept,
    or ``cut`` a speed (rad/s; ``|λ|``, or ``|ln λ|/dt`` in discrete time) with modes at most that fast kept. The
    modal split block-diagonalises ``A`` by an ordered real Schur form and a Sylvester equation, so ``A12 = A21 =
    0``: the reduced model's eigenvalues are exactly the kept ones, and its states ``z0, …`` are the slow modal
    coordinates.

    Parameters
    ----------
    model : FaultModel
        Continuous or discrete model.
    keep : int or sequence of str, optional
        Number of slow modes kept (at least 1), or the names of the states kept.
    cut : float, optional
        Speed (rad/s) of the fastest mode kept; instead of ``keep``.

    Returns
    -------
    ResidualizedResult
        The reduced model, the kept and removed eigenvalues, the basis.

    Raises
    ------
    ModelError
        If ``model`` is not a FaultModel or a state name is unknown.
    ParameterError
        If neither or both of ``keep`` and ``cut`` are given, or ``keep`` is out of range.
    DesignError
        If the fast part is singular (``A22`` with an eigenvalue at 0, discrete: at 1), the modal split cuts a
        complex pair, or ``cut`` keeps no mode.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=[[-1.0, 1.0], [0.0, -50.0]], C=[[1.0, 0.0]], Bu=[[0.0], [50.0]])
    >>> res = residualize(m, cut=10.0)
    >>> res.model.poles(), np.allclose(res.model.freqresp([0.0]), m.freqresp([0.0]))
    (array([-1.+0.j]), True)

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 ("method one"), Table 2.1; Kokotović, Khalil and O'Reilly 1986.
    """
    model = _check_model(model)
    n = model.n
    if (keep is None) == (cut is None):
        raise ParameterError("give exactly one of keep (a number of slow modes, or state names) and cut (a speed "
                             f"in rad/s); got keep={keep!r}, cut={cut!r}")
    lam = scipy.linalg.eigvals(model.A) if n else np.zeros(0, complex)
    if keep is not None and not isinstance(keep, int | np.integer):
        if isinstance(keep, str):
            keep = [keep]
        if not isinstance(keep, Sequence) or not all(isinstance(nm, str) for nm in keep):
            raise ParameterError(f"keep must be a number of slow modes (int) or a sequence of state names, got "
                                 f"{validate.shown(keep)} ({type(keep).__name__})")
        idx = model.index("states", list(keep))
        if len(set(idx)) != len(idx):
            raise ParameterError(f"keep names a state twice: {list(keep)}")
        rest = [i for i in range(n) if i not in idx]
        perm = idx + rest
        V = np.eye(n)[:, perm]
        W = V.T
        k = len(idx)
        names = [model.states[i] for i in idx]
    else:
        if cut is not None:
            cut = validate.positive("cut (a speed in rad/s)", cut)
            k = int(np.sum(_speed(lam, model.dt) <= cut))
        else:
            k = validate.integer("keep (the number of slow modes)", keep, minimum=1)
            if k > n:
                raise ParameterError(f"keep must be at most the model's {n} states, got {k}")
        slow = np.zeros(n, bool)
        slow[np.argsort(_speed(lam, model.dt), kind="stable")[:k]] = True
        V, W, k = _ordered_schur(model.A, slow, model.dt) if n else (np.eye(0), np.eye(0), 0)
        names = _z_names(k)
    At, Bt, Ct = W @ model.A @ V, W @ model.B, model.C @ V
    A11, A12, A21, A22 = At[:k, :k], At[:k, k:], At[k:, :k], At[k:, k:]
    B1, B2, C1, C2 = Bt[:k], Bt[k:], Ct[:, :k], Ct[:, k:]
    fast = scipy.linalg.eigvals(A22) if k < n else np.zeros(0, complex)
    M = A22 - np.eye(n - k) if model.is_discrete else A22
    if k < n:
        sv = np.linalg.svd(M, compute_uv=False)
        if sv[-1] <= n * np.finfo(float).eps * max(sv[0], np.linalg.norm(model.A, 2)):
            where = "1 (discrete)" if model.is_discrete else "0"
            raise DesignError(f"the residualised part has an eigenvalue at {where} (smallest singular value of "
                              f"A22{' - I' if model.is_discrete else ''} is {sv[-1]:.3g}); its quasi-steady state "
                              "is undefined: keep that state")
        XA, XB = np.linalg.solve(M, A21), np.linalg.solve(M, B2)
        Ar, Br, Cr, Dr = A11 - A12 @ XA, B1 - A12 @ XB, C1 - C2 @ XA, model.D - C2 @ XB
    else:
        Ar, Br, Cr, Dr = A11, B1, C1, model.D
    kept = scipy.linalg.eigvals(A11) if k else np.zeros(0, complex)
    reduced = _rebuild(model, Ar, Br, Cr, Dr, names)
    return ResidualizedResult(model=reduced, kept=np.sort_complex(kept), removed=np.sort_complex(fast),
                              basis=V[:, :k])


# ---------------------------------------------------------------------------------------------- balanced
def _gram_factor(A, M, discrete: bool) -> np.ndarray:
    """A factor ``L`` with ``L Lᵀ = P``, ``P`` the Gramian of ``(A, M)`` (``A P + P Aᵀ + M Mᵀ = 0``)."""
    if discrete:
        P = scipy.linalg.solve_discrete_lyapunov(A, M @ M.T)
    else:
        P = scipy.linalg.solve_continuous_lyapunov(A, -M @ M.T)
    w, U = np.linalg.eigh((P + P.T) / 2)
    w[w <= A.shape[0] * np.finfo(float).eps * max(w.max(initial=0.0), 0.0)] = 0.0  # rounding-level directions
    return U * np.sqrt(w)


def balanced_truncation(model: FaultModel, order: int | None = None, *, tol: float | None = None) -> BalancedResult:
    """Balanced truncation (Moore 1981) by the square-root algorithm, with its H∞ error bound.

    The Gramians of the map from every input to every output are factored, ``P = Lc Lcᵀ``, ``Q = Lo Loᵀ``; the SVD
    ``Loᵀ Lc = U Σ Vᵀ`` gives the Hankel singular values ``σ_i`` and the projection ``left = Σ₁^{-1/2} U₁ᵀ Loᵀ``,
    ``right = Lc V₁ Σ₁^{-1/2}`` onto the ``r`` largest. ``D`` is kept; ``‖G − G_r‖∞ ≤ 2 Σ_{i>r} σ_i``. The Hankel
    singular values depend on the scaling of the inputs and outputs (scale them first if the groups' units
    differ).

    Only stable models are reduced: an unstable (or marginally stable) model is refused, because its Gramians do
    not exist; reduce its stable part yourself (split by :func:`residualize`'s modal basis) if needed.

    Parameters
    ----------
    model : FaultModel
        Stable continuous (or Schur-stable discrete) model.
    order : int, optional
        Number of states kept.
    tol : float, optional
        Instead of ``order``: the smallest order (at least 1) whose error bound ``2 Σ`` of the discarded ``σ_i`` is
        ``<= tol``.

    Returns
    -------
    BalancedResult
        The reduced model (balanced states ``z0, …``), all Hankel singular values and the error bound.

    Raises
    ------
    ModelError
        If ``model`` is not a FaultModel.
    ParameterError
        If neither or both of ``order`` and ``tol`` are given, or ``order`` exceeds the number of numerically
        nonzero Hankel singular values (above ``100 n ε σ₁``; the rest belongs to the non-minimal part).
    DesignError
        If the model is not asymptotically stable (the message gives the eigenvalue).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=[[-1.0, 0.0], [0.0, -10.0]], C=[[1.0, 0.1]], Bu=[[1.0], [0.1]])
    >>> res = balanced_truncation(m, tol=0.01)
    >>> res.model.n, [round(float(v), 6) for v in res.hankel]
    (1, [0.500165, 0.000335])

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.3 ("method two"), Table 2.1; Moore 1981; Glover 1984 (error bound).
    """
    model = _check_model(model)
    n = model.n
    if (order is None) == (tol is None):
        raise ParameterError(f"give exactly one of order (states kept) and tol (an H∞ error bound); got "
                             f"order={order!r}, tol={tol!r}")
    lam = scipy.linalg.eigvals(model.A) if n else np.zeros(0, complex)
    margin = (np.abs(lam) - 1.0) if model.is_discrete else lam.real
    if n and margin.max() >= -np.finfo(float).eps ** 0.5 * max(1.0, np.abs(lam).max()):
        worst = lam[np.argmax(margin)]
        where = "on or outside the unit circle" if model.is_discrete else "in the closed right half-plane"
        raise DesignError(f"balanced truncation needs a stable model; eigenvalue {worst:.6g} lies {where} (its "
                          "Gramians do not exist). Reduce the stable part only, or stabilise first")
    A, B, C = model.A, model.B, model.C
    Lc = _gram_factor(A, B, model.is_discrete)
    Lo = _gram_factor(A.T, C.T, model.is_discrete)
    U, s, Vt = np.linalg.svd(Lo.T @ Lc)
    positive = int(np.sum(s > s[0] * 100 * n * np.finfo(float).eps)) if n and s[0] > 0 else 0
    if order is not None:
        r = validate.integer("order (states kept)", order, minimum=1)
        if r > positive:
            raise ParameterError(f"order {r} exceeds the {positive} nonzero Hankel singular values (of {n} states); "
                                 "the rest is uncontrollable or unobservable: use at most that order")
    else:
        tol = validate.non_negative("tol (the H∞ error bound)", tol)
        tails = 2 * np.concatenate([np.cumsum(s[::-1])[::-1], [0.0]])
        r = int(np.argmax(tails <= tol))
        r = max(min(r, positive), 1)
    s1 = s[:r] ** -0.5
    left = s1[:, None] * (U[:, :r].T @ Lo.T)
    right = (Lc @ Vt[:r].T) * s1[None, :]
    reduced = _rebuild(model, left @ A @ right, left @ B, C @ right, model.D, _z_names(r))
    return BalancedResult(model=reduced, hankel=s, error_bound=float(2 * s[r:].sum()), left=left, right=right)
