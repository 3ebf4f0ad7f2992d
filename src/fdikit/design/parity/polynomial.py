"""Parity-space fault detection filters from the DAE (polynomial) form (van der Ploeg 2018, Ch. 2, Sec. 4-3-1).

A discrete model is written as the difference-algebraic equation (2.1)::

    H(q)[x] + L(q)[z] + F(q)[f] = 0,        x = [states; disturbances],  z = [outputs; controls]

with ``q`` the forward shift.  A :class:`~fdikit.model.FaultModel` maps to it as in (2.10)
(with ``G = I``) and (4.6)::

    H(q) = [[−q I + A, Bd], [C, Dd]],   L = [[0, Bu], [−I, Du]],   F = [[Bf], [Df]]

A row polynomial ``N(q) = Σ N_i qⁱ`` with ``N H = 0`` (2.4a) and ``N F ≠ 0`` (2.4b) gives the
residual generator (2.6) ``r = d⁻¹(q) N(q) L(q)[z]``, whose fault map is (2.7)
``r = G(q)[f]``, ``G = −N F / d``.  Lemma 2-1.2 turns ``N H = 0`` into the linear equation
``N̄ H̄ = 0`` on the coefficient row ``N̄ = [N_0 … N_dN]`` and the block-Toeplitz ("bar")
matrix ``H̄`` (block row ``i`` holds ``H_0 … H_dH`` from block column ``i``), and fixes the
DC gain by (2.8b)/(2.9) ``Σ N̄ F̄ / Σ d̄ = −1`` so that ``G(1) = 1``.

Choices and errata (van der Ploeg 2018, Lemma 2-1.2, Sec. 4-3-1):

* the sign of the DC condition is that of (2.8b)/(2.9), ``−1``; the case-study LP (4.8) prints
  ``+1``, which gives ``G(1) = −1`` under (2.7), contradicting the unit DC gain the text asks for;
* the thesis solves the LP (2.9) with GUROBI.  With the minimal degree the left null space is
  one-dimensional and the solution is unique; otherwise fdikit takes the least-norm ``N̄`` in
  the null space that meets the DC condition (an orthogonal projection, no LP solver);
* ``d(q) = Π (q − p_i)`` with real poles (default a triple pole at ``p = 0.9048 = e^{−10 h}``
  for ``h = 0.01``, Sec. 4-3-1); its degree is ``d_N + d_L + 1`` so that the filter is
  strictly proper, ``deg d > deg N L``;
* the filter is realised as a minimal state space (the thesis, Sec. 4-3-1): a chain of
  first-order sections ``1/(q − p_i)`` with the numerator in the Newton basis
  ``Π_{j<i} (q − p_j)``, which stays well conditioned for the high orders of the
  experimental model (a companion form of ``(q − 0.9)²⁹`` would not).

The bar matrices, the left null space, the minimal degree and the rank tests (2.5) are in
:mod:`fdikit.design.parity.polynomial_rank`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit import linalg
from fdikit.dae import DAEModel, dae_form
from fdikit.design.labels import fault_label, label_generator, warn_unlisted_faults
from fdikit.design.parity.polynomial_rank import bar, bar_matrices, detectability, minimal_degree, target_fault
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport, joined_form, no_internal_form
from fdikit.residuals import ResidualGenerator

__all__ = [
    "PolynomialParityDesign",
    "RESPONSE_RTOL",
    "parity_filter",
]


def real_poles(poles, count: int) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(poles, dtype=complex))
    if np.ndim(poles) == 0:
        arr = np.repeat(arr, count)
    if np.any(np.abs(arr.imag) > 0) or not np.all(np.isfinite(arr)):
        raise DesignError(f"poles must be finite real numbers (a repeated real pole as in Sec. 4-3-1), got {poles!r}")
    arr = arr.real
    if np.any(np.abs(arr) >= 1):
        raise DesignError(f"poles {arr.tolist()} must lie strictly inside the unit circle for a stable d(q)")
    return arr


def _newton_chain(num: np.ndarray, poles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Minimal realisation of ``num(q) / Π (q − p_i)`` (``num`` ascending, one column per input).

    Chain ``x_1⁺ = p_1 x_1 + b_1ᵀ v``, ``x_i⁺ = p_i x_i + x_{i−1} + b_iᵀ v``, ``r = x_n + D v``:
    its numerator is ``Σ b_i Π_{j<i}(q − p_j)`` (Newton basis).
    """
    n = poles.size
    num = np.vstack([num, np.zeros((n + 1 - num.shape[0], num.shape[1]))])
    D = num[n].copy()
    rem = num[:n] - np.outer(np.poly(poles)[::-1][:n], D)  # num − D d(q), degree < n
    B = np.zeros((n, num.shape[1]))
    for i, p in enumerate(poles):  # synthetic division by (q − p): remainder b_i, quotient carries on
        quot = np.zeros_like(rem)
        acc = np.zeros(num.shape[1])
        for k in range(rem.shape[0] - 1, -1, -1):
            acc = rem[k] + p * acc
            if k:
                quot[k - 1] = acc
        B[i] = acc
        rem = quot
    A = np.diag(poles) + np.diag(np.ones(n - 1), -1)
    C = np.zeros((1, n))
    C[0, -1] = 1.0
    return A, B, C, D.reshape(1, -1)


