"""Tests of fdikit.spc.controller (Hallouzi 2008, §5.2)."""

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.spc import law
from fdikit.spc.controller import SubspacePredictiveController

A = np.array([[0.7, 0.2], [-0.1, 0.5]])
B = np.array([[1.0], [0.5]])
C = np.array([[1.0, 0.0]])


def _closed_loop(ctl, n_steps, r):
    x = np.zeros(2)
    u = np.zeros(1)
    ys = []
    for _ in range(n_steps):
        y = C @ x
        ys.append(y[0])
        u_next = ctl.step(u, y, r)
        x = A @ x + B @ u
        u = u_next
    return np.array(ys)


def test_frozen_spc_tracks_constant_reference_without_offset():
    # Noise-free LTI data with a white-noise start-up: the frozen predictor is exact (its Lf equals the
    # Markov parameters, tests/spc/test_predictor.py). Penalising only the rate Δu (R_c = 0) gives the
    # law integral action: at a steady state (Δu = 0) the unconstrained optimum has y = r because the
    # DC gain C(I−A)^{-1}B ≠ 0. The closed loop is stable (checked by convergence), so the error
    # decays geometrically; after 200 closed-loop steps it is at round-off / solver level (eps 1e-8).
    rng = np.random.default_rng(0)
    dither = rng.standard_normal((200, 1))
    ctl = SubspacePredictiveController(8, 3, law.SpcWeights([1.0], [0.0], [0.1]), window=40,
                                       startup=dither, frozen=True)
    y = _closed_loop(ctl, 300, [1.0])
    assert abs(y[-1] - 1.0) < 1e-5
    assert np.max(np.abs(y[-20:] - 1.0)) < 1e-5
    d = ctl.diagnostics()
    assert not d["spc"][: ctl.samples_needed - 1].any() and d["spc"][ctl.samples_needed - 1:].all()


def test_startup_input_returned_until_enough_data():
    ctl = SubspacePredictiveController(2, 1, law.SpcWeights([1.0], [0.0], [0.1]), window=8,
                                       startup=lambda k: [0.5 * k])
    assert ctl.samples_needed == 2 * 2 + 8 - 1
    out = [ctl.step([0.0], [0.0], [1.0])[0] for _ in range(3)]
    assert out == [0.5, 1.0, 1.5]


def test_bad_arguments():
    w = law.SpcWeights([1.0], [0.0], [0.1])
    with pytest.raises(ParameterError):
        SubspacePredictiveController(2, 3, w)
    with pytest.raises(ParameterError):
        SubspacePredictiveController(2, 1, w, excitation={"rho": 1.0})
    ctl = SubspacePredictiveController(2, 1, w, window=8)
    ctl.step([0.0], [0.0], [1.0])
    with pytest.raises(DataError):
        ctl.step([0.0, 1.0], [0.0], [1.0])


def test_first_adaptive_move_equals_the_true_model_problem():
    # Noise-free data: ŷ_f = L_p v_p + L_f u_f is exact, with L_p v_p = [C A^i x_{t+1}]_{i<M} (free
    # response from x_{t+1} = A x_t + B u_t) and L_f the lower block-Toeplitz of D = 0, CB, CAB, …
    # The same QP built from these true matrices must give the controller's first move (to the
    # round-off of the RQ fit, bounded by ~1e-8 relative on this well-conditioned dither, cf. the
    # predictor tests).
    M, Nc = 6, 2
    rng = np.random.default_rng(1)
    ctl = SubspacePredictiveController(M, Nc, law.SpcWeights([1.0], [0.01], [0.1]), window=30,
                                       startup=rng.standard_normal((100, 1)))
    x = np.zeros(2)
    u = np.zeros(1)
    for _ in range(ctl.samples_needed):
        y = C @ x
        x_t, u_t = x, u
        u_next = ctl.step(u, y, [1.0])
        x = A @ x + B @ u
        u = u_next
    assert ctl.diagnostics()["spc"][-1] and not ctl.diagnostics()["spc"][-2]
    x_next = A @ x_t + B @ u_t
    obs = np.vstack([C @ np.linalg.matrix_power(A, i) for i in range(M)])
    markov = [np.zeros((1, 1))] + [C @ np.linalg.matrix_power(A, i) @ B for i in range(M - 1)]
    Lf = np.zeros((M, M))
    for i in range(M):
        for j in range(i + 1):
            Lf[i, j] = markov[i - j][0, 0]
    problem = law.spc_problem(obs, Lf, x_next, [1.0], u_t, law.SpcWeights([1.0], [0.01], [0.1]), None, Nc)
    expected = law.unconstrained_move(problem)[:1]
    np.testing.assert_allclose(u_next, expected, rtol=1e-6, atol=1e-8)
