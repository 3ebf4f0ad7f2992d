"""What a design's residuals are called and which fault each one isolates (the ``names=`` / ``isolates=`` of a design).

Every design function of :mod:`fdikit.design` takes the same two keywords:

* ``names`` — a sequence of residual names, one per residual (default: the design's own names);
* ``isolates`` — a sequence with one fault name (or None, a residual that only detects) per residual, or a
  mapping ``residual name -> fault name`` that changes the named residuals only (the others keep the
  design's default, which for a design with ``targets=`` is the target each residual was built for).

Fault names follow docs/ARCHITECTURE.md, "faults in APIs": ``<output>_sensor``, ``<control>_actuator`` or a
fault input of the model (group ``f``) by its own name; a ``:magnitude`` / ``:rate`` suffix is dropped; a bare
signal name is refused with the fault name to use.  :func:`label_generator` applies both to a
:class:`~fdikit.residuals.ResidualGenerator` and passes the model's operating point to it.
:func:`warn_unlisted_faults` is the warning a parity design gives when its residual responds to a fault input
that is neither targeted nor nuisance (so isolation would otherwise name the wrong fault).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping, Sequence

from fdikit.errors import FdiWarning, ModelError, ParameterError
from fdikit.model import FaultModel, actuator_fault_name, sensor_fault_name

__all__ = ["fault_label", "residual_labels", "label_generator", "warn_unlisted_faults"]


def fault_label(model, name: str) -> str:
    """A fault name checked against a model, without its ``:magnitude`` / ``:rate`` suffix.

    Parameters
    ----------
    model : FaultModel, DAEModel or any model with ``outputs``, ``controls`` and ``faults``
        The model whose fault names are valid.
    name : str
        ``<output>_sensor``, ``<control>_actuator`` or a fault input's own name (optionally suffixed).

    Returns
    -------
    str
        The fault name without suffix.

    Raises
    ------
    ParameterError
        A name that is not a string, or a bare output/control name (the message gives the fault name).
    ModelError
        A name that is no fault of the model.

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> fault_label(msd(), "y2_sensor:magnitude"), fault_label(msd(), "u1_actuator")
    ('y2_sensor', 'u1_actuator')

    References
    ----------
    Douglas et al. 1996, §3.1–3.2 (sensor and actuator fault names).
    """
    if isinstance(model, FaultModel):
        from fdikit.fault_maps import split_fault_name

        split_fault_name(model, name)
        return name.partition(":")[0]
    if not isinstance(name, str):
        raise ParameterError(f"fault name must be a string, got {name!r} ({type(name).__name__})")
    base = name.partition(":")[0]
    outputs, controls = tuple(getattr(model, "outputs", ())), tuple(getattr(model, "controls", ()))
    faults = tuple(getattr(model, "faults", ()))
    valid = set(faults) | {sensor_fault_name(o) for o in outputs} | {actuator_fault_name(c) for c in controls}
    if base in valid:
        return base
    if base in outputs:
        raise ParameterError(f"{base!r} is an output; its sensor fault is {sensor_fault_name(base)!r}; faults are "
                             "named by fault name, not by signal name")
    if base in controls:
        raise ParameterError(f"{base!r} is a control; its actuator fault is {actuator_fault_name(base)!r}; faults "
                             "are named by fault name, not by signal name")
    raise ModelError(f"{base!r} is not a fault of the model; use one of {sorted(valid)}")


def residual_labels(
    model,
    count: int,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
    *,
    default_names: Sequence[str] | None = None,
    default_isolates: Sequence[str | None] | None = None,
) -> tuple[tuple[str, ...], tuple[str | None, ...]]:
    """The residual names and the fault each residual isolates, checked.

    Parameters
    ----------
    model : FaultModel, DAEModel or LTV model
        Its fault names are the valid ``isolates`` entries (:func:`fault_label`).
    count : int
        Number of residuals.
    names : sequence of str, optional
        One distinct name per residual; default ``default_names`` (or ``r0, r1, …``).
    isolates : sequence of (str or None), or mapping of str to (str or None), optional
        One fault per residual, or ``residual name -> fault`` for the residuals to change; default
        ``default_isolates`` (or None for every residual).
    default_names, default_isolates : sequence, optional
        The design's own choice (taken as given: a design may tie a residual to a fault it was handed as an
        explicit fault map under a name of its own).

    Returns
    -------
    names : tuple of str
    isolates : tuple of (str or None)

    Raises
    ------
    ParameterError
        ``names`` not ``count`` distinct strings; ``isolates`` of the wrong length, a mapping key that is no
        residual name, or a bare signal name.
    ModelError
        A fault name the model does not have.

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> residual_labels(msd(), 2, isolates={"r1": "y2_sensor"}, default_isolates=["u1_actuator", None])
    (('r0', 'r1'), ('u1_actuator', 'y2_sensor'))

    References
    ----------
    Douglas et al. 1996, Ch. 3 (one residual direction per fault).
    """
    base = tuple(default_names) if default_names is not None else tuple(f"r{k}" for k in range(count))
    if names is None:
        names = base
    else:
        names = (names,) if isinstance(names, str) else tuple(names)
        if len(names) != count or not all(isinstance(n, str) and n for n in names):
            raise ParameterError(f"names must be {count} non-empty strings (one per residual), got {list(names)}")
    if len(set(names)) != len(names):
        raise ParameterError(f"residual names must be distinct, got {list(names)}")
    iso = list(default_isolates) if default_isolates else [None] * count
    if len(iso) != count:
        raise ParameterError(f"{len(iso)} default isolates for {count} residuals")
    if isinstance(isolates, Mapping):
        for key, fault in isolates.items():
            if key not in names:
                raise ParameterError(f"isolates names residual {key!r}, which the design does not have; its "
                                     f"residuals are {list(names)}")
            iso[names.index(key)] = None if fault is None else fault_label(model, fault)
    elif isolates is not None:
        given = [isolates] if isinstance(isolates, str) else list(isolates)
        if len(given) != count:
            raise ParameterError(f"isolates has {len(given)} entries for {count} residuals; give one fault name "
                                 "(or None) per residual, or a mapping residual name -> fault")
        iso = [None if f is None else fault_label(model, f) for f in given]
    return tuple(names), tuple(iso)


def label_generator(generator, model, names=None, isolates=None, *, default_isolates=None):
    """``generator`` with the checked ``names`` / ``isolates`` and the model's operating point.

    Parameters
    ----------
    generator : ResidualGenerator
        As the design built it; its residual names and isolates are the defaults.
    model : FaultModel or DAEModel
        The model of the design (fault names for ``isolates``; its ``operating_point``, when it has one, is
        given to the generator, which then reads absolute signals).
    names, isolates : optional
        As :func:`residual_labels`.
    default_isolates : sequence of (str or None), optional
        The design's own isolates (default: those of ``generator``).

    Returns
    -------
    ResidualGenerator
        A copy (the same object when nothing changes).

    Raises
    ------
    ParameterError, ModelError
        As :func:`residual_labels`.

    Examples
    --------
    >>> from fdikit.plants import msd
    >>> from fdikit.design.observers import kalman
    >>> m = msd()
    >>> g = label_generator(kalman(m, 1.0, 1.0).generator, m, names=["a", "b", "c"], isolates={"b": "y2_sensor"})
    >>> g.residuals, g.isolates
    (('a', 'b', 'c'), (None, 'y2_sensor', None))

    References
    ----------
    Douglas et al. 1996, Ch. 3 (the residual generator of a design).
    """
    res, iso = residual_labels(model, len(generator.residuals), names, isolates,
                               default_names=generator.residuals,
                               default_isolates=generator.isolates if default_isolates is None else default_isolates)
    change = {}
    if res != tuple(generator.residuals):
        change["residuals"] = res
    if iso != tuple(generator.isolates):
        change["isolates"] = iso
    op = getattr(model, "operating_point", None)
    fields = {f.name for f in dataclasses.fields(generator)} if dataclasses.is_dataclass(generator) else set()
    if op is not None and "operating_point" in fields and getattr(generator, "operating_point", None) is None:
        change["operating_point"] = op
    return dataclasses.replace(generator, **change) if change else generator


def warn_unlisted_faults(who: str, responding: Mapping[str, float], stacklevel: int = 3) -> None:
    """Warn that a residual responds to fault inputs the design neither targets nor decouples.

    Parameters
    ----------
    who : str
        The design, for the message.
    responding : mapping of str to float
        Fault name -> relative size of the residual's response to it (nothing is said when empty).
    stacklevel : int, default 3
        Passed to :func:`warnings.warn` (3: the caller of the design).

    Returns
    -------
    None

    Raises
    ------
    FdiWarning
        As a warning (not an exception), when ``responding`` is not empty.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_unlisted_faults("parity_filter", {"yaw_rate_sensor": 0.42})
    >>> "yaw_rate_sensor" in str(w[0].message)
    True

    References
    ----------
    van der Ploeg 2018, §2-3 (a fault that is not decoupled shows in the residual).
    """
    if not responding:
        return
    listed = ", ".join(f"{k!r} (relative response {v:.3g})" for k, v in responding.items())
    warnings.warn(
        f"{who}: the residual also responds to fault inputs that are neither targets nor nuisance: {listed}; an "
        f"alarm may be one of them. Decouple them with nuisance={list(responding)} (or nuisance='others'), or "
        "target them", FdiWarning, stacklevel=stacklevel)
