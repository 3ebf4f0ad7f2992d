"""The ``fdikit`` command line.

Every command checks all of its arguments before any work and answers bad input with one line
``error: ...`` naming the option and what would be accepted (exit code 2, no traceback).  The long
commands (``compare-evaluators``, ``multiple-model``) store each finished result at once and resume
after a kill when rerun with the same arguments; ``--fresh`` starts over (see :mod:`fdikit.resume`).
Every file is written atomically (:mod:`fdikit.atomic`).
"""

from __future__ import annotations

import io
import time
import warnings
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from fdikit.errors import FdiError, FdiWarning, ParameterError

app = typer.Typer(help="fdikit: model-based fault detection and isolation for vehicles and aircraft.",
                  no_args_is_help=True, add_completion=False)
console = Console()
err_console = Console(stderr=True)


def _campaign_commands() -> None:
    from fdikit.cli_campaign import campaign_app

    app.add_typer(campaign_app, name="campaign")


_campaign_commands()


def _fail(exc: Exception) -> None:
    """Print ``error: <message>`` (unwrapped, no markup) on stderr and exit with code 2."""
    err_console.print("[red]error:[/red] ", end="")
    err_console.print(str(exc), markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(code=2)


def _fresh_option():
    return typer.Option(False, "--fresh", help="Start over even when OUT holds a resumable run (the old results "
                        "stay until the new run is complete).")


@app.command()
def demo(
    out: Path = typer.Option(Path("out/demo"), help="Folder for the report, structure plot and traces."),
    seed: int = typer.Option(2026, help="Seed of every random number in the run."),
    method: str = typer.Option("vehicle", help="'vehicle': the nonlinear car at realistic noise, game-theoretic bank "
                               "and MHSSPRT; 'bank': the Beard-Jones bank on the linear App. D model at 1e-4 x nominal "
                               "noise; 'kalman': Kalman detection only (linear)."),
) -> None:
    """End-to-end diagnosis of faults on the PATH vehicle: detection, isolation, report."""
    from fdikit.studies.path1996.demo import check_demo_arguments, run_demo, run_kalman_demo
    from fdikit.studies.path1996.vehicle_demo import run_vehicle_demo

    try:
        check_demo_arguments(out=out, seed=seed, method=method)
    except (FdiError, OSError) as exc:
        _fail(exc)
    start = time.perf_counter()
    runners = {"vehicle": run_vehicle_demo, "bank": run_demo, "kalman": run_kalman_demo}
    with console.status("designing, calibrating on 10 min of fault-free data, diagnosing ..."):
        try:
            res = runners[method](out, seed=seed)
        except (FdiError, OSError) as exc:
            _fail(exc)
    titles = {"vehicle": "Nonlinear PATH car, rough road, realistic sensor noise: game-theoretic bank + MHSSPRT, "
                         "fault at t = 10 s",
              "bank": "PATH vehicle, bank of 4 Beard–Jones filters (15 faults), fault at t = 10 s"}
    if method in titles:
        table = Table(title=titles[method])
        for col in ("scenario", "detected", "delay", "isolated fault", "correct", "false alarms"):
            table.add_column(col, no_wrap=col == "isolated fault")
        for label, s in res.scores.items():
            table.add_row(label, "[green]yes[/green]" if s.detected else "[red]no[/red]",
                          f"{s.detection_delay:.2f} s" if s.detected else "—", s.isolated,
                          str(s.isolation_correct), str(s.false_alarms))
        ok = all(s.isolation_correct for s in res.scores.values())
    else:
        s = res.score
        table = Table(title="PATH 12-state vehicle, Kalman innovations — 0.02 rad/s yaw-rate sensor bias at t = 10 s")
        table.add_column("quantity")
        table.add_column("value", justify="right")
        table.add_row("fault detected", "[green]yes[/green]" if s.detected else "[red]no[/red]")
        table.add_row("detection delay", f"{s.detection_delay:.3f} s" if s.detected else "—")
        table.add_row("isolated fault", s.isolated)
        table.add_row("false alarms before onset", str(s.false_alarms))
        ok = s.detected
    console.print(table)
    if method != "vehicle":
        console.print(f"thresholds: 1 false alarm/h (α = {res.evaluator.alpha:.2e} per sample)")
    for name, path in res.files.items():
        console.print(f"wrote {name}: {path}")
    console.print(f"done in {time.perf_counter() - start:.1f} s")
    if not ok:
        raise typer.Exit(code=1)


@app.command()
def plants() -> None:
    """List the benchmark plants."""
    import inspect

    from fdikit.plants import PLANTS

    table = Table(title="benchmark plants")
    for col in ("name", "parameters", "description"):
        table.add_column(col)
    for name, fn in PLANTS.items():
        params = ", ".join(str(p) for p in inspect.signature(fn).parameters.values())
        table.add_row(name, params or "—", (fn.__doc__ or "").strip().splitlines()[0])
    console.print(table)


@app.command()
def simulate(
    plant: str = typer.Argument(..., help="Plant name (see `fdikit plants`)."),
    fault: list[str] = typer.Option([], "--fault", "-f",
                                    help="Fault spec kind:target[:value][@onset[-end]][#sensor|#actuator], "
                                         "e.g. bias:yaw_rate:0.02@10."),
    duration: float = typer.Option(30.0, help="Simulated time [s]."),
    dt: float = typer.Option(0.01, help="Sample time [s]."),
    noise_std: float = typer.Option(0.0, "--noise-std",
                                    help="Measurement noise standard deviation, the same on every output."),
    seed: int = typer.Option(0, help="Random seed."),
    param: list[str] = typer.Option([], "--param", "-p", help="Plant parameter name=value, e.g. speed=20."),
    out: Path = typer.Option(Path("out/trace.parquet"), help="Parquet file to write."),
) -> None:
    """Simulate a named plant under faults and save the trace as Parquet."""
    from fdikit.fault_spec import parse_fault
    from fdikit.faults import FaultScenario
    from fdikit.plants import get_plant
    from fdikit.resume import check_nonnegative, check_output_file, check_positive, check_seed
    from fdikit.simulate import simulate as run

    try:
        duration = check_positive(duration, "duration", hint=" s")
        dt = check_positive(dt, "dt", hint=" s")
        if dt > duration:
            raise ParameterError(f"dt (--dt) = {dt:g} s must not exceed duration (--duration) = {duration:g} s")
        noise_std = check_nonnegative(noise_std, "noise_std")
        seed = check_seed(seed)
        kw = _plant_params(plant, param)
        model = get_plant(plant, **kw)
        out = check_output_file(out)
        scenario = FaultScenario([parse_fault(s) for s in fault])
        with console.status(f"simulating {plant} for {duration:g} s ..."), warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always", FdiWarning)
            trace = run(model, scenario, duration=duration, dt=dt, measurement_noise_std=noise_std or None, rng=seed,
                        meta={"plant_name": plant, "plant_params": kw})
        for w in seen:  # one line each (a fault that never acts ...), not Python's warning format
            console.print(f"[yellow]warning:[/yellow] {w.message}")
        path = trace.save(out)
    except (FdiError, OSError) as exc:
        _fail(exc)
    console.print(f"{trace!r}\nwrote {path}")


def _plant_params(plant: str, param: list[str]) -> dict:
    """``--param name=value`` pairs: numbers, or text for a parameter annotated ``str``."""
    import inspect
    import math

    from fdikit.plants import PLANTS

    signature = inspect.signature(PLANTS[plant]) if plant in PLANTS else None
    kw: dict = {}
    for p in param:
        key, sep, value = p.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise ParameterError(f"--param needs name=value (e.g. speed=20), got {p!r}")
        if key in kw:
            raise ParameterError(f"--param {key} is given twice; give each parameter once")
        annotation = None
        if signature is not None and key in signature.parameters:
            annotation = signature.parameters[key].annotation
        if annotation in (str, "str"):
            kw[key] = value
            continue
        try:
            number = float(value)
        except ValueError:
            raise ParameterError(f"--param {key}={value}: {value!r} is not a number") from None
        if not math.isfinite(number):
            raise ParameterError(f"--param {key}={value}: the value must be finite")
        kw[key] = number
    return kw


@app.command("compare-evaluators")
def compare_evaluators(
    runs_per_fault: int = typer.Option(2, help="Test runs per fault (15 faults)."),
    healthy_runs: int = typer.Option(5, help="Fault-free test runs."),
    seed: int = typer.Option(0, help="Seed of the training and test runs."),
    bnn: bool = typer.Option(True, help="Include the Bayesian neural network (slowest to train)."),
    evaluators: str = typer.Option(None, help="Comma-separated evaluators to compare (default: all): threshold, "
                                   "cusum, glr, sprt, cusum-whitened, glr-whitened, sprt-whitened, mhsprt, "
                                   "gaussian-ml, bnn."),
    out: Path = typer.Option(Path("out/compare"), help="Folder for scores.csv and comparison.md."),
    fresh: bool = _fresh_option(),
) -> None:
    """Score every residual evaluator on the same PATH bank residuals and tabulate them side by side.

    Each test run's scores are stored in OUT as soon as the run is scored; rerunning the same command
    after an interruption resumes where it stopped.
    """
    from fdikit.studies.path1996.compare import check_comparison_arguments, path_evaluator_comparison

    start = time.perf_counter()
    try:
        chosen = None if evaluators is None else evaluators.split(",")
        check_comparison_arguments(runs_per_fault, healthy_runs, seed, bnn, evaluators=chosen)
        result = path_evaluator_comparison(runs_per_fault, healthy_runs, seed, out, progress=True, bnn=bnn,
                                           evaluators=chosen, fresh=fresh)
    except (FdiError, OSError) as exc:
        _fail(exc)
    table = Table(title=f"PATH bank residuals: {runs_per_fault} runs per fault, {healthy_runs} fault-free runs")
    table.add_column("evaluator", no_wrap=True)
    for col in result.table.columns:
        table.add_column(col, justify="right")
    for name, row in result.table.iterrows():
        table.add_row(name, *[f"{v:.3g}" if isinstance(v, float) else str(v) for v in row])
    console.print(table)
    console.print(f"wrote {out / 'comparison.md'} and {out / 'scores.csv'} in {time.perf_counter() - start:.0f} s")


@app.command("path-evaluation")
def path_evaluation(
    out: Path = typer.Option(Path("out/path_evaluation"), help="Folder for table.md, rows.csv, table_2_1.md, "
                             "fig_2_6.png and residuals/."),
    hours: float = typer.Option(1.0, help="Length of each fault-free run per road (threshold setting, false-alarm "
                                "count) [h]."),
    seed: int = typer.Option(0, help="Seed of every run."),
    roads: str = typer.Option("smooth,rough", help="Comma-separated roads: smooth, rough."),
    faults: str = typer.Option(None, help="Comma-separated fault names (default all 15)."),
    banks: str = typer.Option(None, help="Comma-separated banks (default all): beard-jones, game, kalman."),
    processors: str = typer.Option(None, help="Comma-separated processors (default threshold, cusum-whitened, "
                                   "mhsprt-whitened; 'mhsprt' adds the raw MHSSPRT)."),
    fresh: bool = _fresh_option(),
) -> None:
    """The PATH Ch. 5 evaluation on the nonlinear car at realistic sensor noise (Douglas et al. 1996, §5.1).

    Designs the Beard-Jones and the game-theoretic banks from the car's own linearised, reduced model, runs
    every nominal fault on each road, scores four residual processors on both banks and writes the table,
    residual plots, Table 2.1 and Fig. 2.6.  Each road's results are kept in OUT as soon as the road is done;
    rerunning the same command after an interruption resumes.
    """
    from fdikit.resume import RunStore
    from fdikit.studies.path1996.nonlinear_evaluation import evaluation_setup
    from fdikit.studies.path1996.nonlinear_report import write_path_evaluation
    from fdikit.studies.path1996.nonlinear_table import check_evaluation_arguments, path_evaluation_table

    start = time.perf_counter()
    try:
        args = check_evaluation_arguments(roads=roads.split(","), fault_free_hours=hours, seed=seed,
                                          faults=None if faults is None else faults.split(","),
                                          banks=None if banks is None else banks.split(","),
                                          processors=None if processors is None else processors.split(","))
        store = RunStore(out, "path-evaluation", args, fresh=fresh)
        setup = evaluation_setup()
        table = path_evaluation_table(setup, progress=True, keep_runs=True, store=store, **args)
        write_path_evaluation(out, table, setup)
    except (FdiError, OSError) as exc:
        _fail(exc)
    summary = Table(title="PATH Ch. 5 on the nonlinear car (realistic sensor noise)")
    for col in ("road", "bank", "processor", "detected", "isolated", "false alarms / h"):
        summary.add_column(col)
    for (road, bank, proc), (det, iso, n) in sorted(table.counts().items()):
        summary.add_row(road, bank, proc, f"{det}/{n}", f"{iso}/{n}", f"{table.rate(road, bank, proc):.3g}")
    console.print(summary)
    console.print(f"wrote {out} in {time.perf_counter() - start:.0f} s")


@app.command("target-tracking")
def target_tracking(
    runs: int = typer.Option(100, help="Monte-Carlo runs (Hallouzi 2008 §2.4.2 uses 100)."),
    seed: int = typer.Option(0, help="Seed of the first run."),
    out: Path = typer.Option(Path("out/target_tracking"), help="Folder for summary.md and rmse.png."),
    fresh: bool = _fresh_option(),
) -> None:
    """Convex-model filters vs the IMM on the maneuvering-target benchmark (Hallouzi 2008, §2.4.2).

    The sums of every chunk of runs (at most 10) are kept in OUT as they complete; a killed run resumes
    when rerun with the same arguments.
    """
    from rich.progress import Progress

    from fdikit.resume import RunStore, check_count, check_seed
    from fdikit.studies.hallouzi2008.target_tracking import plot_target_tracking, target_tracking_monte_carlo

    start = time.perf_counter()
    try:
        check_count(runs, "runs")
        check_seed(seed)
        store = RunStore(out, "target-tracking", {"runs": runs, "seed": seed}, fresh=fresh)
        with Progress(console=console, transient=True) as bar:
            task = bar.add_task(f"target tracking: {runs} Monte-Carlo runs", total=runs)
            result = target_tracking_monte_carlo(runs=runs, seed=seed, store=store,
                                                 progress=lambda done: bar.update(task, completed=done))
    except (FdiError, OSError) as exc:
        _fail(exc)
    intervals = list(next(iter(result.summary.values())))
    table = Table(title=f"mean RMSE per interval over {runs} runs: position [m] / velocity [m/s] / B")
    table.add_column("filter", no_wrap=True)
    for iv in intervals:
        table.add_column(str(iv), justify="right")
    lines = ["| filter | " + " | ".join(map(str, intervals)) + " |", "|---" * (len(intervals) + 1) + "|"]
    for name, per in result.summary.items():
        cells = [f"{v['position']:.1f} / {v['velocity']:.2f} / {v['B']:.2f}" for v in per.values()]
        table.add_row(name, *cells)
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    console.print(table)
    try:
        png = io.BytesIO()
        plot_target_tracking(result, png)
        store.publish({"rmse.png": png.getvalue(), "summary.md": "\n".join(lines) + "\n"})
    except (FdiError, OSError) as exc:
        _fail(exc)
    console.print(f"wrote {out / 'summary.md'} and {out / 'rmse.png'} in {time.perf_counter() - start:.0f} s")


@app.command("multiple-model")
def multiple_model(
    runs: int = typer.Option(100, help="Monte-Carlo runs of the tracking and B747 parts (Hallouzi 2008 uses 100)."),
    seed: int = typer.Option(0, help="Master seed."),
    msd_dt: float = typer.Option(0.01, help="MSD sample time [s] (thesis 2.5e-3; at most 0.02)."),
    model_sets: int = typer.Option(15, help="Random model sets of Example 3.1 (thesis: 15)."),
    out: Path = typer.Option(Path("out/multiple_model"), help="Folder for summary.md and the plots."),
    fresh: bool = _fresh_option(),
) -> None:
    """Hallouzi 2008 items 17–20: target tracking, B747, Example 3.1 and the MSD model sets, with plots.

    Each finished item is stored in OUT at once; rerunning the same command after an interruption
    resumes where it stopped.  summary.md is written when all four items are done.
    """
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from fdikit.resume import check_output_folder
    from fdikit.studies.hallouzi2008.report import check_multiple_model_arguments, multiple_model_report

    try:
        check_multiple_model_arguments(runs=runs, seed=seed, msd_dt=msd_dt, model_sets=model_sets)
        check_output_folder(out)
    except (FdiError, OSError) as exc:
        _fail(exc)
    start = time.perf_counter()
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=console) as bar:
        task = bar.add_task("starting", total=4)

        def step(name: str) -> None:
            if bar.tasks[task].description != "starting":
                bar.advance(task)
            bar.update(task, description=name)

        try:
            summary = multiple_model_report(out, runs=runs, seed=seed, msd_dt=msd_dt, model_sets=model_sets,
                                            progress=step, fresh=fresh)
        except (FdiError, OSError) as exc:
            _fail(exc)
        bar.advance(task)
    console.print(summary.read_text())
    console.print(f"wrote {summary} and the plots in {time.perf_counter() - start:.0f} s")


