"""FDI geometry report of a fault model, before any design (Douglas et al. 1996, §4.1 and App. A; Murray 2012, §2.3).

:func:`fdi_report` gives, for a candidate set of faults, the detection-space dimensions, invariant zeros, output
separability, mutual detectability and ``Σν`` against ``n``, with advice on what to change.  Also available as
:func:`fdikit.analysis.gains.fdi_report`.

Examples
--------
>>> from fdikit.plants import path_vehicle_14
>>> rep = fdi_report(path_vehicle_14(), ["throttle_actuator", "brake_actuator", "steering_actuator",
...                                      "air_mass_sensor:magnitude"])
>>> [f.nu for f in rep.faults]
[2, 2, 1, 1]
"""

from __future__ import annotations

import io
import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import linalg, validate
from fdikit.errors import ModelError
from fdikit.fault_maps import resolve_fault
from fdikit.model import FaultModel

__all__ = ["FaultGeometry", "FdiReport", "fdi_report"]


@dataclass(frozen=True, eq=False)
class FaultGeometry:
    """Geometry of one fault: map ``F`` (n x k), ``dim W*``, ``ν = dim T*``, ``dim C T*``, invariant zeros.

    Attributes
    ----------
    name : str
        The fault's name as given.
    kind : str
        Where the map comes from: ``'sensor'``, ``'sensor:magnitude'``, ``'sensor:rate'``, ``'actuator'``,
        ``'fault input'`` (a ``Bf`` column) or ``'matrix'`` (given explicitly).
    F : (n, k) ndarray
        The fault map.
    caisa_dim : int
        ``dim W*``, the minimal (C, A)-invariant subspace containing ``Im F`` (CAISA, Douglas et al. 1996,
        Thm. A.1).
    nu : int
        ``ν = dim T*``, the dimension of the detection space.
    output_dim : int
        ``dim C T*``, the dimension of the fault's output image.
    zeros : ndarray
        Invariant zeros of ``(C, A, F)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.analysis.geometry import fdi_report
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> g = fdi_report(m, ["u0_actuator"]).faults[0]
    >>> g.name, g.kind, g.F.shape, g.nu, g.output_dim, g.zeros.size
    ('u0_actuator', 'fault input', (2, 1), 1, 1, 0)
    """

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
    n, p : int
        States and outputs of the model.
    discrete : bool
        Whether the model is discrete.
    faults : tuple of FaultGeometry
        Per fault, a :class:`FaultGeometry`.
    output_separable : bool
        Whether the ``C T_i*`` are independent (Def. A.1, test (a.7)).
    separation : float
        Smallest singular value of the side-by-side orthonormal bases of the ``C T_i*``
        (1: orthogonal images, 0: dependent) -- how robust output separability is.
    inseparable_pairs : tuple of (str, str)
        Pairs of fault names whose output images intersect.
    dependent_sets : tuple of tuple of str
        Minimal sets of three or more faults whose images are dependent although no
        pair of them is (found only when separability fails without an inseparable pair).
    mutually_detectable : bool or None
        Zeros of ``(C, A, [F_1 … F_q])`` equal the union of the zeros of each
        ``(C, A, F_i)``; None when undefined: the joint system is not left invertible (its
        Rosenbrock pencil loses column rank at every ``s``, e.g. output-inseparable faults), so it
        has no well-defined zeros.
    joint_zeros : ndarray
        Invariant zeros of the joint system ``(C, A, [F_1 … F_q])``.
    extra_zeros : ndarray
        Zeros of the joint system but of no single fault.
    lost_zeros : ndarray
        Zeros of a single fault but not of the joint system (only possible in the undefined case).
    advice : tuple of str
        What to change, one sentence each (empty when nothing needs changing).
    nu_total : int
        ``Σ ν_i``.
    nu_0 : int
        ``n − Σν``, the dimension left for the complementary space (negative: too many faults for one filter).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.analysis.geometry import fdi_report
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> rep = fdi_report(m, {"a": [1.0, 1.0], "b": [1.0, 1.0]})  # the same direction twice
    >>> rep.output_separable, rep.inseparable_pairs, rep.mutually_detectable, len(rep.advice)
    (False, (('a', 'b'),), None, 2)
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
    targets: Mapping[str, np.ndarray] | Sequence[str] | str,
    rtol: float | None = None,
    ztol: float = 1e-6,
) -> FdiReport:
    """Detection and isolation geometry of a candidate fault set for one detection filter.

    For each fault: ``dim W*`` (:func:`linalg.caisa`), ``ν = dim T*`` (:func:`linalg.detection_space`),
    ``dim C T*`` and the invariant zeros of ``(C, A, F)``.  For the set: output separability
    (:func:`linalg.output_separable`), mutual detectability (:func:`linalg.mutually_detectable`)
    and ``Σν`` against ``n`` (Douglas et al. 1996, §4.1; App. A).

    Parameters
    ----------
    model : FaultModel
        The model (its ``A`` and ``C``; continuous or discrete).
    targets : str, sequence of str or mapping
        The candidate faults of the filter: fault names (resolved by :func:`resolve_fault`:
        ``'<output>_sensor'`` is the 2-D sensor fault ``[F¹, A F¹]``, ``'<output>_sensor:magnitude'``
        only ``A F¹`` -- the bias assumption -- and ``'<output>_sensor:rate'`` only ``F¹``;
        ``'<control>_actuator'`` is the actuator column of ``Bu``; a fault input of the model its
        ``Bf`` column; a bare signal name raises :class:`~fdikit.errors.ParameterError`), or a
        mapping ``name -> F`` of explicit n x k maps.
    rtol : float, optional
        Relative rank tolerance of the subspace computations (:mod:`fdikit.linalg` default).
    ztol : float, default 1e-6
        Tolerance for matching zeros, relative to ``max(‖A‖₂, 1)``.

    Returns
    -------
    FdiReport
        The per-fault geometry, separability, mutual detectability and advice; ``print(report)`` gives the
        text, ``report.to_pandas()`` the table.

    Raises
    ------
    ModelError
        When an explicit fault map is not a finite ``n x k`` matrix, a fault name is not a fault of the model,
        or no fault is given.
    ParameterError
        When ``model`` is not a :class:`~fdikit.model.FaultModel`, ``rtol`` or ``ztol`` is negative, or a fault
        is given by a bare signal name.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.analysis.geometry import fdi_report
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.eye(2), outputs=["y0", "y1"],
    ...                controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    >>> rep = fdi_report(m, ["u0_actuator", "u1_actuator"])
    >>> [f.nu for f in rep.faults], rep.output_separable, round(rep.separation, 6), rep.mutually_detectable
    ([1, 1], True, 1.0, True)
    >>> rep.nu_total, rep.nu_0, rep.advice
    (2, 0, ())
    """
    validate.instance("model", model, FaultModel)
    if rtol is not None:
        rtol = validate.non_negative("rtol", rtol)
    ztol = validate.non_negative("ztol", ztol)
    faults = [targets] if isinstance(targets, str) else targets
    A, C, n = model.A, model.C, model.n
    entries: list[tuple[str, np.ndarray, str]] = []
    if isinstance(faults, Mapping):
        for name, F in faults.items():
            F = validate.as_array(f"fault map {name!r}", F, error=ModelError, finite=False)
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
