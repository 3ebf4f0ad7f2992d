"""Property tests of the fault-spec grammar (``parse_fault`` / ``format_fault``) and of fault validation.

* ``parse_fault(format_fault(f)) == f`` for every fault kind, with random finite values, signal
  names, onsets, ends and locations (numbers are written with ``repr``, which reads back exactly);
* ``format_fault`` is canonical: ``format_fault(parse_fault(s)) == s`` for every string it writes, and
  a spec written in any other notation (``ramp`` for ``drift``, ``%e`` / ``%.17g`` numbers, a ``+``
  sign, spaces around it) parses to the same fault as its canonical form;
* a spec with NaN or ±inf in any number slot is refused with a ParameterError naming the spec;
* ``Fault.apply`` leaves every sample before the onset bit for bit unchanged.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fdikit.errors import ParameterError
from fdikit.fault_spec import format_fault, parse_fault
from fdikit.faults import (
    Bias,
    Drift,
    Intermittent,
    LossOfEffectiveness,
    Noise,
    ScaleFactor,
    Stuck,
)

FINITE = st.floats(allow_nan=False, allow_infinity=False)
TARGETS = st.from_regex(r"[\w.]{1,12}", fullmatch=True)
LOCATIONS = st.sampled_from([None, "sensor", "actuator"])


@st.composite
def timing(draw):
    onset = draw(st.one_of(st.just(0.0), FINITE))
    end = draw(st.one_of(st.none(), st.floats(min_value=0, exclude_min=True, allow_infinity=False)))
    if end is not None:
        end = onset + end
        if not (math.isfinite(end) and end > onset):
            end = None
    return {"onset": onset, "end": end, "location": draw(LOCATIONS)}


@st.composite
def faults(draw):
    """A random valid fault of a random kind."""
    kind = draw(st.sampled_from(["bias", "drift", "stuck", "loe", "scale", "noise", "intermittent"]))
    target, kw = draw(TARGETS), draw(timing())
    if kind == "bias":
        return Bias(target, draw(FINITE), **kw)
    if kind == "drift":
        return Drift(target, rate=draw(FINITE), **kw)
    if kind == "stuck":
        return Stuck(target, value=draw(st.one_of(st.none(), FINITE)), **kw)
    if kind == "loe":
        return LossOfEffectiveness(target, loss=draw(st.floats(0.0, 1.0)), **kw)
    if kind == "scale":
        return ScaleFactor(target, factor=draw(FINITE), **kw)
    if kind == "noise":
        return Noise(target, std=draw(st.floats(min_value=0.0, allow_infinity=False)), **kw)
    period = draw(st.one_of(st.just(1.0), st.floats(min_value=0, exclude_min=True, allow_infinity=False)))
    duty = draw(st.one_of(st.just(0.5), st.floats(min_value=0, max_value=1, exclude_min=True)))
    return Intermittent(target, size=draw(FINITE), period=period, duty=duty, **kw)


@settings(max_examples=200)
@given(faults())
def test_parse_of_format_is_the_fault(fault):
    spec = format_fault(fault)
    back = parse_fault(spec)
    assert back == fault and type(back) is type(fault)
    assert fault.spec == spec


@settings(max_examples=200)
@given(faults())
def test_format_is_canonical(fault):
    spec = format_fault(fault)
    assert format_fault(parse_fault(spec)) == spec


def _write(x: float, style: str) -> str:
    if style == "e":
        return f"{x:.17e}"
    if style == "g":
        return f"{x:.17g}"
    if style == "plus":
        return ("+" if x >= 0 and not str(x).startswith("-") else "") + repr(x)
    return repr(x)


@settings(max_examples=200)
@given(faults(), st.sampled_from(["e", "g", "plus", "repr"]), st.booleans())
def test_any_notation_parses_to_the_canonical_fault(fault, style, pad):
    """A hand-written spec (other number notations, ``ramp``, spaces) reads as its canonical form does."""
    kind = {Bias: "bias", Drift: "ramp", Stuck: "stuck", LossOfEffectiveness: "loe", ScaleFactor: "scale",
            Noise: "noise", Intermittent: "intermittent"}[type(fault)]
    values = {Bias: ["size"], Drift: ["rate"], Stuck: ["value"], LossOfEffectiveness: ["loss"],
              ScaleFactor: ["factor"], Noise: ["std"], Intermittent: ["size", "period", "duty"]}[type(fault)]
    nums = [getattr(fault, v) for v in values]
    spec = f"{kind}:{fault.target}"
    if nums[0] is not None:
        spec += ":" + "/".join(_write(x, style) for x in nums)
    spec += f"@{_write(fault.onset, style)}"
    if fault.end is not None:
        spec += f"-{_write(fault.end, style)}"
    if fault.location:
        spec += f"#{fault.location}"
    if pad:
        spec = f"  {spec}\t"
    parsed = parse_fault(spec)
    # %.17g / %.17e / repr all read back to the same double
    assert parsed == fault
    assert parse_fault(format_fault(parsed)) == parsed


BAD_NUMBERS = st.sampled_from(["nan", "NaN", "inf", "-inf", "+inf", "Infinity", "1e999", "-1e400"])


@settings(max_examples=100)
@given(st.sampled_from(["bias", "drift", "stuck", "scale", "intermittent"]), TARGETS,
       st.sampled_from(["value", "onset", "end"]), BAD_NUMBERS)
def test_non_finite_numbers_in_a_spec_are_refused(kind, target, slot, bad):
    value, onset, end = "1.0", "2.0", "3.0"
    if slot == "value":
        value = bad
    elif slot == "onset":
        onset = bad
    else:
        end = bad
    spec = f"{kind}:{target}:{value}@{onset}-{end}"
    with pytest.raises(ParameterError) as info:
        parse_fault(spec)
    msg = str(info.value)
    assert spec in msg and ("finite" in msg or "cannot" in msg)


@settings(max_examples=100)
@given(faults(), st.integers(0, 2**32 - 1))
def test_apply_leaves_samples_before_onset_unchanged(fault, seed):
    rng = np.random.default_rng(seed)
    t = np.linspace(-5.0, 5.0, 101)
    v = rng.standard_normal(101) * 10.0 ** rng.integers(-3, 4)
    with np.errstate(over="ignore", invalid="ignore"):
        out = fault.apply(t, v, np.random.default_rng(seed))
    before = t < fault.onset
    assert out[before].tobytes() == v[before].tobytes()
    if fault.end is not None:
        after = t >= fault.end
        assert out[after].tobytes() == v[after].tobytes()


def test_the_issue_examples_are_refused():
    """``bias:y:nan`` and ``Bias('u', inf, onset=5)`` were accepted before (issue 12)."""
    with pytest.raises(ParameterError, match=r"'bias:y:nan'.*finite"):
        parse_fault("bias:y:nan")
    with pytest.raises(ParameterError, match="size must be a finite number"):
        Bias("u", np.inf, onset=5)


def test_location_suffix_and_intermittent_parameters():
    f = parse_fault("bias:steer:0.1@3#actuator")
    assert f == Bias("steer", 0.1, onset=3.0, location="actuator")
    g = parse_fault("intermittent:speed:0.2/2/0.25@4-10")
    assert (g.size, g.period, g.duty, g.onset, g.end) == (0.2, 2.0, 0.25, 4.0, 10.0)
    assert format_fault(g) == "intermittent:speed:0.2/2.0/0.25@4.0-10.0"
    assert format_fault(Intermittent("speed", 0.2, onset=4)) == "intermittent:speed:0.2@4.0"
    assert format_fault(Intermittent("speed", 0.2, period=3.0)) == "intermittent:speed:0.2/3.0"
    assert format_fault(Stuck("steer", onset=2)) == "stuck:steer@2.0"
    assert format_fault(Bias("y", 1)) == "bias:y:1.0"
    assert Bias("y", 1).size == 1.0 and isinstance(Bias("y", np.float32(0.5)).size, float)
