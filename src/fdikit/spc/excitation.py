"""Persistency of excitation for SPC: least-excited input directions and the excitation term, §5.3.

The input part ``Θ = [R_21 R_22]`` (M·m × ncols) of the RQ factor (5.14) has the SVD (5.39); its left
singular vectors ``w`` of the smallest singular values are the least-excited directions of the future
input space. :func:`least_excited` computes the ``count`` smallest triplets by inverse iteration on the
pseudo-inverse ``Θ^†`` (Chan 1984), with the deflation ``Θ̃^† = Θ^† − v w^T / σ`` (5.40) between them.
:func:`excitation_cost` adds ``τ J_exc`` (5.41)–(5.42) to a QP cost ``u^T H u + c^T u`` (the convention of
:mod:`fdikit.spc.law`, whose unconstrained minimiser is ``−(H + H^T)^{-1} c``): ``H_exc = H + τ I^T I``
(5.43) and ``c_exc = c − 2τ I^T P`` (5.44), ``P = ρ [w_1; …; w_k]``.

Dimensional ambiguity. In (5.41) the directions ``w ∈ R^{M·m}`` live in the space of the full future
input ``[u_{t+1}; …; u_{t+M}]``, while the QP variable is the blocked input ``u_f ∈ R^{N_c·m}`` with
``[u_{t+1}; …; u_{t+M}] = E u_f`` (the move-blocking matrix of (5.28)); the identity blocks of ``I`` in
(5.41) only fit when ``N_c = M``. It is resolved so: the default ``mode="full"`` compares ``ρ w`` with
the full future input, ``I = [E; …; E]`` (one ``E`` per direction), which reduces to the printed
``[I; …; I]`` when ``N_c = M``; ``mode="truncate"`` keeps identity blocks and compares ``u_f`` with the
first ``N_c·m`` entries of each ``ρ w``.

Sign. A singular vector is defined up to sign, and the sign decides which way the input is pushed. It is
fixed deterministically: with ``previous`` (the last blocked input sequence) each ``w`` is turned so
that ``w^T E previous ≥ 0`` (the excitation keeps the direction it already has, no chattering from step
to step); without it, or when ``w^T E previous = 0``, the largest-magnitude entry of ``w`` (first one on
ties) is made positive.

The routines are hand-written (``scipy.linalg.qr`` / ``solve_triangular`` for ``Θ^†``, ``pinv`` when
``Θ`` is rank deficient) because no library offers the deflated inverse iteration or the SPC
excitation term; a full SVD (``numpy.linalg.svd``) is what the tests compare with.

References
----------
Hallouzi 2008, §5.3, Def. 5.1, (5.38)–(5.44); Chan 1984 (inverse iteration and deflation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["LeastExcited", "excitation_cost", "least_excited"]


@dataclass(frozen=True)
class LeastExcited:
    """The smallest singular triplets of ``Θ`` (5.39), smallest first.

    Parameters
    ----------
    sigma : ndarray, shape (k,)
        Singular values, ascending (``s_{Mm}, s_{Mm−1}, …``).
    left : ndarray, shape (M·m, k)
        Left singular vectors ``w`` (the least-excited input directions), one per column.
    right : ndarray, shape (ncols, k)
        Right singular vectors ``v``, with ``Θ v = σ w``.
    iterations : ndarray of int, shape (k,)
        Inverse iterations used per triplet; equal to ``max_iter`` when the tolerance was not reached
        (the vector is then the last iterate, still a direction of small gain).

    References
    ----------
    Hallouzi 2008, §5.3.1, (5.39).

    Examples
    --------
    >>> r = least_excited(np.diag([3.0, 1.0, 2.0]), count=1)
    >>> round(float(r.sigma[0]), 9), np.round(r.left[:, 0], 9) + 0.0
    (1.0, array([0., 1., 0.]))
    """

    sigma: np.ndarray
    left: np.ndarray
    right: np.ndarray
    iterations: np.ndarray


def _pseudo_inverse(theta: np.ndarray) -> np.ndarray:
    """``Θ^†`` of a wide ``Θ``: ``Θ^T = Q R`` gives ``Θ^† = Q R^{-T}``; ``pinv`` when ``R`` is singular."""
    from scipy import linalg

    Q, R = linalg.qr(theta.T, mode="economic")
    d = np.abs(np.diag(R))
    if d.size and d.min() > max(theta.shape) * np.finfo(float).eps * d.max():
        return Q @ linalg.solve_triangular(R, np.eye(R.shape[0]), trans="T")
    return linalg.pinv(theta)


def _sign(w: np.ndarray) -> float:
    i = int(np.argmax(np.abs(w)))
    return -1.0 if w[i] < 0 else 1.0


def least_excited(theta, count: int = 2, *, tol: float = 1e-10, max_iter: int = 50,
                  start=None) -> LeastExcited:
    """The ``count`` least-excited directions of ``Θ`` by inverse iteration with deflation (5.39)–(5.40).

    Each triplet iterates ``ṽ = Θ^† w``, ``v = ṽ/|ṽ|``, ``w̃ = (Θ^†)^T v``, ``w = w̃/|w̃|`` until ``w``
    changes (up to sign) by at most ``tol``; then ``σ = 1/|Θ^† w|`` and ``Θ^†`` is deflated by
    ``v w^T / σ`` before the next triplet. Each ``w`` is signed so that its largest-magnitude entry is
    positive.

    Parameters
    ----------
    theta : array_like, shape (r, ncols), r ≤ ncols
        ``Θ = [R_21 R_22]`` (:attr:`SubspacePredictor.theta <fdikit.spc.predictor.SubspacePredictor.theta>`).
    count : int, default 2
        Number of triplets ``N_PE`` (1 … r).
    tol : float, default 1e-10
        Convergence tolerance on the unit vector ``w``.
    max_iter : int, default 50
        Iterations per triplet.
    start : array_like, shape (r,), optional
        Initial ``w`` (any nonzero vector); default a fixed pseudo-random unit vector (seed 0), so the
        result is reproducible.

    Returns
    -------
    LeastExcited

    Raises
    ------
    DataError
        ``theta`` is not a finite matrix, is taller than wide, or ``Θ^† w`` vanishes (``start`` lies in
        the deflated directions; give another).
    ParameterError
        Bad ``count``, ``tol``, ``max_iter`` or ``start``.

    References
    ----------
    Hallouzi 2008, §5.3.1, (5.39)–(5.40); Chan 1984.

    Examples
    --------
    >>> r = least_excited(np.diag([5.0, 0.5, 2.0, 0.1]), count=2)
    >>> np.round(r.sigma, 9)
    array([0.1, 0.5])
    >>> np.round(r.left, 9) + 0.0
    array([[0., 0.],
           [0., 1.],
           [0., 0.],
           [1., 0.]])
    """
    T = validate.as_matrix("theta", theta, error=DataError)
    r, ncols = T.shape
    if r == 0 or r > ncols:
        raise DataError(f"theta must be a wide matrix (rows ≤ columns), like [R21 R22]; got shape {T.shape}")
    count = validate.integer("count", count, minimum=1)
    if count > r:
        raise ParameterError(f"count must be at most the {r} rows of theta; got {count}")
    tol = validate.positive("tol", tol)
    max_iter = validate.integer("max_iter", max_iter, minimum=1)
    if start is None:
        w0 = np.random.default_rng(0).standard_normal(r)
    else:
        w0 = validate.as_vector("start", start, r)
    if not np.any(w0):
        raise ParameterError("start must be a nonzero vector; give a random one or leave it out")
    w0 = w0 / np.linalg.norm(w0)

    P = _pseudo_inverse(T)
    sigma = np.empty(count)
    left = np.empty((r, count))
    right = np.empty((ncols, count))
    iterations = np.zeros(count, dtype=int)
    for i in range(count):
        w = w0.copy()
        for it in range(1, max_iter + 1):
            vt = P @ w
            nv = np.linalg.norm(vt)
            if nv == 0.0:
                raise DataError(f"Θ^† w vanished at triplet {i + 1}: the start vector lies in the deflated "
                                f"directions; give another start")
            wt = P.T @ (vt / nv)
            w_new = wt / np.linalg.norm(wt)
            step = min(np.linalg.norm(w_new - w), np.linalg.norm(w_new + w))
            w = w_new
            iterations[i] = it
            if step <= tol:
                break
        vt = P @ w
        s = 1.0 / np.linalg.norm(vt)
        v = vt * s
        sgn = _sign(w)
        w, v = sgn * w, sgn * v
        sigma[i], left[:, i], right[:, i] = s, w, v
        P = P - np.outer(v, w) / s  # (5.40)
    return LeastExcited(sigma=sigma, left=left, right=right, iterations=iterations)


def excitation_cost(H, c, left, rho: float, tau: float, E, *, mode: str = "full",
                    previous=None) -> tuple[np.ndarray, np.ndarray]:
    """Add the excitation term ``τ J_exc`` (5.41)–(5.42) to a QP cost: ``(H_exc, c_exc)`` (5.43)–(5.44).

    With ``P = ρ [w_1; …; w_k]`` and ``I = [E; …; E]`` (``mode="full"``) or ``[I; …; I]`` with each
    ``w`` cut to its first ``N_c·m`` entries (``mode="truncate"``), ``J_exc = u^T I^T I u − 2 P^T I u``
    and the cost ``u^T H u + c^T u`` becomes ``u^T (H + τ I^T I) u + (c − 2τ I^T P)^T u``. See the module
    notes for the two modes and the sign rule.

    Parameters
    ----------
    H : array_like, shape (N_c·m, N_c·m)
        Quadratic term of the SPC cost (5.24).
    c : array_like, shape (N_c·m,)
        Linear term of the SPC cost (5.25).
    left : array_like, shape (M·m, k) or (M·m,)
        Least-excited directions ``w`` (:attr:`LeastExcited.left`).
    rho : float
        Excitation level ``ρ ≥ 0``.
    tau : float
        Weight ``τ ≥ 0``.
    E : array_like, shape (M·m, N_c·m)
        Move-blocking matrix: full future input = ``E u_f``.
    mode : {"full", "truncate"}, default "full"
        How ``w ∈ R^{M·m}`` is compared with ``u_f ∈ R^{N_c·m}``.
    previous : array_like, shape (N_c·m,), optional
        Last blocked input sequence, for the sign rule.

    Returns
    -------
    H_exc : ndarray, shape (N_c·m, N_c·m)
    c_exc : ndarray, shape (N_c·m,)

    Raises
    ------
    ParameterError
        Shapes that do not fit, negative ``rho`` or ``tau``, an unknown ``mode``.

    References
    ----------
    Hallouzi 2008, §5.3.2, (5.41)–(5.44).

    Examples
    --------
    >>> H_exc, c_exc = excitation_cost(np.eye(2), np.zeros(2), [0.0, -1.0], 2.0, 0.5, np.eye(2))
    >>> H_exc
    array([[1.5, 0. ],
           [0. , 1.5]])
    >>> c_exc                        # w turned to +e_2 (largest entry positive): −2 τ ρ w
    array([ 0., -2.])
    """
    mode = validate.choice("mode", mode, ("full", "truncate"))
    Em = validate.as_matrix("E", E)
    Mm, n = Em.shape
    Hm = validate.as_matrix("H", H, (n, n))
    cv = validate.as_vector("c", c, n)
    W = validate.as_array("left", left)
    if W.ndim == 1:
        W = W[:, None]
    if W.ndim != 2 or W.shape[0] != Mm or W.shape[1] == 0:
        raise ParameterError(f"left must be (M·m, k) = ({Mm}, k) like E's {Mm} rows; got shape {W.shape}")
    rho = validate.non_negative("rho", rho)
    tau = validate.non_negative("tau", tau)
    if mode == "truncate" and n > Mm:
        raise ParameterError(f"mode 'truncate' needs N_c·m ≤ M·m; E has {n} columns and {Mm} rows")
    Ep = None if previous is None else Em @ validate.as_vector("previous", previous, n)
    W = W.copy()
    for i in range(W.shape[1]):
        d = 0.0 if Ep is None else float(W[:, i] @ Ep)
        W[:, i] *= _sign(W[:, i]) if d == 0.0 else np.sign(d)
    k = W.shape[1]
    if mode == "full":
        block, P = Em, rho * W
    else:
        block, P = np.eye(n), rho * W[:n]
    # I^T I = k · block^T block; I^T P = Σ_i block^T (ρ w_i)
    H_exc = Hm + tau * k * (block.T @ block)
    c_exc = cv - 2.0 * tau * (block.T @ P.sum(axis=1))
    return H_exc, c_exc
