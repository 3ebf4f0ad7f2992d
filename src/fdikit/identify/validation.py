"""Validation of a model on held-out data: simulation fit per output and the two residual tests.

* Fit (MATLAB ``compare``): the model simulated from the data's inputs (its initial state fitted
  by least squares on each segment), ``fit = 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`` per output, in percent.
* Residual: the one-step prediction error ``ε = y − C x̂ − D u`` of the predictor
  ``x̂⁺ = A x̂ + B u + K ε`` (``K`` the identified innovation gain; initial state fitted likewise),
  tested for whiteness and for independence of the inputs at a stated level
  (:mod:`fdikit.identify.correlation`; Ljung 1999, §16.6).

The data are absolute: the model's operating point (``model.operating_point``) is subtracted
first.  Gaps (NaN, ``valid == False``) split the data into segments, each simulated on its own.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, FdiWarning, ParameterError
from fdikit.identify.correlation import CorrelationTest, cross_correlation_test, whiteness_test
from fdikit.identify.data import segments
from fdikit.identify.subspace import IdentifiedModel
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel

__all__ = ["ValidationReport", "validate_model"]


@dataclass(frozen=True, eq=False)
class ValidationReport:
    """Fit and residual tests of a model on validation data.

    Attributes
    ----------
    outputs, controls : tuple of str
        The signals compared and the inputs used.
    fit : (p,) array
        Simulation fit per output in percent (100 is a perfect fit; it can be negative; ``-inf`` for an
        unstable model, whose simulation diverges: a :class:`~fdikit.errors.FdiWarning` says so).
    whiteness : CorrelationTest
        Ljung–Box test of each output's prediction error.
    cross : CorrelationTest or None
        Prediction error against each input (None without controls).
    simulated, prediction_error : list of arrays
        Per segment: the simulated outputs (absolute) and the one-step prediction errors.
    level, lags : float, int
        The tests' level ``α`` and largest lag ``M``.
    samples : int
        Samples compared.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.5]], C=[[1.0]], Bu=[[1.0]], dt=1.0)
    >>> tr = simulate(plant, t=np.arange(200.0), u=np.random.default_rng(2).standard_normal((200, 1)))
    >>> rep = validate_model(plant, tr)
    >>> rep.fit.round(6).tolist(), list(rep.to_pandas().columns[:2])
    ([100.0], ['fit_percent', 'whiteness_statistic'])

    References
    ----------
    Ljung 1999, §16.5–16.6.
    """

    outputs: tuple[str, ...]
    controls: tuple[str, ...]
    fit: np.ndarray
    whiteness: CorrelationTest
    cross: CorrelationTest | None
    simulated: list
    prediction_error: list
    level: float
    lags: int
    samples: int

    @property
    def passed(self) -> bool:
        """True when every whiteness and every cross-correlation test passes."""
        return bool(np.all(self.whiteness.passed) and (self.cross is None or np.all(self.cross.passed)))

    def to_pandas(self):
        """One row per output: fit, Ljung–Box statistic, threshold, p-value, pass; and per input the same.

        Returns
        -------
        pandas.DataFrame
            Indexed by output name.
        """
        import pandas as pd

        w = self.whiteness
        cols = {"fit_percent": self.fit, "whiteness_statistic": w.statistic, "whiteness_threshold": w.threshold,
                "whiteness_pvalue": w.pvalue, "white": w.passed}
        if self.cross is not None:
            c = self.cross
            for j, name in enumerate(self.controls):
                cols[f"cross_{name}_statistic"] = c.statistic[:, j]
                cols[f"cross_{name}_threshold"] = c.threshold
                cols[f"cross_{name}_pvalue"] = c.pvalue[:, j]
                cols[f"independent_of_{name}"] = c.passed[:, j]
        return pd.DataFrame(cols, index=pd.Index(self.outputs, name="output"))

    def plot(self, ax=None):
        """Residual autocorrelation (and input cross-correlation) with the per-lag confidence bound.

        Parameters
        ----------
        ax : matplotlib Axes or a pair of Axes, optional
            One Axes draws the autocorrelation only; two draw both.  Default: a new figure with two.

        Returns
        -------
        The Axes drawn into (a numpy array of two for a new figure).
        """
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots(1, 2 if self.cross is not None else 1, figsize=(9, 3.2), squeeze=False)
            ax = ax.ravel()
        axes = np.atleast_1d(ax)
        lags = np.arange(self.lags + 1)
        a0 = axes[0]
        for i, name in enumerate(self.outputs):
            a0.plot(lags[1:], self.whiteness.correlation[1:, i], "o-", ms=3, label=name)
        a0.axhspan(-self.whiteness.bound, self.whiteness.bound, color="0.85", zorder=0)
        a0.set(xlabel="lag", ylabel="autocorrelation", title=f"prediction error (α = {self.level:g})")
        a0.legend(fontsize="small")
        if len(axes) > 1 and self.cross is not None:
            for i, yn in enumerate(self.outputs):
                for j, un in enumerate(self.controls):
                    axes[1].plot(lags, self.cross.correlation[:, i, j], "o-", ms=3, label=f"{yn} / {un}")
            axes[1].axhspan(-self.cross.bound, self.cross.bound, color="0.85", zorder=0)
            axes[1].set(xlabel="lag", ylabel="cross-correlation", title="prediction error vs inputs")
            axes[1].legend(fontsize="small")
        return ax


def _observability(F: np.ndarray, C: np.ndarray, N: int) -> np.ndarray:
    """``[C; C F; …; C F^{N−1}]`` as an (N, p, n) array, by doubling."""
    O, Fk = C[None], F
    while len(O) < N:
        O = np.concatenate([O, O @ Fk])
        Fk = Fk @ Fk
    return O[:N]


def _fit_x0(F: np.ndarray, C: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``x0`` minimising ``Σ_k ‖r_k − C F^k x0‖²``."""
    N, p = r.shape
    return np.linalg.lstsq(_observability(F, C, N).reshape(N * p, -1), r.reshape(-1), rcond=None)[0]


