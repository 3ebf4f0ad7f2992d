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


# ---------------------------------------------------------------- the result types' .plot() and their functions
def _trace():
    from fdikit.trace import Trace

    t = np.arange(50) * 0.1
    return Trace(t=t, u=np.zeros((50, 1)), y=np.column_stack([np.sin(t), np.cos(t)]), controls=["steer"],
                 outputs=["a", "b"], fault=["none"] * 20 + ["a_sensor"] * 20 + ["none"] * 10)


def _diagnosis():
    from fdikit.diagnosis import Diagnosis

    fired = np.zeros((50, 2), bool)
    fired[25:40, 0] = True
    valid = np.ones(50, bool)
    valid[5:8] = False
    isolated = np.where(fired[:, 0], "a_sensor", "none")
    return Diagnosis(np.arange(50) * 0.1, fired.any(axis=1), fired, ("ra", "rb"), isolated, valid=valid)


def _kalman():
    from fdikit.gaussian import LinearGaussianModel
    from fdikit.multimodel.kalman import kalman_filter

    mdl = LinearGaussianModel(A=np.diag([0.9, 0.8]), C=np.eye(2), Q=0.1 * np.eye(2), R=np.eye(2))
    y = np.random.default_rng(0).normal(size=(30, 2))
    return kalman_filter(mdl, None, y, x0=[0.0, 0.0], P0=np.eye(2))


def _imm():
    from fdikit.gaussian import LinearGaussianModel
    from fdikit.multimodel.imm import IMMFilter

    m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    return imm.run(np.zeros((20, 0)), 2.0 * np.ones((20, 1)))


def _convex():
    from fdikit.multimodel.convex import convex_model_set
    from fdikit.multimodel.convex_filter import dual_convex_filter

    ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]], names=["stuck", "nominal"])
    u = np.sin(0.3 * np.arange(30)).reshape(-1, 1)
    x, y = 0.0, []
    for uk in u[:, 0]:
        y.append([x])
        x = 0.9 * x + uk
    return dual_convex_filter(ms, np.array(y), u, x0=[0.0], P0=[[1.0]])


#: (result factory, the plot function's name, lines drawn into the axes)
RESULTS = {
    "trace": (_trace, "plot_trace", 2),
    "diagnosis": (_diagnosis, "plot_diagnosis", 3),  # one step line per residual and the alarm
    "kalman": (_kalman, "plot_innovations", 6),  # per innovation: the series and its two band lines
    "imm": (_imm, "plot_mode_probabilities", 2),
    "convex": (_convex, "plot_weights", 2),
}


@pytest.mark.parametrize("kind", RESULTS)
@pytest.mark.parametrize("via", ["method", "function"])
def test_result_plots_draw_into_the_given_axes(kind, via):
    import fdikit.plots as plots

    make, func, n_lines = RESULTS[kind]
    result = make()
    draw = result.plot if via == "method" else lambda **kw: getattr(plots, func)(result, **kw)
    backend = matplotlib.get_backend()
    fig, ax = plt.subplots()
    n_figs = plt.get_fignums()
    out = draw(ax=ax)
    assert out is ax
    assert plt.get_fignums() == n_figs  # no new figure
    assert len(ax.lines) == n_lines
    assert ax.get_xlabel()
    assert matplotlib.get_backend() == backend
    plt.close(fig)


@pytest.mark.parametrize("kind", RESULTS)
def test_result_plots_make_a_figure_without_ax(kind, tmp_path):
    make, _, n_lines = RESULTS[kind]
    result = make()
    backend = matplotlib.get_backend()
    n_figs = len(plt.get_fignums())
    fig = result.plot()
    assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 1
    assert len(fig.axes[0].lines) == n_lines
    assert len(plt.get_fignums()) == n_figs + 1
    plt.close(fig)
    fig = result.plot(path=tmp_path / "p.png")  # written to path: closed
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    assert not plt.fignum_exists(fig.number) and len(plt.get_fignums()) == n_figs
    assert matplotlib.get_backend() == backend


