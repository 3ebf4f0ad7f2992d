"""The SPC control law: tracking cost, input/rate/output limits, and the quadratic program, §5.2.2, §6.3.2.

With a linear predictor ``ŷ_f = L_p v_p + L_f E u_f`` — the open-loop subspace predictor of
:mod:`fdikit.spc.predictor` (``L_p, L_f, v_p``) or the closed-loop one of :mod:`fdikit.spc.varx`
(``Γ_r, Λ_r, w_p``, §6.3.2) — the cost (5.17)–(5.19)

    J = (ŷ_f − r_f)ᵀ Q_a (ŷ_f − r_f) + u_fᵀ R_a u_f + Δu_fᵀ R_aᶿ Δu_f,     Δu_f = S_Δ u_f − S_v v_p

is the quadratic ``J(u_f) − J(0) = u_fᵀ H u_f + cᵀ u_f`` (5.23)–(5.25) with

    H  = Eᵀ L_fᵀ Q_a L_f E + S_Δᵀ R_aᶿ S_Δ + R_a
    cᵀ = 2 (v_pᵀ L_pᵀ Q_a L_f E − r_fᵀ Q_a L_f E − v_pᵀ S_vᵀ R_aᶿ S_Δ).

``S_v v_p`` is the last applied input: ``u_t`` in Ch. 5, ``u_{t−1}`` (``S_w w_p``) in Ch. 6; it is passed
directly as ``u_last``, so one function serves both chapters.  The constraints (5.28)–(5.36) are stacked as
``A u_f ≤ b`` (5.37); rows whose bound is infinite are dropped.

Corrections to the printed text:

* (5.27) prints ``u_f = −c (Hᵀ + H)⁻¹``, a row/column mix; the minimiser of ``uᵀHu + cᵀu`` is
  ``u_f = −(H + Hᵀ)⁻¹ c`` (:func:`unconstrained_move`; the test checks the gradient is zero there).
* (5.34) prints ``<``; the bounds are ``≤``.  (5.35) ``[I −I S_Δᵀ −S_Δᵀ …]ᵀ`` is a vertical stack.

Solver (:class:`QpSolver`): one small dense QP per control period (§6.6: 25 variables, 100 rows) of a fixed
shape: set up once with fixed CSC patterns, then only their ``.data`` updated.  Default ``method="clarabel"``
(Clarabel's own API, interior point, Goulart & Chen 2024): 8–17 iterations whatever the conditioning (cond H ≈
3e4 in §6.6), a bounded time, which a real-time loop needs more than a short median; a polishing step (the KKT
system on the identified active set, kept only if the KKT conditions hold to ``eps``) makes active limits exact.
``method="osqp"`` (ADMM, Stellato et al. 2020) warm starts and polishes, but needs hundreds to thousands of
iterations at 1e-8 here: a similar median, a longer tail.  cvxpy with Clarabel is the tests' reference.
Written here: only the SPC assembly (5.17)–(5.37) and the polishing step, which no library provides.

References
----------
Hallouzi 2008, §5.2.2, (5.17)–(5.37); §6.3.2, (6.18)–(6.28); §6.6.  Favoreel & De Moor 1999.
Maciejowski 2002, Ch. 3.  Stellato et al. 2020.  Goulart & Chen 2024.
"""

from __future__ import annotations

import contextlib
import io
import re
import time
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DesignError, ParameterError

__all__ = ["QpSolution", "QpSolver", "SpcLimits", "SpcProblem", "SpcWeights", "move_blocking", "rate_matrix",
           "spc_problem", "unconstrained_move"]


def _square(name: str, value, size: int) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim <= 1:
        a = np.diag(np.broadcast_to(a, (size,)).astype(float))
    if a.shape != (size, size) or not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be a finite {size}×{size} matrix or a vector of {size} diagonal "
                             f"weights; got shape {np.shape(value)}.")
    d = np.diag(a)
    lowest = np.min(d) if np.array_equal(a, np.diag(d)) else np.min(np.linalg.eigvalsh(0.5 * (a + a.T)))
    if lowest < -1e-12 * max(1.0, np.abs(a).max()):
        raise ParameterError(f"{name} must be positive semidefinite (a weight); make its eigenvalues ≥ 0.")
    return a


