"""Multi-rate execution: rate groups stepped at integer multiples of a base period, with per-call timings.

Hallouzi 2008, §6.6, Fig. 6.14: the B747 runs at 100 Hz with the light computations (the multiple-model
FDI) in the same block, the SPC (predictor update and QP) in a 10 Hz block; the result of the slow block
is applied one slow period later (the one-sample computation delay of §6.3.1).  :class:`MultiRate` calls
each group's function on its ticks and records how long every call took, so the slow block's worst case
can be compared with its period — the thesis's real-time question (m = 5 fitted, m = 7 did not).

References
----------
Hallouzi 2008, §6.6, Fig. 6.14.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["MultiRate", "RateGroup"]


@dataclass
class RateGroup:
    """A function called every ``every`` base ticks, and the wall times of its calls.

    Attributes
    ----------
    name : str
        Group name (e.g. ``"fdi 100 Hz"``).
    every : int
        Period in base ticks (≥ 1).
    function : callable
        Called as ``function(tick, t)``.
    seconds : list of float
        Wall time of each call.

    Examples
    --------
    >>> g = RateGroup("slow", 10, lambda k, t: None)
    >>> g.every
    10

    References
    ----------
    Hallouzi 2008, §6.6.
    """

    name: str
    every: int
    function: object
    seconds: list = field(default_factory=list)

    def timing(self, period: float) -> dict:
        """Median, 99th percentile and worst call time, and the worst as a fraction of the group period.

        Parameters
        ----------
        period : float
            The group's period [s] (base period × ``every``).

        Returns
        -------
        dict
            ``calls``, ``median``, ``p99``, ``worst`` [s] and ``budget_used`` (worst / period).
        """
        s = np.asarray(self.seconds, dtype=float)
        if s.size == 0:
            return {"calls": 0, "median": float("nan"), "p99": float("nan"), "worst": float("nan"),
                    "budget_used": float("nan")}
        return {"calls": int(s.size), "median": float(np.median(s)), "p99": float(np.percentile(s, 99)),
                "worst": float(s.max()), "budget_used": float(s.max() / period)}


class MultiRate:
    """Step rate groups on a common base period; groups due on the same tick run in the order added.

    Parameters
    ----------
    dt : float
        Base period [s] (e.g. 0.01 for the 100 Hz plant).

    Examples
    --------
    >>> calls = []
    >>> mr = MultiRate(0.01)
    >>> fast = mr.add("fast", 1, lambda k, t: calls.append(("fast", k)))
    >>> slow = mr.add("slow", 10, lambda k, t: calls.append(("slow", k)))
    >>> mr.run(20)
    >>> sum(1 for c in calls if c[0] == "slow"), sum(1 for c in calls if c[0] == "fast")
    (2, 20)

    References
    ----------
    Hallouzi 2008, §6.6, Fig. 6.14.
    """

    def __init__(self, dt: float) -> None:
        self.dt = validate.positive("dt", dt)
        self.groups: list[RateGroup] = []
        self.tick = 0

    def add(self, name: str, every: int, function) -> RateGroup:
        """Add a group called every ``every`` base ticks (on ticks 0, every, 2·every, …).

        Parameters
        ----------
        name : str
        every : int
        function : callable
            ``function(tick, t)``.

        Returns
        -------
        RateGroup

        Raises
        ------
        ParameterError
            A repeated name, ``every < 1`` or a non-callable.
        """
        every = validate.integer("every", every, minimum=1)
        if any(g.name == name for g in self.groups):
            raise ParameterError(f"a rate group named {name!r} exists; give each group its own name.")
        if not callable(function):
            raise ParameterError(f"the function of rate group {name!r} must be callable as function(tick, t).")
        group = RateGroup(name, every, function)
        self.groups.append(group)
        return group

    def run(self, ticks: int) -> None:
        """Run ``ticks`` base ticks from the current one.

        Parameters
        ----------
        ticks : int
        """
        for _ in range(validate.integer("ticks", ticks, minimum=0)):
            t = self.tick * self.dt
            for g in self.groups:
                if self.tick % g.every == 0:
                    t0 = time.perf_counter()
                    g.function(self.tick, t)
                    g.seconds.append(time.perf_counter() - t0)
            self.tick += 1

    def timings(self) -> dict:
        """:meth:`RateGroup.timing` of every group, by name.

        Returns
        -------
        dict
        """
        return {g.name: g.timing(self.dt * g.every) for g in self.groups}
