"""The B747 fault-tolerant flights as a campaign: Hallouzi 2008, §6.5 on JSBSim, over seeds.

The campaign study ``b747-ftc`` (:mod:`fdikit.campaign`): every run is one flight of
:func:`fdikit.studies.hallouzi2008.b747_ftc_flight.fly_ftc` — JSBSim's B747 at the §4.3.1 point on the
§6.5.1 plan (hold, 120° turn from 75 s, descent from 150 s), Dryden turbulence, Table 6.2 sensor noise
(``thesis_std``, fixed by :func:`~fdikit.studies.hallouzi2008.b747_ftc.ftc_setup`) — with one of the §6.5
scenarios of :func:`~fdikit.studies.hallouzi2008.b747_ftc.scenario_fault`, flown by each design.

Plant ``params``: ``turbulence`` (MIL-F-8785C severity, default 3), ``calibration_seconds`` (the IMM's
process-noise flight, default 300 s) and ``identification_seed`` (the SPC start-up data, default 7).

Faults (fixed by the study; ``check`` refuses other sizes and onsets): kind ``lock`` on
``elevator_actuator`` at ``size`` 1.9 [deg] (§6.5.2) and kind ``runaway`` on ``rudder_actuator`` to ``size``
25 [deg] at 50°/s (§6.5.3), both with ``onset`` 18 s (:data:`~fdikit.studies.hallouzi2008.b747_ftc.T_INJECT`);
a fault-free run is the ``nominal`` scenario.  The Bijlmerramp (another flight condition, no FDI) is not a
campaign scenario; ``fdikit ftc`` flies it.

Designs — the controllers §6.5 compares: ``ftc`` (the closed-loop SPC reconfigured on the IMM's
declaration), ``spc-fixed`` (the same SPC and IMM, kept in the nominal configuration) — both take
``forgetting`` (0.995) and ``adapt`` (``after_switch``) — and ``autopilot`` (the fixed LQR autopilot, no
FDI).  Evaluator kind ``imm``: the FTC's own isolation (model set II + nominal, Table 4.7 with
``T_f = 0.2`` and the persistence of the §4.4.2 study, trusted near the design point, latched at the first
declaration; no parameters: they are the study's).

Rows.  The diagnosis is the latched declaration on the flight's 10-Hz record (alarm from the first record
at or after the declaration, naming ``<group>_actuator``), scored by :func:`fdikit.metrics.score` against
the truth (``none`` before the onset); so ``detection_delay`` is on the 0.1-s grid and
``metrics["isolation_time"]`` is the declaration's own time minus the onset.  The autopilot has no FDI:
its rows are those of a diagnosis that never alarms (a faulty run counts as missed) — read its rows for
the ``metrics``, not the detection columns.  ``metrics``: ``control_kept`` (1 unless the flight was lost:
``|φ| > 60°``, ``|θ| > 30°`` or ``h < 0``), ``lost_time``, ``declared_at`` [s], ``isolation_time`` [s],
``reconfigured`` (the SPC ended in a fault configuration), the tracking errors per phase of
:func:`~fdikit.studies.hallouzi2008.b747_ftc_report.flight_summary` from the onset on (``hold_altitude_max``
[m], ``hold_heading_max``, ``hold_pitch_rms``, ``hold_roll_rms``, ``hold_beta_rms`` [deg],
``hold_airspeed_rms`` [m/s]; ``turn_*``, ``descent_*`` when the flight gets there), the same errors from
:data:`LATE_START` to the end as ``late_*`` (the window of the 17-seed table of ``docs/methods/ftc.md``),
the largest surface deflections ``<surface>_max`` [deg] and ``qp_solved_share``.

Sweep columns: none — the declaration is one latched event gated on the flight phase, not the exceedance
of a statistic at a level; delays are NaN and false-alarm counts zero at every level, so the report's
trade-off curve is flat for ``imm``.

Reproducibility: every flight flies on a fresh JSBSim aircraft
(:func:`~fdikit.studies.hallouzi2008.b747_campaign.fresh_aircraft`; JSBSim's turbulence does not restart
exactly on a restore), the turbulence and noise seed is ``run.seed mod 2**31``; all designs of a run fly the
same seed.

References
----------
Hallouzi 2008, §6.2–§6.6, Tables 6.1–6.2; §4.4.2, Table 4.7.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["B747FtcStudy", "B747_FTC", "SCENARIO_FAULTS", "PLANT_PARAMS", "DESIGN_KINDS", "EVALUATOR_KINDS",
           "LATE_START", "ftc_diagnosis", "ftc_metrics"]

#: ``(kind, fault name)`` → ``(scenario, size, onset)`` of the §6.5 scenarios.
SCENARIO_FAULTS = {("lock", "elevator_actuator"): ("elevator", 1.9, 18.0),
                   ("runaway", "rudder_actuator"): ("rudder", 25.0, 18.0)}
#: Plant parameters and their defaults (those of ``fdikit ftc``).
PLANT_PARAMS = {"turbulence": 3, "calibration_seconds": 300.0, "identification_seed": 7}
#: Design kind → ``(controller, reconfigure)`` and the parameters with their defaults.
DESIGN_KINDS = {"ftc": (("spc", True), {"forgetting": 0.995, "adapt": "after_switch"}),
                "spc-fixed": (("spc", False), {"forgetting": 0.995, "adapt": "after_switch"}),
                "autopilot": (("autopilot", False), {})}
#: Evaluator kinds (no parameters).
EVALUATOR_KINDS = {"imm": {}}
#: Start [s] of the ``late_*`` error window (the seed table of docs/methods/ftc.md: 40–60 s).
LATE_START = 40.0


def ftc_diagnosis(run):
    """The FTC's latched IMM declaration of a flight as a :class:`~fdikit.diagnosis.Diagnosis` on its 10-Hz record.

    Parameters
    ----------
    run : FtcRun
        From :func:`~fdikit.studies.hallouzi2008.b747_ftc_flight.fly_ftc` (no declaration: never alarms).

    Returns
    -------
    Diagnosis
        One column ``imm``; ``isolated`` is ``<group>_actuator`` from the declaration on.

    References
    ----------
    Hallouzi 2008, §6.5 (the fault-tolerant flights), Table 6.1 (the input configurations).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_ftc import FtcRun
    >>> t = np.arange(4) * 0.1
    >>> z = np.zeros((4, 7))
    >>> run = FtcRun(t, z, z[:, :6], z[:, :4], z[:, :4], np.zeros((4, 8)), np.full(4, "nominal"),
    ...              ("rudder", "rudder_lip_+25", 0.15), None, {}, np.zeros(0), np.zeros(0), "rudder", "spc")
    >>> ftc_diagnosis(run).isolated.tolist()
    ['none', 'none', 'rudder_actuator', 'rudder_actuator']
    """
    from fdikit.diagnosis import Diagnosis

    t = np.asarray(run.t, dtype=float)
    alarm = np.zeros(t.size, bool)
    isolated = np.full(t.size, "none", dtype=object)
    if run.declared is not None:
        alarm = t >= run.declared[2] - 1e-9
        isolated[alarm] = f"{run.declared[0]}_actuator"
    probabilities = run.mu if run.mu.size else None
    return Diagnosis(t, alarm, alarm[:, None], ("imm",), isolated.astype(str), probabilities=probabilities,
                     hypotheses=tuple(f"model_{i + 1}" for i in range(run.mu.shape[1])) if run.mu.size else (),
                     meta={"evaluator": "imm", "latched": True})


def ftc_metrics(run, onset: float) -> dict:
    """The per-flight figures of the module docstring ("Rows").

    Parameters
    ----------
    run : FtcRun
    onset : float
        The fault's onset [s]; NaN for a nominal flight (errors then from 0 s).

    Returns
    -------
    dict of str to float

    References
    ----------
    Hallouzi 2008, §6.5 (the fault-tolerant flights), Table 6.1 (the input configurations).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_ftc import FtcRun
    >>> t = np.arange(4) * 0.1
    >>> z = np.zeros((4, 7))
    >>> run = FtcRun(t, z, z[:, :6], z[:, :4], z[:, :4], np.zeros((4, 0)), np.full(4, "autopilot"), None, None,
    ...              {}, np.zeros(0), np.zeros(0), "nominal", "autopilot")
    >>> m = ftc_metrics(run, float("nan"))
    >>> m["control_kept"], m["hold_altitude_max"], "late_pitch_rms" in m
    (1.0, 0.0, False)
    """
    from fdikit.studies.hallouzi2008.b747_ftc_report import flight_summary

    healthy = not np.isfinite(onset)
    start = 0.0 if healthy else float(onset)
    summary = flight_summary(run, start)
    out = {"control_kept": float(run.lost is None), "lost_time": math.nan if run.lost is None else float(run.lost),
           "declared_at": math.nan if run.declared is None else float(run.declared[2])}
    out["isolation_time"] = math.nan if healthy else out["declared_at"] - start
    cfg = np.asarray(run.configuration).astype(str)
    out["reconfigured"] = float(cfg.size > 0 and cfg[-1] not in ("nominal", "autopilot"))
    for phase in ("hold", "turn", "descent"):
        for k, v in summary.get(phase, {}).items():
            out[f"{phase}_{k}"] = float(v)
    if run.t.size and run.t[-1] >= LATE_START:
        for k, v in run.errors(max(LATE_START, start)).items():
            out[f"late_{k}"] = float(v)
    for k, v in summary["surface_max"].items():
        out[f"{k}_max"] = float(v)
    total = sum(run.qp.values())
    if total:
        out["qp_solved_share"] = run.qp.get("solved", 0) / total
    return out


class B747FtcStudy:
    """The ``b747-ftc`` campaign study (module docstring).

    References
    ----------
    Hallouzi 2008, §6.5 (the fault-tolerant flights), Table 6.1 (the input configurations).

    Examples
    --------
    >>> B747_FTC.fault_names(None, "runaway")
    ('rudder_actuator',)
    """

    name = "b747-ftc"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """The fault of each kind the §6.5 scenarios have (``lock``: the elevator, ``runaway``: the rudder)."""
        return tuple(f for k, f in SCENARIO_FAULTS if k == kind)

    def check(self, spec) -> list[str]:
        """Problems with the spec's plant parameters, faults, designs and evaluators."""
        problems = []
        for k, plant in enumerate(spec.plants):
            if plant.kind not in (None, "b747"):
                problems.append(f"plants.{k}.kind: unknown plant {plant.kind!r}; b747-ftc flies 'b747' (the §4.3.1 "
                                "point)")
            for p, v in plant.params.items():
                where = f"plants.{k}.params.{p}"
                if p not in PLANT_PARAMS:
                    problems.append(f"{where}: unknown parameter; b747-ftc takes: {', '.join(PLANT_PARAMS)} (the "
                                    "sensor noise is Table 6.2's, fixed by ftc_setup)")
                elif p == "turbulence" and not (isinstance(v, int) and 0 <= v <= 7):
                    problems.append(f"{where}: MIL-F-8785C severity must be an integer 0-7, got {v!r}")
                elif p == "calibration_seconds" and not (isinstance(v, int | float) and v > 0):
                    problems.append(f"{where}: must be > 0 s, got {v!r}")
                elif p == "identification_seed" and not (isinstance(v, int) and v >= 0):
                    problems.append(f"{where}: must be an integer >= 0, got {v!r}")
        kinds = sorted({k for k, _ in SCENARIO_FAULTS})
        for k, fam in enumerate(spec.faults):
            if fam.kind not in kinds:
                problems.append(f"faults.{k}.kind: unknown fault kind {fam.kind!r}; b747-ftc has: {', '.join(kinds)}")
                continue
            targets = self.fault_names(None, fam.kind) if fam.targets == "all" else fam.targets
            for t in targets:
                if (fam.kind, t) not in SCENARIO_FAULTS:
                    problems.append(f"faults.{k}.targets: {fam.kind} {t!r} is not a §6.5 scenario; {fam.kind} has: "
                                    f"{', '.join(self.fault_names(None, fam.kind))}")
                    continue
                _, size, onset = SCENARIO_FAULTS[(fam.kind, t)]
                if fam.size.values is None or any(abs(s - size) > 1e-9 for s in fam.size.values):
                    problems.append(f"faults.{k}.size: the §6.5 {fam.kind} of {t} is fixed at {size:g} deg; give "
                                    f"size: {{values: [{size:g}]}}")
                if fam.onset.values is None or any(abs(o - onset) > 1e-9 for o in fam.onset.values):
                    problems.append(f"faults.{k}.onset: the §6.5 faults start at {onset:g} s; give "
                                    f"onset: {{values: [{onset:g}]}}")
        for k, d in enumerate(spec.designs):
            kind = d.kind or d.name
            if kind not in DESIGN_KINDS:
                problems.append(f"designs.{k}.kind: unknown design {kind!r}; choose from: {', '.join(DESIGN_KINDS)}")
                continue
            allowed = DESIGN_KINDS[kind][1]
            for p, v in d.params.items():
                where = f"designs.{k}.params.{p}"
                if p not in allowed:
                    problems.append(f"{where}: unknown parameter; {kind} takes: {', '.join(allowed) or 'none'}")
                elif p == "forgetting" and not (isinstance(v, int | float) and 0 < v <= 1):
                    problems.append(f"{where}: λ must be in (0, 1], got {v!r}")
                elif p == "adapt" and v not in ("after_switch", "always", "never"):
                    problems.append(f"{where}: {v!r}; choose from: after_switch, always, never")
        for k, e in enumerate(spec.evaluators):
            kind = e.kind or e.name
            if kind not in EVALUATOR_KINDS:
                problems.append(f"evaluators.{k}.kind: unknown evaluator {kind!r}; choose from: "
                                f"{', '.join(EVALUATOR_KINDS)}")
            elif e.params:
                problems.append(f"evaluators.{k}.params: {kind} takes no parameters (the study's persistence and "
                                "T_f), got " + ", ".join(e.params))
        return problems

    def setup(self, spec) -> dict:
        """Per plant: the :class:`~fdikit.studies.hallouzi2008.b747_ftc.FtcSetup` (aircraft, IMM, SPC data)."""
        from fdikit.studies.hallouzi2008.b747_ftc import ftc_setup

        setups = {}
        for plant in spec.plants:
            pp = {**PLANT_PARAMS, **plant.params}
            setups[plant.name] = ftc_setup(turbulence=int(pp["turbulence"]),
                                           calibration_seconds=float(pp["calibration_seconds"]),
                                           seed=int(pp["identification_seed"]))
        return {"ftc": setups}

    def fly(self, setup, spec, run, design: str):
        """The run's flight by ``design`` on a fresh aircraft.

        Returns
        -------
        FtcRun
        """
        from fdikit.studies.hallouzi2008.b747_campaign import flight_seed, fresh_aircraft
        from fdikit.studies.hallouzi2008.b747_ftc_flight import fly_ftc

        ftc = setup["ftc"][run.plant]
        d = next(x for x in spec.designs if x.name == design)
        (controller, reconfigure), defaults = DESIGN_KINDS[d.kind or d.name]
        params = {**defaults, **d.params}
        scenario = "nominal" if run.healthy else SCENARIO_FAULTS[(run.kind, run.fault)][0]
        fresh_aircraft(ftc.lip)
        return fly_ftc(ftc, scenario, controller=controller, reconfigure=reconfigure, duration=spec.duration,
                       seed=flight_seed(run.seed), **params)

    @staticmethod
    def _truth(run, t) -> np.ndarray:
        truth = np.full(t.size, "none", dtype=object)
        if not run.healthy:
            truth[t >= run.onset] = run.fault
        return truth.astype(str)

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """Rows of the runs: one flight per run × design, scored for every evaluator (module docstring)."""
        from fdikit.campaign.rows import score_row
        from fdikit.metrics import score

        rows = []
        nan, zero = [math.nan] * len(levels), [0] * len(levels)
        for run in runs:
            for d in spec.designs:
                flight = self.fly(setup, spec, run, d.name)
                s = score(self._truth(run, flight.t), ftc_diagnosis(flight))
                metrics = ftc_metrics(flight, run.onset)
                for e in spec.evaluators:
                    rows.append(score_row(run, d.name, e.name, s, nan, zero, metrics))
        return rows

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)``: the flight as a Trace (surfaces [rad] in, the seven SPC outputs in
        SI out), the mode probabilities as residuals (the autopilot: the altitude [m] and heading [rad] errors)."""
        from fdikit.residuals import Residuals
        from fdikit.trace import Trace

        flight = self.fly(setup, spec, run, design)
        t = flight.t
        y = flight.y.copy()
        y[:, [0, 1, 2, 4, 5]] = np.radians(y[:, [0, 1, 2, 4, 5]])
        trace = Trace(t=t, u=np.radians(flight.surfaces), y=y, controls=("aileron", "elevator", "stabilizer", "rudder"),
                      outputs=("roll", "pitch", "heading", "true_airspeed", "alpha", "beta", "altitude"),
                      fault=self._truth(run, t), meta={"study": self.name, "run": run.run, "design": design})
        if flight.mu.size:
            from fdikit.multimodel.isolation import table_4_7_logic

            groups = {i: g for g, idx in table_4_7_logic(0.2).groups.items() for i in idx}
            names = tuple(m.name for m in setup["ftc"][run.plant].lip.models)
            isolates = tuple(f"{groups[i]}_actuator" if i in groups else None for i in range(len(names)))
            residuals = Residuals(t, flight.mu, names, isolates, meta={"what": "IMM mode probabilities"})
        else:
            dpsi = np.radians((flight.y[:, 2] - flight.reference[:, 4] + 180.0) % 360.0 - 180.0)
            err = np.column_stack([flight.y[:, 6] - flight.reference[:, 5], dpsi])
            residuals = Residuals(t, err, ("altitude_error", "heading_error"), (None, None),
                                  meta={"what": "tracking errors (no FDI)"})
        return trace, residuals, ftc_diagnosis(flight)


#: The registered study object.
B747_FTC = B747FtcStudy()
