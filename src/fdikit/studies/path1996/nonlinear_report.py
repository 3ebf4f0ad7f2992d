"""Files of ``fdikit path-evaluation``: the Ch. 5 table, residual plots per fault, Table 2.1 and Fig. 2.6.

Douglas et al. 1996, §2.3 (Table 2.1, Fig. 2.6) and §5.1 (the evaluation), on fdikit's nonlinear car.
Every file is written atomically (:mod:`fdikit.atomic`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["table_markdown", "table_2_1_markdown", "plot_fig_2_6", "plot_fault_residuals", "write_path_evaluation"]

_FULL_22 = (-227.45, -193.79, -159.51, -132.21 + 2.62j, -132.21 - 2.62j, -135.35 + 1.85j, -135.35 - 1.85j, -138.68,
            -26.16 + 4.47j, -26.16 - 4.47j, -1.99 + 6.63j, -1.99 - 6.63j, -3.10 + 6.07j, -3.10 - 6.07j,
            -1.31 + 5.60j, -1.31 - 5.60j, -0.046, -7.09 + 2.48j, -7.09 - 2.48j, -90.91, -1.25, -80.0)


def _fmt(v) -> str:
    if isinstance(v, complex) or (isinstance(v, np.complexfloating)):
        return f"{v.real:.2f} {'+' if v.imag >= 0 else '−'} {abs(v.imag):.2f}i"
    return f"{float(v):.3g}"


def table_markdown(table) -> str:
    """The Ch. 5 table as markdown: counts and false-alarm rates per road and processor, then every row.

    Parameters
    ----------
    table : EvaluationTable
        From :func:`~fdikit.studies.path1996.nonlinear_table.path_evaluation_table`.

    Returns
    -------
    str

    References
    ----------
    Douglas et al. 1996, §5.1.1–5.1.2 (all faults "clearly identified").

    Examples
    --------
    >>> from fdikit.studies.path1996.nonlinear_table import EvaluationTable
    >>> table_markdown(EvaluationTable([], {}, {"game": {"filter1:a": 0.1}}, {})).splitlines()[0]
    '# PATH Ch. 5 on the nonlinear car'
    """
    lines = ["# PATH Ch. 5 on the nonlinear car", "",
             "The report: every fault \"clearly identified\" on both roads (§5.1). fdikit, realistic sensor noise:", "",
             "| road | bank | processor | detected | isolated | false alarms / h |", "|---|---|---|---|---|---|"]
    for (road, bank, proc), (det, iso, n) in sorted(table.counts().items()):
        lines.append(f"| {road} | {bank} | {proc} | {det}/{n} | {iso}/{n} | {table.rate(road, bank, proc):.3g} |")
    banks = list(table.off_nominal)
    lines += ["", "Off-nominal (+2° throttle, no fault, smooth road): peak scaled magnitude per residual group "
              "(the report: all < 0.25)", "", "| group | " + " | ".join(banks) + " |",
              "|---|" + "---|" * len(banks)]
    groups = list(table.off_nominal[banks[0]]) if banks else []
    lines += [f"| {g} | " + " | ".join(f"{table.off_nominal[b].get(g, float('nan')):.3g}" for b in banks) + " |"
              for g in groups]
    lines += ["", "| road | bank | fault | processor | detected | delay [s] | isolated as | isolation delay [s] |",
              "|---|---|---|---|---|---|---|---|"]
    for r in table.rows:
        d = "—" if r.detection_delay is None else f"{r.detection_delay:.2f}"
        i = "—" if r.isolation_delay is None else f"{r.isolation_delay:.2f}"
        lines.append(f"| {r.road} | {r.bank} | {r.fault} | {r.processor} | {'yes' if r.detected else 'no'} | {d} | "
                     f"{r.isolated_as} | {i} |")
    return "\n".join(lines) + "\n"


def table_2_1_markdown(models) -> str:
    """The 22-state spectrum and Table 2.1 (Methods 1 and 2) beside the report's, matched eigenvalue by eigenvalue.

    Parameters
    ----------
    models : DesignModels
        From :func:`~fdikit.studies.path1996.reduction.path_design_models`.

    Returns
    -------
    str

    References
    ----------
    Douglas et al. 1996, §2.3, Table 2.1.

    Examples
    --------
    >>> text = table_2_1_markdown(path_design_models())  # doctest: +SKIP
    >>> text.splitlines()[0]  # doctest: +SKIP
    '# Spectra of the linearised car (Douglas et al. 1996, §2.3)'
    """
    from fdikit.plants.path_vehicle import TABLE_2_1_EIGENVALUES_14
    from fdikit.studies.path1996.reduction import match_eigenvalues

    method2_printed = (-108.98 + 37.67j, -108.98 - 37.67j, -0.046, -18.33 + 13.19j, -18.33 - 13.19j,
                       -7.10 + 2.49j, -7.10 - 2.49j, -79.27, -3.07 + 6.10j, -3.07 - 6.10j, -2.39 + 6.30j,
                       -2.39 - 6.30j, -1.31 + 5.62j, -1.31 - 5.62j)  # "7.10 ± 2.49i" read as −7.10 (OCR)
    out = ["# Spectra of the linearised car (Douglas et al. 1996, §2.3)", ""]
    for title, model, ref in (("22 states", models.full, _FULL_22),
                              ("Method 1 (residualisation), 14 states", models.method1, TABLE_2_1_EIGENVALUES_14),
                              ("Method 2 (balanced truncation), 14 states", models.method2, method2_printed)):
        pairs = match_eigenvalues(np.linalg.eigvals(model.A), ref)
        out += [f"## {title}", "", "| report | fdikit | relative difference |", "|---|---|---|"]
        out += [f"| {_fmt(r)} | {_fmt(c)} | {e:.1%} |" for r, c, e in pairs]
        out.append("")
    return "\n".join(out)


def plot_fig_2_6(models, ax=None, path=None, frequencies=None):
    """Fig. 2.6: singular values of the 22-state model and of Methods 1 and 2 over 0.1–100 rad/s, and their errors.

    Parameters
    ----------
    models : DesignModels
        The models.
    ax : sequence of 2 matplotlib Axes, optional
        Where to draw (values, relative errors; a new figure otherwise).
    path : str or Path, optional
        Save the figure there.
    frequencies : array_like, optional
        ω [rad/s] (default 200 points, 0.1–100).

    Returns
    -------
    matplotlib Figure

    References
    ----------
    Douglas et al. 1996, §2.3, Fig. 2.6.

    Examples
    --------
    >>> fig = plot_fig_2_6(path_design_models())  # doctest: +SKIP
    """
    from fdikit.plots import axes_or_new, finish_plot
    from fdikit.studies.path1996.reduction import singular_values

    w = np.logspace(-1, 2, 200) if frequencies is None else np.asarray(frequencies, dtype=float)
    fig, (a, b) = axes_or_new(ax, 2, figsize=(7, 7), sharex=True)
    full = singular_values(models.full, w)
    for model, style, label in ((models.full, "-", "22 states"), (models.method1, "--", "Method 1 (14)"),
                                (models.method2, ":", "Method 2 (14)")):
        sv = singular_values(model, w)
        for k in range(sv.shape[1]):
            a.loglog(w, sv[:, k], style, color=f"C{k}", label=label if k == 0 else None)
            if model is not models.full:
                b.loglog(w, np.abs(sv[:, k] - full[:, k]) / full[:, k], style, color=f"C{k}",
                         label=label if k == 0 else None)
    a.set_ylabel("singular value")
    a.set_title("Fig. 2.6: control inputs → sensors (colour: σ₁, σ₂, σ₃)")
    a.legend()
    b.set_xlabel("ω [rad/s]")
    b.set_ylabel("|σ_reduced − σ_22| / σ_22")
    b.legend()
    return finish_plot(fig, ax, path)


def plot_fault_residuals(run, bank: str, ax=None, path=None, onset: float = 2.0):
    """Scaled residual magnitudes of every group in the faulty run's own filter, with the nominal level 1.

    Parameters
    ----------
    run : FaultRun
        A faulty run.
    bank : str
        Which bank's residuals (a key of ``run.residuals``).
    ax : matplotlib Axes, optional
        Where to draw.
    path : str or Path, optional
        Save the figure there.
    onset : float, default 2.0
        Fault onset [s] (a vertical line).

    Returns
    -------
    matplotlib Figure

    References
    ----------
    Douglas et al. 1996, §5.1, Figs. 5.1–5.18.

    Examples
    --------
    >>> fig = plot_fault_residuals(run, "game")  # doctest: +SKIP
    """
    from fdikit.plots import axes_or_new, finish_plot
    from fdikit.studies.path1996.nonlinear_evaluation import group_magnitudes

    res = run.residuals[bank]
    mags = group_magnitudes(res)
    own = [g for g in mags if g.split(":")[1] == run.fault.split(":")[0]]
    filt = own[0].split(":")[0] if own else next(iter(mags)).split(":")[0]
    fig, (a,) = axes_or_new(ax, 1)
    for g, m in mags.items():
        if g.startswith(filt + ":"):
            a.plot(res.t, m, label=g.split(":")[1], lw=1.8 if g in own else 0.8)
    a.axhline(1.0, color="k", ls=":", lw=0.8)
    a.axvline(onset, color="grey", ls="--", lw=0.8)
    a.set_xlabel("t [s]")
    a.set_ylabel("scaled residual magnitude")
    a.set_title(f"{run.fault} ({run.road} road), {bank} bank, {filt}")
    a.legend(fontsize=7)
    return finish_plot(fig, ax, path)


def write_path_evaluation(out, table, setup) -> dict[str, Path]:
    """Write ``table.md``, ``rows.csv``, ``table_2_1.md``, ``fig_2_6.png``, ``residuals/<bank>_<road>_<fault>.png``.

    Parameters
    ----------
    out : str or Path
        Output folder (created).
    table : EvaluationTable
        Run with ``keep_runs=True`` for the residual plots.
    setup : EvaluationSetup
        The setup the table was run with.

    Returns
    -------
    dict of str to Path
        The files written.

    Raises
    ------
    OSError
        When the folder cannot be written.

    References
    ----------
    Douglas et al. 1996, §2.3, §5.1.

    Examples
    --------
    >>> files = write_path_evaluation("out/path", table, setup)  # doctest: +SKIP
    """
    import matplotlib.pyplot as plt

    from fdikit.atomic import write_text

    out = Path(out)
    (out / "residuals").mkdir(parents=True, exist_ok=True)
    files = {"table": write_text(out / "table.md", table_markdown(table)),
             "table_2_1": write_text(out / "table_2_1.md", table_2_1_markdown(setup.models))}
    head = "road,bank,fault,processor,detected,isolated,detection_delay,isolation_delay,isolated_as\n"
    csv = head + "".join(f"{r.road},{r.bank},{r.fault},{r.processor},{r.detected},{r.isolated},{r.detection_delay},"
                         f"{r.isolation_delay},{r.isolated_as}\n" for r in table.rows)
    files["rows"] = write_text(out / "rows.csv", csv)
    fig = plot_fig_2_6(setup.models, path=out / "fig_2_6.png")
    plt.close(fig)
    files["fig_2_6"] = out / "fig_2_6.png"
    for (road, fault), run in table.runs.items():
        for bank in run.residuals:
            p = out / "residuals" / f"{bank}_{road}_{fault}.png"
            plt.close(plot_fault_residuals(run, bank, path=p))
            files[f"residuals/{bank}_{road}_{fault}"] = p
    return files
