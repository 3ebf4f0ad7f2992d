"""PATH linear vehicle models of Douglas et al. 1996, Appendix D.

Two continuous-time linearisations of the Berkeley PATH passenger-car model in a
constant-radius turn (tire steer 0.005 rad, 24.87 m/s, about 0.1 g; §2.2), reduced by
residualisation ("method 1", §2.3):

* :func:`path_vehicle_14` -- 14 states, for *actuator*-fault design, eqs. (d.1a–d).
  The throttle (−90.91) and steering (−80) actuator lags are states.
* :func:`path_vehicle_12` -- 12 states, for *sensor*-fault design, eqs. (d.2a–d).
  The two fast actuators are residualised (static), so their columns move into ``B``
  and the accelerometer rows get a steering feedthrough ``D``.

Both have 12 measured outputs and 3 controls::

    x' = A x + B u,        y = C x + D u

Provenance
----------
The matrices are **reconstructed** from a text transcription of App. D of the report.  The printed data
are MATLAB ``format bank`` listings: every entry is **rounded to 2 decimals**, exact
zeros print as ``0`` and tiny nonzero entries as ``0.00`` / ``-0.00`` (stored here as 0).
The true matrices are therefore only known to ±0.005 per printed entry;
:func:`rounding_intervals` gives those intervals.  Eigenvalues of the rounded data
agree with the report's Table 2.1 only to within the effect of that rounding, and the
rounded data are not accurate enough to re-derive the report's App. E filter gains.

The transcription below follows the 12-state listing (d.2a–d), the cleaner of the two
copies, and was checked entry by entry against the 14-state listing (d.1a–c).  Choices
where the seed is garbled or the two listings differ:

1. **Front-wheel rows, engine-speed column** (``C[8:10, 1]``, wheel_speed_fl/fr vs
   omega_e): set to **0**.  Both listings print ``0`` there (the exact-zero format, not
   ``0.00``), while the rear-wheel rows print 0.04 / 0.03 in both listings.  Engine speed
   reaches a wheel speed only through driveline torque; a coupling on the rear wheels
   alone is a rear-wheel-drive vehicle, for which the undriven front wheels have an
   exactly zero coefficient.  (0.03, the rear-wheel value, is not printed anywhere for the
   front wheels.)
2. **Lost minus signs in column 8** (``phi_dot``) of the 14-state ``A`` listing (rows
   3, 4, 5, 8, 10, 11 print ``0.00, 1.83, 0.00, 6.05, 0.01, 0.01``): the 12-state signs
   are used (``-0.00, -1.83, -0.00, -6.05, -0.01, -0.01``).  The tab split of that column
   dropped the sign in every row; ``A[7, 7] = -6.05`` is the roll damping, and with
   +6.05 the spectrum no longer matches Table 2.1.
3. **Wheel-speed rows** (``C`` rows 9–12, columns 3, 5, 6, 7): the 14-state copy is
   garbled (``3.34``, ``3.30``, ``-20 0.30``, ``18.09``, ``-1.99`` ...); the clean
   12-state values are used (``3.54``, ``3.58``, ``-26.36``, ``19.09``, ``-1.89`` ...).
4. **Kinematic identities** printed ``1.00`` (``z' = v_z``, ``phi' = phi_dot``,
   ``theta' = theta_dot`` and the rate-gyro / air-mass / engine-speed output rows) are
   taken as exact 1, not rounded values.
5. ``D`` of the 14-state model (d.1d) is printed as a zero block of unclear size; it is
   the 12 x 3 zero matrix (the accelerometers see the steering only through the
   ``beta`` state, column 14 of ``C``).

The states are ordered as App. D's matrix structure implies:
``A[5, 4] = 1`` (z' = v_z), ``A[6, 7] = 1``, ``A[8, 9] = 1``, actuator diagonals
−90.91 / −1.25 / −80, and the gyro rows of ``C`` pick phi_dot, theta_dot, eps_dot.

Units: air mass kg, engine speed rad/s, velocities m/s, heave z m, angles rad, rates
rad/s, throttle angle deg, brake torque N·m, steering angle rad; accelerations m/s².
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = [
    "path_vehicle_12",
    "path_vehicle_14",
    "rounding_intervals",
    "STATES_12",
    "STATES_14",
    "OUTPUTS",
    "CONTROLS",
    "TABLE_2_1_EIGENVALUES_12",
    "TABLE_2_1_EIGENVALUES_14",
]

STATES_12: tuple[str, ...] = (
    "m_a", "omega_e", "v_x", "v_y", "v_z", "z", "phi", "phi_dot", "theta", "theta_dot", "eps_dot", "tau_b",
)
STATES_14: tuple[str, ...] = (
    "m_a", "omega_e", "v_x", "v_y", "v_z", "z", "phi", "phi_dot", "theta", "theta_dot", "eps_dot",
    "alpha", "tau_b", "beta",
)
OUTPUTS: tuple[str, ...] = (
    "air_mass", "engine_speed", "accel_x", "accel_y", "accel_z", "roll_rate", "pitch_rate", "yaw_rate",
    "wheel_speed_fl", "wheel_speed_fr", "wheel_speed_rl", "wheel_speed_rr",
)
#: Throttle angle (deg), brake torque (N·m), steering angle (rad).
CONTROLS: tuple[str, ...] = ("throttle", "brake", "steering")

#: Table 2.1, method 1 (residualisation), 14-state model, as printed (2 decimals).
TABLE_2_1_EIGENVALUES_14: tuple[complex, ...] = (
    -26.46 + 4.32j, -26.46 - 4.32j,
    -7.53 + 2.94j, -7.53 - 2.94j,
    -0.049,
    -2.07 + 6.54j, -2.07 - 6.54j,
    -1.25,
    -1.44 + 5.50j, -1.44 - 5.50j,
    -2.82 + 5.60j, -2.82 - 5.60j,
    -90.91,
    -80.0,
)
#: The 12-state model has the same spectrum without the throttle and steering actuator
#: modes −90.91 and −80 (§2.3: "the eigenvalues do not change because the actuators are
#: in series").
TABLE_2_1_EIGENVALUES_12: tuple[complex, ...] = TABLE_2_1_EIGENVALUES_14[:-2]

# ---------------------------------------------------------------------------------------
# Transcription of Douglas et al. 1996, App. D, (d.2a–d), one printed row per line.
# "0" = exact zero, "1" = exact kinematic identity (printed 1.00), "-0.00"/"0.00" = tiny
# nonzero of that sign, anything else = rounded to the printed decimals.
# Columns: m_a omega_e v_x v_y v_z z phi phi_dot theta theta_dot eps_dot tau_b
_A12 = """
 -22.42  -0.12    0      0       0        0        0      0      0        0       0      0
 306.69 -29.75  331.11  -1.17  -196.62 -2278.82  56.77   2.92 -3169.84 -273.50   2.99  -0.07
   0      0.06   -0.68   0.06    0.51     5.95   -0.18  -0.00   15.84     1.40  -0.34  -0.00
   0     -0.00   -0.07  -9.03   -0.33    -2.84  -18.33  -1.83   -0.79    -0.10 -23.98  -0.00
   0     -0.00    0.02  -0.00   -3.55   -41.21    0.03  -0.00   -9.21    -0.81   0.01   0.00
   0      0       0      0       1        0        0      0      0        0       0      0
   0      0       0      0       0        0        0      1      0        0       0      0
   0     -0.00   -0.03  -9.75   -0.41    -1.62  -60.48  -6.05   -0.09    -0.10   0.91  -0.00
   0      0       0      0       0        0        0      0      0        1       0      0
   0     -0.02    0.18  -0.01   -0.59    -7.05    0.32  -0.01  -40.09    -3.59   0.06   0.00
   0     -0.00    0.01   0.33    0.05     0.53   -0.17  -0.01    2.03     0.19  -5.62   0.00
   0      0       0      0       0        0        0      0      0        0       0     -1.25
