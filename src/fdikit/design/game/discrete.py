"""Discrete-time game-theoretic detection filters: DGTFDF and DGTMFDF (Murray 2012, Ch. 5).

Observer (5.3) on a *discrete* model (``Φ = model.A``); the residual uses the a-priori estimate
(the text's (2.19c) prints x̂, (2.20c) and (5.3c) say x̄)::

    x̄(k+1) = Φ x̂(k) + Bu u(k),   x̂(k) = x̄(k) + L (y − C x̄ − Du u),   r = y − C x̄ − Du u,   r̄_i = Ĥ_i r

i.e. the predictor ``x̄(k+1) = Φ x̄ + Bu u + ΦL (y − C x̄ − Du u)`` (``observer_generator`` with gain ``ΦL``).

**Gain convention.**  Murray's ``L`` is the *filtered-form* gain of the a-posteriori update; the designs
keep it as ``filter_gain`` (and :func:`discrete_game_riccati`, :func:`secondary_cost`, :func:`gain_update`,
:func:`discrete_game_generator` and ``dgtmfdf(L0=…)`` take it in that form, as the text writes every
equation).  Their ``gain`` is fdikit's observer (predictor) gain ``ΦL``: the generator's state matrix is
``Φ − (ΦL) C = Φ(I − LC)``, the sign and form of python-control's ``dlqe`` and of every other design.

Target ``i`` (``F̂_i``, ``Ĥ_i`` from :func:`~fdikit.design.game.setup.game_problem`) meets its
disturbance-attenuation problem (5.8) when the DARI (5.23) ≡ (5.29) ≡ (5.30) has ``Π_i ≥ 0``.  With
equality and ``P = Π⁻¹`` ((5.29) and (5.44b) rewritten in ``P``; for ``L = Λ⁻¹CᵀV⁻¹`` it is (5.42))::

    P(k+1) = Φ [(I − LC)(P⁻¹ − CᵀĤQĤC)⁻¹(I − LC)ᵀ + L V Lᵀ] Φᵀ + F̂MF̂ᵀ/γ,     P(k0) = P0/γ

with ``V = V̄/γ`` and ``Π_0 = γP0⁻¹`` (5.9).  It needs ``Γ = P⁻¹ − CᵀĤQĤC > 0`` at every step
(Proposition 5.2), checked as ``λ_max(RPRᵀ) < 1`` with ``R = Q^½ĤC``; ``Γ⁻¹ = P + PRᵀ(I − RPRᵀ)⁻¹RP``
avoids inverting ``P``.  Φ and ``I − LC`` must be invertible (Ch. 5 assumption).

* **DGTFDF** (one target, (5.42)–(5.43)): ``Σ = Θ − Cᵀ(ĤQĤ − V⁻¹)C``, ``Θ̃ = [ΦΣ⁻¹Φᵀ + F̂MF̂ᵀ/γ]⁻¹``,
  ``L = Σ⁻¹CᵀV⁻¹`` (erratum: (5.42b) prints Λ for Σ).  The recursion above reproduces it exactly at
  this gain, which minimises ``P(k+1)`` given ``P(k)``.
* **DGTMFDF** (targets sharing one gain, (5.31)–(5.41)): minimise ``J̄ = Σ_i Σ_{k0}^{k1−1} tr(W_iΠ_i(k))``,
  ``W_i = F̂_iK_iF̂_iᵀ/γ − F_iN_iF_iᵀ`` (5.39).  fdikit keeps **one constant gain** over the horizon
  (the text's L may vary with k), so the filter is LTI.  Gradient: (5.34) summed over k, multiplier
  run backward by (5.35) from ``Δ(k1) = 0`` (the forward form (5.38) is not the inverse of (5.35) —
  erratum — and is not used).  (5.41) equals stationarity only through the factors
  ``(I − LC)ᵀ·½∇J̄·V⁻¹(I − CL)``: its fixed-point iteration can converge where ``I − LC`` is singular and
  ``∇J̄ ≠ 0``.  So every (5.41) step must keep ``σ_min(I − LC)`` above a guard,
  stay feasible and lower ``J̄``; otherwise a trust-region quasi-Newton method continues on the true
  cost.  The finite-horizon cost does not enforce stability and, unconstrained, drives a filter
  pole to the unit circle (measured on the F-16XL); accepted gains keep ``ρ(Φ(I − LC)) ≤ max_radius``
  (the stability constraint of the text's ``fmincon`` runs, Remarks 6.1–6.2), and the optimum then
  sits on that bound.  Remark 5.1: no steady-state theory exists; everything is finite-horizon.

Other errata applied: (5.2a) prints ``Φ x(k)`` for the state ``x_i``, read ``Φ x_i(k)``; (5.23), (5.26), (5.27)
need ``F̂_iᵀ`` where the
text prints ``F̂_iΓ̂_iΦL``; (3.32)/(5.9) start from ``P0/γ``, not ``γP0``.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from fdikit import linalg, validate
from fdikit.design.game.setup import GameProblem, game_problem, per_target, weight
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = [
    "DiscreteGameSetup", "discrete_game_setup", "GameRiccatiSolution", "discrete_game_riccati", "secondary_cost",
    "gain_update", "discrete_game_generator", "DiscreteGtfdfDesign", "dgtfdf", "DiscreteGtmfdfDesign", "dgtmfdf",
]

_GUARD = 1.0 - 1e-10  # λ_max(RPRᵀ) at or above this: Γ = P⁻¹ − RᵀR is not positive definite


@dataclass(frozen=True, eq=False)
class DiscreteGameSetup:
    """Partition, weights and horizon of a discrete game filter (Murray 2012, (5.8), (5.9), (5.39)).

    Attributes
    ----------
    problem : targets, ``F̂_i``, ``Ĥ_i``.  gamma : γ (small = strong blocking).  V : ``V̄/γ``.
    P_init : ``P(k0) = P0/γ = Π_0⁻¹``.  steps : horizon ``k1 − k0``.
    Q, M, K, N : per-target weights (p x p; k̂_i; k̂_i; k_i square).
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
        return self.problem.model

    @property
    def names(self) -> tuple[str, ...]:
        return self.problem.names

    def nuisance_covariance(self, name: str) -> np.ndarray:
        """``F̂_i M_i F̂_iᵀ / γ``."""
        F = self.problem.complementary[name]
        return F @ self.M[name] @ F.T / self.gamma

    def cost_weight(self, name: str) -> np.ndarray:
        """``W_i = F̂_iK_iF̂_iᵀ/γ − F_iN_iF_iᵀ`` of the example cost (5.39)."""
        F, Fh = self.problem.targets[name], self.problem.complementary[name]
        return Fh @ self.K[name] @ Fh.T / self.gamma - F @ self.N[name] @ F.T

    def output_weight_root(self, name: str) -> np.ndarray:
        """``R_i = Q_i^½ Ĥ_i C``, so that ``CᵀĤ_iQ_iĤ_iC = R_iᵀR_i``."""
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

    Parameters
    ----------
    model : discrete FaultModel (sample a continuous plant with ``model.discretize(dt)``).
    targets, nuisance : as in :func:`~fdikit.design.game.setup.game_problem`.
    gamma : attenuation bound γ > 0.  Vbar : measurement-noise weight ``V̄ > 0``; ``V = V̄/γ``.
    Q, M, K, N : output weight ``Q_i ≥ 0`` (p x p), complementary-fault weight ``M_i > 0`` and
        secondary-cost weights ``K_i`` (on ``F̂_i``), ``N_i`` (on ``F_i``): scalar, matrix or a
        mapping target → value.  Sampling a continuous design at Δt: ``Q_d = Q_cΔt``,
        ``M_d = M_c/Δt`` (fault columns ZOH-sampled, ≈ ``F_cΔt``), ``V_d = V_c/Δt``.
    P0 : initial-error weight, ``P(k0) = P0/γ`` (``Π_0 = γP0⁻¹``).  ``Q·P0/γ`` must stay below 1
        along ``ĤC`` or the DARI fails at k0 — the initial error reaches the a-priori residual.
    steps : horizon ``k1 − k0`` in samples.

    Raises
    ------
    DesignError
        Continuous model, γ ≤ 0, singular Φ, ``V̄``, ``P0`` or ``M_i`` not positive definite, a weight
        of the wrong size.
    """
    if not model.is_discrete:
        raise DesignError("the discrete game filter needs a discrete model; sample the plant with model.discretize(dt)")
    validate.instance("model", model, FaultModel)
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

    Attributes
    ----------
    covariances : ``P_i(k)`` by target, shape (steps + 1, n, n), ``P_i(k0) = P0/γ``.
    levels : ``λ_max(Q_i^½Ĥ_iCP_i(k)CᵀĤ_iQ_i^½)``, k = k0 … k1 − 1; below 1 ⇔ ``Γ_i(k) > 0``.
    gamma_inverses : ``Γ_i(k)⁻¹``, shape (steps, n, n).
    """

    covariances: dict[str, np.ndarray]
    levels: dict[str, np.ndarray]
    gamma_inverses: dict[str, np.ndarray]

    def information(self, name: str, k: int = -1) -> np.ndarray:
        """``Π_i(k) = P_i(k)⁻¹``."""
        Pi = np.linalg.inv(self.covariances[name][k])
        return (Pi + Pi.T) / 2


