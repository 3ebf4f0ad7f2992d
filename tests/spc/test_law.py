"""The SPC law: matrices against brute force, the quadratic form against the cost's definition (5.17),
the unconstrained minimiser, and constrained solves against cvxpy + Clarabel."""

import numpy as np
import pytest

from fdikit.errors import DesignError, ParameterError
from fdikit.spc.law import QpSolver, SpcLimits, SpcWeights, move_blocking, rate_matrix, spc_problem, unconstrained_move

NP, NC, M, L, Q = 6, 3, 2, 3, 10


def toeplitz_markov(rng, Np=NP, m=M, l=L):
    blocks = [0.4 * rng.standard_normal((l, m)) for _ in range(Np)]
    Lf = np.zeros((Np * l, Np * m))
    for i in range(Np):
        for j in range(i + 1):
            Lf[i * l:(i + 1) * l, j * m:(j + 1) * m] = blocks[i - j]
    return Lf


@pytest.fixture
def data():
    rng = np.random.default_rng(3)
    Lf = toeplitz_markov(rng)
    Lp = rng.standard_normal((NP * L, Q))
    past = rng.standard_normal(Q)
    r = rng.standard_normal(NP * L)
    u_last = rng.standard_normal(M)
    Qc = np.diag([1.0, 0.5, 2.0])
    Rc = np.array([[0.2, 0.05], [0.05, 0.1]])
    Rd = np.diag([0.3, 0.7])
    return rng, Lp, Lf, past, r, u_last, SpcWeights(Qc, Rc, Rd)


def brute_cost(u, Lp, Lf, past, r, u_last, w):
    """(5.17) summed sample by sample, with the held last move and Δu_1 = u_1 − u_last."""
    Qc, Rc, Rd = (np.asarray(x) for x in (w.output, w.input, w.rate))
    moves = u.reshape(NC, M)
    full = np.vstack([moves, np.repeat(moves[-1:], NP - NC, axis=0)])
    y = Lp @ past + Lf @ full.ravel()
    J = 0.0
    for k in range(NP):
        e = y[k * L:(k + 1) * L] - r[k * L:(k + 1) * L]
        J += e @ Qc @ e
    prev = u_last
    for k in range(NC):
        J += moves[k] @ Rc @ moves[k] + (moves[k] - prev) @ Rd @ (moves[k] - prev)
        prev = moves[k]
    return J


def test_blocking_and_rate_matrices_against_loops():
    E = move_blocking(5, 2, 3)
    for i in range(5):
        for j in range(2):
            want = np.eye(3) if j == min(i, 1) else np.zeros((3, 3))
            assert np.array_equal(E[3 * i:3 * i + 3, 3 * j:3 * j + 3], want)
    S = rate_matrix(4, 2)
    u = np.arange(8.0)
    assert np.array_equal(S @ u, np.r_[u[:2], u[2:] - u[:-2]])
    with pytest.raises(ParameterError, match="Nc"):
        move_blocking(3, 4, 1)


def test_quadratic_form_equals_the_cost_definition(data):
    rng, Lp, Lf, past, r, u_last, w = data
    prob = spc_problem(Lp, Lf, past, r, u_last, w, Nc=NC)
    J0 = brute_cost(np.zeros(NC * M), Lp, Lf, past, r, u_last, w)
    for _ in range(5):
        u = rng.standard_normal(NC * M)
        J = brute_cost(u, Lp, Lf, past, r, u_last, w)
        # A quadratic identity: exact up to round-off of sums of O(100) terms of size O(|J|).
        assert prob.cost(u) == pytest.approx(J - J0, rel=1e-12, abs=1e-12 * abs(J0))


