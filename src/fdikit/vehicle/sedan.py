"""The nonlinear PATH car as a plant: operating points, linearisation and fast simulation.

:class:`Sedan` wraps the compiled dynamics of :mod:`fdikit.vehicle.dynamics` (Douglas et al.
1996, Ch. 2 and Ch. 8) with named states, controls, outputs and parameters:

* :meth:`Sedan.design_plant` — the 22-state block of §2.2 as a
  :class:`~fdikit.simulate.NonlinearPlant` (what :func:`~fdikit.nonlinear.trim` and
  :func:`~fdikit.nonlinear.linearize` take);
* :meth:`Sedan.operating_point` — a steady straight run or steady turn at a given throttle or speed;
* :meth:`Sedan.linearize` — the 22-state linear model ``(A, B, C + DA, DB)`` of (2.8) at a point
  (the accelerometer rows include ``D ẋ`` because the outputs are specific forces);
* :meth:`Sedan.simulate` — a run at a 1 kHz RK4 step on a road profile with wind, sensor noise
  and any :mod:`fdikit.faults` on the 12 sensors and 3 actuators, returned as a
  :class:`~fdikit.trace.Trace` sampled at ``dt``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.vehicle.dynamics import AUXILIARY, CONTROLS, N_DESIGN_STATES, SENSORS, STATES, evaluate
from fdikit.vehicle.parameters import MID_SIZE_SEDAN, SedanParameters

__all__ = ["Sedan", "OperatingPoint", "SIGNALS", "throttle_for_speed"]

#: Outputs a design plant can have: the 12 sensors and the auxiliary signals.
SIGNALS = SENSORS + AUXILIARY


@dataclass(frozen=True)
class OperatingPoint:
    """A steady state of the car (all 22 design-state derivatives zero).

    Attributes
    ----------
    x : (26,) ndarray
        State (positions, heading and distance zero).
    u : (3,) ndarray
        Commands: throttle [deg], brake [N m], steering [rad].
    y : (12,) ndarray
        Sensor outputs.
    signals : dict of str to float
        Every auxiliary signal (tire forces, slips, specific forces, ``ground_speed``, ``lateral_acceleration``,
        ``curvature`` …).
    grade, bank : float
        Road slope [rad] the point is for.

    Examples
    --------
    >>> op = Sedan().operating_point(throttle=20.3)
    >>> round(op.speed, 1), op.radius
    (27.0, inf)
    """

    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    signals: dict = field(repr=False)
    grade: float = 0.0
    bank: float = 0.0

    @property
    def speed(self) -> float:
        """Speed over the road [m/s]."""
        return float(self.signals["ground_speed"])

    @property
    def radius(self) -> float:
        """Turn radius [m] (``inf`` straight ahead)."""
        c = float(self.signals["curvature"])
        return float("inf") if abs(c) < 1e-12 else 1.0 / c

    @property
    def lateral_acceleration_g(self) -> float:
        """Lateral acceleration ``V ψ'`` in units of g."""
        return float(self.signals["lateral_acceleration"]) / 9.81