def _check_gain(L: np.ndarray, C: np.ndarray, floor: float = 1e-10) -> float:
    smin = float(np.linalg.svd(np.eye(L.shape[0]) - L @ C, compute_uv=False)[-1])
    if smin <= floor:
        raise DesignError(f"I − LC is singular (σ_min = {smin:.3g}); Murray 2012 Ch. 5 needs an invertible I − LC — "
                          "choose a gain whose a-posteriori update does not cancel a state direction")
    return smin


def _infeasible(setup: DiscreteGameSetup, name: str, k: int, P: np.ndarray, level: float) -> DesignError:
    R = setup.output_weight_root(name)
    lam = float(np.linalg.eigvalsh(np.linalg.inv(P) - R.T @ R).min())
    return DesignError(
        f"target {name!r}: the game Riccati recursion loses P⁻¹ − CᵀĤQĤC > 0 at step k = {k} (smallest eigenvalue "
        f"{lam:.3g}; λ_max(Q^½ĤCPCᵀĤQ^½) = {level:.4g} ≥ 1): the attenuation bound γ = {setup.gamma:g} is not met "
        "with this gain — lower Q or P0, raise γ or M, or change the gain"
    )


def discrete_game_riccati(setup: DiscreteGameSetup, L) -> GameRiccatiSolution:
    """Propagate the DARI with equality (Murray 2012, (5.17), (5.29)–(5.30)) for a given gain, all targets at once.

    ``L`` (Murray's filtered form, a design's ``filter_gain``) is n x p (constant) or a (steps, n, p)
    sequence.  Raises :class:`DesignError` naming the target, the step and the smallest eigenvalue of
    ``P⁻¹ − CᵀĤQĤC`` when positivity is lost, or when ``I − L(k)C`` is singular.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-2, Vbar=1e-2 / 0.01, Q=1e-3, M=5.0, P0=1e-2, steps=50)
    >>> bool(discrete_game_riccati(st, dgtfdf(st).filter_gain).levels["f1"].max() < 1)
    True
    """
    m, steps, names = setup.model, setup.steps, setup.names
    n = m.n
    L = np.asarray(L, dtype=float)
    if L.shape not in ((n, m.p), (steps, n, m.p)):
        raise DesignError(f"gain has shape {L.shape}; give n x p = {n} x {m.p} or a ({steps}, {n}, {m.p}) sequence")
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
            np.linalg.cholesky(S * (1 + 1e-10) - 1e-10 * eye_p)  # ⇔ λ_max(RPRᵀ) < _GUARD
        except np.linalg.LinAlgError:
            lv = 1.0 - np.linalg.eigvalsh(S).min(axis=-1)
            i = int(np.argmax(lv))
            raise _infeasible(setup, names[i], k, P[k, i], float(lv[i])) from None
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
        raise DesignError(f"the secondary optimisation uses one constant gain: L must be n x p = "
                          f"{setup.model.n} x {setup.model.p}, got shape {L.shape}")
    return L


