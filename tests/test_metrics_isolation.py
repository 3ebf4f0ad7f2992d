"""Isolation scores of fdikit.metrics: 'unknown' never correct, the isolation delay (named and held), the correct
fraction, and the Summary's isolation fields — on hand-made diagnoses whose numbers are counted by hand."""

import math

import numpy as np
import pytest

from fdikit.diagnosis import Diagnosis
from fdikit.errors import ParameterError
from fdikit.metrics import Score, score, summarize

DT = 0.5


def _diag(isolated, valid=None):
    """A one-residual diagnosis whose alarm is on wherever the label is not 'none'."""
    iso = np.array(isolated, dtype=str)
    fired = (iso != "none")[:, None]
    return Diagnosis(np.arange(iso.size) * DT, fired[:, 0], fired, ("r",), iso, valid=valid)


def test_unknown_never_counts_as_correct():
    """The old rule took the most frequent *named* label: here 'fa' (1 sample) although 'unknown' is named on 9 of the
    10 alarmed samples.  Now the isolation is 'unknown' and not correct."""
    truth = ["none"] * 2 + ["fa"] * 10
    d = _diag(["none"] * 2 + ["fa"] + ["unknown"] * 9)
    s = score(np.array(truth), d)
    assert s.detected and s.isolated == "unknown" and s.isolation_correct is False
    assert s.correct_fraction == pytest.approx(0.1, abs=1e-15)
    assert s.outcome == "unknown"
    # even a truth label spelled 'unknown' is never a correct isolation
    s2 = score(np.array(["none"] * 2 + ["unknown"] * 10), d)
    assert s2.isolated == "unknown" and s2.isolation_correct is False
    assert s2.correct_fraction == 0.0 and s2.isolation_delay is None
    assert summarize([s]).isolation_accuracy == 0.0


def test_most_frequent_label_with_unknown_counted():
    # 6 of 10 alarmed samples name fa, 4 are unknown: fa is isolated and correct; 0.6 of the alarmed samples are right
    d = _diag(["none"] * 2 + ["unknown"] * 4 + ["fa"] * 6)
    s = score(np.array(["none"] * 2 + ["fa"] * 10), d)
    assert s.isolated == "fa" and s.isolation_correct is True
    assert s.correct_fraction == pytest.approx(0.6, abs=1e-15)


def test_isolation_delay_named_and_held():
    """Onset at sample 2 (t = 1.0 s); fa first named at sample 4, lost at 6 (fb), named again from sample 7 to the end
    of the faulty interval (sample 11): named and held from sample 7, t = 3.5 s, delay 2.5 s.  The detection delay is
    counted from the first alarm (sample 3, unknown): 0.5 s."""
    labels = ["none", "none", "none", "unknown", "fa", "fa", "fb", "fa", "fa", "fa", "fa", "fa"]
    s = score(np.array(["none"] * 2 + ["fa"] * 10), _diag(labels))
    assert s.detection_delay == 0.5
    assert s.isolation_delay == 2.5
    # hold = 0.5 s: named at sample 4 and 5 (t = 2.0, 2.5): held for 0.5 s from sample 4 -> delay 1.0 s
    assert score(np.array(["none"] * 2 + ["fa"] * 10), _diag(labels), hold=0.5).isolation_delay == 1.0
    # hold = 1.0 s from sample 4 needs samples 4..6 (t = 2.0 … 3.0) right; sample 6 is fb -> next candidate 7 -> 2.5 s
    assert score(np.array(["none"] * 2 + ["fa"] * 10), _diag(labels), hold=1.0).isolation_delay == 2.5
    # a wrong label on the last faulty sample: never held to the end
    assert score(np.array(["none"] * 2 + ["fa"] * 10), _diag(labels[:-1] + ["fb"])).isolation_delay is None
    with pytest.raises(ParameterError, match="hold"):
        score(np.array(["none"] * 2 + ["fa"] * 10), _diag(labels), hold=-1.0)


def test_isolation_delay_skips_invalid_samples_and_ends_with_the_faulty_interval():
    """Sample 6 (fb) is invalid (held decision over a gap): it does not break the hold, so fa is held from sample 4
    (t = 2.0 s) -> delay 1.0 s.  The faulty interval ends at sample 9 (the truth returns to 'none'): the wrong labels
    after it do not matter."""
    labels = ["none", "none", "none", "unknown", "fa", "fa", "fb", "fa", "fa", "fa", "fb", "fb"]
    valid = np.ones(12, bool)
    valid[6] = False
    truth = np.array(["none"] * 2 + ["fa"] * 8 + ["none"] * 2)
    assert score(truth, _diag(labels, valid)).isolation_delay == 1.0
    assert score(truth, _diag(labels)).isolation_delay == 2.5  # with sample 6 valid: held from sample 7


def test_missed_and_healthy_traces():
    missed = score(np.array(["none"] * 2 + ["fa"] * 4), _diag(["none"] * 6))
    assert missed.missed and missed.isolation_delay is None and missed.correct_fraction is None
    healthy = score(np.array(["none"] * 6), _diag(["none"] * 3 + ["fa"] * 3))
    assert healthy.isolation_delay is None and healthy.correct_fraction is None and healthy.isolation_correct is None


def test_summary_isolation_fields():
    truth = np.array(["none"] * 2 + ["fa"] * 10)
    a = score(truth, _diag(["none", "none", "none", "unknown", "fa", "fa", "fb"] + ["fa"] * 5))  # delay 2.5
    b = score(truth, _diag(["none"] * 3 + ["fa"] * 9))  # named and held from sample 3: delay 0.5
    c = score(truth, _diag(["none"] * 2 + ["unknown"] * 10))  # never named
    sm = summarize([a, b, c])
    assert sm.mean_isolation_delay == 1.5 and sm.median_isolation_delay == 1.5
    assert sm.isolation_held_rate == pytest.approx(2 / 3, abs=1e-15)
    # correct fractions: a names fa on 7 of its 9 alarmed samples (3 … 11), b on 9 of 9, c on 0 of 10
    assert sm.mean_correct_fraction == pytest.approx((7 / 9 + 1.0 + 0.0) / 3, abs=1e-15)
    assert sm.isolation_accuracy == pytest.approx(2 / 3, abs=1e-15)
    assert math.isnan(summarize([score(np.array(["none"] * 12), _diag(["none"] * 12))]).mean_isolation_delay)


def test_scores_stored_before_the_new_fields_still_load():
    # fdikit.compare stores Score fields as JSON and rebuilds Score(**record): the two new fields default to None
    old = dict(label="fa", onset=1.0, detected=True, detection_delay=0.5, false_alarms=0, fault_free_hours=0.1,
               missed=False, isolated="fa", isolation_correct=True)
    s = Score(**old)
    assert s.isolation_delay is None and s.correct_fraction is None
