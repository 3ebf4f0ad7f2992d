"""The non-finite-trace diagnosis of :mod:`fdikit.simulate`: which sample went bad, and why.

An internal module (used by :mod:`fdikit.simulate`): a run that overflows is
refused with a :class:`~fdikit.errors.DataError` naming the first non-finite sample (index and
time) and signal (:func:`refuse_non_finite`), and the likely cause — the unstable eigenvalue
(Re λ > 0, or |λ| > 1 when discrete) of the plant (:func:`linear_cause`), of the Jacobian of a
nonlinear plant (:func:`jacobian_text`) or of the most unstable frozen model of a schedule
(:func:`scheduled_cause`), or inputs too large for the float range.

Examples
--------
>>> import numpy as np
>>> from fdikit.plants import white_speyer
>>> from fdikit.simulate_diagnosis import linear_cause
>>> linear_cause(white_speyer(), np.zeros((1, 0))).startswith("the plant is unstable")
True
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from fdikit.errors import DataError
from fdikit.model import FaultModel

__all__ = ["refuse_non_finite", "linear_cause", "jacobian_text", "scheduled_cause"]


_FLOAT_RANGE_LOG = math.log(np.finfo(float).max)  # ln(1.8e308): a state growing like e^{at} overflows at a t ≈ 709.8


def _eig_text(lam: complex) -> str:
    """An eigenvalue as text: the real part alone when it is real."""
    return f"{lam.real:.6g}" if lam.imag == 0 else f"{lam.real:.6g}{lam.imag:+.6g}j"


def _instability(A: np.ndarray, discrete: bool, what: str = "A") -> str | None:
    """The sentence naming the unstable eigenvalue of ``A``, or None when ``A`` is stable."""
    A = np.asarray(A, dtype=float)
    if A.size == 0 or not np.all(np.isfinite(A)):
        return None
    lam = np.linalg.eigvals(A)
    if discrete:
        i = int(np.argmax(np.abs(lam)))
        r = float(abs(lam[i]))
        if r <= 1.0:
            return None
        return (f"the plant is unstable: {what} has the eigenvalue λ = {_eig_text(lam[i])} with |λ| = {r:.6g} > 1, "
                f"so its state grows like |λ|^k and leaves the float range after about "
                f"{_FLOAT_RANGE_LOG / math.log(r):.4g} samples")
    i = int(np.argmax(lam.real))
    a = float(lam[i].real)
    if a <= 0.0:
        return None
    return (f"the plant is unstable: {what} has the eigenvalue λ = {_eig_text(lam[i])} with Re λ = {a:.6g} > 0, "
            f"so its state grows like exp({a:.3g} t) and leaves the float range after about "
            f"{_FLOAT_RANGE_LOG / a:.4g} s")


def _first_bad(t: np.ndarray, blocks: Sequence[tuple[str, np.ndarray, Sequence[str]]]) -> tuple[int, str] | None:
    """Earliest non-finite sample over the (kind, array, names) blocks: (index, description)."""
    best = None
    for kind, arr, names in blocks:
        if arr.size == 0:
            continue
        bad_rows = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad_rows.size and (best is None or bad_rows[0] < best[0]):
            k = int(bad_rows[0])
            j = int(np.flatnonzero(~np.isfinite(arr[k]))[0])
            best = (k, f"{kind} {names[j]!r} is {arr[k, j]}")
    return best


def refuse_non_finite(t, blocks, cause: Callable[[], str]) -> None:
    """DataError naming the first non-finite sample and signal of the blocks and the likely cause.

    Parameters
    ----------
    t : (N,) ndarray
        Sample times [s].
    blocks : sequence of (str, (N, k) ndarray, sequence of str)
        ``(kind, values, names)`` per signal group, e.g. ``("state", x, model.states)``.
    cause : callable ``() -> str``
        The likely cause, computed only when a sample is non-finite.

    Raises
    ------
    DataError
        When a block holds a NaN or ±inf: the earliest such sample over all blocks, its time,
        signal and value, and ``cause()``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.simulate_diagnosis import refuse_non_finite
    >>> refuse_non_finite(np.arange(3.0), [("output", np.array([[0.0], [1.0], [np.inf]]), ("y",))],
    ...                   lambda: "a test")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.DataError: simulate would return a non-finite trace: output 'y' is inf at sample 2 (t=2 s) ...
    """
    hit = _first_bad(t, blocks)
    if hit is None:
        return
    k, what = hit
    raise DataError(f"simulate would return a non-finite trace: {what} at sample {k} (t={t[k]:g} s) and after. "
                    f"Likely cause: {cause()}")


def linear_cause(model: FaultModel, v: np.ndarray) -> str:
    """Why a linear run overflowed: the unstable eigenvalue, or inputs too large for the float range.

    Parameters
    ----------
    model : FaultModel
        The simulated plant (continuous: Re λ > 0 is unstable; discrete: |λ| > 1).
    v : (N, k) ndarray
        The stacked inputs of the run (controls, disturbances, faults, noise).

    Returns
    -------
    str
        The unstable eigenvalue and the time (or samples) after which the state leaves the float
        range, or the largest input when the plant is stable.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants import white_speyer
    >>> linear_cause(white_speyer(), np.zeros((1, 0)))  # doctest: +ELLIPSIS
    'the plant is unstable: A has the eigenvalue λ = 6.69443 with Re λ = 6.69443 > 0, ...'
    """
    text = _instability(model.A, model.is_discrete, "A" if not model.is_discrete else "the discrete A")
    if text is not None:
        return text + "; stabilise the plant (close a loop) or simulate a shorter run"
    big = float(np.abs(v).max()) if v.size else 0.0
    return (f"the plant is stable, so its inputs are too large for the float range (largest |input| = {big:.3g}, "
            "faults included); scale the inputs or fault sizes down")


def jacobian_text(f, tk: float, xk: np.ndarray, uk: np.ndarray) -> str:
    """The largest-real-part eigenvalue of a central-difference Jacobian of ``f`` at ``xk`` (best effort).

    Parameters
    ----------
    f : callable ``f(t, x, u) -> (n,)``
        The state derivative of a :class:`~fdikit.simulate.NonlinearPlant`.
    tk : float
        Time [s].
    xk : (n,) ndarray
        The last finite state.
    uk : (m,) ndarray
        The input held at ``tk``.

    Returns
    -------
    str
        ``"; "`` and the sentence naming the unstable eigenvalue (ready to append to a message),
        or ``""`` when the Jacobian is stable or cannot be evaluated.

    Examples
    --------
    >>> import numpy as np
    >>> jacobian_text(lambda t, x, u: 0.5 * x, 0.0, np.zeros(1), np.zeros(0))[:64]
    '; the plant is unstable: the Jacobian of f at the last finite st'
    >>> jacobian_text(lambda t, x, u: -x, 0.0, np.zeros(1), np.zeros(0))
    ''
    """
    try:
        n = xk.size
        J = np.empty((n, n))
        with np.errstate(all="ignore"):
            for i in range(n):
                step = 1e-6 * max(1.0, abs(xk[i]))
                e = np.zeros(n)
                e[i] = step
                J[:, i] = (np.asarray(f(tk, xk + e, uk), dtype=float) - np.asarray(f(tk, xk - e, uk), dtype=float)) \
                    / (2 * step)
        text = _instability(J, False, "the Jacobian of f at the last finite state")
    except Exception:  # noqa: BLE001 - only a diagnosis
        return ""
    return f"; {text}" if text else ""


def scheduled_cause(frozen_A: Callable[[np.ndarray], np.ndarray], rho: np.ndarray, x: np.ndarray) -> str:
    """Why a scheduled run overflowed: the most unstable frozen model ``A(ρ)`` on the schedule before it did.

    Parameters
    ----------
    frozen_A : callable ``values -> (k, n, n) ndarray``
        The stack of the frozen discrete ``A(ρ)`` at the distinct, sorted schedule ``values``.
    rho : (N,) ndarray
        The schedule, one ρ per sample.
    x : (N, n) ndarray
        The run's states, one row per sample of ``rho``; only the schedule before the first
        non-finite row is searched.

    Returns
    -------
    str
        The frozen model with the largest |λ| and, when it is unstable, its eigenvalue and the
        samples after which the state leaves the float range.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([[1.0], [2.0], [np.inf]])
    >>> scheduled_cause(lambda v: v[:, None, None], np.array([0.5, 1.5, 2.0]), x)[:58]
    'the plant is unstable: the frozen model A(ρ = 1.5) has the'
    """
    bad = np.flatnonzero(~np.all(np.isfinite(x), axis=1))
    upto = rho[: int(bad[0])] if bad.size and bad[0] > 0 else rho
    values = np.unique(upto)
    try:
        A = frozen_A(values)
        radius = np.abs(np.linalg.eigvals(A)).max(axis=1)
    except Exception:  # noqa: BLE001 - only a diagnosis
        return "the inputs or the frozen models; check the family"
    i = int(np.argmax(radius))
    text = _instability(A[i], True, f"the frozen model A(ρ = {values[i]:g})")
    if text is None:
        return (f"every frozen model on the schedule is stable (largest |λ| = {radius[i]:.6g}), so the schedule's "
                "variation or the inputs drive the growth; check the schedule rate and the inputs")
    return text + "; stabilise the plant or simulate a shorter schedule"
