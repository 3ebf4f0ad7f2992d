"""Batched execution over many traces at once: arrays of shape (runs R, samples N, signals).

:func:`dlsim_batch` simulates ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k] + D u[k]`` for R runs, each from its
own initial state; :func:`run_generator_batch` runs a :class:`~fdikit.residuals.ResidualGenerator` over them
(operating point as in its ``run``); :func:`threshold_batch` and :func:`cusum_batch` give the decisions of a
fitted threshold / CUSUM evaluator with a normalised decision statistic, and :func:`crossings` turns that
statistic into detection delays and false-alarm counts at many threshold levels at once.

Why hand-written: no library batches a discrete state-space recursion over many independent traces with
per-trace initial states.  ``scipy.signal.dlsim`` and ``control.forced_response`` take one trace and loop in
Python per sample; ``scipy.signal.lfilter`` batches one transfer function along an axis (no MIMO state space,
no initial state in state coordinates); the obvious numpy code (``x = x @ A.T + u[:, k] @ B.T``) pays a
strided copy and a small product per sample.  The default kernel is compiled with numba (imported on first
use, cached on disk): the runs in parallel, one sequential recursion each, the inputs read once.
``method="blas"`` is pure numpy (a GEMM for ``[B; D] u``, a time loop of ``(R × n) @ (n × n)`` products, a
GEMM for ``C x``).  Lifting over blocks as :func:`fdikit.lti.dlsim_blocked` does was measured and is slower
here: its Toeplitz products cost ``M·m·p`` flops per sample against ``(n + p)(n + m)``, and the per-sample
Python loop it removes is gone already (``docs/PERFORMANCE.md``, batched execution).  The threshold window and
the CUSUM are compiled kernels as well, parallel over runs (the CUSUM in the evaluator's arithmetic, bit for bit).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import ResidualGenerator
from fdikit.trace import Trace

__all__ = ["BatchDecision", "LevelCrossings", "crossings", "cusum_batch", "dlsim_batch", "run_generator_batch",
           "threshold_batch"]

_METHODS = ("numba", "blas")
_REBASE = 4096  # the CUSUM's rebase period, as in fdikit.decision.cusum (its run and step rebase alike)
_KERNEL: list = []


def _kernels():
    """The compiled kernels: LTI recursion, threshold window, CUSUM (numba, parallel over runs; cached on disk)."""
    if not _KERNEL:
        import numba
        prange = numba.prange

        @numba.njit(parallel=True, cache=True, nogil=True)
        def lti(Mt, u, off, x0, y, x_end):  # pragma: no cover - compiled
            R, N, m = u.shape
            n = x0.shape[1]
            q = Mt.shape[1]
            for r in prange(R):
                x = x0[r].copy()
                out = np.empty(q)
                for k in range(N):
                    out[:] = 0.0
                    for j in range(n):  # [x+; y] = [A B; C D] [x; u − u0], column by column (vectorises over i)
                        xj = x[j]
                        for i in range(q):
                            out[i] += Mt[j, i] * xj
                    for j in range(m):
                        uj = u[r, k, j] - off[j]
                        for i in range(q):
                            out[i] += Mt[n + j, i] * uj
                    for i in range(q - n):
                        y[r, k, i] = out[n + i]
                    for i in range(n):
                        x[i] = out[i]
                x_end[r] = x

        @numba.njit(parallel=True, cache=True, nogil=True)
        def threshold(r, c, tau, k, n, fired, stat, alarm):  # pragma: no cover - compiled
            R, N, q = r.shape
            for run in prange(R):
                win, top, v = np.zeros((n, q)), np.empty((k, q)), np.empty(q)  # win: a = |r − c| / τ, last n
                for t in range(N):
                    for i in range(q):
                        win[t % n, i] = abs(r[run, t, i] - c[i]) / tau[i]
                    top[:] = 0.0  # the k largest of the window, by an insertion network (0 while fewer than k)
                    for j in range(min(n, t + 1)):
                        v[:] = win[j]
                        for s in range(k):
                            for i in range(q):
                                hi = max(top[s, i], v[i])
                                v[i] = min(top[s, i], v[i])
                                top[s, i] = hi
                    best = 0.0
                    for i in range(q):
                        fired[run, t, i] = top[k - 1, i] > 1.0
                        best = max(best, top[k - 1, i])
                    stat[run, t], alarm[run, t] = best, best > 1.0

        @numba.njit(parallel=True, cache=True, nogil=True)
        def cusum(r, mu, sd, nu, h, two, hold, fired, stat, alarm):  # pragma: no cover - compiled
            R, N, q = r.shape
            for run in prange(R):
                sp, mp, sm, mm = np.zeros(q), np.zeros(q), np.zeros(q), np.zeros(q)
                left = np.zeros(q, np.int64)
                for t in range(N):
                    rebase = (t + 1) % _REBASE == 0
                    best, any_fired = 0.0, False
                    for i in range(q):  # the evaluator's operations, in its order (S += x, M = min, g = S − M)
                        s = (r[run, t, i] - mu[i]) / sd[i]
                        sp[i] += s - nu[i]
                        mp[i] = min(mp[i], sp[i])
                        g = sp[i] - mp[i]
                        if rebase:
                            sp[i], mp[i] = g, 0.0
                        if two:
                            sm[i] += (-s) - nu[i]
                            mm[i] = min(mm[i], sm[i])
                            gm = sm[i] - mm[i]
                            if rebase:
                                sm[i], mm[i] = gm, 0.0
                            g = max(g, gm)
                        z = g / h[i]  # > 1 exactly when g > h (correctly rounded division)
                        fired[run, t, i] = z > 1.0 or left[i] > 0
                        any_fired = any_fired or fired[run, t, i]
                        left[i] = hold if z > 1.0 else max(left[i] - 1, 0)
                        best = max(best, z)
                    stat[run, t], alarm[run, t] = best, any_fired

        _KERNEL.extend([lti, threshold, cusum])
    return _KERNEL


def _runs_array(name: str, value, ndim: int, what: str) -> np.ndarray:
    """A float64 C-contiguous array of ``ndim`` dimensions (no copy when it is one already)."""
    try:
        arr = np.ascontiguousarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataError(f"{name} must be an array of numbers of shape {what}, got {type(value).__name__}") from exc
    if arr.ndim != ndim:
        hint = f"; for one run pass {name}[None]" if arr.ndim == ndim - 1 else ""
        raise DataError(f"{name} must have shape {what}, got {arr.ndim} dimensions (shape {arr.shape}){hint}")
    return arr


def _initial_states(x0, R: int, n: int) -> np.ndarray:
    """``x0`` as (R, n): zeros, one state for every run, or one per run."""
    if x0 is None:
        return np.zeros((R, n))
    x = validate.as_array("x0 (the initial states)", x0)
    if x.shape == (n,):
        return np.tile(x, (R, 1))
    if x.shape != (R, n):
        raise ParameterError(f"x0 has shape {x.shape}; pass ({n},) (every run) or ({R}, {n}) (one state per run)")
    return np.ascontiguousarray(x)


def _simulate(A, B, C, D, u, x0, offset, method) -> tuple[np.ndarray, np.ndarray]:
    """``y`` (R, N, p) and the final states (R, n) for inputs ``u − offset``; matrices already checked."""
    method = validate.choice("method", method, _METHODS)
    R, N, m = u.shape
    n, p = A.shape[0], C.shape[0]
    x0 = _initial_states(x0, R, n)
    if N == 0:
        return np.zeros((R, 0, p)), x0
    if method == "numba":
        y, x_end = np.empty((R, N, p)), np.empty((R, n))
        Mt = np.ascontiguousarray(np.block([[A, B], [C, D]]).T)
        _kernels()[0](Mt, u, np.array(offset, dtype=float), x0, y, x_end)
    else:
        _finite_or_raise(u, offset, np.zeros((R, 0)))
        w = u.reshape(R * N, m) - offset if np.any(offset) else u.reshape(R * N, m)
        W = (w @ np.vstack([B, D]).T).reshape(R, N, n + p)
        X, At, tmp = np.empty((R, N, n)), np.ascontiguousarray(A.T), np.empty((R, n))
        X[:, 0] = x0
        for k in range(N - 1):
            np.matmul(X[:, k], At, out=tmp)
            np.add(tmp, W[:, k, :n], out=X[:, k + 1])
        x_end = X[:, -1] @ At + W[:, -1, :n]
        y = (X.reshape(R * N, n) @ C.T).reshape(R, N, p) + W[..., n:]
    # a NaN/inf anywhere in a run's inputs (or an overflow) makes every later state non-finite: check the ends
    _finite_or_raise(u, offset, x_end if n else y.reshape(R, -1))
    return y, x_end


def _finite_or_raise(u, offset, ends) -> None:
    bad = np.flatnonzero(~np.isfinite(ends if ends.shape[1] else u.reshape(len(u), -1)).all(axis=1))
    if bad.size:
        r = int(bad[0])
        rows = np.flatnonzero(~np.isfinite(u[r] - offset).all(axis=1))
        where = f"sample {int(rows[0])}" if rows.size else "no input sample (the filter overflowed: unstable?)"
        raise DataError(f"{bad.size} run(s) give non-finite values, the first is run {r} (non-finite input at "
                        f"{where}); the batch path has no gap rule: fill or cut invalid samples, or run those "
                        "traces one by one with ResidualGenerator.run, which propagates the filter through gaps")


def dlsim_batch(A, B, C, D, u, x0=None, *, method: str = "numba",
                return_state: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Responses of one discrete LTI system to the inputs of ``R`` independent runs.

    ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k] + D u[k]`` for each run, from its own initial state;
    the same sample-by-sample recursion as ``scipy.signal.dlsim`` (equal to rounding).

    Parameters
    ----------
    A, B, C, D : array_like
        ``n × n``, ``n × m``, ``p × n``, ``p × m``.
    u : (R, N, m) array_like
        Inputs: runs × samples × inputs, finite.
    x0 : (n,) or (R, n) array_like, optional
        Initial state of every run, or one per run (zeros when omitted).
    method : {'numba', 'blas'}, default 'numba'
        The compiled kernel (parallel over runs), or numpy GEMMs around a time loop over all runs.
    return_state : bool, default False
        Also return the state after the last sample of each run.

    Returns
    -------
    y : (R, N, p) ndarray
        Outputs.
    x_end : (R, n) ndarray
        Only with ``return_state``: ``x[N]`` of each run.

    Raises
    ------
    DataError
        If ``u`` is not 3-D with ``m`` inputs, or a run's inputs are not finite (the message names run and sample).
    ParameterError
        For malformed matrices, a bad ``x0`` or an unknown ``method``.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.ones((2, 4, 1))
    >>> y, x_end = dlsim_batch([[0.5]], [[1.0]], [[1.0]], [[0.0]], u, x0=[[0.0], [8.0]], return_state=True)
    >>> y[..., 0].tolist(), x_end.ravel().tolist()
    ([[0.0, 1.0, 1.5, 1.75], [8.0, 5.0, 3.5, 2.75]], [1.875, 2.375])
    """
    A = validate.as_square("A", A)
    B, C = validate.as_matrix("B", B, (A.shape[0], None)), validate.as_matrix("C", C, (None, A.shape[0]))
    D = validate.as_matrix("D", D, (C.shape[0], B.shape[1]))
    u = _runs_array("u", u, 3, f"(runs, samples, {B.shape[1]} inputs)")
    if u.shape[2] != B.shape[1]:
        raise DataError(f"u has {u.shape[2]} inputs (last axis, shape {u.shape}) but B has {B.shape[1]} columns")
    y, x_end = _simulate(A, B, C, D, u, x0, np.zeros(B.shape[1]), method)
    return (y, x_end) if return_state else y


