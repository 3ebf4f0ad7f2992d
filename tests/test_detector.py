"""fdikit.detector: a deployable detector runs a trace (batch) and steps online with identical decisions.

The builders here (``bank``, ``detectors``, ``test_trace``) are shared with tests/test_detector_file.py.
"""

import numpy as np
import pytest

from fdikit.decision import CusumEvaluator, GlrEvaluator, MhsprtEvaluator, SprtEvaluator, ThresholdEvaluator
from fdikit.decision.learned import BnnEvaluator, GaussianMlEvaluator
from fdikit.detector import Detector
from fdikit.errors import DataError, ParameterError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.trace import Trace

DT = 0.1
NOISE = 0.1
U0, Y0 = {"u": 1.5}, {"y1": 10.0, "y2": 20.0}


def bank(operating_point=None) -> ResidualGenerator:
    """Two observers of x[k+1] = 0.9 x + u (y1 = x, y2 = 2 x), each reading one sensor, stacked.

    A bias b on y1 leaves r1 = 0.1 b / (0.1 + 0.3) = b / 4 in steady state (error recursion
    e' = (0.9 − L) e − L b with L = 0.3), and r2 untouched.
    """
    g1 = ResidualGenerator([[0.6]], [[1.0, 0.3, 0.0]], [[-1.0]], [[0.0, 1.0, 0.0]], ("u",), ("y1", "y2"),
                           ("r1",), dt=DT, isolates=("y1_sensor",))
    g2 = ResidualGenerator([[0.9 - 2 * 0.15]], [[1.0, 0.0, 0.15]], [[-2.0]], [[0.0, 0.0, 1.0]], ("u",),
                           ("y1", "y2"), ("r2",), dt=DT, isolates=("y2_sensor",))
    g = stack_generators([g1, g2])
    if operating_point is not None:
        g = ResidualGenerator(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, g.dt, g.isolates,
                              operating_point=operating_point)
    return g


