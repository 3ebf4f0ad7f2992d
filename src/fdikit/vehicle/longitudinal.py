"""The 3-DOF longitudinal car of Ch. 8 §8.1 (x, z, pitch) on the same parts as the 6-DOF car.

Douglas et al. 1996, Ch. 8 §8.1: longitudinal and vertical translation and pitch, one front and one rear
axle, with the suspension, wheel, brake and engine dynamics.  The 14 :data:`LONGITUDINAL_STATES` are
``x_position, height, pitch, v_x, v_z, pitch_rate, wheel_speed_front, wheel_speed_rear, suspension_front,
suspension_rear, air_mass, engine_speed, throttle, brake``; ``x_position`` never feeds back (the road is
sampled by it), so the other 13 are the design block (exact truncation, as for the 6-DOF car).  The parts
are those of :mod:`fdikit.vehicle.dynamics` with the same :class:`~fdikit.vehicle.parameters.SedanParameters`;
an axle is two corners side by side (spring, damper, preload, tire stiffness, wheel inertia 2 × the corner's,
the tire force 2 × the Magic Formula at half the axle load, slip angle 0; half-wheelbases ``l_1 = a > 0``,
``l_2 = −b < 0`` of (8.16)).  The road angle ``c`` is zero and the grade γ rotates gravity,
``g = g(−sin γ, −cos γ)`` in the road frame, as in the 6-DOF car:

* kinematics (8.5), (8.11), (8.12): ``θ̇ = ω_y``, ``ẋ = v_x cos θ + v_z sin θ``,
  ``ż = −v_x sin θ + v_z cos θ``; translation (8.14), (8.15), rotation (8.7);
* wheel radius (8.17): ``r_w = z − l sin θ − h cos θ − ξ``; normal force ``N = K_w max(r_w0 − r_w, 0)``
  (8.26), (8.29); suspension (8.19): ``N cos θ = f_K(h) + f_C(ḣ)`` with ``f_K = F_0 − K(h − h_s) − K'(h − h_s)^5``
  (8.25) and the piecewise-linear damper (8.27), solved for ``ḣ``;
* forces (8.22)–(8.24), (8.28), (8.30): tire force ``F r_x + N r_z`` in body axes
  ``(F cos θ − N sin θ, F sin θ + N cos θ)``, drag ``½ρA C_D |v_a| v_a``, lift ``½ρA C_L v_a²``;
* moments **from the cross product** ``(l c_x − h c_z) × F = (−h F_x − l F_z) c_y`` — the printed (8.31) has
  ``+l`` and so turns a front upward force into a nose-down moment; here it pitches the nose up (θ decreases,
  θ > 0 is nose-down) — plus the aerodynamic moment (8.32) and the reaction ``−(T_d − T_b)`` of the wheel
  torques on the body (body-mounted brakes and drive line, as in :mod:`fdikit.vehicle.dynamics`);
* wheel-centre velocity (8.39), forward speed (8.40), slip ratio (8.41) regularised
  (:func:`fdikit.vehicle.tire.slip_kernel`); wheels (8.36) ``I_w ω̇ = T_d − T_b − r_w F − f_r r_w N``;
  brake split (8.35) and lag (8.34) (fading below ``brake_smoothing``), front drive (8.37) with ``k_d = 1``;
* engine :mod:`fdikit.vehicle.engine` (the Berkeley engine in place of (8.46)) through the slipping clutch
  ``J_e ω̇_e = T_e − c(ω_e − ζ ω_front)``, throttle lag (8.49).

Road irregularity ξ per axle from a :class:`~fdikit.vehicle.road.RoadProfile` (its left track), the front
axle at ``s = x_position``, the rear at ``s − L`` (§8.3.1: the rear sees the front's road ``L/V`` later).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.vehicle.dynamics import damper_rate
from fdikit.vehicle.engine import engine_kernel
from fdikit.vehicle.integrate import road_height
from fdikit.vehicle.parameters import INDEX, MID_SIZE_SEDAN, SedanParameters
from fdikit.vehicle.tire import combined_forces, slip_kernel

__all__ = ["LongitudinalCar", "LongitudinalPoint", "LONGITUDINAL_STATES", "LONGITUDINAL_CONTROLS",
           "LONGITUDINAL_SENSORS", "LONGITUDINAL_AUXILIARY"]

#: State names (14); the last 13 are the design block.
LONGITUDINAL_STATES = ("x_position", "height", "pitch", "v_x", "v_z", "pitch_rate", "wheel_speed_front",
                       "wheel_speed_rear", "suspension_front", "suspension_rear", "air_mass", "engine_speed",
                       "throttle", "brake")
#: Commands: throttle angle [deg], total brake torque [N m].
LONGITUDINAL_CONTROLS = ("throttle", "brake")
#: Sensors: the longitudinal subset of the PATH sensors (per axle).
LONGITUDINAL_SENSORS = ("air_mass", "engine_speed", "accel_x", "accel_z", "pitch_rate", "wheel_speed_front",
                        "wheel_speed_rear")
#: Auxiliary signals (axle totals for the forces).
LONGITUDINAL_AUXILIARY = ("specific_force_x", "specific_force_z", "normal_force_front", "normal_force_rear",
                          "tire_force_front", "tire_force_rear", "slip_ratio_front", "slip_ratio_rear",
                          "ground_speed", "engine_torque", "manifold_pressure", "clutch_torque")
_SIGNALS = LONGITUDINAL_SENSORS + LONGITUDINAL_AUXILIARY
_N, _NA, _NY = len(LONGITUDINAL_STATES), len(LONGITUDINAL_AUXILIARY), len(LONGITUDINAL_SENSORS)
_SHIFT_UP, _SHIFT_DOWN = 4500 * math.pi / 30, 1500 * math.pi / 30
_GEARBOX = ("held", "automatic")

(_M, _IY, _G, _KF, _KR, _KC, _CF, _CR, _KNEE, _BLOW, _KW, _RW0, _IWF, _IWR, _FRR, _AREA, _CD, _CL, _CMY, _RHO, _L,
 _ZETA, _ETA, _CCL, _JE, _TA, _TB, _KB, _WB, _HSF, _HSR, _F0F, _F0R, _PXF, _TIRE, _ENG) = (INDEX[n] for n in (
    "mass", "pitch_inertia", "gravity", "spring_front", "spring_rear", "spring_cubic", "damper_front", "damper_rear",
    "damper_knee", "damper_blowoff", "tire_stiffness", "tire_radius", "wheel_inertia_front", "wheel_inertia_rear",
    "rolling_resistance", "drag_area", "drag_coefficient", "lift_coefficient", "pitch_moment_coefficient",
    "air_density", "wheelbase", "gear_ratio", "driveline_efficiency", "clutch_slip_damping", "engine_inertia",
    "throttle_lag", "brake_lag", "brake_front_share", "brake_smoothing", "static_length_fl", "static_length_rl",
    "preload_fl", "preload_rl", "corner_x", "tire", "engine"))
_PXR = _PXF + 2  # corner_x of rl
_V_MIN = 0.5  # m/s: speed floor of the slip definition, as the 6-DOF car


@njit(cache=True)
def _rhs(x, u, env, p, dx, aux):  # pragma: no cover - compiled
    """Fill ``dx`` (14) and ``aux``; ``env`` = (road front, road rear, wind_x, grade)."""
    z, th, vx, vz, wy = x[1], x[2], x[3], x[4], x[5]
    m_a, w_e, alpha_t, tau_b = x[10], x[11], x[12], x[13]
    cth, sth, m, g = math.cos(th), math.sin(th), p[_M], p[_G]
    ga, gc = -g * math.sin(env[3]), -g * math.cos(env[3])  # gravity in the road frame (grade env[3])
    gbx = cth * ga - sth * gc
    gbz = sth * ga + cth * gc
    vax, q = env[2] - vx, 0.5 * p[_RHO] * p[_AREA]
    fx = q * p[_CD] * abs(vax) * vax
    fz = q * p[_CL] * vax * vax
    my = q * p[_L] * p[_CMY] * vax * vax
    dm_a, t_e, p_m = engine_kernel(p[_ENG:_ENG + 9], m_a, w_e, alpha_t)
    zeta = p[_ZETA]
    t_clutch = p[_CCL] * (w_e - zeta * x[6])
    for i in range(2):
        front = i == 0
        li = p[_PXF] if front else p[_PXR]
        hi = x[8 + i]
        rw = z - li * sth - hi * cth - env[i]
        n = max(2.0 * p[_KW] * (p[_RW0] - rw), 0.0)
        k, c = 2.0 * (p[_KF] if front else p[_KR]), 2.0 * (p[_CF] if front else p[_CR])
        dh = hi - (p[_HSF] if front else p[_HSR])
        f_k = 2.0 * (p[_F0F] if front else p[_F0R]) - k * dh - 2.0 * p[_KC] * dh ** 5
        hdot = damper_rate(f_k - n * cth, c, p[_KNEE], p[_BLOW])
        dx[8 + i] = hdot
        # wheel-centre velocity (8.39) along r_x = (cos θ, sin θ) in body axes (8.40)
        v_f = (vx - hi * wy) * cth + (vz - li * wy - hdot) * sth
        lam = slip_kernel(rw * x[6 + i], v_f, _V_MIN)
        f_corner, _ = combined_forces(p[_TIRE:_TIRE + 19], 0.5 * n, lam, 0.0)
        f_long = 2.0 * f_corner
        fxi = f_long * cth - n * sth
        fzi = f_long * sth + n * cth
        fx, fz = fx + fxi, fz + fzi
        share = p[_KB] if front else 1.0 - p[_KB]
        t_brake = share * tau_b * math.tanh(x[6 + i] / p[_WB])
        t_d = p[_ETA] * zeta * t_clutch if front else 0.0
        iw = 2.0 * (p[_IWF] if front else p[_IWR])
        dx[6 + i] = (t_d - t_brake - rw * f_long - p[_FRR] * rw * n) / iw
        my += -hi * fxi - li * fzi - (t_d - t_brake)
        aux[2 + i], aux[4 + i], aux[6 + i] = n, f_long, lam
    a1 = cth * vx + sth * vz
    dx[0], dx[1], dx[2] = a1, -sth * vx + cth * vz, wy  # (8.11), (8.12), (8.5)
    dx[3], dx[4], dx[5] = -wy * vz + fx / m + gbx, wy * vx + fz / m + gbz, my / p[_IY]  # (8.14), (8.15), (8.7)
    dx[10] = dm_a
    dx[11] = (t_e - t_clutch) / p[_JE]
    dx[12] = (u[0] - alpha_t) / p[_TA]
    dx[13] = (u[1] - tau_b) / p[_TB]
    aux[0], aux[1], aux[8], aux[9], aux[10], aux[11] = fx / m, fz / m, a1, t_e, p_m, t_clutch


@njit(cache=True)
def _sensors(x, aux, y):  # pragma: no cover - compiled
    y[0], y[1], y[2], y[3], y[4], y[5], y[6] = x[10], x[11], aux[0], aux[1], x[5], x[6], x[7]


@njit(cache=True)
def _stage(x, u, env, p, road, spacing, dx, aux):  # pragma: no cover - compiled
    env[0] = road_height(road, spacing, x[0])
    env[1] = road_height(road, spacing, x[0] - p[_L])
    _rhs(x, u, env, p, dx, aux)


@njit(cache=True)
def _run(x0, commands, grade, p, road, spacing, h, every, ratios, final_drive, gear0,
         automatic):  # pragma: no cover - compiled
    """Classical RK4 over ``commands.shape[0]`` steps of ``h``; record every ``every`` steps and the start."""
    n_steps = commands.shape[0]
    n_rec = n_steps // every + 1  # the start and every ``every``-th step
    xs, ys, auxs = np.empty((n_rec, _N)), np.empty((n_rec, _NY)), np.zeros((n_rec, _NA))
    gears = np.empty(n_rec, dtype=np.int64)
    x, env = x0.copy(), np.array([0.0, 0.0, 0.0, grade])
    k1, k2, k3, k4, xt = np.empty(_N), np.empty(_N), np.empty(_N), np.empty(_N), np.empty(_N)
    aux, y = np.zeros(_NA), np.empty(_NY)
    gear, q, r = gear0, p.copy(), 0
    q[_ZETA] = ratios[gear - 1] * final_drive
    for k in range(n_steps + 1):
        uk = commands[min(k, n_steps - 1)]
        if k % every == 0:
            _stage(x, uk, env, q, road, spacing, k1, aux)
            _sensors(x, aux, y)
            xs[r], ys[r], auxs[r], gears[r] = x, y, aux, gear
            if not np.all(np.isfinite(x)):
                return xs, ys, auxs, gears, r
            r += 1
        if k == n_steps:
            break
        if automatic:
            if x[11] > _SHIFT_UP and gear < ratios.size:
                gear += 1
            elif x[11] < _SHIFT_DOWN and gear > 1:
                gear -= 1
            q[_ZETA] = ratios[gear - 1] * final_drive
        _stage(x, uk, env, q, road, spacing, k1, aux)
        xt[:] = x + 0.5 * h * k1
        _stage(xt, uk, env, q, road, spacing, k2, aux)
        xt[:] = x + 0.5 * h * k2
        _stage(xt, uk, env, q, road, spacing, k3, aux)
        xt[:] = x + h * k3
        _stage(xt, uk, env, q, road, spacing, k4, aux)
        x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return xs, ys, auxs, gears, r


@dataclass(frozen=True)
class LongitudinalPoint:
    """A steady run of the longitudinal car (the 13 design-state derivatives zero).

    Attributes
    ----------
    x : (14,) ndarray
        State (``x_position`` zero).
    u : (2,) ndarray
        Commands: throttle [deg], brake [N m].
    y : (7,) ndarray
        Sensor outputs (:data:`LONGITUDINAL_SENSORS`).
    signals : dict of str to float
        The auxiliary signals (:data:`LONGITUDINAL_AUXILIARY`).
    grade : float
        Road grade [rad] (uphill positive).
    gear : int
        The gear (1-based) the point is in.

    Examples
    --------
    >>> op = LongitudinalCar().operating_point(throttle=20.3)
    >>> round(op.speed, 1), op.gear
    (27.0, 4)
    """

    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    signals: dict = field(repr=False)
    grade: float = 0.0
    gear: int = 4

    @property
    def speed(self) -> float:
        """Speed over the road [m/s]."""
        return float(self.signals["ground_speed"])


class LongitudinalCar:
    """The 3-DOF longitudinal car of Douglas et al. 1996, §8.1, with the parameters of the 6-DOF sedan.

    Parameters
    ----------
    params : SedanParameters, default MID_SIZE_SEDAN
        Every number of the car (per corner; the axles take twice the corner values).

    Attributes
    ----------
    states, controls, sensors : tuple of str
        :data:`LONGITUDINAL_STATES` (14), ``("throttle", "brake")``, :data:`LONGITUDINAL_SENSORS` (7).

    Raises
    ------
    ParameterError
        When ``params`` is not a :class:`SedanParameters`.

    References
    ----------
    Douglas et al. 1996, §8.1 (8.1)–(8.49), §8.3.1.

    Examples
    --------
    >>> car = LongitudinalCar()
    >>> len(car.states), car.controls
    (14, ('throttle', 'brake'))
    """

    states = LONGITUDINAL_STATES
    controls = LONGITUDINAL_CONTROLS
    sensors = LONGITUDINAL_SENSORS

    def __init__(self, params: SedanParameters = MID_SIZE_SEDAN) -> None:
        self.params = validate.instance("params", params, SedanParameters)

    def __repr__(self) -> str:
        return f"LongitudinalCar(mass={self.params.mass:g} kg, gear={self.params.gear})"

    def derivatives(self, x, u, *, road=(0.0, 0.0), wind: float = 0.0, grade: float = 0.0,
                    gear: int | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
        """``(ẋ, y, signals)`` at one state and command.

        Parameters
        ----------
        x : array_like, shape (14,)
            State.
        u : array_like, shape (2,)
            Commands: throttle [deg], brake [N m].
        road : sequence of 2 float, default zeros
            Road irregularity ξ under the front and rear axle [m].
        wind : float, default 0.0
            Wind along the road [m/s] (a headwind is negative).
        grade : float, default 0.0
            Road grade [rad] (uphill positive).
        gear : int, optional
            Gear (default the parameters' gear).

        Returns
        -------
        dx : (14,) ndarray
        y : (7,) ndarray
        signals : dict of str to float

        Raises
        ------
        ParameterError
            For arrays of the wrong length or not finite, a gear out of range.

        References
        ----------
        Douglas et al. 1996, §8.1 (8.5)–(8.49).

        Examples
        --------
        >>> car = LongitudinalCar()
        >>> op = car.operating_point(throttle=20.3)
        >>> dx, y, sig = car.derivatives(op.x, op.u)
        >>> float(np.abs(dx[1:]).max()) < 1e-7, round(float(dx[0]), 1)
        (True, 27.0)
        """
        x = validate.as_vector("x", x, _N)
        u = validate.as_vector("u", u, 2)
        env = np.r_[validate.as_vector("road", road, 2), validate.number("wind", wind),
                    validate.number("grade", grade)]
        dx, y, aux = np.empty(_N), np.empty(_NY), np.zeros(_NA)
        _rhs(x, u, env, self.params.as_array(gear), dx, aux)
        _sensors(x, aux, y)
        return dx, y, dict(zip(LONGITUDINAL_AUXILIARY, aux.tolist()))

    def design_plant(self, outputs=LONGITUDINAL_SENSORS, *, grade: float = 0.0, gear: int | None = None):
        """The 13 design states (all but ``x_position``) as a :class:`~fdikit.simulate.NonlinearPlant`.

        Parameters
        ----------
        outputs : sequence of str, default LONGITUDINAL_SENSORS
            Names from the sensors and :data:`LONGITUDINAL_AUXILIARY`.
        grade : float, default 0.0
            Road grade [rad].
        gear : int, optional
            Gear (default the parameters' gear).

        Returns
        -------
        NonlinearPlant
            States ``LONGITUDINAL_STATES[1:]``, controls ``("throttle", "brake")``; smooth road, no wind.

        Raises
        ------
        ParameterError
            For an unknown output name or a gear out of range.

        References
        ----------
        Douglas et al. 1996, §8.1, §8.3.1 (the nonlinear system ``ẋ = f(x, u)`` linearised there).

        Examples
        --------
        >>> plant = LongitudinalCar().design_plant(["pitch_rate"])
        >>> len(plant.states), plant.outputs
        (13, ('pitch_rate',))
        """
        from fdikit.simulate import NonlinearPlant

        names = tuple(outputs)
        for n in names:
            validate.choice("outputs", n, _SIGNALS)
        pick = np.array([_SIGNALS.index(n) for n in names], dtype=int)
        env = np.array([0.0, 0.0, 0.0, validate.number("grade", grade)])
        p, full = self.params.as_array(gear), np.zeros(_N)
        dx, y, aux = np.empty(_N), np.empty(_NY), np.zeros(_NA)

        def _eval(x, u):
            full[1:] = x
            _rhs(full, np.asarray(u, dtype=float), env, p, dx, aux)
            _sensors(full, aux, y)
            return dx[1:].copy(), np.r_[y, aux][pick]

        x0 = self._guess(27.0, 20.3, gear)[1:]
        return NonlinearPlant(f=lambda t, x, u: _eval(x, u)[0], h=lambda t, x, u: _eval(x, u)[1],
                              states=LONGITUDINAL_STATES[1:], outputs=names, controls=LONGITUDINAL_CONTROLS, x0=x0)

    def _guess(self, speed: float, throttle: float, gear: int | None) -> np.ndarray:
        P = self.params
        r = P.tire_radius - P.corner_loads() / P.tire_stiffness
        h_s = P.static_lengths()
        x = np.zeros(_N)
        x[1], x[3] = P.cg_height, speed
        x[6], x[7] = speed / r[0], speed / r[2]
        x[8], x[9] = h_s[0], h_s[2]
        x[10], x[11], x[12] = 2.0e-3, P.gear_ratio(gear) * speed / r[0], throttle
        return x

    def operating_point(self, *, throttle: float | None = None, speed: float | None = None, brake: float = 0.0,
                        grade: float = 0.0, gear: int | None = None, tol: float = 1e-9) -> LongitudinalPoint:
        """The steady run at a held ``throttle`` [deg], or at a ``speed`` [m/s] with the throttle solved for.

        Parameters
        ----------
        throttle : float, optional
            Throttle angle [deg] (give exactly one of ``throttle`` and ``speed``).
        speed : float, optional
            Speed over the road [m/s].
        brake : float, default 0.0
            Brake torque [N m].
        grade : float, default 0.0
            Road grade [rad] (uphill positive).
        gear : int, optional
            Gear (default the parameters' gear).
        tol : float, default 1e-9
            Trim tolerance (:func:`fdikit.nonlinear.trim`).

        Returns
        -------
        LongitudinalPoint

        Raises
        ------
        ParameterError
            Unless exactly one of ``throttle`` and ``speed`` is given, or for values out of range.
        DesignError
            When no steady state is found.

        References
        ----------
        Douglas et al. 1996, §8.3.1 (22.555 % throttle at 27 m/s; operating point ``f(x_0, u_0) = 0``).

        Examples
        --------
        >>> op = LongitudinalCar().operating_point(speed=27.0)
        >>> round(float(op.u[0]) / 90 * 100, 2)  # percent of the 90-degree butterfly
        22.55
        """
        from fdikit.nonlinear import trim

        if (throttle is None) == (speed is None):
            raise ParameterError("operating_point: give exactly one of throttle= [deg] and speed= [m/s]")
        brake = validate.non_negative("brake", brake)
        grade = validate.number("grade", grade)
        gear = self.params.gear if gear is None else validate.integer("gear", gear, minimum=1)
        self.params.gear_ratio(gear)  # checks the range
        plant = self.design_plant(("ground_speed",), grade=grade, gear=gear)
        if throttle is not None:
            throttle = validate.positive("throttle", throttle)
            x0 = self._guess(27.0 * throttle / 20.3, throttle, gear)
            x0[13] = brake
            op = trim(plant, x0[1:], [throttle, brake], tol=tol)
        else:
            from fdikit.vehicle.sedan import throttle_for_speed

            speed = validate.positive("speed", speed)
            return throttle_for_speed(lambda th: self.operating_point(throttle=th, brake=brake, grade=grade, gear=gear,
                                                                      tol=tol), speed, 20.3 * (speed / 27.0) ** 2)
        x = np.zeros(_N)
        x[1:] = op.x
        _, y, sig = self.derivatives(x, op.u, grade=grade, gear=gear)
        return LongitudinalPoint(x=x, u=np.asarray(op.u, dtype=float), y=y, signals=sig, grade=grade, gear=gear)

    def linearize(self, op: LongitudinalPoint, outputs=LONGITUDINAL_SENSORS):
        """The 13-state linear model at ``op`` (deviations; ``x_position`` truncated exactly).

        Parameters
        ----------
        op : LongitudinalPoint
            The point (its grade and gear are used).
        outputs : sequence of str, default LONGITUDINAL_SENSORS
            Output names.

        Returns
        -------
        FaultModel
            Continuous, states ``LONGITUDINAL_STATES[1:]``, controls ``("throttle", "brake")``.

        Raises
        ------
        ParameterError
            When ``op`` is not a :class:`LongitudinalPoint`.

        References
        ----------
        Douglas et al. 1996, §8.3.1 (linearisation at a nominal operating point, central differences).

        Examples
        --------
        >>> car = LongitudinalCar()
        >>> lin = car.linearize(car.operating_point(throttle=20.3))
        >>> lin.A.shape, bool(np.linalg.eigvals(lin.A).real.max() < 0)
        ((13, 13), True)
        """
        from fdikit.nonlinear import linearize

        validate.instance("op", op, LongitudinalPoint)
        plant = self.design_plant(outputs, grade=op.grade, gear=op.gear)
        return linearize(plant, op.x[1:], op.u)

    def simulate(self, duration: float, *, start: LongitudinalPoint | None = None, commands=None, road=None,
                 grade: float | None = None, gearbox: str = "held", dt: float = 0.01, step: float = 0.001):
        """Integrate the car (compiled RK4 at ``step``, sampled at ``dt``) from ``start`` under ``commands``.

        Parameters
        ----------
        duration : float
            Run length [s].
        start : LongitudinalPoint, optional
            Initial state and gear (default the straight run at 20.3° throttle); its commands are held unless
            ``commands`` is given.  A run may start from the last state of another: build the point from it.
        commands : callable or array_like, optional
            ``commands(t) -> (2,)`` (throttle [deg], brake torque [N m]) at every integration step, or a constant.
        road : RoadProfile, optional
            Spatial road (its left track is used; default smooth), covering the distance travelled.
        grade : float, optional
            Road grade [rad] (default the start point's).
        gearbox : {"held", "automatic"}, default "held"
            Gear held, or shifted up above 4500 rpm and down below 1500 rpm.
        dt : float, default 0.01
            Output sample time [s], a whole multiple of ``step``.
        step : float, default 0.001
            Integration step [s].

        Returns
        -------
        Trace
            ``u`` the commands, ``y`` the 7 sensors, ``x`` the 14 states; ``meta["signals"]`` the auxiliary
            signals per sample, ``meta["gear"]`` the gear per sample.

        Raises
        ------
        ParameterError
            For a bad duration, ``dt`` not a multiple of ``step``, commands of the wrong shape, an unknown gearbox,
            a road that is not a RoadProfile or shorter than the distance travelled.
        DataError
            When the run diverges.

        References
        ----------
        Douglas et al. 1996, §8.3.1 (step throttle, brake, 5 % grade and bump runs; rear road delayed ``L/V``).

        Examples
        --------
        >>> car = LongitudinalCar()
        >>> tr = car.simulate(1.0, start=car.operating_point(throttle=20.3))
        >>> tr.x.shape, round(float(tr.x[-1, 0]), 1)
        ((101, 14), 27.0)
        """
        from fdikit.trace import Trace
        from fdikit.vehicle.road import RoadProfile

        duration = validate.positive("duration", duration)
        dt, step = validate.positive("dt", dt), validate.positive("step", step)
        every = int(round(dt / step))
        if every < 1 or abs(every * step - dt) > 1e-9 * dt:
            raise ParameterError(f"simulate: dt={dt:g} s must be a whole multiple of step={step:g} s")
        validate.choice("gearbox", gearbox, _GEARBOX)
        if start is None:
            start = self.operating_point(throttle=20.3)
        validate.instance("start", start, LongitudinalPoint)
        grade = start.grade if grade is None else validate.number("grade", grade)
        if road is None:
            xi, spacing, length, label = np.zeros(2), 1.0, math.inf, "flat"
        else:
            validate.instance("road", road, RoadProfile)
            xi, spacing, length, label = np.ascontiguousarray(road.left), road.spacing, road.length, road.label
        n_out = int(round(duration / dt))
        n_steps, t = n_out * every, np.arange(n_out + 1) * dt
        u = _commands(commands, start.u, np.arange(n_steps) * step)
        P = self.params
        x, y, aux, gear, ok = _run(start.x.astype(float), u, grade, P.as_array(start.gear), xi, float(spacing), step,
                                   every, np.array(P.gear_ratios), P.final_drive, start.gear, gearbox == "automatic")
        if ok < t.size:
            raise DataError(f"simulate: the run diverged at t={t[ok]:g} s (a state became non-finite); check the "
                            "commands and the road, or use a smaller step")
        if x[-1, 0] > length:
            raise ParameterError(f"simulate: the car travelled {x[-1, 0]:g} m, the road is {length:g} m long; "
                                 "generate a longer road")
        meta = {"plant": repr(self), "signals": dict(zip(LONGITUDINAL_AUXILIARY, aux.T)), "gear": gear,
                "road": label, "step": step, "grade": grade}
        return Trace(t=t, u=u[np.minimum(np.arange(t.size) * every, n_steps - 1)], y=y, x=x, meta=meta,
                     controls=LONGITUDINAL_CONTROLS, outputs=LONGITUDINAL_SENSORS, states=LONGITUDINAL_STATES)


def _commands(commands: Callable | None, held: np.ndarray, t: np.ndarray) -> np.ndarray:
    if commands is None:
        out = np.tile(held, (t.size, 1))
    elif callable(commands):
        out = np.array([np.asarray(commands(tk), dtype=float) for tk in t])
    else:
        out = np.tile(validate.as_array("commands", commands), (t.size, 1))
    if out.shape != (t.size, 2) or not np.all(np.isfinite(out)):
        raise ParameterError("simulate: commands must give 2 finite numbers (throttle [deg], brake torque [N m]) "
                             f"at every step, got shape {out.shape[1:]}")
    return np.ascontiguousarray(out)
