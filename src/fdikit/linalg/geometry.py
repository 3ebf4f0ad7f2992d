"""The geometry of detection filters: CAISA, invariant zeros, detection spaces, separability, projectors.

Built on the subspace primitives of :mod:`fdikit.linalg.subspaces`; every tolerance scales with the
data (``1e3 · max(shape) · eps · σ_max`` by default, or a caller's relative tolerance).
The fault maps ``F`` these functions take are built by :mod:`fdikit.fault_maps`.

* the minimal (C, A)-invariant subspace containing ``F`` by CAISA (App. A, Theorem A.1,
  with ``W⁰ = 0``: the report prints ∅, which is not a subspace; the
  iteration starts from the zero subspace);
* invariant zeros of ``(C, A, F)`` and their state directions from the Rosenbrock pencil;
* the minimal unobservability subspace ``T* = W* ⊕ V`` (§4.1, App. A.3), output
  separability (a.7) and mutual detectability (§4.1).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.linalg.subspaces import EPS, as_2d, checked_rtol, intersect, null, orth, rank, span_sum

__all__ = [
    "output_projector",
    "caisa",
    "invariant_zeros",
    "detection_space",
    "output_separable",
    "mutually_detectable",
]


def _system(A, C, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A`` (n x n), ``C`` (p x n), ``F`` (n x k) as finite float matrices, shapes checked."""
    A = validate.as_square("A", A)
    n = A.shape[0]
    C = validate.as_matrix("C", np.atleast_2d(C) if np.ndim(C) == 1 else C, (None, n))
    F = validate.as_matrix("F", np.reshape(F, (-1, 1)) if np.ndim(F) == 1 else F, (n, None))
    return A, C, F


# ---------------------------------------------------------------------- geometry
def caisa(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal (C, A)-invariant subspace containing ``Im F`` (CAISA, Douglas et al. 1996, Thm. A.1).

    ``W⁰ = 0``, ``W^{k+1} = Im F + A (W^k ∩ Ker C)``; the sequence is nondecreasing and
    stops within ``n`` steps.  Returns an orthonormal basis.

    Parameters
    ----------
    A : array_like
        (n, n) state matrix.
    C : array_like
        (p, n) output matrix (a vector is one row).
    F : array_like
        (n, k) fault map (a vector is one column).
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (n, dim W*) orthonormal basis of ``W*``.

    Raises
    ------
    ParameterError
        If ``A`` is not square, ``C`` or ``F`` does not match its n states, a matrix is not finite, or
        ``rtol`` is negative.

    References
    ----------
    Douglas et al. 1996, App. A.3, Theorem A.1 (the report's ``W⁰ = ∅`` read as the zero subspace).

    Examples
    --------
    With ``C F₁ ≠ 0`` the subspace is ``Im F₁`` itself:

    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> from fdikit.linalg import contains
    >>> W = caisa(m.A, m.C, m.Bf[:, 0])
    >>> W.shape, contains(W, m.Bf[:, 0])
    ((3, 1), True)
    """
    A, C, F = _system(A, C, F)
    rtol = checked_rtol(rtol)
    kerC = null(C, rtol)
    W = orth(F, rtol)
    for _ in range(A.shape[0] + 1):
        part = intersect(W, kerC, rtol)
        W_next = span_sum(F, A @ part, rtol=rtol) if part.shape[1] else orth(F, rtol)
        if W_next.shape[1] == W.shape[1]:
            return W_next
        W = W_next
    return W


def invariant_zeros(
    A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Invariant zeros of ``(C, A, F)`` and their state directions.

    The zeros are the finite generalised eigenvalues of the Rosenbrock pencil
    ``[[A − sI, F], [C, 0]]``, computed by SLICOT ``AB08ND`` (slycot) for square and
    non-square systems alike.  ``rtol`` is AB08ND's rank-decision tolerance (reciprocal
    condition bound); the default ``1e5 · (n + max(p, k)) · eps`` (about 1e-10 for n = 6)
    scales with the pencil's size.  AB08ND's own default, ``sqrt((n+p)(n+k)) · eps``, misses
    zeros of ordinary, moderately conditioned systems (an unobservable mode in random
    coordinates was lost in about one case in five).

    For each zero ``z`` the direction is the state part ``x`` of a null vector of
    ``[[A − zI, F], [C, 0]]`` (complex for a complex zero), unit norm.  A multiple zero
    (a cluster of computed zeros with parallel directions) gets directions that span its
    whole generalised zero space: independent null vectors when the zero has several
    directions, and Jordan-chain vectors ``(A − zI) x₂ + F η₂ = x₁, C x₂ = 0`` when it is
    defective.  So ``span(directions)`` is always the invariant-zero subspace ``V`` that
    :func:`detection_space` adds to ``W*``.

    Parameters
    ----------
    A : array_like
        (n, n) state matrix.
    C : array_like
        (p, n) output matrix (a vector is one row).
    F : array_like
        (n, k) fault map (a vector is one column).
    rtol : float, optional
        AB08ND's rank-decision tolerance; default ``1e5 · (n + max(p, k)) · eps``.

    Returns
    -------
    zeros : numpy.ndarray
        (ν,) complex array of the finite invariant zeros (imaginary round-off set to zero); empty if none.
    directions : list of numpy.ndarray
        One unit (n,) state direction per zero, in the same order (complex for a complex zero).

    Raises
    ------
    ParameterError
        If ``A`` is not square, ``C`` or ``F`` does not match its n states, a matrix is not finite, or
        ``rtol`` is negative.

    References
    ----------
    Murray 2012, §2.1.2, (2.12) (zero and direction); Douglas et al. 1996, §4.1 and App. A.3 (the zero
    directions ``V``).

    Examples
    --------
    The second White–Speyer fault has the zero −3 with direction ``e₁``:

    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> z, dirs = invariant_zeros(m.A, m.C, m.Bf[:, 1])
    >>> np.round(z.real, 6).tolist(), np.round(np.abs(dirs[0]), 6).tolist()
    ([-3.0], [1.0, 0.0, 0.0])
    """
    from slycot import ab08nd

    A, C, F = _system(A, C, F)
    rtol = checked_rtol(rtol)
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex), []
    tol = rtol if rtol is not None else 1e5 * (n + max(p, k)) * EPS
    out = ab08nd(n, k, p, A, F, C, np.zeros((p, k)), equil="N", tol=tol)
    nu = out[0]
    if nu == 0:
        return np.zeros(0, dtype=complex), []
    zeros = np.asarray(scipy.linalg.eigvals(out[8][:nu, :nu], out[9][:nu, :nu]), dtype=complex)
    zeros = zeros[np.isfinite(zeros)]
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(F, 2), np.linalg.norm(C, 2), 1.0)
    zeros = np.where(np.abs(zeros.imag) <= 1e-12 * scale, zeros.real, zeros)  # round-off imaginary parts
    return zeros, _zero_directions(A, C, F, zeros)


