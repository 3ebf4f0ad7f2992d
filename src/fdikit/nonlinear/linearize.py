"""Numerical linearisation of a :class:`~fdikit.simulate.NonlinearPlant` at an operating point.

``A = ∂f/∂x``, ``Bu = ∂f/∂u``, ``C = ∂h/∂x``, ``Du = ∂h/∂u`` by central differences with the step
of every entry chosen in the flat region of the estimate-versus-step curve, the procedure of
Douglas et al. 1996, Ch. 8 §8.3.1 ("Linearization at a Nominal Operating Point", Fig. 8.21): too
small a step is ruined by rounding (region I), too large a step by the nonlinearity (region III);
the estimate is taken where it stays flat (region II).  Each column is evaluated on a ladder of
steps ``h_k = 10^-k · max(1, |z_j|)``, ``k = 1 … 9`` (the report's normalised perturbations
``δx/x0`` of 1e-6 … 1e-3 lie inside it); for each entry the step whose estimate agrees best with
both neighbours on the ladder is kept, and that disagreement is the entry's error estimate.
Analytic Jacobians (``jacobian=``) bypass the differences.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from fdikit import validate
from fdikit.errors import FdiWarning, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.operating_point import OperatingPoint
from fdikit.simulate import NonlinearPlant

__all__ = ["JacobianEstimate", "Linearization", "call_plant", "jacobian", "linearization", "linearize"]

#: The ladder of normalised steps h_k / max(1, |z_j|): 1e-1 … 1e-9.
LADDER = 10.0 ** -np.arange(1, 10)
_BLOCKS = ("A", "Bu", "C", "Du")


@dataclass(frozen=True)
class JacobianEstimate:
    """A central-difference Jacobian with the step and error estimate of every entry.

    Attributes
    ----------
    J : (k, m) ndarray
        The Jacobian ``∂g/∂z``.
    steps : (k, m) ndarray
        The step [units of ``z_j``] each entry was taken at (0 for an analytic entry).
    error : (k, m) ndarray
        Error estimate: the larger disagreement of the chosen estimate with its neighbours on the ladder.

    Examples
    --------
    >>> est = jacobian(lambda z: np.array([np.sin(z[0]) * z[1]]), [0.3, 2.0])
    >>> bool(np.allclose(est.J, [[2 * np.cos(0.3), np.sin(0.3)]], rtol=1e-9)), est.steps.shape
    (True, (1, 2))

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1, Fig. 8.21 (choice of the perturbation size).
    """

    J: np.ndarray
    steps: np.ndarray
    error: np.ndarray


@dataclass(frozen=True)
class Linearization:
    """The linearised plant at an operating point, with the steps and error estimates per entry.

    Attributes
    ----------
    model : FaultModel
        Continuous model ``x' = A x + Bu u``, ``y = C x + Du u`` in deviations from the operating point,
        named as the plant; its ``operating_point`` is ``(x, u, y0)``, so generators designed from it run on
        the plant's absolute signals.
    x, u : ndarray
        The operating point (state, control).
    t : float
        The time [s] it was taken at.
    f0, y0 : ndarray
        ``f(t, x, u)`` (zero at an equilibrium) and ``h(t, x, u)`` there.
    steps : dict of str to ndarray
        Per block ``"A"``, ``"Bu"``, ``"C"``, ``"Du"``: the step each entry was taken at (0 if analytic).
    error : dict of str to ndarray
        Per block: the error estimate of each entry (0 if analytic).
    trim : TrimResult or None
        The trim the point came from (:func:`fdikit.nonlinear.trim.trim_and_linearize`), else None.

    Examples
    --------
    >>> plant = NonlinearPlant(f=lambda t, x, u: np.array([x[1], -np.sin(x[0]) + u[0]]),
    ...                        h=lambda t, x, u: x[:1], states=("theta", "omega"), outputs=("angle",),
    ...                        controls=("torque",))
    >>> lin = linearization(plant, [0.0, 0.0], [0.0])
    >>> np.round(lin.model.A, 9).tolist(), float(np.max(lin.error["A"])) < 1e-8
    ([[0.0, 1.0], [-1.0, 0.0]], True)

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (linearisation at a nominal operating point); Ch. 2 §2.2.
    """

    model: FaultModel
    x: np.ndarray
    u: np.ndarray
    t: float
    f0: np.ndarray
    y0: np.ndarray
    steps: dict
    error: dict
    trim: Any = None


def call_plant(plant: NonlinearPlant, which: str, t: float, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``plant.f`` or ``plant.h`` at ``(t, x, u)`` as a float vector of the declared length.

    Parameters
    ----------
    plant : NonlinearPlant
        The plant.
    which : {"f", "h"}
        The function to call.
    t : float
        Time [s].
    x, u : ndarray
        State and control.

    Returns
    -------
    ndarray
        ``(n,)`` for ``f``, ``(p,)`` for ``h``; non-finite values are passed on (the caller decides).

    Raises
    ------
    ModelError
        When the function returns something that is not one number per state (``f``) or output (``h``).

    Examples
    --------
    >>> plant = NonlinearPlant(f=lambda t, x, u: -x, h=lambda t, x, u: x, states=("x",), outputs=("y",),
    ...                        controls=())
    >>> call_plant(plant, "f", 0.0, np.array([2.0]), np.zeros(0)).tolist()
    [-2.0]

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (the nonlinear model ``x' = f(x, u)``).
    """
    size = len(plant.states) if which == "f" else len(plant.outputs)
    word = "state" if which == "f" else "output"
    try:
        value = np.asarray(getattr(plant, which)(t, x, u), dtype=float)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ModelError):
            raise
        raise ModelError(f"plant.{which}(t, x, u) must return {size} numbers (one per {word}); "
                         f"it returned something that is not numbers: {exc}") from None
    if value.ndim == 2 and 1 in value.shape:
        value = value.reshape(-1)
    if value.shape != (size,):
        raise ModelError(f"plant.{which}(t, x, u) returned shape {value.shape}, need ({size},) — one value per {word} "
                         f"({', '.join((plant.states if which == 'f' else plant.outputs)[:6])}"
                         f"{', …' if size > 6 else ''})")
    return value


