"""Banks of residual generators: several filters run as one (:func:`stack_generators`).

Douglas et al. 1996, §4.2 and §5.1: the PATH monitor is a bank of detection filters, each
designed for its own fault group and reading its own measurements; the bank logic of Ch. 1
takes each residual's filter (``ThresholdEvaluator(groups=...)``).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import scipy.linalg

from fdikit.errors import ModelError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals.generator import ResidualGenerator

__all__ = ["stack_generators"]


def stack_generators(generators: Iterable[ResidualGenerator]) -> ResidualGenerator:
    """One generator from several: block-diagonal filter states, concatenated residuals.

    The stacked generator reads the union of the signals (controls in order of first appearance,
    then outputs likewise); a filter's ``B`` and ``D`` get zero columns for the signals it does not
    read, so each filter still sees only its own signals (and the gap rule, which works part by
    part, propagates each filter through a dropout of a signal only if that filter reads it).
    The generators must share ``dt``; residual names must be unique across them; their operating
    points are merged by signal name and must agree where two generators read the same signal.

    Parameters
    ----------
    generators : iterable of ResidualGenerator
        The filters of the bank.

    Returns
    -------
    ResidualGenerator
        States, residuals and ``isolates`` of all generators in the given order.

    Raises
    ------
    ModelError
        On an empty list, different ``dt``, a repeated residual name, or two operating-point values
        for one signal.

    Examples
    --------
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> h = ResidualGenerator([[0.5]], [[0.5]], [[-1.0]], [[1.0]], (), ("z",), ("r2",), dt=1.0)
    >>> bank = stack_generators([g, h])
    >>> bank.n, bank.residuals, bank.outputs, bank.B.tolist()
    (2, ('r', 'r2'), ('y', 'z'), [[1.0, 0.5, 0.0], [0.0, 0.0, 0.5]])
    """
    gens = list(generators)
    if not gens:
        raise ModelError("stack_generators needs at least one generator")
    for i, g in enumerate(gens):
        if not isinstance(g, ResidualGenerator):
            raise ModelError(f"item {i} is a {type(g).__name__}, not a ResidualGenerator (use design.generator)")
    g0 = gens[0]
    for i, g in enumerate(gens[1:], start=1):
        if g.dt != g0.dt:
            raise ModelError(f"generator {i} has dt={g.dt}, generator 0 dt={g0.dt}; discretize them alike first")
    names = [nm for g in gens for nm in g.residuals]
    dup = sorted({nm for nm in names if names.count(nm) > 1})
    if dup:
        raise ModelError(f"residual names {dup} occur in more than one generator; names must be unique")
    controls = tuple(dict.fromkeys(nm for g in gens for nm in g.controls))
    outputs = tuple(dict.fromkeys(nm for g in gens for nm in g.outputs))
    signals = controls + outputs
    Bs, Ds = [], []
    for g in gens:
        cols = [signals.index(nm) for nm in g.controls] + [len(controls) + outputs.index(nm) for nm in g.outputs]
        B, D = np.zeros((g.n, len(signals))), np.zeros((len(g.residuals), len(signals)))
        B[:, cols], D[:, cols] = g.B, g.D
        Bs.append(B)
        Ds.append(D)
    return ResidualGenerator(
        A=scipy.linalg.block_diag(*[g.A for g in gens]),
        B=np.vstack(Bs),
        C=scipy.linalg.block_diag(*[g.C for g in gens]),
        D=np.vstack(Ds),
        controls=controls,
        outputs=outputs,
        residuals=tuple(names),
        dt=g0.dt,
        isolates=tuple(iso for g in gens for iso in g.isolates),
        operating_point=_merged_point(gens),
    )


def _merged_point(gens: list[ResidualGenerator]) -> OperatingPoint | None:
    """The operating points of a bank merged by signal name (None when no generator has one)."""
    if all(g.operating_point is None for g in gens):
        return None
    parts: dict[str, dict[str, float]] = {"x0": {}, "u0": {}, "y0": {}}
    for i, g in enumerate(gens):
        for kind, names in (("u0", g.controls), ("y0", g.outputs)):
            for nm, val in zip(names, g.offset[: len(g.controls)] if kind == "u0" else g.offset[len(g.controls):]):
                old = parts[kind].setdefault(nm, float(val))
                if old != val:
                    raise ModelError(
                        f"generator {i} reads {nm!r} about the operating point {float(val):g}, an earlier one about "
                        f"{old:g}; stacked generators must share the operating point of a signal they both read "
                        "(design them from models with the same operating point)")
        if g.operating_point is not None:
            parts["x0"].update(g.operating_point.x0)
    return OperatingPoint(**parts)
