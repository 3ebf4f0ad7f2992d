"""Exact fault detection and isolation by the nullspace method: ``efdsyn`` and ``efdisyn`` (Varga 2017, §5.2, §5.4).

``efdsyn`` solves the exact fault detection problem (EFDP): a filter ``Q`` with ``Q [Gu Gd Gn; I 0 0] = 0`` whose
fault part ``R_f = Q [G_f; 0]`` has every targeted column nonzero (weakly, or strongly at ``fdfreq``), stable, of
least order when ``minimal=True`` (Procedure EFD).  ``efdisyn`` solves the exact fault detection and isolation
problem (EFDIP) for a structure matrix ``S``: one ``efdsyn`` filter per row, decoupling the faults of the zero
entries (Procedure EFDI).  The basis is :func:`~fdikit.design.nullspace.basis.left_nullspace`; the selection of
basis rows follows the reference's ``efdbasesel``: the rows of least degree that detect every targeted fault.

The filters read ``[u; y]`` (fdikit's generator order; the reference's ``Q`` reads ``[y; u]``) and run in fdikit's
batch and online runtime like any other design.

References
----------
Varga (2017), §5.2 (EFDP, Procedure EFD), §5.4 (EFDIP, Procedure EFDI); fdtools (``efdsyn``, ``efdisyn``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.design.nullspace.basis import NullspaceBasis, denominator, left_nullspace, minimal_realization, realize_rows
from fdikit.design.nullspace.detectability import covered, row_structure
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["NullspaceDesign", "NullspaceBankDesign", "efdsyn", "efdisyn", "split_faults", "bank_rows"]


def split_faults(model: FaultModel, targets, nuisance) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The targeted and the nuisance fault inputs, by fdikit's ``targets=`` / ``nuisance=`` conventions.

    Parameters
    ----------
    model : FaultModel
        The plant; faults are its fault inputs (group ``f``).
    targets : str or sequence of str or None
        The faults to detect; None → every fault input that is not a nuisance.
    nuisance : str or sequence of str or "others"
        The faults to decouple; ``"others"`` → every fault input that is not a target.

    Returns
    -------
    tuple
        ``(targets, nuisance)``.

    Raises
    ------
    ParameterError
        A fault both targeted and decoupled, ``"others"`` without targets, or no target.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0]], Bf=[[1.0, 2.0]])
    >>> split_faults(m, "f0", "others")
    (('f0',), ('f1',))

    References
    ----------
    Varga (2017), §5.2 (detected and decoupled fault inputs).
    """
    from fdikit.fault_maps import check_fault_inputs

    if isinstance(nuisance, str) and nuisance == "others":
        if targets is None:
            raise ParameterError("nuisance='others' needs targets= (the faults to detect)")
        tg = check_fault_inputs(model, targets, "target fault")
        nz = tuple(f for f in model.faults if f not in tg)
    else:
        nz = check_fault_inputs(model, nuisance, "nuisance fault") if nuisance else ()
        tg = (tuple(f for f in model.faults if f not in nz) if targets is None
              else check_fault_inputs(model, targets, "target fault"))
    both = sorted(set(tg) & set(nz))
    if both:
        raise ParameterError(f"faults {both} are both targets and nuisance; name each in one of the two")
    if not tg:
        raise ParameterError("no fault to detect: the model has no fault inputs outside nuisance=; give targets=")
    return tuple(tg), tuple(nz)