@dataclass(frozen=True, eq=False)
class PolynomialParityDesign(FieldReport):
    """An LTI parity (DAE null-space) fault detection filter (van der Ploeg 2018, (2.6)–(2.9)).

    Attributes
    ----------
    generator : residual generator ``r = d⁻¹ N L [z]`` reading the model's controls and outputs.
    dae : the DAE model it was designed on; fault : the detected fault column.
    degree : ``d_N``; null_dimension : dimension of the left null space of ``H̄`` at ``d_N``.
    N : ``(d_N + 1, n_r)`` coefficients ``N_i`` (after the DC normalisation).
    NL : coefficients of ``N(q) L(q)``, row ``i`` = ``qⁱ``, columns ``z = [outputs; controls]``.
    NF : coefficients of ``N(q) F(q)`` (``qⁱ``).
    denominator : ``d̄ = [d_0 … d_n]`` (monic); poles : its roots.
    decoupling : ``‖N̄ H̄‖ / (‖N̄‖ ‖H̄‖)`` (0 for exact decoupling, round-off in practice; ``H̄`` includes the
        nuisance faults' columns).
    model : the discrete FaultModel it was made from, or None (keyword-only; set by :func:`parity_filter`).
    nuisance : the faults the filter is decoupled from (keyword-only).
    responses : relative response ``‖N̄ F̄_j‖ / (‖N̄‖ ‖F̄_j‖)`` of the residual to every fault column ``j`` of the
        DAE (keyword-only; round-off for a nuisance fault).

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> d = parity_filter(dae, "y0_sensor")
    >>> d.degree, d.generator.residuals, round(d.dc_gain, 9), bool(d.decoupling < 1e-12)
    (1, ('r_y0_sensor',), 1.0, True)

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, (2.6)–(2.9).
    """

    generator: ResidualGenerator
    dae: DAEModel
    fault: str
    degree: int
    null_dimension: int
    N: np.ndarray
    NL: np.ndarray
    NF: np.ndarray
    denominator: np.ndarray
    poles: np.ndarray
    decoupling: float
    nuisance: tuple[str, ...] = field(default=(), kw_only=True)
    responses: dict = field(default_factory=dict, kw_only=True)

    @property
    def N_bar(self) -> np.ndarray:
        """``N̄ = [N_0 N_1 … N_dN]`` (one row)."""
        return self.N.reshape(1, -1)

    def fault_gain(self, z) -> np.ndarray:
        """``G(z) = −N(z) F(z) / d(z)`` (2.7) at complex ``z``."""
        z = np.asarray(z, dtype=complex)
        return -np.polyval(self.NF[::-1], z) / np.prod(z[..., None] - self.poles, axis=-1)

    @property
    def dc_gain(self) -> float:
        """``G(1)``; 1 by the normalisation (2.8b)."""
        return float(self.fault_gain(1.0).real)

    @property
    def fault_map(self) -> tuple[np.ndarray, np.ndarray]:
        """``G(q) = −N(q) F(q) / d(q)`` (2.7) as ``(num, den)`` in descending powers of ``q`` (scipy.signal order).

        This is the pre-filter of :func:`fdikit.estimate.isolate_steering_faults` (Sec. 3-2).
        """
        return -self.NF[::-1], self.denominator[::-1]

    @property
    def fault_zeros(self) -> np.ndarray:
        """Zeros of ``N(q) F(q)`` (leading coefficients below ``1e-10 · max|NF|`` dropped)."""
        nf = self.NF.copy()
        while nf.size > 1 and abs(nf[-1]) <= 1e-10 * np.abs(self.NF).max():
            nf = nf[:-1]
        return np.roots(nf[::-1])

    def internal_form(self) -> FaultModel:
        """The plant ``model`` and this filter in series, from ``(u, d, f, w)`` to ``r``.

        ``generator.internal_form(model)`` (:meth:`~fdikit.residuals.ResidualGenerator.internal_form`) with the
        discrete FaultModel the design was made from (field ``model``).  A design made directly on a
        :class:`~fdikit.dae.DAEModel` has no state-space model to join and raises
        :class:`~fdikit.errors.DesignError`.
        """
        if self.model is None:
            no_internal_form(self, "it was designed on a DAEModel, which has no state-space form to join with the "
                                   "filter; design it from the discrete FaultModel (parity_filter converts it)")
        return joined_form(self, self.model)

    def report(self) -> dict:
        """``fault``, ``degree`` (``d_N``), ``null_dimension``, ``N`` (coefficients ``N_i``), ``denominator`` and
        ``poles`` (of ``d(q)``), ``decoupling`` (``‖N̄ H̄‖ / (‖N̄‖ ‖H̄‖)``), ``dc_gain`` (``G(1)``, 1 by design)
        , ``fault_zeros``, ``nuisance`` and ``responses`` (relative response to each fault column)."""
        return {"fault": self.fault, "degree": self.degree, "null_dimension": self.null_dimension, "N": self.N,
                "denominator": self.denominator, "poles": self.poles, "decoupling": self.decoupling,
                "dc_gain": self.dc_gain, "fault_zeros": self.fault_zeros, "nuisance": self.nuisance,
                "responses": dict(self.responses)}


