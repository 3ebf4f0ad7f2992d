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
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from fdikit import validate
from fdikit.design.game.setup import weight
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.ltv import LTVModel, MatrixFunction, invariant_generators, ltv_projector
from fdikit.protocols import no_internal_form
from fdikit.residuals import Residuals

__all__ = [
    "LTVDetectionFilter",
    "LTVGameDesign",
    "LTVFeasibility",
    "ltv_detection_filter",
    "ltv_game_filter",
    "ltv_feasibility",
]


def _check_visible(model: LTVModel, target: str, H: np.ndarray, t: float, rtol: float) -> None:
    C = model.matrix("C", t)
    _, E = invariant_generators(model, target, t, rtol)
    if np.linalg.norm(H @ C @ E) <= 1e-9 * max(np.linalg.norm(C @ E), 1e-300):
        raise DesignError(f"target {target!r} is not output separable from its complementary faults at t = {t:g}: "
                          "Ĥ C W* = 0 (Murray Assumption 3.2); drop a nuisance fault or add a sensor")


# ---------------------------------------------------------------------- the filter
@dataclass(frozen=True, eq=False)
class LTVDetectionFilter:
    """Time-varying observer ``x̂' = A x̂ + B u + L(t)(y − C x̂ − D u)`` with projected residuals ``Ĥ_i(t) r``.

    Murray 2012, (3.7) and (3.9).  Attributes: ``model``; ``gain`` ``t -> L(t)`` (n x p);
    ``complementary`` target -> names of ``F̂_i``; ``gain_batch`` optional ``(N,) times ->
    (N, n, p)`` gains (used by :meth:`run` when given).
    """

    model: LTVModel
    gain: MatrixFunction
    complementary: dict[str, tuple[str, ...]]
    rtol: float = 1e-6
    gain_batch: Callable[[np.ndarray], np.ndarray] | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def projector(self, target: str, t: float) -> np.ndarray:
        """``Ĥ_i(t)`` of a target."""
        return ltv_projector(self.model, self.complementary[target], t, self.rtol)

    def _steps(self, t: np.ndarray, m: int, hold: str):
        """Step matrices on a grid (cached: several runs on one grid pay once)."""
        key = (t.tobytes(), m, hold)
        if key in self._cache:
            return self._cache[key]
        model, h = self.model, np.diff(t)
        mids = t[:-1] + h / 2
        C0 = model.matrix("C", t[0])
        p, n = C0.shape
        B = (lambda s: model.matrix("B", s)) if m else (lambda s: np.zeros((n, 0)))
        D = (lambda s: model.matrix("D", s)) if (m and model.D is not None) else (lambda s: np.zeros((p, m)))
        Ls = self.gain_batch(mids) if self.gain_batch is not None else np.array([self.gain(s) for s in mids])
        q = m + p
        size = n + q * (2 if hold == "foh" else 1)
        aug = np.zeros((t.size - 1, size, size))
        for k, s in enumerate(mids):
            L, C = Ls[k], model.matrix("C", s)
            aug[k, :n, :n] = (model.matrix("A", s) - L @ C) * h[k]
            aug[k, :n, n:n + q] = np.hstack([B(s) - L @ D(s), L]) * h[k]
            if hold == "foh":
                aug[k, n:n + q, n + q:] = np.eye(q)
        E = _expm_batch(aug)
        Phi, G0 = E[:, :n, :n], E[:, :n, n:n + q]
        G1 = E[:, :n, n + q:] if hold == "foh" else np.zeros_like(G0)
        Cs = np.array([model.matrix("C", s) for s in t])
        Ds = np.array([D(s) for s in t])
        Hs = {k: np.array([self.projector(k, s) for s in t]) for k in self.complementary}
        self._cache.clear()
        self._cache[key] = (Phi, G0 - G1, G1, Cs, Ds, Hs)
        return self._cache[key]

    def run(self, t, y, u=None, x0=None, hold: str = "foh") -> Residuals:
        """Projected residuals on sampled data ``(t_k, y_k, u_k)``.

        Each step ``[t_k, t_{k+1}]`` is integrated exactly for inputs interpolated linearly
        between samples (``hold='foh'``, default) or held (``'zoh'``, as
        :meth:`ResidualGenerator.run`), with ``A, B, C, L`` frozen at the step midpoint
        (second order in the time variation).  A high-gain (small γ) filter needs ``'foh'``:
        a held ``y`` lags by half a sample and leaks ``O(dt)`` into every residual.  Then
        ``r_k = y_k − C(t_k) x̂_k − D(t_k) u_k`` and the columns ``'<target>:<output>'``
        hold ``Ĥ_i(t_k) r_k``.  Stable for any gain size.
        """
        t, y = np.asarray(t, dtype=float).ravel(), np.atleast_2d(np.asarray(y, dtype=float).T).T
        C0 = self.model.matrix("C", t[0])
        m = 0 if self.model.B is None else self.model.matrix("B", t[0]).shape[1]
        u = np.zeros((t.size, m)) if u is None else np.atleast_2d(np.asarray(u, dtype=float).T).T
        (N, p), bad = y.shape, [f"hold must be 'foh' or 'zoh', got {hold!r}"] if hold not in ("foh", "zoh") else []
        if t.size < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
            bad.append("t must be finite and strictly increasing with at least 2 samples")
        if N != t.size or p != C0.shape[0] or u.shape != (N, m):
            bad.append(f"y has shape {y.shape} and u {u.shape}; need ({t.size}, {C0.shape[0]}) and ({t.size}, {m}): "
                       "one row per time, one column per output / control")
        elif not (np.all(np.isfinite(y)) and np.all(np.isfinite(u))):
            bad.append("y and u must be finite; clean or interpolate the data")
        if bad:
            raise DataError(bad[0])
        Phi, G0, G1, Cs, Ds, Hs = self._steps(t, m, hold)
        w = np.hstack([u, y])
        x = np.zeros((N, C0.shape[1]))
        x[0] = 0.0 if x0 is None else np.asarray(x0, dtype=float)
        for k in range(N - 1):
            x[k + 1] = Phi[k] @ x[k] + G0[k] @ w[k] + G1[k] @ w[k + 1]
        r = y - np.einsum("kpn,kn->kp", Cs, x) - np.einsum("kpm,km->kp", Ds, u)
        out_names = self.model.outputs or tuple(f"y{i}" for i in range(p))
        cols = [np.einsum("kij,kj->ki", Hs[k], r) for k in self.complementary]
        names = tuple(f"{k}:{o}" for k in self.complementary for o in out_names)
        isolates = tuple(k for k in self.complementary for _ in out_names)
        return Residuals(t, np.hstack(cols), names, isolates, meta={"filter": "ltv", "hold": hold})

    def run_trace(self, trace, x0=None) -> Residuals:
        """:meth:`run` on a :class:`~fdikit.trace.Trace`, reading the model's named controls and outputs."""
        if not self.model.outputs:
            raise DataError("the model has no output names; use run(t, y, u)")
        y = trace.columns("y", self.model.outputs)
        u = trace.columns("u", self.model.controls) if self.model.controls else None
        return self.run(trace.t, y, u, x0)