@dataclass(frozen=True, eq=False)
class NullspaceDesign(FieldReport):
    """A nullspace-based fault detection filter (``efdsyn``) and its report.

    Attributes
    ----------
    generator : ResidualGenerator
        The filter ``Q`` (inputs ``[u; y]``), minimal, with the assigned stable poles, scaled as the reference scales
        it: the smallest column gain of its fault part ``R_f`` (targets) is 1 (the DC gain with ``fdfreq`` ∋ 0, the H∞
        norm otherwise).
    basis : NullspaceBasis
        The left nullspace basis the filter was selected from.
    degrees : tuple of int
        The degrees of the basis rows (the left minimal indices; reference ``info.degs``).
    selection : numpy.ndarray
        ``(q, len(used))`` combination of the basis rows ``used`` (reference ``info.HDesign``, restricted to the used
        rows).
    used : tuple of int
        The basis rows combined.
    order : int
        The filter order.
    structure : numpy.ndarray
        ``(q, len(targets) + len(nuisance))`` booleans: which of ``targets + nuisance`` each residual detects
        (strong at ``fdfreq`` when given, weak otherwise).
    basis_structure : numpy.ndarray
        The same for every basis row (reference ``info.S``), over ``targets``.
    targets, nuisance : tuple of str
        The detected and the decoupled fault inputs.
    poles : numpy.ndarray
        The filter eigenvalues.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> d = efdsyn(m, targets=["f0"], nuisance=["f1"])
    >>> d.order, d.structure.astype(int).tolist()
    (1, [[1, 0]])

    References
    ----------
    Varga (2017), §5.2, Procedure EFD; fdtools (``efdsyn``).
    """

    generator: ResidualGenerator
    basis: NullspaceBasis
    degrees: tuple[int, ...]
    selection: np.ndarray
    used: tuple[int, ...]
    order: int
    structure: np.ndarray
    basis_structure: np.ndarray
    targets: tuple[str, ...]
    nuisance: tuple[str, ...]
    poles: np.ndarray

    REPORT = ("degrees", "selection", "used", "order", "structure", "basis_structure", "targets", "nuisance",
              "poles")


def _selection(selection, q: int, k: int, seed: int = 20170) -> np.ndarray:
    """The ``(q, k)`` combination: given (checked) or a fixed generic one of orthonormal rows (from ``seed``)."""
    if selection is not None:
        H = np.atleast_2d(np.asarray(selection, dtype=float))
        if H.shape != (q, k) or not np.all(np.isfinite(H)) or np.linalg.matrix_rank(H) < q:
            raise ParameterError(f"selection must be a finite ({q}, {k}) matrix of full row rank, got shape "
                                 f"{H.shape}")
        return H
    if q == k:
        return np.eye(k)
    G = np.random.default_rng(seed).standard_normal((k, q))
    return np.linalg.qr(G)[0].T


def _minimal_generator(A, B, C, D, model: FaultModel, names) -> ResidualGenerator:
    A, B, C, D = minimal_realization(A, B, C, D)
    return ResidualGenerator(A, B, C, D, controls=model.controls, outputs=model.outputs, residuals=names,
                             dt=model.dt)


def _unit_fault_gain(gen: ResidualGenerator, model: FaultModel, targets, fdfreq) -> ResidualGenerator:
    """``gen`` scaled as the reference scales its filter: the smallest column gain of ``R_f`` (targets) is 1.

    With ``fdfreq`` containing 0: the smallest over the targets of the largest |DC gain| over the residuals, and the
    sign that makes the largest entry of that column positive; otherwise ``1 / fdhinfminus(R_f)``.
    """
    from fdikit.analysis.channels import frequency_response, minimal_channel
    from fdikit.analysis.performance import fdhinfminus
    from fdikit.errors import ModelError

    R = gen.internal_form(model)
    if fdfreq is not None and np.min(np.atleast_1d(fdfreq)) == 0:
        ch = minimal_channel(R, list(targets))
        try:
            dcg = frequency_response(ch, [0.0])[0].real
        except ModelError:      # a plant pole at 0 left in the realisation though cancelled: its limit just off it
            w = 1e-7 * max(1.0, float(np.linalg.norm(ch.A, 1))) * (1.0 if ch.dt is None else 1.0 / ch.dt)
            dcg = frequency_response(ch, [w])[0].real
        y = np.abs(dcg).max(axis=0)
        j = int(np.argmin(y))
        sc = np.sign(dcg[int(np.argmax(np.abs(dcg[:, j]))), j]) / y[j]
    else:
        sc = 1.0 / fdhinfminus(R, inputs=list(targets)).value
    return dataclasses.replace(gen, C=sc * gen.C, D=sc * gen.D)


