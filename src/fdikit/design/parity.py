"""State-space parity space for discrete LTI and LPV models (Varrier, Koenig & Martinez 2014, §3).

Over a horizon ``s`` the outputs of a discrete model obey the parity relation (7)::

    Y_s = H_os x(k) + H_us U_s + H_ds U_ds + H_fs F_s,      Y_s = [y(k); y(k+1); …; y(k+s)]

with the stacked observability matrix and the block-Toeplitz input maps.  The paper's
(7)–(8) print wrong time indices (s−1 factors in the last row of ``H_os``, ``D(ρ_k)`` and
``B(ρ_k)`` on every block); the exact time-varying forms used here are (research note M6)::

    Φ(i, j)        = A(ρ_{k+i−1}) ··· A(ρ_{k+j}),   Φ(j, j) = I
    [H_os]_i       = C(ρ_{k+i}) Φ(i, 0)
    [H_us]_{i, j}  = D(ρ_{k+i}) if i = j,   C(ρ_{k+i}) Φ(i, j+1) B(ρ_{k+j}) if i > j,   0 if i < j

and the same pattern with ``B_d, D_d`` (``H_ds``), ``B_f, D_f`` (``H_fs``), ``B_w, D_w``.
With ρ frozen over the window (§4.6.1, (44)–(45)) they reduce to ``[C; CA; …; CA^s]`` and
the Markov parameters ``C A^{i−j−1} B``.

The parity matrix (10)–(12) splits ``H_os`` into ``n`` regular rows ``H_os1`` (the
"regular part of the observability matrix", Remark 2: the first linearly independent rows,
in order) and the ``q = (s+1)p − n`` others ``H_os2``, and sets::

    P(ρ) = [−H_os2 H_os1⁻¹,  I_q]   (columns permuted back to the row order of H_os),   P H_os = 0

so that ``r = W₂ᵀ P (Y_s − H_us U_s)`` (9), (12) is zero on healthy, noise-free data for any
``W₂``.  fdikit runs the window backwards, ``Y_s(k) = [y(k−s); …; y(k)]``, so the residual
at sample ``k`` is causal (research note G14); in the frozen mode ρ is frozen at the
newest sample ``ρ_k``.

LPV models here are polynomial in one scheduling parameter, ``X(ρ) = Σ_j ρ^j X_j`` (the
paper's affine form (3) with ``ρ₂ = ρ₁²`` substituted, §5.1).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DataError, DesignError, ModelError
from fdikit.model import GROUPS, FaultModel
from fdikit.residuals import ResidualGenerator, Residuals
from fdikit.trace import Trace

__all__ = [
    "LPVModel",
    "StackedMatrices",
    "stacked_matrices",
    "lpv_stacked_matrices",
    "minimal_horizon",
    "regular_rows",
    "parity_matrix",
    "ParityDesign",
    "parity_design",
    "lpv_parity_residuals",
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
        object.__setattr__(self, "scheduling", str(scheduling))
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
    """Stacked observability and input matrices over a horizon ``s`` (Varrier 2014, (7)–(8)).

    Every array may carry leading batch axes (one set of matrices per ρ).  ``H_os`` is
    ``(s+1)p × n``; ``H[g]`` is ``(s+1)p × (s+1)k_g`` for input group ``g`` with the
    window's inputs stacked sample by sample, ``[v(k); v(k+1); …; v(k+s)]``.
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


