"""How far the linearised car can be trusted: the effective ranges of Table 8.2 (≤ 10 % error).

Douglas et al. 1996, §8.3.1 and §8.3.2, Table 8.2: the nonlinear car and its linearisation at a
nominal point (27 m/s straight at 22.555 % throttle, or the 0.005 rad steady turn at the same
throttle) are driven by the same step of one command, and the range of step sizes over which "the
deviation errors between the linearized and nonlinear systems at steady state are below 10
percent" in "all the significant states" is tabulated.  This module measures that range on
:class:`~fdikit.vehicle.sedan.Sedan`.

The error measure, as read from the report (it gives no formula):

* the nonlinear change of every design state (the 22 of §2.2) at steady state,
  ``Δx_nl = x_nl(∞) − x_0``, and the linear one ``Δx_lin`` of the 22-state
  :meth:`~fdikit.vehicle.sedan.Sedan.linearize` model for the same step ``Δu``;
* per state the relative error ``e_j = |Δx_lin,j − Δx_nl,j| / |Δx_nl,j|``, over the states that
  move: ``|Δx_nl,j| > significance · |x_0,j| + atol`` (defaults 1e-4 and 1e-9 in SI units — a
  state that changes by less than 0.01 % of its nominal value, or that stays at zero by symmetry,
  is not "significant");
* the error of the step is ``max_j e_j``; a step is inside the range when it is ≤ ``tolerance``
  (0.10).  Simulated runs count a state only once it has settled (it moved by at most a tenth of the
  tolerance, relative to its change, over the last tenth of the run).

Two ways to get the steady states: ``method="simulate"`` — the report's procedure: the nonlinear
car (:meth:`Sedan.simulate`, 1 kHz RK4) and the linear model (:func:`fdikit.simulate.simulate`, deviation
inputs, the operating point added back) run ``duration`` seconds (default 300 s, the report's
"about 300 seconds") from the same operating point and the last samples are compared; and
``method="steady"`` (default) — the limits themselves: the nonlinear steady state by trim
(:meth:`Sedan.operating_point` at the stepped commands) and the linear one by ``Δx = −A⁻¹ B Δu``.
Both agree to the residual of the slowest mode (time constant ≈ 31 s at 27 m/s, ``exp(−300/31)`` ≈
6e-5 of the step after 300 s); ``"steady"`` costs milliseconds per step instead of seconds.

Units of the perturbations: throttle in percent of the nominal throttle (the report's "throttle
position is increased by 15 percent" read as a 15 % increase of the 22.555 %, i.e. ±p/100 of the
nominal angle); steering in percent of the nominal steer (undefined, "N/A", at a zero nominal
steer); braking as a total brake force [N] (the unit Table 8.2 prints; Fig. 8.32's caption calls the
quantity a brake torque), applied as the brake torque ``F · r_w`` with ``r_w`` the mean loaded tire
radius at the operating point — the reading §8.3.1 uses for its "1000 N of brake force".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, DesignError, ParameterError

__all__ = ["TABLE_8_2", "ValidityRanges", "steady_state_error", "validity_ranges", "NOMINAL_THROTTLE"]

#: The report's nominal throttle: 22.555 % of the 90° butterfly [deg] (§8.3.1).
NOMINAL_THROTTLE = 0.22555 * 90.0

#: Table 8.2 as printed, keyed by the nominal steering angle [rad]: throttle and steering ranges in percent of the
#: nominal command, braking in "N" as printed (``None``: "N/A").
TABLE_8_2 = {
    0.0: {"throttle": (-15.0, 15.0), "steering": None, "braking": (0.0, 34.0)},
    0.005: {"throttle": (-14.0, 14.0), "steering": (-15.0, 25.0), "braking": (0.0, 27.0)},
}

_N = 22  # design states (§2.2)


@dataclass(frozen=True)
class ValidityRanges:
    """The measured effective ranges of the linearised car at one nominal point.

    Attributes
    ----------
    steering : float
        Nominal steering angle [rad].
    speed, radius : float
        Speed [m/s] and turn radius [m] (``inf`` straight) at the nominal point.
    throttle : tuple of float
        ``(lower, upper)`` throttle steps [% of the nominal throttle] inside which the error is ≤ ``tolerance``.
    steering_range : tuple of float or None
        ``(lower, upper)`` steering steps [% of the nominal steer]; ``None`` ("N/A") at a zero nominal steer.
    braking : tuple of float
        ``(0, upper)`` total brake force [N].
    limiting_state : dict of str to str
        For each bound (``"throttle-"``, ``"throttle+"``, ``"steering-"``, ``"steering+"``, ``"braking"``) the state
        whose error first exceeds the tolerance (``"search limit"`` when none did up to the searched maximum).
    resolution : dict of str to float
        Search resolution per input, in the units above: each bound is the largest step found inside the range,
        the true crossing lies less than one resolution beyond it.
    tolerance : float
        Error limit (0.10 in the report).
    method : str
        ``"steady"`` or ``"simulate"``.

    References
    ----------
    Douglas et al. 1996, §8.3.2, Table 8.2.

    Examples
    --------
    >>> r = ValidityRanges(0.0, 27.0, float("inf"), (-20.0, 25.0), None, (0.0, 160.0), {}, {}, 0.1, "steady")
    >>> r.as_table_row()
    {'throttle': (-20.0, 25.0), 'steering': None, 'braking': (0.0, 160.0)}
    """

    steering: float
    speed: float
    radius: float
    throttle: tuple
    steering_range: tuple | None
    braking: tuple
    limiting_state: dict = field(repr=False)
    resolution: dict = field(repr=False)
    tolerance: float = 0.10
    method: str = "steady"

    def as_table_row(self) -> dict:
        """The ranges in the layout of a :data:`TABLE_8_2` entry (``throttle``, ``steering``, ``braking``)."""
        return {"throttle": self.throttle, "steering": self.steering_range, "braking": self.braking}


def _loaded_radius(car, op) -> float:
    P = car.params
    loads = np.array([op.signals[f"normal_force_{c}"] for c in ("fl", "fr", "rl", "rr")])
    return float(np.mean(P.tire_radius - loads / P.tire_stiffness))


def _deviations(car, op, lin, du: np.ndarray, method: str, duration: float, tolerance: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Δx_nl, Δx_lin, settled)`` at steady state for the step ``du`` (DesignError/DataError when the car fails).

    ``settled`` (simulate only) marks the states that moved by at most ``tolerance/10`` of their change over the last
    tenth of the run: the others (rates that are zero at steady state and still carry the slow mode's residual) are
    not yet at steady state and cannot be compared there.
    """
    x0 = op.x[:_N]
    if method == "steady":
        u = op.u + du
        new = car.operating_point(throttle=u[0], brake=u[1], steering=u[2], grade=op.grade, bank=op.bank)
        dx_lin = -np.linalg.solve(lin.A, lin.B @ du)
        return new.x[:_N] - x0, dx_lin, np.ones(_N, dtype=bool)
    from fdikit.simulate import simulate

    tr = car.simulate(duration, start=op, commands=op.u + du, dt=0.01)
    n = tr.t.size
    lin_tr = simulate(lin, t=tr.t, u=np.tile(du, (n, 1)), x0=np.zeros(_N))
    dnl = tr.x[-1, :_N] - x0
    drift = np.abs(tr.x[-1, :_N] - tr.x[int(0.9 * (n - 1)), :_N])
    return dnl, lin_tr.x[-1], drift <= 0.1 * tolerance * np.abs(dnl)


