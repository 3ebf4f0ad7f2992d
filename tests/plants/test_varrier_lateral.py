"""Renault Scénic LPV lateral model (Varrier, Koenig & Martinez 2014, §5.1, (47)–(48)).

Oracles: the parameter table of §5.1; the entries of (48) written out by hand from the table
(six significant digits); forward Euler of the continuous model;
the kinematic identity a_y = v (β' + r); eigenvalues computed with numpy.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.lpv import LPVModel
from fdikit.plants.varrier_lateral import (
    RHO_STAR,
    SCENIC,
    T_D,
    VarrierParameters,
    rho_from_speed,
    varrier_lateral,
    varrier_lateral_continuous,
    varrier_lateral_lpv,
    varrier_uncertainty,
)


def test_parameters_are_the_table_of_section_5_1():
    p = SCENIC
    assert (p.m, p.l_V, p.l_H, p.I_z, p.c_V, p.c_H, p.g) == (1621, 1.15, 1.38, 1975, 57117, 81396, 9.80665)
    assert (RHO_STAR, T_D) == (0.048, 0.02)  # §5.3: rho* = 1/20.83 = 0.048; s = 3 samples = 60 ms
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.m = 1.0  # type: ignore[misc]
    with pytest.raises(ParameterError, match="c_V"):
        VarrierParameters(c_V=-57117.0)


def test_discrete_matrices_at_rho_star():
    """Note §5 item 1 (values of (48) at T_d = 0.02, rho = 0.048, six significant digits)."""
    m = varrier_lateral(1 / 0.048)
    np.testing.assert_allclose(m.A, [[0.917969, -0.0186741], [0.472323, 0.887936]], atol=5e-7)
    np.testing.assert_allclose(m.Bu.ravel(), [0.0338262, 0.665160], atol=5e-7)
    np.testing.assert_allclose(m.C, [[-85.44911, 1.38113], [0.0, 1.0]], atol=5e-6)
    np.testing.assert_allclose(m.Du.ravel(), [35.23566, 0.0], atol=5e-6)
    # §5.3: B_d = 0.2 B0(0.048), D_d = [0; 2.064]; §5.4: additive a_y fault.
    np.testing.assert_allclose(m.Bd.ravel(), [0.0067653, 0.133032], atol=5e-7)
    np.testing.assert_array_equal(m.Dd.ravel(), [0.0, 2.064])
    np.testing.assert_array_equal(m.Df.ravel(), [1.0, 0.0])
    np.testing.assert_array_equal(m.Bf.ravel(), [0.0, 0.0])
    assert m.dt == 0.02 and m.outputs == ("lateral_acceleration", "yaw_rate")


def test_polynomial_form_is_48_with_rho2_equal_rho_squared():
    """Note §5 item 2: A0 = A00 + rho A01 + rho^2 A02; polynomial and direct (48) agree to 1e-12."""
    lpv = varrier_lateral_lpv()
    assert isinstance(lpv, LPVModel) and lpv.degree == 2
    Td = 0.02
    a = (81396 * 1.38 - 57117 * 1.15)  # l_H c_H − l_V c_V = 46641.93
    np.testing.assert_allclose(lpv.terms[0].A, [[1, -Td], [Td * a / 1975, 1]], rtol=1e-15)
    quad = 1.15**2 * 57117 + 1.38**2 * 81396  # l_V² c_V + l_H² c_H
    np.testing.assert_allclose(lpv.terms[1].A, np.diag([-Td * 138513 / 1621, -Td * quad / 1975]), rtol=1e-14)
    np.testing.assert_allclose(lpv.terms[2].A, [[0, Td * a / 1621], [0, 0]], rtol=1e-15)
    m_, lV, lH, Iz, cV, cH = 1621, 1.15, 1.38, 1975, 57117, 81396
    for rho in np.linspace(0.0, 0.7, 15):
        rho1, rho2 = rho, rho**2  # the paper's two scheduling parameters, (48a)-(48c) term by term
        A = (np.array([[1, -Td], [Td * (lH * cH - lV * cV) / Iz, 1]])
             + rho1 * np.array([[-Td * (cV + cH) / m_, 0], [0, -Td * (lV**2 * cV + lH**2 * cH) / Iz]])
             + rho2 * np.array([[0, Td * (lH * cH - lV * cV) / m_], [0, 0]]))
        B = np.array([[0], [Td * lV * cV / Iz]]) + rho1 * np.array([[Td * cV / m_], [0]])
        C = np.array([[-(cV + cH) / m_, 0], [0, 1]]) + rho1 * np.array([[0, (lH * cH - lV * cV) / m_], [0, 0]])
        m = lpv.at(rho)
        np.testing.assert_allclose(m.A, A, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(m.Bu, B, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(m.C, C, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(m.Du, [[cV / m_], [0]], rtol=1e-15)
        Ap, Bp, Cp, Dp = lpv.matrices(rho)
        np.testing.assert_allclose(Ap, m.A, atol=1e-12)
        np.testing.assert_allclose(Cp, m.C, atol=1e-12)


@pytest.mark.parametrize("speed", [3.0, 10.0, 20.83, 45.0])
def test_euler_of_the_corrected_continuous_model_is_48(speed):
    """A0 = I + T_d A, B0 = T_d B, C0 = C, D0 = D (§5.1 'rectangular' discretisation)."""
    c = varrier_lateral_continuous(speed)
    d = varrier_lateral(speed, dt=0.02)
    np.testing.assert_allclose(d.A, np.eye(2) + 0.02 * c.A, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(d.Bu, 0.02 * c.Bu, rtol=1e-14)
    np.testing.assert_allclose(d.C, c.C, rtol=1e-14)
    np.testing.assert_allclose(d.Du, c.Du, rtol=1e-14)


@pytest.mark.parametrize("speed", [5.0, 20.83, 40.0])
def test_lateral_acceleration_is_v_times_sideslip_rate_plus_yaw_rate(speed):
    """a_y = v (β' + r): confirms the 1/v (not 1/v² as printed) of (47)'s a_y row and the r' sign."""
    m = varrier_lateral_continuous(speed)
    np.testing.assert_allclose(m.C[0], speed * (m.A[0] + [0.0, 1.0]), rtol=1e-13)
    np.testing.assert_allclose(m.Du[0], speed * m.Bu[0], rtol=1e-13)
    assert m.A[1, 1] < 0  # yaw damping: the minus sign missing in the printed (47)
    assert np.all(np.linalg.eigvals(m.A).real < 0)


def test_c0_is_invertible_for_every_rho():
    """Note M5: det C0 = −(c_V + c_H)/m = −85.449 for all rho, so H_os1 = C0 (s >= 1)."""
    lpv = varrier_lateral_lpv()
    dets = [np.linalg.det(lpv.at(r).C) for r in np.linspace(0, 1, 11)]
    np.testing.assert_allclose(dets, -138513 / 1621, rtol=1e-14)
    assert -138513 / 1621 == pytest.approx(-85.449, abs=5e-4)


def test_forward_euler_stability_limit():
    """Note §4.5: max |eig A0| = 1.62 at 1 m/s, 0.74 at 1.5 m/s (unstable below about 1.3 m/s)."""
    def radius(v):
        return max(abs(np.linalg.eigvals(varrier_lateral(v).A)))

    assert radius(1.0) == pytest.approx(1.62, abs=0.005)
    assert radius(1.5) == pytest.approx(0.74, abs=0.005)
    assert radius(1.2) > 1 > radius(1.4)


def test_uncertainty_readings():
    """§5.3 A1 = 0.2 A0(0.048), literal (value computed by hand) and the 'continuous' reading 0.2 (A0 − I)."""
    lit = varrier_uncertainty()
    np.testing.assert_allclose(lit.A[0], [[0.18359, -0.0037348], [0.094465, 0.17759]], atol=5e-6)
    np.testing.assert_array_equal(lit.C[0], np.zeros((2, 2)))
    cont = varrier_uncertainty(mode="continuous")
    np.testing.assert_allclose(cont.A[0], 0.2 * 0.02 * varrier_lateral_continuous(1 / 0.048).A, rtol=1e-12)
    with pytest.raises(ParameterError, match="literal"):
        varrier_uncertainty(mode="physical")


def test_bad_input_is_refused():
    with pytest.raises(ParameterError, match="positive"):
        varrier_lateral(0.0)
    with pytest.raises(ParameterError, match="positive"):
        rho_from_speed([10.0, -1.0])
    with pytest.raises(ParameterError, match="dt"):
        varrier_lateral_lpv(dt=0.0)
    assert rho_from_speed(20.0) == 0.05
    np.testing.assert_array_equal(rho_from_speed([10.0, 20.0]), [0.1, 0.05])
