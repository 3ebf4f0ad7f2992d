"""Pieces every evaluator shares: k-of-n persistence, holding decisions over bad samples, cached isolation,
residual names checked against the fit."""

from __future__ import annotations

import numpy as np

from fdikit.diagnosis import isolate
from fdikit.errors import DataError

__all__ = ["k_of_n", "held", "isolate_cached", "checked_names"]


def k_of_n(exceed: np.ndarray, k: int, n: int) -> np.ndarray:
    """``True`` where at least ``k`` of the last ``n`` rows (this one included) exceed, per column.

    ``k_of_n(x, 1, hold + 1)`` keeps a decision on for ``hold`` samples after it fires.
    """
    if k == 1 and n == 1:
        return exceed
    c = np.cumsum(np.vstack([np.zeros((1, exceed.shape[1]), int), exceed.astype(int)]), axis=0)
    lo = np.maximum(np.arange(1, exceed.shape[0] + 1) - n, 0)
    return (c[1:] - c[lo]) >= k


def held(values: np.ndarray, valid: np.ndarray, initial) -> np.ndarray:
    """Rows for every sample from rows for the valid ones: an invalid sample repeats the last valid row
    (``initial`` before the first), as an online ``step`` holds its state through a bad sample."""
    pos = np.cumsum(valid) - 1
    out = np.empty((valid.size,) + values.shape[1:], dtype=values.dtype)
    out[...] = initial
    has = pos >= 0
    out[has] = values[pos[has]]
    return out


def isolate_cached(cache: dict, fired: np.ndarray, isolates, groups=None) -> str:
    """Isolation of one sample's fired pattern, memoised in ``cache`` (a run has few distinct patterns)."""
    key = fired.tobytes()
    label = cache.get(key)
    if label is None:
        label = cache[key] = str(isolate(fired[None, :], isolates, groups)[0])
    return label


def checked_names(q: int, residuals, fitted) -> tuple[str, ...]:
    """Names of ``q`` residuals: those of ``residuals``, else the fitted ones, else ``r0 …``; raises
    :class:`DataError` when their number is not ``q``."""
    names = residuals.names if residuals is not None else (fitted or tuple(f"r{i}" for i in range(q)))
    if len(names) != q:
        raise DataError(f"got {q} residuals, the evaluator was fitted on {len(names)} ({list(names)})")
    return names
