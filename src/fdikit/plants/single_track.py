"""Linear single-track (bicycle) lateral model with lane-error states (van der Ploeg 2018, App. B).

The lateral/yaw dynamics of a vehicle at constant longitudinal speed ``V_x``, augmented
with the camera's lateral error ``y_e`` and heading error ``psi_e`` to the lane centre,
eq. (B.12)::

    d/dt [V_y, r, y_e, psi_e] = A [V_y, r, y_e, psi_e] + B delta + B_d [kappa, sin(phi)]
    y = [r, y_e, psi_e]

    A = [[(C_f + C_r)/(m V_x),        (C_f l_f - C_r l_r)/(m V_x) - V_x,  0,  0  ],
         [(l_f C_f - l_r C_r)/(I_z V_x), (l_f² C_f + l_r² C_r)/(I_z V_x),   0,  0  ],
         [-1,                          0,                                 0,  V_x],
         [ 0,                         -1,                                 0,  0  ]]
    B   = [-C_f/m, -l_f C_f/I_z, 0, 0]^T
    B_d = [[0, g], [0, 0], [0, 0], [V_x, 0]]          (columns: curvature kappa, sin(bank phi))

with ``r = psi'`` the yaw rate, ``delta`` the front-wheel steering angle (rad), ``kappa``
the road curvature (1/m) and ``phi`` the road bank angle.  The lumped cornering
stiffnesses ``C_f, C_r`` are **negative** (Table 4-1; the tyre force is ``F_y = -C alpha``
with physical stiffness ``-C > 0``), which is the sign convention under which (B.8) as
printed is the standard, stable bicycle model.

Provenance: (B.8)–(B.11) of the thesis; (B.12) itself is garbled in the seed (``B``
printed with 5 entries and without ``/I_z``, ``B_d`` missing a zero, ``C`` printed 4 x 4
with a repeated row).  The matrices above are a reconstruction (fdikit's) that agrees with (B.8)–(B.11): heading
error ``psi_e' = V_x kappa - r`` (B.9),
lateral error ``y_e' = -V_y + V_x psi_e`` (B.10), bank force ``m g sin(phi)`` in the
lateral force balance (B.11).  Steering faults ``delta = f_m delta_set + f_a`` enter along
``B`` (add them with :meth:`FaultModel.with_actuator_faults`).

:func:`single_track_lpv` is the speed-scheduled family ``V_x -> sampled model`` of Sec. 4-3-4
(the speed frozen over each sample), with the DAE matrices (4.17) of each member.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.model import FaultModel, actuator_fault_name

__all__ = [
    "SingleTrackLPV",
    "SingleTrackParameters",
    "PRIUS_2010",
    "single_track",
    "single_track_lpv",
    "understeer_gradient",
    "STATES",
    "OUTPUTS",
    "CONTROLS",
    "DISTURBANCES",
]

STATES: tuple[str, ...] = ("lateral_velocity", "yaw_rate", "lateral_error", "heading_error")
OUTPUTS: tuple[str, ...] = ("yaw_rate", "lateral_error", "heading_error")
CONTROLS: tuple[str, ...] = ("steering",)
#: Road curvature kappa (1/m) and the sine of the road bank angle (sin(phi), dimensionless).
DISTURBANCES: tuple[str, ...] = ("curvature", "bank")


@dataclass(frozen=True)
class SingleTrackParameters:
    """Physical parameters of the single-track model (van der Ploeg 2018, Table 4-1).

    Attributes
    ----------
    l_f, l_r : float
        Distances from the centre of gravity to the front and rear axle (m).
    m : float
        Vehicle mass (kg).
    I_z : float
        Yaw moment of inertia (kg·m²).
    C_f, C_r : float
        Lumped front and rear axle cornering stiffnesses (N/rad), **negative** by the
        thesis' sign convention.
    g : float
        Gravitational acceleration (m/s²).

    Raises
    ------
    ParameterError
        On construction, if a field is not a finite number, a length, mass, inertia or ``g`` is not
        positive, or a cornering stiffness is not negative.

    References
    ----------
    van der Ploeg 2018, §4-1, Table 4-1; App. B-2-1, (B.8).

    Examples
    --------
    >>> p = SingleTrackParameters(m=1800.0)
    >>> p.m, round(p.wheelbase, 6)
    (1800.0, 2.7)
    """

    l_f: float = 1.108
    l_r: float = 1.592
    m: float = 1625.0
    I_z: float = 2865.61
    C_f: float = -1.17e5
    C_r: float = -1.43e5
    g: float = 9.81

    def __post_init__(self) -> None:
        for name in ("l_f", "l_r", "m", "I_z", "g", "C_f", "C_r"):
            object.__setattr__(self, name, validate.number(f"SingleTrackParameters.{name}", getattr(self, name)))
        for name in ("l_f", "l_r", "m", "I_z", "g"):
            value = getattr(self, name)
            if not value > 0:
                raise ParameterError(f"SingleTrackParameters.{name} must be a positive finite number, got {value!r}")
        for name in ("C_f", "C_r"):
            value = getattr(self, name)
            if not value < 0:
                raise ParameterError(
                    f"SingleTrackParameters.{name} must be negative (thesis convention F_y = -C alpha), got {value!r}; "
                    f"pass -{abs(value)!r} for a physical stiffness of {abs(value)!r} N/rad"
                )

    @property
    def wheelbase(self) -> float:
        """``l_f + l_r`` (m)."""
        return self.l_f + self.l_r


#: Toyota Prius 2010 as identified by TNO (van der Ploeg 2018, Table 4-1).
PRIUS_2010 = SingleTrackParameters()


def understeer_gradient(params: SingleTrackParameters = PRIUS_2010) -> float:
    """Understeer gradient ``K_u = m_f/c_f - m_r/c_r`` in rad/(m/s²), with ``c = -C > 0``.

    ``m_f = m l_r / L`` and ``m_r = m l_f / L`` are the static axle loads (kg).  ``K_u > 0``
    is understeer (stable at every speed; no critical speed).  For :data:`PRIUS_2010`
    ``K_u = 0.003526`` rad/(m/s²) (computed from Table 4-1; not printed in the thesis).

    Parameters
    ----------
    params : SingleTrackParameters, default PRIUS_2010
        Vehicle parameters.

    Returns
    -------
    float
        ``K_u`` in rad/(m/s²).

    Raises
    ------
    ParameterError
        If ``params`` is not a :class:`SingleTrackParameters`.

    References
    ----------
    van der Ploeg 2018, Table 4-1 (the parameters); App. B-2-1 (the single-track model).

    Examples
    --------
    >>> round(understeer_gradient(), 6)
    0.003526
    """
    if not isinstance(params, SingleTrackParameters):
        raise ParameterError(f"params must be a SingleTrackParameters, got {type(params).__name__}")
    m_f = params.m * params.l_r / params.wheelbase
    m_r = params.m * params.l_f / params.wheelbase
    return m_f / -params.C_f - m_r / -params.C_r


def single_track(speed: float, params: SingleTrackParameters = PRIUS_2010, dt: float | None = None) -> FaultModel:
    """Single-track lateral model with lane errors at a constant speed (van der Ploeg 2018, (B.12)).

    Parameters
    ----------
    speed : float
        Longitudinal speed ``V_x`` in **m/s** (divide km/h by 3.6); must be positive.
    params : SingleTrackParameters, optional
        Vehicle parameters; default :data:`PRIUS_2010` (Table 4-1).
    dt : float, optional
        If given, the model is sampled with a zero-order hold at this period (s), as the
        thesis does in (4.5) with ``h = 0.01``; otherwise it is continuous.

    Returns
    -------
    FaultModel
        States ``lateral_velocity`` (m/s), ``yaw_rate`` (rad/s), ``lateral_error`` (m),
        ``heading_error`` (rad); outputs ``yaw_rate, lateral_error, heading_error``;
        control ``steering`` (rad); disturbances ``curvature`` (1/m) and ``bank``
        (= sin of the bank angle).

    Raises
    ------
    ParameterError
        If ``speed`` is not a positive finite number (the model has ``1/V_x`` terms).

    References
    ----------
    van der Ploeg 2018, App. B-2, (B.8)–(B.12); §4-3-1, (4.5) (the ZOH sampling); Table 4-1.

    Examples
    --------
    >>> from fdikit.plants import single_track
    >>> m = single_track(70 / 3.6)
    >>> m.outputs
    ('yaw_rate', 'lateral_error', 'heading_error')
    >>> round(float(single_track(70 / 3.6, dt=0.01).A[0, 0]), 6)
    0.919689
    """
    v = _speed(speed)
    if not isinstance(params, SingleTrackParameters):
        raise ParameterError(f"params must be a SingleTrackParameters, got {type(params).__name__}")
    A, Bu, Bd, C = _continuous_matrices(v, params)
    model = FaultModel(
        A, C, Bu=Bu, Bd=Bd, states=STATES, outputs=OUTPUTS, controls=CONTROLS, disturbances=DISTURBANCES
    )
    return model if dt is None else model.discretize(dt)


def _speed(speed) -> float:
    """``speed`` as a positive finite float (m/s), or a ParameterError saying how to fix it."""
    try:
        v = float(speed)
    except (TypeError, ValueError):
        raise ParameterError(f"speed must be a number in m/s, got {speed!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(
            f"speed must be a positive finite longitudinal speed in m/s, got {speed!r}; "
            "the single-track model divides by V_x (use e.g. 70 / 3.6 for 70 km/h)"
        )
    return v


def _continuous_matrices(v, p: SingleTrackParameters) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``A, B, B_d, C`` of (B.12) (reconstructed from (B.8)–(B.11), see the module docstring) at speed ``v`` (m/s;
    a float, or an array for stacks)."""
    v = np.asarray(v, dtype=float)
    A = np.zeros(v.shape + (4, 4))
    A[..., 0, 0] = (p.C_f + p.C_r) / (p.m * v)
    A[..., 0, 1] = (p.C_f * p.l_f - p.C_r * p.l_r) / (p.m * v) - v
    A[..., 1, 0] = (p.l_f * p.C_f - p.l_r * p.C_r) / (p.I_z * v)
    A[..., 1, 1] = (p.l_f**2 * p.C_f + p.l_r**2 * p.C_r) / (p.I_z * v)
    A[..., 2, 0], A[..., 2, 3], A[..., 3, 1] = -1.0, v, -1.0
    Bu = np.zeros(v.shape + (4, 1))
    Bu[..., 0, 0], Bu[..., 1, 0] = -p.C_f / p.m, -p.l_f * p.C_f / p.I_z
    Bd = np.zeros(v.shape + (4, 2))
    Bd[..., 0, 1], Bd[..., 3, 0] = p.g, v
    C = np.broadcast_to(np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]), v.shape + (3, 4))
    return A, Bu, Bd, np.array(C)


