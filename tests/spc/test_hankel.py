"""Tests of fdikit.spc.hankel (Hallouzi 2008, §5.2.1 (5.5), §5.3 Def. 5.1)."""

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.spc.hankel import block_hankel, excitation_rank, input_rcond


def _brute(s, rows, columns, start):
    d = s.shape[1]
    H = np.empty((rows * d, columns))
    for i in range(rows):
        for k in range(columns):
            for c in range(d):
                H[i * d + c, k] = s[start + i + k, c]
    return H


@pytest.mark.parametrize(("rows", "columns", "start"), [(1, None, 0), (3, None, 0), (4, 10, 2), (5, 7, 11)])
def test_block_layout_matches_a_loop(rows, columns, start):
    s = np.random.default_rng(0).standard_normal((25, 3))
    H = block_hankel(s, rows, columns, start)
    cols = 25 - start - rows + 1 if columns is None else columns
    assert np.array_equal(H, _brute(s, rows, cols, start))


def test_vector_is_one_channel():
    s = np.arange(6.0)
    assert np.array_equal(block_hankel(s, 2), block_hankel(s[:, None], 2))


def test_too_short_or_bad_arguments():
    s = np.zeros((5, 2))
    with pytest.raises(DataError, match="samples"):
        block_hankel(s, 6)
    with pytest.raises(DataError, match="more samples"):
        block_hankel(s, 2, 5)
    with pytest.raises(ParameterError):
        block_hankel(s, 0)
    with pytest.raises(DataError):
        block_hankel([[np.nan, 1.0]], 1)


def test_white_noise_is_exciting_of_every_order():
    u = np.random.default_rng(3).standard_normal((300, 2))
    for order in (1, 4, 10):
        assert excitation_rank(u, order) == order * 2
    # 8 × 297 Hankel of white noise: Marchenko–Pastur puts σ_min/σ_max near (1 − √(8/297))/(1 + √(8/297)) ≈ 0.72
    assert input_rcond(u, 4) > 0.5


def test_constant_input_is_exciting_of_order_one():
    u = np.tile([1.0, -2.0], (50, 1))
    # every column of the Hankel matrix is the same vector: rank 1 for every order (= 1·m for m = 1)
    assert excitation_rank(u, 1) == 1
    assert excitation_rank(u, 5) == 1
    assert excitation_rank(u[:, :1], 1) == 1  # m = 1: PE of order 1, not 2
    assert excitation_rank(u[:, :1], 2) == 1
    # exactly singular: the computed σ_min is within the SVD backward error, a few eps · σ_max · size
    assert input_rcond(u[:, :1], 2) <= 10 * 49 * np.finfo(float).eps


def test_one_sinusoid_is_exciting_of_order_two():
    # sin(ωk) satisfies s_{k+2} = 2cos(ω) s_{k+1} − s_k: rank 2 for every order ≥ 2
    u = np.sin(0.3 * np.arange(100))
    assert excitation_rank(u, 2) == 2
    assert excitation_rank(u, 6) == 2
    # Gram of [s_k; s_{k+1}] ≈ (N/2)[[1, cos ω], [cos ω, 1]]: σ_min/σ_max → tan(ω/2) = 0.151; the finite-sample
    # terms are O(1/(N sin ω)) ≈ 3 %
    assert input_rcond(u, 2) == pytest.approx(np.tan(0.15), rel=0.1)


def test_input_rcond_against_numpy():
    u = np.random.default_rng(5).standard_normal((40, 2))
    sv = np.linalg.svd(block_hankel(u, 3), compute_uv=False)
    assert input_rcond(u, 3) == pytest.approx(sv[-1] / sv[0], rel=1e-12)
    assert input_rcond(np.zeros((10, 1)), 2) == 0.0


def test_too_few_columns_for_full_rank():
    with pytest.raises(DataError, match="full row rank"):
        excitation_rank(np.ones((6, 2)), 3)
