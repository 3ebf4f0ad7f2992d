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


def test_infeasible_problem_is_a_design_error(data):
    _, Lp, Lf, past, r, u_last, w = data
    free = Lp @ past
    limits = SpcLimits(u_min=-1e-3, u_max=1e-3, y_min=np.max(free) + 10.0)
    with pytest.raises(DesignError, match="relax the output limits"):
        QpSolver().solve(spc_problem(Lp, Lf, past, r, u_last, w, limits, Nc=NC))


def test_singular_cost_is_a_design_error():
    prob = spc_problem(np.zeros((2, 1)), np.zeros((2, 2)), [0.0], [0.0], [0.0], SpcWeights(1.0, 0.0, 0.0), Nc=1)
    with pytest.raises(DesignError, match="not strictly convex"):
        unconstrained_move(prob)
