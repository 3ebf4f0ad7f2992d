"""Reduced-order detection filters from the γ → 0 limit of the game filter (the "Goh filter").

In the limit the game filter's Riccati matrix has the nuisance subspace in its kernel, and the part of
the state space it spans can be cut away: the detector lives on the complement only and is *exactly*
blind to the nuisance (Douglas et al. 1996, §9.5, (9.57)–(9.68), (9.77), Theorem 9.5; Murray 2012,
§4.3, (4.60)–(4.75), Prop. 4.6, Theorem 4.4).

With the orthonormal ``Γ = [Γ₁; Γ₂]`` (``Im Γ₂ᵀ = ∩ᵢ Ker Sᵢ``, the common kernel of the Goh Riccati
solutions, :func:`fdikit.design.game.goh.goh_riccati`) and ``ΓAΓᵀ = [[A₁₁, A₁₂], [A₂₁, A₂₂]]``,
``CΓᵀ = [C₁, C₂]``, ``ΓB = [B₁; B₂]``, ``S̄ᵢ = Γ₁ Sᵢ Γ₁ᵀ``, the filter on ``η₁ = Γ₁ x`` is (Murray
(4.75) with the sign of the gain term corrected — the printed (4.73)/(4.75) have ``− L y`` and
``− L₁*(y − C₁x̂₁)``, inconsistent with the observer (3.7a))::

    η̂₁' = A₁₁ η̂₁ + B₁ u + L₁ (y − C₁ η̂₁ − D u)
    L₁ = (Σᵢ S̄ᵢ)⁻¹ Σᵢ [ S̄ᵢ Γ₁ B̂ᵢ Ξᵢ B̃ᵢᵀ Cᵀ V⁻¹ + C₁ᵀ H̄ᵢᵀ V⁻¹ H̄ᵢ ]            (4.68)

(``B̂ᵢ, B̃ᵢ, Ξᵢ`` from Algorithm 4.1 on ``F̂ᵢ``, ``H̄ᵢ`` the oblique projector (4.31)).  For one target
whose ``C F̂`` has full column rank this is PATH's (9.63): ``L₁ = S̄⁻¹ C₁ᵀ V̄⁻¹ (I − C₂K) + A₁₂ K`` with
``K = (C₂ᵀ V̄⁻¹ C₂)⁻¹ C₂ᵀ V̄⁻¹`` (9.62), and the closed loop is
``A₁₁ − A₁₂KC₁ − S̄⁻¹C₁ᵀV̄⁻¹(I − C₂K)C₁`` (Theorem 9.5).  ``A₁₂ = L₁ C₂`` (4.70) holds exactly, so the
estimation error ``e₁ = η₁ − η̂₁`` obeys ``e₁' = (A₁₁ − L₁C₁) e₁ − L₁ v`` (9.68): no nuisance term.

**Residual.**  Douglas et al. 1996, §9.5 gives the reduced-order filter ((9.62)–(9.68)) but no formula for its
residual (Figs. 9.6–9.7 plot one).  Here the
residual of target ``i`` is the projected output error ``Ĥᵢ (y − C₁η̂₁ − D u)``, in the coordinates of
an orthonormal basis of ``Im Ĥᵢ`` (named ``"<target>[k]"``, as the full-order game filters).  Since
``y − C₁η̂₁ = C₁e₁ + C₂η₂ + v`` and ``Ĥᵢ C₂ = 0``, it is blind to the nuisance; for one target and a
scalar ``V`` it equals PATH's natural choice ``(I − C₂K)(y − C₁η̂₁)`` (``I − C₂K = H̄ = Ĥ`` then).

The targets' ``Ĥᵢ`` also annihilate the other targets (``F̂ᵢ`` holds them), so with several targets each
residual isolates its own fault when (4.85) ``S̄ⱼ (Σ S̄)⁻¹ S̄ₖ = δⱼₖ S̄ⱼ`` holds — i.e. when there is no
complementary subspace (Murray Theorems 4.4–4.5); :attr:`GohFilterDesign.separation` reports its defect.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import reduce

import numpy as np
import scipy.linalg

from fdikit import linalg
from fdikit.design.game.goh import GohRiccatiSolution, goh_riccati
from fdikit.design.game.setup import GameProblem, game_problem, per_target
from fdikit.design.labels import label_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import ProblemDesign
from fdikit.residuals import ResidualGenerator

__all__ = ["GohFilterDesign", "goh_filter", "goh_detector"]


@dataclass(frozen=True, eq=False)
class GohFilterDesign(ProblemDesign):
    """A reduced-order asymptotic (γ → 0) game filter and its design report.

    Attributes
    ----------
    generator : residual generator of order :attr:`order`; residuals ``"<target>[k]"`` (coordinates of
        ``Ĥᵢ (y − C₁η̂₁ − D u)``), each tied to its target.
    gain : ``L₁`` (n₁ x p), (4.68) / (9.63).
    poles : eigenvalues of ``A₁₁ − L₁ C₁``.
    transformation : orthonormal ``Γ`` (n x n); rows ``Γ₁`` (first :attr:`order`) give the filter
        state ``η₁ = Γ₁ x``, rows ``Γ₂`` span the removed common kernel.
    order : ``n₁``.
    riccati : the Goh Riccati solution of each target (:class:`~fdikit.design.game.goh.GohRiccatiSolution`).
    reduced_riccati : ``S̄ᵢ = Γ₁ Sᵢ Γ₁ᵀ`` by target.
    projectors : ``Ĥᵢ`` by target.
    static_gain : PATH's ``K`` (9.62) giving ``η̂₂ = K (y − C₁η̂₁)`` (9.61) when ``C₂`` has full column
        rank, else None.
    separation : defect of (4.85), ``max ‖S̄ⱼ(ΣS̄)⁻¹S̄ₖ − δⱼₖS̄ⱼ‖ / ‖S̄ⱼ‖`` (0 for one target).
    structure_residual : ``‖A₁₂ − L₁C₂‖ / ‖A‖`` ((4.70); round-off when the design is consistent).
    problem : the target/nuisance partition.

    Made by :func:`goh_filter` / :func:`goh_detector`; ``targets`` gives the target names, ``blocks()`` the
    partitioned transformed plant.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> d = goh_detector(white_speyer("stable-extra-zero"), "f1", ["f2"], V=1.0, Q=0.5)
    >>> d.order, d.targets, d.gain.shape, sorted(d.blocks())
    (2, ('f1',), (2, 2), ['A11', 'A12', 'A21', 'A22', 'C1', 'C2'])

    References
    ----------
    Murray 2012, §4.3.2, (4.60)–(4.75); Douglas et al. 1996, §9.5, (9.61)–(9.63).
    """

    generator: ResidualGenerator
    gain: np.ndarray
    poles: np.ndarray
    transformation: np.ndarray
    order: int
    riccati: dict[str, GohRiccatiSolution]
    reduced_riccati: dict[str, np.ndarray]
    projectors: dict[str, np.ndarray]
    static_gain: np.ndarray | None
    separation: float
    structure_residual: float
    problem: GameProblem

    @property
    def targets(self) -> tuple[str, ...]:
        return self.problem.names

    def blocks(self) -> dict[str, np.ndarray]:
        """``A₁₁, A₁₂, A₂₁, A₂₂, C₁, C₂`` of the transformed plant ``ΓAΓᵀ``, ``CΓᵀ``."""
        m, G, k = self.problem.model, self.transformation, self.order
        At, Ct = G @ m.A @ G.T, m.C @ G.T
        return {"A11": At[:k, :k], "A12": At[:k, k:], "A21": At[k:, :k], "A22": At[k:, k:],
                "C1": Ct[:, :k], "C2": Ct[:, k:]}


    def report(self) -> dict:
        """``gain`` (``L₁``), ``poles`` (of ``A₁₁ − L₁C₁``), ``order`` (``n₁``), ``transformation`` (``Γ``),
        ``reduced_riccati`` (``S̄ᵢ``) and ``projectors`` (``Ĥᵢ``) by target, ``static_gain``, ``separation``
        (defect of (4.85)) and ``structure_residual`` (of (4.70))."""
        return {"gain": self.gain, "poles": self.poles, "order": self.order, "transformation": self.transformation,
                "reduced_riccati": self.reduced_riccati, "projectors": self.projectors,
                "static_gain": self.static_gain, "separation": self.separation,
                "structure_residual": self.structure_residual}


def goh_filter(
    model: FaultModel,
    targets: Sequence[str] | Mapping[str, np.ndarray],
    nuisance: Sequence[str] | Mapping[str, np.ndarray] = (),
    *,
    V=1.0,
    Q=1e-4,
    rtol: float | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> GohFilterDesign:
    """Reduced-order asymptotic game filter for one or several targets (Murray 2012, (4.60)–(4.75)).

    For each target ``i`` the Goh Riccati equation with ``F̂ᵢ`` (the other targets and the nuisance)
    is solved (:func:`fdikit.design.game.goh.goh_riccati`); the common kernel ``∩ Ker Sᵢ`` is cut away and
    the gain is (4.68).  One target gives PATH's reduced-order detector (9.63) (:func:`goh_detector`).

    Parameters
    ----------
    model : continuous FaultModel.
    targets : fault names (resolved by :func:`fdikit.fault_maps.resolve_faults`: ``'<output>_sensor'``,
        ``'<control>_actuator'``, fault inputs of the model) or a mapping name → F.
    nuisance : faults blocked from every residual (names or mapping; ``()`` none, ``'others'`` every
        fault input of the model that is not a target).
    V : ``V = V̄/γ`` held fixed as γ → 0 (PATH's ``V̄``; p x p positive definite or scalar).
    Q : weight on ``Ĥᵢ C e`` (scalar, p x p, or a mapping target → weight).  ``Q < 1/V`` keeps the
        Goh Riccati equation of standard (LQ) type.
    rtol : rank tolerance of the subspace computations.
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[k]`` tied to each target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    GohFilterDesign
        The reduced-order generator (order ``n₁``), its gain ``L₁`` and the design report.

    Raises
    ------
    DesignError
        For a discrete model, a target hidden by its complementary faults, a Goh Riccati equation
        without a positive definite reduced solution, a singular ``Σ S̄ᵢ`` (Prop. 4.6 fails), an
        unstable result, or nothing left to detect (the kernel is the whole space).

    Examples
    --------
    F-16XL (Murray 2012, §6.1.2): three targets, no nuisance, four states — no complementary subspace.

    >>> from fdikit.fault_maps import resolve_faults
    >>> from fdikit.plants.f16xl import f16xl_longitudinal
    >>> m = f16xl_longitudinal()
    >>> faults = resolve_faults(m, ["y_theta_sensor", "elevon_actuator"]) | {"gust": m.Bd}
    >>> d = goh_filter(m, faults, V=1.0, Q=0.5)
    >>> d.order, d.separation < 1e-9
    (4, True)

    References
    ----------
    Murray 2012, §4.2.4, Theorem 4.4, and §4.3, (4.60)–(4.75), Prop. 4.6; Douglas et al. 1996, §9.5, (9.63).
    """
    if model.is_discrete:
        raise DesignError(
            f"the Goh filter is continuous-time but the model is discrete (dt={model.dt}); design on the continuous "
            "model and discretise the generator"
        )
    prob = game_problem(model, targets, nuisance, rtol)
    tnames = prob.names
    given = [targets] if isinstance(targets, str) else list(targets)
    Qs = per_target("Q", Q, tnames, [str(g) for g in given])
    A, C, n, p = model.A, model.C, model.n, model.p
    sols = {t: goh_riccati(A, C, prob.complementary[t], V=V, Q=Qs[t], projector=prob.projectors[t], rtol=rtol)
            for t in tnames}
    kernel = reduce(lambda U, W: linalg.intersect(U, W, rtol), [s.kernel for s in sols.values()])
    if len(tnames) == 1:
        Gam, n1 = sols[tnames[0]].transformation, sols[tnames[0]].order
    else:
        comp = linalg.null(kernel.T, rtol) if kernel.shape[1] else np.eye(n)
        Gam, n1 = np.vstack([comp.T, kernel.T]), comp.shape[1]
    if n1 == 0:
        raise DesignError("the common kernel of the Goh Riccati solutions is the whole state space; nothing to detect")
    G1 = Gam[:n1]
    At, Ct = Gam @ A @ Gam.T, C @ Gam.T
    A11, A12, C1, C2 = At[:n1, :n1], At[:n1, n1:], Ct[:, :n1], Ct[:, n1:]
    Vw = sols[tnames[0]].V
    Vi = np.linalg.inv(Vw)
    Sbar, lhs, rhs = {}, np.zeros((n1, n1)), np.zeros((n1, p))
    for t in tnames:
        s = sols[t]
        Sb = G1 @ s.S @ G1.T
        Sbar[t] = (Sb + Sb.T) / 2
        Bt, Bh, Hb = s.goh.B_tilde, s.goh.B_hat, s.oblique_projector
        term = C1.T @ Hb.T @ Vi @ Hb
        if Bt.shape[1]:
            CB = C @ Bt
            term = term + Sbar[t] @ G1 @ Bh @ np.linalg.solve(CB.T @ Vi @ CB, CB.T @ Vi)
        lhs, rhs = lhs + Sbar[t], rhs + term
    ev = np.linalg.eigvalsh(lhs)
    if ev.min() <= 1e-10 * ev.max():
        raise DesignError(
            f"Σ S̄ᵢ is singular (eigenvalues {np.round(ev, 12).tolist()}; Murray Prop. 4.6 fails): the reduced "
            "filter gain (4.68) is not defined; check that the targets are output separable"
        )
    L1 = np.linalg.solve(lhs, rhs)
    Acl = A11 - L1 @ C1
    poles = scipy.linalg.eigvals(Acl)
    if np.any(poles.real >= 0):
        raise DesignError(f"the reduced-order Goh filter is not stable: poles {np.round(poles, 6).tolist()}")
    sep = 0.0
    if len(tnames) > 1:
        inv = np.linalg.inv(lhs)
        for j in tnames:
            for k in tnames:
                target = Sbar[j] if j == k else 0 * Sbar[j]
                sep = max(sep, np.linalg.norm(Sbar[j] @ inv @ Sbar[k] - target) / np.linalg.norm(Sbar[j]))
    struct = float(np.linalg.norm(A12 - L1 @ C2) / max(np.linalg.norm(A), 1e-300)) if n1 < n else 0.0
    K = None
    if C2.shape[1] and linalg.rank(C2, rtol) == C2.shape[1]:
        K = np.linalg.solve(C2.T @ Vi @ C2, C2.T @ Vi)
    B1, Du = G1 @ model.Bu, model.Du
    rows_C, rows_D, res_names, iso = [], [], [], []
    for t in tnames:
        U = linalg.orth(prob.projectors[t])
        rows_C.append(-U.T @ C1)
        rows_D.append(np.hstack([-U.T @ Du, U.T]))
        res_names += [f"{t}[{k}]" for k in range(U.shape[1])]
        iso += [t] * U.shape[1]
    gen = ResidualGenerator(
        A=Acl, B=np.hstack([B1 - L1 @ Du, L1]), C=np.vstack(rows_C), D=np.vstack(rows_D),
        controls=model.controls, outputs=model.outputs, residuals=tuple(res_names), dt=None, isolates=tuple(iso),
    )
    gen = label_generator(gen, model, names, isolates)
    return GohFilterDesign(gen, L1, poles, Gam, n1, sols, Sbar, dict(prob.projectors), K, float(sep), struct, prob)


def goh_detector(
    model: FaultModel,
    targets: str | Sequence[str] | Mapping[str, np.ndarray],
    nuisance: Sequence[str] | Mapping[str, np.ndarray] | str = (),
    *,
    V=1.0,
    Q=1e-4,
    rtol: float | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> GohFilterDesign:
    """PATH's reduced-order detector for one target fault (Douglas et al. 1996, §9.5, (9.61)–(9.68), (9.77)).

    The order is ``n − dim Ker S``: ``n − dim Ŵ*`` minus the number of closed-right-half-plane
    invariant zeros of ``(C, A, F̂)`` (Theorem 9.4).  A stable invariant zero stays as a filter pole.

    Parameters
    ----------
    model : continuous FaultModel.
    targets : the one fault to detect (a fault name, a one-element sequence, or ``{name: F}``).
    nuisance : the faults to block exactly (names or mapping; ``'others'`` every other fault input of
        the model); ``F̂`` is their side-by-side map.
    V : PATH's ``V̄`` (``ν/γ``; 0.8 in §9.6), p x p or scalar.
    Q : PATH's ``Q₁`` (1 in §9.6).
    rtol : rank tolerance.
    names, isolates : optional
        Residual names and the fault each residual isolates (as :func:`goh_filter`), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    GohFilterDesign
        The reduced-order detector; ``static_gain`` is PATH's ``K`` (9.62) when ``C₂`` has full column rank.

    Raises
    ------
    ParameterError
        More than one target (use :func:`goh_filter`).
    DesignError
        As :func:`goh_filter`.

    Examples
    --------
    The air-mass sensor filter of PATH §9.6 (engine-speed and accelerometer faults as nuisance):

    >>> from fdikit.plants.path_longitudinal import path_longitudinal_7, path_longitudinal_7_fault_maps
    >>> m = path_longitudinal_7()
    >>> d = goh_detector(m, "air_mass_sensor", path_longitudinal_7_fault_maps(), V=0.8, Q=1.0)
    >>> d.order, d.generator.residuals
    (3, ('air_mass_sensor[0]', 'air_mass_sensor[1]', 'air_mass_sensor[2]'))

    References
    ----------
    Douglas et al. 1996, §9.4, Theorem 9.4; §9.5, (9.61)–(9.68), (9.77), Theorem 9.5; §9.6.2.
    """
    prob_targets = targets if not isinstance(targets, str) else [targets]
    if len(prob_targets) != 1:
        raise ParameterError(f"goh_detector detects one target fault, got {list(prob_targets)}; use goh_filter")
    return goh_filter(model, prob_targets, nuisance, V=V, Q=Q, rtol=rtol, names=names, isolates=isolates)
