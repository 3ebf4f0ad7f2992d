"""The fault spec grammar: faults read from and written to strings (the CLI's ``--fault``).

A spec is ``kind:target[:value][@onset[-end]][#sensor|#actuator]``, e.g. ``"bias:yaw_rate:0.02@10"``;
:func:`parse_fault` reads it into one of the fault kinds of :mod:`fdikit.faults` and :func:`format_fault` writes
it, with ``parse_fault(format_fault(f)) == f``.  Every number must be finite.  The kinds and their parameters are
those of :mod:`fdikit.faults` (Douglas et al. 1996, Ch. 3; Hallouzi 2008, Ch. 4).
"""

from __future__ import annotations

import math
import re

from fdikit.errors import ParameterError
from fdikit.faults import (
    Bias,
    Drift,
    Fault,
    Intermittent,
    LossOfEffectiveness,
    Noise,
    ScaleFactor,
    Stuck,
)

__all__ = ["parse_fault", "format_fault"]


_KINDS = {
    "bias": (Bias, "size"),
    "drift": (Drift, "rate"),
    "ramp": (Drift, "rate"),
    "stuck": (Stuck, "value"),
    "loe": (LossOfEffectiveness, "loss"),
    "scale": (ScaleFactor, "factor"),
    "noise": (Noise, "std"),
    "intermittent": (Intermittent, "size"),
}
#: the kind word :func:`format_fault` writes for each class (``ramp`` is read as a drift)
_KIND_OF = {Bias: "bias", Drift: "drift", Stuck: "stuck", LossOfEffectiveness: "loe", ScaleFactor: "scale",
            Noise: "noise", Intermittent: "intermittent"}
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
# also matched (then refused as not finite) so that '@inf' says what is wrong
_NUM_OR_WORD = rf"(?:{_NUM}|[-+]?(?:nan|inf|infinity))"
_TIMING = re.compile(rf"^(?P<onset>{_NUM_OR_WORD})(?:-(?P<end>{_NUM_OR_WORD}))?$", re.IGNORECASE)
_TARGET = re.compile(r"^[\w.]+$")
_GRAMMAR = "kind:target[:value][@onset[-end]][#sensor|#actuator]"


def _spec_number(spec: str, what: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"fault spec {spec!r}: the {what} {text!r} cannot be read as a number") from None
    if not math.isfinite(value):
        raise ParameterError(f"fault spec {spec!r}: the {what} must be a finite number, got {text!r}")
    return value


