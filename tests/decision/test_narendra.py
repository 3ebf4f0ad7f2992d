"""Narendra evaluation filters (FDITOOLS' FDSystem / FDISystem + tstep!): the recursion against a direct loop,
batch = online through gaps, quantile calibration against its false-alarm probability, and the reference's
online cases of test_evaluation.jl (Example 5.3 detection, the Niemann 1998 isolation bank)."""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.analysis import fdisspec, fditspec
from fdikit.decision.narendra import NarendraEvaluator, narendra_signal
from fdikit.design.nullspace import efdisyn, efdsyn
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals
from fdikit.trace import Trace

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "design" / "nullspace"))
from varga_examples import niemann  # noqa: E402


def test_signal_equals_the_reference_recursion():
    rng = np.random.default_rng(0)
    n = np.abs(rng.standard_normal((300, 3)))
    a, b, c = np.array([0.0, 15.0, 1.0]), np.array([10.0, 0.5, 0.0]), np.array([0.9, 0.8, 0.3])
    e, ref = np.zeros(3), []
    for k in range(300):  # tstep!: θ = α‖r‖ (+ β re); re = γ re + ‖r‖
        ref.append(a * n[k] + b * e)
        e = c * e + n[k]
    np.testing.assert_allclose(narendra_signal(n, a, b, c), np.array(ref), rtol=1e-12, atol=1e-12)


def test_run_equals_step_through_gaps_with_groups_and_signatures():
    rng = np.random.default_rng(1)
    N = 600
    r = rng.standard_normal((N, 3)) * 0.3
    r[300:, 0] += 2.0        # fault a: group g1 (residual r0)
    r[450:, 1:] += 2.0       # then both groups
    r[[50, 51, 320]] = np.nan
    valid = np.ones(N, bool)
    valid[52:55] = False
    res = Residuals(np.arange(N) * 0.01, r, ("r0", "r1", "r2"), (), valid=valid)
    ev = NarendraEvaluator(alpha=1.0, beta=0.5, gamma=0.8, thresholds=[2.5, 3.0], groups=["g1", "g2", "g2"],
                           signatures={"a": ["g1"], "b": ["g2"], "c": ["g1", "g2"]})
    d = ev.run(res)
    online = [ev.step(r[k], valid=bool(valid[k])) for k in range(N)]
    assert [s.fault for s in online] == d.isolated.tolist()
    assert np.array_equal(np.array([s.fired for s in online]), d.fired)
    assert [s.valid for s in online] == d.valid.tolist()
    assert d.isolated[350] == "a" and d.isolated[500] == "c"
    assert np.array_equal(d.fired[:, 1], d.fired[:, 2])          # a residual fires with its group
    assert d.meta["theta"].shape == (N, 2)


def test_calibrated_false_alarm_fraction_matches_alpha():
    # θ_i is a stationary filtered norm: the 1 − α/g quantile on fault-free data bounds the per-sample exceedance.
    # With independent groups P(alarm) = 1 − (1 − α/2)² ≈ α; the alarm indicator is correlated over ≈ 2/(1 − γ)
    # samples, so the standard error of the fraction on N samples is ≈ √(α (2/(1 − γ)) / N).
    rng = np.random.default_rng(2)
    N, alpha, gamma = 200_000, 0.01, 0.9
    names = ("a0", "a1", "b0")
    train = Residuals(np.arange(N) * 0.01, rng.standard_normal((N, 3)), names, ())
    test = Residuals(np.arange(N) * 0.01, rng.standard_normal((N, 3)), names, ())
    ev = NarendraEvaluator(alpha=0.5, beta=1.0, gamma=gamma, groups=["a", "a", "b"]).fit(train, false_alarm_prob=alpha)
    expected = 1 - (1 - alpha / 2) ** 2
    se = np.sqrt(expected * (2 / (1 - gamma)) / N)
    assert ev.run(test).alarm.mean() == pytest.approx(expected, abs=6 * se)
    assert ev.calibration.runs == 1


def _simulate(m, u, d, f):
    """Discrete plant response y(k) = C x + D v, x⁺ = A x + B v (v = [u; d; f])."""
    x, ys = np.zeros(m.n), []
    for k in range(len(u)):
        v = np.concatenate([u[k], d[k], f[k]])
        ys.append(m.C @ x + m.D @ v)
        x = m.A @ x + m.B @ v
    return np.array(ys)


def _scaled(gen, gains):
    """The generator with residual i divided by its gain ``gains[i]`` (the reference's results are up to scaling)."""
    s = 1.0 / np.asarray(gains)[:, None]
    return dataclasses.replace(gen, C=gen.C * s, D=gen.D * s)


