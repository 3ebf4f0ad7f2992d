"""Speed-scheduled (LPV) parity filter: van der Ploeg 2018, Lemma 3-3.2, Thm 3-3.4, Sec. 4-3-4."""

from __future__ import annotations

import dataclasses

import cvxpy as cp
import numpy as np
import pytest

from fdikit.design.parity.polynomial import dae_form, parity_filter
from fdikit.design.parity.polynomial_rank import bar_matrices
from fdikit.design.parity.scheduled import scheduled_parity_filter
from fdikit.design.parity.scheduled_window import lpv_bar_matrices, lpv_parity_row, lpv_rank_test
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.faults import Bias, FaultScenario, Noise, ScaleFactor
from fdikit.metrics import vaf
from fdikit.plants.single_track import single_track, single_track_lpv
from fdikit.simulate import simulate, simulate_scheduled, time_grid
from fdikit.trace import Trace

KMH = 1 / 3.6
V70 = 70 * KMH
FAMILY = single_track_lpv()
FA = np.deg2rad(0.1)


def _steering(t):
    return 2.3e-3 * np.sin(0.6 * np.pi * t)  # (4.2)


def _ramp_speed(t):
    """70 km/h until 10 s, raised-cosine to 120 km/h at 50 s, then constant (m/s)."""
    s = np.clip((t - 10.0) / 40.0, 0.0, 1.0)
    return (70.0 + 50.0 * (1 - np.cos(np.pi * s)) / 2) * KMH


def test_family_is_the_sampled_single_track():
    for kmh in (30, 70, 120):
        m, ref = FAMILY(kmh * KMH), single_track(kmh * KMH, dt=0.01).with_actuator_faults(["steering"])
        assert m.faults == ref.faults and m.outputs == ref.outputs and m.dt == 0.01
        np.testing.assert_allclose(m.A, ref.A, rtol=0, atol=1e-15)
        np.testing.assert_allclose(m.B, ref.B, rtol=0, atol=1e-15)
    assert single_track_lpv(steering_fault=False)(V70).faults == ()
    with pytest.raises(ParameterError, match="dt"):
        single_track_lpv(dt=0.0)
    with pytest.raises(ParameterError, match="speed"):
        FAMILY(-1.0)


def test_lpv_bar_matrices_follow_the_window():
    """Lemma 3-3.2 (time-consistent A13): block row i holds H_0(ρ(τ_i)) at column i and H_1 at i + 1."""
    gen = scheduled_parity_filter(FAMILY, V70)
    rhos = np.array([70.0, 95.0, 120.0]) * KMH
    Hb, Lb, Fb = lpv_bar_matrices([gen.dae(r) for r in rhos])
    for i, r in enumerate(rhos):
        H0, H1, L, F = FAMILY.dae_matrices(r)
        np.testing.assert_array_equal(Hb[7 * i : 7 * i + 7, 6 * i : 6 * i + 6], H0)
        np.testing.assert_array_equal(Hb[7 * i : 7 * i + 7, 6 * i + 6 : 6 * i + 12], H1)
        np.testing.assert_array_equal(Lb[7 * i : 7 * i + 7, 4 * i : 4 * i + 4], L)
        np.testing.assert_array_equal(Fb[7 * i : 7 * i + 7, i : i + 1], F)
    stacks = gen.bar_matrices(np.vstack([rhos, np.full(3, V70)]))
    for mine, ref in zip(stacks, (Hb, Lb, Fb)):
        np.testing.assert_array_equal(mine[0], ref)
    for mine, lti in zip(stacks, bar_matrices(dae_form(FAMILY(V70)), 2)):
        np.testing.assert_array_equal(mine[1], lti)  # constant speed: the LTI bar matrices of Lemma 2-1.2


def test_lpv_rank_condition_on_speed_grid():
    """(3.15) / Sec. 4-3-4: Rank [H̄ F̄] = 21 > Rank H̄ = 20 for every (ρ1, ρ2, ρ3) of a grid, incl. extreme speeds."""
    gen = scheduled_parity_filter(FAMILY, V70)
    grid = np.array([1.0, 5.0, 30.0, 70.0, 85.0, 100.0, 120.0, 250.0]) * KMH
    for window in np.array(np.meshgrid(grid, grid, grid)).reshape(3, -1).T:
        test = lpv_rank_test([gen.dae(r) for r in window])
        assert (test.holds, test.rank_with, test.rank_without) == (True, 21, 20), window / KMH


