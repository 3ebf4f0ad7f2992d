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

from fdikit.design.nullspace.factorization import boundary_zeros, coouter_coinner, realization
from fdikit.errors import DesignError, ParameterError

__all__ = ["ZeroStep", "remove_boundary_zeros", "zero_steps_inverse"]


@dataclass(frozen=True, eq=False)
class ZeroStep:
    """One step of :func:`remove_boundary_zeros`: ``T_k(λ) = diag(t_i(λ)) P(λ) Uᵀ`` on the rows ``rows``.

    Attributes
    ----------
    rotation : numpy.ndarray
        ``U`` (orthogonal, ``p × p``).
    rows : tuple of int
        The rows changed after the rotation.
    poles : tuple of float
        The ``π`` given to the removed zeros (one per row; two for a complex pair).
    zero : complex or None
        None: a row shift per row, ``t_i = λ − π_i``.  Real ``λ₀``: ``t = (λ − π)/(λ − λ₀)``.  Complex ``λ₀`` (a
        pair ``λ₀, λ̄₀``, ``q(λ) = (λ − λ₀)(λ − λ̄₀)``): with one row ``t = (λ − π₁)(λ − π₂)/q(λ)``; with two rows
        ``P = [λuᵀ + wᵀ; zᵀ]`` (``z = w + π₂u``, ``det P ∝ λ − π₂``) and ``t = ((λ − π₁)/q(λ), 1)``.
    mix : tuple of numpy.ndarray or None
        ``(u, w)`` of the two-row case.

    Examples
    --------
    >>> st = ZeroStep(np.eye(1), (0,), (-1.0,), None)
    >>> st.rows, st.zero, st.mix
    ((0,), None, None)

    References
    ----------
    Varga (2017), §7.9.
    """

    rotation: np.ndarray
    rows: tuple[int, ...]
    poles: tuple[float, ...]
    zero: complex | None
    mix: tuple[np.ndarray, np.ndarray] | None = None


