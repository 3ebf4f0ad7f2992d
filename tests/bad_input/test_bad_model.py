"""Bad input for the model layer: FaultModel, lti, linalg, analysis and fdi_report."""

from __future__ import annotations

import numpy as np
import pytest
from harness import case, check, ids

from fdikit import FaultModel
from fdikit.analysis.gains import default_freqs, fault_to_residual_gain, structure_matrix
from fdikit.analysis.geometry import fdi_report
from fdikit.design import kalman
from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.fault_maps import actuator_fault_map, resolve_fault, sensor_fault_map, sensor_fault_map_tv
from fdikit.linalg import (
    caisa,
    contains,
    detection_space,
    intersect,
    invariant_zeros,
    mutually_detectable,
    null,
    orth,
    output_separable,
    rank,
    span_sum,
)
from fdikit.lti import dlsim_blocked, lifted_matrices

A2 = [[-1.0, 1.0], [0.0, -2.0]]
C2 = np.eye(2)


def _m(**kw) -> FaultModel:
    args = dict(A=A2, C=C2, Bu=[[0.0], [1.0]], states=["x", "v"], outputs=["pos", "vel"], controls=["u"])
    args.update(kw)
    return FaultModel(**args)


def _mf() -> FaultModel:
    return _m().with_sensor_faults(["pos", "vel"])


def _gen():
    return kalman(_mf().discretize(0.1), Q=1e-4 * np.eye(2), R=1e-2 * np.eye(2)).generator