def test_plots_mark_what_the_results_hold():
    ax = plt.figure().add_subplot()
    _trace().plot(ax=ax)
    assert len(ax.patches) == 1  # the faulty stretch is shaded
    assert [ln.get_label() for ln in ax.lines] == ["a", "b"]
    ax = plt.figure().add_subplot()
    _trace().plot(ax=ax, kind="u")
    assert [ln.get_label() for ln in ax.lines] == ["steer"]
    ax = plt.figure().add_subplot()
    _diagnosis().plot(ax=ax)
    assert [tl.get_text() for tl in ax.get_yticklabels()] == ["ra", "rb", "alarm"]
    assert [tx.get_text() for tx in ax.texts] == ["a_sensor"]  # the alarm, labelled with its isolation
    assert len(ax.patches) == 1  # the invalid samples
    ax = plt.figure().add_subplot()
    res = _kalman()
    res.plot(ax=ax, sigmas=3.0)
    np.testing.assert_allclose(ax.lines[1].get_ydata(), 3.0 * np.sqrt(res.S[:, 0, 0]))
    ax = plt.figure().add_subplot()
    res = _imm()
    res.plot(ax=ax)
    np.testing.assert_array_equal(ax.lines[1].get_ydata(), res.mu[:, 1])
    ax = plt.figure().add_subplot()
    res = _convex()
    res.plot(ax=ax, raw=True)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), res.mu_raw[:, 0])


def test_a_wrong_number_of_axes_is_refused():
    from fdikit.plots import plot_trace

    _, axes = plt.subplots(2, 1)
    with pytest.raises(ParameterError, match="1 panel"):
        plot_trace(_trace(), ax=axes)


