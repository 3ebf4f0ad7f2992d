"""CUSUM evaluator: run lengths against Siegmund and the Page integral equation, design, batch == online.

Oracles: the exact zero-state average run length of a one-sided CUSUM on Gaussian data,
from Page's integral equation solved by Nyström quadrature (independent of the code under
test), and Monte Carlo run lengths.  With ``restart='reset'`` the intervals between
alarms are independent copies of the zero-state run length (renewal), so one long
series per residual gives thousands of run lengths.
"""

import numpy as np
import pytest
from scipy.stats import norm

from fdikit.decision.cusum import CusumEvaluator, cusum_arl, cusum_design
from fdikit.diagnosis import UNKNOWN_FAULT
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals


def page_arl(drift: float, threshold: float, shift: float, nodes: int = 96) -> float:
    """Exact one-sided zero-state ARL of ``g = max(0, g + x − ν)``, ``x ~ N(δ, 1)``, alarm at ``g > h``.

    Page's integral equation ``L(z) = 1 + L(0) Φ(−z − μ) + ∫₀ʰ L(y) φ(y − z − μ) dy`` with
    ``μ = δ − ν``, by Gauss–Legendre Nyström (96 nodes: converged to 1e-12).
    """
    x, w = np.polynomial.legendre.leggauss(nodes)
    y, w = 0.5 * threshold * (x + 1), 0.5 * threshold * w
    mu = shift - drift
    z = np.concatenate([[0.0], y])
    K = np.empty((nodes + 1, nodes + 1))
    K[:, 0] = norm.cdf(-z - mu)
    K[:, 1:] = w * norm.pdf(y[None, :] - z[:, None] - mu)
    return float(np.linalg.solve(np.eye(nodes + 1) - K, np.ones(nodes + 1))[0])


def run_lengths(fired: np.ndarray) -> np.ndarray:
    """Zero-state run lengths (samples up to and including each alarm) of every column."""
    out = []
    for i in range(fired.shape[1]):
        idx = np.flatnonzero(fired[:, i])
        out.append(np.diff(np.concatenate([[-1], idx])))
    return np.concatenate(out)


def _series(n, q, seed, shift=0.0):
    rng = np.random.default_rng(seed)
    return Residuals(np.arange(n) * 0.01, rng.standard_normal((n, q)) + shift, tuple(f"r{i}" for i in range(q)),
                     ("f",) * q)


@pytest.mark.parametrize("h", [2.0, 3.0, 4.0, 5.0, 8.0])
def test_siegmund_against_page_integral_equation(h):
    """Siegmund's corrected-diffusion ARL is within 1.5 % of the exact value for h >= 2, δ <= ν + 0.5.

    (0.8 % fault-free and 0.5-0.7 % at δ = 1 for h >= 3; it degrades for large shifts
    and small h: 2.6 % at h = 2, δ = 1.5, also checked.)
    """
    for shift in (0.0, 0.25, 0.5, 1.0):
        assert cusum_arl(0.5, h, shift, two_sided=False) == pytest.approx(page_arl(0.5, h, shift), rel=0.015)
    assert cusum_arl(0.5, h, 1.5, two_sided=False) == pytest.approx(page_arl(0.5, h, 1.5), rel=0.03)


def test_arl_formula_limits():
    # Δ = δ − ν = 0: ARL = b², continuous through the series branch
    b = 4.0 + 1.166
    assert cusum_arl(0.5, 4.0, 0.5, two_sided=False) == pytest.approx(b * b, rel=1e-12)
    assert cusum_arl(0.5, 4.0, 0.5 + 1e-6, two_sided=False) == pytest.approx(b * b, rel=1e-5)
    # two-sided fault-free: half the one-sided (symmetric)
    assert cusum_arl(0.5, 4.0) == pytest.approx(cusum_arl(0.5, 4.0, two_sided=False) / 2, rel=1e-12)
    np.testing.assert_allclose(cusum_arl([0.5, 0.5], [4.0, 5.0]), [cusum_arl(0.5, 4.0), cusum_arl(0.5, 5.0)])