@dataclass(frozen=True)
class SpcWeights:
    """Weights of the SPC cost (5.17): per-sample output, input and input-rate weights.

    Attributes
    ----------
    output : array_like
        ``Q_c`` (l × l), or a vector of its diagonal.
    input : array_like
        ``R_c`` (m × m), or a vector of its diagonal.
    rate : array_like
        ``R_cᶿ`` (m × m), or a vector of its diagonal.

    Examples
    --------
    >>> w = SpcWeights(output=[1.0, 0.0], input=0.01, rate=0.1)
    >>> w.matrices(2, 1)[0]
    array([[1., 0.],
           [0., 0.]])

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.17)–(5.19).
    """

    output: object
    input: object
    rate: object

    def matrices(self, l: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(Q_c, R_c, R_cᶿ)`` as matrices for ``l`` outputs and ``m`` inputs.

        Parameters
        ----------
        l, m : int
            Numbers of outputs and inputs.

        Returns
        -------
        Q_c, R_c, R_rate : ndarray

        Raises
        ------
        ParameterError
            A weight of the wrong size, non-finite or not positive semidefinite.
        """
        return (_square("SpcWeights.output", self.output, l), _square("SpcWeights.input", self.input, m),
                _square("SpcWeights.rate", self.rate, m))


@dataclass(frozen=True)
class SpcLimits:
    """Input, input-rate and output limits (5.28)–(5.33), the same at every sample of the horizon.

    Each is a vector (one entry per input or output), a scalar for all, or None for unbounded; ``±inf``
    entries are unbounded too.

    Attributes
    ----------
    u_min, u_max : array_like or None
        Input limits.
    du_min, du_max : array_like or None
        Limits on the input change per sample.
    y_min, y_max : array_like or None
        Limits on the predicted outputs.

    Examples
    --------
    >>> SpcLimits(u_min=-1.0, u_max=1.0).vectors(2, 1)[0]
    array([-1.])

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.28)–(5.33).
    """

    u_min: object = None
    u_max: object = None
    du_min: object = None
    du_max: object = None
    y_min: object = None
    y_max: object = None

    def vectors(self, l: int, m: int) -> tuple[np.ndarray, ...]:
        """The six limits as vectors (``±inf`` where unbounded): u_min, u_max, du_min, du_max, y_min, y_max.

        Parameters
        ----------
        l, m : int
            Numbers of outputs and inputs.

        Returns
        -------
        tuple of ndarray

        Raises
        ------
        ParameterError
            A limit of the wrong size, NaN, or a lower limit above its upper one.
        """
        out = []
        for name, size, sign in (("u_min", m, -1), ("u_max", m, 1), ("du_min", m, -1), ("du_max", m, 1),
                                 ("y_min", l, -1), ("y_max", l, 1)):
            v = getattr(self, name)
            v = np.full(size, sign * np.inf) if v is None else np.asarray(v, dtype=float)
            if v.ndim == 0:
                v = np.full(size, float(v))
            if v.shape != (size,) or np.any(np.isnan(v)):
                raise ParameterError(f"SpcLimits.{name} must be a scalar or {size} numbers (±inf for unbounded); "
                                     f"got shape {v.shape}.")
            out.append(v)
        for lo, hi, name in ((0, 1, "u"), (2, 3, "du"), (4, 5, "y")):
            if np.any(out[lo] > out[hi]):
                raise ParameterError(f"SpcLimits: {name}_min exceeds {name}_max; swap or widen them.")
        return tuple(out)


@dataclass(frozen=True)
class SpcProblem:
    """The SPC quadratic program ``min uᵀ H u + cᵀ u  s.t.  A u ≤ b`` (5.37).

    Attributes
    ----------
    H : ndarray, shape (N_c·m, N_c·m)
        Quadratic term (5.24), symmetric positive semidefinite.
    c : ndarray, shape (N_c·m,)
        Linear term (5.25).
    A : ndarray, shape (k, N_c·m)
        Constraint rows (5.35) with finite bounds.
    b : ndarray, shape (k,)
        Their bounds (5.36).

    Examples
    --------
    >>> p = SpcProblem(H=np.eye(1), c=np.array([-2.0]), A=np.zeros((0, 1)), b=np.zeros(0))
    >>> float(unconstrained_move(p)[0])
    1.0

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.37); §6.3.2, (6.28).
    """

    H: np.ndarray
    c: np.ndarray
    A: np.ndarray
    b: np.ndarray

    def cost(self, u) -> float:
        """``uᵀ H u + cᵀ u`` (``J(u) − J(0)``).

        Parameters
        ----------
        u : array_like, shape (N_c·m,)

        Returns
        -------
        float
        """
        u = np.asarray(u, dtype=float)
        return float(u @ self.H @ u + self.c @ u)


def move_blocking(Np: int, Nc: int, m: int) -> np.ndarray:
    """The move-blocking matrix ``E`` (5.20): ``N_c`` free moves, the last one held to the end of ``N_p``.

    Parameters
    ----------
    Np : int
        Prediction horizon (samples).
    Nc : int
        Control horizon, ``1 ≤ N_c ≤ N_p``.
    m : int
        Number of inputs.

    Returns
    -------
    ndarray, shape (Np·m, Nc·m)

    Raises
    ------
    ParameterError
        For ``N_c > N_p`` or non-positive sizes.

    Examples
    --------
    >>> move_blocking(3, 2, 1)
    array([[1., 0.],
           [0., 1.],
           [0., 1.]])

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.20).
    """
    Np = validate.integer("Np", Np, minimum=1)
    Nc = validate.integer("Nc", Nc, minimum=1)
    m = validate.integer("m", m, minimum=1)
    if Nc > Np:
        raise ParameterError(f"the control horizon Nc = {Nc} exceeds the prediction horizon Np = {Np}; "
                             f"choose Nc ≤ Np.")
    blocks = np.minimum(np.arange(Np), Nc - 1)
    return np.kron(np.eye(Nc)[blocks], np.eye(m))


def rate_matrix(Nc: int, m: int) -> np.ndarray:
    """``S_Δ`` (5.21): block lower bidiagonal, ``I`` on the diagonal and ``−I`` below.

    Parameters
    ----------
    Nc : int
        Control horizon.
    m : int
        Number of inputs.

    Returns
    -------
    ndarray, shape (Nc·m, Nc·m)

    Raises
    ------
    ParameterError
        For non-positive sizes.

    Examples
    --------
    >>> rate_matrix(3, 1)
    array([[ 1.,  0.,  0.],
           [-1.,  1.,  0.],
           [ 0., -1.,  1.]])

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.21)–(5.22).
    """
    Nc = validate.integer("Nc", Nc, minimum=1)
    m = validate.integer("m", m, minimum=1)
    return np.kron(np.eye(Nc) - np.eye(Nc, k=-1), np.eye(m))


def spc_problem(Lp, Lf, past, reference, u_last, weights: SpcWeights, limits: SpcLimits | None = None,
                Nc: int = 5) -> SpcProblem:
    """Assemble the SPC quadratic program (5.23)–(5.37) for one control step.

    Parameters
    ----------
    Lp : array_like, shape (Np·l, q)
        Past-data matrix: ``L_p`` (5.15) or ``Γ_r`` (6.13).
    Lf : array_like, shape (Np·l, Np·m)
        Future-input matrix: ``L_f`` or ``Λ_r`` (block lower triangular).
    past : array_like, shape (q,)
        The past-data vector ``v_p`` (5.16) or ``w_p`` (6.13).
    reference : array_like, shape (Np·l,) or (l,)
        ``r_f`` over the horizon, or one value per output held over it.
    u_last : array_like, shape (m,)
        The last applied input ``S_v v_p`` (Ch. 5: ``u_t``; Ch. 6: ``S_w w_p = u_{t−1}``).
    weights : SpcWeights
        ``Q_c, R_c, R_cᶿ``.
    limits : SpcLimits, optional
        Input, rate and output limits (default unbounded).
    Nc : int, default 5
        Control horizon (number of free moves).

    Returns
    -------
    SpcProblem

    Raises
    ------
    ParameterError
        Inconsistent shapes or bad weights or limits.

    Examples
    --------
    >>> Lf = np.tril(np.ones((3, 3)))          # an integrator's Markov parameters
    >>> prob = spc_problem(np.zeros((3, 1)), Lf, [0.0], [1.0], [0.0], SpcWeights(1.0, 0.0, 0.0), Nc=1)
    >>> round(float(unconstrained_move(prob)[0]), 4)
    0.4286

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.23)–(5.37); §6.3.2, (6.21)–(6.27).
    """
    Lp = validate.as_matrix("Lp", Lp)
    Lf = validate.as_matrix("Lf", Lf)
    u_last = np.atleast_1d(np.asarray(u_last, dtype=float))
    m = u_last.size
    if Lf.shape[1] % m or Lf.shape[0] % (Lf.shape[1] // m):
        raise ParameterError(f"Lf has shape {Lf.shape}; with m = {m} inputs (u_last) it must be (Np·l, Np·m).")
    Np = Lf.shape[1] // m
    l = Lf.shape[0] // Np
    if Lp.shape[0] != Lf.shape[0]:
        raise ParameterError(f"Lp has {Lp.shape[0]} rows and Lf {Lf.shape[0]}; both must have Np·l rows.")
    past = validate.as_vector("past", past, size=Lp.shape[1])
    r = np.asarray(reference, dtype=float).ravel()
    if r.size == l:
        r = np.tile(r, Np)
    if r.size != Np * l or not np.all(np.isfinite(r)):
        raise ParameterError(f"reference must hold l = {l} or Np·l = {Np * l} finite values; got {r.size}.")
    if not np.all(np.isfinite(u_last)):
        raise ParameterError("u_last must be finite.")
    Qc, Rc, Rd = weights.matrices(l, m)
    Nc = validate.integer("Nc", Nc, minimum=1)
    S = rate_matrix(Nc, m) if Nc <= Np else move_blocking(Np, Nc, m)   # the latter raises the horizon error
    StS = S[::m, ::m].T @ S[::m, ::m]           # S_Δ = S₁ ⊗ I: S₁ᵀS₁
    # G = L_f E (future outputs per move): E copies the first N_c − 1 moves and sums the held last one.
    G = np.empty((Np * l, Nc * m))
    G[:, : (Nc - 1) * m] = Lf[:, : (Nc - 1) * m]
    G[:, (Nc - 1) * m :] = Lf[:, (Nc - 1) * m :].reshape(Np * l, Np - Nc + 1, m).sum(axis=1)
    free = Lp @ past                            # predicted outputs with u_f = 0
    sv = np.zeros(Nc * m)
    sv[:m] = u_last                             # S_v v_p: only the first block row is nonzero (5.21)
    QG = (Qc @ G.reshape(Np, l, Nc * m)).reshape(Np * l, Nc * m)          # Q_a G, Q_a = I ⊗ Q_c
    # S_Δᵀ(I ⊗ R_cᶿ)S_Δ + I ⊗ R_c = S₁ᵀS₁ ⊗ R_cᶿ + I ⊗ R_c, the Kronecker products by broadcasting
    reg = StS[:, None, :, None] * Rd[:, None] + np.eye(Nc)[:, None, :, None] * Rc[:, None]
    H = G.T @ QG + reg.reshape(Nc * m, Nc * m)
    H = 0.5 * (H + H.T)
    c = 2.0 * ((free - r) @ QG)
    c[:m] -= 2.0 * (u_last @ Rd)                # sv (I ⊗ R_cᶿ) S_Δ: only the first block is nonzero
    u_min, u_max, du_min, du_max, y_min, y_max = (limits or SpcLimits()).vectors(l, m)
    rows, bounds = [], []
    eye = np.eye(Nc * m)
    for mat, hi in ((eye, np.tile(u_max, Nc)), (-eye, -np.tile(u_min, Nc)), (S, np.tile(du_max, Nc) + sv),
                    (-S, -np.tile(du_min, Nc) - sv), (G, np.tile(y_max, Np) - free),
                    (-G, -np.tile(y_min, Np) + free)):
        keep = np.isfinite(hi)
        rows.append(mat[keep])
        bounds.append(hi[keep])
    return SpcProblem(H=H, c=c, A=np.vstack(rows), b=np.concatenate(bounds))


def unconstrained_move(problem: SpcProblem) -> np.ndarray:
    """The unconstrained minimiser ``u_f = −(H + Hᵀ)⁻¹ c`` (corrected (5.26)–(5.27)).

    Parameters
    ----------
    problem : SpcProblem

    Returns
    -------
    ndarray, shape (N_c·m,)

    Raises
    ------
    DesignError
        ``H`` singular (no input, rate or output weight makes the cost strictly convex).

    Examples
    --------
    >>> p = SpcProblem(H=2 * np.eye(2), c=np.array([4.0, -4.0]), A=np.zeros((0, 2)), b=np.zeros(0))
    >>> unconstrained_move(p)
    array([-1.,  1.])

    References
    ----------
    Hallouzi 2008, §5.2.2, (5.26)–(5.27) (printed transposed).
    """
    import scipy.linalg

    try:
        return scipy.linalg.solve(problem.H + problem.H.T, -problem.c, assume_a="sym")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError) as exc:
        raise DesignError("the SPC cost is not strictly convex (H is singular): give the inputs or their "
                          "rates a positive weight.") from exc


@dataclass(frozen=True)
class QpSolution:
    """One QP solve: the moves, the solver's status, its iterations and the wall time.

    Attributes
    ----------
    u : ndarray, shape (N_c·m,)
        The optimal blocked input sequence; apply its first ``m`` entries.
    status : str
        ``"solved"``, ``"solved inaccurate"`` or ``"max_iter"`` (the iteration cap was hit: ``u`` is the
        last iterate, feasible to about the solver tolerance at best — the controller decides what to do).
    iterations : int
        Interior-point (Clarabel) or ADMM (OSQP) iterations.
    seconds : float
        Wall time of the solve.
    polished : bool
        ``u`` is the exact minimiser on the identified active set (KKT conditions checked), not an iterate.

    Examples
    --------
    >>> QpSolution(u=np.zeros(2), status="solved", iterations=25, seconds=1e-4).status
    'solved'

    References
    ----------
    Stellato et al. 2020; Goulart & Chen 2024.
    """

    u: np.ndarray
    status: str
    iterations: int
    seconds: float
    polished: bool = False


def _status(raw, solver: str) -> str:
    """Map a solver's status ("PrimalInfeasible", "primal_infeasible", "problem non convex", …) to ours."""
    words = " ".join(re.sub(r"(?<=[a-z])(?=[A-Z])", " ", str(raw)).replace("_", " ").replace("-", " ").lower().split())
    if "infeasible" in words or "non convex" in words or "unbounded" in words:
        raise DesignError(f"the SPC quadratic program is {words}: " + (
            "relax the output limits (y_min, y_max), then the rate limits, so that some input sequence meets them all."
            if "infeasible" in words and "dual" not in words else
            "H is not positive semidefinite or the cost is unbounded below; check the weights and the predictor."))
    if words in ("solved", "solved inaccurate", "almost solved"):
        return "solved" if words == "solved" else "solved inaccurate"
    if words.startswith(("max", "time limit", "run time limit")):   # max_iter, "maximum iterations reached", …
        return "max_iter"
    raise DesignError(f"{solver} could not solve the SPC quadratic program (status {str(raw)!r}).")


