"""The declared interfaces (docs/ARCHITECTURE.md, "interfaces"): every design result is a
:class:`fdikit.protocols.DesignResult`, every evaluator a :class:`fdikit.protocols.Evaluator`.

Designs: ``internal_form()`` is exactly ``generator.internal_form(model)`` with the model the design was
made for (same matrices, same signal names); ``report()`` is a dict.  Designs without an LTI internal
form (time-varying, parameter-scheduled, made on a DAE) raise a DesignError that says why.
Evaluators: batch ``run`` equals online ``step`` sample by sample, ``reset`` then a replay gives the same
decisions, and fitting again on the same data gives the same evaluator.
"""

from __future__ import annotations

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.decision import (
    BnnEvaluator,
    CusumEvaluator,
    GaussianMlEvaluator,
    GlrEvaluator,
    MhsprtEvaluator,
    NarendraEvaluator,
    SprtEvaluator,
    ThresholdEvaluator,
    Whitened,
)
from fdikit.errors import DesignError
from fdikit.plants.f16xl import F16XL_DRYDEN_GAIN, f16xl_gust, f16xl_longitudinal
from fdikit.plants.white_speyer import white_speyer
from fdikit.protocols import DesignResult, Evaluator
from fdikit.residuals import Residuals


# ----------------------------------------------------------------------------------------------- designs
def _ws_sensors() -> FaultModel:
    """White–Speyer plant with a control and the two sensor faults (Beard–Jones, UIO, observers)."""
    m = white_speyer("stable-zero")
    m = FaultModel(m.A, m.C, Bu=np.ones((3, 1)), controls=("u",), states=m.states, outputs=m.outputs)
    return m.with_sensor_faults(["y1", "y2"])


def _observer():
    from fdikit.design.observers.full_order import observer

    m = _ws_sensors()
    return observer(m, [-2.0, -3.0, -4.0]), m


def _kalman():
    from fdikit.design.observers.full_order import kalman

    m = _ws_sensors().discretize(0.1)
    return kalman(m, 0.1, 0.01 * np.eye(2)), m


def _beard_jones():
    from fdikit.design.observers.beard_jones import beard_jones

    rng = np.random.default_rng(4)
    m = FaultModel(rng.standard_normal((4, 4)), rng.standard_normal((3, 4)), Bu=rng.standard_normal((4, 1)),
                   Bf=rng.standard_normal((4, 2)), faults=("f0", "f1"))
    return beard_jones(m, ["f0", "f1"], {"f0": [-1.5], "f1": [-2.5]}, [-3.0, -4.0]), m


def _restricted_diagonal():
    from fdikit.design.observers.beard_jones import restricted_diagonal

    rng = np.random.default_rng(7)
    m = FaultModel(rng.standard_normal((5, 5)), rng.standard_normal((4, 5)), Bu=rng.standard_normal((5, 1)),
                   Bf=rng.standard_normal((5, 3)), faults=("f0", "f1", "f2"))
    return restricted_diagonal(m, ["f0", "f1", "f2"], poles=-np.arange(1.0, 6.0)), m


def _uio():
    from fdikit.design.observers.uio import uio

    m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bu=[[1.0], [0.0], [1.0]], controls=("u",))
    m = m.with_sensor_faults(["y0", "y1", "y2"])
    return uio(m, "y2_sensor", nuisance="others", poles=[-4.0, -5.0, -6.0]), m


def _hinf():
    from fdikit.design.observers.hinf import hinf_detection_filter

    m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    return hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5), m


def _enhancement():
    from fdikit.design.observers.hinf import enhancement_direction

    d, m = _hinf()
    return enhancement_direction(d, "y_Az_sensor"), m


def _single_game():
    from fdikit.design.game.single_fault import single_fault_game_filter

    m = white_speyer("stable-zero")
    return single_fault_game_filter(m, "f1", ["f2"], gamma=1e-6, Q=0.002, M=0.05), m


