"""Exact model matching by the nullspace method: ``emmsyn`` (Varga 2017, §5.6, Procedures EMM and EMMS).

The exact model-matching problem (EMMP) asks for a proper stable filter ``Q`` on ``[u; y]`` whose internal form
equals an updated reference model:

    Q(λ) G_e(λ) = M(λ) M_r(λ),     G_e = [ Gu Gd Gf Gw ]
                                          [ I  0  0  0 ]

with ``M`` diagonal, proper, stable and invertible, of least degree, chosen so that ``Q`` is proper and stable
(Varga 2017, §5.6).  With ``M_r = I`` from the faults this is fault estimation.  Groups the
reference lacks are matched to zero (controls, disturbances, faults: decoupled), except the noise, which is left
free when ``M_r`` has no noise group (its channel ``Q [Gw; 0]`` is then part of the internal form).

How fdikit solves it, one residual ``i`` at a time.  Row ``i`` of the equation, ``n(λ) G_e = m(λ) M_r,i`` with
``Q_i = n / φ`` and ``M_i = m / φ``, says that the polynomial vector ``[n, −m]`` lies in the left nullspace of the
model with the reference row appended as an output: outputs ``[y; r_i]``, inputs decoupled ``(d, f[, w])``.
Its minimal polynomial basis is :func:`~fdikit.design.nullspace.basis.left_nullspace`; by the predictable-degree
property of minimal bases the least degree ``k`` of a solution with ``m ≢ 0`` is the least degree of a basis row
with ``m ≢ 0``, and the least order of any proper ``Q_i`` is that ``k`` (``Q_i = n / φ`` has order ``deg φ ≥
max(deg n, deg m)``).  fdikit takes, among the solutions of degree ``k``, the one orthogonal (in the scaled
coefficients) to those with ``m = 0`` — the free part ``Q_i + X`` with ``X G_e = 0`` that the reference fixes by
its own basis selection — so when the solution is unique (no ``X``) it is the reference's.  Then
``m = c m_s m_u`` splits into the roots inside ``smarg`` (kept: stable poles of ``Q̃_i = n / m``) and the others,
and the least-degree factor is

    M_i = m_u(λ) / ψ(λ),   deg ψ = deg m_u + (k − deg m),   Q_i = n / (c ψ m_s)

(the unstable and the infinite poles of ``Q̃_i`` moved to ``poles``/``sdeg``; the reference's ``glcf`` with
``mininf`` and ``mindeg`` on a descriptor realisation of ``Q̃_i``), order ``k``, scaled by ``normalize``.

Why by hand: no Python library solves rational matrix equations or computes coprime factorisations with infinite
poles (the reference's ``glsol``/``grsol``/``glcf`` on descriptor pencils); the polynomial-basis route needs only
the nullspace basis fdikit already computes and its row realisation.

References
----------
Varga (2017), §5.6 (EMMP, Procedures EMM and EMMS), §7.4 (minimal polynomial bases, predictable degree), §7.5
(coprime factorisation with least-degree denominators); Forney (1975); fdtools (``emmsyn``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.design.nullspace.basis import default_sdeg, denominator, left_nullspace, minimal_realization, realize_rows
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import GROUPS, FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["ModelMatchingDesign", "ModelMatchingBankDesign", "emmsyn", "NORMALIZE_OPTIONS", "reference_model",
           "updated_reference", "reference_columns", "reference_bank"]

NORMALIZE_OPTIONS = ("gain", "dcgain", "infnorm")
_GROUP_KW = {"u": "controls", "d": "disturbances", "f": "faults", "w": "noise"}


@dataclass(frozen=True, eq=False)
class ModelMatchingDesign(FieldReport):
    """An exact model-matching filter (``emmsyn``) and its report.

    Attributes
    ----------
    generator : ResidualGenerator
        The filter ``Q`` (inputs ``[u; y]``), one residual per output of the reference, stable and proper.
    target : FaultModel
        The updated reference ``M M_r`` (the reference's groups): ``Q G_e = M M_r`` on the matched groups.
    updating : tuple of (numpy.ndarray, numpy.ndarray)
        ``M_i = num / den`` per residual, coefficients in ``λ`` (``s`` or ``z``), highest power first.
    orders : tuple of int
        The order of each residual's filter row (the least order ``k_i``); the filter order is their sum.
    reference : FaultModel
        The reference model ``M_r`` asked for.
    matched : tuple of str
        The groups matched: ``u``, ``d``, ``f`` always (a group ``M_r`` lacks is matched to zero), ``w`` when
        ``M_r`` has noise inputs.
    poles : numpy.ndarray
        The filter eigenvalues.

    Examples
    --------
    Fault estimation for a sensor fault of a two-sensor plant: ``M_r = 1`` from ``f``.

    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=[[0.0], [1.0]])
    >>> d = emmsyn(m, {"f": [[1.0]]})
    >>> d.orders, [np.round(num, 9).tolist() for num, _ in d.updating]
    ((0,), [[1.0]])

    References
    ----------
    Varga (2017), §5.6, Procedure EMM; fdtools (``emmsyn``).
    """

    generator: ResidualGenerator
    target: FaultModel
    updating: tuple[tuple[np.ndarray, np.ndarray], ...]
    orders: tuple[int, ...]
    reference: FaultModel
    matched: tuple[str, ...]
    poles: np.ndarray

    REPORT = ("orders", "updating", "matched", "poles")


@dataclass(frozen=True, eq=False)
class ModelMatchingBankDesign(FieldReport):
    """A bank of model-matching filters, one per reference model (``emmsyn`` or ``ammsyn`` with a sequence).

    Attributes
    ----------
    generator : ResidualGenerator
        The stacked bank (``residuals.stack_generators``).
    filters : tuple of ModelMatchingDesign or ApproximateMatchingDesign
        One design per reference (``emmsyn`` or ``ammsyn``).
    groups : tuple of tuple of str
        The residual names of each filter (for ``ThresholdEvaluator(groups=...)``).
    orders : tuple of int
        The order of each filter.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> emmsyn(m, [{"f": [[1.0, 0.0]]}, {"f": [[0.0, 1.0]]}]).groups
    (('r0',), ('r1',))

    References
    ----------
    Varga (2017), §5.6; fdtools (``emmsyn`` with a bank of reference models).
    """

    generator: ResidualGenerator
    filters: tuple
    groups: tuple[tuple[str, ...], ...]
    orders: tuple[int, ...]

    REPORT = ("groups", "orders")


def reference_model(model: FaultModel, ref, names: Sequence[str] | None = None) -> FaultModel:
    """A reference model ``M_r`` as a FaultModel checked against ``model``: groups absent or in full, same ``dt``.

    Parameters
    ----------
    model : FaultModel
        The plant.
    ref : FaultModel or mapping
        An internal form, or a static ``{group: matrix}`` (:func:`~fdikit.analysis.performance.static_reference`).
    names : sequence of str, optional
        Residual names, checked against the number of outputs.

    Returns
    -------
    FaultModel

    Raises
    ------
    ParameterError, ModelError
        A reference that is neither, group sizes or a sample time that do not fit the model.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> reference_model(m, {"f": [[1.0, 0.0]]}).p
    1

    References
    ----------
    Varga (2017), §5.6 (the reference model); fdtools (``emmsyn``, ``ammsyn``: the input groups of ``sysr``).
    """
    from fdikit.analysis.performance import static_reference

    if isinstance(ref, Mapping):
        if not ref:
            raise ParameterError("the static reference is empty; give {group: matrix}, e.g. {'f': np.eye(mf)}")
        rows = {np.atleast_2d(np.asarray(v, dtype=float)).shape[0] for v in ref.values()}
        if len(rows) != 1:
            raise ParameterError(f"the matrices of the static reference have different row counts {sorted(rows)}")
        ref = static_reference(ref, model, p=rows.pop())
    if not isinstance(ref, FaultModel):
        raise ParameterError(f"the reference must be a FaultModel or a mapping {{group: matrix}}, got "
                             f"{type(ref).__name__}")
    if (ref.dt is None) != (model.dt is None) or (ref.dt is not None and not np.isclose(ref.dt, model.dt)):
        raise ModelError(f"the reference has dt={ref.dt}, the model dt={model.dt}; give both the same sample time")
    for g in GROUPS:
        k, kr = len(model.inputs[g]), len(ref.inputs[g])
        if kr and kr != k:
            raise ModelError(f"the reference has {kr} inputs in group {g!r}, the model {k}; give the group in full "
                             "or leave it out (matched to zero, or free for the noise)")
    if names is not None and len(tuple(names)) != ref.p:
        raise ParameterError(f"{len(tuple(names))} residual names for a reference with {ref.p} outputs")
    return ref


def reference_columns(ref: FaultModel, model: FaultModel, groups: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(B, D)`` of the reference for the model's input ``groups``: zero columns for a group the reference lacks.

    Parameters
    ----------
    ref : FaultModel
        ``M_r`` (:func:`reference_model`).
    model : FaultModel
        The plant (the group sizes).
    groups : sequence of str
        Groups among ``'u', 'd', 'f', 'w'``, in order.

    Returns
    -------
    tuple of numpy.ndarray

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> B, D = reference_columns(reference_model(m, {"f": [[1.0, 0.0]]}), m, ("u", "f"))
    >>> D.tolist()
    [[0.0, 1.0, 0.0]]

    References
    ----------
    Varga (2017), §5.6; fdtools (``emmsyn``: "if any of the above vectors is void, the corresponding transfer
    function matrix is considered null").
    """
    Bs, Ds = [], []
    for g in groups:
        k = len(model.inputs[g])
        has = bool(len(ref.inputs[g]))
        Bs.append(ref.b(g) if has else np.zeros((ref.n, k)))
        Ds.append(ref.d(g) if has else np.zeros((ref.p, k)))
    return np.hstack(Bs).reshape(ref.n, -1), np.hstack(Ds).reshape(ref.p, -1)


