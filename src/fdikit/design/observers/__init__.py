"""Observer-type residual generators: full-order observers, Beard–Jones and restricted-diagonal detection
filters, unknown-input observers, detection-gain families and the H∞-bounded detection filter.

Every design returns a dataclass whose ``gain`` is ``L`` in ``x̂⁺ = A x̂ + B u + L (y − C x̂ − D u)``.

* :mod:`fdikit.design.observers.full_order` — Observer-based residual generators: pole placement and the steady-
  state Kalman filter.
* :mod:`fdikit.design.observers.beard_jones` — Beard–Jones detection filters by left-eigenvector assignment, and
  restricted-diagonal filters.
* :mod:`fdikit.design.observers.uio` — Unknown-input observer (UIO) residual generators: one target fault, every
  other input decoupled.
* :mod:`fdikit.design.observers.detection_gain` — Observer gains that keep Beard–Jones detection spaces invariant
  (Douglas et al. 1996, App. C.1).
* :mod:`fdikit.design.observers.hinf` — H∞-bounded Beard–Jones detection filters (Douglas et al. 1996, App. C).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "full_order": [
            "ObserverDesign", "kalman", "observer", "observer_generator", "unobservable_modes",
        ],
        "beard_jones": [
            "BeardJonesDesign", "RestrictedDiagonalDesign", "beard_jones", "restricted_diagonal",
        ],
        "uio": [
            "UIODesign", "uio", "uio_bank", "unknown_input_matrix",
        ],
        "detection_gain": [
            "DetectionGainFamily", "detection_gain_family",
        ],
        "hinf": [
            "Enhancement", "HinfDesign", "enhancement_direction", "hinf_detection_filter",
        ],
    },
)
