"""The outer loops of the FTC architecture: altitude → pitch and heading → roll references for the inner SPC.

Hallouzi 2008, §6.2, (6.1)–(6.2), Fig. 6.1: two PID loops on ``measured − reference`` turn the altitude and
heading errors into the pitch and roll references of the inner controller; the airspeed reference passes
straight through and the sideslip reference is zero. The thesis gives neither gains nor the anti-windup
scheme; chosen here (documented in ``docs/methods/ftc.md``):

* altitude: ``θ_ref = θ_trim + γ_ref + PID(h − h_ref)`` with ``k_p = −0.05 °/m``, ``k_i = −0.005 °/(m s)``,
  ``k_d = −0.3 °/(m/s)`` and a 1-s derivative filter, limited to ``θ_trim ± 10°``; ``γ_ref`` (the plan's
  flight-path angle) is fed forward, so the integrator does not have to build the descent attitude;
* heading: ``φ_ref = PID(ψ − ψ_ref)`` with the error wrapped to ±180°, ``k_p = −1.5``, ``k_i = −0.01 /s``,
  limited to ±30° (a 3 °/s turn at 92.6 m/s needs 26°);
* anti-windup by clamping (:class:`fdikit.ftc.pid.PID`).

References
----------
Hallouzi 2008, §6.2, (6.1)–(6.2), Fig. 6.1; §6.5.1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate

__all__ = ["OuterLoops", "outer_loops"]


@dataclass
class OuterLoops:
    """Altitude and heading PIDs producing the ``φ, θ, V_TAS, β`` references of the inner loop.

    Attributes
    ----------
    altitude : PID
        On ``h − h_ref`` [m], output the pitch change [deg].
    heading : PID
        On the wrapped ``ψ − ψ_ref`` [deg], output the roll reference [deg].
    pitch_trim : float
        ``θ`` at the trim [deg].
    feedforward : bool
        Add the plan's flight-path angle to the pitch reference.

    Examples
    --------
    >>> from fdikit.ftc.references import nominal_plan
    >>> loops = outer_loops(0.1, pitch_trim=2.0)
    >>> phi, theta, v, beta = loops.references(0.0, nominal_plan(), altitude=980.0, heading=np.pi)
    >>> float(phi + 0.0), float(theta), v, beta
    (0.0, 2.0, 92.6, 0.0)

    References
    ----------
    Hallouzi 2008, §6.2, (6.1)–(6.2).
    """

    altitude: object
    heading: object
    pitch_trim: float
    feedforward: bool = True

    def references(self, t: float, plan, *, altitude: float, heading: float) -> tuple[float, float, float, float]:
        """The inner-loop references at ``t`` for the measured altitude and heading.

        Parameters
        ----------
        t : float
            Time [s].
        plan : FlightPlan
            :class:`fdikit.ftc.references.FlightPlan`.
        altitude : float
            Measured altitude [m].
        heading : float
            Measured heading [rad].

        Returns
        -------
        phi_ref, theta_ref : float
            Roll and pitch references [deg].
        airspeed_ref : float
            [m/s].
        beta_ref : float
            Sideslip reference [deg] (zero).
        """
        v = plan.airspeed_at(t)
        gamma = 0.0
        if self.feedforward:
            dt = self.altitude.dt
            climb = (plan.altitude(t + dt) - plan.altitude(t)) / dt
            gamma = float(np.degrees(np.arcsin(np.clip(climb / v, -1.0, 1.0))))
        theta = self.pitch_trim + gamma + self.altitude.step(altitude - plan.altitude(t))
        err = float(np.degrees((heading - plan.heading(t) + np.pi) % (2 * np.pi) - np.pi))
        phi = self.heading.step(err)
        return phi, theta, v, 0.0


def outer_loops(dt: float, pitch_trim: float, *, altitude_gains=(-0.05, -0.005, -0.3),
                heading_gains=(-1.5, -0.01, 0.0), pitch_range: float = 10.0, roll_limit: float = 30.0) -> OuterLoops:
    """The outer loops with the gains of the module docstring.

    Parameters
    ----------
    dt : float
        Sample time [s] (the SPC's, 0.1 s).
    pitch_trim : float
        ``θ`` at the trim [deg].
    altitude_gains, heading_gains : tuple of float, optional
        ``(k_p, k_i, k_d)`` on ``measured − reference`` (negative: a climb needs more pitch).
    pitch_range : float, optional
        Pitch-change limit [deg].
    roll_limit : float, optional
        Roll-reference limit [deg].

    Returns
    -------
    OuterLoops

    Raises
    ------
    ParameterError
        A non-positive step or limit.

    Examples
    --------
    >>> outer_loops(0.1, 2.0).heading.output_max
    30.0

    References
    ----------
    Hallouzi 2008, §6.2, (6.1)–(6.2).
    """
    from fdikit.ftc.pid import PID

    pitch_range = validate.positive("pitch_range", pitch_range)
    roll_limit = validate.positive("roll_limit", roll_limit)
    alt = PID(*altitude_gains, dt=dt, output_min=-pitch_range, output_max=pitch_range, derivative_filter=1.0)
    hdg = PID(*heading_gains, dt=dt, output_min=-roll_limit, output_max=roll_limit)
    return OuterLoops(alt, hdg, float(validate.number("pitch_trim", pitch_trim)))
