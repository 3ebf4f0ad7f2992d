"""Tests of fdikit.spc.excitation (Hallouzi 2008, §5.3, (5.39)–(5.44)) against numpy's full SVD."""

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.spc.excitation import LeastExcited, excitation_cost, least_excited

EPS = np.finfo(float).eps


def _orthonormal(rng, n, k):
    return np.linalg.qr(rng.standard_normal((n, k)))[0]


@pytest.fixture(scope="module")
def theta():
    """Θ = U diag(s) V^T, 12 × 36 (M·m = 12), with separated small singular values 1e-3, 1e-2, 5e-2."""
    rng = np.random.default_rng(5)
    s = np.r_[1e-3, 1e-2, 5e-2, np.linspace(0.5, 2.0, 9)]
    U, V = _orthonormal(rng, 12, 12), _orthonormal(rng, 36, 12)
    return U @ np.diag(s) @ V.T, s


def _bounds(T, s_sorted, i, tol):
    """Error bounds for triplet i (0 = smallest), derived, not tuned.

    * Θ^† from a backward-stable QR: ‖ΔΘ^†‖ ≲ c·size·eps·κ(Θ)·‖Θ^†‖ (c = 10).
    * Wedin: the singular vector of Θ^† for 1/s_i moves by ≤ ‖ΔΘ^†‖ / gap_i, gap_i = min_j |1/s_i − 1/s_j|;
      each earlier deflation adds at most the same error again, hence the factor (i + 1).
    * Stopping when a step is ≤ tol with contraction q = (s_i/s_{i+1})² leaves ≤ tol·q/(1 − q) ≤ tol.
    * numpy's own vectors are off by ≲ size·eps·σ_max / gap in σ.
    """
    size = max(T.shape)
    kappa = s_sorted[-1] / s_sorted[0]
    dP = 10 * size * EPS * kappa / s_sorted[0]
    inv = 1 / s_sorted
    gap_inv = np.min(np.abs(np.delete(inv, i) - inv[i]))
    gap = np.min(np.abs(np.delete(s_sorted, i) - s_sorted[i]))
    vec = (i + 1) * dP / gap_inv + tol + 10 * size * EPS * s_sorted[-1] / gap
    val = s_sorted[i] ** 2 * (i + 1) * dP + 10 * size * EPS * s_sorted[-1]  # |Δσ| = σ²|Δ(1/σ)|
    return vec, val


def test_matches_numpy_svd_up_to_sign(theta):
    T, s = theta
    r = least_excited(T, count=3)
    Un, sn, Vtn = np.linalg.svd(T, full_matrices=False)
    order = np.argsort(sn)
    assert isinstance(r, LeastExcited) and r.left.shape == (12, 3) and r.right.shape == (36, 3)
    for i in range(3):
        j = order[i]
        vec, val = _bounds(T, np.sort(sn), i, 1e-10)
        assert vec < 1e-6  # far below the O(1) error of a wrong vector: the check has teeth
        assert abs(r.sigma[i] - sn[j]) <= val
        assert abs(r.sigma[i] - s[i]) <= val + 10 * 36 * EPS * s[-1]  # the constructed value too
        sgn = np.sign(r.left[:, i] @ Un[:, j])
        assert np.abs(r.left[:, i] - sgn * Un[:, j]).max() <= vec
        assert np.abs(r.right[:, i] - sgn * Vtn[j]).max() <= vec
        # Θ v = σ w
        assert np.linalg.norm(T @ r.right[:, i] - r.sigma[i] * r.left[:, i]) <= vec * s[-1] + val
    assert np.all(np.diff(r.sigma) > 0)


