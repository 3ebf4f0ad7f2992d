"""Performance metrics of fault detection filters: H∞− index, sensitivity condition, fault-to-noise gap, model matching.

All functions take the *internal form* of a filter — a :class:`~fdikit.model.FaultModel` from
``(u, d, f, w)`` to the residuals (``ResidualGenerator.internal_form(model)``), or a design result
whose ``internal_form()`` is used — or a *bank* of filters: a sequence or mapping of internal forms,
or one internal form with ``groups=`` (the residuals of each filter; :func:`~fdikit.analysis.channels.internal_forms`).
``R_f`` and ``R_w`` are the channels from the fault (group ``f``) and noise (group ``w``) inputs.
The definitions are those of Varga (2017) and FaultDetectionTools.jl:

* :func:`fdhinfminus` — the **H∞− index** ``‖G‖∞− = min_j ‖g_j‖∞``, the smallest H∞ norm of a column
  (Varga's fault-sensitivity measure), or, at given frequencies, ``min_{j,k} ‖g_j(λ_k)‖₂``;
  :func:`fdhinfmax` the largest;
* :func:`fdiscond` — the **fault sensitivity condition** ``β/γ`` with ``β = ‖R_f‖∞−`` and
  ``γ = max_j ‖R_fj‖∞`` (``1`` when all faults are seen equally);
* :func:`fdif2ngap` — the **fault-to-noise gap** ``β/γ`` with ``β = ‖R_ff‖∞−`` of the faults to detect
  and ``γ = ‖[R_fd R_w]‖∞`` of the rest and the noise (``∞`` when ``γ = 0``);
* :func:`fdimmperf` — **model-matching performance** ``‖R_w‖``, ``‖[R_fd R_w]‖`` or ``‖R − M_r‖``
  in the H∞ or H2 norm;
* :func:`~fdikit.analysis.hminus.hminus_index` — the classical **H− index** ``inf_ω σ_m(G(λ(ω)))``
  (``m`` columns), which the reference does not compute; no library provides it, so it is a
  frequency search (module :mod:`fdikit.analysis.hminus` states the search and its tolerance).

H∞ norms are python-control's ``linfnorm`` (SLICOT AB13DD, relative tolerance ``1e-10``), H2 norms a
Lyapunov solve, both on the minimal realisation of the channel (the plant's own modes sit in the
internal form, cancelled by the filter).  ``spec`` (Varga's ``SFDI``) selects the faults each filter
must detect: fault names or a boolean vector (one filter), a boolean ``rows × faults`` matrix, a
:class:`~fdikit.analysis.structure.StructureMatrix`, or a fault × group DataFrame as
:func:`~fdikit.analysis.structure_matrix` returns.

References
----------
Varga (2017), §3.3 (fault sensitivity, the H∞− index), §5.3 (fault-to-noise gap, eq. (5.41)–(5.42)) and
§5.6 (model matching); fdtools (``fdhinfminus``, ``fdiscond``, ``fdif2ngap``, ``fdimmperf``).

Examples
--------
>>> from fdikit import FaultModel
>>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0, 3.0]], Bw=[[0.5]], faults=["f1", "f2"], noise=["w"])
>>> gap = fdif2ngap(R)                            # ‖·‖∞ of 1/(s+1), 3/(s+1) and 0.5/(s+1)
>>> round(gap.ratio, 9), round(gap.beta, 9), round(gap.gamma, 9)
(2.0, 1.0, 0.5)
>>> round(fdiscond(R).ratio, 9)
0.333333333
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.analysis.channels import (
    InternalForms,
    check_freqs,
    check_stable,
    frequency_response,
    h2_norm,
    hinf_norm,
    input_columns,
    internal_forms,
    minimal_channel,
)
from fdikit.errors import ModelError, ParameterError
from fdikit.model import GROUPS, FaultModel

__all__ = ["ColumnNorm", "NormRatio", "fdhinfminus", "fdhinfmax", "fdiscond", "fdif2ngap", "fdimmperf", "as_spec",
           "static_reference"]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class ColumnNorm:
    """An extreme column norm: its value, the input (column) and the frequency [rad/s] where attained.

    Attributes
    ----------
    value : float
        The norm.
    column : str or None
        The input whose column attains it (None when there is no column).
    freq : float
        The frequency [rad/s] where it is attained.

    Examples
    --------
    >>> value, column, freq = ColumnNorm(2.0, "f1", 0.0)
    >>> column
    'f1'
    """

    value: float
    column: str | None
    freq: float

    def __iter__(self):
        """``(value, column, freq)``, as the reference's ``(β, ind, fr)``."""
        return iter((self.value, self.column, self.freq))


