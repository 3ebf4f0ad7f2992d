"""Fault-tolerant control: outer loops, input configurations, reconfiguration and multi-rate execution.

Hallouzi 2008, §6.2–6.6: outer PID loops (altitude → pitch, heading → roll, airspeed) around an inner
closed-loop SPC (:class:`fdikit.spc.ClosedLoopSPC`), run in rate groups, with the Table 6.1 input
configurations of the B747 the multiple-model isolation switches between (the flights themselves are in
:mod:`fdikit.studies.hallouzi2008.b747_ftc`).

* :mod:`fdikit.ftc.pid` — PID loops with anti-windup.
* :mod:`fdikit.ftc.references` — Reference generators for the §6.5 manoeuvres (turn, descent).
* :mod:`fdikit.ftc.multirate` — A rate-group scheduler with per-call timings.
* :mod:`fdikit.ftc.outer` — The altitude → pitch and heading → roll loops around the inner SPC.
* :mod:`fdikit.ftc.configurations` — Table 6.1 on JSBSim's B747: inputs, limits, linear models, start-up data.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "pid": ["PID"],
        "references": ["FlightPlan", "nominal_plan"],
        "multirate": ["RateGroup", "MultiRate"],
        "outer": ["OuterLoops", "outer_loops"],
        "configurations": ["InputConfiguration", "input_configuration", "configuration_model",
                           "identification_data"],
    },
)
