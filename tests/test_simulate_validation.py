"""simulate() never returns a silent wrong answer (issue 12, item 3) and is deterministic per seed (item 8).

* A fault changes no sample before its onset: for any finite fault of every kind on a linear
  plant (with process and measurement noise and a non-zero input), the samples before the onset
  are bit-identical to the fault-free run with the same seed (hypothesis).  The block solver
  works on 32-sample blocks whose later-sample entries are exact zeros, so only a non-finite
  input could leak backwards (``inf * 0 = NaN``); such inputs are refused before the solver.
* The same seed gives bit-identical traces, different seeds differ (hypothesis, linear and
  nonlinear paths).
* A run that would overflow raises a DataError naming the first bad sample, the signal and the
  unstable eigenvalue; the first bad sample is checked against an independent computation of
  when ``e^{a t}`` (or ``|λ|^k``) leaves the float range.
* A fault that acts on no sample warns; a run that would not fit in memory is refused at once.
"""

from __future__ import annotations

import math
import re
import time
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fdikit.errors import DataError, FdiWarning, ParameterError
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
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.simulate import NonlinearPlant, simulate, simulate_scheduled
from fdikit.simulate_checks import _available_memory
from fdikit.simulate_checks import simulation_bytes as _simulation_bytes

LN_MAX = math.log(np.finfo(float).max)  # 709.78: e^x overflows for x above this

A = np.array([[0.0, 1.0, 0.0], [-4.0, -0.6, 0.8], [0.0, 0.3, -2.0]])


def plant() -> FaultModel:
    """Stable, 3 states, 2 controls, a disturbance and a 3-channel noise group."""
    return FaultModel(A=A, C=[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]], Bu=[[0.0, 0.0], [1.0, -0.5], [0.2, 1.0]],
                      Du=[[0.0, 0.1], [0.0, 0.0]], Bd=[[0.1], [0.0], [0.5]], Bw=0.3 * np.eye(3),
                      outputs=["pos", "rate"], controls=["u1", "u2"], disturbances=["gust"],
                      noise=["w1", "w2", "w3"], states=["p", "v", "q"])


DT, DURATION = 0.05, 8.0  # 161 samples: five full 32-sample blocks and one partial
T = np.arange(161) * DT
U = np.column_stack([np.sin(1.1 * T), np.sign(np.sin(0.4 * T))])
D = 0.5 * np.cos(2.3 * T)


def run(scenario=None, rng=7, **kw):
    return simulate(plant(), scenario, duration=DURATION, dt=DT, u=U, d=D, x0=[0.4, -0.2, 0.1],
                    noise_std=[0.1, 0.2, 0.05], measurement_noise_std=[0.01, 0.02], rng=rng, **kw)


SIZE = st.floats(-1e100, 1e100, allow_nan=False)


@st.composite
def any_fault(draw):
    """Any finite fault of any kind on any signal of plant(), acting at some time inside the run."""
    target = draw(st.sampled_from(["pos", "rate", "u1", "u2"]))
    onset = draw(st.floats(DT / 2, DURATION))
    kw = {"onset": onset}
    if draw(st.booleans()):
        kw["end"] = onset + draw(st.floats(DT, DURATION))
    kind = draw(st.sampled_from(range(7)))
    if kind == 0:
        return Bias(target, draw(SIZE), **kw)
    if kind == 1:
        return Drift(target, rate=draw(SIZE), **kw)
    if kind == 2:
        return Stuck(target, value=draw(st.one_of(st.none(), SIZE)), **kw)
    if kind == 3:
        return LossOfEffectiveness(target, loss=draw(st.floats(0, 1)), **kw)
    if kind == 4:
        return ScaleFactor(target, factor=draw(SIZE), **kw)
    if kind == 5:
        return Noise(target, std=draw(st.floats(0, 1e100)), **kw)
    return Intermittent(target, size=draw(SIZE), period=draw(st.floats(0.01, 5.0)), duty=draw(st.floats(0.01, 1.0)),
                        **kw)


