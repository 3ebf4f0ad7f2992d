"""Additive vs multiplicative steering-fault isolation by moving-window least squares.

van der Ploeg 2018, Ch. 3.  A steering actuator with an offset ``f_a`` and a gain
``f_m`` applies ``δ = f_m δ_set + f_a`` (eq. (1.3)); a parity residual generator that rejects the
disturbances and has unit DC gain sees

    r = G(q)[f_a + (f_m − 1) δ_set]                                           (4.10)

with ``G(q) = −N(q)F(q)/d(q)``.  The two faults reach ``r`` through the same transfer function,
so no LTI filter isolates them (Sec. 2-3).  The thesis instead regresses the last ``n`` residual
samples on the known signal ``E = δ_set`` and a constant, Def. 3-1.1 and (3.4)::

    [f̂_a, f̂_m − 1] = argmin_θ ‖ r_n − [1, E_n] θ ‖_2 ,

i.e. in closed form (window mean ``μ_n``, biased window variance ``V_n = σ_n² − μ_n²``, Sec. 1-4)::

    f̂_m − 1 = (μ_n[E r] − μ_n[E] μ_n[r]) / V_n[E],      f̂_a = μ_n[r] − (f̂_m − 1) μ_n[E].

The **pre-filter** variant (Sec. 3-2, (3.7)–(3.8)) regresses on ``Ẽ = G(q)[E]`` instead, which
makes the estimate exact for constant faults once the transients of ``G`` have died out
(Cor. 3-2.2; the convergence is exponential, not finite-time, unless ``G`` is deadbeat).

Conventions and errata applied (van der Ploeg 2018, Def. 3-1.1, (2.7), (4.6), Sec. 4-1):

* Def. 3-1.1 prints the regressor columns as ``[E, 1]`` but (3.4) and the proofs (A.1)–(A.2) read
  the result as ``[f̂_a; f̂_m]``; fdikit uses ``[1, E]`` so the output is ``(f̂_a, f̂_m)``.
* The residual of the case study carries ``(f_m − 1) δ_set`` (4.6); ``f̂_m = nominal_gain + slope``
  with ``nominal_gain = 1``.  Pass ``nominal_gain=0`` for the generic (2.7) form
  ``r = G[f_a + f_m E]``.
* Guard (Sec. 4-1): a window with ``V_n[E] ≈ 0`` (no excitation) has an unbounded
  error bound; it is flagged invalid and its estimates are NaN (never an exception).  So are the
  first ``n − 1`` samples and every window holding a non-finite value.

The error bounds of Thm 3-1.3 and Thm 3-2.1 need the true faults and live in
:mod:`fdikit.estimate.steering_bound`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.signal
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike

from fdikit import validate
from fdikit.errors import DataError, DesignError, ModelError, ParameterError

__all__ = [
    "SteeringFaultEstimate",
    "IsolatorStep",
    "SteeringFaultIsolator",
    "isolate_steering_faults",
    "lateral_fault_map",
    "fault_map_coefficients",
    "FaultMap",
]

#: A SISO discrete fault-to-residual map ``G(q)``: a :class:`scipy.signal.dlti` (TransferFunction,
#: ZerosPolesGain or StateSpace) or a ``(num, den)`` pair of coefficients in descending powers of ``q``.
FaultMap = scipy.signal.dlti | tuple[ArrayLike, ArrayLike]

_CHUNK = 1 << 20  # window elements per vectorised block (bounds the memory of sliding_window_view temporaries)


def lateral_fault_map(pole: float = 0.9048, zero: float = -0.97294, dt: float = 0.01) -> scipy.signal.TransferFunction:
    """Fault-to-residual map of the thesis' parity filter, ``G(q) = K (q − z_0)/(q − p)^3``, ``G(1) = 1``.

    van der Ploeg 2018, (4.10) with the triple pole of Sec. 4-3-1; ``K = (1 − p)^3/(1 − z_0)``
    makes the DC gain 1 (Lemma 2-1.2, (2.8b)).  The zero ``z_0 = −0.97294`` is that of ``N(q)F`` for
    the Table 4-1 vehicle at 70 km/h (computed from the Sec. 4-3-1 filter, not printed in the thesis;
    ``tests/studies/vanderploeg2018`` recompute it).
    Poles used in the thesis: 0.9048, 0.6065, 0.3679 (``e^{-10h}, e^{-50h}, e^{-100h}``).

    Parameters
    ----------
    pole : float, optional
        The triple pole ``p`` (default 0.9048 = ``e^{-10h}``), ``|p| < 1``.
    zero : float, optional
        The zero ``z_0`` (default −0.97294), not 1.
    dt : float, optional
        Sample time ``h`` [s] (default 0.01).

    Returns
    -------
    scipy.signal.TransferFunction
        ``G(q)``, discrete with sample time ``dt``.

    Raises
    ------
    ParameterError
        If ``|pole| ≥ 1``, ``zero`` is 1 or not finite, or ``dt`` is not positive.

    Examples
    --------
    >>> G = lateral_fault_map()
    >>> round(float(np.polyval(G.num, 1.0) / np.polyval(G.den, 1.0)), 12)
    1.0

    References
    ----------
    van der Ploeg 2018, §4-3-1, (4.9)–(4.10); Lemma 2-1.2, (2.8b).
    """
    p = validate.number("pole", pole, finite=False)
    z0 = validate.number("zero", zero, finite=False)
    dt = validate.positive("dt", dt)
    if not (np.isfinite(p) and abs(p) < 1):
        raise ParameterError(f"pole must lie strictly inside the unit circle (|pole| < 1) for a stable filter, "
                             f"got {pole!r}")
    if not (np.isfinite(z0) and z0 != 1.0):
        raise ParameterError(f"zero must be finite and not at q = 1 (the DC gain would vanish), got {zero!r}")
    gain = (1.0 - p) ** 3 / (1.0 - z0)
    return scipy.signal.TransferFunction(gain * np.array([1.0, -z0]), np.poly([p, p, p]), dt=dt)


def fault_map_coefficients(fault_map: FaultMap) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` of a SISO discrete map, descending powers of ``q``, ``den`` monic, ``len(num) == len(den)``.

    Parameters
    ----------
    fault_map : scipy.signal.dlti or tuple
        The map ``G(q)``: a discrete LTI system or a ``(num, den)`` pair in descending powers of ``q``.

    Returns
    -------
    num, den : ndarray
        Coefficients of equal length, ``den[0] = 1`` (the form :func:`scipy.signal.lfilter` reads).

    Raises
    ------
    ModelError
        If the map is not SISO, not proper, or has a zero leading denominator coefficient.
    DesignError
        If it is unstable (a pole on or outside the unit circle): a pre-filter must be the stable ``G(q)``.

    Examples
    --------
    >>> num, den = fault_map_coefficients(([1.0], [2.0, -1.0]))     # G(q) = 1 / (2q − 1)
    >>> num.tolist(), den.tolist()
    ([0.0, 0.5], [1.0, -0.5])

    References
    ----------
    van der Ploeg 2018, §3-2, (3.7)–(3.8) (the pre-filter ``G(q)``); (4.10).
    """
    if isinstance(fault_map, scipy.signal.dlti):
        tf = fault_map.to_tf()
        num, den = np.atleast_2d(np.asarray(tf.num, dtype=float)), np.asarray(tf.den, dtype=float).ravel()
        if num.shape[0] != 1:
            raise ModelError(f"the fault map must be SISO (one residual, one fault); got {num.shape[0]} outputs")
        num = num[0]
    else:
        try:
            num, den = (np.atleast_1d(np.asarray(c, dtype=float)).ravel() for c in fault_map)
        except (TypeError, ValueError):
            raise ModelError(
                f"a fault map is a scipy.signal.dlti or a (num, den) pair of coefficient arrays, got {fault_map!r}"
            ) from None
    num = np.trim_zeros(num, "f") if np.any(num) else np.zeros(1)
    den = np.trim_zeros(den, "f")
    if den.size == 0 or not np.all(np.isfinite(den)) or not np.all(np.isfinite(num)):
        raise ModelError("fault map coefficients must be finite and the denominator non-zero")
    if num.size > den.size:
        raise ModelError(
            f"the fault map is improper (numerator degree {num.size - 1} > denominator degree {den.size - 1}); "
            "a residual generator's fault map G(q) = -N(q)F/d(q) must be proper"
        )
    num, den = num / den[0], den / den[0]
    num = np.concatenate([np.zeros(den.size - num.size), num])
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    if poles.size and np.max(np.abs(poles)) >= 1.0:
        raise DesignError(
            f"the fault map has a pole at |q| = {np.max(np.abs(poles)):.6g} >= 1; the residual generator's "
            "denominator d(q) must be stable (all roots inside the unit circle)"
        )
    return num, den


