"""Distances between the models of a multiple model: ν-gap, L∞ and L2 (reference ``mddist``; Varga 2017, §3.6).

The distance of models ``i`` and ``j`` is that of their control channels ``G_u`` (with ``cdinp``, of
``[G_u G_d]``, the disturbance columns padded with zeros to the largest count):

* ``"nugap"``, Vinnicombe's ν-gap: ``δ_ν = sup_ω κ(G_i(jω), G_j(jω))`` with the chordal distance
  ``κ = σ_max((I + G_j G_jᴴ)^{-1/2} (G_i − G_j) (I + G_iᴴ G_i)^{-1/2})`` when the winding condition holds —
  ``det(I + G_j~ G_i)`` has no zero on the imaginary axis and ``wno det(I + G_j~ G_i) + η(G_i) − η(G_j) = 0``
  (``η``: poles in the open right half plane; ``wno``: counter-clockwise encirclements, counted as the right half
  plane poles minus zeros of the determinant, from the realisation of ``I + G_j~ G_i``) — and 1 otherwise.
  The supremum is taken on a logarithmic grid spanning the models' pole magnitudes, refined around the largest
  value by a bounded scalar search; with ``mdfreq``, ``κ`` is maximised over those frequencies only (the winding
  condition is not used, as in the reference).  Discrete models: the same on their images under
  ``z = (1 + s)/(1 − s)`` (unit circle to imaginary axis, outside of the disc to the right half plane).
* ``"inf"``: ``‖G_i − G_j‖∞`` (python-control's ``linfnorm``, SLICOT AB13DD; with ``mdfreq`` the largest
  ``σ_max`` at those frequencies).
* ``"2"``: ``‖G_i − G_j‖₂`` (python-control's ``norm(p=2)``; ``inf`` when the difference is unstable or, continuous,
  not strictly proper).

Why partly by hand: python-control has no ν-gap; the chordal distance and the winding number are a few lines on
its state-space objects.  Not covered: the ν-gap of models with poles on the stability boundary (``η₀`` of the
winding condition): refused with a clear error.

References
----------
Varga (2017), §3.6 (model detection, distances between models), §6.1; Vinnicombe (2001), Ch. 3 (the ν-gap);
fdtools (``mddist``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = ["ModelDistances", "MODEL_DISTANCES", "mddist", "nu_gap", "check_models"]

MODEL_DISTANCES = ("nugap", "inf", "2")


@dataclass(frozen=True, eq=False)
class ModelDistances:
    """The distances between the models of a multiple model.

    Attributes
    ----------
    distance : str
        ``"nugap"``, ``"inf"`` or ``"2"``.
    values : numpy.ndarray
        ``(N, N)``, symmetric with a zero diagonal.
    peak : numpy.ndarray
        ``(N, N)`` frequencies (rad/s) where each distance is attained (NaN for ``"2"``, and where the ν-gap is 1
        by the winding condition).

    Examples
    --------
    >>> d = ModelDistances("inf", np.zeros((2, 2)), np.zeros((2, 2)))
    >>> d.values.shape
    (2, 2)

    References
    ----------
    Varga (2017), §3.6; fdtools (``mddist``).
    """

    distance: str
    values: np.ndarray
    peak: np.ndarray


def check_models(models: Sequence[FaultModel]) -> tuple[FaultModel, ...]:
    """The models of a multiple model, checked: same outputs, same controls, same sample time.

    Parameters
    ----------
    models : sequence of FaultModel
        At least one model.

    Returns
    -------
    tuple of FaultModel

    Raises
    ------
    ParameterError
        An empty set, a non-FaultModel entry, or models that differ in their outputs, controls or sample time.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]])
    >>> len(check_models([m, m]))
    2

    References
    ----------
    Varga (2017), §2.2.2 (multiple models).
    """
    models = tuple(models)
    if not models or not all(isinstance(m, FaultModel) for m in models):
        raise ParameterError("give a non-empty sequence of FaultModel objects (one per model of the set)")
    m0 = models[0]
    for k, m in enumerate(models[1:], start=1):
        if m.outputs != m0.outputs or m.controls != m0.controls or m.dt != m0.dt:
            raise ParameterError(f"model {k} differs from model 0 in its outputs, controls or sample time; the models "
                                 "of a multiple model share y, u and dt (disturbances may differ)")
    return models


def _channel(m: FaultModel, cdinp: bool, md: int) -> tuple[np.ndarray, ...]:
    mu, k = len(m.controls), len(m.disturbances)
    cols = list(range(mu + (k if cdinp else 0)))
    B, D = m.B[:, cols], m.D[:, cols]
    if cdinp and k < md:
        B = np.hstack([B, np.zeros((m.n, md - k))])
        D = np.hstack([D, np.zeros((D.shape[0], md - k))])
    return m.A, B, m.C, D


def _chordal(G1: np.ndarray, G2: np.ndarray) -> float:
    def inv_sqrt(M):
        w, V = np.linalg.eigh((M + M.conj().T) / 2)
        return (V / np.sqrt(w)) @ V.conj().T

    p, m = G1.shape
    L = inv_sqrt(np.eye(p) + G2 @ G2.conj().T)
    R = inv_sqrt(np.eye(m) + G1.conj().T @ G1)
    return float(np.linalg.norm(L @ (G1 - G2) @ R, 2))


def _rhp(ev: np.ndarray) -> int:
    return int(np.sum(ev.real > 0))


def _winding_holds(sys1, sys2, tol: float = 1e-9) -> bool:
    """Vinnicombe's condition for ``δ_ν < 1`` (no poles on the imaginary axis)."""
    from fdikit.design.nullspace.factorization import series

    A1, B1, C1, D1 = sys1
    A2, B2, C2, D2 = sys2
    adj = (-A2.T, -C2.T, B2.T, D2.T)                   # G₂~(s) = G₂(−s)ᵀ
    A, B, C, D = series((A1, B1, C1, D1), adj)
    D = D + np.eye(D.shape[0])
    sv = np.linalg.svd(D, compute_uv=False)
    if sv[-1] <= tol * max(1.0, sv[0]):                # det(I + G₂~G₁) vanishes at infinity
        return False
    poles = np.linalg.eigvals(A) if A.shape[0] else np.zeros(0)
    zeros = np.linalg.eigvals(A - B @ np.linalg.solve(D, C)) if A.shape[0] else np.zeros(0)
    if np.any(np.abs(zeros.real) <= 1e-7 * np.maximum(1.0, np.abs(zeros))):
        return False                                   # a zero on the imaginary axis
    wno = _rhp(poles) - _rhp(zeros)
    eta1 = _rhp(np.linalg.eigvals(A1)) if A1.shape[0] else 0
    eta2 = _rhp(np.linalg.eigvals(A2)) if A2.shape[0] else 0
    return wno + eta1 - eta2 == 0


