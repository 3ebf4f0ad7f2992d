"""Least-degree left nullspace bases of ``[Gu Gd; I 0]``: the first step of every nullspace synthesis.

A residual generator ``Q(λ) = [Q_u(λ) Q_y(λ)]`` acting on ``[u; y]`` decouples the controls, the disturbances and
the nuisance faults exactly when ``Q(λ) [Gu Gd Gn; ... ]`` vanishes, that is when its rows lie in the left nullspace of

    G_e(λ) = [ Gu(λ)  Gd(λ) ]     (rows: y then u)
             [   I      0   ]

(Varga 2017, §5.2, eq. (5.11) and Procedure EFD, Step 1).  The reference computes a proper basis of that nullspace
from the Kronecker-like staircase form of the system pencil (``glnull``).  fdikit computes the same object as a
**minimal polynomial basis** (Forney): the rows ``N_i(λ) = Σ_j N_ij λ^j`` of least degrees ``ν_1 ≤ ν_2 ≤ …``
(the left minimal indices of ``G_e``), found degree by degree as the parity relations of order ``k`` that are not
shifts ``λ^i N_b(λ)`` of lower-degree ones (the dimension count of the parity spaces of order ``k`` gives the
number of indices equal to ``k``).  Dividing row ``i`` by a stable monic polynomial ``φ_i`` of degree ``ν_i``
gives a simple proper basis (each row of McMillan degree ``ν_i``, total ``Σ ν_i``, the least order of any proper
basis; Varga 2017, §7.4 and ``simple = true``), and any ``q`` constant combinations of the rows of degree ``≤ d``
over one ``φ`` of degree ``d`` are proper filters of order ``d`` — the least-order synthesis of Procedure EFD.

Why by hand: no Python library computes rational nullspaces (slycot exposes zeros and Kronecker indices of a
system pencil, ``ab08nd``, but not the basis).  The parity matrices are formed in the frequency-scaled variable
``μ = λ / α`` with ``α`` the norm of the reduced ``A`` (so that ``A / α`` has norm 1 and the powers stay bounded),
rank decisions are SVD-based and relative to each matrix's norm, and the realisation of row ``i`` is an observer
canonical form in ``μ``, mapped back by ``(α A_o, α B_o, C_o, D_o)``.  The stable denominators replace the
reference's coprime factorisation by generalised-Schur pole placement (``glcf``): the numerator polynomial is the
same up to the left unimodular factor, so degrees, decoupling and structure are the same; the state coordinates
of the filters differ.  Only standard state-space models (``E = I``) are handled here; a proper descriptor model is
turned into one first (:meth:`fdikit.descriptor.DescriptorModel.to_fault_model`).

References
----------
Varga (2017), §5.2 (nullspace method), §7.4 (proper and polynomial nullspace bases, simple bases, least order);
fdtools (``glnull``, ``efdsyn``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

__all__ = ["NullspaceBasis", "left_nullspace", "denominator", "realize_rows", "default_sdeg", "minimal_realization"]


def default_sdeg(dt: float | None) -> float:
    """The reference's default stability degree of the filter poles: −0.05 (continuous), 0.95 (discrete).

    Parameters
    ----------
    dt : float or None
        The model's sample time.

    Returns
    -------
    float

    Examples
    --------
    >>> default_sdeg(None), default_sdeg(0.01)
    (-0.05, 0.95)

    References
    ----------
    Varga (2017), §5.2 (``sdeg``); fdtools (``efdsyn`` defaults).
    """
    return -0.05 if dt is None else 0.95


def denominator(degree: int, poles: Sequence[complex] | None, sdeg: float | None, dt: float | None) -> np.ndarray:
    """The monic stable denominator ``φ`` of a filter row of ``degree``: its coefficients, highest power first.

    Parameters
    ----------
    degree : int
        The degree of ``φ`` (the order of the filter row).
    poles : sequence of complex, optional
        The assigned poles; the first ``degree`` are used (complex ones in conjugate pairs).
    sdeg : float, optional
        Used when ``poles`` is None: all ``degree`` poles at ``sdeg`` (default :func:`default_sdeg`).
    dt : float or None
        The sample time (the stability region of ``sdeg`` and ``poles``).

    Returns
    -------
    numpy.ndarray
        ``degree + 1`` real coefficients of ``φ(λ)``, leading 1.

    Raises
    ------
    ParameterError
        Too few poles, unstable ones, or a selection that is not closed under conjugation.

    Examples
    --------
    >>> denominator(2, None, -1.0, None).tolist()
    [1.0, 2.0, 1.0]

    References
    ----------
    Varga (2017), §5.1 (stable denominators of the proper basis) and §7.5 (coprime factorisation).
    """
    if poles is None:
        s = default_sdeg(dt) if sdeg is None else float(sdeg)
        if (dt is None and s >= 0) or (dt is not None and not abs(s) < 1):
            raise ParameterError(f"sdeg={s} is not a stable pole ({'Re < 0' if dt is None else '|z| < 1'}); "
                                 "give a stable stability degree")
        chosen = np.full(degree, s, dtype=complex)
    else:
        pl = np.asarray(poles, dtype=complex).ravel()
        if pl.size < degree:
            raise ParameterError(f"{pl.size} poles given for a filter of order {degree}; give at least {degree}")
        chosen = pl[:degree]
        bad = chosen[chosen.real >= 0] if dt is None else chosen[np.abs(chosen) >= 1]
        if bad.size:
            raise ParameterError(f"poles {bad.tolist()} are not stable; the filter poles must be stable")
    c = np.poly(chosen) if degree else np.ones(1)
    if np.max(np.abs(c.imag), initial=0.0) > 1e-9 * np.max(np.abs(c)):
        raise ParameterError(f"the first {degree} poles {chosen.tolist()} are not closed under conjugation; "
                             "order them so that each complex pole is followed by its conjugate")
    return c.real.copy()


def realize_rows(rows: Sequence[np.ndarray], dens: Sequence[np.ndarray], scale: float):
    """State-space realisation of the rows ``N_i(μ) / φ_i(λ)``, block diagonal, ``μ = λ / scale``.

    Parameters
    ----------
    rows : sequence of numpy.ndarray
        Row ``i``: the ``(d_i + 1, m)`` coefficients of ``N_i(μ)``, constant term first.
    dens : sequence of numpy.ndarray
        Row ``i``: the monic ``φ_i(λ)`` of degree ``d_i`` (:func:`denominator`), highest power first.
    scale : float
        ``α`` of ``μ = λ / α``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(A, B, C, D)`` of order ``Σ d_i`` with ``m`` inputs and one output per row.

    Examples
    --------
    ``(1 + λ) / (λ + 2)`` as one row with one input:

    >>> A, B, C, D = realize_rows([np.array([[1.0], [1.0]])], [np.array([1.0, 2.0])], 1.0)
    >>> A.tolist(), B.tolist(), C.tolist(), D.tolist()
    ([[-2.0]], [[-1.0]], [[1.0]], [[1.0]])

    References
    ----------
    Varga (2017), §7.4 (realisation of a polynomial basis over its denominators).
    """
    m = rows[0].shape[1]
    blocks = []
    for N, phi in zip(rows, dens):
        d = N.shape[0] - 1
        # φ(λ) = Σ c_k λ^(d-k) in μ = λ/α: φ(αμ)/α^d is monic with coefficients c_k α^(-k)
        a = (phi * scale ** -np.arange(d + 1.0))[::-1][:d]          # a_0 … a_{d-1} of the μ polynomial
        Dd = N[d][None, :]
        if d == 0:
            blocks.append((np.zeros((0, 0)), np.zeros((0, m)), np.zeros((1, 0)), Dd))
            continue
        Ao = np.zeros((d, d))
        Ao[1:, :-1] = np.eye(d - 1)
        Ao[:, -1] = -a
        Bo = N[:d] - a[:, None] * N[d][None, :]
        Co = np.zeros((1, d))
        Co[0, -1] = 1.0
        blocks.append((scale * Ao, scale * Bo, Co, Dd))
    from scipy.linalg import block_diag

    A = block_diag(*[b[0] for b in blocks]) if sum(b[0].shape[0] for b in blocks) else np.zeros((0, 0))
    n = A.shape[0]
    B = np.vstack([b[1] for b in blocks]) if n else np.zeros((0, m))
    C = block_diag(*[b[2] for b in blocks]) if n else np.zeros((len(rows), 0))
    D = np.vstack([b[3] for b in blocks])
    return A, B.reshape(n, m), C.reshape(len(rows), n), D


def minimal_realization(A, B, C, D, tol: float = 1e-7):
    """A minimal realisation of ``(A, B, C, D)``: slycot's ``tb01pd`` (orthogonal staircase forms).

    Parameters
    ----------
    A, B, C, D : numpy.ndarray
        The realisation.
    tol : float, default 1e-7
        ``tb01pd``'s rank tolerance: a lower bound of the reciprocal condition number of the blocks kept (a
        relative tolerance; the reference's tests use ``atol = 1e-7``).  ``tb01pd``'s own default ``n² ε`` keeps
        unobservable modes of series connections that a filter cancels (Example 5.4 keeps two of them).

    Returns
    -------
    tuple of numpy.ndarray

    Examples
    --------
    >>> A, B, C, D = minimal_realization(np.diag([2.0, 3.0, -3.0]), np.ones((3, 1)), [[0.0, 0.0, 1.0]], [[0.0]])
    >>> np.round(A, 9).tolist()
    [[-3.0]]

    References
    ----------
    Varga (2017), §7.3 (minimal realisations; SLICOT ``TB01PD``).
    """
    import control

    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    n, m, p = A.shape[0], D.shape[1], D.shape[0]
    if n == 0 or A.size == 0:
        return np.zeros((0, 0)), np.zeros((0, m)), np.zeros((p, 0)), D
    sys = control.ss(A, B.reshape(n, m), C.reshape(p, n), D).minreal(tol)
    k = sys.nstates
    return (np.asarray(sys.A).reshape(k, k), np.asarray(sys.B).reshape(k, m), np.asarray(sys.C).reshape(p, k),
            np.asarray(sys.D).reshape(p, m))


def _decoupled_realization(model: FaultModel, cols: list[int]):
    """A minimal realisation of the columns ``cols`` of ``[B; D]`` (controls, disturbances, nuisance faults)."""
    B, D = model.B[:, cols], model.D[:, cols]
    if model.n == 0 or B.shape[1] == 0:
        return np.zeros((0, 0)), np.zeros((0, B.shape[1])), np.zeros((model.C.shape[0], 0)), D
    return minimal_realization(model.A, B, model.C, D)


def _toeplitz(C, A, B, D, k):
    """Block lower-triangular ``T_k``: ``D`` on the diagonal, ``C A^(i-j-1) B`` below it."""
    p, m = D.shape
    markov = [D]
    AkB = B
    for _ in range(k):
        markov.append(C @ AkB)
        AkB = A @ AkB
    T = np.zeros(((k + 1) * p, (k + 1) * m))
    for i in range(k + 1):
        for j in range(i + 1):
            T[i * p:(i + 1) * p, j * m:(j + 1) * m] = markov[i - j]
    return T


def _canonical(V: np.ndarray) -> np.ndarray:
    """A basis of the row space of the orthonormal ``V`` that does not depend on the rotation ``V`` came in.

    The new rows of one degree span a unique space, but the SVD returns them in a rotation that rounding (and so the
    BLAS kernel) decides when their singular values are equal.  Projecting fixed vectors ``Z`` onto the space and
    orthonormalising them (QR with a positive diagonal) gives the same rows for every rotation, continuously in the
    space, so ``selection=`` means the same filter on every machine.  When the space is all of ``R^L`` (degree 0
    without decoupled inputs) the rows are the unit vectors: the residuals are the outputs, in order, as the
    reference's basis ``I`` has them.
    """
    q, L = V.shape
    if q <= 1:
        return V
    if q == L:               # the whole space (no decoupled input reaches the outputs): the outputs themselves
        return np.eye(L)
    Z = np.random.default_rng(20170).standard_normal((L, q))
    Qx, Rx = np.linalg.qr(V.T @ (V @ Z))
    return (Qx * np.sign(np.diag(Rx))).T


def _null_rows(M: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal rows spanning the left null space of ``M`` (rank relative to ``‖M‖``)."""
    if M.shape[1] == 0:
        return np.eye(M.shape[0])
    U, s, _ = np.linalg.svd(M, full_matrices=True)
    r = int(np.sum(s > tol * max(s[0] if s.size else 0.0, 1e-300)))
    return U[:, r:].T


