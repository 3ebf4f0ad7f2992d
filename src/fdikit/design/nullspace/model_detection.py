"""Model detection by the nullspace method: ``mdgenspec``, ``emdsyn`` (Procedure EMD), ``amdsyn`` (Procedure AMD)
and ``mdmatch`` (Varga 2017, §6.1–6.3).

A bank of ``N`` filters for a multiple model ``{G^(i)}`` (same outputs and controls): filter ``j`` lies in the left
nullspace of model ``j``'s ``[G_u^(j) G_d^(j); I 0]``, so its residual vanishes when the plant behaves as model
``j``, and it should not vanish under model ``i ≠ j``: ``R_ji = Q_j [G_u^(i) G_d^(i); I 0] ≢ 0``.  Because
``Q_j`` decouples model ``j``'s controls, ``R_ji``'s control part is ``Q_y (G_u^(i) − G_u^(j))``, so model ``i`` is
detected by a basis row of model ``j`` exactly when that row detects the "fault" ``G_u^(i) − G_u^(j)`` (and, with
``emdtest``, ``G_d^(i)``): the weak and strong tests of
:func:`~fdikit.design.nullspace.detectability.row_structure` apply unchanged to that difference model.

``emdsyn`` takes, per model, the basis rows of least degree that detect every other model, one fixed generic
combination of them over one stable denominator (the model's own poles inside ``smarg``, as the reference's proper
basis keeps them, then ``poles``/``sdeg``), and scales the filter as the reference does:
the smallest ``‖R_ji‖∞`` over ``i ≠ j`` is 1 (``normalize=False``), or ``‖R_j0‖ = ‖R_0j‖`` (``normalize=True``).
``performance[j, i]`` is ``‖R_ji‖∞`` of the control channel (with ``emdtest`` of ``[u d]``), or the largest gain
at ``mdfreq``.

References
----------
Varga (2017), §6.1–6.3 (model detection, Procedures EMD and AMD); Varga (2009) (least order model detection);
fdtools (``emdsyn``, ``amdsyn``, ``mdgenspec``, ``mdmatch``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError
from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = ["ModelDetectionDesign", "difference_model", "mdgenspec", "emdsyn", "amdsyn", "mdmatch"]


@dataclass(frozen=True, eq=False)
class ModelDetectionDesign:
    """A bank of exact model detection filters.

    Attributes
    ----------
    generators : tuple of ResidualGenerator
        Filter ``j`` (residual ``r<k>``, or ``r<k>_<l>`` with ``rdim > 1``, ``k = selected[j]``), reading ``[u; y]``.
    performance : numpy.ndarray
        ``(len(selected), N)``: ``performance[j, i]`` the gain of filter ``j`` under model ``i`` (reference
        ``MDperf``).
    degrees : tuple of int
        The basis degree used per filter (its order; with ``minimal=False`` the sum of the row degrees).
    models : tuple of FaultModel
        The multiple model.
    gaps : numpy.ndarray or None
        :func:`amdsyn`: per filter ``j``, ``min_{i≠j} performance[j, i] / ‖R_w^(jj)‖∞`` (``inf`` without noise;
        reference ``MDgap``).
    factorizations : tuple of str or None
        :func:`amdsyn`: the kind of noise factor per filter ("standard", "quasi", …; "none" without noise).
    selected : tuple of int or None
        The models whose filters were designed (reference ``MDSelect``); None: all, in order.

    Examples
    --------
    >>> m1, m2 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]]), FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]])
    >>> d = emdsyn([m1, m2], sdeg=-3.0)
    >>> d.degrees, np.round(d.performance, 6).tolist()
    ((1, 1), [[0.0, 1.0], [1.0, 0.0]])

    References
    ----------
    Varga (2017), §6.2; fdtools (``emdsyn``, ``info.MDperf``).
    """

    generators: tuple[ResidualGenerator, ...]
    performance: np.ndarray
    degrees: tuple[int, ...]
    models: tuple[FaultModel, ...]
    gaps: np.ndarray | None = None
    factorizations: tuple[str, ...] | None = None
    selected: tuple[int, ...] | None = None

    @property
    def filter_models(self) -> tuple[int, ...]:
        """The model index of each filter (``selected``, or all)."""
        return tuple(range(len(self.models))) if self.selected is None else self.selected

    @property
    def orders(self) -> tuple[int, ...]:
        """The filters' state dimensions."""
        return tuple(g.n for g in self.generators)


