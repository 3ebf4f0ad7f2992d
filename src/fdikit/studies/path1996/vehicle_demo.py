"""The end-to-end demo on the nonlinear car (``fdikit demo``): realistic noise, rough road, two faults.

Douglas et al. 1996, §5.1: the car in the 0.005 rad turn at 24.87 m/s on the rough road (§2.1.2), the
sensors at the noise levels of :data:`~fdikit.studies.path1996.nonlinear_evaluation.NOISE_STD`; the PATH
monitor is the game-theoretic bank on the report's fault groups (:mod:`fdikit.studies.path1996.game_bank`)
designed from the car's own linearised, reduced model, with the prewhitened multiple-hypothesis SPRT
(:func:`~fdikit.studies.path1996.nonlinear_table.whitened_mhsprt`) trained on one simulated run per fault
and calibrated on a fault-free run.  Scenarios: the report's nominal yaw-rate gyro bias (0.02 rad/s) and a
+2° throttle fault (Figs. 5.13–5.14), each at ``onset``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["VehicleDemoResult", "VEHICLE_SCENARIOS", "run_vehicle_demo", "plot_vehicle_report"]

#: Demo scenarios: (label, fault name).
VEHICLE_SCENARIOS = (("yaw-rate gyro bias", "yaw_rate_sensor"), ("throttle +2 deg", "throttle_actuator"))
_BANK = "game"


@dataclass(frozen=True, eq=False)
class VehicleDemoResult:
    """What :func:`run_vehicle_demo` returns; dicts keyed by scenario label.

    Attributes
    ----------
    runs : dict of str to FaultRun
        Each scenario's run (deviation trace and residuals of every bank).
    diagnoses : dict of str to Diagnosis
        The MHSSPRT's decisions on the game bank's residuals.
    scores : dict of str to Score
        Detection and isolation of each run.
    evaluator : Prewhitened
        The fitted processor.
    files : dict of str to pathlib.Path
        ``"report"`` and one ``"trace (<label>)"`` per scenario.

    References
    ----------
    Douglas et al. 1996, §5.1.

    Examples
    --------
    >>> res = run_vehicle_demo("out/demo", calibration_minutes=1.0)  # doctest: +SKIP
    >>> sorted(res.scores)  # doctest: +SKIP
    ['throttle +2 deg', 'yaw-rate gyro bias']
    """

    runs: dict
    diagnoses: dict
    scores: dict
    evaluator: object
    files: dict


def run_vehicle_demo(out_dir: str | Path = "out/demo", seed: int = 2026, onset: float = 10.0,
                     duration: float = 30.0, calibration_minutes: float = 10.0, road: str = "rough"
                     ) -> VehicleDemoResult:
    """Diagnose two faults on the nonlinear car at realistic noise; write report.png and the traces.

    Parameters
    ----------
    out_dir : str or PathLike, default "out/demo"
        Output folder.
    seed : int, default 2026
        Seed of every run.
    onset, duration : float, default 10.0, 30.0
        Fault onset and run length [s].
    calibration_minutes : float, default 10.0
        Fault-free run that whitens the residuals and sets the decision threshold [min].
    road : {"rough", "smooth"}, default "rough"
        The road.

    Returns
    -------
    VehicleDemoResult

    Raises
    ------
    ParameterError
        For a bad argument (:func:`~fdikit.studies.path1996.demo.check_demo_arguments`).

    References
    ----------
    Douglas et al. 1996, §5.1, Figs. 5.13–5.14.

    Examples
    --------
    >>> res = run_vehicle_demo("out/demo")  # doctest: +SKIP
    >>> all(s.isolation_correct for s in res.scores.values())  # doctest: +SKIP
    True
    """
    from fdikit.metrics import score
    from fdikit.studies.path1996.demo import check_demo_arguments
    from fdikit.studies.path1996.nonlinear_evaluation import evaluation_setup, fault_run
    from fdikit.studies.path1996.nonlinear_table import whitened_mhsprt

    out = check_demo_arguments(out=out_dir, seed=seed, method="vehicle", onset=onset, duration=duration,
                               calibration_minutes=calibration_minutes)
    setup = evaluation_setup()
    seeds = iter(np.random.default_rng(seed).integers(2**31, size=64))
    healthy = fault_run(setup, None, road, duration=60.0 * calibration_minutes, rng=next(seeds))
    labelled = [(f, fault_run(setup, f, road, duration=20.0, rng=next(seeds)).residuals[_BANK]) for f in setup.nominal]
    evaluator = whitened_mhsprt(healthy.residuals[_BANK].slice(start=2.0), labelled)
    runs, diagnoses, scores, files = {}, {}, {}, {}
    for label, fault in VEHICLE_SCENARIOS:
        run = fault_run(setup, fault, road, duration=duration, onset=onset, rng=next(seeds))
        d = evaluator.run(run.residuals[_BANK])
        runs[label], diagnoses[label], scores[label] = run, d, score(run.trace, d)
        files[f"trace ({label})"] = run.trace.save(out / f"trace_{fault}.parquet")
    files["report"] = plot_vehicle_report(runs, diagnoses, onset, out / "report.png")
    return VehicleDemoResult(runs, diagnoses, scores, evaluator, files)


def plot_vehicle_report(runs, diagnoses, onset: float, path=None, axes=None):
    """One column per scenario: the scaled residual magnitudes of the fault's filter (1 s means), MHSSPRT posteriors.

    Parameters
    ----------
    runs : mapping of str to FaultRun
        Scenario label → run.
    diagnoses : mapping of str to Diagnosis
        Scenario label → MHSSPRT decisions (with ``probabilities``).
    onset : float
        Fault onset [s] (a dashed line).
    path : str or Path, optional
        Write the figure there (returns the path).
    axes : (2, k) array of Axes, optional
        Where to draw (a new figure otherwise; returns the figure).

    Returns
    -------
    pathlib.Path or matplotlib Figure

    References
    ----------
    Douglas et al. 1996, §5.1 (scaled residuals), Ch. 7 (posterior probabilities).

    Examples
    --------
    >>> plot_vehicle_report(res.runs, res.diagnoses, 10.0)  # doctest: +SKIP
    """
    import matplotlib.pyplot as plt

    from fdikit.plots import save_figure
    from fdikit.studies.path1996.nonlinear_evaluation import group_magnitudes

    labels = list(runs)
    if axes is None:
        fig, axes = plt.subplots(2, len(labels), figsize=(6 * len(labels), 6.5), squeeze=False, sharex="col")
    else:
        fig = np.asarray(axes).ravel()[0].figure
    for j, label in enumerate(labels):
        run, d = runs[label], diagnoses[label]
        mags = group_magnitudes(run.residuals[_BANK])
        own = next(g for g in mags if g.endswith(":" + run.fault))
        filt = own.split(":")[0]
        ax = axes[0][j]
        t = run.residuals[_BANK].t
        width = max(1, int(round(1.0 / float(np.median(np.diff(t))))))
        for g, m in mags.items():
            if g.startswith(filt + ":"):
                mean = np.convolve(m, np.ones(width) / width, mode="valid")
                ax.plot(t[width - 1:], mean, lw=1.6 if g == own else 0.7, label=g.split(":")[1])
        ax.axhline(1.0, color="k", ls=":", lw=0.8)
        ax.axvline(onset, color="grey", ls="--", lw=0.8)
        ax.set_title(f"{label}: {filt} of the game bank")
        ax.set_ylabel("scaled magnitude, 1 s mean")
        ax.legend(fontsize=7)
        ax = axes[1][j]
        P = d.probabilities
        top = np.argsort(P.max(axis=0))[::-1][:4]
        for k in top:
            ax.plot(d.t, P[:, k], label=d.hypotheses[k])
        ax.axvline(onset, color="grey", ls="--", lw=0.8)
        ax.set_ylim(-0.05, 1.05)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("MHSSPRT posterior")
        ax.legend(fontsize=7)
    fig.tight_layout()
    if path is None:
        return fig
    save_figure(fig, path)
    plt.close(fig)
    return Path(path)
