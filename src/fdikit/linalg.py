"""Subspaces, fault maps and the geometry of detection filters.

Orthonormal bases and SVD rank decisions throughout; every tolerance scales with the
data (``max(shape) · eps · σ_max`` by default, or a caller's relative tolerance).

* fault maps: sensor faults as the two-dimensional ``F = [F¹, A F¹]`` with
  ``C F¹ = e_i`` (Douglas et al. 1996, eqs. (3.3)–(3.5); App. A.2), actuator faults as
  columns of ``B`` (§3.2);
* the minimal (C, A)-invariant subspace containing ``F`` by CAISA (App. A, Theorem A.1,
  with ``W⁰ = 0``: the report prints ∅, an OCR slip);
* invariant zeros of ``(C, A, F)`` and their state directions from the Rosenbrock pencil;
* the minimal unobservability subspace ``T* = W* ⊕ V`` (§4.1, App. A.3), output
  separability (a.7) and mutual detectability (§4.1).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.errors import DesignError, ModelError
from fdikit.model import FaultModel

__all__ = [
    "rank",
    "orth",
    "null",
    "intersect",
    "span_sum",
    "contains",
    "sensor_fault_map",
    "actuator_fault_map",
    "caisa",
    "invariant_zeros",
    "detection_space",
    "output_separable",
    "mutually_detectable",
]

_EPS = np.finfo(float).eps


def _tol(M: np.ndarray, s: np.ndarray, rtol: float | None) -> float:
    smax = s[0] if s.size else 0.0
    return (rtol if rtol is not None else max(M.shape) * _EPS * 1e3) * max(smax, 0.0)


def rank(M: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank: singular values above ``rtol · σ_max`` (default ``1e3 · max(shape) · eps``)."""
    M = np.atleast_2d(M)
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0