def ltv_detection_filter(model: LTVModel, targets: Sequence[str], nuisance: Sequence[str], gain: MatrixFunction,
                         rtol: float = 1e-6) -> LTVDetectionFilter:
    """A detection filter with a given gain schedule ``L(t)``; target ``i``'s residual is ``Ĥ_i(t) r``."""
    return LTVDetectionFilter(model, gain, _complements(model, targets, nuisance), rtol)


_PADE13 = (64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0, 129060195264000.0,
           10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0, 40840800.0, 960960.0, 16380.0, 182.0, 1.0)


def _expm_batch(A: np.ndarray) -> np.ndarray:
    """``expm`` of a stack of small matrices: Padé(13) scaling and squaring (Higham 2005), vectorised.

    Agrees with :func:`scipy.linalg.expm` to ~1e-12 and is 3–10x faster than calling it per step.
    """
    b = _PADE13
    s = np.ceil(np.log2(np.maximum(np.abs(A).sum(axis=-2).max(axis=-1), 1e-300) / 5.371920351148152))
    s = np.maximum(s, 0).astype(int)
    A = A / (2.0**s)[:, None, None]
    eye = np.eye(A.shape[-1])
    A2 = A @ A
    A4, A6 = A2 @ A2, A2 @ A2 @ A2
    U = A @ (A6 @ (b[13] * A6 + b[11] * A4 + b[9] * A2) + b[7] * A6 + b[5] * A4 + b[3] * A2 + b[1] * eye)
    V = A6 @ (b[12] * A6 + b[10] * A4 + b[8] * A2) + b[6] * A6 + b[4] * A4 + b[2] * A2 + b[0] * eye
    E = np.linalg.solve(V - U, V + U)
    for k in range(int(s.max(initial=0))):
        E[s > k] = E[s > k] @ E[s > k]
    return E


