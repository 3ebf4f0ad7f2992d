"""Subspaces, CAISA, invariant zeros, detection spaces, separability and mutual detectability.

Oracles: ``scipy.linalg.orth``/``null_space``/``subspace_angles``; brute-force dimension counts; a
plain re-implementation of the CAISA recursion and of Wonham's unobservability-subspace algorithm
(UOSA) on scipy primitives; the finite generalised eigenvalues of the Rosenbrock pencil
(``scipy.linalg.eig``) for square systems; planted zeros (unobservable modes, exact by
construction) for non-square ones; Murray (2012) Example 2, whose zeros are
checked against the printed ones; and the PATH properties R-GEO-1…4
on the reconstructed App. D data.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from fdikit import fault_maps as fm
from fdikit import linalg as la
from fdikit.errors import DesignError, ParameterError
from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14


def _angle(U, V) -> float:
    """Largest principal angle between Im U and Im V (inf if the dimensions differ)."""
    U, V = np.atleast_2d(U), np.atleast_2d(V)
    if U.shape[1] != V.shape[1]:
        return np.inf
    if U.shape[1] == 0:
        return 0.0
    return float(np.max(scipy.linalg.subspace_angles(U, V)))


def _planted_rank(rng, m, n, r):
    return rng.standard_normal((m, r)) @ rng.standard_normal((r, n))


# ---------------------------------------------------------------------- basic subspaces
@pytest.mark.parametrize("seed", range(6))
def test_rank_orth_null_match_scipy(seed):
    rng = np.random.default_rng(seed)
    m, n = rng.integers(3, 9, size=2)
    r = int(rng.integers(0, min(m, n) + 1))
    M = _planted_rank(rng, m, n, r)
    assert la.rank(M) == r == np.linalg.matrix_rank(M)
    Q = la.orth(M)
    assert Q.shape == (m, r)
    np.testing.assert_allclose(Q.T @ Q, np.eye(r), atol=1e-12)
    assert _angle(Q, scipy.linalg.orth(M, rcond=1e-10)) < 1e-10
    N = la.null(M)
    assert N.shape == (n, n - r)
    np.testing.assert_allclose(N.T @ N, np.eye(n - r), atol=1e-12)
    assert np.linalg.norm(M @ N) <= 1e-12 * max(np.linalg.norm(M), 1)
    assert _angle(N, scipy.linalg.null_space(M, rcond=1e-10)) < 1e-10


def test_rank_is_scale_invariant_and_edge_cases():
    rng = np.random.default_rng(1)
    M = _planted_rank(rng, 6, 5, 3)
    assert la.rank(1e-9 * M) == la.rank(1e9 * M) == 3
    assert la.rank(np.zeros((3, 4))) == 0
    assert la.orth(np.zeros((3, 4))).shape == (3, 0)
    assert la.null(np.zeros((0, 4))).shape == (4, 4)
    assert la.null(np.eye(3)).shape == (3, 0)
    assert la.rank(np.zeros((0, 3))) == 0


@pytest.mark.parametrize("seed", range(6))
def test_intersect_and_span_sum_dimensions(seed):
    rng = np.random.default_rng(seed)
    n = 8
    c, a, b = 2, 2, 3  # common part, private parts: generic subspaces of dims c+a and c+b
    S = rng.standard_normal((n, c))
    U = np.hstack([S, rng.standard_normal((n, a))]) @ rng.standard_normal((c + a, c + a))
    V = np.hstack([S, rng.standard_normal((n, b))]) @ rng.standard_normal((c + b, c + b))
    inter = la.intersect(U, V)
    total = la.span_sum(U, V)
    # brute force: dim(U ∩ V) = dim U + dim V − dim(U + V), with rank counts from numpy
    assert total.shape[1] == np.linalg.matrix_rank(np.hstack([U, V])) == c + a + b
    assert inter.shape[1] == np.linalg.matrix_rank(U) + np.linalg.matrix_rank(V) - total.shape[1] == c
    assert _angle(inter, S) < 1e-10
    assert la.contains(U, inter) and la.contains(V, inter)
    assert la.contains(total, U) and la.contains(total, V)
    np.testing.assert_allclose(inter.T @ inter, np.eye(c), atol=1e-12)
    # disjoint subspaces and empty bases
    assert la.intersect(U[:, :1], V[:, -1:]).shape == (n, 0) or la.contains(U[:, :1], V[:, -1:])
    assert la.intersect(U, np.zeros((n, 0))).shape == (n, 0)
    assert la.span_sum(U, np.zeros((n, 0))).shape[1] == c + a
    with pytest.raises(ParameterError):
        la.span_sum(np.zeros((n, 0)))


def test_contains():
    U = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    assert la.contains(U, np.array([2.0, -3.0, 0.0]))
    assert la.contains(U, [1.0, 1.0, 0.0])  # a plain list
    assert not la.contains(U, np.array([0.0, 0.0, 1.0]))
    assert not la.contains(U, np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1e-3]]))
    assert la.contains(U, np.array([1.0, 0.0, 1e-12]))
    assert la.contains(np.zeros((3, 0)), np.zeros(3))


# ---------------------------------------------------------------------- CAISA
def _caisa_reference(A, C, F, tol=1e-9):
    """W⁰ = 0, W^{k+1} = Im F + A (W^k ∩ Ker C) with scipy primitives only."""
    n = A.shape[0]
    kerC = scipy.linalg.null_space(C, rcond=tol)
    W = np.zeros((n, 0))
    for _ in range(n + 2):
        if W.shape[1] and kerC.shape[1]:
            N = scipy.linalg.null_space(np.hstack([W, -kerC]), rcond=tol)
            inter = W @ N[: W.shape[1]]
        else:
            inter = np.zeros((n, 0))
        W_next = scipy.linalg.orth(np.hstack([F, A @ inter]), rcond=tol)
        if W_next.shape[1] == W.shape[1]:
            return W_next
        W = W_next
    return W


def _planted_relative_degree(rng, n, p, mu):
    """Random (A, C, f) with C A^k f = 0 for k < mu: C's rows orthogonal to f, A f, …, A^{mu-1} f."""
    A = rng.standard_normal((n, n))
    f = rng.standard_normal((n, 1))
    K = np.hstack([np.linalg.matrix_power(A, k) @ f for k in range(mu)]) if mu else np.zeros((n, 0))
    P = np.eye(n) - (la.orth(K) @ la.orth(K).T if mu else 0)
    C = rng.standard_normal((p, n)) @ P
    return A, C, f


