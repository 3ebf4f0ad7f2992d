"""fit_parameters: recover the front cornering stiffness of the single-track model within its standard error."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import stats

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.identify import fit_parameters
from fdikit.plants.single_track import PRIUS_2010, single_track
from fdikit.simulate import NonlinearPlant, simulate
from fdikit.trace import Trace

SPEED, DT, NOISE = 20.0, 0.05, 0.002  # m/s, s, rad/s (yaw-rate sensor noise std)


def build(p):
    return single_track(SPEED, dataclasses.replace(PRIUS_2010, C_f=float(p[0])), outputs=["yaw_rate"])


def steering(n, rng):
    # held random steps of 0.5 s, ±0.02 rad: a persistently exciting steering input
    return np.repeat(rng.uniform(-0.02, 0.02, n // 10 + 1), 10)[:n, None]


def test_recovers_cornering_stiffness_within_its_standard_error():
    rng = np.random.default_rng(7)
    n = 800
    truth = build([PRIUS_2010.C_f])
    tr = simulate(truth, t=np.arange(n) * DT, u=steering(n, rng), measurement_noise_std=NOISE, rng=rng)
    est = fit_parameters(build, [0.7 * PRIUS_2010.C_f], tr, scale=NOISE, names=["C_f"],
                         bounds=([-5e5], [-1e3]))
    assert est.result.success
    # (θ̂ − θ) / SE is asymptotically standard normal (Ljung 1999, §9.3); |Z| > 4.42 has probability 1e-5.
    z = (est.params[0] - PRIUS_2010.C_f) / est.std[0]
    assert abs(z) < stats.norm.isf(0.5e-5), z
    # with the noise std as the scale, N σ̂² ~ χ²(N − 1): σ̂² lies in 1 ± 5 √(2 / (N − 1)) with probability > 1 − 1e-6
    assert abs(est.sigma2 - 1.0) < 5 * np.sqrt(2 / (n - 1))
    # the SE is small against the parameter (the data inform it) and the fit is high
    assert est.std[0] < 0.05 * abs(PRIUS_2010.C_f)
    assert est.fit[0] > 90
    assert est.as_dict()["C_f"][0] == est.params[0] and est.outputs == ("yaw_rate",)


def test_nonlinear_plant_and_gaps():
    # y = x, x' = -k x + u: k recovered from a NonlinearPlant; output dropouts (NaN, valid == False) are left out
    # of the error (the simulation runs through them), a non-finite control is refused
    def plant(p):
        return NonlinearPlant(f=lambda t, x, u: -p[0] * x + u, h=lambda t, x, u: x, states=("x",), outputs=("y",),
                              controls=("u",))
    rng = np.random.default_rng(8)
    t = np.arange(300) * 0.05
    u = np.sign(np.sin(0.7 * t))[:, None]
    tr = simulate(plant([1.5]), t=t, u=u, measurement_noise_std=0.01, rng=rng)
    y = tr.y.copy()
    y[100:110] = np.nan
    valid = np.ones(300, bool)
    valid[200:205] = False
    y[200:205] = 99.0  # garbage under valid == False
    gappy = Trace(t=t, u=u, y=y, controls=("u",), outputs=("y",), valid=valid)
    est = fit_parameters(plant, [1.0], [gappy], scale=0.01)
    assert est.result.fun.size == 300 - 15
    assert abs(est.params[0] - 1.5) < stats.norm.isf(0.5e-5) * est.std[0]
    bad_u = u.copy()
    bad_u[50] = np.nan
    with pytest.raises(DataError, match="non-finite control at sample 50"):
        fit_parameters(plant, [1.0], Trace(t=t, u=bad_u, y=tr.y, controls=("u",), outputs=("y",)))


def test_bad_arguments():
    rng = np.random.default_rng(9)
    tr = simulate(build([PRIUS_2010.C_f]), t=np.arange(50) * DT, u=steering(50, rng))
    with pytest.raises(ParameterError, match="names"):
        fit_parameters(build, [PRIUS_2010.C_f], tr, names=["a", "b"])
    with pytest.raises(ParameterError, match="not outputs"):
        fit_parameters(build, [PRIUS_2010.C_f], tr, outputs=["speed"])
    with pytest.raises(ModelError, match="FaultModel or a NonlinearPlant"):
        fit_parameters(lambda p: "plant", [1.0], tr)
