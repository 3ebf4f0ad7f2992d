"""Compiled online steps of the residual evaluators: :func:`compile_evaluator` and :class:`CompiledEvaluator`.

What is compiled: the online ``step`` of a fitted :class:`~fdikit.decision.ThresholdEvaluator` (k-of-n
persistence), :class:`~fdikit.decision.CusumEvaluator` (restarts, hold, the rebase of the running sums),
:class:`~fdikit.decision.GlrEvaluator` (the window of change times), :class:`~fdikit.decision.SprtEvaluator`
(repeated or single test) and :class:`~fdikit.decision.MhsprtEvaluator` (Gaussian densities, corrected or literal
form, optional magnitude blocks), one numba call per sample (:mod:`fdikit.runtime.evaluator_kernels`).  A NaN/inf
entry or ``valid=False`` holds the statistics and the decision inside the kernel, exactly as the reference ``step``
does.  The isolation of the fault from the fired pattern stays in Python, computed lazily by the reference's own
logic (:func:`fdikit.decision.common.isolate_cached`; the MHSSPRT's single fired hypothesis), so ``groups``,
``isolates`` and ``signatures`` behave as in the reference.

Why hand-written: no library compiles these recursions, and the reference steps spend their time in per-call numpy
overhead (small arrays, checks, a new array per sample), not in arithmetic.  The kernels repeat the reference's
operations in the reference's order, so the compiled state tracks the reference's over long runs (to rounding of
``exp``/``log`` for the MHSSPRT; bit for bit otherwise).

References
----------
Douglas et al. 1996, Ch. 1 (a threshold per residual) and §7.2.1, Prop. 7.1 (the multiple-hypothesis Shiryayev
SPRT); Page 1954 and Basseville & Nikiforov 1993, §2.2 (the CUSUM), §2.4 (the window-limited GLR of Willsky &
Jones 1976); Wald 1947 (the SPRT).

Examples
--------
>>> import numpy as np
>>> from fdikit.residuals import Residuals
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.runtime.evaluators import compile_evaluator
>>> rng = np.random.default_rng(0)
>>> healthy = Residuals(np.arange(2000) * 0.01, rng.standard_normal((2000, 2)), ("a", "b"), ("fa", "fb"))
>>> ce = compile_evaluator(ThresholdEvaluator().fit(healthy, false_alarm_prob=1e-3))
>>> ce.step(np.array([0.1, -0.2])), ce.step(np.array([9.0, 0.0])), ce.fault
(False, True, 'fa')
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

import fdikit.decision.cusum as _cusum_module
from fdikit.decision.common import check_fitted_names, isolate_cached, step_vector
from fdikit.decision.cusum import CusumEvaluator
from fdikit.decision.densities import GaussianDensity
from fdikit.decision.glr import GlrEvaluator
from fdikit.decision.mhsprt import MhsprtEvaluator
from fdikit.decision.sprt import SprtEvaluator
from fdikit.decision.threshold import ThresholdEvaluator
from fdikit.diagnosis import UNKNOWN_FAULT, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.runtime import evaluator_kernels as kernels

__all__ = ["CompiledEvaluator", "compile_evaluator"]

_F64 = np.dtype(np.float64)
_CONTIGUOUS = (8,)  # strides of a contiguous 1-D float64 array: the only input the fast path hands to the kernel


class CompiledEvaluator:
    """A fitted evaluator's online step as one compiled call per sample (built by :func:`compile_evaluator`).

    Parameters
    ----------
    evaluator : ThresholdEvaluator, CusumEvaluator, GlrEvaluator, SprtEvaluator or MhsprtEvaluator
        The reference it was compiled from (kept as ``evaluator``; it is not stepped or changed).
    kind : str
        ``'threshold'``, ``'cusum'``, ``'glr'``, ``'sprt'`` or ``'mhsprt'``.
    kernel : numba dispatcher
        The module-level step kernel, called as ``kernel(r, valid, *state)``.
    state : tuple
        Parameter and state arrays (and scalars) of the kernel; the state arrays are changed in place.
    mutable : sequence of ndarray
        The arrays of ``state`` that :meth:`reset` restores to their values at construction.
    fired, info : ndarray
        The arrays of ``state`` holding the last decision per column and ``[used, …]``.
    names : tuple of str or None
        Residual names, in the order the kernel reads ``r``.
    columns : tuple of str
        Names of the columns of ``fired`` (residuals, blocks or faults).
    isolation : tuple or None
        ``(isolates, groups, signatures, names)`` for :func:`~fdikit.decision.common.isolate_cached`; None for the
        MHSSPRT (its single fired hypothesis is the fault).
    probabilities : ndarray, optional
        The array of ``state`` holding the hypothesis probabilities (MHSSPRT).
    stats : dict, optional
        Name → function of ``state`` giving the evaluator's statistics (:meth:`statistics`).

    Attributes
    ----------
    kernel, state, names, evaluator, kind
        As above; ``kernel(r, valid, *state)`` returns 0 (no alarm), 1 (alarm) or -1 (``r`` of the wrong length).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision import CusumEvaluator
    >>> from fdikit.runtime.evaluators import compile_evaluator
    >>> ce = compile_evaluator(CusumEvaluator(drift=0.5, threshold=4.0), names=("a",))
    >>> [ce.step(np.array([x])) for x in (0.0, 3.0, 3.0, float("nan"))], ce.decision().valid
    ([False, False, True, True], False)
    """

    def __init__(self, evaluator, kind: str, kernel, state: tuple, mutable: Sequence[np.ndarray], fired: np.ndarray,
                 info: np.ndarray, names, columns: tuple[str, ...], isolation, probabilities=None,
                 stats: dict | None = None) -> None:
        self.evaluator = evaluator
        self.kind = kind
        self.kernel = kernel
        self.state = tuple(state)
        self.names = None if names is None else tuple(names)
        self.columns = tuple(columns)
        self._fitted = evaluator.names if evaluator.names is not None else self.names
        self._label = {"threshold": "the threshold evaluator", "cusum": "the CUSUM", "glr": "the GLR",
                       "sprt": "the SPRT", "mhsprt": "the MHSPRT"}[kind]
        self._fired, self._info, self._P = fired, info, probabilities
        self._isolation = isolation
        self._stats = stats or {}
        self._initial = [(a, a.copy()) for a in mutable]
        self._cache: dict = {}
        self._fault: str | None = None
        self._q = int(self._expected())
        self._call = self._entry_point()

    def _expected(self) -> int:
        return len(self.names) if self.names is not None else int(self.state[-1][2])

    def _entry_point(self):
        """Compile the kernel for these argument types (on copies of the state) and return its typed entry point."""
        probe = np.zeros(self._q)
        copies = tuple(a.copy() if isinstance(a, np.ndarray) else a for a in self.state)
        self.kernel(probe, False, *copies)
        sig = tuple(numba.typeof(a) for a in (probe, False, *self.state))
        overload = self.kernel.overloads.get(sig)
        return self.kernel if overload is None else overload.entry_point

    # ------------------------------------------------------------------ stepping
    def step(self, r, valid: bool = True, *, names=None) -> bool:
        """One sample: the alarm after it (``fired``, ``fault`` and :meth:`decision` give the rest).

        Parameters
        ----------
        r : (q,) float64 ndarray, array_like or mapping
            The residual sample in the order of ``names`` (NaN/inf: a bad sample, the decision holds); a
            contiguous float64 array is passed to the kernel as it is, anything else (lists, other dtypes,
            ``{name: value}``) is converted by the reference's :func:`~fdikit.decision.common.step_vector`.
        valid : bool, default True
            False holds the statistics and the decision (a recovering sample after a gap).
        names : sequence of str, optional
            Names of the values of ``r``, checked against the fitted ones as the reference ``step`` does.

        Returns
        -------
        bool
            The alarm (any column fired).

        Raises
        ------
        DataError
            When ``r`` is not numeric, has the wrong number of values, or its names differ from the fitted ones.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.runtime.evaluators import compile_evaluator
        >>> ce = compile_evaluator(ThresholdEvaluator(thresholds=[1.0, 1.0]), names=("a", "b"))
        >>> ce.step(np.array([0.0, 2.0])), ce.step([0.0, 0.5]), ce.step({"a": 0.0, "b": 3.0})
        (True, False, True)
        """
        if valid is not True and valid is not False:
            valid = bool(valid)
        if names is None and type(r) is np.ndarray and r.dtype is _F64 and r.strides == _CONTIGUOUS:
            status = self._call(r, valid, *self.state)
        else:
            r = np.ascontiguousarray(step_vector(r, self._fitted, names, self._label), dtype=np.float64)
            status = self._call(r, valid, *self.state)
        self._fault = None
        if status < 0:
            raise DataError(
                f"step() got {np.size(r)} residual values; {self._label} was compiled for {self._q} residuals"
                + (f" {list(self.names)}" if self.names is not None else "")
                + ": pass one value per residual, in that order (or a mapping by name)"
            )
        return status == 1

    @property
    def fired(self) -> np.ndarray:
        """Per column (``columns``), the last decision (a copy)."""
        return self._fired.copy()

    @property
    def valid(self) -> bool:
        """Whether the last sample was used (False: a bad or ``valid=False`` sample, or no step yet)."""
        return bool(self._info[0])

    @property
    def probabilities(self) -> np.ndarray | None:
        """The hypothesis probabilities after the last sample (MHSSPRT; None for the others)."""
        return None if self._P is None else self._P.copy()

    @property
    def fault(self) -> str:
        """The isolated fault of the last decision: ``'none'``, a fault name or ``'unknown'`` (computed lazily)."""
        if self._fault is None:
            if self._isolation is None:
                hit = np.flatnonzero(self._fired)
                self._fault = NO_FAULT if hit.size == 0 else self.columns[hit[0]] if hit.size == 1 else UNKNOWN_FAULT
            else:
                iso, groups, signatures, names = self._isolation
                self._fault = isolate_cached(self._cache, self._fired, iso, groups, signatures, names)
        return self._fault

    def decision(self) -> StepDecision:
        """The :class:`~fdikit.diagnosis.StepDecision` the reference ``step`` returned for the last sample.

        Returns
        -------
        StepDecision
            Alarm, fault, ``fired`` (a copy), ``valid`` and the probabilities (MHSSPRT).

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.runtime.evaluators import compile_evaluator
        >>> ce = compile_evaluator(ThresholdEvaluator(thresholds=1.0, isolates=("fa",)), names=("a",))
        >>> _ = ce.step(np.array([2.0]))
        >>> d = ce.decision(); d.alarm, d.fault, d.fired.tolist(), d.valid
        (True, 'fa', [True], True)
        """
        fired = self._fired.copy()
        return StepDecision(bool(fired.any()), self.fault, fired, bool(self._info[0]), self.probabilities)

    def statistics(self) -> dict:
        """The evaluator's statistics after the last sample, as the reference exposes them after ``step``.

        Returns
        -------
        dict
            ``g_plus``/``g_minus`` (CUSUM), ``statistic``/``change_index`` (GLR), ``llr``/``decision`` (SPRT),
            ``state`` (MHSSPRT: ``log F`` corrected, ``F`` literal); empty for the threshold evaluator.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import CusumEvaluator
        >>> from fdikit.runtime.evaluators import compile_evaluator
        >>> ce = compile_evaluator(CusumEvaluator(drift=0.5, threshold=4.0), names=("a",))
        >>> _ = ce.step(np.array([2.0])); ce.statistics()["g_plus"].tolist()
        [1.5]
        """
        return {k: f(self.state) for k, f in self._stats.items()}

    def reset(self) -> None:
        """Back to the state at compilation (start of a new run), as the reference's ``reset``.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.runtime.evaluators import compile_evaluator
        >>> ce = compile_evaluator(ThresholdEvaluator(thresholds=1.0, persistence=(2, 3)), names=("a",))
        >>> [ce.step(np.array([2.0])) for _ in range(2)], (ce.reset(), ce.step(np.array([2.0])))[1]
        ([False, True], False)
        """
        for a, init in self._initial:
            np.copyto(a, init)
        self._fault = None

    def __repr__(self) -> str:
        return f"CompiledEvaluator({self.kind!r}, {len(self.columns)} columns, names={self.names})"


# ---------------------------------------------------------------------- builders (one per reference class)
def _threshold(ev: ThresholdEvaluator, names) -> CompiledEvaluator:
    q = len(names)
    tau, c, iso = ev._ready(q)
    k, n = ev.persistence
    win, cnt = np.zeros((n, q), np.int64), np.zeros(q, np.int64)
    fired, info = np.zeros(q, bool), np.zeros(2, np.int64)
    state = (np.array(c, float), np.array(tau, float), int(k), win, cnt, fired, info)
    return CompiledEvaluator(ev, "threshold", kernels.threshold_step, state, (win, cnt, fired, info), fired, info,
                             names, names, (tuple(iso), ev.groups, ev.signatures, ev.names))


def _cusum(ev: CusumEvaluator, names) -> CompiledEvaluator:
    q = len(names)
    nu, h, mu, sd, iso = ev._ready(q)
    par = np.array([mu, sd, nu, h], dtype=float)
    g, cl, fired = np.zeros((6, q)), np.zeros((2, q), np.int64), np.zeros(q, bool)
    info = np.array([0, ev.two_sided, ev.restart == "reset", ev.hold, _cusum_module._REBASE], np.int64)
    stats = {"g_plus": lambda s: s[1][4].copy(), "g_minus": lambda s: s[1][5].copy()}
    return CompiledEvaluator(ev, "cusum", kernels.cusum_step, (par, g, cl, fired, info), (g, cl, fired, info),
                             fired, info, names, names, (tuple(iso), ev.groups, ev.signatures, ev.names), stats=stats)


def _glr(ev: GlrEvaluator, names) -> CompiledEvaluator:
    q = len(names)
    mean, layout, h = ev._ready(q)
    G, P = layout.index.shape
    M = ev.window
    buf, idx, work = np.zeros((M, G, P)), np.zeros(M, np.int64), np.zeros((3, G, P))
    best = np.zeros((G, P + 1))
    ich = np.array([np.full(G, -1), np.zeros(G, np.int64)], np.int64)
    fired, info = np.zeros(G, bool), np.array([0, 0, 0, -1], np.int64)
    state = (np.array(mean, float), np.ascontiguousarray(layout.index, np.int64), np.ascontiguousarray(layout.whiten),
             np.array(h, float), buf, idx, work, best, ich, fired, info)
    stats = {"statistic": lambda s: s[7][:, 0].copy(), "change_index": lambda s: s[8][0].copy()}
    return CompiledEvaluator(ev, "glr", kernels.glr_step, state, (buf, idx, work, best, ich, fired, info), fired, info,
                             names, layout.names, (layout.isolates, layout.groups, ev.signatures, layout.names),
                             stats=stats)


def _sprt(ev: SprtEvaluator, names) -> CompiledEvaluator:
    q = len(names)
    mean, layout, w, c = ev._ready(q)
    G = len(layout.blocks)
    L, dl, fired = np.zeros((2, G)), np.zeros((3, G), np.int64), np.zeros(G, bool)
    info = np.array([0, ev.restart, ev.hold], np.int64)
    state = (np.array(mean, float), np.ascontiguousarray(layout.index, np.int64), np.ascontiguousarray(w, float),
             np.array(c, float), float(ev.A), float(ev.B), L, dl, fired, info)
    stats = {"llr": lambda s: s[6][1].copy(), "decision": lambda s: s[7][2].astype(np.int8)}
    return CompiledEvaluator(ev, "sprt", kernels.sprt_step, state, (L, dl, fired, info), fired, info, names,
                             layout.names, (layout.isolates, layout.groups, ev.signatures, layout.names), stats=stats)


def _mhsprt(ev: MhsprtEvaluator, names) -> CompiledEvaluator:
    ev._need()
    dens = ev.densities
    for hyp, d in dens.items():
        if type(d) is not GaussianDensity:
            raise ParameterError(
                f"cannot compile the MHSPRT: hypothesis {hyp!r} has a {type(d).__name__} density; only "
                "GaussianDensity (incl. gaussian_mean_density) is compiled — step the reference evaluator instead"
            )
    n = next(iter(dens.values())).dim
    if ev.blocks is None:
        blk, q = np.zeros((0, 1), np.int64), n
    else:
        groups = [np.flatnonzero([b == lab for b in ev.blocks]) for lab in dict.fromkeys(ev.blocks)]
        if len(groups) != n:
            raise ParameterError(f"cannot compile the MHSPRT: {len(groups)} magnitude blocks for densities of "
                                 f"dimension {n}")
        blk = np.full((len(groups), max(len(g) for g in groups)), -1, np.int64)
        for b, g in enumerate(groups):
            blk[b, : len(g)] = g
        q = len(ev.blocks)
    if names is not None and len(names) != q:
        raise DataError(f"{len(names)} residual names for an MHSPRT that reads {q} residuals")
    H = len(dens)
    mean = np.array([d.mean for d in dens.values()], float).reshape(H, n)
    W = np.array([d._W for d in dens.values()], float).reshape(H, n, n)
    hp = np.array([[d._const for d in dens.values()], ev._off, ev._log_p], float)
    fp = np.array([ev._p, ev._ft], float)
    state = np.array(ev._init, float)
    P = np.array(ev._probs(state), float)
    fired = P[1:] >= fp[1]
    work, info = np.zeros((4, max(H, n))), np.array([0, ev.form == "literal", q], np.int64)
    args = (np.ascontiguousarray(blk), mean, W, hp, fp, state, P, fired, work, info)
    return CompiledEvaluator(ev, "mhsprt", kernels.mhsprt_step, args, (state, P, fired, work, info), fired, info,
                             names, ev.faults, None, probabilities=P, stats={"state": lambda s: s[5].copy()})


_BUILDERS = ((ThresholdEvaluator, _threshold), (CusumEvaluator, _cusum), (GlrEvaluator, _glr),
             (SprtEvaluator, _sprt), (MhsprtEvaluator, _mhsprt))


def compile_evaluator(evaluator, names: Sequence[str] | None = None) -> CompiledEvaluator:
    """The compiled online step of a fitted evaluator (see the module docstring for what is compiled).

    Parameters
    ----------
    evaluator : ThresholdEvaluator, CusumEvaluator, GlrEvaluator, SprtEvaluator or MhsprtEvaluator
        A fitted (or fully configured) reference evaluator; its parameters are read now, as the reference reads
        them at its first ``step`` after ``reset``.  It is not changed.
    names : sequence of str, optional
        Residual names, for an evaluator set up by hand (not fitted); checked against the fitted ones otherwise.

    Returns
    -------
    CompiledEvaluator
        Stepping from the start of a run (the reference state after ``reset``).

    Raises
    ------
    ParameterError
        When the evaluator is not one of the kinds above, is not fitted (no thresholds, drift, densities …, or no
        residual names), or uses a part that is not compiled (an MHSSPRT density other than Gaussian).
    DataError
        When ``names`` differ from the fitted names, or the parameters do not fit the residuals.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import GlrEvaluator
    >>> from fdikit.runtime.evaluators import compile_evaluator
    >>> rng = np.random.default_rng(1)
    >>> healthy = Residuals(np.arange(3000) * 0.01, rng.standard_normal((3000, 2)), ("a", "b"), ("fa", "fb"))
    >>> ce = compile_evaluator(GlrEvaluator(window=20).fit(healthy, false_alarm_prob=1e-3))
    >>> alarms = [ce.step(np.array([1.5, 0.0])) for _ in range(20)]
    >>> alarms.index(True) > 0, ce.fault, ce.columns
    (True, 'fa', ('fa', 'fb'))
    """
    found = [(cls, build) for cls, build in _BUILDERS if isinstance(evaluator, cls)]
    if not found:
        raise ParameterError(
            f"cannot compile a {type(evaluator).__name__}; compile_evaluator takes a ThresholdEvaluator, "
            "CusumEvaluator, GlrEvaluator, SprtEvaluator or MhsprtEvaluator — step the reference evaluator instead"
        )
    cls, build = found[0]
    if names is not None:
        names = (names,) if isinstance(names, str) else tuple(names)
        check_fitted_names(names, evaluator.names, f"the {type(evaluator).__name__}")
    names = names if names is not None else evaluator.names
    if names is None and cls is not MhsprtEvaluator:
        raise ParameterError(
            f"the {type(evaluator).__name__} is not fitted (it has no residual names); call fit() on fault-free "
            "residuals, or pass names= (one per residual) for an evaluator set up by hand"
        )
    return build(evaluator, names)
