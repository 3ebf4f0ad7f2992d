"""Narendra-type residual evaluation filters with thresholds and structure-matrix matching (FDITOOLS' online FDD).

FaultDetectionTools.jl evaluates a discrete-time filter bank online (``FDSystem``, ``FDISystem`` and ``tstep!``):
each filter ``i`` (a group of residuals) gets the evaluation signal of a Narendra-type filter on the norm of its
residual vector,

    θ_i(k) = α_i ‖r_i(k)‖ + β_i e_i(k),        e_i(k+1) = γ_i e_i(k) + ‖r_i(k)‖,   e_i(0) = 0,

(Varga 2017, §3.6 (3.40)–(3.41); fdtools ``tstep!``; the instantaneous term plus a discounted sum of the past
norms, ``0 ≤ γ_i ≤ 1``), fires when ``θ_i(k) ≥ τ_i`` and names the fault whose column of the structure matrix equals
the fired pattern (weak isolation), or every fault whose filter fired when the structure matrix is the identity
(strong isolation).  :class:`NarendraEvaluator` is that decision logic as an fdikit evaluator:

* one evaluation signal per residual group (``groups=``; without it, one per residual, ``‖r_i‖ = |r_i|``, the
  reference's ``FDSystem`` with several evaluation signals);
* isolation by a structure matrix — :class:`~fdikit.analysis.structure.StructureMatrix` of the bank
  (``fditspec`` / ``fdisspec``), a :class:`~fdikit.decision.signature.SignatureTable` or a mapping — matched by the
  rule of :mod:`fdikit.decision.signature` (``match='exact'`` is the reference's weak isolation); with the
  identity structure, a single fired filter names its fault and several fired filters (simultaneous faults) give
  ``'unknown'`` with the fired filters in ``Diagnosis.fired`` — fdikit's diagnosis names one fault per sample;
* thresholds given (the reference's ``τ``) or set by :meth:`NarendraEvaluator.fit` as the empirical
  ``1 − α/q`` quantile of each ``θ_i`` on fault-free runs (each run filtered on its own);
* invalid samples and gaps hold ``e_i`` and the decision (the rules of :mod:`fdikit.decision`), so ``run`` and
  ``step`` decide identically.

No library implements this filter; it is a first-order recursion, written here.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.signal

from fdikit.decision.calibration import calibration_report, calibration_runs
from fdikit.decision.common import checked_residuals, held, isolate_cached, isolate_fired, step_vector
from fdikit.decision.signature import SignatureTable, as_signature_table
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["NarendraEvaluator", "narendra_signal"]


def narendra_signal(norms, alpha, beta, gamma) -> np.ndarray:
    """The evaluation signals ``θ(k) = α n(k) + β e(k)``, ``e(k+1) = γ e(k) + n(k)``, ``e(0) = 0``.

    Parameters
    ----------
    norms : (N, g) array_like
        Residual norms ``n_i(k) ≥ 0`` of ``g`` groups (valid samples only, in time order).
    alpha, beta, gamma : float or (g,) array_like
        The filter parameters per group.

    Returns
    -------
    (N, g) ndarray

    References
    ----------
    Varga (2017), §3.6 (3.40)–(3.41); fdtools (``tstep!``).

    Examples
    --------
    >>> narendra_signal([[1.0], [1.0], [1.0]], 0.0, 1.0, 0.5).ravel().tolist()
    [0.0, 1.0, 1.5]
    """
    n = np.atleast_2d(np.asarray(norms, dtype=float))
    g = n.shape[1]
    a, b, c = (np.broadcast_to(np.asarray(x, dtype=float), (g,)) for x in (alpha, beta, gamma))
    theta = a * n
    for i in range(g):
        if b[i] != 0 and n.shape[0]:
            theta[:, i] += b[i] * scipy.signal.lfilter([0.0, 1.0], [1.0, -c[i]], n[:, i])
    return theta


class NarendraEvaluator:
    """Narendra-type evaluation filters per residual group, thresholds, and structure-matrix isolation.

    Parameters
    ----------
    alpha, beta, gamma : float or sequence of float, defaults 0, 1, 0.9
        Filter parameters per group (the reference's defaults); ``α, β ≥ 0`` not both zero, ``0 ≤ γ ≤ 1``.
    thresholds : float or sequence of float, optional
        ``τ_i > 0`` per group; otherwise call :meth:`fit`.
    groups : sequence of str, optional
        The filter (group) of each residual, in residual order; default one group per residual.
    signatures : StructureMatrix, SignatureTable, mapping or DataFrame, optional
        The structure matrix of the bank: which groups each fault fires.  Without it, the residuals' ``isolates``
        and :func:`fdikit.diagnosis.isolate` decide.
    isolates : sequence of str, optional
        The fault tied to each residual (for isolation without ``signatures``).

    Attributes
    ----------
    names : tuple of str or None
        The residual names of the fit.
    group_names : tuple of str or None
        The groups, in order of first appearance.
    calibration : CalibrationReport or None
        After :meth:`fit`: the false-alarm rate achieved on the calibration runs.

    Raises
    ------
    ParameterError
        For parameters outside their ranges.

    References
    ----------
    Varga (2017), §3.6 (residual evaluation, (3.40)–(3.41)) and §5.4 (isolation by the structure matrix);
    fdtools (``FDSystem``, ``FDISystem``, ``tstep!``).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> ev = NarendraEvaluator(thresholds=[2.0, 2.0], signatures={"fa": ["r0"], "fb": ["r0", "r1"]})
    >>> r = Residuals(np.arange(5) * 0.1, np.array([[0, 0], [1, 0], [1, 1], [1, 1], [1, 1]]) * 1.5, ("r0", "r1"), ())
    >>> ev.run(r).isolated.tolist()   # θ(k) = Σ 0.9^(k−1−j) ‖r(j)‖ over the past samples
    ['none', 'none', 'none', 'fa', 'fb']
    """

    def __init__(self, alpha=0.0, beta=1.0, gamma=0.9, thresholds=None, groups: Sequence[str] | None = None,
                 signatures=None, isolates=None) -> None:
        self.alpha, self.beta, self.gamma = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (alpha, beta, gamma))
        if np.any(self.alpha < 0) or np.any(self.beta < 0) or np.any((self.alpha == 0) & (self.beta == 0)):
            raise ParameterError(f"need α ≥ 0, β ≥ 0 and not both zero, got α={self.alpha}, β={self.beta}")
        if np.any((self.gamma < 0) | (self.gamma > 1)):
            raise ParameterError(f"γ must lie in [0, 1] (the discount of past norms), got {self.gamma}")
        self.thresholds = None if thresholds is None else np.atleast_1d(np.asarray(thresholds, dtype=float))
        if self.thresholds is not None and not np.all(self.thresholds > 0):
            raise ParameterError(f"thresholds must be positive, got {self.thresholds}")
        self.groups = None if groups is None else tuple(str(g) for g in groups)
        self.signatures = as_signature_table(signatures)
        self.isolates = None if isolates is None else tuple(isolates)
        self.names: tuple[str, ...] | None = None
        self.calibration = None
        self.reset()

    @property
    def group_names(self) -> tuple[str, ...] | None:
        """The groups in order of first appearance (None before the residuals are known)."""
        if self.groups is not None:
            return tuple(dict.fromkeys(self.groups))
        return self.names

    def _layout(self, q: int, names) -> tuple[np.ndarray, tuple[str, ...]]:
        groups = self.groups if self.groups is not None else tuple(names)
        if len(groups) != q:
            raise DataError(f"groups= gives {len(groups)} entries for {q} residuals; give one group per residual")
        order = tuple(dict.fromkeys(groups))
        M = np.array([[g == h for h in order] for g in groups], dtype=bool)  # (q, g) membership
        g = len(order)
        for nm, v in (("alpha", self.alpha), ("beta", self.beta), ("gamma", self.gamma)):
            if v.size not in (1, g):
                raise DataError(f"{nm} has {v.size} entries for {g} residual groups")
        if self.thresholds is not None and self.thresholds.size not in (1, g):
            raise DataError(f"{self.thresholds.size} thresholds for {g} residual groups")
        return M, order

    def _norms(self, r: np.ndarray, M: np.ndarray) -> np.ndarray:
        return np.sqrt((r**2) @ M.astype(float))

    def _theta(self, r: np.ndarray, M: np.ndarray) -> np.ndarray:
        return narendra_signal(self._norms(r, M), self.alpha, self.beta, self.gamma)

    def _isolation(self, fired_groups: np.ndarray, M: np.ndarray, names, isolates):
        """Per-residual fired pattern (a residual fires with its group), the tied faults, and the signature table
        with this evaluator's groups as its members when the table has none."""
        fired = fired_groups @ M.T.astype(int) > 0
        iso = self.isolates or isolates or (None,) * len(names)
        table = self.signatures
        if table is not None and table.members is None and self.groups is not None:
            members = {g: [n for n, h in zip(names, self.groups) if h == g] for g in dict.fromkeys(self.groups)}
            table = SignatureTable(table, members={g: members.get(g, []) for g in table.groups}, match=table.match)
        return fired, iso, table

    # ------------------------------------------------------------------ calibration
    def fit(self, residuals: Residuals | list[Residuals], false_alarm_prob: float | None = None,
            false_alarms_per_hour: float | None = None) -> NarendraEvaluator:
        """Set ``τ_i`` to the ``1 − α/g`` quantile of ``θ_i`` on fault-free runs; returns ``self``.

        Parameters
        ----------
        residuals : Residuals or list of Residuals
            Fault-free runs; each is filtered from ``e = 0`` on its own.
        false_alarm_prob : float, optional
            ``α`` in (0, 1): the family-wise probability per sample that some ``θ_i`` exceeds its threshold.
        false_alarms_per_hour : float, optional
            A rate instead (:func:`~fdikit.decision.threshold.alpha_from_rate`); give exactly one of the two.

        Returns
        -------
        NarendraEvaluator

        Raises
        ------
        ParameterError
            Neither or both targets, or ``α`` outside (0, 1).
        DataError
            Fewer than ``10 g/α`` valid fault-free samples (the quantile is not resolved), or a group whose
            ``θ`` is zero on the data.
        """
        from fdikit.decision.threshold import calibration_alpha

        calibration_alpha(false_alarm_prob, false_alarms_per_hour, 1.0)     # check the targets before the data
        runs = calibration_runs(residuals)
        alpha = calibration_alpha(false_alarm_prob, false_alarms_per_hour, runs.dt)
        M, order = self._layout(len(runs.names), runs.names)
        thetas = []
        for run in runs.runs:
            ok = run.valid & np.all(np.isfinite(run.r), axis=1)
            thetas.append(self._theta(run.r[ok], M))
        theta = np.vstack(thetas)
        a_i = alpha / len(order)
        if theta.shape[0] * a_i < 10:
            raise DataError(f"calibration at α={alpha:g} needs at least {int(np.ceil(10 / a_i))} fault-free samples "
                            f"(the 1 − α/{len(order)} quantile of θ), got {theta.shape[0]}; give more fault-free data")
        tau = np.quantile(theta, 1 - a_i, axis=0)
        if not np.all(tau > 0):
            bad = [order[i] for i in np.flatnonzero(~(tau > 0))]
            raise DataError(f"group(s) {bad} have θ = 0 on the fault-free data; cannot set a threshold")
        self.thresholds, self.names = tau, runs.names
        if self.isolates is None:
            self.isolates = runs.isolates
        self.reset()
        target = false_alarms_per_hour if false_alarms_per_hour is not None else alpha * 3600.0 / runs.dt
        self.calibration = calibration_report(self, runs, target_rate=target)
        return self

    def _tau(self, g: int) -> np.ndarray:
        if self.thresholds is None:
            raise ParameterError("the evaluator has no thresholds; pass thresholds= or call fit() on fault-free "
                                 "residuals")
        return np.broadcast_to(self.thresholds, (g,))

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series, identical to stepping through it from :meth:`reset`.

        Parameters
        ----------
        residuals : Residuals
            The series (names as fitted).

        Returns
        -------
        Diagnosis
            ``fired`` per residual (a residual fires with its group), ``meta['theta']`` the evaluation signals
            ``(N, g)`` (held over invalid samples).
        """
        residuals = checked_residuals(residuals, self.names, "the Narendra evaluator")
        M, order = self._layout(len(residuals.names), residuals.names)
        tau = self._tau(len(order))
        valid = residuals.valid & np.all(np.isfinite(residuals.r), axis=1)
        theta = held(self._theta(residuals.r[valid], M), valid, 0.0)
        fired, iso, table = self._isolation(theta >= tau, M, residuals.names, residuals.isolates)
        isolated = isolate_fired(fired, iso, None if table else self.groups, table, residuals.names)
        meta = {"evaluator": "narendra", "thresholds": tau.tolist(), "groups": list(order), "theta": theta}
        return Diagnosis(residuals.t, fired.any(axis=1), fired, residuals.names, isolated, valid=valid, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Zero the filter states ``e_i`` (start of a run)."""
        self._e: np.ndarray | None = None
        self._last: np.ndarray | None = None
        self._labels: dict[bytes, str] = {}

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample or ``valid=False`` holds ``e`` and the decision.

        Parameters
        ----------
        r : array_like or mapping
            One residual sample (fitted order, or ``names``).
        valid : bool, default True
            False for a recovering sample (:class:`~fdikit.residuals.ResidualStepper`): treated as invalid.
        names : sequence of str, optional
            Names of the entries of ``r``, checked against the fit.

        Returns
        -------
        StepDecision
        """
        r = step_vector(r, self.names, names, "the Narendra evaluator")
        rn = self.names or tuple(f"r{i}" for i in range(r.size))
        M, order = self._layout(r.size, rn)
        tau = self._tau(len(order))
        if self._e is None:
            self._e = np.zeros(len(order))
        if valid and np.all(np.isfinite(r)):
            n = self._norms(r[None, :], M)[0]
            theta = np.broadcast_to(self.alpha, n.shape) * n + np.broadcast_to(self.beta, n.shape) * self._e
            self._e = np.broadcast_to(self.gamma, n.shape) * self._e + n
            self._last, ok = theta >= tau, True
        else:
            ok = False
        fired_g = np.zeros(len(order), bool) if self._last is None else self._last
        fired, iso, table = self._isolation(fired_g[None, :], M, rn, None)
        fault = isolate_cached(self._labels, fired[0], iso, None if table else self.groups, table, rn)
        return StepDecision(bool(fired.any()), fault, fired[0].copy(), ok)

    def __repr__(self) -> str:
        return (f"NarendraEvaluator(alpha={self.alpha.tolist()}, beta={self.beta.tolist()}, "
                f"gamma={self.gamma.tolist()}, thresholds={self.thresholds})")
