"""Residual generation: the LTI residual generator, its online stepper, banks, and the residual time series.

* :mod:`fdikit.residuals.generator` — :class:`~fdikit.residuals.generator.ResidualGenerator` (``r = Q(y, u)`` in
  state-space form: batch ``run``, online ``step`` with the gap rule of :mod:`fdikit.gaps`, Varga's internal form),
  :class:`~fdikit.residuals.generator.ResidualStepper`, :func:`~fdikit.residuals.generator.stack_generators`;
* :mod:`fdikit.residuals.series` — :class:`~fdikit.residuals.series.Residuals`, the series ``run`` returns.

Both are imported here: ``from fdikit.residuals import ResidualGenerator, Residuals``.
"""

from fdikit.residuals.generator import ResidualGenerator, ResidualStepper, stack_generators
from fdikit.residuals.series import Residuals

__all__ = ["ResidualGenerator", "ResidualStepper", "Residuals", "stack_generators"]
