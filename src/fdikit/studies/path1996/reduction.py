"""Design models from the nonlinear car: linearisation at the §2.2 turn, Table 2.1 and Fig. 2.6.

Douglas et al. 1996, §2.2–2.3: the nonlinear car is linearised at the constant-radius turn
(0.005 rad road-wheel steer, 24.87 m/s), truncated exactly to the 22 states that the outputs see,
and reduced to 14 states two ways — Method 1, residualisation of the wheel speeds and suspension
states (the report's choice), and Method 2, balanced truncation — then to 12 states by also
residualising the throttle and steering actuators (static actuators, App. D).  Table 2.1 lists the
two 14-state spectra and Fig. 2.6 compares the singular values over 0.1–100 rad/s.

Here the same steps run on fdikit's own car (:class:`fdikit.vehicle.Sedan`).  The balanced
truncation uses the inputs and outputs scaled by their nominal sizes (§5.1.1: 2° throttle,
100 N m brake, 0.001 rad steer; the nominal sensor fault sizes), because Hankel singular values
depend on the units and the report's mixed units (kg, rad/s, m/s²) would otherwise decide the result.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.model import FaultModel

__all__ = ["DesignModels", "path_design_models", "match_eigenvalues", "FAST_STATES", "STATIC_ACTUATORS",
           "singular_values"]

#: States Method 1 residualises (§2.3): the wheel speeds and the suspension (force) states.
FAST_STATES = ("wheel_speed_fl", "wheel_speed_fr", "wheel_speed_rl", "wheel_speed_rr",
               "tire_force_fl", "tire_force_fr", "tire_force_rl", "tire_force_rr")
#: Actuators made static for the 12-state model (App. D).
STATIC_ACTUATORS = ("throttle", "steering")
_FORCES = ("normal_force_fl", "normal_force_fr", "normal_force_rl", "normal_force_rr")
#: State names of the App. D models, in the car's names (same order as ``plants.path_vehicle.STATES_14``).
_APP_D_14 = ("air_mass", "engine_speed", "v_x", "v_y", "v_z", "height", "roll", "roll_rate", "pitch", "pitch_rate",
             "yaw_rate", "throttle", "brake", "steering")


@dataclass(frozen=True, eq=False)
class DesignModels:
    """The linear models of §2.2–2.3 from the nonlinear car.

    Attributes
    ----------
    operating_point : OperatingPoint
        The turn linearised about.
    full : FaultModel
        The 22-state linearisation (deviation variables), outputs the 12 sensors.
    method1 : FaultModel
        14 states by residualisation (App. D 14-state order).
    method2 : FaultModel
        14 states by balanced truncation of the scaled model (balanced coordinates ``z0 …``; unscaled again).
    model12 : FaultModel
        12 states: ``method1`` with the throttle and steering actuators also residualised.
    hankel : ndarray
        Hankel singular values of the scaled 22-state model (Method 2).
    bound : float
        Method 2's H∞ error bound ``2 Σ σ_discarded`` (scaled units).

    References
    ----------
    Douglas et al. 1996, §2.2 (2.8), §2.3 (Methods 1 and 2, Table 2.1, Fig. 2.6), App. D.

    Examples
    --------
    >>> dm = path_design_models()  # doctest: +SKIP
    >>> dm.method1.n, dm.model12.n  # doctest: +SKIP
    (14, 12)
    """

    operating_point: object
    full: FaultModel
    method1: FaultModel
    method2: FaultModel
    model12: FaultModel
    hankel: np.ndarray
    bound: float


def _scales(car_nominal: dict | None) -> tuple[np.ndarray, np.ndarray]:
    from fdikit.vehicle import SENSORS

    u = np.array([2.0, 100.0, 0.001])
    if car_nominal is None:
        return u, np.ones(len(SENSORS))
    return u, np.array([car_nominal[f"{s}_sensor"] for s in SENSORS])


def path_design_models(car=None, *, speed: float = 24.87, steering: float = 0.005,
                       nominal: dict | None = None) -> DesignModels:
    """Linearise the car at the §2.2 turn and reduce the model as §2.3 does.

    Parameters
    ----------
    car : Sedan, optional
        The nonlinear car (default ``Sedan()``).
    speed : float, default 24.87
        Speed of the turn [m/s].
    steering : float, default 0.005
        Road-wheel steer angle [rad].
    nominal : dict of str to float, optional
        Nominal fault sizes (``<sensor>_sensor``) that scale the outputs for Method 2 (default: unscaled outputs).

    Returns
    -------
    DesignModels

    Raises
    ------
    DesignError
        When the operating point cannot be trimmed or a reduction fails.

    References
    ----------
    Douglas et al. 1996, §2.2–2.3, App. D.

    Examples
    --------
    >>> dm = path_design_models()  # doctest: +SKIP
    >>> [round(abs(l), 2) for l in sorted(np.linalg.eigvals(dm.method1.A), key=abs)][-2:]  # doctest: +SKIP
    [80.0, 90.91]
    """
    from fdikit.nonlinear import balanced_truncation, residualize
    from fdikit.vehicle import Sedan

    car = Sedan() if car is None else car
    op = car.operating_point(speed=speed, steering=steering)
    from fdikit.vehicle import SENSORS

    # one linearisation for the sensors and the tire forces (every entry's step is chosen on its own, so the
    # sensor rows are those of car.linearize(op))
    both = car.linearize(op, outputs=SENSORS + _FORCES)
    p = len(SENSORS)
    full = FaultModel(A=both.A, Bu=both.Bu, C=both.C[:p], Du=both.Du[:p], states=both.states, outputs=SENSORS,
                      controls=both.controls)
    m1 = residualize(_with_force_states(full, both.C[p:]), keep=list(_APP_D_14)).model
    m1 = _reorder(m1, _APP_D_14)
    m12 = residualize(m1, keep=[s for s in _APP_D_14 if s not in STATIC_ACTUATORS]).model
    su, sy = _scales(nominal)
    scaled = FaultModel(A=full.A, Bu=full.Bu * su, C=full.C / sy[:, None], Du=full.Du * su / sy[:, None],
                        states=full.states, outputs=full.outputs, controls=full.controls)
    bal = balanced_truncation(scaled, order=14)
    r = bal.model
    m2 = FaultModel(A=r.A, Bu=r.Bu / su, C=r.C * sy[:, None], Du=r.Du / su * sy[:, None], states=r.states,
                    outputs=full.outputs, controls=full.controls)
    return DesignModels(op, full, m1, m2, m12, np.asarray(bal.hankel), float(bal.error_bound))


def _with_force_states(full: FaultModel, dN: np.ndarray) -> FaultModel:
    """``full`` with each suspension length ``h_i`` replaced by the tire normal force ``N_i`` (Ch. 2's state ``F_i``).

    Residualising ``h_i`` (``ḣ_i = 0``) would freeze the dampers and leave the body modes undamped; the report's
    fast state is the force of the massless tire, and ``Ḟ_i = 0`` makes the wheel follow the road, so the damper
    acts on the body velocity (§2.1.1, (2.4)).  ``N_i`` is linear in the state near the point: ``N = K_w (r_w0 − r_w)``;
    ``dN`` holds its rows ``∂N_i/∂x`` (fl, fr, rl, rr).
    """
    T = np.eye(full.n)
    for k, c in enumerate(("fl", "fr", "rl", "rr")):
        T[full.states.index(f"suspension_{c}")] = dN[k]
    Ti = np.linalg.inv(T)
    states = [s.replace("suspension_", "tire_force_") for s in full.states]
    return FaultModel(A=T @ full.A @ Ti, Bu=T @ full.Bu, C=full.C @ Ti, Du=full.Du, states=states,
                      outputs=full.outputs, controls=full.controls)


def _reorder(m: FaultModel, order) -> FaultModel:
    idx = [m.states.index(s) for s in order]
    return FaultModel(A=m.A[np.ix_(idx, idx)], Bu=m.Bu[idx], C=m.C[:, idx], Du=m.Du, states=list(order),
                      outputs=m.outputs, controls=m.controls)


def match_eigenvalues(computed, reference) -> list[tuple[complex, complex, float]]:
    """Pair each reference eigenvalue with a computed one (minimum total distance), with the relative error.

    Parameters
    ----------
    computed, reference : array_like of complex
        Eigenvalues; ``len(computed) >= len(reference)``.

    Returns
    -------
    list of (reference, computed, relative error)
        In the reference order; the error is ``|λ_c − λ_r| / |λ_r|``.

    Raises
    ------
    ParameterError
        When there are fewer computed than reference eigenvalues.

    References
    ----------
    Douglas et al. 1996, Table 2.1 (the comparison it asks for).

    Examples
    --------
    >>> [(r, c, round(e, 3)) for r, c, e in match_eigenvalues([-2.0, -10.5], [-10.0, -2.0])]
    [(-10.0, -10.5, 0.05), (-2.0, -2.0, 0.0)]
    """
    from scipy.optimize import linear_sum_assignment

    from fdikit.errors import ParameterError

    c = np.asarray(computed, dtype=complex).ravel()
    r = np.asarray(reference, dtype=complex).ravel()
    if c.size < r.size:
        raise ParameterError(f"match_eigenvalues: {c.size} computed eigenvalues for {r.size} reference ones")
    cost = np.abs(r[:, None] - c[None, :]) / np.maximum(np.abs(r[:, None]), 1e-12)
    rows, cols = linear_sum_assignment(cost)
    out = [None] * r.size
    for i, j in zip(rows, cols):
        rv, cv = complex(r[i]), complex(c[j])
        out[i] = (rv.real if rv.imag == 0 else rv, cv.real if abs(cv.imag) < 1e-12 else cv, float(cost[i, j]))
    return out


def singular_values(model: FaultModel, frequencies) -> np.ndarray:
    """Singular values of ``C (jωI − A)⁻¹ B + D`` (control inputs to outputs) at each frequency (Fig. 2.6).

    Parameters
    ----------
    model : FaultModel
        Continuous model.
    frequencies : array_like
        ω [rad/s].

    Returns
    -------
    (len(frequencies), min(p, m)) ndarray
        Singular values, largest first.

    References
    ----------
    Douglas et al. 1996, §2.3, Fig. 2.6.

    Examples
    --------
    >>> m = FaultModel(A=[[-1.0]], Bu=[[1.0]], C=[[1.0]])
    >>> singular_values(m, [0.0, 1.0]).round(4).ravel().tolist()
    [1.0, 0.7071]
    """
    w = np.asarray(frequencies, dtype=float).ravel()
    n = model.n
    out = []
    for wk in w:
        G = model.C @ np.linalg.solve(1j * wk * np.eye(n) - model.A, model.Bu) + model.Du
        out.append(np.linalg.svd(G, compute_uv=False))
    return np.array(out)
