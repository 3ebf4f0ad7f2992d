"""Plots of traces, residuals, thresholds, alarms, decisions, mode probabilities and model weights.

Every function follows the "plots" convention of ``docs/ARCHITECTURE.md``: it takes ``ax=`` and draws
into it (no new figure), or makes a new figure when ``ax`` is None; it returns the given ``ax``, or the
figure it made; it never selects a matplotlib backend or changes rcParams.  matplotlib is imported only
when something is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fdikit.diagnosis import Diagnosis
from fdikit.residuals import Residuals

if TYPE_CHECKING:
    from fdikit.multimodel.convex_filter import ConvexFilterResult
    from fdikit.multimodel.imm import IMMResult
    from fdikit.multimodel.kalman import KalmanResult
    from fdikit.trace import Trace

__all__ = ["plot_residuals", "plot_trace", "plot_diagnosis", "plot_innovations", "plot_mode_probabilities",
           "plot_weights", "axes_or_new", "finish_plot", "save_figure", "figure_bytes"]


def save_figure(fig, path, dpi: int = 120):
    """Write ``fig`` to ``path`` atomically (:mod:`fdikit.atomic`); the format follows the suffix (PNG default).

    A kill or an error during the write leaves the previous file at ``path`` (if any) untouched.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str, Path or binary file object
        The file; a file object is written as PNG (not atomic: the caller owns it).
    dpi : int
        Resolution.

    Returns
    -------
    Path or the file object
        ``path``.

    Examples
    --------
    >>> import io
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> save_figure(fig, io.BytesIO()).getvalue()[1:4]
    b'PNG'
    >>> plt.close(fig)
    """
    from fdikit.atomic import atomic_path

    if hasattr(path, "write"):
        fig.savefig(path, format="png", dpi=dpi)
        return path
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=dpi)
    return path


def figure_bytes(fig, dpi: int = 120, fmt: str = "png") -> bytes:
    """The figure encoded as ``fmt`` (PNG by default), for storing it with a result part.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    dpi : int
        Resolution.
    fmt : str
        Any format matplotlib writes (``'png'``, ``'svg'``, ``'pdf'`` ...).

    Returns
    -------
    bytes
        The encoded figure.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> figure_bytes(fig, fmt="svg").lstrip()[:5]
    b'<?xml'
    >>> plt.close(fig)
    """
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi)
    return buf.getvalue()


def plot_residuals(
    residuals: Residuals,
    diagnosis: Diagnosis | None = None,
    thresholds: np.ndarray | None = None,
    center: np.ndarray | None = None,
    onset: float | None = None,
    names: Sequence[str] | None = None,
    title: str | None = None,
    path: str | Path | None = None,
    ax=None,
):
    """One panel per residual with its threshold band, alarm samples and the fault onset.

    Parameters
    ----------
    residuals, diagnosis, thresholds, center, onset, names, title
        The series, its decisions (alarm samples marked), the band ``center ± thresholds``, the fault
        onset time, the residuals to draw (default all) and a title.
    path : str or Path, optional
        Write the figure there (PNG, PDF ...; atomically, see :func:`save_figure`).
    ax : matplotlib Axes or sequence of Axes, optional
        Draw into these instead of a new figure: one Axes per residual, or a single Axes for all.

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None (closed once written to ``path``), else ``ax``.  The backend is
        never changed.

    Raises
    ------
    ParameterError
        When ``ax`` holds neither one Axes nor one per residual.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> t = np.arange(100) * 0.1
    >>> res = Residuals(t, np.c_[np.sin(t), np.cos(t)], ("a", "b"), ())
    >>> fig, axes = plt.subplots(2, 1)
    >>> plot_residuals(res, thresholds=0.9, onset=5.0, ax=axes) is axes, len(axes[0].lines)
    (True, 4)
    >>> plt.close(fig)
    """
    names = list(names or residuals.names)
    idx = [residuals.names.index(n) for n in names]
    given = ax
    if ax is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(len(idx), 1, sharex=True, figsize=(9, 1.6 * len(idx) + 0.8), squeeze=False)
        panels = list(grid[:, 0])
    else:
        panels = list(np.ravel(np.asarray(ax, dtype=object)))
        panels = panels * len(idx) if len(panels) == 1 else panels
        if len(panels) != len(idx):
            from fdikit.errors import ParameterError

            raise ParameterError(f"ax has {len(panels)} axes for {len(idx)} residuals; give one, or one per residual")
        fig = panels[0].figure
    for ax, j in zip(panels, idx):
        ax.plot(residuals.t, residuals.r[:, j], lw=0.7, color="tab:blue")
        c = 0.0 if center is None else float(np.broadcast_to(center, (len(residuals.names),))[j])
        if thresholds is not None:
            tau = float(np.broadcast_to(thresholds, (len(residuals.names),))[j])
            for s in (-1, 1):
                ax.axhline(c + s * tau, color="tab:red", ls="--", lw=0.8)
        if diagnosis is not None:
            hit = diagnosis.fired[:, j]
            ax.plot(residuals.t[hit], residuals.r[hit, j], ".", ms=2, color="tab:red")
        if onset is not None:
            ax.axvline(onset, color="k", lw=0.8, ls=":")
        ax.set_ylabel(residuals.names[j], rotation=0, ha="right", fontsize=8)
        ax.tick_params(labelsize=7)
    panels[-1].set_xlabel("time [s]")
    if title:
        fig.suptitle(title, fontsize=10)
    if given is not None:
        if path is not None:
            save_figure(fig, path)
        return given
    fig.tight_layout()
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


def axes_or_new(ax, n: int = 1, **subplots_kw):
    """The figure and the ``n`` axes to draw into: those given, or those of a new figure.

    Parameters
    ----------
    ax : matplotlib Axes, sequence or array of Axes, or None
        Where to draw: ``n`` axes (one Axes when ``n`` is 1).  None makes a new figure with
        ``n`` panels in one column (``plt.subplots(n, 1, squeeze=False, **subplots_kw)``).
    n : int
        The number of panels the plot needs.
    **subplots_kw
        Passed to :func:`matplotlib.pyplot.subplots` for a new figure (``figsize``, ``sharex`` ...).

    Returns
    -------
    fig : matplotlib.figure.Figure
        The figure of the first axes.
    panels : list of Axes
        ``n`` axes.

    Raises
    ------
    ParameterError
        When ``ax`` does not hold exactly ``n`` axes.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, axes = plt.subplots(2, 1)
    >>> axes_or_new(axes, 2)[1] == list(axes)
    True
    >>> plt.close(fig)
    """
    if ax is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(n, 1, squeeze=False, **subplots_kw)
        return fig, list(grid[:, 0])
    panels = list(np.ravel(np.asarray(ax, dtype=object)))
    if len(panels) != n:
        from fdikit.errors import ParameterError

        raise ParameterError(f"ax has {len(panels)} axes; this plot draws {n} panel(s): give {n} axes or ax=None")
    return panels[0].figure, panels


def finish_plot(fig, ax, path=None, dpi: int = 120):
    """What a plot returns: the given ``ax``, or the figure it made (laid out; written and closed with ``path``).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure drawn into.
    ax : Axes, sequence of Axes or None
        The caller's ``ax`` argument (None when the plot made ``fig``).
    path : str, Path or binary file object, optional
        Write the figure there (:func:`save_figure`, atomically).  A figure the plot made is then
        closed (it is in the file); the caller's figure is left open.
    dpi : int
        Resolution of the file.

    Returns
    -------
    The given ``ax``, or ``fig`` when ``ax`` is None.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> finish_plot(fig, ax) is ax
    True
    >>> plt.close(fig)
    """
    if ax is not None:
        if path is not None:
            save_figure(fig, path, dpi=dpi)
        return ax
    fig.tight_layout()
    if path is not None:
        import matplotlib.pyplot as plt

        save_figure(fig, path, dpi=dpi)
        plt.close(fig)
    return fig


def _spans(mask: np.ndarray) -> list[tuple[int, int]]:
    """The runs of True in ``mask`` as ``(first, last)`` index pairs."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    edges = np.flatnonzero(np.diff(m.astype(np.int8)))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2])]


