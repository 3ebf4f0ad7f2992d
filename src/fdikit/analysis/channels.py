"""Transfer channels of internal forms: filters and banks, minimal channels, H∞ and H2 norms, responses.

The performance metrics of :mod:`fdikit.analysis.performance` and the structure matrices of
:mod:`fdikit.analysis.structure` work on the *internal form* of a filter: a
:class:`~fdikit.model.FaultModel` from ``(u, d, f, w)`` to the residuals ``r``
(:meth:`fdikit.residuals.ResidualGenerator.internal_form`, ``DesignResult.internal_form()``;
Varga's ``R(λ) = [R_u R_d R_f R_w]``).  This module holds what they share:

* :func:`internal_forms` — one filter or a bank: a sequence or mapping of internal forms, or one
  internal form split into filters by ``groups=`` (residual rows of each filter);
* :func:`minimal_channel` — a minimal realisation of the channel from some inputs to some residuals.
  fdikit's internal forms carry the plant's states, so an unstable plant mode cancelled by the filter
  is still an eigenvalue of ``A``; stability and norms are decided on the minimal channel
  (python-control's ``minreal``, SLICOT ``TB01PD``);
* :func:`hinf_norm` (python-control's ``linfnorm``, SLICOT ``AB13DD``, relative tolerance ``1e-10``),
  :func:`h2_norm` (a Lyapunov solve), both infinite for an unstable channel;
* :func:`frequency_response` at given frequencies, refusing a frequency that is a pole.

References
----------
Varga (2017), §3.1 (internal form of a filter) and §3.4 (structure matrices); fdtools.

Examples
--------
>>> from fdikit import FaultModel
>>> R = FaultModel(A=[[-2.0]], C=[[1.0]], Bf=[[2.0]], faults=["f"], outputs=["r"])
>>> round(hinf_norm(minimal_channel(R, inputs=["f"]))[0], 9)   # 2/(s + 2): peak 1 at ω = 0
1.0
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import ModelError, ParameterError
from fdikit.model import GROUPS, FaultModel

__all__ = [
    "Channel",
    "InternalForms",
    "internal_forms",
    "minimal_channel",
    "is_stable",
    "check_stable",
    "input_columns",
    "hinf_norm",
    "h2_norm",
    "check_freqs",
    "frequency_response",
]

_EPS = np.finfo(float).eps
#: Relative tolerance of the H∞ norm (python-control ``linfnorm``, SLICOT AB13DD).
HINF_TOL = 1e-10
#: Rank tolerance of the minimal realisations (SLICOT TB01PD's ``TOL``, the reference's ``atol = 1e-7``): the
#: default ``n² ε`` keeps the cancelled modes of a filter in series with a badly scaled plant (the Niemann 1998
#: bank discretised at 0.01 s keeps six modes in a decoupled channel whose gain is 1e-16).
MINREAL_TOL = 1e-7


@dataclass(frozen=True, eq=False)
class Channel:
    """A state-space realisation ``(A, B, C, D)`` of one transfer channel (``dt`` None: continuous).

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        The realisation (``A`` may be ``(0, 0)``: a static channel).
    dt : float or None
        Sample time (None: continuous).

    Examples
    --------
    >>> ch = Channel(np.array([[-1.0]]), np.array([[1.0]]), np.array([[1.0]]), np.zeros((1, 1)))
    >>> ch.n
    1
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float | None = None

    @property
    def n(self) -> int:
        """Order of the realisation."""
        return self.A.shape[0]


@dataclass(frozen=True, eq=False)
class InternalForms:
    """One filter or a bank of filters, each as an internal form.

    Attributes
    ----------
    names : tuple of str
        Filter names (one for a single filter).
    forms : tuple of FaultModel
        The internal forms, all with the same input groups and sample time.
    bank : bool
        Whether a bank was given (a sequence, a mapping or ``groups=``), even of one filter.
    members : tuple of tuple of str
        The residual names of each filter.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=-np.eye(2), C=np.eye(2), Bf=np.eye(2), faults=["a", "b"], outputs=["r1", "r2"])
    >>> bank = internal_forms(R, groups=[["r1"], ["r2"]])
    >>> bank.names, bank.members, bank.faults
    (('filter0', 'filter1'), (('r1',), ('r2',)), ('a', 'b'))
    """

    names: tuple[str, ...]
    forms: tuple[FaultModel, ...]
    bank: bool
    members: tuple[tuple[str, ...], ...]

    @property
    def faults(self) -> tuple[str, ...]:
        """Fault input names (shared by every filter)."""
        return self.forms[0].faults

    @property
    def noise(self) -> tuple[str, ...]:
        """Noise input names (shared by every filter)."""
        return self.forms[0].noise

    @property
    def dt(self) -> float | None:
        """Sample time (None: continuous)."""
        return self.forms[0].dt