def _game_bank():
    from fdikit.design.game.single_fault import game_filter_bank

    m = white_speyer("stable-extra-zero")
    return game_filter_bank(m, ["f1", "f2"], Q=1e-3, M=0.05), m


def _game():
    from fdikit.design.game.multi_fault import game_filter

    m = white_speyer("stable-extra-zero")
    return game_filter(m, ["f1", "f2"], M=0.05, Q={"f1": 1e-3, "f2": 2e-3}, K=0.1, N=1.0), m


def _dgtfdf():
    from fdikit.design.game.discrete import dgtfdf
    from fdikit.design.game.discrete_setup import discrete_game_setup

    m = white_speyer().discretize(0.01)
    st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-2, Vbar=1e-2 / 0.01, Q=1e-3, M=5.0, P0=1e-2, steps=50)
    return dgtfdf(st), m


def _dgtmfdf():
    from fdikit.design.game.discrete import dgtmfdf
    from fdikit.design.game.discrete_setup import discrete_game_setup

    rng = np.random.default_rng(0)
    A = rng.standard_normal((3, 3))
    m = FaultModel(0.9 * A / np.abs(np.linalg.eigvals(A)).max(), rng.standard_normal((2, 3)),
                   Bf=rng.standard_normal((3, 2)), faults=["f1", "f2"], dt=1.0)
    st = discrete_game_setup(m, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, P0=1.0, steps=20)
    return dgtmfdf(st, method="fixed-point", max_radius=0.9999), m


def _goh():
    from fdikit.design.game.reduced_order import goh_filter
    from fdikit.fault_maps import resolve_faults

    m = f16xl_longitudinal()
    faults = resolve_faults(m, ["y_theta_sensor", "elevon_actuator"]) | {"gust": m.Bd}
    return goh_filter(m, faults, V=1.0, Q=0.5), m


def _polynomial_parity():
    from fdikit.design.parity.polynomial import parity_filter
    from fdikit.plants.single_track import single_track_lpv

    m = single_track_lpv()(70 / 3.6)
    return parity_filter(m), m


def _state_space_parity():
    from fdikit.design.parity.state_space import parity_design

    rng = np.random.default_rng(2)
    m = FaultModel(0.5 * np.eye(3) + 0.1 * rng.standard_normal((3, 3)), rng.standard_normal((2, 3)),
                   Bu=rng.standard_normal((3, 1)), dt=0.1)
    return parity_design(m, 2), m


def _efdsyn():
    from fdikit.design.nullspace import efdsyn

    m = _ws_sensors()
    return efdsyn(m, targets="y1_sensor", nuisance="y2_sensor", sdeg=-2.0), m


def _efdisyn():
    from fdikit.design.nullspace import efdisyn

    m = _ws_sensors()
    return efdisyn(m, np.eye(2), sdeg=-2.0), m


def _afdsyn_plant():
    # Gf = (s+1)/(s+2), Gw = 1/(s+2) on one output (test_afdsyn.jl's non-standard case)
    return FaultModel([[-2.0]], [[1.0]], Bf=[[-1.0]], Df=[[1.0]], Bw=[[1.0]], faults=["f"], noise=["w"])


def _afdsyn():
    from fdikit.design.nullspace import afdsyn

    m = _afdsyn_plant()
    return afdsyn(m, sdeg=-3.0), m


def _afdisyn():
    from fdikit.design.nullspace import afdisyn

    m = _afdsyn_plant()
    return afdisyn(m, np.eye(1), sdeg=-3.0), m


