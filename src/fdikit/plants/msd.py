"""Three-mass mass–spring–damper (MSD) LPV benchmark: Hallouzi 2008, §3.6 (after Fekri et al. 2006b).

States ``x = [x1, x2, x3, v1, v2, v3]`` (positions, velocities), controls ``u1`` (force on m1) and
``u2`` (force on m3), outputs the three positions (sensor 2 faulty).  Varying parameters: the spring
``k1 ∈ [0.25, 1.75]`` and the mass ``m3 ∈ [0.2, 1.8]``; fault parameters ``f1`` (effectiveness of
actuator 1) and ``f2`` (gain of sensor 2), both in ``[0, 1]`` with 1 = healthy.  Fixed (3.43):
``m1 = m2 = 1``, ``b1 = … = b4 = 0.01``, ``k2 = 0.15``, ``k3 = 1``, ``k4 = 0.2``.

Erratum applied (Hallouzi 2008, §3.6.1): the printed (3.41) has ``m2`` in row 4 and
merges rows 5 and 6, and (3.42) prints ``1/m2`` for input 2.  The rows used here follow the
topology implied by the LV matrices (3.46)–(3.49) and relation (3.55): spring/damper 1 between
m1 and m2, 2 from m2 to ground, 3 between m1 and m3, 4 between m2 and m3; input 2 acts on m3.
(3.47) prints ``B⁺`` with three columns; it has two.  The sign of ``A^{k1}(5, 2)`` is fixed by
physics.

Examples
--------
>>> m = msd(k1=1.0, m3=1.0)
>>> m.n, m.p, m.controls
(6, 3, ('u1', 'u2'))
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = [
    "MSD_CONSTANTS",
    "MSD_RANGES",
    "MSD_SAMPLE_TIME",
    "msd_matrices",
    "msd",
    "msd_parameter_grid",
    "msd_model_vectors",
    "msd_parameters_to_weights",
    "msd_weights_to_parameters",
]

#: Fixed parameters (3.43).
MSD_CONSTANTS: dict[str, float] = {
    "m1": 1.0, "m2": 1.0, "b1": 0.01, "b2": 0.01, "b3": 0.01, "b4": 0.01, "k2": 0.15, "k3": 1.0, "k4": 0.2,
}
#: Ranges ``(min, max)`` of the varying and fault parameters (§3.6.1).
MSD_RANGES: dict[str, tuple[float, float]] = {"k1": (0.25, 1.75), "m3": (0.2, 1.8), "f1": (0.0, 1.0), "f2": (0.0, 1.0)}
#: Sample time of the first-order discretisation used for model-set design (§3.6.1).
MSD_SAMPLE_TIME = 2.5e-3

_STATES = ("x1", "x2", "x3", "v1", "v2", "v3")
_OUTPUTS = ("y1", "y2", "y3")
_CONTROLS = ("u1", "u2")


def _check(name: str, value: float, allow_outside: bool) -> float:
    value = validate.number(f"MSD parameter {name}", value, finite=False)
    if not np.isfinite(value):
        raise ParameterError(f"MSD parameter {name} must be finite, got {value}")
    if name == "m3" and value <= 0:
        raise ParameterError(f"MSD mass m3 must be positive, got {value}; its range is {MSD_RANGES['m3']}")
    lo, hi = MSD_RANGES[name]
    if not allow_outside and not lo <= value <= hi:
        raise ParameterError(f"MSD parameter {name}={value} is outside its range [{lo}, {hi}]; "
                         "pass allow_outside=True to extrapolate")
    return value


def msd_matrices(k1: float = 1.0, m3: float = 1.0, f1: float = 1.0, f2: float = 1.0,
                 allow_outside: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Continuous-time ``(A, B, C)`` of the MSD, Hallouzi 2008, (3.41)–(3.43) as repaired.

    Parameters
    ----------
    k1, m3 : float
        Varying spring constant and mass.
    f1, f2 : float
        Actuator-1 effectiveness and sensor-2 gain (1 = healthy, 0 = total fault).
    allow_outside : bool
        Accept values outside :data:`MSD_RANGES` (``m3`` must still be positive).

    Returns
    -------
    A : numpy.ndarray
        (6, 6) state matrix for ``x = [x1, x2, x3, v1, v2, v3]``.
    B : numpy.ndarray
        (6, 2) input matrix for ``u1`` (force on m1, scaled by ``f1``) and ``u2`` (force on m3).
    C : numpy.ndarray
        (3, 6) output matrix (the three positions, sensor 2 scaled by ``f2``).

    Raises
    ------
    ParameterError
        If a parameter is not a finite number, outside its range, or ``m3 <= 0``.

    References
    ----------
    Hallouzi 2008, §3.6, (3.41)–(3.43).

    Examples
    --------
    >>> A, B, C = msd_matrices(k1=1.75, m3=0.2, f1=0.0)
    >>> float(A[5, 0]), B[3].tolist(), float(B[5, 1])
    (5.0, [0.0, 0.0], 5.0)
    """
    k1 = _check("k1", k1, allow_outside)
    m3 = _check("m3", m3, allow_outside)
    f1 = _check("f1", f1, allow_outside)
    f2 = _check("f2", f2, allow_outside)
    c = MSD_CONSTANTS
    m1, m2, k2, k3, k4 = c["m1"], c["m2"], c["k2"], c["k3"], c["k4"]
    b1, b2, b3, b4 = c["b1"], c["b2"], c["b3"], c["b4"]
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3] = [-(k1 + k3) / m1, k1 / m1, k3 / m1, -(b1 + b3) / m1, b1 / m1, b3 / m1]
    A[4] = [k1 / m2, -(k1 + k2 + k4) / m2, k4 / m2, b1 / m2, -(b1 + b2 + b4) / m2, b4 / m2]
    A[5] = [k3 / m3, k4 / m3, -(k3 + k4) / m3, b3 / m3, b4 / m3, -(b3 + b4) / m3]
    B = np.zeros((6, 2))
    B[3, 0] = f1 / m1
    B[5, 1] = 1.0 / m3
    C = np.zeros((3, 6))
    C[0, 0], C[1, 1], C[2, 2] = 1.0, f2, 1.0
    return A, B, C


