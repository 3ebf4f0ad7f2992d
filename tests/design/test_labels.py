"""names= / isolates= on every design (fdikit.design.labels) and the operating point carried into the generator."""

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.design.game import (
    dgtfdf,
    discrete_game_setup,
    game_filter,
    game_filter_bank,
    goh_detector,
    goh_filter,
    ltv_detection_filter,
    ltv_game_filter,
    single_fault_game_filter,
)
from fdikit.design.labels import fault_label, label_generator, residual_labels
from fdikit.design.observers import (
    beard_jones,
    enhancement_direction,
    hinf_detection_filter,
    kalman,
    observer,
    observer_generator,
    restricted_diagonal,
    uio,
    uio_bank,
)
from fdikit.design.parity import lpv_parity_residuals, parity_design, parity_filter, robust_lpv_parity
from fdikit.errors import ModelError, ParameterError
from fdikit.ltv import LTVModel
from fdikit.plants import msd, varrier_lateral_lpv, varrier_uncertainty
from fdikit.plants.f16xl import F16XL_DRYDEN_GAIN, f16xl_gust
from fdikit.plants.single_track import single_track_lpv
from fdikit.plants.white_speyer import white_speyer
from fdikit.trace import Trace


def _bj_model():
    return FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bf=[[1.0, 0], [0, 1.0], [0, 0]], faults=["f1", "f2"])


def test_residual_labels_sequence_mapping_and_defaults():
    m = msd()  # fault inputs u1_actuator, y2_sensor; outputs y1..y3; controls u1, u2
    assert residual_labels(m, 2) == (("r0", "r1"), (None, None))
    assert residual_labels(m, 2, ["a", "b"], ["y2_sensor:magnitude", None]) == (("a", "b"), ("y2_sensor", None))
    # a sensor / actuator fault name of a signal that is no fault input is still a fault name (the convention)
    assert residual_labels(m, 1, isolates=["y3_sensor"])[1] == ("y3_sensor",)
    assert residual_labels(m, 2, isolates={"r1": "u2_actuator"}, default_isolates=["y2_sensor", None])[1] == (
        "y2_sensor", "u2_actuator")
    # the design's own defaults are taken as given (explicit fault maps carry names of their own)
    assert residual_labels(m, 1, default_isolates=["my_map"])[1] == ("my_map",)


@pytest.mark.parametrize(("names", "isolates", "error", "match"), [
    (["a"], None, ParameterError, "2 non-empty strings"),
    (["a", "a"], None, ParameterError, "distinct"),
    (None, ["y2_sensor"], ParameterError, "1 entries for 2"),
    (None, {"nope": "y2_sensor"}, ParameterError, "residual 'nope'"),
    (None, ["y2", None], ParameterError, "'y2_sensor'"),  # bare signal name: the fault name is given
    (None, [None, "u1"], ParameterError, "'u1_actuator'"),
    (None, ["wheel_sensor", None], ModelError, "not a fault"),
    (None, [3, None], ParameterError, "string"),
])
def test_bad_names_and_isolates_are_refused(names, isolates, error, match):
    with pytest.raises(error, match=match):
        residual_labels(msd(), 2, names, isolates)


def test_fault_label_on_a_dae_and_an_lpv_model():
    lpv = varrier_lateral_lpv()
    assert fault_label(lpv, "lateral_acceleration_sensor") == "lateral_acceleration_sensor"
    with pytest.raises(ParameterError, match="'yaw_rate_sensor'"):
        fault_label(lpv, "yaw_rate")
    with pytest.raises(ModelError, match="not a fault"):
        fault_label(lpv, "brake_actuator")