def orth(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the range of ``M`` (n x r)."""
    M = np.atleast_2d(np.asarray(M))
    if M.size == 0:
        return np.zeros((M.shape[0], 0), dtype=M.dtype)
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    r = int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0
    return U[:, :r]


def null(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the null space of ``M`` (columns)."""
    M = np.atleast_2d(np.asarray(M))
    if M.shape[0] == 0:
        return np.eye(M.shape[1], dtype=M.dtype)
    _, s, Vh = np.linalg.svd(M, full_matrices=True)
    r = int((s > _tol(M, s, rtol)).sum()) if s.size and s[0] > 0 else 0
    return Vh[r:].conj().T


def span_sum(*bases: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U₁ + Im U₂ + …``."""
    bases = [np.atleast_2d(b) for b in bases if np.size(b)]
    if not bases:
        raise ModelError("span_sum needs at least one non-empty basis")
    return orth(np.hstack(bases), rtol)


def intersect(U: np.ndarray, V: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U ∩ Im V``."""
    U, V = orth(U, rtol), orth(V, rtol)
    if U.shape[1] == 0 or V.shape[1] == 0:
        return np.zeros((U.shape[0], 0))
    N = null(np.hstack([U, -V]), rtol)
    return orth(U @ N[: U.shape[1]], rtol)


def contains(U: np.ndarray, x: np.ndarray, rtol: float = 1e-8) -> bool:
    """Whether every column of ``x`` lies in ``Im U`` (relative residual below ``rtol``)."""
    Q = orth(U)
    x = np.atleast_2d(x.T).T
    res = x - Q @ (Q.conj().T @ x)
    return bool(np.linalg.norm(res) <= rtol * max(np.linalg.norm(x), _EPS))


# ---------------------------------------------------------------------- fault maps
def sensor_fault_map(model: FaultModel, output: str, direction: str = "both", rtol: float = 1e-9) -> np.ndarray:
    """State-space fault map of an additive fault on the sensor of ``output``.

    ``y = C x + e_i μ`` is written as a state fault through ``F¹`` with ``C F¹ = e_i``:
    ``ē = e − F¹ μ`` gives ``ē' = (A + LC) ē + F¹ μ' − A F¹ μ`` (Douglas et al. 1996,
    eq. (3.4); App. A.2).  ``direction``: ``'both'`` → ``[F¹, A F¹]`` (n x 2), ``'magnitude'``
    → ``A F¹`` (the bias direction), ``'rate'`` → ``F¹``.  ``F¹`` is the minimum-norm
    solution; it must solve ``C F¹ = e_i`` exactly (to ``rtol``), otherwise the output is
    not reachable from the states and :class:`DesignError` is raised.
    """
    i = model.index("outputs", output)[0]
    e = np.zeros(model.p)
    e[i] = 1.0
    F1, *_ = np.linalg.lstsq(model.C, e, rcond=None)
    if np.linalg.norm(model.C @ F1 - e) > rtol:
        raise DesignError(
            f"output {output!r} is not in the range of C (residual {np.linalg.norm(model.C @ F1 - e):.2e}): "
            "its sensor fault cannot be written as a state fault F¹ with C F¹ = e_i; use a model whose C has "
            "full row rank for these outputs"
        )
    F1 = F1.reshape(-1, 1)
    F2 = model.A @ F1
    maps = {"both": np.hstack([F1, F2]), "magnitude": F2, "rate": F1}
    if direction not in maps:
        raise ModelError(f"direction must be 'both', 'magnitude' or 'rate', got {direction!r}")
    return maps[direction]


def actuator_fault_map(model: FaultModel, control: str) -> np.ndarray:
    """Fault map of an actuator: the control's column of ``B`` (Douglas et al. 1996, §3.2), n x 1.

    On a model whose actuator lags are states (e.g. the 14-state PATH model) this is the
    command-side fault; a nonzero ``D`` column means the fault also reaches the outputs
    directly, which the geometric filters here do not model (:class:`DesignError`).
    """
    j = model.index("u", control)[0]
    if np.any(model.Du[:, j] != 0):
        raise DesignError(
            f"control {control!r} has a direct feedthrough D[:, {j}] != 0; an actuator fault on it reaches the "
            "outputs directly. Use a model with the actuator dynamics as states (e.g. path_vehicle_14)"
        )
    return model.Bu[:, [j]]


# ---------------------------------------------------------------------- geometry
def caisa(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal (C, A)-invariant subspace containing ``Im F`` (CAISA, Douglas et al. 1996, Thm. A.1).

    ``W⁰ = 0``, ``W^{k+1} = Im F + A (W^k ∩ Ker C)``; the sequence is nondecreasing and
    stops within ``n`` steps.  Returns an orthonormal basis.
    """
    A, C, F = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, C, F))
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
    A: np.ndarray, C: np.ndarray, F: np.ndarray
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Invariant zeros of ``(C, A, F)`` and their state directions.

    The zeros are the finite generalised eigenvalues of the Rosenbrock pencil
    ``[[A − sI, F], [C, 0]]``, computed by slycot's ``ab08nd`` (via python-control) for
    the non-square case.  For each zero ``z`` the direction is the state part ``x`` of
    the null space of ``[[A − zI, F], [C, 0]]`` (complex for a complex zero).
    """
    import control

    A, C, F = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, C, F))
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    sys = control.ss(A, F, C, np.zeros((p, k)))
    zeros = np.asarray(sys.zeros(), dtype=complex)
    dirs = []
    for z in zeros:
        P = np.block([[A - z * np.eye(n), F], [C, np.zeros((p, k))]])
        x = np.linalg.svd(P)[2][-1].conj()[:n]  # right singular vector of the smallest singular value
        dirs.append(x / max(np.linalg.norm(x), _EPS))
    return zeros, dirs


def _real_span(vectors: Sequence[np.ndarray], n: int) -> np.ndarray:
    if not vectors:
        return np.zeros((n, 0))
    V = np.column_stack(vectors)
    return np.hstack([V.real, V.imag])


def detection_space(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal unobservability subspace containing ``Im F``: ``T* = W* ⊕ V`` (Douglas et al. 1996, §4.1).

    ``W*`` from :func:`caisa`, ``V`` the span of the invariant-zero directions of
    ``(C, A, F)``.  Orthonormal basis (n x ν).
    """
    W = caisa(A, C, F, rtol)
    _, dirs = invariant_zeros(A, C, F)
    return span_sum(W, _real_span(dirs, np.shape(A)[0]), rtol=rtol) if dirs else W


def output_separable(
    C: np.ndarray, spaces: Sequence[np.ndarray], rtol: float | None = None
) -> tuple[bool, list[tuple[int, int]]]:
    """Whether the output images ``C T_i`` are independent (Def. A.1; test (a.7)).

    Returns the verdict and the pairs ``(i, j)`` whose images intersect (the faults that
    are "detection equivalent" and cannot be told apart by their residual directions).
    """
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
    """
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