def secondary_cost(setup: DiscreteGameSetup, L) -> tuple[float, np.ndarray]:
    """``J̄(L) = Σ_i Σ_{k=k0}^{k1−1} tr(W_iΠ_i(k))`` and its exact gradient (Murray 2012, (5.31)–(5.40)).

    ``L`` is constant over the horizon; the gradient is (5.34) summed over k with the backward
    multiplier (5.35) from ``Δ(k1) = 0`` (5.36).  :class:`DesignError` when the DARI is infeasible.
    """
    L = _constant_gain(setup, L)
    cost, grad, _, _ = _adjoint(setup, L, discrete_game_riccati(setup, L))
    return cost, grad


def gain_update(setup: DiscreteGameSetup, L) -> np.ndarray:
    """The gain formula (5.41), summed over targets and the horizon, with ``Γ_i, Λ_i`` evaluated at ``L``.

    ``L⁺ = [Σ Γ_iΛ_i(Γ_i + CᵀV⁻¹C)]⁻¹ [Σ Γ_iΛ_iCᵀV⁻¹]``.  Its residual ``Σ Γ_iΛ_i[(Γ_i + CᵀV⁻¹C)L − CᵀV⁻¹]``
    equals ``(I − LC)ᵀ·½∇J̄·V⁻¹(I − CL)``, so a fixed point is stationary only while ``I − LC`` is invertible.
    """
    L = _constant_gain(setup, L)
    _, _, lhs, rhs = _adjoint(setup, L, discrete_game_riccati(setup, L))
    try:
        return np.linalg.solve(lhs, rhs)
    except np.linalg.LinAlgError as exc:
        raise DesignError("Σ Γ_iΛ_i(Γ_i + CᵀV⁻¹C) of (5.41) is singular: the null spaces overlap across targets "
                          "(Murray 2012, Remark 5.3); raise the weights N_i or K_i") from exc


