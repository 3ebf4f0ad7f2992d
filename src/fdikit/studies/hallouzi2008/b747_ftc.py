"""Fault-tolerant flight of JSBSim's B747: outer PIDs, closed-loop SPC, IMM-driven reconfiguration (Hallouzi §6.5).

One flight: the B747 of :func:`fdikit.studies.hallouzi2008.b747_lip.lip_setup` (980 m, 92.6 m/s, flaps 20°,
263 t; Dryden turbulence, Table 6.2 sensor noise ``"thesis_std"``) flies the §6.5.1 plan
(:func:`fdikit.ftc.references.nominal_plan`: a 120° left turn at 75 s — the thesis's 180° → 60° from the
trim heading 0° here —, a descent to 100 m at γ = −5° from 150 s). Two rate groups (§6.6): at 100 Hz the
plant and the IMM (model set II + nominal, Table 4.7 logic, the persistence of the §4.4.2 study); at 10 Hz
the outer loops (:func:`fdikit.ftc.outer.outer_loops`) and the closed-loop SPC
(:class:`fdikit.spc.ClosedLoopSPC`, ``p = f = 20``, ``N_c = 5``, λ = 0.995) on the configuration of
:mod:`fdikit.ftc.configurations`.

Reconfiguration (§6.4). The first declared fault switches the SPC to the fault's Table 6.1 configuration
and re-initialises ``R`` from 100 s of open-loop data (``j = 1000`` columns) of the matching fault model —
the group's most probable model-set-II member at the declaration (e.g. the rudder locked at +25°),
linearised at its own trim (:func:`fdikit.studies.hallouzi2008.aircraft_models.local_model`), which
becomes the origin of the SPC's deviations. The predictor's past window is the flight's last 2 s
expressed in the new configuration (:meth:`ClosedLoopSPC.initialize`, ``past=``). The declaration is
latched: isolation is trusted only near the design point (§6.4), and the flight leaves it. An aileron
fault has no Table 6.1 configuration; it is logged and the configuration kept.

Choices the thesis leaves open, made here: the SPC weights (:data:`WEIGHTS`; ``Q_a`` only on
``φ, θ, V_TAS, β``, as in §6.5); the raise of the airspeed reference after an elevator isolation (the thesis
shows it only in Fig. 6.5): +10 m/s; the identification inputs (white, 1° on surfaces, 2 % on throttle
groups); a flight is declared lost when ``|φ| > 60°``, ``|θ| > 30°`` or ``h < 0`` and stops there.

The fixed controller the thesis compares with (the AG-16 autopilot) is fdikit's LQR autopilot
(:mod:`fdikit.aircraft.autopilot`) at 100 Hz, its heading, altitude and airspeed set points moved along the
same plan, without fault information.

References
----------
Hallouzi 2008, §6.2–§6.6, Tables 6.1–6.2, Figs. 6.1–6.13; §4.4.2, Table 4.7.
"""

from __future__ import annotations

from collections import Counter, deque
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate

__all__ = ["SCENARIOS", "BIJLMER", "WEIGHTS", "ALTITUDE_GAINS", "FORGETTING", "T_INJECT", "FtcSetup", "FtcRun",
           "ftc_setup", "fly_ftc", "scenario_fault"]

