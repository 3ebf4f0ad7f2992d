"""The gap rule: how a residual generator passes a gap of invalid samples (internal module).

Shared by :meth:`fdikit.residuals.ResidualGenerator.run` and
:class:`fdikit.residuals.ResidualStepper`, so that the batch and the online residuals agree
sample for sample (residuals, ``valid`` and ``recovering`` flags).

A sample is *invalid* when a signal the generator reads is NaN/inf.  The filter
``z+ = A z + B_u u + B_y y``, ``r = C z + D_u u + D_y y`` is split into its independent parts
(connected components of the states and residuals through ``A`` and ``C``; a stacked bank gives
one per filter).  On a sample where the outputs ``b`` are invalid, each part ``c`` is fed
``y_b = −(D_{y,cb})⁺ (C_c z_c + D_{u,c} u + D_{y,c,good} y_good) + Π_c y_b,last``: the
least-squares choice that makes the part's residuals closest to zero (exactly zero when
``D_{y,cb}`` has full column rank, as for an observer ``r = y − ŷ``, where it is the predicted
output: open-loop model propagation, channel by channel when only some outputs are missing), and
in the directions the part's feedthrough does not see (``Π_c = I − D⁺D``) the last valid value.
An invalid control is held at its last valid value (0 before any).  The residuals of an invalid
sample are NaN.

The deviation ``δ`` of the filter state from the one the true samples would have given obeys,
with ``e`` the fault-free residual,

    δ+ = (A − B_b D⁺ C) δ − B_b D⁺ e     (invalid sample),      δ+ = A δ     (valid sample),

and the residual transient is ``C δ``.  :class:`Recovery` propagates ``P = Cov δ`` with
``Σ = Cov e = residual_cov``: ``P+ = T P Tᵀ + G Σ Gᵀ`` per invalid sample (``T = A − B_b D⁺ C``,
``G = −B_b D⁺``, part by part), ``P+ = A P Aᵀ`` per valid one.  The finite samples after a gap are
*recovering* (not valid for decisions) while ``diag(C P Cᵀ) > tol² diag(residual_cov)``, i.e. until
every residual's transient standard deviation is at most ``recovery_tol`` times its noise standard
deviation.  The recovery therefore grows with the gap (as ``log`` of the open-loop error growth)
and shrinks with the spectral radius ``ρ(A)``.  Parts fed a held value (not predicted) add an error
the filter matrices cannot bound; for them the recovery lasts at least
``ceil(log tol / log ρ)`` samples (the filter forgetting its state by the factor ``tol``), and a
filter with ``ρ ≥ 1`` and held values never recovers.  ``ρ`` is the spectral radius of the part of
``A`` the residuals see (the observable part of ``(A, C)``, SLICOT TB01PD): a mode no residual
reads cannot show its transient — a Kalman filter that reads one of two tanks in series carries the
other tank's open-loop mode, unobservable from its residual, which would otherwise hold every sample
after a dropout for thousands of samples.

>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.5]], [[0.0, 1.0]], [[-1.0]], [[0.0, 1.0]], ["u"], ["y"], ["r"], dt=1.0)
>>> rule = GapRule(g, None, 0.1)
>>> rule.settle  # least recovery of a part fed held values: ceil(log 0.1 / log 0.5) samples
4
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from fdikit.errors import ParameterError

if TYPE_CHECKING:
    from fdikit.residuals import ResidualGenerator

__all__ = ["GapRule", "Recovery", "gap_options"]


def gap_options(g: ResidualGenerator, residual_cov, tol) -> tuple[np.ndarray, float]:
    """``(Σ, tol)`` of the gap rule after checking them; what :class:`GapRule` and a clean ``run`` both check.

    Parameters
    ----------
    g : ResidualGenerator
        The discrete generator the rule is for (its residual count sizes ``Σ``).
    residual_cov : array or None
        Covariance of the fault-free residuals (q x q, or a length-q row of variances); ``None`` means ``I``.
    tol : float
        ``recovery_tol``: a sample after a gap is recovering until each residual's transient standard deviation is
        at most ``tol`` times its noise standard deviation; in ``(0, 1]``.

    Returns
    -------
    S : (q, q) array
        The residual covariance ``Σ``.
    tol : float
        The tolerance as a float.

    Raises
    ------
    ParameterError
        For a ``recovery_tol`` outside ``(0, 1]`` or a ``residual_cov`` that is not a finite symmetric
        ``q x q`` matrix with a positive diagonal.

    Examples
    --------
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[0.0, 1.0]], [[-1.0]], [[0.0, 1.0]], ["u"], ["y"], ["r"], dt=1.0)
    >>> S, tol = gap_options(g, None, 0.1)
    >>> S.tolist(), tol
    ([[1.0]], 0.1)
    """
    if isinstance(tol, bool) or not isinstance(tol, (int, float, np.integer, np.floating)):
        raise ParameterError(f"recovery_tol must be a number in (0, 1], got {tol!r}")
    if not (np.isfinite(tol) and 0 < tol <= 1):
        raise ParameterError(f"recovery_tol must be in (0, 1] (a fraction of the noise std), got {tol!r}")
    q = len(g.residuals)
    if residual_cov is None:
        S = np.eye(q)
    else:
        try:
            S = np.atleast_2d(np.asarray(residual_cov, dtype=float))
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"residual_cov must be a {q}x{q} covariance matrix, got {residual_cov!r}") from exc
        if S.shape == (1, q) and q > 1:
            S = np.diag(S[0])
        if S.shape != (q, q) or not np.all(np.isfinite(S)) or not np.allclose(S, S.T, rtol=1e-10, atol=0):
            raise ParameterError(f"residual_cov must be a finite symmetric {q}x{q} matrix (residuals "
                                 f"{list(g.residuals)}), got shape {S.shape}")
        if q and not np.all(np.diag(S) > 0):
            raise ParameterError("residual_cov must have a positive diagonal (every residual has noise)")
    return S, float(tol)


class GapRule:
    """The gap rule of one discrete generator (shared by ``run`` and the stepper, so both agree).

    The module docstring gives the rule and its derivation.  Built once per generator: it checks
    ``residual_cov`` and ``tol`` (:class:`~fdikit.errors.ParameterError`), splits the filter into
    its independent parts, and caches per pattern of valid channels the matrices of the rule.

    Parameters
    ----------
    g : ResidualGenerator
        The discrete generator.
    residual_cov, tol :
        As :func:`gap_options`.

    Attributes
    ----------
    rho : float
        Spectral radius of the observable part of the filter's ``(A, C)`` (the modes a residual shows).
    settle : int
        Least number of recovering samples after a gap in which a part is fed held values,
        ``ceil(log tol / log ρ)`` (``-1``: never, for ``ρ >= 1``).

    Examples
    --------
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[0.0, 1.0]], [[-1.0]], [[0.0, 1.0]], ["u"], ["y"], ["r"], dt=1.0)
    >>> GapRule(g, None, 0.1).settle
    4
    """

    def __init__(self, g: ResidualGenerator, residual_cov, tol) -> None:
        S, tol = gap_options(g, residual_cov, tol)
        self.g, self.S, self.tol = g, S, tol
        self.limit = self.tol**2 * np.diag(S)
        self.mu = len(g.controls)
        n = g.n
        rho = _visible_radius(g.A, g.C) if n else 0.0
        self.rho = rho
        self.settle = 0 if n == 0 else (1 if rho == 0 else (
            int(np.ceil(np.log(self.tol) / np.log(rho))) if rho < 1 else -1))
        self.parts = _components(g.A, g.C)
        self._AT = g.A.T.copy()
        self._cache: dict[bytes, tuple] = {}

    def pattern(self, ok_ch: np.ndarray) -> tuple:
        """Per pattern of valid channels: per part (states, rows, M⁺, Π), the δ-matrices (T, Q) and "held"."""
        key = ok_ch.tobytes()
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        g, mu = self.g, self.mu
        bad_y = np.flatnonzero(~ok_ch[mu:])
        bad_u = np.flatnonzero(~ok_ch[:mu])
        good_y = np.flatnonzero(ok_ch[mu:])
        n, q = g.n, len(g.residuals)
        T = g.A.copy()
        G = np.zeros((n, q))
        held = bool(bad_u.size and np.any(g.B[:, bad_u] != 0))
        parts = []
        for states, rows in self.parts:
            Bb = g.B[np.ix_(states, mu + bad_y)]
            M = g.D[np.ix_(rows, mu + bad_y)]
            Mp = np.linalg.pinv(M, rcond=1e-10) if M.size else np.zeros((bad_y.size, rows.size))
            Pi = np.eye(bad_y.size) - Mp @ M
            if states.size and np.any(np.abs(Bb @ Pi) > 1e-12 * max(1.0, np.abs(Bb).max(initial=0))):
                held = True
            K = Bb @ Mp
            if states.size and rows.size:
                T[np.ix_(states, states)] -= K @ g.C[np.ix_(rows, states)]
                G[np.ix_(states, rows)] = -K
            parts.append((states, rows, Mp, Pi))
        hit = (bad_y, bad_u, good_y, parts, T, G @ self.S @ G.T, held)
        self._cache[key] = hit
        return hit

    def propagate(self, z: np.ndarray, v: np.ndarray, ok_ch: np.ndarray, last: np.ndarray) -> np.ndarray:
        """The filter state after an invalid sample ``v`` (entries with ``ok_ch`` False are unusable)."""
        g, mu = self.g, self.mu
        bad_y, bad_u, good_y, parts, _, _, _ = self.pattern(ok_ch)
        w = np.where(ok_ch, v, last)  # controls: last valid value; outputs: replaced per part below
        znew = np.empty_like(z)
        for states, rows, Mp, Pi in parts:
            wc = w.copy()
            if bad_y.size:
                known = g.C[np.ix_(rows, states)] @ z[states] + g.D[rows, :mu] @ w[:mu] \
                    + g.D[np.ix_(rows, mu + good_y)] @ w[mu + good_y]
                wc[mu + bad_y] = -(Mp @ known) + Pi @ last[mu + bad_y]
            znew[states] = g.A[np.ix_(states, states)] @ z[states] + g.B[states] @ wc
        return znew


class Recovery:
    """Which samples after a gap are still recovering (the bookkeeping of :class:`GapRule`).

    Parameters
    ----------
    rule : GapRule
        The rule of the generator whose samples are tracked.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[0.0, 1.0]], [[-1.0]], [[0.0, 1.0]], ["u"], ["y"], ["r"], dt=1.0)
    >>> rec = Recovery(GapRule(g, None, 0.1))
    >>> rec.invalid_sample(np.array([True, False]))  # the output is missing
    >>> rec.active
    True
    """

    def __init__(self, rule: GapRule) -> None:
        self.rule = rule
        self.P: np.ndarray | None = None
        self.hold = 0

    @property
    def active(self) -> bool:
        return self.P is not None or self.hold != 0

    def invalid_sample(self, ok_ch: np.ndarray) -> None:
        rule = self.rule
        _, _, _, _, T, Q, held = rule.pattern(ok_ch)
        P = np.zeros_like(T) if self.P is None else self.P
        self.P = T @ P @ T.T + Q
        if held:
            self.hold = rule.settle

    def valid_sample(self) -> bool:
        """Advance over a valid sample; True when it may be used for decisions."""
        rule = self.rule
        recovering = False
        if self.P is not None:
            d = np.einsum("ij,jk,ik->i", rule.g.C, self.P, rule.g.C)
            if np.any(d > rule.limit):
                recovering = True
                self.P = rule.g.A @ self.P @ rule._AT
            else:
                self.P = None
        if self.hold != 0:
            recovering = True
            self.hold -= 1 if self.hold > 0 else 0
        return not recovering


def _components(A: np.ndarray, C: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Independent parts of a filter: (states, residual rows) connected through A and C."""
    n, q = A.shape[0], C.shape[0]
    parent = list(range(n + q))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def join(i: int, j: int) -> None:
        parent[find(i)] = find(j)

    for i, j in zip(*np.nonzero(A)):
        join(int(i), int(j))
    for k, j in zip(*np.nonzero(C)):
        join(n + int(k), int(j))
    groups: dict[int, list[int]] = {}
    for i in range(n + q):
        groups.setdefault(find(i), []).append(i)
    out = []
    for members in groups.values():
        states = np.array([i for i in members if i < n], dtype=int)
        rows = np.array([i - n for i in members if i >= n], dtype=int)
        out.append((states, rows))
    return out


def _visible_radius(A: np.ndarray, C: np.ndarray) -> float:
    """Spectral radius of the observable part of ``(A, C)`` (SLICOT TB01PD, ``job='O'``); 0 when nothing is seen."""
    from slycot import tb01pd

    n, q = A.shape[0], C.shape[0]
    if q == 0 or not np.any(C):
        return 0.0
    try:
        Ao, _, _, nr = tb01pd(n, 1, q, A.copy(), np.zeros((n, max(1, q))), C.copy(), job="O", equil="N", tol=0.0)
    except Exception:  # noqa: BLE001 - SLICOT failing on a pathological filter: fall back to every mode
        return float(np.max(np.abs(np.linalg.eigvals(A))))
    return float(np.max(np.abs(np.linalg.eigvals(Ao[:nr, :nr])))) if nr else 0.0
