"""Numerical linearisation of a JSBSim aircraft around a trim, with trim offsets and locked surfaces.

The model is Hallouzi's 10-state rigid body (Table 4.1, in SI units) with the inputs the aircraft
has of ``aileron, elevator, stabilizer, rudder`` [rad] (Table 4.1 without the spoilers, which
JSBSim's B747 does not have) and the total ``thrust`` [N] (Hallouzi's ``δ_T``; the
engines are taken at their steady state, so the thrust column is ``(∂f/∂throttle)/(∂T/∂throttle)``
with both derivatives from JSBSim's engine model)::

    ẋ = f° + A (x − x°) + B (u − u°),   y = C x

``f° = f(x°, u°)`` is zero at an exact trim; it is kept because a locked-surface model's best trim
may not be an equilibrium (then the model drifts as the aircraft would). Every derivative is a
central difference with a fixed step (10⁻⁶ relative for states, 10⁻³ rad or throttle for inputs) by
:func:`fdikit.nonlinear.linearize.jacobian`; the engines keep their spool speeds in the state
columns (they cannot jump) and reach the new steady state in the throttle column. A locked
surface's column of ``B`` is zero (Hallouzi §4.2: "the corresponding B column is removed" — kept as
a zero column so every model of a set has the same inputs).

References
----------
Hallouzi 2008, §4.2, §4.3.1, Table 4.1, (4.1)–(4.2).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import ParameterError

__all__ = ["INPUTS", "AircraftLinearization", "linearize_aircraft"]

#: The inputs of the linear models, in order (those the aircraft has).
INPUTS = ("aileron", "elevator", "stabilizer", "rudder", "thrust")



@dataclass(frozen=True)
class AircraftLinearization:
    """A linear model of the aircraft around a trim, with its offsets (Hallouzi (4.1)–(4.2)).

    Attributes
    ----------
    model : FaultModel
        Continuous ``ẋ = A x + B u``, ``y = C x`` in deviation-free coordinates (``x``, ``u`` absolute;
        the offsets below make it affine).
    x0, u0 : ndarray
        The trim state ``x°`` and input ``u°``.
    f0 : ndarray
        ``f(x°, u°)`` (zero at an exact equilibrium).
    trim : AircraftTrim
    thrust_slope : float
        ``∂T/∂throttle`` [N] of all engines together at the trim (steady state), to turn a thrust
        command into a throttle.

    Examples
    --------
    >>> from fdikit.aircraft import JSBSimAircraft, trim_aircraft, HALLOUZI_POINT
    >>> ac = JSBSimAircraft("B747")
    >>> lin = linearize_aircraft(ac, trim_aircraft(ac, HALLOUZI_POINT, {"rudder": 0.2}, require=False))
    >>> bool(abs(lin.f0).max() > 0), lin.model.b("u")[:, 3].tolist() == [0.0] * 10  # off equilibrium, rudder column 0
    (True, True)
    """

    model: object
    x0: np.ndarray
    u0: np.ndarray
    f0: np.ndarray
    trim: object
    thrust_slope: float = float("nan")

    @property
    def offset(self) -> np.ndarray:
        """The constant term ``c = f° − A x° − B u°`` of ``ẋ = A x + B u + c``.

        Returns
        -------
        ndarray
        """
        m = self.model
        return self.f0 - m.A @ self.x0 - m.B @ self.u0


def linearize_aircraft(aircraft, trim, outputs: Sequence[str] | None = None) -> AircraftLinearization:
    """Linearise a trimmed aircraft (:func:`fdikit.aircraft.trim.trim_aircraft`) numerically.

    Parameters
    ----------
    aircraft : JSBSimAircraft
        The aircraft the trim belongs to (it is left at the trim afterwards).
    trim : AircraftTrim
    outputs : sequence of str, optional
        Measured states (of :data:`fdikit.aircraft.plant.STATES`); all ten when omitted.

    Returns
    -------
    AircraftLinearization

    Raises
    ------
    ParameterError
        For an output that is not a state.

    Examples
    --------
    >>> from fdikit.aircraft import JSBSimAircraft, trim_aircraft, HALLOUZI_POINT
    >>> ac = JSBSimAircraft("B747")
    >>> lin = linearize_aircraft(ac, trim_aircraft(ac, HALLOUZI_POINT))
    >>> lin.model.controls, lin.model.A.shape
    (('aileron', 'elevator', 'stabilizer', 'rudder', 'thrust'), (10, 10))
    """
    from fdikit.aircraft.plant import STATES
    from fdikit.model import FaultModel
    from fdikit.nonlinear.linearize import jacobian

    outputs = tuple(STATES if outputs is None else outputs)
    bad = [o for o in outputs if o not in STATES]
    if bad:
        raise ParameterError(f"outputs {bad} are not states; measured states are chosen from {', '.join(STATES)}.")
    inputs = [s for s in INPUTS if s == "thrust" or s in aircraft.surfaces]
    surfaces = [s for s in inputs if s != "thrust"]
    aircraft.set_state(trim.x)
    aircraft.set_throttles(trim.throttle)
    snap = aircraft.snapshot()
    base = dict(trim.positions)
    x0 = np.asarray(trim.x, dtype=float)

    def thrust_at(thr: float) -> float:
        aircraft.set_state(x0)
        aircraft.set_throttles(thr)
        return float(aircraft.thrust().sum())

    def f(z):
        x, du = z[:10], z[10:]
        pos = {**base, **{s: base[s] + d for s, d in zip(surfaces, du, strict=False)}}
        # the engines keep their spool speeds unless the throttle moves (then: its steady state)
        return aircraft.derivatives(x, pos, trim.throttle + du[-1] if du[-1] else None)

    z0 = np.concatenate([x0, np.zeros(len(inputs))])
    steps = np.concatenate([np.maximum(1e-6 * np.abs(x0), 1e-6), np.full(len(inputs), 1e-3)])
    f0 = f(z0)
    J = np.empty((10, z0.size))
    for j in range(z0.size):  # one column at a time: the throttle column re-spools the engines
        J[:, j] = jacobian(lambda zj, j=j: f(np.concatenate([z0[:j], zj, z0[j + 1:]])), z0[j:j + 1],
                           step=steps[j:j + 1]).J[:, 0]
        aircraft.restore(snap)
    dT = (thrust_at(trim.throttle + 1e-3) - thrust_at(trim.throttle - 1e-3)) / 2e-3
    A, B = J[:, :10], J[:, 10:].copy()
    B[:, -1] /= dT
    for j, s in enumerate(surfaces):
        if s in trim.locked:
            B[:, j] = 0.0
    aircraft.restore(snap)
    C = np.eye(10)[[STATES.index(o) for o in outputs]]
    model = FaultModel(A, C, Bu=B, states=STATES, outputs=outputs, controls=inputs)
    u0 = np.array([*(base[s] for s in surfaces), trim.thrust])
    return AircraftLinearization(model=model, x0=x0, u0=u0, f0=f0, trim=trim, thrust_slope=float(dT))
