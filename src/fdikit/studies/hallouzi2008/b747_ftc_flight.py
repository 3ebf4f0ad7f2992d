"""One §6.5 flight of the B747 FTC in the two rate groups of Hallouzi 2008 §6.6 (Fig. 6.14).

:func:`fly_ftc` runs three groups on :class:`fdikit.ftc.multirate.MultiRate` with the plant's 0.01 s base
period, in this order on every tick:

1. ``fdi`` (100 Hz): the sensors; the LQR autopilot when it flies; the fault-free actuator copy; the IMM,
   the Table 4.7 logic with its persistence and, on the first trusted declaration, the reconfiguration;
2. ``spc`` (10 Hz): the outer loops, the closed-loop SPC step and the commands; the records;
3. ``plant`` (100 Hz): one JSBSim step.

The per-group timings (:meth:`MultiRate.timings`) come back in :attr:`FtcRun.timings`, the real-time
budget of §6.6. The set-up, the scenarios and the choices are described in
:mod:`fdikit.studies.hallouzi2008.b747_ftc`.

References
----------
Hallouzi 2008, §6.2–§6.6, Fig. 6.14; §4.4.2, Table 4.7.
"""

from __future__ import annotations

from collections import Counter, deque

import numpy as np

from fdikit import validate
from fdikit.errors import DesignError
from fdikit.studies.hallouzi2008.b747_ftc import (
    ALTITUDE_GAINS,
    BIJLMER,
    FORGETTING,
    SPC_SETTINGS,
    WEIGHTS,
    FtcRun,
    scenario_fault,
)
from fdikit.studies.hallouzi2008.b747_lip import imm_input

__all__ = ["fly_ftc"]

_AIRSPEED_RAISE = 10.0                                        # after an elevator isolation [m/s]
_DRIVEN = ("aileron", "elevator", "stabilizer", "rudder")     # undriven ones are held at the trim
_SPC_OUTPUTS = ("roll", "pitch", "heading", "true_airspeed", "alpha", "beta", "altitude")
_UNITS = np.array([np.degrees(1.0)] * 3 + [1.0] + [np.degrees(1.0)] * 2 + [1.0])


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


def _spc(origin, previous=None, forgetting=FORGETTING):
    from fdikit.spc import ClosedLoopSPC, SpcWeights

    s = SPC_SETTINGS
    spc = ClosedLoopSPC(s["p"], s["f"], s["control_horizon"], SpcWeights(**WEIGHTS[origin.config.name]),
                        origin.limits, forgetting=forgetting) if previous is None else previous
    spc.weights = SpcWeights(**WEIGHTS[origin.config.name])
    spc.limits = origin.limits
    return spc