def test_example_5_3_online_detection():
    # test_evaluation.jl: efdsyn(sdeg=-3, rdim=1) on Example 5.3, Q and Rf normalised by Rf_f1(∞), c2d at 0.01,
    # FDSystem(α=0, β=10, γ=0.9, τ=1): no alarm without faults (d is decoupled), detection of 0.5 steps.
    m = FaultModel(A=np.diag([-2.0, -2.0, -3.0]), C=[[-1.0, -3.0, 0.0], [0.0, 0.0, -1.0]],
                   Bu=[[1.0], [0.0], [1.0]], Du=[[1.0], [1.0]], Bd=[[0.0], [1.0], [0.0]], Dd=[[1.0], [0.0]],
                   controls=["u"], disturbances=["d"], outputs=["y1", "y2"])
    m = m.with_actuator_faults(["u"]).with_sensor_faults(["y2"])
    d = efdsyn(m, sdeg=-3.0, rdim=1)
    R = d.generator.internal_form(m)
    gen = _scaled(d.generator, [R.d("f")[0, 0]]).discretize(0.01)
    md = m.discretize(0.01)
    t = np.arange(0, 1.0 + 1e-9, 0.01)
    rng = np.random.default_rng(4)
    u, dist = np.sin(2 * np.pi * t)[:, None], rng.standard_normal((t.size, 1))
    f = np.zeros((t.size, 2))
    f[5:] = 0.5
    for faults, expect in ((0 * f, False), (f, True)):
        y = _simulate(md, u, dist, faults)
        res = gen.run(Trace(t, u, y, m.controls, m.outputs))
        ev = NarendraEvaluator(alpha=0.0, beta=10.0, gamma=0.9, thresholds=1.0, groups=["fd"])
        assert ev.run(res).alarm[-1] == expect and ev.run(res).alarm.any() == expect


def test_niemann_bank_online_isolation():
    # test_evaluation.jl: Niemann 1998 plant, c2d at 0.01, efdisyn(SFDI = I, FDtol=1e-5, rdim=1): orders 1, 1;
    # fditspec == fdisspec == SFDI; FDISystem(α=0, β=1.1, γ=0.7, τ=1): no alarm without faults (0.1 randn
    # disturbance), indfault [1] for fault 1, [2] for fault 2, [1, 2] for both (0.5 steps from sample 6).
    md = niemann().discretize(0.01)
    bank = efdisyn(md, np.eye(2), fdtol=1e-5, rdim=1)
    assert bank.orders == (1, 1)
    R = bank.generator.internal_form(md)
    weak, strong = fditspec(R, groups=bank.groups, tol=1e-5), fdisspec(R, groups=bank.groups)
    assert weak.matrix.tolist() == strong.matrix.tolist() == np.eye(2, dtype=bool).tolist()
    gen = bank.generator            # each filter scaled to unit H∞ norm of its fault channel (the reference)
    t = np.arange(0, 1.0 + 1e-9, 0.01)
    rng = np.random.default_rng(5)
    u, dist = np.sin(2 * np.pi * t)[:, None] * np.ones((1, 2)), 0.1 * rng.standard_normal((t.size, 1))
    names = md.faults
    ev = NarendraEvaluator(alpha=0.0, beta=1.1, gamma=0.7, thresholds=1.0,
                           groups=[g for g, members in zip(("filter0", "filter1"), bank.groups) for _ in members],
                           signatures=weak)
    for on, expect_fired, expect in (((0, 0), [False, False], "none"), ((1, 0), [True, False], names[0]),
                                     ((0, 1), [False, True], names[1]), ((1, 1), [True, True], "unknown")):
        f = np.zeros((t.size, 2))
        f[5:] = 0.5 * np.array(on)
        res = gen.run(Trace(t, u, _simulate(md, u, dist, f), md.controls, md.outputs))
        diag = ev.run(res)
        assert diag.fired[-1].tolist() == expect_fired and diag.isolated[-1] == expect
        if expect == "none":
            assert not diag.alarm.any()   # no false alarm: the disturbance is decoupled


def test_bad_parameters():
    with pytest.raises(ParameterError, match="γ must lie"):
        NarendraEvaluator(gamma=1.5)
    with pytest.raises(ParameterError, match="not both zero"):
        NarendraEvaluator(alpha=0.0, beta=0.0)
    res = Residuals(np.arange(5) * 0.1, np.zeros((5, 2)), ("a", "b"), ())
    with pytest.raises(ParameterError, match="no thresholds"):
        NarendraEvaluator().run(res)
    with pytest.raises(DataError, match="one group per residual"):
        NarendraEvaluator(thresholds=1.0, groups=["g"]).run(res)
    with pytest.raises(DataError, match="fault-free samples"):
        NarendraEvaluator().fit(Residuals(np.arange(50) * 0.1, np.ones((50, 2)), ("a", "b"), ()),
                                false_alarm_prob=0.01)
