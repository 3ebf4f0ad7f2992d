"""Bad input to :func:`fdikit.simulate.simulate`, :func:`simulate_scheduled` and :func:`time_grid`.

Bad arguments (times, sizes, noise levels, x0, options) raise :class:`ParameterError`; bad signal
data (u, d, t, schedule) and runs that would return non-finite samples raise :class:`DataError`.
Each message names the argument or signal and what is wrong.
"""

from __future__ import annotations

import numpy as np
import pytest
from harness import case, check, ids

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.faults import Bias, Drift, FaultScenario, ScaleFactor
from fdikit.model import FaultModel
from fdikit.simulate import NonlinearPlant, simulate, simulate_scheduled, time_grid

A = np.array([[0.0, 1.0, 0.0], [-4.0, -0.6, 0.8], [0.0, 0.3, -2.0]])
BU = np.array([[0.0, 0.0], [1.0, -0.5], [0.2, 1.0]])
C = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])


def stable():
    return FaultModel(A=A, C=C, Bu=BU, Bd=[[0.1], [0.0], [0.5]], outputs=["pos", "rate"], controls=["u1", "u2"],
                      disturbances=["gust"], states=["p", "v", "q"])


def noisy():
    return FaultModel(A=A, C=C, Bu=BU, Bw=np.eye(3), outputs=["pos", "rate"], controls=["u1", "u2"],
                      noise=["w1", "w2", "w3"], states=["p", "v", "q"])


def unstable():  # eigenvalues 0.5 and -1: grows like e^{0.5 t}
    return FaultModel(A=[[0.5, 0.0], [0.0, -1.0]], C=np.eye(2), Bu=[[1.0], [1.0]], outputs=["a", "b"],
                      controls=["u"], states=["xa", "xb"])


def unstable_discrete():  # eigenvalue 1.5 outside the unit circle
    return FaultModel(A=[[1.5]], C=[[1.0]], Bu=[[1.0]], outputs=["y"], controls=["u"], states=["x"], dt=0.1)


def pendulum_up():  # a nonlinear plant whose state escapes to infinity in finite time
    return NonlinearPlant(f=lambda t, x, u: x**3, h=lambda t, x, u: x, states=["a"], outputs=["a"], controls=[],
                          x0=[10.0])


def nonlinear():
    return NonlinearPlant(f=lambda t, x, u: np.array([x[1], -x[0] + u[0]]), h=lambda t, x, u: x[:1],
                          states=["x", "v"], outputs=["pos"], controls=["force"])


def family():
    from fdikit.plants.single_track import single_track_lpv

    return single_track_lpv()


def unstable_family(rho):
    return FaultModel(A=[[1.0 + 0.01 * rho]], C=[[1.0]], Bu=[[1.0]], outputs=["y"], controls=["u"], states=["x"],
                      dt=0.1)


def run(**kw):
    scenario = kw.pop("scenario", None)
    kw.setdefault("duration", 1.0)
    kw.setdefault("dt", 0.1)
    return simulate(kw.pop("plant", None) or stable(), scenario, **kw)


SPEEDS = np.linspace(70, 120, 101) / 3.6
RAMP = np.repeat(np.linspace(10, 20, 50), 200)  # 50 frozen models with |λ| from 1.1 to 1.2, 10000 samples

