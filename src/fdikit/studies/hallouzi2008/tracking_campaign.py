"""The maneuvering-target Monte Carlo as a campaign study (Hallouzi 2008, §2.4.2, Figs 2.4–2.5).

The campaign study ``target-tracking`` (:mod:`fdikit.campaign`): one run is one Monte-Carlo trajectory of
:func:`~fdikit.studies.hallouzi2008.target_tracking.target_tracking_monte_carlo` — the §2.4.2 maneuver
profile (half left turn in samples [100, 150], right turn in [250, 300]) with the process and measurement
noise of (2.67) — and every design is one of the filters the study compares.  Run ``k`` is exactly
``target_tracking_monte_carlo(runs=1, seed=<the run's plan seed>, filters=(<design>,))``: the study's own
code, with the run's seed, so a row is reproduced by the study function alone.

What a row holds
----------------
``fault = 'none'``: the maneuvers are no injected fault but the benchmark's fixed profile, the same in every
run (the thesis varies only the noise), so the plan holds fault-free runs only (``faults: []``,
``healthy`` = the number of runs).  The study has no decision rule (it scores estimates, not alarms), so the
detection columns say nothing: not detected, not missed, no false alarms, ``fault_free_hours = 0`` (the
report's false-alarm rates are then NaN instead of a claim of zero alarms), delays NaN, and the sweep
columns NaN delays / zero counts — the report's trade-off curve is flat for evaluator ``rmse``.  The figures
are in ``metrics``, per interval ``<i>`` of :data:`~fdikit.studies.hallouzi2008.target_tracking.INTERVALS`
(``straight_1``, ``left_half``, ``straight_2``, ``right``, ``straight_3``; those beyond the run left out):

``position_rmse_<i>``, ``velocity_rmse_<i>``, ``B_rmse_<i>``
    The study's summary figure of this run alone (``summary[filter][<i>]`` of the one-run Monte Carlo):
    the interval mean of the per-sample error norm [m], [m/s], [-].
``position_mse_<i>``, ``velocity_mse_<i>``, ``B_mse_<i>``
    The interval mean of the squared error.  Their mean over runs is exactly the interval mean of the
    squared Monte-Carlo RMSE (2.64) of those runs, ``mean_k RMSE_k²``; ``sqrt`` of it is the pooled RMSE
    of the interval.  (The study's own 100-run summary, ``mean_k RMSE_k``, is a mean of square roots of
    run means and is not a mean of per-run figures; it differs from the pooled figure by the spread of
    ``RMSE_k`` over the interval.)
``chatter``
    The study's chatter of the run: mean ``|Δμ_left|`` per sample in [100, 150].
``mu_left_mean``
    Mean left-turn weight over [120, 150] in CM coordinates (true 0.75; the command's "mean weights").

Plant: kind ``target-tracking`` (the default), no parameters (the noise of (2.67) is the benchmark's).
``duration`` is the run length [s] at ``T_s = 1`` s (400 in the thesis).  Design kinds and ``params``:
``dual_cmf`` (``lam``, default 0.9), ``ekf`` (``q_mu``, default 1e-2), ``imm`` (none).  Evaluator kind:
``rmse`` (no parameters).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["TargetTrackingStudy", "TARGET_TRACKING", "DESIGN_KINDS", "EVALUATOR_KINDS", "run_metrics"]

#: Design kind → its parameters and defaults (those of :func:`target_tracking_monte_carlo`).
DESIGN_KINDS = {"dual_cmf": {"lam": 0.9}, "ekf": {"q_mu": 1e-2}, "imm": {}}
#: Evaluator kinds (no decision: the figures of the run).
EVALUATOR_KINDS = ("rmse",)
_PLANT_KINDS = ("target-tracking",)


def _n_samples(duration: float) -> int:
    from fdikit.plants.target_tracking import TS

    return int(round(duration / TS))


def run_metrics(result) -> dict[str, float]:
    """The ``metrics`` of a row from a one-run :class:`TargetTrackingResult` of one filter (module docstring).

    Parameters
    ----------
    result : TargetTrackingResult
        ``target_tracking_monte_carlo(runs=1, filters=(f,), ...)``.

    Returns
    -------
    dict of str to float
        ``<quantity>_rmse_<interval>``, ``<quantity>_mse_<interval>``, ``chatter``, ``mu_left_mean``.

    Raises
    ------
    ParameterError
        When the result is not of one run and one filter.

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.64).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.target_tracking import target_tracking_monte_carlo
    >>> m = run_metrics(target_tracking_monte_carlo(runs=1, seed=3, n_samples=160, filters=("imm",)))
    >>> sorted(k for k in m if k.startswith("position"))
    ['position_mse_left_half', 'position_mse_straight_1', 'position_rmse_left_half', 'position_rmse_straight_1']
    """
    from fdikit.studies.hallouzi2008.target_tracking import INTERVALS

    if result.runs != 1 or len(result.filters) != 1:
        from fdikit.errors import ParameterError

        raise ParameterError(f"run_metrics takes a one-run, one-filter result; got {result.runs} runs of "
                             f"{len(result.filters)} filters")
    f = result.filters[0]
    n = result.t.size
    curves = {"position": result.rmse_position[f], "velocity": result.rmse_velocity[f], "B": result.rmse_B[f]}
    out: dict[str, float] = {}
    for name, (a, b) in INTERVALS.items():
        if b >= n:
            continue
        for q, c in curves.items():
            out[f"{q}_rmse_{name}"] = float(result.summary[f][name][q])
            out[f"{q}_mse_{name}"] = float(np.mean(c[a:b + 1] ** 2))
    out["chatter"] = float(result.chatter[f])
    if n > 150:
        out["mu_left_mean"] = float(result.cm_weights[f][120:151, 0].mean())
    return out


class TargetTrackingStudy:
    """The ``target-tracking`` campaign study (module docstring).

    References
    ----------
    Hallouzi 2008, §2.4.2 (the maneuvering-target benchmark).

    Examples
    --------
    >>> TARGET_TRACKING.fault_names(None, "maneuver")
    ()
    """

    name = "target-tracking"

    def fault_names(self, plant, kind: str) -> tuple[str, ...]:
        """None: the maneuvers are the fixed profile of every run, not injected faults."""
        return ()

    def check(self, spec) -> list[str]:
        """Problems with the spec's plants, faults, duration, designs and evaluators."""
        from fdikit.plants.target_tracking import TS

        problems = []
        for k, plant in enumerate(spec.plants):
            if (plant.kind or "target-tracking") not in _PLANT_KINDS:
                problems.append(f"plants.{k}.kind: unknown plant {plant.kind!r}; target-tracking has one plant: "
                                "target-tracking")
            for p in plant.params:
                problems.append(f"plants.{k}.params.{p}: unknown parameter; the target-tracking plant takes none "
                                "(the noise of Hallouzi 2008 (2.67) is the benchmark's)")
        for k, _fam in enumerate(spec.faults):
            problems.append(f"faults.{k}: target-tracking injects no faults (the maneuvers of §2.4.2 are in every "
                            "run); remove the entry and give the number of runs as healthy")
        n = _n_samples(spec.duration)
        if n < 1 or not math.isclose(n * TS, spec.duration, rel_tol=0, abs_tol=1e-9 * max(1.0, spec.duration)):
            problems.append(f"duration: {spec.duration} s is not a whole number of samples of {TS:g} s; give e.g. "
                            "400 (the thesis's run)")
        for k, d in enumerate(spec.designs):
            kind = d.kind or d.name
            if kind not in DESIGN_KINDS:
                problems.append(f"designs.{k}.kind: unknown design {kind!r}; choose from: {', '.join(DESIGN_KINDS)}")
                continue
            for p, v in d.params.items():
                if p not in DESIGN_KINDS[kind]:
                    problems.append(f"designs.{k}.params.{p}: unknown parameter; {kind} takes: "
                                    f"{', '.join(DESIGN_KINDS[kind]) or 'none'}")
                elif not (isinstance(v, int | float) and not isinstance(v, bool) and v > 0):
                    problems.append(f"designs.{k}.params.{p}: must be a positive number, got {v!r}")
                elif p == "lam" and not v <= 1:
                    problems.append(f"designs.{k}.params.lam: the forgetting factor must be in (0, 1], got {v!r}")
        for k, e in enumerate(spec.evaluators):
            kind = e.kind or e.name
            if kind not in EVALUATOR_KINDS:
                problems.append(f"evaluators.{k}.kind: unknown evaluator {kind!r}; choose from: "
                                f"{', '.join(EVALUATOR_KINDS)}")
            for p in e.params:
                problems.append(f"evaluators.{k}.params.{p}: unknown parameter; rmse takes none")
        return problems

    def setup(self, spec) -> dict:
        """Design name → (filter, its keyword arguments); nothing to calibrate."""
        out = {}
        for d in spec.designs:
            kind = d.kind or d.name
            out[d.name] = (kind, {**DESIGN_KINDS[kind], **d.params})
        return {"designs": out, "n_samples": _n_samples(spec.duration)}

    @staticmethod
    def _result(setup, run, design: str):
        from fdikit.studies.hallouzi2008.target_tracking import target_tracking_monte_carlo

        kind, params = setup["designs"][design]
        return target_tracking_monte_carlo(runs=1, seed=run.seed, filters=(kind,), n_samples=setup["n_samples"],
                                           **params)

    def run_chunk(self, setup, spec, runs: Sequence, levels: Sequence[float]) -> list[dict]:
        """One row per run × design × evaluator: the study's one-run Monte Carlo of the design's filter."""
        from fdikit.campaign.rows import score_row
        from fdikit.metrics import Score

        none = Score("none", None, False, None, 0, 0.0, False, "none", None)
        rows = []
        for run in runs:
            for d in spec.designs:
                metrics = run_metrics(self._result(setup, run, d.name))
                for e in spec.evaluators:
                    rows.append(score_row(run, d.name, e.name, none, [math.nan] * len(levels), [0] * len(levels),
                                          metrics))
        return rows

    def replay(self, setup, spec, run, design: str, evaluator: str) -> tuple:
        """``(trace, residuals, diagnosis)``: the trajectory, the error norms, the filter's weights (no alarms).

        The residuals are the run's position, velocity and B error norms per sample; the diagnosis holds the
        weights as probabilities (IMM: its 3 modes; CM filters: left and right turn) and never alarms.
        """
        from fdikit.diagnosis import Diagnosis
        from fdikit.residuals import Residuals
        from fdikit.studies.hallouzi2008.target_tracking import target_tracking_trace

        res = self._result(setup, run, design)
        f = res.filters[0]
        child = np.random.SeedSequence(run.seed).spawn(1)[0]
        trace = target_tracking_trace(np.random.default_rng(child), setup["n_samples"])
        r = np.column_stack([res.rmse_position[f], res.rmse_velocity[f], res.rmse_B[f]])
        residuals = Residuals(res.t, r, ("position_error", "velocity_error", "B_error"), ())
        w = res.mean_weights[f]
        hyp = ("straight", "left_turn", "right_turn") if f == "imm" else ("left_turn", "right_turn")
        n = res.t.size
        diagnosis = Diagnosis(res.t, np.zeros(n, bool), np.zeros((n, 0), bool), (), np.full(n, "none"),
                              probabilities=w, hypotheses=hyp)
        return trace, residuals, diagnosis


#: The registered study object.
TARGET_TRACKING = TargetTrackingStudy()
