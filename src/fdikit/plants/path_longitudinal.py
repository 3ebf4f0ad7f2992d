"""PATH 7-state longitudinal car model: the game-filter example of Douglas et al. 1996, §9.6.

The nonlinear PATH vehicle linearised on a straight road at 25 m/s and reduced (spectral
separation + balanced realisation) to 7 states, 7 outputs and 2 inputs (throttle deg, brake
torque N·m); the states are balanced coordinates without physical meaning (Douglas et al. 1996,
§9.6, (9.84)–(9.89))::

    x' = A x + F̂ μ̂,        y = C x + v

Only ``A``, ``C`` and the two sensor-fault maps are printed; ``B`` and ``D`` are not ("for
simplicity, the inputs u will be disregarded"), so the model has **no controls**.

Two corrections to the printed data (Douglas et al. 1996, §9.6, (9.86)–(9.89)), both derived from the printed
fault maps ``F = [f, A f]`` (9.88)–(9.89), which are internally consistent:

1. **A(2,3) = +19.0734** (printed −19.0734).  With the printed sign ``A f − F(:, 2)`` has a
   row-2 error of −14.46 (``F_yω``) and −9.71 (``F_yẍ``); their ratio 1.490 is
   ``f_ω(3)/f_ẍ(3) = 0.3791/0.2544``, which pins the error on entry (2,3) with δ = 38.147.
   After the fix ``‖A f − F(:, 2)‖_∞ ≤ 2.2e−3`` (the rounding of the data) and A is stable:
   eig = {−31.585, −26.229, −2.319 ± 6.649i, −1.535 ± 5.693i, −0.0449}; as printed A has an
   eigenvalue at +0.169.
2. **Rows 1 and 3 of the printed C are exchanged.**  The fault maps are defined by
   ``C f_ω = e_2`` and ``C f_ẍ = e_3`` ((9.89), E_yω = e_2, E_yẍ = e_3), but the printed C gives
   ``C f_ẍ ≈ e_1``.  Either the printed C has rows 1 and 3 swapped or the "ẍ" label is wrong.
   The label is right: the printed reduced-order gain (9.95) has its columns **2 and 3** ≈ 0,
   i.e. the design ignored measurements 2 and 3 — engine speed and longitudinal acceleration,
   the nuisance sensors — in the order the design used; and the printed projector (9.90) has
   rows/columns 2 and 3 equal to zero, i.e. ``C F̂`` contains ``e_2`` and ``e_3``.  Both hold
   only if the design's C had the ẍ row third.  So :data:`PATH7_C` is the printed C with rows
   1 and 3 exchanged; with it ``C f_ω ≈ e_2`` and ``C f_ẍ ≈ e_3`` to 1.3e−3.

Outputs, in the order of (9.84) (whose text as transcribed shows "heave acceleration" twice; the symbol list
gives ``y_m, y_ω, y_ẍ, y_z̈, y_θ̇, y_ωfs, y_ωrs``): ``air_mass`` (kg), ``engine_speed``
(rad/s), ``accel_x`` (longitudinal, m/s²), ``accel_z`` (heave, m/s²), ``pitch_rate`` (rad/s),
``wheel_speed_front`` and ``wheel_speed_rear`` (symmetric wheel speeds, rad/s).

C has condition number ≈ 706 and 4-decimal entries, so quantities that invert it (the
projector of (9.90), the Riccati solutions) are sensitive to the rounding: the printed
projector, Π (9.91), S (9.44) and Γ (9.93) are not reproducible from these data (recomputing them from the printed
A, C differs
beyond the printed digits).
"""

from __future__ import annotations

import numpy as np

from fdikit.model import FaultModel

__all__ = [
    "path_longitudinal_7",
    "path_longitudinal_7_fault_maps",
    "PATH7_A",
    "PATH7_A_PRINTED",
    "PATH7_C",
    "PATH7_C_PRINTED",
    "PATH7_F_ENGINE_SPEED",
    "PATH7_F_ACCEL_X",
    "PATH7_OUTPUTS",
]

#: State matrix exactly as printed in Douglas et al. 1996, §9.6 (A(2,3) = −19.0734: a sign error).
PATH7_A_PRINTED = np.array(
    [
        [-0.0521, -0.2213, 0.2681, -0.0121, 0.0136, 0.0084, -0.0078],
        [-0.3007, -8.0277, -19.0734, -1.1013, 0.0795, 0.2471, 0.0378],
        [-0.3263, -19.7571, -51.0638, -3.2675, -4.8766, -2.4258, 0.0040],
        [0.0454, 2.4036, 15.7922, -2.1857, 6.4655, -0.2062, 0.0495],
        [0.0219, 1.1136, 8.6428, -7.1817, -0.6526, -0.2171, 0.9316],
        [0.0116, 0.5928, 3.8335, -1.0926, -0.6513, -0.9851, 5.9628],
        [0.0154, 0.7868, 4.8494, -1.4900, -1.0329, -6.5688, -2.5996],
    ]
)
PATH7_A_PRINTED.setflags(write=False)

#: State matrix with the sign of A(2,3) corrected to +19.0734 (module docstring, item 1).
PATH7_A = PATH7_A_PRINTED.copy()
PATH7_A[1, 2] = 19.0734
PATH7_A.setflags(write=False)

