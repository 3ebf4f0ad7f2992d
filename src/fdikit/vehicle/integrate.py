"""The compiled fixed-step integrator of the nonlinear car (classical RK4, road sampled by distance).

One call integrates the 26 states over a whole run: commands and wind held over each step (given at
the step rate), the road height under every wheel interpolated on the spatial profiles at the
distance each wheel has travelled (front wheels at ``s``, rear at ``s − L``; Douglas et al. 1996,
§2.1.2 and (8.109): the rear wheels see the front track delayed by ``L/V``), the automatic
gearbox shifting between steps.  Written by hand (numba) because the run must go ≥ 50× faster
than real time at a 1 kHz step, which a Python right-hand side through ``scipy.integrate``
cannot do.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from fdikit.vehicle.dynamics import AUXILIARY, SENSORS, STATES, rhs, sensors
from fdikit.vehicle.parameters import INDEX

__all__ = ["run_kernel"]

_N, _NA, _NY = len(STATES), len(AUXILIARY), len(SENSORS)
_ZETA = INDEX["gear_ratio"]
_L = INDEX["wheelbase"]


@njit(cache=True)
def road_height(profile, spacing, s):  # pragma: no cover - compiled
    """Linear interpolation of ``profile`` (grid step ``spacing``) at distance ``s`` (held beyond the ends)."""
    q = s / spacing
    if q <= 0.0:
        return profile[0]
    k = int(math.floor(q))
    if k >= profile.size - 1:
        return profile[profile.size - 1]
    w = q - k
    return (1.0 - w) * profile[k] + w * profile[k + 1]


@njit(cache=True)
def _stage(x, u, env, p, left, right, spacing, dx, aux):  # pragma: no cover - compiled
    s, wb = x[25], p[_L]
    env[0] = road_height(left, spacing, s)
    env[1] = road_height(right, spacing, s)
    env[2] = road_height(left, spacing, s - wb)
    env[3] = road_height(right, spacing, s - wb)
    rhs(x, u, env, p, dx, aux)


@njit(cache=True)
def run_kernel(x0, commands, wind, slope, p, left, right, spacing, h, every, ratios, final_drive, shift_up,
               shift_down, gear0, automatic):  # pragma: no cover - compiled
    """Integrate ``commands.shape[0]`` steps of ``h``; record every ``every`` steps (and the start).

    Returns ``(x, y, aux, gear, ok)``: states, sensors and auxiliary signals at the recorded samples, the gear
    per sample, and the number of recorded samples that are finite (a diverging run stops there).
    """
    n_steps = commands.shape[0]
    n_rec = n_steps // every + 1
    xs = np.empty((n_rec, _N))
    ys = np.empty((n_rec, _NY))
    auxs = np.zeros((n_rec, _NA))
    gears = np.empty(n_rec, dtype=np.int64)
    x = x0.copy()
    env = np.zeros(8)
    env[6], env[7] = slope[0], slope[1]
    k1, k2, k3, k4 = np.empty(_N), np.empty(_N), np.empty(_N), np.empty(_N)
    aux = np.zeros(_NA)
    xt = np.empty(_N)
    y = np.empty(_NY)
    gear = gear0
    q = p.copy()
    q[_ZETA] = ratios[gear - 1] * final_drive
    r = 0
    for k in range(n_steps + 1):
        uk = commands[min(k, n_steps - 1)]
        env[4], env[5] = wind[min(k, n_steps - 1), 0], wind[min(k, n_steps - 1), 1]
        fresh = k % every == 0  # k1 of this step is the recorded sample's derivative (unless the gear changes)
        if fresh:
            _stage(x, uk, env, q, left, right, spacing, k1, aux)
            sensors(x, aux, y)
            xs[r] = x
            ys[r] = y
            auxs[r] = aux
            gears[r] = gear
            finite = True
            for j in range(_N):
                if not math.isfinite(x[j]):
                    finite = False
            if not finite:
                return xs, ys, auxs, gears, r
            r += 1
        if k == n_steps:
            break
        if automatic:
            w_e = x[1]
            if w_e > shift_up and gear < ratios.size:
                gear += 1
                fresh = False
            elif w_e < shift_down and gear > 1:
                gear -= 1
                fresh = False
            q[_ZETA] = ratios[gear - 1] * final_drive
        if not fresh:
            _stage(x, uk, env, q, left, right, spacing, k1, aux)
        for j in range(_N):
            xt[j] = x[j] + 0.5 * h * k1[j]
        _stage(xt, uk, env, q, left, right, spacing, k2, aux)
        for j in range(_N):
            xt[j] = x[j] + 0.5 * h * k2[j]
        _stage(xt, uk, env, q, left, right, spacing, k3, aux)
        for j in range(_N):
            xt[j] = x[j] + h * k3[j]
        _stage(xt, uk, env, q, left, right, spacing, k4, aux)
        for j in range(_N):
            x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
    return xs, ys, auxs, gears, r
