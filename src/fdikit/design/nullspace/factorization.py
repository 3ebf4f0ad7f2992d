"""Co-outer–co-inner factorisation of a stable proper system, and its quasi / regularised forms (Varga 2017, §7.9).

A stable ``G(λ) = C (λI − A)⁻¹ B + D`` (``p × m``, full row rank ``p``) factors as ``G = G_o G_i`` with ``G_i``
co-inner (``G_i G_i~ = I``, ``G_i~(s) = G_i(−s)ᵀ``, discrete ``G_i(1/z)ᵀ``) and ``G_o`` square, stable and
minimum phase (its zeros are the stable zeros of ``G`` and the mirror images of the unstable ones).  Procedure AFD
(Varga 2017, §5.3) uses ``G_o`` of the noise part ``R_w`` of the nullspace filter: ``Q ← G_o⁻¹ Q`` makes the noise
channel co-inner, which maximises the fault-to-noise gap.

What is covered
---------------
* **Standard case** (:func:`coouter_coinner`): continuous with ``D Dᵀ > 0`` and no zeros on the imaginary axis,
  discrete with ``D Dᵀ > 0`` and no zeros on the unit circle.  Riccati method — the dual of the inner–outer
  factorisation of ``Gᵀ`` (Zhou, Doyle and Glover 1996, Thm. 13.34 / 21.19): the stabilising solution ``X`` of the
  filter ARE ``A X + X Aᵀ − (X Cᵀ + B Dᵀ) (D Dᵀ)⁻¹ (C X + D Bᵀ) + B Bᵀ = 0`` (SciPy's ``solve_continuous_are``, or
  ``solve_discrete_are`` with ``R = D Dᵀ + C X Cᵀ``) gives ``G_o = (A, (B Dᵀ + X Cᵀ) R^{-1/2}, C, R^{1/2})``;
  solved on the part of the state controllable from the noise (``X`` is zero on the rest, the stable zeros of ``G``).
* **Non-standard case, one row** (:func:`quasi_coouter_row`): a row ``G`` (``p = 1``), continuous, with zeros at
  infinity (``D = 0``) or on the imaginary axis.  The quasi-co-outer factor has those zeros; the reference inverts it
  and then stabilises ``G_o⁻¹ Q`` by a left coprime factorisation with poles at ``sdeg`` (``nonstd = 1``).  For one
  row this is the same as inverting the *shifted* factor whose boundary and infinite zeros are moved to the
  assigned poles, which is what is returned (``n_o(λ)`` from the spectral factor of ``G G~`` by polynomial roots:
  meant for the small orders of a residual row); ``smarg`` moves the slow stable zeros as well.  The Wiener–Hopf
  factors of one row (reference ``nonstd = 3, 4, 5``) are in :mod:`~fdikit.design.nullspace.row_factors`.
* **Regularised case** (:func:`regularized_coouter`): the co-outer factor of ``[G  εI]`` (Varga 2017, Remark 5.8;
  reference ``nonstd = 2``), always standard.

* **Non-standard case, several rows or discrete** (:func:`quasi_coouter`): zeros at infinity and on the
  boundary, removed by row operations on the realisation (row shifts of the infinite zeros, divisions by
  ``λ − λ₀`` or by ``(λ − λ₀)(λ − λ̄₀)``, :mod:`~fdikit.design.nullspace.zero_steps`) and moved to the poles;
  the Wiener–Hopf factors of several rows are in :mod:`~fdikit.design.nullspace.wiener_hopf`.  Discrete ``D Dᵀ``
  singular is the standard case (``R + C X Cᵀ > 0``).


References
----------
Varga (2017), §5.3 (Procedure AFD), Remark 5.8, §7.9 (inner–outer factorisations); fdtools (``goifac``);
Zhou, Doyle and Glover (1996), §13.7.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from fdikit.errors import DesignError, ParameterError

__all__ = ["CoOuterFactor", "coouter_coinner", "regularized_coouter", "quasi_coouter_row", "quasi_coouter",
           "boundary_zeros", "series", "inverse", "realization", "transfer",
           "canonical_factor"]


@dataclass(frozen=True, eq=False)
class CoOuterFactor:
    """A co-outer–co-inner factorisation ``G = G_o G_i`` of a stable system.

    Attributes
    ----------
    outer : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``G_o`` (square ``p × p``, stable; minimum phase, with ``D`` invertible in the standard
        and the regularised cases; for :func:`quasi_coouter_row` the shifted factor).
    inner : tuple of numpy.ndarray or None
        ``(A, B, C, D)`` of ``G_i`` (``p × m``, ``G_i G_i~ = I``) in the standard case; None otherwise.
    dt : float or None
        Sample time.
    kind : str
        ``"standard"``, ``"quasi"`` (boundary/infinite zeros shifted) or ``"regularized"``.
    shifted : int
        Number of zeros on the boundary or at infinity moved to the assigned poles (``"quasi"`` only).

    Examples
    --------
    >>> f = coouter_coinner([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 1.0]])
    >>> f.kind, np.round(f.outer[3], 6).tolist()
    ('standard', [[1.0]])

    References
    ----------
    Varga (2017), §7.9; fdtools (``goifac``).
    """

    outer: tuple[np.ndarray, ...]
    inner: tuple[np.ndarray, ...] | None
    dt: float | None
    kind: str
    shifted: int = 0


def realization(A, B, C, D) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D)`` as float arrays of consistent shapes (an empty ``A`` gives a static gain).

    Parameters
    ----------
    A, B, C, D : array_like
        The matrices.

    Returns
    -------
    tuple of numpy.ndarray

    Examples
    --------
    >>> [M.shape for M in realization([], np.zeros((0, 2)), np.zeros((1, 0)), [[1.0, 2.0]])]
    [(0, 0), (0, 2), (1, 0), (1, 2)]

    References
    ----------
    Varga (2017), §7.3.
    """
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    n = A.shape[0] if A.size else 0
    p, m = D.shape
    return A.reshape(n, n), B.reshape(n, m), C.reshape(p, n), D