# ---------------------------------------------------------------------- generators and designs
def discrete_game_generator(setup: DiscreteGameSetup, L, targets: Sequence[str] | None = None) -> ResidualGenerator:
    """Residual generator of the observer (5.3) with projected residuals ``Q_iᵀ r`` (Murray 2012, (5.3), (5.6)).

    ``x̄(k+1) = Φ(I − LC) x̄ + (Bu − ΦL Du) u + ΦL y``, ``r = y − C x̄ − Du u``; ``Q_i`` is an orthonormal
    basis of ``Im Ĥ_i`` and the residuals are named ``<target>[j]``, each isolating its target.
    """
    m = setup.model
    names, blocks, isolates = [], [], []
    for t in targets if targets is not None else setup.names:
        Qi = linalg.orth(setup.problem.projectors[t])
        blocks.append(Qi)
        names += [f"{t}[{j}]" for j in range(Qi.shape[1])]
        isolates += [t] * Qi.shape[1]
    return observer_generator(m, m.A @ np.asarray(L, dtype=float), names, np.hstack(blocks), isolates)


@dataclass(frozen=True, eq=False)
class DiscreteGtfdfDesign(FieldReport):
    """Discrete single-fault game filter (DGTFDF, Murray 2012, (5.42)–(5.43)).

    Attributes
    ----------
    generator : observer (5.3) at the final gain, projected residual of ``target``.
    gain : the observer (predictor) gain ``Φ L(k1 − 1)``: the generator's state matrix is ``Φ − gain·C``.
    filter_gain : Murray's filtered-form ``L(k1 − 1)`` (``gain = Φ @ filter_gain``).
    filter_gains : ``L(k) = Σ(k)⁻¹CᵀV⁻¹``, shape (steps, n, p), filtered form.
    covariances : ``P(k) = Θ(k)⁻¹``, shape (steps + 1, n, n).  levels : ``λ_max(Q^½ĤCP(k)CᵀĤQ^½)`` (< 1).
    poles : eigenvalues of ``Φ(I − LC)`` at the final gain.
    settled : the gain's last relative change is below ``settle_rtol``; settling_step : first k after
        which every relative change stays below it (None if it has not settled).
    """

    generator: ResidualGenerator
    target: str
    gain: np.ndarray
    filter_gain: np.ndarray
    filter_gains: np.ndarray
    covariances: np.ndarray
    levels: np.ndarray
    poles: np.ndarray
    settled: bool
    settling_step: int | None

    def information(self, k: int = -1) -> np.ndarray:
        """``Θ(k) = P(k)⁻¹``."""
        Pi = np.linalg.inv(self.covariances[k])
        return (Pi + Pi.T) / 2

    REPORT = ("target", "gain", "filter_gain", "poles", "levels", "settled", "settling_step")


