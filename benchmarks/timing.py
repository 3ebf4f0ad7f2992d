"""Shared helpers of the benchmark scripts: best-of timing and the CPU's name (run them from the repository root)."""

from __future__ import annotations

import platform
import time


def best(fn, repeat: int) -> tuple[float, object]:
    """Smallest wall time of ``repeat`` calls of ``fn`` and the result of the last call."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def cpu_name() -> str:
    """The CPU model from /proc/cpuinfo (Linux), else ``platform.processor()``."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"