def transfer(sys, lam: complex) -> np.ndarray:
    """``G(λ) = D + C (λI − A)⁻¹ B`` of a realisation ``(A, B, C, D)`` at one complex point.

    Parameters
    ----------
    sys : tuple of numpy.ndarray
        ``(A, B, C, D)``, shaped as :func:`realization` returns them.
    lam : complex
        The point (not a pole).

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> transfer((np.array([[-1.0]]), np.array([[1.0]]), np.array([[2.0]]), np.array([[0.0]])), 1.0).tolist()
    [[1.0]]

    References
    ----------
    Varga (2017), §7.3.
    """
    A, B, C, D = sys
    return D + (C @ np.linalg.solve(lam * np.eye(A.shape[0]) - A, B) if A.shape[0] else 0)


def _sqrtm_sym(R: np.ndarray, inverse_: bool = False) -> np.ndarray:
    w, V = np.linalg.eigh((R + R.T) / 2)
    s = np.sqrt(w) if not inverse_ else 1.0 / np.sqrt(w)
    return (V * s) @ V.T


def canonical_factor(A, B, C, D) -> tuple[np.ndarray, ...]:
    """``F U_rᵀ`` with ``U_r`` the orthogonal polar factor of ``D = P U_r``: the same ``F F~``, ``D`` symmetric
    positive definite.

    A factor to invert is defined up to a constant orthogonal factor on the right; the rotations of the row
    operations that build it (SVD bases whose signs and, for repeated singular values, directions rounding decides)
    leave it there.  This choice removes them, so the filter does not depend on the BLAS kernel.

    Parameters
    ----------
    A, B, C, D : array_like
        A realisation of a square ``F`` with ``D`` invertible.

    Returns
    -------
    tuple of numpy.ndarray

    Examples
    --------
    >>> A, B, C, D = canonical_factor([[-1.0]], [[1.0]], [[1.0]], [[-2.0]])
    >>> B.tolist(), D.tolist()
    ([[-1.0]], [[2.0]])

    References
    ----------
    Varga (2017), §7.9 (co-outer factors are unique up to a constant orthogonal factor).
    """
    A, B, C, D = realization(A, B, C, D)
    U, _, Vt = np.linalg.svd(D)
    Ur = U @ Vt
    return A, B @ Ur.T, C, D @ Ur.T


