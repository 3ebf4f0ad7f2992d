"""Metrics: a detection delay known in closed form through the whole pipeline, and counting rules."""

import math

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.decision import ThresholdEvaluator
from fdikit.design import observer
from fdikit.diagnosis import Diagnosis
from fdikit.errors import DataError
from fdikit.faults import Bias, Drift, FaultScenario
from fdikit.metrics import MISSED, score, summarize
from fdikit.simulate import simulate


def _deadbeat():
    model = FaultModel(A=[[0.5]], C=[[1.0]], outputs=["y"], dt=0.01)
    return model, observer(model, poles=[0.0]).generator


def test_detection_delay_of_a_drift_known_in_closed_form():
    """Deadbeat observer (L = 0.5) on x+ = 0.5 x, y = x + f, f a drift of rate ρ from t0.

    Error e+ = −L f, so r[k] = f[k] − 0.5 f[k−1] = ρ (0.5 (k+1) dt) at k samples after onset;
    the first sample with r > τ is k* = floor(2τ/(ρ dt)) and the delay is k* dt.
    """
    model, gen = _deadbeat()
    rate, tau, t0 = 0.4, 0.051, 2.0
    trace = simulate(model, FaultScenario([Drift("y", rate, onset=t0)]), duration=6.0)
    d = ThresholdEvaluator(thresholds=[tau], isolates=["y_sensor"]).run(gen.run(trace))
    s = score(trace, d)
    k_star = math.floor(2 * tau / (rate * 0.01))
    assert s.detected and not s.missed
    assert s.detection_delay == pytest.approx(k_star * 0.01, abs=1e-9)
    assert s.isolated == "y_sensor" and s.isolation_correct
    assert s.false_alarms == 0
    assert s.fault_free_hours == pytest.approx(2.0 / 3600)


def test_false_alarms_missed_and_summary():
    t = np.arange(100) * 0.1
    truth = np.where(t >= 5.0, "f1", "none")
    alarm = np.zeros(100, bool)
    alarm[[10, 11, 30]] = True  # two false alarms (rising edges at 1.0 and 3.0 s)
    d = Diagnosis(t, alarm, alarm[:, None], ("r",), np.where(alarm, "f1", "none"))
    s = score(truth, d)
    assert s.false_alarms == 2 and s.missed and not s.detected
    assert s.false_alarm_rate == pytest.approx(2 / (50 * 0.1 / 3600))
    assert s.outcome == MISSED
    healthy = score(np.full(100, "none"), d)
    assert healthy.label == "none" and healthy.false_alarms == 2 and healthy.outcome == "f1"
    alarm2 = np.zeros(100, bool)
    alarm2[60:] = True
    iso = np.where(alarm2, "unknown", "none")
    iso[65:] = "f2"
    hit = score(truth, Diagnosis(t, alarm2, alarm2[:, None], ("r",), iso))
    assert hit.detection_delay == pytest.approx(1.0) and hit.isolated == "f2" and hit.isolation_correct is False
    summ = summarize([s, healthy, hit])
    assert summ.runs == 3 and summ.faulty_runs == 2
    assert summ.detection_rate == 0.5 and summ.missed_rate == 0.5
    assert summ.false_alarms == 4
    assert summ.false_alarm_rate == pytest.approx(4 / ((50 + 100 + 50) * 0.1 / 3600))
    assert summ.isolation_accuracy == 0.0
    assert summ.confusion.loc["f1", MISSED] == 1 and summ.confusion.loc["f1", "f2"] == 1
    assert summ.confusion.loc["none", "f1"] == 1


def test_bias_on_pipeline_and_length_mismatch():
    model, gen = _deadbeat()
    trace = simulate(model, FaultScenario([Bias("y", 1.0, onset=1.0)]), duration=2.0)
    d = ThresholdEvaluator(thresholds=[0.4]).run(gen.run(trace))
    s = score(trace, d)
    # r = f − 0.5 f[k−1] settles at 0.5 > 0.4: detected at onset, isolation unknown without ties
    assert s.detection_delay == pytest.approx(0.0) and s.isolated == "unknown"
    with pytest.raises(DataError, match="samples"):
        score(trace.fault[:-1], d)
    with pytest.raises(DataError):
        summarize([])
