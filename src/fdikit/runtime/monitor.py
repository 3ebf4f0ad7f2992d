"""The fused monitor: a detector's residual generator and evaluator, compiled, one ``step`` per sample.

:class:`Monitor` is the compiled twin of :class:`fdikit.detector_online.DetectorStepper`: ``step(u, y)`` takes the
absolute signals of one sample, runs the compiled filter step (:mod:`fdikit.runtime.generator`) and the compiled
evaluator step (:mod:`fdikit.runtime.evaluators`) on the residuals the evaluator was fitted to, with the
detector's warm-up and the gap rule's validity flags, and returns the alarm.  The full decision
(:class:`fdikit.diagnosis.StepDecision`, equal to the reference stepper's) is built only when asked for, by
:meth:`Monitor.decision` — a deployment loop reads ``alarm`` every sample and the decision when it fires.

Examples
--------
>>> import numpy as np
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.detector import Detector
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> m = compile_detector(Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",))))
>>> [m.step(np.ones(1), np.array([y])) for y in (0.0, 1.0, 1.9, 3.71)], m.decision().fault
([False, False, False, True], 'y_sensor')
"""

from __future__ import annotations

import copy

import numpy as np

from fdikit.detector import Detector
from fdikit.detector_online import missing_sample
from fdikit.errors import ParameterError
from fdikit.runtime.evaluators import compile_evaluator
from fdikit.runtime.generator import CompiledGenerator

__all__ = ["Monitor", "compile_detector"]


class Monitor:
    """A detector compiled for deployment: ``step(u, y)`` -> alarm; :meth:`decision` -> the StepDecision.

    Parameters
    ----------
    detector : Detector
        The detector; the monitor runs its own copy of the evaluator.
    dt : float, optional
        Sample time for a continuous generator.

    Attributes
    ----------
    detector : Detector
        The detector compiled.
    generator : CompiledGenerator
        The compiled filter step (its ``reference`` takes gaps and recovering samples).
    evaluator : CompiledEvaluator
        The compiled evaluator step.

    Raises
    ------
    ParameterError
        For something other than a Detector, or an evaluator the runtime does not compile.
    ModelError
        For a continuous generator without ``dt``.

    Examples
    --------
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> m = Monitor(Detector(g, ThresholdEvaluator(thresholds=[0.5])))
    >>> m.step(np.ones(1), np.zeros(1), valid=False), m.decision().valid, m.last_valid
    (False, False, False)
    """

    def __init__(self, detector: Detector, dt: float | None = None) -> None:
        if not isinstance(detector, Detector):
            raise ParameterError(f"detector must be a fdikit.detector.Detector, got {type(detector).__name__}")
        self.detector = detector
        self.generator = CompiledGenerator(detector.generator, dt=dt, residual_cov=detector.residual_cov,
                                           recovery_tol=detector.recovery_tol, select=detector.residual_names)
        self.evaluator = compile_evaluator(copy.deepcopy(detector.evaluator), names=detector.residual_names)
        self.reset()

    def reset(self) -> None:
        """Start a new run: the filter at rest, the evaluator reset, the warm-up again."""
        self.generator.reset()
        self.evaluator.reset()
        self._warm = self.detector.warmup_samples(self.generator.generator.dt)
        self._last = None

    @property
    def residuals(self) -> np.ndarray | None:
        """The residuals of the last sample in the evaluator's order (a copy; NaN on a bad sample; None before)."""
        return None if self._last is None else self._last.copy()

    @property
    def last_valid(self) -> bool:
        """The generator's validity flag of the last sample."""
        return self.generator.last_valid

    @property
    def last_recovering(self) -> bool:
        """Whether the last sample was recovering from a gap."""
        return self.generator.last_recovering

    @property
    def invalid(self) -> int:
        """Bad samples since creation or :meth:`reset`."""
        return self.generator.invalid

    def step(self, u, y, *, valid: bool = True) -> bool:
        """The alarm for one sample.

        Parameters
        ----------
        u, y : numpy.ndarray of float64, or sequence, or mapping of name to float
            Absolute controls and outputs in the detector's order (1-D float64 arrays take the compiled path);
            NaN marks a missing value.
        valid : bool, default True
            False for a sample the source flagged invalid: a dropout of every signal.

        Returns
        -------
        bool
            The evaluator's alarm (held on a bad or recovering sample, as the reference).

        Raises
        ------
        DataError
            For values that are not numbers, a mapping with other names, or the wrong number of values.
        """
        if not valid:
            u, y = missing_sample(u), missing_sample(y)
        r = self.generator.step(u, y)
        self._last = r
        ok = self.generator.reference.last_valid
        if self._warm:
            self._warm -= 1
            ok = False
        return self.evaluator.step(r, ok)

    def decision(self):
        """The :class:`fdikit.diagnosis.StepDecision` of the last sample (equal to the reference stepper's).

        Returns
        -------
        StepDecision
        """
        return self.evaluator.decision()

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
        g = self.generator.generator
        g.check_trace(trace)
        U, Y = trace.columns("u", g.controls), trace.columns("y", g.outputs)
        out = []
        for k in range(len(trace)):
            self.step(U[k], Y[k], valid=bool(trace.valid[k]))
            out.append(self.decision())
        return out


def compile_detector(detector: Detector, dt: float | None = None) -> Monitor:
    """The compiled monitor of a detector (:class:`Monitor`).

    Parameters
    ----------
    detector : Detector
        Generator and fitted evaluator.
    dt : float, optional
        Sample time for a continuous generator.

    Returns
    -------
    Monitor

    Raises
    ------
    ParameterError
        For something other than a Detector, or an evaluator the runtime does not compile.

    Examples
    --------
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), dt=1.0)
    >>> compile_detector(Detector(g, ThresholdEvaluator(thresholds=[1.0]))).step(np.zeros(0), np.ones(1))
    False
    """
    return Monitor(detector, dt)