def _one_form(name: str, value) -> FaultModel:
    if isinstance(value, FaultModel):
        return value
    from fdikit.residuals import ResidualGenerator

    if isinstance(value, ResidualGenerator):
        raise ParameterError(f"{name} is a ResidualGenerator; pass its internal form generator.internal_form(model) "
                             "(a FaultModel from (u, d, f, w) to the residuals) or the design result")
    internal = getattr(value, "internal_form", None)
    if callable(internal):
        form = internal()
        if not isinstance(form, FaultModel):
            raise ParameterError(f"{name}.internal_form() returned {type(form).__name__}, not a FaultModel")
        return form
    raise ParameterError(f"{name} must be an internal form (FaultModel from (u, d, f, w) to r) or a design result "
                         f"with internal_form(), got {type(value).__name__}")


def _split(form: FaultModel, groups) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    if isinstance(groups, Mapping):
        names, specs = tuple(str(k) for k in groups), list(groups.values())
    elif isinstance(groups, Sequence) and not isinstance(groups, str):
        specs = list(groups)
        names = tuple(f"filter{i}" for i in range(len(specs)))
    else:
        raise ParameterError(f"groups must be a mapping filter -> residuals or a sequence of residual lists, "
                             f"got {type(groups).__name__}")
    if not specs:
        raise ParameterError("groups is empty; give the residual rows of at least one filter")
    members = []
    for nm, rows in zip(names, specs):
        if isinstance(rows, (str, int, np.integer)):
            rows = [rows]
        rows = list(rows)
        if not rows:
            raise ParameterError(f"filter {nm!r} of groups has no residuals")
        out = []
        for r in rows:
            if isinstance(r, (int, np.integer)) and not isinstance(r, bool):
                if not 0 <= r < form.p:
                    raise ParameterError(f"filter {nm!r}: residual row {r} is out of range (the form has {form.p})")
                out.append(form.outputs[int(r)])
            elif isinstance(r, str):
                if r not in form.outputs:
                    raise ParameterError(f"filter {nm!r}: no residual named {r!r}; the form has {list(form.outputs)}")
                out.append(r)
            else:
                raise ParameterError(f"filter {nm!r}: residuals are given by name or row index, got {r!r}")
        if len(set(out)) != len(out):
            raise ParameterError(f"filter {nm!r} lists a residual twice: {out}")
        members.append(tuple(out))
    return names, tuple(members)


def internal_forms(sysr, groups=None) -> InternalForms:
    """One filter or a bank, as internal forms with shared input groups.

    Parameters
    ----------
    sysr : FaultModel, design result, sequence or mapping of them
        A single internal form (or a ``DesignResult``, whose ``internal_form()`` is taken); a sequence
        (filters ``filter0, filter1, …``) or mapping ``name -> form`` is a bank.
    groups : mapping or sequence, optional
        With a single form: the residuals of each filter of a stacked bank, by name or row index
        (``{"filter_a": ["r0", "r1"], ...}`` or ``[[0, 1], [2]]``).

    Returns
    -------
    InternalForms
        The filters, their names and residuals.

    Raises
    ------
    ParameterError
        For a wrong type, an empty bank, or ``groups`` naming unknown residuals.
    ModelError
        When the filters of a bank differ in their inputs or sample time.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0], [2.0]], Bf=[[1.0]], faults=["f"], outputs=["a", "b"])
    >>> bank = internal_forms(R, groups={"one": ["a"], "two": [1]})
    >>> bank.names, bank.members, bank.bank
    (('one', 'two'), (('a',), ('b',)), True)
    """
    if groups is not None:
        form = _one_form("sysr", sysr)
        names, members = _split(form, groups)
        forms = tuple(form.submodel(outputs=list(m)) for m in members)
        return InternalForms(names, forms, True, members)
    if isinstance(sysr, Mapping):
        names = tuple(str(k) for k in sysr)
        forms = tuple(_one_form(f"sysr[{k!r}]", v) for k, v in sysr.items())
        bank = True
    elif isinstance(sysr, (list, tuple)):
        forms = tuple(_one_form(f"sysr[{i}]", v) for i, v in enumerate(sysr))
        names = tuple(f"filter{i}" for i in range(len(forms)))
        bank = True
    else:
        forms, names, bank = (_one_form("sysr", sysr),), ("filter",), False
    if not forms:
        raise ParameterError("the bank is empty; give at least one internal form")
    first = forms[0]
    for nm, f in zip(names[1:], forms[1:]):
        for g in GROUPS:
            if f.inputs[g] != first.inputs[g]:
                raise ModelError(f"filter {nm!r} has inputs {list(f.inputs[g])} in group {g!r}, filter "
                                 f"{names[0]!r} has {list(first.inputs[g])}; the filters of a bank share their inputs")
        if (f.dt is None) != (first.dt is None) or (f.dt is not None and not np.isclose(f.dt, first.dt)):
            raise ModelError(f"filter {nm!r} has dt={f.dt}, filter {names[0]!r} dt={first.dt}; a bank shares dt")
    return InternalForms(names, forms, bank, tuple(f.outputs for f in forms))


