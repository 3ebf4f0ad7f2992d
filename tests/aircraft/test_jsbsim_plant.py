"""The JSBSim plant: faults where JSBSim reads them, trim of three aircraft, linearisation against flight.

Tolerances: the trim residuals are driven to 1e-6 (rad/s², g, rad/s) by construction and asserted
there; a trimmed aircraft then drifts only by the curvature of JSBSim's round, rotating Earth
(level flight is not an equilibrium of zero body rates: ``q = V/R ≈ 1.5e-5 rad/s``), so the
altitude over 10 s may move by about ``V² t² / (2R) ≈ 0.07 m`` and the speed by ``g θ_drift t``
(< 0.02 m/s); the bounds are ten times these. The linear model is checked against the difference
of two flown responses (perturbed minus unperturbed, which removes that drift): the
perturbation is 1e-3, so the neglected second-order terms are about 1e-3 of the response, and
JSBSim's multi-step integrators (Adams–Bashforth at 120 Hz) add errors of order ``(ω dt)²`` and one
step of lag in ``α̇``; the bound is 5 % of each response component. The flights run at 500 Hz
(JSBSim's rectangular-Euler body rates cost ~15 % on the speed response at 120 Hz) and start through
``restore(snapshot())`` like the base flight (a bare ``set_state`` keeps JSBSim's integrator history,
a 4e-4 m/s offset in the first step).
"""

import numpy as np
import pytest

from fdikit.actuator_faults import EngineFailure, Float, LockInPlace, Runaway
from fdikit.aircraft import (
    B747_LIMITS,
    HALLOUZI_POINT,
    FlightCondition,
    JSBSimAircraft,
    linearize_aircraft,
    prepare_aircraft,
    trim_aircraft,
)
from fdikit.errors import ParameterError
from fdikit.faults import Bias, FaultScenario, Stuck

TRIM_POINTS = {
    "B747": HALLOUZI_POINT,
    "737": FlightCondition(altitude=3000.0, airspeed=150.0),
    "global5000": FlightCondition(altitude=5000.0, airspeed=180.0, flight_path_angle=np.radians(-3.0)),
}


@pytest.fixture(scope="module")
def b747():
    ac = JSBSimAircraft("B747")
    trim = trim_aircraft(ac, HALLOUZI_POINT)
    return ac, trim, ac.snapshot()


def fly(ac, seconds):
    out = []
    for _ in range(int(round(seconds / ac.dt))):
        ac.step()
        out.append(ac.state())
    return np.array(out)


@pytest.mark.parametrize("name", sorted(TRIM_POINTS))
def test_trim_converges_and_holds_for_three_aircraft(name):
    ac = JSBSimAircraft(name)
    cond = TRIM_POINTS[name]
    tr = trim_aircraft(ac, cond)
    assert tr.converged
    x0 = ac.state()
    np.testing.assert_allclose(x0[[3, 9]], [cond.airspeed, cond.altitude], rtol=1e-9)
    np.testing.assert_allclose(x0[7] - x0[4], cond.flight_path_angle, atol=1e-6)  # θ − α = γ, wings level
    y = fly(ac, 10.0)
    climb = cond.airspeed * np.sin(cond.flight_path_angle) * np.arange(1, len(y) + 1) * ac.dt
    assert np.max(np.abs(y[:, 3] - cond.airspeed)) < 0.2
    # a descent is not an equilibrium: the density grows by |Δh|/H (H ≈ 9 km scale height), about 1 %
    # over the 94 m of the global5000's run, and the path bends by as much
    assert np.max(np.abs(y[:, 9] - cond.altitude - climb)) < 1.0 + 0.02 * np.max(np.abs(climb))
    assert np.max(np.abs(y[:, :3])) < 1e-3  # body rates stay at zero


def test_hallouzi_point_mass_flaps_and_limits(b747):
    ac, tr, snap = b747
    ac.restore(snap)
    assert ac.mass == pytest.approx(263e3, rel=1e-9)
    assert np.degrees(tr.positions["flap"]) == pytest.approx(20.0)
    assert tr.positions["elevator"] == 0.0  # trimmed with the stabiliser
    lim = B747_LIMITS["stabilizer"]
    assert lim.lower < tr.positions["stabilizer"] < lim.upper


def test_surface_position_is_what_jsbsim_reads_and_a_fault_changes_the_flight(b747):
    ac, tr, snap = b747
    ac.restore(snap)
    ac.inject([])
    healthy = fly(ac, 8.0)
    ac.restore(snap)
    ac.inject([LockInPlace("elevator", position=np.radians(5.0), onset=1.0)])
    faulty = fly(ac, 8.0)
    ac.inject([])
    # JSBSim's aerodynamics read fcs/elevator-pos-rad: it is the actuator's position, not the FCS's
    assert ac.fdm["fcs/elevator-pos-rad"] == pytest.approx(np.radians(5.0), rel=1e-12)
    assert ac.fdm["fcs/elevator-cmd-norm"] == 0.0  # the FCS command path is not what moved it
    # 5 deg trailing edge down: nose down, the aircraft descends
    assert faulty[-1, 9] < healthy[-1, 9] - 20.0
    assert np.max(np.abs(faulty[:, 1] - healthy[:, 1])) > np.radians(1.0)


