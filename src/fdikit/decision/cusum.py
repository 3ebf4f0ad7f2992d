"""Two-sided CUSUM per residual (Page 1954; Basseville & Nikiforov 1993 §2.2), with Siegmund's ARL.

Each residual is standardised with its fault-free mean and standard deviation,
``s_k = (r_k − μ0)/σ``, and drives two one-sided Page statistics::

    g⁺_k = max(0, g⁺_{k−1} + s_k − ν)        (an increase of the mean)
    g⁻_k = max(0, g⁻_{k−1} − s_k − ν)        (a decrease)

with drift ``ν`` and threshold ``h`` in units of ``σ``.  The residual's test crosses at
sample ``k`` when ``g⁺_k > h`` or ``g⁻_k > h``.

Restart policy (``restart=``):

* ``'reset'`` (default, Page's renewal form): after a crossing both statistics of that
  residual restart from 0 at the next sample.  Every run length between alarms is then a
  fresh copy of the zero-state run length, so the mean time between false alarms is the
  ARL0 of the design and a sustained fault re-alarms every ARL(δ) samples.  ``fired`` is
  True at the crossing sample and for the next ``hold`` valid samples (``hold`` ≥ ARL(δ)
  keeps it on during a sustained fault).
* ``'none'``: the statistics are never reset; ``fired`` is True while ``g > h`` (and for
  ``hold`` valid samples after).  Under a sustained fault the alarm stays on; after a false
  alarm the statistic hovers near ``h`` and can re-cross, so only the first alarm of a run
  follows the ARL theory.

The residuals' alarm is any fired residual; the fault is isolated from the fired
residuals and each residual's tied fault by :func:`fdikit.diagnosis.isolate`, or, with
``signatures=``, by the fault-signature table (:mod:`fdikit.decision.signature`).  ``fit`` takes
one fault-free run or a list of runs (:mod:`fdikit.decision.calibration`: pooled moments, each run
evaluated on its own for the ``calibration`` report).

Average run length (Siegmund 1985, Basseville & Nikiforov eq. 5.2.44): for a one-sided
CUSUM whose increments ``s − ν`` are Gaussian with mean ``Δ`` and unit variance,

    ARL(Δ) ≈ (exp(−2Δb) + 2Δb − 1) / (2Δ²),   b = h + 1.166,   ARL(0) = b²,

(``1.166 = 2·0.583`` corrects for the overshoot of the threshold).  A mean shift of ``δ``
(in ``σ``) gives ``Δ = δ − ν`` for the upper and ``Δ = −δ − ν`` for the lower statistic;
fault-free, ``Δ = −ν`` and ``ARL0 ≈ (exp(2νb) − 2νb − 1)/(2ν²)``.  Two-sided,
``1/ARL = 1/ARL⁺ + 1/ARL⁻`` (van Dobben de Bruyn 1968; exact when the two sides cannot be
positive together, very accurate otherwise).  Run lengths count samples up to and
including the alarm sample, so a fault starting at sample ``k0`` is detected, on average,
``ARL(δ) − 1`` samples after ``k0``.

Numerics: ``g = S − min(0, min S)`` with ``S`` the running sum of the increments since the
last restart; :meth:`CusumEvaluator.run` evaluates this with cumulative sums over chunks and
:meth:`CusumEvaluator.step` with the same additions in the same order, so the two agree
bit for bit.  ``S`` is rebased (``S ← g``, ``min ← 0``) every 4096 valid samples so it
never grows large.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from fdikit.decision.calibration import calibration_report, calibration_runs
from fdikit.decision.common import (
    checked_residuals,
    held,
    is_count,
    isolate_cached,
    isolate_fired,
    k_of_n,
    step_vector,
)
from fdikit.decision.signature import as_signature_table
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["CusumEvaluator", "cusum_arl", "cusum_design", "SIEGMUND_CORRECTION"]

#: Siegmund's overshoot correction ``b = h + 1.166`` (``2·0.583``, ``0.583 = −ζ(1/2)/√(2π)``).
SIEGMUND_CORRECTION = 1.166

_REBASE = 4096  # valid samples between rebases of the running sum (same in run and step)
_SCALAR = 16  # samples of scalar recursion after a restart before returning to chunked sums
_RESTARTS = ("reset", "none")


def _arl_one_sided(mean_increment, b):
    """Siegmund's ARL for increments of mean ``Δ`` and unit variance, boundary ``b``."""
    d = np.asarray(mean_increment, dtype=float)
    b = np.asarray(b, dtype=float)
    x = 2.0 * d * b
    small = np.abs(x) < 1e-3
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        full = (np.expm1(-x) + x) / (2.0 * d * d)
    series = b * b * (1.0 - x / 3.0 + x * x / 12.0 - x**3 / 60.0)
    return np.where(small, series, full)