@settings(max_examples=60)
@given(st.lists(any_fault(), min_size=1, max_size=3), st.integers(0, 2**31 - 1))
def test_no_fault_changes_a_sample_before_its_onset(faults, seed):
    """Bit-identical before the earliest onset, for every kind, size and signal (1e100 sizes included)."""
    ref = run(rng=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FdiWarning)  # a short-duty intermittent fault may hit no sample
        tr = run(FaultScenario(faults), rng=seed)
    before = T < min(f.onset for f in faults)
    assert before.any()
    for block in ("y", "x", "u", "d"):
        assert getattr(tr, block)[before].tobytes() == getattr(ref, block)[before].tobytes(), block
    assert (tr.fault[before] == "none").all()
    assert np.all(np.isfinite(tr.y)) and np.all(np.isfinite(tr.x))


@settings(max_examples=30)
@given(st.integers(0, 2**31 - 1), st.integers(0, 2**31 - 1))
def test_same_seed_same_trace_other_seed_differs(seed, other):
    scenario = FaultScenario([Noise("pos", std=0.5, onset=2.0), Bias("u1", 0.3, onset=4.0)])
    a, b = run(scenario, rng=seed), run(scenario, rng=seed)
    for block in ("y", "x", "u"):
        assert getattr(a, block).tobytes() == getattr(b, block).tobytes()
    assert a.meta["seed"] == seed
    if other != seed:
        c = run(scenario, rng=other)
        # continuous noise: two seeds give the same draw with probability 0, so every sample differs
        assert np.all(c.y != a.y) and np.all(c.x[1:] != a.x[1:])
        np.testing.assert_array_equal(c.x[0], a.x[0])


def _pendulum() -> NonlinearPlant:
    return NonlinearPlant(f=lambda t, x, u: np.array([x[1], -9.81 * np.sin(x[0]) - 0.2 * x[1] + u[0]]),
                          h=lambda t, x, u: x[:1].copy(), states=["angle", "rate"], outputs=["angle"],
                          controls=["torque"], x0=[0.3, 0.0])


@settings(max_examples=10)
@given(st.integers(0, 2**31 - 1), st.integers(0, 2**31 - 1))
def test_nonlinear_path_is_deterministic_per_seed(seed, other):
    kw = {"duration": 2.0, "dt": 0.02, "noise_std": [1e-4, 1e-3], "measurement_noise_std": 0.01,
          "u": lambda tk: [0.1 * np.sin(tk)]}
    a, b = simulate(_pendulum(), rng=seed, **kw), simulate(_pendulum(), rng=seed, **kw)
    assert a.y.tobytes() == b.y.tobytes() and a.x.tobytes() == b.x.tobytes()
    if other != seed:
        assert np.all(simulate(_pendulum(), rng=other, **kw).y != a.y)


# ---------------------------------------------------------------------------------------------- block solver


def test_the_block_solver_would_leak_inf_backwards_so_inf_never_reaches_it():
    """The issue's case: an inf from sample 100 on made NaN of the earlier samples of its 32-block.  The
    solver itself now refuses it (naming the first bad sample), and simulate refuses it earlier still."""
    m = plant().discretize(DT)
    v = np.zeros((161, 6))  # u1, u2, gust, w1..w3
    v[100:, 0] = np.inf
    with pytest.raises(DataError, match=r"v \(the input sequence\) has a non-finite entry at row 100, column 0"):
        dlsim_blocked(m.A, m.B, m.C, m.D, v)
    with pytest.raises(ParameterError, match="size must be a finite number"):
        Bias("u1", np.inf, onset=5.0)
    with pytest.raises(DataError, match=r"u has a non-finite value inf in signal 'u1' at sample 100 \(t=5 s\)"):
        simulate(plant(), duration=DURATION, dt=DT, u=np.where(np.arange(161)[:, None] >= 100, [np.inf, 0], 0))
    # a finite fault that overflows to inf is refused before the solver, naming the fault: 1e308 (t - 5)
    # passes the float maximum 1.797e308 at the first sample with t - 5 > 1.797
    k = math.floor((5.0 + np.finfo(float).max / 1e308) / DT) + 1
    with pytest.raises(DataError, match=rf"Drift fault .* 'u1' non-finite \(inf\) at sample {k} \(t={k * DT:g} s\)"):
        run(FaultScenario([Drift("u1", rate=1e308, onset=5.0)]))


