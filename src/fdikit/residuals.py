"""Residual generators (the implementation form ``r = Q(y, u)``) and residual time series.

A :class:`ResidualGenerator` is an LTI filter in state-space form driven by the
controls ``u`` and the measurements ``y`` named in its ``controls`` and ``outputs``::

    z' = A z + B [u; y]        (z[k+1] in discrete time)
    r  = C z + D [u; y]

``run(trace)`` processes a whole :class:`~fdikit.trace.Trace` at once (a blocked,
vectorised recursion); ``online()`` returns a :class:`ResidualStepper` whose
``step(u, y)`` gives the same residuals one sample at a time and survives bad
samples.  ``internal_form(model)`` is Varga's internal form ``R``: the
interconnection of the plant model and the filter, from ``(u, d, f, w)`` to ``r``,
so decoupling is a number, not a plot.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from fdikit.errors import DataError, ModelError
from fdikit.lti import dlsim_blocked
from fdikit.model import GROUPS, FaultModel
from fdikit.trace import Trace

__all__ = ["ResidualGenerator", "ResidualStepper", "Residuals", "stack_generators"]


@dataclass(frozen=True, eq=False)
class Residuals:
    """Residual time series.

    Attributes
    ----------
    t : (N,) times; r : (N, q) residuals (NaN on invalid samples); names : residual names;
    isolates : per residual, the fault it is tied to (None = detection only);
    valid : (N,) bool, False where the input sample was bad and the filter held its state.
    """

    t: np.ndarray
    r: np.ndarray
    names: tuple[str, ...]
    isolates: tuple[str | None, ...]
    valid: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        r = np.atleast_2d(np.asarray(self.r, dtype=float))
        t = np.asarray(self.t, dtype=float).ravel()
        if r.shape != (t.size, len(self.names)):
            raise DataError(f"residuals have shape {r.shape}, need ({t.size}, {len(self.names)})")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "r", r)
        object.__setattr__(self, "names", tuple(self.names))
        isolates = tuple(self.isolates) if self.isolates else (None,) * len(self.names)
        if len(isolates) != len(self.names):
            raise DataError(f"{len(isolates)} 'isolates' entries for {len(self.names)} residuals")
        object.__setattr__(self, "isolates", isolates)
        valid = np.ones(t.size, bool) if self.valid is None else np.asarray(self.valid, bool)
        object.__setattr__(self, "valid", valid)

    def __len__(self) -> int:
        return self.t.size

    def slice(self, start: float | None = None, stop: float | None = None) -> Residuals:
        """The samples with ``start <= t < stop``."""
        mask = np.ones(self.t.size, bool)
        if start is not None:
            mask &= self.t >= start
        if stop is not None:
            mask &= self.t < stop
        return Residuals(self.t[mask], self.r[mask], self.names, self.isolates, self.valid[mask], dict(self.meta))

    def to_pandas(self):
        import pandas as pd

        df = pd.DataFrame(self.r, columns=list(self.names), index=pd.Index(self.t, name="t"))
        df["valid"] = self.valid
        return df


def _mat(name, value, shape):
    arr = np.atleast_2d(np.asarray(value, dtype=float)) if np.size(value) else np.zeros(shape)
    if arr.shape != shape:
        raise ModelError(f"residual generator {name} has shape {arr.shape}, need {shape}")
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"residual generator {name} has non-finite entries")
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
        return ResidualGenerator(Ad, Bd, Cd, Dd, self.controls, self.outputs, self.residuals, dt, self.isolates)

    def _check_dt(self, dt: float) -> None:
        if self.dt is not None and not np.isclose(dt, self.dt, rtol=1e-6):
            raise DataError(f"data sampled at dt={dt:g} but the generator is discrete with dt={self.dt:g}; resample")

    def _for_dt(self, dt: float) -> ResidualGenerator:
        if self.dt is None:
            return self.discretize(dt)
        self._check_dt(dt)
        return self

    def inputs_from(self, trace: Trace) -> np.ndarray:
        """The (N, m + p) block ``[u, y]`` this generator reads, taken from a trace by name."""
        return np.hstack([trace.columns("u", self.controls), trace.columns("y", self.outputs)])

    def run(self, trace: Trace, x0: np.ndarray | None = None) -> Residuals:
        """Residuals of a whole trace (vectorised).  NaN/inf in the used signals raise :class:`DataError`."""
        v = self.inputs_from(trace)
        bad = np.argwhere(~np.isfinite(v))
        if bad.size:
            k, j = bad[0]
            name = (self.controls + self.outputs)[j]
            raise DataError(
                f"signal {name!r} is not finite at sample {k} (t={trace.t[k]:g}); run() needs clean data — "
                "clean the trace, or use online().step(), which skips bad samples"
            )
        g = self._for_dt(trace.dt)
        r, _, _ = dlsim_blocked(g.A, g.B, g.C, g.D, v, x0)
        return Residuals(trace.t, r, self.residuals, self.isolates, meta={"trace": dict(trace.meta)})

    def online(self, x0: np.ndarray | None = None, dt: float | None = None) -> ResidualStepper:
        """A stepper for sample-by-sample use; a continuous generator needs ``dt``."""
        if self.dt is None and dt is None:
            raise ModelError("a continuous residual generator needs dt= to run online")
        return ResidualStepper(self if dt is None else self._for_dt(dt), x0)

    def internal_form(self, model: FaultModel) -> FaultModel:
        """The plant model and this filter in series: a FaultModel from ``(u, d, f, w)`` to ``r``.

        For a continuous model and a discrete generator the model is first ZOH-discretised
        at the generator's ``dt``.  The states are the plant's followed by the filter's.
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