@dataclass(frozen=True, eq=False)
class SteeringFaultEstimate:
    """Moving-window estimates of the steering offset and gain (van der Ploeg 2018, (3.4) / (3.8)).

    Attributes
    ----------
    t : ndarray
        (N,) sample times (or indices).
    f_a_hat : ndarray
        (N,) additive fault estimate, in the residual's units (rad for a steering angle); NaN where invalid.
    f_m_hat : ndarray
        (N,) multiplicative fault estimate (gain, ``nominal_gain`` when healthy); NaN where invalid.
    valid : ndarray of bool
        (N,) True where the window is full, finite and exciting (``V_n`` above the guard).
    regressor : ndarray
        (N,) the regressor signal used: ``E`` or the pre-filtered ``Ẽ = G(q)[E]``.
    mean, variance : ndarray
        (N,) ``μ_n`` and ``V_n`` of the regressor over each window (NaN before the first full window).
    excitation_factor : ndarray
        (N,) ``sqrt((max(1, σ_n²) + |μ_n|)/(n V_n))``, the bound of Lemma A-1.1 on
        ``‖Φ_n‖_2`` with the ``max(1, σ²)`` correction (erratum: see :mod:`fdikit.estimate.steering_bound`);
        measurable online, it is the excitation monitor (6.1).  inf where ``V_n = 0``.
    n : int
        Window length.
    nominal_gain : float
        The healthy gain (1 in the thesis convention).
    prefilter : tuple of ndarray or None
        ``(num, den)`` of the pre-filter ``G(q)``, or None.

    Examples
    --------
    >>> E = np.array([1.0, 2.0, 4.0, 3.0, 1.0, 2.0])
    >>> est = isolate_steering_faults(0.1 + (1.5 - 1.0) * E, E, n=3)   # f_a = 0.1, f_m = 1.5, G = 1
    >>> len(est), est.valid.tolist(), est.prefiltered
    (6, [False, False, True, True, True, True], False)
    >>> round(float(est.f_a_hat[-1]), 6), round(float(est.f_m_hat[-1]), 6)
    (0.1, 1.5)

    References
    ----------
    van der Ploeg 2018, Def. 3-1.1, (3.1)–(3.4); §3-2, (3.8).
    """

    t: np.ndarray
    f_a_hat: np.ndarray
    f_m_hat: np.ndarray
    valid: np.ndarray
    regressor: np.ndarray
    mean: np.ndarray
    variance: np.ndarray
    excitation_factor: np.ndarray
    n: int
    nominal_gain: float = 1.0
    prefilter: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def prefiltered(self) -> bool:
        """True for the pre-filter estimator (3.8)."""
        return self.prefilter is not None

    def __len__(self) -> int:
        return self.t.size


