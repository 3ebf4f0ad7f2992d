"""Douglas et al. 1996 (the PATH report): the four-filter Beard–Jones health monitor of the vehicle,
the comparison of every evaluator on its residuals, the Ch. 5 evaluation on fdikit's nonlinear car, and the
end-to-end demos.

* :mod:`fdikit.studies.path1996.bank` — The PATH vehicle health monitor: four Beard–Jones detection filters for 12
  sensors and 3 actuators.
* :mod:`fdikit.studies.path1996.compare` — Residual processors side by side on the PATH bank's residuals (``fdikit
  compare-evaluators``).
* :mod:`fdikit.studies.path1996.demo` — The end-to-end demos on the linear PATH vehicle.
* :mod:`fdikit.studies.path1996.reduction` — Design models from the nonlinear car: linearisation at the §2.2 turn,
  Table 2.1 and Fig. 2.6.
* :mod:`fdikit.studies.path1996.game_bank` — The PATH monitor with disturbance-attenuating (game-theoretic) filters on
  the report's fault groups.
* :mod:`fdikit.studies.path1996.kalman_bank` — A Kalman-filter monitor for the PATH car: one steady-state filter, its
  12 innovations as residuals.
* :mod:`fdikit.studies.path1996.nonlinear_evaluation` — The Ch. 5 evaluation on the nonlinear car at realistic sensor
  noise: setup, nominal sizes, runs.
* :mod:`fdikit.studies.path1996.nonlinear_table` — The Ch. 5 table: detection, isolation and false alarms per fault,
  road, bank and processor.
* :mod:`fdikit.studies.path1996.nonlinear_report` — Files of ``fdikit path-evaluation``.
* :mod:`fdikit.studies.path1996.vehicle_demo` — The end-to-end demo on the nonlinear car (``fdikit demo``).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "bank": [
            "EIGENVALUES", "FILTER_GROUPS", "PathBank", "nominal_fault_sizes", "path_bank", "path_fault_model",
            "path_runs", "scale_to_nominal",
        ],
        "compare": [
            "EVALUATORS", "check_comparison_arguments", "path_evaluator_comparison",
        ],
        "demo": [
            "ACTUATOR_NOISE_STD", "BankDemoResult", "DemoResult", "SENSOR_NOISE_STD", "check_demo_arguments",
            "demo_model", "plot_bank_report", "run_demo", "run_kalman_demo",
        ],
        "reduction": [
            "DesignModels", "FAST_STATES", "STATIC_ACTUATORS", "match_eigenvalues", "path_design_models",
            "singular_values",
        ],
        "kalman_bank": [
            "path_kalman_bank",
        ],
        "nonlinear_evaluation": [
            "EvaluationSetup", "FaultRun", "NOISE_STD", "car_nominal_sizes", "deviation_trace", "evaluation_setup",
            "fault_run", "group_magnitudes", "off_nominal_peaks", "off_nominal_run",
        ],
        "nonlinear_table": [
            "BANKS", "DEFAULT_PROCESSORS", "EvaluationTable", "FAULTS", "PROCESSORS", "Prewhitened", "TableRow",
            "check_evaluation_arguments", "path_evaluation_table", "whitened_mhsprt",
        ],
        "nonlinear_report": [
            "plot_fault_residuals", "plot_fig_2_6", "table_2_1_markdown", "table_markdown", "write_path_evaluation",
        ],
        "game_bank": [
            "GAME_WEIGHTS", "path_game_bank",
        ],
        "vehicle_demo": [
            "VEHICLE_SCENARIOS", "VehicleDemoResult", "plot_vehicle_report", "run_vehicle_demo",
        ],
    },
)
