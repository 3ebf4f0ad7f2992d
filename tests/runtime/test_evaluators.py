"""Compiled evaluator steps == reference step == reference run, sample by sample; ThresholdEvaluator.run's compiled
pass == the numpy formula; clear errors."""

import numpy as np
import pytest

from fdikit.decision import CusumEvaluator, GlrEvaluator, SprtEvaluator, ThresholdEvaluator
from fdikit.decision.common import held, isolate_fired, k_of_n
from fdikit.decision.densities import GaussianDensity, UniformMeanDensity
from fdikit.decision.mhsprt import MhsprtEvaluator
from fdikit.diagnosis import alarm_events
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals
from fdikit.runtime.evaluators import CompiledEvaluator, compile_evaluator

GROUPS, PER = 4, 3
NAMES = tuple(f"r{g}{i}" for g in range(GROUPS) for i in range(PER))
ISOLATES = tuple(f"f{g}" for g in range(GROUPS) for _ in range(PER))


def _residuals(n, seed, fault=None, onset=0.5, shift=1.5, bad=False):
    """12 white N(0, 1) residuals in 4 groups of 3; ``fault`` shifts its group from ``onset``; ``bad`` adds NaN/inf
    entries and ``valid=False`` samples (also inside the fault)."""
    rng = np.random.default_rng(seed)
    r = rng.standard_normal((n, len(NAMES)))
    if fault is not None:
        r[int(onset * n):, [k for k, f in enumerate(ISOLATES) if f == fault]] += shift
    valid = np.ones(n, bool)
    if bad:
        for k in (3, 40, 41, n // 2 + 7, n - 5):
            r[k] = np.nan
        r[60, 4] = np.inf
        r[n // 2 + 30, 1] = np.nan
        for k in (10, 11, 12, n // 2 + 3, n // 2 + 4, n // 2 + 40, n - 2):
            valid[k] = False
    return Residuals(np.arange(n) * 0.01, r, NAMES, ISOLATES, valid=valid)


HEALTHY = _residuals(4000, seed=1)
FAULTY = _residuals(1500, seed=2, fault="f1", bad=True)
CLEAN = _residuals(1500, seed=3, bad=True)


def _close(a, b, scale=1.0):
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * scale)


def _check(ev, res, stats=()):
    """Step the reference and the compiled evaluator through ``res`` (after a partial run and reset()), and compare
    both with the reference batch run, sample by sample."""
    d = ev.run(res)
    ce = compile_evaluator(ev)
    assert isinstance(ce, CompiledEvaluator) and ce.evaluator is ev and ce.names == res.names
    for k in range(50):  # a partial run first: reset() must forget it
        ce.step(res.r[k], valid=bool(res.valid[k]))
    ce.reset()
    ev.reset()
    for k in range(len(res)):
        x, ok = res.r[k], bool(res.valid[k])
        ref = ev.step(x, valid=ok)
        alarm = ce.step(x, valid=ok)
        got = ce.decision()
        assert alarm is ref.alarm == got.alarm == bool(d.alarm[k]), k
        assert ce.fault == ref.fault == got.fault == str(d.isolated[k]), k
        np.testing.assert_array_equal(got.fired, ref.fired)
        np.testing.assert_array_equal(ce.fired, d.fired[k])
        assert got.valid == ref.valid == bool(d.valid[k]) == ce.valid, k
        if ref.probabilities is not None:
            _close(got.probabilities, ref.probabilities)
            _close(got.probabilities, d.probabilities[k])
        now = ce.statistics()
        for name, ref_value in stats:
            _close(now[name], ref_value(ev, d, k), 1e3)
    return d


def test_threshold_with_persistence():
    ev = ThresholdEvaluator(persistence=(2, 3)).fit(HEALTHY, false_alarm_prob=1e-2)
    assert _check(ev, FAULTY).first_alarm().fault == "f1"
    _check(ev, CLEAN)


def test_threshold_with_signatures_and_lists():
    sig = {"f0": ["f0"], "f1": ["f1"], "f2": ["f1", "f2"], "f3": ["f3"]}
    ev = ThresholdEvaluator(signatures=sig).fit(HEALTHY, false_alarm_prob=1e-2)
    d = _check(ev, FAULTY)
    assert "f1" in set(d.isolated.tolist())
    ce = compile_evaluator(ev)
    ev.reset()
    for k in range(200):  # lists and mappings by name go through the reference's step_vector
        x = FAULTY.r[k]
        assert ce.step(x.tolist()) == ce.step(dict(zip(NAMES, x))) == ev.step(x).alarm


def test_cusum_reset_and_hold():
    ev = CusumEvaluator(hold=5).fit(HEALTHY, arl0=500.0, shift=1.5)
    stats = [("g_plus", lambda ev, d, k: ev.g_plus), ("g_minus", lambda ev, d, k: d.meta["g_minus"][k])]
    for res in (FAULTY, CLEAN):
        d = _check(ev, res, stats)
    assert d.detected


def test_cusum_rebase_over_a_long_run_one_sided_no_restart():
    """restart='none' never resets the running sums: only the rebase every 4096 valid samples does."""
    ev = CusumEvaluator(two_sided=False, restart="none").fit(HEALTHY, arl0=1e4, shift=1.5)
    long = _residuals(9000, seed=4, fault="f2", onset=0.8, bad=True)
    stats = [("g_plus", lambda ev, d, k: d.meta["g_plus"][k]), ("g_minus", lambda ev, d, k: ev.g_minus)]
    assert _check(ev, long, stats).detected


def test_glr_blocks():
    ev = GlrEvaluator(window=50).fit(HEALTHY, false_alarm_prob=1e-3)
    stats = [("statistic", lambda ev, d, k: d.meta["statistic"][k]),
             ("change_index", lambda ev, d, k: ev.change_index)]
    d = _check(ev, FAULTY, stats)
    assert d.first_alarm().fault == "f1"
    _check(ev, CLEAN, stats)


@pytest.mark.parametrize("restart", [True, False])
def test_sprt(restart):
    ev = SprtEvaluator(shift=1.5, alpha=1e-3, beta=1e-3, restart=restart, hold=3).fit(HEALTHY)
    stats = [("llr", lambda ev, d, k: d.meta["llr"][k]), ("decision", lambda ev, d, k: ev.decision)]
    d = _check(ev, FAULTY, stats)
    assert d.detected == restart  # the single test accepts H0 for good before the fault


def _labelled(n=3000):
    return {"none": HEALTHY, **{f"f{g}": _residuals(n, seed=10 + g, fault=f"f{g}", onset=0.0) for g in range(GROUPS)}}


@pytest.mark.parametrize("form", ["corrected", "literal"])
def test_mhsprt_gaussian(form):
    ev = MhsprtEvaluator(p=1e-3, pi=1e-3, form=form).fit(_labelled())
    stats = [("state", lambda ev, d, k: ev._state)]
    d = _check(ev, FAULTY, stats)
    assert d.first_alarm().fault == "f1"
    _check(ev, CLEAN, stats)


def test_mhsprt_magnitude_blocks():
    blocks = tuple(f"b{g}" for g in range(GROUPS) for _ in range(PER))
    ev = MhsprtEvaluator(p=1e-3, blocks=blocks).fit(_labelled(1500))
    _check(ev, FAULTY, [("state", lambda ev, d, k: ev._state)])


def test_mhsprt_long_run_stays_normalised():
    """Fault states absorb: over a long faulty run the log posterior of 'none' falls without bound in the reference;
    the compiled state follows it (log-space normalisation)."""
    ev = MhsprtEvaluator(p=1e-3).fit(_labelled(1500))
    long = _residuals(6000, seed=5, fault="f3", onset=0.1, bad=True)
    ce = compile_evaluator(ev)
    ev.reset()
    for k in range(len(long)):
        ev.step(long.r[k], valid=bool(long.valid[k]))
        ce.step(long.r[k], valid=bool(long.valid[k]))
    _close(ce.statistics()["state"], ev._state, abs(ev._state).max())
    assert ce.fault == "f3" and ev._state[0] < -100


def test_threshold_run_compiled_pass_equals_numpy_formula():
    """run() on a long series (the compiled pass) gives exactly what the numpy formula gives, alarms included."""
    res = _residuals(12000, seed=6, fault="f2", bad=True)  # 144,000 entries: above the compiled-pass size
    sig = {"f0": ["f0"], "f1": ["f1", "f2"], "f2": ["f2"], "f3": ["f3"]}
    for kw in ({"persistence": (1, 1)}, {"persistence": (2, 4)}, {"groups": ("a",) * 6 + ("b",) * 6},
               {"signatures": sig}):
        ev = ThresholdEvaluator(**kw).fit(HEALTHY, false_alarm_prob=1e-2)
        d = ev.run(res)
        valid = res.valid & np.all(np.isfinite(res.r), axis=1)
        fired = held(k_of_n(np.abs(res.r[valid] - ev.center) > ev.thresholds, *ev.persistence), valid, False)
        isolated = isolate_fired(fired, ISOLATES, ev.groups, ev.signatures, NAMES)
        np.testing.assert_array_equal(d.valid, valid)
        np.testing.assert_array_equal(d.fired, fired)
        np.testing.assert_array_equal(d.alarm, fired.any(axis=1))
        assert d.isolated.dtype == isolated.dtype and np.array_equal(d.isolated, isolated)
        assert d.alarms == alarm_events(res.t, fired.any(axis=1), fired, NAMES, isolated) and len(d.alarms) > 5


def test_errors():
    ev = ThresholdEvaluator().fit(HEALTHY, false_alarm_prob=1e-2)
    ce = compile_evaluator(ev)
    with pytest.raises(DataError, match="compiled for 12 residuals"):
        ce.step(np.zeros(11))
    with pytest.raises(DataError, match="compiled for 12 residuals"):
        ce.step([0.0] * 13)
    with pytest.raises(DataError, match="as numbers"):
        ce.step(["a"] * 12)
    with pytest.raises(DataError, match="missing"):
        ce.step({"x": 1.0, **dict(zip(NAMES[1:], [0.0] * 11))})
    with pytest.raises(DataError, match="reordered"):
        compile_evaluator(ev, names=NAMES[::-1])
    assert ce.step(np.zeros(12)) is False  # usable after an error
    for unfitted in (ThresholdEvaluator(), CusumEvaluator(), GlrEvaluator(), SprtEvaluator(shift=1.0),
                     MhsprtEvaluator()):
        with pytest.raises(ParameterError):
            compile_evaluator(unfitted)
    with pytest.raises(ParameterError, match="no thresholds"):
        compile_evaluator(ThresholdEvaluator(), names=("a",))
    with pytest.raises(ParameterError, match="cannot compile a str"):
        compile_evaluator("threshold")
    dens = {"none": GaussianDensity(0.0, 1.0), "f": UniformMeanDensity([0.5], [2.0], 1.0)}
    with pytest.raises(ParameterError, match="UniformMeanDensity"):
        compile_evaluator(MhsprtEvaluator(dens))
    hand = compile_evaluator(MhsprtEvaluator({"none": GaussianDensity(0.0, 1.0), "f": GaussianDensity(1.0, 1.0)}))
    assert hand.names is None and hand.columns == ("f",)
    with pytest.raises(DataError, match="compiled for 1 residuals"):
        hand.step(np.zeros(2))