def difference_model(model_j: FaultModel, model_i: FaultModel, *, emdtest: bool = False) -> FaultModel:
    """``G_u^(i) − G_u^(j)`` (and ``G_d^(i)`` with ``emdtest``) as the fault channels of a model with ``j``'s signals.

    A filter that decouples model ``j``'s controls sees model ``i`` through these "faults" only (its control inputs
    carry nothing here: ``B_u = 0``, ``D_u = 0``).

    Parameters
    ----------
    model_j, model_i : FaultModel
        Models with the same outputs and controls.
    emdtest : bool, default False
        Include model ``i``'s disturbance channels.

    Returns
    -------
    FaultModel
        States ``[x_i; x_j]``; faults ``delta_<control>`` (and ``model_<disturbance>``).

    Examples
    --------
    >>> m1, m2 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]]), FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]])
    >>> difference_model(m1, m2).faults
    ('delta_u0',)

    References
    ----------
    Varga (2017), §6.1 (model detectability).
    """
    from scipy.linalg import block_diag

    mu, kd = len(model_i.controls), len(model_i.disturbances) if emdtest else 0
    Bi, Di = model_i.B[:, : mu + kd], model_i.D[:, : mu + kd]
    Bj = np.hstack([model_j.B[:, :mu], np.zeros((model_j.n, kd))])
    Dj = np.hstack([model_j.D[:, :mu], np.zeros((model_j.D.shape[0], kd))])
    n = model_i.n + model_j.n
    faults = [f"delta_{c}" for c in model_i.controls] + [f"model_{d}" for d in model_i.disturbances[:kd]]
    return FaultModel(block_diag(model_i.A, model_j.A), np.hstack([model_i.C, -model_j.C]),
                      Bu=np.zeros((n, mu)), Du=np.zeros((model_i.C.shape[0], mu)), Bf=np.vstack([Bi, Bj]),
                      Df=Di - Dj, controls=model_j.controls, outputs=model_j.outputs, faults=faults, dt=model_j.dt)


def _row_tests(models, j, basis, dens, mdtol, mdfreq, mdgaintol, emdtest) -> np.ndarray:
    """``(rows, N)``: which basis rows of model ``j`` detect each model (False on the diagonal)."""
    from fdikit.design.nullspace.detectability import row_structure

    out = np.zeros((len(basis.rows), len(models)), dtype=bool)
    for i, mi in enumerate(models):
        if i == j:
            continue
        dm = difference_model(models[j], mi, emdtest=emdtest)
        # weak, or strong at some frequency of mdfreq (reference: detected at one of them suffices)
        freqs = [None] if mdfreq is None else list(np.atleast_1d(np.asarray(mdfreq, dtype=float)))
        for f in freqs:
            S = row_structure(dm, basis, dm.faults, fdtol=mdtol, fdfreq=f, fdgaintol=mdgaintol, dens=dens)
            out[:, i] |= S.any(axis=1)         # some channel of model i
    return out


def mdgenspec(models: Sequence[FaultModel], *, mdtol: float = 1e-4, mdfreq=None, mdgaintol: float = 0.01,
              emdtest: bool = False) -> np.ndarray:
    """The achievable model detection structure: ``S[j, i]`` — can a filter of model ``j`` detect model ``i``?

    Parameters
    ----------
    models : sequence of FaultModel
        The multiple model (:func:`~fdikit.design.nullspace.model_distances.check_models`).
    mdtol : float, default 1e-4
        Relative threshold of weak detectability (reference ``MDtol``).
    mdfreq : float or sequence of float, optional
        Frequencies (rad/s) of strong detectability (reference ``MDfreq``): model ``i`` counts as detected when the
        gain exceeds ``mdgaintol`` at one of them.
    mdgaintol : float, default 0.01
        Gain threshold of strong detectability, on the basis rows over the default denominators (``MDGainTol``).
    emdtest : bool, default False
        Test the disturbance channels of model ``i`` too.

    Returns
    -------
    numpy.ndarray
        ``(N, N)`` booleans, False on the diagonal.

    Raises
    ------
    ParameterError
        Bad models.

    Examples
    --------
    >>> m1, m2 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]]), FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]])
    >>> mdgenspec([m1, m2]).tolist(), mdgenspec([m1, m2], mdfreq=0).tolist()   # equal DC gains
    ([[False, True], [True, False]], [[False, False], [False, False]])

    References
    ----------
    Varga (2017), §6.1; fdtools (``mdgenspec``).
    """
    from fdikit.design.nullspace.basis import denominator, left_nullspace
    from fdikit.design.nullspace.model_distances import check_models

    models = check_models(models)
    S = np.zeros((len(models), len(models)), dtype=bool)
    for j, mj in enumerate(models):
        basis = left_nullspace(mj)
        if not basis.rows:
            continue
        dens = [denominator(nu, None, None, mj.dt) for nu in basis.degrees]
        S[j] = _row_tests(models, j, basis, dens, mdtol, mdfreq, mdgaintol, emdtest).any(axis=0)
    return S


