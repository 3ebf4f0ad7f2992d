"""Tests of fdikit.studies.hallouzi2008.spc_msd (set-up only; the closed-loop runs take ~1 min)."""

import numpy as np
from scipy.signal import cont2discrete

from fdikit.plants.msd import MSD_RANGES, msd_matrices
from fdikit.studies.hallouzi2008 import spc_msd


def test_zero_order_hold_discretisation_matches_scipy():
    a, b, c = msd_matrices(k1=1.3, m3=0.7)
    ad, bd, _, _, _ = cont2discrete((a, b, c, np.zeros((3, 2))), spc_msd.DT, method="zoh")
    a2, b2, c2 = spc_msd._discrete(1.3, 0.7)
    np.testing.assert_allclose(a2, ad, atol=1e-12)
    np.testing.assert_allclose(b2, bd, atol=1e-12)


def test_parameter_trajectory_stays_in_the_ranges():
    t = np.linspace(0, 400, 4001)
    k1, m3 = spc_msd._parameters(t)
    assert k1[0] == 1.0 and m3[0] == 1.0 and np.isclose(k1[-1], 1.6) and np.isclose(m3[-1], 0.5)
    for name, v in (("k1", k1), ("m3", m3)):
        lo, hi = MSD_RANGES[name]
        assert np.all((v >= lo) & (v <= hi))
