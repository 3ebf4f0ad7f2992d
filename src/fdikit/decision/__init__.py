"""Residual evaluation: turn residuals into a :class:`~fdikit.diagnosis.Diagnosis`.

Every evaluator has ``fit`` (fault-free or labelled residuals), ``run(residuals) -> Diagnosis``
(batch), ``step(r, valid=True, names=None) -> StepDecision`` (online, identical decisions) and
``reset()``.

Invalid and recovering samples: ``run`` uses only the samples with ``residuals.valid`` True and a
finite residual; on every other sample — a NaN/inf residual (a gap), or a *recovering* sample after a
gap (:class:`~fdikit.residuals.ResidualStepper`) — no statistic is updated (CUSUM sums, SPRT
log-likelihood ratios, GLR windows, k-of-n persistence counters and hold timers, posteriors, network
feedback state) and the previous decision is held.  ``step(r, valid=stepper.last_valid)`` does the
same online, so batch and online decisions are identical.

Names: an evaluator remembers the residual names it was fitted on; ``run`` refuses a series whose
names differ (:class:`~fdikit.errors.DataError` naming the missing and the extra residuals, or the
positions of reordered ones: use ``residuals.select(evaluator.names)``), and so does ``step`` when
given ``names=`` (or a mapping ``{name: value}``).  Bad arguments raise
:class:`~fdikit.errors.ParameterError`.
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
