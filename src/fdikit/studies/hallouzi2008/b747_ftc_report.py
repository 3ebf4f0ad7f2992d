"""The §6.5 B747 flights of Hallouzi 2008 as files: per-flight data, plots, a table and an HTML page.

:func:`write_b747_ftc` flies every scenario of :mod:`fdikit.studies.hallouzi2008.b747_ftc` with the FTC
(SPC + IMM reconfiguration), with the SPC kept in its nominal configuration (no reconfiguration) for the
two anticipated faults, and with the fixed LQR autopilot; each flight is kept in the output folder as soon
as it is done (:class:`fdikit.resume.RunStore`), so a killed run resumes. Then it writes per scenario the
references and responses, the surfaces and throttles and (for the FDI scenarios) the mode probabilities;
the reciprocal condition number of ``R11`` of every SPC flight; ``ftc_b747.md`` / ``.csv`` with the
isolation time next to the thesis's, the tracking errors per phase and the surface use; and
``report.html``.

References
----------
Hallouzi 2008, §6.5, Figs. 6.2–6.13.
"""

from __future__ import annotations

import base64
import html
import io

import numpy as np

__all__ = ["FLIGHTS", "THESIS_ISOLATION", "write_b747_ftc", "flight_summary"]

#: ``(key, scenario, controller, reconfigure)`` of the flights written.
FLIGHTS = (
    ("nominal-ftc", "nominal", "spc", True), ("nominal-autopilot", "nominal", "autopilot", False),
    ("elevator-ftc", "elevator", "spc", True), ("elevator-spc-fixed", "elevator", "spc", False),
    ("elevator-autopilot", "elevator", "autopilot", False),
    ("rudder-ftc", "rudder", "spc", True), ("rudder-spc-fixed", "rudder", "spc", False),
    ("rudder-autopilot", "rudder", "autopilot", False),
    ("bijlmer-ftc", "bijlmer", "spc", False), ("bijlmer-autopilot", "bijlmer", "autopilot", False),
)
#: Isolation times of the thesis [s] (§6.5.2: elevator at 28 s, §6.5.3: rudder at 22 s; injected at 18 s).
THESIS_ISOLATION = {"elevator": 28.0, "rudder": 22.0}
_PHASES = (("hold", 0.0, 75.0), ("turn", 75.0, 150.0), ("descent", 150.0, np.inf))
_ARRAYS = ("t", "y", "reference", "surfaces", "throttles", "mu", "rcond", "step_seconds")
_GROUPS = ("fdi", "spc", "plant")


def flight_summary(run, start: float) -> dict:
    """Isolation, loss, QP statuses, errors per phase (from ``start`` on) and surface use of one flight.

    Parameters
    ----------
    run : FtcRun
    start : float
        Time the fault is injected [s] (errors are measured from there on).

    Returns
    -------
    dict

    Examples
    --------
    >>> flight_summary.__name__
    'flight_summary'

    References
    ----------
    Hallouzi 2008, §6.5.
    """
    out = {"declared": list(run.declared) if run.declared else None, "lost": run.lost, "qp": run.qp,
           "qp_ms_median": float(np.median(run.step_seconds) * 1e3) if run.step_seconds.size else None,
           "timings": run.timings}
    for name, a, b in _PHASES:
        if np.any((run.t >= max(a, start)) & (run.t < b)):
            out[name] = run.errors(max(a, start), b)
    out["surface_max"] = dict(zip(("aileron", "elevator", "stabilizer", "rudder"),
                                  np.max(np.abs(run.surfaces), axis=0).round(2).tolist(), strict=True))
    return out


def _npz(run) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, configuration=run.configuration.astype(str), **{k: getattr(run, k) for k in _ARRAYS})
    return buf.getvalue()


