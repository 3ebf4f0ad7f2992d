"""Files of ``fdikit b747``: Tables 4.6 and 4.8 next to the thesis, per-run rows, plots and an HTML page.

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

__all__ = ["THESIS_FIG_4_3", "plot_lip_run", "plot_sweep", "plot_table_4_6", "table_4_6_files",
           "table_4_6_markdown", "write_b747_report"]

#: Hallouzi 2008, Fig. 4.3 as read in the text (§4.4.1): the weight each fault interval should show.
THESIS_FIG_4_3 = {"elevator": "μ(3) ≈ 0.7", "alpha_sensor": "μ(6) ≈ 0.5, μ(8) ≈ 0.5", "rudder": "μ(2) ≈ 0.55",
                  "hydraulic": "μ(7) → 1", "engine": "μ(5) → ≈ 1", "none": "μ(8) ≈ 1"}

_COLOURS = {"correct": "tab:green", "incorrect": "tab:red", "missed": "tab:orange", "false alarm": "tab:purple"}


def plot_lip_run(run, ax=None, path=None, t_fault: float = 20.0):
    """One LIP flight: surface position, the Table 4.7 group weights (0.5-s mean; the IMM's probabilities
    jump between models from one sample to the next at this signal-to-noise ratio), the declaration, altitude.

    Parameters
    ----------
    run : LipRun
        From :func:`fdikit.studies.hallouzi2008.b747_lip.fly_lip` (model set II plus nominal).
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
    >>> run = LipRun(t, np.full((t.size, 8), 0.125), np.full(t.size, "none"), "rudder", 5.0, (None, np.nan), 0,
    ...              np.zeros(t.size), np.full(t.size, 980.0))
    >>> len(plot_lip_run(run).axes)
    3

    References
    ----------
    Hallouzi 2008, §4.4.1–§4.4.2, Tables 4.6 and 4.8.
    """
    from fdikit.plots import axes_or_new, finish_plot

    fig, (a0, a1, a2) = axes_or_new(ax, 3, figsize=(8, 7), sharex=True)
    if run.positions.size:
        a0.plot(run.t, run.positions, color="k")
        a0.axhline(run.lock, color="tab:red", ls=":", label=f"lock {run.lock:+.1f} deg")
        a0.legend(loc="best", fontsize=8)
    a0.set_ylabel(f"{run.surface or 'surface'} [deg]")
    from fdikit.multimodel.isolation import table_4_7_logic

    logic = table_4_7_logic(0.2)
    width = max(1, int(round(0.5 / max(run.t[1] - run.t[0], 1e-9)))) if run.t.size > 1 else 1
    kernel = np.ones(width) / width
    cover = np.convolve(np.ones(run.t.size), kernel, mode="same")  # the mean over the samples there are at the ends
    groups = {**{g: list(idx) for g, idx in logic.groups.items()}, "nominal": [logic.nominal]}
    for g, idx in groups.items():
        w = run.mu[:, idx].sum(axis=1) if run.mu.shape[1] > max(idx) else np.zeros(run.t.size)
        a1.plot(run.t, np.convolve(w, kernel, mode="same") / cover, label=g, lw=1.2)
    on = run.declared != "none"
    if on.any():
        a1.fill_between(run.t, 0, 1, where=on, color="tab:red", alpha=0.1, label=f"declared ({run.declared[on][0]})")
    a1.set_ylabel("group weight (0.5-s mean)")
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
    """Outcome and isolation delay over the lock position, one panel per surface (grey: the surface's
    position when it locked, right axis; a miss at delay 0).

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
    >>> len(plot_sweep(t).axes)   # the panel and its twin (position at injection)
    2

    References
    ----------
    Hallouzi 2008, §4.4.1–§4.4.2, Tables 4.6 and 4.8.
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
        a.set_ylabel(f"{s}: delay [s]")
        a.legend(loc="upper left", fontsize=7)
        twin = a.twinx()
        twin.plot([r.lock for r in rows], [r.start for r in rows], color="0.6", lw=0.8)
        twin.set_ylabel("position at injection [deg]", color="0.5", fontsize=8)
    panels[-1].set_xlabel("lock position [deg]")
    return finish_plot(fig, ax, path)


