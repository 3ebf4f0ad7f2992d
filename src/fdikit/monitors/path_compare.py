"""Residual processors side by side on the PATH bank's residuals (``fdikit compare-evaluators``).

Training and test data come from separate seeds: a 10-minute fault-free run calibrates the
fault-free statistics (thresholds, CUSUM, GLR, SPRT); one labelled run per fault trains the
multiple-hypothesis SPRT (Douglas et al. 1996, Ch. 7), the Gaussian ML classifier (§6.2.1) and
the Bayesian neural network (Ch. 6); every evaluator is then scored on the same fresh runs
(:func:`fdikit.compare.compare_evaluators`).
"""

from __future__ import annotations

from pathlib import Path

from fdikit.compare import Comparison, compare_evaluators
from fdikit.monitors.path_bank import path_bank, path_runs

__all__ = ["path_evaluator_comparison"]


def path_evaluator_comparison(
    runs_per_fault: int = 2,
    healthy_runs: int = 5,
    seed: int = 0,
    out: str | Path | None = None,
    progress: bool = False,
    bnn: bool = True,
    noise_fraction: float = 1e-4,
) -> Comparison:
    """Fit every evaluator on training runs and score them on fresh PATH runs.

    ``out``: a folder for ``scores.csv`` (written run by run) and ``comparison.md``.
    """
    import numpy as np

    from fdikit.decision import CusumEvaluator, GlrEvaluator, SprtEvaluator, ThresholdEvaluator, Whitened
    from fdikit.decision.bnn import BnnEvaluator
    from fdikit.decision.gaussian_ml import GaussianMlEvaluator
    from fdikit.decision.mhsprt import MhsprtEvaluator

    bank = path_bank()
    onset = 5.0
    healthy = path_runs(bank, runs_per_fault=0, healthy_runs=1, duration=600.0, seed=seed,
                        noise_fraction=noise_fraction)[0][1].slice(start=10.0)
    labelled = path_runs(bank, runs_per_fault=1, healthy_runs=1, onset=onset, seed=seed + 1,
                         noise_fraction=noise_fraction, progress=progress)
    g = bank.groups
    # design shift of CUSUM and SPRT: 4 fault-free standard deviations per residual (the nominal faults move
    # their own scaled residual by 1, far more than 4σ at this noise level)
    shift = 4.0 * healthy.r.std(axis=0, ddof=1)
    # vector tests (GLR, SPRT) per fault within each filter: residual '<filter>:<fault>[k]' → '<filter>:<fault>'
    blocks = [name.split("[")[0] for name in healthy.names]
    evaluators = {
        "threshold (5 of 10)": ThresholdEvaluator(groups=g, persistence=(5, 10)).fit(healthy, false_alarms_per_hour=1),
        "CUSUM": CusumEvaluator(groups=g).fit(healthy, mean_time_between_false_alarms=3600.0, shift=shift),
        "GLR (M = 50)": GlrEvaluator(window=50, blocks=blocks, groups=g).fit(healthy, false_alarms_per_hour=1),
        "SPRT": SprtEvaluator(shift=shift, alpha=1e-6, beta=1e-3, blocks=blocks, groups=g).fit(healthy),
    }
    # the same tests on AR(5)-prewhitened residuals (the bank's residuals are coloured; decision.whiten)
    innov = Whitened(ThresholdEvaluator(), order=5).fit(healthy, false_alarm_prob=1e-3).whiten(healthy)
    w_shift = 4.0 * np.nanstd(innov.r, axis=0, ddof=1)
    evaluators["CUSUM, whitened"] = Whitened(CusumEvaluator(groups=g), 5).fit(
        healthy, mean_time_between_false_alarms=3600.0, shift=w_shift)
    evaluators["GLR, whitened"] = Whitened(GlrEvaluator(window=50, blocks=blocks, groups=g), 5).fit(
        healthy, false_alarms_per_hour=1)
    evaluators["SPRT, whitened"] = Whitened(
        SprtEvaluator(shift=w_shift, alpha=1e-6, beta=1e-3, blocks=blocks, groups=g), 5).fit(healthy)
    by_fault = {"none": healthy}
    for trace, res in labelled[1:]:
        by_fault[str(trace.fault[-1])] = res.slice(start=onset + 1.0)
    evaluators["MHSSPRT"] = MhsprtEvaluator().fit(by_fault, regularization=1e-6)
    sequences = [res for _, res in labelled]
    labels = [trace.fault for trace, _ in labelled]
    evaluators["Gaussian ML"] = GaussianMlEvaluator().fit(sequences, labels)
    if bnn:
        evaluators["Bayesian NN"] = BnnEvaluator().fit(sequences, labels)
    runs = path_runs(bank, runs_per_fault=runs_per_fault, healthy_runs=healthy_runs, onset=onset, seed=seed + 2,
                     noise_fraction=noise_fraction, progress=progress)
    out = None if out is None else Path(out)
    result = compare_evaluators(evaluators, runs, scores_csv=None if out is None else out / "scores.csv",
                                progress=progress)
    if out is not None:
        (out / "comparison.md").write_text(result.to_markdown() + "\n")
    return result
