"""Evaluators of a residual campaign: their kinds, calibration, and the rows of a batch of runs.

Shared by the studies whose designs are residual generators (:mod:`fdikit.studies.path1996.campaign`, a
user's own): every design's residuals go through every evaluator; each run is scored by
:func:`fdikit.metrics.score` on the evaluator's own :meth:`run` (the reference semantics: persistence,
isolation, restarts), and the sweep columns come from the batched decision statistic
(:mod:`fdikit.batch`: ``statistic > λ`` alarms exactly where the evaluator with its threshold scaled by λ
would, :func:`fdikit.batch.crossings`).

Evaluator kinds and their ``params``:

``threshold``
    :class:`~fdikit.decision.ThresholdEvaluator` with the bank's isolation logic (``groups``);
    ``false_alarms_per_hour`` (default 1), ``persistence`` ``[k, n]`` (default ``[5, 10]``, the PATH
    comparison's), ``calibration`` seconds of fault-free data (default 600; the first 10 s are dropped).
``cusum``
    :class:`~fdikit.decision.CusumEvaluator` (two-sided, reset after an alarm, bank isolation);
    ``mean_time_between_false_alarms`` [s] (default 3600), ``shift`` — the design shift in fault-free
    standard deviations of each residual (default 4), ``calibration`` as above.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["EVALUATOR_KINDS", "check_evaluators", "calibration_seconds", "fit_evaluator", "evaluate_runs"]

#: Evaluator kind → its parameters and their defaults.
EVALUATOR_KINDS = {
    "threshold": {"false_alarms_per_hour": 1.0, "persistence": [5, 10], "calibration": 600.0},
    "cusum": {"mean_time_between_false_alarms": 3600.0, "shift": 4.0, "calibration": 600.0},
}
_DROP = 10.0


def _params(named) -> dict:
    return {**EVALUATOR_KINDS[named.kind or named.name], **named.params}


def check_evaluators(evaluators) -> list[str]:
    """Problems with a spec's ``evaluators`` entries (unknown kinds or parameters, bad values).

    Parameters
    ----------
    evaluators : list of Named

    Returns
    -------
    list of str
        ``"evaluators.<i>.<entry>: <what is wrong>"``, empty when all is well.

    Examples
    --------
    >>> from fdikit.campaign.spec import Named
    >>> for p in check_evaluators([Named(name="t", kind="threshold", params={"persistance": [5, 10]})]):
    ...     print(p)
    evaluators.0.params.persistance: unknown parameter; threshold takes: false_alarms_per_hour, persistence, calibration
    """
    problems = []
    for k, named in enumerate(evaluators):
        kind = named.kind or named.name
        if kind not in EVALUATOR_KINDS:
            problems.append(f"evaluators.{k}.kind: unknown evaluator {kind!r}; "
                            f"choose from: {', '.join(EVALUATOR_KINDS)}")
            continue
        known = EVALUATOR_KINDS[kind]
        for p in named.params:
            if p not in known:
                problems.append(f"evaluators.{k}.params.{p}: unknown parameter; {kind} takes: {', '.join(known)}")
        p = _params(named)
        if any(p not in known for p in named.params):
            continue
        for name in ("false_alarms_per_hour", "mean_time_between_false_alarms", "shift", "calibration"):
            if name in p and not (isinstance(p[name], int | float) and not isinstance(p[name], bool) and p[name] > 0):
                problems.append(f"evaluators.{k}.params.{name}: must be a positive number, got {p[name]!r}")
        if "calibration" in p and isinstance(p["calibration"], int | float) and p["calibration"] <= 2 * _DROP:
            problems.append(f"evaluators.{k}.params.calibration: {p['calibration']} s leaves too little "
                            f"fault-free data after the first {_DROP:g} s are dropped; give at least {3 * _DROP:g} s")
        if "persistence" in p:
            kn = p["persistence"]
            if not (isinstance(kn, list | tuple) and len(kn) == 2 and all(isinstance(v, int) for v in kn)
                    and 1 <= kn[0] <= kn[1]):
                problems.append(f"evaluators.{k}.params.persistence: must be [k, n] with 1 <= k <= n, got {kn!r}")
    return problems


def calibration_seconds(evaluators) -> float:
    """The longest fault-free calibration run the evaluators ask for [s].

    Parameters
    ----------
    evaluators : list of Named

    Returns
    -------
    float

    Examples
    --------
    >>> from fdikit.campaign.spec import Named
    >>> calibration_seconds([Named(name="threshold"), Named(name="c", kind="cusum", params={"calibration": 900})])
    900.0
    """
    return float(max(_params(e)["calibration"] for e in evaluators))


def fit_evaluator(named, healthy, groups: Sequence[str] | None):
    """Calibrate one evaluator of the spec on fault-free residuals.

    Parameters
    ----------
    named : Named
        The spec's evaluator entry (checked by :func:`check_evaluators`).
    healthy : Residuals
        Fault-free residuals of the design; the first 10 s and everything after the evaluator's
        ``calibration`` seconds are left out.
    groups : sequence of str, optional
        The filter of each residual (bank isolation logic).

    Returns
    -------
    ThresholdEvaluator or CusumEvaluator
        Fitted.
    """
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator

    p = _params(named)
    data = healthy.slice(start=_DROP, stop=float(p["calibration"]))
    if (named.kind or named.name) == "threshold":
        return ThresholdEvaluator(groups=groups, persistence=tuple(p["persistence"])).fit(
            data, false_alarms_per_hour=float(p["false_alarms_per_hour"]))
    shift = float(p["shift"]) * data.r.std(axis=0, ddof=1)
    return CusumEvaluator(groups=groups).fit(
        data, mean_time_between_false_alarms=float(p["mean_time_between_false_alarms"]), shift=shift)


def evaluate_runs(runs, traces, residuals: Mapping[str, np.ndarray], names: Mapping[str, tuple],
                  isolates: Mapping[str, tuple], evaluators: Mapping[tuple[str, str], object],
                  levels: Sequence[float]) -> list[dict]:
    """The result rows of a batch of runs of one plant: run × design × evaluator, in that order.

    Parameters
    ----------
    runs : sequence of RunPlan
        The runs (one plant), ``R`` of them.
    traces : sequence of Trace
        Their traces (same length and sample times).
    residuals : mapping of str to ndarray
        Design → residuals of all runs, ``(R, N, q)``.
    names, isolates : mapping of str to tuple
        Design → residual names, and the fault each residual is tied to.
    evaluators : mapping of (str, str) to evaluator
        (design, evaluator name) → the fitted evaluator, in the spec's evaluator order per design.
    levels : sequence of float
        The sweep levels.

    Returns
    -------
    list of dict
        Rows of :data:`fdikit.campaign.schema.SCHEMA`.
    """
    from fdikit.batch import crossings, cusum_batch, threshold_batch
    from fdikit.campaign.rows import score_row
    from fdikit.decision import ThresholdEvaluator
    from fdikit.metrics import score
    from fdikit.residuals import Residuals

    t = traces[0].t
    # the onset as fdikit.metrics.score takes it: the time of the first faulty sample
    onsets = np.array([t[np.argmax(tr.fault != "none")] if (tr.fault != "none").any() else np.nan for tr in traces])
    out: dict[tuple, list] = {}
    for (design, ev_name), ev in evaluators.items():
        r = residuals[design]
        stat = (threshold_batch if isinstance(ev, ThresholdEvaluator) else cusum_batch)(ev, r).statistic
        cross = crossings(stat, t, onsets, levels=levels)
        delays, fas = cross.delay, cross.upcrossings
        for i, (plan, trace) in enumerate(zip(runs, traces)):
            res = Residuals(t, r[i], names[design], isolates[design])
            s = score(trace, ev.run(res))
            out[(plan.run, design, ev_name)] = [plan, design, ev_name, s, delays[i], fas[i]]
    return [score_row(*out[k]) for k in sorted(out, key=lambda k: (k[0],))]
