"""The Monte-Carlo parts of ``fdikit multiple-model`` as one campaign study (Hallouzi 2008, §2.4.1, §3.3.1, §3.6.2).

The campaign study ``multiple-model`` (:mod:`fdikit.campaign`) runs, per plant kind, the existing study code
with the run's plan seed; one row per run × design × evaluator of the run's plant kind (designs and
evaluators belong to a plant kind, below, and only those of the run's kind give rows).

In the campaign
---------------
``b747`` — §2.4.1, Table 2.6 (item 18): run = one trajectory of
:func:`~fdikit.studies.hallouzi2008.b747.b747_monte_carlo` (``runs=1, seed=<plan seed>``, 1000 samples,
the four partial faults of Table 2.6 in sequence, always all four: the schedule is fixed by the plant).  The
plan's fault picks the **window** the row's diagnosis is scored on: a fault (``alpha_sensor``,
``delta_s_loss``, ``delta_c_loss``, ``V_TAS_sensor``; kind ``table-2.6``) → from the end of the previous fault
interval (or sample 0) to the end of its own, the row's ``size`` / ``onset`` being Table 2.6's (0.3 … , 2.0 …
8.0 s); fault-free (``healthy``) → the first nominal interval, samples 0–199.  Designs ``dual_cmf``
(``lam`` 0.85, ``prior_std`` 0.3), ``ekf`` (``q_mu`` 1e-2), ``imm``.  Evaluators: ``most-probable`` — the most
probable model (:func:`~fdikit.multimodel.isolation.mode_diagnosis`, (2.7)); no threshold, so the sweep
columns are NaN / 0 and its trade-off curve is flat; ``weight-threshold`` — Table 4.7's logic with each fault
model its own group (``threshold`` T_f, default 0.2): the alarm is ``|1 − μ_nominal| ≥ T_f``, so the sweep
statistic is ``|1 − μ_nominal| / T_f`` (:func:`fdikit.batch.crossings`).  Metrics: the study's per-interval
``state_rmse_<i>`` / ``weights_rmse_<i>`` of the run alone and ``state_mse_<i>`` / ``weights_mse_<i>``
(whose mean over runs is the interval mean of the squared Monte-Carlo RMSE (2.64)).

``msd`` — §3.6.2, Table 3.3 (item 20): run = :func:`~fdikit.studies.hallouzi2008.msd.simulate_msd` at the
plan seed (100 s at ``dt`` = 0.01 s, the command's default, 60 dB SNR), filtered by the augmented EKF on the
design's model set (:func:`~fdikit.studies.hallouzi2008.msd_model_sets.run_msd_model_set`: ``od``, ``cp``,
``lv``; ``q_x``, ``q_mu``, ``grid_levels``).  Deviation from the thesis's single run with both faults: a
campaign run carries one fault — ``u1_actuator`` (f1, on [30, 50) s) or ``x2_sensor`` (f2, on [70, 80) s),
kind ``loss``, ``size`` = the lost fraction ``1 − f`` (thesis 0.5), the other fault healthy — or none, so that
detection and false alarms are counted per fault; onsets are the study's (30 s, 70 s; the row holds them).
The thesis reads the faults off the reconstructed ``f̂1``, ``f̂2`` (Fig. 3.9) without a decision rule;
evaluator ``fault-size`` is fdikit's: a fault is named when its reconstructed loss ``1 − f̂`` exceeds
``threshold`` (default 0.25, half the thesis's fault), the larger loss isolated, nothing during the first
``skip`` s (default 5: the weights' start-up); sweep statistic ``max(1 − f̂) / threshold``.  Metrics:
``vaf_<state>`` (Table 3.3), ``f1_fault_mean``, ``f2_fault_mean`` (mean ``f̂`` over the fault intervals),
``k1_rmse``, ``m3_rmse`` (after ``skip``).

``example-3-1`` — §3.3.1, Table 3.1 (item 19): run = one random model set,
``example_3_1(model_sets=1, seed=<plan seed>)``; design ``pairs``, evaluator ``conditioning`` (no decision:
the detection and sweep columns are empty, ``fault_free_hours = 0``).  Metrics: ``observability_<q><r>``,
``basis_<q><r>`` per pair, and the pattern indicators of :meth:`Example31Result.frequency` for the one set,
whose means over runs are that method's fractions.  The command draws its 15 sets in sequence from one
stream (with redraws), the campaign each from its own seed: the same distribution, not the same sets.
Example-3-1 runs are the plan's fault-free runs (``healthy``); it has no faults.

Not in the campaign
-------------------
Item 17 (target tracking) is the ``target-tracking`` study (:mod:`~fdikit.studies.hallouzi2008.tracking_campaign`).
Table 3.4 (§3.6.4, OD vs minimum mismatch) is a conditioning comparison whose ratio is deterministic (16.17 in
every realization): no diagnosis and nothing a campaign would count.

Plants take no parameters except ``msd``: ``dt`` (default 0.01, at most 0.02) and ``snr_db`` (60).  The spec's
``duration`` is the MSD run length (the B747 run is the study's 1000 samples, Example 3.1 its 300 steps).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

__all__ = ["MultipleModelStudy", "MULTIPLE_MODEL", "DESIGN_KINDS", "EVALUATOR_KINDS", "FAULT_KINDS",
           "PLANT_KINDS", "b747_window"]

#: Plant kind → its parameters and defaults.
PLANT_KINDS = {"b747": {}, "msd": {"dt": 0.01, "snr_db": 60.0}, "example-3-1": {}}
#: Design kind → (plant kind, parameters and defaults).
DESIGN_KINDS = {
    "dual_cmf": ("b747", {"lam": 0.85, "prior_std": 0.3}), "ekf": ("b747", {"q_mu": 1e-2}), "imm": ("b747", {}),
    "od": ("msd", {"q_x": 3e-6, "q_mu": 1e-6}), "cp": ("msd", {"q_x": 3e-6, "q_mu": 1e-6, "grid_levels": 5}),
    "lv": ("msd", {"q_x": 3e-6, "q_mu": 1e-6}), "pairs": ("example-3-1", {}),
}
#: Evaluator kind → (plant kind, parameters and defaults).
EVALUATOR_KINDS = {
    "most-probable": ("b747", {}), "weight-threshold": ("b747", {"threshold": 0.2}),
    "fault-size": ("msd", {"threshold": 0.25, "skip": 5.0}), "conditioning": ("example-3-1", {}),
}
#: Fault kind → plant kind.
FAULT_KINDS = {"table-2.6": "b747", "loss": "msd"}
_MSD_FAULTS = {"u1_actuator": 30.0, "x2_sensor": 70.0}


def _kind(named, default=None) -> str:
    return named.kind or (named.name if default is None else default)


def _faults_of(plant_kind: str, kind: str) -> tuple[str, ...]:
    from fdikit.plants.b747 import B747_MODEL_NAMES

    if FAULT_KINDS.get(kind) != plant_kind:
        return ()
    return tuple(B747_MODEL_NAMES[1:]) if plant_kind == "b747" else tuple(_MSD_FAULTS)


def b747_window(fault: str) -> tuple[int, int, float, float]:
    """The samples ``[a, b]`` (inclusive) a B747 row is scored on, and the fault's Table 2.6 size and onset [s].

    Parameters
    ----------
    fault : str
        A Table 2.6 fault (a model name of :data:`~fdikit.plants.b747.B747_MODEL_NAMES`) or ``'none'``.

    Returns
    -------
    tuple
        ``(a, b, size, onset)``; for ``'none'`` the first nominal interval and NaN size / onset.

    Raises
    ------
    ParameterError
        When ``fault`` is not a fault of Table 2.6.

    References
    ----------
    Hallouzi 2008, §2.4.1, Table 2.6.

    Examples
    --------
    >>> b747_window("delta_s_loss"), b747_window("none")[:2]
    ((301, 500, 0.4, 4.0), (0, 199))
    """
    from fdikit.plants.b747 import B747_FAULT_SCHEDULE, B747_MODEL_NAMES
    from fdikit.studies.hallouzi2008.b747 import TS

    if fault == "none":
        return 0, B747_FAULT_SCHEDULE[0][0] - 1, math.nan, math.nan
    start = 0
    for a, b, w in B747_FAULT_SCHEDULE:
        k = int(np.argmax(w[1:])) + 1
        if B747_MODEL_NAMES[k] == fault:
            return start, b, float(w[k]), round(a * TS, 12)
        start = b + 1
    from fdikit.errors import ParameterError

    raise ParameterError(f"{fault!r} is not a fault of Table 2.6; choose from: {', '.join(B747_MODEL_NAMES[1:])}")


class MultipleModelStudy:
    """The ``multiple-model`` campaign study (module docstring).

    References
    ----------
    Hallouzi 2008, §2.4.1 (Table 2.6), §3.6.2 (the MSD model sets), Example 3.1.

    Examples
    --------
    >>> from fdikit.campaign.spec import Named
    >>> MULTIPLE_MODEL.fault_names(Named(name="b", kind="b747"), "table-2.6")
    ('delta_c_loss', 'delta_s_loss', 'V_TAS_sensor', 'alpha_sensor')
    >>> MULTIPLE_MODEL.fault_names(Named(name="m", kind="msd"), "table-2.6")
    ()
    """

    name = "multiple-model"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """The faults of ``kind`` on ``plant``: Table 2.6's four on a B747, u1_actuator and x2_sensor on the MSD."""
        return _faults_of(_kind(plant), kind)

    def check(self, spec) -> list[str]:
        """Problems with the spec's plants, faults, designs and evaluators."""
        problems = []
        kinds = set()
        for k, plant in enumerate(spec.plants):
            pk = _kind(plant)
            if pk not in PLANT_KINDS:
                problems.append(f"plants.{k}.kind: unknown plant {pk!r}; choose from: {', '.join(PLANT_KINDS)}")
                continue
            kinds.add(pk)
            for p, v in plant.params.items():
                if p not in PLANT_KINDS[pk]:
                    problems.append(f"plants.{k}.params.{p}: unknown parameter; {pk} takes: "
                                    f"{', '.join(PLANT_KINDS[pk]) or 'none'}")
                elif p == "dt" and not (isinstance(v, int | float) and 0 < v <= 0.02):
                    problems.append(f"plants.{k}.params.dt: must be in (0, 0.02] s (the MSD's series ZOH), got {v!r}")
                elif p == "snr_db" and not isinstance(v, int | float):
                    problems.append(f"plants.{k}.params.snr_db: must be a number [dB], got {v!r}")
        if "msd" in kinds and spec.duration <= max(_MSD_FAULTS.values()) + 10.0:
            problems.append(f"duration: {spec.duration} s is the MSD run length and must exceed 80 s (the sensor "
                            "fault is on [70, 80) s); the thesis's is 100")
        for k, fam in enumerate(spec.faults):
            if fam.kind not in FAULT_KINDS:
                problems.append(f"faults.{k}.kind: unknown fault kind {fam.kind!r}; choose from: "
                                f"{', '.join(FAULT_KINDS)}")
                continue
            pk = FAULT_KINDS[fam.kind]
            names = _faults_of(pk, fam.kind)
            if fam.targets != "all":
                bad = [t for t in fam.targets if t not in names]
                if bad:
                    problems.append(f"faults.{k}.targets: unknown {fam.kind} fault {bad[0]!r}; choose from: "
                                    f"{', '.join(names)}")
                elif len(spec.plants) > 1:
                    problems.append(f"faults.{k}.targets: with several plants give targets: all (a list would be "
                                    f"planned on every plant, and only {pk} has {fam.kind} faults)")
            if "onset" in fam.model_fields_set:
                problems.append(f"faults.{k}.onset: the {fam.kind} onsets are the study's (Table 2.6; MSD 30 s and "
                                "70 s); remove the entry")
            if fam.kind == "table-2.6" and "size" in fam.model_fields_set:
                problems.append(f"faults.{k}.size: the table-2.6 sizes are Table 2.6's; remove the entry")
            if fam.kind == "loss":
                lims = fam.size.values or fam.size.uniform or fam.size.loguniform
                if min(lims) < 0 or max(lims) > 1:
                    problems.append(f"faults.{k}.size: a loss is the lost fraction 1 − f in [0, 1], got {lims}")
        for what, table in (("designs", DESIGN_KINDS), ("evaluators", EVALUATOR_KINDS)):
            for k, d in enumerate(getattr(spec, what)):
                kind = _kind(d)
                if kind not in table:
                    problems.append(f"{what}.{k}.kind: unknown {what[:-1]} {kind!r}; choose from: {', '.join(table)}")
                    continue
                pk, known = table[kind]
                if pk not in kinds:
                    problems.append(f"{what}.{k}.kind: {kind} is for {pk} plants and the spec has none")
                for p, v in d.params.items():
                    if p not in known:
                        problems.append(f"{what}.{k}.params.{p}: unknown parameter; {kind} takes: "
                                        f"{', '.join(known) or 'none'}")
                    elif not (isinstance(v, int | float) and not isinstance(v, bool) and v > 0):
                        problems.append(f"{what}.{k}.params.{p}: must be a positive number, got {v!r}")
                    elif p == "threshold" and kind == "weight-threshold" and not v < 1:
                        problems.append(f"{what}.{k}.params.threshold: T_f must lie in (0, 1), got {v!r}")
        return problems

    def setup(self, spec) -> dict:
        """Plant name → kind and parameters; designs and evaluators with their parameters (nothing to fit)."""
        plants = {p.name: (_kind(p), {**PLANT_KINDS[_kind(p)], **p.params}) for p in spec.plants}
        designs = {d.name: (_kind(d), DESIGN_KINDS[_kind(d)][0], {**DESIGN_KINDS[_kind(d)][1], **d.params})
                   for d in spec.designs}
        evaluators = {e.name: (_kind(e), EVALUATOR_KINDS[_kind(e)][0], {**EVALUATOR_KINDS[_kind(e)][1], **e.params})
                      for e in spec.evaluators}
        return {"plants": plants, "designs": designs, "evaluators": evaluators}

    # ------------------------------------------------------------------ one run of one design
    def _b747(self, setup, run, design):
        from fdikit.plants.b747 import B747_MODEL_NAMES
        from fdikit.studies.hallouzi2008.b747 import INTERVALS, b747_monte_carlo

        kind, _, params = setup["designs"][design]
        res = b747_monte_carlo(runs=1, seed=run.seed, filters=(kind,), **params)
        metrics = {}
        for name, (a, b) in INTERVALS.items():
            for q, curve in (("state", res.rmse_state[kind]), ("weights", res.rmse_weights[kind])):
                metrics[f"{q}_rmse_{name}"] = float(res.summary[kind][name][q])
                metrics[f"{q}_mse_{name}"] = float(np.mean(curve[a:b + 1] ** 2))
        return res.t, res.mean_weights[kind], B747_MODEL_NAMES, metrics

    def _msd_sim(self, setup, spec, run):
        from fdikit.studies.hallouzi2008.msd import simulate_msd

        _, params = setup["plants"][run.plant]
        sizes = {f: 1.0 - run.size if run.fault == f else 1.0 for f in _MSD_FAULTS}
        return simulate_msd(seed=run.seed, duration=spec.duration, dt=float(params["dt"]),
                            snr_db=float(params["snr_db"]), f1_size=sizes["u1_actuator"], f2_size=sizes["x2_sensor"])

    @staticmethod
    def _msd(setup, sim, design):
        from fdikit.studies.hallouzi2008.msd_model_sets import run_msd_model_set

        kind, _, params = setup["designs"][design]
        return run_msd_model_set(sim, kind, **params)

    @staticmethod
    def _b747_decision(t, mu, names, evaluator: tuple, window):
        """Diagnosis and sweep statistic of one B747 window."""
        from fdikit.multimodel.isolation import GroupThresholdLogic, mode_diagnosis

        kind, _, params = evaluator
        a, b = window
        t, mu = t[a:b + 1], mu[a:b + 1]
        if kind == "most-probable":
            return mode_diagnosis(t, mu, names, nominal=0), None
        T = float(params["threshold"])
        logic = GroupThresholdLogic(groups={n: [i] for i, n in enumerate(names) if i}, nominal=0, threshold=T)
        return mode_diagnosis(t, mu, names, logic=logic), np.abs(1.0 - mu[:, 0]) / T

    @staticmethod
    def _msd_decision(sim, run_result, evaluator: tuple):
        """Diagnosis and sweep statistic of the MSD ``fault-size`` rule (module docstring)."""
        from fdikit.diagnosis import Diagnosis

        _, _, params = evaluator
        T, skip = float(params["threshold"]), float(params["skip"])
        loss = 1.0 - run_result.params[:, 2:4]
        loss[sim.t < skip] = 0.0
        loss = np.nan_to_num(loss, nan=0.0, posinf=0.0, neginf=0.0)
        fired = loss > T
        names = tuple(_MSD_FAULTS)
        isolated = np.where(fired.any(axis=1), np.array(names)[np.argmax(loss, axis=1)], "none")
        return Diagnosis(sim.t, fired.any(axis=1), fired, names, isolated), loss.max(axis=1) / T

    @staticmethod
    def _msd_labels(sim) -> np.ndarray:
        f = sim.params
        return np.where(f[:, 2] < 1.0, "u1_actuator", np.where(f[:, 3] < 1.0, "x2_sensor", "none"))

    @staticmethod
    def _msd_metrics(sim, r, skip: float) -> dict:
        from fdikit.studies.hallouzi2008.msd import MSD_STATES

        m = {f"vaf_{s}": float(r.vaf[s]) for s in MSD_STATES}
        t = sim.t
        m["f1_fault_mean"] = float(r.params[(t >= 30.0) & (t < 50.0), 2].mean())
        m["f2_fault_mean"] = float(r.params[(t >= 70.0) & (t < 80.0), 3].mean())
        late = t >= skip
        for j, name in ((0, "k1"), (1, "m3")):
            m[f"{name}_rmse"] = float(np.sqrt(np.mean((r.params[late, j] - sim.params[late, j]) ** 2)))
        return m

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """One row per run × design × evaluator of the run's plant kind (module docstring)."""
        from fdikit.campaign.rows import score_row
        from fdikit.metrics import Score, score

        empty = Score("none", None, False, None, 0, 0.0, False, "none", None)
        nan_sweep, zero_sweep = [math.nan] * len(levels), [0] * len(levels)
        rows = []
        for run in runs:
            pk = setup["plants"][run.plant][0]
            designs = [d.name for d in spec.designs if setup["designs"][d.name][1] == pk]
            evaluators = [e.name for e in spec.evaluators if setup["evaluators"][e.name][1] == pk]
            if pk == "example-3-1":
                metrics = _example_metrics(run.seed)
                rows += [score_row(run, d, e, empty, nan_sweep, zero_sweep, metrics)
                         for d in designs for e in evaluators]
                continue
            if pk == "b747":
                a, b, size, onset = b747_window(run.fault)
                plan = replace(run, size=size, onset=onset)
                for d in designs:
                    t, mu, names, metrics = self._b747(setup, run, d)
                    labels = self._b747_labels(t.size)[a:b + 1]
                    for e in evaluators:
                        diag, stat = self._b747_decision(t, mu, names, setup["evaluators"][e], (a, b))
                        rows.append(self._row(plan, d, e, score(labels, diag), stat, diag.t, labels, levels, metrics))
                continue
            sim = self._msd_sim(setup, spec, run)
            labels = self._msd_labels(sim)
            onset = _MSD_FAULTS.get(run.fault, math.nan)
            plan = replace(run, onset=onset)
            for d in designs:
                r = self._msd(setup, sim, d)
                for e in evaluators:
                    ev = setup["evaluators"][e]
                    diag, stat = self._msd_decision(sim, r, ev)
                    metrics = self._msd_metrics(sim, r, float(ev[2]["skip"]))
                    rows.append(self._row(plan, d, e, score(labels, diag), stat, sim.t, labels, levels, metrics))
        return rows

    @staticmethod
    def _b747_labels(n: int) -> np.ndarray:
        from fdikit.studies.hallouzi2008.b747 import b747_weight_profile

        return b747_weight_profile(n)[1]

    @staticmethod
    def _row(plan, design, evaluator, s, stat, t, labels, levels, metrics) -> dict:
        """The row; sweep columns from ``stat`` with the fault-free samples as :func:`fdikit.metrics.score` counts."""
        from fdikit.batch import crossings
        from fdikit.campaign.rows import score_row

        if stat is None:
            return score_row(plan, design, evaluator, s, [math.nan] * len(levels), [0] * len(levels), metrics)
        healthy = labels == "none"
        onset = t[np.argmax(~healthy)] if (~healthy).any() else math.nan  # the first faulty sample, as score's
        c = crossings(stat[None, :], t, [onset], healthy=healthy[None, :], levels=levels)
        return score_row(plan, design, evaluator, s, c.delay[0], c.upcrossings[0], metrics)

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)`` of one row (residuals: the weights, or the reconstructed losses)."""
        from fdikit.residuals import Residuals
        from fdikit.trace import Trace

        pk = setup["plants"][run.plant][0]
        if pk == "b747":
            from fdikit.studies.hallouzi2008.b747 import b747_trace

            a, b, _, _ = b747_window(run.fault)
            t, mu, names, _ = self._b747(setup, run, design)
            tr = b747_trace(np.random.default_rng(np.random.SeedSequence(run.seed).spawn(1)[0]))  # the study's run
            w = slice(a, b + 1)
            trace = Trace(t=tr.t[w], u=tr.u[w], y=tr.y[w], controls=tr.controls, outputs=tr.outputs, x=tr.x[w],
                          states=tr.states, fault=tr.fault[w], meta=tr.meta)
            diag, _ = self._b747_decision(t, mu, names, setup["evaluators"][evaluator], (a, b))
            return trace, Residuals(diag.t, mu[a:b + 1], tuple(f"mu_{n}" for n in names), ()), diag
        if pk == "msd":
            sim = self._msd_sim(setup, spec, run)
            r = self._msd(setup, sim, design)
            diag, _ = self._msd_decision(sim, r, setup["evaluators"][evaluator])
            trace = Trace(t=sim.t, u=sim.u, y=sim.y, controls=("u1", "u2"), outputs=("x1", "x2", "x3"), x=sim.x,
                          states=("x1", "x2", "x3", "v1", "v2", "v3"), fault=self._msd_labels(sim))
            residuals = Residuals(sim.t, 1.0 - r.params[:, 2:4], ("f1_loss", "f2_loss"), tuple(_MSD_FAULTS))
            return trace, residuals, diag
        from fdikit.errors import ParameterError

        raise ParameterError(f"run {run.run} is an example-3-1 model set: it has no trajectory to replay")


def _example_metrics(seed: int) -> dict:
    from fdikit.studies.hallouzi2008.example_3_1 import PAIRS, example_3_1

    ex = example_3_1(model_sets=1, seed=seed)
    m = {}
    for j, (q, r) in enumerate(PAIRS):
        m[f"observability_{q + 1}{r + 1}"] = float(ex.observability[0, j])
        m[f"basis_{q + 1}{r + 1}"] = float(ex.basis[0, j])
    m.update({k: float(v) for k, v in ex.frequency().items()})
    return m


#: The registered study object.
MULTIPLE_MODEL = MultipleModelStudy()
