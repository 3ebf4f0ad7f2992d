"""§2.4.1 B747 with B and C from JSBSim's B747 instead of the substitute (Hallouzi 2008, §2.4.1, Tables 2.5–2.6)."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.plants.b747 import b747_longitudinal, b747_model_set
from fdikit.plants.b747_jsbsim import b747_jsbsim_matrices
from fdikit.studies.hallouzi2008.b747 import INTERVALS, b747_monte_carlo, b747_snr, b747_trace

_LON = [1, 3, 4, 7, 9]  # q, V_TAS, α, θ, h in fdikit.aircraft.plant.STATES
_IN = 0.0254  # m per inch
_SLUG_FT2 = 14.59390293720636 * 0.3048**2  # kg m² per slug ft²


@pytest.fixture(scope="module")
def jsb():
    """The cached linearisation and a second, independent B747 at the same trim (state, surfaces, throttle)."""
    from fdikit.aircraft import JSBSimAircraft

    lin = b747_jsbsim_matrices()
    ac = JSBSimAircraft("B747")
    ac.set_mass(lin.mass)
    ac.set_state(lin.trim.x)
    ac.set_throttles(lin.trim.throttle)
    return lin, ac, ac.snapshot()


def test_trim_point_and_selector(jsb):
    lin, ac, _ = jsb
    tr = lin.trim
    assert tr.converged and tr.x[3] == 133.8 and tr.x[9] == 600.0  # §2.4.1: 600 m, 133.8 m/s, level
    assert tr.positions["elevator"] == 0.0 and tr.positions["flap"] == 0.0  # trimmed with the stabiliser
    np.testing.assert_array_equal(lin.C, np.eye(5)[[0, 1, 2, 4]])  # q, V, α, h
    assert lin.B.shape == (5, 6) and not lin.B.flags.writeable
    assert b747_jsbsim_matrices() is lin  # cached per process
    with pytest.raises(ParameterError, match="airspeed"):
        b747_jsbsim_matrices(airspeed=-1.0)


def test_surface_columns_against_a_wider_central_difference(jsb):
    """δ_c column against ±10⁻² rad of elevator (the module uses 10⁻³).  JSBSim's B747 elevator terms are
    linear in δe, so both differences have no truncation error; rounding of ẋ (|ẋ| ≲ 10, ε = 2e-16) over
    2h gives ≲ 1e-13 per rad — rtol 1e-8 with an absolute floor 1e-10 for the zero θ̇, ḣ rows.
    δ_s is fdikit's stabiliser: the elevator terms ×STABILIZER_GAIN (2)."""
    from fdikit.aircraft import STABILIZER_GAIN

    lin, ac, snap = jsb
    tr, h = lin.trim, 1e-2
    f = []
    for d in (h, -h):
        f.append(ac.derivatives(tr.x, {**tr.positions, "elevator": d}))
        ac.restore(snap)
    np.testing.assert_allclose(lin.B[:, 0], (f[0] - f[1])[_LON] / (2 * h), rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(lin.B[:, 1], STABILIZER_GAIN * lin.B[:, 0], rtol=1e-8, atol=1e-10)
    assert lin.B[0, 0] < 0 and lin.B[2, 0] < 0  # trailing edge down: nose down, lift up (α̇ < 0 per rad)


def test_engine_columns_against_total_thrust_and_kinematics(jsb):
    """Per-engine thrust columns [per N of one engine] vs independent computations at the same trim:

    * their mean equals the total-thrust column of ``linearize_aircraft`` (1 N of total thrust = ¼ N on each
      of 4 equal engines, forces add); rtol 1e-6 bounds the h² truncation of each difference (h = 10⁻³);
    * thrust along the body x axis: ``V̇ = cos α / m`` and ``α̇ = −sin α / (m V)`` per N (rtol 1e-6, same bound);
    * pitch: engines sit below the CG (JSBSim z −97 in outer, −121 in inner, CG −26 in), so every column
      pitches nose-up and the inner ones more, by exactly their 24 in lower thrust line over I_yy; and the
      inner engine's q̇ equals (propulsion + aerodynamic pitch moment change)/I_yy read from JSBSim.
    """
    from fdikit.aircraft import linearize_aircraft

    lin, ac, snap = jsb
    tr, B = lin.trim, lin.B
    total = linearize_aircraft(ac, tr).model
    ac.restore(snap)
    np.testing.assert_allclose(B[:, 2:].mean(axis=1), total.B[_LON, total.controls.index("thrust")],
                               rtol=1e-6, atol=1e-15)
    alpha, V = tr.x[4], tr.x[3]
    np.testing.assert_allclose(B[1, 2:], np.cos(alpha) / lin.mass, rtol=1e-6)
    np.testing.assert_allclose(B[2, 2:], -np.sin(alpha) / (lin.mass * V), rtol=1e-6)
    np.testing.assert_array_equal(B[3:, 2:], 0.0)
    np.testing.assert_allclose(B[:, 2], B[:, 5], rtol=1e-9)  # symmetric engines 1 and 4, 2 and 3
    np.testing.assert_allclose(B[:, 3], B[:, 4], rtol=1e-9)
    fdm = ac.fdm
    Iyy = fdm["inertia/iyy-slugs_ft2"] * _SLUG_FT2
    z_cg = fdm["inertia/cg-z-in"]
    assert 0 < B[0, 2] < B[0, 3]  # outer < inner, both nose-up
    np.testing.assert_allclose((B[0, 3] - B[0, 2]) * Iyy, 24 * _IN, rtol=1e-6)
    thr, m, T = np.full(4, tr.throttle), [], []
    for d in (1e-3, -1e-3):  # engine 2 alone; moments in lbf ft → N m
        thr[1] = tr.throttle + d
        ac.derivatives(tr.x, tr.positions, thr)
        m.append(np.array([fdm["moments/m-prop-lbsft"], fdm["moments/m-aero-lbsft"]]) * 4.4482216152605 * 0.3048)
        T.append(ac.thrust()[1])
        ac.restore(snap)
    dm = (m[0] - m[1]) / (T[0] - T[1])
    np.testing.assert_allclose(dm[0], (z_cg + 121) * _IN, rtol=1e-6)  # propulsion: the thrust line's arm
    np.testing.assert_allclose(B[0, 3], dm.sum() / Iyy, rtol=1e-6)


def test_jsbsim_model_set_has_table_2_5_structure():
    """Table 2.5 with the JSBSim B: models 2/3 zero the δ_c/δ_s column, 4/5 the V/α entry of C; A is (2.56)."""
    lin = b747_jsbsim_matrices()
    models = b747_model_set(dt=None, b_source="jsbsim")
    nom = models[0]
    np.testing.assert_array_equal(nom.B, lin.B)
    np.testing.assert_array_equal(nom.C, lin.C)
    np.testing.assert_array_equal(nom.A, b747_longitudinal().A)  # A is thesis data
    for k, col in ((1, 0), (2, 1)):
        np.testing.assert_array_equal(models[k].B[:, col], 0.0)
        keep = [j for j in range(6) if j != col]
        np.testing.assert_array_equal(models[k].B[:, keep], nom.B[:, keep])
        np.testing.assert_array_equal(models[k].C, nom.C)
    for k, (i, j) in ((3, (1, 1)), (4, (2, 2))):
        assert models[k].C[i, j] == 0.0 and np.count_nonzero(models[k].C - nom.C) == 1
        np.testing.assert_array_equal(models[k].B, nom.B)
    np.testing.assert_array_equal(b747_longitudinal(a_source="jsbsim", b_source="jsbsim").A, lin.A_jsbsim)
    with pytest.raises(ParameterError, match="b_source"):
        b747_longitudinal(b_source="thesis")
    with pytest.raises(ParameterError, match="a35 applies"):
        b747_longitudinal(a35="printed", a_source="jsbsim")


def test_jsbsim_a_modes_next_to_the_corrected_a():
    """JSBSim's A against the corrected (2.56): a stable short period and phugoid of similar frequency
    (1.135 vs 1.154 rad/s; 0.087 vs 0.093 rad/s), and a stable height mode where (2.56) has +0.00065."""
    ev = np.sort_complex(np.linalg.eigvals(b747_jsbsim_matrices().A_jsbsim))
    np.testing.assert_allclose(ev, np.sort_complex([-0.7487 + 1.1350j, -0.7487 - 1.1350j, -0.00347 + 0.08703j,
                                                    -0.00347 - 0.08703j, -0.00099]), atol=1e-4)


def test_jsbsim_snr_and_reduced_monte_carlo_reproduce_the_substitute_claims():
    """The claims checked for the substitute (tests/studies/hallouzi2008/test_scenarios_b747.py) on the JSBSim
    B, one 5-run Monte Carlo (seed 0): all hold.

    SNR (thesis ≈ 35 dB; default σ_δ = 2.1 rad): > 31 dB on all four.  State RMSE ≲ 0.14 (thesis) before the
    V-sensor fault for the dual CMF and the IMM, and for the EKF up to 700; in the V fault the IMM (> 0.5) and the
    dual CMF fail it and the EKF is the lowest.  Weights: both CM filters beat the IMM in every fault interval
    (EKF by 10 %), the IMM beats both in the fault-free intervals between the faults, the dual CMF the EKF.
    Measured: state before 800 dual CMF ≤ 0.124, IMM ≤ 0.061, EKF ≤ 0.105 to 700; V fault 0.61 / 0.16 / 2.23.
    """
    snr = b747_snr(b747_trace(3, b_source="jsbsim"))
    assert np.all(snr > 31), snr
    r = b747_monte_carlo(runs=5, seed=0, b_source="jsbsim")
    s = r.summary
    before = [k for k, (a, b) in INTERVALS.items() if b < 800]
    for f in ("dual_cmf", "imm"):
        assert max(s[f][k]["state"] for k in before) < 0.14, (f, s[f])
    assert max(s["ekf"][k]["state"] for k, (a, b) in INTERVALS.items() if b <= 700) < 0.14, s["ekf"]
    v = {f: s[f]["V_TAS_20"]["state"] for f in r.filters}
    assert v["imm"] > 0.5 and v["dual_cmf"] > 0.14 and v["ekf"] < min(v["dual_cmf"], v["imm"]), v
    for k in ("alpha_30", "delta_s_40", "delta_c_50", "V_TAS_20"):
        assert s["dual_cmf"][k]["weights"] < s["imm"][k]["weights"], k
        assert s["ekf"][k]["weights"] < 0.9 * s["imm"][k]["weights"], k
    for k in ("nominal_2", "nominal_3", "nominal_4"):
        assert s["imm"][k]["weights"] < s["dual_cmf"][k]["weights"] < s["ekf"][k]["weights"], k
    for f in r.filters:
        np.testing.assert_allclose(r.mean_weights[f].sum(axis=1), 1.0, atol=1e-8)
