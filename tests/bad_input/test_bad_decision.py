"""Bad-input battery: residual evaluators (fdikit.decision).

Names checked against the fit (issue 12 item 5), in ``run`` and in ``step(names=)``; bad arguments of the
constructors and of ``fit``; residual samples that are not numbers.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from harness import case, check, ids

from fdikit.decision import (
    BnnEvaluator,
    CusumEvaluator,
    GaussianMlEvaluator,
    GlrEvaluator,
    MhsprtEvaluator,
    SprtEvaluator,
    ThresholdEvaluator,
)
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals


def _res(r, names=("a", "b"), isolates=("fa", "fb")):
    r = np.asarray(r, float)
    return Residuals(np.arange(len(r)) * 0.01, r, names, isolates)


@cache
def healthy():
    return _res(np.random.default_rng(0).standard_normal((2000, 2)))


def renamed(names, isolates=None):
    h = healthy()
    cols = {"a": 0, "b": 1}
    r = np.column_stack([h.r[:, cols.get(n, 0)] for n in names])
    return _res(r, names, isolates or tuple(f"f{n}" for n in names))


@cache
def fitted(kind):
    h = healthy()
    if kind == "threshold":
        return ThresholdEvaluator().fit(h, false_alarm_prob=1e-3)
    if kind == "cusum":
        return CusumEvaluator().fit(h, arl0=1e4, shift=1.0)
    if kind == "glr":
        return GlrEvaluator(window=10).fit(h, false_alarm_prob=1e-3)
    if kind == "sprt":
        return SprtEvaluator(shift=1.0).fit(h)
    rng = np.random.default_rng(1)
    faulty = [_res(rng.standard_normal((300, 2)) * 0.5 + [a, -a]) for a in (1.0, 2.0, 4.0)]
    if kind == "mhsprt":
        return MhsprtEvaluator().fit({"none": h, "fa": faulty})
    data = {"none": [h], "fa": [faulty[1]], "fb": [_res(rng.standard_normal((300, 2)) * 0.5 + [0.0, 3.0])]}
    if kind == "gaussian_ml":
        return GaussianMlEvaluator(inputs="raw").fit(data)
    if kind == "bnn":
        return BnnEvaluator(inputs="raw", max_iter=2, rm_steps=0).fit(data)
    raise AssertionError(kind)


KINDS = ("threshold", "cusum", "glr", "sprt", "mhsprt", "gaussian_ml", "bnn")

CASES = []
for _k in KINDS:
    CASES += [
        case(f"{_k}-run-reordered", lambda k=_k: fitted(k).run(renamed(("b", "a"))), DataError, "reordered", "'a'"),
        case(f"{_k}-run-missing", lambda k=_k: fitted(k).run(renamed(("a",))), DataError, "missing", "'b'"),
        case(f"{_k}-run-renamed", lambda k=_k: fitted(k).run(renamed(("a", "c"))), DataError, "missing", "extra",
             "'c'"),
        case(f"{_k}-run-array", lambda k=_k: fitted(k).run(np.zeros((10, 2))), DataError, "residuals", "ndarray"),
        case(f"{_k}-step-reordered", lambda k=_k: fitted(k).step([0.0, 0.0], names=("b", "a")), DataError,
             "reordered"),
        case(f"{_k}-step-strings", lambda k=_k: fitted(k).step(["x", "y"]), DataError, "numbers"),
    ]

CASES += [
    case("step-names-count", lambda: fitted("threshold").step([0.0, 0.0], names=("a",)), DataError, "names"),
    case("step-mapping-extra", lambda: fitted("cusum").step({"a": 0.0, "b": 0.0, "c": 1.0}), DataError, "extra",
         "'c'"),
    case("threshold-persistence", lambda: ThresholdEvaluator(persistence=(3, 2)), ParameterError, "persistence"),
    case("threshold-negative", lambda: ThresholdEvaluator(thresholds=[-1.0]), ParameterError, "thresholds",
         "positive"),
    case("threshold-alpha-2", lambda: ThresholdEvaluator().fit(healthy(), false_alarm_prob=2.0), ParameterError,
         "false-alarm", "(0, 1)"),
    case("threshold-method", lambda: ThresholdEvaluator().fit(healthy(), false_alarm_prob=1e-3, method="magic"),
         ParameterError, "method", "magic"),
    case("threshold-fit-array", lambda: ThresholdEvaluator().fit(np.zeros((100, 2)), false_alarm_prob=1e-3),
         DataError, "residuals"),
    case("threshold-unfitted", lambda: ThresholdEvaluator().run(healthy()), ParameterError, "fit()"),
    case("threshold-both-targets",
         lambda: ThresholdEvaluator().fit(healthy(), false_alarm_prob=1e-3, false_alarms_per_hour=1.0),
         ParameterError, "exactly one"),
    case("cusum-restart", lambda: CusumEvaluator(restart="sometimes"), ParameterError, "restart", "sometimes"),
    case("cusum-hold", lambda: CusumEvaluator(hold=-1), ParameterError, "hold"),
    case("glr-window-0", lambda: GlrEvaluator(window=0), ParameterError, "window"),
    case("glr-window-str", lambda: GlrEvaluator(window="ten"), ParameterError, "window"),
    case("sprt-alpha", lambda: SprtEvaluator(shift=1.0, alpha=2.0), ParameterError, "alpha"),
    case("bnn-threshold", lambda: BnnEvaluator(threshold=2.0), ParameterError, "threshold"),
    case("bnn-inputs", lambda: BnnEvaluator(inputs="loud"), ParameterError, "inputs", "loud"),
    case("gaussian-inputs", lambda: GaussianMlEvaluator(inputs="loud"), ParameterError, "inputs", "loud"),
    case("mhsprt-unfitted", lambda: MhsprtEvaluator().run(healthy()), ParameterError, "densities"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