@dataclass(frozen=True, eq=False)
class NormRatio:
    """A ratio ``β/γ`` and its terms (:func:`fdiscond`, :func:`fdif2ngap`).

    Attributes
    ----------
    ratio, beta, gamma : float or (N,) ndarray
        The ratio and its numerator and denominator; arrays (one entry per filter of a bank, or per
        residual for a ``rows × faults`` ``spec``), floats for one filter.
    names : tuple of str
        The filter or residual names of the entries (one name for a float result).

    Unpacks as ``ratio, beta, gamma`` (the reference's ``(gap, β, γ)``).

    Examples
    --------
    >>> gap, beta, gamma = NormRatio(2.0, 4.0, 2.0, ("r",))
    >>> gap
    2.0
    """

    ratio: float | np.ndarray
    beta: float | np.ndarray
    gamma: float | np.ndarray
    names: tuple[str, ...]

    def __iter__(self):
        """``(ratio, beta, gamma)``."""
        return iter((self.ratio, self.beta, self.gamma))


# ---------------------------------------------------------------------- spec (SFDI)
def as_spec(spec, faults: Sequence[str]) -> np.ndarray | None:
    """``spec`` as a boolean vector (m,) or matrix (rows, m) over ``faults``; None stays None.

    Parameters
    ----------
    spec : None, sequence of str, array_like of bool, StructureMatrix or pandas.DataFrame
        Fault names (the faults to detect), a boolean vector or ``rows × faults`` matrix (Varga's
        ``SFDI``), a :class:`~fdikit.analysis.structure.StructureMatrix`, or a boolean fault × group
        DataFrame (:func:`~fdikit.analysis.structure_matrix`; transposed to ``groups × faults``).
    faults : sequence of str
        The fault names (columns).

    Returns
    -------
    ndarray of bool or None

    Raises
    ------
    ParameterError
        For an unknown fault name, a wrong number of columns or non-boolean entries.

    Examples
    --------
    >>> as_spec(["b"], ("a", "b")).tolist(), as_spec([[1, 0], [0, 1]], ("a", "b")).tolist()
    ([False, True], [[True, False], [False, True]])
    """
    faults = tuple(faults)
    if spec is None:
        return None
    if hasattr(spec, "matrix") and hasattr(spec, "faults") and hasattr(spec, "rows"):  # StructureMatrix
        order = _fault_order(tuple(spec.faults), faults)
        return np.asarray(spec.matrix, dtype=bool)[:, order]
    if hasattr(spec, "to_numpy") and hasattr(spec, "index") and hasattr(spec, "columns"):  # fault × group frame
        order = _fault_order(tuple(str(f) for f in spec.index), faults)
        raw = np.asarray(spec.to_numpy())
        if raw.dtype != bool:
            raise ParameterError(f"a spec DataFrame must be boolean (faults × residual groups), got {raw.dtype}")
        return raw[order].T.copy()
    if isinstance(spec, str) or (isinstance(spec, Sequence) and spec and all(isinstance(s, str) for s in spec)):
        names = [spec] if isinstance(spec, str) else list(spec)
        unknown = [s for s in names if s not in faults]
        if unknown:
            raise ParameterError(f"spec names fault(s) {unknown} that the internal form does not have {list(faults)}")
        return np.array([f in names for f in faults], dtype=bool)
    arr = np.asarray(spec)
    if arr.dtype != bool:
        if arr.dtype.kind not in "iuf" or not np.all(np.isin(arr, (0, 1))):
            raise ParameterError(f"spec must be boolean (or 0/1), fault names or a structure matrix, got {spec!r}")
        arr = arr.astype(bool)
    if arr.ndim not in (1, 2) or arr.shape[-1] != len(faults):
        raise ParameterError(f"spec has shape {arr.shape}; it needs one column per fault ({len(faults)}: "
                             f"{list(faults)})")
    return arr


