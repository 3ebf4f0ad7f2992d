"""B and C of the §2.4.1 B747 example from JSBSim's B747, in place of the lost (2.57)–(2.61): Hallouzi 2008, §2.4.1.

Hallouzi 2008, §2.4.1 prints the longitudinal A (2.56) of the B747 at 600 m and 133.8 m/s but its B and C
((2.57)–(2.61)) are lost in the seed.  :func:`b747_jsbsim_matrices` trims JSBSim's B747 (Berndt 2004;
fdikit's plant, :class:`fdikit.aircraft.JSBSimAircraft`) at that point — level, flaps 0, wings level, JSBSim's
default mass (structure and default fuel, 249 974 kg; the thesis gives neither mass nor flaps for §2.4.1) —
and linearises it numerically in the thesis's state order ``x = [q, V_TAS, α, θ, h]`` with the inputs
``u = [δ_c, δ_s, T_n1, T_n2, T_n3, T_n4]``:

* ``δ_c`` is JSBSim's elevator [rad], ``δ_s`` fdikit's stabiliser [rad].  JSBSim's B747 has no stabiliser;
  fdikit adds one as the elevator's lift and pitching-moment terms scaled by
  :data:`fdikit.aircraft.definition.STABILIZER_GAIN` (= 2), so the δ_s column is the elevator's ×2 — an
  approximation, not JSBSim data.  Both columns come from :func:`fdikit.aircraft.linearize_aircraft`
  (central differences, 10⁻³ rad).
* ``T_ni`` is the thrust of engine *i* [N]: one engine's throttle is moved by ±10⁻³ at a time with every
  engine at the steady state of its throttle (``derivatives(x, positions, throttles)``), and the change of
  ``ẋ`` is divided by that engine's change of thrust.  A newton on one engine accelerates along the body x
  axis (``V̇ = cos α / m``) and pitches the aircraft by its thrust line's offset below the CG (inner engines
  2, 3 sit 24 in lower than the outer ones, so they pitch more); the lateral moments of one engine are
  outside this longitudinal model.
* ``C`` selects ``q, V_TAS, α, h`` (identity rows, text of §2.4.1).

The trim uses the stabiliser with the elevator faired (:func:`fdikit.aircraft.trim_aircraft`), so the
linearisation is around ``δ_c = 0``.  The JSBSim A (``A_jsbsim``) is returned for comparison with the printed
A (2.56): its modes are −0.749 ± 1.135j (short period), −0.0035 ± 0.087j (phugoid) and −0.0010 (height mode),
against −0.634 ± 1.154j, −0.00234 ± 0.0929j and +0.00065 of the corrected (2.56).

The result is cached per process (trim and linearisation take about a second).

References
----------
Hallouzi 2008, §2.4.1, (2.54)–(2.61); Berndt 2004 (JSBSim).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from fdikit import validate

__all__ = ["B747JSBSimMatrices", "b747_jsbsim_matrices"]

#: Indices of the thesis's states ``q, V_TAS, α, θ, h`` in :data:`fdikit.aircraft.plant.STATES`.
_LONGITUDINAL = (1, 3, 4, 7, 9)
_THROTTLE_STEP = 1e-3


@dataclass(frozen=True)
class B747JSBSimMatrices:
    """The longitudinal linearisation of JSBSim's B747 at the §2.4.1 point (arrays are read-only).

    Attributes
    ----------
    A_jsbsim : (5, 5) ndarray
        ``∂ẋ/∂x`` in the state order ``q, V_TAS, α, θ, h`` (SI; for comparison with (2.56)).
    B : (5, 6) ndarray
        ``∂ẋ/∂u`` for ``δ_c`` (elevator) and ``δ_s`` (stabiliser) [per rad] and the four engine thrusts [per N].
    C : (4, 5) ndarray
        Selector of ``q, V_TAS, α, h``.
    trim : AircraftTrim
        The trim (:func:`fdikit.aircraft.trim_aircraft`).
    engine_thrust : (4,) ndarray
        Thrust of each engine at the trim [N].
    engine_gain : (4,) ndarray
        ``∂T_i/∂throttle_i`` of each engine at the trim [N] (the divisor of its column).
    mass : float
        Aircraft mass at the trim [kg].
    notes : str
        How the matrices were obtained and what is approximated.

    Examples
    --------
    >>> lin = b747_jsbsim_matrices()
    >>> lin.B.shape, lin.C.shape, lin.trim.converged
    ((5, 6), (4, 5), True)

    References
    ----------
    Hallouzi 2008, §2.4.1, (2.54)–(2.61).
    """

    A_jsbsim: np.ndarray
    B: np.ndarray
    C: np.ndarray
    trim: object
    engine_thrust: np.ndarray
    engine_gain: np.ndarray
    mass: float
    notes: str


def b747_jsbsim_matrices(altitude: float = 600.0, airspeed: float = 133.8, mass: float | None = None
                         ) -> B747JSBSimMatrices:
    """Trim JSBSim's B747 in level flight and linearise it in the §2.4.1 states and inputs (cached).

    Parameters
    ----------
    altitude : float, default 600.0
        Altitude above sea level [m] (§2.4.1).
    airspeed : float, default 133.8
        True airspeed [m/s] (§2.4.1).
    mass : float or None, default None
        Aircraft mass [kg]; ``None`` keeps JSBSim's default (249 974 kg: structure and default fuel).

    Returns
    -------
    B747JSBSimMatrices
        ``A_jsbsim``, ``B``, ``C``, the trim and notes; the same (read-only) object for the same arguments.

    Raises
    ------
    ParameterError
        For a negative altitude or a non-positive airspeed or mass.
    DesignError
        If the aircraft does not trim there.

    References
    ----------
    Hallouzi 2008, §2.4.1, (2.54)–(2.61); Berndt 2004.

    Examples
    --------
    >>> lin = b747_jsbsim_matrices()
    >>> [round(float(v), 2) for v in lin.B[0, :2]]  # q̇ per rad of elevator and stabiliser [1/s²]
    [-1.14, -2.28]
    >>> round(float(lin.B[1, 2] * lin.mass / np.cos(lin.trim.x[4])), 6)  # V̇ per N of one engine: cos α / m
    1.0
    """
    altitude = validate.non_negative("altitude", altitude)
    airspeed = validate.positive("airspeed", airspeed)
    if mass is not None:
        mass = validate.positive("mass", mass)
    return _matrices(altitude, airspeed, mass)


@functools.lru_cache(maxsize=8)
def _matrices(altitude: float, airspeed: float, mass: float | None) -> B747JSBSimMatrices:
    from fdikit.aircraft import FlightCondition, JSBSimAircraft, linearize_aircraft, trim_aircraft

    ac = JSBSimAircraft("B747")
    trim = trim_aircraft(ac, FlightCondition(altitude=altitude, airspeed=airspeed, flaps=0.0, mass=mass))
    lin = linearize_aircraft(ac, trim)
    idx = list(_LONGITUDINAL)
    A = lin.model.A[np.ix_(idx, idx)]
    controls = lin.model.controls
    B_surf = lin.model.B[np.ix_(idx, [controls.index("elevator"), controls.index("stabilizer")])]
    ac.set_state(trim.x)
    ac.set_throttles(trim.throttle)
    snap = ac.snapshot()
    n = ac.engines
    thrust0 = ac.thrust()
    B_eng, gain = np.empty((5, n)), np.empty(n)
    for i in range(n):
        f, T = [], []
        for sign in (1.0, -1.0):
            thr = np.full(n, trim.throttle)
            thr[i] += sign * _THROTTLE_STEP
            f.append(ac.derivatives(trim.x, trim.positions, thr))
            T.append(ac.thrust()[i])
            ac.restore(snap)
        gain[i] = (T[0] - T[1]) / (2 * _THROTTLE_STEP)
        B_eng[:, i] = (f[0] - f[1])[idx] / (T[0] - T[1])
    B = np.hstack([B_surf, B_eng])
    C = np.eye(5)[[0, 1, 2, 4]]
    notes = (f"JSBSim B747 trimmed level at {altitude:g} m, {airspeed:g} m/s TAS, flaps 0, mass {ac.mass:.0f} kg "
             f"({'JSBSim default' if mass is None else 'given'}); stabiliser {trim.positions['stabilizer']:.4f} rad, "
             f"elevator 0, throttle {trim.throttle:.4f}, α = θ = {trim.x[4]:.4f} rad. δ_c = elevator; δ_s = fdikit's "
             "stabiliser (elevator terms ×2, an approximation). Thrust columns per N of one engine, engines at "
             "steady state. States q, V_TAS, α, θ, h; C selects q, V_TAS, α, h.")
    out = B747JSBSimMatrices(A_jsbsim=A, B=B, C=C, trim=trim, engine_thrust=thrust0, engine_gain=gain,
                             mass=float(ac.mass), notes=notes)
    for arr in (A, B, C, thrust0, gain):
        arr.setflags(write=False)
    return out