def test_closed_form_tends_to_the_projection_and_solves_the_qp():
    """(3.17) = ½ Σ u_i u_iᵀ F_j / (1 + γ s_i²) + ½ P F_j (SVD of H̄); γ → ∞ gives ½ P F_j, the QP (3.16) optimum."""
    Hb, _, Fb = bar_matrices(dae_form(FAMILY(V70)), 2)
    f = Fb[:, 0]
    U, s, _ = np.linalg.svd(Hb)
    s = np.concatenate([s, np.zeros(U.shape[0] - s.size)])
    s[s < 1e-12 * s[0]] = 0.0
    proj = 0.5 * U[:, s == 0] @ (U[:, s == 0].T @ f)
    np.testing.assert_allclose(lpv_parity_row(Hb, f), proj, rtol=0, atol=1e-14)
    gaps, cosines = [], []
    for gamma in (1e5, 1e7, 1e9, 1e11, 1e12):
        row = lpv_parity_row(Hb, f, gamma)
        ref = 0.5 * U @ ((U.T @ f) / (1 + gamma * s**2))
        assert np.abs(row - ref).max() <= 1e-15 * gamma * np.abs(ref).max()  # forming γ H̄H̄ᵀ costs ~ γ eps ‖H̄‖²
        gaps.append(np.linalg.norm(row - proj) / np.linalg.norm(proj))
        cosines.append(row @ proj / (np.linalg.norm(row) * np.linalg.norm(proj)))
    # slow convergence: the smallest non-zero singular value 3.2e-6 needs γ ≫ 1/σ² ≈ 1e11
    assert all(a > b for a, b in zip(gaps, gaps[1:])) and gaps[-1] < 0.1
    assert cosines[1] == pytest.approx(0.77, abs=0.005)  # independent reproduction: cosine ≈ 0.77 at γ = 1e7
    assert cosines[-1] > 0.99
    # independent convex solve of (3.16): max N̄F̄_j s.t. N̄H̄ = 0, ‖N̄‖ ≤ 1 (Clarabel via cvxpy)
    n = cp.Variable(Hb.shape[0])
    cp.Problem(cp.Maximize(f @ n), [Hb.T @ n == 0, cp.norm(n, 2) <= 1]).solve()
    assert f @ n.value == pytest.approx(2 * np.linalg.norm(proj), rel=1e-6)
    assert n.value @ proj / (np.linalg.norm(n.value) * np.linalg.norm(proj)) > 0.999


def test_q2_column_is_degenerate():
    """Sec. 4-3-4: the q² column of F̄ lies in the range of H̄, so (3.17) gives N̄ ≈ 0 there."""
    Hb, _, Fb = bar_matrices(dae_form(FAMILY(V70)), 2)
    assert np.linalg.norm(lpv_parity_row(Hb, Fb[:, 2])) <= 1e-14 * np.linalg.norm(Fb[:, 2])
    ratios = [np.linalg.norm(lpv_parity_row(Hb, Fb[:, 2], g)) / np.linalg.norm(lpv_parity_row(Hb, Fb[:, 0], g))
              for g in (1e5, 1e7, 1e9)]
    assert ratios[0] > ratios[1] > ratios[2] and ratios[1] < 1e-4  # measured 1.4e-3, 4.6e-5, 8.0e-7
    with pytest.raises(DesignError, match="column"):
        scheduled_parity_filter(FAMILY, V70, column=2)


def _s1_trace(duration=70.0):
    """S1 of Sec. 4-3-1 without disturbances: f_a = 0.1° at 30 s, f_m = 0.9 at 50 s, 70 km/h."""
    t = time_grid(duration, 0.01)
    scenario = FaultScenario([ScaleFactor("steering", factor=0.9, onset=50.0), Bias("steering", FA, onset=30.0)])
    return simulate(FAMILY(V70), scenario, t=t, u=_steering(t))


def test_constant_speed_reproduces_lti_and_vaf_rises_with_gamma():
    """Sec. 4-3-4, Fig. 4-14: exact with the projection; VAF(LTI, LPV) rises with γ and exceeds 99.9 % at γ = 1e7.

    The thesis prints VAF = 99.98 % at γ = 1e7 and "γ > 8·10⁶ approaches the LTI result" (Fig. 4-14).
    """
    trace = _s1_trace()
    speed = np.full(len(trace), V70)
    r_lti = parity_filter(FAMILY(V70)).generator.run(trace).r[:, 0]
    r_proj = scheduled_parity_filter(FAMILY, V70).run(trace, schedule=speed).r[:, 0]
    assert np.abs(r_proj - r_lti).max() <= 1e-8 * np.abs(r_lti).max()
    r_col1 = scheduled_parity_filter(FAMILY, V70, column=1).run(trace, schedule=speed).r[:, 0]
    assert np.abs(r_col1 - r_proj).max() <= 1e-8 * np.abs(r_lti).max()  # any non-degenerate j: same null row
    gammas = (1e5, 1e6, 1e7, 1e8, 1e9)
    vafs = [vaf(r_lti, scheduled_parity_filter(FAMILY, V70, gamma=g).run(trace, schedule=speed).r[:, 0])
            for g in gammas]
    assert all(a <= b for a, b in zip(vafs, vafs[1:])) and vafs[1] < vafs[2]
    assert vafs[2] > 99.9 and vafs[1] < 99.9
    assert vafs[0] < 90.0


