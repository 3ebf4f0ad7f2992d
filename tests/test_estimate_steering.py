"""Steering-fault isolation: moving-window LS, its bound, the pre-filter (van der Ploeg 2018, Ch. 3, Sec. 4-3-2/4-3-3).

Oracles: brute-force least squares per window (numpy.linalg.lstsq), scipy.signal for the filters and
frequency responses, dense SVDs for the operator norms, and numbers from an independent
reproduction (separate scripts) next to the thesis' printed statements.
Residuals are ``r = G(q)[f_a + (f_m − 1) δ_set]`` with the thesis' fault map at 70 km/h,
``G(q) = K (q − z_0)/(q − p)^3``, as the parity filter gives after disturbance rejection.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.estimate.steering import (
    SteeringFaultIsolator,
    fault_map_coefficients,
    isolate_steering_faults,
    lateral_fault_map,
)
from fdikit.estimate.steering_bound import isolation_error_bound, restricted_matrices

H = 0.01
T = np.arange(7001) * H  # 70 s
E = 2.3e-3 * np.sin(0.6 * np.pi * T)  # (4.2)
DEG = np.pi / 180


def residual(pole, f_a, f_m, setpoint=E):
    num, den = fault_map_coefficients(lateral_fault_map(pole=pole))
    return scipy.signal.lfilter(num, den, f_a + (f_m - 1.0) * setpoint)


def constant_faults():
    return np.full(T.size, 0.1 * DEG), np.full(T.size, 0.5)  # Sec. 4-3-2 Case 1


def stepped_faults():
    # Sec. 4-3-3 Case 1: f_m 0.5 -> 0.6 at 40 s, f_a 0.1 -> 0.12 deg at 50 s
    return np.where(T >= 50 - 1e-9, 0.12, 0.1) * DEG, np.where(T >= 40 - 1e-9, 0.6, 0.5)


def settling_time(est, truth, t0, t1, tol):
    """Time after t0 from which |est - truth| <= tol (and est finite) on every sample up to t1."""
    m = (T >= t0 - 1e-9) & (T < t1 - 1e-9)
    bad = np.flatnonzero(~(np.abs(est[m] - truth[m]) <= tol))
    return 0.0 if bad.size == 0 else T[m][bad[-1]] + H - t0


# ---------------------------------------------------------------- the estimator itself


def test_window_estimates_equal_brute_force_least_squares():
    rng = np.random.default_rng(3)
    r, e = rng.normal(size=60), rng.normal(size=60)
    n = 7
    for nominal in (1.0, 0.0):
        est = isolate_steering_faults(r, e, n, nominal_gain=nominal)
        for k in range(n - 1, 60):
            phi = np.column_stack([np.ones(n), e[k - n + 1 : k + 1]])
            theta = np.linalg.lstsq(phi, r[k - n + 1 : k + 1], rcond=None)[0]
            assert est.f_a_hat[k] == pytest.approx(theta[0], rel=1e-10, abs=1e-12)
            assert est.f_m_hat[k] == pytest.approx(nominal + theta[1], rel=1e-10, abs=1e-12)
        assert not est.valid[: n - 1].any() and np.isnan(est.f_a_hat[: n - 1]).all() and est.valid[n - 1 :].all()


def test_online_isolator_reproduces_batch_including_nan_samples():
    f_a, f_m = stepped_faults()
    r = residual(0.9048, f_a, f_m)[:1500].copy()
    e = E[:1500].copy()
    r[400] = np.nan  # a lost residual sample
    e[900] = np.nan  # a lost set-point sample (holds the pre-filter state)
    for prefilter in (None, lateral_fault_map()):
        batch = isolate_steering_faults(r, e, 50, prefilter=prefilter)
        iso = SteeringFaultIsolator(50, prefilter=prefilter)
        steps = [iso.step(rk, ek) for rk, ek in zip(r, e)]
        np.testing.assert_array_equal([s.valid for s in steps], batch.valid)
        np.testing.assert_allclose([s.f_a_hat for s in steps], batch.f_a_hat, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose([s.f_m_hat for s in steps], batch.f_m_hat, rtol=1e-9, atol=1e-12)
        # the windows holding a NaN (and only those, apart from the first n-1 samples) are invalid
        bad = np.zeros(1500, bool)
        bad[:49] = True
        bad[400:450] = True
        bad[900:950] = True
        np.testing.assert_array_equal(~batch.valid, bad)


def test_guard_flags_windows_without_excitation_and_never_raises():
    e = E[:1000].copy()
    e[300:600] = 1e-3  # constant steering: V_n[E] = 0
    r = 0.5 * e + 1e-3
    with np.errstate(all="raise"):  # no warnings either
        est = isolate_steering_faults(r, e, 20)
    inside = np.arange(319, 600)  # windows entirely in the constant stretch
    assert not est.valid[inside].any()
    assert np.isnan(est.f_a_hat[inside]).all() and np.isnan(est.f_m_hat[inside]).all()
    assert np.isinf(est.excitation_factor[inside]).all() or np.all(est.excitation_factor[inside] > 1e10)
    assert est.valid[600 + 19 :].all() and est.valid[19:300].all()
    # a raised floor also refuses weak but non-zero excitation: V_n of a 20-sample sine window is ~1e-8 near a peak
    strict = isolate_steering_faults(r, e, 20, min_variance=1e-9)
    assert 0 < strict.valid.sum() < est.valid.sum()
    # all-constant input and too-short input: everything invalid, no exception
    assert not isolate_steering_faults(np.ones(50), np.ones(50), 10).valid.any()
    assert not isolate_steering_faults(np.ones(5), np.arange(5.0), 10).valid.any()


def test_bad_input_raises_clear_errors():
    with pytest.raises(ParameterError, match="window length n"):
        isolate_steering_faults(E, E, 1)
    with pytest.raises(DataError, match="equal length"):
        isolate_steering_faults(E[:10], E[:11], 5)
    with pytest.raises(DesignError, match="inside the unit circle"):
        isolate_steering_faults(E, E, 10, prefilter=([0.0, 1.0], [1.0, -1.2]))
    with pytest.raises(DesignError, match="DC gain 2"):
        isolate_steering_faults(E, E, 10, prefilter=([0.0, 1.0], [1.0, -0.5]))
    with pytest.raises(ModelError, match="improper"):
        SteeringFaultIsolator(10, prefilter=([1.0, 0.0, 0.0], [1.0, -0.5]))
    est = isolate_steering_faults(E, E, 10)
    with pytest.raises(DataError, match="non-finite"):
        isolation_error_bound(est, E, E, np.full(E.size, np.nan), 1.0)


def test_lateral_fault_map_unit_dc_and_printed_frequency_response():
    # independent: G(e^{jωh}) at 0.3 Hz, 70 km/h = 0.79491 - 0.51841j (p = 0.9048), 0.98891 - 0.13341j (p = 0.6065)
    for pole, printed in ((0.9048, 0.79491 - 0.51841j), (0.6065, 0.98891 - 0.13341j), (0.9, 0.81302 - 0.49882j)):
        num, den = fault_map_coefficients(lateral_fault_map(pole=pole))
        assert np.polyval(num, 1.0) / np.polyval(den, 1.0) == pytest.approx(1.0, abs=1e-12)
        _, g = scipy.signal.freqz(num, den, worN=[2 * np.pi * 0.3 * H])
        assert g[0] == pytest.approx(printed, abs=1e-5)


# ---------------------------------------------------------------- Thm 3-1.3


def test_fm_estimate_biased_toward_real_part_of_G_and_fa_unbiased():
    """Thm 3-1.3, Sec. 4-3-2: f̂_m -> 1 + (f_m - 1) Re G(e^{jω0 h}) = 0.6025 for f_m = 0.5, p = 0.9048.

    Thesis Sec. 4-3-2 Case 1 (Fig. 4-6): at n = 500 "f̂_a converges to the true f_a" but "the multiplicative
    fault has an offset".  Note §5.6 table: 0.6025 / 0.5055 / 0.5019 for p = 0.9048 / 0.6065 / 0.3679.
    """
    f_a, f_m = constant_faults()
    window = (T >= 25 - 1e-9) & (T < 65 - 1e-9)  # 40 s = 12 whole periods of the 0.3 Hz set-point
    for pole, note in ((0.9048, 0.6025), (0.6065, 0.5055), (0.3679, 0.5019)):
        num, den = fault_map_coefficients(lateral_fault_map(pole=pole))
        _, g = scipy.signal.freqz(num, den, worN=[2 * np.pi * 0.3 * H])
        limit = 1.0 + (0.5 - 1.0) * g[0].real
        assert limit == pytest.approx(note, abs=5e-5)
        r = residual(pole, f_a, f_m)
        for n in (10, 100, 500):
            est = isolate_steering_faults(r, E, n, t=T)
            assert np.nanmean(est.f_m_hat[window]) == pytest.approx(limit, abs=2e-4)
            assert np.nanmean(est.f_a_hat[window]) == pytest.approx(0.1 * DEG, rel=2e-3)
    # measured: 0.60255 (n = 10), 0.60261 (100), 0.60254 (500) against 0.602545


def test_bound_holds_tight_at_n10_loose_at_n500():
    """Thm 3-1.3: θ_e <= Θ_e; Sec. 4-3-2: at n = 10 "the bound touches θ_e", at n = 500 it "is no longer close".

    Note §5.6 (vehicle model, t >= 25 s): max θ/Θ = 0.9957 / 0.876 / 0.403, median 0.053 / 0.342 / 0.360.
    """
    f_a, f_m = constant_faults()
    r = residual(0.9048, f_a, f_m)
    late = T >= 25
    expected = {10: (0.9957, 0.053), 100: (0.876, 0.342), 500: (0.403, 0.360)}
    mean_theta, mean_bound = [], []
    for n, (max_ratio, median_ratio) in expected.items():
        est = isolate_steering_faults(r, E, n, t=T)
        b = isolation_error_bound(est, r, E, f_a, f_m)
        ratio = b.ratio[late]
        assert np.all(ratio <= 1.0)
        assert ratio.max() == pytest.approx(max_ratio, abs=0.005)
        assert np.median(ratio) == pytest.approx(median_ratio, abs=0.005)
        assert np.all(b.bound[late] == pytest.approx(b.bound_thesis[late], rel=1e-12))  # σ² ~ 3e-6 << 1
        mean_theta.append(b.theta[late].mean())
        mean_bound.append(b.bound[late].mean())
    # larger n pushes both the error and the bound down: measured θ 0.629 > 0.243 > 0.103, Θ 7.85 > 0.65 > 0.29
    assert mean_theta[0] > mean_theta[1] > mean_theta[2] > 0.1
    assert mean_bound[0] > mean_bound[1] > mean_bound[2]


def test_error_and_bound_shrink_as_poles_move_to_origin():
    """Sec. 4-3-2 Case 2 (Fig. 4-7), n = 10: error and bound fall from p = 0.9048 to 0.6065, marginally to 0.3679."""
    f_a, f_m = constant_faults()
    late = T >= 25
    theta, bound = [], []
    for pole in (0.9048, 0.6065, 0.3679):
        r = residual(pole, f_a, f_m)
        est = isolate_steering_faults(r, E, 10, t=T)
        b = isolation_error_bound(est, r, E, f_a, f_m)
        assert np.all(b.ratio[late] <= 1.0)
        theta.append(b.theta[late].mean())
        bound.append(b.bound[late].mean())
    # measured mean θ: 0.629, 0.159, 0.095; mean Θ: 7.85, 1.34, 0.78
    assert theta[0] > 3 * theta[1] and theta[1] > theta[2]
    assert bound[0] > 3 * bound[1] and bound[1] > bound[2]
    assert theta[1] - theta[2] < theta[0] - theta[1]  # diminishing returns


def test_e1_equals_restricted_matrix_form_of_G_minus_identity():
    """(3.6a): e_1 = ‖T_n (f_m E + f_a) + O_n x_F(k-n+1)‖ for the realisation of G(q) - I (Def. 3-1.2, newest first)."""
    f_a, f_m = stepped_faults()
    r = residual(0.9048, f_a, f_m)
    n = 40
    est = isolate_steering_faults(r, E, n)
    b = isolation_error_bound(est, r, E, f_a, f_m)
    num, den = fault_map_coefficients(lateral_fault_map())
    g_minus_i = (num - den, den)
    O, Tn = restricted_matrices(g_minus_i, n)
    u = f_a + (f_m - 1.0) * E
    A, B, C, D = scipy.signal.tf2ss(*g_minus_i)
    _, y, x = scipy.signal.dlsim((A, B, C, D, H), u)  # independent simulation of G - I
    for k in (n - 1, 3000, 3999, 4020, 5005, 7000):
        window = u[k - n + 1 : k + 1][::-1]
        y_window = O @ x[k - n + 1] + Tn @ window
        np.testing.assert_allclose(y_window, y[k - n + 1 : k + 1, 0][::-1], rtol=1e-9, atol=1e-15)
        assert b.e1[k] == pytest.approx(np.linalg.norm(y_window), rel=1e-8)


def test_regressor_norm_is_exact_and_printed_lemma_a11_fails_for_large_sigma():
    """Lemma A-1.1 erratum: sqrt((1+|μ|)/(nV)) bounds ‖Φ_n‖_2 only when σ_n² <= 1."""
    k = np.arange(400)
    e = 3.0 + np.sin(0.05 * k)  # σ² ≈ 9.5 > 1
    r = 0.2 + 0.5 * e + 0.01 * np.cos(0.3 * k)
    n = 30
    est = isolate_steering_faults(r, e, n, nominal_gain=0.0)
    b = isolation_error_bound(est, r, e, 0.2, 0.5)
    for j in (n - 1, 100, 250, 399):
        phi = np.column_stack([np.ones(n), e[j - n + 1 : j + 1]])
        exact = np.linalg.norm(np.linalg.pinv(phi), 2)
        assert b.regressor_norm[j] == pytest.approx(exact, rel=1e-9)
        assert b.factor[j] >= exact * (1 - 1e-12)
        assert b.factor_thesis[j] < exact  # the printed bound is violated here
    assert np.all(b.theta[est.valid] <= b.bound[est.valid])


# ---------------------------------------------------------------- Sec. 3-2: the pre-filter


def test_prefilter_exact_for_constant_faults():
    """Cor. 3-2.2: constant faults are estimated exactly (<= 1e-8) after the transient."""
    f_a, f_m = constant_faults()
    late = T >= 20
    for pole in (0.9048, 0.6065, 0.3679):
        G = lateral_fault_map(pole=pole)
        r = residual(pole, f_a, f_m)
        for n in (10, 100, 500):
            est = isolate_steering_faults(r, E, n, t=T, prefilter=G)
            assert np.max(np.abs(est.f_a_hat[late] - f_a[late])) <= 1e-8 * DEG
            assert np.max(np.abs(est.f_m_hat[late] - f_m[late])) <= 1e-8
    # the plain FI filter keeps its 0.10 offset in f_m on the same data
    plain = isolate_steering_faults(residual(0.9048, f_a, f_m), E, 500)
    assert np.nanmean(plain.f_m_hat[late]) - 0.5 == pytest.approx(0.1025, abs=1e-3)


def test_prefilter_settling_times_match_thesis():
    """Sec. 4-3-3: n = 10 converges "within 1 to 2 s", n = 500 "only after 5 s"; p = 0.6065 "0.25 s" (Fig. 4-13).

    Settling time = time after the step from which |f̂ - f| stays within 1 % of the step (0.001 for f_m,
    0.0002 deg for f_a) until the next step or the end.  Note §5.6: 1.21/1.30, 5.08/5.33, 0.23/0.31 s.
    Measured: 1.22/1.28, 1.65/1.71 (n = 100), 5.09/5.34, 0.24/0.29 s.
    """
    f_a, f_m = stepped_faults()
    cases = {(0.9048, 10): (1.0, 2.0), (0.9048, 100): (1.0, 2.0), (0.9048, 500): (4.5, 6.0), (0.6065, 10): (0.15, 0.4)}
    for (pole, n), (lo, hi) in cases.items():
        r = residual(pole, f_a, f_m)
        est = isolate_steering_faults(r, E, n, t=T, prefilter=lateral_fault_map(pole=pole))
        t_m = settling_time(est.f_m_hat, f_m, 40, 50, 0.001)
        t_a = settling_time(est.f_a_hat, f_a, 50, 70, 0.0002 * DEG)
        assert lo <= t_m <= hi and lo <= t_a <= hi, (pole, n, t_m, t_a)


def test_prefilter_coupling_trends_with_poles():
    """Sec. 4-3-3 Case 2: poles nearer 0 give less coupling of an f_m change into f̂_a, more of an f_a change into f̂_m.

    Note §5.6: max |f̂_m err| after the f_a step 0.23 / 0.84 / 1.08; max |f̂_a err| after the f_m step
    0.0016 / 0.0004 / 0.0003 deg (p = 0.9048 / 0.6065 / 0.3679, n = 10).
    """
    f_a, f_m = stepped_faults()
    after_fa, after_fm = T >= 50 - 1e-9, (T >= 40 - 1e-9) & (T < 50 - 1e-9)
    into_m, into_a = [], []
    for pole in (0.9048, 0.6065, 0.3679):
        est = isolate_steering_faults(residual(pole, f_a, f_m), E, 10, prefilter=lateral_fault_map(pole=pole))
        into_m.append(np.max(np.abs(est.f_m_hat - f_m)[after_fa]))
        into_a.append(np.max(np.abs(est.f_a_hat - f_a)[after_fm]) / DEG)
    np.testing.assert_allclose(into_m, [0.23, 0.84, 1.08], atol=0.01)
    np.testing.assert_allclose(into_a, [0.0016, 0.0004, 0.0003], atol=0.0001)


def test_prefilter_bound_holds_and_matches_dense_evaluation():
    """Thm 3-2.1 with the (3.10a) erratum: Θ̃_e >= θ̃_e; ẽ_1 checked against dense matrices of Def. 3-1.2."""
    f_a, f_m = stepped_faults()
    G = lateral_fault_map()
    r = residual(0.9048, f_a, f_m)
    for n in (10, 100):
        est = isolate_steering_faults(r, E, n, t=T, prefilter=G)
        b = isolation_error_bound(est, r, E, f_a, f_m)
        late = T >= 20
        assert np.all(b.theta[late] <= b.bound[late])
        assert np.all(b.bound[late] >= b.bound_thesis[late] * (1 - 1e-12))  # ‖E_n‖_2 >= ‖E‖_∞
        assert np.max(b.mismatch[late]) < 1e-12  # r is G[f] up to rounding (|r| ~ 1e-3)
        assert np.max(b.bound[(T >= 20) & (T < 39.9)]) < 1e-8  # constant faults: Θ̃ ≈ 0 (Cor. 3-2.2)
    # dense evaluation of (3.10a) (corrected) at windows straddling the f_m step, n = 100
    n = 100
    est = isolate_steering_faults(r, E, n, prefilter=G)
    b = isolation_error_bound(est, r, E, f_a, f_m)
    A, B, C, D = scipy.signal.tf2ss(G.num, G.den)
    sys = (A, B, C, D, H)
    xa = scipy.signal.dlsim(sys, f_a)[2]
    xm = scipy.signal.dlsim(sys, (f_m - 1) * E)[2]
    xe = scipy.signal.dlsim(sys, E)[2]
    O, Tn = restricted_matrices(G, n)
    for k in (4000, 4050, 4098, 5030):
        s, win = k - n + 1, slice(k - n + 1, k + 1)
        dm = np.diag((f_m - 1)[win][::-1])
        fa_n, e_n = f_a[win][::-1], E[win][::-1]
        e1 = (np.linalg.norm(O @ xm[s] - dm @ O @ xe[s]) + np.linalg.norm(O @ xa[s] + Tn @ fa_n - fa_n)
              + np.linalg.norm(Tn @ dm - dm @ Tn, 2) * np.linalg.norm(e_n))
        assert b.e1[k] == pytest.approx(e1, rel=1e-6, abs=1e-14)
