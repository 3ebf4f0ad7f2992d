"""Discrete LPV models and their stacked parity-relation matrices (Varrier et al. 2014, §2–§3, §4.1).

Models here are polynomial in one scheduling parameter, ``X(ρ) = Σ_j ρ^j X_j`` (the paper's
affine form (3) with ``ρ₂ = ρ₁²`` substituted, §5.1): :class:`LPVModel`.

Over a horizon ``s`` the outputs of a discrete model obey the parity relation (7)::

    Y_s = H_os x(k) + H_us U_s + H_ds U_ds + H_fs F_s,      Y_s = [y(k); y(k+1); …; y(k+s)]

with the stacked observability matrix and the block-Toeplitz input maps.  The paper's
(7)–(8) print wrong time indices (s−1 factors in the last row of ``H_os``, ``D(ρ_k)`` and
``B(ρ_k)`` on every block); the exact time-varying forms used here, obtained by iterating (6), are::

    Φ(i, j)        = A(ρ_{k+i−1}) ··· A(ρ_{k+j}),   Φ(j, j) = I
    [H_os]_i       = C(ρ_{k+i}) Φ(i, 0)
    [H_us]_{i, j}  = D(ρ_{k+i}) if i = j,   C(ρ_{k+i}) Φ(i, j+1) B(ρ_{k+j}) if i > j,   0 if i < j

and the same pattern with ``B_d, D_d`` (``H_ds``), ``B_f, D_f`` (``H_fs``), ``B_w, D_w``.
With ρ frozen over the window (§4.6.1, (44)–(45)) they reduce to ``[C; CA; …; CA^s]`` and
the Markov parameters ``C A^{i−j−1} B``.

Uncertain models (§2, (2), (5)) add scalar unknowns δ_i to ``A`` and ``C``
(:class:`Uncertainty`); :func:`uncertain_stacked_matrices` expands the stacked matrices in the
monomials of δ, the ``H̃`` maps of (14) used by the robust design (:mod:`fdikit.design.parity.criteria`).
The parity matrix and residuals built on these matrices are in :mod:`fdikit.design.parity.state_space`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import ModelError, ParameterError
from fdikit.model import GROUPS, FaultModel

__all__ = [
    "LPVModel",
    "StackedMatrices",
    "stacked_matrices",
    "lpv_stacked_matrices",
    "Uncertainty",
    "UncertainStack",
    "uncertain_stacked_matrices",
]


# ---------------------------------------------------------------------------------------------- LPV model
def _group_slices(model: FaultModel) -> dict[str, slice]:
    """Columns of each input group in ``B``/``D`` (groups in the order u, d, f, w)."""
    out, start = {}, 0
    for g in GROUPS:
        k = len(model.inputs[g])
        out[g] = slice(start, start + k)
        start += k
    return out


@dataclass(frozen=True, eq=False)
class LPVModel:
    """Discrete LPV model polynomial in a scalar scheduling parameter ρ.

    ``x[k+1] = A(ρ_k) x[k] + B(ρ_k) v[k]``, ``y[k] = C(ρ_k) x[k] + D(ρ_k) v[k]`` with
    ``X(ρ) = Σ_j ρ^j X_j`` for every matrix, ``v = [u; d; f; w]`` as in :class:`FaultModel`.

    Parameters
    ----------
    terms : mapping int -> FaultModel, or sequence of FaultModel
        ``terms[j]`` holds the coefficient matrices of ``ρ^j``.  All terms must be discrete
        with the same ``dt`` and the same state, output and input names; missing powers are
        zero.  Term 0 supplies the names.
    scheduling : str
        Name of ρ (documentation only), e.g. ``"1/speed"``.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> lpv = LPVModel({0: FaultModel([[1.0]], [[1.0]], dt=0.1), 1: FaultModel([[-0.5]], [[0.0]], dt=0.1)})
    >>> float(lpv.at(0.4).A[0, 0])
    0.8
    """

    terms: tuple[FaultModel, ...]
    scheduling: str = "rho"

    def __init__(self, terms: Mapping[int, FaultModel] | Sequence[FaultModel], scheduling: str = "rho") -> None:
        if isinstance(terms, Mapping):
            if not terms or 0 not in terms:
                raise ModelError("an LPVModel needs the constant term (power 0) of its matrices")
            if any(not isinstance(j, int | np.integer) or j < 0 for j in terms):
                raise ModelError(f"LPVModel powers must be integers >= 0, got {sorted(terms)}")
            degree = max(terms)
            base = terms[0]
            seq = [terms.get(j) for j in range(degree + 1)]
        else:
            seq = list(terms)
            if not seq:
                raise ModelError("an LPVModel needs at least the constant term")
            base = seq[0]
        if not isinstance(base, FaultModel):
            raise ModelError(f"LPVModel terms must be FaultModel objects, got {type(base).__name__}")
        if not base.is_discrete:
            raise ModelError("LPVModel terms must be discrete (dt > 0); discretize the coefficient models first")
        zero = base.replace(A=np.zeros_like(base.A), C=np.zeros_like(base.C),
                            **{f"{m}{g}": np.zeros_like(getattr(base, f"{m}{g}")) for g in GROUPS for m in "BD"})
        out = []
        for j, term in enumerate(seq):
            term = zero if term is None else term
            if not isinstance(term, FaultModel):
                raise ModelError(f"LPVModel term {j} is a {type(term).__name__}, not a FaultModel")
            same = (term.states == base.states and term.outputs == base.outputs and term.inputs == base.inputs
                    and term.dt == base.dt)
            if not same:
                raise ModelError(
                    f"LPVModel term {j} differs from term 0 in names, input groups or dt; every coefficient "
                    "model must have the same states, outputs, inputs and sample time"
                )
            out.append(term)
        object.__setattr__(self, "terms", tuple(out))
        if not isinstance(scheduling, str) or not scheduling.strip():
            raise ParameterError(f"scheduling must be a non-empty name of the scheduling parameter, got {scheduling!r}")
        object.__setattr__(self, "scheduling", scheduling)
        for name in "ABCD":
            arr = np.stack([getattr(t, name) for t in out])
            arr.setflags(write=False)
            object.__setattr__(self, f"_{name}", arr)

    # sizes and names ------------------------------------------------------------------
    @property
    def degree(self) -> int:
        """Highest power of ρ."""
        return len(self.terms) - 1

    @property
    def template(self) -> FaultModel:
        """The constant term (names, groups, ``dt``)."""
        return self.terms[0]

    n = property(lambda self: self.template.n, doc="Number of states.")
    p = property(lambda self: self.template.p, doc="Number of outputs.")
    dt = property(lambda self: self.template.dt, doc="Sample time.")
    states = property(lambda self: self.template.states)
    outputs = property(lambda self: self.template.outputs)
    controls = property(lambda self: self.template.controls)
    disturbances = property(lambda self: self.template.disturbances)
    faults = property(lambda self: self.template.faults)

    def columns(self, group: str) -> slice:
        """Columns of ``B``/``D`` that belong to input group ``group``."""
        slices = _group_slices(self.template)
        if group not in slices:
            raise ModelError(f"unknown input group {group!r}; use one of {GROUPS}")
        return slices[group]

    def matrices(self, rho) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``A, B, C, D`` at ρ (any shape, real or complex); each has shape ``rho.shape + (rows, cols)``."""
        rho = np.asarray(rho)
        out = []
        for name in "ABCD":
            coef = getattr(self, f"_{name}")
            val = np.zeros(rho.shape + coef.shape[1:], dtype=np.result_type(rho, float))
            for c in coef[::-1]:  # Horner
                val = val * rho[..., None, None] + c
            out.append(val)
        return tuple(out)

    def at(self, rho: float) -> FaultModel:
        """The frozen model at a real ρ, as a discrete :class:`FaultModel`."""
        r = float(rho)
        if not np.isfinite(r):
            raise ModelError(f"rho must be a finite number, got {rho!r}")
        A, B, C, D = self.matrices(r)
        kw = {}
        for g in GROUPS:
            sl = self.columns(g)
            kw[f"B{g}"], kw[f"D{g}"] = B[:, sl], D[:, sl]
        return self.template.replace(A=A, C=C, **kw)

    def __repr__(self) -> str:
        return f"LPVModel(degree {self.degree} in {self.scheduling}, {self.template!r})"


