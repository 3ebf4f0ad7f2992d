"""Learned residual classifiers (Douglas et al. 1996, Ch. 7): the Bayesian neural network and the
Gaussian maximum-likelihood classifier, trained on labelled runs.

* :mod:`fdikit.decision.learned.bnn` — Bayesian neural network residual processor (Douglas et al. 1996, Ch. 6); the
  network is in :mod:`fdikit.decision.learned.network`, the training-data helpers in
  :mod:`fdikit.decision.learned.labelled_runs`.
* :mod:`fdikit.decision.learned.network` — The recurrent logistic perceptron of the BNN with exact gradients
  (Douglas et al. 1996, Ch. 6, (6.1)).
* :mod:`fdikit.decision.learned.quasi_newton` — Quasi-Newton minimisation (DFP and BFGS updates) and Robbins–Monro
  step sizes (Douglas et al. 1996, §6.3).
* :mod:`fdikit.decision.learned.gaussian_ml` — Gaussian maximum-likelihood classifier as a single-layer perceptron
  (Douglas et al. 1996, §6.2.1).
* :mod:`fdikit.decision.learned.labelled_runs` — Labelled residual runs as training data, and residual rows as
  classifier inputs (Douglas et al. 1996, §6.2–6.4).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "bnn": [
            "BnnEvaluator", "TrainingReport",
        ],
        "network": [
            "BnnNetwork",
        ],
        "quasi_newton": [
            "QuasiNewtonResult", "quasi_newton", "robbins_monro_steps",
        ],
        "gaussian_ml": [
            "GaussianMlEvaluator",
        ],
        "labelled_runs": [
            "LabelledInputs", "as_runs", "one_hot_targets", "posterior_decisions",
        ],
    },
)