def test_huge_finite_bias_leaves_the_samples_before_its_block_position_alone():
    ref = run()
    tr = run(FaultScenario([Bias("u2", 1e300, onset=5.0)]))  # onset at sample 100, inside the block 96..127
    assert tr.y[:100].tobytes() == ref.y[:100].tobytes()
    assert np.all(np.isfinite(tr.y)) and np.abs(tr.x[101:]).max() > 1e290


# ---------------------------------------------------------------------------------------------- non-finite runs


def test_unstable_continuous_plant_names_sample_state_and_eigenvalue():
    m = FaultModel(A=[[0.5, 0.0], [0.0, -1.0]], C=np.eye(2), Bu=[[1.0], [1.0]], outputs=["a", "b"],
                   controls=["u"], states=["xa", "xb"])
    # x_a(k) = e^{0.5 * 0.5 k} exactly grows past the float range at the first k with 0.25 k > ln(max)
    k = math.floor(LN_MAX / 0.25) + 1
    with pytest.raises(DataError) as info:
        simulate(m, duration=3000.0, dt=0.5, x0=[1.0, 0.0])
    msg = str(info.value)
    assert f"state 'xa' is inf at sample {k} (t={k * 0.5:g} s)" in msg
    assert "unstable" in msg and "λ = 0.5" in msg and "Re λ = 0.5 > 0" in msg


def test_unstable_discrete_plant_names_modulus():
    m = FaultModel(A=[[1.5]], C=[[1.0]], Bu=[[1.0]], outputs=["y"], controls=["u"], states=["x"], dt=0.1)
    k = math.floor(LN_MAX / math.log(1.5)) + 1
    with pytest.raises(DataError) as info:
        simulate(m, duration=400.0, x0=[1.0])
    msg = str(info.value)
    assert f"state 'x' is inf at sample {k} " in msg and "|λ| = 1.5 > 1" in msg


def test_stable_plant_with_huge_input_blames_the_input():
    m = FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[10.0]], outputs=["y"], controls=["u"], states=["x"])
    with pytest.raises(DataError, match="the plant is stable, so its inputs are too large"):
        simulate(m, duration=5.0, dt=0.1, u=np.full(51, 1e308))


def test_unstable_nonlinear_plant_names_the_state():
    blowup = NonlinearPlant(f=lambda t, x, u: x**3, h=lambda t, x, u: x, states=["a"], outputs=["a"], controls=[],
                            x0=[10.0])
    with pytest.raises(DataError, match=r"state 'a' became non-finite .* at sample \d+ \(t=[\d.]+ s\)"):
        simulate(blowup, duration=5.0, dt=0.5, substeps=1)
    linear_unstable = NonlinearPlant(f=lambda t, x, u: 0.8 * x, h=lambda t, x, u: x, states=["a"], outputs=["a"],
                                     controls=[], x0=[1.0])
    with pytest.raises(DataError, match=r"Jacobian of f .* Re λ = 0.8 > 0"):
        simulate(linear_unstable, duration=1000.0, dt=1.0)


def test_scheduled_unstable_names_first_bad_sample():
    def family(rho):
        return FaultModel(A=[[1.0 + 0.01 * rho]], C=[[1.0]], Bu=[[1.0]], outputs=["y"], controls=["u"],
                          states=["x"], dt=0.1)

    rho = np.repeat(np.linspace(10, 20, 50), 200)
    x, k = 1.0, 0  # the same recursion in plain floats: x(k+1) = (1 + 0.01 ρ_k) x(k)
    while math.isfinite(x):
        x = (1.0 + 0.01 * float(rho[k])) * x
        k += 1
    with pytest.raises(DataError) as info:
        simulate_scheduled(family, rho, x0=[1.0])
    msg = str(info.value)
    assert f"at sample {k} (t={k * 0.1:g} s)" in msg and "unstable" in msg and "|λ|" in msg


