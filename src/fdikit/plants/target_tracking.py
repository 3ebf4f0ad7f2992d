"""The maneuvering-target tracking benchmark of Hallouzi 2008, §2.4.2, (2.65)–(2.68).

A constant-velocity target in the plane, ``x = [p_x, v_x, p_y, v_y]`` (m, m/s), sampled at
``T_s = 1`` s and measured fully (``C = I_4``).  Only the input matrix switches, with a scalar input
``u ≡ 1`` (an acceleration of 1 m/s² along (−1, 1)/√2 or (1, −1)/√2)::

    A = [[1, T_s, 0, 0], [0, 1, 0, 0], [0, 0, 1, T_s], [0, 0, 0, 1]],   C = I_4          (2.65)
    B^(1) = 0 (straight),  B^(2) = √2 [−0.25, −0.5, 0.25, 0.5]ᵀ (left),  B^(3) = −B^(2) (right)   (2.66)
    Q = 1e-3 I_4,  R = diag(2.5e4, 1, 2.5e4, 1)                                          (2.67)
    Π = 0.98 on the diagonal, 0.01 elsewhere                                             (2.68)

The convex-model filters use only the two turn models (straight flight is ``0.5 B^(2) + 0.5 B^(3)``);
the IMM uses all three.
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = [
    "TRACKING_MODES",
    "TS",
    "Q_TRACKING",
    "R_TRACKING",
    "PI_TRACKING",
    "X0_TRACKING",
    "tracking_A",
    "tracking_B",
]

#: Sample time T_s [s] (§2.4.2).
TS = 1.0
#: Process-noise covariance (2.67).
Q_TRACKING = 1e-3 * np.eye(4)
#: Measurement-noise covariance (2.67); about 20 dB SNR on all four measurements.
R_TRACKING = np.diag([2.5e4, 1.0, 2.5e4, 1.0])
#: IMM transition matrix (2.68).
PI_TRACKING = np.full((3, 3), 0.01) + 0.97 * np.eye(3)
#: Initial target state [p_x, v_x, p_y, v_y] (§2.4.2).
X0_TRACKING = np.array([-500.0, 0.0, -500.0, 5.0])

TRACKING_MODES = ("straight", "left_turn", "right_turn")


def tracking_A(dt: float = TS) -> np.ndarray:
    """The constant-velocity transition matrix (Hallouzi 2008, (2.65)).

    Parameters
    ----------
    dt : float, default TS (1.0)
        Sample time ``T_s`` [s].

    Returns
    -------
    numpy.ndarray
        (4, 4) transition matrix for ``x = [p_x, v_x, p_y, v_y]``.

    Raises
    ------
    ParameterError
        If ``dt`` is not a finite positive number.

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.65).

    Examples
    --------
    >>> tracking_A(0.5)[0].tolist()
    [1.0, 0.5, 0.0, 0.0]
    """
    dt = validate.number("dt (the sample time)", dt, finite=False)
    if not (np.isfinite(dt) and dt > 0):
        raise ParameterError(f"sample time dt must be positive, got {dt}")
    A = np.eye(4)
    A[0, 1] = A[2, 3] = dt
    return A


def tracking_B(model: str) -> np.ndarray:
    """Input matrix (4, 1) of ``"straight"``, ``"left_turn"`` or ``"right_turn"`` (Hallouzi 2008, (2.66)).

    Parameters
    ----------
    model : {"straight", "left_turn", "right_turn"}
        One of :data:`TRACKING_MODES`.

    Returns
    -------
    numpy.ndarray
        (4, 1) input matrix ``B^(i)`` for the scalar input ``u ≡ 1`` [m/s²].

    Raises
    ------
    ParameterError
        If ``model`` is not one of the three modes.

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.66).

    Examples
    --------
    >>> (tracking_B("left_turn").ravel() / np.sqrt(2)).tolist()
    [-0.25, -0.5, 0.25, 0.5]
    """
    left = np.sqrt(2.0) * np.array([[-0.25], [-0.5], [0.25], [0.5]])
    table = {"straight": 0.0 * left, "left_turn": left, "right_turn": -left}
    if model not in table:
        raise ParameterError(f"unknown tracking model {model!r}; choose one of {TRACKING_MODES}")
    return table[model]


