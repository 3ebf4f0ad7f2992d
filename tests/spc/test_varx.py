"""Tests for fdikit.spc.varx: VARX fit (6.10)–(6.12) and multi-step matrices (6.14)–(6.16)."""

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.spc.varx import VarxPredictor, varx_data, varx_fit

EPS = np.finfo(float).eps


def _innovation_system(rng, n, m, l, rho):
    """Random (A, B, C, K) with Φ = A − KC of spectral radius ``rho`` (diagonalisable, random basis)."""
    eig = rho * np.exp(1j * rng.uniform(0, np.pi, n // 2))
    blocks = [np.array([[e.real, -e.imag], [e.imag, e.real]]) for e in eig]
    if n % 2:
        blocks.append(np.array([[rho]]))
    D = np.zeros((n, n))
    i = 0
    for b in blocks:
        D[i : i + len(b), i : i + len(b)] = b
        i += len(b)
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    phi = S @ D @ np.linalg.inv(S)
    B = rng.standard_normal((n, m))
    C = rng.standard_normal((l, n))
    K = 0.3 * rng.standard_normal((n, l))
    return phi + K @ C, B, C, K, phi


def _xi0(phi, B, C, K, p):
    """True Ξ_0 = [CΦ^{p−1}[B K] … C[B K]] (6.8) and the window map X (x̂_t = X w_p)."""
    BK = np.hstack([B, K])
    X = np.hstack([np.linalg.matrix_power(phi, p - 1 - i) @ BK for i in range(p)])
    return C @ X, X


def _independent_multistep(A, B, C, X, rows):
    """Kalman predictor with future innovations zero: x̂_{t+1} = A x̂_t + B u_t, x̂_t = X w_p."""
    gamma = np.vstack([C @ np.linalg.matrix_power(A, i) @ X for i in range(1, rows + 1)])
    m, l = B.shape[1], C.shape[0]
    lam = np.zeros((rows * l, rows * m))
    for r in range(rows):  # ŷ_{t+1+r} = C A^{r+1} x̂_t + Σ_c C A^{r−c} B u_{t+c}
        for c in range(r + 1):
            lam[r * l : (r + 1) * l, c * m : (c + 1) * m] = C @ np.linalg.matrix_power(A, r - c) @ B
    return gamma, lam


@pytest.mark.parametrize("full", [True, False])
def test_multistep_matches_kalman_predictor(full):
    rng = np.random.default_rng(3)
    n, m, l, p, f = 5, 2, 2, 40, 6
    A, B, C, K, phi = _innovation_system(rng, n, m, l, 0.5)
    xi0, X = _xi0(phi, B, C, K, p)
    pred = VarxPredictor(xi0, p, m, l)
    cb, ck = pred.markov()
    for j in range(p):
        cpj = C @ np.linalg.matrix_power(phi, j)
        np.testing.assert_allclose(cb[j], cpj @ B, rtol=0, atol=1e-14 * (1 + np.abs(cpj @ B).max()))
        np.testing.assert_allclose(ck[j], cpj @ K, rtol=0, atol=1e-14 * (1 + np.abs(cpj @ K).max()))
    gamma, lam = pred.multistep(f, full=full)
    rows = f if full else f - 1
    assert gamma.shape == (rows * l, p * (m + l)) and lam.shape == (rows * l, rows * m)
    g_ref, l_ref = _independent_multistep(A, B, C, X, rows)
    # Truncation bound: exactly CA^iX = CΦ^iX + Σ_{j<i} CΦ^{i−j−1}K·CA^jX, while (6.14) drops from CΦ^iX
    # the i leading blocks T_i = [CΦ^{p−1+i}[BK] … CΦ^p[BK]], so e_i = ‖Γ_i − CA^iX‖ obeys
    # e_i ≤ ‖T_i‖ + Σ_j ‖CΦ^{i−j−1}K‖ e_j (e_0 = 0); round-off adds ~ eps·‖Γ‖ per operation.
    BK = np.hstack([B, K])
    e = [0.0]
    for i in range(1, rows + 1):
        t_i = np.linalg.norm(np.hstack([C @ np.linalg.matrix_power(phi, p - 1 + i - q) @ BK for q in range(i)]), 2)
        e.append(t_i + sum(np.linalg.norm(ck[i - j - 1], 2) * e[j] for j in range(i)))
    for i in range(1, rows + 1):
        blk = slice((i - 1) * l, i * l)
        tol = e[i] + 1e3 * EPS * np.linalg.norm(g_ref[blk], 2)
        assert np.linalg.norm(gamma[blk] - g_ref[blk], 2) <= tol
    assert e[rows] < 1e-8  # the truncation really is small here (0.5^40 ≈ 1e-12 times gains)
    # Λ: CA^{i−1}B = CΦ^{i−1}B + Σ_{j=1}^{i−1} CΦ^{i−j−1}K·CA^{j−1}B holds exactly (i ≤ p): round-off only.
    np.testing.assert_allclose(lam, l_ref, rtol=0, atol=1e3 * EPS * np.abs(l_ref).max())


def _nilpotent_system(rng, p, m, l):
    """n = p·l states, Φ nilpotent (l Jordan chains of length p, Φ^p = 0): noise-free Z has full row rank."""
    n = p * l
    N = np.zeros((n, n))
    for c in range(l):
        for i in range(1, p):
            N[c * p + i, c * p + i - 1] = 1.0
    S = np.eye(n) + 0.2 * rng.standard_normal((n, n))
    phi = S @ N @ np.linalg.inv(S)
    B = rng.standard_normal((n, m))
    C = rng.standard_normal((l, n))
    K = 0.2 * rng.standard_normal((n, l))
    return phi + K @ C, B, C, K, phi


def test_varx_fit_noise_free_recovers_markov_and_multistep():
    rng = np.random.default_rng(7)
    p, m, l = 3, 2, 2
    A, B, C, K, phi = _nilpotent_system(rng, p, m, l)
    assert np.max(np.abs(np.linalg.eigvals(A))) < 1.5  # data of 400 samples stay well within range
    N = 400
    u = rng.standard_normal((N, m))
    x = np.zeros(A.shape[0])
    y = np.zeros((N, l))
    for k in range(N):  # innovation form (6.3)-(6.4) with e_k = 0: y_k = Ξ_0 w_p exactly since Φ^p = 0
        y[k] = C @ x
        x = A @ x + B @ u[k]
    pred = varx_fit(u, y, p)
    xi0, X = _xi0(phi, B, C, K, p)
    Z, _ = varx_data(u, y, p)
    # LS round-off: relative error ≲ cond(Z)·eps (noise-free, zero residual); factor 100 for accumulation.
    tol = 100 * np.linalg.cond(Z) * EPS
    assert np.linalg.norm(pred.Xi0 - xi0) <= tol * np.linalg.norm(xi0)
    for full in (True, False):
        gamma, lam = pred.multistep(p, full=full)
        rows = p if full else p - 1
        g_ref, l_ref = _independent_multistep(A, B, C, X, rows)  # Φ^p = 0: no truncation at all
        np.testing.assert_allclose(gamma, g_ref, rtol=0, atol=100 * tol * np.abs(g_ref).max())
        np.testing.assert_allclose(lam, l_ref, rtol=0, atol=100 * tol * np.abs(l_ref).max())
    # the fitted predictor reproduces the data one step ahead
    t = 250
    assert np.allclose(pred.Xi0 @ pred.past(u[:t], y[:t]), y[t], rtol=0, atol=100 * tol * np.abs(y).max())


def test_varx_fit_columns_window_and_errors():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 1))
    y = np.zeros((200, 1))
    for k in range(1, 200):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.1 * rng.standard_normal()
    Z, Y = varx_data(u, y, 2, columns=50)
    assert Z.shape == (4, 50) and Y.shape == (1, 50)
    np.testing.assert_array_equal(Z[:, -1], [u[197, 0], y[197, 0], u[198, 0], y[198, 0]])
    np.testing.assert_array_equal(Y[0, -1], y[199, 0])
    ref = np.linalg.lstsq(Z.T, Y.T, rcond=None)[0].T  # independent LS solution of (6.10)
    np.testing.assert_allclose(varx_fit(u, y, 2, columns=50).Xi0, ref, rtol=1e-10, atol=1e-12)
    with pytest.raises(DataError):
        varx_fit(u, y, 2, columns=199)
    with pytest.raises(DataError):
        varx_fit(np.zeros((200, 1)), y, 2)  # no excitation: rank deficient
    pred = varx_fit(u, y, 2)
    with pytest.raises(ParameterError):
        pred.multistep(3)
    with pytest.raises(ParameterError):
        pred.multistep(1, full=False)
    with pytest.raises(DataError):
        pred.past(u[:1], y[:1])