def minimal_channel(form: FaultModel, inputs: Sequence[str] | None = None, outputs: Sequence[str] | None = None,
                    *, output_mask=None) -> Channel:
    """Minimal realisation of the channel from ``inputs`` to ``outputs`` of an internal form.

    Parameters
    ----------
    form : FaultModel
        The internal form.
    inputs : sequence of str, optional
        Input names (any group); default all inputs.
    outputs : sequence of str, optional
        Residual names; default all.
    output_mask : (p, m) array_like of bool, optional
        Element-wise mask: the channel is ``mask .* G`` (each column realised with the rows of its mask;
        the columns are stacked, so the order is at most ``m`` times the form's).

    Returns
    -------
    Channel
        A minimal realisation (controllable and observable part), by python-control's ``minreal``.

    Raises
    ------
    ModelError
        An input name the form does not have.
    ParameterError
        An ``output_mask`` of the wrong shape.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0, 0.0], [0.0, 3.0]], C=[[1.0, 0.0]], Bf=[[1.0], [1.0]], faults=["f"])
    >>> minimal_channel(R, ["f"]).n   # the unstable mode is unobservable
    1
    """
    names = [nm for g in GROUPS for nm in form.inputs[g]]
    if inputs is None:
        cols = list(range(len(names)))
    else:
        missing = [nm for nm in inputs if nm not in names]
        if missing:
            raise ModelError(f"no input named {missing}; the internal form has {names}")
        cols = [names.index(nm) for nm in inputs]
    rows = list(range(form.p)) if outputs is None else form.index("outputs", list(outputs))
    B, C, D = form.B[:, cols], form.C[rows], form.D[rows][:, cols]
    if output_mask is not None:
        mask = np.asarray(output_mask, dtype=bool)
        if mask.shape != D.shape:
            raise ParameterError(f"output_mask has shape {mask.shape}, the channel is {D.shape}")
        A = scipy.linalg.block_diag(*([form.A] * len(cols))) if cols else np.zeros((0, 0))
        B = scipy.linalg.block_diag(*[B[:, [j]] for j in range(len(cols))]) if cols else np.zeros((0, 0))
        C = np.hstack([C * mask[:, [j]] for j in range(len(cols))]) if cols else np.zeros((len(rows), 0))
        D = D * mask
    else:
        A = form.A
    return _reduce(A, B, C, D, form.dt)


def _reduce(A, B, C, D, dt) -> Channel:
    A, B, C, D = (np.array(x, dtype=float) for x in (A, B, C, D))
    if A.shape[0] == 0 or B.shape[1] == 0 or C.shape[0] == 0 or not (np.any(B) and np.any(C)):
        return Channel(np.zeros((0, 0)), np.zeros((0, D.shape[1])), np.zeros((D.shape[0], 0)), D, dt)
    import control

    sys = control.ss(A, B, C, D, 0 if dt is None else dt)
    red = control.minreal(sys, tol=MINREAL_TOL, verbose=False)
    Ar, Br, Cr = (np.asarray(x, dtype=float) for x in (red.A, red.B, red.C))
    if Ar.size == 0:
        Ar, Br, Cr = np.zeros((0, 0)), np.zeros((0, D.shape[1])), np.zeros((D.shape[0], 0))
    return Channel(Ar, Br, Cr, np.asarray(red.D, dtype=float).reshape(D.shape), dt)


