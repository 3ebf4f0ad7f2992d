"""Target/nuisance partition, complementary faults and projectors of the game-theoretic filters.

Shared by the continuous, discrete, time-varying and asymptotic designs (Murray 2012,
§2.1.3, (2.4)–(2.11), (3.10); Douglas et al. 1996, Ch. 9):

* the first ``s`` faults are **targets** ``F_1 … F_s``, the rest are **nuisance** ``F̂``;
* the **complementary fault** of target ``i`` is ``F̂_i = [F_1 … F_{i−1} F_{i+1} … F_s  F̂]``
  (it includes the nuisance);
* ``Ŵ_i*`` is the minimal (C, A)-invariant subspace containing ``Im F̂_i`` (CAISA) and the
  projector ``Ĥ_i = I − (CŴ_i*)[(CŴ_i*)ᵀ(CŴ_i*)]⁻¹(CŴ_i*)ᵀ`` (3.10) annihilates ``C Ŵ_i*``;
  the projected residual ``r̄_i = Ĥ_i r`` is then (approximately, for γ > 0) blind to ``F̂_i``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import linalg, validate
from fdikit.errors import DesignError, ParameterError
from fdikit.fault_maps import resolve_faults, resolve_nuisance
from fdikit.model import FaultModel

__all__ = ["GameProblem", "game_problem", "per_target", "weight"]


@dataclass(frozen=True, eq=False)
class GameProblem:
    """Partitioned fault directions of a game-theoretic detection-filter design.

    Attributes
    ----------
    model : the plant.
    targets : ``F_i`` (n x k_i) by target name, in design order.
    nuisance : ``F̂`` (n x k̂), all nuisance directions side by side (k̂ may be 0).
    nuisance_names : names of the nuisance faults, in the column order of ``nuisance``.
    complementary : ``F̂_i`` by target name.
    projectors : ``Ĥ_i`` (p x p, symmetric, idempotent, kernel ``C Ŵ_i*``) by target name.
    invariant_subspaces : orthonormal basis of ``Ŵ_i*`` by target name.

    Made by :func:`game_problem`; :attr:`names` gives the target names in design order.

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> prob = game_problem(white_speyer(), ["f1", "f2"])
    >>> prob.names, prob.complementary["f1"].shape, prob.nuisance.shape
    (('f1', 'f2'), (3, 1), (3, 0))

    References
    ----------
    Murray 2012, §2.1.1 and §3.1.1, (3.10).
    """

    model: FaultModel
    targets: dict[str, np.ndarray]
    nuisance: np.ndarray
    nuisance_names: tuple[str, ...]
    complementary: dict[str, np.ndarray]
    projectors: dict[str, np.ndarray]
    invariant_subspaces: dict[str, np.ndarray]

    @property
    def names(self) -> tuple[str, ...]:
        """Target names in design order."""
        return tuple(self.targets)


def weight(name: str, value, dim: int) -> np.ndarray:
    """A symmetric positive (semi)definite design weight as a ``dim x dim`` matrix.

    A scalar means ``value · I``; a vector a diagonal; a matrix is checked for shape and
    symmetry.

    Parameters
    ----------
    name : str
        Name of the weight in the error messages (``'Q'``, ``'M'``, ``'V'``, …).
    value : float, (dim,) array or (dim, dim) array
        The weight: a scalar (``value · I``), the diagonal, or the full symmetric matrix.
    dim : int
        Its size.

    Returns
    -------
    numpy.ndarray
        The (dim, dim) symmetric weight.

    Raises
    ------
    ParameterError
        A wrong number of diagonal entries or shape, non-finite entries, an asymmetric matrix, or a
        negative eigenvalue (beyond rounding).

    Examples
    --------
    >>> weight("Q", [1.0, 2.0], 2)
    array([[1., 0.],
           [0., 2.]])

    References
    ----------
    Murray 2012, §3.1.1, (3.11).
    """
    W = validate.as_array(f"weight {name}", value, finite=False)
    if W.ndim == 0:
        W = float(W) * np.eye(dim)
    elif W.ndim == 1:
        if W.size != dim:
            raise ParameterError(f"weight {name} has {W.size} diagonal entries; it must be {dim} x {dim}")
        W = np.diag(W)
    if W.shape != (dim, dim):
        raise ParameterError(f"weight {name} has shape {W.shape}; it must be {dim} x {dim} (or a scalar)")
    if not np.all(np.isfinite(W)):
        raise ParameterError(f"weight {name} has non-finite entries")
    if not np.allclose(W, W.T, rtol=1e-10, atol=1e-14 * max(1.0, np.abs(W).max(initial=0.0))):
        raise ParameterError(f"weight {name} must be symmetric")
    if dim and np.linalg.eigvalsh((W + W.T) / 2).min() < -1e-12 * max(1.0, np.abs(W).max()):
        raise ParameterError(f"weight {name} must be positive semidefinite")
    return (W + W.T) / 2


def per_target(name: str, value, targets: GameProblem | Sequence[str], given: Sequence[str] = ()) -> dict[str, object]:
    """A design weight given once for every target, or as a mapping target → weight, as a dict in target order.

    ``targets`` is a :class:`GameProblem` (its target names) or the target names.  A mapping may be keyed by the
    target names or by the names the caller wrote, ``given`` (aligned with the target names: the ``targets=``
    argument of the design as given).  A key that names no target, or a target without a key, is a
    :class:`~fdikit.errors.ParameterError` naming the weight and the targets.  The values are returned as given
    (check them with :func:`weight`).

    Parameters
    ----------
    name : str
        Name of the weight in the error messages.
    value : object or mapping
        One weight for every target, or a mapping target name → weight.
    targets : GameProblem or sequence of str
        The problem (its target names) or the target names, in design order.
    given : sequence of str, optional
        The target names as the caller wrote them, aligned with ``targets`` (accepted as keys too).

    Returns
    -------
    dict
        Target name → weight, in target order.

    Raises
    ------
    ParameterError
        A mapping key that names no target, or a target without a key.

    Examples
    --------
    >>> per_target("Q", {"f2": 2e-3, "f1": 1e-3}, ["f1", "f2"])
    {'f1': 0.001, 'f2': 0.002}
    >>> per_target("M", 0.01, ["f1", "f2"])
    {'f1': 0.01, 'f2': 0.01}

    References
    ----------
    Murray 2012, §3.2.3, (3.27)–(3.28) (one ``Q_i``, ``M_i``, ``K_i``, ``N_i`` per target).
    """
    names = list(targets.names if isinstance(targets, GameProblem) else targets)
    if not isinstance(value, Mapping):
        return {t: value for t in names}
    alias = dict(zip(given, names, strict=False))
    out = {}
    for key, v in value.items():
        t = alias.get(key, key)
        if t not in names:
            raise ParameterError(f"weight {name} is given for {key!r}, which is not a target; targets are {names}")
        out[t] = v
    missing = [t for t in names if t not in out]
    if missing:
        raise ParameterError(f"weight {name} has no entry for target(s) {missing}; give one value for every target "
                             f"or a mapping with one per target {names}")
    return {t: out[t] for t in names}


def game_problem(
    model: FaultModel,
    targets: Mapping[str, np.ndarray] | Sequence[str] | str,
    nuisance: Mapping[str, np.ndarray] | Sequence[str] | str = (),
    rtol: float | None = None,
) -> GameProblem:
    """Partition faults into targets and nuisance, and build ``F̂_i``, ``Ŵ_i*`` and ``Ĥ_i``.

    Parameters
    ----------
    model : FaultModel
        The plant (continuous or discrete; only ``A`` and ``C`` are used).
    targets : fault name, sequence of fault names, or mapping name → F
        The faults to detect.  Names are resolved by :func:`fdikit.fault_maps.resolve_faults`
        (``'<output>_sensor'`` is the sensor fault ``[F¹, A F¹]``, ``'<control>_actuator'`` an
        actuator fault, a fault input of the model its column); a mapping gives explicit n x k
        maps.  A bare signal name raises :class:`ParameterError`.
    nuisance : as ``targets``, or ``'others'``
        The faults to block: ``()`` (default) none, ``'others'`` every fault input of the model
        that is not a target (:func:`fdikit.fault_maps.resolve_nuisance`).
    rtol : float, optional
        Relative rank tolerance of the subspace computations.

    Returns
    -------
    GameProblem
        The target maps ``F_i``, the nuisance ``F̂``, and by target the complementary faults ``F̂_i``,
        the subspaces ``Ŵ_i*`` and the projectors ``Ĥ_i``.

    Raises
    ------
    ParameterError
        If there is no target (and, from the name resolution, an unknown or bare signal name).
    DesignError
        If a name is both target and nuisance, or a target is hidden by its complementary faults
        (``Ĥ_i C W_i* = 0``: not output separable, Murray Assumption 3.2).

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> prob = game_problem(white_speyer(), ["f1", "f2"])
    >>> [int(round(float(np.trace(H)))) for H in prob.projectors.values()]
    [1, 1]

    References
    ----------
    Murray 2012, §2.1.1–2.1.2, (2.4)–(2.11), and §3.1.1, (3.10); Douglas et al. 1996, Ch. 9.
    """
    T = resolve_faults(model, targets)
    N = resolve_nuisance(model, nuisance, list(T))
    if not T:
        raise ParameterError("no target fault given; name at least one fault to detect")
    both = set(T) & set(N)
    if both:
        raise DesignError(f"{sorted(both)} given both as target and as nuisance; each fault is one or the other")
    n = model.n
    F_nuis = np.hstack(list(N.values())) if N else np.zeros((n, 0))
    comp, proj, spaces = {}, {}, {}
    for name, F in T.items():
        Fhat = np.hstack([G for k, G in T.items() if k != name] + [F_nuis]) if (len(T) > 1 or N) else np.zeros((n, 0))
        W = linalg.caisa(model.A, model.C, Fhat, rtol) if Fhat.shape[1] else np.zeros((n, 0))
        H = linalg.output_projector(model.C, W, rtol)
        visible = np.linalg.norm(H @ model.C @ linalg.caisa(model.A, model.C, F, rtol))
        if visible < 1e-9 * max(1.0, np.linalg.norm(model.C)):
            raise DesignError(
                f"target {name!r} is not output separable from its complementary faults: Ĥ_i C W_i* = 0; "
                "drop a nuisance fault or add a sensor"
            )
        comp[name], proj[name], spaces[name] = Fhat, H, W
    return GameProblem(model, T, F_nuis, tuple(N), comp, proj, spaces)