def _plots(flights: dict, scenario: str) -> dict:
    import matplotlib.pyplot as plt

    figs = {}
    runs = {k: v for k, v in flights.items() if k.startswith(scenario + "-")}
    labels = ("φ [deg]", "θ [deg]", "ψ [deg]", "V_TAS [m/s]", "β [deg]", "h [m]")
    cols, refs = (0, 1, 2, 3, 5, 6), (0, 1, 4, 2, 3, 5)
    fig, axes = plt.subplots(3, 2, figsize=(11, 8), sharex=True)
    for ax, lab, c, r in zip(axes.ravel(), labels, cols, refs, strict=True):
        for key, d in runs.items():
            ax.plot(d["t"], d["y"][:, c], lw=0.9, label=key.split("-", 1)[1])
        ftc = runs.get(f"{scenario}-ftc")
        if ftc is not None:
            ax.plot(ftc["t"], ftc["reference"][:, r], "k--", lw=0.8, label="reference (FTC)")
        ax.set_ylabel(lab)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(f"B747 {scenario}: references and responses")
    figs[f"{scenario}_responses"] = fig
    fig, axes = plt.subplots(5, 1, figsize=(9, 9), sharex=True)
    for key, d in runs.items():
        for j, name in enumerate(("aileron", "elevator", "stabilizer", "rudder")):
            axes[j].plot(d["t"], d["surfaces"][:, j], lw=0.9, label=key.split("-", 1)[1])
            axes[j].set_ylabel(f"{name} [deg]")
        axes[4].plot(d["t"], d["throttles"], lw=0.8)
    axes[4].set_ylabel("throttles")
    axes[4].set_xlabel("time [s]")
    axes[0].legend(fontsize=7)
    figs[f"{scenario}_surfaces"] = fig
    ftc = runs.get(f"{scenario}-ftc")
    if ftc is not None and ftc["mu"].size and scenario != "bijlmer":
        from fdikit.studies.hallouzi2008.aircraft_models import MODEL_SET_II

        fig, ax = plt.subplots(figsize=(9, 3.5))
        names = [f"{f} {s:+g}" if s is not None else f for f, s in MODEL_SET_II]
        for j, nm in enumerate(names):
            ax.plot(ftc["t"], ftc["mu"][:, j], lw=0.9, label=nm)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("μ")
        ax.legend(fontsize=7, ncol=4)
        figs[f"{scenario}_modes"] = fig
    return figs


def _table(summaries: dict) -> tuple[str, str]:
    head = ["flight", "isolated (thesis)", "lost", "phase", "max |h−h_ref| [m]", "max |ψ−ψ_ref| [deg]",
            "RMS θ err [deg]", "RMS β [deg]", "RMS V err [m/s]", "max |aileron|, |elevator|, |stab.|, |rudder| [deg]"]
    md = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    csv = [",".join(h.replace(",", ";") for h in head)]
    for key, s in summaries.items():
        scen = key.split("-")[0]
        iso = "—"
        if s["declared"]:
            g, model, t = s["declared"]
            iso = f"{g} ({model}) at {t:.1f} s"
            if scen in THESIS_ISOLATION:
                iso += f" ({THESIS_ISOLATION[scen]:.0f} s)"
        lost = "—" if s["lost"] is None else f"{s['lost']:.1f} s"
        surf = ", ".join(f"{v:.1f}" for v in s["surface_max"].values())
        phases = [p for p, *_ in _PHASES if p in s] or [None]   # a flight lost before any phase: one row
        for phase in phases:
            e = s.get(phase)
            nums = (["—"] * 5 if e is None else
                    [f"{e['altitude_max']:.1f}", f"{e['heading_max']:.1f}", f"{e['pitch_rms']:.2f}",
                     f"{e['beta_rms']:.2f}", f"{e['airspeed_rms']:.2f}"])
            row = [key, iso, lost, phase or "—", *nums, surf]
            md.append("| " + " | ".join(row) + " |")
            csv.append(",".join(c.replace(",", ";") for c in row))
            iso = lost = surf = ""
    md += ["", "Real-time budget (§6.6): call times of the rate groups [ms], median / p99 (worst share of the period).",
           "", "| flight | FDI, 100 Hz | SPC, 10 Hz | plant, 100 Hz | QP solve, median |", "|---|---|---|---|---|"]
    for key, s in summaries.items():
        cells = []
        for g in _GROUPS:
            t = (s.get("timings") or {}).get(g)
            cells.append("—" if not t or not t.get("calls") else
                         f"{1e3 * t['median']:.2f} / {1e3 * t['p99']:.2f} ({100 * t['budget_used']:.0f} %)")
        qp = s.get("qp_ms_median")
        md.append(f"| {key} | " + " | ".join(cells) + f" | {'—' if qp is None else f'{qp:.2f}'} |")
    return "\n".join(md) + "\n", "\n".join(csv) + "\n"


