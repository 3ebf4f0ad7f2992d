"""PATH Ch. 9 7-state longitudinal model (Douglas et al. 1996, §9.6, (9.84)–(9.89)).

Oracles: the printed fault maps ``F = [f, A f]`` and their defining equations ``C f = e_i``, and the
spectrum computed independently after the A(2,3) sign fix (see fdikit.plants.path_longitudinal).
"""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.fault_maps import resolve_faults
from fdikit.plants.path_longitudinal import (
    PATH7_A,
    PATH7_A_PRINTED,
    PATH7_C,
    PATH7_C_PRINTED,
    PATH7_F_ACCEL_X,
    PATH7_F_ENGINE_SPEED,
    PATH7_OUTPUTS,
    path_longitudinal_7,
    path_longitudinal_7_fault_maps,
)

#: Independent computation: eig(A) after A(2,3) := +19.0734, printed to 3 decimals (4 for the slow pole).
EIG_FIXED = np.array([-31.585, -26.229, -2.319 + 6.649j, -2.319 - 6.649j, -1.535 + 5.693j, -1.535 - 5.693j, -0.0449])


def _sorted(z):
    return np.array(sorted(np.asarray(z, dtype=complex), key=lambda w: (round(w.real, 2), w.imag)))


def test_corrected_spectrum_matches_the_note_to_the_printed_decimals():
    ev = _sorted(np.linalg.eigvals(path_longitudinal_7().A))
    assert np.max(np.abs(ev - _sorted(EIG_FIXED))) < 6e-4


def test_printed_a23_sign_gives_an_unstable_eigenvalue_and_inconsistent_fault_maps():
    """As printed, eig(A) has +0.169 and A f − F(:,2) has row-2 errors −14.46 and −9.71."""
    ev = np.linalg.eigvals(PATH7_A_PRINTED)
    assert ev.real.max() == pytest.approx(0.169, abs=1e-3)
    err_w = PATH7_A_PRINTED @ PATH7_F_ENGINE_SPEED[:, 0] - PATH7_F_ENGINE_SPEED[:, 1]
    err_x = PATH7_A_PRINTED @ PATH7_F_ACCEL_X[:, 0] - PATH7_F_ACCEL_X[:, 1]
    assert err_w[1] == pytest.approx(-14.46, abs=0.01)
    assert err_x[1] == pytest.approx(-9.71, abs=0.01)
    # the ratio pins the error on column 3: f_w(3) / f_x(3) = 0.3791 / 0.2544
    assert err_w[1] / err_x[1] == pytest.approx(0.3791 / 0.2544, rel=2e-3)
    # one entry differs between printed and corrected A: (2,3), by 2 x 19.0734
    diff = np.argwhere(PATH7_A != PATH7_A_PRINTED)
    assert diff.tolist() == [[1, 2]]


@pytest.mark.parametrize("F", [PATH7_F_ENGINE_SPEED, PATH7_F_ACCEL_X], ids=["F_yw", "F_yxdd"])
def test_second_column_is_A_times_first_to_the_printed_rounding(F):
    """(9.89): F = [f, A f].  Measured residuals 2.2e-3 (F_yω) and 0.9e-3 (F_yẍ); ~ A's size x 5e-5 rounding."""
    assert np.max(np.abs(PATH7_A @ F[:, 0] - F[:, 1])) < 3e-3


def test_fault_maps_solve_C_f_equal_unit_vector_in_the_labelled_row_order():
    """C f_ω = e_2 and C f_ẍ = e_3 (E_yω, E_yẍ of (9.89)) with the rows of C in the labelled order."""
    C = path_longitudinal_7().C
    e = np.eye(7)
    assert np.max(np.abs(C @ PATH7_F_ENGINE_SPEED[:, 0] - e[1])) < 1.5e-3
    assert np.max(np.abs(C @ PATH7_F_ACCEL_X[:, 0] - e[2])) < 1.5e-3
    # the printed row order instead maps f_ẍ to e_1: printed rows 1 and 3 are exchanged
    assert np.max(np.abs(PATH7_C_PRINTED @ PATH7_F_ACCEL_X[:, 0] - e[0])) < 1.5e-3
    np.testing.assert_array_equal(PATH7_C[[0, 2]], PATH7_C_PRINTED[[2, 0]])
    np.testing.assert_array_equal(PATH7_C[[1, 3, 4, 5, 6]], PATH7_C_PRINTED[[1, 3, 4, 5, 6]])


def test_model_structure_and_names():
    m = path_longitudinal_7()
    assert (m.n, m.p, m.controls, m.faults) == (7, 7, (), ())
    assert m.outputs == PATH7_OUTPUTS
    assert m.outputs[:3] == ("air_mass", "engine_speed", "accel_x")
    assert not m.is_discrete
    assert np.linalg.cond(m.C) == pytest.approx(706, rel=5e-3)


def test_exact_sensor_maps_of_the_model_agree_with_the_printed_maps_to_the_rounding():
    """resolve_faults gives [C⁻¹e_i, A C⁻¹e_i]; printed maps differ by the 4-decimal rounding amplified by cond(C)."""
    m = path_longitudinal_7()
    exact = resolve_faults(m, ["engine_speed_sensor", "accel_x_sensor"])
    printed = path_longitudinal_7_fault_maps()
    assert list(printed) == list(exact) == ["engine_speed_sensor", "accel_x_sensor"]
    for name in exact:
        d = np.abs(exact[name] - printed[name])
        assert d[:, 0].max() < 0.06 and d[:, 1].max() < 0.25
        # relative to the column size the difference is a few 1e-3
        assert np.linalg.norm(exact[name] - printed[name]) / np.linalg.norm(printed[name]) < 3e-3


def test_fault_map_helper_returns_copies():
    maps = path_longitudinal_7_fault_maps()
    maps["engine_speed_sensor"][0, 0] = 99.0
    assert path_longitudinal_7_fault_maps()["engine_speed_sensor"][0, 0] == 0.2107
    with pytest.raises(ValueError):
        PATH7_F_ENGINE_SPEED[0, 0] = 1.0
