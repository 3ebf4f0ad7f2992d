"""fdikit: model-based fault detection, isolation and fault-tolerant control.

The layers, from data to decisions (``docs/ARCHITECTURE.md``):

* model layer — :mod:`fdikit.model` (:class:`FaultModel`, LTI with named signals), :mod:`fdikit.lpv`,
  :mod:`fdikit.ltv`, :mod:`fdikit.dae`, :mod:`fdikit.gaussian`, :mod:`fdikit.descriptor` (:class:`DescriptorModel`);
  :mod:`fdikit.plants` (benchmark plants);
* signals — :mod:`fdikit.faults` (+ :mod:`fdikit.fault_spec`), :mod:`fdikit.simulate`, :mod:`fdikit.trace`
  (+ :mod:`fdikit.trace_io`), :mod:`fdikit.gaps`;
* residual generation — :mod:`fdikit.design` (observers, game, parity families), :mod:`fdikit.residuals`;
* decisions — :mod:`fdikit.decision` (evaluators), :mod:`fdikit.detector` (a deployable detector, saved by
  :mod:`fdikit.detector_file`), :mod:`fdikit.multimodel` (banks of estimators),
  :mod:`fdikit.estimate` (fault sizes), :mod:`fdikit.diagnosis`, :mod:`fdikit.metrics`, :mod:`fdikit.compare`;
* analysis and plots — :mod:`fdikit.analysis`, :mod:`fdikit.linalg` (+ :mod:`fdikit.linalg.subspaces`,
  :mod:`fdikit.fault_maps`), :mod:`fdikit.plots`;
* infrastructure — :mod:`fdikit.errors`, :mod:`fdikit.validate`, :mod:`fdikit.atomic`, :mod:`fdikit.resume`,
  :mod:`fdikit.protocols`;
* reproductions of the source documents — :mod:`fdikit.studies`.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submodules=["analysis", "decision", "design", "estimate", "multimodel", "plants", "studies"],
    submod_attrs={
        "errors": ["DataError", "DesignError", "FdiError", "FdiWarning", "ModelError", "ParameterError"],
        "detector": ["Detector"],
        "detector_online": ["DetectorStepper"],
        "model": ["FaultModel"],
        "descriptor.model": ["DescriptorModel"],
    },
)
__version__ = "0.1.0"
