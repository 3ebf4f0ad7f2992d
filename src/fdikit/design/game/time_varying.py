"""Finite-horizon, time-varying game-theoretic detection filters (Murray 2012, Ch. 3).

Plant (Murray 2012, (3.1); Douglas et al. 1996, (9.1)), on a finite horizon ``[t0, t1]``::

    x' = A(t) x + B(t) u + Σ_i F_i(t) μ_i,      y = C(t) x + D(t) u + v

given as an :class:`~fdikit.ltv.LTVModel`; the projectors ``Ĥ_i(t)`` (Murray (3.10)) come
from :func:`~fdikit.ltv.ltv_projector`.

**Single-fault GTFDF** (Murray (3.29)–(3.30) in covariance form ``P = Γ⁻¹``; Douglas et
al. 1996, (9.17) with ``P = γΠ⁻¹``), integrated forward with :func:`scipy.integrate.solve_ivp`::

    Ṗ = A P + P Aᵀ + F̂ M F̂ᵀ/γ − P Cᵀ (V⁻¹ − Ĥ Q Ĥ) C P,     P(t0) = P0/γ,     L = P Cᵀ V⁻¹

**Feasibility of a given gain** ``L(t)`` shared by several targets (Problem 3.1): integrate
(3.32) per target, ``Ṗ_i = (A−LC)P_i + P_i(A−LC)ᵀ + F̂_iM_iF̂_iᵀ/γ + LVLᵀ + P_iCᵀĤ_iQ_iĤ_iCP_i``;
``Ψ_i ≤ 0`` (3.16)–(3.18) is met iff ``P_i`` stays finite and positive definite on ``[t0, t1]``.

Erratum applied: the initial condition is ``P_i(t0) = P0/γ``; the dissertation prints
``P_i(t0) = γ P0`` under (3.32) (§3.3), which contradicts ``Π0 ≜ γ P0⁻¹`` defined with (3.12)
(``P_i = Π_i⁻¹`` gives ``P_i(t0) = P0/γ``).
Weights follow Murray: ``γ`` is the attenuation bound (small γ = strong blocking), ``M`` the
complementary-fault weight, ``Q`` the projected-output weight, ``V = V̄/γ`` the noise weight
and ``P0`` the initial-error weight of the DAP (3.11).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from fdikit import validate
from fdikit.design.game.ltv_filter import LTVDetectionFilter, complements, ltv_labels
from fdikit.design.game.setup import weight
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.ltv import LTVModel, MatrixFunction, invariant_generators, ltv_projector
from fdikit.protocols import no_internal_form

__all__ = [
    "LTVGameDesign",
    "LTVFeasibility",
    "ltv_game_filter",
    "ltv_feasibility",
]


def _check_visible(model: LTVModel, target: str, H: np.ndarray, t: float, rtol: float) -> None:
    C = model.matrix("C", t)
    _, E = invariant_generators(model, target, t, rtol)
    if np.linalg.norm(H @ C @ E) <= 1e-9 * max(np.linalg.norm(C @ E), 1e-300):
        raise DesignError(f"target {target!r} is not output separable from its complementary faults at t = {t:g}: "
                          "Ĥ C W* = 0 (Murray Assumption 3.2); drop a nuisance fault or add a sensor")


#: Methods of :func:`scipy.integrate.solve_ivp`.
_IVP_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


def _grid(t) -> np.ndarray:
    t = validate.as_array("the time grid t", t, finite=False).ravel()
    if t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ParameterError("the time grid t must be finite, strictly increasing, with t0 and t1 (≥ 2 points)")
    return t


def _stack(model: LTVModel, names: Sequence[str], t: float, n: int) -> np.ndarray:
    return np.hstack([model.matrix(k, t) for k in names]) if names else np.zeros((n, 0))


def _sym(P: np.ndarray) -> np.ndarray:
    return (P + P.T) / 2


def _riccati(model: LTVModel, target: str, comp: tuple[str, ...], t: np.ndarray, gain: MatrixFunction | None, *,
             gamma, M, Q, V, P0, rtol, atol, method, escape, geometry_rtol):
    """Integrate ``Ṗ = K0 P + P K0ᵀ + R − P S P`` from ``P0/γ``; returns (solution, escape time, n, V⁻¹).

    ``gain=None``: single-fault GTFDF (3.29), ``K0 = A``, ``R = F̂MF̂ᵀ/γ``, ``S = Cᵀ(V⁻¹ − ĤQĤ)C``.
    Given ``L(t)``: (3.32), ``K0 = A − LC``, ``R = F̂MF̂ᵀ/γ + LVLᵀ``, ``S = −CᵀĤQĤC``.
    The exact Jacobian is ``I⊗K + K⊗I`` with ``K = K0 − P S``.
    """
    gamma = validate.number("gamma", gamma, finite=False)
    if not (math.isfinite(gamma) and gamma > 0):
        raise ParameterError(f"gamma must be a positive attenuation bound (small = strong blocking), got {gamma!r}")
    A0, C0 = model.matrix("A", t[0]), model.matrix("C", t[0])
    p, n = C0.shape
    if A0.shape != (n, n):
        raise ModelError(f"A(t0) is {A0.shape} and C(t0) is {C0.shape}; need n x n and p x n")
    Mw = weight("M", M[target] if isinstance(M, Mapping) else M, _stack(model, comp, t[0], n).shape[1])
    Qw = weight("Q", Q[target] if isinstance(Q, Mapping) else Q, p)
    Vw, Pw = weight("V", V, p), weight("P0", P0, n)
    for name, W in (("V", Vw), ("P0", Pw)):
        if np.linalg.eigvalsh(W).min() <= 0:
            raise ParameterError(f"weight {name} must be positive definite")
    Vinv = np.linalg.inv(Vw)

    @functools.lru_cache(maxsize=8)
    def coeffs(s: float):
        A, C, Fh = model.matrix("A", s), model.matrix("C", s), _stack(model, comp, s, n)
        H = ltv_projector(model, comp, s, geometry_rtol)
        if gain is None:
            return A, Fh @ Mw @ Fh.T / gamma, C.T @ (Vinv - H @ Qw @ H) @ C
        L = np.asarray(gain(s), dtype=float)
        return A - L @ C, Fh @ Mw @ Fh.T / gamma + L @ Vw @ L.T, -C.T @ H @ Qw @ H @ C

    def rhs(s, P):
        K0, R, S = coeffs(s)
        P = _sym(P)
        return K0 @ P + P @ K0.T + R - P @ S @ P

    def jac(s, P):
        K0, _, S = coeffs(s)
        K, eye = K0 - _sym(P) @ S, np.eye(n)
        return np.kron(K, eye) + np.kron(eye, K)

    scale = max(1.0, np.abs(Pw).max() / gamma, np.abs(coeffs(float(t[0]))[1]).max() * (t[-1] - t[0]))
    sol, t_escape = _integrate(rhs, jac, Pw / gamma, t, scale, escape, rtol, atol, method)
    return sol, t_escape, n, Vinv


def _integrate(rhs, jac, P_start: np.ndarray, t: np.ndarray, scale: float, escape: float, rtol: float,
               atol: float | None, method: str):
    """Forward Riccati integration with a finite-escape event; returns (solution, escape time or None).

    Escape is declared when ``max |P_ij|`` exceeds ``escape · scale`` (or the solver stalls:
    then the last time it reached, or ``P`` turns indefinite on the grid).  Near an escape
    ``P ≈ K/(t_e − t)``, so the time is extrapolated as ``t* + m/ṁ`` (``m`` the largest entry
    at the event time ``t*``).
    """
    n = P_start.shape[0]
    bound = escape * scale

    def event(s, p):
        return bound - np.abs(p).max()

    event.terminal = True
    atol = atol if atol is not None else 1e-12 * max(1.0, np.abs(P_start).max())
    kw = dict(method=method, t_eval=t, events=event, rtol=rtol, atol=atol,
              jac=(lambda s, p: jac(s, p.reshape(n, n))) if method in ("Radau", "BDF", "LSODA") else None)
    f = lambda s, p: rhs(s, p.reshape(n, n)).ravel()  # noqa: E731
    try:
        sol = solve_ivp(f, (t[0], t[-1]), P_start.ravel(), dense_output=True, **kw)
    except ValueError:  # an escape within the first step leaves no interpolant to build
        sol = solve_ivp(f, (t[0], t[-1]), P_start.ravel(), **kw)
    if sol.status == 1:
        ts, P = float(sol.t_events[0][0]), sol.y_events[0][0].reshape(n, n)
        i = np.unravel_index(np.argmax(np.abs(P)), P.shape)
        rate = rhs(ts, P)[i] * np.sign(P[i])
        return sol, float(ts + (abs(P[i]) / rate if rate > 0 else 0.0))
    if sol.status == -1:  # the solver stalled: P blows up faster than the event could see
        return sol, float(sol.sol.t_max if sol.sol is not None else sol.t[-1] if sol.t.size else t[0])
    for s_k, P in zip(sol.t, sol.y.T.reshape(-1, n, n)):
        if np.linalg.eigvalsh(_sym(P)).min() < -1e-8 * np.abs(P).max():
            return sol, float(s_k)
    return sol, None


@dataclass(frozen=True, eq=False)
class LTVGameDesign:
    """A finite-horizon single-fault game filter (Murray 2012, (3.29)–(3.30), covariance form).

    Made by :func:`ltv_game_filter`; ``poles(k)`` gives the frozen-time eigenvalues of ``A − L C`` at ``t_k``,
    ``generator`` the filter and ``report()`` the fields as a dict (``internal_form()`` raises: it is time-varying).

    Attributes
    ----------
    filter : LTVDetectionFilter
        The time-varying filter (gain from the dense Riccati solution, projector ``Ĥ(t)``).
    target : str
        The target fault.
    t : (N,) array
        The design grid.
    covariance, gains, projector : (N, n, n), (N, n, p) and (N, p, p) arrays
        ``P(t_k)``, ``L(t_k) = P Cᵀ V⁻¹`` and ``Ĥ(t_k)`` on the grid.
    gamma : float
        The attenuation bound γ.

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer("stable-extra-zero"), ["f1", "f2"])
    >>> d = ltv_game_filter(m, "f1", ["f2"], np.linspace(0, 1, 3), gamma=1e-2, M=0.05, Q=1e-3)
    >>> d.target, d.gains.shape, d.covariance.shape, d.projector.shape
    ('f1', (3, 3, 2), (3, 3, 3), (3, 2, 2))

    References
    ----------
    Murray 2012, §3.3, (3.29)–(3.30).
    """

    filter: LTVDetectionFilter
    target: str
    t: np.ndarray
    covariance: np.ndarray
    gains: np.ndarray
    projector: np.ndarray
    gamma: float

    def poles(self, k: int = -1) -> np.ndarray:
        """Eigenvalues of ``A(t_k) − L(t_k) C(t_k)`` (frozen-time; default the final time)."""
        m = self.filter.model
        return scipy.linalg.eigvals(m.matrix("A", self.t[k]) - self.gains[k] @ m.matrix("C", self.t[k]))

    @property
    def generator(self) -> LTVDetectionFilter:
        """The time-varying filter (:attr:`filter`; run it with ``run`` / ``run_trace``)."""
        return self.filter

    def internal_form(self):
        """Not available: raises :class:`~fdikit.errors.DesignError`.

        The gain ``L(t)`` and projector ``Ĥ(t)`` vary with time, so plant and filter in series are not an
        LTI :class:`~fdikit.model.FaultModel`.
        """
        no_internal_form(self, "the finite-horizon filter is time-varying (gain L(t), projector Ĥ(t)), so plant "
                               "and filter in series are not an LTI FaultModel; run it with generator.run(...)")

    def report(self) -> dict:
        """``target``, ``gamma``, the grid ``t`` and on it ``gains`` (``L(t_k)``), ``covariance`` (``P(t_k)``),
        ``projector`` (``Ĥ(t_k)``), and ``poles`` (frozen-time eigenvalues at the final time)."""
        return {"target": self.target, "gamma": self.gamma, "t": self.t, "gains": self.gains,
                "covariance": self.covariance, "projector": self.projector, "poles": self.poles()}


def ltv_game_filter(model: LTVModel, targets: str | Sequence[str], nuisance: Sequence[str] | str, t, *,
                    gamma: float, M=1.0, Q=1e-3, V=1.0, P0=1.0, rtol: float = 1e-8, atol: float | None = None,
                    method: str = "BDF", escape: float = 1e4, geometry_rtol: float = 1e-6,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> LTVGameDesign:
    """Finite-horizon time-varying single-fault game-theoretic detection filter (GTFDF).

    Integrates ``Ṗ = A P + P Aᵀ + F̂MF̂ᵀ/γ − P Cᵀ(V⁻¹ − ĤQĤ)C P`` forward from
    ``P(t0) = P0/γ`` (Murray 2012, (3.29) with ``P = Γ⁻¹``; the ``γ P0`` printed under (3.32)
    is corrected) and sets ``L = P Cᵀ V⁻¹`` (3.30).  ``F̂`` stacks the nuisance directions,
    ``Ĥ(t)`` annihilates ``C Ŵ*(t)`` (3.10).  :func:`scipy.integrate.solve_ivp` (stiff ``BDF``
    with the exact Jacobian) gives ``P`` on the grid ``t`` and a dense solution for the gain.

    Parameters
    ----------
    model : LTVModel
        The plant.
    targets : str or one-element sequence of str
        The one fault of the model to detect.
    nuisance : sequence of str or ``'others'``
        The faults to block: fault names, ``()`` none, or ``'others'`` every other fault of the model.
    t : (N,) array
        Time grid [s], strictly increasing, ``t[0] = t0`` and ``t[-1] = t1``.
    gamma : float
        Attenuation bound γ > 0 of (3.11) (small = strong blocking).
    M, Q, V, P0 : float or array, optional
        Complementary-fault, projected-output, noise (``V = V̄/γ``) and initial-error weights (a scalar is a
        multiple of I; defaults 1, 1e-3, 1, 1); ``M`` and ``Q`` may map target -> weight.
    rtol, atol, method : optional
        :func:`scipy.integrate.solve_ivp` settings (defaults 1e-8, scaled to ``P0/γ``, ``'BDF'``).
    escape : float, optional
        Finite escape is declared when ``max|P_ij|`` exceeds ``escape`` (default 1e4) times
        ``max(1, ‖P0‖/γ, ‖F̂MF̂ᵀ‖(t1 − t0)/γ)``; the time is extrapolated (``P ~ 1/(t_e − t)``).
    geometry_rtol : float, optional
        Relative rank tolerance of the projector and separability checks (default 1e-6).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>:<output>`` tied to the target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    LTVGameDesign
        The filter with the dense gain ``L(t)``, and ``P``, ``L``, ``Ĥ`` on the grid.

    Raises
    ------
    DesignError
        On finite escape (the time is in the message), or a target that is not output separable from the
        nuisance, or a name given both as target and nuisance.
    ParameterError
        More than one target, an unknown fault or a bare signal name, γ not positive, bad weights, a bad grid or
        an unknown integration method.
    ModelError
        ``A(t0)`` and ``C(t0)`` of inconsistent sizes.

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer("stable-extra-zero"), ["f1", "f2"])
    >>> d = ltv_game_filter(m, "f1", ["f2"], np.linspace(0, 4, 5), gamma=1e-6, M=0.05, Q=1e-3)
    >>> np.round(np.sort_complex(d.poles()), 2)
    array([-316.27+0.j  ,   -3.53-1.79j,   -3.53+1.79j])

    (Murray 2012, Remark 6.6, prints −3.5305 ± 1.7895j and −316.27 for the steady state.)

    References
    ----------
    Murray 2012, §3.1.1, (3.10); §3.3, (3.29)–(3.32); Douglas et al. 1996, §9.1, (9.1); §9.2, (9.17).
    """
    validate.choice("integration method", method, _IVP_METHODS)
    given = [targets] if isinstance(targets, str) else list(targets)
    if len(given) != 1:
        raise ParameterError(f"ltv_game_filter detects one target fault, got {given}; check several with "
                             "ltv_feasibility")
    target = str(given[0])
    comp = complements(model, [target], nuisance)[target]
    res, iso = ltv_labels(model, {target: comp}, names, isolates)
    t = _grid(t)
    for s in (t[0], t[len(t) // 2], t[-1]):
        _check_visible(model, target, ltv_projector(model, comp, s, geometry_rtol), s, geometry_rtol)
    sol, t_escape, n, Vinv = _riccati(model, target, comp, t, None, gamma=gamma, M=M, Q=Q, V=V, P0=P0, rtol=rtol,
                                      atol=atol, method=method, escape=escape, geometry_rtol=geometry_rtol)
    if t_escape is not None:
        raise DesignError(
            f"the game Riccati equation of target {target!r} escapes (P unbounded or indefinite) at t = {t_escape:.6g}"
            f" within [{t[0]:g}, {t[-1]:g}]: γ = {gamma:g} is not attainable with these weights; increase gamma, "
            "decrease Q (keep V⁻¹ − ĤQĤ > 0), or shorten the horizon"
        )
    Ps = np.array([_sym(P) for P in sol.y.T.reshape(-1, n, n)])
    gains = np.array([P @ model.matrix("C", s).T @ Vinv for P, s in zip(Ps, t)])
    dense = sol.sol

    def gain(s: float) -> np.ndarray:
        return _sym(dense(s).reshape(n, n)) @ model.matrix("C", s).T @ Vinv

    def gain_batch(ts: np.ndarray) -> np.ndarray:
        P = np.moveaxis(dense(ts).reshape(n, n, -1), -1, 0)
        return np.array([_sym(Pk) @ model.matrix("C", s).T @ Vinv for Pk, s in zip(P, ts)])

    filt = LTVDetectionFilter(model, gain, {target: comp}, geometry_rtol, gain_batch, names=res, isolates=iso)
    Hs = np.array([ltv_projector(model, comp, s, geometry_rtol) for s in t])
    return LTVGameDesign(filt, target, t, Ps, gains, Hs, float(gamma))


@dataclass(frozen=True, eq=False)
class LTVFeasibility:
    """Result of the finite-horizon check ``Ψ_i ≤ 0`` for a given gain (Murray 2012, (3.16)–(3.18), (3.32)).

    Made by :func:`ltv_feasibility`; ``all_feasible`` says whether every target's DAP holds.

    Attributes
    ----------
    t : (N,) array
        The grid.
    feasible : dict of str to bool
        Whether the DAP of each target holds on ``[t0, t1]``.
    escape_time : dict of str to float or None
        The time of finite escape [s] by target (None: none on the horizon).
    covariance : dict of str to (K, n, n) array
        ``P_i(t_k)`` by target, up to the escape (K ≤ N).

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer(), ["f1", "f2"])
    >>> L = np.array([[38.179, 40.535], [13.995, 16.317], [2.0, 5.678]])
    >>> res = ltv_feasibility(m, ["f1", "f2"], [], lambda t: L, [0.0, 0.5], gamma=1.0, M=0.05, Q=0.1, P0=1.0)
    >>> res.all_feasible, res.escape_time
    (True, {'f1': None, 'f2': None})

    References
    ----------
    Murray 2012, §3.1.2, Problem 3.1; §3.2.1, (3.16)–(3.18); §3.3, (3.32).
    """

    t: np.ndarray
    feasible: dict[str, bool]
    escape_time: dict[str, float | None]
    covariance: dict[str, np.ndarray]

    @property
    def all_feasible(self) -> bool:
        """Every target's DAP holds with the shared gain."""
        return all(self.feasible.values())