def _fault_order(given: tuple[str, ...], faults: tuple[str, ...]) -> list[int]:
    if set(given) != set(faults) or len(given) != len(faults):
        raise ParameterError(f"the spec's faults {list(given)} differ from the internal form's {list(faults)}")
    return [given.index(f) for f in faults]


def _rows(bank: InternalForms, spec):
    """Evaluation units ``(name, form, outputs, fault mask)`` and whether the result is a vector."""
    mf = len(bank.faults)
    S = as_spec(spec, bank.faults)
    if bank.bank:
        if S is None:
            S = np.ones((len(bank.forms), mf), dtype=bool)
        S = S.reshape(1, -1) if S.ndim == 1 else S
        if S.shape[0] != len(bank.forms):
            raise ParameterError(f"spec has {S.shape[0]} rows for a bank of {len(bank.forms)} filters")
        return [(nm, f, None, S[i]) for i, (nm, f) in enumerate(zip(bank.names, bank.forms))], True
    form = bank.forms[0]
    if S is None or S.ndim == 1:
        return [(bank.names[0], form, None, np.ones(mf, dtype=bool) if S is None else S)], False
    if S.shape[0] != form.p:
        raise ParameterError(f"a rows × faults spec has {S.shape[0]} rows, the filter has {form.p} residuals "
                             f"{list(form.outputs)}")
    return [(r, form, [r], S[i]) for i, r in enumerate(form.outputs)], True


# ---------------------------------------------------------------------- column norms
def _column_norms(form: FaultModel, inputs, outputs, freqs) -> tuple[np.ndarray, np.ndarray]:
    """(m,) column norms and the frequency of each: H∞ of each column, or the extreme over ``freqs`` (min, max)."""
    if freqs is None:
        vals, where = [], []
        for nm in inputs:
            g, w = hinf_norm(minimal_channel(form, [nm], outputs))
            vals.append(g)
            where.append(w)
        return np.array(vals), np.array(where)
    omega = check_freqs(freqs, form.dt)
    H = frequency_response(minimal_channel(form, list(inputs), outputs), omega)  # (N, p, m)
    return np.linalg.norm(H, axis=1), omega  # (N, m) and the frequencies


def _extreme(form, inputs, outputs, freqs, kind: str) -> ColumnNorm:
    inputs = list(inputs)
    if not inputs:
        raise ParameterError("no columns to take the norm of; select at least one input")
    vals, where = _column_norms(form, inputs, outputs, freqs)
    pick = np.argmin if kind == "min" else np.argmax
    if freqs is None:
        j = int(pick(vals))
        return ColumnNorm(float(vals[j]), inputs[j], float(where[j]))
    k, j = np.unravel_index(int(pick(vals)), vals.shape)
    return ColumnNorm(float(vals[k, j]), inputs[j], float(where[k]))


