"""A JSBSim aircraft as a plant: named SI inputs and sensors, fixed-rate steps, snapshots, turbulence.

The plant wraps one ``jsbsim.FGFDMExec`` on a definition prepared by
:func:`fdikit.aircraft.definition.prepare_aircraft`, so that every surface position is the one the
actuator model (:class:`fdikit.aircraft.actuators.ActuatorBank`) computes — faults included.
Units are SI throughout (rad, rad/s, m, m/s, kg, N); JSBSim's feet, knots and pounds stay inside.

The rigid-body state used for trim and linearisation is Hallouzi's (Table 4.1, here in SI)::

    x = [p, q, r, V_TAS, α, β, φ, θ, ψ, h]

and :meth:`JSBSimAircraft.derivatives` evaluates ``ẋ = f(x, u)`` at a state written as JSBSim's
initial condition (``run_ic``: every model runs once with the integration suspended), with the
engines at the steady state of their throttle.

References
----------
Berndt 2004 (JSBSim); Hallouzi 2008, §4.3.1 and Table 4.1 (the states), App. A (Table A.1).
"""

from __future__ import annotations

import shutil
import weakref
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["FT", "KT", "LBF", "LBM", "SENSORS", "STATES", "AircraftSnapshot", "JSBSimAircraft"]

FT = 0.3048  #: m per ft
KT = 1852.0 / 3600.0  #: m/s per knot
LBF = 4.4482216152605  #: N per lbf
LBM = 0.45359237  #: kg per lb

#: The rigid-body state (Hallouzi 2008, Table 4.1, in SI units).
STATES = ("roll_rate", "pitch_rate", "yaw_rate", "true_airspeed", "alpha", "beta", "roll", "pitch", "heading",
          "altitude")

#: The sensors: JSBSim property and factor to SI.
_SENSOR_PROPS = {
    "roll_rate": ("velocities/p-rad_sec", 1.0),
    "pitch_rate": ("velocities/q-rad_sec", 1.0),
    "yaw_rate": ("velocities/r-rad_sec", 1.0),
    "true_airspeed": ("velocities/vt-fps", FT),
    "alpha": ("aero/alpha-rad", 1.0),
    "beta": ("aero/beta-rad", 1.0),
    "roll": ("attitude/phi-rad", 1.0),
    "pitch": ("attitude/theta-rad", 1.0),
    "heading": ("attitude/psi-rad", 1.0),
    "altitude": ("position/h-sl-ft", FT),
    "calibrated_airspeed": ("velocities/vc-fps", FT),
    "vertical_speed": ("velocities/h-dot-fps", FT),
    "flight_path_angle": ("flight-path/gamma-rad", 1.0),
    "load_factor_x": ("accelerations/Nx", 1.0),
    "load_factor_y": ("accelerations/Ny", 1.0),
    "load_factor_z": ("accelerations/Nz", 1.0),
}
#: Sensor names, in the order of :meth:`JSBSimAircraft.outputs`.
SENSORS = tuple(_SENSOR_PROPS)

_IC_BODY = ("ic/u-fps", "ic/v-fps", "ic/w-fps", "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec", "ic/phi-rad",
            "ic/theta-rad", "ic/psi-true-rad", "ic/h-sl-ft", "ic/lat-geod-rad", "ic/long-gc-rad")
_NOW_BODY = ("velocities/u-fps", "velocities/v-fps", "velocities/w-fps", "velocities/p-rad_sec",
             "velocities/q-rad_sec", "velocities/r-rad_sec", "attitude/phi-rad", "attitude/theta-rad",
             "attitude/psi-rad", "position/h-sl-ft", "position/lat-geod-rad", "position/long-gc-rad")


@dataclass(frozen=True)
class AircraftSnapshot:
    """Everything needed to put the aircraft back where it was (:meth:`JSBSimAircraft.restore`).

    Attributes
    ----------
    time : float
        Simulation time [s].
    body : ndarray
        ``u, v, w`` [ft/s], ``p, q, r`` [rad/s], ``φ, θ, ψ`` [rad], ``h`` [ft], latitude, longitude [rad]
        (JSBSim's own units, restored bit for bit).
    engines : ndarray
        Turbine spool speeds ``N1, N2`` [%] (piston engines keep their rpm on restore).
    properties : dict
        Surface positions, override flags, commands, fuel and payload.
    actuators : object
        The actuator bank's state (:meth:`ActuatorBank.snapshot`).
    commands : dict
        The control commands (:attr:`JSBSimAircraft.commands`).

    Examples
    --------
    >>> ac = JSBSimAircraft("B747")
    >>> snap = ac.snapshot()
    >>> ac.step(10)
    >>> ac.restore(snap)
    >>> ac.time == snap.time
    True
    """

    time: float
    body: np.ndarray
    engines: np.ndarray
    properties: dict = field(default_factory=dict)
    actuators: object = None
    commands: dict = field(default_factory=dict)


