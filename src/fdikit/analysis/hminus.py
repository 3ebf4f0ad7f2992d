"""The classical H− index ``inf_ω σ_m(G(λ(ω)))`` of a stable internal form, by a frequency search.

Varga (2017) and FaultDetectionTools.jl measure fault sensitivity by the H∞− index
``min_j ‖g_j‖∞`` (:func:`fdikit.analysis.performance.fdhinfminus`); the literature's H− index
(Hou & Patton; Liu et al.) is the smallest ``m``-th singular value over frequency.  No library computes
it (python-control and SLICOT give the H∞ norm, the *largest* singular value), so it is searched here:
a grid (log-spaced over four decades either side of the system's pole and zero magnitudes in continuous
time, uniform plus log-refined towards Nyquist in discrete time) with the frequencies of the poles and
transmission zeros added, then a bounded scalar minimisation (``scipy.optimize.minimize_scalar``) on the
bracket of each local grid minimum, to a relative frequency tolerance ``1e-9``.  Continuous time also
takes the limit ``ω → ∞`` (``σ_m(D)``).  A dip narrower than the grid spacing away from every pole and
zero can be missed; the frequencies of the zeros are where ``σ_m`` vanishes, so those are never missed.

References
----------
Varga (2017), §3.3 (fault sensitivity measures); fdtools.

Examples
--------
>>> from fdikit import FaultModel
>>> R = FaultModel(A=[[-2.0]], C=[[1.0]], Bf=[[-1.0]], Df=[[1.0]], faults=["f"])   # (s + 1)/(s + 2)
>>> h = hminus_index(R)
>>> round(h.value, 9), round(h.freq, 9)
(0.5, 0.0)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg
import scipy.optimize

from fdikit import validate
from fdikit.analysis.channels import (
    check_freqs,
    check_stable,
    frequency_response,
    input_columns,
    internal_forms,
    minimal_channel,
)
from fdikit.analysis.performance import ColumnNorm
from fdikit.errors import ParameterError

__all__ = ["hminus_index"]


def _sigma_m(ch, w: float) -> float:
    G = frequency_response(ch, [w])[0]
    m = G.shape[1]
    s = np.linalg.svd(G, compute_uv=False)
    return float(s[m - 1]) if s.size >= m else 0.0


def hminus_index(sysr, freqs=None, *, inputs: Sequence[str] | None = None, num: int = 400) -> ColumnNorm:
    """Classical H− index ``inf_ω σ_m(G(λ(ω)))``: the smallest ``m``-th singular value over frequency.

    ``m`` is the number of columns (default the faults); ``σ_m = 0`` when ``G`` has fewer rows than
    columns.  Without ``freqs`` the infimum over all frequencies is searched (module docstring:
    grid with pole and zero frequencies, refined by a bounded minimisation to a relative frequency
    tolerance ``1e-9``); continuous time includes ``ω = ∞`` (``σ_m(D)``), discrete time runs over
    ``[0, π/dt]``.  With ``freqs`` the minimum over those frequencies.

    Parameters
    ----------
    sysr : FaultModel or design result
        A stable internal form.
    freqs : float or array_like, optional
        Frequencies [rad/s]; default the search over all.
    inputs : sequence of str, optional
        The columns; default the faults.
    num : int, default 400
        Points of the search grid.

    Returns
    -------
    ColumnNorm
        ``value`` (the index), ``column`` None, ``freq`` where attained (``inf`` for the ``D`` limit).

    Raises
    ------
    ModelError
        When the internal form is unstable.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-2.0]], C=[[1.0]], Bf=[[1.0]], Df=[[1.0]], faults=["f"])  # (s + 3)/(s + 2)
    >>> h = hminus_index(R)
    >>> round(h.value, 6), h.freq
    (1.0, inf)
    """
    num = validate.integer("num", num, minimum=3)
    form = internal_forms(sysr).forms[0]
    check_stable(form)
    cols = input_columns(form, inputs)
    if not cols:
        raise ParameterError("no columns to take the H− index of; the internal form has no faults")
    ch = minimal_channel(form, cols)
    if freqs is not None:
        omega = check_freqs(freqs, form.dt)
        vals = [_sigma_m(ch, w) for w in omega]
        k = int(np.argmin(vals))
        return ColumnNorm(float(vals[k]), None, float(omega[k]))
    if ch.D.shape[0] < ch.D.shape[1]:
        return ColumnNorm(0.0, None, 0.0)
    grid = _search_grid(ch, num)
    vals = np.array([_sigma_m(ch, w) for w in grid])
    best_k = int(np.argmin(vals))
    best = (vals[best_k], grid[best_k])
    for k in range(1, grid.size - 1):
        if vals[k] <= vals[k - 1] and vals[k] <= vals[k + 1]:
            lo, hi = grid[k - 1], grid[k + 1]
            res = scipy.optimize.minimize_scalar(lambda w: _sigma_m(ch, w), bounds=(lo, hi), method="bounded",
                                                 options={"xatol": 1e-9 * max(abs(grid[k]), 1e-12)})
            if res.fun < best[0]:
                best = (float(res.fun), float(res.x))
    if form.dt is None:
        at_inf = _sigma_m(ch, np.inf)
        if at_inf <= best[0]:
            best = (at_inf, float("inf"))
    return ColumnNorm(float(best[0]), None, float(best[1]))


def _search_grid(ch, num: int) -> np.ndarray:
    feats = []
    if ch.n:
        ev = np.linalg.eigvals(ch.A)
        feats.append(np.abs(ev) if ch.dt is None else np.abs(np.angle(ev)) / ch.dt)
        p, m = ch.D.shape
        if p == m:  # transmission zeros: generalised eigenvalues of the system pencil
            M = np.block([[ch.A, ch.B], [ch.C, ch.D]])
            N = np.block([[np.eye(ch.n), np.zeros((ch.n, m))], [np.zeros((p, ch.n + m))]])
            z = scipy.linalg.eigvals(M, N)
            z = z[np.isfinite(z)]
            feats.append(np.abs(z.imag) if ch.dt is None else np.abs(np.angle(z)) / ch.dt)
    feats = np.concatenate(feats) if feats else np.zeros(0)
    feats = feats[np.isfinite(feats) & (feats > 0)]
    if ch.dt is None:
        scale = feats if feats.size else np.array([1.0])
        lo, hi = max(scale.min(), 1e-8) * 1e-4, scale.max() * 1e4
        grid = np.concatenate([[0.0], np.logspace(np.log10(lo), np.log10(hi), num), feats])
    else:
        nyq = np.pi / ch.dt
        grid = np.concatenate([np.linspace(0.0, nyq, num), np.logspace(np.log10(nyq) - 6, np.log10(nyq), num // 2),
                               feats[feats <= nyq]])
    return np.unique(grid)
