"""Write the logs of the "bring your own plant and data" tutorial (docs/tutorial/*.csv.gz).

Two plants, each logged the way a test engineer would export it: a timestamp column, engineering units,
a few dropped rows (a logger hiccup), one fault per faulty log.

* **car** — fdikit's nonlinear 6-DOF sedan (``fdikit.vehicle``) at 20 m/s on a smooth road, the road-wheel
  steering excited by a small multisine (0.1–2 Hz, ±0.25°) as on a handling test; logged: steering command
  [deg], yaw rate [deg/s], lateral acceleration [g].  Sensor noise of ``fdikit.studies.path1996.demo``:
  yaw rate 0.002 rad/s, lateral accelerometer 0.05 m/s² per sample at 100 Hz (inside the MEMS ranges of
  automotive gyros and ESC accelerometers).  Logs: ``car_train`` (120 s, identification), ``car_healthy``
  (600 s, calibration), ``car_yaw_bias`` (yaw-rate sensor bias 1.5 deg/s from 30 s), ``car_steer_offset``
  (steering actuator offset 0.4° at the road wheel from 30 s: a misaligned steering linkage).  The sizes are
  two to three times what the tutorial's identified-model detector can see at one false alarm per hour (docs/tutorial.md
  gives the measured limits); smaller faults are missed, and the tutorial says so.
* **tanks** — two tanks in series, the pump flow commanded [L/min], both levels logged [cm]; level-sensor
  noise 0.2 cm (no rows dropped: a filter of these slow tanks needs ~15 min to forget a held pump command, see
  :mod:`fdikit.gaps`); logs ``tanks_healthy`` (3600 s at 1 Hz) and ``tanks_level2_bias`` (level-2 sensor bias
  +1.5 cm from 1200 s).  The plant is the tutorial's own Python function (``docs/tutorial/tanks.py``).

Run ``.venv/bin/python tools/make_tutorial_data.py`` to rewrite the files (seeded: the same bytes every time
on one machine).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd

OUT = Path(__file__).resolve().parents[1] / "docs" / "tutorial"
START = pd.Timestamp("2026-11-30T09:00:00Z")


def _write(name: str, df: pd.DataFrame, drop: int, rng) -> None:
    if drop:
        rows = np.sort(rng.choice(np.arange(100, len(df) - 100), size=drop, replace=False))
        df = df.drop(index=df.index[rows])    # the logger lost these rows: gaps in the time stamps
    df.to_csv(OUT / f"{name}.csv.gz", index=False, float_format="%.6g", compression={"method": "gzip", "mtime": 0})


def car_logs() -> None:
    from fdikit.faults import Bias, FaultScenario
    from fdikit.vehicle import SENSORS, Sedan, simulate_sedan

    car = Sedan()
    op = car.operating_point(speed=20.0)
    freqs = np.array([0.1, 0.23, 0.41, 0.67, 1.1, 1.7, 2.0])
    phases = np.random.default_rng(7).uniform(0, 2 * np.pi, freqs.size)
    amp = np.deg2rad(0.25) / np.sqrt(freqs.size)

    def commands(t):
        steer = op.u[2] + amp * np.sum(np.sin(2 * np.pi * freqs * t + phases))
        return np.array([op.u[0], op.u[1], steer])

    noise = {"yaw_rate": 0.002, "accel_y": 0.05}
    runs = {
        "car_train": (120.0, None, 1),
        "car_healthy": (600.0, None, 2),
        "car_yaw_bias": (60.0, Bias("yaw_rate", np.deg2rad(1.5), onset=30.0), 3),
        "car_steer_offset": (60.0, Bias("steering", np.deg2rad(0.4), onset=30.0), 4),
    }
    for name, (duration, fault, seed) in runs.items():
        scenario = FaultScenario([fault]) if fault is not None else None
        tr = simulate_sedan(car, duration, start=op, commands=commands, scenario=scenario,
                            measurement_noise_std=noise, rng=seed, keep_signals=False)
        df = pd.DataFrame({
            "time": (START + pd.to_timedelta(tr.t, unit="s")).strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
            "steer_deg": np.rad2deg(tr.signal("steering", "u")),
            "yaw_dps": np.rad2deg(tr.y[:, SENSORS.index("yaw_rate")]),
            "ay_g": tr.y[:, SENSORS.index("accel_y")] / 9.80665,
            "fault": tr.fault,
        })
        _write(name, df, drop=5, rng=np.random.default_rng(seed + 100))


def tank_logs() -> None:
    from fdikit.faults import Bias, FaultScenario
    from fdikit.nonlinear import trim_and_linearize
    from fdikit.simulate import simulate

    spec = importlib.util.spec_from_file_location("tanks", OUT / "tanks.py")
    tanks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tanks)
    plant = tanks.plant()
    lin = trim_and_linearize(plant, x0=[0.3, 0.3], u0=[1e-4], y0={"level2": 0.25})
    q0 = lin.trim.u[0]
    rng = np.random.default_rng(11)
    for name, duration, fault, seed in (("tanks_healthy", 3600.0, None, 12),
                                        ("tanks_level2_bias", 2400.0, Bias("level2", 0.015, onset=1200.0), 13)):
        t = np.arange(0.0, duration, 1.0)
        # the pump command steps around the trim every 2 minutes (±15 %)
        q = q0 * (1 + 0.15 * np.repeat(rng.choice([-1.0, 1.0], size=t.size // 120 + 1), 120)[: t.size])
        tr = simulate(plant, FaultScenario([fault]) if fault is not None else None, t=t, u=q[:, None],
                      x0=lin.trim.x, measurement_noise_std=0.002, rng=seed)
        df = pd.DataFrame({
            "t_s": tr.t,
            "pump_lpm": tr.u[:, 0] * 60_000.0,
            "level1_cm": tr.y[:, 0] * 100.0,
            "level2_cm": tr.y[:, 1] * 100.0,
            "fault": tr.fault,
        })
        _write(name, df, drop=0, rng=np.random.default_rng(seed + 100))


if __name__ == "__main__":
    import sys

    if "tanks" in sys.argv[1:] or len(sys.argv) == 1:
        tank_logs()
    if "car" in sys.argv[1:] or len(sys.argv) == 1:
        car_logs()