def _stack(generator: ResidualGenerator, traces: Sequence[Trace]) -> tuple[ResidualGenerator, np.ndarray]:
    """The discrete generator for the traces' sample time and their stacked absolute inputs (R, N, m + p)."""
    for i in (i for i, tr in enumerate(traces) if not isinstance(tr, Trace)):
        raise DataError(f"traces[{i}] is a {type(traces[i]).__name__}, not a fdikit.trace.Trace")
    lengths = sorted({len(tr) for tr in traces})
    if len(lengths) > 1:
        raise DataError(f"the traces have {len(lengths)} different lengths ({', '.join(map(str, lengths[:5]))} "
                        "samples); a batch needs equal lengths: cut them to a common length or run them one by one")
    g = generator
    if lengths[0] > 1:
        dts = np.array([ResidualGenerator.check_uniform(tr) for tr in traces])
        if not np.allclose(dts, dts[0], rtol=1e-6, atol=0):
            i = int(np.flatnonzero(~np.isclose(dts, dts[0], rtol=1e-6, atol=0))[0])
            raise DataError(f"traces[{i}] is sampled at dt={dts[i]:g} s, traces[0] at {dts[0]:g} s; a batch needs "
                            "one sample time: resample them")
        if g.dt is None:
            g = g.discretize(float(dts[0]))
        elif not np.isclose(dts[0], g.dt, rtol=1e-6):
            raise DataError(f"the traces are sampled at dt={dts[0]:g} but the generator is discrete with "
                            f"dt={g.dt:g}; resample")
    elif g.dt is None:
        raise DataError("a continuous generator needs traces of at least 2 samples (their sample time)")
    v = np.stack([generator.absolute_inputs(tr) for tr in traces])
    ok = np.isfinite(v).all(axis=2)
    if not ok.all():
        i, k = (int(a[0]) for a in np.nonzero(~ok))
        raise DataError(f"traces[{i}] has an invalid sample at t={traces[i].t[k]:g} s ({int((~ok).sum())} in all "
                        "the traces); the batch path has no gap rule: run such traces with generator.run(trace)")
    return g, v


