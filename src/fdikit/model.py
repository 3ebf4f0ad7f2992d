"""The fault model: an LTI state space whose inputs are split into named groups.

A :class:`FaultModel` is the one model setup every synthesis function shares
(Varga's ``fdimodset``)::

    x' = A x + Bu u + Bd d + Bf f + Bw w          (x' = dx/dt, or x[k+1])
    y  = C x + Du u + Dd d + Df f + Dw w

with controls ``u``, disturbances ``d``, faults ``f`` and noise ``w``.  States,
outputs and every input carry names.  Sensor faults enter the output equation
(``Df`` column = unit vector), actuator faults enter like the control they corrupt
(Douglas et al. 1996, Ch. 3, eqs. (3.1), (3.3) and §3.2).

Examples
--------
>>> import numpy as np
>>> from fdikit import FaultModel
>>> m = FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[1.0]], states=["v"], outputs=["speed"],
...                controls=["throttle"])
>>> m = m.with_sensor_faults(["speed"]).with_actuator_faults(["throttle"])
>>> m.faults
('speed_sensor', 'throttle_actuator')
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import ModelError, ParameterError
from fdikit.operating_point import OperatingPoint

__all__ = [
    "FaultModel",
    "GROUPS",
    "sensor_fault_name",
    "actuator_fault_name",
]

#: Input groups in the order their columns appear in ``B`` and ``D``.
GROUPS: tuple[str, ...] = ("u", "d", "f", "w")
_DISCRETIZE_METHODS = ("zoh", "foh", "bilinear", "euler", "backward_diff", "impulse")
_GROUP_WORD = {"u": "controls", "d": "disturbances", "f": "faults", "w": "noise"}


def sensor_fault_name(output: str) -> str:
    """Name of the fault input that corrupts the sensor measuring ``output``.

    Parameters
    ----------
    output : str
        Output name.

    Returns
    -------
    str
        ``"<output>_sensor"`` (docs/ARCHITECTURE.md, "faults in APIs").

    Examples
    --------
    >>> sensor_fault_name("yaw_rate")
    'yaw_rate_sensor'
    """
    return f"{output}_sensor"


def actuator_fault_name(control: str) -> str:
    """Name of the fault input that corrupts the actuator driven by ``control``.

    Parameters
    ----------
    control : str
        Control name.

    Returns
    -------
    str
        ``"<control>_actuator"`` (docs/ARCHITECTURE.md, "faults in APIs").

    Examples
    --------
    >>> actuator_fault_name("throttle")
    'throttle_actuator'
    """
    return f"{control}_actuator"


def _matrix(name: str, value, rows: int | None, cols: int | None) -> np.ndarray:
    """Validated read-only float matrix; ``None`` means an empty/zero block of the given shape."""
    if value is None:
        if rows is None or cols is None:
            raise ModelError(f"{name} is required")
        out = np.zeros((rows, cols))
    else:
        out = validate.as_array(name, value, error=ModelError, finite=False)
        if out.ndim == 1 and cols == 1:
            out = out.reshape(-1, 1)
        if out.size == 0:
            out = np.zeros((rows if rows is not None else 0, cols if cols is not None else 0))
        out = validate.as_matrix(name, out, (rows, cols), error=ModelError)
    out.setflags(write=False)
    return out


def _names(kind: str, names: Sequence[str] | None, count: int, prefix: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}{i}" for i in range(count))
    if isinstance(names, str):
        raise ModelError(f"{kind} names must be a sequence of strings, got the single string {names!r}")
    try:
        names = tuple(names)
    except TypeError:
        raise ModelError(f"{kind} names must be a sequence of strings, got {type(names).__name__}") from None
    for n in names:
        if not isinstance(n, str):
            raise ModelError(f"{kind} names must be strings, got {n!r} ({type(n).__name__}); name every {kind}")
        if not n.strip():
            raise ModelError(f"{kind} names must not be empty or blank, got {n!r}; give every {kind} a name")
    names = tuple(str(n) for n in names)
    if len(names) != count:
        raise ModelError(f"{len(names)} {kind} names given for {count} {kind}")
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise ModelError(f"duplicate {kind} name {n!r}; names must be unique")
        seen.add(n)
    return names


@dataclass(frozen=True, eq=False)
class FaultModel:
    """Continuous (``dt is None``) or discrete (``dt > 0``) LTI model with grouped inputs.

    Parameters
    ----------
    A, C : array_like
        State and output matrices (n x n, p x n).
    Bu, Du, Bd, Dd, Bf, Df, Bw, Dw : array_like, optional
        Input and feedthrough matrices of the control, disturbance, fault and noise
        groups.  A missing ``B`` block has as many columns as the group has names
        (zero if none); a missing ``D`` block is zero.
    states, outputs, controls, disturbances, faults, noise : sequence of str, optional
        Names; default ``x0, x1, ...``, ``y0, ...``, ``u0, ...``, ``d0, ...``,
        ``f0, ...``, ``w0, ...``.
    dt : float, optional
        Sample time for a discrete model; ``None`` (default) for continuous time.
    operating_point : OperatingPoint, optional
        The absolute ``(x0, u0, y0)`` the deviation model holds about
        (:class:`fdikit.operating_point.OperatingPoint`; :meth:`with_operating_point` sets it).
        Generators designed from the model inherit it and run on absolute signals.

    Raises
    ------
    ModelError
        On a shape mismatch, a duplicate name or a non-finite entry; the message names
        the matrix and the offending row/column.

    Examples
    --------
    >>> m = FaultModel(A=[[0.0, 1.0], [0.0, -0.5]], C=[[1.0, 0.0]], Bu=[[0.0], [1.0]],
    ...                states=["pos", "vel"], outputs=["pos_meas"], controls=["force"])
    >>> m, m.Bu.shape, m.with_sensor_faults(["pos_meas"]).faults
    (FaultModel(continuous, n=2, p=1, u=1, d=0, f=0, w=0), (2, 1), ('pos_meas_sensor',))
    """

    A: np.ndarray
    C: np.ndarray
    B: np.ndarray = field(repr=False)
    D: np.ndarray = field(repr=False)
    states: tuple[str, ...]
    outputs: tuple[str, ...]
    inputs: dict[str, tuple[str, ...]]
    dt: float | None = None
    operating_point: OperatingPoint | None = None

    def __init__(
        self,
        A,
        C,
        *,
        Bu=None,
        Du=None,
        Bd=None,
        Dd=None,
        Bf=None,
        Df=None,
        Bw=None,
        Dw=None,
        states: Sequence[str] | None = None,
        outputs: Sequence[str] | None = None,
        controls: Sequence[str] | None = None,
        disturbances: Sequence[str] | None = None,
        faults: Sequence[str] | None = None,
        noise: Sequence[str] | None = None,
        dt: float | None = None,
        operating_point: OperatingPoint | None = None,
    ) -> None:
        A = _matrix("A", A, None, None)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ModelError(f"A must be square, got shape {A.shape}")
        C = _matrix("C", C, None, n)
        p = C.shape[0]
        blocks_b, blocks_d, groups = [], [], {}
        given = {"u": (Bu, Du, controls), "d": (Bd, Dd, disturbances), "f": (Bf, Df, faults), "w": (Bw, Dw, noise)}
        for g in GROUPS:
            Bg, Dg, names = given[g]
            if Bg is None and Dg is None:
                count = 0 if names is None else len(names)
            elif Bg is not None:
                count = _matrix(f"B{g}", Bg, n, None).shape[1]
            else:
                count = _matrix(f"D{g}", Dg, p, None).shape[1]
            blocks_b.append(_matrix(f"B{g}", Bg, n, count))
            blocks_d.append(_matrix(f"D{g}", Dg, p, count))
            groups[g] = _names(_GROUP_WORD[g], names, count, "u" if g == "u" else g)
        all_inputs = [name for g in GROUPS for name in groups[g]]
        if len(set(all_inputs)) != len(all_inputs):
            dup = next(x for x in all_inputs if all_inputs.count(x) > 1)
            raise ModelError(f"input name {dup!r} is used in two groups; input names must be unique")
        if dt is not None:
            dt = validate.number("dt (the sample time)", dt, error=ModelError, finite=False)
            if not np.isfinite(dt) or dt <= 0:
                raise ModelError(f"dt must be a positive sample time or None (continuous), got {dt}")
        B = np.hstack(blocks_b) if n else np.zeros((0, len(all_inputs)))
        D = np.hstack(blocks_d) if p else np.zeros((0, len(all_inputs)))
        B.setflags(write=False)
        D.setflags(write=False)
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "D", D)
        object.__setattr__(self, "states", _names("state", states, n, "x"))
        object.__setattr__(self, "outputs", _names("output", outputs, p, "y"))
        object.__setattr__(self, "inputs", groups)
        object.__setattr__(self, "dt", dt)
        if operating_point is not None and not isinstance(operating_point, OperatingPoint):
            raise ModelError(f"operating_point must be a fdikit.operating_point.OperatingPoint, got "
                             f"{type(operating_point).__name__}; use model.with_operating_point(x0=, u0=, y0=)")
        object.__setattr__(self, "operating_point", operating_point)

    # ------------------------------------------------------------------ sizes and blocks
    @property
    def n(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.C.shape[0]

    @property
    def is_discrete(self) -> bool:
        """Whether the model is discrete (``dt`` is a sample time)."""
        return self.dt is not None

    @property
    def controls(self) -> tuple[str, ...]:
        """Control input names (group ``u``)."""
        return self.inputs["u"]

    @property
    def disturbances(self) -> tuple[str, ...]:
        """Disturbance input names (group ``d``)."""
        return self.inputs["d"]

    @property
    def faults(self) -> tuple[str, ...]:
        """Fault input names (group ``f``)."""
        return self.inputs["f"]

    @property
    def noise(self) -> tuple[str, ...]:
        """Noise input names (group ``w``)."""
        return self.inputs["w"]

    def _slice(self, group: str) -> slice:
        if group not in GROUPS:
            raise ParameterError(f"unknown input group {group!r}; use one of {GROUPS}")
        start = sum(len(self.inputs[g]) for g in GROUPS[: GROUPS.index(group)])
        return slice(start, start + len(self.inputs[group]))

    def b(self, group: str) -> np.ndarray:
        """Input matrix of one group (``'u'``, ``'d'``, ``'f'`` or ``'w'``)."""
        return self.B[:, self._slice(group)]

    def d(self, group: str) -> np.ndarray:
        """Feedthrough matrix of one group."""
        return self.D[:, self._slice(group)]

    Bu = property(lambda self: self.b("u"), doc="Control input matrix.")
    Bd = property(lambda self: self.b("d"), doc="Disturbance input matrix.")
    Bf = property(lambda self: self.b("f"), doc="Fault input matrix.")
    Bw = property(lambda self: self.b("w"), doc="Noise input matrix.")
    Du = property(lambda self: self.d("u"), doc="Control feedthrough.")
    Dd = property(lambda self: self.d("d"), doc="Disturbance feedthrough.")
    Df = property(lambda self: self.d("f"), doc="Fault feedthrough.")
    Dw = property(lambda self: self.d("w"), doc="Noise feedthrough.")

    def _blocks(self) -> dict[str, np.ndarray]:
        return {f"{m}{g}": getattr(self, f"{m}{g}") for g in GROUPS for m in "BD"}

    def _names_kw(self) -> dict:
        return {_GROUP_WORD[g]: self.inputs[g] for g in GROUPS} | {
            "states": self.states, "outputs": self.outputs, "operating_point": self.operating_point}

    def with_operating_point(self, x0=None, u0=None, y0=None) -> FaultModel:
        """A copy that holds about the absolute operating point ``(x0, u0, y0)``.

        Parameters
        ----------
        x0, u0, y0 : array_like or mapping, optional
            One value per state / control / output in the model's order, or ``{name: value}`` for
            some of them (the others 0); omitted means 0.

        Returns
        -------
        FaultModel
            The same matrices (deviation coordinates) with ``operating_point`` set.

        Raises
        ------
        ParameterError
            For a vector of the wrong length, an unknown name or a non-finite value.

        Examples
        --------
        >>> m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], controls=["u"], outputs=["y"])
        >>> m.with_operating_point(u0=[2.0], y0={"y": 2.0}).operating_point.y0
        {'y': 2.0}
        """
        op = OperatingPoint.from_vectors(self.states, self.controls, self.outputs, x0, u0, y0)
        return self.replace(operating_point=op)

    def replace(self, **changes) -> FaultModel:
        """A copy with some constructor arguments changed (e.g. ``Bf=..., faults=...``).

        Raises :class:`ModelError` for an unknown argument name, or as the constructor does.
        """
        kw = {"A": self.A, "C": self.C, "dt": self.dt} | self._blocks() | self._names_kw()
        unknown = set(changes) - set(kw)
        if unknown:
            raise ModelError(f"unknown FaultModel argument(s) {sorted(unknown)}; valid: {sorted(kw)}")
        kw.update(changes)
        return FaultModel(**kw)

    def index(self, kind: str, names: Sequence[str] | str) -> list[int]:
        """Positions of named ``'states'``, ``'outputs'`` or inputs of a group (``'u'``, ``'d'``, ``'f'``, ``'w'``).

        Parameters
        ----------
        kind : str
            ``'states'``, ``'outputs'`` or a group.
        names : str or sequence of str
            The names to look up.

        Returns
        -------
        list of int
            Their 0-based positions, in the order given.

        Raises
        ------
        ParameterError
            If ``kind`` is not one of those.
        ModelError
            If a name is not in the model (the message lists the names it has).
        """
        if isinstance(names, str):
            names = [names]
        if not isinstance(kind, str):
            raise ParameterError(f"name kind must be a string ('states', 'outputs' or one of {GROUPS}), got {kind!r}")
        pool = {"states": self.states, "outputs": self.outputs}.get(kind) or self.inputs.get(kind)
        if pool is None and kind not in ("states", "outputs") and kind not in GROUPS:
            raise ParameterError(f"unknown name kind {kind!r}; use 'states', 'outputs' or one of {GROUPS}")
        pool = pool or ()
        out = []
        for name in names:
            if name not in pool:
                word = {"states": "state", "outputs": "output"}.get(kind) or f"{_GROUP_WORD[kind]} input"
                raise ModelError(f"no {word} named {name!r}; the model has {list(pool)}")
            out.append(pool.index(name))
        return out

    # ------------------------------------------------------------------ fault channels
    def add_faults(self, names: Sequence[str], Bf, Df=None) -> FaultModel:
        """Append fault inputs with given directions (``Bf`` n x k, ``Df`` p x k; ``Df`` default zero).

        Raises :class:`ModelError` for a single string as ``names``, a wrong shape or a duplicate name.
        """
        if isinstance(names, str):
            raise ModelError(
                f"fault names must be a sequence of strings, got the single string {names!r}; use [{names!r}]"
            )
        names = tuple(names)
        k = len(names)
        Bf_new = _matrix("Bf (new faults)", Bf, self.n, k)
        Df_new = _matrix("Df (new faults)", Df, self.p, k)
        return self.replace(
            Bf=np.hstack([self.Bf, Bf_new]), Df=np.hstack([self.Df, Df_new]), faults=self.faults + tuple(names)
        )

    def with_sensor_faults(self, outputs: Sequence[str]) -> FaultModel:
        """Add one additive fault per named output, entering the output equation.

        ``y = C x + ... + E_i μ_i`` with ``E_i`` the unit vector of output ``i``
        (Douglas et al. 1996, eq. (3.3)).  Fault names are ``"<output>_sensor"``.

        Parameters
        ----------
        outputs : str or sequence of str
            Output names.

        Returns
        -------
        FaultModel
            A copy with the new fault inputs appended to group ``f``.

        Raises
        ------
        ParameterError
            If ``outputs`` is empty.
        ModelError
            If an output is unknown or its fault input already exists.
        """
        if not isinstance(outputs, str) and len(outputs) == 0:
            raise ParameterError("outputs is empty; name at least one output whose sensor can fail")
        idx = self.index("outputs", outputs)
        Df = np.zeros((self.p, len(idx)))
        Df[idx, range(len(idx))] = 1.0
        return self.add_faults([sensor_fault_name(self.outputs[i]) for i in idx], np.zeros((self.n, len(idx))), Df)

    def with_actuator_faults(self, controls: Sequence[str]) -> FaultModel:
        """Add one additive fault per named control, in the same direction as that control.

        The fault direction is the control's column of ``Bu`` and ``Du`` (Douglas et al.
        1996, §3.2: "the direction of an engine throttle control fault is the first
        column of the B matrix").  Fault names are ``"<control>_actuator"``.

        Parameters
        ----------
        controls : str or sequence of str
            Control names.

        Returns
        -------
        FaultModel
            A copy with the new fault inputs appended to group ``f``.

        Raises
        ------
        ParameterError
            If ``controls`` is empty.
        ModelError
            If a control is unknown or its fault input already exists.
        """
        if not isinstance(controls, str) and len(controls) == 0:
            raise ParameterError("controls is empty; name at least one control whose actuator can fail")
        idx = self.index("u", controls)
        return self.add_faults([actuator_fault_name(self.controls[i]) for i in idx], self.Bu[:, idx], self.Du[:, idx])

    # ------------------------------------------------------------------ transformations
    def submodel(self, outputs: Sequence[str] | None = None, inputs: Sequence[str] | None = None) -> FaultModel:
        """Keep only the named outputs and/or inputs (inputs of any group, by name).

        ``None`` keeps all; the states are kept.  Raises :class:`ModelError` for an unknown name.
        """
        C, D, kw = self.C, self.D, self._names_kw()
        if outputs is not None:
            rows = self.index("outputs", outputs)
            C, D, kw["outputs"] = C[rows], D[rows], tuple(self.outputs[i] for i in rows)
        new = {"A": self.A, "C": C, "dt": self.dt, "states": self.states, "outputs": kw["outputs"],
               "operating_point": self.operating_point}
        keep = None if inputs is None else set(inputs)
        if keep is not None:
            known = {nm for g in GROUPS for nm in self.inputs[g]}
            missing = keep - known
            if missing:
                raise ModelError(f"no input named {sorted(missing)}; the model has {sorted(known)}")
        for g in GROUPS:
            sl = self._slice(g)
            cols = [j for j, nm in enumerate(self.inputs[g]) if keep is None or nm in keep]
            new[f"B{g}"] = self.B[:, sl][:, cols]
            new[f"D{g}"] = D[:, sl][:, cols]
            new[_GROUP_WORD[g]] = tuple(self.inputs[g][j] for j in cols)
        return FaultModel(**new)

    def discretize(self, dt: float, method: str = "zoh") -> FaultModel:
        """Sampled model with the same groups and names.

        ``method`` is any of :func:`scipy.signal.cont2discrete`'s (``'zoh'`` is exact
        for piecewise-constant inputs).

        Parameters
        ----------
        dt : float
            Sample time [s], positive.
        method : str, default "zoh"
            ``'zoh'``, ``'foh'``, ``'bilinear'``, ``'euler'``, ``'backward_diff'`` or ``'impulse'``.

        Returns
        -------
        FaultModel
            The discrete model.

        Raises
        ------
        ModelError
            If the model is already discrete.
        ParameterError
            If ``dt`` is not positive or ``method`` is unknown.
        """
        import scipy.signal

        if self.is_discrete:
            raise ModelError(f"model is already discrete (dt={self.dt}); discretize a continuous model")
        dt = validate.positive("dt (the sample time)", dt, error=ParameterError)
        validate.choice("discretization method", method, _DISCRETIZE_METHODS, error=ParameterError)
        Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((self.A, self.B, self.C, self.D), dt, method=method)
        return self._with_matrices(Ad, Bd, Cd, Dd, dt)

    def _with_matrices(self, A, B, C, D, dt) -> FaultModel:
        kw = {"A": A, "C": C, "dt": dt} | self._names_kw()
        for g in GROUPS:
            sl = self._slice(g)
            kw[f"B{g}"], kw[f"D{g}"] = B[:, sl], D[:, sl]
        return FaultModel(**kw)

    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A``."""
        return scipy.linalg.eigvals(self.A)

    def freqresp(self, omega, group: str | None = None) -> np.ndarray:
        """Frequency response ``C (zI − A)⁻¹ B + D`` at ``omega`` (rad/s), shape (len(omega), p, k).

        ``z = jω`` in continuous time and ``e^{jω dt}`` in discrete time; ``group``
        restricts the inputs to one group (``'u'``, ``'d'``, ``'f'``, ``'w'``).

        Parameters
        ----------
        omega : array_like
            Frequencies [rad/s].
        group : str, optional
            One input group; default all inputs.

        Returns
        -------
        numpy.ndarray
            Complex (len(omega), p, k) array.
        """
        omega = validate.as_vector("omega (rad/s)", omega)
        B, D = (self.B, self.D) if group is None else (self.b(group), self.d(group))
        z = np.exp(1j * omega * self.dt) if self.is_discrete else 1j * omega
        eye = np.eye(self.n)
        return np.array([self.C @ np.linalg.solve(zk * eye - self.A, B) + D for zk in z])

    # ------------------------------------------------------------------ python-control interop
    def to_control(self):
        """A :class:`control.StateSpace` with all inputs (groups in order u, d, f, w) and names."""
        import control

        names = [nm for g in GROUPS for nm in self.inputs[g]]
        return control.ss(
            self.A, self.B, self.C, self.D, self.dt if self.dt is not None else 0,
            states=list(self.states), outputs=list(self.outputs), inputs=names,
        )

    @classmethod
    def from_control(
        cls,
        sys,
        *,
        controls: Sequence[str] | None = None,
        disturbances: Sequence[str] = (),
        faults: Sequence[str] = (),
        noise: Sequence[str] = (),
    ) -> FaultModel:
        """Build from a :class:`control.StateSpace`, assigning its named inputs to groups.

        Inputs named in ``disturbances``, ``faults`` or ``noise`` go to those groups;
        ``controls`` defaults to every remaining input, in the system's order.

        Raises :class:`ModelError` if ``sys`` is no :class:`control.StateSpace`, a named input does not
        exist, or the sample time is unspecified (``dt=True``).
        """
        from fdikit.model_interop import model_from_control

        return model_from_control(cls, sys, controls=controls, disturbances=disturbances, faults=faults, noise=noise)

    def __repr__(self) -> str:
        kind = "continuous" if self.dt is None else f"discrete dt={self.dt:g}"
        groups = ", ".join(f"{g}={len(self.inputs[g])}" for g in GROUPS)
        return f"FaultModel({kind}, n={self.n}, p={self.p}, {groups})"
