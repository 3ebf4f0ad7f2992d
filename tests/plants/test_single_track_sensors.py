"""Lateral acceleration and side-slip outputs of the single-track model (``outputs=``)."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.dae import dae_form
from fdikit.errors import ParameterError
from fdikit.plants.registry import get_plant
from fdikit.plants.single_track import OUTPUTS, PRIUS_2010, SENSORS, single_track, single_track_lpv

P = PRIUS_2010
ALL = ("lateral_acceleration", "sideslip", "yaw_rate")


def test_default_outputs_unchanged():
    for dt in (None, 0.01):
        old, new = single_track(20.0, dt=dt), single_track(20.0, dt=dt, outputs=OUTPUTS)
        assert old.outputs == OUTPUTS and new.outputs == OUTPUTS
        np.testing.assert_array_equal(old.C, new.C)
        assert not old.D.any()
    assert single_track_lpv().outputs == OUTPUTS and SENSORS[:3] == OUTPUTS


def test_lateral_acceleration_is_the_tyre_force_balance():
    """Independent physics: a_y = (F_yf + F_yr)/m + g sin φ, F_y = C α (thesis sign, C < 0),
    α_f = (V_y + l_f r)/V − δ, α_r = (V_y − l_r r)/V; β = V_y / V.  Exact to rounding."""
    rng = np.random.default_rng(1)
    for v in (5.0, 19.44, 33.3):
        m = single_track(v, outputs=ALL)
        for _ in range(5):
            x = rng.normal(size=4) * [0.5, 0.2, 1.0, 0.05]
            delta, kappa, bank = rng.normal(size=3) * [0.02, 1e-3, 0.05]
            vy, r = x[0], x[1]
            a_f, a_r = (vy + P.l_f * r) / v - delta, (vy - P.l_r * r) / v
            a_y = (P.C_f * a_f + P.C_r * a_r) / P.m + P.g * bank
            y = m.C @ x + m.Du @ [delta] + m.Dd @ [kappa, bank]
            scale = abs(P.C_f) / P.m * (abs(a_f) + abs(a_r)) + P.g * abs(bank)
            assert y[0] == pytest.approx(a_y, abs=1e-13 * scale)
            assert y[1] == pytest.approx(vy / v, rel=1e-15)
            assert y[2] == x[1]


def test_lateral_acceleration_equals_finite_differences_of_the_state():
    """a_y = d/dt V_y + V r along a free response (δ = d = 0), the derivative by central differences.

    Central-difference error |x(t+h) − x(t−h)|/(2h) − ẋ(t) ≤ h²/6 max|x'''| with x''' = A³ x; the
    trajectory is the exact exponential, so the bound (times 1.01 for rounding) is the tolerance.
    """
    from scipy.linalg import expm

    v, h = 19.44, 1e-3
    m = single_track(v, outputs=ALL)
    x0 = np.array([0.3, 0.1, 0.5, 0.02])
    E = expm(m.A * h)  # the exact flow over one step; X[k] = E^k x0 (rounding grows ~k eps, far below the bound)
    X = np.empty((2000, 4))
    X[0] = x0
    for k in range(1, len(X)):
        X[k] = E @ X[k - 1]
    vy_dot = (X[2:, 0] - X[:-2, 0]) / (2 * h)
    a_fd = vy_dot + v * X[1:-1, 1]
    a_model = (X[1:-1] @ m.C.T)[:, 0]
    bound = h**2 / 6 * np.abs(X @ np.linalg.matrix_power(m.A, 3).T)[:, 0].max()
    assert np.abs(a_fd - a_model).max() <= 1.01 * bound + 1e-12
    assert np.abs(a_model).max() > 1e3 * bound  # the check is not vacuous


def test_sampled_and_scheduled_family_carry_the_feedthrough():
    family = single_track_lpv(outputs=ALL)
    for v in (8.0, 19.44, 30.0):
        ref = single_track(v, dt=0.01, outputs=ALL).with_actuator_faults(["steering"])
        mine = family(v)
        assert mine.outputs == ALL and mine.faults == ref.faults
        for a, b in ((mine.A, ref.A), (mine.B, ref.B), (mine.C, ref.C), (mine.D, ref.D)):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)
        assert mine.Du[0, 0] == pytest.approx(-P.C_f / P.m) and mine.Df[0, 0] == mine.Du[0, 0]
        dae = dae_form(mine)
        for a, b in zip(family.dae_matrices(v), (*dae.H, *dae.L, *dae.F)):
            np.testing.assert_array_equal(a, b)
    A, B, C, D = family.state_space([10.0, 20.0])
    np.testing.assert_allclose(D[1], family(20.0).D[:, :3], rtol=0, atol=1e-15)  # [steering, curvature, bank]
    np.testing.assert_allclose(C[0], family(10.0).C, rtol=0, atol=1e-15)


def test_scheduled_filter_on_lateral_acceleration_decouples_exactly():
    """With a_y among the outputs the fast path (dae_matrices) is taken and speed changes leave r ≈ 0."""
    from fdikit.design.parity.scheduled import scheduled_parity_filter
    from fdikit.simulate import simulate_scheduled, time_grid

    family = single_track_lpv(outputs=OUTPUTS + ("lateral_acceleration",))
    gen = scheduled_parity_filter(family, 20.0)
    assert gen.fast_path
    t = time_grid(4.0, 0.01)
    trace = simulate_scheduled(family, 18.0 + 2.0 * t, u=2.3e-3 * np.sin(0.6 * np.pi * t),
                               d=np.column_stack([np.full(t.size, 1 / 350), np.full(t.size, 0.02)]))
    r = gen.run(trace).r[:, 0]
    # exact projection: the residual is round-off times the signals (|z| ~ 1, cond. of the window ~ 1e6)
    assert np.abs(r).max() < 1e-8


def test_bad_output_selection_and_registry():
    for bad, match in ((["lateral_accel"], "outputs"), ([], "at least one"), (["sideslip", "sideslip"], "repeats")):
        with pytest.raises(ParameterError, match=match):
            single_track(20.0, outputs=bad)
        with pytest.raises(ParameterError, match=match):
            single_track_lpv(outputs=bad)
    m = get_plant("single-track", speed=20.0, dt=0.01, outputs=["lateral_acceleration"])
    assert m.outputs == ("lateral_acceleration",) and m.dt == 0.01