def plant_trace(n, seed, fault=None, onset=0, size=2.0, absolute=False) -> Trace:
    """A run of the plant in deviation (or absolute) coordinates, with an optional sensor bias."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    x = np.zeros(n)
    for k in range(n - 1):
        x[k + 1] = 0.9 * x[k] + u[k]
    y = np.c_[x, 2 * x] + NOISE * rng.standard_normal((n, 2))
    if fault is not None:
        y[onset:, fault] += size
    if absolute:
        u, y = u + U0["u"], y + [Y0["y1"], Y0["y2"]]
    return Trace(np.arange(n) * DT, u[:, None], y, ("u",), ("y1", "y2"))


def test_trace(absolute=False) -> Trace:
    """A y1-sensor fault from sample 150, a y2 dropout at 40–42, a control dropout at 100 and two samples
    flagged invalid (70, 71)."""
    tr = plant_trace(300, 9, fault=0, onset=150, absolute=absolute)
    y, u = tr.y.copy(), tr.u.copy()
    y[40:43, 1] = np.nan
    u[100, 0] = np.nan
    valid = np.ones(len(tr), bool)
    valid[70:72] = False
    return Trace(tr.t, u, y, tr.controls, tr.outputs, valid=valid)


test_trace.__test__ = False  # a builder, not a test


def evaluators(g: ResidualGenerator) -> dict:
    """Each evaluator kind, fitted on small healthy (and, for the learned ones, faulty) runs of ``g``."""
    healthy = g.run(plant_trace(2000, 1))
    data = {"none": healthy, "y1_sensor": g.run(plant_trace(400, 2, fault=0)),
            "y2_sensor": g.run(plant_trace(400, 3, fault=1))}
    small = {k: v.slice(stop=v.t[299 if k == "none" else 199]) for k, v in data.items()}  # the BNN trains slowly
    return {
        "threshold": ThresholdEvaluator(persistence=(2, 3)).fit(healthy, false_alarm_prob=1e-3),
        "cusum": CusumEvaluator().fit(healthy, arl0=1000.0, shift=1.0),
        "sprt": SprtEvaluator(shift=0.5).fit(healthy),
        "glr": GlrEvaluator(window=10).fit(healthy, false_alarm_prob=1e-3),
        "mhsprt": MhsprtEvaluator(p=1e-3, pi=1e-3).fit(data),
        "gaussian_ml": GaussianMlEvaluator().fit(data),
        "bnn": BnnEvaluator(hidden=(3,), max_iter=20, rm_steps=5, rho0=0.01, rng=np.random.default_rng(4)).fit(small),
    }


def detectors() -> dict:
    g = bank()
    return {k: Detector(g, ev, name=k, units={"y1": "deg"}, columns={"y2": "Y2_LOG"})
            for k, ev in evaluators(g).items()}


@pytest.fixture(scope="module")
def all_detectors():
    return detectors()


def same_decisions(diag, steps) -> None:
    """Batch Diagnosis vs online StepDecisions: alarm, isolated fault, fired pattern, validity — exactly.

    Probabilities agree to rounding: the batch evaluates the same recursion vectorised, the stepper one row
    at a time, so each sample differs by a few ulps and the (contracting) posterior recursion does not
    accumulate them beyond N·eps = 300 · 2.2e-16 ≈ 7e-14 on probabilities in [0, 1]; 1e-12 bounds that.
    """
    assert diag.alarm.tolist() == [s.alarm for s in steps]
    assert diag.isolated.tolist() == [s.fault for s in steps]
    assert np.array_equal(diag.fired, np.array([s.fired for s in steps]))
    assert diag.valid.tolist() == [s.valid for s in steps]
    if diag.probabilities is not None:
        assert np.allclose(diag.probabilities, np.array([s.probabilities for s in steps]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", ["threshold", "cusum", "sprt", "glr", "mhsprt", "gaussian_ml", "bnn"])
def test_batch_and_online_identical_through_gaps_and_invalid_samples(all_detectors, kind):
    det = all_detectors[kind]
    tr = test_trace()
    diag = det.run(tr)
    # the detector is the generator's residuals through the evaluator's run, nothing else
    ref = det.evaluator.run(det.generator.run(tr))
    assert np.array_equal(diag.alarm, ref.alarm) and diag.isolated.tolist() == ref.isolated.tolist()
    same_decisions(diag, det.online().run(tr))
    # the gap (40–42), the control dropout (100) and the flagged samples (70, 71) are not used
    assert not diag.valid[[40, 41, 42, 70, 71, 100]].any()


def test_the_fault_is_detected_and_isolated(all_detectors):
    """The y1 bias (2.0, i.e. r1 = 0.5 = 5 noise σ in steady state) is found by every evaluator, and the
    threshold bank isolates it: healthy before the onset at sample 150 (α = 1e-3, 2-of-3 persistence)."""
    tr = test_trace()
    for kind, det in all_detectors.items():
        diag = det.run(tr)
        assert diag.alarm[200:].any(), kind
    thr = all_detectors["threshold"].run(tr)
    assert not thr.alarm[:150].any()
    assert thr.isolated[160:].tolist().count("y1_sensor") > 100


def test_online_takes_mappings_or_vectors_and_flags_invalid_samples(all_detectors):
    det = all_detectors["cusum"]
    tr = test_trace()
    a, b = det.online(), det.online()
    for k in range(len(tr)):
        ok = bool(tr.valid[k])
        da = a.step(tr.u[k], tr.y[k], valid=ok)
        db = b.step({"u": tr.u[k, 0]}, {"y2": tr.y[k, 1], "y1": tr.y[k, 0]}, valid=ok)
        assert (da.alarm, da.fault, da.valid) == (db.alarm, db.fault, db.valid)
        assert np.array_equal(a.residuals, b.residuals, equal_nan=True)
    assert a.invalid == 6  # 3 gap samples, 2 flagged, 1 control dropout
    with pytest.raises(DataError, match="missing"):
        a.step({"u": 1.0}, {"y1": 1.0})
    for bad in (None, [1.0, 2.0, 3.0], [[1.0], [2.0, 3.0]]):  # a flagged sample is still checked
        with pytest.raises(DataError):
            a.step([1.0], bad, valid=False)


def test_steppers_are_independent_of_each_other_and_of_batch(all_detectors):
    det = all_detectors["sprt"]
    tr = test_trace()
    first = det.online().run(tr)
    s = det.online()
    s.step(tr.u[0], tr.y[0])
    assert [d.alarm for d in det.online().run(tr)] == [d.alarm for d in first]
    s.reset()
    assert [d.alarm for d in s.run(tr)] == [d.alarm for d in first]


def test_operating_point_absolute_signals_equal_deviations():
    """The generator subtracts u0, y0: absolute logs give the residuals of the deviation run, up to the
    rounding of the offsets (|y| ≤ 40, so a few ulps of 40 ≈ 1e-14)."""
    op = OperatingPoint(u0=U0, y0=Y0)
    g_abs, g_dev = bank(op), bank()
    ev = ThresholdEvaluator().fit(g_dev.run(plant_trace(2000, 1)), false_alarm_prob=1e-3)
    det = Detector(g_abs, ev)
    assert det.operating_point == op
    r_abs = det.residuals(test_trace(absolute=True)).r
    r_dev = Detector(g_dev, ev).residuals(test_trace()).r
    assert np.allclose(r_abs, r_dev, rtol=0, atol=1e-12, equal_nan=True)
    assert np.array_equal(np.isnan(r_abs), np.isnan(r_dev))


def test_an_evaluator_fitted_on_a_subset_reads_its_residuals():
    g = bank()
    res = g.run(plant_trace(2000, 1)).select(["r2"])
    det = Detector(g, ThresholdEvaluator().fit(res, false_alarm_prob=1e-3))
    assert det.residual_names == ("r2",)
    tr = test_trace()
    same_decisions(det.run(tr), det.online().run(tr))
    other = ThresholdEvaluator().fit(g.run(plant_trace(2000, 1)).select(["r1"]), false_alarm_prob=1e-3)
    other.names = ("r9",)
    with pytest.raises(DataError, match="r9"):
        Detector(g, other)


def test_signals_units_columns_and_metadata(all_detectors):
    det = all_detectors["threshold"]
    assert (det.controls, det.outputs) == (("u",), ("y1", "y2"))
    assert det.log_spec() == {"controls": {"u": "u"}, "outputs": {"y1": "y1", "y2": "Y2_LOG"},
                              "units": {"y1": "deg"}}
    import fdikit

    assert det.fdikit_version == fdikit.__version__ and det.created.endswith("+00:00")
    g = bank()
    with pytest.raises(ParameterError, match="does not read"):
        Detector(g, det.evaluator, units={"speed": "km/h"})
    with pytest.raises(ParameterError, match="non-empty string"):
        Detector(g, det.evaluator, columns={"y1": ""})
    with pytest.raises(ParameterError, match="ResidualGenerator"):
        Detector("g", det.evaluator)
    with pytest.raises(ParameterError, match="lacks"):
        Detector(g, object())
    with pytest.raises(ParameterError):
        Detector(g, det.evaluator, recovery_tol=2.0)


def test_read_log_rereads_a_csv_with_the_stored_columns_and_units(tmp_path):
    g = bank()
    ev = ThresholdEvaluator().fit(g.run(plant_trace(2000, 1)), false_alarm_prob=1e-3)
    det = Detector(g, ev, units={"y1": "deg"}, columns={"y2": "Y2_LOG"}, time_column="time")
    tr = plant_trace(50, 5)
    cols = zip(tr.t.tolist(), tr.u[:, 0].tolist(), np.degrees(tr.y[:, 0]).tolist(), tr.y[:, 1].tolist())
    rows = ["time,u,y1,Y2_LOG"] + [f"{t!r},{u!r},{y1!r},{y2!r}" for t, u, y1, y2 in cols]
    (tmp_path / "log.csv").write_text("\n".join(rows) + "\n")
    back = det.read_log(tmp_path / "log.csv")
    assert np.allclose(back.y, tr.y, rtol=1e-14, atol=1e-15)
    assert np.allclose(back.t, tr.t, rtol=0, atol=1e-12)
    # the import record of that log gives the same reading instructions back
    assert Detector(g, ev).with_log(back).log_spec() == det.log_spec()
    assert np.array_equal(Detector(g, ev).with_log(back).read_log(tmp_path / "log.csv").y, back.y)