class _Flight:
    """The state of one flight and the two rate groups' functions (see the module docstring)."""

    def __init__(self, setup, scenario, controller, reconfigure, seed, forgetting, adapt, isolation):
        from scipy.linalg.lapack import dtrcon

        from fdikit.aircraft.actuators import ActuatorBank
        from fdikit.aircraft.plant import SENSORS
        from fdikit.ftc.outer import outer_loops
        from fdikit.ftc.references import nominal_plan
        from fdikit.multimodel.isolation import table_4_7_logic

        lip = setup.lip
        ac = self.ac = lip.aircraft
        self.every = int(round(SPC_SETTINGS["dt"] / ac.dt))
        self._trcon = dtrcon
        self.setup, self.lip, self.controller, self.reconfigure = setup, lip, controller, reconfigure
        self.adapt, self.isolation = adapt, isolation
        self.bijlmer = scenario == "bijlmer"   # unanticipated: the 6-input configuration, no FDI, always adapting
        ac.restore(setup.bijlmer["start"] if self.bijlmer else setup.start)
        ac.set_turbulence(lip.turbulence, seed=seed)
        ac.inject(scenario_fault(scenario))
        self.autopilot = setup.bijlmer["autopilot"] if self.bijlmer else lip.autopilot
        self.mass_after = ac.mass - BIJLMER["mass_lost"] if self.bijlmer else None
        self.healthy = ActuatorBank(ac.actuators.limits)
        self.healthy.restore(ac.actuators.snapshot())
        self.rng = np.random.default_rng(seed)
        self.plan = nominal_plan(heading=0.0, new_heading=-120.0,
                                 airspeed=BIJLMER["airspeed"] if self.bijlmer else 92.6)
        self.imm_idx = [SENSORS.index(s) for s in lip.measured]
        self.spc_idx = [SENSORS.index(s) for s in _SPC_OUTPUTS]
        self.h_idx, self.psi_idx = SENSORS.index("altitude"), SENSORS.index("heading")
        self.stepper = lip.imm.online()
        self.logic = table_4_7_logic(0.2)
        n = max(1, int(round(lip.confirm / ac.dt)))
        self.persistence = _Persistence(max(1, int(np.ceil(lip.share * n))), n)
        self.origin = self.origin0 = setup.bijlmer["origin"] if self.bijlmer else setup.origins[("nominal", "nominal")]
        self.loops = outer_loops(SPC_SETTINGS["dt"], pitch_trim=float(self.origin.y0[1]),
                                 altitude_gains=ALTITUDE_GAINS[self.origin.config.name])
        self.spc = None
        p, m = SPC_SETTINGS["p"], self.origin.config.m
        if controller == "spc":
            self.spc = _spc(self.origin, forgetting=forgetting)
            self.spc.adapt = adapt == "always" or self.bijlmer
            self.spc.initialize(self.origin.u, self.origin.y, past=(np.zeros((p + 1, m)), np.zeros((p + 1, 7))))
        self.rec = {k: [] for k in ("t", "y", "r", "s", "thr", "mu", "cfg", "sec")}
        self.rcond, self.declared, self.lost, self.failed = [], None, None, 0
        self.u_prev = self.dev_prev = self.y = None
        self.mu = np.full(len(lip.models), np.nan)
        self.throttles = [f"throttle_{i + 1}" for i in range(ac.engines)]
        self.hist = deque(maxlen=p + 2)                # (commanded surfaces, throttles, SPC outputs) per SPC step

    # ------------------------------------------------------------------ 100 Hz
    def fdi(self, tick, _t) -> None:
        ac, t = self.ac, self.ac.time
        if self.mass_after is not None and t >= BIJLMER["onset"]:
            ac.set_mass(self.mass_after, in_flight=True)
            self.mass_after = None
        y = self.y = ac.measure(self.lip.noise_std, self.rng)
        if self.controller == "autopilot":
            plan = self.plan
            self.autopilot.apply(ac, y, {"heading": plan.heading(t), "altitude": plan.altitude(t),
                                         "true_airspeed": plan.airspeed_at(t)})
        pos = self.healthy.update(ac.surface_commands(), t, ac.dt)
        if self.controller != "spc" or self.bijlmer:
            return
        key, ready = None, self.declared is None and len(self.hist) == self.hist.maxlen
        if self.isolation is None:                     # the IMM runs on; only its first declaration acts
            self.mu = self.stepper.step(imm_input(ac, pos), y[self.imm_idx]).mu
            raw = str(self.logic.isolate(self.mu[None])[0]) if self._trusted(t, y) else "none"
            label = self.persistence.step(raw)
            if label is not None and ready:
                models = self.lip.models
                member = max((i for i, m in enumerate(models) if m.fault == label), key=lambda i: self.mu[i])
                key = (label, models[member].name)
        elif ready and t >= self.isolation[1]:
            key = next(k for k in self.setup.origins if k[1] == self.isolation[0])
        if key is not None:
            self.declared = (*key, t)
            if self.reconfigure and key in self.setup.origins:
                self._switch(key, t)

    def _trusted(self, t, y) -> bool:
        """Near the design point, where the isolation is trusted (§6.4): straight and level commanded (before
        the plan's turn and descent), ``|h − h°| ≤ 100 m`` and ``|V − V°| ≤ 10 m/s``."""
        plan, y0 = self.plan, self.origin0.y0
        return (t < min(plan.turn_start, plan.descent_start) and abs(y[9] - y0[6]) <= 100.0
                and abs(y[3] - y0[3]) <= 10.0)

    def _switch(self, key, t) -> None:
        """§6.4: the fault's configuration, R from its model's data, the flight's last 2 s as the past window."""
        o = self.origin = self.setup.origins[key]
        if key[0] == "elevator":
            self.plan = self.plan.with_airspeed(t, self.plan.airspeed + _AIRSPEED_RAISE)
        self.spc = _spc(o, self.spc)
        self.spc.adapt = self.adapt != "never"
        alt = self.loops.altitude
        alt.kp, alt.ki, alt.kd = ALTITUDE_GAINS[o.config.name]      # the integrator is kept: bumpless
        past_u = np.array([o.config.vector(p, th, o.positions, o.throttles) for p, th, _ in self.hist])
        past_y = np.array([y7 for *_, y7 in self.hist]) - o.y0
        past_y[:, 2] = (past_y[:, 2] + 180.0) % 360.0 - 180.0
        self.spc.initialize(o.u, o.y, past=(past_u[:-1], past_y[:-1]))   # the last one comes with step()
        self.u_prev, self.dev_prev = past_u[-1], past_y[-1]

    # ------------------------------------------------------------------ 10 Hz
    def control(self, tick, _t) -> None:
        ac, t, y, o = self.ac, self.ac.time, self.y, self.origin
        y7 = y[self.spc_idx] * _UNITS
        refs = self.loops.references(t, self.plan, altitude=y[self.h_idx], heading=y[self.psi_idx])
        if self.controller == "spc":
            dev = y7 - o.y0
            dev[2] = (dev[2] + 180.0) % 360.0 - 180.0
            r = np.zeros(7)
            r[[0, 1, 3, 5]] = np.array(refs) - o.y0[[0, 1, 3, 5]]
            u = np.zeros(o.config.m)
            if self.u_prev is not None:
                try:
                    u = self.spc.step(self.u_prev, self.dev_prev, r)
                    self.rec["sec"].append(self.spc.history[-1].seconds)
                except DesignError:                    # the solver failed on this QP: hold the last input
                    u, self.failed = self.u_prev, self.failed + 1
            self.u_prev, self.dev_prev = u, dev
            ac.set_inputs(**{**{s: o.positions[s] for s in _DRIVEN}, **o.config.commands(u, o.positions, o.throttles)})
            self.hist.append(({s: ac.commands[s] for s in _DRIVEN}, np.array([ac.commands[c] for c in self.throttles]),
                              y7))
            if tick % (10 * self.every) == 0:      # once a second: LAPACK's 1-norm estimate, O(n²) on a triangle
                self.rcond.append(float(self._trcon(self.spc.factor.R11, norm="1", uplo="L")[0]))
        rec, plan, a = self.rec, self.plan, ac.actuators.positions
        rec["t"].append(t)
        rec["y"].append(y7)
        rec["r"].append([*refs, np.degrees(plan.heading(t)), plan.altitude(t)])
        rec["s"].append(np.degrees([a["aileron"], a["elevator"], a["stabilizer"], a["rudder"]]))
        rec["thr"].append([ac.commands[c] for c in self.throttles])
        rec["mu"].append(self.mu.copy())
        rec["cfg"].append(o.config.name if self.controller == "spc" else "autopilot")
        if abs(y7[0]) > 60.0 or abs(y7[1]) > 30.0 or y7[6] < 0.0:
            self.lost = t

    def result(self, scenario, timings) -> FtcRun:
        rec = self.rec
        qp = Counter(h.status for h in self.spc.history) if self.spc is not None else Counter()
        if self.failed:
            qp["failed (input held)"] = self.failed
        return FtcRun(t=np.array(rec["t"]), y=np.array(rec["y"]), reference=np.array(rec["r"]),
                      surfaces=np.array(rec["s"]), throttles=np.array(rec["thr"]),
                      mu=np.array(rec["mu"]) if self.controller == "spc" else np.zeros((len(rec["t"]), 0)),
                      configuration=np.array(rec["cfg"]), declared=self.declared, lost=self.lost, qp=dict(qp),
                      step_seconds=np.array(rec["sec"]), rcond=np.array(self.rcond), scenario=scenario,
                      controller=self.controller, timings=timings)