class Sedan:
    """The nonlinear car of Douglas et al. 1996, Ch. 2 and 8, with the parameters of a mid-size sedan.

    Parameters
    ----------
    params : SedanParameters, default MID_SIZE_SEDAN
        Every number of the car.

    Attributes
    ----------
    states, controls, sensors : tuple of str
        :data:`~fdikit.vehicle.dynamics.STATES` (26), ``("throttle", "brake", "steering")``, the 12 PATH sensors.

    Raises
    ------
    ParameterError
        When ``params`` is not a :class:`SedanParameters`.

    References
    ----------
    Douglas et al. 1996, §2.1–2.2, §8.2, App. D (sensor order).

    Examples
    --------
    >>> car = Sedan()
    >>> len(car.states), car.controls, car.sensors[:3]
    (26, ('throttle', 'brake', 'steering'), ('air_mass', 'engine_speed', 'accel_x'))
    """

    states = STATES
    controls = CONTROLS
    sensors = SENSORS

    def __init__(self, params: SedanParameters = MID_SIZE_SEDAN) -> None:
        self.params = validate.instance("params", params, SedanParameters)
        self._p = params.as_array()

    def __repr__(self) -> str:
        return f"Sedan(mass={self.params.mass:g} kg, gear={self.params.gear})"

    # ------------------------------------------------------------------------------------------ point evaluation
    def derivatives(self, x, u, *, road=(0.0, 0.0, 0.0, 0.0), wind=(0.0, 0.0), grade: float = 0.0,
                    bank: float = 0.0) -> tuple[np.ndarray, np.ndarray, dict]:
        """``(ẋ, y, signals)`` at one state and command.

        Parameters
        ----------
        x : array_like, shape (26,)
            State.
        u : array_like, shape (3,)
            Commands.
        road : sequence of 4 float, default zeros
            Road height under the wheels fl, fr, rl, rr [m].
        wind : sequence of 2 float, default zeros
            Earth-frame wind [m/s].
        grade, bank : float, default 0.0
            Road slope [rad] (uphill and right-side-up positive).

        Returns
        -------
        dx : (26,) ndarray
        y : (12,) ndarray
        signals : dict of str to float

        Raises
        ------
        ParameterError
            For arrays of the wrong length or not finite.

        Examples
        --------
        >>> car = Sedan()
        >>> op = car.operating_point(throttle=20.3)
        >>> dx, y, sig = car.derivatives(op.x, op.u)
        >>> float(np.abs(dx[:22]).max()) < 1e-7
        True
        """
        x, u = _vector("x", x, len(STATES)), _vector("u", u, 3)
        env = np.r_[_vector("road", road, 4), _vector("wind", wind, 2), validate.number("grade", grade),
                    validate.number("bank", bank)]
        dx, y, aux = evaluate(x, u, env, self._p)
        return dx, y, dict(zip(AUXILIARY, aux.tolist()))

    # -------------------------------------------------------------------------------------------- design plant
    def design_plant(self, outputs=SENSORS, *, grade: float = 0.0, bank: float = 0.0):
        """The 22-state block of §2.2 as a :class:`~fdikit.simulate.NonlinearPlant` (level, smooth road, no wind).

        Parameters
        ----------
        outputs : sequence of str, default SENSORS
            Output names from :data:`SIGNALS`.
        grade, bank : float, default 0.0
            Road slope [rad].

        Returns
        -------
        NonlinearPlant
            States ``STATES[:22]``, controls ``CONTROLS``, the chosen outputs; ``x0`` the 27 m/s straight run.

        Raises
        ------
        ParameterError
            For an unknown output name.

        References
        ----------
        Douglas et al. 1996, §2.2 (the 22-state block ``x_1`` after exact truncation).

        Examples
        --------
        >>> plant = Sedan().design_plant(["yaw_rate", "curvature"])
        >>> len(plant.states), plant.outputs
        (22, ('yaw_rate', 'curvature'))
        """
        from fdikit.simulate import NonlinearPlant

        names = tuple(outputs)
        for n in names:
            validate.choice("outputs", n, SIGNALS)
        pick = np.array([SIGNALS.index(n) for n in names], dtype=int)
        env = np.array([0.0] * 6 + [validate.number("grade", grade), validate.number("bank", bank)])
        p, full = self._p, np.zeros(len(STATES))

        def _eval(x, u):
            full[:N_DESIGN_STATES] = x
            dx, y, aux = evaluate(full, u, env, p)
            return dx, np.r_[y, aux][pick]

        x0 = self._straight_guess(27.0)[:N_DESIGN_STATES]
        return NonlinearPlant(f=lambda t, x, u: _eval(x, u)[0][:N_DESIGN_STATES], h=lambda t, x, u: _eval(x, u)[1],
                              states=STATES[:N_DESIGN_STATES], outputs=names, controls=CONTROLS, x0=x0)

    def _straight_guess(self, speed: float, throttle: float = 20.0) -> np.ndarray:
        P = self.params
        loads = P.corner_loads()
        r = P.tire_radius - loads / P.tire_stiffness
        x = np.zeros(len(STATES))
        x[0] = 0.5 * P.ambient_pressure * P.manifold_volume / (287.05 * P.manifold_temperature)  # half an atmosphere
        x[1] = P.gear_ratio() * speed / r[0]
        x[2] = speed
        x[5] = P.cg_height
        x[11:15] = speed / r
        x[15] = throttle
        x[18:22] = P.static_lengths()
        return x

    # --------------------------------------------------------------------------------------- operating points
    def operating_point(self, *, throttle: float | None = None, speed: float | None = None, steering: float = 0.0,
                        brake: float = 0.0, grade: float = 0.0, bank: float = 0.0, tol: float = 1e-9
                        ) -> OperatingPoint:
        """The steady run at a held ``throttle`` [deg], or at a ``speed`` [m/s] with the throttle solved for.

        Parameters
        ----------
        throttle : float, optional
            Throttle angle [deg] (give exactly one of ``throttle`` and ``speed``).
        speed : float, optional
            Speed over the road [m/s].
        steering : float, default 0.0
            Road-wheel steer angle [rad] (a steady turn when nonzero; positive turns left).
        brake : float, default 0.0
            Brake torque [N m].
        grade, bank : float, default 0.0
            Road slope [rad].
        tol : float, default 1e-9
            Trim tolerance (:func:`fdikit.nonlinear.trim`).

        Returns
        -------
        OperatingPoint

        Raises
        ------
        ParameterError
            Unless exactly one of ``throttle`` and ``speed`` is given, or for values that are not finite.
        DesignError
            When no steady state is found (e.g. a throttle too small to move the car).

        References
        ----------
        Douglas et al. 1996, §2.2 (0.005 rad steer at 24.87 m/s), §8.3 (22.555 % throttle at 27 m/s).

        Examples
        --------
        >>> op = Sedan().operating_point(speed=24.87, steering=0.005)
        >>> round(op.radius), round(op.lateral_acceleration_g, 3)
        (639, 0.099)
        """
        from fdikit.nonlinear import trim

        if (throttle is None) == (speed is None):
            raise ParameterError("operating_point: give exactly one of throttle= [deg] and speed= [m/s]")
        steering = validate.number("steering", steering)
        brake = validate.non_negative("brake", brake)
        if throttle is not None:
            throttle = validate.positive("throttle", throttle)
            plant = self.design_plant(("ground_speed",), grade=grade, bank=bank)
            guess_speed = 27.0 * throttle / 20.3
            x0 = self._straight_guess(guess_speed, throttle)
            x0[15:18] = throttle, brake, steering
            op = trim(plant, x0[:N_DESIGN_STATES], [throttle, brake, steering], tol=tol)
        else:
            speed = validate.positive("speed", speed)
            return throttle_for_speed(
                lambda th: self.operating_point(throttle=th, steering=steering, brake=brake, grade=grade, bank=bank,
                                                tol=tol), speed, 20.3 * (speed / 27.0) ** 2)
        x = np.zeros(len(STATES))
        x[:N_DESIGN_STATES] = op.x
        _, y, aux = self.derivatives(x, op.u, grade=grade, bank=bank)
        return OperatingPoint(x=x, u=np.asarray(op.u, dtype=float), y=y, signals=aux, grade=float(grade),
                              bank=float(bank))

    def linearize(self, op: OperatingPoint, outputs=SENSORS):
        """The 22-state linear model at ``op``: ``ẋ = A x + B u``, ``y = (C + D A) x + D B u`` (2.8), deviations.

        Parameters
        ----------
        op : OperatingPoint
            The point.
        outputs : sequence of str, default SENSORS
            Output names from :data:`SIGNALS`.

        Returns
        -------
        FaultModel
            Continuous, 22 states named as :data:`STATES` ``[:22]``, controls ``CONTROLS``.

        Raises
        ------
        ParameterError
            When ``op`` is not an :class:`OperatingPoint`.

        References
        ----------
        Douglas et al. 1996, §2.2 (2.7)–(2.8), Ch. 8 §8.3.1 (perturbation sizes).

        Examples
        --------
        >>> car = Sedan()
        >>> lin = car.linearize(car.operating_point(throttle=20.3))
        >>> lin.A.shape, lin.C.shape
        ((22, 22), (12, 22))
        """
        from fdikit.nonlinear import linearize

        validate.instance("op", op, OperatingPoint)
        plant = self.design_plant(outputs, grade=op.grade, bank=op.bank)
        return linearize(plant, op.x[:N_DESIGN_STATES], op.u)

    # --------------------------------------------------------------------------------------------- simulation
    def simulate(self, duration: float, *, start: OperatingPoint | None = None, commands=None, road=None,
                 wind: Callable | None = None, scenario=None, measurement_noise_std: Mapping | None = None,
                 dt: float = 0.01, step: float = 0.001, gearbox: str = "held", grade: float | None = None,
                 bank: float | None = None, rng=None, keep_signals: bool = True):
        """Simulate a run; see :func:`fdikit.vehicle.run.simulate_sedan` (this car, same arguments).

        Returns
        -------
        Trace

        Examples
        --------
        >>> car = Sedan()
        >>> tr = car.simulate(1.0, start=car.operating_point(throttle=20.3))
        >>> tr.y.shape
        (101, 12)
        """
        from fdikit.vehicle.run import simulate_sedan

        return simulate_sedan(self, duration, start=start, commands=commands, road=road, wind=wind, scenario=scenario,
                              measurement_noise_std=measurement_noise_std, dt=dt, step=step, gearbox=gearbox,
                              grade=grade, bank=bank, rng=rng, keep_signals=keep_signals)


