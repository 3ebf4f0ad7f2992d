"""Mean-value spark-ignition engine with the manifold air mass as state.

The PATH model's engine is the Berkeley model (Douglas et al. 1996, Ch. 2; Cho & Hedrick 1989),
only cited in the report: its states are the manifold air mass ``m_a`` [kg] and the engine speed
``ω_e``, measured by the first two PATH sensors.  This module is a published mean-value model of
that structure:

* throttle flow (Cho & Hedrick 1989): ``ṁ_in = MAX · TC(α) · PRI(p_m)`` with
  ``TC(α) = 1 − cos(1.14459 α − 1.06)`` (degrees; 1 above 79.46°) and the pressure-ratio
  influence ``PRI = 1 − exp(9 (p_m/p_atm − 1))``;
* manifold: ideal gas, ``p_m = m_a R T_m / V_m``; port flow by speed density (Hendricks &
  Sorenson 1990; Heywood 1988): ``ṁ_out = η_v V_d ω_e m_a / (4π V_m)``;
* torque (Heywood 1988, Ch. 13 and 15): indicated ``T_i = η_i Q_LHV ṁ_out / (AFR ω_e)`` (fuel
  energy per cycle; stoichiometric mixture), friction ``T_f = fmep V_d/(4π)`` with
  ``fmep = 0.97 + 0.15 N + 0.05 N²`` bar (N in 1000 rpm), pumping ``(p_atm − p_m) V_d/(4π)``;
  ``T_e = T_i − T_f − T_pump``.

Choices the sources leave to the user (``V_d``, ``V_m``, ``η_v``, ``η_i``) are in
:class:`~fdikit.vehicle.parameters.SedanParameters`.  Induction-to-power delay and fuel
wall-wetting are not modelled (a mean-value model at the report's time scales).  Written by hand:
no maintained Python library provides a mean-value engine.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["engine_state", "ENGINE_FIELDS"]

#: The engine numbers in the order the compiled kernel reads them.
ENGINE_FIELDS = ("throttle_max_flow", "manifold_volume", "manifold_temperature", "displacement",
                 "volumetric_efficiency", "indicated_efficiency", "fuel_heating_value", "air_fuel_ratio",
                 "ambient_pressure")

_R_AIR = 287.05  # J/(kg K)
_ALPHA_WOT = 79.46  # deg: TC(α) = 1 above


@njit(cache=True)
def engine_kernel(e, m_a, omega_e, alpha_deg):  # pragma: no cover - compiled
    """``(ṁ_a, T_e, p_m)``: manifold mass rate [kg/s], net torque [N m] and manifold pressure [Pa]."""
    max_flow, v_m, t_m, v_d, eta_v, eta_i, q_lhv, afr, p_atm = e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8]
    a = min(max(alpha_deg, 0.0), _ALPHA_WOT)
    tc = 1.0 - math.cos(math.radians(1.14459 * a - 1.06))
    p_m = m_a * _R_AIR * t_m / v_m
    pri = 1.0 - math.exp(9.0 * (p_m / p_atm - 1.0))
    m_in = max_flow * tc * pri
    m_out = eta_v * v_d * omega_e * m_a / (4.0 * math.pi * v_m)
    t_i = eta_i * q_lhv * eta_v * v_d * m_a / (4.0 * math.pi * v_m * afr)  # = η_i Q ṁ_out / (AFR ω_e)
    n_krpm = omega_e * 30.0 / math.pi * 1e-3
    fmep = (0.97 + 0.15 * n_krpm + 0.05 * n_krpm * n_krpm) * 1e5
    t_f = fmep * v_d / (4.0 * math.pi)
    t_pump = (p_atm - p_m) * v_d / (4.0 * math.pi)
    return m_in - m_out, t_i - t_f - t_pump, p_m


def engine_state(params, air_mass, engine_speed, throttle) -> dict[str, np.ndarray]:
    """Air-mass rate, net torque and manifold pressure of the engine at given states and throttle.

    Parameters
    ----------
    params : SedanParameters
        The car (its engine numbers are used).
    air_mass : array_like
        Manifold air mass ``m_a`` [kg].
    engine_speed : array_like
        ``ω_e`` [rad/s].
    throttle : array_like
        Throttle angle ``α`` [deg].

    Returns
    -------
    dict of str to ndarray
        ``"air_mass_rate"`` [kg/s], ``"torque"`` [N m], ``"manifold_pressure"`` [Pa].

    Raises
    ------
    ParameterError
        For inputs that are not finite.

    References
    ----------
    Cho & Hedrick 1989 (throttle flow); Hendricks & Sorenson 1990 (speed density); Heywood 1988 (torque, friction).

    Examples
    --------
    >>> from fdikit.vehicle.parameters import MID_SIZE_SEDAN
    >>> out = engine_state(MID_SIZE_SEDAN, 1.0e-3, 190.0, 20.0)
    >>> round(float(out["manifold_pressure"]) / 1e3, 1)  # kPa
    46.5
    """
    from fdikit import validate

    arrays = np.broadcast_arrays(*(validate.as_array(f"engine_state: {name}", v) for name, v in
                                   (("air_mass", air_mass), ("engine_speed", engine_speed), ("throttle", throttle))))
    e = params.engine_array()
    out = {k: np.empty(arrays[0].shape) for k in ("air_mass_rate", "torque", "manifold_pressure")}
    for k in np.ndindex(arrays[0].shape):
        out["air_mass_rate"][k], out["torque"][k], out["manifold_pressure"][k] = engine_kernel(
            e, float(arrays[0][k]), float(arrays[1][k]), float(arrays[2][k]))
    return out
