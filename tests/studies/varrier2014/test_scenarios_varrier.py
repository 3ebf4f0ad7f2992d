"""The a_y-sensor fault scenario of Varrier, Koenig & Martinez 2014, §5.4–5.5.

Item 14 is asserted: the fault is +0.5 m/s² on a_y over [150 s, 158 s) only, the residuals are
normalised to mean one over the faulty time and ϖ is computed exactly as defined.  Item 15: the paper's
values ϖ_LPV = 1.39, ϖ_LPVu = 4.04 (§5.5) are **not reproduced** (the MIPS data are not available and
ϖ depends on the simulated uncertainty class); what is reproduced and asserted is the paper's
conclusion that the U-LPV residual separates the fault better than the LPV one.
"""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.design.parity.state_space import lpv_parity_residuals
from fdikit.errors import DataError, ParameterError
from fdikit.plants.varrier_lateral import rho_from_speed, varrier_lateral_lpv
from fdikit.studies.varrier2014.scenarios import (
    fault_window_masks,
    min_max_ratio,
    normalise_residual,
    speed_profile,
    steering_profile,
    varrier_comparison,
    varrier_trace,
)


def test_fault_is_half_a_metre_per_second_squared_on_ay_from_150_to_158_s():
    """§5.4: '+0.5 m.s⁻²' added 'from t = 150s to t = 158s to the first system output a_y(k)'."""
    faulty = varrier_trace(seed=4)
    clean = varrier_trace(seed=4, fault_size=0.0)
    t = faulty.t
    assert t[1] - t[0] == pytest.approx(0.02) and len(t) == 10000
    window = (t >= 150 - 1e-9) & (t < 158 - 1e-9)
    assert window.sum() == 400
    diff = faulty.signal("lateral_acceleration") - clean.signal("lateral_acceleration")
    np.testing.assert_allclose(diff[window], 0.5, rtol=1e-12)
    np.testing.assert_array_equal(diff[~window], 0.0)
    np.testing.assert_array_equal(faulty.signal("yaw_rate"), clean.signal("yaw_rate"))
    np.testing.assert_array_equal(faulty.x, clean.x)
    assert faulty.fault_onset == pytest.approx(150.0)
    np.testing.assert_array_equal(faulty.fault != "none", window)
    np.testing.assert_allclose(faulty.signal("speed"), speed_profile(t))
    np.testing.assert_allclose(faulty.signal("steering", "u"), steering_profile(t))
    v = faulty.signal("speed")
    assert 14 < v.min() and v.max() < 27  # around the paper's 75 km/h mean (20.83 m/s)


def test_simulation_is_the_lpv_model_of_the_parity_design():
    """With δ = 0 and d = 0 the simulated plant is (48) itself: the exact-mode LPV residual vanishes
    outside the fault and equals the fault response inside."""
    tr = varrier_trace(delta=0.0, disturbance=0.0, duration=170.0)
    lpv = varrier_lateral_lpv()
    rho = rho_from_speed(tr.signal("speed"))
    r = lpv_parity_residuals(lpv, tr, rho, 3, mode="exact").r
    faulty, healthy = fault_window_masks(tr, 3)
    assert np.abs(r[healthy]).max() < 1e-10
    assert np.abs(r[faulty]).max() > 0.1


def test_window_masks_normalisation_and_score():
    """ϖ = min|r_n| faulty / max|r_n| healthy, r_n = r / mean(r faulty) (§5.5, Remark 8); edge windows excluded."""
    tr = varrier_trace(duration=170.0, delta=0.0, disturbance=0.0)
    faulty, healthy = fault_window_masks(tr, 3)
    assert faulty.sum() == 400 - 3  # windows [k−3, k] entirely inside the 400 faulty samples
    assert healthy.sum() == len(tr) - 3 - (400 + 3)
    assert not (faulty & healthy).any()
    r = np.zeros(len(tr))
    r[faulty] = -2.0 + 0.5 * np.sin(np.arange(faulty.sum()))
    r[healthy] = 0.25 * np.cos(np.arange(healthy.sum()))
    rn = normalise_residual(r, faulty)
    assert rn[faulty].mean() == pytest.approx(1.0, rel=1e-12)
    expected = np.abs(r[faulty]).min() / np.abs(r[healthy]).max()
    assert min_max_ratio(r, faulty, healthy) == pytest.approx(expected, rel=1e-12)
    assert min_max_ratio(-3 * r, faulty, healthy) == pytest.approx(expected, rel=1e-12)  # scale and sign free
    with pytest.raises(DataError, match="normalised"):
        normalise_residual(np.zeros(len(tr)), faulty)
    with pytest.raises(DataError, match="no faulty sample"):
        fault_window_masks(varrier_trace(duration=10.0), 3)
    with pytest.raises(ParameterError, match="fault_window"):
        varrier_trace(fault_window=(158.0, 150.0))


ULPV = ("ulpv_lmi", "ulpv_adjugate", "ulpv_theorem1", "ulpv_constant")


@pytest.mark.parametrize("seed", range(5))
def test_ulpv_separates_the_fault_and_lpv_does_not_paper_values_not_reproduced(seed):
    """§5.5: ϖ_LPV = 1.39 and ϖ_LPVu = 4.04 in the paper — not reproduced: here ϖ_LPV = 0.89 and
    ϖ_LPVu = 1.23 (LMI), 1.23 (adjugate), 1.36 (pointwise Theorem 1), 1.12 (constant fault) for seed 0.

    Reproduced, and asserted for seeds 0–4: the paper's conclusion that the U-LPV residual rejects the
    unmodelled dynamics better — every U-LPV variant scores higher than the LPV residual.  The margin is
    the meaning of ϖ: ϖ > 1 means one threshold separates every faulty sample from every healthy one, and
    each U-LPV variant is above 1 while the LPV residual is below (its healthy peaks exceed its faulty
    minimum, the "large amplitudes" the paper reports for LPV).  Over seeds 0–19 ϖ_LPV lies in 0.25–0.91
    and the U-LPV variants in 1.06–1.62 (the smallest is 6 % above 1); the SDP of the LMI design moves
    ϖ by ~1e-3 between BLAS kernels, far inside these margins.  Also checked: every residual is
    normalised to mean one over the fault and the U-LPV design has κ < κ_max.
    """
    tr = varrier_trace(seed=seed)
    cmp = varrier_comparison(tr)
    faulty, _ = fault_window_masks(tr, 3)
    assert set(cmp.varpi) == {"lpv", *ULPV}
    for name, res in cmp.residuals.items():
        assert np.isfinite(cmp.varpi[name]) and cmp.varpi[name] > 0
        assert res.r[faulty, 0].mean() == pytest.approx(1.0, rel=1e-9)
    assert cmp.design.kappa < cmp.design.kappa_max
    assert cmp.varpi["lpv"] < 1.0, cmp.varpi
    assert min(cmp.varpi[name] for name in ULPV) > 1.0, cmp.varpi
