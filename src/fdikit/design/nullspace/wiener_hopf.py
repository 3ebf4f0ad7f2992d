"""Wiener–Hopf factors of the noise channel of several residuals, continuous or discrete (reference
``nonstd = 3, 4, 5``).

The quasi-co-outer factor ``R_wo`` of ``R_w = R_wo R_wi`` keeps the zeros of ``R_w`` at infinity and on the
boundary.  The reference splits it as ``R_wo = R_woe R_wouz`` (``gcrange`` with ``zeros = "s-unstable"``), the
unstable zeros in the right factor ``R_wouz``, and inverts only the left one (``nonstd = 3``), the left one and
``R_wouz(φ(λ))`` (``nonstd = 4``, zeros shifted by the Möbius map ``φ``), or the left one and the co-outer factor
of ``[R_wouz εI]`` (``nonstd = 5``).  Here, in two passes of the row operations of
:func:`~fdikit.design.nullspace.zero_steps.remove_boundary_zeros`:

1. ``T R_w = G₁`` has no such zeros and ``G₁ = G₁ₒ G₁ᵢ`` is standard, so ``R_wo = T⁻¹ G₁ₒ`` (minimal).
2. The same on the transpose, ``T̂ R_woᵀ = Ĝ₁``, gives ``R_wo = Ĝ₁ᵀ T̂⁻ᵀ``: ``R_woe = Ĝ₁ᵀ`` (biproper, stable,
   zeros the stable zeros of ``R_wo`` and the poles ``π`` of the steps) and ``R_wouz = T̂⁻ᵀ`` (the boundary and
   infinite zeros, poles ``π``).  The ``π`` of this pass default to the slowest real poles of ``R_wo``, so that,
   as in the one-row form of :mod:`~fdikit.design.nullspace.row_factors`, ``R_woe⁻¹`` adds no dynamics; for one
   row with real slowest poles the two agree (tested).

The returned ``F`` is the factor to invert, ``Q ← F⁻¹ Q``: ``R_woe``, ``R_woe R_wouz(φ)`` or ``R_woe R_ε``.

References
----------
Varga (2017), §5.3 (Procedure AFD, non-standard case), §7.9; fdtools (``afdredsyn``, ``nonstd = 3, 4, 5``;
``gcrange``, ``gbilin``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.design.nullspace.factorization import (
    CoOuterFactor,
    canonical_factor,
    realization,
    regularized_coouter,
    series,
)
from fdikit.errors import ParameterError

__all__ = ["moebius", "wiener_hopf", "WIENER_HOPF_JOBS_SEVERAL"]

WIENER_HOPF_JOBS_SEVERAL = ("plain", "shift", "regularize")


def moebius(A, B, C, D, a: float, b: float, c: float, d: float) -> tuple[np.ndarray, ...]:
    """``G(φ(λ))`` for ``φ(λ) = (aλ + b)/(cλ + d)``, on the state space of ``G`` (reference ``gbilin``).

    ``φ I − A = M (λI − Ā)/(cλ + d)`` with ``M = aI − cA`` and ``Ā = M⁻¹(dA − bI)``, so
    ``G(φ) = (Ā, M⁻¹B, C (cĀ + dI), D + c C M⁻¹ B)``.

    Parameters
    ----------
    A, B, C, D : array_like
        The realisation of ``G``.
    a, b, c, d : float
        The map (``ad − bc ≠ 0``).

    Returns
    -------
    tuple of numpy.ndarray

    Raises
    ------
    ParameterError
        A degenerate map, or ``aI − cA`` singular (``a/c`` a pole of ``G``: ``G(φ)`` is improper).

    Examples
    --------
    ``1/(s + 2)`` at ``φ = s − 0.5`` is ``1/(s + 1.5)``:

    >>> Ab, Bb, Cb, Db = moebius([[-2.0]], [[1.0]], [[1.0]], [[0.0]], 1.0, -0.5, 0.0, 1.0)
    >>> float(Ab[0, 0]), float(Bb[0, 0] * Cb[0, 0]), float(Db[0, 0])
    (-1.5, 1.0, 0.0)

    References
    ----------
    Varga (2017), §7.3; fdtools (``gbilin``).
    """
    A, B, C, D = realization(A, B, C, D)
    if abs(a * d - b * c) <= 1e-14 * max(abs(a * d), abs(b * c), 1e-300):
        raise ParameterError(f"φ = ({a}λ + {b})/({c}λ + {d}) is degenerate (ad − bc = 0)")
    n = A.shape[0]
    M = a * np.eye(n) - c * A
    if n and np.linalg.cond(M) > 1e12:
        raise ParameterError(f"aI − cA is singular: λ = {a / c:g} is a pole of G, so G(φ) is not proper")
    Abar = np.linalg.solve(M, d * A - b * np.eye(n)) if n else A
    MB = np.linalg.solve(M, B) if n else B
    return Abar, MB, C @ (c * Abar + d * np.eye(n)), D + c * (C @ MB)


def _minimal(sys):
    from fdikit.design.nullspace.basis import minimal_realization

    return minimal_realization(*sys)


def _transpose(sys):
    A, B, C, D = sys
    return A.T, C.T, B.T, D.T


def _slow_real_poles(A: np.ndarray, dt) -> list[float]:
    ev = np.linalg.eigvals(A) if A.size else np.zeros(0)
    real = ev[np.abs(ev.imag) <= 1e-9 * np.maximum(1.0, np.abs(ev))].real
    return sorted(real, key=lambda x: -x if dt is None else -abs(x))


def wiener_hopf(A, B, C, D, dt: float | None = None, *, job: str = "plain", poles: Sequence[float] | None = None,
                sdeg: float | None = None, sdegzer: float | None = None, epsreg: float = 0.1,
                tol: float = 1e-7) -> CoOuterFactor:
    """The Wiener–Hopf factor ``F`` of the noise channel ``R_w`` of several residuals (``Q ← F⁻¹ Q``).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation of ``R_w`` (full row rank), with zeros at infinity or on the stability boundary.
    dt : float or None
        Sample time.
    job : {"plain", "shift", "regularize"}, default "plain"
        ``F = R_woe`` (``nonstd = 3``), ``R_woe R_wouz(φ)`` (4) or ``R_woe R_ε`` (5); see the module docstring.
    poles : sequence of float, optional
        The poles ``π`` of ``R_wouz`` (real, stable), in order; default the slowest real poles of ``R_wo``, then
        ``sdeg``.
    sdeg : float, optional
        Default −0.05 (discrete 0.95).
    sdegzer : float, optional
        ``δ`` of ``φ`` (``"shift"``), as the reference builds it: continuous ``φ = (s − δ)/(1 − δs)`` (only
        ``s − δ`` without infinite zeros, only ``1/(1 − δs)`` without finite ones), ``δ < 0``, default −0.05;
        discrete ``φ = z/δ``, ``0 < δ < 1``, default 0.95.
    epsreg : float, default 0.1
        ``ε > 0`` (``"regularize"``).
    tol : float, default 1e-7
        Relative tolerance of the rank and boundary decisions.

    Returns
    -------
    CoOuterFactor
        ``kind = "wiener-hopf"``, ``outer = F`` (biproper, stable, minimum phase), ``shifted`` = the number of
        zeros of ``R_wouz``.

    Raises
    ------
    ParameterError
        Bad ``job``, ``sdegzer`` or ``epsreg``.
    DesignError
        ``R_w`` without full row rank.

    Examples
    --------
    ``R_w = diag(1/(s+2), s/(s+3))`` is its own quasi-co-outer factor; with ``π`` its poles −2, −3 the factor
    ``R_woe`` is constant (``±I``), so ``F⁻¹`` adds no dynamics and ``R_wouz = R_w`` keeps both zeros:

    >>> f = wiener_hopf(np.diag([-2.0, -3.0]), np.eye(2), np.diag([1.0, -3.0]), np.diag([0.0, 1.0]))
    >>> Af, Bf, Cf, Df = f.outer
    >>> F = Cf @ np.linalg.solve(1j * np.eye(len(Af)) - Af, Bf) + Df
    >>> f.shifted, np.round(np.abs(F), 9).tolist()
    (2, [[1.0, 0.0], [0.0, 1.0]])

    References
    ----------
    Varga (2017), §5.3, §7.9; fdtools (``afdredsyn``, ``nonstd = 3, 4, 5``).
    """
    from fdikit import validate
    from fdikit.design.nullspace.zero_steps import remove_boundary_zeros, zero_steps_inverse

    job = validate.choice("job", job, WIENER_HOPF_JOBS_SEVERAL)
    A, B, C, D = realization(A, B, C, D)
    p = D.shape[0]
    # pass 1: R_w = T⁻¹ G₁, G₁ = G₁ₒ G₁ᵢ, so R_wo = T⁻¹ G₁ₒ (T's poles cancel the zeros it gave G₁ₒ)
    _, _, steps1, g1 = remove_boundary_zeros(A, B, C, D, dt, poles=None, sdeg=sdeg, tol=tol)
    rwo = _minimal(series(g1.outer, zero_steps_inverse(steps1, p, dt)))
    # pass 2 on R_woᵀ: T̂ R_woᵀ = Ĝ₁, so R_wo = Ĝ₁ᵀ T̂⁻ᵀ = R_woe R_wouz
    pis = list(poles) if poles is not None else _slow_real_poles(rwo[0], dt)
    At, Bt, Ct, Dt = _transpose(rwo)
    C2, D2, steps2, _ = remove_boundary_zeros(At, Bt, Ct, Dt, dt, poles=pis, sdeg=sdeg, tol=tol)
    rwoe = _transpose((At, Bt, C2, D2))
    moved = sum(len(st.poles) for st in steps2)
    if job == "plain" or not moved:
        return CoOuterFactor(canonical_factor(*rwoe), None, dt, "wiener-hopf", moved)
    rwouz = _transpose(zero_steps_inverse(steps2, p, dt))
    if job == "regularize":
        right = regularized_coouter(*rwouz, dt, epsreg=epsreg).outer
    else:
        right = moebius(*rwouz, *_shift_map(steps2, dt, sdegzer))
    return CoOuterFactor(canonical_factor(*_minimal(series(right, rwoe))), None, dt, "wiener-hopf", moved)


def _shift_map(steps, dt, sdegzer) -> tuple[float, float, float, float]:
    """``(a, b, c, d)`` of the reference's ``φ``: ``(s − δ)/(1 − δs)`` (parts as needed), discrete ``z/δ``."""
    if dt is not None:
        delta = 0.95 if sdegzer is None else float(sdegzer)
        if not 0 < delta < 1:
            raise ParameterError(f"sdegzer must be in (0, 1) for a discrete model, got {sdegzer}")
        return 1.0 / delta, 0.0, 0.0, 1.0
    delta = -0.05 if sdegzer is None else float(sdegzer)
    if not delta < 0:
        raise ParameterError(f"sdegzer must be negative, got {sdegzer}")
    finite = any(st.zero is not None for st in steps)
    infinite = any(st.zero is None for st in steps)
    a, b = (1.0, -delta) if finite else (0.0, 1.0)
    return a, b, -delta if infinite else 0.0, 1.0
