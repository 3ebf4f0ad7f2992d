"""fdikit.batch against independent computations: scipy.signal.dlsim per trace, the generators' and evaluators'
own ``run`` per trace, and a brute-force loop for the level crossings.

Tolerances of the simulations are a forward rounding-error bound of the recursion (the system's norms, the
horizon Σ‖A^k‖ and the data's scale), so they hold under any BLAS kernel; the decisions are compared exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

from fdikit.batch import crossings, cusum_batch, dlsim_batch, run_generator_batch, threshold_batch
from fdikit.decision import CusumEvaluator, ThresholdEvaluator
from fdikit.errors import DataError, ParameterError
from fdikit.lti import dlsim_blocked
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, Residuals
from fdikit.trace import Trace

EPS = np.finfo(float).eps


def rounding_bound(A, B, C, D, u, X) -> float:
    """Bound on max |y − ŷ| of the recursion computed in floating point, from the states ``X`` (N, n).

    Each step ``[x+; y] = [A B; C D] [x; u]`` errs by at most ``γ ‖[A B; C D]‖_F ‖[x; u]‖`` (``γ = (n + m + 1)
    eps``, a dot product of ``n + m`` terms); the state errors are filtered by ``A``, so they add up to at most
    ``Σ_{k<N} ‖A^k‖₂`` times the largest step error, and reach ``y`` through ``C``.
    """
    n, m = B.shape
    N = u.shape[0]
    gamma = (n + m + 1) * EPS
    z = np.sqrt(np.max(np.sum(X**2, axis=1) + np.sum(u**2, axis=1)))
    horizon, P = 0.0, np.eye(n)
    for _ in range(N):
        horizon += np.linalg.norm(P, 2)
        P = A @ P
    step = gamma * np.linalg.norm(np.block([[A, B], [C, D]])) * z
    return float(np.linalg.norm(C, 2) * horizon * step + step)


def system(n, m, p, seed, rho=0.95):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    A = rho * M / np.max(np.abs(scipy.linalg.eigvals(M)))
    return A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))


@pytest.mark.parametrize("method", ["numba", "blas"])
def test_dlsim_batch_equals_scipy_dlsim_per_trace(method):
    A, B, C, D = system(5, 3, 2, seed=1, rho=0.99)
    rng = np.random.default_rng(2)
    R, N = 6, 300
    u = rng.standard_normal((R, N, 3)) * np.array([1.0, 100.0, 1e-3])
    x0 = 10 * rng.standard_normal((R, 5))
    y, x_end = dlsim_batch(A, B, C, D, u, x0, method=method, return_state=True)
    assert y.shape == (R, N, 2) and x_end.shape == (R, 5)
    for i in range(R):
        _, yi, xi = scipy.signal.dlsim((A, B, C, D, 1.0), u[i], x0=x0[i])
        tol = 2 * rounding_bound(A, B, C, D, u[i], xi)
        assert np.abs(y[i] - yi).max() <= tol
        assert np.abs(x_end[i] - (A @ xi[-1] + B @ u[i, -1])).max() <= tol / np.linalg.norm(C, 2) + tol
    one = dlsim_batch(A, B, C, D, u, x0[2], method=method)  # one x0 for every run
    _, y2, x2 = scipy.signal.dlsim((A, B, C, D, 1.0), u[0], x0=x0[2])
    assert np.abs(one[0] - y2).max() <= 2 * rounding_bound(A, B, C, D, u[0], x2)


def test_dlsim_batch_on_the_path_filters_equals_dlsim_blocked():
    from fdikit.studies.path1996.bank import path_bank

    g = path_bank().generator.discretize(0.01)  # the 50-state PATH bank
    rng = np.random.default_rng(3)
    u = rng.standard_normal((3, 200, g.B.shape[1]))
    for method in ("numba", "blas"):
        y = dlsim_batch(g.A, g.B, g.C, g.D, u, method=method)
        for i in range(3):
            ref, X, _ = dlsim_blocked(g.A, g.B, g.C, g.D, u[i])
            assert np.abs(y[i] - ref).max() <= 2 * rounding_bound(g.A, g.B, g.C, g.D, u[i], X)


def test_dlsim_batch_without_states_and_without_samples():
    D = np.array([[2.0, -1.0]])
    u = np.arange(12.0).reshape(2, 3, 2)
    y = dlsim_batch(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), D, u)
    np.testing.assert_array_equal(y, u @ D.T)
    A, B, C, D = system(2, 1, 1, seed=4)
    y, x_end = dlsim_batch(A, B, C, D, np.zeros((3, 0, 1)), np.ones(2), return_state=True)
    assert y.shape == (3, 0, 1) and np.array_equal(x_end, np.ones((3, 2)))


def generator_with_operating_point():
    A, B, C, D = system(4, 3, 2, seed=5, rho=0.9)
    op = OperatingPoint.from_vectors(["x1"], ["throttle"], ["speed", "yaw_rate"], x0=[25.0], u0=[0.2],
                                     y0=[25.0, 0.0])
    return ResidualGenerator(A, B, C, D, ("throttle",), ("speed", "yaw_rate"), ("r_speed", "r_yaw"), dt=0.01,
                             operating_point=op)


def traces(R, N, seed, dt=0.01):
    rng = np.random.default_rng(seed)
    t = np.arange(N) * dt
    return [Trace(t, 0.2 + 0.05 * rng.standard_normal((N, 1)),
                  np.c_[25.0 + rng.standard_normal(N), 0.1 * rng.standard_normal(N)],
                  ("throttle",), ("speed", "yaw_rate")) for _ in range(R)]


@pytest.mark.parametrize("method", ["numba", "blas"])
def test_run_generator_batch_equals_run_per_trace_with_an_operating_point(method):
    g = generator_with_operating_point()
    assert np.any(g.offset)
    trs = traces(4, 250, seed=6)
    x0 = np.random.default_rng(7).standard_normal((4, 4))
    from_traces = run_generator_batch(g, trs, x0, method=method)
    v = np.stack([g.absolute_inputs(tr) for tr in trs])
    from_array = run_generator_batch(g, v, x0, method=method)
    for i, tr in enumerate(trs):
        ref = g.run(tr, x0[i]).r
        dev = g.inputs_from(tr)
        X = scipy.signal.dlsim((g.A, g.B, g.C, g.D, g.dt), dev, x0=x0[i])[2]
        tol = 2 * rounding_bound(g.A, g.B, g.C, g.D, dev, X)
        assert np.abs(from_traces[i] - ref).max() <= tol
        assert np.abs(from_array[i] - ref).max() <= tol
    # without subtracting the operating point the residuals would be far off
    plain = ResidualGenerator(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, dt=g.dt)
    assert np.abs(run_generator_batch(plain, v, x0) - from_array).max() > 1.0


def test_run_generator_batch_discretises_a_continuous_generator_for_traces():
    A, B, C, D = system(3, 3, 2, seed=8)
    gc = ResidualGenerator(A - 2 * np.eye(3), B, C, D, ("throttle",), ("speed", "yaw_rate"), ("a", "b"))
    trs = traces(2, 100, seed=9)
    r = run_generator_batch(gc, trs)
    gd = gc.discretize(0.01)
    for i, tr in enumerate(trs):
        X = scipy.signal.dlsim((gd.A, gd.B, gd.C, gd.D, 0.01), gd.inputs_from(tr))[2]
        tol = 2 * rounding_bound(gd.A, gd.B, gd.C, gd.D, gd.inputs_from(tr), X)
        assert np.abs(r[i] - gc.run(tr).r).max() <= tol
    with pytest.raises(ParameterError, match="continuous.*discretize"):
        run_generator_batch(gc, np.zeros((2, 10, 3)))


def test_bad_simulation_inputs_are_refused_with_what_to_do():
    A, B, C, D = system(2, 2, 1, seed=10)
    with pytest.raises(DataError, match=r"shape \(runs, samples, 2 inputs\).*2 dimensions.*u\[None\]"):
        dlsim_batch(A, B, C, D, np.zeros((5, 2)))
    with pytest.raises(DataError, match="3 inputs.*B has 2 columns"):
        dlsim_batch(A, B, C, D, np.zeros((1, 5, 3)))
    with pytest.raises(ParameterError, match=r"x0 has shape \(3,\)"):
        dlsim_batch(A, B, C, D, np.zeros((2, 5, 2)), x0=np.zeros(3))
    with pytest.raises(ParameterError, match="C has 3 columns"):
        dlsim_batch(A, B, np.zeros((1, 3)), D, np.zeros((2, 5, 2)))
    with pytest.raises(ParameterError, match="method"):
        dlsim_batch(A, B, C, D, np.zeros((2, 5, 2)), method="fast")
    u = np.zeros((3, 5, 2))
    u[1, 3, 0] = np.nan
    for method in ("numba", "blas"):
        with pytest.raises(DataError, match="first is run 1 .*sample 3.*ResidualGenerator.run"):
            dlsim_batch(A, B, C, D, u, method=method)
    g = generator_with_operating_point()
    with pytest.raises(ParameterError, match="ResidualGenerator"):
        run_generator_batch("filter", np.zeros((1, 3, 3)))
    with pytest.raises(DataError, match=r"2 signals.*reads 3: \['throttle', 'speed', 'yaw_rate'\]"):
        run_generator_batch(g, np.zeros((1, 3, 2)))


def test_bad_traces_are_refused_with_what_to_do():
    g = generator_with_operating_point()
    trs = traces(2, 50, seed=11)
    with pytest.raises(DataError, match="2 different lengths"):
        run_generator_batch(g, [trs[0], traces(1, 40, seed=1)[0]])
    with pytest.raises(DataError, match=r"traces\[1\] is sampled at dt=0.02"):
        run_generator_batch(g, [trs[0], traces(1, 50, seed=1, dt=0.02)[0]])
    with pytest.raises(DataError, match="generator is discrete with dt=0.01; resample"):
        run_generator_batch(g, traces(2, 50, seed=1, dt=0.02))
    with pytest.raises(DataError, match=r"traces\[1\] is a str"):
        run_generator_batch(g, [trs[0], "trace"])
    bad = trs[1]
    y = bad.y.copy()
    y[7, 0] = np.nan
    gap = Trace(bad.t, bad.u, y, bad.controls, bad.outputs)
    with pytest.raises(DataError, match=r"traces\[1\] has an invalid sample at t=0.07 s.*generator.run"):
        run_generator_batch(g, [trs[0], gap])
    other = Trace(bad.t, bad.u, bad.y, ("brake",), bad.outputs)
    with pytest.raises(DataError, match="throttle"):
        run_generator_batch(g, [trs[0], other])


def residual_batch(R, N, q, seed, fault_at=None, size=3.0):
    rng = np.random.default_rng(seed)
    r = rng.standard_normal((R, N, q))
    if fault_at is not None:
        r[:, fault_at:, 0] += size * np.linspace(0.2, 1.0, R)[:, None]
    return r


def per_run(ev, r):
    t = np.arange(r.shape[1]) * 0.01
    names = tuple(f"r{i}" for i in range(r.shape[2]))
    return [ev.run(Residuals(t, r[i], names, (None,) * r.shape[2])) for i in range(r.shape[0])]


@pytest.mark.parametrize("persistence", [(1, 1), (2, 3), (3, 5), (4, 4), (1, 6)])
def test_threshold_batch_equals_run_and_its_statistic_scales_the_threshold(persistence):
    r = residual_batch(5, 400, 3, seed=12, fault_at=250, size=2.0)
    healthy = Residuals(np.arange(2000) * 0.01, np.random.default_rng(13).standard_normal((2000, 3)),
                        ("r0", "r1", "r2"), (None,) * 3)
    ev = ThresholdEvaluator(persistence=persistence).fit(healthy, false_alarm_prob=0.05)
    d = threshold_batch(ev, r)
    assert d.names == ("r0", "r1", "r2")
    runs = per_run(ev, r)
    assert np.array_equal(d.statistic > 1, d.alarm)
    for i, diag in enumerate(runs):
        assert np.array_equal(d.alarm[i], diag.alarm)
        assert np.array_equal(d.fired[i], diag.fired)
    assert d.alarm.any() and not d.alarm.all()
    for lam in (0.6, 1.7):
        scaled = ThresholdEvaluator(thresholds=lam * ev.thresholds, center=ev.center, persistence=persistence)
        for i, diag in enumerate(per_run(scaled, r)):
            assert np.array_equal(d.statistic[i] > lam, diag.alarm)
    # the statistic itself: max over residuals of the k-th largest of the window, brute force
    k, n = persistence
    a = np.abs(r - ev.center) / ev.thresholds
    brute = np.zeros(r.shape[:2])
    for j in range(r.shape[1]):
        w = np.sort(a[:, max(0, j - n + 1) : j + 1], axis=1)[:, ::-1]
        brute[:, j] = (w[:, k - 1] if w.shape[1] >= k else np.zeros_like(w[:, 0])).max(axis=1)
    np.testing.assert_array_equal(d.statistic, brute)


@pytest.mark.parametrize("two_sided", [True, False])
@pytest.mark.parametrize("hold", [0, 3])
def test_cusum_batch_without_restarts_equals_run(two_sided, hold):
    r = residual_batch(3, 5000, 2, seed=14, fault_at=4500, size=1.0)  # > 4096 samples: crosses a rebase
    ev = CusumEvaluator(drift=[0.5, 0.4], threshold=[6.0, 7.0], mean=0.01, sigma=[1.0, 1.1], two_sided=two_sided,
                        restart="none", hold=hold)
    d = cusum_batch(ev, r)
    for i, diag in enumerate(per_run(ev, r)):
        assert np.array_equal(d.alarm[i], diag.alarm)
        assert np.array_equal(d.fired[i], diag.fired)
        g = np.maximum(diag.meta["g_plus"], diag.meta["g_minus"]) / ev.threshold
        np.testing.assert_array_equal(d.statistic[i], g.max(axis=1))  # bit for bit: the same arithmetic
    assert d.alarm.any()
    if hold == 0:
        assert np.array_equal(d.statistic > 1, d.alarm)


def test_cusum_batch_gives_the_first_alarm_of_a_resetting_cusum():
    r = residual_batch(6, 1500, 3, seed=15, fault_at=700, size=1.5)
    healthy = Residuals(np.arange(5000) * 0.01, np.random.default_rng(16).standard_normal((5000, 3)),
                        ("r0", "r1", "r2"), (None,) * 3)
    ev = CusumEvaluator(hold=5).fit(healthy, arl0=300.0, shift=1.0)
    d = cusum_batch(ev, r)
    n_alarmed = 0
    for i, diag in enumerate(per_run(ev, r)):
        first = np.flatnonzero(diag.alarm)
        batch = np.flatnonzero(d.statistic[i] > 1)
        assert (first.size == 0) == (batch.size == 0)
        if first.size:
            n_alarmed += 1
            assert first[0] == batch[0]
            assert np.array_equal(d.alarm[i, : first[0] + 1], diag.alarm[: first[0] + 1])
    assert n_alarmed >= 4


def test_bad_evaluator_inputs_are_refused_with_what_to_do():
    r = np.zeros((2, 10, 3))
    with pytest.raises(ParameterError, match="no thresholds.*fit"):
        threshold_batch(ThresholdEvaluator(), r)
    with pytest.raises(ParameterError, match="no drift/threshold.*fit"):
        cusum_batch(CusumEvaluator(), r)
    with pytest.raises(ParameterError, match="ThresholdEvaluator, got CusumEvaluator"):
        threshold_batch(CusumEvaluator(drift=0.5, threshold=5.0), r)
    with pytest.raises(ParameterError, match="CusumEvaluator, got ThresholdEvaluator"):
        cusum_batch(ThresholdEvaluator(thresholds=1.0), r)
    with pytest.raises(DataError, match="2 thresholds values for 3 residuals"):
        threshold_batch(ThresholdEvaluator(thresholds=[1.0, 2.0]), r)
    with pytest.raises(DataError, match=r"shape \(runs, samples, residuals\)"):
        threshold_batch(ThresholdEvaluator(thresholds=1.0), np.zeros((10, 3)))
    healthy = Residuals(np.arange(100) * 0.01, np.random.default_rng(0).standard_normal((100, 2)), ("a", "b"),
                        (None, None))
    fitted = ThresholdEvaluator().fit(healthy, false_alarm_prob=0.01)
    with pytest.raises(DataError, match=r"3 residuals .*fitted on 2: \['a', 'b'\]"):
        threshold_batch(fitted, r)
    bad = np.zeros((2, 10, 2))
    bad[1, 4, 1] = np.nan
    with pytest.raises(DataError, match="run 1, sample 4, residual 1.*evaluator.run"):
        threshold_batch(fitted, bad)
    with pytest.raises(DataError, match="run 1, sample 4, residual 1"):
        cusum_batch(CusumEvaluator(drift=0.5, threshold=5.0), bad)


def brute_crossings(stat, t, onset, levels, healthy=None):
    R, N = stat.shape
    delay = np.full((R, len(levels)), np.nan)
    ups = np.zeros((R, len(levels)), int)
    for i in range(R):
        for j, lam in enumerate(levels):
            for k in range(N):
                fault = onset[i] is not None and not np.isnan(onset[i]) and t[k] >= onset[i]
                ok = (not fault) if healthy is None else healthy[i, k]
                if ok and stat[i, k] > lam and (k == 0 or stat[i, k - 1] <= lam):
                    ups[i, j] += 1
                if fault and stat[i, k] > lam and np.isnan(delay[i, j]):
                    delay[i, j] = t[k] - onset[i]
    return delay, ups


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 4), st.integers(1, 30), st.integers(0, 2**31 - 1), st.booleans())
def test_crossings_equal_a_brute_force_loop(R, N, seed, mask):
    rng = np.random.default_rng(seed)
    stat = np.round(rng.exponential(1.0, (R, N)), 1)  # rounded: ties with the levels and between samples
    t = np.cumsum(rng.uniform(0.5, 1.5, N))
    onset = [None if rng.random() < 0.3 else float(rng.uniform(t[0] - 1, t[-1] + 1)) for _ in range(R)]
    levels = np.unique(np.round(rng.uniform(0.0, 3.0, rng.integers(1, 6)), 1))
    healthy = rng.random((R, N)) < 0.7 if mask else None
    c = crossings(stat, t, onset, healthy, levels)
    delay, ups = brute_crossings(stat, t, onset, levels, healthy)
    np.testing.assert_array_equal(c.delay, delay)
    np.testing.assert_array_equal(c.upcrossings, ups)
    assert np.array_equal(c.levels, levels)


def test_crossings_of_a_batch_statistic_and_bad_input():
    r = residual_batch(4, 300, 2, seed=17, fault_at=200, size=4.0)
    d = threshold_batch(ThresholdEvaluator(thresholds=[3.0, 3.0], persistence=(2, 3)), r)
    t = np.arange(300) * 0.01
    onset = np.array([2.0, 2.0, np.nan, 2.0])
    c = crossings(d.statistic, t, onset, levels=np.linspace(0.5, 2.0, 7))
    delay, ups = brute_crossings(d.statistic, t, onset, c.levels)
    np.testing.assert_array_equal(c.delay, delay)
    np.testing.assert_array_equal(c.upcrossings, ups)
    assert np.isnan(c.delay[2]).all() and np.isfinite(c.delay[3, 0])
    with pytest.raises(DataError, match="statistic must have shape"):
        crossings(np.zeros(5), t[:5], [None])
    with pytest.raises(DataError, match="non-finite"):
        crossings(np.full((1, 3), np.nan), t[:3], [None])
    with pytest.raises(DataError, match="increasing"):
        crossings(np.zeros((1, 3)), [0.0, 2.0, 1.0], [None])
    with pytest.raises(DataError, match="one time per run"):
        crossings(np.zeros((2, 3)), t[:3], [None])
    with pytest.raises(DataError, match="healthy"):
        crossings(np.zeros((2, 3)), t[:3], [None, 1.0], healthy=np.ones((3, 2), bool))
    with pytest.raises(ParameterError, match="strictly increasing"):
        crossings(np.zeros((1, 3)), t[:3], [None], levels=[2.0, 1.0])
