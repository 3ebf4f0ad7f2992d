"""Continuous steady-state single-fault game-theoretic detection filter (GTFDF) and the bank of them.

Murray 2012, §3.3 and §6.1.1; Douglas et al. 1996, Ch. 9.  One observer per target fault

    x̂' = A x̂ + Bu u + L (y − C x̂ − Du u),    r = y − C x̂ − Du u,    r̄ = Ĥ r

blocks the complementary faults ``F̂`` (nuisance, or the other faults of a bank) by the attenuation bound γ.

* :func:`single_fault_game_filter` — the single-fault GTFDF (3.29)–(3.30) in covariance form:
  ``0 = A P + P Aᵀ + F̂ M F̂ᵀ/γ − P Cᵀ (V⁻¹ − Ĥ Q Ĥ) C P``, ``L = P Cᵀ V⁻¹`` (no optimisation);
* :func:`game_filter_bank` — one single-fault filter per fault (Murray's "UIO" bank, §6.1.1).

A discrete model (``model.dt`` set) runs the discrete single-fault filter of Murray 2012, Ch. 5
(:func:`~fdikit.design.game.discrete.dgtfdf`).  The multiple-fault filter is
:func:`fdikit.design.game.multi_fault.game_filter`.  Residuals are named ``"<target>[k]"``: the coordinates of
``Ĥ r`` in an orthonormal basis of ``Im Ĥ`` (fdikit's sign convention ``r = y − ŷ``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import linalg
from fdikit.design.game.discrete import DiscreteGtfdfDesign, dgtfdf
from fdikit.design.game.discrete_setup import DiscreteGameSetup, discrete_game_setup
from fdikit.design.game.riccati import checked_gamma, require_continuous, solve_game_are
from fdikit.design.game.setup import GameProblem, game_problem, per_target, weight
from fdikit.design.labels import label_generator
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.fault_maps import resolve_nuisance
from fdikit.model import FaultModel
from fdikit.protocols import ProblemDesign, joined_form
from fdikit.residuals import ResidualGenerator, stack_generators

__all__ = [
    "GameBankDesign",
    "SingleFaultGameDesign",
    "game_filter_bank",
    "single_fault_game_filter",
]


# ---------------------------------------------------------------------------- helpers (shared with multi_fault)
def _inv_pd(name: str, W: np.ndarray) -> np.ndarray:
    if W.size and np.linalg.eigvalsh(W).min() <= 1e-14 * max(1.0, np.abs(W).max()):
        raise ParameterError(f"weight {name} must be positive definite (it is inverted)")
    return np.linalg.inv(W)


def residual_basis(H: np.ndarray) -> np.ndarray:
    """Orthonormal basis of ``Im Ĥ`` (p x rank Ĥ): the coordinates of the projected residual."""
    return linalg.orth(H)


def residual_names(target: str, k: int) -> list[str]:
    """Names ``"<target>[0]"`` … ``"<target>[k-1]"`` of the projected residual's coordinates."""
    return [f"{target}[{j}]" for j in range(k)]


def given_names(spec) -> list[str]:
    """The target names as the user gave them (one name, or the keys / items of ``targets``)."""
    return [str(k) for k in spec] if not isinstance(spec, str) else [spec]


def discrete_setup(model, targets, nuisance, *, gamma, V, Q, M, K=0.0, N=0.0, P0=None, steps=None
                   ) -> DiscreteGameSetup:
    """The Murray Ch. 5 setup for a discrete model with the continuous entry points' weights.

    ``V`` keeps its meaning (Murray's ``V = V̄/γ``, so ``Vbar = γ V``); ``Q``, ``M``, ``K``, ``N`` are passed
    as they are (per-sample weights); ``P0`` defaults to ``γ`` (``P(k0) = P0/γ = I``) and ``steps`` to 500.
    """
    g = checked_gamma(gamma)
    return discrete_game_setup(model, targets, nuisance, gamma=g, Vbar=weight("V", V, model.p) * g, Q=Q, M=M,
                               K=K, N=N, P0=g if P0 is None else P0, steps=500 if steps is None else steps)


