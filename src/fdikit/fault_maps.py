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

    Parameters
    ----------
    model : FaultModel
        The plant; its ``A`` and ``C`` are used.
    output : str
        Name of the output whose sensor fails (an output name, not the fault name).
    direction : {"both", "magnitude", "rate"}, default "both"
        Which columns to return (see above).
    rtol : float, default 1e-9
        Bound on ``‖C F¹ − e_i‖`` for ``F¹`` to count as a solution.

    Returns
    -------
    numpy.ndarray
        (n, 2) ``[F¹, A F¹]``, or the (n, 1) column ``A F¹`` (``'magnitude'``) or ``F¹`` (``'rate'``).

    Raises
    ------
    ParameterError
        If ``model`` is not a :class:`~fdikit.model.FaultModel` or ``direction`` is not one of the three.
    ModelError
        If the model has no output ``output``.
    DesignError
        If ``e_i`` is not in the range of ``C`` (no ``F¹`` solves ``C F¹ = e_i``).

    References
    ----------
    Douglas et al. 1996, §3.1, (3.3)–(3.5); App. A.2, (a.5)–(a.6).

    Examples
    --------
    >>> from fdikit.plants import f16xl_longitudinal
    >>> m = f16xl_longitudinal()  # C = I: F¹ is the unit vector of theta
    >>> F = sensor_fault_map(m, "y_theta")
    >>> F.shape, F[:, 0].tolist(), bool(np.allclose(F[:, 1], m.A[:, 3]))
    ((4, 2), [0.0, 0.0, 0.0, 1.0], True)
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

    Parameters
    ----------
    A, C : callable
        ``t -> (n, n)`` state matrix and ``t -> (p, n)`` output matrix.
    output : int
        Index (0-based) of the output whose sensor fails.
    t : float
        Time [s] at which the map is evaluated.
    dF1 : callable, optional
        ``t -> (n,)`` derivative of ``F¹``; default a central difference of the minimum-norm ``F¹``.
    step : float, optional
        Step [s] of that difference; default ``1e-6 · max(1, |t|)``.
    rtol : float, default 1e-9
        Bound on ``‖C(τ) F¹(τ) − e_i‖`` for ``F¹`` to count as a solution.

    Returns
    -------
    numpy.ndarray
        (n, 2) ``[F¹(t), F²(t)]``.

    Raises
    ------
    ParameterError
        If ``A``, ``C`` or ``dF1`` is not callable, ``t`` is not a finite number, or ``output`` is not an
        index of the outputs of ``C(t)``.
    DesignError
        If ``e_i`` is not in the range of ``C(τ)`` at ``t`` (or at ``t ± step``).

    References
    ----------
    Douglas et al. 1996, App. A.2 (the time-varying form of (a.5)) and App. A.3, (a.9).

    Examples
    --------
    >>> A = lambda t: np.array([[0.0, 1.0], [-1.0, -t]])
    >>> C = lambda t: np.array([[1.0, t]])
    >>> np.round(sensor_fault_map_tv(A, C, 0, 1.0), 6).tolist()
    [[0.5, 1.0], [0.5, -1.0]]
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

    Parameters
    ----------
    model : FaultModel
        The plant.
    control : str
        Name of the control whose actuator fails (a control name, not the fault name).

    Returns
    -------
    numpy.ndarray
        (n, 1) column of ``Bu`` of that control.

    Raises
    ------
    ParameterError
        If ``model`` is not a :class:`~fdikit.model.FaultModel`.
    ModelError
        If the model has no control ``control``.
    DesignError
        If the control's column of ``Du`` is nonzero.

    References
    ----------
    Douglas et al. 1996, §3.2.

    Examples
    --------
    >>> from fdikit.plants import f16xl_longitudinal
    >>> m = f16xl_longitudinal()
    >>> actuator_fault_map(m, "elevon").shape
    (4, 1)
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

    Parameters
    ----------
    model : FaultModel
        The model whose outputs, controls and fault inputs define the valid names.
    name : str
        A fault name, optionally with a ``:magnitude`` / ``:rate`` suffix.

    Returns
    -------
    tuple of str
        ``(kind, signal, suffix)``: kind ``'fault'``, ``'sensor'`` or ``'actuator'``; the fault input's,
        output's or control's name; the suffix without the colon (``''`` when none).

    Raises
    ------
    ParameterError
        A name that is not a string, an unknown suffix, or a bare signal name (an output or control):
        the message gives the fault name to use (``'theta' is an output; its sensor fault is
        'theta_sensor'``).
    ModelError
        A name the model does not know, or a suffix on an actuator fault.

    Examples
    --------
    >>> from fdikit.plants import f16xl_longitudinal
    >>> m = f16xl_longitudinal()
    >>> split_fault_name(m, "y_theta_sensor:magnitude"), split_fault_name(m, "elevon_actuator")
    (('sensor', 'y_theta', 'magnitude'), ('actuator', 'elevon', ''))
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

    Parameters
    ----------
    model : FaultModel
        The model whose fault inputs (group ``f``) are the valid names.
    names : str or sequence of str
        One name or several.
    what : str, default "fault"
        Word used in the error message for a name that is not a string.

    Returns
    -------
    tuple of str
        The names, unchanged (a single string becomes a 1-tuple).

    Raises
    ------
    ParameterError
        If ``model`` is not a :class:`~fdikit.model.FaultModel`, a name is not a string, or it is a bare
        output or control name.
    ModelError
        If a name is no fault input of the model (for a sensor or actuator fault name, the message
        names ``with_sensor_faults`` / ``with_actuator_faults``).

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> check_fault_inputs(msd(), "y2_sensor")
    ('y2_sensor',)
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

    Parameters
    ----------
    model : FaultModel
        The plant.
    name : str
        A fault name, optionally with a ``:magnitude`` / ``:rate`` suffix.

    Returns
    -------
    F : numpy.ndarray
        (n, k) fault map: k = 2 for a sensor fault, 1 for a suffixed sensor fault, an actuator or a
        fault input.
    kind : str
        ``'sensor'``, ``'sensor:magnitude'``, ``'sensor:rate'``, ``'actuator'`` or ``'fault input'``.

    Raises
    ------
    ParameterError
        As :func:`split_fault_name` (not a string, unknown suffix, bare signal name).
    ModelError
        As :func:`split_fault_name`, or a suffix on a fault input that is not a sensor fault.
    DesignError
        If a fault input reaches the outputs without being a pure sensor fault, or from
        :func:`sensor_fault_map` / :func:`actuator_fault_map`.

    References
    ----------
    Douglas et al. 1996, §3.1, (3.5) (sensor faults) and §3.2 (actuator faults).

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> m = msd()
    >>> [(F.shape, kind) for F, kind in (resolve_fault(m, "y2_sensor"), resolve_fault(m, "u1_actuator"))]
    [((6, 2), 'sensor'), ((6, 1), 'fault input')]
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

    Parameters
    ----------
    model : FaultModel
        The plant.
    faults : mapping of str to array_like, sequence of str, or str
        Explicit maps by name (an (n, k) matrix; a (k, n) one is transposed), or fault names.

    Returns
    -------
    dict of str to numpy.ndarray
        The (n, kᵢ) fault map of each fault, by name (without suffix), in the given order.

    Raises
    ------
    ParameterError
        If ``model`` is not a :class:`~fdikit.model.FaultModel`, or as :func:`resolve_fault`.
    ModelError
        If an explicit map is not a finite matrix with n rows (or n columns), or as :func:`resolve_fault`.
    DesignError
        As :func:`resolve_fault`.

    Examples
    --------
    >>> from fdikit.plants import f16xl_longitudinal
    >>> maps = resolve_faults(f16xl_longitudinal(), ["y_q_sensor:magnitude", "elevon_actuator"])
    >>> {name: F.shape for name, F in maps.items()}
    {'y_q_sensor': (4, 1), 'elevon_actuator': (4, 1)}
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

    Parameters
    ----------
    model : FaultModel
        The plant.
    nuisance : mapping of str to array_like, sequence of str, or str
        ``()``, ``'others'``, fault names or explicit maps (as :func:`resolve_faults`).
    targets : sequence of str, default ()
        The design's targets, left out of ``'others'`` (suffixes ignored).

    Returns
    -------
    dict of str to numpy.ndarray
        The (n, kᵢ) fault map of each nuisance fault by name; empty for none.

    Raises
    ------
    ParameterError
        If ``nuisance`` is None, or as :func:`resolve_faults`.
    ModelError, DesignError
        As :func:`resolve_faults`.

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> m = msd()
    >>> list(resolve_nuisance(m, "others", targets=["y2_sensor"])), resolve_nuisance(m, ())
    (['u1_actuator'], {})
    """
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        given = {str(t).partition(":")[0] for t in targets}
        return {f: resolve_fault(model, f)[0] for f in model.faults if f not in given}
    if isinstance(nuisance, Mapping) or len(nuisance):
        return resolve_faults(model, nuisance)
    return {}
