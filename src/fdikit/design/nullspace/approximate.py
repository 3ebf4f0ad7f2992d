"""Approximate fault detection and isolation by the nullspace method: afdsyn, afdisyn (Varga 2017, §5.3, §5.5).

``afdsyn`` solves the approximate fault detection problem (AFDP, Procedure AFD): a stable filter ``Q`` that
decouples the controls, disturbances and nuisance faults exactly (``Q = Q̄ Q_1``, ``Q_1`` a left nullspace basis of
``[Gu Gd Gn; I 0 0]``), detects every targeted fault and maximises the fault-to-noise gap
``‖R_f‖∞− / ‖R_w‖∞`` with ``‖R_w‖∞ = γ``.  The steps: select ``q_1 ≤ rank R_w`` rows of the basis (least order,
all targets detected, ``H R_w`` of full row rank at a test frequency); factor their noise part
``R_w = R_wo R_wi`` (co-outer–co-inner, :mod:`~fdikit.design.nullspace.factorization`) and set ``Q ← R_wo⁻¹ Q``
(non-standard case: the quasi factor with its boundary and infinite zeros moved to the assigned poles, or the
regularised factor); scale to ``‖R_w‖∞ = γ``.  When ``rdim`` exceeds ``rank R_w`` the remaining residuals come
from the rows that decouple the noise too (an exact design, scaled so that its fault gain is the first part's gap;
reference ``scale2``).  Without noise (or ``R_w = 0``) the problem is exact and :func:`~.exact.efdsyn` solves it.

``afdisyn`` builds one ``afdsyn`` filter per row of a structure matrix (Procedure AFDI); a row whose strong design
fails is designed again with its zeros as noise (the reference's weak AFDIP of ``afdsyn(sysf, SFDI)``).

Plant modes that only the faults or the noise excite are moved out of the internal form by a left coprime factor
(:mod:`~fdikit.design.nullspace.stabilization`) before the noise is factored.

Differences from the reference: the basis is the least-degree polynomial basis over stable denominators
(:mod:`~fdikit.design.nullspace.basis`), so state coordinates and the design matrices ``H`` differ, and every basis
pole is assigned (the reference's ``smarg`` acts here on the stabilisation of the internal form and on the zeros
moved in the ``"quasi"`` case of one row); with several residuals (or a discrete model) the quasi and Wiener–Hopf
factors are built by row operations on the realisation (:mod:`~fdikit.design.nullspace.zero_steps`), not by the
reference's descriptor reductions (``goifac``, ``gcrange``, ``glcf``): another member of the same family of
factors, so the quasi gaps need not be equal.

References
----------
Varga (2017), §5.3 (AFDP, Procedure AFD), §5.5 (AFDIP, Procedure AFDI), Remark 5.8; fdtools (``afdsyn``,
``afdisyn``, ``afdredsyn``).
"""

from __future__ import annotations

import dataclasses
import itertools
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.design.nullspace.basis import NullspaceBasis, denominator, left_nullspace, minimal_realization, realize_rows
from fdikit.design.nullspace.detectability import covered, fault_response, frequency_points, row_structure
from fdikit.design.nullspace.exact import bank_rows, efdsyn, split_faults
from fdikit.design.nullspace.factorization import transfer
from fdikit.design.nullspace.noise_factors import NONSTD_OPTIONS, attenuate_noise
from fdikit.errors import DesignError, FdiWarning, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["ApproximateDesign", "ApproximateBankDesign", "afdsyn", "afdisyn"]

_TEST_FREQ = 0.6180339887          # fixed test frequency of the rank checks (the reference draws one at random)