def throttle_for_speed(point_at: Callable, speed: float, guess: float, *, rtol: float = 1e-10,
                       max_iterations: int = 40):
    """The steady state at ``speed``: the throttle found by the secant method on steady states at fixed throttle.

    A trim with the speed as an output target and the throttle free can wander into the throttle's clipped,
    flat region (below 0°) from a poor guess — which guess is poor depends on rounding, so it changed with the
    BLAS kernel; every trim at a fixed throttle is a square, well-conditioned solve, and the speed is monotone in
    the throttle.

    Parameters
    ----------
    point_at : callable
        ``point_at(throttle) -> point`` with a ``speed`` attribute (a steady state at that throttle [deg]).
    speed : float
        Target speed [m/s].
    guess : float
        First throttle [deg].
    rtol : float, default 1e-10
        Relative speed tolerance.
    max_iterations : int, default 40
        Secant steps.

    Returns
    -------
    point
        ``point_at`` at the throttle found.

    Raises
    ------
    DesignError
        When the speed is not reached (the last throttle and speed in the message).

    References
    ----------
    Douglas et al. 1996, §2.2 (the turn at 24.87 m/s), §8.3.1 (27 m/s).

    Examples
    --------
    >>> car = Sedan()
    >>> round(float(throttle_for_speed(lambda th: car.operating_point(throttle=th), 27.0, 15.0).u[0]) / 90 * 100, 3)
    22.555
    """
    from fdikit.errors import DesignError

    lo, hi = 0.05, 79.0
    t0 = min(max(guess, lo), hi)
    p0 = point_at(t0)
    t1 = min(max(t0 + (1.0 if p0.speed < speed else -1.0), lo), hi)
    p1 = point_at(t1)
    for _ in range(max_iterations):
        if abs(p1.speed - speed) <= rtol * speed:
            return p1
        slope = (p1.speed - p0.speed) / (t1 - t0) if t1 != t0 else 0.0
        step = (speed - p1.speed) / slope if slope > 0 else (1.0 if p1.speed < speed else -1.0)
        t_next = min(max(t1 + max(min(step, 10.0), -10.0), lo), hi)
        t0, p0 = t1, p1
        while True:
            try:
                p1, t1 = point_at(t_next), t_next
                break
            except DesignError:
                if abs(t_next - t0) < 1e-6:
                    raise
                t_next = 0.5 * (t_next + t0)  # the car may not run steadily that far: a shorter step
    raise DesignError(f"no steady state at {speed:g} m/s: throttle {t1:.6g} deg gives {p1.speed:.9g} m/s after "
                      f"{max_iterations} secant steps")


def _vector(name: str, value, n: int) -> np.ndarray:
    v = validate.as_array(name, value)
    if v.shape != (n,):
        raise ParameterError(f"{name} must be a vector of {n} numbers, got shape {v.shape}")
    return v
