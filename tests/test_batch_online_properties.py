"""Property tests (issue 12 item 8): batch == online for every residual generator and every evaluator.

Generators with both a batch ``run`` and an online stepper: :class:`ResidualGenerator` (discrete,
continuous run online at a ``dt``, stacked banks) and :class:`ScheduledResidualGenerator` (the
only other ``online``/``step`` pair under ``src/fdikit`` that turns a trace into residuals, apart
from the multiple-model filters of ``fdikit.multimodel``, which are not residual generators).
Random filters, random data, random invalid samples (single NaN entries, whole-sample gaps, NaN
controls).

Equality: the flags (``valid``, ``recovering``, NaN positions) must be identical — they depend only
on which samples are bad.  The residual values are equal to rounding, not bit for bit: ``run`` uses
the lifted blocked recursion of :func:`fdikit.lti.dlsim_blocked` (products of up to 32 powers of
``A``) and superposition, ``step`` the plain recursion.  Both evaluate the same linear recursion of a
stable filter (spectral radius ≤ 0.9 here) in double precision; the difference is bounded by a small
multiple of ``N_ops · eps · max|r|`` with ``N_ops`` of the order of the block length times the state
dimension (≈ 1e-13 relative); the tolerance ``1e-9 (1 + max|r|)`` leaves four orders of margin.

Evaluators get the *same* residual series in both paths, so their decisions must be identical
(``alarm``, ``fired``, ``isolated``, ``valid``) with ``step(r, valid=res.valid[k])``.  ``reset`` then
a new run equals a fresh run; ``fit`` again equals a fresh fit.
"""

from __future__ import annotations

import copy
from functools import cache

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fdikit.decision import (
    BnnEvaluator,
    CusumEvaluator,
    GaussianMlEvaluator,
    GlrEvaluator,
    MhsprtEvaluator,
    SprtEvaluator,
    ThresholdEvaluator,
)
from fdikit.residuals import ResidualGenerator, Residuals, stack_generators
from fdikit.trace import Trace

DT = 0.1


def _generator(rng, n, m, p, q, strictly_proper=False, dt=DT, names=None):
    A = rng.standard_normal((n, n)) if n else np.zeros((0, 0))
    if n:
        rho = np.max(np.abs(np.linalg.eigvals(A)))
        A = A * (rng.uniform(0.0, 0.9) / rho if rho > 0 else 1.0)
    B = rng.standard_normal((n, m + p))
    C = rng.standard_normal((q, n))
    D = rng.standard_normal((q, m + p))
    if strictly_proper:
        D[:, m:] = 0.0
    controls = tuple(f"u{i}" for i in range(m))
    outputs = tuple(f"y{i}" for i in range(p))
    return ResidualGenerator(A, B, C, D, controls, outputs, names or tuple(f"r{i}" for i in range(q)), dt)


def _data(rng, gen, N, p_entry, p_gap, dt=DT):
    m, p = len(gen.controls), len(gen.outputs)
    u = rng.standard_normal((N, m))
    y = rng.standard_normal((N, p))
    for X in (u, y):
        X[rng.random(X.shape) < p_entry] = np.nan
    k = 0
    while k < N:
        if rng.random() < p_gap:
            L = int(rng.integers(1, 15))
            y[k : k + L] = np.nan
            k += L
        k += 1
    return Trace(t=np.arange(N) * dt, u=u, y=y, controls=gen.controls, outputs=gen.outputs)


def _same(batch: Residuals, online: Residuals) -> None:
    np.testing.assert_array_equal(batch.valid, online.valid)
    np.testing.assert_array_equal(batch.recovering, online.recovering)
    fin = np.isfinite(batch.r)
    np.testing.assert_array_equal(fin, np.isfinite(online.r))
    scale = 1.0 + (np.abs(online.r[fin]).max() if fin.any() else 0.0)
    np.testing.assert_allclose(batch.r[fin], online.r[fin], rtol=0, atol=1e-9 * scale)
    assert not (batch.valid & batch.recovering).any()
    assert not batch.valid[~fin.all(axis=1)].any()


shapes = st.tuples(st.integers(0, 4), st.integers(0, 2), st.integers(1, 3), st.integers(1, 3))


@settings(max_examples=60)
@given(seed=st.integers(0, 2**32 - 1), shape=shapes, N=st.integers(1, 120), p_entry=st.sampled_from([0.0, 0.02, 0.1]),
       p_gap=st.sampled_from([0.0, 0.03, 0.1]), strictly_proper=st.booleans(), tol=st.sampled_from([0.05, 0.1, 1.0]))
