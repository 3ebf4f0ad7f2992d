"""Douglas et al. 1996 (the PATH report): the four-filter Beard–Jones health monitor of the vehicle,
the comparison of every evaluator on its residuals, and the end-to-end demos.

* :mod:`fdikit.studies.path1996.bank` — The PATH vehicle health monitor: four Beard–Jones detection filters for 12
  sensors and 3 actuators.
* :mod:`fdikit.studies.path1996.compare` — Residual processors side by side on the PATH bank's residuals (``fdikit
  compare-evaluators``).
* :mod:`fdikit.studies.path1996.demo` — The end-to-end demos on the PATH vehicle.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "bank": [
            "EIGENVALUES", "FILTER_GROUPS", "PathBank", "nominal_fault_sizes", "path_bank", "path_fault_model",
            "path_runs",
        ],
        "compare": [
            "EVALUATORS", "check_comparison_arguments", "path_evaluator_comparison",
        ],
        "demo": [
            "ACTUATOR_NOISE_STD", "BankDemoResult", "DemoResult", "SENSOR_NOISE_STD", "check_demo_arguments",
            "demo_model", "plot_bank_report", "run_demo", "run_kalman_demo",
        ],
    },
)
