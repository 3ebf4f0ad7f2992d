"""The operating point of a linear model: the absolute state, controls and outputs it is linearised about.

A :class:`~fdikit.model.FaultModel` is written in deviation coordinates, ``δx = x − x0``,
``δu = u − u0``, ``δy = y − y0`` (Douglas et al. 1996, §2.2: the linear vehicle model is the
nonlinear simulation linearised about a constant-speed trim; Hallouzi 2008, §4.3, (4.1)–(4.2): the
B747 models carry their trim offsets).  Logged data are absolute.  An :class:`OperatingPoint`
carries ``(x0, u0, y0)`` by signal name; a model holds it (``FaultModel.operating_point``), a
residual generator designed from the model inherits it and subtracts ``u0`` and ``y0`` from the
absolute signals it reads, so ``generator.run(trace)`` on a logged trace needs no offsets by hand.

Values are kept by name (not by position) so that a generator reading a subset of the model's
signals, or a bank of generators reading different signals, takes the offsets it needs.

Examples
--------
>>> op = OperatingPoint.from_vectors(["v"], ["throttle"], ["speed"], x0=[25.0], u0=[0.2], y0=[25.0])
>>> op.output_values(["speed"]).tolist(), op.control_values(["throttle", "brake"]).tolist()
([25.0], [0.2, 0.0])
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit.errors import ParameterError

__all__ = ["OperatingPoint"]

_PARTS = {"x0": "states", "u0": "controls", "y0": "outputs"}


def _part(what: str, values, names: Sequence[str] | None) -> dict[str, float]:
    """``{name: value}`` from a mapping or from a vector in the order of ``names``; finite floats only."""
    if values is None:
        return {}
    if isinstance(values, Mapping):
        items = list(values.items())
        if names is not None:
            unknown = [k for k, _ in items if k not in names]
            if unknown:
                raise ParameterError(f"operating point {what} names {unknown} that are not {_PARTS[what]} of the "
                                     f"model; its {_PARTS[what]} are {list(names)}")
    else:
        if names is None:
            raise ParameterError(f"operating point {what} given as a vector needs the signal names; pass a mapping "
                                 "{name: value}")
        try:
            arr = np.asarray(values, dtype=float).ravel()
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"operating point {what} must be numbers, got {values!r}") from exc
        if arr.size != len(names):
            raise ParameterError(f"operating point {what} has {arr.size} values for the {len(names)} "
                                 f"{_PARTS[what]} {list(names)}; give one per signal or a mapping {{name: value}}")
        items = list(zip(names, arr.tolist()))
    out = {}
    for k, v in items:
        if not isinstance(k, str) or not k:
            raise ParameterError(f"operating point {what} keys must be signal names (non-empty strings), got {k!r}")
        try:
            fv = float(v)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"operating point {what}[{k!r}] must be a number, got {v!r}") from exc
        if not math.isfinite(fv):
            raise ParameterError(f"operating point {what}[{k!r}] = {fv} is not finite")
        out[k] = fv
    return out


@dataclass(frozen=True)
class OperatingPoint:
    """Absolute values ``x0``, ``u0``, ``y0`` by signal name about which a linear model holds.

    Parameters
    ----------
    x0, u0, y0 : mapping of str to float, optional
        State, control and output values by name; a signal not named is 0 (its deviation and
        absolute values coincide).

    Raises
    ------
    ParameterError
        For a non-string name or a non-finite value.

    Examples
    --------
    >>> op = OperatingPoint(u0={"steer": 0.01}, y0={"yaw_rate": 0.05})
    >>> op.as_dict()
    {'x0': {}, 'u0': {'steer': 0.01}, 'y0': {'yaw_rate': 0.05}}
    >>> OperatingPoint.from_dict(op.as_dict()) == op
    True
    """

    x0: dict[str, float] = field(default_factory=dict)
    u0: dict[str, float] = field(default_factory=dict)
    y0: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for what in _PARTS:
            object.__setattr__(self, what, _part(what, getattr(self, what) or {}, None))

    @classmethod
    def from_vectors(cls, states: Sequence[str], controls: Sequence[str], outputs: Sequence[str],
                     x0=None, u0=None, y0=None) -> OperatingPoint:
        """An operating point from vectors in the order of the given names (or mappings checked against them).

        Parameters
        ----------
        states, controls, outputs : sequence of str
            The model's signal names.
        x0, u0, y0 : array_like or mapping, optional
            One value per name, or ``{name: value}`` for some names; omitted means 0.

        Returns
        -------
        OperatingPoint

        Raises
        ------
        ParameterError
            For a vector of the wrong length, a name the model does not have or a non-finite value.

        Examples
        --------
        >>> OperatingPoint.from_vectors(["x"], ["u"], ["y"], u0=[2.0]).u0
        {'u': 2.0}
        """
        return cls(_part("x0", x0, tuple(states)), _part("u0", u0, tuple(controls)), _part("y0", y0, tuple(outputs)))

    @staticmethod
    def _values(part: dict[str, float], names: Sequence[str]) -> np.ndarray:
        return np.array([part.get(nm, 0.0) for nm in names], dtype=float)

    def control_values(self, names: Sequence[str]) -> np.ndarray:
        """``u0`` of the named controls (0 for a control the point does not name).

        Parameters
        ----------
        names : sequence of str
            Control names.

        Returns
        -------
        numpy.ndarray
            One value per name.

        Examples
        --------
        >>> OperatingPoint(u0={"a": 1.0}).control_values(["a", "b"]).tolist()
        [1.0, 0.0]
        """
        return self._values(self.u0, names)

    def output_values(self, names: Sequence[str]) -> np.ndarray:
        """``y0`` of the named outputs (0 for an output the point does not name).

        Parameters
        ----------
        names : sequence of str
            Output names.

        Returns
        -------
        numpy.ndarray
            One value per name.

        Examples
        --------
        >>> OperatingPoint(y0={"y": 3.0}).output_values(["y"]).tolist()
        [3.0]
        """
        return self._values(self.y0, names)

    def state_values(self, names: Sequence[str]) -> np.ndarray:
        """``x0`` of the named states (0 for a state the point does not name).

        Parameters
        ----------
        names : sequence of str
            State names.

        Returns
        -------
        numpy.ndarray
            One value per name.

        Examples
        --------
        >>> OperatingPoint(x0={"v": 25.0}).state_values(["v"]).tolist()
        [25.0]
        """
        return self._values(self.x0, names)

    def restricted(self, controls: Sequence[str], outputs: Sequence[str]) -> OperatingPoint:
        """The point's controls and outputs among the given names (states kept): what a generator reading them needs.

        Parameters
        ----------
        controls, outputs : sequence of str
            The signals to keep.

        Returns
        -------
        OperatingPoint

        Examples
        --------
        >>> OperatingPoint(u0={"a": 1.0, "b": 2.0}).restricted(["b"], []).u0
        {'b': 2.0}
        """
        return OperatingPoint(dict(self.x0), {k: v for k, v in self.u0.items() if k in controls},
                              {k: v for k, v in self.y0.items() if k in outputs})

    def as_dict(self) -> dict:
        """JSON-ready ``{"x0": {...}, "u0": {...}, "y0": {...}}``.

        Returns
        -------
        dict

        Examples
        --------
        >>> OperatingPoint(y0={"y": 1.5}).as_dict()["y0"]
        {'y': 1.5}
        """
        return {"x0": dict(self.x0), "u0": dict(self.u0), "y0": dict(self.y0)}

    @classmethod
    def from_dict(cls, data: Mapping) -> OperatingPoint:
        """The inverse of :meth:`as_dict`.

        Parameters
        ----------
        data : mapping
            With keys among ``x0``, ``u0``, ``y0``, each a mapping name → number.

        Returns
        -------
        OperatingPoint

        Raises
        ------
        ParameterError
            For another key or a bad value.

        Examples
        --------
        >>> OperatingPoint.from_dict({"u0": {"u": 1.0}}).u0
        {'u': 1.0}
        """
        if not isinstance(data, Mapping):
            raise ParameterError(f"an operating point must be a mapping with keys x0, u0, y0, got "
                                 f"{type(data).__name__}")
        extra = sorted(set(data) - set(_PARTS))
        if extra:
            raise ParameterError(f"operating point keys {extra} are unknown; use x0, u0, y0")
        parts = {}
        for k in _PARTS:
            v = data.get(k, {})
            if not isinstance(v, Mapping):
                raise ParameterError(f"operating point {k} must be a mapping name -> value, got {type(v).__name__}")
            parts[k] = dict(v)
        return cls(**parts)

    @property
    def is_zero(self) -> bool:
        """True when every value is 0 (deviation and absolute coordinates coincide)."""
        return not any(v != 0.0 for part in (self.x0, self.u0, self.y0) for v in part.values())