#: Output matrix exactly as printed (rows 1 and 3 exchanged relative to the fault maps).
PATH7_C_PRINTED = np.array(
    [
        [0.0075, 0.4605, 0.3710, 0.1023, 0.0513, 0.0340, -0.0137],
        [0.7318, 2.7938, -2.8640, 0.1680, -0.0415, -0.0491, -0.0029],
        [0.0028, 0.1711, -0.2654, 0.0765, -0.0161, 0.0093, -0.0008],
        [0.0000, -0.0007, -0.0005, -0.0216, -0.0496, -0.0438, 0.0697],
        [-0.0000, -0.0024, 0.0050, 0.0111, 0.0205, -0.0027, 0.0009],
        [0.4214, -0.1440, 0.0371, 0.2203, -0.1764, -0.0129, 0.1051],
        [0.4211, 0.1318, -0.4410, -0.2741, -0.0304, -0.0734, 0.0585],
    ]
)
PATH7_C_PRINTED.setflags(write=False)

#: Output matrix in the labelled row order (printed rows 1 and 3 exchanged; docstring, item 2).
PATH7_C = PATH7_C_PRINTED[[2, 1, 0, 3, 4, 5, 6]].copy()
PATH7_C.setflags(write=False)

#: Engine-speed sensor-fault map ``F_yω = [f, A f]`` as printed (7 x 2), ``C f ≈ e_2``.
PATH7_F_ENGINE_SPEED = np.array(
    [
        [0.2107, -0.0681],
        [0.2986, -1.1171],
        [0.3791, 14.0532],
        [1.7301, -9.9008],
        [-2.3516, -13.4314],
        [-13.8538, -43.7274],
        [-9.8358, 118.5002],
    ]
)
PATH7_F_ENGINE_SPEED.setflags(write=False)

#: Longitudinal-accelerometer sensor-fault map ``F_yẍ = [f, A f]`` as printed (7 x 2), ``C f ≈ e_3``.
PATH7_F_ACCEL_X = np.array(
    [
        [0.0873, 0.0209],
        [0.9262, 7.7252],
        [0.2544, -99.5538],
        [-3.0910, 35.2772],
        [4.0831, 33.4690],
        [24.1122, 80.5043],
        [17.1083, -200.5111],
    ]
)
PATH7_F_ACCEL_X.setflags(write=False)

#: Output names in the order of (9.84).
PATH7_OUTPUTS: tuple[str, ...] = (
    "air_mass",
    "engine_speed",
    "accel_x",
    "accel_z",
    "pitch_rate",
    "wheel_speed_front",
    "wheel_speed_rear",
)


def path_longitudinal_7() -> FaultModel:
    """The 7-state longitudinal model of Douglas et al. 1996, §9.6, (9.86)–(9.87), corrected.

    ``A`` with A(2,3) = +19.0734 and ``C`` in the labelled row order (module docstring); no
    controls (``B``, ``D`` are not printed), no fault inputs.  The air-mass sensor fault of the
    example is the target (``'air_mass_sensor'`` resolves to ``[f, A f]`` with ``C f = e_1`` via
    :func:`fdikit.fault_maps.resolve_faults`); the printed nuisance maps are in
    :func:`path_longitudinal_7_fault_maps`.
    ``resolve_faults(model, ['engine_speed_sensor', 'accel_x_sensor'])``
    gives the exact maps of this (rounded) model instead, which differ from the printed ones by
    the rounding (≤ 0.05 in ``f``, ≤ 0.23 in ``A f``).

    Returns
    -------
    FaultModel
        Continuous model with 7 balanced states ``x1 … x7``, the 7 outputs listed in the module
        docstring, and no controls, disturbance, fault or noise inputs.

    References
    ----------
    Douglas et al. 1996, §9.6, (9.84)–(9.89).

    Examples
    --------
    >>> m = path_longitudinal_7()
    >>> m.n, m.p, m.controls
    (7, 7, ())
    >>> m.outputs[:3]
    ('air_mass', 'engine_speed', 'accel_x')
    """
    return FaultModel(
        PATH7_A,
        PATH7_C,
        states=tuple(f"x{i}" for i in range(1, 8)),
        outputs=PATH7_OUTPUTS,
    )


def path_longitudinal_7_fault_maps() -> dict[str, np.ndarray]:
    """The printed nuisance fault maps of §9.6: ``{'engine_speed_sensor': F_yω, 'accel_x_sensor': F_yẍ}``.

    Each is ``[f, A f]`` (7 x 2) to 4 decimals; ``F̂_{y_m} = [F_yω, F_yẍ]`` is the 4-column
    complementary map of the air-mass filter.  Pass the dict as ``nuisance=`` to a design.

    Returns
    -------
    dict of str to numpy.ndarray
        ``'engine_speed_sensor'`` → ``F_yω`` and ``'accel_x_sensor'`` → ``F_yẍ``, each a (7, 2) array
        ``[f, A f]``; new arrays on each call.

    References
    ----------
    Douglas et al. 1996, §9.6, (9.88)–(9.89).

    Examples
    --------
    >>> maps = path_longitudinal_7_fault_maps()
    >>> list(maps), maps["engine_speed_sensor"].shape
    (['engine_speed_sensor', 'accel_x_sensor'], (7, 2))
    """
    return {"engine_speed_sensor": PATH7_F_ENGINE_SPEED.copy(), "accel_x_sensor": PATH7_F_ACCEL_X.copy()}
