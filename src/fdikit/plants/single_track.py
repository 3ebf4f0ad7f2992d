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

Production cars also measure the lateral acceleration and (on test vehicles) the side slip;
``outputs=`` selects among :data:`SENSORS` (default :data:`OUTPUTS`, as before)::

    a_y  = V_y' + V_x r = V_x (β' + r)          (β = V_y / V_x at constant V_x)
         = (C_f + C_r)/(m V_x) V_y + (C_f l_f - C_r l_r)/(m V_x) r - C_f/m delta + g sin(phi)
    beta = V_y / V_x

``a_y`` is the first row of the state equation plus ``V_x r``, so it has the feedthrough
``D = -C_f/m`` from the steering and ``g`` from ``sin(phi)`` — the kinematic acceleration of the
path, as the ``lateral_acceleration`` of the nonlinear car (:mod:`fdikit.vehicle.dynamics`).  A body-fixed
accelerometer on a banked road reads the specific force ``a_y - g sin(phi)`` (the tyre forces over
``m``): drop the bank column if you model it.  Being an output equation, ``a_y`` is the same for the
continuous and the ZOH-sampled model.

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
from collections.abc import Sequence
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
    "sensor_selection",
    "STATES",
    "OUTPUTS",
    "SENSORS",
    "CONTROLS",
    "DISTURBANCES",
]

STATES: tuple[str, ...] = ("lateral_velocity", "yaw_rate", "lateral_error", "heading_error")
#: The default outputs: yaw rate and the camera's lane errors (eq. (B.12)).
OUTPUTS: tuple[str, ...] = ("yaw_rate", "lateral_error", "heading_error")
#: Every output ``outputs=`` may select: :data:`OUTPUTS`, the lateral acceleration ``a_y = V_x (β' + r)`` [m/s²]
#: and the side-slip angle ``β = V_y / V_x`` [rad] (the names of :mod:`fdikit.plants.varrier_lateral`).
SENSORS: tuple[str, ...] = OUTPUTS + ("lateral_acceleration", "sideslip")
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


