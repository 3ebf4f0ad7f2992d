"""The PATH vehicle health monitor: four Beard–Jones detection filters for 12 sensors and 3 actuators.

Douglas et al. 1996, §4.1–4.2 (the fault groups) and §5.1.1 (residual scaling, nominal
fault sizes).  Filters 1–3 cover the 12 sensors on the 12-state model, filter 4 the three
actuators and the air-mass sensor (bias direction only) on the 14-state model:

=========  ===========================================================  ==========
filter     faults                                                       model
=========  ===========================================================  ==========
filter1    engine speed, lateral accel., vertical accel., pitch rate    12-state
filter2    longitudinal accel., roll rate, yaw rate, engine speed       12-state
filter3    the four wheel speeds                                        12-state
filter4    throttle, brake, steering, air mass (magnitude direction)    14-state
=========  ===========================================================  ==========

Choices where the report is silent or its data do not allow its own design (each is an
assumption, documented here and in ``docs/methods/beard_jones.md``):

* The models are App. D with ``tiny='midpoint'``: entries printed ``±0.00`` restored as
  ``±0.0025``.  With them at zero the 12-state ``C`` has rank 11 and no sensor fault has
  a state-space map ``C F¹ = e_i``.
* The brake's detection space is taken two-dimensional, ``Im [F, A F]``, as the report does
  (§4.1: "very weakly observable"; with the restored tiny entries ``C F_brake`` is of order
  1e-3 and the minimal space would be ``Im F``).  With the entries at zero the set
  {throttle, brake, steering, air-mass bias} is not output separable.
* Eigenvalue sets: filter 4 as printed (§4.2.2: throttle {−4, −9}, brake {−5, −8},
  steering {−6}, air mass {−7}; Ξ_0 not printed); filter 3's wheel speed fl {−3, −10}
  as printed, the other sets chosen in the report's range ("reasonable response time but
  not unrealistically fast", §4.2); these are fdikit's choices.
* Residual scaling (§5.1.1): each fault's residual is divided by the steady-state
  magnitude a nominal fault produces in the linear model, so a nominal fault gives 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.design.observers.beard_jones import BeardJonesDesign, beard_jones
from fdikit.errors import DesignError, ParameterError
from fdikit.fault_maps import resolve_faults
from fdikit.model import FaultModel, actuator_fault_name, sensor_fault_name
from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14
from fdikit.residuals import ResidualGenerator, stack_generators

__all__ = [
    "PathBank", "path_bank", "path_runs", "FILTER_GROUPS", "EIGENVALUES", "nominal_fault_sizes", "path_fault_model",
    "scale_to_nominal",
]

#: Fault names per filter (``<output>_sensor``, ``<control>_actuator``; ``:magnitude`` keeps ``A F¹`` only).
FILTER_GROUPS: dict[str, list[str]] = {
    "filter1": ["engine_speed_sensor", "accel_y_sensor", "accel_z_sensor", "pitch_rate_sensor"],
    "filter2": ["accel_x_sensor", "roll_rate_sensor", "yaw_rate_sensor", "engine_speed_sensor"],
    "filter3": ["wheel_speed_fl_sensor", "wheel_speed_fr_sensor", "wheel_speed_rl_sensor", "wheel_speed_rr_sensor"],
    "filter4": ["throttle_actuator", "brake_actuator", "steering_actuator", "air_mass_sensor:magnitude"],
}

_SENSOR_SETS = ([-3.0, -10.0], [-4.0, -9.0], [-5.0, -8.0], [-6.0, -7.0])
#: Continuous-time eigenvalue sets per filter: per fault (in FILTER_GROUPS order), then Ξ_0.
EIGENVALUES: dict[str, tuple[list[list[float]], list[float]]] = {
    "filter1": (list(_SENSOR_SETS), [-1.5, -2.0, -11.0, -12.0]),
    "filter2": (list(_SENSOR_SETS), [-1.5, -2.0, -11.0, -12.0]),
    "filter3": (list(_SENSOR_SETS), [-1.5, -2.0, -11.0, -12.0]),
    "filter4": ([[-4.0, -9.0], [-5.0, -8.0], [-6.0], [-7.0]], [-1.5, -2.0, -2.5, -3.0, -10.0, -11.0, -12.0, -13.0]),
}


def nominal_fault_sizes() -> dict[str, float]:
    """Nominal fault sizes of Douglas et al. 1996, §5.1.1, computed on the linear 12-state model.

    Air mass, engine speed and wheel speeds: the steady-state output change of a +2°
    throttle step; longitudinal accelerometer: the largest transient of that step, also
    used for the lateral and vertical accelerometers; rate gyros 0.02 rad/s; throttle 2°,
    brake 100 N·m (Fig. 5.15), steering 0.001 rad.  The air-mass fault of filter 4 is the
    0.07 kg of Fig. 5.18.

    Returns
    -------
    dict of str to float
        Size per fault name, for the 12 ``<output>_sensor`` faults (in the output's unit) and the 3
        ``<control>_actuator`` faults (deg, N·m, rad).

    References
    ----------
    Douglas et al. 1996, §5.1.1, Figs. 5.15, 5.18.

    Examples
    --------
    >>> sizes = nominal_fault_sizes()
    >>> len(sizes), sizes["throttle_actuator"], sizes["air_mass_sensor"], round(float(sizes["engine_speed_sensor"]), 2)
    (15, 2.0, 0.07, 24.35)
    """
    import control

    m = path_vehicle_12("midpoint")
    sys = control.ss(m.A, m.Bu[:, [0]], m.C, m.Du[:, [0]])
    dc = 2.0 * np.asarray(sys.dcgain()).ravel()
    t = np.linspace(0, 20, 4001)
    step = 2.0 * control.step_response(sys, T=t).outputs
    sizes = {sensor_fault_name(o): abs(dc[i]) for i, o in enumerate(m.outputs)}
    ax = float(np.max(np.abs(step[m.outputs.index("accel_x")])))
    for o in ("accel_x", "accel_y", "accel_z"):
        sizes[sensor_fault_name(o)] = ax
    for o in ("roll_rate", "pitch_rate", "yaw_rate"):
        sizes[sensor_fault_name(o)] = 0.02
    sizes[sensor_fault_name("air_mass")] = 0.07
    sizes.update({actuator_fault_name("throttle"): 2.0, actuator_fault_name("brake"): 100.0,
                  actuator_fault_name("steering"): 0.001})
    return sizes


def path_fault_model(n_states: int = 14) -> FaultModel:
    """The App. D model (``tiny='midpoint'``) with all 15 faults as inputs: 12 sensors, 3 actuators.

    Parameters
    ----------
    n_states : {12, 14}, default 14
        Which App. D model; the 12-state model has the 12 sensor faults only (its actuators are static).

    Returns
    -------
    FaultModel
        Continuous model whose fault inputs are ``<control>_actuator`` (14 states only) and ``<output>_sensor``.

    Raises
    ------
    ParameterError
        If ``n_states`` is not 12 or 14.

    References
    ----------
    Douglas et al. 1996, App. D; §4.1 (the fault set).

    Examples
    --------
    >>> m = path_fault_model()
    >>> m.n, len(m.faults), m.faults[0]
    (14, 15, 'throttle_actuator')
    >>> len(path_fault_model(12).faults)
    12
    """
    if isinstance(n_states, bool) or n_states not in (12, 14):
        raise ParameterError(f"n_states must be 12 or 14 (the PATH App. D models), got {n_states!r}")
    m = (path_vehicle_14 if n_states == 14 else path_vehicle_12)("midpoint")
    if n_states == 14:
        m = m.with_actuator_faults(m.controls)
    return m.with_sensor_faults(m.outputs)


@dataclass(frozen=True, eq=False)
class PathBank:
    """The four-filter bank.

    Attributes
    ----------
    designs : dict of str to BeardJonesDesign
        The Beard–Jones design of each filter (``"filter1"`` … ``"filter4"``).
    generator : ResidualGenerator
        All filters stacked (block-diagonal), residuals ``'<filter>:<fault>[k]'``
        scaled so a nominal fault gives a steady magnitude of 1.
    groups : tuple of str
        The filter of each residual (for the bank isolation logic, ``ThresholdEvaluator(groups=...)``).
    nominal : dict of str to float
        Nominal fault size per fault name (:func:`nominal_fault_sizes`).
    scales : dict of (str, str) to float
        The divisor of each (filter, fault) residual group.

    References
    ----------
    Douglas et al. 1996, §4.1–4.2 (the filters), §5.1.1 (the scaling).

    Examples
    --------
    Designing the bank takes about half a second (:func:`path_bank`):

    >>> bank = path_bank()  # doctest: +SKIP
    >>> len(bank.groups), sorted(bank.designs)  # doctest: +SKIP
    (29, ['filter1', 'filter2', 'filter3', 'filter4'])
    """

    designs: dict[str, BeardJonesDesign]
    generator: ResidualGenerator
    groups: tuple[str, ...]
    nominal: dict[str, float]
    scales: dict[tuple[str, str], float]


def _dc(model: FaultModel, gen: ResidualGenerator) -> np.ndarray:
    """Steady-state gain from the fault inputs to the residuals (continuous or discrete)."""
    R = gen.internal_form(model)
    n = R.n
    M = (np.eye(n) - R.A) if R.is_discrete else -R.A
    return R.C @ np.linalg.solve(M, R.Bf) + R.Df


def scale_to_nominal(name: str, base: FaultModel, generator: ResidualGenerator, faults, nominal: Mapping[str, float],
                     dt: float | None = None) -> tuple[ResidualGenerator, dict]:
    """Scale each fault's residual group of one filter so its nominal fault gives magnitude 1 in steady state.

    Parameters
    ----------
    name : str
        The filter's name; the residuals are renamed ``'<name>:<residual>'``.
    base : FaultModel
        The continuous design model the filter was designed on (its sensor, and for filter 4 actuator, faults are
        added to compute the steady-state gains).
    generator : ResidualGenerator
        The filter's generator (continuous, or discrete at ``dt``), ``isolates`` naming the faults.
    faults : sequence of str
        The filter's faults.
    nominal : mapping of str to float
        Nominal size of each fault.
    dt : float, optional
        Sample time of a discrete generator.

    Returns
    -------
    generator : ResidualGenerator
        The scaled, renamed generator.
    scales : dict of (str, str) to float
        ``(name, fault)`` → the divisor.

    Raises
    ------
    DesignError
        When a fault has no steady-state residual.

    References
    ----------
    Douglas et al. 1996, §5.1.1 (the residual scaling).

    Examples
    --------
    >>> bank = path_bank()  # doctest: +SKIP
    >>> round(bank.scales[("filter2", "yaw_rate_sensor")], 4) > 0  # doctest: +SKIP
    True
    """
    check = base.with_sensor_faults(base.outputs)
    if any(f.endswith("_actuator") for f in faults):
        check = check.with_actuator_faults(base.controls)
    if dt is not None:
        check = check.discretize(dt)
    G = _dc(check, generator)
    g = generator
    factors = np.ones(len(g.residuals))
    scales = {}
    for f in faults:
        rows = [k for k, iso in enumerate(g.isolates) if iso == f]
        mag = np.linalg.norm(G[rows, check.faults.index(f)]) * nominal[f]
        if not mag > 0:
            raise DesignError(f"{name}: fault {f} has no steady-state residual; it cannot be scaled")
        factors[rows] = 1.0 / mag
        scales[(name, f)] = mag
    scaled = ResidualGenerator(g.A, g.B, factors[:, None] * g.C, factors[:, None] * g.D, g.controls, g.outputs,
                               [f"{name}:{r}" for r in g.residuals], g.dt, g.isolates)
    return scaled, scales


def path_bank(dt: float | None = None, poles: dict | None = None, *,
              models: tuple[FaultModel, FaultModel] | None = None,
              nominal: Mapping[str, float] | None = None) -> PathBank:
    """Design the PATH four-filter bank (continuous, or on the ZOH models at ``dt`` with ``e^{λ dt}``).

    Parameters
    ----------
    dt : float, optional
        Sample time [s]; the filters are designed on the ZOH models with the eigenvalues mapped to
        ``e^{λ dt}``.  ``None`` (default) designs in continuous time.
    poles : dict, optional
        Filter name → ``(sets, complement)`` replacing entries of :data:`EIGENVALUES` (continuous-time
        eigenvalues of ``A − L C``: one list per fault in :data:`FILTER_GROUPS` order, then Ξ_0).
    models : (FaultModel, FaultModel), optional
        The continuous 12-state (sensor filters) and 14-state (filter 4) design models, e.g. those of the
        nonlinear car (:func:`fdikit.studies.path1996.reduction.path_design_models`); default App. D
        (``tiny='midpoint'``).  Outputs and controls must carry the App. D names.
    nominal : mapping of str to float, optional
        Nominal fault sizes for the residual scaling (default :func:`nominal_fault_sizes`); all 15 faults.

    Returns
    -------
    PathBank
        The four designs, the stacked scaled generator, the filter of each residual, the nominal
        sizes and the scale factors.

    Raises
    ------
    DesignError
        When a filter cannot be designed (the message names the filter).
    ParameterError
        For a bad ``dt`` or ``poles`` that name no filter of :data:`FILTER_GROUPS`.

    References
    ----------
    Douglas et al. 1996, §4.1–4.2 (fault groups, eigenvalues), §5.1.1 (residual scaling).

    Examples
    --------
    The design takes about half a second:

    >>> bank = path_bank()  # doctest: +SKIP
    >>> bank.generator.residuals[0], bank.groups[-1]  # doctest: +SKIP
    ('filter1:engine_speed_sensor[0]', 'filter4')
    """
    if dt is not None:
        dt = validate.positive("dt", dt)
    if poles is not None:
        if not isinstance(poles, Mapping):
            raise ParameterError(f"poles must be a dict filter name -> (sets, complement), got "
                                 f"{type(poles).__name__}")
        unknown = sorted(set(poles) - set(FILTER_GROUPS))
        if unknown:
            raise ParameterError(f"poles given for unknown filter(s) {unknown}; the filters are "
                                 f"{list(FILTER_GROUPS)}")
    eig = dict(EIGENVALUES, **(poles or {}))
    if models is None:
        models = (path_vehicle_12("midpoint"), path_vehicle_14("midpoint"))
    elif len(models) != 2 or not all(isinstance(m, FaultModel) and not m.is_discrete for m in models):
        raise ParameterError("models must be (12-state, 14-state) continuous FaultModels")
    nominal = dict(nominal_fault_sizes() if nominal is None else nominal)
    missing = sorted({f.partition(":")[0] for specs in FILTER_GROUPS.values() for f in specs} - set(nominal))
    if missing:
        raise ParameterError(f"nominal: no size for {missing}; give all 15 fault sizes")
    designs, gens, groups, scales = {}, [], [], {}
    for name, specs in FILTER_GROUPS.items():
        base = models[1] if name == "filter4" else models[0]
        model = base if dt is None else base.discretize(dt)
        sets, comp = eig[name]

        def to_plane(lam, _dt=dt):
            lam = np.asarray(lam, dtype=complex)
            return lam if _dt is None else np.exp(lam * _dt)

        faults = [s.partition(":")[0] for s in specs]
        maps = resolve_faults(model, specs)
        if name == "filter4":  # the brake's detection space taken 2-D, Im [F, A F] (§4.1)
            F = maps["brake_actuator"]
            maps["brake_actuator"] = np.hstack([F, model.A @ F])
        try:
            d = beard_jones(model, maps, {f: to_plane(s) for f, s in zip(faults, sets)}, to_plane(comp))
        except DesignError as exc:
            raise DesignError(f"{name}: {exc}") from exc
        designs[name] = d
        g, group_scales = scale_to_nominal(name, base, d.generator, faults, nominal, dt)
        scales.update(group_scales)
        gens.append(g)
        groups += [name] * len(g.residuals)
    return PathBank(designs, stack_generators(gens), tuple(groups), nominal, scales)


def path_runs(
    bank: PathBank,
    *,
    runs_per_fault: int = 1,
    healthy_runs: int = 1,
    duration: float = 20.0,
    onset: float = 5.0,
    size: float = 1.0,
    noise_fraction: float = 1e-4,
    dt: float = 0.01,
    seed: int = 0,
    progress: bool = False,
):
    """Simulated runs of the PATH scenarios with the bank's residuals: ``[(trace, residuals), ...]``.

    Each of the 15 faults as a bias of ``size`` times its nominal size (§5.1.1) at ``onset``,
    ``runs_per_fault`` times, plus ``healthy_runs`` fault-free runs; the 14-state plant
    (``tiny='midpoint'``) sampled at ``dt`` with white sensor noise of ``noise_fraction``
    times each sensor's nominal fault.  Seeds derive from ``seed``.

    Parameters
    ----------
    bank : PathBank
        From :func:`path_bank`.
    runs_per_fault : int, default 1
        Runs per fault (15 faults).
    healthy_runs : int, default 1
        Fault-free runs (first in the list).
    duration : float, default 20.0
        Length of each run [s].
    onset : float, default 5.0
        Fault onset [s], before ``duration``.
    size : float, default 1.0
        Bias size as a multiple of the nominal size.
    noise_fraction : float, default 1e-4
        Sensor noise standard deviation as a fraction of each sensor's nominal fault.
    dt : float, default 0.01
        Sample time [s] of the simulation and of the discretised generator.
    seed : int, default 0
        Seed from which each run's seed is drawn.
    progress : bool, default False
        Show a ``rich`` progress bar.

    Returns
    -------
    list of (Trace, Residuals)
        ``healthy_runs + 15 * runs_per_fault`` pairs: the simulated run and the bank's residuals on it.

    Raises
    ------
    ParameterError
        On a bad argument, or an ``onset`` not before ``duration``.

    References
    ----------
    Douglas et al. 1996, §5.1.1 (nominal fault sizes).

    Examples
    --------
    With a bank from :func:`path_bank` (half a second to design), one short fault-free run:

    >>> runs = path_runs(path_bank(), runs_per_fault=0, duration=1.0, onset=0.5)  # doctest: +SKIP
    >>> len(runs), runs[0][1].r.shape  # doctest: +SKIP
    (1, (101, 29))
    """
    from fdikit.faults import Bias, FaultScenario
    from fdikit.simulate import simulate

    validate.instance("bank", bank, PathBank, "design it with path_bank()")
    validate.integer("runs_per_fault", runs_per_fault, minimum=0)
    validate.integer("healthy_runs", healthy_runs, minimum=0)
    validate.integer("seed", seed, minimum=0)
    duration = validate.positive("duration", duration)
    onset = validate.non_negative("onset", onset)
    size = validate.number("size", size)
    noise_fraction = validate.non_negative("noise_fraction", noise_fraction)
    dt = validate.positive("dt", dt)
    if onset >= duration:
        raise ParameterError(f"onset = {onset} s is not before the end of the run (duration = {duration} s); "
                             "every fault would act after the run")
    plant = path_fault_model(14).discretize(dt)
    gen = bank.generator.discretize(dt)
    noise = noise_fraction * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    specs = [None] * healthy_runs + [f for f in plant.faults for _ in range(runs_per_fault)]
    seeds = np.random.default_rng(seed).integers(2**31, size=len(specs))
    items = list(zip(specs, seeds))
    if progress:
        from rich.progress import track

        items = track(items, description="simulating PATH runs")
    out = []
    for fault, s in items:
        faults = []
        if fault is not None:
            signal, loc = fault.rsplit("_", 1)
            faults = [Bias(signal, size * bank.nominal[fault], onset=onset, location=loc)]
        trace = simulate(plant, FaultScenario(faults), duration=duration, measurement_noise_std=noise, rng=int(s))
        out.append((trace, gen.run(trace)))
    return out