#: The §6.5 scenarios.
SCENARIOS = ("nominal", "elevator", "rudder", "bijlmer")
#: Fault injection time [s] (§6.5.2–§6.5.3).
T_INJECT = 18.0
#: The §6.5.4 "Bijlmerramp": its flight condition (mass as the other flights: the thesis gives none), the
#: fault time [s] and the mass lost with engines 3 and 4 and their pylons [kg].
BIJLMER = {"altitude": 980.0, "airspeed": 133.8, "flaps": 1.0, "onset": 10.0, "mass_lost": 10_028.0}
_SPC_DT = 0.1
#: λ of the recursive update (the thesis: 0.995; see the module docstring).
FORGETTING = 0.999
_P = _F = 20
_NC = 5
_J = 1000
_AIRSPEED_RAISE = 10.0
#: SPC weights per configuration: outputs ``φ θ ψ V α β h``, inputs (deg, %), input rates.
WEIGHTS = {
    "nominal": dict(output=[10.0, 10.0, 0.0, 1.0, 0.0, 10.0, 0.0], input=[0.1, 0.1, 0.1, 0.01],
                    rate=[1.0, 1.0, 1.0, 0.1]),
    "elevator": dict(output=[10.0, 30.0, 0.0, 1.0, 0.0, 10.0, 0.0], input=[0.1, 0.01, 0.1, 0.01],
                     rate=[1.0, 0.1, 1.0, 0.1]),
    "rudder": dict(output=[10.0, 10.0, 0.0, 1.0, 0.0, 10.0, 0.0], input=[0.1, 0.1, 0.01, 0.01],
                   rate=[1.0, 1.0, 0.1, 0.1]),
    "unanticipated": dict(output=[10.0, 10.0, 0.0, 1.0, 0.0, 10.0, 0.0], input=[0.1, 0.1, 0.01, 0.1, 0.01, 0.01],
                          rate=[1.0, 1.0, 0.1, 1.0, 0.1, 0.1]),
}
#: Altitude-loop gains ``(k_p, k_i, k_d)`` per configuration: with the 0.5 °/s stabilizer the pitch loop is slow,
#: and the default gains of :func:`fdikit.ftc.outer.outer_loops` drive a growing phugoid (±15° pitch).
ALTITUDE_GAINS = {"nominal": (-0.05, -0.005, -0.3), "rudder": (-0.05, -0.005, -0.3), "elevator": (-0.01, -0.0005, -0.2),
                  "unanticipated": (-0.05, -0.005, -0.3)}
_DRIVEN = ("aileron", "elevator", "stabilizer", "rudder")   # undriven ones are held at the trim
_MODEL_GROUP = {"rudder": "rudder", "elevator": "elevator"}


@dataclass
class _Origin:
    """One SPC configuration with the trim its deviations are taken from and its initialisation data."""

    config: object
    positions: dict
    throttles: np.ndarray
    y0: np.ndarray
    u: np.ndarray
    y: np.ndarray
    limits: object


@dataclass
class FtcSetup:
    """Aircraft, IMM and the SPC initialisations of every configuration (built once by :func:`ftc_setup`).

    Attributes
    ----------
    lip : LipSetup
        Aircraft, IMM and persistence of :func:`fdikit.studies.hallouzi2008.b747_lip.lip_setup`.
    trim : AircraftTrim
        The nominal trim.
    origins : dict
        ``(configuration, model name)`` → trim and open-loop data (nominal and the model-set-II faults).
    settings : dict
    start : AircraftSnapshot
        The aircraft at the nominal trim.
    bijlmer : dict
        ``start``, ``origin`` (the 6-input configuration) and ``autopilot`` at the §6.5.4 condition.

    Examples
    --------
    >>> setup = ftc_setup(calibration_seconds=30.0)  # doctest: +SKIP

    References
    ----------
    Hallouzi 2008, §6.4–§6.5.
    """

    lip: object
    trim: object
    origins: dict
    settings: dict = field(default_factory=dict)
    start: object = None
    bijlmer: dict = field(default_factory=dict)