def check_stable(form: FaultModel, outputs=None) -> None:
    """Raise :class:`~fdikit.errors.ModelError` when the minimal realisation of ``form`` (its ``outputs``) is unstable.

    Parameters
    ----------
    form : FaultModel
        The internal form.
    outputs : sequence of str, optional
        The residuals checked (default all).

    Raises
    ------
    ModelError
        When the minimal channel has a pole with ``Re ≥ 0`` (``|z| ≥ 1``); the message lists them.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> check_stable(FaultModel(A=[[-1.0, 0.0], [0.0, 2.0]], C=[[1.0, 0.0]], Bf=[[1.0], [1.0]], faults=["f"]))
    """
    ch = minimal_channel(form, outputs=outputs)
    if not is_stable(ch.A, ch.dt):
        ev = np.linalg.eigvals(ch.A)
        bad = ev[ev.real >= 0] if ch.dt is None else ev[np.abs(ev) >= 1]
        raise ModelError(f"the internal form is unstable: pole(s) {np.round(bad, 6).tolist()} of its minimal "
                         "realisation; the H∞ norms are infinite (stabilise the filter)")


def input_columns(form: FaultModel, inputs) -> list[str]:
    """Input names of ``form`` (any group) as a list, checked; ``None`` gives the faults.

    Parameters
    ----------
    form : FaultModel
        The internal form.
    inputs : str, sequence of str or None
        Input names of any group; None: the fault inputs.

    Returns
    -------
    list of str

    Raises
    ------
    ParameterError
        A name the form does not have.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> input_columns(FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0]], Bw=[[1.0]], faults=["f"], noise=["w"]), None)
    ['f']
    """
    if inputs is None:
        return list(form.faults)
    names = [inputs] if isinstance(inputs, str) else list(inputs)
    known = [nm for g in GROUPS for nm in form.inputs[g]]
    unknown = [nm for nm in names if nm not in known]
    if unknown:
        raise ParameterError(f"no input named {unknown}; the internal form has {known}")
    return names


def is_stable(A, dt: float | None) -> bool:
    """Whether every eigenvalue of ``A`` is in the open left half plane (``dt`` None) or open unit disc.

    Parameters
    ----------
    A : array_like
        Square state matrix (``(0, 0)`` is stable).
    dt : float or None
        Sample time (None: continuous).

    Returns
    -------
    bool

    Examples
    --------
    >>> is_stable([[-1.0]], None), is_stable([[1.0]], 0.1), is_stable(np.zeros((0, 0)), None)
    (True, False, True)
    """
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return True
    ev = scipy.linalg.eigvals(A)
    return bool(np.all(ev.real < 0)) if dt is None else bool(np.all(np.abs(ev) < 1))


def hinf_norm(ch: Channel) -> tuple[float, float]:
    """H∞ norm of a channel and the frequency [rad/s] of the peak; ``(inf, nan)`` when unstable.

    python-control's ``linfnorm`` (SLICOT AB13DD, relative tolerance ``1e-10``) on the minimal
    realisation; a static or empty channel gives ``σ_max(D)`` at frequency 0.

    Parameters
    ----------
    ch : Channel
        Preferably minimal (:func:`minimal_channel`): stability is judged on its ``A``.

    Returns
    -------
    (float, float)
        ``(‖G‖∞, ω_peak)``.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[0.5]], C=[[1.0]], Bf=[[1.0]], faults=["f"], dt=0.1)
    >>> [round(float(x), 9) for x in hinf_norm(minimal_channel(R))]   # 1/(z − 0.5): peak 2 at ω = 0
    [2.0, 0.0]
    """
    if ch.D.size == 0:
        return 0.0, 0.0
    if ch.n == 0:
        return float(np.linalg.norm(ch.D, 2)), 0.0
    if not is_stable(ch.A, ch.dt):
        return float("inf"), float("nan")
    import control

    g, w = control.linfnorm(control.ss(ch.A, ch.B, ch.C, ch.D, 0 if ch.dt is None else ch.dt), tol=HINF_TOL)
    return float(g), float(w)