#: Relative response ``‖N̄ F̄_j‖ / (‖N̄‖ ‖F̄_j‖)`` at or below which the filter counts as blind to fault ``j``: far
#: above the round-off of a null-space row (~1e-14), far below the response of a fault that is not decoupled.
RESPONSE_RTOL = 1e-8


def _nuisance_faults(dae: DAEModel, nuisance, target: str) -> tuple[str, ...]:
    if nuisance is None:
        raise ParameterError("nuisance=None is not a fault set; use () for none or 'others' for every other fault")
    if isinstance(nuisance, str) and nuisance == "others":
        return tuple(f for f in dae.faults if f != target)
    out = []
    for nm in [nuisance] if isinstance(nuisance, str) else list(nuisance):
        nm = fault_label(dae, nm)
        if nm not in dae.faults:
            raise DesignError(f"nuisance {nm!r} is not a fault column of the DAE; its faults are {list(dae.faults)} "
                              "(add it to the model with with_sensor_faults / with_actuator_faults)")
        if nm == target:
            raise ParameterError(f"{nm!r} is the target and cannot be nuisance too")
        out.append(nm)
    return tuple(dict.fromkeys(out))


def _decoupled(dae: DAEModel, nuisance: Sequence[str]) -> DAEModel:
    """The DAE with the nuisance fault columns moved from ``F(q)`` into the unknowns (``H̃ = [H F_nuisance]``, §2-3)."""
    if not nuisance:
        return dae
    idx = [dae.faults.index(f) for f in nuisance]
    keep = [j for j in range(len(dae.faults)) if j not in idx]
    d = max(len(dae.H), len(dae.F))
    H = list(dae.H) + [np.zeros_like(dae.H[0])] * (d - len(dae.H))
    F = list(dae.F) + [np.zeros_like(dae.F[0])] * (d - len(dae.F))
    return DAEModel(H=tuple(np.hstack([h, f[:, idx]]) for h, f in zip(H, F)), L=dae.L,
                    F=tuple(f[:, keep] for f in dae.F), unknowns=dae.unknowns + tuple(nuisance), outputs=dae.outputs,
                    controls=dae.controls, faults=tuple(dae.faults[j] for j in keep), dt=dae.dt)


