"""Faults are named by fault name (docs/ARCHITECTURE.md, "faults in APIs" and "targeted / ignored faults").

``<output>_sensor`` (``:magnitude`` / ``:rate``), ``<control>_actuator`` or a fault input of the model by its own
name; a bare signal name is refused with a ParameterError that gives the fault name.  ``targets=`` are the faults a
design detects, ``nuisance=`` those it must ignore: ``()`` (the default) none, ``'others'`` every other fault input.
"""

from __future__ import annotations

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit import fault_maps as fmaps
from fdikit.analysis.gains import fault_to_residual_gain
from fdikit.analysis.geometry import fdi_report
from fdikit.design.game.multi_fault import game_filter
from fdikit.design.game.reduced_order import goh_detector
from fdikit.design.game.setup import game_problem
from fdikit.design.game.single_fault import game_filter_bank, single_fault_game_filter
from fdikit.design.game.time_varying import ltv_game_filter
from fdikit.design.observers.beard_jones import beard_jones, restricted_diagonal
from fdikit.design.observers.detection_gain import detection_gain_family
from fdikit.design.observers.full_order import observer_generator
from fdikit.design.observers.uio import uio, uio_bank
from fdikit.design.parity.polynomial import parity_filter
from fdikit.errors import ModelError, ParameterError
from fdikit.ltv import LTVModel
from fdikit.plants.f16xl import f16xl_gust
from fdikit.plants.path_longitudinal import path_longitudinal_7
from fdikit.plants.single_track import single_track, single_track_lpv
from fdikit.plants.white_speyer import white_speyer


def _plant() -> FaultModel:
    """3 states measured directly (C = I), one control ``u``; no fault inputs."""
    return FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bu=[[1.0], [1.0], [0.0]], controls=["u"],
                      outputs=["y0", "y1", "y2"])


def _faulty() -> FaultModel:
    """_plant() with sensor faults on y0 and y2 and the actuator fault of u as fault inputs."""
    return _plant().with_sensor_faults(["y0", "y2"]).with_actuator_faults(["u"])


OUTPUT_MSG = "'y0' is an output; its sensor fault is 'y0_sensor'"
CONTROL_MSG = "'u' is a control; its actuator fault is 'u_actuator'"


# ---------------------------------------------------------------------- resolve_faults
def test_resolve_faults_takes_fault_names():
    m = _plant()
    maps = fmaps.resolve_faults(m, ["y0_sensor", "y1_sensor:magnitude", "u_actuator"])
    assert list(maps) == ["y0_sensor", "y1_sensor", "u_actuator"]
    np.testing.assert_array_equal(maps["y0_sensor"], fmaps.sensor_fault_map(m, "y0"))
    np.testing.assert_array_equal(maps["y1_sensor"], fmaps.sensor_fault_map(m, "y1", "magnitude"))
    np.testing.assert_array_equal(maps["u_actuator"], m.Bu)
    # one name, and the fault inputs of a model by their own names (pure sensor fault -> its sensor map)
    assert list(fmaps.resolve_faults(m, "y2_sensor:rate")) == ["y2_sensor"]
    fm = _faulty()
    np.testing.assert_array_equal(fmaps.resolve_faults(fm, ["y0_sensor"])["y0_sensor"], fmaps.sensor_fault_map(m, "y0"))
    np.testing.assert_array_equal(fmaps.resolve_faults(fm, ["u_actuator"])["u_actuator"], m.Bu)
    # explicit maps keep working, under their own keys
    F = np.array([[1.0], [0.0], [0.0]])
    np.testing.assert_array_equal(fmaps.resolve_faults(m, {"my_fault": F})["my_fault"], F)


@pytest.mark.parametrize("model", [_plant(), _faulty()], ids=["plain", "with-fault-inputs"])
@pytest.mark.parametrize("name, message", [
    ("y0", OUTPUT_MSG),
    ("u", CONTROL_MSG),
    ("y0:magnitude", "its sensor fault is 'y0_sensor:magnitude'"),
])
def test_signal_names_are_refused_with_the_fault_name(model, name, message):
    with pytest.raises(ParameterError, match=message):
        fmaps.resolve_faults(model, [name])
    with pytest.raises(ParameterError, match=message):
        fmaps.resolve_fault(model, name)


