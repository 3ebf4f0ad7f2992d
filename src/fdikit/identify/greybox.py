"""Grey-box identification: the physical parameters of a model by output-error least squares.

``build(params)`` returns the plant (a :class:`~fdikit.model.FaultModel` or a
:class:`~fdikit.simulate.NonlinearPlant`); :func:`fdikit.simulate.simulate` runs it on the
data's inputs (each gap-free segment from the plant's initial state) and
:func:`scipy.optimize.least_squares` minimises the scaled output error

    V(θ) = Σ_k Σ_i ((ŷ_i(k; θ) − y_i(k)) / s_i)²

with ``s_i`` the scale of output ``i`` (Ljung 1999, Ch. 7: the prediction-error criterion with
the output-error predictor).
Each trace is one experiment, simulated as a whole from ``x0`` (the state is not known after a gap, so the
simulation runs through it): an output sample that is not finite or has ``valid == False`` is left out of
the error; a non-finite control cannot be simulated through and is refused (split the trace into
separate experiments, each starting at ``x0``).
With ``s_i`` the noise standard deviation of output ``i`` (or any scale under which the scaled
errors have one common variance), the covariance of the estimate is asymptotically
``σ̂² (JᵀJ)⁻¹``, ``J`` the Jacobian of the scaled errors at the optimum and
``σ̂² = V(θ̂) / (N − d)`` (N residuals, d parameters; Ljung 1999, Ch. 9: the asymptotic distribution of the estimate).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.simulate import NonlinearPlant, simulate
from fdikit.trace import Trace

__all__ = ["ParameterFit", "fit_parameters"]


@dataclass(frozen=True, eq=False)
class ParameterFit:
    """Estimated parameters with their uncertainty.

    Attributes
    ----------
    params : (d,) array
        The estimate ``θ̂``.
    names : tuple of str
        Parameter names.
    std : (d,) array
        Standard errors (square roots of the diagonal of ``covariance``).
    covariance : (d, d) array
        ``σ̂² (JᵀJ)⁻¹``.
    sigma2 : float
        ``σ̂²``, the variance of the scaled output error (about 1 when the scales are the noise std).
    fit : (p,) array
        Output fit per output in percent, ``100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)``.
    outputs : tuple of str
        The outputs fitted.
    model : FaultModel or NonlinearPlant
        ``build(params)``.
    result : scipy.optimize.OptimizeResult
        The raw least-squares result (``nfev``, ``status``, ``message`` …).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> def build(p):
    ...     return FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[p[0]]], controls=["u"], outputs=["y"])
    >>> tr = simulate(build([3.0]), t=np.arange(100) * 0.1, u=np.ones((100, 1)), measurement_noise_std=0.01, rng=0)
    >>> est = fit_parameters(build, [1.0], tr, scale=0.01, names=["gain"])
    >>> list(est.as_dict()), bool(abs(est.params[0] - 3.0) < 5 * est.std[0])
    (['gain'], True)

    References
    ----------
    Ljung 1999, Ch. 9 (the asymptotic covariance).
    """

    params: np.ndarray
    names: tuple[str, ...]
    std: np.ndarray
    covariance: np.ndarray
    sigma2: float
    fit: np.ndarray
    outputs: tuple[str, ...]
    model: object
    result: object

    def as_dict(self) -> dict[str, tuple[float, float]]:
        """``{name: (estimate, standard error)}``."""
        return {n: (float(v), float(s)) for n, v, s in zip(self.names, self.params, self.std)}


def _plant(build, params) -> FaultModel | NonlinearPlant:
    plant = build(params)
    if not isinstance(plant, FaultModel | NonlinearPlant):
        raise ModelError(f"build(params) returned a {type(plant).__name__}; it must return a FaultModel or a "
                         "NonlinearPlant")
    return plant


def fit_parameters(
    build: Callable[[np.ndarray], FaultModel | NonlinearPlant],
    p0,
    data,
    *,
    outputs: Sequence[str] | None = None,
    names: Sequence[str] | None = None,
    bounds=(-np.inf, np.inf),
    scale=None,
    x0=None,
    method: str = "rk4",
    substeps: int = 4,
    **least_squares_options,
) -> ParameterFit:
    """Fit the parameters of ``build(params)`` to measured outputs by output-error least squares.

    Parameters
    ----------
    build : callable ``params -> FaultModel | NonlinearPlant``
        The plant for a parameter vector (the same signal names for every vector).
    p0 : (d,) array_like
        Initial parameters (finite; also their scale for the trust region, ``x_scale = |p0|``).
    data : Trace or sequence of Trace
        Measured controls and outputs (absolute: a FaultModel's operating point is applied), one
        experiment per trace, each starting at ``x0``.  Output samples that are NaN or have
        ``valid == False`` are left out of the error (module docstring).
    outputs : sequence of str, optional
        The outputs to fit (default all of the plant's).
    names : sequence of str, optional
        Parameter names (default ``p0, p1 …``).
    bounds : (lower, upper), default no bounds
        As :func:`scipy.optimize.least_squares` (scalars or one value per parameter).
    scale : float or (p,) array_like, optional
        Scale ``s_i`` of each fitted output; default the standard deviation of the measured output.
        Give the noise standard deviations for covariances in absolute terms.
    x0 : (n,) array_like, optional
        Initial state of every segment (default the plant's: zero, or ``NonlinearPlant.x0``).
    method, substeps :
        Integration of a NonlinearPlant (:func:`fdikit.simulate.simulate`).
    **least_squares_options
        Passed to :func:`scipy.optimize.least_squares` (e.g. ``diff_step``, ``max_nfev``).

    Returns
    -------
    ParameterFit
        Estimates, standard errors, covariance, the fit per output, the model and the raw result.

    Raises
    ------
    ParameterError
        For a bad ``p0``, ``names``, ``scale`` or an output the plant does not have.
    ModelError
        When ``build`` does not return a plant.
    DataError
        When the data lack the plant's signals, hold a non-finite control, have no usable output
        sample, or the traces' sample times differ.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> def build(p):
    ...     return FaultModel(A=[[-p[0]]], C=[[1.0]], Bu=[[p[0]]], controls=["u"], outputs=["y"])
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(400) * 0.05
    >>> tr = simulate(build([2.0]), t=t, u=np.sign(np.sin(t))[:, None], measurement_noise_std=0.01, rng=rng)
    >>> est = fit_parameters(build, [1.0], tr, scale=0.01, names=["pole"])
    >>> bool(abs(est.params[0] - 2.0) < 4 * est.std[0]), bool(0.5 < est.sigma2 < 1.5)
    (True, True)

    References
    ----------
    Ljung 1999, Ch. 7 (the prediction-error criterion, output-error predictor), Ch. 9 (asymptotic covariance).
    """
    from scipy.optimize import least_squares

    p0 = validate.as_vector("p0", p0)
    d = p0.size
    names = tuple(f"p{k}" for k in range(d)) if names is None else tuple(names)
    if len(names) != d:
        raise ParameterError(f"{len(names)} parameter names for {d} parameters; give one name per entry of p0")
    plant = _plant(build, p0)
    outputs = tuple(plant.outputs if outputs is None else outputs)
    missing = [o for o in outputs if o not in plant.outputs]
    if missing:
        raise ParameterError(f"outputs {missing} are not outputs of the plant; it has {list(plant.outputs)}")
    cols = [plant.outputs.index(o) for o in outputs]
    traces = [data] if isinstance(data, Trace) else list(data) if isinstance(data, Sequence) else []
    if not traces or not all(isinstance(tr, Trace) for tr in traces):
        raise DataError(f"data must be a Trace or a non-empty list of Traces, got {type(data).__name__}")
    us, ys, masks = [], [], []
    for k, tr in enumerate(traces):
        u, y = tr.columns("u", plant.controls), tr.columns("y", outputs)
        if not np.all(np.isfinite(u)):
            row = int(np.argwhere(~np.isfinite(u))[0, 0])
            raise DataError(f"trace {k} has a non-finite control at sample {row} (t={tr.t[row]:g}); the plant cannot "
                            "be simulated through it: split the trace there into separate experiments")
        if abs(tr.dt - traces[0].dt) > 1e-9 * traces[0].dt:
            raise DataError(f"trace {k} has sample time {tr.dt:g} s, trace 0 {traces[0].dt:g} s; use one sample time")
        ok = np.isfinite(y) & np.asarray(getattr(tr, "valid", np.ones(len(tr), bool)), bool)[:, None]
        us.append((tr.t - tr.t[0], u))
        ys.append(np.where(ok, y, 0.0))
        masks.append(ok)
    if not any(m.any() for m in masks):
        raise DataError("the data hold no finite, valid output sample to fit")
    if scale is None:
        scale = np.array([np.concatenate([y[m[:, i], i] for y, m in zip(ys, masks)]).std()
                          for i in range(len(outputs))])
        scale = np.where(scale > 0, scale, 1.0)
    else:
        scale = validate.as_vector("scale", np.broadcast_to(np.asarray(scale, float), (len(outputs),)))
        if np.any(scale <= 0):
            raise ParameterError(f"scale must be positive (one per output {list(outputs)}), got {scale.tolist()}")

    def simulated(params) -> list[np.ndarray]:
        pl = _plant(build, params)
        op = getattr(pl, "operating_point", None)
        u0 = op.control_values(pl.controls) if op is not None else 0.0
        y0 = op.output_values(pl.outputs)[cols] if op is not None else 0.0
        out = []
        for t, u in us:
            tr = simulate(pl, t=t, u=u - u0, x0=x0, method=method, substeps=substeps)
            out.append(tr.y[:, cols] + y0)
        return out

    def residual(params) -> np.ndarray:
        return np.concatenate([((ysim - y) / scale)[m] for ysim, y, m in zip(simulated(params), ys, masks)])

    options = {"x_scale": np.where(p0 != 0, np.abs(p0), 1.0), **least_squares_options}
    res = least_squares(residual, p0, bounds=bounds, **options)
    N = res.fun.size
    if N <= d:
        raise ParameterError(f"{N} residuals for {d} parameters; fit needs more samples than parameters")
    sigma2 = float(2.0 * res.cost / (N - d))
    J = np.atleast_2d(res.jac)
    cov = sigma2 * np.linalg.pinv(J.T @ J)
    sims = simulated(res.x)
    fit = np.empty(len(outputs))
    for i in range(len(outputs)):
        y_i = np.concatenate([y[m[:, i], i] for y, m in zip(ys, masks)])
        e_i = np.concatenate([(ysim - y)[m[:, i], i] for ysim, y, m in zip(sims, ys, masks)])
        fit[i] = 100.0 * (1.0 - np.linalg.norm(e_i) / np.linalg.norm(y_i - y_i.mean()))
    return ParameterFit(res.x, names, np.sqrt(np.diag(cov)), cov, sigma2, fit, outputs, build(res.x), res)