def efdsyn(model: FaultModel, *, targets=None, nuisance=(), rdim: int | None = None, minimal: bool = True,
           poles: Sequence[complex] | None = None, sdeg: float | None = None, fdtol: float = 1e-4,
           fdgaintol: float = 0.01, fdfreq=None, selection=None, nullspace: bool = True, tol: float = 1e-9,
           names=None, isolates=None) -> NullspaceDesign:
    """Exact fault detection filter by the nullspace method (Procedure EFD).

    Parameters
    ----------
    model : FaultModel
        The plant with its controls ``u``, disturbances ``d`` and fault inputs ``f`` (noise ``w`` is ignored).
    targets : str or sequence of str, optional
        The faults to detect (default: every fault input not in ``nuisance``).
    nuisance : str or sequence of str or "others", default ()
        Fault inputs to decouple exactly, like disturbances.
    rdim : int, optional
        Number of residuals ``q`` (default 1 when ``minimal``, else the number of basis rows).
    minimal : bool, default True
        Least order: the rows of least degree ``d`` that detect every target, combined over one denominator of
        degree ``d`` (order ``d`` for ``q = 1``).  False: all basis rows, each over its own denominator
        (order ``Σ ν_i``).
    poles : sequence of complex, optional
        Filter poles (the first ``d`` of them per denominator); default all at ``sdeg``.
    sdeg : float, optional
        Stability degree of the poles when ``poles`` is None (default −0.05, or 0.95 discrete).
    fdtol : float, default 1e-4
        Relative threshold of weak detectability (reference ``FDtol``).
    fdgaintol : float, default 0.01
        Gain threshold of strong detectability at ``fdfreq`` (reference ``FDGainTol``), applied, as the reference
        does, to the basis rows over the default denominators (all poles at −0.05, or 0.95 discrete), so that
        feasibility does not depend on the ``poles``/``sdeg`` chosen for the filter.
    fdfreq : float or sequence of float, optional
        Frequencies (rad/s) at which each target must be strongly detected (reference ``FDfreq``).
    selection : array_like, optional
        The ``(q, k)`` combination of the ``k`` selected basis rows (reference ``HDesign``); default a fixed
        generic one (identity when ``q = k``).
    nullspace : bool, default True
        The minimal proper basis (True) or the observer basis ``[−Gu I]`` (False, the reference's
        ``nullspace = false``; no disturbances): the synthesis then runs on the observer's residuals, whose rows
        ``selection`` combines, and the filter keeps the plant's order
        (:mod:`~fdikit.design.nullspace.observer_basis`).
    tol : float, default 1e-9
        Relative rank tolerance of the nullspace computation.
    names, isolates : optional
        Residual labels (``fdikit.design.labels``).

    Returns
    -------
    NullspaceDesign

    Raises
    ------
    DesignError
        When no filter exists: the decoupled inputs use up the outputs, or a target is not detectable once they
        are decoupled (the message names the faults), or fewer than ``rdim`` rows are available.
    ParameterError
        Bad options.

    Examples
    --------
    Varga (2017), Example 5.4: the least-order detector of two faults has order 1.

    ``Gu = [(s+1)/(s−2); (s+2)/(s−3)]``, ``Gd = [(s−1)/(s+2); 0]``, ``Gf = [Gu [0; 1]]`` realised by hand:

    >>> m = FaultModel([[2.0, 0, 0], [0, 3.0, 0], [0, 0, -2.0]], [[3.0, 0, -3.0], [0, 5.0, 0]],
    ...                Bu=[[1.0], [1.0], [0.0]], Bd=[[0.0], [0.0], [1.0]], Du=[[1.0], [1.0]], Dd=[[1.0], [0.0]],
    ...                Bf=[[1.0, 0.0], [1.0, 0.0], [0.0, 0.0]], Df=[[1.0, 0.0], [1.0, 1.0]])
    >>> d = efdsyn(m, sdeg=-3.0)
    >>> d.order, d.degrees, d.structure.tolist()
    (1, (1,), [[True, True]])

    References
    ----------
    Varga (2017), §5.2, Procedure EFD; fdtools (``efdsyn``).
    """
    from fdikit.design.labels import label_generator
    from fdikit.design.nullspace.stabilization import stabilize_rows

    if not nullspace:
        from fdikit.design.nullspace.observer_basis import observer_reduction

        obs = observer_reduction(model, poles=poles, sdeg=sdeg)
        return obs.compose(efdsyn(obs.reduced, targets=targets, nuisance=nuisance, rdim=rdim, minimal=minimal,
                                  poles=poles, sdeg=sdeg, fdtol=fdtol, fdgaintol=fdgaintol, fdfreq=fdfreq,
                                  selection=selection, tol=tol, names=names, isolates=isolates), model)
    targets, nuisance = split_faults(model, targets, nuisance)
    basis = left_nullspace(model, nuisance, tol=tol)
    k_all = len(basis.rows)
    if not k_all:
        raise DesignError(f"no residual is free of the controls, disturbances and nuisance faults {list(nuisance)}: "
                          f"[Gd Gn] has full row rank {len(model.outputs)}")
    q = (1 if minimal else k_all) if rdim is None else int(rdim)
    if not 1 <= q <= k_all:
        raise DesignError(f"rdim={rdim}: the nullspace basis has {k_all} rows, so 1 ≤ rdim ≤ {k_all}")
    dens_own = [denominator(nu, poles, sdeg, model.dt) for nu in basis.degrees]
    # strong detectability is judged over the default denominators, not the design's poles (the reference's sdegNS)
    chk_own = [denominator(nu, None, None, model.dt) for nu in basis.degrees]
    S_freq = row_structure(model, basis, targets, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, dens=chk_own,
                           by_frequency=True)
    S_basis = S_freq.all(axis=2)
    missing = [f for f, hit in zip(targets, covered(S_freq)) if not hit]
    if missing:
        kind = f"strongly at {np.atleast_1d(fdfreq).tolist()} rad/s" if fdfreq is not None else "weakly"
        raise DesignError(f"faults {missing} cannot be detected {kind} once the controls, disturbances and nuisance "
                          f"faults {list(nuisance)} are decoupled; the EFDP has no solution "
                          "(fdigenspec lists the achievable structures)")
    if minimal:
        for d in sorted(set(basis.degrees)):
            used = tuple(i for i, nu in enumerate(basis.degrees) if nu <= d)
            if len(used) >= q and covered(S_freq, used).all():
                break
    else:
        used = tuple(range(k_all))
    faults = targets + nuisance

    def build(seed: int):
        H = _selection(selection, q, len(used), seed)
        if minimal:
            rows = basis.combined(H, used)
            d = len(rows[0]) - 1
            A, B, C, D = realize_rows(rows, [denominator(d, poles, sdeg, model.dt)] * q, basis.scale)
        else:
            A, B, C, D = realize_rows(basis.rows, dens_own, basis.scale)
            C, D = H @ C, H @ D
        gen, _ = stabilize_rows(_minimal_generator(A, B, C, D, model, tuple(f"r{i}" for i in range(q))), model,
                                nuisance=nuisance, poles=poles, sdeg=sdeg)
        gen = label_generator(_unit_fault_gain(gen, model, targets, fdfreq), model, names, isolates)
        if minimal:
            S = row_structure(model, basis, faults, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol,
                              dens=[denominator(d, None, None, model.dt)] * q, rows=rows, by_frequency=True)
        else:
            S = _combined_structure(model, basis, H, chk_own, faults, fdtol, fdfreq, fdgaintol)
        return gen, H, S

    # a generic combination can still bring a target's gain under fdtol: then the next fixed ones are tried
    for seed in (range(20170, 20178) if minimal and selection is None and q < len(used) else (20170,)):
        gen, H, S = build(seed)
        if covered(S[:, : len(targets)]).all():
            break
    else:
        raise DesignError(f"the selection {H.round(3).tolist()} of the basis rows {list(used)} misses a target; "
                          "give another selection=")
    return NullspaceDesign(gen, basis, basis.degrees, H, used, gen.n, S.all(axis=2), S_basis, targets, nuisance,
                           np.linalg.eigvals(gen.A) if gen.n else np.zeros(0, complex), model=model)


