"""The PATH vehicle's linear campaigns: the App. D plant, the §5.1.1 faults, the bank designs, the evaluators.

The campaign study ``path-linear`` (:mod:`fdikit.campaign`): runs of the 14-state linear model
(:func:`~fdikit.studies.path1996.bank.path_fault_model`, ``tiny='midpoint'``), discretised at ``dt``,
with white sensor noise, exactly as :func:`~fdikit.studies.path1996.bank.path_runs` simulates them.

Plant ``params``:

``noise``
    ``realistic`` (default): the per-sample standard deviations of
    :data:`fdikit.studies.path1996.nonlinear_evaluation.NOISE_STD` (gyros 0.002 rad/s, accelerometers
    0.05 m/s², a_z 0.3 m/s² on a rough road, wheel speeds 0.1 rad/s, engine speed 0.5 rad/s, air mass 1 %;
    sources in ``docs/methods/nonlinear_vehicle.md``); ``report``: 1e-4 of each sensor's nominal fault, the
    level at which the PATH report's results are shown (Douglas et al. 1996, §5.1.1); or a mapping output →
    standard deviation.
``dt``
    Sample time [s] (default 0.01).

Fault kinds (``targets: all`` is the 15 faults of §5.1.1: the 12 sensors and the 3 actuators; ``size`` is a
multiple of the fault's nominal size, :func:`~fdikit.studies.path1996.bank.nominal_fault_sizes`):
``bias`` (a step of ``size`` nominal sizes) and ``drift`` (a ramp of ``size`` nominal sizes per second).

Design kinds: ``beard-jones`` (the four-filter bank, :func:`~fdikit.studies.path1996.bank.path_bank`),
``kalman`` (one steady-state Kalman filter, :func:`~fdikit.studies.path1996.kalman_bank.path_kalman_bank`,
designed for the plant's noise), ``game`` (the game-theoretic bank,
:func:`~fdikit.studies.path1996.game_bank.path_game_bank`, weights in ``params``: ``gamma``, ``M``, ``Q``),
``nullspace`` (the exact ``efdisyn`` bank, :func:`~fdikit.studies.path1996.nullspace_bank.path_nullspace_bank`; with
``noise_weighted`` (default true) its basis rows are combined for the plant's noise, by ``criterion``:
``variance`` (default, the DC gain over the stationary std) or ``gap`` (``afdsyn(selection="gap")``: the DC gap,
the noise whitened)).
Evaluators: every kind of :mod:`fdikit.campaign.evaluation` but ``mhsprt-whitened`` (fitted on runs with the
fault from 2 s, the nonlinear study's); ``glr`` … ``bnn`` are those of ``fdikit compare-evaluators``
(:mod:`fdikit.studies.path1996.compare`, Douglas et al. 1996, Ch. 6–7), fitted exactly as it fits them.
Calibration runs are fault-free runs of the same plant from the seed ``SeedSequence(seed, spawn_key=(plant, 1))``,
disjoint from every run's.  When an evaluator is trained (``mhsprt``, ``gaussian-ml``, ``bnn``), the labelled
training runs are those of the comparison (``path_runs(..., runs_per_fault=1, healthy_runs=1)``): one fault-free
run, then each of the 15 faults as a bias of 1 nominal size from 5 s, 20 s each, at the plant's noise, their
seeds drawn as :func:`~fdikit.studies.path1996.bank.path_runs` draws them from
``SeedSequence(seed, spawn_key=(plant, 2))`` (disjoint from the runs' and the calibration's).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["PathLinearStudy", "PATH_LINEAR", "DESIGN_KINDS", "FAULT_KINDS", "NOISE_PRESETS", "EVALUATORS"]

#: Design kind → its parameters and defaults.
DESIGN_KINDS = {"beard-jones": {}, "kalman": {}, "game": {"gamma": 1e-6, "M": 0.01, "Q": 1e-6},
                "nullspace": {"noise_weighted": True, "criterion": "variance"}}
#: Fault kinds.
FAULT_KINDS = ("bias", "drift")
#: Named noise levels of the plant's ``noise`` parameter.
NOISE_PRESETS = ("realistic", "report")
_PLANT_PARAMS = ("noise", "dt")
#: The evaluator kinds of :mod:`fdikit.campaign.evaluation` the study runs.
EVALUATORS = ("threshold", "cusum", "glr", "sprt", "cusum-whitened", "glr-whitened", "sprt-whitened", "mhsprt",
              "gaussian-ml", "bnn")
#: The labelled training runs (``fdikit compare-evaluators``'s): onset [s], duration [s], size [nominal sizes].
TRAINING = {"onset": 5.0, "duration": 20.0, "size": 1.0}


@dataclass(frozen=True, eq=False)
class _Plant:
    model: object  # the discrete FaultModel
    noise: np.ndarray  # per output
    designs: dict  # design name → (generator, groups)
    evaluators: dict  # (design, evaluator) → fitted evaluator


class PathLinearStudy:
    """The ``path-linear`` campaign study (module docstring).

    References
    ----------
    Douglas et al. 1996, Ch. 4 (the bank), §5.1.1 (the faults and their nominal sizes).

    Examples
    --------
    >>> PATH_LINEAR.fault_names(None, "bias")[:2]
    ('throttle_actuator', 'brake_actuator')
    """

    name = "path-linear"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """The 15 fault inputs of the App. D model, as §5.1.1 lists them (any plant, any kind)."""
        from fdikit.studies.path1996.bank import path_fault_model

        return tuple(path_fault_model(14).faults)

    def check(self, spec) -> list[str]:
        """Problems with the spec's plant parameters, fault kinds and targets, designs and evaluators."""
        from fdikit.campaign.evaluation import check_evaluators
        from fdikit.studies.path1996.bank import path_fault_model

        outputs = path_fault_model(14).outputs
        problems = []
        for k, plant in enumerate(spec.plants):
            for p, v in plant.params.items():
                if p not in _PLANT_PARAMS:
                    problems.append(f"plants.{k}.params.{p}: unknown parameter; path-linear takes: noise, dt")
                elif p == "noise" and not (v in NOISE_PRESETS or isinstance(v, dict)):
                    problems.append(f"plants.{k}.params.noise: {v!r} is neither {' nor '.join(NOISE_PRESETS)} nor a "
                                    "mapping output → standard deviation")
                elif p == "noise" and isinstance(v, dict):
                    missing = [o for o in outputs if o not in v]
                    if missing or any(not isinstance(x, int | float) or x < 0 for x in v.values()):
                        problems.append(f"plants.{k}.params.noise: give a standard deviation >= 0 for every output "
                                        f"({', '.join(outputs)}); missing {missing}")
                elif p == "dt" and not (isinstance(v, int | float) and 0 < v <= 0.1):
                    problems.append(f"plants.{k}.params.dt: must be in (0, 0.1] s, got {v!r}")
        names = self.fault_names(None, "bias")
        for k, fam in enumerate(spec.faults):
            if fam.kind not in FAULT_KINDS:
                problems.append(f"faults.{k}.kind: unknown fault kind {fam.kind!r}; "
                                f"choose from: {', '.join(FAULT_KINDS)}")
            if fam.targets != "all":
                bad = [t for t in fam.targets if t not in names]
                if bad:
                    problems.append(f"faults.{k}.targets: unknown fault {bad[0]!r}; choose from: {', '.join(names)}")
        for k, d in enumerate(spec.designs):
            kind = d.kind or d.name
            if kind not in DESIGN_KINDS:
                problems.append(f"designs.{k}.kind: unknown design {kind!r}; choose from: {', '.join(DESIGN_KINDS)}")
                continue
            for p in d.params:
                if p not in DESIGN_KINDS[kind]:
                    problems.append(f"designs.{k}.params.{p}: unknown parameter; {kind} takes: "
                                    f"{', '.join(DESIGN_KINDS[kind]) or 'none'}")
        return problems + check_evaluators(spec.evaluators, EVALUATORS, self.name)

    # ------------------------------------------------------------------ set-up (once per worker)
    @staticmethod
    def _noise(params, nominal, outputs) -> np.ndarray:
        from fdikit.model import sensor_fault_name
        from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD

        level = params.get("noise", "realistic")
        if level == "report":
            return 1e-4 * np.array([nominal[sensor_fault_name(o)] for o in outputs])
        table = NOISE_STD if level == "realistic" else level
        return np.array([float(table[o]) for o in outputs])

    def setup(self, spec) -> dict:
        """Per plant: the discrete model, the noise, every design's generator and the calibrated evaluators."""
        from fdikit.campaign.evaluation import calibration_seconds, fit_evaluator, needs_training
        from fdikit.campaign.plan import RunPlan
        from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14
        from fdikit.simulate import simulate
        from fdikit.studies.path1996.bank import nominal_fault_sizes, path_bank, path_fault_model
        from fdikit.studies.path1996.game_bank import path_game_bank
        from fdikit.studies.path1996.kalman_bank import path_kalman_bank
        from fdikit.studies.path1996.nullspace_bank import path_nullspace_bank

        nominal = nominal_fault_sizes()
        models = (path_fault_model(12), path_fault_model(14))
        plain = (path_vehicle_12("midpoint"), path_vehicle_14("midpoint"))
        plants = {}
        beard_jones = None
        for k, plant in enumerate(spec.plants):
            dt = float(plant.params.get("dt", 0.01))
            model = models[1].discretize(dt)
            noise = self._noise(plant.params, nominal, model.outputs)
            std = dict(zip(model.outputs, noise))
            designs = {}
            for d in spec.designs:
                kind = d.kind or d.name
                if kind == "beard-jones":  # noise-independent: designed once for every plant
                    bank = beard_jones = beard_jones or path_bank()
                elif kind == "kalman":
                    bank = path_kalman_bank(models[1], std, dt=dt)
                elif kind == "nullspace":       # designed on the fault-free App. D models, as the study does
                    par = {**DESIGN_KINDS["nullspace"], **d.params}
                    bank = path_nullspace_bank(plain, nominal, noise_std=std if par["noise_weighted"] else None,
                                               dt=dt, criterion=par["criterion"])
                else:
                    bank = path_game_bank(models, nominal, std, dt=dt, **{**DESIGN_KINDS["game"], **d.params})
                gen = bank.generator if bank.generator.dt == dt else bank.generator.discretize(dt)
                designs[d.name] = (gen, bank.groups)
            seed = np.random.SeedSequence(spec.seed, spawn_key=(k, 1))
            healthy = simulate(model, duration=calibration_seconds(spec.evaluators), measurement_noise_std=noise,
                               rng=np.random.default_rng(seed))
            training = []
            if needs_training(spec.evaluators):
                labels = ["none", *self.fault_names(plant, "bias")]
                seeds = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(k, 2))).integers(
                    2**31, size=len(labels))
                training = [_simulate(model, noise, nominal, TRAINING["duration"],
                                      RunPlan(-1, -1, plant.name, f, "none" if f == "none" else "bias",
                                              TRAINING["size"], TRAINING["onset"], int(s)))
                            for f, s in zip(labels, seeds)]
            evaluators = {}
            for d in spec.designs:
                gen, groups = designs[d.name]
                res = gen.run(healthy)
                labelled = [(tr, gen.run(tr)) for tr in training]
                for e in spec.evaluators:
                    evaluators[(d.name, e.name)] = fit_evaluator(e, res, groups, labelled, TRAINING["onset"])
            plants[plant.name] = _Plant(model, noise, designs, evaluators)
        return {"plants": plants, "nominal": nominal}

    # ------------------------------------------------------------------ runs
    def _trace(self, setup, spec, run):
        plant = setup["plants"][run.plant]
        return _simulate(plant.model, plant.noise, setup["nominal"], spec.duration, run)

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """Rows of the runs: simulate each, every design's residuals in one batch per plant, every evaluator."""
        from fdikit.batch import run_generator_batch
        from fdikit.campaign.evaluation import evaluate_runs

        rows = []
        for name in dict.fromkeys(r.plant for r in runs):
            mine = [r for r in runs if r.plant == name]
            plant = setup["plants"][name]
            traces = [self._trace(setup, spec, r) for r in mine]
            residuals, names, isolates = {}, {}, {}
            for design, (gen, _) in plant.designs.items():
                residuals[design] = run_generator_batch(gen, traces)
                names[design] = gen.residuals
                isolates[design] = gen.isolates or (None,) * len(gen.residuals)
            rows += evaluate_runs(mine, traces, residuals, names, isolates, plant.evaluators, levels)
        order = {r.run: i for i, r in enumerate(runs)}
        return sorted(rows, key=lambda row: order[row["run"]])

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)`` of one run."""
        plant = setup["plants"][run.plant]
        trace = self._trace(setup, spec, run)
        residuals = plant.designs[design][0].run(trace)
        return trace, residuals, plant.evaluators[(design, evaluator)].run(residuals)


def _simulate(model, noise, nominal, duration: float, run):
    """One run as :func:`~fdikit.studies.path1996.bank.path_runs` simulates it (a bias or drift of ``run.size``
    nominal sizes from ``run.onset``, white sensor noise, the run's seed)."""
    from fdikit.faults import Bias, Drift, FaultScenario
    from fdikit.simulate import simulate

    faults = []
    if not run.healthy:
        signal, loc = run.fault.rsplit("_", 1)
        cls = Bias if run.kind == "bias" else Drift
        faults = [cls(signal, run.size * nominal[run.fault], onset=run.onset, location=loc)]
    return simulate(model, FaultScenario(faults), duration=duration, measurement_noise_std=noise, rng=run.seed)


#: The registered study object.
PATH_LINEAR = PathLinearStudy()
