"""F-16XL longitudinal dynamics, the aircraft example of the game-theoretic and H∞ filters.

:func:`f16xl_longitudinal` is Murray 2012, §6.1 (Example 1, from Chen & Speyer 2002):
four states, every state measured (``C = I``), the elevon as control and the wind gust
as a disturbance.  The numbers are as printed; two consistency checks pin them (the gust
column equals column 2 of ``A``, and ``−A e_4`` is the printed magnitude column of
``F_θ``; Murray note §8.1).
"""

from __future__ import annotations

import numpy as np

from fdikit.model import FaultModel

__all__ = ["f16xl_longitudinal", "F16XL_A"]

#: State matrix of Murray 2012, §6.1 (states u, w in ft/s, q in deg/s, θ in deg).
F16XL_A = np.array(
    [
        [-0.0674, 0.0430, -0.8886, -0.5587],
        [0.0205, -1.4666, 16.5800, -0.0299],
        [0.1377, -1.6788, -0.6819, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ]
)
_B_ELEVON = np.array([[-0.1672], [-1.5179], [-9.7842], [0.0]])
_B_GUST = np.array([[0.0430], [-1.4666], [-1.6788], [0.0]])


def f16xl_longitudinal() -> FaultModel:
    """F-16XL longitudinal model of Murray 2012, §6.1 (Example 1).

    Returns
    -------
    FaultModel
        States ``u, w, q, theta``; outputs ``y_u, y_w, y_q, y_theta`` (``C = I``); control
        ``elevon``; disturbance ``gust`` (``B_wg`` = column 2 of ``A``).  The three faults of
        the example are named by :func:`fdikit.design.resolve_faults`: ``'y_theta'`` (the
        pitch-angle sensor, ``[e_4, A e_4]``), ``'elevon'`` (``F_δ = B_δ``) and the gust as a
        fault map ``{'gust': model.Bd}``.

    Examples
    --------
    >>> m = f16xl_longitudinal()
    >>> m.n, m.p, m.controls, m.disturbances
    (4, 4, ('elevon',), ('gust',))
    """
    return FaultModel(
        F16XL_A,
        np.eye(4),
        Bu=_B_ELEVON,
        Bd=_B_GUST,
        states=("u", "w", "q", "theta"),
        outputs=("y_u", "y_w", "y_q", "y_theta"),
        controls=("elevon",),
        disturbances=("gust",),
    )