def remove_boundary_zeros(A, B, C, D, dt: float | None = None, *, poles: Sequence[float] | None = None,
                          sdeg: float | None = None, tol: float = 1e-7):
    """``G₁ = T(λ) G`` without the zeros of ``G`` at infinity and on the stability boundary, on ``G``'s ``(A, B)``.

    ``T = T_K ⋯ T_1`` (:class:`ZeroStep`).  Continuous, while ``D`` lacks full row rank, the rows of its left null
    space are multiplied by ``λ − π`` (``C_i ← C_i (A − πI)``, ``D_i ← C_i B``).  Then, for each zero ``λ₀`` on the
    boundary (the transmission zeros of ``G``, python-control's ``zeros``; real ones first):

    * real ``λ₀`` (0; discrete ``±1``): the row of the left null vector of ``G(λ₀)`` becomes
      ``(λ − π) r(λ)/(λ − λ₀)`` (``C_i ← −C_i (A − πI)(λ₀I − A)⁻¹``, ``D_i ← −C_i (λ₀I − A)⁻¹ B``);
    * a complex pair ``λ₀, λ̄₀``, ``q(λ) = (λ − λ₀)(λ − λ̄₀)``: if the null vector ``v`` is real up to a phase, its
      row becomes ``(λ − π₁)(λ − π₂) r/q`` (``C_i ← C_i (A − π₁I)(A − π₂I) q(A)⁻¹``); otherwise, with ``v``'s phase
      fixed so that ``Re v ⊥ Im v`` and the two rows rotated onto ``Re v``, ``Im v``, the null combination is
      ``γ = w + λ₀u`` and the rows become ``(λ − π₁)(λu + w)ᵀR/q`` (``C ← (c_u A + c_w)(A − π₁I) q(A)⁻¹``,
      ``D ← d_u``) and ``zᵀR`` with ``z = w + π₂u`` (so ``det T_k ∝ (λ − π₁)(λ − π₂)/q``).  The coefficients come
      from matching the strictly proper parts; the fixed phase makes the factor of ``U G`` that of ``G`` rotated.

    ``T⁻¹`` is stable and proper with poles at the ``π`` (:func:`zero_steps_inverse`); ``G₁`` is ready for
    :func:`~fdikit.design.nullspace.factorization.coouter_coinner`.

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
    factor : CoOuterFactor
        The standard co-outer–co-inner factorisation of ``G₁`` (solved to decide that no zero is left).

    Raises
    ------
    DesignError
        ``G`` without full row rank, or a boundary zero that could not be located (use the regularised factor).
    ParameterError
        Unstable or complex ``poles``.

    Examples
    --------
    ``s/(s+3)`` (a zero at 0) with π = −1 becomes ``(s+1)/(s+3)``:

    >>> C1, D1, steps, _ = remove_boundary_zeros([[-3.0]], [[1.0]], [[-3.0]], [[1.0]], sdeg=-1.0)
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
            return C, D, steps, coouter_coinner(A, B, C, D, dt, tol=tol)
        except DesignError as err:
            reason = err
        lam, W, g = _boundary_zero(A, B, C, D, dt, tol)
        if lam is None:
            raise DesignError(f"{reason}; no zero of G on the boundary was located: use nonstd='regularize'")
        C, D = W.T @ C, W.T @ D                     # the null vector now lives on the last row (or two rows)
        I = np.eye(n)
        pi1, pi2 = (pis[k] if k < len(pis) else sdeg for k in (moved, moved + 1))
        if lam.imag == 0:                           # real λ₀ (0; discrete ±1): r(λ₀) = 0 on the last row
            M = np.linalg.inv(lam.real * I - A)
            C[-1], D[-1] = -C[-1] @ (A - pi1 * I) @ M, -C[-1] @ M @ B
            steps.append(ZeroStep(W, (p - 1,), (pi1,), lam.real))
            moved += 1
            continue
        qA = A @ A - 2 * lam.real * A + abs(lam) ** 2 * I            # q(A), q(λ) = (λ − λ₀)(λ − λ̄₀)
        if g is None:                               # a real row vanishes at λ₀ and λ̄₀: (λ − π₁)(λ − π₂) r / q
            C[-1] = np.linalg.solve(qA.T, (C[-1] @ (A - pi1 * I) @ (A - pi2 * I)).T).T
            steps.append(ZeroStep(W, (p - 1,), (pi1, pi2), lam))
        else:                                       # γᵀ[r1; r2](λ₀) = 0 with γ = w + λ₀u: rows (λ−π₁)(λu+w)ᵀR/q, zᵀR
            u = g.imag / lam.imag
            w = g.real - lam.real * u
            z = w + pi2 * u
            cu, cw, du = u @ C[-2:], w @ C[-2:], u @ D[-2:]
            cz, dz = z @ C[-2:], z @ D[-2:]
            C[-2] = np.linalg.solve(qA.T, (cu @ A @ (A - pi1 * I) + cw @ (A - pi1 * I)).T).T
            D[-2], C[-1], D[-1] = du, cz, dz
            steps.append(ZeroStep(W, (p - 2, p - 1), (pi1, pi2), lam, (u, w)))
        moved += 2
    raise DesignError("the zeros on the boundary could not be removed: G has no full row rank")


def _completed(X: np.ndarray) -> np.ndarray:
    """An orthogonal ``p × p`` matrix whose last columns are the orthonormal columns of ``X``."""
    Qf = np.linalg.qr(X, mode="complete")[0]
    return np.hstack([Qf[:, X.shape[1]:], X])


def _boundary_zero(A, B, C, D, dt, tol):
    """A zero ``λ₀`` of ``G`` on the boundary (real ones first; complex with ``Im λ₀ > 0``), the rotation ``W`` that
    puts its left null vector on the last row (or, complex and not real up to a phase, on the last two rows), and
    the null vector's coefficients ``γ`` on those two rows (None otherwise); ``(None, None, None)`` if none."""
    n = A.shape[0]
    zs = boundary_zeros(A, B, C, D, dt, tol=tol)
    upper = zs[zs.imag > tol * np.maximum(1.0, np.abs(zs))]
    cands = [complex(x) for x in ([0.0] if dt is None else [1.0, -1.0])]
    cands += [complex(1j * x.imag) if dt is None else complex(x / abs(x)) for x in upper]
    for lam in cands:
        if lam.imag == 0:
            G = C @ np.linalg.solve(lam.real * np.eye(n) - A, B) + D
            W, s0, _ = np.linalg.svd(G)
            if s0[-1] <= tol * max(1.0, s0[0]):
                return lam, W, None
            continue
        U, s0, _ = np.linalg.svd(C @ np.linalg.solve(lam * np.eye(n) - A, B) + D)
        if s0[-1] > tol * max(1.0, s0[0]):
            continue
        v = np.conj(U[:, -1])                       # v G(λ₀) = 0, up to a complex scalar
        # the phase that makes Re v ⊥ Im v with ‖Re v‖ ≥ ‖Im v‖: a choice that does not depend on the phase LAPACK
        # returned, so that the factor of U G is U times the factor of G (output rotations)
        phi = 0.5 * np.arctan2(-2 * (v.real @ v.imag), v.real @ v.real - v.imag @ v.imag)
        v = v * np.exp(1j * phi)
        a, b = np.linalg.norm(v.real), np.linalg.norm(v.imag)
        if C.shape[0] == 1 or b <= tol * a:
            return lam, _completed((v.real / a)[:, None]), None
        Q2 = np.vstack([v.real / a, v.imag / b])
        return lam, _completed(Q2.T), np.array([a, 1j * b])
    return None, None, None


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
        A, Bs, Cs, Ds = _step_inverse(st)
        B, C, D = np.zeros((A.shape[0], p)), np.zeros((p, A.shape[0])), np.eye(p)
        B[:, list(st.rows)] = Bs
        C[list(st.rows)] = Cs
        D[np.ix_(st.rows, st.rows)] = Ds
        out = series(out, (A, B, st.rotation @ C, st.rotation @ D))
    return out