def continuous_only(model: FaultModel, **given) -> None:
    """Refuse the discrete design's horizon arguments on a continuous model."""
    bad = [k for k, v in given.items() if v is not None]
    if bad:
        raise ParameterError(f"{', '.join(bad)} set the finite horizon of the discrete design (a model with dt); "
                             "the continuous design is steady-state — leave them unset")


# ---------------------------------------------------------------------------- single fault
@dataclass(frozen=True, eq=False)
class SingleFaultGameDesign(ProblemDesign):
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

    Made by :func:`single_fault_game_filter` for a continuous model; ``report()`` gives the same numbers as a dict.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> d = single_fault_game_filter(white_speyer("stable-extra-zero"), "f1", ["f2"], Q=1e-3, M=0.05)
    >>> d.target, d.solver, d.gain.shape, d.generator.residuals
    ('f1', 'care', (3, 2), ('f1[0]',))

    References
    ----------
    Murray 2012, §3.3, (3.29)–(3.30).
    """

    generator: ResidualGenerator
    gain: np.ndarray
    poles: np.ndarray
    covariance: np.ndarray
    projector: np.ndarray
    target: str
    problem: GameProblem
    solver: str


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
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
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
    targets : the one fault to detect — a fault name resolved by :func:`fdikit.fault_maps.resolve_faults`
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
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[k]`` tied to the target), as
        :func:`~fdikit.design.labels.residual_labels`.

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

    References
    ----------
    Murray 2012, §3.3, (3.29)–(3.32), Remark 6.8; Douglas et al. 1996, §9.2, (9.4), (9.15)–(9.17), (9.26);
    discrete: Murray 2012, §5.3, (5.42)–(5.43).
    """
    if model.is_discrete:
        if np.any(weight("R", R, model.p)):
            raise ParameterError("R (PATH's weight R_1) has no counterpart in the discrete design of Murray 2012 "
                                 "Ch. 5; leave R = 0 for a discrete model")
        setup = discrete_setup(model, targets, nuisance, gamma=gamma, V=V, Q=Q, M=M, P0=P0, steps=steps)
        if len(setup.names) != 1:
            raise DesignError(f"single_fault_game_filter takes one target, got {list(setup.names)}; use game_filter")
        return dgtfdf(setup, names=names, isolates=isolates)
    continuous_only(model, P0=P0, steps=steps)
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

    def hamiltonian() -> np.ndarray:
        """The Hamiltonian-Schur solution, axis test at 1000·eps of the scaled norm, residual-checked (≤ 1e-8)."""
        return solve_game_are(A.T, -C.T @ S @ C, W, axis_tol=1e3 * np.finfo(float).eps,
                              what=f"the single-fault game Riccati equation for {name!r}").X

    if np.linalg.eigvalsh(S).min() > 1e-12 * np.abs(S).max():
        solver = "care"
        try:
            P = scipy.linalg.solve_continuous_are(A.T, C.T, W, np.linalg.inv(S))
        except (np.linalg.LinAlgError, ValueError) as exc:
            # scipy's symmetry test of the stable subspace can refuse a badly scaled equation under one BLAS
            # kernel and accept it under another (the PATH game bank on the car: V ~ 1e-12, ‖H‖ ≈ 8e10, the
            # spectrum 1.8 from the imaginary axis — 2e-11 of ‖H‖, yet 1e5 times the eps·‖H‖ a backward-stable
            # eigensolver can misplace an eigenvalue by).  Retry with the Hamiltonian-Schur solver, its axis test
            # at 1000·eps of the scaled norm and its own residual check (≤ 1e-8) guarding the result.
            solver = "hamiltonian"
            try:
                P = hamiltonian()
            except DesignError:
                raise DesignError(
                    f"the single-fault game Riccati equation for {name!r} has no stabilizing solution ({exc}); "
                    "check that (C, A) is detectable"
                ) from exc
    else:
        solver = "hamiltonian"
        P = solve_game_are(A.T, -C.T @ S @ C, W, what=f"the single-fault game Riccati equation for {name!r}").X
    P = (P + P.T) / 2
    ev = np.linalg.eigvalsh(P)
    if solver == "care" and ev.min() < -1e-8 * max(ev.max(), 1e-300):
        # SciPy's Schur solver can return an inaccurate, indefinite solution of this badly scaled equation under
        # one BLAS kernel (the PATH car's filter 4 under Haswell/Zen: min eigenvalue −0.05, positive under
        # Prescott/SkylakeX); the Hamiltonian-Schur solver with its residual check decides instead
        try:
            P = hamiltonian()
            solver = "hamiltonian"
        except DesignError:
            pass
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
    basis = residual_basis(H)
    gen = label_generator(observer_generator(model, L, residual_names(name, basis.shape[1]), basis), model, names,
                          isolates, default_isolates=[name] * basis.shape[1])
    return SingleFaultGameDesign(gen, L, poles, P, H, name, prob, solver)