@dataclass(frozen=True, eq=False)
class ApproximateDesign(FieldReport):
    """An approximate fault detection filter (``afdsyn``) and its report.

    Attributes
    ----------
    generator : ResidualGenerator
        The filter ``Q`` (inputs ``[u; y]``), minimal and stable; ``‖R_w‖∞ = γ`` for the noise-attenuating part.
    basis : NullspaceBasis
        The left nullspace basis of ``[Gu Gd Gn; I 0 0]``.
    degrees : tuple of int
        Its row degrees (reference ``info.degs``).
    selection : numpy.ndarray
        ``(q_1, len(used))`` combination of the basis rows ``used`` (reference ``info.HDesign``).
    used : tuple of int
        The basis rows of the noise-attenuating part.
    order : int
        The filter order.
    gap : float
        The achieved fault-to-noise gap ``β/γ`` (:func:`~fdikit.analysis.performance.fdif2ngap` over the targets,
        at ``fdfreq`` when given; ``inf`` without noise).
    beta : float
        ``‖R_f‖∞−`` of the targets (at ``fdfreq`` when given).
    gamma : float
        ``‖R_w‖∞`` achieved (``γ`` asked for; 0 without noise).
    noise_rank : int
        The normal rank of ``R_w`` of the basis (reference ``rw``).
    factorization : str
        ``"standard"``, ``"quasi"``, ``"regularized"``, ``"wiener-hopf"``, ``"wiener-hopf-shift"``,
        ``"wiener-hopf-regularize"`` or ``"none"`` (exact problem).
    shifted : int
        Number of zeros of the noise factor moved (boundary, infinite and, with ``smarg``, slow ones) or handled by
        the Wiener–Hopf factor.
    targets, nuisance : tuple of str
        The detected and the decoupled fault inputs.
    poles : numpy.ndarray
        The filter eigenvalues.

    Examples
    --------
    >>> m = FaultModel([[-2.0]], [[1.0]], Bf=[[1.0]], Df=[[1.0]], Bw=[[1.0]], faults=["f"])
    >>> d = afdsyn(m, sdeg=-3.0)
    >>> round(d.gap, 6), d.order, d.factorization
    (3.0, 1, 'quasi')

    References
    ----------
    Varga (2017), §5.3, Procedure AFD; fdtools (``afdsyn``).
    """

    generator: ResidualGenerator
    basis: NullspaceBasis
    degrees: tuple[int, ...]
    selection: np.ndarray
    used: tuple[int, ...]
    order: int
    gap: float
    beta: float
    gamma: float
    noise_rank: int
    factorization: str
    shifted: int
    targets: tuple[str, ...]
    nuisance: tuple[str, ...]
    poles: np.ndarray

    REPORT = ("degrees", "selection", "used", "order", "gap", "beta", "gamma", "noise_rank", "factorization",
              "shifted", "targets", "nuisance", "poles")


def _noise_numerators(model: FaultModel, basis: NullspaceBasis, lam: complex) -> np.ndarray:
    """``N(λ) [0; G_w(λ)]``: the noise part of the basis numerators at ``λ`` (rank as ``R_w``)."""
    mu = len(model.controls)
    Nl = basis.evaluate(lam)
    if not model.noise:
        return np.zeros((Nl.shape[0], 0))
    A, C = model.A, model.C
    Bw, Dw = model.b("w"), model.d("w")
    Gw = Dw + (C @ np.linalg.solve(lam * np.eye(model.n) - A, Bw) if model.n else 0)
    return Nl[:, mu:] @ Gw


def _rank(M: np.ndarray, scale: float, tol: float = 1e-7) -> int:
    """Rank with singular values below ``tol · scale`` counted as zero (``scale``: the norms of the factors)."""
    if not M.size:
        return 0
    return int(np.sum(np.linalg.svd(M, compute_uv=False) > tol * scale))


def _candidates(k: int, q: int, degrees, selection=None):
    """``(used, H)`` pairs in the order of the reference's ``afdbasesel``: ``q`` rows alone, then more, combined."""
    if selection is not None:
        H = np.atleast_2d(np.asarray(selection, dtype=float))
        if H.shape != (q, k) or not np.all(np.isfinite(H)) or np.linalg.matrix_rank(H) < q:
            raise ParameterError(f"selection must be a finite ({q}, {k}) matrix of full row rank (the noise-"
                                 f"attenuating residuals from the {k} basis rows), got shape {H.shape}")
        yield tuple(range(k)), H
        return
    rng = np.random.default_rng(20170)
    for nout in range(q, k + 1):
        combos = sorted(itertools.combinations(range(k), nout),
                        key=lambda c: (sum(degrees[i] for i in c) if nout == q else q * max(degrees[i] for i in c)))
        H = np.eye(q) if nout == q else np.linalg.qr(rng.standard_normal((nout, q)))[0].T
        for used in combos:
            yield used, H