def test_importing_fdikit_and_the_result_modules_does_not_import_matplotlib():
    import subprocess
    import sys

    code = ("import sys, fdikit, fdikit.residuals, fdikit.diagnosis, fdikit.trace, fdikit.plots, "
            "fdikit.multimodel.kalman, fdikit.multimodel.imm, fdikit.multimodel.convex, fdikit.analysis.gains; "
            "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"


def _gain_table():
    from fdikit.analysis.gains import GainTable

    gains = np.array([[[1.0, 1e-3], [1e-4, 2.0]], [[0.5, 1e-3], [1e-4, 1.0]]])
    return GainTable(np.array([0.1, 1.0]), gains, ("f1", "f2"), ("g1", "g2"), (("r1",), ("r2",)))


def test_gain_table_plot_draws_into_the_given_axes(tmp_path):
    table = _gain_table()
    backend = matplotlib.get_backend()
    fig, ax = plt.subplots()
    n_figs = plt.get_fignums()
    assert table.plot(ax=ax) is ax
    assert plt.get_fignums() == n_figs and len(ax.images) == 1
    assert [t.get_text() for t in ax.texts] == ["0", "-60", "-80", "6"]  # peak gains in dB
    assert [t.get_text() for t in ax.get_yticklabels()] == ["f1", "f2"]
    assert table.plot(tmp_path / "s.png", ax=ax) is ax  # the caller's figure is written, and left open
    assert (tmp_path / "s.png").read_bytes()[:4] == b"\x89PNG" and plt.fignum_exists(fig.number)
    assert matplotlib.get_backend() == backend


def test_gain_table_plot_without_ax_makes_a_figure_outside_pyplot(tmp_path):
    from matplotlib.figure import Figure

    n_figs = plt.get_fignums()
    fig = _gain_table().plot(tmp_path / "s.svg")
    assert isinstance(fig, Figure) and plt.get_fignums() == n_figs  # its own Agg canvas, not a pyplot figure
    assert (tmp_path / "s.svg").read_bytes().lstrip().startswith(b"<?xml")
    assert list(tmp_path.iterdir()) == [tmp_path / "s.svg"]  # written atomically: no temporary file left


# ---------------------------------------------------------------- the studies' figures
def _b747_result():
    from types import SimpleNamespace

    from fdikit.studies.hallouzi2008.b747 import N_SAMPLES, TS

    t = TS * np.arange(N_SAMPLES)
    ones = {f: np.linspace(1.0, 2.0, t.size) for f in ("ekf", "imm")}
    return SimpleNamespace(t=t, filters=("ekf", "imm"), rmse_weights=ones, rmse_state=ones, runs=1)


def _msd_inputs():
    from types import SimpleNamespace

    t = np.arange(50) * 0.1
    sim = SimpleNamespace(t=t, params=np.ones((50, 4)))
    return sim, {"od": SimpleNamespace(params=np.ones((50, 4))), "lv": SimpleNamespace(params=np.zeros((50, 4)))}


def _target_tracking_result():
    from types import SimpleNamespace

    from fdikit.studies.hallouzi2008.target_tracking import N_SAMPLES, TS

    t = TS * np.arange(N_SAMPLES)
    per = {f: np.ones(t.size) for f in ("ekf", "imm")}
    return SimpleNamespace(t=t, filters=("ekf", "imm"), rmse_position=per, rmse_velocity=per, rmse_B=per,
                           cm_weights={f: np.full((t.size, 2), 0.5) for f in ("ekf", "imm")},
                           true_weights=np.full((t.size, 2), 0.5), runs=1)


def _bank_panels():
    from types import SimpleNamespace

    from fdikit.diagnosis import Diagnosis

    t = np.arange(100) * 0.1
    res = Residuals(t, np.column_stack([np.sin(t), np.cos(t), t]), ("F1:a", "F1:b", "F2:c"), ("a", "b", "c"))
    fired = np.abs(res.r) > 0.9
    diag = Diagnosis(t, fired.any(axis=1), fired, res.names, np.where(fired.any(axis=1), "a", "none"))
    band = SimpleNamespace(center=np.zeros(3), thresholds=np.full(3, 0.9))
    return [("one", res, diag, ["F1:a", "F1:b"]), ("two", res, diag, ["F2:c"])], band


def _study_plots():
    from fdikit.studies.hallouzi2008.report import plot_b747, plot_msd
    from fdikit.studies.hallouzi2008.target_tracking import plot_target_tracking
    from fdikit.studies.path1996.demo import plot_bank_report

    panels, band = _bank_panels()
    # name: (draw(path=, axes=), the axes layout it needs, lines per panel)
    return {
        "b747": (lambda **kw: plot_b747(_b747_result(), **kw), (2, 1), [2, 2]),
        "msd": (lambda **kw: plot_msd(*_msd_inputs(), **kw), (4, 1), [3] * 4),
        "target_tracking": (lambda **kw: plot_target_tracking(_target_tracking_result(), **kw), (4, 1),
                            [2, 2, 2, 3]),
        # per residual: the series, two threshold lines, the fired samples and the onset; unused panel empty
        "bank_report": (lambda **kw: plot_bank_report(panels, band, 5.0, **kw), (2, 2), [5, 5, 5, 0]),
    }


@pytest.mark.parametrize("name", ["b747", "msd", "target_tracking", "bank_report"])
def test_study_figures_draw_into_the_given_axes(name, tmp_path):
    draw, shape, lines = _study_plots()[name]
    backend = matplotlib.get_backend()
    fig, axes = plt.subplots(*shape, squeeze=False)
    axes = axes if shape[1] > 1 else axes[:, 0]
    n_figs = plt.get_fignums()
    assert draw(axes=axes) is axes
    assert plt.get_fignums() == n_figs  # no new figure
    assert [len(ax.lines) for ax in np.ravel(axes)] == lines
    assert draw(axes=axes, path=tmp_path / "f.png") is axes  # the caller's figure is written and left open
    assert (tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG" and plt.fignum_exists(fig.number)
    assert matplotlib.get_backend() == backend
    with pytest.raises(ParameterError, match="panel"):
        draw(axes=np.ravel(axes)[:-1])


@pytest.mark.parametrize("name", ["b747", "msd", "target_tracking", "bank_report"])
def test_study_figures_without_axes_make_a_figure(name, tmp_path):
    import io

    draw, shape, _ = _study_plots()[name]
    n_figs = len(plt.get_fignums())
    fig = draw()
    assert len(fig.axes) == shape[0] * shape[1] and len(plt.get_fignums()) == n_figs + 1
    plt.close(fig)
    buf = io.BytesIO()
    fig = draw(path=buf)  # as the report stores its parts: written, then closed
    assert buf.getvalue()[1:4] == b"PNG" and not plt.fignum_exists(fig.number)
    assert len(plt.get_fignums()) == n_figs