def _quadratic_ratio(lam: complex, pi1: float, pi2: float) -> tuple[np.ndarray, ...]:
    """``q(λ)/((λ − π₁)(λ − π₂))``, ``q = (λ − λ₀)(λ − λ̄₀)``, in controllable canonical form."""
    a1, a0 = -(pi1 + pi2), pi1 * pi2
    q1, q0 = -2 * lam.real, abs(lam) ** 2
    return (np.array([[0.0, 1.0], [-a0, -a1]]), np.array([[0.0], [1.0]]), np.array([[q0 - a0, q1 - a1]]),
            np.ones((1, 1)))


def _step_inverse(st: ZeroStep) -> tuple[np.ndarray, ...]:
    """``diag(1/t_i) P⁻¹`` of one step on its rows (``P = I`` except in the two-row complex case)."""
    if st.zero is None or complex(st.zero).imag == 0:
        k = len(st.rows)
        lam0 = None if st.zero is None else float(np.real(st.zero))
        C = np.diag([1.0 if lam0 is None else pi - lam0 for pi in st.poles])      # 1/(λ−π) or 1 + (π−λ₀)/(λ−π)
        return np.diag(np.asarray(st.poles, float)), np.eye(k), C, np.eye(k) * (0.0 if lam0 is None else 1.0)
    lam, (pi1, pi2) = complex(st.zero), st.poles
    A1, B1, C1, D1 = _quadratic_ratio(lam, pi1, pi2)
    if st.mix is None:
        return A1, B1, C1, D1
    u, w = st.mix
    z = w + pi2 * u
    k = u[0] * w[1] - u[1] * w[0]                  # det P = k (λ − π₂)
    # P⁻¹ diag(q/(λ−π₁), 1): column 1 = [z₂; −z₁] q/(k(λ−π₁)(λ−π₂)), column 2 = [−(u₂λ+w₂); u₁λ+w₁]/(k(λ−π₂))
    A = np.block([[A1, np.zeros((2, 1))], [np.zeros((1, 2)), np.array([[pi2]])]])
    B = np.block([[B1, np.zeros((2, 1))], [np.zeros((1, 1)), np.ones((1, 1))]])
    zc = np.array([[z[1]], [-z[0]]]) / k
    C = np.hstack([zc @ C1, np.array([[-(w[1] + u[1] * pi2)], [w[0] + u[0] * pi2]]) / k])
    D = np.hstack([zc * D1[0, 0], np.array([[-u[1]], [u[0]]]) / k])
    return A, B, C, D
