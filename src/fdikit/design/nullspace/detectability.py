"""Weak and strong fault detectability of the rows of a nullspace basis (Varga 2017, §3.5 and §5.2).

Fault ``f_j`` is *weakly* detectable by row ``N_i`` when ``N_i(λ) [0; G_fj(λ)] ≢ 0``; this is decided at two
generic points, relative to ``‖N_i(λ)‖ ‖G_fj(λ)‖`` (threshold ``fdtol``, the reference's ``FDtol``).  It is
*strongly* detectable at the frequencies ``Ω`` when the filter row ``N_i(λ) / φ_i(λ)`` times ``G_fj`` has gain
above ``fdgaintol`` (``FDGainTol``) at every ``λ ∈ Ω`` (``jω`` or ``e^{jω dt}``).  At a frequency that is a pole of
the plant the response is taken just off the pole, so a pole the filter cancels gives its finite limit and one it
does not cancel an unbounded (detected) gain.

References
----------
Varga (2017), §3.5 (weak and strong detectability), §5.2; fdtools (``fditspec``, ``fdisspec``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = ["fault_response", "row_structure", "frequency_points", "covered"]

_GENERIC = (0.613 + 0.791j, -0.377 + 1.93j)


def frequency_points(freqs: Sequence[float] | float | None, dt: float | None) -> np.ndarray:
    """The points ``λ = jω`` (continuous) or ``e^{jω dt}`` (discrete) of real frequencies ``ω`` (rad/s).

    Parameters
    ----------
    freqs : float or sequence of float or None
        The frequencies; None gives no points.
    dt : float or None
        The sample time.

    Returns
    -------
    numpy.ndarray
        Complex points.

    Raises
    ------
    ParameterError
        A negative or non-finite frequency.

    Examples
    --------
    >>> frequency_points([0.0, 2.0], None).tolist()
    [0j, 2j]

    References
    ----------
    Varga (2017), §3.3 (strong detectability at given frequencies).
    """
    if freqs is None:
        return np.zeros(0, dtype=complex)
    w = np.atleast_1d(np.asarray(freqs, dtype=float)).ravel()
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ParameterError(f"fdfreq must hold finite frequencies ≥ 0 (rad/s), got {w.tolist()}")
    return 1j * w if dt is None else np.exp(1j * w * dt)


def fault_response(model: FaultModel, faults: Sequence[str], lam: complex) -> np.ndarray:
    """``G_f(λ) = C (λI − A)^{-1} B_f + D_f`` of the named fault inputs at one point, ``(p, len(faults))``.

    Parameters
    ----------
    model : FaultModel
        The plant.
    faults : sequence of str
        Fault inputs (group ``f``).
    lam : complex
        The point; at a pole of the plant it is moved off by ``1e-7 · max(1, |λ|)``.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0]], Bf=[[1.0]])
    >>> complex(fault_response(m, ["f0"], 0.0)[0, 0])
    (1+0j)

    References
    ----------
    Varga (2017), §3.3 (fault detectability conditions).
    """
    return _response(model, faults, lam)[0]


def _response(model: FaultModel, faults: Sequence[str], lam: complex) -> tuple[np.ndarray, complex]:
    """``G_f`` at ``λ`` (moved off a pole) and the point used."""
    cols = [len(model.controls) + len(model.disturbances) + i for i in model.index("f", faults)]
    B, D, A, n = model.B[:, cols], model.D[:, cols], model.A, model.n
    if not n:
        return D.astype(complex), lam
    M = lam * np.eye(n) - A
    if np.linalg.cond(M) > 1e12:
        lam = lam + 1e-7 * max(1.0, abs(lam)) * (1 + 1j) / np.sqrt(2)
        M = lam * np.eye(n) - A
    return D + model.C @ np.linalg.solve(M, B), lam


def row_structure(model: FaultModel, basis, faults: Sequence[str], *, fdtol: float = 1e-4,
                  fdfreq=None, fdgaintol: float = 0.01, dens: Sequence[np.ndarray] | None = None,
                  rows: Sequence[np.ndarray] | None = None, by_frequency: bool = False) -> np.ndarray:
    """Which faults each row detects: ``(q, len(faults))`` booleans, weak or (with ``fdfreq``) strong.

    A row is strong for a fault when it detects it at every frequency of ``fdfreq``; ``by_frequency`` keeps the
    frequencies apart, ``(q, len(faults), len(fdfreq))``, which is what feasibility needs (:func:`covered`).

    Parameters
    ----------
    model : FaultModel
        The plant the basis was computed for.
    basis : NullspaceBasis
        The basis (its ``scale`` and, when ``rows`` is None, its rows).
    faults : sequence of str
        The fault inputs to test.
    fdtol : float, default 1e-4
        Relative threshold of weak detectability.
    fdfreq : float or sequence of float, optional
        Frequencies (rad/s) of strong detectability; the gain must exceed ``fdgaintol`` at all of them.
    fdgaintol : float, default 0.01
        Gain threshold of strong detectability.
    dens : sequence of numpy.ndarray, optional
        The denominators ``φ_i`` (highest power first); required with ``fdfreq``.
    rows : sequence of numpy.ndarray, optional
        Coefficient rows to test instead of the basis rows (e.g. combined rows).
    by_frequency : bool, default False
        One boolean matrix per frequency (a trailing axis; one entry for the weak structure).

    Returns
    -------
    numpy.ndarray
        Boolean matrix (``by_frequency``: a stack of them).

    Raises
    ------
    ParameterError
        ``fdfreq`` without ``dens``.

    Examples
    --------
    >>> from fdikit.design.nullspace.basis import left_nullspace
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bd=[[1.0]], Bf=[[1.0, 0.0]], Df=[[0.0, 0.0], [0.0, 1.0]])
    >>> row_structure(m, left_nullspace(m), ["f0", "f1"]).tolist()
    [[False, True]]

    References
    ----------
    Varga (2017), §3.4 (weak and strong structure matrices); fdtools (``fdisspec``).
    """
    coeffs = list(basis.rows if rows is None else rows)
    faults = tuple(faults)
    pts = frequency_points(fdfreq, model.dt)
    S = np.zeros((len(coeffs), len(faults)), dtype=bool)
    if not coeffs or not faults:
        return np.zeros((*S.shape, max(pts.size, 1)), dtype=bool) if by_frequency else S
    mu = len(model.controls)
    poly = np.polynomial.polynomial.polyval
    for z in _GENERIC:
        G, lam = _response(model, faults, z * basis.scale)
        Gn = np.linalg.norm(G, axis=0)
        for i, N in enumerate(coeffs):
            Ny = poly(lam / basis.scale, N)[mu:]
            val = np.abs(Ny @ G)
            S[i] |= val > fdtol * np.linalg.norm(Ny) * Gn
    S = np.repeat(S[:, :, None], max(pts.size, 1), axis=2)
    if pts.size:
        if dens is None:
            raise ParameterError("strong detectability (fdfreq) needs the filter denominators")
        for k, lam0 in enumerate(pts):
            G, lam = _response(model, faults, lam0)
            for i, N in enumerate(coeffs):
                # the realised row is N(λ/α) / φ'(λ/α) with the monic φ'(μ) = φ(αμ) / α^d (basis.realize_rows)
                d = len(dens[i]) - 1
                gain = np.abs(poly(lam / basis.scale, N)[mu:] @ G) * basis.scale ** d / abs(np.polyval(dens[i], lam))
                S[i, :, k] &= gain > fdgaintol
    return S if by_frequency else S.all(axis=2)


def covered(S: np.ndarray, used: Sequence[int] | None = None) -> np.ndarray:
    """Per fault: do the rows ``used`` (default all) detect it, at every frequency by some row?

    The reference's feasibility test (``efdbasesel``, ``fdigenspec``): a combination of rows detects a fault
    strongly at every frequency when, at each frequency, one of its rows does; no single row need detect it at all
    of them (``[s/(s+1); (s²+4)/(s+3)²]`` at 0 and 2 rad/s).

    Parameters
    ----------
    S : numpy.ndarray
        ``row_structure(..., by_frequency=True)``, or a 2-D matrix (one frequency).
    used : sequence of int, optional
        The rows of ``S`` to combine.

    Returns
    -------
    numpy.ndarray
        One boolean per fault.

    Examples
    --------
    >>> S = np.array([[[False, True]], [[True, False]]])    # two rows, one fault, two frequencies
    >>> covered(S).tolist(), covered(S, [0]).tolist(), covered(S.all(axis=2)).tolist()
    ([True], [False], [False])

    References
    ----------
    Varga (2017), §5.2 (Procedure EFD, step 2); fdtools (``efdbasesel``).
    """
    S3 = S[:, :, None] if S.ndim == 2 else S
    if used is not None:
        S3 = S3[list(used)]
    return S3.any(axis=0).all(axis=-1)
