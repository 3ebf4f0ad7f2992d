"""Residual evaluation: turn residuals into a :class:`~fdikit.diagnosis.Diagnosis`."""

from fdikit.decision.threshold import StepDecision, ThresholdEvaluator, alpha_from_rate

__all__ = ["StepDecision", "ThresholdEvaluator", "alpha_from_rate"]
