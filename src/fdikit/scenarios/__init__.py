"""Simulation scenarios of the seeds, as functions that return :class:`~fdikit.trace.Trace` objects.

* :mod:`fdikit.scenarios.vanderploeg` — the single-track steering-fault cases S1–S8 of van der Ploeg
  2018, Ch. 4 (:func:`vanderploeg_case`, :func:`lateral_run`, :func:`cornering_run`);
* :mod:`fdikit.scenarios.varrier` — the lateral-acceleration sensor fault of Varrier et al. 2014, §5
  (:func:`varrier_trace`, the ϖ score :func:`min_max_ratio`);
* :mod:`fdikit.scenarios.target_tracking` — the maneuvering-target benchmark of Hallouzi 2008, §2.4.2
  (:func:`target_tracking_trace`, :func:`target_tracking_monte_carlo`);
* :mod:`fdikit.scenarios.b747` — the B747 linear FDI benchmark of Hallouzi 2008, §2.4.1
  (:func:`b747_trace`, :func:`b747_monte_carlo`);
* :mod:`fdikit.scenarios.msd` — the LPV mass–spring–damper run of Hallouzi 2008, §3.6.2
  (:func:`simulate_msd`, :func:`run_msd_filter`); :mod:`fdikit.scenarios.msd_model_sets` — the same run on the
  OD, CP and LV model sets (Table 3.3, :func:`msd_table_3_3`), and the OD vs minimum-mismatch conditioning
  (Table 3.4, :func:`~fdikit.scenarios.msd.msd_observability_comparison`);
* :mod:`fdikit.scenarios.example_3_1` — Table 3.1 of Hallouzi 2008, pair conditioning vs observability
  (:func:`example_3_1`).
"""

from fdikit.scenarios.b747 import b747_monte_carlo, b747_trace
from fdikit.scenarios.example_3_1 import example_3_1
from fdikit.scenarios.msd import run_msd_filter, simulate_msd
from fdikit.scenarios.msd_model_sets import msd_table_3_3
from fdikit.scenarios.target_tracking import target_tracking_monte_carlo, target_tracking_trace
from fdikit.scenarios.vanderploeg import cornering_run, lateral_run, true_steering_faults, vanderploeg_case
from fdikit.scenarios.varrier import min_max_ratio, varrier_comparison, varrier_trace

__all__ = [
    "b747_monte_carlo",
    "b747_trace",
    "cornering_run",
    "example_3_1",
    "lateral_run",
    "min_max_ratio",
    "msd_table_3_3",
    "run_msd_filter",
    "simulate_msd",
    "target_tracking_monte_carlo",
    "target_tracking_trace",
    "true_steering_faults",
    "vanderploeg_case",
    "varrier_comparison",
    "varrier_trace",
]
