"""Analysis of fault models and residual generators: gain maps, structure matrices, FDI geometry reports.

* :func:`fault_to_residual_gain` -- the largest singular value, frequency by frequency, of the
  transfer from each fault to each residual *group* of a generator's internal form (the
  singular-value plots of Douglas et al. 1996, Figs. 4.1–4.4; Varga's internal form ``R``);
  :meth:`GainTable.plot` draws the fault × residual "structure plot".
* :func:`structure_matrix` -- which residual group responds to which fault (a number, not a plot).
* :func:`fdi_report` -- before any design: detection-space dimensions, invariant zeros, output
  separability, mutual detectability and ``Σν`` against ``n`` for a candidate set of faults,
  with advice on what to change (Douglas et al. 1996, §4.1 and App. A; Murray 2012, §2.3).

Examples
--------
>>> from fdikit.analysis import fdi_report
>>> from fdikit.plants import path_vehicle_14
>>> rep = fdi_report(path_vehicle_14(), ["throttle", "brake", "steering", "air_mass:magnitude"])
>>> [f.nu for f in rep.faults]
[2, 2, 1, 1]
"""

from __future__ import annotations

import io
import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import linalg
from fdikit.errors import ModelError
from fdikit.linalg import resolve_fault
from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = [
    "GainTable",
    "fault_to_residual_gain",
    "structure_matrix",
    "FaultGeometry",
    "FdiReport",
    "fdi_report",
    "resolve_fault",
    "default_freqs",
]

_EPS = np.finfo(float).eps


