"""Fault isolation from multiple-model weights: the group-sum threshold logic of Hallouzi 2008, Table 4.7.

Table 4.7 (§4.4.2) declares the system nominal when the weight of the nominal model is close to
one, and a fault of a given surface when the weights of that surface's models add up to at least
the threshold ``T_f`` while the nominal model is not dominant::

    F_0 (nominal)  = |1 − μ^(8)| <  T_f
    F_g (group g)  = |Σ_{i ∈ g} μ^(i)| ≥ T_f  AND  |1 − μ^(8)| ≥ T_f

with ``T_f = 0.2``, the groups rudder {1, 2}, elevator {3, 5, 6}, aileron {4, 7} of model set II
(Table 4.5) and model 8 the nominal model.  The table caption says "F_0, …, F_4" but only
F_0 … F_3 exist (thesis slip).

Table 4.7 leaves two points open; the choices made here:

* several F_g true at once → the group with the largest weight sum is isolated (first group on an
  exact tie);
* nominal false but no group reaches ``T_f`` → ``'unknown'`` with the alarm on;
* no latching by default; ``latch=True`` keeps the first isolated fault for the rest of the run
  (Ch. 6 switches the controller once).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.diagnosis import UNKNOWN_FAULT, Diagnosis
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT

__all__ = ["GroupThresholdLogic", "table_4_7_logic", "most_probable_mode", "mode_diagnosis"]


@dataclass(frozen=True)
class GroupThresholdLogic:
    """Group-sum threshold isolation of Hallouzi 2008, Table 4.7 (generalised to any grouping).

    Attributes
    ----------
    groups : mapping of str to sequence of int
        Fault name → indices (0-based) of the models that represent that fault.
    nominal : int
        0-based index of the nominal model.
    threshold : float
        The fault threshold ``T_f`` in (0, 1) (Table 4.7: 0.2).
    latch : bool
        Keep the first isolated fault for the rest of a run (default False).
    tol : float
        Comparisons are made as ``≥ T_f − tol`` / ``< T_f − tol`` so that decimal boundary cases
        come out as written: in doubles ``1 − 0.8 = 0.19999999999999996 < 0.2``, yet in exact arithmetic
        ``|1 − 0.8| = 0.2`` is not ``< T_f``, so Table 4.7 makes μ^(8) = 0.8 *not* nominal.

    Raises
    ------
    ParameterError
        If ``groups`` is not a non-empty mapping of non-empty index lists, uses a reserved name
        (``'none'``, ``'unknown'``), has a negative index or contains the nominal model, or the threshold
        is not in (0, 1).

    Examples
    --------
    >>> logic = table_4_7_logic()
    >>> mu = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    >>> logic.isolate([mu]).tolist(), logic.isolate([[0.3, 0, 0, 0, 0, 0, 0, 0.7]]).tolist()
    (['none'], ['rudder'])
    >>> logic = GroupThresholdLogic(groups={"a": [1], "b": [2]}, nominal=0)
    >>> logic.names, logic.signatures([[0.2, 0.7, 0.1]]).tolist()
    (('none', 'a', 'b'), [[False, True, False]])

    References
    ----------
    Hallouzi 2008, §4.4.2, Table 4.7 (with the groups of model set II, §4.3.4, Table 4.5).
    """

    groups: Mapping[str, Sequence[int]]
    nominal: int
    threshold: float = 0.2
    latch: bool = False
    tol: float = 1e-12

    def __post_init__(self) -> None:
        if not isinstance(self.groups, Mapping):
            raise ParameterError(
                f"groups must be a mapping fault name -> model indices, got {type(self.groups).__name__}"
            )
        groups = {str(k): tuple(validate.integer(f"model index of group {k!r}", i) for i in v)
                  for k, v in dict(self.groups).items()}
        object.__setattr__(self, "nominal", validate.integer("nominal", self.nominal))
        object.__setattr__(self, "threshold", validate.number("threshold", self.threshold))
        object.__setattr__(self, "tol", validate.non_negative("tol", self.tol))
        if not groups or any(len(v) == 0 for v in groups.values()):
            raise ParameterError(
                "GroupThresholdLogic needs at least one fault group, each with at least one model index"
            )
        if NO_FAULT in groups or UNKNOWN_FAULT in groups:
            raise ParameterError(f"fault group names {NO_FAULT!r} and {UNKNOWN_FAULT!r} are reserved; rename the group")
        members = [i for v in groups.values() for i in v]
        if min(members + [self.nominal]) < 0:
            raise ParameterError("model indices of GroupThresholdLogic are 0-based and must be non-negative, got index "
                                 f"{min(members + [self.nominal])} (-1 is not allowed)")
        if self.nominal in members:
            raise ParameterError(f"the nominal model {self.nominal} is also listed in a fault group; remove it there")
        if not 0.0 < self.threshold < 1.0:
            raise ParameterError(f"threshold T_f = {self.threshold} must lie in (0, 1) (Table 4.7 uses 0.2)")
        object.__setattr__(self, "groups", groups)

    @property
    def names(self) -> tuple[str, ...]:
        """Signature names: ``'none'`` (F_0) then the fault groups (F_1, F_2, …)."""
        return (NO_FAULT, *self.groups)

    @property
    def n_models(self) -> int:
        """Smallest number of models the logic can read."""
        return 1 + max([self.nominal, *(i for v in self.groups.values() for i in v)])

    def _mu(self, mu) -> np.ndarray:
        mu = np.atleast_2d(validate.as_array("mu (model weights)", mu, error=DataError, finite=False))
        if mu.ndim != 2:
            raise DataError(f"mu (model weights) must be an N x models array, got shape {mu.shape}")
        if mu.shape[1] < self.n_models:
            raise DataError(
                f"model weights have {mu.shape[1]} columns but the logic refers to model index {self.n_models - 1}; "
                "pass one column per model of the set"
            )
        return mu

    def signatures(self, mu) -> np.ndarray:
        """The boolean signatures ``[F_0, F_1, …]`` of Table 4.7 per sample, shape (N, 1 + groups)."""
        mu = self._mu(mu)
        T = self.threshold - self.tol
        off_nominal = np.abs(1.0 - mu[:, self.nominal]) >= T
        cols = [~off_nominal]
        for idx in self.groups.values():
            cols.append((np.abs(mu[:, list(idx)].sum(axis=1)) >= T) & off_nominal)
        return np.column_stack(cols)

    def isolate(self, mu, valid=None) -> np.ndarray:
        """Isolated fault per sample: ``'none'``, a group name, or ``'unknown'`` (see module notes).

        Where ``valid`` is False the previous decision is held.
        """
        mu = self._mu(mu)
        sig = self.signatures(mu)
        sums = np.column_stack([mu[:, list(idx)].sum(axis=1) for idx in self.groups.values()])
        names = np.array(list(self.groups), dtype=object)
        best = np.argmax(np.where(sig[:, 1:], sums, -np.inf), axis=1)
        out = np.where(sig[:, 0], NO_FAULT, np.where(sig[:, 1:].any(axis=1), names[best], UNKNOWN_FAULT))
        out = _hold(out.astype(object), valid)
        if self.latch:
            first = np.flatnonzero(out != NO_FAULT)
            if first.size:
                out[first[0]:] = out[first[0]]
        return out.astype(str)


def table_4_7_logic(threshold: float = 0.2, latch: bool = False) -> GroupThresholdLogic:
    """The logic of Hallouzi 2008, Table 4.7, for model set II (Table 4.5) plus the nominal model 8.

    Models (1-based in the thesis): 1, 2 rudder at ±25 deg; 3, 5, 6 elevator at −23, 17, −6 deg;
    4, 7 aileron at 15, −15 deg; 8 nominal.  Here indices are 0-based.

    Parameters
    ----------
    threshold : float, optional
        ``T_f`` (default 0.2, as in Table 4.7).
    latch : bool, optional
        Keep the first isolated fault for the rest of a run (default False).

    Returns
    -------
    GroupThresholdLogic
        Groups rudder (0, 1), elevator (2, 4, 5), aileron (3, 6); nominal model 7.

    Examples
    --------
    >>> logic = table_4_7_logic()
    >>> logic.nominal, logic.n_models, list(logic.groups)
    (7, 8, ['rudder', 'elevator', 'aileron'])

    References
    ----------
    Hallouzi 2008, §4.4.2, Table 4.7; §4.3.4, Table 4.5 (model set II).
    """
    return GroupThresholdLogic(
        groups={"rudder": (0, 1), "elevator": (2, 4, 5), "aileron": (3, 6)}, nominal=7, threshold=threshold, latch=latch
    )


def _hold(out: np.ndarray, valid) -> np.ndarray:
    if valid is None:
        return out
    valid = np.asarray(valid, bool)
    out = out.copy()
    for k in np.flatnonzero(~valid):
        out[k] = out[k - 1] if k > 0 else NO_FAULT
    return out


def most_probable_mode(mu, hypotheses: Sequence[str], nominal: int = 0, valid=None) -> np.ndarray:
    """Isolated fault per sample as the most probable mode (``'none'`` when it is the nominal mode).

    Parameters
    ----------
    mu : array_like
        Mode probabilities or model weights (N, M) (or one sample (M,)).
    hypotheses : sequence of str
        The M mode names.
    nominal : int, optional
        Index of the nominal mode (default 0).
    valid : array_like of bool, optional
        (N,); where False the previous decision is held (``'none'`` at the first sample).

    Returns
    -------
    ndarray of str
        (N,) isolated fault names, ``'none'`` for the nominal mode.

    Examples
    --------
    >>> most_probable_mode([[0.9, 0.1, 0.0], [0.2, 0.7, 0.1]], ["nominal", "a", "b"]).tolist()
    ['none', 'a']

    References
    ----------
    Hallouzi 2008, §2.3.1, (2.7) (the mode probabilities μ_k of the IMM filter).
    """
    mu = np.atleast_2d(np.asarray(mu, dtype=float))
    best = np.argmax(mu, axis=1)
    names = np.array(hypotheses, dtype=object)[best]
    out = np.where(best == nominal, NO_FAULT, names).astype(object)
    return _hold(out, valid).astype(str)


def mode_diagnosis(
    t,
    mu,
    hypotheses: Sequence[str],
    nominal: int = 0,
    logic: GroupThresholdLogic | None = None,
    valid=None,
) -> Diagnosis:
    """A :class:`~fdikit.diagnosis.Diagnosis` from mode probabilities.

    Without ``logic`` the most probable mode is isolated; ``fired`` marks it, and the alarm is on
    when it is not the nominal mode.  With ``logic`` (e.g. :func:`table_4_7_logic`) ``fired`` holds
    the Table 4.7 signatures and the alarm is "not nominal" (held on invalid samples).

    Parameters
    ----------
    t : array_like
        Sample times (N,).
    mu : array_like
        Mode probabilities or model weights (N, M).
    hypotheses : sequence of str
        The M mode names.
    nominal : int, optional
        Index of the nominal mode (default 0); used without ``logic``.
    logic : GroupThresholdLogic, optional
        Group-sum threshold logic; None isolates the most probable mode.
    valid : array_like of bool, optional
        (N,); where False the previous decision is held.

    Returns
    -------
    Diagnosis
        With ``alarm``, ``fired``, ``names``, ``isolated`` and the probabilities.

    Raises
    ------
    DataError
        If the number of columns of ``mu`` differs from the number of hypotheses.

    Examples
    --------
    >>> d = mode_diagnosis([0.0, 1.0], [[0.9, 0.1, 0.0], [0.2, 0.7, 0.1]], ["nominal", "a", "b"])
    >>> d.isolated.tolist(), d.alarm.tolist()
    (['none', 'a'], [False, True])

    References
    ----------
    Hallouzi 2008, §2.3.1, (2.7); §4.4.2, Table 4.7.
    """
    mu = np.atleast_2d(np.asarray(mu, dtype=float))
    hypotheses = tuple(str(h) for h in hypotheses)
    if mu.shape[1] != len(hypotheses):
        raise DataError(f"{mu.shape[1]} probability columns but {len(hypotheses)} hypothesis names; pass one per mode")
    if logic is None:
        isolated = most_probable_mode(mu, hypotheses, nominal, valid)
        fired = np.zeros(mu.shape, bool)
        fired[np.arange(mu.shape[0]), np.argmax(mu, axis=1)] = True
        names = hypotheses
    else:
        isolated = logic.isolate(mu, valid)
        fired = logic.signatures(mu)
        names = logic.names
    alarm = isolated != NO_FAULT
    return Diagnosis(
        t=np.asarray(t, dtype=float), alarm=alarm, fired=fired, names=names, isolated=isolated,
        probabilities=mu, hypotheses=hypotheses, valid=valid,
    )
