"""Per-sample cost of the residual evaluators, online (``step``) and in batch (``run``).

Synthetic residuals: 100,000 samples × 12 residuals in 4 fault groups of 3 (white N(0, 1),
a 1.5σ shift on group ``f1`` over the second half).  Each evaluator is calibrated on a
separate fault-free run, then timed on the same series in batch (best of ``--repeat``) and
online (one ``step`` per sample, once); the table also says whether the two gave the same
decisions.  The multiple-hypothesis SPRT and the BNN are trained on labelled runs of the
same generator (training time not counted); they are skipped, with the reason, when their
modules are not available or cannot be built.

Run: ``python benchmarks/bench_evaluators.py [--samples N] [--online-samples N]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from fdikit.decision.cusum import CusumEvaluator
from fdikit.decision.glr import GlrEvaluator
from fdikit.decision.sprt import SprtEvaluator
from fdikit.decision.threshold import ThresholdEvaluator
from fdikit.residuals import Residuals

GROUPS = 4
PER_GROUP = 3
SHIFT = 1.5


def residuals(n: int, seed: int, fault: str | None = None, onset: float = 0.5) -> Residuals:
    rng = np.random.default_rng(seed)
    q = GROUPS * PER_GROUP
    names = tuple(f"r{g}{i}" for g in range(GROUPS) for i in range(PER_GROUP))
    isolates = tuple(f"f{g}" for g in range(GROUPS) for _ in range(PER_GROUP))
    r = rng.standard_normal((n, q))
    if fault is not None:
        cols = [k for k, f in enumerate(isolates) if f == fault]
        r[int(onset * n) :, cols] += SHIFT
    return Residuals(np.arange(n) * 0.01, r, names, isolates)


def build(train_n: int) -> tuple[list, list]:
    """The evaluators to time, and the ones skipped with the reason."""
    healthy = residuals(train_n, seed=1)
    out = [
        ("ThresholdEvaluator (α = 1e-3)", ThresholdEvaluator().fit(healthy, false_alarm_prob=1e-3)),
        ("CusumEvaluator (ARL0 = 1e4, δ = 1.5σ)", CusumEvaluator().fit(healthy, arl0=1e4, shift=SHIFT)),
        ("GlrEvaluator (M = 50, 4 blocks of 3)", GlrEvaluator(window=50).fit(healthy, false_alarm_prob=1e-3)),
        ("GlrEvaluator (M = 50, 12 scalar)", GlrEvaluator(window=50, blocks="each").fit(healthy,
                                                                                          false_alarm_prob=1e-3)),
        ("SprtEvaluator (4 blocks of 3)", SprtEvaluator(shift=SHIFT, alpha=1e-3, beta=1e-3).fit(healthy)),
    ]
    skipped = []
    labelled = {"none": healthy, **{f"f{g}": residuals(train_n, seed=10 + g, fault=f"f{g}", onset=0.0)
                                    for g in range(GROUPS)}}
    try:
        from fdikit.decision.mhsprt import MhsprtEvaluator
    except ImportError as exc:
        skipped.append(("MhsprtEvaluator", f"not available ({exc})"))
    else:
        try:
            out.append(("MhsprtEvaluator (Gaussian densities)", MhsprtEvaluator().fit(labelled)))
        except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
            skipped.append(("MhsprtEvaluator", f"could not be built: {type(exc).__name__}: {exc}"))
    try:
        from fdikit.decision.learned.bnn import BnnEvaluator
    except ImportError as exc:
        skipped.append(("BnnEvaluator", f"not available ({exc})"))
    else:
        try:
            small = {k: v.slice(stop=v.t[0] + 20.0) for k, v in labelled.items()}
            out.append(("BnnEvaluator (trained briefly)", BnnEvaluator(max_iter=30, rm_steps=0, rng=0).fit(small)))
        except Exception as exc:  # noqa: BLE001
            skipped.append(("BnnEvaluator", f"could not be built: {type(exc).__name__}: {exc}"))
    return out, skipped


def time_batch(ev, res: Residuals, repeat: int):
    best, d = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        d = ev.run(res)
        best = min(best, time.perf_counter() - t0)
    return best, d


def time_online(ev, res: Residuals):
    ev.reset()
    rows = res.r
    fired = []
    t0 = time.perf_counter()
    for row in rows:
        fired.append(ev.step(row).fired)
    return time.perf_counter() - t0, np.array(fired)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--online-samples", type=int, default=None, help="samples stepped online (default: all)")
    ap.add_argument("--train-samples", type=int, default=50_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    res = residuals(args.samples, seed=0, fault="f1")
    n_on = args.online_samples or args.samples
    online_res = res.slice(stop=res.t[n_on - 1] + 1e-9) if n_on < args.samples else res
    evaluators, skipped = build(args.train_samples)

    import numpy
    import scipy

    import fdikit

    print(f"fdikit {fdikit.__version__ if hasattr(fdikit, '__version__') else '?'}, numpy {numpy.__version__}, "
          f"scipy {scipy.__version__}, Python {platform.python_version()}, {platform.machine()}")
    print(f"{args.samples:,} samples × {len(res.names)} residuals (online: {len(online_res):,} samples)\n")
    print("| evaluator | batch [µs/sample] | online [µs/sample] | online / batch | same decisions |")
    print("|---|---|---|---|---|")
    for name, ev in evaluators:
        tb, d = time_batch(ev, res, args.repeat)
        to, fired = time_online(ev, online_res)
        same = bool(np.array_equal(fired, d.fired[: len(online_res)]))
        ub, uo = tb / len(res) * 1e6, to / len(online_res) * 1e6
        print(f"| {name} | {ub:.2f} | {uo:.1f} | {uo / ub:.0f} | {'yes' if same else 'NO'} |")
    for name, why in skipped:
        print(f"| {name} | – | – | – | {why} |")


if __name__ == "__main__":
    main()
