"""Fault maps: the state-space direction ``F`` of a named fault (Douglas et al. 1996, Ch. 3, App. A.2).

Sensor faults are the two-dimensional ``F = [F¹, A F¹]`` with ``C F¹ = e_i`` (eqs. (3.3)–(3.5); App. A.2),
actuator faults columns of ``B`` (§3.2), fault inputs of the model (group ``f``) their own columns.  Faults are
named by fault name (``<output>_sensor[:magnitude|:rate]``, ``<control>_actuator`` or a fault input's name;
docs/ARCHITECTURE.md, "faults in APIs"): :func:`split_fault_name` parses one, :func:`resolve_fault` and
:func:`resolve_faults` give the maps of the ``targets=`` of a design, :func:`resolve_nuisance` those of its
``nuisance=``, and :func:`check_fault_inputs` checks names of fault inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from fdikit import validate
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel, actuator_fault_name, sensor_fault_name

__all__ = [
    "sensor_fault_map",
    "sensor_fault_map_tv",
    "actuator_fault_map",
    "split_fault_name",
    "check_fault_inputs",
    "resolve_fault",
    "resolve_faults",
    "resolve_nuisance",
]


def sensor_fault_map(model: FaultModel, output: str, direction: str = "both", rtol: float = 1e-9) -> np.ndarray:
    """State-space fault map of an additive fault on the sensor of ``output``.

    ``y = C x + e_i μ`` is written as a state fault through ``F¹`` with ``C F¹ = e_i``:
    ``ē = e − F¹ μ`` gives ``ē' = (A + LC) ē + F¹ μ' − A F¹ μ`` (Douglas et al. 1996,
    eq. (3.4); App. A.2).  ``direction``: ``'both'`` → ``[F¹, A F¹]`` (n x 2), ``'magnitude'``
    → ``A F¹`` (the bias direction), ``'rate'`` → ``F¹``.  ``F¹`` is the minimum-norm
    solution; it must solve ``C F¹ = e_i`` exactly (to ``rtol``), otherwise the output is
    not reachable from the states and :class:`DesignError` is raised.
    """
    validate.instance("model", model, FaultModel)
    validate.choice("direction", direction, ("both", "magnitude", "rate"))
    i = model.index("outputs", output)[0]
    e = np.zeros(model.p)
    e[i] = 1.0
    F1, *_ = np.linalg.lstsq(model.C, e, rcond=None)
    if np.linalg.norm(model.C @ F1 - e) > rtol:
        raise DesignError(
            f"output {output!r} is not in the range of C (residual {np.linalg.norm(model.C @ F1 - e):.2e}): "
            "its sensor fault cannot be written as a state fault F¹ with C F¹ = e_i; use a model whose C has "
            "full row rank for these outputs"
        )
    F1 = F1.reshape(-1, 1)
    F2 = model.A @ F1
    maps = {"both": np.hstack([F1, F2]), "magnitude": F2, "rate": F1}
    if direction not in maps:
        raise ParameterError(f"direction must be 'both', 'magnitude' or 'rate', got {direction!r}")
    return maps[direction]


def sensor_fault_map_tv(
    A: Callable[[float], np.ndarray],
    C: Callable[[float], np.ndarray],
    output: int,
    t: float,
    dF1: Callable[[float], np.ndarray] | None = None,
    step: float | None = None,
    rtol: float = 1e-9,
) -> np.ndarray:
    """Two-dimensional sensor-fault map of a time-varying model at time ``t``: ``[F¹(t), F²(t)]``.

    ``C(t) F¹(t) = e_i`` (minimum-norm) and ``F² = A F¹ − dF¹/dt`` (Douglas et al. 1996, App. A.2; the
    printed (a.9b) reads ``A b + ḃ``; the Goh transformation it names gives ``A b − ḃ``, the sign of
    ``A B₁ − Ḃ₁`` in (9.38) and of ``A F_i − Ḟ_i`` in App. A.2).
    ``dF1`` gives the derivative; otherwise a central difference with ``step`` (default ``1e-6 · max(1, |t|)``).
    ``A`` and ``C`` are callables ``t -> matrix``; ``output`` is the output's index.
    """
    for nm, fn in (("A", A), ("C", C), ("dF1", dF1)):
        if fn is not None and not callable(fn):
            raise ParameterError(f"{nm} must be a function of time t -> matrix, got {type(fn).__name__}")
    t = validate.number("t", t)
    validate.integer("output", output, minimum=0)
    p0 = np.atleast_2d(np.asarray(C(t), dtype=float)).shape[0]
    if output >= p0:
        raise ParameterError(f"output index {output} is out of range; C(t) has {p0} outputs (0 .. {p0 - 1})")

    def f1(tau: float) -> np.ndarray:
        Ct = np.atleast_2d(np.asarray(C(tau), dtype=float))
        e = np.zeros(Ct.shape[0])
        e[output] = 1.0
        x, *_ = np.linalg.lstsq(Ct, e, rcond=None)
        if np.linalg.norm(Ct @ x - e) > rtol:
            raise DesignError(f"output {output} is not in the range of C(t) at t = {tau:g}; no sensor-fault map")
        return x

    F1 = f1(t)
    if dF1 is not None:
        d = np.asarray(dF1(t), dtype=float).ravel()
    else:
        h = step if step is not None else 1e-6 * max(1.0, abs(t))
        d = (f1(t + h) - f1(t - h)) / (2 * h)
    F2 = np.atleast_2d(np.asarray(A(t), dtype=float)) @ F1 - d
    return np.column_stack([F1, F2])


def actuator_fault_map(model: FaultModel, control: str) -> np.ndarray:
    """Fault map of an actuator: the control's column of ``B`` (Douglas et al. 1996, §3.2), n x 1.

    On a model whose actuator lags are states (e.g. the 14-state PATH model) this is the
    command-side fault; a nonzero ``D`` column means the fault also reaches the outputs
    directly, which the geometric filters here do not model (:class:`DesignError`).
    """
    validate.instance("model", model, FaultModel)
    j = model.index("u", control)[0]
    if np.any(model.Du[:, j] != 0):
        raise DesignError(
            f"control {control!r} has a direct feedthrough D[:, {j}] != 0; an actuator fault on it reaches the "
            "outputs directly. Use a model with the actuator dynamics as states (e.g. path_vehicle_14)"
        )
    return model.Bu[:, [j]]


def _signal_hint(model: FaultModel, base: str, suffix: str = "") -> str | None:
    """The message refusing a bare signal name, naming the fault to use (None if ``base`` is no signal)."""
    tail = f":{suffix}" if suffix else ""
    if base in model.outputs:
        return f"{base!r} is an output; its sensor fault is {sensor_fault_name(base) + tail!r}"
    if base in model.controls:
        return f"{base!r} is a control; its actuator fault is {actuator_fault_name(base) + tail!r}"
    return None


def split_fault_name(model: FaultModel, name: str) -> tuple[str, str, str]:
    """Parse a fault name against a model: ``(kind, signal, suffix)``.

    * a fault input of the model (group ``f``) by its own name → ``('fault', name, suffix)``;
    * ``'<output>_sensor'`` → ``('sensor', output, suffix)``, with the optional suffix ``':magnitude'``
      (``A F¹`` only, the bias assumption, Douglas et al. 1996, §3.1) or ``':rate'`` (``F¹`` only);
    * ``'<control>_actuator'`` → ``('actuator', control, '')``.

    Raises
    ------
    ParameterError
        A name that is not a string, an unknown suffix, or a bare signal name (an output or control):
        the message gives the fault name to use (``'theta' is an output; its sensor fault is
        'theta_sensor'``).
    ModelError
        A name the model does not know, or a suffix on an actuator fault.
    """
    validate.instance("model", model, FaultModel)
    if not isinstance(name, str):
        raise ParameterError(f"fault name must be a string, got {name!r} ({type(name).__name__})")
    base, _, suffix = name.partition(":")
    if suffix and suffix not in ("magnitude", "rate"):
        raise ParameterError(
            f"unknown fault suffix {suffix!r} in {name!r}; use ':magnitude' or ':rate' (sensor faults)"
        )
    if base in model.faults:
        return "fault", base, suffix
    sensors = {sensor_fault_name(o): o for o in model.outputs}
    if base in sensors:
        return "sensor", sensors[base], suffix
    actuators = {actuator_fault_name(c): c for c in model.controls}
    if base in actuators:
        if suffix:
            raise ModelError(f"{name!r}: the ':{suffix}' suffix applies to sensor faults only, {base!r} is an "
                             "actuator fault")
        return "actuator", actuators[base], ""
    hint = _signal_hint(model, base, suffix)
    if hint:
        raise ParameterError(f"{hint}; faults are named by fault name, not by signal name")
    raise ModelError(
        f"{base!r} is not a fault of the model; fault names are <output>_sensor {list(sensors)}, "
        f"<control>_actuator {list(actuators)} and the fault inputs {list(model.faults)}"
    )


def check_fault_inputs(model: FaultModel, names: Sequence[str] | str, what: str = "fault") -> tuple[str, ...]:
    """Names of fault inputs of the model (group ``f``), checked; a bare signal name is refused.

    For designs that act on the model's fault inputs themselves (:func:`fdikit.design.observers.uio.uio`,
    the gain tables of :mod:`fdikit.analysis`).  Raises :class:`ParameterError` for a signal name (with the
    fault name to use) and :class:`ModelError` for a name that is no fault input of the model.
    """
    validate.instance("model", model, FaultModel)
    names = (names,) if isinstance(names, str) else tuple(names)
    for nm in names:
        if not isinstance(nm, str):
            raise ParameterError(f"{what} names must be strings, got {nm!r} ({type(nm).__name__})")
        if nm in model.faults:
            continue
        hint = _signal_hint(model, nm)
        if hint:
            raise ParameterError(f"{hint}; faults are named by fault name, not by signal name")
        kind = "sensor" if nm in {sensor_fault_name(o) for o in model.outputs} else (
            "actuator" if nm in {actuator_fault_name(c) for c in model.controls} else None)
        if kind:
            add = "with_sensor_faults" if kind == "sensor" else "with_actuator_faults"
            raise ModelError(f"{nm!r} is not a fault input of the model; add it with model.{add}([...]) "
                             f"(the model has fault inputs {list(model.faults)})")
        model.index("f", nm)  # raises the model's own ModelError for an unknown name
    return names


def resolve_fault(model: FaultModel, name: str) -> tuple[np.ndarray, str]:
    """State-space fault map of a named fault and its kind.

    ``name`` is a fault name (:func:`split_fault_name`):

    * ``'<output>_sensor'`` → :func:`sensor_fault_map` ``[F¹, A F¹]`` (kind ``'sensor'``);
      ``'<output>_sensor:magnitude'`` → ``A F¹`` only (the bias assumption, Douglas et al. 1996, §3.1),
      ``'<output>_sensor:rate'`` → ``F¹`` only (kind ``'sensor:magnitude'`` / ``'sensor:rate'``);
    * ``'<control>_actuator'`` → :func:`actuator_fault_map`, the column of ``Bu`` (``'actuator'``);
    * a fault input of the model (group ``f``) by its own name → its ``Bf`` column when ``Df`` is
      zero (``'fault input'``), the sensor map of output ``i`` when it is a pure sensor fault
      (``Df = e_i``, ``Bf = 0``).

    A bare signal name (``'theta'``, ``'throttle'``) raises :class:`ParameterError` naming the fault.
    """
    kind, base, suffix = split_fault_name(model, name)
    if kind == "fault":
        j = model.index("f", base)[0]
        df, bf = model.Df[:, j], model.Bf[:, j]
        if not np.any(df):
            if suffix:
                raise ModelError(f"{name!r}: the suffix applies to sensor faults only")
            return bf.reshape(-1, 1), "fault input"
        i = int(np.argmax(np.abs(df)))
        if np.any(bf) or np.count_nonzero(df) != 1 or df[i] != 1.0:
            raise DesignError(f"fault {base!r} reaches the outputs directly and is not a pure sensor fault; "
                              "pass its state-space fault map in a dict")
        base, kind = model.outputs[i], "sensor"
    if kind == "sensor":
        direction = suffix or "both"
        return sensor_fault_map(model, base, direction), "sensor" if direction == "both" else f"sensor:{suffix}"
    return actuator_fault_map(model, base), "actuator"


def resolve_faults(model: FaultModel, faults: Mapping[str, np.ndarray] | Sequence[str] | str) -> dict[str, np.ndarray]:
    """Fault maps by fault name.

    A mapping gives explicit ``F`` matrices (n x k) under its keys.  A name or a sequence of
    names is resolved by :func:`fdikit.fault_maps.resolve_fault`: ``'<output>_sensor'`` is the sensor
    fault ``[F¹, A F¹]``, ``'<output>_sensor:magnitude'`` its bias direction ``A F¹`` only
    (Douglas et al. 1996, §4.1, the air-mass fix), ``'<control>_actuator'`` the actuator fault
    ``B[:, j]``, a fault input of the model (group ``f``) its own map.  The keys are the names
    without the suffix.  A bare signal name (``'theta'``) raises :class:`ParameterError` whose
    message gives the fault name (``'theta_sensor'``).
    """
    validate.instance("model", model, FaultModel)
    if isinstance(faults, str):
        faults = [faults]
    if isinstance(faults, Mapping):
        out = {}
        for name, F in faults.items():
            F = np.atleast_2d(validate.as_array(f"fault map {name!r}", F, error=ModelError))
            if F.shape[0] != model.n and F.shape[1] == model.n:
                F = F.T
            if F.shape[0] != model.n:
                raise ModelError(f"fault map {name!r} has {F.shape[0]} rows; the model has {model.n} states")
            out[str(name)] = F
        return out
    out = {}
    for spec in faults:
        F, _ = resolve_fault(model, spec)
        out[spec.partition(":")[0]] = F
    return out


def resolve_nuisance(
    model: FaultModel, nuisance: Mapping[str, np.ndarray] | Sequence[str] | str, targets: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """Fault maps of the faults a design must ignore (the ``nuisance=`` convention).

    ``()`` (or an empty mapping) means none; the string ``'others'`` means every fault input of the
    model (group ``f``) not named in ``targets``; anything else is resolved by :func:`resolve_faults`.
    """
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        given = {str(t).partition(":")[0] for t in targets}
        return {f: resolve_fault(model, f)[0] for f in model.faults if f not in given}
    if isinstance(nuisance, Mapping) or len(nuisance):
        return resolve_faults(model, nuisance)
    return {}