"""
# Columns: throttle brake steering
_B12 = """
 2.35  0     0
 0     0     0
 0     0    -1.09
 0     0   123.72
 0     0     0.04
 0     0     0
 0     0     0
 0     0   134.16
 0     0     0
 0     0     0.39
 0     0    49.17
 0     1.25  0
"""
# Rows: the 12 outputs.  Wheel rows 9 and 10, column 2: printed "0" (choice 1 above).
_C12 = """
 1     0      0      0      0       0       0      0      0       0      0      0
 0     1      0      0      0       0       0      0      0       0      0      0
 0     0.06  -0.68   0.06   0.51    5.95   -0.18  -0.00   15.84    1.40  -0.34  -0.00
 0    -0.00  -0.07  -9.03  -0.33   -2.84  -18.33  -1.83   -0.79   -0.10 -23.98  -0.00
 0    -0.00   0.02  -0.00  -3.55  -41.21    0.03  -0.00   -9.21   -0.81   0.01   0.00
 0     0      0      0      0       0       0      1      0       0      0      0
 0     0      0      0      0       0       0      0      0       1      0      0
 0     0      0      0      0       0       0      0      0       0      1      0
 0     0      3.54  -0.01  -2.24  -26.36  -19.11  -1.63   29.89    2.54  -2.56  -0.00
 0     0      3.58  -0.01  -2.30  -26.33   19.09   1.67   29.86    2.61   2.24  -0.00
 0     0.04   3.02  -0.01  -1.76  -20.06  -16.88  -1.47  -27.90   -2.45  -2.50  -0.00
 0     0.03   3.12  -0.01  -1.89  -22.20   17.93   1.53  -30.88   -2.62   2.56  -0.00
