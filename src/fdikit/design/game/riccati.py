"""Indefinite (H∞-type) algebraic Riccati equations of the game-theoretic detection filters.

Two equations appear in Murray 2012, Ch. 3:

* the per-target Riccati equation for a *given* gain ``L`` (3.26)/(3.28), (3.35)::

      0 = Π (A − LC) + (A − LC)ᵀ Π + Π R Π + Q̄,     R = F̂ M F̂ᵀ/γ + L V Lᵀ ≥ 0,  Q̄ = Cᵀ Ĥ Q Ĥ C ≥ 0

  whose quadratic term is *nonnegative* (the bounded-real-lemma form of an H∞ norm test), so
  the usual stabilizability/detectability conditions do not apply and the Hamiltonian (3.36)
  ``H = [[A − LC, R], [−Q̄, −(A − LC)ᵀ]]`` must be checked directly (Remark 3.2): a stabilizing
  solution (``A − LC + R Π`` Hurwitz) exists iff ``H`` has no imaginary-axis eigenvalue and
  ``A − LC`` is Hurwitz (Theorem 3.1, where the printed "≤ 0" means Hurwitz);
* the covariance form of the single-fault filter (3.29)–(3.30) with ``P = Γ⁻¹``::

      0 = A P + P Aᵀ + F̂ M F̂ᵀ/γ − P Cᵀ S C P,     S = V⁻¹ − Ĥ Q Ĥ  (indefinite in general)

Both are ``X A + Aᵀ X + X R X + Q = 0`` for some (A, R, Q) with symmetric ``R`` and ``Q``;
:func:`solve_game_are` solves that by the ordered real Schur form of the Hamiltonian
``[[A, R], [−Q, −Aᵀ]]`` (stable invariant subspace ``[U₁; U₂]``, ``X = U₂ U₁⁻¹``), after a
scalar scaling ``X̃ = s X`` that equalises ‖R‖ and ‖Q‖ (with γ = 1e−6 they differ by ~10⁸) and a
symplectic diagonal balancing of ``A``, followed by Newton refinement steps (Lyapunov solves) and
a residual check.

The module also holds the per-target Riccati solution for a given gain (:func:`game_riccati`) and the
GTMFDF cost with its analytic gradient (:func:`game_cost`) that :func:`fdikit.design.game.multi_fault.game_filter`
minimises.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.design.game.setup import GameProblem, per_target, weight
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

__all__ = ["RiccatiSolution", "solve_game_are", "hamiltonian_margin", "game_riccati", "game_cost"]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class RiccatiSolution:
    """Stabilizing solution of ``X A + Aᵀ X + X R X + Q = 0``.

    Attributes
    ----------
    X : symmetric solution (n x n).
    hamiltonian_margin : ``min |Re λ(H)|`` over the Hamiltonian eigenvalues (distance of the
        spectrum from the imaginary axis; 0 means no stabilizing solution).
    closed_loop_poles : eigenvalues of ``A + R X`` (all in the open left half-plane).
    residual : ``‖X A + Aᵀ X + X R X + Q‖ / (‖Q‖ + 2‖A‖‖X‖ + ‖R‖‖X‖²)``.

    The property ``stabilizing`` says whether ``A + R X`` is Hurwitz.

    Examples
    --------
    >>> import numpy as np
    >>> sol = solve_game_are(np.array([[-1.0]]), np.array([[0.5]]), np.array([[1.0]]))
    >>> sol.X.shape, sol.stabilizing, bool(sol.residual < 1e-8)
    ((1, 1), True, True)

    References
    ----------
    Murray 2012, §3.2.3, (3.26), Theorem 3.1.
    """

    X: np.ndarray
    hamiltonian_margin: float
    closed_loop_poles: np.ndarray
    residual: float

    @property
    def stabilizing(self) -> bool:
        """Whether ``A + R X`` is Hurwitz."""
        return bool(np.all(self.closed_loop_poles.real < 0))


def hamiltonian_margin(A: np.ndarray, R: np.ndarray, Q: np.ndarray) -> float:
    """``min |Re λ|`` of the Hamiltonian ``[[A, R], [−Q, −Aᵀ]]`` (Murray 2012, (3.36)).

    Parameters
    ----------
    A, R, Q : (n, n) arrays
        The coefficients of ``X A + Aᵀ X + X R X + Q = 0`` (``R``, ``Q`` symmetric).

    Returns
    -------
    float
        The distance of the Hamiltonian spectrum from the imaginary axis (0: no stabilizing solution).

    Examples
    --------
    >>> import numpy as np
    >>> round(hamiltonian_margin(np.array([[-1.0]]), np.array([[0.5]]), np.array([[1.0]])), 6)   # √(1 − 0.5)
    0.707107

    References
    ----------
    Murray 2012, §3.4.1, (3.36), Remark 3.2.
    """
    H = np.block([[A, R], [-Q, -A.T]])
    return float(np.min(np.abs(scipy.linalg.eigvals(H).real)))


def _are_residual(X, A, R, Q) -> np.ndarray:
    return X @ A + A.T @ X + X @ R @ X + Q


def solve_game_are(
    A: np.ndarray,
    R: np.ndarray,
    Q: np.ndarray,
    *,
    axis_tol: float = 1e-10,
    refine: int = 2,
    max_residual: float = 1e-8,
    what: str = "the game Riccati equation",
) -> RiccatiSolution:
    """Stabilizing solution of the indefinite ARE ``X A + Aᵀ X + X R X + Q = 0``.

    The sign of the quadratic term is that of Murray 2012, (3.35) (``R ≥ 0`` there; any symmetric
    ``R`` is accepted, e.g. ``−Cᵀ S C`` for the covariance form (3.29) with ``P``).

    Parameters
    ----------
    A, R, Q : (n, n) arrays; ``R`` and ``Q`` symmetric.
    axis_tol : Hamiltonian eigenvalues with ``|Re λ| ≤ axis_tol · ‖H̃‖`` (scaled Hamiltonian)
        count as imaginary-axis eigenvalues.
    refine : number of Newton refinement steps (one Lyapunov solve each).
    max_residual : relative residual above which the solution is rejected.
    what : name of the equation for error messages.

    Returns
    -------
    RiccatiSolution

    Raises
    ------
    DesignError
        If the Hamiltonian has eigenvalues on (or within ``axis_tol`` of) the imaginary axis,
        so that no stabilizing solution exists (Murray 2012, Remark 3.2), or the stable
        invariant subspace is not a graph (``U₁`` singular), or the residual is too large.

    Examples
    --------
    >>> import numpy as np
    >>> sol = solve_game_are(np.array([[-1.0]]), np.array([[0.5]]), np.array([[1.0]]))
    >>> round(float(sol.X[0, 0]), 6), sol.stabilizing       # 0.5 x² − 2x + 1 = 0, x = 2 − √2
    (0.585786, True)

    References
    ----------
    Murray 2012, §3.2.3, (3.26), Remark 3.2; §3.4.1, (3.35)–(3.36).
    """
    A = validate.as_square("A", A)
    n = A.shape[0]
    R = validate.as_square("R", R, n)
    Q = validate.as_square("Q", Q, n)
    validate.integer("refine", refine, minimum=0)
    axis_tol = validate.non_negative("axis_tol", axis_tol)
    max_residual = validate.positive("max_residual", max_residual)
    R, Q = (R + R.T) / 2, (Q + Q.T) / 2
    if n == 0:
        return RiccatiSolution(np.zeros((0, 0)), np.inf, np.zeros(0), 0.0)
    nR, nQ = np.linalg.norm(R, 2), np.linalg.norm(Q, 2)
    s = np.sqrt(nR / nQ) if nR > 0 and nQ > 0 else 1.0
    # symplectic balancing T = diag(D, D⁻¹): Ã = D⁻¹AD, R̃ = D⁻¹RD⁻¹/s, Q̃ = s DQD, X = D⁻¹X̃D⁻¹/s
    _, (scale, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    d = scale.astype(float)
    At = A * (1.0 / d)[:, None] * d[None, :]
    Rt = R * np.outer(1.0 / d, 1.0 / d) / s
    Qt = Q * np.outer(d, d) * s
    H = np.block([[At, Rt], [-Qt, -At.T]])
    eig = scipy.linalg.eigvals(H)
    margin_scaled = float(np.min(np.abs(eig.real)))  # = that of the unscaled H (similar matrices)
    hnorm = max(np.linalg.norm(H, 1), _EPS)
    if margin_scaled <= axis_tol * hnorm:
        raise DesignError(
            f"{what} has no stabilizing solution: its Hamiltonian has an eigenvalue on the imaginary axis "
            f"(min |Re λ| = {margin_scaled:.3g} relative to ‖H‖ = {hnorm:.3g}); the attenuation bound γ is too "
            "small for these weights and gain — increase γ, decrease Q or M, or change the gain"
        )
    T, U, sdim = scipy.linalg.schur(H, output="real", sort="lhp")
    if sdim != n:
        raise DesignError(
            f"{what}: the Hamiltonian has {sdim} stable eigenvalues instead of {n}; no stabilizing solution"
        )
    U1, U2 = U[:n, :n], U[n:, :n]
    if np.linalg.cond(U1) > 1 / (1e3 * _EPS):
        raise DesignError(f"{what}: the stable invariant subspace of the Hamiltonian is not a graph (U₁ singular)")
    Xt = np.linalg.solve(U1.T, U2.T).T
    Xt = (Xt + Xt.T) / 2
    for _ in range(refine):
        res = _are_residual(Xt, At, Rt, Qt)
        if np.abs(res).max() <= 1e-15 * (np.abs(Qt).max() + np.abs(At).max() * np.abs(Xt).max()):
            break
        Acl = At + Rt @ Xt
        dX = scipy.linalg.solve_continuous_lyapunov(Acl.T, -res)
        Xn = Xt + (dX + dX.T) / 2
        if np.linalg.norm(_are_residual(Xn, At, Rt, Qt)) < np.linalg.norm(res):
            Xt = Xn
        else:
            break
    X = Xt * np.outer(1.0 / d, 1.0 / d) / s
    X = (X + X.T) / 2
    res = np.linalg.norm(_are_residual(X, A, R, Q))
    nX = np.linalg.norm(X)
    denom = np.linalg.norm(Q) + 2 * np.linalg.norm(A) * nX + np.linalg.norm(R) * nX**2
    rel = float(res / denom) if denom > 0 else float(res)
    if rel > max_residual:
        raise DesignError(
            f"{what}: the Schur solution has relative residual {rel:.2e}; the problem is too badly scaled"
        )
    poles = scipy.linalg.eigvals(A + R @ X)
    # the scalings are similarity transformations of H, so its eigenvalues are those of the original
    return RiccatiSolution(X, margin_scaled, poles, rel)


# ---------------------------------------------------------------------------- problem-level helpers
def require_continuous(model: FaultModel) -> None:
    if model.is_discrete:
        raise DesignError(
            f"the steady-state game filter is continuous-time but the model is discrete (dt={model.dt}); "
            "design on the continuous model and discretise the generator, or use the discrete game filter"
        )


def checked_gamma(gamma: float) -> float:
    g = validate.number("gamma", gamma, finite=False)
    if not (np.isfinite(g) and g > 0):
        raise ParameterError(f"the attenuation bound gamma must be a positive finite number, got {gamma!r}")
    return g


@dataclass(frozen=True, eq=False)
class TargetTerms:
    name: str
    F: np.ndarray
    Fhat: np.ndarray
    Qbar: np.ndarray  # Cᵀ Ĥ Q Ĥ C
    R0: np.ndarray  # F̂ M F̂ᵀ / γ
    W: np.ndarray  # F̂ K F̂ᵀ / γ − F N Fᵀ


def target_terms(problem: GameProblem, gamma: float, Q, M, K, N, given: Sequence[str] = ()) -> list[TargetTerms]:
    g = checked_gamma(gamma)
    C, p = problem.model.C, problem.model.p
    Qs, Ms, Ks, Ns = (per_target(nm, w, problem, given) for nm, w in (("Q", Q), ("M", M), ("K", K), ("N", N)))
    out = []
    for name in problem.names:
        F, Fh, H = problem.targets[name], problem.complementary[name], problem.projectors[name]
        k = Fh.shape[1]
        Qw = weight(f"Q[{name}]", Qs[name], p)
        Mw, Kw = weight(f"M[{name}]", Ms[name], k), weight(f"K[{name}]", Ks[name], k)
        Nw = weight(f"N[{name}]", Ns[name], F.shape[1])
        Qbar = C.T @ H @ Qw @ H @ C
        R0 = Fh @ Mw @ Fh.T / g
        W = Fh @ Kw @ Fh.T / g - F @ Nw @ F.T
        out.append(TargetTerms(name, F, Fh, (Qbar + Qbar.T) / 2, (R0 + R0.T) / 2, (W + W.T) / 2))
    return out


def checked_gain(problem: GameProblem, L) -> np.ndarray:
    m = problem.model
    L = np.asarray(L, dtype=float)
    if L.shape != (m.n, m.p):
        raise ParameterError(f"the gain L must be n x p = {m.n} x {m.p}, got shape {L.shape}")
    if not np.all(np.isfinite(L)):
        raise DesignError("the gain L has non-finite entries")
    return L


def _riccati(problem: GameProblem, L: np.ndarray, t: TargetTerms, V: np.ndarray) -> RiccatiSolution:
    A, C = problem.model.A, problem.model.C
    Acl = A - L @ C
    return solve_game_are(Acl, t.R0 + L @ V @ L.T, t.Qbar,
                          what=f"the game Riccati equation (3.28) of target {t.name!r}")


def game_riccati(
    problem: GameProblem,
    L,
    target: str,
    *,
    gamma: float = 1e-6,
    V=1.0,
    Q=1e-4,
    M=0.01,
) -> RiccatiSolution:
    """Stabilizing solution ``Π_i`` of the per-target Riccati equation for a given gain (Murray 2012, (3.28)).

    ``0 = Π(A − LC) + (A − LC)ᵀΠ + Π R Π + Q̄``, ``R = F̂ M F̂ᵀ/γ + L V Lᵀ``, ``Q̄ = Cᵀ Ĥ Q Ĥ C``,
    solved through the Hamiltonian (3.36) by :func:`~fdikit.design.game.riccati.solve_game_are`.
    By Theorem 3.1 (its "``A − LC + RΠ ≤ 0``" read as Hurwitz, the property its proof in §3.4.1 uses),
    when ``A − LC`` is Hurwitz and the
    Hamiltonian has no imaginary-axis eigenvalue, ``Π ≥ 0``, ``A − LC + RΠ`` is Hurwitz and
    ``Ker Π`` is the unobservable subspace of ``(ĤC, A − LC)``.  Returned ``X`` is ``Π``.

    Parameters
    ----------
    problem : GameProblem
        The partitioned faults (:func:`~fdikit.design.game.setup.game_problem`), continuous model.
    L : (n, p) array
        The filter gain (observer sign: ``A − L C``).
    target : str
        The target ``i`` whose equation is solved.
    gamma : float
        Attenuation bound γ > 0 (default 1e-6).
    V : float or (p, p) array
        Murray's ``V = V̄/γ`` (default 1).
    Q, M : float, array or mapping target → value
        Output weight (p x p, default 1e-4) and complementary-fault weight (sized to ``F̂_i``, default 0.01).

    Returns
    -------
    RiccatiSolution
        ``X = Π_i`` (n x n), the Hamiltonian margin, the poles of ``A − LC + RΠ`` and the relative residual.

    Raises
    ------
    ParameterError
        A gain of the wrong shape, or ``target`` not a target of ``problem``.
    DesignError
        If ``A − LC`` is not Hurwitz or the Hamiltonian has imaginary-axis eigenvalues (the
        attenuation bound γ is not met by this gain: Remark 3.2), or the model is discrete.

    Examples
    --------
    >>> from fdikit.design.game.setup import game_problem
    >>> from fdikit.design.game.single_fault import game_filter_bank
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> model = white_speyer("stable-extra-zero")
    >>> prob = game_problem(model, ["f1", "f2"])
    >>> bank = game_filter_bank(model, ["f1", "f2"], Q=1e-3, M=0.05)
    >>> L = (bank.gains["f1"] + bank.gains["f2"]) / 2          # a stable shared gain
    >>> sol = game_riccati(prob, L, "f1", Q=1e-3, M=0.05)
    >>> sol.X.shape, sol.stabilizing, bool(np.linalg.eigvalsh(sol.X).min() > -1e-12)
    ((3, 3), True, True)

    References
    ----------
    Murray 2012, §3.2.3, (3.28), Theorem 3.1; §3.4.1, (3.36).
    """
    require_continuous(problem.model)
    L = checked_gain(problem, L)
    if target not in problem.targets:
        raise ParameterError(f"{target!r} is not a target of the problem; targets are {problem.names}")
    poles = scipy.linalg.eigvals(problem.model.A - L @ problem.model.C)
    if np.any(poles.real >= 0):
        raise DesignError(
            f"A − LC is not Hurwitz (poles {np.round(poles, 6).tolist()}); Theorem 3.1 needs a stable filter"
        )
    t = next(x for x in target_terms(problem, gamma, Q, M, 0.0, 0.0) if x.name == target)
    return _riccati(problem, L, t, weight("V", V, problem.model.p))


def stacked_cost(problem: GameProblem, L: np.ndarray, targets: list[TargetTerms], V: np.ndarray):
    """J, ∂J/∂L, Π_i, Hamiltonian margins (the gradient of (3.27) under (3.28): see :func:`game_cost`)."""
    C = problem.model.C
    J, grad, pis, margins = 0.0, np.zeros_like(L), {}, {}
    for t in targets:
        sol = _riccati(problem, L, t, V)
        Pi = sol.X
        Acl = problem.model.A - L @ C + (t.R0 + L @ V @ L.T) @ Pi
        Delta = scipy.linalg.solve_continuous_lyapunov(Acl, -t.W)
        J += float(np.trace(t.W @ Pi))
        grad += 2 * Pi @ Delta @ (Pi @ L @ V - C.T)
        pis[t.name], margins[t.name] = Pi, sol.hamiltonian_margin
    return J, grad, pis, margins


def game_cost(
    problem: GameProblem,
    L,
    *,
    gamma: float = 1e-6,
    V=1.0,
    Q=1e-4,
    M=0.01,
    K=0.01,
    N=1.0,
) -> tuple[float, np.ndarray]:
    """Steady-state GTMFDF cost and its gradient (Murray 2012, §3.2.3, (3.27) with (3.28)).

    ``J(L) = Σ_i tr(W_i Π_i(L))``, ``W_i = F̂_i K_i F̂_iᵀ/γ − F_i N_i F_iᵀ`` and

        ∂J/∂L = Σ_i 2 Π_i Δ_i (Π_i L V − Cᵀ),   0 = (A − LC + R_iΠ_i) Δ_i + Δ_i (·)ᵀ + W_i

    whose zero is the stationarity condition (3.25) ``L = (Σ Π_iΔ_iΠ_i)⁻¹ Σ Π_iΔ_i Cᵀ V⁻¹``.
    Weights are one value for every target or a mapping target → value.

    Parameters
    ----------
    problem : GameProblem
        The partitioned faults (:func:`~fdikit.design.game.setup.game_problem`), continuous model.
    L : (n, p) array
        The filter gain (observer sign: ``A − L C``).
    gamma : float
        Attenuation bound γ > 0 (default 1e-6).
    V : float or (p, p) array
        Murray's ``V = V̄/γ`` (default 1).
    Q, M, K, N : float, array or mapping target → value
        Riccati weights ``Q_i`` (p x p), ``M_i`` (sized to ``F̂_i``) and cost weights ``K_i`` (sized to ``F̂_i``,
        penalises complementary-fault transmission), ``N_i`` (sized to ``F_i``, rewards target transmission).

    Returns
    -------
    J : float
        The cost ``Σ_i tr(W_i Π_i(L))``.
    grad : (n, p) array
        ``∂J/∂L``.

    Raises
    ------
    DesignError
        If a Riccati equation has no stabilizing solution at ``L``.

    Examples
    --------
    >>> from fdikit.design.game.setup import game_problem
    >>> from fdikit.design.game.single_fault import game_filter_bank
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> model = white_speyer("stable-extra-zero")
    >>> prob = game_problem(model, ["f1", "f2"])
    >>> bank = game_filter_bank(model, ["f1", "f2"], Q=1e-3, M=0.05)
    >>> L = (bank.gains["f1"] + bank.gains["f2"]) / 2          # a stable shared gain
    >>> J, grad = game_cost(prob, L, Q=1e-3, M=0.05, K=0.1, N=5.0)
    >>> f"{J:.3e}", grad.shape
    ('1.577e-04', (3, 2))

    References
    ----------
    Murray 2012, §3.2.2, (3.25), and §3.2.3, (3.27)–(3.28).
    """
    require_continuous(problem.model)
    L = checked_gain(problem, L)
    J, grad, _, _ = stacked_cost(problem, L, target_terms(problem, gamma, Q, M, K, N), weight("V", V, problem.model.p))
    return J, grad


def _hamiltonian(Acl: np.ndarray, R: np.ndarray, Qbar: np.ndarray) -> np.ndarray:
    n = Acl.shape[0]
    H = np.empty((2 * n, 2 * n))
    H[:n, :n], H[:n, n:], H[n:, :n], H[n:, n:] = Acl, R, -Qbar, -Acl.T
    return H


def target_margins(problem: GameProblem, L: np.ndarray, targets: list[TargetTerms], V: np.ndarray, grad: bool = False):
    """Margins ``[−max Re λ(A − LC), min |Re λ(H_i)| …]`` and, with ``grad``, their gradients in ``L``.

    The gradients are first-order eigenvalue perturbations ``dλ = wᴴ dX v / wᴴ v`` (simple eigenvalues),
    with ``dH_i = [[−dL C, dL V Lᵀ + L V dLᵀ], [0, Cᵀ dLᵀ]]``.
    """
    A, C = problem.model.A, problem.model.C
    n = A.shape[0]
    Acl = A - L @ C
    if not grad:
        out = [-np.linalg.eigvals(Acl).real.max()]
        for t in targets:
            out.append(np.abs(np.linalg.eigvals(_hamiltonian(Acl, t.R0 + L @ V @ L.T, t.Qbar)).real).min())
        return np.array(out)
    lam, wl, vr = scipy.linalg.eig(Acl, left=True, right=True)
    k = int(np.argmax(lam.real))
    w, v = wl[:, k], vr[:, k]
    out = [-lam[k].real]
    grads = [np.real(np.outer(w.conj(), C @ v) / (w.conj() @ v))]
    for t in targets:
        mu, wl, vr = scipy.linalg.eig(_hamiltonian(Acl, t.R0 + L @ V @ L.T, t.Qbar), left=True, right=True)
        k = int(np.argmin(np.abs(mu.real)))
        v1, v2, w1, w2 = vr[:n, k], vr[n:, k], wl[:n, k], wl[n:, k]
        G = (
            -np.outer(w1.conj(), C @ v1)
            + np.outer(w1.conj(), V @ L.T @ v2)
            + np.outer(v2, (V @ L.T @ w1).conj())
            + np.outer(v2, (C @ w2).conj())
        ) / (wl[:, k].conj() @ vr[:, k])
        out.append(abs(mu[k].real))
        grads.append(np.sign(mu[k].real) * G.real)
    return np.array(out), grads
