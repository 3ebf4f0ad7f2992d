"""Robust uncertain-LPV parity design (Varrier, Koenig & Martinez 2014, §4).

Oracles: random and optimised Rayleigh quotients (scipy.optimize), an orthonormal null-space
basis (scipy), the closed-form minimisers of 𝒫₂ (Lagrange) and of the sign-enumerated ‖W₂‖₁
constraint, eigenvalue checks of every returned LMI matrix, det·inv for the adjugate, and the
moment-curve identity of the Property-1 simplex.  Where an independent reconstruction of the
example gave a number, it is quoted as such.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from fdikit.design.parity.criteria import (
    gamma_kappa,
    kappa_max,
    p2_solution,
    robust_criteria,
    theorem1,
    theorem1_batch,
)
from fdikit.design.parity.lmi import lti_lmi
from fdikit.design.parity.polytope import (
    adjugate,
    box_vertices,
    is_admissible,
    polynomial_coefficients,
    polytopic_lmi,
    property1_vertices,
    repair_vertex,
    scheduling_weights,
)
from fdikit.design.parity.robust import robust_lpv_parity
from fdikit.design.parity.state_space import parity_matrix
from fdikit.errors import DesignError, ParameterError
from fdikit.lpv import lpv_stacked_matrices
from fdikit.plants.varrier_lateral import varrier_lateral_lpv, varrier_uncertainty

LPV = varrier_lateral_lpv()
UNC = [varrier_uncertainty()]


@pytest.fixture(scope="module")
def crit48():
    return robust_criteria(LPV, UNC, 0.048, 3)


@pytest.fixture(scope="module")
def design():
    return robust_lpv_parity(LPV, UNC, 3, kappa=0.1, rho_max=0.2, rho_nominal=0.048)


def _J(w, c):
    return float(w @ c.gamma1 @ w / (w @ c.gamma2 @ w))


def test_gammas_are_symmetric_psd_with_the_expected_ranks(crit48):
    """Note item 8: Γ₁, Γ₂ symmetric PSD; rank Γ₂ = (s+1) l_f = 4; G is 8 × 26 (note item 4)."""
    c = crit48
    assert c.G.shape == (8, 26) and c.gamma1.shape == (6, 6)
    for M in (c.gamma1, c.gamma2):
        np.testing.assert_allclose(M, M.T, atol=1e-12 * np.abs(M).max())
        assert np.linalg.eigvalsh(M)[0] > -1e-10 * np.abs(M).max()
    assert np.linalg.matrix_rank(c.gamma2, tol=1e-10 * np.abs(c.gamma2).max()) == 4
    assert np.linalg.eigvalsh(c.gamma1)[0] > 0.04  # Γ₁ ≻ 0: no perfect decoupling (15) at s = 3
    const = robust_criteria(LPV, UNC, 0.048, 3, fault_model="constant")
    assert np.linalg.matrix_rank(const.gamma2, tol=1e-10) == 1
    np.testing.assert_allclose(const.gamma2, np.outer(c.fault_direction, c.fault_direction), rtol=1e-12)


def test_theorem1_attains_the_minimum(crit48):
    """Note item 8: J(W₂*) = λ_min; random and locally optimised W₂ never do better.

    λ_min(0.048) = 0.040359 and W₂* as in an independent reconstruction."""
    c = crit48
    e = theorem1(c.gamma1, c.gamma2, sign_ref=c.fault_direction)
    assert _J(e.W2, c) == pytest.approx(e.lambda_min, rel=1e-10)
    assert e.lambda_min == pytest.approx(0.040359, abs=5e-7)
    np.testing.assert_allclose(e.W2, [0.64403, -0.11946, -0.70734, 0.04556, 0.26173, -0.00696], atol=5e-6)
    assert e.eigenvalues[0] == pytest.approx(0.0404, abs=5e-5) and e.eigenvalues[1] == pytest.approx(8.864, abs=5e-4)
    rng = np.random.default_rng(0)
    assert min(_J(w, c) for w in rng.standard_normal((3000, 6))) >= e.lambda_min
    for w0 in rng.standard_normal((4, 6)):
        res = scipy.optimize.minimize(lambda w: _J(w, c), w0, method="BFGS")
        assert e.lambda_min <= res.fun <= e.lambda_min * (1 + 1e-5)
    lam_b, w_b = theorem1_batch(c.gamma1[None], c.gamma2[None], c.fault_direction[None])
    assert lam_b[0] == pytest.approx(e.lambda_min, rel=1e-10)
    np.testing.assert_allclose(w_b[0], e.W2, atol=1e-8)


def test_theorem1_does_not_depend_on_the_parity_basis(crit48):
    """Note item 8: an orthonormal (SVD) basis of the left null space gives the same λ_min and W."""
    c = crit48
    us_H = lpv_stacked_matrices(LPV, 0.048, 3).H_os
    N = scipy.linalg.null_space(us_H.T).T  # another basis: N = T P
    T = N @ np.linalg.pinv(c.P)
    G1, G2 = T @ c.gamma1 @ T.T, T @ c.gamma2 @ T.T
    e, e2 = theorem1(c.gamma1, c.gamma2), theorem1(G1, G2)
    assert e2.lambda_min == pytest.approx(e.lambda_min, rel=1e-9)
    W, W_svd = c.P.T @ e.W2, N.T @ e2.W2
    assert abs(W @ W_svd) / (np.linalg.norm(W) * np.linalg.norm(W_svd)) == pytest.approx(1.0, abs=1e-10)


def test_theorem1_with_exact_decoupling():
    """Singular Γ₁: λ_min = 0 and W₂ ∈ null Γ₁ maximising Γ₂."""
    G1 = np.diag([1.0, 0.0, 0.0])
    G2 = np.diag([5.0, 1.0, 3.0])
    e = theorem1(G1, G2)
    assert e.lambda_min == 0.0
    np.testing.assert_allclose(np.abs(e.W2), [0, 0, 1], atol=1e-12)
    with pytest.raises(DesignError, match="not detectable"):
        theorem1(np.eye(2), np.zeros((2, 2)))


def test_gamma_kappa_is_pd_iff_kappa_squared_below_lambda_min():
    """Note item 9 (re-derived: wᵀΓ₁w > κ²wᵀΓ₂w ∀w ⇔ κ² < min J) on a grid of ρ and κ."""
    for rho in (0.0, 0.048, 0.1, 0.2):
        c = robust_criteria(LPV, UNC, rho, 3)
        lam = theorem1(c.gamma1, c.gamma2).lambda_min
        for f in (0.5, 0.9, 0.999, 1.001, 1.1, 2.0):
            kappa = np.sqrt(f * lam)
            pd = np.linalg.eigvalsh(c.gamma1 - kappa**2 * c.gamma2)[0] > 0
            assert pd == (f < 1)
            if f < 1:
                gamma_kappa(c.gamma1, c.gamma2, kappa)
            else:
                with pytest.raises(DesignError, match="κ_max"):
                    gamma_kappa(c.gamma1, c.gamma2, kappa)


def test_paper_kappa_27_is_refused_with_the_largest_valid_kappa():
    """§5.3 κ = 27 makes Γ_κ indefinite for every ρ; κ_max = sqrt(min λ_min) = 0.149 on [0, 0.2]."""
    grid = robust_criteria(LPV, UNC, np.linspace(0, 0.2, 41), 3)
    k_max = kappa_max(grid.gamma1, grid.gamma2)
    assert k_max == pytest.approx(np.sqrt(0.0222147), rel=1e-4)  # λ_min at ρ = 0 (independent reconstruction: 0.0222)
    with pytest.raises(DesignError, match=r"largest valid κ is 0\.1490"):
        robust_lpv_parity(LPV, UNC, 3, kappa=27.0, rho_max=0.2)
    c = robust_criteria(LPV, UNC, 0.048, 3)
    assert np.linalg.eigvalsh(c.gamma1 - 27.0**2 * c.gamma2)[0] < 0
    assert np.linalg.eigvalsh(c.gamma1 - 27.0**-2 * c.gamma2)[0] > 0  # the 'inverse' reading 1/27 is valid


def test_p2_converges_to_theorem1_as_kappa_squared_approaches_lambda_min(crit48):
    """Note item 9: the 𝒫₂ minimiser with cᵀW₂ = 1 tends to the Theorem-1 eigenvector."""
    c = crit48
    e = theorem1(c.gamma1, c.gamma2)
    ones = np.ones(6)
    angles = []
    for f in (0.5, 0.9, 0.99, 0.9999):
        w = p2_solution(c.gamma1, c.gamma2, np.sqrt(f * e.lambda_min), ones)
        assert ones @ w == pytest.approx(1.0)
        angles.append(np.arccos(min(1.0, abs(w @ e.W2) / np.linalg.norm(w))))
    assert all(a > b for a, b in itertools.pairwise(angles)) and angles[-1] < 1e-3


def test_lti_lmi_matches_the_closed_form(crit48):
    """Note item 10: the SDP (27)/(31) with cᵀW₂ = 1 equals Γ_κ⁻¹c/(cᵀΓ_κ⁻¹c); the returned matrix is PSD."""
    c = crit48
    kappa = 0.15
    lmi = lti_lmi(c.gamma1, c.gamma2, kappa)
    w = p2_solution(c.gamma1, c.gamma2, kappa, np.ones(6))
    np.testing.assert_allclose(lmi.W2, w, rtol=1e-5, atol=1e-6 * np.abs(w).max())
    Gk = c.gamma1 - kappa**2 * c.gamma2
    assert lmi.gamma == pytest.approx(w @ Gk @ w, rel=1e-5)
    assert lmi.min_eig > -1e-7
    block = np.block([[np.linalg.inv(Gk), lmi.W2[:, None]], [lmi.W2[None], np.array([[lmi.gamma * 1.0001]])]])
    assert np.linalg.eigvalsh(block)[0] > -1e-9 * np.abs(block).max()


def test_l1_normalisation_by_sign_enumeration_matches_brute_force(crit48):
    """Note item 10: min wᵀΓ_κw s.t. ‖w‖₁ ≥ ε = max over σ of the closed form ε²/(σᵀΓ_κ⁻¹σ)."""
    c = crit48
    kappa, eps = 0.15, 1.0
    lmi = lti_lmi(c.gamma1, c.gamma2, kappa, normalization="l1", eps=eps)
    Gi = np.linalg.inv(c.gamma1 - kappa**2 * c.gamma2)
    best = min(itertools.product((1.0, -1.0), repeat=6), key=lambda sg: eps**2 / (np.array(sg) @ Gi @ np.array(sg)))
    sg = np.array(best) * best[0]
    w = eps * Gi @ sg / (sg @ Gi @ sg)
    assert lmi.gamma == pytest.approx(eps**2 / (sg @ Gi @ sg), rel=1e-5)
    np.testing.assert_array_equal(lmi.sign, sg)
    np.testing.assert_allclose(lmi.W2, w, rtol=1e-4, atol=1e-5 * np.abs(w).max())
    assert np.abs(lmi.W2).sum() >= eps * (1 - 1e-6)


def test_property1_polytope():
    """Note item 11: N+1 of the 2^N box vertices satisfy (46) (coordinates {0, ρ_max^j}); weights ≥ 0,
    sum to 1 and reproduce the moment curve (ρ, ρ², …, ρ^N)."""
    N, rmax = 5, 0.2
    box = box_vertices(N, rmax)
    assert box.shape == (32, 5)
    admissible = box[[is_admissible(v, rmax) for v in box]]
    P1 = property1_vertices(N, rmax)
    assert len(admissible) == N + 1 == len(P1)
    assert {tuple(v) for v in admissible} == {tuple(v) for v in P1}
    literal = np.array(list(itertools.product((0.0, rmax), repeat=N)))  # (46) with ν ∈ {0, ρ_max} as printed
    assert sum(is_admissible(v, rmax) for v in literal) == 2
    rho = np.linspace(0, rmax, 101)
    a = scheduling_weights(rho, N, 0.0, rmax)
    assert a.min() >= 0 and np.allclose(a.sum(axis=1), 1, atol=1e-15)
    np.testing.assert_allclose(a @ P1, rho[:, None] ** np.arange(1, N + 1), atol=1e-16)


def test_adjugate_polynomial_and_vertex_identity():
    """Note item 11: Σ α̃_j Γ̃_j = adj Γ_κ(ρ) exactly before truncation, = det(Γ_κ) Γ_κ⁻¹ (the α₀ identity)."""
    kappa, rmin, rmax = 0.1, 0.02, 0.2

    def gk(r):
        c = robust_criteria(LPV, UNC, r, 3, rows=(0, 1))
        return c.gamma1 - kappa**2 * c.gamma2

    M, deg = polynomial_coefficients(lambda r: adjugate(gk(r)), rmin, rmax)
    V = np.cumsum(M, axis=0)
    for rho in (0.02, 0.0333, 0.07, 0.15, 0.2):
        G = gk(rho)
        exact = np.linalg.det(G) * np.linalg.inv(G)
        np.testing.assert_allclose(adjugate(G), exact, rtol=1e-8, atol=1e-10 * np.abs(exact).max())
        poly = np.tensordot(scheduling_weights(rho, deg, rmin, rmax), V, axes=1)
        np.testing.assert_allclose(poly, exact, rtol=1e-6, atol=1e-9 * np.abs(exact).max())
    with pytest.raises(DesignError, match="not a polynomial"):
        polynomial_coefficients(lambda r: 1 / (r - 1.5), 0.0, 1.0)


def test_degrees_of_gamma1_and_gamma2_by_least_squares():
    """§5.3 '6 products' (Γ₂): ρ-degrees 8 (Γ₁) and 6 (Γ₂), confirmed by polynomial fits on a real grid."""
    rho = np.linspace(0, 1, 40)
    c = robust_criteria(LPV, UNC, rho, 3, rows=(0, 1))
    for M, deg in ((c.gamma2, 6), (c.gamma1, 8)):
        Y = M.reshape(len(rho), -1)
        P = np.polynomial.polynomial
        fits = [np.abs(P.polyval(rho, P.polyfit(rho, Y, d)).T - Y).max() / np.abs(Y).max() for d in (deg - 1, deg)]
        assert fits[0] > 1e-6 and fits[1] < 1e-9


def test_vertex_repair_keeps_eigenvectors_and_positive_eigenvalues():
    """Note item 11 / (41)–(42): repaired vertices are PD, same eigenvectors, positive eigenvalues unchanged."""
    rng = np.random.default_rng(3)
    Q = np.linalg.qr(rng.standard_normal((5, 5)))[0]
    d = np.array([-3.0, -0.5, 0.2, 1.0, 4.0])
    M = (Q * d) @ Q.T
    for mode, new in (("paper", 40.0), ("inverse", 0.02)):
        F, count = repair_vertex(M, mode, factor=10.0)
        assert count == 2
        dF, VF = np.linalg.eigh(F)
        np.testing.assert_allclose(np.sort(dF), np.sort([new, new, 0.2, 1.0, 4.0]), rtol=1e-12)
        for k in (2, 3, 4):  # eigenvectors of the kept eigenvalues
            np.testing.assert_allclose(F @ Q[:, k], d[k] * Q[:, k], atol=1e-12)
        np.testing.assert_allclose(F @ Q[:, 0], new * Q[:, 0], atol=1e-12)
    F, count = repair_vertex(np.eye(3))
    assert count == 0 and np.array_equal(F, np.eye(3))
    with pytest.raises(ParameterError, match="repair"):
        repair_vertex(M, "clip")


def test_scheduled_w2_is_continuous_nonzero_and_decouples(design):
    """Note item 12 and the LMI feasibility check: cᵀW₂(ρ) = 1, Lipschitz in ρ, W(ρ)ᵀH_os(ρ) = 0."""
    d = design
    assert d.order == 5 and d.W_vertices.shape == (6, 6) and len(d.vertices) == 6
    assert d.n_repaired == (0, 3, 1, 4, 0, 4)  # independent: vertex minimum eigenvalues 41, −2.0e7, −1.3e4, …
    np.testing.assert_allclose([np.linalg.eigvalsh(V)[0] for V in d.vertices[[0, 1, 4]]], [41.24, -1.994e7, 3985.0],
                               rtol=1e-3)
    for V, W, g in zip(d.repaired, d.W_vertices, d.gamma):  # every vertex LMI (39) holds at the returned point
        assert np.linalg.eigvalsh(V)[0] > 0
        blk = np.block([[V, W[:, None]], [W[None], np.array([[g * (1 + 1e-6)]])]])
        assert np.linalg.eigvalsh(blk / np.abs(blk).max())[0] > 0
        assert d.c @ W == pytest.approx(1.0, abs=1e-7)
    assert np.ptp(d.gamma) == 0  # one common γ' (40)
    rho = np.linspace(0, 0.2, 401)
    w = d.w2(rho)
    np.testing.assert_allclose(w @ d.c, 1.0, atol=1e-7)
    assert np.linalg.norm(w, axis=1).min() > 0.5
    steps = [np.abs(d.w2(rho + h) - w).max() for h in (1e-4, 5e-5)]
    assert steps[0] / steps[1] == pytest.approx(2.0, rel=0.05)
    H = lpv_stacked_matrices(LPV, rho, 3).H_os
    WT = np.einsum("kq,kqj->kj", w, parity_matrix(H, d.rows))
    assert np.abs(np.einsum("kj,kjn->kn", WT, H)).max() < 1e-12 * np.abs(WT).max() * np.abs(H).max()


def test_polytopic_lmi_against_the_per_vertex_closed_form(design):
    """With cᵀW_i = 1 the vertex LMIs (39) decouple: W_i = Γ̌_i c / (cᵀΓ̌_i c), bound 1/(cᵀΓ̌_i c) (Lagrange);
    the common γ' of (40) is the largest of them."""
    V, c = design.repaired, design.c
    bound = np.array([1 / (c @ Vi @ c) for Vi in V])
    assert design.gamma[0] == pytest.approx(bound.max(), rel=1e-6)
    per = polytopic_lmi(V, c, objective="sum")
    np.testing.assert_allclose(per.gamma, bound, rtol=1e-6)
    for Vi, Wi in zip(V, per.W):
        ref = Vi @ c / (c @ Vi @ c)
        np.testing.assert_allclose(Wi, ref, rtol=1e-4, atol=1e-6 * np.abs(ref).max())
    with pytest.raises(DesignError, match="not positive definite"):
        polytopic_lmi(design.vertices, c)  # the raw prefix-sum vertices 1, 2, 3, 5 are indefinite (Remark 6)
    with pytest.raises(ParameterError, match="objective"):
        polytopic_lmi(V, c, objective="max")