def nu_gap(sys1, sys2, *, freqs: Sequence[float] | None = None, dt: float | None = None) -> tuple[float, float]:
    """Vinnicombe's ν-gap of two systems ``(A, B, C, D)`` of equal shape, and the peak frequency.

    A discrete pair is mapped by ``z = (1 + s)/(1 − s)`` (:func:`~fdikit.design.nullspace.wiener_hopf.moebius`),
    which carries the unit circle onto the imaginary axis (``e^{jθ}`` to ``j tan(θ/2)``) and the poles outside the
    unit disc into the right half plane, so the chordal distances and the winding condition are those of the
    continuous images; the peak is mapped back to ``ω = 2 arctan(ω_c)/dt``.

    Parameters
    ----------
    sys1, sys2 : tuple of array_like
        The realisations.
    freqs : sequence of float, optional
        Evaluate the chordal distance at these frequencies only (rad/s; the winding condition is not checked).
    dt : float, optional
        The sample time of a discrete pair (None: continuous).

    Returns
    -------
    (float, float)
        ``(δ_ν, ω_peak)``; ``(1.0, nan)`` when the winding condition fails.

    Raises
    ------
    ParameterError
        Systems of different shapes, or a pole on the stability boundary (not covered).

    Examples
    --------
    ``1/(s+1)`` and ``2/(s+1)``: with ``x = ω² + 1`` the chordal distance is ``√(x / ((x+1)(x+4)))``, largest at
    ``x = 2`` (ω = 1) with 1/3:

    >>> d, w = nu_gap(([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), ([[-1.0]], [[1.0]], [[2.0]], [[0.0]]))
    >>> round(d, 9), round(w, 6)
    (0.333333333, 1.0)

    References
    ----------
    Vinnicombe (2001), Ch. 3 (definition 3.1, theorem 3.5); Varga (2017), §3.6.
    """
    from scipy.optimize import minimize_scalar

    from fdikit.design.nullspace.factorization import realization, transfer

    s1, s2 = realization(*sys1), realization(*sys2)
    if s1[3].shape != s2[3].shape:
        raise ParameterError(f"the two systems have different shapes {s1[3].shape} and {s2[3].shape}")
    if dt is not None:
        from fdikit.design.nullspace.wiener_hopf import moebius

        for A in (s1[0], s2[0]):
            if A.shape[0] and np.any(np.abs(np.abs(np.linalg.eigvals(A)) - 1) <= 1e-9):
                raise ParameterError("a model has a pole on the unit circle: the ν-gap of such models (η₀ in the "
                                     "winding condition) is not covered; use distance='inf' on a shifted model")
        c1, c2 = moebius(*s1, 1.0, 1.0, -1.0, 1.0), moebius(*s2, 1.0, 1.0, -1.0, 1.0)
        wc = None if freqs is None else np.tan(np.clip(np.asarray(freqs, dtype=float) * dt, 0, np.pi) / 2)
        if wc is not None:
            wc[np.asarray(freqs, dtype=float) * dt >= np.pi] = np.inf
        v, w = nu_gap(c1, c2, freqs=wc)
        return v, (float(2 * np.arctan(w) / dt) if np.isfinite(w) else (np.pi / dt if w == np.inf else w))
    for A in (s1[0], s2[0]):
        if A.shape[0] and np.any(np.abs(np.linalg.eigvals(A).real) <= 1e-9 * max(1.0, np.linalg.norm(A, 2))):
            raise ParameterError("a model has a pole on the imaginary axis: the ν-gap of such models (η₀ in the "
                                 "winding condition) is not covered; use distance='inf' on a shifted model")

    def kappa(w: float) -> float:
        return _chordal(transfer(s1, 1j * w), transfer(s2, 1j * w))

    if freqs is not None:
        w = np.atleast_1d(np.asarray(freqs, dtype=float))
        vals = [kappa(x) if np.isfinite(x) else _chordal(s1[3], s2[3]) for x in w]
        k = int(np.argmax(vals))
        return float(vals[k]), float(w[k])
    if not _winding_holds(s1, s2):
        return 1.0, float("nan")
    ev = np.concatenate([np.linalg.eigvals(A) for A in (s1[0], s2[0]) if A.shape[0]] or [np.ones(1)])
    lo, hi = max(np.abs(ev).min(), 1e-12) * 1e-3, max(np.abs(ev).max(), 1e-12) * 1e3
    grid = np.concatenate([[0.0], np.logspace(np.log10(lo), np.log10(hi), 2000)])
    vals = np.array([kappa(x) for x in grid])
    best, wbest = float(vals.max()), float(grid[int(np.argmax(vals))])
    k = int(np.argmax(vals))
    if 0 < k < grid.size - 1:
        r = minimize_scalar(lambda x: -kappa(np.exp(x)), bounds=(np.log(grid[k - 1] if k > 1 else lo),
                                                                 np.log(grid[k + 1])), method="bounded",
                            options={"xatol": 1e-10})
        if -r.fun > best:
            best, wbest = float(-r.fun), float(np.exp(r.x))
    k_inf = _chordal(s1[3], s2[3])
    if k_inf > best:
        best, wbest = k_inf, float("inf")
    return best, wbest


