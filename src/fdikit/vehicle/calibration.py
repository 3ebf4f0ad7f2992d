"""Calibration of the nonlinear car to the PATH report's own figures.

Douglas et al. 1996 prints three steady-state figures of its cars: 22.555 % throttle holds 27 m/s
(§8.3.1, the Ch. 8 model); a 0.01 rad step steer at 27 m/s (throttle held) settles at ≈ 0.2 g with
R ≈ 310 m (§8.3.2); a 0.005 rad steer at 24.87 m/s gives ≈ 0.1 g and R = 638.73 m (§2.2, the
Berkeley model; §8.3.2 gives ≈ 620 m at ≈ 26.5 m/s for its own).  :func:`calibrate` solves two
parameters for the first and third figures (each a 1-D root by Brent's method, alternated to a
fixed point); :func:`calibration_figures` measures all of them on any car, by trim — the steady
state a step steer settles to (the behaviour tests check the run converges to it).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CalibrationFigures", "calibration_figures", "calibrate", "REPORT_FIGURES", "THROTTLE_27"]

#: 22.555 % of the 90° throttle [deg].
THROTTLE_27 = 0.22555 * 90.0
#: The report's figures (Douglas et al. 1996, §2.2, §8.3.1–8.3.2).
REPORT_FIGURES = {"speed_at_22.555%": 27.0, "step_steer_g": 0.2, "step_steer_radius": 310.0,
                  "turn_radius_24.87": 638.73, "turn_g_24.87": 0.1}


@dataclass(frozen=True)
class CalibrationFigures:
    """The report's steady-state figures measured on a car.

    Attributes
    ----------
    speed : float
        Straight-line speed at 22.555 % throttle [m/s] (report 27).
    step_steer_g, step_steer_radius, step_steer_speed : float
        Steady state of the 0.01 rad step steer from 27 m/s with the throttle held (report ≈ 0.2 g, R ≈ 310 m).
    turn_radius, turn_g, turn_throttle : float
        The 0.005 rad turn at 24.87 m/s (report R = 638.73 m, ≈ 0.1 g) and the throttle it takes [deg].

    References
    ----------
    Douglas et al. 1996, §2.2, §8.3.1–8.3.2.

    Examples
    --------
    >>> fig = calibration_figures()  # doctest: +SKIP
    >>> round(fig.speed, 3), round(fig.turn_radius, 1)  # doctest: +SKIP
    (27.0, 638.7)
    """

    speed: float
    step_steer_g: float
    step_steer_radius: float
    step_steer_speed: float
    turn_radius: float
    turn_g: float
    turn_throttle: float


def calibration_figures(car=None) -> CalibrationFigures:
    """Measure the report's steady-state figures on ``car`` (by trim).

    Parameters
    ----------
    car : Sedan, optional
        Default ``Sedan()`` (the calibrated mid-size sedan).

    Returns
    -------
    CalibrationFigures

    Raises
    ------
    DesignError
        When a steady state cannot be found.

    References
    ----------
    Douglas et al. 1996, §2.2, §8.3.1–8.3.2.

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> fig = calibration_figures(Sedan())
    >>> round(fig.speed, 2), round(fig.turn_radius), round(fig.step_steer_g, 2)
    (27.0, 639, 0.21)
    """
    from fdikit.vehicle.sedan import Sedan

    car = Sedan() if car is None else car
    straight = car.operating_point(throttle=THROTTLE_27)
    step = car.operating_point(throttle=THROTTLE_27, steering=0.01)
    turn = car.operating_point(speed=24.87, steering=0.005)
    return CalibrationFigures(speed=straight.speed, step_steer_g=step.lateral_acceleration_g,
                              step_steer_radius=step.radius, step_steer_speed=step.speed, turn_radius=turn.radius,
                              turn_g=turn.lateral_acceleration_g, turn_throttle=float(turn.u[0]))


def calibrate(params=None, *, speed: float = 27.0, radius: float = 638.73, rounds: int = 3, xtol: float = 1e-9):
    """Solve ``throttle_max_flow`` (27 m/s at 22.555 %) and ``cg_to_front_axle`` (R at 0.005 rad, 24.87 m/s).

    Parameters
    ----------
    params : SedanParameters, optional
        Starting parameters (default ``MID_SIZE_SEDAN``); every other number is kept.
    speed : float, default 27.0
        Target speed at 22.555 % throttle [m/s].
    radius : float, default 638.73
        Target radius of the 0.005 rad turn at 24.87 m/s [m].
    rounds : int, default 3
        Alternations of the two 1-D solves.
    xtol : float, default 1e-9
        Brent tolerance on the relative parameter change.

    Returns
    -------
    SedanParameters
        The calibrated parameters.

    Raises
    ------
    DesignError
        When a target cannot be bracketed (MAX in 0.1–1 kg/s, the CM in 20–80 % of the wheelbase).

    References
    ----------
    Douglas et al. 1996, §2.2, §8.3.1.

    Examples
    --------
    >>> from fdikit.vehicle.parameters import MID_SIZE_SEDAN
    >>> p = calibrate(MID_SIZE_SEDAN, rounds=1)  # doctest: +SKIP
    >>> abs(p.throttle_max_flow / MID_SIZE_SEDAN.throttle_max_flow - 1) < 1e-4  # doctest: +SKIP
    True
    """
    from scipy.optimize import brentq

    from fdikit import validate
    from fdikit.errors import DesignError
    from fdikit.vehicle.parameters import MID_SIZE_SEDAN
    from fdikit.vehicle.sedan import Sedan

    p = MID_SIZE_SEDAN if params is None else params
    speed, radius = validate.positive("speed", speed), validate.positive("radius", radius)
    rounds = validate.integer("rounds", rounds, minimum=1)

    def speed_error(flow, q):
        return Sedan(q.with_(throttle_max_flow=flow)).operating_point(throttle=THROTTLE_27).speed - speed

    def radius_error(a, q):
        return Sedan(q.with_(cg_to_front_axle=a)).operating_point(speed=24.87, steering=0.005).radius - radius

    L = p.wheelbase
    for _ in range(rounds):
        for name, fn, lo, hi in (("throttle_max_flow", speed_error, 0.1, 1.0),
                                 ("cg_to_front_axle", radius_error, 0.35 * L, 0.65 * L)):
            try:
                value = brentq(fn, lo, hi, args=(p,), xtol=xtol * hi)
            except (ValueError, DesignError) as exc:
                raise DesignError(f"calibrate: {name} cannot meet its target in [{lo:g}, {hi:g}]: {exc}") from exc
            p = p.with_(**{name: value})
    return p