def msd(k1: float = 1.0, m3: float = 1.0, f1: float = 1.0, f2: float = 1.0, dt: float | None = None,
        allow_outside: bool = False) -> FaultModel:
    """The MSD as a :class:`~fdikit.model.FaultModel`, continuous or first-order discretised.

    With ``dt`` the model is ``x[k+1] = (I + dt A) x[k] + dt B u[k]`` (Hallouzi 2008, App. B,
    (B.8)–(B.9), ``M = 1``; §3.6.1 uses ``dt = 2.5e-3``), the discretisation that keeps a convex
    combination of local models equal to the discretised combination.  Additive fault channels
    ``u1_actuator`` and ``y2_sensor`` are attached for residual design; the multiplicative faults of
    the thesis are the parameters ``f1``, ``f2``.

    Parameters
    ----------
    k1, m3 : float, default 1.0
        Varying spring constant and mass (ranges in :data:`MSD_RANGES`).
    f1, f2 : float, default 1.0
        Actuator-1 effectiveness and sensor-2 gain (1 = healthy, 0 = total fault).
    dt : float or None, default None
        Sample time [s] of the first-order discretisation; ``None`` gives the continuous model.
    allow_outside : bool, default False
        Accept parameter values outside :data:`MSD_RANGES`.

    Returns
    -------
    FaultModel
        6 states, controls ``u1, u2``, outputs ``y1 … y3`` and the fault inputs ``u1_actuator``,
        ``y2_sensor``; discrete with ``dt`` if given.

    Raises
    ------
    ParameterError
        On a bad parameter (see :func:`msd_matrices`) or a ``dt`` that is not a finite positive number.

    References
    ----------
    Hallouzi 2008, §3.6, (3.41)–(3.43); App. B, (B.8)–(B.9).

    Examples
    --------
    >>> m = msd(k1=1.75, f2=0.5, dt=MSD_SAMPLE_TIME)
    >>> m.dt, m.faults
    (0.0025, ('u1_actuator', 'y2_sensor'))
    """
    A, B, C = msd_matrices(k1, m3, f1, f2, allow_outside=allow_outside)
    if dt is not None:
        dt = validate.number("dt", dt, finite=False)
        if not np.isfinite(dt) or dt <= 0:
            raise ParameterError(f"dt must be a positive sample time or None (continuous), got {dt}")
        A, B = np.eye(6) + dt * A, dt * B
    model = FaultModel(A, C, Bu=B, states=_STATES, outputs=_OUTPUTS, controls=_CONTROLS, dt=dt)
    return model.with_actuator_faults(["u1"]).with_sensor_faults(["y2"])