def cusum_arl(drift, threshold, shift=0.0, two_sided: bool = True):
    """Siegmund's approximation of the average run length of a CUSUM on N(δ, 1) data.

    Parameters
    ----------
    drift : float or array_like
        ``ν`` (in units of the residual's σ), ``≥ 0``.
    threshold : float or array_like
        ``h`` (in σ), ``> 0``.
    shift : float or array_like
        Mean shift ``δ`` of the standardised residual (0: the fault-free ARL0).
    two_sided : bool
        Combine the upper and lower statistics, ``1/ARL = 1/ARL⁺ + 1/ARL⁻``.

    Returns
    -------
    float or ndarray
        Expected number of samples up to and including the alarm, starting from ``g = 0``
        (``inf`` when it overflows).

    Raises
    ------
    ParameterError
        When a drift is negative or a threshold is not positive.

    References
    ----------
    Siegmund 1985 (the overshoot-corrected approximation); Basseville & Nikiforov 1993, §5.2, (5.2.44);
    van Dobben de Bruyn 1968 (the two-sided combination).

    Examples
    --------
    >>> round(float(cusum_arl(0.5, 4.0, two_sided=False)), 1)
    338.1
    >>> round(float(cusum_arl(0.5, 4.0, shift=1.0)), 2)
    8.34
    """
    nu, h = np.asarray(drift, dtype=float), np.asarray(threshold, dtype=float)
    if not np.all(nu >= 0):
        raise ParameterError(f"CUSUM drift must be >= 0, got {drift}")
    if not np.all(h > 0):
        raise ParameterError(f"CUSUM threshold must be positive, got {threshold}")
    delta = np.asarray(shift, dtype=float)
    b = h + SIEGMUND_CORRECTION
    up = _arl_one_sided(delta - nu, b)
    if not two_sided:
        out = up
    else:
        down = _arl_one_sided(-delta - nu, b)
        with np.errstate(divide="ignore"):
            out = 1.0 / (1.0 / up + 1.0 / down)
    return float(out) if out.ndim == 0 else out


def _threshold_for(arl0: float, nu: float, two_sided: bool) -> float:
    """The ``h`` whose Siegmund ARL0 equals ``arl0`` for drift ``nu``."""
    at_zero = float(_arl_one_sided(-nu, SIEGMUND_CORRECTION)) / (2.0 if two_sided else 1.0)
    if not arl0 > at_zero:
        raise ParameterError(
            f"target ARL0={arl0:g} is not above {at_zero:.3g} samples, the run length of h=0 with drift {nu:g}; "
            "ask for a longer mean time between false alarms"
        )

    def f(h):
        return np.log(cusum_arl(nu, h, 0.0, two_sided)) - np.log(arl0)

    hi = 1.0
    while f(hi) < 0:
        hi *= 2.0
        if hi > 1e6:
            raise ParameterError(f"no CUSUM threshold below 1e6 reaches ARL0={arl0:g} with drift {nu:g}")
    return float(brentq(f, 1e-12, hi, xtol=1e-13, rtol=4 * np.finfo(float).eps))


