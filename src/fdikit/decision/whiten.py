"""Prewhitening of coloured residuals before a test that assumes white ones (CUSUM, GLR, SPRT).

Detection-filter residuals are coloured: their noise passes through the filter's slow poles.
:class:`Whitened` fits an autoregressive model ``r_k = Σ_{j=1}^{p} a_j r_{k−j} + e_k`` to each
fault-free residual (Yule–Walker, :func:`scipy.linalg.solve_toeplitz`), applies the inverse filter
``e_k = r_k − c − Σ a_j (r_{k−j} − c)`` and hands the innovations ``e`` to the wrapped evaluator,
which it fits on the whitened fault-free data.  A step of size ``b`` in ``r`` becomes a step of
``b`` in ``e`` at its first sample that settles to ``(1 − Σ a_j) b``: whitening trades the
steady part of a bias for white statistics (Basseville & Nikiforov 1993, §8.1, "innovation"
residual processing).
"""

from __future__ import annotations

from collections import deque

import numpy as np
import scipy.linalg
import scipy.signal

from fdikit.decision.common import is_count, step_vector
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["Whitened", "yule_walker"]


def yule_walker(x: np.ndarray, order: int) -> np.ndarray:
    """AR coefficients ``a_1 … a_p`` of a zero-mean series by the Yule–Walker equations.

    Parameters
    ----------
    x : (N,) array_like, or a list of them
        The series, mean already removed; several runs pool their autocovariances (no lag product
        crosses from one run into the next).
    order : int
        ``p``, the AR order; ``N > 2 p`` needed.

    Returns
    -------
    (p,) ndarray
        ``a_1 … a_p`` of ``x_k = Σ_j a_j x_{k−j} + e_k`` (biased autocovariances, a Toeplitz solve).

    Raises
    ------
    DataError
        When the series has ``2 p`` samples or fewer, or is constant.

    References
    ----------
    Basseville & Nikiforov 1993, §8.1 (innovation-based residual processing).

    Examples
    --------
    >>> import numpy as np
    >>> import scipy.signal
    >>> from fdikit.decision.whiten import yule_walker
    >>> x = scipy.signal.lfilter([1.0], [1.0, -0.9], np.random.default_rng(0).standard_normal(5000))
    >>> np.round(yule_walker(x, 1), 2).tolist()
    [0.9]
    """
    runs = [np.asarray(seg, dtype=float) for seg in x] if isinstance(x, list) else [np.asarray(x, dtype=float)]
    n = sum(seg.size for seg in runs)
    if n <= 2 * order:
        raise DataError(f"need more than {2 * order} samples for an AR({order}) fit, got {n}")
    acf = np.array([sum(seg[: seg.size - k] @ seg[k:] for seg in runs if seg.size > k) for k in range(order + 1)]) / n
    if acf[0] <= 0:
        raise DataError("the residual is constant; nothing to whiten")
    return scipy.linalg.solve_toeplitz(acf[:order], acf[1 : order + 1])


