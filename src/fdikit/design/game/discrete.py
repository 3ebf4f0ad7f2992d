"""Discrete-time game-theoretic detection filters: DGTFDF and DGTMFDF (Murray 2012, Ch. 5).

Both run the observer (5.3) on a *discrete* model (``Φ = model.A``) with the projected residuals ``r̄_i = Ĥ_i r``
of :func:`~fdikit.design.game.discrete_setup.discrete_game_generator`; the setup, the DARI propagation, the
secondary cost and the gain formula (5.41) are in :mod:`fdikit.design.game.discrete_setup`.

**Gain convention.**  Murray's ``L`` is the *filtered-form* gain of the a-posteriori update; the designs
keep it as ``filter_gain`` (and ``dgtmfdf(L0=…)`` takes it in that form, as the text writes every equation).
Their ``gain`` is fdikit's observer (predictor) gain ``ΦL``: the generator's state matrix is
``Φ − (ΦL) C = Φ(I − LC)``, the sign and form of python-control's ``dlqe`` and of every other design.

* **DGTFDF** (one target, (5.42)–(5.43)): ``Σ = Θ − Cᵀ(ĤQĤ − V⁻¹)C``, ``Θ̃ = [ΦΣ⁻¹Φᵀ + F̂MF̂ᵀ/γ]⁻¹``,
  ``L = Σ⁻¹CᵀV⁻¹`` (erratum: (5.42b) prints Λ for Σ).  The DARI recursion of
  :func:`~fdikit.design.game.discrete_setup.discrete_game_riccati` reproduces it exactly at this gain, which
  minimises ``P(k+1)`` given ``P(k)``.
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
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from fdikit import validate
from fdikit.design.game.discrete_setup import (
    GUARD,
    DiscreteGameSetup,
    GameRiccatiSolution,
    discrete_game_generator,
    discrete_game_riccati,
    gain_update,
    infeasible,
    secondary_cost,
)
from fdikit.errors import DesignError, ParameterError
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["DiscreteGtfdfDesign", "dgtfdf", "DiscreteGtmfdfDesign", "dgtmfdf"]


@dataclass(frozen=True, eq=False)
class DiscreteGtfdfDesign(FieldReport):
    """Discrete single-fault game filter (DGTFDF, Murray 2012, (5.42)–(5.43)).

    Made by :func:`dgtfdf` (or :func:`~fdikit.design.game.single_fault.single_fault_game_filter` on a discrete
    model); ``report()`` gives the ``REPORT`` fields as a dict, ``internal_form()`` plant and filter in series, and
    ``information(k)`` ``Θ(k) = P(k)⁻¹``.

    Attributes
    ----------
    generator : ResidualGenerator
        The observer (5.3) at the final gain with the projected residual of ``target`` (``"<target>[j]"``).
    target : str
        The target fault.
    gain : (n, p) array
        The observer (predictor) gain ``Φ L(k1 − 1)``: the generator's state matrix is ``Φ − gain·C``.
    filter_gain : (n, p) array
        Murray's filtered-form ``L(k1 − 1)`` (``gain = Φ @ filter_gain``).
    filter_gains : (steps, n, p) array
        ``L(k) = Σ(k)⁻¹CᵀV⁻¹``, filtered form, k = k0 … k1 − 1.
    covariances : (steps + 1, n, n) array
        ``P(k) = Θ(k)⁻¹``, k = k0 … k1.
    levels : (steps,) array
        ``λ_max(Q^½ĤCP(k)CᵀĤQ^½)`` (all below 1: ``Γ(k) > 0``).
    poles : (n,) complex array
        Eigenvalues of ``Φ(I − LC)`` at the final gain.
    settled : bool
        Whether the gain's last relative change is below ``settle_rtol``.
    settling_step : int or None
        The first k after which every relative change of the gain stays below ``settle_rtol`` (None if it has
        not settled).

    Examples
    --------
    >>> from fdikit.design.game.discrete_setup import discrete_game_setup
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1"], ["f2"], gamma=1e-2, Vbar=1.0, Q=1e-3,
    ...                          M=5.0, P0=1e-2, steps=50)
    >>> d = dgtfdf(st)
    >>> d.target, d.filter_gains.shape, d.covariances.shape, d.generator.residuals
    ('f1', (50, 3, 2), (51, 3, 3), ('f1[0]',))
    >>> bool(np.allclose(d.gain, st.model.A @ d.filter_gain))
    True

    References
    ----------
    Murray 2012, §5.3, (5.42)–(5.43); the observer: §5.1.1, (5.3).
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
        """``Θ(k) = P(k)⁻¹`` (n x n) at step ``k`` (default the last, k1)."""
        Pi = np.linalg.inv(self.covariances[k])
        return (Pi + Pi.T) / 2

    REPORT = ("target", "gain", "filter_gain", "poles", "levels", "settled", "settling_step")