def test_unknown_names_and_bad_suffixes():
    m = _plant()
    with pytest.raises(ModelError, match="'zz' is not a fault of the model.*'y0_sensor'.*'u_actuator'"):
        fmaps.resolve_faults(m, ["zz"])
    with pytest.raises(ModelError, match="sensor faults only"):
        fmaps.resolve_fault(m, "u_actuator:magnitude")
    with pytest.raises(ParameterError, match="suffix"):
        fmaps.resolve_fault(m, "y0_sensor:bias")
    with pytest.raises(ModelError, match="not a fault input of the model; add it with model.with_sensor_faults"):
        fmaps.check_fault_inputs(m, ["y1_sensor"])


def test_resolve_nuisance_convention():
    m = _faulty()
    assert fmaps.resolve_nuisance(m, ()) == {}
    others = fmaps.resolve_nuisance(m, "others", ["y0_sensor"])
    explicit = fmaps.resolve_faults(m, ["y2_sensor", "u_actuator"])
    assert list(others) == list(explicit)
    for k in explicit:
        np.testing.assert_array_equal(others[k], explicit[k])
    with pytest.raises(ParameterError, match="'others'"):
        fmaps.resolve_nuisance(m, None)


# ---------------------------------------------------------------------- designs refuse signal names
def test_beard_jones_and_restricted_diagonal_refuse_signal_names():
    m = _plant()
    with pytest.raises(ParameterError, match=OUTPUT_MSG):
        beard_jones(m, ["y0", "y2_sensor"], {"y0_sensor": [-4.0, -5.0], "y2_sensor": [-6.0]})
    with pytest.raises(ParameterError, match=CONTROL_MSG):
        restricted_diagonal(m, ["u", "y0_sensor"], poles=[-4.0, -5.0, -6.0])
    d = beard_jones(m, ["y0_sensor:magnitude", "y2_sensor:magnitude"], {"y0_sensor": [-4.0], "y2_sensor": [-6.0]},
                    [-5.0])
    assert set(d.generator.isolates) == {"y0_sensor", "y2_sensor"}


def test_uio_refuses_signal_names():
    m = _faulty()
    with pytest.raises(ParameterError, match="'y2' is an output; its sensor fault is 'y2_sensor'"):
        uio(m, "y2")
    with pytest.raises(ParameterError, match=OUTPUT_MSG):
        uio(m, "y2_sensor", nuisance=["y0"])
    with pytest.raises(ParameterError, match=CONTROL_MSG):
        uio_bank(m, ["y2_sensor", "u"])
    with pytest.raises(ParameterError, match="one target"):
        uio(m, ["y0_sensor", "y2_sensor"])
    with pytest.raises(ParameterError, match="'others'"):
        uio(m, "y2_sensor", nuisance=None)


def test_game_filters_refuse_signal_names():
    ws = white_speyer("stable-extra-zero")
    with pytest.raises(ParameterError, match="'y1' is an output; its sensor fault is 'y1_sensor'"):
        game_filter(ws, ["y1", "f2"])
    with pytest.raises(ParameterError, match="'y2_sensor'"):
        single_fault_game_filter(ws, "f1", ["y2"])
    with pytest.raises(ParameterError, match="'y1_sensor'"):
        game_filter_bank(ws, ["f1", "y1"])
    with pytest.raises(ParameterError, match="'air_mass' is an output; its sensor fault is 'air_mass_sensor'"):
        goh_detector(path_longitudinal_7(), "air_mass", ["engine_speed_sensor"])