def _normal_rank(A, B, C, D, scale: float) -> int:
    """Normal rank of ``C (λI − A)^{-1} B + D`` from two generic points."""
    if B.shape[1] == 0:
        return 0
    n = A.shape[0]
    best = 0
    for z in (0.613 + 0.791j, -0.377 + 1.93j):
        G = D + (C @ np.linalg.solve(z * scale * np.eye(n) - A, B) if n else 0)
        s = np.linalg.svd(G, compute_uv=False)
        best = max(best, int(np.sum(s > 1e-10 * max(s[0], 1e-300))) if s.size else 0)
    return best


@dataclass(frozen=True, eq=False)
class NullspaceBasis:
    """A minimal polynomial basis of the left nullspace of ``[Gu Gd Gn; I 0 0]`` and its proper realisation.

    Attributes
    ----------
    rows : tuple of numpy.ndarray
        Row ``i``: the ``(ν_i + 1, mu + p)`` coefficients of ``N_i(μ)``, constant term first, in the scaled
        variable ``μ = λ / scale``; columns are ``[u; y]`` (fdikit's generator input order).  Each row has unit norm.
    degrees : tuple of int
        ``ν_i``, ascending: the left minimal indices (Varga 2017, §7.4).
    scale : float
        ``α`` of ``μ = λ / α``.
    controls, outputs : tuple of str
        The signals the rows act on.
    nuisance : tuple of str
        The fault inputs decoupled with the controls and disturbances.
    dt : float or None
        Sample time of the model.

    Examples
    --------
    >>> from fdikit.model import FaultModel
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bd=[[1.0]], Bf=np.eye(1), Df=[[0.0], [1.0]])
    >>> b = left_nullspace(m)
    >>> b.degrees
    (0,)

    References
    ----------
    Varga (2017), §7.4 (minimal polynomial bases) and §5.1 (the nullspace method); Forney (1975).
    """

    rows: tuple[np.ndarray, ...]
    degrees: tuple[int, ...]
    scale: float
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    nuisance: tuple[str, ...]
    dt: float | None

    def evaluate(self, lam: complex, rows: Sequence[int] | None = None) -> np.ndarray:
        """``N(λ)`` at one complex point: the numerator rows (without denominators), ``(q, mu + p)``.

        Parameters
        ----------
        lam : complex
            The point ``λ`` (``s`` or ``z``).
        rows : sequence of int, optional
            Which rows (default all).

        Returns
        -------
        numpy.ndarray
        """
        idx = range(len(self.rows)) if rows is None else rows
        mu = lam / self.scale
        return np.array([np.polynomial.polynomial.polyval(mu, self.rows[i]) for i in idx]).reshape(len(idx), -1)

    def generator(self, poles: Sequence[complex] | None = None, sdeg: float | None = None, names=None):
        """The simple proper basis: one residual per row, row ``i`` over its own stable ``φ_i`` of degree ``ν_i``.

        Parameters
        ----------
        poles, sdeg : optional
            As :func:`denominator` (the first ``ν_i`` poles for row ``i``).
        names : sequence of str, optional
            Residual names (default ``n0, n1, …``).

        Returns
        -------
        ResidualGenerator
            Order ``Σ ν_i``, inputs ``[u; y]``.
        """
        from fdikit.residuals import ResidualGenerator

        dens = [denominator(nu, poles, sdeg, self.dt) for nu in self.degrees]
        A, B, C, D = realize_rows(self.rows, dens, self.scale)
        names = tuple(f"n{i}" for i in range(len(self.rows))) if names is None else tuple(names)
        return ResidualGenerator(A, B, C, D, controls=self.controls, outputs=self.outputs, residuals=names,
                                 dt=self.dt)

    def combined(self, H: np.ndarray, rows: Sequence[int]) -> list[np.ndarray]:
        """The rows ``H @ N_rows(μ)`` as coefficient arrays padded to the largest degree of ``rows``.

        Parameters
        ----------
        H : numpy.ndarray
            ``(q, len(rows))`` combination.
        rows : sequence of int
            The basis rows combined.

        Returns
        -------
        list of numpy.ndarray
            ``q`` arrays ``(d + 1, mu + p)`` with ``d = max degree``.
        """
        d = max(self.degrees[i] for i in rows)
        padded = np.zeros((len(rows), d + 1, self.rows[0].shape[1]))
        for k, i in enumerate(rows):
            padded[k, : self.degrees[i] + 1] = self.rows[i]
        return [np.tensordot(h, padded, axes=1) for h in np.atleast_2d(H)]