def mddist(models: Sequence[FaultModel], *, distance: str = "nugap", mdfreq: Sequence[float] | float | None = None,
           cdinp: bool = False) -> ModelDistances:
    """Pairwise distances of the models of a multiple model (reference ``mddist``).

    Parameters
    ----------
    models : sequence of FaultModel
        The models (same outputs, controls and sample time; :func:`check_models`).
    distance : {"nugap", "inf", "2"}, default "nugap"
        See the module docstring.
    mdfreq : float or sequence of float, optional
        Frequencies (rad/s) at which to evaluate (``"nugap"``, ``"inf"``).
    cdinp : bool, default False
        Use ``[G_u G_d]`` instead of ``G_u``.

    Returns
    -------
    ModelDistances

    Raises
    ------
    ParameterError
        Bad models or options; ``mdfreq`` with ``"2"``; ``"nugap"`` with a pole on the stability boundary.

    Examples
    --------
    Two first-order actuators ``14/(s+14)`` and ``7/(s+7)``: ``‖G₁ − G₂‖∞ = 1/3`` (at ``ω = √98``):

    >>> m1 = FaultModel([[-14.0]], [[14.0]], Bu=[[1.0]])
    >>> m2 = FaultModel([[-7.0]], [[7.0]], Bu=[[1.0]])
    >>> d = mddist([m1, m2], distance="inf")
    >>> round(float(d.values[0, 1]), 9), round(float(d.peak[0, 1] ** 2), 6)
    (0.333333333, 98.0)

    References
    ----------
    Varga (2017), §3.6; fdtools (``mddist``).
    """
    from fdikit import validate
    from fdikit.analysis.channels import check_freqs

    models = check_models(models)
    distance = validate.choice("distance", distance, MODEL_DISTANCES)
    dt = models[0].dt
    if distance == "2" and mdfreq is not None:
        raise ParameterError("mdfreq applies to distance='nugap' or 'inf', not to '2'")
    freqs = None
    if mdfreq is not None:
        freqs = check_freqs(mdfreq, dt)
        if np.any(freqs < 0):
            raise ParameterError(f"mdfreq must be non-negative frequencies in rad/s, got {mdfreq}")
    md = max(len(m.disturbances) for m in models)
    chans = [_channel(m, cdinp, md) for m in models]
    N = len(models)
    vals, peak = np.zeros((N, N)), np.full((N, N), np.nan)
    np.fill_diagonal(peak, 0.0)
    for i in range(N):
        for j in range(i + 1, N):
            if distance == "nugap":
                v, w = nu_gap(chans[i], chans[j], freqs=freqs, dt=dt)
            else:
                v, w = _difference_norm(chans[i], chans[j], distance, freqs, dt)
            vals[i, j] = vals[j, i] = v
            peak[i, j] = peak[j, i] = w
    return ModelDistances(distance, vals, peak)


