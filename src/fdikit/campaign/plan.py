"""The runs of a campaign: every run's plant, fault, size, onset and seed, each derivable by itself.

Grid sampling enumerates, per plant, ``healthy`` fault-free runs, then every fault family × target × size
value × onset value, ``repeats`` times; random sampling draws each run.  Either way run ``k`` takes
everything random (the parameters drawn from a distribution and its simulation seed) from
``numpy.random.SeedSequence(spec.seed, spawn_key=(k,))`` — the spawn-key mechanism numpy provides for
independent, reproducible streams — so a run is reproduced from the spec and its index alone, whichever
worker computed it and whatever else ran.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fdikit.campaign.spec import CampaignSpec
from fdikit.errors import ParameterError

__all__ = ["RunPlan", "plan_runs", "plan_run", "NO_FAULT"]

#: Fault label, kind and target of a fault-free run.
NO_FAULT = "none"


@dataclass(frozen=True)
class RunPlan:
    """One run of a campaign.

    Attributes
    ----------
    run : int
        Index in the plan.
    chunk : int
        The chunk (task and results file) of the run: ``run // chunk_size``.
    plant : str
        Name of the spec's plant.
    fault : str
        The fault name (the study's, e.g. ``yaw_rate_sensor``) or ``'none'``.
    kind : str
        Fault kind (``bias`` ...) or ``'none'``.
    size : float
        Fault size (NaN when fault-free).
    onset : float
        Onset [s] (NaN when fault-free).
    seed : int
        The run's simulation seed (< 2**63).

    Examples
    --------
    >>> RunPlan(0, 0, "linear", "none", "none", float("nan"), float("nan"), 7).healthy
    True
    """

    run: int
    chunk: int
    plant: str
    fault: str
    kind: str
    size: float
    onset: float
    seed: int

    @property
    def healthy(self) -> bool:
        """Whether the run is fault-free."""
        return self.fault == NO_FAULT


def _rng(spec: CampaignSpec, k: int):
    import numpy as np

    return np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(k,)))


def _targets(spec: CampaignSpec) -> dict[tuple[int, int], list[str]]:
    """(plant index, fault family index) → the family's targets on that plant."""
    from fdikit.campaign.studies import get_study

    study = get_study(spec.study)
    return {(i, j): list(study.fault_names(plant, fam.kind)) if fam.targets == "all" else list(fam.targets)
            for i, plant in enumerate(spec.plants) for j, fam in enumerate(spec.faults)}


def _cells(spec: CampaignSpec) -> list[tuple]:
    """Grid cells ``(plant, fault, kind, size or None, onset or None, family)`` in plan order."""
    targets = _targets(spec)
    cells = []
    for i, plant in enumerate(spec.plants):
        cells += [(plant.name, NO_FAULT, NO_FAULT, math.nan, math.nan)] * int(spec.healthy)
        for j, fam in enumerate(spec.faults):
            for target in targets[(i, j)]:
                for size in fam.size.grid:
                    for onset in fam.onset.grid:
                        cells += [(plant.name, target, fam.kind, size, onset, fam)] * spec.sampling.grid.repeats
    return cells


def _finish(spec: CampaignSpec, k: int, rng, plant, fault, kind, size, onset, fam=None) -> RunPlan:
    if fam is not None:
        size = fam.size.draw(rng) if size is None else float(size)
        onset = fam.onset.draw(rng) if onset is None else float(onset)
    return RunPlan(k, k // spec.chunk_size, plant, fault, kind, size, onset, int(rng.integers(2**63)))


def _random_run(spec: CampaignSpec, k: int, targets: dict) -> RunPlan:
    rng = _rng(spec, k)
    i = int(rng.integers(len(spec.plants)))
    plant = spec.plants[i]
    if not spec.faults or rng.random() < spec.healthy:
        return _finish(spec, k, rng, plant.name, NO_FAULT, NO_FAULT, math.nan, math.nan)
    j = int(rng.integers(len(spec.faults)))
    fam = spec.faults[j]
    target = targets[(i, j)][int(rng.integers(len(targets[(i, j)])))]
    return _finish(spec, k, rng, plant.name, target, fam.kind, None, None, fam)


def plan_runs(spec: CampaignSpec) -> list[RunPlan]:
    """Every run of the campaign, in order.

    Parameters
    ----------
    spec : CampaignSpec

    Returns
    -------
    list of RunPlan

    Examples
    --------
    >>> from fdikit.campaign.spec import CampaignSpec
    >>> spec = CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 20.0,
    ...     "plants": [{"name": "linear"}], "healthy": 2, "chunk_size": 2,
    ...     "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor", "roll_rate_sensor"],
    ...                 "onset": {"uniform": [4.0, 6.0]}}],
    ...     "designs": [{"name": "kalman", "kind": "kalman"}], "evaluators": [{"name": "t", "kind": "threshold"}]})
    >>> [(p.run, p.chunk, p.fault) for p in plan_runs(spec)]
    [(0, 0, 'none'), (1, 0, 'none'), (2, 1, 'yaw_rate_sensor'), (3, 1, 'roll_rate_sensor')]
    >>> plan_runs(spec)[3] == plan_run(spec, 3), 4.0 <= plan_runs(spec)[2].onset <= 6.0
    (True, True)
    """
    if spec.sampling.random is not None:
        targets = _targets(spec)
        return [_random_run(spec, k, targets) for k in range(spec.sampling.random.runs)]
    return [_finish(spec, k, _rng(spec, k), *cell) for k, cell in enumerate(_cells(spec))]


def plan_run(spec: CampaignSpec, run: int) -> RunPlan:
    """Run ``run`` of the campaign, derived by itself (the same as ``plan_runs(spec)[run]``).

    Parameters
    ----------
    spec : CampaignSpec
    run : int
        Index, ``0 <= run <`` the number of runs.

    Returns
    -------
    RunPlan

    Raises
    ------
    ParameterError
        When ``run`` is out of range.

    Examples
    --------
    >>> from fdikit.campaign.spec import CampaignSpec
    >>> spec = CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 20.0,
    ...     "plants": [{"name": "linear"}], "healthy": 1, "designs": [{"name": "k", "kind": "kalman"}],
    ...     "evaluators": [{"name": "t", "kind": "threshold"}]})
    >>> plan_run(spec, 5)
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: run 5 is not in the campaign: it has 1 runs (0 to 0)
    """
    if spec.sampling.random is not None:
        n = spec.sampling.random.runs
        if not 0 <= run < n:
            raise ParameterError(f"run {run} is not in the campaign: it has {n} runs (0 to {n - 1})")
        return _random_run(spec, run, _targets(spec))
    cells = _cells(spec)
    if not 0 <= run < len(cells):
        raise ParameterError(f"run {run} is not in the campaign: it has {len(cells)} runs (0 to {len(cells) - 1})")
    return _finish(spec, run, _rng(spec, run), *cells[run])