def test_lock_in_place_travels_at_the_rate_limit(b747):
    ac, tr, snap = b747
    ac.restore(snap)
    lock = np.radians(-20.0)
    ac.inject([LockInPlace("elevator", position=lock, onset=0.5)])
    pos = []
    for _ in range(200):
        ac.step()
        pos.append(ac.actuators.positions["elevator"])
    ac.inject([])
    rate = np.diff(pos) / ac.dt
    limit = B747_LIMITS["elevator"].rate_down
    assert np.min(rate) == pytest.approx(-limit, rel=1e-12)  # travels at 37 deg/s …
    assert np.all(rate >= -limit * (1 + 1e-12))  # … never faster
    n_max = np.sum(np.isclose(rate, -limit, rtol=1e-9))
    assert n_max == pytest.approx((tr.positions["elevator"] - lock) / (limit * ac.dt), abs=15)  # most of the way
    assert pos[-1] == pytest.approx(lock, abs=1e-6)  # and stays


def test_runaway_at_its_own_rate_and_stuck_float_engine_failure(b747):
    ac, tr, snap = b747
    ac.restore(snap)
    rate = np.radians(20.0)  # slower than the 50 deg/s actuator
    ac.inject(FaultScenario([Runaway("rudder", position=np.radians(25), rate=rate, onset=0.0),
                             Stuck("aileron", onset=0.0), Float("stabilizer", onset=0.0),
                             EngineFailure("throttle_3", onset=0.0)]))
    ail0 = ac.actuators.positions["aileron"]
    ac.set_inputs(aileron=np.radians(10.0))
    rud = []
    for _ in range(60):
        ac.step()
        rud.append(ac.actuators.positions["rudder"])
    assert np.max(np.diff(rud)) / ac.dt == pytest.approx(rate, rel=1e-12)
    assert ac.actuators.positions["aileron"] == ail0  # stuck where it was, whatever the command
    assert abs(ac.actuators.positions["stabilizer"]) < abs(tr.positions["stabilizer"])  # floating to 0
    thrust = ac.thrust()
    assert thrust[2] == 0.0 and np.all(thrust[[0, 1, 3]] > 1e4)
    ac.inject([])


def test_sensor_faults_apply_in_measure(b747):
    ac, tr, snap = b747
    ac.restore(snap)
    ac.inject([Bias("alpha", 0.05, onset=0.0)])
    y = ac.measure()
    ac.inject([])
    assert y[4] - ac.outputs()[4] == pytest.approx(0.05)


LONGITUDINAL, LATERAL = [1, 3, 4, 7, 9], [0, 2, 5, 6, 8]  # q V α θ h / p r β φ ψ


def test_linearization_matches_flown_responses():
    # JSBSim integrates body rates by rectangular Euler: at 120 Hz its own error on the speed response is
    # ~15 %; at 500 Hz (used here) it is below 4 %, so the flight is a fair reference for the linear model
    ac = JSBSimAircraft("B747", dt=0.002)
    tr = trim_aircraft(ac, HALLOUZI_POINT)
    snap = ac.snapshot()
    lin = linearize_aircraft(ac, tr)
    A, B = lin.model.A, lin.model.B
    np.testing.assert_allclose(lin.f0, 0.0, atol=1e-9)
    from scipy.linalg import expm

    horizon, dt = 2.0, ac.dt
    ac.restore(snap)
    base = fly(ac, horizon)
    n = len(base)
    checks = []
    for j, h in ((4, 1e-3), (3, 0.1), (1, 1e-3), (5, 1e-3), (0, 1e-3)):  # α, V, q, β, p
        ac.restore(snap)
        x = tr.x.copy()
        x[j] += h
        ac.set_state(x)
        ac.restore(ac.snapshot())  # start the flight as the base one does (JSBSim's integrators restarted)
        Phi = expm(A * dt)
        pred, z = [], x - tr.x
        for _ in range(n):
            z = Phi @ z
            pred.append(z)
        checks.append((j in LONGITUDINAL, fly(ac, horizon) - base, np.array(pred)))
    for i, name in enumerate(lin.model.controls[:-1]):  # surfaces held at ±1e-3 rad from the start
        flown = []
        for sign in (1, -1):
            ac.restore(snap)
            pos = {**tr.positions, name: tr.positions[name] + sign * 1e-3}
            ac.hold_surfaces(pos)
            ac.set_inputs(**{name: pos[name]})
            ac.restore(ac.snapshot())
            flown.append(fly(ac, horizon))
        # the central difference of the flight, as the linearisation takes it: JSBSim's B747 drag has a
        # |δe| term, which has a kink at the trim's δe = 0
        dx = (flown[0] - flown[1]) / 2
        M = expm(np.block([[A, B[:, i:i + 1]], [np.zeros((1, 11))]]) * dt)
        z, pred = np.r_[np.zeros(10), 1e-3], []
        for _ in range(n):
            z = M @ z
            pred.append(z[:10].copy())
        checks.append((name in ("elevator", "stabilizer"), dx, np.array(pred)))
    for longitudinal, dx, pred in checks:
        # a symmetric trim: the other axis responds only to second order (excluded)
        axis = LONGITUDINAL if longitudinal else LATERAL
        scale = np.max(np.abs(pred[:, axis]), axis=0)
        assert np.max(np.abs(dx - pred)[:, axis] / scale) < 0.05