def _expm(M: np.ndarray) -> np.ndarray:
    """``e^M`` by scaling and squaring with a degree-16 Taylor polynomial (numpy only; stacks (..., k, k) allowed).

    After scaling ``‖M / 2^s‖₁ ≤ 1/2`` (the largest norm of the stack) the truncation error is below
    ``0.5¹⁷ / 17! < 1e-19``; for the 7 x 7 single-track matrices this agrees with
    :func:`scipy.linalg.expm` to round-off (tested) and costs ~20 small products instead of a LAPACK
    solve, which matters when the LPV filter rediscretises at every sample.  For a stack of 7001
    speeds it took 0.03–0.06 s, scipy's batched ``expm`` 0.1–13 s (slow when other processes load the CPU).
    """
    norm = float(np.abs(M).sum(axis=-2).max())
    s = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    X = M / 2.0**s
    E = np.broadcast_to(np.eye(M.shape[-1]), M.shape)
    term = E
    for k in range(1, 17):
        term = term @ X / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


@functools.lru_cache(maxsize=8192)
def _sampled_matrices(v: float, p: SingleTrackParameters, dt: float) -> tuple[np.ndarray, ...]:
    """Exact ZOH ``(𝒜, ℬ, ℬ_d, C)`` at one speed (thesis (4.5)), cached by ``(v, p, dt)``.

    ``expm([[A, B, B_d], [0, 0, 0]] h)`` — the augmented exponential that
    :func:`scipy.signal.cont2discrete` (``'zoh'``) also uses, so the values equal
    ``single_track(v, p, dt)`` to round-off.
    """
    out = _zoh(np.float64(v), p, dt)
    for arr in out:
        arr.setflags(write=False)
    return out