def _select(model, basis, targets, q, minimal, poles, sdeg, fdtol, fdfreq, fdgaintol, Nw, wscale, selection):
    """The first candidate that detects every target and keeps ``H R_w`` of rank ``q``: (used, H, A, B, C, D)."""
    dens_own = [denominator(nu, poles, sdeg, model.dt) for nu in basis.degrees]
    for used, H in _candidates(len(basis.rows), q, basis.degrees, selection):
        if _rank(H @ Nw[list(used)], wscale * np.linalg.norm(H, 2)) < q:
            continue
        if minimal:
            rows = basis.combined(H, used)
            d = max(basis.degrees[i] for i in used)
            dens = [denominator(d, poles, sdeg, model.dt)] * q
            # strong detectability over the default denominators, not the design's poles (the reference's sdegNS)
            chk = [denominator(d, None, None, model.dt)] * q
            S = row_structure(model, basis, targets, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, dens=chk,
                              rows=rows, by_frequency=True)
            if not covered(S).all():
                continue
            return used, H, realize_rows(rows, dens, basis.scale)
        chk_own = [denominator(nu, None, None, model.dt) for nu in basis.degrees]
        S = row_structure(model, basis, targets, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, dens=chk_own,
                          by_frequency=True)
        if not covered(S, used).all():
            continue
        A, B, C, D = realize_rows([basis.rows[i] for i in used], [dens_own[i] for i in used], basis.scale)
        return used, H, (A, B, H @ C, H @ D)
    raise DesignError(f"no combination of {q} residual(s) from the {len(basis.rows)} basis rows (degrees "
                      f"{list(basis.degrees)}) detects every target {list(targets)} with a noise part of full row "
                      f"rank {q}; lower rdim or check fdigenspec")


def _gap_selection(model, basis, target, minimal, poles, sdeg, fdfreq) -> np.ndarray:
    """The combination ``h`` of all basis rows with the largest gap of one residual for one target at one frequency.

    For one residual the noise factor and the stabilisation are scalar factors, so the final gap at ``λ₀`` is
    ``|h a| / ‖h W‖`` with ``a = R_f(λ₀) e_j`` and ``W = R_w(λ₀)`` of the rows as they are realised; over real ``h``
    that is the generalised Rayleigh quotient of ``(Re a a^H, Re W W^H)``, maximised by its top eigenvector.
    Written here: no library solves this quotient for a rank-2 numerator with real ``h``.
    """
    lam = frequency_points(fdfreq, model.dt)
    if lam.size != 1:
        raise ParameterError(f"selection='gap' optimises the gap at one frequency: give one fdfreq, got {fdfreq}")
    k = len(basis.rows)
    if minimal:
        rows = basis.combined(np.eye(k), range(k))
        dens = [denominator(max(basis.degrees), poles, sdeg, model.dt)] * k
    else:
        rows, dens = basis.rows, [denominator(nu, poles, sdeg, model.dt) for nu in basis.degrees]
    form = _gen(*realize_rows(rows, dens, basis.scale), model, tuple(f"r{i}" for i in range(k))).internal_form(model)
    cols = FaultModel(form.A, form.C, Bf=np.hstack([form.b("f")[:, [form.faults.index(target)]], form.b("w")]),
                      Df=np.hstack([form.d("f")[:, [form.faults.index(target)]], form.d("w")]), dt=model.dt)
    G = fault_response(cols, cols.faults, complex(lam[0]))
    a, W = G[:, 0], G[:, 1:]
    # Re(W W^H) = X Xᵀ, X = [Re W  Im W]; with X = U S Vᵀ and h = g S⁻¹ Uᵀ the quotient is ‖g Y‖²/‖g‖², Y = S⁻¹ Uᵀ
    # [Re a  Im a] (an SVD, not a Cholesky of X Xᵀ: the PATH sensors' noise levels are 5 decades apart)
    U, sv, _ = np.linalg.svd(np.hstack([W.real, W.imag]), full_matrices=False)
    if sv.size < k or sv[-1] <= 1e-9 * sv[0]:
        raise DesignError(f"a combination of the {k} basis rows decouples the noise at fdfreq={fdfreq}: the gap is "
                          "unbounded there; use rdim to add the noise-free residuals, or give a selection")
    T = U.T / sv[:, None]
    g = np.linalg.svd(T @ np.column_stack([a.real, a.imag]))[0][:, 0]
    h = g @ T
    return (h / np.linalg.norm(h))[None, :]