def run_generator_batch(generator: ResidualGenerator, data, x0=None, *, method: str = "numba",
                        return_state: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Residuals of a discrete residual generator over many runs at once.

    Equal to ``generator.run(trace).r`` for each run (to rounding) on clean data: the signals are absolute
    when the generator carries an operating point (its ``u0``, ``y0`` are subtracted, as ``run`` does).

    Parameters
    ----------
    generator : ResidualGenerator
        Discrete (``dt`` set); a continuous one is accepted only with traces (then ZOH-discretised at their
        sample time, as ``run`` does).
    data : (R, N, m + p) array_like or sequence of Trace
        The generator's input vectors ``[u; y]`` in the order of ``generator.signals`` (absolute values when
        it has an operating point), or traces of equal length and sample time holding those signals.
    x0 : (n,) or (R, n) array_like, optional
        Initial filter state of every run or of each run (zeros when omitted).
    method : {'numba', 'blas'}, default 'numba'
        As in :func:`dlsim_batch`.
    return_state : bool, default False
        Also return the filter state after the last sample of each run.

    Returns
    -------
    r : (R, N, q) ndarray
        Residuals, in the order of ``generator.residuals``.
    x_end : (R, n) ndarray
        Only with ``return_state``.

    Raises
    ------
    ParameterError
        If ``generator`` is not a ResidualGenerator, is continuous with an array, or ``x0``/``method`` is bad.
    DataError
        For an array of the wrong shape, traces of different lengths or sample times (or another sample time
        than the generator's), missing signals, or invalid (NaN/flagged) samples: the batch has no gap rule.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> y = [0.0, 1.0, 1.9, 3.71, 4.439, 5.0951]
    >>> v = np.stack([np.c_[np.ones(6), y], np.c_[np.ones(6), np.zeros(6)]])
    >>> np.round(run_generator_batch(g, v)[..., 0], 6).tolist()
    [[0.0, 0.0, 0.0, 1.0, 0.5, 0.3], [0.0, -1.0, -1.4, -1.56, -1.624, -1.6496]]
    """
    if not isinstance(generator, ResidualGenerator):
        raise ParameterError(f"generator must be a fdikit.residuals.ResidualGenerator, got {type(generator).__name__}")
    g, nv = generator, len(generator.signals)
    if isinstance(data, Sequence) and not isinstance(data, str | bytes) and data and isinstance(data[0], Trace):
        g, v = _stack(generator, data)
    elif g.dt is None:
        raise ParameterError("the generator is continuous (dt=None): discretise it first with "
                             "generator.discretize(dt), or pass traces (their sample time is used)")
    elif (v := _runs_array("data", data, 3, f"(runs, samples, {nv} signals {list(g.signals)})")).shape[2] != nv:
        raise DataError(f"data has {v.shape[2]} signals (last axis, shape {v.shape}); the generator reads {nv}: "
                        f"{list(g.signals)} (controls then outputs)")
    r, x_end = _simulate(g.A, g.B, g.C, g.D, v, x0, g.offset, method)
    return (r, x_end) if return_state else r


@dataclass(frozen=True)
class BatchDecision:
    """Decisions of an evaluator over a batch of runs, with the normalised decision statistic.

    Attributes
    ----------
    alarm : (R, N) bool ndarray
        Any residual fired.
    fired : (R, N, q) bool ndarray
        The decision of each residual.
    statistic : (R, N) ndarray
        The normalised statistic: ``statistic > λ`` is the crossing of the nominal threshold scaled by ``λ``
        (``> 1``: the nominal one); see :func:`threshold_batch` and :func:`cusum_batch` for its definition.
    names : tuple of str or None
        Residual names of the evaluator's fit (None when it was not fitted on named residuals).

    Examples
    --------
    >>> import numpy as np
    >>> d = BatchDecision(np.zeros((1, 2), bool), np.zeros((1, 2, 1), bool), np.zeros((1, 2)), ("r",))
    >>> d.statistic.shape
    (1, 2)
    """

    alarm: np.ndarray
    fired: np.ndarray
    statistic: np.ndarray
    names: tuple[str, ...] | None = None


def _residuals(r, names, what: str) -> np.ndarray:
    r = _runs_array("r (the residuals)", r, 3, "(runs, samples, residuals)")
    if names is not None and r.shape[2] != len(names):
        raise DataError(f"r has {r.shape[2]} residuals (last axis) but {what} was fitted on {len(names)}: "
                        f"{list(names)}")
    bad = ~np.isfinite(r)
    if bad.any():
        i, k, j = (int(a[0]) for a in np.nonzero(bad))
        raise DataError(f"r has a non-finite value at run {i}, sample {k}, residual {j} ({int(bad.sum())} in all): "
                        "the batch evaluators take every sample as valid; fill or cut invalid samples, or run "
                        "evaluator.run(Residuals(...)) per run, which holds its decisions over them")
    return r


def _per_residual(name: str, value, q: int, default: float) -> np.ndarray:
    if value is None:
        return np.full(q, float(default))
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if arr.size not in (1, q):
        raise DataError(f"{arr.size} {name} values for {q} residuals")
    return np.array(np.broadcast_to(arr, (q,)))


def threshold_batch(evaluator, r) -> BatchDecision:
    """A fitted threshold evaluator's decisions on a batch of residuals, with its normalised statistic.

    Residual ``i`` fires at sample ``k`` when at least ``k_p`` of its last ``n_p`` values of
    ``a_i = |r_i − c_i| / τ_i`` exceed 1 (persistence ``(k_p, n_p)``; the first samples use the shorter window
    they have).  The statistic is ``max_i`` of the ``k_p``-th largest of those ``n_p`` values (0 while fewer
    than ``k_p`` samples exist), so ``statistic > 1`` is exactly ``alarm``, and ``statistic > λ`` is the alarm
    of the thresholds ``λ τ`` (to the rounding of ``λ τ``).  Equal to ``evaluator.run`` per run.

    Parameters
    ----------
    evaluator : ThresholdEvaluator
        With thresholds (given or from ``fit``).
    r : (R, N, q) array_like
        Residuals, all samples valid (finite).

    Returns
    -------
    BatchDecision
        ``alarm``, ``fired``, ``statistic`` and the fitted residual names.

    Raises
    ------
    ParameterError
        If ``evaluator`` is not a ThresholdEvaluator or has no thresholds.
    DataError
        If ``r`` is not 3-D, has another number of residuals than the fit or the thresholds, or holds a
        NaN/inf (the batch takes every sample as valid; ``run`` per run holds its decisions over invalid ones).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision import ThresholdEvaluator
    >>> ev = ThresholdEvaluator(thresholds=[2.0], persistence=(2, 3))
    >>> d = threshold_batch(ev, np.array([[[3.0], [0.0], [5.0], [1.0], [1.0]]]))
    >>> d.statistic.tolist(), d.alarm.tolist()
    ([[0.0, 0.0, 1.5, 0.5, 0.5]], [[False, False, True, False, False]])
    """
    from fdikit.decision.threshold import ThresholdEvaluator

    if not isinstance(evaluator, ThresholdEvaluator):
        raise ParameterError(f"evaluator must be a ThresholdEvaluator, got {type(evaluator).__name__}")
    if evaluator.thresholds is None:
        raise ParameterError("the evaluator has no thresholds; pass thresholds= or call fit() on fault-free residuals")
    r = _residuals(r, evaluator.names, "the threshold evaluator")
    R, N, q = r.shape
    tau, c = _per_residual("thresholds", evaluator.thresholds, q, 1.0), _per_residual("center", evaluator.center, q, 0)
    kp, n_p = evaluator.persistence
    fired, stat, alarm = np.empty((R, N, q), bool), np.empty((R, N)), np.empty((R, N), bool)
    _kernels()[1](r, c, tau, kp, n_p, fired, stat, alarm)
    return BatchDecision(alarm, fired, stat, evaluator.names)


def cusum_batch(evaluator, r) -> BatchDecision:
    """A CUSUM evaluator's decisions on a batch of residuals, with its normalised statistic.

    The statistic is that of the non-resetting recursion (``restart='none'``): with ``s = (r − μ0)/σ``,
    ``g⁺_i``, ``g⁻_i`` are the Page statistics of ``s_i − ν_i`` and ``−s_i − ν_i`` (the evaluator's arithmetic,
    bit for bit: running sum minus running minimum, rebased every 4096 samples), and
    ``statistic = max_i max(g⁺_i, g⁻_i) / h_i`` (``g⁻`` is 0 one-sided).  ``statistic > 1`` is exactly a
    crossing of some residual, ``statistic > λ`` a crossing of the thresholds ``λ h``.  ``fired`` is the
    crossing held for ``hold`` samples, ``alarm`` any fired residual: equal to the evaluator's ``run`` for
    ``restart='none'``.  For ``restart='reset'`` (the default) both recursions agree up to the first crossing,
    so the first alarm of each run is exact (first sample with ``statistic > 1``); after it the evaluator
    restarts and re-alarms, while ``alarm``/``fired`` here keep the non-resetting decisions.

    Parameters
    ----------
    evaluator : CusumEvaluator
        With drift and threshold (given or from ``fit``).
    r : (R, N, q) array_like
        Residuals, all samples valid (finite).

    Returns
    -------
    BatchDecision
        ``alarm``, ``fired``, ``statistic`` and the fitted residual names.

    Raises
    ------
    ParameterError
        If ``evaluator`` is not a CusumEvaluator or has no drift/threshold.
    DataError
        If ``r`` is not 3-D, has another number of residuals than the fit or the parameters, or holds a NaN/inf.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision import CusumEvaluator
    >>> ev = CusumEvaluator(drift=0.5, threshold=2.0, two_sided=False)
    >>> d = cusum_batch(ev, np.array([[[1.5], [1.5], [1.5], [-3.0]]]))
    >>> d.statistic.tolist(), d.alarm.tolist()
    ([[0.5, 1.0, 1.5, 0.0]], [[False, False, True, False]])
    """
    from fdikit.decision.cusum import CusumEvaluator

    if not isinstance(evaluator, CusumEvaluator):
        raise ParameterError(f"evaluator must be a CusumEvaluator, got {type(evaluator).__name__}")
    if evaluator.drift is None or evaluator.threshold is None:
        raise ParameterError("the CUSUM has no drift/threshold; pass drift= and threshold= or call "
                             "fit(fault_free, arl0=..., shift=...)")
    r = _residuals(r, evaluator.names, "the CUSUM")
    R, N, q = r.shape
    nu, h = (_per_residual(nm, getattr(evaluator, nm), q, 1.0) for nm in ("drift", "threshold"))
    mu, sd = _per_residual("mean", evaluator.mean, q, 0.0), _per_residual("sigma", evaluator.sigma, q, 1.0)
    fired, stat, alarm = np.empty((R, N, q), bool), np.empty((R, N)), np.empty((R, N), bool)
    _kernels()[2](r, mu, sd, nu, h, evaluator.two_sided, evaluator.hold, fired, stat, alarm)
    return BatchDecision(alarm, fired, stat, evaluator.names)


@dataclass(frozen=True)
class LevelCrossings:
    """First-crossing delays and false-alarm up-crossings of a batch statistic at several levels.

    Attributes
    ----------
    levels : (L,) ndarray
        The levels (scale factors of the nominal threshold), increasing.
    delay : (R, L) ndarray
        Time from the onset to the first sample at or after it with ``statistic > level``; NaN when it never
        crosses, or for a fault-free run.
    upcrossings : (R, L) int ndarray
        Up-crossings of each level at fault-free samples (false alarms).

    Examples
    --------
    >>> import numpy as np
    >>> c = LevelCrossings(np.array([1.0]), np.array([[0.5]]), np.array([[0]]))
    >>> c.delay.shape
    (1, 1)
    """

    levels: np.ndarray
    delay: np.ndarray
    upcrossings: np.ndarray


def crossings(statistic, t, onset, healthy=None, levels=1.0) -> LevelCrossings:
    """Detection delays and false-alarm counts of a batch statistic at many threshold levels at once.

    For each run and level ``λ``: the delay is ``t[k] − onset`` for the first sample ``k`` with
    ``t[k] ≥ onset`` and ``statistic[k] > λ`` (NaN when none, or for a fault-free run); an up-crossing is a
    sample ``k`` with ``statistic[k] > λ`` and (``k = 0`` or ``statistic[k−1] ≤ λ``), counted when ``k`` is
    fault-free.  One pass over the samples for all levels (each sample's level index by binary search, counts
    by histograms).

    Parameters
    ----------
    statistic : (R, N) array_like
        A normalised decision statistic (:class:`BatchDecision`), finite.
    t : (N,) array_like
        Sample times, increasing.
    onset : (R,) array_like
        Fault onset time of each run (in the units of ``t``); NaN or None for a fault-free run.
    healthy : (R, N) bool array_like, optional
        The fault-free samples whose up-crossings count; default the samples before the onset (every sample of
        a fault-free run).
    levels : float or (L,) array_like, default 1.0
        Scale factors of the nominal threshold, strictly increasing.

    Returns
    -------
    LevelCrossings
        ``levels``, ``delay`` (R, L) and ``upcrossings`` (R, L).

    Raises
    ------
    DataError
        If ``statistic`` is not 2-D and finite, ``t`` is not increasing with one time per sample, or ``onset`` /
        ``healthy`` do not match the runs.
    ParameterError
        If ``levels`` is empty, not finite or not strictly increasing.

    Examples
    --------
    >>> import numpy as np
    >>> stat = np.array([[0.5, 1.5, 0.5, 0.2, 2.5, 3.0], [0.1, 1.2, 0.3, 1.4, 0.2, 0.1]])
    >>> c = crossings(stat, np.arange(6.0), [3.0, None], levels=[1.0, 2.0])
    >>> c.delay.tolist(), c.upcrossings.tolist()
    ([[1.0, 1.0], [nan, nan]], [[1, 0], [2, 0]])
    """
    stat = _runs_array("statistic", statistic, 2, "(runs, samples)")
    if not np.isfinite(stat).all():
        raise DataError("statistic has non-finite values; crossings needs a finite statistic at every sample")
    R, N = stat.shape
    t = _runs_array("t", t, 1, f"({N},) sample times")
    if t.shape != (N,) or not (np.isfinite(t).all() and np.all(np.diff(t) > 0)):
        raise DataError(f"t must be {N} finite, increasing sample times (one per sample), got shape {t.shape}")
    on = np.array([np.nan if o is None else o for o in np.atleast_1d(np.asarray(onset, dtype=object))], float)
    if on.shape != (R,):
        raise DataError(f"onset must give one time per run ({R}; NaN or None when fault-free), got shape {on.shape}")
    lv = validate.as_array("levels", levels).ravel()
    if lv.size == 0 or np.any(np.diff(lv) <= 0):
        raise ParameterError(f"levels must be one or more strictly increasing numbers, got {lv.tolist()}")
    L = lv.size
    k0 = np.where(np.isnan(on), N, np.searchsorted(t, np.where(np.isnan(on), np.inf, on), side="left"))
    after = np.arange(N) >= k0[:, None]
    ok = ~after if healthy is None else np.asarray(healthy, dtype=bool)
    if ok.shape != (R, N):
        raise DataError(f"healthy must be an (R, N) = ({R}, {N}) boolean mask, got shape {ok.shape}")
    c = np.searchsorted(lv, stat, side="left")  # level j is exceeded exactly when j < c (λ_j < statistic)
    prev = np.concatenate([np.zeros_like(c[:, :1]), c[:, :-1]], axis=1)
    rows = np.arange(R)[:, None] * (L + 1)
    up = ok & (c > prev)  # levels prev ≤ j < c are crossed upwards at this sample
    diff = np.bincount((rows + prev)[up], minlength=R * (L + 1)) - np.bincount((rows + c)[up], minlength=R * (L + 1))
    upcrossings = np.cumsum(diff.reshape(R, L + 1), axis=1)[:, :L]
    run_max = np.maximum.accumulate(np.where(after, c, 0), axis=1)  # levels crossed since the onset
    hist = np.bincount((rows + run_max)[after], minlength=R * (L + 1)).reshape(R, L + 1)
    first = k0[:, None] + np.cumsum(hist, axis=1)[:, :L]  # k0 + #(samples after the onset below level j)
    delay, hit = np.full((R, L), np.nan), first < N
    delay[hit] = t[first[hit]] - np.broadcast_to(on[:, None], (R, L))[hit]
    return LevelCrossings(lv, delay, upcrossings.astype(np.int64))