class IsolatorStep(NamedTuple):
    """One online estimate: ``f_a_hat``, ``f_m_hat`` (NaN when invalid), ``valid``.

    Attributes
    ----------
    f_a_hat : float
        Additive fault estimate; NaN when invalid.
    f_m_hat : float
        Multiplicative fault (gain) estimate; NaN when invalid.
    valid : bool
        Whether the window is full, finite and exciting.

    Examples
    --------
    >>> iso = SteeringFaultIsolator(n=2)
    >>> iso.step(0.6, 1.0)
    IsolatorStep(f_a_hat=nan, f_m_hat=nan, valid=False)
    >>> step = iso.step(1.1, 2.0)
    >>> round(step.f_a_hat, 12), round(step.f_m_hat, 12), step.valid
    (0.1, 1.5, True)

    References
    ----------
    van der Ploeg 2018, Def. 3-1.1, (3.4).
    """

    f_a_hat: float
    f_m_hat: float
    valid: bool


def _check_window(n) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2:
        raise ParameterError(
            f"window length n must be a positive integer >= 2 (a regression on [1, E] needs 2 samples), got {n!r}"
        )
    return int(n)


def _check_guard(min_variance: float, rtol: float) -> tuple[float, float]:
    mv = validate.number("min_variance", min_variance, finite=False)
    rt = validate.number("rtol", rtol, finite=False)
    if not (np.isfinite(mv) and mv >= 0):
        raise ParameterError(f"min_variance must be a finite non-negative number >= 0 (in units of E squared), "
                             f"got {min_variance!r}")
    if not (np.isfinite(rt) and 0 <= rt < 1):
        raise ParameterError(f"rtol must be in [0, 1) (threshold on V_n/σ_n² of the regressor), got {rtol!r}")
    return mv, rt