def _gen(A, B, C, D, model, names) -> ResidualGenerator:
    # TB01PD at its usual 1e-7 once reduced nine combined rows (PATH, selection="gap", minimal=False) to a wrong
    # second-order filter (response off by 4e-4, the controls no longer decoupled): keep a reduction only if it
    # keeps the response to 1e-9 at two test points, else reduce at 1e-10
    full = (A, B, C, D)
    for tol in (1e-7, 1e-10):
        A, B, C, D = minimal_realization(*full, tol=tol)
        if _same_response(full, (A, B, C, D), model.dt):
            break
    return ResidualGenerator(A, B, C, D, controls=model.controls, outputs=model.outputs, residuals=names,
                             dt=model.dt)


def _same_response(full, red, dt) -> bool:
    """Whether ``red`` has the response of ``full`` to 1e-9 (relative) at two points of the boundary (both stable)."""
    for w in (0.7, 3.1):
        lam = 1j * w if dt is None else np.exp(1j * w * min(dt, 1.0))
        g0, g1 = transfer(full, lam), transfer(red, lam)
        if np.linalg.norm(g0 - g1) > 1e-9 * max(np.linalg.norm(g0), 1e-300):
            return False
    return True


def _noise_free(model: FaultModel) -> FaultModel:
    """The model with its noise inputs moved to the disturbances (for the rows that decouple the noise too)."""
    return FaultModel(model.A, model.C, Bu=model.b("u"), Du=model.d("u"),
                      Bd=np.hstack([model.b("d"), model.b("w")]), Dd=np.hstack([model.d("d"), model.d("w")]),
                      Bf=model.b("f"), Df=model.d("f"), states=model.states, outputs=model.outputs,
                      controls=model.controls, disturbances=model.disturbances + model.noise, faults=model.faults,
                      dt=model.dt)


def _detectable(model: FaultModel, targets, nuisance, fdtol, fdfreq, fdgaintol, tol) -> tuple[str, ...]:
    """The targets some row of the basis decoupling ``nuisance`` detects (at each of ``fdfreq``)."""
    basis = left_nullspace(model, nuisance, tol=tol)
    S = row_structure(model, basis, targets, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, by_frequency=True,
                      dens=[denominator(nu, None, None, model.dt) for nu in basis.degrees])
    return tuple(t for t, hit in zip(targets, covered(S)) if hit)


def _nuisance_as_noise(model: FaultModel, nuisance) -> FaultModel:
    """The model with the fault inputs ``nuisance`` moved to the noise (the weak design of a structure row)."""
    keep = [i for i, f in enumerate(model.faults) if f not in nuisance]
    move = [model.faults.index(f) for f in nuisance]
    return FaultModel(model.A, model.C, Bu=model.b("u"), Du=model.d("u"), Bd=model.b("d"), Dd=model.d("d"),
                      Bf=model.b("f")[:, keep], Df=model.d("f")[:, keep],
                      Bw=np.hstack([model.b("w"), model.b("f")[:, move]]),
                      Dw=np.hstack([model.d("w"), model.d("f")[:, move]]), states=model.states,
                      outputs=model.outputs, controls=model.controls, disturbances=model.disturbances,
                      faults=[model.faults[i] for i in keep], noise=list(model.noise) + list(nuisance), dt=model.dt)


