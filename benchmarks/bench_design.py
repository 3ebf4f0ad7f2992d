"""PATH four-filter bank: design time, and the cost of running the bank on 100,000 samples.

Design is compared with the nearest thing a Python user has: plain observer pole placement
(`control.place`, no fault decoupling) for the same four models and spectra.  Running is
compared with `scipy.signal.dlsim` and `control.forced_response` on the same stacked,
discretised bank.  Run: ``python benchmarks/bench_design.py``.
"""

from __future__ import annotations

import argparse

import control
import numpy as np
import scipy.signal

from fdikit.model import sensor_fault_name
from fdikit.plants import path_vehicle_12, path_vehicle_14
from fdikit.simulate import simulate
from fdikit.studies.path1996 import path_bank, path_fault_model
from fdikit.studies.path1996.bank import EIGENVALUES
from timing import best


def place_all():
    for name, (sets, comp) in EIGENVALUES.items():
        m = path_vehicle_14("midpoint") if name == "filter4" else path_vehicle_12("midpoint")
        poles = np.concatenate([np.concatenate(sets), comp])
        control.place(m.A.T, m.C.T, poles)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    path_bank()  # warm imports
    t_design, bank = best(path_bank, args.repeat)
    t_place, _ = best(place_all, args.repeat)
    dt = 0.01
    plant = path_fault_model(14).discretize(dt)
    noise = 1e-4 * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    trace = simulate(plant, duration=(args.samples - 1) * dt, measurement_noise_std=noise, rng=0)
    gen = bank.generator.discretize(dt)
    v = gen.inputs_from(trace)
    runs = {
        "fdikit bank run (batch)": lambda: gen.run(trace).r,
        "fdikit bank online step": lambda: gen.online().run(trace).r,
        "scipy.signal.dlsim": lambda: scipy.signal.dlsim((gen.A, gen.B, gen.C, gen.D, dt), v, t=trace.t)[1],
        "control.forced_response": lambda: control.forced_response(gen.to_control(), T=trace.t, U=v.T).outputs.T,
    }
    res = {k: best(fn, args.repeat) for k, fn in runs.items()}
    ref = res["scipy.signal.dlsim"][1]
    print(f"bank: 4 filters, {gen.n} states, {len(gen.residuals)} residuals, {args.samples} samples, "
          f"best of {args.repeat}")
    print("\n| step | time | ratio |\n|---|---|---|")
    print(f"| design of the 4-filter bank (fdikit.studies.path1996.bank) | {t_design * 1e3:.0f} ms | "
          f"{t_design / t_place:.0f}x control.place of the same spectra ({t_place * 1e3:.1f} ms) |")
    base = res["fdikit bank run (batch)"][0]
    for k, (t, out) in res.items():
        diff = np.abs(out - ref).max() / np.abs(ref).max()
        assert diff < 1e-8, (k, diff)
        print(f"| {k} | {t:.3f} s ({t / args.samples * 1e6:.2f} µs/sample) | {t / base:.1f}x batch, "
              f"rel. diff {diff:.0e} |")


if __name__ == "__main__":
    main()