# ---------------------------------------------------------------------------------------------- warnings, memory


def test_fault_after_the_run_warns_and_leaves_the_run_fault_free():
    with pytest.warns(FdiWarning, match="onset 50 s lies after the end of the run"):
        tr = run(FaultScenario([Bias("pos", 1.0, onset=50.0)]))
    assert (tr.fault == "none").all()
    assert tr.y.tobytes() == run().y.tobytes()
    with pytest.warns(FdiWarning, match="before the run starts"):
        simulate(plant(), FaultScenario([Bias("pos", 1.0, onset=-5.0, end=-1.0)]), duration=1.0, dt=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FdiWarning)
        run(FaultScenario([Bias("pos", 1.0, onset=DURATION)]))  # acts on the last sample: no warning


def test_huge_duration_is_refused_at_once_with_the_size():
    for duration, dt in ((1e12, 1e-3), (1e300, 1e-300), (3.6e6, 1e-4)):
        start = time.perf_counter()
        with pytest.raises(ParameterError, match=r"needs about .* bytes .* of memory .* available"):
            simulate(plant(), duration=duration, dt=dt)
        assert time.perf_counter() - start < 1.0


def test_memory_estimate_against_a_small_budget(monkeypatch):
    """With 1 MiB available, 100 samples run and 100 000 are refused with the bytes they need."""
    import fdikit.simulate_checks as sim

    monkeypatch.setattr(sim, "_available_memory", lambda: (2.0**20, "test budget"))
    simulate(plant(), duration=99 * DT, dt=DT)
    need = _simulation_bytes(100_001, 3, 2, 2, 1, 2 + 1 + 0 + 3, 0)
    with pytest.raises(ParameterError, match=re.escape(f"needs about {need:.3g} bytes")):
        simulate(plant(), duration=100_000 * DT, dt=DT)
    # per sample at least the float64 arrays of the trace itself: t, u, y, x, d
    assert need >= 100_001 * 8 * (1 + 2 + 2 + 3 + 1)


def test_available_memory_reads_meminfo_or_falls_back(tmp_path):
    fake = tmp_path / "meminfo"
    fake.write_text("MemTotal: 100 kB\nMemAvailable:    2048 kB\n")
    assert _available_memory(str(fake)) == (2048 * 1024.0, f"MemAvailable in {fake}")
    nbytes, source = _available_memory(str(tmp_path / "missing"))
    assert nbytes > 0 and "MemAvailable" not in source


# ---------------------------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("kwargs", "error", "pattern"),
    [
        ({"x0": [np.nan, 0.0, 0.0]}, ParameterError, "x0 must be finite"),
        ({"measurement_noise_std": -0.1}, ParameterError, "measurement_noise_std holds standard deviations.*>= 0"),
        ({"measurement_noise_std": [0.1, np.inf]}, ParameterError, "measurement_noise_std must be finite"),
        ({"noise_std": [0.1, -0.2, 0.1]}, ParameterError, "noise_std holds standard deviations.*>= 0"),
        ({"rng": -3}, ParameterError, "rng, a seed, must be >= 0"),
        ({"substeps": 0}, ParameterError, "substeps must be >= 1"),
        ({"u": np.full((161, 2), np.nan)}, DataError, "u has a non-finite value nan in signal 'u1' at sample 0"),
    ],
)
def test_bad_arguments_are_refused_before_any_work(kwargs, error, pattern):
    base = {"duration": DURATION, "dt": DT, "u": U, "d": D}
    base.update(kwargs)
    with pytest.raises(error, match=pattern):
        simulate(plant(), **base)


def test_issue_examples_give_clear_errors():
    """``x0=[nan]`` and ``measurement_noise_std=-0.1`` were accepted before (issue 12)."""
    m = FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[1.0]], outputs=["y"], controls=["u"], states=["x"])
    with pytest.raises(ParameterError, match="x0 must be finite"):
        simulate(m, duration=1.0, dt=0.1, x0=[np.nan])
    with pytest.raises(ParameterError, match=">= 0"):
        simulate(m, duration=1.0, dt=0.1, measurement_noise_std=-0.1)
