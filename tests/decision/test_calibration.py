"""Calibration on a list of fault-free runs (fdikit.decision.calibration) and the evaluators' fit on run lists."""

import numpy as np
import pytest
from scipy.stats import chi2, poisson

from fdikit.decision import CusumEvaluator, GlrEvaluator, SprtEvaluator, ThresholdEvaluator
from fdikit.decision.calibration import CalibrationReport, calibration_report, calibration_runs
from fdikit.errors import DataError
from fdikit.metrics import rate_interval
from fdikit.residuals import Residuals


def _run(r, dt=0.1, t0=0.0, names=("a", "b"), isolates=("fa", "fb")):
    r = np.asarray(r, float)
    return Residuals(t0 + np.arange(r.shape[0]) * dt, r, names, isolates)


def test_fit_on_a_run_list_equals_fit_on_the_pooled_samples():
    """Pooling is exact: the threshold, centre (and CUSUM / GLR / SPRT moments) of fit([r1, r2]) equal those of a fit
    on one run holding the same rows — the runs' times both start at 0 (no glued times needed).  dt = 0.125 s is
    exact in binary, so the median sample time (and α from a rate) is the same bit for bit."""
    rng = np.random.default_rng(3)
    r1, r2 = rng.standard_normal((700, 2)), 2.0 + 3.0 * rng.standard_normal((500, 2))
    runs = [_run(r1, dt=0.125), _run(r2, dt=0.125)]
    pooled = _run(np.vstack([r1, r2]), dt=0.125)
    for kw in ({"false_alarm_prob": 1e-3}, {"false_alarms_per_hour": 5.0},
               {"false_alarm_prob": 4e-2, "method": "empirical"}):
        a, b = ThresholdEvaluator().fit(runs, **kw), ThresholdEvaluator().fit(pooled, **kw)
        np.testing.assert_array_equal(a.thresholds, b.thresholds)
        np.testing.assert_array_equal(a.center, b.center)
        assert a.alpha == b.alpha
    c1, c2 = CusumEvaluator().fit(runs, arl0=1e3, shift=1.0), CusumEvaluator().fit(pooled, arl0=1e3, shift=1.0)
    np.testing.assert_array_equal(c1.threshold, c2.threshold)
    np.testing.assert_array_equal(c1.sigma, c2.sigma)
    g1, g2 = GlrEvaluator(window=5).fit(runs, false_alarm_prob=1e-3), GlrEvaluator(window=5).fit(pooled,
                                                                                              false_alarm_prob=1e-3)
    np.testing.assert_array_equal(g1.cov, g2.cov)
    np.testing.assert_array_equal(g1.threshold, g2.threshold)
    np.testing.assert_array_equal(SprtEvaluator(shift=1.0).fit(runs).mean, SprtEvaluator(shift=1.0).fit(pooled).mean)
    # the pooled statistics are those of numpy on the stacked rows
    both = np.vstack([r1, r2])
    np.testing.assert_allclose(a.center, both.mean(axis=0), rtol=1e-13)
    # duration: 1200 samples of 0.125 s
    assert a.calibration.hours == 150.0 / 3600.0
    assert a.calibration.runs == 2 and a.calibration.samples == 1200


def test_no_persistence_window_crosses_a_run_boundary():
    """Run 1 ends and run 2 starts with one large sample each.  With 2-of-2 persistence each run alone never alarms;
    glued end to end the two samples are consecutive and alarm once.  The calibration report evaluates each run on
    its own: 0 alarms.  Threshold: σ of the pooled ±1 data with the two outliers of 100 is ≈ 4.5, so
    τ = σ Φ⁻¹(1 − 1e−3/2) ≈ 15: every ±1 sample is below it and 100 above."""
    n = 999
    base = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)[:, None]
    r1, r2 = base.copy(), base.copy()
    r1[-1], r2[0] = 100.0, 100.0
    a, b = _run(r1, names=("r",), isolates=("f",)), _run(r2, names=("r",), isolates=("f",))
    ev = ThresholdEvaluator(persistence=(2, 2)).fit([a, b], false_alarm_prob=1e-3)
    pooled = np.vstack([r1, r2])[:, 0]
    from scipy.stats import norm

    assert ev.thresholds[0] == pytest.approx(np.std(pooled, ddof=1) * norm.isf(1e-3 / 2), rel=1e-12)   # the pooled σ
    assert 1.0 < ev.thresholds[0] < 100.0
    assert ev.calibration.alarms == 0
    glued = _run(np.vstack([r1, r2]), names=("r",), isolates=("f",))
    assert len(ev.run(glued).alarms) == 1  # what gluing the runs would have counted
    # the same through calibration_report, and with 1-of-1 persistence both outliers alarm (two alarms)
    one = ThresholdEvaluator(thresholds=ev.thresholds, center=ev.center)
    assert calibration_report(one, calibration_runs([a, b])).alarms == 2
    # CUSUM: the sums restart with each run too.  With S = (100 − μ)/σ ≈ 31 (σ ≈ 3.2) the ±1 samples give
    # increments |s| − ν ≤ 1/σ + |μ|/σ − 0.5 < 0, so g⁺ sits at 0 before a spike; one spike makes g⁺ = S − ν < h =
    # 1.5 S, two consecutive spikes g⁺ = 2S − 2ν ≥ 1.5 S (as S ≥ 4ν = 2): an alarm only when the runs are glued.
    cu = CusumEvaluator(drift=0.5, threshold=1.0).fit([a, b])
    cu.threshold = np.array([1.5 * (100.0 - cu.mean[0]) / cu.sigma[0]])
    assert calibration_report(cu, calibration_runs([a, b])).alarms == 0 and len(cu.run(glued).alarms) == 1