@pytest.mark.parametrize("two_sided", [False, True])
def test_fault_free_arl_matches_siegmund(two_sided):
    """Measured ARL0 (ν = 0.5, h = 4) on N(0, 1) data against Siegmund's approximation.

    2,000,000 samples (8 residuals × 250,000), ≈ 6,000 one-sided / 12,000 two-sided run
    lengths.  Tolerance: 3 Monte Carlo standard errors (sample std / √n) plus the bias of
    the approximation itself, measured against the exact one-sided ARL from Page's
    integral equation (+0.8 % here).  The exact ARL is checked at 3 SE as well.
    """
    d = CusumEvaluator(0.5, 4.0, two_sided=two_sided).run(_series(250_000, 8, seed=2024 + two_sided))
    rl = run_lengths(d.fired)
    mean, se = rl.mean(), rl.std(ddof=1) / np.sqrt(rl.size)
    theory = cusum_arl(0.5, 4.0, 0.0, two_sided=two_sided)
    exact_one = page_arl(0.5, 4.0, 0.0)
    bias = abs(cusum_arl(0.5, 4.0, 0.0, two_sided=False) / exact_one - 1) * theory
    assert rl.size > (5000 if not two_sided else 10000)
    assert abs(mean - theory) <= 3 * se + bias, (mean, se, theory, bias)
    exact = exact_one / (2 if two_sided else 1)  # symmetric sides: 1/ARL = 2/ARL⁺
    assert abs(mean - exact) <= 3 * se + (0.005 * exact if two_sided else 0.0), (mean, se, exact)


def test_detection_delay_matches_cusum_arl():
    """Zero-state run length under a mean shift δ = 1 (ν = 0.5, h = 4): ARL(δ) = 8.34 (Siegmund).

    Every interval between alarms of a constantly shifted series is a run length from
    g = 0 after the onset; the alarm comes ``ARL(δ) − 1`` samples after the first faulty
    one.  Tolerance: 3 SE plus Siegmund's bias against the integral equation (−0.5 %).
    """
    d = CusumEvaluator(0.5, 4.0).run(_series(100_000, 2, seed=7, shift=1.0))
    rl = run_lengths(d.fired)
    mean, se = rl.mean(), rl.std(ddof=1) / np.sqrt(rl.size)
    theory = cusum_arl(0.5, 4.0, 1.0)
    exact = page_arl(0.5, 4.0, 1.0)
    assert abs(mean - theory) <= 3 * se + abs(theory - exact), (mean, se, theory, exact)
    assert abs(mean - exact) <= 3 * se
    # as a Diagnosis detection delay: 2000 runs (columns) with the fault from their first sample
    r = _series(80, 2000, seed=8, shift=1.0)
    first = CusumEvaluator(0.5, 4.0, restart="none").run(r).fired.argmax(axis=0)  # index = run length − 1
    assert np.all(CusumEvaluator(0.5, 4.0).run(r).fired.any(axis=0))
    assert first.mean() == pytest.approx(exact - 1, abs=3 * first.std(ddof=1) / np.sqrt(first.size))


def test_design_hits_target_arl0():
    for arl0, shift in [(100.0, 1.0), (1000.0, 0.5), (1e5, 2.0)]:
        for two in (False, True):
            nu, h = cusum_design(arl0, shift, two_sided=two)
            assert nu == shift / 2
            assert cusum_arl(nu, h, 0.0, two_sided=two) == pytest.approx(arl0, rel=1e-10)
    # fit: per-residual design at q·ARL0 on the fault-free σ; shift given in residual units
    rng = np.random.default_rng(0)
    r = Residuals(np.arange(50_000) * 0.01, rng.standard_normal((50_000, 2)) * [1.0, 3.0] + [0.5, -1.0],
                  ("a", "b"), ("fa", "fb"))
    ev = CusumEvaluator().fit(r, mean_time_between_false_alarms=20.0, shift=1.5)
    np.testing.assert_allclose(ev.mean, [0.5, -1.0], atol=0.05)
    np.testing.assert_allclose(ev.drift, 1.5 / (2 * ev.sigma), rtol=1e-12)
    np.testing.assert_allclose(cusum_arl(ev.drift, ev.threshold), 2 * 2000.0, rtol=1e-9)
    assert ev.arl0 == pytest.approx(2000.0)
    # threshold only, from a given drift
    ev2 = CusumEvaluator(drift=0.25).fit(r, arl0=500.0)
    np.testing.assert_allclose(ev2.drift, 0.25)
    np.testing.assert_allclose(cusum_arl(0.25, ev2.threshold), 1000.0, rtol=1e-9)