def _combined_structure(model, basis, H, dens, faults, fdtol, fdfreq, fdgaintol) -> np.ndarray:
    """Structure of ``H · diag(N_i / φ_i)`` per frequency: a residual detects what its nonzero-weighted rows detect,
    generically."""
    S_rows = row_structure(model, basis, faults, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, dens=dens,
                           by_frequency=True)
    weights = np.abs(H) > 1e-12 * np.max(np.abs(H))
    return np.einsum("ij,jfk->ifk", weights.astype(int), S_rows.astype(int)) > 0


@dataclass(frozen=True, eq=False)
class NullspaceBankDesign(FieldReport):
    """A bank of nullspace filters, one per row of a structure matrix (``efdisyn``).

    Attributes
    ----------
    generator : ResidualGenerator
        The stacked bank (``residuals.stack_generators``); residual ``r<i>`` (or ``r<i>_<k>``) belongs to row ``i``.
    filters : tuple of NullspaceDesign
        One design per row of ``specification``.
    specification : numpy.ndarray
        The structure matrix ``S`` asked for, ``(rows, len(faults))``.
    faults : tuple of str
        The columns of ``specification``.
    groups : tuple of tuple of str
        The residual names of each filter (for ``ThresholdEvaluator(groups=...)``).
    orders : tuple of int
        The order of each filter.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> efdisyn(m, np.eye(2)).groups
    (('r0',), ('r1',))

    References
    ----------
    Varga (2017), §5.4, Procedure EFDI; fdtools (``efdisyn``).
    """

    generator: ResidualGenerator
    filters: tuple[NullspaceDesign, ...]
    specification: np.ndarray
    faults: tuple[str, ...]
    groups: tuple[tuple[str, ...], ...]
    orders: tuple[int, ...]

    REPORT = ("specification", "faults", "groups", "orders")


