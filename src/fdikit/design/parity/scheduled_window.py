"""Time-indexed bar matrices, rank test and parity row of one LPV window (van der Ploeg 2018, Sec. 3-3, Lemma 3-3.2,
Fact 3-3.3, Thm 3-3.4).

The speed-scheduled parity filter (:mod:`fdikit.design.parity.scheduled`) works on a window of the
DAE models ``H_k(q)[x] + L_k(q)[z] + F_k(q)[f] = 0`` (3.11) at the instants ``τ_0 … τ_{d_N}``
(oldest first).  For one such window this module builds the time-indexed bar matrices
``(H̄_k, L̄_k, F̄_k)`` of Lemma 3-3.2, tests the fault's detectability ``Rank [H̄_k F̄_k] > Rank H̄_k``
(Fact 3-3.3, (3.15)) and gives the unnormalised parity row of Theorem 3-3.4::

    N̄_k*(γ) = ½ F̄_{k,j}ᵀ (I + γ H̄_k H̄_kᵀ)⁻¹                                    (3.17)

or its exact limit ``γ → ∞``, ``N̄_k = ½ (P_k F̄_{k,j})ᵀ`` with ``P_k`` the orthogonal projector
onto the left null space of ``H̄_k`` (``gamma=None``).

Errata (van der Ploeg 2018, Lemma 3-3.2):

* the windows are time-consistent: block row ``i`` of ``H̄_k`` holds ``H_j(ρ(τ_i))`` at block
  column ``i + j`` (columns ``x(τ_0) … x(τ_{d_N} + d_H)``), ``F̄_k``, ``L̄_k`` likewise.  The
  thesis labels its first block row ``ρ_1 = V_x(k − 1)`` (reversed) and prints the ``z``
  window one sample short and the ``r`` sum from ``i = 0``; the rank test (3.15) is
  unaffected by the ordering.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.dae import DAEModel
from fdikit.design.parity.polynomial_rank import RankTest
from fdikit.design.parity.polynomial_rank import time_varying_bar as _bar
from fdikit.errors import DesignError
from fdikit.linalg import rank

__all__ = [
    "lpv_bar_matrices",
    "lpv_parity_row",
    "lpv_rank_test",
]


def lpv_bar_matrices(window: Sequence[DAEModel], fault: str | None = None) -> tuple[np.ndarray, ...]:
    """``(H̄_k, L̄_k, F̄_k)`` of Lemma 3-3.2 from the DAE models at the instants ``τ_0 … τ_{d_N}`` (oldest first).

    Parameters
    ----------
    window : sequence of DAEModel, one per instant (``d_N + 1`` of them).
    fault : str or None, the fault column of ``F`` (default: the only fault).

    Returns
    -------
    tuple of three arrays, the time-indexed bar matrices of ``H``, ``L`` and of the fault column of ``F``.

    Examples
    --------
    >>> from fdikit.dae import dae_form; from fdikit.plants.single_track import single_track_lpv
    >>> window = [dae_form(single_track_lpv()(v)) for v in (19.0, 19.5, 20.0)]
    >>> [M.shape for M in lpv_bar_matrices(window)]
    [(21, 24), (21, 12), (21, 3)]

    References
    ----------
    van der Ploeg 2018, Lemma 3-3.2.
    """
    j = window[0].fault_index(fault)
    return (_bar([m.H for m in window]), _bar([m.L for m in window]), _bar([[F[:, [j]] for F in m.F] for m in window]))


def lpv_rank_test(window: Sequence[DAEModel], fault: str | None = None) -> RankTest:
    """Fact 3-3.3 / (3.15): ``Rank [H̄_k F̄_k] > Rank H̄_k`` for one window of parameter values.

    Parameters
    ----------
    window, fault : as in :func:`lpv_bar_matrices`.

    Returns
    -------
    RankTest

    Examples
    --------
    >>> from fdikit.dae import dae_form; from fdikit.plants.single_track import single_track_lpv
    >>> window = [dae_form(single_track_lpv()(v)) for v in (19.0, 19.5, 20.0)]
    >>> lpv_rank_test(window)
    RankTest(holds=True, rank_with=21, rank_without=20)

    References
    ----------
    van der Ploeg 2018, Fact 3-3.3, (3.15).
    """
    Hb, _, Fb = lpv_bar_matrices(window, fault)
    r_with, r_without = rank(np.hstack([Hb, Fb])), rank(Hb)
    return RankTest(r_with > r_without, r_with, r_without)


def lpv_parity_row(H_bar: np.ndarray, F_column: np.ndarray, gamma: float | None = None) -> np.ndarray:
    """Parity row(s) of Theorem 3-3.4 before normalisation; stacks of windows are allowed (leading axis).

    ``gamma`` a positive number: the closed form (3.17) ``½ F̄_jᵀ (I + γ H̄ H̄ᵀ)⁻¹``.
    ``gamma=None``: its limit ``½ (P F̄_j)ᵀ``, ``P = I − H̄ H̄⁺`` (SVD, relative rank tolerance).

    Parameters
    ----------
    H_bar : (m, n) or (K, m, n) array, ``H̄_k`` (or a stack of them).
    F_column : (m,) or (K, m) array, the column ``F̄_{k,j}``.
    gamma : float or None, the Lagrange multiplier (None: the exact limit).

    Returns
    -------
    (m,) or (K, m) array, the unnormalised row(s) ``N̄_k``.

    Raises
    ------
    DesignError
        ``gamma`` not a positive finite number.

    Examples
    --------
    >>> import numpy as np
    >>> H, f = np.array([[1.0], [0.0]]), np.array([1.0, 1.0])
    >>> lpv_parity_row(H, f).round(6).tolist(), lpv_parity_row(H, f, gamma=1.0).round(6).tolist()
    ([0.0, 0.5], [0.25, 0.5])

    References
    ----------
    van der Ploeg 2018, Thm 3-3.4, (3.17).
    """
    H = np.asarray(H_bar, dtype=float)
    f = np.asarray(F_column, dtype=float)
    single = H.ndim == 2
    H, f = (H[None], f.reshape(1, -1)) if single else (H, f.reshape(H.shape[0], -1))
    if gamma is None:
        U, s, _ = np.linalg.svd(H, full_matrices=True)
        tol = 1e3 * max(H.shape[1:]) * np.finfo(float).eps * s[:, :1]
        c = np.einsum("kij,ki->kj", U, f)
        c[:, : s.shape[1]] *= ~(s > tol)
        out = 0.5 * np.einsum("kij,kj->ki", U, c)
    else:
        if not (np.isfinite(gamma) and gamma > 0):
            raise DesignError(f"gamma must be a positive Lagrange multiplier (thesis: 1e7) or None, got {gamma}")
        M = np.eye(H.shape[1]) + gamma * np.einsum("kij,klj->kil", H, H)
        out = 0.5 * np.linalg.solve(M, f[..., None])[..., 0]
    return out[0] if single else out
