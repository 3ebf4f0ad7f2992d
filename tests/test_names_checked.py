"""Names are checked (issue 12 item 5): evaluators against the residual names of their fit, generators
against the signals of the trace — in the batch (``run``) and the online (``step``) path.

The issue's case: an evaluator fitted on residuals ``(a, b)`` silently applied those thresholds to
residuals named ``(b, a)``.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from fdikit.decision import (
    BnnEvaluator,
    CusumEvaluator,
    GaussianMlEvaluator,
    GlrEvaluator,
    MhsprtEvaluator,
    SprtEvaluator,
    ThresholdEvaluator,
)
from fdikit.errors import DataError
from fdikit.residuals import ResidualGenerator, Residuals, stack_generators
from fdikit.trace import Trace

KINDS = ("threshold", "cusum", "glr", "sprt", "mhsprt", "gaussian_ml", "bnn")


def _res(r, names=("a", "b"), isolates=("fa", "fb")):
    r = np.asarray(r, float)
    return Residuals(np.arange(len(r)) * 0.01, r, names, isolates)


@cache
def _healthy():
    # residual 'a' has ten times the noise of 'b': thresholds fitted on (a, b) are far from symmetric
    return _res(np.random.default_rng(0).standard_normal((3000, 2)) * [1.0, 0.1])


@cache
def _fitted(kind):
    h = _healthy()
    rng = np.random.default_rng(1)
    if kind == "threshold":
        return ThresholdEvaluator().fit(h, false_alarm_prob=1e-3)
    if kind == "cusum":
        return CusumEvaluator().fit(h, arl0=1e4, shift=1.0)
    if kind == "glr":
        return GlrEvaluator(window=10).fit(h, false_alarm_prob=1e-3)
    if kind == "sprt":
        return SprtEvaluator(shift=1.0).fit(h)
    fa = [_res(rng.standard_normal((300, 2)) * [1.0, 0.1] + [0.0, s]) for s in (0.5, 1.0, 2.0)]
    if kind == "mhsprt":
        return MhsprtEvaluator().fit({"none": h, "fa": fa})
    data = {"none": [h], "fa": [fa[1]], "fb": [_res(rng.standard_normal((300, 2)) * [1.0, 0.1] + [4.0, 0.0])]}
    if kind == "gaussian_ml":
        return GaussianMlEvaluator(inputs="raw").fit(data)
    return BnnEvaluator(inputs="raw", max_iter=2, rm_steps=0).fit(data)


def _series(names):
    h = _healthy()
    col = {"a": 0, "b": 1}
    return _res(h.r[:300, [col.get(n, 0) for n in names]], names, tuple(f"f{n}" for n in names))


@pytest.mark.parametrize("kind", KINDS)
def test_evaluator_refuses_reordered_missing_and_extra_residuals(kind):
    ev = _fitted(kind)
    assert ev.names == ("a", "b")
    with pytest.raises(DataError, match=r"reordered.*\['b', 'a'\].*fitted on \['a', 'b'\]") as err:
        ev.run(_series(("b", "a")))
    assert "'b' at 0 (fitted at 1)" in str(err.value)
    with pytest.raises(DataError, match=r"missing \['b'\], extra \[\]"):
        ev.run(_series(("a",)))
    with pytest.raises(DataError, match=r"missing \[\], extra \['c'\]"):
        ev.run(_series(("a", "b", "c")))
    with pytest.raises(DataError, match=r"missing \['b'\], extra \['c'\]"):
        ev.run(_series(("a", "c")))
    # online: names given with the sample are checked the same way
    ev.reset()
    with pytest.raises(DataError, match="reordered"):
        ev.step([0.0, 0.0], names=("b", "a"))
    with pytest.raises(DataError, match=r"extra \['c'\]"):
        ev.step({"a": 0.0, "c": 0.0})
    # the right names (or the series reordered by name) are accepted, batch and online alike
    good = _series(("a", "b"))
    d = ev.run(_series(("b", "a")).select(ev.names))
    ev.reset()
    steps = [ev.step(good.r[k], names=good.names) for k in range(len(good))]
    np.testing.assert_array_equal([s.alarm for s in steps], d.alarm)
    np.testing.assert_array_equal(ev.run(good).alarm, d.alarm)


def test_the_issue_case_no_longer_silent():
    """Fitted on (a, b) with σ_a = 10 σ_b: on (b, a) the thresholds would be swapped (10× off each way)."""
    ev = _fitted("threshold")
    assert ev.thresholds[0] > 5 * ev.thresholds[1]
    with pytest.raises(DataError, match="reordered"):
        ev.run(_series(("b", "a")))


def _gen(dt=0.1):
    A = np.array([[0.5, 0.1], [0.0, 0.3]])
    B = np.array([[0.1, 0.2, 0.0], [0.0, 0.1, 0.3]])
    D = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    return ResidualGenerator(A, B, -np.eye(2), D, ("u",), ("y1", "y2"), ("r1", "r2"), dt)


def _trace(controls=("u",), outputs=("y1", "y2"), dt=0.1, n=40):
    rng = np.random.default_rng(2)
    return Trace(t=np.arange(n) * dt, u=rng.standard_normal((n, len(controls))),
                 y=rng.standard_normal((n, len(outputs))), controls=controls, outputs=outputs)


@pytest.mark.parametrize("path", ["run", "online"])
def test_generator_refuses_traces_that_do_not_match(path):
    gen = _gen()
    go = gen.run if path == "run" else (lambda tr: gen.online().run(tr))
    with pytest.raises(DataError, match=r"missing outputs \['y2'\]; the trace's outputs not read: \['y3'\]"):
        go(_trace(outputs=("y1", "y3")))
    with pytest.raises(DataError, match=r"missing controls \['u'\] \(\['u'\] found as outputs\)"):
        go(_trace(controls=("v",), outputs=("y1", "y2", "u")))
    with pytest.raises(DataError, match=r"dt=0\.05 but the generator is discrete with dt=0\.1"):
        go(_trace(dt=0.05))
    # extra signals in the trace are fine (a generator of a bank reads a subset), and the order of the
    # trace's columns does not matter: signals are taken by name
    tr = _trace(outputs=("y2", "extra", "y1"))
    ref = Trace(t=tr.t, u=tr.u, y=tr.y[:, [2, 0]], controls=("u",), outputs=("y1", "y2"))
    np.testing.assert_allclose(go(tr).r, gen.run(ref).r, rtol=1e-12, atol=1e-15)


def test_step_by_name():
    gen = _gen()
    tr = _trace()
    a, b = gen.online(), gen.online()
    for k in range(len(tr)):
        ra = a.step(tr.u[k], tr.y[k])
        rb = b.step({"u": tr.u[k, 0]}, {"y2": tr.y[k, 1], "y1": tr.y[k, 0]})
        np.testing.assert_array_equal(ra, rb)
    with pytest.raises(DataError, match=r"missing \['y2'\], extra \['y3'\]"):
        gen.online().step({"u": 0.0}, {"y1": 0.0, "y3": 0.0})


def test_stacked_bank_checks_every_signal():
    g1 = _gen()
    g2 = ResidualGenerator(g1.A, g1.B, g1.C, g1.D, g1.controls, g1.outputs, ("s1", "s2"), g1.dt)
    bank = stack_generators([g1, g2])
    with pytest.raises(DataError, match=r"missing outputs \['y1'\]"):
        bank.run(_trace(outputs=("y2",)))


def test_scheduled_generator_checks_signals_both_paths():
    from fdikit.design.parity.scheduled import scheduled_parity_filter
    from fdikit.plants.single_track import single_track_lpv

    gen = scheduled_parity_filter(single_track_lpv(), 70 / 3.6)
    n = 20
    outputs = tuple(o for o in gen.outputs if o != "yaw_rate") + ("speed",)
    tr = Trace(t=np.arange(n) * gen.dt, u=np.zeros((n, len(gen.controls))), y=np.ones((n, len(outputs))),
               controls=gen.controls, outputs=outputs)
    for go in (gen.run, gen.online().run):
        with pytest.raises(DataError, match=r"missing outputs \['yaw_rate'\]"):
            go(tr)
