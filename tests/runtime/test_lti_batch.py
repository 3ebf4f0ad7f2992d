"""The compiled batch LTI response against scipy.signal.dlsim and the lifted solver."""

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from fdikit.errors import DataError
from fdikit.runtime.lti_batch import CHUNK, diagonal_blocks, lsim, lsim_columns


def _system(rng, sizes, m, q):
    blocks = []
    for k in sizes:
        a = rng.standard_normal((k, k))
        blocks.append(a * 0.95 / max(abs(np.linalg.eigvals(a))))
    A = scipy.linalg.block_diag(*blocks)
    n = A.shape[0]
    return A, rng.standard_normal((n, m)), rng.standard_normal((q, n)), rng.standard_normal((q, m))


@pytest.mark.parametrize("sizes, N", [((12,), 3 * CHUNK + 7), ((5, 3, 4), 1000), ((1,), 1), ((2, 2), CHUNK)])
def test_equals_dlsim(sizes, N):
    rng = np.random.default_rng(len(sizes) + N)
    A, B, C, D = _system(rng, sizes, 4, 3)
    v = rng.standard_normal((N, 4))
    x0 = rng.standard_normal(A.shape[0])
    y, X, x_end = lsim(A, B, C, D, v, x0, states=True)
    _, yr, xr = scipy.signal.dlsim((A, B, C, D, 1.0), v, x0=x0)
    scale = np.abs(yr).max()
    np.testing.assert_allclose(y, yr, rtol=1e-12, atol=1e-12 * scale)
    np.testing.assert_allclose(X, xr, rtol=1e-12, atol=1e-12 * np.abs(xr).max())
    np.testing.assert_allclose(x_end, A @ xr[-1] + B @ v[-1], rtol=1e-12, atol=1e-12 * np.abs(xr).max())
    assert lsim(A, B, C, D, v, x0)[1] is None


def test_block_partition():
    rng = np.random.default_rng(1)
    A = _system(rng, (3, 1, 2), 1, 1)[0]
    assert diagonal_blocks(A).tolist() == [0, 3, 4, 6]
    A[0, 5] = 0.1  # couples the first and last block: one block
    assert diagonal_blocks(A).tolist() == [0, 6]
    assert diagonal_blocks(np.zeros((2, 2))).tolist() == [0, 1, 2]


def test_columns_read_in_place_and_stop_at_bad_sample():
    rng = np.random.default_rng(2)
    A, B, C, D = _system(rng, (3,), 3, 2)
    U, Y = rng.standard_normal((50, 2)), rng.standard_normal((50, 3))
    off = rng.standard_normal(3)
    v = np.hstack([U[:, [1]], Y[:, [2, 0]]]) - off
    valid = np.ones(50, bool)
    y, _, _, bad = lsim_columns(A, B, C, D, U, [1], Y, [2, 0], off, valid, np.zeros(3))
    assert bad == 50
    np.testing.assert_allclose(y, lsim(A, B, C, D, v)[0], rtol=1e-13, atol=1e-13)
    valid[30] = False
    assert lsim_columns(A, B, C, D, U, [1], Y, [2, 0], off, valid, np.zeros(3))[3] == 30
    Y[20, 0] = np.inf
    assert lsim_columns(A, B, C, D, U, [1], Y, [2, 0], off, valid, np.zeros(3))[3] == 20


def test_static_and_inputless_systems():
    y = lsim(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[1.0, 2.0]], np.ones((3, 2)))[0]
    assert y.ravel().tolist() == [3.0, 3.0, 3.0]
    y = lsim([[0.5]], np.zeros((1, 0)), [[1.0]], np.zeros((1, 0)), np.zeros((3, 0)), [4.0])[0]
    assert y.ravel().tolist() == [4.0, 2.0, 1.0]


def test_bad_input():
    with pytest.raises(DataError, match="not finite at sample 1"):
        lsim([[0.5]], [[1.0]], [[1.0]], [[0.0]], [[1.0], [np.nan]])
    with pytest.raises(DataError, match=r"need \(N, 1\)"):
        lsim([[0.5]], [[1.0]], [[1.0]], [[0.0]], np.ones((3, 2)))
