"""Residual generation: the LTI residual generator, its online stepper, banks, and the residual time series.

* :mod:`fdikit.residuals.generator` — :class:`~fdikit.residuals.generator.ResidualGenerator` (``r = Q(y, u)`` in
  state-space form: batch ``run``, online ``step`` with the gap rule of :mod:`fdikit.gaps`, Varga's internal form),
  :class:`~fdikit.residuals.generator.ResidualStepper`;
* :mod:`fdikit.residuals.bank` — :func:`~fdikit.residuals.bank.stack_generators` (a bank of filters as one, each
  reading its own signals);
* :mod:`fdikit.residuals.series` — :class:`~fdikit.residuals.series.Residuals`, the series ``run`` returns.

All are imported here: ``from fdikit.residuals import ResidualGenerator, Residuals``.
"""

from fdikit.residuals.bank import stack_generators
from fdikit.residuals.generator import ResidualGenerator, ResidualStepper
from fdikit.residuals.series import Residuals

__all__ = ["ResidualGenerator", "ResidualStepper", "Residuals", "stack_generators"]