def _gain(gen: ResidualGenerator, dm: FaultModel, mdfreq) -> float:
    from fdikit.analysis.channels import frequency_response, hinf_norm, minimal_channel

    ch = minimal_channel(gen.internal_form(dm), list(dm.faults))
    if mdfreq is None:
        return float(hinf_norm(ch)[0])
    G = frequency_response(ch, np.atleast_1d(np.asarray(mdfreq, dtype=float)))
    return float(max(np.linalg.norm(g, 2) for g in G))


def _filter_poles(model: FaultModel, degree: int, poles, sdeg, smarg) -> list[complex]:
    """The ``degree`` filter poles: the model's own poles inside the margin (slowest first, conjugate pairs kept
    together), as the reference's proper basis keeps them and moves only the others, then ``poles``, then ``sdeg``."""
    from fdikit.design.nullspace.basis import default_sdeg, minimal_realization

    cols = list(range(len(model.controls) + len(model.disturbances)))
    A = minimal_realization(model.A, model.B[:, cols], model.C, model.D[:, cols])[0] if model.n else np.zeros((0, 0))
    ev = np.linalg.eigvals(A) if A.size else np.zeros(0, complex)
    if model.dt is None:
        margin = -np.sqrt(np.finfo(float).eps) if smarg is None else float(smarg)
        inside, slow = ev[ev.real < margin], lambda x: -x.real
    else:
        margin = 1 - np.sqrt(np.finfo(float).eps) if smarg is None else float(smarg)
        inside, slow = ev[np.abs(ev) < margin], lambda x: -abs(x)
    chosen: list[complex] = []
    for x in sorted((x for x in inside if x.imag >= 0), key=slow):
        k = 1 if x.imag == 0 else 2
        if len(chosen) + k <= degree:
            chosen += [complex(x)] if k == 1 else [complex(x), complex(np.conj(x))]
    fill = list(poles) if poles is not None else []
    s0 = default_sdeg(model.dt) if sdeg is None else float(sdeg)
    return (chosen + fill + [s0] * degree)[:degree]


def _options(models, rdim, selection, select, normalize, **kw) -> dict:
    from fdikit.errors import ParameterError

    if rdim is not None and (isinstance(rdim, bool) or not isinstance(rdim, int | np.integer) or rdim < 1):
        raise ParameterError(f"rdim must be an integer >= 1 or None, got {rdim!r}")
    if selection is not None and len(selection) != len(models):
        raise ParameterError(f"selection needs one entry (a matrix or None) per model: {len(models)}, got "
                             f"{len(selection)}")
    N = len(models)
    sel = tuple(range(N)) if select is None else tuple(int(j) for j in np.atleast_1d(select))
    if not sel or len(set(sel)) != len(sel) or min(sel) < 0 or max(sel) >= N:
        raise ParameterError(f"select must be distinct model indices in 0 … {N - 1} (at least one), got {select!r}")
    if normalize and sel[0] != 0:
        raise ParameterError("normalize=True scales the filters against filter 0, so select must start with 0 "
                             f"(got {list(sel)})")
    return {"rdim": None if rdim is None else int(rdim), "selection": selection, "select": sel,
            "normalize": bool(normalize), **kw}


