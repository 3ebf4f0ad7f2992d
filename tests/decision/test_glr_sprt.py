"""GLR and SPRT evaluators: statistics against their definitions, estimates and error rates against theory.

Many independent runs are evaluated at once as separate blocks (columns) of one
residual series; a block's test only sees its own residuals.
"""

import numpy as np
import pytest
from scipy.stats import chi2, multivariate_normal, norm

from fdikit.decision.glr import GlrEvaluator, glr_threshold, residual_blocks
from fdikit.decision.sprt import SprtEvaluator, sprt_asn, sprt_thresholds
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

SIGMA = np.array([[1.0, 0.6, 0.2], [0.6, 2.0, -0.5], [0.2, -0.5, 0.5]])


def _gaussian(n, cov, rng):
    return rng.standard_normal((n, cov.shape[0])) @ np.linalg.cholesky(cov).T


def _runs_as_blocks(runs):
    """(R, N, p) runs -> one (N, R·p) series with one block label per run."""
    R, N, p = runs.shape
    e = runs.transpose(1, 0, 2).reshape(N, R * p)
    labels = [f"run{i}" for i in range(R) for _ in range(p)]
    return e, labels


# ---------------------------------------------------------------------------------------------- GLR
def test_glr_statistic_matches_definition():
    """g_k = max over the last M change times of Sᵀ Σ⁻¹ S / (2n), by brute force, with Σ correlated."""
    rng = np.random.default_rng(0)
    e = _gaussian(120, SIGMA, rng) + [0.1, -0.2, 0.3]
    e[70:] += [1.0, 0.0, -0.5]
    res = Residuals(np.arange(120) * 0.1, e, ("a", "b", "c"), ("f", "f", "f"))
    mean, M = np.array([0.1, -0.2, 0.3]), 15
    d = GlrEvaluator(window=M, threshold=5.0, mean=mean, cov=SIGMA).run(res)
    Si = np.linalg.inv(SIGMA)
    for k in range(120):
        vals = []
        for j in range(max(0, k - M + 1), k + 1):
            S = (e[j : k + 1] - mean).sum(axis=0)
            vals.append((S @ Si @ S / (2 * (k - j + 1)), j, S / (k - j + 1)))
        best = max(vals, key=lambda v: v[0])
        assert d.meta["statistic"][k, 0] == pytest.approx(best[0], rel=1e-10)
        assert d.meta["change_index"][k, 0] == best[1]
        np.testing.assert_allclose(d.meta["change_size"][0][k], best[2], rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(d.fired[:, 0], d.meta["statistic"][:, 0] > 5.0)


def test_glr_change_time_and_size():
    """Shift ν = (1, −1, 0.5) at k0 in correlated noise, 300 runs, looked at k0 + 60 (window 100).

    Change time: ĵ is off by more than m samples only if the log-likelihood walk of a
    wrong change time beats the true one; each step of that walk is N(−d²/2, d²),
    d² = νᵀΣ⁻¹ν, so P(|ĵ − k0| > m) ≤ 2 Σ_{i>m} Φ(−√i d/2) (union bound, ν known).
    Size: with ĵ ≈ k0, n (ν̂ − ν)ᵀ Σ⁻¹ (ν̂ − ν) ~ χ²₃ (the window mean has covariance Σ/n):
    the fraction above the 99 % point stays within binomial error of 1 %.
    """
    rng = np.random.default_rng(1)
    R, N, k0, M = 300, 500, 400, 100
    nu = np.array([1.0, -1.0, 0.5])
    runs = np.stack([_gaussian(N, SIGMA, rng) for _ in range(R)])
    runs[:, k0:] += nu
    e, labels = _runs_as_blocks(runs)
    res = Residuals(np.arange(N) * 0.01, e, tuple(f"r{i}" for i in range(3 * R)), ("f",) * (3 * R))
    d = GlrEvaluator(window=M, threshold=glr_threshold(1e-3, M, 3), cov=np.kron(np.eye(R), SIGMA),
                     blocks=labels).run(res)
    k = k0 + 60
    err = d.meta["change_index"][k] - k0
    d2 = nu @ np.linalg.solve(SIGMA, nu)
    m = 5
    bound = 2 * norm.cdf(-np.sqrt(np.arange(m + 1, 10_000)) * np.sqrt(d2) / 2).sum()
    assert np.mean(np.abs(err) > m) <= bound + 3 * np.sqrt(bound * (1 - bound) / R), (np.abs(err).max(), bound)
    assert np.median(np.abs(err)) <= 1
    n = k - d.meta["change_index"][k] + 1
    est = np.array([s[k] for s in d.meta["change_size"]])
    dev = est - nu
    maha = n * np.einsum("ij,ij->i", dev, np.linalg.solve(SIGMA, dev.T).T)
    assert np.mean(maha > chi2.ppf(0.99, 3)) <= 0.01 + 3 * np.sqrt(0.01 * 0.99 / R)
    assert np.mean(maha) == pytest.approx(3.0, abs=3 * np.sqrt(6 / R) + 0.3)  # + selection of ĵ
    assert np.all(d.fired[k0 + M // 2])  # every run's block has detected half a window after the change


def test_glr_false_alarm_probability_is_bounded():
    """Per-sample false-alarm probability of a fitted 3-D GLR (correlated Σ) lies in [α/M, α].

    h = χ²₃.isf(α/M)/2 makes every window's statistic exceed with probability α/M exactly,
    so α/M is a lower bound (one window) and α the union bound over the M windows (an
    upper bound, not an approximation: the windows overlap).  Samples M apart see disjoint
    windows, so they are independent Bernoulli trials: binomial tolerance, 3 SD.
    Measured: 228 of 20,000 = 0.57 α for M = 10.
    """
    rng = np.random.default_rng(2)
    M, alpha = 10, 0.02
    fit = Residuals(np.arange(100_000) * 0.01, _gaussian(100_000, SIGMA, rng), ("a", "b", "c"), ("f", "f", "f"))
    ev = GlrEvaluator(window=M).fit(fit, false_alarm_prob=alpha)
    assert ev.threshold[0] == pytest.approx(chi2.isf(alpha / M, 3) / 2)
    np.testing.assert_allclose(ev.cov, SIGMA, atol=0.05)
    N = 200_000
    d = ev.run(Residuals(np.arange(N) * 0.01, _gaussian(N, SIGMA, rng), ("a", "b", "c"), ("f", "f", "f")))
    trials = d.fired[np.arange(M - 1, N, M), 0]
    n, hits = trials.size, int(trials.sum())
    assert hits <= alpha * n + 3 * np.sqrt(alpha * n)
    assert hits >= alpha / M * n - 3 * np.sqrt(alpha / M * n)
    assert 0.3 < hits / (alpha * n) < 0.8  # regression of the measured 0.57 α (M = 10, p = 3)


def _glr_bad_residuals():
    rng = np.random.default_rng(3)
    e = np.hstack([_gaussian(800, SIGMA, rng), rng.standard_normal((800, 1))])
    e[400:, :2] += [1.2, 1.2]
    e[600:, 3] += 1.5
    e[[5, 6, 450], 1] = np.nan
    e[700, 3] = -np.inf
    valid = np.ones(800, bool)
    valid[[0, 300]] = False
    return Residuals(np.arange(800) * 0.01, e, ("a", "b", "c", "d"), ("fab", "fab", "fc", "fd"), valid)


@pytest.mark.parametrize("blocks", ["isolates", "each", "all", ["x", "x", "y", "x"]])
def test_glr_batch_equals_online(blocks):
    r = _glr_bad_residuals()
    cov = np.zeros((4, 4))
    cov[:3, :3], cov[3, 3] = SIGMA, 1.0
    ev = GlrEvaluator(window=25, threshold=6.0, cov=cov, mean=0.05, blocks=blocks, isolates=r.isolates)
    batch = ev.run(r)
    ev.reset()
    rows = np.where(r.valid[:, None], r.r, np.nan)
    steps, stat, idx, size = [], [], [], []
    for row in rows:
        steps.append(ev.step(row))
        stat.append(ev.statistic)
        idx.append(ev.change_index)
        size.append(np.concatenate(ev.change_size))
    np.testing.assert_array_equal(batch.fired, [s.fired for s in steps])
    np.testing.assert_array_equal(batch.isolated, [s.fault for s in steps])
    np.testing.assert_array_equal(batch.valid, [s.valid for s in steps])
    np.testing.assert_allclose(batch.meta["statistic"], stat, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(batch.meta["change_index"], idx)
    np.testing.assert_allclose(np.hstack(batch.meta["change_size"]), size, rtol=0, atol=1e-12)
    assert batch.invalid_count == 6
    np.testing.assert_array_equal(batch.fired[6], batch.fired[4])
    assert batch.fired[500:, 0].mean() > 0.9


def test_glr_blocks_and_isolation():
    assert residual_blocks("isolates", ("a", "b", "c", "d"), ("f1", None, "f1", "f2")) == (
        ("f1", (0, 2)), ("b", (1,)), ("f2", (3,)))
    assert residual_blocks("each", ("a", "b"), ("f", "f")) == (("a", (0,)), ("b", (1,)))
    assert residual_blocks("all", ("a", "b"), (None, None)) == (("all", (0, 1)),)
    r = _glr_bad_residuals()
    d = GlrEvaluator(window=25, threshold=glr_threshold(1e-4, 25, 2), cov=np.diag([1.0, 2.0, 0.5, 1.0])).fit(
        r.slice(stop=3.9), false_alarm_prob=1e-4).run(r)
    assert d.names == ("fab", "fc", "fd")
    assert d.meta["blocks"] == {"fab": ["a", "b"], "fc": ["c"], "fd": ["d"]}
    assert d.first_alarm().fault == "fab" and 400 <= d.first_alarm().index < 430
    assert np.mean(d.isolated[450:600] == "fab") > 0.9
    assert np.mean(d.isolated[650:] == "unknown") > 0.9  # two faults' blocks fire


def test_glr_bad_input():
    r = Residuals(np.arange(50) * 1.0, np.random.default_rng(0).standard_normal((50, 2)), ("a", "b"), ())
    with pytest.raises(ParameterError, match="no threshold"):
        GlrEvaluator().run(r)
    with pytest.raises(ParameterError, match="window"):
        GlrEvaluator(window=0)
    with pytest.raises(ParameterError, match="positive"):
        GlrEvaluator(threshold=-1.0)
    with pytest.raises(DataError, match="3 thresholds for 2 blocks"):
        GlrEvaluator(threshold=[1, 2, 3]).run(r)
    with pytest.raises(DataError, match="covariance of shape"):
        GlrEvaluator(threshold=5.0, cov=np.eye(3)).run(r)
    with pytest.raises(DataError, match="not positive definite"):
        GlrEvaluator(threshold=5.0, cov=[[1.0, 1.0], [1.0, 1.0]], blocks="all").run(r)
    ev = GlrEvaluator(threshold=5.0).fit(r)
    with pytest.raises(DataError, match="fitted on 2"):
        ev.step([0.0, 0.0, 0.0])
    ev = GlrEvaluator(threshold=5.0)
    ev.step([0.0, 0.0])
    with pytest.raises(DataError, match="got 1 residuals after steps with 2; call reset"):
        ev.step([0.0])
    with pytest.raises(DataError, match="at least 10"):
        GlrEvaluator().fit(r.slice(stop=5.0))
    with pytest.raises(ParameterError, match="one label per residual"):
        GlrEvaluator(threshold=5.0, blocks="pairs").run(r)
    with pytest.raises(ParameterError, match="3 block labels for 2"):
        GlrEvaluator(threshold=5.0, blocks=["x", "y", "z"]).run(r)
    with pytest.raises(ParameterError, match=r"\(0, 1\)"):
        glr_threshold(0.0, 10)
    with pytest.raises(ParameterError, match="one filter"):
        GlrEvaluator(threshold=5.0, blocks="all", groups=("g1", "g2")).run(r)


# ---------------------------------------------------------------------------------------------- SPRT
def test_sprt_llr_matches_log_density_ratio():
    rng = np.random.default_rng(4)
    e = _gaussian(60, SIGMA, rng)
    mean, delta = np.array([0.2, 0.0, -0.1]), np.array([0.5, -0.3, 0.4])
    d = SprtEvaluator(delta, 1e-6, 1e-6, mean=mean, cov=SIGMA, restart=False).run(
        Residuals(np.arange(60.0), e + mean, ("a", "b", "c"), ("f", "f", "f")))
    lam = multivariate_normal(mean + delta, SIGMA).logpdf(e + mean) - multivariate_normal(mean, SIGMA).logpdf(e + mean)
    stop = int(np.argmax(d.meta["decision"][:, 0] != 0))
    assert 5 < stop < 59 and d.meta["decision"][stop, 0] == -1  # H0 accepted (the data are fault-free)
    np.testing.assert_allclose(d.meta["llr"][: stop + 1, 0], np.cumsum(lam)[: stop + 1], rtol=1e-10, atol=1e-12)
    assert np.all(d.meta["llr"][stop:, 0] == d.meta["llr"][stop, 0])  # the single test stopped
    assert d.meta["divergence"][0] == pytest.approx(0.5 * delta @ np.linalg.solve(SIGMA, delta))


def test_sprt_wald_error_rates_and_asn():
    """Single SPRT (no restarts), 4000 runs per hypothesis, α = 0.05, β = 0.1, δ = 0.25σ.

    Error rates: at most α and β (and Wald's rigorous α' + β' ≤ α + β), 3 binomial SD of
    slack.  Expected sample number: Wald's E[N | H1] ≈ ((1−β)A + βB)/D (76.0 here) neglects
    the overshoot of the thresholds and uses the nominal β.  Measured ≈ 82.3: with the
    attained β' (≈ 0.09, +1.6 samples) and Siegmund's mean overshoot ≈ 0.583 σ_λ per
    boundary (σ_λ = √(2D); +0.583 σ_λ / D = 4.7 samples) the approximation matches within
    3 SE (SE of the mean of N, plus the sampling error of β' through (A − B)/D).  Wald's
    uncorrected value must be below the measurement.  Same for E[N | H0] (63.8 / ≈ 69.2).
    """
    alpha, beta, R, delta, length = 0.05, 0.1, 4000, 0.25, 1200
    A, B = sprt_thresholds(alpha, beta)
    D = delta**2 / 2
    overshoot = 0.583 * np.sqrt(2 * D) / D
    rng = np.random.default_rng(11)
    wrong = {}
    for hyp in (0, 1):
        e = rng.standard_normal((length, R)) + hyp * delta
        res = Residuals(np.arange(length) * 1.0, e, tuple(f"r{i}" for i in range(R)), ("f",) * R)
        d = SprtEvaluator(delta, alpha, beta, mean=0.0, cov=1.0, blocks="each", restart=False).run(res)
        final = d.meta["decision"][-1]
        assert np.all(final != 0)  # every test stopped
        np.testing.assert_array_equal(d.fired[-1], final == 1)  # latched decision
        N = np.argmax(d.meta["decision"] != 0, axis=0) + 1
        rate = wrong[hyp] = np.mean(final == (1 if hyp == 0 else -1))
        target = alpha if hyp == 0 else beta
        assert rate <= target + 3 * np.sqrt(target * (1 - target) / R), (hyp, rate)
        wald = sprt_asn(alpha, beta, D, hypothesis=hyp)
        # Wald's formula with the attained error rate, thresholds unchanged
        attained = ((1 - rate) * B + rate * A) / -D if hyp == 0 else ((1 - rate) * A + rate * B) / D
        se = np.hypot(N.std(ddof=1) / np.sqrt(R), (A - B) / D * np.sqrt(rate * (1 - rate) / R))
        assert N.mean() > wald
        assert abs(N.mean() - (attained + overshoot)) <= 3 * se, (hyp, N.mean(), attained + overshoot, se)
    assert wrong[0] + wrong[1] <= alpha + beta + 3 * np.sqrt((alpha + beta) / R)


def _sprt_residuals():
    rng = np.random.default_rng(6)
    e = np.hstack([_gaussian(1500, SIGMA, rng), rng.standard_normal((1500, 1))])
    e[700:, :3] += [0.6, 0.4, 0.0]
    e[[3, 4, 900], 2] = np.nan
    valid = np.ones(1500, bool)
    valid[1000] = False
    return Residuals(np.arange(1500) * 0.01, e, ("a", "b", "c", "d"), ("f1", "f1", "f1", "f2"), valid)


@pytest.mark.parametrize("restart,hold,blocks", [(True, 0, "isolates"), (True, 4, "each"), (False, 0, "isolates"),
                                                 (False, 0, ["x", "y", "x", "y"])])
def test_sprt_batch_equals_online(restart, hold, blocks):
    r = _sprt_residuals()
    cov = np.zeros((4, 4))
    cov[:3, :3], cov[3, 3] = SIGMA, 1.0
    ev = SprtEvaluator([0.6, 0.4, 0.1, -0.5], 0.01, 0.02, mean=0.0, cov=cov, blocks=blocks, restart=restart,
                       hold=hold, isolates=r.isolates)
    batch = ev.run(r)
    ev.reset()
    rows = np.where(r.valid[:, None], r.r, np.nan)
    steps, llr, dec = [], [], []
    for row in rows:
        steps.append(ev.step(row))
        llr.append(ev.llr)
        dec.append(ev.decision)
    np.testing.assert_array_equal(batch.fired, [s.fired for s in steps])
    np.testing.assert_array_equal(batch.isolated, [s.fault for s in steps])
    np.testing.assert_array_equal(batch.valid, [s.valid for s in steps])
    np.testing.assert_allclose(batch.meta["llr"], llr, rtol=0, atol=1e-12)
    ok = batch.valid
    np.testing.assert_array_equal(batch.meta["decision"][ok], np.array(dec)[ok])
    assert batch.invalid_count == 4


def test_sprt_restart_semantics():
    r = _sprt_residuals()
    ev = SprtEvaluator([0.6, 0.4, 0.0, -0.5], 0.01, 0.01, cov=np.diag([1.0, 2.0, 0.5, 1.0]), blocks="isolates")
    d = ev.run(r)
    A, B = sprt_thresholds(0.01, 0.01)
    L, dec = d.meta["llr"][:, 0], d.meta["decision"][:, 0]
    np.testing.assert_array_equal(dec == 1, L >= A)
    np.testing.assert_array_equal(dec == -1, L <= B)
    # after any decision the next valid sample restarts from Λ = 0: Λ = λ = wᵀe − c there,
    # w = Σ⁻¹δ = (0.6, 0.2, 0), c = ½ δᵀw = 0.22
    k = np.flatnonzero((dec != 0)[:-1] & d.valid[1:]) + 1
    assert k.size > 20
    np.testing.assert_allclose(L[k], r.r[k, :3] @ [0.6, 0.2, 0.0] - 0.22, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(d.fired[:, 0], dec == 1)
    assert d.first_alarm(after=7.0).fault == "f1" and d.first_alarm(after=7.0).index < 760


def test_sprt_bad_input():
    r = Residuals(np.arange(50) * 1.0, np.random.default_rng(0).standard_normal((50, 2)), ("a", "b"), ())
    for a, b in [(0.0, 0.1), (0.1, 1.0), (0.6, 0.5), (-0.1, 0.1)]:
        with pytest.raises(ParameterError, match="alpha"):
            SprtEvaluator(1.0, a, b)
    with pytest.raises(ParameterError, match="zero shift"):
        SprtEvaluator([1.0, 0.0], blocks="each").run(r)
    with pytest.raises(DataError, match="3 shift values for 2"):
        SprtEvaluator([1.0, 1.0, 1.0]).run(r)
    with pytest.raises(ParameterError, match="hold"):
        SprtEvaluator(1.0, hold=1.5)
    with pytest.raises(ParameterError, match="positive variances"):
        SprtEvaluator(1.0, cov=[1.0, -1.0])
    with pytest.raises(ParameterError, match="finite"):
        SprtEvaluator([np.nan])
    ev = SprtEvaluator(1.0).fit(r)
    with pytest.raises(DataError, match="fitted on 2"):
        ev.step([0.0])
    ev = SprtEvaluator(1.0)
    ev.step([0.0, 0.0, 0.0])
    with pytest.raises(DataError, match="call reset"):
        ev.step([0.0, 0.0])
    with pytest.raises(DataError, match="at least 10"):
        SprtEvaluator(1.0).fit(r.slice(stop=3.0))
    with pytest.raises(ParameterError, match="divergence"):
        sprt_asn(0.01, 0.01, 0.0)