def _difference_norm(sys1, sys2, distance: str, freqs, dt) -> tuple[float, float]:
    """``‖G₁ − G₂‖`` (``"inf"``: L∞, or the largest σ_max at ``freqs``; ``"2"``: L2) and the peak frequency."""
    import control
    from scipy.linalg import block_diag

    from fdikit.design.nullspace.factorization import transfer

    (A1, B1, C1, D1), (A2, B2, C2, D2) = sys1, sys2
    diff = (block_diag(A1, A2), np.vstack([B1, B2]), np.hstack([C1, -C2]), D1 - D2)
    if freqs is not None:
        pts = [1j * x if dt is None else np.exp(1j * x * dt) for x in freqs]
        g = [np.linalg.norm(transfer(diff, s), 2) if np.isfinite(s) else np.linalg.norm(diff[3], 2) for s in pts]
        k = int(np.argmax(g))
        return float(g[k]), float(freqs[k])
    if diff[0].shape[0] == 0:
        if distance == "inf":
            return float(np.linalg.norm(diff[3], 2)), 0.0
        return (0.0 if not np.any(diff[3]) or dt is not None else float("inf")), float("nan")
    sys = control.ss(*diff, 0 if dt is None else dt)
    if distance == "inf":
        g, w = control.linfnorm(sys)
        return float(g), float(w)
    red = control.minreal(sys, verbose=False)
    ev = np.linalg.eigvals(np.asarray(red.A)) if red.nstates else np.zeros(0)
    stable = np.all(ev.real < 0) if dt is None else np.all(np.abs(ev) < 1)
    proper = dt is not None or not np.any(diff[3])
    return (float(control.norm(red, p=2)) if stable and proper else float("inf")), float("nan")