def emdsyn(models: Sequence[FaultModel], *, rdim: int | None = None, minimal: bool = True, selection=None,
           select: Sequence[int] | None = None, poles: Sequence[complex] | None = None, sdeg: float | None = None,
           smarg: float | None = None, mdtol: float = 1e-4, mdfreq=None, mdgaintol: float = 0.01,
           emdtest: bool = False, normalize: bool = False) -> ModelDetectionDesign:
    """Exact model detection filters of least order, one per model (Procedure EMD; reference ``emdsyn``).

    Parameters
    ----------
    models : sequence of FaultModel
        The multiple model: same outputs, controls and sample time; disturbances may differ.
    rdim : int, optional
        Residuals per filter (reference ``rdim``; default 1, or with ``minimal=False`` the number of basis rows): the
        least degree ``d`` with at least ``rdim`` basis rows of degree ``≤ d`` that together detect every other
        model.
    minimal : bool, default True
        Least order (the rows of degree ``≤ d`` over one denominator of degree ``d``).  False: full order (reference
        ``minimal = false``): every basis row over its own denominator, ``rdim`` combinations of them.
    selection : sequence of array_like or None, optional
        Per filter, the ``(rdim, k)`` combination of those ``k`` rows (all rows with ``minimal=False``; reference
        ``HDesign``, in fdikit's basis coordinates), or None for the default: the identity when ``k = rdim``, else a
        fixed generic one.
    select : sequence of int, optional
        The models whose filters are designed, in order (reference ``MDSelect``); default all.
    poles : sequence of complex, optional
        Filter poles for the places the model's own poles do not fill (see ``smarg``); then ``sdeg``.
    sdeg : float, optional
        Stability degree of the remaining poles (default −0.05, discrete 0.95).
    smarg : float, optional
        Stability margin (default ``−√ε``, discrete ``1 − √ε``): the model's poles inside it are the filter's first
        poles (slowest first), as the reference's proper basis keeps its poles there and moves only the others.
    mdtol, mdfreq, mdgaintol, emdtest
        As :func:`mdgenspec`; ``mdfreq`` also sets where ``performance`` is evaluated.
    normalize : bool, default False
        False: each filter's smallest off-diagonal gain is 1.  True: filter 0 so, and filter ``j`` such that
        ``performance[j, 0] = performance[0, j]`` (needs ``select`` to start with 0).

    Returns
    -------
    ModelDetectionDesign

    Raises
    ------
    DesignError
        A model that no filter of another model can tell apart (``mdgenspec`` shows which).
    ParameterError
        Bad models or options.

    Examples
    --------
    >>> m1, m2 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]]), FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]])
    >>> d = emdsyn([m1, m2])       # each filter keeps its model's pole: Q_j = [−G_j  1] on [u; y], up to scale
    >>> d.orders, [np.round(np.linalg.eigvals(g.A).real, 6).tolist() for g in d.generators]
    ((1, 1), [[-1.0], [-2.0]])
    >>> [np.round(np.linalg.eigvals(g.A).real, 6).tolist() for g in emdsyn([m1, m2], smarg=-5.0).generators]
    [[-0.05], [-0.05]]

    References
    ----------
    Varga (2017), §6.2, Procedure EMD; fdtools (``emdsyn``).
    """
    from fdikit.design.nullspace.model_distances import check_models

    models = check_models(models)
    opts = _options(models, rdim, selection, select, normalize, poles=poles, sdeg=sdeg, smarg=smarg, mdtol=mdtol,
                    mdfreq=mdfreq, mdgaintol=mdgaintol, emdtest=emdtest, minimal=bool(minimal))
    pairs = [_exact_filter(models, j, opts) for j in opts["select"]]
    gens, P = _scaled([g for g, _ in pairs], models, opts)
    return ModelDetectionDesign(gens, P, tuple(d for _, d in pairs), models, selected=_selected(opts, models))


def _combination(selection, j: int, q: int, k: int) -> np.ndarray:
    """The ``(q, k)`` combination of filter ``j``'s rows: ``selection[j]`` (checked) or a fixed generic one."""
    from fdikit.errors import ParameterError

    H = None if selection is None else selection[j]
    if H is None:
        if q == k:
            return np.eye(k)
        return np.linalg.qr(np.random.default_rng(20170).standard_normal((k, q)))[0].T
    H = np.atleast_2d(np.asarray(H, dtype=float))
    if H.shape != (q, k) or not np.all(np.isfinite(H)) or np.linalg.matrix_rank(H) < q:
        raise ParameterError(f"selection[{j}] must be a finite ({q}, {k}) matrix of full row rank (filter {j} "
                             f"combines its {k} least-degree basis rows into {q} residuals), got shape {H.shape}")
    return H