def parse_fault(spec: str) -> Fault:
    """Parse ``"kind:target[:value][@onset[-end]][#location]"``, e.g. ``"bias:yaw_rate:0.02@10"``.

    Kinds: bias, drift (or ramp), stuck (value optional: hold at onset), loe, scale, noise,
    intermittent (value ``size[/period[/duty]]``, by default a 1 s period and 50 % duty).
    ``#sensor`` or ``#actuator`` fixes the location of a name that is both an output and a
    control.  Every number must be finite; :func:`format_fault` writes the same grammar, and
    ``parse_fault(format_fault(f)) == f`` for every fault.

    Raises
    ------
    ParameterError
        For a spec that is not a str, does not follow the grammar, names an unknown kind or
        holds a number that cannot be read, is not finite or is out of the kind's range.

    Parameters
    ----------
    spec : str
        The fault spec.

    Returns
    -------
    Fault
        The fault of the spec's kind.

    Examples
    --------
    >>> parse_fault("intermittent:speed:0.2/2/0.25@4-10")
    Intermittent(target='speed', onset=4.0, end=10.0, location=None, size=0.2, period=2.0, duty=0.25)
    """
    if not isinstance(spec, str):
        raise ParameterError(f"a fault spec must be a string like 'bias:yaw_rate:0.02@10', "
                             f"got {type(spec).__name__} {spec!r:.60}")
    text = spec.strip()
    if not text:
        raise ParameterError(f"the fault spec is empty; write {_GRAMMAR}, e.g. 'bias:yaw_rate:0.02@10'")
    kw: dict = {}
    text, hash_, loc = text.partition("#")
    if hash_:
        if loc not in ("sensor", "actuator"):
            raise ParameterError(f"fault spec {spec!r}: the location after '#' must be 'sensor' or 'actuator', "
                                 f"got {loc!r}")
        kw["location"] = loc
    text, at, timing = text.partition("@")
    head = text.split(":", 2)
    if len(head) < 2 or (at and not timing):
        raise ParameterError(f"cannot read fault spec {spec!r}; write {_GRAMMAR} "
                             f"with kind one of {sorted(_KINDS)}, e.g. 'bias:yaw_rate:0.02@10'")
    kind, target = head[0], head[1]
    if kind not in _KINDS:
        raise ParameterError(f"cannot read fault spec {spec!r}: unknown fault kind {kind!r}; write {_GRAMMAR} "
                             f"with kind one of {sorted(_KINDS)}, e.g. 'bias:yaw_rate:0.02@10'")
    if not _TARGET.match(target):
        raise ParameterError(f"cannot read fault spec {spec!r}: the target must be a signal name (letters, digits, "
                             f"'_' and '.'), got {target!r}")
    kw["target"] = target
    cls, field_name = _KINDS[kind]
    value = head[2] if len(head) == 3 else ""
    if value:
        parts = value.split("/")
        names = (field_name, "period", "duty") if cls is Intermittent else (field_name,)
        if len(parts) > len(names):
            raise ParameterError(f"fault spec {spec!r}: a {kind} fault takes one value ({field_name})"
                                 if len(names) == 1 else
                                 f"fault spec {spec!r}: an intermittent fault takes at most size/period/duty")
        for name, part in zip(names, parts):
            kw[name] = _spec_number(spec, name, part)
    elif cls is not Stuck:
        raise ParameterError(f"fault spec {spec!r} needs a value after the target, e.g. {f'{kind}:{target}:0.1'!r}")
    if at:
        m = _TIMING.match(timing)
        if not m:
            raise ParameterError(f"cannot read fault spec {spec!r}: after '@' write onset or onset-end in seconds, "
                                 f"got {timing!r}")
        kw["onset"] = _spec_number(spec, "onset", m["onset"])
        if m["end"]:
            kw["end"] = _spec_number(spec, "end", m["end"])
    try:
        return cls(**kw)
    except ParameterError as exc:
        raise ParameterError(f"fault spec {spec!r}: {exc}") from None


def format_fault(fault: Fault) -> str:
    """The spec string of ``fault``, the grammar of :func:`parse_fault`; ``parse_fault(format_fault(f)) == f``.

    Numbers are written with ``repr`` (the shortest string that reads back to the same float);
    the onset is left out when it is 0 and the fault never ends, the value of a :class:`Stuck`
    fault that holds its onset value is left out, as are an :class:`Intermittent` fault's
    default period (1 s) and duty (0.5) at the end of its value.  The location is written as
    ``#sensor`` / ``#actuator`` when it is set.

    Raises
    ------
    ParameterError
        For an object that is not one of the fault kinds, or a target that the grammar cannot
        hold (anything but letters, digits, ``_`` and ``.``).

    Parameters
    ----------
    fault : Fault
        Any fault kind of this module.

    Returns
    -------
    str
        Its spec string.

    Examples
    --------
    >>> format_fault(Bias("yaw_rate", 0.02, onset=10))
    'bias:yaw_rate:0.02@10.0'
    >>> format_fault(parse_fault("ramp:speed:2e-3@1-5"))
    'drift:speed:0.002@1.0-5.0'
    """
    kind = _KIND_OF.get(type(fault))
    if kind is None:
        raise ParameterError(f"format_fault needs a Fault of one of the kinds {sorted(_KINDS)}, "
                             f"got {type(fault).__name__} {fault!r:.60}")
    if not _TARGET.match(fault.target):
        raise ParameterError(f"format_fault: the target {fault.target!r} cannot be written in a fault spec "
                             "(only letters, digits, '_' and '.' are allowed in a spec's signal name)")
    text = f"{kind}:{fault.target}"
    if isinstance(fault, Intermittent):
        values = [fault.size, fault.period, fault.duty]
        while len(values) > 1 and values[-1] == (1.0, 0.5)[len(values) - 2]:
            values.pop()
        text += ":" + "/".join(repr(v) for v in values)
    else:
        value = getattr(fault, _KINDS[kind][1])
        if value is not None:
            text += f":{value!r}"
    if fault.onset != 0.0 or fault.end is not None:
        text += f"@{fault.onset!r}"
        if fault.end is not None:
            text += f"-{fault.end!r}"
    if fault.location is not None:
        text += f"#{fault.location}"
    return text
