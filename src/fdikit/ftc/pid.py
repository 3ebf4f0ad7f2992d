"""A discrete PID loop with output limits, a filtered derivative and anti-windup, for the FTC outer loops.

Hallouzi 2008, §6.2, (6.1)–(6.2): the outer loops of the FTC architecture turn altitude into a pitch
reference and heading into a roll reference with PID laws on the error *measured − reference*, whose
integrators have anti-windup (the text names it but gives neither the gains nor the scheme).  Here:

* error convention (6.1)–(6.2): ``e = measured − reference``; a positive climb response then needs
  negative gains, as the thesis notes;
* integral by the forward Euler rule, derivative on the error through a first-order filter
  ``D(z) = kd (1 − z⁻¹) / (T_f + dt − T_f z⁻¹)`` (backward Euler of ``kd s / (T_f s + 1)``);
* anti-windup (Åström & Hägglund 2006, §3.5): ``"clamp"`` (conditional integration: the integrator stops
  while the output is saturated in the direction the error drives it) or ``"back_calculation"``
  (the integrator is corrected by ``(u_sat − u) / T_t`` with tracking time ``T_t``).

Written by hand: a PID with these two schemes is a few lines, and python-control has no discrete
saturating PID object to step sample by sample.

References
----------
Hallouzi 2008, §6.2, (6.1)–(6.2).  Åström & Hägglund 2006, Ch. 3.
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["PID"]


class PID:
    """A discrete PID on ``e = measured − reference`` with output limits and anti-windup.

    Parameters
    ----------
    kp, ki, kd : float
        Proportional, integral [1/s] and derivative [s] gains.
    dt : float
        Sample time [s].
    output_min, output_max : float, optional
        Output limits (default unbounded).
    derivative_filter : float, default 0
        Time constant ``T_f`` [s] of the derivative filter (0: a plain backward difference).
    anti_windup : {"clamp", "back_calculation"}, default "clamp"
        Scheme that keeps the integrator from winding up while the output saturates.
    tracking_time : float, optional
        ``T_t`` of the back-calculation scheme (default ``√(T_i T_d)`` if both exist, else ``T_i``).

    Examples
    --------
    >>> pid = PID(2.0, 1.0, 0.0, dt=0.1, output_min=-1.0, output_max=1.0)
    >>> round(pid.step(0.2), 12), round(pid.step(0.2), 12)
    (0.4, 0.42)

    References
    ----------
    Hallouzi 2008, §6.2, (6.1)–(6.2).  Åström & Hägglund 2006, §3.5.
    """

    def __init__(self, kp: float, ki: float = 0.0, kd: float = 0.0, *, dt: float, output_min: float | None = None,
                 output_max: float | None = None, derivative_filter: float = 0.0, anti_windup: str = "clamp",
                 tracking_time: float | None = None) -> None:
        self.kp = validate.number("kp", kp)
        self.ki = validate.number("ki", ki)
        self.kd = validate.number("kd", kd)
        self.dt = validate.positive("dt", dt)
        self.output_min = -np.inf if output_min is None else validate.number("output_min", output_min, finite=False)
        self.output_max = np.inf if output_max is None else validate.number("output_max", output_max, finite=False)
        if self.output_min >= self.output_max:
            raise ParameterError(f"output_min = {self.output_min} must be below output_max = {self.output_max}.")
        self.derivative_filter = validate.non_negative("derivative_filter", derivative_filter)
        self.anti_windup = validate.choice("anti_windup", anti_windup, ["clamp", "back_calculation"])
        if tracking_time is None:
            ti = abs(self.kp / self.ki) if self.ki and self.kp else 1.0
            td = abs(self.kd / self.kp) if self.kp else 0.0
            tracking_time = np.sqrt(ti * td) if td > 0 else ti
        self.tracking_time = validate.positive("tracking_time", tracking_time)
        self.reset()

    def reset(self, integral: float = 0.0) -> None:
        """Clear the state (integral, derivative filter, last error).

        Parameters
        ----------
        integral : float, default 0
            Initial integrator output (for a bumpless start at a trim value).
        """
        self.integral = float(integral)
        self._deriv = 0.0
        self._last = None

    def step(self, error: float) -> float:
        """One sample: the limited output for ``error = measured − reference``.

        Parameters
        ----------
        error : float

        Returns
        -------
        float

        Raises
        ------
        ParameterError
            A non-finite error (hold the last output instead of calling ``step``).
        """
        e = validate.number("error", error)
        if self._last is None:
            self._last = e
        tf, dt = self.derivative_filter, self.dt
        self._deriv = (tf * self._deriv + self.kd * (e - self._last)) / (tf + dt)
        self._last = e
        raw = self.kp * e + self.integral + self._deriv
        out = float(min(max(raw, self.output_min), self.output_max))
        step = self.ki * e * dt
        if self.anti_windup == "clamp":
            if not ((raw > self.output_max and step > 0) or (raw < self.output_min and step < 0)):
                self.integral += step
        else:
            self.integral += step + (out - raw) * dt / self.tracking_time
        return out