def plot_trace(trace: Trace, signals: Sequence[str] | None = None, kind: str = "y", ax=None,
               title: str | None = None, path=None):
    """The signals of a trace over time, with the faulty samples shaded.

    Parameters
    ----------
    trace : Trace
        The run.
    signals : sequence of str, optional
        The signals to draw (default all of block ``kind``).
    kind : {'y', 'u', 'x', 'd'}
        The block the signals belong to: measurements, controls, states or disturbances.
    ax : matplotlib Axes, optional
        Draw into it; default a new figure.
    title : str, optional
        Axes title.
    path : str, Path or binary file object, optional
        Write the figure there (see :func:`finish_plot`).

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None, else ``ax``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from fdikit.trace import Trace
    >>> t = np.arange(4) * 0.1
    >>> tr = Trace(t=t, u=np.zeros((4, 1)), y=np.c_[t, -t], controls=["steer"], outputs=["a", "b"],
    ...            fault=["none", "none", "a_sensor", "a_sensor"])
    >>> fig, ax = plt.subplots()
    >>> plot_trace(tr, ax=ax) is ax, len(ax.lines), len(ax.patches)
    (True, 2, 1)
    >>> plt.close(fig)
    """
    names = list(signals) if signals is not None else list(trace.names_of(kind))
    fig, (axes,) = axes_or_new(ax, 1, figsize=(9, 3.5))
    for nm in names:
        axes.plot(trace.t, trace.signal(nm, kind), lw=0.8, label=nm)
    for a, b in _spans(trace.fault != "none"):
        axes.axvspan(trace.t[a], trace.t[b], color="0.9", zorder=0)
    axes.set_xlabel("time [s]")
    axes.set_ylabel({"y": "measurements", "u": "controls", "x": "states", "d": "disturbances"}.get(kind, kind))
    if names:
        axes.legend(fontsize=7, loc="upper right")
    if title:
        axes.set_title(title, fontsize=10)
    return finish_plot(fig, ax, path)