def series(first, second):
    """``second · first``: the realisation of the series connection (``first``'s output feeds ``second``).

    Parameters
    ----------
    first, second : tuple of numpy.ndarray
        ``(A, B, C, D)`` each.

    Returns
    -------
    tuple of numpy.ndarray
        States of ``first`` followed by those of ``second``.

    Examples
    --------
    >>> A, B, C, D = series(([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), ([], np.zeros((0, 1)), np.zeros((1, 0)), [[2.0]]))
    >>> C.tolist()
    [[2.0]]

    References
    ----------
    Varga (2017), §7.3 (operations on state-space realisations).
    """
    A1, B1, C1, D1 = realization(*first)
    A2, B2, C2, D2 = realization(*second)
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    B = np.vstack([B1, B2 @ D1])
    C = np.hstack([D2 @ C1, C2])
    return A, B, C, D2 @ D1


def inverse(A, B, C, D):
    """The inverse ``G⁻¹`` of a square system with invertible ``D``: ``(A − B D⁻¹ C, B D⁻¹, −D⁻¹ C, D⁻¹)``.

    Parameters
    ----------
    A, B, C, D : array_like
        The realisation.

    Returns
    -------
    tuple of numpy.ndarray

    Raises
    ------
    DesignError
        When ``D`` is singular (relative to its norm).

    Examples
    --------
    >>> [M.tolist() for M in inverse([[-2.0]], [[1.0]], [[1.0]], [[1.0]])]
    [[[-3.0]], [[1.0]], [[-1.0]], [[1.0]]]

    References
    ----------
    Varga (2017), §7.3 (inverse systems).
    """
    A, B, C, D = realization(A, B, C, D)
    if D.shape[0] != D.shape[1]:
        raise DesignError(f"only a square system is inverted here, got {D.shape}")
    s = np.linalg.svd(D, compute_uv=False)
    if not s.size or s[-1] <= 1e-12 * max(s[0], 1.0):
        raise DesignError(f"D is singular (singular values {np.round(s, 12).tolist()}): G has zeros at infinity")
    Di = np.linalg.inv(D)
    return A - B @ Di @ C, B @ Di, -Di @ C, Di


def boundary_zeros(A, B, C, D, dt: float | None = None, *, tol: float = 1e-7) -> np.ndarray:
    """Zeros of a full-row-rank ``G`` on the stability boundary (imaginary axis or unit circle).

    They are those of ``G G~`` there, where the filter Riccati equation of :func:`coouter_coinner` loses its
    stabilising solution; taken from the invariant zeros (SLICOT ``AB08ND``), not from the Hamiltonian, whose
    defective pairs ``±z`` of a multiple zero rounding moved onto the axis under some BLAS kernels (PATH's three
    actuator faults: four zeros at ``−0.05``, on the axis at ``±0.0655 j``).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation with ``D Dᵀ > 0``.
    dt : float or None
        Sample time.
    tol : float, default 1e-7
        Relative distance to the boundary counted as on it (to ``max(1, |z|)``).

    Returns
    -------
    numpy.ndarray
        The boundary zeros found (complex), each once.

    Examples
    --------
    ``s / (s + 2)`` has a zero at 0:

    >>> z = boundary_zeros([[-2.0]], [[1.0]], [[-2.0]], [[1.0]])
    >>> len(z), bool(np.all(np.abs(z) < 1e-9))
    (1, True)

    References
    ----------
    Varga (2017), §7.9 (the standard case of the factorisation); Zhou, Doyle and Glover (1996), §13.7.
    """
    import control

    A, B, C, D = realization(A, B, C, D)
    if not A.shape[0]:
        return np.zeros(0, complex)
    zs = np.asarray(control.ss(A, B, C, D, 0 if dt is None else dt).zeros(), complex)
    zs = zs[np.isfinite(zs)]
    near = np.abs(zs.real) if dt is None else np.abs(np.abs(zs) - 1.0)
    return zs[near <= tol * np.maximum(1.0, np.abs(zs))]


