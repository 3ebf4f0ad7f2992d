"""PATH App. D linear vehicle models (Douglas et al. 1996): spectra, structure, names."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import linear_sum_assignment

from fdikit import FaultModel
from fdikit.plants import (
    TABLE_2_1_EIGENVALUES_12,
    TABLE_2_1_EIGENVALUES_14,
    path_vehicle_12,
    path_vehicle_14,
    rounding_intervals,
)

STATES_12 = ["m_a", "omega_e", "v_x", "v_y", "v_z", "z", "phi", "phi_dot", "theta", "theta_dot", "eps_dot", "tau_b"]
STATES_14 = STATES_12[:11] + ["alpha", "tau_b", "beta"]
OUTPUTS = [
    "air_mass", "engine_speed", "accel_x", "accel_y", "accel_z", "roll_rate", "pitch_rate", "yaw_rate",
    "wheel_speed_fl", "wheel_speed_fr", "wheel_speed_rl", "wheel_speed_rr",
]
#: Table 2.1 prints eigenvalues to 2 decimals: real and imaginary parts are each +-0.005.
TABLE_ROUNDING = 0.005 * np.sqrt(2)
N_MONTE_CARLO = 2000


def _pair(reference: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` reordered so that entry i is the one closest to ``reference[i]`` (optimal matching)."""
    rows, cols = linear_sum_assignment(np.abs(np.subtract.outer(reference, values)))
    out = np.empty(len(reference), dtype=complex)
    out[rows] = values[cols]
    return out


