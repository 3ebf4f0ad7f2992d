"""Shared timing helper of the benchmark scripts (run them from the repository root)."""

from __future__ import annotations

import time


def best(fn, repeat: int) -> tuple[float, object]:
    """Smallest wall time of ``repeat`` calls of ``fn`` and the result of the last call."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out
