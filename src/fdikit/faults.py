"""Fault signals on named sensors and actuators, and fault scenarios.

Each fault acts on one signal: a sensor (a measured output, corrupted after the
plant) or an actuator (a control input, corrupted before the plant).  A fault is a
function ``apply(t, v, rng) -> v_faulty`` of the clean signal sampled at times
``t``; it is active on ``onset <= t < end``.

The kinds follow Douglas et al. 1996, Ch. 3 (additive sensor bias, eq. (3.3);
actuator faults in the direction of the control, §3.2; a stuck actuator,
App. A), Hallouzi 2008 Ch. 4 (lock-in-place, loss of effectiveness) and the
usual taxonomy of Simulink Fault Analyzer (bias, drift, stuck, scale factor,
noise, intermittent).

Examples
--------
>>> from fdikit.faults import Bias, FaultScenario
>>> scenario = FaultScenario([Bias("yaw_rate", 0.02, onset=10.0)], label="gyro bias")
>>> scenario.resolve(outputs=["yaw_rate", "speed"], controls=["steering"]).faults[0].name
'yaw_rate_sensor'
"""

from __future__ import annotations

import re
from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from fdikit.errors import ModelError
from fdikit.model import actuator_fault_name, sensor_fault_name

__all__ = [
    "Fault",
    "Bias",
    "Drift",
    "Stuck",
    "LossOfEffectiveness",
    "ScaleFactor",
    "Noise",
    "Intermittent",
    "FaultScenario",
    "NO_FAULT",
    "parse_fault",
]

Location = Literal["sensor", "actuator"]
#: Truth label of a sample with no active fault.
NO_FAULT = "none"