def _zoh(v: np.ndarray, p: SingleTrackParameters, dt: float) -> tuple[np.ndarray, ...]:
    """``(𝒜, ℬ, ℬ_d, C)`` at the speed(s) ``v``: one (batched) exponential of the augmented matrix."""
    A, Bu, Bd, C = _continuous_matrices(v, p)
    n, k = A.shape[-1], Bu.shape[-1] + Bd.shape[-1]
    M = np.zeros(A.shape[:-2] + (n + k, n + k))
    M[..., :n, :n], M[..., :n, n : n + 1], M[..., :n, n + 1 :] = A, Bu, Bd
    E = _expm(dt * M)[..., :n, :]
    return E[..., :n], E[..., n : n + 1], E[..., n + 1 :], C


@dataclass(frozen=True)
class SingleTrackLPV:
    """Speed-scheduled family of sampled single-track models (van der Ploeg 2018, Sec. 4-3-4).

    Calling the family with a speed (m/s) returns the discrete :class:`FaultModel` of
    :func:`single_track` at that speed, with the steering fault ``steering_actuator``
    (``ℬ_f = ℬ``, eq. (4.5)) when ``steering_fault`` is true.  This is the thesis' "complete
    discretisation" (ref. [36]): the speed is frozen over each sample, so the parameter-varying
    model is ``X(k+1) = 𝒜(V_x(k)) X(k) + ℬ(V_x(k)) δ(k) + ℬ_d(V_x(k)) d(k)``.  The sampled
    matrices are cached per speed (the LPV filter asks for the same speeds several times).

    Attributes
    ----------
    params : SingleTrackParameters
        Vehicle parameters (default :data:`PRIUS_2010`, Table 4-1).
    dt : float
        Sample time ``h`` in s (default 0.01, as in the thesis).
    steering_fault : bool
        Add the additive steering fault input ``steering_actuator`` (default True).

    References
    ----------
    van der Ploeg 2018, §4-3-4, (4.17); §4-3-1, (4.5).

    Examples
    --------
    >>> family = single_track_lpv()
    >>> model = family(70 / 3.6)
    >>> model.faults, model.dt
    (('steering_actuator',), 0.01)
    >>> round(float(model.A[0, 0]), 6)
    0.919689
    """

    params: SingleTrackParameters = PRIUS_2010
    dt: float = 0.01
    steering_fault: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.params, SingleTrackParameters):
            raise ParameterError(f"params must be a SingleTrackParameters, got {type(self.params).__name__}")
        dt = validate.number("dt (sample time in s)", self.dt)
        if not dt > 0:
            raise ParameterError(f"dt must be a positive sample time in s (the thesis uses 0.01), got {self.dt!r}")
        object.__setattr__(self, "dt", dt)

    def matrices(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Read-only ``(𝒜, ℬ, ℬ_d, C)`` at ``speed`` (m/s): the sampled (4.5) matrices, cached."""
        return _sampled_matrices(_speed(speed), self.params, self.dt)

    def state_space(self, speed) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Stacks ``(𝒜, [ℬ ℬ_d], C, 0)`` at every speed of an array (m/s), in one batched exponential.

        Shapes ``(N, 4, 4), (N, 4, 3), (N, 3, 4), (N, 3, 3)``; ``B`` and ``D`` act on
        ``[steering, curvature, bank]``.  The vectorised form of :meth:`matrices` (equal to round-off,
        not cached), read by :func:`fdikit.simulate.simulate_scheduled` when the speed changes every sample.
        """
        v = np.atleast_1d(np.asarray(speed, dtype=float))
        if v.ndim != 1 or not np.all(np.isfinite(v) & (v > 0)):
            raise ParameterError("speeds must be a 1-D array of positive finite longitudinal speeds in m/s")
        A, Bu, Bd, C = _zoh(v, self.params, self.dt)
        return A, np.concatenate([Bu, Bd], axis=-1), C, np.zeros(C.shape[:-1] + (3,))

    def __call__(self, speed: float) -> FaultModel:
        """The discrete model at ``speed`` (m/s)."""
        A, Bu, Bd, C = self.matrices(speed)
        faults = {"Bf": Bu, "faults": [actuator_fault_name(c) for c in CONTROLS]} if self.steering_fault else {}
        return FaultModel(
            A, C, Bu=Bu, Bd=Bd, states=STATES, outputs=OUTPUTS, controls=CONTROLS, disturbances=DISTURBANCES,
            dt=self.dt, **faults,
        )

    def dae_matrices(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(H_0, H_1, L, F)`` of the DAE (4.17) at ``speed`` (m/s): ``(H_0 + H_1 q) x + L z + F f = 0``.

        ``x = [V_y, r, y_e, ψ_e, κ, sin φ]``, ``z = [r, y_e, ψ_e, δ_set]`` (outputs, then the
        steering command), ``f`` the steering fault (``f_a``, or ``(f_m − 1) δ_set``)::

            H_0 = [[𝒜, ℬ_d], [C, 0]],  H_1 = [[−I, 0], [0, 0]],  L = [[0, ℬ], [−I, 0]],  F = [ℬ; 0]
        """
        return _dae_matrices(_speed(speed), self.params, self.dt)


@functools.lru_cache(maxsize=8192)
def _dae_matrices(v: float, p: SingleTrackParameters, dt: float) -> tuple[np.ndarray, ...]:
    A, Bu, Bd, C = _sampled_matrices(v, p, dt)
    n, ny, nd = A.shape[0], C.shape[0], Bd.shape[1]
    H0, H1 = np.zeros((n + ny, n + nd)), np.zeros((n + ny, n + nd))
    H0[:n, :n], H0[:n, n:], H0[n:, :n] = A, Bd, C
    H1[:n, :n] = -np.eye(n)
    L, F = np.zeros((n + ny, ny + 1)), np.zeros((n + ny, 1))
    L[:n, ny:], L[n:, :ny], F[:n] = Bu, -np.eye(ny), Bu
    for arr in (H0, H1, L, F):
        arr.setflags(write=False)
    return H0, H1, L, F


def single_track_lpv(
    params: SingleTrackParameters = PRIUS_2010, dt: float = 0.01, steering_fault: bool = True
) -> SingleTrackLPV:
    """The speed-scheduled single-track family ``speed (m/s) -> discrete FaultModel`` (van der Ploeg 2018, (4.17)).

    See :class:`SingleTrackLPV`; ``family(v)`` equals ``single_track(v, params, dt)`` (plus the
    steering fault) and ``family.dae_matrices(v)`` gives the DAE (4.17).

    Parameters
    ----------
    params : SingleTrackParameters, default PRIUS_2010
        Vehicle parameters (Table 4-1).
    dt : float, default 0.01
        Sample time ``h`` [s].
    steering_fault : bool, default True
        Give each member the additive steering fault input ``steering_actuator``.

    Returns
    -------
    SingleTrackLPV
        The family; call it with a speed in m/s.

    Raises
    ------
    ParameterError
        If ``params`` is not a :class:`SingleTrackParameters` or ``dt`` is not a positive number.

    References
    ----------
    van der Ploeg 2018, §4-3-4, (4.17).

    Examples
    --------
    >>> family = single_track_lpv(dt=0.02)
    >>> family(20.0).dt, family.dae_matrices(20.0)[0].shape
    (0.02, (7, 6))
    """
    return SingleTrackLPV(params, dt, steering_fault)
