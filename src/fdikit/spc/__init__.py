"""Subspace predictive control: data-driven predictors and the predictive-control quadratic program.

Hallouzi 2008, Ch. 5 (open-loop subspace predictor, SPC law, persistency of excitation) and Ch. 6 /
App. C (closed-loop VARX predictor with a recursive Givens update).

* :mod:`fdikit.spc.hankel` — Block-Hankel data matrices and the persistency-of-excitation test.
* :mod:`fdikit.spc.predictor` — The open-loop subspace predictor ``ŷ_f = L_p v_p + L_f u_f``.
* :mod:`fdikit.spc.excitation` — Least-excited input directions and the excitation term of the QP.
* :mod:`fdikit.spc.law` — The SPC cost, constraints and quadratic program (OSQP).
* :mod:`fdikit.spc.varx` — The closed-loop (VARX) predictor and its multi-step matrices.
* :mod:`fdikit.spc.givens` — Recursive update of the VARX predictor by Givens rotations.
* :mod:`fdikit.spc.controller` — The adaptive open-loop SPC controller of Ch. 5.
* :mod:`fdikit.spc.closed_loop` — The closed-loop SPC controller of Ch. 6.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "hankel": ["block_hankel", "excitation_rank", "input_rcond"],
        "predictor": ["SubspacePredictor", "subspace_predictor"],
        "excitation": ["LeastExcited", "excitation_cost", "least_excited"],
        "law": ["QpSolution", "QpSolver", "SpcLimits", "SpcProblem", "SpcWeights", "move_blocking", "rate_matrix",
                "spc_problem", "unconstrained_move"],
        "varx": ["VarxPredictor", "varx_data", "varx_fit"],
        "givens": ["RecursiveVarx"],
        "controller": ["SubspacePredictiveController"],
        "closed_loop": ["ClosedLoopSPC"],
    },
)
