"""The 3-DOF longitudinal car of §8.1: agreement with the 6-DOF car, the §8.3.1 runs, linearisation, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.nonlinear.linearize import linearization
from fdikit.vehicle import MID_SIZE_SEDAN, Sedan
from fdikit.vehicle.longitudinal import LongitudinalCar, LongitudinalPoint
from fdikit.vehicle.road import flat_road, sine_bump

P = MID_SIZE_SEDAN
THROTTLE_27 = 20.2995  # deg: 22.555 % of the 90-degree butterfly (§8.3.1)
_GRADE_5 = -np.arctan(0.05)  # a 5 % downhill grade (uphill positive)


@pytest.fixture(scope="module")
def car():
    return LongitudinalCar()


@pytest.fixture(scope="module")
def accelerate(car):
    """§8.3.1 Fig. 8.13: from 10 m/s (1st gear, 2900 rpm) step to half throttle (45°), held 60 s, automatic box."""
    start = car.operating_point(speed=10.0, gear=1)
    return car.simulate(60.0, start=start, commands=[45.0, 0.0], gearbox="automatic")


def _loaded_radius(axle: int) -> float:
    return P.tire_radius - P.corner_loads()[2 * axle] / P.tire_stiffness


# ------------------------------------------------------------------------------------- agreement with 6-DOF
def test_straight_run_is_the_6dof_straight_run(car):
    # The same equations in the plane (symmetric car, no steering): both trims solve them to tol 1e-9 of the terms;
    # a Jacobian condition of ~1e3 (speed mode -0.03 against actuator modes -90) bounds the state error by ~1e-6.
    op = car.operating_point(throttle=THROTTLE_27)
    o6 = Sedan().operating_point(throttle=THROTTLE_27)
    s6 = Sedan.states
    pairs = {"v_x": "v_x", "v_z": "v_z", "height": "height", "pitch": "pitch", "pitch_rate": "pitch_rate",
             "air_mass": "air_mass", "engine_speed": "engine_speed", "wheel_speed_front": "wheel_speed_fl",
             "wheel_speed_rear": "wheel_speed_rl", "suspension_front": "suspension_fl",
             "suspension_rear": "suspension_rl"}
    for mine, theirs in pairs.items():
        a, b = op.x[car.states.index(mine)], o6.x[s6.index(theirs)]
        assert a == pytest.approx(b, rel=1e-6, abs=1e-12), mine
    assert o6.x[s6.index("wheel_speed_fr")] == pytest.approx(o6.x[s6.index("wheel_speed_fl")], rel=1e-9)
    assert op.speed == pytest.approx(o6.speed, rel=1e-6)
    assert op.speed == pytest.approx(27.0, abs=0.01)  # the calibration: 22.555 % holds 27 m/s
    assert op.x[car.states.index("pitch")] < 0  # drive torque and drag: nose slightly up at the front-drive point


# --------------------------------------------------------------------------------------------- §8.3.1 runs
def test_step_throttle_pitches_nose_up_and_shifts_up(accelerate):
    t, th, v = accelerate.t, accelerate.x[:, 2], accelerate.x[:, 3]
    gear = np.asarray(accelerate.meta["gear"])
    ups = int(np.sum(np.diff(gear) > 0))
    # Measured: 3 upshifts (1→2 at 14.9 m/s, 2→3 at 27.6, 3→4 at 43.4 m/s), as the three jumps of Fig. 8.13.
    assert ups >= 1
    assert np.all(np.diff(gear) >= 0)  # accelerating: never a downshift
    assert np.all(np.diff(v) > 0)  # half throttle accelerates throughout
    # after the 11 ms throttle lag the car accelerates: pitch negative (nose-up, θ > 0 is nose-down) all along
    assert np.all(th[t >= 0.5] < 0)
    # nose-up eases as acceleration falls and the aerodynamic moment grows (§8.3.1): smaller |θ| at the end
    assert abs(th[-1]) < 0.5 * abs(th[(t >= 0.5) & (t <= 2.0)]).max()


def test_brake_after_the_throttle_pitches_nose_down_and_decelerates(car, accelerate):
    # Fig. 8.14: throttle released, 1000 N total brake force (torque 1000 N × loaded radius) for 15 s.
    last = accelerate.x[-1].copy()
    start = LongitudinalPoint(x=last, u=np.zeros(2), y=accelerate.y[-1], signals={},
                              gear=int(accelerate.meta["gear"][-1]))
    r = _loaded_radius(0)
    tr = car.simulate(15.0, start=start, commands=[0.0, 1000.0 * r], gearbox="automatic")
    t, x, sig = tr.t, tr.x, tr.meta["signals"]
    assert np.all(x[t >= 0.5, 2] > 0)  # nose down
    # Deceleration from the force balance along the road: brake force, engine drag through the drive line
    # (η ζ T_clutch / r, T_clutch < 0 at closed throttle), drag, rolling resistance, with the wheels' spin inertia
    # in the effective mass.  Neglected: the loaded radius varying with load transfer (ΔN ≈ m a H / L ≈ 400 N per
    # axle → 1 mm of 311 mm, 0.3 %) and terms of order θ² and slip (1e-4): 1 % covers them three times.
    v = np.asarray(sig["ground_speed"])
    gear = np.asarray(tr.meta["gear"])
    zeta = np.array([P.gear_ratio(int(g)) for g in gear])
    kb, wb = P.brake_front_share, P.brake_smoothing
    f_brake = x[:, 13] * (kb * np.tanh(x[:, 6] / wb) + (1 - kb) * np.tanh(x[:, 7] / wb)) / r
    f_engine = -P.driveline_efficiency * zeta * np.asarray(sig["clutch_torque"]) / r
    q = 0.5 * P.air_density * P.drag_area
    f_road = q * P.drag_coefficient * v**2 + P.rolling_resistance * (P.mass * P.gravity - q * P.lift_coefficient * v**2)
    m_eff = P.mass + 2 * (P.wheel_inertia_front + P.wheel_inertia_rear) / r**2
    w = (t >= 5.0) & (t <= 15.0)  # after 6 brake lags (0.8 s): the brake at 1 − e^{−6.25} = 99.8 %
    measured = (v[w][-1] - v[w][0]) / (t[w][-1] - t[w][0])
    predicted = -np.trapezoid(f_brake[w] + f_engine[w] + f_road[w], t[w]) / (t[w][-1] - t[w][0]) / m_eff
    assert measured == pytest.approx(predicted, rel=0.01)
    assert f_brake[w].mean() == pytest.approx(1000.0, rel=1e-3)  # tanh(ω/0.5) = 1 at highway wheel speeds
    assert measured < -1000.0 / P.mass  # the road load adds to the brake


def test_coast_down_a_5_percent_grade(car):
    # Fig. 8.15: no throttle, no brake, down 5 %, from the level 15 m/s point (not an equilibrium on the grade).
    # Gravity along the road, m g sin γ ≈ 760 N, exceeds drag + rolling + engine drag (≈ 600 N in 4th at 15 m/s).
    start = car.operating_point(speed=15.0)
    tr = car.simulate(40.0, start=start, commands=[0.0, 0.0], grade=_GRADE_5)
    t, x, sig = tr.t, tr.x, tr.meta["signals"]
    v = np.asarray(sig["ground_speed"])
    assert v[-1] > v[0] + 1.0 and np.all(np.diff(v[t >= 1.0]) > 0)  # speeds up
    wy = x[:, 5]
    # the pitch mode (≈ −1.7 ± 6 j rad/s) rings at first and has died out (e^{−1.7·35}) by the end
    assert np.sum(np.diff(np.sign(wy[t <= 5.0])) != 0) >= 4
    assert np.abs(wy[t >= 35.0]).max() < 1e-2 * np.abs(wy[t <= 2.0]).max()
    # Relative pitch at the end (θ is relative to the road: gravity is rotated, not the road): quasi-static
    # balance of the pitch moments — aerodynamic, the longitudinal tire forces with their torque reaction
    # (lever h + r_w), rolling resistance, wheel spin — against the pitch stiffness of the axles (spring in series
    # with tire) less the normal forces' h N θ.  Neglected: heave–pitch coupling (bounded below), −Σ l F θ.
    k = -1
    n = np.array([sig["normal_force_front"][k], sig["normal_force_rear"][k]])
    f = np.array([sig["tire_force_front"][k], sig["tire_force_rear"][k]])
    h = x[k, 8:10]
    rw = P.tire_radius - n / (2 * P.tire_stiffness)
    spin = 2 * np.array([P.wheel_inertia_front, P.wheel_inertia_rear]) * np.gradient(x[:, 6:8], t, axis=0)[k]
    aero = 0.5 * P.air_density * P.drag_area * P.wheelbase * P.pitch_moment_coefficient * v[k] ** 2
    moment = aero - np.sum((h + rw) * f) - P.rolling_resistance * np.sum(rw * n) - np.sum(spin)
    ks = 2 * np.array([P.spring_front, P.spring_rear])
    kax = ks * 2 * P.tire_stiffness / (ks + 2 * P.tire_stiffness)
    lever = np.array([P.cg_to_front_axle, -(P.wheelbase - P.cg_to_front_axle)])
    k_theta = np.sum(kax * lever**2) - np.sum(h * n)
    theta_qs = moment / k_theta
    # coupling bound: the load change ΔN (lift, grade) heaves the car by ΔN/Σk; Σ k l turns that into a moment
    d_n = abs(n.sum() - P.mass * P.gravity)
    coupling = abs(np.sum(kax * lever)) * d_n / kax.sum() + abs(np.sum(lever * f)) * abs(x[k, 2])
    assert x[k, 2] == pytest.approx(theta_qs, abs=2 * coupling / k_theta + 0.01 * abs(theta_qs))
    assert x[k, 2] > 5 * aero / k_theta > 0  # nose-down, more than the aerodynamic moment alone gives


def test_bump_gives_two_pitch_events_a_wheelbase_apart(car):
    # Fig. 8.16: 0.01 m × 0.3 m (1 − cos) bump at 27 m/s; the front axle meets it at s = 20 m, the rear L/V later.
    start = car.operating_point(speed=27.0)
    road = flat_road(120.0) + sine_bump(120.0, position=20.0)
    tr = car.simulate(3.0, start=start, road=road, dt=0.001)
    t = tr.t
    acc = np.gradient(tr.x[:, 5], t)  # pitch acceleration: the sharp corners of the pitch angle
    big = np.flatnonzero(np.abs(acc) > 0.1 * np.abs(acc).max())
    clusters = np.split(big, np.flatnonzero(np.diff(t[big]) > 0.03) + 1)
    assert len(clusters) == 2
    first = [c[0] for c in clusters]
    v = start.speed
    assert t[first[0]] == pytest.approx(20.0 / v, abs=0.3 / v)  # within the bump's passage time
    # both events are the same bump seen at the same phase: their separation is L/V to the 1 ms sampling
    assert t[first[1]] - t[first[0]] == pytest.approx(P.wheelbase / v, abs=2e-3)
    assert acc[first[0]] < 0 < acc[first[1]]  # front lifted: nose up first; rear lifted: nose down
    assert np.abs(tr.x[:, 2] - start.x[2]).max() < 1e-3  # a small disturbance (≈ 1e-4 rad)


# ------------------------------------------------------------------------------------------- linearisation
def test_linear_model_is_the_6dof_symmetric_block(car):
    op = car.operating_point(speed=27.0)
    sedan = Sedan()
    o6 = sedan.operating_point(speed=27.0)
    lin = linearization(car.design_plant(), op.x[1:], op.u)
    l6 = linearization(sedan.design_plant(), o6.x[:22], o6.u)
    assert np.linalg.eigvals(car.linearize(op).A).real.max() < 0
    # Mapping: a longitudinal state is the symmetric motion of the 6-DOF car — wheel_speed_front ↔ fl = fr,
    # suspension_front ↔ fl = fr (likewise rear), the rest one to one.  T embeds (per axle → both corners),
    # P = T⁺ averages the two corners; A_long = P A_6 T when the symmetric subspace is invariant.
    s6, sl = sedan.states[:22], car.states[1:]
    corners = {"wheel_speed_front": ("wheel_speed_fl", "wheel_speed_fr"),
               "wheel_speed_rear": ("wheel_speed_rl", "wheel_speed_rr"),
               "suspension_front": ("suspension_fl", "suspension_fr"),
               "suspension_rear": ("suspension_rl", "suspension_rr")}
    T = np.zeros((22, 13))
    for j, name in enumerate(sl):
        for c in corners.get(name, (name,)):
            T[s6.index(c), j] = 1.0
    Pm = np.linalg.pinv(T)
    A6, AL = l6.model.A, lin.model.A
    # invariance: symmetric motion drives no lateral state and no left-right difference (roundoff only)
    lateral = [s6.index(n) for n in ("v_y", "roll", "roll_rate", "yaw_rate", "steering")]
    assert np.abs((A6 @ T)[lateral]).max() < 1e-9 * np.abs(A6).max()
    pred = Pm @ A6 @ T
    # tolerance: the central-difference error estimates of both (propagated through T, P) plus roundoff of the
    # differences (ε/δ ≈ 1e-10 of the row's scale at relative steps ≈ 1e-6), which the ladder can miss
    row = np.maximum(np.abs(AL).max(axis=1, keepdims=True), np.abs(pred).max(axis=1, keepdims=True))
    tol = 3 * (np.abs(Pm) @ l6.error["A"] @ T + lin.error["A"]) + 1e-9 * row
    assert np.all(np.abs(AL - pred) <= tol)
    np.testing.assert_allclose(lin.model.Bu, Pm @ l6.model.Bu[:, :2], rtol=1e-6, atol=1e-9)
    # every longitudinal eigenvalue is one of the 22-state car's
    e6 = np.linalg.eigvals(A6)
    for e in np.linalg.eigvals(AL):
        assert np.min(np.abs(e6 - e)) <= 1e-6 * abs(e)


# ------------------------------------------------------------------------------------------ bad arguments
def test_bad_arguments_raise_parameter_error(car):
    op = car.operating_point(throttle=THROTTLE_27)
    with pytest.raises(ParameterError, match="params"):
        LongitudinalCar(params="sedan")
    with pytest.raises(ParameterError, match="exactly one"):
        car.operating_point()
    with pytest.raises(ParameterError, match="exactly one"):
        car.operating_point(throttle=20.0, speed=27.0)
    with pytest.raises(ParameterError, match="gear"):
        car.operating_point(speed=27.0, gear=7)
    with pytest.raises(ParameterError, match="x"):
        car.derivatives(np.zeros(13), [20.0, 0.0])
    with pytest.raises(ParameterError, match="op"):
        car.linearize(Sedan().operating_point(throttle=THROTTLE_27))
    with pytest.raises(ParameterError, match="multiple"):
        car.simulate(1.0, start=op, dt=0.0015)
    with pytest.raises(ParameterError, match="gearbox"):
        car.simulate(1.0, start=op, gearbox="manual")
    with pytest.raises(ParameterError, match="commands"):
        car.simulate(0.1, start=op, commands=[20.0, 0.0, 0.0])
    with pytest.raises(ParameterError, match="road"):
        car.simulate(1.0, start=op, road="flat")
    with pytest.raises(ParameterError, match="longer road"):
        car.simulate(1.0, start=op, road=flat_road(10.0))
