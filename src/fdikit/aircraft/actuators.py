"""Control-surface actuators: position limits, rate limits, a first-order lag, and faults on the way.

Each surface follows ``δ̇ = clip((δ_c − δ)/τ, −rate_down, rate_up)`` with ``δ_c`` the command clipped
to the position limits, integrated exactly over a step for the lag and then rate-limited. Faults
(:mod:`fdikit.faults`, :mod:`fdikit.actuator_faults`) on ``<surface>`` act here, before JSBSim:

* :class:`~fdikit.actuator_faults.LockInPlace`, :class:`~fdikit.actuator_faults.Runaway`,
  :class:`~fdikit.actuator_faults.Float` replace the command by their position (clipped to the
  limits) and the surface travels there at ``min(fault rate, rate limit)`` — Hallouzi's Fig. 4.1;
* :class:`~fdikit.faults.Stuck` holds the position the surface had at the onset (or its value);
* every other kind (loss of effectiveness, bias, scale factor …) changes the command.

The B747 limits are Hallouzi's App. A (Table A.2, after Hanke & Nordwall 1970), lumped: elevator
−23…17 deg at 37 deg/s, ailerons ±20 deg at 40/45 deg/s (down/up; the inner ailerons' range, also
JSBSim's own aileron range — Ch. 4 sweeps the aileron LIP over ±15 deg only), rudder ±25 deg at
50 deg/s, flaps 0…25 deg at 1.8 deg/s, stabiliser −12…3 deg at 0.5 deg/s (App. A: 0.2 to 0.5).
Other aircraft get their JSBSim FCS ranges and 60 deg/s.

References
----------
Hallouzi 2008, App. A, Table A.2; §4.2, Fig. 4.1; Hanke & Nordwall 1970.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.actuator_faults import TravelFault
from fdikit.errors import ParameterError
from fdikit.faults import Stuck

__all__ = ["B747_LIMITS", "ActuatorBank", "SurfaceLimits", "default_limits"]


@dataclass(frozen=True)
class SurfaceLimits:
    """Position and rate limits of one surface actuator, and its lag.

    Attributes
    ----------
    lower, upper : float
        Position limits [rad].
    rate_down, rate_up : float
        Rate limits [rad/s] towards ``lower`` and towards ``upper`` (> 0).
    lag : float
        Time constant τ [s] of the first-order actuator (default 0.05; 0: rate limit only).

    Examples
    --------
    >>> SurfaceLimits(-0.4, 0.3, 0.6, 0.6).upper
    0.3
    """

    lower: float
    upper: float
    rate_down: float
    rate_up: float
    lag: float = 0.05

    def __post_init__(self) -> None:
        if not validate.number("lower", self.lower) < validate.number("upper", self.upper):
            raise ParameterError(f"SurfaceLimits: lower ({self.lower}) must be below upper ({self.upper}).")
        validate.positive("rate_down", self.rate_down)
        validate.positive("rate_up", self.rate_up)
        validate.non_negative("lag", self.lag)


def _deg(lo, hi, down, up) -> SurfaceLimits:
    return SurfaceLimits(*np.radians([lo, hi, down, up]).tolist())


#: Hallouzi 2008, App. A (Table A.2), lumped as in Ch. 4.
B747_LIMITS = {
    "elevator": _deg(-23, 17, 37, 37),
    "aileron": _deg(-20, 20, 40, 45),
    "rudder": _deg(-25, 25, 50, 50),
    "flap": _deg(0, 25, 1.8, 1.8),
    "stabilizer": _deg(-12, 3, 0.5, 0.5),
}


def default_limits(definition) -> dict:
    """The actuator limits of a prepared aircraft: App. A for the B747, the FCS ranges otherwise.

    Parameters
    ----------
    definition : AircraftDefinition

    Returns
    -------
    dict
        Surface → :class:`SurfaceLimits`.

    Examples
    --------
    >>> from fdikit.aircraft.definition import prepare_aircraft
    >>> round(float(np.degrees(default_limits(prepare_aircraft("B747"))["rudder"].upper)), 6)
    25.0
    """
    if definition.name == "B747":
        return {s: B747_LIMITS[s] for s in definition.surfaces}
    out = {}
    for s in definition.surfaces:
        rng = definition.ranges.get(s)
        if s == "flap":
            out[s] = _deg(0, 40, 3, 3)
        else:
            lo, hi = rng if rng is not None else (-np.radians(25), np.radians(25))
            out[s] = SurfaceLimits(min(lo, -1e-3), max(hi, 1e-3), np.radians(60), np.radians(60))
    return out


class ActuatorBank:
    """The surface actuators of an aircraft, with their faults.

    Parameters
    ----------
    limits : mapping
        Surface → :class:`SurfaceLimits`.

    Attributes
    ----------
    positions : dict
        Current surface positions [rad].
    faults : list
        The faults acting on the surfaces (set with :meth:`inject`).

    Examples
    --------
    >>> bank = ActuatorBank(B747_LIMITS)
    >>> p = bank.update({"elevator": 1.0}, 0.0, 0.1)
    >>> round(float(np.degrees(p["elevator"])), 6)   # 0.1 s at 37 deg/s
    3.7
    """

    def __init__(self, limits: Mapping) -> None:
        self.limits = dict(limits)
        self.positions = dict.fromkeys(self.limits, 0.0)
        self.faults: list = []
        self._held: dict = {}

    def inject(self, faults) -> None:
        """Set the surface faults (replacing earlier ones).

        Parameters
        ----------
        faults : iterable of Fault
            Faults whose target is a surface of the bank.

        Raises
        ------
        ParameterError
            For a target that is not a surface.
        """
        faults = list(faults)
        for f in faults:
            if f.target not in self.limits:
                raise ParameterError(f"no actuator {f.target!r}; the surfaces are {', '.join(self.limits)}.")
        self.faults = faults
        self._held = {}

    def place(self, positions: Mapping) -> None:
        """Put surfaces at positions [rad] at once (for trim and linearisation; no limits applied).

        Parameters
        ----------
        positions : mapping
        """
        for s, v in positions.items():
            if s not in self.positions:
                raise ParameterError(f"no actuator {s!r}; the surfaces are {', '.join(self.limits)}.")
            self.positions[s] = float(v)

    def update(self, commands: Mapping, t: float, dt: float) -> dict:
        """Move every surface one step towards its (possibly faulty) command.

        Parameters
        ----------
        commands : mapping
            Surface → commanded position [rad].
        t : float
            Time at the start of the step [s] (faults are active from their onset).
        dt : float
            Step [s].

        Returns
        -------
        dict
            The new positions (also in :attr:`positions`).
        """
        tt = np.array([t])
        for s, lim in self.limits.items():
            cmd, rate_cap = float(commands.get(s, self.positions[s])), np.inf
            for f in self.faults:
                if f.target != s or not f.active(tt)[0]:
                    continue
                if isinstance(f, TravelFault):
                    cmd = f.position
                    rate_cap = f.rate if f.rate is not None else np.inf
                elif isinstance(f, Stuck):
                    cmd = self._held.setdefault(id(f), self.positions[s] if f.value is None else f.value)
                    rate_cap = 0.0 if f.value is None else np.inf
                else:
                    cmd = float(f.apply(tt, np.array([cmd]))[0])
            cmd = min(max(cmd, lim.lower), lim.upper)
            pos = self.positions[s]
            move = (cmd - pos) * (-np.expm1(-dt / lim.lag) if lim.lag > 0 else 1.0)
            up, down = min(lim.rate_up, rate_cap) * dt, min(lim.rate_down, rate_cap) * dt
            self.positions[s] = pos + min(max(move, -down), up)
        return dict(self.positions)

    def snapshot(self) -> tuple:
        """The bank's state, for :meth:`restore`.

        Returns
        -------
        tuple
        """
        return dict(self.positions), dict(self._held)

    def restore(self, state) -> None:
        """Restore a :meth:`snapshot`.

        Parameters
        ----------
        state : tuple
        """
        if state is not None:
            self.positions, self._held = dict(state[0]), dict(state[1])
