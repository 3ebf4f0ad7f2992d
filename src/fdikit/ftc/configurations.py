"""SPC input configurations (Hallouzi 2008, Table 6.1) on JSBSim's B747, their limits and linear models.

The thesis's SPC drives groups of the B747's 29 controls; each configuration uses the groups the fault
leaves working (§6.4). JSBSim's B747 (:mod:`fdikit.aircraft`) has one aileron, elevator, stabilizer and
rudder channel and four engines, and **no spoilers**, so the configurations are Table 6.1 without them:

=============  ==========================================  =====================================
fault          Table 6.1                                    here
=============  ==========================================  =====================================
none           ailerons, elevators, rudders, engines (m=4)  aileron, elevator, rudder, engines
elevator       ailerons, stabilizer, rudders, engines       aileron, stabilizer, rudder, engines
rudder         ailerons, spoilers, elevators, engines       aileron, elevator, engines 1–2,
               left, engines right (m = 5)                   engines 3–4 (m = 4: no spoilers)
unanticipated  all seven groups (m = 7)                     aileron, elevator, stabilizer, rudder,
                                                            engines 1–2, engines 3–4 (m = 6)
=============  ==========================================  =====================================

An engine input moves the throttles of its engines together (symmetrically, as in §6.4); controls a
configuration does not drive stay at the trim. The SPC works on deviations from a trim in the units the
thesis plots: surfaces in degrees, throttles in percent, and the Table 6.2 outputs ``φ, θ, ψ`` [deg],
``V_TAS`` [m/s], ``α, β`` [deg], ``h`` [m] (:data:`SPC_OUTPUTS`).

Limits: the surfaces' App. A travel and rate limits (:data:`fdikit.aircraft.B747_LIMITS`) less the trim;
the throttles 0–100 % and, as the thesis gives no engine rate, 10 %/s (about the spool-up of a
high-bypass engine from approach power).

The linear model of a configuration (:func:`configuration_model`) is the aircraft's rigid-body ``A``
(:func:`fdikit.aircraft.linearize_aircraft`) with one ``B`` column per configuration input, each a
central difference of JSBSim's state derivative (engines at their steady state, as the thrust column of
:mod:`fdikit.aircraft.linearize`) — the thesis's "open-loop simulation of the fault model" that
initialises the predictor (§6.4) runs on it (:func:`identification_data`). Written here because no
library knows the B747's control groups.

References
----------
Hallouzi 2008, §6.4, Tables 6.1–6.2; App. A, Table A.2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["SPC_OUTPUTS", "TABLE_6_2_NOISE", "ENGINE_RATE", "TABLE_6_1", "InputConfiguration",
           "input_configuration", "configuration_model", "identification_data"]

#: The SPC outputs of Table 6.2 (states of :data:`fdikit.aircraft.plant.STATES`) and their unit factors from SI.
SPC_OUTPUTS = (("roll", 180 / np.pi), ("pitch", 180 / np.pi), ("heading", 180 / np.pi), ("true_airspeed", 1.0),
               ("alpha", 180 / np.pi), ("beta", 180 / np.pi), ("altitude", 1.0))
#: Table 6.2 sensor-noise standard deviations, in the SPC units (deg, m/s, m).
TABLE_6_2_NOISE = np.array([1.73e-4, 1.73e-4, 1.73e-4, 0.1, 1.73e-3, 1.73e-3, 0.1])
#: Throttle rate limit [%/s] (not given by the thesis; see the module docstring).
ENGINE_RATE = 10.0
_ENGINES = {"engines": [0, 1, 2, 3], "engines_left": [0, 1], "engines_right": [2, 3]}   # 0-based indices
_SURFACES = ("aileron", "elevator", "stabilizer", "rudder")
#: Table 6.1 on JSBSim's B747 (no spoilers): configuration → its SPC inputs.
TABLE_6_1 = {
    "nominal": ("aileron", "elevator", "rudder", "engines"),
    "elevator": ("aileron", "stabilizer", "rudder", "engines"),
    "rudder": ("aileron", "elevator", "engines_left", "engines_right"),
    "unanticipated": ("aileron", "elevator", "stabilizer", "rudder", "engines_left", "engines_right"),
}


@dataclass(frozen=True)
class InputConfiguration:
    """One row of Table 6.1: the SPC inputs, in degrees (surfaces) and percent (throttle groups).

    Attributes
    ----------
    name : str
    inputs : tuple of str
        Of ``aileron, elevator, stabilizer, rudder`` and ``engines`` (all four), ``engines_left`` (1–2),
        ``engines_right`` (3–4).

    Examples
    --------
    >>> cfg = input_configuration("rudder")
    >>> cfg.commands([1.0, 0.0, 5.0, -5.0], {"aileron": 0.0, "elevator": 0.0}, [0.5] * 4)["throttle_1"]
    0.55

    References
    ----------
    Hallouzi 2008, §6.4, Table 6.1.
    """

    name: str
    inputs: tuple

    @property
    def m(self) -> int:
        """Number of SPC inputs."""
        return len(self.inputs)

    def commands(self, u, positions, throttles) -> dict:
        """The aircraft commands (:meth:`fdikit.aircraft.JSBSimAircraft.set_inputs`) for the SPC input ``u``.

        Parameters
        ----------
        u : array_like, shape (m,)
            Deviations from the trim: surfaces [deg], throttle groups [%].
        positions : mapping
            Trim surface positions [rad] (at least those the configuration drives).
        throttles : array_like, shape (4,)
            Trim throttle of each engine (0…1).

        Returns
        -------
        dict
            Surface commands [rad] of the driven surfaces and ``throttle_1 … throttle_4``.

        Raises
        ------
        ParameterError
            If ``u`` does not have one entry per input.
        """
        u = validate.as_vector("u", u, size=self.m)
        thr = np.array(throttles, dtype=float)
        out = {}
        for name, v in zip(self.inputs, u, strict=True):
            if name in _ENGINES:
                thr[_ENGINES[name]] += v / 100.0
            else:
                out[name] = float(positions[name] + np.radians(v))
        out.update({f"throttle_{i + 1}": float(t) for i, t in enumerate(thr)})
        return out

    def vector(self, positions, throttles, reference_positions, reference_throttles) -> np.ndarray:
        """The SPC input (deviation from the reference trim) that the given surfaces and throttles are.

        Parameters
        ----------
        positions, reference_positions : mapping
            Surface positions [rad].
        throttles, reference_throttles : array_like, shape (4,)
            Throttles (0…1); an engine group's input is the mean change of its engines.

        Returns
        -------
        ndarray, shape (m,)
        """
        thr = np.asarray(throttles, dtype=float) - np.asarray(reference_throttles, dtype=float)
        return np.array([100.0 * thr[_ENGINES[n]].mean() if n in _ENGINES
                         else np.degrees(positions[n] - reference_positions[n]) for n in self.inputs])

    def limits(self, positions, throttles, dt: float, surface_limits=None):
        """Input and rate limits of the SPC QP around a trim.

        Parameters
        ----------
        positions : mapping
            Trim surface positions [rad].
        throttles : array_like, shape (4,)
            Trim throttles (0…1).
        dt : float
            SPC sample time [s] (the rate limits are per sample).
        surface_limits : mapping, optional
            Surface → :class:`fdikit.aircraft.actuators.SurfaceLimits` (default App. A).

        Returns
        -------
        SpcLimits
        """
        from fdikit.aircraft import B747_LIMITS
        from fdikit.spc.law import SpcLimits

        lims = surface_limits or B747_LIMITS
        dt = validate.positive("dt", dt)
        lo, hi, rate = [], [], []
        for n in self.inputs:
            if n in _ENGINES:
                t = float(np.mean(np.asarray(throttles, dtype=float)[_ENGINES[n]]))
                lo.append(-100.0 * t)
                hi.append(100.0 * (1.0 - t))
                rate.append(ENGINE_RATE * dt)
            else:
                s = lims[n]
                lo.append(np.degrees(s.lower - positions[n]))
                hi.append(np.degrees(s.upper - positions[n]))
                rate.append(np.degrees(min(s.rate_down, s.rate_up)) * dt)
        rate = np.array(rate)
        return SpcLimits(u_min=np.array(lo), u_max=np.array(hi), du_min=-rate, du_max=rate)


def input_configuration(name: str) -> InputConfiguration:
    """The Table 6.1 configuration for a fault group (``"nominal"``, ``"elevator"``, ``"rudder"``, ``"unanticipated"``).

    Parameters
    ----------
    name : str

    Returns
    -------
    InputConfiguration

    Raises
    ------
    ParameterError
        For an unknown configuration.

    Examples
    --------
    >>> input_configuration("elevator").inputs
    ('aileron', 'stabilizer', 'rudder', 'engines')

    References
    ----------
    Hallouzi 2008, §6.4, Table 6.1.
    """
    validate.choice("configuration", name, sorted(TABLE_6_1))
    return InputConfiguration(name, TABLE_6_1[name])


def configuration_model(aircraft, trim, configuration: InputConfiguration, dt: float):
    """Discrete model ``x⁺ = A x + B u``, ``y = C x`` of the aircraft at ``trim`` with the configuration's inputs.

    Parameters
    ----------
    aircraft : JSBSimAircraft
        The aircraft the trim belongs to (left at the trim).
    trim : AircraftTrim
        From :func:`fdikit.aircraft.trim_aircraft` (a fault model's trim for a fault configuration).
    configuration : InputConfiguration
    dt : float
        Sample time [s] (zero-order hold, :func:`scipy.linalg.expm`).

    Returns
    -------
    A : ndarray, shape (10, 10)
        On the deviations of :data:`fdikit.aircraft.plant.STATES` (SI).
    B : ndarray, shape (10, m)
        Per degree (surfaces) or percent (throttle groups).
    C : ndarray, shape (7, 10)
        The :data:`SPC_OUTPUTS` in their units.

    Raises
    ------
    ParameterError
        If the configuration drives a surface the aircraft does not have, or one the trim locks.

    Examples
    --------
    >>> from fdikit.aircraft import JSBSimAircraft, trim_aircraft, HALLOUZI_POINT
    >>> ac = JSBSimAircraft("B747", dt=0.01)
    >>> A, B, C = configuration_model(ac, trim_aircraft(ac, HALLOUZI_POINT), input_configuration("rudder"), 0.1)
    >>> bool(B[2, 2] * B[2, 3] < 0)   # left and right engines yaw the aircraft opposite ways
    True

    References
    ----------
    Hallouzi 2008, §6.4; §4.2, (4.1)–(4.2).
    """
    import scipy.linalg as sla

    from fdikit.aircraft import linearize_aircraft
    from fdikit.aircraft.plant import STATES

    dt = validate.positive("dt", dt)
    bad = [n for n in configuration.inputs if n in _SURFACES and (n not in aircraft.surfaces or n in trim.locked)]
    if bad:
        raise ParameterError(f"configuration {configuration.name!r} drives {bad[0]!r}, which the aircraft does not "
                             f"have or the trim locks; pick the configuration of the fault (Table 6.1).")
    A = linearize_aircraft(aircraft, trim).model.A
    snap = aircraft.snapshot()
    x0 = np.asarray(trim.x, dtype=float)

    def f(name: str, d: float) -> np.ndarray:
        pos, thr = dict(trim.positions), np.full(aircraft.engines, float(trim.throttle))
        if name in _ENGINES:
            thr[_ENGINES[name]] += d / 100.0
        else:
            pos[name] += np.radians(d)
        out = aircraft.derivatives(x0, pos, thr)
        aircraft.restore(snap)
        return out

    step = 0.5   # deg or %: the columns' central differences
    Bc = np.column_stack([(f(n, step) - f(n, -step)) / (2 * step) for n in configuration.inputs])
    n, m = A.shape[0], Bc.shape[1]
    M = sla.expm(np.block([[A, Bc], [np.zeros((m, n + m))]]) * dt)
    C = np.zeros((len(SPC_OUTPUTS), n))
    for i, (name, k) in enumerate(SPC_OUTPUTS):
        C[i, STATES.index(name)] = k
    return M[:n, :n], M[:n, n:], C


def identification_data(A, B, C, samples: int, rng: np.random.Generator, *, input_std,
                        noise_std=TABLE_6_2_NOISE) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop data of a linear model under white inputs, with sensor noise (the §6.4 initialisation data).

    Parameters
    ----------
    A, B, C : ndarray
        From :func:`configuration_model`.
    samples : int
        Number of samples (the thesis: ``j = 1000`` columns, 100 s at 10 Hz, plus ``p``).
    rng : numpy.random.Generator
    input_std : float or array_like
        Standard deviation of each white input (deg, %).
    noise_std : array_like, optional
        Output noise standard deviations (default Table 6.2).

    Returns
    -------
    u : ndarray, shape (samples, m)
    y : ndarray, shape (samples, 7)

    Examples
    --------
    >>> u, y = identification_data(np.eye(1) * 0.9, np.ones((1, 1)), np.ones((1, 1)), 5,
    ...                            np.random.default_rng(0), input_std=1.0, noise_std=[0.0])
    >>> bool(y[1, 0] == u[0, 0])
    True

    References
    ----------
    Hallouzi 2008, §6.4, §6.5.
    """
    samples = validate.integer("samples", samples, minimum=1)
    u = np.asarray(input_std, dtype=float) * rng.standard_normal((samples, B.shape[1]))
    x = np.zeros(A.shape[0])
    y = np.empty((samples, C.shape[0]))
    for k in range(samples):
        y[k] = C @ x
        x = A @ x + B @ u[k]
    return u, y + np.asarray(noise_std, dtype=float) * rng.standard_normal(y.shape)