@dataclass(frozen=True)
class Fault(ABC):
    """Base class: a fault on signal ``target`` active on ``onset <= t < end``.

    ``location`` is ``'sensor'`` or ``'actuator'``; ``None`` lets the scenario
    resolve it from the plant's names (an error when the name is both an output and
    a control).
    """

    target: str
    onset: float = field(default=0.0, kw_only=True)
    end: float | None = field(default=None, kw_only=True)
    location: Location | None = field(default=None, kw_only=True)

    def __post_init__(self) -> None:
        if not isinstance(self.target, str) or not self.target:
            raise ModelError(f"a fault needs the name of the signal it acts on, got {self.target!r}")
        if self.location not in (None, "sensor", "actuator"):
            raise ModelError(f"fault location must be 'sensor' or 'actuator', got {self.location!r}")
        if not np.isfinite(self.onset):
            raise ModelError(f"fault onset must be a finite time, got {self.onset}")
        if self.end is not None and not self.end > self.onset:
            raise ModelError(f"fault end ({self.end}) must be after its onset ({self.onset})")

    @property
    def name(self) -> str:
        """Truth label: ``'<target>_sensor'`` or ``'<target>_actuator'`` (the FaultModel fault name)."""
        if self.location is None:
            raise ModelError(f"fault on {self.target!r} has no location yet; resolve the scenario against a plant")
        return sensor_fault_name(self.target) if self.location == "sensor" else actuator_fault_name(self.target)

    def active(self, t: np.ndarray) -> np.ndarray:
        """Boolean mask of the samples where the fault acts."""
        t = np.asarray(t, dtype=float)
        mask = t >= self.onset
        if self.end is not None:
            mask &= t < self.end
        return mask

    def apply(self, t: np.ndarray, v: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """The faulty signal: ``v`` (samples,) changed where the fault is active."""
        t = np.asarray(t, dtype=float)
        v = np.asarray(v, dtype=float)
        out = v.copy()
        mask = self.active(t)
        if mask.any():
            out[mask] = self._faulty(t, v, mask, rng)
        return out

    @abstractmethod
    def _faulty(self, t: np.ndarray, v: np.ndarray, mask: np.ndarray, rng) -> np.ndarray:
        """Faulty values on the active samples ``v[mask]``."""


@dataclass(frozen=True)
class Bias(Fault):
    """Additive step: ``v + size`` (sensor bias, Douglas et al. 1996 eq. (3.3); actuator offset)."""

    size: float = 0.0

    def _faulty(self, t, v, mask, rng):
        return v[mask] + self.size


@dataclass(frozen=True)
class Drift(Fault):
    """Ramp: ``v + rate * (t - onset)``."""

    rate: float = 0.0

    def _faulty(self, t, v, mask, rng):
        return v[mask] + self.rate * (t[mask] - self.onset)


@dataclass(frozen=True)
class Stuck(Fault):
    """Stuck-at / lock-in-place: the signal holds ``value``, or its value at onset when ``value`` is None.

    Lock-in-place of a control surface, Hallouzi 2008 §4.1; stuck actuator,
    Douglas et al. 1996 App. A (``m_i = −u_i + u_ic``).
    """

    value: float | None = None

    def _faulty(self, t, v, mask, rng):
        if self.value is not None:
            return np.full(mask.sum(), float(self.value))
        first = int(np.argmax(mask))
        return np.full(mask.sum(), v[first])


@dataclass(frozen=True)
class LossOfEffectiveness(Fault):
    """Multiplicative loss: ``(1 - loss) * v`` with ``loss`` in [0, 1] (Hallouzi 2008, §4.1)."""

    loss: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0.0 <= self.loss <= 1.0:
            raise ModelError(f"loss of effectiveness must be in [0, 1] (0 = healthy, 1 = dead), got {self.loss}")

    def _faulty(self, t, v, mask, rng):
        return (1.0 - self.loss) * v[mask]


@dataclass(frozen=True)
class ScaleFactor(Fault):
    """Gain error: ``factor * v`` (a sensor scale-factor fault; van der Ploeg's ``f_m``)."""

    factor: float = 1.0

    def _faulty(self, t, v, mask, rng):
        return self.factor * v[mask]


@dataclass(frozen=True)
class Noise(Fault):
    """Extra zero-mean Gaussian noise of standard deviation ``std``."""

    std: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.std >= 0:
            raise ModelError(f"noise std must be >= 0, got {self.std}")

    def _faulty(self, t, v, mask, rng):
        if rng is None:
            raise ModelError("a Noise fault needs a numpy.random.Generator (pass rng= or seed= to simulate)")
        return v[mask] + self.std * rng.standard_normal(mask.sum())


@dataclass(frozen=True)
class Intermittent(Fault):
    """Bias ``size`` switched on for ``duty * period`` seconds out of every ``period`` after onset."""

    size: float = 0.0
    period: float = 1.0
    duty: float = 0.5

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.period > 0 or not 0 < self.duty <= 1:
            raise ModelError(f"intermittent fault needs period > 0 and 0 < duty <= 1, got {self.period}, {self.duty}")

    def active(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        # a relative tolerance keeps samples that fall on a phase boundary on the right side of it
        tol = 1e-9 * self.period
        phase = np.mod(t - self.onset + tol, self.period)
        return super().active(t) & (phase < self.duty * self.period)

    def _faulty(self, t, v, mask, rng):
        return v[mask] + self.size


class FaultScenario:
    """A set of faults plus a label (the truth name of the run).

    Parameters
    ----------
    faults : iterable of Fault
    label : str, optional
        Defaults to the names of the faults joined by ``'+'``, or ``'none'``.
    """

    def __init__(self, faults: Iterable[Fault] = (), label: str | None = None) -> None:
        self.faults: tuple[Fault, ...] = tuple(faults)
        for f in self.faults:
            if not isinstance(f, Fault):
                raise ModelError(f"a FaultScenario holds Fault objects, got {type(f).__name__}")
        self._label = label

    @property
    def label(self) -> str:
        if self._label is not None:
            return self._label
        if not self.faults:
            return NO_FAULT
        return "+".join(f.target if f.location is None else f.name for f in self.faults)

    def resolve(self, outputs: Sequence[str], controls: Sequence[str]) -> FaultScenario:
        """Check every target against a plant's outputs/controls and fix each fault's location.

        Raises
        ------
        ModelError
            For a target the plant does not have, a location that does not match, or an
            ambiguous name (both an output and a control) without an explicit location.
        """
        resolved = []
        for f in self.faults:
            is_out, is_ctl = f.target in outputs, f.target in controls
            loc = f.location
            if loc is None:
                if is_out and is_ctl:
                    raise ModelError(
                        f"{f.target!r} is both an output and a control of the plant; "
                        "give the fault location='sensor' or location='actuator'"
                    )
                loc = "sensor" if is_out else "actuator" if is_ctl else None
            if (loc == "sensor" and not is_out) or (loc == "actuator" and not is_ctl) or loc is None:
                raise ModelError(
                    f"the plant has no {'sensor' if loc == 'sensor' else 'actuator' if loc else 'signal'} "
                    f"named {f.target!r}; its outputs are {list(outputs)} and its controls {list(controls)}"
                )
            resolved.append(replace(f, location=loc))
        return FaultScenario(resolved, self._label)

    def truth(self, t: np.ndarray) -> np.ndarray:
        """Per-sample name of the active fault(s) (``'+'``-joined), ``'none'`` where healthy."""
        t = np.asarray(t, dtype=float)
        out = np.full(t.shape, NO_FAULT, dtype=object)
        for f in self.faults:
            mask = f.active(t)
            out[mask] = np.where(out[mask] == NO_FAULT, f.name, out[mask] + "+" + f.name)
        return out.astype(str)

    def __iter__(self):
        return iter(self.faults)

    def __len__(self) -> int:
        return len(self.faults)

    def __repr__(self) -> str:
        return f"FaultScenario({list(self.faults)!r}, label={self.label!r})"


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
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SPEC = re.compile(
    rf"^(?P<kind>\w+):(?P<target>[\w.]+)(?::(?P<value>[^@]*))?(?:@(?P<onset>{_NUM})(?:-(?P<end>{_NUM}))?)?$"
)


def parse_fault(spec: str) -> Fault:
    """Parse ``"kind:target[:value][@onset[-end]]"``, e.g. ``"bias:yaw_rate:0.02@10"``.

    Kinds: bias, drift (or ramp), stuck (value optional: hold at onset), loe, scale,
    noise, intermittent (bias with 1 s period, 50 % duty).
    """
    m = _SPEC.match(spec.strip())
    if not m or m["kind"] not in _KINDS:
        raise ModelError(
            f"cannot read fault spec {spec!r}; write kind:target[:value][@onset[-end]] "
            f"with kind one of {sorted(_KINDS)}, e.g. 'bias:yaw_rate:0.02@10'"
        )
    cls, field_name = _KINDS[m["kind"]]
    kw: dict = {"target": m["target"]}
    try:
        if m["value"]:
            kw[field_name] = float(m["value"])
        elif cls is not Stuck:
            example = f"{m['kind']}:{m['target']}:0.1"
            raise ModelError(f"fault spec {spec!r} needs a value after the target, e.g. {example!r}")
        if m["onset"]:
            kw["onset"] = float(m["onset"])
        if m["end"]:
            kw["end"] = float(m["end"])
    except ValueError as exc:
        raise ModelError(f"fault spec {spec!r} has a number that cannot be read: {exc}") from None
    return cls(**kw)