def _null_direction(M: np.ndarray, E: np.ndarray, z: complex, n: int) -> np.ndarray:
    """State part of the right singular vector of ``M − zE`` for its smallest singular value."""
    x = np.linalg.svd(M - z * E)[2][-1].conj()[:n]
    return x / max(np.linalg.norm(x), EPS)


def _zero_directions(A: np.ndarray, C: np.ndarray, F: np.ndarray, zeros: np.ndarray) -> list[np.ndarray]:
    """Directions of ``zeros`` (see :func:`invariant_zeros`): one unit vector per zero, clusters spanning V.

    Zeros within ``1e-5 · ‖[[A, F], [C, 0]]‖`` whose individual directions are (nearly) parallel are
    one multiple zero (a defective double zero splits by ~√eps): its directions are recomputed at the
    cluster mean from the null space of the pencil and, if that is too small, from Jordan chains.
    """
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    M = np.block([[A, F], [C, np.zeros((p, k))]])
    E = np.zeros_like(M)
    E[:n, :n] = np.eye(n)
    scale = max(np.linalg.norm(M, 2), 1.0)
    dirs = [_null_direction(M, E, z, n) for z in zeros]
    todo = list(range(len(zeros)))
    while todo:
        i = todo[0]
        members = [j for j in todo if abs(zeros[j] - zeros[i]) <= 1e-5 * scale]
        todo = [j for j in todo if j not in members]
        m = len(members)
        if m == 1:
            continue
        sv = np.linalg.svd(np.column_stack([dirs[j] for j in members]), compute_uv=False)
        if sv[-1] > 1e-3 * sv[0]:  # distinct close zeros with their own directions
            continue
        z = np.mean(zeros[members])
        if abs(z.imag) <= 1e-14 * scale:  # a real multiple zero (a defective one splits into a conjugate pair)
            z = z.real
        P = M - z * E  # real for a real zero, so its directions are real
        # eigen-directions first: null vectors of P(z) (at least one, at most m)
        _, s, Vh = np.linalg.svd(P)
        s = np.concatenate([s, np.zeros(Vh.shape[0] - s.size)])
        r1 = int(np.clip((s <= 1e-8 * max(s[0], EPS)).sum(), 1, m))
        U = np.linalg.svd(Vh[-r1:, :n].conj().T, full_matrices=False)[0][:, :r1]
        if r1 < m:  # defective: complete with chain vectors, P v1 = 0, P v2 = E v1, …, stacked block-bidiagonally
            K = np.kron(np.eye(m), P) - np.kron(np.eye(m, k=-1), E)
            _, s, Vh = np.linalg.svd(K)
            s = np.concatenate([s, np.zeros(Vh.shape[0] - s.size)])
            keep = np.union1d(np.flatnonzero(s <= 1e-8 * max(s[0], EPS)), np.arange(Vh.shape[0] - m, Vh.shape[0]))
            N = Vh[keep].conj().T
            X = np.hstack([N[b * (n + k) : b * (n + k) + n] for b in range(m)])
            X = X - U @ (U.conj().T @ X)
            U = np.hstack([U, np.linalg.svd(X)[0][:, : m - r1]])
        for j, col in zip(members, U.T):
            dirs[j] = col / max(np.linalg.norm(col), EPS)
    return dirs


