"""Observability of multiple-model systems and the minimum-mismatch model set: Hallouzi 2008, §3.3.1 and §3.6.4.

:func:`observability_condition` is the condition number (3.9) of the nonlinear observability matrix of Def. 3.1,
(3.7)–(3.8); :func:`pair_observability` averages it for a two-model MM along a state realization (Example 3.1,
Table 3.4); :func:`minimum_mismatch_points` places the models of Li et al.'s (2005) minimum-mismatch set, the
comparison of §3.6.4.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fdikit.errors import DesignError

__all__ = ["minimum_mismatch_points", "observability_condition", "pair_observability"]


def minimum_mismatch_points(distribution, n_models: int) -> np.ndarray:
    """Parameter values of Li et al.'s (2005) "minimum-mismatch" set, Hallouzi 2008, §3.6.4, (3.58).

    The CDF is split into ``n_models`` equiprobable regions; each model sits at the probability
    centre of its region, ``F⁻¹((i − ½)/N)``.  ``distribution`` is a frozen ``scipy.stats``
    distribution (anything with ``ppf``).

    Parameters
    ----------
    distribution : scipy.stats frozen distribution
        Distribution of the parameter (anything with ``ppf``).
    n_models : int
        Number of models, at least 1.

    Returns
    -------
    ndarray
        (n_models,) parameter values, increasing.

    Raises
    ------
    DesignError
        If ``n_models < 1`` or ``distribution`` has no ``ppf``.

    Examples
    --------
    >>> from scipy.stats import norm
    >>> minimum_mismatch_points(norm(1.0, 0.2), 2).round(4).tolist()   # §3.6.4: 0.865 and 1.135
    [0.8651, 1.1349]

    References
    ----------
    Hallouzi 2008, §3.6.4, (3.58), Table 3.4 (after Li et al. 2005).
    """
    if int(n_models) < 1:
        raise DesignError(f"n_models must be >= 1, got {n_models}")
    if not hasattr(distribution, "ppf"):
        raise DesignError("distribution must have a ppf (inverse CDF), e.g. scipy.stats.norm(1.0, 0.2)")
    q = (np.arange(int(n_models)) + 0.5) / int(n_models)
    return np.asarray(distribution.ppf(q), float)


def observability_condition(step: Callable[[np.ndarray, np.ndarray], np.ndarray],
                            output: Callable[[np.ndarray], np.ndarray], state, inputs,
                            rel_step: float = 1e-6) -> tuple[float, np.ndarray]:
    """Condition number (3.9) of the nonlinear observability matrix ``∂hⁿ/∂x`` of Def. 3.1, (3.7)–(3.8).

    ``hⁿ(x) = [h(x); h(f(x, u_k)); …; h(f^{n−1}(x))]`` with ``f(x, u) = step(x, u)``, ``h = output``
    and ``u_k … u_{k+n−2}`` the first ``n − 1`` rows of ``inputs``.  The Jacobian is taken by
    central differences (exact for systems quadratic in ``x``, such as the MM system with the
    weights appended to the state, (3.10)).  Returns ``(cond, jacobian)``; ``cond`` is ``inf`` if
    the matrix is rank deficient.

    Parameters
    ----------
    step : callable
        ``step(x, u) -> x_next``, the state transition ``f``.
    output : callable
        ``output(x) -> y``, the measurement ``h``.
    state : array_like
        The point ``x`` (n) where the matrix is evaluated.
    inputs : array_like
        Inputs ``u_k, …`` (at least n − 1 rows).
    rel_step : float, optional
        Relative central-difference step (default 1e-6).

    Returns
    -------
    cond : float
        ``σ_max / σ_min`` of the observability matrix, (3.9); ``inf`` when it is rank deficient.
    jacobian : ndarray
        ``∂hⁿ/∂x`` (n·p x n).

    Raises
    ------
    DesignError
        If fewer than n − 1 input samples are given.

    Examples
    --------
    >>> step = lambda z, u: np.array([z[1] * z[0], z[1]])     # x⁺ = μ x with the weight μ as a state
    >>> cond, J = observability_condition(step, lambda z: z[:1], [1.0, 0.5], np.zeros((1, 1)))
    >>> round(cond, 4), J.round(6).tolist()
    (1.6404, [[1.0, 0.0], [0.5, 1.0]])

    References
    ----------
    Hallouzi 2008, §3.3.1, Definition 3.1, (3.7)–(3.10).
    """
    x0 = np.asarray(state, float).ravel()
    n = x0.size
    U = np.atleast_2d(np.asarray(inputs, float))
    if U.shape[0] < n - 1:
        raise DesignError(f"need n − 1 = {n - 1} input samples, got {U.shape[0]}")

    def stacked(x):
        out = [np.atleast_1d(output(x))]
        for k in range(n - 1):
            x = np.asarray(step(x, U[k]), float)
            out.append(np.atleast_1d(output(x)))
        return np.concatenate(out)

    J = np.empty((stacked(x0).size, n))
    for i in range(n):
        h = rel_step * max(1.0, abs(x0[i]))
        e = np.zeros(n)
        e[i] = h
        J[:, i] = (stacked(x0 + e) - stacked(x0 - e)) / (2 * h)
    sv = np.linalg.svd(J, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 and sv.size >= n else float("inf")
    return cond, J


def pair_observability(first, second, C, states, weights, u) -> float:
    """Mean condition number (3.9) of the observability matrix of a 2-model MM along a state realization.

    The MM is ``x⁺ = μ (A₁x + B₁u) + (1 − μ)(A₂x + B₂u)``, ``y = C x``, with the weight appended to the state as a
    constant (``z = [x; μ]``, one free weight; the thesis does not say how the weights enter (3.8)); ``first``,
    ``second`` are ``(A, B)``;
    ``states`` (K, n) and ``weights`` (K,) are the points ``(x_k, μ_k)`` where the matrix is evaluated; the
    input ``u`` (m,) is held constant over the ``n`` steps of (3.8).  Used for Example 3.1 and Table 3.4.

    Parameters
    ----------
    first, second : tuple of array_like
        ``(A, B)`` of the two models, (n x n) and (n x m).
    C : array_like
        Common output matrix (p x n).
    states : array_like
        (K, n) states ``x_k``.
    weights : array_like
        (K,) weights ``μ_k`` of the first model.
    u : array_like
        (m,) input held constant.

    Returns
    -------
    float
        Mean of the condition numbers over the K points.

    Examples
    --------
    >>> c = pair_observability(([[0.5]], [[1.0]]), ([[0.9]], [[1.0]]), [[1.0]], [[1.0]], [0.5], [0.0])
    >>> round(c, 3)
    3.866

    References
    ----------
    Hallouzi 2008, §3.3.1, Example 3.1, (3.8)–(3.9), Table 3.1; §3.6.4, Table 3.4.
    """
    (A1, B1), (A2, B2) = [(np.asarray(A, float), np.atleast_2d(np.asarray(B, float))) for A, B in (first, second)]
    C = np.atleast_2d(np.asarray(C, float))
    n = A1.shape[0]
    u = np.atleast_1d(np.asarray(u, float))
    B1 = B1.reshape(n, -1)
    B2 = B2.reshape(n, -1)

    def step(z, uk):
        x, m = z[:n], z[n]
        return np.concatenate([m * (A1 @ x + B1 @ uk) + (1 - m) * (A2 @ x + B2 @ uk), z[n:]])

    U = np.tile(u, (n, 1))
    conds = [observability_condition(step, lambda z: C @ z[:n], np.append(x, m), U)[0]
             for x, m in zip(np.asarray(states, float), np.asarray(weights, float))]
    return float(np.mean(conds))