def _complements(model: LTVModel, targets: Sequence[str] | str,
                 nuisance: Sequence[str] | str) -> dict[str, tuple[str, ...]]:
    """Complementary faults by target; ``nuisance='others'`` is every other fault of the LTV model."""
    targets = [targets] if isinstance(targets, str) else [str(k) for k in targets]
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str):
        nuisance = [k for k in model.faults if k not in targets] if nuisance == "others" else [nuisance]
    nuisance = [str(k) for k in nuisance]
    if not targets:
        raise ParameterError("no target fault given; name at least one fault to detect")
    for k in targets + nuisance:
        if k not in model.faults:
            if k in model.outputs or k in model.controls:
                kind, fault = ("output", f"{k}_sensor") if k in model.outputs else ("control", f"{k}_actuator")
                what = "sensor" if kind == "output" else "actuator"
                raise ParameterError(f"{k!r} is an {kind}; its {what} fault is {fault!r}; faults are named by fault "
                                     f"name, not by signal name (the LTV model has {list(model.faults)})")
            raise ParameterError(f"no fault named {k!r}; the LTV model has {list(model.faults)}")
    both = set(targets) & set(nuisance)
    if both:
        raise DesignError(f"{sorted(both)} given both as target and as nuisance; each fault is one or the other")
    return {k: tuple(j for j in targets if j != k) + tuple(nuisance) for k in targets}


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

    Attributes
    ----------
    filter : the time-varying filter (gain from the dense Riccati solution, projector ``Ĥ(t)``).
    target : the target fault; t : design grid; covariance : ``P(t_k)`` (N, n, n);
    gains : ``L(t_k) = P Cᵀ V⁻¹`` (N, n, p); projector : ``Ĥ(t_k)`` (N, p, p); gamma : the bound.
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
                    method: str = "BDF", escape: float = 1e4, geometry_rtol: float = 1e-6) -> LTVGameDesign:
    """Finite-horizon time-varying single-fault game-theoretic detection filter (GTFDF).

    Integrates ``Ṗ = A P + P Aᵀ + F̂MF̂ᵀ/γ − P Cᵀ(V⁻¹ − ĤQĤ)C P`` forward from
    ``P(t0) = P0/γ`` (Murray 2012, (3.29) with ``P = Γ⁻¹``; the ``γ P0`` printed under (3.32)
    is corrected) and sets ``L = P Cᵀ V⁻¹`` (3.30).  ``F̂`` stacks the nuisance directions,
    ``Ĥ(t)`` annihilates ``C Ŵ*(t)`` (3.10).  :func:`scipy.integrate.solve_ivp` (stiff ``BDF``
    with the exact Jacobian) gives ``P`` on the grid ``t`` and a dense solution for the gain.

    Parameters
    ----------
    model : LTVModel.
    targets : the one fault of the model to detect (a fault name or a one-element sequence).
    nuisance : faults to block: a sequence of fault names, ``()`` none, or ``'others'`` every
        other fault of the model.
    t : time grid, ``t[0] = t0`` and ``t[-1] = t1``.
    gamma : attenuation bound (3.11); M, Q, V, P0 : weights (scalar = multiple of I).
    rtol, atol, method : ``solve_ivp`` settings.
    escape : finite escape is declared when ``max|P_ij|`` exceeds ``escape`` times
        ``max(1, ‖P0‖/γ, ‖F̂MF̂ᵀ‖(t1 − t0)/γ)``; the time is extrapolated (``P ~ 1/(t_e − t)``).

    Raises
    ------
    DesignError
        On finite escape (the time is in the message), bad weights, or a target that is not
        output separable from the nuisance.

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer("stable-extra-zero"), ["f1", "f2"])
    >>> d = ltv_game_filter(m, "f1", ["f2"], np.linspace(0, 4, 5), gamma=1e-6, M=0.05, Q=1e-3)
    >>> np.round(np.sort_complex(d.poles()), 2)
    array([-316.27+0.j  ,   -3.53-1.79j,   -3.53+1.79j])
    """
    validate.choice("integration method", method, _IVP_METHODS)
    given = [targets] if isinstance(targets, str) else list(targets)
    if len(given) != 1:
        raise ParameterError(f"ltv_game_filter detects one target fault, got {given}; check several with "
                             "ltv_feasibility")
    target = str(given[0])
    comp = _complements(model, [target], nuisance)[target]
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

    filt = LTVDetectionFilter(model, gain, {target: comp}, geometry_rtol, gain_batch)
    Hs = np.array([ltv_projector(model, comp, s, geometry_rtol) for s in t])
    return LTVGameDesign(filt, target, t, Ps, gains, Hs, float(gamma))


