"""Renault Scénic lateral dynamics, LPV in ρ = 1/v (Varrier et al. 2014, §5.1, (47)–(48)).

Bicycle model with states side-slip ``β`` and yaw rate ``r``, steering input ``u_L`` and
outputs lateral acceleration ``a_y`` and ``r``, (47)::

    β' = −(c_V + c_H)/(m v) β + ((l_H c_H − l_V c_V)/(m v²) − 1) r + c_V/(m v) u_L
    r' =  (l_H c_H − l_V c_V)/I_z β − (l_V² c_V + l_H² c_H)/(I_z v) r + l_V c_V/I_z u_L
    a_y = −(c_V + c_H)/m β + (l_H c_H − l_V c_V)/(m v) r + c_V/m u_L

Two typos of the printed (47) are corrected, as (48) and the identity ``a_y = v (β' + r)``
require: the ``r'``-row ``r``-entry carries a minus sign, and the
``a_y``-row ``r``-entry has ``1/v``, not ``1/v²``.

The discrete model (48) is the forward-Euler ("rectangular") discretisation at ``T_d``,
``A₀ = I + T_d A``, ``B₀ = T_d B``, ``C₀ = C``, ``D₀ = D``, polynomial in ``ρ = 1/v`` with
``ρ₂ = 1/v² = ρ²`` substituted (§5.1).  ``T_d`` is not printed; 0.02 s follows from "s = 3
samples (60 ms)" (§5.3).  Euler is unstable below about 1.3 m/s at 0.02 s (spectral radius
of ``A₀`` above 1).

The paper's uncertainty and unknown input (§5.3): ``A₁ = 0.2 A₀(ρ*)``, ``B_d = 0.2 B₀(ρ*)``,
``D_d = [0; 2.064]`` with ``ρ* = 1/20.83 = 0.048``; the fault is an additive bias on the
``a_y`` sensor (``D_f = [1; 0]``, ``B_f = 0``, §5.4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.lpv import LPVModel, Uncertainty
from fdikit.model import FaultModel

__all__ = [
    "VarrierParameters",
    "SCENIC",
    "RHO_STAR",
    "T_D",
    "varrier_lateral_continuous",
    "varrier_lateral_lpv",
    "varrier_lateral",
    "varrier_uncertainty",
    "rho_from_speed",
    "STATES",
    "OUTPUTS",
    "CONTROLS",
]

STATES: tuple[str, ...] = ("sideslip", "yaw_rate")
OUTPUTS: tuple[str, ...] = ("lateral_acceleration", "yaw_rate")
CONTROLS: tuple[str, ...] = ("steering",)
DISTURBANCES: tuple[str, ...] = ("unknown_input",)
FAULTS: tuple[str, ...] = ("lateral_acceleration_sensor",)
#: Design scheduling point ρ* = 1/20.83 ≈ 0.048 (75 km/h), §5.3, used as printed.
RHO_STAR: float = 0.048
#: Sample time (s) inferred from "s = 3 samples (60 ms)", §5.3.
T_D: float = 0.02


@dataclass(frozen=True)
class VarrierParameters:
    """Vehicle parameters of the Renault Scénic (Varrier et al. 2014, §5.1 table).

    Attributes
    ----------
    m : float
        Mass (kg).
    l_V, l_H : float
        Centre of gravity to front / rear axle (m).
    I_z : float
        Yaw inertia (kg m²).
    c_V, c_H : float
        Front / rear axle cornering stiffness (N/rad, positive).
    g : float
        Gravity (m/s², listed in the table, unused by the model).

    Raises
    ------
    ParameterError
        On construction, if a field is not a positive finite number.

    References
    ----------
    Varrier et al. 2014, §5.1 (the parameter table).

    Examples
    --------
    >>> VarrierParameters(m=1700.0).m
    1700.0
    """

    m: float = 1621.0
    l_V: float = 1.15
    l_H: float = 1.38
    I_z: float = 1975.0
    c_V: float = 57117.0
    c_H: float = 81396.0
    g: float = 9.80665

    def __post_init__(self) -> None:
        for name in ("m", "l_V", "l_H", "I_z", "c_V", "c_H", "g"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ParameterError(f"VarrierParameters.{name} must be a positive finite number, got {value!r}")


#: The table of §5.1.
SCENIC = VarrierParameters()


def rho_from_speed(speed) -> np.ndarray | float:
    """Scheduling parameter ``ρ = 1/v`` (v in m/s), §5.1.

    Parameters
    ----------
    speed : float or array_like
        Longitudinal speed(s) ``v`` [m/s].

    Returns
    -------
    float or numpy.ndarray
        ``ρ = 1/v`` [s/m]: a float for a scalar speed, else an array of the speeds' shape.

    Raises
    ------
    ParameterError
        If a speed is not positive and finite.

    References
    ----------
    Varrier et al. 2014, §5.1.

    Examples
    --------
    >>> rho_from_speed(20.0)
    0.05
    >>> rho_from_speed([10.0, 20.0]).tolist()
    [0.1, 0.05]
    """
    v = validate.as_array("speed", speed, finite=False)
    if not np.all(np.isfinite(v) & (v > 0)):
        raise ParameterError("speed must be positive and finite (m/s) to schedule on rho = 1/v; "
                         f"got min {np.nanmin(v) if v.size else v}")
    rho = 1.0 / v
    return float(rho) if rho.ndim == 0 else rho


def _check_dt(dt) -> float:
    try:
        dt = float(dt)
    except (TypeError, ValueError):
        raise ParameterError(f"dt must be a positive sample time in s, got {dt!r}") from None
    if not (math.isfinite(dt) and dt > 0):
        raise ParameterError(f"dt must be a positive sample time in s, got {dt!r}")
    return dt


def _check_params(params) -> VarrierParameters:
    if not isinstance(params, VarrierParameters):
        raise ParameterError(f"params must be a VarrierParameters, got {type(params).__name__}")
    return params


def varrier_lateral_continuous(speed: float, params: VarrierParameters = SCENIC) -> FaultModel:
    """Continuous bicycle model (47), corrected, at a constant speed (m/s).

    Parameters
    ----------
    speed : float
        Longitudinal speed ``v`` [m/s], positive.
    params : VarrierParameters, default SCENIC
        Vehicle parameters (§5.1 table).

    Returns
    -------
    FaultModel
        Continuous model, states ``sideslip`` [rad], ``yaw_rate`` [rad/s]; outputs
        ``lateral_acceleration`` [m/s²], ``yaw_rate``; control ``steering`` [rad] (with feedthrough
        ``Du``); no disturbance or fault inputs.

    Raises
    ------
    ParameterError
        If ``speed`` is not one positive finite number, or ``params`` is not a :class:`VarrierParameters`.

    References
    ----------
    Varrier et al. 2014, §5.1, (47) (two typos corrected, see the module docstring).

    Examples
    --------
    >>> m = varrier_lateral_continuous(20.0)
    >>> round(float(m.A[0, 0]), 6)
    -4.272455
    """
    rho = rho_from_speed(speed)
    if np.ndim(rho):
        raise ParameterError("speed must be a single number")
    p = _check_params(params)
    cs, cd = p.c_V + p.c_H, p.l_H * p.c_H - p.l_V * p.c_V
    A = [[-cs / p.m * rho, cd / p.m * rho**2 - 1.0], [cd / p.I_z, -(p.l_V**2 * p.c_V + p.l_H**2 * p.c_H) / p.I_z * rho]]
    B = [[p.c_V / p.m * rho], [p.l_V * p.c_V / p.I_z]]
    C = [[-cs / p.m, cd / p.m * rho], [0.0, 1.0]]
    D = [[p.c_V / p.m], [0.0]]
    return FaultModel(A, C, Bu=B, Du=D, states=STATES, outputs=OUTPUTS, controls=CONTROLS)


def varrier_lateral_lpv(dt: float = T_D, params: VarrierParameters = SCENIC, *, rho_star: float = RHO_STAR
                        ) -> LPVModel:
    """Discrete LPV model (48a)–(48d) as a polynomial in ρ = 1/v, with ``B_d, D_d`` and the ``a_y`` fault.

    ``A₀(ρ) = A₀₀ + ρ A₀₁ + ρ² A₀₂``, ``B₀(ρ) = B₀₀ + ρ B₀₁``, ``C₀(ρ) = C₀₀ + ρ C₀₁``,
    ``D₀`` constant; disturbance ``unknown_input`` with ``B_d = 0.2 B₀(ρ*)`` and
    ``D_d = [0; 2.064]`` (§5.3); fault ``lateral_acceleration_sensor`` with ``D_f = [1; 0]`` (§5.4).

    Parameters
    ----------
    dt : float, default T_D (0.02)
        Sample time ``T_d`` [s] of the forward-Euler discretisation.
    params : VarrierParameters, default SCENIC
        Vehicle parameters.
    rho_star : float, default RHO_STAR (0.048)
        Scheduling point ρ* [s/m] of ``B_d = 0.2 B₀(ρ*)``.

    Returns
    -------
    LPVModel
        Degree-2 polynomial in ρ (scheduling ``"1/speed"``): terms ``0, 1, 2`` are discrete
        :class:`~fdikit.model.FaultModel` coefficient matrices with 2 states, 2 outputs, the control
        ``steering``, the disturbance ``unknown_input`` and the fault ``lateral_acceleration_sensor``.

    Raises
    ------
    ParameterError
        If ``dt`` or ``rho_star`` is not a positive number, or ``params`` is not a :class:`VarrierParameters`.

    References
    ----------
    Varrier et al. 2014, §5.1, (48a)–(48d); §5.3 (``B_d``, ``D_d``); §5.4 (``D_f``).

    Examples
    --------
    >>> lpv = varrier_lateral_lpv()
    >>> lpv.degree, lpv.outputs
    (2, ('lateral_acceleration', 'yaw_rate'))
    """
    dt, p = _check_dt(dt), _check_params(params)
    rho_star = validate.positive("rho_star", rho_star)
    cs, cd = p.c_V + p.c_H, p.l_H * p.c_H - p.l_V * p.c_V
    cq = p.l_V**2 * p.c_V + p.l_H**2 * p.c_H
    A = [np.array([[1.0, -dt], [dt * cd / p.I_z, 1.0]]),
         np.array([[-dt * cs / p.m, 0.0], [0.0, -dt * cq / p.I_z]]),
         np.array([[0.0, dt * cd / p.m], [0.0, 0.0]])]
    B = [np.array([[0.0], [dt * p.l_V * p.c_V / p.I_z]]), np.array([[dt * p.c_V / p.m], [0.0]]), np.zeros((2, 1))]
    C = [np.array([[-cs / p.m, 0.0], [0.0, 1.0]]), np.array([[0.0, cd / p.m], [0.0, 0.0]]), np.zeros((2, 2))]
    D = [np.array([[p.c_V / p.m], [0.0]]), np.zeros((2, 1)), np.zeros((2, 1))]
    Bd = 0.2 * (B[0] + rho_star * B[1])
    names = dict(states=STATES, outputs=OUTPUTS, controls=CONTROLS, disturbances=DISTURBANCES, faults=FAULTS, dt=dt)
    terms = {}
    for j in range(3):
        terms[j] = FaultModel(
            A[j], C[j], Bu=B[j], Du=D[j],
            Bd=Bd if j == 0 else np.zeros((2, 1)), Dd=[[0.0], [2.064]] if j == 0 else np.zeros((2, 1)),
            Bf=np.zeros((2, 1)), Df=[[1.0], [0.0]] if j == 0 else np.zeros((2, 1)), **names,
        )
    return LPVModel(terms, scheduling="1/speed")


def varrier_lateral(speed: float = 1.0 / RHO_STAR, dt: float = T_D, params: VarrierParameters = SCENIC) -> FaultModel:
    """The discrete model (48) frozen at one speed (m/s); default 20.83 m/s (ρ* = 0.048).

    Parameters
    ----------
    speed : float, default 1 / RHO_STAR (20.83)
        Longitudinal speed ``v`` [m/s], positive.
    dt : float, default T_D (0.02)
        Sample time [s].
    params : VarrierParameters, default SCENIC
        Vehicle parameters.

    Returns
    -------
    FaultModel
        Discrete model ``(48)`` at ``ρ = 1/speed``, with the disturbance ``unknown_input`` and the
        fault ``lateral_acceleration_sensor`` of :func:`varrier_lateral_lpv`.

    Raises
    ------
    ParameterError
        If ``speed`` is not one positive finite number, or ``dt`` or ``params`` is invalid.

    References
    ----------
    Varrier et al. 2014, §5.1, (48); §5.3–5.4.

    Examples
    --------
    >>> round(float(varrier_lateral(1 / 0.048).A[0, 0]), 6)
    0.917969
    """
    rho = rho_from_speed(speed)
    if np.ndim(rho):
        raise ParameterError("speed must be a single number")
    return varrier_lateral_lpv(dt, params).at(rho)


def varrier_uncertainty(dt: float = T_D, params: VarrierParameters = SCENIC, *, mode: str = "literal",
                        rho_star: float = RHO_STAR, scale: float = 0.2) -> Uncertainty:
    """The uncertainty ``Ā = A₀(ρ) + δ A₁`` of §5.3 (one δ, C certain).

    Parameters
    ----------
    dt : float, default T_D (0.02)
        Sample time [s] of the discrete model (48).
    params : VarrierParameters, default SCENIC
        Vehicle parameters.
    mode : {"literal", "continuous"}, default "literal"
        ``"literal"`` — ``A₁ = 0.2 A₀(ρ*)`` as printed (it contains ``0.2 I``, a ±20 %
        per-step scaling of the state); ``"continuous"`` — ``A₁ = 0.2 (A₀(ρ*) − I) = 0.2 T_d A(ρ*)``,
        20 % of the continuous dynamics (an fdikit reading, not the paper's).
    rho_star : float, default RHO_STAR (0.048)
        Scheduling point ρ* [s/m] at which ``A₀`` is evaluated.
    scale : float, default 0.2
        The 20 % of §5.3.

    Returns
    -------
    Uncertainty
        One uncertain direction ``stiffness`` with ``A`` of shape (1, 2, 2) (``A₁``); ``C`` certain.

    Raises
    ------
    ParameterError
        If ``mode`` is not one of the two readings, or ``dt``, ``params``, ``rho_star`` or ``scale`` is invalid.

    References
    ----------
    Varrier et al. 2014, §5.3.

    Examples
    --------
    >>> u = varrier_uncertainty(mode="continuous")
    >>> u.name, u.A.shape, round(float(u.A[0, 0, 0]), 6)
    ('stiffness', (1, 2, 2), -0.016406)
    """
    scale = validate.number("scale", scale)
    validate.choice("uncertainty mode", mode, ("literal", "continuous"))
    lpv = varrier_lateral_lpv(dt, params, rho_star=rho_star)
    A0 = lpv.matrices(rho_star)[0]
    if mode == "literal":
        A1 = scale * A0
    elif mode == "continuous":
        A1 = scale * (A0 - np.eye(2))
    else:
        raise ParameterError(f"unknown uncertainty mode {mode!r}; use 'literal' (0.2 A0(rho*)) or 'continuous'")
    return Uncertainty(A=A1, n=2, p=2, name="stiffness")