# ---------------------------------------------------------------------------------------------- stacking
@dataclass(frozen=True, eq=False)
class StackedMatrices:
    """Stacked observability and input matrices over a horizon ``s`` (Varrier et al. 2014, (7)–(8)).

    Every array may carry leading batch axes (one set of matrices per ρ).  ``H_os`` is
    ``(s+1)p × n``; ``H[g]`` is ``(s+1)p × (s+1)k_g`` for input group ``g`` with the
    window's inputs stacked sample by sample, ``[v(k); v(k+1); …; v(k+s)]``.

    Attributes
    ----------
    H_os : ndarray
        Stacked observability matrix, ``(..., (s+1)p, n)``.
    H : dict of str to ndarray
        Input maps by group ``"u"``, ``"d"``, ``"f"``, ``"w"`` (also as ``H_us``, ``H_ds``, ``H_fs``, ``H_ws``).
    s : int
        Horizon.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> st = stacked_matrices(FaultModel([[0.5]], [[2.0]], Bu=[[1.0]], dt=1.0), 2)
    >>> st.H_us.tolist(), st.H_fs.shape
    ([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 2.0, 0.0]], (3, 0))
    """

    H_os: np.ndarray
    H: dict[str, np.ndarray]
    s: int

    H_us = property(lambda self: self.H["u"], doc="Control map.")
    H_ds = property(lambda self: self.H["d"], doc="Disturbance map.")
    H_fs = property(lambda self: self.H["f"], doc="Fault map.")
    H_ws = property(lambda self: self.H["w"], doc="Noise map.")