class QpSolver:
    """A QP solver for successive SPC problems of one shape: set up once, then only the numbers updated.

    Parameters
    ----------
    max_iter : int, optional
        Iteration cap: default 100 for Clarabel (the thesis's cap, §6.6; it needs 8–17), 4000 for OSQP.
    eps : float, default 1e-8
        Clarabel's gap and feasibility tolerances, OSQP's absolute and relative ones, and the KKT check's.
    warm_start : bool, default True
        OSQP: start from the last solution (an interior-point method does not warm start).
    method : {"clarabel", "osqp"}, default "clarabel"
        Clarabel (interior point) or OSQP (ADMM); see the module notes for the choice.

    Examples
    --------
    >>> prob = SpcProblem(H=np.eye(2), c=np.array([-2.0, -2.0]), A=np.eye(2), b=np.array([0.5, 3.0]))
    >>> [np.round(QpSolver(method=m).solve(prob).u, 6) for m in ("clarabel", "osqp")]
    [array([0.5, 1. ]), array([0.5, 1. ])]

    References
    ----------
    Goulart & Chen 2024; Stellato et al. 2020; Hallouzi 2008, §6.6.
    """

    def __init__(self, max_iter: int | None = None, eps: float = 1e-8, warm_start: bool = True, *,
                 method: str = "clarabel") -> None:
        if method not in ("clarabel", "osqp"):
            raise ParameterError(f"method must be 'clarabel' or 'osqp'; got {method!r}.")
        self.max_iter = None if max_iter is None else validate.integer("max_iter", max_iter, minimum=1)
        self.eps = validate.positive("eps", eps)
        self.method, self.warm_start = method, bool(warm_start)
        self._solver = self._key = None

    def _setup(self, P, c, A, b, key):  # a new solver; CSC patterns (P's upper triangle, A's nonzeros) kept
        import scipy.sparse as sp

        (n, k, _), cap = key, self.max_iter or (100 if self.method == "clarabel" else 4000)
        self._pcol, self._prow = np.tril_indices(n)             # CSC order of the upper triangle
        self._acol, self._arow = np.nonzero(A.T)                # CSC order of A's nonzeros
        P_csc = sp.csc_matrix((P[self._prow, self._pcol], self._prow, np.r_[0, np.cumsum(np.arange(1, n + 1))]))
        A_csc = sp.csc_matrix((A[self._arow, self._acol], self._arow,
                               np.r_[0, np.cumsum(np.bincount(self._acol, minlength=n))]), shape=(k, n))
        if self.method == "clarabel":
            import clarabel
            st = clarabel.DefaultSettings()
            st.verbose, st.presolve_enable, st.input_sparse_dropzeros, st.max_iter = False, False, False, cap
            st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = self.eps
            self._solver = clarabel.DefaultSolver(P_csc, c, A_csc, b, [clarabel.NonnegativeConeT(k)], st)
        else:
            import osqp
            self._solver = osqp.OSQP()
            self._solver.setup(P=P_csc, q=c, A=A_csc, l=np.full(k, -np.inf), u=b, eps_abs=self.eps, eps_rel=self.eps,
                               max_iter=cap, polishing=True, verbose=False, warm_starting=self.warm_start)
        self._key = key

    def solve(self, problem: SpcProblem) -> QpSolution:
        """Solve ``min uᵀHu + cᵀu s.t. A u ≤ b``.

        Parameters
        ----------
        problem : SpcProblem

        Returns
        -------
        QpSolution

        Raises
        ------
        DesignError
            Infeasible constraints (relax the output limits, the usual culprit, or the rate limits), ``H`` not
            positive semidefinite, or a solver failure.
        ParameterError
            A non-finite bound in ``b``.
        """
        t0 = time.perf_counter()
        P = problem.H + problem.H.T                       # ½ uᵀ P u + cᵀ u  =  uᵀ H u + cᵀ u
        c, A, b = np.asarray(problem.c, dtype=float), np.asarray(problem.A, dtype=float), problem.b
        if not np.all(np.isfinite(b)):
            raise ParameterError("the bounds b must be finite: drop the rows without a bound (as spc_problem does).")
        try:                                              # a PSD H is the solvers' premise; Cholesky is cheap
            np.linalg.cholesky(P + 1e-12 * max(1.0, np.abs(P).max()) * np.eye(len(c)))
        except np.linalg.LinAlgError:
            _status("non convex", self.method)
        key = (len(c), A.shape[0], np.count_nonzero(A))
        if self._solver is None or key != self._key or np.count_nonzero(A[self._arow, self._acol]) != key[2]:
            self._setup(P, c, A, b, key)                  # a new shape, or A's nonzeros left the cached pattern
        else:                                             # only the .data of the cached patterns
            names = ("P", "q", "A", "b") if self.method == "clarabel" else ("Px", "q", "Ax", "u")
            self._solver.update(**dict(zip(names, (P[self._prow, self._pcol], c, A[self._arow, self._acol], b))))
        if self.method == "clarabel":
            res = self._solver.solve()
            status, x, iters = _status(res.status, "Clarabel"), np.array(res.x, dtype=float), int(res.iterations)
            xp = None if status == "max_iter" else _polish(P, c, A, b, np.asarray(res.z) > np.asarray(res.s), self.eps)
            polished, x = (True, xp) if xp is not None else (False, x)
        else:
            with contextlib.redirect_stdout(io.StringIO()):   # OSQP prints polishing notes even with verbose=False
                res = self._solver.solve(raise_error=False)
            status, x, iters = _status(res.info.status, "OSQP"), np.array(res.x, dtype=float), int(res.info.iter)
            polished = int(res.info.status_polish) == 1
        return QpSolution(u=x, status=status, iterations=iters, seconds=time.perf_counter() - t0, polished=polished)


def _polish(P, c, A, b, active, tol):
    """The KKT solution on the active set, or None unless it is primal and dual feasible and stationary."""
    Aa, n = A[active], len(c)
    try:
        sol = np.linalg.solve(np.block([[P, Aa.T], [Aa, np.zeros((len(Aa), len(Aa)))]]), np.r_[-c, b[active]])
    except np.linalg.LinAlgError:
        return None                                   # dependent active rows: keep the interior-point iterate
    xp, lam = sol[:n], sol[n:]                        # accept only a KKT point (optimal for a convex QP)
    ok = (np.all(np.isfinite(sol)) and np.max(A @ xp - b, initial=0.0) <= tol * (1.0 + np.abs(b).max(initial=0.0))
          and np.min(lam, initial=0.0) >= -tol * (1.0 + np.abs(lam).max(initial=0.0))
          and np.abs(P @ xp + c + Aa.T @ lam).max() <= tol * (1.0 + np.abs(c).max() + np.abs(P @ xp).max()))
    return xp if ok else None
