"""Observer gains that keep Beard–Jones detection spaces invariant (Douglas et al. 1996, App. C.1).

Prop. C.3/C.4, (c.2), (c.7): for (C, A)-invariant detection spaces ``W_1 … W_q`` with output-separable
images, ``(A + LC) W_i ⊆ W_i`` for every i iff

    L = Σ_i (−A W_i F̂_i + W_i α_i) H_i + β H_0

with free ``α_i`` (ν_i x k_i) and ``β`` (n x k_0); ``F̂_i`` are right singular vectors of ``C W_i``
(identity when ``C W_i`` is monic) and ``H_i`` the natural projections (k_i x p) onto the coordinates
of ``C W_i F̂_i`` along the other images and their orthogonal complement (``Im H_0``).  The family is
the design freedom that :func:`fdikit.design.observers.hinf.hinf_detection_filter` spends on the H∞ bound.

Gain sign: the report's ``L`` above is that of ``A + LC``.  fdikit's gains are observer gains
(``x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)``, state matrix ``A − LC``), so
:meth:`DetectionGainFamily.gain` returns the negative of (c.7),
``L = Σ_i (A W_i F̂_i − W_i α_i) H_i − β H_0``, and :meth:`~DetectionGainFamily.parameters` and
:meth:`~DetectionGainFamily.invariance_defect` take an observer gain.  The parameters ``α_i``, ``β``
keep the report's meaning (``α_i = W_i⁺ (A − LC) W_i F̂_i`` is the restricted closed loop, the same in
either sign).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import linalg
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.fault_maps import resolve_faults
from fdikit.model import FaultModel

__all__ = ["DetectionGainFamily", "detection_gain_family"]


@dataclass(frozen=True, eq=False)
class DetectionGainFamily:
    """All gains that keep a set of detection spaces invariant (Douglas et al. 1996, Prop. C.4, (c.7)).

    Attributes
    ----------
    A, C : the plant matrices.
    fault_maps : ``F_i`` by fault name (n x k).
    spaces : ``W_i`` (n x ν_i): the fault columns, completed by an orthonormal basis of the rest
        of the minimal unobservability subspace ``T_i*`` (invariant-zero directions, CAISA steps).
    row_bases : ``F̂_i`` (ν_i x k_i): right singular vectors of ``C W_i`` (identity when monic).
    residual_maps : natural projections ``H_i`` (k_i x p), ``H_i C W_i F̂_i = I``, ``H_i C W_j = 0``.
    complement_map : ``H_0`` (k_0 x p), orthonormal rows spanning ``(Σ C W_i)^⊥``.
    projectors : ``C W_i F̂_i H_i`` (p x p), the (oblique) projection onto ``C W_i``.
    base_gain : the observer gain ``Σ A W_i F̂_i H_i`` (``A − base_gain C`` = the report's ``Â = A + L̂C``;
        the report's (c.17h) ``L̂ = −Σ A W_i F̂_i H_i`` is its negative).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust
    >>> fam = detection_gain_family(f16xl_gust(), ["y_Az_sensor", "elevon_actuator"])
    >>> L = fam.gain({"y_Az_sensor": -np.eye(2), "elevon_actuator": [[-2.0]]})
    >>> fam.names, fam.coordinates.shape, max(fam.invariance_defect(L).values()) < 1e-9
    (('y_Az_sensor', 'elevon_actuator'), (4, 4), True)

    References
    ----------
    Douglas et al. 1996, App. C.1, Prop. C.3/C.4, (c.2), (c.7), (c.17).
    """

    A: np.ndarray
    C: np.ndarray
    fault_maps: dict[str, np.ndarray]
    spaces: dict[str, np.ndarray]
    row_bases: dict[str, np.ndarray]
    residual_maps: dict[str, np.ndarray]
    complement_map: np.ndarray
    projectors: dict[str, np.ndarray]
    base_gain: np.ndarray

    names = property(lambda self: tuple(self.spaces), doc="Fault names in design order.")

    @property
    def coordinates(self) -> np.ndarray:
        """``𝐓 = [H_1; …; H_q; H_0]`` (p x p, invertible): output coordinates of (c.17)."""
        return np.vstack([*self.residual_maps.values(), self.complement_map])

    def gain(self, alphas: Mapping[str, np.ndarray], beta: np.ndarray | None = None) -> np.ndarray:
        """Observer gain ``L = Σ_i (A W_i F̂_i − W_i α_i) H_i − β H_0`` (minus (c.7)); a missing α_i or β is zero.

        Every ``W_i`` is invariant under ``A − L C``, with ``W_i⁺ (A − L C) W_i F̂_i = α_i``.
        """
        unknown = set(alphas) - set(self.spaces)
        if unknown:
            raise ParameterError(f"alphas given for unknown fault(s) {sorted(unknown)}; faults are {list(self.names)}")
        L = self.base_gain.copy()
        for name, W in self.spaces.items():
            if name in alphas:
                a = np.atleast_2d(np.asarray(alphas[name], dtype=float))
                want = (W.shape[1], self.residual_maps[name].shape[0])
                if a.shape != want:
                    raise ParameterError(f"alpha of {name!r} has shape {a.shape}; it must be {want} "
                                         "(dim W_i x dim C W_i)")
                L = L - W @ a @ self.residual_maps[name]
        k0 = self.complement_map.shape[0]
        if beta is not None and k0:
            b = np.asarray(beta, dtype=float).reshape(self.A.shape[0], -1)
            if b.shape[1] != k0:
                raise ParameterError(f"beta has {b.shape[1]} columns; it must be n x {k0} (the dimension of Im H_0)")
            L = L - b @ self.complement_map
        return L

    def parameters(self, L: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """``(α_i, β)`` of an observer gain (Prop. C.3 "only if": ``α_i = W_i⁺ (A − LC) W_i F̂_i``, ``β = −L N_0``)."""
        L = np.asarray(L, dtype=float)
        Acl = self.A - L @ self.C
        alphas = {k: np.linalg.lstsq(W, Acl @ W @ self.row_bases[k], rcond=None)[0] for k, W in self.spaces.items()}
        N0 = np.linalg.inv(self.coordinates)[:, self.C.shape[0] - self.complement_map.shape[0]:]
        return alphas, -L @ N0

    def invariance_defect(self, L: np.ndarray) -> dict[str, float]:
        """``‖(I − P_{W_i})(A − LC) W_i‖ / (‖A − LC‖ ‖W_i‖)`` per fault, for an observer gain (0: ``W_i`` invariant).

        The part of ``(A − LC) W_i`` outside ``W_i``, relative to the scale of the closed loop and of the basis
        (spectral norms), so an exactly invariant space reads at rounding level (~1e-16) even when
        ``(A − LC) W_i`` itself is nearly zero; the defect of a space that is not invariant is at most 1.
        (Normalising by ``‖(A − LC) W_i‖`` instead, as before, read 0.38 for an invariant space whose image had
        collapsed to 2e-15.)
        """
        Acl = self.A - np.asarray(L, dtype=float) @ self.C
        scale = np.linalg.norm(Acl, 2)
        out = {}
        for k, W in self.spaces.items():
            Q = linalg.orth(W)
            X = Acl @ W
            denom = max(scale * np.linalg.norm(W, 2), np.finfo(float).tiny)
            out[k] = float(np.linalg.norm(X - Q @ (Q.T @ X), 2) / denom)
        return out


def _space(A, C, F, name, rtol):
    if linalg.rank(F, rtol) < F.shape[1]:
        raise DesignError(f"fault map of {name!r} has dependent columns (rank {linalg.rank(F, rtol)} < {F.shape[1]}); "
                          "pass independent fault directions")
    T = linalg.detection_space(A, C, F, rtol)
    Q = linalg.orth(F, rtol)
    rest = linalg.orth(T - Q @ (Q.T @ T), rtol) if T.shape[1] > F.shape[1] else np.zeros((A.shape[0], 0))
    return np.hstack([F, rest])


def detection_gain_family(
    model: FaultModel, targets: Mapping[str, np.ndarray] | Sequence[str] | str, rtol: float | None = None
) -> DetectionGainFamily:
    """Parameterise the gains that keep every fault's detection space invariant (Prop. C.3/C.4).

    Parameters
    ----------
    model : FaultModel (continuous; only ``A`` and ``C`` are used).
    targets : fault names resolved by :func:`fdikit.fault_maps.resolve_faults` (``'<output>_sensor'`` is
        the sensor fault ``[F¹, A F¹]`` with ``C F¹ = e_i``, ``'<control>_actuator'`` a column of ``Bu``),
        or a mapping name → fault map ``F``.
    rtol : relative rank tolerance of the subspace computations (default ``None``: fdikit.linalg's default).

    Returns
    -------
    DetectionGainFamily
        The spaces ``W_i``, projections ``H_i``, ``H_0`` and the base gain; ``gain(alphas, beta)`` gives a member.

    Raises
    ------
    ModelError
        A discrete model, or a name that is not a fault of the model.
    ParameterError
        A bare signal name instead of a fault name.
    DesignError
        No fault given, dependent fault columns, detection spaces that overlap, a fault that does not
        reach the outputs, or images ``C W_i`` that are not independent (not output separable, Def. A.1).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust
    >>> fam = detection_gain_family(f16xl_gust(), ["y_Az_sensor", "elevon_actuator"])
    >>> [W.shape[1] for W in fam.spaces.values()]
    [2, 1]
    >>> L = fam.gain({"elevon_actuator": [[-2.0]]})
    >>> np.round(np.linalg.lstsq(fam.spaces["elevon_actuator"],
    ...          (fam.A - L @ fam.C) @ fam.spaces["elevon_actuator"], rcond=None)[0], 12)
    array([[-2.]])

    References
    ----------
    Douglas et al. 1996, App. C.1, Prop. C.3/C.4, (c.2), (c.7).
    """
    if model.is_discrete:
        raise ModelError("the H∞ detection filter of App. C is continuous-time; pass a continuous model")
    maps = resolve_faults(model, targets)
    if not maps:
        raise DesignError("no fault given; name at least one fault to detect")
    A, C = model.A, model.C
    n, p = model.n, model.p
    spaces = {k: _space(A, C, F, k, rtol) for k, F in maps.items()}
    allW = np.hstack(list(spaces.values()))
    if linalg.rank(allW, rtol) < allW.shape[1]:
        raise DesignError(f"the detection spaces {[(k, W.shape[1]) for k, W in spaces.items()]} are not independent "
                          f"(total dimension {allW.shape[1]}, rank {linalg.rank(allW, rtol)}, n = {n}); "
                          "split the faults over several filters")
    row_bases = {}
    for k, W in spaces.items():
        CW = C @ W
        r = linalg.rank(CW, rtol)
        if r == 0:
            raise DesignError(f"fault {k!r} does not reach the outputs (C W_i = 0); it cannot be detected")
        row_bases[k] = np.eye(W.shape[1]) if r == W.shape[1] else np.linalg.svd(CW)[2][:r].T
    M = np.hstack([C @ spaces[k] @ row_bases[k] for k in spaces])
    if linalg.rank(M, rtol) < M.shape[1]:
        _, pairs = linalg.output_separable(C, list(spaces.values()), rtol)
        keys = list(spaces)
        raise DesignError(f"faults not output separable: images C W_i of {[(keys[i], keys[j]) for i, j in pairs]} "
                          "are dependent; use '<output>_sensor:magnitude' for a sensor fault, or put the faults in "
                          "different filters")
    N0 = scipy.linalg.null_space(M.T) if M.shape[1] < p else np.zeros((p, 0))
    T = np.linalg.inv(np.hstack([M, N0]))
    start, residual_maps, projectors = 0, {}, {}
    base = np.zeros((n, p))
    for k, W in spaces.items():
        kk = row_bases[k].shape[1]
        Hk = T[start : start + kk]
        residual_maps[k] = Hk
        projectors[k] = C @ W @ row_bases[k] @ Hk
        base += A @ W @ row_bases[k] @ Hk  # the observer gain; the report's L̂ (c.17h) is −base
        start += kk
    return DetectionGainFamily(A, C, maps, spaces, row_bases, residual_maps, T[start:], projectors, base)