def write_b747_ftc(out_dir, *, quick: bool = False, seed: int = 1, fresh: bool = False, progress=None) -> dict:
    """Fly :data:`FLIGHTS` and write the plots, ``ftc_b747.md``/``.csv`` and ``report.html`` into ``out_dir``.

    Parameters
    ----------
    out_dir : path-like
        Output folder; each finished flight is kept in it and reused by a rerun with the same arguments.
    quick : bool, optional
        120-s flights and a 60-s IMM calibration instead of 300 s each (the turn only starts at 75 s and
        the descent at 150 s, so a quick run shows the fault and the turn, not the descent).
    seed : int, optional
        Turbulence and sensor-noise seed of every flight.
    fresh : bool, optional
        Start over instead of resuming.
    progress : callable, optional
        Called with a message per flight.

    Returns
    -------
    dict
        Flight key → its summary (:func:`flight_summary`).

    Raises
    ------
    ParameterError
        When ``out_dir`` holds a run of other arguments (pass ``fresh=True``).

    Examples
    --------
    Not run here (JSBSim, several minutes):

    >>> summary = write_b747_ftc("out/ftc", quick=True)  # doctest: +SKIP
    >>> summary["rudder-ftc"]["declared"][0]  # doctest: +SKIP
    'rudder'

    References
    ----------
    Hallouzi 2008, §6.5.
    """
    import matplotlib.pyplot as plt

    from fdikit.resume import RunStore
    from fdikit.studies.hallouzi2008.b747_ftc import BIJLMER, T_INJECT, ftc_setup
    from fdikit.studies.hallouzi2008.b747_ftc_flight import fly_ftc

    duration = 120.0 if quick else 300.0
    store = RunStore(out_dir, "ftc-b747", {"quick": quick, "seed": seed}, fresh=fresh)
    setup = None
    summaries, flights = {}, {}
    for key, scenario, controller, reconfigure in FLIGHTS:
        payload = store.load(key)
        if payload is None:
            if setup is None:
                if progress:
                    progress("trimming the B747, identifying the IMM's process noise and the SPC initial data")
                setup = ftc_setup(calibration_seconds=60.0 if quick else 300.0)
            if progress:
                progress(f"flight {key} ({duration:.0f} s)")
            run = fly_ftc(setup, scenario, controller=controller, reconfigure=reconfigure, duration=duration,
                          seed=seed)
            start = BIJLMER["onset"] if scenario == "bijlmer" else T_INJECT
            payload = flight_summary(run, 0.0 if scenario == "nominal" else start)
            store.save(key, payload, files={f"{key}.npz": _npz(run)})
        summaries[key] = payload
        with np.load(store.file(f"{key}.npz")) as z:
            flights[key] = {k: z[k] for k in z.files}
    files = {}
    for scenario in dict.fromkeys(s for _, s, _, _ in FLIGHTS):
        for name, fig in _plots(flights, scenario).items():
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
            plt.close(fig)
            files[f"{name}.png"] = buf.getvalue()
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for key, d in flights.items():
        if d["rcond"].size:
            ax.semilogy(np.arange(d["rcond"].size), d["rcond"], label=key)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("rcond(R11)")
    ax.legend(fontsize=7)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    files["rcond.png"] = buf.getvalue()
    md, csv = _table(summaries)
    images = "".join(f'<figure><img src="data:image/png;base64,{base64.b64encode(v).decode()}" width="820">'
                     f"<figcaption>{html.escape(k)}</figcaption></figure>" for k, v in files.items())
    main = md.split("\n\n")[0].splitlines()
    rows = "".join("<tr>" + "".join(f"<td>{html.escape(c.strip())}</td>" for c in line.strip("|").split("|"))
                   + "</tr>" for line in main[2:])
    heads = "".join(f"<th>{html.escape(c.strip())}</th>" for c in md.splitlines()[0].strip("|").split("|"))
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>fdikit: B747 fault-tolerant flights</title>"
            "<style>td,th{border:1px solid #ccc;padding:2px 6px;font-size:12px}</style></head><body>"
            f"<h1>Hallouzi 2008 §6.5 on JSBSim's B747</h1><p>{duration:.0f}-s flights, seed {seed}, Dryden "
            "turbulence, Table 6.2 sensor noise; see docs/methods/ftc.md.</p>"
            f"<table><tr>{heads}</tr>{rows}</table><pre>{html.escape(md.split(chr(10) * 2, 1)[1])}</pre>"
            f"{images}</body></html>")
    store.publish({**files, "ftc_b747.csv": csv, "ftc_b747.md": md, "report.html": page})
    return summaries
