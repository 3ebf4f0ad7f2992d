"""The ``fdikit`` command line."""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from fdikit.errors import FdiError

app = typer.Typer(help="fdikit: model-based fault detection and isolation for vehicles and aircraft.",
                  no_args_is_help=True, add_completion=False)
console = Console()


def _fail(exc: Exception) -> None:
    console.print(f"[red]error:[/red] {exc}")
    raise typer.Exit(code=2)


@app.command()
def demo(
    out: Path = typer.Option(Path("out/demo"), help="Folder for report.png and trace.parquet."),
    seed: int = typer.Option(2026, help="Seed of every random number in the run."),
) -> None:
    """End-to-end diagnosis of a yaw-rate sensor bias on the PATH vehicle (Kalman residuals + thresholds)."""
    from fdikit.demo import run_demo

    start = time.perf_counter()
    with console.status("simulating, calibrating thresholds on 10 min fault-free data, diagnosing ..."):
        try:
            res = run_demo(out, seed=seed)
        except FdiError as exc:
            _fail(exc)
    s = res.score
    table = Table(title="PATH 12-state vehicle — 0.02 rad/s yaw-rate sensor bias at t = 10 s")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("fault detected", "[green]yes[/green]" if s.detected else "[red]no[/red]")
    table.add_row("detection delay", f"{s.detection_delay:.3f} s" if s.detected else "—")
    table.add_row("isolated fault", s.isolated)
    table.add_row("isolation correct", str(s.isolation_correct))
    table.add_row("false alarms before onset", str(s.false_alarms))
    first = res.diagnosis.first_alarm(after=s.onset)
    table.add_row("residuals at first alarm", ", ".join(first.residuals) if first else "—")
    table.add_row("threshold calibration", f"1 false alarm/h (α = {res.evaluator.alpha:.2e} per sample)")
    console.print(table)
    for name, path in res.files.items():
        console.print(f"wrote {name}: {path}")
    console.print(f"done in {time.perf_counter() - start:.1f} s")
    if not s.detected:
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
                                    help="Fault spec kind:target[:value][@onset[-end]], e.g. bias:yaw_rate:0.02@10."),
    duration: float = typer.Option(30.0, help="Simulated time [s]."),
    dt: float = typer.Option(0.01, help="Sample time [s]."),
    noise: float = typer.Option(0.0, help="Measurement noise std, the same on every output."),
    seed: int = typer.Option(0, help="Random seed."),
    param: list[str] = typer.Option([], "--param", "-p", help="Plant parameter name=value, e.g. speed=20."),
    out: Path = typer.Option(Path("out/trace.parquet"), help="Parquet file to write."),
) -> None:
    """Simulate a named plant under faults and save the trace as Parquet."""
    from fdikit.faults import FaultScenario, parse_fault
    from fdikit.plants import get_plant
    from fdikit.simulate import simulate as run

    try:
        kw = {}
        for p in param:
            key, _, value = p.partition("=")
            if not value:
                raise typer.BadParameter(f"--param needs name=value, got {p!r}")
            kw[key] = float(value)
        model = get_plant(plant, **kw)
        scenario = FaultScenario([parse_fault(s) for s in fault])
        with console.status(f"simulating {plant} for {duration:g} s ..."):
            trace = run(model, scenario, duration=duration, dt=dt, measurement_noise=noise or None, rng=seed,
                        meta={"plant_name": plant, "plant_params": kw})
        path = trace.save(out)
    except FdiError as exc:
        _fail(exc)
    console.print(f"{trace!r}\nwrote {path}")


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