def test_scheduled_filter_tracks_offset_while_speed_varies():
    """Required demonstration (Sec. 4-3-4, Fig. 4-15): speed 70 → 120 km/h (10–50 s), f_a = 0.1° at 30 s.

    Steady tracking error over 50–60 s: LTI filter designed at 70 km/h vs the scheduled filter (projection and
    γ = 1e7).  The plant is the frozen-speed ZOH model at every sample ("complete discretisation").
    """
    t = time_grid(60.0, 0.01)
    speed = _ramp_speed(t)
    trace = simulate_scheduled(FAMILY, speed, FaultScenario([Bias("steering", FA, onset=30.0)]), u=_steering(t))
    assert trace.outputs[-1] == "speed"
    f = np.where(t >= 30.0, FA, 0.0)
    last, before = t >= 50.0, t < 30.0

    def rms(r):
        return float(np.sqrt(np.mean((r - f)[last] ** 2)))

    r_lti = parity_filter(FAMILY(V70)).generator.run(trace).r[:, 0]
    r_proj = scheduled_parity_filter(FAMILY, V70).run(trace).r[:, 0]
    r_gamma = scheduled_parity_filter(FAMILY, V70, gamma=1e7).run(trace).r[:, 0]
    assert rms(r_lti) > 10 * FA  # ≈ 0.12 rad: the 70 km/h filter loses the offset completely
    assert rms(r_proj) < 1e-9 * FA  # ≈ 1.6e-13 rad: exact decoupling at every speed
    assert rms(r_gamma) < 1e-2 * FA  # ≈ 4.3e-6 rad
    assert rms(r_lti) > 1e3 * rms(r_gamma)
    assert np.abs(r_proj[before]).max() < 1e-12  # speed changes alone leave the scheduled residual at round-off
    assert np.abs(r_lti[before]).max() > 1e-3  # ... but not the LTI one (≈ 3e-3 rad before the fault)