def h2_norm(ch: Channel) -> float:
    """H2 norm of a channel: ``√trace(C P Cᵀ (+ D Dᵀ))`` with the controllability Gramian ``P``.

    Infinite for an unstable channel and for a continuous channel with ``D ≠ 0`` (not strictly proper;
    ``D`` counts as zero when ``‖D‖ ≤ 100 ε max(1, ‖C‖ ‖B‖)``).  Discrete time: the sum of the squared
    impulse-response samples (``D Dᵀ`` included).

    Parameters
    ----------
    ch : Channel
        Preferably minimal (:func:`minimal_channel`).

    Returns
    -------
    float

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-2.0]], C=[[1.0]], Bf=[[1.0]], faults=["f"])
    >>> round(h2_norm(minimal_channel(R)), 12)   # 1/(s + 2): √(1/4)
    0.5
    """
    if ch.D.size == 0:
        return 0.0
    scale = max(1.0, np.linalg.norm(ch.C, 2) * np.linalg.norm(ch.B, 2) if ch.n else 1.0)
    d_zero = np.linalg.norm(ch.D, 2) <= 100 * _EPS * scale
    if ch.dt is None and not d_zero:
        return float("inf")
    if ch.n == 0:
        return float(np.linalg.norm(ch.D, "fro")) if ch.dt is not None else 0.0
    if not is_stable(ch.A, ch.dt):
        return float("inf")
    if ch.dt is None:
        P = scipy.linalg.solve_continuous_lyapunov(ch.A, -ch.B @ ch.B.T)
        val = np.trace(ch.C @ P @ ch.C.T)
    else:
        P = scipy.linalg.solve_discrete_lyapunov(ch.A, ch.B @ ch.B.T)
        val = np.trace(ch.C @ P @ ch.C.T + ch.D @ ch.D.T)
    return float(np.sqrt(max(val, 0.0)))


def check_freqs(freqs, dt: float | None) -> np.ndarray:
    """Frequencies [rad/s] as a non-empty 1-D float array; ``inf`` (the ``D`` term) only in continuous time.

    Parameters
    ----------
    freqs : float or array_like
        Frequencies in rad/s.
    dt : float or None
        Sample time (None: continuous).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ParameterError
        Empty, not 1-D, NaN or ``-inf``, or ``inf`` in discrete time.

    Examples
    --------
    >>> check_freqs(0, None).tolist(), check_freqs([1.0, np.inf], None).tolist()
    ([0.0], [1.0, inf])
    """
    arr = np.atleast_1d(validate.as_array("freqs", freqs, finite=False)).astype(float)
    if arr.ndim != 1 or arr.size == 0:
        raise ParameterError(f"freqs must be one real frequency or a non-empty 1-D array (rad/s), got shape "
                             f"{arr.shape}")
    if np.any(np.isnan(arr)) or np.any(arr == -np.inf):
        raise ParameterError("freqs must be real frequencies in rad/s (no NaN, no -inf)")
    if dt is not None and np.any(np.isinf(arr)):
        raise ParameterError("freqs = inf has no meaning in discrete time; the frequencies run up to π/dt")
    return arr


def frequency_response(ch: Channel, freqs) -> np.ndarray:
    """``G(λ_k)`` at ``λ = jω`` (continuous; ``ω = inf`` gives ``D``) or ``λ = e^{jω dt}``, shape (N, p, m).

    Parameters
    ----------
    ch : Channel
        The channel.
    freqs : float or array_like
        Frequencies in rad/s (:func:`check_freqs`).

    Returns
    -------
    numpy.ndarray
        Complex ``(N, p, m)``.

    Raises
    ------
    ModelError
        When some ``λ_k`` is a pole of the channel (``σ_min(A − λI) ≤ n ε max(1, ‖A‖)``).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0]], faults=["f"])
    >>> np.round(np.abs(frequency_response(minimal_channel(R), [0.0, 1.0, np.inf])[:, 0, 0]), 6).tolist()
    [1.0, 0.707107, 0.0]
    """
    omega = check_freqs(freqs, ch.dt)
    n = ch.n
    out = np.empty((omega.size, *ch.D.shape), dtype=complex)
    tol = max(n, 1) * _EPS * max(1.0, np.linalg.norm(ch.A, 1) if n else 1.0)
    for k, w in enumerate(omega):
        if n == 0 or np.isinf(w):
            out[k] = ch.D
            continue
        lam = np.exp(1j * w * ch.dt) if ch.dt is not None else 1j * w
        M = lam * np.eye(n) - ch.A
        if np.linalg.svd(M, compute_uv=False)[-1] <= tol:
            raise ModelError(f"the frequency {w:g} rad/s (λ = {complex(np.round(lam, 12))}) is a pole of the "
                             "channel; the response there is infinite")
        out[k] = ch.C @ np.linalg.solve(M, ch.B) + ch.D
    return out
