"""The compiled residual-generator step against the reference stepper and the batch run."""

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.runtime.generator import CompiledGenerator, compile_generator
from fdikit.trace import Trace


def _generator(rng, n, name, controls, outputs, dt=0.01):
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    nv = len(controls) + len(outputs)
    q = len(outputs)
    return ResidualGenerator(A, rng.standard_normal((n, nv)), rng.standard_normal((q, n)),
                             rng.standard_normal((q, nv)), controls, outputs,
                             tuple(f"{name}_r{i}" for i in range(q)), dt=dt)


@pytest.fixture(scope="module")
def bank():
    rng = np.random.default_rng(7)
    g = stack_generators([_generator(rng, 4, "a", ("u0",), ("y0", "y1")),
                          _generator(rng, 3, "b", ("u1",), ("y1", "y2"))])
    op = OperatingPoint(u0={"u0": 1.0, "u1": -2.0}, y0={"y0": 0.5, "y1": 3.0, "y2": -1.0})
    return ResidualGenerator(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, g.dt, g.isolates, op)


def _trace(bank, N, seed, gaps=()):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((N, 2)) + [1.0, -2.0]
    y = rng.standard_normal((N, 3)) + [0.5, 3.0, -1.0]
    valid = np.ones(N, bool)
    for k, col in gaps:
        if col is None:
            valid[k] = False
        else:
            y[k, col] = np.nan
    y[N // 2 :, 1] += 2.0  # a sensor bias
    return Trace(np.arange(N) * bank.dt, u, y, bank.controls, bank.outputs, valid=valid)


@pytest.mark.parametrize("gaps", [(), ((50, 0), (51, 0), (300, None), (301, 2), (302, None), (600, 1))])
def test_compiled_equals_reference_and_batch(bank, gaps):
    tr = _trace(bank, 900, 3, gaps)
    batch = bank.run(tr)
    ref = bank.online().run(tr)
    s = compile_generator(bank)
    U, Y = tr.columns("u", bank.controls), tr.columns("y", bank.outputs)
    r = np.empty_like(batch.r)
    valid, recovering = np.empty(len(tr), bool), np.empty(len(tr), bool)
    for k in range(len(tr)):
        u, y = (U[k], Y[k]) if tr.valid[k] else (np.full(2, np.nan), np.full(3, np.nan))
        r[k] = s.step(u, y)
        valid[k], recovering[k] = s.last_valid, s.last_recovering
    scale = np.nanmax(np.abs(batch.r))
    for other in (batch, ref):
        np.testing.assert_allclose(r, other.r, rtol=1e-12, atol=1e-12 * scale)
        assert (valid == other.valid).all() and (recovering == other.recovering).all()
    assert s.invalid == sum(1 for _ in gaps)


def test_select_orders_residuals_and_reset(bank):
    names = (bank.residuals[3], bank.residuals[0])
    s = CompiledGenerator(bank, select=names)
    full = compile_generator(bank)
    u, y = np.array([1.5, -1.0]), np.array([0.0, 2.0, 1.0])
    for _ in range(3):
        r = s.step(u, y).copy()
        rf = full.step(u, y)
    np.testing.assert_allclose(r, rf[[3, 0]], rtol=1e-14)
    assert s.names == names
    s.reset()
    np.testing.assert_array_equal(s.x, np.zeros(bank.n))
    s.reset(np.ones(bank.n))
    np.testing.assert_array_equal(s.x, np.ones(bank.n))


def test_other_inputs_take_the_reference_path(bank):
    s, ref = compile_generator(bank), bank.online()
    u, y = [1.5, -1.0], {"y0": 0.0, "y1": 2.0, "y2": 1.0}
    np.testing.assert_allclose(s.step(u, y), ref.step(u, y), rtol=1e-14)
    np.testing.assert_allclose(s.step(np.array([1, 2]), np.array([3, 4, 5])), ref.step([1, 2], [3, 4, 5]), rtol=1e-14)
    with pytest.raises(DataError, match="got 4 values"):
        s.step(np.ones(2), np.ones(2))
    with pytest.raises(DataError, match="do not match"):
        s.step(u, {"y0": 1.0})
    with pytest.raises(ParameterError, match="does not have"):
        CompiledGenerator(bank, select=("nope",))
    with pytest.raises(ParameterError, match="ResidualGenerator"):
        CompiledGenerator("bank")
