"""dlsim_blocked against the plain sample-by-sample recursion (and scipy.signal.dlsim)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from fdikit.lti import dlsim_blocked, lifted_matrices
from reference import state_space_loop


def _system(kind: str, n: int, m: int, p: int, seed: int):
    rng = np.random.default_rng(seed)
    if kind == "stable":
        M = rng.standard_normal((n, n))
        A = 0.95 * M / np.max(np.abs(scipy.linalg.eigvals(M)))
    else:  # marginally stable: rotations and an integrator, every eigenvalue on the unit circle
        blocks = []
        k = 0
        while k + 2 <= n:
            th = rng.uniform(0.1, 1.0)
            blocks.append(np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
            k += 2
        if k < n:
            blocks.append(np.eye(1))
        T = rng.standard_normal((n, n)) + 3 * np.eye(n)  # well-conditioned similarity
        A = T @ scipy.linalg.block_diag(*blocks) @ np.linalg.inv(T)
        assert np.allclose(np.abs(scipy.linalg.eigvals(A)), 1.0)
    return (A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m)),
            rng.standard_normal(n))


def _close(a, b, scale):
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("kind", ["stable", "marginal"])
@pytest.mark.parametrize("block", [1, 2, 7, 32, 50, 64, 1000])
def test_blocked_equals_naive_loop(kind, block):
    A, B, C, D, x0 = _system(kind, n=5, m=2, p=3, seed=block + (0 if kind == "stable" else 10_000))
    v = np.random.default_rng(block).standard_normal((200, 2))
    y, x, x_end = dlsim_blocked(A, B, C, D, v, x0, block=block)
    y_ref, x_ref, x_end_ref = state_space_loop(A, B, C, D, v, x0)
    scale = max(1.0, np.abs(x_ref).max())
    assert y.shape == (200, 3) and x.shape == (200, 5) and x_end.shape == (5,)
    _close(x, x_ref, scale)
    _close(y, y_ref, np.abs(y_ref).max())
    _close(x_end, x_end_ref, scale)
    np.testing.assert_array_equal(x[0], x0)


@pytest.mark.parametrize("N", [1, 5, 31, 32, 33, 97])
def test_lengths_around_the_block_size(N):
    A, B, C, D, x0 = _system("stable", n=3, m=1, p=2, seed=N)
    v = np.random.default_rng(N).standard_normal((N, 1))
    y, x, x_end = dlsim_blocked(A, B, C, D, v, x0, block=32)
    y_ref, x_ref, x_end_ref = state_space_loop(A, B, C, D, v, x0)
    _close(x, x_ref, max(1.0, np.abs(x_ref).max()))
    _close(y, y_ref, max(1.0, np.abs(y_ref).max()))
    _close(x_end, x_end_ref, max(1.0, np.abs(x_end_ref).max()))


def test_matches_scipy_dlsim():
    A, B, C, D, x0 = _system("stable", n=4, m=2, p=2, seed=99)
    v = np.random.default_rng(0).standard_normal((300, 2))
    _, y_ref, x_ref = scipy.signal.dlsim((A, B, C, D, 1.0), v, x0=x0)
    y, x, _ = dlsim_blocked(A, B, C, D, v, x0, block=16)
    _close(x, x_ref, np.abs(x_ref).max())
    _close(y, y_ref, np.abs(y_ref).max())


def test_zero_states_is_pure_feedthrough():
    D = np.array([[1.0, -2.0], [0.5, 3.0]])
    v = np.random.default_rng(1).standard_normal((10, 2))
    y, x, x_end = dlsim_blocked(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((2, 0)), D, v, block=4)
    np.testing.assert_array_equal(y, v @ D.T)
    assert x.shape == (10, 0) and x_end.shape == (0,)


def test_no_inputs_is_the_free_response():
    A, _, C, _, x0 = _system("marginal", n=4, m=1, p=2, seed=3)
    v = np.zeros((45, 0))
    y, x, x_end = dlsim_blocked(A, np.zeros((4, 0)), C, np.zeros((2, 0)), v, x0, block=8)
    ref = np.array([np.linalg.matrix_power(A, k) @ x0 for k in range(46)])
    _close(x, ref[:45], np.abs(ref).max())
    _close(y, ref[:45] @ C.T, np.abs(ref).max() * np.abs(C).max())
    _close(x_end, ref[45], np.abs(ref).max())


def test_empty_input_returns_initial_state():
    A, B, C, D, x0 = _system("stable", n=3, m=1, p=1, seed=4)
    y, x, x_end = dlsim_blocked(A, B, C, D, np.zeros((0, 1)), x0)
    assert y.shape == (0, 1) and x.shape == (0, 3)
    np.testing.assert_array_equal(x_end, x0)


def test_lifted_matrices_definition():
    A, B, _, _, _ = _system("stable", n=2, m=1, p=1, seed=5)
    M = 4
    Phi, T, AM, Gamma = lifted_matrices(A, B, M)
    P = [np.linalg.matrix_power(A, j) for j in range(M + 1)]
    np.testing.assert_allclose(Phi, np.vstack(P[:M]), atol=1e-14)
    np.testing.assert_allclose(AM, P[M], atol=1e-14)
    np.testing.assert_allclose(Gamma, np.hstack([P[M - 1 - i] @ B for i in range(M)]), atol=1e-14)
    for j in range(M):
        for i in range(M):
            blk = T[2 * j : 2 * j + 2, i : i + 1]
            ref = P[j - 1 - i] @ B if i < j else np.zeros((2, 1))
            np.testing.assert_allclose(blk, ref, atol=1e-14)


def test_non_finite_input_is_refused_not_spread_into_its_block():
    """A NaN at sample 40 would corrupt samples 32-39 of the lifted block solve: refused instead."""
    import pytest

    from fdikit.errors import DataError
    from fdikit.lti import dlsim_blocked

    v = np.ones((64, 1))
    v[40] = np.nan
    with pytest.raises(DataError, match="v \\(the input sequence\\)"):
        dlsim_blocked(np.array([[0.5]]), np.array([[1.0]]), np.array([[1.0]]), np.array([[0.0]]), v)