def test_iterations_follow_the_contraction_rate(theta):
    T, s = theta
    start = np.random.default_rng(1).standard_normal(12)
    r = least_excited(T, count=3, tol=1e-10, start=start)
    Un = np.linalg.svd(T)[0][:, ::-1]  # ascending singular values
    c = Un.T @ start
    for i in range(3):
        # the error tan θ_k of w shrinks by q = (s_i/s_{i+1})² per iteration from tan θ_0 (the start's
        # components on the directions not yet deflated over its component on the target); a step ≤ tol is
        # reached once q^k tan θ_0 ≲ tol, plus one iteration to measure the step and one for the (1 + q) factor
        q = (s[i] / s[i + 1]) ** 2
        tan0 = np.linalg.norm(c[i + 1:]) / abs(c[i])
        assert 1 <= r.iterations[i] <= int(np.ceil(np.log(1e-10 / tan0) / np.log(q))) + 2
    assert least_excited(T, count=1, max_iter=1).iterations[0] == 1


def test_deflation_removes_the_least_excited_term(theta):
    """(5.40): Θ^† − v_1 w_1^T / σ_1 equals Σ_{i≥2} v_i w_i^T / s_i from the full SVD."""
    T, _ = theta
    r = least_excited(T, count=1)
    Un, sn, Vtn = np.linalg.svd(T, full_matrices=False)
    deflated = np.linalg.pinv(T) - np.outer(r.right[:, 0], r.left[:, 0]) / r.sigma[0]
    expected = Vtn[:-1].T @ np.diag(1 / sn[:-1]) @ Un[:, :-1].T
    vec, val = _bounds(T, np.sort(sn), 0, 1e-10)
    # the removed term has norm 1/σ_1; its error is ≤ (2·vec + val/σ_1)/σ_1 (two vectors, one value)
    assert np.abs(deflated - expected).max() <= (2 * vec + val / sn[-1]) / sn[-1]
    # and the iteration on the deflated matrix finds the second triplet: count=2 does exactly that
    r2 = least_excited(T, count=2)
    assert abs(r2.sigma[1] - sn[-2]) <= _bounds(T, np.sort(sn), 1, 1e-10)[1]
    assert abs(r2.left[:, 0] @ r2.left[:, 1]) <= 2 * vec


def test_sign_rule_and_start(theta):
    T, _ = theta
    r = least_excited(T, count=2)
    for i in range(2):
        w = r.left[:, i]
        assert w[np.argmax(np.abs(w))] > 0
    again = least_excited(T, count=2, start=-np.ones(12))
    assert np.allclose(again.left, r.left, rtol=0, atol=1e-8)  # same directions, same signs
    with pytest.raises(ParameterError, match="nonzero"):
        least_excited(T, start=np.zeros(12))


def test_rank_deficient_theta_gives_the_smallest_nonzero(theta):
    T, s = theta
    U, sn, Vt = np.linalg.svd(T, full_matrices=False)
    sn2 = sn.copy()
    sn2[-1] = 0.0  # rank 11: the pseudo-inverse path
    r = least_excited(U @ np.diag(sn2) @ Vt, count=1)
    assert abs(r.sigma[0] - sn[-2]) <= 1e-8 * sn[-2]


def test_argument_errors(theta):
    T, _ = theta
    with pytest.raises(DataError, match="wide"):
        least_excited(T.T)
    with pytest.raises(ParameterError, match="at most"):
        least_excited(T, count=13)


def _blocking(M, Nc, m):
    """E: future input u_{t+i} = u_f block min(i, Nc − 1) (inputs held after the control horizon)."""
    E = np.zeros((M * m, Nc * m))
    for i in range(M):
        b = min(i, Nc - 1)
        E[i * m:(i + 1) * m, b * m:(b + 1) * m] = np.eye(m)
    return E


@pytest.fixture(scope="module")
def qp():
    rng = np.random.default_rng(9)
    M, Nc, m = 6, 3, 2
    E = _blocking(M, Nc, m)
    G = rng.standard_normal((Nc * m, Nc * m))
    W = _orthonormal(rng, M * m, 2)
    return G @ G.T, rng.standard_normal(Nc * m), W, E


