"""Mass–spring–damper LPV benchmark, Hallouzi 2008, §3.6."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.multimodel.model_set import vectorize
from fdikit.plants.msd import msd, msd_matrices, msd_model_vectors, msd_parameter_grid


def _assembled(k1, m3, f1, f2):
    """Independent assembly from the topology: springs/dampers 1: m1–m2, 2: m2–ground, 3: m1–m3, 4: m2–m3."""
    k = {1: k1, 2: 0.15, 3: 1.0, 4: 0.2}
    links = {1: (0, 1), 2: (1, None), 3: (0, 2), 4: (1, 2)}
    K, Bd = np.zeros((3, 3)), np.zeros((3, 3))
    for i, (a, b) in links.items():
        for mat, c in ((K, k[i]), (Bd, 0.01)):
            mat[a, a] += c
            if b is not None:
                mat[b, b] += c
                mat[a, b] -= c
                mat[b, a] -= c
    Minv = np.diag(1 / np.array([1.0, 1.0, m3]))
    A = np.block([[np.zeros((3, 3)), np.eye(3)], [-Minv @ K, -Minv @ Bd]])
    B = np.vstack([np.zeros((3, 2)), Minv @ np.array([[f1, 0], [0, 0], [0, 1]])])
    return A, B, np.diag([1.0, f2, 1.0]) @ np.eye(3, 6)


@pytest.mark.parametrize("params", [(1.0, 1.0, 1.0, 1.0), (0.25, 1.8, 0.3, 1.0), (1.75, 0.2, 1.0, 0.0)])
def test_matrices_equal_the_assembled_mechanics(params):
    for X, Y in zip(msd_matrices(*params), _assembled(*params)):
        np.testing.assert_allclose(X, Y, atol=1e-15)


def test_model_is_passive_and_discretisation_is_first_order():
    for k1, m3 in [(0.25, 0.2), (1.75, 1.8), (1.0, 1.0)]:
        assert np.linalg.eigvals(msd(k1, m3).A).real.max() < 0  # damped (k2 grounds m2)
    A, B, C = msd_matrices(0.7, 1.3)
    d = msd(0.7, 1.3, dt=2.5e-3)
    np.testing.assert_allclose(d.A, np.eye(6) + 2.5e-3 * A)
    np.testing.assert_allclose(d.Bu, 2.5e-3 * B)
    assert d.faults == ("u1_actuator", "y2_sensor") and d.dt == 2.5e-3


def test_grid_and_model_vectors():
    P = msd_parameter_grid()
    assert P.shape == (13 * 13 * 21, 4)
    assert not np.any((P[:, 2] < 1) & (P[:, 3] < 1))  # single faults only
    M = msd_model_vectors(P[:3])
    A, B, C = msd_matrices(*P[1])
    np.testing.assert_allclose(M[:, 1], vectorize(np.eye(6) + 2.5e-3 * A, 2.5e-3 * B, C), atol=1e-15)


def test_bad_parameters():
    with pytest.raises(ParameterError, match="outside its range"):
        msd_matrices(k1=2.0)
    with pytest.raises(ParameterError, match="positive"):
        msd_matrices(m3=-1.0, allow_outside=True)
    with pytest.raises(ParameterError, match="dt"):
        msd(dt=0.0)