@app.command("b747")
def b747(
    out: Path = typer.Option(Path("out/b747"), help="Folder for table.md, rows.csv, report.html and the plots."),
    step: float = typer.Option(0.5, help="Lock-position step of the sweep [deg] (thesis: 0.5; 81 + 61 + 101 runs)."),
    hours: float = typer.Option(1.0, help="Fault-free flight for the false-alarm count [h]."),
    seed: int = typer.Option(0, help="Base seed of the sweep and the fault-free flights."),
    surfaces: str = typer.Option("elevator,aileron,rudder", help="Comma-separated surfaces to sweep."),
    noise: str = typer.Option("thesis_cov", help="Sensor-noise preset: thesis_cov ((4.4) as covariances) or "
                              "thesis_std (Table 6.2 as standard deviations)."),
    turbulence: int = typer.Option(3, help="MIL-F-8785C turbulence severity 0-7 (3: light)."),
    fresh: bool = _fresh_option(),
) -> None:
    """Hallouzi 2008 Ch. 4 on the JSBSim B747: Table 4.8 (lock-in-place sweep, IMM with model set II) and Table 4.6.

    Trims JSBSim's B747 at 980 m / 92.6 m/s / flaps 20 / 263 t, builds model set II from it, identifies
    the IMM's process noise on a fault-free turbulent flight, counts false alarms on HOURS of fault-free
    flight, then flies every lock position and writes the table next to the thesis's, the rows, the plots
    (surface position, mode probabilities, altitude of one run per surface) and report.html; then the
    linear §4.4.1 run with model set I (Table 4.6, Fig. 4.3).  Each run is kept in OUT as soon as it is
    done; rerunning resumes.
    """
    import base64

    from fdikit import validate
    from fdikit.resume import RunStore, check_seed
    from fdikit.studies.hallouzi2008.b747_lip import NOISE_PRESETS, false_alarm_rate, fly_lip, lip_setup
    from fdikit.studies.hallouzi2008.b747_report import table_4_6_files, write_b747_report
    from fdikit.studies.hallouzi2008.table_4_6 import run_table_4_6
    from fdikit.studies.hallouzi2008.table_4_8 import SWEEP_RANGES, table_4_8

    start = time.perf_counter()
    try:
        names = [validate.choice("--surfaces", s.strip(), list(SWEEP_RANGES)) for s in surfaces.split(",")]
        validate.choice("--noise", noise, sorted(NOISE_PRESETS))
        validate.in_range("--turbulence", validate.integer("--turbulence", turbulence, minimum=0), 0, 7)
        step = validate.positive("--step", step)
        hours = validate.non_negative("--hours", hours)
        check_seed(seed)
        args = {"step": step, "hours": hours, "seed": seed, "surfaces": names, "noise": noise,
                "turbulence": turbulence}
        store = RunStore(out, "b747", args, fresh=fresh)
        with console.status("trimming the B747, building model set II, identifying the process noise ..."):
            setup = lip_setup(noise=noise, turbulence=turbulence)
        fa = None
        if hours > 0:
            fa = store.load("false-alarms")
            if fa is None:
                with console.status(f"{hours:g} h of fault-free flight ..."):
                    fa = false_alarm_rate(setup, hours, seed=seed * 1000 + 1)
                store.save("false-alarms", list(fa))
            fa = tuple(fa)
        table = table_4_8(setup, step=step, surfaces=names, seed=seed, store=store, progress=True)
        examples = []
        for s in names:
            rows = [r for r in table.rows if r.surface == s]
            pick = min(rows, key=lambda r: abs(r.lock - (SWEEP_RANGES[s][1] * 0.5)))
            examples.append(fly_lip(setup, s, pick.lock, seed=pick.seed))
        linear = store.load("table-4-6")
        if linear is None:
            with console.status("Table 4.6: the linear run with model set I ..."):
                md, png = table_4_6_files(run_table_4_6(seed=seed))
            linear = {"markdown": md, "png": base64.b64encode(png).decode("ascii")}
            store.save("table-4-6", linear)
        write_b747_report(out, table, setup, examples, fa, (linear["markdown"], base64.b64decode(linear["png"])))
    except (FdiError, OSError) as exc:
        _fail(exc)
    summary = Table(title="Hallouzi 2008 Table 4.8 on the JSBSim B747 (fdikit / thesis)")
    summary.add_column("")
    for s in table.summary():
        summary.add_column(s)
    from fdikit.studies.hallouzi2008.table_4_8 import THESIS_TABLE_4_8

    for key in ("correct", "incorrect", "missed", "false alarm", "delay"):
        unit = " s" if key == "delay" else " %"
        summary.add_row(key, *(f"{e[key]:.1f}{unit} / {THESIS_TABLE_4_8[s][key]:.1f}{unit}"
                               for s, e in table.summary().items()))
    console.print(summary)
    if fa is not None:
        console.print(f"false alarms: {fa[0]} in {fa[1]:.2f} h of fault-free flight")
    console.print(f"wrote {out} in {time.perf_counter() - start:.0f} s ({len(table.rows)} runs)")