def parity_filter(
    model: DAEModel | FaultModel,
    targets: str | Sequence[str] | None = None,
    *,
    degree: int | None = None,
    poles: float | Sequence[float] = 0.9048,
    name: str | None = None,
    nuisance: Sequence[str] | str = (),
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> PolynomialParityDesign:
    """LTI parity-space fault detection filter (van der Ploeg 2018, Lemma 2-1.2, (2.6)–(2.9); Sec. 4-3-1).

    Parameters
    ----------
    model : DAEModel or FaultModel
        The DAE (2.1), or a discrete FaultModel converted by :func:`dae_form`.
    targets : str, optional
        The fault to detect, by fault name (a column of ``F``: ``'<control>_actuator'``,
        ``'<output>_sensor'``, …) or a one-element sequence; may be omitted when there is one.
        The other faults are decoupled only when named in ``nuisance``.
    degree : int, optional
        Parity degree ``d_N``; default the minimal one (:func:`minimal_degree`).
    poles : float or sequence of float
        Real poles of ``d(q)``: one value is repeated ``d_N + d_L + 1`` times (default 0.9048,
        the thesis' triple pole); a sequence needs at least ``deg N L`` entries (the filter
        is strictly proper with more).
    name : str, optional
        Residual name (default ``r_<fault>``; the same as ``names=[name]``).
    nuisance : str or sequence of str, optional
        Faults (columns of ``F``) the residual is decoupled from: ``()`` (default) none, ``'others'`` every
        other fault, or fault names.  They join the unknowns, ``N [H F_nuisance] = 0`` (Sec. 2-3): an LTI
        filter exists iff the target is isolable from them (:func:`~fdikit.design.parity.polynomial_rank.isolability`).
    names, isolates : optional
        Residual name (default ``r_<fault>``) and the fault it isolates (default the target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    PolynomialParityDesign
        With ``G(1) = 1`` (2.8b) and ``N̄ H̄ = 0`` (2.8a); ``responses`` gives its relative response to every
        fault.  When the residual also responds (relative response above :data:`RESPONSE_RTOL`) to a fault
        that is neither the target nor nuisance, a :class:`~fdikit.errors.FdiWarning` lists those faults: an
        alarm could be one of them, and isolation would name the target wrongly.

    Raises
    ------
    ParameterError
        ``model`` neither a DAEModel nor a FaultModel; several targets or a bare signal name.
    DesignError
        Undetectable or unknown fault, unstable or complex poles, too few poles, a fault whose
        residual response vanishes at DC (the normalisation (2.8b) is then impossible), or a target that
        is not isolable from the nuisance faults (the message gives the normal ranks of Sec. 2-3).

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> design = parity_filter(single_track_lpv()(70 / 3.6))
    >>> design.degree, design.null_dimension, design.generator.n
    (2, 1, 3)
    >>> round(design.dc_gain, 12), round(float(design.fault_zeros[0].real), 5)
    (1.0, -0.97294)

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, (2.6)–(2.9); Sec. 4-3-1.
    """
    dae = dae_form(model) if isinstance(model, FaultModel) else model
    if not isinstance(dae, DAEModel):
        raise ParameterError(f"parity_filter needs a DAEModel or a discrete FaultModel, got {type(model).__name__}")
    fault = target_fault(dae, targets)
    nuis = _nuisance_faults(dae, nuisance, fault)
    full, dae = dae, _decoupled(dae, nuis)
    try:
        dN = minimal_degree(dae, fault) if degree is None else int(degree)
    except DesignError as exc:
        if not nuis:
            raise
        test = detectability(dae, fault)
        raise DesignError(f"fault {fault!r} is not isolable from nuisance {list(nuis)} (Sec. 2-3): normal ranks "
                          f"[H F_nuisance F] {test.rank_with}, [H F_nuisance] {test.rank_without}; no LTI parity "
                          f"filter sees it while ignoring them ({exc})") from exc
    Hb, Lb, Fb = bar_matrices(dae, dN, fault)
    V = linalg.null(Hb.T).T
    g = Fb.sum(axis=1)  # N̄ F̄ 1 = N(1) F(1)
    Vg = V @ g
    if V.shape[0] == 0 or np.linalg.norm(Vg) <= 1e-10 * np.linalg.norm(g):
        raise DesignError(
            f"no parity row of degree {dN} sees fault {fault!r} at DC: N(1)F(1) = 0 for every N̄ with N̄H̄ = 0 "
            f"(null space dimension {V.shape[0]}); use degree=None (minimal) or a larger degree"
        )
    dL = len(dae.L) - 1
    p = real_poles(poles, dN + dL + 1)
    den = np.poly(p)[::-1]
    # least-norm N̄ in the null space with Σ N̄F̄ = −Σ d̄ = −d(1) (2.9); d(1) from the factors, since the
    # expanded coefficients of (q − 0.9)¹³ cancel to ~1e-13 = d(1) itself
    Nb = -np.prod(1.0 - p) * (Vg @ V) / (Vg @ Vg)
    NL = (Nb @ Lb).reshape(-1, len(dae.knowns))
    NF = Nb @ Fb
    nz = np.flatnonzero(np.abs(NL).max(axis=1) > 1e-10 * np.abs(NL).max())
    deg_NL = int(nz[-1]) if nz.size else 0
    if p.size < deg_NL:
        raise DesignError(f"d(q) has degree {p.size} but N(q)L(q) has degree {deg_NL}: the filter would be improper "
                          f"(use at least {deg_NL} poles, or {deg_NL + 1} for a strictly proper filter)")
    n_y = len(dae.outputs)
    num = np.hstack([NL[:, n_y:], NL[:, :n_y]])[: p.size + 1]  # generator inputs are [controls; outputs]
    A, B, C, D = _newton_chain(num, p)
    if name is not None and names is not None:
        raise ParameterError("give the residual name once: names= (name= is its older spelling)")
    gen = ResidualGenerator(A, B, C, D, dae.controls, dae.outputs, (name or f"r_{fault}",), dae.dt, (fault,))
    gen = label_generator(gen, model, names, isolates)
    decoupling = float(np.linalg.norm(Nb @ Hb) / (np.linalg.norm(Nb) * np.linalg.norm(Hb)))
    responses = {}
    for j, f in enumerate(full.faults):
        Fj = bar([c[:, [j]] for c in full.F], dN)
        scale = np.linalg.norm(Nb) * np.linalg.norm(Fj)
        responses[f] = float(np.linalg.norm(Nb @ Fj) / scale) if scale > 0 else 0.0
    claimed = {fault} | {f for f in gen.isolates if f is not None}
    warn_unlisted_faults("parity_filter", {f: r for f, r in responses.items()
                                           if f not in claimed and f not in nuis and r > RESPONSE_RTOL})
    return PolynomialParityDesign(
        generator=gen, dae=full, fault=fault, degree=dN, null_dimension=V.shape[0], N=Nb.reshape(dN + 1, -1),
        NL=NL, NF=NF, denominator=den, poles=p, decoupling=decoupling,
        model=model if isinstance(model, FaultModel) else None, nuisance=nuis, responses=responses,
    )
