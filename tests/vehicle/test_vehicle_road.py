"""fdikit.vehicle.road: spatial road profiles (Robson, Gill, bump) and the crosswind pulse.

Statistical tolerances.  A Welch PSD estimate with Hann windows, 50 % overlap and K segments has a relative
variance per bin of ``(1 + 2·0.167²)/K ≈ 1.056/K`` (Welch's overlap correction for the Hann window); the ratio
estimate/theory averaged over M adjacent bins has variance ``1.056/K · (1 + 2·(4/9) + 2·(1/36))/M = 2.05/(K M)``,
since the Hann-windowed DFT bins are correlated with amplitude coefficients −2/3 (neighbour) and 1/6 (two apart),
i.e. 4/9 and 1/36 in power.  Every band is asserted within 5 such σ plus the window-leakage bias, which is computed
exactly from the AR(1) autocovariance (``_expected_welch``), not assumed.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from fdikit.errors import ParameterError
from fdikit.vehicle.road import (
    RoadProfile,
    crosswind_pulse,
    flat_road,
    gill_coherence,
    gill_psd,
    gill_road,
    robson_psd,
    robson_road,
    sine_bump,
)

VAR_FACTOR = 1.056 * (1 + 2 * 4 / 9 + 2 / 36)  # per-band variance factor of a Welch ratio (module docstring)


def _bands(f, edges):
    return [(lo, hi, (f >= lo) & (f < hi)) for lo, hi in edges]


def _expected_welch(var, phi, ds, nperseg):
    """E[welch] (one-sided, Hann, no detrend) of a stationary AR(1) with variance ``var`` and coefficient ``phi``.

    ``E[P(f_k)] = (2 ds / Σw²) Σ_m R(m) c_w(m) e^{-2πi k m / L}``, ``R(m) = var φ^|m|``, ``c_w`` the window's
    autocorrelation; the DFT is taken on a 2L grid and every second bin kept.
    """
    w = scipy.signal.get_window("hann", nperseg)
    lags = np.arange(-(nperseg - 1), nperseg)
    a = var * phi ** np.abs(lags) * np.correlate(w, w, "full")
    buf = np.zeros(2 * nperseg)
    buf[:nperseg], buf[-(nperseg - 1):] = a[nperseg - 1:], a[:nperseg - 1]
    return 2 * ds / np.sum(w * w) * np.real(np.fft.rfft(buf))[::2]


# ---------------------------------------------------------------------------------------------- Robson
ROBSON_EDGES = [(0.02, 0.05), (0.05, 0.2), (0.2, 1.0), (1.0, 5.0), (5.0, 10.0)]


@pytest.mark.parametrize("convention", ["report", "one-sided"])
def test_robson_welch_psd_matches_theory(convention):
    ds, n, nper = 0.05, 2_000_000, 2 ** 14
    x = robson_road((n - 1) * ds, spacing=ds, psd_convention=convention, rng=11).left
    f, P = scipy.signal.welch(x, fs=1 / ds, nperseg=nper, detrend=False)
    theory = robson_psd(f[1:], psd_convention=convention, spacing=ds)
    gain2 = 2 * np.pi * 1e-7 * (np.pi if convention == "one-sided" else 1.0)
    a = 2 * np.pi * 0.01
    expected = _expected_welch(gain2 / (2 * a), np.exp(-a * ds), ds, nper)[1:]
    K = 2 * (n // nper) - 1
    for lo, hi, m in _bands(f[1:], ROBSON_EDGES):
        ratio = np.mean(P[1:][m] / theory[m])
        bias = np.mean(expected[m] / theory[m]) - 1
        sigma = np.sqrt(VAR_FACTOR / (K * m.sum()))
        assert abs(bias) < sigma  # the leakage is small: the comparison is with robson_psd, not with the bias
        assert abs(ratio - 1) < 5 * sigma + abs(bias), (convention, lo, hi, ratio, sigma, bias)


def test_robson_psd_closed_forms():
    lam = np.array([0.0, 0.01, 0.1, 1.0])
    np.testing.assert_allclose(robson_psd(lam, psd_convention="one-sided"), 1e-7 / (lam ** 2 + 1e-4), rtol=1e-13)
    np.testing.assert_allclose(robson_psd(lam), 1e-7 / (np.pi * (lam ** 2 + 1e-4)), rtol=1e-13)
    # the sampled PSD is the continuous one plus its aliases: the same well below Nyquist, above it near Nyquist
    lo = np.array([0.001, 0.01, 0.1])
    np.testing.assert_allclose(robson_psd(lo, spacing=0.05), robson_psd(lo), rtol=1e-4)
    assert robson_psd(10.0, spacing=0.05) > robson_psd(10.0)
    # the sampled PSD integrates to the AR(1) variance R_c/(2 λ_0)
    lam = np.linspace(0, 10, 200_001)
    area = np.trapezoid(robson_psd(lam, spacing=0.05), lam)
    assert area == pytest.approx(1e-7 / (2 * 0.01), rel=1e-6)


def test_robson_variance_lag_one_and_stationary_start():
    ds, n = 1.0, 2_000_000
    x = robson_road((n - 1) * ds, spacing=ds, rng=3).left
    var, phi = 1e-7 / (2 * 0.01), np.exp(-2 * np.pi * 0.01 * ds)
    # relative std of the sample variance of an AR(1): sqrt(2 (1 + φ²) / ((1 - φ²) n))
    assert np.var(x) == pytest.approx(var, rel=5 * np.sqrt(2 * (1 + phi ** 2) / ((1 - phi ** 2) * n)))
    r1 = np.dot(x[1:], x[:-1]) / np.dot(x, x)
    assert r1 == pytest.approx(phi, abs=5 * np.sqrt((1 - phi ** 2) / n))
    # the first and last samples of many short roads have the stationary variance (std of a variance: sqrt(2/N))
    gen = np.random.default_rng(5)
    ends = np.array([robson_road(10.0, spacing=1.0, rng=gen).left[[0, -1]] for _ in range(3000)])
    np.testing.assert_allclose(np.var(ends, axis=0), var, rtol=5 * np.sqrt(2 / 3000))


def test_robson_conventions_differ_by_sqrt_pi_and_tracks_are_equal():
    a = robson_road(200.0, rng=4)
    b = robson_road(200.0, rng=4, psd_convention="one-sided")
    # equal up to rounding carried through the recursion (relative to the profile's scale, not to each sample)
    np.testing.assert_allclose(b.left, np.sqrt(np.pi) * a.left, rtol=0, atol=1e-12 * np.abs(b.left).max())
    assert np.array_equal(a.left, a.right)


def test_same_seed_same_profile_bit_for_bit():
    assert np.array_equal(robson_road(300.0, rng=9).left, robson_road(300.0, rng=9).left)
    g1, g2 = gill_road(300.0, intensity=1e-7, rng=9), gill_road(300.0, intensity=1e-7, rng=9)
    assert np.array_equal(g1.left, g2.left) and np.array_equal(g1.right, g2.right)
    assert not np.array_equal(robson_road(300.0, rng=9).left, robson_road(300.0, rng=10).left)


# ---------------------------------------------------------------------------------------------- Gill
def _gill_long():
    ds, n = 0.5, 2_000_000
    return ds, n, gill_road((n - 1) * ds, intensity=1e-7, spacing=ds, rng=21)


def test_gill_coherence_matches_theory_and_falls():
    ds, n, road = _gill_long()
    nper = 2 ** 13
    f, C = scipy.signal.coherence(road.left, road.right, fs=1 / ds, nperseg=nper, detrend=False)
    K = 2 * (n // nper) - 1
    k_eff = K / 1.056
    theory = gill_coherence(f, spacing=ds, squared=True)
    for lo, hi, m in _bands(f, [(3e-4, 1.5e-3), (1.5e-3, 5e-3), (5e-3, 0.02), (0.02, 0.05)]):
        c = theory[m]
        # large-K estimate of the magnitude-squared coherence: bias (1 - C)²/K, variance 2 C (1 - C)² / K
        expected = np.mean(c + (1 - c) ** 2 / k_eff)
        sigma = np.sqrt(VAR_FACTOR * np.mean(2 * c * (1 - c) ** 2) / (K * m.sum()))
        assert abs(C[m].mean() - expected) < 5 * sigma, (lo, hi, C[m].mean(), expected, sigma)
    # high wavenumber: the theory is ~0 and the estimate is its null bias ~1/K_eff (a Beta(1, K-1)-like variable)
    high = (f >= 0.2) & (f < 1.0)
    assert gill_coherence(0.2, spacing=ds, squared=True) < 1e-4
    assert C[high].mean() < 3 / K
    low = (f > 0) & (f < 1.5e-3)
    assert C[low].mean() > 100 * C[high].mean()


def test_gill_coherence_closed_form():
    assert float(gill_coherence(0.0)) == pytest.approx(0.75, abs=1e-15)
    assert float(gill_coherence(0.0, coherence=0.3)) == pytest.approx(0.3, abs=1e-15)
    lam = np.array([0.0, 0.01, 0.05, 1.0])
    l1, l2 = 0.01, 0.01 * np.sqrt(7.0)
    np.testing.assert_allclose(gill_coherence(lam), (l2 ** 2 - l1 ** 2) / (2 * lam ** 2 + l1 ** 2 + l2 ** 2),
                               rtol=1e-12)
    assert np.all(np.diff(gill_coherence(np.linspace(0, 1, 50))) < 0)
    np.testing.assert_allclose(gill_coherence(lam, squared=True), gill_coherence(lam) ** 2, rtol=1e-14)
    # given cut-offs: rho(0) is still the parameter; fully correlated tracks are equal
    assert float(gill_coherence(0.0, gamma=(0.1, 2.0))) == pytest.approx(0.75, rel=1e-12)
    same = gill_road(50.0, intensity=1e-7, coherence=1.0, rng=2)
    assert np.array_equal(same.left, same.right)


def test_gill_track_psd_matches_theory():
    ds, n, road = _gill_long()
    nper = 2 ** 13
    K = 2 * (n // nper) - 1
    # the track is the sum of two independent AR(1) parts, c_i = S_0/2 each, variance π c_i/(2 λ_i)
    expected = sum(_expected_welch(np.pi * 0.5e-7 / (2 * lam_c), np.exp(-2 * np.pi * lam_c * ds), ds, nper)
                   for lam_c in (0.01, 0.01 * np.sqrt(7.0)))[1:]
    for track in (road.left, road.right):
        f, P = scipy.signal.welch(track, fs=1 / ds, nperseg=nper, detrend=False)
        theory = gill_psd(f[1:], intensity=1e-7, spacing=ds)
        for lo, hi, m in _bands(f[1:], [(1e-3, 5e-3), (5e-3, 0.02), (0.02, 0.2), (0.2, 1.0)]):
            ratio = np.mean(P[1:][m] / theory[m])
            bias = np.mean(expected[m] / theory[m]) - 1
            sigma = np.sqrt(VAR_FACTOR / (K * m.sum()))
            assert abs(bias) < sigma
            assert abs(ratio - 1) < 5 * sigma + abs(bias), (lo, hi, ratio, sigma, bias)
    # closed form and the high-wavenumber level S_0 / λ²
    lam = np.array([0.0, 0.01, 0.1])
    l1, l2 = 0.01, 0.01 * np.sqrt(7.0)
    closed = 0.5e-7 * (1 / (lam ** 2 + l1 ** 2) + 1 / (lam ** 2 + l2 ** 2))
    np.testing.assert_allclose(gill_psd(lam, intensity=1e-7), closed, rtol=1e-12)
    assert float(gill_psd(1e3, intensity=1e-7)) * 1e6 == pytest.approx(1e-7, rel=1e-8)


def test_gill_variance_of_each_track():
    # variance = π c1/(2 λ1) + π c2/(2 λ2), the integral of the one-sided PSD; relative std of an AR(1) variance
    ds, n = 2.0, 1_000_000
    road = gill_road((n - 1) * ds, intensity=1e-7, spacing=ds, rng=8)
    l1, l2 = 0.01, 0.01 * np.sqrt(7.0)
    var = np.pi * 0.5e-7 / (2 * l1) + np.pi * 0.5e-7 / (2 * l2)
    phi = np.exp(-2 * np.pi * l1 * ds)  # the slower part bounds the correlation length
    tol = 5 * np.sqrt(2 * (1 + phi ** 2) / ((1 - phi ** 2) * n))
    assert np.var(road.left) == pytest.approx(var, rel=tol)
    assert np.var(road.right) == pytest.approx(var, rel=tol)


# ---------------------------------------------------------------------------------------------- profile, bump, wind
def test_heights_exact_on_a_linear_profile():
    ds = 0.1
    s = np.arange(101) * ds
    road = RoadProfile(ds, 0.3 + 0.02 * s, -0.1 * s, "ramp")
    q = np.random.default_rng(0).uniform(0, road.length, 500)
    left, right = road.heights(q)
    np.testing.assert_allclose(left, 0.3 + 0.02 * q, rtol=0, atol=1e-15)
    np.testing.assert_allclose(right, -0.1 * q, rtol=0, atol=1e-15)
    assert road.length == pytest.approx(10.0, rel=1e-15)
    assert isinstance(road.heights(2.5)[0], float)
    assert road.heights(road.length)[1] == pytest.approx(-1.0, abs=1e-15)
    assert road.heights(q.reshape(50, 10))[0].shape == (50, 10)
    with pytest.raises(ParameterError, match="longer road"):
        road.heights(10.5)
    with pytest.raises(ParameterError, match="negative"):
        road.heights([-0.1, 1.0])


def test_profile_add_and_validation():
    a, b = flat_road(20.0), sine_bump(20.0, position=5.0)
    c = a + b
    np.testing.assert_array_equal(c.left, b.left)
    assert c.label == "flat + " + b.label
    with pytest.raises(ParameterError, match="same length and spacing"):
        a + flat_road(30.0)
    with pytest.raises(ParameterError, match="RoadProfile"):
        a + 1.0
    with pytest.raises(ParameterError, match="same length"):
        RoadProfile(1.0, [0, 1, 2], [0, 1])
    with pytest.raises(ParameterError, match="left"):
        RoadProfile(1.0, [[0, 1], [2, 3]], [0, 1])
    with pytest.raises(ParameterError, match="right"):
        RoadProfile(1.0, [0, 1], [0, np.nan])
    with pytest.raises(ParameterError, match="spacing"):
        RoadProfile(0.0, [0, 1], [0, 1])
    with pytest.raises((AttributeError, TypeError)):
        a.spacing = 1.0
    with pytest.raises(ValueError):
        a.left[0] = 1.0  # read-only arrays


def test_bump_peak_and_width():
    ds, pos, h, w = 0.01, 2.0, 0.01, 0.3
    bump = sine_bump(5.0, position=pos, height=h, width=w, spacing=ds)
    s = np.arange(bump.left.size) * ds
    assert bump.left.max() == pytest.approx(h, rel=1e-14)
    assert s[np.argmax(bump.left)] == pytest.approx(pos + w / 2, abs=1e-12)
    nz = np.flatnonzero(bump.left > 1e-12 * h)
    assert s[nz[0]] == pytest.approx(pos + ds, abs=1e-9) and s[nz[-1]] == pytest.approx(pos + w - ds, abs=1e-9)
    # the trapezoid sum of a full cosine period is exact: area h·w/2
    assert np.sum(bump.left) * ds == pytest.approx(h * w / 2, rel=1e-12)
    np.testing.assert_array_equal(bump.left, bump.right)
    # off-grid position: the samples are the formula's values
    off = sine_bump(5.0, position=1.234, spacing=0.05)
    u = (np.arange(off.left.size) * 0.05 - 1.234) / 0.3
    formula = np.where((u > 0) & (u < 1), 0.005 * (1 - np.cos(2 * np.pi * u)), 0.0)
    np.testing.assert_allclose(off.left, formula, rtol=0, atol=1e-18)
    with pytest.raises(ParameterError, match="does not fit"):
        sine_bump(2.0, position=1.9)
    with pytest.raises(ParameterError, match="position"):
        sine_bump(2.0, position=-1.0)
    with pytest.raises(ParameterError, match="width"):
        sine_bump(2.0, position=0.5, width=0.0)


def test_crosswind_pulse_shape_and_sign():
    t = np.arange(0, 15, 0.01)
    W = crosswind_pulse(t)
    assert W.shape == (t.size, 2)
    on = (t >= 1.0) & (t < 11.0)
    np.testing.assert_allclose(W[on, 1], 15.0, rtol=1e-15)
    np.testing.assert_array_equal(W[~on], 0.0)
    np.testing.assert_allclose(W[:, 0], 0.0, atol=1e-14)
    assert np.sum(W[:, 1]) * 0.01 == pytest.approx(150.0, abs=15.0 * 0.01)
    east = crosswind_pulse([0.5, 3.0], speed=10.0, start=0.0, duration=2.0, direction=0.0)
    np.testing.assert_allclose(east, [[10.0, 0.0], [0.0, 0.0]], atol=1e-15)
    right = crosswind_pulse(5.0, direction=-np.pi / 2)  # blowing toward the right: W_Y < 0
    assert right.shape == (1, 2) and right[0, 1] == pytest.approx(-15.0)


@pytest.mark.parametrize("call, name", [
    (lambda: robson_road(-1.0), "length"),
    (lambda: robson_road(10.0, spacing=0.0), "spacing"),
    (lambda: robson_road(10.0, spacing=20.0), "spacing"),
    (lambda: robson_road(10.0, roughness=0.0), "roughness"),
    (lambda: robson_road(10.0, cutoff=-0.01), "cutoff"),
    (lambda: robson_road(10.0, psd_convention="two-sided"), "psd_convention"),
    (lambda: robson_road(10.0, rng=-1), "rng"),
    (lambda: robson_road(10.0, rng="seed"), "rng"),
    (lambda: robson_psd([-0.1]), "wavenumber"),
    (lambda: robson_psd([11.0], spacing=0.05), "wavenumber"),
    (lambda: gill_road(10.0, intensity=0.0), "intensity"),
    (lambda: gill_road(10.0, intensity=1e-7, coherence=1.5), "coherence"),
    (lambda: gill_road(10.0, intensity=1e-7, track=0.0), "track"),
    (lambda: gill_road(10.0, intensity=1e-7, gamma=(0.1,)), "gamma"),
    (lambda: gill_road(10.0, intensity=1e-7, gamma=(0.1, -1.0)), "gamma"),
    (lambda: gill_coherence(0.1, squared=1), "squared"),
    (lambda: gill_psd(0.1, intensity=-1.0), "intensity"),
    (lambda: sine_bump(10.0, position=1.0, height=np.inf), "height"),
    (lambda: crosswind_pulse([0.0, np.nan]), "t"),
    (lambda: crosswind_pulse(1.0, speed=-1.0), "speed"),
    (lambda: crosswind_pulse(1.0, duration=0.0), "duration"),
    (lambda: flat_road(10.0, spacing=-1.0), "spacing"),
])
def test_bad_arguments_name_the_argument(call, name):
    with pytest.raises(ParameterError, match=name):
        call()