@dataclass(frozen=True, eq=False)
class GameBankDesign:
    """A bank of single-fault game filters (Murray 2012, §6.1.1, the "UIO" bank).

    Attributes
    ----------
    generator : the stacked generator (one block of residuals ``"<fault>[k]"`` per filter).
    filters : the single-fault designs by fault name.

    The properties ``gains`` and ``poles`` give each filter's ``L`` (n x p) and eigenvalues of ``A − L C`` by fault
    name.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> bank = game_filter_bank(white_speyer("stable-extra-zero"), ["f1", "f2"], Q=1e-3, M=0.05)
    >>> list(bank.filters), bank.gains["f1"].shape
    (['f1', 'f2'], (3, 2))

    References
    ----------
    Murray 2012, §6.1.1.
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
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> GameBankDesign:
    """One single-fault game filter per fault, each blocking all the others (Murray 2012, §6.1.1).

    Filter ``i`` has target ``F_i`` (``targets``: fault names or a mapping name → F) and
    ``F̂_i = [F_j]_{j≠i}`` plus the ``nuisance`` faults (blocked by every filter; ``()`` none,
    ``'others'`` every fault input of the model that is not a target).  ``Q`` and ``M`` may be one
    value or a mapping fault → value (``M`` is sized to each ``F̂_i``).  A bank does not need mutual
    detectability (Murray 2012, Remark 2.4): each filter forms only one detection space.

    Parameters
    ----------
    model : FaultModel
        The plant, continuous.
    targets : sequence of str or mapping name → (n, k) array
        The faults, one filter each (fault names resolved by :func:`fdikit.fault_maps.resolve_faults`).
    nuisance : sequence of str, mapping or ``'others'``
        Faults every filter blocks besides the other targets: ``()`` (default) none.
    gamma : float
        Attenuation bound γ > 0 of every filter (default 1e-6).
    V : float or (p, p) array
        Murray's ``V = V̄/γ`` (default 1).
    Q, M : float, array or mapping fault → value
        Output weight (p x p) and complementary-fault weight (sized to each ``F̂_i``) of each filter (defaults 1e-4
        and 0.01; scalars mean multiples of I).
    names, isolates : optional
        Names and isolated faults of the stacked residuals of the bank (default ``<target>[k]`` of each filter,
        tied to its target), as :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    GameBankDesign
        The stacked generator and the single-fault designs by fault name.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> bank = game_filter_bank(white_speyer("stable-extra-zero"), ["f1", "f2"], Q=1e-3, M=0.05)
    >>> bank.generator.residuals
    ('f1[0]', 'f2[0]')

    References
    ----------
    Murray 2012, §6.1.1, Remark 2.4; the filters: §3.3, (3.29)–(3.30).
    """
    require_continuous(model)
    prob = game_problem(model, targets, ())
    given = given_names(targets)
    Qs, Ms = per_target("Q", Q, prob, given), per_target("M", M, prob, given)
    extra = resolve_nuisance(model, nuisance, list(prob.names))
    designs = {}
    for name in prob.names:
        others = {k: F for k, F in prob.targets.items() if k != name} | extra
        designs[name] = single_fault_game_filter(
            model, {name: prob.targets[name]}, others, gamma=gamma, V=V, Q=Qs[name], M=Ms[name]
        )
    return GameBankDesign(label_generator(stack_generators([d.generator for d in designs.values()]), model, names,
                                          isolates), designs)
