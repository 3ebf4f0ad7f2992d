"""Detector(warmup=): the first seconds of a run are not valid for decisions, batch and online alike, and saved."""

from __future__ import annotations

import numpy as np

from fdikit.decision import ThresholdEvaluator
from fdikit.detector import Detector
from fdikit.residuals import ResidualGenerator
from fdikit.trace import Trace


def _detector(warmup):
    # observer of x+ = 0.9 x + u, y = x started at 0 while the plant starts at x = 5: the residual 5·0.4^k decays
    g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=0.1)
    return Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",)), warmup=warmup)


def _trace():
    x = 5.0 * 0.9 ** np.arange(40)
    return Trace(np.arange(40) * 0.1, np.zeros((40, 1)), x[:, None], ("u",), ("y",))


def test_warmup_hides_the_initial_transient_in_batch_and_online(tmp_path):
    tr = _trace()
    assert _detector(0.0).run(tr).alarm[:3].all()            # 5, 2.5, 1.25 > 0.5: the start transient alarms
    det = _detector(0.5)                                      # 5 samples
    d = det.run(tr)
    assert not d.alarm.any() and not d.valid[:5].any() and d.valid[5:].all()
    online = [s.alarm for s in det.online().run(tr)]
    assert online == d.alarm.tolist()
    back = Detector.load(det.save(tmp_path / "d.json"))
    assert back.warmup == 0.5 and back.run(tr).alarm.tolist() == d.alarm.tolist()
    stepper = back.online()
    stepper.run(tr)
    stepper.reset()                                           # a new run warms up again
    assert not stepper.step([0.0], [5.0]).valid