def test_unconstrained_minimiser_zeroes_the_gradient_and_matches_osqp(data):
    _, Lp, Lf, past, r, u_last, w = data
    prob = spc_problem(Lp, Lf, past, r, u_last, w, Nc=NC)
    u = unconstrained_move(prob)
    # Central differences of the brute-force cost (a quadratic: exact up to round-off / h).
    h = 1e-5
    grad = [(brute_cost(u + h * e, Lp, Lf, past, r, u_last, w) - brute_cost(u - h * e, Lp, Lf, past, r, u_last, w))
            / (2 * h) for e in np.eye(NC * M)]
    assert np.max(np.abs(grad)) < 1e-6
    sol = QpSolver().solve(prob)
    assert sol.status == "solved"
    # OSQP stops at eps = 1e-8 on the KKT residual; on a problem with cond(H) ≈ 1e2 the iterate is within
    # ~cond·eps of the minimiser.
    cond = np.linalg.cond(prob.H)
    assert np.max(np.abs(sol.u - u)) < 10 * cond * 1e-8 * max(1.0, np.max(np.abs(u)))


def test_held_reference_equals_tiled_reference(data):
    _, Lp, Lf, past, _, u_last, w = data
    a = spc_problem(Lp, Lf, past, [1.0, -1.0, 0.5], u_last, w, Nc=NC)
    b = spc_problem(Lp, Lf, past, np.tile([1.0, -1.0, 0.5], NP), u_last, w, Nc=NC)
    assert np.array_equal(a.c, b.c)


def clarabel(prob):
    import cvxpy as cp
    x = cp.Variable(prob.H.shape[0])
    q = cp.Problem(cp.Minimize(cp.quad_form(x, prob.H) + prob.c @ x), [prob.A @ x <= prob.b])
    q.solve(solver=cp.CLARABEL)
    assert q.status == "optimal"
    return x.value, q.value


def test_constrained_solves_match_clarabel_over_a_receding_horizon(data):
    rng, Lp, Lf, past, r, u_last, w = data
    free = Lp @ past
    limits = SpcLimits(u_min=-0.3, u_max=[0.3, 0.2], du_min=-0.15, du_max=0.15,
                       y_min=np.min(free.reshape(NP, L), axis=0) - 0.2, y_max=np.max(free.reshape(NP, L), axis=0) + 0.2)
    solver = QpSolver()
    active = 0
    for k in range(8):                       # changing reference and last input: the warm-started path
        prob = spc_problem(Lp, Lf, past, r * np.cos(0.3 * k), u_last * 0.2 * np.sin(k), w, limits, Nc=NC)
        sol = solver.solve(prob)
        ref, J = clarabel(prob)
        assert sol.status == "solved"
        # Both solvers at 1e-8 tolerances: optimal costs agree to ~1e-6 of the cost's scale, the iterates
        # satisfy A u ≤ b to the same tolerance.
        scale = max(1.0, abs(J), float(np.abs(prob.c).sum()))
        assert prob.cost(sol.u) == pytest.approx(J, abs=1e-6 * scale)
        assert np.max(prob.A @ sol.u - prob.b) < 1e-6 * max(1.0, np.max(np.abs(prob.b)))
        assert np.max(np.abs(sol.u - ref)) < 1e-4
        active += int(np.any(prob.A @ ref - prob.b > -1e-7))
    assert active >= 4                       # the limits do bind on most steps


def test_infinite_limits_drop_rows_and_bad_input_is_refused(data):
    _, Lp, Lf, past, r, u_last, w = data
    prob = spc_problem(Lp, Lf, past, r, u_last, w, SpcLimits(u_max=[1.0, np.inf]), Nc=NC)
    assert prob.A.shape == (NC, NC * M)
    with pytest.raises(ParameterError, match="u_min exceeds"):
        spc_problem(Lp, Lf, past, r, u_last, w, SpcLimits(u_min=1.0, u_max=0.0), Nc=NC)
    with pytest.raises(ParameterError, match="positive semidefinite"):
        spc_problem(Lp, Lf, past, r, u_last, SpcWeights(-1.0, 0.1, 0.1), Nc=NC)
    with pytest.raises(ParameterError, match="reference"):
        spc_problem(Lp, Lf, past, [1.0, 2.0], u_last, w, Nc=NC)