def afdsyn(model: FaultModel, *, targets=None, nuisance=(), rdim: int | None = None, minimal: bool = True,
           poles: Sequence[complex] | None = None, sdeg: float | None = None, gamma: float = 1.0,
           nonstd: str = "quasi", epsreg: float = 0.1, sdegzer: float | None = None, smarg: float | None = None,
           exact: bool = False, fdtol: float = 1e-4,
           fdgaintol: float = 0.01, fdfreq=None, selection=None, nullspace: bool = True, tol: float = 1e-9,
           names=None, isolates=None) -> ApproximateDesign:
    """Approximate fault detection filter by the nullspace method (Procedure AFD).

    Parameters
    ----------
    model : FaultModel
        The plant with controls ``u``, disturbances ``d``, fault inputs ``f`` and noise ``w``.
    targets, nuisance
        As :func:`~fdikit.design.nullspace.exact.efdsyn` (nuisance faults are decoupled exactly).
    rdim : int, optional
        Number of residuals (default 1 when ``minimal``, else all basis rows); the first ``min(rdim, rank R_w)``
        attenuate the noise and detect every target, the others decouple the noise and detect the targets they can.
    minimal : bool, default True
        Least order selection of the basis rows (as ``efdsyn``).
    poles, sdeg : optional
        The filter poles / stability degree of the basis denominators and of the zeros moved in the non-standard
        case (default −0.05, discrete 0.95).
    gamma : float, default 1
        ``‖R_w‖∞`` of the result.
    nonstd : {"quasi", "regularize", "wiener-hopf", "wiener-hopf-shift", "wiener-hopf-regularize"}, default "quasi"
        Non-standard case (``R_w`` with zeros at infinity or on the boundary), the reference's ``nonstd = 1 … 5``:
        the quasi factor with those zeros moved to the poles (1), the factor of ``[R_w εI]`` (2), and the
        Wiener–Hopf factor ``X`` of ``R_wo = X R`` (3), with ``R``'s zeros shifted by ``sdegzer`` (4) or ``R``
        regularised by ``epsreg`` (5): :mod:`~fdikit.design.nullspace.row_factors` for one residual of a
        continuous model, :mod:`~fdikit.design.nullspace.wiener_hopf` for several residuals or a discrete model.
        With several residuals or discrete, 1 is
        :func:`~fdikit.design.nullspace.factorization.quasi_coouter`.
    epsreg : float, default 0.1
        ``ε`` of the regularisations (``nonstd`` "regularize", "wiener-hopf-regularize").
    sdegzer : float, optional
        ``δ`` of the zero shift ("wiener-hopf-shift"), default −0.05 (discrete 0.95): boundary zeros ``jω₀`` move
        to ``(jω₀ + δ)/(1 + jω₀δ)`` (``δ`` for ``ω₀ = 0``; ``jω₀ + δ`` without infinite zeros), zeros at infinity
        to ``1/δ``; discrete ``z = ±1`` to ``±δ``.
    smarg : float, optional
        Stability margin (default ``−√ε``, discrete ``1 − √ε``): the internal form's poles beyond it are moved to
        ``poles``/``sdeg`` by a left coprime factor, and in the "quasi" case the zeros of the noise factor with real
        part at least ``smarg`` are moved too (by default only those on the boundary and at infinity).
    exact : bool, default False
        Solve the exact problem instead (``efdsyn`` ignoring the noise); the gap is still reported.
    selection : array_like or "gap", optional
        ``(q_1, k)`` combination of all ``k`` basis rows for the noise-attenuating residuals (reference
        ``HDesign``, in fdikit's basis coordinates); default the least-order search.  ``"gap"`` (not in the
        reference): for one residual and one target, the combination of all rows with the largest gap at the one
        frequency ``fdfreq`` — the noise factor of one residual is a scalar, so the gap there is
        ``|h a| / ‖h W‖`` (``a``, ``W``: the rows' fault and noise responses), a generalised Rayleigh quotient.
    fdtol, fdgaintol, fdfreq, nullspace, tol, names, isolates
        As :func:`~fdikit.design.nullspace.exact.efdsyn`; ``fdfreq`` also sets the frequencies of ``β``; with
        ``nullspace=False`` the plant poles at or beyond ``smarg`` are moved to ``poles``/``sdeg`` by the observer.

    Returns
    -------
    ApproximateDesign

    Raises
    ------
    DesignError
        No basis, a target that cannot be detected once ``u``, ``d`` and the nuisance faults are decoupled,
        ``rdim`` too large, a zero gap, or a non-standard case outside the implemented ones (the message says
        which).
    ParameterError
        Bad options.

    Examples
    --------
    Varga (2017), Example 5.6: ``Gu = [(s+1)/(s+2); (s+2)/(s+3)]``, ``Gw = [1/(s+2); 0]``,
    ``Gf = [(s+1)/(s+2) 0; 0 1]``; with ``sdeg = −3`` a first-order filter; its gap is at most the book's 3, which
    the best ``selection`` of the two basis rows reaches (``selection`` is in fdikit's basis coordinates, not the
    reference's ``HDesign`` ones, but the same on every machine):

    >>> m = FaultModel([[-2.0, 0, 0], [0, -3.0, 0], [0, 0, -2.0]], [[-1.0, 0, 1.0], [0, -1.0, 0]],
    ...                Bu=[[1.0], [1.0], [0.0]], Du=[[1.0], [1.0]], Bf=[[1.0, 0], [0, 0], [0, 0]],
    ...                Df=[[1.0, 0], [0, 1.0]], Bw=[[0.0], [0.0], [1.0]])
    >>> d = afdsyn(m, sdeg=-3.0)
    >>> d.order, np.round(d.poles.real, 6).tolist(), bool(0 < d.gap <= 3 + 1e-8)
    (1, [-3.0], True)

    References
    ----------
    Varga (2017), §5.3, Procedure AFD, Remark 5.8; fdtools (``afdsyn``, ``afdredsyn``).
    """
    from fdikit import validate
    from fdikit.analysis.channels import hinf_norm, minimal_channel
    from fdikit.analysis.performance import fdhinfminus, fdif2ngap
    from fdikit.design.labels import label_generator
    from fdikit.design.nullspace.stabilization import stabilize_rows
    from fdikit.residuals import stack_generators

    gamma = validate.positive("gamma", gamma)
    nonstd = validate.choice("nonstd", nonstd, NONSTD_OPTIONS)
    if not nullspace:
        from fdikit.design.nullspace.observer_basis import observer_reduction

        obs = observer_reduction(model, poles=poles, sdeg=sdeg, smarg=smarg)
        return obs.compose(afdsyn(obs.reduced, targets=targets, nuisance=nuisance, rdim=rdim, minimal=minimal,
                                  poles=poles, sdeg=sdeg, gamma=gamma, nonstd=nonstd, epsreg=epsreg,
                                  sdegzer=sdegzer, smarg=smarg, exact=exact, fdtol=fdtol, fdgaintol=fdgaintol,
                                  fdfreq=fdfreq, selection=selection, tol=tol, names=names, isolates=isolates),
                           model)
    targets, nuisance = split_faults(model, targets, nuisance)
    basis = left_nullspace(model, nuisance, tol=tol)
    k = len(basis.rows)
    if not k:
        raise DesignError(f"no residual is free of the controls, disturbances and nuisance faults {list(nuisance)}: "
                          f"[Gd Gn] has full row rank {len(model.outputs)}; the AFDP has no solution")
    lam = 1j * _TEST_FREQ if model.dt is None else np.exp(1j * _TEST_FREQ * model.dt)
    Nw = _noise_numerators(model, basis, lam)
    wscale = max(1.0, float(np.linalg.norm(basis.evaluate(lam), 2))) * max(1.0, float(np.linalg.norm(
        np.hstack([model.b("w").ravel(), model.d("w").ravel(), np.ones(1)]))))
    rw = _rank(Nw, wscale)

    def finish(gen, used, H, kind, shifted):
        gen = label_generator(gen, model, names, isolates)
        form = gen.internal_form(model)
        g = fdif2ngap(form, list(targets), fdfreq) if model.noise else None
        beta = float(g.beta) if g is not None else float(fdhinfminus(form, fdfreq, inputs=list(targets)).value)
        ratio, gam = (float(g.ratio), float(g.gamma)) if g is not None else (np.inf, 0.0)
        if not beta > 0:
            raise DesignError(f"the filter detects no fault: β = ‖R_f‖∞− = {beta:.3g} (γ = {gam:.3g}); the gap is 0")
        return ApproximateDesign(gen, basis, basis.degrees, H, tuple(used), gen.n, ratio, beta, gam, rw, kind,
                                 shifted, targets, nuisance,
                                 np.linalg.eigvals(gen.A) if gen.n else np.zeros(0, complex), model=model)

    if rw == 0 or exact:
        if isinstance(selection, str):
            raise ParameterError(f"selection={selection!r} weighs the noise; the design is exact here (no noise "
                                 "reaches the residuals, or exact=True): give a matrix or None")
        d = efdsyn(model, targets=targets, nuisance=nuisance, rdim=rdim, minimal=minimal, poles=poles, sdeg=sdeg,
                   fdtol=fdtol, fdgaintol=fdgaintol, fdfreq=fdfreq, selection=selection, tol=tol)
        return finish(d.generator, d.used, d.selection, "none", 0)
    if rdim is None:
        q1, q2 = (1, 0) if minimal else (rw, k - rw)
    else:
        q = validate.integer("rdim", rdim, minimum=1)
        if q > k:
            raise DesignError(f"rdim={q}: the nullspace basis has {k} rows, so 1 ≤ rdim ≤ {k}")
        q1, q2 = min(q, rw), q - min(q, rw)
    if isinstance(selection, str):
        validate.choice("selection", selection, ("gap",))
        free = [f for f in model.faults if f not in targets and f not in nuisance]
        if q1 != 1 or len(targets) != 1 or free:
            raise ParameterError(f"selection='gap' designs one noise-attenuating residual for one target with every "
                                 f"other fault decoupled; got {q1} residual(s), targets {list(targets)} and free "
                                 f"faults {free}: give one target, the others as nuisance, and rdim=1")
        selection = _gap_selection(model, basis, targets[0], minimal, poles, sdeg, fdfreq)
        # the optimum nearly cancels the noise away from fdfreq (PATH's wheel speeds: |h N_w| = 1e-7 against rows of
        # 2e-4 … 2e-3 at the test frequency): its rank is judged relative to the rows' own noise there, not in the
        # model's units (it is not decoupled at fdfreq, to 1e-9, by the selection's own test)
        wscale = float(np.linalg.norm(Nw, 2))
    used, H, (A, B, C, D) = _select(model, basis, targets, q1, minimal, poles, sdeg, fdtol, fdfreq, fdgaintol, Nw,
                                    wscale, selection)
    g1, _ = stabilize_rows(_gen(A, B, C, D, model, tuple(f"r{i}" for i in range(q1))), model, nuisance=nuisance,
                           poles=poles, sdeg=sdeg, smarg=smarg)
    g1, fac = attenuate_noise(g1, model, nonstd=nonstd, epsreg=epsreg, poles=poles, sdeg=sdeg, smarg=smarg,
                              sdegzer=sdegzer)
    wn = hinf_norm(minimal_channel(g1.internal_form(model), list(model.noise)))[0]
    if not (np.isfinite(wn) and wn > 0):
        raise DesignError(f"‖R_w‖∞ = {wn} after the factorisation; the filter is unstable or the noise vanished")
    g1 = dataclasses.replace(g1, C=(gamma / wn) * g1.C, D=(gamma / wn) * g1.D)
    gen = g1
    if q2:
        beta1 = float(fdhinfminus(g1.internal_form(model), fdfreq, inputs=list(targets)).value)
        # the noise-free residuals need not see every target (the first ones do): those they can (Example 5.9)
        t2 = _detectable(_noise_free(model), targets, nuisance, fdtol, fdfreq, fdgaintol, tol) or targets
        try:
            d2 = efdsyn(_noise_free(model), targets=t2, nuisance=nuisance, rdim=q2, minimal=minimal,
                        poles=poles, sdeg=sdeg, fdtol=fdtol, fdgaintol=fdgaintol, fdfreq=fdfreq, tol=tol)
        except DesignError as err:
            raise DesignError(f"rdim={q1 + q2}: the {q2} residual(s) that decouple the noise are not available: "
                              f"{err}") from err
        g2 = d2.generator
        rf = hinf_norm(minimal_channel(g2.internal_form(_noise_free(model)), list(targets)))[0]
        g2 = dataclasses.replace(g2, C=(gamma * beta1 / rf) * g2.C, D=(gamma * beta1 / rf) * g2.D,
                                 residuals=tuple(f"r{q1 + i}" for i in range(q2)))
        gen = stack_generators([g1, g2])
    return finish(gen, used, H, fac.kind, fac.shifted)