def table_4_6_markdown(result) -> str:
    """Table 4.6 / Fig. 4.3 of a linear run: mean weights per interval, the Table 4.7 decision, the thesis's figure.

    Parameters
    ----------
    result : Table46Result
        From :func:`fdikit.studies.hallouzi2008.table_4_6.run_table_4_6`.

    Returns
    -------
    str
        Markdown: one row per interval (1 s after each switch skipped), then the state VAFs.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.studies.hallouzi2008.table_4_6 import Table46Result
    >>> t = np.arange(300) * 0.01
    >>> mu = np.tile(np.eye(8)[7], (300, 1))
    >>> "none_1" in table_4_6_markdown(Table46Result(t, np.array(["none"] * 300), mu, mu, None, None, None, {}))
    True

    References
    ----------
    Hallouzi 2008, §4.4.1–§4.4.2, Tables 4.6 and 4.8.
    """
    from fdikit.studies.hallouzi2008.table_4_6 import scenario_intervals, table_4_6_isolation

    settle = 1.0  # as table_4_6_isolation: the weights' transient after each switch is skipped
    decided = table_4_6_isolation(result, settle=settle)
    spans = {name: (start, end) for name, start, end in scenario_intervals(result.t)}
    lines = ["| interval | mean weights μ(1) … μ(8) | Table 4.7 decision (share of samples) | thesis (Fig. 4.3) |",
             "|---|---|---|---|"]
    for name, (label, share) in decided.items():
        base = "none" if name.startswith("none") else name
        start, end = spans[name]
        rows = (result.t >= start + settle - 1e-9) & (result.t < end - 1e-9)
        weights = " ".join(f"{v:.2f}" for v in result.mu[rows].mean(axis=0))
        lines.append(f"| {name} | {weights} | {label} ({100 * share:.0f} %) | {THESIS_FIG_4_3.get(base, '')} |")
    vaf = ", ".join(f"{k} {v:.1f} %" for k, v in result.vaf.items())
    return "\n".join(lines) + f"\n\nState VAF: {vaf}\n"


def plot_table_4_6(result, ax=None, path=None):
    """Estimated weights μ(1) … μ(8) against time, with the fault intervals shaded (Hallouzi 2008, Fig. 4.3).

    Parameters
    ----------
    result : Table46Result
    ax : matplotlib.axes.Axes, optional
        Axes to draw on (a new figure when omitted).
    path : str or Path, optional
        Write the figure there (atomically).

    Returns
    -------
    The given axes, or the new figure.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.table_4_6 import Table46Result
    >>> t = np.arange(200) * 0.01
    >>> mu = np.tile(np.eye(8)[7], (200, 1))
    >>> fig = plot_table_4_6(Table46Result(t, np.array(["none"] * 200), mu, mu, None, None, None, {}))
    >>> len(fig.axes[0].lines)
    8

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    from fdikit.plots import axes_or_new, finish_plot
    from fdikit.studies.hallouzi2008.table_4_6 import scenario_intervals

    fig, (a,) = axes_or_new(ax, 1, figsize=(9, 4))
    for i in range(result.mu.shape[1]):
        a.plot(result.t, result.mu[:, i], lw=1.0, label=f"μ({i + 1})")
    for name, start, end in scenario_intervals(result.t):
        if not name.startswith("none"):
            a.axvspan(start, end, color="0.9", zorder=0)
            a.text(0.5 * (start + end), 1.02, name, ha="center", va="bottom", fontsize=7)
    a.set(xlabel="time [s]", ylabel="weight", ylim=(-0.02, 1.1), xlim=(result.t[0], result.t[-1]))
    a.legend(ncol=8, fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.08))
    return finish_plot(fig, ax, path)


def table_4_6_files(result) -> tuple[str, bytes]:
    """The markdown (:func:`table_4_6_markdown`) and the PNG (:func:`plot_table_4_6`) of a linear run.

    Parameters
    ----------
    result : Table46Result

    Returns
    -------
    markdown : str
    png : bytes

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.table_4_6 import Table46Result
    >>> t = np.arange(300) * 0.01
    >>> mu = np.tile(np.eye(8)[7], (300, 1))
    >>> md, png = table_4_6_files(Table46Result(t, np.array(["none"] * 300), mu, mu, None, None, None, {}))
    >>> png[:4]
    b'\\x89PNG'

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    import matplotlib.pyplot as plt

    from fdikit.plots import figure_bytes

    fig = plot_table_4_6(result)
    try:
        return table_4_6_markdown(result), figure_bytes(fig)
    finally:
        plt.close(fig)


def write_b747_report(out, table, setup, examples=(), false_alarms=None, linear=None) -> dict:
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
    linear : tuple, optional
        ``(markdown, png_bytes)`` of the §4.4.1 linear run with model set I (:func:`table_4_6_files`):
        ``table_4_6.md`` and ``table_4_6.png``.

    Returns
    -------
    dict
        File role → path.

    Examples
    --------
    >>> write_b747_report("out/b747", table, setup, examples, (0, 1.0), linear)  # doctest: +SKIP

    References
    ----------
    Hallouzi 2008, §4.4.1–§4.4.2, Tables 4.6 and 4.8.
    """
    from fdikit.atomic import write_text

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
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
    if linear is not None:
        from fdikit.atomic import write_bytes

        linear_md, png = linear
        files["table_4_6"] = write_text(out / "table_4_6.md", "# Table 4.6 / Fig. 4.3: the linear run with model "
                                        "set I (augmented EKF)\n\n" + linear_md)
        files["table_4_6_plot"] = write_bytes(out / "table_4_6.png", png)
    for run in examples:
        p = out / f"run_{run.surface}_{run.lock:+.1f}.png"
        plot_lip_run(run, path=p)
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
    if linear is not None:
        page = page.replace("<figure>", "<h2>Table 4.6 (linear, model set I)</h2><pre>"
                            + html.escape(linear[0]) + "</pre><figure>", 1)
    files["html"] = write_text(out / "report.html", page)
    return files