def _quiet_exec(jsbsim, root: str):
    """A new ``FGFDMExec`` without JSBSim's start-up banner (its level comes from ``JSBSIM_DEBUG`` at construction)."""
    import os

    before = os.environ.get("JSBSIM_DEBUG")
    os.environ["JSBSIM_DEBUG"] = before if before is not None else "0"
    try:
        fdm = jsbsim.FGFDMExec(root)
    finally:
        if before is None:
            del os.environ["JSBSIM_DEBUG"]
    fdm.set_debug_level(int(os.environ.get("JSBSIM_DEBUG", "0")))
    return fdm


class JSBSimAircraft:
    """A JSBSim aircraft with fdikit's surface actuators, named SI signals and fixed-rate stepping.

    Parameters
    ----------
    aircraft : str, optional
        A JSBSim aircraft name (default ``"B747"``); :func:`fdikit.aircraft.jsbsim_aircraft` lists them.
    dt : float, optional
        The step [s] (default 1/120: 120 Hz, JSBSim's usual rate).
    limits : mapping, optional
        Surface → :class:`fdikit.aircraft.actuators.SurfaceLimits` for the surfaces to change; the others
        keep :func:`fdikit.aircraft.actuators.default_limits` (Hallouzi App. A for the B747).
    folder : str, optional
        Where to build the prepared aircraft root (a temporary directory when omitted).

    Attributes
    ----------
    fdm : jsbsim.FGFDMExec
        The JSBSim executive (for properties fdikit does not wrap).
    actuators : ActuatorBank
        The surface actuators (limits, rates, faults).
    controls : tuple of str
        ``elevator, aileron, rudder, flap`` [rad] (those the aircraft has), ``pitch_trim`` [rad, added to
        the elevator command], ``throttle_1 … throttle_n`` [0…1], ``gear`` [0 up … 1 down].

    Raises
    ------
    ParameterError
        For an unknown aircraft or a non-positive step.

    Examples
    --------
    >>> ac = JSBSimAircraft("B747")
    >>> ac.controls[:3], ac.engines
    (('elevator', 'aileron', 'rudder'), 4)
    """

    def __init__(self, aircraft: str = "B747", dt: float = 1.0 / 120.0, *, limits=None, folder=None) -> None:
        import jsbsim

        from fdikit.aircraft.actuators import ActuatorBank, default_limits
        from fdikit.aircraft.definition import prepare_aircraft

        self.dt = validate.positive("dt", dt)
        self.definition = prepare_aircraft(aircraft, folder)
        if folder is None:  # the private root goes with the plant
            weakref.finalize(self, shutil.rmtree, self.definition.root, ignore_errors=True)
        self.name = aircraft
        self.fdm = _quiet_exec(jsbsim, self.definition.root)
        if not self.fdm.load_model(aircraft):
            raise DataError(f"JSBSim could not load the aircraft {aircraft!r}.")
        self.fdm.set_dt(self.dt)
        self.engines = self.definition.engines
        self.surfaces = self.definition.surfaces
        self.actuators = ActuatorBank({**default_limits(self.definition), **(limits or {})})
        self.controls = (*self.surfaces, "pitch_trim", *(f"throttle_{i + 1}" for i in range(self.engines)), "gear")
        self.commands = dict.fromkeys(self.controls, 0.0)
        self.sensor_faults: tuple = ()
        self._engine_faults: tuple = ()
        self._cutoff: dict = {}
        self.fdm["ic/h-sl-ft"] = 10000.0
        self.fdm["ic/vt-kts"] = 200.0
        self.fdm.run_ic()
        self.fdm["gear/gear-cmd-norm"] = 0.0
        for s in (*self.surfaces, "gear") if self.definition.gear else self.surfaces:
            self.fdm[f"fdikit/{s}-override"] = 1.0
        self.fdm["propulsion/set-running"] = -1
        tanks = [line.split()[0] for line in self.fdm.query_property_catalog("contents-lbs").splitlines()
                 if line.startswith("propulsion/tank")]  # JSBSim lists tank 0 without its index
        self._mass_properties = ([t.replace("propulsion/tank/", "propulsion/tank[0]/") for t in tanks]
                                 + [f"inertia/pointmass-weight-lbs[{self.definition.payload}]"])
        catalog = self.fdm.query_property_catalog("propulsion/engine")
        turbine = "propulsion/engine/n1 " in catalog or "propulsion/engine[0]/n1 " in catalog
        self._spools = [f"propulsion/engine[{i}]/{n}" for i in range(self.engines * turbine) for n in ("n1", "n2")]

    # ---------------------------------------------------------------- signals
    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return float(self.fdm["simulation/sim-time-sec"])

    @property
    def mass(self) -> float:
        """Total mass [kg] (structure, payload and fuel)."""
        return float(self.fdm["inertia/weight-lbs"]) * LBM

    def outputs(self) -> np.ndarray:
        """The sensors (:data:`SENSORS`) in SI units, noise-free (heading wrapped to [−π, π)).

        Returns
        -------
        ndarray
            One value per sensor.
        """
        f = self.fdm
        y = np.array([f[p] * k for p, k in _SENSOR_PROPS.values()])
        y[8] = (y[8] + np.pi) % (2 * np.pi) - np.pi  # heading in [−π, π)
        return y

    def state(self) -> np.ndarray:
        """The rigid-body state :data:`STATES` (the first ten sensors).

        Returns
        -------
        ndarray
        """
        return self.outputs()[:10]

    def thrust(self) -> np.ndarray:
        """Thrust per engine [N].

        Returns
        -------
        ndarray
        """
        return np.array([self.fdm[f"propulsion/engine[{i}]/thrust-lbs"] * LBF for i in range(self.engines)])

    # ---------------------------------------------------------------- inputs
    def set_inputs(self, **commands: float) -> None:
        """Set control commands by name (:attr:`controls`); unnamed ones keep their value.

        Parameters
        ----------
        **commands : float
            Surface commands [rad] (the actuators move the surfaces), ``pitch_trim`` [rad],
            ``throttle_<i>`` [0…1], ``gear`` [0…1].

        Raises
        ------
        ParameterError
            For an unknown control name or a non-finite value.
        """
        for name, value in commands.items():
            if name not in self.commands:
                raise ParameterError(f"{self.name} has no control {name!r}; "
                                     f"its controls are {', '.join(self.controls)}.")
            self.commands[name] = validate.number(name, value)

    def inject(self, scenario) -> None:
        """Set the faults of a run (replacing earlier ones).

        Surface faults go to the actuators, :class:`~fdikit.actuator_faults.EngineFailure` on
        ``throttle_<i>`` cuts engine *i* off at its onset (JSBSim's thrust is then zero), other throttle
        faults change the throttle command, and sensor faults are applied by :meth:`measure`.

        Parameters
        ----------
        scenario : FaultScenario or iterable of Fault
            Targets are sensors (:data:`SENSORS`) or controls (:attr:`controls`).

        Raises
        ------
        ParameterError
            For a target the aircraft does not have.
        """
        from fdikit.actuator_faults import EngineFailure
        from fdikit.faults import FaultScenario

        faults = scenario if isinstance(scenario, FaultScenario) else FaultScenario(scenario)
        faults = faults.resolve(SENSORS, self.controls).faults
        self.sensor_faults = tuple(f for f in faults if f.location == "sensor")
        self.actuators.inject(f for f in faults if f.location == "actuator" and f.target in self.surfaces)
        self._engine_faults = tuple(f for f in faults if f.location == "actuator" and f.target not in self.surfaces)
        bad = [f for f in self._engine_faults if not f.target.startswith("throttle_")]
        if bad:
            raise ParameterError(f"fault on {bad[0].target!r}: only surfaces, throttles and sensors take faults.")
        self._cutoff = {int(f.target.split("_")[1]) - 1: f for f in self._engine_faults if isinstance(f, EngineFailure)}

    def measure(self, noise_std=None, rng: np.random.Generator | None = None) -> np.ndarray:
        """The sensors (:meth:`outputs`) with the sensor faults of :meth:`inject` and noise.

        Parameters
        ----------
        noise_std : float or array_like, optional
            Standard deviation per sensor (SI units); none when omitted.
        rng : numpy.random.Generator, optional
            Source of the noise (needed with ``noise_std``).

        Returns
        -------
        ndarray
        """
        y = self.outputs()
        if noise_std is not None:
            y = y + np.asarray(noise_std, dtype=float) * rng.standard_normal(y.size)
        t = np.array([self.time])
        for f in self.sensor_faults:
            i = SENSORS.index(f.target)
            y[i] = f.apply(t, y[i:i + 1], rng)[0]
        return y

    def _write_commands(self) -> None:
        f = self.fdm
        t = np.array([self.time])
        for i in range(self.engines):
            cmd = self.commands[f"throttle_{i + 1}"]
            for fault in self._engine_faults:
                if fault.target == f"throttle_{i + 1}":
                    cmd = float(fault.apply(t, np.array([cmd]))[0])
            f[f"fcs/throttle-cmd-norm[{i}]"] = min(max(cmd, 0.0), 1.0)
            if i in self._cutoff and self._cutoff[i].active(t)[0]:
                f[f"propulsion/engine[{i}]/set-running"] = 0
        f["gear/gear-cmd-norm"] = min(max(self.commands["gear"], 0.0), 1.0)
        if self.definition.gear:
            f["fdikit/gear-pos-norm"] = f["gear/gear-cmd-norm"]

    def _write_surfaces(self, positions: dict) -> None:
        for s in self.surfaces:
            if s == "flap":
                self.fdm["fdikit/flap-pos-deg"] = np.degrees(positions[s])
            else:
                self.fdm[f"fdikit/{s}-pos-rad"] = positions[s]

    def surface_commands(self) -> dict:
        """The position each surface actuator is commanded to [rad] (``pitch_trim`` added to the elevator).

        Returns
        -------
        dict
        """
        surf = {s: self.commands[s] for s in self.surfaces}
        if "elevator" in surf:
            surf["elevator"] += self.commands["pitch_trim"]
        return surf

    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of :attr:`dt`: actuators, then one JSBSim step each.

        Parameters
        ----------
        n : int, optional
            Number of steps (default 1).

        Raises
        ------
        DataError
            If JSBSim stops (a crash, or the simulation terminated).
        """
        for _ in range(validate.integer("n", n, minimum=0)):
            self._write_surfaces(self.actuators.update(self.surface_commands(), self.time, self.dt))
            self._write_commands()
            if not self.fdm.run():
                raise DataError(f"JSBSim stopped at t = {self.time:.2f} s (crash or terminate).")

    # ---------------------------------------------------------------- set-up
    def set_mass(self, mass: float, *, in_flight: bool = False) -> None:
        """Set the total mass [kg] with a payload at the empty-weight CG (fuel kept; drained if too heavy).

        Parameters
        ----------
        mass : float
            Total mass [kg].
        in_flight : bool, optional
            Only change the payload, from the next step (no re-initialisation, which resets the state).

        Raises
        ------
        ParameterError
            If the mass is below the aircraft's empty weight.
        """
        mass = validate.positive("mass", mass)
        f = self.fdm
        slot = self._mass_properties[-1]
        tanks = self._mass_properties[:-1]
        fuel = np.array([f[t] for t in tanks])
        dry = f["inertia/weight-lbs"] - f[slot] - fuel.sum()
        extra = mass / LBM - dry - fuel.sum()
        if mass / LBM < dry:
            raise ParameterError(f"mass = {mass:.0f} kg is below the {self.name}'s empty weight {dry * LBM:.0f} kg.")
        if in_flight and extra < 0:
            raise ParameterError(f"in flight the mass stays ≥ {(dry + fuel.sum()) * LBM:.0f} kg; got {mass:.0f}.")
        if in_flight:
            f[slot] = extra
            return
        if extra < 0:
            for t, c in zip(tanks, fuel, strict=True):
                f[t] = c * (1 + extra / fuel.sum())
        f[slot] = max(extra, 0.0)
        f.run_ic()

    def set_turbulence(self, severity: int = 0, wind_20ft: float = 0.0, seed: int | None = None) -> None:
        """Switch the MIL-F-8785C Dryden turbulence (JSBSim's ``turb-type`` 3) on or off.

        Parameters
        ----------
        severity : int, optional
            MIL-F-8785C probability-of-exceedance level 0 (off) … 7 (3 light, 4 moderate, 6 severe).
        wind_20ft : float, optional
            Wind speed 20 ft above ground [m/s] for the low-altitude model (default 0).
        seed : int, optional
            The turbulence's random seed (JSBSim's ``atmosphere/randomseed``: a new generator).

        Raises
        ------
        ParameterError
            For a severity outside 0…7.
        """
        severity = validate.integer("severity", severity, minimum=0)
        validate.in_range("severity", severity, 0, 7)
        f = self.fdm
        if seed is not None:
            f["atmosphere/randomseed"] = validate.integer("seed", seed, minimum=0)
        f["atmosphere/turb-type"] = 3 if severity else 0
        f["atmosphere/turbulence/milspec/severity"] = severity
        wind = validate.non_negative("wind_20ft", wind_20ft)
        f["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = wind / FT

    # ---------------------------------------------------------------- snapshots
    def snapshot(self) -> AircraftSnapshot:
        """The current state (:class:`AircraftSnapshot`), for :meth:`restore`.

        Returns
        -------
        AircraftSnapshot
        """
        f = self.fdm
        engines = np.array([f[p] for p in self._spools])
        props = {k: f[k] for k in self._restored_properties()}
        return AircraftSnapshot(time=self.time, body=np.array([f[p] for p in _NOW_BODY]), engines=engines,
                                properties=props, actuators=self.actuators.snapshot(), commands=dict(self.commands))

    def _restored_properties(self) -> list[str]:
        unit = {s: "deg" if s == "flap" else "rad" for s in self.surfaces}
        return ([f"fdikit/{s}-pos-{unit[s]}" for s in self.surfaces] + [f"fdikit/{s}-override" for s in self.surfaces]
                + [f"fcs/throttle-cmd-norm[{i}]" for i in range(self.engines)]
                + [f"propulsion/engine[{i}]/{k}" for i in range(self.engines) for k in ("set-running", "seized")]
                + ["gear/gear-cmd-norm"]
                + (["fdikit/gear-pos-norm"] if self.definition.gear else []) + self._mass_properties)

    def restore(self, snap: AircraftSnapshot) -> None:
        """Put the aircraft back into a :meth:`snapshot` state.

        JSBSim restarts from the restored state (its multi-step integrators and the turbulence filters
        start afresh), so a restored flight repeats the original to rounding (1e-13 relative) when the
        original also started from a restore.

        Parameters
        ----------
        snap : AircraftSnapshot
        """
        f = self.fdm
        f.set_dt(self.dt)  # JSBSim's FGLinearization leaves the step at 0
        self._set_body(snap.body)
        f.reset_to_initial_conditions(0)  # also restarts the integrators' histories and the gust filters
        for k, v in snap.properties.items():
            f[k] = v
        for p, v in zip(self._spools, snap.engines, strict=True):
            f[p] = v
        f.run_ic()
        f.set_sim_time(snap.time)
        self.actuators.restore(snap.actuators)
        self.commands = dict(snap.commands)

    def _set_body(self, body) -> None:
        f = self.fdm
        # JSBSim's IC resolves u, v, w against the attitude, so the attitude goes first
        for p in (6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5):
            f[_IC_BODY[p]] = body[p]

    # ---------------------------------------------------------------- model
    def set_state(self, x, *, latitude: float | None = None, longitude: float | None = None) -> None:
        """Write the rigid-body state :data:`STATES` as the current state (``run_ic``).

        JSBSim's multi-step integrators keep their history; to fly from the new state as from a
        fresh start, follow with ``restore(snapshot())``.

        Parameters
        ----------
        x : array_like
            ``[p, q, r, V_TAS, α, β, φ, θ, ψ, h]`` in SI units.
        latitude, longitude : float, optional
            Position [rad]; the current one when omitted.

        Raises
        ------
        ParameterError
            For a state of the wrong length or non-finite.
        """
        x = validate.as_vector("x (the states " + ", ".join(STATES) + ")", x, 10)
        p, q, r, vt, alpha, beta, phi, theta, psi, h = x
        u = vt * np.cos(alpha) * np.cos(beta)
        v = vt * np.sin(beta)
        w = vt * np.sin(alpha) * np.cos(beta)
        f = self.fdm
        lat = f["position/lat-geod-rad"] if latitude is None else latitude
        lon = f["position/long-gc-rad"] if longitude is None else longitude
        self._set_body(np.array([u / FT, v / FT, w / FT, p, q, r, phi, theta, psi, h / FT, lat, lon]))
        f.run_ic()

    def hold_surfaces(self, positions: dict) -> None:
        """Put the surfaces at the given positions [rad] at once (actuators included), for trim and linearisation.

        Parameters
        ----------
        positions : dict
            Surface → position [rad]; surfaces not named keep their position.
        """
        self.actuators.place(positions)
        self._write_surfaces(self.actuators.positions)

    def set_engine_running(self, engine: int, running: bool) -> None:
        """Start or cut off one engine at once (a cut engine is stopped and seized: no thrust at all).

        Parameters
        ----------
        engine : int
            Engine number, 1-based.
        running : bool

        Raises
        ------
        ParameterError
            For an engine number the aircraft does not have.
        """
        engine = validate.integer("engine", engine, minimum=1)
        if engine > self.engines:
            raise ParameterError(f"the {self.name} has engines 1…{self.engines}; got engine {engine}.")
        self.fdm[f"propulsion/engine[{engine - 1}]/set-running"] = 1 if running else 0
        # seized too: JSBSim's run_ic gives a stopped, unseized turbine a windmill thrust of ~7.6 kN
        self.fdm[f"propulsion/engine[{engine - 1}]/seized"] = 0 if running else 1

    def set_throttles(self, throttles, steady: bool = True) -> None:
        """Set every engine's throttle and (by default) bring the engines to their steady state.

        Parameters
        ----------
        throttles : float or array_like
            One value for all engines or one per engine, 0…1.
        steady : bool, optional
            Spool the engines to the steady state of the throttle (default True).
        """
        t = np.broadcast_to(np.asarray(throttles, dtype=float), (self.engines,))
        for i, v in enumerate(t):
            self.commands[f"throttle_{i + 1}"] = float(v)
        self._write_commands()
        if steady:
            self.fdm.run_ic()
            self.fdm.get_propulsion().get_steady_state()

    def derivatives(self, x, positions: dict | None = None, throttles=None) -> np.ndarray:
        """``ẋ = f(x, u)`` for the rigid-body state :data:`STATES` (no time step is taken).

        Parameters
        ----------
        x : array_like
            The state, SI units.
        positions : dict, optional
            Surface positions [rad] (the current ones when omitted).
        throttles : float or array_like, optional
            Throttles with the engines at steady state (the current engine state when omitted).

        Returns
        -------
        ndarray
            The state derivative; ``α̇, β̇`` from the body accelerations, the Euler rates from
            ``p, q, r``, ``ḣ`` from JSBSim.
        """
        if positions:
            self.hold_surfaces(positions)
        self.set_state(x)
        if throttles is not None:
            self.set_throttles(throttles)
            self.fdm.run_ic()
        f = self.fdm
        p, q, r, vt, alpha, beta, phi, theta, _psi, _h = x
        uvw = np.array([f["velocities/u-fps"], f["velocities/v-fps"], f["velocities/w-fps"]]) * FT
        dot = np.array([f["accelerations/udot-ft_sec2"], f["accelerations/vdot-ft_sec2"],
                        f["accelerations/wdot-ft_sec2"]]) * FT
        u, v, w = uvw
        vdot = uvw @ dot / vt
        adot = (u * dot[2] - w * dot[0]) / (u * u + w * w)
        bdot = (vt * dot[1] - v * vdot) / (vt * np.sqrt(max(u * u + w * w, 1e-12)))
        pqr_dot = [f["accelerations/pdot-rad_sec2"], f["accelerations/qdot-rad_sec2"], f["accelerations/rdot-rad_sec2"]]
        sphi, cphi, ttheta = np.sin(phi), np.cos(phi), np.tan(theta)
        euler = [p + (q * sphi + r * cphi) * ttheta, q * cphi - r * sphi, (q * sphi + r * cphi) / np.cos(theta)]
        return np.array([*pqr_dot, vdot, adot, bdot, *euler, f["velocities/h-dot-fps"] * FT])