def test_design_report_counts_and_adjugate_variant(design):
    """§5.3 counts are reported, not asserted equal to the paper (6/14 products, 2^14 box, 6 vertices)."""
    d = design
    assert d.degrees == {"gamma1": 8, "gamma2": 6, "det": 18, "adjugate": 18}
    assert d.box_vertices == 2 ** d.degrees["adjugate"] and len(d.W_vertices) == d.order + 1
    assert d.kappa_max == pytest.approx(0.149046, rel=1e-5)
    # method="adjugate" with every power kept is the pointwise 𝒫₂ optimum W₂ ∝ Γ_κ⁻¹c
    full = robust_lpv_parity(LPV, UNC, 3, kappa=0.1, rho_max=0.2, rho_nominal=0.048, method="adjugate", order=30)
    assert full.truncation_error < 1e-8
    for rho in (0.01, 0.048, 0.15):
        c = robust_criteria(LPV, UNC, rho, 3)
        w, ref = full.w2(rho), p2_solution(c.gamma1, c.gamma2, 0.1, full.c)
        assert abs(w @ ref) / (np.linalg.norm(w) * np.linalg.norm(ref)) == pytest.approx(1.0, abs=1e-9)
    J, lam = full.criterion([1 / 20.83, 1 / 50])
    assert np.all(J >= lam) and np.all(J <= lam * 1.01)


def test_bad_criteria_input_is_refused():
    with pytest.raises(DesignError, match="no target fault"):
        robust_criteria(LPV, UNC, 0.048, 3, nuisance=["lateral_acceleration_sensor"])
    with pytest.raises(ParameterError, match="no fault named"):
        robust_criteria(LPV, UNC, 0.048, 3, nuisance=["yaw_rate_sensor"])
    with pytest.raises(ParameterError, match="fault_model"):
        robust_criteria(LPV, UNC, 0.048, 3, fault_model="ramp")
    with pytest.raises(ParameterError, match="rho_min < rho_max"):
        robust_lpv_parity(LPV, UNC, 3, kappa=0.1, rho_min=0.2, rho_max=0.1)