class Whitened:
    """An evaluator applied to AR-prewhitened residuals.

    Parameters
    ----------
    evaluator : evaluator
        An unfitted evaluator whose ``fit`` takes fault-free residuals (threshold, CUSUM, GLR, SPRT);
        ``fit_kwargs`` of :meth:`fit` are passed on to it.
    order : int, default 5
        AR order ``p`` per residual.

    Attributes
    ----------
    coef : (q, p) ndarray or None
        AR coefficients per residual after :meth:`fit`.
    center : (q,) ndarray or None
        Fault-free mean ``c`` per residual after :meth:`fit`.

    Raises
    ------
    ParameterError
        When ``order`` is not a positive integer.

    References
    ----------
    Basseville & Nikiforov 1993, §8.1 (innovation-based residual processing).

    Examples
    --------
    >>> import numpy as np
    >>> import scipy.signal
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.decision.whiten import Whitened
    >>> x = scipy.signal.lfilter([1.0], [1.0, -0.9], np.random.default_rng(0).standard_normal(5000))
    >>> healthy = Residuals(np.arange(5000) * 0.01, x[:, None], ("r",), ("f",))
    >>> w = Whitened(ThresholdEvaluator(), order=1).fit(healthy, false_alarm_prob=1e-3)
    >>> np.round(w.coef, 2).tolist(), round(float(w.evaluator.thresholds[0]), 1)
    ([[0.9]], 3.3)
    """

    def __init__(self, evaluator, order: int = 5) -> None:
        if not is_count(order, 1):
            raise ParameterError(f"order must be a positive integer, got {order}")
        self.evaluator, self.order = evaluator, int(order)
        self.coef: np.ndarray | None = None
        self.center: np.ndarray | None = None
        self.reset()

    def fit(self, residuals: Residuals | list[Residuals], **fit_kwargs) -> Whitened:
        """AR models from fault-free residuals (one run or a list), then the wrapped evaluator on their innovations.

        Several runs pool their mean and autocovariances (no lag crosses a run boundary) and the wrapped
        evaluator is fitted on the list of whitened runs.
        """
        runs = residuals if isinstance(residuals, list) else [residuals]
        rows = [res.r[res.valid] for res in runs]
        rows = [r[np.all(np.isfinite(r), axis=1)] for r in rows]
        self.center = np.concatenate(rows).mean(axis=0)
        self.coef = np.array([yule_walker([r[:, j] - self.center[j] for r in rows], self.order)
                              for j in range(self.center.size)])
        white = [self.whiten(res) for res in runs]
        self.evaluator.fit(white if isinstance(residuals, list) else white[0], **fit_kwargs)
        self.reset()
        return self

    def whiten(self, residuals: Residuals) -> Residuals:
        """The innovations ``e`` of ``residuals`` (NaN, invalid, on bad samples)."""
        if self.coef is None:
            raise ParameterError("the whitener is not fitted; call fit() on fault-free residuals")
        if residuals.r.shape[1] != self.coef.shape[0]:
            raise DataError(f"{residuals.r.shape[1]} residuals, the whitener was fitted on {self.coef.shape[0]}")
        valid = residuals.valid & np.all(np.isfinite(residuals.r), axis=1)
        x = residuals.r[valid] - self.center
        e = np.column_stack([scipy.signal.lfilter(np.r_[1.0, -a], [1.0], x[:, j]) for j, a in enumerate(self.coef)])
        out = np.full(residuals.r.shape, np.nan)
        out[valid] = e
        return Residuals(residuals.t, out, residuals.names, residuals.isolates, valid, dict(residuals.meta))

    def run(self, residuals: Residuals) -> Diagnosis:
        """Whiten (bad samples skipped, as :meth:`step` does) and run the wrapped evaluator."""
        d = self.evaluator.run(self.whiten(residuals))
        d.meta["whitening"] = {"order": self.order}
        return d

    def reset(self) -> None:
        self._past: deque = deque(maxlen=self.order)
        reset = getattr(self.evaluator, "reset", None)
        if reset is not None:
            reset()

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """One sample: the innovation from the last ``p`` valid samples, then the wrapped ``step``.

        The :class:`~fdikit.protocols.Evaluator` step: ``valid=False`` or a NaN/inf entry (a gap, or a
        recovering sample after one) skips the sample as :meth:`run` does — the AR memory is not advanced and
        the wrapped evaluator holds its decision; ``names`` (or a mapping ``{name: value}``) are checked
        against the residual names of the fit.
        """
        if self.coef is None:
            raise ParameterError("the whitener is not fitted; call fit() on fault-free residuals")
        r = step_vector(r, getattr(self.evaluator, "names", None), names, "the whitener")
        if not valid or not np.all(np.isfinite(r)):
            return self.evaluator.step(np.full(r.shape, np.nan), valid=False)  # skipped, as in run()
        x = r - self.center
        e = x.copy()
        for j, past in enumerate(reversed(self._past)):  # past[-1] is x_{k−1}
            e -= self.coef[:, j] * past
        self._past.append(x)
        return self.evaluator.step(e)
