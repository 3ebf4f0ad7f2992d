"""Models from data: subspace identification, grey-box parameter fitting, model validation.

* :mod:`fdikit.identify.data` — Traces split into gap-free segments (NaN, ``valid == False``) with the means removed.
* :mod:`fdikit.identify.subspace` — N4SID / PO-MOESP identification of ``x⁺ = A x + B u + K e``, ``y = C x + D u + e``
  with the order by BIC of the prediction error (or the singular-value gap), ``B, D`` refitted on the simulation
  error, unstable eigenvalues reflected (Van Overschee & De Moor 1996, Ch. 4; Verhaegen 1994; Ljung 1999, §16.4).
* :mod:`fdikit.identify.greybox` — Physical parameters of a model by output-error least squares, with their
  standard errors (Ljung 1999, Ch. 7, Ch. 9).
* :mod:`fdikit.identify.correlation` — Residual whiteness (Ljung–Box) and input–residual independence tests
  (Ljung 1999, §16.6).
* :mod:`fdikit.identify.validation` — Validation on held-out data: fit per output, the two residual tests.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "correlation": ["CorrelationTest", "cross_correlation_test", "whiteness_test"],
        "data": ["IdentificationData", "segments"],
        "greybox": ["ParameterFit", "fit_parameters"],
        "subspace": ["IdentifiedModel", "subspace_id"],
        "validation": ["ValidationReport", "validate_model"],
    },
)