def jacobian(fun: Callable[[np.ndarray], np.ndarray], z, *, step=None, rtol: float = 1e-6,
             name: str = "g") -> JacobianEstimate:
    """Central-difference Jacobian of ``fun`` at ``z`` with the step of each entry in the flat region.

    Parameters
    ----------
    fun : callable ``fun(z) -> (k,)``
        The function (a 1-D float array in and out).
    z : array_like, shape (m,)
        The point.
    step : float or array_like of shape (m,), optional
        A fixed step per column (absolute, > 0) instead of the ladder search (one evaluation pair per column).
    rtol : float, default 1e-6
        An entry whose error estimate exceeds ``rtol`` times the size of the terms of its row
        (``max(|g_i|, max_j |J_ij| max(1, |z_j|))``) raises an :class:`~fdikit.errors.FdiWarning`: no flat region found.
    name : str, default "g"
        What the warning calls the function.

    Returns
    -------
    JacobianEstimate
        ``J``, the step and the error estimate of every entry (error 0 with a fixed ``step``).

    Raises
    ------
    ParameterError
        For a ``z`` that is not a finite vector, a ``step`` that is not positive, or a ``rtol`` that is not > 0.
    ModelError
        When ``fun`` is not finite at ``z`` or at every step of a column's ladder.

    Examples
    --------
    >>> est = jacobian(lambda z: np.array([z[0] ** 3, np.exp(z[1])]), [1e3, 0.0])
    >>> bool(np.allclose(est.J, [[3e6, 0.0], [0.0, 1.0]], rtol=1e-10, atol=1e-9))
    True

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1, Fig. 8.21 (regions I–III of the estimate versus the perturbation size).
    """
    z = validate.as_vector("z (the point)", z)
    rtol = validate.positive("rtol", rtol)
    m = z.size
    scale = np.maximum(1.0, np.abs(z))
    g0 = np.asarray(fun(z), dtype=float)
    if not np.all(np.isfinite(g0)):
        raise ModelError(f"{name} is not finite at the operating point {z.tolist()}: {g0.tolist()}")
    k = g0.size
    if step is not None:
        steps = validate.as_vector("step", step) * np.ones(m) if np.ndim(step) == 0 else validate.as_vector(
            "step", step, m)
        if np.any(steps <= 0):
            raise ParameterError(f"step must be > 0 (one per column or one for all), got {steps.tolist()}")
        J = np.empty((k, m))
        for j in range(m):
            J[:, j] = _central(fun, z, j, steps[j])
            if not np.all(np.isfinite(J[:, j])):
                raise ModelError(f"{name} is not finite at z ± step along column {j} (step {steps[j]:.3g})")
        return JacobianEstimate(J, np.tile(steps, (k, 1)), np.zeros((k, m)))
    J, steps, err = np.empty((k, m)), np.empty((k, m)), np.empty((k, m))
    for j in range(m):
        h = LADDER * scale[j]
        D = np.array([_central(fun, z, j, hk) for hk in h])          # (K, k)
        bad = ~np.all(np.isfinite(D), axis=1)
        if bad.all():
            raise ModelError(f"{name} is not finite at z ± h along column {j} for every step h in "
                             f"{h[0]:.1e} … {h[-1]:.1e}")
        diff = np.full((len(h) + 1, k), np.inf)
        with np.errstate(invalid="ignore"):
            diff[1:-1] = np.abs(np.diff(D, axis=0))
        diff[np.isnan(diff)] = np.inf
        # the disagreement of estimate q with its neighbours (the ends have one neighbour)
        e = np.maximum(np.where(np.isinf(diff[:-1]), diff[1:], diff[:-1]),
                       np.where(np.isinf(diff[1:]), diff[:-1], diff[1:]))
        e[bad] = np.inf
        best = np.argmin(e, axis=0)                                  # first (largest step) among ties
        cols = np.arange(k)
        J[:, j], steps[:, j], err[:, j] = D[best, cols], h[best], e[best, cols]
    size = np.maximum(np.abs(g0), np.max(np.abs(J) * scale, axis=1, initial=0.0))
    loose = err * scale > rtol * size[:, None]
    if np.any(loose):
        i, j = map(int, np.argwhere(loose)[0])
        warnings.warn(f"no flat region of the central difference for ∂{name}_{i}/∂z_{j}: error estimate "
                      f"{err[i, j]:.2e} at step {steps[i, j]:.1e} for the estimate {J[i, j]:.6g} "
                      f"({int(loose.sum())} entr{'y' if loose.sum() == 1 else 'ies'} above rtol={rtol:g}); "
                      f"pass the analytic Jacobian or a fixed step", FdiWarning, stacklevel=2)
    return JacobianEstimate(J, steps, err)


