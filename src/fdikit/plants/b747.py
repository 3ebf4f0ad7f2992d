"""Boeing 747 linear longitudinal FDI example: Hallouzi 2008, §2.4.1, (2.54)–(2.61), Tables 2.5–2.6.

Operating point: altitude 600 m, 133.8 m/s.  States ``x = [q, V_TAS, α, θ, h]`` (θ is the pitch
angle; the thesis calls it "roll angle"), inputs ``[δ_c, δ_s, T_n1 … T_n4]`` (column and stabiliser
deflection [rad], engine thrust [N]), outputs ``q, V_TAS, α, h``.

Erratum (Hallouzi 2008, (2.56)): the printed ``A(3, 5) = 6.83e-1`` gives a 9.6 rad/s short period;
``6.83e-7`` (exponent misread) gives the plausible modes −0.634 ± 1.154j (short period),
−0.00234 ± 0.0929j (phugoid) and +0.00065 (height mode).  ``a35="corrected"`` (default) uses 6.83e-7,
``a35="printed"`` the printed value.

**Substitutes.** The B and C matrices (2.57)–(2.61) are lost in the seed.  ``C`` is the selector of
``q, V, α, h`` (text of §2.4.1).  ``B`` is a *labelled substitute*, not thesis data: column and
stabiliser act mainly on pitch acceleration (−1.2 and −2.4 rad/s² per rad) with a small lift term on
α (−0.03 and −0.06 1/s per rad); each engine accelerates along V by 1/(3·10⁵ kg) per N and pitches
nose-up by 6.7·10⁻⁸ rad/s² per N.  Fault models (Table 2.5): 2/3 zero the δ_c/δ_s column of B, 4/5
zero the V/α entry of C ("total" faults).

``b_source="jsbsim"`` replaces the substitute B (and C, the same selector) by the linearisation of JSBSim's
B747 at the §2.4.1 point (:func:`fdikit.plants.b747_jsbsim.b747_jsbsim_matrices`: elevator, fdikit's
stabiliser = elevator terms ×2, thrust per N of each engine); A stays the printed A (2.56), which is thesis
data.  ``a_source="jsbsim"`` takes JSBSim's A as well.

References
----------
Hallouzi 2008, §2.4.1, (2.54)–(2.61), Tables 2.5–2.6.
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = [
    "B747_STATES",
    "B747_MODEL_NAMES",
    "B747_FAULT_SCHEDULE",
    "B747_NOISE",
    "B747_TRANSITION",
    "b747_longitudinal",
    "b747_model_set",
]

B747_STATES = ("q", "V_TAS", "alpha", "theta", "h")
_OUTPUTS = ("q", "V_TAS", "alpha", "h")
_CONTROLS = ("delta_c", "delta_s", "T_n1", "T_n2", "T_n3", "T_n4")
#: Table 2.5, in model order.
B747_MODEL_NAMES = ("nominal", "delta_c_loss", "delta_s_loss", "V_TAS_sensor", "alpha_sensor")
#: Table 2.6: (first sample, last sample, true convex weights over the 5 models); T_s = 0.01 s.
#: The 4th interval (20 % V_TAS-sensor fault) has no samples in Table 2.6 as printed; 800–900 by the pattern.
B747_FAULT_SCHEDULE: tuple[tuple[int, int, tuple[float, ...]], ...] = (
    (200, 300, (0.7, 0.0, 0.0, 0.0, 0.3)),
    (400, 500, (0.6, 0.0, 0.4, 0.0, 0.0)),
    (600, 700, (0.5, 0.5, 0.0, 0.0, 0.0)),
    (800, 900, (0.8, 0.0, 0.0, 0.2, 0.0)),
)
#: §2.4.1: process noise covariance Q = 1e-6 I and measurement covariance R for (q, V, α, h).
B747_NOISE: dict[str, np.ndarray] = {"Q": 1e-6 * np.eye(5), "R": np.diag([1e-5, 1e-4, 1e-5, 1e-3])}
#: IMM transition matrix (2.63), rows = from-model.
B747_TRANSITION = np.array([
    [0.9, 0.025, 0.025, 0.025, 0.025],
    [0.1, 0.9, 0.0, 0.0, 0.0],
    [0.1, 0.0, 0.9, 0.0, 0.0],
    [0.1, 0.0, 0.0, 0.9, 0.0],
    [0.1, 0.0, 0.0, 0.0, 0.9],
])
for _arr in (B747_NOISE["Q"], B747_NOISE["R"], B747_TRANSITION):
    _arr.setflags(write=False)

_A35 = {"corrected": 6.83e-7, "printed": 6.83e-1}


_B_SOURCES = ("substitute", "jsbsim")
_A_SOURCES = ("thesis", "jsbsim")


def _matrices(a35: str, b_source: str = "substitute", a_source: str = "thesis"
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if not isinstance(a35, str) or a35 not in _A35:
        raise ParameterError(f"a35 must be 'corrected' (6.83e-7) or 'printed' (6.83e-1), got {a35!r}")
    validate.choice("b_source (where B and C come from)", b_source, _B_SOURCES)
    validate.choice("a_source (where A comes from)", a_source, _A_SOURCES)
    if a_source == "jsbsim" and a35 != "corrected":
        raise ParameterError("a35 applies to the thesis's A only; use a_source='thesis' with a35='printed'")
    if "jsbsim" in (a_source, b_source):
        from fdikit.plants.b747_jsbsim import b747_jsbsim_matrices

        lin = b747_jsbsim_matrices()
    A = np.array([
        [-5.91e-1, -1.56e-4, -1.36, 0.0, -1.23e-6],
        [-1.47e-1, -8.72e-3, 4.83, -9.81, 5.31e-5],
        [9.80e-1, -1.18e-3, -6.72e-1, 0.0, _A35[a35]],
        [1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, -1.34e2, 1.34e2, 0.0],
    ])
    thrust = np.array([6.7e-8, 1.0 / 3e5, 0.0, 0.0, 0.0])  # SUBSTITUTE, see module docstring
    B = np.column_stack([[-1.2, 0.0, -0.03, 0.0, 0.0], [-2.4, 0.0, -0.06, 0.0, 0.0]] + [thrust] * 4)
    C = np.eye(5)[[0, 1, 2, 4]]
    if b_source == "jsbsim":
        B, C = np.array(lin.B), np.array(lin.C)
    if a_source == "jsbsim":
        A = np.array(lin.A_jsbsim)
    return A, B, C


def b747_longitudinal(model: str = "nominal", a35: str = "corrected", dt: float | None = None, *,
                      b_source: str = "substitute", a_source: str = "thesis") -> FaultModel:
    """One model of Table 2.5 (Hallouzi 2008, §2.4.1) as a :class:`~fdikit.model.FaultModel`.

    Parameters
    ----------
    model : str
        One of :data:`B747_MODEL_NAMES`.
    a35 : {"corrected", "printed"}
        Value of ``A(3, 5)`` (see the module erratum).
    dt : float, optional
        ZOH sample time (the thesis uses 0.01 s); continuous if ``None``.
    b_source : {"substitute", "jsbsim"}, default "substitute"
        B and C: the labelled substitute, or the JSBSim B747 linearisation
        (:func:`~fdikit.plants.b747_jsbsim.b747_jsbsim_matrices`).
    a_source : {"thesis", "jsbsim"}, default "thesis"
        A: the printed (2.56) with ``a35``, or the JSBSim B747's (then ``a35`` must stay "corrected").

    Returns
    -------
    FaultModel
        5 states ``q, V_TAS, alpha, theta, h``, 6 controls ``delta_c, delta_s, T_n1 … T_n4``, 4 outputs
        ``q, V_TAS, alpha, h``; the fault of ``model`` is built into ``Bu`` or ``C`` (no fault inputs).

    Raises
    ------
    ParameterError
        On an unknown model name, ``a35``, ``b_source`` or ``a_source``, or a ``dt`` that is not positive.

    References
    ----------
    Hallouzi 2008, §2.4.1, (2.54)–(2.61), Table 2.5.

    Examples
    --------
    >>> m = b747_longitudinal("alpha_sensor")
    >>> m.C[2].tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0]
    >>> round(float(b747_longitudinal("nominal", b_source="jsbsim").Bu[0, 0]), 2)  # JSBSim q̇ per rad elevator
    -1.14
    """
    if dt is not None:
        dt = validate.positive("dt", dt)
    if not isinstance(model, str) or model not in B747_MODEL_NAMES:
        raise ParameterError(f"unknown B747 model {model!r}; choose one of {', '.join(B747_MODEL_NAMES)}")
    A, B, C = _matrices(a35, b_source, a_source)
    if model == "delta_c_loss":
        B[:, 0] = 0.0
    elif model == "delta_s_loss":
        B[:, 1] = 0.0
    elif model == "V_TAS_sensor":
        C[1, 1] = 0.0
    elif model == "alpha_sensor":
        C[2, 2] = 0.0
    m = FaultModel(A, C, Bu=B, states=B747_STATES, outputs=_OUTPUTS, controls=_CONTROLS)
    return m if dt is None else m.discretize(dt)


def b747_model_set(a35: str = "corrected", dt: float | None = 0.01, *, b_source: str = "substitute",
                   a_source: str = "thesis") -> tuple[FaultModel, ...]:
    """The five models of Table 2.5 in order (ZOH at ``dt = 0.01`` s by default, §2.4.1).

    Parameters
    ----------
    a35 : {"corrected", "printed"}
        Value of ``A(3, 5)`` (see the module erratum).
    dt : float or None, default 0.01
        ZOH sample time [s]; ``None`` gives the continuous models.
    b_source : {"substitute", "jsbsim"}, default "substitute"
        Where B and C come from (:func:`b747_longitudinal`).
    a_source : {"thesis", "jsbsim"}, default "thesis"
        Where A comes from (:func:`b747_longitudinal`).

    Returns
    -------
    tuple of FaultModel
        The models of :data:`B747_MODEL_NAMES`, in that order, built by :func:`b747_longitudinal`.

    Raises
    ------
    ParameterError
        On an unknown ``a35``, ``b_source`` or ``a_source``, or a ``dt`` that is not positive.

    References
    ----------
    Hallouzi 2008, §2.4.1, Table 2.5.

    Examples
    --------
    >>> models = b747_model_set()
    >>> len(models), models[0].dt
    (5, 0.01)
    """
    if dt is not None:
        dt = validate.positive("dt", dt)
    return tuple(b747_longitudinal(name, a35=a35, dt=dt, b_source=b_source, a_source=a_source)
                 for name in B747_MODEL_NAMES)
