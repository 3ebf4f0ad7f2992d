"""A 10^4-run PATH campaign on 2 cores: the campaign engine on 1 and 2 workers and on Dask, against the hand loop.

The campaign is ``benchmarks/path_10k.yaml`` (linear PATH plant, 20-s runs at 100 Hz, the Beard–Jones bank,
thresholds, realistic noise).  The peer is what the studies did before the engine and what a user would
write: one Python loop of simulate → ``generator.run`` → ``evaluator.run`` → ``metrics.score`` in one
process (timed on ``--loop-runs`` runs, its per-run time extrapolated to 10^4).  Each engine run writes
into a fresh folder; the chunk files of every engine run are checked byte-identical before any time is
printed.  Efficiency from 1 to 2 workers is ``T1 / (2 T2)``.

Run: ``python benchmarks/bench_campaign.py`` (about 10 minutes on the 2-core CI machine).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import fdikit
from timing import cpu_name

SPEC = Path(__file__).with_name("path_10k.yaml")


def digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted((folder / "runs").glob("*.parquet"))}


def hand_loop(spec, n: int) -> float:
    """Seconds per run of the single-process loop a study used to be (set-up excluded)."""
    from fdikit.campaign.plan import plan_runs
    from fdikit.metrics import score
    from fdikit.studies.path1996.campaign import PATH_LINEAR

    setup = PATH_LINEAR.setup(spec)
    runs = plan_runs(spec)[:n]
    t0 = time.perf_counter()
    for run in runs:
        trace, _, diag = PATH_LINEAR.replay(setup, spec, run, "beard-jones", "threshold")
        score(trace, diag)
    return (time.perf_counter() - t0) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--loop-runs", type=int, default=500)
    ap.add_argument("--runs", type=int, default=None, help="Override the spec's 10^4 runs (for a quick look).")
    args = ap.parse_args()
    from fdikit.campaign.engine import run_campaign
    from fdikit.campaign.spec import load_campaign
    from fdikit.campaign.stats import campaign_statistics
    from fdikit.campaign.store import load_results

    spec = load_campaign(SPEC)
    if args.runs:
        spec = spec.model_copy(update={"sampling": spec.sampling.model_copy(
            update={"random": spec.sampling.random.model_copy(update={"runs": args.runs})})})
    n = spec.sampling.random.runs
    per_run = hand_loop(spec, args.loop_runs)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, kw in (("engine, local, 1 worker", {"workers": 1}), ("engine, local, 2 workers", {"workers": 2}),
                          ("engine, Dask LocalCluster, 2 workers", {"workers": 2, "backend": "dask"})):
            folder = Path(tmp) / label.replace(" ", "_").replace(",", "")
            done = run_campaign(spec, folder, **kw)
            results[label] = (done.seconds, digests(folder))
        ref = results["engine, local, 1 worker"][1]
        assert len(ref) == done.chunks and all(d == ref for _, d in results.values()), "results differ"
        manifest, table = load_results(folder)
        stats = campaign_statistics(table, manifest["levels"])
    t1 = results["engine, local, 1 worker"][0]
    load = os.getloadavg()
    print(f"fdikit {fdikit.__version__}, numpy {np.__version__}, Python {platform.python_version()}, {cpu_name()}, "
          f"{os.cpu_count()} cores; load average before/after {load[0]:.2f}")
    print(f"{n} runs × {spec.duration:g} s at 100 Hz ({n * 2001:,} samples), 1 design × 1 evaluator, "
          f"chunks of {spec.chunk_size}; chunk files byte-identical across the three engine runs\n")
    print("| how | wall time [s] | runs/s | time / hand loop | efficiency vs 1 worker |")
    print("|---|---|---|---|---|")
    loop = per_run * n
    print(f"| hand loop, 1 process (timed on {args.loop_runs} runs, extrapolated) | {loop:.0f} | {1 / per_run:.0f} "
          "| 1.00 | |")
    for label, (t, _) in results.items():
        workers = 1 if "1 worker" in label else 2
        print(f"| {label} | {t:.0f} | {n / t:.0f} | {t / loop:.2f} | {t1 / (workers * t):.2f} |")
    row = stats.overall.iloc[0]
    print(f"\ndetection rate {row['detection_rate']:.3f} [{row['detection_low']:.3f}, {row['detection_high']:.3f}], "
          f"isolation rate {row['isolation_rate']:.3f}, false alarms {row['false_alarm_rate']:.3g}/h "
          f"[{row['false_alarm_rate_low']:.3g}, {row['false_alarm_rate_high']:.3g}]")


if __name__ == "__main__":
    main()
