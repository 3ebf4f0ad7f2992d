"""MSD OD model set + augmented EKF (Hallouzi 2008, §3.6.2, Table 3.3, Figs 3.8–3.9)."""

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from fdikit.errors import ParameterError
from fdikit.metrics import vaf
from fdikit.multimodel.model_set import vectorize
from fdikit.plants.msd import msd_matrices, msd_model_vectors, msd_parameter_grid
from fdikit.studies.hallouzi2008.msd import msd_od_model_set, run_msd_filter, simulate_msd

DT = 0.01


@pytest.fixture(scope="module")
def sim():
    return simulate_msd(seed=0, dt=DT)


@pytest.fixture(scope="module")
def ekf(sim):
    return run_msd_filter(sim, msd_od_model_set(DT), "ekf")


def _window(sim, a, b):
    return (sim.t >= a) & (sim.t < b)


def test_vaf_matches_definition_3_53():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(500, 2))
    xh = x + 0.3 * rng.normal(size=(500, 2))
    expected = [100 * (1 - np.var(x[:, j] - xh[:, j]) / np.var(x[:, j])) for j in range(2)]
    assert np.allclose(vaf(x, xh), expected)
    assert vaf(x, -3 * x).tolist() == [0.0, 0.0]  # clipped at 0 by the max{·, 0} of (3.53)


def test_simulation_matches_expm_zoh_and_snr(sim):
    """The series ZOH equals scipy's expm transition; the output noise is 60 dB below the signal (§3.6.2)."""
    x, M = np.zeros(6), np.zeros((8, 8))
    for k in range(1500):
        A, B, _ = msd_matrices(*sim.params[k])
        M[:6, :6], M[:6, 6:] = A * DT, B * DT
        E = scipy.linalg.expm(M)
        x = E[:6, :6] @ x + E[:6, 6:] @ sim.u[k]
    assert np.abs(x - sim.x[1500]).max() < 1e-10 * np.abs(sim.x[:1500]).max()
    y0 = np.column_stack([sim.x[:, 0], sim.params[:, 3] * sim.x[:, 1], sim.x[:, 2]])
    snr = 20 * np.log10(np.sqrt(np.mean(y0 ** 2, 0)) / np.sqrt(np.mean((sim.y - y0) ** 2, 0)))
    assert np.allclose(snr, 60.0, atol=0.25)  # measured 60.02, 60.12, 59.93 dB (10^4 samples)
    # faults of the assumed scenario: f1 = 0.5 on [30, 50) s, f2 = 0.5 on [70, 80) s
    assert set(np.unique(sim.params[:, 2])) == {0.5, 1.0} and np.all(sim.params[_window(sim, 30, 50), 2] == 0.5)


def test_od_set_structure_and_nominal_models_not_convex():
    """§3.6.1, Table 3.2: rank 5 → 6 models: two nominal, two with f1 = 0, two with f2 = 0, every fault
    parameter at a limit (what the Fig. 3.9 sums need).  The two nominal models span only a line in
    (k1, 1/m3) (as Table 3.2's models 3 and 5 do), so the healthy centre (k1, m3) = (1, 1) has affine but no
    convex weights: the reason run_msd_filter leaves the weights unprojected.

    The members are fixed by the tie rule of ``pivoted_qr`` (not by LAPACK's rounding), so this exact set
    is designed on every BLAS kernel; the 6th model, beyond the rank, is also the one farthest (in the
    model-vector norm) from the first five among the models with both faults at a limit."""
    ms = msd_od_model_set(DT)
    assert ms.rank == 5 and ms.parameters.shape == (6, 4)
    np.testing.assert_allclose(ms.parameters, [[0.25, 0.2, 1, 1], [1.75, 1.8, 1, 1], [1.75, 0.2, 1, 0],
                                                  [0.25, 1.8, 1, 0], [0.25, 0.2, 0, 1], [0.25, 0.6, 0, 1]], rtol=1e-15)
    assert np.all(np.isin(ms.parameters[:, 2:], (0.0, 1.0)))
    assert len(ms.actuator_fault) == 2 and len(ms.sensor_fault) == 2
    nominal = np.flatnonzero((ms.parameters[:, 2] == 1) & (ms.parameters[:, 3] == 1))
    assert len(nominal) == 2
    grid = msd_parameter_grid(np.linspace(0.25, 1.75, 5), np.linspace(0.2, 1.8, 5), [0.0, 0.5, 1.0])
    M = msd_model_vectors(grid, dt=DT)
    at_limits = np.flatnonzero(np.isin(grid[:, 2], (0, 1)) & np.isin(grid[:, 3], (0, 1)))
    gaps = [min(np.linalg.norm(M[:, j] - M[:, i]) for i in ms.indices[:5]) for j in at_limits]
    assert at_limits[int(np.argmax(gaps))] == ms.indices[5]
    V = np.column_stack([vectorize(a, b, c) for a, b, c in zip(ms.A, ms.B, ms.C)])
    A, B, C = msd_matrices(1.0, 1.0)
    target = vectorize(np.eye(6) + DT * A, DT * B, C)
    Aeq = np.vstack([V, np.ones(6)])
    beq = np.concatenate([target, [1.0]])
    w = np.linalg.lstsq(Aeq, beq, rcond=None)[0]
    assert np.abs(Aeq @ w - beq).max() < 1e-12 and w.min() < -0.1  # exact, but with a negative weight
    lp = scipy.optimize.linprog(np.zeros(6), A_eq=Aeq, b_eq=beq, bounds=[(0, None)] * 6, method="highs")
    assert lp.status == 2  # infeasible: no convex combination reproduces the healthy centre


