"""nuisance= on the parity designs, and the warning of a residual that responds to an unlisted fault (issue 16)."""

import warnings

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.analysis import fault_to_residual_gain
from fdikit.design.parity import parity_design, parity_filter, stacked_fault_map
from fdikit.design.parity.polynomial import RESPONSE_RTOL
from fdikit.errors import DesignError, FdiWarning, ParameterError
from fdikit.lpv import stacked_matrices
from fdikit.plants.single_track import single_track_lpv

CAR_SENSORS = ("yaw_rate", "lateral_error", "heading_error", "lateral_acceleration")


def _roundoff_bound(design, model, freqs):
    """Round-off bound of the internal form's frequency response, per frequency: solving (zI − A) x = B_f in floating
    point has relative error <= n·eps·κ(zI − A) (backward-stable solve), so |r| computed for an exactly decoupled
    fault is at most that times ‖C‖‖x‖; a factor 10 covers the product with C and the sum with D_f."""
    G = design.generator.internal_form(model)
    out = []
    for w in freqs:
        M = np.exp(1j * w * model.dt) * np.eye(G.n) - G.A
        x = np.linalg.solve(M, G.Bf)
        out.append(10 * G.n * np.finfo(float).eps * np.linalg.cond(M) * np.linalg.norm(G.C, 2) * np.linalg.norm(x, 2))
    return np.array(out)


def test_parity_filter_warns_about_the_yaw_rate_bias_it_would_call_a_steering_fault():
    """The user report: a yaw-rate sensor bias shows in the steering residual; the design now says so."""
    m = single_track_lpv()(70 / 3.6).with_sensor_faults(["yaw_rate"])
    with pytest.warns(FdiWarning, match=r"'yaw_rate_sensor'.*nuisance=\['yaw_rate_sensor'\]"):
        d = parity_filter(m, "steering_actuator")
    assert d.responses["yaw_rate_sensor"] > RESPONSE_RTOL and d.nuisance == ()
    # independently: the yaw-rate bias reaches the residual at every frequency (internal form, python-side solve)
    freqs = np.array([0.5, 2.0, 10.0])
    g = fault_to_residual_gain(d.generator, m, freqs)
    yaw = g.gains[:, list(g.faults).index("yaw_rate_sensor"), 0]
    assert np.all(yaw > 1e3 * _roundoff_bound(d, m, freqs))
    # with these three sensors the steering fault cannot be told from a yaw-rate bias: refused with the ranks
    with pytest.raises(DesignError, match=r"not isolable from nuisance \['yaw_rate_sensor'\].*normal ranks"):
        parity_filter(m, "steering_actuator", nuisance="yaw_rate_sensor")


