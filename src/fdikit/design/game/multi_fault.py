"""Multiple-fault game-theoretic detection filter (GTMFDF): one gain for all targets, steady state.

Murray 2012, Ch. 3 and Ch. 6; Chung & Speyer 1998; Douglas et al. 1996, Ch. 9.  One observer

    x̂' = A x̂ + Bu u + L (y − C x̂ − Du u),    r = y − C x̂ − Du u,    r̄_i = Ĥ_i r

serves ``s`` target faults.  For each target ``i`` the disturbance-attenuation problem (3.11)
bounds the transmission from the complementary faults ``F̂_i`` (other targets and nuisance),
the sensor noise and the initial error to the projected residual ``Ĥ_i C e`` by γ; it holds
when the Riccati equation (3.26)/(3.28) ``0 = Π_i(A − LC) + (A − LC)ᵀΠ_i + Π_i R_i Π_i + Q̄_i``
has a stabilizing solution ``Π_i ≥ 0`` (Theorem 3.1), with ``R_i = F̂_i M_i F̂_iᵀ/γ + L V Lᵀ``,
``Q̄_i = Cᵀ Ĥ_i Q_i Ĥ_i C`` and ``V = V̄/γ`` (V̄ = sensor-noise weight).  Small γ means strong
blocking (γ → 0 recovers the restricted-diagonal/Beard–Jones structure); γ → ∞ the Kalman filter.

* :func:`game_filter` — the multiple-fault GTMFDF (3.27)–(3.28): ``L`` minimises
  ``J(L) = Σ_i tr(W_i Π_i(L))``, ``W_i = F̂_i K_i F̂_iᵀ/γ − F_i N_i F_iᵀ``, by gradient-based
  optimisation with margins on ``Re λ(A − LC)`` and on the Hamiltonian spectra;
* :func:`~fdikit.design.game.riccati.game_riccati`, :func:`~fdikit.design.game.riccati.game_cost` — the
  per-target Riccati solution for a given gain and the cost with its analytic gradient.

A discrete model (``model.dt`` set) runs the discrete multiple-fault filter of Murray 2012, Ch. 5
(:func:`~fdikit.design.game.discrete.dgtmfdf`).  The single-fault filter and the bank are in
:mod:`fdikit.design.game.single_fault`.  Residuals are named ``"<target>[k]"``: the coordinates of ``Ĥ_i r`` in
an orthonormal basis of ``Im Ĥ_i`` (fdikit's sign convention ``r = y − ŷ``), tied to their target for isolation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from fdikit import validate
from fdikit.design.game.discrete import DiscreteGtmfdfDesign, dgtmfdf
from fdikit.design.game.riccati import (
    checked_gain,
    checked_gamma,
    require_continuous,
    stacked_cost,
    target_margins,
    target_terms,
)
from fdikit.design.game.setup import GameProblem, game_problem, per_target, weight
from fdikit.design.game.single_fault import (
    continuous_only,
    discrete_setup,
    given_names,
    residual_basis,
    residual_names,
    single_fault_game_filter,
)
from fdikit.design.labels import label_generator
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import ProblemDesign
from fdikit.residuals import ResidualGenerator

__all__ = [
    "GameDesign",
    "game_filter",
]


#: Methods of :func:`scipy.optimize.minimize` (lower case; scipy compares case-insensitively).
_MINIMIZE_METHODS = ("nelder-mead", "powell", "cg", "bfgs", "newton-cg", "l-bfgs-b", "tnc", "cobyla", "cobyqa",
                     "slsqp", "trust-constr", "dogleg", "trust-ncg", "trust-exact", "trust-krylov")


# ---------------------------------------------------------------------------- multiple faults
@dataclass(frozen=True, eq=False)
class GameDesign(ProblemDesign):
    """Steady-state game-theoretic multiple-fault detection filter (GTMFDF, Murray 2012 (3.27)–(3.28)).

    Attributes
    ----------
    generator : one observer; residuals ``"<target>[k]"`` (coordinates of ``Ĥ_i r``) for every target.
    gain : optimised ``L`` (n x p).
    poles : eigenvalues of ``A − L C``.
    riccati : ``Π_i`` by target (stabilizing solutions of (3.28) at ``gain``).
    hamiltonian_margins : ``min |Re λ(H_i)|`` by target.
    projectors : ``Ĥ_i`` by target.
    cost : ``J(gain)`` of (3.27); ``initial_cost`` at ``initial_gain``.
    success, status, message, nit : the optimiser's report (:func:`scipy.optimize.minimize`).
    problem : the :class:`~fdikit.design.game.setup.GameProblem`.

    Made by :func:`game_filter` for a continuous model; ``report()`` gives the same numbers as a dict.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> d = game_filter(white_speyer("stable-extra-zero"), ["f1", "f2"], M=0.05, Q=1e-3, options={"maxiter": 3})
    >>> d.gain.shape, sorted(d.riccati), bool(d.cost <= d.initial_cost)
    ((3, 2), ['f1', 'f2'], True)

    References
    ----------
    Murray 2012, §3.2.3, (3.26)–(3.28), Theorem 3.1.
    """

    generator: ResidualGenerator
    gain: np.ndarray
    poles: np.ndarray
    riccati: dict[str, np.ndarray]
    hamiltonian_margins: dict[str, float]
    projectors: dict[str, np.ndarray]
    cost: float
    initial_gain: np.ndarray
    initial_cost: float
    success: bool
    status: int
    message: str
    nit: int
    problem: GameProblem


    def report(self) -> dict:
        """``gain`` (``L``), ``poles``, ``riccati`` (``Π_i``) and ``hamiltonian_margins`` by target, ``projectors``
        (``Ĥ_i``), ``cost`` and ``initial_cost`` (``J`` of (3.27)) and the optimiser's ``success``, ``message``,
        ``nit``."""
        return {"gain": self.gain, "poles": self.poles, "riccati": self.riccati,
                "hamiltonian_margins": self.hamiltonian_margins, "projectors": self.projectors, "cost": self.cost,
                "initial_cost": self.initial_cost, "success": self.success, "message": self.message, "nit": self.nit}


def _barrier(s: np.ndarray, width: np.ndarray) -> float:
    """C¹ log-barrier: ``−log z + z − 1`` for ``z = s/width < 1``, 0 beyond (inactive far from the bound)."""
    z = s / width
    return float(np.sum(np.where(z < 1, -np.log(np.maximum(z, 1e-300)) + z - 1, 0.0)))


def _initial_gain(prob, tg, given, g, Vw, Q, M, eps) -> np.ndarray:
    """Average of the single-fault GTFDF gains; if that violates the margins, the feasible single-fault
    gain of lowest cost (the average can be unstable, e.g. Murray 2012, §6.2.4)."""
    Qs, Ms = per_target("Q", Q, prob, given), per_target("M", M, prob, given)
    gains = [
        single_fault_game_filter(prob.model, {t.name: t.F}, {"complementary": t.Fhat}, gamma=g, V=Vw,
                                 Q=Qs[t.name], M=Ms[t.name]).gain
        for t in tg
    ]
    average = sum(gains) / len(gains)
    if np.all(target_margins(prob, average, tg, Vw) - eps > 0):
        return average
    costs = []
    for L in gains:
        try:
            ok = np.all(target_margins(prob, L, tg, Vw) - eps > 0)
            costs.append(stacked_cost(prob, L, tg, Vw)[0] if ok else np.inf)
        except DesignError:
            costs.append(np.inf)
    if not np.isfinite(min(costs)):
        raise DesignError(
            "neither the average of the single-fault game-filter gains nor any of them meets the margins of the "
            "multiple-fault problem; give a feasible initial gain L0 (e.g. a Beard–Jones gain) or increase gamma"
        )
    return gains[int(np.argmin(costs))]


def game_filter(
    model: FaultModel,
    targets: Sequence[str] | Mapping[str, np.ndarray],
    nuisance: Sequence[str] | Mapping[str, np.ndarray] | str = (),
    *,
    gamma: float = 1e-6,
    V=1.0,
    Q=1e-4,
    M=0.01,
    K=0.01,
    N=1.0,
    L0=None,
    eps_stab: float | None = None,
    eps_ham: float | None = None,
    barrier: float | None = None,
    method: str | None = None,
    options: Mapping | None = None,
    P0=None,
    steps: int | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> GameDesign | DiscreteGtmfdfDesign:
    """Game-theoretic multiple-fault detection filter, steady state (Murray 2012, (3.27)–(3.28)).

    Minimises ``J(L) = Σ_i tr[(F̂_i K_i F̂_iᵀ/γ − F_i N_i F_iᵀ) Π_i(L)]`` over the shared gain, each
    ``Π_i`` the stabilizing solution of (3.28).  ``K_i`` penalises complementary-fault transmission
    (pushes ``F̂_i`` into ``Ker Π_i``), ``N_i`` rewards target transmission (sensitivity enhancement,
    §6.1.4).  With ``s = 1`` this is the enhanced single-fault design of §3.3/§6.1.4(a).

    **Optimiser.**  :func:`scipy.optimize.minimize` (``method``, default ``'L-BFGS-B'``; any method
    that uses a gradient) on ``J(L)/|J(L0)| + barrier · Σ_j b(s_j/w_j)`` with the analytic gradient
    of ``J`` (:func:`~fdikit.design.game.riccati.game_cost`) and eigenvalue-perturbation gradients of the margins.
    The slacks are
    ``s_0 = −max Re λ(A − LC) − eps_stab`` and ``s_i = min |Re λ(H_i)| − eps_ham``;
    ``b(z) = −log z + z − 1`` for ``z < 1`` and 0 otherwise is a C¹ log-barrier that acts only when
    a margin has fallen below its value at ``L0`` (``w_j = s_j(L0)``); points outside the
    constraints (or without a stabilizing Riccati solution) return a huge cost, like Murray's
    handling of ``care`` failures (Remark 6.2).  The dissertation used MATLAB ``fminunc``/``fmincon``
    with unstated margins and tolerances.

    .. warning:: The cost is **unbounded below** as a Hamiltonian eigenvalue approaches the
       imaginary axis (``Π_i`` grows and ``−tr N F Π F → −∞``), and it has many
       local minima.  The result therefore depends on ``L0``, the margins, ``barrier`` and the
       stopping rules; check the isolation of the design (e.g. DC gains of ``Ĥ_i C (sI − A + LC)⁻¹ F_j``)
       rather than trusting the optimum.

    **Discrete model** (``model.dt`` set): the discrete multiple-fault filter of Murray 2012, Ch. 5
    (DGTMFDF, one constant gain over a finite horizon) — ``dgtmfdf(discrete_game_setup(model, targets,
    nuisance, gamma=gamma, Vbar=gamma * V, Q=Q, M=M, K=K, N=N, P0=P0, steps=steps), L0, method=method,
    **options)``.  ``V`` keeps its meaning ``V̄/γ``; ``Q``, ``M``, ``K``, ``N`` are per-sample weights of
    the finite-horizon cost (5.39) (from a continuous design at Δt: ``Q Δt``, ``M/Δt``, ``V/Δt``,
    ``K, N ∝ 1/Δt²``); ``P0`` defaults to ``gamma`` (``P(k0) = I``) and ``steps`` to 500; ``L0`` is in
    Murray's filtered form; ``method`` is ``'auto'`` (default), ``'fixed-point'`` or ``'gradient'`` and
    ``options`` takes the keywords ``maxiter``, ``min_sigma``, ``max_radius``, ``xtol`` of
    :func:`~fdikit.design.game.discrete.dgtmfdf` (which stays available for a prepared setup).
    ``eps_stab``, ``eps_ham`` and ``barrier`` belong to the continuous optimiser and are refused; the
    discrete stability bound is ``options={'max_radius': …}``.

    Parameters
    ----------
    model : FaultModel, continuous (steady-state design) or discrete (Murray Ch. 5, above).
    targets : target faults (fault names resolved by :func:`fdikit.fault_maps.resolve_faults`, or a
        mapping name → F); ``F̂_i`` = the other targets plus the ``nuisance`` faults.
    nuisance : faults every residual must block: ``()`` (default) none, ``'others'`` every fault
        input of the model that is not a target, or names / a mapping name → F.
    gamma : attenuation bound (Murray's examples: 1e−6).
    V : ``V̄/γ`` (p x p or scalar).
    Q, M, K, N : Riccati and cost weights, one value or a mapping target → value (``Q`` p x p,
        ``M``, ``K`` sized to ``F̂_i``, ``N`` sized to ``F_i``; scalars mean multiples of I).
    L0 : initial gain; default the average of the single-fault GTFDF gains
        (:func:`single_fault_game_filter` per target with ``F̂_i``, ``Q_i``, ``M_i``), or, when the
        average violates the margins, the feasible single-fault gain of lowest cost.
    eps_stab, eps_ham : required margins on ``Re λ(A − LC)`` and ``|Re λ(H_i)|`` (default 1e-3 each).
    barrier : weight of the barrier relative to the normalised cost (default 1e-2).
    method, options : passed to :func:`scipy.optimize.minimize` (default ``'L-BFGS-B'`` and options
        ``{'maxiter': 500}``); for a discrete model see above.
    P0, steps : discrete models only: initial-error weight (``P(k0) = P0/γ``) and horizon in samples.
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[k]`` tied to each target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    GameDesign or DiscreteGtmfdfDesign
        The latter for a discrete model; its ``gain`` is the observer (predictor) gain ``Φ L`` and
        ``filter_gain`` Murray's filtered-form ``L``.

    Raises
    ------
    DesignError
        Bad weights, or an initial gain that violates the margins or has no stabilizing Riccati
        solution (give a feasible ``L0``, or relax ``eps_stab``/``eps_ham``).
    ParameterError
        ``P0``/``steps`` for a continuous model; ``eps_stab``/``eps_ham``/``barrier``, an unknown
        ``method`` or ``options`` key for a discrete one.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> d = game_filter(white_speyer("stable-extra-zero"), ["f1", "f2"], M=0.05, Q={"f1": 1e-3, "f2": 2e-3},
    ...                 K=0.1, N={"f1": 5.0, "f2": 10.0})
    >>> d.generator.residuals, bool(d.cost < d.initial_cost)
    (('f1[0]', 'f2[0]'), True)

    References
    ----------
    Murray 2012, §3.2.2–3.2.3, (3.26)–(3.28), §6.1.4, Remark 6.2; discrete: Murray 2012, §5.2.2, (5.39).
    """
    if model.is_discrete:
        given = [nm for nm, val in (("eps_stab", eps_stab), ("eps_ham", eps_ham), ("barrier", barrier))
                 if val is not None]
        if given:
            raise ParameterError(f"{', '.join(given)} are margins of the continuous optimiser; for a discrete model "
                                 f"(dt={model.dt}) bound the filter poles with options={{'max_radius': ...}}")
        dmethod = validate.choice("discrete optimiser method", "auto" if method is None else method,
                                  ("auto", "fixed-point", "gradient"))
        if options is not None and not isinstance(options, Mapping):
            raise ParameterError(f"options must be a mapping of dgtmfdf keywords, got {type(options).__name__}")
        unknown = sorted(set(options or {}) - {"maxiter", "min_sigma", "max_radius", "xtol"})
        if unknown:
            raise ParameterError(f"options {unknown} are not keywords of the discrete design; use maxiter, "
                                 "min_sigma, max_radius, xtol")
        setup = discrete_setup(model, targets, nuisance, gamma=gamma, V=V, Q=Q, M=M, K=K, N=N, P0=P0,
                                steps=steps)
        return dgtmfdf(setup, L0, method=dmethod, names=names, isolates=isolates, **dict(options or {}))
    continuous_only(model, P0=P0, steps=steps)
    eps_stab = 1e-3 if eps_stab is None else eps_stab
    eps_ham = 1e-3 if eps_ham is None else eps_ham
    barrier = 1e-2 if barrier is None else barrier
    method = "L-BFGS-B" if method is None else method
    require_continuous(model)
    g = checked_gamma(gamma)
    if not callable(method):
        validate.choice("optimiser method", method.lower() if isinstance(method, str) else method, _MINIMIZE_METHODS)
    for nm, val in (("eps_stab", eps_stab), ("eps_ham", eps_ham), ("barrier", barrier)):
        validate.non_negative(nm, val)
    if options is not None and not isinstance(options, Mapping):
        raise ParameterError(
            f"options must be a mapping of scipy.optimize.minimize options, got {type(options).__name__}"
        )
    prob = game_problem(model, targets, nuisance)
    given = given_names(targets)
    tg = target_terms(prob, g, Q, M, K, N, given)
    Vw = weight("V", V, model.p)
    n, p = model.n, model.p
    eps = np.array([eps_stab] + [eps_ham] * len(tg), dtype=float)
    if L0 is None:
        L0 = _initial_gain(prob, tg, given, g, Vw, Q, M, eps)
    L0 = checked_gain(prob, L0)
    s0 = target_margins(prob, L0, tg, Vw) - eps
    if np.any(s0 <= 0):
        raise DesignError(
            f"the initial gain violates the margins (stability slack {s0[0]:.3g}, Hamiltonian slacks "
            f"{np.round(s0[1:], 6).tolist()}); give a feasible L0 or reduce eps_stab/eps_ham"
        )
    try:
        J0, _, _, _ = stacked_cost(prob, L0, tg, Vw)
    except DesignError as exc:
        raise DesignError(f"the initial gain has no stabilizing game Riccati solution: {exc}; give another L0") from exc
    scale = max(abs(J0), 1e-300)
    best = {"f": np.inf, "x": L0.ravel().copy()}

    def fun(x: np.ndarray):
        L = x.reshape(n, p)
        s = target_margins(prob, L, tg, Vw) - eps
        if np.any(s <= 0):
            return 1e10, np.zeros_like(x)
        try:
            J, G, _, _ = stacked_cost(prob, L, tg, Vw)
        except DesignError:
            return 1e10, np.zeros_like(x)
        b = _barrier(s, s0)
        f = J / scale + barrier * b
        grad = G / scale
        if barrier and b > 0:  # the barrier and its gradient vanish where every margin exceeds its width
            _, ds = target_margins(prob, L, tg, Vw, grad=True)
            z = s / s0
            for j in np.flatnonzero(z < 1):
                grad = grad + barrier * (1 - 1 / z[j]) / s0[j] * ds[j]
        if f < best["f"]:
            best["f"], best["x"] = f, x.copy()
        return f, grad.ravel()

    opts = {"maxiter": 500} | dict(options or {})
    res = scipy.optimize.minimize(fun, L0.ravel(), jac=True, method=method, options=opts)
    x = res.x if fun(res.x)[0] <= best["f"] else best["x"]
    L = x.reshape(n, p)
    J, _, pis, margins = stacked_cost(prob, L, tg, Vw)
    bases = {t: residual_basis(prob.projectors[t]) for t in prob.names}
    res_names = [nm for t in prob.names for nm in residual_names(t, bases[t].shape[1])]
    iso = [t for t in prob.names for _ in range(bases[t].shape[1])]
    gen = label_generator(observer_generator(model, L, res_names, np.hstack(list(bases.values()))), model, names,
                          isolates, default_isolates=iso)
    return GameDesign(
        generator=gen, gain=L, poles=scipy.linalg.eigvals(model.A - L @ model.C), riccati=pis,
        hamiltonian_margins=margins, projectors=dict(prob.projectors), cost=J, initial_gain=L0, initial_cost=J0,
        success=bool(res.success), status=int(res.status), message=str(res.message), nit=int(getattr(res, "nit", 0)),
        problem=prob,
    )