@pytest.mark.parametrize("mode", ["full", "truncate"])
def test_cost_terms_are_5_43_and_5_44(qp, mode):
    H, c, W, E = qp
    rho, tau = 3.0, 0.7
    n = E.shape[1]
    H_exc, c_exc = excitation_cost(H, c, W, rho, tau, E, mode=mode)
    signs = np.array([np.sign(W[np.argmax(np.abs(W[:, i])), i]) for i in range(2)])
    Ws = W * signs
    if mode == "full":
        I = np.vstack([E, E])
        P = rho * np.r_[Ws[:, 0], Ws[:, 1]]
    else:
        I = np.vstack([np.eye(n), np.eye(n)])
        P = rho * np.r_[Ws[:n, 0], Ws[:n, 1]]
    scale = 10 * EPS * (np.linalg.norm(H) + tau * np.linalg.norm(I) ** 2 + np.linalg.norm(c) + tau * rho * 4)
    assert np.abs((H_exc - H) - tau * I.T @ I).max() <= scale
    assert np.abs((c_exc - c) + 2 * tau * I.T @ P).max() <= scale
    # the pure excitation term alone (H = 0, c = 0): its minimiser −(2 H_exc)^{-1} c_exc is lstsq(I, P)
    H0, c0 = excitation_cost(np.zeros_like(H), np.zeros(n), W, rho, tau, E, mode=mode)
    u_star = -np.linalg.solve(H0 + H0.T, c0)
    ref = np.linalg.lstsq(I, P, rcond=None)[0]
    assert np.abs(u_star - ref).max() <= 100 * EPS * rho * np.linalg.cond(I) ** 2
    if mode == "full":
        # E u* is the projection of ρ·mean(w) on range(E): the residual is orthogonal to range(E)
        resid = rho * Ws.mean(axis=1) - E @ u_star
        assert np.abs(E.T @ resid).max() <= 100 * EPS * rho * np.linalg.cond(I) ** 2


def test_pure_excitation_reaches_rho_w_without_blocking():
    rng = np.random.default_rng(2)
    w = _orthonormal(rng, 8, 1)
    E = np.eye(8)  # N_c = M: the printed (5.41) with identity blocks
    H0, c0 = excitation_cost(np.zeros((8, 8)), np.zeros(8), w, 2.5, 1.0, E)
    u_star = -np.linalg.solve(H0 + H0.T, c0)
    w_eff = w[:, 0] * np.sign(w[np.argmax(np.abs(w[:, 0])), 0])
    assert np.abs(u_star - 2.5 * w_eff).max() <= 100 * EPS * 2.5


def test_sign_is_deterministic(qp):
    H, c, W, E = qp
    a = excitation_cost(H, c, W, 1.0, 1.0, E)
    b = excitation_cost(H, c, -W, 1.0, 1.0, E)
    assert np.array_equal(a[1], b[1]) and np.array_equal(a[0], b[0])
    # with previous: w^T E previous ≥ 0 for the w actually used
    w = W[:, :1]
    for previous in (E.T @ w[:, 0], -E.T @ w[:, 0]):
        _, cp = excitation_cost(H, c, w, 1.0, 1.0, E, previous=previous)
        _, cm = excitation_cost(H, c, -w, 1.0, 1.0, E, previous=previous)
        assert np.array_equal(cp, cm)
        used = -(cp - c) / 2.0  # = E^T w_used (τ = ρ = 1, one direction)
        assert used @ previous >= 0.0


def test_cost_argument_errors(qp):
    H, c, W, E = qp
    with pytest.raises(ParameterError, match="mode"):
        excitation_cost(H, c, W, 1.0, 1.0, E, mode="half")
    with pytest.raises(ParameterError, match="left"):
        excitation_cost(H, c, W[:5], 1.0, 1.0, E)
    with pytest.raises(ParameterError):
        excitation_cost(H, c, W, -1.0, 1.0, E)
    with pytest.raises(ParameterError, match="truncate"):
        excitation_cost(np.eye(8), np.zeros(8), np.ones(4), 1.0, 1.0, np.ones((4, 8)), mode="truncate")