def test_parity_filter_nuisance_decouples_the_yaw_rate_bias_and_keeps_the_steering_fault():
    m = single_track_lpv(outputs=CAR_SENSORS)(70 / 3.6).with_sensor_faults(["yaw_rate"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", FdiWarning)  # nothing is unlisted now
        d = parity_filter(m, "steering_actuator", nuisance="others")
    assert d.nuisance == ("yaw_rate_sensor",) and d.generator.isolates == ("steering_actuator",)
    freqs = np.array([0.5, 2.0, 10.0, 50.0])
    g = fault_to_residual_gain(d.generator, m, freqs)
    gains = {f: g.gains[:, j, 0] for j, f in enumerate(g.faults)}
    bound = _roundoff_bound(d, m, freqs)
    assert np.all(gains["yaw_rate_sensor"] <= bound)
    # the steering fault is still seen: its gain is |G(z)| of (2.7), computed from the polynomials N F / d
    np.testing.assert_allclose(gains["steering_actuator"], np.abs(d.fault_gain(np.exp(1j * freqs * m.dt))),
                               rtol=0, atol=bound.max() * 10)
    assert abs(d.dc_gain - 1.0) <= 1e-9 and d.responses["yaw_rate_sensor"] <= RESPONSE_RTOL


def test_parity_filter_nuisance_arguments_are_checked():
    m = single_track_lpv(outputs=CAR_SENSORS)(70 / 3.6).with_sensor_faults(["yaw_rate"])
    with pytest.raises(ParameterError, match="'yaw_rate_sensor'"):
        parity_filter(m, "steering_actuator", nuisance=["yaw_rate"])
    with pytest.raises(ParameterError, match="target"):
        parity_filter(m, "steering_actuator", nuisance=["steering_actuator"])
    with pytest.raises(DesignError, match="not a fault column"):
        parity_filter(m, "steering_actuator", nuisance=["lateral_error_sensor"])
    with pytest.raises(ParameterError, match="None"):
        parity_filter(m, "steering_actuator", nuisance=None)


def _three_sensor_model():
    A = np.array([[0.9, 0.1], [0.0, 0.8]])
    C = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    m = FaultModel(A, C, Bu=[[0.0], [1.0]], dt=0.1)
    return m.with_sensor_faults(["y0", "y1"]).with_actuator_faults(["u0"])


def test_stacked_fault_map_matches_the_stacked_matrices_of_fdikit_lpv():
    m, s = _three_sensor_model(), 2
    H = stacked_matrices(m, s).H_fs  # columns sample by sample: [f(k); f(k+1); f(k+2)], k_f faults each
    kf = len(m.faults)
    for j, f in enumerate(m.faults):
        jj = m.index("f", f)[0]
        np.testing.assert_allclose(stacked_fault_map(m, m.Bf[:, [jj]], m.Df[:, [jj]], s), H[:, j::kf], rtol=0,
                                   atol=1e-15 * np.abs(H).max())


def test_parity_design_nuisance_decouples_and_reports_unlisted_faults():
    m = _three_sensor_model()
    # decoupled from y0's sensor only: the actuator fault also drives the residual and is neither listed
    with pytest.warns(FdiWarning, match="'u0_actuator'"):
        d = parity_design(m, 1, targets="y1_sensor", nuisance=["y0_sensor"])
    assert d.generator.isolates == ("y1_sensor",) * len(d.generator.residuals)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FdiWarning)
        d = parity_design(m, 1, targets="y1_sensor", nuisance="others")
    assert d.nuisance == ("y0_sensor", "u0_actuator") and d.report()["targets"] == ("y1_sensor",)
    # an FIR filter: its fault gains are finite at every frequency; ‖W‖‖H_f‖ scales the round-off of W H_f
    freqs = np.array([0.0, 1.0, 5.0, 20.0])
    g = fault_to_residual_gain(d.generator, m, freqs)
    gains = {f: g.gains[:, j, :].max(axis=1) for j, f in enumerate(g.faults)}
    scale = np.linalg.norm(d.W, 2) * max(np.linalg.norm(stacked_fault_map(m, m.Bf, m.Df, d.s), 2), 1.0)
    tol = 100 * d.W.size * np.finfo(float).eps * scale  # rounding of the sums in Wᵀ H_f and of the null basis
    assert np.all(gains["y0_sensor"] <= tol) and np.all(gains["u0_actuator"] <= tol)
    assert np.all(gains["y1_sensor"] > 1e6 * tol)  # the target is detected at every frequency
    # a pure detector (no targets, no isolates) is not warned about: it is meant to see everything
    with warnings.catch_warnings():
        warnings.simplefilter("error", FdiWarning)
        parity_design(m, 1)


def test_parity_design_refuses_impossible_decoupling_with_the_numbers():
    m = _three_sensor_model()
    with pytest.raises(DesignError, match=r"q = 1 parity directions at horizon s=0 .* rank 1 = q"):
        parity_design(m, 0, nuisance=["y0_sensor", "y1_sensor"])
    twin = m.replace(Bf=np.c_[m.Bf, m.Bu], Df=np.c_[m.Df, m.Du], faults=[*m.faults, "twin"])
    with pytest.raises(DesignError, match=r"does not see target\(s\) \['twin'\]"):
        parity_design(twin, 1, targets="twin", nuisance=["u0_actuator"])
    with pytest.raises(ParameterError, match="both targets and nuisance"):
        parity_design(m, 1, targets="y0_sensor", nuisance=["y0_sensor"])
    with pytest.raises(ParameterError, match="'y0_sensor'"):
        parity_design(m, 1, nuisance=["y0"])
