"""Operating points on models and generators; banks of generators reading different signals."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.trace import Trace


def _close(a, b, n):
    """Batch (blocked solve) and online (stepped) residuals agree to rounding: ``n`` steps of a
    stable filter with |gain| ≤ 1 each add at most a few ulps of the signal scale."""
    scale = 1.0 + np.nanmax(np.abs(b))
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * n * scale)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))


def _observer(op=None, outputs=("y",), name="r"):
    # x+ = 0.9 x + u, y = x; observer gain 0.5: z+ = 0.4 z + u + 0.5 y, r = y − z
    return ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), outputs, (name,), dt=1.0,
                             operating_point=op)


def test_generator_subtracts_the_operating_point_batch_and_online():
    rng = np.random.default_rng(0)
    N = 50
    du = rng.standard_normal(N)
    x = np.zeros(N + 1)
    for k in range(N):
        x[k + 1] = 0.9 * x[k] + du[k]
    dy = x[:N]
    u0, y0 = 3.0, -7.0
    dev = Trace(np.arange(N, dtype=float), du[:, None], dy[:, None], ("u",), ("y",))
    absolute = Trace(np.arange(N, dtype=float), (du + u0)[:, None], (dy + y0)[:, None], ("u",), ("y",))
    g_dev = _observer()
    g_abs = _observer(OperatingPoint(u0={"u": u0}, y0={"y": y0}))
    r_dev = g_dev.run(dev).r
    _close(g_abs.run(absolute).r, g_abs.online().run(absolute).r, N)
    # the same filter on deviations: the residuals agree to rounding of the subtraction (|values| ~ 10)
    np.testing.assert_allclose(g_abs.run(absolute).r, r_dev, rtol=0, atol=1e-12 * (abs(u0) + abs(y0)) * N)
    # an observer of the exact model: the residual of fault-free data is zero
    assert np.max(np.abs(r_dev)) < 1e-12 * N


def test_model_operating_point_survives_transformations():
    m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], controls=["u"], outputs=["y"], states=["x"])
    m = m.with_operating_point(x0=[2.0], u0=[2.0], y0=[2.0])
    for mm in (m.with_sensor_faults(["y"]), m.discretize(0.1), m.submodel(outputs=["y"])):
        assert mm.operating_point == m.operating_point
    with pytest.raises(ParameterError, match="1 controls"):
        m.with_operating_point(u0=[1.0, 2.0])
    with pytest.raises(ParameterError, match="not controls"):
        m.with_operating_point(u0={"v": 1.0})
    with pytest.raises(ParameterError, match="not finite"):
        m.with_operating_point(y0=[np.nan])


def test_invalid_samples_of_the_trace_are_dropouts():
    N = 20
    t = np.arange(N, dtype=float)
    valid = np.ones(N, bool)
    valid[5:8] = False
    tr = Trace(t, np.ones((N, 1)), np.ones((N, 1)), ("u",), ("y",), valid=valid)
    res = _observer().run(tr)
    assert np.isnan(res.r[5:8]).all() and not res.valid[5:8].any()
    _close(res.r, _observer().online().run(tr).r, N)


def test_stack_generators_reading_different_signals_equals_each_filter_alone():
    rng = np.random.default_rng(1)
    N = 40
    tr = Trace(np.arange(N, dtype=float), rng.standard_normal((N, 1)), rng.standard_normal((N, 2)), ("u",),
               ("y", "z"))
    g1 = _observer(OperatingPoint(u0={"u": 1.0}, y0={"y": 2.0}))
    g2 = ResidualGenerator([[0.5]], [[0.5]], [[-1.0]], [[1.0]], (), ("z",), ("r2",), dt=1.0,
                           operating_point=OperatingPoint(y0={"z": -1.0}))
    bank = stack_generators([g1, g2])
    assert bank.controls == ("u",) and bank.outputs == ("y", "z")
    assert bank.operating_point.y0 == {"y": 2.0, "z": -1.0}
    r = bank.run(tr).r
    # block-diagonal filters: each residual is its own filter's (the blocked solve may order sums differently)
    _close(r[:, 0], g1.run(tr).r[:, 0], N)
    _close(r[:, 1], g2.run(tr).r[:, 0], N)
    _close(r, bank.online().run(tr).r, N)
    # a dropout of z makes the sample invalid (all residuals NaN) but leaves the filter that does not read z
    # untouched afterwards; the filter reading z is propagated through it by the gap rule
    y = tr.y.copy()
    y[10, 1] = np.nan
    gap = Trace(tr.t, tr.u, y, ("u",), ("y", "z"))
    rb = bank.run(gap).r
    assert np.isnan(rb[10]).all()
    _close(rb[11:, 0], r[11:, 0], N)
    assert np.max(np.abs(rb[11:, 1] - r[11:, 1])) > 1e-3


def test_stack_refuses_conflicting_operating_points():
    g1 = _observer(OperatingPoint(y0={"y": 1.0}))
    g2 = _observer(OperatingPoint(y0={"y": 2.0}), name="r2")
    with pytest.raises(ModelError, match="operating point"):
        stack_generators([g1, g2])


def test_a_trace_with_a_gap_in_its_time_stamps_is_refused():
    t = np.delete(np.arange(20.0), 7)          # a row dropped, as by DataFrame.dropna()
    tr = Trace(t, np.ones((19, 1)), np.ones((19, 1)), ("u",), ("y",))
    g = _observer()
    with pytest.raises(DataError, match="not uniformly sampled.*from t=6 to 8"):
        g.run(tr)
    with pytest.raises(DataError, match="not uniformly sampled"):
        g.online().run(tr)
