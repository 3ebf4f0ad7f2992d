"""Co-outer–co-inner factorisation (Riccati), quasi (one row) and regularised factors: checked on frequency grids."""

import numpy as np
import pytest

from fdikit.design.nullspace.factorization import (
    boundary_zeros,
    coouter_coinner,
    inverse,
    quasi_coouter,
    quasi_coouter_row,
    regularized_coouter,
    series,
)
from fdikit.errors import DesignError, ParameterError


def _resp(sys, lam):
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in sys)
    n = A.shape[0] if A.size else 0
    if not n:
        return D.astype(complex)
    return D + C.reshape(-1, n) @ np.linalg.solve(lam * np.eye(n) - A, B.reshape(n, -1))


def _stable_random(seed, n, p, m, dt=None):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    if dt is None:
        A = A - (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    else:
        A = 0.8 * A / np.max(np.abs(np.linalg.eigvals(A)))
    return A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))


@pytest.mark.parametrize("dt", [None, 0.1])
def test_standard_factorisation_on_a_grid(dt):
    G = _stable_random(1, 4, 2, 3, dt)
    f = coouter_coinner(*G, dt)
    assert f.kind == "standard"
    Ao, Bo, Co, Do = f.outer
    zeros_o = np.linalg.eigvals(inverse(Ao, Bo, Co, Do)[0])
    poles_o = np.linalg.eigvals(Ao)
    if dt is None:
        assert zeros_o.real.max() < 0 and poles_o.real.max() < 0
        lams = 1j * np.logspace(-2, 2, 41)
    else:
        assert np.abs(zeros_o).max() < 1 and np.abs(poles_o).max() < 1
        lams = np.exp(1j * np.linspace(0, np.pi, 41))
    scale = max(np.linalg.norm(_resp(G, lam), 2) for lam in lams)
    for lam in lams:
        Gl, Gol, Gil = _resp(G, lam), _resp(f.outer, lam), _resp(f.inner, lam)
        np.testing.assert_allclose(Gol @ Gil, Gl, atol=1e-9 * scale)
        np.testing.assert_allclose(Gil @ Gil.conj().T, np.eye(2), atol=1e-9)
        np.testing.assert_allclose(Gol @ Gol.conj().T, Gl @ Gl.conj().T, atol=1e-9 * scale**2)


def test_first_order_row_by_hand():
    # G = [1/(s+1)  1]: |G|² = (ω² + 2)/(ω² + 1), Go = (s + √2)/(s + 1)
    f = coouter_coinner([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 1.0]])
    for w in (0.0, 0.7, 3.0):
        np.testing.assert_allclose(_resp(f.outer, 1j * w)[0, 0], (1j * w + np.sqrt(2)) / (1j * w + 1), rtol=1e-12)
    q = quasi_coouter_row([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 1.0]])     # standard: the same factor
    assert q.shifted == 0
    for w in (0.0, 0.7, 3.0):
        np.testing.assert_allclose(_resp(q.outer, 1j * w), _resp(f.outer, 1j * w), rtol=1e-10)


def test_square_minimum_phase_with_a_multiple_zero_is_its_own_outer_factor():
    # G = ((s + 1)/(s + 3))² ⊗ diag(1, 10⁴): square, D invertible, zeros at −1 twice per row; G_o = G, G_i = I.
    # B̃ = B (I − D⁻¹D) = 0, so the filter ARE has X = 0; on the whole, its Hamiltonian has defective pairs ±1
    a = np.array([[-3.0, 1.0], [0.0, -3.0]])
    b = np.array([[0.0], [1.0]])
    c = np.array([[4.0, -4.0]])                      # (s+1)² / (s+3)² = 1 + (−4s − 8)/(s+3)²
    A, B = np.kron(np.eye(2), a), np.kron(np.diag([1.0, 1e4]), b)
    C, D = np.kron(np.eye(2), c), np.diag([1.0, 1e4])
    f = coouter_coinner(A, B, C, D)
    for w in (0.0, 0.4, 5.0):
        g = ((1j * w + 1) / (1j * w + 3)) ** 2
        np.testing.assert_allclose(_resp((A, B, C, D), 1j * w), np.diag([g, 1e4 * g]), rtol=1e-12)
        np.testing.assert_allclose(_resp(f.outer, 1j * w), _resp((A, B, C, D), 1j * w), rtol=1e-9)
        np.testing.assert_allclose(_resp(f.inner, 1j * w), np.eye(2), atol=1e-9)