@dataclass(frozen=True)
class FtcRun:
    """One flight, sampled at 10 Hz.

    Attributes
    ----------
    t : ndarray
    y : ndarray, shape (N, 7)
        ``φ θ ψ`` [deg], ``V_TAS`` [m/s], ``α β`` [deg], ``h`` [m] (measured).
    reference : ndarray, shape (N, 6)
        Inner references ``φ θ V β`` and the plan's ``ψ`` [deg], ``h`` [m].
    surfaces : ndarray, shape (N, 4)
        Aileron, elevator, stabilizer, rudder positions [deg].
    throttles : ndarray, shape (N, 4)
    mu : ndarray, shape (N, 8)
        Mode probabilities (model set II + nominal); empty for the autopilot.
    configuration : ndarray of str
    declared : tuple or None
        ``(fault group, model, time)`` of the isolation.
    lost : float or None
        Time the flight was declared lost.
    qp : dict
        QP status counts.
    step_seconds : ndarray
        Time of each SPC step [s].
    rcond : ndarray
        Reciprocal condition number of ``R11`` once per second.
    scenario, controller : str

    Examples
    --------
    >>> run = fly_ftc(ftc_setup(calibration_seconds=30.0), "nominal", duration=20.0)  # doctest: +SKIP
    >>> run.errors()["altitude_max"] < 20.0  # doctest: +SKIP
    True

    References
    ----------
    Hallouzi 2008, §6.5.
    """

    t: np.ndarray
    y: np.ndarray
    reference: np.ndarray
    surfaces: np.ndarray
    throttles: np.ndarray
    mu: np.ndarray
    configuration: np.ndarray
    declared: tuple | None
    lost: float | None
    qp: dict
    step_seconds: np.ndarray
    rcond: np.ndarray
    scenario: str
    controller: str

    def errors(self, start: float = 0.0) -> dict:
        """Tracking errors from ``start`` on: max ``|h − h_ref|``, max ``|ψ − ψ_ref|``, RMS ``θ, φ, β`` errors.

        Parameters
        ----------
        start : float, optional
            [s].

        Returns
        -------
        dict
            ``altitude_max`` [m], ``heading_max`` [deg], ``pitch_rms``, ``roll_rms``, ``beta_rms`` [deg],
            ``airspeed_rms`` [m/s].
        """
        k = self.t >= start
        y, r = self.y[k], self.reference[k]
        dpsi = (y[:, 2] - r[:, 4] + 180.0) % 360.0 - 180.0

        def rms(a):
            return float(np.sqrt(np.mean(a**2))) if a.size else float("nan")

        return {"altitude_max": float(np.max(np.abs(y[:, 6] - r[:, 5]), initial=0.0)),
                "heading_max": float(np.max(np.abs(dpsi), initial=0.0)),
                "pitch_rms": rms(y[:, 1] - r[:, 1]), "roll_rms": rms(y[:, 0] - r[:, 0]),
                "beta_rms": rms(y[:, 5]), "airspeed_rms": rms(y[:, 3] - r[:, 2])}


def scenario_fault(scenario: str) -> list:
    """The §6.5 faults of a scenario: elevator LIP at 1.9° or rudder runaway to 25° at 50°/s (both at 18 s), or
    engines 3 and 4 lost at 10 s (the Bijlmerramp; its mass loss is applied by :func:`fly_ftc`).

    Parameters
    ----------
    scenario : {"nominal", "elevator", "rudder", "bijlmer"}

    Returns
    -------
    list of Fault

    Raises
    ------
    ParameterError
        For an unknown scenario.

    Examples
    --------
    >>> [type(f).__name__ for f in scenario_fault("rudder")], scenario_fault("nominal")
    (['Runaway'], [])

    References
    ----------
    Hallouzi 2008, §6.5.2–§6.5.4.
    """
    from fdikit.actuator_faults import EngineFailure, LockInPlace, Runaway

    validate.choice("scenario", scenario, list(SCENARIOS))
    if scenario == "elevator":
        return [LockInPlace("elevator", position=float(np.radians(1.9)), onset=T_INJECT)]
    if scenario == "rudder":
        return [Runaway("rudder", position=float(np.radians(25.0)), rate=float(np.radians(50.0)), onset=T_INJECT)]
    if scenario == "bijlmer":
        return [EngineFailure(f"throttle_{i}", onset=BIJLMER["onset"]) for i in (3, 4)]
    return []