def _real_span(vectors: Sequence[np.ndarray], n: int) -> np.ndarray:
    if not vectors:
        return np.zeros((n, 0))
    V = np.column_stack(vectors)
    return np.hstack([V.real, V.imag])


def detection_space(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal unobservability subspace containing ``Im F``: ``T* = W* ⊕ V`` (Douglas et al. 1996, §4.1).

    ``W*`` from :func:`caisa`, ``V`` the span of the invariant-zero directions of
    ``(C, A, F)``.  Orthonormal basis (n x ν).

    Parameters
    ----------
    A : array_like
        (n, n) state matrix.
    C : array_like
        (p, n) output matrix (a vector is one row).
    F : array_like
        (n, k) fault map (a vector is one column).
    rtol : float, optional
        Rank tolerance of :func:`caisa` and of the sum (see :func:`rank`); the zeros use
        :func:`invariant_zeros`' default.

    Returns
    -------
    numpy.ndarray
        (n, ν) orthonormal basis of ``T*`` (real: a complex direction contributes its real and imaginary
        parts).

    Raises
    ------
    ParameterError
        If ``A`` is not square, ``C`` or ``F`` does not match its n states, a matrix is not finite, or
        ``rtol`` is negative.

    References
    ----------
    Douglas et al. 1996, §4.1 and App. A.3 (``T*ᵢ = W*ᵢ ⊕ Vᵢ``).

    Examples
    --------
    The zero direction of ``f2`` makes its detection space two-dimensional:

    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> caisa(m.A, m.C, m.Bf[:, 1]).shape[1], detection_space(m.A, m.C, m.Bf[:, 1]).shape[1]
    (1, 2)
    """
    A, C, F = _system(A, C, F)
    W = caisa(A, C, F, rtol)
    _, dirs = invariant_zeros(A, C, F)
    return span_sum(W, _real_span(dirs, np.shape(A)[0]), rtol=rtol) if dirs else W


def output_separable(
    C: np.ndarray, spaces: Sequence[np.ndarray], rtol: float | None = None
) -> tuple[bool, list[tuple[int, int]]]:
    """Whether the output images ``C T_i`` are independent (Def. A.1; test (a.7)).

    Returns the verdict and the pairs ``(i, j)`` whose images intersect (the faults that
    are "detection equivalent" and cannot be told apart by their residual directions).

    Parameters
    ----------
    C : array_like
        (p, n) output matrix.
    spaces : sequence of array_like
        Bases (n, νᵢ) of the subspaces ``Tᵢ`` (e.g. :func:`detection_space` of each fault).
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    separable : bool
        True when ``rank [C T₁, …, C T_q]`` is the sum of the ranks of the ``C Tᵢ``.
    pairs : list of tuple of int
        The index pairs ``(i, j)``, ``i < j``, whose output images intersect.

    Raises
    ------
    ParameterError
        If a space does not have n rows (the columns of ``C``), or a matrix is not finite.

    References
    ----------
    Douglas et al. 1996, §4.1 and App. A.3, (a.7).

    Examples
    --------
    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> T = [detection_space(m.A, m.C, m.Bf[:, [i]]) for i in range(2)]
    >>> output_separable(m.C, T)
    (True, [])
    """
    C = as_2d("C", C)
    spaces = [as_2d(f"space {i}", T) for i, T in enumerate(spaces)]
    for i, T in enumerate(spaces):
        if T.shape[0] != C.shape[1]:
            raise ParameterError(f"space {i} has {T.shape[0]} rows but C has {C.shape[1]} columns (states)")
    images = [orth(C @ T, rtol) for T in spaces]
    total = rank(np.hstack(images), rtol) if images else 0
    ok = total == sum(im.shape[1] for im in images)
    pairs = [
        (i, j)
        for i in range(len(images))
        for j in range(i + 1, len(images))
        if rank(np.hstack([images[i], images[j]]), rtol) < images[i].shape[1] + images[j].shape[1]
    ]
    return ok, pairs


def mutually_detectable(
    A: np.ndarray, C: np.ndarray, faults: Sequence[np.ndarray], rtol: float = 1e-6
) -> tuple[bool, np.ndarray, np.ndarray]:
    """Mutual detectability (Douglas et al. 1996, §4.1): zeros of the union = union of the zeros.

    Returns the verdict, the zeros of ``(C, A, [F₁ … F_q])`` and the union of the zeros of
    each ``(C, A, F_i)``.  The two multisets are matched with a tolerance relative to ‖A‖.

    Parameters
    ----------
    A : array_like
        (n, n) state matrix.
    C : array_like
        (p, n) output matrix.
    faults : sequence of array_like
        The fault maps ``Fᵢ``, each (n, kᵢ).
    rtol : float, default 1e-6
        Two zeros match when they differ by at most ``rtol · max(‖A‖₂, 1)``.

    Returns
    -------
    detectable : bool
        True when the two multisets of zeros match one to one.
    joint : numpy.ndarray
        Complex zeros of ``(C, A, [F₁ … F_q])``.
    union : numpy.ndarray
        The zeros of every ``(C, A, Fᵢ)``, concatenated.

    Raises
    ------
    ParameterError
        If ``faults`` is empty, a matrix has the wrong shape or is not finite, or ``rtol`` is negative.

    References
    ----------
    Douglas et al. 1996, §4.1 (the zero sets of each filter's faults) and App. A.3.

    Examples
    --------
    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> ok, joint, union = mutually_detectable(m.A, m.C, [m.Bf[:, [0]], m.Bf[:, [1]]])
    >>> ok, np.round(joint.real, 6).tolist()
    (True, [-3.0])
    """
    A = validate.as_square("A", A)
    C = validate.as_matrix("C", C, (None, A.shape[0]))
    faults = [validate.as_matrix(f"fault map {i}", F, (A.shape[0], None)) for i, F in enumerate(faults)]
    if not faults:
        raise ParameterError("mutually_detectable needs at least one fault map")
    rtol = validate.non_negative("rtol", rtol)
    joint, _ = invariant_zeros(A, C, np.hstack(faults))
    union = np.concatenate([invariant_zeros(A, C, F)[0] for F in faults]) if faults else np.zeros(0)
    scale = max(np.linalg.norm(A, 2), 1.0)
    left = list(union)
    extra = []
    for z in joint:
        k = int(np.argmin(np.abs(np.array(left) - z))) if left else -1
        if k >= 0 and abs(left[k] - z) <= rtol * scale:
            left.pop(k)
        else:
            extra.append(z)
    return not extra and not left, joint, union


def output_projector(C: np.ndarray, W: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthogonal projector ``I − h hᵀ`` onto the complement of ``range(C W)`` (``h`` an orthonormal basis).

    The residual projector ``Ĥ`` of Murray 2012, (2.11); ``I`` when ``W`` has no columns.

    Parameters
    ----------
    C : numpy.ndarray
        (p, n) output matrix.
    W : numpy.ndarray
        (n, k) basis of the subspace to hide from the residual (e.g. the nuisance faults' ``Ŵ*``).
    rtol : float, optional
        Relative rank tolerance: singular values above ``rtol · σ_max`` count; default
        ``1e3 · max(shape) · eps``.

    Returns
    -------
    numpy.ndarray
        (p, p) symmetric idempotent ``Ĥ`` with ``Ker Ĥ = C W``.

    References
    ----------
    Murray 2012, §2.1.2, (2.11).

    Examples
    --------
    >>> from fdikit.plants import white_speyer
    >>> m = white_speyer()
    >>> H = output_projector(m.C, caisa(m.A, m.C, m.Bf[:, 0]))
    >>> np.round(H, 6).tolist(), np.allclose(H @ m.C @ m.Bf[:, 0], 0)
    ([[0.5, 0.5], [0.5, 0.5]], True)
    """
    p = C.shape[0]
    if W.shape[1] == 0:
        return np.eye(p)
    h = orth(C @ W, rtol)
    return np.eye(p) - h @ h.T