def dgtfdf(
    setup: DiscreteGameSetup,
    targets: str | Sequence[str] | None = None,
    settle_rtol: float = 1e-8,
    *,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> DiscreteGtfdfDesign:
    """Discrete single-fault game-theoretic detection filter (Murray 2012, (5.42)–(5.43)), time-varying gain.

    From ``Θ(k0) = Π_0``: ``Σ = Θ − Cᵀ(ĤQĤ − V⁻¹)C``, ``Θ̃ = [ΦΣ⁻¹Φᵀ + F̂MF̂ᵀ/γ]⁻¹``, ``L(k) = Σ⁻¹CᵀV⁻¹``,
    computed as ``Σ⁻¹ = Γ⁻¹ − L CΓ⁻¹``, ``L = Γ⁻¹Cᵀ(V + CΓ⁻¹Cᵀ)⁻¹`` with ``Γ = Θ − CᵀĤQĤC > 0`` checked at
    every step.  The target is blocked from its ``F̂_i``.  A bank of these is the "UIO" of Murray §6.1.1.
    The generator uses the last gain.  ``filter_gain(s)`` hold Murray's ``L``; ``gain = Φ @ filter_gain`` is the
    observer gain (module docstring).

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`~fdikit.design.game.discrete_setup.discrete_game_setup` (γ, ``V``, ``Q``, ``M``, ``P0``
        and the horizon).
    targets : str or one-element sequence of str, optional
        The one target of the setup to detect (a ``":magnitude"``/``":rate"`` suffix is ignored); default the
        setup's only target.
    settle_rtol : float, optional
        Relative change of the gain from one step to the next below which it counts as settled (default 1e-8).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[j]`` tied to the target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    DiscreteGtfdfDesign
        The generator at the last gain, the gain sequence, the covariances, the levels and the poles.

    Raises
    ------
    ParameterError
        ``setup`` not a :class:`~fdikit.design.game.discrete_setup.DiscreteGameSetup`, more than one target
        named, no target named when the setup has several, or a name that is not a target of the setup.
    DesignError
        Positivity of ``Γ = Θ − CᵀĤQĤC`` lost at a step (γ is not attainable with these weights; the message
        gives the step).

    Examples
    --------
    >>> from fdikit.design.game.discrete_setup import discrete_game_setup
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer().discretize(0.01)
    >>> st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-2, Vbar=1e-2 / 0.01, Q=1e-3, M=5.0, steps=1000)
    >>> d = dgtfdf(st)
    >>> d.settled, d.settling_step, bool(np.all(np.abs(d.poles) < 1))
    (True, 417, True)

    References
    ----------
    Murray 2012, §5.3, (5.42)–(5.43) (erratum: (5.42b) prints Λ for Σ), Proposition 5.2; the bank: §6.1.1.
    """
    validate.instance("setup", setup, DiscreteGameSetup, "build it with discrete_game_setup(...)")
    if targets is None and len(setup.names) > 1:
        raise ParameterError(f"the setup has targets {list(setup.names)}; name the one the single-fault filter detects")
    given = [setup.names[0]] if targets is None else [targets] if isinstance(targets, str) else list(targets)
    if len(given) != 1:
        raise ParameterError(f"dgtfdf detects one target, got {given}; use dgtmfdf for several")
    target = str(given[0]).partition(":")[0]
    if target not in setup.names:
        raise ParameterError(f"{target!r} is not a target of the setup; targets are {list(setup.names)}")
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
        if levels[k] >= GUARD:
            raise infeasible(setup, target, k, P[k], levels[k])
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
        discrete_game_generator(setup, L, [target], names=names, isolates=isolates), target, Phi @ L, L, gains, P,
        levels,
        scipy.linalg.eigvals(Phi @ (np.eye(m.n) - L @ C)), settled,
        (int(above[-1]) + 2 if above.size else 1) if settled else None, model=setup.model,
    )