def validate_model(model, data, *, lags: int = 20, level: float = 0.01, gain=None,
                   initial_state: str = "estimate") -> ValidationReport:
    """Fit per output, residual whiteness and input–residual independence on held-out data.

    Parameters
    ----------
    model : IdentifiedModel or FaultModel
        An identified model (its ``K`` is the predictor gain) or a FaultModel: discrete at the
        data's sample time, or continuous (discretised by ZOH at it).  The predictor gain of a
        FaultModel is ``gain`` if given, else ``Bw`` when its noise group is an innovation
        (``p`` noise inputs with ``Dw = I``), else zero (the residual is the simulation error).
    data : Trace or sequence of Trace
        Validation data (absolute signals; not those the model was fitted on).
    lags : int >= 1, default 20
        Largest lag ``M`` of the correlation tests.
    level : float in (0, 1), default 0.01
        Significance level of each test.
    gain : (n, p) array_like, optional
        Predictor gain ``K`` (overrides the model's).
    initial_state : {"estimate", "zero"}, default "estimate"
        Fit the initial state of each segment by least squares, or start from zero.

    Returns
    -------
    ValidationReport

    Raises
    ------
    ParameterError
        For a model of another type, a bad gain, lags, level or initial_state.
    DataError
        When the data's sample time differs from a discrete model's, or the data lack its signals.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.8]], C=[[1.0]], Bu=[[1.0]], Bw=[[0.5]], Dw=[[1.0]], dt=1.0)
    >>> rng = np.random.default_rng(3)
    >>> tr = simulate(plant, t=np.arange(3000.0), u=rng.standard_normal((3000, 1)), noise_std=0.2, rng=rng)
    >>> rep = validate_model(plant, tr)
    >>> bool(80 < rep.fit[0] < 90), rep.passed  # noise std ≈ 0.26 against an output std ≈ 1.7: fit ≈ 85 %
    (True, True)

    References
    ----------
    Ljung 1999, §16.6 (residual analysis), §16.5 (model validation: simulation on fresh data).
    """
    K = None
    if isinstance(model, IdentifiedModel):
        model, K = model.model, model.K
    validate.instance("model", model, FaultModel, "pass an IdentifiedModel (subspace_id) or a FaultModel")
    validate.choice("initial_state", initial_state, ("estimate", "zero"))
    ds = segments(data, model.controls, model.outputs, min_length=lags + 2, detrend=False)
    if model.is_discrete:
        if abs(model.dt - ds.dt) > 1e-9 * ds.dt:
            raise DataError(f"the data are sampled at {ds.dt:g} s but the model at {model.dt:g} s; validate on data "
                            "at the model's sample time")
    else:
        model = model.discretize(ds.dt)
    n, p = model.n, model.p
    if gain is not None:
        K = validate.as_matrix("gain", gain, (n, p))
    elif K is None:
        innovation = len(model.noise) == p and np.array_equal(model.Dw, np.eye(p))
        K = model.Bw if innovation else np.zeros((n, p))
    op = model.operating_point
    u0 = op.control_values(model.controls) if op is not None else np.zeros(len(model.controls))
    y0 = op.output_values(model.outputs) if op is not None else np.zeros(p)
    A, B, C, D = model.A, model.Bu, model.C, model.Du
    F = A - K @ C
    if np.any(np.abs(np.linalg.eigvals(F)) >= 1):
        raise ParameterError("the predictor A − K C is not stable; the prediction error would diverge (check the "
                             "gain, or pass gain= a stabilising Kalman gain)")
    diverges = bool(np.any(np.abs(np.linalg.eigvals(A)) >= 1))
    if diverges:
        warnings.warn(f"the model has the unstable eigenvalues {np.round(_unstable(A), 4).tolist()}: its simulation "
                      "diverges, so the fit is -inf (the prediction-error tests still run); identify a stable model "
                      "(subspace_id(..., stable=True))", FdiWarning, stacklevel=2)
    sims, errs, us = [], [], []
    num = np.zeros(p)
    den_parts = []
    for u, y in zip(ds.u, ds.y):
        u, y = u - u0, y - y0
        ys = np.full_like(y, np.nan) if diverges else dlsim_blocked(A, B, C, D, u)[0]
        eps, _, _ = dlsim_blocked(F, np.hstack([B - K @ D, K]), -C, np.hstack([-D, np.eye(p)]), np.hstack([u, y]))
        if initial_state == "estimate":
            if not diverges:
                ys = ys + _response(A, C, _fit_x0(A, C, y - ys), len(y))
            eps = eps - _response(F, C, _fit_x0(F, C, eps), len(y))
        sims.append(ys + y0)
        errs.append(eps)
        us.append(u)
        num += np.sum((y - ys) ** 2, axis=0)
        den_parts.append(y)
    yall = np.concatenate(den_parts)
    den = np.sum((yall - yall.mean(axis=0)) ** 2, axis=0)
    fit = 100.0 * (1.0 - np.sqrt(num) / np.sqrt(np.where(den > 0, den, np.nan)))
    if diverges:
        fit = np.full(p, -np.inf)
    white = whiteness_test(errs, lags, level)
    cross = cross_correlation_test(errs, us, lags, level) if model.controls else None
    return ValidationReport(model.outputs, model.controls, fit, white, cross, sims, errs, white.level, white.lags,
                            ds.samples)


def _unstable(A: np.ndarray) -> np.ndarray:
    lam = np.linalg.eigvals(A)
    return lam[np.abs(lam) >= 1]


def _response(F: np.ndarray, C: np.ndarray, x0: np.ndarray, N: int) -> np.ndarray:
    """Free response ``C F^k x0`` for ``k = 0 … N−1``."""
    return _observability(F, C, N) @ x0
