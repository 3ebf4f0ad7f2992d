"""Prewhitening: AR fit, white innovations, batch == online, and CUSUM false alarms back at their design rate."""

import numpy as np
import pytest
import scipy.signal

from fdikit.decision import CusumEvaluator, ThresholdEvaluator
from fdikit.decision.whiten import Whitened, yule_walker
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals


def _ar1(phi, n, seed, q=1):
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((n, q))
    return scipy.signal.lfilter([1.0], [1.0, -phi], e, axis=0)


def _res(x):
    return Residuals(np.arange(x.shape[0]) * 0.01, x, tuple(f"r{j}" for j in range(x.shape[1])), ())


def test_yule_walker_recovers_ar_and_whitens():
    """AR(2) coefficients within 4 standard errors (≈ √((1 − a₂²)/N)); innovations' lag-1..5 autocorrelations
    within 4/√N of zero."""
    rng = np.random.default_rng(0)
    N = 200_000
    x = scipy.signal.lfilter([1.0], [1.0, -1.2, 0.5], rng.standard_normal(N))
    a = yule_walker(x, 2)
    np.testing.assert_allclose(a, [1.2, -0.5], atol=4 * np.sqrt((1 - 0.25) / N))
    w = Whitened(ThresholdEvaluator(), order=2).fit(_res(x[:, None]), false_alarm_prob=1e-3)
    e = w.whiten(_res(x[:, None])).r[:, 0]
    e = e - e.mean()
    for lag in range(1, 6):
        assert abs(e[:-lag] @ e[lag:] / (e @ e)) < 4 / np.sqrt(N)


def test_cusum_false_alarms_at_design_rate_only_after_whitening():
    """CUSUM designed for ARL0 = 1000 samples on strongly coloured noise (AR(1), φ = 0.9): without whitening
    the alarm count is many times N/ARL0; whitened it is N/ARL0 within 4 Poisson standard deviations
    (run lengths of a reset CUSUM are close to exponential) plus 20 % for the AR fit and Siegmund's approximation."""
    x_fit, x_test = _ar1(0.9, 200_000, 1), _ar1(0.9, 200_000, 2)
    N, arl0 = x_test.shape[0], 1000.0

    def count(ev):
        return len(ev.run(_res(x_test)).alarms)

    plain = CusumEvaluator().fit(_res(x_fit), arl0=arl0, shift=1.0 * x_fit.std())
    white = Whitened(CusumEvaluator(), order=3).fit(_res(x_fit), arl0=arl0, shift=1.0)
    expected = N / arl0
    assert count(plain) > 5 * expected
    assert abs(count(white) - expected) < 4 * np.sqrt(expected) + 0.2 * expected


def test_batch_equals_online_with_bad_samples():
    x = _ar1(0.8, 3000, 3, q=2)
    x[1500:, 0] += 3.0
    x[[10, 700, 701], 1] = np.nan
    w = Whitened(CusumEvaluator(), order=4).fit(_res(_ar1(0.8, 20_000, 4, q=2)), arl0=1e4, shift=1.0)
    batch = w.run(_res(x))
    w.reset()
    steps = [w.step(row) for row in x]
    np.testing.assert_array_equal(batch.fired, np.array([s.fired for s in steps]))
    np.testing.assert_array_equal(batch.valid, [s.valid for s in steps])
    assert batch.detected and batch.first_alarm(after=15.0) is not None


def test_bad_input():
    with pytest.raises(ParameterError, match="order"):
        Whitened(ThresholdEvaluator(), order=0)
    with pytest.raises(ParameterError, match="not fitted"):
        Whitened(ThresholdEvaluator()).run(_res(np.zeros((10, 1))))
    with pytest.raises(DataError, match="more than"):
        yule_walker(np.ones(5), 3)
