"""Residual processors side by side on the PATH bank's residuals (``fdikit compare-evaluators``).

Training and test data come from separate seeds: a 10-minute fault-free run calibrates the
fault-free statistics (thresholds, CUSUM, GLR, SPRT); one labelled run per fault trains the
multiple-hypothesis SPRT (Douglas et al. 1996, Ch. 7), the Gaussian ML classifier (§6.2.1) and
the Bayesian neural network (Ch. 6); every evaluator is then scored on the same fresh runs
(:func:`fdikit.compare.compare_evaluators`).

With an output folder the comparison is resumable: each test run's scores are stored as soon as
the run is scored, and a rerun with the same arguments skips them (rules in :mod:`fdikit.resume`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

from fdikit.compare import Comparison, compare_evaluators, score_run, scores_csv_text, tabulate
from fdikit.errors import ParameterError
from fdikit.studies.path1996.bank import path_bank, path_fault_model, path_runs

__all__ = ["path_evaluator_comparison", "check_comparison_arguments", "fit_comparison_evaluator", "EVALUATORS"]

#: The evaluators of the comparison: command-line key → table name (the table's row order).
EVALUATORS = {
    "threshold": "threshold (5 of 10)",
    "cusum": "CUSUM",
    "glr": "GLR (M = 50)",
    "sprt": "SPRT",
    "cusum-whitened": "CUSUM, whitened",
    "glr-whitened": "GLR, whitened",
    "sprt-whitened": "SPRT, whitened",
    "mhsprt": "MHSSPRT",
    "gaussian-ml": "Gaussian ML",
    "bnn": "Bayesian NN",
}
_ONSET = 5.0


def check_comparison_arguments(runs_per_fault=2, healthy_runs=5, seed=0, bnn=True, noise_fraction=1e-4,
                               evaluators: Sequence[str] | None = None) -> dict:
    """Validate the arguments of :func:`path_evaluator_comparison` before any work; return them normalised.

    ``evaluators`` (keys of :data:`EVALUATORS`, or ``None`` for all) comes back as a list in table order
    (``'bnn'`` dropped when ``bnn`` is false).

    Parameters
    ----------
    runs_per_fault, healthy_runs : int, default 2, 5
        Test runs per fault and fault-free test runs (>= 0, not both 0).
    seed : int, default 0
        Seed, >= 0.
    bnn : bool, default True
        Include the Bayesian neural network.
    noise_fraction : float, default 1e-4
        Sensor noise as a fraction of the nominal fault sizes, > 0.
    evaluators : sequence of str, optional
        Keys of :data:`EVALUATORS`; ``None`` for all.

    Returns
    -------
    dict
        ``runs_per_fault``, ``healthy_runs``, ``seed``, ``noise_fraction`` and ``evaluators`` (list in table order).

    Raises
    ------
    ParameterError
        Naming the argument and what would be accepted.

    References
    ----------
    Douglas et al. 1996, Ch. 6–7 and §5.1.1 (the processors and the runs compared).

    Examples
    --------
    >>> check_comparison_arguments(evaluators=["cusum", "threshold"])["evaluators"]
    ['threshold', 'cusum']
    >>> check_comparison_arguments(bnn=False)["evaluators"][-1]
    'gaussian-ml'
    """
    from fdikit.resume import check_count, check_positive, check_seed, option_name

    args = {"runs_per_fault": check_count(runs_per_fault, "runs_per_fault", 0),
            "healthy_runs": check_count(healthy_runs, "healthy_runs", 0), "seed": check_seed(seed)}
    if args["runs_per_fault"] + args["healthy_runs"] == 0:
        raise ParameterError(f"no test runs: {option_name('runs_per_fault')} and {option_name('healthy_runs')} "
                             "are both 0; ask for at least one run (e.g. --healthy-runs 1)")
    if not isinstance(bnn, bool):
        raise ParameterError(f"{option_name('bnn')} must be True or False, got {bnn!r}")
    args["noise_fraction"] = check_positive(noise_fraction, "noise_fraction")
    known = ", ".join(EVALUATORS)
    if evaluators is None:
        chosen = [k for k in EVALUATORS if bnn or k != "bnn"]
    else:
        if isinstance(evaluators, str) or not all(isinstance(e, str) for e in evaluators):
            raise ParameterError(f"{option_name('evaluators')} must be a list of names from: {known}; "
                                 f"got {evaluators!r}")
        names = [e.strip().lower() for e in evaluators if e.strip()]
        if not names:
            raise ParameterError(f"{option_name('evaluators')} is empty; name at least one of: {known}")
        bad = [e for e in names if e not in EVALUATORS]
        if bad:
            raise ParameterError(f"{option_name('evaluators')}: unknown evaluator {bad[0]!r}; choose from: {known}")
        if "bnn" in names and not bnn:
            raise ParameterError(f"{option_name('evaluators')} names 'bnn' but bnn=False (--no-bnn) excludes it; "
                                 "drop one of the two")
        chosen = [k for k in EVALUATORS if k in names]
    args["evaluators"] = chosen
    return args


def path_evaluator_comparison(
    runs_per_fault: int = 2,
    healthy_runs: int = 5,
    seed: int = 0,
    out: str | Path | None = None,
    progress: bool = False,
    bnn: bool = True,
    noise_fraction: float = 1e-4,
    evaluators: Sequence[str] | None = None,
    fresh: bool = False,
) -> Comparison:
    """Fit every evaluator on training runs and score them on fresh PATH runs.

    Parameters
    ----------
    runs_per_fault, healthy_runs : int
        Test runs per fault (15 faults) and fault-free test runs (>= 0 each, not both 0).
    seed : int
        Seed (>= 0) of the training runs (``seed``, ``seed + 1``) and the test runs (``seed + 2``).
    out : str or PathLike, optional
        Folder for ``scores.csv`` and ``comparison.md``.  With ``out``, each test run's scores are
        stored atomically in ``out/parts-*/run-NNNNN.json`` as soon as the run is scored, and a rerun
        with the same arguments after a kill resumes (finished runs are reused; the evaluators are
        refitted, deterministically, only when some run is missing).  ``scores.csv`` and
        ``comparison.md`` are written atomically once every run is scored.  Rules:
        :mod:`fdikit.resume`.
    progress : bool
        Show rich progress bars.
    bnn : bool
        Include the Bayesian neural network (slowest to train).
    noise_fraction : float
        Sensor noise as a fraction of each sensor's nominal fault size (> 0).
    evaluators : sequence of str, optional
        Keys of :data:`EVALUATORS` to compare (default: all).
    fresh : bool
        Start over even when ``out`` holds a resumable run of other arguments.

    Returns
    -------
    Comparison
        ``scores`` (evaluator table name → one :class:`~fdikit.metrics.Score` per test run) and ``table``
        (one row per evaluator, in :data:`EVALUATORS` order); ``to_markdown()`` renders it.

    Raises
    ------
    ParameterError
        For a bad argument (checked before any work) or an ``out`` holding a run of other arguments.

    References
    ----------
    Douglas et al. 1996, Ch. 7 (MHSSPRT), §6.2.1 (Gaussian ML), Ch. 6 (Bayesian neural network),
    §5.1.1 (nominal fault sizes).

    Examples
    --------
    Even the smallest comparison simulates a 10-minute training run (a few seconds), so it is not
    run here:

    >>> result = path_evaluator_comparison(runs_per_fault=0, healthy_runs=1, bnn=False,
    ...                                    evaluators=["threshold"])  # doctest: +SKIP
    >>> list(result.scores)  # doctest: +SKIP
    ['threshold (5 of 10)']
    """
    args = check_comparison_arguments(runs_per_fault, healthy_runs, seed, bnn, noise_fraction, evaluators)
    chosen = args["evaluators"]
    if out is None:
        fitted = _fit(chosen, seed, noise_fraction, progress)
        runs = path_runs(_bank(), runs_per_fault=runs_per_fault, healthy_runs=healthy_runs, onset=_ONSET,
                         seed=seed + 2, noise_fraction=noise_fraction, progress=progress)
        return compare_evaluators(fitted, runs, progress=progress)

    from fdikit.metrics import Score
    from fdikit.resume import RunStore

    store = RunStore(out, "compare-evaluators", args, fresh=fresh)
    specs = _test_specs(runs_per_fault, healthy_runs, seed + 2)
    keys = [f"run-{k:05d}" for k in range(len(specs))]
    records = {key: store.load(key) for key in keys}
    todo = [k for k, key in enumerate(keys) if records[key] is None]
    if todo:
        fitted = _fit(chosen, seed, noise_fraction, progress)
        items = todo
        if progress:
            from rich.progress import track

            done = len(specs) - len(todo)
            items = track(todo, description=f"scoring test runs ({done} of {len(specs)} done earlier)"
                          if done else "scoring test runs", total=len(todo))
        for k in items:
            trace, residuals = _test_run(specs[k], noise_fraction)
            scored = score_run(fitted, trace, residuals)
            records[keys[k]] = store.save(keys[k], {"run": k, "scores": {n: asdict(s) for n, s in scored.items()}})
    names = [EVALUATORS[k] for k in chosen]
    scores = {n: [Score(**records[key]["scores"][n]) for key in keys] for n in names}
    result = tabulate(scores)
    store.publish({"scores.csv": scores_csv_text(scores), "comparison.md": result.to_markdown() + "\n"})
    return result


_CACHE: dict = {}


def _bank():
    if "bank" not in _CACHE:
        _CACHE["bank"] = path_bank()
    return _CACHE["bank"]


def _test_specs(runs_per_fault: int, healthy_runs: int, seed: int, dt: float = 0.01):
    """The test runs of :func:`fdikit.studies.path1996.bank.path_runs`: ``[(fault or None, seed), ...]``."""
    import numpy as np

    plant = path_fault_model(14).discretize(dt)
    specs = [None] * healthy_runs + [f for f in plant.faults for _ in range(runs_per_fault)]
    seeds = np.random.default_rng(seed).integers(2**31, size=len(specs))
    return [(f, int(s)) for f, s in zip(specs, seeds)]


def _test_run(spec, noise_fraction: float, size: float = 1.0, duration: float = 20.0, dt: float = 0.01):
    """One test run, exactly as :func:`fdikit.studies.path1996.bank.path_runs` simulates it."""
    import numpy as np

    from fdikit.faults import Bias, FaultScenario
    from fdikit.model import sensor_fault_name
    from fdikit.simulate import simulate

    bank = _bank()
    key = ("plant", dt)
    if key not in _CACHE:
        plant = path_fault_model(14).discretize(dt)
        _CACHE[key] = (plant, bank.generator.discretize(dt))
    plant, gen = _CACHE[key]
    noise = noise_fraction * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    fault, s = spec
    faults = []
    if fault is not None:
        signal, loc = fault.rsplit("_", 1)
        faults = [Bias(signal, size * bank.nominal[fault], onset=_ONSET, location=loc)]
    trace = simulate(plant, FaultScenario(faults), duration=duration, measurement_noise_std=noise, rng=s)
    return trace, gen.run(trace)


def _fit(chosen: Sequence[str], seed: int, noise_fraction: float, progress: bool) -> dict:
    """Fit the chosen evaluators (keys of EVALUATORS) on the training runs; ``{table name: evaluator}``."""
    bank = _bank()
    healthy = path_runs(bank, runs_per_fault=0, healthy_runs=1, duration=600.0, seed=seed,
                        noise_fraction=noise_fraction)[0][1].slice(start=10.0)
    labelled = None
    if any(k in chosen for k in ("mhsprt", "gaussian-ml", "bnn")):
        labelled = path_runs(bank, runs_per_fault=1, healthy_runs=1, onset=_ONSET, seed=seed + 1,
                             noise_fraction=noise_fraction, progress=progress)
    return {EVALUATORS[k]: fit_comparison_evaluator(k, healthy, bank.groups, labelled, onset=_ONSET) for k in chosen}


def fit_comparison_evaluator(key: str, healthy, groups: Sequence[str] | None, labelled=None, *, onset: float = _ONSET,
                             false_alarms_per_hour: float = 1.0, mean_time_between_false_alarms: float = 3600.0,
                             shift: float = 4.0, window: int = 50, alpha: float = 1e-6, beta: float = 1e-3,
                             order: int = 5, regularization: float = 1e-6):
    """One evaluator of the comparison, fitted as ``fdikit compare-evaluators`` fits it.

    The fault-free statistics (thresholds, CUSUM, GLR, SPRT and their AR-whitened variants) come from
    ``healthy``; the MHSSPRT (fault densities from the labelled runs after ``onset + 1`` s), the Gaussian ML
    classifier and the Bayesian NN from ``labelled``.  The defaults are the comparison's.

    Parameters
    ----------
    key : str
        A key of :data:`EVALUATORS`.
    healthy : Residuals
        Fault-free residuals (start-up transient removed).
    groups : sequence of str, optional
        The filter of each residual (bank isolation logic).
    labelled : sequence of (Trace, Residuals), optional
        Labelled training runs, fault-free ones labelled ``'none'`` (needed by ``mhsprt``, ``gaussian-ml``,
        ``bnn``); the MHSSPRT takes each faulty run's fault from its last sample.
    onset : float, default 5.0
        Fault onset of the labelled runs [s].
    false_alarms_per_hour : float, default 1.0
        Target rate of the threshold and GLR tests.
    mean_time_between_false_alarms : float, default 3600.0
        CUSUM target [s].
    shift : float, default 4.0
        Design shift of CUSUM and SPRT in fault-free standard deviations of each (whitened) residual.
    window : int, default 50
        GLR window [samples].
    alpha, beta : float, default 1e-6, 1e-3
        SPRT error probabilities.
    order : int, default 5
        AR order of the whitening.
    regularization : float, default 1e-6
        MHSSPRT density regularisation.

    Returns
    -------
    object
        The fitted evaluator (``run(residuals) -> Diagnosis``).

    Raises
    ------
    ParameterError
        For an unknown key, or a learned evaluator without ``labelled`` runs.

    References
    ----------
    Douglas et al. 1996, Ch. 7 (MHSSPRT), §6.2.1 (Gaussian ML), Ch. 6 (Bayesian neural network).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> res = Residuals(np.arange(2000) * 0.01, np.random.default_rng(0).standard_normal((2000, 1)), ("r",), ("f",))
    >>> type(fit_comparison_evaluator("glr", res, None)).__name__
    'GlrEvaluator'
    """
    import numpy as np

    from fdikit.decision import CusumEvaluator, GlrEvaluator, SprtEvaluator, ThresholdEvaluator, Whitened
    from fdikit.decision.learned.bnn import BnnEvaluator
    from fdikit.decision.learned.gaussian_ml import GaussianMlEvaluator
    from fdikit.decision.mhsprt import MhsprtEvaluator

    if key not in EVALUATORS:
        raise ParameterError(f"unknown evaluator {key!r}; choose from: {', '.join(EVALUATORS)}")
    if key in ("mhsprt", "gaussian-ml", "bnn") and labelled is None:
        raise ParameterError(f"{key} is trained on labelled runs; pass labelled=[(trace, residuals), ...]")
    g = groups
    # vector tests (GLR, SPRT) per fault within each filter: residual '<filter>:<fault>[k]' → '<filter>:<fault>'
    blocks = [name.split("[")[0] for name in healthy.names]
    if key == "threshold":
        return ThresholdEvaluator(groups=g, persistence=(5, 10)).fit(
            healthy, false_alarms_per_hour=false_alarms_per_hour)
    if key in ("cusum", "sprt"):
        # design shift of CUSUM and SPRT: 4 fault-free standard deviations per residual (the nominal faults move
        # their own scaled residual by 1, far more than 4σ at the report's noise level)
        delta = shift * healthy.r.std(axis=0, ddof=1)
        if key == "cusum":
            return CusumEvaluator(groups=g).fit(
                healthy, mean_time_between_false_alarms=mean_time_between_false_alarms, shift=delta)
        return SprtEvaluator(shift=delta, alpha=alpha, beta=beta, blocks=blocks, groups=g).fit(healthy)
    if key == "glr":
        return GlrEvaluator(window=window, blocks=blocks, groups=g).fit(
            healthy, false_alarms_per_hour=false_alarms_per_hour)
    if key == "glr-whitened":
        return Whitened(GlrEvaluator(window=window, blocks=blocks, groups=g), order).fit(
            healthy, false_alarms_per_hour=false_alarms_per_hour)
    if key in ("cusum-whitened", "sprt-whitened"):
        # the same tests on AR-prewhitened residuals (the bank's residuals are coloured; decision.whiten)
        innov = Whitened(ThresholdEvaluator(), order=order).fit(healthy, false_alarm_prob=1e-3).whiten(healthy)
        w_shift = shift * np.nanstd(innov.r, axis=0, ddof=1)
        if key == "cusum-whitened":
            return Whitened(CusumEvaluator(groups=g), order).fit(
                healthy, mean_time_between_false_alarms=mean_time_between_false_alarms, shift=w_shift)
        return Whitened(SprtEvaluator(shift=w_shift, alpha=alpha, beta=beta, blocks=blocks, groups=g),
                        order).fit(healthy)
    if key == "mhsprt":
        return MhsprtEvaluator().fit(_by_fault(healthy, labelled, onset), regularization=regularization)
    runs, labels = [res for _, res in labelled], [trace.fault for trace, _ in labelled]
    if key == "gaussian-ml":
        return GaussianMlEvaluator().fit(runs, labels)
    return BnnEvaluator().fit(runs, labels)


def _by_fault(healthy, labelled, onset):
    by_fault = {"none": healthy}
    for trace, res in labelled:
        if str(trace.fault[-1]) != "none":  # path_runs puts its one fault-free run first
            by_fault[str(trace.fault[-1])] = res.slice(start=onset + 1.0)
    return by_fault
