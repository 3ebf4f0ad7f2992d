"""The Ch. 5 table on the nonlinear car: detection, isolation and false alarms per fault, road and processor.

Douglas et al. 1996, §5.1: for each road (smooth; rough, §2.1.2) one fault-free run sets the
processors' thresholds and a second, independent one counts their false alarms per hour; labelled
runs (one per fault, other seeds) train the multiple-hypothesis SPRT; each of the 15 nominal
faults is then added at t = 2 s to a fresh run and scored (:func:`fdikit.metrics.score`):
detected, detection delay, isolated (the bank logic of the threshold groups, or the SPRT's
hypothesis), isolation delay (first sample from which the isolated fault is right until the end).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["PROCESSORS", "TableRow", "EvaluationTable", "path_evaluation_table"]

#: The residual processors (key → name in the table).
PROCESSORS = {"threshold": "threshold (5 of 10)", "mhsprt": "MHSSPRT", "cusum-whitened": "CUSUM, whitened"}
_ONSET = 2.0


@dataclass(frozen=True)
class TableRow:
    """One (road, fault, processor) entry of the Ch. 5 table.

    Attributes
    ----------
    road, fault, processor : str
        Road, fault name and processor name.
    detected, isolated : bool
        Whether the fault was detected, and isolated correctly.
    detection_delay, isolation_delay : float or None
        Seconds after the onset (None when not detected / not isolated).
    isolated_as : str
        What the processor isolated (``'unknown'``, ``'none'`` when missed).

    Examples
    --------
    >>> TableRow("smooth", "yaw_rate_sensor", "MHSSPRT", True, True, 0.1, 0.2, "yaw_rate_sensor").isolated
    True
    """

    road: str
    fault: str
    processor: str
    detected: bool
    isolated: bool
    detection_delay: float | None
    isolation_delay: float | None
    isolated_as: str


@dataclass(frozen=True, eq=False)
class EvaluationTable:
    """The Ch. 5 evaluation: rows, false alarms per hour, off-nominal peaks.

    Attributes
    ----------
    rows : list of TableRow
        One per (road, fault, processor).
    false_alarms : dict of (str, str) to (int, float)
        (road, processor) → (false alarms, fault-free hours of the test run).
    off_nominal : dict of str to float
        Peak scaled magnitude per residual group in the +2° throttle run (the report: all < 0.25).
    nominal : dict of str to float
        The nominal fault sizes used.

    Examples
    --------
    >>> EvaluationTable([], {}, {}, {}).counts()
    {}
    """

    rows: list
    false_alarms: dict
    off_nominal: dict
    nominal: dict
    runs: dict = field(default_factory=dict, repr=False)

    def counts(self) -> dict[tuple[str, str], tuple[int, int, int]]:
        """(road, processor) → (detected, isolated, faults).

        Returns
        -------
        dict
        """
        out: dict[tuple[str, str], list[int]] = {}
        for r in self.rows:
            c = out.setdefault((r.road, r.processor), [0, 0, 0])
            c[0] += r.detected
            c[1] += r.isolated
            c[2] += 1
        return {k: tuple(v) for k, v in out.items()}

    def rate(self, road: str, processor: str) -> float:
        """False alarms per hour of ``processor`` on ``road``.

        Returns
        -------
        float
        """
        n, hours = self.false_alarms[(road, processor)]
        return n / hours


def _isolation_delay(diagnosis, label: str, onset: float) -> float | None:
    iso = np.asarray(diagnosis.isolated)
    t = np.asarray(diagnosis.t)
    after = t >= onset
    right = (iso == label) & after
    if not right[-1]:
        return None
    wrong = np.flatnonzero(after & ~right)
    k = int(wrong[-1]) + 1 if wrong.size else int(np.flatnonzero(after)[0])
    return float(t[k] - onset)


def _fit(setup, healthy, labelled, chosen):
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator, Whitened
    from fdikit.decision.mhsprt import MhsprtEvaluator

    g = setup.bank.groups
    out = {}
    if "threshold" in chosen:
        out[PROCESSORS["threshold"]] = ThresholdEvaluator(groups=g, persistence=(5, 10)).fit(
            healthy, false_alarms_per_hour=1)
    if "cusum-whitened" in chosen:
        innov = Whitened(ThresholdEvaluator(), order=5).fit(healthy, false_alarm_prob=1e-3).whiten(healthy)
        shift = 4.0 * np.nanstd(innov.r, axis=0, ddof=1)
        out[PROCESSORS["cusum-whitened"]] = Whitened(CusumEvaluator(groups=g), 5).fit(
            healthy, mean_time_between_false_alarms=3600.0, shift=shift)
    if "mhsprt" in chosen:
        data = {"none": healthy}
        for run in labelled:
            data[run.fault] = run.residuals.slice(start=_ONSET + 1.0)
        out[PROCESSORS["mhsprt"]] = MhsprtEvaluator().fit(data, regularization=1e-6)
    return out


def path_evaluation_table(setup=None, *, roads=("smooth", "rough"), faults=None, processors=None,
                          fault_free_hours: float = 1.0, duration: float = 20.0, seed: int = 0,
                          progress: bool = False, keep_runs: bool = False) -> EvaluationTable:
    """Run the Ch. 5 evaluation on the nonlinear car.

    Parameters
    ----------
    setup : EvaluationSetup, optional
        Default :func:`~fdikit.studies.path1996.nonlinear_evaluation.evaluation_setup`.
    roads : sequence of {"smooth", "rough"}, default both
        Roads.
    faults : sequence of str, optional
        Fault names (default all 15).
    processors : sequence of str, optional
        Keys of :data:`PROCESSORS` (default all).
    fault_free_hours : float, default 1.0
        Length of each fault-free run (one to set thresholds, one to count false alarms) [h].
    duration : float, default 20.0
        Length of each faulty run [s] (fault at 2 s).
    seed : int, default 0
        Seed of every run (independent streams per run).
    progress : bool, default False
        Show a rich progress bar.
    keep_runs : bool, default False
        Keep the faulty runs (for plots) in ``runs``.

    Returns
    -------
    EvaluationTable

    Raises
    ------
    ParameterError
        For an unknown road, fault or processor, or a non-positive length.

    References
    ----------
    Douglas et al. 1996, §5.1.1–5.1.2, Ch. 7 (MHSSPRT).

    Examples
    --------
    >>> table = path_evaluation_table(faults=["yaw_rate_sensor"], fault_free_hours=0.05)  # doctest: +SKIP
    >>> sorted(table.counts())[0]  # doctest: +SKIP
    ('rough', 'CUSUM, whitened')
    """
    from fdikit import validate
    from fdikit.metrics import score
    from fdikit.studies.path1996.nonlinear_evaluation import evaluation_setup, fault_run, off_nominal_peaks

    setup = evaluation_setup() if setup is None else setup
    faults = list(setup.nominal) if faults is None else [validate.choice("faults", f, tuple(setup.nominal))
                                                         for f in faults]
    chosen = list(PROCESSORS) if processors is None else [validate.choice("processors", p, tuple(PROCESSORS))
                                                          for p in processors]
    for r in roads:
        validate.choice("roads", r, ("smooth", "rough"))
    hours = validate.positive("fault_free_hours", fault_free_hours)
    duration = validate.positive("duration", duration)
    seeds = iter(np.random.default_rng(validate.integer("seed", seed, minimum=0)).integers(2**31, size=10_000))
    rows, false_alarms, runs = [], {}, {}
    steps = len(roads) * (2 + 2 * len(faults))
    with _progress(progress, steps) as tick:
        for road in roads:
            healthy = fault_run(setup, None, road, duration=hours * 3600.0, rng=next(seeds)).residuals
            tick(f"{road}: fault-free calibration")
            labelled = []
            if "mhsprt" in chosen:
                for f in faults:
                    labelled.append(fault_run(setup, f, road, duration=duration, rng=next(seeds)))
                    tick(f"{road}: training {f}")
            else:
                tick(f"{road}: (no training)", len(faults))
            evaluators = _fit(setup, healthy.slice(start=_ONSET), labelled, chosen)
            test = fault_run(setup, None, road, duration=hours * 3600.0, rng=next(seeds))
            for name, ev in evaluators.items():
                s = score(test.trace, ev.run(test.residuals))
                false_alarms[(road, name)] = (int(s.false_alarms), float(s.fault_free_hours))
            tick(f"{road}: fault-free test")
            for f in faults:
                run = fault_run(setup, f, road, duration=duration, rng=next(seeds))
                if keep_runs:
                    runs[(road, f)] = run
                for name, ev in evaluators.items():
                    d = ev.run(run.residuals)
                    s = score(run.trace, d)
                    rows.append(TableRow(road, f, name, bool(s.detected), bool(s.isolation_correct),
                                         s.detection_delay, _isolation_delay(d, f, _ONSET), str(s.isolated)))
                tick(f"{road}: {f}")
    return EvaluationTable(rows, false_alarms, off_nominal_peaks(setup), dict(setup.nominal), runs)


class _progress:
    """A rich progress bar (or nothing) with a ``tick(description, steps=1)`` callback."""

    def __init__(self, show: bool, total: int):
        self.show, self.total = show, total

    def __enter__(self):
        if not self.show:
            return lambda *a, **k: None
        from rich.progress import Progress

        self.bar = Progress()
        self.bar.start()
        task = self.bar.add_task("PATH evaluation", total=self.total)
        return lambda desc, n=1: self.bar.update(task, advance=n, description=desc)

    def __exit__(self, *exc):
        if self.show:
            self.bar.stop()
        return False
