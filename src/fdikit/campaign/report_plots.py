"""The figures of the campaign report (:mod:`fdikit.campaign.report`), drawn on matplotlib ``Figure`` objects.

Every figure is a :class:`matplotlib.figure.Figure` made directly (no pyplot, no global figure state, the
backend never selected), so the report can be written from any thread or a process without a display;
:func:`png_data_uri` encodes one for an ``<img>`` of a self-contained page and :func:`write_png` writes one
atomically.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

__all__ = ["new_figure", "png_bytes", "png_data_uri", "write_png", "delay_distribution_figure", "tradeoff_figure",
           "detection_by_fault_figure", "example_trace_figure"]

_NONE = "none"


def new_figure(width: float = 8.0, height: float = 4.0):
    """A new matplotlib figure, not registered with pyplot.

    Parameters
    ----------
    width, height : float
        Size [inch].

    Returns
    -------
    matplotlib.figure.Figure
        The empty figure.

    Examples
    --------
    >>> new_figure(4, 3).get_size_inches().tolist()
    [4.0, 3.0]
    """
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def png_bytes(fig, dpi: int = 100) -> bytes:
    """The figure as PNG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    dpi : int, default 100
        Resolution.

    Returns
    -------
    bytes
        The PNG file.

    Examples
    --------
    >>> png_bytes(new_figure(2, 1))[1:4]
    b'PNG'
    """
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def png_data_uri(fig, dpi: int = 100) -> str:
    """The figure as a ``data:image/png;base64,...`` URI for an ``<img src=...>``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    dpi : int, default 100
        Resolution.

    Returns
    -------
    str
        The URI.

    Examples
    --------
    >>> png_data_uri(new_figure(2, 1))[:22]
    'data:image/png;base64,'
    """
    return "data:image/png;base64," + base64.b64encode(png_bytes(fig, dpi)).decode("ascii")


def write_png(fig, path: str | Path, dpi: int = 100) -> Path:
    """Write the figure as PNG atomically (:func:`fdikit.atomic.write_bytes`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The file.
    dpi : int, default 100
        Resolution.

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_png(new_figure(2, 1), pathlib.Path(tempfile.mkdtemp()) / "f.png")
    >>> p.read_bytes()[1:4]
    b'PNG'
    """
    from fdikit.atomic import write_bytes

    path = Path(path)
    write_bytes(path, png_bytes(fig, dpi))
    return path


def _pairs(df) -> list[tuple[str, str]]:
    return sorted({(str(d), str(e)) for d, e in zip(df["design"], df["evaluator"])})


def delay_distribution_figure(table):
    """Detection-delay distributions: one panel per design, the empirical CDF of each evaluator.

    The curve at delay ``d`` is the fraction of the faulty runs detected within ``d`` seconds of the onset,
    so it levels off at the detection rate.

    Parameters
    ----------
    table : pandas.DataFrame
        Results rows with ``design``, ``evaluator``, ``fault``, ``detected``, ``detection_delay``.

    Returns
    -------
    matplotlib.figure.Figure or None
        None when no faulty run was detected.

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame(dict(design=["a", "a"], evaluator=["e", "e"], fault=["f", "f"], detected=[True, False],
    ...                       detection_delay=[0.5, float("nan")]))
    >>> len(delay_distribution_figure(t).axes)
    1
    """
    faulty = table[table["fault"] != _NONE]
    det = faulty[faulty["detected"].astype(bool) & np.isfinite(faulty["detection_delay"].astype(float))]
    if det.empty:
        return None
    designs = sorted({str(d) for d in faulty["design"]})
    fig = new_figure(8.0, 2.6 * len(designs) + 0.4)
    axes = fig.subplots(len(designs), 1, squeeze=False, sharex=True)[:, 0]
    for ax, design in zip(axes, designs):
        rows = faulty[faulty["design"] == design]
        for evaluator in sorted({str(e) for e in rows["evaluator"]}):
            g = rows[rows["evaluator"] == evaluator]
            d = np.sort(g.loc[g["detected"].astype(bool), "detection_delay"].to_numpy(float))
            d = d[np.isfinite(d)]
            if d.size == 0:
                continue
            y = np.arange(1, d.size + 1) / len(g)
            ax.step(np.r_[0.0, d], np.r_[0.0, y], where="post", label=evaluator)
        ax.set_title(f"design {design}", fontsize=9)
        ax.set_ylabel("detected fraction", fontsize=8)
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    axes[-1].set_xlabel("detection delay after onset [s]")
    return fig


def tradeoff_figure(tradeoff, floor: float | None = None):
    """The trade-off curves over the threshold sweep: median delay and detection rate against false alarms per hour.

    One line per design × evaluator through its sweep levels; the nominal level (1.0) is a star.  The false-alarm
    axis is logarithmic: a level without false alarms is drawn, as an open marker, at ``floor`` (default half
    the smallest resolvable rate, ``0.5 / hours``).

    Parameters
    ----------
    tradeoff : pandas.DataFrame
        :attr:`fdikit.campaign.stats.CampaignStatistics.tradeoff`.
    floor : float, optional
        Where zero rates are drawn [1/h].

    Returns
    -------
    matplotlib.figure.Figure or None
        None without fault-free time.

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame(dict(design="a", evaluator="e", level=[0.5, 1.0], false_alarm_rate=[2.0, 0.0],
    ...                       fault_free_hours=2.0, delay_median=[0.5, 1.0], detection_rate=[1.0, 0.5]))
    >>> [ax.get_xscale() for ax in tradeoff_figure(t).axes]
    ['log', 'log']
    """
    ok = tradeoff[np.isfinite(tradeoff["false_alarm_rate"].astype(float))]
    if ok.empty:
        return None
    if floor is None:
        floor = 0.5 / float(ok["fault_free_hours"].max())
    fig = new_figure(9.0, 4.0)
    ax_delay, ax_rate = fig.subplots(1, 2)
    for k, (design, evaluator) in enumerate(_pairs(ok)):
        g = ok[(ok["design"] == design) & (ok["evaluator"] == evaluator)].sort_values("level")
        x = np.maximum(g["false_alarm_rate"].to_numpy(float), floor)
        zero = g["false_alarm_rate"].to_numpy(float) <= 0
        nominal = np.isclose(g["level"].to_numpy(float), 1.0)
        color = f"C{k % 10}"
        for ax, y in ((ax_delay, g["delay_median"].to_numpy(float)), (ax_rate, g["detection_rate"].to_numpy(float))):
            ax.plot(x, y, "-", color=color, lw=1.0, label=f"{design} / {evaluator}")
            ax.plot(x[~zero], y[~zero], "o", color=color, ms=3)
            ax.plot(x[zero], y[zero], "o", mfc="none", color=color, ms=4)
            ax.plot(x[nominal], y[nominal], "*", color=color, ms=10)
    for ax in (ax_delay, ax_rate):
        ax.set_xscale("log")
        ax.set_xlabel("false alarms per hour")
        ax.grid(alpha=0.3, which="both")
    ax_delay.set_ylabel("median detection delay [s]")
    ax_rate.set_ylabel("detection rate")
    ax_rate.set_ylim(0, 1.02)
    ax_delay.legend(fontsize=7)
    return fig


def detection_by_fault_figure(detection):
    """Detection rate per fault: grouped horizontal bars, one per design × evaluator, with their intervals.

    Parameters
    ----------
    detection : pandas.DataFrame
        :attr:`fdikit.campaign.stats.CampaignStatistics.detection`.

    Returns
    -------
    matplotlib.figure.Figure or None
        None without faulty runs.

    Examples
    --------
    >>> import pandas as pd
    >>> d = pd.DataFrame(dict(design="a", evaluator="e", fault=["f", "g"], detection_rate=[0.5, 1.0],
    ...                       detection_low=[0.1, 0.7], detection_high=[0.9, 1.0]))
    >>> len(detection_by_fault_figure(d).axes[0].patches)
    2
    """
    if detection.empty:
        return None
    faults = sorted({str(f) for f in detection["fault"]})
    pairs = _pairs(detection)
    fig = new_figure(8.0, 0.25 * len(faults) * len(pairs) + 0.5 * len(faults) + 1.2)
    ax = fig.subplots()
    height = 0.8 / len(pairs)
    for k, (design, evaluator) in enumerate(pairs):
        g = detection[(detection["design"] == design) & (detection["evaluator"] == evaluator)].set_index("fault")
        g = g.reindex(faults)
        rate = g["detection_rate"].to_numpy(float)
        err = np.vstack([rate - g["detection_low"].to_numpy(float), g["detection_high"].to_numpy(float) - rate])
        y = np.arange(len(faults)) + (k - (len(pairs) - 1) / 2) * height
        ax.barh(y, np.nan_to_num(rate), height=height * 0.9, xerr=np.nan_to_num(err), color=f"C{k % 10}",
                error_kw={"lw": 0.8, "capsize": 2}, label=f"{design} / {evaluator}")
    ax.set_yticks(np.arange(len(faults)), faults, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1.02)
    ax.set_xlabel("detection rate (bars: Clopper–Pearson interval)")
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=7, loc="lower right")
    return fig


def example_trace_figure(residuals, diagnosis, onset: float | None = None, title: str = ""):
    """One example run: a panel per residual (alarm samples marked, onset dotted, alarms red) and the decisions.

    Parameters
    ----------
    residuals : fdikit.residuals.Residuals
        The run's residuals.
    diagnosis : fdikit.diagnosis.Diagnosis
        The evaluator's decisions on them; a ``thresholds`` list in its ``meta`` (one per residual) is drawn.
    onset : float, optional
        Fault onset [s] (None for a fault-free run).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Examples
    --------
    >>> from fdikit.diagnosis import Diagnosis, isolate
    >>> from fdikit.residuals import Residuals
    >>> t = np.arange(50) * 0.1
    >>> res = Residuals(t, (t > 2.5).astype(float)[:, None], ("r",), ("f",))
    >>> fired = res.r > 0.5
    >>> diag = Diagnosis(t, fired[:, 0], fired, ("r",), isolate(fired, ("f",)))
    >>> len(example_trace_figure(res, diag, onset=2.5, title="run 0").axes)
    2
    """
    q = len(residuals.names)
    shown = list(residuals.names[:8])
    fig = new_figure(9.0, 1.5 * len(shown) + 0.45 * len(diagnosis.names) + 1.6)
    axes = fig.subplots(len(shown) + 1, 1, sharex=True, squeeze=False,
                        height_ratios=[1.0] * len(shown) + [0.3 * len(diagnosis.names) + 0.8])[:, 0]
    tau = diagnosis.meta.get("thresholds") if isinstance(diagnosis.meta, dict) else None
    tau = np.asarray(tau, float) if tau is not None and np.size(tau) == q else None
    residuals.plot(ax=list(axes[:-1]), diagnosis=diagnosis if diagnosis.fired.shape[1] == q else None,
                   thresholds=tau, onset=onset, names=shown)
    axes[-2].set_xlabel("")
    diagnosis.plot(ax=axes[-1])
    for ax in axes:
        for a in diagnosis.alarms:
            ax.axvline(a.time, color="tab:red", lw=0.8, alpha=0.6)
    if onset is not None:
        axes[-1].axvline(onset, color="k", lw=0.8, ls=":")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