CASES = [
    # ------------------------------------------------------------------ FaultModel constructor
    case("A-string", lambda: FaultModel(A="abc", C=[[1.0]]), ModelError, "A", "number"),
    case("A-nan", lambda: FaultModel(A=[[np.nan]], C=[[1.0]]), ModelError, "A", "non-finite"),
    case("A-inf", lambda: FaultModel(A=[[1.0, np.inf], [0, 1]], C=C2), ModelError, "A", "non-finite"),
    case("A-not-square", lambda: FaultModel(A=[[1.0, 2.0]], C=[[1.0, 0.0]]), ModelError, "A", "square"),
    case("A-3d", lambda: FaultModel(A=np.zeros((2, 2, 2)), C=C2), ModelError, "A", "2-D"),
    case("A-ragged", lambda: FaultModel(A=[[1.0, 2.0], [3.0]], C=C2), ModelError, "A", "number"),
    case("A-complex", lambda: FaultModel(A=[[1j]], C=[[1.0]]), ModelError, "A", "real"),
    case("A-none", lambda: FaultModel(A=None, C=[[1.0]]), ModelError, "A", "required"),
    case("C-wrong-cols", lambda: FaultModel(A=A2, C=[[1.0, 0.0, 0.0]]), ModelError, "C", "columns"),
    case("C-nan", lambda: FaultModel(A=A2, C=[[np.nan, 0.0]]), ModelError, "C", "non-finite"),
    case("Bu-wrong-rows", lambda: FaultModel(A=A2, C=C2, Bu=[[1.0], [0.0], [0.0]]), ModelError, "Bu", "rows"),
    case("Du-wrong-rows", lambda: FaultModel(A=A2, C=C2, Bu=[[1.0], [0.0]], Du=[[0.0]]), ModelError, "Du", "rows"),
    case("Bf-Df-cols-mismatch", lambda: FaultModel(A=A2, C=C2, Bf=np.zeros((2, 1)), Df=np.zeros((2, 2))),
         ModelError, "Df", "columns"),
    case("Bw-string-entry", lambda: FaultModel(A=A2, C=C2, Bw=[["a"], ["b"]]), ModelError, "Bw", "number"),
    case("states-count", lambda: _m(states=["x"]), ModelError, "state", "1"),
    case("states-duplicate", lambda: _m(states=["x", "x"]), ModelError, "duplicate", "'x'"),
    case("outputs-single-string", lambda: _m(outputs="pos"), ModelError, "output", "single string"),
    case("outputs-empty-name", lambda: _m(outputs=["pos", ""]), ModelError, "output", "empty"),
    case("outputs-non-string", lambda: _m(outputs=["pos", 3]), ModelError, "output", "string"),
    case("controls-count", lambda: _m(controls=["u", "v"]), ModelError, "control", "2"),
    case("input-two-groups", lambda: _m(Bd=[[1.0], [0.0]], disturbances=["u"]), ModelError, "'u'", "two groups"),
    case("dt-zero", lambda: _m(dt=0), ModelError, "dt", "positive"),
    case("dt-negative", lambda: _m(dt=-0.1), ModelError, "dt", "positive"),
    case("dt-nan", lambda: _m(dt=float("nan")), ModelError, "dt", "positive"),
    case("dt-inf", lambda: _m(dt=float("inf")), ModelError, "dt", "positive"),
    case("dt-string", lambda: _m(dt="0.1s"), ModelError, "dt", "number"),
    case("dt-bool", lambda: _m(dt=True), ModelError, "dt", "number"),
    # ------------------------------------------------------------------ FaultModel methods
    case("replace-unknown", lambda: _m().replace(Bx=1), ModelError, "Bx"),
    case("index-unknown-kind", lambda: _m().index("inputs", ["u"]), ParameterError, "kind", "'inputs'"),
    case("index-unknown-name", lambda: _m().index("outputs", ["speed"]), ModelError, "'speed'", "output"),
    case("sensor-fault-unknown", lambda: _m().with_sensor_faults(["speed"]), ModelError, "'speed'", "output"),
    case("sensor-fault-twice", lambda: _m().with_sensor_faults(["pos"]).with_sensor_faults(["pos"]),
         ModelError, "pos_sensor", "duplicate"),
    case("sensor-fault-empty", lambda: _m().with_sensor_faults([]), ParameterError, "outputs", "empty"),
    case("actuator-fault-unknown", lambda: _m().with_actuator_faults(["brake"]), ModelError, "'brake'", "control"),
    case("add-faults-single-string", lambda: _m().add_faults("ab", np.zeros((2, 2))), ModelError, "fault", "string"),
    case("add-faults-shape", lambda: _m().add_faults(["a"], np.zeros((3, 1))), ModelError, "Bf", "rows"),
    case("submodel-unknown-output", lambda: _m().submodel(outputs=["speed"]), ModelError, "'speed'"),
    case("submodel-unknown-input", lambda: _m().submodel(inputs=["brake"]), ModelError, "brake"),
    case("discretize-zero", lambda: _m().discretize(0.0), ParameterError, "dt", "positive"),
    case("discretize-string", lambda: _m().discretize("0.1"), ParameterError, "dt", "number"),
    case("discretize-nan", lambda: _m().discretize(float("nan")), ParameterError, "dt", "positive"),
    case("discretize-method", lambda: _m().discretize(0.1, method="tustinn"), ParameterError, "method", "zoh"),
    case("discretize-twice", lambda: _m(dt=0.1).discretize(0.1), ModelError, "already discrete"),
    case("freqresp-nan", lambda: _m().freqresp([np.nan]), ParameterError, "omega", "finite"),
    case("freqresp-string", lambda: _m().freqresp("fast"), ParameterError, "omega", "number"),
    case("freqresp-group", lambda: _m().freqresp([1.0], group="x"), ParameterError, "group", "'x'"),
    case("from-control-not-ss", lambda: FaultModel.from_control("sys"), ModelError, "StateSpace"),
    case("from-control-unknown-fault", lambda: FaultModel.from_control(_m().to_control(), faults=["zz"]),
         ModelError, "zz"),
    # ------------------------------------------------------------------ lti
    case("dlsim-v-shape", lambda: dlsim_blocked(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)),
                                                np.ones((10, 3))), DataError, "v", "columns"),
    case("dlsim-v-nan", lambda: dlsim_blocked(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)),
                                              np.full((10, 1), np.nan)), DataError, "v", "finite"),
    case("dlsim-block-zero", lambda: dlsim_blocked(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)),
                                                   np.ones((10, 1)), block=0), ParameterError, "block", "positive"),
    case("dlsim-x0-size", lambda: dlsim_blocked(np.eye(2), np.ones((2, 1)), np.eye(2), np.zeros((2, 1)),
                                                np.ones((10, 1)), x0=[1.0, 2.0, 3.0]), ParameterError, "x0", "2"),
    case("dlsim-A-not-square", lambda: dlsim_blocked(np.ones((2, 3)), np.ones((2, 1)), np.eye(2),
                                                     np.zeros((2, 1)), np.ones((10, 1))),
         ParameterError, "A", "square"),
    case("lifted-M-negative", lambda: lifted_matrices(np.eye(2), np.ones((2, 1)), -3), ParameterError, "M", "integer"),
    case("lifted-M-string", lambda: lifted_matrices(np.eye(2), np.ones((2, 1)), "4"), ParameterError, "M", "integer"),
    # ------------------------------------------------------------------ linalg
    case("rank-string", lambda: rank("abc"), ParameterError, "M", "number"),
    case("rank-nan", lambda: rank([[np.nan, 1.0]]), ParameterError, "M", "non-finite"),
    case("rank-rtol-negative", lambda: rank(np.eye(2), rtol=-1.0), ParameterError, "rtol", "non-negative"),
    case("orth-inf", lambda: orth([[np.inf, 1.0]]), ParameterError, "M", "non-finite"),
    case("null-3d", lambda: null(np.zeros((2, 2, 2))), ParameterError, "M", "2-D"),
    case("span-sum-rows", lambda: span_sum(np.eye(2), np.eye(3)), ParameterError, "rows"),
    case("contains-size", lambda: contains(np.eye(3), [1.0, 0.0]), ParameterError, "x", "3"),
    case("sensor-map-unknown", lambda: sensor_fault_map(_m(), "speed"), ModelError, "'speed'"),
    case("sensor-map-direction", lambda: sensor_fault_map(_m(), "pos", direction="up"), ParameterError,
         "direction", "'up'"),
    case("sensor-map-not-model", lambda: sensor_fault_map("model", "pos"), ParameterError, "model", "FaultModel"),
    case("actuator-map-unknown", lambda: actuator_fault_map(_m(), "brake"), ModelError, "'brake'"),
    case("resolve-fault-unknown", lambda: resolve_fault(_m(), "nope"), ModelError, "'nope'"),
    case("resolve-fault-suffix", lambda: resolve_fault(_m(), "pos:speed"), ParameterError, "suffix", "'speed'"),
    case("caisa-shape", lambda: caisa(np.eye(2), np.eye(2), np.ones((3, 1))), ParameterError, "F", "rows"),
    case("caisa-nan", lambda: caisa(np.eye(2), np.eye(2), [[np.nan], [0.0]]), ParameterError, "F", "non-finite"),
    case("zeros-A-not-square", lambda: invariant_zeros(np.ones((2, 3)), np.eye(2), np.ones((2, 1))),
         ParameterError, "A", "square"),
    case("detection-space-C-cols", lambda: detection_space(np.eye(2), np.ones((1, 3)), np.ones((2, 1))),
         ParameterError, "C", "columns"),
    case("mutually-detectable-shape", lambda: mutually_detectable(np.eye(2), np.eye(2), [np.ones((3, 1))]),
         ParameterError, "fault", "rows"),
    case("intersect-rows", lambda: intersect(np.eye(2), np.eye(3)), ParameterError, "rows"),
    case("output-separable-shape", lambda: output_separable(np.eye(2), [np.ones((3, 1))]), ParameterError,
         "space", "rows"),
    case("sensor-map-tv-output", lambda: sensor_fault_map_tv(lambda t: np.eye(2), lambda t: np.eye(2), 5, 0.0),
         ParameterError, "output", "5"),
    case("sensor-map-tv-not-callable", lambda: sensor_fault_map_tv(np.eye(2), lambda t: np.eye(2), 0, 0.0),
         ParameterError, "A", "function of time"),
    case("index-names-not-strings", lambda: _m().index("outputs", [0]), ModelError, "0", "output"),
    case("to-control-after-bad-replace", lambda: _m().replace(C=np.ones((2, 3))), ModelError, "C", "columns"),
    # ------------------------------------------------------------------ analysis and fdi_report
    case("gain-freqs-negative", lambda: fault_to_residual_gain(_gen(), _mf().discretize(0.1), [-1.0]),
         ParameterError, "freqs", "non-negative"),
    case("gain-unknown-fault", lambda: fault_to_residual_gain(_gen(), _mf().discretize(0.1), [1.0], faults=["zz"]),
         ModelError, "zz"),
    case("gain-not-generator", lambda: fault_to_residual_gain("gen", _mf().discretize(0.1), [1.0]),
         ParameterError, "generator", "ResidualGenerator"),
    case("structure-rtol-negative", lambda: structure_matrix(_gen(), _mf().discretize(0.1), rtol=-1.0),
         ParameterError, "rtol", "non-negative"),
    case("structure-freqs-string", lambda: structure_matrix(_gen(), _mf().discretize(0.1), freqs="all"),
         ParameterError, "freqs", "number"),
    case("default-freqs-num-zero", lambda: default_freqs(0.1, num=0), ParameterError, "num", "positive"),
    case("default-freqs-dt-negative", lambda: default_freqs(-0.1), ParameterError, "dt", "positive"),
    case("fdi-report-unknown", lambda: fdi_report(_mf(), ["zz"]), ModelError, "zz"),
    case("fdi-report-empty", lambda: fdi_report(_mf(), []), ModelError, "at least one fault"),
    case("fdi-report-ztol", lambda: fdi_report(_mf(), ["pos_sensor"], ztol=-1.0), ParameterError, "ztol",
         "non-negative"),
    case("fdi-report-not-model", lambda: fdi_report(None, ["pos_sensor"]), ParameterError, "model", "FaultModel"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
