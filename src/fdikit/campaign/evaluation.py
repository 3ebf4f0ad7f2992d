"""Evaluators of a residual campaign: their kinds, calibration, and the rows of a batch of runs.

Shared by the studies whose designs are residual generators (:mod:`fdikit.studies.path1996.campaign`,
:mod:`fdikit.studies.path1996.nonlinear_campaign`, a user's own): every design's residuals go through every
evaluator; each run is scored by :func:`fdikit.metrics.score` on the evaluator's own :meth:`run` (the reference
semantics: persistence, isolation, restarts).

Evaluator kinds and their ``params``.  Every kind but ``gaussian-ml`` and ``bnn`` is calibrated on the study's
fault-free calibration run: ``calibration`` seconds of it (default 600) after its first ``drop`` seconds (default
10; the PATH nonlinear table drops 2).  The kinds after ``cusum`` are those of ``fdikit compare-evaluators``
(Douglas et al. 1996, Ch. 6–7), fitted by :func:`fdikit.studies.path1996.compare.fit_comparison_evaluator` with
that comparison's parameters as defaults, and ``mhsprt-whitened`` is the nonlinear table's
(:func:`fdikit.studies.path1996.nonlinear_table.whitened_mhsprt`).

``threshold``
    :class:`~fdikit.decision.ThresholdEvaluator` with the bank's isolation logic (``groups``);
    ``false_alarms_per_hour`` (default 1), ``persistence`` ``[k, n]`` (default ``[5, 10]``, the PATH
    comparison's).
``cusum``
    :class:`~fdikit.decision.CusumEvaluator` (two-sided, reset after an alarm, bank isolation);
    ``mean_time_between_false_alarms`` [s] (default 3600), ``shift`` — the design shift in fault-free
    standard deviations of each residual (default 4).
``glr``
    :class:`~fdikit.decision.GlrEvaluator`, one vector test per (filter, fault) residual group;
    ``false_alarms_per_hour`` (default 1), ``window`` [samples] (default 50).
``sprt``
    :class:`~fdikit.decision.SprtEvaluator` (Wald, restarted) per residual group; ``shift`` (default 4
    fault-free standard deviations), ``alpha`` (default 1e-6), ``beta`` (default 1e-3).
``cusum-whitened``, ``glr-whitened``, ``sprt-whitened``
    The same on AR-prewhitened residuals (:class:`~fdikit.decision.Whitened`), with ``order`` (default 5); the
    shifts in standard deviations of the innovations.
``mhsprt``
    :class:`~fdikit.decision.mhsprt.MhsprtEvaluator` with a density per hypothesis: fault-free from the
    calibration run, each fault's from its labelled training run after ``onset + 1`` s; ``regularization``
    (default 1e-6).
``mhsprt-whitened``
    The MHSSPRT on AR(5)-prewhitened residuals with mean-shift hypotheses, ``F_T`` set on the calibration run
    (training runs with the fault from 2 s, as the nonlinear table's).
``gaussian-ml``, ``bnn``
    :class:`~fdikit.decision.learned.gaussian_ml.GaussianMlEvaluator` and
    :class:`~fdikit.decision.learned.bnn.BnnEvaluator` trained on every labelled training run (fault-free
    ones included); no parameters.

Which training runs there are is the study's choice (its module docstring); :data:`TRAINED` lists the kinds that
need them.

Sweep columns: ``threshold`` and ``cusum`` from the batched statistics of :mod:`fdikit.batch` (``statistic > λ``
alarms exactly where the evaluator with its threshold scaled by λ would; for CUSUM up to the first alarm of a
run, :func:`fdikit.batch.cusum_batch`), ``cusum-whitened`` the same on the innovations; ``glr`` and
``glr-whitened`` from the GLR's own statistic (``Diagnosis.meta['statistic']`` divided by each block's threshold,
the largest block: the GLR has neither persistence nor restarts, so this is exact).  The SPRT's log-likelihood
ratio restarts at its thresholds, the MHSSPRT's posterior and the classifiers' decisions have no threshold to
scale: ``sprt``, ``sprt-whitened``, ``mhsprt``, ``mhsprt-whitened``, ``gaussian-ml`` and ``bnn`` rows have NaN
sweep delays and zero sweep false alarms — their trade-off curve in the report is flat (their detection columns
are filled as for every evaluator).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from fdikit.errors import ParameterError

__all__ = ["EVALUATOR_KINDS", "TRAINED", "check_evaluators", "calibration_seconds", "needs_training",
           "fit_evaluator", "evaluate_runs"]

_CAL = {"calibration": 600.0, "drop": 10.0}
#: Evaluator kind → its parameters and their defaults.
EVALUATOR_KINDS = {
    "threshold": {"false_alarms_per_hour": 1.0, "persistence": [5, 10], **_CAL},
    "cusum": {"mean_time_between_false_alarms": 3600.0, "shift": 4.0, **_CAL},
    "glr": {"false_alarms_per_hour": 1.0, "window": 50, **_CAL},
    "sprt": {"shift": 4.0, "alpha": 1e-6, "beta": 1e-3, **_CAL},
    "cusum-whitened": {"mean_time_between_false_alarms": 3600.0, "shift": 4.0, "order": 5, **_CAL},
    "glr-whitened": {"false_alarms_per_hour": 1.0, "window": 50, "order": 5, **_CAL},
    "sprt-whitened": {"shift": 4.0, "alpha": 1e-6, "beta": 1e-3, "order": 5, **_CAL},
    "mhsprt": {"regularization": 1e-6, **_CAL},
    "mhsprt-whitened": {**_CAL},
    "gaussian-ml": {},
    "bnn": {},
}
#: The kinds trained on labelled runs.
TRAINED = ("mhsprt", "mhsprt-whitened", "gaussian-ml", "bnn")
_DROP = 10.0
_POSITIVE = ("false_alarms_per_hour", "mean_time_between_false_alarms", "shift", "calibration", "regularization")
_COUNTS = {"window": 1, "order": 1}


def _params(named) -> dict:
    return {**EVALUATOR_KINDS[named.kind or named.name], **named.params}


def check_evaluators(evaluators, kinds: Sequence[str] | None = None, study: str = "the study") -> list[str]:
    """Problems with a spec's ``evaluators`` entries (unknown kinds or parameters, bad values).

    Parameters
    ----------
    evaluators : list of Named
    kinds : sequence of str, optional
        The kinds the study supports (default every kind of :data:`EVALUATOR_KINDS`).
    study : str
        How messages name the study.

    Returns
    -------
    list of str
        ``"evaluators.<i>.<entry>: <what is wrong>"``, empty when all is well.

    Examples
    --------
    >>> from fdikit.campaign.spec import Named
    >>> for p in check_evaluators([Named(name="t", kind="glr", params={"windw": 30})]):
    ...     print(p)
    evaluators.0.params.windw: unknown parameter; glr takes: false_alarms_per_hour, window, calibration, drop
    >>> for p in check_evaluators([Named(name="g", kind="glr", params={"window": 0})]):
    ...     print(p)
    evaluators.0.params.window: must be an integer >= 1, got 0
    """
    problems = []
    allowed = tuple(EVALUATOR_KINDS) if kinds is None else tuple(kinds)
    for k, named in enumerate(evaluators):
        kind = named.kind or named.name
        if kind not in EVALUATOR_KINDS:
            problems.append(f"evaluators.{k}.kind: unknown evaluator {kind!r}; choose from: {', '.join(allowed)}")
            continue
        if kind not in allowed:
            problems.append(f"evaluators.{k}.kind: {study} has no evaluator {kind!r} (its training runs do not "
                            f"fit it); choose from: {', '.join(allowed)}")
            continue
        known = EVALUATOR_KINDS[kind]
        for p in named.params:
            if p not in known:
                problems.append(f"evaluators.{k}.params.{p}: unknown parameter; {kind} takes: "
                                f"{', '.join(known) or 'none'}")
        p = _params(named)
        if any(p not in known for p in named.params):
            continue
        for name in _POSITIVE:
            if name in p and not _number(p[name], 0.0):
                problems.append(f"evaluators.{k}.params.{name}: must be a positive number, got {p[name]!r}")
        for name in ("alpha", "beta"):
            if name in p and not (_number(p[name], 0.0) and p[name] < 0.5):
                problems.append(f"evaluators.{k}.params.{name}: must be a probability in (0, 0.5), got {p[name]!r}")
        for name, low in _COUNTS.items():
            if name in p and not (isinstance(p[name], int) and not isinstance(p[name], bool) and p[name] >= low):
                problems.append(f"evaluators.{k}.params.{name}: must be an integer >= {low}, got {p[name]!r}")
        if "drop" in p and not (_number(p["drop"], -1.0) and p["drop"] >= 0):
            problems.append(f"evaluators.{k}.params.drop: must be a number of seconds >= 0, got {p['drop']!r}")
        elif "calibration" in p and _number(p["calibration"], 0.0) and p["calibration"] <= max(2 * p["drop"], 20.0):
            problems.append(f"evaluators.{k}.params.calibration: {p['calibration']} s leaves too little "
                            f"fault-free data after the first {p['drop']:g} s are dropped; give at least "
                            f"{max(3 * p['drop'], 30.0):g} s")
        if "persistence" in p:
            kn = p["persistence"]
            if not (isinstance(kn, list | tuple) and len(kn) == 2 and all(isinstance(v, int) for v in kn)
                    and 1 <= kn[0] <= kn[1]):
                problems.append(f"evaluators.{k}.params.persistence: must be [k, n] with 1 <= k <= n, got {kn!r}")
    return problems


def _number(x, above: float) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and bool(np.isfinite(x)) and x > above


def needs_training(evaluators) -> bool:
    """Whether some evaluator is trained on labelled runs (a kind of :data:`TRAINED`).

    Parameters
    ----------
    evaluators : list of Named

    Returns
    -------
    bool

    Examples
    --------
    >>> from fdikit.campaign.spec import Named
    >>> needs_training([Named(name="threshold")]), needs_training([Named(name="m", kind="mhsprt")])
    (False, True)
    """
    return any((e.kind or e.name) in TRAINED for e in evaluators)


def calibration_seconds(evaluators) -> float:
    """The longest fault-free calibration run the evaluators ask for [s] (600 when none asks: learned ones only).

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
    return float(max((_params(e)["calibration"] for e in evaluators if "calibration" in _params(e)), default=600.0))


