"""Thresholds of the Shiryayev SPRT: the false-alarm bound and the dynamic-programming threshold (Douglas et al.
1996, §7.2.2–7.2.3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import expit

from fdikit.decision.densities import GaussianDensity, UniformMeanDensity
from fdikit.errors import ParameterError

__all__ = ["ShiryayevDP", "shiryayev_dp", "shiryayev_threshold"]


def shiryayev_threshold(
    false_alarm_prob: float | None = None,
    *,
    false_alarm_cost: float | None = None,
    delay_cost: float | None = None,
    measurement_cost: float = 0.0,
) -> float:
    """The announcement threshold ``F_T`` (§7.2.3).

    * from a false-alarm probability ``α``: ``F_T = 1 − α`` — at an announcement ``P(no fault | data) = 1 − F ≤ α``,
      so ``P(false alarm) ≤ α`` when the change time follows the prior (the report's "practical rule");
    * from costs ``Q`` (false alarm), ``S`` (miss-alarm, i.e. delay, per sample) and ``C`` (per measurement): the
      report's bound on the infinite-horizon threshold, ``F_T ≤ (Q − C)/(Q + S)`` (from (7.21) with ``A ≥ 0``).
      The exact value needs the expected cost-to-go ``A(F_T)``; :func:`shiryayev_dp` computes it for ``m = 1``.

    Parameters
    ----------
    false_alarm_prob : float, optional
        ``α`` in (0, 1); give this or the costs.
    false_alarm_cost : float, optional
        ``Q``, the cost of a false alarm; must exceed ``measurement_cost``.
    delay_cost : float, optional
        ``S >= 0``, the cost per sample of a missed (delayed) announcement; needed with ``false_alarm_cost``.
    measurement_cost : float, default 0.0
        ``C >= 0``, the cost per measurement.

    Returns
    -------
    float
        ``F_T = 1 − α``, or the bound ``(Q − C)/(Q + S)``.

    Raises
    ------
    ParameterError
        When neither or both of ``false_alarm_prob`` and ``false_alarm_cost`` are given, ``α`` is not in (0, 1),
        or the costs violate ``S >= 0``, ``C >= 0``, ``Q > C`` (a missing ``delay_cost`` included).

    References
    ----------
    Douglas et al. 1996, §7.2.3, (7.20)–(7.21) (the threshold bound and ``α_i = 1 − F_{T,i}``) and §7.2.2,
    (7.10b) (``Q > C``).

    Examples
    --------
    >>> from fdikit.decision.shiryayev import shiryayev_threshold
    >>> shiryayev_threshold(0.05), round(shiryayev_threshold(false_alarm_cost=10.0, delay_cost=1.0), 6)
    (0.95, 0.909091)
    """
    if (false_alarm_prob is None) == (false_alarm_cost is None):
        raise ParameterError("give either false_alarm_prob, or false_alarm_cost and delay_cost")
    if false_alarm_prob is not None:
        if not 0 < false_alarm_prob < 1:
            raise ParameterError(f"false-alarm probability must be in (0, 1), got {false_alarm_prob}")
        return 1.0 - float(false_alarm_prob)
    Q, S, C = float(false_alarm_cost), float(delay_cost if delay_cost is not None else np.nan), float(measurement_cost)
    if not (S >= 0 and C >= 0 and Q > C):
        raise ParameterError(
            f"need delay_cost >= 0, measurement_cost >= 0 and false_alarm_cost > measurement_cost "
                         f"(7.10b), got Q={Q}, S={S}, C={C}")
    return (Q - C) / (Q + S)


@dataclass(frozen=True, eq=False)
class ShiryayevDP:
    """Result of :func:`shiryayev_dp`.

    ``threshold``: infinite-horizon ``F_T`` (7.21); ``bound``: ``(Q − C)/(Q + S)``; ``horizon_thresholds[n−1]``:
    the threshold with ``n`` stages to go (non-decreasing in ``n``, → ``threshold``); ``grid``/``cost``: ``J*(F)``;
    ``converged``: value iteration met ``tol``.

    Attributes
    ----------
    threshold : float
        Infinite-horizon threshold ``F_T`` (7.21): announce while the posterior is at or above it.
    bound : float
        The report's bound ``(Q − C)/(Q + S)`` (:func:`shiryayev_threshold`).
    horizon_thresholds : (iterations,) ndarray
        ``horizon_thresholds[n − 1]`` is the threshold with ``n`` stages to go.
    grid : (grid_size,) ndarray
        Posterior values ``F`` in [0, 1] (logit-spaced) on which ``J*`` is tabulated.
    cost : (grid_size,) ndarray
        ``J*(F)``, the Bayes risk of the optimal policy on ``grid``.
    iterations : int
        Value-iteration sweeps run.
    converged : bool
        Whether the last sweep changed ``J`` by at most ``tol · Q``.

    References
    ----------
    Douglas et al. 1996, §7.2.2, (7.8)–(7.10) (the dynamic program) and §7.2.3, (7.20)–(7.21) (its thresholds).

    Examples
    --------
    >>> from fdikit.decision.densities import GaussianDensity
    >>> from fdikit.decision.shiryayev import shiryayev_dp
    >>> res = shiryayev_dp(GaussianDensity(0.0, 1.0), GaussianDensity(1.0, 1.0), 0.01, 10.0, 1.0,
    ...                    grid_size=201, nodes=201)
    >>> res.converged, round(res.threshold, 2), round(res.expected_cost(0.0), 2)
    (True, 0.49, 6.99)
    """

    threshold: float
    bound: float
    horizon_thresholds: np.ndarray
    grid: np.ndarray
    cost: np.ndarray
    iterations: int
    converged: bool

    def expected_cost(self, F: float) -> float:
        """Bayes risk ``J*(F)`` of the optimal policy started at posterior ``F``."""
        return float(np.interp(F, self.grid, self.cost))


def _support(d) -> tuple[float, float]:
    if isinstance(d, GaussianDensity):
        s = np.sqrt(d.cov[0, 0])
        return d.mean[0] - 12 * s, d.mean[0] + 12 * s
    if isinstance(d, UniformMeanDensity):
        s = np.sqrt(d.cov[0, 0])
        return d.low[0] - 12 * s, d.high[0] + 12 * s
    raise ParameterError("pass x_range=(lo, hi) for densities other than GaussianDensity/UniformMeanDensity")


def shiryayev_dp(
    f0, f1, p: float, false_alarm_cost: float, delay_cost: float, measurement_cost: float = 0.0, *,
    grid_size: int = 401, nodes: int = 401, x_range: tuple[float, float] | None = None,
    tol: float = 1e-10, max_iter: int = 100_000,
) -> ShiryayevDP:
    """Dynamic-programming thresholds of §7.2.2 for the binary test (``m = 1``, scalar measurement).

    Value iteration on (7.8)–(7.10): ``J_N = (1 − F) Q``, ``J_k(F) = min[(1 − F) Q, C + S F + A_k(F)]`` with
    ``A_k(F) = E[J_{k+1}(F') | F]``, ``F'`` the posterior after the next sample, the expectation over the predictive
    density ``M f_1 + (1 − M) f_0``.  ``F`` lives on a logit-spaced grid (``J`` is concave, interpolated linearly),
    the expectation is a trapezoid rule on ``nodes`` points.  The report calls this intractable and stops at the
    bound; for ``m > 1`` the state is ``m``-dimensional and no grid is offered.

    Parameters
    ----------
    f0, f1 : density
        Scalar densities (``dim`` 1, row-wise ``logpdf``) of the measurement without and with the fault, e.g.
        :class:`~fdikit.decision.densities.GaussianDensity`.
    p : float
        Per-sample prior probability of the switch ``H_0 → H_1``, in [0, 1).
    false_alarm_cost : float
        ``Q``.
    delay_cost : float
        ``S``, per sample of delay.
    measurement_cost : float, default 0.0
        ``C``, per measurement.
    grid_size : int, default 401
        Points of the posterior grid (0, 1 and ``grid_size − 2`` logit-spaced points in between).
    nodes : int, default 401
        Trapezoid nodes of the expectation over the next measurement.
    x_range : (float, float), optional
        Integration range of the measurement; default ±12 σ around the supports of ``f0`` and ``f1`` (required
        for densities other than ``GaussianDensity`` / ``UniformMeanDensity``).
    tol : float, default 1e-10
        Stop when a sweep changes ``J`` by at most ``tol · Q``.
    max_iter : int, default 100000
        Most value-iteration sweeps.

    Returns
    -------
    ShiryayevDP
        The infinite-horizon threshold, the bound, the thresholds per horizon, ``J*`` on the grid and the
        convergence record.

    Raises
    ------
    ParameterError
        When ``p`` is not in [0, 1), the costs are invalid (:func:`shiryayev_threshold`), a density is not
        scalar, or ``x_range`` is needed and not given.

    References
    ----------
    Douglas et al. 1996, §7.2.2, (7.8)–(7.10), Lemma 7.3, and §7.2.3, (7.20)–(7.21).

    Examples
    --------
    >>> from fdikit.decision.densities import GaussianDensity
    >>> from fdikit.decision.shiryayev import shiryayev_dp
    >>> res = shiryayev_dp(GaussianDensity(0.0, 1.0), GaussianDensity(1.0, 1.0), 0.01, 10.0, 1.0,
    ...                    grid_size=201, nodes=201)
    >>> round(res.threshold, 2), round(res.bound, 6)
    (0.49, 0.909091)
    """
    if not 0 <= p < 1:
        raise ParameterError(f"p must be in [0, 1), got {p}")
    bound = shiryayev_threshold(false_alarm_cost=false_alarm_cost, delay_cost=delay_cost,
                                measurement_cost=measurement_cost)
    Q, S, C = float(false_alarm_cost), float(delay_cost), float(measurement_cost)
    if getattr(f0, "dim", 1) != 1 or getattr(f1, "dim", 1) != 1:
        raise ParameterError("shiryayev_dp handles scalar measurements only")
    if x_range is None:
        (a0, b0), (a1, b1) = _support(f0), _support(f1)
        x_range = (min(a0, a1), max(b0, b1))
    x = np.linspace(*x_range, nodes)
    w = np.full(nodes, x[1] - x[0])
    w[[0, -1]] *= 0.5
    l0, l1 = f0.logpdf(x[:, None]), f1.logpdf(x[:, None])
    q0, q1 = w * np.exp(l0), w * np.exp(l1)
    q0, q1 = q0 / q0.sum(), q1 / q1.sum()
    F = np.concatenate([[0.0], expit(np.linspace(-30, 30, grid_size - 2)), [1.0]])
    M = F + p * (1.0 - F)
    with np.errstate(divide="ignore"):
        logit_M = np.log(M) - np.log1p(-M)
    Fn = expit(logit_M[:, None] + (l1 - l0)[None, :])  # posterior after each node, per grid point
    idx = np.clip(np.searchsorted(F, Fn) - 1, 0, F.size - 2)
    frac = (Fn - F[idx]) / (F[idx + 1] - F[idx])
    weight = M[:, None] * q1 + (1.0 - M[:, None]) * q0
    T = np.zeros((F.size, F.size))  # A = T @ J: predictive expectation of the interpolated J at the next posterior
    rows = np.broadcast_to(np.arange(F.size)[:, None], idx.shape)
    np.add.at(T, (rows, idx), weight * (1.0 - frac))
    np.add.at(T, (rows, idx + 1), weight * frac)
    stop = (1.0 - F) * Q
    J, thresholds, converged, it = stop.copy(), [], False, 0
    while it < max_iter:
        it += 1
        A = T @ J
        go = C + S * F + A
        J_new = np.minimum(stop, go)
        g = stop - go  # <= 0: stopping is optimal; the stop region is the top interval [F_T, 1]
        k = np.flatnonzero(g > 0)
        k = k[-1] if k.size else -1
        thresholds.append(F[0] if k < 0 else F[-1] if k == F.size - 1 else
                          F[k] + g[k] / (g[k] - g[k + 1]) * (F[k + 1] - F[k]))
        done = np.abs(J_new - J).max() <= tol * Q
        J = J_new
        if done:
            converged = True
            break
    return ShiryayevDP(float(thresholds[-1]), bound, np.array(thresholds), F, J, it, converged)
