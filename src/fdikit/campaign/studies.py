"""What a campaign simulates: the study protocol, the registered studies and the shipped specs.

A study turns the spec's plants, faults, designs and evaluators into result rows.  fdikit registers its
own (:data:`STUDIES`, imported lazily); a spec may instead name any object implementing :class:`Study`
as ``"package.module:attribute"`` — the way to run a campaign on one's own plant.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from fdikit.errors import ParameterError

if TYPE_CHECKING:
    from fdikit.campaign.plan import RunPlan
    from fdikit.campaign.spec import CampaignSpec, Named

__all__ = ["Study", "STUDIES", "get_study", "check_spec", "shipped_specs"]

#: Registered studies: name → ``"module:attribute"`` of the study object.
STUDIES = {
    "path-linear": "fdikit.studies.path1996.campaign:PATH_LINEAR",
    "path-nonlinear": "fdikit.studies.path1996.nonlinear_campaign:PATH_NONLINEAR",
    "target-tracking": "fdikit.studies.hallouzi2008.tracking_campaign:TARGET_TRACKING",
    "multiple-model": "fdikit.studies.hallouzi2008.multiple_model_campaign:MULTIPLE_MODEL",
    "b747-lip": "fdikit.studies.hallouzi2008.b747_campaign:B747_LIP",
    "b747-ftc": "fdikit.studies.hallouzi2008.ftc_campaign:B747_FTC",
}


@runtime_checkable
class Study(Protocol):
    """What the campaign engine needs from a study.

    ``setup`` is computed once per worker process (designs, calibrated evaluators) and must be
    deterministic; ``run_chunk`` must give the same rows for the same runs whatever ran before in the
    process.  Rows have the columns of :data:`fdikit.campaign.schema.COLUMNS`
    (:func:`fdikit.campaign.rows.score_row` builds one from a :class:`~fdikit.metrics.Score`).

    Attributes
    ----------
    name : str
        The name specs use (``study:``).

    Examples
    --------
    >>> isinstance(get_study("path-linear"), Study)
    True
    """

    name: str

    def fault_names(self, plant: Named, kind: str) -> Sequence[str]:
        """The faults of ``kind`` the study can inject on ``plant`` (what ``targets: all`` means)."""

    def check(self, spec: CampaignSpec) -> list[str]:
        """Problems with the spec's plants, faults, designs and evaluators, each ``"<entry>: <what is wrong>"``."""

    def setup(self, spec: CampaignSpec) -> Any:
        """Designs and calibrated evaluators (once per worker)."""

    def run_chunk(self, setup: Any, spec: CampaignSpec, runs: Sequence[RunPlan], levels: Sequence[float]) -> list[dict]:
        """Result rows of ``runs``: one per run × design × evaluator, in that order."""

    def replay(self, setup: Any, spec: CampaignSpec, run: RunPlan, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)`` of one run, as the campaign computed it."""


def get_study(name: str) -> Study:
    """The study a spec names: a registered one or ``"package.module:attribute"``.

    Parameters
    ----------
    name : str

    Returns
    -------
    Study

    Raises
    ------
    ParameterError
        When the name is neither registered nor importable, or the object is not a :class:`Study`.

    Examples
    --------
    >>> get_study("path-linear").name
    'path-linear'
    >>> get_study("nope")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: study 'nope' is not registered (path-linear, ...) ... naming a study object
    """
    target = STUDIES.get(name, name)
    if ":" not in target:
        raise ParameterError(f"study {name!r} is not registered ({', '.join(STUDIES)}) and is not "
                             "'package.module:attribute' naming a study object")
    module, _, attr = target.partition(":")
    try:
        obj = getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError) as exc:
        raise ParameterError(f"study {name!r}: cannot import {target} ({exc})") from None
    if not isinstance(obj, Study):
        raise ParameterError(f"study {name!r}: {target} is not a campaign study (it needs name, fault_names, check, "
                             "setup, run_chunk and replay: fdikit.campaign.studies.Study)")
    return obj


def check_spec(spec: CampaignSpec, where: str = "(a mapping)") -> None:
    """Run the study's own check of a spec.

    Parameters
    ----------
    spec : CampaignSpec
    where : str
        How messages name the spec (its file).

    Raises
    ------
    ParameterError
        Listing every problem the study found.

    Examples
    --------
    >>> from fdikit.campaign.spec import CampaignSpec
    >>> spec = CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 20.0,
    ...     "plants": [{"name": "linear"}], "healthy": 1, "designs": [{"name": "b", "kind": "beard-jonse"}],
    ...     "evaluators": [{"name": "t", "kind": "threshold"}]})
    >>> check_spec(spec)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: the campaign spec (a mapping) is not valid for study 'path-linear':
      designs.0.kind: unknown design 'beard-jonse'; choose from: beard-jones, ...
    """
    problems = get_study(spec.study).check(spec)
    if problems:
        raise ParameterError(f"the campaign spec {where} is not valid for study {spec.study!r}:\n"
                             + "\n".join(f"  {p}" for p in problems))


def shipped_specs() -> dict[str, Path]:
    """The campaign specs shipped with fdikit: name → file (``fdikit/campaign/specs/<name>.yaml``).

    Returns
    -------
    dict of str to Path

    Examples
    --------
    >>> "path-linear" in shipped_specs()
    True
    """
    folder = Path(__file__).with_name("specs")
    return {p.stem: p for p in sorted(folder.glob("*.yaml"))}
