"""Order reductions of descriptor models that keep the transfer matrix: non-dynamic modes, minimal realisations.

* :func:`remove_nondynamic` eliminates the *non-dynamic modes* (simple infinite eigenvalues: the index-1
  algebraic variables) with ``E`` left general: in SVD coordinates ``E = diag(Σ, 0)``, the invertible part of
  the algebraic block ``A₂₂`` is solved for and substituted (a Schur complement; ``D`` is updated).  This is the
  reduction that the reference's ``gir`` (and ``gss2ss``) performs after its controllability/observability steps.
* :func:`minimal_realization` (``gminreal``-like) removes in addition every uncontrollable and unobservable
  eigenvalue, finite and infinite: the infinite and finite parts of ``A − λE`` are separated (the orthogonal
  staircase of :func:`fdikit.descriptor.staircase.split_infinite`, then the rows scaled to ``A∞ = I``,
  ``Ef = I`` and the generalised Sylvester equation solved as ``X − N X F = R``, a finite sum since ``N`` is
  nilpotent), the finite part ``Ef⁻¹(Af, Bf)`` and the infinite part
  ``A∞⁻¹(E∞, B∞)`` (a nilpotent standard system with the same Markov parameters ``C N^k B``) are each reduced
  by SLICOT ``TB01PD`` (orthogonal staircase, slycot), recombined, and the non-dynamic modes removed again.

Covered: regular pencils ``A − λE`` of any index, proper or improper, continuous or discrete.  Not covered: the
result of :func:`minimal_realization` has ``E = diag(I, N)`` (not the reference's upper-triangular ``E`` from
orthogonal transformations only): the parts are scaled by ``Ef⁻¹`` and ``A∞⁻¹`` and decoupled by a
(non-orthogonal) Sylvester transformation, so models with ``Ef``, ``A∞`` or the Sylvester solution badly
conditioned lose accuracy in proportion; no balancing is done.

References
----------
Varga (2017), §9.1.3 (non-dynamic modes, irreducible and minimal descriptor realisations), §10.3.1
(``gir``, ``gminreal``).  ``fdtools`` (through DescriptorSystems.jl ``gir``, ``gminreal``).
Varga (1990), "Computation of irreducible generalized state-space realizations", Kybernetika 26.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.descriptor.model import DescriptorModel
from fdikit.descriptor.staircase import split_infinite
from fdikit.errors import ModelError, ParameterError

__all__ = ["remove_nondynamic", "minimal_realization", "nondynamic_count"]

_EPS = float(np.finfo(float).eps)


def _check(model, tol):
    if not isinstance(model, DescriptorModel):
        raise ModelError(f"expected a fdikit.descriptor.DescriptorModel, got {type(model).__name__}; convert a "
                         "FaultModel with DescriptorModel.from_fault_model")
    if tol is not None:
        tol = validate.number("tol (relative rank tolerance)", tol)
        if not 0.0 <= tol < 1.0:
            raise ParameterError(f"tol (relative rank tolerance) must be in [0, 1), got {tol}")
    n = model.n
    rtol = n * n * _EPS if tol is None else tol
    return rtol * max(np.linalg.norm(model.A), np.linalg.norm(model.E), 1e-300), tol


def _svd_coordinates(model: DescriptorModel, thresh: float):
    """``Uᵀ(A, E, B)V``, ``C V`` with ``Uᵀ E V = diag(Σ, 0)``, ``Uᵀ A₂₂ V`` compressed: (A, E, B, C, r, k)."""
    n = model.n
    U, S, Vt = scipy.linalg.svd(model.E, lapack_driver="gesvd")
    r = int(np.sum(S > thresh))
    A, B, C = U.T @ model.A @ Vt.T, U.T @ model.B, model.C @ Vt.T
    E = np.zeros((n, n))
    E[:r, :r] = np.diag(S[:r])
    U2, S2, V2t = scipy.linalg.svd(A[r:, r:], lapack_driver="gesvd")
    k = int(np.sum(S2 > thresh))
    Q = scipy.linalg.block_diag(np.eye(r), U2)
    Z = scipy.linalg.block_diag(np.eye(r), V2t.T)
    A, B, C = Q.T @ A @ Z, Q.T @ B, C @ Z
    A[r:, r:] = 0.0
    A[r:r + k, r:r + k] = np.diag(S2[:k])
    return A, E, B, C, r, k


def nondynamic_count(model: DescriptorModel, *, tol: float | None = None) -> int:
    """The number of non-dynamic modes: ``rank A₂₂`` in SVD coordinates ``E = diag(Σ, 0)``.

    Parameters
    ----------
    model : DescriptorModel
        The model.
    tol : float, optional
        Relative rank tolerance (``tol · max(‖A‖_F, ‖E‖_F)``); default ``n² ε``.

    Returns
    -------
    int

    Raises
    ------
    ModelError
        If ``model`` is not a DescriptorModel.

    Examples
    --------
    >>> m = DescriptorModel([[-1.0, 0.0], [1.0, -1.0]], [[0.0, 1.0]], E=[[1.0, 0.0], [0.0, 0.0]], Bu=[[1.0], [0.0]])
    >>> nondynamic_count(m)
    1
    """
    thresh, _ = _check(model, tol)
    if model.n == 0:
        return 0
    return _svd_coordinates(model, thresh)[5]


def remove_nondynamic(model: DescriptorModel, *, tol: float | None = None) -> DescriptorModel:
    """Eliminate the non-dynamic modes (index-1 algebraic variables), keeping ``E`` general.

    In coordinates where ``E = diag(Σ, 0, 0)`` and ``A = [[A₁₁, A₁₂, A₁₃], [A₂₁, S, 0], [A₃₁, 0, 0]]`` (``S``
    diagonal, invertible), the middle equations ``0 = A₂₁ x₁ + S x₂ + B₂ u`` give ``x₂``; substituting it gives a
    model of order ``n − rank S`` with ``E = diag(Σ, 0)`` and ``D − C₂ S⁻¹ B₂``.  The transfer matrix is
    unchanged.  An index-1 model (``A₂₂`` invertible) comes out with ``E = Σ`` invertible.

    Parameters
    ----------
    model : DescriptorModel
        The model.
    tol : float, optional
        Relative rank tolerance for ``E`` and ``A₂₂``; default ``n² ε``.

    Returns
    -------
    DescriptorModel
        The reduced model (states renamed ``x0, ...``), or ``model`` itself when it has no non-dynamic mode.

    Raises
    ------
    ModelError
        If ``model`` is not a DescriptorModel.

    Examples
    --------
    >>> m = DescriptorModel([[-1.0, 0.0], [1.0, -1.0]], [[0.0, 1.0]], E=[[1.0, 0.0], [0.0, 0.0]], Bu=[[1.0], [0.0]])
    >>> r = remove_nondynamic(m)
    >>> r.n, float(round(r.poles()[0].real, 12))
    (1, -1.0)

    References
    ----------
    Varga (2017), §9.1.3 and §10.3.1 (``gir``).
    """
    thresh, _ = _check(model, tol)
    if model.n == 0:
        return model
    A, E, B, C, r, k = _svd_coordinates(model, thresh)
    if k == 0:
        return model
    n = model.n
    a = np.arange(r, r + k)
    keep = np.r_[np.arange(r), np.arange(r + k, n)]
    Sinv = 1.0 / np.diag(A)[a]
    Ka = A[np.ix_(keep, a)] * Sinv  # A_keep,a S⁻¹
    Ca = C[:, a] * Sinv
    A_new = A[np.ix_(keep, keep)] - Ka @ A[np.ix_(a, keep)]
    B_new = B[keep] - Ka @ B[a]
    C_new = C[:, keep] - Ca @ A[np.ix_(a, keep)]
    D_new = model.D - Ca @ B[a]
    return model.with_matrices(E[np.ix_(keep, keep)], A_new, B_new, C_new, D_new)


def _tb01pd(A, B, C, tol):
    """Minimal part of a standard ``(A, B, C)`` by SLICOT TB01PD (no balancing)."""
    from slycot import tb01pd

    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    if n == 0 or m == 0 or p == 0:
        return np.zeros((0, 0)), np.zeros((0, m)), np.zeros((p, 0))
    # slycot's wrapper wants B with max(m, p) columns and C with max(m, p) rows (SLICOT's workspace layout)
    k = max(m, p)
    Bp, Cp = np.zeros((n, k)), np.zeros((k, n))
    Bp[:, :m], Cp[:p] = B, C
    Ar, Br, Cr, nr = tb01pd(n, m, p, A.copy(), Bp, Cp, job="M", equil="N",
                            tol=1e3 * n * _EPS if tol is None else tol)
    return Ar[:nr, :nr], Br[:nr, :m], Cr[:p, :nr]


def minimal_realization(model: DescriptorModel, *, tol: float | None = None) -> DescriptorModel:
    """A minimal realisation: no uncontrollable or unobservable eigenvalue (finite or infinite), no non-dynamic mode.

    Parameters
    ----------
    model : DescriptorModel
        The model (any regular pencil; proper or improper).
    tol : float, optional
        Relative rank tolerance of every step (``TB01PD``'s lower bound on reciprocal condition numbers);
        default ``n² ε`` for the pencil steps and ``1e3 · n · ε`` for ``TB01PD`` (the rounding of the
        transformations before it exceeds SLICOT's own default ``n² ε``).  Cancellations that hold only
        to a looser accuracy (e.g. a series connection designed to cancel) need a larger ``tol`` (``1e-7``).

    Returns
    -------
    DescriptorModel
        ``E = diag(I, N)``, ``A = diag(Af, I)``: a standard finite part and a nilpotent infinite part (``N`` a
        minimal realisation of the polynomial part); ``E = I`` when the model is proper.  States ``x0, ...``.

    Raises
    ------
    ModelError
        If ``model`` is not a DescriptorModel.

    Examples
    --------
    >>> m = DescriptorModel([[-1.0, 0.0], [0.0, -2.0]], [[1.0, 1.0]], Bu=[[1.0], [0.0]])  # −2 is uncontrollable
    >>> minimal_realization(m).poles().real.tolist()
    [-1.0]

    References
    ----------
    Varga (2017), §10.3.1 (``gminreal``); Varga (1990).
    """
    thresh, tol = _check(model, tol)
    m = remove_nondynamic(model, tol=tol)
    n = m.n
    if n == 0:
        return m
    S = np.linalg.svd(m.E, compute_uv=False)
    if S[-1] > thresh:  # proper: a standard system
        Ar, Br, Cr = _tb01pd(np.linalg.solve(m.E, m.A), np.linalg.solve(m.E, m.B), m.C, tol)
        return m.with_matrices(np.eye(Ar.shape[0]), Ar, Br, Cr, m.D)
    Q, Z, ni = split_infinite(m.A, m.E, tol=tol)
    A, E, B, C = Q.T @ m.A @ Z, Q.T @ m.E @ Z, Q.T @ m.B, m.C @ Z
    i, f = slice(0, ni), slice(ni, n)
    # rows scaled to A∞ = I and Ef = I: the blocks are (N − λ·… ) with N = A∞⁻¹E∞ nilpotent and F = Ef⁻¹Af
    Ninf = np.linalg.solve(A[i, i], E[i, i])
    A12, E12, B1 = (np.linalg.solve(A[i, i], M) for M in (A[i, f], E[i, f], B[i]))
    F = np.linalg.solve(E[f, f], A[f, f])
    B2 = np.linalg.solve(E[f, f], B[f])
    # decoupling [[I, Y], [0, I]] (·) [[I, X], [0, I]]: X − N X F = E12 F − A12 (a finite sum, N nilpotent),
    # Y = −E12 − N X
    R = E12 @ F - A12
    X, term = R.copy(), R
    for _ in range(ni - 1):
        term = Ninf @ term @ F
        X += term
    Y = -E12 - Ninf @ X
    Ninf, Binf, Cinf = _tb01pd(Ninf, B1 + Y @ B2, C[:, i], tol)
    Af, Bf, Cf = _tb01pd(F, B2, C[:, i] @ X + C[:, f], tol)
    kf, ki = Af.shape[0], Ninf.shape[0]
    reduced = m.with_matrices(scipy.linalg.block_diag(np.eye(kf), Ninf), scipy.linalg.block_diag(Af, np.eye(ki)),
                              np.vstack([Bf, Binf]), np.hstack([Cf, Cinf]), m.D)
    return remove_nondynamic(reduced, tol=tol)