@app.command("ftc")
def ftc(
    out: Path = typer.Option(Path("out/ftc"), help="Folder for the plots and tables (the B747 flights in OUT/b747)."),
    quick: bool = typer.Option(False, help="Shorter runs: MSD 300 s / 100 s, window 250; B747 flights 120 s."),
    msd: bool = typer.Option(True, help="Run the §5.4 MSD experiments."),
    b747: bool = typer.Option(True, help="Run the §6.5 B747 flights (JSBSim)."),
    seed: int = typer.Option(1, help="Turbulence and sensor-noise seed of the B747 flights."),
    fresh: bool = typer.Option(False, help="Start the B747 flights over instead of resuming OUT/b747."),
) -> None:
    """Hallouzi 2008 Ch. 5–6: adaptive SPC on the MSD, and fault-tolerant flight of the B747.

    §5.4: the SPC (predictor re-identified every step on a receding window) and an MPC with a frozen
    predictor track y1 and y3 while k1 and m3 drift and a 0.25 s input delay appears at 200 s; then the SPC
    with and without the persistency-of-excitation term (responses, inputs, rcond of [R21 R22], RMSE table).
    §6.5: the B747 flies the hold–turn–descent plan nominally, with an elevator lock at 1.9° and a rudder
    runaway to 25° (both at 18 s) and the Bijlmerramp engine loss, by the FTC (closed-loop SPC reconfigured
    by the IMM), by the SPC without reconfiguration and by the fixed LQR autopilot (responses, surfaces,
    mode probabilities, rcond(R11), a table and report.html).  Each flight is kept as soon as it is done;
    rerunning resumes.
    """
    from fdikit.resume import check_seed

    start = time.perf_counter()
    try:
        check_seed(seed)
        if not (msd or b747):
            raise ParameterError("--no-msd and --no-b747 leave nothing to run; drop one of them.")
        if msd:
            from fdikit.studies.hallouzi2008.spc_msd import write_msd_ftc

            with console.status("§5.4: SPC and fixed MPC on the MSD, then the excitation runs ...") as status:
                write_msd_ftc(out, quick=quick, progress=lambda msg: status.update(msg))
            console.print((out / "msd_ftc_rmse.md").read_text())
        if b747:
            from fdikit.studies.hallouzi2008.b747_ftc_report import write_b747_ftc

            with console.status("§6.5: B747 flights ...") as status:
                write_b747_ftc(out / "b747", quick=quick, seed=seed, fresh=fresh,
                               progress=lambda msg: status.update(f"§6.5: {msg}"))
            console.print((out / "b747" / "ftc_b747.md").read_text(), markup=False, soft_wrap=True)
    except (FdiError, OSError) as exc:
        _fail(exc)
    console.print(f"wrote {out} in {time.perf_counter() - start:.0f} s")


