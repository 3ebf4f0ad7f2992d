"""Thresholds of the Shiryayev SPRT: the false-alarm bound and the dynamic-programming threshold (§7.1)."""

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