def test_generator_batch_equals_online(seed, shape, N, p_entry, p_gap, strictly_proper, tol):
    rng = np.random.default_rng(seed)
    gen = _generator(rng, *shape, strictly_proper=strictly_proper)
    tr = _data(rng, gen, N, p_entry, p_gap)
    q = len(gen.residuals)
    M = rng.standard_normal((q, q))
    cov = M @ M.T + 0.1 * np.eye(q)
    batch = gen.run(tr, residual_cov=cov, recovery_tol=tol)
    stepper = gen.online(residual_cov=cov, recovery_tol=tol)
    online = stepper.run(tr)
    _same(batch, online)
    assert stepper.invalid == int((~np.isfinite(gen.inputs_from(tr)).all(axis=1)).sum())
    # reset then rerun equals a fresh run; a second trace after reset equals its own fresh run
    stepper.reset()
    _same(stepper.run(tr), online)
    tr2 = _data(rng, gen, N, p_entry, p_gap)
    stepper.reset()
    _same(gen.run(tr2, residual_cov=cov, recovery_tol=tol), stepper.run(tr2))


@settings(max_examples=30)
@given(seed=st.integers(0, 2**32 - 1), n1=st.integers(1, 3), n2=st.integers(0, 3), m=st.integers(0, 2),
       p=st.integers(1, 3), N=st.integers(2, 120), p_entry=st.sampled_from([0.0, 0.05]),
       p_gap=st.sampled_from([0.03, 0.1]))
def test_stacked_bank_batch_equals_online_and_each_filter_alone(seed, n1, n2, m, p, N, p_entry, p_gap):
    """A bank: batch == online, and each filter of the bank gives what it gives alone (the gap rule
    treats the filters of a bank separately)."""
    rng = np.random.default_rng(seed)
    g1 = _generator(rng, n1, m, p, p, names=tuple(f"a{i}" for i in range(p)))
    g2 = _generator(rng, n2, m, p, 1, names=("b0",))
    bank = stack_generators([g1, g2])
    tr = _data(rng, bank, N, p_entry, p_gap)
    batch = bank.run(tr)
    _same(batch, bank.online().run(tr))
    alone = g1.run(tr)
    fin = np.isfinite(alone.r)
    np.testing.assert_allclose(batch.r[:, :p][fin], alone.r[fin], rtol=0,
                               atol=1e-9 * (1 + np.abs(alone.r[fin]).max(initial=0)))


@settings(max_examples=20)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 3), N=st.integers(2, 80), p_gap=st.sampled_from([0.0, 0.1]))
def test_continuous_generator_run_equals_online_at_the_trace_dt(seed, n, N, p_gap):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A = A - (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)  # Hurwitz
    gen = ResidualGenerator(A, rng.standard_normal((n, 3)), rng.standard_normal((2, n)), rng.standard_normal((2, 3)),
                            ("u0",), ("y0", "y1"), ("r0", "r1"), None)
    tr = _data(rng, gen, N, 0.02, p_gap, dt=0.05)
    _same(gen.run(tr), gen.online(dt=0.05).run(tr))


# ------------------------------------------------------------------------------------------ scheduled filter
@cache
def _scheduled():
    from fdikit.design.parity.scheduled import scheduled_parity_filter
    from fdikit.plants.single_track import single_track_lpv

    return scheduled_parity_filter(single_track_lpv(), 70 / 3.6)


@settings(max_examples=12)
@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 40), p_entry=st.sampled_from([0.0, 0.03, 0.1]),
       first_bad=st.booleans(), tol=st.sampled_from([0.1, 0.5]))
def test_scheduled_batch_equals_online(seed, N, p_entry, first_bad, tol):
    gen = _scheduled()
    rng = np.random.default_rng(seed)
    outputs = gen.outputs + ("speed",)
    y = 0.01 * rng.standard_normal((N, len(outputs)))
    y[:, -1] = rng.uniform(60, 90, N) / 3.6
    u = 0.01 * rng.standard_normal((N, len(gen.controls)))
    y[rng.random(y.shape) < p_entry] = np.nan  # NaN speed too: the sample is invalid
    if first_bad:
        y[0, 0] = np.nan
    tr = Trace(t=np.arange(N) * gen.dt, u=u, y=y, controls=gen.controls, outputs=outputs)
    batch = gen.run(tr, recovery_tol=tol)
    stepper = gen.online(recovery_tol=tol)
    online = stepper.run(tr)
    _same(batch, online)
    stepper.reset()
    _same(stepper.run(tr), online)


# ------------------------------------------------------------------------------------------ evaluators
KINDS = ("threshold", "cusum", "glr", "sprt", "mhsprt", "gaussian_ml", "bnn")


def _res(r, valid=None):
    r = np.asarray(r, float)
    return Residuals(np.arange(len(r)) * 0.01, r, ("a", "b"), ("fa", "fb"), valid)


def _train(seed):
    rng = np.random.default_rng(seed)
    h = _res(rng.standard_normal((1500, 2)))
    fa = [_res(rng.standard_normal((200, 2)) * 0.5 + [s, 0.0]) for s in (1.5, 3.0)]
    fb = [_res(rng.standard_normal((200, 2)) * 0.5 + [0.0, s]) for s in (1.5, 3.0)]
    return h, fa, fb


