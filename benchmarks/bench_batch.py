"""Batched execution over many traces: fdikit.batch vs a loop of run, plain numpy and scipy.signal.dlsim.

The demo's 12-state Kalman residual generator on the PATH vehicle (15 inputs: 3 controls + 12 measurements,
12 residuals) over R traces × N samples (default 1,000 × 1,000, each simulated from rest with its own noise
seed), then the 50-state PATH bank (29 residuals) on the same measurements, then the threshold and CUSUM
evaluators on the 12 residuals.
Each method is timed as the best of ``--repeat`` runs after one warm-up call (numba compiles, or loads its
on-disk cache, on the first call; that time is printed apart).  All outputs are checked against each other
before any figure is printed.

Run: ``python benchmarks/bench_batch.py`` (from the repository root).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numba
import numpy as np
import scipy
import scipy.signal

import fdikit
from fdikit.batch import cusum_batch, dlsim_batch, run_generator_batch, threshold_batch
from fdikit.decision import CusumEvaluator, ThresholdEvaluator
from fdikit.design import kalman
from fdikit.residuals import Residuals
from fdikit.simulate import simulate
from fdikit.studies.path1996.bank import path_bank
from fdikit.studies.path1996.demo import ACTUATOR_NOISE_STD, SENSOR_NOISE_STD, demo_model
from timing import best, cpu_name


def numpy_baseline(g, v: np.ndarray) -> np.ndarray:
    """The obvious vectorised code: one time loop over all traces at once."""
    R, N, _ = v.shape
    At, Bt, Ct, Dt = g.A.T, g.B.T, g.C.T, g.D.T
    x = np.zeros((R, g.n))
    r = np.empty((R, N, len(g.residuals)))
    for k in range(N):
        vk = v[:, k]
        r[:, k] = x @ Ct + vk @ Dt
        x = x @ At + vk @ Bt
    return r


def table(title: str, rows: list[tuple[str, float, float]], samples: int, base: str) -> None:
    print(f"\n{title}\n")
    print(f"| method | time [s] | samples/s | time / {base} | max rel. diff |")
    print("|---|---:|---:|---:|---:|")
    t_base = dict((name, t) for name, t, _ in rows)[base]
    for name, t, diff in rows:
        print(f"| {name} | {t:.3f} | {samples / t:,.0f} | {t / t_base:.2f} | {diff:.1e} |")


def timed(methods: dict, repeat: int) -> tuple[dict, dict]:
    """Warm-up (first-call) times and best-of-``repeat`` times and outputs of each method."""
    first, results = {}, {}
    for name, fn in methods.items():
        t0 = time.perf_counter()
        fn()
        first[name] = time.perf_counter() - t0
        results[name] = best(fn, repeat)
    return first, results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    R, N, dt = args.runs, args.samples, 0.01

    model = demo_model(dt)
    W = np.diag([ACTUATOR_NOISE_STD[c] ** 2 for c in model.controls])
    v_std = np.array([SENSOR_NOISE_STD[o] for o in model.outputs])
    gen = kalman(model, W, np.diag(v_std**2)).generator
    phases = np.random.default_rng(0).uniform(0, 2 * np.pi, R)
    traces = [simulate(model, duration=(N - 1) * dt, noise_cov=W, measurement_noise_std=v_std, rng=i,
                       u=lambda t, ph=ph: [np.sin(t + ph), 10 * np.sin(0.3 * t + ph), 1e-3 * np.sin(0.7 * t + ph)])
              for i, ph in enumerate(phases)]  # each run from rest, as the filter starts
    t = traces[0].t
    v = np.stack([gen.inputs_from(tr) for tr in traces])
    samples = R * N

    # ---------------------------------------------------------------- the 12-state generator
    methods = {
        "loop of ResidualGenerator.run over Trace objects": lambda: np.stack([gen.run(tr).r for tr in traces]),
        "numpy, vectorised over traces (time loop)": lambda: numpy_baseline(gen, v),
        "scipy.signal.dlsim per trace": lambda: np.stack(
            [scipy.signal.dlsim((gen.A, gen.B, gen.C, gen.D, dt), v[i])[1] for i in range(R)]),
        "fdikit dlsim_batch (numba)": lambda: dlsim_batch(gen.A, gen.B, gen.C, gen.D, v),
        "fdikit run_generator_batch (numba), array": lambda: run_generator_batch(gen, v),
        "fdikit run_generator_batch (blas), array": lambda: run_generator_batch(gen, v, method="blas"),
        "fdikit run_generator_batch (numba), from the Trace list": lambda: run_generator_batch(gen, traces),
    }
    first, res = timed(methods, args.repeat)
    ref = res["scipy.signal.dlsim per trace"][1]
    scale = np.abs(ref).max()
    rows = []
    for name, (tm, out) in res.items():
        diff = np.abs(out - ref).max() / scale
        assert diff < 1e-9, f"{name} disagrees with dlsim: {diff}"
        rows.append((name, tm, diff))
    r12 = res["fdikit run_generator_batch (numba), array"][1]
    del res

    # ---------------------------------------------------------------- the 50-state bank
    bank = path_bank().generator.discretize(dt)
    vb = np.stack([bank.inputs_from(tr) for tr in traces])
    bmethods = {
        "loop of ResidualGenerator.run over Trace objects": lambda: np.stack([bank.run(tr).r for tr in traces]),
        "numpy, vectorised over traces (time loop)": lambda: numpy_baseline(bank, vb),
        "fdikit run_generator_batch (numba)": lambda: run_generator_batch(bank, vb),
        "fdikit run_generator_batch (blas)": lambda: run_generator_batch(bank, vb, method="blas"),
    }
    bfirst, bres = timed(bmethods, args.repeat)
    bref = bres["loop of ResidualGenerator.run over Trace objects"][1]
    bscale = np.abs(bref).max()
    brows = []
    for name, (tm, out) in bres.items():
        diff = np.abs(out - bref).max() / bscale
        assert diff < 1e-9, f"{name} disagrees with run: {diff}"
        brows.append((name, tm, diff))
    del bres

    # ---------------------------------------------------------------- evaluators on the 12 residuals
    names = gen.residuals
    healthy = Residuals(t, r12[0], names, gen.isolates)
    fit = [Residuals(t, r12[i], names, gen.isolates) for i in range(10)]
    thr = ThresholdEvaluator(persistence=(3, 5)).fit(fit, false_alarm_prob=1e-3)
    thr1 = ThresholdEvaluator().fit(fit, false_alarm_prob=1e-3)
    cus = CusumEvaluator(restart="none").fit(fit, arl0=500.0, shift=2 * healthy.r.std(axis=0))
    each = [Residuals(t, r12[i], names, gen.isolates) for i in range(R)]
    erows, efirst = [], {}
    evaluators = (("threshold (1, 1)", thr1, threshold_batch), ("threshold k-of-n (3, 5)", thr, threshold_batch),
                  ("CUSUM two-sided, restart='none'", cus, cusum_batch))
    for label, ev, fn in evaluators:
        f, res = timed({"loop": lambda ev=ev: np.stack([ev.run(x).alarm for x in each]),
                        "batch": lambda ev=ev, fn=fn: fn(ev, r12)}, args.repeat)
        (t_loop, a_loop), (t_batch, d) = res["loop"], res["batch"]
        assert np.array_equal(a_loop, d.alarm), f"{label}: batch alarms differ from run"
        if getattr(ev, "hold", 0) == 0:
            assert np.array_equal(d.statistic > 1, d.alarm)
        erows.append((label, t_loop, t_batch, a_loop.mean()))
        efirst[label] = f["batch"]

    load = os.getloadavg()
    print(f"fdikit {fdikit.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, numba {numba.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}, {cpu_name()}, {os.cpu_count()} cores, "
          f"load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}")
    print(f"{R} traces x {N} samples = {samples:,} samples, best of {args.repeat}")
    table(f"12-state generator ({gen.B.shape[1]} inputs, {len(gen.residuals)} residuals); diff vs scipy.signal.dlsim",
          rows, samples, "numpy, vectorised over traces (time loop)")
    print("\nfirst call (numba compile or cache load): " + ", ".join(
        f"{k.split('fdikit ')[1]} {first[k]:.2f} s" for k in first if k.startswith("fdikit")))
    table(f"50-state PATH bank ({bank.B.shape[1]} inputs, {len(bank.residuals)} residuals); diff vs run",
          brows, samples, "numpy, vectorised over traces (time loop)")
    print(f"\nEvaluators on the 12 residuals ({R} x {N}); batch alarms equal the loop's at every sample\n")
    print("| evaluator | loop of run [s] | batch [s] | batch samples/s | speed-up | alarmed samples |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, t_loop, t_batch, frac in erows:
        print(f"| {label} | {t_loop:.3f} | {t_batch:.3f} | {samples / t_batch:,.0f} | {t_loop / t_batch:.1f}x | "
              f"{frac:.2%} |")


if __name__ == "__main__":
    main()
