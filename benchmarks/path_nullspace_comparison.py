"""The exact nullspace bank against the report's Beard–Jones bank on the nonlinear PATH car at realistic sensor noise.

The runs and decision logic of ``fdikit path-evaluation`` (:func:`fdikit.studies.path1996.nonlinear_table.
path_evaluation_table`): per road, one fault-free run sets the processors' thresholds, a second independent one
counts their false alarms, one labelled run per fault trains the whitened MHSSPRT, and each of the 15 nominal
faults at t = 2 s is scored on a fresh run (20 s); seeds drawn exactly as there (seed 0 and both roads give the
same runs as ``docs/methods/nonlinear_vehicle.md``'s table).  Sensor noise :data:`NOISE_STD` (per sample, 100 Hz).
The processors are refitted here with the same calls because ``path_evaluation_table`` accepts only its own
bank names.

Banks: ``beard-jones`` (:func:`~fdikit.studies.path1996.bank.path_bank`), ``nullspace`` (``efdisyn`` with the
generic combination, :func:`~fdikit.studies.path1996.nullspace_bank.path_nullspace_bank`), ``nullspace-noise``
(the same rows combined for the best DC fault-to-noise ratio), ``nullspace-gap`` (``afdsyn(selection="gap")`` per
residual: all basis rows combined for the best DC gap, the noise whitened), optionally ``game`` and ``kalman``.

Also per bank: filter orders; the fault-to-noise gap ``fdif2ngap`` at ω = 0 of each (filter, fault) residual
group on the discrete linear group model (faults in nominal sizes, noise inputs ``diag(NOISE_STD)``; β = 1 for a
scaled residual); the measured fault-free rms of each scaled residual group on the test run (1 = a nominal fault).

Run from the repository root::

    python benchmarks/path_nullspace_comparison.py --hours 1 --jobs 2 --out /tmp/path_nullspace.md
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402

ROADS = ("smooth", "rough")
ONSET = 2.0
#: Sample time of the sensors and the generators [s] (the evaluation's).
DT = 0.01
BANK_NAMES = ("beard-jones", "nullspace", "nullspace-noise", "nullspace-gap", "game", "kalman")


def make_setup(banks):
    """The evaluation setup with the nullspace banks added, restricted to ``banks``."""
    from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD, EvaluationSetup, evaluation_setup
    from fdikit.studies.path1996.nullspace_bank import path_nullspace_bank

    s = evaluation_setup()
    pair = (s.models.model12, s.models.method1)
    all_banks = dict(s.banks)
    all_banks["nullspace"] = path_nullspace_bank(pair, s.nominal)
    all_banks["nullspace-noise"] = path_nullspace_bank(pair, s.nominal, noise_std=NOISE_STD, dt=DT)
    all_banks["nullspace-gap"] = path_nullspace_bank(pair, s.nominal, noise_std=NOISE_STD, dt=DT, criterion="gap")
    chosen = {b: all_banks[b] for b in banks}
    gens = {b: (g.generator if g.generator.dt else g.generator.discretize(DT)) for b, g in chosen.items()}
    return EvaluationSetup(s.car, s.operating_point, s.models, s.nominal, chosen, gens, default=banks[0])


def fit_processors(groups, healthy, labelled):
    """The three default processors of the evaluation, fitted as ``nonlinear_table`` fits them."""
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator, Whitened
    from fdikit.studies.path1996.nonlinear_table import PROCESSORS, whitened_mhsprt

    out = {PROCESSORS["threshold"]: ThresholdEvaluator(groups=groups, persistence=(5, 10)).fit(
        healthy, false_alarms_per_hour=1)}
    innov = Whitened(ThresholdEvaluator(), order=5).fit(healthy, false_alarm_prob=1e-3).whiten(healthy)
    shift = 4.0 * np.nanstd(innov.r, axis=0, ddof=1)
    out[PROCESSORS["cusum-whitened"]] = Whitened(CusumEvaluator(groups=groups), 5).fit(
        healthy, mean_time_between_false_alarms=3600.0, shift=shift)
    out[PROCESSORS["mhsprt-whitened"]] = whitened_mhsprt(healthy, labelled)
    return out


def linear_figures(setup, name, noise_std) -> dict:
    """Orders and the fault-to-noise gaps at ω = 0 of each (filter, fault) group on the linear group models."""
    from fdikit.analysis import fdif2ngap
    from fdikit.studies.path1996.nullspace_bank import group_model

    bank = setup.banks[name]
    gen = setup.generators[name]
    out = {"orders": {}, "gaps": {}}
    for g, d in bank.designs.items():
        out["orders"][g] = list(getattr(d, "orders", ())) or [int(d.generator.n)]
    if name == "kalman":
        return out
    pair = (setup.models.model12, setup.models.method1)
    for g in bank.designs:
        m, faults = group_model(pair, g)
        sigma = np.array([noise_std[o] for o in m.outputs])
        cols = m.index("f", list(faults))
        nom = np.array([setup.nominal[f] for f in faults])
        md = m.replace(Bf=m.Bf[:, cols] * nom, Df=m.Df[:, cols] * nom, faults=faults,
                       Bw=np.zeros((m.n, m.p)), Dw=np.diag(sigma), noise=tuple(f"w_{o}" for o in m.outputs)
                       ).discretize(DT)
        form = gen.internal_form(md)
        names = {f: [r for r in gen.residuals if r.startswith(f"{g}:{f}[")] for f in faults}
        sub = form.submodel(outputs=[r for f in faults for r in names[f]])
        gap = fdif2ngap(sub, np.eye(len(faults), dtype=bool), freqs=[0.0], groups=names)
        out["gaps"].update({f"{g}:{f}": float(v) for f, v in zip(faults, np.atleast_1d(gap.ratio))})
    return out


def off_nominal(setup, banks) -> dict:
    """Peak scaled group magnitudes of the §5.1.1 off-nominal run, per scaled bank."""
    from fdikit.studies.path1996.nonlinear_evaluation import off_nominal_peaks, off_nominal_run

    run = off_nominal_run(setup)
    return {b: off_nominal_peaks(setup, bank=b, run=run) for b in banks if setup.banks[b].scales}


def evaluate_road(road: str, k_road: int, n_roads: int, banks, hours: float, test_hours: float, seed: int,
                  duration: float = 20.0) -> dict:
    """One road of the evaluation for every bank (the loop of ``path_evaluation_table``)."""
    from fdikit.metrics import score
    from fdikit.studies.path1996.nonlinear_evaluation import fault_run, group_magnitudes
    from fdikit.studies.path1996.nonlinear_table import FAULTS

    t0 = time.perf_counter()
    setup = make_setup(banks)
    faults = list(FAULTS)
    per_road = 2 + 2 * len(faults)
    all_seeds = np.random.default_rng(seed).integers(2**31, size=per_road * n_roads)
    seeds = [int(v) for v in all_seeds[k_road * per_road:(k_road + 1) * per_road]]
    healthy = fault_run(setup, None, road, duration=hours * 3600.0, rng=seeds[0])
    labelled = [fault_run(setup, f, road, duration=duration, rng=sd) for f, sd in zip(faults, seeds[2:2 + len(faults)])]
    evaluators = {b: fit_processors(setup.banks[b].groups, healthy.residuals[b].slice(start=ONSET),
                                    [(run.fault, run.residuals[b]) for run in labelled]) for b in banks}
    del healthy, labelled
    test = fault_run(setup, None, road, duration=test_hours * 3600.0, rng=seeds[1])
    out = {"road": road, "false_alarms": {}, "rows": [], "rms": {}}
    for b in banks:
        res = test.residuals[b].slice(start=ONSET)
        if setup.banks[b].scales:
            out["rms"][b] = {g: float(np.sqrt(np.mean(v**2))) for g, v in group_magnitudes(res).items()}
        for pname, ev in evaluators[b].items():
            s = score(test.trace, ev.run(test.residuals[b]))
            out["false_alarms"][f"{b}|{pname}"] = [int(s.false_alarms), float(s.fault_free_hours)]
    del test
    for f, sd in zip(faults, seeds[2 + len(faults):]):
        run = fault_run(setup, f, road, duration=duration, rng=sd)
        for b in banks:
            for pname, ev in evaluators[b].items():
                s = score(run.trace, ev.run(run.residuals[b]))
                out["rows"].append([b, f, pname, bool(s.detected), bool(s.isolation_correct), str(s.isolated)])
    out["seconds"] = time.perf_counter() - t0
    return out


def markdown(results, linear, banks, hours, test_hours) -> str:
    """The comparison table."""
    from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD
    from fdikit.studies.path1996.nonlinear_table import PROCESSORS

    procs = [PROCESSORS[k] for k in ("threshold", "cusum-whitened", "mhsprt-whitened")]
    lines = [f"Noise per sample at 100 Hz: {', '.join(f'{k} {v:g}' for k, v in NOISE_STD.items())}.",
             f"Fault-free calibration {hours:g} h, false-alarm test {test_hours:g} h per road; 15 faults × 20 s "
             "(nominal bias at 2 s).", "",
             "| road | bank | " + " | ".join(f"{p} det./iso. (FA/h)" for p in procs) + " |",
             "|---|---|" + "---|" * len(procs)]
    for r in results:
        for b in banks:
            cells = []
            for p in procs:
                rows = [x for x in r["rows"] if x[0] == b and x[2] == p]
                n, h = r["false_alarms"][f"{b}|{p}"]
                cells.append(f"{sum(x[3] for x in rows)} / {sum(x[4] for x in rows)} ({n} in {h:.2f} h)")
            lines.append(f"| {r['road']} | {b} | " + " | ".join(cells) + " |")
    lines += ["", "| bank | filter orders | fdif2ngap at ω=0 min / median | fault-free rms of scaled groups "
              "median / max (smooth; rough) |", "|---|---|---|---|"]
    for b in banks:
        lin = linear[b]
        orders = "; ".join(f"{g}: {','.join(map(str, o))}" for g, o in lin["orders"].items())
        gaps = np.array(list(lin["gaps"].values()))
        gtxt = f"{gaps.min():.3g} / {np.median(gaps):.3g}" if gaps.size else "—"
        rms = []
        for r in results:
            v = np.array(list(r["rms"].get(b, {}).values()))
            rms.append(f"{np.median(v):.3g} / {v.max():.3g}" if v.size else "—")
        lines.append(f"| {b} | {orders} | {gtxt} | {'; '.join(rms)} |")
    lines += ["", "Per-group fault-free rms (scaled; 1 = nominal fault) and gap:", "",
              "| group | " + " | ".join(f"{b} rms {r['road']}" for b in banks for r in results
                                      if b in r["rms"]) + " | " + " | ".join(f"{b} gap" for b in banks
                                                                            if linear[b]["gaps"]) + " |"]
    cols = [(b, r) for b in banks for r in results if b in r["rms"]]
    gcols = [b for b in banks if linear[b]["gaps"]]
    lines.append("|---|" + "---|" * (len(cols) + len(gcols)))
    keys = list(linear[gcols[0]]["gaps"]) if gcols else []
    for k in keys:
        f = k.split(":", 1)[1]
        g = k.split(":", 1)[0]
        cell = [f"{r['rms'][b].get(k, float('nan')):.3g}" for b, r in cols]
        gap = [f"{linear[b]['gaps'].get(k, float('nan')):.3g}" for b in gcols]
        lines.append(f"| {g}:{f} | " + " | ".join(cell + gap) + " |")
    lines += ["", "Per fault, whitened MHSSPRT / threshold isolated as:", ""]
    for r in results:
        for b in banks:
            for p in (procs[2], procs[0]):
                rows = [x for x in r["rows"] if x[0] == b and x[2] == p]
                miss = [f"{x[1]}→{x[5]}" for x in rows if not x[4]]
                lines.append(f"- {r['road']}, {b}, {p}: not isolated {len(miss)}: {', '.join(miss) or '—'}")
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=1.0, help="fault-free calibration run per road [h]")
    parser.add_argument("--test-hours", type=float, default=None, help="false-alarm test run per road [h]")
    parser.add_argument("--roads", nargs="+", default=list(ROADS), choices=ROADS)
    parser.add_argument("--banks", nargs="+", default=["beard-jones", "nullspace", "nullspace-noise"],
                        choices=BANK_NAMES)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--out", default=None, help="write the markdown table (and a .json of the raw rows) here")
    a = parser.parse_args(argv)
    from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD

    test_hours = a.test_hours or a.hours
    t0 = time.perf_counter()
    args = [(road, k, len(a.roads), a.banks, a.hours, test_hours, a.seed) for k, road in enumerate(a.roads)]
    if a.jobs > 1:
        with ProcessPoolExecutor(min(a.jobs, len(args))) as pool:
            results = list(pool.map(evaluate_road, *zip(*args)))
    else:
        results = [evaluate_road(*x) for x in args]
    setup = make_setup(a.banks)
    linear = {b: linear_figures(setup, b, NOISE_STD) for b in a.banks}
    text = markdown(results, linear, a.banks, a.hours, test_hours)
    off = off_nominal(setup, a.banks)
    text += ("\n\nOff-nominal run (+2° throttle, no fault, no noise, smooth, 60 s; the report: every scaled "
             "group < 0.25):\n\n")
    text += "\n".join(f"- {b}: largest {max(pk.values()):.3g}; above 0.25: " + (", ".join(
        f"{k} {v:.3g}" for k, v in pk.items() if v > 0.25) or "none") for b, pk in off.items())
    text += f"\n\nWall time {time.perf_counter() - t0:.0f} s (per road: " + ", ".join(
        f"{r['road']} {r['seconds']:.0f} s" for r in results) + f"), seed {a.seed}, jobs {a.jobs}."
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")
        with open(a.out.rsplit(".", 1)[0] + ".json", "w") as fh:
            json.dump({"results": results, "linear": linear, "off_nominal": off}, fh)


if __name__ == "__main__":
    main()
