"""The online side of a :class:`~fdikit.detector.Detector`: one decision per sample (the deployment API).

``Detector.online()`` returns a :class:`DetectorStepper`; ``step(u, y)`` takes the absolute signals of one sample
and returns the evaluator's :class:`~fdikit.diagnosis.StepDecision`, identical to the batch ``Detector.run``.

Examples
--------
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.detector import Detector
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> s = Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",))).online()
>>> [s.step([1.0], [y]).fault for y in (0.0, 1.0, 1.9, 3.71)]
['none', 'none', 'none', 'y_sensor']
"""

from __future__ import annotations

import copy
from collections.abc import Mapping

import numpy as np

from fdikit.detector import Detector
from fdikit.errors import ParameterError

__all__ = ["DetectorStepper", "missing_sample"]


def missing_sample(values):
    """NaN in place of every value of a sample flagged invalid, keeping the names and the shape to be checked.

    Parameters
    ----------
    values : sequence of float or mapping of name to float
        One sample's controls or outputs.

    Returns
    -------
    numpy.ndarray or dict
        The same shape (or names) with every value NaN; anything that is not numbers is returned as it is, for
        the generator's step to report.

    Examples
    --------
    >>> missing_sample({"u": 1.0}), missing_sample([1.0, 2.0]).tolist()
    ({'u': nan}, [nan, nan])
    """
    if isinstance(values, Mapping):
        return {k: float("nan") for k in values}
    try:
        return values if values is None or isinstance(values, (str, bytes)) else np.full(np.shape(values), np.nan)
    except ValueError:  # ragged: the generator's step reports it
        return values


class DetectorStepper:
    """Online deployment of a :class:`Detector`: ``step(u, y)`` -> the evaluator's StepDecision.

    Parameters
    ----------
    detector : Detector
        The detector; the stepper runs its own copy of the evaluator.
    dt : float, optional
        Sample time for a continuous generator.

    Attributes
    ----------
    residuals : numpy.ndarray or None
        The residuals of the last sample (NaN on a bad one), in the evaluator's order.
    last_valid, last_recovering : bool
        The generator's flags of the last sample.
    invalid : int
        Bad samples since creation or :meth:`reset`.

    Raises
    ------
    ModelError
        For a continuous generator without ``dt``.

    Examples
    --------
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> s = Detector(g, ThresholdEvaluator(thresholds=[0.5])).online()
    >>> s.step([1.0], [0.0], valid=False).valid, s.last_valid
    (False, False)
    """

    def __init__(self, detector: Detector, dt: float | None = None) -> None:
        if not isinstance(detector, Detector):
            raise ParameterError(f"detector must be a fdikit.detector.Detector, got {type(detector).__name__}")
        self.detector = detector
        self._gen = detector.generator.online(dt=dt, residual_cov=detector.residual_cov,
                                              recovery_tol=detector.recovery_tol)
        self._ev = copy.deepcopy(detector.evaluator)
        self.reset()

    def reset(self) -> None:
        """Start a new run: the filter at rest, the evaluator reset."""
        self._gen.reset()
        self._ev.reset()
        self.residuals = None
        self._warm = self.detector.warmup_samples(self._gen.generator.dt)

    @property
    def last_valid(self) -> bool:
        return self._gen.last_valid

    @property
    def last_recovering(self) -> bool:
        return self._gen.last_recovering

    @property
    def invalid(self) -> int:
        return self._gen.invalid

    def step(self, u, y, *, valid: bool = True):
        """Decision for one sample.

        Parameters
        ----------
        u, y : sequence of float or mapping of name to float
            Absolute controls and outputs, in the detector's ``controls``/``outputs`` order or by name; NaN marks
            a missing value.
        valid : bool, default True
            False for a sample the source flagged invalid (as ``trace.valid``): treated as a dropout of
            every signal.

        Returns
        -------
        StepDecision
            The evaluator's decision (held, ``valid`` False, on a bad or recovering sample).

        Raises
        ------
        DataError
            For values that are not numbers, a mapping with other names, or the wrong number of values.
        """
        if not valid:
            u, y = missing_sample(u), missing_sample(y)
        r = self._gen.step(u, y)
        idx = self.detector._index
        r = r if idx is None else r[idx]
        self.residuals = r
        warm = self._warm > 0
        self._warm -= warm
        return self._ev.step(r, valid=self._gen.last_valid and not warm)

    def run(self, trace) -> list:
        """Step through a whole trace (its ``valid`` flags included): one StepDecision per sample.

        Parameters
        ----------
        trace : Trace
            Absolute signals, holding every control and output the detector reads.

        Returns
        -------
        list of StepDecision

        Raises
        ------
        DataError
            On a missing signal.
        """
        g = self._gen.generator
        g.check_trace(trace)
        U, Y = trace.columns("u", g.controls), trace.columns("y", g.outputs)
        ok = getattr(trace, "valid", None)
        ok = np.ones(len(trace), bool) if ok is None else ok
        return [self.step(U[k], Y[k], valid=bool(ok[k])) for k in range(len(trace))]
