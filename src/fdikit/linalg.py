"""Subspaces, fault maps and the geometry of detection filters.

Orthonormal bases and SVD rank decisions throughout; every tolerance scales with the
data (``max(shape) · eps · σ_max`` by default, or a caller's relative tolerance).

* fault maps: sensor faults as the two-dimensional ``F = [F¹, A F¹]`` with
  ``C F¹ = e_i`` (Douglas et al. 1996, eqs. (3.3)–(3.5); App. A.2), actuator faults as
  columns of ``B`` (§3.2);
* the minimal (C, A)-invariant subspace containing ``F`` by CAISA (App. A, Theorem A.1,
  with ``W⁰ = 0``: the report prints ∅, which is not a subspace; the
  iteration starts from the zero subspace);
* invariant zeros of ``(C, A, F)`` and their state directions from the Rosenbrock pencil;
* the minimal unobservability subspace ``T* = W* ⊕ V`` (§4.1, App. A.3), output
  separability (a.7) and mutual detectability (§4.1).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel, actuator_fault_name, sensor_fault_name

__all__ = [
    "resolve_faults",
    "resolve_nuisance",
    "split_fault_name",
    "check_fault_inputs",
    "output_projector",
    "rank",
    "orth",
    "null",
    "intersect",
    "span_sum",
    "contains",
    "sensor_fault_map",
    "actuator_fault_map",
    "sensor_fault_map_tv",
    "resolve_fault",
    "caisa",
    "invariant_zeros",
    "detection_space",
    "output_separable",
    "mutually_detectable",
]

_EPS = np.finfo(float).eps


def _mat(name: str, M) -> np.ndarray:
    """``M`` as a finite real or complex 2-D array (a vector is one row); ParameterError otherwise."""
    return validate.as_matrix(name, M, promote=True, complex_ok=True)


def _rtol(rtol):
    if rtol is None:
        return None
    return validate.non_negative("rtol", rtol)


def _system(A, C, F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A`` (n x n), ``C`` (p x n), ``F`` (n x k) as finite float matrices, shapes checked."""
    A = validate.as_square("A", A)
    n = A.shape[0]
    C = validate.as_matrix("C", np.atleast_2d(C) if np.ndim(C) == 1 else C, (None, n))
    F = validate.as_matrix("F", np.reshape(F, (-1, 1)) if np.ndim(F) == 1 else F, (n, None))
    return A, C, F


def _tol(M: np.ndarray, s: np.ndarray, rtol: float | None) -> float:
    smax = s[0] if s.size else 0.0
    return (rtol if rtol is not None else max(M.shape) * _EPS * 1e3) * max(smax, 0.0)