def _window_fit(Ew: np.ndarray, rw: np.ndarray, n: int, nominal: float, min_var: float, rtol: float):
    """Least squares of each window row of ``rw`` on ``[1, Ew]``: returns f_a, f_m, valid, μ, V, factor."""
    finite = np.isfinite(Ew).all(axis=1) & np.isfinite(rw).all(axis=1)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        mu = Ew.mean(axis=1)
        Ec = Ew - mu[:, None]
        var = (Ec * Ec).mean(axis=1)
        sigma2 = var + mu * mu
        mu_r = rw.mean(axis=1)
        cov = (Ec * (rw - mu_r[:, None])).mean(axis=1)
        valid = finite & (sigma2 > 0) & (var > min_var) & (var > rtol * sigma2)
        slope = np.where(valid, cov / np.where(valid, var, 1.0), np.nan)
        f_a = np.where(valid, mu_r - slope * mu, np.nan)
        factor = np.sqrt((np.maximum(1.0, sigma2) + np.abs(mu)) / (n * var))
    mu = np.where(finite, mu, np.nan)
    var = np.where(finite, var, np.nan)
    factor = np.where(finite, factor, np.nan)
    return f_a, nominal + slope, valid, mu, var, factor


def _prefilter_batch(num: np.ndarray, den: np.ndarray, E: np.ndarray) -> np.ndarray:
    """``G(q)[E]`` from a zero state; a non-finite sample gives NaN and holds the filter state (as online)."""
    out = np.full(E.shape, np.nan)
    finite = np.isfinite(E)
    if not finite.any():
        return out
    zi = np.zeros(den.size - 1)
    idx = np.flatnonzero(finite)
    breaks = np.flatnonzero(np.diff(idx) > 1) + 1
    for run in np.split(idx, breaks):
        if den.size > 1:
            out[run], zi = scipy.signal.lfilter(num, den, E[run], zi=zi)
        else:
            out[run] = num[0] * E[run]
    return out


