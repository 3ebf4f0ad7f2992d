"""Trim of a JSBSim aircraft in steady straight flight, with surfaces free or locked.

Steady straight flight at airspeed ``V``, altitude ``h`` and flight-path angle ``γ`` with zero body
rates: the residuals ``ṗ, q̇, ṙ, V̇, α̇, β̇`` and ``ḣ − V sin γ`` of
:meth:`fdikit.aircraft.plant.JSBSimAircraft.derivatives` are driven to zero by least squares
(:func:`scipy.optimize.least_squares`, throttle bounded to 0…1). The unknowns are ``α, θ, β``, the
throttle (all engines alike) and the free surfaces; wings are level (``φ = 0``) unless a lateral
surface is locked, when ``φ`` is free too (a stuck rudder is held with bank and aileron). Pitch is
trimmed with the stabiliser where the aircraft has one (the B747 of :mod:`fdikit.aircraft.definition`;
the elevator is then faired at 0) and with the elevator otherwise; with the pitch device locked
or saturated at its limit, the airspeed is freed and the aircraft settles at the speed it trims
at. This is Hallouzi's "each fault model is trimmed at a slightly different equilibrium"
(§4.3.1, (4.1)–(4.2)).

JSBSim's own trim (``do_trim``) moves the FCS *commands*; with the surfaces driven by fdikit's
actuators it cannot be used, hence this solver.

References
----------
Hallouzi 2008, §4.3.1 (the trim point 980 m, 92.6 m/s, flaps 20 deg, 263 t) and (4.1)–(4.2).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.errors import DesignError, ParameterError

__all__ = ["HALLOUZI_POINT", "AircraftTrim", "FlightCondition", "trim_aircraft"]

_G = 9.80665


@dataclass(frozen=True)
class FlightCondition:
    """A steady straight flight condition.

    Attributes
    ----------
    altitude : float
        Altitude above sea level [m].
    airspeed : float
        True airspeed [m/s].
    flight_path_angle : float
        γ [rad] (default 0: level).
    flaps : float
        Flap deflection [rad] (default 0).
    mass : float or None
        Total mass [kg] (fuel adjusted); ``None`` keeps the aircraft's.
    heading : float
        ψ [rad] (default 0).

    Examples
    --------
    >>> HALLOUZI_POINT.altitude, HALLOUZI_POINT.airspeed
    (980.0, 92.6)
    """

    altitude: float
    airspeed: float
    flight_path_angle: float = 0.0
    flaps: float = 0.0
    mass: float | None = None
    heading: float = 0.0

    def __post_init__(self) -> None:
        validate.non_negative("altitude", self.altitude)
        validate.positive("airspeed", self.airspeed)
        validate.in_range("flight_path_angle", self.flight_path_angle, -np.pi / 4, np.pi / 4)
        validate.non_negative("flaps", self.flaps)
        if self.mass is not None:
            validate.positive("mass", self.mass)


#: Hallouzi 2008, §4.3.1: 980 m, 92.6 m/s TAS, flaps 20 deg, 263 t (the GARTEUR AG-16 initial condition).
HALLOUZI_POINT = FlightCondition(altitude=980.0, airspeed=92.6, flaps=float(np.radians(20.0)), mass=263e3)


@dataclass(frozen=True)
class AircraftTrim:
    """A trimmed steady flight.

    Attributes
    ----------
    condition : FlightCondition
    x : ndarray
        The state :data:`fdikit.aircraft.plant.STATES` (SI).
    positions : dict
        Surface positions [rad] (locked ones included).
    throttle : float
        Throttle of every engine (0…1).
    thrust : float
        Total thrust [N].
    residual : ndarray
        The trim residuals ``ṗ, q̇, ṙ, V̇/g, α̇, β̇, (ḣ − V sin γ)/V`` at the solution.
    locked : dict
        The surfaces held fixed.

    Examples
    --------
    >>> from fdikit.aircraft.plant import JSBSimAircraft
    >>> tr = trim_aircraft(JSBSimAircraft("737"), FlightCondition(3000.0, 150.0))
    >>> tr.converged, round(float(np.degrees(tr.x[4])), 1)   # α at 150 m/s
    (True, 3.1)
    """

    condition: FlightCondition
    x: np.ndarray
    positions: dict
    throttle: float
    thrust: float
    residual: np.ndarray
    locked: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        """Whether every residual is below 1e-6 (rad/s², g, rad/s)."""
        return bool(np.max(np.abs(self.residual)) < 1e-6)


def trim_aircraft(aircraft, condition: FlightCondition, locked: Mapping | None = None, *,
                  require: bool = True, start: AircraftTrim | None = None) -> AircraftTrim:
    """Trim ``aircraft`` at ``condition`` and leave it there, ready to fly.

    Parameters
    ----------
    aircraft : JSBSimAircraft
    condition : FlightCondition
    locked : mapping, optional
        Surface → position [rad] held fixed (a lock-in-place model's surface).
    require : bool, optional
        Raise when the trim does not converge (default True); with False the best point is returned
        (its :attr:`AircraftTrim.residual` says how far from equilibrium it is).
    start : AircraftTrim, optional
        A nearby trim to start from (e.g. the previous lock position of a sweep).

    Returns
    -------
    AircraftTrim

    Raises
    ------
    ParameterError
        For a locked surface the aircraft does not have, or flaps on an aircraft without them.
    DesignError
        When ``require`` and the residual stays above 1e-6.

    Examples
    --------
    >>> from fdikit.aircraft.plant import JSBSimAircraft
    >>> ac = JSBSimAircraft("B747")
    >>> tr = trim_aircraft(ac, HALLOUZI_POINT)
    >>> tr.converged, round(ac.mass / 1e3, 3)
    (True, 263.0)
    """
    from scipy.optimize import least_squares

    locked = dict(locked or {})
    for s in locked:
        if s not in aircraft.surfaces or s == "flap":
            raise ParameterError(f"cannot lock {s!r}: the {aircraft.name}'s trim surfaces are "
                                 f"{', '.join(x for x in aircraft.surfaces if x != 'flap')}.")
    if condition.flaps and "flap" not in aircraft.surfaces:
        raise ParameterError(f"the {aircraft.name} has no flap surface fdikit drives; use flaps=0.")
    if condition.mass is not None:
        aircraft.set_mass(condition.mass)
    fixed = {**locked, **({"flap": condition.flaps} if "flap" in aircraft.surfaces else {})}
    pitch = [s for s in ("stabilizer", "elevator") if s in aircraft.surfaces and s not in locked][:1]
    if "stabilizer" in pitch and "elevator" not in locked:
        fixed["elevator"] = 0.0  # trimmed with the stabiliser, elevator faired
    free = pitch + [s for s in ("aileron", "rudder") if s in aircraft.surfaces and s not in locked]
    names = ["alpha", "theta", "beta", "throttle", *free]
    if len(free) - len(pitch) < 2:
        names.append("phi")
    if not pitch:
        names.append("airspeed")
    V0, gam = condition.airspeed, condition.flight_path_angle

    def unpack(z):
        d = dict(zip(names, z, strict=True))
        V = d.get("airspeed", V0)
        x = np.array([0, 0, 0, V, d["alpha"], d["beta"], d.get("phi", 0.0), d["theta"], condition.heading,
                      condition.altitude])
        return x, {**fixed, **{s: d[s] for s in free}}, d["throttle"]

    def residual(z):
        x, pos, thr = unpack(z)
        dx = aircraft.derivatives(x, pos, thr)
        return np.array([*dx[:3], dx[3] / _G, dx[4], dx[5], (dx[9] - x[3] * np.sin(gam)) / x[3]])

    z0 = {"alpha": 0.05, "theta": 0.05 + gam, "beta": 0.0, "throttle": 0.5, "phi": 0.0, "airspeed": V0,
          **dict.fromkeys(free, 0.0)}
    if start is not None:
        z0.update(alpha=start.x[4], beta=start.x[5], phi=start.x[6], theta=start.x[7], throttle=start.throttle,
                  **{s: start.positions[s] for s in free if s in start.positions})
    lo = {"alpha": -0.3, "theta": -0.8, "beta": -0.5, "throttle": 0.0, "phi": -1.0, "airspeed": 0.5 * V0}
    hi = {"alpha": 0.4, "theta": 0.8, "beta": 0.5, "throttle": 1.0, "phi": 1.0, "airspeed": 2.0 * V0}
    for s in free:
        lim = aircraft.actuators.limits[s]
        lo[s], hi[s] = lim.lower, lim.upper
    def solve(names):
        return least_squares(residual, [z0[n] for n in names], bounds=([lo[n] for n in names],
                             [hi[n] for n in names]), xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=400)

    z0 = {k: min(max(v, lo.get(k, -np.inf)), hi.get(k, np.inf)) for k, v in z0.items()}
    sol = solve(names)
    if pitch and "airspeed" not in names and np.max(np.abs(sol.fun)) > 1e-6:
        # the pitch device saturates: hold it at the limit it reached and let the airspeed settle instead
        k = names.index(pitch[0])
        fixed[pitch[0]] = float(sol.x[k])
        z0.update(zip(names, sol.x, strict=True))
        names = [n for n in names if n != pitch[0]] + ["airspeed"]
        free.remove(pitch[0])
        sol = solve(names)
    x, pos, thr = unpack(sol.x)
    res = residual(sol.x)  # also leaves the aircraft at the solution
    aircraft.set_inputs(**{s: pos[s] for s in aircraft.surfaces},
                        **{f"throttle_{i + 1}": thr for i in range(aircraft.engines)})
    out = AircraftTrim(condition=condition, x=x, positions=pos, throttle=float(thr),
                       thrust=float(aircraft.thrust().sum()), residual=res, locked=locked)
    if require and not out.converged:
        raise DesignError(f"the {aircraft.name} does not trim at {condition} with {locked or 'no surface'} locked: "
                          f"largest residual {np.max(np.abs(res)):.2e} (throttle {thr:.3f}, "
                          f"{', '.join(f'{s} {np.degrees(v):.1f} deg' for s, v in pos.items())}).")
    return out