def test_ekf_reconstructs_faults(sim, ekf):
    """Fig. 3.9 relations f1 = 1 − Σμ̂(f1=0 models), f2 likewise.  Measured (seed 0, the same on the
    Prescott, Haswell and SkylakeX kernels to 1e-11): f2 mean 0.523 on [72, 80) (truth 0.5), ≥ 0.995 when
    healthy; f1 converges in ≈ 10 s (only u1 excites it): mean 0.527 on [40, 50), 0.995 on [5, 30), and
    recovers as slowly after the fault: 0.57 at 50–52.5 s, 0.79 at 55–60 s, 0.89 at 62.5–70 s, mean 0.851
    on [60, 70).  Tolerances are about twice the measured errors (seeds 1, 2 give the same figures to 0.01)."""
    f1, f2 = ekf.f1, ekf.f2
    assert abs(f2[_window(sim, 72, 80)].mean() - 0.5) < 0.05
    assert f2[_window(sim, 5, 70)].mean() > 0.98 and f2[_window(sim, 85, 100)].mean() > 0.98
    assert abs(f1[_window(sim, 40, 50)].mean() - 0.5) < 0.1
    assert f1[_window(sim, 5, 30)].mean() > 0.95
    assert f1[_window(sim, 60, 70)].mean() > 0.7
    assert f1[_window(sim, 50, 55)].mean() < f1[_window(sim, 55, 60)].mean() < f1[_window(sim, 60, 70)].mean()
    # the reconstructed varying parameters follow the trajectory (mean abs error over 5–100 s)
    s = _window(sim, 5, 100)
    assert np.abs(ekf.params[s, 0] - sim.params[s, 0]).mean() < 0.1
    assert np.abs(ekf.params[s, 1] - sim.params[s, 1]).mean() < 0.25  # measured 0.218 (k1: 0.070)


def test_ekf_state_vaf_table_3_3(ekf):
    """Table 3.3 (OD): x1 100, x2 95.9, x3 100, v1 99.2, v2 97.1, v3 99.1 %.  Measured here: 100, 99.5, 100,
    98.9, 98.2, 99.0 %; all > 90 % and v2 lowest, as in the thesis (x2 is not second lowest here)."""
    v = ekf.vaf
    assert min(v.values()) > 97.0
    assert v["x1"] > 99.9 and v["x3"] > 99.9
    assert min(v, key=v.get) == "v2"
    assert np.isclose(sum(ekf.mu[-1]), 1.0, atol=0.01)


def test_bad_input_raises(sim):
    with pytest.raises(ParameterError, match="filter must be"):
        run_msd_filter(sim, msd_od_model_set(DT), "imm")
    with pytest.raises(ParameterError, match="discretised at"):
        run_msd_filter(sim, msd_od_model_set(2.5e-3))
    with pytest.raises(ParameterError, match="f1_size"):
        simulate_msd(f1_size=1.5)
    with pytest.raises(ParameterError, match="too coarse"):
        simulate_msd(dt=0.1)


def test_table_3_4_od_set_is_16_times_better_conditioned():
    """§3.6.4, Table 3.4: the OD set {0.2, 1.8} beats the minimum-mismatch set {0.8651, 1.1349} in every
    realization, by the thesis's factor (printed ratios 2.24e6/1.39e5 = 16.1 … 3.57e6/2.21e5 = 16.15).

    The ratio equals the ratio of the model separations in 1/m3 (16.17) to 0.1 %; measured 16.169 (short runs).
    """
    from fdikit.studies.hallouzi2008.msd import msd_observability_comparison

    r = msd_observability_comparison(realizations=3, n_steps=300, samples=30, seed=1)
    assert sorted(r.od_models.tolist()) == [0.2, 1.8]
    np.testing.assert_allclose(r.mismatch_models, [0.8651, 1.1349], atol=5e-5)
    assert np.all(r.od < r.mismatch)
    assert r.predicted_ratio == pytest.approx((1 / 0.2 - 1 / 1.8) / (1 / 0.86510 - 1 / 1.13490), rel=1e-4)
    np.testing.assert_allclose(r.ratio, r.predicted_ratio, rtol=2e-3)
    thesis = np.array([2.24e6 / 1.39e5, 2.5e6 / 1.55e5, 2.13e6 / 1.32e5, 2.24e6 / 1.39e5, 3.57e6 / 2.21e5])
    assert np.all(np.abs(r.ratio.mean() / thesis - 1) < 0.01)