@pytest.mark.parametrize("method", ["clarabel", "osqp"])
def test_infeasible_problem_is_a_design_error(data, method):
    _, Lp, Lf, past, r, u_last, w = data
    free = Lp @ past
    limits = SpcLimits(u_min=-1e-3, u_max=1e-3, y_min=np.max(free) + 10.0)
    with pytest.raises(DesignError, match="relax the output limits"):
        QpSolver(method=method).solve(spc_problem(Lp, Lf, past, r, u_last, w, limits, Nc=NC))


def test_singular_cost_is_a_design_error():
    prob = spc_problem(np.zeros((2, 1)), np.zeros((2, 2)), [0.0], [0.0], [0.0], SpcWeights(1.0, 0.0, 0.0), Nc=1)
    with pytest.raises(DesignError, match="not strictly convex"):
        unconstrained_move(prob)


def hallouzi_66_problem(rng, p=20, m=5, l=7, n=8, Nc=5):
    """The §6.6 configuration: a VARX predictor (p = f = 20) of a random stable system, its Γ, Λ (6.13), and
    the SPC QP with input and rate limits on every input: N_c·m = 25 variables, 100 constraint rows."""
    from fdikit.spc.varx import VarxPredictor

    A = rng.standard_normal((n, n))
    A *= 0.6 / max(abs(np.linalg.eigvals(A)))      # Φ = A − KC with K = 0: ρ(Φ) = 0.6
    B, C, K = rng.standard_normal((n, m)), rng.standard_normal((l, n)), np.zeros((n, l))
    BK = np.hstack([B, K])
    xi0 = np.hstack([C @ np.linalg.matrix_power(A, p - 1 - i) @ BK for i in range(p)])
    gamma, lam = VarxPredictor(xi0, p, m, l).multistep(p)
    w = SpcWeights(output=np.ones(l), input=0.01 * np.eye(m), rate=0.1 * np.eye(m))
    limits = SpcLimits(u_min=-0.5, u_max=0.5, du_min=-0.2, du_max=0.2)
    return spc_problem(gamma, lam, rng.standard_normal(p * (m + l)), rng.uniform(-3, 3, l), rng.uniform(-0.3, 0.3, m),
                       w, limits, Nc)


@pytest.mark.parametrize("method", ["clarabel", "osqp"])
def test_25_variable_spc_qp_equals_cvxpy_clarabel(method):
    import cvxpy as cp

    rng = np.random.default_rng(66)
    solver = QpSolver(method=method)
    for _ in range(3):                         # the first solve sets up, the others update the cached patterns
        prob = hallouzi_66_problem(rng)
        assert prob.H.shape == (25, 25) and prob.A.shape == (100, 25)
        sol = solver.solve(prob)
        assert sol.status == "solved" and sol.polished
        x = cp.Variable(25)
        con = prob.A @ x <= prob.b
        ref = cp.Problem(cp.Minimize(cp.quad_form(x, prob.H) + prob.c @ x), [con])
        ref.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
        assert ref.status == "optimal"
        u_ref, lam_ref, J = x.value, np.maximum(con.dual_value, 0.0), prob.cost(sol.u)
        scale_b = 1.0 + np.abs(prob.b).max()
        # QpSolver's polished u is a checked KKT point: feasible to eps = 1e-8 (it is in fact ~1e-12).
        assert np.max(prob.A @ sol.u - prob.b) <= 1e-8 * scale_b
        # The reference stops at a duality gap ≤ 1e-10·(1 + |J|) (Clarabel's criterion, in its scaling): a
        # margin of 100 for the scaling gives the cost tolerance; J(u) cannot be worse than the reference's.
        tol_J = 1e-8 * (1.0 + abs(J))
        assert prob.cost(u_ref) - J <= tol_J and J - prob.cost(u_ref) <= tol_J
        # Strong convexity, μ = λ_min(P), P = H + Hᵀ, u* = u:  (μ/2)‖u_ref − u*‖² ≤ J(u_ref) − J* + λ*ᵀ(A u_ref − b)₊
        # (the last term: the reference may be infeasible by up to its tol_feas).  With J(u_ref) − J* ≤ tol_J:
        mu = np.linalg.eigvalsh(prob.H + prob.H.T)[0]
        viol = np.maximum(prob.A @ u_ref - prob.b, 0.0)
        bound = np.sqrt(2.0 * (tol_J + 2.0 * lam_ref.sum() * viol.max()) / mu)
        assert np.linalg.norm(u_ref - sol.u) <= bound
        # Both see the same active limits (margins 1e-6 ≫ the 1e-10 tolerances and round-off).
        act = prob.A @ sol.u - prob.b > -1e-6 * scale_b
        assert np.array_equal(act, prob.A @ u_ref - prob.b > -1e-6 * scale_b)
        assert 3 <= act.sum() < 25             # some limits bind, not all
        assert sol.iterations <= (20 if method == "clarabel" else 4000)


