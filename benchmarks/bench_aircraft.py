"""Cost of fdikit's JSBSim aircraft layer: simulation, trim and linearisation of the B747 against raw JSBSim.

Everything starts from the Hallouzi trim (``fdikit.aircraft.HALLOUZI_POINT``: 980 m, 92.6 m/s TAS, flaps
20 deg, 263 t, wings level).  Timed side by side in one run, best of ``--repeat`` (the simulation runs are
interleaved round by round, so a change of machine load hits every run alike):

1. **Simulation**, ``--duration`` s simulated at 120 Hz with the commands held, × real time = simulated
   seconds / wall seconds:

   * fdikit ``JSBSimAircraft("B747").step()`` once per step (the Python actuator model with the App. A limits
     and rates moves every surface, the positions are written over JSBSim's FCS by the override of
     :mod:`fdikit.aircraft.definition`, then one ``fdm.run()``);
   * the same with MIL-F-8785C Dryden turbulence (``set_turbulence(4, seed=1)``, moderate);
   * the same with the sensors read every step (``ac.measure(noise_std=NOISE_STD, rng=...)``, 16 sensors);
   * ``fdm.run()`` alone on fdikit's prepared B747 (no Python per step: what the definition changes cost);
   * the peer, raw JSBSim: a plain ``jsbsim.FGFDMExec`` on JSBSim's stock B747 (no fdikit), trimmed by
     JSBSim's own ``do_trim(1)`` at the same altitude, airspeed, flaps (``fcs/flap-cmd-norm`` = 20/30) and gear
     up, stepping ``fdm.run()`` with the trim's commands held.  The stock model's five tanks full give
     262.35 t, the nearest it comes to 263 t (it has no payload point mass to load).

2. **Trim**: fdikit ``trim_aircraft(ac, HALLOUZI_POINT)`` (least squares on ``ac.derivatives``, the stabiliser
   trims pitch) against ``fdm.do_trim(1)`` on the stock B747 at the same condition; and a trim with the
   rudder locked at 25 deg (``locked={"rudder": np.radians(25)}``, ``require=False``: bank and aileron hold it as
   far as they can).  JSBSim's trim moves the FCS *commands* (throttle, elevator, aileron, rudder) and cannot
   hold a surface at a locked position, which is why fdikit has its own: on fdikit's aircraft with the rudder
   held at 25 deg by the override, ``do_trim(1)`` raises ``TrimFailureError`` (its time to failing is shown).

3. **Linearisation**: fdikit ``linearize_aircraft(ac, trim)`` (central differences of ``ac.derivatives``, 10
   states, 5 inputs, thrust column through the engines' steady state) against ``jsbsim.FGLinearization(fdm)``
   on the same fdm at the same trim and on the stock B747 at its own trim.  ``FGLinearization`` sets the
   step to 0; it is put back with ``fdm.set_dt`` (fdikit's ``restore`` does the same).  The agreement of the
   rigid-body ``A`` blocks is asserted (``max |ΔA| < 1e-4 max |A|``, as in
   ``tests/aircraft/test_jsbsim_plant.py``) before any figure is printed, with JSBSim's states mapped to
   fdikit's (ft/s and ft to SI).

One core: the thread variables are set to 1 before numpy is imported; JSBSim's banner is silenced
(``JSBSIM_DEBUG=0``).

Run: ``python benchmarks/bench_aircraft.py [--duration 60] [--repeat 5]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"
os.environ.setdefault("JSBSIM_DEBUG", "0")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import timing  # noqa: E402 (benchmarks/timing.py, run from the repository root)

RATE = 120.0  # Hz
FT = 0.3048
KT = 1852.0 / 3600.0
LOCKED_RUDDER = float(np.radians(25.0))
#: Illustrative sensor noise (SI) for the 16 sensors of ``fdikit.aircraft.SENSORS``: body rates, airspeed,
#: α, β, attitude, altitude, CAS, vertical speed, γ, load factors (the timing does not depend on the values).
NOISE_STD = np.array([1e-3, 1e-3, 1e-3, 0.1, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1.0, 0.1, 0.1, 1e-3, 1e-3, 1e-3, 1e-3])
#: JSBSim's FGLinearization state names in the order of fdikit's STATES, and the factor of each to SI.
JSBSIM_STATES = ("P", "Q", "R", "Vt", "Alpha", "Beta", "Phi", "Theta", "Psi", "Alt")
JSBSIM_SCALE = np.array([1, 1, 1, FT, 1, 1, 1, 1, 1, FT])


def stock_b747(dt: float):
    """A plain ``FGFDMExec`` on JSBSim's stock B747 (JSBSim's own root directory) and its full tanks [lb]."""
    import jsbsim

    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    if not fdm.load_model("B747"):
        raise RuntimeError("JSBSim could not load its stock B747")
    fdm.set_dt(dt)
    fdm.run_ic()  # (the tanks' fill fraction is known after the first initialisation)
    tanks = [line.split()[0] for line in fdm.query_property_catalog("contents-lbs").splitlines()
             if line.startswith("propulsion/tank")]  # tank 0 has no index in its name
    return fdm, {p: fdm[p] / (fdm[p.replace("contents-lbs", "pct-full")] / 100.0) for p in tanks}


def stock_condition(fdm, full: dict, cond) -> None:
    """Put the stock B747 at ``cond`` (wings level, gear up, flaps, tanks refilled), engines running, by ``run_ic``."""
    for prop, lbs in full.items():  # a flight burns fuel; every run starts full
        fdm[prop] = lbs
    for prop, value in (("ic/h-sl-ft", cond.altitude / FT), ("ic/vt-kts", cond.airspeed / KT),
                        ("ic/gamma-rad", cond.flight_path_angle), ("ic/psi-true-rad", cond.heading),
                        ("ic/phi-rad", 0.0), ("ic/beta-rad", 0.0), ("ic/p-rad_sec", 0.0), ("ic/q-rad_sec", 0.0),
                        ("ic/r-rad_sec", 0.0)):
        fdm[prop] = value
    fdm["gear/gear-cmd-norm"] = 0.0
    fdm["fcs/flap-cmd-norm"] = np.degrees(cond.flaps) / 30.0  # the B747's flap detents end at 30 deg
    fdm["propulsion/set-running"] = -1
    fdm.run_ic()


def stock_trim(fdm, full: dict, cond) -> float:
    """Set the condition (untimed) and trim with JSBSim's ``do_trim(1)``; the wall time of the trim."""
    stock_condition(fdm, full, cond)
    t0 = time.perf_counter()
    fdm.do_trim(1)
    return time.perf_counter() - t0


