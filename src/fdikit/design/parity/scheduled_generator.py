"""Runtime of the speed-scheduled parity filter: the scheduled residual generator and its online stepper (van der
Ploeg 2018, Thm 3-3.4, Cor. 3-3.5; Sec. 4-3-4).

:class:`ScheduledResidualGenerator` (built by :func:`~fdikit.design.parity.scheduled.scheduled_parity_filter`)
rebuilds at every step ``k`` the bar matrices of its window of parameter values, takes the parity row
:func:`~fdikit.design.parity.scheduled_window.lpv_parity_row`, scales it so that ``Σ N̄_k F̄_k = −d(1)``
((4.18)–(4.19)) and runs the input-output form of Corollary 3-3.5::

    d(q) r = w,   w(k) = N̄_k L̄_k [z(τ_0); …; z(τ_{d_N + d_L})],   τ_i = k − deg d + i

with ``d(q)`` a cascade of first-order sections.  :meth:`ScheduledResidualGenerator.run` is vectorised;
:class:`ScheduledStepper` steps one sample at a time; both give the same residuals and follow the same
gap rule (a sample with a NaN/inf gives a NaN residual, a window holding one gives ``w = 0``).

The schedule is a measured signal: :meth:`ScheduledResidualGenerator.run` reads it from the
trace by name (an output or control column, default ``"speed"``) or takes an array;
:func:`fdikit.simulate.simulate_scheduled` appends it to the trace as an output column.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from fdikit.dae import DAEModel, dae_form
from fdikit.design.parity.polynomial import PolynomialParityDesign
from fdikit.design.parity.scheduled_window import lpv_parity_row
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import no_internal_form
from fdikit.residuals import Residuals
from fdikit.trace import Trace, check_signals

__all__ = [
    "ScheduledResidualGenerator",
    "ScheduledStepper",
]

Family = Callable[[float], FaultModel]


@dataclass(frozen=True, eq=False)
class ScheduledResidualGenerator:
    """A parity filter whose row ``N̄_k`` follows a measured schedule ``ρ`` (Thm 3-3.4, Cor. 3-3.5).

    Build it with :func:`~fdikit.design.parity.scheduled.scheduled_parity_filter`.  ``run(trace)`` is vectorised;
    ``online()`` gives a :class:`ScheduledStepper` with ``step(u, y, rho)``; both give the same residuals.

    Attributes
    ----------
    family : ``ρ -> FaultModel`` (discrete, same names and ``dt`` for every ``ρ``).
    fault, degree, poles, gamma, column : design choices (``gamma=None`` is the exact projection).
    controls, outputs, residuals, isolates, dt : as :class:`~fdikit.residuals.ResidualGenerator`.
    schedule : name of the trace column holding ``ρ``.
    reference : the LTI :class:`~fdikit.design.parity.polynomial.PolynomialParityDesign` at the design point.
    fast_path : whether the family's ``dae_matrices`` is used (see :meth:`dae`).
    grid : spacing ``h`` of the ``ρ`` grid (nodes ``ρ_ref + i h``) on which the family is evaluated, the DAE
        coefficients linear in ``ρ`` between nodes (error ≤ ``h²/8 · max‖∂²M/∂ρ²‖``); None (default): the family
        at every distinct ``ρ`` (exact; one ``family(ρ)`` per sample for a measured, noisy ``ρ``).
    design_point : the ``ρ`` of the design (``reference``), a node of ``grid``.

    Examples
    --------
    >>> from fdikit.design.parity.scheduled import scheduled_parity_filter
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
    grid: float | None = None
    design_point: float = 0.0
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def window(self) -> int:
        """Number of past samples the filter reads (``deg d``)."""
        return self.poles.size

    def _coefficients(self, rho: float) -> tuple[tuple[np.ndarray, ...], ...]:
        """``(H, L, F)`` coefficient tuples at ``rho`` (``F``: the fault column): exact, or interpolated on ``grid``."""
        if self.grid is None:
            return self._exact(rho)
        stacks = self._stacks(np.array([float(rho)]))
        return tuple(tuple(S[0, j] for j in range(S.shape[1])) for S in stacks)

    def _stacks(self, vals: np.ndarray) -> list[np.ndarray]:
        """``H``, ``L``, ``F`` coefficient stacks ``(values, degree + 1, rows, cols)`` at the values ``vals``.

        With ``grid = h``: node ``i = ⌊(ρ − ρ_ref)/h⌋``, ``θ = (ρ − ρ_ref)/h − i``, ``M = (1 − θ) M_i + θ M_{i+1}``
        (exactly ``M_i`` on a node, so the design point and constant schedules on a node are exact).
        """
        if self.grid is None:
            coeffs = [self._exact(v) for v in vals]
            return [np.stack([np.stack(c[part]) for c in coeffs]) for part in range(3)]
        ref, h = float(self.design_point), float(self.grid)
        u = (vals - ref) / h
        i = np.floor(u)
        theta = (u - i)[:, None, None, None]
        nodes, inv = np.unique(i, return_inverse=True)
        lo = [self._exact(ref + n * h) for n in nodes]
        hi = [self._exact(ref + (n + 1) * h) for n in nodes]
        out = []
        for part in range(3):
            a = np.stack([np.stack(c[part]) for c in lo])[inv]
            b = np.stack([np.stack(c[part]) for c in hi])[inv]
            out.append(np.where(theta == 0.0, a, (1.0 - theta) * a + theta * b))
        return out

    def _exact(self, rho: float) -> tuple[tuple[np.ndarray, ...], ...]:
        """``(H, L, F)`` of ``family(rho)`` (through ``dae_matrices`` on the fast path), cached per value."""
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
        (``fast_path``); otherwise ``dae_form(family(rho), [fault])``.  Values are cached.  With ``grid`` set,
        the coefficients are interpolated between the grid nodes (what the filter runs on).
        """
        H, L, F = self._coefficients(rho)
        ref = self.reference.dae
        return DAEModel(H, L, F, ref.unknowns, ref.outputs, ref.controls, (self.fault,), ref.dt)

    def bar_matrices(self, windows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stacks of ``(H̄_k, L̄_k, F̄_k)`` (Lemma 3-3.2), one per row of ``windows`` (``d_N + 1`` values, oldest first).

        The same matrices as :func:`~fdikit.design.parity.scheduled_window.lpv_bar_matrices` on
        ``[dae(ρ) for ρ in window]``, assembled for many windows at once.
        """
        windows = np.atleast_2d(np.asarray(windows, dtype=float))
        vals, idx = np.unique(windows, return_inverse=True)
        idx = idx.reshape(windows.shape)
        out = []
        for C in self._stacks(vals):  # (values, degree + 1, rows, cols)
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

    def run(self, trace: Trace, schedule: np.ndarray | str | None = None, *, recovery_tol: float = 0.1,
            smoothing: float | None = None, smoothing_kind: str = "ramp") -> Residuals:
        """Residuals of a whole trace; ``schedule`` is an array (N,), a column name, or None (``self.schedule``).

        Vectorised, and identical to :meth:`online` stepping (same residuals to rounding, same flags).

        ``smoothing`` (time constant ``τ`` in s; default None, no smoothing) smooths a *measured* schedule
        causally before it schedules the filter, so ``online`` gives the same result:
        ``smoothing_kind="ramp"`` (default) is Brown's double exponential smoothing (``s₁ ← a s₁ + (1 − a) ρ``,
        ``s₂ ← a s₂ + (1 − a) s₁``, output ``2 s₁ − s₂``, ``a = e^{−dt/τ}``): no steady lag while the speed
        ramps; ``"lowpass"`` is the first-order low-pass ``s(k) = a s(k−1) + (1 − a) ρ(k)`` (white noise
        variance × ``(1 − a)/(1 + a) ≈ dt/(2τ)``, but a lag ``τ ρ'`` that the residual sees as a speed error).
        Smoothing is off by default: an exact schedule needs none, and the filter's own ``d(q)`` already
        averages white speed noise (benchmarks/bench_scheduled.py: 0.05–0.1 m/s noise raised the residual rms
        by 5–15 % at realistic output noise; a 1 s low-pass made it 9× worse on a 0.65 m/s² speed change, the
        ramp kind with τ ≤ 0.3 s did not); see docs/methods/lateral_fault_isolation.md.

        Gap rule (a sample is *invalid* when a used signal or the schedule is NaN/inf): its residual
        is NaN.  The parity value ``w(k) = N̄_k L̄_k [z(τ_0) … z(τ_{d_N+d_L})]`` is formed only when
        every sample of its window is valid; otherwise ``w(k) = 0``, its fault-free prediction (the
        parity relation is zero without fault and noise), so the ``d(q)`` filter is propagated
        through the gap.  The samples after a gap are *recovering* (finite residual, ``valid``
        False) until :meth:`recovery_length` samples after the last zero-filled ``w``.  At the
        start of a run that begins with a valid sample the window is padded with zeros as before
        (the start-up transient is not flagged).
        """
        rho = _Smoother(smoothing, smoothing_kind, self.dt).run(self.checked_schedule(trace, schedule))
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
        meta = {"trace": dict(trace.meta), "schedule": schedule if isinstance(schedule, str) else self.schedule,
                "smoothing": smoothing, "smoothing_kind": smoothing_kind}
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

    def online(self, *, recovery_tol: float = 0.1, smoothing: float | None = None,
               smoothing_kind: str = "ramp") -> ScheduledStepper:
        """A stepper with zero initial history (like ``run``), the same gap rule and schedule smoothing."""
        return ScheduledStepper(self, recovery_tol=recovery_tol, smoothing=smoothing, smoothing_kind=smoothing_kind)

    @property
    def generator(self) -> ScheduledResidualGenerator:
        """The scheduled filter itself (what :func:`~fdikit.design.parity.scheduled.scheduled_parity_filter` returns is
        its own generator)."""
        return self

    def internal_form(self):
        """Not available: raises :class:`~fdikit.errors.DesignError` (the parity row follows ρ).

        ``reference.internal_form()`` gives the LTI internal form at the design point.
        """
        no_internal_form(self, "the parity row follows the measured schedule rho, so plant and filter in series "
                               "are not an LTI FaultModel; reference.internal_form() gives it at the design point")

    def report(self) -> dict:
        """``fault``, ``degree``, ``poles``, ``gamma`` (None: exact projection), ``column``, ``schedule`` (the trace
        column of ρ), ``window`` (past samples read), ``grid`` (None: exact per value) and ``reference`` (the
        design-point report)."""
        return {"fault": self.fault, "degree": self.degree, "poles": self.poles, "gamma": self.gamma,
                "column": self.column, "schedule": self.schedule, "window": self.window, "grid": self.grid,
                "reference": self.reference.report()}


