"""Nonlinear plants: operating points (trim), numerical linearisation, model reduction.

* :mod:`fdikit.nonlinear.linearize` — Central-difference linearisation of a ``NonlinearPlant`` with the step of every
  entry in the flat region (Douglas et al. 1996, Ch. 8 §8.3.1, Fig. 8.21).
* :mod:`fdikit.nonlinear.trim` — Operating points: equilibria and steady states (a straight run, a steady turn) under
  fixed states, controls, output targets and free derivatives (Douglas et al. 1996, Ch. 2 §2.2, Ch. 8 §8.3);
  ``trim_and_linearize`` gives the linear model and its operating point in one call.
* :mod:`fdikit.nonlinear.reduce` — Reduction of the linearised model: minimal realisation, residualisation, balanced
  truncation (Douglas et al. 1996, Ch. 2 §2.3).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "linearize": [
            "JacobianEstimate", "Linearization", "call_plant", "jacobian", "linearization", "linearize",
        ],
        "reduce": [
            "BalancedResult", "MinimalResult", "ResidualizedResult", "balanced_truncation", "minimal", "residualize",
        ],
        "trim": [
            "TrimResult", "trim", "trim_and_linearize",
        ],
    },
)