def _ca_invariant(A, C, W) -> bool:
    part = la.intersect(W, la.null(C))
    return part.shape[1] == 0 or la.contains(W, A @ part, rtol=1e-9)


@pytest.mark.parametrize("mu", [0, 1, 2, 3])
@pytest.mark.parametrize("seed", range(4))
def test_caisa_one_dimensional_fault_is_krylov_up_to_relative_degree(mu, seed):
    rng = np.random.default_rng(100 * mu + seed)
    n, p = 8, 3
    A, C, f = _planted_relative_degree(rng, n, p, mu)
    markov = [np.linalg.norm(C @ np.linalg.matrix_power(A, k) @ f) for k in range(mu + 1)]
    scale = np.linalg.norm(C) * np.linalg.norm(A) ** mu * np.linalg.norm(f)
    assert all(v < 1e-9 * scale for v in markov[:mu]) and markov[mu] > 1e-3 * scale  # planted μ
    W = la.caisa(A, C, f)
    krylov = np.hstack([np.linalg.matrix_power(A, k) @ f for k in range(mu + 1)])
    assert W.shape[1] == mu + 1
    assert _angle(W, krylov) < 1e-8
    assert _angle(W, _caisa_reference(A, C, f)) < 1e-8
    assert _ca_invariant(A, C, W)


@pytest.mark.parametrize("seed", range(5))
def test_caisa_multidimensional_fault_matches_recursion(seed):
    rng = np.random.default_rng(seed)
    n, p = 9, 4
    A, C, f2 = _planted_relative_degree(rng, n, p, 2)
    F = np.hstack([rng.standard_normal((n, 1)), f2])  # one column seen at once, one after two steps
    W = la.caisa(A, C, F)
    ref = _caisa_reference(A, C, F)
    assert W.shape[1] == ref.shape[1] == 4
    assert _angle(W, ref) < 1e-8
    assert _ca_invariant(A, C, W)
    assert la.contains(W, F)