def _reference_multistep(xi0, p, m, l, rows):
    """(6.14)–(6.16) written out block by block, as printed: Γ_i, Λ's blocks, then the Toeplitz fill."""
    d = m + l
    blocks = [xi0[:, (p - 1 - j) * d : (p - j) * d] for j in range(p)]  # CΦ^j[B K], j = 0 first
    cb = [b[:, :m] for b in blocks]
    ck = [b[:, m:] for b in blocks]
    gam = [xi0]
    for i in range(1, rows + 1):
        g = np.zeros_like(xi0)
        if i < p:
            g[:, i * d :] = xi0[:, : (p - i) * d]  # (6.16)
        for j in range(i):
            g = g + ck[i - j - 1] @ gam[j]  # (6.14)
        gam.append(g)
    lam = [np.zeros((l, m))]
    for i in range(1, rows + 1):
        b = cb[i - 1].copy()
        for j in range(1, i):
            b = b + ck[i - j - 1] @ lam[j]  # (6.15)
        lam.append(b)
    lam_big = np.zeros((rows * l, rows * m))
    for r in range(rows):
        for c in range(r + 1):
            lam_big[r * l : (r + 1) * l, c * m : (c + 1) * m] = lam[r - c + 1]
    return np.vstack(gam[1:]), lam_big


