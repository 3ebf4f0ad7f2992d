"""Building blocks of the discrete game-theoretic detection filters (Murray 2012, Ch. 5).

The setup (targets, weights, horizon), the DARI propagation for a given gain, the secondary cost ``J̄`` with its
exact gradient, the gain formula (5.41) and the residual generator of the observer (5.3).  The designs that use them,
DGTFDF and DGTMFDF, are in :mod:`fdikit.design.game.discrete`.

Observer (5.3) on a *discrete* model (``Φ = model.A``); the residual uses the a-priori estimate
(the text's (2.19c) prints x̂, (2.20c) and (5.3c) say x̄)::

    x̄(k+1) = Φ x̂(k) + Bu u(k),   x̂(k) = x̄(k) + L (y − C x̄ − Du u),   r = y − C x̄ − Du u,   r̄_i = Ĥ_i r

i.e. the predictor ``x̄(k+1) = Φ x̄ + Bu u + ΦL (y − C x̄ − Du u)`` (``observer_generator`` with gain ``ΦL``).

**Gain convention.**  Murray's ``L`` is the *filtered-form* gain of the a-posteriori update;
:func:`discrete_game_riccati`, :func:`secondary_cost`, :func:`gain_update` and :func:`discrete_game_generator` take it
in that form, as the text writes every equation (the designs keep it as ``filter_gain``; their ``gain`` is fdikit's
observer (predictor) gain ``ΦL``, so the generator's state matrix is ``Φ − (ΦL) C = Φ(I − LC)``).

Target ``i`` (``F̂_i``, ``Ĥ_i`` from :func:`~fdikit.design.game.setup.game_problem`) meets its
disturbance-attenuation problem (5.8) when the DARI (5.23) ≡ (5.29) ≡ (5.30) has ``Π_i ≥ 0``.  With
equality and ``P = Π⁻¹`` ((5.29) and (5.44b) rewritten in ``P``; for ``L = Λ⁻¹CᵀV⁻¹`` it is (5.42))::

    P(k+1) = Φ [(I − LC)(P⁻¹ − CᵀĤQĤC)⁻¹(I − LC)ᵀ + L V Lᵀ] Φᵀ + F̂MF̂ᵀ/γ,     P(k0) = P0/γ

with ``V = V̄/γ`` and ``Π_0 = γP0⁻¹`` (5.9).  It needs ``Γ = P⁻¹ − CᵀĤQĤC > 0`` at every step
(Proposition 5.2), checked as ``λ_max(RPRᵀ) < 1`` with ``R = Q^½ĤC``; ``Γ⁻¹ = P + PRᵀ(I − RPRᵀ)⁻¹RP``
avoids inverting ``P``.  Φ and ``I − LC`` must be invertible (Ch. 5 assumption).

The secondary cost (5.31) with the example weight (5.39) is summed over the horizon for one constant gain; its
gradient is (5.34) summed over k with the multiplier run backward by (5.35) from ``Δ(k1) = 0`` (5.36) (the forward
form (5.38) is not the inverse of (5.35) — erratum — and is not used).

Other errata applied: (5.2a) prints ``Φ x(k)`` for the state ``x_i``, read ``Φ x_i(k)``; (5.23), (5.26), (5.27)
need ``F̂_iᵀ`` where the text prints ``F̂_iΓ̂_iΦL``; (3.32)/(5.9) start from ``P0/γ``, not ``γP0``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import linalg, validate
from fdikit.design.game.setup import GameProblem, game_problem, per_target, weight
from fdikit.design.labels import label_generator
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = [
    "DiscreteGameSetup", "discrete_game_setup", "GameRiccatiSolution", "discrete_game_riccati", "secondary_cost",
    "gain_update", "discrete_game_generator",
]

GUARD = 1.0 - 1e-10  # λ_max(RPRᵀ) at or above this: Γ = P⁻¹ − RᵀR is not positive definite


@dataclass(frozen=True, eq=False)
class DiscreteGameSetup:
    """Partition, weights and horizon of a discrete game filter (Murray 2012, (5.8), (5.9), (5.39)).

    Made by :func:`discrete_game_setup`, which checks every weight; the designs
    :func:`~fdikit.design.game.discrete.dgtfdf` and :func:`~fdikit.design.game.discrete.dgtmfdf` take it.  The
    properties ``model`` and ``names`` give the plant and the target names (design order); the methods give the
    per-target matrices of the recursions.

    Attributes
    ----------
    problem : GameProblem
        The targets ``F_i``, complementary faults ``F̂_i`` and projectors ``Ĥ_i``
        (:func:`~fdikit.design.game.setup.game_problem`).
    gamma : float
        The attenuation bound γ > 0 of (5.8) (small = strong blocking).
    V : (p, p) array
        The noise weight ``V = V̄/γ`` (5.9).
    P_init : (n, n) array
        The initial covariance ``P(k0) = P0/γ = Π_0⁻¹``.
    steps : int
        The horizon ``k1 − k0`` in samples.
    Q : dict of str to (p, p) array
        Output weight ``Q_i ≥ 0`` on ``Ĥ_i C e_i`` by target.
    M : dict of str to (k̂_i, k̂_i) array
        Complementary-fault weight ``M_i > 0`` by target (k̂_i columns of ``F̂_i``).
    K, N : dict of str to (k̂_i, k̂_i) and (k_i, k_i) arrays
        Secondary-cost weights of (5.39) on ``F̂_i`` and on ``F_i`` by target (zero: no secondary cost).

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1"], ["f2"], gamma=1e-2, Vbar=1.0, Q=1e-3,
    ...                          M=5.0, steps=50)
    >>> st.names, st.steps, float(st.V[0, 0]), st.nuisance_covariance("f1").shape, st.output_weight_root("f1").shape
    (('f1',), 50, 100.0, (3, 3), (2, 3))

    References
    ----------
    Murray 2012, §5.1.1, (5.8); §5.1.2, (5.9); §5.2.2, (5.39).
    """

    problem: GameProblem
    gamma: float
    V: np.ndarray
    P_init: np.ndarray
    steps: int
    Q: dict[str, np.ndarray]
    M: dict[str, np.ndarray]
    K: dict[str, np.ndarray]
    N: dict[str, np.ndarray]

    @property
    def model(self) -> FaultModel:
        """The discrete plant (``problem.model``)."""
        return self.problem.model

    @property
    def names(self) -> tuple[str, ...]:
        """The target names in design order."""
        return self.problem.names

    def nuisance_covariance(self, name: str) -> np.ndarray:
        """``F̂_i M_i F̂_iᵀ / γ`` (n x n) of target ``name``."""
        F = self.problem.complementary[name]
        return F @ self.M[name] @ F.T / self.gamma

    def cost_weight(self, name: str) -> np.ndarray:
        """``W_i = F̂_iK_iF̂_iᵀ/γ − F_iN_iF_iᵀ`` (n x n) of the example cost (5.39), target ``name``."""
        F, Fh = self.problem.targets[name], self.problem.complementary[name]
        return Fh @ self.K[name] @ Fh.T / self.gamma - F @ self.N[name] @ F.T

    def output_weight_root(self, name: str) -> np.ndarray:
        """``R_i = Q_i^½ Ĥ_i C`` (p x n), so that ``CᵀĤ_iQ_iĤ_iC = R_iᵀR_i``, of target ``name``."""
        w, U = np.linalg.eigh(self.Q[name])
        return (U * np.sqrt(np.clip(w, 0.0, None))) @ U.T @ self.problem.projectors[name] @ self.model.C


def _weights(kind: str, value, dims: Mapping[str, int]) -> dict[str, np.ndarray]:
    """:func:`~fdikit.design.game.setup.per_target`, each checked as a ``dims[target]``-square :func:`weight`."""
    return {nm: weight(f"{kind}[{nm}]", v, dims[nm]) for nm, v in per_target(kind, value, list(dims)).items()}


def _positive(name: str, W: np.ndarray) -> np.ndarray:
    if W.size and np.linalg.eigvalsh(W).min() <= 0:
        raise ParameterError(f"weight {name} must be positive definite")
    return W


def discrete_game_setup(
    model: FaultModel,
    targets: Mapping[str, np.ndarray] | Sequence[str],
    nuisance: Mapping[str, np.ndarray] | Sequence[str] = (),
    *,
    gamma: float,
    Vbar,
    Q,
    M,
    K=0.0,
    N=0.0,
    P0=1.0,
    steps: int = 500,
    rtol: float | None = None,
) -> DiscreteGameSetup:
    """Partition the faults of a discrete model and fix the weights (Murray 2012, (5.8), (5.9), (5.39)).

    Sampling a continuous design at Δt: ``Q_d = Q_cΔt``, ``M_d = M_c/Δt`` (fault columns ZOH-sampled,
    ≈ ``F_cΔt``), ``V_d = V_c/Δt``.  ``Q·P0/γ`` must stay below 1 along ``ĤC`` or the DARI fails at k0 — the
    initial error reaches the a-priori residual.

    Parameters
    ----------
    model : FaultModel
        The plant, discrete (sample a continuous plant with ``model.discretize(dt)``); ``Φ = model.A`` must be
        invertible.
    targets : sequence of str or mapping name → (n, k) array
        The faults to detect, as in :func:`~fdikit.design.game.setup.game_problem`.
    nuisance : sequence of str, mapping or ``'others'``, optional
        The faults to block: ``()`` (default) none, ``'others'`` every other fault input of the model.
    gamma : float
        The attenuation bound γ > 0 of (5.8) (small = strong blocking).
    Vbar : float or (p, p) array
        Measurement-noise weight ``V̄ > 0`` of (5.8); the recursions use ``V = V̄/γ``.
    Q : float, array or mapping target → value
        Output weight ``Q_i ≥ 0`` (p x p; a scalar means ``Q_i · I``).
    M : float, array or mapping target → value
        Complementary-fault weight ``M_i > 0``, sized to the columns of ``F̂_i``.
    K, N : float, array or mapping target → value, optional
        Secondary-cost weights of (5.39), ``K_i`` on ``F̂_i`` and ``N_i`` on ``F_i`` (default 0: no secondary
        cost; :func:`~fdikit.design.game.discrete.dgtmfdf` needs one of them nonzero).
    P0 : float or (n, n) array, optional
        Initial-error weight ``P0 > 0`` (default 1): ``P(k0) = P0/γ`` (``Π_0 = γP0⁻¹``).
    steps : int, optional
        The horizon ``k1 − k0`` in samples (default 500).
    rtol : float, optional
        Relative rank tolerance of the subspace computations of
        :func:`~fdikit.design.game.setup.game_problem`.

    Returns
    -------
    DiscreteGameSetup
        The partition, ``V = V̄/γ``, ``P(k0) = P0/γ``, the horizon and the per-target weights.

    Raises
    ------
    DesignError
        A continuous model, a singular Φ, a name given both as target and nuisance, or a target hidden by its
        complementary faults (:func:`~fdikit.design.game.setup.game_problem`).
    ParameterError
        ``model`` not a FaultModel, γ not positive and finite, ``steps`` not a positive integer, ``V̄``, ``P0``
        or ``M_i`` not positive definite, a weight of the wrong size or not symmetric positive semidefinite, a
        weight mapping that misses a target, or an unknown fault name.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, steps=20)
    >>> st.names, st.M["f1"].shape, float(st.P_init[0, 0])
    (('f1', 'f2'), (1, 1), 1.0)

    References
    ----------
    Murray 2012, §5.1.1, (5.1), (5.8), Assumptions 5.1–5.5; §5.1.2, (5.9); §5.2.2, (5.39).
    """
    validate.instance("model", model, FaultModel)
    if not model.is_discrete:
        raise DesignError("the discrete game filter needs a discrete model; sample the plant with model.discretize(dt)")
    gamma = validate.number("gamma", gamma, finite=False)
    if not (np.isfinite(gamma) and gamma > 0):
        raise ParameterError(f"gamma must be a positive finite attenuation bound, got {gamma}")
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer | float) or int(steps) != steps or steps < 1:
        raise ParameterError(f"steps must be a positive integer horizon, got {steps}")
    s = np.linalg.svd(model.A, compute_uv=False)
    if s[-1] <= 1e-12 * max(s[0], 1.0):
        raise DesignError(f"Φ = model.A is singular (σ_min = {s[-1]:.3g}); Murray 2012 Ch. 5 assumes an invertible "
                          "state-transition matrix (a sampled continuous plant always has one)")
    prob = game_problem(model, targets, nuisance, rtol)
    kh = {t: prob.complementary[t].shape[1] for t in prob.names}
    return DiscreteGameSetup(
        prob, float(gamma), _positive("Vbar", weight("Vbar", Vbar, model.p)) / gamma,
        _positive("P0", weight("P0", P0, model.n)) / gamma, int(steps),
        _weights("Q", Q, {t: model.p for t in prob.names}),
        {t: _positive(f"M[{t}]", Mi) for t, Mi in _weights("M", M, kh).items()},
        _weights("K", K, kh), _weights("N", N, {t: prob.targets[t].shape[1] for t in prob.names}),
    )


# ---------------------------------------------------------------------- the DARI propagation
@dataclass(frozen=True, eq=False)
class GameRiccatiSolution:
    """Forward solution of the DGTMFDF Riccati equations for a given gain.

    Made by :func:`discrete_game_riccati`; ``information(name, k)`` gives ``Π_i(k) = P_i(k)⁻¹``.

    Attributes
    ----------
    covariances : dict of str to (steps + 1, n, n) array
        ``P_i(k)`` by target, k = k0 … k1, ``P_i(k0) = P0/γ``.
    levels : dict of str to (steps,) array
        ``λ_max(Q_i^½Ĥ_iCP_i(k)CᵀĤ_iQ_i^½)`` by target, k = k0 … k1 − 1; below 1 ⇔ ``Γ_i(k) > 0``.
    gamma_inverses : dict of str to (steps, n, n) array
        ``Γ_i(k)⁻¹`` by target, k = k0 … k1 − 1.

    Examples
    --------
    >>> from fdikit.design.game.discrete import dgtfdf
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1"], ["f2"], gamma=1e-2, Vbar=1.0, Q=1e-3,
    ...                          M=5.0, P0=1e-2, steps=50)
    >>> sol = discrete_game_riccati(st, dgtfdf(st).filter_gain)
    >>> sol.covariances["f1"].shape, sol.levels["f1"].shape, sol.information("f1").shape
    ((51, 3, 3), (50,), (3, 3))

    References
    ----------
    Murray 2012, §5.2.1, (5.17), (5.29)–(5.30), Proposition 5.2.
    """

    covariances: dict[str, np.ndarray]
    levels: dict[str, np.ndarray]
    gamma_inverses: dict[str, np.ndarray]

    def information(self, name: str, k: int = -1) -> np.ndarray:
        """``Π_i(k) = P_i(k)⁻¹`` of target ``name`` (default the last step, k1)."""
        Pi = np.linalg.inv(self.covariances[name][k])
        return (Pi + Pi.T) / 2


def _check_gain(L: np.ndarray, C: np.ndarray, floor: float = 1e-10) -> float:
    smin = float(np.linalg.svd(np.eye(L.shape[0]) - L @ C, compute_uv=False)[-1])
    if smin <= floor:
        raise DesignError(f"I − LC is singular (σ_min = {smin:.3g}); Murray 2012 Ch. 5 needs an invertible I − LC — "
                          "choose a gain whose a-posteriori update does not cancel a state direction")
    return smin


def infeasible(setup: DiscreteGameSetup, name: str, k: int, P: np.ndarray, level: float) -> DesignError:
    R = setup.output_weight_root(name)
    lam = float(np.linalg.eigvalsh(np.linalg.inv(P) - R.T @ R).min())
    return DesignError(
        f"target {name!r}: the game Riccati recursion loses P⁻¹ − CᵀĤQĤC > 0 at step k = {k} (smallest eigenvalue "
        f"{lam:.3g}; λ_max(Q^½ĤCPCᵀĤQ^½) = {level:.4g} ≥ 1): the attenuation bound γ = {setup.gamma:g} is not met "
        "with this gain — lower Q or P0, raise γ or M, or change the gain"
    )


def discrete_game_riccati(setup: DiscreteGameSetup, L) -> GameRiccatiSolution:
    """Propagate the DARI with equality (Murray 2012, (5.17), (5.29)–(5.30)) for a given gain, all targets at once.

    ``P(k+1) = Φ [(I − LC)Γ⁻¹(I − LC)ᵀ + L V Lᵀ] Φᵀ + F̂MF̂ᵀ/γ`` with ``Γ = P⁻¹ − CᵀĤQĤC`` from
    ``P(k0) = P0/γ`` (module docstring); ``Γ > 0`` is checked at every step (Proposition 5.2).

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`discrete_game_setup`.
    L : (n, p) or (steps, n, p) array
        The gain in Murray's filtered form (a design's ``filter_gain``; an observer gain ``G`` is ``Φ⁻¹G``),
        constant or one per step.

    Returns
    -------
    GameRiccatiSolution
        ``P_i(k)``, the levels ``λ_max(RPRᵀ)`` and ``Γ_i(k)⁻¹`` of every target.

    Raises
    ------
    ParameterError
        ``L`` of another shape.
    DesignError
        ``I − L(k)C`` singular, or positivity of ``P⁻¹ − CᵀĤQĤC`` lost (the message names the target, the step
        and the smallest eigenvalue: γ is not met with this gain).

    Examples
    --------
    The time-varying DGTFDF gains reproduce the design's own covariances:

    >>> from fdikit.design.game.discrete import dgtfdf
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-2, Vbar=1e-2 / 0.01, Q=1e-3, M=5.0, P0=1e-2, steps=50)
    >>> d = dgtfdf(st)
    >>> sol = discrete_game_riccati(st, d.filter_gains)
    >>> bool(sol.levels["f1"].max() < 1), bool(np.allclose(sol.covariances["f1"], d.covariances))
    (True, True)

    References
    ----------
    Murray 2012, §5.2.1, (5.17), (5.23), (5.29)–(5.30), Proposition 5.2 (§5.4); §5.3, (5.44b).
    """
    m, steps, names = setup.model, setup.steps, setup.names
    n = m.n
    L = np.asarray(L, dtype=float)
    if L.shape not in ((n, m.p), (steps, n, m.p)):
        raise ParameterError(f"gain has shape {L.shape}; give n x p = {n} x {m.p} or a ({steps}, {n}, {m.p}) sequence")
    Ls = L if L.ndim == 3 else L[None]
    for Lk in Ls:
        _check_gain(Lk, m.C)
    R = np.stack([setup.output_weight_root(t) for t in names])  # (s, p, n)
    Rt = np.swapaxes(R, 1, 2)
    Nc = np.stack([setup.nuisance_covariance(t) for t in names])
    P = np.empty((steps + 1, len(names), n, n))
    Ginv = np.empty((steps, len(names), n, n))
    P[0] = setup.P_init
    eye_p = np.eye(m.p)
    for k in range(steps):
        if k < len(Ls):
            Lk = Ls[k]
            Phat = m.A @ (np.eye(n) - Lk @ m.C)
            G = m.A @ Lk @ setup.V @ Lk.T @ m.A.T + Nc  # G_i of (5.17)
        RP = R @ P[k]
        S = eye_p - RP @ Rt
        try:
            np.linalg.cholesky(S * (1 + 1e-10) - 1e-10 * eye_p)  # ⇔ λ_max(RPRᵀ) < GUARD
        except np.linalg.LinAlgError:
            lv = 1.0 - np.linalg.eigvalsh(S).min(axis=-1)
            i = int(np.argmax(lv))
            raise infeasible(setup, names[i], k, P[k, i], float(lv[i])) from None
        Ginv[k] = P[k] + np.swapaxes(RP, 1, 2) @ np.linalg.solve(S, RP)
        Pn = Phat @ Ginv[k] @ Phat.T + G
        P[k + 1] = (Pn + np.swapaxes(Pn, 1, 2)) / 2
    RPR = R[None] @ P[:-1] @ Rt[None]
    lev = np.linalg.eigvalsh((RPR + np.swapaxes(RPR, -1, -2)) / 2).max(axis=-1)
    return GameRiccatiSolution({t: P[:, i] for i, t in enumerate(names)}, {t: lev[:, i] for i, t in enumerate(names)},
                               {t: Ginv[:, i] for i, t in enumerate(names)})


# ---------------------------------------------------------------------- secondary optimisation
def _adjoint(setup: DiscreteGameSetup, L: np.ndarray, sol: GameRiccatiSolution):
    """Cost, exact gradient and the two (5.41) sums for a constant gain (one backward sweep)."""
    m, names = setup.model, setup.names
    Phi, C, V = m.A, m.C, setup.V
    CV = C.T @ np.linalg.inv(V)
    Phat = Phi @ (np.eye(m.n) - L @ C)
    Ginv = np.stack([sol.gamma_inverses[t] for t in names], axis=1)  # (steps, s, n, n)
    Pis = np.linalg.inv(np.stack([sol.covariances[t] for t in names], axis=1))
    Pis = (Pis + np.swapaxes(Pis, -1, -2)) / 2
    W = np.stack([setup.cost_weight(t) for t in names])
    RtR = np.stack([(R := setup.output_weight_root(t)).T @ R for t in names])
    cost = float(np.einsum("sij,ksji->", W, Pis[:-1]))
    Y = Ginv @ Phat.T  # Γ⁻¹Φ̂ᵀ
    X = np.empty_like(Ginv)
    lam = np.zeros_like(W)  # ∂J̄/∂Π(k+1) = −Δ(k+1); zero at k1 (5.36)
    for k in range(setup.steps - 1, -1, -1):
        X[k] = Pis[k + 1] @ lam @ Pis[k + 1]
        lam = W + Y[k] @ X[k] @ np.swapaxes(Y[k], -1, -2)  # (5.35), (5.37), (5.40)
    grad = 2 * Phi.T @ np.einsum("ksij,ksjl->il", X, Phat @ Ginv @ C.T - Phi @ L @ V)  # (5.34)
    T = Phat.T @ X @ Phat @ Ginv  # −Γ_iΛ_i of (5.41)
    lhs = np.einsum("ksij,ksjl->il", T, Pis[:-1] - RtR + CV @ C)
    return cost, grad, lhs, np.einsum("ksij,jl->il", T, CV)


def _constant_gain(setup: DiscreteGameSetup, L) -> np.ndarray:
    L = np.asarray(L, dtype=float)
    if L.shape != (setup.model.n, setup.model.p):
        raise ParameterError(f"the secondary optimisation uses one constant gain: L must be n x p = "
                          f"{setup.model.n} x {setup.model.p}, got shape {L.shape}")
    return L


def secondary_cost(setup: DiscreteGameSetup, L) -> tuple[float, np.ndarray]:
    """``J̄(L) = Σ_i Σ_{k=k0}^{k1−1} tr(W_iΠ_i(k))`` and its exact gradient (Murray 2012, (5.31)–(5.40)).

    ``L`` is constant over the horizon; the gradient is (5.34) summed over k with the backward
    multiplier (5.35) from ``Δ(k1) = 0`` (5.36).  ``W_i`` is the weight (5.39) of
    :meth:`DiscreteGameSetup.cost_weight`.

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`discrete_game_setup`, with the weights ``K_i``, ``N_i``.
    L : (n, p) array
        The constant gain in Murray's filtered form (a design's ``filter_gain``).

    Returns
    -------
    cost : float
        ``J̄(L)``.
    gradient : (n, p) array
        ``∂J̄/∂L``.

    Raises
    ------
    ParameterError
        ``L`` not n x p.
    DesignError
        ``I − LC`` singular, or the DARI infeasible with this gain (:func:`discrete_game_riccati`).

    Examples
    --------
    >>> from fdikit.design.game.discrete import dgtfdf
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1,
    ...                          M=1.0, K=1.0, N=1.0, steps=20)
    >>> J, g = secondary_cost(st, dgtfdf(st, "f1").filter_gain)
    >>> round(J, 6), g.shape
    (0.000557, (3, 2))

    References
    ----------
    Murray 2012, §5.2.2, (5.31), (5.34)–(5.37), (5.39)–(5.40).
    """
    L = _constant_gain(setup, L)
    cost, grad, _, _ = _adjoint(setup, L, discrete_game_riccati(setup, L))
    return cost, grad


def gain_update(setup: DiscreteGameSetup, L) -> np.ndarray:
    """The gain formula (5.41), summed over targets and the horizon, with ``Γ_i, Λ_i`` evaluated at ``L``.

    ``L⁺ = [Σ Γ_iΛ_i(Γ_i + CᵀV⁻¹C)]⁻¹ [Σ Γ_iΛ_iCᵀV⁻¹]``.  Its residual ``Σ Γ_iΛ_i[(Γ_i + CᵀV⁻¹C)L − CᵀV⁻¹]``
    equals ``(I − LC)ᵀ·½∇J̄·V⁻¹(I − CL)``, so a fixed point is stationary only while ``I − LC`` is invertible.

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`discrete_game_setup`, with the weights ``K_i``, ``N_i``.
    L : (n, p) array
        The constant gain in Murray's filtered form at which ``Γ_i`` and ``Λ_i`` are evaluated.

    Returns
    -------
    numpy.ndarray
        The next (n, p) gain ``L⁺`` of the fixed-point iteration, filtered form.

    Raises
    ------
    ParameterError
        ``L`` not n x p.
    DesignError
        ``I − LC`` singular or the DARI infeasible (:func:`discrete_game_riccati`), or
        ``Σ Γ_iΛ_i(Γ_i + CᵀV⁻¹C)`` singular (the null spaces overlap across targets, Remark 5.3).

    Examples
    --------
    >>> from fdikit.design.game.discrete import dgtfdf
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1,
    ...                          M=1.0, K=1.0, N=1.0, steps=20)
    >>> gain_update(st, dgtfdf(st, "f1").filter_gain).shape
    (3, 2)

    References
    ----------
    Murray 2012, §5.2.2, (5.37), (5.40)–(5.41), Remark 5.3.
    """
    L = _constant_gain(setup, L)
    _, _, lhs, rhs = _adjoint(setup, L, discrete_game_riccati(setup, L))
    try:
        return np.linalg.solve(lhs, rhs)
    except np.linalg.LinAlgError as exc:
        raise DesignError("Σ Γ_iΛ_i(Γ_i + CᵀV⁻¹C) of (5.41) is singular: the null spaces overlap across targets "
                          "(Murray 2012, Remark 5.3); raise the weights N_i or K_i") from exc


# ---------------------------------------------------------------------- the residual generator
def discrete_game_generator(
    setup: DiscreteGameSetup, L, targets: Sequence[str] | None = None, *, names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> ResidualGenerator:
    """Residual generator of the observer (5.3) with projected residuals ``Q_iᵀ r`` (Murray 2012, (5.3), (5.6)).

    ``x̄(k+1) = Φ(I − LC) x̄ + (Bu − ΦL Du) u + ΦL y``, ``r = y − C x̄ − Du u``; ``Q_i`` is an orthonormal
    basis of ``Im Ĥ_i`` and the residuals are named ``<target>[j]``, each isolating its target.

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`discrete_game_setup` (the model and the projectors ``Ĥ_i``).
    L : (n, p) array
        The constant gain in Murray's filtered form; the generator's observer gain is ``Φ L``.
    targets : sequence of str, optional
        The targets whose projected residuals are produced, in this order (default every target of the setup).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[j]`` tied to its target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    ResidualGenerator
        The discrete filter with state matrix ``Φ(I − LC)`` and residuals ``<target>[j]``.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, steps=20)
    >>> L = np.full((3, 2), 0.1)
    >>> gen = discrete_game_generator(st, L)
    >>> gen.residuals, bool(np.allclose(gen.A, m.A @ (np.eye(3) - L @ m.C)))
    (('f1[0]', 'f2[0]'), True)

    References
    ----------
    Murray 2012, §5.1.1, (5.3), (5.6); §2.2.2 (the discrete detection filter).
    """
    m = setup.model
    res_names, blocks, iso = [], [], []
    for t in targets if targets is not None else setup.names:
        Qi = linalg.orth(setup.problem.projectors[t])
        blocks.append(Qi)
        res_names += [f"{t}[{j}]" for j in range(Qi.shape[1])]
        iso += [t] * Qi.shape[1]
    gen = observer_generator(m, m.A @ np.asarray(L, dtype=float), res_names, np.hstack(blocks))
    return label_generator(gen, m, names, isolates, default_isolates=iso)
