"""Simulation speed of the nonlinear car: fdikit's compiled 1 kHz RK4 vs the Python loops a user would write.

fdikit: ``Sedan().simulate(--duration, start=op)`` at the 27 m/s straight run (22.555 % of 90° throttle),
1 kHz classical RK4 in one numba kernel, recorded at 100 Hz; timed after one warm-up call that compiles
(or loads the cache), best of ``--repeat``, on the smooth road, on a Robson road (PATH §2.1.2) and with
sensor noise plus a yaw-rate bias.  Real-time factor = simulated seconds / wall seconds.

Peers, on a ``--short`` run and scaled per simulated second (same start, same held commands):

* ``scipy.integrate.solve_ivp`` (RK45, rtol 1e-6, default atol) on ``car.derivatives(x, u)``;
* a hand-written fixed-step RK4 loop in Python at 1 kHz calling ``car.derivatives(x, u)`` (one compiled
  right-hand-side evaluation per call), on the smooth and the rough road (``road.heights`` under the wheels);
* the same RK4 loop with the right-hand side interpreted (``NUMBA_DISABLE_JIT=1``, in a child process) —
  what the model costs written as plain Python.

The Python RK4 loop and the compiled kernel do the same arithmetic in the same order: their final states on the
smooth road are asserted equal to rounding before any figure is printed.  One core: the thread variables are set
to 1 before numpy is imported.

Run: ``python benchmarks/bench_vehicle.py [--duration 600] [--short 5] [--repeat 3]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

THROTTLE = 0.22555 * 90  # deg: holds 27 m/s (Douglas et al. 1996, §8.3)
STEP = 1e-3


def make_rhs(car, u, road=None):
    """``f(x) = ẋ`` by ``car.derivatives`` with the commands held; road heights under the wheels when given."""
    wb = car.params.wheelbase

    def f(x):
        if road is None:
            return car.derivatives(x, u)[0]
        s = x[25]  # distance travelled: front wheels at s, rear at s - wheelbase (held at the start)
        fl, fr = road.heights(s)
        rl, rr = road.heights(max(s - wb, 0.0))
        return car.derivatives(x, u, road=(fl, fr, rl, rr))[0]

    return f


def python_rk4(car, op, duration: float, road=None) -> np.ndarray:
    """Fixed-step RK4 in Python on ``car.derivatives`` (commands held), the same operations as the kernel."""
    f, h = make_rhs(car, op.u, road), STEP
    x = op.x.copy()
    for _ in range(int(round(duration / h))):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def interpreted_peer(duration: float) -> None:
    """Child-process entry (``NUMBA_DISABLE_JIT=1``): time the Python RK4 loop on the interpreted model."""
    from fdikit.vehicle import Sedan

    car = Sedan()
    op = car.operating_point(throttle=THROTTLE)
    t0 = time.perf_counter()
    x = python_rk4(car, op, duration)
    print(json.dumps({"time": time.perf_counter() - t0, "x": x.tolist()}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--duration", type=float, default=600.0, help="simulated seconds of the fdikit runs")
    ap.add_argument("--short", type=float, default=5.0, help="simulated seconds of the Python peers")
    ap.add_argument("--interpreted", type=float, default=1.0, help="simulated seconds of the interpreted peer")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--child", type=float, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        interpreted_peer(args.child)
        return

    import numba
    import scipy
    from scipy.integrate import solve_ivp

    import fdikit
    from fdikit.faults import Bias, FaultScenario
    from fdikit.studies.path1996.demo import SENSOR_NOISE_STD
    from fdikit.vehicle import Sedan
    from fdikit.vehicle.road import robson_road
    from timing import best, cpu_name

    car = Sedan()
    op = car.operating_point(throttle=THROTTLE)
    # The run may travel 1.5x the start speed's distance (simulate_sedan's margin): 600 s needs ~24.3 km of road.
    road = robson_road(max(20000.0, 1.6 * 27.0 * args.duration + 100.0), rng=0)
    scenario = FaultScenario([Bias("yaw_rate", 0.02, onset=1.0)])
    t0 = time.perf_counter()
    car.simulate(1.0, start=op)  # compiles (or loads numba's cache)
    warm = time.perf_counter() - t0

    D = args.duration
    runs = {
        "fdikit Sedan.simulate, smooth road": lambda: car.simulate(D, start=op),
        "fdikit Sedan.simulate, Robson road": lambda: car.simulate(D, start=op, road=road),
        "fdikit Sedan.simulate, smooth, noise + yaw-rate bias": lambda: car.simulate(
            D, start=op, scenario=scenario, measurement_noise_std=SENSOR_NOISE_STD, rng=0),
    }
    rows = {}  # name -> (wall per simulated second, simulated seconds, wall, extra)
    for name, fn in runs.items():
        t, tr = best(fn, args.repeat)
        assert np.all(np.isfinite(tr.y)) and tr.y.shape == (int(round(D / 0.01)) + 1, 12)
        rows[name] = (t / D, D, t, "")
    base = rows["fdikit Sedan.simulate, smooth road"][0]

    # --- peers (short runs, best of repeat)
    S = args.short
    tr_s = car.simulate(S, start=op)
    tr_r = car.simulate(S, start=op, road=road)
    u = op.u
    nfev = {}

    def ivp(rd):
        f = make_rhs(car, u, rd)
        sol = solve_ivp(lambda t, x: f(x), (0.0, S), op.x, method="RK45", rtol=1e-6)
        assert sol.success, sol.message
        nfev["n"] = sol.nfev
        return sol.y[:, -1]

    t, x_ivp = best(lambda: ivp(None), args.repeat)
    rows["scipy solve_ivp RK45 (rtol 1e-6) on car.derivatives, smooth"] = (t / S, S, t, f"{nfev['n']} evaluations")
    t, x_ivpr = best(lambda: ivp(road), args.repeat)
    rows["scipy solve_ivp RK45 (rtol 1e-6) on car.derivatives, Robson road"] = (t / S, S, t,
                                                                                f"{nfev['n']} evaluations")
    t, x_rk = best(lambda: python_rk4(car, op, S), args.repeat)
    rows["Python RK4 loop (1 kHz) on car.derivatives, smooth"] = (t / S, S, t,
                                                                  f"{4 * int(round(S / STEP))} evaluations")
    t, x_rkr = best(lambda: python_rk4(car, op, S, road), args.repeat)
    rows["Python RK4 loop (1 kHz) on car.derivatives, Robson road"] = (t / S, S, t, "road.heights per evaluation")

    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, __file__, "--child", str(args.interpreted)], env=env, check=True,
                         capture_output=True, text=True, cwd=os.path.dirname(os.path.abspath(__file__)))
    child = json.loads(out.stdout.strip().splitlines()[-1])
    Si = args.interpreted
    rows["Python RK4 loop (1 kHz), interpreted model (NUMBA_DISABLE_JIT=1)"] = (child["time"] / Si, Si, child["time"],
                                                                              "child process")

    # --- agreement (before any figure is printed)
    scale = np.maximum(np.abs(tr_s.x[-1]), 1.0)
    d_rk = np.max(np.abs(x_rk - tr_s.x[-1]) / scale)
    assert d_rk < 1e-12, f"Python RK4 and the compiled RK4 disagree on the smooth road: {d_rk:.2e}"
    d_rkr = np.max(np.abs(x_rkr - tr_r.x[-1]) / np.maximum(np.abs(tr_r.x[-1]), 1.0))
    assert d_rkr < 1e-9, f"Python RK4 and the compiled RK4 disagree on the Robson road: {d_rkr:.2e}"
    tr_i = car.simulate(Si, start=op)
    d_int = np.max(np.abs(np.array(child["x"]) - tr_i.x[-1]) / np.maximum(np.abs(tr_i.x[-1]), 1.0))
    assert d_int < 1e-9, f"the interpreted model disagrees with the compiled one: {d_int:.2e}"
    d_ivp = np.max(np.abs(x_ivp - tr_s.x[-1]) / scale)
    d_ivpr = np.max(np.abs(x_ivpr - tr_r.x[-1]) / np.maximum(np.abs(tr_r.x[-1]), 1.0))

    print(f"fdikit {fdikit.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, numba {numba.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}, {cpu_name()}, one thread; "
          f"{time.strftime('%Y-%m-%d')}")
    print(f"27 m/s straight run, 1 kHz RK4 recorded at 100 Hz; fdikit {D:g} s simulated, peers {S:g} s "
          f"(interpreted {Si:g} s), best of {args.repeat}; warm-up call (compile or cache load) {warm:.2f} s\n")
    print("| run | simulated [s] | wall [s] | wall per simulated s [ms] | real-time factor | time / fdikit smooth | "
          "note |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for name, (per, sim, wall, note) in rows.items():
        print(f"| {name} | {sim:g} | {wall:.3f} | {1e3 * per:.2f} | {1 / per:,.1f}x | {per / base:.1f} | {note} |")
    print(f"\nfinal-state agreement with the compiled RK4 (max |Δx| / max(|x|, 1)): Python RK4 smooth {d_rk:.1e}, "
          f"Robson {d_rkr:.1e}, interpreted model {d_int:.1e}; solve_ivp RK45 (another method) {d_ivp:.1e} "
          f"smooth, {d_ivpr:.1e} Robson")
    worst = max(v[0] for k, v in rows.items() if k.startswith("fdikit"))
    print(f"slowest fdikit run: {1 / worst:.1f}x real time -> the >= 50x requirement is "
          f"{'met' if 1 / worst >= 50 else 'NOT met'}")


if __name__ == "__main__":
    main()