@pytest.fixture(scope="module")
def table_3_3(sim):
    from fdikit.studies.hallouzi2008.msd_model_sets import msd_table_3_3

    return msd_table_3_3(sim)


def test_table_3_3_all_sets_track_states_and_faults(sim, table_3_3):
    """Table 3.3 / item 20: state VAF > 90 % for the OD, CP and LV sets, v2 the lowest in each (thesis: x2, v2
    lowest); f1, f2 reconstructed in their fault windows and ≈ 1 outside.

    Measured (seed 0, T_s = 0.01 s): VAF OD 100/99.5/100/98.9/98.2/99.0, LV 100/99.1/100/99.7/98.7/99.9 on every
    kernel; CP v2 95.2 (Prescott), 97.2 (Haswell), 98.4 (SkylakeX): its base simplex is still picked by LAPACK's
    pivoted QR, whose ties rounding decides (thesis OD 100/95.9/100/99.2/97.1/99.1, CP …/95.4/…/96.8/…,
    LV …/91.5/…/95.7/…).
    """
    for name, run in table_3_3.items():
        v = run.vaf
        assert min(v.values()) > 90.0, (name, v)
        assert min(v, key=v.get) == "v2", (name, v)
        assert v["x1"] > 99.9 and v["x3"] > 99.5
        p = run.params
        assert abs(p[_window(sim, 42, 50), 2].mean() - 0.5) < 0.1, name  # f1 = 0.5 in [30, 50) s
        assert abs(p[_window(sim, 72, 80), 3].mean() - 0.5) < 0.1, name  # f2 = 0.5 in [70, 80) s
        assert p[_window(sim, 5, 30), 2].mean() > 0.95 and p[_window(sim, 5, 70), 3].mean() > 0.95, name


def test_cp_reconstruction_is_quantised_and_lv_is_smooth(sim, table_3_3):
    """§3.6.2, Figs 3.7–3.11: the CP parameters come from the nearest grid model (3.51)–(3.52), the LV ones from
    the maps (3.54)–(3.57); LV tracks m3 best (measured mean |error| 0.043 against CP 0.17, OD 0.16)."""
    cp, lv = table_3_3["cp"].params, table_3_3["lv"].params
    grid_k1 = np.linspace(0.25, 1.75, 5)
    assert np.all(np.isin(np.round(cp[:, 0], 12), np.round(grid_k1, 12)))
    assert np.unique(lv[:, 0]).size > 1000
    s = _window(sim, 5, 100)
    err = {k: np.abs(r.params[s, 1] - sim.params[s, 1]).mean() for k, r in table_3_3.items()}
    assert err["lv"] < 0.5 * min(err["od"], err["cp"]), err
    w = table_3_3["lv"].mu
    assert w.min() >= 0 and w.max() <= 1  # box constraint of (3.39)


def test_lv_convex_set_reproduces_the_msd_matrices():
    """Item 8 through the filter's model: the LV blend at the (3.54)–(3.57) weights equals the first-order
    discretised MSD for any (k1, m3, f1, f2) in range."""
    from fdikit.multimodel.convex import limit_value_convex_set
    from fdikit.multimodel.model_set import first_order_discretize
    from fdikit.studies.hallouzi2008.msd_model_sets import msd_lv_model_set

    ms = limit_value_convex_set(msd_lv_model_set(DT), Q=np.eye(6), R=np.eye(3))
    rng = np.random.default_rng(0)
    for _ in range(5):
        k1, m3, f1, f2 = rng.uniform(0.25, 1.75), rng.uniform(0.2, 1.8), rng.uniform(), rng.uniform()
        mu = [(1.75 - k1) / 1.5, (1 / m3 - 1 / 1.8) / (1 / 0.2 - 1 / 1.8), 1 - f1, 1 - f2]
        A, B, C = msd_matrices(k1, m3, f1, f2)
        Ad, Bd = first_order_discretize(A, B, DT)
        got = ms.blend(mu)
        for a, b in zip(got[:3], (Ad, Bd, C)):
            np.testing.assert_allclose(a, b, atol=1e-12)