@app.command("design")
def design(
    spec: str = typer.Argument(..., help="The design spec: a YAML file, a .py file or an importable module name "
                               "(model, filters, log, calibration; see docs/tutorial.md)."),
    healthy: list[Path] = typer.Option(..., "--healthy", help="A fault-free CSV log to calibrate the thresholds on "
                                       "(repeat for several runs)."),
    out: Path = typer.Option(Path("detector.json"), "--out", "-o", help="The detector file to write."),
    key: str = typer.Option(None, "--key", envvar="FDIKIT_DETECTOR_KEY", help="Secret for an HMAC-signed file "
                            "(default a plain SHA-256 digest)."),
) -> None:
    """Design a detector from a model spec, calibrate it on fault-free logs, write it to a detector file."""
    from fdikit.detector_spec import build_detector, load_spec

    try:
        det = build_detector(load_spec(spec), healthy)
        det.save(out, key=key)
    except (FdiError, OSError) as exc:
        _fail(exc)
    ev = det.evaluator
    table = Table(title=f"{det.name}: {len(det.generator.residuals)} residuals, thresholds on {len(healthy)} log(s)")
    for col in ("residual", "threshold"):
        table.add_column(col)
    for nm, tau in zip(ev.names, ev.thresholds):
        table.add_row(nm, f"{tau:.4g}")
    console.print(table)
    cal = ev.calibration
    lo, hi = cal.interval
    console.print(f"calibration: {cal.alarms} alarm(s) in {cal.hours:.3g} h of fault-free logs ({cal.runs} run(s)): "
                  f"{cal.rate:.3g}/h, {cal.confidence:.0%} interval [{lo:.3g}, {hi:.3g}]/h (target "
                  f"{cal.target_rate:g}/h); these logs cannot resolve a rate below {cal.min_resolvable_rate:.3g}/h")
    sig = ev.signatures
    if sig is not None and sig.indistinguishable:
        console.print(f"faults the bank cannot tell apart: {[list(s) for s in sig.indistinguishable]}")
    console.print(f"wrote {out}")