def dgtfdf(setup: DiscreteGameSetup, targets: str | Sequence[str] | None = None,
           settle_rtol: float = 1e-8) -> DiscreteGtfdfDesign:
    """Discrete single-fault game-theoretic detection filter (Murray 2012, (5.42)–(5.43)), time-varying gain.

    From ``Θ(k0) = Π_0``: ``Σ = Θ − Cᵀ(ĤQĤ − V⁻¹)C``, ``Θ̃ = [ΦΣ⁻¹Φᵀ + F̂MF̂ᵀ/γ]⁻¹``, ``L(k) = Σ⁻¹CᵀV⁻¹``,
    computed as ``Σ⁻¹ = Γ⁻¹ − L CΓ⁻¹``, ``L = Γ⁻¹Cᵀ(V + CΓ⁻¹Cᵀ)⁻¹`` with ``Γ = Θ − CᵀĤQĤC > 0`` checked at
    every step.  ``targets`` names the one target of the setup to detect (a fault name or a
    one-element sequence; default: the setup's only target); it is blocked from its ``F̂_i``.  A bank
    of these is the "UIO" of Murray §6.1.1.  The generator uses the last gain.  ``filter_gain(s)`` hold
    Murray's ``L``; ``gain = Φ @ filter_gain`` is the observer gain (module docstring).

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-2, Vbar=1e-2 / 0.01, Q=1e-3, M=5.0, steps=2000)
    >>> d = dgtfdf(st)
    >>> d.settled, bool(np.all(np.abs(d.poles) < 1))
    (True, True)
    """
    validate.instance("setup", setup, DiscreteGameSetup, "build it with discrete_game_setup(...)")
    if targets is None and len(setup.names) > 1:
        raise DesignError(f"the setup has targets {list(setup.names)}; name the one the single-fault filter detects")
    given = [setup.names[0]] if targets is None else [targets] if isinstance(targets, str) else list(targets)
    if len(given) != 1:
        raise ParameterError(f"dgtfdf detects one target, got {given}; use dgtmfdf for several")
    target = str(given[0]).partition(":")[0]
    if target not in setup.names:
        raise DesignError(f"{target!r} is not a target of the setup; targets are {list(setup.names)}")
    m = setup.model
    Phi, C, V = m.A, m.C, setup.V
    R, Nc = setup.output_weight_root(target), setup.nuisance_covariance(target)
    P = np.empty((setup.steps + 1, m.n, m.n))
    gains = np.empty((setup.steps, m.n, m.p))
    levels = np.empty(setup.steps)
    P[0] = setup.P_init
    for k in range(setup.steps):
        RP = R @ P[k]
        levels[k] = float(np.linalg.eigvalsh(RP @ R.T).max())
        if levels[k] >= _GUARD:
            raise _infeasible(setup, target, k, P[k], levels[k])
        Ginv = P[k] + RP.T @ np.linalg.solve(np.eye(m.p) - RP @ R.T, RP)
        GC = Ginv @ C.T
        gains[k] = np.linalg.solve(V + C @ GC, GC.T).T
        Pn = Phi @ (Ginv - gains[k] @ GC.T) @ Phi.T + Nc
        P[k + 1] = (Pn + Pn.T) / 2
    change = np.linalg.norm(np.diff(gains, axis=0), axis=(1, 2)) / np.linalg.norm(gains[1:], axis=(1, 2))
    above = np.flatnonzero(change >= settle_rtol)
    settled = bool(change.size and change[-1] < settle_rtol)
    L = gains[-1]
    return DiscreteGtfdfDesign(
        discrete_game_generator(setup, L, [target]), target, Phi @ L, L, gains, P, levels,
        scipy.linalg.eigvals(Phi @ (np.eye(m.n) - L @ C)), settled,
        (int(above[-1]) + 2 if above.size else 1) if settled else None, model=setup.model,
    )