@pytest.mark.parametrize("seed", range(5))
def test_caisa_is_minimal(seed):
    """W* ⊆ every (C, A)-invariant subspace containing F; here A-invariant ones (planted) and Im F itself."""
    rng = np.random.default_rng(seed)
    n, d, p = 8, 4, 2
    S = rng.standard_normal((n, n))
    blk = np.block([[rng.standard_normal((d, d)), rng.standard_normal((d, n - d))],
                    [np.zeros((n - d, d)), rng.standard_normal((n - d, n - d))]])
    A = S @ blk @ np.linalg.inv(S)  # Im S[:, :d] is A-invariant
    V = S[:, :d]
    F = V @ rng.standard_normal((d, 1))
    C = rng.standard_normal((p, n))
    C = C - (C @ F) @ np.linalg.pinv(F)  # C F = 0: W* is larger than Im F
    W = la.caisa(A, C, F)
    assert W.shape[1] >= 2
    assert la.contains(V, W, rtol=1e-8)
    # C F of full column rank: W* = Im F
    F2 = rng.standard_normal((n, 2))
    C2 = rng.standard_normal((3, n))
    assert _angle(la.caisa(A, C2, F2), F2) < 1e-10


# ---------------------------------------------------------------------- invariant zeros
def _pencil_zeros(A, C, F):
    """Finite generalised eigenvalues of [[A, F], [C, 0]] − s [[I, 0], [0, 0]] (square systems)."""
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    assert k == p
    P = np.block([[A, F], [C, np.zeros((p, k))]])
    E = np.zeros_like(P)
    E[:n, :n] = np.eye(n)
    w = scipy.linalg.eig(P, E, right=False)
    return w[np.isfinite(w) & (np.abs(w) < 1e5 * np.linalg.norm(P))]  # drop the (perturbed) infinite ones


def _sorted(z):
    z = np.asarray(z, dtype=complex)
    return z[np.lexsort((np.round(z.imag, 6), np.round(z.real, 6)))]


def _direction_residual(A, C, F, z, x) -> float:
    """Relative residual of the pencil equation (A − zI) x + F η = 0, C x = 0, with the best η."""
    n = A.shape[0]
    eta = np.linalg.lstsq(F.astype(complex), -(A - z * np.eye(n)) @ x, rcond=None)[0]
    res = np.concatenate([(A - z * np.eye(n)) @ x + F @ eta, C @ x])
    scale = np.linalg.norm(np.block([[A, F], [C, np.zeros((C.shape[0], F.shape[1]))]]), 2)
    return float(np.linalg.norm(res) / (scale * np.linalg.norm(x)))


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("k", [1, 2, 3])
def test_invariant_zeros_square_match_rosenbrock_eig(seed, k):
    rng = np.random.default_rng(seed)
    n = 6
    A, F, C = rng.standard_normal((n, n)), rng.standard_normal((n, k)), rng.standard_normal((k, n))
    z, dirs = la.invariant_zeros(A, C, F)
    ref = _pencil_zeros(A, C, F)
    assert z.size == ref.size == n - k  # generic square system with CF invertible: n − k zeros
    np.testing.assert_allclose(_sorted(z), _sorted(ref), rtol=1e-8, atol=1e-8)
    assert len(dirs) == z.size
    for zi, x in zip(z, dirs):
        assert abs(np.linalg.norm(x) - 1) < 1e-12
        assert _direction_residual(A, C, F, zi, x) < 1e-8


def _planted_unobservable(rng, Au):
    """(A, C, F) whose unobservable modes are the eigenvalues of ``Au`` (2 x 2), in random coordinates.

    Unobservable modes are invariant zeros of (C, A, F) for every F; with 2 outputs and 1 fault
    column a generic tall system has no other zero.  Returns the system and the exact zero space.
    """
    n = 6
    A = np.block([[rng.standard_normal((4, 4)), np.zeros((4, 2))], [rng.standard_normal((2, 4)), Au]])
    C = np.hstack([rng.standard_normal((2, 4)), np.zeros((2, 2))])
    F = rng.standard_normal((n, 1))
    S = rng.standard_normal((n, n))
    Si = np.linalg.inv(S)
    return S @ A @ Si, C @ Si, S @ F, S[:, 4:]