def stock_state(fdm) -> np.ndarray:
    """Altitude [m] and true airspeed [m/s] of a raw fdm."""
    return np.array([fdm["position/h-sl-ft"] * FT, fdm["velocities/vt-fps"] * FT])


def jsbsim_A(fdm) -> tuple[np.ndarray, float]:
    """JSBSim's ``FGLinearization`` rigid-body ``A`` in fdikit's states and SI units, and its wall time."""
    import jsbsim

    dt = fdm.get_delta_t()
    t0 = time.perf_counter()
    lin = jsbsim.FGLinearization(fdm)
    wall = time.perf_counter() - t0
    fdm.set_dt(dt)  # FGLinearization leaves the step at 0
    names = list(lin.x_names)
    idx = [names.index(n) for n in JSBSIM_STATES]
    A = np.asarray(lin.system_matrix)[np.ix_(idx, idx)] * JSBSIM_SCALE[:, None] / JSBSIM_SCALE[None, :]
    return A, wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=60.0, help="simulated seconds of every flight")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    import jsbsim
    import scipy

    import fdikit
    from fdikit.aircraft import HALLOUZI_POINT, JSBSimAircraft, linearize_aircraft, trim_aircraft

    dt, cond = 1.0 / RATE, HALLOUZI_POINT
    n = int(round(args.duration * RATE))
    t0 = time.perf_counter()
    ac = JSBSimAircraft("B747", dt=dt)
    t_make = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = trim_aircraft(ac, cond)
    t_first = time.perf_counter() - t0
    assert tr.converged, f"fdikit's trim did not converge: {np.max(np.abs(tr.residual)):.1e}"
    snap = ac.snapshot()
    raw, full = stock_b747(dt)
    stock_trim(raw, full, cond)
    got = stock_state(raw)
    assert np.allclose(got, [cond.altitude, cond.airspeed], rtol=1e-6), f"do_trim left the condition: {got}"
    assert abs(raw["fcs/flap-pos-deg"] - 20.0) < 1e-9 and raw["gear/gear-pos-norm"] == 0.0

    # --- 1. simulation, interleaved rounds
    def fly_fdikit(turbulence: bool = False, measure: bool = False) -> tuple[float, np.ndarray]:
        ac.restore(snap)
        if turbulence:
            ac.set_turbulence(4, seed=1)
        rng = np.random.default_rng(1)
        start = ac.state()[[9, 3]]
        t0 = time.perf_counter()
        if measure:
            for _ in range(n):
                ac.step()
                y = ac.measure(noise_std=NOISE_STD, rng=rng)
            assert np.all(np.isfinite(y))
        else:
            for _ in range(n):
                ac.step()
        wall = time.perf_counter() - t0
        ac.set_turbulence(0)
        return wall, ac.state()[[9, 3]] - start

    def fly_prepared() -> tuple[float, np.ndarray]:
        ac.restore(snap)
        start, run = ac.state()[[9, 3]], ac.fdm.run
        t0 = time.perf_counter()
        for _ in range(n):
            run()
        return time.perf_counter() - t0, ac.state()[[9, 3]] - start

    def fly_raw() -> tuple[float, np.ndarray]:
        stock_trim(raw, full, cond)  # untimed start from a fresh trim
        start, run = stock_state(raw), raw.run
        t0 = time.perf_counter()
        for _ in range(n):
            run()
        return time.perf_counter() - t0, stock_state(raw) - start

    flights = {
        "fdikit `JSBSimAircraft.step()` (Python actuators + surface override)": fly_fdikit,
        "fdikit `step()`, Dryden turbulence (`set_turbulence(4, seed=1)`)": lambda: fly_fdikit(turbulence=True),
        "fdikit `step()` + `measure(noise_std, rng)` every step": lambda: fly_fdikit(measure=True),
        "JSBSim `fdm.run()` alone on fdikit's prepared B747": fly_prepared,
        "raw JSBSim: stock B747, `do_trim(1)`, `fdm.run()` (peer)": fly_raw,
    }
    sim = {k: (np.inf, None) for k in flights}
    for _ in range(args.repeat):
        for name, fn in flights.items():
            wall, drift = fn()
            assert np.all(np.isfinite(drift))
            if wall < sim[name][0]:
                sim[name] = (wall, drift)

    # --- 2. trim
    trims = {}
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        tr = trim_aircraft(ac, cond)
        times.append(time.perf_counter() - t0)
    trims["fdikit `trim_aircraft(ac, HALLOUZI_POINT)`"] = (min(times), f"max residual {np.max(np.abs(tr.residual)):.0e}"
                                                         f", stabiliser {np.degrees(tr.positions['stabilizer']):.2f}°"
                                                         f", α {np.degrees(tr.x[4]):.2f}°")
    snap = ac.snapshot()
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        tl = trim_aircraft(ac, cond, locked={"rudder": LOCKED_RUDDER}, require=False)
        times.append(time.perf_counter() - t0)
    trims["fdikit `trim_aircraft`, rudder locked at 25° (`require=False`)"] = (
        min(times), f"{'converged' if tl.converged else 'best point'}, max residual {np.max(np.abs(tl.residual)):.1e}"
                    f", φ {np.degrees(tl.x[6]):.1f}°, aileron {np.degrees(tl.positions['aileron']):.1f}°")
    times = [stock_trim(raw, full, cond) for _ in range(args.repeat)]
    trims["JSBSim `do_trim(1)`, stock B747 (peer)"] = (min(times), f"α {raw['aero/alpha-deg']:.2f}°, elevator "
                                                                    f"{np.degrees(raw['fcs/elevator-pos-rad']):.2f}°")
    times, failed = [], 0
    for _ in range(args.repeat):
        ac.restore(snap)
        ac.hold_surfaces({"rudder": LOCKED_RUDDER})
        ac.fdm.run_ic()
        t0 = time.perf_counter()
        try:
            ac.fdm.do_trim(1)
        except jsbsim.TrimFailureError:
            failed += 1
        times.append(time.perf_counter() - t0)
    trims["JSBSim `do_trim(1)` on fdikit's B747, rudder held at 25°"] = (
        min(times), f"`TrimFailureError` in {failed} of {args.repeat}" if failed else "no failure (unexpected)")
    base_trim = trims["JSBSim `do_trim(1)`, stock B747 (peer)"][0]

    # --- 3. linearisation
    tr = trim_aircraft(ac, cond)
    snap = ac.snapshot()
    times = []
    for _ in range(args.repeat):
        ac.restore(snap)
        t0 = time.perf_counter()
        lin = linearize_aircraft(ac, tr)
        times.append(time.perf_counter() - t0)
    A = lin.model.A
    peer_times = []
    for _ in range(args.repeat):
        ac.restore(snap)
        A_same, wall = jsbsim_A(ac.fdm)
        peer_times.append(wall)
    ac.restore(snap)
    assert ac.fdm.get_delta_t() == dt
    stock_times = []
    for _ in range(args.repeat):
        stock_trim(raw, full, cond)
        A_stock, wall = jsbsim_A(raw)
        stock_times.append(wall)
    assert raw.get_delta_t() == dt
    scale = np.max(np.abs(A))
    err = np.max(np.abs(A_same - A)) / scale
    assert err < 1e-4, f"FGLinearization and linearize_aircraft disagree: max |ΔA| / max |A| = {err:.1e}"
    lon, lat = [3, 4, 1, 7], [5, 0, 2, 6]  # (V, α, q, θ) and (β, p, r, φ)
    blocks = {k: np.max(np.abs(A_same - A)[np.ix_(b, b)]) / np.max(np.abs(A[np.ix_(b, b)]))
              for k, b in (("longitudinal (V, α, q, θ)", lon), ("lateral (β, p, r, φ)", lat))}
    err_stock = np.max(np.abs(A_stock - A)) / scale
    lins = {
        "fdikit `linearize_aircraft(ac, trim)` (10 states, 5 inputs)": (min(times), "`A`, `B`, offsets"),
        "JSBSim `FGLinearization(ac.fdm)`, fdikit's fdm at fdikit's trim": (min(peer_times), "12 states, 4 inputs"),
        "JSBSim `FGLinearization(fdm)`, stock B747 at `do_trim` (peer)": (min(stock_times), "12 states, 4 inputs"),
    }
    base_lin = lins["JSBSim `FGLinearization(fdm)`, stock B747 at `do_trim` (peer)"][0]

    # --- report
    stock_t = raw["inertia/weight-lbs"] * 0.45359237 / 1e3
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"fdikit {fdikit.__version__}, JSBSim {jsbsim.__version__}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}, Python {platform.python_version()}, {platform.machine()}, {timing.cpu_name()}, "
          f"{os.cpu_count()} cores, one thread, load average {load:.2f}; {time.strftime('%Y-%m-%d')}")
    print(f"B747 at the Hallouzi trim (980 m, 92.6 m/s, flaps 20°, fdikit 263 t / stock {stock_t:.2f} t); "
          f"{args.duration:g} s at {RATE:g} Hz ({n} steps), best of {args.repeat}; "
          f"JSBSimAircraft construction {1e3 * t_make:.0f} ms, "
          f"first trim_aircraft call {1e3 * t_first:.0f} ms (imports scipy.optimize; not in the table)\n")
    base = sim["raw JSBSim: stock B747, `do_trim(1)`, `fdm.run()` (peer)"][0]
    print("| run | wall [s] | per step [µs] | × real time | wall / raw JSBSim | Δh, ΔV after the run |")
    print("|---|---:|---:|---:|---:|---|")
    for name, (wall, drift) in sim.items():
        print(f"| {name} | {wall:.3f} | {1e6 * wall / n:.1f} | {args.duration / wall:,.0f}x | {wall / base:.1f} | "
              f"{drift[0]:+.2f} m, {drift[1]:+.3f} m/s |")
    print("\n| trim | time [ms] | / JSBSim `do_trim` | result |")
    print("|---|---:|---:|---|")
    for name, (wall, note) in trims.items():
        print(f"| {name} | {1e3 * wall:.1f} | {wall / base_trim:.2g} | {note} |")
    print("\n| linearisation | time [ms] | / stock `FGLinearization` | note |")
    print("|---|---:|---:|---|")
    for name, (wall, note) in lins.items():
        print(f"| {name} | {1e3 * wall:.1f} | {wall / base_lin:.2g} | {note} |")
    print(f"\nrigid-body A, FGLinearization on the same fdm vs linearize_aircraft: max |ΔA| / max |A| = {err:.1e} "
          + ", ".join(f"{k} {v:.1e}" for k, v in blocks.items())
          + f"; stock B747 at its own trim (elevator, not stabiliser; {stock_t:.2f} t) vs fdikit: {err_stock:.1e}")


if __name__ == "__main__":
    main()
