"""Residual tests: statistics against a brute-force computation, level and power by binomial bounds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from fdikit.errors import DataError
from fdikit.identify import cross_correlation_test, whiteness_test

SERIES, N, LAGS, LEVEL = 40, 1000, 20, 0.05


def ar1(rng, phi, n=N):
    e = rng.standard_normal(n + 200)
    x = np.zeros_like(e)
    for k in range(1, e.size):
        x[k] = phi * x[k - 1] + e[k]
    return x[200:, None]


def test_ljung_box_statistic_matches_the_textbook_formula():
    e = np.random.default_rng(0).standard_normal((500, 2))
    res = whiteness_test(e, lags=10)
    for j in range(2):
        x = e[:, j] - e[:, j].mean()
        r = [np.dot(x[k:], x[:-k]) / np.dot(x, x) for k in range(1, 11)]
        q = 500 * 502 * sum(rk**2 / (500 - k) for k, rk in enumerate(r, 1))
        assert res.statistic[j] == pytest.approx(q, rel=1e-12)
    assert res.threshold == pytest.approx(stats.chi2.ppf(0.99, 10))
    assert res.bound == pytest.approx(stats.norm.ppf(0.995) / np.sqrt(500))


def test_whiteness_level_and_power():
    # Under H0 each test rejects with probability ≈ LEVEL (χ² asymptotics, N = 1000 ≫ M = 20), so the
    # number of rejections among SERIES independent white series is Binomial(SERIES, LEVEL); the bound below is
    # exceeded with probability < 1e-4.  An AR(1) residual with φ = 0.5 has ρ_1 = 0.5, so Q ≈ N Σ φ^(2k) ≈ 333
    # against a threshold of 31.4: the power is ≈ 1; we require at least the 1e-4 quantile of Binomial(40, 0.99).
    rng = np.random.default_rng(1)
    white = sum(not whiteness_test(rng.standard_normal((N, 1)), LAGS, LEVEL).passed[0] for _ in range(SERIES))
    assert white <= stats.binom.isf(1e-4, SERIES, LEVEL)
    coloured = sum(not whiteness_test(ar1(rng, 0.5), LAGS, LEVEL).passed[0] for _ in range(SERIES))
    assert coloured >= stats.binom.ppf(1e-4, SERIES, 0.99)


def test_cross_correlation_statistic_is_the_regression_statistic():
    # N rᵀ R⁻¹ r / λ is the explained sum of squares of regressing ε on [u(t) … u(t−M)], over λ.
    rng = np.random.default_rng(2)
    u, e = ar1(rng, 0.8, 600), rng.standard_normal((600, 1))
    M = 5
    res = cross_correlation_test(e, u, lags=M)
    uc, ec = u[:, 0] - u.mean(), e[:, 0] - e.mean()
    Phi = np.column_stack([uc[M - k:600 - k] for k in range(M + 1)])
    y = ec[M:]
    fitted = Phi @ np.linalg.lstsq(Phi, y, rcond=None)[0]
    assert res.statistic[0, 0] == pytest.approx(np.dot(fitted, fitted) / np.mean(y**2), rel=1e-10)
    assert res.dof == M + 1


def test_cross_correlation_level_with_a_coloured_input_and_power():
    # White ε independent of an AR(1) input: the statistic is χ²(M + 1) without a white input, so the rejections
    # are Binomial(SERIES, LEVEL) (bound exceeded with probability < 1e-4).  A residual holding 0.3 u(t − 2)
    # (an unmodelled path; correlation 0.3 / √(1 + 0.09 σ_u²)) is rejected with power ≈ 1.
    rng = np.random.default_rng(3)
    rejected, leaked = 0, 0
    for _ in range(SERIES):
        u = ar1(rng, 0.8)
        e = rng.standard_normal((N, 1))
        rejected += not cross_correlation_test(e, u, LAGS, LEVEL).passed[0, 0]
        leaked += not cross_correlation_test(e + 0.3 * np.roll(u, 2, axis=0), u, LAGS, LEVEL).passed[0, 0]
    assert rejected <= stats.binom.isf(1e-4, SERIES, LEVEL)
    assert leaked >= stats.binom.ppf(1e-4, SERIES, 0.99)


def test_segments_are_not_joined_and_bad_data_refused():
    rng = np.random.default_rng(4)
    x = ar1(rng, 0.0, 400)
    whole = whiteness_test(x, 5)
    split = whiteness_test([x[:200], x[200:]], 5)
    assert split.samples == whole.samples == 400
    # the lag products across the split are left out: the statistics differ, but only by those terms
    assert split.statistic[0] != whole.statistic[0]
    with pytest.raises(DataError, match="NaN"):
        whiteness_test(np.r_[x, [[np.nan]]])
    with pytest.raises(DataError, match="lags"):
        whiteness_test(x[:5], 10)
