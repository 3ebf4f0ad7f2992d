"""Residual tests of model validation: whiteness (Ljung–Box) and independence from the inputs.

A model that captures the data leaves one-step prediction errors ``ε`` that are white and
uncorrelated with past inputs (Ljung 1999, §16.6).

* Whiteness, per output: the sample autocorrelation ``ρ_k = c_k / c_0`` for ``k = 1 … M`` and the
  Ljung–Box statistic ``Q = N (N + 2) Σ ρ_k² / (N − k)``, asymptotically ``χ²(M)`` for a white
  residual of a model fixed before the data (held-out validation data: no degrees of freedom are
  spent).  The test rejects at level ``α`` when ``Q > χ²_{1−α}(M)``, so a white residual is
  rejected with probability ``α`` (asymptotically); ``±z_{1−α/2}/√N`` is the per-lag bound.
* Independence, per output and input: with ``φ(t) = [u(t), u(t−1), …, u(t−M)]``,
  ``r = (1/N) Σ φ(t) ε(t)`` and ``R = (1/N) Σ φ φᵀ``, the statistic ``N rᵀ R⁻¹ r / λ``
  (``λ`` the residual variance) is asymptotically ``χ²(M + 1)`` when ``ε`` is white and
  independent of ``u`` (Ljung 1999, §16.6); it does not need a white input.

Each output (and each output–input pair) is tested at level ``α`` on its own. Data in several
gap-free segments are pooled: the sums run inside each segment, never across a gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError

__all__ = ["CorrelationTest", "cross_correlation_test", "whiteness_test"]


@dataclass(frozen=True, eq=False)
class CorrelationTest:
    """Result of a residual correlation test.

    Attributes
    ----------
    kind : str
        ``"whiteness"`` or ``"cross-correlation"``.
    statistic, pvalue : arrays
        Test statistic and its p-value: shape (p,) for whiteness, (p, m) for cross-correlation.
    passed : bool array
        ``statistic <= threshold`` (the residual passes at ``level``); same shape.
    threshold : float
        ``χ²_{1−level}(dof)``.
    dof : int
        Degrees of freedom (``M``, or ``M + 1`` for cross-correlation).
    level : float
        Significance level ``α`` (the probability of rejecting a residual that satisfies the hypothesis).
    lags : int
        ``M``.
    correlation : array
        Normalised correlations: (M + 1, p) autocorrelation at lags 0 … M, or (M + 1, p, m)
        cross-correlation ``ε(t)`` with ``u(t − k)``.
    bound : float
        Per-lag confidence bound ``z_{1−α/2} / √N``.
    samples : int
        ``N``.

    Examples
    --------
    >>> import numpy as np
    >>> res = whiteness_test(np.random.default_rng(0).standard_normal((500, 2)), lags=10, level=0.05)
    >>> res.kind, res.dof, res.statistic.shape, round(res.threshold, 2)
    ('whiteness', 10, (2,), 18.31)

    References
    ----------
    Ljung 1999, §16.6.
    """

    kind: str
    statistic: np.ndarray
    pvalue: np.ndarray
    passed: np.ndarray
    threshold: float
    dof: int
    level: float
    lags: int
    correlation: np.ndarray
    bound: float
    samples: int


def _segments(name: str, value, width: int | None = None) -> list[np.ndarray]:
    parts = value if isinstance(value, list | tuple) else [value]
    out = []
    for k, part in enumerate(parts):
        a = np.asarray(part, dtype=float)
        a = a.reshape(-1, 1) if a.ndim == 1 else a
        if a.ndim != 2:
            raise DataError(f"{name} segment {k} must be an (N, k) array, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise DataError(f"{name} segment {k} holds NaN or inf; split the data at the gaps and pass the "
                            "segments as a list")
        if width is not None and a.shape[1] != width:
            raise DataError(f"{name} segment {k} has {a.shape[1]} columns, the others {width}")
        width = a.shape[1]
        out.append(a)
    return out


def _check(lags, level, segs) -> tuple[int, float, int]:
    lags = validate.integer("lags", lags, minimum=1)
    level = validate.in_range("level", level, 0.0, 1.0, closed="neither")
    N = sum(len(s) for s in segs)
    if min(len(s) for s in segs) <= lags:
        raise DataError(f"a residual segment of {min(len(s) for s in segs)} samples is not longer than lags={lags}; "
                        "use fewer lags or longer segments")
    return lags, level, N


def whiteness_test(residual, lags: int = 20, level: float = 0.01) -> CorrelationTest:
    """Ljung–Box whiteness test of each residual column.

    Parameters
    ----------
    residual : (N, p) array or list of such arrays (gap-free segments)
        Prediction errors, finite.
    lags : int >= 1, default 20
        ``M``, the largest lag.
    level : float in (0, 1), default 0.01
        Significance level ``α``.

    Returns
    -------
    CorrelationTest
        ``kind="whiteness"``, statistic ``Q`` per column, ``dof = M``.

    Raises
    ------
    DataError
        For a non-finite residual or a segment not longer than ``lags``.
    ParameterError
        For a bad ``lags`` or ``level``.

    Examples
    --------
    >>> import numpy as np
    >>> e = np.random.default_rng(1).standard_normal((2000, 1))
    >>> whiteness_test(e).passed.tolist(), whiteness_test(np.cumsum(e, axis=0)).passed.tolist()
    ([True], [False])

    References
    ----------
    Ljung 1999, §16.6 (residual analysis: the whiteness test).
    """
    from scipy import stats

    segs = _segments("residual", residual)
    lags, level, N = _check(lags, level, segs)
    mean = np.concatenate(segs).mean(axis=0)
    segs = [s - mean for s in segs]
    c = np.array([sum(np.sum(s[k:] * s[:len(s) - k], axis=0) for s in segs) for k in range(lags + 1)]) / N
    rho = c / np.where(c[0] > 0, c[0], 1.0)  # a zero residual has no correlation (Q = 0)
    k = np.arange(1, lags + 1)[:, None]
    Q = N * (N + 2) * np.sum(rho[1:] ** 2 / (N - k), axis=0)
    thr = float(stats.chi2.ppf(1 - level, lags))
    return CorrelationTest("whiteness", Q, stats.chi2.sf(Q, lags), Q <= thr, thr, lags, level, lags, rho,
                           float(stats.norm.ppf(1 - level / 2) / np.sqrt(N)), N)


def cross_correlation_test(residual, u, lags: int = 20, level: float = 0.01) -> CorrelationTest:
    """Test that each residual column is uncorrelated with each input at lags 0 … M.

    Parameters
    ----------
    residual : (N, p) array or list of such arrays (gap-free segments)
        Prediction errors, finite.
    u : (N, m) array or list of such arrays (the same segments)
        The inputs.
    lags : int >= 1, default 20
        ``M``: ``ε(t)`` against ``u(t), …, u(t − M)``.
    level : float in (0, 1), default 0.01
        Significance level ``α``.

    Returns
    -------
    CorrelationTest
        ``kind="cross-correlation"``, statistic per (output, input), ``dof = M + 1``.

    Raises
    ------
    DataError
        For non-finite data, segments that do not match, or a segment not longer than ``lags``.
    ParameterError
        For a bad ``lags`` or ``level``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> u, e = rng.standard_normal((2000, 1)), rng.standard_normal((2000, 1))
    >>> leak = e + 0.3 * np.roll(u, 2, axis=0)  # an unmodelled input path
    >>> cross_correlation_test(e, u).passed.tolist(), cross_correlation_test(leak, u).passed.tolist()
    ([[True]], [[False]])

    References
    ----------
    Ljung 1999, §16.6 (residual analysis: independence of residuals and past inputs).
    """
    from scipy import stats

    es = _segments("residual", residual)
    us = _segments("u", u)
    if len(us) != len(es) or any(len(a) != len(b) for a, b in zip(es, us)):
        raise DataError("residual and u must have the same segments (one input row per residual row)")
    lags, level, _ = _check(lags, level, es)
    p, m = es[0].shape[1], us[0].shape[1]
    e_mean, u_mean = np.concatenate(es).mean(axis=0), np.concatenate(us).mean(axis=0)
    # rows t = M … N−1 of every segment; Phi[:, k] = u(t − k)
    phis, eps = [], []
    for e, uu in zip(es, us):
        uu = uu - u_mean
        n = len(e) - lags
        phis.append(np.stack([uu[lags - k:lags - k + n] for k in range(lags + 1)], axis=1))  # (n, M+1, m)
        eps.append(e[lags:] - e_mean)
    Phi, E = np.concatenate(phis), np.concatenate(eps)
    N = len(E)
    lam = np.sum(E**2, axis=0) / N
    stat, corr = np.zeros((p, m)), np.zeros((lags + 1, p, m))
    for j in range(m):
        P = Phi[:, :, j]
        Ru = P.T @ P / N
        r = P.T @ E / N  # (M+1, p)
        lam_ = np.where(lam > 0, lam, 1.0)  # a zero residual is uncorrelated with anything
        stat[:, j] = N * np.sum(r * np.linalg.solve(Ru, r), axis=0) / lam_
        corr[:, :, j] = r / np.sqrt(lam_ * np.sum(P[:, 0] ** 2) / N)
    thr = float(stats.chi2.ppf(1 - level, lags + 1))
    return CorrelationTest("cross-correlation", stat, stats.chi2.sf(stat, lags + 1), stat <= thr, thr, lags + 1,
                           level, lags, corr, float(stats.norm.ppf(1 - level / 2) / np.sqrt(N)), N)