def _augmented(model: FaultModel, ref: FaultModel, row: int, match_noise: bool) -> FaultModel:
    """The plant with reference row ``row`` appended as the last output; the matched inputs as faults."""
    import scipy.linalg

    A = scipy.linalg.block_diag(model.A, ref.A)
    C = scipy.linalg.block_diag(model.C, ref.C[row:row + 1])
    kw: dict = {}
    for g in GROUPS:
        Br, Dr = reference_columns(ref, model, (g,))
        kw[g] = (np.vstack([model.b(g), Br]), np.vstack([model.d(g), Dr[row:row + 1]]))
    fault_groups = ("f", "w") if match_noise else ("f",)
    Bf = np.hstack([kw[g][0] for g in fault_groups])
    Df = np.hstack([kw[g][1] for g in fault_groups])
    faults = sum((model.inputs[g] for g in fault_groups), ())
    return FaultModel(A, C, Bu=kw["u"][0], Du=kw["u"][1], Bd=kw["d"][0], Dd=kw["d"][1], Bf=Bf, Df=Df,
                      controls=model.controls, disturbances=model.disturbances, faults=faults,
                      outputs=model.outputs + ("__reference__",), dt=model.dt)


def _least_solution(basis, tol: float) -> np.ndarray:
    """The solution ``[n, −m]`` of least degree with ``m ≢ 0``, orthogonal to those with ``m = 0``: ``(k+1, L)``."""
    last = basis.rows[0].shape[1] - 1 if basis.rows else 0
    with_m = [j for j, r in enumerate(basis.rows) if np.linalg.norm(r[:, last]) > tol]
    if not with_m:
        raise DesignError("the reference is not achievable: no proper Q gives Q G_e = M M_r (the rank of "
                          "[G_e; M_r] exceeds that of G_e: the reference asks for a signal the outputs do not carry, "
                          "or for a nonzero response to a decoupled input)")
    k = min(basis.degrees[j] for j in with_m)
    shifts = []
    for j, r in enumerate(basis.rows):
        d = basis.degrees[j]
        for i in range(k - d + 1):
            v = np.zeros((k + 1, r.shape[1]))
            v[i:i + d + 1] = r
            shifts.append(v.ravel())
    P = np.linalg.qr(np.array(shifts).T)[0].T                     # orthonormal rows spanning degree-k solutions
    Pm = P.reshape(len(P), k + 1, -1)[:, :, last]
    U = np.linalg.svd(Pm)[0]
    return (U[:, 0] @ P).reshape(k + 1, -1)                      # largest m part: orthogonal to the m = 0 ones