def _check_s(s) -> int:
    if isinstance(s, bool) or not isinstance(s, int | np.integer) or s < 0:
        raise ModelError(f"the horizon s must be an integer >= 0, got {s!r}")
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

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel([[0.5]], [[2.0]], Bu=[[1.0]], dt=1.0)
    >>> stacked_matrices(m, 2).H_os.ravel().tolist()
    [2.0, 1.0, 0.5]
    """
    models = [model] if isinstance(model, FaultModel) else list(model)
    if not models or not all(isinstance(m, FaultModel) for m in models):
        raise ModelError("stacked_matrices needs a FaultModel or a non-empty sequence of FaultModel objects")
    if len(models) == 1:
        if s is None:
            raise ModelError("give the horizon s for a single model (e.g. stacked_matrices(model, 3))")
        s = _check_s(s)
        models = models * (s + 1)
    elif s is not None and _check_s(s) != len(models) - 1:
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
    """Stacked matrices of an :class:`LPVModel` (Varrier 2014, (7)–(8), corrected; (45)).

    Parameters
    ----------
    rho : array_like
        ``mode="frozen"``: ρ values (any shape, real or complex), one frozen window each.
        ``mode="exact"``: windows of ρ with the last axis of length ``s+1``, oldest sample first.
    s : int
        Horizon.
    groups : sequence of str
        Input groups whose maps are wanted.
    """
    s = _check_s(s)
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


def minimal_horizon(n: int, p: int, residuals: int = 1) -> int:
    """Smallest ``s`` with ``q = (s+1)p − n >= residuals`` (cf. Varrier 2014, (13): ``s = ⌈n/m⌉``).

    >>> minimal_horizon(2, 2)
    1
    """
    if n < 0 or p < 1 or residuals < 1:
        raise ModelError(f"need n >= 0, p >= 1 and residuals >= 1, got n={n}, p={p}, residuals={residuals}")
    return max(0, -(-(n + residuals) // p) - 1)


# ---------------------------------------------------------------------------------------------- parity matrix
def regular_rows(H_os: np.ndarray, rtol: float = 1e-9) -> tuple[int, ...]:
    """The first ``n`` linearly independent rows of ``H_os``, in order (Remark 2: ``reg(𝒪)``).

    Raises
    ------
    DesignError
        If ``H_os`` has rank < n (the pair (A, C) is not observable over the horizon).
    """
    H = np.asarray(H_os)
    if H.ndim != 2:
        raise ModelError(f"regular_rows needs one 2-D H_os, got shape {H.shape}")
    n = H.shape[1]
    scale = max(np.linalg.norm(H, 2), np.finfo(float).tiny)
    rows: list[int] = []
    for i in range(H.shape[0]):
        trial = H[rows + [i]]
        if np.linalg.svd(trial, compute_uv=False)[-1] > rtol * scale:
            rows.append(i)
            if len(rows) == n:
                return tuple(rows)
    raise DesignError(
        f"H_os has rank {len(rows)} < n = {n}: the model is not observable over the horizon; "
        "check (A, C) observability or increase s"
    )


def parity_matrix(H_os: np.ndarray, rows: Sequence[int] | None = None, cond_max: float = 1e12) -> np.ndarray:
    """Parity basis ``P = [−H_os2 H_os1⁻¹, I_q]`` with ``P H_os = 0`` (Varrier 2014, (10)–(12)).

    Parameters
    ----------
    H_os : (..., (s+1)p, n) array
        Stacked observability matrices (batch axes allowed, real or complex).
    rows : sequence of int, optional
        Rows forming ``H_os1``; default :func:`regular_rows` of the first batch element.
    cond_max : float
        Largest accepted condition number of ``H_os1``.

    Returns
    -------
    (..., q, (s+1)p) array; the columns of the ``H_os2`` rows hold ``I_q``.

    Examples
    --------
    >>> import numpy as np
    >>> parity_matrix(np.array([[2.0], [1.0], [0.5]])).tolist()
    [[-0.5, 1.0, 0.0], [-0.25, 0.0, 1.0]]
    """
    H = np.asarray(H_os)
    N, n = H.shape[-2], H.shape[-1]
    if rows is None:
        rows = regular_rows(H.reshape((-1, N, n))[0].real)
    rows = [int(i) for i in rows]
    if len(rows) != n or len(set(rows)) != n or not all(0 <= i < N for i in rows):
        raise ModelError(f"rows must be {n} distinct row indices of H_os (0..{N - 1}), got {rows}")
    rest = [i for i in range(N) if i not in rows]
    H1, H2 = H[..., rows, :], H[..., rest, :]
    cond = np.linalg.cond(H1)
    if np.any(~np.isfinite(cond)) or np.max(cond) > cond_max:
        raise DesignError(
            f"H_os1 (rows {rows}) is singular or ill-conditioned (condition number {np.max(cond):.3g}); "
            "pass other rows= or check observability over the scheduling range"
        )
    X = np.swapaxes(np.linalg.solve(np.swapaxes(H1, -1, -2), np.swapaxes(H2, -1, -2)), -1, -2)  # H2 H1⁻¹
    P = np.zeros(H.shape[:-2] + (N - n, N), dtype=X.dtype)
    P[..., rows] = -X
    P[..., rest] = np.eye(N - n)
    return P


# ---------------------------------------------------------------------------------------------- LTI generator
@dataclass(frozen=True, eq=False)
class ParityDesign:
    """An LTI parity-space residual generator and its design data.

    Attributes
    ----------
    generator : FIR :class:`ResidualGenerator`, ``r(k) = Wᵀ(Y_s(k) − H_us U_s(k))`` over ``[k−s, k]``.
    P : (q, (s+1)p) parity basis; W2 : (q, k) free parameter; W : ((s+1)p, k) parity matrix ``Pᵀ W₂``.
    stacked : the stacked matrices; rows : the rows of ``H_os1``; s : horizon.
    """

    generator: ResidualGenerator
    P: np.ndarray
    W2: np.ndarray
    W: np.ndarray
    stacked: StackedMatrices
    rows: tuple[int, ...]
    s: int

    @property
    def q(self) -> int:
        """Dimension of the parity space, ``(s+1)p − n``."""
        return self.P.shape[0]


def _as_w2(W2, q: int) -> np.ndarray:
    W2 = np.eye(q) if W2 is None else np.asarray(W2, dtype=float)
    if W2.ndim == 1:
        W2 = W2[:, None]
    if W2.ndim != 2 or W2.shape[0] != q or not np.all(np.isfinite(W2)):
        raise ModelError(f"W2 must be a finite vector or matrix with q = {q} rows, got shape {W2.shape}")
    if np.linalg.norm(W2) == 0:
        raise DesignError("W2 = 0 gives the trivial residual r = 0; choose a non-zero W2 (Varrier 2014, (28))")
    return W2


def parity_design(model: FaultModel, s: int | None = None, *, W2=None, rows: Sequence[int] | None = None,
                  names: Sequence[str] | None = None, isolates: Sequence[str | None] | None = None) -> ParityDesign:
    """Parity-space residual generator of a discrete LTI model (Varrier 2014, (7)–(12); Chow & Willsky 1984).

    The residual is ``r(k) = W₂ᵀ P (Y_s(k) − H_us U_s(k))`` over the window ``[k−s, k]``,
    built as an FIR :class:`ResidualGenerator` whose state holds the last ``s`` samples of
    ``[u; y]`` (the first ``s`` outputs are start-up transients).

    Parameters
    ----------
    model : FaultModel
        Discrete model; the generator reads all its controls and outputs.
    s : int, optional
        Horizon; default :func:`minimal_horizon` for one residual.
    W2 : array_like, optional
        (q,) or (q, k); default ``I_q`` (the q primary parity residuals).
    rows, names, isolates
        Rows of ``H_os1``; residual names (default ``parity_0, …``); fault tied to each residual.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel([[0.9]], [[1.0], [2.0]], Bu=[[1.0]], dt=0.1)
    >>> d = parity_design(m, 0)
    >>> d.q, bool(np.allclose(d.P @ d.stacked.H_os, 0))
    (1, True)
    """
    if not isinstance(model, FaultModel):
        raise ModelError(f"parity_design needs a FaultModel, got {type(model).__name__}")
    if not model.is_discrete:
        raise ModelError("parity_design needs a discrete model; use model.discretize(dt) first")
    s = minimal_horizon(model.n, model.p) if s is None else _check_s(s)
    st = stacked_matrices(model, s)
    if st.H_os.shape[0] <= model.n:
        raise DesignError(f"horizon s={s} gives (s+1)p = {st.H_os.shape[0]} <= n = {model.n} rows: no parity "
                          f"space; use s >= {minimal_horizon(model.n, model.p)}")
    rows = regular_rows(st.H_os) if rows is None else tuple(int(i) for i in rows)
    P = parity_matrix(st.H_os, rows)
    W2 = _as_w2(W2, P.shape[0])
    W = P.T @ W2
    k, p, mu = W2.shape[1], model.p, len(model.controls)
    Wy = W.T  # (k, (s+1)p)
    Wu = -(W.T @ st.H_us)  # (k, (s+1)mu)
    nv = mu + p
    M = [np.hstack([Wu[:, i * mu:(i + 1) * mu], Wy[:, i * p:(i + 1) * p]]) for i in range(s + 1)]
    A = np.eye(s * nv, k=nv) if s else np.zeros((0, 0))  # z = [v(k−s); …; v(k−1)] shifts up
    B = np.zeros((s * nv, nv))
    if s:
        B[-nv:] = np.eye(nv)
    C = np.hstack(M[:s]) if s else np.zeros((k, 0))
    names = tuple(f"parity_{i}" for i in range(k)) if names is None else tuple(names)
    gen = ResidualGenerator(A, B, C, M[s], model.controls, model.outputs, names, model.dt,
                            tuple(isolates) if isolates is not None else ())
    return ParityDesign(gen, P, W2, W, st, tuple(rows), s)


# ---------------------------------------------------------------------------------------------- LPV runner
def lpv_parity_residuals(
    lpv: LPVModel,
    trace: Trace,
    rho,
    s: int,
    *,
    W2: np.ndarray | Callable[[np.ndarray], np.ndarray] | None = None,
    mode: str = "frozen",
    rows: Sequence[int] | None = None,
    names: Sequence[str] | None = None,
) -> Residuals:
    """LPV parity residual ``r(k) = W₂(ρ_k)ᵀ P(ρ) (Y_s(k) − H_us(ρ) U_s(k))``, P recomputed every sample.

    Varrier 2014, (9), (12) and (16), on the causal window ``[k−s, k]``.

    Parameters
    ----------
    lpv : LPVModel
    trace : Trace
        Must hold the controls and outputs of ``lpv`` by name.
    rho : (N,) array_like
        Scheduling parameter per sample (e.g. ``1 / speed``).
    s : int
        Horizon.
    W2 : array, callable or None
        (q,) or (q, k) constant; or a function of a 1-D array of ρ_k returning (N, q) or
        (N, q, k) (a scheduled ``W₂(ρ)``, e.g. :meth:`RobustParityDesign.w2`); default ``I_q``.
    mode : ``"frozen"`` (ρ frozen at ρ_k over the window, §4.6.1) or ``"exact"``
        (time-varying stacking with ρ_{k−s}, …, ρ_k).
    rows : rows of ``H_os1``; default :func:`regular_rows` at the median ρ.
    names : residual names; default ``parity_0, …``.

    Returns
    -------
    Residuals
        The first ``s`` samples (incomplete window) are NaN and marked invalid.
    """
    s = _check_s(s)
    u = trace.columns("u", lpv.controls)
    y = trace.columns("y", lpv.outputs)
    rho = np.asarray(rho, dtype=float).ravel()
    N = len(trace)
    if rho.shape != (N,):
        raise DataError(f"rho has {rho.size} samples but the trace has {N}; give one scheduling value per sample")
    for label, arr in (("rho", rho), ("controls", u), ("outputs", y)):
        if not np.all(np.isfinite(arr)):
            raise DataError(f"{label} contain NaN/inf at sample {int(np.argwhere(~np.isfinite(arr))[0][0])}; "
                            "clean the data first")
    if N <= s:
        raise DataError(f"the trace has {N} samples; a horizon s={s} needs more than {s}")
    win = np.lib.stride_tricks.sliding_window_view
    Y = win(y, s + 1, axis=0).transpose(0, 2, 1).reshape(N - s, -1)  # [y(k−s); …; y(k)]
    U = win(u, s + 1, axis=0).transpose(0, 2, 1).reshape(N - s, -1)
    sched = rho[s:] if mode == "frozen" else win(rho, s + 1)
    st = lpv_stacked_matrices(lpv, sched, s, mode=mode, groups=("u",))
    if rows is None:
        rows = regular_rows(lpv_stacked_matrices(lpv, float(np.median(rho)), s, groups=()).H_os)
    P = parity_matrix(st.H_os, rows)
    z = np.einsum("kqj,kj->kq", P, Y - np.einsum("kij,kj->ki", st.H_us, U))
    q = P.shape[-2]
    if callable(W2):
        w = np.asarray(W2(rho[s:]), dtype=float)
        if w.ndim == 2:
            w = w[..., None]
        if w.shape[:2] != (N - s, q):
            raise ModelError(f"the W2 function returned shape {w.shape}; need ({N - s}, {q}) or ({N - s}, {q}, k)")
        r = np.einsum("kqi,kq->ki", w, z)
    else:
        r = z @ _as_w2(W2, q)
    k = r.shape[1]
    out = np.full((N, k), np.nan)
    out[s:] = r
    valid = np.arange(N) >= s
    names = tuple(f"parity_{i}" for i in range(k)) if names is None else tuple(names)
    meta = {"trace": dict(trace.meta), "s": s, "mode": mode, "rows": list(rows)}
    return Residuals(trace.t, out, names, (), valid, meta)


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
    """One unknown scalar δ: ``Ā(ρ) = A₀(ρ) + δ Ã(ρ)``, ``C̄(ρ) = C₀(ρ) + δ C̃(ρ)`` (Varrier 2014, (2), (5)).

    ``A`` and ``C`` are constant matrices or mappings power -> coefficient of ``ρ^power``;
    ``n`` and ``p`` are the model's sizes (checked against the LPV model when stacking).
    As in (5), ``B`` and ``D`` are certain; δ is taken constant over the window (note G22).
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
    """Stacked matrices of the uncertain model expanded in the monomials of δ (Varrier 2014, (14)).

    ``nominal`` holds ``H_os, H_us, …`` at δ = 0; ``tilde[kind][e]`` is the coefficient of the
    monomial ``δ^e`` (``e`` an exponent tuple, total degree ≥ 1) in the stacked ``kind``
    map, ``kind`` in ``"os"`` and the input groups ``"u", "d", "f", "w"``.  Printed (14) has
    ``H̃_ds U_s``; it is ``H̃_ds U_ds`` (typo, note G17).
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
    """δ-expansion of the stacked matrices of an uncertain LPV model (Varrier 2014, (5), (14)).

    ``Σ_e δ^e tilde[kind][e]`` plus the nominal map equals the stacked map of the model with
    ``Ā = A₀ + Σ δ_i Ã_i`` and ``C̄ = C₀ + Σ δ_i C̃_i`` exactly (a polynomial identity in δ).
    ``rho`` and ``mode`` are as in :func:`lpv_stacked_matrices`.
    """
    s = _check_s(s)
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