def plot_diagnosis(diagnosis: Diagnosis, ax=None, title: str | None = None, path=None):
    """The decisions over time: one step line per residual (or hypothesis), the alarm above them.

    Each alarm is labelled with the fault it isolated; samples the evaluator did not use
    (``valid`` False) are shaded.

    Parameters
    ----------
    diagnosis : Diagnosis
        The decisions.
    ax : matplotlib Axes, optional
        Draw into it; default a new figure.
    title : str, optional
        Axes title.
    path : str, Path or binary file object, optional
        Write the figure there (see :func:`finish_plot`).

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None, else ``ax``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fired = np.array([[0, 0], [1, 0], [1, 0]], bool)
    >>> d = Diagnosis(t=np.arange(3.0), alarm=fired.any(1), fired=fired, names=("ra", "rb"),
    ...               isolated=np.array(["none", "a", "a"]))
    >>> fig, ax = plt.subplots()
    >>> plot_diagnosis(d, ax=ax) is ax, len(ax.lines), [x.get_text() for x in ax.texts]
    (True, 3, ['a'])
    >>> plt.close(fig)
    """
    t, q = diagnosis.t, len(diagnosis.names)
    fig, (axes,) = axes_or_new(ax, 1, figsize=(9, 0.45 * q + 1.5))
    for j in range(q):
        axes.step(t, j + 0.8 * diagnosis.fired[:, j], where="post", lw=0.8, color="tab:blue")
    axes.step(t, q + 0.8 * np.asarray(diagnosis.alarm, float), where="post", lw=1.0, color="tab:red")
    for a in diagnosis.alarms:
        axes.text(a.time, q + 0.85, a.fault, fontsize=7, va="bottom")
    for a, b in _spans(~diagnosis.valid):
        axes.axvspan(t[a], t[b], color="0.9", zorder=0)
    axes.set_yticks(range(q + 1), [*diagnosis.names, "alarm"], fontsize=7)
    axes.set_ylim(-0.3, q + 1.3)
    axes.set_xlabel("time [s]")
    if title:
        axes.set_title(title, fontsize=10)
    return finish_plot(fig, ax, path)