# ---------------------------------------------------------------------- gains and structure
def _residual_groups(generator: ResidualGenerator) -> tuple[tuple[str, ...], tuple[tuple[int, ...], ...]]:
    """Residual groups in order of first appearance: by ``isolates``; a residual with None alone, by its name.

    Residuals named ``'<filter>:<...>'`` (a stacked bank, e.g. :func:`fdikit.monitors.path_bank`) are
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
    omega : (N,) frequencies, rad/s.
    gains : (N, q_f, q_g) largest singular value of the transfer from fault ``faults[j]`` to the
        residuals of group ``groups[g]`` at ``omega[k]``.
    faults : fault names (rows of the map).
    groups : residual-group names (columns): the fault a group isolates, or the residual's own name.
    members : the residual names of each group.
    dt : sample time of the internal form (None: continuous).
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

    def plot(self, path=None, floor_db: float = -200.0, title: str | None = None):
        """Fault × residual-group map of the peak gain in dB (the "structure plot").

        Cells are coloured by gain (clipped below at ``floor_db`` under the largest entry) and
        labelled with their value; the figure is written to ``path`` (any matplotlib format) when
        given.  Uses the Agg canvas directly, so it changes no global matplotlib state.
        Returns the :class:`matplotlib.figure.Figure`.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        peak = self.peak()
        top = peak.max() if peak.size and peak.max() > 0 else 1.0
        with np.errstate(divide="ignore"):
            dbv = 20 * np.log10(np.maximum(peak, top * 10 ** (floor_db / 20)))
        nf, ng = peak.shape
        fig = Figure(figsize=(1.2 + 0.9 * max(ng, 2), 1.0 + 0.45 * max(nf, 2)), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
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
            fig.savefig(path, dpi=120)
        return fig


def _fault_columns(model: FaultModel, faults) -> tuple[tuple[str, ...], list[list[int]]]:
    if faults is None:
        faults = model.faults
    if isinstance(faults, str):
        faults = [faults]
    if isinstance(faults, Mapping):
        names = tuple(faults)
        cols = [model.index("f", [v] if isinstance(v, str) else list(v)) for v in faults.values()]
    else:
        names = tuple(faults)
        cols = [model.index("f", nm) for nm in names]
    if not names:
        raise ModelError("the model has no faults (group f); add them with with_sensor_faults/with_actuator_faults")
    return names, cols


def _check_omega(omega, dt: float | None) -> np.ndarray:
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or omega.size == 0:
        raise ModelError(f"freqs must be a non-empty 1-D array of frequencies in rad/s, got shape {omega.shape}")
    if not np.all(np.isfinite(omega)) or np.any(omega < 0):
        raise ModelError("freqs must be finite and non-negative (rad/s)")
    if dt is not None and omega.max() > np.pi / dt * (1 + 1e-12):
        raise ModelError(
            f"freqs go up to {omega.max():g} rad/s, above the Nyquist frequency π/dt = {np.pi / dt:g} rad/s of the "
            "discrete internal form; keep freqs <= π/dt"
        )
    return omega


def default_freqs(dt: float | None, num: int = 200) -> np.ndarray:
    """Default grid: ``logspace(-2, 3)`` rad/s, capped at ``0.999 π/dt`` in discrete time."""
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

    Parameters
    ----------
    generator, model : the residual generator and the fault model it runs on.
    freqs : frequencies in rad/s (``<= π/dt`` for a discrete internal form).
    faults : fault names of the model (default: all), or a mapping ``label -> [fault names]`` that
        treats several fault inputs as one multi-dimensional fault.

    Residual groups: the residuals tied to the same fault by ``generator.isolates`` form one group
    named after that fault; a residual with ``isolates`` None is a group of its own, named after it.
    """
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
    """
    import pandas as pd

    dt = generator.dt if generator.dt is not None else model.dt
    table = fault_to_residual_gain(generator, model, default_freqs(dt) if freqs is None else freqs, faults)
    G = table.peak()
    floor = (1e-10 * G.max() if G.size else 0.0) if atol is None else atol
    S = (G > rtol * G.max(axis=0, keepdims=True)) & (G > floor)
    return pd.DataFrame(S, index=pd.Index(table.faults, name="fault"), columns=pd.Index(table.groups, name="residual"))


# ---------------------------------------------------------------------- geometry report
@dataclass(frozen=True, eq=False)
class FaultGeometry:
    """Geometry of one fault: map ``F`` (n x k), ``dim W*``, ``ν = dim T*``, ``dim C T*``, invariant zeros."""

    name: str
    kind: str
    F: np.ndarray
    caisa_dim: int
    nu: int
    output_dim: int
    zeros: np.ndarray


@dataclass(frozen=True, eq=False)
class FdiReport:
    """What the geometry says about detecting and isolating a set of faults with one filter.

    Attributes
    ----------
    n, p : states and outputs of the model; ``discrete`` whether it is discrete.
    faults : per fault, a :class:`FaultGeometry`.
    output_separable : whether the ``C T_i*`` are independent (Def. A.1, test (a.7)).
    separation : smallest singular value of the side-by-side orthonormal bases of the ``C T_i*``
        (1: orthogonal images, 0: dependent) -- how robust output separability is.
    inseparable_pairs : pairs of fault names whose output images intersect.
    dependent_sets : minimal sets of three or more faults whose images are dependent although no
        pair of them is (found only when separability fails without an inseparable pair).
    mutually_detectable : zeros of ``(C, A, [F_1 … F_q])`` equal the union of the zeros of each
        ``(C, A, F_i)``; None when undefined: the joint system is not left invertible (its
        Rosenbrock pencil loses column rank at every ``s``, e.g. output-inseparable faults), so it
        has no well-defined zeros.  ``joint_zeros``, ``extra_zeros`` (joint but of no single fault)
        and ``lost_zeros`` (of a single fault but not joint; only possible in the undefined case).
    advice : what to change, one sentence each.
    """

    n: int
    p: int
    discrete: bool
    faults: tuple[FaultGeometry, ...]
    output_separable: bool
    separation: float
    inseparable_pairs: tuple[tuple[str, str], ...]
    dependent_sets: tuple[tuple[str, ...], ...]
    mutually_detectable: bool | None
    joint_zeros: np.ndarray
    extra_zeros: np.ndarray
    lost_zeros: np.ndarray
    advice: tuple[str, ...]

    @property
    def nu_total(self) -> int:
        """``Σ ν_i``."""
        return sum(f.nu for f in self.faults)

    @property
    def nu_0(self) -> int:
        """Dimension left for the complementary space, ``n − Σν`` (negative: too many faults for one filter)."""
        return self.n - self.nu_total

    def to_pandas(self):
        """One row per fault: kind, columns of F, dim W*, ν, dim C T*, zeros; summary in ``df.attrs``."""
        import pandas as pd

        df = pd.DataFrame(
            {
                "kind": [f.kind for f in self.faults],
                "columns": [f.F.shape[1] for f in self.faults],
                "dim_W": [f.caisa_dim for f in self.faults],
                "nu": [f.nu for f in self.faults],
                "dim_CT": [f.output_dim for f in self.faults],
                "zeros": [_fmt_zeros(f.zeros) for f in self.faults],
            },
            index=pd.Index([f.name for f in self.faults], name="fault"),
        )
        df.attrs.update(
            n=self.n, nu_total=self.nu_total, output_separable=self.output_separable, separation=self.separation,
            inseparable_pairs=list(self.inseparable_pairs), dependent_sets=list(self.dependent_sets),
            mutually_detectable=self.mutually_detectable, extra_zeros=list(self.extra_zeros), advice=list(self.advice),
        )
        return df

    def _summary(self) -> list[str]:
        lines = [
            f"n = {self.n}, p = {self.p}; Σν = {self.nu_total} ({'≤' if self.nu_0 >= 0 else '>'} n, ν₀ = {self.nu_0})",
            f"output separable: {'yes' if self.output_separable else 'NO'} (separation {self.separation:.3g})",
        ]
        if self.inseparable_pairs:
            lines.append("  not separable: " + "; ".join(f"{a} / {b}" for a, b in self.inseparable_pairs))
        if self.dependent_sets:
            lines.append("  dependent sets: " + "; ".join(" + ".join(s) for s in self.dependent_sets))
        md = {True: "yes", False: "NO", None: "undefined (joint system not left invertible)"}[self.mutually_detectable]
        lines.append(f"mutually detectable: {md}; joint zeros {_fmt_zeros(self.joint_zeros)}"
                     + (f", extra {_fmt_zeros(self.extra_zeros)}" if self.extra_zeros.size else "")
                     + (f", lost {_fmt_zeros(self.lost_zeros)}" if self.lost_zeros.size else ""))
        return lines

    def __str__(self) -> str:
        cols = ("fault", "kind", "k", "dim W*", "ν", "dim CT*", "zeros")
        rows = [(f.name, f.kind, str(f.F.shape[1]), str(f.caisa_dim), str(f.nu), str(f.output_dim),
                 _fmt_zeros(f.zeros)) for f in self.faults]
        tail = self._summary() + [f"→ {a}" for a in self.advice]
        try:
            from rich.console import Console
            from rich.table import Table
        except ImportError:  # pragma: no cover - rich is a dependency; plain text as a fallback
            widths = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(cols)]
            fmt = "  ".join(f"{{:<{w}}}" for w in widths)
            return "\n".join([fmt.format(*cols)] + [fmt.format(*r) for r in rows] + tail)
        table = Table(*cols, title="FDI geometry")
        for r in rows:
            table.add_row(*r)
        buf = io.StringIO()
        console = Console(file=buf, width=120, color_system=None, force_terminal=False)
        console.print(table)
        for line in tail:
            console.print(line, highlight=False, markup=False)
        return buf.getvalue().rstrip()


