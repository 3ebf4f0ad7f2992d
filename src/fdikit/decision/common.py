"""Pieces every evaluator shares: k-of-n persistence, holding decisions over bad samples, cached isolation
(per-residual logic or a signature table), residual names checked against the fit."""

from __future__ import annotations

import numpy as np

from fdikit.diagnosis import isolate
from fdikit.errors import DataError
from fdikit.residuals import Residuals

__all__ = ["is_count", "k_of_n", "held", "isolate_cached", "isolate_fired", "checked_names",
           "check_fitted_names", "checked_residuals", "step_vector"]


def is_count(value, minimum: int) -> bool:
    """True for an integer (or an integral float) ``>= minimum``; False for anything else (no exception).

    Parameters
    ----------
    value : object
        The value to test; booleans, strings and non-finite numbers are not counts.
    minimum : int
        The smallest accepted count.

    Returns
    -------
    bool
        Whether ``value`` is an integral number ``>= minimum``.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> from fdikit.decision.common import is_count
    >>> is_count(3, 1), is_count(2.0, 1), is_count(0, 1), is_count(True, 1)
    (True, True, False, False)
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    return bool(np.isfinite(value) and int(value) == value and value >= minimum)


def k_of_n(exceed: np.ndarray, k: int, n: int) -> np.ndarray:
    """``True`` where at least ``k`` of the last ``n`` rows (this one included) exceed, per column.

    ``k_of_n(x, 1, hold + 1)`` keeps a decision on for ``hold`` samples after it fires.

    Parameters
    ----------
    exceed : (N, q) bool array
        Per-sample, per-residual exceedances (rows in time order, valid samples only).
    k : int
        How many of the window's rows must exceed; ``1 <= k <= n``.
    n : int
        Window length in samples, the current row included; the first rows use the shorter window they have.

    Returns
    -------
    (N, q) bool array
        The persistent decision per sample and column (``exceed`` itself for ``k = n = 1``).

    References
    ----------
    Douglas et al. 1996, Ch. 1 (threshold detection balancing false against missed alarms); the k-of-n
    persistence rule itself is not from the source documents.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.common import k_of_n
    >>> x = np.array([[1], [0], [1], [1], [0]], dtype=bool)
    >>> k_of_n(x, 2, 3).ravel().tolist()
    [False, False, True, True, True]
    """
    if k == 1 and n == 1:
        return exceed
    c = np.cumsum(np.vstack([np.zeros((1, exceed.shape[1]), int), exceed.astype(int)]), axis=0)
    lo = np.maximum(np.arange(1, exceed.shape[0] + 1) - n, 0)
    return (c[1:] - c[lo]) >= k


def held(values: np.ndarray, valid: np.ndarray, initial) -> np.ndarray:
    """Rows for every sample from rows for the valid ones: an invalid sample repeats the last valid row
    (``initial`` before the first), as an online ``step`` holds its state through a bad sample.

    Parameters
    ----------
    values : (M, ...) array
        One row per valid sample, in time order (``M = valid.sum()``).
    valid : (N,) bool array
        Which of the ``N`` samples are valid.
    initial : scalar or array
        The row used before the first valid sample (broadcast to a row of ``values``).

    Returns
    -------
    (N, ...) array
        One row per sample, of the dtype of ``values``.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.common import held
    >>> held(np.array([1.0, 2.0, 3.0]), np.array([False, True, False, True, True]), 0.0).tolist()
    [0.0, 1.0, 1.0, 2.0, 3.0]
    """
    pos = np.cumsum(valid) - 1
    out = np.empty((valid.size,) + values.shape[1:], dtype=values.dtype)
    out[...] = initial
    has = pos >= 0
    out[has] = values[pos[has]]
    return out


def isolate_fired(fired: np.ndarray, isolates, groups=None, signatures=None, names=None) -> np.ndarray:
    """Per-sample isolation of per-residual decisions: the single-fault logic, or a signature table.

    Parameters
    ----------
    fired : (N, q) bool array
        Per-sample, per-residual (or per-block) decisions.
    isolates : sequence of str or None
        Fault name tied to each residual.
    groups : sequence, optional
        The filter each residual belongs to (:func:`fdikit.diagnosis.isolate`); ignored with ``signatures``.
    signatures : SignatureTable, optional
        Isolate by matching the fired residual groups against the table
        (:func:`fdikit.decision.signature.signature_isolation`) instead.
    names : sequence of str, optional
        Residual names (``r0 …`` when not given), for ``signatures``.

    Returns
    -------
    (N,) str ndarray
        ``'none'``, a fault name or ``'unknown'`` per sample.

    References
    ----------
    Douglas et al. 1996, §1 (the fault announced from the pattern of fired residuals).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.common import isolate_fired
    >>> from fdikit.decision.signature import SignatureTable
    >>> fired = np.array([[True, True]])
    >>> isolate_fired(fired, ("fa", "fb")).tolist(), isolate_fired(fired, ("fa", "fb"),
    ...     signatures=SignatureTable({"fa": ["fa", "fb"], "fb": ["fb"]})).tolist()
    (['unknown'], ['fa'])
    """
    if signatures is None:
        return isolate(fired, isolates, groups)
    from fdikit.decision.signature import signature_isolation

    fired = np.asarray(fired, bool)
    names = tuple(names) if names is not None else tuple(f"r{i}" for i in range(fired.shape[1]))
    return signature_isolation(fired, signatures, names, isolates)


def isolate_cached(cache: dict, fired: np.ndarray, isolates, groups=None, signatures=None, names=None) -> str:
    """Isolation of one sample's fired pattern, memoised in ``cache`` (a run has few distinct patterns).

    The label is :func:`isolate_fired` of the pattern, so ``step`` names exactly what ``run`` names.

    Parameters
    ----------
    cache : dict
        Memo from the pattern's bytes to its label; updated in place.
    fired : (q,) bool array
        Which residuals fired at this sample.
    isolates : sequence of str or None
        Fault name tied to each residual.
    groups : sequence, optional
        The filter each residual belongs to (:func:`fdikit.diagnosis.isolate`).
    signatures : SignatureTable, optional
        Isolate from the table instead (:func:`isolate_fired`).
    names : sequence of str, optional
        Residual names, for ``signatures``.

    Returns
    -------
    str
        The isolated fault name, ``"none"`` or ``"unknown"``.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.common import isolate_cached
    >>> cache = {}
    >>> isolate_cached(cache, np.array([True, False]), ("a_sensor", "b_sensor")), len(cache)
    ('a_sensor', 1)
    """
    key = fired.tobytes()
    label = cache.get(key)
    if label is None:
        label = cache[key] = str(isolate_fired(fired[None, :], isolates, groups, signatures, names)[0])
    return label


def checked_names(q: int, residuals, fitted) -> tuple[str, ...]:
    """Names of ``q`` residuals: those of ``residuals``, else the fitted ones, else ``r0 …``; raises
    :class:`~fdikit.errors.DataError` when their number is not ``q``.

    Parameters
    ----------
    q : int
        Number of residuals in the data.
    residuals : Residuals or None
        The series, whose names win when given.
    fitted : tuple of str or None
        The names the evaluator was fitted on.

    Returns
    -------
    tuple of str
        ``q`` residual names.

    Raises
    ------
    DataError
        When the chosen names are not ``q``.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> from fdikit.decision.common import checked_names
    >>> checked_names(2, None, None), checked_names(2, None, ("x", "y"))
    (('r0', 'r1'), ('x', 'y'))
    """
    names = residuals.names if residuals is not None else (fitted or tuple(f"r{i}" for i in range(q)))
    if len(names) != q:
        raise DataError(f"got {q} residuals, the evaluator was fitted on {len(names)} ({list(names)})")
    return names


def check_fitted_names(names, fitted, evaluator: str = "the evaluator") -> None:
    """Raise :class:`~fdikit.errors.DataError` unless the residual ``names`` are exactly the ``fitted`` ones, in order.

    The message names the difference: the missing and the extra residuals, or, for the same set in
    another order, the positions that differ.  ``fitted`` None (an evaluator set up by hand, not fitted)
    accepts any names.

    Parameters
    ----------
    names : sequence of str or None
        Residual names of the data (None: not checked).
    fitted : sequence of str or None
        Residual names of the fit (None: any names accepted).
    evaluator : str, default "the evaluator"
        How the message names the evaluator.

    Raises
    ------
    DataError
        When ``names`` differ from ``fitted`` (missing or extra residuals, or the same residuals reordered).

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> from fdikit.decision.common import check_fitted_names
    >>> check_fitted_names(("a", "b"), ("a", "b"))
    >>> try:
    ...     check_fitted_names(("b", "a"), ("a", "b"))
    ... except Exception as exc:
    ...     print(type(exc).__name__)
    DataError
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
    """``residuals`` after checking that it is a :class:`~fdikit.residuals.Residuals` whose names match the fitted
    ones.

    Parameters
    ----------
    residuals : Residuals
        The series to check.
    fitted : sequence of str or None
        Residual names of the fit (None: any names accepted).
    evaluator : str, default "the evaluator"
        How the message names the evaluator.

    Returns
    -------
    Residuals
        ``residuals`` itself.

    Raises
    ------
    DataError
        When ``residuals`` is not a ``Residuals``, or its names differ from ``fitted``
        (:func:`check_fitted_names`).

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.common import checked_residuals
    >>> r = Residuals(np.arange(3) * 0.1, np.zeros((3, 2)), ("a", "b"), ("fa", "fb"))
    >>> checked_residuals(r, ("a", "b")).names
    ('a', 'b')
    """
    if not isinstance(residuals, Residuals):
        raise DataError(f"residuals must be a fdikit.residuals.Residuals (from a generator's run), got "
                        f"{type(residuals).__name__}")
    check_fitted_names(residuals.names, fitted, evaluator)
    return residuals


def step_vector(r, fitted=None, names=None, evaluator: str = "the evaluator") -> np.ndarray:
    """One residual sample for ``step`` as a float vector; ``names`` (optional) are checked against ``fitted``.

    A mapping ``{name: value}`` is accepted too: its keys are the names, in order.

    Parameters
    ----------
    r : array_like or mapping
        The sample: ``q`` numbers (NaN for a missing one), or ``{name: value}``.
    fitted : sequence of str, optional
        Residual names of the fit.
    names : str or sequence of str, optional
        Names of the values of ``r`` (a mapping's keys when not given); checked against ``fitted``.
    evaluator : str, default "the evaluator"
        How the message names the evaluator.

    Returns
    -------
    (q,) float array
        The sample.

    Raises
    ------
    DataError
        When ``r`` is not numeric, when the number of names differs from the number of values, or when the
        names differ from ``fitted``.

    References
    ----------
    No source document: bookkeeping shared by the evaluators of ``fdikit.decision`` (see its module
    docstring for the rules on invalid samples and residual names).

    Examples
    --------
    >>> from fdikit.decision.common import step_vector
    >>> step_vector({"a": 1.0, "b": float("nan")}, fitted=("a", "b")).tolist()
    [1.0, nan]
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

