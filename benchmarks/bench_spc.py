"""One closed-loop SPC step in the B747 rudder configuration: predictor update + multi-step matrices + QP.

Hallouzi 2008, §6.6: ``p = f = N_p = 20``, ``N_c = 5``, ``m = 5`` inputs, ``l = 7`` outputs, so the QP has
``N_c·m = 25`` variables; the step must fit the 10 Hz control period (goal ≤ 2 ms, 98 % slack).

The data come from a random stable innovation-form system (8 states, 5 inputs, 7 outputs, ``ρ(A − KC) ≤ 0.6``)
under white inputs: the step's cost depends on the dimensions, not on the aircraft.  The SPC limits are
input and rate bounds on every input (the surfaces' position and rate limits), 100 rows; output bounds
are left out — on random data they make many steps infeasible, and each one adds 2·N_p·l = 280 rows,
which multiplies OSQP's time by about 8 (measured while writing :mod:`fdikit.spc.law`).

Each step: :meth:`fdikit.spc.RecursiveVarx.update` (Givens, λ = 0.995), :meth:`VarxPredictor.multistep`
(f = 20, one triangular solve), :func:`fdikit.spc.spc_problem`, :meth:`fdikit.spc.QpSolver.solve` (the default,
Clarabel's own API with cached CSC patterns and a polishing step).  The same problems are also solved by
``QpSolver(method="osqp")`` (warm started, outside the step's timing).

Peers, in the same run, on the same data:

* the predictor update as a batch QR of the λ-weighted data window (``numpy.linalg.qr`` of the 1000-column
  ``[Z; Y]ᵀ``), which is what a user without the recursive update would do;
* the QP with cvxpy (a parametrised, DPP-compiled problem, so only the parameters change between steps)
  and Clarabel, the solver the tests use as a reference.

Single-threaded BLAS (set before numpy is imported).  Run: ``python benchmarks/bench_spc.py [--steps N]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"  # single-threaded BLAS: comparable timings on a shared machine

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from fdikit.spc import QpSolver, RecursiveVarx, SpcLimits, SpcWeights, spc_problem  # noqa: E402
from timing import cpu_name  # noqa: E402

P = F = 20
NC = 5
M_IN, L_OUT, N_X = 5, 7, 8
FORGET = 0.995


def system(rng):
    """A random stable innovation-form system with ρ(A) ≤ 0.9 and ρ(A − KC) ≤ 0.6."""
    while True:
        A = rng.standard_normal((N_X, N_X))
        A *= 0.9 / max(abs(np.linalg.eigvals(A)))
        B = rng.standard_normal((N_X, M_IN))
        C = rng.standard_normal((L_OUT, N_X))
        K = 0.05 * rng.standard_normal((N_X, L_OUT))
        if max(abs(np.linalg.eigvals(A - K @ C))) <= 0.6:
            return A, B, C, K


def simulate(sysm, u, rng, noise=0.05):
    A, B, C, K = sysm
    x = np.zeros(N_X)
    y = np.empty((len(u), L_OUT))
    for k, uk in enumerate(u):
        e = noise * rng.standard_normal(L_OUT)
        y[k] = C @ x + e
        x = A @ x + B @ uk + K @ e
    return y


def percentiles(times):
    t = np.asarray(times) * 1e3
    return float(np.median(t)), float(np.percentile(t, 99)), float(t.max())


def main(steps: int) -> None:
    rng = np.random.default_rng(0)
    sysm = system(rng)
    n0 = 1000 + P
    u = rng.standard_normal((n0 + steps + P, M_IN))
    y = simulate(sysm, u, rng)
    weights = SpcWeights(output=np.ones(L_OUT), input=0.01 * np.eye(M_IN), rate=0.1 * np.eye(M_IN))
    limits = SpcLimits(u_min=-np.ones(M_IN), u_max=np.ones(M_IN), du_min=-0.3 * np.ones(M_IN),
                       du_max=0.3 * np.ones(M_IN))
    rec = RecursiveVarx(P, M_IN, L_OUT, forgetting=FORGET)
    rec.initialize(u[:n0], y[:n0])
    solver, osqp_solver = QpSolver(), QpSolver(method="osqp")
    reference = np.tile(rng.uniform(-1, 1, L_OUT), F)

    fd_update, fd_qp, fd_step, batch_update, cvx_qp = [], [], [], [], []
    fd_multi, fd_setup, fd_solve, osqp_qp, iters, osqp_iters, osqp_diff = [], [], [], [], [], [], 0.0
    problems, polished = [], 0
    for k in range(n0, n0 + steps):
        pred0 = rec.predictor
        w_p = pred0.past(u[:k], y[:k])
        t0 = time.perf_counter()
        rec.update(w_p, y[k])
        t1 = time.perf_counter()
        pred = rec.predictor
        gamma, lam = pred.multistep(F)
        t1b = time.perf_counter()
        prob = spc_problem(gamma, lam, pred.past(u[:k + 1], y[:k + 1]), reference, np.clip(u[k], -1, 1), weights,
                           limits, NC)
        t1c = time.perf_counter()
        sol = solver.solve(prob)
        t2 = time.perf_counter()
        fd_update.append(t1 - t0)
        fd_multi.append(t1b - t1)
        fd_setup.append(t1c - t1b)
        fd_solve.append(t2 - t1c)
        fd_qp.append(t2 - t1)
        fd_step.append(t2 - t0)
        iters.append(sol.iterations)
        problems.append((prob, sol.u))
        polished += sol.polished
        t3 = time.perf_counter()
        sol_o = osqp_solver.solve(prob)
        osqp_qp.append(time.perf_counter() - t3)
        osqp_iters.append(sol_o.iterations)
        osqp_diff = max(osqp_diff, float(np.max(np.abs(sol_o.u - sol.u))))
    # Batch QR of the weighted window (the recursive update's peer), on the same columns.
    cols = 1000
    for k in range(n0, n0 + min(steps, 200)):
        wts = np.sqrt(FORGET ** np.arange(cols)[::-1])
        t0 = time.perf_counter()
        Z = np.stack([np.concatenate([np.r_[u[i - P + j], y[i - P + j]] for j in range(P)])
                      for i in range(k - cols, k)])
        data = np.hstack([Z, y[k - cols:k]]) * wts[:, None]
        np.linalg.qr(data, mode="r")
        batch_update.append(time.perf_counter() - t0)
    # cvxpy + Clarabel, DPP-parametrised.
    import cvxpy as cp

    prob0 = problems[0][0]
    nv = prob0.H.shape[0]
    x = cp.Variable(nv)
    Hs = cp.Parameter((nv, nv), PSD=True)
    c = cp.Parameter(nv)
    A = cp.Parameter(prob0.A.shape)
    b = cp.Parameter(prob0.b.shape)
    qp = cp.Problem(cp.Minimize(0.5 * cp.quad_form(x, Hs) + c @ x), [A @ x <= b])
    worst = 0.0
    for prob, u_fd in problems[: min(steps, 200)]:
        Hs.value = prob.H + prob.H.T
        c.value = prob.c
        A.value, b.value = prob.A, prob.b
        t0 = time.perf_counter()
        qp.solve(solver=cp.CLARABEL)
        cvx_qp.append(time.perf_counter() - t0)
        worst = max(worst, float(np.max(np.abs(x.value - u_fd)) / max(1.0, np.max(np.abs(x.value)))))

    print(f"CPU: {cpu_name()}; {steps} steps; QP variables {nv}, constraints {prob0.A.shape[0]}")
    rows = [("fdikit step (update + Γ, Λ + QP)", fd_step), ("  fdikit predictor update (Givens)", fd_update),
            ("  fdikit Γ, Λ, QP set-up + Clarabel", fd_qp), ("    Γ, Λ (multistep)", fd_multi),
            ("    QP set-up (spc_problem)", fd_setup), ("    QpSolver.solve (Clarabel + polish)", fd_solve),
            ("QpSolver(method='osqp').solve", osqp_qp), ("batch QR of the weighted window", batch_update),
            ("cvxpy + Clarabel QP (DPP)", cvx_qp)]
    print(f"{'':40s} {'median ms':>10s} {'p99 ms':>8s} {'max ms':>8s}")
    for name, times in rows:
        med, p99, mx = percentiles(times)
        print(f"{name:40s} {med:10.3f} {p99:8.3f} {mx:8.3f}")
    med_u, med_b = np.median(fd_update), np.median(batch_update)
    med_q = np.median(np.asarray(fd_qp))
    print(f"ratios: batch QR / Givens update {med_b / med_u:.1f}×; cvxpy+Clarabel / (fdikit Γ, Λ, QP) "
          f"{np.median(cvx_qp) / med_q:.1f}×; cvxpy+Clarabel / QpSolver.solve "
          f"{np.median(cvx_qp) / np.median(fd_solve):.1f}×;"
          f" OSQP / QpSolver.solve {np.median(osqp_qp) / np.median(fd_solve):.1f}×")
    print(f"iterations: Clarabel {min(iters)}–{max(iters)} (median {np.median(iters):.0f}), OSQP {min(osqp_iters)}–"
          f"{max(osqp_iters)} (median {np.median(osqp_iters):.0f}); polished solves {polished}/{len(problems)}")
    print(f"largest move difference: QpSolver vs cvxpy+Clarabel (default tol) {worst:.1e}, vs OSQP {osqp_diff:.1e}")
    print(f"whole-step goal ≤ 2 ms (median): {'met' if np.median(fd_step) * 1e3 <= 2.0 else 'NOT met'}")
    print(f"10 Hz budget 100 ms: p99 of the fdikit step uses {percentiles(fd_step)[1] / 100:.1%}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000)
    main(ap.parse_args().steps)