@dataclass(frozen=True, eq=False)
class DiscreteGtmfdfDesign(FieldReport):
    """Discrete multiple-fault game filter (DGTMFDF, Murray 2012, (5.31)–(5.41)), one constant gain.

    Made by :func:`dgtmfdf` (or :func:`~fdikit.design.game.multi_fault.game_filter` on a discrete model);
    ``report()`` gives the ``REPORT`` fields as a dict and ``internal_form()`` plant and filter in series.

    Attributes
    ----------
    generator : ResidualGenerator
        The observer (5.3) with the projected residuals ``"<target>[j]"`` of every target.
    gain : (n, p) array
        The observer (predictor) gain ``Φ L``: the generator's state matrix is ``Φ − gain·C``.
    filter_gain : (n, p) array
        Murray's filtered-form ``L`` (``gain = Φ @ filter_gain``).
    poles : (n,) complex array
        Eigenvalues of ``Φ(I − LC)`` (moduli at most ``max_radius``).
    sigma_min : float
        ``σ_min(I − LC)``.
    cost, initial_cost : float
        ``J̄`` (5.31) at the final and at the initial gain.
    gradient : (n, p) array
        ``∂J̄/∂L`` at the final gain.
    method : str
        The stages run: ``'fixed-point'``, ``'gradient'`` or ``'fixed-point+gradient'``.
    iterations : tuple of int
        Accepted (5.41) steps and optimiser iterations.
    riccati : GameRiccatiSolution
        The DARI solution at the final gain (:func:`~fdikit.design.game.discrete_setup.discrete_game_riccati`).
    notes : tuple of str
        Why each stage stopped.

    Examples
    --------
    >>> from fdikit.design.game.discrete_setup import discrete_game_setup
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1,
    ...                          M=1.0, K=1.0, N=1.0, steps=20)
    >>> d = dgtmfdf(st, maxiter=20)
    >>> d.generator.residuals, d.filter_gain.shape, sorted(d.riccati.covariances)
    (('f1[0]', 'f2[0]'), (3, 2), ['f1', 'f2'])

    References
    ----------
    Murray 2012, §5.2.2, (5.31)–(5.41); the observer: §5.1.1, (5.3).
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
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> DiscreteGtmfdfDesign:
    """Discrete game-theoretic multiple-fault detection filter, constant gain (Murray 2012, §5.2.2, (5.31)–(5.41)).

    Minimises the secondary cost ``J̄`` (:func:`~fdikit.design.game.discrete_setup.secondary_cost`) over one
    constant gain that keeps every target's DARI feasible (module docstring).

    Parameters
    ----------
    setup : DiscreteGameSetup
        From :func:`~fdikit.design.game.discrete_setup.discrete_game_setup`, with nonzero ``K_i``/``N_i``.
    L0 : (n, p) array, optional
        Initial gain in Murray's filtered form (``filter_gain``; an observer gain ``G`` is ``Φ⁻¹G``);
        default the mean of the targets' :func:`dgtfdf` filter gains or the one of them with the lowest
        cost (the first acceptable).  A Beard–Jones gain is a good start at small γ.
    method : {'auto', 'fixed-point', 'gradient'}, optional
        ``'fixed-point'`` iterates (5.41), accepting a (halved up to 4 times) step only if
        ``σ_min(I − LC) ≥ min_sigma``, the DARI stays feasible and ``J̄`` does not rise;
        ``'gradient'`` runs ``scipy.optimize.minimize(method='trust-constr')`` with a BFGS Hessian
        and the exact gradient on ``J̄`` (rejected gains count as +∞, so the region shrinks);
        ``'auto'`` (default) runs the first, then the second unless (5.41) converged.
    maxiter : int, optional
        Iterations of each stage (default 200).
    min_sigma : float, optional
        The (5.41) guard on ``σ_min(I − LC)`` (default 1e-3).
    max_radius : float, optional
        Every accepted gain keeps ``ρ(Φ(I − LC)) ≤ max_radius`` (in (0, 1); default 0.99); use
        ``exp(−σΔt)`` for a decay rate σ [1/s].  The optimum usually sits on this bound.
    xtol : float, optional
        (5.41) has converged when its step is below ``xtol`` times ``‖L‖`` (default 1e-8).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[j]`` tied to each target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    DiscreteGtmfdfDesign
        The generator at the final gain, both gain forms, the poles, the cost before and after, the stages run
        and the DARI solution.

    Raises
    ------
    ParameterError
        ``setup`` not a :class:`~fdikit.design.game.discrete_setup.DiscreteGameSetup`, an unknown ``method``,
        ``maxiter`` not a positive integer, ``max_radius`` outside (0, 1), or ``L0`` not an n x p matrix.
    DesignError
        All cost weights zero (the multiplier vanishes, §5.2.2), an unacceptable ``L0`` (DARI infeasible,
        ``I − L0C`` singular or ``ρ(Φ(I − L0C)) > max_radius``), or no acceptable default start.

    Examples
    --------
    >>> from fdikit.design.game.discrete_setup import discrete_game_setup
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> st = discrete_game_setup(white_speyer().discretize(0.01), ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1,
    ...                          M=1.0, K=1.0, N=1.0, steps=20)
    >>> d = dgtmfdf(st, maxiter=20)
    >>> d.method, bool(d.cost < d.initial_cost), bool(np.abs(d.poles).max() <= 0.99)
    ('fixed-point+gradient', True, True)

    References
    ----------
    Murray 2012, §5.2.2, (5.31)–(5.41), Remarks 5.1 and 5.3; the stability bound: §6.1, Remarks 6.1–6.2.
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
        discrete_game_generator(setup, L, names=names, isolates=isolates), m.A @ L, L,
        scipy.linalg.eigvals(m.A @ (np.eye(m.n) - L @ m.C)),
        float(np.linalg.svd(np.eye(m.n) - L @ m.C, compute_uv=False)[-1]), J, J_init, g, "+".join(stages),
        (it_fp, it_gd), discrete_game_riccati(setup, L), tuple(notes), model=setup.model,
    )