def _central(fun, z, j, h):
    zp, zm = z.copy(), z.copy()
    zp[j] += h
    zm[j] -= h
    hh = zp[j] - zm[j]                       # the step actually represented in floating point
    with np.errstate(all="ignore"):
        return (np.asarray(fun(zp), dtype=float) - np.asarray(fun(zm), dtype=float)) / hh


def linearization(plant: NonlinearPlant, x, u, t: float = 0.0, *, step=None, rtol: float = 1e-6,
                  jacobian: Mapping[str, Callable] | None = None) -> Linearization:
    """Linearise ``plant`` at ``(x, u)``: the model, the steps chosen per entry and their error estimates.

    Parameters
    ----------
    plant : NonlinearPlant
        The plant ``x' = f(t, x, u)``, ``y = h(t, x, u)``.
    x : array_like, shape (n,)
        Operating state (an equilibrium from :func:`~fdikit.nonlinear.trim.trim`, or any point; ``f0`` reports
        ``f`` there).
    u : array_like, shape (m,)
        Operating control.
    t : float, default 0.0
        Time [s] (for a time-varying plant).
    step : float or array_like of shape (n + m,), optional
        Fixed absolute steps for the columns ``[x; u]`` instead of the flat-region search.
    rtol : float, default 1e-6
        Warning threshold of the error estimate, relative to the size of the row's terms (see :func:`jacobian`).
    jacobian : mapping, optional
        Analytic blocks ``{"A": dfdx, "Bu": dfdu, "C": dhdx, "Du": dhdu}``, each ``(t, x, u) -> matrix``; a given
        block bypasses the differences, a missing one is differenced.

    Returns
    -------
    Linearization
        ``model`` (continuous :class:`~fdikit.model.FaultModel` named as the plant), the operating point, ``f0``,
        ``y0``, and per block the steps and error estimates.

    Raises
    ------
    ParameterError
        For a plant that is not a NonlinearPlant, an ``x``/``u`` of the wrong size or not finite, a bad ``step`` or
        ``rtol``, or a ``jacobian`` that is not a mapping of the four block names to callables.
    ModelError
        When ``f``/``h`` return the wrong shape or a non-finite value at the point, or an analytic block has the
        wrong shape.

    Examples
    --------
    Van der Pol, ``x1' = x2``, ``x2' = μ (1 − x1²) x2 − x1 + u``, at ``x = (1, 2)`` with μ = 0.5:

    >>> mu = 0.5
    >>> vdp = NonlinearPlant(f=lambda t, x, u: np.array([x[1], mu * (1 - x[0]**2) * x[1] - x[0] + u[0]]),
    ...                      h=lambda t, x, u: np.array([x[0]]), states=("x1", "x2"), outputs=("y",),
    ...                      controls=("u",))
    >>> lin = linearization(vdp, [1.0, 2.0], [0.0])
    >>> np.round(lin.model.A, 10).tolist()   # [[0, 1], [-2 μ x1 x2 - 1, μ (1 - x1²)]]
    [[0.0, 1.0], [-3.0, 0.0]]

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (central differences, perturbation size in the flat region, Fig. 8.21),
    §8.3.2 (linearisation around a constant steering angle); Ch. 2 §2.2 (the linear model of the turning car).
    """
    validate.instance("plant", plant, NonlinearPlant, "build one with fdikit.simulate.NonlinearPlant(f, h, ...)")
    n, p, m = len(plant.states), len(plant.outputs), len(plant.controls)
    x = validate.as_vector("x (the operating state)", x, n)
    u = validate.as_vector("u (the operating control)", u, m)
    t = validate.number("t", t)
    analytic = _analytic_blocks(jacobian)
    f0 = call_plant(plant, "f", t, x, u)
    y0 = call_plant(plant, "h", t, x, u)
    for which, value in (("f", f0), ("h", y0)):
        if not np.all(np.isfinite(value)):
            raise ModelError(f"plant.{which} is not finite at the operating point x={x.tolist()}, u={u.tolist()}: "
                             f"{value.tolist()}")
    if step is not None and np.ndim(step) != 0:
        step = validate.as_vector("step", step, n + m)
    z = np.concatenate([x, u])
    blocks, steps, error = {}, {}, {}
    for which, (bx, bu), k in (("f", ("A", "Bu"), n), ("h", ("C", "Du"), p)):
        for block, cols, size in ((bx, slice(0, n), n), (bu, slice(n, n + m), m)):
            if block in analytic:
                blocks[block] = _analytic(block, analytic[block], t, x, u, (k, size))
                steps[block], error[block] = np.zeros((k, size)), np.zeros((k, size))
                continue
            if size == 0 or k == 0:
                blocks[block], steps[block], error[block] = (np.zeros((k, size)) for _ in range(3))
                continue

            def g(zc, which=which, cols=cols):
                zz = z.copy()
                zz[cols] = zc
                return call_plant(plant, which, t, zz[:n], zz[n:])

            fixed = None if step is None else (step if np.ndim(step) == 0 else step[cols])
            est = _jacobian(g, z[cols], step=fixed, rtol=rtol, name=f"{which}[{block}]")
            blocks[block], steps[block], error[block] = est.J, est.steps, est.error
    op = OperatingPoint.from_vectors(plant.states, plant.controls, plant.outputs, x, u, y0)
    model = FaultModel(A=blocks["A"], C=blocks["C"], Bu=blocks["Bu"], Du=blocks["Du"], states=plant.states,
                       outputs=plant.outputs, controls=plant.controls, operating_point=op)
    return Linearization(model, x, u, t, f0, y0, steps, error)