def bank_rows(model: FaultModel, structure, faults, design, rdim=None
              ) -> tuple[np.ndarray, tuple[str, ...], tuple, object]:
    """One filter per row of a structure matrix, named and stacked: the loop of ``efdisyn`` and ``afdisyn``.

    Parameters
    ----------
    model : FaultModel
        The plant.
    structure : array_like of bool
        ``S``: row ``i`` detects the faults of its ones and decouples those of its zeros (and every fault of the
        model not in ``faults``).
    faults : sequence of str or None
        The columns of ``S`` (default the model's fault inputs).
    design : callable
        ``design(targets, nuisance, rdim)`` returning a design with a ``generator`` (``efdsyn`` or ``afdsyn`` with
        the caller's options).
    rdim : int or sequence of int, optional
        The number of residuals of every filter, or one per row (the reference's vector ``rdim``); passed on.

    Returns
    -------
    S : numpy.ndarray
        The structure as booleans.
    faults : tuple of str
    filters : tuple
        The designs, their residuals renamed ``r<i>`` (``r<i>_<k>`` for several) and tied to the row's fault when
        it detects one only.
    generator : ResidualGenerator
        The stacked bank.

    Raises
    ------
    ParameterError
        A malformed ``structure`` or a row without ones.
    DesignError
        A row that cannot be achieved (the message gives the row).

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> S, faults, filters, gen = bank_rows(m, np.eye(2), None, lambda t, n, q: efdsyn(m, targets=t, nuisance=n))
    >>> gen.residuals, gen.isolates
    (('r0', 'r1'), ('f0', 'f1'))

    References
    ----------
    Varga (2017), §5.4 (one filter per row of the structure matrix).
    """
    from fdikit.fault_maps import check_fault_inputs
    from fdikit.residuals import stack_generators

    faults = tuple(model.faults) if faults is None else tuple(check_fault_inputs(model, faults))
    S = np.atleast_2d(np.asarray(structure))
    if S.ndim != 2 or S.shape[1] != len(faults) or not np.isin(S, (0, 1)).all():
        raise ParameterError(f"structure must be a 0/1 matrix with one column per fault {list(faults)}, got shape "
                             f"{S.shape}")
    S = S.astype(bool)
    if rdim is None or np.ndim(rdim) == 0:
        rdims = [rdim] * len(S)
    else:
        rdims = [validate.integer("rdim", r, minimum=1) for r in rdim]
        if len(rdims) != len(S):
            raise ParameterError(f"rdim has {len(rdims)} entries; give one per row of the structure ({len(S)}) or "
                                 "one number for all")
    filters = []
    for i, row in enumerate(S):
        tg = tuple(f for f, s in zip(faults, row) if s)
        nz = tuple(f for f, s in zip(faults, row) if not s) + tuple(f for f in model.faults if f not in faults)
        if not tg:
            raise ParameterError(f"row {i} of the structure has no fault to detect")
        try:
            d = design(tg, nz, rdims[i])
        except DesignError as err:
            raise DesignError(f"row {i} of the structure ({row.astype(int).tolist()}) is not achievable: {err}"
                              ) from err
        q = len(d.generator.residuals)
        names = (f"r{i}",) if q == 1 else tuple(f"r{i}_{k}" for k in range(q))
        iso = tg[0] if len(tg) == 1 else None
        filters.append(dataclasses.replace(d, generator=dataclasses.replace(d.generator, residuals=names,
                                                                            isolates=(iso,) * q)))
    return S, faults, tuple(filters), stack_generators([f.generator for f in filters])


