"""Nonlinear aircraft through JSBSim: fault injection at the surfaces, trim, linearisation, closed-loop flight.

Hallouzi 2008, Ch. 4 (lock-in-place faults, model sets around trim) and App. A (B747 control
limits and rates), on JSBSim's nonlinear aircraft (Berndt 2004).

* :mod:`fdikit.aircraft.definition` — A JSBSim aircraft prepared so that fdikit drives its surfaces.
* :mod:`fdikit.aircraft.actuators` — Surface actuators with limits, rates and faults.
* :mod:`fdikit.aircraft.plant` — The aircraft as a plant: SI signals, steps, snapshots, turbulence.
* :mod:`fdikit.aircraft.trim` — Trim in steady straight flight, surfaces free or locked.
* :mod:`fdikit.aircraft.linearize` — Numerical linear models around a trim, with the trim offsets.
* :mod:`fdikit.aircraft.autopilot` — An LQR autopilot holding the trim (stands in for the SPC of Ch. 6).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "definition": ["STABILIZER_GAIN", "SURFACES", "AircraftDefinition", "jsbsim_aircraft", "prepare_aircraft"],
        "actuators": ["B747_LIMITS", "ActuatorBank", "SurfaceLimits", "default_limits"],
        "plant": ["FT", "KT", "LBF", "LBM", "SENSORS", "STATES", "AircraftSnapshot", "JSBSimAircraft"],
        "trim": ["HALLOUZI_POINT", "AircraftTrim", "FlightCondition", "trim_aircraft"],
        "linearize": ["INPUTS", "AircraftLinearization", "linearize_aircraft"],
        "autopilot": ["BRYSON_INPUT", "BRYSON_STATE", "LQRAutopilot", "lqr_autopilot"],
    },
)
