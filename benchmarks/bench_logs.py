"""Reading a CSV log into a Trace, next to pandas reading the same file (the peer a user would otherwise call).

A 100 Hz log with an ISO 8601 time column, three signals in engineering units (deg, deg/s, g) and 0.1 % of the
rows dropped (gaps).  ``Trace.from_csv`` = ``pandas.read_csv`` + clock parsing + the grid check + inserting the
gap rows + pint unit conversion; the ratio says what the checks cost on top of reading.  Also: saving and loading a
detector file (`fdikit.detector_file`, digest checked) and the online step of a loaded detector.
Run from the repository root: ``python benchmarks/bench_logs.py [--rows 1000000]``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from timing import best, cpu_name


def write_log(path: Path, rows: int) -> None:
    rng = np.random.default_rng(0)
    t = pd.Timestamp("2026-01-01T00:00:00Z") + pd.to_timedelta(np.arange(rows) * 0.01, unit="s")
    df = pd.DataFrame({"time": t.strftime("%Y-%m-%dT%H:%M:%S.%fZ"), "steer_deg": rng.standard_normal(rows),
                       "yaw_dps": rng.standard_normal(rows), "ay_g": 0.01 * rng.standard_normal(rows)})
    df.drop(index=rng.choice(np.arange(1, rows - 1), size=rows // 1000, replace=False)).to_csv(path, index=False)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    from fdikit.trace import Trace

    folder = Path(tempfile.mkdtemp())
    path = folder / "log.csv"
    write_log(path, args.rows)
    log = dict(time="time", controls={"steering": "steer_deg"}, outputs={"yaw_rate": "yaw_dps", "accel_y": "ay_g"},
               units={"steering": "deg", "yaw_rate": "deg/s", "accel_y": "g0"})
    t_pd, _ = best(lambda: pd.read_csv(path), args.repeat)
    t_fd, tr = best(lambda: Trace.from_csv(path, **log), args.repeat)
    print(f"CPU: {cpu_name()}; {args.rows} rows, {int((~tr.valid).sum())} gap samples inserted")
    print(f"pandas.read_csv            {t_pd:8.3f} s")
    print(f"Trace.from_csv             {t_fd:8.3f} s   ({t_fd / t_pd:.2f}x pandas)")

    from fdikit.decision import ThresholdEvaluator
    from fdikit.detector import Detector
    from fdikit.residuals import ResidualGenerator

    g = ResidualGenerator(0.5 * np.eye(4), np.ones((4, 3)), np.eye(2, 4), np.ones((2, 3)), ("steering",),
                          ("yaw_rate", "accel_y"), ("r1", "r2"), dt=0.01)
    det = Detector(g, ThresholdEvaluator(thresholds=[1.0, 1.0]), units=log["units"])
    file = folder / "det.json"
    t_save, _ = best(lambda: det.save(file), args.repeat)
    t_load, back = best(lambda: Detector.load(file), args.repeat)
    stepper = back.online()
    u, y = [0.01], [0.02, 0.1]
    n = 20_000
    t_step, _ = best(lambda: [stepper.step(u, y) for _ in range(n)], args.repeat)
    print(f"detector save / load       {1e3 * t_save:8.2f} / {1e3 * t_load:.2f} ms  ({file.stat().st_size} bytes)")
    print(f"online step (4 states)     {1e6 * t_step / n:8.1f} µs per sample")


if __name__ == "__main__":
    main()
