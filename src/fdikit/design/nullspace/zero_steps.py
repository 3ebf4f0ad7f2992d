"""Removal of the zeros at infinity and on the stability boundary of ``G`` by row operations, ``G₁ = T(λ) G``.

The quasi-co-outer factor of several residuals (:func:`~fdikit.design.nullspace.factorization.quasi_coouter`) and
the Wiener–Hopf factors (:mod:`~fdikit.design.nullspace.wiener_hopf`) both start from ``G₁``, which has none of
those zeros, and from the steps ``T_k`` that produced it: the factor holding the removed zeros is ``T⁻¹``
(:func:`zero_steps_inverse`).  Why by hand: the reference does this with descriptor-system factorisations
(``goifac``, ``gcrange``) that no Python library has; the row operations here keep the state space of ``G`` and
need only rank decisions on ``D`` and on ``G(λ₀)``.

References
----------
Varga (2017), §5.3 (quasi-co-outer factor), §7.9 (inner–outer and range factorisations); fdtools (``goifac``,
``gcrange``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.design.nullspace.factorization import coouter_coinner, realization
from fdikit.errors import DesignError, ParameterError

__all__ = ["ZeroStep", "remove_boundary_zeros", "zero_steps_inverse"]


@dataclass(frozen=True, eq=False)
class ZeroStep:
    """One step of :func:`remove_boundary_zeros`: ``T_k(λ) = diag(t_i(λ)) Uᵀ``.

    Attributes
    ----------
    rotation : numpy.ndarray
        ``U`` (orthogonal, ``p × p``).
    rows : tuple of int
        The rows ``i`` multiplied after the rotation.
    poles : tuple of float
        ``π_i`` of each row.
    zero : float or None
        ``λ₀`` of a division (``t_i = (λ − π_i)/(λ − λ₀)``), None for a row shift (``t_i = λ − π_i``).

    Examples
    --------
    >>> st = ZeroStep(np.eye(1), (0,), (-1.0,), None)
    >>> st.rows, st.zero
    ((0,), None)

    References
    ----------
    Varga (2017), §7.9.
    """

    rotation: np.ndarray
    rows: tuple[int, ...]
    poles: tuple[float, ...]
    zero: float | None


def remove_boundary_zeros(A, B, C, D, dt: float | None = None, *, poles: Sequence[float] | None = None,
                          sdeg: float | None = None, tol: float = 1e-7):
    """``G₁ = T(λ) G`` without the zeros of ``G`` at infinity and at ``s = 0`` (``z = ±1``), on ``G``'s ``(A, B)``.

    ``T = T_K ⋯ T_1`` with ``T_k = diag(t_i) U_kᵀ`` (:class:`ZeroStep`): continuous, while ``D`` lacks full row
    rank, the rows of its left null space are multiplied by ``λ − π`` (``C_i ← C_i (A − πI)``, ``D_i ← C_i B``);
    then, for each zero ``λ₀`` (0; discrete ``±1``) the row of a left null vector of ``G(λ₀)`` becomes
    ``(λ − π) r(λ)/(λ − λ₀)`` (``C_i ← −C_i (A − πI)(λ₀I − A)⁻¹``, ``D_i ← −C_i (λ₀I − A)⁻¹ B``).  ``T⁻¹`` is
    stable and proper (:func:`zero_steps_inverse`); ``G₁`` is ready for :func:`coouter_coinner`.

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation of ``G`` (full row rank).
    dt : float or None
        Sample time.
    poles : sequence of float, optional
        The ``π`` of the moved zeros, in order (real, stable); after them ``sdeg``.
    sdeg : float, optional
        Default −0.05 (discrete 0.95).
    tol : float, default 1e-7
        Relative tolerance of the rank and boundary decisions.

    Returns
    -------
    C1, D1 : numpy.ndarray
        ``G₁ = (A, B, C1, D1)``.
    steps : list of ZeroStep

    Raises
    ------
    DesignError
        ``G`` without full row rank, or boundary zeros elsewhere (a complex pair): use the regularised factor.
    ParameterError
        Unstable or complex ``poles``.

    Examples
    --------
    ``s/(s+3)`` (a zero at 0) with π = −1 becomes ``(s+1)/(s+3)``:

    >>> C1, D1, steps = remove_boundary_zeros([[-3.0]], [[1.0]], [[-3.0]], [[1.0]], sdeg=-1.0)
    >>> np.round(C1 * D1, 6).tolist(), steps[0].zero
    ([[-2.0]], 0.0)

    References
    ----------
    Varga (2017), §5.3 (the quasi-co-outer factor), §7.9.
    """
    from fdikit.design.nullspace.basis import default_sdeg

    A, B, C, D = realization(A, B, C, D)
    n, p = A.shape[0], D.shape[0]
    C, D = C.copy(), D.copy()
    sdeg = default_sdeg(dt) if sdeg is None else float(sdeg)
    pis = [complex(x) for x in np.ravel(poles)] if poles is not None else []
    stable = (lambda x: x.real < 0) if dt is None else (lambda x: abs(x) < 1)
    if any(abs(x.imag) > 0 or not stable(x) for x in pis) or not stable(complex(sdeg)):
        raise ParameterError(f"the poles of the moved zeros must be real and stable, got {pis or sdeg}")
    pis = [x.real for x in pis]
    steps: list[ZeroStep] = []
    moved = 0
    scale = max(1.0, np.linalg.norm(np.block([[A, B], [C, D]]), 2))
    for _ in range(n + p + 1):
        if dt is None:
            U, sv, _ = np.linalg.svd(D)
            r = int(np.sum(sv > tol * scale))
            if r < p:
                C, D = U.T @ C, U.T @ D
                D[r:] = 0.0
                used = []
                for i in range(r, p):
                    pi = pis[moved] if moved < len(pis) else sdeg
                    C[i], D[i] = C[i] @ (A - pi * np.eye(n)), C[i] @ B
                    used.append(pi)
                    moved += 1
                steps.append(ZeroStep(U, tuple(range(r, p)), tuple(used), None))
                continue
        try:
            coouter_coinner(A, B, C, D, dt, tol=tol)
            return C, D, steps
        except DesignError as err:
            reason = err
        for lam in ([0.0] if dt is None else [1.0, -1.0]):
            M = np.linalg.inv(lam * np.eye(n) - A)
            W, s0, _ = np.linalg.svd(C @ M @ B + D)
            if s0[-1] <= tol * max(1.0, s0[0]):     # G(λ₀) loses rank: a zero there
                break
        else:
            raise DesignError(f"{reason}; the quasi factorisation moves zeros at infinity and at "
                              f"{'0' if dt is None else '±1'} only: use nonstd='regularize'")
        pi = pis[moved] if moved < len(pis) else sdeg
        C, D = W.T @ C, W.T @ D                     # the last row is the left null vector's: r(λ₀) = 0
        C[-1], D[-1] = -C[-1] @ (A - pi * np.eye(n)) @ M, -C[-1] @ M @ B
        steps.append(ZeroStep(W, (p - 1,), (pi,), lam))
        moved += 1
    raise DesignError("the zeros on the boundary could not be removed: G has no full row rank")


def zero_steps_inverse(steps: Sequence[ZeroStep], p: int, dt: float | None = None) -> tuple[np.ndarray, ...]:
    """A realisation of ``T⁻¹ = T_1⁻¹ ⋯ T_K⁻¹`` (``T_k⁻¹ = U_k diag(1/t_i)``): stable, proper, poles at the ``π``.

    Parameters
    ----------
    steps : sequence of ZeroStep
        From :func:`remove_boundary_zeros`.
    p : int
        The number of rows of ``G``.
    dt : float or None
        Sample time (the realisation is the same in ``λ``).

    Returns
    -------
    tuple of numpy.ndarray
        ``(A, B, C, D)``, ``p × p``, of order the number of moved zeros.

    Examples
    --------
    One row shift with π = −1: ``T⁻¹ = 1/(λ + 1)``.

    >>> A, B, C, D = zero_steps_inverse([ZeroStep(np.eye(1), (0,), (-1.0,), None)], 1)
    >>> A.tolist(), B.tolist(), C.tolist(), D.tolist()
    ([[-1.0]], [[1.0]], [[1.0]], [[0.0]])

    References
    ----------
    Varga (2017), §7.3 (series connections), §7.9.
    """
    from fdikit.design.nullspace.factorization import series

    out = (np.zeros((0, 0)), np.zeros((0, p)), np.zeros((p, 0)), np.eye(p))
    for st in reversed(steps):                      # T_K⁻¹ acts first
        k = len(st.rows)
        A = np.diag(np.asarray(st.poles, dtype=float))
        B = np.zeros((k, p))
        C = np.zeros((p, k))
        D = np.eye(p)
        for j, (i, pi) in enumerate(zip(st.rows, st.poles)):
            B[j, i] = 1.0
            C[i, j] = 1.0 if st.zero is None else pi - st.zero     # 1/(λ−π) or 1 + (π−λ₀)/(λ−π)
            D[i, i] = 0.0 if st.zero is None else 1.0
        out = series(out, (A, B, st.rotation @ C, st.rotation @ D))
    return out