@dataclass(frozen=True, eq=False)
class ApproximateBankDesign(FieldReport):
    """A bank of approximate filters, one per row of a structure matrix (``afdisyn``).

    Attributes
    ----------
    generator : ResidualGenerator
        The stacked bank; residual ``r<i>`` (or ``r<i>_<k>``) belongs to row ``i``.
    filters : tuple of ApproximateDesign
        One design per row of ``specification``.
    specification : numpy.ndarray
        The structure matrix asked for.
    faults : tuple of str
        Its columns.
    groups : tuple of tuple of str
        The residual names of each filter.
    orders : tuple of int
        The order of each filter.
    gaps : numpy.ndarray
        The gap of each filter (reference ``info.gap``).
    weak : tuple of bool
        Rows whose strong design failed and whose filter treats the row's zeros as noise (the reference's weak
        AFDIP).

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2), Dw=[[0.1], [0.0]])
    >>> afdisyn(m, np.eye(2)).groups
    (('r0',), ('r1',))

    References
    ----------
    Varga (2017), §5.5, Procedure AFDI; fdtools (``afdisyn``).
    """

    generator: ResidualGenerator
    filters: tuple[ApproximateDesign, ...]
    specification: np.ndarray
    faults: tuple[str, ...]
    groups: tuple[tuple[str, ...], ...]
    orders: tuple[int, ...]
    gaps: np.ndarray
    weak: tuple[bool, ...]

    REPORT = ("specification", "faults", "groups", "orders", "gaps", "weak")