_jacobian = jacobian


def linearize(plant: NonlinearPlant, x, u, t: float = 0.0, *, step=None, rtol: float = 1e-6,
              jacobian: Mapping[str, Callable] | None = None) -> FaultModel:
    """The linearised plant at ``(x, u)`` as a continuous :class:`~fdikit.model.FaultModel`.

    ``linearization(...).model``; see :func:`linearization` for the steps and error estimates.

    Parameters
    ----------
    plant : NonlinearPlant
        The plant.
    x, u : array_like
        Operating state (n,) and control (m,).
    t : float, default 0.0
        Time [s].
    step : float or array_like, optional
        Fixed absolute steps for the columns ``[x; u]`` instead of the flat-region search.
    rtol : float, default 1e-6
        Warning threshold of the error estimates.
    jacobian : mapping, optional
        Analytic blocks ``{"A", "Bu", "C", "Du"}`` as callables ``(t, x, u) -> matrix``.

    Returns
    -------
    FaultModel
        ``A = ∂f/∂x``, ``Bu = ∂f/∂u``, ``C = ∂h/∂x``, ``Du = ∂h/∂u``; states, outputs, controls named as the plant.

    Examples
    --------
    The hanging pendulum ``θ'' = −(g/l) sin θ − c θ' + τ`` (g/l = 9.81, c = 0.1), ``y = θ``:

    >>> pend = NonlinearPlant(f=lambda t, x, u: np.array([x[1], -9.81 * np.sin(x[0]) - 0.1 * x[1] + u[0]]),
    ...                       h=lambda t, x, u: x[:1], states=("theta", "omega"), outputs=("angle",),
    ...                       controls=("torque",))
    >>> m = linearize(pend, [0.0, 0.0], [0.0])
    >>> m, np.round(m.A, 9).tolist(), m.controls
    (FaultModel(continuous, n=2, p=1, u=1, d=0, f=0, w=0), [[0.0, 1.0], [-9.81, -0.1]], ('torque',))

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (linearisation at a nominal operating point, Fig. 8.21).
    """
    return linearization(plant, x, u, t, step=step, rtol=rtol, jacobian=jacobian).model