def fdhinfminus(sysr, freqs=None, *, inputs: Sequence[str] | None = None) -> ColumnNorm:
    """H∞− index ``min_j ‖g_j‖∞`` of the columns of a stable internal form (default: its fault columns).

    With ``freqs`` the minimum is over the 2-norms of the columns of ``G(λ_k)`` at those frequencies
    (``λ = jω``, or ``e^{jω dt}``).

    Parameters
    ----------
    sysr : FaultModel or design result
        The internal form.
    freqs : float or array_like, optional
        Frequencies [rad/s]; default all (the H∞ norm of each column).
    inputs : sequence of str, optional
        The columns (input names of any group); default the faults.

    Returns
    -------
    ColumnNorm
        ``value`` (``β``), the ``column`` attaining it and the ``freq`` [rad/s] where.

    Raises
    ------
    ModelError
        When the internal form is unstable, or a frequency is a pole.
    ParameterError
        For an unknown input or no columns.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0, 3.0]], faults=["f1", "f2"])
    >>> b = fdhinfminus(R)
    >>> round(b.value, 9), b.column
    (1.0, 'f1')
    >>> round(fdhinfminus(R, [1.0]).value, 6)   # |1/(j + 1)|
    0.707107
    """
    form = internal_forms(sysr).forms[0]
    check_stable(form)
    return _extreme(form, input_columns(form, inputs), None, freqs, "min")


def fdhinfmax(sysr, freqs=None, *, inputs: Sequence[str] | None = None) -> ColumnNorm:
    """Largest column norm ``max_j ‖g_j‖∞`` (or over ``freqs``), as :func:`fdhinfminus` with the maximum.

    Parameters
    ----------
    sysr, freqs, inputs
        As :func:`fdhinfminus`.

    Returns
    -------
    ColumnNorm

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0, 3.0]], faults=["f1", "f2"])
    >>> m = fdhinfmax(R)
    >>> round(m.value, 9), m.column
    (3.0, 'f2')
    """
    form = internal_forms(sysr).forms[0]
    return _extreme(form, input_columns(form, inputs), None, freqs, "max")


# ---------------------------------------------------------------------- condition and gap
def fdiscond(sysr, spec=None, freqs=None, *, groups=None) -> NormRatio:
    """Fault sensitivity condition ``β/γ``: smallest over largest column norm of ``R_f`` (selected faults).

    ``β = min_j ‖R_fj‖∞`` and ``γ = max_j ‖R_fj‖∞`` over the faults ``spec`` selects (default all), or
    the minimum and maximum of the column 2-norms of ``R_f(λ_k)`` at ``freqs``.  A ``rows × faults``
    ``spec`` gives one value per residual (its row of ``R_f``), a bank one per filter (``spec`` one row per
    filter, default all faults).  ``ratio`` is NaN when every selected column is zero.

    Parameters
    ----------
    sysr : FaultModel, design result, or a bank (sequence / mapping of them)
        Stable internal form(s).
    spec : fault names, bool array, StructureMatrix or DataFrame, optional
        The faults each filter (or residual) is to detect (``SFDI``).
    freqs : float or array_like, optional
        Frequencies [rad/s]; default all.
    groups : mapping or sequence, optional
        With one internal form: the residuals of each filter of a stacked bank.

    Returns
    -------
    NormRatio
        ``ratio`` (``scond``), ``beta``, ``gamma``: floats for one filter, arrays for a bank or a matrix spec.

    Raises
    ------
    ModelError
        When an internal form is unstable.
    ParameterError
        When ``spec`` does not fit the faults or filters, or selects no fault for some filter.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0], [1.0]], Bf=[[1.0, 3.0]], Df=[[0.0, 0.0], [0.0, 1.0]],
    ...                faults=["f1", "f2"], outputs=["r1", "r2"])
    >>> c = fdiscond(R, [[True, True], [False, True]])
    >>> np.round(c.ratio, 6).tolist(), c.names
    ([0.333333, 1.0], ('r1', 'r2'))
    """
    bank = internal_forms(sysr, groups)
    units, vector = _rows(bank, spec)
    beta, gamma = [], []
    for name, form, outputs, mask in units:
        check_stable(form, outputs)
        cols = [f for f, s in zip(bank.faults, mask) if s]
        if not cols:
            raise ParameterError(f"spec selects no fault for {name!r}; fdiscond needs at least one")
        vals, _ = _column_norms(form, cols, outputs, freqs)
        beta.append(float(np.min(vals)))
        gamma.append(float(np.max(vals)))
    b, g = np.array(beta), np.array(gamma)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(g > 0, b / np.where(g > 0, g, 1.0), np.nan)
    names = tuple(u[0] for u in units)
    if not vector:
        return NormRatio(float(r[0]), float(b[0]), float(g[0]), names)
    return NormRatio(r, b, g, names)


