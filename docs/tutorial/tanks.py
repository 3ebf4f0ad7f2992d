"""Two tanks in series, written as a user would: the plant is a Python function.

Tank 1 (area 0.5 m²) is filled by a pump (flow q [m³/s]) and drains through an orifice into tank 2
(area 0.8 m²), which drains to the sump; Torricelli outflow a √(2 g h).  Both levels are measured [m].
"""

import numpy as np

from fdikit.simulate import NonlinearPlant

AREA = (0.5, 0.8)            # tank cross sections [m²]
ORIFICE = (2.0e-4, 1.6e-4)   # effective outflow areas [m²]
G = 9.80665


def dynamics(t, x, u):
    h1, h2 = np.maximum(x, 0.0)
    q12, q2 = ORIFICE[0] * np.sqrt(2 * G * h1), ORIFICE[1] * np.sqrt(2 * G * h2)
    return np.array([(u[0] - q12) / AREA[0], (q12 - q2) / AREA[1]])


def levels(t, x, u):
    return np.array([x[0], x[1]])


def plant() -> NonlinearPlant:
    return NonlinearPlant(f=dynamics, h=levels, states=("h1", "h2"), controls=("pump",),
                          outputs=("level1", "level2"), x0=np.array([0.3, 0.3]))