LTI_DESIGNS = {
    "ObserverDesign(observer)": _observer, "ObserverDesign(kalman)": _kalman, "BeardJonesDesign": _beard_jones,
    "RestrictedDiagonalDesign": _restricted_diagonal, "UIODesign": _uio, "HinfDesign": _hinf,
    "Enhancement": _enhancement, "SingleFaultGameDesign": _single_game, "GameBankDesign": _game_bank,
    "GameDesign": _game, "DiscreteGtfdfDesign": _dgtfdf, "DiscreteGtmfdfDesign": _dgtmfdf,
    "GohFilterDesign": _goh, "PolynomialParityDesign": _polynomial_parity, "ParityDesign": _state_space_parity,
    "NullspaceDesign": _efdsyn, "NullspaceBankDesign": _efdisyn,
    "ApproximateDesign": _afdsyn, "ApproximateBankDesign": _afdisyn,
}


def _same_model(a: FaultModel, b: FaultModel) -> None:
    for attr in ("A", "B", "C", "D"):
        np.testing.assert_array_equal(getattr(a, attr), getattr(b, attr), err_msg=attr)
    assert (a.states, a.outputs, a.inputs, a.dt) == (b.states, b.outputs, b.inputs, b.dt)


@pytest.mark.parametrize("name", list(LTI_DESIGNS))
def test_design_result_protocol_and_internal_form(name):
    design, model = LTI_DESIGNS[name]()
    assert isinstance(design, DesignResult)
    _same_model(design.internal_form(), design.generator.internal_form(model))
    report = design.report()
    assert isinstance(report, dict) and report
    assert report is not design.report()  # a fresh dict each call


def _ltv_game():
    from fdikit.design.game.time_varying import ltv_game_filter
    from fdikit.ltv import LTVModel

    model = LTVModel.from_lti(white_speyer("stable-zero"), ["f1", "f2"])
    return ltv_game_filter(model, "f1", ["f2"], np.linspace(0.0, 10.0, 11), gamma=1e-6, M=0.05, Q=1e-3, V=1.0)


def _scheduled():
    from fdikit.design.parity.scheduled import scheduled_parity_filter
    from fdikit.plants.single_track import single_track_lpv

    return scheduled_parity_filter(single_track_lpv(), 70 / 3.6)


def _robust():
    from fdikit.design.parity.robust import robust_lpv_parity
    from fdikit.plants.varrier_lateral import varrier_lateral_lpv, varrier_uncertainty

    return robust_lpv_parity(varrier_lateral_lpv(), [varrier_uncertainty()], 3, kappa=0.1, rho_max=0.2,
                             rho_nominal=0.048)


def _parity_on_dae():
    from fdikit.dae import dae_form
    from fdikit.design.parity.polynomial import parity_filter
    from fdikit.plants.single_track import single_track_lpv

    return parity_filter(dae_form(single_track_lpv()(70 / 3.6)))


#: Designs without an LTI internal form, and the reason their error gives.
NO_INTERNAL_FORM = {
    "LTVGameDesign": (_ltv_game, "time-varying"),
    "ScheduledResidualGenerator": (_scheduled, "schedule"),
    "RobustParityDesign": (_robust, "scheduled on the LPV parameter"),
    "PolynomialParityDesign(on a DAE)": (_parity_on_dae, "DAEModel"),
}


@pytest.mark.parametrize("name", list(NO_INTERNAL_FORM))
def test_designs_without_an_internal_form_say_why(name):
    build, why = NO_INTERNAL_FORM[name]
    design = build()
    assert isinstance(design, DesignResult)
    assert design.generator is not None
    with pytest.raises(DesignError, match=why):
        design.internal_form()
    assert isinstance(design.report(), dict) and design.report()


def test_a_design_made_by_hand_has_no_model_to_join():
    from dataclasses import replace

    design, model = _observer()
    bare = replace(design, model=None)
    with pytest.raises(DesignError, match="holds no model"):
        bare.internal_form()
    _same_model(bare.generator.internal_form(model), design.internal_form())


# -------------------------------------------------------------------------------------------- evaluators
def _res(r, valid=None):
    r = np.asarray(r, float)
    return Residuals(np.arange(len(r)) * 0.01, r, ("a", "b"), ("fa", "fb"), valid)


