"""The speed-scheduled parity filter on a *measured* (noisy) speed: time per 30 s trace and residual noise.

A wheel-speed-derived speed is new at every sample, so the exact path evaluates ``family(ρ)`` (and for a
family without ``dae_matrices`` its ZOH discretisation, :func:`scipy.linalg.expm`) once per sample; with the
true speed of a constant-speed run it does so once.  This script times, per 30 s trace at the plant's 100 Hz:

* the exact path and the ``grid=`` path (coefficients interpolated between nodes ``h`` apart), for the
  single-track family with its own ``dae_matrices`` (``single_track_lpv``) and for a generic family
  (``lambda v: single_track(v, dt=0.01).with_actuator_faults(["steering"])``, the path any user family takes);
* the residual rms (before the fault) on the noisy speed over that on the true speed, without and with the
  causal ``smoothing=`` of the schedule (low-pass and ramp-tracking kinds, several time constants).

The scenario is :func:`fdikit.studies.vanderploeg2018.scenarios.lateral_run` (open loop, curve
``κ = 1/350`` and bank 1.43° from 15 s, Table 4-2), at a constant 70 km/h and on a 70 → 100 km/h raised-cosine
ramp (5–25 s).  Noise: speed 0.05 and 0.1 m/s std (wheel-speed derived, the task's range; sensor-noise figures
give 0.05–0.1 rad/s per wheel); outputs yaw rate 5e-4 rad/s (automotive MEMS gyro, low end of
5e-4–2.5e-3 rad/s at 100 Hz), lateral error 0.01 m and heading error 1e-3 rad (camera: engineering
estimates, no datasheet figure).  The residual's sensitivity to a speed error grows with the lane error,
which drifts in this open-loop run, so the ratios depend on the scenario: read them as an example.

Run: ``python benchmarks/bench_scheduled.py [--repeat 1] [--quick]``.
"""

from __future__ import annotations

import argparse

import numpy as np

from fdikit.design.parity.scheduled import scheduled_parity_filter
from fdikit.plants.single_track import single_track, single_track_lpv
from fdikit.studies.vanderploeg2018.scenarios import lateral_run
from timing import best, cpu_name

KMH = 1 / 3.6
V70 = 70 * KMH
OUTPUT_NOISE = (5e-4, 0.01, 1e-3)


def generic_family(v):
    """A family without ``dae_matrices``: every ``ρ`` costs a FaultModel, a ZOH (scipy expm) and a DAE form."""
    return single_track(v, dt=0.01).with_actuator_faults(["steering"])


def ramp_kmh(t):
    s = np.clip((np.asarray(t) - 5.0) / 20.0, 0.0, 1.0)
    return 70.0 + 30.0 * (1 - np.cos(np.pi * s)) / 2


def rms(x):
    return float(np.sqrt(np.mean(x**2)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="skip the slow exact generic path")
    args = parser.parse_args()
    print(f"CPU: {cpu_name()}")
    rng = np.random.default_rng(2026)
    for label, speed_kmh in (("70 km/h", 70.0), ("ramp 70-100 km/h", ramp_kmh)):
        trace = lateral_run(30.0, speed_kmh=speed_kmh, measurement_noise_std=OUTPUT_NOISE, rng=rng)
        speed = trace.signal("speed")
        noisy = {sd: speed + sd * rng.standard_normal(speed.size) for sd in (0.05, 0.1)}
        print(f"\n== {label}: {len(trace)} samples, dt = {trace.dt} s")
        print("time per 30 s trace [s] (best of --repeat):")
        for fname, fam in (("single_track_lpv", single_track_lpv()), ("generic family", generic_family)):
            for grid in (None, 0.05):
                if fname == "generic family" and grid is None and args.quick:
                    continue
                for sname, sched in (("true speed", speed), ("noisy 0.1 m/s", noisy[0.1])):
                    def go(fam=fam, grid=grid, sched=sched, trace=trace):
                        return scheduled_parity_filter(fam, V70, grid=grid).run(trace, schedule=sched)
                    sec, _ = best(go, args.repeat)
                    print(f"  {fname:17s} grid={str(grid):5s} {sname:14s} {sec:8.3f}")
        gen = scheduled_parity_filter(single_track_lpv(), V70)
        exact = gen.run(trace, schedule=noisy[0.1]).r[:, 0]
        gridded = scheduled_parity_filter(single_track_lpv(), V70, grid=0.05).run(trace, schedule=noisy[0.1]).r[:, 0]
        print(f"grid 0.05 m/s vs exact (noisy speed): max |Δr| / max |r| = "
              f"{np.abs(gridded - exact).max() / np.abs(exact).max():.2e}")
        for scale in (1.0, 0.1):  # the output noise above, and ten times lower (where speed noise shows)
            run = lateral_run(30.0, speed_kmh=speed_kmh, measurement_noise_std=tuple(scale * np.array(OUTPUT_NOISE)),
                              rng=rng)
            base = rms(gen.run(run, schedule=speed).r[:, 0])  # the run has no fault: every sample
            print(f"output noise × {scale:g}: residual rms on the true speed {base:.3e}; ratio noisy / true:")
            for sd, sched in noisy.items():
                row = [f"none {rms(gen.run(run, schedule=sched).r[:, 0]) / base:5.2f}"]
                for kind in ("lowpass", "ramp"):
                    for tau in (0.1, 0.3, 1.0):
                        r = gen.run(run, schedule=sched, smoothing=tau, smoothing_kind=kind).r[:, 0]
                        row.append(f"{kind} τ={tau:g} {rms(r) / base:5.2f}")
                print(f"  speed noise {sd:g} m/s: " + " | ".join(row))


if __name__ == "__main__":
    main()