AU = {
    "distinct": np.diag([-2.0, -3.0]),
    "double": np.diag([-2.0, -2.0]),  # two independent directions
    "jordan": np.array([[-2.0, 1.0], [0.0, -2.0]]),  # defective: a Jordan chain
}


@pytest.mark.parametrize("case", sorted(AU))
def test_invariant_zeros_nonsquare_planted(case):
    """Regression: AB08ND's default tolerance lost these zeros in ~20 % of seeds (linalg fix, rtol default)."""
    expect = _sorted(np.linalg.eigvals(AU[case]))
    for seed in range(60):
        rng = np.random.default_rng(seed)
        A, C, F, Vexact = _planted_unobservable(rng, AU[case])
        z, dirs = la.invariant_zeros(A, C, F)
        np.testing.assert_allclose(_sorted(z), expect, atol=1e-5)
        D = np.column_stack(dirs)
        V = la.orth(np.hstack([D.real, D.imag]))
        assert _angle(V, Vexact) < 1e-6, seed  # the directions span the whole zero space
        if case != "jordan":
            for zi, x in zip(z, dirs):
                assert _direction_residual(A, C, F, zi, x) < 1e-8
        else:  # the first direction of the cluster is the eigen-direction (at the cluster's mean), the second
            # completes the chain: (A − zI) x₂ + F η₂ ∈ span{x₁}, C x₂ = 0
            zbar = z.mean().real
            assert _direction_residual(A, C, F, zbar, dirs[0]) < 1e-8
            x1, x2 = dirs
            assert np.linalg.norm(C @ x2) < 1e-8 * np.linalg.norm(C)
            G = np.hstack([F, x1.reshape(-1, 1)])
            r = (A - zbar * np.eye(6)) @ x2
            assert np.linalg.norm(r - G @ np.linalg.lstsq(G, r, rcond=None)[0]) < 1e-8 * np.linalg.norm(A)


# ---------------------------------------------------------------------- detection spaces
def _uosa_reference(A, C, F):
    """Wonham's UOSA: T⁰ = X, T^{k+1} = W* + (A⁻¹ T^k ∩ Ker C) -- the minimal UOS containing F, no zeros needed."""
    n = A.shape[0]
    W = _caisa_reference(A, C, F)
    kerC = scipy.linalg.null_space(C, rcond=1e-9)
    T = np.eye(n)
    for _ in range(n + 2):
        Tperp = scipy.linalg.null_space(T.T, rcond=1e-9)
        pre = scipy.linalg.null_space(Tperp.T @ A, rcond=1e-9) if Tperp.shape[1] else np.eye(n)
        inter = la.intersect(pre, kerC)
        T_next = scipy.linalg.orth(np.hstack([W, inter]), rcond=1e-9)
        if T_next.shape[1] == T.shape[1]:
            return T_next
        T = T_next
    return T


@pytest.mark.parametrize("case", sorted(AU))
@pytest.mark.parametrize("seed", range(5))
def test_detection_space_matches_uosa_planted(case, seed):
    A, C, F, Vexact = _planted_unobservable(np.random.default_rng(seed), AU[case])
    T = la.detection_space(A, C, F)
    assert T.shape[1] == 3  # Im F (C F ≠ 0) ⊕ the 2-D zero space
    assert _angle(T, _uosa_reference(A, C, F)) < 1e-6
    assert _angle(T, np.hstack([F, Vexact])) < 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_detection_space_square_system_matches_uosa(seed):
    """Square tall-enough system with relative degree 1 and real/complex transmission zeros: T* = W* ⊕ V."""
    rng = np.random.default_rng(seed)
    n = 6
    A, C, f = _planted_relative_degree(rng, n, 1, 1)
    T = la.detection_space(A, C, f)
    z, _ = la.invariant_zeros(A, C, f)
    assert T.shape[1] == 2 + z.size == n  # SISO, relative degree 2: n − 2 zeros; T* = whole space
    assert _angle(T, _uosa_reference(A, C, f)) < 1e-6
    A2, C2, F2 = rng.standard_normal((n, n)), rng.standard_normal((3, n)), rng.standard_normal((n, 2))
    T2 = la.detection_space(A2, C2, F2)
    assert _angle(T2, _uosa_reference(A2, C2, F2)) < 1e-6
    assert la.rank(C2 @ T2) == la.rank(C2 @ la.caisa(A2, C2, F2))  # C T* = C W* (Murray 2012, (2.13))


