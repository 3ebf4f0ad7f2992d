"""Unknown-input observer (UIO) residual generators: one target fault, every other input decoupled.

The full-order UIO of Chen & Patton (1999, §3.2) for ``x' = A x + Bu u + E v``,
``y = C x + Du u`` with an unknown input ``v``::

    z' = N z + T Bu u + K ȳ,       x̂ = z + H ȳ,       ȳ = y − Du u
    H = E (CE)⁺,  T = I − H C,  A1 = T A,  N = A1 − K1 C,  K = K1 + K2,  K2 = N H

makes the error ``e = x − x̂`` obey ``e' = N e`` whatever ``v`` is: ``T E = 0`` needs
``rank CE = rank E`` (every unknown direction visible at the outputs), and ``N`` stable
needs ``(C, A1)`` detectable — the unobservable modes of ``(C, A1)`` are the invariant
zeros of ``(A, E, C)``, so those must be stable (Chen & Patton 1999, §3.2; Darouach,
Zasadzinski & Xu 1994).  The residual ``r = ȳ − C x̂`` is then blind to ``v`` and to ``u``
and sees the one fault left out of ``E``: the single-fault filter of Massoumnia, Verghese &
Willsky (1989) that Murray 2012, §1.1.1 and Remark 2.4 uses as the
baseline — all faults but one in an unobservable subspace, and a bank of them needs no
mutual detectability.

Unknown-input directions ``E`` (:func:`unknown_input_matrix`):

* a fault or disturbance in the state equation only (``D`` column 0): its ``B`` column;
* a fault in the outputs, ``y = C x + d μ`` (a sensor fault: ``d = e_i``), possibly also in
  the states (``x' = … + b μ``): with ``C F¹ = d`` (minimum-norm solution) the substitution
  ``x̄ = x + F¹ μ`` gives ``y = C x̄`` and

      x̄' = A x̄ + Bu u + (b − A F¹) μ + F¹ μ'         (continuous)
      x̄[k+1] = A x̄[k] + Bu u[k] + (b − A F¹) μ[k] + F¹ μ[k+1]   (discrete),

  a state fault with the two directions ``[F¹, A F¹ − b]`` — for ``b = 0`` exactly
  :func:`fdikit.fault_maps.sensor_fault_map`'s ``[F¹, A F¹]`` (Douglas et al. 1996, eq. (3.4);
  Murray 2012, (2.3)/(2.17)).  ``μ`` and ``μ'`` are decoupled as two independent inputs;
  the transfer from ``μ`` to ``r`` is then zero for any signal, differentiable or not.
  ``d`` must lie in the range of ``C`` (:class:`DesignError` otherwise);
* disturbances (group ``d``) are always unknown inputs; they must not reach the outputs
  directly (``Dd = 0``) — model such a disturbance as a fault to get the substitution.

Residual reduction.  With ``U⊥`` an orthonormal basis of ``(Im CE)^⊥`` the generator
returns ``U⊥ᵀ r = U⊥ᵀ (ȳ − C z)`` (``U⊥ᵀ C H = 0``), ``p − rank CE`` residuals.  This loses
nothing: the transfer ``R(s)`` from ``(u, y)`` to ``r`` annihilates ``C (sI − A)⁻¹ E``, whose
normal rank is ``rank CE``, so ``rank R(s) ≤ p − rank CE``; ``U⊥ᵀ R(s)`` has that full rank
(at ``s = ∞`` it is ``U⊥ᵀ [−Du, I]``), hence every row of ``R`` is a rational combination
of the rows of ``U⊥ᵀ R``: the reduced residual is zero only when the full one is.  Since
the rows of ``R`` span the whole left null space of the unknown-input transfer, a target
the UIO cannot see cannot be seen by any linear residual decoupled from ``E``.

Partial pole placement.  When ``(C, A1)`` has unobservable (fixed) modes, an orthogonal
staircase (SLICOT ``AB01ND`` on the dual pair ``(A1ᵀ, Cᵀ)``) splits the state into an
observable part, whose poles are placed, and the fixed modes, which stay as they are (they
must be stable); the design's ``fixed_modes`` and ``notes`` report them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import fault_maps, linalg, lti, validate
from fdikit.design.labels import label_generator, residual_labels
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["UIODesign", "uio", "uio_bank", "unknown_input_matrix"]

_EPS = np.finfo(float).eps
#: relative size below which a transfer counts as zero (target detectability test)
_ZERO = np.sqrt(_EPS)


@dataclass(frozen=True, eq=False)
class UIODesign(FieldReport):
    """An unknown-input observer residual generator and its design report.

    Attributes
    ----------
    generator : residual generator; residuals ``<target>[k]``, ``k < p − rank CE``, all tied to the target.
    target : the fault the residual responds to.
    decoupled : the nuisance faults and disturbances the residual is blind to (plus the controls).
    E : unknown-input directions (n x k), blocks in the order of ``decoupled`` (two columns for a
        fault that reaches the outputs).
    H, T, K, N : the UIO matrices (``K = K1 + N H``); ``K1`` the gain on the observable part of ``(C, T A)``.
    poles : eigenvalues of ``N`` (placed poles and fixed modes).
    fixed_modes : unobservable modes of ``(C, T A)`` = invariant zeros of ``(A, E, C)``; not assignable.
    residual_basis : ``U⊥`` (p x q), orthonormal basis of ``(Im CE)^⊥``; residual = ``U⊥ᵀ (ȳ − C x̂)``.
    visibility : ``σ_min(C E₀) / ‖C‖`` for an orthonormal basis ``E₀`` of ``Im E`` (1 = well visible,
        → 0 as an unknown direction hides from the outputs; ``H`` grows as its inverse).
    omega : frequency grid (rad/s) of the decoupling numbers.
    target_gain : ``max_ω ‖G_r,target(jω)‖`` (internal form).
    decoupling : per decoupled input and control, ``max_ω ‖G_r,input‖ / target_gain`` (≈ 1e-15 when exact).
    notes : remarks of the design (partial pole placement, fixed modes kept).
    model : the FaultModel the design was made for (keyword-only; set by :func:`uio`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bu=[[1.0], [1.0], [0.0]]).with_sensor_faults(["y0"])
    >>> d = uio(m, "y0_sensor", poles=[-4.0, -5.0, -6.0])
    >>> d.target, d.fixed_modes.size, sorted(d.poles.real.round(6).tolist())
    ('y0_sensor', 0, [-6.0, -5.0, -4.0])

    References
    ----------
    Murray 2012, §1.1.1, Remark 2.4 (the single-fault filter this UIO implements).
    """

    generator: ResidualGenerator
    target: str
    decoupled: tuple[str, ...]
    E: np.ndarray
    H: np.ndarray
    T: np.ndarray
    K: np.ndarray
    K1: np.ndarray
    N: np.ndarray
    poles: np.ndarray
    fixed_modes: np.ndarray
    residual_basis: np.ndarray
    visibility: float
    omega: np.ndarray
    target_gain: float
    decoupling: dict[str, float]
    notes: tuple[str, ...] = ()
    def report(self) -> dict:
        """``target``, ``decoupled`` (inputs the residual is blind to), the UIO matrices ``H``, ``T``, ``K``,
        ``K1``, ``N``, ``poles`` (of ``N``), ``fixed_modes``, ``visibility`` (``σ_min(C E₀) / ‖C‖``),
        ``target_gain`` (peak fault-to-residual gain) and ``decoupling`` (peak gain of each decoupled input
        relative to ``target_gain``), ``notes``."""
        return {"target": self.target, "decoupled": self.decoupled, "H": self.H, "T": self.T, "K": self.K,
                "K1": self.K1, "N": self.N, "poles": self.poles, "fixed_modes": self.fixed_modes,
                "visibility": self.visibility, "target_gain": self.target_gain, "decoupling": self.decoupling,
                "notes": self.notes}


# ---------------------------------------------------------------------- unknown-input directions
def unknown_input_matrix(
    model: FaultModel, faults: Sequence[str] = (), disturbances: bool = True, rtol: float = 1e-9
) -> tuple[np.ndarray, dict[str, slice]]:
    """Unknown-input directions ``E`` of named faults (and of every disturbance) as state inputs.

    See the module docstring for the sensor-fault substitution ``[F¹, A F¹ − b]``.

    Parameters
    ----------
    model : FaultModel
        The plant with fault inputs (group ``f``).
    faults : str or sequence of str
        Fault inputs of the model to treat as unknown inputs (default none).
    disturbances : bool
        Also append every disturbance column ``Bd`` (default True).
    rtol : float
        Relative tolerance of ``‖C F¹ − d‖ ≤ rtol ‖d‖`` for a fault that reaches the outputs (default 1e-9).

    Returns
    -------
    E : (n, k) array
        Unknown-input directions: one column per state fault or disturbance, two (``[F¹, A F¹ − b]``)
        per fault that reaches the outputs.
    where : dict of str to slice
        Per input name, its columns of ``E``.

    Raises
    ------
    ParameterError
        When ``model`` is not a FaultModel or ``rtol`` is negative.
    ModelError
        For an unknown fault name.
    DesignError
        For a fault whose output direction is not in the range of ``C``, or a disturbance
        with ``Dd ≠ 0``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2)).with_sensor_faults(["y0"])
    >>> E, where = unknown_input_matrix(m, ["y0_sensor"])
    >>> E.tolist(), where
    ([[1.0, -1.0], [0.0, 0.0]], {'y0_sensor': slice(0, 2, None)})

    References
    ----------
    Douglas et al. 1996, §3.1, (3.4)–(3.5) (sensor fault as the state-fault pair ``[F¹, A F¹]``).
    """
    validate.instance("model", model, FaultModel)
    rtol = validate.non_negative("rtol", rtol)
    if isinstance(faults, str):
        faults = [faults]
    idx = model.index("f", list(faults))
    blocks: list[np.ndarray] = []
    where: dict[str, slice] = {}
    start = 0
    for name, j in zip(faults, idx):
        b, d = model.Bf[:, j], model.Df[:, j]
        if not np.any(d):
            block = b.reshape(-1, 1)
        else:
            F1, *_ = np.linalg.lstsq(model.C, d, rcond=None)
            miss = np.linalg.norm(model.C @ F1 - d)
            if miss > rtol * np.linalg.norm(d):
                raise DesignError(
                    f"fault {name!r} reaches the outputs along a direction outside the range of C "
                    f"(relative residual {miss / np.linalg.norm(d):.2e}): it cannot be written as a state fault "
                    "x̄ = x + F¹μ with C F¹ = Df column, so a UIO cannot decouple it; add sensors or drop it"
                )
            block = np.column_stack([F1, model.A @ F1 - b])
        blocks.append(block)
        where[name] = slice(start, start + block.shape[1])
        start += block.shape[1]
    if disturbances and model.disturbances:
        bad = [nm for nm, col in zip(model.disturbances, model.Dd.T) if np.any(col)]
        if bad:
            raise DesignError(
                f"disturbances {bad} reach the outputs directly (Dd ≠ 0); a UIO needs unknown inputs in the "
                "state equation only. Declare them as faults (group f) to use the sensor-fault substitution"
            )
        for nm, col in zip(model.disturbances, model.Bd.T):
            blocks.append(col.reshape(-1, 1))
            where[nm] = slice(start, start + 1)
            start += 1
    E = np.hstack(blocks) if blocks else np.zeros((model.n, 0))
    return E, where


def _invisible(C: np.ndarray, E: np.ndarray, where: dict[str, slice], tol: float) -> str:
    """Which unknown inputs the outputs cannot see (for the rank error message)."""
    alone = []
    for nm, sl in where.items():
        Ei = linalg.orth(E[:, sl])
        if Ei.shape[1] > _rank_abs(C @ Ei, tol):
            alone.append(nm)
    if alone:
        return f"invisible alone (C maps their directions to a smaller space): {alone}"
    Nc = linalg.null(C @ E)
    Nc = Nc - linalg.null(E) @ (linalg.null(E).T @ Nc) if E.shape[1] else Nc
    joint = [nm for nm, sl in where.items() if np.linalg.norm(Nc[sl]) > 1e-6]
    return f"jointly invisible (their output directions C·E are linearly dependent): {joint}"


def _rank_abs(M: np.ndarray, tol: float) -> int:
    return int((np.linalg.svd(M, compute_uv=False) > tol).sum()) if M.size else 0


# ---------------------------------------------------------------------- helpers
def _fmt(z: np.ndarray) -> list:
    return [complex(np.round(v, 6)) if abs(np.imag(v)) > 0 else float(np.round(np.real(v), 6)) for v in z]


def _observable_split(A1: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, int]:
    """Orthogonal ``Z``: ``Zᵀ A1 Z = [[Ao, 0], [*, Af]]``, ``C Z = [Co, 0]``; and ``dim Ao`` (SLICOT AB01ND, dual)."""
    import slycot

    n, p = A1.shape[0], C.shape[0]
    if n == 0 or p == 0 or not np.any(C):
        return np.eye(n), 0
    _, _, nobs, _, _, Z, _ = slycot.ab01nd(n, p, A1.T.copy(), C.T.copy(), jobz="I")
    return np.asarray(Z), int(nobs)


def _kalman_gain(Ao: np.ndarray, Co: np.ndarray, discrete: bool) -> np.ndarray:
    """Gain of the unit-weight (``Q = I``, ``R = I``) steady-state Kalman filter of an observable ``(Ao, Co)``.

    The default UIO gain: always stabilising, and each mode moves only as far as the weights
    ask.  Pole placement of its own poles with :func:`control.place` (Tits–Yang) gave gains
    10³–10⁴ times larger on some random 10-state, 8-output systems, and equally spaced real poles
    scaled to the plant gave ``‖K‖ ≈ 2.5e5`` on the 14-state PATH model (≈ 40 here).
    """
    no, p = Ao.shape[0], Co.shape[0]
    if no == 0:
        return np.zeros((0, p))
    Q, R = np.eye(no), np.eye(p)
    if discrete:
        P = scipy.linalg.solve_discrete_are(Ao.T, Co.T, Q, R)
        return np.linalg.solve(Co @ P @ Co.T + R, Co @ P @ Ao.T).T
    P = scipy.linalg.solve_continuous_are(Ao.T, Co.T, Q, R)
    return P @ Co.T


def _grid(model: FaultModel, N: np.ndarray) -> np.ndarray:
    if model.is_discrete:
        return np.pi / model.dt * np.logspace(-4, 0, 61)
    lam = np.abs(np.concatenate([scipy.linalg.eigvals(model.A), scipy.linalg.eigvals(N)]))
    lam = lam[lam > 1e-12 * max(1.0, lam.max(initial=0.0))]
    lo, hi = (lam.min(), lam.max()) if lam.size else (1.0, 1.0)
    return np.logspace(np.log10(lo) - 2, np.log10(hi) + 2, 61)


def _freqresp(A, B, C, D, omega, dt) -> np.ndarray:
    z = np.exp(1j * omega * dt) if dt is not None else 1j * omega
    eye = np.eye(A.shape[0])
    return np.array([C @ np.linalg.solve(zk * eye - A, B) + D for zk in z])


# ---------------------------------------------------------------------- design
def uio(
    model: FaultModel, targets: str | Sequence[str], nuisance: Sequence[str] | str = (),
    poles: Sequence[complex] | None = None, *, names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> UIODesign:
    """Unknown-input observer residual generator for one target fault (Chen & Patton 1999, §3.2).

    Parameters
    ----------
    model : FaultModel (continuous or discrete) with fault inputs (group ``f``).
    targets : the fault the residual must respond to: the name of a fault input of the model
        (``'<output>_sensor'`` after :meth:`~fdikit.FaultModel.with_sensor_faults`, ``'<control>_actuator'``,
        …), or a one-element sequence of it.  A bare signal name raises :class:`ParameterError`.
    nuisance : fault inputs to decouple: ``()`` (default) none, ``'others'`` every other fault input
        of the model, or a sequence of names.  Disturbances (group ``d``) are always decoupled;
        noise ``w`` is not.
    poles : the assignable poles of ``N`` — ``n − len(fixed_modes)`` stable values (conjugate
        pairs), placed with :func:`control.place` on the observable part of ``(C, T A)``.  Default
        (``None``): ``K1`` is the gain of the unit-weight steady-state Kalman filter of that part
        (``Q = I``, ``R = I``): stable by construction and with moderate gains; its poles are
        reported in ``poles``.
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[k]``, all tied to the target),
        as :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    UIODesign
        The generator ``z' = N z + (T Bu − K Du) u + K y``, ``r = U⊥ᵀ (y − Du u − C z)`` and its report.

    Raises
    ------
    ParameterError
        A signal name instead of a fault name, more than one target (use :func:`uio_bank`), a ``model``
        that is not a FaultModel, or the target among the nuisance faults.
    ModelError
        Unknown fault names.
    DesignError
        ``rank CE < rank E`` (the message gives both ranks and the invisible inputs); no output
        left after decoupling; an unstable fixed mode (invariant zero of ``(A, E, C)``); poles of the
        wrong number or unstable; a target that the decoupled residual cannot see.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.design.observers.uio import uio
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=[[1, 0, 0], [0, 1, 0], [0, 0, 1]],
    ...                Bu=[[1.0], [1.0], [0.0]], controls=["u"]).with_sensor_faults(["y0", "y2"])
    >>> d = uio(m, "y2_sensor", nuisance="others", poles=[-4.0, -5.0, -6.0])
    >>> d.generator.residuals, d.decoupling["y0_sensor"] < 1e-12, d.decoupling["u"] < 1e-12
    (('y2_sensor[0]', 'y2_sensor[1]'), True, True)

    References
    ----------
    Murray 2012, §1.1.1, Remark 2.4; Douglas et al. 1996, §3.1, (3.4)–(3.5) (sensor-fault directions).
    """
    import control

    if not isinstance(model, FaultModel):
        raise ParameterError(f"uio needs a FaultModel, got {type(model).__name__}")
    given = fault_maps.check_fault_inputs(model, targets, "target")
    if len(given) != 1:
        raise ParameterError(f"uio detects one target fault, got {list(given)}; use uio_bank for several")
    target = given[0]
    jt = model.index("f", target)[0]
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        nuisance = tuple(f for f in model.faults if f != target)
    else:
        nuisance = tuple(dict.fromkeys(fault_maps.check_fault_inputs(model, nuisance, "nuisance")))
        if target in nuisance:
            raise ParameterError(f"the target {target!r} is also listed as a nuisance fault; remove it from nuisance")
    A, C, Bu, Du = model.A, model.C, model.Bu, model.Du
    n, p, m = model.n, model.p, len(model.controls)
    discrete = model.is_discrete
    E, where = unknown_input_matrix(model, nuisance)
    decoupled = tuple(where)

    # --- H = E (CE)⁺ through an orthonormal basis E₀ of Im E (same H; scale-free rank test)
    E0 = linalg.orth(E)
    qe = E0.shape[1]
    normC = max(np.linalg.norm(C, 2), _EPS)
    CE0 = C @ E0
    U, s, _ = np.linalg.svd(CE0, full_matrices=True)
    tol = 1e3 * max(n, p, 1) * _EPS * normC
    rCE = int((s > tol).sum())
    if rCE < qe:
        raise DesignError(
            f"rank(C E) = {rCE} < rank(E) = {qe}: the outputs do not see every unknown-input direction, so no "
            f"UIO decouples them (H = E (CE)⁺ needs rank CE = rank E); {_invisible(C, E, where, tol)}. "
            "Decouple fewer inputs, or add sensors that see them"
        )
    q = p - qe
    if q == 0:
        raise DesignError(
            f"decoupling {list(decoupled)} uses rank(C E) = {qe} of the {p} outputs; no residual is left for "
            f"{target!r}. Decouple fewer inputs or add sensors"
        )
    visibility = float(s[qe - 1] / normC) if qe else 1.0
    H = E0 @ np.linalg.pinv(CE0) if qe else np.zeros((n, p))
    T = np.eye(n) - H @ C
    A1 = T @ A
    Uperp = U[:, qe:]

    # --- fixed modes (unobservable part of (C, A1)) and placement of the observable part
    Z, no = _observable_split(A1, C)
    At = Z.T @ A1 @ Z
    fixed = scipy.linalg.eigvals(At[no:, no:]) if no < n else np.zeros(0, complex)
    margin = 1e3 * max(n, 1) * _EPS * max(1.0, np.linalg.norm(A, 2))
    if fixed.size and not np.all(lti.is_stable(fixed, discrete, margin)):
        bad = fixed[~lti.is_stable(fixed, discrete, margin)]
        raise DesignError(
            f"(C, T A) is not detectable: its unobservable modes {_fmt(bad)} — the invariant zeros of (A, E, C) "
            f"with E the directions of {list(decoupled)} — are not stable "
            f"({'|z| < 1' if discrete else 'Re < 0'} needed); no UIO decoupling these inputs converges"
        )
    Zo = Z[:, :no]
    Ao, Co = At[:no, :no], C @ Zo
    K1 = np.zeros((n, p))
    if poles is None:
        K1 = Zo @ _kalman_gain(Ao, Co, discrete)
    elif no or np.size(poles):
        poles = validate.as_complex_vector("poles", poles)
        if poles.shape != (no,):
            raise DesignError(
                f"need {no} UIO poles (n = {n} minus {n - no} fixed modes {_fmt(fixed)}), got {poles.size}"
            )
        if not np.all(lti.is_stable(poles, discrete)):
            raise DesignError(f"requested UIO poles {_fmt(poles[~lti.is_stable(poles, discrete)])} are not stable")
        W = linalg.orth(Co)  # compress dependent outputs; W Wᵀ Co = Co
        try:
            Lr = np.asarray(control.place(Ao.T, (W.T @ Co).T, poles)).T
        except Exception as exc:  # python-control/scipy raise assorted types
            raise DesignError(f"pole placement of the UIO failed for poles {_fmt(poles)}: {exc}") from exc
        K1 = Zo @ Lr @ W.T
    N = A1 - K1 @ C
    achieved = scipy.linalg.eigvals(N)
    if not np.all(lti.is_stable(achieved, discrete)):
        bad = achieved[~lti.is_stable(achieved, discrete)]
        raise DesignError(f"the placed UIO is not stable: poles {_fmt(bad)}")
    K = K1 + N @ H
    notes = []
    if fixed.size:
        notes.append(
            f"only {no} of {n} poles assignable: {fixed.size} fixed mode(s) {_fmt(fixed)} (invariant zeros of "
            "(A, E, C), unobservable from (C, T A)) kept in N"
        )

    gen = ResidualGenerator(
        A=N,
        B=np.hstack([T @ Bu - K @ Du, K]),
        C=-Uperp.T @ C,
        D=Uperp.T @ np.hstack([-Du, np.eye(p)]),
        controls=model.controls,
        outputs=model.outputs,
        residuals=tuple(f"{target}[{k}]" for k in range(q)),
        dt=model.dt,
        isolates=(target,) * q,
    )
    gen = label_generator(gen, model, names, isolates)

    # --- attained decoupling and target detectability, from the internal form
    omega = _grid(model, N)
    G = gen.internal_form(model)
    Rt = G.freqresp(omega, "f")[:, :, jt]
    Gyt = model.freqresp(omega, "f")[:, :, jt]
    Ry = _freqresp(gen.A, gen.B[:, m:], gen.C, gen.D[:, m:], omega, model.dt)
    bound = np.linalg.norm(Ry, 2, axis=(1, 2)) * np.linalg.norm(Gyt, axis=1)
    if not np.any(bound > 0):
        raise DesignError(f"fault {target!r} does not reach the outputs at all; nothing can detect it")
    seen = np.linalg.norm(Rt, axis=1)
    rel = float(np.max(seen / np.where(bound > 0, bound, np.inf)))
    if rel < _ZERO:
        raise DesignError(
            f"target {target!r} is in the unknown-input subspace: after decoupling {list(decoupled)} its "
            f"residual response is {rel:.1e} of ‖filter‖·‖plant‖ (numerically zero). No linear residual "
            "decoupled from these inputs can detect it; decouple fewer faults"
        )
    target_gain = float(seen.max())
    decoupling: dict[str, float] = {}
    for grp, names in (("f", nuisance), ("d", model.disturbances), ("u", model.controls)):
        if names:
            Rg = G.freqresp(omega, grp)
            for nm in names:
                col = model.index(grp, nm)[0]
                decoupling[nm] = float(np.max(np.linalg.norm(Rg[:, :, col], axis=1)) / target_gain)
    return UIODesign(
        generator=gen, target=target, decoupled=decoupled, E=E, H=H, T=T, K=K, K1=K1, N=N, poles=achieved,
        fixed_modes=fixed, residual_basis=Uperp, visibility=visibility, omega=omega, target_gain=target_gain,
        decoupling=decoupling, notes=tuple(notes), model=model,
    )


def uio_bank(
    model: FaultModel,
    targets: Sequence[str] | str | None = None,
    nuisance: Sequence[str] | str = (),
    *,
    poles: Sequence[complex] | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> list[UIODesign]:
    """A bank of UIOs (generalised observer scheme): one per fault, each decoupled from the others.

    Stack the bank into one generator with ``stack_generators([d.generator for d in bank])``
    (:func:`~fdikit.residuals.stack_generators`).  Unlike a Beard–Jones bank, no mutual
    detectability is needed (Murray 2012, §1.1): each UIO only needs its own rank and zero conditions.

    Parameters
    ----------
    model : FaultModel
    targets : the fault inputs to isolate (default all of the model's).  UIO ``i`` targets
        ``targets[i]`` and decouples every other target plus ``nuisance`` (and the disturbances).
    nuisance : fault inputs decoupled by every member: ``()`` (default) none, ``'others'`` every
        fault input of the model that is not a target, or a sequence of names.  Faults of the model
        that are neither targets nor nuisance are neither targeted nor decoupled.
    poles : passed to every :func:`uio` (``None``: each design's default).
    names, isolates : optional
        Names and isolated faults of the residuals of the whole bank, member after member (default
        ``<target>[k]`` of each member, tied to its target), as :func:`~fdikit.design.labels.residual_labels`;
        each member's generator gets its share.

    Returns
    -------
    list of UIODesign
        One design per target, in the order of ``targets``.

    Raises
    ------
    ParameterError
        A signal name instead of a fault name, or ``nuisance=None``; and what :func:`uio` raises.
    ModelError
        A model without fault inputs, or an unknown fault name.
    DesignError
        A member that cannot be designed (the message names its target and gives :func:`uio`'s reason).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3)).with_sensor_faults(["y0", "y2"])
    >>> bank = uio_bank(m, poles=[-4.0, -5.0, -6.0])
    >>> [(d.target, d.decoupled) for d in bank]
    [('y0_sensor', ('y2_sensor',)), ('y2_sensor', ('y0_sensor',))]

    References
    ----------
    Murray 2012, §1.1.1, Remark 2.4.
    """
    faults = model.faults if targets is None else fault_maps.check_fault_inputs(model, targets, "target")
    if not faults:
        raise ModelError("uio_bank needs at least one fault; the model has none (add faults with with_*_faults)")
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        nuisance = model.faults
    extra = tuple(f for f in fault_maps.check_fault_inputs(model, nuisance, "nuisance") if f not in faults)
    bank = []
    for f in faults:
        try:
            bank.append(uio(model, f, nuisance=[g for g in faults if g != f] + list(extra), poles=poles))
        except DesignError as exc:
            raise DesignError(f"bank member for target {f!r}: {exc}") from exc
    if names is None and isolates is None:
        return bank
    gens = [d.generator for d in bank]
    res, iso = residual_labels(model, sum(len(g.residuals) for g in gens), names, isolates,
                               default_names=[r for g in gens for r in g.residuals],
                               default_isolates=[k for g in gens for k in g.isolates])
    out, start = [], 0
    for d, g in zip(bank, gens):
        stop = start + len(g.residuals)
        out.append(dataclasses.replace(d, generator=dataclasses.replace(g, residuals=res[start:stop],
                                                                         isolates=iso[start:stop])))
        start = stop
    return out