def afdisyn(model: FaultModel, structure, *, faults=None, rdim: int | Sequence[int] | None = None,
            weak_fallback: bool = True,
            **options) -> ApproximateBankDesign:
    """A bank of approximate fault detection filters for the structure matrix ``structure`` (Procedure AFDI).

    Parameters
    ----------
    model : FaultModel
        The plant.
    structure : array_like of bool
        ``S``: row ``i`` asks for a filter that detects the faults of its ones, decouples those of its zeros
        exactly and attenuates the noise.
    faults : sequence of str, optional
        The columns of ``S`` (default the model's fault inputs).
    rdim : int or sequence of int, optional
        Residuals per filter, or one number per row.
    weak_fallback : bool, default True
        When a row's strong design fails (its zeros cannot be decoupled, or a target is then not detected),
        design it again with the row's zeros as noise, with a :class:`~fdikit.errors.FdiWarning` (as the reference
        does; its ``R_f`` columns of those faults are then attenuated, not zero).  False: raise instead.
    **options
        ``minimal``, ``poles``, ``sdeg``, ``gamma``, ``nonstd``, ``epsreg``, ``sdegzer``, ``smarg``, ``exact``,
        ``fdtol``, ``fdgaintol``, ``fdfreq``, ``nullspace``, ``tol``: as :func:`afdsyn`, for every row.

    Returns
    -------
    ApproximateBankDesign

    Raises
    ------
    DesignError
        A row that cannot be achieved, weakly either (the row and the reason).
    ParameterError
        A malformed ``structure`` or an unknown option.

    Examples
    --------
    Varga (2017), Example 5.11: the plant of Example 5.6 with ``S = I``; gaps 3 and ∞.

    >>> m = FaultModel([[-2.0, 0, 0], [0, -3.0, 0], [0, 0, -2.0]], [[-1.0, 0, 1.0], [0, -1.0, 0]],
    ...                Bu=[[1.0], [1.0], [0.0]], Du=[[1.0], [1.0]], Bf=[[1.0, 0], [0, 0], [0, 0]],
    ...                Df=[[1.0, 0], [0, 1.0]], Bw=[[0.0], [0.0], [1.0]])
    >>> np.round(afdisyn(m, np.eye(2), sdeg=-3.0).gaps, 6).tolist()
    [3.0, inf]

    References
    ----------
    Varga (2017), §5.5, Procedure AFDI; fdtools (``afdisyn``).
    """
    allowed = {"minimal", "poles", "sdeg", "gamma", "nonstd", "epsreg", "sdegzer", "smarg", "exact", "fdtol",
               "fdgaintol", "fdfreq", "nullspace", "tol"}
    bad = sorted(set(options) - allowed)
    if bad:
        raise ParameterError(f"unknown option(s) {bad}; afdisyn takes {sorted(allowed)}")
    weak = []

    def design(tg, nz, rdim):
        try:
            d = afdsyn(model, targets=tg, nuisance=nz, rdim=rdim, **options)
        except DesignError as err:
            if not (weak_fallback and nz):
                raise
            warnings.warn(f"afdisyn: the strong design detecting {list(tg)} failed ({err}); the faults {list(nz)} "
                          "are treated as noise (weak design)", FdiWarning, stacklevel=4)
            weak.append(True)
            return afdsyn(_nuisance_as_noise(model, nz), targets=tg, rdim=rdim, **options)
        weak.append(False)
        return d

    S, faults, filters, gen = bank_rows(model, structure, faults, design, rdim=rdim)
    return ApproximateBankDesign(gen, filters, S, faults, tuple(tuple(f.generator.residuals) for f in filters),
                                 tuple(f.order for f in filters), np.array([f.gap for f in filters]), tuple(weak),
                                 model=model)
