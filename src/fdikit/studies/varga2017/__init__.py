"""Varga 2017 (*Solving Fault Diagnosis Problems*), Chapter 8: the aircraft case studies on the reference's data.

* :mod:`fdikit.studies.varga2017.aircraft` — CS1 (flight actuator faults, Tables 8.2–8.3) and CS2 (air data
  sensor faults, Tables 8.4–8.5) on the multiple models of FaultDetectionTools.jl's ``Examples/*.jld2``.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "aircraft": [
            "ACTUATOR_FAULTS", "CS1_SFDI", "NOMINAL", "SENSOR_FAULTS", "AircraftCase", "actuator_case",
            "closed_loop_degree", "closed_loop_norms", "data_file", "interpolated_gain_errors", "positive_feedback",
            "remark81_gains", "sensor_case", "static_gain_error",
        ],
    },
)