# ---------------------------------------------------------------------- Murray (2012) Example 2
EX2_A = np.array([[0.0, 3.0, 4.0], [1.0, 2.0, 3.0], [0.0, 2.0, 5.0]])
EX2_C = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
EX2_F1 = np.array([[1.0], [-0.5], [0.5]])
# (F_2, zeros of (C, A, F_2), zeros of (C, A, [F_1 F_2]), η at the joint zero up to scale, mutually detectable)
EX2_CASES = {
    "6.2.1": ([3.0, 1.0, 0.0], [-3.0], [-3.0], [0.0, 1.0], True),
    "6.2.2": ([-3.0, 1.0, 0.0], [3.0], [3.0], [0.0, 1.0], True),
    "6.2.3": ([5.0, 1.0, 1.0], [], [-1.5], [-2.0, 1.0], False),
    "6.2.4": ([0.0, 0.0, 1.0], [], [2.0], [-2.0, 1.0], False),
}


@pytest.mark.parametrize("case", sorted(EX2_CASES))
def test_murray_example2_zeros_directions_and_mutual_detectability(case):
    """Murray (2012) §6.2, Example 2 (zeros as printed in §6.2.1–6.2.4).

    Data as printed: A = [0 3 4; 1 2 3; 0 2 5], C = [0 1 0; 0 0 1], F_1 = [1, −0.5, 0.5]ᵀ; the
    zero direction is ν ∝ e_1 in all four cases.
    """
    f2, z2, zj, eta, md = EX2_CASES[case]
    A, C, F1, F2 = EX2_A, EX2_C, EX2_F1, np.array(f2).reshape(-1, 1)
    assert la.invariant_zeros(A, C, F1)[0].size == 0
    z, d = la.invariant_zeros(A, C, F2)
    np.testing.assert_allclose(np.sort(z.real), z2, atol=1e-10)
    np.testing.assert_allclose(z.imag, 0, atol=1e-12)
    F12 = np.hstack([F1, F2])
    z, d = la.invariant_zeros(A, C, F12)
    np.testing.assert_allclose(z.real, zj, atol=1e-10)
    x = d[0]
    assert _angle(x.reshape(-1, 1), np.eye(3)[:, :1]) < 1e-10  # ν ∝ e_1
    assert _direction_residual(A, C, F12, z[0], x) < 1e-12
    eta_x = np.linalg.lstsq(F12, -(A - z[0] * np.eye(3)) @ x, rcond=None)[0]
    assert _angle(eta_x.reshape(-1, 1).real, np.array(eta).reshape(-1, 1)) < 1e-10
    ok, joint, union = la.mutually_detectable(A, C, [F1, F2])
    assert ok is md
    np.testing.assert_allclose(joint.real, zj, atol=1e-10)
    np.testing.assert_allclose(np.sort(union.real), z2, atol=1e-10)
    # detection spaces: T_1 = Im F_1; T_2 = span{e1, e2} when F_2 has the zero, else Im F_2
    T1, T2 = la.detection_space(A, C, F1), la.detection_space(A, C, F2)
    assert _angle(T1, F1) < 1e-12
    assert _angle(T2, np.eye(3)[:, :2] if z2 else F2) < 1e-10
    assert la.output_separable(C, [T1, T2]) == (True, [])


# ---------------------------------------------------------------------- PATH
M12 = path_vehicle_12("midpoint")
M14 = path_vehicle_14()
GROUPS_12 = {
    1: ["engine_speed", "accel_y", "accel_z", "pitch_rate"],
    2: ["accel_x", "roll_rate", "yaw_rate", "engine_speed"],
    3: ["wheel_speed_fl", "wheel_speed_fr", "wheel_speed_rl", "wheel_speed_rr"],
}


