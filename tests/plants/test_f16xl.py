"""F-16XL plants: Murray 2012 §6.1 (4 states) and Douglas et al. 1996 App. C.5 (5 states with a Dryden gust).

The App. C.5 data are reconstructed from a damaged print; these tests pin the reconstruction to the numbers the
report prints elsewhere (F_Az, Murray's model of the same airframe).
"""

import numpy as np
import pytest
import scipy.linalg

from fdikit import fault_maps, linalg
from fdikit.errors import ParameterError
from fdikit.plants.f16xl import F16XL_A, F16XL_DRYDEN_GAIN, f16xl_gust, f16xl_longitudinal


def test_longitudinal_gust_column_is_the_w_column():
    """Murray 2012 §6.1: the gust enters like w (B_wg = column 2 of A), printed [0.0430, −1.4666, −1.6788, 0]."""
    m = f16xl_longitudinal()
    np.testing.assert_array_equal(m.Bd[:, 0], m.A[:, 1])
    np.testing.assert_array_equal(m.Bd[:, 0], [0.0430, -1.4666, -1.6788, 0.0])


def test_gust_model_contains_murrays_airframe():
    """App. C.5 and Murray §6.1 print the same A (4x4 block) and elevon column; B_δ(1) takes Murray's sign."""
    m, m4 = f16xl_gust(), f16xl_longitudinal()
    np.testing.assert_array_equal(m.A[:4, :4], F16XL_A)
    np.testing.assert_array_equal(m.Bu[:4], m4.Bu)
    assert m.Bu[0, 0] == -0.1672 and m.Bu[4, 0] == 0.0
    # the gust state enters like w in rows 1-3 (the reconstruction A(1,5) = 0.0430) and is a first-order lag
    np.testing.assert_array_equal(m.A[:3, 4], m.A[:3, 1])
    assert m.A[4, 4] == -1.1948 and not np.any(m.A[4, :4])


def test_printed_accelerometer_fault_map():
    """Douglas et al. 1996, App. C.5: F_Az normalised = [[0, 0.9986], [0, 0.0534], [0, 0], [1, 0], [0, 0]].

    This pins C(2,4) = 0 (C e_4 must be ∝ e_3) and C(3,4) = −0.0299 (F¹ = e_4/C(3,4)).
    """
    m = f16xl_gust()
    F, kind = fault_maps.resolve_fault(m, "y_Az_sensor")
    assert kind == "sensor"
    np.testing.assert_allclose(m.C @ F[:, 0], [0, 0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(F[:, 0], [0, 0, 0, 1 / -0.0299, 0], rtol=1e-12, atol=1e-12)
    Fn = F / np.linalg.norm(F, axis=0)
    Fn = Fn * np.sign(Fn[np.abs(Fn).argmax(axis=0), range(2)])  # the print drops the column signs
    printed = np.array([[0, 0.9986], [0, 0.0534], [0, 0], [1, 0], [0, 0]])
    np.testing.assert_allclose(Fn, printed, atol=5e-5)


def test_faults_have_no_invariant_zeros_and_are_mutually_detectable():
    """App. C.5: (C, A, F¹_Az), (C, A, F²_Az), (C, A, F_δ) have no invariant zeros, the minimal
    unobservability subspaces are the fault directions, and the faults are mutually detectable."""
    m = f16xl_gust()
    F_az = fault_maps.resolve_fault(m, "y_Az_sensor")[0]
    F_d = m.Bu
    for F in (F_az[:, [0]], F_az[:, [1]], F_d, F_az):
        zeros, _ = linalg.invariant_zeros(m.A, m.C, F)
        assert zeros.size == 0
        T = linalg.detection_space(m.A, m.C, F)
        assert T.shape[1] == F.shape[1] and linalg.contains(F, T)
    ok, joint, _ = linalg.mutually_detectable(m.A, m.C, [F_az, F_d])
    assert ok and joint.size == 0
    assert linalg.output_separable(m.C, [F_az, F_d])[0]


@pytest.mark.parametrize("gain, variance", [(F16XL_DRYDEN_GAIN, 1.0), (1.57, 1.57**2 / (2 * 1.1948))])
def test_gust_variance(gain, variance):
    """Dryden first-order gust: stationary var(w_g) = B_ω²/(2 V/L) under unit-PSD noise (Lyapunov, scipy)."""
    m = f16xl_gust(gust_gain=gain)
    Bw = m.Bw[:, [0]]
    X = scipy.linalg.solve_continuous_lyapunov(m.A, -Bw @ Bw.T)
    assert X[4, 4] == pytest.approx(variance, rel=1e-12)


def test_noise_channels_and_options():
    """Sensor noises reach only their own outputs (D = diag(d_q, 0.143, 0.245, 0.245)); wind only the gust state."""
    m = f16xl_gust(pitch_rate_noise=0.02, az_w_coefficient=1.0517)
    np.testing.assert_array_equal(m.Dw[:, 1:], np.diag([0.02, 0.143, 0.245, 0.245]))
    assert not np.any(m.Dw[:, 0]) and not np.any(m.Bw[:, 1:]) and m.Bw[4, 0] == 1.57
    assert m.C[2, 1] == 1.0517 and f16xl_gust().C[2, 1] == -1.0517
    with pytest.raises(ParameterError, match="pitch_rate_noise"):
        f16xl_gust(pitch_rate_noise=-0.01)
