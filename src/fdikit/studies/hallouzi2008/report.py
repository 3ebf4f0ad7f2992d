"""One command for the multiple-model reproductions of Hallouzi 2008 (§2.4, §3.3.1, §3.6).

:func:`multiple_model_report` runs, in turn,

1. the target-tracking Monte Carlo (§2.4.2, Figs. 2.4–2.5),
2. the B747 linear FDI Monte Carlo (§2.4.1, Table 2.6),
3. Example 3.1 / Table 3.1 (§3.3.1),
4. the MSD runs of the OD, CP and LV model sets (§3.6.2, Table 3.3) and the OD vs minimum-mismatch
   conditioning (§3.6.4, Table 3.4),

and writes ``summary.md`` and one PNG plot per part into ``out``.  Each finished part is kept (atomically) in
``out/parts-*/`` at once, so a killed run resumes where it stopped; ``summary.md`` is assembled from the parts
when all are done (rules in :mod:`fdikit.resume`).  The CLI entry is ``fdikit multiple-model``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from fdikit.plots import axes_or_new, finish_plot

__all__ = ["multiple_model_report", "check_multiple_model_arguments", "plot_b747", "plot_msd", "PARTS"]


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def plot_b747(result, path=None, axes=None):
    """Fig. 2.3 style: weight and state RMSE per sample of the three filters, fault intervals shaded.

    Parameters
    ----------
    result : B747MonteCarloResult
        From :func:`fdikit.studies.hallouzi2008.b747.b747_monte_carlo`.
    path : str, Path or binary file object, optional
        Write the figure there (atomically, :func:`fdikit.plots.save_figure`).
    axes : sequence of two matplotlib Axes, optional
        The weight-RMSE and state-RMSE panels; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure or the given ``axes``
        A new figure (closed once written to ``path``) when ``axes`` is None, else ``axes``.

    References
    ----------
    Hallouzi 2008, §2.4.1, Fig. 2.3, Table 2.6.

    Examples
    --------
    The plot needs a full 1000-sample Monte Carlo (the fault intervals of Table 2.6) and matplotlib, so
    it is not run here:

    >>> from fdikit.studies.hallouzi2008.b747 import b747_monte_carlo
    >>> fig = plot_b747(b747_monte_carlo(runs=1, filters=("ekf",)))  # doctest: +SKIP
    >>> len(fig.axes)  # doctest: +SKIP
    2
    """
    from fdikit.studies.hallouzi2008.b747 import FAULT_INTERVALS, INTERVALS

    fig, panels = axes_or_new(axes, 2, figsize=(8, 6), sharex=True)
    for f in result.filters:
        panels[0].plot(result.t, result.rmse_weights[f], label=f, lw=1)
        panels[1].semilogy(result.t, result.rmse_state[f], label=f, lw=1)
    panels[0].set_ylabel("weight RMSE")
    panels[1].set_ylabel("state RMSE")
    panels[1].set_xlabel("t [s]")
    for ax in panels:
        for name in FAULT_INTERVALS:
            a, b = INTERVALS[name]
            ax.axvspan(result.t[a], result.t[b], color="0.9")
        ax.legend(fontsize=7)
    panels[0].set_title(f"Hallouzi 2008 §2.4.1 (substitute B), {result.runs} Monte-Carlo runs")
    return finish_plot(fig, axes, path)


def plot_msd(sim, runs: dict, path=None, axes=None):
    """Figs 3.7–3.11 style: k1, m3, f1, f2 reconstructed by the OD, CP and LV sets against the truth.

    Parameters
    ----------
    sim : MSDSimulation
        From :func:`fdikit.studies.hallouzi2008.msd.simulate_msd` (the true parameters).
    runs : dict
        Model-set key → run with ``params`` (N, 4), e.g.
        :func:`fdikit.studies.hallouzi2008.msd_model_sets.msd_table_3_3`.
    path : str, Path or binary file object, optional
        Write the figure there (atomically, :func:`fdikit.plots.save_figure`).
    axes : sequence of four matplotlib Axes, optional
        The k1, m3, f1 and f2 panels; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure or the given ``axes``
        A new figure (closed once written to ``path``) when ``axes`` is None, else ``axes``.

    References
    ----------
    Hallouzi 2008, §3.6.2, Figs 3.7–3.11.

    Examples
    --------
    Not run here (matplotlib):

    >>> from fdikit.studies.hallouzi2008.msd import simulate_msd
    >>> from fdikit.studies.hallouzi2008.msd_model_sets import run_msd_model_set
    >>> sim = simulate_msd(duration=1.0, dt=0.01)
    >>> fig = plot_msd(sim, {"lv": run_msd_model_set(sim, "lv")})  # doctest: +SKIP
    >>> len(fig.axes)  # doctest: +SKIP
    4
    """
    fig, panels = axes_or_new(axes, 4, figsize=(8, 9), sharex=True)
    limits = ((0.0, 2.0), (0.0, 2.2), (-0.1, 1.3), (-0.1, 1.3))  # a blend near 1/m3 = 0 sends m3 off the chart
    for j, (ax, name) in enumerate(zip(panels, ("k1", "m3", "f1", "f2"))):
        ax.plot(sim.t, sim.params[:, j], "k--", lw=1, label="true")
        for key, run in runs.items():
            ax.plot(sim.t, run.params[:, j], lw=0.8, label=key.upper())
        ax.set_ylabel(name)
        ax.set_ylim(*limits[j])
        ax.legend(fontsize=7, loc="upper right")
    panels[-1].set_xlabel("t [s]")
    panels[0].set_title("Hallouzi 2008 §3.6.2: parameters from the weights (augmented EKF)")
    return finish_plot(fig, axes, path)


#: The parts of the report, in order: (key, progress label).
PARTS = (("item17", "target tracking (§2.4.2)"), ("item18", "B747 linear FDI (§2.4.1)"),
         ("item19", "Example 3.1 (§3.3.1)"), ("item20", "MSD model sets (§3.6)"))
#: Side file (plot) of each part, copied into ``out`` under the same name.
PLOTS = {"item17": "target_tracking.png", "item18": "b747.png", "item20": "msd.png"}


def check_multiple_model_arguments(*, runs=100, seed=0, msd_dt=0.01, model_sets=15) -> dict:
    """Validate the arguments of :func:`multiple_model_report` (before any work); return them normalised.

    Parameters
    ----------
    runs : int, default 100
        Monte-Carlo size, >= 1.
    seed : int, default 0
        Master seed, >= 0.
    msd_dt : float, default 0.01
        MSD sample time [s], in (0, 0.02].
    model_sets : int, default 15
        Number of random sets of Example 3.1, >= 1.

    Returns
    -------
    dict
        ``runs``, ``seed``, ``msd_dt``, ``model_sets``, checked.

    Raises
    ------
    ParameterError
        Naming the argument: ``runs`` and ``model_sets`` integers >= 1, ``seed`` an integer >= 0,
        ``msd_dt`` finite in (0, 0.02] s (the series ZOH of :func:`fdikit.studies.hallouzi2008.msd.simulate_msd`
        is too coarse above 0.02 s).

    References
    ----------
    Hallouzi 2008, §2.4, §3.3.1, §3.6 (the reproductions the arguments size).

    Examples
    --------
    >>> check_multiple_model_arguments(runs=3)
    {'runs': 3, 'seed': 0, 'msd_dt': 0.01, 'model_sets': 15}
    """
    from fdikit.resume import check_count, check_positive, check_seed

    return {"runs": check_count(runs, "runs"), "seed": check_seed(seed),
            "msd_dt": check_positive(msd_dt, "msd_dt", maximum=0.02,
                                     hint=" s (the thesis uses 2.5e-3; the MSD sampling needs <= 0.02)"),
            "model_sets": check_count(model_sets, "model_sets")}


def multiple_model_report(out, *, runs: int = 100, seed: int = 0, msd_dt: float = 0.01, model_sets: int = 15,
                          progress: Callable[[str], None] | None = None, fresh: bool = False) -> Path:
    """Run items 17–20 and write ``summary.md`` and the plots into ``out``; returns the summary's path.

    Parameters
    ----------
    out : str or PathLike
        Output folder (created; must be writable).
    runs : int
        Monte-Carlo size of the tracking and B747 parts (thesis: 100).
    seed : int
        Master seed (>= 0).
    msd_dt : float
        MSD sample time, in (0, 0.02] s (thesis 2.5e-3 s; 0.01 s keeps the EKF loops short, see
        :mod:`fdikit.studies.hallouzi2008.msd`).
    model_sets : int
        Number of random sets of Example 3.1 (thesis: 15).
    progress : callable, optional
        Called with the name of each part before it starts (or is reused).
    fresh : bool
        Start over even when ``out`` holds a resumable run (see :class:`fdikit.resume.RunStore`).

    Returns
    -------
    pathlib.Path
        ``out/summary.md``.

    Notes
    -----
    Every argument is checked before any work.  Each part (its summary section and its plot) is stored
    atomically in ``out/parts-*/`` as soon as it is finished; ``summary.md`` and the plots in ``out`` are
    written, atomically, only when all four parts are complete, so an earlier summary is never truncated.
    A rerun with the same arguments after a kill resumes, reusing the finished parts; a rerun with other
    arguments is refused unless ``fresh`` (rules in :mod:`fdikit.resume`).

    Raises
    ------
    ParameterError
        For a bad argument or an output folder holding a run of other arguments.

    References
    ----------
    Hallouzi 2008, §2.4.1–2.4.2, §3.3.1 (Table 3.1), §3.6.2 (Table 3.3), §3.6.4 (Table 3.4).

    Examples
    --------
    Even with one Monte-Carlo run the four parts take over a minute, so the call is not run here:

    >>> path = multiple_model_report("out/multiple-model", runs=1, model_sets=1)  # doctest: +SKIP
    >>> path.name  # doctest: +SKIP
    'summary.md'
    """
    from fdikit.resume import RunStore

    args = check_multiple_model_arguments(runs=runs, seed=seed, msd_dt=msd_dt, model_sets=model_sets)
    store = RunStore(out, "multiple-model", args, fresh=fresh)
    say = progress or (lambda _name: None)
    compute = {"item17": _item17, "item18": _item18, "item19": _item19, "item20": _item20}
    sections = {}
    for key, label in PARTS:
        payload = store.load(key)
        if payload is None:
            say(label)
            text, png = compute[key](**args)
            files = {PLOTS[key]: png} if key in PLOTS else {}
            payload = store.save(key, {"section": text}, files)
        else:
            say(f"{label}: done earlier, reused")
        sections[key] = payload["section"]
    header = f"# Hallouzi 2008 multiple-model reproductions (runs = {runs}, seed = {seed})\n\n"
    summary = header + "".join(sections[k] + "\n" for k, _ in PARTS)
    files = {name: store.file(name).read_bytes() for name in PLOTS.values()}
    store.publish({**files, "summary.md": summary})
    return store.out / "summary.md"


def _png(plot, *args) -> bytes:
    import io

    buf = io.BytesIO()
    plot(*args, buf)
    return buf.getvalue()


def _item17(*, runs, seed, **_):
    from fdikit.studies.hallouzi2008.target_tracking import plot_target_tracking, target_tracking_monte_carlo

    tt = target_tracking_monte_carlo(runs=runs, seed=seed)
    png = _png(plot_target_tracking, tt)
    intervals = list(next(iter(tt.summary.values())))
    rows = [[f] + [f"{v['position']:.1f} / {v['velocity']:.2f} / {v['B']:.2f}" for v in tt.summary[f].values()]
            for f in tt.filters]
    weights = ", ".join(f"{f} ({tt.cm_weights[f][120:151, 0].mean():.3f}, {tt.cm_weights[f][120:151, 1].mean():.3f})"
                        for f in tt.filters)
    return ("## Item 17: target tracking, RMSE position [m] / velocity [m/s] / B\n\n"
            + _table(["filter", *intervals], rows)
            + f"\nMean weights over [120, 150] (true 0.75, 0.25): {weights}.\n![](target_tracking.png)\n"), png


def _item18(*, runs, seed, **_):
    from fdikit.studies.hallouzi2008.b747 import b747_monte_carlo, b747_snr, b747_trace

    b7 = b747_monte_carlo(runs=runs, seed=seed)
    png = _png(plot_b747, b7)
    names = list(next(iter(b7.summary.values())))
    rows = [[f] + [f"{b7.summary[f][k]['weights']:.3f} / {b7.summary[f][k]['state']:.3f}" for k in names]
            for f in b7.filters]
    snr = np.mean([b747_snr(b747_trace(s)) for s in range(3)], axis=0)
    return ("## Item 18: B747, weight RMSE / state RMSE per interval (substitute B)\n\n"
            + _table(["filter", *names], rows)
            + f"\nSNR q / V / α / h: {' / '.join(f'{v:.1f}' for v in snr)} dB (thesis ≈ 35).\n![](b747.png)\n"), png


def _item19(*, model_sets, seed, **_):
    from fdikit.studies.hallouzi2008.example_3_1 import example_3_1

    ex = example_3_1(model_sets=model_sets, seed=seed)
    freq = ex.frequency()
    ratio = float(np.median(ex.observability[:, 4] / ex.observability[:, 3]))
    rows = [[str(i + 1)] + [f"{v:.3g}" for v in row] for i, row in enumerate(ex.observability)]
    return ("## Item 19: Example 3.1, mean observability condition number per model pair\n\n"
            + _table(["set", "{1,2}", "{1,3}", "{2,3}", "{1,4}", "{2,4}", "{3,4}"], rows)
            + "\nPatterns (fraction of sets): " + ", ".join(f"{k} {v:.2f}" for k, v in freq.items())
            + f"; median cond{{2,4}}/cond{{1,4}} = {ratio:.2f} (printed 1.50).\n"), None


def _item20(*, msd_dt, seed, **_):
    from fdikit.studies.hallouzi2008.msd import MSD_STATES, msd_observability_comparison, simulate_msd
    from fdikit.studies.hallouzi2008.msd_model_sets import msd_table_3_3

    sim = simulate_msd(seed=seed, dt=msd_dt)
    t33 = msd_table_3_3(sim)
    png = _png(plot_msd, sim, t33)
    rows = [[k.upper()] + [f"{r.vaf[s]:.1f}" for s in MSD_STATES] for k, r in t33.items()]
    t34 = msd_observability_comparison(seed=seed)
    return ("## Item 20: MSD, state VAF (%) (Table 3.3)\n\n" + _table(["set", *MSD_STATES], rows)
            + "\n![](msd.png)\n\nTable 3.4, mean observability condition number: "
            + ", ".join(f"{a:.3g} (OD) vs {b:.3g} (min. mismatch)" for a, b in zip(t34.od, t34.mismatch))
            + f"; ratio {t34.ratio.min():.2f}–{t34.ratio.max():.2f} (thesis 16.1–16.15).\n"), png
