"""A :class:`~fdikit.model.FaultModel` from a python-control state space (``FaultModel.from_control``).

python-control's :class:`control.StateSpace` carries input names but no input groups; this
assigns them to the groups ``u``, ``d``, ``f``, ``w`` by name.

Examples
--------
>>> import control
>>> from fdikit.model import FaultModel
>>> sys = control.ss([[-1.0]], [[1.0, 0.5]], [[1.0]], [[0.0, 0.0]], inputs=["u", "gust"], outputs=["y"])
>>> model_from_control(FaultModel, sys, disturbances=["gust"]).inputs["d"]
('gust',)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.errors import ModelError

__all__ = ["model_from_control"]

_GROUP_WORD = {"u": "controls", "d": "disturbances", "f": "faults", "w": "noise"}


def model_from_control(cls, sys, *, controls: Sequence[str] | None = None, disturbances: Sequence[str] = (),
                       faults: Sequence[str] = (), noise: Sequence[str] = ()):
    """Build a FaultModel (class ``cls``) from a :class:`control.StateSpace`, assigning its named inputs to groups.

    Parameters
    ----------
    cls : type
        :class:`fdikit.model.FaultModel` (or a subclass).
    sys : control.StateSpace
        The system; its input, state and output labels become the names.
    controls : sequence of str, optional
        Default every input not named in the other groups, in the system's order.
    disturbances, faults, noise : sequence of str
        Inputs of those groups.

    Returns
    -------
    FaultModel

    Raises
    ------
    ModelError
        If ``sys`` is no :class:`control.StateSpace`, a named input does not exist, or the sample time
        is unspecified (``dt=True``).

    Examples
    --------
    >>> import control
    >>> from fdikit.model import FaultModel
    >>> model_from_control(FaultModel, control.ss([[-2.0]], [[1.0]], [[1.0]], [[0.0]])).controls
    ('u[0]',)
    """
    import control

    if not isinstance(sys, control.StateSpace):
        raise ModelError(f"from_control needs a control.StateSpace, got {type(sys).__name__}; use control.ss(...)")
    in_names = list(sys.input_labels)
    others = list(disturbances) + list(faults) + list(noise)
    if controls is None:
        controls = [nm for nm in in_names if nm not in others]
    groups = {"u": list(controls), "d": list(disturbances), "f": list(faults), "w": list(noise)}
    kw: dict = {}
    for g, names in groups.items():
        missing = [nm for nm in names if nm not in in_names]
        if missing:
            raise ModelError(f"the system has no input named {missing}; its inputs are {in_names}")
        cols = [in_names.index(nm) for nm in names]
        kw[f"B{g}"] = np.asarray(sys.B)[:, cols]
        kw[f"D{g}"] = np.asarray(sys.D)[:, cols]
        kw[_GROUP_WORD[g]] = names
    dt = None if not sys.dt else (None if sys.dt is True else float(sys.dt))
    if sys.dt is True:
        raise ModelError("the system is discrete with an unspecified sample time (dt=True); give it a number")
    return cls(A=sys.A, C=sys.C, states=list(sys.state_labels), outputs=list(sys.output_labels), dt=dt, **kw)