def _is_stable_root(lam: np.ndarray, dt, smarg: float) -> np.ndarray:
    return lam.real < smarg if dt is None else np.abs(lam) < smarg


def _row_filter(v: np.ndarray, scale: float, dt, poles, sdeg, smarg: float, tol: float):
    """``Q_i`` and ``M_i = m_u / ψ`` from the solution ``v = [n, −m]`` (coefficients in ``μ = λ / scale``)."""
    k = v.shape[0] - 1
    n, m = v[:, :-1], -v[:, -1]
    dm = int(np.flatnonzero(np.abs(m) > tol * np.max(np.abs(v)))[-1])
    c = m[dm]
    roots = scale * np.roots(m[: dm + 1][::-1]) if dm else np.zeros(0, dtype=complex)
    good = _is_stable_root(roots, dt, smarg)
    m_s, m_u = (np.atleast_1d(np.poly(roots[sel]).real) for sel in (good, ~good))
    psi = denominator(int(np.sum(~good)) + k - dm, poles, sdeg, dt)
    A, B, C, D = realize_rows([n * scale ** (dm - k) / c], [np.polymul(psi, m_s)], scale)   # it realises α^k N / φ
    return (A, B, C, D), m_u, psi


def _normalizer(num: np.ndarray, den: np.ndarray, dt, normalize: str) -> float:
    """The scaling ``sc`` of ``M_i`` (``normalize``): 1 (unit zpk gain), its DC gain, or its H∞ norm."""
    if normalize == "gain":
        return 1.0
    if normalize == "dcgain":
        lam0 = 0.0 if dt is None else 1.0
        sc = np.polyval(num, lam0) / np.polyval(den, lam0)
        if not abs(sc) > 1e-12:
            raise DesignError(f"normalize='dcgain' is impossible: the updating factor {num.tolist()} / "
                              f"{den.tolist()} vanishes at DC (the filter would have an unstable pole there); "
                              "use normalize='gain' or 'infnorm'")
        return float(sc)
    from fdikit.analysis.channels import Channel, hinf_norm

    return float(hinf_norm(Channel(*_siso(num, den), dt))[0])