def test_calibration_runs_checks_the_runs():
    good = _run(np.zeros((20, 2)))
    with pytest.raises(DataError, match="empty"):
        calibration_runs([])
    with pytest.raises(DataError, match="differ"):
        calibration_runs([good, _run(np.zeros((20, 2)), names=("a", "c"))])
    with pytest.raises(DataError, match="ties"):
        calibration_runs([good, _run(np.zeros((20, 2)), isolates=("fb", "fa"))])
    with pytest.raises(DataError, match="at least 10"):
        calibration_runs([_run(np.zeros((4, 2))), _run(np.zeros((5, 2)))])
    with pytest.raises(DataError, match="Residuals"):
        calibration_runs([good, np.zeros((3, 2))])
    # runs of different sample times: duration per run, dt the median within runs
    runs = calibration_runs([_run(np.zeros((10, 2)), dt=0.1), _run(np.zeros((30, 2)), dt=0.2)])
    assert runs.hours == pytest.approx((10 * 0.1 + 30 * 0.2) / 3600, rel=1e-12) and runs.dt == pytest.approx(0.2)


@pytest.mark.parametrize("k,T,c", [(0, 1.0, 0.95), (1, 2.5, 0.95), (3, 2.0, 0.95), (17, 40.0, 0.9), (250, 10.0, 0.99)])
def test_garwood_interval(k, T, c):
    """Exact Poisson interval: ends from scipy.stats.chi2, and the defining tail property checked with
    scipy.stats.poisson — P(X ≥ k | λ_lo T) = a/2 and P(X ≤ k | λ_hi T) = a/2 (to the root's precision)."""
    lo, hi = rate_interval(k, T, c)
    a = 1 - c
    assert hi == pytest.approx(chi2.ppf(1 - a / 2, 2 * k + 2) / (2 * T), rel=1e-12)
    if k == 0:
        assert lo == 0.0
        assert hi == pytest.approx(-np.log(a / 2) / T, rel=1e-12)  # chi2 with 2 dof: ppf(p) = −2 ln(1 − p)
    else:
        assert lo == pytest.approx(chi2.ppf(a / 2, 2 * k) / (2 * T), rel=1e-12)
        assert poisson.sf(k - 1, lo * T) == pytest.approx(a / 2, rel=1e-8)
    assert poisson.cdf(k, hi * T) == pytest.approx(a / 2, rel=1e-8)


def test_garwood_exact_values():
    # chi2.ppf(0.025, 6) = 1.237344, chi2.ppf(0.975, 8) = 17.534546 (tables): k = 3 in 2 h
    lo, hi = rate_interval(3, 2.0)
    assert lo == pytest.approx(1.2373442457 / 4, rel=1e-9) and hi == pytest.approx(17.5345461395 / 4, rel=1e-9)
    with pytest.raises(Exception, match="count"):
        rate_interval(-1, 1.0)
    with pytest.raises(Exception, match="hours"):
        rate_interval(1, 0.0)
    with pytest.raises(Exception, match="confidence"):
        rate_interval(1, 1.0, 1.0)


def test_report_on_gaussian_data():
    """White N(0, 1) residuals, 1 false alarm per hour asked, 10 runs of 1 h at dt = 1 s: the alarms counted are
    those of the evaluator on the runs; the report's interval is rate_interval of that count, and the
    smallest resolvable rate is −ln(0.025)/10 h = 0.369/h."""
    rng = np.random.default_rng(11)
    runs = [_run(rng.standard_normal((3600, 1)), dt=1.0, names=("r",), isolates=("f",)) for _ in range(10)]
    ev = ThresholdEvaluator().fit(runs, false_alarms_per_hour=1.0)
    rep = ev.calibration
    assert isinstance(rep, CalibrationReport)
    assert rep.hours == pytest.approx(10.0) and rep.target_rate == 1.0 and rep.runs == 10
    assert rep.alarms == sum(len(ev.run(r).alarms) for r in runs)
    assert rep.interval == rate_interval(rep.alarms, 10.0)
    assert rep.min_resolvable_rate == pytest.approx(-np.log(0.025) / 10.0, rel=1e-12)
    # the count is Poisson-like with mean ≤ 10 (the per-sample α makes ≤ 1 exceedance/h on average): the
    # probability of more than 25 alarms is poisson.sf(25, 10) = 1.1e−5
    assert rep.alarms <= 25


def test_whitened_fit_on_a_list_pools_the_runs_without_crossing_them():
    import scipy.signal

    from fdikit.decision import ThresholdEvaluator
    from fdikit.decision.whiten import Whitened, yule_walker
    from fdikit.residuals import Residuals

    rng = np.random.default_rng(5)
    runs = []
    for _ in range(3):
        x = scipy.signal.lfilter([1.0], [1.0, -0.8], rng.standard_normal(4000))
        runs.append(Residuals(np.arange(4000) * 0.01, x[:, None], ("r",), ("f",)))
    w = Whitened(ThresholdEvaluator(), order=1).fit(runs, false_alarms_per_hour=1.0)
    # pooled Yule-Walker: the sum of within-run lag-1 products over the sum of squares (mean removed)
    xs = [r.r[:, 0] - w.center[0] for r in runs]
    ref = sum(x[:-1] @ x[1:] for x in xs) / sum(x @ x for x in xs)
    assert w.coef[0, 0] == pytest.approx(ref, rel=1e-12)
    assert yule_walker(xs, 1)[0] == pytest.approx(ref, rel=1e-12)
    # AR(1) with a = 0.8 from 12000 samples: standard error sqrt((1 - a²)/N) ≈ 0.0055; 5 standard errors
    assert abs(w.coef[0, 0] - 0.8) < 5 * np.sqrt((1 - 0.8**2) / 12000)
    assert w.evaluator.calibration.runs == 3