def cusum_design(arl0: float, shift: float, two_sided: bool = True) -> tuple[float, float]:
    """Drift and threshold of a CUSUM from a target ARL0 and the fault size.

    ``ν = δ/2`` (the optimal drift for a shift of ``δ``, half-way between the two means)
    and ``h`` solves ``cusum_arl(ν, h, 0) = arl0`` (Siegmund's approximation, by
    :func:`scipy.optimize.brentq`).

    Parameters
    ----------
    arl0 : float
        Target fault-free average run length in samples (mean time between false alarms
        divided by the sample time).
    shift : float
        Fault size ``δ`` in units of the residual's σ, ``> 0``.
    two_sided : bool
        Design the two-sided test (both statistics count towards false alarms).

    Returns
    -------
    (drift, threshold) : tuple of float
        ``ν = δ/2`` and the ``h`` whose Siegmund ARL0 is ``arl0``, both in units of σ.

    Raises
    ------
    ParameterError
        When ``shift`` is not a positive finite number, when ``arl0`` is not a finite number of samples
        above 1, or when ``arl0`` is not above the run length of ``h = 0`` with that drift (no threshold
        reaches it).

    References
    ----------
    Basseville & Nikiforov 1993, §2.2 (the drift half-way between the two means) and §5.2, (5.2.44)
    (Siegmund's ARL).

    Examples
    --------
    >>> nu, h = cusum_design(500.0, 1.0)
    >>> nu, round(h, 3)
    (0.5, 5.063)
    """
    if not np.isfinite(shift) or not shift > 0:
        raise ParameterError(f"fault size (shift) must be positive, in units of sigma; got {shift}")
    if not np.isfinite(arl0) or not arl0 > 1:
        raise ParameterError(f"target ARL0 must be a number of samples > 1, got {arl0}")
    nu = 0.5 * float(shift)
    return nu, _threshold_for(float(arl0), nu, two_sided)


def _param(name: str, value, positive: bool = True):
    if value is None:
        return None
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be a scalar or one value per residual, got shape {arr.shape}")
    if positive and not np.all(arr > 0):
        raise ParameterError(f"{name} must be positive, got {arr}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {arr}")
    return arr


def _widen(name: str, arr, q: int, default: float) -> np.ndarray:
    if arr is None:
        return np.full(q, default)
    if arr.size not in (1, q):
        raise DataError(f"{arr.size} {name} values for {q} residuals")
    return np.array(np.broadcast_to(arr, (q,)))


def _page(xp: np.ndarray, xm: np.ndarray | None, h: float, reset: bool):
    """Page statistics of one residual over its valid samples.

    Returns ``g⁺``, ``g⁻`` (zeros when one-sided) and the crossings.  The arithmetic is
    the online recursion of :meth:`CusumEvaluator.step`: ``S ← S + x``, ``M ← min(M, S)``,
    ``g = S − M``; restart ``S = M = 0`` after a crossing (``reset``); rebase ``S ← g``,
    ``M ← 0`` every ``_REBASE`` samples since the last restart.  Long stretches without a
    crossing are evaluated with cumulative sums over chunks; right after a restart (where
    the next crossing may be a few samples away, e.g. during a fault) a scalar loop runs
    until ``_SCALAR`` samples pass without one.
    """
    n = xp.size
    two = xm is not None
    gp, gm, ex = np.empty(n), np.zeros(n), np.zeros(n, bool)
    sp = mp = sm = mm = 0.0
    count, pos, chunk, scalar = 0, 0, 64, False
    while pos < n:
        if scalar:
            end = min(n, pos + _SCALAR)
            a = xp[pos:end].tolist()
            c = xm[pos:end].tolist() if two else a
            g1, g2, e = [0.0] * len(a), [0.0] * len(a), [False] * len(a)
            scalar = False
            for j in range(len(a)):
                sp += a[j]
                if sp < mp:
                    mp = sp
                g1[j] = gpj = sp - mp
                hit = gpj > h
                if two:
                    sm += c[j]
                    if sm < mm:
                        mm = sm
                    g2[j] = gmj = sm - mm
                    hit = hit or gmj > h
                e[j] = hit
                count += 1
                if hit and reset:
                    sp = mp = sm = mm = 0.0
                    count, scalar = 0, True
                elif count == _REBASE:
                    sp, mp, count = gpj, 0.0, 0
                    if two:
                        sm, mm = gmj, 0.0
            gp[pos:end], ex[pos:end] = g1, e
            if two:
                gm[pos:end] = g2
            pos = end
            continue
        L = min(n - pos, _REBASE - count, chunk)
        s1 = np.add.accumulate(np.concatenate(([sp], xp[pos : pos + L])))[1:]
        m1 = np.minimum.accumulate(np.concatenate(([mp], s1)))[1:]
        g1 = s1 - m1
        e = g1 > h
        if two:
            s2 = np.add.accumulate(np.concatenate(([sm], xm[pos : pos + L])))[1:]
            m2 = np.minimum.accumulate(np.concatenate(([mm], s2)))[1:]
            g2 = s2 - m2
            e |= g2 > h
        if reset and e.any():
            L = int(np.argmax(e)) + 1
            sp = mp = sm = mm = 0.0
            count, chunk, scalar = 0, 64, True
        else:
            sp, mp = float(s1[L - 1]), float(m1[L - 1])
            if two:
                sm, mm = float(s2[L - 1]), float(m2[L - 1])
            count += L
            if count == _REBASE:
                sp, mp, count = float(g1[L - 1]), 0.0, 0
                if two:
                    sm, mm = float(g2[L - 1]), 0.0
            chunk = min(2 * chunk, _REBASE)
        gp[pos : pos + L] = g1[:L]
        if two:
            gm[pos : pos + L] = g2[:L]
        ex[pos : pos + L] = e[:L]
        pos += L
    return gp, gm, ex