def _bad_sample_residuals():
    rng = np.random.default_rng(5)
    rr = rng.standard_normal((3000, 3))
    rr[1000:, 1] += 1.2
    rr[2000:, 0] -= 1.0
    rr[[10, 11, 1500, 2999], 1] = np.nan
    rr[300, 0] = np.inf
    valid = np.ones(3000, bool)
    valid[2500] = False
    return Residuals(np.arange(3000) * 0.01, rr, ("a", "b", "c"), ("fa", "fb", None), valid)


@pytest.mark.parametrize("restart,hold,two_sided", [("reset", 0, True), ("reset", 5, True), ("none", 0, True),
                                                    ("none", 3, False), ("reset", 0, False)])
def test_batch_equals_online(restart, hold, two_sided):
    r = _bad_sample_residuals()
    ev = CusumEvaluator([0.5, 0.6, 0.5], [4.0, 3.5, 5.0], mean=[0.0, 0.1, 0.0], sigma=[1.0, 1.1, 0.9],
                        restart=restart, hold=hold, two_sided=two_sided, isolates=r.isolates)
    batch = ev.run(r)
    ev.reset()
    rows = np.where(r.valid[:, None], r.r, np.nan)
    steps, gp, gm = [], [], []
    for row in rows:
        steps.append(ev.step(row))
        gp.append(ev.g_plus)
        gm.append(ev.g_minus)
    np.testing.assert_array_equal(batch.fired, [s.fired for s in steps])
    np.testing.assert_array_equal(batch.isolated, [s.fault for s in steps])
    np.testing.assert_array_equal(batch.valid, [s.valid for s in steps])
    np.testing.assert_allclose(batch.meta["g_plus"], gp, rtol=0, atol=1e-12)
    np.testing.assert_allclose(batch.meta["g_minus"], gm, rtol=0, atol=1e-12)
    assert batch.invalid_count == 6
    np.testing.assert_array_equal(batch.fired[11], batch.fired[9])  # held through bad samples
    assert batch.fired[1100:, 1].mean() > 0.1


def test_long_run_rebase_batch_equals_online():
    """Beyond the 4096-sample rebase of the running sums, with restart='none' (no resets)."""
    rng = np.random.default_rng(9)
    rr = rng.standard_normal((12_000, 2))
    rr[9000:, 0] += 0.8
    r = Residuals(np.arange(12_000) * 0.01, rr, ("a", "b"), ())
    ev = CusumEvaluator(0.5, 6.0, restart="none")
    batch = ev.run(r)
    ev.reset()
    gp = []
    for row in rr:
        ev.step(row)
        gp.append(ev.g_plus)
    np.testing.assert_allclose(batch.meta["g_plus"], gp, rtol=0, atol=1e-12)
    # the Lindley recursion g = max(0, g + s − ν), evaluated directly
    g, ref = np.zeros(2), []
    for row in rr:
        g = np.maximum(0.0, g + row - 0.5)
        ref.append(g)
    np.testing.assert_allclose(batch.meta["g_plus"], ref, rtol=0, atol=1e-11)


def test_fired_semantics():
    rng = np.random.default_rng(3)
    rr = rng.standard_normal((2000, 1))
    rr[1000:1400] += 1.5
    r = Residuals(np.arange(2000) * 0.01, rr, ("a",), ("f",))
    none = CusumEvaluator(0.5, 4.0, restart="none").run(r)
    g = np.maximum(none.meta["g_plus"], none.meta["g_minus"])
    np.testing.assert_array_equal(none.fired[:, 0], g[:, 0] > 4.0)  # fired while g > h
    assert none.fired[1100:1400, 0].all()  # sustained through the fault
    reset = CusumEvaluator(0.5, 4.0, restart="reset").run(r)
    g = np.maximum(reset.meta["g_plus"], reset.meta["g_minus"])[:, 0]
    np.testing.assert_array_equal(reset.fired[:, 0], g > 4.0)  # one sample per crossing
    cross = np.flatnonzero(g > 4.0)
    nxt = cross[cross < 1999] + 1
    np.testing.assert_allclose(reset.meta["g_plus"][nxt, 0], np.maximum(0.0, rr[nxt, 0] - 0.5), atol=1e-12)
    np.testing.assert_allclose(reset.meta["g_minus"][nxt, 0], np.maximum(0.0, -rr[nxt, 0] - 0.5), atol=1e-12)
    held = CusumEvaluator(0.5, 4.0, restart="reset", hold=3).run(r)
    expect = np.zeros(2000, bool)
    for k in cross:
        expect[k : k + 4] = True
    np.testing.assert_array_equal(held.fired[:, 0], expect)