SMOOTHING_KINDS = ("lowpass", "ramp")


class _Smoother:
    """Causal smoothing of the schedule, one sample at a time (the same arithmetic in ``run`` and ``online``).

    ``lowpass``: ``s(k) = a s(k−1) + (1 − a) ρ(k)``, ``a = exp(−dt/τ)`` (lag ``τ ρ'`` on a ramp).
    ``ramp``: Brown's double exponential smoothing, ``s₁ ← a s₁ + (1 − a) ρ``, ``s₂ ← a s₂ + (1 − a) s₁``,
    output ``2 s₁ − s₂`` (no steady lag on a ramp, ~1.7× the low-pass noise for the same ``τ``).
    State starts at the first finite ``ρ``; a NaN/inf sample is passed through (NaN) and leaves the state.
    """

    def __init__(self, tau: float | None, kind: str, dt: float) -> None:
        if tau is not None:
            if isinstance(tau, bool) or not isinstance(tau, (int, float, np.integer, np.floating)) or not (
                    np.isfinite(tau) and tau > 0):
                raise ParameterError(f"smoothing must be a positive time constant in s (or None: no smoothing), "
                                     f"got {tau!r}")
        if kind not in SMOOTHING_KINDS:
            raise ParameterError(f"smoothing_kind must be one of {list(SMOOTHING_KINDS)}, got {kind!r}")
        self.tau, self.kind = tau, kind
        self.a = 0.0 if tau is None else float(np.exp(-dt / float(tau)))
        self.s1 = self.s2 = None

    def __call__(self, rho: float) -> float:
        if self.tau is None or not np.isfinite(rho):
            return rho
        a = self.a
        if self.s1 is None:
            self.s1 = self.s2 = rho
        else:
            self.s1 = a * self.s1 + (1.0 - a) * rho
            self.s2 = a * self.s2 + (1.0 - a) * self.s1
        return self.s1 if self.kind == "lowpass" else 2.0 * self.s1 - self.s2

    def run(self, rho: np.ndarray) -> np.ndarray:
        if self.tau is None:
            return rho
        return np.array([self(float(v)) for v in rho])


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
    smoothing, smoothing_kind : the causal smoothing of ``rho`` (see :meth:`ScheduledResidualGenerator.run`).

    Raises
    ------
    ParameterError
        A bad ``recovery_tol``, ``smoothing`` or ``smoothing_kind``.

    Examples
    --------
    >>> from fdikit.design.parity.scheduled import scheduled_parity_filter
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> st = scheduled_parity_filter(single_track_lpv(), 70 / 3.6).online()
    >>> float(st.step([0.0], [0.0, 0.0, 0.0], 19.0)), st.step([float("nan")], [0.0, 0.0, 0.0], 19.0), st.invalid
    (0.0, nan, 1)

    References
    ----------
    van der Ploeg 2018, Cor. 3-3.5.
    """

    def __init__(self, generator: ScheduledResidualGenerator, *, recovery_tol: float = 0.1,
                 smoothing: float | None = None, smoothing_kind: str = "ramp") -> None:
        self.generator = generator
        self._n_dec = generator.recovery_length(recovery_tol)
        self._smoothing = (smoothing, smoothing_kind)
        _Smoother(smoothing, smoothing_kind, generator.dt)  # check the arguments now
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
        self._smoother = _Smoother(*self._smoothing, g.dt)
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
        rho = self._smoother(rho)
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
        meta = {"trace": dict(trace.meta), "schedule": schedule if isinstance(schedule, str) else g.schedule,
                "smoothing": self._smoothing[0], "smoothing_kind": self._smoothing[1]}
        return Residuals(trace.t, r[:, None], g.residuals, g.isolates, valid, meta=meta, recovering=rec)
