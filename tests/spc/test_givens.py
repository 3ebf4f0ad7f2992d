"""Tests for fdikit.spc.givens: the recursive Givens update (6.17), App. C, against weighted batch LS/QR."""

import numpy as np
import pytest
from scipy.linalg import qr

from fdikit.errors import DataError, ParameterError
from fdikit.spc.givens import RecursiveVarx
from fdikit.spc.varx import varx_data


def _data(rng, N, m, l):
    """Output of a random stable ARX-like system driven by white input plus white noise (full-rank Z)."""
    u = rng.standard_normal((N, m))
    y = np.zeros((N, l))
    a = 0.4 * rng.standard_normal((l, l)) / np.sqrt(l)
    b = rng.standard_normal((l, m))
    for k in range(1, N):
        y[k] = a @ y[k - 1] + b @ u[k - 1] + 0.1 * rng.standard_normal(l)
    return u, y


@pytest.mark.parametrize("lam", [0.995, 1.0])
def test_recursive_equals_weighted_batch(lam):
    rng = np.random.default_rng(11)
    p, m, l, N0, N = 4, 2, 2, 60, 600
    u, y = _data(rng, N, m, l)
    rv = RecursiveVarx(p, m, l, forgetting=lam)
    rv.initialize(u[:N0], y[:N0])
    for t in range(N0, N):
        rv.update(np.hstack([u[t - p : t], y[t - p : t]]).ravel(), y[t])
    Z, Y = varx_data(u, y, p)  # all N − p columns; column c holds y_{p+c}
    n_upd = N - N0
    # weights on squared residuals: initial block discounted by λ^{n_upd}, update i (0-based) by λ^{n_upd−1−i}
    w = np.r_[np.full(N0 - p, lam**n_upd), lam ** np.arange(n_upd - 1, -1, -1)]
    sw = np.sqrt(w)
    ref = np.linalg.lstsq((Z * sw).T, (Y * sw).T, rcond=None)[0].T
    xi0 = rv.predictor.Xi0
    # relative error ≲ cond(√W Zᵀ)·eps·(number of rotations applied ≈ n_upd); measured-free bound 1e-10
    cond = np.linalg.cond((Z * sw).T)
    assert cond * 1e-16 * n_upd < 1e-10  # the bound below is meaningful for this data
    assert np.linalg.norm(xi0 - ref) <= 1e-10 * np.linalg.norm(ref)
    R11, R21 = rv.R11, rv.R21
    assert np.all(np.triu(R11, 1) == 0.0)  # stays exactly lower triangular
    gram = (Z * w) @ Z.T
    cross = (Y * w) @ Z.T
    np.testing.assert_allclose(R11 @ R11.T, gram, rtol=0, atol=1e-12 * np.abs(gram).max())
    np.testing.assert_allclose(R21 @ R11.T, cross, rtol=0, atol=1e-12 * np.abs(gram).max())
    # batch QR of the λ-weighted data matrix: same triangle up to column signs
    up = qr(np.vstack([Z, Y]).T * sw[:, None], mode="r")[0]
    low = up[: p * (m + l)].T
    sgn = np.sign(np.diag(low[: p * (m + l)])) * np.sign(np.diag(R11))
    np.testing.assert_allclose(np.vstack([R11, R21]) * sgn, low, rtol=0, atol=1e-11 * np.abs(low).max())
    assert rv.samples == N - p


def test_tracks_parameter_jump_only_with_forgetting():
    rng = np.random.default_rng(5)
    N, jump = 2000, 1000
    u = rng.standard_normal((N, 1))
    y = np.zeros((N, 1))
    for k in range(1, N):
        a = 0.5 if k < jump else -0.3
        y[k] = a * y[k - 1] + u[k - 1] + 0.01 * rng.standard_normal()
    est = {}
    for lam in (0.98, 1.0):
        rv = RecursiveVarx(1, 1, 1, forgetting=lam)
        rv.initialize(u[:50], y[:50])
        for t in range(50, N):
            rv.update([u[t - 1, 0], y[t - 1, 0]], y[t])
        est[lam] = rv.predictor.Xi0[0]
    # λ = 0.98: effective window 1/(1−λ) = 50 samples, old data weight 0.98^1000 ≈ 2e-9; LS std of the
    # y-coefficient ≈ σ_e/(√50·std(y)) ≈ 0.01/(7·1) ≈ 1.5e-3, so 0.02 is > 10 standard deviations.
    assert abs(est[0.98][1] - (-0.3)) < 0.02 and abs(est[0.98][0] - 1.0) < 0.02
    # λ = 1 weighs both regimes about equally: its estimate sits far from the new value
    assert abs(est[1.0][1] - (-0.3)) > 0.2


def test_errors():
    with pytest.raises(ParameterError):
        RecursiveVarx(2, 1, 1, forgetting=1.5)
    rv = RecursiveVarx(2, 1, 1)
    with pytest.raises(DataError):
        rv.update(np.zeros(4), [0.0])
    with pytest.raises(DataError):
        rv.initialize(np.ones((4, 1)), np.ones((4, 1)))  # too few columns
    rng = np.random.default_rng(0)
    rv.initialize(rng.standard_normal((50, 1)), rng.standard_normal((50, 1)))
    with pytest.raises((DataError, ParameterError)):
        rv.update(np.zeros(3), [0.0])
    with pytest.raises(DataError):
        rv.update(np.full(4, np.nan), [0.0])
