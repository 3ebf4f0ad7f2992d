"""The interfaces every design result and every evaluator follows (``docs/ARCHITECTURE.md``, "interfaces").

Two :class:`typing.Protocol` classes, checkable at run time with ``isinstance`` (which checks
that the members exist, not their signatures):

* :class:`DesignResult` — what a synthesis function in :mod:`fdikit.design` returns: the
  residual generator, the plant and filter joined (its internal form) and the design report.
* :class:`Evaluator` — a residual evaluator of :mod:`fdikit.decision`: ``fit`` on residuals,
  ``run`` a whole series, ``step`` one sample online with the same decisions, ``reset``.

:class:`FieldReport` is a base for design dataclasses whose report is a list of their fields;
:func:`joined_form` and :func:`no_internal_form` are the two ways a design answers ``internal_form()``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

if TYPE_CHECKING:
    from fdikit.model import FaultModel

__all__ = ["DesignResult", "Evaluator", "FieldReport", "ProblemDesign", "joined_form", "no_internal_form"]


@runtime_checkable
class DesignResult(Protocol):
    """A residual-generator design and its report.

    Attributes
    ----------
    generator : :class:`fdikit.residuals.ResidualGenerator`
        The filter reading the model's named controls and outputs.  Parameter-varying and
        time-varying designs hold their own generator types instead
        (:class:`~fdikit.design.parity.scheduled_generator.ScheduledResidualGenerator`,
        :class:`~fdikit.design.game.ltv_filter.LTVDetectionFilter`, or the scheduled design itself),
        each with its own ``run``.

    Examples
    --------
    >>> from fdikit.design.observers.full_order import observer
    >>> from fdikit.model import FaultModel
    >>> m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], controls=("u",), outputs=("y",))
    >>> d = observer(m, [-3.0])
    >>> isinstance(d, DesignResult), sorted(d.report())[:2]
    (True, ['covariance', 'gain'])
    >>> d.internal_form().inputs["u"]
    ('u',)
    """

    generator: Any

    def internal_form(self):
        """The plant and the filter in series, from ``(u, d, f, w)`` to ``r``.

        Returns
        -------
        FaultModel
            ``generator.internal_form(model)`` with the model the design was made for (Varga's internal
            form: decoupling and fault visibility read off as transfer functions, not plots).

        Raises
        ------
        DesignError
            When the design has no LTI internal form (time-varying or parameter-varying filters), or
            does not hold its model; the message says which.
        """
        ...

    def report(self) -> dict:
        """The design report: the quantities the design computed, by name.

        Returns
        -------
        dict
            A plain dict (a fresh one at each call; the arrays are the design's own).  Typical keys:
            ``gain`` (the observer gain, sign as in the design's docstring), ``poles`` (filter
            eigenvalues), detection ``spaces`` / ``projectors``, conditioning numbers, and attained
            attenuation or decoupling numbers.  Each design's ``report`` docstring lists its keys.
        """
        ...


@runtime_checkable
class Evaluator(Protocol):
    """A residual evaluator: decisions from residual series, in batch and online with the same result.

    Implemented by :class:`~fdikit.decision.threshold.ThresholdEvaluator`,
    :class:`~fdikit.decision.cusum.CusumEvaluator`, :class:`~fdikit.decision.glr.GlrEvaluator`,
    :class:`~fdikit.decision.sprt.SprtEvaluator`, :class:`~fdikit.decision.mhsprt.MhsprtEvaluator`,
    :class:`~fdikit.decision.narendra.NarendraEvaluator`,
    :class:`~fdikit.decision.learned.gaussian_ml.GaussianMlEvaluator` and
    :class:`~fdikit.decision.learned.bnn.BnnEvaluator`.

    Attributes
    ----------
    None in common: the members are the four methods; each evaluator documents its own parameters.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import Residuals
    >>> quiet = Residuals(np.arange(500) * 0.1, np.random.default_rng(0).standard_normal((500, 1)), ("r",), ())
    >>> ev = ThresholdEvaluator().fit(quiet, false_alarm_prob=1e-3)
    >>> isinstance(ev, Evaluator), ev.step([10.0]).alarm
    (True, True)
    """

    def fit(self, *args, **kwargs):
        """Fit the evaluator's statistics or parameters; returns the evaluator.

        The data differ by family: fault-free :class:`~fdikit.residuals.Residuals` (threshold, CUSUM,
        GLR, SPRT), residuals per hypothesis (MHSPRT), or labelled runs (Gaussian ML, BNN).  Fitting
        twice on the same data gives the same evaluator.
        """
        ...

    def run(self, residuals):
        """Decide every sample of a :class:`~fdikit.residuals.Residuals` series.

        Returns
        -------
        Diagnosis
            Alarms, per-residual decisions and the isolated fault per sample.  Does not disturb the
            online state used by :meth:`step`.
        """
        ...

    def step(self, r, *, valid: bool = True, names=None):
        """Decide one sample online (keyword arguments ``valid``, ``names``).

        Parameters
        ----------
        r : array_like
            The residual vector of one sample, in the fitted order (or in the order ``names`` gives).
        valid : bool
            False for an invalid sample (a gap): the evaluator holds its state.
        names : sequence of str, optional
            Names of the entries of ``r``.

        Returns
        -------
        StepDecision
            The same decision :meth:`run` gives for that sample, started from :meth:`reset`.
        """
        ...

    def reset(self) -> None:
        """Return the online state to the start of a run."""
        ...


def joined_form(design, model):
    """``design.generator.internal_form(model)``, the helper behind the designs' ``internal_form()``.

    Parameters
    ----------
    design : DesignResult
        A design with a :class:`~fdikit.residuals.ResidualGenerator` as ``generator``.
    model : FaultModel or None
        The model the design was made for.

    Returns
    -------
    FaultModel
        Plant and filter in series, from ``(u, d, f, w)`` to ``r``.

    Raises
    ------
    DesignError
        When ``model`` is None (a design made by hand, without its model, cannot join the plant).

    Examples
    --------
    >>> from fdikit.design.observers.full_order import observer
    >>> from fdikit.model import FaultModel
    >>> m = FaultModel([[-1.0]], [[1.0]], outputs=("y",))
    >>> joined_form(observer(m, [-2.0]), m).outputs
    ('y',)
    """
    if model is None:
        from fdikit.errors import DesignError

        raise DesignError(f"this {type(design).__name__} holds no model (it was not made by its design function); "
                          "call design.generator.internal_form(model) with the plant model")
    return design.generator.internal_form(model)


def no_internal_form(design, why: str) -> None:
    """Raise the error of a design without an LTI internal form (time-varying, scheduled, made on a DAE).

    Parameters
    ----------
    design : object
        The design (its type is named in the message).
    why : str
        The reason, for the message.

    Raises
    ------
    DesignError
        Always: ``"<type> has no internal form: <why>"``.

    Examples
    --------
    >>> no_internal_form(object(), "it varies with time")
    Traceback (most recent call last):
    ...
    fdikit.errors.DesignError: object has no internal form: it varies with time
    """
    from fdikit.errors import DesignError

    raise DesignError(f"{type(design).__name__} has no internal form: {why}")


@dataclass(frozen=True, eq=False)
class FieldReport:
    """Base of a design dataclass whose report is a set of its fields and whose model is a field.

    A subclass names its report quantities in ``REPORT`` (its Attributes section says what each
    gives); the design function sets ``model`` (keyword-only, so it follows the subclass's fields).

    Attributes
    ----------
    model : FaultModel or None
        The model the design was made for; :meth:`internal_form` joins it with ``generator``.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True, eq=False)
    ... class Toy(FieldReport):
    ...     gain: float
    ...     REPORT = ("gain",)
    >>> Toy(2.0).report()
    {'gain': 2.0}
    """

    REPORT: ClassVar[tuple[str, ...]] = ()
    model: FaultModel | None = field(default=None, repr=False, kw_only=True)

    def internal_form(self) -> FaultModel:
        """The plant ``model`` and ``generator`` in series, from ``(u, d, f, w)`` to ``r``.

        Returns
        -------
        FaultModel
            ``generator.internal_form(model)``.

        Raises
        ------
        DesignError
            When ``model`` is None (see :func:`joined_form`).
        """
        return joined_form(self, self.model)

    def report(self) -> dict:
        """The fields named in ``REPORT``, by name (a fresh dict; see the class's Attributes).

        Returns
        -------
        dict
        """
        return {name: getattr(self, name) for name in self.REPORT}


class ProblemDesign:
    """Base of a design that holds its :class:`~fdikit.design.game.setup.GameProblem` as ``problem``.

    :meth:`internal_form` joins ``problem.model`` (the model the targets and nuisance were resolved on) with
    ``generator``; the subclass gives :meth:`report`.

    Examples
    --------
    >>> from fdikit.design.game.single_fault import single_fault_game_filter
    >>> from fdikit.plants import white_speyer
    >>> isinstance(single_fault_game_filter(white_speyer(), "f1"), ProblemDesign)
    True
    """

    def internal_form(self) -> FaultModel:
        """The plant ``problem.model`` and ``generator`` in series, from ``(u, d, f, w)`` to ``r``.

        Returns
        -------
        FaultModel
            ``generator.internal_form(problem.model)``.
        """
        return joined_form(self, self.problem.model)
