"""Residual evaluation: turn residuals into a :class:`~fdikit.diagnosis.Diagnosis`.

Every evaluator has ``fit`` (fault-free or labelled residuals), ``run(residuals) -> Diagnosis``
(batch), ``step(r) -> StepDecision`` (online, identical decisions; a bad sample holds the
previous decision) and ``reset()``.
"""

from fdikit.decision.bnn import BnnEvaluator
from fdikit.decision.cusum import CusumEvaluator, cusum_arl, cusum_design
from fdikit.decision.gaussian_ml import GaussianMlEvaluator
from fdikit.decision.glr import GlrEvaluator, glr_threshold
from fdikit.decision.mhsprt import MhsprtEvaluator
from fdikit.decision.shiryayev import shiryayev_threshold
from fdikit.decision.sprt import SprtEvaluator, sprt_asn, sprt_thresholds
from fdikit.decision.threshold import ThresholdEvaluator, alpha_from_rate
from fdikit.decision.whiten import Whitened
from fdikit.diagnosis import StepDecision

__all__ = [
    "BnnEvaluator",
    "CusumEvaluator",
    "GaussianMlEvaluator",
    "GlrEvaluator",
    "MhsprtEvaluator",
    "SprtEvaluator",
    "StepDecision",
    "ThresholdEvaluator",
    "Whitened",
    "alpha_from_rate",
    "cusum_arl",
    "cusum_design",
    "glr_threshold",
    "shiryayev_threshold",
    "sprt_asn",
    "sprt_thresholds",
]
