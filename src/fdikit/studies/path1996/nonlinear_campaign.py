"""The PATH monitor on the nonlinear car as a campaign: the Ch. 5 evaluation of ``fdikit path-evaluation``.

The campaign study ``path-nonlinear`` (:mod:`fdikit.campaign`) runs what
:func:`~fdikit.studies.path1996.nonlinear_table.path_evaluation_table` runs (Douglas et al. 1996, §5.1): the
nonlinear car (:func:`~fdikit.studies.path1996.nonlinear_evaluation.evaluation_setup`: the 0.005 rad turn at
24.87 m/s, the design models, the nominal sizes measured on the car, the banks) simulated by
:func:`~fdikit.studies.path1996.nonlinear_evaluation.fault_run` at its realistic sensor noise
(:data:`~fdikit.studies.path1996.nonlinear_evaluation.NOISE_STD`), on a smooth or the Robson rough road.

Plants: one per road; ``params``: ``road`` (``smooth`` or ``rough``; default the plant's ``kind``, else its
name).  Fault kind ``bias`` on the 15 faults of the monitor
(:data:`~fdikit.studies.path1996.nonlinear_table.FAULTS`, ``targets: all``); ``size`` in nominal sizes (a
negative size is the opposite sign, ``fault_run``'s ``sign``), ``onset`` [s] (the study's is 2 s).  Designs:
``beard-jones``, ``game``, ``kalman`` — the banks of the evaluation set-up as that study designs them (no
parameters).  Evaluators: the kinds of :mod:`fdikit.campaign.evaluation` but ``gaussian-ml`` and ``bnn`` (the
study trains no classifier and has no fault-free training run); the study's processors are ``threshold``,
``cusum-whitened``, ``mhsprt`` and ``mhsprt-whitened`` with ``drop: 2`` and ``calibration: 3600`` (one hour of
fault-free driving, its first 2 s left out), fitted as the study fits them.

Seeds: run ``k`` is ``fault_run(..., rng=seed_k)`` with the plan's seed (its residuals computed by
:func:`fdikit.batch.run_generator_batch`, the generators' own recursion batched over the chunk's runs); the
fault-free calibration run of plant ``i`` takes ``SeedSequence(seed, spawn_key=(i, 1))``; the labelled training runs
(kinds ``mhsprt``, ``mhsprt-whitened``: one run per fault of
:data:`~fdikit.studies.path1996.nonlinear_table.FAULTS`, nominal size, from 2 s, ``duration`` long, as the study
trains them) draw their seeds from ``SeedSequence(seed, spawn_key=(i, 2))`` — disjoint from every run's. The study's
separate fault-free test hour per road is expressed as fault-free runs of the campaign (``healthy``; 180 runs of 20
s per road make the hour): their false alarms per hour are the report's column. Each run starts at the trimmed turn,
so its filters start settled, as the study's do.

Rows: the detection and isolation columns from :func:`fdikit.metrics.score` of each processor's diagnosis; the
sweep columns as :mod:`fdikit.campaign.evaluation` says (threshold, CUSUM, GLR kinds: the level crossings of
their statistic; the MHSSPRT kinds: NaN delays and zero counts, a flat trade-off curve); ``metrics`` is empty.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["PathNonlinearStudy", "PATH_NONLINEAR", "DESIGN_KINDS", "EVALUATORS", "ROADS", "TRAINING_ONSET"]

#: Design kinds (the banks of :func:`~fdikit.studies.path1996.nonlinear_evaluation.evaluation_setup`).
DESIGN_KINDS = ("beard-jones", "game", "kalman")
#: Evaluator kinds of :mod:`fdikit.campaign.evaluation` the study runs.
EVALUATORS = ("threshold", "cusum", "glr", "sprt", "cusum-whitened", "glr-whitened", "sprt-whitened", "mhsprt",
              "mhsprt-whitened")
#: Roads.
ROADS = ("smooth", "rough")
#: Onset [s] of the faults in the training runs (the study's).
TRAINING_ONSET = 2.0


@dataclass(frozen=True, eq=False)
class _Plant:
    road: str
    evaluators: dict  # (design, evaluator) → fitted evaluator


def _road(plant) -> str:
    return str(plant.params.get("road", plant.kind if plant.kind in ROADS else plant.name))


class PathNonlinearStudy:
    """The ``path-nonlinear`` campaign study (module docstring).

    References
    ----------
    Douglas et al. 1996, Ch. 5 (the evaluation on the nonlinear car), §5.1.1.

    Examples
    --------
    >>> PATH_NONLINEAR.fault_names(None, "bias")[:2]
    ('air_mass_sensor', 'engine_speed_sensor')
    """

    name = "path-nonlinear"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """The 15 faults of the PATH monitor, in the order of the report's groups (any plant, any kind)."""
        from fdikit.studies.path1996.nonlinear_table import FAULTS

        return tuple(FAULTS)

    def check(self, spec) -> list[str]:
        """Problems with the spec's roads, fault kinds and targets, designs and evaluators."""
        from fdikit.campaign.evaluation import check_evaluators

        problems = []
        for k, plant in enumerate(spec.plants):
            for p in plant.params:
                if p != "road":
                    problems.append(f"plants.{k}.params.{p}: unknown parameter; path-nonlinear takes: road")
            if _road(plant) not in ROADS:
                problems.append(f"plants.{k}.params.road: unknown road {_road(plant)!r}; choose from: "
                                f"{', '.join(ROADS)} (or name the plant after its road)")
        names = self.fault_names(None, "bias")
        for k, fam in enumerate(spec.faults):
            if fam.kind != "bias":
                problems.append(f"faults.{k}.kind: unknown fault kind {fam.kind!r}; path-nonlinear has: bias")
            if fam.targets != "all":
                bad = [t for t in fam.targets if t not in names]
                if bad:
                    problems.append(f"faults.{k}.targets: unknown fault {bad[0]!r}; choose from: {', '.join(names)}")
            lows = [v for v in (fam.onset.values or []) + (fam.onset.uniform or []) + (fam.onset.loguniform or [])]
            if any(v < 0 or v >= spec.duration for v in lows):
                problems.append(f"faults.{k}.onset: onsets must lie in [0, duration = {spec.duration}) s, got {lows}")
        for k, d in enumerate(spec.designs):
            kind = d.kind or d.name
            if kind not in DESIGN_KINDS:
                problems.append(f"designs.{k}.kind: unknown design {kind!r}; choose from: {', '.join(DESIGN_KINDS)}")
            elif d.params:
                problems.append(f"designs.{k}.params: {kind} takes no parameters (the evaluation set-up designs it), "
                                f"got {sorted(d.params)}")
        if TRAINING_ONSET >= spec.duration:
            problems.append(f"duration: the training runs are duration long with the fault from {TRAINING_ONSET} s; "
                            "give a longer duration")
        return problems + check_evaluators(spec.evaluators, EVALUATORS, self.name)

    # ------------------------------------------------------------------ set-up (once per worker)
    def setup(self, spec) -> dict:
        """The evaluation set-up (car, banks) and, per road, the evaluators fitted on its calibration run."""
        from dataclasses import replace

        from fdikit.campaign.evaluation import calibration_seconds, fit_evaluator, needs_training
        from fdikit.studies.path1996.nonlinear_evaluation import evaluation_setup, fault_run

        es = evaluation_setup()
        designs = {d.name: d.kind or d.name for d in spec.designs}
        kinds = tuple(dict.fromkeys(designs.values()))
        # fault_run runs every generator of the set-up on its trace: give it only the banks the spec uses (the
        # calibration hour), or none (short runs: their residuals are computed in one batch per bank instead)
        used, bare = replace(es, generators={k: es.generators[k] for k in kinds}), replace(es, generators={})
        faults = self.fault_names(None, "bias")
        plants = {}
        for k, plant in enumerate(spec.plants):
            road = _road(plant)
            healthy = fault_run(used, None, road, duration=calibration_seconds(spec.evaluators),
                                rng=np.random.SeedSequence(spec.seed, spawn_key=(k, 1)))
            training = {kind: [] for kind in kinds}
            if needs_training(spec.evaluators):
                seeds = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(k, 2))).integers(
                    2**31, size=len(faults))
                traces = [fault_run(bare, f, road, duration=spec.duration, onset=TRAINING_ONSET, rng=int(s)).trace
                          for f, s in zip(faults, seeds)]
                training = {kind: list(zip(traces, _residuals(es.generators[kind], traces))) for kind in kinds}
            evaluators = {}
            for d in spec.designs:
                kind = designs[d.name]
                for e in spec.evaluators:
                    evaluators[(d.name, e.name)] = fit_evaluator(e, healthy.residuals[kind], es.banks[kind].groups,
                                                                 training[kind], TRAINING_ONSET)
            plants[plant.name] = _Plant(road, evaluators)
            del healthy, training
        return {"evaluation": es, "bare": bare, "plants": plants, "designs": designs}

    # ------------------------------------------------------------------ runs
    @staticmethod
    def _trace(setup, spec, run):
        from fdikit.studies.path1996.nonlinear_evaluation import fault_run

        road = setup["plants"][run.plant].road
        if run.healthy:
            return fault_run(setup["bare"], None, road, duration=spec.duration, rng=run.seed).trace
        return fault_run(setup["bare"], run.fault, road, duration=spec.duration, onset=run.onset, size=run.size,
                         rng=run.seed).trace

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """Rows of the runs: ``fault_run`` each, every bank's residuals in one batch per plant, every evaluator."""
        from fdikit.batch import run_generator_batch
        from fdikit.campaign.evaluation import evaluate_runs

        rows = []
        for name in dict.fromkeys(r.plant for r in runs):
            mine = [r for r in runs if r.plant == name]
            traces = [self._trace(setup, spec, r) for r in mine]
            residuals, names, isolates = {}, {}, {}
            for design, kind in setup["designs"].items():
                gen = setup["evaluation"].generators[kind]
                residuals[design] = run_generator_batch(gen, traces)
                names[design] = gen.residuals
                isolates[design] = gen.isolates or (None,) * len(gen.residuals)
            rows += evaluate_runs(mine, traces, residuals, names, isolates, setup["plants"][name].evaluators, levels)
        order = {r.run: i for i, r in enumerate(runs)}
        return sorted(rows, key=lambda row: order[row["run"]])

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)`` of one run."""
        trace = self._trace(setup, spec, run)
        residuals = setup["evaluation"].generators[setup["designs"][design]].run(trace)
        return trace, residuals, setup["plants"][run.plant].evaluators[(design, evaluator)].run(residuals)


def _residuals(gen, traces) -> list:
    """The generator's residuals on each trace, computed in one batch (:func:`fdikit.batch.run_generator_batch`)."""
    from fdikit.batch import run_generator_batch
    from fdikit.residuals import Residuals

    r = run_generator_batch(gen, traces)
    isolates = gen.isolates or (None,) * len(gen.residuals)
    return [Residuals(tr.t, r[i], gen.residuals, isolates) for i, tr in enumerate(traces)]


#: The registered study object.
PATH_NONLINEAR = PathNonlinearStudy()
