"""Residual generation speed: fdikit batch and online vs python-control and scipy.signal, same system, same run.

The system is the demo's 12-state Kalman residual generator on the PATH vehicle
(15 inputs: 3 controls + 12 measurements, 12 residuals), driven by 100,000 samples.
Each method is timed as the best of ``--repeat`` runs; peak memory by tracemalloc.
All outputs are checked against each other before any figure is printed.

Run: ``python benchmarks/bench_simulate.py`` (or ``make bench``).
"""

from __future__ import annotations

import argparse
import platform
import tracemalloc

import control
import numpy as np
import scipy
import scipy.signal

import fdikit
from fdikit.design import kalman
from fdikit.simulate import simulate
from fdikit.studies.path1996.demo import ACTUATOR_NOISE_STD, SENSOR_NOISE_STD, demo_model
from timing import best


def peak_memory(fn) -> float:
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    model = demo_model(0.01)
    W = np.diag([ACTUATOR_NOISE_STD[c] ** 2 for c in model.controls])
    v_std = np.array([SENSOR_NOISE_STD[o] for o in model.outputs])
    gen = kalman(model, W, np.diag(v_std**2)).generator
    trace = simulate(model, duration=(args.samples - 1) * 0.01, noise_cov=W, measurement_noise_std=v_std, rng=0,
                     u=lambda t: [np.sin(t), 10 * np.sin(0.3 * t), 1e-3 * np.sin(0.7 * t)])
    v = gen.inputs_from(trace)
    sys_c = gen.to_control()
    N = len(trace)

    methods = {
        "fdikit ResidualGenerator.run (batch)": lambda: gen.run(trace).r,
        "fdikit ResidualStepper.step (online)": lambda: gen.online().run(trace).r,
        "control.forced_response": lambda: control.forced_response(sys_c, T=trace.t, U=v.T).outputs.T,
        "scipy.signal.dlsim": lambda: scipy.signal.dlsim((gen.A, gen.B, gen.C, gen.D, 0.01), v, t=trace.t)[1],
    }
    results = {}
    for name, fn in methods.items():
        t, out = best(fn, args.repeat)
        results[name] = (t, peak_memory(fn), out)

    ref = results["scipy.signal.dlsim"][2]
    scale = np.abs(ref).max()
    print(f"fdikit {fdikit.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
          f"control {control.__version__}, Python {platform.python_version()}, {platform.machine()}")
    print(f"12-state residual generator, {gen.B.shape[1]} inputs, {len(gen.residuals)} residuals, {N} samples, "
          f"best of {args.repeat}\n")
    print("| method | time [s] | samples/s | peak memory [MiB] | time / fdikit batch | max rel. diff vs dlsim |")
    print("|---|---|---|---|---|---|")
    base = results["fdikit ResidualGenerator.run (batch)"][0]
    for name, (t, mem, out) in results.items():
        diff = np.abs(out - ref).max() / scale
        assert diff < 1e-9, f"{name} disagrees with dlsim: {diff}"
        print(f"| {name} | {t:.3f} | {N / t:,.0f} | {mem:.1f} | {t / base:.1f} | {diff:.1e} |")


if __name__ == "__main__":
    main()
