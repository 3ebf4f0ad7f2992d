"""ResidualGenerator: batch vs online, convergence, internal form, continuous filters, bad data.

Oracles: the observer error dynamics written out by hand, ``scipy.signal.dlsim`` and
``scipy.signal.cont2discrete``, and the model itself for the gap rule (open-loop propagation through invalid samples).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from fdikit import DataError, FaultModel, ModelError
from fdikit.design import kalman, observer
from fdikit.faults import Bias, FaultScenario, Stuck
from fdikit.residuals import ResidualGenerator, Residuals
from fdikit.simulate import simulate
from fdikit.trace import Trace

DT = 0.05
OBS_POLES_D = [0.2, 0.35, 0.5, 0.7]
OBS_POLES_C = [-2.0, -3.0, -4.5, -6.0]


def _model(dt: float | None = DT, seed: int = 0) -> FaultModel:
    """4 states, 3 outputs ('a', 'b', 'c'), 2 controls, 1 disturbance, 2 noise inputs; sensor + actuator faults."""
    rng = np.random.default_rng(seed)
    n, p = 4, 3
    M = rng.standard_normal((n, n))
    Ac = M - (np.max(scipy.linalg.eigvals(M).real) + 0.3) * np.eye(n)
    m = FaultModel(
        A=Ac, C=rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 2)), Du=0.2 * rng.standard_normal((p, 2)),
        Bd=rng.standard_normal((n, 1)), Bw=0.3 * rng.standard_normal((n, 2)),
        outputs=["a", "b", "c"], controls=["u1", "u2"], disturbances=["gust"], noise=["w1", "w2"],
    )
    m = m.with_sensor_faults(["b"]).with_actuator_faults(["u2"])
    return m if dt is None else m.discretize(dt)


def _designs(model):
    poles = OBS_POLES_D if model.is_discrete else OBS_POLES_C
    return {
        "observer": observer(model, poles),
        "kalman": kalman(model, Q=np.diag([0.5, 0.2]), R=np.diag([0.01, 0.02, 0.01])),
    }


def _u(t):
    return np.column_stack([np.sin(0.9 * t), 0.5 + 0.3 * np.cos(2.1 * t)])


def _trace(model, scenario=None, duration=20.0, noise=True, x0=None, seed=1):
    """Noise=False also switches the disturbance off: the nominal, undisturbed plant."""
    kw = {"noise_std": [0.5, 0.2], "measurement_noise_std": [0.1, 0.14, 0.1]} if noise else {}
    dt = model.dt or DT
    t = np.arange(int(round(duration / dt)) + 1) * dt
    d = (lambda tk: [0.2 * np.sin(tk)]) if noise else None
    return simulate(model, scenario, t=t, u=_u(t), d=d, x0=x0, rng=seed, **kw)


def _relclose(a, b, rel=1e-12):
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * max(np.abs(b).max(), 1e-300))


# ---------------------------------------------------------------------------------------------- batch vs online


@pytest.mark.parametrize("kind", ["observer", "kalman"])
def test_run_equals_online_step(kind):
    model = _model()
    gen = _designs(model)[kind].generator
    tr = _trace(model, FaultScenario([Bias("b", 0.5, onset=8.0), Stuck("u2", onset=12.0)]))
    res = gen.run(tr)
    assert res.names == ("a", "b", "c") and res.r.shape == (len(tr), 3) and res.valid.all()
    stepper = gen.online()
    r_step = np.array([stepper.step(tr.u[k], tr.y[k]) for k in range(len(tr))])
    _relclose(res.r, r_step)
    _relclose(res.r, gen.online().run(tr).r)
    # with an initial filter state too
    z0 = np.array([0.3, -0.2, 0.1, 0.4])
    st = gen.online(x0=z0)
    _relclose(gen.run(tr, x0=z0).r, np.array([st.step(tr.u[k], tr.y[k]) for k in range(len(tr))]))
    assert res.meta["trace"]["seed"] == 1


@pytest.mark.parametrize("kind", ["observer", "kalman"])
def test_nominal_residual_decays_at_the_observer_rate(kind):
    model = _model()
    design = _designs(model)[kind]
    tr = _trace(model, noise=False, x0=[1.0, -0.5, 0.8, 0.3], duration=40.0)  # 801 samples
    r = np.linalg.norm(design.generator.run(tr).r, axis=1)
    assert r[0] > 0.1
    assert r[-1] < 1e-10 * r[0]
    rho = np.max(np.abs(design.poles))
    if kind == "observer":
        np.testing.assert_allclose(np.sort(np.abs(design.poles)), OBS_POLES_D, rtol=1e-8)
    # average decay over a window [k1, k2] where the slowest mode dominates (the next mode's share at k1 is
    # (0.5/0.7)^30 ~ 4e-5 for the observer, (0.928/0.958)^200 ~ 2e-3 for the Kalman filter, which moves the
    # averaged rate by ~share/(k2-k1) << 1e-3) and rounding does not (r[k2] >> 1e-16 r[0])
    k1, k2 = (30, 60) if kind == "observer" else (200, 400)
    rate = (r[k2] / r[k1]) ** (1 / (k2 - k1))
    assert rate == pytest.approx(rho, rel=1e-3)


def test_residual_equals_the_internal_form_response_to_a_fault():
    model = _model()
    gen = _designs(model)["observer"].generator
    tr = _trace(model, FaultScenario([Bias("b", 0.5, onset=3.0)]), noise=False)
    R = gen.internal_form(model)
    j = model.faults.index("b_sensor")
    f = 0.5 * (tr.t >= 3.0)
    _, r_f = scipy.signal.dlsim((R.A, R.Bf[:, [j]], R.C, R.Df[:, [j]], DT), f)[:2]
    # u and d reach r only through rounding, so the residual is the fault response
    _relclose(gen.run(tr).r, r_f, rel=1e-9)


# ---------------------------------------------------------------------------------------------- internal form


@pytest.mark.parametrize("dt", [DT, None])
@pytest.mark.parametrize("kind", ["observer", "kalman"])
def test_internal_form_decouples_u_and_gives_the_error_dynamics(dt, kind):
    model = _model(dt)
    design = _designs(model)[kind]
    L = design.gain
    R = design.generator.internal_form(model)
    assert R.outputs == ("a", "b", "c") and R.states == model.states + ("filter_0", "filter_1", "filter_2", "filter_3")
    for g in ("u", "d", "f", "w"):
        assert R.inputs[g] == model.inputs[g]
    assert R.dt == model.dt
    omega = np.array([0.0, 0.1, 1.0, 5.0, 30.0])
    scale = np.abs(model.freqresp(omega, "u")).max()
    assert np.abs(R.freqresp(omega, "u")).max() < 1e-10 * scale
    # e = x - x_hat obeys e' = (A - L C) e + (B_g - L D_g) g and r = C e + D_g g (y-channel groups)
    A, C = model.A, model.C
    for g in ("d", "f", "w"):
        Bg, Dg = model.b(g), model.d(g)
        for w in omega:
            z = np.exp(1j * w * dt) if dt else 1j * w
            ref = C @ np.linalg.solve(z * np.eye(4) - A + L @ C, Bg - L @ Dg) + Dg
            got = R.freqresp([w], g)[0]
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10 * max(1.0, np.abs(ref).max()))
    # the sensor fault reaches r: no accidental decoupling
    assert np.abs(R.freqresp(omega, "f")[:, :, model.faults.index("b_sensor")]).max() > 0.5


def test_internal_form_continuous_model_and_discrete_generator():
    mc = _model(None)
    gen = _designs(_model(DT))["observer"].generator
    R1 = gen.internal_form(mc)
    R2 = gen.internal_form(mc.discretize(DT))
    for attr in ("A", "B", "C", "D"):
        np.testing.assert_allclose(getattr(R1, attr), getattr(R2, attr), rtol=0, atol=1e-13)
    with pytest.raises(ModelError, match="continuous generator cannot be joined"):
        _designs(mc)["observer"].generator.internal_form(_model(DT))
    with pytest.raises(ModelError, match="differs from generator dt"):
        gen.internal_form(mc.discretize(0.1))


# ---------------------------------------------------------------------------------------------- continuous generator


def test_continuous_generator_runs_discretised_at_the_trace_dt():
    mc = _model(None)
    gen = _designs(mc)["observer"].generator
    assert gen.dt is None
    tr = _trace(mc, FaultScenario([Bias("a", 0.2, onset=5.0)]))
    res = gen.run(tr)
    _relclose(res.r, gen.discretize(DT).run(tr).r)
    Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((gen.A, gen.B, gen.C, gen.D), DT, method="zoh")
    _, r_ref, _ = scipy.signal.dlsim((Ad, Bd, Cd, Dd, DT), gen.inputs_from(tr))
    _relclose(res.r, r_ref, rel=1e-11)
    _relclose(gen.online(dt=DT).run(tr).r, res.r)
    with pytest.raises(ModelError, match="needs dt="):
        gen.online()
    with pytest.raises(ModelError, match="already discrete"):
        gen.discretize(DT).discretize(DT)


# ---------------------------------------------------------------------------------------------- bad data


def _with_nans(tr: Trace) -> Trace:
    u, y = tr.u.copy(), tr.y.copy()
    y[50, 1] = np.nan
    u[70, 0] = np.inf
    y[71, 2] = np.nan
    return Trace(t=tr.t, u=u, y=y, x=tr.x, controls=tr.controls, outputs=tr.outputs, states=tr.states,
                 fault=tr.fault, meta=tr.meta)


def test_run_handles_gaps_exactly_like_online():
    """Batch and online give the same residuals and flags on a trace with bad samples (gap rule)."""
    model = _model()
    gen = _designs(model)["kalman"].generator
    clean = _trace(model)
    bad = _with_nans(clean)
    batch = gen.run(bad)
    stepper = gen.online()
    online = stepper.run(bad)
    bad_k = [50, 70, 71]
    assert np.isnan(batch.r[bad_k]).all() and np.isnan(online.r[bad_k]).all()
    assert stepper.invalid == 3
    np.testing.assert_array_equal(batch.valid, online.valid)
    np.testing.assert_array_equal(batch.recovering, online.recovering)
    finite = np.isfinite(batch.r).all(axis=1)
    np.testing.assert_array_equal(finite, ~np.isin(np.arange(len(bad)), bad_k))
    _relclose(batch.r[finite], online.r[finite], rel=1e-10)
    # before the first gap: the clean run; recovering samples are finite but not valid
    _relclose(batch.r[:50], gen.run(clean).r[:50])
    assert batch.valid[:50].all() and not batch.valid[bad_k].any()
    assert np.isfinite(batch.r[batch.recovering]).all() and not batch.valid[batch.recovering].any()
    assert not batch.recovering[bad_k].any()


def test_gap_propagates_the_model_open_loop():
    """For an observer r = y − C x̂ − D u the gap rule feeds ŷ: the state follows x̂+ = A x̂ + B u (the model)."""
    model = _model()
    gen = _designs(model)["kalman"].generator
    assert np.allclose(gen.C, -model.C)  # the generator's state is x̂
    clean = _trace(model)
    st = gen.online()
    for k in range(30):
        st.step(clean.u[k], clean.y[k])
    x = st.x.copy()
    u = clean.u[30]
    assert np.isnan(st.step(u, [np.nan] * 3)).all() and not st.last_valid
    np.testing.assert_allclose(st.x, model.A @ x + model.Bu @ u, rtol=1e-12, atol=1e-12)
    # only output 'b' missing: it is replaced by its prediction, 'a' and 'c' are used
    x = st.x.copy()
    u, y = clean.u[31], clean.y[31].copy()
    y_hat = model.C @ x + model.Du @ u
    y_fed = y.copy()
    y_fed[1] = y_hat[1]
    ref = gen.online(x0=x)
    ref.step(u, y_fed)
    y[1] = np.nan
    st.step(u, y)
    np.testing.assert_allclose(st.x, ref.x, rtol=1e-12, atol=1e-12)
    # a missing control is held at its last valid value
    x = st.x.copy()
    ref = gen.online(x0=x)
    ref.step(clean.u[31], clean.y[32])
    st.step([np.nan, np.nan], clean.y[32])
    np.testing.assert_allclose(st.x, ref.x, rtol=1e-12, atol=1e-12)


def test_nan_in_unread_signal_is_no_bad_sample():
    model = _model()
    gen = _designs(model)["kalman"].generator
    clean = _trace(model)
    spare = np.full((len(clean), 1), np.nan)
    extra = Trace(t=clean.t, u=np.hstack([clean.u, spare]), y=clean.y, controls=clean.controls + ("spare",),
                  outputs=clean.outputs)
    _relclose(gen.run(extra).r, gen.run(clean).r)
    assert gen.online().run(extra).valid.all() and gen.run(extra).valid.all()


def test_step_with_wrong_vector_length():
    gen = _designs(_model())["observer"].generator
    st = gen.online()
    with pytest.raises(DataError, match=r"got 4 values; need 2 controls \['u1', 'u2'\] and 3 outputs"):
        st.step([0.0, 0.0], [0.0, 0.0])
    with pytest.raises(DataError, match="got 6 values"):
        st.step([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(st.x, np.zeros(4))  # a rejected call leaves the state alone


def test_dt_mismatch_is_a_data_error():
    model = _model()
    gen = _designs(model)["observer"].generator
    other = _trace(_model(None).discretize(0.1), noise=False)
    with pytest.raises(DataError, match=r"sampled at dt=0\.1 but the generator is discrete with dt=0\.05"):
        gen.run(other)
    with pytest.raises(DataError, match="resample"):
        gen.online(dt=0.1)


def test_online_run_checks_the_trace_sample_time_like_run():
    """``online().run(trace)`` must not silently filter data sampled at another rate than ``run`` refuses."""
    gen = _designs(_model())["observer"].generator
    other = _trace(_model(None).discretize(0.1), noise=False)
    with pytest.raises(DataError):
        gen.online().run(other)


def test_missing_signal_in_trace():
    gen = _designs(_model())["observer"].generator
    tr = _trace(_model())
    slim = Trace(t=tr.t, u=tr.u, y=tr.y[:, :2], controls=tr.controls, outputs=["a", "b"])
    with pytest.raises(DataError, match=r"missing outputs \['c'\]"):
        gen.run(slim)
    with pytest.raises(DataError, match=r"missing outputs \['c'\]"):
        gen.online().run(slim)


# ---------------------------------------------------------------------------------------------- containers


def test_generator_validation():
    with pytest.raises(ModelError, match=r"B has 2 columns but must have 3 \(shape \(2, 2\)\)"):
        ResidualGenerator(A=np.eye(2), B=np.zeros((2, 2)), C=np.zeros((1, 2)), D=np.zeros((1, 3)),
                          controls=["u"], outputs=["a", "b"], residuals=["r"], dt=0.1)
    with pytest.raises(ModelError, match="non-finite"):
        ResidualGenerator(A=[[np.nan]], B=np.zeros((1, 1)), C=[[1.0]], D=[[0.0]], controls=[], outputs=["a"],
                          residuals=["r"], dt=0.1)
    with pytest.raises(ModelError, match="'isolates' entries"):
        ResidualGenerator(A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]], controls=[], outputs=["a"], residuals=["r"],
                          dt=0.1, isolates=["x", "y"])
    with pytest.raises(ModelError, match="dt must be positive"):
        ResidualGenerator(A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]], controls=[], outputs=["a"], residuals=["r"],
                          dt=0.0)


def test_static_generator_without_states():
    gen = ResidualGenerator(A=np.zeros((0, 0)), B=np.zeros((0, 3)), C=np.zeros((1, 0)), D=[[1.0, -1.0, 0.0]],
                            controls=[], outputs=["a", "b", "c"], residuals=["a-b"], dt=DT, isolates=["a_sensor"])
    tr = _trace(_model())
    res = gen.run(tr)
    np.testing.assert_allclose(res.r[:, 0], tr.y[:, 0] - tr.y[:, 1], rtol=0, atol=1e-15 * np.abs(tr.y).max())
    assert res.isolates == ("a_sensor",)


def test_residuals_container():
    t = np.arange(10) * 0.5
    res = Residuals(t, np.arange(20.0).reshape(10, 2), ["r1", "r2"], [None, "f"])
    part = res.slice(1.0, 3.0)
    np.testing.assert_array_equal(part.t, [1.0, 1.5, 2.0, 2.5])
    np.testing.assert_array_equal(part.r, res.r[2:6])
    df = res.to_pandas()
    assert list(df.columns) == ["r1", "r2", "valid", "recovering"] and df["valid"].all() and not df["recovering"].any()
    with pytest.raises(DataError, match=r"residuals have shape \(10, 2\), need \(10, 3\)"):
        Residuals(t, res.r, ["a", "b", "c"], ())