def coouter_coinner(A, B, C, D, dt: float | None = None, *, tol: float = 1e-7) -> CoOuterFactor:
    """Co-outer–co-inner factorisation ``G = G_o G_i`` of a stable system in the standard case (Riccati method).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation of ``G`` (``p × m``), with ``D Dᵀ > 0``.
    dt : float or None
        Sample time (None: continuous).
    tol : float, default 1e-7
        Relative tolerance of the full-rank and boundary-zero tests.

    Returns
    -------
    CoOuterFactor
        ``outer = (A, B_o, C, D_o)`` (square, ``D_o = (D Dᵀ [+ C X Cᵀ])^{1/2}``) and ``inner`` with
        ``G_i G_i~ = I``.

    Raises
    ------
    DesignError
        The non-standard case: ``D Dᵀ`` singular (zeros at infinity) or zeros on the stability boundary (the message
        names them); the Riccati solver failing.

    Examples
    --------
    ``G = [1/(s+1)  1]``: ``G G~ = (ω² + 2)/(ω² + 1)``, so ``G_o = (s + √2)/(s + 1)``:

    >>> f = coouter_coinner([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 1.0]])
    >>> Ao, Bo, Co, Do = f.outer
    >>> round(float(Ao[0, 0] - Bo[0, 0] * Co[0, 0] / Do[0, 0]), 6)   # the zero of G_o
    -1.414214

    References
    ----------
    Varga (2017), §7.9; fdtools (``goifac``); Zhou, Doyle and Glover (1996), Thm. 13.34 (dual form).
    """
    A, B, C, D = realization(A, B, C, D)
    n, p, m = A.shape[0], D.shape[0], D.shape[1]
    sv = np.linalg.svd(D, compute_uv=False)
    full = p <= m and sv.size and sv[-1] > tol * max(sv[0], 1e-300)
    if not full and (dt is None or n == 0 or p > m):
        raise DesignError(f"D (singular values {np.round(sv, 9).tolist()}) does not have full row rank {p}: G has "
                          "zeros at infinity (non-standard case); use the quasi factorisation or the regularised "
                          "factorisation")
    R = D @ D.T
    if n == 0:
        Do = _sqrtm_sym(R)
        return CoOuterFactor((A, np.zeros((0, p)), C, Do), (A, B, C, _sqrtm_sym(R, True) @ D), dt, "standard")
    # discrete with D Dᵀ singular: R + C X Cᵀ > 0 still; the unit-circle test is then on the factor's zeros below
    bz = boundary_zeros(A, B, C, D, dt, tol=tol) if full else np.zeros(0, complex)
    if bz.size:
        raise DesignError(f"G has zeros on the stability boundary {np.round(bz, 6).tolist()} (non-standard case); "
                          "use the quasi factorisation or the regularised factorisation")
    S = B @ D.T
    try:
        X = _filter_riccati(A, B, C, D, dt, tol) if full else sla.solve_discrete_are(A.T, C.T, B @ B.T, R, s=S)
    except (np.linalg.LinAlgError, ValueError) as err:
        raise DesignError(f"the filter Riccati equation of the co-outer factor has no stabilising solution: {err}"
                          ) from err
    Rt = R if dt is None else R + C @ X @ C.T
    if not full:
        w = np.linalg.eigvalsh((Rt + Rt.T) / 2)
        zo = np.linalg.eigvals(A - (A @ X @ C.T + S) @ np.linalg.solve(Rt, C)) if w[0] > tol * max(w[-1], 1.0) \
            else np.ones(1)
        if np.max(np.abs(zo)) >= 1 - tol:
            raise DesignError("G has zeros on the unit circle (non-standard case); use the quasi factorisation or "
                              "the regularised factorisation")
    Rh, Rhi = _sqrtm_sym(Rt), _sqrtm_sym(Rt, True)
    if dt is None:
        K = (X @ C.T + S) @ np.linalg.inv(Rt)
    else:
        K = (A @ X @ C.T + S) @ np.linalg.inv(Rt)
    outer = (A, K @ Rh, C, Rh)
    # inner = G_o⁻¹ G realised on the observer states: (A − K C, B − K D, −Rh⁻¹ C, Rh⁻¹ D)
    inner = (A - K @ C, B - K @ D, Rhi @ C, Rhi @ D)
    return CoOuterFactor(outer, inner, dt, "standard")


