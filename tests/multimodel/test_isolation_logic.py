"""Table 4.7 decision logic (Hallouzi 2008, §4.4.2, T_f = 0.2).

Model set II (Table 4.5) + nominal model 8: rudder {1, 2}, elevator {3, 5, 6}, aileron {4, 7}
(1-based in the thesis, 0-based here).
"""

from fractions import Fraction

import numpy as np
import pytest

from fdikit.errors import DataError, ParameterError
from fdikit.multimodel.isolation import GroupThresholdLogic, mode_diagnosis, table_4_7_logic


def _mu(**w):
    """μ vector from 1-based thesis indices, e.g. _mu(m8=0.8, m1=0.2)."""
    mu = np.zeros(8)
    for k, v in w.items():
        mu[int(k[1:]) - 1] = v
    return mu


def _brute(mu, T=0.2):
    """Table 4.7 transcribed literally (1-based μ^(i)), in exact rational arithmetic of the decimal weights."""
    m = {i + 1: Fraction(str(round(float(mu[i]), 12))) for i in range(8)}
    T = Fraction(str(T))
    off = abs(1 - m[8]) >= T
    return [abs(1 - m[8]) < T, abs(m[1] + m[2]) >= T and off, abs(m[3] + m[5] + m[6]) >= T and off,
            abs(m[4] + m[7]) >= T and off]


def test_boundary_nominal_weight_0_8_is_not_nominal():
    # §4.1 item 16: μ^(8) = 0.8 → |1 − 0.8| = 0.2 ≥ T_f, so F_0 is false
    logic = table_4_7_logic()
    mu = np.array([_mu(m8=0.8, m1=0.2), _mu(m8=0.81, m1=0.19), _mu(m8=0.8, m3=0.1, m5=0.1)])
    sig = logic.signatures(mu)
    assert logic.names == ("none", "rudder", "elevator", "aileron")
    assert sig.tolist() == [[False, True, False, False], [True, False, False, False], [False, False, True, False]]
    assert logic.isolate(mu).tolist() == ["rudder", "none", "elevator"]


def test_group_sum_boundary_and_unknown():
    logic = table_4_7_logic()
    # off-nominal, but each group sums to < 0.2 → no signature true → 'unknown' (alarm without isolation)
    mu = np.array([_mu(m8=0.55, m1=0.15, m3=0.15, m4=0.15), _mu(m8=0.6, m4=0.2, m7=0.0, m1=0.2),
                   _mu(m8=0.0, m4=0.5, m7=0.5)])
    assert logic.signatures(mu).tolist() == [[False] * 4, [False, True, False, True], [False, False, False, True]]
    # tie rule (Table 4.7 gives none; fdikit's choice): largest group sum; on an exact tie the first group (rudder)
    assert logic.isolate(mu).tolist() == ["unknown", "rudder", "aileron"]
    mu2 = np.array([_mu(m8=0.5, m4=0.3, m1=0.2)])
    assert logic.isolate(mu2).tolist() == ["aileron"]


def test_signatures_equal_literal_table_on_random_and_grid_weights():
    rng = np.random.default_rng(0)
    mu = np.round(rng.dirichlet(0.3 * np.ones(8), size=3000), 12)
    grid = np.round(rng.integers(0, 6, size=(2000, 8)) * 0.1, 10)   # hits the 0.2 / 0.8 boundaries exactly
    grid[:, 7] = np.round(1 - grid[:, :7].sum(axis=1).clip(0, 1), 10)
    mu = np.vstack([mu, grid])
    sig = table_4_7_logic().signatures(mu)
    ref = np.array([_brute(m) for m in mu])
    assert np.array_equal(sig, ref)
    assert sig[:, 0].sum() > 0 and sig[:, 1:].sum() > 0
    # exactly one of F_0 or "off-nominal" holds; F_0 excludes every fault signature
    assert not np.any(sig[:, 0] & sig[:, 1:].any(axis=1))


def test_latch_and_hold_and_diagnosis():
    logic = table_4_7_logic(latch=True)
    mu = np.array([_mu(m8=1.0), _mu(m8=0.5, m3=0.5), _mu(m8=1.0), _mu(m8=0.5, m4=0.5)])
    assert logic.isolate(mu).tolist() == ["none", "elevator", "elevator", "elevator"]
    plain = table_4_7_logic()
    assert plain.isolate(mu, valid=[True, True, False, True]).tolist() == ["none", "elevator", "elevator", "aileron"]
    hyp = tuple(f"model{i}" for i in range(1, 9))
    d = mode_diagnosis(np.arange(4.0), mu, hyp, nominal=7, logic=plain)
    assert d.alarm.tolist() == [False, True, False, True]
    assert [a.fault for a in d.alarms] == ["elevator", "aileron"]
    assert d.names == ("none", "rudder", "elevator", "aileron") and d.hypotheses == hyp
    d2 = mode_diagnosis(np.arange(4.0), mu, hyp, nominal=7)     # most probable mode (ties → first index)
    assert d2.isolated.tolist() == ["none", "model3", "none", "model4"]


def test_bad_logic_and_data_raise():
    with pytest.raises(ParameterError, match="nominal model 7 is also listed"):
        GroupThresholdLogic(groups={"a": (0, 7)}, nominal=7)
    with pytest.raises(ParameterError, match="threshold"):
        GroupThresholdLogic(groups={"a": (0,)}, nominal=1, threshold=1.5)
    with pytest.raises(DataError, match="columns"):
        table_4_7_logic().signatures(np.ones((3, 5)) / 5)
