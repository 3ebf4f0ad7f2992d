"""The end-to-end demos on the linear PATH vehicle (the default demo on the nonlinear car is
:mod:`fdikit.studies.path1996.vehicle_demo`).

:func:`run_demo` (``fdikit demo --method bank``): the four-filter Beard–Jones bank of
:mod:`fdikit.studies.path1996.bank` diagnoses a yaw-rate gyro bias and a throttle actuator
fault, each isolated by the bank logic, and writes a structure plot (fault × residual gain).

:func:`run_kalman_demo` (``fdikit demo --method kalman``), the detection-only baseline.
Scenario (Douglas et al. 1996: the 12-state model of App. D; the 0.02 rad/s nominal
rate-sensor fault of §5.1.1): the vehicle holds its operating point (deviation inputs
zero) with actuator jitter and sensor noise; a 0.02 rad/s bias appears on the yaw-rate
sensor at t = 10 s.  A steady-state Kalman filter (sampled at 100 Hz) gives one
innovation per sensor; thresholds are calibrated on a separate 10-minute fault-free run
for 1 false alarm per hour.  Each innovation is tied to its own sensor for isolation
(a sensor bias shows first and most in its own innovation; this is a heuristic, not the
geometric isolation of a detection filter).

Noise levels are not in the report (its §5.1.2 gives only the 0.3 m/s² vertical
accelerometer noise); the others below are assumptions typical of automotive sensors.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fdikit.decision import ThresholdEvaluator
from fdikit.design import ObserverDesign, kalman
from fdikit.diagnosis import Diagnosis
from fdikit.errors import ParameterError
from fdikit.faults import Bias, FaultScenario
from fdikit.metrics import Score, score
from fdikit.model import FaultModel, sensor_fault_name
from fdikit.plants import path_vehicle_12
from fdikit.plots import plot_residuals, save_figure
from fdikit.residuals import Residuals
from fdikit.simulate import simulate
from fdikit.trace import Trace

__all__ = ["DemoResult", "BankDemoResult", "demo_model", "run_demo", "run_kalman_demo", "check_demo_arguments",
           "plot_bank_report", "SENSOR_NOISE_STD", "ACTUATOR_NOISE_STD"]

#: Sensor noise standard deviations (per sample at 100 Hz), in App. D output order.
SENSOR_NOISE_STD = {
    "air_mass": 0.005, "engine_speed": 0.5, "accel_x": 0.05, "accel_y": 0.05, "accel_z": 0.3,
    "roll_rate": 0.002, "pitch_rate": 0.002, "yaw_rate": 0.002, "wheel_speed_fl": 0.1,
    "wheel_speed_fr": 0.1, "wheel_speed_rl": 0.1, "wheel_speed_rr": 0.1,
}
#: Actuator jitter standard deviations: throttle [deg], brake torque [N m], steering [rad].
ACTUATOR_NOISE_STD = {"throttle": 0.05, "brake": 5.0, "steering": 2e-4}


@dataclass(frozen=True, eq=False)
class DemoResult:
    """What :func:`run_kalman_demo` returns.

    Attributes
    ----------
    trace : Trace
        The faulty run (yaw-rate bias at ``onset``).
    residuals : Residuals
        The 12 Kalman innovations on it, each tied to its own sensor fault.
    diagnosis : Diagnosis
        The threshold decisions.
    score : Score
        Detection delay, false alarms and isolation of the run.
    design : ObserverDesign
        The steady-state Kalman filter.
    evaluator : ThresholdEvaluator
        Thresholds calibrated on the fault-free run.
    files : dict of str to pathlib.Path
        ``"trace"`` (``trace.parquet``) and ``"report"`` (``report.png``).

    References
    ----------
    Douglas et al. 1996, App. D (the 12-state model), §5.1.1 (the 0.02 rad/s nominal rate-sensor fault).

    Examples
    --------
    The demo simulates a calibration run and writes files (seconds), so it is not run here:

    >>> result = run_kalman_demo("out/demo", duration=3.0, onset=1.0, calibration_minutes=0.5)  # doctest: +SKIP
    >>> sorted(result.files), result.residuals.r.shape  # doctest: +SKIP
    (['report', 'trace'], (301, 12))
    """

    trace: Trace
    residuals: Residuals
    diagnosis: Diagnosis
    score: Score
    design: ObserverDesign
    evaluator: ThresholdEvaluator
    files: dict


def check_demo_arguments(*, out="out/demo", seed=2026, method="vehicle", onset=10.0, duration=30.0,
                         calibration_minutes=10.0, dt=0.01, **positive) -> Path:
    """Check the demo's arguments before any work; return the output folder (created, writable).

    Parameters
    ----------
    out : str or PathLike, default "out/demo"
        Output folder; created if missing, must be writable.
    seed : int, default 2026
        Seed, >= 0.
    method : {"vehicle", "bank", "kalman"}, default "vehicle"
        Which demo.
    onset, duration : float, default 10.0, 30.0
        Fault onset and run length [s]; ``onset < duration``.
    calibration_minutes : float, default 10.0
        Length of the fault-free calibration run [min].
    dt : float, default 0.01
        Sample time [s], smaller than ``duration``.
    **positive : float
        Further values that must be finite and > 0 (``fault_size``, ``noise_fraction``, ``false_alarms_per_hour``).

    Returns
    -------
    pathlib.Path
        The output folder.

    Raises
    ------
    ParameterError
        Naming the argument: ``method`` 'vehicle', 'bank' or 'kalman', ``seed`` an integer >= 0,
        ``onset`` < ``duration``, times and the other keyword values (``fault_size``, ``noise_fraction``,
        ``false_alarms_per_hour``) finite and > 0, ``out`` a writable folder.

    References
    ----------
    Douglas et al. 1996, §5.1.1 (the demo scenarios).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp()) / "demo"
    >>> check_demo_arguments(out=folder, method="kalman", fault_size=0.02) == folder
    True
    """
    from fdikit.resume import check_output_folder, check_positive, check_seed

    if method not in ("vehicle", "bank", "kalman"):
        raise ParameterError(f"unknown method (--method) {method!r}; use 'vehicle', 'bank' or 'kalman'")
    check_seed(seed)
    for name, value in {"onset": onset, "duration": duration, "calibration_minutes": calibration_minutes, "dt": dt,
                        **positive}.items():
        check_positive(value, name)
    if onset >= duration:
        raise ParameterError(f"onset (--onset) = {onset:g} s must lie before the end of the run, duration = "
                             f"{duration:g} s")
    if dt >= duration:
        raise ParameterError(f"dt = {dt:g} s must be smaller than duration = {duration:g} s")
    return check_output_folder(out)


def demo_model(dt: float = 0.01) -> FaultModel:
    """The 12-state PATH model, actuator jitter as its noise group, sampled at ``dt``.

    Parameters
    ----------
    dt : float, default 0.01
        ZOH sample time [s].

    Returns
    -------
    FaultModel
        Discrete 12-state model with the noise group ``<control>_jitter`` (entering like the controls,
        ``Bw = Bu``, ``Dw = Du``) and the 12 fault inputs ``<output>_sensor``.

    References
    ----------
    Douglas et al. 1996, App. D, (d.2a–d).

    Examples
    --------
    >>> m = demo_model()
    >>> m.n, m.dt, m.noise
    (12, 0.01, ('throttle_jitter', 'brake_jitter', 'steering_jitter'))
    """
    m = path_vehicle_12()
    m = m.replace(Bw=m.Bu, Dw=m.Du, noise=[f"{c}_jitter" for c in m.controls])
    return m.with_sensor_faults(m.outputs).discretize(dt)


def run_kalman_demo(
    out_dir: str | Path = "out/demo",
    seed: int = 2026,
    fault_size: float = 0.02,
    onset: float = 10.0,
    duration: float = 30.0,
    calibration_minutes: float = 10.0,
    false_alarms_per_hour: float = 1.0,
    dt: float = 0.01,
) -> DemoResult:
    """Run the demo; writes ``report.png`` and ``trace.parquet`` to ``out_dir`` (each atomically).

    Every argument is checked first (:func:`check_demo_arguments`).

    Parameters
    ----------
    out_dir : str or PathLike, default "out/demo"
        Output folder.
    seed : int, default 2026
        Seed of the calibration and test runs.
    fault_size : float, default 0.02
        Yaw-rate sensor bias [rad/s].
    onset : float, default 10.0
        Fault onset [s].
    duration : float, default 30.0
        Length of the faulty run [s].
    calibration_minutes : float, default 10.0
        Length of the fault-free calibration run [min].
    false_alarms_per_hour : float, default 1.0
        Design false-alarm rate of the thresholds.
    dt : float, default 0.01
        Sample time [s].

    Returns
    -------
    DemoResult
        Trace, innovations, diagnosis, score, Kalman design, evaluator and the written files.

    Raises
    ------
    ParameterError
        For a bad argument (see :func:`check_demo_arguments`).

    References
    ----------
    Douglas et al. 1996, App. D; §5.1.1 (nominal rate-sensor fault), §5.1.2 (vertical accelerometer noise).

    Examples
    --------
    A short run still simulates a calibration run and writes a plot (about 2 s), so it is not run here:

    >>> result = run_kalman_demo("out/demo", duration=3.0, onset=1.0, calibration_minutes=0.5)  # doctest: +SKIP
    >>> result.score.detected  # doctest: +SKIP
    True
    """
    out = check_demo_arguments(out=out_dir, seed=seed, method="kalman", onset=onset, duration=duration,
                               calibration_minutes=calibration_minutes, dt=dt, fault_size=fault_size,
                               false_alarms_per_hour=false_alarms_per_hour)
    model = demo_model(dt)
    W = np.diag([ACTUATOR_NOISE_STD[c] ** 2 for c in model.controls])
    v_std = np.array([SENSOR_NOISE_STD[o] for o in model.outputs])
    design = kalman(model, W, np.diag(v_std**2))
    generator = replace(design.generator, isolates=tuple(sensor_fault_name(o) for o in model.outputs))

    rng = np.random.default_rng(seed)
    seeds = rng.integers(2**31, size=2)
    healthy = simulate(model, duration=60 * calibration_minutes, noise_cov=W, measurement_noise_std=v_std,
                       rng=int(seeds[0]))
    evaluator = ThresholdEvaluator().fit(generator.run(healthy).slice(start=5.0),
                                        false_alarms_per_hour=false_alarms_per_hour)

    scenario = FaultScenario([Bias("yaw_rate", fault_size, onset=onset)], label="yaw-rate gyro bias")
    trace = simulate(model, scenario, duration=duration, noise_cov=W, measurement_noise_std=v_std, rng=int(seeds[1]),
                     meta={"demo": "path12 yaw-rate bias", "plant": "path12 (Douglas et al. 1996, App. D)"})
    residuals = generator.run(trace)
    diagnosis = evaluator.run(residuals)
    result_score = score(trace, diagnosis)

    files = {"trace": trace.save(out / "trace.parquet")}
    fired = [n for n in residuals.names if diagnosis.fired[:, residuals.names.index(n)].any()]
    shown = list(dict.fromkeys(["yaw_rate", *fired, "roll_rate", "accel_y"]))[:6]
    plot_residuals(
        residuals, diagnosis, evaluator.thresholds, evaluator.center, onset=onset, names=shown,
        title=f"PATH vehicle, Kalman innovations: {fault_size} rad/s yaw-rate bias at t = {onset} s "
        f"(thresholds for {false_alarms_per_hour:g} false alarm/h)",
        path=out / "report.png",
    )
    files["report"] = out / "report.png"
    return DemoResult(trace, residuals, diagnosis, result_score, design, evaluator, files)


@dataclass(frozen=True, eq=False)
class BankDemoResult:
    """What :func:`run_demo` returns; the dicts are keyed by scenario label (:data:`BANK_SCENARIOS`).

    Attributes
    ----------
    traces : dict of str to Trace
        The faulty run of each scenario.
    diagnoses : dict of str to Diagnosis
        The bank's threshold decisions on each run.
    scores : dict of str to Score
        Detection and isolation score of each run.
    evaluator : ThresholdEvaluator
        Thresholds (grouped by filter, persistence 5 of 10) calibrated on the fault-free run.
    noise : numpy.ndarray
        (12,) sensor noise standard deviations used.
    files : dict of str to pathlib.Path
        ``"report"``, ``"structure"`` and one ``"trace (<label>)"`` per scenario.

    References
    ----------
    Douglas et al. 1996, §4.1–4.2 (the bank), §5.1.1 (nominal fault sizes), Figs. 5.13–5.14.

    Examples
    --------
    The demo designs the bank, simulates and writes files (seconds), so it is not run here:

    >>> result = run_demo("out/demo", duration=3.0, onset=1.0, calibration_minutes=0.5)  # doctest: +SKIP
    >>> sorted(result.scores)  # doctest: +SKIP
    ['throttle +2 deg', 'yaw-rate gyro bias']
    """

    traces: dict[str, Trace]
    diagnoses: dict[str, Diagnosis]
    scores: dict[str, Score]
    evaluator: ThresholdEvaluator
    noise: np.ndarray
    files: dict


#: Demo scenarios: (label, signal, location, size) — the report's nominal yaw-rate fault (§5.1.1)
#: and a +2° throttle command fault (Figs. 5.13–5.14).
BANK_SCENARIOS = (("yaw-rate gyro bias", "yaw_rate", "sensor", 0.02), ("throttle +2 deg", "throttle", "actuator", 2.0))


def run_demo(
    out_dir: str | Path = "out/demo",
    seed: int = 2026,
    onset: float = 10.0,
    duration: float = 30.0,
    noise_fraction: float = 1e-4,
    calibration_minutes: float = 10.0,
    dt: float = 0.01,
) -> BankDemoResult:
    """PATH bank demo: two faults, each detected and isolated; writes report.png, structure.png and traces.

    The plant is the 14-state App. D model (``tiny='midpoint'``) sampled at ``dt`` with white
    sensor noise of ``noise_fraction`` times each sensor's nominal fault size (the
    reconstructed filters amplify noise strongly; see ``docs/methods/beard_jones.md``).
    Thresholds: 1 false alarm per hour on a fault-free run, persistence 5 of 10.  Every argument is
    checked first (:func:`check_demo_arguments`); every file is written atomically.

    Parameters
    ----------
    out_dir : str or PathLike, default "out/demo"
        Output folder.
    seed : int, default 2026
        Seed of the calibration and scenario runs.
    onset : float, default 10.0
        Fault onset [s].
    duration : float, default 30.0
        Length of each faulty run [s].
    noise_fraction : float, default 1e-4
        Sensor noise as a fraction of each sensor's nominal fault size.
    calibration_minutes : float, default 10.0
        Length of the fault-free calibration run [min].
    dt : float, default 0.01
        Sample time [s].

    Returns
    -------
    BankDemoResult
        Per scenario the trace, diagnosis and score; the evaluator, the noise levels and the written files.

    Raises
    ------
    ParameterError
        For a bad argument (see :func:`check_demo_arguments`).

    References
    ----------
    Douglas et al. 1996, §4.1–4.2 (the bank), §5.1.1 (nominal fault sizes), Figs. 5.13–5.14.

    Examples
    --------
    The bank design, the runs and the plots take a few seconds, so the call is not run here:

    >>> result = run_demo("out/demo", duration=3.0, onset=1.0, calibration_minutes=0.5)  # doctest: +SKIP
    >>> sorted(result.files)  # doctest: +SKIP
    ['report', 'structure', 'trace (throttle +2 deg)', 'trace (yaw-rate gyro bias)']
    """
    from fdikit.analysis.gains import fault_to_residual_gain
    from fdikit.studies.path1996 import path_bank, path_fault_model

    out = check_demo_arguments(out=out_dir, seed=seed, method="bank", onset=onset, duration=duration,
                               calibration_minutes=calibration_minutes, dt=dt, noise_fraction=noise_fraction)
    bank = path_bank()
    gen = bank.generator.discretize(dt)
    plant = path_fault_model(14).discretize(dt)
    noise = noise_fraction * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    seeds = np.random.default_rng(seed).integers(2**31, size=1 + len(BANK_SCENARIOS))
    healthy = simulate(plant, duration=60 * calibration_minutes, measurement_noise_std=noise, rng=int(seeds[0]))
    evaluator = ThresholdEvaluator(groups=bank.groups, persistence=(5, 10)).fit(
        gen.run(healthy).slice(start=10.0), false_alarms_per_hour=1.0)
    traces, diagnoses, scores, files = {}, {}, {}, {}
    panels = []
    for (label, signal, loc, size), s in zip(BANK_SCENARIOS, seeds[1:]):
        scenario = FaultScenario([Bias(signal, size, onset=onset, location=loc)], label=label)
        trace = simulate(plant, scenario, duration=duration, measurement_noise_std=noise, rng=int(s),
                         meta={"demo": f"path bank: {label}"})
        residuals = gen.run(trace)
        diagnosis = evaluator.run(residuals)
        traces[label], diagnoses[label], scores[label] = trace, diagnosis, score(trace, diagnosis)
        fault = scenario.resolve(plant.outputs, plant.controls).faults[0].name
        files[f"trace ({label})"] = trace.save(out / f"trace_{signal}.parquet")
        group = next(g for g, iso in zip(bank.groups, residuals.isolates) if iso == fault)
        panels.append((label, residuals, diagnosis, [n for n, g in zip(residuals.names, bank.groups) if g == group]))
    plot_bank_report(panels, evaluator, onset, out / "report.png")
    files["report"] = out / "report.png"
    table = fault_to_residual_gain(gen, plant, np.logspace(-2, np.log10(np.pi / dt), 40))
    files["structure"] = save_figure(table.plot(), out / "structure.png")
    return BankDemoResult(traces, diagnoses, scores, evaluator, noise, files)


def plot_bank_report(panels, evaluator, onset, path=None, axes=None):
    """The bank demo's report figure: one column per scenario, the residuals of the filter that holds the fault.

    Parameters
    ----------
    panels : sequence of (str, Residuals, Diagnosis, list of str)
        Per scenario: its label, the bank's residuals and decisions, and the names of the residuals
        to draw (one row each).
    evaluator : ThresholdEvaluator
        The fitted evaluator (``center`` and ``thresholds`` give the threshold band).
    onset : float
        Fault onset time [s] (a dotted line).
    path : str, Path or binary file object, optional
        Write the figure there (atomically, :func:`fdikit.plots.save_figure`).
    axes : 2-D array of matplotlib Axes, optional
        ``rows × len(panels)`` axes, ``rows`` the largest number of residuals of a panel; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure or the given ``axes``
        A new figure (closed once written to ``path``) when ``axes`` is None, else ``axes``.

    References
    ----------
    Douglas et al. 1996, §5.1.1 (the nominal yaw-rate sensor fault), Figs. 5.13–5.14 (the throttle fault).

    Examples
    --------
    :func:`run_demo` draws it from its two scenarios; here one made-up scenario, into given axes (only
    ``center`` and ``thresholds`` of the evaluator are read):

    >>> import matplotlib.pyplot as plt
    >>> from types import SimpleNamespace
    >>> t = np.arange(100) * 0.1
    >>> res = Residuals(t, np.c_[np.sin(t), np.cos(t)], ("F1:a", "F1:b"), ("a", "b"))
    >>> fired = np.abs(res.r) > 0.9
    >>> diag = Diagnosis(t, fired.any(axis=1), fired, res.names, np.where(fired.any(axis=1), "a", "none"))
    >>> band = SimpleNamespace(center=np.zeros(2), thresholds=np.full(2, 0.9))
    >>> fig, axes = plt.subplots(2, 1, squeeze=False)
    >>> plot_bank_report([("bias", res, diag, ["F1:a", "F1:b"])], band, 5.0, axes=axes) is axes
    True
    >>> plt.close(fig)
    """
    from fdikit.plots import axes_or_new, finish_plot

    rows, cols = max(len(p[3]) for p in panels), len(panels)
    if axes is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(rows, cols, figsize=(6 * cols, 1.3 * rows + 1), sharex=True, squeeze=False)
    else:
        fig, flat = axes_or_new(axes, rows * cols)
        grid = np.asarray(flat, dtype=object).reshape(rows, cols)
    for col, (label, res, diag, names) in enumerate(panels):
        for row in range(rows):
            ax = grid[row, col]
            if row >= len(names):
                ax.axis("off")
                continue
            j = res.names.index(names[row])
            ax.plot(res.t, res.r[:, j], lw=0.7)
            for sgn in (-1, 1):
                ax.axhline(evaluator.center[j] + sgn * evaluator.thresholds[j], color="tab:red", ls="--", lw=0.7)
            hit = diag.fired[:, j]
            ax.plot(res.t[hit], res.r[hit, j], ".", ms=2, color="tab:red")
            ax.axvline(onset, color="k", ls=":", lw=0.8)
            ax.set_ylabel(names[row].split(":", 1)[1], rotation=0, ha="right", fontsize=7)
            ax.tick_params(labelsize=7)
        grid[0, col].set_title(f"{label}: {names[0].split(':')[0]} residuals (scaled, nominal fault = 1)", fontsize=9)
        grid[-1, col].set_xlabel("time [s]")
    return finish_plot(fig, axes, path, dpi=110)