def test_reports_and_other_designs_refuse_signal_names():
    m = _faulty()
    with pytest.raises(ParameterError, match=OUTPUT_MSG):
        fdi_report(m, ["y0", "u_actuator"])
    gen = observer_generator(m, 2.0 * np.eye(3))
    with pytest.raises(ParameterError, match=OUTPUT_MSG):
        fault_to_residual_gain(gen, m, [0.1, 1.0], faults=["y0"])
    with pytest.raises(ParameterError, match=CONTROL_MSG):
        fault_to_residual_gain(gen, m, [0.1, 1.0], faults={"both": ["y0_sensor", "u"]})
    with pytest.raises(ParameterError, match="'y_Az' is an output; its sensor fault is 'y_Az_sensor'"):
        detection_gain_family(f16xl_gust(), ["y_Az", "elevon_actuator"])
    with pytest.raises(ParameterError, match="'steering' is a control; its actuator fault is 'steering_actuator'"):
        parity_filter(single_track_lpv()(70 / 3.6), "steering")
    with pytest.raises(ParameterError, match="'steering_actuator'"):
        LTVModel.from_family(lambda t: single_track(10.0 + t), ["steering"])
    with pytest.raises(ParameterError, match="'y1_sensor'"):
        LTVModel.from_lti(white_speyer(), ["y1"])
    ltv = LTVModel.from_lti(white_speyer(), ["f1", "y1_sensor"])
    assert set(ltv.faults) == {"f1", "y1_sensor"}


# ---------------------------------------------------------------------- nuisance: () none, 'others' all other faults
def test_uio_nuisance_others_equals_the_explicit_list_and_default_is_none():
    m = _faulty()
    poles = [-4.0, -5.0, -6.0]
    others = uio(m, "y2_sensor", nuisance="others", poles=poles)
    explicit = uio(m, "y2_sensor", nuisance=["y0_sensor", "u_actuator"], poles=poles)
    assert others.decoupled == explicit.decoupled == ("y0_sensor", "u_actuator")
    for a, b in zip((others.generator.A, others.generator.B, others.generator.C, others.generator.D),
                    (explicit.generator.A, explicit.generator.B, explicit.generator.C, explicit.generator.D)):
        np.testing.assert_array_equal(a, b)
    none = uio(m, "y2_sensor", poles=poles)
    assert none.decoupled == () and len(none.generator.residuals) == 3
    assert set(none.decoupling) == {"u"}  # only the controls are reported: no fault is decoupled
    # the bank: 'others' adds every fault input that is not a target to each member's decoupled set
    bank = uio_bank(m, ["y2_sensor"], nuisance="others", poles=poles)
    assert [d.decoupled for d in bank] == [("y0_sensor", "u_actuator")]
    assert [d.decoupled for d in uio_bank(m, ["y0_sensor", "y2_sensor"], poles=poles)] == [("y2_sensor",),
                                                                                            ("y0_sensor",)]


def test_game_nuisance_others_equals_the_explicit_list_and_default_is_none():
    ws = white_speyer("stable-extra-zero")
    prob = game_problem(ws, ["f1"])
    assert prob.complementary["f1"].shape == (3, 0) and prob.nuisance_names == ()
    assert game_problem(ws, ["f1"], "others").nuisance_names == ("f2",)
    kw = dict(gamma=1e-6, V=1.0, Q=1e-3, M=0.05)
    a = single_fault_game_filter(ws, "f1", "others", **kw)
    b = single_fault_game_filter(ws, "f1", ["f2"], **kw)
    np.testing.assert_array_equal(a.gain, b.gain)
    bank_a = game_filter_bank(ws, ["f1"], "others", **kw)
    bank_b = game_filter_bank(ws, ["f1"], ["f2"], **kw)
    np.testing.assert_array_equal(bank_a.filters["f1"].gain, bank_b.filters["f1"].gain)


def test_ltv_nuisance_others_equals_the_explicit_list():
    m = LTVModel.from_lti(white_speyer("stable-extra-zero"), ["f1", "f2"])
    t = np.linspace(0, 4, 5)
    a = ltv_game_filter(m, "f1", "others", t, gamma=1e-6, M=0.05, Q=1e-3)
    b = ltv_game_filter(m, "f1", ["f2"], t, gamma=1e-6, M=0.05, Q=1e-3)
    np.testing.assert_array_equal(a.gains, b.gains)
    with pytest.raises(ParameterError, match="'y1' is an output; its sensor fault is 'y1_sensor'"):
        ltv_game_filter(LTVModel.from_lti(white_speyer(), ["f1", "y1_sensor"]), "f1", ["y1"], t, gamma=1e-6)
