"""The compiled online runtime: numba kernels for the online steps, a fused monitor, batch kernels, C export.

The reference implementations (:mod:`fdikit.residuals`, :mod:`fdikit.decision`, :mod:`fdikit.multimodel`) define
the results; this package computes the same numbers (to 1e-12 relative) at the speed a deployment needs.

* :mod:`fdikit.runtime.generator` — compiled residual-generator stepper (gaps by the reference gap rule).
* :mod:`fdikit.runtime.evaluators` — compiled evaluator steps (threshold, CUSUM, GLR, MHSSPRT).
* :mod:`fdikit.runtime.estimators` — compiled Kalman filter and IMM cycle.
* :mod:`fdikit.runtime.monitor` — a fused monitor: a detector's generator and evaluator in one step.
* :mod:`fdikit.runtime.lti_batch` — the batch LTI response: only the needed flops, bounded memory.
* :mod:`fdikit.runtime.c_export` — a designed detector as portable C99 for a target computer.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "generator": ["CompiledGenerator", "compile_generator"],
        "evaluators": ["CompiledEvaluator", "compile_evaluator"],
        "estimators": ["CompiledKalman", "CompiledIMM", "compile_kalman", "compile_imm"],
        "monitor": ["Monitor", "compile_detector"],
        "lti_batch": ["lsim"],
        "c_export": ["CExport", "export_c"],
    },
)
