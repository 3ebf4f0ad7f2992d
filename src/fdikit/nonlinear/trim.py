"""Operating points of a :class:`~fdikit.simulate.NonlinearPlant`: equilibria and steady states.

The PATH report finds its nominal points by simulating until steady state (Douglas et al. 1996, Ch. 8 §8.3.1:
about 300 s for the straight run at 27 m/s; Ch. 2 §2.2: the 0.005 rad steady turn of 638.73 m radius at
24.87 m/s).  :func:`trim` solves for the point directly, in the vocabulary of python-control's
``find_eqpt``: ``x0``/``u0`` are the initial guess, ``ix``/``iu`` the states and controls held at those values,
``y0``/``iy`` output targets, ``dx0``/``idx`` derivative targets.  A derivative left out of ``idx`` is free — the
heading ``ψ' = r`` of a steady turn, the position of a straight run — and an output target expresses a
constraint such as the radius of the turn (curvature ``r / v = 1 / R``).  Signals may be named.  The equations
are solved by :func:`scipy.optimize.least_squares`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from fdikit import validate
from fdikit.errors import DesignError, ParameterError
from fdikit.nonlinear.linearize import Linearization, call_plant, linearization
from fdikit.simulate import NonlinearPlant

__all__ = ["TrimResult", "trim", "trim_and_linearize"]


@dataclass(frozen=True)
class TrimResult:
    """An operating point found by :func:`trim`.

    Attributes
    ----------
    x, u, y : ndarray
        State, control and output ``h(t, x, u)`` at the point.
    dx : ndarray
        ``f(t, x, u)`` (zero at an equilibrium; a free derivative keeps its value, e.g. ``ψ' = r``).
    residual : float
        Largest absolute violation of the imposed equations (derivative targets and output targets).
    success : bool
        Whether ``residual <= tol · scale`` (always True for a returned result; a failure raises).
    iterations : int
        Function evaluations of the solver.
    scale : float
        The size the residual is compared with: 1 + the largest target + the largest term of the equations
        (``max_i Σ_j |∂r_i/∂z_j| max(1, |z_j|)``).
    free : tuple of str
        The unknowns solved for (state and control names).

    Examples
    --------
    >>> plant = NonlinearPlant(f=lambda t, x, u: -x + u, h=lambda t, x, u: 2 * x, states=("x",), outputs=("y",),
    ...                        controls=("u",))
    >>> op = trim(plant, [0.0], [0.0], y0=[4.0])
    >>> op.success, np.round(op.x, 12).tolist(), np.round(op.u, 12).tolist(), op.free
    (True, [2.0], [2.0], ('x', 'u'))

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (nominal operating point ``f(x0, u0) = 0``).
    """

    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    dx: np.ndarray
    residual: float
    success: bool
    iterations: int
    scale: float
    free: tuple


def trim(plant: NonlinearPlant, x0=None, u0=None, y0=None, *, t: float = 0.0, ix=(), iu=None, iy=None, dx0=None,
         idx=None, tol: float = 1e-9, max_iterations: int = 1000) -> TrimResult:
    """Find an operating point: ``f(t, x, u)[idx] = dx0[idx]`` and ``h(t, x, u)[iy] = y0[iy]``.

    Parameters
    ----------
    plant : NonlinearPlant
        The plant.
    x0 : array_like, shape (n,), optional
        Initial guess of the state (default ``plant.x0``); the states in ``ix`` are held at these values.
    u0 : array_like, shape (m,), optional
        Initial guess of the control (default zeros); the controls in ``iu`` are held at these values.
    y0 : array_like of shape (p,) or mapping name -> value, optional
        Output targets.  A mapping (``{"curvature": 1 / R}``) targets the outputs it names; an array targets the
        outputs in ``iy`` (all when ``iy`` is omitted).
    t : float, default 0.0
        Time [s].
    ix : sequence of str or int, default ()
        States held at ``x0`` (e.g. the speed of a 27 m/s run); the others are solved for.
    iu : sequence of str or int, optional
        Controls held at ``u0``.  Default as ``find_eqpt``: all controls when there are no output targets, none when
        there are.
    iy : sequence of str or int, optional
        Outputs an array ``y0`` targets (all by default).
    dx0 : array_like of shape (n,) or mapping name -> value, optional
        Derivative targets (zero by default: an equilibrium); a mapping sets the named states' targets.
    idx : sequence of str or int, optional
        Derivatives that must meet ``dx0`` (all by default); the others are free (the heading of a steady turn).
    tol : float, default 1e-9
        Success when the largest equation residual is ``<= tol · scale`` (see :class:`TrimResult`).
    max_iterations : int, default 1000
        Limit of the solver's function evaluations.

    Returns
    -------
    TrimResult
        ``x``, ``u``, ``y``, ``dx``, ``residual``, ``success``, ``iterations``, ``scale``, ``free``.

    Raises
    ------
    ParameterError
        For a plant that is not a NonlinearPlant, guesses or targets of the wrong size or not finite, an unknown
        signal name or an index out of range, a ``tol`` or ``max_iterations`` out of range.
    ModelError
        When ``f`` or ``h`` returns the wrong shape.
    DesignError
        When no point meets the equations within ``tol`` (the message gives the residual, the worst equation and
        the point reached).

    Examples
    --------
    The pendulum ``θ'' = −9.81 sin θ − 0.1 θ' + τ`` with no torque: from a guess near θ = 3 the solver finds the
    upright equilibrium θ = π.

    >>> pend = NonlinearPlant(f=lambda t, x, u: np.array([x[1], -9.81 * np.sin(x[0]) - 0.1 * x[1] + u[0]]),
    ...                       h=lambda t, x, u: x[:1], states=("theta", "omega"), outputs=("angle",),
    ...                       controls=("torque",))
    >>> op = trim(pend, [3.0, 0.0], [0.0])
    >>> round(float(op.x[0]), 10), op.residual < 1e-9
    (3.1415926536, True)

    Holding the pendulum at 30° takes the torque 9.81 sin 30° (the torque is solved for because of ``y0``):

    >>> op = trim(pend, [0.0, 0.0], [0.0], y0={"angle": np.pi / 6})
    >>> round(float(op.u[0]), 10)
    4.905

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3.1 (nominal point ``f(x0, u0) = 0``, the 27 m/s straight run), §8.3.2 and
    Ch. 2 §2.2 (the steady constant-radius turn at a fixed steering angle).
    """
    validate.instance("plant", plant, NonlinearPlant, "build one with fdikit.simulate.NonlinearPlant(f, h, ...)")
    n, p, m = len(plant.states), len(plant.outputs), len(plant.controls)
    x0 = plant.x0 if x0 is None else validate.as_vector("x0 (the state guess)", x0, n)
    u0 = np.zeros(m) if u0 is None else validate.as_vector("u0 (the control guess)", u0, m)
    t = validate.number("t", t)
    tol = validate.positive("tol", tol)
    max_iterations = validate.integer("max_iterations", max_iterations, minimum=1)
    # output targets
    if isinstance(y0, Mapping):
        if iy is not None:
            raise ParameterError("give iy only with an array y0; a mapping y0 names its outputs itself")
        iy = _indices("y0", list(y0), plant.outputs, "output")
        y_target = np.array([validate.number(f"y0[{plant.outputs[i]!r}]", y0[key]) for i, key in zip(iy, y0)])
    elif y0 is not None:
        y_full = validate.as_vector("y0 (the output targets)", y0, p)
        iy = list(range(p)) if iy is None else _indices("iy", iy, plant.outputs, "output")
        y_target = y_full[iy]
    else:
        if iy is not None:
            raise ParameterError("iy selects outputs of y0; give y0 (the output targets) too")
        iy, y_target = [], np.zeros(0)
    # derivative targets
    dx_full = np.zeros(n)
    if isinstance(dx0, Mapping):
        for i, key in zip(_indices("dx0", list(dx0), plant.states, "state"), dx0):
            dx_full[i] = validate.number(f"dx0[{plant.states[i]!r}]", dx0[key])
    elif dx0 is not None:
        dx_full = validate.as_vector("dx0 (the derivative targets)", dx0, n)
    idx = list(range(n)) if idx is None else _indices("idx", idx, plant.states, "state")
    dx_target = dx_full[idx]
    ix = _indices("ix", ix, plant.states, "state")
    iu = (list(range(m)) if not iy else []) if iu is None else _indices("iu", iu, plant.controls, "control")
    free_x = [i for i in range(n) if i not in ix]
    free_u = [i for i in range(m) if i not in iu]
    free = tuple(plant.states[i] for i in free_x) + tuple(plant.controls[i] for i in free_u)

    def point(z):
        x, u = x0.copy(), u0.copy()
        x[free_x] = z[:len(free_x)]
        u[free_u] = z[len(free_x):]
        return x, u

    def equations(z):
        x, u = point(z)
        dx = call_plant(plant, "f", t, x, u)
        y = call_plant(plant, "h", t, x, u) if iy else np.zeros(p)
        return np.concatenate([dx[idx] - dx_target, y[iy] - y_target])

    z0 = np.concatenate([x0[free_x], u0[free_u]])
    r0 = equations(z0)
    if not np.all(np.isfinite(r0)):
        raise ParameterError(f"the plant is not finite at the initial guess x0={x0.tolist()}, u0={u0.tolist()}; "
                             f"start from a point where f and h are defined")
    targets = np.concatenate([dx_target, y_target])
    if r0.size == 0:
        raise ParameterError("nothing to solve: no derivative or output is constrained (idx and iy are empty)")
    if z0.size == 0:
        z, nfev = z0, 1
    else:
        sol = least_squares(equations, z0, method="trf",
                            x_scale=np.maximum(1.0, np.abs(z0)), xtol=1e-15, ftol=1e-15, gtol=1e-15,
                            max_nfev=max_iterations)
        z, nfev = sol.x, int(sol.nfev)
    res = equations(z)
    residual = float(np.max(np.abs(res)))
    scale = 1.0 + float(np.max(np.abs(targets), initial=0.0)) + _term_size(equations, z)
    x, u = point(z)
    dx = call_plant(plant, "f", t, x, u)
    y = call_plant(plant, "h", t, x, u)
    if not (np.isfinite(residual) and residual <= tol * scale):
        names = [f"d{plant.states[i]}/dt" for i in idx] + [plant.outputs[i] for i in iy]
        worst = int(np.nanargmax(np.abs(res))) if np.any(np.isfinite(res)) else 0
        raise DesignError(f"no operating point found: residual {residual:.3e} > tol · scale = {tol * scale:.3e} "
                          f"(worst equation {names[worst]}: {res[worst]:.3e}) after {nfev} evaluations, at "
                          f"x={np.round(x, 6).tolist()}, u={np.round(u, 6).tolist()}; check that the targets are "
                          f"reachable with the free variables {list(free)}, or try another guess")
    return TrimResult(x, u, y, dx, residual, True, nfev, scale, free)


def _term_size(equations, z) -> float:
    """``max_i Σ_j |∂r_i/∂z_j| max(1, |z_j|)`` by forward differences (the size of the terms that cancel)."""
    if z.size == 0:
        return 0.0
    r = equations(z)
    s = np.maximum(1.0, np.abs(z))
    total = np.zeros(r.size)
    for j in range(z.size):
        zz = z.copy()
        h = 1e-7 * s[j]
        zz[j] += h
        with np.errstate(all="ignore"):
            total += np.abs((equations(zz) - r) / h) * s[j]
    total = total[np.isfinite(total)]
    return float(np.max(total, initial=0.0))


def _indices(what: str, items, names: Sequence[str], word: str) -> list[int]:
    if isinstance(items, str | int | np.integer):
        items = [items]
    try:
        items = list(items)
    except TypeError:
        raise ParameterError(f"{what} must be a sequence of {word} names or indices, got {items!r}") from None
    out = []
    for item in items:
        if isinstance(item, str):
            if item not in names:
                raise ParameterError(f"{what}: unknown {word} {item!r}; the plant's {word}s are {list(names)}")
            out.append(names.index(item))
        elif isinstance(item, int | np.integer) and not isinstance(item, bool):
            if not -len(names) <= item < len(names):
                raise ParameterError(f"{what}: {word} index {item} out of range for {len(names)} {word}s")
            out.append(int(item) % len(names))
        else:
            raise ParameterError(f"{what}: {item!r} is neither a {word} name nor an index")
    if len(set(out)) != len(out):
        raise ParameterError(f"{what} lists a {word} twice: {items}")
    return out


def trim_and_linearize(plant: NonlinearPlant, x0=None, u0=None, y0=None, *, step=None, rtol: float = 1e-6,
                       jacobian=None, **trim_options) -> Linearization:
    """Trim the plant and linearise it there, in one call: the model and its operating point together.

    :func:`trim` with ``x0``, ``u0``, ``y0`` and ``trim_options``, then
    :func:`~fdikit.nonlinear.linearize.linearization` at the point found (``step``, ``rtol``, ``jacobian``).

    Parameters
    ----------
    plant : NonlinearPlant
        The plant.
    x0, u0, y0 : optional
        Initial guesses and output targets, as for :func:`trim`.
    step, rtol, jacobian : optional
        As for :func:`~fdikit.nonlinear.linearize.linearization`.
    **trim_options
        ``t``, ``ix``, ``iu``, ``iy``, ``dx0``, ``idx``, ``tol``, ``max_iterations`` of :func:`trim`.

    Returns
    -------
    Linearization
        ``model`` in deviation coordinates with ``model.operating_point`` = the trimmed ``(x, u, y)``, the
        steps and error estimates, and ``trim`` (the :class:`TrimResult`).

    Raises
    ------
    DesignError
        When the trim fails (see :func:`trim`).
    ParameterError
        For a bad argument of either step.

    Examples
    --------
    A tank ``h' = (q − √h) / 2`` with outflow ``√h`` measured: the level 4 needs the inflow 2.

    >>> tank = NonlinearPlant(f=lambda t, x, u: np.array([(u[0] - np.sqrt(x[0])) / 2]),
    ...                       h=lambda t, x, u: np.array([np.sqrt(x[0])]), states=("level",), outputs=("outflow",),
    ...                       controls=("inflow",), x0=np.array([4.0]))
    >>> lin = trim_and_linearize(tank, x0=[4.0], u0=[1.0], ix=["level"], iu=[])
    >>> lin.model.operating_point.u0, round(float(lin.model.A[0, 0]), 6)   # ∂f/∂h = −1/(4 √h) = −1/8
    ({'inflow': 2.0}, -0.125)

    References
    ----------
    Douglas et al. 1996, Ch. 8 §8.3 (the nominal operating point, then the linearisation about it).
    """
    point = trim(plant, x0, u0, y0, **trim_options)
    lin = linearization(plant, point.x, point.u, trim_options.get("t", 0.0), step=step, rtol=rtol, jacobian=jacobian)
    return replace(lin, trim=point)