@app.command("diagnose")
def diagnose(
    detector: Path = typer.Argument(..., help="A detector file (fdikit design)."),
    logs: list[Path] = typer.Argument(..., help="CSV log(s) to diagnose."),
    out: Path = typer.Option(Path("out/diagnosis"), "--out", "-o", help="Folder for diagnosis.csv, alarms.csv and "
                             "report.html (one sub-folder per log when several)."),
    key: str = typer.Option(None, "--key", envvar="FDIKIT_DETECTOR_KEY", help="The secret of an HMAC-signed file."),
) -> None:
    """Diagnose logs with a saved detector: a per-sample diagnosis table and an HTML report with the residuals."""
    from fdikit.detector import Detector
    from fdikit.diagnosis_report import write_diagnosis

    try:
        det = Detector.load(detector, key=key)
        traces = [det.read_log(p) for p in logs]
    except (FdiError, OSError) as exc:
        _fail(exc)
    table = Table(title=f"diagnosis by {det.name}")
    for col in ("log", "alarms", "first alarm [s]", "fault named at it", "report"):
        table.add_column(col)
    for path, trace in zip(logs, traces):
        folder = out if len(logs) == 1 else out / path.name.split(".")[0]
        try:
            diag, files = write_diagnosis(folder, det, trace, log_name=path.name)
        except (FdiError, OSError) as exc:
            _fail(exc)
        first = diag.first_alarm()
        table.add_row(path.name, str(len(diag.alarms)), "-" if first is None else f"{first.time:g}",
                      "-" if first is None else first.fault, str(files["report"]))
    console.print(table)


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
