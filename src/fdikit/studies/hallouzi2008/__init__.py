"""Hallouzi 2008: the target-tracking, B747 and mass–spring–damper benchmarks of the multiple-model
methods, Table 3.1 and the model-set comparison (Table 3.3), and the report command.

* :mod:`fdikit.studies.hallouzi2008.target_tracking` — Maneuvering-target tracking: dual CMF vs augmented EKF vs IMM
  (Hallouzi 2008, §2.4.2, Figs 2.4–2.5).
* :mod:`fdikit.studies.hallouzi2008.b747` — B747 linear longitudinal FDI benchmark: dual CMF vs augmented EKF vs IMM
  (Hallouzi 2008, §2.4.1, Figs 2.2–2.3).
* :mod:`fdikit.studies.hallouzi2008.msd` — MSD benchmark with an OD model set and convex-model filters (Hallouzi
  2008, §3.6.2, Table 3.3, Figs 3.8–3.9).
* :mod:`fdikit.studies.hallouzi2008.msd_model_sets` — MSD benchmark with the CP and LV model sets next to the OD set
  (Hallouzi 2008, §3.6.2, Table 3.3, Figs 3.7–3.11).
* :mod:`fdikit.studies.hallouzi2008.example_3_1` — Example 3.1: basis conditioning vs degree of observability of
  model pairs (Hallouzi 2008, §3.3.1, Table 3.1).
* :mod:`fdikit.studies.hallouzi2008.aircraft_models` — B747 model sets around trim from the JSBSim aircraft: LIP
  models, Tables 4.2–4.5 (Hallouzi 2008, Ch. 4).
* :mod:`fdikit.studies.hallouzi2008.table_4_6` — Table 4.6 / Fig. 4.3: the linear simulation with model set I
  (LQR, augmented EKF) and the Table 4.7 logic on it (Hallouzi 2008, §4.4.1).
* :mod:`fdikit.studies.hallouzi2008.b747_lip` — LIP isolation on the nonlinear JSBSim B747: one closed-loop
  flight with the IMM of model set II (Hallouzi 2008, §4.4.2).
* :mod:`fdikit.studies.hallouzi2008.table_4_8` — Table 4.8 on the nonlinear B747: the lock-position sweep
  (Hallouzi 2008, §4.4.2).
* :mod:`fdikit.studies.hallouzi2008.b747_report` — Files of ``fdikit b747`` (Table 4.8, plots, HTML).
* :mod:`fdikit.studies.hallouzi2008.spc_msd` — Adaptive SPC against a fixed-model MPC on the MSD, and the
  persistency-of-excitation experiment (Hallouzi 2008, §5.4).
* :mod:`fdikit.studies.hallouzi2008.report` — One command for the multiple-model reproductions of Hallouzi 2008
  (§2.4, §3.3.1, §3.6).
* :mod:`fdikit.studies.hallouzi2008.b747_ftc` — The §6.5 fault-tolerant flights of the JSBSim B747: set-up,
  scenarios, results (Hallouzi 2008, §6.4–§6.5).
* :mod:`fdikit.studies.hallouzi2008.b747_ftc_flight` — One FTC flight in the §6.6 rate groups (IMM, SPC, plant).
* :mod:`fdikit.studies.hallouzi2008.b747_ftc_report` — Files of the B747 part of ``fdikit ftc``.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "target_tracking": [
            "INTERVALS", "N_SAMPLES", "TargetTrackingResult", "maneuver_profile", "plot_target_tracking",
            "target_tracking_monte_carlo", "target_tracking_trace", "tracking_convex_set", "tracking_imm_modes",
        ],
        "b747": [
            "B747MonteCarloResult", "INTERVALS", "N_SAMPLES", "TS", "b747_convex_set", "b747_lq_gain",
            "b747_monte_carlo", "b747_snr", "b747_trace", "b747_weight_profile",
        ],
        "msd": [
            "MSDFilterResult", "MSDModelSet", "MSDSimulation", "MSD_STATES", "ObservabilityComparison",
            "msd_observability_comparison", "msd_od_model_set", "msd_profile", "run_msd_filter", "simulate_msd",
        ],
        "msd_model_sets": [
            "ModelSetRun", "msd_cp_model_set", "msd_lv_model_set", "msd_table_3_3", "run_msd_model_set",
        ],
        "aircraft_models": [
            "LIP_RANGES", "LocalModel", "MEASURED", "MODEL_SET_I", "MODEL_SET_II", "b747_at_point",
            "large_model_set", "local_model", "model_set",
        ],
        "table_4_6": [
            "Table46Result", "Table46Scenario", "b747_lqr_gain", "build_table_4_6", "equivalent_lip_weight",
            "model_set_i_logic", "noise_covariances", "run_table_4_6", "scenario_intervals", "simulate_table_4_6",
            "table_4_6_isolation",
        ],
        "b747_lip": ["NOISE_PRESETS", "T_FAULT", "LipRun", "LipSetup", "false_alarm_rate", "fly_lip", "imm_input",
                     "lip_setup"],
        "table_4_8": [
            "FDIKIT_TABLE_4_8", "SWEEP_RANGES", "THESIS_TABLE_4_8", "LipRow", "Table48", "lock_positions", "table_4_8",
        ],
        "b747_report": [
            "THESIS_FIG_4_3", "plot_lip_run", "plot_sweep", "plot_table_4_6", "table_4_6_files", "table_4_6_markdown",
            "write_b747_report",
        ],
        "example_3_1": [
            "Example31Result", "PAIRS", "example_3_1", "example_3_1_models",
        ],
        "spc_msd": ["LIMITS", "PE_SETTINGS", "run_msd_spc", "write_msd_ftc"],
        "b747_ftc": ["SCENARIOS", "BIJLMER", "SPC_SETTINGS", "FtcSetup", "FtcRun", "ftc_setup", "scenario_fault"],
        "b747_ftc_flight": ["fly_ftc"],
        "b747_ftc_report": ["FLIGHTS", "THESIS_ISOLATION", "write_b747_ftc", "flight_summary"],
        "report": [
            "PARTS", "check_multiple_model_arguments", "multiple_model_report", "plot_b747", "plot_msd",
        ],
    },
)