def left_nullspace(model: FaultModel, nuisance: Sequence[str] = (), *, tol: float = 1e-9) -> NullspaceBasis:
    """The minimal polynomial basis of the left nullspace of ``[Gu Gd Gn; I 0 0]`` (``Gn``: nuisance faults).

    Parameters
    ----------
    model : FaultModel
        The plant (continuous or discrete); its controls, disturbances and the ``nuisance`` fault inputs are
        decoupled.  Noise inputs are ignored (exact synthesis).
    nuisance : sequence of str, default ()
        Fault inputs (group ``f``) to decouple as well.
    tol : float, default 1e-9
        Relative rank tolerance of the parity matrices (singular values below ``tol · ‖M_k‖`` count as zero).

    Returns
    -------
    NullspaceBasis
        ``p − rank [Gd Gn]`` rows of ascending degree; an empty basis (no rows) when the outputs carry no
        information free of the decoupled inputs.

    Raises
    ------
    ParameterError, ModelError
        A nuisance name that is no fault input of the model.
    DesignError
        When the degree search exceeds the state dimension (a rank decision failed; loosen ``tol``).

    Examples
    --------
    Two measurements of one state with a disturbance on the state: one static relation ``y1 − y2``.

    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bd=[[1.0]])
    >>> b = left_nullspace(m)
    >>> b.degrees, np.round(b.rows[0] * np.sqrt(2), 6).tolist()
    ((0,), [[1.0, -1.0]])

    References
    ----------
    Varga (2017), §5.2 eq. (5.11), §7.4; fdtools (``glnull``).
    """
    from fdikit.fault_maps import check_fault_inputs

    nuisance = tuple(check_fault_inputs(model, nuisance, "nuisance fault")) if nuisance else ()
    if not (np.isfinite(tol) and 0 < tol < 1):
        raise ParameterError(f"tol must be in (0, 1), got {tol}")
    mu, md = len(model.controls), len(model.disturbances)
    nf0 = mu + md
    cols = list(range(nf0)) + [nf0 + i for i in model.index("f", nuisance)]
    A, B, C, D = _decoupled_realization(model, cols)
    n, p = A.shape[0], C.shape[0]
    scale = max(1.0, float(np.linalg.norm(A, 2))) if n else 1.0
    As, Bs = A / scale, B / scale
    Bu, Bw = Bs[:, :mu], Bs[:, mu:]
    Du, Dw = D[:, :mu], D[:, mu:]
    target = p - _normal_rank(A, B[:, mu:], C, D[:, mu:], scale)
    found: list[np.ndarray] = []           # y-coefficients (k+1, p) of each basis row
    degrees: list[int] = []
    O = np.zeros((0, n))
    CAk = C.copy()
    for k in range(n + 1):
        if len(found) >= target:
            break
        O = np.vstack([O, CAk])
        CAk = CAk @ As
        M = np.hstack([O, _toeplitz(C, As, Bw, Dw, k)])
        P = _null_rows(M, tol)
        shifts = [np.concatenate([np.zeros(i * p), v.ravel(), np.zeros((k - degrees[b] - i) * p)])
                  for b, v in enumerate(found) for i in range(k - degrees[b] + 1)]
        if shifts:
            S = np.linalg.qr(np.array(shifts).T)[0]
            P = P - (P @ S) @ S.T
        if P.shape[0]:
            _, s, Vt = np.linalg.svd(P, full_matrices=False)
            new = _canonical(Vt[: int(np.sum(s > 1e-6))])  # P's rows orthonormal: s ≈ 1 (new) or ≈ 0 (a shift)
        else:
            new = P
        for v in new[: target - len(found)]:
            found.append(v.reshape(k + 1, p))
            degrees.append(k)
    if len(found) < target:
        raise DesignError(f"the nullspace basis search found {len(found)} of {target} rows up to degree {n}; "
                          f"a rank decision failed at tol={tol} (try a larger tol)")
    rows = []
    for v in found:
        k = v.shape[0] - 1
        w = -(v.reshape(1, -1) @ _toeplitz(C, As, Bu, Du, k)).reshape(k + 1, mu)
        row = np.hstack([w, v]).ravel()
        lead = row[np.flatnonzero(np.abs(row) > 1e-6 * np.max(np.abs(row)))[0]]     # sign: first clear entry > 0
        rows.append((np.sign(lead) / np.linalg.norm(row)) * row.reshape(k + 1, -1))
    return NullspaceBasis(tuple(rows), tuple(degrees), scale, model.controls, model.outputs, nuisance, model.dt)