def _exact_filter(models, j, opts):
    """Filter ``j`` of Procedure EMD (unscaled) and its degree (with ``minimal=False``: the sum of the degrees)."""
    from fdikit.design.nullspace.basis import denominator, left_nullspace, minimal_realization, realize_rows

    mj, mdfreq, minimal = models[j], opts["mdfreq"], opts.get("minimal", True)
    others = [i for i in range(len(models)) if i != j]
    basis = left_nullspace(mj)
    if not basis.rows:
        raise DesignError(f"model {j}: its disturbances use up the outputs; no residual decouples it")
    q = opts["rdim"] if opts["rdim"] is not None else (1 if minimal else len(basis.rows))
    if q > len(basis.rows):
        raise DesignError(f"rdim={q}: the nullspace basis of model {j} has {len(basis.rows)} rows")
    chk = [denominator(nu, None, None, mj.dt) for nu in basis.degrees]
    T = _row_tests(models, j, basis, chk, opts["mdtol"], mdfreq, opts["mdgaintol"], opts["emdtest"])
    missing = [i for i in others if not T[:, i].any()]
    if missing:
        raise DesignError(f"models {missing} cannot be told apart from model {j} by a filter that decouples "
                          f"model {j}{' at the frequencies ' + str(mdfreq) if mdfreq is not None else ''} "
                          "(see mdgenspec)")

    def den(d: int) -> np.ndarray:
        return denominator(d, _filter_poles(mj, d, opts["poles"], opts["sdeg"], opts["smarg"]), None, mj.dt)

    if minimal:
        for d in sorted(set(basis.degrees)):
            used = [k for k, nu in enumerate(basis.degrees) if nu <= d]
            if len(used) >= q and all(T[used, i].any() for i in others):
                break
        H = _combination(opts["selection"], j, q, len(used))
        A, B, C, D = minimal_realization(*realize_rows(basis.combined(H, used), [den(d)] * q, basis.scale))
    else:                       # full order: every row over its own denominator, rdim combinations
        H = _combination(opts["selection"], j, q, len(basis.rows))
        A, B, C, D = realize_rows(basis.rows, [den(nu) for nu in basis.degrees], basis.scale)
        A, B, C, D = minimal_realization(A, B, H @ C, H @ D)
        d = sum(basis.degrees)
    names = (f"r{j}",) if q == 1 else tuple(f"r{j}_{k}" for k in range(q))
    return ResidualGenerator(A, B, C, D, controls=mj.controls, outputs=mj.outputs, residuals=names, dt=mj.dt), d


def _selected(opts, models) -> tuple[int, ...] | None:
    return None if opts["select"] == tuple(range(len(models))) else opts["select"]


def _scaled(gens, models, opts):
    """The performance matrix and the filters scaled as the reference scales them (see :func:`emdsyn`)."""
    N, sel = len(models), opts["select"]
    gens = list(gens)
    P = np.array([[_gain(gens[r], difference_model(models[j], models[i], emdtest=opts["emdtest"]), opts["mdfreq"])
                   for i in range(N)] for r, j in enumerate(sel)])
    off = np.ones(P.shape, dtype=bool)
    off[range(len(sel)), list(sel)] = False
    if N > 1 and np.any(P[off] <= 0):
        raise DesignError("a combination of basis rows lost a model; this should not happen with the generic choice")
    for r, j in enumerate(sel if N > 1 else ()):
        sc = P[0, j] / P[r, 0] if opts["normalize"] and r > 0 else 1.0 / np.delete(P[r], j).min()
        P[r] *= sc
        gens[r] = dataclasses.replace(gens[r], C=sc * gens[r].C, D=sc * gens[r].D)
    return tuple(gens), P


def mdmatch(design: ModelDetectionDesign, model: FaultModel, *, mdfreq=None,
            emdtest: bool = False) -> tuple[np.ndarray, int]:
    """The gains of the bank on a plant model and the model it matches best (reference ``mdmatch``).

    Parameters
    ----------
    design : ModelDetectionDesign
        The bank.
    model : FaultModel
        The plant (same outputs and controls as the bank's models).
    mdfreq : float or sequence of float, optional
        Evaluate at these frequencies (largest pointwise gain) instead of the H∞ norm.
    emdtest : bool, default False
        Include the plant's disturbance channels.

    Returns
    -------
    gains : numpy.ndarray
        ``‖Q_j [G_u G_d; I 0]‖`` per filter ``j``.
    index : int
        The model of the filter with the smallest gain: the matching model.

    Examples
    --------
    >>> m1, m2 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]]), FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]])
    >>> gains, k = mdmatch(emdsyn([m1, m2]), m2)
    >>> k, bool(gains[1] < 1e-9)
    (1, True)

    References
    ----------
    Varga (2017), §6.1; fdtools (``mdmatch``).
    """
    from fdikit.design.nullspace.model_distances import check_models

    check_models(list(design.models) + [model])
    g = np.array([_gain(gen, difference_model(design.models[j], model, emdtest=emdtest), mdfreq)
                  for gen, j in zip(design.generators, design.filter_models)])
    return g, int(design.filter_models[int(np.argmin(g))])