def plot_innovations(result: KalmanResult, t=None, names: Sequence[str] | None = None, sigmas: float = 2.0,
                     ax=None, title: str | None = None, path=None):
    """The innovations of a Kalman filter run with their ``± sigmas·√S_ii`` bands.

    Parameters
    ----------
    result : KalmanResult
        The filtered record.
    t : array_like, optional
        The time of each sample (default the sample index).
    names : sequence of str, optional
        The measurement names (legend); default ``e0, e1, ...``.
    sigmas : float
        Half-width of the band in innovation standard deviations.
    ax : matplotlib Axes, optional
        Draw into it; default a new figure.
    title : str, optional
        Axes title.
    path : str, Path or binary file object, optional
        Write the figure there (see :func:`finish_plot`).

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None, else ``ax``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.kalman import kalman_filter
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> res = kalman_filter(mdl, None, [[1.0], [0.5], [0.2]], x0=[0.0], P0=[[1.0]])
    >>> fig, ax = plt.subplots()
    >>> plot_innovations(res, ax=ax) is ax, len(ax.lines)
    (True, 3)
    >>> plt.close(fig)
    """
    e = np.asarray(result.innovations)
    xlabel = "sample k" if t is None else "time"
    t = np.arange(e.shape[0]) if t is None else np.asarray(t, float)
    names = list(names) if names is not None else [f"e{j}" for j in range(e.shape[1])]
    fig, (axes,) = axes_or_new(ax, 1, figsize=(9, 3.5))
    for j, nm in enumerate(names):
        (line,) = axes.plot(t, e[:, j], lw=0.8, label=nm)
        band = sigmas * np.sqrt(np.asarray(result.S)[:, j, j])
        axes.plot(t, band, ls="--", lw=0.6, color=line.get_color())
        axes.plot(t, -band, ls="--", lw=0.6, color=line.get_color())
    axes.set_xlabel(xlabel)
    axes.set_ylabel("innovation")
    if names:
        axes.legend(fontsize=7, loc="upper right")
    if title:
        axes.set_title(title, fontsize=10)
    return finish_plot(fig, ax, path)


def _lines(ax, t, values, names, ylabel: str, xlabel: str, title: str | None) -> None:
    for j, nm in enumerate(names):
        ax.plot(t, values[:, j], lw=1, label=nm)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if names:
        ax.legend(fontsize=7, loc="upper right")
    if title:
        ax.set_title(title, fontsize=10)


def plot_mode_probabilities(result: IMMResult, ax=None, title: str | None = None, path=None):
    """The mode probabilities of an IMM run over time, one line per mode.

    Parameters
    ----------
    result : IMMResult
        The IMM run (``result.t`` on the x axis, ``result.mu`` drawn, ``result.modes`` in the legend).
    ax : matplotlib Axes, optional
        Draw into it; default a new figure.
    title : str, optional
        Axes title.
    path : str, Path or binary file object, optional
        Write the figure there (see :func:`finish_plot`).

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None, else ``ax``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.imm import IMMFilter
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    >>> res = imm.run(np.zeros((5, 0)), 2.0 * np.ones((5, 1)))
    >>> fig, ax = plt.subplots()
    >>> plot_mode_probabilities(res, ax=ax) is ax, [x.get_label() for x in ax.lines]
    (True, ['nominal', 'gain fault'])
    >>> plt.close(fig)
    """
    fig, (axes,) = axes_or_new(ax, 1, figsize=(9, 3.5))
    _lines(axes, result.t, np.asarray(result.mu), list(result.modes), "mode probability", "time", title)
    axes.set_ylim(-0.03, 1.03)
    return finish_plot(fig, ax, path)


def plot_weights(result: ConvexFilterResult, t=None, raw: bool = False, ax=None, title: str | None = None,
                 path=None):
    """The model weights of a convex-model filter run over time, one line per model.

    Parameters
    ----------
    result : ConvexFilterResult
        The run (``result.mu`` drawn, ``result.names`` in the legend).
    t : array_like, optional
        The time of each sample (default the sample index).
    raw : bool
        Draw the weights before the projection (``result.mu_raw``) instead.
    ax : matplotlib Axes, optional
        Draw into it; default a new figure.
    title : str, optional
        Axes title.
    path : str, Path or binary file object, optional
        Write the figure there (see :func:`finish_plot`).

    Returns
    -------
    matplotlib.figure.Figure or the given ``ax``
        A new figure when ``ax`` is None, else ``ax``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> from fdikit.multimodel.convex_filter import dual_convex_filter
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> u = np.ones((5, 1))
    >>> res = dual_convex_filter(ms, np.zeros((5, 1)), u, x0=[0.0], P0=[[1.0]])
    >>> fig, ax = plt.subplots()
    >>> plot_weights(res, ax=ax) is ax, [x.get_label() for x in ax.lines]
    (True, ['stuck', 'nominal'])
    >>> plt.close(fig)
    """
    mu = np.asarray(result.mu_raw if raw else result.mu)
    xlabel = "sample k" if t is None else "time"
    t = np.arange(mu.shape[0]) if t is None else np.asarray(t, float)
    fig, (axes,) = axes_or_new(ax, 1, figsize=(9, 3.5))
    _lines(axes, t, mu, list(result.names), "weight μ (before projection)" if raw else "weight μ", xlabel, title)
    return finish_plot(fig, ax, path)