@pytest.mark.parametrize("output", M12.outputs)
def test_r_geo_1_sensor_maps(output):
    """R-GEO-1: C F¹ = e_i and F² = A F¹ (eq. (3.5)); 'magnitude'/'rate' pick the columns."""
    i = M12.outputs.index(output)
    F = fm.sensor_fault_map(M12, output)
    assert F.shape == (12, 2)
    np.testing.assert_allclose(M12.C @ F[:, 0], np.eye(12)[i], atol=1e-9)
    np.testing.assert_allclose(F[:, 1], M12.A @ F[:, 0], rtol=1e-12)
    np.testing.assert_array_equal(fm.sensor_fault_map(M12, output, "magnitude"), F[:, 1:])
    np.testing.assert_array_equal(fm.sensor_fault_map(M12, output, "rate"), F[:, :1])


def test_r_geo_1_rank_deficient_c_raises():
    """With tiny='zero' C12 has rank 11 (zero τ_b column): only the air mass (e_1 ∈ Im C) keeps a sensor map."""
    m = path_vehicle_12()
    assert la.rank(m.C) == 11
    ok = []
    for output in m.outputs:
        try:
            fm.sensor_fault_map(m, output)
            ok.append(output)
        except DesignError as exc:
            assert "not in the range of C" in str(exc)
    assert ok == ["air_mass"]
    with pytest.raises(ParameterError, match="direction"):
        fm.sensor_fault_map(M12, "air_mass", "bias")


def test_r_geo_2_actuator_detection_spaces():
    """R-GEO-2 on path_vehicle_14(): throttle 2 (C F = 0, C A F ∝ e_1), brake 2 (C F = 0 with the printed zeros),
    steering 1; no invariant zeros, so T* = W* = span{F, …, A^μ F}."""
    A, C = M14.A, M14.C
    expect = {"throttle": 2, "brake": 2, "steering": 1}
    for control, nu in expect.items():
        F = fm.actuator_fault_map(M14, control)
        assert la.invariant_zeros(A, C, F)[0].size == 0
        T = la.detection_space(A, C, F)
        assert T.shape[1] == la.caisa(A, C, F).shape[1] == nu, control
        krylov = np.hstack([np.linalg.matrix_power(A, k) @ F for k in range(nu)])
        assert _angle(T, krylov) < 1e-10
    F = fm.actuator_fault_map(M14, "throttle")
    np.testing.assert_array_equal(C @ F, 0)
    CAF = (C @ A @ F).ravel()
    np.testing.assert_allclose(CAF, 2.35 * 90.91 * np.eye(12)[0], rtol=1e-12)
    with pytest.raises(DesignError):  # the 12-state steering column has a feedthrough
        fm.actuator_fault_map(M12, "steering")


def test_r_geo_2_sensor_detection_spaces_are_the_fault_maps():
    """Every 2-D sensor fault on the 12-state midpoint model: no invariant zeros (C is invertible there, so
    none can exist) and T* = W* = Im F."""
    for output in M12.outputs:
        F = fm.sensor_fault_map(M12, output)
        assert la.invariant_zeros(M12.A, M12.C, F)[0].size == 0, output
        assert _angle(la.detection_space(M12.A, M12.C, F), F) < 1e-10, output


def test_path14_air_mass_zeros():
    """The 2-D air-mass fault on the 14-state model has zeros at the brake (−1.25) and throttle (−90.91)
    actuator poles, directions e_τb and e_α: C e_α = C e_τb = 0 and (A − z I) e_α = 2.35 e_ma ∈ Im F,
    (A − z I) e_τb = −0.07 e_ωe ∈ Im F (F = [e_ma, A e_ma] spans e_ma, e_ωe).  Hence ν = 4 there.
    On the midpoint model only −90.91 remains (AB08ND's default tolerance missed it before the fix)."""
    A, C = M14.A, M14.C
    F = fm.sensor_fault_map(M14, "air_mass")
    z, d = la.invariant_zeros(A, C, F)
    order = np.argsort(z.real)
    np.testing.assert_allclose(z.real[order], [-90.91, -1.25], rtol=1e-12)
    e = np.eye(14)
    assert _angle(d[order[0]].real.reshape(-1, 1), e[:, [11]]) < 1e-10
    assert _angle(d[order[1]].real.reshape(-1, 1), e[:, [12]]) < 1e-10
    assert la.detection_space(A, C, F).shape[1] == 4
    m = path_vehicle_14("midpoint")
    z, d = la.invariant_zeros(m.A, m.C, fm.sensor_fault_map(m, "air_mass"))
    np.testing.assert_allclose(z.real, [-90.91], rtol=1e-12)


