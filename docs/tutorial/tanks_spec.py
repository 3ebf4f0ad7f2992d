"""The ``fdikit design`` spec of the two tanks (docs/tutorial.md): the plant is a Python function."""

from tanks import plant

from fdikit.nonlinear import trim_and_linearize

name = "two-tanks"
description = "level sensors and pump of two tanks in series"


def model():
    # level 2 at 25 cm; continuous, so fdikit design discretises it at the logs' sample time
    return trim_and_linearize(plant(), x0=[0.2, 0.2], u0=[3e-4], y0={"level2": 0.25}).model


filters = [{"name": "tank1", "outputs": ["level1"], "process_noise_cov": 1e-11, "measurement_noise_std": 0.002},
           {"name": "tank2", "outputs": ["level2"], "process_noise_cov": 1e-11, "measurement_noise_std": 0.002}]
log = {"time": "t_s", "columns": {"pump": "pump_lpm", "level1": "level1_cm", "level2": "level2_cm"},
       "units": {"pump": "L/min", "level1": "cm", "level2": "cm"}}
calibration = {"false_alarms_per_hour": 1.0, "persistence": [3, 5]}
