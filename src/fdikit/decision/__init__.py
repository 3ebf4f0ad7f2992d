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

* :mod:`fdikit.decision.threshold` — Fixed thresholds per residual, calibrated on fault-free data, with k-of-n
  persistence.
* :mod:`fdikit.decision.cusum` — Two-sided CUSUM per residual (Page 1954; Basseville & Nikiforov 1993 §2.2), with
  Siegmund's ARL.
* :mod:`fdikit.decision.glr` — Window-limited GLR test for a change in mean of unknown size (Willsky & Jones 1976).
* :mod:`fdikit.decision.sprt` — Wald's sequential probability ratio test per residual block, single or repeated
  (Wald 1947).
* :mod:`fdikit.decision.mhsprt` — Multiple-hypothesis Shiryayev SPRT (Malladi & Speyer; Douglas et al. 1996, Ch. 7).
* :mod:`fdikit.decision.shiryayev` — Thresholds of the Shiryayev SPRT: the false-alarm bound and the dynamic-
  programming threshold (Douglas et al. 1996, §7.2.2–7.2.3).
* :mod:`fdikit.decision.densities` — Hypothesis densities for the multiple-hypothesis Shiryayev SPRT (Douglas et al.
  1996, §7.2).
* :mod:`fdikit.decision.whiten` — Prewhitening of coloured residuals before a test that assumes white ones (CUSUM,
  GLR, SPRT).
* :mod:`fdikit.decision.narendra` — Narendra-type evaluation filters with thresholds and structure-matrix matching
  (FDITOOLS' online FDD, Varga 2017 §3.6).
* :mod:`fdikit.decision.signature` — Isolation from a fault-signature (structure) table: the fault whose pattern
  of residual groups fired.
* :mod:`fdikit.decision.calibration` — Calibration on a list of fault-free runs, and the report of the false-alarm
  rate the data support.
* :mod:`fdikit.decision.common` — Pieces every evaluator shares: k-of-n persistence, holding decisions over bad
  samples, cached isolation, residual names checked against the fit.
* :mod:`fdikit.decision.learned` — Learned residual classifiers (Douglas et al. 1996, Ch. 7): the Bayesian neural
  network and the Gaussian maximum-likelihood classifier, trained on labelled runs.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submodules=["learned"],
    submod_attrs={
        "threshold": [
            "ThresholdEvaluator", "alpha_from_rate",
        ],
        "cusum": [
            "CusumEvaluator", "SIEGMUND_CORRECTION", "cusum_arl", "cusum_design",
        ],
        "glr": [
            "BlockLayout", "GlrEvaluator", "as_covariance", "fit_moments", "glr_threshold", "residual_blocks",
        ],
        "sprt": [
            "SprtEvaluator", "sprt_asn", "sprt_thresholds",
        ],
        "mhsprt": [
            "MhsprtEvaluator", "magnitude_blocks",
        ],
        "shiryayev": [
            "ShiryayevDP", "shiryayev_dp", "shiryayev_threshold",
        ],
        "densities": [
            "GaussianDensity", "UniformMeanDensity", "gaussian_mean_density",
        ],
        "whiten": [
            "Whitened", "yule_walker",
        ],
        "narendra": ["NarendraEvaluator", "narendra_signal"],
        "signature": [
            "MATCH_RULES", "SignatureTable", "as_signature_table", "signature_isolation",
        ],
        "calibration": [
            "CalibrationReport", "CalibrationRuns", "calibration_report", "calibration_runs",
        ],
        "common": [
            "check_fitted_names", "checked_names", "checked_residuals", "held", "is_count", "isolate_cached",
            "isolate_fired", "k_of_n", "step_vector",
        ],
        "learned": [
            "BnnEvaluator", "BnnNetwork", "BnnNetwork", "GaussianMlEvaluator", "QuasiNewtonResult",
            "QuasiNewtonResult", "TrainingReport", "quasi_newton", "quasi_newton", "robbins_monro_steps",
            "robbins_monro_steps",
        ],
    },
)