def _filter_riccati(A, B, C, D, dt, tol):
    """The stabilising ``X`` of the filter ARE with ``D Dᵀ > 0``, solved on the part controllable from the noise.

    With ``F = A − B D⁺ C``, ``B̃ = B (I − D⁺ D)``: ``F X + X Fᵀ − X Cᵀ R⁻¹ C X + B̃ B̃ᵀ = 0`` (discrete alike), and
    in the controllability staircase of ``(F, B̃)`` (absolute threshold ``tol·max(1, ‖[A B]‖)``) ``X = diag(X₁, 0)``
    when the uncontrollable part, the zeros of ``G``, is stable.  A square ``G`` with ``D`` invertible has ``X = 0``;
    solved on the whole, the Hamiltonian's defective pairs of a multiple zero made SciPy refuse it under some BLAS
    kernels (PATH's three actuator faults).
    """
    from fdikit.descriptor.staircase import controllability_staircase

    n = A.shape[0]
    R = D @ D.T
    Dp = D.T @ np.linalg.inv(R)
    F = A - B @ Dp @ C
    Z, nc = controllability_staircase(F, B - B @ Dp @ D, tol * max(1.0, np.linalg.norm(np.hstack([A, B]), 2)))
    ev = np.linalg.eigvals((Z.T @ F @ Z)[nc:, nc:])
    if ev.size and (np.max(ev.real) >= 0 if dt is None else np.max(np.abs(ev)) >= 1):
        Z, nc = np.eye(n), n                        # an unstable zero: X is not zero on it, solve on the whole
    X = np.zeros((n, n))
    if nc:
        Zc = Z[:, :nc]
        A1, B1, C1 = Zc.T @ A @ Zc, Zc.T @ B, C @ Zc
        solve = sla.solve_continuous_are if dt is None else sla.solve_discrete_are
        X = Zc @ solve(A1.T, C1.T, B1 @ B1.T, R, s=B1 @ D.T) @ Zc.T
    return (X + X.T) / 2


def regularized_coouter(A, B, C, D, dt: float | None = None, *, epsreg: float = 0.1) -> CoOuterFactor:
    """The co-outer factor of ``[G  εI]`` (Varga 2017, Remark 5.8; reference ``nonstd = 2``): always standard.

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation of ``G``.
    dt : float or None
        Sample time.
    epsreg : float, default 0.1
        ``ε > 0``.

    Returns
    -------
    CoOuterFactor
        ``kind = "regularized"``; ``outer`` of ``[G εI]`` (its ``inner`` is dropped).

    Raises
    ------
    ParameterError
        ``epsreg ≤ 0``.

    Examples
    --------
    ``[1/(s+2)  0.3]``: the zero of the factor is at ``−√(1 + 4·0.09)/0.3``:

    >>> Ao, Bo, Co, Do = regularized_coouter([[-2.0]], [[1.0]], [[1.0]], [[0.0]], epsreg=0.3).outer
    >>> round(float(Ao[0, 0] - Bo[0, 0] * Co[0, 0] / Do[0, 0]), 6)
    -3.887301

    References
    ----------
    Varga (2017), Remark 5.8; Glover and Varga (2011).
    """
    from fdikit import validate

    eps = validate.positive("epsreg", epsreg)
    A, B, C, D = realization(A, B, C, D)
    p = D.shape[0]
    f = coouter_coinner(A, np.hstack([B, np.zeros((A.shape[0], p))]), C, np.hstack([D, eps * np.eye(p)]), dt)
    return CoOuterFactor(f.outer, None, dt, "regularized")


