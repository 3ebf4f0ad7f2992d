"""Fault-to-residual gains, structure matrices and FDI geometry reports.

Oracles: closed-form transfer functions of a diagonal plant with a diagonal observer gain (each
residual sees one actuator and one sensor fault), continuous and discrete; the PATH group-4 geometry
(Douglas et al. 1996, §4.1–4.2) and Murray (2012) Example 2 for the reports.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fdikit import FaultModel, ModelError
from fdikit import fault_maps as fm
from fdikit.analysis.gains import GainTable, default_freqs, fault_to_residual_gain, structure_matrix
from fdikit.analysis.geometry import fdi_report
from fdikit.design import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.fault_maps import resolve_fault
from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14

a = np.array([-1.0, -2.0, -3.0])
L_C = np.array([4.0, 5.0, 6.0])  # continuous observer gains: poles a − l = −5, −7, −9
L_D = np.array([0.3, 0.4, 0.5])
DT = 0.05


def _diagonal_model() -> FaultModel:
    m = FaultModel(A=np.diag(a), C=np.eye(3), Bu=np.eye(3), outputs=["y0", "y1", "y2"], controls=["u0", "u1", "u2"])
    return m.with_actuator_faults(["u0", "u1", "u2"]).with_sensor_faults(["y0", "y1", "y2"])


W = np.logspace(-2, 2, 41)


def test_gain_continuous_matches_closed_form():
    """Observer e' = (a − l) e + f_act − l f_sen, r = e + f_sen (per channel, decoupled):
    actuator → own residual 1/|jω − p|, sensor → own residual |jω − a| / |jω − p|, p = a − l; zero elsewhere."""
    m = _diagonal_model()
    g = observer_generator(m, np.diag(L_C))
    t = fault_to_residual_gain(g, m, W)
    assert isinstance(t, GainTable)
    assert t.gains.shape == (W.size, 6, 3)
    assert t.groups == ("y0", "y1", "y2") and t.members == (("y0",), ("y1",), ("y2",))
    assert t.faults == m.faults and t.dt is None
    jw = 1j * W
    for i in range(3):
        p = a[i] - L_C[i]
        np.testing.assert_allclose(t.gains[:, i, i], 1 / np.abs(jw - p), rtol=1e-12)
        np.testing.assert_allclose(t.gains[:, 3 + i, i], np.abs(jw - a[i]) / np.abs(jw - p), rtol=1e-12)
        off = [j for j in range(3) if j != i]
        assert np.all(t.gains[:, i, off] == 0) and np.all(t.gains[:, 3 + i, off] == 0)
    df = t.to_pandas()
    assert list(df.index) == list(m.faults) and list(df.columns) == ["y0", "y1", "y2"]
    np.testing.assert_allclose(df.loc["u0_actuator", "y0"], 20 * np.log10(1 / np.abs(1j * W[0] - (a[0] - L_C[0]))))
    assert df.loc["u0_actuator", "y1"] == -np.inf
    np.testing.assert_allclose(t.to_pandas(db=False).to_numpy(), t.peak())
    long = t.to_pandas(over_frequency=True)
    assert long.shape == (W.size * 6, 3)
    np.testing.assert_allclose(long.loc[(W[3], "y1_sensor"), "y1"], 20 * np.log10(t.gains[3, 4, 1]))


def test_gain_discrete_matches_closed_form():
    """ZOH model per channel: x⁺ = e^{a dt} x + b f, b = (e^{a dt} − 1)/a; predictor observer pole φ − l;
    actuator → own residual |b / (z − φ + l)| at z = e^{jω dt}."""
    md = _diagonal_model().discretize(DT)
    g = observer_generator(md, np.diag(L_D))
    w = np.linspace(0.1, np.pi / DT, 30)
    t = fault_to_residual_gain(g, md, w)
    assert t.dt == DT
    z = np.exp(1j * w * DT)
    for i in range(3):
        phi = np.exp(a[i] * DT)
        b = (phi - 1) / a[i]
        np.testing.assert_allclose(t.gains[:, i, i], np.abs(b / (z - phi + L_D[i])), rtol=1e-10)
        np.testing.assert_allclose(t.gains[:, 3 + i, i], np.abs((z - phi) / (z - phi + L_D[i])), rtol=1e-10)
    S = structure_matrix(g, md)
    np.testing.assert_array_equal(S.to_numpy(), np.vstack([np.eye(3, dtype=bool)] * 2))
    with pytest.raises(ParameterError, match="Nyquist"):
        fault_to_residual_gain(g, md, [np.pi / DT * 1.5])


def test_continuous_generator_on_discrete_model_is_rejected_and_discrete_generator_discretises_the_model():
    m = _diagonal_model()
    gd = observer_generator(m.discretize(DT), np.diag(L_D))
    t = fault_to_residual_gain(gd, m, [0.1, 1.0])  # the continuous model is ZOH-discretised at the generator's dt
    assert t.dt == DT
    with pytest.raises(ModelError):
        fault_to_residual_gain(observer_generator(m, np.diag(L_C)), m.discretize(DT), [1.0])


def test_structure_matrix_diagonal_and_coupled():
    m = _diagonal_model()
    S = structure_matrix(observer_generator(m, np.diag(L_C)), m)
    assert S.dtypes.eq(bool).all()
    np.testing.assert_array_equal(S.to_numpy(), np.vstack([np.eye(3, dtype=bool)] * 2))
    # a gain L[0, 1] puts −2 at (0, 1) of A − LC: e1 drives e0, so residual y0 also sees what drives e1
    # (u1_actuator, y1_sensor); nothing else changes
    L = np.diag(L_C)
    L[0, 1] = 2.0
    S = structure_matrix(observer_generator(m, L), m)
    expect = np.vstack([np.eye(3, dtype=bool)] * 2)
    expect[1, 0] = expect[4, 0] = True
    np.testing.assert_array_equal(S.to_numpy(), expect)
    # the rule is relative to each residual's strongest response (about −160 dB here), with an absolute floor
    tiny = np.diag(L_C)
    tiny[0, 1] = 1e-7
    g = observer_generator(m, tiny)
    assert not structure_matrix(g, m).loc["y1_sensor", "y0"]
    assert structure_matrix(g, m, rtol=1e-9).loc["y1_sensor", "y0"]
    assert not structure_matrix(g, m, rtol=1e-9, atol=1e-6).loc["y1_sensor", "y0"]


def test_residual_groups_follow_isolates_and_multi_column_faults():
    m = _diagonal_model()
    g = observer_generator(m, np.diag(L_C))
    # residuals y0, y1 isolate the first two actuator faults; y2 only detects
    g = dataclasses.replace(g, isolates=("u0_actuator", "u0_actuator", None))
    t = fault_to_residual_gain(g, m, W)
    assert t.groups == ("u0_actuator", "y2") and t.members == (("y0", "y1"), ("y2",))
    # group gain = σ_max over the group's rows = norm of the column restricted to them
    full = fault_to_residual_gain(observer_generator(m, np.diag(L_C)), m, W)
    np.testing.assert_allclose(t.gains[:, 3, 0], full.gains[:, 3, 0], rtol=1e-12)  # y0_sensor only reaches y0
    S = structure_matrix(g, m)
    assert S.loc["u1_actuator", "u0_actuator"] and S.loc["u2_actuator", "y2"]
    assert not S.loc["u2_actuator", "u0_actuator"]
    # a mapping of labels to fault inputs: a 2-column fault, σ_max of the 1 x 2 block over residual y2 ...
    t2 = fault_to_residual_gain(g, m, W, faults={"act12": ["u1_actuator", "u2_actuator"], "s0": "y0_sensor"})
    assert t2.faults == ("act12", "s0")
    np.testing.assert_allclose(t2.gains[:, 0, 1], full.gains[:, 2, 2], rtol=1e-12)
    np.testing.assert_allclose(t2.gains[:, 0, 0], full.gains[:, 1, 1], rtol=1e-12)
    with pytest.raises(ModelError):
        fault_to_residual_gain(g, m, W, faults=["nope"])
    with pytest.raises(ParameterError, match="non-negative"):
        fault_to_residual_gain(g, m, [-1.0])


def test_plot_writes_the_structure_map(tmp_path):
    m = _diagonal_model()
    t = fault_to_residual_gain(observer_generator(m, np.diag(L_C)), m, W)
    path = tmp_path / "structure.png"
    fig = t.plot(path)
    assert path.exists() and path.stat().st_size > 1000
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ax = fig.axes[0]
    assert [tl.get_text() for tl in ax.get_yticklabels()] == list(m.faults)
    t.plot(tmp_path / "structure.svg")
    assert (tmp_path / "structure.svg").exists()


def test_default_freqs():
    assert default_freqs(None)[0] == pytest.approx(1e-2) and default_freqs(None)[-1] == pytest.approx(1e3)
    assert default_freqs(0.1)[-1] == pytest.approx(0.999 * np.pi / 0.1)


# ---------------------------------------------------------------------- FDI report
M14 = path_vehicle_14()
GROUP_4 = ["throttle_actuator", "brake_actuator", "steering_actuator", "air_mass_sensor:magnitude"]


def test_fdi_report_group_4():
    """Group 4 of the report's table (§1.4.2): ν = (2, 2, 1, 1), ν₀ = 8.  On the reconstructed data with the
    ±0.00 entries at 0 the triple (throttle, brake, air-mass magnitude) has dependent output images (see
    tests/test_linalg.py::test_r_geo_4_group_4_reconstructed_data), so the report must say so."""
    rep = fdi_report(M14, GROUP_4)
    assert [f.nu for f in rep.faults] == [2, 2, 1, 1]
    assert [f.caisa_dim for f in rep.faults] == [2, 2, 1, 1]
    assert [f.output_dim for f in rep.faults] == [1, 1, 1, 1]
    assert [f.kind for f in rep.faults] == ["actuator", "actuator", "actuator", "sensor:magnitude"]
    assert all(f.zeros.size == 0 for f in rep.faults)
    assert rep.nu_total == 6 and rep.nu_0 == 8
    assert not rep.output_separable and rep.separation < 1e-12
    assert rep.inseparable_pairs == ()
    assert rep.dependent_sets == (("throttle_actuator", "brake_actuator", "air_mass_sensor:magnitude"),)
    assert rep.mutually_detectable is None  # the joint system is not left invertible
    assert any("dependent" in s and "another filter" in s for s in rep.advice)
    df = rep.to_pandas()
    assert list(df["nu"]) == [2, 2, 1, 1] and list(df["dim_CT"]) == [1, 1, 1, 1]
    assert df.attrs["nu_total"] == 6
    text = str(rep)
    for word in ("throttle_actuator", "air_mass_sensor:magnitude", "Σν = 6", "ν₀ = 8", "dependent"):
        assert word in text


def test_fdi_report_flags_throttle_and_two_dimensional_air_mass():
    rep = fdi_report(M14, ["throttle_actuator", "brake_actuator", "steering_actuator", "air_mass_sensor"])
    assert ("throttle_actuator", "air_mass_sensor") in rep.inseparable_pairs
    assert ("brake_actuator", "air_mass_sensor") in rep.inseparable_pairs
    am = rep.faults[3]
    assert am.kind == "sensor" and am.F.shape == (14, 2) and am.nu == 4 and am.output_dim == 2
    np.testing.assert_allclose(np.sort(am.zeros.real), [-90.91, -1.25], rtol=1e-12)
    advice = " ".join(rep.advice)
    assert "'air_mass_sensor:magnitude'" in advice and "magnitude direction A F¹" in advice
    assert "another filter" in advice


def test_fdi_report_midpoint_group_4_is_clean():
    """With the ±0.00 entries at their rounding midpoints and the brake taken 2-D (report §4.1) the set is
    separable and mutually detectable: no advice."""
    m = path_vehicle_14("midpoint")
    Fb = fm.actuator_fault_map(m, "brake")
    maps = {
        "throttle": fm.actuator_fault_map(m, "throttle"),
        "brake": np.hstack([Fb, m.A @ Fb]),
        "steering": fm.actuator_fault_map(m, "steering"),
        "air_mass:magnitude": fm.sensor_fault_map(m, "air_mass", "magnitude"),
    }
    rep = fdi_report(m, maps)
    assert [f.nu for f in rep.faults] == [2, 2, 1, 1]
    assert all(f.kind == "matrix" for f in rep.faults)
    assert rep.output_separable and 0.1 < rep.separation <= 1
    assert rep.mutually_detectable is True and rep.extra_zeros.size == 0
    assert rep.advice == ()


def test_fdi_report_too_many_faults_for_one_filter():
    m = path_vehicle_12("midpoint")
    rep = fdi_report(m, [f"{o}_sensor" for o in m.outputs[:7]])
    assert rep.nu_total == 14 and rep.nu_0 == -2
    assert any("Σν = 14 > n = 12" in s and "split" in s for s in rep.advice)
    rep = fdi_report(m, ["engine_speed_sensor", "accel_y_sensor", "accel_z_sensor", "pitch_rate_sensor"])  # group 1
    assert rep.output_separable and rep.mutually_detectable and rep.nu_0 == 4 and rep.advice == ()


EX2_A = np.array([[0.0, 3.0, 4.0], [1.0, 2.0, 3.0], [0.0, 2.0, 5.0]])
EX2_C = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
EX2_F1 = np.array([1.0, -0.5, 0.5])


@pytest.mark.parametrize(
    "f2, md, extra, unstable",
    [
        ([3.0, 1.0, 0.0], True, [], False),
        ([5.0, 1.0, 1.0], False, [-1.5], False),
        ([0.0, 0.0, 1.0], False, [2.0], True),
    ],
)
def test_fdi_report_murray_example2(f2, md, extra, unstable):
    """Murray (2012) §6.2.1, 6.2.3, 6.2.4: extra zeros −1.5 (stable) and +2 (unstable) of the joint system."""
    m = FaultModel(A=EX2_A, C=EX2_C)
    rep = fdi_report(m, {"F1": EX2_F1, "F2": np.array(f2)})
    assert rep.output_separable
    assert rep.mutually_detectable is md
    np.testing.assert_allclose(rep.extra_zeros.real, extra, atol=1e-10)
    text = " ".join(rep.advice)
    if md:
        assert rep.advice == ()
        np.testing.assert_allclose(rep.faults[1].zeros.real, [-3.0], atol=1e-10)
        assert rep.faults[1].nu == 2 and rep.nu_total == 3 and rep.nu_0 == 0
    else:
        assert "not mutually detectable" in text and "restricted-diagonal" in text and "unknown-input" in text
        assert ("no stable BJ filter" in text) is unstable


def test_fdi_report_inseparable_actuators_and_undetectable_fault():
    m = FaultModel(A=-np.eye(3), C=np.eye(2, 3), Bu=np.array([[1.0, 2.0], [0.0, 0.0], [0.0, 0.0]]),
                   controls=["a", "b"])
    rep = fdi_report(m, ["a_actuator", "b_actuator"])
    assert rep.inseparable_pairs == (("a_actuator", "b_actuator"),)
    assert any("move one of them" in s for s in rep.advice)
    rep = fdi_report(m, {"hidden": np.array([0.0, 0.0, 1.0])})
    assert rep.faults[0].output_dim == 0
    assert any("cannot be detected" in s for s in rep.advice)


def test_resolve_fault_names():
    m = path_vehicle_14().with_sensor_faults(["air_mass"]).with_actuator_faults(["throttle"])
    F, kind = resolve_fault(m, "air_mass_sensor")
    np.testing.assert_array_equal(F, fm.sensor_fault_map(m, "air_mass"))
    assert kind == "sensor"
    F, kind = resolve_fault(m, "air_mass_sensor:magnitude")
    np.testing.assert_array_equal(F, fm.sensor_fault_map(m, "air_mass")[:, 1:])
    assert kind == "sensor:magnitude"
    assert resolve_fault(m, "air_mass_sensor:rate")[0].shape == (14, 1)
    # the same names on a model without the fault inputs: <output>_sensor and <control>_actuator still resolve
    plain = path_vehicle_14()
    np.testing.assert_array_equal(resolve_fault(plain, "air_mass_sensor")[0], fm.sensor_fault_map(m, "air_mass"))
    np.testing.assert_array_equal(resolve_fault(plain, "throttle_actuator")[0], m.Bu[:, [0]])
    F, kind = resolve_fault(m, "throttle_actuator")
    np.testing.assert_array_equal(F, m.Bu[:, [0]])
    assert kind == "fault input"
    with pytest.raises(ParameterError, match="'throttle' is a control; its actuator fault is 'throttle_actuator'"):
        resolve_fault(m, "throttle")
    with pytest.raises(ParameterError, match="'air_mass' is an output; its sensor fault is 'air_mass_sensor'"):
        resolve_fault(m, "air_mass")
    with pytest.raises(ModelError, match="not a fault of the model"):
        resolve_fault(m, "nope")
    with pytest.raises(ModelError, match="sensor faults only"):
        resolve_fault(m, "throttle_actuator:magnitude")
    with pytest.raises(ParameterError, match="suffix"):
        resolve_fault(m, "air_mass_sensor:bias")
    with pytest.raises(DesignError):  # 12-state steering has a feedthrough
        resolve_fault(path_vehicle_12("midpoint"), "steering_actuator")
    with pytest.raises(ModelError):
        fdi_report(m, {"bad": np.ones((3, 1))})
    with pytest.raises(ModelError):
        fdi_report(m, [])
