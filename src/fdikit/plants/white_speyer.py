"""The three-state White–Speyer system: Murray 2012, §6.2 (Example 2).

An unstable plant (eigenvalues 6.6944, 1.1867, −0.8811) with two outputs and two fault
directions.  ``F_1 = [1, −0.5, 0.5]ᵀ`` is common to the four cases; ``F_2`` sets the
invariant-zero structure that the game filter has to cope with (invariant zeros
of ``(C, A, F_2)``; ``tests/test_linalg.py`` checks them):

=======================  ================  ==============================================
case                     ``F_2``            zeros
=======================  ================  ==============================================
``stable-zero``          ``[3, 1, 0]``      ``(C, A, F_2)`` at −3 (§6.2.1)
``unstable-zero``        ``[−3, 1, 0]``     ``(C, A, F_2)`` at +3 (§6.2.2)
``stable-extra-zero``    ``[5, 1, 1]``      extra zero of ``(C, A, [F_1 F_2])`` at −1.5 (§6.2.3)
``unstable-extra-zero``  ``[0, 0, 1]``      extra zero of ``(C, A, [F_1 F_2])`` at +2 (§6.2.4)
=======================  ================  ==============================================
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = ["white_speyer", "WHITE_SPEYER_CASES"]

#: ``F_2`` of each case of Murray 2012, §6.2.1–6.2.4.
WHITE_SPEYER_CASES: dict[str, tuple[float, float, float]] = {
    "stable-zero": (3.0, 1.0, 0.0),
    "unstable-zero": (-3.0, 1.0, 0.0),
    "stable-extra-zero": (5.0, 1.0, 1.0),
    "unstable-extra-zero": (0.0, 0.0, 1.0),
}


def white_speyer(case: str = "stable-zero") -> FaultModel:
    """White–Speyer example of Murray 2012, §6.2, with faults ``f1`` and ``f2``.

    ``A = [[0, 3, 4], [1, 2, 3], [0, 2, 5]]``, ``C = [[0, 1, 0], [0, 0, 1]]``, ``B = 0``;
    ``F_1 = [1, −0.5, 0.5]ᵀ`` and ``F_2`` from :data:`WHITE_SPEYER_CASES`.

    Parameters
    ----------
    case : {"stable-zero", "unstable-zero", "stable-extra-zero", "unstable-extra-zero"}, default "stable-zero"
        Which ``F_2`` of :data:`WHITE_SPEYER_CASES` (Murray 2012, §6.2.1–6.2.4).

    Returns
    -------
    FaultModel
        Continuous model with 3 states ``x1 … x3``, outputs ``y1, y2``, no controls and the fault
        inputs ``f1``, ``f2`` (columns ``F_1``, ``F_2`` of ``Bf``).

    Raises
    ------
    ParameterError
        If ``case`` is not one of the four cases.

    References
    ----------
    Murray 2012, §6.2 (Example 2), §6.2.1–6.2.4.

    Examples
    --------
    >>> m = white_speyer("unstable-zero")
    >>> m.Bf[:, 1].tolist()
    [-3.0, 1.0, 0.0]
    """
    if not isinstance(case, str) or case not in WHITE_SPEYER_CASES:
        raise ParameterError(f"unknown White–Speyer case {case!r}; choose one of {', '.join(WHITE_SPEYER_CASES)}")
    A = np.array([[0.0, 3.0, 4.0], [1.0, 2.0, 3.0], [0.0, 2.0, 5.0]])
    C = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    F = np.column_stack([[1.0, -0.5, 0.5], WHITE_SPEYER_CASES[case]])
    return FaultModel(A, C, Bf=F, faults=("f1", "f2"), states=("x1", "x2", "x3"), outputs=("y1", "y2"))
