"""Tests of fdikit.spc.predictor against a known discrete LTI system (Hallouzi 2008, §5.2.1)."""

import numpy as np
import pytest

from fdikit.errors import DataError
from fdikit.spc.hankel import block_hankel
from fdikit.spc.predictor import SubspacePredictor, subspace_predictor

EPS = np.finfo(float).eps


def _system(rng, n=4, m=2, l=2):
    """A random stable (spectral radius 0.8) n-state system with a direct feedthrough."""
    A = rng.standard_normal((n, n))
    A *= 0.8 / max(abs(np.linalg.eigvals(A)))
    return A, rng.standard_normal((n, m)), rng.standard_normal((l, n)), rng.standard_normal((l, m))


def _simulate(A, B, C, D, u, x0):
    x, y = x0.copy(), np.empty((u.shape[0], C.shape[0]))
    for k, uk in enumerate(u):
        y[k] = C @ x + D @ uk
        x = A @ x + B @ uk
    return y


def _toeplitz(A, B, C, D, M):
    """T_M of (5.8): block (i, k) = D for i = k, C A^{i−k−1} B below the diagonal."""
    l, m = D.shape
    markov = [D] + [C @ np.linalg.matrix_power(A, i) @ B for i in range(M - 1)]
    T = np.zeros((M * l, M * m))
    for i in range(M):
        for k in range(i + 1):
            T[i * l:(i + 1) * l, k * m:(k + 1) * m] = markov[i - k]
    return T, np.array(markov)


def _tolerance(u, y, M, j=None):
    """Forward-error bound of a backward-stable least-squares solve: ~ (size) · eps · κ, with κ the condition
    of the data rows [V_p; U_f] restricted to their numerical rank (n + 2Mm), times |[Y_f]|/σ_min as scale."""
    N = u.shape[0]
    fit = N - 2 * M + 1
    j = fit if j is None else j
    s = fit - j
    X = np.vstack([block_hankel(y, M, j, s), block_hankel(u, M, j, s), block_hankel(u, M, j, s + M)])
    sv = np.linalg.svd(X, compute_uv=False)
    r = int(np.sum(sv > sv[0] * max(X.shape) * EPS))
    return max(X.shape) * EPS * sv[0] / sv[r - 1], r


@pytest.fixture(scope="module")
def plant():
    rng = np.random.default_rng(17)
    A, B, C, D = _system(rng)
    u = rng.standard_normal((260, 2))
    y = _simulate(A, B, C, D, u, rng.standard_normal(4))
    return A, B, C, D, u, y


def test_lf_is_the_markov_toeplitz(plant):
    A, B, C, D, u, y = plant
    M = 8  # M ≥ 2n
    ident = 200
    P = subspace_predictor(u[:ident], y[:ident], M)
    T, markov = _toeplitz(A, B, C, D, M)
    rel, rank = _tolerance(u[:ident], y[:ident], M)
    # noise-free data of an order-4 system: [V_p; U_f] has rank n + 2Mm = 4 + 32 (PE of order 2M + n)
    assert rank == 4 + 2 * M * 2
    tol = 10 * rel * np.linalg.norm(T)
    assert tol < 1e-8 * np.linalg.norm(T)  # the data are well conditioned: a sharp check
    assert np.abs(P.Lf - T).max() <= tol
    assert np.abs(P.markov() - markov).max() <= tol
    assert P.Lp.shape == (M * 2, M * 4) and P.Lf.shape == (M * 2, M * 2)
    assert P.theta.shape == (M * 2, M * 4 + M * 2)


def test_prediction_equals_simulated_future(plant):
    A, B, C, D, u, y = plant
    M, ident = 8, 200
    P = subspace_predictor(u[:ident], y[:ident], M)
    rel, _ = _tolerance(u[:ident], y[:ident], M)
    for t in (ident + 5, ident + 30, 240):  # trajectories outside the identification window
        v_p = P.past(u[: t + 1], y[: t + 1])
        expected = y[t + 1: t + M + 1].ravel()
        got = P.predict(v_p, u[t + 1: t + M + 1].ravel())
        # the error is L_err v: bounded by the relative error of L times |[v_p; u_f]|, times the |L| scale
        scale = np.linalg.norm(np.hstack([P.Lp, P.Lf]), 2) * np.linalg.norm(np.r_[v_p, u[t + 1: t + M + 1].ravel()])
        assert np.abs(got - expected).max() <= 10 * rel * scale


def test_past_vector_layout(plant):
    *_, u, y = plant
    P = subspace_predictor(u[:200], y[:200], 3)
    v = P.past(u[:50], y[:50])
    assert np.array_equal(v, np.r_[y[47], y[48], y[49], u[47], u[48], u[49]])


def test_receding_window_uses_the_last_columns(plant):
    A, B, C, D, u, y = plant
    M, j = 4, 80
    N = 200
    full = subspace_predictor(u[:N], y[:N], M, columns=j)
    tail = subspace_predictor(u[N - (2 * M + j - 1): N], y[N - (2 * M + j - 1): N], M)
    assert np.array_equal(full.Lp, tail.Lp) and np.array_equal(full.Lf, tail.Lf)
    assert np.array_equal(full.R21, tail.R21) and np.array_equal(full.R22, tail.R22)
    # samples before the window do not matter: corrupt them, same predictor
    u2, y2 = u[:N].copy(), y[:N].copy()
    u2[:50] = 0.0
    y2[:50] = 1e3
    again = subspace_predictor(u2, y2, M, columns=j)
    assert np.array_equal(again.Lf, full.Lf)
    # and the window-only predictor is still exact
    T, _ = _toeplitz(A, B, C, D, M)
    rel, _ = _tolerance(u[:N], y[:N], M, j)
    assert np.abs(full.Lf - T).max() <= 10 * rel * np.linalg.norm(T)


def test_theta_is_the_input_rows_of_the_rq_factor(plant):
    """R R^T of [V_p; U_f] equals the data Gram matrix: the U_f rows of R carry the U_f Gram block."""
    *_, u, y = plant
    M = 3
    P = subspace_predictor(u[:120], y[:120], M)
    Uf = block_hankel(u[:120], M, 120 - 2 * M + 1, M)
    G = P.theta @ P.theta.T
    assert np.allclose(G, Uf @ Uf.T, rtol=0, atol=100 * EPS * np.linalg.norm(Uf) ** 2)


def test_errors(plant):
    *_, u, y = plant
    with pytest.raises(DataError, match="samples"):
        subspace_predictor(u[:20], y[:20], 4)
    with pytest.raises(DataError, match="same samples"):
        subspace_predictor(u[:100], y[:90], 2)
    with pytest.raises(DataError, match="columns"):
        subspace_predictor(u[:100], y[:100], 2, columns=500)
    P = subspace_predictor(u[:100], y[:100], 2)
    with pytest.raises(DataError, match="rows"):
        P.past(u[:1], y[:1])
    assert isinstance(P, SubspacePredictor)
