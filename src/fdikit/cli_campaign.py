"""``fdikit campaign``: run a campaign spec, resume it, report on it (:mod:`fdikit.campaign`)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from fdikit.errors import FdiError

__all__ = ["campaign_app"]

campaign_app = typer.Typer(help="Monte Carlo campaigns: plants × faults × designs × evaluators, resumable, "
                           "on a process pool or a Dask cluster.", no_args_is_help=True)
console = Console()
err_console = Console(stderr=True)


def _fail(exc: Exception) -> None:
    err_console.print("[red]error:[/red] ", end="")
    err_console.print(str(exc), markup=False, highlight=False, soft_wrap=True)
    raise typer.Exit(code=2)


@campaign_app.command("run")
def run(
    spec: str = typer.Argument(..., help="A campaign spec (YAML file) or the name of a shipped one "
                               "(`fdikit campaign list`)."),
    out: Path = typer.Option(None, "--out", "-o", help="Results folder (default out/campaign/<name>)."),
    workers: int = typer.Option(None, "--workers", "-j", help="Worker processes (default: the CPU count)."),
    backend: str = typer.Option("local", "--backend", help="local (process pool) or dask (distributed)."),
    scheduler: str = typer.Option(None, "--scheduler", help="Address of a running Dask scheduler, e.g. "
                                  "tcp://10.0.0.5:8786 (implies --backend dask)."),
    fresh: bool = typer.Option(False, "--fresh", help="Replace the results of another spec in OUT (kept until the "
                               "new campaign is complete)."),
    progress: bool = typer.Option(True, help="Show a progress bar with the time remaining."),
    report: bool = typer.Option(True, help="Write OUT/report.html when the campaign is complete."),
) -> None:
    """Run a campaign (or resume it: finished chunks are kept; rerun the same command after a kill)."""
    from fdikit.campaign.engine import run_campaign
    from fdikit.campaign.spec import load_campaign

    try:
        checked = load_campaign(spec)
        folder = out if out is not None else Path("out/campaign") / checked.name
        done = run_campaign(checked, folder, workers=workers, backend=backend, scheduler=scheduler, fresh=fresh,
                            progress=progress, say=lambda msg: console.print(msg, markup=False))
        console.print(f"{done.runs} runs in {done.chunks} chunks ({done.computed} computed, {done.reused} resumed) "
                      f"on {done.workers} {done.backend} worker(s) in {done.seconds:.1f} s → {folder}")
        _summary(folder)
        if report:
            _report(folder, examples=2)
    except (FdiError, OSError) as exc:
        _fail(exc)


def _summary(folder: Path) -> None:
    from fdikit.campaign.stats import campaign_statistics
    from fdikit.campaign.store import load_results

    manifest, table = load_results(folder)
    stats = campaign_statistics(table, manifest["levels"])
    view = Table(title=f"campaign {manifest['name']}: {manifest['runs']} runs ({stats.confidence:.0%} intervals)")
    for col in ("design", "evaluator", "detection rate", "median delay [s]", "isolation rate", "false alarms [1/h]"):
        view.add_column(col)
    for _, r in stats.overall.iterrows():
        view.add_row(str(r["design"]), str(r["evaluator"]),
                     f"{r['detection_rate']:.3f} [{r['detection_low']:.3f}, {r['detection_high']:.3f}]",
                     f"{r['delay_median']:.3g}",
                     f"{r['isolation_rate']:.3f} [{r['isolation_low']:.3f}, {r['isolation_high']:.3f}]",
                     f"{r['false_alarm_rate']:.3g} [{r['false_alarm_rate_low']:.3g}, {r['false_alarm_rate_high']:.3g}]")
    console.print(view)


def _report(folder: Path, examples: int) -> Path:
    from fdikit.campaign.engine import replay
    from fdikit.campaign.report import write_report

    page = write_report(folder, replay=lambda run, design, evaluator: replay(folder, run, design, evaluator),
                        examples=examples, progress=True)
    console.print(f"wrote {page}")
    return page


@campaign_app.command("report")
def report_cmd(
    folder: Path = typer.Argument(..., help="A campaign's results folder."),
    examples: int = typer.Option(2, help="Example traces per design × evaluator (re-simulated from their seeds)."),
) -> None:
    """Write FOLDER/report.html: rates with intervals, delays, false alarms, confusion, trade-off, example traces."""
    from fdikit.resume import check_count

    try:
        check_count(examples, "examples", 0)
        _report(folder, examples)
    except (FdiError, OSError) as exc:
        _fail(exc)


@campaign_app.command("list")
def list_specs() -> None:
    """The shipped campaign specs and the registered studies."""
    from fdikit.campaign.plan import plan_runs
    from fdikit.campaign.spec import load_campaign
    from fdikit.campaign.studies import STUDIES, shipped_specs

    view = Table(title="shipped campaign specs")
    for col in ("name", "study", "runs", "designs × evaluators", "file"):
        view.add_column(col)
    try:
        for name, path in shipped_specs().items():
            spec = load_campaign(path)
            view.add_row(name, spec.study, str(len(plan_runs(spec))),
                         f"{len(spec.designs)} × {len(spec.evaluators)}", str(path))
    except FdiError as exc:
        _fail(exc)
    console.print(view)
    console.print("studies: " + ", ".join(STUDIES))