def test_non_standard_cases_are_refused_with_the_zeros():
    with pytest.raises(DesignError, match="zeros at infinity"):
        coouter_coinner([[-2.0]], [[1.0]], [[1.0]], [[0.0]])                 # 1/(s+2)
    with pytest.raises(DesignError, match="stability boundary"):
        coouter_coinner([[-2.0]], [[-2.0]], [[1.0]], [[1.0]])                # s/(s+2)
    np.testing.assert_allclose(boundary_zeros([[-2.0]], [[-2.0]], [[1.0]], [[1.0]]), [0.0], atol=1e-12)
    # (z − 1)/(z − 0.5) = 1 − 0.5/(z − 0.5): its zero at 1; (z − 0.9)/(z − 0.5) = 1 − 0.4/(z − 0.5): none
    np.testing.assert_allclose(boundary_zeros([[0.5]], [[-0.5]], [[1.0]], [[1.0]], 1.0), [1.0], atol=1e-12)
    assert boundary_zeros([[0.5]], [[-0.4]], [[1.0]], [[1.0]], 1.0).size == 0
    assert boundary_zeros([[-2.0]], [[1.0]], [[1.0]], [[1.0]]).size == 0
    with pytest.raises(ParameterError, match="one row"):
        quasi_coouter_row(np.eye(1), np.ones((1, 1)), np.ones((2, 1)), np.zeros((2, 1)))


def test_quasi_row_shifts_boundary_and_infinite_zeros():
    # 1/(s+2): zero at ∞ → (s+3)/(s+2);  s/(s+2): zero at 0 → (s+0.3)/(s+2)
    for (A, B, C, D), sdeg, zero in [(([[-2.0]], [[1.0]], [[1.0]], [[0.0]]), -3.0, -3.0),
                                     (([[-2.0]], [[-2.0]], [[1.0]], [[1.0]]), -0.3, -0.3)]:
        f = quasi_coouter_row(A, B, C, D, sdeg=sdeg)
        assert f.kind == "quasi" and f.shifted == 1
        z = np.linalg.eigvals(inverse(*f.outer)[0])
        np.testing.assert_allclose(z, [zero], rtol=1e-10)
        # |g_o(jω)| / |g(jω)| = |jω − sdeg| / |n_b(jω)| with the shifted factor only
        np.testing.assert_allclose(np.linalg.eigvals(f.outer[0]), [-2.0], rtol=1e-12)


def test_regularised_factor_by_hand():
    # [1/(s+2)  0.3]: |.|² = 0.09 (ω² + 1.36/0.09)/(ω² + 4)
    f = regularized_coouter([[-2.0]], [[1.0]], [[1.0]], [[0.0]], epsreg=0.3)
    z = np.linalg.eigvals(inverse(*f.outer)[0])
    np.testing.assert_allclose(z, [-np.sqrt(1.36) / 0.3], rtol=1e-10)
    for w in (0.0, 1.0, 10.0):
        np.testing.assert_allclose(abs(_resp(f.outer, 1j * w)[0, 0]) ** 2, 1 / (w * w + 4) + 0.09, rtol=1e-10)
    with pytest.raises(ParameterError):
        regularized_coouter([[-2.0]], [[1.0]], [[1.0]], [[0.0]], epsreg=0.0)


def test_series_and_inverse_cancel():
    G = _stable_random(5, 3, 2, 2)
    A, B, C, D = series(G, inverse(*G))
    for w in (0.1, 2.0):
        np.testing.assert_allclose(_resp((A, B, C, D), 1j * w), np.eye(2), atol=1e-9)


# ------------------------------------------------------------------ quasi factor of several rows (nonstd = 1)
def _response(F, w):
    A, B, C, D = F
    return C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B) + D if A.size else D


@pytest.mark.parametrize("row", [([[-2.0]], [[1.0]], [[1.0]], [[0.0]]),            # 1/(s+2): a zero at ∞
                                 ([[-2.0]], [[-2.0]], [[1.0]], [[1.0]]),           # s/(s+2): a zero at 0
                                 (np.diag([-2.0, -3.0]), [[-1.0], [2.0]], [[1.0, 1.0]], [[0.0]])])
def test_quasi_factor_of_rows_agrees_with_the_polynomial_one(row):
    # two independent constructions (state-space row operations / polynomial spectral factor) of one row
    a, b = quasi_coouter(*row, sdeg=-3.0), quasi_coouter_row(*row, sdeg=-3.0)
    assert a.shifted == b.shifted == 1
    for w in (0.0, 0.3, 1.0, 7.0):
        assert abs(_response(a.outer, w)[0, 0]) == pytest.approx(abs(_response(b.outer, w)[0, 0]), rel=1e-9)


def test_quasi_factor_of_two_rows_is_rotation_equivariant():
    # G = diag(1/(s+2), s/(s+3)): by hand F = diag((s+1)/(s+2), (s+1)/(s+3)) for π = −1 (up to a unitary constant);
    # for U G (rotated residuals) the new noise part F_U⁻¹ U G has the singular values of F⁻¹ G
    A, B, C, D = np.diag([-2.0, -3.0]), np.eye(2), np.diag([1.0, -3.0]), np.diag([0.0, 1.0])
    th = 0.7
    U = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    f, fu = quasi_coouter(A, B, C, D, sdeg=-1.0), quasi_coouter(A, B, U @ C, U @ D, sdeg=-1.0)
    assert f.shifted == fu.shifted == 2
    for w in (0.0, 0.5, 2.0, 20.0):
        s = 1j * w
        F = np.diag([(s + 1) / (s + 2), (s + 1) / (s + 3)])
        Fh = _response(f.outer, w)
        np.testing.assert_allclose(Fh @ Fh.conj().T, F @ F.conj().T, rtol=1e-9, atol=1e-12)
        G = C @ np.linalg.solve(s * np.eye(2) - A, B) + D
        sv = np.linalg.svd(np.linalg.solve(Fh, G), compute_uv=False)
        svu = np.linalg.svd(np.linalg.solve(_response(fu.outer, w), U @ G), compute_uv=False)
        np.testing.assert_allclose(svu, sv, rtol=1e-9, atol=1e-12)


