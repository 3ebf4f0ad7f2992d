"""Bad-input battery: residual generators (fdikit.residuals, fdikit.design.parity.scheduled).

Traces whose signals or sample time do not match the generator (issue 12 item 5), bad options of
``run``/``online`` (initial state, residual covariance, recovery tolerance), samples that are not
numbers, malformed generators and residual series.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from harness import case, check, ids

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.residuals import ResidualGenerator, Residuals, stack_generators
from fdikit.trace import Trace

DT = 0.1


def gen(dt=DT, residuals=("r1", "r2")):
    A = np.array([[0.5, 0.1], [0.0, 0.3]])
    B = np.array([[0.1, 0.2, 0.0], [0.0, 0.1, 0.3]])
    C = -np.eye(2)
    D = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    return ResidualGenerator(A, B, C, D, ("u",), ("y1", "y2"), residuals, dt)


def trace(controls=("u",), outputs=("y1", "y2"), dt=DT, n=50):
    rng = np.random.default_rng(0)
    t = np.arange(n) * dt
    return Trace(t=t, u=rng.standard_normal((n, len(controls))), y=rng.standard_normal((n, len(outputs))),
                 controls=controls, outputs=outputs)


@cache
def scheduled():
    from fdikit.design.parity.scheduled import scheduled_parity_filter
    from fdikit.plants.single_track import single_track_lpv

    return scheduled_parity_filter(single_track_lpv(), 70 / 3.6)


def sched_trace(drop=None, dt=None, n=20):
    g = scheduled()
    outputs = tuple(o for o in g.outputs if o != drop) + ("speed",)
    rng = np.random.default_rng(1)
    d = dt or g.dt
    y = rng.standard_normal((n, len(outputs))) * 0.01
    y[:, -1] = 70 / 3.6
    return Trace(t=np.arange(n) * d, u=rng.standard_normal((n, len(g.controls))) * 0.01, y=y,
                 controls=g.controls, outputs=outputs)


CASES = [
    # ----------------------------------------------------------------------- run: traces that do not match
    case("run-not-a-trace", lambda: gen().run({"u": [0.0]}), DataError, "trace", "dict"),
    case("run-missing-output", lambda: gen().run(trace(outputs=("y1",))), DataError, "missing outputs", "'y2'"),
    case("run-missing-control", lambda: gen().run(trace(controls=("v",))), DataError, "missing controls", "'u'",
         "'v'"),
    case("run-control-as-output", lambda: gen().run(trace(controls=("w",), outputs=("y1", "y2", "u"))), DataError,
         "missing controls", "found as outputs"),
    case("run-renamed-output", lambda: gen().run(trace(outputs=("y1", "y3"))), DataError, "'y2'", "'y3'"),
    case("run-dt-mismatch", lambda: gen().run(trace(dt=0.05)), DataError, "dt=0.05", "resample"),
    case("run-continuous-one-sample", lambda: gen(dt=None).run(trace(n=1)), DataError, "2 samples"),
    # ----------------------------------------------------------------------- run: bad options
    case("run-x0-length", lambda: gen().run(trace(), x0=[0.0]), ParameterError, "x0", "2 states"),
    case("run-x0-nan", lambda: gen().run(trace(), x0=[np.nan, 0.0]), ParameterError, "x0", "finite"),
    case("run-x0-string", lambda: gen().run(trace(), x0="zero"), ParameterError, "x0"),
    case("run-cov-shape", lambda: gen().run(trace(), residual_cov=np.eye(3)), ParameterError, "residual_cov", "2x2"),
    case("run-cov-nan", lambda: gen().run(trace(), residual_cov=[[np.nan, 0], [0, 1]]), ParameterError,
         "residual_cov", "finite"),
    case("run-cov-asym", lambda: gen().run(trace(), residual_cov=[[1.0, 0.5], [0.0, 1.0]]), ParameterError,
         "residual_cov", "symmetric"),
    case("run-cov-zero-diag", lambda: gen().run(trace(), residual_cov=[[0.0, 0.0], [0.0, 1.0]]), ParameterError,
         "residual_cov", "positive"),
    case("run-cov-string", lambda: gen().run(trace(), residual_cov="diag"), ParameterError, "residual_cov"),
    case("run-tol-zero", lambda: gen().run(trace(), recovery_tol=0.0), ParameterError, "recovery_tol"),
    case("run-tol-negative", lambda: gen().run(trace(), recovery_tol=-0.1), ParameterError, "recovery_tol"),
    case("run-tol-above-one", lambda: gen().run(trace(), recovery_tol=2.0), ParameterError, "recovery_tol", "(0, 1]"),
    case("run-tol-nan", lambda: gen().run(trace(), recovery_tol=np.nan), ParameterError, "recovery_tol"),
    case("run-tol-string", lambda: gen().run(trace(), recovery_tol="0.1"), ParameterError, "recovery_tol"),
    # ----------------------------------------------------------------------- online
    case("online-continuous-no-dt", lambda: gen(dt=None).online(), ModelError, "dt="),
    case("online-dt-zero", lambda: gen(dt=None).online(dt=0.0), ParameterError, "dt", "positive"),
    case("online-dt-negative", lambda: gen(dt=None).online(dt=-0.1), ParameterError, "dt"),
    case("online-dt-string", lambda: gen(dt=None).online(dt="0.1"), ParameterError, "dt"),
    case("online-dt-mismatch", lambda: gen().online(dt=0.05), DataError, "dt=0.05", "resample"),
    case("online-x0", lambda: gen().online(x0=[1.0, 2.0, 3.0]), ParameterError, "x0"),
    case("online-tol", lambda: gen().online(recovery_tol=0), ParameterError, "recovery_tol"),
    case("step-length", lambda: gen().online().step([0.0], [0.0]), DataError, "outputs", "'y2'"),
    case("step-strings", lambda: gen().online().step(["a"], [0.0, 0.0]), DataError, "numbers"),
    case("step-none", lambda: gen().online().step(None, [0.0, 0.0]), DataError, "controls"),
    case("step-map-missing", lambda: gen().online().step({"u": 0.0}, {"y1": 0.0}), DataError, "missing", "'y2'"),
    case("step-map-extra", lambda: gen().online().step({"u": 0.0, "v": 1.0}, [0.0, 0.0]), DataError, "extra",
         "'v'"),
    case("stepper-run-not-trace", lambda: gen().online().run([1, 2, 3]), DataError, "trace", "list"),
    case("stepper-run-missing", lambda: gen().online().run(trace(outputs=("y1",))), DataError, "missing outputs",
         "'y2'"),
    case("stepper-run-dt", lambda: gen().online().run(trace(dt=0.2)), DataError, "dt=0.2"),
    case("stepper-reset-x0", lambda: gen().online().reset(x0=[np.inf, 0.0]), ParameterError, "x0"),
    # ----------------------------------------------------------------------- malformed generators, containers
    case("gen-B-shape", lambda: ResidualGenerator(np.eye(2), np.zeros((2, 2)), np.eye(2), np.zeros((2, 3)), ("u",),
                                                  ("y1", "y2"), ("r1", "r2"), DT), ModelError, "B", "shape"),
    case("gen-A-nan", lambda: ResidualGenerator([[np.nan]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), DT),
         ModelError, "A", "non-finite"),
    case("gen-dt-zero", lambda: ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), 0.0),
         ModelError, "dt"),
    case("gen-isolates", lambda: ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), DT,
                                                   ("f", "g")), ModelError, "isolates"),
    case("discretize-discrete", lambda: gen().discretize(0.1), ModelError, "already discrete"),
    case("stack-empty", lambda: stack_generators([]), ModelError, "at least one"),
    case("stack-not-generator", lambda: stack_generators([gen(), "g"]), ModelError, "item 1", "str"),
    case("stack-dup-names", lambda: stack_generators([gen(), gen()]), ModelError, "'r1'", "unique"),
    case("stack-dt", lambda: stack_generators([gen(), gen(dt=0.2, residuals=("s1", "s2"))]), ModelError, "dt"),
    case("residuals-shape", lambda: Residuals(np.arange(3.0), np.zeros((3, 2)), ("a",), ()), DataError, "shape"),
    case("residuals-isolates", lambda: Residuals(np.arange(3.0), np.zeros((3, 1)), ("a",), ("f", "g")), DataError,
         "isolates"),
    case("residuals-valid-length", lambda: Residuals(np.arange(3.0), np.zeros((3, 1)), ("a",), (), [True]),
         DataError, "valid", "3 samples"),
    # ----------------------------------------------------------------------- scheduled parity filter
    case("sched-not-trace", lambda: scheduled().run("trace.parquet"), DataError, "trace", "str"),
    case("sched-missing-output", lambda: scheduled().run(sched_trace(drop="yaw_rate")), DataError, "missing outputs",
         "'yaw_rate'"),
    case("sched-dt", lambda: scheduled().run(sched_trace(dt=0.05)), DataError, "dt=0.05", "resample"),
    case("sched-schedule-length", lambda: scheduled().run(sched_trace(), schedule=np.ones(3)), DataError, "schedule",
         "20"),
    case("sched-schedule-strings", lambda: scheduled().run(sched_trace(), schedule=["fast"] * 20), DataError,
         "schedule", "numbers"),
    case("sched-schedule-name", lambda: scheduled().run(sched_trace(), schedule="velocity"), DataError,
         "'velocity'"),
    case("sched-tol", lambda: scheduled().run(sched_trace(), recovery_tol=5), ParameterError, "recovery_tol"),
    case("sched-online-tol", lambda: scheduled().online(recovery_tol="x"), ParameterError, "recovery_tol"),
    case("sched-step-sizes", lambda: scheduled().online().step([0.0], [0.0], 19.4), DataError, "outputs"),
    case("sched-step-strings", lambda: scheduled().online().step(["a"], [0.0, 0.0, 0.0], 19.4), DataError, "numbers"),
    case("sched-stepper-run-missing", lambda: scheduled().online().run(sched_trace(drop="yaw_rate")), DataError,
         "missing outputs"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
