"""Reference trajectories for the FTC flights: hold, turn to a new heading, descend at a fixed flight-path angle.

Hallouzi 2008, §6.5.1: straight and level at 980 m and 92.6 m/s on heading 180°; at T = 75 s a heading
change to 60°; at T = 150 s a descent to 100 m at γ = −5°; sideslip held at zero.  The text does not give
the profiles' shapes; chosen here (and documented in ``docs/methods/ftc.md``):

* the heading reference turns at a constant rate (default 3 °/s, a standard-rate turn) the short way
  round;
* the altitude reference descends as ``h_ref(t) = h_0 + V sin γ (t − t_0)``, floored at the target;
* the airspeed reference is held (a fault-dependent change, as after the elevator lock of §6.5.2, is a
  :meth:`FlightPlan.with_airspeed` step).

References
----------
Hallouzi 2008, §6.5.1, §6.5.2.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["FlightPlan", "nominal_plan"]


@dataclass(frozen=True)
class FlightPlan:
    """Piecewise references for heading, altitude, airspeed and sideslip (angles in rad, SI units).

    Attributes
    ----------
    heading0, heading1 : float
        Initial and final heading [rad].
    turn_start : float
        Time the turn starts [s].
    turn_rate : float
        Heading-reference rate [rad/s] (> 0).
    altitude0, altitude1 : float
        Initial and final altitude [m].
    descent_start : float
        Time the descent starts [s].
    flight_path_angle : float
        γ of the climb or descent [rad] (its sign must take altitude0 towards altitude1).
    airspeed : float
        True-airspeed reference [m/s].
    airspeed_steps : tuple of (float, float)
        ``(time, airspeed)`` changes after the start, in time order.

    Examples
    --------
    >>> plan = nominal_plan()
    >>> round(float(np.degrees(plan.heading(85.0))), 6), round(plan.altitude(160.0), 3)
    (150.0, 899.294)

    References
    ----------
    Hallouzi 2008, §6.5.1.
    """

    heading0: float
    heading1: float
    turn_start: float
    turn_rate: float
    altitude0: float
    altitude1: float
    descent_start: float
    flight_path_angle: float
    airspeed: float
    airspeed_steps: tuple = ()

    def heading(self, t: float) -> float:
        """The heading reference [rad, in (−π, π]] at ``t``.

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        float
        """
        change = np.angle(np.exp(1j * (self.heading1 - self.heading0)))      # the short way round
        done = max(0.0, t - self.turn_start) * self.turn_rate
        psi = self.heading0 + np.sign(change) * min(done, abs(change))
        return float(np.angle(np.exp(1j * psi)))

    def altitude(self, t: float) -> float:
        """The altitude reference [m] at ``t``.

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        float
        """
        rate = self.airspeed_at(t) * np.sin(self.flight_path_angle)
        h = self.altitude0 + rate * max(0.0, t - self.descent_start)
        lo, hi = sorted((self.altitude0, self.altitude1))
        return float(min(max(h, lo), hi))

    def airspeed_at(self, t: float) -> float:
        """The true-airspeed reference [m/s] at ``t``.

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        float
        """
        v = self.airspeed
        for when, value in self.airspeed_steps:
            if t >= when:
                v = value
        return float(v)

    def with_airspeed(self, t: float, airspeed: float) -> FlightPlan:
        """The plan with the airspeed reference changed to ``airspeed`` from ``t`` on (§6.5.2).

        Parameters
        ----------
        t : float
            Time of the change [s].
        airspeed : float
            New reference [m/s].

        Returns
        -------
        FlightPlan
        """
        steps = tuple(sorted(self.airspeed_steps + ((validate.number("t", t), validate.positive("airspeed",
                                                                                                  airspeed)),)))
        return replace(self, airspeed_steps=steps)


def nominal_plan(*, altitude: float = 980.0, airspeed: float = 92.6, heading: float = 180.0,
                 new_heading: float = 60.0, turn_start: float = 75.0, turn_rate: float = 3.0,
                 descent_start: float = 150.0, target_altitude: float = 100.0,
                 flight_path_angle: float = -5.0) -> FlightPlan:
    """The §6.5.1 scenario: hold, turn 180° → 60° at 75 s, descend to 100 m at γ = −5° from 150 s.

    Parameters
    ----------
    altitude, airspeed : float
        Initial altitude [m] and airspeed [m/s].
    heading, new_heading : float
        Initial and final heading [deg].
    turn_start : float
        Turn start [s].
    turn_rate : float
        Heading-reference rate [deg/s] (default 3, a standard-rate turn; not given by the thesis).
    descent_start, target_altitude : float
        Descent start [s] and final altitude [m].
    flight_path_angle : float
        γ [deg] (negative for a descent).

    Returns
    -------
    FlightPlan

    Raises
    ------
    ParameterError
        A non-positive turn rate or airspeed, or a γ whose sign does not lead to the target altitude.

    Examples
    --------
    >>> plan = nominal_plan()
    >>> round(float(np.degrees(plan.heading(200.0))), 6), plan.altitude(1000.0)
    (60.0, 100.0)

    References
    ----------
    Hallouzi 2008, §6.5.1.
    """
    gamma = np.radians(validate.number("flight_path_angle", flight_path_angle))
    if (target_altitude - altitude) * gamma < 0 or (gamma == 0 and target_altitude != altitude):
        raise ParameterError(f"flight_path_angle = {np.degrees(gamma):g} deg does not lead from {altitude:g} m to "
                             f"{target_altitude:g} m; use a negative angle to descend and a positive one to climb.")
    return FlightPlan(heading0=np.radians(validate.number("heading", heading)),
                      heading1=np.radians(validate.number("new_heading", new_heading)),
                      turn_start=validate.number("turn_start", turn_start),
                      turn_rate=np.radians(validate.positive("turn_rate", turn_rate)),
                      altitude0=validate.number("altitude", altitude),
                      altitude1=validate.number("target_altitude", target_altitude),
                      descent_start=validate.number("descent_start", descent_start),
                      flight_path_angle=float(gamma), airspeed=validate.positive("airspeed", airspeed))