def _analytic_blocks(jac) -> dict:
    if jac is None:
        return {}
    if not isinstance(jac, Mapping):
        raise ParameterError(f"jacobian must be a mapping of {', '.join(_BLOCKS)} to callables (t, x, u) -> matrix, "
                             f"got {type(jac).__name__}")
    unknown = [key for key in jac if key not in _BLOCKS]
    if unknown:
        raise ParameterError(f"jacobian has unknown block(s) {unknown}; the blocks are {', '.join(_BLOCKS)}")
    for key, fn in jac.items():
        if not callable(fn):
            raise ParameterError(f"jacobian[{key!r}] must be callable (t, x, u) -> matrix, got {type(fn).__name__}")
    return dict(jac)


def _analytic(block, fn, t, x, u, shape):
    try:
        M = np.asarray(fn(t, x, u), dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"jacobian[{block!r}](t, x, u) did not return numbers: {exc}") from None
    if M.size == 0 and 0 in shape:
        return np.zeros(shape)
    if M.shape != shape:
        raise ModelError(f"jacobian[{block!r}](t, x, u) returned shape {M.shape}, need {shape}")
    if not np.all(np.isfinite(M)):
        raise ModelError(f"jacobian[{block!r}](t, x, u) is not finite at the operating point")
    return M