def fly_ftc(setup, scenario: str = "nominal", *, controller: str = "spc", reconfigure: bool = True,
            duration: float = 300.0, seed: int = 0, forgetting: float = FORGETTING, adapt: str = "after_switch",
            isolation: tuple | None = None, progress=None) -> FtcRun:
    """Fly the §6.5 plan with a fault scenario, by the FTC (SPC + IMM switching) or by the LQR autopilot.

    Parameters
    ----------
    setup : FtcSetup
        From :func:`fdikit.studies.hallouzi2008.b747_ftc.ftc_setup`.
    scenario : {"nominal", "elevator", "rudder", "bijlmer"}
    controller : {"spc", "autopilot"}
    reconfigure : bool, optional
        Switch the SPC configuration on isolation (default True; False keeps the nominal one).
    duration : float, optional
        [s] (default 300).
    seed : int, optional
        Turbulence and sensor-noise seed.
    forgetting : float, optional
        λ of the recursive predictor update (default the thesis's 0.995).
    adapt : {"after_switch", "always", "never"}, optional
        When the predictor is updated: only after a reconfiguration (default; the nominal predictor stays
        the identified one), always (the thesis), or never. The Bijlmerramp always adapts (no FDI:
        adaptation is how the SPC learns the fault).
    isolation : tuple of (str, float), optional
        ``(model name, time)``: switch to that fault model's configuration at that time instead of running the
        IMM (a known fault, to study the reconfiguration apart from the isolation); e.g.
        ``("rudder_lip_+25", 22.0)``, the thesis's isolation time.
    progress : callable, optional
        Called with the simulated time every 10 s.

    Returns
    -------
    FtcRun

    Raises
    ------
    ParameterError
        For an unknown scenario, controller, adaptation mode or isolation model, or λ outside (0, 1].

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_ftc import ftc_setup
    >>> run = fly_ftc(ftc_setup(calibration_seconds=30.0), "rudder", duration=40.0)  # doctest: +SKIP
    >>> run.declared[0]  # doctest: +SKIP
    'rudder'

    References
    ----------
    Hallouzi 2008, §6.2–§6.6.
    """
    from fdikit.ftc.multirate import MultiRate

    scenario_fault(scenario)
    validate.choice("controller", controller, ["spc", "autopilot"])
    validate.choice("adapt", adapt, ["after_switch", "always", "never"])
    forgetting = validate.in_range("forgetting", forgetting, 0.0, 1.0, closed="right")
    if isolation is not None:
        validate.choice("isolation model", isolation[0], [k[1] for k in setup.origins if k[0] != "nominal"])
    duration = validate.positive("duration", duration)
    flight = _Flight(setup, scenario, controller, reconfigure, seed, forgetting, adapt, isolation)
    ac = flight.ac
    mr = MultiRate(ac.dt)
    mr.add("fdi", 1, flight.fdi)
    mr.add("spc", flight.every, flight.control)
    mr.add("plant", 1, lambda tick, t: ac.step())
    for tick in range(int(round(duration / ac.dt))):
        mr.run(1)
        if flight.lost is not None:
            break
        if progress is not None and tick % 1000 == 0:
            progress(ac.time)
    return flight.result(scenario, mr.timings())
