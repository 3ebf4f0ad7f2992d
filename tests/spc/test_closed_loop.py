"""Closed-loop SPC: the step equals the QP built from the batch VARX fit; the loop tracks; switching configurations."""

import numpy as np
import pytest

from fdikit.errors import DataError
from fdikit.spc.closed_loop import ClosedLoopSPC
from fdikit.spc.law import SpcLimits, SpcWeights, spc_problem, unconstrained_move
from fdikit.spc.varx import varx_fit

A = np.array([[0.9, 0.2], [0.0, 0.7]])
B = np.array([[0.0], [0.5]])
C = np.array([[1.0, 0.0]])
K = np.array([[0.4], [0.1]])


def plant_data(n, rng, noise=0.05, u=None):
    u = rng.standard_normal((n, 1)) if u is None else u
    x = np.zeros(2)
    y = np.empty((n, 1))
    for k in range(n):
        e = noise * rng.standard_normal(1)
        y[k] = C @ x + e
        x = A @ x + B @ u[k] + K @ e
    return u, y


def test_step_equals_the_qp_of_the_batch_fit():
    rng = np.random.default_rng(0)
    u, y = plant_data(400, rng)
    w = SpcWeights(1.0, 0.01, 0.1)
    spc = ClosedLoopSPC(8, 8, 3, w, forgetting=1.0)
    spc.initialize(u[:399], y[:399])
    got = spc.step(u[399], y[399], reference=[0.7])
    # λ = 1: the recursive factor after one update is the batch fit on all 400 samples.
    pred = varx_fit(u, y, 8)
    gamma, lam = pred.multistep(8)
    prob = spc_problem(gamma, lam, pred.past(u, y), [0.7], u[399], w, Nc=3)
    want = unconstrained_move(prob)[:1]
    # The recursive and batch Ξ̂_0 agree to ~1e-12 relative; OSQP stops at 1e-8 on a cond(H) ≈ 1e2 problem.
    assert got == pytest.approx(want, rel=1e-5, abs=1e-7)
    assert spc.history[-1].status == "solved"


def test_closed_loop_tracks_a_constant_reference_without_offset():
    rng = np.random.default_rng(1)
    u0, y0 = plant_data(600, rng)
    spc = ClosedLoopSPC(10, 10, 3, SpcWeights(1.0, 0.0, 0.05), SpcLimits(u_min=-3.0, u_max=3.0))
    spc.initialize(u0, y0)
    x = np.zeros(2)
    u_prev, r = np.zeros(1), 1.0
    ys = []
    noise = 0.01
    for _ in range(400):
        e = noise * rng.standard_normal(1)
        y = C @ x + e
        u_t = spc.step(u_prev, y, reference=[r])
        x = A @ x + B @ u_prev + K @ e
        u_prev = u_t
        ys.append(y[0])
    tail = np.array(ys[-200:])
    # Only Δu is penalised (R_c = 0): at rest the cost is zero only at y = r, so the mean error is the
    # noise's: std of the mean over 200 correlated samples ≤ σ_y·√(10/200); allow 6 of those.
    bound = 6 * np.std(tail) * np.sqrt(10 / 200) + 1e-9
    assert abs(np.mean(tail) - r) < bound
    assert np.std(tail) < 10 * noise


def test_frozen_predictor_does_not_move():
    rng = np.random.default_rng(2)
    u, y = plant_data(300, rng)
    spc = ClosedLoopSPC(6, 6, 2, SpcWeights(1.0, 0.01, 0.1), adapt=False)
    spc.initialize(u, y)
    before = spc.predictor.Xi0.copy()
    for k in range(5):
        spc.step(u[k], y[k], reference=[0.0])
    assert np.array_equal(spc.predictor.Xi0, before)


def test_reinitialise_with_another_input_configuration():
    rng = np.random.default_rng(3)
    u, y = plant_data(300, rng)
    spc = ClosedLoopSPC(6, 6, 2, SpcWeights(1.0, 0.01, 0.1))
    spc.initialize(u, y)
    assert spc.m == 1
    u2 = np.hstack([u, rng.standard_normal((300, 1))])
    spc.initialize(u2, y)
    assert spc.m == 2
    assert spc.step(u2[-1], y[-1], reference=[0.0]).shape == (2,)


def test_bad_use_is_refused():
    spc = ClosedLoopSPC(4, 4, 2, SpcWeights(1.0, 0.01, 0.1))
    with pytest.raises(DataError, match="initialize"):
        spc.step([0.0], [0.0], reference=[0.0])
    with pytest.raises(Exception, match="f = 5 exceeds p = 4"):
        ClosedLoopSPC(4, 5, 2, SpcWeights(1.0, 0.01, 0.1))
    rng = np.random.default_rng(4)
    u, y = plant_data(100, rng)
    spc.initialize(u, y)
    with pytest.raises(DataError):
        spc.step([np.nan], [0.0], reference=[0.0])


def test_past_window_is_the_plants_not_the_models():
    rng = np.random.default_rng(5)
    u, y = plant_data(300, rng)
    spc = ClosedLoopSPC(6, 6, 2, SpcWeights(1.0, 0.01, 0.1), forgetting=1.0)
    past_u, past_y = np.zeros((7, 1)), np.zeros((7, 1))
    spc.initialize(u, y, past=(past_u, past_y))
    spc.step([0.0], [0.0], reference=[0.0])
    # λ = 1: the factor after one update is the batch fit of the data plus the column
    # [zero window; y = 0] — the plant at rest, not the model data's last window.
    pred = varx_fit(u, y, 6)
    Z = np.column_stack([pred.past(u[: k + 1], y[: k + 1]) for k in range(5, 299)] + [np.zeros(6 * 2)])
    Y = np.column_stack([y[k + 1] for k in range(5, 299)] + [np.zeros(1)])
    want = np.linalg.lstsq(Z.T, Y.T, rcond=None)[0].T
    assert spc.predictor.Xi0 == pytest.approx(want, rel=1e-8, abs=1e-10)
    with pytest.raises(DataError, match="past must be"):
        spc.initialize(u, y, past=(past_u[:3], past_y[:3]))