def test_linearization_matches_jsbsim_own(b747):
    """JSBSim's FGLinearization (the peer) on the same trim: the rigid-body block of A agrees."""
    import jsbsim

    ac, tr, snap = b747
    ac.restore(snap)
    lin = linearize_aircraft(ac, tr)
    peer = jsbsim.FGLinearization(ac.fdm)
    names = list(peer.x_names)
    ours = ["P", "Q", "R", "Vt", "Alpha", "Beta", "Phi", "Theta", "Psi", "Alt"]
    idx = [names.index(n) for n in ours]
    scale = np.array([1, 1, 1, 0.3048, 1, 1, 1, 1, 1, 0.3048])  # JSBSim's ft/s and ft to SI
    A_peer = np.asarray(peer.system_matrix)[np.ix_(idx, idx)] * scale[:, None] / scale[None, :]
    ac.restore(snap)  # (also puts back the step FGLinearization set to 0)
    err = np.abs(A_peer - lin.model.A)
    assert np.max(err) < 1e-4 * np.max(np.abs(lin.model.A))


def test_turbulence_is_reproducible_with_a_seed(b747):
    ac, tr, snap = b747
    runs = []
    for seed in (3, 3, 4):
        ac.restore(snap)
        ac.set_turbulence(severity=4, seed=seed)
        runs.append(fly(ac, 3.0))
    ac.set_turbulence(0)
    ac.restore(snap)
    calm = fly(ac, 3.0)
    gust = np.max(np.abs(runs[0] - calm), axis=0)
    assert np.all(gust[:3] > 1e-3)  # the gusts move the body rates
    # the same seed repeats the gusts (JSBSim rotates them with the heading, and a restored heading of
    # 2π versus 0 differs in the last bits, so the repeat is to 1e-3 of the gust response, not bit for bit)
    assert np.max(np.abs(runs[0] - runs[1]) / gust) < 1e-3
    assert np.max(np.abs(runs[0] - runs[2])[:, :3] / gust[:3]) > 0.1


def test_bad_input_is_refused():
    with pytest.raises(ParameterError, match="ships no aircraft"):
        prepare_aircraft("Boeing-9000")
    ac = JSBSimAircraft("737")
    with pytest.raises(ParameterError, match="no control"):
        ac.set_inputs(spoiler=0.1)
    with pytest.raises(ParameterError, match="no flap"):
        trim_aircraft(ac, FlightCondition(3000.0, 150.0, flaps=0.3))
    with pytest.raises(ParameterError, match="empty weight"):
        ac.set_mass(1000.0)
    with pytest.raises(ParameterError, match="no signal named .canard"):
        ac.inject([LockInPlace("canard", position=0.0)])


def test_limits_given_for_some_surfaces_keep_the_others():
    from fdikit.aircraft import SurfaceLimits

    narrow = SurfaceLimits(*np.radians([-15, 15, 40, 45]).tolist())
    ac = JSBSimAircraft("B747", limits={"aileron": narrow})
    assert ac.actuators.limits["aileron"] is narrow
    assert ac.actuators.limits["rudder"] == B747_LIMITS["rudder"]
    # with ±15° ailerons (Ch. 4's lumped range) a 25° rudder cannot be trimmed straight; with ±20° it can
    assert not trim_aircraft(ac, HALLOUZI_POINT, {"rudder": np.radians(25)}, require=False).converged


def test_mass_lost_in_flight_keeps_the_state():
    ac = JSBSimAircraft("B747", dt=0.01)
    trim_aircraft(ac, HALLOUZI_POINT)
    ac.step(10)
    x = ac.state()
    m = ac.mass
    ac.set_mass(m - 10_028.0, in_flight=True)
    assert np.array_equal(ac.state(), x)               # no re-initialisation
    ac.step()
    assert ac.mass == pytest.approx(m - 10_028.0, abs=1.0)    # less one step of fuel burn (≈ 0.05 kg)
    with pytest.raises(ParameterError, match="in flight"):
        ac.set_mass(ac.mass - 5_000.0, in_flight=True)     # 3 t of payload left: fuel would have to go
