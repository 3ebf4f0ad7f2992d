"""Campaigns: Monte Carlo over plants × faults × designs × evaluators, resumable, on a process pool or Dask.

A campaign spec (YAML, :mod:`fdikit.campaign.spec`) names a study, its plants, fault families, designs,
evaluators, seeds and run length; the plan (:mod:`fdikit.campaign.plan`) derives every run by itself; the
engine (:mod:`fdikit.campaign.engine`) computes chunks of runs on workers and stores each chunk atomically
(:mod:`fdikit.campaign.store`); the statistics and the HTML report (:mod:`fdikit.campaign.stats`,
:mod:`fdikit.campaign.report`) come from the stored table alone.  ``fdikit campaign run`` / ``report``.

* :mod:`fdikit.campaign.spec` — the spec, checked by pydantic and by the study.
* :mod:`fdikit.campaign.plan` — the runs and their seeds.
* :mod:`fdikit.campaign.studies` — the study protocol, the registered studies, the shipped specs.
* :mod:`fdikit.campaign.evaluation` — evaluators of residual studies: kinds, calibration, rows.
* :mod:`fdikit.campaign.rows`, :mod:`fdikit.campaign.schema` — the result rows and their table.
* :mod:`fdikit.campaign.store` — the results folder, atomic chunk files, resumption.
* :mod:`fdikit.campaign.engine` — local process pool and Dask backends.
* :mod:`fdikit.campaign.stats`, :mod:`fdikit.campaign.report`, :mod:`fdikit.campaign.report_plots` — statistics
  with intervals, the trade-off curve, the report.
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "spec": ["CampaignSpec", "load_campaign"],
        "plan": ["RunPlan", "plan_runs", "plan_run"],
        "studies": ["Study", "get_study", "shipped_specs"],
        "engine": ["run_campaign", "replay", "CampaignRun"],
        "store": ["load_results"],
        "stats": ["campaign_statistics", "CampaignStatistics"],
        "report": ["write_report"],
    },
)