@dataclass(frozen=True, eq=False)
class LTVFeasibility:
    """Result of the finite-horizon check ``Ψ_i ≤ 0`` for a given gain (Murray 2012, (3.16)–(3.18), (3.32)).

    Attributes
    ----------
    t : the grid; feasible : target -> bool; escape_time : target -> time of finite escape or None;
    covariance : target -> ``P_i(t_k)`` up to the escape (K, n, n).
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
    breaks the bound.  Settings as :func:`ltv_game_filter`.

    Examples
    --------
    >>> from fdikit.ltv import LTVModel
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = LTVModel.from_lti(white_speyer(), ["f1", "f2"])
    >>> L = np.array([[38.179, 40.535], [13.995, 16.317], [2.0, 5.678]])  # a Beard–Jones gain, Murray 2012, §6.2
    >>> res = ltv_feasibility(m, ["f1", "f2"], [], lambda t: L, [0.0, 5.0], gamma=1.0, M=0.05, Q=0.1, P0=1.0)
    >>> res.feasible, round(res.escape_time["f1"], 3)
    ({'f1': False, 'f2': True}, 1.06)
    """
    comps = _complements(model, targets, nuisance)
    t = _grid(t)
    feasible, escapes, covs = {}, {}, {}
    for target, comp in comps.items():
        sol, t_escape, n, _ = _riccati(model, target, comp, t, gain, gamma=gamma, M=M, Q=Q, V=V, P0=P0, rtol=rtol,
                                       atol=atol, method=method, escape=escape, geometry_rtol=geometry_rtol)
        feasible[target], escapes[target] = t_escape is None, t_escape
        covs[target] = np.array([_sym(P) for P in sol.y.T.reshape(-1, n, n)])
    return LTVFeasibility(t, feasible, escapes, covs)