def fdif2ngap(sysr, spec=None, freqs=None, *, groups=None, atol: float = float(np.sqrt(_EPS))) -> NormRatio:
    """Fault-to-noise gap ``β/γ = ‖R_ff‖∞− / ‖[R_fd R_w]‖∞`` of one filter or of each filter of a bank.

    ``R_ff`` are the columns of ``R_f`` of the faults ``spec`` selects (default all), ``R_fd`` the others;
    ``β`` is their H∞− index (:func:`fdhinfminus`; at ``freqs`` the minimum column 2-norm there) and ``γ``
    the H∞ norm over all frequencies (as the reference computes it, also when ``freqs`` is given).
    A ``rows × faults`` ``spec`` gives one gap per residual, a bank one per filter.

    Conventions: ``γ ≤ atol`` counts as zero and gives ``ratio = ∞`` (no noise, everything else
    decoupled); ``β = 0`` (no fault to detect, or a zero column) gives ``ratio = 0``, also when ``γ = 0``.

    Parameters
    ----------
    sysr : FaultModel, design result, or a bank (sequence / mapping of them)
        Stable internal form(s).
    spec : fault names, bool array, StructureMatrix or DataFrame, optional
        The faults to detect (``SFDI``); default all faults.
    freqs : float or array_like, optional
        Frequencies [rad/s] for ``β``; default all.
    groups : mapping or sequence, optional
        With one internal form: the residuals of each filter of a stacked bank.
    atol : float, default √ε
        Absolute tolerance below which ``γ`` is zero.

    Returns
    -------
    NormRatio
        ``ratio`` (the gap), ``beta``, ``gamma``: floats for one filter, arrays for a bank or a matrix spec.

    Raises
    ------
    ModelError
        When an internal form is unstable.
    ParameterError
        When the form has neither faults nor noise, or ``spec`` does not fit.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[2.0]], faults=["f"])   # no noise: infinite gap
    >>> g = fdif2ngap(R)
    >>> g.ratio, round(g.beta, 9), g.gamma
    (inf, 2.0, 0.0)
    """
    from fdikit import validate

    atol = validate.non_negative("atol", atol)
    bank = internal_forms(sysr, groups)
    if not bank.faults and not bank.noise:
        raise ParameterError("the internal form has neither faults (group f) nor noise (group w); no gap to compute")
    units, vector = _rows(bank, spec)
    beta, gamma = [], []
    for _, form, outputs, mask in units:
        check_stable(form, outputs)
        det = [f for f, s in zip(bank.faults, mask) if s]
        rest = [f for f, s in zip(bank.faults, mask) if not s] + list(bank.noise)
        b = float(np.min(_column_norms(form, det, outputs, freqs)[0])) if det else 0.0
        g = hinf_norm(minimal_channel(form, rest, outputs))[0] if rest else 0.0
        beta.append(b)
        gamma.append(0.0 if g <= atol else g)
    b, g = np.array(beta), np.array(gamma)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(b == 0, 0.0, np.where(g > 0, b / np.where(g > 0, g, 1.0), np.inf))
    names = tuple(u[0] for u in units)
    if not vector:
        return NormRatio(float(r[0]), float(b[0]), float(g[0]), names)
    return NormRatio(r, b, g, names)


# ---------------------------------------------------------------------- model matching
def _norm(ch, which) -> float:
    return hinf_norm(ch)[0] if which == "inf" else h2_norm(ch)


