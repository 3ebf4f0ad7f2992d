"""Simulation runs of the nonlinear car: commands, road, wind, faults and sensor noise → a Trace.

The run the PATH report evaluates its monitor on (Douglas et al. 1996, §2.1.4, §5.1): the car
starts at an operating point, the commands hold (or follow a schedule), the road is a spatial
profile (:mod:`fdikit.vehicle.road`), the wind a function of time; the dynamics are integrated by
the compiled RK4 of :mod:`fdikit.vehicle.integrate` at ``step`` (1 kHz by default) and sampled at
``dt``.  Faults of :mod:`fdikit.faults` act as in :func:`fdikit.simulate.simulate`: actuator faults
on the commands before the plant (at the integration rate), sensor faults on the measurements
after the noise.  Independent random streams for noise and each fault, so the same seed gives the
same run bit for bit and a fault changes no sample before its onset.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.vehicle.dynamics import AUXILIARY, CONTROLS, SENSORS, STATES

__all__ = ["simulate_sedan", "GEARBOX_MODES"]

#: ``"held"`` keeps the parameters' gear; ``"automatic"`` shifts up above 4500 rpm and down below 1500 rpm.
GEARBOX_MODES = ("held", "automatic")
_SHIFT_UP, _SHIFT_DOWN = 4500 * np.pi / 30, 1500 * np.pi / 30


def simulate_sedan(car, duration: float, *, start=None, commands=None, road=None, wind: Callable | None = None,
                   scenario=None, measurement_noise_std: Mapping | None = None, dt: float = 0.01,
                   step: float = 0.001, gearbox: str = "held", grade: float | None = None, bank: float | None = None,
                   rng=None, keep_signals: bool = True):
    """Simulate the nonlinear car for ``duration`` seconds.

    Parameters
    ----------
    car : Sedan
        The car.
    duration : float
        Run length [s].
    start : OperatingPoint, optional
        Initial steady state (default: the straight run at 20.3° throttle); its commands are held unless
        ``commands`` is given.
    commands : callable or array_like, optional
        ``commands(t) -> (3,)`` (throttle [deg], brake [N m], steering [rad]) evaluated at every integration step,
        or a constant (3,) vector.
    road : RoadProfile, optional
        Spatial road profile (default a smooth road); must cover the distance travelled plus the wheelbase.
    wind : callable, optional
        ``wind(t) -> (N, 2)`` earth-frame wind [m/s] at the step times (e.g. a partial of
        :func:`fdikit.vehicle.road.crosswind_pulse`).
    scenario : FaultScenario, optional
        Faults on the sensors (:data:`SENSORS`) and actuators (:data:`CONTROLS`).
    measurement_noise_std : mapping of str to float, optional
        Per-sensor white-noise standard deviation (names from :data:`SENSORS`; missing ones noise-free).
    dt : float, default 0.01
        Output sample time [s], a whole multiple of ``step``.
    step : float, default 0.001
        Integration step [s].
    gearbox : {"held", "automatic"}, default "held"
        Gear held, or shifted by engine speed.
    grade, bank : float, optional
        Road slope [rad] (default the start point's).
    rng : numpy.random.Generator or int, optional
        Random source (noise and random faults).
    keep_signals : bool, default True
        Keep the auxiliary signals in ``meta["signals"]`` (long runs that do not need them save the memory and the
        trace's metadata checks).

    Returns
    -------
    Trace
        ``u`` the commands (before actuator faults), ``y`` the 12 sensors (noise and sensor faults), ``x`` the 26
        states; ``meta["signals"]`` a dict of the auxiliary signals per sample (unless ``keep_signals`` is false) and
        ``meta["gear"]``.

    Raises
    ------
    ParameterError
        For a ``dt`` that is not a multiple of ``step``, unknown sensor names in the noise, a road too short,
        commands of the wrong shape or not finite, an unknown gearbox mode.
    DataError
        When the run diverges (the message gives the time).

    References
    ----------
    Douglas et al. 1996, §2.1.4 (the evaluation run), §5.1 (faults and noise), §8.3 (the 1 kHz runs of Ch. 8).

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> from fdikit.faults import Bias, FaultScenario
    >>> car = Sedan()
    >>> tr = simulate_sedan(car, 2.0, scenario=FaultScenario([Bias("yaw_rate", 0.02, onset=1.0)]))
    >>> round(float(tr.y[-1, 7]), 6), str(tr.fault[-1])
    (0.02, 'yaw_rate_sensor')
    """
    from fdikit.faults import FaultScenario
    from fdikit.simulate import apply_faults
    from fdikit.trace import Trace
    from fdikit.vehicle.integrate import run_kernel
    from fdikit.vehicle.road import RoadProfile, flat_road
    from fdikit.vehicle.sedan import OperatingPoint, Sedan

    validate.instance("car", car, Sedan)
    duration = validate.positive("duration", duration)
    dt, step = validate.positive("dt", dt), validate.positive("step", step)
    every = int(round(dt / step))
    if every < 1 or abs(every * step - dt) > 1e-9 * dt:
        raise ParameterError(f"simulate_sedan: dt={dt:g} s must be a whole multiple of step={step:g} s")
    validate.choice("gearbox", gearbox, GEARBOX_MODES)
    rng = np.random.default_rng(rng)
    scenario = (scenario or FaultScenario()).resolve(SENSORS, CONTROLS)
    if start is None:
        start = car.operating_point(throttle=20.3)
    validate.instance("start", start, OperatingPoint)
    grade = start.grade if grade is None else validate.number("grade", grade)
    bank = start.bank if bank is None else validate.number("bank", bank)
    n_out = int(round(duration / dt))
    n_steps = n_out * every
    t_step = np.arange(n_steps) * step
    t = np.arange(n_out + 1) * dt
    u_cmd = _commands(commands, start.u, t_step)
    w = np.zeros((n_steps, 2)) if wind is None else validate.as_array("wind(t)", wind(t_step))
    if w.shape != (n_steps, 2):
        raise ParameterError(f"simulate_sedan: wind(t) must return ({n_steps}, 2) earth-frame wind, got {w.shape}")
    reach = duration * max(start.speed, 1.0) * 1.5 + 20.0  # room for the car to speed up by half
    road = flat_road(2.0 * reach) if road is None else validate.instance("road", road, RoadProfile)
    if road.length < reach:
        raise ParameterError(f"simulate_sedan: the road is {road.length:g} m long, the run may travel about "
                             f"{reach:g} m; generate a longer road")
    std = _noise(measurement_noise_std)
    rng_v, *rng_f = rng.spawn(1 + len(scenario))
    u_act = apply_faults(scenario, "actuator", t_step, u_cmd, CONTROLS, rng_f)
    P = car.params
    x, y, aux, gear, ok = run_kernel(
        start.x.copy(), np.ascontiguousarray(u_act), np.ascontiguousarray(w), np.array([grade, bank]),
        P.as_array(), np.ascontiguousarray(road.left), np.ascontiguousarray(road.right), float(road.spacing),
        step, every, np.array(P.gear_ratios), P.final_drive, _SHIFT_UP, _SHIFT_DOWN, P.gear, gearbox == "automatic")
    if ok < t.size or not np.all(np.isfinite(y)):
        bad = min(ok, t.size - 1)
        raise DataError(f"simulate_sedan: the run diverged at t={t[bad]:g} s (a state became non-finite); "
                        "check the commands and the road, or use a smaller step")
    y = y + rng_v.standard_normal(y.shape) * std
    y = apply_faults(scenario, "sensor", t, y, SENSORS, rng_f)
    u_out = u_cmd[np.minimum(np.arange(t.size) * every, n_steps - 1)]
    meta = {"plant": repr(car), "scenario": scenario.label, "faults": [repr(f) for f in scenario], "gear": gear,
            "road": road.label, "step": step}
    if keep_signals:
        meta["signals"] = dict(zip(AUXILIARY, aux.T))
    return Trace(t=t, u=u_out, y=y, x=x, controls=CONTROLS, outputs=SENSORS, states=STATES,
                 fault=scenario.truth(t), meta=meta)


def _commands(commands, held: np.ndarray, t: np.ndarray) -> np.ndarray:
    if commands is None:
        return np.tile(held, (t.size, 1))
    if callable(commands):
        rows = [np.asarray(commands(tk), dtype=float) for tk in t]
        out = np.array(rows)
    else:
        out = np.tile(validate.as_array("commands", commands), (t.size, 1))
    if out.shape != (t.size, 3) or not np.all(np.isfinite(out)):
        raise ParameterError("simulate_sedan: commands must give 3 finite numbers (throttle [deg], brake [N m], "
                             f"steering [rad]) at every step, got shape {out.shape[1:]}")
    return out


def _noise(std: Mapping | None) -> np.ndarray:
    out = np.zeros(len(SENSORS))
    if std is None:
        return out
    if not isinstance(std, Mapping):
        raise ParameterError("measurement_noise_std must be a mapping sensor name -> standard deviation")
    for name, value in std.items():
        validate.choice("measurement_noise_std", name, SENSORS)
        out[SENSORS.index(name)] = validate.non_negative(f"measurement_noise_std[{name!r}]", value)
    return out