"""
_D12 = """
 0  0   0
 0  0   0
 0  0  -1.09
 0  0 123.72
 0  0   0.04
 0  0   0
 0  0   0
 0  0   0
 0  0  -0.00
 0  0  -0.00
 0  0   0
 0  0   0
"""
# 14-state additions, App. D (d.1a–c): the actuator columns alpha (12) and beta (14) of A
# (tau_b becomes column 13), B = rows 12-14 only, and C's beta column (C's alpha column is 0).
# Column alpha: rows 1..14.
_A14_ALPHA = "2.35 0 0 0 0 0 0 0 0 0 0 -90.91 0 0"
# Column beta: rows 1..14 (rows 1..12 equal the 12-state steering column of B).
_A14_BETA = "0 0 -1.09 123.72 0.04 0 0 134.16 0 0.39 49.17 0 0 -80.00"
_B14_TAIL = """
 90.91  0     0
 0      1.25  0
 0      0    80.00
"""
_C14_BETA = "0 0 -1.09 123.72 0.04 0 0 0 -0.00 -0.00 0 0"


def _parse(text: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Printed table -> (value, lower bound, upper bound) of the unrounded entries."""
    rows = [line.split() for line in text.strip().splitlines()]
    value = np.zeros((len(rows), len(rows[0])))
    lo, hi = value.copy(), value.copy()
    for i, row in enumerate(rows):
        if len(row) != value.shape[1]:
            raise AssertionError(f"transcription row {i} has {len(row)} entries, expected {value.shape[1]}")
        for j, token in enumerate(row):
            v = float(token)
            half = 0.5 * 10.0 ** -len(token.split(".")[1]) if "." in token else 0.0
            value[i, j] = v if v != 0 else 0.0
            if v == 0 and half:  # "0.00" / "-0.00": tiny, of the printed sign
                lo[i, j], hi[i, j] = (-half, 0.0) if token.startswith("-") else (0.0, half)
            else:
                lo[i, j], hi[i, j] = v - half, v + half
    return value, lo, hi


