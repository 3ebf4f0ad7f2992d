"""Speed-scheduled (LPV) parity fault detection filter (van der Ploeg 2018, Sec. 3-3, Thm 3-3.4; Sec. 4-3-4).

The model varies with a measured parameter ``ρ`` (the longitudinal speed): ``H_k(q)[x] +
L_k(q)[z] + F_k(q)[f] = 0`` (3.11), sampled with the parameter frozen over each sample
("complete discretisation", Sec. 4-3-4).  At every step ``k`` the filter rebuilds the
time-indexed bar matrices of Lemma 3-3.2 from the models at the instants of its window and
takes the parity row of Theorem 3-3.4::

    N̄_k*(γ) = ½ F̄_{k,j}ᵀ (I + γ H̄_k H̄_kᵀ)⁻¹                                    (3.17)

or its exact limit ``γ → ∞``, ``N̄_k = ½ (P_k F̄_{k,j})ᵀ`` with ``P_k`` the orthogonal projector
onto the left null space of ``H̄_k`` (``gamma=None``).  ``N̄_k`` is then
scaled so that ``Σ N̄_k F̄_k = −d(1)`` ((4.18)–(4.19): the fault-to-residual DC gain is 1),
and the residual follows the input-output form of Corollary 3-3.5::

    d(q) r = w,   w(k) = N̄_k L̄_k [z(τ_0); …; z(τ_{d_N + d_L})],   τ_i = k − deg d + i

so ``r(k)`` uses ``z`` and ``ρ`` up to ``k − 1`` only (strictly proper).

Errata and reconstruction choices (van der Ploeg 2018, Lemma 3-3.2, Thm 3-3.4, Sec. 4-3-4):

* the windows are time-consistent: block row ``i`` of ``H̄_k`` holds ``H_j(ρ(τ_i))`` at block
  column ``i + j`` (columns ``x(τ_0) … x(τ_{d_N} + d_H)``), ``F̄_k``, ``L̄_k`` likewise.  The
  thesis labels its first block row ``ρ_1 = V_x(k − 1)`` (reversed) and prints the ``z``
  window one sample short and the ``r`` sum from ``i = 0``; the rank test (3.15) is
  unaffected by the ordering;
* ``N_k(1) F_k(1)`` in (4.18) is read as ``Σ N̄_k F̄_k`` (the current coefficients);
* ``j`` must select a coefficient of ``F`` that reaches ``N_k(q) F_k(q)``: for the
  single-track model the ``q²`` column lies in the range of ``H̄_k`` (the fault at the last
  instant only moves the next state), so ``N̄_k ≈ 0`` there (Sec. 4-3-4); that choice raises
  :class:`DesignError`;
* ``d(q) = Π (q − p_i)`` with real poles, run as a cascade of first-order sections.

The schedule is a measured signal: :meth:`ScheduledResidualGenerator.run` reads it from the
trace by name (an output or control column, default ``"speed"``) or takes an array;
:func:`fdikit.simulate.simulate_scheduled` appends it to the trace as an output column.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from fdikit.design.parity.polynomial import (
    DAEModel,
    PolynomialParityDesign,
    RankTest,
    dae_form,
    parity_filter,
    real_poles,
    target_fault,
)
from fdikit.design.parity.polynomial import time_varying_bar as _bar
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.linalg import rank
from fdikit.model import FaultModel
from fdikit.protocols import no_internal_form
from fdikit.residuals import Residuals, check_signals
from fdikit.trace import Trace

__all__ = [
    "ScheduledResidualGenerator",
    "ScheduledStepper",
    "lpv_bar_matrices",
    "lpv_parity_row",
    "lpv_rank_test",
    "scheduled_parity_filter",
]

Family = Callable[[float], FaultModel]


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


@dataclass(frozen=True, eq=False)
class ScheduledResidualGenerator:
    """A parity filter whose row ``N̄_k`` follows a measured schedule ``ρ`` (Thm 3-3.4, Cor. 3-3.5).

    Build it with :func:`scheduled_parity_filter`.  ``run(trace)`` is vectorised; ``online()``
    gives a :class:`ScheduledStepper` with ``step(u, y, rho)``; both give the same residuals.

    Attributes
    ----------
    family : ``ρ -> FaultModel`` (discrete, same names and ``dt`` for every ``ρ``).
    fault, degree, poles, gamma, column : design choices (``gamma=None`` is the exact projection).
    controls, outputs, residuals, isolates, dt : as :class:`~fdikit.residuals.ResidualGenerator`.
    schedule : name of the trace column holding ``ρ``.
    reference : the LTI :class:`PolynomialParityDesign` at the design point.
    fast_path : whether the family's ``dae_matrices`` is used (see :meth:`dae`).

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> gen = scheduled_parity_filter(single_track_lpv(), 70 / 3.6)
    >>> gen.fault, gen.schedule, gen.fast_path
    ('steering_actuator', 'speed', True)

    References
    ----------
    van der Ploeg 2018, Thm 3-3.4, Cor. 3-3.5; Sec. 4-3-4.
    """

    family: Family
    fault: str
    degree: int
    poles: np.ndarray
    gamma: float | None
    column: int
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    residuals: tuple[str, ...]
    isolates: tuple[str | None, ...]
    dt: float
    schedule: str
    reference: PolynomialParityDesign
    fast_path: bool = False
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def window(self) -> int:
        """Number of past samples the filter reads (``deg d``)."""
        return self.poles.size

    def _coefficients(self, rho: float) -> tuple[tuple[np.ndarray, ...], ...]:
        """``(H, L, F)`` coefficient tuples at ``rho`` (``F``: the fault column), cached per value."""
        key = float(rho)
        hit = self._cache.get(key)
        if hit is None:
            if self.fast_path:
                H0, H1, L, F = self.family.dae_matrices(key)
                hit = ((H0, H1), (L,), (F,))
            else:
                model = self.family(key)
                if not isinstance(model, FaultModel) or model.dt != self.dt or model.outputs != self.outputs:
                    raise ModelError(f"family({key}) must return a discrete FaultModel with dt={self.dt} and "
                                     f"outputs {list(self.outputs)} like the design point")
                dae = dae_form(model, [self.fault])
                hit = (dae.H, dae.L, dae.F)
            if len(self._cache) > 100_000:
                self._cache.clear()
            self._cache[key] = hit
        return hit

    def dae(self, rho: float) -> DAEModel:
        """The DAE (4.17) at parameter value ``rho``.

        A family with a ``dae_matrices(rho) -> (H_0, H_1, L, F)`` method (e.g.
        :class:`~fdikit.plants.single_track.SingleTrackLPV`) whose matrices equal
        ``dae_form(family(reference), [fault])`` at the design point is read through it
        (``fast_path``); otherwise ``dae_form(family(rho), [fault])``.  Values are cached.
        """
        H, L, F = self._coefficients(rho)
        ref = self.reference.dae
        return DAEModel(H, L, F, ref.unknowns, ref.outputs, ref.controls, (self.fault,), ref.dt)

    def bar_matrices(self, windows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stacks of ``(H̄_k, L̄_k, F̄_k)`` (Lemma 3-3.2), one per row of ``windows`` (``d_N + 1`` values, oldest first).

        The same matrices as :func:`lpv_bar_matrices` on ``[dae(ρ) for ρ in window]``, assembled
        for many windows at once.
        """
        windows = np.atleast_2d(np.asarray(windows, dtype=float))
        vals, idx = np.unique(windows, return_inverse=True)
        idx = idx.reshape(windows.shape)
        coeffs = [self._coefficients(v) for v in vals]
        out = []
        for part in range(3):
            C = np.stack([np.stack(c[part]) for c in coeffs])  # (values, degree + 1, rows, cols)
            _, deg1, r, c = C.shape
            K, n_rows = windows.shape
            M = np.zeros((K, n_rows * r, (n_rows + deg1 - 1) * c))
            for i in range(n_rows):
                for j in range(deg1):
                    M[:, i * r : (i + 1) * r, (i + j) * c : (i + j + 1) * c] = C[idx[:, i], j]
            out.append(M)
        return out[0], out[1], out[2]

    def rows(self, windows: np.ndarray) -> np.ndarray:
        """Normalised ``N̄_k L̄_k`` (one row per window of ``d_N + 1`` parameter values, oldest first).

        Raises :class:`DesignError` where ``Σ N̄_k F̄_k ≈ 0`` (a degenerate column ``j``).
        """
        windows = np.atleast_2d(np.asarray(windows, dtype=float))
        uniq, inv = np.unique(windows, axis=0, return_inverse=True)
        Hb, Lb, Fb = self.bar_matrices(uniq)
        Nb = lpv_parity_row(Hb, Fb[:, :, self.column], self.gamma)
        nf = np.einsum("ki,kij->k", Nb, Fb)
        bad = np.flatnonzero(~(np.abs(nf) > 1e-12 * np.linalg.norm(Fb, axis=(1, 2)) ** 2))
        if bad.size:
            raise DesignError(
                f"at schedule window {uniq[bad[0]].tolist()} the parity row does not see the fault "
                f"(Σ N̄F̄ = {nf[bad[0]]:.2e}): column j={self.column} of F̄ lies in the range of H̄; choose column=0"
            )
        scale = -np.prod(1.0 - self.poles) / nf
        return (np.einsum("ki,kij->kj", Nb, Lb) * scale[:, None])[inv.ravel()]

    def _windows(self, rho: np.ndarray) -> np.ndarray:
        """Per sample ``k`` the parameters at ``τ_i = k − deg d + i``, ``i = 0…d_N`` (before ``k = 0``: ``ρ(0)``)."""
        n = self.window
        padded = np.concatenate([np.full(n, rho[0]), rho])
        return np.stack([padded[i : i + rho.size] for i in range(self.degree + 1)], axis=1)

    def _z_lags(self) -> int:
        return self.degree + len(self.reference.dae.L)

    def recovery_length(self, tol: float = 0.1) -> int:
        """Samples a residual stays *recovering* after the last sample whose ``w`` was zero-filled.

        The residual is ``r = h * w`` with ``h`` the impulse response of ``1/d(q)``.  A value
        ``w_j`` that could not be formed (its window held an invalid sample) is replaced by 0 (its
        fault-free prediction), which leaves ``r_k`` short by ``h_{k−j} w_j``.  Taking ``w`` white,
        the transient's variance relative to the residual's is at most ``Σ_{i≥k−j} h_i² / Σ_i h_i²``
        (every earlier ``w`` missing); the sample is valid again when this is ``≤ tol²``.  Pure
        function of the poles (one value per ``tol``).
        """
        if isinstance(tol, bool) or not isinstance(tol, (int, float, np.integer, np.floating)) or not (
                np.isfinite(tol) and 0 < tol <= 1):
            raise ParameterError(f"recovery_tol must be a number in (0, 1], got {tol!r}")
        pmax = float(np.max(np.abs(self.poles))) if self.poles.size else 0.0
        length = int(max(64, np.ceil(60.0 * max(1, self.poles.size) / max(1e-3, 1.0 - pmax))))
        h = np.zeros(length)
        h[0] = 1.0
        for pole in self.poles:
            h = scipy.signal.lfilter([1.0], [1.0, -pole], h)
        tail = np.cumsum((h**2)[::-1])[::-1]  # tail[d] = Σ_{i≥d} h_i²
        return int(np.argmax(tail <= tol**2 * tail[0]))

    def run(self, trace: Trace, schedule: np.ndarray | str | None = None, *, recovery_tol: float = 0.1) -> Residuals:
        """Residuals of a whole trace; ``schedule`` is an array (N,), a column name, or None (``self.schedule``).

        Vectorised, and identical to :meth:`online` stepping (same residuals to rounding, same flags).

        Gap rule (a sample is *invalid* when a used signal or the schedule is NaN/inf): its residual
        is NaN.  The parity value ``w(k) = N̄_k L̄_k [z(τ_0) … z(τ_{d_N+d_L})]`` is formed only when
        every sample of its window is valid; otherwise ``w(k) = 0``, its fault-free prediction (the
        parity relation is zero without fault and noise), so the ``d(q)`` filter is propagated
        through the gap.  The samples after a gap are *recovering* (finite residual, ``valid``
        False) until :meth:`recovery_length` samples after the last zero-filled ``w``.  At the
        start of a run that begins with a valid sample the window is padded with zeros as before
        (the start-up transient is not flagged).
        """
        rho = self.checked_schedule(trace, schedule)
        n_dec = self.recovery_length(recovery_tol)
        z = np.hstack([trace.columns("y", self.outputs), trace.columns("u", self.controls)])
        N = len(trace)
        ok = np.all(np.isfinite(z), axis=1) & np.isfinite(rho)
        n, m = self.window, self._z_lags()
        okp = np.concatenate([np.full(n, bool(ok[0]) if N else True), ok])
        cs = np.concatenate([[0], np.cumsum(okp)])
        win_ok = (cs[m : m + N] - cs[:N]) == m  # samples k−n … k−n+m−1 all valid
        zp = np.vstack([np.zeros((n, z.shape[1])), np.where(ok[:, None], z, 0.0)])
        w = np.zeros(N)
        if win_ok.any():
            zwin = np.hstack([zp[i : i + N] for i in range(m)])[win_ok]
            w[win_ok] = np.einsum("kj,kj->k", self.rows(self._windows(rho)[win_ok]), zwin)
        for pole in self.poles:
            w = scipy.signal.lfilter([1.0], [1.0, -pole], w)
        idx = np.arange(N)
        last_fill = np.maximum.accumulate(np.where(~win_ok, idx, -(n_dec + 1)))
        valid = ok & (idx - last_fill >= n_dec)
        r = np.where(ok, w, np.nan)
        meta = {"trace": dict(trace.meta), "schedule": schedule if isinstance(schedule, str) else self.schedule}
        return Residuals(trace.t, r[:, None], self.residuals, self.isolates, valid, meta=meta,
                         recovering=ok & ~valid)

    def checked_schedule(self, trace: Trace, schedule=None) -> np.ndarray:
        """The schedule of ``trace`` after checking that the filter can read the trace (type, dt, signals).

        Raises
        ------
        DataError
            For a non-trace, another sample time, missing signals or a bad schedule.
        """
        if not isinstance(trace, Trace):
            raise DataError(f"trace must be a fdikit.trace.Trace, got {type(trace).__name__}")
        if len(trace) > 1 and not np.isclose(trace.dt, self.dt, rtol=1e-6):
            raise DataError(f"data sampled at dt={trace.dt:g} but the filter runs at dt={self.dt:g}; resample")
        check_signals(trace, self.controls, self.outputs)
        return self._schedule_of(trace, schedule)

    def _schedule_of(self, trace: Trace, schedule) -> np.ndarray:
        if schedule is None or isinstance(schedule, str):
            name = schedule or self.schedule
            kind = "y" if name in trace.outputs else "u" if name in trace.controls else None
            if kind is None:
                raise DataError(f"the trace has no column {name!r} for the schedule; pass schedule=<array of "
                                f"{len(trace)} values> or the name of one of {list(trace.outputs + trace.controls)}")
            rho = trace.signal(name, kind)
        else:
            try:
                rho = np.asarray(schedule, dtype=float).ravel()
            except (TypeError, ValueError) as exc:
                raise DataError(f"the schedule must be {len(trace)} numbers (one per sample), got "
                                f"{type(schedule).__name__}") from exc
        if rho.shape != (len(trace),):
            raise DataError(f"the schedule must be {len(trace)} values (one per sample), got shape {rho.shape}")
        return rho

    def online(self, *, recovery_tol: float = 0.1) -> ScheduledStepper:
        """A stepper with zero initial history (like ``run``) and the same gap rule."""
        return ScheduledStepper(self, recovery_tol=recovery_tol)

    @property
    def generator(self) -> ScheduledResidualGenerator:
        """The scheduled filter itself (what :func:`scheduled_parity_filter` returns is its own generator)."""
        return self

    def internal_form(self):
        """Not available: raises :class:`~fdikit.errors.DesignError` (the parity row follows ρ).

        ``reference.internal_form()`` gives the LTI internal form at the design point.
        """
        no_internal_form(self, "the parity row follows the measured schedule rho, so plant and filter in series "
                               "are not an LTI FaultModel; reference.internal_form() gives it at the design point")

    def report(self) -> dict:
        """``fault``, ``degree``, ``poles``, ``gamma`` (None: exact projection), ``column``, ``schedule`` (the trace
        column of ρ), ``window`` (past samples read) and ``reference`` (the design-point report)."""
        return {"fault": self.fault, "degree": self.degree, "poles": self.poles, "gamma": self.gamma,
                "column": self.column, "schedule": self.schedule, "window": self.window,
                "reference": self.reference.report()}