def _origin(ac, trim, config, rng) -> _Origin:
    from fdikit.aircraft.plant import STATES
    from fdikit.ftc.configurations import SPC_OUTPUTS, configuration_model, identification_data

    A, B, C = configuration_model(ac, trim, config, _SPC_DT)
    std = [2.0 if n.startswith("engines") else 1.0 for n in config.inputs]
    u, y = identification_data(A, B, C, _J + _P, rng, input_std=std)
    thr = np.full(ac.engines, float(trim.throttle))
    y0 = np.array([trim.x[STATES.index(n)] * k for n, k in SPC_OUTPUTS])
    return _Origin(config, dict(trim.positions), thr, y0, u, y, config.limits(trim.positions, thr, _SPC_DT))


def ftc_setup(*, turbulence: int = 3, calibration_seconds: float = 300.0, seed: int = 7) -> FtcSetup:
    """Build the aircraft and IMM (:func:`lip_setup`, noise ``"thesis_std"``) and every SPC initialisation.

    Parameters
    ----------
    turbulence : int, optional
        MIL-F-8785C severity (default 3, light).
    calibration_seconds : float, optional
        Fault-free flight the IMM's process noise is identified on (default 300 s).
    seed : int, optional
        Seed of the identification data.

    Returns
    -------
    FtcSetup

    Examples
    --------
    >>> setup = ftc_setup(calibration_seconds=30.0)  # doctest: +SKIP

    References
    ----------
    Hallouzi 2008, §6.4–§6.5.
    """
    from fdikit.aircraft import HALLOUZI_POINT, FlightCondition, linearize_aircraft, lqr_autopilot, trim_aircraft
    from fdikit.ftc.configurations import input_configuration
    from fdikit.studies.hallouzi2008.aircraft_models import local_model
    from fdikit.studies.hallouzi2008.b747_lip import lip_setup

    lip = lip_setup(noise="thesis_std", turbulence=turbulence, calibration_seconds=calibration_seconds)
    ac = lip.aircraft
    rng = np.random.default_rng(seed)
    ac.restore(lip.start)
    ac.set_turbulence(0)
    trim = lip.nominal.linearization.trim
    origins = {("nominal", "nominal"): _origin(ac, trim, input_configuration("nominal"), rng)}
    for m in lip.models:
        if m.fault in _MODEL_GROUP:
            fault_trim = local_model(ac, m.fault, m.size).linearization.trim
            origins[(m.fault, m.name)] = _origin(ac, fault_trim, input_configuration(_MODEL_GROUP[m.fault]), rng)
    ac.restore(lip.start)
    cond = FlightCondition(BIJLMER["altitude"], BIJLMER["airspeed"], flaps=float(np.radians(BIJLMER["flaps"])),
                           mass=HALLOUZI_POINT.mass)
    b_trim = trim_aircraft(ac, cond)
    bijlmer = {"origin": _origin(ac, b_trim, input_configuration("unanticipated"), rng),
               "autopilot": lqr_autopilot(linearize_aircraft(ac, b_trim)), "start": ac.snapshot()}
    ac.restore(lip.start)
    setup = FtcSetup(lip, trim, origins, dict(turbulence=turbulence, calibration_seconds=calibration_seconds,
                                              seed=seed), bijlmer=bijlmer)
    setup.start = lip.start
    return setup


class _Persistence:
    """Online form of the §4.4.2 declaration: a label in at least ``k`` of the last ``n`` raw decisions."""

    def __init__(self, k: int, n: int) -> None:
        self.k, self.window, self.counts = k, deque(maxlen=n), Counter()

    def step(self, label: str) -> str | None:
        if len(self.window) == self.window.maxlen:
            self.counts[self.window[0]] -= 1
        self.window.append(label)
        self.counts[label] += 1
        best, c = max(((g, c) for g, c in self.counts.items() if g not in ("none", "unknown")),
                      key=lambda gc: gc[1], default=(None, 0))
        return best if c >= self.k else None


