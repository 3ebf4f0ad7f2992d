"""The nonlinear PATH vehicle: a 6-DOF car with Magic-Formula tires, a mean-value engine and actuators.

Douglas et al. 1996, Ch. 2 (the Berkeley model as modified: suspension with a massless linear tire,
road roughness, slope, 32 → 22 states) and Ch. 8 (Nguyen's 6-DOF equations of motion).

* :mod:`fdikit.vehicle.parameters` — The numbers of a front-drive mid-size sedan, calibrated to the report.
* :mod:`fdikit.vehicle.tire` — Magic-Formula tire forces with Bakker's combined slip.
* :mod:`fdikit.vehicle.engine` — Mean-value engine with the manifold air mass as state.
* :mod:`fdikit.vehicle.dynamics` — The equations of motion (compiled) and the state, control and sensor names.
* :mod:`fdikit.vehicle.integrate` — The compiled fixed-step RK4 over a road profile.
* :mod:`fdikit.vehicle.sedan` — The car as a plant: operating points, linearisation, simulation.
* :mod:`fdikit.vehicle.run` — Simulation runs with road, wind, faults and sensor noise.
* :mod:`fdikit.vehicle.road` — Road profiles (Robson, Gill two-track, bumps) and crosswind.
* :mod:`fdikit.vehicle.longitudinal` — The 3-DOF longitudinal car of §8.1 (x, z, pitch) on the same parts.
* :mod:`fdikit.vehicle.validity` — The effective ranges of the linearised car (Table 8.2, ≤ 10 % error).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "parameters": ["GEAR_RATIOS", "INDEX", "MID_SIZE_SEDAN", "SedanParameters"],
        "tire": ["BAKKER_1987", "TireCoefficients", "peak_slips", "slip_ratio", "tire_forces"],
        "engine": ["ENGINE_FIELDS", "engine_state"],
        "dynamics": ["AUXILIARY", "CONTROLS", "ENVIRONMENT", "N_DESIGN_STATES", "SENSORS", "STATES"],
        "integrate": ["run_kernel"],
        "sedan": ["OperatingPoint", "SIGNALS", "Sedan"],
        "run": ["GEARBOX_MODES", "simulate_sedan"],
        "longitudinal": ["LONGITUDINAL_AUXILIARY", "LONGITUDINAL_CONTROLS", "LONGITUDINAL_SENSORS",
                         "LONGITUDINAL_STATES", "LongitudinalCar", "LongitudinalPoint"],
        "validity": ["NOMINAL_THROTTLE", "TABLE_8_2", "ValidityRanges", "steady_state_error", "validity_ranges"],
    },
)
