"""The H∞ least-distance problem by Chu–Doyle–Lee's γ-iteration and optimal Nehari approximation (``glinfldp``).

``min ‖Y R_i − F‖∞`` over stable ``Y``, with ``R_i`` co-inner (``R_i R_i~ = I``) and ``F`` stable, is the 2-block
distance problem ``min ‖[F₁ − Y, F₂]‖∞`` with ``F₁ = F R_i~`` and ``F₂ F₂~ = F F~ − F₁ F₁~`` (the complementary
inner factor is not needed).  For ``γ > ‖F₂‖∞`` the co-spectral factor ``V`` (stable, stable inverse) of

    ``Φ_γ = γ² I − F F~ + F₁ F₁~ = V V~``

reduces it to a 1-block problem: ``γ`` is achievable when the antistable part of ``V⁻¹ F₁`` has Hankel norm below
1, and then ``Y = V · N(V⁻¹ F₁)``, ``N`` the optimal Nehari approximation (Glover's all-pass construction), has
``‖[F₁ − Y, F₂]‖∞ ≤ γ``.  Bisection on ``γ`` gives the optimum to ``reltol``.

This is the reference's route (``glinfldp``: ``glsfg``, ``gnehari``).  Where the optimal ``Y`` is not unique
(``γ_opt = ‖F₂‖∞``, e.g. Example 5.6c) it fixes the same member of the family the reference returns; the central
controller of the equivalent H∞ plant (SLICOT ``SB10AD``) is another member, with other sensitivities.

Steps: the stable part ``Z`` of ``F₁ F₁~ − F F~`` once (ordered Schur form and a Sylvester equation, then a
minimal realisation), so ``Φ_γ = Z + Z~ + γ² I`` and ``V = (A_Z, L, C_Z, I) R₀^½`` with ``R₀ = Φ_γ(∞)`` and ``L``
from the stabilising solution of the filter Riccati equation of that positive-real split (scipy's
``solve_continuous_are``); the Nehari step on the balanced realisation of the mirrored antistable part.
Continuous time; ``least_distance`` maps discrete problems by the bilinear transform.

Why by hand: no Python library solves 2-block distance problems or optimal Nehari approximations (SLICOT
``AB09CD`` returns only the stable part of a Hankel-norm approximation, not the antistable one Nehari needs).

References
----------
Varga (2017), §5.6 (Procedure AMMS, step 4), §7.10 (the 2-block least-distance problem, Chu–Doyle–Lee's method;
the Nehari problem); Chu, Doyle and Lee (1986); Glover (1984); fdtools (``glinfldp``, ``gnehari``, ``glsfg``).
"""

from __future__ import annotations

import numpy as np

from fdikit.design.nullspace.factorization import inverse, realization, series
from fdikit.errors import DesignError

__all__ = ["distance_error", "nehari", "two_block_distance"]