def fit_evaluator(named, healthy, groups: Sequence[str] | None, labelled: Sequence[tuple] | None = None,
                  onset: float | None = None):
    """Calibrate (or train) one evaluator of the spec.

    Parameters
    ----------
    named : Named
        The spec's evaluator entry (checked by :func:`check_evaluators`).
    healthy : Residuals
        Fault-free residuals of the design; the first ``drop`` seconds and everything after the evaluator's
        ``calibration`` seconds are left out.
    groups : sequence of str, optional
        The filter of each residual (bank isolation logic).
    labelled : sequence of (Trace, Residuals), optional
        The study's labelled training runs (kinds of :data:`TRAINED`); a faulty run's fault is its trace's last
        label, fault-free runs are labelled ``'none'``.
    onset : float, optional
        The fault onset of the labelled runs [s] (``mhsprt``: the fault densities are fitted after
        ``onset + 1`` s; ``mhsprt-whitened`` needs 2 s).

    Returns
    -------
    object
        The fitted evaluator (``run(residuals) -> Diagnosis``).

    Raises
    ------
    ParameterError
        When a trained kind gets no labelled runs or onset, or ``mhsprt-whitened`` an onset other than 2 s.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.campaign.spec import Named
    >>> from fdikit.residuals import Residuals
    >>> t = np.arange(6000) * 0.01
    >>> res = Residuals(t, np.random.default_rng(0).standard_normal((6000, 1)), ("r",), ("f",))
    >>> ev = fit_evaluator(Named(name="g", kind="glr", params={"calibration": 60.0}), res, None)
    >>> type(ev).__name__, ev.window
    ('GlrEvaluator', 50)
    """
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator

    kind = named.kind or named.name
    p = _params(named)
    if kind in TRAINED and (labelled is None or onset is None):
        raise ParameterError(f"evaluator {named.name!r} ({kind}) is trained on labelled runs; pass labelled= and "
                             "onset= (the study's training runs)")
    data = healthy.slice(start=float(p["drop"]), stop=float(p["calibration"])) if "calibration" in p else healthy
    if kind == "threshold":
        return ThresholdEvaluator(groups=groups, persistence=tuple(p["persistence"])).fit(
            data, false_alarms_per_hour=float(p["false_alarms_per_hour"]))
    if kind == "cusum":
        shift = float(p["shift"]) * data.r.std(axis=0, ddof=1)
        return CusumEvaluator(groups=groups).fit(
            data, mean_time_between_false_alarms=float(p["mean_time_between_false_alarms"]), shift=shift)
    if kind == "mhsprt-whitened":
        from fdikit.studies.path1996.nonlinear_table import whitened_mhsprt

        if float(onset) != 2.0:
            raise ParameterError(f"evaluator {named.name!r} (mhsprt-whitened) fits its fault means after 3 s of "
                                 f"training runs with the fault from 2 s; this study's start at {onset} s: use mhsprt")
        return whitened_mhsprt(data, [(str(tr.fault[-1]), res) for tr, res in labelled if str(tr.fault[-1]) != "none"])
    from fdikit.studies.path1996.compare import fit_comparison_evaluator

    kwargs = {k: v for k, v in p.items() if k not in ("calibration", "drop", "persistence")}
    return fit_comparison_evaluator(kind, data, groups, labelled, onset=5.0 if onset is None else float(onset),
                                    **kwargs)


