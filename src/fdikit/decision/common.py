"""Pieces every evaluator shares: k-of-n persistence, holding decisions over bad samples, cached isolation,
residual names checked against the fit."""

from __future__ import annotations

import numpy as np

from fdikit.diagnosis import isolate
from fdikit.errors import DataError
from fdikit.residuals import Residuals

__all__ = ["is_count", "k_of_n", "held", "isolate_cached", "checked_names",
           "check_fitted_names", "checked_residuals", "step_vector"]


def is_count(value, minimum: int) -> bool:
    """True for an integer (or an integral float) ``>= minimum``; False for anything else (no exception)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    return bool(np.isfinite(value) and int(value) == value and value >= minimum)


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


def check_fitted_names(names, fitted, evaluator: str = "the evaluator") -> None:
    """Raise :class:`DataError` unless the residual ``names`` are exactly the ``fitted`` ones, in order.

    The message names the difference: the missing and the extra residuals, or, for the same set in
    another order, the positions that differ.  ``fitted`` None (an evaluator set up by hand, not fitted)
    accepts any names.
    """
    if fitted is None or names is None:
        return
    names, fitted = tuple(names), tuple(fitted)
    if names == fitted:
        return
    missing = [n for n in fitted if n not in names]
    extra = [n for n in names if n not in fitted]
    if missing or extra or len(names) != len(fitted):
        raise DataError(
            f"residual names {list(names)} differ from the {list(fitted)} {evaluator} was fitted on: "
            f"missing {missing}, extra {extra}; run the generator it was fitted with, or fit it again"
        )
    moved = [f"{n!r} at {i} (fitted at {fitted.index(n)})" for i, n in enumerate(names) if fitted[i] != n]
    raise DataError(
        f"residuals are reordered: got {list(names)}, {evaluator} was fitted on {list(fitted)} "
        f"({', '.join(moved)}); its thresholds would apply to the wrong residuals — reorder them by name with "
        f"residuals.select({list(fitted)})"
    )


def checked_residuals(residuals, fitted, evaluator: str = "the evaluator") -> Residuals:
    """``residuals`` after checking that it is a :class:`Residuals` whose names match the fitted ones."""
    if not isinstance(residuals, Residuals):
        raise DataError(f"residuals must be a fdikit.residuals.Residuals (from a generator's run), got "
                        f"{type(residuals).__name__}")
    check_fitted_names(residuals.names, fitted, evaluator)
    return residuals


def step_vector(r, fitted=None, names=None, evaluator: str = "the evaluator") -> np.ndarray:
    """One residual sample for ``step`` as a float vector; ``names`` (optional) are checked against ``fitted``.

    A mapping ``{name: value}`` is accepted too: its keys are the names, in order.
    """
    from collections.abc import Mapping

    if isinstance(r, Mapping):
        names = tuple(r) if names is None else names
        r = list(r.values())
    try:
        arr = np.asarray(r, dtype=float).ravel()
    except (TypeError, ValueError) as exc:
        raise DataError(f"step() needs the residual sample as numbers (NaN for a missing one), got {r!r}") from exc
    if names is not None:
        names = (names,) if isinstance(names, str) else tuple(names)
        if len(names) != arr.size:
            raise DataError(f"step() got {arr.size} residual values but {len(names)} names {list(names)}")
        check_fitted_names(names, fitted, evaluator)
    return arr