CASES = [
    # ---- duration / dt / t
    case("duration-nan", lambda: run(duration=np.nan), ParameterError, "duration", "finite"),
    case("duration-inf", lambda: run(duration=np.inf), ParameterError, "duration", "finite"),
    case("duration-negative", lambda: run(duration=-1.0), ParameterError, "duration", ">= 0"),
    case("duration-string", lambda: run(duration="10"), ParameterError, "duration", "number"),
    case("duration-list", lambda: run(duration=[1.0, 2.0]), ParameterError, "duration", "number"),
    case("dt-zero", lambda: run(dt=0.0), ParameterError, "dt", "> 0"),
    case("dt-negative", lambda: run(dt=-0.1), ParameterError, "dt", "> 0"),
    case("dt-nan", lambda: run(dt=np.nan), ParameterError, "dt", "finite"),
    case("dt-inf", lambda: run(dt=np.inf), ParameterError, "dt", "finite"),
    case("dt-string", lambda: run(dt="0.1"), ParameterError, "dt", "number"),
    case("dt-other-than-discrete-plant", lambda: run(plant=unstable_discrete(), dt=0.5), ParameterError,
         "dt", "discrete plant"),
    case("no-duration-no-t", lambda: simulate(stable(), dt=0.1), ParameterError, "duration", "t"),
    case("no-dt-no-t", lambda: simulate(stable(), duration=1.0), ParameterError, "dt", "t"),
    case("huge-duration-memory", lambda: run(duration=1e13, dt=0.01), ParameterError, "memory", "bytes"),
    case("huge-sample-count-memory", lambda: run(duration=1e6, dt=1e-6), ParameterError, "memory", "duration"),
    case("t-nan", lambda: simulate(stable(), t=[0.0, 0.1, np.nan, 0.3]), DataError, "t", "finite"),
    case("t-decreasing", lambda: simulate(stable(), t=[0.3, 0.2, 0.1, 0.0]), DataError, "t", "increasing"),
    case("t-repeated", lambda: simulate(stable(), t=[0.0, 0.0, 0.0]), DataError, "t", "increasing"),
    case("t-non-uniform", lambda: simulate(stable(), t=[0.0, 0.1, 0.25, 0.3]), DataError, "t", "uniformly"),
    case("t-2d", lambda: simulate(stable(), t=np.zeros((3, 2))), DataError, "t", "1-D"),
    case("t-empty", lambda: simulate(stable(), t=[]), DataError, "t", "empty"),
    case("t-strings", lambda: simulate(stable(), t=["a", "b"]), DataError, "t", "number"),
    case("t-and-duration", lambda: simulate(stable(), t=[0.0, 0.1], duration=1.0, dt=0.1), ParameterError,
         "t", "duration"),
    # ---- x0
    case("x0-nan", lambda: run(x0=[np.nan, 0.0, 0.0]), ParameterError, "x0", "finite"),
    case("x0-inf", lambda: run(x0=[0.0, np.inf, 0.0]), ParameterError, "x0", "finite"),
    case("x0-short", lambda: run(x0=[1.0, 2.0]), ParameterError, "x0", "3"),
    case("x0-2d", lambda: run(x0=np.zeros((3, 1))), ParameterError, "x0", "shape"),
    case("x0-string", lambda: run(x0="abc"), ParameterError, "x0", "number"),
    case("x0-nonlinear-nan", lambda: run(plant=nonlinear(), x0=[np.nan, 0.0]), ParameterError, "x0", "finite"),
    case("nonlinear-plant-x0-nan", lambda: NonlinearPlant(f=lambda t, x, u: x, h=lambda t, x, u: x, states=["a"],
                                                          outputs=["a"], controls=[], x0=[np.nan]),
         ModelError, "x0", "finite"),
    case("nonlinear-plant-f-not-callable", lambda: NonlinearPlant(f=3, h=lambda t, x, u: x, states=["a"],
                                                                  outputs=["a"], controls=[]),
         ModelError, "f", "callable"),
    case("nonlinear-h-wrong-length", lambda: run(plant=NonlinearPlant(
        f=lambda t, x, u: -x, h=lambda t, x, u: np.zeros(3), states=["a"], outputs=["a"], controls=[])),
        ModelError, "h", "outputs"),
    case("nonlinear-f-wrong-length", lambda: run(plant=NonlinearPlant(
        f=lambda t, x, u: np.zeros(3), h=lambda t, x, u: x, states=["a"], outputs=["a"], controls=[])),
        ModelError, "f", "states"),
    # ---- noise levels
    case("measurement-noise-negative", lambda: run(measurement_noise_std=-0.1), ParameterError,
         "measurement_noise_std", ">= 0"),
    case("measurement-noise-nan", lambda: run(measurement_noise_std=np.nan), ParameterError,
         "measurement_noise_std", "finite"),
    case("measurement-noise-inf", lambda: run(measurement_noise_std=[0.1, np.inf]), ParameterError,
         "measurement_noise_std", "finite"),
    case("measurement-noise-wrong-length", lambda: run(measurement_noise_std=[0.1, 0.2, 0.3]), ParameterError,
         "measurement_noise_std", "2"),
    case("measurement-noise-string", lambda: run(measurement_noise_std="loud"), ParameterError,
         "measurement_noise_std", "number"),
    case("measurement-noise-std-matrix", lambda: run(measurement_noise_std=np.eye(2)), ParameterError,
         "measurement_noise_std", "standard deviation", "measurement_noise_cov"),
    case("measurement-noise-std-and-cov", lambda: run(measurement_noise_std=0.1, measurement_noise_cov=0.01),
         ParameterError, "measurement_noise_std", "measurement_noise_cov", "not both"),
    case("measurement-noise-cov-negative-variance", lambda: run(measurement_noise_cov=[0.01, -0.01]),
         ParameterError, "measurement_noise_cov", "variances", ">= 0"),
    case("measurement-noise-cov-wrong-length", lambda: run(measurement_noise_cov=[0.1, 0.2, 0.3]), ParameterError,
         "measurement_noise_cov", "2"),
    case("measurement-noise-not-psd", lambda: run(measurement_noise_cov=[[1.0, 2.0], [2.0, 1.0]]), ParameterError,
         "measurement_noise_cov", "semidefinite"),
    case("measurement-noise-asymmetric", lambda: run(measurement_noise_cov=[[1.0, 0.5], [0.0, 1.0]]), ParameterError,
         "measurement_noise_cov", "symmetric"),
    case("measurement-noise-nan-matrix", lambda: run(measurement_noise_cov=[[np.nan, 0.0], [0.0, 1.0]]),
         ParameterError, "measurement_noise_cov", "finite"),
    case("measurement-noise-3d", lambda: run(measurement_noise_cov=np.zeros((2, 2, 2))), ParameterError,
         "measurement_noise_cov", "shape"),
    case("noise-cov-without-noise-group", lambda: run(noise_cov=0.1), ParameterError, "noise_cov", "noise"),
    case("noise-std-without-noise-group", lambda: run(noise_std=0.1), ParameterError, "noise_std", "noise"),
    case("noise-std-negative", lambda: run(plant=noisy(), noise_std=-1.0), ParameterError, "noise_std", ">= 0"),
    case("noise-cov-negative", lambda: run(plant=noisy(), noise_cov=-1.0), ParameterError, "noise_cov", ">= 0"),
    case("noise-std-and-cov", lambda: run(plant=noisy(), noise_std=0.1, noise_cov=0.01), ParameterError,
         "noise_std", "noise_cov", "not both"),
    case("noise-cov-nan", lambda: run(plant=noisy(), noise_cov=[0.1, np.nan, 0.1]), ParameterError,
         "noise_cov", "finite"),
    case("noise-std-nonlinear-negative", lambda: run(plant=nonlinear(), noise_std=[-0.1, 0.1]), ParameterError,
         "noise_std", ">= 0"),
    case("noise-cov-nonlinear-negative", lambda: run(plant=nonlinear(), noise_cov=[-0.1, 0.1]), ParameterError,
         "noise_cov", ">= 0"),
    # ---- u / d signals
    case("u-wrong-rows", lambda: run(u=np.zeros((10, 2))), DataError, "u", "shape"),
    case("u-wrong-columns", lambda: run(u=np.zeros((11, 3))), DataError, "u", "shape"),
    case("u-nan", lambda: run(u=np.full((11, 2), np.nan)), DataError, "u", "non-finite"),
    case("u-inf-names-sample", lambda: run(u=np.where(np.arange(22).reshape(11, 2) == 7, np.inf, 0.0)),
         DataError, "u2", "t=0.3"),
    case("u-strings", lambda: run(u="abc"), DataError, "u", "number"),
    case("u-callable-wrong-length", lambda: run(u=lambda tk: [1.0, 2.0, 3.0]), DataError, "u", "2"),
    case("u-callable-nan", lambda: run(u=lambda tk: [np.nan, 0.0]), DataError, "u", "non-finite"),
    case("u-callable-raises", lambda: run(u=lambda tk: 1 / 0), DataError, "u", "ZeroDivisionError"),
    case("d-wrong-shape", lambda: run(d=np.zeros((11, 2))), DataError, "d", "shape"),
    case("d-nan", lambda: run(d=np.full(11, np.nan)), DataError, "d", "non-finite"),
    case("d-for-nonlinear", lambda: run(plant=nonlinear(), d=np.zeros((11, 1))), ParameterError, "d", "NonlinearPlant"),
    # ---- faults in a simulation
    case("fault-unknown-signal", lambda: run(scenario=FaultScenario([Bias("brake", 1.0)])), ParameterError,
         "brake", "pos"),
    case("fault-sensor-on-control", lambda: run(scenario=FaultScenario([Bias("u1", 1.0, location="sensor")])),
         ParameterError, "u1", "sensor"),
    case("fault-drift-overflows", lambda: run(scenario=FaultScenario([Drift("u1", rate=1e308)]), duration=3.0),
         DataError, "u1", "drift"),
    case("fault-scale-overflows", lambda: run(scenario=FaultScenario([ScaleFactor("pos", factor=1e308)]),
                                              x0=[10.0, 0.0, 0.0]),
         DataError, "pos", "scale"),
    case("scenario-a-string", lambda: run(scenario="bias:pos:1"), ParameterError, "scenario", "FaultScenario"),
    case("scenario-a-fault", lambda: run(scenario=Bias("pos", 1.0)), ParameterError, "scenario", "FaultScenario"),
    # ---- non-finite results
    case("unstable-continuous", lambda: run(plant=unstable(), duration=3000.0, dt=0.5, x0=[1.0, 0.0]), DataError,
         "unstable", "0.5", "t="),
    case("unstable-discrete", lambda: run(plant=unstable_discrete(), duration=400.0, dt=None, x0=[1.0]), DataError,
         "unstable", "1.5", "|λ|"),
    case("unstable-nonlinear", lambda: run(plant=pendulum_up(), duration=5.0, dt=0.5, substeps=1), DataError,
         "non-finite", "t="),
    case("unstable-nonlinear-solve-ivp", lambda: run(plant=pendulum_up(), duration=5.0, dt=0.5, method="solve_ivp"),
         DataError, "t=", "a"),
    # ---- other options
    case("plant-wrong-type", lambda: simulate("path12", duration=1.0, dt=0.1), ParameterError, "plant", "FaultModel"),
    case("method-unknown", lambda: run(plant=nonlinear(), method="euler"), ParameterError, "method", "rk4"),
    case("substeps-zero", lambda: run(plant=nonlinear(), substeps=0), ParameterError, "substeps", ">= 1"),
    case("substeps-float", lambda: run(plant=nonlinear(), substeps=2.5), ParameterError, "substeps", "integer"),
    case("rng-string", lambda: run(rng="seed"), ParameterError, "rng", "seed"),
    case("rng-negative", lambda: run(rng=-1), ParameterError, "rng", "negative"),
    case("meta-not-dict", lambda: run(meta=["a"]), ParameterError, "meta", "dict"),
    # ---- time_grid
    case("time-grid-dt-zero", lambda: time_grid(1.0, 0.0), ParameterError, "dt", "> 0"),
    case("time-grid-duration-nan", lambda: time_grid(np.nan, 0.1), ParameterError, "duration", "finite"),
    case("time-grid-huge", lambda: time_grid(1e15, 1e-3), ParameterError, "memory", "bytes"),
    # ---- simulate_scheduled
    case("scheduled-schedule-nan", lambda: simulate_scheduled(family(), np.r_[SPEEDS[:50], np.nan]), DataError,
         "schedule", "finite"),
    case("scheduled-schedule-short", lambda: simulate_scheduled(family(), [20.0]), DataError, "schedule", "2"),
    case("scheduled-schedule-strings", lambda: simulate_scheduled(family(), ["a", "b"]), DataError,
         "schedule", "number"),
    case("scheduled-family-not-callable", lambda: simulate_scheduled(5, SPEEDS), ParameterError, "family",
         "callable"),
    case("scheduled-family-continuous", lambda: simulate_scheduled(lambda r: stable(), SPEEDS), ModelError,
         "family", "discrete"),
    case("scheduled-schedule-name-int", lambda: simulate_scheduled(family(), SPEEDS, schedule_name=3), ParameterError,
         "schedule_name", "str"),
    case("scheduled-u-wrong-shape", lambda: simulate_scheduled(family(), SPEEDS, u=np.zeros(50)), DataError,
         "u", "shape"),
    case("scheduled-x0-nan", lambda: simulate_scheduled(family(), SPEEDS, x0=[np.nan, 0, 0, 0]), ParameterError,
         "x0", "finite"),
    case("scheduled-unstable", lambda: simulate_scheduled(unstable_family, RAMP, x0=[1.0]), DataError,
         "unstable", "|λ|", "t="),
    case("scheduled-unstable-constant", lambda: simulate_scheduled(unstable_family, np.full(8000, 10.0), x0=[1.0]),
         DataError, "unstable", "1.1"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
