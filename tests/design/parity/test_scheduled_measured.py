"""The scheduled parity filter on a measured schedule: causal smoothing, the ``grid=`` fast path, names/isolates."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.design.parity.scheduled import scheduled_parity_filter
from fdikit.errors import ModelError, ParameterError
from fdikit.faults import Bias, FaultScenario
from fdikit.plants.single_track import single_track, single_track_lpv
from fdikit.simulate import simulate_scheduled, time_grid
from fdikit.trace import Trace

KMH = 1 / 3.6
V70 = 70 * KMH
FAMILY = single_track_lpv()
DT = 0.01


def _trace(duration=4.0, noise=0.07, seed=3):
    t = time_grid(duration, DT)
    speed = (70 + 10 * t / duration) * KMH
    trace = simulate_scheduled(FAMILY, speed, FaultScenario([Bias("steering", np.deg2rad(0.1), onset=1.0)]),
                               u=2.3e-3 * np.sin(0.6 * np.pi * t),
                               d=np.column_stack([np.full(t.size, 1 / 350), np.full(t.size, 0.02)]))
    noisy = speed + noise * np.random.default_rng(seed).standard_normal(t.size)
    return trace, speed, noisy


def _smoothed(gen, rho, tau, kind):
    """The smoothed schedule as the filter sees it, read back through a trace column."""
    st = gen.online(smoothing=tau, smoothing_kind=kind)
    return np.array([st._smoother(float(v)) for v in rho])


@pytest.mark.parametrize("kind", ["lowpass", "ramp"])
def test_smoothing_online_equals_batch_with_a_gap(kind):
    trace, _, noisy = _trace(3.0)
    noisy[120] = np.nan  # a missing speed sample
    gen = scheduled_parity_filter(FAMILY, V70, gamma=1e7)
    batch = gen.run(trace, schedule=noisy, smoothing=0.2, smoothing_kind=kind)
    st = gen.online(smoothing=0.2, smoothing_kind=kind)
    online = np.array([st.step(trace.u[k], trace.y[k, :3], noisy[k]) for k in range(len(trace))])
    np.testing.assert_allclose(online, batch.r[:, 0], rtol=0, atol=1e-14, equal_nan=True)
    assert np.isnan(batch.r[120, 0]) and st.invalid == 1
    assert batch.meta["smoothing"] == 0.2 and batch.meta["smoothing_kind"] == kind
    plain = gen.run(trace, schedule=noisy)
    assert np.nanmax(np.abs(plain.r[:, 0] - batch.r[:, 0])) > 0  # the option does something


def test_lowpass_variance_and_lag_match_theory():
    """First-order low-pass s(k) = a s(k−1) + (1−a) x(k):

    * white noise of variance σ²: stationary variance σ² (1−a)/(1+a); the sample variance of M = 40 000
      samples with correlation time 1/(1−a) ≈ 20 has relative standard error ≈ √(2·2·20/M) ≈ 0.045, so ±20 %
      is > 4 standard errors;
    * a ramp x(k) = c k: steady error x − s = c a/(1−a) exactly (lowpass); Brown's 2 s₁ − s₂: 0.
    """
    gen = scheduled_parity_filter(FAMILY, V70)
    tau = 0.2
    a = np.exp(-DT / tau)
    e = 0.1 * np.random.default_rng(0).standard_normal(40_000)
    s = _smoothed(gen, V70 + e, tau, "lowpass")[1000:]
    assert np.var(s) == pytest.approx(0.01 * (1 - a) / (1 + a), rel=0.2)
    c = 0.5 * DT  # 0.5 m/s² speed ramp
    ramp = V70 + c * np.arange(3000)
    lag = ramp - _smoothed(gen, ramp, tau, "lowpass")
    assert lag[-1] == pytest.approx(c * a / (1 - a), rel=1e-9)
    # Brown: transient error ~ k a^k c, below 1e-9 m/s after 3000 samples (a^3000 ≈ 3e-66)
    assert abs(ramp[-1] - _smoothed(gen, ramp, tau, "ramp")[-1]) < 1e-9


def test_grid_coefficients_within_the_interpolation_bound():
    """Linear interpolation error ≤ h²/8 max|M''| (M'' by central differences of the exact family, step 2e-3)."""
    h = 0.2
    gen = scheduled_parity_filter(FAMILY, V70, grid=h)
    exact = scheduled_parity_filter(FAMILY, V70)
    rho = V70 + np.random.default_rng(1).uniform(-1.0, 3.0, 40)
    lo, hi = rho.min() - h, rho.max() + h
    fine = np.linspace(lo, hi, int((hi - lo) / 2e-3))
    step = fine[1] - fine[0]
    S = exact._stacks(fine)
    for part, M in enumerate(gen._stacks(rho)):
        d2 = np.abs(S[part][2:] - 2 * S[part][1:-1] + S[part][:-2]).max(axis=0) / step**2
        err = np.abs(M - exact._stacks(rho)[part]).max(axis=0)
        # 1.05: the difference quotient's own O(step²) error; 1e-15: rounding of entries of size ~1
        assert np.all(err <= 1.05 * h**2 / 8 * d2 + 1e-15), part


def test_grid_residual_converges_quadratically_and_is_exact_on_nodes():
    trace, speed, noisy = _trace()
    exact = scheduled_parity_filter(FAMILY, V70).run(trace, schedule=noisy).r[:, 0]
    errs = [np.abs(scheduled_parity_filter(FAMILY, V70, grid=h).run(trace, schedule=noisy).r[:, 0] - exact).max()
            for h in (0.2, 0.1)]
    # error = c h² + O(h³): halving h divides it by 4 up to the next order (3–5 allowed)
    assert 3.0 < errs[0] / errs[1] < 5.0
    assert errs[1] < 1e-4 * np.abs(exact).max()
    const = np.full(len(trace), V70)  # the design point is a node: same as the exact path
    np.testing.assert_array_equal(scheduled_parity_filter(FAMILY, V70, grid=0.1).run(trace, schedule=const).r,
                                  scheduled_parity_filter(FAMILY, V70).run(trace, schedule=const).r)


def test_grid_bounds_the_family_calls_of_a_generic_family():
    calls = []

    def family(v):
        calls.append(v)
        return single_track(v, dt=DT).with_actuator_faults(["steering"])

    trace, _, noisy = _trace(1.5)
    h = 0.5
    gen = scheduled_parity_filter(family, V70, grid=h)
    calls.clear()
    gen.run(trace, schedule=noisy)
    nodes = (noisy.max() - noisy.min()) / h + 2  # the nodes bracketing every sample
    assert len(set(calls)) <= nodes
    calls.clear()
    scheduled_parity_filter(family, V70).run(trace, schedule=noisy)
    assert len(set(calls)) == len(np.unique(noisy)) > 5 * nodes  # the exact path: one model per sample
    online = gen.online().run(trace, schedule=noisy)  # shares the node cache
    np.testing.assert_allclose(online.r, gen.run(trace, schedule=noisy).r, rtol=0, atol=1e-14)


def test_names_and_isolates():
    gen = scheduled_parity_filter(FAMILY, V70, names=["r_steer"], isolates={"r_steer": None})
    assert gen.residuals == ("r_steer",) and gen.isolates == (None,)
    assert scheduled_parity_filter(FAMILY, V70).isolates == ("steering_actuator",)
    assert scheduled_parity_filter(FAMILY, V70, name="x").residuals == ("x",)
    trace, speed, _ = _trace(1.0)
    res = gen.run(trace, schedule=speed)
    assert res.names == ("r_steer",) and res.isolates == (None,)
    with pytest.raises(ParameterError, match="bare|steering_actuator"):
        scheduled_parity_filter(FAMILY, V70, isolates=["steering"])
    with pytest.raises(ModelError):
        scheduled_parity_filter(FAMILY, V70, isolates=["wheel_speed_sensor"])  # no such output
    with pytest.raises(ParameterError, match="one per residual"):
        scheduled_parity_filter(FAMILY, V70, names=["a", "b"])
    with pytest.raises(ParameterError, match="once"):
        scheduled_parity_filter(FAMILY, V70, name="a", names=["a"])
    with pytest.raises(ParameterError, match="does not have"):
        scheduled_parity_filter(FAMILY, V70, isolates={"r_x": None})


def test_bad_smoothing_and_grid():
    gen = scheduled_parity_filter(FAMILY, V70)
    trace, speed, _ = _trace(1.5)
    for bad in (0.0, -1.0, np.inf, True, "1"):
        with pytest.raises(ParameterError, match="smoothing"):
            gen.run(trace, schedule=speed, smoothing=bad)
        with pytest.raises(ParameterError, match="smoothing"):
            gen.online(smoothing=bad)
    with pytest.raises(ParameterError, match="smoothing_kind"):
        gen.run(trace, schedule=speed, smoothing=0.1, smoothing_kind="median")
    for bad in (0.0, -0.1, np.nan, "0.1"):
        with pytest.raises(ParameterError, match="grid"):
            scheduled_parity_filter(FAMILY, V70, grid=bad)
    assert isinstance(trace, Trace)