def test_r_geo_3_throttle_air_mass_separability():
    """R-GEO-3: (throttle, air mass 2-D) not output separable; (throttle, air-mass magnitude A F¹) separable."""
    A, C = M14.A, M14.C
    T_thr = la.detection_space(A, C, fm.actuator_fault_map(M14, "throttle"))
    T_am2 = la.detection_space(A, C, fm.sensor_fault_map(M14, "air_mass"))
    T_am1 = la.detection_space(A, C, fm.sensor_fault_map(M14, "air_mass", "magnitude"))
    assert la.output_separable(C, [T_thr, T_am2]) == (False, [(0, 1)])
    assert la.output_separable(C, [T_thr, T_am1]) == (True, [])


@pytest.mark.parametrize("group", sorted(GROUPS_12))
def test_r_geo_4_sensor_groups(group):
    """R-GEO-4, groups 1–3 (12-state midpoint): ν = 2 each, Σν = 8 (ν₀ = 4), output separable, mutually
    detectable.  With C invertible nobody has zeros, so mutual detectability holds trivially (∅ = ∅)."""
    Fs = [fm.sensor_fault_map(M12, o) for o in GROUPS_12[group]]
    Ts = [la.detection_space(M12.A, M12.C, F) for F in Fs]
    assert [T.shape[1] for T in Ts] == [2, 2, 2, 2]
    assert la.output_separable(M12.C, Ts) == (True, [])
    ok, joint, union = la.mutually_detectable(M12.A, M12.C, Fs)
    assert ok and joint.size == 0 and union.size == 0


def test_r_geo_4_group_4_reconstructed_data():
    """R-GEO-4, group 4 (throttle, brake, steering, air-mass magnitude; 14-state).

    On path_vehicle_14() (entries printed ±0.00 set to 0) ν = (2, 2, 1, 1) and nobody has an invariant
    zero, so ``mutually_detectable`` returns True (∅ = ∅).  But the set is NOT output separable: no pair
    fails, the triple (throttle, brake, air-mass magnitude) does.  C T_thr = span{e_1}, C T_brake = span{C e_ωe}
    (the brake torque reaches only the engine speed in the rounded A) and C A F¹_ma = −22.42 e_1 + 306.69 C e_ωe.
    The joint system is then not even left invertible (its zeros are undefined).  With the ±0.00 entries at the
    midpoint of their rounding interval (tiny='midpoint'; brake taken 2-D as in the report) the set is output
    separable, with a margin that comes from those sub-print-precision couplings only.
    """
    A, C = M14.A, M14.C
    Fs = [fm.actuator_fault_map(M14, "throttle"), fm.actuator_fault_map(M14, "brake"),
          fm.actuator_fault_map(M14, "steering"), fm.sensor_fault_map(M14, "air_mass", "magnitude")]
    Ts = [la.detection_space(A, C, F) for F in Fs]
    assert [T.shape[1] for T in Ts] == [2, 2, 1, 1]
    assert la.output_separable(C, Ts) == (False, [])
    assert la.output_separable(C, [Ts[0], Ts[1], Ts[3]])[0] is False
    ok, joint, union = la.mutually_detectable(A, C, Fs)
    assert ok and joint.size == 0 and union.size == 0
    m = path_vehicle_14("midpoint")
    Fb = fm.actuator_fault_map(m, "brake")
    Fs = [fm.actuator_fault_map(m, "throttle"), np.hstack([Fb, m.A @ Fb]),
          fm.actuator_fault_map(m, "steering"), fm.sensor_fault_map(m, "air_mass", "magnitude")]
    Ts = [la.detection_space(m.A, m.C, F) for F in Fs]
    assert [T.shape[1] for T in Ts] == [2, 2, 1, 1]
    assert la.output_separable(m.C, Ts) == (True, [])
    ok, joint, union = la.mutually_detectable(m.A, m.C, Fs)
    assert ok and joint.size == 0 and union.size == 0