def _difference(form: FaultModel, ref: FaultModel, name: str):
    """Channel of ``R − M_r`` with the void groups of ``M_r`` taken as zero."""
    from fdikit.analysis.channels import Channel

    if ref.p != form.p:
        raise ModelError(f"the reference {name} has {ref.p} outputs, the filter {form.p}")
    if (ref.dt is None) != (form.dt is None) or (ref.dt is not None and not np.isclose(ref.dt, form.dt)):
        raise ModelError(f"the reference {name} has dt={ref.dt}, the filter dt={form.dt}")
    Bm = np.zeros((ref.n, form.B.shape[1]))
    Dm = np.zeros((ref.p, form.B.shape[1]))
    start = 0
    for g in GROUPS:
        k, kr = len(form.inputs[g]), len(ref.inputs[g])
        if kr and kr != k:
            raise ModelError(f"the reference {name} has {kr} inputs in group {g!r}, the filter {k}; "
                             "give the group in full or leave it out (taken as zero)")
        if kr:
            Bm[:, start:start + k], Dm[:, start:start + k] = ref.b(g), ref.d(g)
        start += k
    import scipy.linalg

    A = scipy.linalg.block_diag(form.A, ref.A)
    B = np.vstack([form.B, Bm])
    C = np.hstack([form.C, -ref.C])
    D = form.D - Dm
    diff = FaultModel(A, C, Bu=B, Du=D, dt=form.dt) if B.shape[1] else None
    if diff is None:
        return Channel(np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((form.p, 0)), np.zeros((form.p, 0)), form.dt)
    return minimal_channel(diff)


def static_reference(gains: Mapping, like: FaultModel, *, p: int | None = None) -> FaultModel:
    """A static ``M_r`` as an internal form with ``like``'s input groups (one hidden state at −1, discrete 0).

    Parameters
    ----------
    gains : mapping
        ``{group: matrix}`` with groups among ``'u', 'd', 'f', 'w'``; a group left out is zero.
    like : FaultModel
        Gives the input names of each group and the sample time (a plant or an internal form).
    p : int, optional
        The number of outputs (default ``like.p``).

    Returns
    -------
    FaultModel

    Raises
    ------
    ParameterError
        An unknown group or a matrix of the wrong shape.

    Examples
    --------
    >>> like = FaultModel([[-1.0]], [[1.0], [1.0]], Bf=[[1.0, 2.0]])
    >>> static_reference({"f": np.eye(2)}, like).d("f").tolist()
    [[1.0, 0.0], [0.0, 1.0]]

    References
    ----------
    Varga (2017), §5.6 (the reference model of fault estimation, ``M_r = I``); fdtools (``fdimmperf``).
    """
    from fdikit import validate

    p = like.p if p is None else int(p)
    kw: dict = {}
    for g, M in gains.items():
        if g not in GROUPS:
            raise ParameterError(f"a static reference maps input groups {GROUPS} to matrices, got key {g!r}")
        M = validate.as_matrix(f"gains[{g!r}]", M, (p, len(like.inputs[g])))
        kw[f"B{g}"], kw[f"D{g}"] = np.zeros((1, M.shape[1])), M
        kw[{"u": "controls", "d": "disturbances", "f": "faults", "w": "noise"}[g]] = like.inputs[g]
    return FaultModel([[-1.0 if like.dt is None else 0.0]], np.zeros((p, 1)), dt=like.dt, **kw)


