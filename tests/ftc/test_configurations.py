"""Table 6.1 configurations: commands, limits, and the linear model against fdikit's B747 linearisation."""

import numpy as np
import pytest
import scipy.signal as ss

from fdikit.aircraft import B747_LIMITS, HALLOUZI_POINT, JSBSimAircraft, linearize_aircraft, trim_aircraft
from fdikit.errors import ParameterError
from fdikit.ftc.configurations import (
    ENGINE_RATE,
    TABLE_6_1,
    configuration_model,
    identification_data,
    input_configuration,
)


@pytest.fixture(scope="module")
def b747():
    ac = JSBSimAircraft("B747", dt=0.01)
    trim = trim_aircraft(ac, HALLOUZI_POINT)
    return ac, trim, linearize_aircraft(ac, trim)


def test_table_6_1_without_spoilers():
    assert input_configuration("nominal").inputs == ("aileron", "elevator", "rudder", "engines")
    assert "stabilizer" in TABLE_6_1["elevator"] and "elevator" not in TABLE_6_1["elevator"]
    assert "rudder" not in TABLE_6_1["rudder"] and {"engines_left", "engines_right"} <= set(TABLE_6_1["rudder"])
    assert input_configuration("unanticipated").m == 6
    with pytest.raises(ParameterError, match="configuration"):
        input_configuration("spoilers")


def test_commands_and_vector_are_inverse():
    cfg = input_configuration("rudder")
    pos = {"aileron": 0.01, "elevator": -0.02}
    thr = [0.5, 0.5, 0.6, 0.6]
    cmd = cfg.commands([2.0, -1.0, 10.0, -5.0], pos, thr)
    assert cmd["aileron"] == pytest.approx(0.01 + np.radians(2.0), abs=1e-15)
    assert [cmd[f"throttle_{i}"] for i in (1, 2, 3, 4)] == pytest.approx([0.6, 0.6, 0.55, 0.55], abs=1e-15)
    back = cfg.vector({**pos, "aileron": cmd["aileron"], "elevator": cmd["elevator"]},
                      [cmd[f"throttle_{i}"] for i in (1, 2, 3, 4)], pos, thr)
    assert back == pytest.approx([2.0, -1.0, 10.0, -5.0], abs=1e-12)
    with pytest.raises(ParameterError):
        cfg.commands([1.0, 2.0], pos, thr)


def test_limits_are_app_a_less_the_trim(b747):
    _, trim, _ = b747
    cfg = input_configuration("elevator")
    thr = np.full(4, trim.throttle)
    lim = cfg.limits(trim.positions, thr, 0.1)
    stab = B747_LIMITS["stabilizer"]
    assert lim.u_max[1] == pytest.approx(np.degrees(stab.upper - trim.positions["stabilizer"]), abs=1e-12)
    assert lim.du_max[1] == pytest.approx(0.05, abs=1e-12)                 # 0.5 °/s at 10 Hz
    assert lim.u_min[3] == pytest.approx(-100 * trim.throttle, abs=1e-12)
    assert lim.du_max[3] == pytest.approx(ENGINE_RATE * 0.1, abs=1e-12)


@pytest.mark.parametrize("name", sorted(TABLE_6_1))
def test_model_columns_equal_the_linearisation(b747, name):
    ac, trim, lin = b747
    cfg = input_configuration(name)
    Ad, Bd, C = configuration_model(ac, trim, cfg, 0.1)
    A, B, controls = lin.model.A, lin.model.B, lin.model.controls
    # JSBSim's aerodynamic tables are piecewise linear, so both central differences (0.5° / 0.5 % here,
    # 1e-3 rad / throttle there) give the same slope; what is left is the round-off of the differences
    # (≈ 1e-13 / 1e-3) and of the two discretisations.
    for j, n in enumerate(cfg.inputs):
        if n in controls:
            col = B[:, controls.index(n)] * np.pi / 180
        elif n == "engines":
            col = B[:, controls.index("thrust")] * lin.thrust_slope / 100
        else:
            continue
        Ad2, Bd2, *_ = ss.cont2discrete((A, col[:, None], np.eye(10), np.zeros((10, 1))), 0.1)
        assert Ad == pytest.approx(Ad2, rel=1e-8, abs=1e-9)
        assert Bd[:, j] == pytest.approx(Bd2[:, 0], rel=1e-7, abs=1e-7 * np.abs(Bd2).max())
    assert C.shape == (7, 10) and C[0, 6] == pytest.approx(180 / np.pi)


def test_engine_groups_add_up_and_yaw_opposite_ways(b747):
    ac, trim, _ = b747
    _, Bn, _ = configuration_model(ac, trim, input_configuration("nominal"), 0.1)
    _, Br, _ = configuration_model(ac, trim, input_configuration("rudder"), 0.1)
    assert Br[:, 2] + Br[:, 3] == pytest.approx(Bn[:, 3], rel=1e-7, abs=1e-7 * np.abs(Bn[:, 3]).max())
    assert Br[2, 2] > 0 > Br[2, 3]                 # left engines yaw right (r > 0), right engines left
    # mirror images to 2e-6: JSBSim's engine locations are not exactly symmetric
    assert Br[2, 2] == pytest.approx(-Br[2, 3], rel=1e-4)


def test_locked_surface_cannot_be_an_input(b747):
    ac, _, _ = b747
    locked = trim_aircraft(ac, HALLOUZI_POINT, {"rudder": np.radians(10.0)}, require=False)
    with pytest.raises(ParameterError, match="locks"):
        configuration_model(ac, locked, input_configuration("nominal"), 0.1)


def test_identification_data_is_the_model_response_plus_noise():
    rng = np.random.default_rng(0)
    A, B, C = np.array([[0.5]]), np.array([[1.0, 2.0]]), np.array([[1.0], [3.0]])
    u, y = identification_data(A, B, C, 20_000, rng, input_std=[1.0, 0.5], noise_std=[0.0, 0.1])
    x = np.zeros(1)
    want = np.empty((u.shape[0], 2))
    for k in range(u.shape[0]):
        want[k] = C @ x
        x = A @ x + B @ u[k]
    assert y[:, 0] == pytest.approx(want[:, 0], abs=1e-12)
    # the noise: std 0.1 estimated from 20 000 samples, standard error 0.1/√(2·20 000) = 5e-4; allow 5 of those
    assert np.std(y[:, 1] - want[:, 1]) == pytest.approx(0.1, abs=2.5e-3)
    assert np.std(u, axis=0) == pytest.approx([1.0, 0.5], rel=0.025)
