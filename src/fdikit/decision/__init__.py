"""Residual evaluation: turn residuals into a :class:`~fdikit.diagnosis.Diagnosis`."""

from fdikit.decision.threshold import ThresholdEvaluator, alpha_from_rate
from fdikit.diagnosis import StepDecision

__all__ = ["StepDecision", "ThresholdEvaluator", "alpha_from_rate"]