# ---------------------------------------------------------------------- PATH App. C: F-16XL
def _f16xl(sign_bdelta: float):
    """F-16XL longitudinal data of Douglas et al. 1996 App. C.5 as reconstructed in fdikit.plants.f16xl:
    C(2,4) = 0 (the printed extra 1.0000 is a print slip: the printed F_Az needs C(:,4) ∝ e_3) and A(1,5) = 0.0430."""
    A = np.array([
        [-0.0674, 0.0430, -0.8886, -0.5587, 0.0430],
        [0.0205, -1.4666, 16.5800, -0.0299, -1.4666],
        [0.1377, -1.6788, -0.6819, 0.0, -1.6788],
        [0.0, 0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, -1.1948],
    ])
    C = np.array([
        [0.0, 0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0591, 0.0, 0.0, 0.0],
        [0.0139, 1.0517, 0.1485, -0.0299, 0.0],
        [-0.0677, 0.0431, 0.0171, 0.0, 0.0],
    ])
    B_delta = np.array([[sign_bdelta * 0.1672], [-1.5179], [-9.7842], [0.0], [0.0]])
    return A, C, B_delta


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_f16xl_fault_triples_have_no_zeros_and_minimal_spaces(sign):
    """App. C.5: (C, A, F¹_Az), (C, A, F²_Az) and (C, A, F_δ) have no invariant zeros and T* = Im F.

    F¹_Az = e_4 / C(3,4) (C F¹ = e_3), F²_Az = A F¹ ∝ [0.9986, 0.0534, 0, 0, 0] (the printed normalised column);
    the first entry of B_δ has an uncertain sign (G17), so both are checked.
    """
    A, C, B_delta = _f16xl(sign)
    F1 = np.zeros((5, 1))
    F1[3, 0] = 1.0 / C[2, 3]
    np.testing.assert_allclose(C @ F1, [[0], [0], [1], [0]], atol=1e-12)
    F2 = A @ F1
    np.testing.assert_allclose((F2 / np.linalg.norm(F2)).ravel() * np.sign(F2[0, 0]), [0.9986, 0.0534, 0, 0, 0],
                               atol=5e-4)
    for F in (F1, F2, B_delta):
        zeros, _ = la.invariant_zeros(A, C, F)
        assert zeros.size == 0
        T = la.detection_space(A, C, F)
        assert T.shape[1] == 1 and la.contains(T, F)


def test_time_varying_sensor_fault_map():
    """App. A.2: F² = A F¹ − dF¹/dt with C(t) F¹(t) = e_i; the derivative by central differences matches the
    analytic −C⁻¹ Ċ C⁻¹ e_i, and a constant model reduces to the LTI map [F¹, A F¹]."""
    rng = np.random.default_rng(3)
    n = 4
    A0, A1 = rng.standard_normal((n, n)), rng.standard_normal((n, n))
    C0, C1 = rng.standard_normal((n, n)) + 3 * np.eye(n), rng.standard_normal((n, n))

    def A(t):
        return A0 + np.sin(t) * A1

    def C(t):
        return C0 + t * C1

    t, i = 0.7, 2
    F = fm.sensor_fault_map_tv(A, C, i, t)
    Ci = np.linalg.inv(C(t))
    F1 = Ci[:, i]
    dF1 = -Ci @ C1 @ Ci[:, i]
    np.testing.assert_allclose(F[:, 0], F1, rtol=1e-12)
    np.testing.assert_allclose(F[:, 1], A(t) @ F1 - dF1, rtol=1e-7)
    exact = fm.sensor_fault_map_tv(A, C, i, t, dF1=lambda _t: dF1)
    np.testing.assert_allclose(exact[:, 1], A(t) @ F1 - dF1, rtol=1e-12)
    from fdikit import FaultModel

    m = FaultModel(A=A0, C=C0)
    np.testing.assert_allclose(fm.sensor_fault_map_tv(lambda _t: A0, lambda _t: C0, i, 5.0),
                               fm.sensor_fault_map(m, m.outputs[i]), rtol=1e-9, atol=1e-12)
    from fdikit.errors import DesignError

    with pytest.raises(DesignError, match="not in the range"):
        fm.sensor_fault_map_tv(A, lambda _t: np.zeros((n, n)), i, t)
