"""Factors of the noise part of one residual row in the non-standard case: spectral data and Wiener–Hopf factors.

A stable continuous row ``g(s)`` (``1 × m``, realisation of order ``n``, denominator ``d``) has the spectral
density ``g g~ = k² n_o(s) n_o(−s) / (d(s) d(−s))`` with ``n_o`` monic, roots in the closed left half plane.  The
quasi-co-outer factor is ``g_o = k n_o / d``: it has the zeros of ``n_o`` on the imaginary axis (``n_b``) and
``n − deg n_o`` zeros at infinity; ``n_s`` collects the strictly stable roots (``n_o = n_s n_b``).  Procedure AFD
(Varga 2017, §5.3) replaces the noise factor by an invertible stable factor ``F`` and sets ``Q ← F⁻¹ Q``; the
reference offers five choices (``nonstd``).  For one row they reduce to polynomial operations on ``n_s``, ``n_b``,
``d``, which is why this module works with polynomials (meant for the small orders of a residual row; the
reference uses descriptor pencil reductions, ``goifac`` and ``gcrange``, which no Python library provides):

* ``nonstd = 1`` (:func:`~fdikit.design.nullspace.factorization.quasi_coouter_row`): the boundary and infinite
  zeros (and those with real part at least ``smarg``) moved to the assigned poles.
* ``nonstd = 3`` (Wiener–Hopf): ``g_o = X R`` with ``R = n_b / r`` holding the boundary and infinite zeros and
  ``X = k n_s r / d`` biproper; ``F = X``.  ``r`` (degree ``deg n_b + n − deg n_o``) is taken from the roots of
  ``d`` — the slowest first, conjugate pairs kept together — so that ``F⁻¹`` adds no dynamics the row does not
  have (the reference's ``gcrange`` keeps the poles of ``g_o`` in ``X``; its test shows the poles of ``Q`` equal
  to those of the model).
* ``nonstd = 4``: ``F = X R(φ(s))`` with the bilinear map ``φ(s) = (s − δ)`` for boundary zeros and
  ``1/(1 − δ s)`` for infinite ones (their product when both occur), which moves a zero at ``jω₀`` to
  ``φ⁻¹(jω₀)`` (``δ`` for ``ω₀ = 0``) and a zero at infinity to ``1/δ``; ``δ = sdegzer``.
* ``nonstd = 5``: ``F = X R_ε`` with ``R_ε`` the co-outer factor of ``[R  εI]``.

References
----------
Varga (2017), §5.3 (Procedure AFD, non-standard case), Remark 5.8, §7.9; fdtools (``afdsyn``, ``nonstd``;
``gcrange``, ``gbilin``, ``goifac``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ParameterError

__all__ = ["RowSpectrum", "row_spectrum", "realize_biproper", "wiener_hopf_row", "WIENER_HOPF_JOBS"]

WIENER_HOPF_JOBS = ("plain", "shift", "regularize")


@dataclass(frozen=True, eq=False)
class RowSpectrum:
    """The spectral data ``g g~ = k² n_o(s) n_o(−s) / (d(s) d(−s))`` of one stable continuous row.

    Attributes
    ----------
    gain : float
        ``k``.
    den : numpy.ndarray
        ``d`` (monic, degree ``n``), highest power first.
    stable : numpy.ndarray
        The strictly stable roots of ``n_o``.
    boundary : numpy.ndarray
        The roots of ``n_o`` on the imaginary axis (each once; purely imaginary).
    infinite : int
        The number of zeros at infinity, ``n − deg n_o``.

    Examples
    --------
    >>> r = row_spectrum([[-2.0]], [[-2.0]], [[1.0]], [[1.0]])     # s/(s+2)
    >>> r.infinite, r.stable.size, np.abs(r.boundary).round(6).tolist()
    (0, 0, [0.0])

    References
    ----------
    Varga (2017), §7.9 (spectral factorisation).
    """

    gain: float
    den: np.ndarray
    stable: np.ndarray
    boundary: np.ndarray
    infinite: int


def row_spectrum(A, B, C, D, *, tol: float = 1e-7) -> RowSpectrum:
    """The spectral factor data of a stable continuous row ``g = C (sI − A)⁻¹ B + D`` (``C`` one row).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable **minimal** realisation (``C`` and ``D`` one row).
    tol : float, default 1e-7
        Relative distance of a root to the imaginary axis counted as on it.

    Returns
    -------
    RowSpectrum

    Raises
    ------
    ParameterError
        More than one row.
    DesignError
        ``g = 0``.

    Examples
    --------
    ``1/(s+2)``: one zero at infinity.

    >>> row_spectrum([[-2.0]], [[1.0]], [[1.0]], [[0.0]]).infinite
    1

    References
    ----------
    Varga (2017), §7.9.
    """
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    n = A.shape[0] if A.size else 0
    if C.shape[0] != 1 or D.shape[0] != 1:
        raise ParameterError(f"a row is factored here, got {D.shape[0]} rows; the non-standard case of several "
                             "residuals is not implemented: use nonstd='regularize' or rdim=1")
    A, B, C = A.reshape(n, n), B.reshape(n, D.shape[1]), C.reshape(1, n)
    d = np.poly(A) if n else np.ones(1)
    # numerators n_i = d(s) (c (sI−A)⁻¹ b_i + d_i) = det(sI − A + b_i c) − d(s) + d_i d(s)
    nums = [np.poly(A - B[:, [i]] @ C) - d + D[0, i] * d if n else D[0, i] * d for i in range(B.shape[1])]
    P = np.zeros(2 * n + 1)
    for num in nums:
        P[-(2 * len(num) - 1):] += np.convolve(num, _mirror(num))
    scale = max(np.max(np.abs(P)), 1e-300)
    nz = np.flatnonzero(np.abs(P) > 1e-12 * scale)
    if not nz.size:
        raise DesignError("the row is zero: no co-outer factor")
    P = P[nz[0]:]
    roots = np.roots(P) if P.size > 1 else np.zeros(0, complex)
    mag = max(1.0, np.max(np.abs(roots), initial=0.0))
    on_axis = np.abs(roots.real) <= tol * mag
    # the axis roots of n_o(s) n_o(−s) are double: sorted along the axis, each pair gives one root of n_o
    axis = np.sort_complex(1j * roots[on_axis].imag)
    boundary = 1j * (axis[0::2].imag + axis[1::2].imag) / 2 if axis.size % 2 == 0 else 1j * axis.imag
    return RowSpectrum(float(np.sqrt(abs(P[0]))), d, roots[(roots.real < 0) & ~on_axis], boundary,
                       n - (P.size - 1) // 2)


def realize_biproper(num, den) -> tuple[np.ndarray, ...]:
    """Controller-form realisation ``(A, B, C, D)`` of ``num(s)/den(s)`` with ``deg num ≤ deg den``.

    Parameters
    ----------
    num, den : array_like
        Real coefficients, highest power first.

    Returns
    -------
    tuple of numpy.ndarray

    Raises
    ------
    ParameterError
        ``deg num > deg den`` or ``den`` with a zero leading coefficient.

    Examples
    --------
    >>> A, B, C, D = realize_biproper([1.0, 3.0], [1.0, 2.0])     # (s+3)/(s+2)
    >>> A.tolist(), C.tolist(), D.tolist()
    ([[-2.0]], [[1.0]], [[1.0]])

    References
    ----------
    Varga (2017), §7.3 (realisations).
    """
    num, den = np.real(np.atleast_1d(np.asarray(num, complex))), np.atleast_1d(np.asarray(den, float))
    n = den.size - 1
    if num.size - 1 > n or den[0] == 0:
        raise ParameterError(f"num/den is improper or den has a zero leading coefficient ({num}, {den})")
    num = np.concatenate([np.zeros(n + 1 - num.size), num]) / den[0]
    den = den / den[0]
    D = np.array([[num[0]]])
    if n == 0:
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), D
    A = np.zeros((n, n))
    A[0, :] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    return A, B, (num - num[0] * den)[1:].reshape(1, n), D


def _poly(roots) -> np.ndarray:
    return np.real(np.poly(roots)) if len(roots) else np.ones(1)


def _slowest(roots: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """``count`` roots of ``d`` for ``r`` (slowest first, conjugate pairs together), the other roots, and whether
    all ``count`` are roots of ``d``."""
    order = sorted(range(roots.size), key=lambda i: (-roots[i].real, abs(roots[i].imag), roots[i].imag))
    chosen: list[int] = []
    for i in order:
        if len(chosen) == count:
            break
        if i in chosen:
            continue
        if abs(roots[i].imag) > 1e-12 * max(1.0, abs(roots[i])):
            mate = min((j for j in order if j != i and j not in chosen),
                       key=lambda j: abs(roots[j] - np.conj(roots[i])))
            if len(chosen) + 2 <= count:
                chosen += [i, mate]
            continue
        chosen.append(i)
    if len(chosen) < count:      # only conjugate pairs left for one place: a real root at the pair's real part
        extra = [next(roots[j].real for j in order if j not in chosen)]
        return np.concatenate([roots[chosen], extra]), roots, False
    return roots[chosen], np.delete(roots, chosen), True


def _mirror(p: np.ndarray) -> np.ndarray:
    """``p(−s)``."""
    return p * (-1.0) ** (p.size - 1 - np.arange(p.size))


def _compose(p: np.ndarray, num_g: np.ndarray, den_g: np.ndarray) -> np.ndarray:
    """``p(φ(s)) · den_g(s)^{deg p}`` for ``φ = num_g/den_g`` (homogenised composition)."""
    k = p.size - 1
    out = np.zeros(1)
    for j, c in enumerate(p):          # c s^{k−j} → c num_g^{k−j} den_g^{j}
        term = c * np.ones(1)
        for _ in range(k - j):
            term = np.convolve(term, num_g)
        for _ in range(j):
            term = np.convolve(term, den_g)
        out = np.polyadd(out, term)
    return out


def wiener_hopf_row(A, B, C, D, *, job: str = "plain", sdegzer: float = -0.05, epsreg: float = 0.1,
                    tol: float = 1e-7) -> tuple[tuple[np.ndarray, ...], int]:
    """The Wiener–Hopf factor ``F`` of one stable continuous row (reference ``nonstd = 3, 4, 5``).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable **minimal** realisation of the noise row ``g``.
    job : {"plain", "shift", "regularize"}, default "plain"
        ``F = X`` (``nonstd = 3``), ``F = X R(φ(s))`` (``nonstd = 4``) or ``F = X R_ε`` (``nonstd = 5``); see the
        module docstring.
    sdegzer : float, default -0.05
        ``δ < 0`` of the zero shift (``"shift"``).
    epsreg : float, default 0.1
        ``ε > 0`` (``"regularize"``).
    tol : float, default 1e-7
        Relative distance of a root to the imaginary axis counted as on it.

    Returns
    -------
    F : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``F``: biproper, stable and minimum phase.
    moved : int
        The number of boundary and infinite zeros of ``g_o`` handled (0: the standard case, ``F = g_o``).

    Raises
    ------
    ParameterError
        Bad ``job``, ``sdegzer ≥ 0``, ``epsreg ≤ 0``, or more than one row.
    DesignError
        ``g = 0``.

    Examples
    --------
    ``s/(s+2)`` (a zero at 0): ``F`` is constant for ``"plain"``; ``"shift"`` with ``δ = −0.1`` gives
    ``F ∝ (s + 0.1)/(s + 2.1)``:

    >>> (Af, Bf, Cf, Df), moved = wiener_hopf_row([[-2.0]], [[-2.0]], [[1.0]], [[1.0]], job="shift", sdegzer=-0.1)
    >>> moved, np.round(np.linalg.eigvals(Af - Bf @ Cf / Df[0, 0]).real, 6).tolist()
    (1, [-0.1])

    References
    ----------
    Varga (2017), §5.3; fdtools (``afdsyn``, ``nonstd = 3, 4, 5``).
    """
    from fdikit import validate

    job = validate.choice("job", job, WIENER_HOPF_JOBS)
    spec = row_spectrum(A, B, C, D, tol=tol)
    n_b, k_inf = _poly(spec.boundary), spec.infinite
    moved = spec.boundary.size + k_inf
    r_roots, rest, among = _slowest(np.roots(spec.den) if spec.den.size > 1 else np.zeros(0, complex), moved)
    r = _poly(r_roots)
    # X = k n_s r / d; with r taken from d's roots, X = k n_s / (d / r)
    num = spec.gain * _poly(spec.stable)
    num, den = (num, _poly(rest)) if among else (np.convolve(num, r), spec.den)
    if job == "shift" and moved:
        delta = float(sdegzer)
        if not delta < 0:
            raise ParameterError(f"sdegzer={delta} must be negative (the shifted zeros are at δ and 1/δ)")
        num_g = np.array([1.0, -delta]) if spec.boundary.size else np.ones(1)     # φ = (s − δ) ...
        den_g = np.array([-delta, 1.0]) if k_inf else np.ones(1)                  # ... / (1 − δ s)
        # R(φ(s)) = n_b(φ) / r(φ) = n_b~ den_g^{k∞} / r~, with p~ = p(φ) den_g^{deg p}
        num = np.convolve(num, _compose(n_b, num_g, den_g))
        for _ in range(k_inf):
            num = np.convolve(num, den_g)
        den = np.convolve(den, _compose(r, num_g, den_g))
    elif job == "regularize" and moved:
        eps = validate.positive("epsreg", epsreg)
        # R R~ + ε² = P / (r r(−s)), P = n_b n_b(−s) + ε² r r(−s) = c m(s) m(−s), m monic with stable roots
        P = np.polyadd(np.convolve(n_b, _mirror(n_b)), eps ** 2 * np.convolve(r, _mirror(r)))
        roots = np.roots(P)
        num = np.convolve(num, np.sqrt(abs(P[0])) * _poly(roots[roots.real < 0]))
        den = np.convolve(den, r)
    return realize_biproper(num, den), moved