@pytest.mark.parametrize(("p", "m", "l", "f", "full"), [(20, 5, 7, 20, True), (20, 5, 7, 12, False), (6, 1, 2, 1, True),
                                                     (5, 3, 1, 5, False), (4, 2, 3, 3, True)])
def test_multistep_equals_the_printed_recursion(p, m, l, f, full):
    rng = np.random.default_rng(p * 100 + m * 10 + l)
    xi0 = 0.3 * rng.standard_normal((l, p * (m + l)))
    rows = f if full else f - 1
    gamma, lam = VarxPredictor(xi0, p, m, l).multistep(f, full=full)
    g_ref, l_ref = _reference_multistep(xi0, p, m, l, rows)
    g_abs, l_abs = _reference_multistep(np.abs(xi0), p, m, l, rows)
    assert gamma.shape == g_ref.shape and lam.shape == l_ref.shape
    assert gamma.flags.c_contiguous and lam.flags.c_contiguous
    # Both are sums of the same products in different orders (forward substitution vs the printed loop): the
    # difference is within n·eps times the recursion run on |Ξ_0| (a bound on every partial sum), n the
    # number of terms per entry ≤ (rows + 1)·l.
    n = (rows + 1) * l
    assert np.all(np.abs(gamma - g_ref) <= 2 * n * EPS * g_abs)
    assert np.all(np.abs(lam - l_ref) <= 2 * n * EPS * l_abs)
    assert np.array_equal(lam == 0, l_ref == 0)  # the zero blocks above the diagonal stay exactly zero
