"""Files of ``fdikit b747``: Table 4.8 next to the thesis, per-run rows, plots and an HTML page.

Hallouzi 2008, §4.4.2 (Table 4.8) on fdikit's JSBSim B747: the sweep's table and rows, the outcome
and delay over the lock position, and for one run per surface the flown trajectory, the surface
position and the IMM's mode probabilities. Every file is written atomically (:mod:`fdikit.atomic`).

References
----------
Hallouzi 2008, §4.4.2, Table 4.8, Fig. 4.1.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

__all__ = ["plot_lip_run", "plot_sweep", "write_b747_report"]

_COLOURS = {"correct": "tab:green", "incorrect": "tab:red", "missed": "tab:orange", "false alarm": "tab:purple"}


def plot_lip_run(run, names, ax=None, path=None, t_fault: float = 20.0):
    """One LIP flight: surface position, mode probabilities, altitude.

    Parameters
    ----------
    run : LipRun
        From :func:`fdikit.studies.hallouzi2008.b747_lip.fly_lip`.
    names : sequence of str
        The mode names (the setup's model names).
    ax : sequence of 3 Axes, optional
        Where to draw (a new figure when omitted).
    path : str or Path, optional
        Write the figure there.
    t_fault : float, optional
        Injection time [s], marked.

    Returns
    -------
    The given axes, or the new figure.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.studies.hallouzi2008.b747_lip import LipRun
    >>> t = np.arange(0, 4, 0.01)
    >>> run = LipRun(t, np.full((t.size, 2), 0.5), np.full(t.size, "none"), "rudder", 5.0, (None, np.nan), 0,
    ...              np.zeros(t.size), np.full(t.size, 980.0))
    >>> len(plot_lip_run(run, ["a", "b"]).axes)
    3
    """
    from fdikit.plots import axes_or_new, finish_plot

    fig, (a0, a1, a2) = axes_or_new(ax, 3, figsize=(8, 7), sharex=True)
    if run.positions.size:
        a0.plot(run.t, run.positions, color="k")
        a0.axhline(run.lock, color="tab:red", ls=":", label=f"lock {run.lock:+.1f} deg")
        a0.legend(loc="best", fontsize=8)
    a0.set_ylabel(f"{run.surface or 'surface'} [deg]")
    for j, name in enumerate(names):
        a1.plot(run.t, run.mu[:, j], label=name, lw=1.2 if name == "nominal" else 0.9)
    a1.set_ylabel("mode probability")
    a1.set_ylim(-0.02, 1.02)
    a1.legend(loc="center left", fontsize=7, ncol=2)
    a2.plot(run.t, run.altitude, color="tab:blue")
    a2.set_ylabel("altitude [m]")
    a2.set_xlabel("t [s]")
    label, delay = run.first
    title = f"{run.surface} LIP at {run.lock:+.1f} deg: {run.outcome}" if run.surface else "fault-free"
    if label is not None:
        title += f" ({label} after {delay:.2f} s)"
    a0.set_title(title)
    for a in (a0, a1, a2):
        a.axvline(t_fault, color="0.5", ls="--", lw=0.8)
    return finish_plot(fig, ax, path)


def plot_sweep(table, ax=None, path=None):
    """Outcome and isolation delay over the lock position, one panel per surface.

    Parameters
    ----------
    table : Table48
    ax : sequence of Axes, optional
        One per surface in the table.
    path : str or Path, optional

    Returns
    -------
    The given axes, or the new figure.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.table_4_8 import LipRow, Table48
    >>> t = Table48((LipRow("rudder", 5.0, 1, "correct", "rudder", 2.0, "rudder", 0.0),), {})
    >>> len(plot_sweep(t).axes)
    1
    """
    from fdikit.plots import axes_or_new, finish_plot

    surfaces = [s for s in ("elevator", "aileron", "rudder") if any(r.surface == s for r in table.rows)]
    fig, panels = axes_or_new(ax, len(surfaces), figsize=(8, 2.6 * len(surfaces)))
    for a, s in zip(panels, surfaces, strict=True):
        rows = [r for r in table.rows if r.surface == s]
        for outcome, colour in _COLOURS.items():
            sel = [r for r in rows if r.outcome == outcome]
            if sel:
                d = [r.delay if np.isfinite(r.delay) else 0.0 for r in sel]
                a.scatter([r.lock for r in sel], d, c=colour, s=14, label=outcome)
        a.plot([r.lock for r in rows], [r.start for r in rows], color="0.6", lw=0.8, label="position at injection")
        a.set_ylabel(f"{s}: delay [s]")
        a.legend(loc="upper right", fontsize=7)
    panels[-1].set_xlabel("lock position [deg]")
    return finish_plot(fig, ax, path)


def write_b747_report(out, table, setup, examples=(), false_alarms=None) -> dict:
    """Write ``table.md``, ``rows.csv``, ``sweep.png``, one ``run_<surface>.png`` per example and ``report.html``.

    Parameters
    ----------
    out : str or Path
        The output folder (created).
    table : Table48
    setup : LipSetup
    examples : sequence of LipRun, optional
        Runs to plot.
    false_alarms : tuple, optional
        ``(count, hours)`` of the fault-free flights (:func:`fdikit.studies.hallouzi2008.b747_lip.false_alarm_rate`).

    Returns
    -------
    dict
        File role → path.
    """
    from fdikit.atomic import write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = [m.name for m in setup.models]
    files = {}
    md = table.markdown()
    fa_line = ""
    if false_alarms is not None:
        n, hours = false_alarms
        fa_line = f"False alarms on {hours:.2f} h of fault-free flight: {n} ({n / hours:.2g} per hour).\n"
    settings = ", ".join(f"{k} = {v}" for k, v in table.settings.items())
    files["table"] = write_text(out / "table.md", "# Table 4.8 on the JSBSim B747\n\n" + md + "\n" + fa_line
                                + f"\nSettings: {settings}\n")
    header = "surface,lock_deg,seed,outcome,declared,delay_s,final,position_at_injection_deg\n"
    body = "".join(f"{r.surface},{r.lock:.1f},{r.seed},{r.outcome},{r.declared or ''},{r.delay:.3f},{r.final},"
                   f"{r.start:.3f}\n" for r in table.rows)
    files["rows"] = write_text(out / "rows.csv", header + body)
    plot_sweep(table, path=out / "sweep.png")
    files["sweep"] = out / "sweep.png"
    for run in examples:
        p = out / f"run_{run.surface}_{run.lock:+.1f}.png"
        plot_lip_run(run, names, path=p)
        files[f"run_{run.surface}"] = p
    rows_html = "".join(
        "<tr>" + "".join(f"<td>{html.escape(c.strip())}</td>" for c in line.strip("|").split("|")) + "</tr>"
        for line in md.splitlines()[2:])
    heads = "".join(f"<th>{html.escape(c.strip())}</th>" for c in md.splitlines()[0].strip("|").split("|"))
    images = "".join(f'<figure><img src="{Path(p).name}" width="720"><figcaption>{html.escape(Path(p).name)}'
                     "</figcaption></figure>" for k, p in files.items() if str(p).endswith(".png"))
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>fdikit b747: Table 4.8</title>"
            "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}td,th{border:1px solid #ccc;"
            "padding:2px 6px}table{border-collapse:collapse}</style></head><body>"
            "<h1>Hallouzi 2008, Table 4.8, on the nonlinear JSBSim B747</h1>"
            f"<table><tr>{heads}</tr>{rows_html}</table><p>{html.escape(fa_line)}</p>"
            f"<p>Settings: {html.escape(settings)}</p>{images}"
            "<p>Rows: <a href='rows.csv'>rows.csv</a>; table: <a href='table.md'>table.md</a>.</p></body></html>")
    files["html"] = write_text(out / "report.html", page)
    return files