def _fit(kind, seed=0):
    h, fa, fb = _train(seed)
    if kind == "threshold":
        return ThresholdEvaluator(persistence=(2, 3)).fit(h, false_alarm_prob=1e-2)
    if kind == "cusum":
        return CusumEvaluator(hold=2).fit(h, arl0=500.0, shift=1.0)
    if kind == "glr":
        return GlrEvaluator(window=8).fit(h, false_alarm_prob=1e-2)
    if kind == "sprt":
        return SprtEvaluator(shift=1.0, hold=1).fit(h)
    if kind == "mhsprt":
        return MhsprtEvaluator().fit({"none": h, "fa": fa, "fb": fb})
    data = {"none": [h], "fa": fa, "fb": fb}
    if kind == "gaussian_ml":
        return GaussianMlEvaluator(inputs="raw").fit(data)
    return BnnEvaluator(inputs="raw", max_iter=3, rm_steps=0).fit(data)


@cache
def _fitted(kind):
    return _fit(kind)


def _series(rng, N, shift_at, p_nan, p_rec):
    r = rng.standard_normal((N, 2))
    if shift_at < N:
        r[shift_at:] += rng.choice([[2.5, 0.0], [0.0, 2.5], [2.0, 2.0]])
    r[rng.random((N, 2)) < p_nan] = np.nan
    valid = np.isfinite(r).all(axis=1) & ~(rng.random(N) < p_rec)  # recovering: finite but not valid
    return _res(r, valid)


def _stepped(ev, res):
    out = [ev.step(res.r[k], valid=bool(res.valid[k])) for k in range(len(res))]
    return (np.array([s.alarm for s in out], bool), np.array([s.fired for s in out], bool),
            np.array([s.fault for s in out]), np.array([s.valid for s in out], bool))


def _assert_decisions(d, stepped):
    alarm, fired, fault, valid = stepped
    np.testing.assert_array_equal(d.alarm, alarm)
    np.testing.assert_array_equal(d.fired, fired.reshape(d.fired.shape))
    np.testing.assert_array_equal(d.isolated, fault)
    np.testing.assert_array_equal(d.valid, valid)


series = dict(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 120), shift_at=st.integers(0, 150),
              p_nan=st.sampled_from([0.0, 0.05, 0.2]), p_rec=st.sampled_from([0.0, 0.1, 0.3]))


def _property(kind):
    @settings(max_examples=25)
    @given(**series)
    def prop(seed, N, shift_at, p_nan, p_rec):
        ev = copy.deepcopy(_fitted(kind))
        rng = np.random.default_rng(seed)
        res = _series(rng, N, shift_at, p_nan, p_rec)
        d = ev.run(res)
        ev.reset()
        first = _stepped(ev, res)
        _assert_decisions(d, first)
        # a recovering sample (valid False, finite) is held exactly like a NaN one
        assert not (d.valid & ~res.valid).any()
        # reset then rerun equals a fresh run; another series after reset equals its batch run
        ev.reset()
        _assert_decisions(d, _stepped(ev, res))
        other = _series(rng, N, shift_at // 2, p_nan, p_rec)
        ev.reset()
        _assert_decisions(ev.run(other), _stepped(ev, other))

    prop.__name__ = f"test_{kind}_batch_equals_online_and_reset"
    return prop


for _kind in KINDS:
    globals()[f"test_{_kind}_batch_equals_online_and_reset"] = _property(_kind)


def test_refit_equals_a_fresh_fit():
    """fit() again on other data gives exactly the evaluator a fresh fit on that data gives."""
    rng = np.random.default_rng(5)
    res = _series(rng, 200, 100, 0.05, 0.1)
    for kind in KINDS:
        ev = _fit(kind, seed=0)
        ev.step([0.3, -0.2])  # some online state that the refit must discard
        h, fa, fb = _train(1)
        if kind == "threshold":
            ev.fit(h, false_alarm_prob=1e-2)
        elif kind == "cusum":
            ev.fit(h, arl0=500.0, shift=1.0)
        elif kind == "glr":
            ev.fit(h, false_alarm_prob=1e-2)
        elif kind == "sprt":
            ev.fit(h)
        elif kind == "mhsprt":
            ev.fit({"none": h, "fa": fa, "fb": fb})
        elif kind == "gaussian_ml":
            ev.fit({"none": [h], "fa": fa, "fb": fb})
        else:
            ev.fit({"none": [h], "fa": fa, "fb": fb})
        fresh = _fit(kind, seed=1)
        d, d_fresh = ev.run(res), fresh.run(res)
        np.testing.assert_array_equal(d.alarm, d_fresh.alarm, err_msg=kind)
        np.testing.assert_array_equal(d.isolated, d_fresh.isolated, err_msg=kind)
        _assert_decisions(d, _stepped(ev, res))