@dataclass(frozen=True, eq=False)
class DiscreteGtmfdfDesign(FieldReport):
    """Discrete multiple-fault game filter (DGTMFDF, Murray 2012, (5.31)–(5.41)), one constant gain.

    Attributes
    ----------
    generator : observer (5.3) with the projected residuals of every target.
    gain : the observer (predictor) gain ``Φ L`` (state matrix ``Φ − gain·C``); filter_gain : Murray's ``L``.
    poles : eigenvalues of ``Φ(I − LC)``; sigma_min : ``σ_min(I − LC)``.
    cost, initial_cost : ``J̄`` at the final and the initial gain; gradient : ``∂J̄/∂L`` at the end.
    method : stages run (``'fixed-point'``, ``'gradient'`` or both); iterations : accepted (5.41)
        steps, optimiser iterations.  riccati : the DARI solution at the final gain.
    notes : why each stage stopped.
    """

    generator: ResidualGenerator
    gain: np.ndarray
    filter_gain: np.ndarray
    poles: np.ndarray
    sigma_min: float
    cost: float
    initial_cost: float
    gradient: np.ndarray
    method: str
    iterations: tuple[int, int]
    riccati: GameRiccatiSolution
    notes: tuple[str, ...]

    REPORT = ("gain", "filter_gain", "poles", "sigma_min", "cost", "initial_cost", "method", "iterations", "notes")


def _try_cost(setup: DiscreteGameSetup, L: np.ndarray, floor: float, max_radius: float):
    """Cost and gradient; None if L is rejected (DARI infeasible, σ_min(I − LC) < floor, ρ(Φ(I − LC)) > max_radius)."""
    m = setup.model
    IL = np.eye(m.n) - L @ m.C
    if np.linalg.svd(IL, compute_uv=False)[-1] < floor or np.abs(np.linalg.eigvals(m.A @ IL)).max() > max_radius:
        return None
    try:
        return secondary_cost(setup, L)
    except DesignError:
        return None


