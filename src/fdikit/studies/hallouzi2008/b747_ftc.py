"""Fault-tolerant flight of JSBSim's B747: outer PIDs, closed-loop SPC, IMM-driven reconfiguration (Hallouzi §6.5).

One flight: the B747 of :func:`fdikit.studies.hallouzi2008.b747_lip.lip_setup` (980 m, 92.6 m/s, flaps 20°,
263 t; Dryden turbulence, Table 6.2 sensor noise ``"thesis_std"``) flies the §6.5.1 plan
(:func:`fdikit.ftc.references.nominal_plan`: a 120° left turn at 75 s — the thesis's 180° → 60° from the
trim heading 0° here —, a descent to 100 m at γ = −5° from 150 s). Two rate groups (§6.6): at 100 Hz the
plant and the IMM (model set II + nominal, Table 4.7 logic, the persistence of the §4.4.2 study); at 10 Hz
the outer loops (:func:`fdikit.ftc.outer.outer_loops`) and the closed-loop SPC
(:class:`fdikit.spc.ClosedLoopSPC`, ``p = f = 20``, ``N_c = 5``, λ = 0.995) on the configuration of
:mod:`fdikit.ftc.configurations`. This module builds the set-up and holds the results;
:func:`fdikit.studies.hallouzi2008.b747_ftc_flight.fly_ftc` flies.

Reconfiguration (§6.4). The first declared fault switches the SPC to the fault's Table 6.1 configuration
and re-initialises ``R`` from 100 s of open-loop data (``j = 1000`` columns) of the matching fault model —
the group's most probable model-set-II member at the declaration (e.g. the rudder locked at +25°),
linearised at its own trim (:func:`fdikit.studies.hallouzi2008.aircraft_models.local_model`), which
becomes the origin of the SPC's deviations. The predictor's past window is the flight's last 2 s
expressed in the new configuration (:meth:`ClosedLoopSPC.initialize`, ``past=``). The declaration is
latched: isolation is trusted only near the design point (§6.4), and the flight leaves it. An aileron
fault has no Table 6.1 configuration; it is logged and the configuration kept.

Choices the thesis leaves open or that had to change (figures in ``docs/methods/ftc.md``):

* the SPC weights (:data:`WEIGHTS`; ``Q_a`` only on ``φ, θ, V_TAS, β``, as in §6.5) and, for the elevator
  configuration, slower altitude-loop gains (:data:`ALTITUDE_GAINS`: the 0.5 °/s stabilizer cannot follow
  the default ones, and a growing phugoid sets in);
* the start-up data: white inputs (1° on surfaces, 2 % on throttle groups) on the configuration's linear
  model, Table 6.2 noise; the first past window is the trim, not the data's end (a false first innovation
  otherwise wrecks the fit);
* the predictor adapts (λ = 0.995) only after a reconfiguration; the nominal one stays as identified —
  adapting it under turbulence degrades the nominal flight and, during a rudder runaway, delays or
  prevents the isolation (``adapt="always"`` is the thesis's);
* isolation is trusted while the plan commands straight and level flight near the design point;
* after an elevator isolation the airspeed reference is raised by 10 m/s (Fig. 6.5 shows a raise only);
* a QP the solver fails on holds the last input and is counted in :attr:`FtcRun.qp`;
* a flight is declared lost when ``|φ| > 60°``, ``|θ| > 30°`` or ``h < 0`` and stops there.

The Bijlmerramp (§6.5.4, :data:`BIJLMER`) cuts engines 3 and 4 and drops 10 028 kg at 10 s, flies the
6-input configuration without FDI and always adapts; JSBSim has no model of the wing damage, CG shift or
hydraulic loss, so those are not simulated.

The fixed controller the thesis compares with (the AG-16 autopilot) is fdikit's LQR autopilot
(:mod:`fdikit.aircraft.autopilot`) at 100 Hz, its heading, altitude and airspeed set points moved along the
same plan, without fault information.

References
----------
Hallouzi 2008, §6.2–§6.6, Tables 6.1–6.2, Figs. 6.1–6.13; §4.4.2, Table 4.7.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fdikit import validate

__all__ = ["SCENARIOS", "BIJLMER", "SPC_SETTINGS", "WEIGHTS", "ALTITUDE_GAINS", "FORGETTING", "T_INJECT", "FtcSetup",
           "FtcRun", "ftc_setup", "scenario_fault"]

#: The §6.5 scenarios.
SCENARIOS = ("nominal", "elevator", "rudder", "bijlmer")
#: Fault injection time [s] (§6.5.2–§6.5.3).
T_INJECT = 18.0
#: The §6.5.4 "Bijlmerramp": its flight condition (mass as the other flights: the thesis gives none), the
#: fault time [s] and the mass lost with engines 3 and 4 and their pylons [kg].
BIJLMER = {"altitude": 980.0, "airspeed": 133.8, "flaps": 1.0, "onset": 10.0, "mass_lost": 10_028.0}
#: The SPC of §6.5: sample time [s], past and future horizons, control horizon, start-up data columns.
SPC_SETTINGS = {"dt": 0.1, "p": 20, "f": 20, "control_horizon": 5, "columns": 1000}
#: λ of the recursive update (the thesis's 0.995).
FORGETTING = 0.995
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
_RECONFIGURED = ("rudder", "elevator")   # the fault groups of model set II with a Table 6.1 configuration


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
        Reciprocal condition number of ``R11`` once per second (1-norm, LAPACK ``trcon`` estimate).
    scenario, controller : str
    timings : dict
        Per rate group (``fdi``, ``spc``, ``plant``) the :meth:`fdikit.ftc.multirate.RateGroup.timing`.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_ftc_flight import fly_ftc
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
    timings: dict = field(default_factory=dict)

    def errors(self, start: float = 0.0, end: float = np.inf) -> dict:
        """Tracking errors over ``start ≤ t < end``: max ``|h − h_ref|``, max ``|ψ − ψ_ref|``, RMS ``θ, φ, β`` errors.

        Parameters
        ----------
        start, end : float, optional
            [s] (default the whole flight).

        Returns
        -------
        dict
            ``altitude_max`` [m], ``heading_max`` [deg], ``pitch_rms``, ``roll_rms``, ``beta_rms`` [deg],
            ``airspeed_rms`` [m/s].
        """
        k = (self.t >= start) & (self.t < end)
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
    engines 3 and 4 lost at 10 s (the Bijlmerramp; its mass loss is applied by
    :func:`fdikit.studies.hallouzi2008.b747_ftc_flight.fly_ftc`).

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

    dt = SPC_SETTINGS["dt"]
    A, B, C = configuration_model(ac, trim, config, dt)
    std = [2.0 if n.startswith("engines") else 1.0 for n in config.inputs]
    u, y = identification_data(A, B, C, SPC_SETTINGS["columns"] + SPC_SETTINGS["p"], rng, input_std=std)
    thr = np.full(ac.engines, float(trim.throttle))
    y0 = np.array([trim.x[STATES.index(n)] * k for n, k in SPC_OUTPUTS])
    return _Origin(config, dict(trim.positions), thr, y0, u, y, config.limits(trim.positions, thr, dt))


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
        if m.fault in _RECONFIGURED:
            fault_trim = local_model(ac, m.fault, m.size).linearization.trim
            origins[(m.fault, m.name)] = _origin(ac, fault_trim, input_configuration(m.fault), rng)
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