def test_online_equals_batch_and_follows_the_gap_rule():
    t = time_grid(3.0, 0.01)
    speed = (70 + 50 * t / 3.0) * KMH  # fast ramp so every window differs
    trace = simulate_scheduled(FAMILY, speed, FaultScenario([Bias("steering", FA, onset=1.0)]), u=_steering(t),
                               d=np.column_stack([np.full(t.size, 1 / 350), np.zeros(t.size)]))
    gen = scheduled_parity_filter(FAMILY, V70, gamma=1e7)
    clean = gen.run(trace, schedule="speed")
    batch = clean.r[:, 0]
    stepper = gen.online()
    online = np.array([stepper.step(trace.u[k], trace.y[k, :3], speed[k]) for k in range(len(trace))])
    np.testing.assert_allclose(online, batch, rtol=0, atol=1e-14)
    assert clean.valid.all() and not clean.recovering.any()
    # a NaN sample: NaN residual; the windows holding it give w = 0; recovering for recovery_length() after
    y = trace.y.copy()
    y[100, 1] = np.nan
    bad = Trace(t=t, u=trace.u, y=y, controls=trace.controls, outputs=trace.outputs)
    res = gen.run(bad)
    stepper = gen.online()
    out = stepper.run(bad)
    assert np.isnan(res.r[100, 0]) and np.isnan(out.r[100, 0]) and stepper.invalid == 1
    np.testing.assert_array_equal(res.valid, out.valid)
    np.testing.assert_array_equal(res.recovering, out.recovering)
    keep = np.arange(len(trace)) != 100
    np.testing.assert_allclose(out.r[keep, 0], res.r[keep, 0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(res.r[:100, 0], batch[:100], rtol=0, atol=0)  # before the gap: untouched
    # the last zero-filled w is at the last window holding sample 100: k = 100 + window
    n_dec = gen.recovery_length()
    last_fill = 100 + gen.window
    expect = np.ones(len(trace), bool)
    expect[100 : last_fill + n_dec] = False
    np.testing.assert_array_equal(res.valid, expect)
    assert res.recovering.sum() == last_fill + n_dec - 101
    # after the recovery the transient is below recovery_tol (0.1) of the residual's own size
    after = slice(last_fill + n_dec, len(trace))
    dev = np.abs(res.r[after, 0] - batch[after])
    assert dev.max() <= 0.1 * np.abs(batch[after]).max()


def test_recovery_length_from_the_impulse_response():
    """One pole p: Σ_{i≥d} p^{2i} / Σ p^{2i} = p^{2d} ≤ tol² ⇔ d ≥ log tol / log p."""
    gen = scheduled_parity_filter(FAMILY, V70)
    single = dataclasses.replace(gen, poles=np.array([0.9]))
    assert single.recovery_length(0.1) == int(np.ceil(np.log(0.1) / np.log(0.9)))
    assert gen.recovery_length(0.5) < gen.recovery_length(0.1) < gen.recovery_length(0.01)


def test_generic_family_equals_fast_path():
    """A family without dae_matrices goes through dae_form(family(ρ)); both paths give the same residual.

    Likewise the simulator: SingleTrackLPV.state_space (one batched exponential for all speeds) and
    family(ρ) per speed give the same trace (bitwise here: the batch shares the per-speed scaling).
    """
    t = time_grid(2.0, 0.01)
    speed = (80 + 20 * t) * KMH
    trace = simulate_scheduled(FAMILY, speed, u=_steering(t))
    generic = scheduled_parity_filter(lambda v: FAMILY(v), V70)
    fast = scheduled_parity_filter(FAMILY, V70)
    assert fast.fast_path and not generic.fast_path
    np.testing.assert_allclose(generic.run(trace).r, fast.run(trace).r, rtol=0, atol=1e-15)
    slow_trace = simulate_scheduled(lambda v: FAMILY(v), speed, u=_steering(t))
    np.testing.assert_array_equal(slow_trace.y, trace.y)


def test_simulate_scheduled_matches_simulate_at_constant_speed():
    t = time_grid(20.0, 0.01)
    d = np.where(t[:, None] >= 5.0, [1 / 350, 0.03], 0.0)
    scenario = FaultScenario([ScaleFactor("steering", factor=0.8, onset=8.0), Bias("steering", FA, onset=12.0),
                              Bias("yaw_rate", 1e-3, onset=15.0), Noise("heading_error", std=1e-3, onset=4.0)])
    mine = simulate_scheduled(FAMILY, np.full(t.size, V70), scenario, u=_steering(t), d=d, rng=5)
    ref = simulate(FAMILY(V70), scenario, t=t, u=_steering(t), d=d, rng=5)
    # same fault streams as simulate(): the noise fault (std 1e-3) draws the same numbers
    np.testing.assert_allclose(mine.y[:, :3], ref.y, rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(mine.fault, ref.fault)
    np.testing.assert_array_equal(mine.signal("speed"), V70)


def test_bad_input_errors():
    gen = scheduled_parity_filter(FAMILY, V70)
    trace = simulate(FAMILY(V70), t=time_grid(1.0, 0.01), u=_steering(time_grid(1.0, 0.01)))
    with pytest.raises(DataError, match="schedule"):
        gen.run(trace)  # no 'speed' column in a plain simulate() trace
    with pytest.raises(DataError, match="one per sample"):
        gen.run(trace, schedule=np.ones(5))
    with pytest.raises(DesignError, match="gamma"):
        scheduled_parity_filter(FAMILY, V70, gamma=-1.0).run(trace, schedule=np.full(len(trace), V70))
    with pytest.raises(DesignError, match="column"):
        scheduled_parity_filter(FAMILY, V70, column=5)
    with pytest.raises(DesignError, match="improper|poles"):
        scheduled_parity_filter(FAMILY, V70, poles=[0.5, 0.5])
    with pytest.raises(ModelError, match="discrete"):
        scheduled_parity_filter(lambda v: single_track(v), V70)
    with pytest.raises(DataError, match="equally long"):
        vaf(np.ones(3), np.ones(4))


def test_simulate_scheduled_bad_family():
    speed = np.linspace(70, 80, 50) * KMH

    class Wrong:  # state_space that does not match the family's models
        def __call__(self, v):
            return FAMILY(v)

        def state_space(self, v):
            A, B, C, D = FAMILY.state_space(v)
            return 0.5 * A, B, C, D

    with pytest.raises(ModelError, match="state_space disagrees"):
        simulate_scheduled(Wrong(), speed)
    with pytest.raises(ModelError, match="names, sizes and dt"):
        simulate_scheduled(lambda v: single_track(v, dt=0.01 if v < 20 else 0.02), speed)
    with pytest.raises(ModelError, match="discrete"):
        simulate_scheduled(lambda v: single_track(v), speed)
    with pytest.raises(ModelError, match="already an output"):
        simulate_scheduled(FAMILY, speed, schedule_name="yaw_rate")
    with pytest.raises(DataError, match="2\\+ finite"):
        simulate_scheduled(FAMILY, [V70, np.nan])
