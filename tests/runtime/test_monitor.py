"""The compiled monitor against the reference DetectorStepper, sample by sample."""

import numpy as np
import pytest

from fdikit.decision import CusumEvaluator, ThresholdEvaluator
from fdikit.detector import Detector
from fdikit.errors import DataError, ParameterError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.runtime import Monitor, compile_detector
from fdikit.trace import Trace


def _generator(rng, n, name, controls, outputs):
    A = rng.standard_normal((n, n))
    A *= 0.8 / max(abs(np.linalg.eigvals(A)))
    nv, q = len(controls) + len(outputs), len(outputs)
    return ResidualGenerator(A, 0.3 * rng.standard_normal((n, nv)), rng.standard_normal((q, n)),
                             np.hstack([np.zeros((q, len(controls))), np.eye(q)]), controls, outputs,
                             tuple(f"{name}_r{i}" for i in range(q)), dt=0.01,
                             isolates=tuple(f"{o}_sensor" for o in outputs))


@pytest.fixture(scope="module")
def bank():
    rng = np.random.default_rng(3)
    g = stack_generators([_generator(rng, 3, "a", ("u0",), ("y0", "y1")),
                          _generator(rng, 2, "b", ("u1",), ("y2",))])
    op = OperatingPoint(u0={"u0": 1.0, "u1": -2.0}, y0={"y0": 0.5, "y1": 3.0, "y2": -1.0})
    return ResidualGenerator(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, g.dt, g.isolates, op)


def _trace(N, seed, bias=True):
    rng = np.random.default_rng(seed)
    u = 0.1 * rng.standard_normal((N, 2)) + [1.0, -2.0]
    y = 0.1 * rng.standard_normal((N, 3)) + [0.5, 3.0, -1.0]
    if bias:
        y[N // 2 :, 2] += 1.0
    return Trace(np.arange(N) * 0.01, u, y, ("u0", "u1"), ("y0", "y1", "y2"))


def _detectors(bank):
    healthy = bank.run(_trace(4000, 1, bias=False))
    sel = (bank.residuals[2], bank.residuals[0], bank.residuals[1])  # a subset, in another order
    th = ThresholdEvaluator(persistence=(2, 3)).fit(healthy.select(sel), false_alarm_prob=1e-3)
    cu = CusumEvaluator().fit(healthy, arl0=1e3, shift=0.5)
    return {"threshold": Detector(bank, th, warmup=0.05), "cusum": Detector(bank, cu, recovery_tol=0.05)}


@pytest.mark.parametrize("kind", ["threshold", "cusum"])
def test_monitor_equals_detector_stepper(bank, kind):
    det = _detectors(bank)[kind]
    tr = _trace(1200, 5)
    U, Y = tr.u.copy(), tr.y.copy()
    Y[100, 1] = np.nan
    Y[700:704] = np.nan  # a gap: the gap rule, recovering samples
    valid = np.ones(len(tr), bool)
    valid[300] = valid[900] = False
    mon, ref = compile_detector(det), det.online()
    for _ in range(2):  # the second time after reset()
        alarms = 0
        for k in range(len(tr)):
            a = mon.step(U[k], Y[k], valid=bool(valid[k]))
            d = ref.step(U[k], Y[k], valid=bool(valid[k]))
            m = mon.decision()
            assert a == d.alarm and m.fault == d.fault and m.valid == d.valid, (kind, k)
            np.testing.assert_array_equal(m.fired, d.fired)
            np.testing.assert_allclose(mon.residuals, ref.residuals, rtol=1e-12, atol=1e-12)
            assert (mon.last_valid, mon.last_recovering, mon.invalid) == (ref.last_valid, ref.last_recovering,
                                                                          ref.invalid)
            alarms += a
        assert alarms > 0
        mon.reset()
        ref.reset()


def test_monitor_run_and_errors(bank):
    det = _detectors(bank)["threshold"]
    tr = _trace(300, 6)
    got = Monitor(det).run(tr)
    want = det.online().run(tr)
    assert [d.alarm for d in got] == [d.alarm for d in want] and [d.fault for d in got] == [d.fault for d in want]
    mon = compile_detector(det)
    with pytest.raises(DataError, match="got 4 values"):
        mon.step(np.ones(2), np.ones(2))
    with pytest.raises(ParameterError, match="Detector"):
        Monitor(bank)
