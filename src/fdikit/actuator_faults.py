"""Faults of control surfaces and engines that travel: lock-in-place at a rate, runaway, float, engine failure.

Hallouzi 2008, §4.2 and Fig. 4.1: a lock-in-place (LIP) surface freezes at a position
``δ^ε ∈ [δ^min, δ^max]`` that need not be the one it had — it moves *at its maximum rate* to the
lock position and stays there; a runaway (hard-over) is LIP at a limit reached at the runaway
rate (§6.5.3: the rudders run to 25 deg at 50 deg/s). :class:`fdikit.faults.Stuck` jumps at once;
these kinds travel. They are :class:`fdikit.faults.Fault` kinds, so scenarios, truth labels and
offline ``apply`` work as for every other fault; online, the aircraft actuators
(:class:`fdikit.aircraft.actuators.ActuatorBank`) move the surface to ``position`` at
``min(rate, the actuator's rate limit)``.

``apply`` on a sampled signal moves from the signal's value at the onset towards the lock position
at ``rate`` (units per second; ``None``: at once).

References
----------
Hallouzi 2008, §4.2, Fig. 4.1 (LIP and runaway), §6.5.3 (rudder runaway at 50 deg/s), §4.3.2
(engine separation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from fdikit.errors import ParameterError
from fdikit.faults import Fault

__all__ = ["TravelFault", "LockInPlace", "Runaway", "Float", "EngineFailure"]


@dataclass(frozen=True)
class TravelFault(Fault):
    """Base of the faults that drive a surface to a position at a rate (not used directly).

    The target, onset, end and location are those of :class:`fdikit.faults.Fault`.

    Parameters
    ----------
    position : float
        The lock position, in the signal's units (rad for a surface).
    rate : float or None
        Travel rate [units/s] (> 0); ``None``: the actuator's own rate limit (online) or at once (offline).

    Examples
    --------
    >>> lip = LockInPlace("elevator", position=0.1, rate=0.5, onset=1.0)
    >>> lip.apply([0.0, 1.0, 1.1, 2.0], [0.0] * 4).round(3).tolist()
    [0.0, 0.0, 0.05, 0.1]
    """

    position: float = 0.0
    rate: float | None = None
    _values: ClassVar[tuple[str, ...]] = ("position", "rate")

    def _optional(self, name: str) -> bool:
        return name == "rate"

    def _check(self, owner: str) -> None:
        if self.rate is not None and not self.rate > 0:
            raise ParameterError(f"{owner}: the travel rate must be > 0 (units per second), got rate={self.rate}; "
                                 "use rate=None for the actuator's own rate limit")

    def _faulty(self, t, v, mask, rng):
        first = int(np.argmax(mask))
        start, goal = v[first], self.position
        if self.rate is None:
            return np.full(mask.sum(), goal)
        step = self.rate * (t[mask] - t[first])
        return start + np.clip(goal - start, -step, step)


@dataclass(frozen=True)
class LockInPlace(TravelFault):
    """Lock-in-place (Hallouzi 2008, §4.2): the surface travels at its maximum rate to ``position`` and stays.

    Parameters
    ----------
    position : float
        The lock position (rad for a surface); it may differ from the position at the onset.
    rate : float or None
        Travel rate [units/s]; ``None`` (default): the actuator's rate limit (offline: at once).

    Examples
    --------
    >>> LockInPlace("rudder", position=-0.2, onset=20.0).position
    -0.2
    """


@dataclass(frozen=True)
class Runaway(TravelFault):
    """Runaway / hard-over (Hallouzi 2008, §6.5.3): the surface runs at ``rate`` to ``position`` (a limit) and sticks.

    Parameters
    ----------
    position : float
        The limit the surface runs to.
    rate : float
        The runaway rate [units/s] (required; capped online by the actuator's rate limit).

    Examples
    --------
    >>> import numpy as np
    >>> Runaway("rudder", position=np.radians(25), rate=np.radians(50), onset=18.0).rate > 0
    True
    """

    def _check(self, owner: str) -> None:
        if self.rate is None:
            raise ParameterError(f"{owner}: a runaway needs its rate (units per second), e.g. rate=np.radians(50)")
        super()._check(owner)


@dataclass(frozen=True)
class Float(TravelFault):
    """Floating surface: the actuator lets go and the surface trails the flow (zero hinge moment).

    Approximation: the hinge moment is not modelled; the surface is taken to trail at ``position``
    (default 0, faired with the wing or tail) and to get there at ``rate``.

    Parameters
    ----------
    position : float
        The trail position (default 0).
    rate : float or None
        Travel rate [units/s]; ``None``: the actuator's rate limit.

    Examples
    --------
    >>> Float("aileron", onset=5.0).position
    0.0
    """


@dataclass(frozen=True)
class EngineFailure(Fault):
    """Engine failure: no thrust from the onset (online: fuel cut off, the engine spools down).

    Offline ``apply`` sets the signal to zero.

    Parameters
    ----------
    target : str
        The engine's throttle, ``throttle_<i>`` (1-based engine number).
    onset : float
        Time of the failure [s]; ``end`` and ``location`` as for :class:`fdikit.faults.Fault`.

    Examples
    --------
    >>> EngineFailure("throttle_3", onset=95.0).apply([90.0, 95.0], [0.6, 0.6]).tolist()
    [0.6, 0.0]
    """

    def _faulty(self, t, v, mask, rng):
        return np.zeros(mask.sum())