def test_status_strings_are_normalised():
    from fdikit.spc.law import _status

    for raw in ("problem non convex", "problem_non_convex", "non-convex", "dual infeasible", "DualInfeasible"):
        with pytest.raises(DesignError, match="not positive semidefinite"):
            _status(raw, "OSQP")
    for raw in ("primal infeasible", "primal_infeasible", "PrimalInfeasible", "primal infeasible inaccurate",
                "AlmostPrimalInfeasible"):
        with pytest.raises(DesignError, match="relax the output limits"):
            _status(raw, "OSQP")
    assert [_status(r, "x") for r in ("solved", "Solved", "solved_inaccurate", "solved inaccurate", "AlmostSolved",
                                      "maximum iterations reached", "MaxIterations", "MaxTime")] == \
        ["solved"] * 2 + ["solved inaccurate"] * 3 + ["max_iter"] * 3
    with pytest.raises(DesignError, match="could not solve"):
        _status("NumericalError", "Clarabel")


@pytest.mark.parametrize("method", ["clarabel", "osqp"])
def test_non_convex_and_non_finite_problems_are_refused(method):
    from fdikit.spc.law import SpcProblem

    bad = SpcProblem(H=np.diag([1.0, -1.0]), c=np.zeros(2), A=np.eye(2), b=np.ones(2))
    with pytest.raises(DesignError, match="non convex"):
        QpSolver(method=method).solve(bad)
    with pytest.raises(ParameterError, match="finite"):
        QpSolver(method=method).solve(SpcProblem(H=np.eye(2), c=np.zeros(2), A=np.eye(2), b=np.array([1.0, np.inf])))
    with pytest.raises(ParameterError, match="method"):
        QpSolver(method="quadprog")


@pytest.mark.parametrize("method", ["clarabel", "osqp"])
def test_changed_sparsity_and_shape_set_the_solver_up_again(method):
    from fdikit.spc.law import SpcProblem

    solver = QpSolver(method=method)
    H, c = np.eye(2), np.array([-2.0, -2.0])
    first = solver.solve(SpcProblem(H=H, c=c, A=np.array([[1.0, 0.0]]), b=np.array([0.5])))
    np.testing.assert_allclose(first.u, [0.5, 1.0], atol=1e-9)
    # A nonzero outside the cached pattern: u₁ + u₂ ≤ 1 → u = (0.5, 0.5).
    second = solver.solve(SpcProblem(H=H, c=c, A=np.array([[1.0, 1.0]]), b=np.array([1.0])))
    np.testing.assert_allclose(second.u, [0.5, 0.5], atol=1e-9)
    third = solver.solve(SpcProblem(H=H, c=c, A=np.zeros((0, 2)), b=np.zeros(0)))   # no constraints at all
    np.testing.assert_allclose(third.u, [1.0, 1.0], atol=1e-6)