def quasi_coouter_row(A, B, C, D, *, poles: Sequence[complex] | None = None, sdeg: float = -0.05,
                      smarg: float | None = None, tol: float = 1e-7) -> CoOuterFactor:
    """The shifted quasi-co-outer factor ``g_o = k n_s(s) φ(s) / d(s)`` of one stable continuous row ``g``.

    ``g g~ = n_o(s) n_o(−s) / (d(s) d(−s))`` with ``n_o`` the spectral factor (roots in the closed left half
    plane).  ``n_s`` keeps the strictly stable roots of ``n_o``; its roots on the imaginary axis and the
    ``deg d − deg n_o`` zeros at infinity are replaced by ``φ`` (the roots ``poles`` or all at ``sdeg``), so that
    ``g_o`` is biproper, stable and minimum phase and ``g_o⁻¹ Q`` is the reference's ``nonstd = 1`` result
    (quasi-co-outer inverse, then left coprime stabilisation with those poles).  In the standard case
    (no shifted zero) ``g_o`` is the co-outer factor.

    Parameters
    ----------
    A, B, C, D : array_like
        A stable **minimal** realisation of the row (``C`` one row).
    poles : sequence of complex, optional
        Roots of ``φ`` (first ``deg φ`` of them).
    sdeg : float, default -0.05
        Root of ``φ`` when ``poles`` is None.
    smarg : float, optional
        Stability margin: the zeros with real part at least ``smarg`` are moved too (reference ``smarg`` of the
        ``glcf`` stabilisation; default ``−√ε``, only the boundary and infinite zeros).
    tol : float, default 1e-7
        Relative distance of a root to the imaginary axis counted as on it.

    Returns
    -------
    CoOuterFactor
        ``kind = "quasi"``, ``shifted = deg φ``.

    Raises
    ------
    ParameterError
        More than one row, or unstable ``poles``.
    DesignError
        ``g = 0``.

    Examples
    --------
    ``1/(s+2)`` has a zero at infinity; with ``sdeg = −3`` the factor is ``(s + 3)/(s + 2)``:

    >>> f = quasi_coouter_row([[-2.0]], [[1.0]], [[1.0]], [[0.0]], sdeg=-3.0)
    >>> Ao, Bo, Co, Do = f.outer
    >>> f.shifted, round(float(Do[0, 0]), 6), round(float(Ao[0, 0] - Bo[0, 0] * Co[0, 0] / Do[0, 0]), 6)
    (1, 1.0, -3.0)

    References
    ----------
    Varga (2017), §5.3 (the quasi-co-outer factor), §7.9; Glover and Varga (2011); fdtools (``afdredsyn``,
    ``nonstd = 1``).
    """
    from fdikit.design.nullspace.basis import denominator
    from fdikit.design.nullspace.row_factors import realize_biproper, row_spectrum

    A, B, C, D = realization(A, B, C, D)
    if C.shape[0] != 1:
        raise ParameterError(f"quasi_coouter_row factors one row, got {C.shape[0]} rows")
    spec = row_spectrum(A, B, C, D, tol=tol)
    margin = -np.sqrt(np.finfo(float).eps) if smarg is None else float(smarg)
    stable = spec.stable[spec.stable.real < margin]
    n_shift = A.shape[0] - stable.size
    phi = denominator(n_shift, poles, sdeg, None)
    num_o = spec.gain * np.real(np.convolve(np.poly(stable), phi)) if stable.size else spec.gain * phi
    return CoOuterFactor(realize_biproper(num_o, spec.den), None, None, "quasi", n_shift)