def msd_parameter_grid(k1_values=None, m3_values=None, fault_values=None) -> np.ndarray:
    """Parameter tuples ``(k1, m3, f1, f2)`` of the large model set of §3.6.1 (single faults only).

    The thesis does not give the grids; the defaults (an fdikit choice) are
    ``k1 ∈ 0.25:0.125:1.75`` (13), ``m3 ∈ linspace(0.2, 1.8, 13)`` and fault levels
    ``{0, 0.1, …, 1}``.  The (k1, m3) grid is crossed with ``f1 ∈ fault_values, f2 = 1`` and with
    ``f1 = 1, f2 ∈ fault_values \\ {1}`` (each healthy model appears once).

    Parameters
    ----------
    k1_values, m3_values : array_like, optional
        Grid values of the spring ``k1`` and the mass ``m3`` (defaults above).
    fault_values : array_like, optional
        Fault levels used for ``f1`` and ``f2`` in turn (default ``{0, 0.1, …, 1}``).

    Returns
    -------
    numpy.ndarray
        ``(N_ℓ, 4)`` array, columns ``k1, m3, f1, f2``.

    Raises
    ------
    ParameterError
        If one of the grids is empty.

    References
    ----------
    Hallouzi 2008, §3.6.1; the large model set ``M_ℓ``, (3.15).

    Examples
    --------
    >>> msd_parameter_grid().shape
    (3549, 4)
    >>> msd_parameter_grid([1.0], [1.0], [0.0, 1.0]).tolist()
    [[1.0, 1.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 0.0]]
    """
    k1_values = np.linspace(0.25, 1.75, 13) if k1_values is None else np.asarray(k1_values, float).ravel()
    m3_values = np.linspace(0.2, 1.8, 13) if m3_values is None else np.asarray(m3_values, float).ravel()
    faults = np.linspace(0.0, 1.0, 11) if fault_values is None else np.asarray(fault_values, float).ravel()
    if k1_values.size == 0 or m3_values.size == 0 or faults.size == 0:
        raise ParameterError("msd_parameter_grid needs at least one value for k1, m3 and the fault levels")
    pairs = [(f, 1.0) for f in faults] + [(1.0, f) for f in faults if f != 1.0]
    if 1.0 not in faults:
        pairs.append((1.0, 1.0))
    rows = [(k1, m3, f1, f2) for (f1, f2) in pairs for k1 in k1_values for m3 in m3_values]
    return np.array(rows)


def msd_model_vectors(parameters, dt: float | None = MSD_SAMPLE_TIME) -> np.ndarray:
    """Large model set ``M_ℓ`` (3.14)–(3.15) of the MSD: one column ``vec([A_d B_d; C 0])`` per tuple.

    ``vec`` stacks columns (Fortran order); ``A_d = I + dt A``, ``B_d = dt B`` (App. B, first
    order) or the continuous matrices if ``dt is None``.  Shape ``(72, N_ℓ)``.

    Parameters
    ----------
    parameters : array_like
        ``(N_ℓ, 4)`` tuples ``(k1, m3, f1, f2)`` (one tuple may be given as a 4-vector), each within
        :data:`MSD_RANGES`, e.g. from :func:`msd_parameter_grid`.
    dt : float or None, default MSD_SAMPLE_TIME
        Sample time [s] of the first-order discretisation; ``None`` for the continuous matrices.

    Returns
    -------
    numpy.ndarray
        ``(72, N_ℓ)`` array, one column ``vec([A_d B_d; C 0])`` (a 9 × 8 block) per tuple.

    Raises
    ------
    ParameterError
        If ``parameters`` does not have 4 columns.
    ParameterError
        If a parameter is not finite or outside its range (see :func:`msd_matrices`).

    References
    ----------
    Hallouzi 2008, §3.3.2, (3.14)–(3.15); §3.6.1.

    Examples
    --------
    >>> msd_model_vectors([[1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 0.0, 1.0]]).shape
    (72, 2)
    """
    parameters = np.atleast_2d(np.asarray(parameters, float))
    if parameters.shape[1] != 4:
        raise ParameterError(f"parameters must have 4 columns (k1, m3, f1, f2), got shape {parameters.shape}")
    columns = []
    for k1, m3, f1, f2 in parameters:
        A, B, C = msd_matrices(k1, m3, f1, f2)
        if dt is not None:
            A, B = np.eye(6) + dt * A, dt * B
        columns.append(np.block([[A, B], [C, np.zeros((3, 2))]]).ravel(order="F"))
    return np.column_stack(columns)