def _fmt_zeros(z: np.ndarray) -> str:
    if not np.size(z):
        return "none"
    return ", ".join(f"{v.real:.4g}" if abs(v.imag) <= 1e-9 * max(abs(v), 1) else f"{v.real:.4g}{v.imag:+.4g}j"
                     for v in np.asarray(z, dtype=complex))


def _match(a: np.ndarray, b: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Multiset difference of two zero lists: (in a but not b, in b but not a)."""
    left, extra = list(b), []
    for z in a:
        k = int(np.argmin(np.abs(np.array(left) - z))) if left else -1
        if k >= 0 and abs(left[k] - z) <= tol:
            left.pop(k)
        else:
            extra.append(z)
    return np.array(extra, dtype=complex), np.array(left, dtype=complex)


def _dependent_sets(images: list[np.ndarray], rtol) -> list[tuple[int, ...]]:
    """Minimal index sets (size >= 3) whose output images are linearly dependent."""
    found: list[tuple[int, ...]] = []
    q = len(images)
    if q > 12:
        return found
    for size in range(3, q + 1):
        for combo in itertools.combinations(range(q), size):
            if any(set(s) <= set(combo) for s in found):
                continue
            stacked = np.hstack([images[i] for i in combo])
            if stacked.shape[1] and linalg.rank(stacked, rtol) < stacked.shape[1]:
                found.append(combo)
    return found


def fdi_report(
    model: FaultModel,
    faults: Mapping[str, np.ndarray] | Sequence[str],
    rtol: float | None = None,
    ztol: float = 1e-6,
) -> FdiReport:
    """Detection and isolation geometry of a candidate fault set for one detection filter.

    Parameters
    ----------
    model : FaultModel (its ``A`` and ``C``; continuous or discrete).
    faults : fault names (resolved by :func:`resolve_fault`: an output name is its 2-D sensor fault
        ``[F¹, A F¹]``, ``'<output>:magnitude'`` only ``A F¹`` -- the bias assumption -- and
        ``'<output>:rate'`` only ``F¹``; a control name is its actuator column of ``Bu``; a fault
        input of the model its ``Bf`` column), or a mapping ``name -> F`` of explicit n x k maps.
    rtol : relative rank tolerance of the subspace computations (:mod:`fdikit.linalg` default).
    ztol : tolerance for matching zeros, relative to ``max(‖A‖₂, 1)``.

    For each fault: ``dim W*`` (:func:`linalg.caisa`), ``ν = dim T*`` (:func:`linalg.detection_space`),
    ``dim C T*`` and the invariant zeros of ``(C, A, F)``.  For the set: output separability
    (:func:`linalg.output_separable`), mutual detectability (:func:`linalg.mutually_detectable`)
    and ``Σν`` against ``n`` (Douglas et al. 1996, §4.1; App. A).
    """
    if isinstance(faults, str):
        faults = [faults]
    A, C, n = model.A, model.C, model.n
    entries: list[tuple[str, np.ndarray, str]] = []
    if isinstance(faults, Mapping):
        for name, F in faults.items():
            F = np.asarray(F, dtype=float)
            F = F.reshape(-1, 1) if F.ndim == 1 else F
            if F.ndim != 2 or F.shape[0] != n or not np.all(np.isfinite(F)):
                raise ModelError(f"fault map {name!r} must be a finite {n} x k matrix, got shape {F.shape}")
            entries.append((str(name), F, "matrix"))
    else:
        for name in faults:
            F, kind = resolve_fault(model, name)
            entries.append((name, F, kind))
    if not entries:
        raise ModelError("fdi_report needs at least one fault")
    geo, spaces, maps = [], [], []
    for name, F, kind in entries:
        T = linalg.detection_space(A, C, F, rtol)
        zeros, _ = linalg.invariant_zeros(A, C, F)
        geo.append(FaultGeometry(name, kind, F, linalg.caisa(A, C, F, rtol).shape[1], T.shape[1],
                                 linalg.rank(C @ T, rtol) if T.shape[1] else 0, zeros))
        spaces.append(T)
        maps.append(F)
    names = [g.name for g in geo]
    sep, pairs = linalg.output_separable(C, spaces, rtol)
    images = [linalg.orth(C @ T, rtol) for T in spaces]
    stacked = np.hstack(images)
    if stacked.shape[1] > stacked.shape[0]:
        separation = 0.0  # more image directions than outputs
    else:
        separation = float(np.linalg.svd(stacked, compute_uv=False).min()) if stacked.shape[1] else 1.0
    dep = _dependent_sets(images, rtol) if not sep and not pairs else []
    md, joint, union = linalg.mutually_detectable(A, C, maps, ztol)
    tol = ztol * max(np.linalg.norm(A, 2), 1.0)
    extra, lost = _match(joint, union, tol)
    if _degenerate(A, C, np.hstack(maps), rtol):
        md = None
    report_pairs = tuple((names[i], names[j]) for i, j in pairs)
    report_dep = tuple(tuple(names[i] for i in s) for s in dep)
    advice = _advice(model, geo, report_pairs, report_dep, md, extra)
    return FdiReport(model.n, model.p, model.is_discrete, tuple(geo), sep, separation, report_pairs, report_dep,
                     md, joint, extra, lost, tuple(advice))


def _degenerate(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol) -> bool:
    """Whether ``(C, A, F)`` is not left invertible: the Rosenbrock pencil drops column rank at every ``s``.

    Tested at two generic points of the scale of ``A``; the joint zeros are then undefined.
    """
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    scale = max(np.linalg.norm(A, 2), 1.0)
    for s0 in (0.6180339887 + 1.2360679775j, -0.4142135624 + 0.7320508076j):
        P = np.block([[A - s0 * scale * np.eye(n), F], [C, np.zeros((p, k))]])
        if linalg.rank(P, rtol) == n + k:
            return False
    return True


def _advice(model, geo, pairs, dep, md, extra) -> list[str]:
    out: list[str] = []
    by_name = {g.name: g for g in geo}
    for g in geo:
        if g.output_dim == 0:
            out.append(f"{g.name}: C T* = 0, the fault never reaches the outputs; it cannot be detected with these "
                       "sensors")
        if any(abs(z) <= 1e-9 * max(np.linalg.norm(model.A, 2), 1.0) for z in g.zeros) and not model.is_discrete:
            out.append(f"{g.name}: invariant zero at the origin; a constant fault gives no steady-state residual")
        if model.is_discrete and any(abs(z - 1) <= 1e-9 for z in g.zeros):
            out.append(f"{g.name}: invariant zero at z = 1; a constant fault gives no steady-state residual")
    for a, b in pairs:
        sensor = [x for x in (a, b) if by_name[x].kind == "sensor"]
        if sensor:
            s = sensor[0]
            out.append(f"{a} and {b} are not output separable (detection equivalent): keep only the magnitude "
                       f"direction A F¹ of the sensor fault {s} ('{s}:magnitude', the bias assumption) or move one "
                       "fault to another filter")
        else:
            out.append(f"{a} and {b} are not output separable (detection equivalent): move one of them to another "
                       "filter")
    for s in dep:
        out.append(f"{' + '.join(s)}: the output images are dependent together although no pair is; move one of "
                   "them to another filter (or a magnitude-only sensor direction may help)")
    nu = sum(g.nu for g in geo)
    if nu > model.n:
        out.append(f"Σν = {nu} > n = {model.n}: the detection spaces cannot be independent in one filter; split the "
                   "faults into several filters (a bank)")
    if md is None:
        out.append("the joint system (C, A, [F_1 … F_q]) is not left invertible (dependent fault directions, or more "
                   "fault columns than independent output directions): its invariant zeros, and so mutual "
                   "detectability, are undefined; make the set output separable first")
    elif not md:
        unstable = [z for z in extra if (abs(z) >= 1 if model.is_discrete else z.real >= 0)]
        msg = (f"not mutually detectable: the extra zeros {_fmt_zeros(extra)} become eigenvalues of a Beard–Jones "
               "filter")
        msg += ("; one is unstable, so no stable BJ filter exists: use a restricted-diagonal filter (RDDF) or a "
                "bank of unknown-input observers / single-fault filters" if unstable else
                "; acceptable if they are fast enough, otherwise use a restricted-diagonal filter (RDDF) or a bank "
                "of unknown-input observers / single-fault filters")
        out.append(msg)
    return out
