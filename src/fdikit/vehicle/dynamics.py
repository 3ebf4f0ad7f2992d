"""Equations of motion of the nonlinear car: the 6-DOF body of Ch. 8 on the Ch. 2 suspension.

Douglas et al. 1996, Ch. 8 §8.2 (Nguyen's 6-DOF model) with the Ch. 2 §2.1.1 suspension (a
massless linear tire in series with the spring and damper, one state per corner), the Berkeley
state set of §2.2 and the actuators of §2.3.  The 26 states, in :data:`STATES` order::

    air_mass, engine_speed, v_x, v_y, v_z, height, roll, roll_rate, pitch, pitch_rate, yaw_rate,
    wheel_speed_fl … _rr, throttle, brake, steering, suspension_fl … _rr,        (the 22 of §2.2)
    x_position, y_position, yaw, distance                                          (the 4 truncated)

The first 22 are the report's ``x_1`` (§2.2, with body rates for the Euler-angle rates and the
suspension length ``h_i`` of Ch. 8 for the force ``F_i`` of Ch. 2 — the same dynamics in other
coordinates); the last four never feed back (the road is sampled by ``distance``, gravity and
slope act in the heading frame), so the 22-state block is exact truncation (§2.2).

Equations (with the corrections the report's own checks call for):

* frames (8.50)–(8.53): ``c = R_θ R_φ R_ε e``; road normal on the plane road, ``r_z`` =
  ``(−sθ cφ, sφ, cθ cφ)`` in body axes (8.55)–(8.57) with ``n = e_z``; slope by rotating gravity
  (§2.1.3): grade γ and bank κ give ``g = g(−sin γ, cos γ sin κ, −cos γ cos κ)`` in the heading frame;
* tire heading (8.58)–(8.63), **with the minus sign of (8.60)** in ``r_xz`` (dropped in (8.63));
* wheel radius (8.76)/(8.81) on the plane road: ``r_w = z + l r_zx + y r_zy − h r_zz − ξ``
  (``y`` the signed lateral position, ``y = −s`` of the report); normal force
  ``N = K_w max(r_w0 − r_w, 0)`` (8.29);
* suspension (8.77) **with ``r_zz`` for the printed cos(θ − γ)**: ``N r_zz = f_K(h) + f_C(ḣ)``,
  ``f_K = F_0 − K(h − h_s) − K'(h − h_s)^5`` (8.25) about the static length, ``f_C = −F_d(ḣ)``
  the piecewise-linear damper (8.27, on ``ḣ``), solved for ``ḣ``;
* wheel-centre velocity (8.93), slip angle (8.95) ``α = −atan(v·r_y / v·r_x)``, slip ratio (8.92)
  regularised (:mod:`fdikit.vehicle.tire`), combined-slip Magic Formula;
* forces (8.82)–(8.87); moments **from the cross product** ``(l, y, −h) × F`` (the printed
  ``M_y`` has inconsistent signs, §8.2), plus the reaction ``−(T_d − T_b)`` of the drive and
  brake torques on the body about each axle (body-mounted brakes and drive line: the force at
  the contact patch then acts with its full lever arm, which (8.88)–(8.90) omit);
* Euler equations (8.68), translation (8.74), kinematics (8.67), (8.72);
* wheels (8.36) ``I_w ω̇ = T_d − T_b − r_w F_x − d N``, brake split (8.91), drive split (8.104)
  (front drive, open differential), engine (:mod:`fdikit.vehicle.engine`) coupled by a slipping
  clutch ``J_e ω̇_e = T_e − c(ω_e − ζ ω_axle)``;
* actuators (§2.3): ``α̇ = (α_c − α)/τ_α``, ``τ̇_b = (τ_c − τ_b)/τ_b``, ``δ̇ = (δ_c − δ)/τ_δ``.

Aerodynamics (8.23), (8.24), (8.32), (8.82)–(8.84), (8.88) with the air velocity relative to the
car in the heading frame: drag ``½ρA C_D V_a v_ax``, side force ``½ρA C_S V_a v_ay``, lift
``½ρA C_L V_a²`` (up), pitch moment ``½ρA L C_M V_a²`` (nose-down positive), yaw moment
``½ρA L C_N V_a v_ay``.

Outputs: the 12 PATH sensors (App. D order) — the accelerometers measure specific force
``(F − F_gravity)/m`` at the CM in body axes (so pitch and roll show on them as on real sensors).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from fdikit.vehicle.engine import engine_kernel
from fdikit.vehicle.parameters import INDEX
from fdikit.vehicle.tire import combined_forces, slip_kernel

__all__ = ["STATES", "CONTROLS", "SENSORS", "ENVIRONMENT", "AUXILIARY", "N_DESIGN_STATES"]

_CORNERS = ("fl", "fr", "rl", "rr")
#: State names (26).
STATES = (("air_mass", "engine_speed", "v_x", "v_y", "v_z", "height", "roll", "roll_rate", "pitch", "pitch_rate",
           "yaw_rate") + tuple(f"wheel_speed_{c}" for c in _CORNERS) + ("throttle", "brake", "steering")
          + tuple(f"suspension_{c}" for c in _CORNERS) + ("x_position", "y_position", "yaw", "distance"))
#: The first 22 states are the §2.2 block that stays after exact truncation.
N_DESIGN_STATES = 22
#: Commands: throttle angle [deg], brake torque [N m] (total), road-wheel steer angle [rad].
CONTROLS = ("throttle", "brake", "steering")
#: The 12 PATH sensors in App. D order.
SENSORS = ("air_mass", "engine_speed", "accel_x", "accel_y", "accel_z", "roll_rate", "pitch_rate", "yaw_rate",
           "wheel_speed_fl", "wheel_speed_fr", "wheel_speed_rl", "wheel_speed_rr")
#: Environment inputs: road height under each wheel [m], earth-frame wind [m/s], grade and bank [rad].
ENVIRONMENT = ("road_fl", "road_fr", "road_rl", "road_rr", "wind_x", "wind_y", "grade", "bank")
#: Auxiliary signals the dynamics compute along the way.
AUXILIARY = (("specific_force_x", "specific_force_y", "specific_force_z")
             + tuple(f"normal_force_{c}" for c in _CORNERS) + tuple(f"tire_force_x_{c}" for c in _CORNERS)
             + tuple(f"tire_force_y_{c}" for c in _CORNERS) + tuple(f"slip_angle_{c}" for c in _CORNERS)
             + tuple(f"slip_ratio_{c}" for c in _CORNERS)
             + ("ground_speed", "lateral_acceleration", "curvature", "engine_torque", "manifold_pressure"))

_I = {n: INDEX[n] for n in INDEX}
_M, _IX, _IY, _IZ = _I["mass"], _I["roll_inertia"], _I["pitch_inertia"], _I["yaw_inertia"]
_KF, _KR, _KC = _I["spring_front"], _I["spring_rear"], _I["spring_cubic"]
_CF, _CR, _KNEE, _BLOW = _I["damper_front"], _I["damper_rear"], _I["damper_knee"], _I["damper_blowoff"]
_KW, _RW0 = _I["tire_stiffness"], _I["tire_radius"]
_IWF, _IWR, _FRR = _I["wheel_inertia_front"], _I["wheel_inertia_rear"], _I["rolling_resistance"]
_AREA, _CD, _CL, _CS = _I["drag_area"], _I["drag_coefficient"], _I["lift_coefficient"], _I["side_force_coefficient"]
_CMY, _CMZ, _RHO, _L = _I["pitch_moment_coefficient"], _I["yaw_moment_coefficient"], _I["air_density"], _I["wheelbase"]
_ZETA, _ETA, _CCL, _JE = _I["gear_ratio"], _I["driveline_efficiency"], _I["clutch_slip_damping"], _I["engine_inertia"]
_TA, _TB, _TD, _KB = _I["throttle_lag"], _I["brake_lag"], _I["steering_lag"], _I["brake_front_share"]
_WB, _G = _I["brake_smoothing"], _I["gravity"]
_HS, _F0, _PX, _PY = _I["static_length_fl"], _I["preload_fl"], _I["corner_x"], _I["corner_y"]
_TIRE, _ENG, _SMALL = _I["tire"], _I["engine"], _I["small_angle"]
_N_AUX = len(AUXILIARY)
_V_MIN = 0.5  # m/s: speed floor of the slip definitions


@njit(cache=True)
def damper_rate(force, c, knee, blowoff):  # pragma: no cover - compiled
    """``ḣ`` with ``F_d(ḣ) = force`` for the piecewise-linear damper (8.27) (slope c inside ±knee, blowoff·c beyond)."""
    f_knee = c * knee
    if force > f_knee:
        return knee + (force - f_knee) / (blowoff * c)
    if force < -f_knee:
        return -knee + (force + f_knee) / (blowoff * c)
    return force / c


@njit(cache=True)
def rhs(x, u, env, p, dx, aux):  # pragma: no cover - compiled
    """Fill ``dx`` (26) with ``f(x, u, env)`` and ``aux`` with the :data:`AUXILIARY` signals."""
    m_a, w_e, vx, vy, vz, z = x[0], x[1], x[2], x[3], x[4], x[5]
    phi, wx, th, wy, wz = x[6], x[7], x[8], x[9], x[10]
    alpha_t, tau_b, delta = x[15], x[16], x[17]
    eps = x[24]
    if p[_SMALL] > 0.0:  # §8.3: small relative roll and pitch (yaw exact)
        cphi, sphi, cth, sth, tphi = 1.0, phi, 1.0, th, phi
    else:
        cphi, sphi, cth, sth, tphi = math.cos(phi), math.sin(phi), math.cos(th), math.sin(th), math.tan(phi)
    ceps, seps = math.cos(eps), math.sin(eps)
    m, g = p[_M], p[_G]
    # road normal in body axes (n = e_z of the road plane)
    rzx, rzy, rzz = -sth * cphi, sphi, cth * cphi
    # gravity in the heading frame, then body axes c = R_θ R_φ (heading frame)
    grade, bank = env[6], env[7]
    ga = -g * math.sin(grade)
    gb = g * math.cos(grade) * math.sin(bank)
    gc = -g * math.cos(grade) * math.cos(bank)
    gy_ = cphi * gb + sphi * gc
    gz_ = -sphi * gb + cphi * gc
    gbx = cth * ga - sth * gz_
    gby = gy_
    gbz = sth * ga + cth * gz_
    # aerodynamics: air velocity relative to the car, heading frame ≈ body for the horizontal plane
    wxh = ceps * env[4] + seps * env[5]
    wyh = -seps * env[4] + ceps * env[5]
    vax, vay = wxh - vx, wyh - vy
    va = math.sqrt(vax * vax + vay * vay)
    q = 0.5 * p[_RHO] * p[_AREA]
    fx = q * p[_CD] * va * vax
    fy = q * p[_CS] * va * vay
    fz = q * p[_CL] * va * va
    mx = 0.0
    my = q * p[_L] * p[_CMY] * va * va
    mz = q * p[_L] * p[_CMZ] * va * vay
    # engine and drive line
    dm_a, t_e, p_m = engine_kernel(p[_ENG:_ENG + 9], m_a, w_e, alpha_t)
    zeta = p[_ZETA]
    w_axle = 0.5 * (x[11] + x[12])
    t_clutch = p[_CCL] * (w_e - zeta * w_axle)
    t_drive = 0.5 * p[_ETA] * zeta * t_clutch  # per front wheel
    sd, cd = math.sin(delta), math.cos(delta)
    for i in range(4):
        li, yi = p[_PX + i], p[_PY + i]
        hi = x[18 + i]
        front = i < 2
        xi = env[i]
        # wheel radius and normal force
        rw = z + li * rzx + yi * rzy - hi * rzz - xi
        n = p[_KW] * (p[_RW0] - rw)
        if n < 0.0:
            n = 0.0
        # suspension: N r_zz = f_K(h) + f_C(hdot), f_C = -F_d(hdot)
        k = p[_KF] if front else p[_KR]
        c = p[_CF] if front else p[_CR]
        dh = hi - p[_HS + i]
        f_k = p[_F0 + i] - k * dh - p[_KC] * dh ** 5
        hdot = damper_rate(f_k - n * rzz, c, p[_KNEE], p[_BLOW])
        dx[18 + i] = hdot
        # tire heading r_x ⟂ axle and r_z; r_y = r_z × r_x
        tan_d = sd / cd if front else 0.0
        rxx = 1.0 / math.sqrt(1.0 + tan_d * tan_d + ((rzx + rzy * tan_d) / rzz) ** 2)
        rxy = rxx * tan_d
        rxz = -(rzx + rzy * tan_d) * rxx / rzz
        ryx = rzy * rxz - rzz * rxy
        ryy = rzz * rxx - rzx * rxz
        ryz = rzx * rxy - rzy * rxx
        # wheel-centre velocity (8.93): v + ω × (l, y, −h) − ḣ c_z
        pvx = vx - hi * wy - yi * wz
        pvy = vy + hi * wx + li * wz
        pvz = vz + yi * wx - li * wy - hdot
        v_f = pvx * rxx + pvy * rxy + pvz * rxz
        v_s = pvx * ryx + pvy * ryy + pvz * ryz
        slip_angle = -math.atan(v_s / max(abs(v_f), _V_MIN))
        lam = slip_kernel(rw * x[11 + i], v_f, _V_MIN)
        f_long, f_lat = combined_forces(p[_TIRE:_TIRE + 19], n, lam, slip_angle)
        # tire force in body axes
        fxi = f_long * rxx + f_lat * ryx + n * rzx
        fyi = f_long * rxy + f_lat * ryy + n * rzy
        fzi = f_long * rxz + f_lat * ryz + n * rzz
        fx += fxi
        fy += fyi
        fz += fzi
        # brake and drive torques; wheel spin
        share = 0.5 * p[_KB] if front else 0.5 * (1.0 - p[_KB])
        t_brake = share * tau_b * math.tanh(x[11 + i] / p[_WB])
        t_d = t_drive if front else 0.0
        iw = p[_IWF] if front else p[_IWR]
        dx[11 + i] = (t_d - t_brake - rw * f_long - p[_FRR] * rw * n) / iw
        # moments: arm (l, y, −h) × F, and the reaction of the wheel torques about the axle r_y
        t_net = t_d - t_brake
        mx += yi * fzi + hi * fyi - t_net * ryx
        my += -hi * fxi - li * fzi - t_net * ryy
        mz += li * fyi - yi * fxi - t_net * ryz
        aux[3 + i] = n
        aux[7 + i] = f_long
        aux[11 + i] = f_lat
        aux[15 + i] = slip_angle
        aux[19 + i] = lam
    # engine, actuators
    dx[0] = dm_a
    dx[1] = (t_e - t_clutch) / p[_JE]
    dx[15] = (u[0] - alpha_t) / p[_TA]
    dx[16] = (u[1] - tau_b) / p[_TB]
    dx[17] = (u[2] - delta) / p[_TD]
    # translation (8.74) and rotation (8.68)
    ix, iy, iz = p[_IX], p[_IY], p[_IZ]
    dx[2] = wz * vy - wy * vz + fx / m + gbx
    dx[3] = wx * vz - wz * vx + fy / m + gby
    dx[4] = wy * vx - wx * vy + fz / m + gbz
    dx[7] = mx / ix + wy * wz * (iy - iz) / ix
    dx[9] = my / iy + wz * wx * (iz - ix) / iy
    dx[10] = mz / iz + wx * wy * (ix - iy) / iz
    # kinematics (8.67), (8.72): heading-frame velocity R_φᵀ R_θᵀ v
    a1 = cth * vx + sth * vz
    c1 = -sth * vx + cth * vz
    b2 = cphi * vy - sphi * c1
    dx[5] = sphi * vy + cphi * c1
    dx[6] = cth * wx + sth * wz
    dx[8] = tphi * (sth * wx - cth * wz) + wy
    deps = (-sth * wx + cth * wz) / cphi
    dx[24] = deps
    dx[22] = ceps * a1 - seps * b2
    dx[23] = seps * a1 + ceps * b2
    speed = math.sqrt(a1 * a1 + b2 * b2)
    dx[25] = speed
    # auxiliary: specific force (non-gravitational force / m), lateral acceleration, curvature
    aux[0] = fx / m
    aux[1] = fy / m
    aux[2] = fz / m
    aux[23] = speed
    aux[24] = speed * deps
    aux[25] = deps / max(speed, _V_MIN)
    aux[26] = t_e
    aux[27] = p_m


@njit(cache=True)
def sensors(x, aux, y):  # pragma: no cover - compiled
    """Fill ``y`` (12) with the PATH sensor outputs from the state and the auxiliary signals."""
    y[0] = x[0]
    y[1] = x[1]
    y[2] = aux[0]
    y[3] = aux[1]
    y[4] = aux[2]
    y[5] = x[7]
    y[6] = x[9]
    y[7] = x[10]
    y[8] = x[11]
    y[9] = x[12]
    y[10] = x[13]
    y[11] = x[14]


def evaluate(x, u, env, p) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(dx, y, aux)`` at one point (a thin Python wrapper around the compiled kernels)."""
    dx = np.empty(len(STATES))
    aux = np.zeros(_N_AUX)
    y = np.empty(len(SENSORS))
    rhs(np.asarray(x, dtype=float), np.asarray(u, dtype=float), np.asarray(env, dtype=float), p, dx, aux)
    sensors(np.asarray(x, dtype=float), aux, y)
    return dx, y, aux
