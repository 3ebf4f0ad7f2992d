"""van der Ploeg 2018: the single-track steering-fault cases S1–S8 (Ch. 4).

* :mod:`fdikit.studies.vanderploeg2018.scenarios` — Simulation cases of van der Ploeg 2018, Ch. 4: lateral vehicle
  with additive and multiplicative steering faults.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "scenarios": [
            "ADDITIVE", "CASES", "MULTIPLICATIVE", "OUTPUTS", "TABLE_4_2", "cornering_run", "cosine_speed_sweep",
            "design_bank_angle", "lateral_run", "perturbed_parameters", "steering_setpoint", "true_steering_faults",
            "vanderploeg_case",
        ],
    },
)