class ScheduledStepper:
    """Online scheduled residuals: ``step(u, y, rho)`` returns ``r(k)`` for the sample ``(u(k), y(k), ρ(k))``.

    Gap rule as :meth:`ScheduledResidualGenerator.run`: a sample with a NaN/inf (in ``u``, ``y``
    or ``rho``) gives a NaN residual and counts in ``invalid``; it still enters the window (marked
    invalid), and every ``w`` whose window holds an invalid sample is replaced by 0 so the
    ``d(q)`` filter runs on.  ``last_valid`` is False on invalid and on recovering samples,
    ``last_recovering`` True on the latter.

    Parameters
    ----------
    generator : ScheduledResidualGenerator, the filter to step.
    recovery_tol : float in (0, 1], the recovery tolerance (see ``recovery_length``; default 0.1).

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> st = scheduled_parity_filter(single_track_lpv(), 70 / 3.6).online()
    >>> float(st.step([0.0], [0.0, 0.0, 0.0], 19.0)), st.step([float("nan")], [0.0, 0.0, 0.0], 19.0), st.invalid
    (0.0, nan, 1)

    References
    ----------
    van der Ploeg 2018, Cor. 3-3.5.
    """

    def __init__(self, generator: ScheduledResidualGenerator, *, recovery_tol: float = 0.1) -> None:
        self.generator = generator
        self._n_dec = generator.recovery_length(recovery_tol)
        self.reset()

    def reset(self) -> None:
        """Start again with zero history."""
        g = self.generator
        n = g.window
        self._z = np.zeros((n, len(g.outputs) + len(g.controls)))
        self._rho: np.ndarray | None = None
        self._ok = np.ones(n, bool)
        self._x = np.zeros(n)
        self._k = 0
        self._last_fill = -(self._n_dec + 1)
        self.invalid = 0
        self.last_valid = True
        self.last_recovering = False

    def step(self, u: Sequence[float], y: Sequence[float], rho: float) -> float:
        """Residual of this sample (``u``, ``y`` in the generator's controls/outputs order, ``rho`` the schedule)."""
        g = self.generator
        try:
            u, y = np.asarray(u, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
            rho = float(rho)
        except (TypeError, ValueError) as exc:
            raise DataError(f"step() needs numbers for u, y and rho (NaN marks a missing value): {exc}") from exc
        if u.size != len(g.controls) or y.size != len(g.outputs):
            raise DataError(f"step() needs {len(g.controls)} controls {list(g.controls)} and {len(g.outputs)} "
                            f"outputs {list(g.outputs)}, got {u.size} and {y.size}")
        ok = bool(np.all(np.isfinite(u)) and np.all(np.isfinite(y)) and np.isfinite(rho))
        if self._rho is None:
            self._rho = np.full(g.window, rho if ok else np.nan)
            self._ok[:] = ok
        m = g._z_lags()
        if self._ok[:m].all():
            row = g.rows(self._rho[: g.degree + 1])[0]
            w = float(row @ self._z[:m].ravel())
        else:
            w = 0.0
            self._last_fill = self._k
        for i, p in enumerate(g.poles):
            self._x[i] = p * self._x[i] + w
            w = self._x[i]
        self._z = np.vstack([self._z[1:], np.concatenate([y, u]) if ok else np.zeros(self._z.shape[1])])
        self._rho = np.append(self._rho[1:], rho if ok else np.nan)
        self._ok = np.append(self._ok[1:], ok)
        self.last_valid = ok and self._k - self._last_fill >= self._n_dec
        self.last_recovering = ok and not self.last_valid
        self._k += 1
        if not ok:
            self.invalid += 1
            return float("nan")
        return w

    def run(self, trace: Trace, schedule: np.ndarray | str | None = None) -> Residuals:
        """Step through a whole trace (what :meth:`ScheduledResidualGenerator.run` vectorises)."""
        g = self.generator
        rho = g.checked_schedule(trace, schedule)
        U, Y = trace.columns("u", g.controls), trace.columns("y", g.outputs)
        r = np.empty(len(trace))
        valid = np.empty(len(trace), bool)
        rec = np.empty(len(trace), bool)
        for k in range(len(trace)):
            r[k] = self.step(U[k], Y[k], rho[k])
            valid[k], rec[k] = self.last_valid, self.last_recovering
        meta = {"trace": dict(trace.meta), "schedule": schedule if isinstance(schedule, str) else g.schedule}
        return Residuals(trace.t, r[:, None], g.residuals, g.isolates, valid, meta=meta, recovering=rec)


def scheduled_parity_filter(
    family: Family,
    reference: float,
    targets: str | Sequence[str] | None = None,
    *,
    degree: int | None = None,
    poles: float | Sequence[float] = 0.9048,
    gamma: float | None = None,
    column: int = 0,
    schedule: str = "speed",
    name: str | None = None,
) -> ScheduledResidualGenerator:
    """Speed-scheduled parity filter (van der Ploeg 2018, Thm 3-3.4, (3.17), (4.18); Sec. 4-3-4).

    Parameters
    ----------
    family : callable ``ρ -> FaultModel``
        Discrete models with the fault input, e.g. :func:`fdikit.plants.single_track.single_track_lpv`.
    reference : float
        Design point ``ρ`` for the degree search and the checks (e.g. ``70 / 3.6`` m/s).
    targets : str, optional
        The fault to detect, by fault name (default: the model's only fault).
    degree : int, optional
        ``d_N``; default the minimal degree at ``reference``.
    poles : float or sequence of float
        Real poles of ``d(q)`` (default 0.9048, repeated ``d_N + d_L + 1`` times).
    gamma : float or None
        Lagrange multiplier of (3.17) (the thesis uses 1e7); None (default) is the exact
        ``γ → ∞`` projection.
    column : int
        ``j``, the column of ``F̄_k`` (coefficient of ``q^j``) that (3.16) maximises; default 0.
    schedule : str
        Name of the trace column holding ``ρ`` (default ``"speed"``).
    name : str, optional
        Residual name (default ``r_<fault>``).

    Returns
    -------
    ScheduledResidualGenerator, the scheduled filter (its own ``generator``; ``reference``: the LTI design).

    Raises
    ------
    ParameterError
        ``family`` not callable; several targets or a bare signal name.
    ModelError
        ``family(reference)`` not a discrete FaultModel.
    DesignError
        If the fault is not detectable at ``reference``, ``column`` is out of range or
        degenerate there, or there are fewer than ``d_N + d_L + 1`` poles.

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> gen = scheduled_parity_filter(single_track_lpv(), 70 / 3.6)
    >>> gen.degree, gen.window, gen.residuals
    (2, 3, ('r_steering_actuator',))

    References
    ----------
    van der Ploeg 2018, Thm 3-3.4, (3.17), (4.18)–(4.19); Sec. 4-3-4.
    """
    if not callable(family):
        raise ParameterError(
            f"family must be a callable ρ -> discrete FaultModel (e.g. plants.single_track.single_track_lpv()), "
            f"got {type(family).__name__}"
        )
    model = family(reference)
    if not isinstance(model, FaultModel) or not model.is_discrete:
        raise ModelError(f"family({reference}) must return a discrete FaultModel, got {model!r}")
    dae = dae_form(model)
    fault = target_fault(dae, targets, "scheduled_parity_filter")
    ref = parity_filter(dae_form(model, [fault]), fault, degree=degree, poles=poles, name=name)
    min_poles = ref.degree + len(dae.L)
    p = real_poles(poles, min_poles)
    if p.size < min_poles:
        raise DesignError(f"the scheduled filter needs at least d_N + d_L + 1 = {min_poles} poles, got {p.size}")
    n_cols = ref.degree + len(dae.F)
    if not 0 <= int(column) < n_cols:
        raise DesignError(f"column must index F̄ (0 … {n_cols - 1}), got {column}")
    fast = callable(getattr(family, "dae_matrices", None))
    if fast:
        mats = family.dae_matrices(reference)
        want = (*ref.dae.H, *ref.dae.L, *ref.dae.F)
        fast = len(mats) == len(want) and all(np.shape(a) == b.shape and np.allclose(a, b) for a, b in zip(mats, want))
    gen = ScheduledResidualGenerator(
        family=family, fault=fault, degree=ref.degree, poles=p, gamma=None if gamma is None else float(gamma),
        column=int(column), controls=model.controls, outputs=model.outputs, residuals=ref.generator.residuals,
        isolates=ref.generator.isolates, dt=float(model.dt), schedule=schedule, reference=ref, fast_path=fast,
    )
    Hb, _, Fb = gen.bar_matrices(np.full((1, ref.degree + 1), float(reference)))
    Fj = Fb[0, :, gen.column]
    if np.linalg.norm(lpv_parity_row(Hb[0], Fj)) <= 1e-8 * np.linalg.norm(Fj):
        raise DesignError(f"column j={column} of F̄ lies in the range of H̄ at the design point (P F̄_j = 0), so "
                          "(3.17) gives N̄ ≈ 0 (Sec. 4-3-4: the q² column); choose column=0")
    gen.rows(np.full((1, ref.degree + 1), float(reference)))  # e.g. a bad gamma fails now, not at run time
    return gen