def quasi_coouter(A, B, C, D, dt: float | None = None, *, poles: Sequence[complex] | None = None,
                  sdeg: float | None = None, tol: float = 1e-7) -> CoOuterFactor:
    """The shifted quasi-co-outer factor of a stable ``G`` with zeros at infinity or on the stability boundary.

    ``G`` (``p × m``, full row rank) is reduced, on its own ``(A, B)``, to ``G₁ = T(λ) G`` without those zeros
    (:func:`~fdikit.design.nullspace.zero_steps.remove_boundary_zeros`: row shifts for the zeros at infinity, and
    divisions of the rows of the left null vectors by ``λ − λ₀``, or by ``(λ − λ₀)(λ − λ̄₀)`` for a complex pair,
    with the moved zeros placed at ``π``).  ``T⁻¹`` is stable and proper, so
    ``T⁻¹ G₁ₒ`` is the quasi-co-outer factor of ``G``; the returned ``F = W G₁ₒ`` (``G₁ₒ`` the standard co-outer
    factor of ``G₁``, ``W`` the product of the orthogonal row rotations of the steps, so that ``F`` of ``U G`` is
    ``U F`` up to a constant orthogonal factor on the right, removed by :func:`canonical_factor`: ``D`` symmetric
    positive definite) is biproper, stable and minimum phase with the moved zeros at the poles ``π``: ``F⁻¹ Q`` is
    stable and proper, and ``F⁻¹ G`` keeps the zeros of ``G`` on the boundary and at infinity.
    For one continuous row this is :func:`quasi_coouter_row` (which also takes ``smarg``); the reference instead
    inverts the quasi factor and stabilises with ``glcf`` — another member of the same family of left coprime
    factors.  (Discrete zeros at infinity, ``D`` singular, are standard: ``R + C X Cᵀ > 0``.)

    Parameters
    ----------
    A, B, C, D : array_like
        A stable realisation of ``G``.
    dt : float or None
        Sample time.
    poles : sequence of float, optional
        The poles ``π`` of the moved zeros, in order (real, stable); default all at ``sdeg``.
    sdeg : float, optional
        ``π`` when ``poles`` is None (default −0.05, discrete 0.95).
    tol : float, default 1e-7
        Relative tolerance of the rank and boundary decisions.

    Returns
    -------
    CoOuterFactor
        ``kind = "quasi"``, ``shifted`` = number of zeros moved.

    Raises
    ------
    DesignError
        ``G`` without full row rank.
    ParameterError
        Unstable or complex ``poles``.

    Examples
    --------
    ``diag(1/(s+2), s/(s+3))``: one zero at infinity, one at 0; ``F = diag((s+1)/(s+2), (s+1)/(s+3))`` with π = −1:

    >>> f = quasi_coouter(np.diag([-2.0, -3.0]), np.eye(2), np.diag([1.0, -3.0]), np.diag([0.0, 1.0]), sdeg=-1.0)
    >>> Ao, Bo, Co, Do = f.outer
    >>> f.shifted, np.round(np.sort(np.linalg.eigvals(Ao - Bo @ np.linalg.solve(Do, Co)).real), 6).tolist()
    (2, [-1.0, -1.0])

    References
    ----------
    Varga (2017), §5.3 (the quasi-co-outer factor, ``nonstd = 1``), §7.9.
    """
    from fdikit.design.nullspace.zero_steps import remove_boundary_zeros

    A, B, C, D = realization(A, B, C, D)
    _, _, steps, g1 = remove_boundary_zeros(A, B, C, D, dt, poles=poles, sdeg=sdeg, tol=tol)
    W = np.eye(D.shape[0])
    for st in steps:
        W = W @ st.rotation
    Ao, Bo, Co, Do = g1.outer
    return CoOuterFactor(canonical_factor(Ao, Bo, W @ Co, W @ Do), None, dt, "quasi",
                         sum(len(st.poles) for st in steps))

