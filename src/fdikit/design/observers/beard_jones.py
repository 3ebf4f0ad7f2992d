"""Beard–Jones detection filters by left-eigenvector assignment, and restricted-diagonal filters.

A Beard–Jones detection filter is a full-order observer ``x̂' = (A + LC) x̂ + (B + LD) u − L y``
whose gain makes every fault's detection space ``T_i`` invariant under ``A + LC``, so that
fault ``i`` drives the residual only along ``C T_i``; the output projector ``Ĥ_i``
annihilating ``Σ_{j≠i} C T_j`` then gives a residual ``z_i`` that sees fault ``i`` alone
(Douglas et al. 1996, §4.2 and App. A–B).

The gain comes from Algorithm B.1 (Douglas et al. 1996, App. B): the spectrum is split
into sets ``Ξ_i`` (|Ξ_i| = ν_i = dim T_i) and ``Ξ_0`` (the rest, ν_0 = n − Σν_i); for each
``λ_ij ∈ Ξ_i`` the left eigenvector ``v_ij`` must be orthogonal to the complementary
faults ``F̂_i = [T_j]_{j≠i}`` (``F̂_0`` = all of them), i.e. it lies in the null space
(b.10)::

    [Aᵀ − λ_ij I   Cᵀ] [v_ij]
    [F̂_iᵀ          0 ] [w_ij] = 0,

and the gain solves (b.12) ``𝒱ᵀ L = 𝒲ᵀ``, so that ``v_ijᵀ (A + LC) = λ_ij v_ijᵀ``.  The
printed (b.9) lists the fault maps ``F_j``, but the derivation it summarises ((b.2)–(b.6),
App. B) asks the left eigenvectors to annihilate the detection spaces ``T_j*``; so here
``F̂_i`` holds bases of the *detection spaces* of the other faults.  The two differ when
``dim T_j > rank F_j`` (a sensor fault's ``[F¹, A F¹]``), and with the maps alone ``T_j``
would not be invariant under ``A + LC``.

The report states the selection criterion — the left eigenvectors are "the set with the
greatest degree of linear independence", measured by the smallest singular value of the
eigenvector matrix (Douglas et al. 1996, §4.2.1, after Douglas & Speyer 1995b) — but not
the search.  fdikit
picks each ``v_ij ∈ Im V_ij`` to maximise the smallest singular value of ``𝒱`` by the
rank-one sweep of Kautsky, Nichols & Van Dooren (1985, method 0): each vector in turn is
replaced by the unit vector of its admissible subspace farthest from the span of the
others, until σ_min(𝒱) stops growing.  The design reports σ(𝒱) next to the upper bounds
σ([V_ij]) as in the report's (4.3) and (4.8).

Sign conventions: the report writes the filter with ``A + LC`` and the residual ``C x̂ + D u − y``.
fdikit's :attr:`BeardJonesDesign.gain` is the observer gain of
``x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)`` (state matrix ``A − L C``, python-control's
``lqe`` sign), i.e. the *negative* of the report's matrix, which stays available as
:attr:`BeardJonesDesign.report_gain` (``A + report_gain C = A − gain C``); the equations above
are in the report's sign.  The residual is ``y − C x̂ − D u`` (the innovation), the negative of
the report's, so a positive bias gives a positive residual.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import linalg, lti, validate
from fdikit.design.labels import label_generator
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.fault_maps import resolve_faults
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator, stack_generators

__all__ = ["BeardJonesDesign", "beard_jones", "restricted_diagonal", "RestrictedDiagonalDesign"]


@dataclass(frozen=True, eq=False)
class BeardJonesDesign(FieldReport):
    """A Beard–Jones detection filter and its design report.

    Attributes
    ----------
    generator : residual generator; residuals ``<fault>[k]`` = coordinates of ``Ĥ_i r`` in
        ``Ĥ_i C T_i`` (``dim C T_i`` per fault), each tied to its fault.
    gain : observer gain ``L`` of ``x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)``: the generator's state
        matrix is ``A − L C``.  The report prints the negative (its filter is ``A + L C``); see
        :attr:`report_gain`.
    assigned_poles : assigned sets by fault, plus ``'complement'`` (Ξ_0).
    poles : eigenvalues of ``A − L C`` actually obtained.
    detection_spaces : orthonormal bases of ``T_i``.
    projectors : ``Ĥ_i`` (p x p, symmetric, idempotent, kernel ``Σ_{j≠i} C T_j``).
    left_eigenvectors : ``𝒱`` (n x n, complex in general), columns in the order of ``order``.
    order : the eigenvalue of each column of ``𝒱``.
    sigma, sigma_bound : ``σ(𝒱)`` and the upper bounds ``σ([V_ij])`` (report (4.3)/(4.8)).
    model : the FaultModel the design was made for (keyword-only; set by the design function).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bf=[[1.0, 0], [0, 1.0], [0, 0]], faults=["f1", "f2"])
    >>> d = beard_jones(m, ["f1", "f2"], {"f1": [-4.0], "f2": [-5.0]}, [-6.0])
    >>> d.generator.residuals, np.allclose(d.report_gain, -d.gain), round(d.condition_number, 6)
    (('f1[0]', 'f2[0]'), True, 1.0)

    References
    ----------
    Douglas et al. 1996, App. B, Alg. B.1, (b.10), (b.12); §4.2.1, (4.3).
    """

    generator: ResidualGenerator
    gain: np.ndarray
    assigned_poles: dict[str, np.ndarray]
    poles: np.ndarray
    detection_spaces: dict[str, np.ndarray]
    projectors: dict[str, np.ndarray]
    left_eigenvectors: np.ndarray
    order: np.ndarray
    sigma: np.ndarray
    sigma_bound: np.ndarray

    @property
    def report_gain(self) -> np.ndarray:
        """The gain as Douglas et al. 1996 print it: ``L`` of ``A + L C`` (``= −gain``), the solution of (b.12)."""
        return -self.gain

    @property
    def condition_number(self) -> float:
        """``σ_max(𝒱) / σ_min(𝒱)`` of the unit-norm left eigenvectors."""
        return float(self.sigma[0] / self.sigma[-1])

    def report(self) -> dict:
        """``gain`` (the attribute ``gain``), ``assigned_poles`` (by fault), ``poles`` (obtained),
        ``detection_spaces`` (``T_i``), ``projectors`` (``Ĥ_i``), ``left_eigenvectors`` (``𝒱``), ``sigma`` and
        ``sigma_bound`` (singular values of ``𝒱`` and their bounds) and ``condition_number`` (of ``𝒱``)."""
        return {"gain": self.gain, "assigned_poles": self.assigned_poles, "poles": self.poles,
                "detection_spaces": self.detection_spaces, "projectors": self.projectors,
                "left_eigenvectors": self.left_eigenvectors, "sigma": self.sigma, "sigma_bound": self.sigma_bound,
                "condition_number": self.condition_number}


def _self_conjugate(name: str, lam: np.ndarray, scale: float) -> None:
    for z in lam[lam.imag != 0]:
        if np.min(np.abs(lam - np.conj(z))) > 1e-10 * scale:
            raise DesignError(f"eigenvalue set {name!r} has {z} without its conjugate; complex values come in pairs")


def _admissible(A, C, Fhat, lam, rtol) -> tuple[np.ndarray, np.ndarray]:
    """``V, W`` spanning the solutions of (b.10) for one eigenvalue (orthonormal in ``[v; w]``)."""
    n, p = A.shape[0], C.shape[0]
    top = np.hstack([A.T - lam * np.eye(n), C.T])
    M = np.vstack([top, np.hstack([Fhat.T, np.zeros((Fhat.shape[1], p))])]) if Fhat.shape[1] else top
    N = linalg.null(M, rtol)
    return N[:n], N[n:]


def _select(V_blocks: list[np.ndarray], pair: list[bool], sweeps: int, rng: np.random.Generator):
    """Kautsky–Nichols–Van Dooren rank-one sweep maximising σ_min of the unit eigenvector matrix.

    ``V_blocks[j]`` spans the admissible v for slot j; ``pair[j]`` marks a complex slot whose
    conjugate partner is the conjugate vector.  Returns the coefficient vectors.
    """
    Q = [linalg.orth(Vb) for Vb in V_blocks]
    R = [np.linalg.lstsq(Vb, Qb, rcond=None)[0] for Vb, Qb in zip(V_blocks, Q)]  # V_j R_j = Q_j
    coef = []
    for Qb in Q:
        c = rng.standard_normal(Qb.shape[1]) + (1j * rng.standard_normal(Qb.shape[1]) if np.iscomplexobj(Qb) else 0)
        coef.append(c / np.linalg.norm(c))

    def matrix(cs, skip=None):
        cols = []
        for k, (Qb, c, is_pair) in enumerate(zip(Q, cs, pair)):
            if k == skip:
                continue
            v = Qb @ c
            v = v / np.linalg.norm(v)
            cols.extend([v, v.conj()] if is_pair else [v])
        return np.column_stack(cols)

    def smin(cs):
        return np.linalg.svd(matrix(cs), compute_uv=False)[-1]

    best, best_val = list(coef), smin(coef)
    for _ in range(sweeps):
        for j, Qb in enumerate(Q):
            if len(Q) > 1:
                U, s, _ = np.linalg.svd(matrix(coef, skip=j), full_matrices=True)
                r = int((s > 1e-12 * max(s[0], 1e-300)).sum())
                S = U[:, r:]  # orthogonal complement of the other vectors
                if S.shape[1] == 0:
                    continue
                _, _, Wh = np.linalg.svd(S.conj().T @ Qb)
                coef[j] = Wh[0].conj()
        val = smin(coef)
        if val > best_val * (1 + 1e-9):
            best, best_val = list(coef), val
        else:
            break
    return [Rb @ c for Rb, c in zip(R, best)]


def _assign(model, spaces, sets, sweeps, seed, rtol):
    """Algorithm B.1 steps 2–4: admissible bases, selection, gain.  ``sets`` maps group → poles.

    Returns the report's gain (b.12), ``L`` of ``A + L C``; callers negate it into the observer gain.
    """
    A, C = model.A, model.C
    n = model.n
    names = [k for k in sets if k != "complement"]
    slots, V_blocks, W_blocks, pair = [], [], [], []
    for key in [*names, "complement"]:
        others = [spaces[k] for k in names if k != key]
        Fhat = np.hstack(others) if others else np.zeros((n, 0))
        for lam in sets[key]:
            if lam.imag < 0:
                continue  # the conjugate partner of a complex slot
            lam_c = complex(lam) if lam.imag != 0 else float(lam.real)
            V, W = _admissible(A, C, Fhat, lam_c, rtol)
            if V.shape[1] == 0 or linalg.rank(V) == 0:
                raise DesignError(
                    f"no left eigenvector for λ = {lam_c} in set {key!r}: the equations (b.10) have no solution; "
                    "λ is an invariant zero of the complementary faults or an unobservable mode — choose another value"
                )
            slots.append(lam_c)
            V_blocks.append(V)
            W_blocks.append(W)
            pair.append(lam.imag != 0)
    rng = np.random.default_rng(seed)
    coef = _select(V_blocks, pair, sweeps, rng)
    cols_v, cols_w, order = [], [], []
    for V, W, c, lam, is_pair in zip(V_blocks, W_blocks, coef, slots, pair):
        v, w = V @ c, W @ c
        s = np.linalg.norm(v)
        v, w = v / s, w / s
        cols_v.extend([v, v.conj()] if is_pair else [v.real if not np.iscomplexobj(lam) else v])
        cols_w.extend([w, w.conj()] if is_pair else [w.real if not np.iscomplexobj(lam) else w])
        order.extend([lam, np.conj(lam)] if is_pair else [lam])
    Vm, Wm = np.column_stack(cols_v), np.column_stack(cols_w)
    sigma = np.linalg.svd(Vm, compute_uv=False)
    if sigma[-1] <= 1e3 * np.finfo(float).eps * n:
        raise DesignError(
            f"the selected left eigenvectors are dependent (σ_min = {sigma[-1]:.2e}); the specification leaves "
            "too few independent directions — check the set sizes against the detection-space dimensions"
        )
    L = np.linalg.solve(Vm.T, Wm.T)
    if np.abs(L.imag).max() > 1e-8 * max(np.abs(L).max(), 1.0):
        raise DesignError("the gain came out complex: complex eigenvalues must come in conjugate pairs")
    bound = np.linalg.svd(np.hstack(V_blocks), compute_uv=False)
    return L.real, Vm, np.array(order), sigma, bound


def _check_sets(model, dims, poles, complement_poles):
    n, discrete = model.n, model.is_discrete
    scale = max(np.linalg.norm(model.A, 2), 1.0)
    if not isinstance(poles, Mapping):
        raise ParameterError("poles must be a mapping fault name -> poles (eigenvalues), got "
                             f"{type(poles).__name__}; e.g. {{{next(iter(dims), 'fault')!r}: [-1.0]}}")
    sets = {}
    for name, nu in dims.items():
        if name not in poles:
            raise DesignError(f"no poles given for fault {name!r}; it needs {nu} (its detection-space dimension)")
        sets[name] = validate.as_complex_vector(f"poles[{name!r}]", poles[name])
    unknown = set(poles) - set(dims)
    if unknown:
        raise ParameterError(f"poles given for unknown fault(s) {sorted(unknown)}; faults are {list(dims)}")
    nu0 = n - sum(dims.values())
    sets["complement"] = (validate.as_complex_vector("complement_poles", complement_poles)
                          if complement_poles is not None else np.zeros(0, dtype=complex))
    wanted = dict(dims, complement=nu0)
    for name, lam in sets.items():
        if lam.size != wanted[name]:
            raise DesignError(f"set {name!r} has {lam.size} eigenvalues but needs {wanted[name]} "
                              f"(detection-space dimensions {dims}, n = {n})")
        _self_conjugate(name, lam, scale)
        if not np.all(lti.is_stable(lam, discrete)):
            raise DesignError(f"set {name!r} has unstable eigenvalues {lam[~lti.is_stable(lam, discrete)].tolist()}")
    everything = np.concatenate(list(sets.values()))
    for i, z in enumerate(everything):
        if np.any(np.abs(everything[i + 1 :] - z) <= 1e-9 * scale):
            raise DesignError(f"eigenvalue {z} is assigned twice; Algorithm B.1 needs distinct values")
    return sets


def _residual_generator(model, L, names, spaces, rtol):
    """Observer with gain L (state matrix A − LC) and per-fault projected residual coordinates."""
    C = model.C
    projectors, blocks, res_names, isolates = {}, [], [], []
    for name in names:
        others = [spaces[k] for k in names if k != name]
        h = linalg.orth(C @ np.hstack(others), rtol) if others else np.zeros((model.p, 0))
        H = np.eye(model.p) - h @ h.T
        Q = linalg.orth(H @ C @ spaces[name], rtol)
        if Q.shape[1] == 0:
            raise DesignError(f"fault {name!r} is invisible after projection: C T_i lies in the other faults' images")
        projectors[name] = H
        blocks.append(Q)
        res_names += [f"{name}[{k}]" for k in range(Q.shape[1])]
        isolates += [name] * Q.shape[1]
    Q = np.hstack(blocks)
    # L is the observer gain (the report's matrix negated): r = y − C x̂ − Du u, x̂' = (A − LC) x̂ + (Bu − L Du) u + L y
    gen = observer_generator(model, L, res_names, Q)
    return gen, isolates, projectors


def beard_jones(
    model: FaultModel,
    targets: Mapping[str, np.ndarray] | Sequence[str] | str,
    poles: Mapping[str, Sequence[complex]],
    complement_poles: Sequence[complex] | None = None,
    *,
    sweeps: int = 100,
    seed: int = 0,
    rtol: float | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> BeardJonesDesign:
    """Beard–Jones detection filter by left-eigenvector assignment (Douglas et al. 1996, App. B, Alg. B.1).

    Parameters
    ----------
    model : FaultModel (continuous or discrete; ``D`` of the controls is handled).
    targets : the faults to detect and isolate: fault names (``'<output>_sensor'``,
        ``'<output>_sensor:magnitude'``, ``'<control>_actuator'``, fault inputs of the model; see
        :func:`resolve_faults`) or a mapping name → fault map ``F``.  A bare signal name raises
        :class:`ParameterError`.
    poles : for each fault, ``ν_i = dim T_i`` distinct eigenvalues of ``A − L C`` (Ξ_i).
    complement_poles : the ``ν_0 = n − Σ ν_i`` remaining eigenvalues (Ξ_0).
    sweeps, seed : eigenvector selection (sweep limit, default 100; seed of the random start, default 0).
    rtol : relative rank tolerance of the subspace computations (default ``None``: fdikit.linalg's default).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<fault>[k]`` tied to each target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    BeardJonesDesign
        ``gain`` is the observer gain (``A − L C``); ``report_gain`` the report's ``L`` of ``A + L C``.

    Raises
    ------
    DesignError
        Σ ν_i > n; faults not output separable (the pairs are named); not mutually
        detectable (the extra zeros are named); an invariant zero of a fault missing from
        its set; a set of the wrong size, unstable, not self-conjugate or repeated; an
        eigenvalue that admits no left eigenvector.
    ParameterError
        A bad argument: not a FaultModel, ``poles`` not a mapping or keyed by a non-target, poles that are not
        finite numbers, negative ``sweeps``/``seed``/``rtol``, a bare signal name.
    ModelError
        A name that is not a fault of the model.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bf=[[1.0, 0], [0, 1.0], [0, 0]], faults=["f1", "f2"])
    >>> d = beard_jones(m, ["f1", "f2"], {"f1": [-4.0], "f2": [-5.0]}, complement_poles=[-6.0])
    >>> {k: T.shape[1] for k, T in d.detection_spaces.items()}, np.sort(d.poles.real).round(6).tolist()
    ({'f1': 1, 'f2': 1}, [-6.0, -5.0, -4.0])

    References
    ----------
    Douglas et al. 1996, App. B, Alg. B.1, (b.9)–(b.12); §4.2.1, (4.3).
    """
    validate.integer("sweeps", sweeps, minimum=0)
    validate.integer("seed", seed, minimum=0)
    if rtol is not None:
        validate.non_negative("rtol", rtol)
    maps = resolve_faults(model, targets)
    A, C = model.A, model.C
    spaces = {k: linalg.detection_space(A, C, F, rtol) for k, F in maps.items()}
    dims = {k: T.shape[1] for k, T in spaces.items()}
    if sum(dims.values()) > model.n:
        raise DesignError(
            f"the detection spaces need {sum(dims.values())} dimensions {dims} but the model has n = {model.n}; "
            "split the faults over several filters or use restricted_diagonal()"
        )
    ok, pairs = linalg.output_separable(C, list(spaces.values()), rtol)
    if not ok:
        keys = list(spaces)
        what = ", ".join(f"({keys[i]}, {keys[j]})" for i, j in pairs) or f"the set {keys} (no pair alone)"
        raise DesignError(
            f"faults not output separable: {what}; their output images C T_i are dependent. Keep only the "
            "magnitude direction of a sensor fault ('<output>_sensor:magnitude'), or put them in different filters"
        )
    mutual, joint, union = linalg.mutually_detectable(A, C, list(maps.values()))
    if not mutual:
        raise DesignError(
            f"faults not mutually detectable: zeros of the joint fault map {np.round(joint, 6).tolist()} differ from "
            f"the union of the single-fault zeros {np.round(union, 6).tolist()}; the extra zeros would be fixed "
            "filter eigenvalues. Use restricted_diagonal() or a UIO bank"
        )
    sets = _check_sets(model, dims, poles, complement_poles)
    scale = max(np.linalg.norm(A, 2), 1.0)
    for k, F in maps.items():
        zeros, _ = linalg.invariant_zeros(A, C, F)
        for z in zeros:
            if np.min(np.abs(sets[k] - z)) > 1e-6 * scale:
                raise DesignError(
                    f"fault {k!r} has the invariant zero {z:.6g}, a fixed eigenvalue of its detection space; "
                    f"include it in its set (given {sets[k].tolist()})"
                )
    L_report, Vm, order, sigma, bound = _assign(model, spaces, sets, sweeps, seed, rtol)
    L = -L_report  # the observer gain: A + L_report C = A − L C
    achieved = scipy.linalg.eigvals(A - L @ C)
    gen, default_iso, projectors = _residual_generator(model, L, list(spaces), spaces, rtol)
    gen = label_generator(gen, model, names, isolates, default_isolates=default_iso)
    return BeardJonesDesign(gen, L, sets, achieved, spaces, projectors, Vm, order, sigma, bound, model=model)


@dataclass(frozen=True, eq=False)
class RestrictedDiagonalDesign(FieldReport):
    """A bank of restricted-diagonal filters, one per target fault (App. A.4).

    ``filters[name]`` is the single-group design whose nuisance detection space ``T̂_i``
    (minimal UOS of all other faults together) is invariant; ``generator`` stacks them.

    Attributes
    ----------
    generator : ResidualGenerator
        The stacked bank; residuals ``<target>[k]``, each tied to its target.
    filters : dict of str to BeardJonesDesign
        Per target, its filter (``gain`` is the observer gain of ``A − L C``).
    nuisance_spaces : dict of str to (n, k) array
        Per target, an orthonormal basis of ``T̂_i``.
    model : FaultModel or None
        The model the design was made for (keyword-only; set by :func:`restricted_diagonal`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bf=[[1.0, 0], [0, 1.0], [0, 0]], faults=["f1", "f2"])
    >>> rd = restricted_diagonal(m, ["f1", "f2"], poles=[-4.0, -5.0, -6.0])
    >>> list(rd.filters), {k: T.shape for k, T in rd.nuisance_spaces.items()}
    (['f1', 'f2'], {'f1': (3, 1), 'f2': (3, 1)})

    References
    ----------
    Douglas et al. 1996, App. A.4, (a.10)–(a.11).
    """

    generator: ResidualGenerator
    filters: dict[str, BeardJonesDesign]
    nuisance_spaces: dict[str, np.ndarray]
    def report(self) -> dict:
        """By target fault: ``gains`` (each filter's ``gain``), ``poles``, ``nuisance_spaces`` (``T̂_i``),
        ``projectors`` (``Ĥ_i``) and ``condition_numbers`` (of each filter's left eigenvectors)."""
        f = self.filters
        return {"gains": {k: d.gain for k, d in f.items()}, "poles": {k: d.poles for k, d in f.items()},
                "nuisance_spaces": self.nuisance_spaces,
                "projectors": {k: d.projectors[k] for k, d in f.items()},
                "condition_numbers": {k: d.condition_number for k, d in f.items()}}


def restricted_diagonal(
    model: FaultModel,
    targets: Mapping[str, np.ndarray] | Sequence[str],
    poles: Sequence[complex],
    *,
    sweeps: int = 100,
    seed: int = 0,
    rtol: float | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> RestrictedDiagonalDesign:
    """Restricted-diagonal detection filters (RDDFP, Douglas et al. 1996, App. A.4).

    For each target ``i`` the complementary faults ``F̂_i`` (a.10) are lumped into one
    nuisance fault whose minimal unobservability subspace ``T̂_i`` is made invariant (its
    own Beard–Jones design with a single group); the projector ``Ĥ_i`` annihilates
    ``C T̂_i`` and the residual ``z_i = Ĥ_i r`` (a.11) is decoupled from every fault but
    ``F_i``.  Unlike :func:`beard_jones` this needs neither mutual detectability nor
    ``Σ ν_i ≤ n`` — only that each target stays visible: ``C T_i ⊄ C T̂_i``.

    Parameters
    ----------
    model : FaultModel (continuous or discrete).
    targets : at least two fault names (as in :func:`beard_jones`) or a mapping name → ``F``;
        each is the target of one filter and a complementary (nuisance) fault of all the others.
    poles : n stable, distinct, self-conjugate eigenvalues of ``A − L C`` used by every filter;
        the first ``dim T̂_i`` go to the nuisance space (keep conjugate pairs adjacent).
    sweeps, seed, rtol : as in :func:`beard_jones`.
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<target>[k]`` tied to its target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    RestrictedDiagonalDesign
        One filter per target and their stack; each filter's ``gain`` is the observer gain (``A − L C``).

    Raises
    ------
    DesignError
        Fewer than two targets; nuisance faults that fill the state space or hide a target
        (``C T_i ⊆ C T̂_i``); a conjugate pair split at ``dim T̂_i``; poles unstable, repeated or
        not self-conjugate; an eigenvalue that admits no left eigenvector.
    ParameterError
        Not ``n`` finite poles, a negative ``sweeps``, a bare signal name.
    ModelError
        A name that is not a fault of the model.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=np.diag([-1.0, -2.0, -3.0]), C=np.eye(3), Bf=[[1.0, 0], [0, 1.0], [0, 0]], faults=["f1", "f2"])
    >>> rd = restricted_diagonal(m, ["f1", "f2"], poles=[-4.0, -5.0, -6.0])
    >>> rd.generator.residuals
    ('f1[0]', 'f1[1]', 'f2[0]', 'f2[1]')

    References
    ----------
    Douglas et al. 1996, App. A.4, (a.10)–(a.11); App. B, Alg. B.1.
    """
    maps = resolve_faults(model, targets)
    if len(maps) < 2:
        raise DesignError("a restricted-diagonal bank needs at least two faults")
    poles = validate.as_complex_vector("poles", poles)
    if poles.size != model.n:
        raise ParameterError(f"need n = {model.n} poles, got {poles.size}")
    validate.integer("sweeps", sweeps, minimum=0)
    filters, spaces, gens = {}, {}, []
    A, C = model.A, model.C
    for target, F in maps.items():
        nuisance = np.hstack([G for k, G in maps.items() if k != target])
        T_hat = linalg.detection_space(A, C, nuisance, rtol)
        nu = T_hat.shape[1]
        if nu >= model.n:
            raise DesignError(f"the nuisance faults of {target!r} fill the state space (dim T̂ = {nu}); no residual")
        image_hat = linalg.orth(C @ T_hat, rtol)
        target_image = linalg.orth(C @ linalg.detection_space(A, C, F, rtol), rtol)
        if linalg.rank(np.hstack([image_hat, target_image]), rtol) == image_hat.shape[1]:
            raise DesignError(f"target {target!r} is hidden by its nuisance faults: C T_i ⊆ C T̂_i")
        if np.iscomplex(poles[nu - 1]) and nu < poles.size and np.isclose(poles[nu], np.conj(poles[nu - 1])):
            raise DesignError(f"poles[{nu - 1}], poles[{nu}] are a conjugate pair split between the nuisance space "
                              f"(dim {nu}) and the rest for target {target!r}; reorder the poles")
        nuis_name = f"not_{target}"
        sets = {nuis_name: poles[:nu]}
        sub = _check_sets(model, {nuis_name: nu}, sets, poles[nu:])
        L_report, Vm, order, sigma, bound = _assign(model, {nuis_name: T_hat}, sub, sweeps, seed, rtol)
        L = -L_report  # the observer gain (A − L C)
        # residual: every output direction outside C T̂ (a.11), tied to the target
        H = np.eye(model.p) - image_hat @ image_hat.T
        Q = linalg.orth(H, rtol)
        res_names = [f"{target}[{k}]" for k in range(Q.shape[1])]
        gen = label_generator(observer_generator(model, L, res_names, Q), model,
                              default_isolates=[target] * len(res_names))
        filters[target] = BeardJonesDesign(gen, L, sub, scipy.linalg.eigvals(A - L @ C), {nuis_name: T_hat},
                                           {target: H}, Vm, order, sigma, bound, model=model)
        spaces[target] = T_hat
        gens.append(gen)
    return RestrictedDiagonalDesign(label_generator(stack_generators(gens), model, names, isolates), filters, spaces,
                                    model=model)
