"""Threshold evaluator: calibration against binomial theory, persistence, batch == online, bad input."""

import numpy as np
import pytest
from scipy.stats import norm

from fdikit import FaultModel
from fdikit.decision import ThresholdEvaluator, alpha_from_rate
from fdikit.design import kalman
from fdikit.diagnosis import UNKNOWN_FAULT, isolate
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals
from fdikit.simulate import simulate


def _kalman_setup(seed=0):
    rng = np.random.default_rng(seed)
    A = np.array([[0.95, 0.1, 0.0], [-0.1, 0.9, 0.05], [0.0, 0.0, 0.8]])
    model = FaultModel(A=A, C=rng.standard_normal((3, 3)), Bw=np.eye(3), dt=0.01)
    W, V = 0.01 * np.eye(3), 0.04 * np.eye(3)
    return model, W, V, kalman(model, W, V).generator


def test_calibrated_rate_matches_binomial_on_fresh_data():
    """Fit on one fault-free run, count exceedances on another: Binomial(N, α/q) per residual.

    Kalman innovations are white Gaussian, so each residual exceeds its Gaussian threshold
    with probability α/q per sample.  Tolerance: 4 binomial standard deviations plus the
    effect of estimating σ from 100k samples (δσ/σ ≈ 1/√(2N) moves the tail probability by
    2 z φ(z) δσ/σ, ≈ 16 counts here).
    """
    model, W, V, gen = _kalman_setup()
    fit_run = gen.run(simulate(model, duration=1000, noise_cov=W, measurement_noise_std=np.sqrt(np.diag(V)), rng=1))
    fresh = gen.run(simulate(model, duration=1000, noise_cov=W, measurement_noise_std=np.sqrt(np.diag(V)), rng=2))
    alpha = 0.03
    ev = ThresholdEvaluator().fit(fit_run.slice(start=2.0), false_alarm_prob=alpha)
    r = fresh.slice(start=2.0)
    exceed = (np.abs(r.r - ev.center) > ev.thresholds).sum(axis=0)
    N, a_i = len(r), alpha / 3
    z = norm.isf(a_i / 2)
    tol = 4 * np.sqrt(N * a_i * (1 - a_i)) + N * 2 * z * norm.pdf(z) / np.sqrt(2 * N)
    np.testing.assert_array_less(np.abs(exceed - N * a_i), tol)


def test_empirical_calibration_quantile():
    rng = np.random.default_rng(3)
    r = Residuals(np.arange(200_000) * 0.01, rng.standard_t(4, size=(200_000, 1)), ("r",), ())
    ev = ThresholdEvaluator().fit(r, false_alarm_prob=1e-2, method="empirical")
    frac = np.mean(np.abs(r.r[:, 0] - ev.center[0]) > ev.thresholds[0])
    assert frac == pytest.approx(1e-2, abs=2e-4)
    with pytest.raises(DataError, match="needs at least"):
        ThresholdEvaluator().fit(r.slice(stop=1.0), false_alarm_prob=1e-3, method="empirical")


def test_rate_per_hour_conversion():
    assert alpha_from_rate(1.0, 0.01) == pytest.approx(0.01 / 3600)
    rng = np.random.default_rng(0)
    r = Residuals(np.arange(50_000) * 0.01, rng.standard_normal((50_000, 2)), ("a", "b"), ())
    ev = ThresholdEvaluator().fit(r, false_alarms_per_hour=1.0)
    assert ev.alpha == pytest.approx(0.01 / 3600)
    np.testing.assert_allclose(ev.thresholds / r.r.std(axis=0, ddof=1), norm.isf(ev.alpha / 4), rtol=1e-12)


def _brute_persistence(exceed, k, n):
    out = np.zeros_like(exceed)
    for i in range(exceed.shape[0]):
        out[i] = exceed[max(0, i - n + 1) : i + 1].sum(axis=0) >= k
    return out


@pytest.mark.parametrize("k,n", [(1, 1), (2, 3), (3, 5), (5, 5)])
def test_persistence_matches_brute_force(k, n):
    rng = np.random.default_rng(k * 10 + n)
    r = Residuals(np.arange(400) * 0.1, rng.standard_normal((400, 2)), ("a", "b"), ("fa", "fb"))
    ev = ThresholdEvaluator(thresholds=[0.8, 1.0], persistence=(k, n))
    d = ev.run(r)
    np.testing.assert_array_equal(d.fired, _brute_persistence(np.abs(r.r) > [0.8, 1.0], k, n))
    np.testing.assert_array_equal(d.alarm, d.fired.any(axis=1))


def test_batch_equals_online_with_bad_samples():
    rng = np.random.default_rng(5)
    rr = rng.standard_normal((500, 3))
    rr[[10, 11, 200, 499], 1] = np.nan
    rr[300, 0] = np.inf
    r = Residuals(np.arange(500) * 0.01, rr, ("a", "b", "c"), ("fa", "fb", None))
    ev = ThresholdEvaluator(thresholds=[1.5, 1.5, 2.0], center=[0.1, 0.0, 0.0], persistence=(2, 3),
                            isolates=("fa", "fb", None))
    batch = ev.run(r)
    ev.reset()
    steps = [ev.step(row) for row in rr]
    np.testing.assert_array_equal(batch.fired, np.array([s.fired for s in steps]))
    np.testing.assert_array_equal(batch.isolated, [s.fault for s in steps])
    np.testing.assert_array_equal(batch.valid, [s.valid for s in steps])
    assert batch.invalid_count == 5
    # an invalid sample holds the previous decision
    np.testing.assert_array_equal(batch.fired[11], batch.fired[9])


def test_isolation_logic():
    fired = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 0]], bool)
    out = isolate(fired, ("f1", "f1", None))
    assert out.tolist() == ["none", "f1", "f1", UNKNOWN_FAULT, UNKNOWN_FAULT, "f1"]
    out = isolate(fired, ("f1", "f2", "f3"))
    assert out.tolist() == ["none", "f1", UNKNOWN_FAULT, "f3", UNKNOWN_FAULT, "f2"]


def test_bad_input():
    r = Residuals(np.arange(5) * 1.0, np.zeros((5, 2)), ("a", "b"), ())
    with pytest.raises(ParameterError, match="no thresholds"):
        ThresholdEvaluator().run(r)
    with pytest.raises(DataError, match="3 thresholds for 2"):
        ThresholdEvaluator(thresholds=[1, 1, 1]).run(r)
    with pytest.raises(ParameterError, match="exactly one"):
        ThresholdEvaluator().fit(r)
    with pytest.raises(DataError, match="at least 10"):
        ThresholdEvaluator().fit(r, false_alarm_prob=0.01)
    const = Residuals(np.arange(50) * 1.0, np.zeros((50, 1)), ("a",), ())
    with pytest.raises(DataError, match="constant"):
        ThresholdEvaluator().fit(const, false_alarm_prob=0.01)
    with pytest.raises(ParameterError, match="persistence"):
        ThresholdEvaluator(persistence=(3, 2))
    with pytest.raises(ParameterError, match="positive"):
        ThresholdEvaluator(thresholds=[-1.0])