def _products(A: np.ndarray) -> list[list[np.ndarray]]:
    """``Φ[i][j] = A_{i−1} ··· A_j`` for ``0 <= j <= i <= s`` (A: (..., s+1, n, n))."""
    s1, n = A.shape[-3], A.shape[-1]
    eye = np.broadcast_to(np.eye(n, dtype=A.dtype), A.shape[:-3] + (n, n))
    phi = [[None] * s1 for _ in range(s1)]
    for j in range(s1):
        cur = eye
        phi[j][j] = cur
        for i in range(j + 1, s1):
            cur = A[..., i - 1, :, :] @ cur
            phi[i][j] = cur
    return phi


def _toeplitz(phi, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Block lower-triangular map of one input group (B, C, D: (..., s+1, ·, ·))."""
    s1, p, k = C.shape[-3], C.shape[-2], B.shape[-1]
    batch = C.shape[:-3]
    H = np.zeros(batch + (s1 * p, s1 * k), dtype=np.result_type(B, C, D))
    for i in range(s1):
        H[..., i * p:(i + 1) * p, i * k:(i + 1) * k] = D[..., i, :, :]
        for j in range(i):
            H[..., i * p:(i + 1) * p, j * k:(j + 1) * k] = C[..., i, :, :] @ phi[i][j + 1] @ B[..., j, :, :]
    return H


def _stack(A, B, C, D, groups: Mapping[str, slice], s: int) -> StackedMatrices:
    phi = _products(A)
    H_os = np.concatenate([C[..., i, :, :] @ phi[i][0] for i in range(s + 1)], axis=-2)
    H = {g: _toeplitz(phi, B[..., sl], C, D[..., sl]) for g, sl in groups.items()}
    return StackedMatrices(H_os, H, s)


def check_horizon(s) -> int:
    if isinstance(s, bool) or not isinstance(s, int | np.integer) or s < 0:
        raise ParameterError(f"the horizon s must be an integer >= 0 (a non-negative integer), got {s!r}")
    return int(s)


def stacked_matrices(model: FaultModel | Sequence[FaultModel], s: int | None = None) -> StackedMatrices:
    """Stacked matrices of a discrete LTI model, or exactly of a time-varying window of models.

    Parameters
    ----------
    model : FaultModel or sequence of FaultModel
        One discrete model (LTI, needs ``s``) or the ``s+1`` models in force at samples
        ``k, …, k+s`` (exact time-varying stacking; ``s`` is implied).
    s : int, optional
        Horizon for a single model.

    Returns
    -------
    StackedMatrices
        ``H_os`` and the maps of every input group over the window.

    Raises
    ------
    ParameterError
        If ``model`` is not a FaultModel or a non-empty sequence of them, or ``s`` is missing for a single
        model or not a non-negative integer.
    ModelError
        If a model is continuous, the window's models differ in dimensions or inputs, or ``s`` contradicts the
        length of the window.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel([[0.5]], [[2.0]], Bu=[[1.0]], dt=1.0)
    >>> stacked_matrices(m, 2).H_os.ravel().tolist()
    [2.0, 1.0, 0.5]
    """
    models = [model] if isinstance(model, FaultModel) else list(model)
    if not models or not all(isinstance(m, FaultModel) for m in models):
        raise ParameterError("stacked_matrices needs a FaultModel or a non-empty sequence of FaultModel objects "
                             f"as model, got {type(model).__name__}")
    if len(models) == 1:
        if s is None:
            raise ParameterError("give the horizon s for a single model (e.g. stacked_matrices(model, 3))")
        s = check_horizon(s)
        models = models * (s + 1)
    elif s is not None and check_horizon(s) != len(models) - 1:
        raise ModelError(f"{len(models)} models make a window of horizon s={len(models) - 1}, not s={s}")
    s = len(models) - 1
    base = models[0]
    for m in models:
        if not m.is_discrete:
            raise ModelError("parity stacking needs discrete models; use model.discretize(dt) first")
        if m.inputs != base.inputs or m.n != base.n or m.p != base.p:
            raise ModelError("every model in a time-varying window must have the same dimensions and inputs")
    A, B, C, D = (np.stack([getattr(m, a) for m in models]) for a in "ABCD")
    return _stack(A, B, C, D, _group_slices(base), s)


def lpv_stacked_matrices(lpv: LPVModel, rho, s: int, *, mode: str = "frozen", groups: Sequence[str] = GROUPS
                         ) -> StackedMatrices:
    """Stacked matrices of an :class:`LPVModel` (Varrier et al. 2014, (7)–(8), corrected; (45)).

    Parameters
    ----------
    lpv : LPVModel
        The model.
    rho : array_like
        ``mode="frozen"``: ρ values (any shape, real or complex), one frozen window each.
        ``mode="exact"``: windows of ρ with the last axis of length ``s+1``, oldest sample first.
    s : int
        Horizon.
    mode : {"frozen", "exact"}
        ρ constant over each window ((44)–(45), default) or the exact time-varying stacking.
    groups : sequence of str
        Input groups whose maps are wanted (default all).

    Returns
    -------
    StackedMatrices
        Arrays with the batch shape of ``rho`` (without the window axis) in front.

    Raises
    ------
    ParameterError
        If ``s`` is not a non-negative integer.
    ModelError
        On an unknown ``mode`` or, with ``mode="exact"``, windows whose last axis is not ``s+1`` long.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> lpv = LPVModel({0: FaultModel([[1.0]], [[1.0]], Bu=[[1.0]], dt=0.1),
    ...                 1: FaultModel([[-0.5]], [[0.0]], Bu=[[0.0]], dt=0.1)})     # A(ρ) = 1 − 0.5 ρ
    >>> st = lpv_stacked_matrices(lpv, 0.4, 2)
    >>> st.H_os.round(6).ravel().tolist(), st.H_us.round(6).tolist()
    ([1.0, 0.8, 0.64], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.8, 1.0, 0.0]])
    >>> lpv_stacked_matrices(lpv, [0.0, 0.4], 1).H_os.shape     # two frozen windows
    (2, 2, 1)
    >>> lpv_stacked_matrices(lpv, [0.0, 0.4], 1, mode="exact").H_os.ravel().tolist()   # C; C A(ρ_k = 0)
    [1.0, 1.0]
    """
    s = check_horizon(s)
    rho = np.asarray(rho)
    if mode == "frozen":
        rho = np.repeat(rho[..., None], s + 1, axis=-1)
    elif mode == "exact":
        if rho.ndim == 0 or rho.shape[-1] != s + 1:
            raise ModelError(f"mode='exact' needs rho windows with a last axis of length s+1={s + 1}, got {rho.shape}")
    else:
        raise ModelError(f"unknown stacking mode {mode!r}; use 'frozen' or 'exact'")
    A, B, C, D = lpv.matrices(rho)
    return _stack(A, B, C, D, {g: lpv.columns(g) for g in groups}, s)


# ---------------------------------------------------------------------------------------------- uncertainty
def _poly_coefficients(name: str, value, shape: tuple[int, int]) -> np.ndarray:
    """(d+1, rows, cols) coefficients from a constant matrix or a mapping power -> matrix."""
    if value is None:
        return np.zeros((1,) + shape)
    items = dict(value) if isinstance(value, Mapping) else {0: value}
    if any(not isinstance(j, int | np.integer) or j < 0 for j in items):
        raise ModelError(f"{name}: powers of rho must be integers >= 0, got {sorted(items)}")
    out = np.zeros((max(items) + 1,) + shape)
    for j, M in items.items():
        M = np.atleast_2d(np.asarray(M, dtype=float))
        if M.shape != shape or not np.all(np.isfinite(M)):
            raise ModelError(f"{name} coefficient of rho^{j} has shape {M.shape}, need a finite {shape} matrix")
        out[j] = M
    return out


@dataclass(frozen=True, eq=False)
class Uncertainty:
    """One unknown scalar δ: ``Ā(ρ) = A₀(ρ) + δ Ã(ρ)``, ``C̄(ρ) = C₀(ρ) + δ C̃(ρ)`` (Varrier et al. 2014, (2), (5)).

    ``A`` and ``C`` are constant matrices or mappings power -> coefficient of ``ρ^power``;
    ``n`` and ``p`` are the model's sizes (checked against the LPV model when stacking).
    As in (5), ``B`` and ``D`` are certain; δ is taken constant over the window, as (14) does (its ``ζ_k`` is built
    from ``δ_k`` alone).

    Parameters
    ----------
    A : array_like or mapping of int to array_like, optional
        ``Ã`` (n x n), constant or by power of ρ; zero if omitted.
    C : array_like or mapping of int to array_like, optional
        ``C̃`` (p x n), constant or by power of ρ; zero if omitted.
    n, p : int
        Numbers of states and outputs of the model (keyword-only).
    name : str, optional
        Name of δ (default ``"delta"``).

    Raises
    ------
    ModelError
        If a power is not a non-negative integer, or a coefficient is not a finite matrix of the given size.

    Examples
    --------
    >>> u = Uncertainty(A=[[0.1]], n=1, p=1, name="dA")
    >>> [M.tolist() for M in u.matrices(0.4)]          # Ã(ρ), C̃(ρ)
    [[[0.1]], [[0.0]]]
    """

    A: np.ndarray
    C: np.ndarray
    name: str = "delta"

    def __init__(self, A=None, C=None, *, n: int, p: int, name: str = "delta") -> None:
        object.__setattr__(self, "A", _poly_coefficients(f"uncertainty {name!r} A", A, (n, n)))
        object.__setattr__(self, "C", _poly_coefficients(f"uncertainty {name!r} C", C, (p, n)))
        object.__setattr__(self, "name", str(name))

    def matrices(self, rho) -> tuple[np.ndarray, np.ndarray]:
        """``Ã(ρ), C̃(ρ)`` for any shape of ρ (real or complex)."""
        rho = np.asarray(rho)
        out = []
        for coef in (self.A, self.C):
            val = np.zeros(rho.shape + coef.shape[1:], dtype=np.result_type(rho, float))
            for c in coef[::-1]:
                val = val * rho[..., None, None] + c
            out.append(val)
        return out[0], out[1]


@dataclass(frozen=True, eq=False)
class UncertainStack:
    """Stacked matrices of the uncertain model expanded in the monomials of δ (Varrier et al. 2014, (14)).

    ``nominal`` holds ``H_os, H_us, …`` at δ = 0; ``tilde[kind][e]`` is the coefficient of the
    monomial ``δ^e`` (``e`` an exponent tuple, total degree ≥ 1) in the stacked ``kind``
    map, ``kind`` in ``"os"`` and the input groups ``"u", "d", "f", "w"``.  Printed (14) has
    ``H̃_ds U_s``; it is ``H̃_ds U_ds`` (typo: ``H̃_ds`` multiplies the unknown inputs, as ``H_ds`` does).

    Attributes
    ----------
    nominal : StackedMatrices
        The stacked matrices at δ = 0.
    tilde : dict
        ``tilde[kind][e]``: coefficient of ``δ^e`` in the stacked map ``kind`` (``"os"`` or an input group);
        only non-zero coefficients are kept.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> lpv = LPVModel({0: FaultModel([[1.0]], [[1.0]], Bu=[[1.0]], dt=0.1),
    ...                 1: FaultModel([[-0.5]], [[0.0]], Bu=[[0.0]], dt=0.1)})     # A(ρ) = 1 − 0.5 ρ
    >>> us = uncertain_stacked_matrices(lpv, [Uncertainty(A=[[0.1]], n=1, p=1)], 0.4, 1)
    >>> us.nominal.H_os.round(6).ravel().tolist(), us.monomials("os"), us.tilde["os"][(1,)].round(6).ravel().tolist()
    ([1.0, 0.8], [(1,)], [0.0, 0.1])
    """

    nominal: StackedMatrices
    tilde: dict[str, dict[tuple[int, ...], np.ndarray]]

    def monomials(self, kind: str) -> list[tuple[int, ...]]:
        """Monomials present in ``kind``, by total degree then exponents."""
        return sorted(self.tilde[kind], key=lambda e: (sum(e), tuple(-x for x in e)))


def _pmul(P1: dict, P2: dict) -> dict:
    out: dict = {}
    for e1, M1 in P1.items():
        for e2, M2 in P2.items():
            e = tuple(a + b for a, b in zip(e1, e2))
            out[e] = out[e] + M1 @ M2 if e in out else M1 @ M2
    return out


def uncertain_stacked_matrices(lpv: LPVModel, uncertainties: Sequence[Uncertainty], rho, s: int, *,
                               mode: str = "frozen", groups: Sequence[str] = ("u", "d", "f")) -> UncertainStack:
    """δ-expansion of the stacked matrices of an uncertain LPV model (Varrier et al. 2014, (5), (14)).

    ``Σ_e δ^e tilde[kind][e]`` plus the nominal map equals the stacked map of the model with
    ``Ā = A₀ + Σ δ_i Ã_i`` and ``C̄ = C₀ + Σ δ_i C̃_i`` exactly (a polynomial identity in δ).
    ``rho`` and ``mode`` are as in :func:`lpv_stacked_matrices`.

    Parameters
    ----------
    lpv : LPVModel
        The nominal model ``A₀(ρ), C₀(ρ), B(ρ), D(ρ)``.
    uncertainties : sequence of Uncertainty
        The unknowns δ_i with their ``Ã_i``, ``C̃_i``.
    rho : array_like
        Scheduling values, as in :func:`lpv_stacked_matrices`.
    s : int
        Horizon.
    mode : {"frozen", "exact"}
        As in :func:`lpv_stacked_matrices`.
    groups : sequence of str
        Input groups whose maps are expanded (default ``("u", "d", "f")``; the others are empty).

    Returns
    -------
    UncertainStack
        The nominal stacked matrices and the coefficients of every monomial of δ.

    Raises
    ------
    ParameterError
        If ``s`` is not a non-negative integer.
    ModelError
        If an uncertainty does not match the model's sizes, or ``mode``/``rho`` are invalid.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> lpv = LPVModel({0: FaultModel([[1.0]], [[1.0]], Bu=[[1.0]], dt=0.1),
    ...                 1: FaultModel([[-0.5]], [[0.0]], Bu=[[0.0]], dt=0.1)})     # A(ρ) = 1 − 0.5 ρ
    >>> dA = Uncertainty(A=[[0.1]], n=1, p=1, name="dA")
    >>> us = uncertain_stacked_matrices(lpv, [dA], 0.4, 2)
    >>> us.monomials("os"), us.tilde["os"][(2,)].round(6).ravel().tolist()     # δ² in C A²: 0.1²
    ([(1,), (2,)], [0.0, 0.0, 0.01])
    """
    s = check_horizon(s)
    unc = list(uncertainties)
    for u in unc:
        if not isinstance(u, Uncertainty) or u.A.shape[1:] != (lpv.n, lpv.n) or u.C.shape[1:] != (lpv.p, lpv.n):
            raise ModelError(f"uncertainties must be Uncertainty objects with n={lpv.n}, p={lpv.p}")
    rho = np.asarray(rho)
    win = np.repeat(rho[..., None], s + 1, axis=-1) if mode == "frozen" else rho
    if mode not in ("frozen", "exact") or win.ndim == 0 or win.shape[-1] != s + 1:
        raise ModelError(f"mode must be 'frozen' or 'exact' (rho windows of length s+1={s + 1}), got {mode!r}")
    A, B, C, D = lpv.matrices(win)
    N = len(unc)
    zero = (0,) * N
    unit = [tuple(int(i == j) for j in range(N)) for i in range(N)]
    At, Ct = zip(*[u.matrices(win) for u in unc]) if unc else ((), ())
    hasA = [bool(np.any(u.A)) for u in unc]
    hasC = [bool(np.any(u.C)) for u in unc]
    Abar = [{zero: A[..., i, :, :]} | {unit[l]: At[l][..., i, :, :] for l in range(N) if hasA[l]}
            for i in range(s + 1)]
    Cbar = [{zero: C[..., i, :, :]} | {unit[l]: Ct[l][..., i, :, :] for l in range(N) if hasC[l]}
            for i in range(s + 1)]
    p, n = lpv.p, lpv.n
    batch = A.shape[:-3]
    eye = {zero: np.broadcast_to(np.eye(n, dtype=A.dtype), batch + (n, n))}
    phi = [[None] * (s + 1) for _ in range(s + 1)]
    for j in range(s + 1):
        cur = eye
        phi[j][j] = cur
        for i in range(j + 1, s + 1):
            cur = _pmul(Abar[i - 1], cur)
            phi[i][j] = cur

    def assemble(blocks: dict, shape: tuple[int, int]) -> dict:
        out: dict = {}
        for (i, j), poly in blocks.items():
            for e, M in poly.items():
                if e not in out:
                    out[e] = np.zeros(batch + shape, dtype=np.result_type(M, float))
                out[e][..., i * p:(i + 1) * p, j * M.shape[-1]:(j + 1) * M.shape[-1]] = M
        return out

    polys = {"os": assemble({(i, 0): _pmul(Cbar[i], phi[i][0]) for i in range(s + 1)}, ((s + 1) * p, n))}
    for g in groups:
        sl = lpv.columns(g)
        k = sl.stop - sl.start
        blocks = {(i, i): {zero: D[..., i, :, sl]} for i in range(s + 1)}
        for i in range(s + 1):
            for j in range(i):
                blocks[(i, j)] = _pmul(_pmul(Cbar[i], phi[i][j + 1]), {zero: B[..., j, :, sl]})
        polys[g] = assemble(blocks, ((s + 1) * p, (s + 1) * k))
    empty = {g: np.zeros(batch + ((s + 1) * p, 0)) for g in GROUPS if g not in groups}
    nominal = StackedMatrices(polys["os"][zero], {g: polys[g][zero] for g in groups} | empty, s)
    tilde = {kind: {e: M for e, M in poly.items() if e != zero and np.any(M)} for kind, poly in polys.items()}
    return UncertainStack(nominal, tilde)
