"""Analysis of fault models and residual generators: gain maps, structure matrices, FDI geometry reports.

* :func:`fault_to_residual_gain` -- the largest singular value, frequency by frequency, of the
  transfer from each fault to each residual *group* of a generator's internal form (the
  singular-value plots of Douglas et al. 1996, Figs. 4.1–4.4; Varga's internal form ``R``);
  :meth:`GainTable.plot` draws the fault × residual "structure plot".
* :func:`structure_matrix` -- which residual group responds to which fault (a number, not a plot).
* :func:`~fdikit.analysis.geometry.fdi_report` (module :mod:`fdikit.analysis.geometry`) -- before any design:
  detection-space dimensions, invariant zeros, output separability, mutual detectability and ``Σν``
  against ``n`` for a candidate set of faults, with advice on what to change (Douglas et al. 1996, §4.1
  and App. A; Murray 2012, §2.3).

Examples
--------
>>> from fdikit.analysis import fdi_report
>>> from fdikit.plants import path_vehicle_14
>>> rep = fdi_report(path_vehicle_14(), ["throttle_actuator", "brake_actuator", "steering_actuator",
...                                      "air_mass_sensor:magnitude"])
>>> [f.nu for f in rep.faults]
[2, 2, 1, 1]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ModelError, ParameterError
from fdikit.fault_maps import check_fault_inputs
from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = [
    "GainTable",
    "fault_to_residual_gain",
    "structure_matrix",
    "default_freqs",
]

_EPS = np.finfo(float).eps


# ---------------------------------------------------------------------- gains and structure
def _residual_groups(generator: ResidualGenerator) -> tuple[tuple[str, ...], tuple[tuple[int, ...], ...]]:
    """Residual groups in order of first appearance: by ``isolates``; a residual with None alone, by its name.

    Residuals named ``'<filter>:<...>'`` (a stacked bank, e.g. :func:`fdikit.studies.path1996.bank`) are
    grouped per filter, ``'<filter>:<fault>'``, so a fault covered by two filters keeps two groups.
    """
    keys: list[str] = []
    rows: dict[str, list[int]] = {}
    for i, (name, iso) in enumerate(zip(generator.residuals, generator.isolates)):
        key = iso if iso is not None else name
        if iso is not None and ":" in name:
            key = f"{name.split(':', 1)[0]}:{iso}"
        if iso is None and key in rows:  # a detection-only residual named like an isolated fault
            key = f"{name} (residual)"
        if key not in rows:
            keys.append(key)
            rows[key] = []
        rows[key].append(i)
    return tuple(keys), tuple(tuple(rows[k]) for k in keys)


@dataclass(frozen=True, eq=False)
class GainTable:
    """Fault-to-residual-group gains of a residual generator.

    Attributes
    ----------
    omega : (N,) ndarray
        Frequencies [rad/s].
    gains : (N, q_f, q_g) ndarray
        ``gains[k, j, g]``: largest singular value of the transfer from fault ``faults[j]`` to the
        residuals of group ``groups[g]`` at ``omega[k]``.
    faults : tuple of str
        Fault names (rows of the map).
    groups : tuple of str
        Residual-group names (columns): the fault a group isolates, or the residual's own name.
    members : tuple of tuple of str
        The residual names of each group.
    dt : float or None
        Sample time of the internal form [s] (None: continuous).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.design import observer_generator
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> gen = observer_generator(m, np.diag([4.0, 5.0]))  # residual poles −5, −7
    >>> table = fault_to_residual_gain(gen, m, [0.0, 1.0])
    >>> table.faults, table.groups, np.round(table.peak(), 6).tolist()
    (('u0_actuator', 'u1_actuator'), ('y0', 'y1'), [[0.2, 0.0], [0.0, 0.142857]])
    """

    omega: np.ndarray
    gains: np.ndarray
    faults: tuple[str, ...]
    groups: tuple[str, ...]
    members: tuple[tuple[str, ...], ...]
    dt: float | None = None

    def peak(self) -> np.ndarray:
        """Largest gain over frequency, (q_f, q_g)."""
        return self.gains.max(axis=0)

    def to_pandas(self, db: bool = True, over_frequency: bool = False):
        """Peak gain over frequency as a fault × group DataFrame (in dB by default).

        ``over_frequency=True`` gives the whole table instead, indexed by ``(omega, fault)``.
        An exactly zero gain is ``-inf`` dB.
        """
        import pandas as pd

        def conv(x):
            if not db:
                return x
            with np.errstate(divide="ignore"):
                return 20 * np.log10(x)

        if not over_frequency:
            return pd.DataFrame(
                conv(self.peak()), index=pd.Index(self.faults, name="fault"),
                columns=pd.Index(self.groups, name="residual"),
            )
        idx = pd.MultiIndex.from_product([self.omega, self.faults], names=["omega", "fault"])
        flat = self.gains.reshape(-1, len(self.groups))
        return pd.DataFrame(conv(flat), index=idx, columns=pd.Index(self.groups, name="residual"))

    def plot(self, path=None, floor_db: float = -200.0, title: str | None = None, ax=None):
        """Fault × residual-group map of the peak gain in dB (the "structure plot").

        Cells are coloured by gain (clipped below at ``floor_db`` under the largest entry) and
        labelled with their value.

        Parameters
        ----------
        path : str, Path or binary file object, optional
            Write the figure there (any matplotlib format, by the suffix; atomically, see
            :func:`fdikit.plots.save_figure`).
        floor_db : float
            Lowest gain shown, in dB below the largest entry.
        title : str, optional
            Axes title (default: the frequency range).
        ax : matplotlib Axes, optional
            Draw into it (the colour bar takes room from it); default a new figure on its own Agg
            canvas, outside pyplot, so no global matplotlib state changes.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            The new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> table = GainTable(np.array([1.0]), np.array([[[1.0, 1e-3]]]), ("f",), ("f", "g"), (("r1",), ("r2",)))
        >>> fig, ax = plt.subplots()
        >>> table.plot(ax=ax) is ax, [t.get_text() for t in ax.texts]
        (True, ['0', '-60'])
        >>> plt.close(fig)
        """
        from fdikit.plots import save_figure

        peak = self.peak()
        top = peak.max() if peak.size and peak.max() > 0 else 1.0
        with np.errstate(divide="ignore"):
            dbv = 20 * np.log10(np.maximum(peak, top * 10 ** (floor_db / 20)))
        nf, ng = peak.shape
        given = ax
        if ax is None:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            fig = Figure(figsize=(1.2 + 0.9 * max(ng, 2), 1.0 + 0.45 * max(nf, 2)), layout="constrained")
            FigureCanvasAgg(fig)
            ax = fig.add_subplot()
        fig = ax.figure
        im = ax.imshow(dbv, cmap="viridis", aspect="auto", vmin=dbv.min() if dbv.size else 0)
        ax.set_xticks(range(ng), self.groups, rotation=45, ha="right")
        ax.set_yticks(range(nf), self.faults)
        ax.set_xlabel("residual group")
        ax.set_ylabel("fault")
        mid = (dbv.max() + dbv.min()) / 2 if dbv.size else 0
        for i in range(nf):
            for j in range(ng):
                label = f"{dbv[i, j]:.0f}".replace("-0", "0") if abs(dbv[i, j]) < 0.5 else f"{dbv[i, j]:.0f}"
                ax.text(j, i, label, ha="center", va="center", fontsize=7,
                        color="white" if dbv[i, j] < mid else "black")
        fig.colorbar(im, ax=ax, label="peak gain [dB]")
        lo, hi = (self.omega.min(), self.omega.max()) if self.omega.size else (0, 0)
        ax.set_title(title or f"fault → residual gain, ω ∈ [{lo:.3g}, {hi:.3g}] rad/s", fontsize=9)
        if path is not None:
            save_figure(fig, path, dpi=120)
        return fig if given is None else given


def _fault_columns(model: FaultModel, faults) -> tuple[tuple[str, ...], list[list[int]]]:
    if faults is None:
        faults = model.faults
    if isinstance(faults, str):
        faults = [faults]
    if isinstance(faults, Mapping):
        names = tuple(faults)
        cols = [model.index("f", list(check_fault_inputs(model, v))) for v in faults.values()]
    else:
        names = check_fault_inputs(model, faults)
        cols = [model.index("f", nm) for nm in names]
    if not names:
        raise ModelError("the model has no faults (group f); add them with with_sensor_faults/with_actuator_faults")
    return names, cols


def _check_omega(omega, dt: float | None) -> np.ndarray:
    omega = np.atleast_1d(validate.as_array("freqs", omega, finite=False))
    if omega.ndim != 1 or omega.size == 0:
        raise ParameterError(f"freqs must be a non-empty 1-D array of frequencies in rad/s, got shape {omega.shape}")
    if not np.all(np.isfinite(omega)) or np.any(omega < 0):
        raise ParameterError("freqs must be finite and non-negative (rad/s)")
    if dt is not None and omega.max() > np.pi / dt * (1 + 1e-12):
        raise ParameterError(
            f"freqs go up to {omega.max():g} rad/s, above the Nyquist frequency π/dt = {np.pi / dt:g} rad/s of the "
            "discrete internal form; keep freqs <= π/dt"
        )
    return omega


def default_freqs(dt: float | None, num: int = 200) -> np.ndarray:
    """Default grid: ``logspace(-2, 3)`` rad/s, capped at ``0.999 π/dt`` in discrete time.

    Parameters
    ----------
    dt : float or None
        Sample time [s] of a discrete internal form; None for continuous time.
    num : int, default 200
        Number of frequencies.

    Returns
    -------
    (num,) ndarray
        Log-spaced frequencies [rad/s] from ``1e-2`` to ``1e3`` (or ``0.999 π/dt`` when lower).

    Examples
    --------
    >>> from fdikit.analysis.gains import default_freqs
    >>> default_freqs(None, 3).round(6).tolist(), round(float(default_freqs(0.1, 5)[-1]), 6)
    ([0.01, 3.162278, 1000.0], 31.384511)
    """
    num = validate.integer("num", num, minimum=1)
    if dt is not None:
        dt = validate.positive("dt", dt)
    hi = 1e3 if dt is None else min(1e3, 0.999 * np.pi / dt)
    return np.logspace(-2, np.log10(hi), num)


def fault_to_residual_gain(
    generator: ResidualGenerator,
    model: FaultModel,
    freqs,
    faults: Sequence[str] | Mapping[str, Sequence[str]] | None = None,
) -> GainTable:
    """Gain from each fault to each residual group, frequency by frequency.

    The transfer ``R_f(z)`` from the model's faults (group ``f``) to the residuals is that of
    ``generator.internal_form(model)``, evaluated at ``z = jω`` (continuous) or
    ``z = e^{jω dt}`` (discrete) by :meth:`FaultModel.freqresp`.  For fault ``j`` and residual
    group ``g`` the entry is ``σ_max(R_f(z)[rows of g, columns of j])``.

    Residual groups: the residuals tied to the same fault by ``generator.isolates`` form one group
    named after that fault; a residual with ``isolates`` None is a group of its own, named after it.

    Parameters
    ----------
    generator : ResidualGenerator
        The residual generator (a design's ``.generator``).
    model : FaultModel
        The fault model it runs on.
    freqs : array_like
        Frequencies [rad/s], non-negative (``<= π/dt`` for a discrete internal form).
    faults : sequence of str or mapping, optional
        The fault inputs of the model to show (default: all), by fault name (a bare signal name
        raises :class:`~fdikit.errors.ParameterError`), or a mapping ``label -> [fault names]`` that
        treats several fault inputs as one multi-dimensional fault.

    Returns
    -------
    GainTable
        The gains ``(len(freqs), faults, groups)`` with the fault, group and member names.

    Raises
    ------
    ParameterError
        When ``generator`` or ``model`` is of the wrong type, ``freqs`` is empty, negative, not finite or above
        Nyquist, or a fault is given by a bare signal name.
    ModelError
        When the model has no faults, or a fault name is not one of its fault inputs.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.design import observer_generator
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> gen = observer_generator(m, np.diag([4.0, 5.0]))  # residual poles −5, −7
    >>> table = fault_to_residual_gain(gen, m, [0.0, 1.0])  # 1/|jω + 5| and 1/|jω + 7| on the diagonal
    >>> table.gains.shape, np.round(table.gains[:, 0, 0], 6).tolist()
    ((2, 2, 2), [0.2, 0.196116])
    """
    validate.instance("generator", generator, ResidualGenerator, "pass a design's .generator")
    validate.instance("model", model, FaultModel)
    R = generator.internal_form(model)
    omega = _check_omega(freqs, R.dt)
    names, cols = _fault_columns(model, faults)
    groups, rows = _residual_groups(generator)
    H = R.freqresp(omega, group="f")  # (N, q, nf)
    gains = np.empty((omega.size, len(names), len(groups)))
    for j, c in enumerate(cols):
        for g, r in enumerate(rows):
            gains[:, j, g] = np.linalg.norm(H[:, r][:, :, c], ord=2, axis=(1, 2))
    members = tuple(tuple(generator.residuals[i] for i in r) for r in rows)
    return GainTable(omega, gains, names, groups, members, R.dt)


def structure_matrix(
    generator: ResidualGenerator,
    model: FaultModel,
    freqs=None,
    rtol: float = 1e-6,
    faults: Sequence[str] | Mapping[str, Sequence[str]] | None = None,
    atol: float | None = None,
):
    """Which residual group responds to which fault: a boolean fault × group DataFrame.

    Rule (column-relative, so it does not mix the units of different residuals): with ``G`` the
    peak gain over ``freqs`` (:func:`fault_to_residual_gain`), ``S[f, g]`` is True when

        ``G[f, g] > rtol · max_f' G[f', g]``  and  ``G[f, g] > atol``,

    i.e. residual group ``g`` responds to ``f`` at more than ``rtol`` of its strongest fault
    response.  ``atol`` (default ``1e-10 ·`` the largest entry of the table) keeps a group that
    responds to nothing (a column of round-off) all False.  ``freqs`` defaults to
    :func:`default_freqs` (``1e-2 … 1e3`` rad/s, capped below Nyquist).

    Parameters
    ----------
    generator : ResidualGenerator
        The residual generator.
    model : FaultModel
        The fault model it runs on.
    freqs : array_like, optional
        Frequencies [rad/s]; default :func:`default_freqs` for the generator's (else the model's) ``dt``.
    rtol : float, default 1e-6
        Relative threshold per residual group, ``>= 0``.
    faults : sequence of str or mapping, optional
        The faults (rows), as for :func:`fault_to_residual_gain`.
    atol : float, optional
        Absolute floor on the gain, ``>= 0``; default ``1e-10`` times the largest entry.

    Returns
    -------
    pandas.DataFrame
        Booleans, index ``fault`` (the fault names), columns ``residual`` (the residual groups).

    Raises
    ------
    ParameterError
        When ``rtol`` or ``atol`` is negative, or for the arguments :func:`fault_to_residual_gain` refuses.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.design import observer_generator
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> gen = observer_generator(m, np.diag([4.0, 5.0]))  # residual poles −5, −7
    >>> structure_matrix(gen, m).to_numpy().tolist()
    [[True, False], [False, True]]
    """
    import pandas as pd

    validate.instance("generator", generator, ResidualGenerator, "pass a design's .generator")
    validate.instance("model", model, FaultModel)
    rtol = validate.non_negative("rtol", rtol)
    if atol is not None:
        atol = validate.non_negative("atol", atol)
    dt = generator.dt if generator.dt is not None else model.dt
    table = fault_to_residual_gain(generator, model, default_freqs(dt) if freqs is None else freqs, faults)
    G = table.peak()
    floor = (1e-10 * G.max() if G.size else 0.0) if atol is None else atol
    S = (G > rtol * G.max(axis=0, keepdims=True)) & (G > floor)
    return pd.DataFrame(S, index=pd.Index(table.faults, name="fault"), columns=pd.Index(table.groups, name="residual"))
