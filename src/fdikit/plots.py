"""Plots of residuals, thresholds, alarms and the fault onset."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fdikit.diagnosis import Diagnosis
from fdikit.residuals import Residuals

__all__ = ["plot_residuals", "save_figure", "figure_bytes"]


def save_figure(fig, path, dpi: int = 120):
    """Write ``fig`` to ``path`` atomically (:mod:`fdikit.atomic`); the format follows the suffix (PNG default).

    A kill or an error during the write leaves the previous file at ``path`` (if any) untouched.
    ``path`` may also be a binary file object (written as PNG, not atomic: the caller owns it).
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
    """The figure encoded as ``fmt`` (PNG by default), for storing it with a result part."""
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
        A new figure when ``ax`` is None, else ``ax``.  The backend is never changed.
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