def isolate_steering_faults(
    residual: ArrayLike,
    setpoint: ArrayLike,
    n: int,
    *,
    t: ArrayLike | None = None,
    prefilter: FaultMap | None = None,
    nominal_gain: float = 1.0,
    min_variance: float = 0.0,
    rtol: float = 1e-10,
) -> SteeringFaultEstimate:
    """Isolate an additive from a multiplicative steering fault over a moving window (batch).

    van der Ploeg 2018, FI filter (3.4)/(4.11), or with ``prefilter`` the pre-filter FI filter
    (3.7)–(3.8)/(4.13).  Vectorised over all windows with ``sliding_window_view``; the online twin
    :class:`SteeringFaultIsolator` gives the same numbers sample by sample.

    Parameters
    ----------
    residual : (N,) array
        Residual ``r = G(q)[f_a + (f_m − nominal_gain) E]`` of a disturbance-decoupled generator with
        ``G(1) = 1`` (e.g. the parity filter (4.9)).
    setpoint : (N,) array
        The known signal ``E`` (the steering set-point ``δ_set``, as commanded).
    n : int
        Window length (the thesis uses 10, 100, 500 in simulation and 200 in the experiments).
    t : (N,) array, optional
        Sample times for the result (default: sample indices).
    prefilter : FaultMap, optional
        ``G(q)`` to regress on ``Ẽ = G(q)[E]`` (run from a zero state, like the residual generator).
        Must be stable with ``G(1) = 1``.
    nominal_gain : float
        Healthy gain added to the slope: 1 for the thesis' ``(f_m − 1) δ_set`` convention (4.6).
    min_variance, rtol : float
        Guard: a window is valid only if ``V_n[E] > min_variance`` and ``V_n[E] > rtol σ_n²[E]``
        (``rtol`` flags a regressor collinear with the constant, e.g. a constant set-point; raise
        ``min_variance`` to refuse weakly exciting windows, in units of ``E²``).

    Returns
    -------
    SteeringFaultEstimate
        Estimates, validity and the regressor statistics per sample.

    Raises
    ------
    DataError
        If ``residual`` and ``setpoint`` are not 1-D arrays of equal length, or ``t`` does not match them.
    ParameterError
        If ``n`` is not an integer ≥ 2, or ``min_variance``/``rtol``/``nominal_gain`` is out of range.
    ModelError
        If ``prefilter`` is not a proper SISO map.
    DesignError
        If ``prefilter`` is unstable or its DC gain is not 1.

    Examples
    --------
    A constant offset of 0.002 rad and a gain of 0.5, seen through a unit DC-gain filter:

    >>> import numpy as np, scipy.signal
    >>> G = lateral_fault_map(pole=0.6065)
    >>> t = np.arange(3000) * 0.01
    >>> E = 2.3e-3 * np.sin(0.6 * np.pi * t)
    >>> num, den = fault_map_coefficients(G)  # equal lengths: lfilter reads them in powers of 1/q
    >>> r = scipy.signal.lfilter(num, den, 0.002 + (0.5 - 1.0) * E)
    >>> est = isolate_steering_faults(r, E, n=100, t=t, prefilter=G)
    >>> print(f"{est.f_a_hat[-1]:.6f} {est.f_m_hat[-1]:.6f}")
    0.002000 0.500000

    References
    ----------
    van der Ploeg 2018, Def. 3-1.1, (3.4), (4.11); §3-2, (3.7)–(3.8), Cor. 3-2.2, (4.13).
    """
    n = _check_window(n)
    min_var, rt = _check_guard(min_variance, rtol)
    nominal_gain = validate.number("nominal_gain", nominal_gain)
    r = validate.as_array("residual", residual, error=DataError, finite=False)
    E = validate.as_array("setpoint", setpoint, error=DataError, finite=False)
    if r.ndim != 1 or E.shape != r.shape:
        raise DataError(
            f"residual and setpoint must be 1-D arrays of equal length (samples), got shapes {r.shape} and "
            f"{E.shape}; pass one residual and the matching steering set-point samples"
        )
    N = r.size
    tt = np.arange(N, dtype=float) if t is None else validate.as_array("t", t, error=DataError)
    if tt.shape != (N,):
        raise DataError(f"t has shape {tt.shape}, need ({N},): one time per sample")
    coeffs = None
    if prefilter is not None:
        coeffs = fault_map_coefficients(prefilter)
        _check_unit_dc(*coeffs)
        E = _prefilter_batch(*coeffs, E)
    nominal = float(nominal_gain)
    f_a, f_m = np.full(N, np.nan), np.full(N, np.nan)
    valid = np.zeros(N, dtype=bool)
    mu, var, factor = np.full(N, np.nan), np.full(N, np.nan), np.full(N, np.nan)
    if N >= n:
        Ew, rw = sliding_window_view(E, n), sliding_window_view(r, n)
        step = max(1, _CHUNK // n)
        for lo in range(0, Ew.shape[0], step):
            hi = min(lo + step, Ew.shape[0])
            out = _window_fit(Ew[lo:hi], rw[lo:hi], n, nominal, min_var, rt)
            sl = slice(lo + n - 1, hi + n - 1)
            f_a[sl], f_m[sl], valid[sl], mu[sl], var[sl], factor[sl] = out
    return SteeringFaultEstimate(tt, f_a, f_m, valid, E, mu, var, factor, n, nominal, coeffs)


def _check_unit_dc(num: np.ndarray, den: np.ndarray, tol: float = 1e-6) -> None:
    dc = np.polyval(num, 1.0) / np.polyval(den, 1.0)
    if not abs(dc - 1.0) <= tol:
        raise DesignError(
            f"the pre-filter has DC gain {dc:.6g}, not 1; the FI filter assumes G(1) = 1 (Lemma 2-1.2, (2.8b)). "
            "Normalise the residual generator (scale N(q) by -d(1)/(N(1)F(1))) and pass its fault map"
        )


class SteeringFaultIsolator:
    """Online FI filter: one ``step(residual, setpoint)`` per sample, same numbers as :func:`isolate_steering_faults`.

    van der Ploeg 2018, (3.4) or with ``prefilter`` (3.8).  A ring buffer holds the last ``n``
    samples; the pre-filter ``G(q)`` runs in transposed direct form II (as :func:`scipy.signal.lfilter`)
    from a zero state.  A non-finite set-point holds the pre-filter state; any window holding a
    non-finite value is invalid (NaN estimates, ``valid=False``).

    Parameters
    ----------
    n : int
        Window length, ≥ 2.
    prefilter : FaultMap, optional
        ``G(q)`` for the pre-filter estimator (stable, ``G(1) = 1``); None regresses on ``E`` itself.
    nominal_gain : float, optional
        Healthy gain added to the slope (default 1).
    min_variance, rtol : float, optional
        The excitation guard, as in :func:`isolate_steering_faults` (defaults 0 and 1e-10).

    Raises
    ------
    ParameterError
        If ``n`` is not an integer ≥ 2, or the guard or ``nominal_gain`` is out of range.
    ModelError, DesignError
        If ``prefilter`` is not a proper, stable SISO map with unit DC gain.

    Examples
    --------
    >>> iso = SteeringFaultIsolator(n=3)
    >>> [iso.step(0.5 * e + 0.1, e).valid for e in (1.0, 2.0, 4.0)]
    [False, False, True]
    >>> s = iso.step(0.5 * 3.0 + 0.1, 3.0)
    >>> round(s.f_a_hat, 12), round(s.f_m_hat, 12)
    (0.1, 1.5)

    References
    ----------
    van der Ploeg 2018, Def. 3-1.1, (3.4); §3-2, (3.8).
    """

    def __init__(
        self,
        n: int,
        *,
        prefilter: FaultMap | None = None,
        nominal_gain: float = 1.0,
        min_variance: float = 0.0,
        rtol: float = 1e-10,
    ) -> None:
        self.n = _check_window(n)
        self.min_variance, self.rtol = _check_guard(min_variance, rtol)
        self.nominal_gain = validate.number("nominal_gain", nominal_gain)
        self.prefilter = None
        if prefilter is not None:
            self.prefilter = fault_map_coefficients(prefilter)
            _check_unit_dc(*self.prefilter)
        self.reset()

    def reset(self) -> None:
        """Empty the window and zero the pre-filter state."""
        self._E: deque[float] = deque(maxlen=self.n)
        self._r: deque[float] = deque(maxlen=self.n)
        self._z = np.zeros(0 if self.prefilter is None else self.prefilter[1].size - 1)

    def _filter(self, e: float) -> float:
        if self.prefilter is None:
            return e
        if not np.isfinite(e):
            return float("nan")
        b, a = self.prefilter
        z = self._z
        y = b[0] * e + (z[0] if z.size else 0.0)
        for i in range(z.size):
            nxt = z[i + 1] if i + 1 < z.size else 0.0
            z[i] = nxt + b[i + 1] * e - a[i + 1] * y
        return float(y)

    def step(self, residual: float, setpoint: float) -> IsolatorStep:
        """Push one sample; return the estimate of the window ending at it."""
        setpoint = validate.number("setpoint", setpoint, error=DataError, finite=False)
        residual = validate.number("residual", residual, error=DataError, finite=False)
        self._E.append(self._filter(setpoint))
        self._r.append(residual)
        if len(self._E) < self.n:
            return IsolatorStep(float("nan"), float("nan"), False)
        Ew = np.array(self._E)[None, :]
        rw = np.array(self._r)[None, :]
        f_a, f_m, valid, *_ = _window_fit(Ew, rw, self.n, self.nominal_gain, self.min_variance, self.rtol)
        return IsolatorStep(float(f_a[0]), float(f_m[0]), bool(valid[0]))
