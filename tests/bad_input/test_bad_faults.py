"""Bad input to fault construction, fault scenarios and the fault-spec parser (fdikit.faults).

Every case must raise the named :mod:`fdikit.errors` class with a message that names the
offending argument (or spec) and the problem.
"""

from __future__ import annotations

import numpy as np
import pytest
from harness import case, check, ids

from fdikit.errors import DataError, ParameterError
from fdikit.fault_spec import format_fault, parse_fault
from fdikit.faults import (
    Bias,
    Drift,
    FaultScenario,
    Intermittent,
    LossOfEffectiveness,
    Noise,
    ScaleFactor,
    Stuck,
)

OUT, CTL = ("yaw_rate", "speed", "steer"), ("steer", "throttle")
T = np.arange(10) * 0.1

CASES = [
    # ---- fault sizes: finite real numbers
    case("bias-size-nan", lambda: Bias("speed", np.nan), ParameterError, "size", "finite"),
    case("bias-size-inf", lambda: Bias("speed", np.inf, onset=5), ParameterError, "size", "finite"),
    case("bias-size-neg-inf", lambda: Bias("speed", -np.inf), ParameterError, "size", "finite"),
    case("bias-size-string", lambda: Bias("speed", "abc"), ParameterError, "size", "number"),
    case("bias-size-numeric-string", lambda: Bias("speed", "0.1"), ParameterError, "size", "number"),
    case("bias-size-none", lambda: Bias("speed", None), ParameterError, "size", "number"),
    case("bias-size-list", lambda: Bias("speed", [1.0, 2.0]), ParameterError, "size", "number"),
    case("bias-size-bool", lambda: Bias("speed", True), ParameterError, "size", "number"),
    case("bias-size-complex", lambda: Bias("speed", 1 + 2j), ParameterError, "size", "number"),
    case("drift-rate-nan", lambda: Drift("speed", rate=np.nan), ParameterError, "rate", "finite"),
    case("drift-rate-inf", lambda: Drift("speed", rate=-np.inf), ParameterError, "rate", "finite"),
    case("drift-rate-string", lambda: Drift("speed", rate="fast"), ParameterError, "rate", "number"),
    case("stuck-value-nan", lambda: Stuck("steer", value=np.nan), ParameterError, "value", "finite"),
    case("stuck-value-inf", lambda: Stuck("steer", value=np.inf), ParameterError, "value", "finite"),
    case("stuck-value-string", lambda: Stuck("steer", value="x"), ParameterError, "value", "number"),
    case("loe-above-one", lambda: LossOfEffectiveness("throttle", loss=1.5), ParameterError, "loss", "[0, 1]"),
    case("loe-negative", lambda: LossOfEffectiveness("throttle", loss=-0.1), ParameterError, "loss", "[0, 1]"),
    case("loe-nan", lambda: LossOfEffectiveness("throttle", loss=np.nan), ParameterError, "loss", "finite"),
    case("scale-inf", lambda: ScaleFactor("speed", factor=np.inf), ParameterError, "factor", "finite"),
    case("scale-nan", lambda: ScaleFactor("speed", factor=np.nan), ParameterError, "factor", "finite"),
    case("noise-std-negative", lambda: Noise("speed", std=-1.0), ParameterError, "std", ">= 0"),
    case("noise-std-nan", lambda: Noise("speed", std=np.nan), ParameterError, "std", "finite"),
    case("noise-std-inf", lambda: Noise("speed", std=np.inf), ParameterError, "std", "finite"),
    case("intermittent-size-nan", lambda: Intermittent("speed", size=np.nan), ParameterError, "size", "finite"),
    case("intermittent-period-zero", lambda: Intermittent("speed", 1.0, period=0.0), ParameterError,
         "period", "> 0"),
    case("intermittent-period-nan", lambda: Intermittent("speed", 1.0, period=np.nan), ParameterError,
         "period", "finite"),
    case("intermittent-period-inf", lambda: Intermittent("speed", 1.0, period=np.inf), ParameterError,
         "period", "finite"),
    case("intermittent-duty-zero", lambda: Intermittent("speed", 1.0, duty=0.0), ParameterError, "duty", "(0, 1]"),
    case("intermittent-duty-above-one", lambda: Intermittent("speed", 1.0, duty=1.5), ParameterError,
         "duty", "(0, 1]"),
    # ---- onset / end / target / location
    case("onset-nan", lambda: Bias("speed", 1.0, onset=np.nan), ParameterError, "onset", "finite"),
    case("onset-inf", lambda: Bias("speed", 1.0, onset=np.inf), ParameterError, "onset", "finite"),
    case("onset-string", lambda: Bias("speed", 1.0, onset="5"), ParameterError, "onset", "number"),
    case("onset-none", lambda: Bias("speed", 1.0, onset=None), ParameterError, "onset", "number"),
    case("end-nan", lambda: Bias("speed", 1.0, onset=1.0, end=np.nan), ParameterError, "end", "finite"),
    case("end-inf", lambda: Bias("speed", 1.0, end=np.inf), ParameterError, "end", "end=None"),
    case("end-before-onset", lambda: Bias("speed", 1.0, onset=5.0, end=2.0), ParameterError, "end", "onset"),
    case("end-equals-onset", lambda: Bias("speed", 1.0, onset=5.0, end=5.0), ParameterError, "end", "onset"),
    case("end-string", lambda: Bias("speed", 1.0, end="7"), ParameterError, "end", "number"),
    case("target-empty", lambda: Bias("", 1.0), ParameterError, "target", "name"),
    case("target-int", lambda: Bias(5, 1.0), ParameterError, "target", "name"),
    case("target-none", lambda: Bias(None, 1.0), ParameterError, "target", "name"),
    case("location-unknown", lambda: Bias("speed", 1.0, location="engine"), ParameterError,
         "location", "'sensor' or 'actuator'"),
    case("name-before-resolve", lambda: Bias("speed", 1.0).name, ParameterError, "speed", "resolve"),
    case("noise-apply-without-rng", lambda: Noise("speed", std=1.0).apply(T, np.zeros(10)), ParameterError,
         "rng", "Generator"),
    case("apply-shape-mismatch", lambda: Bias("speed", 1.0).apply(T, np.zeros(7)), DataError, "shape", "t"),
    case("apply-non-numeric", lambda: Bias("speed", 1.0).apply(T, ["a"] * 10), DataError, "v", "number"),
    # ---- scenarios
    case("scenario-holds-string", lambda: FaultScenario(["bias:speed:1"]), ParameterError, "Fault", "str"),
    case("scenario-single-fault-not-list", lambda: FaultScenario(Bias("speed", 1.0)), ParameterError,
         "faults", "iterable"),
    case("scenario-label-int", lambda: FaultScenario([Bias("speed", 1.0)], label=5), ParameterError, "label", "str"),
    case("scenario-label-empty", lambda: FaultScenario([Bias("speed", 1.0)], label=""), ParameterError,
         "label", "empty"),
    case("resolve-unknown-target", lambda: FaultScenario([Bias("brake", 1.0)]).resolve(OUT, CTL), ParameterError,
         "brake", "yaw_rate"),
    case("resolve-ambiguous", lambda: FaultScenario([Bias("steer", 1.0)]).resolve(OUT, CTL), ParameterError,
         "steer", "location"),
    case("resolve-wrong-sensor", lambda: FaultScenario([Bias("throttle", 1.0, location="sensor")]).resolve(OUT, CTL),
         ParameterError, "throttle", "sensor"),
    case("resolve-wrong-actuator", lambda: FaultScenario([Bias("speed", 1.0, location="actuator")]).resolve(OUT, CTL),
         ParameterError, "speed", "actuator"),
    # ---- the spec parser
    case("spec-bias-nan", lambda: parse_fault("bias:y:nan"), ParameterError, "bias:y:nan", "finite"),
    case("spec-bias-inf", lambda: parse_fault("bias:y:inf"), ParameterError, "bias:y:inf", "finite"),
    case("spec-bias-neg-inf", lambda: parse_fault("bias:y:-inf"), ParameterError, "bias:y:-inf", "finite"),
    case("spec-bias-overflow", lambda: parse_fault("bias:y:1e999"), ParameterError, "1e999", "finite"),
    case("spec-onset-nan", lambda: parse_fault("bias:y:1@nan"), ParameterError, "bias:y:1@nan", "onset"),
    case("spec-onset-inf", lambda: parse_fault("bias:y:1@inf"), ParameterError, "bias:y:1@inf", "onset"),
    case("spec-end-inf", lambda: parse_fault("bias:y:1@5-inf"), ParameterError, "bias:y:1@5-inf", "end"),
    case("spec-unknown-kind", lambda: parse_fault("kaboom:y:1"), ParameterError, "kaboom", "kind"),
    case("spec-empty", lambda: parse_fault(""), ParameterError, "fault spec", "empty"),
    case("spec-none", lambda: parse_fault(None), ParameterError, "fault spec", "string"),
    case("spec-number", lambda: parse_fault(5), ParameterError, "fault spec", "string"),
    case("spec-no-value", lambda: parse_fault("bias:y"), ParameterError, "bias:y", "needs a value"),
    case("spec-value-word", lambda: parse_fault("bias:y:abc"), ParameterError, "abc", "number"),
    case("spec-end-before-onset", lambda: parse_fault("bias:y:1@20-10"), ParameterError, "end", "onset"),
    case("spec-loe-above-one", lambda: parse_fault("loe:y:1.5"), ParameterError, "loss", "[0, 1]"),
    case("spec-noise-negative", lambda: parse_fault("noise:y:-1"), ParameterError, "std", ">= 0"),
    case("spec-bad-location", lambda: parse_fault("bias:y:1@2#engine"), ParameterError, "engine", "location"),
    case("spec-intermittent-period-zero", lambda: parse_fault("intermittent:y:1/0"), ParameterError,
         "period", "> 0"),
    case("spec-too-many-values", lambda: parse_fault("bias:y:1/2"), ParameterError, "bias:y:1/2", "one value"),
    case("spec-no-target", lambda: parse_fault("bias::1"), ParameterError, "bias::1", "target"),
    # ---- the spec writer
    case("format-not-a-fault", lambda: format_fault("bias:y:1"), ParameterError, "Fault", "str"),
    case("format-target-with-colon", lambda: format_fault(Bias("a:b", 1.0)), ParameterError, "a:b", "target"),
    case("format-target-with-space", lambda: format_fault(Bias("a b", 1.0)), ParameterError, "a b", "target"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