def single_track(
    speed: float, params: SingleTrackParameters = PRIUS_2010, dt: float | None = None, *,
    outputs: Sequence[str] | None = None,
) -> FaultModel:
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
    outputs : sequence of str, optional
        Measured signals, in this order, from :data:`SENSORS`: ``yaw_rate`` [rad/s],
        ``lateral_error`` [m], ``heading_error`` [rad], ``lateral_acceleration`` [m/s²]
        (``a_y = V_x (β' + r)``, with feedthrough from ``steering`` and ``bank``) and
        ``sideslip`` [rad] (``β = V_y / V_x``).  Default :data:`OUTPUTS` (the thesis' three).

    Returns
    -------
    FaultModel
        States ``lateral_velocity`` (m/s), ``yaw_rate`` (rad/s), ``lateral_error`` (m),
        ``heading_error`` (rad); the selected outputs (default ``yaw_rate, lateral_error,
        heading_error``); control ``steering`` (rad); disturbances ``curvature`` (1/m) and ``bank``
        (= sin of the bank angle).

    Raises
    ------
    ParameterError
        If ``speed`` is not a positive finite number (the model has ``1/V_x`` terms), or ``outputs``
        is empty, repeats a name or names a signal not in :data:`SENSORS`.

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
    >>> m = single_track(20.0, outputs=["yaw_rate", "lateral_acceleration", "sideslip"])
    >>> round(float(m.Du[1, 0]), 3), float(m.Dd[1, 1]), float(m.C[2, 0])   # -C_f/m, g, 1/V_x
    (72.0, 9.81, 0.05)
    """
    v = _speed(speed)
    if not isinstance(params, SingleTrackParameters):
        raise ParameterError(f"params must be a SingleTrackParameters, got {type(params).__name__}")
    names = sensor_selection(outputs)
    A, Bu, Bd, _ = _continuous_matrices(v, params)
    C, Du, Dd = _output_matrices(v, params, names)
    model = FaultModel(
        A, C, Bu=Bu, Bd=Bd, Du=Du, Dd=Dd, states=STATES, outputs=names, controls=CONTROLS, disturbances=DISTURBANCES
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


def sensor_selection(outputs: Sequence[str] | None = None) -> tuple[str, ...]:
    """The checked output names of a single-track model: ``outputs`` as a tuple, or :data:`OUTPUTS` if None.

    Parameters
    ----------
    outputs : sequence of str, optional
        Names from :data:`SENSORS` (a single string is one name).

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        If the selection is empty, repeats a name or names an unknown signal.

    References
    ----------
    van der Ploeg 2018, App. B-2, (B.12) (the default outputs).

    Examples
    --------
    >>> sensor_selection(), sensor_selection("lateral_acceleration")
    (('yaw_rate', 'lateral_error', 'heading_error'), ('lateral_acceleration',))
    """
    if outputs is None:
        return OUTPUTS
    names = (outputs,) if isinstance(outputs, str) else tuple(outputs)
    if not names:
        raise ParameterError(f"outputs must name at least one signal of {list(SENSORS)}; omit it for {list(OUTPUTS)}")
    for name in names:
        validate.choice("outputs", name, SENSORS)
    if len(set(names)) != len(names):
        raise ParameterError(f"outputs repeats a signal: {list(names)}; name each of {list(SENSORS)} at most once")
    return names


def _output_matrices(v, p: SingleTrackParameters, names: tuple[str, ...]) -> tuple[np.ndarray, ...]:
    """``C, D_u, D_d`` of the outputs ``names`` at speed ``v`` (a float or an array for stacks).

    ``a_y = V_y' + V_x r`` is row 0 of ``[A B B_d]`` plus ``V_x`` on ``r``; ``β = V_y / V_x``.
    """
    v = np.asarray(v, dtype=float)
    shape = v.shape + (len(names),)
    C, Du, Dd = np.zeros(shape + (4,)), np.zeros(shape + (1,)), np.zeros(shape + (2,))
    for i, name in enumerate(names):
        if name in STATES:
            C[..., i, STATES.index(name)] = 1.0
        elif name == "lateral_acceleration":
            C[..., i, 0] = (p.C_f + p.C_r) / (p.m * v)
            C[..., i, 1] = (p.C_f * p.l_f - p.C_r * p.l_r) / (p.m * v)
            Du[..., i, 0], Dd[..., i, 1] = -p.C_f / p.m, p.g
        else:  # sideslip
            C[..., i, 0] = 1.0 / v
    return C, Du, Dd


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
    outputs : tuple of str
        The measured signals, from :data:`SENSORS` (default :data:`OUTPUTS`); with
        ``lateral_acceleration`` the members have the feedthrough ``D`` of :func:`single_track`.

    Raises
    ------
    ParameterError
        On construction: ``params`` not a :class:`SingleTrackParameters`, ``dt`` not positive, or
        a bad ``outputs`` selection (see :func:`single_track`).

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
    >>> single_track_lpv(outputs=("yaw_rate", "lateral_acceleration"))(20.0).outputs
    ('yaw_rate', 'lateral_acceleration')
    """

    params: SingleTrackParameters = PRIUS_2010
    dt: float = 0.01
    steering_fault: bool = True
    outputs: tuple[str, ...] = OUTPUTS

    def __post_init__(self) -> None:
        if not isinstance(self.params, SingleTrackParameters):
            raise ParameterError(f"params must be a SingleTrackParameters, got {type(self.params).__name__}")
        dt = validate.number("dt (sample time in s)", self.dt)
        if not dt > 0:
            raise ParameterError(f"dt must be a positive sample time in s (the thesis uses 0.01), got {self.dt!r}")
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "outputs", sensor_selection(self.outputs))

    def matrices(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Read-only ``(𝒜, ℬ, ℬ_d, C)`` at ``speed`` (m/s): the sampled (4.5) matrices, cached.

        ``C`` of the selected :attr:`outputs`; their feedthrough is :meth:`feedthrough`.
        """
        v = _speed(speed)
        A, Bu, Bd, _ = _sampled_matrices(v, self.params, self.dt)
        return A, Bu, Bd, self._outputs_at(v)[0]

    def feedthrough(self, speed: float) -> tuple[np.ndarray, np.ndarray]:
        """Read-only ``(D_u, D_d)`` of the selected :attr:`outputs` at ``speed`` (m/s) (zero for the default three)."""
        return self._outputs_at(_speed(speed))[1:]

    def _outputs_at(self, v: float) -> tuple[np.ndarray, ...]:
        return _output_rows(v, self.params, self.outputs)

    def state_space(self, speed) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Stacks ``(𝒜, [ℬ ℬ_d], C, 0)`` at every speed of an array (m/s), in one batched exponential.

        Shapes ``(N, 4, 4), (N, 4, 3), (N, 3, 4), (N, 3, 3)``; ``B`` and ``D`` act on
        ``[steering, curvature, bank]``.  The vectorised form of :meth:`matrices` (equal to round-off,
        not cached), read by :func:`fdikit.simulate.simulate_scheduled` when the speed changes every sample.
        """
        v = np.atleast_1d(np.asarray(speed, dtype=float))
        if v.ndim != 1 or not np.all(np.isfinite(v) & (v > 0)):
            raise ParameterError("speeds must be a 1-D array of positive finite longitudinal speeds in m/s")
        A, Bu, Bd, _ = _zoh(v, self.params, self.dt)
        C, Du, Dd = _output_matrices(v, self.params, self.outputs)
        return A, np.concatenate([Bu, Bd], axis=-1), C, np.concatenate([Du, Dd], axis=-1)

    def __call__(self, speed: float) -> FaultModel:
        """The discrete model at ``speed`` (m/s)."""
        A, Bu, Bd, C = self.matrices(speed)
        Du, Dd = self.feedthrough(speed)
        faults = ({"Bf": Bu, "Df": Du, "faults": [actuator_fault_name(c) for c in CONTROLS]}
                  if self.steering_fault else {})
        return FaultModel(
            A, C, Bu=Bu, Bd=Bd, Du=Du, Dd=Dd, states=STATES, outputs=self.outputs, controls=CONTROLS,
            disturbances=DISTURBANCES, dt=self.dt, **faults,
        )

    def dae_matrices(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(H_0, H_1, L, F)`` of the DAE (4.17) at ``speed`` (m/s): ``(H_0 + H_1 q) x + L z + F f = 0``.

        ``x = [V_y, r, y_e, ψ_e, κ, sin φ]``, ``z = [y; δ_set]`` (the selected outputs, then the
        steering command; default ``[r, y_e, ψ_e, δ_set]``), ``f`` the steering fault (``f_a``, or
        ``(f_m − 1) δ_set``)::

            H_0 = [[𝒜, ℬ_d], [C, D_d]],  H_1 = [[−I, 0], [0, 0]],  L = [[0, ℬ], [−I, D_u]],  F = [ℬ; D_u]

        (``D_u = D_d = 0`` for the default outputs, as printed in (4.17)).
        """
        return _dae_matrices(_speed(speed), self.params, self.dt, self.outputs)


@functools.lru_cache(maxsize=8192)
def _output_rows(v: float, p: SingleTrackParameters, names: tuple[str, ...]) -> tuple[np.ndarray, ...]:
    out = _output_matrices(np.float64(v), p, names)
    for arr in out:
        arr.setflags(write=False)
    return out


@functools.lru_cache(maxsize=8192)
def _dae_matrices(v: float, p: SingleTrackParameters, dt: float, names: tuple[str, ...] = OUTPUTS
                  ) -> tuple[np.ndarray, ...]:
    A, Bu, Bd, _ = _sampled_matrices(v, p, dt)
    C, Du, Dd = _output_rows(v, p, names)
    n, ny, nd = A.shape[0], C.shape[0], Bd.shape[1]
    H0, H1 = np.zeros((n + ny, n + nd)), np.zeros((n + ny, n + nd))
    H0[:n, :n], H0[:n, n:], H0[n:, :n], H0[n:, n:] = A, Bd, C, Dd
    H1[:n, :n] = -np.eye(n)
    L, F = np.zeros((n + ny, ny + 1)), np.zeros((n + ny, 1))
    L[:n, ny:], L[n:, :ny], L[n:, ny:], F[:n], F[n:] = Bu, -np.eye(ny), Du, Bu, Du
    for arr in (H0, H1, L, F):
        arr.setflags(write=False)
    return H0, H1, L, F


def single_track_lpv(
    params: SingleTrackParameters = PRIUS_2010, dt: float = 0.01, steering_fault: bool = True, *,
    outputs: Sequence[str] | None = None,
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
    outputs : sequence of str, optional
        Measured signals from :data:`SENSORS` (default :data:`OUTPUTS`), as in :func:`single_track`.

    Returns
    -------
    SingleTrackLPV
        The family; call it with a speed in m/s.

    Raises
    ------
    ParameterError
        If ``params`` is not a :class:`SingleTrackParameters`, ``dt`` is not a positive number or
        ``outputs`` is a bad selection.

    References
    ----------
    van der Ploeg 2018, §4-3-4, (4.17).

    Examples
    --------
    >>> family = single_track_lpv(dt=0.02)
    >>> family(20.0).dt, family.dae_matrices(20.0)[0].shape
    (0.02, (7, 6))
    """
    return SingleTrackLPV(params, dt, steering_fault, sensor_selection(outputs))
