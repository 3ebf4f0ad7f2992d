"""Import time of fdikit's packages beyond numpy + scipy.linalg, next to the peers a user would otherwise import.

Each import runs in a fresh interpreter (``python -X importtime`` would also count the interpreter start); the time
of ``import numpy, scipy.linalg`` is measured in the same interpreter first and subtracted.  Median of 7 runs.
Run from the repository root: ``python benchmarks/bench_import.py``.
"""

from __future__ import annotations

import statistics
import subprocess
import sys

BASE = "import numpy, scipy.linalg"
TARGETS = [
    ("fdikit.design", "import fdikit.design"),
    ("fdikit.decision", "import fdikit.decision"),
    ("fdikit.multimodel", "import fdikit.multimodel"),
    ("fdikit.design: first use (kalman)", "from fdikit.design import kalman"),
    ("fdikit.design.game (all of its names)", "from fdikit.design.game import *"),
    ("scipy.signal (peer)", "import scipy.signal"),
    ("control (python-control, peer)", "import control"),
]
CODE = """
import time
t0 = time.perf_counter(); {base}; t1 = time.perf_counter(); {target}; t2 = time.perf_counter()
print(t2 - t1)
"""


def extra_seconds(target: str, runs: int = 7) -> float:
    """Median time of ``target`` after numpy + scipy.linalg, each run in a fresh interpreter."""
    out = []
    for _ in range(runs):
        res = subprocess.run([sys.executable, "-c", CODE.format(base=BASE, target=target)], capture_output=True,
                             text=True, check=True)
        out.append(float(res.stdout.strip()))
    return statistics.median(out)


def main() -> None:
    rows = [(label, extra_seconds(code)) for label, code in TARGETS]
    ref = dict(rows)["control (python-control, peer)"]
    print("| import | time beyond numpy + scipy.linalg [s] | / import control |")
    print("|---|---|---|")
    for label, sec in rows:
        print(f"| `{label}` | {sec:.3f} | {sec / ref:.2f} |")


if __name__ == "__main__":
    main()