def _siso(num: np.ndarray, den: np.ndarray):
    """A realisation of ``num / den`` (proper, ``den`` monic, both highest power first): ``realize_rows`` in ``λ``."""
    N = np.zeros((len(den), 1))
    N[: len(num), 0] = num[::-1]
    return realize_rows([N], [den], 1.0)


def updated_reference(ref: FaultModel, updating) -> FaultModel:
    """The updated reference ``diag(M_i) M_r`` in the reference's groups.

    Parameters
    ----------
    ref : FaultModel
        ``M_r``.
    updating : sequence of (numpy.ndarray, numpy.ndarray)
        ``M_i = num / den`` per output, proper, coefficients highest power first.

    Returns
    -------
    FaultModel

    Examples
    --------
    >>> ref = FaultModel([[-1.0]], [[0.0]], Df=[[2.0]])
    >>> T = updated_reference(ref, [(np.array([1.0]), np.array([1.0, 3.0]))])     # 2/(s+3)
    >>> round(float((T.C @ np.linalg.solve(-T.A, T.b("f")) + T.d("f"))[0, 0]), 9)
    0.666666667

    References
    ----------
    Varga (2017), §5.6 (the updating factor ``M``); fdtools (``info.M * sysr``).
    """
    import scipy.linalg

    from fdikit.design.nullspace.factorization import series

    blocks = [_siso(num, den) for num, den in updating]
    M = (scipy.linalg.block_diag(*[b[0] for b in blocks]), scipy.linalg.block_diag(*[b[1] for b in blocks]),
         scipy.linalg.block_diag(*[b[2] for b in blocks]), scipy.linalg.block_diag(*[b[3] for b in blocks]))
    n_m = M[0].shape[0]
    M = (M[0], M[1].reshape(n_m, len(blocks)), M[2].reshape(len(blocks), n_m), M[3])
    A, B, C, D = series((ref.A, ref.B, ref.C, ref.D), M)
    kw: dict = {}
    start = 0
    for g in GROUPS:
        k = len(ref.inputs[g])
        kw[f"B{g}"], kw[f"D{g}"], kw[_GROUP_KW[g]] = B[:, start:start + k], D[:, start:start + k], ref.inputs[g]
        start += k
    return FaultModel(A, C, outputs=ref.outputs, dt=ref.dt, **kw)


