"""A documented state-feedback autopilot: LQR on the nominal linear model, holding the trim.

Hallouzi's nonlinear isolation study (§4.4.2) flies the aircraft with the subspace predictive
controller of Ch. 5–6; until fdikit has it, this autopilot holds the trim the way the thesis's
linear study does (§4.4.1: LQR, "because the fault models are unstable"): ``u = u° − K (x̂ − x°)``
with ``K`` the continuous LQR gain of the nominal model (:func:`scipy.linalg.solve_continuous_are`),
weights by Bryson's rule (``Q = diag(1/x_max²)``, ``R = diag(1/u_max²)``), and ``x̂`` the measured
rigid-body state (the first ten sensors: rates, airspeed, α, β, attitudes, altitude — an aircraft
has all of them). The heading error is wrapped to ±π. The stabiliser stays at its trim (a trim
surface at 0.5 deg/s, not a control surface), the thrust command becomes a throttle through the
engines' steady-state slope, and the surface commands are clipped by the actuators.

It holds altitude, speed, heading and wings level against turbulence; it does not adapt to a
fault (a locked elevator leaves pitch to the remaining inputs, and the aircraft may depart).

References
----------
Hallouzi 2008, §4.4.1 (LQR closed loop), §4.4.2 and Ch. 6 (the SPC autopilot this stands in for).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

__all__ = ["BRYSON_STATE", "BRYSON_INPUT", "LQRAutopilot", "lqr_autopilot"]

#: Bryson's-rule maximum deviations of :data:`fdikit.aircraft.plant.STATES` (rad, rad/s, m/s, m).
BRYSON_STATE = {"roll_rate": np.radians(5), "pitch_rate": np.radians(3), "yaw_rate": np.radians(3),
                "true_airspeed": 2.0, "alpha": np.radians(2), "beta": np.radians(1), "roll": np.radians(5),
                "pitch": np.radians(3), "heading": np.radians(3), "altitude": 10.0}
#: Bryson's-rule maximum inputs (rad; thrust N).
BRYSON_INPUT = {"aileron": np.radians(5), "elevator": np.radians(5), "rudder": np.radians(5), "thrust": 50e3}


@dataclass(frozen=True)
class LQRAutopilot:
    """LQR state feedback around a trim (see the module docstring).

    Attributes
    ----------
    K : ndarray
        Gain (inputs × 10 states), ``u − u° = −K (x − x°)``.
    inputs : tuple of str
        The controlled inputs (of ``aileron, elevator, rudder, thrust``).
    x0 : ndarray
        The trim state.
    u0 : dict
        The trim commands: surfaces [rad], ``thrust`` [N] and the trim throttle.
    thrust_slope : float
        ``∂T/∂throttle`` [N].

    Examples
    --------
    >>> from fdikit.aircraft import JSBSimAircraft, trim_aircraft, linearize_aircraft, HALLOUZI_POINT
    >>> ac = JSBSimAircraft("B747")
    >>> ap = lqr_autopilot(linearize_aircraft(ac, trim_aircraft(ac, HALLOUZI_POINT)))
    >>> ap.K.shape, ap.inputs
    ((4, 10), ('aileron', 'elevator', 'rudder', 'thrust'))
    """

    K: np.ndarray
    inputs: tuple
    x0: np.ndarray
    u0: dict
    thrust_slope: float

    def commands(self, y, setpoint: Mapping | None = None) -> dict:
        """Commands for :meth:`fdikit.aircraft.plant.JSBSimAircraft.set_inputs` from the sensors.

        Parameters
        ----------
        y : array_like
            The sensors (:data:`fdikit.aircraft.plant.SENSORS`; the first ten are used).
        setpoint : mapping, optional
            State name → value (SI) replacing the trim value the state is held at — e.g. ``heading`` and
            ``altitude`` moved along a flight plan (the gain stays the trim's).

        Returns
        -------
        dict
            Surface commands [rad], under ``"thrust"`` the thrust command [N] and under ``"throttle"`` the
            throttle of every engine.
        """
        x_ref = self.x0
        if setpoint:
            from fdikit.aircraft.plant import STATES

            x_ref = self.x0.copy()
            for name, value in setpoint.items():
                x_ref[STATES.index(name)] = value
        dx = np.asarray(y, dtype=float)[:10] - x_ref
        dx[8] = (dx[8] + np.pi) % (2 * np.pi) - np.pi
        du = -self.K @ dx
        out = {name: self.u0[name] + d for name, d in zip(self.inputs, du, strict=True)}
        out["throttle"] = self.u0["throttle"] + (out["thrust"] - self.u0["thrust"]) / self.thrust_slope
        return out

    def apply(self, aircraft, y, setpoint: Mapping | None = None) -> dict:
        """Set the aircraft's surface and throttle commands from the sensors (:meth:`commands`).

        Parameters
        ----------
        aircraft : JSBSimAircraft
        y : array_like
            Its sensors.
        setpoint : mapping, optional
            As for :meth:`commands`.

        Returns
        -------
        dict
            The commands (:meth:`commands`).
        """
        c = self.commands(y, setpoint)
        aircraft.set_inputs(**{n: c[n] for n in self.inputs if n != "thrust"},
                            **{f"throttle_{i + 1}": c["throttle"] for i in range(aircraft.engines)})
        return c


def lqr_autopilot(linearization, state_max: Mapping | None = None, input_max: Mapping | None = None,
                  inputs=("aileron", "elevator", "rudder", "thrust")) -> LQRAutopilot:
    """The LQR autopilot of a trimmed aircraft's linear model (Bryson's-rule weights).

    Parameters
    ----------
    linearization : AircraftLinearization
        :func:`fdikit.aircraft.linearize.linearize_aircraft` at the trim to hold.
    state_max, input_max : mapping, optional
        Bryson's maximum deviations (defaults :data:`BRYSON_STATE`, :data:`BRYSON_INPUT`).
    inputs : sequence of str, optional
        The inputs the autopilot moves.

    Returns
    -------
    LQRAutopilot

    Raises
    ------
    ParameterError
        For an input the linear model does not have.

    Examples
    --------
    >>> from fdikit.aircraft import JSBSimAircraft, trim_aircraft, linearize_aircraft, HALLOUZI_POINT
    >>> ac = JSBSimAircraft("B747")
    >>> lin = linearize_aircraft(ac, trim_aircraft(ac, HALLOUZI_POINT))
    >>> ap = lqr_autopilot(lin)
    >>> closed = lin.model.A - lin.model.B[:, [0, 1, 3, 4]] @ ap.K
    >>> bool(np.linalg.eigvals(closed).real.max() < 0)   # the loop is stable
    True
    """
    from scipy.linalg import solve_continuous_are

    from fdikit.aircraft.plant import STATES
    from fdikit.errors import ParameterError

    m = linearization.model
    bad = [i for i in inputs if i not in m.controls]
    if bad:
        raise ParameterError(f"inputs {bad} are not inputs of the linear model ({', '.join(m.controls)}).")
    smax = {**BRYSON_STATE, **(state_max or {})}
    umax = {**BRYSON_INPUT, **(input_max or {})}
    cols = [m.controls.index(i) for i in inputs]
    B = m.B[:, cols]
    Q = np.diag([1.0 / smax[s] ** 2 for s in STATES])
    R = np.diag([1.0 / umax[i] ** 2 for i in inputs])
    # ψ is a pure integrator the controller can reach; the Riccati equation is solvable
    P = solve_continuous_are(m.A, B, Q, R)
    K = np.linalg.solve(R, B.T @ P)
    u0 = dict(zip(m.controls, linearization.u0, strict=True))
    u0["throttle"] = linearization.trim.throttle
    return LQRAutopilot(K=K, inputs=tuple(inputs), x0=np.asarray(linearization.x0, float), u0=u0,
                        thrust_slope=linearization.thrust_slope)