def _column(text: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _parse("\n".join(text.split()))


def _matrices_12() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return {"A": _parse(_A12), "Bu": _parse(_B12), "C": _parse(_C12), "Du": _parse(_D12)}


def _matrices_14() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    m12 = _matrices_12()
    # 12-state position of each 14-state state (None: actuator state alpha/beta).
    where = [STATES_12.index(s) if s in STATES_12 else None for s in STATES_14]
    keep = [i for i, k in enumerate(where) if k is not None]
    src = [k for k in where if k is not None]
    ia, ib = STATES_14.index("alpha"), STATES_14.index("beta")
    out = {}
    for part in range(3):  # value, lo, hi alike
        A = np.zeros((14, 14))
        A[np.ix_(keep, keep)] = m12["A"][part][np.ix_(src, src)]
        A[:, ia] = _column(_A14_ALPHA)[part][:, 0]
        A[:, ib] = _column(_A14_BETA)[part][:, 0]
        B = np.zeros((14, 3))
        B[11:, :] = _parse(_B14_TAIL)[part]
        C = np.zeros((12, 14))
        C[:, keep] = m12["C"][part][:, src]
        C[:, ib] = _column(_C14_BETA)[part][:, 0]
        for key, M in zip(("A", "Bu", "C", "Du"), (A, B, C, np.zeros((12, 3)))):
            out.setdefault(key, []).append(M)
    return {k: tuple(v) for k, v in out.items()}


def _with_tiny(m: dict, tiny: str) -> dict[str, np.ndarray]:
    """Printed values; with ``tiny='midpoint'`` entries printed ``±0.00`` become ``±0.0025``.

    The report's ``-0.00`` entries are nonzero couplings below the print precision; the
    most important are the brake-torque column of ``C`` (the report calls the brake "very
    weakly observable", §4.1).  With them at zero ``C`` of the 12-state model has rank 11
    and no sensor fault can be written as a state fault (``C F¹ = e_i`` has no solution);
    the midpoint of each rounding interval (half the last printed digit, with the printed
    sign) restores full rank.  This is an assumption, not report data.
    """
    if not isinstance(tiny, str) or tiny not in ("zero", "midpoint"):
        raise ParameterError(f"tiny must be 'zero' or 'midpoint', got {tiny!r}")
    out = {}
    for key, (value, lo, hi) in m.items():
        out[key] = value if tiny == "zero" else np.where((value == 0) & (lo != hi), (lo + hi) / 2, value)
    return out


def path_vehicle_12(tiny: str = "zero") -> FaultModel:
    """12-state PATH vehicle model for sensor-fault design (Douglas et al. 1996, App. D, (d.2a–d)).

    Continuous time, linearised in a 0.005 rad, 24.87 m/s constant-radius turn and
    reduced by residualisation (§2.3, method 1), with the throttle and steering
    actuators also residualised.  Hence ``B[:, steering]`` is the 14-state model's
    ``beta`` column of ``A`` and the accelerometer outputs carry a feedthrough:
    ``C[2:5] = A[2:5]`` and ``D[2:5] = B[2:5]`` (the outputs are the accelerations
    ``v_x', v_y', v_z'``; the printed ``D`` also has two ``-0.00`` wheel-speed entries).

    States ``m_a, omega_e, v_x, v_y, v_z, z, phi, phi_dot, theta, theta_dot, eps_dot,
    tau_b``; outputs :data:`OUTPUTS`; controls ``throttle`` (deg), ``brake`` (N·m),
    ``steering`` (rad).

    ``tiny='midpoint'`` restores the entries printed ``±0.00`` as ``±0.0025`` (an
    assumption; needed for sensor-fault detection filters, see :func:`_with_tiny`).

    Data are reconstructed from the transcribed App. D and **rounded to 2 decimals** in the
    original; see the module docstring for the transcription choices and
    :func:`rounding_intervals` for the uncertainty of each entry.  Eigenvalues:
    Table 2.1 without −90.91 and −80 (:data:`TABLE_2_1_EIGENVALUES_12`), to within the
    rounding.

    Parameters
    ----------
    tiny : {"zero", "midpoint"}, default "zero"
        How entries printed ``±0.00`` are read: as 0, or as ``±0.0025`` (the midpoint of their
        rounding interval; an assumption that gives ``C`` full rank).

    Returns
    -------
    FaultModel
        Continuous model, 12 states, the 12 outputs :data:`OUTPUTS`, the controls :data:`CONTROLS`
        (``Bu`` (12, 3), ``Du`` (12, 3)); no disturbance, fault or noise inputs.

    Raises
    ------
    ParameterError
        If ``tiny`` is not ``"zero"`` or ``"midpoint"``.

    References
    ----------
    Douglas et al. 1996, App. D, (d.2a–d); §2.3, Table 2.1.

    Examples
    --------
    >>> from fdikit.plants import path_vehicle_12
    >>> m = path_vehicle_12()
    >>> m.n, m.p, m.controls
    (12, 12, ('throttle', 'brake', 'steering'))
    """
    m = _with_tiny(_matrices_12(), tiny)
    return FaultModel(
        m["A"], m["C"], Bu=m["Bu"], Du=m["Du"],
        states=STATES_12, outputs=OUTPUTS, controls=CONTROLS,
    )


def path_vehicle_14(tiny: str = "zero") -> FaultModel:
    """14-state PATH vehicle model for actuator-fault design (Douglas et al. 1996, App. D, (d.1a–d)).

    As :func:`path_vehicle_12` but with the first-order throttle (``alpha``, pole
    −90.91) and steering (``beta``, pole −80) actuators kept as states, so
    ``B = [0; diag(90.91, 1.25, 80)]`` (rows ``alpha, tau_b, beta``) and ``D = 0``.
    A throttle fault enters along ``B[:, throttle]``, which the outputs do not see
    directly (``C B[:, 0] = 0``) but one step later only through the air mass
    (``C A B[:, 0] ∝ e_1``): throttle and air mass are not output separable (§4.1).

    States ``m_a, omega_e, v_x, v_y, v_z, z, phi, phi_dot, theta, theta_dot, eps_dot,
    alpha, tau_b, beta``.  Eigenvalues: Table 2.1, method 1
    (:data:`TABLE_2_1_EIGENVALUES_14`), to within the 2-decimal rounding of the data.
    Reconstructed data; see the module docstring.

    Parameters
    ----------
    tiny : {"zero", "midpoint"}, default "zero"
        How entries printed ``±0.00`` are read: as 0, or as ``±0.0025`` (see :func:`path_vehicle_12`).

    Returns
    -------
    FaultModel
        Continuous model, 14 states, the 12 outputs :data:`OUTPUTS`, the controls :data:`CONTROLS`
        (``Bu`` (14, 3), ``Du = 0``); no disturbance, fault or noise inputs.

    Raises
    ------
    ParameterError
        If ``tiny`` is not ``"zero"`` or ``"midpoint"``.

    References
    ----------
    Douglas et al. 1996, App. D, (d.1a–d); §2.3, Table 2.1.

    Examples
    --------
    >>> from fdikit.plants import path_vehicle_14
    >>> m = path_vehicle_14()
    >>> m.n, m.states[11], m.is_discrete
    (14, 'alpha', False)
    """
    m = _with_tiny(_matrices_14(), tiny)
    return FaultModel(
        m["A"], m["C"], Bu=m["Bu"], Du=m["Du"],
        states=STATES_14, outputs=OUTPUTS, controls=CONTROLS,
    )


def rounding_intervals(n_states: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Interval of each unrounded App. D entry that is consistent with the printed value.

    Parameters
    ----------
    n_states : {12, 14}
        Which model (:func:`path_vehicle_12` or :func:`path_vehicle_14`).

    Returns
    -------
    dict
        ``{"A": (lo, hi), "Bu": (lo, hi), "C": (lo, hi), "Du": (lo, hi)}`` with
        ``lo <= true entry <= hi``: ±0.005 around an entry printed with 2 decimals,
        ``[-0.005, 0]`` for ``-0.00``, ``[0, 0.005]`` for ``0.00``, and ``lo = hi`` for
        exact zeros (printed ``0``) and kinematic ones.  Use these to propagate the
        rounding of the printed data (e.g. Monte Carlo of the spectrum).

    Raises
    ------
    ParameterError
        If ``n_states`` is not 12 or 14.

    References
    ----------
    Douglas et al. 1996, App. D (the printed 2-decimal listings).

    Examples
    --------
    >>> lo, hi = rounding_intervals(12)["A"]
    >>> lo.shape, bool((lo <= hi).all())
    ((12, 12), True)
    """
    if n_states == 12:
        m = _matrices_12()
    elif n_states == 14:
        m = _matrices_14()
    else:
        raise ParameterError(f"the PATH App. D models have 12 or 14 states, got n_states={n_states!r}")
    return {key: (lo, hi) for key, (_, lo, hi) in m.items()}
