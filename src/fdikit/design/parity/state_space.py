"""State-space parity space for discrete LTI and LPV models (Varrier et al. 2014, §3).

The stacked matrices of the parity relation (7)–(8) (``Y_s = H_os x + H_us U_s + …``) are built
in :mod:`fdikit.lpv`.  The parity matrix (10)–(12) splits ``H_os`` into ``n`` regular rows
``H_os1`` (the "regular part of the observability matrix", Remark 2: the first linearly
independent rows, in order) and the ``q = (s+1)p − n`` others ``H_os2``, and sets::

    P(ρ) = [−H_os2 H_os1⁻¹,  I_q]   (columns permuted back to the row order of H_os),   P H_os = 0

so that ``r = W₂ᵀ P (Y_s − H_us U_s)`` (9), (12) is zero on healthy, noise-free data for any
``W₂``.  fdikit runs the window backwards, ``Y_s(k) = [y(k−s); …; y(k)]``, so the residual
at sample ``k`` is causal (uses samples up to ``k`` only); in the frozen mode ρ is frozen at the
newest sample ``ρ_k``.  :func:`parity_design` builds the LTI residual generator (an FIR
:class:`~fdikit.residuals.ResidualGenerator`); :func:`lpv_parity_residuals` recomputes ``P(ρ)``
at every sample of a trace (16).  The robust choice of ``W₂`` is in
:mod:`fdikit.design.parity.criteria`, :mod:`fdikit.design.parity.lmi` and :mod:`fdikit.design.parity.robust`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit import linalg, validate
from fdikit.design.labels import fault_label, label_generator, residual_labels, warn_unlisted_faults
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.fault_maps import split_fault_name
from fdikit.lpv import LPVModel, StackedMatrices, check_horizon, lpv_stacked_matrices, stacked_matrices
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator, Residuals
from fdikit.trace import Trace

__all__ = [
    "minimal_horizon",
    "regular_rows",
    "parity_matrix",
    "ParityDesign",
    "parity_design",
    "stacked_fault_map",
    "RESPONSE_RTOL",
    "lpv_parity_residuals",
]


def minimal_horizon(n: int, p: int, residuals: int = 1) -> int:
    """Smallest ``s`` with ``q = (s+1)p − n >= residuals`` (cf. Varrier et al. 2014, (13): ``s = ⌈n/m⌉``).

    Parameters
    ----------
    n, p : int
        Number of states and of outputs.
    residuals : int
        Parity-space dimension ``q`` wanted (default 1).

    Returns
    -------
    int
        The horizon ``s >= 0``.

    Raises
    ------
    ParameterError
        ``n < 0``, ``p < 1`` or ``residuals < 1``.

    Examples
    --------
    >>> minimal_horizon(2, 2), minimal_horizon(2, 2, residuals=3)
    (1, 2)

    References
    ----------
    Varrier et al. 2014, §3.3, (13).
    """
    if n < 0 or p < 1 or residuals < 1:
        raise ParameterError(f"need n >= 0, p >= 1 and residuals >= 1, got n={n}, p={p}, residuals={residuals}")
    return max(0, -(-(n + residuals) // p) - 1)


# ---------------------------------------------------------------------------------------------- parity matrix
def regular_rows(H_os: np.ndarray, rtol: float = 1e-9) -> tuple[int, ...]:
    """The first ``n`` linearly independent rows of ``H_os``, in order (Remark 2: ``reg(𝒪)``).

    Parameters
    ----------
    H_os : ((s+1)p, n) array_like
        Stacked observability matrix.
    rtol : float
        A row is independent when it raises the smallest singular value above ``rtol ‖H_os‖₂`` (default 1e-9).

    Returns
    -------
    tuple of int
        The ``n`` row indices forming ``H_os1``.

    Raises
    ------
    ParameterError
        ``H_os`` is not 2-D.
    DesignError
        If ``H_os`` has rank < n (the pair (A, C) is not observable over the horizon).

    Examples
    --------
    >>> import numpy as np
    >>> regular_rows(np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0]]))
    (0, 2)

    References
    ----------
    Varrier et al. 2014, §3.2, Remark 2, (10).
    """
    H = np.asarray(H_os)
    if H.ndim != 2:
        raise ParameterError(f"regular_rows needs one 2-D H_os, got shape {H.shape}")
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
    """Parity basis ``P = [−H_os2 H_os1⁻¹, I_q]`` with ``P H_os = 0`` (Varrier et al. 2014, (10)–(12)).

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
    (..., q, (s+1)p) array
        The parity basis; the columns of the ``H_os2`` rows hold ``I_q``.

    Raises
    ------
    ParameterError
        ``rows`` that are not ``n`` distinct row indices.
    DesignError
        ``H_os1`` singular or with condition number above ``cond_max``; ``H_os`` of rank < n.

    Examples
    --------
    >>> import numpy as np
    >>> parity_matrix(np.array([[2.0], [1.0], [0.5]])).tolist()
    [[-0.5, 1.0, 0.0], [-0.25, 0.0, 1.0]]

    References
    ----------
    Varrier et al. 2014, §3.2, (10)–(12).
    """
    H = np.asarray(H_os)
    N, n = H.shape[-2], H.shape[-1]
    if rows is None:
        rows = regular_rows(H.reshape((-1, N, n))[0].real)
    rows = [int(i) for i in rows]
    if len(rows) != n or len(set(rows)) != n or not all(0 <= i < N for i in rows):
        raise ParameterError(f"rows must be {n} distinct row indices of H_os (0..{N - 1}), got {rows}")
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
class ParityDesign(FieldReport):
    """An LTI parity-space residual generator and its design data.

    Attributes
    ----------
    generator : FIR ResidualGenerator, ``r(k) = Wᵀ(Y_s(k) − H_us U_s(k))`` over ``[k−s, k]``.
    P : (q, (s+1)p) parity basis.
    W2 : (q, k) free parameter.
    W : ((s+1)p, k) parity matrix ``Pᵀ W₂``.
    stacked : the stacked matrices (:class:`~fdikit.lpv.StackedMatrices`).
    rows : the rows of ``H_os1``.
    s : horizon.
    model : the FaultModel of the design (keyword-only; set by :func:`parity_design`).
    targets, nuisance : the faults the residual must see and those it is decoupled from (keyword-only).
    responses : relative response ``‖Wᵀ H_f‖₂ / (‖W‖₂ ‖H_f‖₂)`` of the residual to each fault input of the
        model and each named fault over the window (keyword-only; 0 up to round-off for a decoupled fault).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> d = parity_design(FaultModel([[0.9]], [[1.0], [2.0]], Bu=[[1.0]], dt=0.1), 0)
    >>> d.q, d.rows, d.P.tolist(), d.W.shape
    (1, (0,), [[-2.0, 1.0]], (2, 1))

    References
    ----------
    Varrier et al. 2014, §3.1–3.2, (7)–(12).
    """

    generator: ResidualGenerator
    P: np.ndarray
    W2: np.ndarray
    W: np.ndarray
    stacked: StackedMatrices
    rows: tuple[int, ...]
    s: int
    targets: tuple[str, ...] = field(default=(), kw_only=True)
    nuisance: tuple[str, ...] = field(default=(), kw_only=True)
    responses: dict = field(default_factory=dict, kw_only=True)

    @property
    def q(self) -> int:
        """Dimension of the parity space, ``(s+1)p − n``."""
        return self.P.shape[0]

    def report(self) -> dict:
        """``s`` (horizon), ``q`` (parity-space dimension), ``rows`` (of ``H_os1``), ``P`` (parity basis),
        ``W2`` (free parameter), ``W`` (parity matrix ``Pᵀ W₂``), ``targets``, ``nuisance`` and ``responses``
        (relative response to each fault)."""
        return {"s": self.s, "q": self.q, "rows": self.rows, "P": self.P, "W2": self.W2, "W": self.W,
                "targets": self.targets, "nuisance": self.nuisance, "responses": dict(self.responses)}


#: Relative response ``‖Wᵀ H_f‖ / (‖W‖ ‖H_f‖)`` at or below which a parity residual counts as blind to a fault: far
#: above the round-off of ``P`` and of a null-space basis (~1e-13 for condition numbers up to 1e3), far below the
#: response of a fault that is seen.
RESPONSE_RTOL = 1e-8


def _fault_io(model: FaultModel, name: str, F=None) -> tuple[np.ndarray, np.ndarray]:
    """``(B_f, D_f)`` of a named fault: a fault input's columns, a sensor's ``(0, e_i)``, an actuator's ``Bu``/``Du``
    columns, or an explicit state-space map ``(F, 0)``."""
    if F is not None:
        F = np.atleast_2d(validate.as_array(f"fault map {name!r}", F, error=ModelError))
        F = F.T if F.shape[0] != model.n and F.shape[1] == model.n else F
        if F.shape[0] != model.n:
            raise ModelError(f"fault map {name!r} has {F.shape[0]} rows; the model has {model.n} states")
        return F, np.zeros((model.p, F.shape[1]))
    kind, base, _ = split_fault_name(model, name)
    if kind == "fault":
        j = [model.index("f", base)[0]]
        return model.Bf[:, j], model.Df[:, j]
    if kind == "sensor":
        return np.zeros((model.n, 1)), np.eye(model.p)[:, [model.outputs.index(base)]]
    j = [model.controls.index(base)]
    return model.Bu[:, j], model.Du[:, j]


def _fault_specs(model: FaultModel, spec, what: str, exclude: Sequence[str] = ()) -> dict:
    """Fault name -> ``(B_f, D_f)`` for ``targets=`` / ``nuisance=`` (``'others'``: every fault input not excluded)."""
    if spec is None:
        raise ParameterError(f"{what}=None is not a fault set; use () for none" +
                             (" or 'others' for every other fault input" if what == "nuisance" else ""))
    if isinstance(spec, str) and spec == "others" and what == "nuisance":
        return {f: _fault_io(model, f) for f in model.faults if f not in exclude}
    if isinstance(spec, Mapping):
        return {str(k): _fault_io(model, str(k), F) for k, F in spec.items()}
    names = [spec] if isinstance(spec, str) else list(spec)
    return {fault_label(model, nm): _fault_io(model, nm) for nm in names}


def stacked_fault_map(model: FaultModel, B: np.ndarray, D: np.ndarray, s: int) -> np.ndarray:
    """Window map ``((s+1)p, (s+1)k)`` of a fault entering as ``x⁺ = … + B f``, ``y = … + D f``.

    Block ``(i, j)`` is ``D`` for ``j = i`` and ``C A^{i−j−1} B`` for ``j < i``: the ``H_fs`` of
    :class:`~fdikit.lpv.StackedMatrices` for one fault, with the window's samples stacked in the same order.

    Parameters
    ----------
    model : FaultModel
        Discrete model (its ``A``, ``C``).
    B, D : (n, k), (p, k) array_like
        How the fault enters the states and the outputs.
    s : int
        Horizon.

    Returns
    -------
    numpy.ndarray
        The ((s+1)p, (s+1)k) lower block-triangular Toeplitz map.

    Raises
    ------
    ParameterError
        A bad horizon.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel([[0.5]], [[2.0]], dt=1.0)
    >>> stacked_fault_map(m, [[1.0]], [[0.0]], 2).tolist()
    [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 2.0, 0.0]]

    References
    ----------
    Varrier et al. 2014, §3.1, (7)–(8).
    """
    s = check_horizon(s)
    B, D = np.atleast_2d(np.asarray(B, dtype=float)), np.atleast_2d(np.asarray(D, dtype=float))
    p, k = model.p, B.shape[1]
    markov = [D]
    Ak = np.eye(model.n)
    for _ in range(s):
        markov.append(model.C @ Ak @ B)
        Ak = model.A @ Ak
    H = np.zeros(((s + 1) * p, (s + 1) * k))
    for i in range(s + 1):
        for j in range(i + 1):
            H[i * p:(i + 1) * p, j * k:(j + 1) * k] = markov[i - j]
    return H


def _relative_response(W: np.ndarray, H: np.ndarray) -> float:
    scale = np.linalg.norm(W, 2) * np.linalg.norm(H, 2)
    return float(np.linalg.norm(W.T @ H, 2) / scale) if scale > 0 else 0.0


def _as_w2(W2, q: int) -> np.ndarray:
    W2 = np.eye(q) if W2 is None else validate.as_array("W2", W2, finite=False)
    if W2.ndim == 1:
        W2 = W2[:, None]
    if W2.ndim != 2 or W2.shape[0] != q or not np.all(np.isfinite(W2)):
        raise ParameterError(f"W2 must be a finite vector or matrix with q = {q} rows, got shape {W2.shape}")
    if np.linalg.norm(W2) == 0:
        raise DesignError("W2 = 0 gives the trivial residual r = 0; choose a non-zero W2 (Varrier 2014, (28))")
    return W2


def parity_design(model: FaultModel, s: int | None = None, *, W2=None, rows: Sequence[int] | None = None,
                  targets: Sequence[str] | Mapping[str, np.ndarray] | str = (),
                  nuisance: Sequence[str] | Mapping[str, np.ndarray] | str = (),
                  names: Sequence[str] | None = None,
                  isolates: Sequence[str | None] | Mapping[str, str | None] | None = None) -> ParityDesign:
    """Parity-space residual generator of a discrete LTI model (Varrier et al. 2014, (7)–(12); Chow & Willsky 1984).

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
        (q,) or (q, k); default ``I_q`` (the q primary parity residuals).  With ``nuisance``, ``W2`` weights
        the ``q'`` directions of the parity space left after decoupling ((q',) or (q', k); default all of them):
        the stored ``W2`` is that basis times the given one.
    rows : sequence of int, optional
        Rows of ``H_os1``.
    targets : str, sequence of str or mapping, optional
        Faults the residual must see (fault names, docs/ARCHITECTURE.md "faults in APIs", or a mapping
        name -> state-space map ``F``); a target the decoupled residual is blind to raises :class:`DesignError`.
    nuisance : str, sequence of str or mapping, optional
        Faults the residual is decoupled from, over the whole window (``W₂ᵀ P H_f = 0``): ``()`` none,
        ``'others'`` every fault input of the model that is not a target, fault names or explicit maps.
    names, isolates : optional
        Residual names (default ``parity_0, …``) and the fault each residual isolates (default the target when
        there is one, else None), as :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    ParityDesign
        The FIR generator and ``P``, ``W₂``, ``W``, the stacked matrices, the rows of ``H_os1`` and the
        residual's relative response to each fault (``responses``).  When the residual is tied to faults
        (``targets`` or ``isolates``) and also responds (relative response above :data:`RESPONSE_RTOL`) to a
        fault input of the model that is neither a target nor nuisance, a :class:`~fdikit.errors.FdiWarning`
        lists those faults: an alarm could be one of them.

    Raises
    ------
    ParameterError
        ``model`` not a FaultModel; a bad horizon, ``rows`` or ``W2`` shape.
    ModelError
        A continuous model.
    DesignError
        No parity space at horizon ``s``; ``H_os`` of rank < n or ``H_os1`` ill-conditioned; ``W2 = 0``; a
        nuisance set that fills the parity space (nothing is left after decoupling); a target the residual does
        not see.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel([[0.9]], [[1.0], [2.0]], Bu=[[1.0]], dt=0.1)
    >>> d = parity_design(m, 0)
    >>> d.q, bool(np.allclose(d.P @ d.stacked.H_os, 0))
    (1, True)

    Two sensors of one state: the residual that ignores the first sensor's fault isolates the second's.

    >>> m2 = FaultModel([[0.9]], [[1.0], [1.0]], Bu=[[1.0]], dt=0.1).with_sensor_faults(["y0", "y1"])
    >>> d2 = parity_design(m2, 1, targets="y1_sensor", nuisance="others")
    >>> d2.generator.isolates, d2.responses["y0_sensor"] < 1e-12, d2.responses["y1_sensor"] > 0.1
    (('y1_sensor',), True, True)

    References
    ----------
    Varrier et al. 2014, §3.1–3.2, (7)–(12).
    """
    if not isinstance(model, FaultModel):
        raise ParameterError(f"parity_design needs a FaultModel, got {type(model).__name__}")
    if not model.is_discrete:
        raise ModelError("parity_design needs a discrete model; use model.discretize(dt) first")
    s = minimal_horizon(model.n, model.p) if s is None else check_horizon(s)
    st = stacked_matrices(model, s)
    if st.H_os.shape[0] <= model.n:
        raise DesignError(f"horizon s={s} gives (s+1)p = {st.H_os.shape[0]} <= n = {model.n} rows: no parity "
                          f"space; use s >= {minimal_horizon(model.n, model.p)}")
    rows = regular_rows(st.H_os) if rows is None else tuple(int(i) for i in rows)
    P = parity_matrix(st.H_os, rows)
    tg = _fault_specs(model, targets, "targets")
    nu = _fault_specs(model, nuisance, "nuisance", exclude=tuple(tg))
    if set(tg) & set(nu):
        raise ParameterError(f"faults {sorted(set(tg) & set(nu))} are both targets and nuisance; name each once")
    Hf = {k: stacked_fault_map(model, B, D, s) for k, (B, D) in (tg | nu).items()}
    for f in model.faults:
        if f not in Hf:
            Hf[f] = stacked_fault_map(model, *_fault_io(model, f), s)
    if nu:
        M = P @ np.hstack([Hf[k] for k in nu])
        basis = linalg.null(M.T)
        if basis.shape[1] == 0:
            kk = sum(B.shape[1] for B, _ in nu.values())
            raise DesignError(
                f"the q = {P.shape[0]} parity directions at horizon s={s} cannot be decoupled from nuisance "
                f"{list(nu)}: P H_f has rank {linalg.rank(M)} = q (the nuisance faults over the window span the parity "
                f"space; each step adds p = {model.p} directions and {kk} nuisance columns); use a longer horizon s or "
                "fewer nuisance faults")
        W2 = basis @ _as_w2(W2, basis.shape[1])
    else:
        W2 = _as_w2(W2, P.shape[0])
    W = P.T @ W2
    responses = {k: _relative_response(W, H) for k, H in Hf.items()}
    blind = [k for k in tg if responses[k] <= RESPONSE_RTOL]
    if blind:
        raise DesignError(f"the parity residual does not see target(s) {blind} (relative response "
                          f"{[f'{responses[k]:.3g}' for k in blind]} <= {RESPONSE_RTOL:g}) once decoupled from "
                          f"{list(nu)}; drop them from nuisance, choose another W2 or a longer horizon")
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
    gen = ResidualGenerator(A, B, C, M[s], model.controls, model.outputs, tuple(f"parity_{i}" for i in range(k)),
                            model.dt)
    gen = label_generator(gen, model, names, isolates, default_isolates=[next(iter(tg))] * k if len(tg) == 1 else None)
    claimed = set(tg) | {f for f in gen.isolates if f is not None}
    if claimed:
        warn_unlisted_faults("parity_design", {f: responses[f] for f in model.faults
                                               if f not in claimed and f not in nu and responses[f] > RESPONSE_RTOL})
    return ParityDesign(gen, P, W2, W, st, tuple(rows), s, model=model, targets=tuple(tg), nuisance=tuple(nu),
                        responses=responses)


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
    isolates: Sequence[str | None] | None = None,
) -> Residuals:
    """LPV parity residual ``r(k) = W₂(ρ_k)ᵀ P(ρ) (Y_s(k) − H_us(ρ) U_s(k))``, P recomputed every sample.

    Varrier et al. 2014, (9), (12) and (16), on the causal window ``[k−s, k]``.

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
    isolates : the fault each residual isolates (None: detection only); default none.

    Returns
    -------
    Residuals
        The first ``s`` samples (incomplete window) are NaN and marked invalid.

    Raises
    ------
    ParameterError
        A bad horizon, ``rows`` or ``W2`` (or a ``W2`` function returning the wrong shape).
    ModelError
        An unknown ``mode`` (raised by :func:`fdikit.lpv.lpv_stacked_matrices`).
    DataError
        ``rho`` without one value per sample; NaN/inf in ``rho``, controls or outputs; a trace of at most
        ``s`` samples or without the model's signals.
    DesignError
        ``H_os`` of rank < n, or ``H_os1`` ill-conditioned somewhere on the trace.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants import varrier_lateral_lpv
    >>> from fdikit.simulate import simulate
    >>> lpv = varrier_lateral_lpv()
    >>> tr = simulate(lpv.at(0.05), duration=2.0, u=lambda t: [0.02 * np.sin(t)], x0=[0.01, 0.05])
    >>> r = lpv_parity_residuals(lpv, tr, np.full(len(tr), 0.05), 3)
    >>> r.r.shape, int(r.valid.sum()), bool(np.abs(r.r[3:]).max() < 1e-9)
    ((101, 6), 98, True)

    References
    ----------
    Varrier et al. 2014, (9), (12), (16); §4.6.1 (frozen ρ).
    """
    s = check_horizon(s)
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
            raise ParameterError(f"the W2 function returned shape {w.shape}; need ({N - s}, {q}) or ({N - s}, {q}, k)")
        r = np.einsum("kqi,kq->ki", w, z)
    else:
        r = z @ _as_w2(W2, q)
    k = r.shape[1]
    out = np.full((N, k), np.nan)
    out[s:] = r
    valid = np.arange(N) >= s
    names, isolates = residual_labels(lpv, k, names, isolates, default_names=[f"parity_{i}" for i in range(k)])
    meta = {"trace": dict(trace.meta), "s": s, "mode": mode, "rows": list(rows)}
    return Residuals(trace.t, out, names, isolates, valid, meta)
