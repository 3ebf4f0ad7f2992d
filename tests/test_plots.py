"""Plots follow docs/ARCHITECTURE.md ("plots"): they draw into a given ``ax``, create no figure then,
and never select a matplotlib backend."""

from __future__ import annotations

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.residuals import Residuals


@pytest.fixture
def residuals():
    t = np.arange(200) * 0.01
    r = np.column_stack([np.sin(t), np.cos(t)])
    return Residuals(t, r, ("a", "b"), ("fa", "fb"))


@pytest.fixture(autouse=True)
def _close_all():
    yield
    plt.close("all")


def test_importing_and_plotting_keep_the_backend(residuals, tmp_path):
    before = matplotlib.get_backend()
    import fdikit.plots as plots

    fig = plots.plot_residuals(residuals, thresholds=0.5, onset=1.0, path=tmp_path / "r.png")
    assert matplotlib.get_backend() == before
    assert (tmp_path / "r.png").stat().st_size > 0
    assert not plt.fignum_exists(fig.number)  # written to path: closed


def test_plot_residuals_draws_into_the_given_axes(residuals):
    from fdikit.plots import plot_residuals

    fig, axes = plt.subplots(2, 1)
    n_figs = len(plt.get_fignums())
    out = plot_residuals(residuals, thresholds=[0.5, 0.7], onset=1.0, ax=axes)
    assert out is axes
    assert len(plt.get_fignums()) == n_figs  # no new figure
    for ax in axes:
        assert len(ax.lines) == 4  # the residual, two threshold lines, the onset
    one = plt.figure().add_subplot()
    n_figs = len(plt.get_fignums())
    assert plot_residuals(residuals, ax=one) is one
    assert len(one.lines) == 2 and len(plt.get_fignums()) == n_figs
    with pytest.raises(ParameterError, match="one per residual"):
        plot_residuals(residuals, ax=list(axes) + [one])


def test_a_new_figure_without_ax(residuals):
    from fdikit.plots import plot_residuals

    n_figs = len(plt.get_fignums())
    fig = plot_residuals(residuals)
    assert len(plt.get_fignums()) == n_figs + 1 and len(fig.axes) == 2
    plt.close(fig)
    assert len(plt.get_fignums()) == n_figs