def msd_parameters_to_weights(k1: float, m3: float, f1: float, f2: float) -> np.ndarray:
    """Limit-value weights ``(μ_k1, μ_m3, μ_f1, μ_f2)`` of a parameter tuple: inverse of (3.54)–(3.57).

    ``μ = 0`` is the "+" limit (``k1max``, ``m3max``, healthy) and ``μ = 1`` the other limit;
    ``μ_m3`` is affine in ``1/m3``.

    Parameters
    ----------
    k1, m3 : float
        Spring constant and mass (``m3 > 0``).
    f1, f2 : float
        Actuator-1 effectiveness and sensor-2 gain (1 = healthy).

    Returns
    -------
    numpy.ndarray
        (4,) weights ``[μ_k1, μ_m3, μ_f1, μ_f2]`` (in ``[0, 1]`` for parameters within :data:`MSD_RANGES`).

    Raises
    ------
    ParameterError
        If ``m3 <= 0``.

    References
    ----------
    Hallouzi 2008, §3.6.2, (3.54)–(3.57).

    Examples
    --------
    >>> msd_parameters_to_weights(1.0, 1.0, 1.0, 1.0).round(12).tolist()
    [0.5, 0.1, 0.0, 0.0]
    """
    (k1lo, k1hi), (m3lo, m3hi) = MSD_RANGES["k1"], MSD_RANGES["m3"]
    if m3 <= 0:
        raise ParameterError(f"m3 must be positive, got {m3}")
    return np.array([
        (k1 - k1hi) / (k1lo - k1hi),
        (1.0 / m3 - 1.0 / m3hi) / (1.0 / m3lo - 1.0 / m3hi),
        1.0 - f1,
        1.0 - f2,
    ])


def msd_weights_to_parameters(weights) -> tuple[float, float, float, float]:
    """Parameters ``(k1, m3, f1, f2)`` from limit-value weights, Hallouzi 2008, (3.54)–(3.57).

    ``k1 = k1max + μ_k1 (k1min − k1max)``, ``m3 = m3max m3min / (m3min + μ_m3 (m3max − m3min))``,
    ``f1 = 1 − μ_f1``, ``f2 = 1 − μ_f2``.

    Parameters
    ----------
    weights : array_like
        Four limit-value weights ``(μ_k1, μ_m3, μ_f1, μ_f2)``.

    Returns
    -------
    tuple of float
        ``(k1, m3, f1, f2)``.

    Raises
    ------
    ParameterError
        If ``weights`` does not hold exactly 4 values.

    References
    ----------
    Hallouzi 2008, §3.6.2, (3.54)–(3.57).

    Examples
    --------
    >>> [round(v, 12) for v in msd_weights_to_parameters([0.5, 0.1, 0.0, 0.0])]
    [1.0, 1.0, 1.0, 1.0]
    """
    mu = np.asarray(weights, float).ravel()
    if mu.shape != (4,):
        raise ParameterError(f"expected 4 weights (μ_k1, μ_m3, μ_f1, μ_f2), got shape {mu.shape}")
    (k1lo, k1hi), (m3lo, m3hi) = MSD_RANGES["k1"], MSD_RANGES["m3"]
    k1 = k1hi + mu[0] * (k1lo - k1hi)
    m3 = m3hi * m3lo / (m3lo + mu[1] * (m3hi - m3lo))
    return float(k1), float(m3), float(1.0 - mu[2]), float(1.0 - mu[3])