def test_observer_designs_round_names_and_isolates_through():
    m = msd()
    names, iso = ["ra", "rb", "rc"], ["u1_actuator", None, "y2_sensor"]
    for d in (kalman(m, 1.0, 1.0, names=names, isolates=iso),
              observer(m, [-2.0, -2.5, -3.0, -3.5, -4.0, -4.5], names=names, isolates=iso)):
        assert d.generator.residuals == tuple(names) and d.generator.isolates == tuple(iso)
    g = observer_generator(m, kalman(m, 1.0, 1.0).gain, names=names, isolates={"rb": "y2_sensor"})
    assert g.residuals == tuple(names) and g.isolates == (None, "y2_sensor", None)
    with pytest.raises(ParameterError, match="once"):
        observer_generator(m, kalman(m, 1.0, 1.0).gain, outputs=names, names=names)
    with pytest.raises(ParameterError, match="'y1_sensor'"):
        kalman(m, 1.0, 1.0, isolates=["y1", None, None])

    bj = _bj_model()
    d = beard_jones(bj, ["f1", "f2"], {"f1": [-4.0], "f2": [-5.0]}, [-6.0])
    assert d.generator.isolates == ("f1", "f2")  # the default: each residual tied to its target
    d = beard_jones(bj, ["f1", "f2"], {"f1": [-4.0], "f2": [-5.0]}, [-6.0], names=["a", "b"],
                    isolates={"b": None})
    assert d.generator.residuals == ("a", "b") and d.generator.isolates == ("f1", None)
    rd = restricted_diagonal(bj, ["f1", "f2"], poles=[-4.0, -5.0, -6.0], isolates={"f2[0]": "f1"})
    assert rd.generator.residuals == ("f1[0]", "f1[1]", "f2[0]", "f2[1]")
    assert rd.generator.isolates == ("f1", "f1", "f1", "f2")

    three = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3)).with_sensor_faults(["y0", "y2"])
    q = len(uio(three, "y0_sensor", nuisance="others", poles=[-4.0, -5.0, -6.0]).generator.residuals)
    u = uio(three, "y0_sensor", nuisance="others", poles=[-4.0, -5.0, -6.0], names=[f"u{i}" for i in range(q)])
    assert u.generator.residuals == tuple(f"u{i}" for i in range(q)) and u.generator.isolates == ("y0_sensor",) * q
    sizes = [len(d.generator.residuals) for d in uio_bank(three, poles=[-4.0, -5.0, -6.0])]
    names = [f"b{i}" for i in range(sum(sizes))]
    bank = uio_bank(three, poles=[-4.0, -5.0, -6.0], names=names, isolates={names[0]: None})
    assert [d.generator.residuals for d in bank] == [tuple(names[:sizes[0]]), tuple(names[sizes[0]:])]
    assert bank[0].generator.isolates == (None,) + ("y0_sensor",) * (sizes[0] - 1)
    assert bank[1].generator.isolates == ("y2_sensor",) * sizes[1]

    gust = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    h = hinf_detection_filter(gust, ["y_Az_sensor", "elevon_actuator"], gamma=1.5)
    k = len(h.generator.residuals)
    h2 = hinf_detection_filter(gust, ["y_Az_sensor", "elevon_actuator"], gamma=1.5,
                               names=[f"z{i}" for i in range(k)], isolates=[None] * k)
    assert h2.generator.residuals[0] == "z0" and set(h2.generator.isolates) == {None}
    # the enhancement direction finds the rows of z_i from the design, not from the (renamed) isolates
    e1, e2 = enhancement_direction(h, "y_Az_sensor"), enhancement_direction(h2, "y_Az_sensor", names=["q"])
    np.testing.assert_array_equal(e1.generator.C, e2.generator.C)
    assert e2.generator.residuals == ("q",) and e2.generator.isolates == ("y_Az_sensor",)