def test_isolation_through_ties():
    """A shift on residuals tied to one fault names it; residuals tied to different faults give 'unknown'."""
    rng = np.random.default_rng(4)
    names, iso = ("a1", "a2", "b1", "u"), ("fa", "fa", "fb", None)
    ev = CusumEvaluator(0.5, 10.0, restart="none", isolates=iso)  # ARL0 ≈ 1.5e5, ARL(2σ) ≈ 7

    def last(shifts):
        rr = rng.standard_normal((600, 4)) + shifts
        d = ev.run(Residuals(np.arange(600) * 0.01, rr, names, iso))
        return d, d.isolated[-300:]

    d, lab = last([2.0, 2.0, 0, 0])
    assert set(lab) == {"fa"} and d.alarms[0].fault == "fa"
    _, lab = last([0, 0, -2.0, 0])
    assert set(lab) == {"fb"}
    _, lab = last([2.0, 0, 2.0, 0])
    assert set(lab) == {UNKNOWN_FAULT}  # residuals of two faults fire
    _, lab = last([0, 0, 0, 2.0])
    assert set(lab) == {UNKNOWN_FAULT}  # an untied residual detects but does not isolate
    # bank logic: a filter whose residuals point to two faults is discarded
    banked = CusumEvaluator(0.5, 10.0, restart="none", isolates=iso, groups=("g1", "g1", "g1", "g2"))
    rr = rng.standard_normal((600, 4)) + [2.0, 0, 2.0, 0]
    d = banked.run(Residuals(np.arange(600) * 0.01, rr, names, iso))
    assert d.isolated[-1] == UNKNOWN_FAULT


def test_bad_input():
    r = Residuals(np.arange(50) * 1.0, np.random.default_rng(0).standard_normal((50, 2)), ("a", "b"), ())
    with pytest.raises(ParameterError, match="no drift/threshold"):
        CusumEvaluator().run(r)
    with pytest.raises(ParameterError, match="no drift/threshold"):
        CusumEvaluator(drift=0.5).step([0.0, 0.0])
    with pytest.raises(DataError, match="3 threshold values for 2 residuals"):
        CusumEvaluator(0.5, [4, 4, 4]).run(r)
    ev = CusumEvaluator(0.5, [4, 4])
    ev.step([0.0, 0.0])
    with pytest.raises(DataError, match="got 3 residuals after steps with 2"):
        ev.step([0.0, 0.0, 0.0])
    ev.reset()
    with pytest.raises(DataError, match="2 threshold values for 3 residuals"):
        ev.step([0.0, 0.0, 0.0])
    for kw in ({"drift": 0.0}, {"drift": -1.0}, {"threshold": 0.0}, {"sigma": -1.0}):
        with pytest.raises(ParameterError, match="must be positive"):
            CusumEvaluator(**kw)
    with pytest.raises(ParameterError, match="restart"):
        CusumEvaluator(restart="sometimes")
    with pytest.raises(ParameterError, match="hold"):
        CusumEvaluator(hold=-1)
    with pytest.raises(ParameterError, match="needs a target"):
        CusumEvaluator().fit(r, shift=1.0)
    with pytest.raises(ParameterError, match="shift="):
        CusumEvaluator().fit(r, arl0=100.0)
    with pytest.raises(DataError, match="at least 10"):
        CusumEvaluator().fit(r.slice(stop=5.0))
    with pytest.raises(DataError, match="constant"):
        CusumEvaluator().fit(Residuals(np.arange(50) * 1.0, np.zeros((50, 1)), ("a",), ()))
    with pytest.raises(ParameterError, match="positive"):
        cusum_design(100.0, 0.0)
    with pytest.raises(ParameterError, match="not above"):
        cusum_design(1.02, 1.0)
    with pytest.raises(ParameterError, match="threshold must be positive"):
        cusum_arl(0.5, -1.0)
