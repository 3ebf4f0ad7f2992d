"""A Kalman-filter monitor for the PATH car: one steady-state filter, its 12 innovations as residuals.

The baseline a user would otherwise build (and the third bank the issue compares): a steady-state
Kalman filter on the 14-state design model (Douglas et al. 1996, App. D structure, here fdikit's own
Method-1 model), sampled at 100 Hz, with the actuator jitter of the linear demo as process noise and
the sensor noise of :data:`~fdikit.studies.path1996.nonlinear_evaluation.NOISE_STD` as measurement
noise.  Its innovations are white for the linear model; a fault shows as a mean shift with its own
direction, so the isolation is left to a processor that learns the directions (the prewhitened
MHSSPRT); the threshold processors tie each innovation to its own sensor, a heuristic that cannot
isolate actuator faults.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fdikit.model import FaultModel

__all__ = ["path_kalman_bank"]


def path_kalman_bank(model: FaultModel, noise_std: Mapping[str, float], *, dt: float = 0.01,
                     actuator_std: Mapping[str, float] | None = None):
    """The Kalman monitor as a one-filter :class:`~fdikit.studies.path1996.bank.PathBank` (discrete generator).

    Parameters
    ----------
    model : FaultModel
        Continuous design model (the 14-state Method-1 model).
    noise_std : mapping of str to float
        Per-sample sensor noise at ``dt`` (the model's output names).
    dt : float, default 0.01
        Sample time [s].
    actuator_std : mapping of str to float, optional
        Process noise on the controls (default the linear demo's actuator jitter: 0.05°, 5 N m, 2e-4 rad).

    Returns
    -------
    PathBank
        ``designs = {"kalman": ObserverDesign}``; the generator (discrete at ``dt``) gives residuals
        ``'kalman:<output>'`` isolating ``'<output>_sensor'``; every residual in group ``"kalman"``; scales empty.

    Raises
    ------
    ParameterError
        For a missing noise level.

    References
    ----------
    Douglas et al. 1996, §5.1 (the evaluation it is compared on), Ch. 7 (the MHSSPRT it feeds).

    Examples
    --------
    >>> from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD, evaluation_setup
    >>> bank = path_kalman_bank(evaluation_setup().models.method1, NOISE_STD)  # doctest: +SKIP
    >>> bank.generator.residuals[0], bank.generator.dt  # doctest: +SKIP
    ('kalman:air_mass', 0.01)
    """
    from dataclasses import replace

    from fdikit import validate
    from fdikit.design import kalman
    from fdikit.errors import ParameterError
    from fdikit.model import sensor_fault_name
    from fdikit.studies.path1996.bank import PathBank
    from fdikit.studies.path1996.demo import ACTUATOR_NOISE_STD

    dt = validate.positive("dt", dt)
    missing = [o for o in model.outputs if o not in noise_std]
    if missing:
        raise ParameterError(f"noise_std: no level for {missing}")
    act = ACTUATOR_NOISE_STD if actuator_std is None else actuator_std
    md = model.discretize(dt)
    W = np.diag([validate.positive(f"actuator_std[{c!r}]", act[c]) ** 2 for c in md.controls])
    R = np.diag([validate.positive(f"noise_std[{o!r}]", noise_std[o]) ** 2 for o in md.outputs])
    Q = md.Bu @ W @ md.Bu.T  # actuator jitter through the sampled input matrix (semidefinite)
    design = kalman(md, Q, R)
    g = design.generator
    gen = replace(g, residuals=tuple(f"kalman:{o}" for o in md.outputs),
                  isolates=tuple(sensor_fault_name(o) for o in md.outputs))
    return PathBank({"kalman": design}, gen, ("kalman",) * len(md.outputs), {}, {})