def _tf_realization(num, den, dt=None):
    """A minimal realisation of a 2 × 2 transfer matrix (python-control)."""
    import control

    G = control.minreal(control.ss(control.tf(num, den, 0 if dt is None else dt)), verbose=False)
    return G.A, G.B, G.C, G.D


def test_quasi_factor_of_a_complex_boundary_pair():
    # one row (s²+1)/(s+1)²: the row operations (a division by s²+1) and the polynomial factor agree; with two rows
    # diag((s²+1)/(s+1)², 1/(s+3)): F = diag((s+3)²/(s+1)², (s+3)/(s+3)) at π = −3, up to a unitary constant
    A, B, C, D = np.array([[-2.0, -1.0], [1.0, 0.0]]), np.array([[1.0], [0.0]]), np.array([[-2.0, 0.0]]), [[1.0]]
    a, b = quasi_coouter(A, B, C, D, sdeg=-3.0), quasi_coouter_row(A, B, C, D, sdeg=-3.0)
    assert a.shifted == b.shifted == 2
    for w in (0.0, 0.3, 1.0, 7.0):
        assert abs(_response(a.outer, w)[0, 0]) == pytest.approx(abs(_response(b.outer, w)[0, 0]), rel=1e-9)
    from scipy.linalg import block_diag

    A2, B2, C2, D2 = block_diag(A, [[-3.0]]), block_diag(B, [[1.0]]), block_diag(C, [[1.0]]), np.diag([1.0, 0.0])
    f = quasi_coouter(A2, B2, C2, D2, sdeg=-3.0)
    assert f.shifted == 3
    for w in (0.0, 0.5, 2.0, 20.0):
        s = 1j * w
        F = np.diag([(s + 3) ** 2 / (s + 1) ** 2, 1.0])
        Fh = _response(f.outer, w)
        np.testing.assert_allclose(Fh @ Fh.conj().T, F @ F.conj().T, rtol=1e-9, atol=1e-12)
    with pytest.raises(ParameterError, match="real and stable"):
        quasi_coouter(A, B, C, D, poles=[-1 + 1j])


@pytest.mark.parametrize("dt", [None, 0.1])
def test_zero_steps_of_a_complex_pair_on_two_rows(dt):
    # G = [[q/((λ−a)(λ−b)), 1/(λ−c)], [0, 1/(λ−d)]] with q vanishing at λ₀, λ̄₀ on the boundary (±j; discrete e^{±j}):
    # the left null vector at λ₀ is complex, so the pair is removed on two rows; T⁻¹ G₁ = G and G₁ is standard
    from fdikit.design.nullspace.zero_steps import remove_boundary_zeros, zero_steps_inverse

    if dt is None:
        q, dens, pts = [1, 0, 1], ([1, 3, 2], [1, 7, 12], [1, 3]), (0.3j, 1j, 2.0, 5j)
    else:
        q, dens, pts = [1, -2 * np.cos(1.0), 1], ([1, -0.8, 0.15], [1, -0.2], [1, -0.4]), (np.exp(0.3j), np.exp(1j),
                                                                                            0.9, -0.7)
    sys = _tf_realization([[q, [1]], [[0], [1]]], [[dens[0], dens[1]], [[1], dens[2]]], dt)
    C1, D1, steps, g1 = remove_boundary_zeros(*sys, dt, sdeg=-2.0 if dt is None else 0.5)
    pair = [st for st in steps if st.mix is not None]
    assert len(pair) == 1 and pair[0].rows == (0, 1) and pair[0].poles == ((-2.0, -2.0) if dt is None else (0.5, 0.5))
    assert abs(pair[0].zero - (1j if dt is None else np.exp(1j))) < 1e-12
    Ti = zero_steps_inverse(steps, 2, dt)
    assert np.linalg.eigvals(Ti[0]) == pytest.approx(np.full(Ti[0].shape[0], -2.0 if dt is None else 0.5), abs=1e-6)
    for lam in pts:
        G = _resp(sys, lam)
        np.testing.assert_allclose(_resp(Ti, lam) @ _resp((sys[0], sys[1], C1, D1), lam), G, rtol=0,
                                   atol=1e-12 * np.abs(G).max())
    assert coouter_coinner(sys[0], sys[1], C1, D1, dt).kind == g1.kind == "standard"