def _trusted(t, plan, y, origin) -> bool:
    """Near the design point, where the isolation is trusted (§6.4): straight and level commanded (before the
    plan's turn and descent), ``|h − h°| ≤ 100 m`` and ``|V − V°| ≤ 10 m/s``."""
    steady = t < min(plan.turn_start, plan.descent_start)
    return steady and abs(y[9] - origin.y0[6]) <= 100.0 and abs(y[3] - origin.y0[3]) <= 10.0


def _spc(origin, previous=None, forgetting=0.999):
    from fdikit.spc import ClosedLoopSPC, SpcWeights

    spc = ClosedLoopSPC(_P, _F, _NC, SpcWeights(**WEIGHTS[origin.config.name]), origin.limits,
                        forgetting=forgetting) if previous is None else previous
    spc.weights = SpcWeights(**WEIGHTS[origin.config.name])
    spc.limits = origin.limits
    return spc


def fly_ftc(setup: FtcSetup, scenario: str = "nominal", *, controller: str = "spc", reconfigure: bool = True,
            duration: float = 300.0, seed: int = 0, forgetting: float = FORGETTING, adapt: str = "after_switch",
            isolation: tuple | None = None, progress=None) -> FtcRun:
    """Fly the §6.5 plan with a fault scenario, by the FTC (SPC + IMM switching) or by the LQR autopilot.

    Parameters
    ----------
    setup : FtcSetup
    scenario : {"nominal", "elevator", "rudder", "bijlmer"}
    controller : {"spc", "autopilot"}
    reconfigure : bool, optional
        Switch the SPC configuration on isolation (default True; False keeps the nominal one).
    duration : float, optional
        [s] (default 300).
    seed : int, optional
        Turbulence and sensor-noise seed.
    forgetting : float, optional
        λ of the recursive predictor update (default :data:`FORGETTING`; the thesis's 0.995 loses the
        descent here, see the module docstring).
    adapt : {"after_switch", "always", "never"}, optional
        When the predictor is updated: only after a reconfiguration (default; the nominal predictor stays
        the identified one — see the module docstring), always (the thesis), or never. The Bijlmerramp
        always adapts (no FDI: adaptation is how the SPC learns the fault).
    isolation : tuple of (str, float), optional
        ``(model name, time)``: switch to that fault model's configuration at that time instead of running the
        IMM (a known fault — to study the reconfiguration apart from the isolation); e.g.
        ``("rudder_lip_+25", 22.0)``, the thesis's isolation time.
    progress : callable, optional
        Called with the simulated time every 10 s.

    Returns
    -------
    FtcRun

    Raises
    ------
    ParameterError
        For an unknown scenario, controller or isolation model.

    Examples
    --------
    >>> run = fly_ftc(ftc_setup(calibration_seconds=30.0), "rudder", duration=40.0)  # doctest: +SKIP
    >>> run.declared[0]  # doctest: +SKIP
    'rudder'

    References
    ----------
    Hallouzi 2008, §6.2–§6.6.
    """
    from fdikit.aircraft.actuators import ActuatorBank
    from fdikit.aircraft.plant import SENSORS
    from fdikit.ftc.outer import outer_loops
    from fdikit.ftc.references import nominal_plan
    from fdikit.multimodel.isolation import table_4_7_logic

    faults = scenario_fault(scenario)
    validate.choice("controller", controller, ["spc", "autopilot"])
    if isolation is not None:
        validate.choice("isolation model", isolation[0], [k[1] for k in setup.origins if k[0] != "nominal"])
    duration = validate.positive("duration", duration)
    lip, ac = setup.lip, setup.lip.aircraft
    bijlmer = scenario == "bijlmer"   # unanticipated: the 6-input configuration, no FDI, always adapting
    ac.restore(setup.bijlmer["start"] if bijlmer else setup.start)
    ac.set_turbulence(lip.turbulence, seed=seed)
    ac.inject(faults)
    autopilot = setup.bijlmer["autopilot"] if bijlmer else lip.autopilot
    mass_after = ac.mass - BIJLMER["mass_lost"] if bijlmer else None
    healthy = ActuatorBank(ac.actuators.limits)
    healthy.restore(ac.actuators.snapshot())
    rng = np.random.default_rng(seed)
    plan = nominal_plan(heading=0.0, new_heading=-120.0, airspeed=BIJLMER["airspeed"] if bijlmer else 92.6)
    idx = [SENSORS.index(s) for s in lip.measured]
    spc_idx = [SENSORS.index(s) for s in ("roll", "pitch", "heading", "true_airspeed", "alpha", "beta", "altitude")]
    units = np.array([np.degrees(1.0)] * 3 + [1.0] + [np.degrees(1.0)] * 2 + [1.0])
    stepper = lip.imm.online()
    logic = table_4_7_logic(0.2)
    n = max(1, int(round(lip.confirm / ac.dt)))
    persistence = _Persistence(max(1, int(np.ceil(lip.share * n))), n)
    every = int(round(_SPC_DT / ac.dt))
    origin = origin0 = setup.bijlmer["origin"] if bijlmer else setup.origins[("nominal", "nominal")]
    loops = outer_loops(_SPC_DT, pitch_trim=float(origin.y0[1]), altitude_gains=ALTITUDE_GAINS[origin.config.name])
    spc = None
    if controller == "spc":
        spc = _spc(origin, forgetting=validate.in_range("forgetting", forgetting, 0.0, 1.0, closed="right"))
        spc.adapt = validate.choice("adapt", adapt, ["after_switch", "always", "never"]) == "always" or bijlmer
        spc.initialize(origin.u, origin.y, past=(np.zeros((_P + 1, origin.config.m)), np.zeros((_P + 1, 7))))
    rec = {k: [] for k in ("t", "y", "r", "s", "thr", "mu", "cfg", "sec")}
    rcond, declared, lost = [], None, None
    u_prev = dev_prev = None
    mu = np.full(len(lip.models), np.nan)
    throttles = [f"throttle_{i + 1}" for i in range(ac.engines)]
    hist_pos, hist_thr, hist_y = deque(maxlen=_P + 2), deque(maxlen=_P + 2), deque(maxlen=_P + 2)
    for k in range(int(round(duration / ac.dt))):
        t = ac.time
        if mass_after is not None and t >= BIJLMER["onset"]:
            ac.set_mass(mass_after, in_flight=True)
            mass_after = None
        y = ac.measure(lip.noise_std, rng)
        if controller == "autopilot":
            c = autopilot.commands(y, {"heading": plan.heading(t), "altitude": plan.altitude(t),
                                           "true_airspeed": plan.airspeed_at(t)})
            ac.set_inputs(aileron=c["aileron"], elevator=c["elevator"], rudder=c["rudder"],
                          **dict.fromkeys(throttles, c["throttle"]))
        pos = healthy.update(ac.surface_commands(), t, ac.dt)
        if controller == "spc" and not bijlmer:   # the IMM runs on; only its first declaration acts
            key = None
            if isolation is None:
                u_imm = np.array([pos["aileron"], pos["elevator"], pos["stabilizer"], pos["rudder"],
                                  ac.thrust().sum(), 1.0])
                mu = stepper.step(u_imm, y[idx]).mu
                raw = str(logic.isolate(mu[None])[0]) if _trusted(t, plan, y, origin0) else "none"
                label = persistence.step(raw)
                if label is not None and declared is None and len(hist_y) == _P + 2:
                    member = max((i for i, m in enumerate(lip.models) if m.fault == label), key=lambda i: mu[i])
                    key = (label, lip.models[member].name)
            elif declared is None and t >= isolation[1] and len(hist_y) == _P + 2:
                key = next(k_ for k_ in setup.origins if k_[1] == isolation[0])
            if key is not None:
                declared = (*key, t)
                if reconfigure and key in setup.origins:
                    origin = setup.origins[key]
                    if key[0] == "elevator":
                        plan = plan.with_airspeed(t, plan.airspeed + _AIRSPEED_RAISE)
                    spc = _spc(origin, spc)
                    gains = ALTITUDE_GAINS[origin.config.name]
                    loops.altitude.kp, loops.altitude.ki, loops.altitude.kd = gains   # integrator kept: bumpless
                    spc.adapt = adapt != "never"
                    past_u = np.array([origin.config.vector(p_, th, origin.positions, origin.throttles)
                                       for p_, th in zip(hist_pos, hist_thr, strict=True)])
                    past_y = np.array(hist_y) - origin.y0
                    past_y[:, 2] = (past_y[:, 2] + 180.0) % 360.0 - 180.0
                    spc.initialize(origin.u, origin.y, past=(past_u[:-1], past_y[:-1]))  # the last comes with step()
                    u_prev = past_u[-1]
                    dev_prev = past_y[-1]
        if k % every == 0:
            y7 = y[spc_idx] * units
            phi_r, theta_r, v_r, beta_r = loops.references(t, plan, altitude=y[SENSORS.index("altitude")],
                                                           heading=y[SENSORS.index("heading")])
            if controller == "spc":
                dev = y7 - origin.y0
                dev[2] = (dev[2] + 180.0) % 360.0 - 180.0
                r = np.zeros(7)
                r[[0, 1, 3, 5]] = np.array([phi_r, theta_r, v_r, beta_r]) - origin.y0[[0, 1, 3, 5]]
                u = np.zeros(origin.config.m) if u_prev is None else spc.step(u_prev, dev_prev, r)
                if spc.history:
                    rec["sec"].append(spc.history[-1].seconds)
                u_prev, dev_prev = u, dev
                cmd = origin.config.commands(u, origin.positions, origin.throttles)
                ac.set_inputs(**{**{s: origin.positions[s] for s in _DRIVEN}, **cmd})
                hist_pos.append({s: ac.commands[s] for s in _DRIVEN})
                hist_thr.append(np.array([ac.commands[c_] for c_ in throttles]))
                hist_y.append(y7)
                if k % (10 * every) == 0:
                    rcond.append(1.0 / np.linalg.cond(spc.factor.R11))
            rec["t"].append(t)
            rec["y"].append(y7)
            rec["r"].append([phi_r, theta_r, v_r, beta_r, np.degrees(plan.heading(t)), plan.altitude(t)])
            a = ac.actuators.positions
            rec["s"].append(np.degrees([a["aileron"], a["elevator"], a["stabilizer"], a["rudder"]]))
            rec["thr"].append([ac.commands[c_] for c_ in throttles])
            rec["mu"].append(mu.copy())
            rec["cfg"].append(origin.config.name if controller == "spc" else "autopilot")
            if abs(y7[0]) > 60.0 or abs(y7[1]) > 30.0 or y7[6] < 0.0:
                lost = t
                break
            if progress is not None and k % (1000 * every) == 0:
                progress(t)
        ac.step()
    qp = Counter(h.status for h in spc.history) if spc is not None else Counter()
    return FtcRun(t=np.array(rec["t"]), y=np.array(rec["y"]), reference=np.array(rec["r"]),
                  surfaces=np.array(rec["s"]), throttles=np.array(rec["thr"]),
                  mu=np.array(rec["mu"]) if controller == "spc" else np.zeros((len(rec["t"]), 0)),
                  configuration=np.array(rec["cfg"]), declared=declared, lost=lost, qp=dict(qp),
                  step_seconds=np.array(rec["sec"]), rcond=np.array(rcond), scenario=scenario,
                  controller=controller)