def steady_state_error(car, op, delta_u, *, model=None, method: str = "steady", duration: float = 300.0,
                       significance: float = 1e-4, atol: float = 1e-9, tolerance: float = 0.10) -> tuple[float, str]:
    """The linearisation error of one command step: ``max_j |Δx_lin,j − Δx_nl,j| / |Δx_nl,j|`` over moving states.

    Parameters
    ----------
    car : Sedan
        The nonlinear car.
    op : OperatingPoint
        The nominal point (of ``car``).
    delta_u : array_like, shape (3,)
        Step of the commands: throttle [deg], brake torque [N m], steering [rad].
    model : FaultModel, optional
        The linear model at ``op`` (default ``car.linearize(op)``).
    method : {"steady", "simulate"}, default "steady"
        Exact steady states (trim and ``−A⁻¹BΔu``), or both models simulated for ``duration`` (module docstring).
    duration : float, default 300.0
        Run length [s] for ``"simulate"``.
    significance, atol : float, default 1e-4 and 1e-9
        A state counts when ``|Δx_nl,j| > significance · |x_0,j| + atol``.
    tolerance : float, default 0.10
        The error limit the result will be held to; with ``"simulate"`` a state also counts only when it has
        settled: it moved by at most ``tolerance/10`` of its change over the last tenth of the run (a rate that is
        zero at steady state and still carries the slow mode's residual is not at steady state).

    Returns
    -------
    error : float
        The largest relative error over the counted states (``inf`` when the nonlinear car has no steady state for
        the step or the run diverges).
    state : str
        The state that attains it (``""`` when no state moves, ``"no steady state"`` for ``inf``).

    Raises
    ------
    ParameterError
        For a ``delta_u`` that is not 3 finite numbers, an unknown method, a non-positive duration or tolerance,
        negative significance or atol.

    References
    ----------
    Douglas et al. 1996, §8.3.1 ("deviation errors ... at steady state are below 10 percent"), §8.3.2, Table 8.2.

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> car = Sedan()
    >>> op = car.operating_point(throttle=NOMINAL_THROTTLE)
    >>> err, state = steady_state_error(car, op, [0.03 * NOMINAL_THROTTLE, 0.0, 0.0])  # +3 % throttle
    >>> bool(err < 0.02), state
    (True, 'v_z')
    >>> err, state = steady_state_error(car, op, [0.0, 0.0, 0.001])  # a small steer from straight ahead
    >>> bool(err > 0.5)  # the speed loss in a turn is even in the steer: the linearisation misses it
    True
    """
    du = validate.as_vector("delta_u", delta_u, 3)
    validate.choice("method", method, ("steady", "simulate"))
    duration = validate.positive("duration", duration)
    significance, atol = validate.non_negative("significance", significance), validate.non_negative("atol", atol)
    tolerance = validate.positive("tolerance", tolerance)
    lin = car.linearize(op) if model is None else model
    try:
        dnl, dlin, settled = _deviations(car, op, lin, du, method, duration, tolerance)
    except (DesignError, DataError):
        return float("inf"), "no steady state"
    moving = (np.abs(dnl) > significance * np.abs(op.x[:_N]) + atol) & settled
    if not moving.any():
        return 0.0, ""
    err = np.where(moving, np.abs(dlin - dnl) / np.where(moving, np.abs(dnl), 1.0), 0.0)
    j = int(np.argmax(err))
    return round(float(err[j]), 12), car.states[j]


