"""Fault signals, scenarios, spec parsing, and faults applied in simulation.

Every fault kind is checked sample by sample against its defining formula, with the samples
before onset and after end compared for exact equality with the clean signal.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from fdikit import FaultModel, ParameterError
from fdikit.fault_spec import parse_fault
from fdikit.faults import (
    NO_FAULT,
    Bias,
    Drift,
    FaultScenario,
    Intermittent,
    LossOfEffectiveness,
    Noise,
    ScaleFactor,
    Stuck,
)
from fdikit.simulate import simulate, time_grid

DT = 0.01
T = time_grid(30.0, DT)  # the grid simulate() uses
ONSET, END = 10.0, 20.0


def _clean(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.sin(0.7 * T) + 0.1 * rng.standard_normal(T.size) + 2.0


def _windows(onset=ONSET, end=END):
    before = T < onset
    during = (T >= onset) & (T < end) if end is not None else T >= onset
    after = ~before & ~during
    return before, during, after


def _check_untouched(v, out, onset=ONSET, end=END):
    before, _, after = _windows(onset, end)
    np.testing.assert_array_equal(out[before], v[before])
    np.testing.assert_array_equal(out[after], v[after])


# ---------------------------------------------------------------------------------------------- single kinds


@pytest.mark.parametrize("end", [END, None])
def test_bias(end):
    v = _clean()
    out = Bias("a", 0.25, onset=ONSET, end=end).apply(T, v)
    _check_untouched(v, out, end=end)
    _, during, _ = _windows(end=end)
    np.testing.assert_array_equal(out[during], v[during] + 0.25)
    assert during.sum() == (1000 if end else 2001)  # 10.00 ... 19.99 / 10.00 ... 30.00


def test_drift_value_is_rate_times_time_since_onset():
    v = _clean()
    out = Drift("a", rate=-0.3, onset=ONSET, end=END).apply(T, v)
    _check_untouched(v, out)
    _, during, _ = _windows()
    np.testing.assert_allclose(out[during] - v[during], -0.3 * (T[during] - ONSET), rtol=0, atol=1e-14)
    assert out[np.argmax(during)] == v[np.argmax(during)]  # a ramp starts at zero


def test_stuck_holds_value_at_onset():
    v = _clean()
    out = Stuck("a", onset=ONSET, end=END).apply(T, v)
    _check_untouched(v, out)
    _, during, _ = _windows()
    k0 = int(np.argmax(during))
    assert T[k0] == pytest.approx(ONSET) and T[k0 - 1] < ONSET
    np.testing.assert_array_equal(out[during], np.full(during.sum(), v[k0]))


def test_stuck_holds_a_given_value():
    v = _clean()
    out = Stuck("a", value=-4.5, onset=ONSET, end=END).apply(T, v)
    _check_untouched(v, out)
    _, during, _ = _windows()
    np.testing.assert_array_equal(out[during], -4.5)


@pytest.mark.parametrize("loss", [0.0, 0.3, 1.0])
def test_loss_of_effectiveness(loss):
    v = _clean()
    out = LossOfEffectiveness("a", loss=loss, onset=ONSET, end=END).apply(T, v)
    _check_untouched(v, out)
    _, during, _ = _windows()
    np.testing.assert_array_equal(out[during], (1.0 - loss) * v[during])


@pytest.mark.parametrize(("loss", "pattern"), [(-0.01, r"must be in \[0, 1\]"), (1.01, r"must be in \[0, 1\]"),
                                               (np.nan, "loss must be a finite number")])
def test_loss_of_effectiveness_outside_unit_interval(loss, pattern):
    with pytest.raises(ParameterError, match=pattern):
        LossOfEffectiveness("a", loss=loss)


def test_scale_factor():
    v = _clean()
    out = ScaleFactor("a", factor=1.7, onset=ONSET, end=END).apply(T, v)
    _check_untouched(v, out)
    _, during, _ = _windows()
    np.testing.assert_array_equal(out[during], 1.7 * v[during])


def test_noise_std_within_chi_square_tolerance_and_zero_mean():
    v = _clean()
    std = 0.4
    out = Noise("a", std=std, onset=ONSET, end=END).apply(T, v, np.random.default_rng(42))
    _check_untouched(v, out)
    _, during, _ = _windows()
    e = out[during] - v[during]
    n = e.size
    # (n-1) s^2 / sigma^2 ~ chi2(n-1): two-sided 1e-6 quantiles
    lo, hi = scipy.stats.chi2.ppf([1e-6, 1 - 1e-6], n - 1)
    s2 = e.var(ddof=1)
    assert lo <= (n - 1) * s2 / std**2 <= hi
    assert abs(e.mean()) < 5 * std / np.sqrt(n)
    # same generator state, same noise; another seed, other noise
    again = Noise("a", std=std, onset=ONSET, end=END).apply(T, v, np.random.default_rng(42))
    np.testing.assert_array_equal(out, again)
    other = Noise("a", std=std, onset=ONSET, end=END).apply(T, v, np.random.default_rng(43))
    assert np.all(other[during] != out[during])


def test_noise_needs_rng_and_nonnegative_std():
    with pytest.raises(ParameterError, match="numpy.random.Generator"):
        Noise("a", std=0.1).apply(T, _clean())
    with pytest.raises(ParameterError, match="std must be >= 0"):
        Noise("a", std=-0.1)


@pytest.mark.parametrize(
    ("onset", "period", "duty", "dt"),
    [
        (10.0, 1.0, 0.5, 0.01),
        (10.0, 1.0, 0.3, 0.01),
        (2.37, 0.7, 0.3, 0.01),
        (1.1, 1.0, 0.4, 0.1),
        (0.7, 0.6, 0.5, 0.1),
    ],
)
def test_intermittent_active_samples_per_period_equal_duty(onset, period, duty, dt):
    t = time_grid(40.0, dt)
    v = np.cos(t)
    f = Intermittent("a", size=0.5, period=period, duty=duty, onset=onset)
    out = f.apply(t, v)
    k = np.rint((t - onset) / dt).astype(int)  # sample index since onset (integers by construction)
    per, on = round(period / dt), round(duty * period / dt)
    expected = (k >= 0) & (np.mod(k, per) < on)
    changed = out != v
    full = (k >= 0) & (k < per * ((k.max() + 1) // per))
    counts = np.add.reduceat(changed[full].astype(int), np.arange(0, full.sum(), per))
    np.testing.assert_array_equal(counts, on)  # exactly duty*period/dt active samples in every period
    np.testing.assert_array_equal(changed, expected)
    np.testing.assert_array_equal(out[expected], v[expected] + 0.5)


def test_intermittent_validation():
    with pytest.raises(ParameterError, match="period > 0"):
        Intermittent("a", period=0.0)
    with pytest.raises(ParameterError, match="0 < duty <= 1"):
        Intermittent("a", duty=0.0)
    with pytest.raises(ParameterError, match="0 < duty <= 1"):
        Intermittent("a", duty=1.5)


def test_fault_construction_validation():
    with pytest.raises(ParameterError, match="must be after its onset"):
        Bias("a", 1.0, onset=5.0, end=5.0)
    with pytest.raises(ParameterError, match="onset must be a finite number"):
        Bias("a", 1.0, onset=np.inf)
    with pytest.raises(ParameterError, match="'sensor' or 'actuator'"):
        Bias("a", 1.0, location="engine")
    with pytest.raises(ParameterError, match="name of the signal"):
        Bias("", 1.0)
    with pytest.raises(ParameterError, match="no location yet"):
        _ = Bias("a", 1.0).name


# ---------------------------------------------------------------------------------------------- scenarios

OUTPUTS = ("yaw_rate", "speed", "steer")
CONTROLS = ("steer", "throttle")


def test_resolve_fixes_location_from_names():
    sc = FaultScenario([Bias("yaw_rate", 0.1), Bias("throttle", 0.2), Bias("steer", 0.3, location="actuator")])
    r = sc.resolve(OUTPUTS, CONTROLS)
    assert [f.location for f in r] == ["sensor", "actuator", "actuator"]
    assert [f.name for f in r] == ["yaw_rate_sensor", "throttle_actuator", "steer_actuator"]
    assert r.label == "yaw_rate_sensor+throttle_actuator+steer_actuator"
    assert sc.label == "yaw_rate+throttle+steer_actuator"  # unresolved targets keep their bare names
    assert FaultScenario([Bias("yaw_rate", 0.1)], label="gyro").resolve(OUTPUTS, CONTROLS).label == "gyro"


def test_resolve_errors_name_the_plant_signals():
    with pytest.raises(ParameterError, match=r"both an output and a control"):
        FaultScenario([Bias("steer", 0.1)]).resolve(OUTPUTS, CONTROLS)
    with pytest.raises(ParameterError, match=r"no sensor named 'throttle'.*\['yaw_rate', 'speed', 'steer'\]"):
        FaultScenario([Bias("throttle", 0.1, location="sensor")]).resolve(OUTPUTS, CONTROLS)
    with pytest.raises(ParameterError, match=r"no actuator named 'speed'.*\['steer', 'throttle'\]"):
        FaultScenario([Bias("speed", 0.1, location="actuator")]).resolve(OUTPUTS, CONTROLS)
    with pytest.raises(
        ParameterError, match=r"no signal named 'brake'.*\['yaw_rate', 'speed', 'steer'\].*\['steer', 'throttle'\]"
    ):
        FaultScenario([Bias("brake", 0.1)]).resolve(OUTPUTS, CONTROLS)
    with pytest.raises(ParameterError, match="holds Fault objects"):
        FaultScenario(["bias:speed:1"])


def test_truth_labels_with_overlap_and_none():
    sc = FaultScenario(
        [Bias("speed", 1.0, onset=5.0, end=15.0), Drift("throttle", rate=0.1, onset=10.0)]
    ).resolve(OUTPUTS, CONTROLS)
    truth = sc.truth(T)
    assert truth.shape == T.shape
    expect = np.full(T.size, NO_FAULT, dtype=object)
    expect[(T >= 5) & (T < 10)] = "speed_sensor"
    expect[(T >= 10) & (T < 15)] = "speed_sensor+throttle_actuator"
    expect[T >= 15] = "throttle_actuator"
    np.testing.assert_array_equal(truth, expect.astype(str))
    assert set(truth.tolist()) == {"none", "speed_sensor", "speed_sensor+throttle_actuator", "throttle_actuator"}
    np.testing.assert_array_equal(FaultScenario().truth(T), np.full(T.size, "none"))
    assert FaultScenario().label == "none" and len(FaultScenario()) == 0


# ---------------------------------------------------------------------------------------------- parse_fault


def test_parse_fault_specs():
    f = parse_fault("bias:yaw_rate:0.02@10")
    assert isinstance(f, Bias) and f.target == "yaw_rate" and f.size == 0.02 and f.onset == 10.0 and f.end is None
    f = parse_fault("bias:yaw_rate:-0.5@10-20")
    assert f.size == -0.5 and f.onset == 10.0 and f.end == 20.0
    f = parse_fault("stuck:steer@3.5")
    assert isinstance(f, Stuck) and f.value is None and f.onset == 3.5
    f = parse_fault("stuck:steer:0.1")
    assert f.value == 0.1 and f.onset == 0.0
    f = parse_fault("ramp:speed:2e-3@1")
    assert isinstance(f, Drift) and f.rate == 0.002
    assert isinstance(parse_fault("drift:speed:1"), Drift)
    f = parse_fault("loe:throttle:0.4@2.5-7.5")
    assert isinstance(f, LossOfEffectiveness) and f.loss == 0.4 and (f.onset, f.end) == (2.5, 7.5)
    assert parse_fault("scale:speed:1.1").factor == 1.1
    assert parse_fault("noise:speed:0.3").std == 0.3
    f = parse_fault("intermittent:speed:0.2@4")
    assert isinstance(f, Intermittent) and f.size == 0.2 and f.period == 1.0 and f.duty == 0.5
    assert parse_fault("  bias:a.b:1  ").target == "a.b"


def test_parse_fault_onset_in_exponent_notation():
    """``[^-@]+`` for the onset splits ``5e-1`` at its minus sign (onset '5e', end '1')."""
    f = parse_fault("bias:speed:1@5e-1")
    assert (f.onset, f.end) == (0.5, None)
    f = parse_fault("bias:speed:1@5e-1-2.5")
    assert (f.onset, f.end) == (0.5, 2.5)


@pytest.mark.parametrize(
    ("spec", "pattern"),
    [
        ("kaboom:speed:1", "cannot read fault spec"),
        ("bias", "cannot read fault spec"),
        ("bias:speed", "needs a value"),
        ("bias:speed:abc", "cannot be read"),
        ("bias:speed:1@x", "cannot read fault spec"),
        ("bias:speed:1@20-10", "must be after its onset"),
        ("loe:speed:1.5", r"\[0, 1\]"),
        ("noise:speed:-1", "std must be >= 0"),
    ],
)
def test_parse_fault_bad_specs(spec, pattern):
    with pytest.raises(ParameterError, match=pattern):
        parse_fault(spec)


# ---------------------------------------------------------------------------------------------- in simulation


def _plant() -> FaultModel:
    A = np.array([[0.0, 1.0, 0.0], [-2.0, -0.8, 0.5], [0.0, 0.0, -1.5]])
    Bu = np.array([[0.0, 0.0], [1.0, 0.2], [0.3, 1.0]])
    C = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    return FaultModel(A=A, C=C, Bu=Bu, outputs=["pos", "vel", "load"], controls=["force", "valve"],
                      states=["x", "v", "l"])


SIM_T = time_grid(6.0, 0.02)
SIM_ONSET, SIM_END = 2.0, 4.5
KINDS = {
    "bias": lambda tgt: Bias(tgt, 0.3, onset=SIM_ONSET, end=SIM_END),
    "drift": lambda tgt: Drift(tgt, rate=0.2, onset=SIM_ONSET, end=SIM_END),
    "stuck": lambda tgt: Stuck(tgt, onset=SIM_ONSET, end=SIM_END),
    "stuck_value": lambda tgt: Stuck(tgt, value=-0.4, onset=SIM_ONSET, end=SIM_END),
    "loe": lambda tgt: LossOfEffectiveness(tgt, loss=0.6, onset=SIM_ONSET, end=SIM_END),
    "scale": lambda tgt: ScaleFactor(tgt, factor=1.5, onset=SIM_ONSET, end=SIM_END),
    "noise": lambda tgt: Noise(tgt, std=0.2, onset=SIM_ONSET, end=SIM_END),
    "intermittent": lambda tgt: Intermittent(tgt, size=0.3, period=0.5, duty=0.4, onset=SIM_ONSET, end=SIM_END),
}


def _u(t):
    return np.column_stack([1.0 + 0.5 * np.sin(1.3 * t), 0.8 + 0.3 * np.cos(0.9 * t)])


def _run(scenario=None, seed=123):
    return simulate(_plant(), scenario, t=SIM_T, u=_u(SIM_T), x0=[0.2, -0.1, 0.5],
                    measurement_noise_std=[0.01, 0.02, 0.01], rng=seed)


@pytest.mark.parametrize("kind", list(KINDS))
def test_sensor_fault_changes_only_its_own_output(kind):
    clean = _run()
    fault = KINDS[kind]("vel")
    tr = _run(FaultScenario([fault]))
    j = 1
    others = [0, 2]
    np.testing.assert_array_equal(tr.y[:, others], clean.y[:, others])
    np.testing.assert_array_equal(tr.x, clean.x)
    np.testing.assert_array_equal(tr.u, clean.u)
    before, after = SIM_T < SIM_ONSET, SIM_T >= SIM_END
    np.testing.assert_array_equal(tr.y[before | after, j], clean.y[before | after, j])
    during = ~before & ~after
    if kind != "noise":  # deterministic kinds: exactly the fault's formula applied to the clean measurement
        np.testing.assert_array_equal(tr.y[:, j], fault.apply(SIM_T, clean.y[:, j]))
    assert np.any(tr.y[during, j] != clean.y[during, j])
    np.testing.assert_array_equal(tr.fault, np.where(fault.active(SIM_T), "vel_sensor", "none"))
    assert not np.any(fault.active(SIM_T)[before | after])
    assert tr.meta["scenario"] == "vel_sensor" and tr.meta["seed"] == 123


@pytest.mark.parametrize("kind", list(KINDS))
def test_actuator_fault_changes_outputs_only_from_onset_and_u_stays_commanded(kind):
    clean = _run()
    fault = KINDS[kind]("valve")
    tr = _run(FaultScenario([fault]))
    np.testing.assert_array_equal(tr.u, _u(SIM_T))  # the trace logs the command, not the faulty actuator
    before = SIM_T < SIM_ONSET
    # the same seed gives the same fault-free samples: nothing before onset may change
    np.testing.assert_array_equal(tr.y[before], clean.y[before])
    np.testing.assert_array_equal(tr.x[before], clean.x[before])
    # with no feedthrough the state reacts one sample after the onset sample
    k0 = int(np.argmax(~before))
    np.testing.assert_array_equal(tr.x[k0], clean.x[k0])
    assert np.any(tr.x[k0 + 1 :] != clean.x[k0 + 1 :])
    if kind != "noise":
        # independent: simulate the fault-free plant driven by the faulty actuator signal
        u_act = _u(SIM_T)
        u_act[:, 1] = fault.apply(SIM_T, u_act[:, 1])
        ref = simulate(_plant(), t=SIM_T, u=u_act, x0=[0.2, -0.1, 0.5], measurement_noise_std=[0.01, 0.02, 0.01],
                       rng=123)
        np.testing.assert_array_equal(tr.x, ref.x)
        np.testing.assert_array_equal(tr.y, ref.y)