def _check(model: FaultModel, gen: ResidualGenerator, target: FaultModel, groups) -> None:
    """Raise when ``Q G_e − M M_r`` is not zero to rounding at three points (a rank decision failed)."""
    from fdikit.design.nullspace.factorization import transfer

    alpha = max(1.0, float(np.linalg.norm(model.A, 2))) if model.n else 1.0
    Bg, Dg = np.hstack([model.b(g) for g in groups]), np.hstack([model.d(g) for g in groups])
    Eu = np.hstack([np.eye(len(model.controls)) if g == "u" else np.zeros((len(model.controls), len(model.inputs[g])))
                    for g in groups])
    Bt, Dt = reference_columns(target, model, groups)
    worst = 0.0
    for lam in (0.7 + 0.7j, 1j * np.sqrt(alpha), alpha * (0.6 + 0.8j)):
        Q = transfer((gen.A, gen.B, gen.C, gen.D), lam)
        G = np.vstack([Eu, transfer((model.A, Bg, model.C, Dg), lam)])    # the generator reads [u; y]
        T = transfer((target.A, Bt, target.C, Dt), lam)
        scale = np.linalg.norm(Q, 2) * np.linalg.norm(G, 2) + np.linalg.norm(T, 2)
        worst = max(worst, float(np.linalg.norm(Q @ G - T, 2) / max(scale, 1e-300)))
    if worst > 1e-6:
        raise DesignError(f"the model-matching filter fails its check: |Q G_e − M M_r| is {worst:.1e} of the terms "
                          "(a rank decision of the least-degree solution failed, typically for a reference of high "
                          "order or with widely spread poles; reduce the reference (minimal, balanced realisation) "
                          "or change tol)")


def _single(model: FaultModel, ref: FaultModel, names, poles, sdeg, smarg, normalize, tol) -> ModelMatchingDesign:
    match_noise = bool(len(ref.inputs["w"]))
    rows, Ms, orders = [], [], []
    for i in range(ref.p):
        aug = _augmented(model, ref, i, match_noise)
        basis = left_nullspace(aug, aug.faults)
        v = _least_solution(basis, tol)
        (A, B, C, D), num, den = _row_filter(v, basis.scale, model.dt, poles, sdeg, smarg, tol)
        sc = _normalizer(num, den, model.dt, normalize)
        rows.append((A, B, C / sc, D / sc))
        Ms.append((num / sc, den))
        orders.append(v.shape[0] - 1)
    import scipy.linalg

    A = scipy.linalg.block_diag(*[r[0] for r in rows])
    nq, mq = A.shape[0], rows[0][1].shape[1]
    B = np.vstack([r[1] for r in rows]).reshape(nq, mq)
    C = scipy.linalg.block_diag(*[r[2] for r in rows]).reshape(ref.p, nq)
    D = np.vstack([r[3] for r in rows])
    A, B, C, D = minimal_realization(A, B, C, D)
    gen = ResidualGenerator(A, B, C, D, controls=model.controls, outputs=model.outputs,
                            residuals=tuple(ref.outputs if names is None else names), dt=model.dt)
    matched = ("u", "d", "f", "w") if match_noise else ("u", "d", "f")
    target = updated_reference(ref, Ms)
    _check(model, gen, target, matched)
    return ModelMatchingDesign(gen, target, tuple(Ms), tuple(orders), ref, matched,
                               np.linalg.eigvals(A) if A.size else np.zeros(0), model=model)


def reference_bank(model: FaultModel, references, names, synthesize) -> ModelMatchingBankDesign:
    """A bank: ``synthesize(reference, names)`` per reference, residual ``i`` of filter ``j`` named ``r<j>_<i>``.

    Parameters
    ----------
    model : FaultModel
        The plant.
    references : sequence
        The references (FaultModels or static mappings).
    names : None
        Must be None (a bank names its residuals).
    synthesize : callable
        ``(reference, names) -> design`` with a ``generator``.

    Returns
    -------
    ModelMatchingBankDesign

    Raises
    ------
    ParameterError
        ``names`` given, or an empty bank.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> bank = reference_bank(m, [{"f": [[1.0, 0.0]]}], None, lambda r, nm: emmsyn(m, r, names=nm))
    >>> bank.groups
    (('r0',),)

    References
    ----------
    Varga (2017), §5.6; fdtools (``emmsyn``/``ammsyn`` with a bank of reference models).
    """
    from fdikit.residuals import stack_generators

    if names is not None:
        raise ParameterError("names is for one reference; a bank names residual i of filter j r<j>_<i>")
    if not references:
        raise ParameterError("the bank of references is empty")
    filters = []
    for j, r in enumerate(references):
        p = reference_model(model, r).p
        filters.append(synthesize(r, (f"r{j}",) if p == 1 else tuple(f"r{j}_{i}" for i in range(p))))
    gen = stack_generators([f.generator for f in filters])
    return ModelMatchingBankDesign(gen, tuple(filters), tuple(tuple(f.generator.residuals) for f in filters),
                                   tuple(f.generator.n for f in filters), model=model)