def _sweep_statistic(ev, r: np.ndarray, series: list, diagnoses: list) -> np.ndarray | None:
    """The normalised batch statistic of an evaluator (module docstring), or None when it has none."""
    from fdikit.batch import cusum_batch, threshold_batch
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator, Whitened

    if isinstance(ev, ThresholdEvaluator):
        return threshold_batch(ev, r).statistic
    if isinstance(ev, CusumEvaluator):
        return cusum_batch(ev, r).statistic
    if isinstance(ev, Whitened) and isinstance(ev.evaluator, CusumEvaluator):
        return cusum_batch(ev.evaluator, np.stack([ev.whiten(res).r for res in series])).statistic
    if all(d.meta.get("evaluator") == "glr" for d in diagnoses):  # GlrEvaluator, bare or whitened
        return np.stack([(d.meta["statistic"] / np.asarray(d.meta["threshold"])).max(axis=1) for d in diagnoses])
    return None


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
        Rows of :data:`fdikit.campaign.schema.SCHEMA` (sweep columns as the module docstring says).

    Examples
    --------
    One faulty run (a step of 5 in a unit-variance residual at 5 s) and a fixed threshold of 3:

    >>> import numpy as np
    >>> from fdikit.campaign.plan import RunPlan
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.trace import Trace
    >>> t = np.arange(1000) * 0.01
    >>> r = np.random.default_rng(0).standard_normal((1, 1000, 1)); r[0, 500:, 0] += 5.0
    >>> trace = Trace(t, np.zeros((1000, 0)), np.zeros((1000, 1)), (), ("y",),
    ...               fault=np.where(t >= 5.0, "y_sensor", "none"))
    >>> plan = RunPlan(0, 0, "p", "y_sensor", "bias", 5.0, 5.0, 1)
    >>> ev = ThresholdEvaluator(thresholds=3.0, isolates=("y_sensor",))
    >>> (row,) = evaluate_runs([plan], [trace], {"d": r}, {"d": ("r",)}, {"d": ("y_sensor",)},
    ...                        {("d", "threshold"): ev}, levels=[1.0, 2.0])
    >>> row["detected"], row["isolated"], row["sweep_delay"][0] == row["detection_delay"]
    (True, 'y_sensor', True)
    """
    from fdikit.batch import crossings
    from fdikit.campaign.rows import score_row
    from fdikit.metrics import score
    from fdikit.residuals import Residuals

    t = traces[0].t
    # the onset as fdikit.metrics.score takes it: the time of the first faulty sample
    onsets = np.array([t[np.argmax(tr.fault != "none")] if (tr.fault != "none").any() else np.nan for tr in traces])
    out: dict[tuple, list] = {}
    for (design, ev_name), ev in evaluators.items():
        r = residuals[design]
        series = [Residuals(t, r[i], names[design], isolates[design]) for i in range(len(runs))]
        diagnoses = [ev.run(res) for res in series]
        stat = _sweep_statistic(ev, r, series, diagnoses)
        if stat is None:
            delays, fas = np.full((len(runs), len(levels)), np.nan), np.zeros((len(runs), len(levels)), int)
        else:
            cross = crossings(stat, t, onsets, levels=levels)
            delays, fas = cross.delay, cross.upcrossings
        for i, (plan, trace) in enumerate(zip(runs, traces)):
            out[(plan.run, design, ev_name)] = [plan, design, ev_name, score(trace, diagnoses[i]), delays[i], fas[i]]
    return [score_row(*out[k]) for k in sorted(out, key=lambda k: (k[0],))]
