"""Fault signals on named sensors and actuators, and fault scenarios.

Each fault acts on one signal: a sensor (a measured output, corrupted after the
plant) or an actuator (a control input, corrupted before the plant).  A fault is a
function ``apply(t, v, rng) -> v_faulty`` of the clean signal sampled at times
``t``; it is active on ``onset <= t < end``.

The kinds follow Douglas et al. 1996, Ch. 3 (additive sensor bias, eq. (3.3);
actuator faults in the direction of the control, §3.2; a stuck actuator,
App. A), Hallouzi 2008, Ch. 4 (lock-in-place, loss of effectiveness) and the
usual taxonomy of Simulink Fault Analyzer (bias, drift, stuck, scale factor,
noise, intermittent).

Every number of a fault (onset, end, size) must be finite (a :class:`~fdikit.errors.ParameterError`
otherwise), and a fault never changes a sample before its onset.  The spec strings of faults (the CLI's
``--fault``) are read and written by :mod:`fdikit.fault_spec`.

Examples
--------
>>> from fdikit.faults import Bias, FaultScenario
>>> scenario = FaultScenario([Bias("yaw_rate", 0.02, onset=10.0)], label="gyro bias")
>>> scenario.resolve(outputs=["yaw_rate", "speed"], controls=["steering"]).faults[0].name
'yaw_rate_sensor'
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import ClassVar, Literal

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
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
]

Location = Literal["sensor", "actuator"]
#: Truth label of a sample with no active fault.
NO_FAULT = "none"


def _real(owner: str, name: str, value, *, finite: bool = True, hint: str = "") -> float:
    """``value`` as a float: a real number (not a bool, str or array), finite unless ``finite=False``."""
    v = validate.number(f"{owner}: {name}", value, finite=False)
    if finite and not math.isfinite(v):
        raise ParameterError(f"{owner}: {name} must be a finite number, got {v}{hint}")
    return v


@dataclass(frozen=True)
class Fault(ABC):
    """Base class: a fault on signal ``target`` active on ``onset <= t < end``.

    ``location`` is ``'sensor'`` or ``'actuator'``; ``None`` lets the scenario
    resolve it from the plant's names (an error when the name is both an output and
    a control).  Every number (onset, end and the kind's size) must be finite; they are
    stored as floats.

    Parameters
    ----------
    target : str
        The signal the fault acts on: an output (sensor fault) or a control (actuator fault) of the plant.
    onset : float, keyword-only
        Time [s] the fault appears (default 0).
    end : float or None, keyword-only
        Time [s] it disappears; ``None`` (default) for a permanent fault.
    location : {'sensor', 'actuator'} or None, keyword-only
        Where it acts; ``None`` resolves it from the plant's names.

    Raises
    ------
    ParameterError
        For an empty or non-string target, an unknown location, a non-number or non-finite
        onset, end or size, an end not after the onset, or a size out of the kind's range.

    Examples
    --------
    >>> f = Bias("yaw_rate", 0.02, onset=10.0, end=20.0)
    >>> f.active([5.0, 10.0, 19.9, 20.0]).tolist()
    [False, True, True, False]
    """

    target: str
    onset: float = field(default=0.0, kw_only=True)
    end: float | None = field(default=None, kw_only=True)
    location: Location | None = field(default=None, kw_only=True)

    #: names of the kind's numeric parameters (validated finite and stored as float)
    _values: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self) -> None:
        kind = type(self).__name__
        if not isinstance(self.target, str) or not self.target:
            raise ParameterError(
                f"{kind}: target must be the name of the signal the fault acts on (a non-empty str), "
                f"got {self.target!r}"
            )
        owner = f"{kind} on {self.target!r}"
        if self.location not in (None, "sensor", "actuator"):
            raise ParameterError(f"{owner}: location must be 'sensor' or 'actuator' (or None to resolve it from "
                                 f"the plant's names), got {self.location!r}")
        object.__setattr__(self, "onset", _real(owner, "onset", self.onset))
        if self.end is not None:
            end = _real(owner, "end", self.end, finite=False)
            if not math.isfinite(end):
                raise ParameterError(f"{owner}: end must be a finite time, got {end}; "
                                     "use end=None for a fault that never ends")
            if not end > self.onset:
                raise ParameterError(f"{owner}: end ({end}) must be after its onset ({self.onset})")
            object.__setattr__(self, "end", end)
        for name in self._values:
            value = getattr(self, name)
            if value is not None or not self._optional(name):
                object.__setattr__(self, name, _real(owner, name, value))
        self._check(owner)

    def _optional(self, name: str) -> bool:
        """Whether the parameter ``name`` may be None."""
        return False

    def _check(self, owner: str) -> None:  # noqa: B027 - a hook; most kinds take any finite value
        """Range checks of the kind's parameters (after they are known finite floats)."""

    @property
    def name(self) -> str:
        """Truth label: ``'<target>_sensor'`` or ``'<target>_actuator'`` (the FaultModel fault name)."""
        if self.location is None:
            raise ParameterError(f"fault on {self.target!r} has no location yet; resolve the scenario against a "
                                 "plant (FaultScenario.resolve) or give location='sensor' or 'actuator'")
        return sensor_fault_name(self.target) if self.location == "sensor" else actuator_fault_name(self.target)

    @property
    def spec(self) -> str:
        """The fault as a spec string (:func:`~fdikit.fault_spec.format_fault`); ``parse_fault(f.spec) == f``."""
        from fdikit.fault_spec import format_fault

        return format_fault(self)

    def active(self, t: np.ndarray) -> np.ndarray:
        """Boolean mask of the samples where the fault acts."""
        t = np.asarray(t, dtype=float)
        mask = t >= self.onset
        if self.end is not None:
            mask &= t < self.end
        return mask

    def apply(self, t: np.ndarray, v: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """The faulty signal: ``v`` (samples,) changed where the fault is active.

        Samples before the onset (and from the end on) are returned unchanged, bit for bit.

        Raises
        ------
        DataError
            When ``t`` or ``v`` is not numeric or their shapes differ.
        ParameterError
            For a :class:`Noise` fault without a generator ``rng``.
        """
        arrs = []
        for label, a in (("t", t), ("v", v)):
            try:
                arrs.append(np.asarray(a, dtype=float))
            except (TypeError, ValueError):
                raise DataError(f"{type(self).__name__}.apply: {label} must hold numbers, got {a!r:.80}") from None
        t, v = arrs
        if t.ndim != 1 or t.shape != v.shape:
            raise DataError(f"{type(self).__name__}.apply: t has shape {t.shape} and v {v.shape}; "
                            "need two 1-D arrays of the same length (one value per sample)")
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
    """Additive step: ``v + size`` (sensor bias, Douglas et al. 1996 eq. (3.3); actuator offset).

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    size : float
        The step added to the signal, in its units.

    Examples
    --------
    >>> Bias("yaw_rate", 0.02, onset=10).size
    0.02
    """

    size: float = 0.0
    _values: ClassVar[tuple[str, ...]] = ("size",)

    def _faulty(self, t, v, mask, rng):
        return v[mask] + self.size


@dataclass(frozen=True)
class Drift(Fault):
    """Ramp: ``v + rate * (t - onset)``.

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    rate : float
        Slope, in the signal's units per second.

    Examples
    --------
    >>> Drift("speed", 0.1, onset=2.0).rate
    0.1
    """

    rate: float = 0.0
    _values: ClassVar[tuple[str, ...]] = ("rate",)

    def _faulty(self, t, v, mask, rng):
        return v[mask] + self.rate * (t[mask] - self.onset)


@dataclass(frozen=True)
class Stuck(Fault):
    """Stuck-at / lock-in-place: the signal holds ``value``, or its value at onset when ``value`` is None.

    Lock-in-place of a control surface, Hallouzi 2008, §4.1; stuck actuator,
    Douglas et al. 1996, App. A (``m_i = −u_i + u_ic``).

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    value : float or None
        The value the signal holds; ``None`` (default) holds its value at the onset.

    Examples
    --------
    >>> Stuck("steering", onset=3.0).value is None
    True
    """

    value: float | None = None
    _values: ClassVar[tuple[str, ...]] = ("value",)

    def _optional(self, name: str) -> bool:
        return True

    def _faulty(self, t, v, mask, rng):
        if self.value is not None:
            return np.full(mask.sum(), float(self.value))
        first = int(np.argmax(mask))
        return np.full(mask.sum(), v[first])


@dataclass(frozen=True)
class LossOfEffectiveness(Fault):
    """Multiplicative loss: ``(1 - loss) * v`` with ``loss`` in [0, 1] (Hallouzi 2008, §4.1).

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    loss : float
        Lost fraction of the signal, in [0, 1] (1: the actuator does nothing).

    Examples
    --------
    >>> LossOfEffectiveness("throttle", 0.3).loss
    0.3
    """

    loss: float = 0.0
    _values: ClassVar[tuple[str, ...]] = ("loss",)

    def _check(self, owner: str) -> None:
        if not 0.0 <= self.loss <= 1.0:
            raise ParameterError(f"{owner}: loss of effectiveness must be in [0, 1] (0 = healthy, 1 = dead), "
                                 f"got loss={self.loss}")

    def _faulty(self, t, v, mask, rng):
        return (1.0 - self.loss) * v[mask]


@dataclass(frozen=True)
class ScaleFactor(Fault):
    """Gain error: ``factor * v`` (a sensor scale-factor fault; van der Ploeg's ``f_m``).

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    factor : float
        Multiplier of the signal (1: no fault).

    Examples
    --------
    >>> ScaleFactor("lateral_acceleration", 1.2).factor
    1.2
    """

    factor: float = 1.0
    _values: ClassVar[tuple[str, ...]] = ("factor",)

    def _faulty(self, t, v, mask, rng):
        return self.factor * v[mask]


@dataclass(frozen=True)
class Noise(Fault):
    """Extra zero-mean Gaussian noise of standard deviation ``std``.

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    std : float
        Standard deviation of the added noise (>= 0), in the signal's units.

    Examples
    --------
    >>> Noise("yaw_rate", 0.01).std
    0.01
    """

    std: float = 0.0
    _values: ClassVar[tuple[str, ...]] = ("std",)

    def _check(self, owner: str) -> None:
        if not self.std >= 0:
            raise ParameterError(f"{owner}: noise std must be >= 0, got std={self.std}")

    def _faulty(self, t, v, mask, rng):
        if not isinstance(rng, np.random.Generator):
            raise ParameterError(f"a Noise fault on {self.target!r} needs rng, a numpy.random.Generator "
                                 f"(got {type(rng).__name__}; pass rng= or seed= to simulate)")
        return v[mask] + self.std * rng.standard_normal(mask.sum())


@dataclass(frozen=True)
class Intermittent(Fault):
    """Bias ``size`` switched on for ``duty * period`` seconds out of every ``period`` after onset.

    The target, onset, end and location are those of :class:`Fault`.

    Parameters
    ----------
    size : float
        The step added while on.
    period : float
        Period [s] (> 0, default 1).
    duty : float
        On fraction of each period, in (0, 1] (default 0.5).

    Examples
    --------
    >>> Intermittent("speed", 0.2, period=2.0, duty=0.25).active([0.0, 0.4, 0.6, 2.1]).tolist()
    [True, True, False, True]
    """

    size: float = 0.0
    period: float = 1.0
    duty: float = 0.5
    _values: ClassVar[tuple[str, ...]] = ("size", "period", "duty")

    def _check(self, owner: str) -> None:
        if not self.period > 0:
            raise ParameterError(f"{owner}: intermittent fault needs period > 0, got period={self.period}")
        if not 0 < self.duty <= 1:
            raise ParameterError(f"{owner}: intermittent fault needs a duty in (0, 1] (0 < duty <= 1), "
                                 f"got duty={self.duty}")

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
        Applied in this order to each signal (so ``[ScaleFactor, Bias]`` on one actuator gives
        ``factor * u + size``).
    label : str, optional
        Defaults to the names of the faults joined by ``'+'``, or ``'none'``.

    Raises
    ------
    ParameterError
        When ``faults`` is not an iterable of :class:`Fault` or ``label`` is not a non-empty str.

    Examples
    --------
    >>> FaultScenario([Bias("yaw_rate", 0.02, onset=10)]).label
    'yaw_rate'
    """

    def __init__(self, faults: Iterable[Fault] = (), label: str | None = None) -> None:
        if isinstance(faults, Fault):
            raise ParameterError("FaultScenario: faults must be an iterable of Fault objects; "
                                 f"wrap the single fault in a list: FaultScenario([{faults!r}])")
        if isinstance(faults, str):
            raise ParameterError(f"FaultScenario: faults must be Fault objects, got the str {faults!r}; "
                                 "read spec strings with fdikit.fault_spec.parse_fault")
        try:
            self.faults: tuple[Fault, ...] = tuple(faults)
        except TypeError:
            raise ParameterError(f"FaultScenario: faults must be an iterable of Fault objects, "
                                 f"got {type(faults).__name__}") from None
        for f in self.faults:
            if not isinstance(f, Fault):
                hint = "; read spec strings with fdikit.fault_spec.parse_fault" if isinstance(f, str) else ""
                raise ParameterError(f"a FaultScenario holds Fault objects, got {type(f).__name__} {f!r:.60}{hint}")
        if label is not None and (not isinstance(label, str) or not label):
            raise ParameterError(f"FaultScenario: label must be a non-empty str (or None), got {label!r}")
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
        ParameterError
            For a target the plant does not have, a location that does not match, or an
            ambiguous name (both an output and a control) without an explicit location.
        """
        outputs, controls = list(outputs), list(controls)
        resolved = []
        for f in self.faults:
            is_out, is_ctl = f.target in outputs, f.target in controls
            loc = f.location
            if loc is None:
                if is_out and is_ctl:
                    raise ParameterError(
                        f"{f.target!r} is both an output and a control of the plant; "
                        "give the fault location='sensor' or location='actuator'"
                    )
                loc = "sensor" if is_out else "actuator" if is_ctl else None
            if (loc == "sensor" and not is_out) or (loc == "actuator" and not is_ctl) or loc is None:
                raise ParameterError(
                    f"the plant has no {'sensor' if loc == 'sensor' else 'actuator' if loc else 'signal'} "
                    f"named {f.target!r}; its outputs are {outputs} and its controls {controls}"
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