class CusumEvaluator:
    """Two-sided CUSUM per residual (see the module docstring for the equations and restarts).

    Parameters
    ----------
    drift : float or array_like, optional
        ``ν`` in units of σ, one value or one per residual.  Set here, or by
        :meth:`fit` from a target ARL0 and fault size.
    threshold : float or array_like, optional
        ``h`` in units of σ (alarm when ``g > h``).
    mean, sigma : float or array_like, optional
        ``μ0`` and ``σ`` per residual (default 0 and 1, or the fault-free estimates
        after :meth:`fit`).
    two_sided : bool
        Run both ``g⁺`` and ``g⁻`` (default); False keeps only ``g⁺`` (increases).
    restart : {'reset', 'none'}
        Restart both statistics of a residual after it crosses (default) or never.
    hold : int
        Keep ``fired`` on for this many valid samples after a crossing (default 0).
    isolates, groups : sequence, optional
        Fault tied to each residual, and the filter of each residual in a bank, as in
        :class:`~fdikit.decision.threshold.ThresholdEvaluator`.
    signatures : SignatureTable, mapping or DataFrame, optional
        Isolate by the fault-signature table (:mod:`fdikit.decision.signature`) instead.

    Attributes
    ----------
    calibration : CalibrationReport or None
        After :meth:`fit` with a target: the alarms raised on the calibration runs over their hours, with the
        Garwood interval (:class:`~fdikit.decision.calibration.CalibrationReport`).

    References
    ----------
    Page 1954 (the one-sided cumulative sum); Basseville & Nikiforov 1993, §2.2 (the two-sided CUSUM);
    Douglas et al. 1996, Ch. 7 introduction (the CUSUM compared with the Shiryayev SPRT).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> rng = np.random.default_rng(0)
    >>> healthy = Residuals(np.arange(20000) * 0.01, rng.standard_normal((20000, 2)), ("a", "b"), ("fa", "fb"))
    >>> ev = CusumEvaluator().fit(healthy, arl0=1000.0, shift=1.0)
    >>> ev.drift.round(2).tolist(), ev.threshold.round(2).tolist()
    ([0.5, 0.5], [6.46, 6.44])
    """

    def __init__(
        self, drift=None, threshold=None, mean=None, sigma=None, *, two_sided: bool = True,
        restart: str = "reset", hold: int = 0, isolates=None, groups=None, signatures=None,
    ) -> None:
        self.drift = _param("drift", drift)
        self.threshold = _param("threshold", threshold)
        self.mean = _param("mean", mean, positive=False)
        self.sigma = _param("sigma", sigma)
        if restart not in _RESTARTS:
            raise ParameterError(f"restart must be one of {_RESTARTS}, got {restart!r}")
        if not is_count(hold, 0):
            raise ParameterError(f"hold must be a non-negative number of samples, got {hold}")
        self.two_sided = bool(two_sided)
        self.restart = restart
        self.hold = int(hold)
        self.isolates = None if isolates is None else tuple(isolates)
        self.groups = None if groups is None else tuple(groups)
        self.signatures = as_signature_table(signatures)
        self.names: tuple[str, ...] | None = None
        self.arl0: float | None = None
        self.calibration = None
        self.reset()

    # ------------------------------------------------------------------ calibration
    def fit(
        self, residuals: Residuals | list[Residuals], arl0: float | None = None,
        mean_time_between_false_alarms: float | None = None, shift=None,
    ) -> CusumEvaluator:
        """Estimate ``μ0`` and ``σ`` per residual on fault-free data; optionally design ``ν`` and ``h``.

        Parameters
        ----------
        residuals : Residuals or list of Residuals
            Fault-free residuals, one run or several (invalid and non-finite rows are skipped; the rows of
            all runs are pooled, :func:`~fdikit.decision.calibration.calibration_runs`).
        arl0, mean_time_between_false_alarms : float, optional
            Target fault-free run length of the whole evaluator, in samples or in seconds
            (converted with the median sample time within the runs).  Split evenly over the ``q``
            residuals: each is designed for ``q · arl0`` (``1/ARL`` adds over
            independent residuals; positively correlated residuals lengthen the joint run length).
        shift : float or array_like, optional
            Fault size to detect, in residual units (one value or one per residual);
            sets ``ν = shift/(2σ)``.  Without it the drift given to the constructor is
            kept and only ``h`` is designed.

        Returns
        -------
        self
            With ``mean``, ``sigma``, ``names`` (and ``drift``, ``threshold``, ``arl0`` with a target), and
            ``calibration`` (the report on the calibration runs) when the evaluator is complete.
        """
        runs = calibration_runs(residuals)
        r = runs.rows
        q = r.shape[1]
        mean, sigma = r.mean(axis=0), r.std(axis=0, ddof=1)
        if not np.all(sigma > 0):
            bad = [runs.names[i] for i in np.flatnonzero(~(sigma > 0))]
            raise DataError(f"residual(s) {bad} are constant on the fault-free data; cannot standardise them")
        if arl0 is not None and mean_time_between_false_alarms is not None:
            raise ParameterError("give at most one of arl0 and mean_time_between_false_alarms")
        if mean_time_between_false_alarms is not None:
            dt = runs.dt
            if not mean_time_between_false_alarms > 0 or not dt > 0:
                raise ParameterError(
                    f"need a positive mean time between false alarms and sample time, "
                    f"got {mean_time_between_false_alarms} s and dt={dt}"
                )
            arl0 = mean_time_between_false_alarms / dt
        if shift is not None and arl0 is None:
            raise ParameterError(
                "a fault size (shift=) needs a target arl0= or mean_time_between_false_alarms="
            )
        if arl0 is not None:
            if shift is not None:
                delta = _widen("shift", _param("shift", shift), q, 1.0) / sigma
                nu = 0.5 * delta
            elif self.drift is not None:
                nu = _widen("drift", self.drift, q, 0.5)
            else:
                raise ParameterError(
                    "to design the threshold from arl0, give shift= (the fault size) or a drift"
                )
            h = np.array([_threshold_for(float(arl0) * q, float(v), self.two_sided) for v in nu])
            self.drift, self.threshold, self.arl0 = nu, h, float(arl0)
        self.mean, self.sigma = mean, sigma
        self.names = runs.names
        if self.isolates is None:
            self.isolates = runs.isolates
        self.reset()
        self.calibration = None
        if self.drift is not None and self.threshold is not None:
            target = 3600.0 / (self.arl0 * runs.dt) if self.arl0 is not None else None
            self.calibration = calibration_report(self, runs, target_rate=target)
        return self

    def _ready(self, q: int, residuals: Residuals | None = None):
        if self.drift is None or self.threshold is None:
            raise ParameterError(
                "the CUSUM has no drift/threshold; pass drift= and threshold= or call "
                "fit(fault_free, arl0=..., shift=...)"
            )
        nu = _widen("drift", self.drift, q, 0.5)
        h = _widen("threshold", self.threshold, q, 1.0)
        mu = _widen("mean", self.mean, q, 0.0)
        sd = _widen("sigma", self.sigma, q, 1.0)
        iso = self.isolates or (residuals.isolates if residuals is not None else (None,) * q)
        if len(iso) != q:
            raise DataError(f"{len(iso)} 'isolates' entries for {q} residuals")
        return nu, h, mu, sd, tuple(iso)

    def _meta(self, nu, h, mu, sd) -> dict:
        return {
            "evaluator": "cusum", "drift": nu.tolist(), "threshold": h.tolist(), "mean": mu.tolist(),
            "sigma": sd.tolist(), "two_sided": self.two_sided, "restart": self.restart, "hold": self.hold,
            "arl0": self.arl0,
        }

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series; identical to stepping through it.

        ``meta`` holds the parameters and the statistics ``g_plus``, ``g_minus`` (N, q)
        (the value at each sample before any restart; held on invalid samples).
        """
        residuals = checked_residuals(residuals, self.names, "the CUSUM")
        q = len(residuals.names)
        nu, h, mu, sd, iso = self._ready(q, residuals)
        r = residuals.r
        valid = residuals.valid & np.all(np.isfinite(r), axis=1)
        s = (r[valid] - mu) / sd
        xp = s - nu
        xm = (-s) - nu
        nv = s.shape[0]
        gp, gm, ex = np.zeros((nv, q)), np.zeros((nv, q)), np.zeros((nv, q), bool)
        for i in range(q):
            gp[:, i], gm[:, i], ex[:, i] = _page(
                xp[:, i], xm[:, i] if self.two_sided else None, float(h[i]), self.restart == "reset"
            )
        fired = held(k_of_n(ex, 1, self.hold + 1), valid, False)
        isolated = isolate_fired(fired, iso, self.groups, self.signatures, residuals.names)
        meta = self._meta(nu, h, mu, sd)
        meta["g_plus"], meta["g_minus"] = held(gp, valid, 0.0), held(gm, valid, 0.0)
        return Diagnosis(residuals.t, fired.any(axis=1), fired, residuals.names, isolated, valid=valid, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Restart the statistics from zero (start of a new run)."""
        self._state = None
        self.g_plus: np.ndarray | None = None
        self.g_minus: np.ndarray | None = None

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the statistics and the decision.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the statistics and the decision hold.  ``names`` (optional) are
        checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).

        After the call, ``g_plus`` and ``g_minus`` hold the current statistics.  The
        parameters are read at the first step after :meth:`reset` (or :meth:`fit`).
        """
        r = step_vector(r, self.names, names, "the CUSUM")
        st = self._state
        if st is not None and st["q"] != r.size:
            raise DataError(f"step() got {r.size} residuals after steps with {st['q']}; call reset() first")
        if st is None:
            q = r.size
            nu, h, mu, sd, iso = self._ready(q)
            z = np.zeros(q)
            st = self._state = {"q": q, "nu": nu, "h": h, "mu": mu, "sd": sd, "iso": iso, "cache": {},
                                "sp": z, "mp": z, "sm": z, "mm": z, "count": np.zeros(q, int),
                                "left": np.zeros(q, int), "fired": np.zeros(q, bool)}
            self.g_plus, self.g_minus = z, z
        if not (valid and np.all(np.isfinite(r))):
            fired = st["fired"]
            return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), False)
        nu, h = st["nu"], st["h"]
        s = (r - st["mu"]) / st["sd"]
        sp = st["sp"] + (s - nu)
        mp = np.minimum(st["mp"], sp)
        gp = sp - mp
        e = gp > h
        if self.two_sided:
            sm = st["sm"] + ((-s) - nu)
            mm = np.minimum(st["mm"], sm)
            gm = sm - mm
            e = e | (gm > h)
        else:
            sm = mm = gm = st["sm"]
        count = st["count"] + 1
        if self.restart == "reset" and e.any():
            sp, mp, sm, mm = (np.where(e, 0.0, a) for a in (sp, mp, sm, mm))
            count = np.where(e, 0, count)
        rebase = count == _REBASE
        if rebase.any():
            sp, mp = np.where(rebase, gp, sp), np.where(rebase, 0.0, mp)
            sm, mm = np.where(rebase, gm, sm), np.where(rebase, 0.0, mm)
            count = np.where(rebase, 0, count)
        left = st["left"]
        fired = e | (left > 0)
        st["left"] = np.where(e, self.hold, np.maximum(left - 1, 0)) if self.hold else left
        st.update(sp=sp, mp=mp, sm=sm, mm=mm, count=count, fired=fired)
        self.g_plus, self.g_minus = gp, gm
        return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), True)

    def _isolate(self, fired: np.ndarray) -> str:
        """Isolation of one sample's pattern (memoised: the patterns of a run are few)."""
        return isolate_cached(self._state["cache"], fired, self._state["iso"], self.groups, self.signatures,
                              self.names)

    def __repr__(self) -> str:
        return (f"CusumEvaluator(drift={self.drift}, threshold={self.threshold}, restart={self.restart!r}, "
                f"hold={self.hold}, two_sided={self.two_sided})")
