"""Model-set design, Hallouzi 2008, Ch. 3 (§3.3–3.6) and App. B."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.spatial
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import norm

from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.multimodel.cp_design import convex_weights, cp_model_set
from fdikit.multimodel.lv_design import limit_value_model_set
from fdikit.multimodel.model_set import (
    affine_weights,
    first_order_discretize,
    gap_rank,
    nearest_model,
    taylor_remainder_bound,
    unvectorize,
    vectorize,
)
from fdikit.multimodel.observability import minimum_mismatch_points, observability_condition
from fdikit.multimodel.od_design import od_model_set, pivoted_qr
from fdikit.plants.msd import (
    MSD_RANGES,
    msd_matrices,
    msd_model_vectors,
    msd_parameter_grid,
    msd_parameters_to_weights,
    msd_weights_to_parameters,
)


def test_vectorize_round_trip_and_column_order():
    rng = np.random.default_rng(1)
    A, B, C, D = rng.normal(size=(3, 3)), rng.normal(size=(3, 2)), rng.normal(size=(2, 3)), rng.normal(size=(2, 2))
    v = vectorize(A, B, C, D)
    np.testing.assert_array_equal(v[:3], A[:, 0])  # (3.14): vec stacks the columns of [A B; C D]
    np.testing.assert_array_equal(v[3:5], C[:, 0])
    for X, Y in zip(unvectorize(v, 3, 2, 2), (A, B, C, D)):
        np.testing.assert_array_equal(X, Y)
    with pytest.raises(ModelError, match="entries"):
        unvectorize(v, 3, 2, 3)


# ------------------------------------------------------------------ App. B (item 5)
def test_first_order_discretisation_commutes_with_convex_combination():
    """(B.8)–(B.9): Σ μ_i (I + T A_i) = I + T Σ μ_i A_i when Σ μ_i = 1."""
    rng = np.random.default_rng(2)
    As, Bs = rng.normal(size=(4, 5, 5)), rng.normal(size=(4, 5, 2))
    mu = rng.dirichlet(np.ones(4))
    lhs_A = sum(m * first_order_discretize(A, B, 0.01)[0] for m, A, B in zip(mu, As, Bs))
    lhs_B = sum(m * first_order_discretize(A, B, 0.01)[1] for m, A, B in zip(mu, As, Bs))
    rhs_A, rhs_B = first_order_discretize(np.tensordot(mu, As, 1), np.tensordot(mu, Bs, 1), 0.01)
    np.testing.assert_allclose(lhs_A, rhs_A, atol=1e-14)
    np.testing.assert_allclose(lhs_B, rhs_B, atol=1e-15)


def test_taylor_bound_value_and_that_it_bounds_the_remainder():
    """(B.5): ‖A‖ = 3, T = 0.01, M = 1 gives (0.03)²/2/(1 − 0.01) = 4.545e-4 (§4.3.1 "order 1e-4")."""
    assert taylor_remainder_bound(3.0, 0.01, 1) == pytest.approx(0.03 ** 2 / 2 / 0.99, rel=1e-12)
    assert taylor_remainder_bound(3.0, 0.01, 1) == pytest.approx(4.545e-4, rel=1e-3)
    rng = np.random.default_rng(3)
    A = rng.normal(size=(5, 5))
    A *= 3.0 / np.abs(A).sum()  # ‖A‖ (B.7) = 3
    remainder = scipy.linalg.expm(0.01 * A) - first_order_discretize(A, np.zeros((5, 1)), 0.01)[0]
    assert np.abs(remainder).max() <= taylor_remainder_bound(A, 0.01, 1)
    with pytest.raises(DesignError, match="reduce the sample time"):
        taylor_remainder_bound(3.0, 1.0, 1)


def test_first_order_discretisation_error_is_second_order():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(4, 4))
    errors = [np.abs(scipy.linalg.expm(T * A) - first_order_discretize(A, np.eye(4), T)[0]).max()
              for T in (0.01, 0.005, 0.0025)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)  # halving T divides the error by 4: O(T²)


def test_gap_rank():
    assert gap_rank([3.0, 0.943, 0.0222, 0.00739, 0.00237, 1e-15, 3e-16]) == 5
    assert gap_rank([1.0, 0.5, 0.25]) == 3  # no significant gap: full rank
    assert gap_rank([2.0, 0.0, 0.0]) == 1


# ------------------------------------------------------------------ OD (item 6, Fig. 3.1)
def _blob(rng, n=1000):
    return np.vstack([rng.gamma(2.0, 1.0, n) + 1.0, rng.normal(0.0, 0.5, n) + 0.3 * rng.gamma(2.0, 1.0, n)])


def test_od_random_2d_models_three_members_exact_affine_representation():
    """§3.3.2, Fig. 3.1: 1000 random 2-D models → N_r = 2, 3 models, every model exactly representable."""
    rng = np.random.default_rng(5)
    M = _blob(rng)
    od = od_model_set(M)
    assert od.rank == 2 and len(od.indices) == 3
    np.testing.assert_array_equal(od.models, M[:, list(od.indices)])  # members of M_ℓ
    assert od.residual.max() < 1e-10
    np.testing.assert_allclose(od.weights.sum(axis=0), 1.0, atol=1e-12)  # affine projection (3.21)
    # "well separated": the selected simplex is better conditioned than 90 % of random triples
    cond = np.linalg.cond(np.vstack([od.models, np.ones(3)]))
    random_conds = [np.linalg.cond(np.vstack([M[:, idx], np.ones(3)]))
                    for idx in (rng.choice(M.shape[1], 3, replace=False) for _ in range(400))]
    assert cond < np.quantile(random_conds, 0.10)


def test_affine_projection_is_the_stacked_least_squares_and_exact_in_the_affine_hull():
    rng = np.random.default_rng(6)
    Mr, M = rng.normal(size=(8, 4)), rng.normal(size=(8, 30))
    W = affine_weights(Mr, M)
    assert W.shape == (4, 30)
    stacked = np.linalg.lstsq(np.vstack([Mr, np.ones(4)]), np.vstack([M, np.ones(30)]), rcond=None)[0]
    np.testing.assert_allclose(W, stacked, atol=1e-12)  # (3.21) literally
    inside = Mr @ rng.dirichlet(np.ones(4), 30).T + Mr @ (rng.normal(size=30) * np.array([[1.0], [-1.0], [0.0], [0.0]]))
    np.testing.assert_allclose(affine_weights(Mr, inside).sum(axis=0), 1.0, atol=1e-12)
    with pytest.raises(ModelError, match="entries"):
        affine_weights(Mr, M[:5])


def test_pivoted_qr_matches_lapack_without_ties():
    """Without ties the pivots and |diag R| are those of Businger–Golub (LAPACK geqp3)."""
    M = np.random.default_rng(11).normal(size=(8, 12)) * np.logspace(0, -3, 12)
    piv, d = pivoted_qr(M)
    _, R, lapack = scipy.linalg.qr(M, mode="economic", pivoting=True)
    np.testing.assert_array_equal(piv, lapack)
    np.testing.assert_allclose(d, np.abs(np.diag(R)), rtol=1e-10)


@given(st.integers(0, 2**32 - 1), st.floats(1e-15, 1e-12))
def test_pivoted_qr_ties_are_decided_by_the_key_not_by_rounding(seed, noise):
    """Exact ties (a duplicated column) and a rank-deficient tail (7 columns of rank 5 in 6 rows: the 6th
    step finds every residual numerically zero): relative perturbations of 1e-15 to 1e-12, above the
    rounding differences between BLAS kernels, never change the pivots; ties go to the lowest priority."""
    rng = np.random.default_rng(seed)
    base = rng.normal(size=(6, 5))
    M = np.hstack([base, base[:, :1], base[:, 1:3] @ [[1.0], [-2.0]]])  # col 5 = col 0, col 6 in the span
    piv, d = pivoted_qr(M)
    assert d[5] <= 1e-12 * d[0] and d[4] > 1e-6 * d[0]  # rank 5
    for _ in range(3):
        shaken = M * (1 + noise * rng.standard_normal(M.shape))
        np.testing.assert_array_equal(pivoted_qr(shaken)[0], piv)
    assert list(piv).index(0) < list(piv).index(5)  # the twins tie; the lower index wins
    assert piv[5] == min(set(range(7)) - set(piv[:5].tolist()))  # zero-residual step: lowest free index
    prio = np.zeros(7)
    prio[0] = 1.0  # column 5 now preferred to its twin
    piv2, _ = pivoted_qr(M, priority=prio)
    assert list(piv2).index(5) < list(piv2).index(0)


def test_pivoted_qr_bad_arguments():
    with pytest.raises(ParameterError, match="tie_tol"):
        pivoted_qr(np.eye(2), tie_tol=1.5)
    with pytest.raises(ParameterError, match="tie_tol"):
        pivoted_qr(np.eye(2), tie_tol="small")
    with pytest.raises(ParameterError, match="priority"):
        pivoted_qr(np.eye(2), priority=[0.0])
    with pytest.raises(ParameterError, match="priority"):
        pivoted_qr(np.eye(2), priority=["a", "b"])
    with pytest.raises(ParameterError, match="rank"):
        od_model_set(np.eye(3), rank=0)


def test_od_rejects_too_many_models_and_bad_input():
    with pytest.raises(DesignError, match="requested"):
        od_model_set(np.eye(3), rank=3)
    with pytest.raises(ModelError, match="NaN"):
        od_model_set([[1.0, np.nan], [0.0, 1.0]])


# ------------------------------------------------------------------ CP (item 7)
def test_cp_random_2d_simplex_encloses_every_sample():
    """§3.4, Fig. 3.3: N_h = n_g + 1 = 3 vertices; every sample in the polytope (LP check, (3.30))."""
    rng = np.random.default_rng(7)
    M = _blob(rng)
    cp = cp_model_set(M)
    assert cp.vertices.shape == (2, 3)
    for j in range(0, M.shape[1], 7):
        lam = convex_weights(cp.vertices, cp.coordinates[:, j])
        assert lam is not None and lam.min() >= -1e-12
    np.testing.assert_allclose(cp.vertices @ cp.weights, cp.coordinates, atol=1e-10)
    assert cp.weights.min() >= -1e-12
    np.testing.assert_allclose(cp.weights.min(axis=1), 0.0, atol=1e-12)  # every facet touches a sample
    np.testing.assert_allclose(cp.basis @ cp.coordinates, M, atol=1e-10)  # rank-2 SVD is exact here
    # J_CP (3.29) is positive (vertices outside the data hull) and matches a direct distance computation
    hull = scipy.spatial.ConvexHull(cp.coordinates.T)
    assert cp.cost > 0
    outside = [not np.all(hull.equations[:, :2] @ v + hull.equations[:, 2] <= 1e-9) for v in cp.vertices.T]
    assert all(outside)


def test_convex_weights_rejects_outside_point():
    V = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    assert convex_weights(V, [0.6, 0.6]) is None
    np.testing.assert_allclose(V @ convex_weights(V, [0.2, 0.3]), [0.2, 0.3], atol=1e-9)


# ------------------------------------------------------------------ MSD design (item 20, §3.6.1)
@pytest.fixture(scope="module")
def msd_large_set():
    params = msd_parameter_grid()
    return params, msd_model_vectors(params)


def test_msd_od_rank_five_and_six_models(msd_large_set):
    """§3.6.1/Fig. 3.5: numerical rank 5 from σ and |diag R| (clear gap) → 6 local models."""
    params, M = msd_large_set
    od = od_model_set(M)
    assert gap_rank(od.singular_values) == 5 and od.rank == 5
    assert od.singular_values[4] / od.singular_values[5] > 1e9
    assert od.diag_r[4] / od.diag_r[5] > 1e11
    # |diag R| of (3.19) (independent computation, grid-independent): 3.0, 0.943, 0.0222, 0.00739, 0.00237
    np.testing.assert_allclose(od.diag_r[:5], [3.0, 0.943, 0.0222, 0.00739, 0.00237], rtol=3e-3)
    assert len(od.indices) == 6
    chosen = params[list(od.indices)]
    assert np.any(chosen[:, 2] == 0.0) and np.any(chosen[:, 3] == 0.0)  # actuator- and sensor-fault models
    corners = [(k1, m3) for k1, m3 in chosen[:, :2] if k1 in MSD_RANGES["k1"] and m3 in MSD_RANGES["m3"]]
    assert len(corners) >= 4  # limit-corner models (Table 3.2 has 5 of 6 at corners)
    assert od.residual.max() < 1e-12  # the model vectors are affine in (k1, 1/m3, f1, f2): exact representation


def test_msd_od_fault_weights_track_fault_parameters(msd_large_set):
    """Fig. 3.9 idea: with the OD weights, f1 = 1 − Σ(weights of f1 = 0 models) for models with m3, k1 at OD nodes."""
    params, M = msd_large_set
    od = od_model_set(M)
    chosen = params[list(od.indices)]
    # the f1 coordinate is affine in the model vector, so it is the weighted sum of the chosen models' f1
    np.testing.assert_allclose(od.weights.T @ chosen[:, 2], params[:, 2], atol=1e-9)
    np.testing.assert_allclose(od.weights.T @ chosen[:, 3], params[:, 3], atol=1e-9)
    # parameter reconstruction (3.52) returns the exact grid model
    j = 1234
    assert nearest_model(M, od.models @ od.weights[:, j]) == j


@pytest.mark.parametrize("n_vertices", [None, 6])
def test_msd_cp_encloses_every_model(msd_large_set, n_vertices):
    """§3.6.1: n_g = 5; the thesis uses N_h = 6 vertices.  Every large-set model is a convex combination."""
    _, M = msd_large_set
    cp = cp_model_set(M, n_vertices=n_vertices)
    assert cp.basis.shape[1] == 5  # n_g = 5
    assert cp.vertices.shape[1] == (5 if n_vertices is None else 6)  # default d + 1, affine dimension d = 4
    np.testing.assert_allclose(cp.basis @ cp.vertices @ cp.weights, M, atol=1e-7)  # LP weights, tol 1e-9·scale
    assert cp.weights.min() >= -1e-12
    np.testing.assert_allclose(cp.weights.sum(axis=0), 1.0, atol=1e-9)
    for j in range(0, M.shape[1], 120):
        assert convex_weights(cp.vertices, cp.coordinates[:, j]) is not None


def test_cp_cost_falls_with_more_vertices():
    """Fig. 3.3: more vertices give a tighter polytope; the J_CP fit (3.29) beats the start simplex.

    Measured on the 2-D blob: simplex 81.9 → fitted 25.4 (3 vertices), 6.45 (4), 3.14 (5)."""
    rng = np.random.default_rng(0)
    P = rng.normal(size=(2, 300)) * [[2.0], [1.0]]
    costs = [cp_model_set(P, rank=2, optimize=False).cost]
    costs += [cp_model_set(P, rank=2, n_vertices=k).cost for k in (3, 4, 5)]
    assert costs[1] < 0.5 * costs[0]
    assert costs[1] > costs[2] > costs[3]
    with pytest.raises(DesignError, match="at least d"):
        cp_model_set(P, rank=2, n_vertices=2)


# ------------------------------------------------------------------ LV (item 8, §3.5, (3.44)–(3.57))
def _msd_lv(dt=None):
    upper = {"k1": MSD_RANGES["k1"][1], "m3": MSD_RANGES["m3"][1], "f1": 1.0, "f2": 1.0}
    lower = {"k1": MSD_RANGES["k1"][0], "m3": MSD_RANGES["m3"][0], "f1": 0.0, "f2": 0.0}
    return limit_value_model_set(msd_matrices, upper, lower, dt=dt)


def test_lv_delta_matrices_match_thesis_formulas():
    """(3.46)–(3.49), with the A^{k1}(5, 2) sign and the two-column B⁺ corrected."""
    lv = _msd_lv()
    (k1lo, k1hi), (m3lo, m3hi) = MSD_RANGES["k1"], MSD_RANGES["m3"]
    Ak1 = np.zeros((6, 6))
    Ak1[3, :2] = [k1hi - k1lo, k1lo - k1hi]
    Ak1[4, :2] = [k1lo - k1hi, k1hi - k1lo]
    np.testing.assert_allclose(lv.deltas[0][0], Ak1, atol=1e-14)
    Am3 = np.zeros((6, 6))
    Am3[5] = (1 / m3lo - 1 / m3hi) * np.array([1.0, 0.2, -1.2, 0.01, 0.01, -0.02])
    np.testing.assert_allclose(lv.deltas[1][0], Am3, atol=1e-13)
    np.testing.assert_allclose(lv.deltas[1][1][5], [0.0, 1 / m3lo - 1 / m3hi], atol=1e-14)
    np.testing.assert_allclose(lv.deltas[2][1][3], [-1.0, 0.0])
    np.testing.assert_allclose(lv.deltas[3][2], -np.outer(np.eye(3)[1], np.eye(6)[1]))
    np.testing.assert_allclose(lv.offset[1], [[0, 0]] * 3 + [[1, 0], [0, 0], [0, 1 / m3hi]])


def test_lv_weights_reproduce_exact_msd_matrices():
    """(3.54)–(3.57): LV model at the mapped weights = exact MSD (continuous and first-order discrete)."""
    rng = np.random.default_rng(8)
    lv, lv_d = _msd_lv(), _msd_lv(dt=2.5e-3)
    for _ in range(50):
        k1, m3, f = rng.uniform(*MSD_RANGES["k1"]), rng.uniform(*MSD_RANGES["m3"]), rng.uniform(0, 1)
        f1, f2 = (f, 1.0) if rng.random() < 0.5 else (1.0, f)
        mu = msd_parameters_to_weights(k1, m3, f1, f2)
        assert np.all((mu >= 0) & (mu <= 1))
        A, B, C = msd_matrices(k1, m3, f1, f2)
        Al, Bl, Cl, Dl = lv.model(mu)
        np.testing.assert_allclose(Al, A, atol=1e-13)
        np.testing.assert_allclose(Bl, B, atol=1e-13)
        np.testing.assert_allclose(Cl, C, atol=1e-15)
        np.testing.assert_array_equal(Dl, 0.0)
        Ad, Bd, _, _ = lv_d.model(mu)
        np.testing.assert_allclose(Ad, np.eye(6) + 2.5e-3 * A, atol=1e-15)
        np.testing.assert_allclose(Bd, 2.5e-3 * B, atol=1e-15)
        np.testing.assert_allclose(msd_weights_to_parameters(mu), (k1, m3, f1, f2), rtol=1e-12)
    # interval centres: μ_k1 = 0.5, μ_m3 = 0.1 at k1 = m3 = 1
    np.testing.assert_allclose(msd_parameters_to_weights(1.0, 1.0, 1.0, 1.0), [0.5, 0.1, 0.0, 0.0], atol=1e-15)
    with pytest.raises(DesignError, match=r"\[0, 1\]"):
        lv.model([0.5, 1.5, 0.0, 0.0])
    with pytest.raises(DesignError, match="same parameters"):
        limit_value_model_set(msd_matrices, {"k1": 1.75}, {"m3": 0.2})


# ------------------------------------------------------------------ minimum mismatch (item 9, §3.6.4)
def test_minimum_mismatch_two_regions():
    """(3.58): N(1, 0.2²), 2 equiprobable regions → m3 = 0.865 and 1.135 (§3.6.4, Fig. 3.14)."""
    pts = minimum_mismatch_points(norm(1.0, 0.2), 2)
    np.testing.assert_allclose(pts, [0.8651, 1.1349], atol=5e-5)
    np.testing.assert_allclose(norm(1.0, 0.2).cdf(pts), [0.25, 0.75])
    with pytest.raises(DesignError, match="ppf"):
        minimum_mismatch_points([1.0, 0.2], 2)


# ------------------------------------------------------------------ observability (Def. 3.1, item 19)
def test_observability_matrix_of_a_linear_system_is_the_kalman_matrix():
    rng = np.random.default_rng(9)
    A, C = rng.normal(size=(3, 3)), rng.normal(size=(1, 3))
    cond, J = observability_condition(lambda x, u: A @ x + u, lambda x: C @ x, rng.normal(size=3), np.ones((2, 3)))
    O = np.vstack([C, C @ A, C @ A @ A])
    np.testing.assert_allclose(J, O, atol=1e-8)
    assert cond == pytest.approx(np.linalg.cond(O), rel=1e-6)


def test_pair_observability_of_identical_models_is_singular():
    """Two identical local models make the weight unobservable (cond = inf); distinct ones give a finite
    condition number equal to the direct Jacobian's (3.7)–(3.9)."""
    from fdikit.multimodel.observability import pair_observability

    A, B, C = np.array([[0.9, 0.2], [-0.1, 0.8]]), np.array([0.1, 0.3]), np.array([[1.0, 0.0]])
    assert pair_observability((A, B), (A, B), C, [np.array([0.5, -0.2])], [0.3], [1.0]) == np.inf
    A2 = A + 0.1
    x, m = np.array([0.5, -0.2]), 0.3
    step = lambda z, u: np.concatenate([z[2] * (A @ z[:2] + B * u[0]) + (1 - z[2]) * (A2 @ z[:2] + B * u[0]), z[2:]])  # noqa: E731
    direct = observability_condition(step, lambda z: C @ z[:2], np.append(x, m), np.ones((2, 1)))[0]
    assert pair_observability((A, B), (A2, B), C, [x], [m], [1.0]) == pytest.approx(direct, rel=1e-12)