def ltv_feasibility(model: LTVModel, targets: Sequence[str], nuisance: Sequence[str], gain: MatrixFunction, t, *,
                    gamma: float, M=1.0, Q=1e-3, V=1.0, P0=1.0, rtol: float = 1e-8, atol: float | None = None,
                    method: str = "BDF", escape: float = 1e4, geometry_rtol: float = 1e-6) -> LTVFeasibility:
    """Check whether a gain schedule ``L(t)`` shared by several targets satisfies every DAP on ``[t0, t1]``.

    For each target integrates (3.32) from ``P_i(t0) = P0/γ`` (erratum: not ``γ P0``)::

        Ṗ_i = (A−LC)P_i + P_i(A−LC)ᵀ + F̂_iM_iF̂_iᵀ/γ + LVLᵀ + P_iCᵀĤ_iQ_iĤ_iCP_i

    with ``F̂_i`` the other targets and the nuisance.  ``P_i = Π_i⁻¹`` finite and positive
    definite on the horizon is (3.15) = 0 with (3.17) tight and (3.18), so the game cost
    (3.12) is nonpositive (Problem 3.1).  ``M`` and ``Q`` may map target -> weight.  With
    small γ a fixed gain needs a small ``P0`` (``P0 ~ γ``): else the initial error alone
    breaks the bound.

    Parameters
    ----------
    model : LTVModel
        The plant.
    targets : sequence of str
        The faults sharing the gain, one DAP each.
    nuisance : sequence of str or ``'others'``
        The faults every target blocks besides the other targets: ``()`` none, ``'others'`` every other fault.
    gain : callable
        ``t -> L(t)``, the (n, p) gain schedule to check.
    t : (N,) array
        Time grid [s], strictly increasing, ``t[0] = t0`` and ``t[-1] = t1``.
    gamma, M, Q, V, P0, rtol, atol, method, escape, geometry_rtol : optional
        As in :func:`ltv_game_filter` (``gamma`` is required).

    Returns
    -------
    LTVFeasibility
        Feasibility, escape time and ``P_i(t_k)`` by target.

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer(), ["f1", "f2"])
    >>> L = np.array([[38.179, 40.535], [13.995, 16.317], [2.0, 5.678]])  # a Beard–Jones gain, Murray 2012, §6.2
    >>> res = ltv_feasibility(m, ["f1", "f2"], [], lambda t: L, [0.0, 5.0], gamma=1.0, M=0.05, Q=0.1, P0=1.0)
    >>> res.feasible, round(res.escape_time["f1"], 3)
    ({'f1': False, 'f2': True}, 1.06)

    References
    ----------
    Murray 2012, §3.1.2, Problem 3.1; §3.2.1, (3.12), (3.15)–(3.18); §3.3, (3.32).
    """
    comps = complements(model, targets, nuisance)
    t = _grid(t)
    feasible, escapes, covs = {}, {}, {}
    for target, comp in comps.items():
        sol, t_escape, n, _ = _riccati(model, target, comp, t, gain, gamma=gamma, M=M, Q=Q, V=V, P0=P0, rtol=rtol,
                                       atol=atol, method=method, escape=escape, geometry_rtol=geometry_rtol)
        feasible[target], escapes[target] = t_escape is None, t_escape
        covs[target] = np.array([_sym(P) for P in sol.y.T.reshape(-1, n, n)])
    return LTVFeasibility(t, feasible, escapes, covs)