def _train(seed=0):
    rng = np.random.default_rng(seed)
    h = _res(rng.standard_normal((1500, 2)))
    fa = [_res(rng.standard_normal((200, 2)) * 0.5 + [s, 0.0]) for s in (1.5, 3.0)]
    fb = [_res(rng.standard_normal((200, 2)) * 0.5 + [0.0, s]) for s in (1.5, 3.0)]
    return h, fa, fb


def _fit(kind, ev=None):
    """Fit (or refit ``ev``) on the same training data; returns the evaluator."""
    h, fa, fb = _train()
    labelled = {"none": [h], "fa": fa, "fb": fb}
    new, fit = {
        "threshold": (lambda: ThresholdEvaluator(persistence=(2, 3)), lambda e: e.fit(h, false_alarm_prob=1e-2)),
        "cusum": (lambda: CusumEvaluator(hold=2), lambda e: e.fit(h, arl0=500.0, shift=1.0)),
        "glr": (lambda: GlrEvaluator(window=8), lambda e: e.fit(h, false_alarm_prob=1e-2)),
        "sprt": (lambda: SprtEvaluator(shift=1.0, hold=1), lambda e: e.fit(h)),
        "mhsprt": (lambda: MhsprtEvaluator(), lambda e: e.fit({"none": h, "fa": fa, "fb": fb})),
        "gaussian_ml": (lambda: GaussianMlEvaluator(inputs="raw"), lambda e: e.fit(labelled)),
        "bnn": (lambda: BnnEvaluator(inputs="raw", max_iter=8, rm_steps=0), lambda e: e.fit(labelled)),
        "whitened_cusum": (lambda: Whitened(CusumEvaluator(hold=2), order=2),
                           lambda e: e.fit(h, arl0=500.0, shift=1.0)),
        "narendra": (lambda: NarendraEvaluator(alpha=1.0, beta=0.5, gamma=0.5),
                     lambda e: e.fit(h, false_alarm_prob=2e-2)),
    }[kind]
    return fit(new() if ev is None else ev)


def _series():
    rng = np.random.default_rng(11)
    r = rng.standard_normal((160, 2))
    r[60:110] += [2.5, 0.0]
    r[110:] += [0.0, 2.5]
    r[rng.random((160, 2)) < 0.03] = np.nan
    return _res(r, np.isfinite(r).all(axis=1))


def _stepped(ev, res):
    out = [ev.step(res.r[k], valid=bool(res.valid[k]), names=res.names) for k in range(len(res))]
    return (np.array([s.alarm for s in out], bool), np.array([s.fired for s in out], bool),
            np.array([s.fault for s in out]), np.array([s.valid for s in out], bool))


def _assert_same(d, stepped, what):
    alarm, fired, fault, valid = stepped
    np.testing.assert_array_equal(d.alarm, alarm, err_msg=what)
    np.testing.assert_array_equal(d.fired, fired.reshape(d.fired.shape), err_msg=what)
    np.testing.assert_array_equal(d.isolated, fault, err_msg=what)
    np.testing.assert_array_equal(d.valid, valid, err_msg=what)


@pytest.mark.parametrize("kind", ["threshold", "cusum", "glr", "sprt", "mhsprt", "gaussian_ml", "bnn",
                                  "whitened_cusum", "narendra"])
def test_evaluator_protocol_batch_online_refit_reset(kind):
    ev = _fit(kind)
    assert isinstance(ev, Evaluator)
    res = _series()
    d = ev.run(res)
    assert d.alarm.any()  # the series has faults: the comparison is not between two empty alarm sets
    ev.reset()
    _assert_same(d, _stepped(ev, res), "run vs step")
    ev.reset()
    _assert_same(d, _stepped(ev, res), "reset then replay")
    ev.step(res.r[70])  # leave some online state behind; the refit must discard it
    _fit(kind, ev)
    _assert_same(ev.run(res), _stepped(ev, res), "refit: run vs step")
    _assert_same(ev.run(res), (d.alarm, d.fired, d.isolated, d.valid), "refit vs first fit")