def test_game_designs_round_names_and_isolates_through():
    ws = white_speyer("stable-extra-zero")
    d = single_fault_game_filter(ws, "f1", ["f2"], Q=1e-3, M=0.05, names=["g"], isolates=["f2"])
    assert d.generator.residuals == ("g",) and d.generator.isolates == ("f2",)
    bank = game_filter_bank(ws, ["f1", "f2"], Q=1e-3, M=0.05, isolates={"f1[0]": None})
    assert bank.generator.isolates == (None, "f2")
    gf = game_filter(ws, ["f1", "f2"], M=0.05, Q=1e-3, options={"maxiter": 2}, names=["a", "b"])
    assert gf.generator.residuals == ("a", "b") and gf.generator.isolates == ("f1", "f2")
    with pytest.raises(ModelError, match="not a fault"):
        game_filter(ws, ["f1", "f2"], M=0.05, Q=1e-3, options={"maxiter": 2}, isolates=["f1", "f9"])
    ws3 = white_speyer()
    g = goh_filter(ws3, ["f1", "f2"], names=["p", "q"]).generator
    assert g.residuals == ("p", "q") and g.isolates == ("f1", "f2")
    g = goh_detector(ws3, "f1", ["f2"], names=["p"]).generator
    assert g.residuals == ("p",) and g.isolates == ("f1",)
    st = discrete_game_setup(ws3.discretize(0.01), ["f1"], ["f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, steps=20)
    d = dgtfdf(st, names=["r"], isolates=[None])
    assert d.generator.residuals == ("r",) and d.generator.isolates == (None,)
    lm = LTVModel.from_lti(ws3, ["f1", "f2"])
    res = ltv_detection_filter(lm, ["f1"], ["f2"], lambda t: np.ones((3, 2)), names=["a", "b"],
                               isolates={"b": "f2"}).run(np.linspace(0, 1, 5), np.zeros((5, 2)))
    assert res.names == ("a", "b") and res.isolates == ("f1", "f2")
    g = ltv_game_filter(lm, "f1", ["f2"], np.linspace(0, 1, 3), gamma=1e-2, M=0.05, Q=1e-3, names=["x", "y"])
    assert g.generator.names == ("x", "y")
    with pytest.raises(ParameterError, match="2 non-empty"):
        ltv_game_filter(lm, "f1", ["f2"], np.linspace(0, 1, 3), gamma=1e-2, M=0.05, Q=1e-3, names=["x"])


def test_parity_designs_round_names_and_isolates_through():
    m = FaultModel([[0.9]], [[1.0], [2.0]], Bu=[[1.0]], dt=0.1).with_sensor_faults(["y0", "y1"])
    d = parity_design(m, 1, names=["p0", "p1", "p2"], isolates=["y0_sensor", None, "y1_sensor"])
    assert d.generator.residuals == ("p0", "p1", "p2") and d.generator.isolates == ("y0_sensor", None, "y1_sensor")
    car = single_track_lpv()(70 / 3.6)
    f = parity_filter(car, "steering_actuator", names=["r_delta"])
    assert f.generator.residuals == ("r_delta",) and f.generator.isolates == ("steering_actuator",)
    assert parity_filter(car, isolates=[None]).generator.isolates == (None,)
    with pytest.raises(ParameterError, match="once"):
        parity_filter(car, name="a", names=["b"])
    lpv, unc = varrier_lateral_lpv(), [varrier_uncertainty()]
    rp = robust_lpv_parity(lpv, unc, 3, kappa=0.1, rho_max=0.2, rho_nominal=0.048, method="adjugate",
                           names=["ay"], isolates=["lateral_acceleration_sensor"])
    assert rp.names == ("ay",) and rp.isolates == ("lateral_acceleration_sensor",)
    from fdikit.simulate import simulate

    tr = simulate(lpv.at(0.05), duration=0.2, u=lambda t: [0.0], x0=[0.0, 0.0])
    r = rp.residuals(tr, np.full(len(tr), 0.05))
    assert r.names == ("ay",) and r.isolates == ("lateral_acceleration_sensor",)
    r = lpv_parity_residuals(lpv, tr, np.full(len(tr), 0.05), 3, W2=np.ones(6), isolates=[None])
    assert r.isolates == (None,)


def _constant_trace(model, u0, y0, n=60):
    t = np.arange(n) * model.dt
    return Trace(t, np.tile(u0, (n, 1)), np.tile(y0, (n, 1)), model.controls, model.outputs)


def test_designs_on_a_model_with_an_operating_point_give_zero_residual_on_u0_y0():
    base = single_track_lpv()(70 / 3.6)
    u0, y0 = np.array([0.02]), np.array([0.15, 0.4, -0.05])  # absolute steering, yaw rate, lane errors
    m = base.with_operating_point(u0=u0, y0=y0)
    tr = _constant_trace(m, u0, y0)
    # each generator subtracts u0, y0 exactly once: the deviations are zero up to the rounding of u − u0, y − y0
    # (≤ eps |u0|, eps |y0|), which the stable filter amplifies by at most its gain; zero here is exact in practice
    # and the bound below is that rounding times the filter's l1 gain bound Σ‖C Aᵏ B‖ + ‖D‖ over the run
    for design in (kalman(m, 1e-3, 1e-2), parity_filter(m, "steering_actuator"), parity_design(m, 2)):
        g = design.generator
        assert g.operating_point is not None
        gain = np.linalg.norm(g.D, 2) + sum(np.linalg.norm(g.C @ np.linalg.matrix_power(g.A, k) @ g.B, 2)
                                             for k in range(len(tr)))
        tol = 4 * np.finfo(float).eps * np.linalg.norm(np.r_[u0, y0]) * gain
        r = g.run(tr).r
        assert np.nanmax(np.abs(r)) <= tol
        # the same signals read as deviations (no operating point) do give a residual: the test can fail
        bare = type(g)(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, g.dt, g.isolates)
        assert np.nanmax(np.abs(bare.run(tr).r)) > 1e3 * tol
    # label_generator keeps an operating point the generator already has and adds none for a model without one
    g = kalman(m, 1e-3, 1e-2).generator
    assert label_generator(g, base).operating_point is g.operating_point
    assert kalman(base, 1e-3, 1e-2).generator.operating_point is None