def fdimmperf(sysr, spec=None, *, ref=None, norm="inf", groups=None) -> float | np.ndarray:
    """Model-matching performance: ``‖R_w‖``, ``‖[R_fd R_w]‖`` or ``‖R − M_r‖`` in the H∞ or H2 norm.

    * no ``spec``, no ``ref``: ``‖R_w‖`` (0 without noise inputs);
    * ``spec`` a fault vector: ``‖[R_fd R_w]‖`` with ``R_fd`` the columns of the faults not selected;
      a ``rows × faults`` matrix (one filter): ``R_fd = (¬spec) .* R_f`` element-wise;
    * ``ref``: ``‖R − M_r‖`` with ``M_r`` an internal form of the same residuals; a group ``M_r`` lacks
      (e.g. ``M_r`` from the faults only) is taken as zero;
    * a bank: one value per filter (``spec`` one row per filter, ``ref`` a sequence of as many references).

    The value is infinite for an unstable channel, and for ``norm=2`` when a continuous channel is not
    strictly proper.

    Parameters
    ----------
    sysr : FaultModel, design result, or a bank
        The internal form(s).
    spec : fault names, bool array, StructureMatrix or DataFrame, optional
        The faults to detect (``SFDI``); the others count as nuisance.
    ref : FaultModel, design result, mapping, or a sequence of them (bank), optional
        The reference model ``M_r`` (not with ``spec``); a mapping ``{group: matrix}`` is a static
        ``M_r`` (``{"f": np.eye(q)}`` for fault estimation; fdikit's models need a state).
    norm : {'inf', 2}, default 'inf'
        H∞ (``'inf'``, ``np.inf``) or H2 norm.
    groups : mapping or sequence, optional
        With one internal form: the residuals of each filter of a stacked bank.

    Returns
    -------
    float or (N,) ndarray
        ``γ``; one per filter of a bank.

    Raises
    ------
    ParameterError
        For an unknown norm, both ``spec`` and ``ref``, or a spec that does not fit.
    ModelError
        When ``ref`` does not match the filter (outputs, input groups, sample time).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-2.0]], C=[[1.0]], Bf=[[2.0]], Bw=[[1.0]], faults=["f"], noise=["w"])
    >>> round(fdimmperf(R), 9), round(fdimmperf(R, norm=2), 9)   # 1/(s + 2): peak 1/2, H2 norm 1/2
    (0.5, 0.5)
    >>> round(fdimmperf(R, ref={"f": [[1.0]]}), 9)   # M_r = 1 from f: ‖[2/(s+2) − 1, 1/(s+2)]‖∞ at ω = ∞
    1.0
    """
    if isinstance(norm, str):
        which = {"inf": "inf", "2": "2"}.get(norm.lower())
    else:
        which = "inf" if norm == np.inf else "2" if norm == 2 else None
    if which is None:
        raise ParameterError(f"norm must be 'inf' (H∞) or 2 (H2), got {norm!r}")
    if spec is not None and ref is not None:
        raise ParameterError("give spec (nuisance faults) or ref (a reference model), not both")
    bank = internal_forms(sysr, groups)
    if ref is not None:
        if isinstance(ref, Mapping) and all(k in GROUPS for k in ref):
            ref = static_reference(ref, bank.forms[0])
        elif isinstance(ref, (list, tuple)):
            ref = [static_reference(r, f) if isinstance(r, Mapping) else r for f, r in zip(bank.forms, ref)]
        refs = internal_forms(ref)
        if len(refs.forms) != len(bank.forms) or refs.bank != bank.bank:
            raise ParameterError(f"ref has {len(refs.forms)} filter(s), sysr {len(bank.forms)}; give one reference "
                                 "per filter")
        vals = [_norm(_difference(f, r, nm), which) for nm, f, r in zip(bank.names, bank.forms, refs.forms)]
        return np.array(vals) if bank.bank else float(vals[0])
    S = as_spec(spec, bank.faults)
    if not bank.bank and S is not None and S.ndim == 2:
        form = bank.forms[0]
        if S.shape[0] != form.p:
            raise ParameterError(f"a rows × faults spec has {S.shape[0]} rows, the filter has {form.p} residuals")
        cols = list(bank.faults) + list(bank.noise)
        mask = np.hstack([~S, np.ones((form.p, len(bank.noise)), dtype=bool)])
        return _norm(minimal_channel(form, cols, output_mask=mask), which) if cols else 0.0
    units, vector = _rows(bank, spec)  # no spec: every fault is "to detect", γ = ‖R_w‖
    vals = []
    for _, form, outputs, mask in units:
        cols = [f for f, s in zip(bank.faults, mask) if not s] + list(bank.noise)
        vals.append(_norm(minimal_channel(form, cols, outputs), which) if cols else 0.0)
    return np.array(vals) if vector else float(vals[0])