def _difference(first, second):
    """``first − second`` on the states of both."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [np.zeros((n2, n1)), A2]])
    return A, np.vstack([B1, B2]), np.hstack([C1, -C2]), D1 - D2


def distance_error(inner, Y, F):
    """``Y R_i − F`` as one realisation (states of ``R_i``, ``Y``, then ``F``): the error of a least-distance ``Y``.

    Parameters
    ----------
    inner, Y, F : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``R_i``, ``Y`` and ``F``.

    Returns
    -------
    tuple of numpy.ndarray

    Examples
    --------
    ``R_i = 1``, ``Y = 2`` and ``F = 1/(s+1) + 0.5``:

    >>> static = lambda d: (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[d]])
    >>> A, B, C, D = distance_error(static(1.0), static(2.0), ([[-1.0]], [[1.0]], [[1.0]], [[0.5]]))
    >>> A.shape, C.tolist(), D.tolist()
    ((1, 1), [[-1.0]], [[1.5]])

    References
    ----------
    Varga (2017), §7.10 (the least-distance problem).
    """
    return _difference(series(inner, Y), realization(*F))


def _split(A, B, C, D, margin: float = 0.0):
    """``G = G_s + G_u``: poles left (``G_s``, with ``D``) and right (``G_u``, ``D = 0``) of ``margin``."""
    import scipy.linalg as sla

    n = A.shape[0]
    if n == 0:
        return (A, B, C, D), (A, B, C, np.zeros_like(D))
    T, Z, k = sla.schur(A, output="real", sort=lambda x, y: x < margin)
    A11, A12, A22 = T[:k, :k], T[:k, k:], T[k:, k:]
    X = sla.solve_sylvester(A11, -A22, -A12) if 0 < k < n else np.zeros((k, n - k))
    Bt, Ct = Z.T @ B, C @ Z
    Bs, Bu = Bt[:k] - X @ Bt[k:], Bt[k:]
    Cs, Cu = Ct[:, :k], Ct[:, :k] @ X + Ct[:, k:]
    return (A11, Bs, Cs, D), (A22, Bu, Cu, np.zeros_like(D))


def _conjugate(A, B, C, D):
    """``G~(s) = G(−s)ᵀ``."""
    return -A.T, -C.T, B.T, D.T


def _hankel_gramians(A, B, C):
    import scipy.linalg as sla

    P = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Q = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
    return P, Q


def _psd_root(P):
    """``L`` with ``L Lᵀ = P`` for a symmetric positive semidefinite ``P`` (eigenvalues clipped at 0)."""
    w, U = np.linalg.eigh(0.5 * (P + P.T))
    return U * np.sqrt(np.clip(w, 0.0, None))


def _antistable_hankel_norm(A, B, C) -> float:
    """The Hankel norm of ``G_u~`` for an antistable ``G_u = (A, B, C, 0)``."""
    if A.shape[0] == 0:
        return 0.0
    P, Q = _hankel_gramians(-A, B, C)     # G_u(−s) = (−A, −B, C, 0): the sign of B does not change the Gramians
    return float(np.sqrt(max(np.max(np.linalg.eigvals(P @ Q).real), 0.0)))


def nehari(A, B, C, D):
    """The optimal stable approximation ``X`` of ``G``: ``‖G − X‖∞ = σ₁``, the Hankel norm of ``G``'s antistable part.

    Parameters
    ----------
    A, B, C, D : array_like
        ``G`` (continuous, no poles on the imaginary axis).

    Returns
    -------
    tuple
        ``((A, B, C, D) of X, σ₁)``: ``X`` is ``G``'s stable part (with ``D``) plus the optimal (zeroth-order
        Hankel-norm) stable approximation of its antistable part ``G_u`` (Glover's formulas on the balanced
        realisation of ``G_u(−s)``, the largest Hankel singular value with its multiplicity).

    Raises
    ------
    DesignError
        Poles on the imaginary axis.

    Examples
    --------
    ``G = 1/(1 − s)``: ``X = 1/2``, ``‖G − X‖∞ = 1/2`` (an all-pass error).

    >>> (Ax, Bx, Cx, Dx), s1 = nehari([[1.0]], [[1.0]], [[-1.0]], [[0.0]])
    >>> Ax.shape, round(float(Dx[0, 0]), 12), round(s1, 12)
    ((0, 0), 0.5, 0.5)

    References
    ----------
    Glover (1984); Varga (2017), §7.10; fdtools (``gnehari``).
    """
    A, B, C, D = realization(A, B, C, D)
    if A.shape[0] and np.min(np.abs(np.linalg.eigvals(A).real)) <= 1e-10 * max(1.0, np.linalg.norm(A, 1)):
        raise DesignError("the Nehari approximation needs a system without poles on the imaginary axis")
    (As, Bs, Cs, Ds), (Au, Bu, Cu, _) = _split(A, B, C, D)
    if Au.shape[0] == 0:
        return (As, Bs, Cs, Ds), 0.0
    # H(s) = G_u(−s) = (−A_u, −B_u, C_u, 0), stable; balanced realisation by the square-root method, Hankel
    # singular values below 1e-10 σ₁ truncated (an error of at most twice their sum: a minimal realisation at a
    # coarser rank tolerance dropped modes that mattered on badly scaled realisations)
    Ah, Bh, Ch = -Au, -Bu, Cu
    P, Q = _hankel_gramians(Ah, Bh, Ch)
    Lp, Lq = _psd_root(P), _psd_root(Q)
    U, s, Vt = np.linalg.svd(Lq.T @ Lp)
    k = int(np.sum(s > 1e-10 * s[0])) if s.size and s[0] > 0 else 0
    if k == 0:
        return (As, Bs, Cs, Ds), 0.0
    U, s, Vt = U[:, :k], s[:k], Vt[:k]
    Ti = np.diag(s ** -0.5) @ U.T @ Lq.T          # x_bal = Ti x
    T = Lp @ Vt.T @ np.diag(s ** -0.5)
    Ab, Bb, Cb = Ti @ Ah @ T, Ti @ Bh, Ch @ T
    s1 = float(s[0])
    r = int(np.sum(np.abs(s - s1) <= 1e-8 * s1))
    B1, B2, C1, C2 = Bb[:r], Bb[r:], Cb[:, :r], Cb[:, r:]
    Uf = -np.linalg.lstsq(C1.T, B1, rcond=None)[0]             # B₁ = −C₁ᵀ U
    S2 = np.diag(s[r:])
    Gam = S2 @ S2 - s1 ** 2 * np.eye(len(s) - r)
    A22 = Ab[r:, r:]
    Ahat = np.linalg.solve(Gam, s1 ** 2 * A22.T + S2 @ A22 @ S2 - s1 * C2.T @ Uf @ B2.T) if r < len(s) else A22
    Bhat = np.linalg.solve(Gam, S2 @ B2 + s1 * C2.T @ Uf) if r < len(s) else B2
    Chat = C2 @ S2 + s1 * Uf @ B2.T
    Dhat = -s1 * Uf
    # H − Ĥ is all-pass of gain σ₁ and Ĥ antistable, so X_u(s) = Ĥ(−s) is stable and ‖G_u − X_u‖∞ = σ₁
    Ax, Bx, Cx = -Ahat, -Bhat, Chat
    n1, n2 = As.shape[0], Ax.shape[0]
    Aall = np.block([[As, np.zeros((n1, n2))], [np.zeros((n2, n1)), Ax]])
    return (Aall, np.vstack([Bs, Bx]), np.hstack([Cs, Cx]), Ds + Dhat), s1


def _spectral_factor(Z, R0):
    """``V`` stable with stable inverse, ``V V~ = Z + Z~ + (R₀ − 2 D_Z)``; None when ``Φ`` is not positive."""
    import scipy.linalg as sla

    A, B, C, _ = Z
    try:
        Rh = np.linalg.cholesky(R0)
    except np.linalg.LinAlgError:
        return None
    if A.shape[0] == 0:
        return A, B, C, Rh
    try:
        W = sla.solve_continuous_are(A.T, C.T, np.zeros_like(A), R0, s=B)
    except (np.linalg.LinAlgError, ValueError):
        return None
    L = np.linalg.solve(R0, (B + W @ C.T).T).T
    if np.max(np.linalg.eigvals(A - L @ C).real) >= 0:
        return None
    return A, L @ Rh, C, Rh


def two_block_distance(inner, F, *, reltol: float = 1e-4):
    """``Y`` stable minimising ``‖Y R_i − F‖∞`` by Chu–Doyle–Lee's γ-iteration (continuous time).

    Parameters
    ----------
    inner : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``R_i`` (``r × m``, stable, co-inner).
    F : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``F`` (``q × m``, stable).
    reltol : float, default 1e-4
        Bisection stops when the bracket of ``γ`` is below ``reltol`` of its upper end.

    Returns
    -------
    tuple
        ``((A, B, C, D) of Y, γ)``: ``γ`` the upper end of the final bracket, a distance ``Y`` achieves (each
        accepted ``Y`` is checked by its H∞ norm).

    Raises
    ------
    DesignError
        When no ``γ`` up to ``1.001 ‖F‖∞`` passes (an ill-posed problem, e.g. ``F`` unstable).

    Examples
    --------
    ``R_i = [s+1, s+3, 1] / (√2 (s + √5.5))`` and ``F = [1, 1, 0]`` (Example 5.6c after the factorisation): the
    optimum ``‖F₂‖∞ = √(3/5.5)``, reached at ``ω = 0``.

    >>> a = 5.5 ** 0.5
    >>> Ri = ([[-a]], [[1 - a, 3 - a, 1.0]], [[2 ** -0.5]], [[2 ** -0.5, 2 ** -0.5, 0.0]])
    >>> F = (np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[1.0, 1.0, 0.0]])
    >>> Y, g = two_block_distance(Ri, F)
    >>> abs(g / (3 / 5.5) ** 0.5 - 1) < 2e-4
    True

    References
    ----------
    Chu, Doyle and Lee (1986); Varga (2017), §7.10; fdtools (``glinfldp``).
    """
    from fdikit.analysis.channels import Channel, hinf_norm
    from fdikit.design.nullspace.basis import minimal_realization

    Ri, F = realization(*inner), realization(*F)
    q = F[3].shape[0]
    F1 = series(_conjugate(*Ri), F)                       # F R_i~ (q × r)
    # F₁F₁~ − F F~ and its stable part Z (D_Z = 0); Φ_γ(∞) = γ² I + D₁D₁ᵀ − D Dᵀ
    Pf = series(_conjugate(*F1), F1)
    Pg = series(_conjugate(*F), F)
    Aphi, Bphi, Cphi, D0 = _difference(Pf, Pg)
    Z, _ = _split(Aphi, Bphi, Cphi, np.zeros((q, q)))    # not reduced: a rank tolerance of 1e-7 dropped modes
    #                                                       worth 4e-4 of Φ on PATH

    def attempt(g):
        V = _spectral_factor(Z, g * g * np.eye(q) + D0)
        if V is None:
            return None
        E = series(F1, inverse(*V))        # V⁻¹ F₁
        _, Eu = _split(*E)
        try:
            if _antistable_hankel_norm(Eu[0], Eu[1], Eu[2]) >= 1.0:
                return None
            Y = minimal_realization(*series(nehari(*E)[0], V))
        except (DesignError, np.linalg.LinAlgError):
            # γ so close to ‖F₂‖∞ that V⁻¹ has poles on the axis to rounding: counted as not achieved
            return None
        # accepted only if Y achieves γ: the test above is exact in exact arithmetic, but rounding in V near the
        # boundary has let it pass below the optimum (a random 3-state problem: bracket 1.5830, achieved 1.7308)
        return Y if float(hinf_norm(Channel(*distance_error(Ri, Y, F), None))[0]) <= g * (1 + 1e-9) else None

    top = float(hinf_norm(Channel(*F, None))[0])
    if top == 0.0:
        return (np.zeros((0, 0)), np.zeros((0, Ri[3].shape[0])), np.zeros((q, 0)), np.zeros((q, Ri[3].shape[0]))), 0.0
    hi, lo = 1.001 * top, 0.0
    Y = attempt(hi)
    if Y is None:
        raise DesignError(f"no γ up to 1.001 ‖F‖∞ = {hi:g} passes the Chu–Doyle–Lee test: the least-distance "
                          "problem is ill-posed (check that the reference is stable)")
    while hi - lo > reltol * hi and hi > 1e-9 * top:     # (an exact match, γ_opt = 0: down to 1e-9 ‖F‖∞)
        g = 0.5 * (lo + hi)
        Yg = attempt(g)
        if Yg is None:
            lo = g
        else:
            hi, Y = g, Yg
    return Y, hi
