"""Continuous steady-state game-theoretic (disturbance-attenuation) detection filters.

Murray 2012, Ch. 3 and Ch. 6; Chung & Speyer 1998; Douglas et al. 1996, Ch. 9.  One observer

    x̂' = A x̂ + Bu u + L (y − C x̂ − Du u),    r = y − C x̂ − Du u,    r̄_i = Ĥ_i r

serves ``s`` target faults.  For each target ``i`` the disturbance-attenuation problem (3.11)
bounds the transmission from the complementary faults ``F̂_i`` (other targets and nuisance),
the sensor noise and the initial error to the projected residual ``Ĥ_i C e`` by γ; it holds
when the Riccati equation (3.26)/(3.28) ``0 = Π_i(A − LC) + (A − LC)ᵀΠ_i + Π_i R_i Π_i + Q̄_i``
has a stabilizing solution ``Π_i ≥ 0`` (Theorem 3.1), with ``R_i = F̂_i M_i F̂_iᵀ/γ + L V Lᵀ``,
``Q̄_i = Cᵀ Ĥ_i Q_i Ĥ_i C`` and ``V = V̄/γ`` (V̄ = sensor-noise weight).  Small γ means strong
blocking (γ → 0 recovers the restricted-diagonal/Beard–Jones structure); γ → ∞ the Kalman filter.

* :func:`single_fault_game_filter` — the single-fault GTFDF (3.29)–(3.30) in covariance form:
  ``0 = A P + P Aᵀ + F̂ M F̂ᵀ/γ − P Cᵀ (V⁻¹ − Ĥ Q Ĥ) C P``, ``L = P Cᵀ V⁻¹`` (no optimisation);
* :func:`game_filter_bank` — one single-fault filter per fault (Murray's "UIO" bank, §6.1.1);
* :func:`game_filter` — the multiple-fault GTMFDF (3.27)–(3.28): ``L`` minimises
  ``J(L) = Σ_i tr(W_i Π_i(L))``, ``W_i = F̂_i K_i F̂_iᵀ/γ − F_i N_i F_iᵀ``, by gradient-based
  optimisation with margins on ``Re λ(A − LC)`` and on the Hamiltonian spectra;
* :func:`game_riccati`, :func:`game_cost` — the per-target Riccati solution for a given gain and
  the cost with its analytic gradient.

Residuals are named ``"<target>[k]"``: the coordinates of ``Ĥ_i r`` in an orthonormal basis of
``Im Ĥ_i`` (fdikit's sign convention ``r = y − ŷ``), tied to their target for isolation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from fdikit import linalg, validate
from fdikit.design.game.discrete import (
    DiscreteGameSetup,
    DiscreteGtfdfDesign,
    DiscreteGtmfdfDesign,
    dgtfdf,
    dgtmfdf,
    discrete_game_setup,
)
from fdikit.design.game.riccati import (
    checked_gain,
    checked_gamma,
    require_continuous,
    solve_game_are,
    stacked_cost,
    target_margins,
    target_terms,
)
from fdikit.design.game.setup import GameProblem, game_problem, per_target, weight
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.linalg import resolve_nuisance
from fdikit.model import FaultModel
from fdikit.protocols import joined_form
from fdikit.residuals import ResidualGenerator, stack_generators

__all__ = [
    "GameDesign",
    "GameBankDesign",
    "SingleFaultGameDesign",
    "game_filter",
    "game_filter_bank",
    "single_fault_game_filter",
]


#: Methods of :func:`scipy.optimize.minimize` (lower case; scipy compares case-insensitively).
_MINIMIZE_METHODS = ("nelder-mead", "powell", "cg", "bfgs", "newton-cg", "l-bfgs-b", "tnc", "cobyla", "cobyqa",
                     "slsqp", "trust-constr", "dogleg", "trust-ncg", "trust-exact", "trust-krylov")


# ---------------------------------------------------------------------------- helpers
def _inv_pd(name: str, W: np.ndarray) -> np.ndarray:
    if W.size and np.linalg.eigvalsh(W).min() <= 1e-14 * max(1.0, np.abs(W).max()):
        raise ParameterError(f"weight {name} must be positive definite (it is inverted)")
    return np.linalg.inv(W)


def _residual_basis(H: np.ndarray) -> np.ndarray:
    """Orthonormal basis of ``Im Ĥ`` (p x rank Ĥ): the coordinates of the projected residual."""
    return linalg.orth(H)


def _names(target: str, k: int) -> list[str]:
    return [f"{target}[{j}]" for j in range(k)]


def _given_names(spec) -> list[str]:
    return [str(k) for k in spec] if not isinstance(spec, str) else [spec]


def _discrete_setup(model, targets, nuisance, *, gamma, V, Q, M, K=0.0, N=0.0, P0=None, steps=None
                    ) -> DiscreteGameSetup:
    """The Murray Ch. 5 setup for a discrete model with the continuous entry points' weights.

    ``V`` keeps its meaning (Murray's ``V = V̄/γ``, so ``Vbar = γ V``); ``Q``, ``M``, ``K``, ``N`` are passed
    as they are (per-sample weights); ``P0`` defaults to ``γ`` (``P(k0) = P0/γ = I``) and ``steps`` to 500.
    """
    g = checked_gamma(gamma)
    return discrete_game_setup(model, targets, nuisance, gamma=g, Vbar=weight("V", V, model.p) * g, Q=Q, M=M,
                               K=K, N=N, P0=g if P0 is None else P0, steps=500 if steps is None else steps)


def _continuous_only(model: FaultModel, **given) -> None:
    """Refuse the discrete design's horizon arguments on a continuous model."""
    bad = [k for k, v in given.items() if v is not None]
    if bad:
        raise ParameterError(f"{', '.join(bad)} set the finite horizon of the discrete design (a model with dt); "
                             "the continuous design is steady-state — leave them unset")


# ---------------------------------------------------------------------------- single fault
@dataclass(frozen=True, eq=False)
class SingleFaultGameDesign:
    """Single-fault game-theoretic detection filter (GTFDF, Murray 2012 (3.29)–(3.30)).

    Attributes
    ----------
    generator : residual generator; residuals ``"<target>[k]"`` = coordinates of ``Ĥ r``.
    gain : ``L = P Cᵀ V⁻¹`` (n x p).
    poles : eigenvalues of ``A − L C``.
    covariance : ``P = Γ⁻¹``, the stabilizing solution of the covariance-form Riccati equation.
    projector : ``Ĥ`` (p x p).
    target : resolved target name.
    problem : the :class:`~fdikit.design.game.setup.GameProblem` (one target).
    solver : ``'care'`` (``V⁻¹ − ĤQĤ + γ(I−Ĥ)R(I−Ĥ) > 0``) or ``'hamiltonian'`` (indefinite).
    """

    generator: ResidualGenerator
    gain: np.ndarray
    poles: np.ndarray
    covariance: np.ndarray
    projector: np.ndarray
    target: str
    problem: GameProblem
    solver: str

    def internal_form(self) -> FaultModel:
        """The plant ``model`` and this filter in series, from ``(u, d, f, w)`` to ``r``.

        ``generator.internal_form(model)`` (:meth:`~fdikit.residuals.ResidualGenerator.internal_form`) with the
        model the design was made for (the model of ``problem``).
        """
        return joined_form(self, self.problem.model)

    def report(self) -> dict:
        """``target``, ``gain`` (``L``), ``poles`` (of ``A − L C``), ``covariance`` (``P``), ``projector`` (``Ĥ``)
        and ``solver`` (which Riccati solver gave ``P``)."""
        return {"target": self.target, "gain": self.gain, "poles": self.poles, "covariance": self.covariance,
                "projector": self.projector, "solver": self.solver}


def single_fault_game_filter(
    model: FaultModel,
    targets: str | Sequence[str] | Mapping[str, np.ndarray],
    nuisance: Sequence[str] | Mapping[str, np.ndarray] | str = (),
    *,
    gamma: float = 1e-6,
    V=1.0,
    Q=1e-4,
    M=0.01,
    R=0.0,
    P0=None,
    steps: int | None = None,
) -> SingleFaultGameDesign | DiscreteGtfdfDesign:
    """Single-fault game-theoretic detection filter, steady state (Murray 2012, (3.29)–(3.30)).

    Solves, in the covariance form ``P = Γ⁻¹`` (Murray 2012, §3.3: (3.32) is (3.16) written in
    ``P_i = Π_i⁻¹``; here its steady state at ``L = P Cᵀ V⁻¹``)::

        0 = A P + P Aᵀ + F̂ M F̂ᵀ/γ − P Cᵀ S C P,   S = V⁻¹ − Ĥ Q Ĥ + γ (I − Ĥ) R (I − Ĥ)
        L = P Cᵀ V⁻¹

    by :func:`scipy.linalg.solve_continuous_are` when ``S > 0``, else by the Hamiltonian Schur
    solver :func:`fdikit.design.game.riccati.solve_game_are`.

    **Scaling (Murray ↔ PATH).**  Murray's ``V`` is ``V̄/γ`` with ``V̄`` the sensor-noise weight of
    the attenuation ratio (3.11).  Douglas et al. 1996, (9.4)/(9.15)/(9.17), write the noise weight
    ``V_PATH`` (= V̄) inside the ratio and ``γ·V_PATH⁻¹`` in the game cost, so ``V = V_PATH/γ``;
    their extra weight ``R_1`` on ``N_1 C e = (I − Ĥ) C e`` sits next to ``V_PATH⁻¹`` in the
    denominator and also enters the cost multiplied by γ, hence the term ``γ (I − Ĥ) R (I − Ĥ)``
    above (``R`` in PATH's units).  PATH's ``P_PATH = γ Π⁻¹`` (9.17) is ``γ P`` here, and their gain
    (9.26) ``γ Π⁻¹ Cᵀ V_PATH⁻¹ = P Cᵀ V⁻¹`` is the same ``L`` (R does not enter the gain directly).
    To reproduce PATH's example (ν = 1e−8, ν/γ = 0.8, Q = R = M = I): ``gamma = 1.25e-8``,
    ``V = 0.8`` (= ν/γ), ``Q = 1``, ``M = 1``, ``R = 1``.

    **Discrete model** (``model.dt`` set): the discrete single-fault filter of Murray 2012, Ch. 5
    (DGTFDF, (5.42)–(5.43)) — ``dgtfdf(discrete_game_setup(model, targets, nuisance, gamma=gamma,
    Vbar=gamma * V, Q=Q, M=M, P0=P0, steps=steps))``: ``V`` keeps its meaning ``V̄/γ``, ``Q`` and ``M``
    are per-sample weights (from a continuous design at Δt: ``Q Δt``, ``M/Δt``, ``V/Δt``), ``P0``
    (default ``gamma``, i.e. ``P(k0) = I``) and ``steps`` (default 500) fix the finite horizon whose last
    gain the generator uses.  ``R`` must be 0 (Ch. 5 has no ``R_1`` term).
    :func:`~fdikit.design.game.discrete.dgtfdf` stays available for a prepared setup.

    Parameters
    ----------
    model : FaultModel, continuous (steady-state design) or discrete (Murray Ch. 5, above).
    targets : the one fault to detect — a fault name resolved by :func:`fdikit.linalg.resolve_faults`
        (``'<output>_sensor'`` = sensor fault ``[F¹, A F¹]``, ``'<control>_actuator'`` = actuator fault,
        a fault input of the model), a one-element sequence of it, or a mapping ``{name: F}``.
    nuisance : faults to block (names or mapping), forming ``F̂``: ``()`` (default) none, ``'others'``
        every other fault input of the model.
    gamma : attenuation bound γ > 0 (small = strong blocking).
    V : Murray's ``V = V̄/γ`` (p x p or scalar), positive definite.
    Q : output weight (p x p or scalar) on ``Ĥ C e``.
    M : complementary-fault weight (dim F̂ square, or scalar).
    R : PATH's weight ``R_1`` on ``(I − Ĥ) C e`` (p x p or scalar; default 0 = Murray's form).
    P0, steps : discrete models only: initial-error weight (``P(k0) = P0/γ``) and horizon in samples.

    Returns
    -------
    SingleFaultGameDesign or DiscreteGtfdfDesign
        The latter for a discrete model; its ``gain`` is the observer (predictor) gain ``Φ L`` and
        ``filter_gain`` Murray's filtered-form ``L``.

    Raises
    ------
    DesignError
        A bad weight, a target hidden by the nuisance faults, or when the Riccati equation has no
        stabilizing nonnegative solution (γ too small for ``Q``; discrete: positivity lost at a step).
    ParameterError
        ``P0``/``steps`` for a continuous model, a nonzero ``R`` for a discrete one.

    Examples
    --------
    Murray 2012, Remark 6.8 (White–Speyer, F_2 = [0, 0, 1]; printed −1.1925, −4.1878, −100.14):

    >>> import numpy as np
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> d = single_fault_game_filter(white_speyer("unstable-extra-zero"), "f1", ["f2"],
    ...                              gamma=1e-6, V=1.0, Q=1e-4, M=0.01)
    >>> np.round(np.sort(d.poles.real), 4)
    array([-100.1401,   -4.1878,   -1.1925])
    """
    if model.is_discrete:
        if np.any(weight("R", R, model.p)):
            raise ParameterError("R (PATH's weight R_1) has no counterpart in the discrete design of Murray 2012 "
                                 "Ch. 5; leave R = 0 for a discrete model")
        setup = _discrete_setup(model, targets, nuisance, gamma=gamma, V=V, Q=Q, M=M, P0=P0, steps=steps)
        if len(setup.names) != 1:
            raise DesignError(f"single_fault_game_filter takes one target, got {list(setup.names)}; use game_filter")
        return dgtfdf(setup)
    _continuous_only(model, P0=P0, steps=steps)
    require_continuous(model)
    g = checked_gamma(gamma)
    prob = game_problem(model, targets, nuisance)
    if len(prob.names) != 1:
        raise DesignError(f"single_fault_game_filter takes one target, got {list(prob.names)}; use game_filter")
    name = prob.names[0]
    A, C, p = model.A, model.C, model.p
    Fhat, H = prob.complementary[name], prob.projectors[name]
    Vw = weight("V", V, p)
    Vi = _inv_pd("V", Vw)
    Qw, Rw = weight("Q", Q, p), weight("R", R, p)
    Mw = weight("M", M, Fhat.shape[1])
    N1 = np.eye(p) - H
    S = Vi - H @ Qw @ H + g * N1 @ Rw @ N1
    S = (S + S.T) / 2
    W = Fhat @ Mw @ Fhat.T / g
    W = (W + W.T) / 2
    if np.linalg.eigvalsh(S).min() > 1e-12 * np.abs(S).max():
        solver = "care"
        try:
            P = scipy.linalg.solve_continuous_are(A.T, C.T, W, np.linalg.inv(S))
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise DesignError(
                f"the single-fault game Riccati equation for {name!r} has no stabilizing solution ({exc}); "
                "check that (C, A) is detectable"
            ) from exc
    else:
        solver = "hamiltonian"
        P = solve_game_are(A.T, -C.T @ S @ C, W, what=f"the single-fault game Riccati equation for {name!r}").X
    P = (P + P.T) / 2
    ev = np.linalg.eigvalsh(P)
    if ev.min() < -1e-8 * max(ev.max(), 1e-300):
        raise DesignError(
            f"the single-fault game Riccati solution for {name!r} is not positive semidefinite (min eigenvalue "
            f"{ev.min():.3g}): the attenuation bound γ={g:g} is not achievable with Q; increase γ or decrease Q"
        )
    L = P @ C.T @ Vi
    poles = scipy.linalg.eigvals(A - L @ C)
    if np.any(poles.real >= 0):
        raise DesignError(f"the single-fault game filter for {name!r} is not stable: poles {np.round(poles, 6)}")
    basis = _residual_basis(H)
    gen = observer_generator(model, L, _names(name, basis.shape[1]), basis, [name] * basis.shape[1])
    return SingleFaultGameDesign(gen, L, poles, P, H, name, prob, solver)


@dataclass(frozen=True, eq=False)
class GameBankDesign:
    """A bank of single-fault game filters (Murray 2012, §6.1.1, the "UIO" bank).

    Attributes
    ----------
    generator : the stacked generator (one block of residuals ``"<fault>[k]"`` per filter).
    filters : the single-fault designs by fault name.
    """

    generator: ResidualGenerator
    filters: dict[str, SingleFaultGameDesign]

    @property
    def gains(self) -> dict[str, np.ndarray]:
        return {k: d.gain for k, d in self.filters.items()}

    @property
    def poles(self) -> dict[str, np.ndarray]:
        return {k: d.poles for k, d in self.filters.items()}

    def internal_form(self) -> FaultModel:
        """The plant ``model`` and this filter in series, from ``(u, d, f, w)`` to ``r``.

        ``generator.internal_form(model)`` (:meth:`~fdikit.residuals.ResidualGenerator.internal_form`) with the
        model the design was made for (the model of the filters' problems).
        """
        return joined_form(self, next(iter(self.filters.values())).problem.model)

    def report(self) -> dict:
        """By target fault: ``gains``, ``poles`` and ``projectors`` (``Ĥ_i``) of the single-fault filters."""
        return {"gains": self.gains, "poles": self.poles,
                "projectors": {k: d.projector for k, d in self.filters.items()}}


def game_filter_bank(
    model: FaultModel,
    targets: Sequence[str] | Mapping[str, np.ndarray],
    nuisance: Sequence[str] | Mapping[str, np.ndarray] | str = (),
    *,
    gamma: float = 1e-6,
    V=1.0,
    Q=1e-4,
    M=0.01,
) -> GameBankDesign:
    """One single-fault game filter per fault, each blocking all the others (Murray 2012, §6.1.1).

    Filter ``i`` has target ``F_i`` (``targets``: fault names or a mapping name → F) and
    ``F̂_i = [F_j]_{j≠i}`` plus the ``nuisance`` faults (blocked by every filter; ``()`` none,
    ``'others'`` every fault input of the model that is not a target).  ``Q`` and ``M`` may be one
    value or a mapping fault → value (``M`` is sized to each ``F̂_i``).  A bank does not need mutual
    detectability (Murray 2012, Remark 2.4): each filter forms only one detection space.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> bank = game_filter_bank(white_speyer("stable-extra-zero"), ["f1", "f2"], Q=1e-3, M=0.05)
    >>> bank.generator.residuals
    ('f1[0]', 'f2[0]')
    """
    require_continuous(model)
    prob = game_problem(model, targets, ())
    given = _given_names(targets)
    Qs, Ms = per_target("Q", Q, prob, given), per_target("M", M, prob, given)
    extra = resolve_nuisance(model, nuisance, list(prob.names))
    designs = {}
    for name in prob.names:
        others = {k: F for k, F in prob.targets.items() if k != name} | extra
        designs[name] = single_fault_game_filter(
            model, {name: prob.targets[name]}, others, gamma=gamma, V=V, Q=Qs[name], M=Ms[name]
        )
    return GameBankDesign(stack_generators([d.generator for d in designs.values()]), designs)


# ---------------------------------------------------------------------------- multiple faults
@dataclass(frozen=True, eq=False)
class GameDesign:
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

    def internal_form(self) -> FaultModel:
        """The plant ``model`` and this filter in series, from ``(u, d, f, w)`` to ``r``.

        ``generator.internal_form(model)`` (:meth:`~fdikit.residuals.ResidualGenerator.internal_form`) with the
        model the design was made for (the model of ``problem``).
        """
        return joined_form(self, self.problem.model)

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
    targets : target faults (fault names resolved by :func:`fdikit.linalg.resolve_faults`, or a
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
        setup = _discrete_setup(model, targets, nuisance, gamma=gamma, V=V, Q=Q, M=M, K=K, N=N, P0=P0,
                                steps=steps)
        return dgtmfdf(setup, L0, method=dmethod, **dict(options or {}))
    _continuous_only(model, P0=P0, steps=steps)
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
    given = _given_names(targets)
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
    bases = {t: _residual_basis(prob.projectors[t]) for t in prob.names}
    names = [nm for t in prob.names for nm in _names(t, bases[t].shape[1])]
    isolates = [t for t in prob.names for _ in range(bases[t].shape[1])]
    gen = observer_generator(model, L, names, np.hstack(list(bases.values())), isolates)
    return GameDesign(
        generator=gen, gain=L, poles=scipy.linalg.eigvals(model.A - L @ model.C), riccati=pis,
        hamiltonian_margins=margins, projectors=dict(prob.projectors), cost=J, initial_gain=L0, initial_cost=J0,
        success=bool(res.success), status=int(res.status), message=str(res.message), nit=int(getattr(res, "nit", 0)),
        problem=prob,
    )