def dgtmfdf(
    setup: DiscreteGameSetup,
    L0=None,
    *,
    method: str = "auto",
    maxiter: int = 200,
    min_sigma: float = 1e-3,
    max_radius: float = 0.99,
    xtol: float = 1e-8,
) -> DiscreteGtmfdfDesign:
    """Discrete game-theoretic multiple-fault detection filter, constant gain (Murray 2012, §5.2.2, (5.31)–(5.41)).

    Parameters
    ----------
    setup : from :func:`discrete_game_setup`, with nonzero ``K_i``/``N_i``.
    L0 : initial gain in Murray's filtered form (``filter_gain``; an observer gain ``G`` is ``Φ⁻¹G``);
        default the mean of the targets' :func:`dgtfdf` filter gains or the one of them with the lowest
        cost (the first acceptable).  A Beard–Jones gain is a good start at small γ.
    method : ``'fixed-point'`` iterates (5.41), accepting a (halved up to 4 times) step only if
        ``σ_min(I − LC) ≥ min_sigma``, the DARI stays feasible and ``J̄`` does not rise;
        ``'gradient'`` runs ``scipy.optimize.minimize(method='trust-constr')`` with a BFGS Hessian
        and the exact gradient on ``J̄`` (rejected gains count as +∞, so the region shrinks);
        ``'auto'`` runs the first, then the second unless (5.41) converged.
    maxiter : iterations of each stage.  min_sigma : the (5.41) guard.  xtol : (5.41) convergence.
    max_radius : every accepted gain keeps ``ρ(Φ(I − LC)) ≤ max_radius`` (< 1); use
        ``exp(−σΔt)`` for a decay rate σ.  The optimum usually sits on this bound.

    Raises
    ------
    DesignError
        Bad ``method`` or ``max_radius``, all cost weights zero (the multiplier vanishes, §5.2.2), or
        an unacceptable ``L0`` (no acceptable default).
    """
    validate.instance("setup", setup, DiscreteGameSetup, "build it with discrete_game_setup(...)")
    if method not in ("auto", "fixed-point", "gradient"):
        raise ParameterError(f"unknown method {method!r}; use 'auto', 'fixed-point' or 'gradient'")
    validate.integer("maxiter", maxiter, minimum=1)
    max_radius = validate.number("max_radius", max_radius)
    if not 0 < max_radius < 1:
        raise ParameterError(f"max_radius must lie in (0, 1) so that the filter is stable, got {max_radius}")
    if not any(np.any(setup.cost_weight(t)) for t in setup.names):
        raise DesignError("the secondary cost weights K_i and N_i are all zero: the multiplier Δ_i vanishes and (5.41) "
                          "gives no gain (Murray 2012, §5.2.2); set K (complementary) and N (target) weights")
    m = setup.model
    if L0 is None:
        singles = [dgtfdf(setup, t).filter_gain for t in setup.names]
        scored = [(c, r) for c in [np.mean(singles, axis=0)] + singles
                  if (r := _try_cost(setup, c, 1e-10, max_radius)) is not None]
        if not scored:
            raise DesignError("neither the mean nor any single-fault DGTFDF gain is feasible and within max_radius for "
                              "every target; give L0 (e.g. a Beard–Jones gain), raise γ or M, or lower Q")
        L, (J, g) = min(scored, key=lambda cr: cr[1][0])
    else:
        L = validate.as_matrix("L0", L0, (m.n, m.p))
        if L.shape != (m.n, m.p):
            raise DesignError(f"L0 has shape {L.shape}; it must be n x p = {m.n} x {m.p}")
        if (res := _try_cost(setup, L, 1e-10, max_radius)) is None:
            raise DesignError(f"L0 is not acceptable: the DARI is infeasible (see discrete_game_riccati(setup, L0)), "
                              f"I − L0C is singular or ρ(Φ(I − L0C)) > max_radius = {max_radius}")
        J, g = res
    J_init, stages, notes, it_fp, it_gd = J, [], [], 0, 0
    converged = False
    if method in ("auto", "fixed-point"):
        stages.append("fixed-point")
        reason = f"reached maxiter = {maxiter}"
        for _ in range(maxiter):
            step = gain_update(setup, L) - L
            if np.linalg.norm(step) <= xtol * np.linalg.norm(L):
                reason, converged = "converged", True
                break
            for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625):
                res = _try_cost(setup, L + alpha * step, min_sigma, max_radius)
                if res is not None and res[0] <= J + 1e-13 * abs(J):
                    L, (J, g), it_fp = L + alpha * step, res, it_fp + 1
                    break
            else:
                smin = np.linalg.svd(np.eye(m.n) - (L + step) @ m.C, compute_uv=False)[-1]
                reason = (f"guard: σ_min(I − L⁺C) = {smin:.3g} < {min_sigma:g}, (5.41) heads for a singular I − LC"
                          if smin < min_sigma else "no feasible, cost-decreasing step along (5.41)")
                break
        notes.append(f"fixed-point: {reason} after {it_fp} accepted steps")
    if method == "gradient" or (method == "auto" and not converged):
        stages.append("gradient")
        sL, sJ = np.linalg.norm(L) or 1.0, abs(J) or 1.0

        def fun(x):
            r = _try_cost(setup, x.reshape(L.shape) * sL, 1e-10, max_radius)
            return (np.inf, np.zeros_like(x)) if r is None else (r[0] / sJ, r[1].ravel() * sL / sJ)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the BFGS update is skipped after rejected steps
            opt = scipy.optimize.minimize(fun, L.ravel() / sL, jac=True, hess=scipy.optimize.BFGS(),
                                          method="trust-constr", options={"maxiter": maxiter, "gtol": 1e-12,
                                                                          "xtol": 1e-12, "initial_tr_radius": 0.01})
        res = _try_cost(setup, opt.x.reshape(L.shape) * sL, 1e-10, max_radius)
        if res is not None and res[0] <= J:
            L, (J, g) = opt.x.reshape(L.shape) * sL, res
        it_gd = int(opt.nit)
        notes.append(f"gradient: {opt.message} ({opt.nit} iterations)")
    return DiscreteGtmfdfDesign(
        discrete_game_generator(setup, L), m.A @ L, L, scipy.linalg.eigvals(m.A @ (np.eye(m.n) - L @ m.C)),
        float(np.linalg.svd(np.eye(m.n) - L @ m.C, compute_uv=False)[-1]), J, J_init, g, "+".join(stages),
        (it_fp, it_gd), discrete_game_riccati(setup, L), tuple(notes), model=setup.model,
    )