def amdsyn(models: Sequence[FaultModel], *, rdim: int | None = None, minimal: bool = True, selection=None,
           select: Sequence[int] | None = None,
           poles: Sequence[complex] | None = None, sdeg: float | None = None, smarg: float | None = None,
           mdtol: float = 1e-4, mdfreq=None, mdgaintol: float = 0.01, emdtest: bool = False, normalize: bool = False,
           nonstd: str = "quasi", epsreg: float = 0.1, sdegzer: float | None = None) -> ModelDetectionDesign:
    """Approximate model detection filters: ``emdsyn``'s filters with their own-model noise made co-inner
    (Procedure AMD; reference ``amdsyn``).

    Filter ``j`` of :func:`emdsyn` is multiplied by ``F⁻¹``, ``F`` the (co-outer, or non-standard) factor of its noise
    channel on model ``j``, ``R_w^(jj) = Q_j [G_w^(j); 0]``
    (:func:`~fdikit.design.nullspace.noise_factors.noise_factor`), which maximises the gap ``β_j / ‖R_w^(jj)‖∞``
    (``β_j`` its smallest gain on another model); then the filters are scaled as in :func:`emdsyn`.

    Parameters
    ----------
    models : sequence of FaultModel
        The multiple model; each model's noise inputs (group ``w``) are attenuated.
    rdim, minimal, selection, select, poles, sdeg, smarg, mdtol, mdfreq, mdgaintol, emdtest, normalize
        As :func:`emdsyn`.
    nonstd, epsreg, sdegzer
        The non-standard noise factor, as :func:`~fdikit.design.nullspace.approximate.afdsyn`.

    Returns
    -------
    ModelDetectionDesign
        With ``gaps`` and ``factorizations``.

    Raises
    ------
    DesignError, ParameterError
        As :func:`emdsyn`.

    Examples
    --------
    Output noise ``y = G_j u + w``: the noise part of ``Q_j ∝ [−G_j 1]`` is constant, so the gap is the L∞ distance
    to the other model, ``‖1/(s+1) − 2/(s+2)‖∞ = ‖s/((s+1)(s+2))‖∞ = 1/3`` (at ω = √2):

    >>> m1 = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], Dw=[[1.0]])
    >>> m2 = FaultModel([[-2.0]], [[2.0]], Bu=[[1.0]], Dw=[[1.0]])
    >>> d = amdsyn([m1, m2])
    >>> d.factorizations, np.round(d.gaps, 6).tolist()
    (('standard', 'standard'), [0.333333, 0.333333])

    References
    ----------
    Varga (2017), §6.3, Procedure AMD; fdtools (``amdsyn``, ``info.MDgap``).
    """
    from fdikit.analysis.channels import hinf_norm, minimal_channel
    from fdikit.design.nullspace.model_distances import check_models
    from fdikit.design.nullspace.noise_factors import attenuate_noise

    models = check_models(models)
    opts = _options(models, rdim, selection, select, normalize, poles=poles, sdeg=sdeg, smarg=smarg, mdtol=mdtol,
                    mdfreq=mdfreq, mdgaintol=mdgaintol, emdtest=emdtest, minimal=bool(minimal))
    gens, kinds, degs = [], [], []
    for j in opts["select"]:
        mj = models[j]
        g, d = _exact_filter(models, j, opts)
        degs.append(d)
        ch = minimal_channel(g.internal_form(mj), list(mj.noise)) if mj.noise else None
        if ch is None or hinf_norm(ch)[0] <= 1e-12 * max(1.0, float(np.abs(g.D).max(initial=0.0))):
            gens.append(g)
            kinds.append("none")
            continue
        g, fac = attenuate_noise(g, mj, channel=ch, nonstd=nonstd, epsreg=epsreg, poles=poles, sdeg=sdeg,
                                 smarg=smarg, sdegzer=sdegzer)
        gens.append(g)
        kinds.append(fac.kind)
    gens, P = _scaled(gens, models, opts)
    gaps = np.full(len(gens), np.inf)
    for r, (g, j) in enumerate(zip(gens, opts["select"])):
        if kinds[r] != "none":
            wn = hinf_norm(minimal_channel(g.internal_form(models[j]), list(models[j].noise)))[0]
            gaps[r] = np.delete(P[r], j).min() / wn if len(models) > 1 else np.inf
    return ModelDetectionDesign(gens, P, tuple(degs), models, gaps, tuple(kinds), selected=_selected(opts, models))
