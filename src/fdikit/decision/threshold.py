"""Fixed thresholds per residual, calibrated on fault-free data, with k-of-n persistence.

The simplest residual processor of Douglas et al. 1996, §1 ("a simple threshold per
residual, traded between false and missed alarms").  Residual ``i`` fires when
``|r_i − c_i| > τ_i`` in at least ``k`` of the last ``n`` valid samples; the alarm
is on when any residual fires, and the fault is isolated when every fired residual
is tied to the same fault (:func:`fdikit.diagnosis.isolate`) or, with ``signatures=``, when the
fired residual groups match the fault's signature (:mod:`fdikit.decision.signature`).

Calibration for a target false-alarm probability ``α`` per sample (family-wise,
split evenly over the ``q`` residuals, Bonferroni):

* ``method='gaussian'``: ``c_i`` = mean, ``τ_i = σ_i Φ⁻¹(1 − α/(2q))`` — exact for
  Gaussian residuals (Kalman innovations), usable for any ``α``;
* ``method='empirical'``: ``τ_i`` = the ``1 − α/q`` quantile of ``|r_i − c_i|`` —
  distribution-free, needs at least ``10 q / α`` fault-free samples.

A rate of false alarms per hour converts to ``α = rate · dt / 3600`` (each exceedance
counted as an alarm; persistence and correlated residuals only lower the rate, so the
conversion is conservative).  ``fit`` takes one fault-free run or a list of runs
(:mod:`fdikit.decision.calibration`) and reports the false-alarm rate achieved on them with its
exact Poisson interval (``calibration``).
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.stats import norm

from fdikit.decision.calibration import calibration_report, calibration_runs
from fdikit.decision.common import checked_residuals, held, isolate_cached, isolate_fired, k_of_n, step_vector
from fdikit.decision.signature import as_signature_table
from fdikit.diagnosis import Alarm, Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["ThresholdEvaluator", "alpha_from_rate", "calibration_alpha"]

_COMPILED_RUN = 1 << 16  # residual entries from which run() uses the compiled pass (numba loaded on first use)


def alpha_from_rate(false_alarms_per_hour: float, dt: float) -> float:
    """Per-sample false-alarm probability for a target number of false alarms per hour.

    ``α = rate · dt / 3600``, capped at 1: every exceedance counted as one alarm, so the conversion is
    conservative (persistence and correlated residuals only lower the rate).

    Parameters
    ----------
    false_alarms_per_hour : float
        Target number of false alarms per hour of fault-free running [1/h]; positive.
    dt : float
        Sample time of the residuals [s]; positive.

    Returns
    -------
    float
        The per-sample false-alarm probability ``α`` in (0, 1].

    Raises
    ------
    ParameterError
        When the rate or ``dt`` is not positive.

    References
    ----------
    Douglas et al. 1996, Ch. 1 (a threshold per residual, traded between the rates of false and missed alarms).

    Examples
    --------
    >>> from fdikit.decision.threshold import alpha_from_rate
    >>> alpha_from_rate(36.0, 0.1)
    0.001
    """
    if not false_alarms_per_hour > 0 or not dt > 0:
        raise ParameterError(f"need a positive rate and sample time, got {false_alarms_per_hour}/h and dt={dt}")
    return min(1.0, false_alarms_per_hour * dt / 3600.0)


def calibration_alpha(false_alarm_prob: float | None, false_alarms_per_hour: float | None, dt: float) -> float:
    """The per-sample false-alarm probability of a calibration: given, or from a rate (exactly one of the two).

    Parameters
    ----------
    false_alarm_prob : float or None
        ``α`` in (0, 1).
    false_alarms_per_hour : float or None
        A rate instead (:func:`alpha_from_rate`).
    dt : float
        The residuals' sample time.

    Returns
    -------
    float
        ``α`` in (0, 1).

    Raises
    ------
    ParameterError
        Neither or both targets, or ``α`` outside (0, 1).

    References
    ----------
    Douglas et al. 1996, Ch. 1.

    Examples
    --------
    >>> calibration_alpha(None, 36.0, 0.1), calibration_alpha(0.01, None, 0.1)
    (0.001, 0.01)
    """
    if (false_alarm_prob is None) == (false_alarms_per_hour is None):
        raise ParameterError("give exactly one of false_alarm_prob and false_alarms_per_hour")
    alpha = alpha_from_rate(false_alarms_per_hour, dt) if false_alarm_prob is None else float(false_alarm_prob)
    if not 0 < alpha < 1:
        raise ParameterError(f"false-alarm probability must be in (0, 1), got {alpha}")
    return alpha


class ThresholdEvaluator:
    """Per-residual thresholds with k-of-n persistence.

    Parameters
    ----------
    thresholds : array_like, optional
        Fixed ``τ_i``; otherwise call :meth:`fit` on fault-free residuals.
    center : array_like, optional
        ``c_i`` (default 0, or the fault-free mean after :meth:`fit`).
    persistence : (k, n)
        Fire when ``k`` of the last ``n`` valid samples exceed (default (1, 1)).
    isolates : sequence, optional
        Fault tied to each residual; :meth:`fit` takes it from the residuals when not
        given, and :meth:`run` falls back to the residuals' own.  :meth:`step` sees bare
        vectors, so online isolation needs it set (here or by :meth:`fit`).
    groups : sequence, optional
        The filter each residual belongs to, for a bank: filters whose residuals point to
        two or more faults are discarded (:func:`fdikit.diagnosis.isolate`).
    signatures : SignatureTable, mapping or DataFrame, optional
        Isolate by the fault-signature table instead (:mod:`fdikit.decision.signature`): the fired
        residual groups are matched against each fault's pattern, so a fault that fires several groups is
        named; ``run`` and ``step`` name the same fault.  ``groups`` is then ignored.

    Attributes
    ----------
    calibration : CalibrationReport or None
        After :meth:`fit`: hours of data, the alarms the calibrated evaluator raises on the calibration runs,
        the Garwood interval of that rate and the smallest rate the data resolve
        (:class:`~fdikit.decision.calibration.CalibrationReport`).

    References
    ----------
    Douglas et al. 1996, Ch. 1 (a simple threshold per residual, set from empirical studies that balance the
    rate of false alarms against the rate of missed alarms).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import ThresholdEvaluator
    >>> rng = np.random.default_rng(0)
    >>> healthy = Residuals(np.arange(10000) * 0.01, rng.standard_normal((10000, 1)), ("r",), ("f",))
    >>> ev = ThresholdEvaluator().fit(healthy, false_alarm_prob=1e-3)
    >>> round(float(ev.thresholds[0]), 1)
    3.3
    >>> round(ev.calibration.hours * 3600), ev.calibration.runs
    (100, 1)
    """

    def __init__(
        self, thresholds=None, center=None, persistence: tuple[int, int] = (1, 1), isolates=None, groups=None,
        signatures=None,
    ) -> None:
        k, n = persistence
        if not (1 <= k <= n):
            raise ParameterError(f"persistence (k, n) needs 1 <= k <= n, got {persistence}")
        self.persistence = (int(k), int(n))
        self.thresholds = None if thresholds is None else np.atleast_1d(np.asarray(thresholds, dtype=float))
        if self.thresholds is not None and not np.all(self.thresholds > 0):
            raise ParameterError(f"thresholds must be positive, got {self.thresholds}")
        self.center = None if center is None else np.atleast_1d(np.asarray(center, dtype=float))
        self.isolates = None if isolates is None else tuple(isolates)
        self.groups = None if groups is None else tuple(groups)
        self.signatures = as_signature_table(signatures)
        self.names: tuple[str, ...] | None = None
        self.alpha: float | None = None
        self.calibration = None
        self.reset()

    # ------------------------------------------------------------------ calibration
    def fit(
        self,
        residuals: Residuals | list[Residuals],
        false_alarm_prob: float | None = None,
        false_alarms_per_hour: float | None = None,
        method: str = "gaussian",
    ) -> ThresholdEvaluator:
        """Calibrate centres and thresholds on fault-free residuals; returns ``self``.

        Parameters
        ----------
        residuals : Residuals or list of Residuals
            Fault-free residuals, one run or several (:func:`~fdikit.decision.calibration.calibration_runs`:
            their valid, finite rows are pooled — at least 10 must remain — while the calibration report
            evaluates each run on its own, so no persistence window crosses a run boundary).
        false_alarm_prob : float, optional
            ``α`` in (0, 1), the family-wise false-alarm probability per sample.
        false_alarms_per_hour : float, optional
            A rate instead, converted by :func:`alpha_from_rate` with the median sample time within the runs;
            give exactly one of the two.
        method : {'gaussian', 'empirical'}, default 'gaussian'
            ``τ_i = σ_i Φ⁻¹(1 − α/(2q))``, or the ``1 − α/q`` quantile of ``|r_i − c_i|`` (needs
            ``10 q/α`` samples).

        Returns
        -------
        ThresholdEvaluator
            ``self``, with ``center``, ``thresholds``, ``alpha``, ``names``, ``calibration`` (and ``isolates``
            when unset).

        Raises
        ------
        ParameterError
            When neither or both targets are given, ``α`` is not in (0, 1) or ``method`` is unknown.
        DataError
            When there are too few samples, or a residual is constant on the data.
        """
        calibration_alpha(false_alarm_prob, false_alarms_per_hour, 1.0)     # check the targets before the data
        runs = calibration_runs(residuals)
        r = runs.rows
        q = r.shape[1]
        alpha = calibration_alpha(false_alarm_prob, false_alarms_per_hour, runs.dt)
        a_i = alpha / q
        center = r.mean(axis=0)
        if method == "gaussian":
            std = r.std(axis=0, ddof=1)
            tau = std * norm.isf(a_i / 2)
        elif method == "empirical":
            if r.shape[0] * a_i < 10:
                raise DataError(
                    f"empirical calibration at α={alpha:g} needs at least {int(np.ceil(10 / a_i))} samples, "
                    f"got {r.shape[0]}; use method='gaussian' or more fault-free data"
                )
            tau = np.quantile(np.abs(r - center), 1 - a_i, axis=0)
        else:
            raise ParameterError(f"unknown calibration method {method!r}; use 'gaussian' or 'empirical'")
        if not np.all(tau > 0):
            bad = [runs.names[i] for i in np.flatnonzero(~(tau > 0))]
            raise DataError(f"residual(s) {bad} are constant on the fault-free data; cannot set a threshold")
        self.center, self.thresholds, self.alpha = center, tau, alpha
        self.names = runs.names
        if self.isolates is None:
            self.isolates = runs.isolates
        self.reset()
        target = false_alarms_per_hour if false_alarms_per_hour is not None else alpha * 3600.0 / runs.dt
        self.calibration = calibration_report(self, runs, target_rate=target)
        return self

    def _ready(self, q: int, residuals: Residuals | None = None) -> tuple[np.ndarray, np.ndarray, tuple]:
        if self.thresholds is None:
            raise ParameterError(
                "the evaluator has no thresholds; pass thresholds= or call fit() on fault-free residuals"
            )
        tau = np.broadcast_to(self.thresholds, (q,)) if self.thresholds.size in (1, q) else None
        if tau is None:
            raise DataError(f"{self.thresholds.size} thresholds for {q} residuals")
        c = np.zeros(q) if self.center is None else np.broadcast_to(self.center, (q,))
        iso = self.isolates or (residuals.isolates if residuals is not None else (None,) * q)
        return np.asarray(tau), np.asarray(c), tuple(iso)

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series; identical to stepping through it.

        A series of 65,536 residual entries or more is evaluated in one compiled pass
        (:func:`fdikit.runtime.evaluator_kernels.threshold_batch`, numba loaded on first use) with the same
        results; shorter ones by numpy.
        """
        residuals = checked_residuals(residuals, self.names, "the threshold evaluator")
        q = len(residuals.names)
        tau, c, iso = self._ready(q, residuals)
        r = residuals.r
        k, n = self.persistence
        meta = {"evaluator": "threshold", "thresholds": tau.tolist(), "persistence": list(self.persistence)}
        if r.size >= _COMPILED_RUN:
            return self._run_compiled(residuals, tau, c, iso, meta)
        valid = residuals.valid & np.all(np.isfinite(r), axis=1)
        fired = held(k_of_n(np.abs(r[valid] - c) > tau, k, n), valid, False)
        isolated = isolate_fired(fired, iso, self.groups, self.signatures, residuals.names)
        return Diagnosis(residuals.t, fired.any(axis=1), fired, residuals.names, isolated, valid=valid, meta=meta)

    def _run_compiled(self, residuals: Residuals, tau, c, iso, meta: dict) -> Diagnosis:
        """:meth:`run` for a long series: the same decisions from one compiled pass
        (:func:`fdikit.runtime.evaluator_kernels.threshold_batch`), the isolation once per distinct fired pattern."""
        from fdikit.runtime.evaluator_kernels import threshold_batch

        r = np.ascontiguousarray(residuals.r, dtype=float)
        N, q = r.shape
        fired, alarm = np.empty((N, q), bool), np.empty(N, bool)
        valid, starts = np.empty(N, bool), np.empty(N, np.int64)
        k, n = self.persistence
        m = threshold_batch(r, np.array(residuals.valid, dtype=bool), np.array(c, dtype=float),
                            np.array(tau, dtype=float), k, n, fired, alarm, valid, starts)  # writable copies: one type
        starts = starts[:m]  # the fired pattern is constant from each start to the next
        rows = fired[starts]
        packed = np.ascontiguousarray(np.packbits(rows, axis=1))
        keys = packed.view(np.dtype((np.void, packed.shape[1]))).ravel()
        _, first, inv = np.unique(keys, return_index=True, return_inverse=True)
        patterns = rows[first]
        labels = isolate_fired(patterns, iso, self.groups, self.signatures, residuals.names)
        inv = np.asarray(inv).ravel()
        isolated = np.repeat(labels[inv], np.diff(np.append(starts, N)))
        rises = np.flatnonzero(alarm[starts] & ~np.concatenate([[False], alarm[starts[:-1]]]))
        fired_names = [tuple(nm for nm, f in zip(residuals.names, p) if f) for p in patterns.tolist()]
        alarms = tuple(Alarm(time, int(i), lab, fired_names[u]) for time, i, lab, u in zip(
            residuals.t[starts[rises]].tolist(), starts[rises].tolist(), labels[inv[rises]].tolist(),
            inv[rises].tolist()))
        return Diagnosis(residuals.t, alarm, fired, residuals.names, isolated, alarms=alarms, valid=valid, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Forget the persistence window (start of a new run)."""
        self._window: deque = deque(maxlen=self.persistence[1])
        self._last = None
        self._labels: dict[bytes, str] = {}

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the previous decision.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the statistics and the decision hold.  ``names`` (optional) are
        checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).
        """
        r = step_vector(r, self.names, names, "the threshold evaluator")
        tau, c, iso = self._ready(r.size)
        if not (valid and np.all(np.isfinite(r))):
            fired = np.zeros(r.size, bool) if self._last is None else self._last
            valid = False
        else:
            self._window.append(np.abs(r - c) > tau)
            fired = np.sum(self._window, axis=0) >= self.persistence[0]
            self._last = fired
            valid = True
        fault = isolate_cached(self._labels, fired, iso, self.groups, self.signatures, self.names)
        return StepDecision(bool(fired.any()), fault, fired.copy(), valid)

    def __repr__(self) -> str:
        return f"ThresholdEvaluator(thresholds={self.thresholds}, persistence={self.persistence}, alpha={self.alpha})"