def _bound(error, step: float, resolution: float, maximum: float, tolerance: float) -> tuple[float, str]:
    """Largest ``p`` on the grid ``k·step`` (refined by bisection on ``n·resolution``) with error <= tolerance."""
    last, k = 0.0, 1
    while True:
        p = min(k * step, maximum)
        e, state = error(p)
        if e > tolerance:
            lo, hi, worst = round(last / resolution), round(p / resolution), state
            while hi - lo > 1:
                mid = (lo + hi) // 2
                e_mid, s_mid = error(mid * resolution)
                if e_mid > tolerance:
                    hi, worst = mid, s_mid
                else:
                    lo = mid
            return float(lo * resolution), worst
        last = p
        if p >= maximum:
            return float(p), "search limit"
        k += 1


def validity_ranges(car, *, steering: float = 0.0, throttle: float = NOMINAL_THROTTLE, tolerance: float = 0.10,
                    method: str = "steady", duration: float = 300.0, steps=(2.0, 5.0, 20.0),
                    resolution=(0.5, 1.0, 2.0), maxima=(60.0, 100.0, 2000.0),
                    inputs=("throttle", "steering", "braking"), significance: float = 1e-4,
                    atol: float = 1e-9) -> ValidityRanges:
    """Table 8.2 for this car: the command steps over which the linearisation is within ``tolerance`` at steady state.

    From the steady run at ``throttle`` and ``steering`` (:meth:`Sedan.operating_point`) and its 22-state
    linearisation, each command is stepped alone, up and down (brake only up), on the grid ``k · step`` until the
    error of :func:`steady_state_error` exceeds ``tolerance``; the last interval is bisected down to
    ``resolution``.

    Parameters
    ----------
    car : Sedan
        The nonlinear car.
    steering : float, default 0.0
        Nominal steering angle [rad] (the report uses 0 and 0.005).
    throttle : float, default NOMINAL_THROTTLE
        Nominal throttle [deg] (22.555 % of 90°).
    tolerance : float, default 0.10
        Error limit.
    method : {"steady", "simulate"}, default "steady"
        See :func:`steady_state_error`.
    duration : float, default 300.0
        Run length [s] for ``"simulate"``.
    steps, resolution, maxima : 3 floats each
        Coarse grid step, final resolution and search limit for throttle [% of nominal], steering [% of nominal] and
        braking [N].
    inputs : sequence of str, default all three
        Which ranges to measure (the others are returned as ``(nan, nan)``).
    significance, atol : float
        See :func:`steady_state_error`.

    Returns
    -------
    ValidityRanges

    Raises
    ------
    ParameterError
        For a non-positive tolerance or duration, an unknown method or input, or steps, resolutions, maxima that
        are not 3 positive numbers with ``resolution <= step <= maximum``.
    DesignError
        When the nominal point has no steady state.

    References
    ----------
    Douglas et al. 1996, §8.3.1 (Figs. 8.22–8.24), §8.3.2 (Figs. 8.30–8.33), Table 8.2.

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> r = validity_ranges(Sedan(), inputs=("braking",), resolution=(0.5, 1.0, 10.0), steps=(2.0, 5.0, 50.0))
    >>> r.braking, r.limiting_state["braking"], TABLE_8_2[0.0]["braking"]
    ((0.0, 160.0), 'v_z', (0.0, 34.0))
    """
    from fdikit.vehicle.sedan import Sedan

    validate.instance("car", car, Sedan)
    steering, throttle = validate.number("steering", steering), validate.positive("throttle", throttle)
    tolerance, duration = validate.positive("tolerance", tolerance), validate.positive("duration", duration)
    validate.choice("method", method, ("steady", "simulate"))
    steps, resolution, maxima = (validate.as_vector(n, v, 3) for n, v in
                                 (("steps", steps), ("resolution", resolution), ("maxima", maxima)))
    for k, name in enumerate(("throttle", "steering", "braking")):
        if not 0 < resolution[k] <= steps[k] <= maxima[k]:
            raise ParameterError(f"validity_ranges: for {name} need 0 < resolution <= step <= maximum, got "
                                 f"{resolution[k]:g}, {steps[k]:g}, {maxima[k]:g}; pass e.g. steps=(2, 5, 20), "
                                 "resolution=(0.5, 1, 2), maxima=(60, 100, 2000)")
        ratio = steps[k] / resolution[k]
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            raise ParameterError(f"validity_ranges: the {name} step {steps[k]:g} must be a whole multiple of its "
                                 f"resolution {resolution[k]:g}; e.g. step 2 with resolution 0.5")
    inputs = tuple(inputs)
    for name in inputs:
        validate.choice("inputs", name, ("throttle", "steering", "braking"))
    op = car.operating_point(throttle=throttle, steering=steering)
    lin = car.linearize(op)
    r_w = _loaded_radius(car, op)

    def err(du):
        return steady_state_error(car, op, du, model=lin, method=method, duration=duration,
                                  significance=significance, atol=atol, tolerance=tolerance)

    nan2, limiting = (float("nan"), float("nan")), {}
    out = {"throttle": nan2, "steering": nan2 if steering != 0.0 else None, "braking": nan2}
    args = dict(tolerance=tolerance)
    if "throttle" in inputs:
        hi, limiting["throttle+"] = _bound(lambda p: err([p / 100 * throttle, 0.0, 0.0]), steps[0], resolution[0],
                                           maxima[0], **args)
        lo, limiting["throttle-"] = _bound(lambda p: err([-p / 100 * throttle, 0.0, 0.0]), steps[0], resolution[0],
                                           min(maxima[0], 99.0), **args)
        out["throttle"] = (-lo, hi)
    if "steering" in inputs and steering != 0.0:
        hi, limiting["steering+"] = _bound(lambda p: err([0.0, 0.0, p / 100 * steering]), steps[1], resolution[1],
                                           maxima[1], **args)
        lo, limiting["steering-"] = _bound(lambda p: err([0.0, 0.0, -p / 100 * steering]), steps[1], resolution[1],
                                           maxima[1], **args)
        out["steering"] = (-lo, hi)
    if "braking" in inputs:
        hi, limiting["braking"] = _bound(lambda f: err([0.0, f * r_w, 0.0]), steps[2], resolution[2], maxima[2],
                                         **args)
        out["braking"] = (0.0, hi)
    res = {"throttle": float(resolution[0]), "steering": float(resolution[1]), "braking": float(resolution[2])}
    return ValidityRanges(steering=steering, speed=op.speed, radius=op.radius, throttle=out["throttle"],
                          steering_range=out["steering"], braking=out["braking"], limiting_state=limiting,
                          resolution=res, tolerance=tolerance, method=method)