def efdisyn(model: FaultModel, structure, *, faults=None, rdim: int | Sequence[int] | None = None,
            minimal: bool = True,
            poles=None, sdeg: float | None = None, fdtol: float = 1e-4, fdgaintol: float = 0.01, fdfreq=None,
            nullspace: bool = True, tol: float = 1e-9) -> NullspaceBankDesign:
    """A bank of exact fault detection filters achieving the structure matrix ``structure`` (Procedure EFDI).

    Parameters
    ----------
    model : FaultModel
        The plant.
    structure : array_like of bool
        ``S``: row ``i`` asks for a filter that detects the faults of its ones and decouples those of its zeros.
    faults : sequence of str, optional
        The columns of ``S`` (default the model's fault inputs, in order).
    rdim : int or sequence of int, optional
        As :func:`efdsyn`, for every row, or one per row.
    minimal, poles, sdeg, fdtol, fdgaintol, fdfreq, nullspace, tol
        As :func:`efdsyn`, for every row.

    Returns
    -------
    NullspaceBankDesign

    Raises
    ------
    DesignError
        A row that cannot be achieved (the message gives the row and the faults).
    ParameterError
        A malformed ``structure``.

    Examples
    --------
    Two faults on two sensors of a first-order plant, isolated by the diagonal structure:

    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> bank = efdisyn(m, np.eye(2))
    >>> bank.orders, bank.generator.residuals
    ((1, 1), ('r0', 'r1'))

    References
    ----------
    Varga (2017), §5.4, Procedure EFDI; fdtools (``efdisyn``).
    """
    S, faults, filters, gen = bank_rows(
        model, structure, faults,
        lambda tg, nz, q: efdsyn(model, targets=tg, nuisance=nz, rdim=q, minimal=minimal, poles=poles, sdeg=sdeg,
                                 fdtol=fdtol, fdgaintol=fdgaintol, fdfreq=fdfreq, nullspace=nullspace, tol=tol),
        rdim=rdim)
    groups = tuple(tuple(f.generator.residuals) for f in filters)
    return NullspaceBankDesign(gen, filters, S, faults, groups, tuple(f.order for f in filters), model=model)
