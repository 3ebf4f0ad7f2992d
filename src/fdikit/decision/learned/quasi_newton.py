"""Quasi-Newton minimisation (DFP and BFGS updates) and Robbins–Monro step sizes (Douglas et al. 1996, §6.3).

The BNN's deterministic training (:mod:`fdikit.decision.learned.bnn`) uses :func:`quasi_newton`: the
Davidon–Fletcher–Powell rank-2 update of the report, or BFGS (the default there; identical
iterates with exact line searches, far fewer cost evaluations with a practical one), with
scipy's strong-Wolfe line search.  :func:`robbins_monro_steps` gives ``ρ_k = ρ₀/(k+1)^a``,
``a ∈ (0.5, 1]`` so that ``Σρ = ∞`` and ``Σρ² < ∞``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import line_search as _wolfe_search

from fdikit.errors import DataError, ParameterError

__all__ = ["QuasiNewtonResult", "quasi_newton", "robbins_monro_steps"]


@dataclass(frozen=True)
class QuasiNewtonResult:
    """Outcome of :func:`quasi_newton`: minimiser, cost, gradient, inverse-Hessian estimate.

    Attributes
    ----------
    x : (n,) ndarray
        The last iterate (the minimiser when ``converged``).
    fun : float
        Cost at ``x``.
    grad : (n,) ndarray
        Gradient at ``x``.
    H : (n, n) ndarray
        The inverse-Hessian estimate at the end.
    iterations : int
        Quasi-Newton steps taken.
    evaluations : int
        Calls of the cost function, line searches included.
    converged : bool
        Whether a stopping test (``gtol``, or ``htol`` and ``ftol`` together) was met.
    message : str
        Why the iteration stopped.
    history : tuple of float
        The cost after each iteration, the starting cost first.

    References
    ----------
    Douglas et al. 1996, §6.3.1 (Davidon–Fletcher–Powell training of the network).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.quasi_newton import quasi_newton
    >>> res = quasi_newton(lambda x: (float(x @ x), 2 * x), np.ones(2))
    >>> res.converged, np.round(res.x, 6).tolist(), len(res.history) == res.iterations + 1
    (True, [0.0, 0.0], True)
    """

    x: np.ndarray
    fun: float
    grad: np.ndarray
    H: np.ndarray
    iterations: int
    evaluations: int
    converged: bool
    message: str
    history: tuple[float, ...] = ()


def _backtrack(fg, x, d, f0, g0):
    """Armijo backtracking from a unit step; the fallback when the Wolfe search fails."""
    slope, a = float(g0 @ d), 1.0
    for _ in range(60):
        f1, g1 = fg(x + a * d)
        if np.isfinite(f1) and f1 <= f0 + 1e-4 * a * slope:
            return a, f1, g1
        a *= 0.5
    return None


def _wolfe(fg, x, d, f0, g0, f_prev=None, c2=0.1):
    """Strong-Wolfe line search (scipy's MINPACK ``dcsrch``), first trial from the last decrease;
    Armijo backtracking when it fails."""
    cache: dict = {}

    def ev(z):
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = fg(z)
        return cache[key]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = _wolfe_search(lambda z: ev(z)[0], lambda z: ev(z)[1], x, d, gfk=g0, old_fval=f0,
                          old_old_fval=f_prev, c1=1e-4, c2=c2)[0]
    if a is None or not a > 0:
        return _backtrack(fg, x, d, f0, g0)
    f1, g1 = ev(x + a * d)
    return a, f1, g1


def quasi_newton(
    fun: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0,
    *,
    update: str = "dfp",
    max_iter: int = 200,
    gtol: float = 1e-6,
    htol: float = 1e-3,
    ftol: float = 1e-9,
    c2: float | None = None,
    line_search: Callable | None = None,
) -> QuasiNewtonResult:
    """Quasi-Newton minimisation with the Davidon–Fletcher–Powell update (§6.3.1) or BFGS.

    ``H`` estimates the inverse Hessian; after a step ``s`` with gradient change ``y``:

    * DFP:  ``H ← H + s sᵀ/(sᵀy) − H y yᵀ H/(yᵀ H y)``
    * BFGS: ``H ← (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ``,  ``ρ = 1/(sᵀy)``

    Both keep ``H`` positive definite when ``sᵀy > 0`` (the Wolfe condition guarantees it), and with
    an exact line search both end on a quadratic in ``n`` iterations with ``H = A⁻¹`` (they are the
    two ends of the Broyden family and give identical iterates under exact searches).  With inexact
    searches DFP corrects a poor ``H`` much more slowly.  ``H₀ = I`` (no Shanno–Phua rescaling: on an
    8-variable quadratic with condition 10³ it cost both updates their ``n``-step termination in
    floating point, one extra iteration).

    Parameters
    ----------
    fun : callable
        ``x -> (f, grad)``: the cost (float) and its gradient ((n,) array).
    x0 : array_like
        Starting point (flattened).
    update : {'dfp', 'bfgs'}, default 'dfp'
        The report's DFP update, or BFGS.
    max_iter : int, default 200
        Iteration limit.
    gtol : float, default 1e-6
        Stop when ``‖grad‖∞ ≤ gtol``.
    htol, ftol : float, default 1e-3, 1e-9
        The report's test: stop when the relative change of ``H`` (Frobenius) is below
        ``htol`` and the relative decrease of ``f`` is below ``ftol`` in the same iteration.
    c2 : float, optional
        Curvature constant of the default strong-Wolfe search (MINPACK ``dcsrch`` via scipy, first
        trial step from the last decrease, Armijo backtracking as the fallback); default 0.1 for DFP,
        which needs a fairly exact search, 0.9 for BFGS.
    line_search : callable, optional
        ``(fun, x, d, f, g) -> (alpha, f_new, g_new)``, or None on failure, used instead of the default search.

    Returns
    -------
    QuasiNewtonResult
        The last iterate, its cost, gradient and ``H``, the counts, whether it converged and why it stopped
        (a failed line search or the iteration limit return ``converged`` False, no exception).

    Raises
    ------
    ParameterError
        When ``update`` is not 'dfp' or 'bfgs'.
    DataError
        When the cost or its gradient is not finite at ``x0``.

    References
    ----------
    Douglas et al. 1996, §6.3.1 (the Davidon–Fletcher–Powell algorithm, convergence in ``n`` steps on a quadratic)
    and §6.4 (the deterministic initial training).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.quasi_newton import quasi_newton
    >>> A, b = np.diag([1.0, 10.0]), np.ones(2)
    >>> res = quasi_newton(lambda x: (0.5 * x @ A @ x - b @ x, A @ x - b), np.zeros(2))
    >>> res.converged, np.round(res.x, 6).tolist()
    (True, [1.0, 0.1])
    """
    if update not in ("dfp", "bfgs"):
        raise ParameterError(f"unknown quasi-Newton update {update!r}; use 'dfp' or 'bfgs'")
    c2 = (0.1 if update == "dfp" else 0.9) if c2 is None else float(c2)
    x = np.array(x0, dtype=float).ravel()
    f, g = fun(x)
    f, g = float(f), np.asarray(g, dtype=float)
    if not np.isfinite(f) or not np.all(np.isfinite(g)):
        raise DataError(f"the cost or its gradient is not finite at the starting point (f = {f})")
    n = x.size
    H, fresh, f_prev = np.eye(n), True, None
    history, evals = [f], [1]

    def fg(z):
        evals[0] += 1
        return fun(z)

    def search(d):
        if line_search is not None:
            return line_search(fg, x, d, f, g)
        return _wolfe(fg, x, d, f, g, f_prev, c2)

    def result(it, ok, msg):
        return QuasiNewtonResult(x, f, g, H, it, evals[0], ok, msg, tuple(history))

    for it in range(1, max_iter + 1):
        if np.max(np.abs(g)) <= gtol:
            return result(it - 1, True, "gradient below gtol")
        d = -H @ g
        if not g @ d < 0:  # lost positive definiteness numerically: restart from steepest descent
            H, fresh, d = np.eye(n), True, -g
        step = search(d)
        if step is None and not fresh:
            H, fresh, d = np.eye(n), True, -g
            step = search(d)
        if step is None:
            return result(it - 1, False, "line search found no decrease")
        a, f1, g1 = step
        s, y = a * d, np.asarray(g1, dtype=float) - g
        sy = float(s @ y)
        dH = np.inf
        if sy > 1e-12 * np.linalg.norm(s) * np.linalg.norm(y):
            Hy = H @ y
            if update == "dfp":
                change = np.outer(s, s) / sy - np.outer(Hy, Hy) / float(y @ Hy)
            else:
                change = ((sy + y @ Hy) / sy**2) * np.outer(s, s) - (np.outer(Hy, s) + np.outer(s, Hy)) / sy
            dH = np.linalg.norm(change) / np.linalg.norm(H)
            H, fresh = H + change, False
        df = f - float(f1)
        f_prev, x, f, g = f, x + s, float(f1), np.asarray(g1, dtype=float)
        history.append(f)
        if dH <= htol and df <= ftol * max(abs(f), 1e-300):
            return result(it, True, "Hessian estimate and cost settled")
    return result(max_iter, bool(np.max(np.abs(g)) <= gtol), "iteration limit")


def robbins_monro_steps(rho0: float, n: int, a: float = 0.75) -> np.ndarray:
    """Robbins–Monro gains ``ρ_k = ρ_0/(k+1)^a``, ``k = 0..n−1`` (§6.3.2).

    ``ρ_k > 0``; ``Σρ_k = ∞`` needs ``a ≤ 1`` and ``Σρ_k² = ρ_0² ζ(2a) < ∞`` needs ``a > 1/2``.

    Parameters
    ----------
    rho0 : float
        ``ρ_0 > 0``, the first gain.
    n : int
        Number of gains.
    a : float, default 0.75
        Decay exponent in (0.5, 1].

    Returns
    -------
    (n,) ndarray
        ``ρ_0, ρ_0/2^a, …, ρ_0/n^a``.

    Raises
    ------
    ParameterError
        When ``rho0`` is not positive or ``a`` is not in (0.5, 1].

    References
    ----------
    Douglas et al. 1996, §6.3.2 (the Robbins–Monro stochastic minimisation and its gain conditions).

    Examples
    --------
    >>> from fdikit.decision.learned.quasi_newton import robbins_monro_steps
    >>> robbins_monro_steps(1.0, 4, a=1.0).round(4).tolist()
    [1.0, 0.5, 0.3333, 0.25]
    """
    if not rho0 > 0:
        raise ParameterError(f"the Robbins-Monro gain rho0 must be positive, got {rho0}")
    if not 0.5 < a <= 1:
        raise ParameterError(
            f"the Robbins-Monro exponent must be in (0.5, 1] (sum rho = inf, sum rho^2 < inf), got {a}"
        )
    return rho0 / np.arange(1, int(n) + 1, dtype=float) ** a