def rank(M: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank: singular values above ``rtol · σ_max`` (default ``1e3 · max(shape) · eps``)."""
    M, rtol = _mat("M", M), _rtol(rtol)
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0


def orth(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the range of ``M`` (n x r)."""
    M, rtol = _mat("M", M), _rtol(rtol)
    if M.size == 0:
        return np.zeros((M.shape[0], 0), dtype=M.dtype)
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    r = int((s > _tol(M, s, rtol)).sum()) if s[0] > 0 else 0
    return U[:, :r]


def null(M: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of the null space of ``M`` (columns)."""
    M, rtol = _mat("M", M), _rtol(rtol)
    if M.shape[0] == 0:
        return np.eye(M.shape[1], dtype=M.dtype)
    _, s, Vh = np.linalg.svd(M, full_matrices=True)
    r = int((s > _tol(M, s, rtol)).sum()) if s.size and s[0] > 0 else 0
    return Vh[r:].conj().T


def span_sum(*bases: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U₁ + Im U₂ + …``."""
    bases = [_mat(f"basis {i}", b) for i, b in enumerate(bases) if np.size(b)]
    if not bases:
        raise ParameterError("span_sum needs at least one non-empty basis")
    rows = {b.shape[0] for b in bases}
    if len(rows) > 1:
        raise ParameterError(f"span_sum: the bases have different numbers of rows {sorted(rows)}; "
                             "every basis must live in the same space")
    return orth(np.hstack(bases), rtol)


def intersect(U: np.ndarray, V: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of ``Im U ∩ Im V``."""
    U, V = orth(U, rtol), orth(V, rtol)
    if U.shape[0] != V.shape[0]:
        raise ParameterError(f"intersect: U has {U.shape[0]} rows but V has {V.shape[0]}; both bases must live in "
                             "the same space")
    if U.shape[1] == 0 or V.shape[1] == 0:
        return np.zeros((U.shape[0], 0))
    N = null(np.hstack([U, -V]), rtol)
    return orth(U @ N[: U.shape[1]], rtol)


def contains(U: np.ndarray, x: np.ndarray, rtol: float = 1e-8) -> bool:
    """Whether every column of ``x`` lies in ``Im U`` (relative residual below ``rtol``)."""
    Q = orth(U)
    x = np.asarray(x)
    x = _mat("x", x.reshape(-1, 1) if x.ndim == 1 else x)
    if x.shape[0] != Q.shape[0]:
        raise ParameterError(f"x has {x.shape[0]} rows but U has {Q.shape[0]}; pass vectors of length {Q.shape[0]}")
    res = x - Q @ (Q.conj().T @ x)
    return bool(np.linalg.norm(res) <= rtol * max(np.linalg.norm(x), _EPS))


# ---------------------------------------------------------------------- fault maps
def sensor_fault_map(model: FaultModel, output: str, direction: str = "both", rtol: float = 1e-9) -> np.ndarray:
    """State-space fault map of an additive fault on the sensor of ``output``.

    ``y = C x + e_i μ`` is written as a state fault through ``F¹`` with ``C F¹ = e_i``:
    ``ē = e − F¹ μ`` gives ``ē' = (A + LC) ē + F¹ μ' − A F¹ μ`` (Douglas et al. 1996,
    eq. (3.4); App. A.2).  ``direction``: ``'both'`` → ``[F¹, A F¹]`` (n x 2), ``'magnitude'``
    → ``A F¹`` (the bias direction), ``'rate'`` → ``F¹``.  ``F¹`` is the minimum-norm
    solution; it must solve ``C F¹ = e_i`` exactly (to ``rtol``), otherwise the output is
    not reachable from the states and :class:`DesignError` is raised.
    """
    validate.instance("model", model, FaultModel)
    validate.choice("direction", direction, ("both", "magnitude", "rate"))
    i = model.index("outputs", output)[0]
    e = np.zeros(model.p)
    e[i] = 1.0
    F1, *_ = np.linalg.lstsq(model.C, e, rcond=None)
    if np.linalg.norm(model.C @ F1 - e) > rtol:
        raise DesignError(
            f"output {output!r} is not in the range of C (residual {np.linalg.norm(model.C @ F1 - e):.2e}): "
            "its sensor fault cannot be written as a state fault F¹ with C F¹ = e_i; use a model whose C has "
            "full row rank for these outputs"
        )
    F1 = F1.reshape(-1, 1)
    F2 = model.A @ F1
    maps = {"both": np.hstack([F1, F2]), "magnitude": F2, "rate": F1}
    if direction not in maps:
        raise ParameterError(f"direction must be 'both', 'magnitude' or 'rate', got {direction!r}")
    return maps[direction]


def sensor_fault_map_tv(
    A: Callable[[float], np.ndarray],
    C: Callable[[float], np.ndarray],
    output: int,
    t: float,
    dF1: Callable[[float], np.ndarray] | None = None,
    step: float | None = None,
    rtol: float = 1e-9,
) -> np.ndarray:
    """Two-dimensional sensor-fault map of a time-varying model at time ``t``: ``[F¹(t), F²(t)]``.

    ``C(t) F¹(t) = e_i`` (minimum-norm) and ``F² = A F¹ − dF¹/dt`` (Douglas et al. 1996, App. A.2; the
    printed (a.9b) reads ``A b + ḃ``; the Goh transformation it names gives ``A b − ḃ``, the sign of
    ``A B₁ − Ḃ₁`` in (9.38) and of ``A F_i − Ḟ_i`` in App. A.2).
    ``dF1`` gives the derivative; otherwise a central difference with ``step`` (default ``1e-6 · max(1, |t|)``).
    ``A`` and ``C`` are callables ``t -> matrix``; ``output`` is the output's index.
    """
    for nm, fn in (("A", A), ("C", C), ("dF1", dF1)):
        if fn is not None and not callable(fn):
            raise ParameterError(f"{nm} must be a function of time t -> matrix, got {type(fn).__name__}")
    t = validate.number("t", t)
    validate.integer("output", output, minimum=0)
    p0 = np.atleast_2d(np.asarray(C(t), dtype=float)).shape[0]
    if output >= p0:
        raise ParameterError(f"output index {output} is out of range; C(t) has {p0} outputs (0 .. {p0 - 1})")

    def f1(tau: float) -> np.ndarray:
        Ct = np.atleast_2d(np.asarray(C(tau), dtype=float))
        e = np.zeros(Ct.shape[0])
        e[output] = 1.0
        x, *_ = np.linalg.lstsq(Ct, e, rcond=None)
        if np.linalg.norm(Ct @ x - e) > rtol:
            raise DesignError(f"output {output} is not in the range of C(t) at t = {tau:g}; no sensor-fault map")
        return x

    F1 = f1(t)
    if dF1 is not None:
        d = np.asarray(dF1(t), dtype=float).ravel()
    else:
        h = step if step is not None else 1e-6 * max(1.0, abs(t))
        d = (f1(t + h) - f1(t - h)) / (2 * h)
    F2 = np.atleast_2d(np.asarray(A(t), dtype=float)) @ F1 - d
    return np.column_stack([F1, F2])


def actuator_fault_map(model: FaultModel, control: str) -> np.ndarray:
    """Fault map of an actuator: the control's column of ``B`` (Douglas et al. 1996, §3.2), n x 1.

    On a model whose actuator lags are states (e.g. the 14-state PATH model) this is the
    command-side fault; a nonzero ``D`` column means the fault also reaches the outputs
    directly, which the geometric filters here do not model (:class:`DesignError`).
    """
    validate.instance("model", model, FaultModel)
    j = model.index("u", control)[0]
    if np.any(model.Du[:, j] != 0):
        raise DesignError(
            f"control {control!r} has a direct feedthrough D[:, {j}] != 0; an actuator fault on it reaches the "
            "outputs directly. Use a model with the actuator dynamics as states (e.g. path_vehicle_14)"
        )
    return model.Bu[:, [j]]


def _signal_hint(model: FaultModel, base: str, suffix: str = "") -> str | None:
    """The message refusing a bare signal name, naming the fault to use (None if ``base`` is no signal)."""
    tail = f":{suffix}" if suffix else ""
    if base in model.outputs:
        return f"{base!r} is an output; its sensor fault is {sensor_fault_name(base) + tail!r}"
    if base in model.controls:
        return f"{base!r} is a control; its actuator fault is {actuator_fault_name(base) + tail!r}"
    return None


def split_fault_name(model: FaultModel, name: str) -> tuple[str, str, str]:
    """Parse a fault name against a model: ``(kind, signal, suffix)``.

    * a fault input of the model (group ``f``) by its own name → ``('fault', name, suffix)``;
    * ``'<output>_sensor'`` → ``('sensor', output, suffix)``, with the optional suffix ``':magnitude'``
      (``A F¹`` only, the bias assumption, Douglas et al. 1996, §3.1) or ``':rate'`` (``F¹`` only);
    * ``'<control>_actuator'`` → ``('actuator', control, '')``.

    Raises
    ------
    ParameterError
        A name that is not a string, an unknown suffix, or a bare signal name (an output or control):
        the message gives the fault name to use (``'theta' is an output; its sensor fault is
        'theta_sensor'``).
    ModelError
        A name the model does not know, or a suffix on an actuator fault.
    """
    validate.instance("model", model, FaultModel)
    if not isinstance(name, str):
        raise ParameterError(f"fault name must be a string, got {name!r} ({type(name).__name__})")
    base, _, suffix = name.partition(":")
    if suffix and suffix not in ("magnitude", "rate"):
        raise ParameterError(
            f"unknown fault suffix {suffix!r} in {name!r}; use ':magnitude' or ':rate' (sensor faults)"
        )
    if base in model.faults:
        return "fault", base, suffix
    sensors = {sensor_fault_name(o): o for o in model.outputs}
    if base in sensors:
        return "sensor", sensors[base], suffix
    actuators = {actuator_fault_name(c): c for c in model.controls}
    if base in actuators:
        if suffix:
            raise ModelError(f"{name!r}: the ':{suffix}' suffix applies to sensor faults only, {base!r} is an "
                             "actuator fault")
        return "actuator", actuators[base], ""
    hint = _signal_hint(model, base, suffix)
    if hint:
        raise ParameterError(f"{hint}; faults are named by fault name, not by signal name")
    raise ModelError(
        f"{base!r} is not a fault of the model; fault names are <output>_sensor {list(sensors)}, "
        f"<control>_actuator {list(actuators)} and the fault inputs {list(model.faults)}"
    )


def check_fault_inputs(model: FaultModel, names: Sequence[str] | str, what: str = "fault") -> tuple[str, ...]:
    """Names of fault inputs of the model (group ``f``), checked; a bare signal name is refused.

    For designs that act on the model's fault inputs themselves (:func:`fdikit.design.observers.uio.uio`,
    the gain tables of :mod:`fdikit.analysis`).  Raises :class:`ParameterError` for a signal name (with the
    fault name to use) and :class:`ModelError` for a name that is no fault input of the model.
    """
    validate.instance("model", model, FaultModel)
    names = (names,) if isinstance(names, str) else tuple(names)
    for nm in names:
        if not isinstance(nm, str):
            raise ParameterError(f"{what} names must be strings, got {nm!r} ({type(nm).__name__})")
        if nm in model.faults:
            continue
        hint = _signal_hint(model, nm)
        if hint:
            raise ParameterError(f"{hint}; faults are named by fault name, not by signal name")
        kind = "sensor" if nm in {sensor_fault_name(o) for o in model.outputs} else (
            "actuator" if nm in {actuator_fault_name(c) for c in model.controls} else None)
        if kind:
            add = "with_sensor_faults" if kind == "sensor" else "with_actuator_faults"
            raise ModelError(f"{nm!r} is not a fault input of the model; add it with model.{add}([...]) "
                             f"(the model has fault inputs {list(model.faults)})")
        model.index("f", nm)  # raises the model's own ModelError for an unknown name
    return names


def resolve_fault(model: FaultModel, name: str) -> tuple[np.ndarray, str]:
    """State-space fault map of a named fault and its kind.

    ``name`` is a fault name (:func:`split_fault_name`):

    * ``'<output>_sensor'`` → :func:`sensor_fault_map` ``[F¹, A F¹]`` (kind ``'sensor'``);
      ``'<output>_sensor:magnitude'`` → ``A F¹`` only (the bias assumption, Douglas et al. 1996, §3.1),
      ``'<output>_sensor:rate'`` → ``F¹`` only (kind ``'sensor:magnitude'`` / ``'sensor:rate'``);
    * ``'<control>_actuator'`` → :func:`actuator_fault_map`, the column of ``Bu`` (``'actuator'``);
    * a fault input of the model (group ``f``) by its own name → its ``Bf`` column when ``Df`` is
      zero (``'fault input'``), the sensor map of output ``i`` when it is a pure sensor fault
      (``Df = e_i``, ``Bf = 0``).

    A bare signal name (``'theta'``, ``'throttle'``) raises :class:`ParameterError` naming the fault.
    """
    kind, base, suffix = split_fault_name(model, name)
    if kind == "fault":
        j = model.index("f", base)[0]
        df, bf = model.Df[:, j], model.Bf[:, j]
        if not np.any(df):
            if suffix:
                raise ModelError(f"{name!r}: the suffix applies to sensor faults only")
            return bf.reshape(-1, 1), "fault input"
        i = int(np.argmax(np.abs(df)))
        if np.any(bf) or np.count_nonzero(df) != 1 or df[i] != 1.0:
            raise DesignError(f"fault {base!r} reaches the outputs directly and is not a pure sensor fault; "
                              "pass its state-space fault map in a dict")
        base, kind = model.outputs[i], "sensor"
    if kind == "sensor":
        direction = suffix or "both"
        return sensor_fault_map(model, base, direction), "sensor" if direction == "both" else f"sensor:{suffix}"
    return actuator_fault_map(model, base), "actuator"


# ---------------------------------------------------------------------- geometry
def caisa(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal (C, A)-invariant subspace containing ``Im F`` (CAISA, Douglas et al. 1996, Thm. A.1).

    ``W⁰ = 0``, ``W^{k+1} = Im F + A (W^k ∩ Ker C)``; the sequence is nondecreasing and
    stops within ``n`` steps.  Returns an orthonormal basis.
    """
    A, C, F = _system(A, C, F)
    rtol = _rtol(rtol)
    kerC = null(C, rtol)
    W = orth(F, rtol)
    for _ in range(A.shape[0] + 1):
        part = intersect(W, kerC, rtol)
        W_next = span_sum(F, A @ part, rtol=rtol) if part.shape[1] else orth(F, rtol)
        if W_next.shape[1] == W.shape[1]:
            return W_next
        W = W_next
    return W


def invariant_zeros(
    A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Invariant zeros of ``(C, A, F)`` and their state directions.

    The zeros are the finite generalised eigenvalues of the Rosenbrock pencil
    ``[[A − sI, F], [C, 0]]``, computed by SLICOT ``AB08ND`` (slycot) for square and
    non-square systems alike.  ``rtol`` is AB08ND's rank-decision tolerance (reciprocal
    condition bound); the default ``1e5 · (n + max(p, k)) · eps`` (about 1e-10 for n = 6)
    scales with the pencil's size.  AB08ND's own default, ``sqrt((n+p)(n+k)) · eps``, misses
    zeros of ordinary, moderately conditioned systems (an unobservable mode in random
    coordinates was lost in about one case in five).

    For each zero ``z`` the direction is the state part ``x`` of a null vector of
    ``[[A − zI, F], [C, 0]]`` (complex for a complex zero), unit norm.  A multiple zero
    (a cluster of computed zeros with parallel directions) gets directions that span its
    whole generalised zero space: independent null vectors when the zero has several
    directions, and Jordan-chain vectors ``(A − zI) x₂ + F η₂ = x₁, C x₂ = 0`` when it is
    defective.  So ``span(directions)`` is always the invariant-zero subspace ``V`` that
    :func:`detection_space` adds to ``W*``.
    """
    from slycot import ab08nd

    A, C, F = _system(A, C, F)
    rtol = _rtol(rtol)
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex), []
    tol = rtol if rtol is not None else 1e5 * (n + max(p, k)) * _EPS
    out = ab08nd(n, k, p, A, F, C, np.zeros((p, k)), equil="N", tol=tol)
    nu = out[0]
    if nu == 0:
        return np.zeros(0, dtype=complex), []
    zeros = np.asarray(scipy.linalg.eigvals(out[8][:nu, :nu], out[9][:nu, :nu]), dtype=complex)
    zeros = zeros[np.isfinite(zeros)]
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(F, 2), np.linalg.norm(C, 2), 1.0)
    zeros = np.where(np.abs(zeros.imag) <= 1e-12 * scale, zeros.real, zeros)  # round-off imaginary parts
    return zeros, _zero_directions(A, C, F, zeros)


def _null_direction(M: np.ndarray, E: np.ndarray, z: complex, n: int) -> np.ndarray:
    """State part of the right singular vector of ``M − zE`` for its smallest singular value."""
    x = np.linalg.svd(M - z * E)[2][-1].conj()[:n]
    return x / max(np.linalg.norm(x), _EPS)


def _zero_directions(A: np.ndarray, C: np.ndarray, F: np.ndarray, zeros: np.ndarray) -> list[np.ndarray]:
    """Directions of ``zeros`` (see :func:`invariant_zeros`): one unit vector per zero, clusters spanning V.

    Zeros within ``1e-5 · ‖[[A, F], [C, 0]]‖`` whose individual directions are (nearly) parallel are
    one multiple zero (a defective double zero splits by ~√eps): its directions are recomputed at the
    cluster mean from the null space of the pencil and, if that is too small, from Jordan chains.
    """
    n, k, p = A.shape[0], F.shape[1], C.shape[0]
    M = np.block([[A, F], [C, np.zeros((p, k))]])
    E = np.zeros_like(M)
    E[:n, :n] = np.eye(n)
    scale = max(np.linalg.norm(M, 2), 1.0)
    dirs = [_null_direction(M, E, z, n) for z in zeros]
    todo = list(range(len(zeros)))
    while todo:
        i = todo[0]
        members = [j for j in todo if abs(zeros[j] - zeros[i]) <= 1e-5 * scale]
        todo = [j for j in todo if j not in members]
        m = len(members)
        if m == 1:
            continue
        sv = np.linalg.svd(np.column_stack([dirs[j] for j in members]), compute_uv=False)
        if sv[-1] > 1e-3 * sv[0]:  # distinct close zeros with their own directions
            continue
        z = np.mean(zeros[members])
        if abs(z.imag) <= 1e-14 * scale:  # a real multiple zero (a defective one splits into a conjugate pair)
            z = z.real
        P = M - z * E  # real for a real zero, so its directions are real
        # eigen-directions first: null vectors of P(z) (at least one, at most m)
        _, s, Vh = np.linalg.svd(P)
        s = np.concatenate([s, np.zeros(Vh.shape[0] - s.size)])
        r1 = int(np.clip((s <= 1e-8 * max(s[0], _EPS)).sum(), 1, m))
        U = np.linalg.svd(Vh[-r1:, :n].conj().T, full_matrices=False)[0][:, :r1]
        if r1 < m:  # defective: complete with chain vectors, P v1 = 0, P v2 = E v1, …, stacked block-bidiagonally
            K = np.kron(np.eye(m), P) - np.kron(np.eye(m, k=-1), E)
            _, s, Vh = np.linalg.svd(K)
            s = np.concatenate([s, np.zeros(Vh.shape[0] - s.size)])
            keep = np.union1d(np.flatnonzero(s <= 1e-8 * max(s[0], _EPS)), np.arange(Vh.shape[0] - m, Vh.shape[0]))
            N = Vh[keep].conj().T
            X = np.hstack([N[b * (n + k) : b * (n + k) + n] for b in range(m)])
            X = X - U @ (U.conj().T @ X)
            U = np.hstack([U, np.linalg.svd(X)[0][:, : m - r1]])
        for j, col in zip(members, U.T):
            dirs[j] = col / max(np.linalg.norm(col), _EPS)
    return dirs


def _real_span(vectors: Sequence[np.ndarray], n: int) -> np.ndarray:
    if not vectors:
        return np.zeros((n, 0))
    V = np.column_stack(vectors)
    return np.hstack([V.real, V.imag])


def detection_space(A: np.ndarray, C: np.ndarray, F: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Minimal unobservability subspace containing ``Im F``: ``T* = W* ⊕ V`` (Douglas et al. 1996, §4.1).

    ``W*`` from :func:`caisa`, ``V`` the span of the invariant-zero directions of
    ``(C, A, F)``.  Orthonormal basis (n x ν).
    """
    A, C, F = _system(A, C, F)
    W = caisa(A, C, F, rtol)
    _, dirs = invariant_zeros(A, C, F)
    return span_sum(W, _real_span(dirs, np.shape(A)[0]), rtol=rtol) if dirs else W


def output_separable(
    C: np.ndarray, spaces: Sequence[np.ndarray], rtol: float | None = None
) -> tuple[bool, list[tuple[int, int]]]:
    """Whether the output images ``C T_i`` are independent (Def. A.1; test (a.7)).

    Returns the verdict and the pairs ``(i, j)`` whose images intersect (the faults that
    are "detection equivalent" and cannot be told apart by their residual directions).
    """
    C = _mat("C", C)
    spaces = [_mat(f"space {i}", T) for i, T in enumerate(spaces)]
    for i, T in enumerate(spaces):
        if T.shape[0] != C.shape[1]:
            raise ParameterError(f"space {i} has {T.shape[0]} rows but C has {C.shape[1]} columns (states)")
    images = [orth(C @ T, rtol) for T in spaces]
    total = rank(np.hstack(images), rtol) if images else 0
    ok = total == sum(im.shape[1] for im in images)
    pairs = [
        (i, j)
        for i in range(len(images))
        for j in range(i + 1, len(images))
        if rank(np.hstack([images[i], images[j]]), rtol) < images[i].shape[1] + images[j].shape[1]
    ]
    return ok, pairs


def mutually_detectable(
    A: np.ndarray, C: np.ndarray, faults: Sequence[np.ndarray], rtol: float = 1e-6
) -> tuple[bool, np.ndarray, np.ndarray]:
    """Mutual detectability (Douglas et al. 1996, §4.1): zeros of the union = union of the zeros.

    Returns the verdict, the zeros of ``(C, A, [F₁ … F_q])`` and the union of the zeros of
    each ``(C, A, F_i)``.  The two multisets are matched with a tolerance relative to ‖A‖.
    """
    A = validate.as_square("A", A)
    C = validate.as_matrix("C", C, (None, A.shape[0]))
    faults = [validate.as_matrix(f"fault map {i}", F, (A.shape[0], None)) for i, F in enumerate(faults)]
    if not faults:
        raise ParameterError("mutually_detectable needs at least one fault map")
    rtol = validate.non_negative("rtol", rtol)
    joint, _ = invariant_zeros(A, C, np.hstack(faults))
    union = np.concatenate([invariant_zeros(A, C, F)[0] for F in faults]) if faults else np.zeros(0)
    scale = max(np.linalg.norm(A, 2), 1.0)
    left = list(union)
    extra = []
    for z in joint:
        k = int(np.argmin(np.abs(np.array(left) - z))) if left else -1
        if k >= 0 and abs(left[k] - z) <= rtol * scale:
            left.pop(k)
        else:
            extra.append(z)
    return not extra and not left, joint, union


def resolve_faults(model: FaultModel, faults: Mapping[str, np.ndarray] | Sequence[str] | str) -> dict[str, np.ndarray]:
    """Fault maps by fault name.

    A mapping gives explicit ``F`` matrices (n x k) under its keys.  A name or a sequence of
    names is resolved by :func:`fdikit.linalg.resolve_fault`: ``'<output>_sensor'`` is the sensor
    fault ``[F¹, A F¹]``, ``'<output>_sensor:magnitude'`` its bias direction ``A F¹`` only
    (Douglas et al. 1996, §4.1, the air-mass fix), ``'<control>_actuator'`` the actuator fault
    ``B[:, j]``, a fault input of the model (group ``f``) its own map.  The keys are the names
    without the suffix.  A bare signal name (``'theta'``) raises :class:`ParameterError` whose
    message gives the fault name (``'theta_sensor'``).
    """
    validate.instance("model", model, FaultModel)
    if isinstance(faults, str):
        faults = [faults]
    if isinstance(faults, Mapping):
        out = {}
        for name, F in faults.items():
            F = np.atleast_2d(validate.as_array(f"fault map {name!r}", F, error=ModelError))
            if F.shape[0] != model.n and F.shape[1] == model.n:
                F = F.T
            if F.shape[0] != model.n:
                raise ModelError(f"fault map {name!r} has {F.shape[0]} rows; the model has {model.n} states")
            out[str(name)] = F
        return out
    out = {}
    for spec in faults:
        F, _ = resolve_fault(model, spec)
        out[spec.partition(":")[0]] = F
    return out


def resolve_nuisance(
    model: FaultModel, nuisance: Mapping[str, np.ndarray] | Sequence[str] | str, targets: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """Fault maps of the faults a design must ignore (the ``nuisance=`` convention).

    ``()`` (or an empty mapping) means none; the string ``'others'`` means every fault input of the
    model (group ``f``) not named in ``targets``; anything else is resolved by :func:`resolve_faults`.
    """
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        given = {str(t).partition(":")[0] for t in targets}
        return {f: resolve_fault(model, f)[0] for f in model.faults if f not in given}
    if isinstance(nuisance, Mapping) or len(nuisance):
        return resolve_faults(model, nuisance)
    return {}


def output_projector(C: np.ndarray, W: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthogonal projector ``I − h hᵀ`` onto the complement of ``range(C W)`` (``h`` an orthonormal basis).

    The detection-space projector ``Ĥ`` of Murray 2012, (2.15); ``I`` when ``W`` has no columns.
    """
    p = C.shape[0]
    if W.shape[1] == 0:
        return np.eye(p)
    h = orth(C @ W, rtol)
    return np.eye(p) - h @ h.T