def emmsyn(model: FaultModel, reference, *, names: Sequence[str] | None = None,
           poles: Sequence[complex] | None = None, sdeg: float | None = None, smarg: float | None = None,
           normalize: str = "gain", tol: float = 1e-7) -> ModelMatchingDesign | ModelMatchingBankDesign:
    """Exact model matching, least order per residual: ``Q G_e = M M_r`` (Procedures EMM/EMMS).

    Parameters
    ----------
    model : FaultModel
        The plant (continuous or discrete).
    reference : FaultModel, mapping, or a sequence of them
        ``M_r``: an internal form with one output per residual and the model's input groups (a group it lacks is
        matched to zero; noise then stays free), or a static ``{group: matrix}`` (``{"f": np.eye(mf)}``: fault
        estimation).  A sequence gives a bank, one filter per reference.
    names : sequence of str, optional
        Residual names (default the reference's output names; ``r<i>`` for static ones).  Not with a bank.
    poles : sequence of complex, optional
        Poles of ``M_i`` (the first ones the row needs); default all at ``sdeg``.
    sdeg : float, optional
        Default −0.05 (continuous) or 0.95 (discrete), as the reference's.
    smarg : float, optional
        The stability margin: poles of the exact solution ``Q̃_i`` with ``Re λ < smarg`` (``|λ| < smarg``) are kept,
        the others moved; default ``−√ε`` (``1 − √ε``).
    normalize : {'gain', 'dcgain', 'infnorm'}, default 'gain'
        ``M_i`` scaled to unit zero-pole gain, unit DC gain or unit H∞ norm (reference ``normalize``).
    tol : float, default 1e-7
        Threshold of a nonzero reference coefficient in the unit-norm solution (reference ``atol``).

    Returns
    -------
    ModelMatchingDesign or ModelMatchingBankDesign

    Raises
    ------
    DesignError
        When the reference is not achievable, or ``normalize='dcgain'`` meets an ``M_i`` that vanishes at DC.
    ParameterError, ModelError
        A malformed reference, group sizes or sample time that do not fit the model, bad options.

    Examples
    --------
    Estimating an actuator fault from two sensors of ``1/(s+1)``: the exact estimate ``f̂ = M f`` needs the
    inverse of the plant, so ``M = 1/(s + 0.05)`` makes it proper (order 1):

    >>> m = FaultModel([[-1.0]], [[1.0], [2.0]], Bu=[[1.0]], Bf=[[1.0]])
    >>> d = emmsyn(m, {"f": [[1.0]]})
    >>> d.orders, [np.round(den, 9).tolist() for _, den in d.updating]
    ((1,), [[1.0, 0.05]])

    References
    ----------
    Varga (2017), §5.6, Procedures EMM and EMMS; fdtools (``emmsyn``).
    """
    if normalize not in NORMALIZE_OPTIONS:
        raise ParameterError(f"normalize must be one of {NORMALIZE_OPTIONS}, got {normalize!r}")
    if not (np.isfinite(tol) and 0 < tol < 1):
        raise ParameterError(f"tol must be in (0, 1), got {tol}")
    dt = model.dt
    if smarg is None:
        smarg = -np.sqrt(np.finfo(float).eps) if dt is None else 1 - np.sqrt(np.finfo(float).eps)
    denominator(1, None, default_sdeg(dt) if sdeg is None else sdeg, dt)          # checks sdeg
    opts = dict(poles=poles, sdeg=sdeg, smarg=float(smarg), normalize=normalize, tol=tol)
    if isinstance(reference, (list, tuple)):
        return reference_bank(model, reference, names,
                              lambda r, nm: _single(model, reference_model(model, r), nm, **opts))
    ref = reference_model(model, reference, names)
    if names is None and isinstance(reference, Mapping):
        names = tuple(f"r{i}" for i in range(ref.p))
    return _single(model, ref, names, **opts)
