"""Residual generators: the implementation form ``r = Q(y, u)``, its online stepper and banks.

A :class:`ResidualGenerator` is an LTI filter in state-space form driven by the
controls ``u`` and the measurements ``y`` named in its ``controls`` and ``outputs``::

    z' = A z + B [u; y]        (z[k+1] in discrete time)
    r  = C z + D [u; y]

``run(trace)`` processes a whole :class:`~fdikit.trace.Trace` at once (a compiled,
vectorised recursion between gaps); ``online()`` returns a :class:`ResidualStepper` whose
``step(u, y)`` gives the same residuals one sample at a time.  Both follow one gap rule
for invalid (NaN/inf) samples: the filter is propagated with the model and the inputs
through the gap and the samples after it are marked *recovering* (not valid for
decisions) until the gap transient has decayed below the noise (:class:`ResidualStepper`
gives the rule; :mod:`fdikit.gaps` implements it and gives its derivation).
``internal_form(model)`` is Varga's internal form ``R``: the interconnection of the plant
model and the filter, from ``(u, d, f, w)`` to ``r``, so decoupling is a number, not a plot.
The series they return, :class:`~fdikit.residuals.series.Residuals`, is :mod:`fdikit.residuals.series`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.gaps import GapRule, Recovery, gap_options
from fdikit.model import GROUPS, FaultModel
from fdikit.operating_point import OperatingPoint
from fdikit.residuals.series import Residuals
from fdikit.trace import Trace, check_signals

__all__ = ["ResidualGenerator", "ResidualStepper"]


def _mat(name, value, shape):
    """A read-only filter matrix of ``shape`` (:func:`fdikit.validate.as_matrix`; empty means zeros)."""
    arr = (validate.as_matrix(f"residual generator {name}", value, shape, error=ModelError, promote=True)
           if np.size(value) else np.zeros(shape))
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class ResidualGenerator:
    """An LTI residual generator driven by named controls and measurements.

    Parameters
    ----------
    A, B, C, D : array_like
        Filter matrices; the columns of ``B`` and ``D`` are ``[u; y]`` in the order of
        ``controls`` then ``outputs``.
    controls, outputs : sequence of str
        Names of the plant signals the filter reads.
    residuals : sequence of str
        Names of the residuals (rows of ``C``).
    dt : float or None
        Sample time, or None for a continuous filter (``run`` then discretises it
        with a zero-order hold at the trace's sample time).
    isolates : sequence of (str or None), optional
        The fault each residual is tied to; None for a residual that only detects.
    operating_point : OperatingPoint, optional
        The absolute operating point of the model the filter was designed from
        (:class:`fdikit.operating_point.OperatingPoint`).  The filter reads deviations: ``run`` and
        ``online().step`` take ABSOLUTE signals and subtract ``u0`` / ``y0`` of the signals read.
        None (default) means the signals are deviations already.

    Raises
    ------
    ModelError
        If a matrix is not finite or its shape does not match the filter order, the signals and the
        residuals, ``isolates`` has the wrong length, ``dt`` is not positive or ``operating_point`` is
        not an OperatingPoint.

    Examples
    --------
    An observer of ``x[k+1] = 0.9 x[k] + u[k]``, ``y = x`` with gain 0.5 (``r = y − ẑ``); a sensor bias of 1
    from sample 3 on:

    >>> from fdikit.trace import Trace
    >>> g = ResidualGenerator(A=[[0.4]], B=[[1.0, 0.5]], C=[[-1.0]], D=[[0.0, 1.0]],
    ...                       controls=("u",), outputs=("y",), residuals=("r",), dt=1.0)
    >>> y = [0.0, 1.0, 1.9, 3.71, 4.439, 5.0951]
    >>> trace = Trace(np.arange(6.0), np.ones((6, 1)), np.c_[y], ("u",), ("y",))
    >>> np.round(g.run(trace).r[:, 0], 6).tolist()
    [0.0, 0.0, 0.0, 1.0, 0.5, 0.3]
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    residuals: tuple[str, ...]
    dt: float | None = None
    isolates: tuple[str | None, ...] = ()
    operating_point: OperatingPoint | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for attr in ("controls", "outputs", "residuals"):
            set_(self, attr, tuple(getattr(self, attr)))
        A = np.atleast_2d(np.asarray(self.A, dtype=float)) if np.size(self.A) else np.zeros((0, 0))
        n = A.shape[0]
        nv, q = len(self.controls) + len(self.outputs), len(self.residuals)
        set_(self, "A", _mat("A", A, (n, n)))
        set_(self, "B", _mat("B", self.B, (n, nv)))
        set_(self, "C", _mat("C", self.C, (q, n)))
        set_(self, "D", _mat("D", self.D, (q, nv)))
        iso = tuple(self.isolates) if self.isolates else (None,) * q
        if len(iso) != q:
            raise ModelError(f"{len(iso)} 'isolates' entries for {q} residuals")
        set_(self, "isolates", iso)
        if self.dt is not None and not self.dt > 0:
            raise ModelError(f"dt must be positive or None, got {self.dt}")
        op = self.operating_point
        if op is not None:
            if not isinstance(op, OperatingPoint):
                raise ModelError(f"operating_point must be a fdikit.operating_point.OperatingPoint, got "
                                 f"{type(op).__name__}")
            set_(self, "operating_point", op.restricted(self.controls, self.outputs))
        offset = np.zeros(nv) if op is None else np.concatenate(
            [op.control_values(self.controls), op.output_values(self.outputs)])
        offset.setflags(write=False)
        set_(self, "offset", offset)

    @property
    def signals(self) -> tuple[str, ...]:
        """The signals read, controls then outputs (the columns of ``B`` and ``D``)."""
        return self.controls + self.outputs

    @property
    def n(self) -> int:
        """Filter order."""
        return self.A.shape[0]

    def discretize(self, dt: float) -> ResidualGenerator:
        """ZOH-discretised copy of a continuous generator (inputs held between samples)."""
        import scipy.signal

        if self.dt is not None:
            raise ModelError(f"the generator is already discrete (dt={self.dt})")
        Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((self.A, self.B, self.C, self.D), dt, method="zoh")
        return ResidualGenerator(Ad, Bd, Cd, Dd, self.controls, self.outputs, self.residuals, dt, self.isolates,
                                 self.operating_point)

    def _check_dt(self, dt: float) -> None:
        if self.dt is not None and not np.isclose(dt, self.dt, rtol=1e-6):
            raise DataError(f"data sampled at dt={dt:g} but the generator is discrete with dt={self.dt:g}; resample")

    @staticmethod
    def check_uniform(trace: Trace) -> float:
        """The trace's sample time, after checking that its samples are uniformly spaced (to 0.1 % of ``dt``).

        A filter steps once per sample, so a gap in the time stamps (rows dropped from a log) would be stepped
        over as if no time had passed.  Import logs with :meth:`fdikit.trace.Trace.from_csv` /
        :meth:`~fdikit.trace.Trace.from_pandas`, which put invalid samples in the gaps.

        Raises :class:`DataError` naming the first irregular step.
        """
        dt = trace.dt
        steps = np.diff(trace.t)
        bad = np.flatnonzero(np.abs(steps - dt) > 1e-3 * dt)
        if bad.size:
            k = int(bad[0])
            raise DataError(
                f"the trace is not uniformly sampled: the step from t={trace.t[k]:g} to {trace.t[k + 1]:g} s is "
                f"{steps[k]:g} s, the sample time {dt:g} s ({bad.size} irregular steps); a filter would step over the "
                "gap as if no time had passed. Import the log with Trace.from_csv / Trace.from_pandas, which "
                "inserts invalid samples in the gaps")
        return dt

    def _for_dt(self, dt: float) -> ResidualGenerator:
        if self.dt is None:
            return self.discretize(dt)
        self._check_dt(dt)
        return self

    def check_trace(self, trace: Trace) -> None:
        """Raise :class:`DataError` unless ``trace`` holds every signal this generator reads, in its group.

        The message names the missing signals (and, for a signal found in the other group, where it is),
        and the signals of the trace that could have been meant.  Signals of the trace that the generator
        does not read are allowed (a generator of a bank reads a subset).
        """
        if not isinstance(trace, Trace):
            raise DataError(f"trace must be a fdikit.trace.Trace, got {type(trace).__name__}")
        check_signals(trace, self.controls, self.outputs)

    def inputs_from(self, trace: Trace) -> np.ndarray:
        """The (N, m + p) block ``[u − u0, y − y0]`` this generator reads, taken from a trace by name.

        The deviations from the generator's operating point (none: the trace's values); the rows of the
        samples the trace flags invalid (``trace.valid`` False: a gap, a bad status) are NaN.
        """
        return self.absolute_inputs(trace) - self.offset

    def absolute_inputs(self, trace: Trace) -> np.ndarray:
        """The (N, m + p) block ``[u, y]`` as the trace holds it, NaN on the samples it flags invalid."""
        self.check_trace(trace)
        v = np.hstack([trace.columns("u", self.controls), trace.columns("y", self.outputs)])
        v[~trace.valid] = np.nan
        return v

    def run(
        self, trace: Trace, x0: np.ndarray | None = None, *, residual_cov=None, recovery_tol: float = 0.1
    ) -> Residuals:
        """Residuals of a whole trace, vectorised between gaps; identical to ``online().run(trace)``.

        A sample with a NaN/inf in a signal the generator reads is *invalid*: its residuals are NaN
        and the filter is propagated through it by the gap rule of :class:`ResidualStepper` and
        :mod:`fdikit.gaps` (model prediction of the missing measurements, last value of a missing
        control).  The samples after a gap are *recovering* (finite residuals, ``valid`` False,
        ``recovering`` True) until the gap transient has decayed below ``recovery_tol`` noise
        standard deviations.  Stretches of valid samples are processed by the compiled recursion of
        :func:`fdikit.runtime.lti_batch.lsim`; only the invalid samples and the recovery bookkeeping are
        stepped one by one (by superposition: the response to the usable inputs and the response to
        the gap rule's state corrections are each one compiled pass over the whole trace).

        Parameters
        ----------
        trace : Trace
            Must hold the generator's controls and outputs (see :meth:`check_trace`) at the
            generator's ``dt``.
        x0 : array_like, optional
            Initial filter state (default zeros).
        residual_cov : array_like, optional
            Covariance (or only its shape: any positive multiple gives the same result) of the
            fault-free residuals, used to decide when a gap transient is "below the noise";
            default the identity (equal, uncorrelated residual noise).
        recovery_tol : float
            A recovering sample becomes valid when the standard deviation of the gap transient in
            every residual is at most ``recovery_tol`` times that residual's noise standard deviation.

        Raises
        ------
        DataError
            On missing signals or a sample time different from the generator's.
        ParameterError
            On a bad ``x0``, ``residual_cov`` or ``recovery_tol``.

        Returns
        -------
        Residuals
            Residuals at the trace's times, with ``valid`` / ``recovering`` flags and the trace's
            metadata under ``meta["trace"]``.
        """
        from fdikit.runtime.lti_batch import lsim, lsim_columns

        self.check_trace(trace)
        if len(trace) > 1:
            g = self._for_dt(self.check_uniform(trace))
        elif self.dt is None:
            raise DataError("a continuous generator needs a trace of at least 2 samples (its sample time)")
        else:
            g = self
        x0 = _state0(g, x0)
        meta = {"trace": dict(trace.meta)}
        # clean data (the usual case): one compiled pass reading the trace's columns in place
        r, _, _, bad = lsim_columns(g.A, g.B, g.C, g.D, trace.u, [trace.controls.index(c) for c in self.controls],
                                    trace.y, [trace.outputs.index(c) for c in self.outputs], self.offset,
                                    trace.valid, x0)
        if bad == len(trace):
            gap_options(g, residual_cov, recovery_tol)  # the options are checked alike on clean data
            return Residuals(trace.t, r, self.residuals, self.isolates, meta=meta)
        del r
        v = self.inputs_from(trace)
        ok_ch = np.isfinite(v)
        ok = ok_ch.all(axis=1)
        rule = GapRule(g, residual_cov, recovery_tol)
        N, n = v.shape[0], g.n
        # Superposition: x = X0 + c, X0 the response to the usable inputs (bad entries 0) from rest, c the
        # response to x0 and to the state corrections E the gap rule applies on invalid samples.  Only the
        # invalid samples (and the recovery bookkeeping) are stepped; both responses are one compiled pass.
        v0 = np.where(ok_ch, v, 0.0)
        r0, X0, _ = lsim(g.A, g.B, g.C, g.D, v0, states=True)
        E = np.zeros((N, n))
        valid = np.zeros(N, bool)
        recovering = np.zeros(N, bool)
        rec = Recovery(rule)
        last = np.zeros(v.shape[1])
        c, kc = x0.copy(), 0
        bad_idx = np.flatnonzero(~ok)
        starts = bad_idx[np.concatenate([[True], np.diff(bad_idx) > 1])]
        ends = bad_idx[np.concatenate([np.diff(bad_idx) > 1, [True]])] + 1
        prev = 0
        for a, b in zip(starts.tolist(), ends.tolist()):
            self._flags(rec, valid, recovering, prev, a)
            if a > prev:
                last = v[a - 1].copy()
            c = np.linalg.matrix_power(g.A, a - kc) @ c if n else c
            for k in range(a, b):
                x = X0[k] + c
                znew = rule.propagate(x, v[k], ok_ch[k], last)
                E[k] = znew - (g.A @ x + g.B @ v0[k])
                c = g.A @ c + E[k]
                last[ok_ch[k]] = v[k, ok_ch[k]]
                rec.invalid_sample(ok_ch[k])
            kc, prev = b, b
        self._flags(rec, valid, recovering, prev, N)
        rc, _, _ = lsim(g.A, np.eye(n), g.C, np.zeros((len(self.residuals), n)), E, x0)
        r = r0 + rc
        r[~ok] = np.nan
        return Residuals(trace.t, r, self.residuals, self.isolates, valid, meta=meta, recovering=recovering)

    @staticmethod
    def _flags(rec: Recovery, valid: np.ndarray, recovering: np.ndarray, start: int, stop: int) -> None:
        """Flags of the valid samples ``start … stop − 1`` (recovering while the gap transient lasts)."""
        i = start
        while i < stop and rec.active:
            valid[i] = rec.valid_sample()
            recovering[i] = not valid[i]
            i += 1
        valid[i:stop] = True

    def online(
        self, x0: np.ndarray | None = None, dt: float | None = None, *, residual_cov=None, recovery_tol: float = 0.1
    ) -> ResidualStepper:
        """A stepper for sample-by-sample use (same gap rule and options as :meth:`run`).

        A continuous generator needs ``dt`` (it is then ZOH-discretised); a discrete one accepts
        only its own ``dt``.

        Raises :class:`ModelError` for a continuous generator without ``dt``, :class:`ParameterError`
        for a ``dt`` that is not a positive number (or a bad ``x0``, ``residual_cov``, ``recovery_tol``)
        and :class:`DataError` for a ``dt`` other than a discrete generator's own.
        """
        if self.dt is None and dt is None:
            raise ModelError("a continuous residual generator needs dt= to run online")
        number = isinstance(dt, (int, float, np.floating, np.integer)) and not isinstance(dt, bool)
        if dt is not None and not (number and np.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt must be a positive number of seconds, got {dt!r}")
        g = self if dt is None else self._for_dt(float(dt))
        return ResidualStepper(g, x0, residual_cov=residual_cov, recovery_tol=recovery_tol)

    def internal_form(self, model: FaultModel) -> FaultModel:
        """The plant model and this filter in series: a FaultModel from ``(u, d, f, w)`` to ``r``.

        For a continuous model and a discrete generator the model is first ZOH-discretised
        at the generator's ``dt``.  The states are the plant's followed by the filter's.

        Raises :class:`ModelError` if a continuous generator meets a discrete model, the sample times
        differ, or the model lacks a signal the generator reads.
        """
        if model.is_discrete and self.dt is None:
            raise ModelError("a continuous generator cannot be joined with a discrete model; discretize the generator")
        if self.dt is not None:
            if model.is_discrete and not np.isclose(model.dt, self.dt):
                raise ModelError(f"model dt={model.dt} differs from generator dt={self.dt}")
            if not model.is_discrete:
                model = model.discretize(self.dt)
        iu = model.index("u", self.controls)
        iy = model.index("outputs", self.outputs)
        nv = model.B.shape[1]
        Su = np.zeros((len(iu), nv))
        Su[range(len(iu)), iu] = 1.0
        mu = len(self.controls)
        Bu_f, By_f = self.B[:, :mu], self.B[:, mu:]
        Du_f, Dy_f = self.D[:, :mu], self.D[:, mu:]
        Cy, Dy = model.C[iy], model.D[iy]
        n, nf = model.n, self.n
        A = np.block([[model.A, np.zeros((n, nf))], [By_f @ Cy, self.A]])
        B = np.vstack([model.B, Bu_f @ Su + By_f @ Dy])
        C = np.hstack([Dy_f @ Cy, self.C])
        D = Du_f @ Su + Dy_f @ Dy
        kw: dict = {}
        start = 0
        for g in GROUPS:
            k = len(model.inputs[g])
            kw[f"B{g}"], kw[f"D{g}"] = B[:, start : start + k], D[:, start : start + k]
            start += k
        return FaultModel(
            A, C, states=model.states + tuple(f"filter_{i}" for i in range(nf)), outputs=self.residuals,
            controls=model.controls, disturbances=model.disturbances, faults=model.faults, noise=model.noise,
            dt=model.dt, **kw,
        )

    def to_control(self):
        """The filter as a :class:`control.StateSpace` with inputs ``[u; y]`` and outputs ``r``."""
        import control

        return control.ss(self.A, self.B, self.C, self.D, 0 if self.dt is None else self.dt,
                          inputs=list(self.controls) + list(self.outputs), outputs=list(self.residuals))


def _state0(g: ResidualGenerator, x0) -> np.ndarray:
    if x0 is None:
        return np.zeros(g.n)
    try:
        x = np.asarray(x0, dtype=float).ravel()
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"x0 must be {g.n} numbers (the filter state), got {x0!r}") from exc
    if x.size != g.n:
        raise ParameterError(f"x0 has {x.size} entries, the filter has {g.n} states")
    if not np.all(np.isfinite(x)):
        raise ParameterError("x0 has non-finite entries; the initial filter state must be finite")
    return x.copy()


class ResidualStepper:
    """Online residual generation, one sample at a time, through gaps of invalid samples.

    ``step(u, y)`` returns the residual vector of the current sample.  The gap rule (the same
    in :meth:`ResidualGenerator.run`, which gives the same residuals and flags; implemented and
    derived in :mod:`fdikit.gaps`):

    * **invalid sample** (a NaN/inf in a signal the generator reads): the residuals are NaN,
      ``last_valid`` is False, ``invalid`` counts it, and the filter is propagated with the model
      and the inputs: each independent part of the filter (one per filter of a stacked bank) is
      fed, for the missing outputs, the values that make its residuals zero (least squares) — for
      an observer ``r = y − ŷ`` this is its own prediction ``ŷ``, i.e. open-loop propagation of
      the model, channel by channel when only some outputs are missing.  Directions of a missing
      output that the residual does not read directly (a strictly proper filter, a zero
      feedthrough) are fed the last valid value, and so is a missing control.
    * **recovering sample** (finite, after a gap): the residuals are computed as usual but
      ``last_valid`` is False and ``last_recovering`` True, until the transient the gap left in
      the filter has decayed below the noise: the covariance ``P`` of the state deviation is
      propagated through the gap from ``residual_cov`` (``P+ = T P Tᵀ + G Σ Gᵀ`` per invalid
      sample, ``P+ = A P Aᵀ`` per valid one) and the sample becomes valid when every residual's
      transient standard deviation ``sqrt((C P Cᵀ)_ii)`` is at most ``recovery_tol · sqrt(Σ_ii)``.
      The length therefore grows with the gap (slowly: as ``log`` of the open-loop error growth)
      and shrinks with the filter's spectral radius ``ρ(A)``; parts fed held values recover for
      at least ``ceil(log(recovery_tol) / log ρ(A))`` samples.  A filter with ``ρ(A) ≥ 1`` and
      held values never recovers (every later sample stays recovering).
    * **valid sample**: ``last_valid`` True; evaluators use it (pass ``valid=stepper.last_valid``
      to their ``step``).

    ``step`` accepts the values as sequences in the generator's ``controls``/``outputs`` order,
    or as mappings ``{name: value}`` which are checked against those names; they are absolute
    signals when the generator carries an operating point (its ``u0``, ``y0`` are subtracted).

    Parameters
    ----------
    generator : ResidualGenerator
        A discrete generator (:meth:`ResidualGenerator.online` discretises a continuous one).
    x0 : array_like, optional
        Initial filter state (default zeros).
    residual_cov, recovery_tol
        The recovery rule's options, as in :meth:`ResidualGenerator.run`.

    Attributes
    ----------
    x : numpy.ndarray
        Current filter state.
    last_valid, last_recovering : bool
        Flags of the last sample stepped.
    invalid : int
        Number of invalid samples since creation or :meth:`reset`.
    last_inputs : numpy.ndarray
        The last valid value of every input ``[u − u0; y − y0]`` (what the gap rule holds through a dropout).

    Raises
    ------
    ParameterError
        On a bad ``x0``, ``residual_cov`` or ``recovery_tol``.

    Examples
    --------
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> s = g.online()
    >>> s.step({"u": 1.0}, {"y": float("nan")}), s.last_valid, s.invalid
    (array([nan]), False, 1)
    """

    def __init__(self, generator: ResidualGenerator, x0: np.ndarray | None = None, *,
                 residual_cov=None, recovery_tol: float = 0.1) -> None:
        g = generator
        self.generator = g
        self._rule = GapRule(g, residual_cov, recovery_tol)
        self._x0 = _state0(g, x0)
        self._AB = np.hstack([g.A, g.B])
        self._CD = np.hstack([g.C, g.D])
        self.reset()

    def reset(self, x0: np.ndarray | None = None) -> None:
        """Start again: the initial state (``x0``, else the one given at creation), no gap history."""
        self.x = self._x0.copy() if x0 is None else _state0(self.generator, x0)
        self.invalid = 0
        self.last_valid = True
        self.last_recovering = False
        self.last_inputs = np.zeros(self._AB.shape[1] - self.generator.n)
        self._rec = Recovery(self._rule)

    def _vector(self, values, names: tuple[str, ...], what: str) -> np.ndarray:
        if values is None or isinstance(values, (str, bytes)):
            raise DataError(f"step() {what} must be {len(names)} numbers {list(names)} (NaN marks a missing value), "
                            f"got {values!r}")
        if isinstance(values, Mapping):
            keys = list(values)
            missing = [nm for nm in names if nm not in values]
            extra = [k for k in keys if k not in names]
            if missing or extra:
                raise DataError(f"step() {what} do not match the generator's {list(names)}: missing {missing}, "
                                f"extra {extra}")
            values = [values[nm] for nm in names]
        try:
            arr = np.asarray(values, dtype=float).ravel()
        except (TypeError, ValueError) as exc:
            raise DataError(f"step() {what} must be numbers (NaN marks a missing value), got {values!r}") from exc
        return arr

    def step(self, u, y) -> np.ndarray:
        """Residuals for one sample.

        Parameters
        ----------
        u, y : sequence of float or mapping of name to float
            The controls and outputs, in the generator's ``controls``/``outputs`` order, or by name.

        Returns
        -------
        numpy.ndarray
            (q,) residuals: NaN on an invalid sample; see the class docstring for ``last_valid``.

        Raises
        ------
        DataError
            If ``u`` or ``y`` is None, a string, not numbers, a mapping with other names, or the wrong
            number of values.
        """
        g = self.generator
        v = np.concatenate([self._vector(u, g.controls, "controls"), self._vector(y, g.outputs, "outputs")])
        if v.size != g.B.shape[1]:
            raise DataError(
                f"step() got {v.size} values; need {len(g.controls)} controls {list(g.controls)} "
                f"and {len(g.outputs)} outputs {list(g.outputs)}"
            )
        v = v - g.offset
        ok_ch = np.isfinite(v)
        if not ok_ch.all():
            self.invalid += 1
            self.last_valid = False
            self.last_recovering = False
            self.x = self._rule.propagate(self.x, v, ok_ch, self.last_inputs)
            self.last_inputs[ok_ch] = v[ok_ch]
            self._rec.invalid_sample(ok_ch)
            return np.full(len(g.residuals), np.nan)
        xv = np.concatenate([self.x, v])
        r = self._CD @ xv
        self.x = self._AB @ xv
        self.last_inputs = v.copy()
        self.last_valid = self._rec.valid_sample() if self._rec.active else True
        self.last_recovering = not self.last_valid
        return r

    def run(self, trace: Trace) -> Residuals:
        """Step through a whole trace (the loop ``run()`` vectorises); flags as in :meth:`step`."""
        g = self.generator
        if not isinstance(trace, Trace):
            raise DataError(f"trace must be a fdikit.trace.Trace, got {type(trace).__name__}")
        if len(trace) > 1:
            g._check_dt(g.check_uniform(trace))
        v = g.absolute_inputs(trace)
        mu = len(g.controls)
        r = np.empty((len(trace), len(g.residuals)))
        valid = np.empty(len(trace), bool)
        recovering = np.empty(len(trace), bool)
        for k in range(len(trace)):
            r[k] = self.step(v[k, :mu], v[k, mu:])
            valid[k] = self.last_valid
            recovering[k] = self.last_recovering
        return Residuals(trace.t, r, g.residuals, g.isolates, valid, meta={"trace": dict(trace.meta)},
                         recovering=recovering)
