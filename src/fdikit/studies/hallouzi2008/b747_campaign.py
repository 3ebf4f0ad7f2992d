"""The B747 lock-in-place isolation study as a campaign: Hallouzi 2008, §4.4.2 (Table 4.8) on JSBSim.

The campaign study ``b747-lip`` (:mod:`fdikit.campaign`): every run is one closed-loop flight of
:func:`fdikit.studies.hallouzi2008.b747_lip.fly_lip` — JSBSim's B747 at the §4.3.1 point, the LQR
autopilot, Dryden turbulence, sensor noise of a preset — with a lock-in-place (LIP) of one surface at
the run's onset, or none; the IMM of model set II plus the nominal model (Table 4.5) weighs the models,
the Table 4.7 logic (``T_f = 0.2``) with the study's persistence declares the fault.

Plant ``params`` (the flight condition is the §4.3.1 point of
:func:`~fdikit.studies.hallouzi2008.aircraft_models.b747_at_point`):

``noise``
    ``thesis_cov`` (default: (4.4) read as covariances) or ``thesis_std`` (Table 6.2 as standard
    deviations), :data:`fdikit.studies.hallouzi2008.b747_lip.NOISE_PRESETS`.
``turbulence``
    MIL-F-8785C severity 0–7 (default 3, light).
``calibration_seconds``, ``calibration_seed``
    The fault-free flight the IMM's process noise is identified on (default 300 s, seed 10000, as
    ``fdikit b747``).

Fault kind ``lock`` (:class:`~fdikit.actuator_faults.LockInPlace`; the study has no runaway): targets
``elevator_actuator``, ``aileron_actuator``, ``rudder_actuator`` (``targets: all``); ``size`` is the lock
position [deg], within the surface's App. A limits; ``onset`` the injection time (§4.4.2: 20 s).  The
Table 4.8 sweep is ``size: {values: [...]}`` with the 0.5° grid of
:func:`~fdikit.studies.hallouzi2008.table_4_8.lock_positions` (the shipped ``b747-lip.yaml``).

Design kind ``model-set-ii``: the IMM of :func:`~fdikit.studies.hallouzi2008.b747_lip.lip_setup`, params
``q_inflation`` (4), ``to_fault`` (1e-3), ``measured`` (``table_6_2``).  Evaluator kind ``table-4-7``:
the Table 4.7 logic with ``T_f = 0.2`` and the persistence of the study, params ``confirm`` (2 s) and
``share`` (0.75).  A second evaluator flies the run again (the declarations come out of the flight).

Rows.  The diagnosis is the study's confirmed declaration per sample (:attr:`LipRun.declared`, each
group named ``<surface>_actuator``, ``unknown`` kept), scored by :func:`fdikit.metrics.score` against
the truth (``none`` before the onset, the locked surface after).  ``metrics`` holds the study's own
per-run figures (:mod:`~fdikit.studies.hallouzi2008.table_4_8`): the outcome as 0/1 flags
``correct``, ``incorrect``, ``missed``, ``false_alarm`` (:attr:`LipRun.outcome`; a fault-free run has
only ``false_alarm``), ``isolation_time`` (onset to the first declaration, NaN when none — Table 4.8's
delay where the outcome is correct), ``study_false_alarms`` (declarations before the onset),
``final_correct`` (the declaration at the end names the surface) and ``position_at_injection`` [deg].

Sweep columns: the decision statistic is the share-of-window order statistic of the nominal model's
deficit, ``s_k`` = the ``⌈share·n⌉``-th largest of ``(1 − μ_nominal)/T_f`` over the last ``n = confirm/dt``
samples (0 while fewer samples exist): ``s_k > λ`` exactly when the Table 4.7 "not nominal" test at
``λ·T_f`` held in the persistence's share of the window.  At ``λ = 1`` it fires at or before the row's
declaration (the declaration also needs the *same* group to hold), so the trade-off curve is that of
the persistent any-fault alarm, the detection part of the study's rule.

Reproducibility.  JSBSim's turbulence does not restart exactly on a snapshot restore: two flights of
the same seed on one aircraft differ by about 1 cm in altitude and 5e-3 in μ after 5 s (measured; no
turbulence: identical).  Every run therefore flies on a fresh JSBSim aircraft restored to the setup's
trim (:func:`fresh_aircraft`, 20–50 ms), which makes a run's row a function of the spec and its index
alone — the engine's bit-identity across workers — and equal to ``fly_lip`` on a fresh aircraft.
The turbulence and noise seed of a run is ``run.seed mod 2**31`` (JSBSim's ``randomseed`` is a C int).

References
----------
Hallouzi 2008, §4.3.1, §4.4.2, Tables 4.5, 4.7, 4.8, (4.4), App. A; Table 6.2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["B747LipStudy", "B747_LIP", "FAULT_NAMES", "FAULT_KINDS", "PLANT_PARAMS", "DESIGN_KINDS",
           "EVALUATOR_KINDS", "T_F", "fresh_aircraft", "flight_seed", "lip_diagnosis", "lip_statistic",
           "lip_metrics"]

#: Fault name → the surface of :func:`~fdikit.studies.hallouzi2008.b747_lip.fly_lip` (and the Table 4.7 group).
FAULT_NAMES = {"elevator_actuator": "elevator", "aileron_actuator": "aileron", "rudder_actuator": "rudder"}
#: Fault kinds of the study.
FAULT_KINDS = ("lock",)
#: Plant parameters and their defaults (those of ``fdikit b747``).
PLANT_PARAMS = {"noise": "thesis_cov", "turbulence": 3, "calibration_seconds": 300.0, "calibration_seed": 10_000}
#: Design kind → parameters and defaults (:func:`~fdikit.studies.hallouzi2008.b747_lip.lip_setup`).
DESIGN_KINDS = {"model-set-ii": {"q_inflation": 4.0, "to_fault": 1e-3, "measured": "table_6_2"}}
#: Evaluator kind → parameters and defaults.
EVALUATOR_KINDS = {"table-4-7": {"confirm": 2.0, "share": 0.75}}
#: The Table 4.7 threshold of the study.
T_F = 0.2


def fresh_aircraft(setup) -> None:
    """Give a LIP set-up a new JSBSim B747 at its trim (``setup.start``), for a flight that repeats exactly.

    Parameters
    ----------
    setup : LipSetup
        Modified in place: ``setup.aircraft`` is replaced.

    Examples
    --------
    >>> fresh_aircraft(lip_setup(calibration_seconds=20.0))  # doctest: +SKIP

    References
    ----------
    Hallouzi 2008, §4.4.2 (the flights); module docstring (why).
    """
    from fdikit.aircraft import JSBSimAircraft

    ac = JSBSimAircraft("B747", dt=setup.aircraft.dt)
    ac.restore(setup.start)
    setup.aircraft = ac


def flight_seed(seed: int) -> int:
    """The turbulence and noise seed of a run: its plan seed modulo ``2**31`` (JSBSim's seed is a C int).

    Parameters
    ----------
    seed : int
        :attr:`fdikit.campaign.plan.RunPlan.seed`.

    Returns
    -------
    int

    References
    ----------
    Hallouzi 2008, §4.4 (the Table 4.8 lock-in-place sweep), Table 4.7 (the isolation logic).

    Examples
    --------
    >>> flight_seed(2**31 + 5)
    5
    """
    return int(seed) % 2**31


def lip_diagnosis(run):
    """The study's confirmed declarations of a flight as a :class:`~fdikit.diagnosis.Diagnosis`.

    Parameters
    ----------
    run : LipRun
        From :func:`~fdikit.studies.hallouzi2008.b747_lip.fly_lip`.

    Returns
    -------
    Diagnosis
        ``fired`` per fault group (``elevator_actuator``, ``aileron_actuator``, ``rudder_actuator``),
        ``isolated`` the declared fault name (``unknown`` kept), the mode probabilities as
        ``probabilities``.

    References
    ----------
    Hallouzi 2008, §4.4 (the Table 4.8 lock-in-place sweep), Table 4.7 (the isolation logic).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_lip import LipRun
    >>> t = np.arange(4) * 0.01
    >>> run = LipRun(t, np.full((4, 8), 0.125), np.array(["none", "rudder", "rudder", "unknown"]), "rudder", 5.0,
    ...              ("rudder", 0.0), 0, np.zeros(4), np.zeros(4))
    >>> lip_diagnosis(run).isolated.tolist()
    ['none', 'rudder_actuator', 'rudder_actuator', 'unknown']
    """
    from fdikit.diagnosis import Diagnosis

    names = tuple(FAULT_NAMES)
    declared = np.asarray(run.declared).astype(str)
    to_name = {g: f for f, g in FAULT_NAMES.items()}
    isolated = np.array([to_name.get(d, d) for d in declared], dtype=object).astype(str)
    fired = np.column_stack([declared == FAULT_NAMES[f] for f in names])
    return Diagnosis(run.t, declared != "none", fired, names, isolated, probabilities=run.mu,
                     hypotheses=tuple(f"model_{i + 1}" for i in range(run.mu.shape[1])),
                     meta={"evaluator": "table-4-7", "threshold": T_F})


def lip_statistic(mu, confirm_samples: int, share: float) -> np.ndarray:
    """The sweep statistic: the ``⌈share·n⌉``-th largest ``(1 − μ_nominal)/T_f`` of the last ``n`` samples.

    Parameters
    ----------
    mu : (N, M) array_like
        Mode probabilities, the nominal model last.
    confirm_samples : int
        ``n``, the persistence window in samples.
    share : float
        Share of the window, in (0.5, 1].

    Returns
    -------
    (N,) ndarray
        0 while the window holds fewer than ``⌈share·n⌉`` samples.

    References
    ----------
    Hallouzi 2008, §4.4 (the Table 4.8 lock-in-place sweep), Table 4.7 (the isolation logic).

    Examples
    --------
    >>> mu = np.array([[0.0, 1.0], [0.5, 0.5], [0.8, 0.2], [0.0, 1.0]])
    >>> lip_statistic(mu, 2, 1.0).round(6).tolist()
    [0.0, 0.0, 2.5, 0.0]
    """
    deficit = np.abs(1.0 - np.asarray(mu, dtype=float)[:, -1]) / T_F
    n = max(1, int(confirm_samples))
    k = max(1, int(math.ceil(share * n)))
    padded = np.concatenate([np.full(n - 1, -np.inf), deficit])
    windows = np.lib.stride_tricks.sliding_window_view(padded, n)
    out = np.partition(windows, n - k, axis=1)[:, n - k]
    return np.where(np.isfinite(out), out, 0.0)


def lip_metrics(run, onset: float) -> dict:
    """The study's per-run figures of a flight (module docstring, "Rows").

    Parameters
    ----------
    run : LipRun
    onset : float
        Injection time [s] (NaN for a fault-free flight).

    Returns
    -------
    dict of str to float

    References
    ----------
    Hallouzi 2008, §4.4 (the Table 4.8 lock-in-place sweep), Table 4.7 (the isolation logic).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.b747_lip import LipRun
    >>> t = np.arange(4) * 0.01
    >>> run = LipRun(t, np.zeros((4, 8)), np.array(["none", "none", "rudder", "rudder"]), "rudder", 5.0,
    ...              ("rudder", 0.01), 0, np.array([0.0, 1.0, 5.0, 5.0]), np.zeros(4))
    >>> m = lip_metrics(run, 0.01)
    >>> m["correct"], m["isolation_time"], m["position_at_injection"]
    (1.0, 0.01, 1.0)
    """
    out = {"false_alarm": float(run.false_alarms > 0), "study_false_alarms": float(run.false_alarms)}
    if run.surface is None:
        return out
    outcome = run.outcome
    for o in ("correct", "incorrect", "missed"):
        out[o] = float(outcome == o)
    out["false_alarm"] = float(outcome == "false alarm")
    out["isolation_time"] = float(run.first[1])
    out["final_correct"] = float(str(run.declared[-1]) == run.surface)
    k0 = min(int(np.searchsorted(run.t, onset)), run.t.size - 1)
    out["position_at_injection"] = float(run.positions[k0])
    return out


def _params(named, table) -> dict:
    return {**table[named.kind or named.name], **named.params}


class B747LipStudy:
    """The ``b747-lip`` campaign study (module docstring).

    References
    ----------
    Hallouzi 2008, §4.4 (the Table 4.8 lock-in-place sweep), Table 4.7 (the isolation logic).

    Examples
    --------
    >>> B747_LIP.fault_names(None, "lock")
    ('elevator_actuator', 'aileron_actuator', 'rudder_actuator')
    """

    name = "b747-lip"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """The three surfaces of §4.4.2 as fault names (any plant)."""
        return tuple(FAULT_NAMES)

    def check(self, spec) -> list[str]:
        """Problems with the spec's plant parameters, faults, designs and evaluators."""
        from fdikit.aircraft import B747_LIMITS
        from fdikit.studies.hallouzi2008.b747_lip import NOISE_PRESETS

        problems = []
        for k, plant in enumerate(spec.plants):
            if plant.kind not in (None, "b747"):
                problems.append(f"plants.{k}.kind: unknown plant {plant.kind!r}; b747-lip flies 'b747' (the §4.3.1 "
                                "point)")
            for p, v in plant.params.items():
                where = f"plants.{k}.params.{p}"
                if p not in PLANT_PARAMS:
                    problems.append(f"{where}: unknown parameter; b747-lip takes: {', '.join(PLANT_PARAMS)}")
                elif p == "noise" and v not in NOISE_PRESETS:
                    problems.append(f"{where}: {v!r} is not a noise preset; choose from: {', '.join(NOISE_PRESETS)}")
                elif p == "turbulence" and not (isinstance(v, int) and 0 <= v <= 7):
                    problems.append(f"{where}: MIL-F-8785C severity must be an integer 0-7, got {v!r}")
                elif p == "calibration_seconds" and not (isinstance(v, int | float) and v > 0):
                    problems.append(f"{where}: must be > 0 s, got {v!r}")
                elif p == "calibration_seed" and not (isinstance(v, int) and v >= 0):
                    problems.append(f"{where}: must be an integer >= 0, got {v!r}")
        for k, fam in enumerate(spec.faults):
            if fam.kind not in FAULT_KINDS:
                problems.append(f"faults.{k}.kind: unknown fault kind {fam.kind!r}; b747-lip has: "
                                f"{', '.join(FAULT_KINDS)} (lock-in-place)")
            targets = list(FAULT_NAMES) if fam.targets == "all" else fam.targets
            for t in targets:
                if t not in FAULT_NAMES:
                    hint = f" (the fault name is {t}_actuator)" if f"{t}_actuator" in FAULT_NAMES else ""
                    problems.append(f"faults.{k}.targets: unknown fault {t!r}{hint}; choose from: "
                                    f"{', '.join(FAULT_NAMES)}")
                    continue
                lim = B747_LIMITS[FAULT_NAMES[t]]
                lo, hi = math.degrees(lim.lower), math.degrees(lim.upper)
                sizes = fam.size.values or fam.size.uniform or fam.size.loguniform
                bad = [s for s in sizes if not lo - 1e-9 <= s <= hi + 1e-9]
                if bad:
                    problems.append(f"faults.{k}.size: lock position {bad[0]} deg of {t} is outside its App. A range "
                                    f"[{lo:g}, {hi:g}] deg")
            onsets = fam.onset.values or fam.onset.uniform or fam.onset.loguniform
            if min(onsets) < 0:
                problems.append(f"faults.{k}.onset: must be >= 0 s, got {min(onsets)}")
        problems += self._check_named(spec.designs, "designs", DESIGN_KINDS)
        problems += self._check_named(spec.evaluators, "evaluators", EVALUATOR_KINDS)
        return problems

    @staticmethod
    def _check_named(entries, what, kinds) -> list[str]:
        problems = []
        for k, d in enumerate(entries):
            kind = d.kind or d.name
            if kind not in kinds:
                problems.append(f"{what}.{k}.kind: unknown {what[:-1]} {kind!r}; choose from: {', '.join(kinds)}")
                continue
            for p, v in d.params.items():
                where = f"{what}.{k}.params.{p}"
                if p not in kinds[kind]:
                    problems.append(f"{where}: unknown parameter; {kind} takes: {', '.join(kinds[kind])}")
                elif p == "measured" and v not in ("table_6_2", "section_4_4_1"):
                    problems.append(f"{where}: {v!r}; choose from: table_6_2, section_4_4_1")
                elif p in ("q_inflation", "confirm") and not (isinstance(v, int | float) and v > 0):
                    problems.append(f"{where}: must be > 0, got {v!r}")
                elif p == "to_fault" and not (isinstance(v, int | float) and 0 <= v <= 0.1):
                    problems.append(f"{where}: must be in [0, 0.1] per sample, got {v!r}")
                elif p == "share" and not (isinstance(v, int | float) and 0.5 < v <= 1):
                    problems.append(f"{where}: must be in (0.5, 1], got {v!r}")
        return problems

    # ------------------------------------------------------------------ set-up (once per worker)
    def setup(self, spec) -> dict:
        """Per plant × design: the :class:`~fdikit.studies.hallouzi2008.b747_lip.LipSetup` (trim, model set II,
        identified process noise, IMM)."""
        from fdikit.studies.hallouzi2008.b747_lip import lip_setup

        setups = {}
        for plant in spec.plants:
            pp = {**PLANT_PARAMS, **plant.params}
            for d in spec.designs:
                dp = _params(d, DESIGN_KINDS)
                setups[(plant.name, d.name)] = lip_setup(
                    noise=pp["noise"], turbulence=int(pp["turbulence"]), q_inflation=float(dp["q_inflation"]),
                    to_fault=float(dp["to_fault"]), measured=dp["measured"],
                    calibration_seconds=float(pp["calibration_seconds"]), calibration_seed=int(pp["calibration_seed"]))
        return {"lip": setups}

    # ------------------------------------------------------------------ runs
    def fly(self, setup, spec, run, design: str, evaluator: str):
        """The run's flight (:func:`~fdikit.studies.hallouzi2008.b747_lip.fly_lip`) on a fresh aircraft.

        Returns
        -------
        LipRun
        """
        from fdikit.studies.hallouzi2008.b747_lip import fly_lip

        lip = setup["lip"][(run.plant, design)]
        ep = _params(next(e for e in spec.evaluators if e.name == evaluator), EVALUATOR_KINDS)
        lip.confirm, lip.share = float(ep["confirm"]), float(ep["share"])
        fresh_aircraft(lip)
        seed = flight_seed(run.seed)
        if run.healthy:
            return fly_lip(lip, None, seed=seed, duration=spec.duration, t_fault=np.inf)
        return fly_lip(lip, FAULT_NAMES[run.fault], float(run.size), seed=seed, duration=spec.duration,
                       t_fault=float(run.onset))

    def _truth(self, run, t) -> np.ndarray:
        truth = np.full(t.size, "none", dtype=object)
        if not run.healthy:
            truth[t >= run.onset] = run.fault
        return truth.astype(str)

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """Rows of the runs: one flight per run × design × evaluator, scored as the module docstring says."""
        from fdikit.batch import crossings
        from fdikit.campaign.rows import score_row
        from fdikit.metrics import score

        rows = []
        for run in runs:
            for d in spec.designs:
                for e in spec.evaluators:
                    flight = self.fly(setup, spec, run, d.name, e.name)
                    lip = setup["lip"][(run.plant, d.name)]
                    s = score(self._truth(run, flight.t), lip_diagnosis(flight))
                    n = max(1, int(round(lip.confirm / lip.aircraft.dt)))
                    stat = lip_statistic(flight.mu, n, lip.share)
                    cross = crossings(stat[None], flight.t, [math.nan if run.healthy else run.onset], levels=levels)
                    rows.append(score_row(run, d.name, e.name, s, cross.delay[0], cross.upcrossings[0],
                                          lip_metrics(flight, run.onset)))
        return rows

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)``: the flight as a Trace (the locked surface's position [rad] as
        input, altitude as output), the mode probabilities as residuals, the declarations."""
        from fdikit.residuals import Residuals
        from fdikit.trace import Trace

        flight = self.fly(setup, spec, run, design, evaluator)
        n = flight.t.size
        surface = FAULT_NAMES.get(run.fault, "none")
        pos = np.radians(flight.positions) if flight.positions.size else np.zeros(n)
        trace = Trace(t=flight.t, u=pos[:, None], y=flight.altitude[:, None], controls=(f"{surface}_position",),
                      outputs=("altitude",), fault=self._truth(run, flight.t),
                      meta={"study": self.name, "run": run.run, "seed": flight_seed(run.seed)})
        from fdikit.multimodel.isolation import table_4_7_logic

        groups = {i: g for g, idx in table_4_7_logic(T_F).groups.items() for i in idx}
        lip = setup["lip"][(run.plant, design)]
        names = tuple(m.name for m in lip.models)
        isolates = tuple(f"{groups[i]}_actuator" if i in groups else None for i in range(len(names)))
        residuals = Residuals(flight.t, flight.mu, names, isolates, meta={"what": "IMM mode probabilities"})
        return trace, residuals, lip_diagnosis(flight)


#: The registered study object.
B747_LIP = B747LipStudy()