class ResidualStepper:
    """Online residual generation, one sample at a time.

    ``step(u, y)`` returns the residual vector of the current sample.  A sample with a
    NaN/inf in the used signals gives NaN residuals, is counted in ``invalid`` and leaves
    the filter state unchanged (the filter holds its state through the gap).
    """

    def __init__(self, generator: ResidualGenerator, x0: np.ndarray | None = None) -> None:
        g = generator
        self.generator = g
        self.x = np.zeros(g.n) if x0 is None else np.asarray(x0, dtype=float).copy()
        self.invalid = 0
        self.last_valid = True
        self._AB = np.hstack([g.A, g.B])
        self._CD = np.hstack([g.C, g.D])

    def step(self, u: Sequence[float], y: Sequence[float]) -> np.ndarray:
        """Residuals for one sample; ``u`` and ``y`` in the generator's ``controls``/``outputs`` order."""
        g = self.generator
        v = np.concatenate([np.asarray(u, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()])
        if v.size != g.B.shape[1]:
            raise DataError(
                f"step() got {v.size} values; need {len(g.controls)} controls {list(g.controls)} "
                f"and {len(g.outputs)} outputs {list(g.outputs)}"
            )
        if not np.all(np.isfinite(v)):
            self.invalid += 1
            self.last_valid = False
            return np.full(len(g.residuals), np.nan)
        self.last_valid = True
        xv = np.concatenate([self.x, v])
        r = self._CD @ xv
        self.x = self._AB @ xv
        return r

    def run(self, trace: Trace) -> Residuals:
        """Step through a whole trace (the loop ``run()`` vectorises); bad samples become invalid."""
        if len(trace) > 1:
            self.generator._check_dt(trace.dt)
        v = self.generator.inputs_from(trace)
        mu = len(self.generator.controls)
        r = np.empty((len(trace), len(self.generator.residuals)))
        valid = np.empty(len(trace), bool)
        for k in range(len(trace)):
            r[k] = self.step(v[k, :mu], v[k, mu:])
            valid[k] = self.last_valid
        g = self.generator
        return Residuals(trace.t, r, g.residuals, g.isolates, valid, meta={"trace": dict(trace.meta)})


def stack_generators(generators: Iterable[ResidualGenerator]) -> ResidualGenerator:
    """One generator from several: block-diagonal filter states, concatenated residuals.

    Every generator must read the same controls and outputs in the same order and share
    ``dt``; residual names must be unique across them.

    Raises
    ------
    ModelError
        On an empty list, different signals, different ``dt`` or a repeated residual name.
    """
    gens = list(generators)
    if not gens:
        raise ModelError("stack_generators needs at least one generator")
    for i, g in enumerate(gens):
        if not isinstance(g, ResidualGenerator):
            raise ModelError(f"item {i} is a {type(g).__name__}, not a ResidualGenerator (use design.generator)")
    g0 = gens[0]
    for i, g in enumerate(gens[1:], start=1):
        if g.controls != g0.controls or g.outputs != g0.outputs:
            raise ModelError(
                f"generator {i} reads controls {list(g.controls)} and outputs {list(g.outputs)}, generator 0 reads "
                f"{list(g0.controls)} and {list(g0.outputs)}; stacked generators must read the same signals in "
                "the same order"
            )
        if g.dt != g0.dt:
            raise ModelError(f"generator {i} has dt={g.dt}, generator 0 dt={g0.dt}; discretize them alike first")
    names = [nm for g in gens for nm in g.residuals]
    dup = sorted({nm for nm in names if names.count(nm) > 1})
    if dup:
        raise ModelError(f"residual names {dup} occur in more than one generator; names must be unique")
    return ResidualGenerator(
        A=scipy.linalg.block_diag(*[g.A for g in gens]),
        B=np.vstack([g.B for g in gens]),
        C=scipy.linalg.block_diag(*[g.C for g in gens]),
        D=np.vstack([g.D for g in gens]),
        controls=g0.controls,
        outputs=g0.outputs,
        residuals=tuple(names),
        dt=g0.dt,
        isolates=tuple(iso for g in gens for iso in g.isolates),
    )
