"""The campaign specification: what to run, checked before any work.

A campaign is a YAML file (or a mapping) with these entries, validated by pydantic; every mistake is
reported at once, each line naming the entry (``faults.0.size.uniform``) and what would be accepted:

``name``
    Name of the campaign (used in the report).
``study``
    What is simulated and how: a registered study (``path-linear``, ...: :data:`fdikit.campaign.studies.STUDIES`)
    or ``"package.module:attribute"`` naming a user's own study object (:class:`fdikit.campaign.studies.Study`).
``seed``
    The campaign seed (>= 0).  Run ``k`` draws everything random — its sampled parameters and its simulation
    seed — from ``numpy.random.SeedSequence(seed, spawn_key=(k,))``, so every run is reproducible by itself
    (:func:`fdikit.campaign.plan.plan_run`) and independent of how the runs are split over workers.
``duration``
    Length of each run [s].
``plants``
    Plants or operating points: a list of ``{name, params}``; ``params`` are the study's (e.g. the noise level).
``faults``
    A list of fault families ``{kind, targets, size, onset}``: ``targets`` is ``"all"`` or a list of the study's
    fault names; ``size`` and ``onset`` are ``{values: [...]}`` (a grid axis), ``{uniform: [low, high]}`` or
    ``{loguniform: [low, high]}`` (drawn per run).
``healthy``
    Fault-free runs per plant (grid sampling) or their fraction of the runs (random sampling, ``0 <= x < 1``).
``sampling``
    ``{grid: {repeats: n}}`` — every plant × fault kind × target × size value × onset value, ``n`` times,
    after ``healthy`` fault-free runs per plant — or ``{random: {runs: n}}``: ``n`` runs, each drawing its
    plant, whether it is fault-free, its fault family, target, size and onset.
``designs``, ``evaluators``
    Lists of ``{name, kind, params}``: the residual generators and the decision rules of the study; every
    design is scored with every evaluator on the same residuals.
``sweep``
    ``{low, high, points}``: the threshold scale factors (log-spaced, 1 always included) at which each run
    stores its detection delay and its false alarms, for the trade-off curve of the report.
``chunk_size``
    Runs per task (default 50).  Part of the specification, not of the machine: the same chunks are computed
    whatever the number of workers, which is what makes results bit-identical across worker counts.

Examples
--------
>>> spec = CampaignSpec.model_validate({
...     "name": "demo", "study": "path-linear", "duration": 20.0,
...     "plants": [{"name": "linear"}], "faults": [{"kind": "bias", "targets": ["yaw_rate_sensor"]}],
...     "designs": [{"name": "bank", "kind": "beard-jones"}],
...     "evaluators": [{"name": "threshold", "kind": "threshold"}]})
>>> spec.sampling.grid.repeats, spec.faults[0].size.values, spec.chunk_size
(1, [1.0], 50)
>>> len(sweep_levels(spec.sweep)), 1.0 in sweep_levels(spec.sweep)
(25, True)
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from fdikit.errors import DataError, ParameterError

__all__ = ["CampaignSpec", "Distribution", "FaultFamily", "Named", "Sampling", "Sweep", "load_campaign",
           "spec_fingerprint", "sweep_levels"]

_STRICT = ConfigDict(extra="forbid")


class Distribution(BaseModel):
    """A parameter axis: ``values`` (a grid), or ``uniform`` / ``loguniform`` ``[low, high]`` drawn per run.

    Examples
    --------
    >>> Distribution(uniform=[4.0, 8.0]).uniform
    [4.0, 8.0]
    """

    model_config = _STRICT
    values: list[float] | None = None
    uniform: list[float] | None = Field(None, min_length=2, max_length=2)
    loguniform: list[float] | None = Field(None, min_length=2, max_length=2)

    @model_validator(mode="after")
    def _one(self):
        given = [k for k in ("values", "uniform", "loguniform") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of values, uniform, loguniform (got {given or 'none'})")
        if self.values is not None and not self.values:
            raise ValueError("values is empty; give at least one value")
        for k in ("uniform", "loguniform"):
            lim = getattr(self, k)
            if lim is not None and not lim[0] <= lim[1]:
                raise ValueError(f"{k}: low {lim[0]} is above high {lim[1]}")
        if self.loguniform is not None and self.loguniform[0] <= 0:
            raise ValueError(f"loguniform needs positive limits, got {self.loguniform}")
        return self

    @property
    def grid(self) -> list[float | None]:
        """The grid values; ``[None]`` (one cell, drawn per run) for a distribution."""
        return list(self.values) if self.values is not None else [None]

    def draw(self, rng) -> float:
        """One value: uniform / log-uniform from ``rng``, or a uniform choice among ``values``."""
        import numpy as np

        if self.uniform is not None:
            return float(rng.uniform(*self.uniform))
        if self.loguniform is not None:
            return float(np.exp(rng.uniform(*np.log(self.loguniform))))
        return float(self.values[int(rng.integers(len(self.values)))])


class FaultFamily(BaseModel):
    """Faults of one kind on some targets, with their size and onset axes.

    Examples
    --------
    >>> FaultFamily(kind="bias", targets="all").onset.values
    [5.0]
    """

    model_config = _STRICT
    kind: str
    targets: Literal["all"] | list[str] = "all"
    size: Distribution = Field(default_factory=lambda: Distribution(values=[1.0]))
    onset: Distribution = Field(default_factory=lambda: Distribution(values=[5.0]))


class Named(BaseModel):
    """A plant, design or evaluator: ``name`` (unique in its list), ``kind`` and the study's ``params``.

    Examples
    --------
    >>> Named(name="bank", kind="beard-jones").params
    {}
    """

    model_config = _STRICT
    name: str = Field(pattern=r"^[A-Za-z0-9_.+-]{1,60}$")
    kind: str | None = None
    params: dict[str, Any] = Field(default_factory=dict)


class _Grid(BaseModel):
    model_config = _STRICT
    repeats: int = Field(1, ge=1)


class _Random(BaseModel):
    model_config = _STRICT
    runs: int = Field(ge=1)


class Sampling(BaseModel):
    """``{grid: {repeats}}`` or ``{random: {runs}}`` (module docstring).

    Examples
    --------
    >>> Sampling(random={"runs": 100}).random.runs
    100
    """

    model_config = _STRICT
    grid: _Grid | None = None
    random: _Random | None = None

    @model_validator(mode="after")
    def _one(self):
        if (self.grid is None) == (self.random is None):
            if self.random is None:
                self.grid = _Grid()
                return self
            raise ValueError("give one of grid and random, not both")
        return self


class Sweep(BaseModel):
    """Threshold scale factors ``low … high`` (log-spaced, ``points`` of them, 1 included).

    Examples
    --------
    >>> Sweep(low=0.5, high=2.0, points=3).points
    3
    """

    model_config = _STRICT
    low: float = Field(0.5, gt=0)
    high: float = Field(4.0, gt=0)
    points: int = Field(24, ge=1, le=200)

    @model_validator(mode="after")
    def _order(self):
        if not self.low <= 1.0 <= self.high:
            raise ValueError(f"the sweep [{self.low}, {self.high}] must contain 1 (the nominal threshold)")
        return self


class CampaignSpec(BaseModel):
    """A whole campaign (module docstring).

    Examples
    --------
    >>> CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 1.0,
    ...     "plants": [{"name": "p"}], "faults": [], "healthy": 3, "designs": [{"name": "d"}],
    ...     "evaluators": [{"name": "e"}]}).healthy
    3.0
    """

    model_config = _STRICT
    name: str = Field(min_length=1)
    study: str = Field(min_length=1)
    description: str = ""
    seed: int = Field(0, ge=0)
    duration: float = Field(gt=0)
    plants: list[Named] = Field(min_length=1)
    faults: list[FaultFamily] = Field(default_factory=list)
    healthy: float = Field(0, ge=0)
    sampling: Sampling = Field(default_factory=Sampling)
    designs: list[Named] = Field(min_length=1)
    evaluators: list[Named] = Field(min_length=1)
    sweep: Sweep = Field(default_factory=Sweep)
    chunk_size: int = Field(50, ge=1, le=100_000)

    @model_validator(mode="after")
    def _consistent(self):
        for what in ("plants", "designs", "evaluators"):
            names = [n.name for n in getattr(self, what)]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise ValueError(f"{what}: names must be unique, {dup} appear more than once")
        if self.sampling.random is not None:
            if not self.healthy < 1:
                raise ValueError(f"healthy = {self.healthy}: with random sampling it is the fraction of fault-free "
                                 "runs, 0 <= healthy < 1")
        elif self.healthy != int(self.healthy):
            raise ValueError(f"healthy = {self.healthy}: with grid sampling it is a number of runs per plant")
        if not self.faults and self.healthy == 0:
            raise ValueError("no runs: no faults and healthy = 0; give a fault family or fault-free runs")
        for k, fam in enumerate(self.faults):
            if fam.onset.values is not None and max(fam.onset.values) >= self.duration:
                raise ValueError(f"faults.{k}.onset: {max(fam.onset.values)} s is not before the end of the run "
                                 f"(duration {self.duration} s)")
            for axis in ("uniform", "loguniform"):
                lim = getattr(fam.onset, axis)
                if lim is not None and lim[1] >= self.duration:
                    raise ValueError(f"faults.{k}.onset.{axis}: {lim[1]} s is not before the end of the run "
                                     f"(duration {self.duration} s)")
        return self


def sweep_levels(sweep: Sweep) -> list[float]:
    """The sweep's threshold scale factors: ``points`` log-spaced from ``low`` to ``high``, plus 1.

    Parameters
    ----------
    sweep : Sweep

    Returns
    -------
    list of float
        Increasing, without repeats, 1.0 exactly among them.

    Examples
    --------
    >>> sweep_levels(Sweep(low=0.5, high=2.0, points=3))
    [0.5, 1.0, 2.0]
    """
    import numpy as np

    levels = np.geomspace(sweep.low, sweep.high, sweep.points) if sweep.points > 1 else np.array([sweep.low])
    levels = np.unique(np.round(np.append(levels, 1.0), 12))
    return [float(v) for v in levels]


def spec_fingerprint(spec: CampaignSpec) -> str:
    """SHA-256 of the spec's canonical JSON and the fdikit version: what a results folder is tied to.

    Parameters
    ----------
    spec : CampaignSpec

    Returns
    -------
    str
        64 hex digits.

    Examples
    --------
    >>> s = CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 1.0,
    ...     "plants": [{"name": "p"}], "healthy": 1, "designs": [{"name": "d"}], "evaluators": [{"name": "e"}]})
    >>> len(spec_fingerprint(s)), spec_fingerprint(s) == spec_fingerprint(s.model_copy())
    (64, True)
    """
    import fdikit

    text = json.dumps({"spec": spec.model_dump(mode="json"), "fdikit": fdikit.__version__}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _spec_error(where: str, exc: ValidationError) -> ParameterError:
    lines = []
    for e in exc.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top)"
        msg = e["msg"].removeprefix("Value error, ")
        if e["type"] == "extra_forbidden":
            msg = "unknown entry (check its spelling; the entries are listed in fdikit.campaign.spec)"
        lines.append(f"  {loc}: {msg}")
    return ParameterError(f"the campaign spec {where} is not valid:\n" + "\n".join(lines))


def load_campaign(source: str | os.PathLike | dict) -> CampaignSpec:
    """Read and check a campaign spec: a YAML file, the name of a shipped spec, or a mapping.

    Parameters
    ----------
    source : str, PathLike or dict
        ``spec.yaml``; a shipped spec's name (``path-linear``, listed by
        :func:`fdikit.campaign.studies.shipped_specs`); or the spec as a mapping.

    Returns
    -------
    CampaignSpec
        Validated; the study's own check (plant, fault, design and evaluator names and parameters)
        runs too (:func:`fdikit.campaign.studies.check_spec`).

    Raises
    ------
    DataError
        When the file does not exist or is not YAML.
    ParameterError
        Listing every invalid entry, each by its place in the spec.

    Examples
    --------
    >>> load_campaign({"name": "x", "study": "path-linear", "duration": -1.0})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: the campaign spec (a mapping) is not valid:
      duration: Input should be greater than 0
      plants: Field required
      designs: Field required
      evaluators: Field required
    """
    from fdikit.campaign.studies import check_spec, shipped_specs

    where = "(a mapping)"
    if isinstance(source, dict):
        data = source
    else:
        path = Path(source)
        shipped = shipped_specs()
        if not path.exists() and str(source) in shipped:
            path = shipped[str(source)]
        if not path.is_file():
            raise DataError(f"campaign spec {source} does not exist; give a YAML file or one of the shipped specs: "
                            f"{', '.join(shipped)}")
        import yaml

        try:
            data = yaml.safe_load(path.read_text())
        except yaml.YAMLError as exc:
            raise DataError(f"campaign spec {path} is not valid YAML: {exc}") from None
        if not isinstance(data, dict):
            raise DataError(f"campaign spec {path} must be a YAML mapping (name: ..., study: ...), "
                            f"got {type(data).__name__}")
        where = str(path)
    try:
        spec = CampaignSpec.model_validate(data)
    except ValidationError as exc:
        raise _spec_error(where, exc) from None
    check_spec(spec, where)
    return spec
