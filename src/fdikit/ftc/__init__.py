"""Fault-tolerant control: outer loops, input configurations, reconfiguration and multi-rate execution.

Hallouzi 2008, §6.2–6.6: outer PID loops (altitude → pitch, heading → roll, airspeed) around an inner
closed-loop SPC (:class:`fdikit.spc.ClosedLoopSPC`), run in rate groups.  The input configurations of
Table 6.1 and their switching by multiple-model isolation on the B747 are not implemented yet.

* :mod:`fdikit.ftc.pid` — PID loops with anti-windup.
* :mod:`fdikit.ftc.references` — Reference generators for the §6.5 manoeuvres (turn, descent).
* :mod:`fdikit.ftc.multirate` — A rate-group scheduler with per-call timings.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "pid": ["PID"],
        "references": ["FlightPlan", "nominal_plan"],
        "multirate": ["RateGroup", "MultiRate"],
    },
)