def _first_order_bound(A: np.ndarray, half_width: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
    """Worst-case first-order eigenvalue shift for entrywise perturbations ``|dA_jk| <= half_width_jk``.

    ``d lambda = y^H dA x / (y^H x)`` (y, x left/right eigenvectors), so
    ``|d lambda| <= |y|^T H |x| / |y^H x|``: the entrywise refinement of ``kappa_i * ||dA||``.
    """
    w, vl, vr = scipy.linalg.eig(A, left=True, right=True)
    out = []
    for lam in eigenvalues:
        i = int(np.argmin(np.abs(w - lam)))
        y, x = vl[:, i], vr[:, i]
        out.append(np.abs(y) @ half_width @ np.abs(x) / abs(np.vdot(y, x)))
    return np.array(out)


@pytest.mark.parametrize(
    ("build", "n", "table"),
    [(path_vehicle_12, 12, TABLE_2_1_EIGENVALUES_12), (path_vehicle_14, 14, TABLE_2_1_EIGENVALUES_14)],
    ids=["path12", "path14"],
)
def test_spectrum_matches_table_2_1_within_the_rounding_of_the_data(build, n, table):
    """Eigenvalues of the reconstructed A vs Table 2.1 (method 1), with a tolerance from the rounding.

    The App. D entries are printed to 2 decimals, so each true entry lies in the interval
    of :func:`rounding_intervals` (+-0.005, or [-0.005, 0] for "-0.00"; exact zeros and
    kinematic ones are exact).  Table 2.1 was computed from the unrounded model and is
    itself rounded to 2 decimals.  So the printed eigenvalue must lie within

        (how far rounding of A can move the eigenvalue) + 0.005*sqrt(2)  (Table rounding).

    How far rounding moves each eigenvalue is measured two ways, and both must agree:

    * Monte Carlo: 2000 matrices with every rounded entry drawn uniformly in its interval
      (seed 0); the spread is max |lambda_sample - lambda_nominal| per eigenvalue.
    * First order, worst case: ``|y|^T H |x| / |y^H x|`` with H the interval half-widths
      (the entrywise form of the condition-number bound kappa_i ||dA||, which here is
      about 20x looser, e.g. kappa = 117 for the -26.46 pair).  The Monte Carlo spread
      must not exceed it by more than 5 % (second-order terms), i.e. the bound is valid.

    The printed value must lie inside the Monte Carlo spread plus the Table rounding.
    The worst-conditioned pair -26.46 +- 4.32i is computed as -26.467 +- 4.395i (off by
    0.076, spread 0.23); -0.049 is computed as -0.055 (off by 0.006, spread 0.07).  A
    wrong sign or a misplaced entry moves eigenvalues by O(1) and fails.
    """
    model = build()
    lo, hi = rounding_intervals(n)["A"]
    assert np.all(lo <= model.A) and np.all(model.A <= hi)
    printed = np.asarray(table, dtype=complex)
    nominal = _pair(printed, scipy.linalg.eigvals(model.A))

    rng = np.random.default_rng(0)
    spread = np.zeros(len(printed))
    for _ in range(N_MONTE_CARLO):
        sample = _pair(nominal, scipy.linalg.eigvals(rng.uniform(lo, hi)))
        spread = np.maximum(spread, np.abs(sample - nominal))

    bound = _first_order_bound(model.A, np.maximum(hi - model.A, model.A - lo), nominal)
    assert np.all(spread <= 1.05 * bound), (spread, bound)

    miss = np.abs(nominal - printed)
    tolerance = spread + TABLE_ROUNDING
    assert np.all(miss <= tolerance), [(p, z, m, t) for p, z, m, t in zip(printed, nominal, miss, tolerance) if m > t]


def test_spectrum_of_rounded_data_as_recomputed_in_the_research_note():
    """eig(A12) recomputed independently from the same transcription of App. D; pin it to 3 decimals."""
    expected = np.array([
        -26.467 + 4.395j, -26.467 - 4.395j, -7.527 + 2.956j, -7.527 - 2.956j, -2.822 + 5.604j, -2.822 - 5.604j,
        -2.064 + 6.530j, -2.064 - 6.530j, -1.437 + 5.498j, -1.437 - 5.498j, -1.25, -0.0550,
    ])
    computed = _pair(expected, scipy.linalg.eigvals(path_vehicle_12().A))
    np.testing.assert_allclose(computed.real, expected.real, atol=5e-4)
    np.testing.assert_allclose(computed.imag, expected.imag, atol=5e-4)


def test_14_state_spectrum_is_12_state_spectrum_plus_actuator_poles():
    """The throttle/steering actuators are in series (rows alpha, beta hold only their diagonal),
    so eig(A14) = eig(A12) U {-90.91, -80} exactly; the tolerance is eps-level, 1e-12 ||A14||_F (~4e-9)."""
    a12, a14 = path_vehicle_12().A, path_vehicle_14().A
    expected = np.concatenate([scipy.linalg.eigvals(a12), [-90.91, -80.0]])
    computed = _pair(expected, scipy.linalg.eigvals(a14))
    assert np.max(np.abs(computed - expected)) <= 1e-12 * np.linalg.norm(a14)


def test_14_state_model_contains_the_12_state_model():
    """A14 restricted to the 12 shared states is A12; C likewise; the residualised actuators give B12."""
    m12, m14 = path_vehicle_12(), path_vehicle_14()
    idx = [m14.states.index(s) for s in m12.states]
    np.testing.assert_array_equal(m14.A[np.ix_(idx, idx)], m12.A)
    np.testing.assert_array_equal(m14.C[:, idx], m12.C)
    ia, ib, it = (m14.states.index(s) for s in ("alpha", "beta", "tau_b"))
    # Static actuator: alpha = throttle, beta = steering, so B12 = A14[:, alpha/beta] on the shared states.
    np.testing.assert_array_equal(m12.Bu[:, 0], m14.A[idx, ia])
    np.testing.assert_array_equal(m12.Bu[:, 2], m14.A[idx, ib])
    np.testing.assert_array_equal(m12.Bu[:, 1], m14.Bu[idx, 1])
    np.testing.assert_array_equal(m12.Du[:, 2], m14.C[:, ib])
    assert (m14.A[ia, ia], m14.A[ib, ib], m14.A[it, it]) == (-90.91, -80.0, -1.25)
    np.testing.assert_array_equal(m14.Bu[[ia, it, ib]], np.diag([90.91, 1.25, 80.0]))
    assert not np.any(m14.Bu[: ia]) and not np.any(m14.Du)


def test_throttle_fault_is_seen_only_through_air_mass():
    """Note §3.4: C F = 0 and C A F ∝ e_1 for F = B14[:, throttle] (throttle and air mass not output separable)."""
    m = path_vehicle_14()
    F = m.Bu[:, m.index("u", "throttle")[0]]
    scale = np.linalg.norm(m.C) * np.linalg.norm(F)
    assert np.linalg.norm(m.C @ F) <= 1e-14 * scale
    caf = m.C @ m.A @ F
    assert caf[0] == pytest.approx(2.35 * 90.91)  # air mass row: A[m_a, alpha] * B[alpha, throttle]
    assert np.linalg.norm(caf[1:]) <= 1e-14 * np.linalg.norm(m.A) * scale
    # Steering, by contrast, reaches the outputs directly (1-D detection space).
    assert np.linalg.norm(m.C @ m.Bu[:, 2]) > 100.0


def test_accelerometer_rows_are_state_derivative_rows():
    """Accelerometers measure v_x', v_y', v_z': C12 rows 3-5 = A12 rows 3-5 and D12 rows 3-5 = B12 rows 3-5."""
    m = path_vehicle_12()
    np.testing.assert_array_equal(m.C[2:5], m.A[2:5])
    np.testing.assert_array_equal(m.D[2:5], m.B[2:5])
    # The printed D has nonzeros only in the steering column, rows 3-5 (the "-0.00" wheel rows round to 0).
    nonzero = np.argwhere(m.Du != 0)
    assert sorted(map(tuple, nonzero)) == [(2, 2), (3, 2), (4, 2)]
    np.testing.assert_array_equal(m.Du[2:5, 2], [-1.09, 123.72, 0.04])


def test_output_selection_rows_and_transcription_choices():
    """Identity rows of C, the front-wheel engine-speed coupling taken as 0, and the roll damping sign."""
    for m in (path_vehicle_12(), path_vehicle_14()):
        for row, state in [(0, "m_a"), (1, "omega_e"), (5, "phi_dot"), (6, "theta_dot"), (7, "eps_dot")]:
            expected = np.zeros(m.n)
            expected[m.states.index(state)] = 1.0
            np.testing.assert_array_equal(m.C[row], expected)
        we = m.states.index("omega_e")
        np.testing.assert_array_equal(m.C[8:12, we], [0.0, 0.0, 0.04, 0.03])  # rear-wheel drive, see module doc
        pd = m.states.index("phi_dot")
        assert m.A[pd, pd] == -6.05  # 14-state listing lost this sign


def test_rounding_intervals_encode_the_print_format():
    """Exact zeros and kinematic ones have zero width; "-0.00" is [-0.005, 0]; rounded entries +-0.005."""
    m = path_vehicle_12()
    lo, hi = rounding_intervals(12)["A"]
    assert lo[0, 2] == hi[0, 2] == 0.0  # printed "0"
    assert lo[5, 4] == hi[5, 4] == 1.0  # z' = v_z
    assert (lo[2, 7], hi[2, 7]) == (-0.005, 0.0)  # printed "-0.00"
    assert (lo[4, 11], hi[4, 11]) == (0.0, 0.005)  # printed "0.00"
    assert hi[1, 8] - lo[1, 8] == pytest.approx(0.01) and m.A[1, 8] == -3169.84
    lo14, hi14 = rounding_intervals(14)["Bu"]
    assert (lo14[11, 0], hi14[11, 0]) == pytest.approx((90.905, 90.915))


def test_rounding_intervals_rejects_unknown_order():
    from fdikit.errors import ParameterError

    with pytest.raises(ParameterError, match="12 or 14"):
        rounding_intervals(13)


@pytest.mark.parametrize(("build", "states"), [(path_vehicle_12, STATES_12), (path_vehicle_14, STATES_14)])
def test_names_shapes_and_continuity(build, states):
    m = build()
    assert isinstance(m, FaultModel)
    assert m.dt is None and not m.is_discrete
    assert list(m.states) == states
    assert list(m.outputs) == OUTPUTS
    assert m.controls == ("throttle", "brake", "steering")
    assert m.disturbances == () and m.faults == () and m.noise == ()
    assert m.A.shape == (len(states),) * 2
    assert m.C.shape == (12, len(states))
    assert m.B.shape == (len(states), 3) and m.D.shape == (12, 3)


def test_table_constants():
    assert len(TABLE_2_1_EIGENVALUES_14) == 14 and len(TABLE_2_1_EIGENVALUES_12) == 12
    assert set(TABLE_2_1_EIGENVALUES_14) - set(TABLE_2_1_EIGENVALUES_12) == {-90.91, -80.0}
    # Complex eigenvalues come in conjugate pairs.
    values = np.array(TABLE_2_1_EIGENVALUES_14)
    np.testing.assert_array_equal(np.sort_complex(values), np.sort_complex(values.conj()))
