"""B747 linear longitudinal example, Hallouzi 2008, §2.4.1."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from fdikit.errors import ParameterError
from fdikit.plants.b747 import B747_FAULT_SCHEDULE, B747_MODEL_NAMES, B747_TRANSITION, b747_longitudinal, b747_model_set


def test_eigenvalues_corrected_and_printed_a35():
    """Hallouzi 2008, (2.56) erratum (spectra computed independently): A(3,5) = 6.83e-7 → −0.634±1.154j,
    −0.00234±0.0929j, +0.00065; printed 6.83e-1 → −0.341±9.560j, −0.291±1.130j, −0.00815."""
    ev = np.sort_complex(np.linalg.eigvals(b747_longitudinal().A))
    np.testing.assert_allclose(ev, np.sort_complex([-0.634 + 1.154j, -0.634 - 1.154j, -0.00234 + 0.0929j,
                                                    -0.00234 - 0.0929j, 0.00065]), atol=6e-4)
    ev = np.sort_complex(np.linalg.eigvals(b747_longitudinal(a35="printed").A))
    np.testing.assert_allclose(ev, np.sort_complex([-0.341 + 9.560j, -0.341 - 9.560j, -0.291 + 1.130j,
                                                    -0.291 - 1.130j, -0.00815]), atol=6e-4)


def test_height_row_is_v_times_theta_minus_alpha():
    A = b747_longitudinal().A
    np.testing.assert_array_equal(A[4], [0, 0, -134.0, 134.0, 0])  # ḣ ≈ V (θ − α), V = 134 ≈ 133.8 m/s


def test_fault_models_differ_in_one_column_or_entry_and_partial_faults_are_convex():
    """Table 2.5/2.6: each fault model changes one B column or one C entry, so a partial fault is the convex
    combination with the true weights of Table 2.6 (e.g. 30 % α-sensor fault = 0.7 nominal + 0.3 model 5)."""
    models = b747_model_set(dt=None)
    nom = models[0]
    assert np.count_nonzero(models[1].B - nom.B) == np.count_nonzero(nom.B[:, 0])
    assert np.count_nonzero(models[2].B - nom.B) == np.count_nonzero(nom.B[:, 1])
    assert np.count_nonzero(models[3].C - nom.C) == 1 and np.count_nonzero(models[4].C - nom.C) == 1
    for _, _, w in B747_FAULT_SCHEDULE:
        C = sum(wi * m.C for wi, m in zip(w, models))
        B = sum(wi * m.B for wi, m in zip(w, models))
        fault = int(np.argmax(w[1:])) + 1
        size = w[fault]
        C_true, B_true = nom.C.copy(), nom.B.copy()
        if fault == 1:
            B_true[:, 0] *= 1 - size
        elif fault == 2:
            B_true[:, 1] *= 1 - size
        elif fault == 3:
            C_true[1, 1] = 1 - size
        else:
            C_true[2, 2] = 1 - size
        np.testing.assert_allclose(C, C_true, atol=1e-15)
        np.testing.assert_allclose(B, B_true, atol=1e-15)
    assert [s[:2] for s in B747_FAULT_SCHEDULE] == [(200, 300), (400, 500), (600, 700), (800, 900)]


def test_zoh_discretisation_and_observability():
    m = b747_longitudinal(dt=0.01)
    np.testing.assert_allclose(m.A, scipy.linalg.expm(0.01 * b747_longitudinal().A), atol=1e-13)
    c = b747_longitudinal()
    O = np.vstack([c.C @ np.linalg.matrix_power(c.A, k) for k in range(5)])
    assert np.linalg.matrix_rank(O) == 5  # θ is unmeasured but observable through h
    np.testing.assert_allclose(B747_TRANSITION.sum(axis=1), 1.0)  # (2.63) is row-stochastic
    assert len(b747_model_set()) == len(B747_MODEL_NAMES) == 5


def test_bad_names():
    with pytest.raises(ParameterError, match="nominal"):
        b747_longitudinal("rudder")
    with pytest.raises(ParameterError, match="corrected"):
        b747_longitudinal(a35="6.83e-5")
