"""The Ch. 5 evaluation on the nonlinear car at realistic sensor noise.

Douglas et al. 1996, §5.1: the monitor, designed from the linearised and reduced car (here
fdikit's own, :func:`~fdikit.studies.path1996.reduction.path_design_models`), watches the nonlinear
car in the 0.005 rad turn at 24.87 m/s on a smooth and a rough road (§2.1.2, Robson roughness
1e-7 m²).  Three banks run on the same data: the report's four Beard–Jones filters, the same groups
with game-theoretic filters (the default), and one Kalman filter.  Residuals are scaled so a nominal
fault gives 1 in the linear model (§5.1.1); the off-nominal run (+2° throttle, no fault) shows the
nonlinearity alone; every one of the 15 faults at its nominal size is added at t = 2 s.  The
processors and the table are in :mod:`fdikit.studies.path1996.nonlinear_table`.

Nominal sizes on the car (§5.1.1): air mass, engine speed and wheel speeds the steady change of
a +2° throttle step; the longitudinal accelerometer the largest transient of that step (also used
for the lateral and vertical ones); rate gyros 0.02 rad/s; throttle ±2°; brake the torque that
slows the car from 25 to 21 m/s; steering 0.001 rad.

Sensor noise (:data:`NOISE_STD`, per sample at 100 Hz): rate gyros 0.002 rad/s, accelerometers
0.05 m/s² (a_z 0.3 m/s², the report's own figure, §5.1.2), wheel speeds 0.1 rad/s, engine speed
0.5 rad/s — the ranges of automotive MEMS gyros, ESC-grade accelerometers, toothed-wheel and crank
sensors — and the air-mass sensor 1 % of its reading (MAP accuracy class).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["NOISE_STD", "EvaluationSetup", "evaluation_setup", "car_nominal_sizes", "deviation_trace",
           "FaultRun", "fault_run", "group_magnitudes", "off_nominal_run", "off_nominal_peaks"]

#: Sensor noise standard deviations [units of each sensor] per sample at 100 Hz (air mass: 1 % of 1.1e-3 kg).
NOISE_STD = {
    "air_mass": 1.1e-5, "engine_speed": 0.5, "accel_x": 0.05, "accel_y": 0.05, "accel_z": 0.3,
    "roll_rate": 0.002, "pitch_rate": 0.002, "yaw_rate": 0.002, "wheel_speed_fl": 0.1, "wheel_speed_fr": 0.1,
    "wheel_speed_rl": 0.1, "wheel_speed_rr": 0.1,
}
_DT = 0.01


@dataclass(frozen=True, eq=False)
class EvaluationSetup:
    """The car, its turn, the design models, the nominal fault sizes and the bank.

    Attributes
    ----------
    car : Sedan
        The nonlinear car.
    operating_point : OperatingPoint
        The 0.005 rad turn at 24.87 m/s.
    models : DesignModels
        Linearisation and reductions at that point.
    nominal : dict of str to float
        Nominal size of each of the 15 faults (sensor units; deg, N m, rad).
    banks : dict of str to PathBank
        The banks on ``models`` (continuous, scaled with ``nominal``): ``"beard-jones"`` (the report's filters,
        :func:`~fdikit.studies.path1996.bank.path_bank`) and ``"game"`` (disturbance attenuating,
        :func:`~fdikit.studies.path1996.game_bank.path_game_bank`) and ``"kalman"`` (one steady-state Kalman
        filter, :func:`~fdikit.studies.path1996.kalman_bank.path_kalman_bank`).
    generators : dict of str to ResidualGenerator
        Each bank discretised at 100 Hz (what runs on the data).
    default : str
        The bank :attr:`bank` and :attr:`generator` return (the PATH monitor's default, ``"game"``).

    References
    ----------
    Douglas et al. 1996, §4.2, §5.1.1.

    Examples
    --------
    >>> setup = evaluation_setup()  # doctest: +SKIP
    >>> len(setup.nominal), setup.generator.dt  # doctest: +SKIP
    (15, 0.01)
    """

    car: object
    operating_point: object
    models: object
    nominal: dict
    banks: dict = field(repr=False)
    generators: dict = field(repr=False)
    default: str = "game"

    @property
    def bank(self):
        """The default bank."""
        return self.banks[self.default]

    @property
    def generator(self):
        """The default bank's 100 Hz generator."""
        return self.generators[self.default]


def car_nominal_sizes(car, op) -> dict[str, float]:
    """The §5.1.1 nominal fault sizes measured on the nonlinear car at ``op``.

    Parameters
    ----------
    car : Sedan
        The car.
    op : OperatingPoint
        The nominal turn.

    Returns
    -------
    dict of str to float
        ``<sensor>_sensor`` and ``<control>_actuator`` sizes.

    Raises
    ------
    DesignError
        When the off-nominal or braked steady state cannot be trimmed.

    References
    ----------
    Douglas et al. 1996, §5.1.1, Figs. 5.15–5.18.

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> car = Sedan()
    >>> sizes = car_nominal_sizes(car, car.operating_point(speed=24.87, steering=0.005))  # doctest: +SKIP
    >>> sizes["yaw_rate_sensor"], sizes["throttle_actuator"]  # doctest: +SKIP
    (0.02, 2.0)
    """
    from fdikit.vehicle import SENSORS

    alpha, _, steer = op.u
    off = car.operating_point(throttle=alpha + 2.0, steering=steer)
    step = car.simulate(20.0, start=op, commands=[alpha + 2.0, 0.0, steer])
    sizes = {f"{s}_sensor": float(abs(off.y[k] - op.y[k])) for k, s in enumerate(SENSORS)}
    ax = float(np.max(np.abs(step.y[:, SENSORS.index("accel_x")] - op.y[SENSORS.index("accel_x")])))
    for s in ("accel_x", "accel_y", "accel_z"):
        sizes[f"{s}_sensor"] = ax
    for s in ("roll_rate", "pitch_rate", "yaw_rate"):
        sizes[f"{s}_sensor"] = 0.02
    sizes["throttle_actuator"] = 2.0
    sizes["steering_actuator"] = 0.001
    sizes["brake_actuator"] = _brake_25_to_21(car, op)
    return sizes


def _brake_25_to_21(car, op) -> float:
    """The brake torque that lowers the steady speed from 25 to 21 m/s with the 25 m/s throttle held (§5.1.1)."""
    from fdikit.nonlinear import trim
    from fdikit.vehicle import N_DESIGN_STATES

    at25 = car.operating_point(speed=25.0, steering=op.u[2])
    plant = car.design_plant(("ground_speed",))
    x0 = at25.x[:N_DESIGN_STATES].copy()
    u0 = [at25.u[0], 50.0, op.u[2]]
    res = trim(plant, x0, u0, y0=[21.0], iu=["throttle", "steering"])
    return float(res.u[1])


def evaluation_setup(car=None) -> EvaluationSetup:
    """Trim the turn, linearise and reduce, size the faults and design the bank.

    Parameters
    ----------
    car : Sedan, optional
        Default ``Sedan()``.

    Returns
    -------
    EvaluationSetup

    Raises
    ------
    DesignError
        When a step fails (trim, reduction, a filter).

    References
    ----------
    Douglas et al. 1996, §2.2–2.3, §4.2, §5.1.1.

    Examples
    --------
    >>> setup = evaluation_setup()  # doctest: +SKIP
    >>> setup.bank.groups.count("filter4")  # doctest: +SKIP
    8
    """
    from fdikit.studies.path1996.bank import path_bank
    from fdikit.studies.path1996.game_bank import path_game_bank
    from fdikit.studies.path1996.kalman_bank import path_kalman_bank
    from fdikit.studies.path1996.reduction import path_design_models
    from fdikit.vehicle import Sedan

    car = Sedan() if car is None else car
    op = car.operating_point(speed=24.87, steering=0.005)
    nominal = car_nominal_sizes(car, op)
    models = path_design_models(car, nominal=nominal)
    pair = (models.model12, models.method1)
    banks = {"beard-jones": path_bank(models=pair, nominal=nominal),
             "game": path_game_bank(pair, nominal, NOISE_STD, dt=_DT),
             "kalman": path_kalman_bank(models.method1, NOISE_STD, dt=_DT)}
    generators = {k: b.generator if b.generator.dt else b.generator.discretize(_DT) for k, b in banks.items()}
    return EvaluationSetup(car, op, models, nominal, banks, generators)


def deviation_trace(trace, op):
    """``trace`` with the operating point's commands and sensor values subtracted (what the linear filters see).

    Parameters
    ----------
    trace : Trace
        A run of the car.
    op : OperatingPoint
        The design point.

    Returns
    -------
    Trace

    References
    ----------
    Douglas et al. 1996, §2.2 (2.8): the linear model is in deviations from the nominal.

    Examples
    --------
    >>> from fdikit.vehicle import Sedan
    >>> car = Sedan()
    >>> op = car.operating_point(speed=24.87, steering=0.005)
    >>> float(np.abs(deviation_trace(car.simulate(0.5, start=op), op).y).max()) < 1e-9
    True
    """
    from dataclasses import replace

    meta = {k: v for k, v in trace.meta.items() if k != "signals"}
    return replace(trace, u=trace.u - op.u, y=trace.y - op.y, meta=meta)


@dataclass(frozen=True, eq=False)
class FaultRun:
    """One simulated run with its deviation trace and scaled residuals.

    Attributes
    ----------
    fault : str or None
        Fault name (``None`` fault-free).
    road : str
        ``"smooth"`` or ``"rough"``.
    trace : Trace
        Deviation trace (:func:`deviation_trace`).
    residuals : dict of str to Residuals
        Every bank's scaled residuals on the same trace.

    References
    ----------
    Douglas et al. 1996, §5.1.

    Examples
    --------
    >>> FaultRun.__name__
    'FaultRun'
    """

    fault: str | None
    road: str
    trace: object
    residuals: object


def fault_run(setup: EvaluationSetup, fault: str | None, road: str, *, duration: float = 20.0, onset: float = 2.0,
              size: float = 1.0, sign: float = 1.0, noise: bool = True, rng=None, commands=None) -> FaultRun:
    """Simulate the car in the turn with one nominal fault (or none) and run the bank on it.

    Parameters
    ----------
    setup : EvaluationSetup
        From :func:`evaluation_setup`.
    fault : str or None
        ``<sensor>_sensor`` or ``<control>_actuator`` (a bias of ``sign · size ·`` nominal), or None.
    road : {"smooth", "rough"}
        Smooth, or the Robson road of §2.1.2 (roughness 1e-7 m², cut-off 0.01 cycle/m).
    duration, onset : float, default 20.0, 2.0
        Run length and fault onset [s].
    size, sign : float, default 1.0, 1.0
        Multiple of the nominal size, and its sign.
    noise : bool, default True
        Add :data:`NOISE_STD`.
    rng : numpy.random.Generator or int, optional
        Random source (road and noise).
    commands : array_like, optional
        Commands instead of the operating point's (e.g. the off-nominal +2° throttle).

    Returns
    -------
    FaultRun

    Raises
    ------
    ParameterError
        For an unknown road or fault name.

    References
    ----------
    Douglas et al. 1996, §5.1.1–5.1.2.

    Examples
    --------
    >>> run = fault_run(evaluation_setup(), "yaw_rate_sensor", "smooth", duration=4.0)  # doctest: +SKIP
    >>> run.residuals["beard-jones"].r.shape  # doctest: +SKIP
    (401, 29)
    """
    from fdikit import validate
    from fdikit.faults import Bias, FaultScenario
    from fdikit.vehicle.road import robson_road

    validate.choice("road", road, ("smooth", "rough"))
    rng = np.random.default_rng(rng)
    rng_road, rng_sim = rng.spawn(2)
    op = setup.operating_point
    faults = []
    if fault is not None:
        validate.choice("fault", fault, tuple(setup.nominal))
        signal, loc = fault.rsplit("_", 1)
        faults = [Bias(signal, sign * size * setup.nominal[fault], onset=onset, location=loc)]
    length = duration * op.speed * 1.5 + 50.0
    profile = None if road == "smooth" else robson_road(length, rng=rng_road)
    trace = setup.car.simulate(duration, start=op, commands=commands, road=profile, scenario=FaultScenario(faults),
                               measurement_noise_std=NOISE_STD if noise else None, rng=rng_sim, keep_signals=False)
    dev = deviation_trace(trace, op)
    return FaultRun(fault, road, dev, {k: g.run(dev) for k, g in setup.generators.items()})


def group_magnitudes(residuals) -> dict[str, np.ndarray]:
    """Per (filter, fault) residual group: the Euclidean norm of its scaled residuals per sample.

    Parameters
    ----------
    residuals : Residuals
        A bank's residuals (names ``'<filter>:<fault>[k]'``).

    Returns
    -------
    dict of str to ndarray
        ``'<filter>:<fault>'`` → (N,) magnitudes (1 for a nominal fault in the linear model, steady state).

    References
    ----------
    Douglas et al. 1996, §5.1.1 (scaled residual magnitudes).

    Examples
    --------
    >>> from fdikit.residuals import Residuals
    >>> res = Residuals(np.arange(2.0), np.array([[3.0, 4.0], [0.0, 1.0]]), ("f1:a[0]", "f1:a[1]"), ("a", "a"))
    >>> group_magnitudes(res)["f1:a"].tolist()
    [5.0, 1.0]
    """
    groups: dict[str, list[int]] = {}
    for k, name in enumerate(residuals.names):
        groups.setdefault(name.split("[")[0], []).append(k)
    return {g: np.linalg.norm(residuals.r[:, idx], axis=1) for g, idx in groups.items()}


def off_nominal_run(setup: EvaluationSetup, duration: float = 60.0) -> FaultRun:
    """The §5.1.1 off-nominal run: +2° throttle above the turn's, no fault, smooth road, no noise; every bank.

    Parameters
    ----------
    setup : EvaluationSetup
        From :func:`evaluation_setup`.
    duration : float, default 60.0
        Run length [s].

    Returns
    -------
    FaultRun

    References
    ----------
    Douglas et al. 1996, §5.1.1.

    Examples
    --------
    >>> run = off_nominal_run(evaluation_setup(), 5.0)  # doctest: +SKIP
    >>> sorted(run.residuals)  # doctest: +SKIP
    ['beard-jones', 'game', 'kalman']
    """
    op = setup.operating_point
    return fault_run(setup, None, "smooth", duration=duration, noise=False, commands=[op.u[0] + 2.0, op.u[1], op.u[2]])


def off_nominal_peaks(setup: EvaluationSetup, *, duration: float = 60.0, settle: float = 2.0,
                      bank: str | None = None, run: FaultRun | None = None) -> dict[str, float]:
    """The §5.1.1 off-nominal test: +2° throttle, no fault, smooth road, no noise; peak scaled magnitude per group.

    Parameters
    ----------
    setup : EvaluationSetup
        From :func:`evaluation_setup`.
    duration : float, default 60.0
        Run length [s] (the car settles ≈ 2 m/s faster).
    settle : float, default 2.0
        Filter start-up time left out [s] (the report adds faults at 2 s for the same reason).
    bank : str, optional
        Which bank (default the setup's default).
    run : FaultRun, optional
        The off-nominal run already simulated (every bank's residuals are in it); ``duration`` is then unused.

    Returns
    -------
    dict of str to float
        ``'<filter>:<fault>'`` → largest magnitude after ``settle`` (the report: all < 0.25).

    References
    ----------
    Douglas et al. 1996, §5.1.1.

    Examples
    --------
    >>> peaks = off_nominal_peaks(evaluation_setup(), duration=10.0)  # doctest: +SKIP
    >>> len(peaks)  # doctest: +SKIP
    16
    """
    run = off_nominal_run(setup, duration) if run is None else run
    res = run.residuals[setup.default if bank is None else bank]
    keep = res.t >= settle
    return {g: float(m[keep].max()) for g, m in group_magnitudes(res).items()}
