"""State-space LTI/LPV parity space (Varrier, Koenig & Martinez 2014, §3).

Oracles: brute-force simulation of the (time-varying) recursion over the window; the defining
identity P H_os = 0 and scipy's null space; the internal form (plant + generator) on a frequency
grid; residuals of simulated LPV data (exactly zero when healthy, scaling with |Δρ| when ρ is frozen).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from fdikit import FaultModel
from fdikit.design.parity.state_space import (
    lpv_parity_residuals,
    minimal_horizon,
    parity_design,
    parity_matrix,
    regular_rows,
)
from fdikit.errors import DataError, DesignError, ModelError, ParameterError
from fdikit.lpv import (
    LPVModel,
    Uncertainty,
    lpv_stacked_matrices,
    stacked_matrices,
    uncertain_stacked_matrices,
)
from fdikit.plants.varrier_lateral import varrier_lateral_lpv, varrier_uncertainty
from fdikit.trace import Trace


def _random_model(rng, n=3, p=2, dt=0.1) -> FaultModel:
    return FaultModel(
        rng.standard_normal((n, n)) * 0.5, rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 2)),
        Du=rng.standard_normal((p, 2)), Bd=rng.standard_normal((n, 1)), Dd=rng.standard_normal((p, 1)),
        Bf=rng.standard_normal((n, 1)), Df=rng.standard_normal((p, 1)), dt=dt,
    )


def _simulate_window(models, x0, v):
    """y(k+i) for the window by the recursion itself; v[i] = [u; d; f; w] at sample i."""
    x, ys = x0, []
    for m, vi in zip(models, v):
        ys.append(m.C @ x + m.D @ vi)
        x = m.A @ x + m.B @ vi
    return np.concatenate(ys)


def _stack_inputs(v, sl):
    return np.concatenate([vi[sl] for vi in v])


def _check_identity(st, models, rng):
    n, nv = models[0].n, models[0].B.shape[1]
    for _ in range(5):
        x0, v = rng.standard_normal(n), rng.standard_normal((len(models), nv))
        Y = _simulate_window(models, x0, v)
        pred = st.H_os @ x0 + st.H_us @ _stack_inputs(v, slice(0, 2)) + st.H_ds @ _stack_inputs(v, slice(2, 3))
        pred = pred + st.H_fs @ _stack_inputs(v, slice(3, 4))
        np.testing.assert_allclose(Y, pred, rtol=1e-12, atol=1e-12 * np.abs(Y).max())


def test_lti_stacking_matches_simulation_and_markov_form():
    """Note item 3 (LTI): Y_s − H_os x − H_us U_s − H_ds U_ds − H_fs F_s ≡ 0; H_os = [C; CA; CA²; CA³]."""
    rng = np.random.default_rng(1)
    m = _random_model(rng)
    st = stacked_matrices(m, 3)
    _check_identity(st, [m] * 4, rng)
    np.testing.assert_allclose(st.H_os, np.vstack([m.C @ np.linalg.matrix_power(m.A, i) for i in range(4)]))
    np.testing.assert_allclose(st.H_us[6:8, 0:2], m.C @ m.A @ m.A @ m.Bu)  # block (3, 0): C A² B
    assert st.H_us.shape == (8, 8) and st.H_fs.shape == (8, 4) and st.H_ws.shape == (8, 0)


def test_time_varying_stacking_matches_simulation():
    """Note item 3 (exact time-varying): the corrected (7)–(8) with ρ_k … ρ_{k+s}."""
    rng = np.random.default_rng(2)
    models = [_random_model(rng) for _ in range(4)]
    _check_identity(stacked_matrices(models), models, rng)


@pytest.mark.parametrize("mode", ["frozen", "exact"])
def test_lpv_vehicle_stacking_matches_simulation(mode):
    rng = np.random.default_rng(3)
    lpv = varrier_lateral_lpv()
    for _ in range(3):
        rho = rng.uniform(0.02, 0.2, 4) if mode == "exact" else rng.uniform(0.02, 0.2)
        st = lpv_stacked_matrices(lpv, rho, 3, mode=mode)
        models = [lpv.at(r) for r in np.broadcast_to(rho, 4)]
        n, nv = 2, 3
        x0, v = rng.standard_normal(n), rng.standard_normal((4, nv))
        Y = _simulate_window(models, x0, v)
        pred = st.H_os @ x0 + st.H_us @ v[:, 0] + st.H_ds @ v[:, 1] + st.H_fs @ v[:, 2]
        np.testing.assert_allclose(Y, pred, rtol=1e-12, atol=1e-12 * np.abs(Y).max())


def test_batched_stacking_equals_pointwise():
    lpv = varrier_lateral_lpv()
    rho = np.array([0.03, 0.1, 0.5])
    batch = lpv_stacked_matrices(lpv, rho, 3)
    for i, r in enumerate(rho):
        np.testing.assert_allclose(batch.H_os[i], stacked_matrices(lpv.at(r), 3).H_os, rtol=1e-14)
        np.testing.assert_allclose(batch.H_us[i], stacked_matrices(lpv.at(r), 3).H_us, rtol=1e-14)


def test_vehicle_parity_matrix():
    """Note item 5: P(ρ) H_os(ρ) = 0 to 1e-12; rank H_os = n = 2; H_os1 = C0 (rows 0, 1); q = 6.

    P(0.048)'s first two columns match an independent reconstruction (five decimals)."""
    lpv = varrier_lateral_lpv()
    assert minimal_horizon(2, 2) == 1  # (13): s = E(n/m) = 1
    rhos = np.linspace(0.0, 0.7, 36)
    H = lpv_stacked_matrices(lpv, rhos, 3).H_os
    P = parity_matrix(H, (0, 1))
    assert P.shape == (36, 6, 8)
    rel = np.abs(P @ H).max(axis=(1, 2)) / (np.abs(P).max(axis=(1, 2)) * np.abs(H).max(axis=(1, 2)))
    assert rel.max() < 1e-14
    assert all(np.linalg.matrix_rank(h) == 2 for h in H)
    assert regular_rows(H[5]) == (0, 1)
    np.testing.assert_array_equal(P[:, :, 2:], np.broadcast_to(np.eye(6), (36, 6, 6)))
    p48 = parity_matrix(lpv_stacked_matrices(lpv, 0.048, 3).H_os)
    printed = [[-0.91033, -1.56475], [0.00553, -0.89557], [-0.82006, -2.82579], [0.00998, -0.79340],
               [-0.73091, -3.81389], [0.01347, -0.69492]]
    np.testing.assert_allclose(p48[:, :2], printed, atol=5e-6)
    # the rows of P span the whole left null space of H_os (scipy's orthonormal basis)
    N = scipy.linalg.null_space(lpv_stacked_matrices(lpv, 0.048, 3).H_os.T)
    assert np.max(scipy.linalg.subspace_angles(p48.T, N)) < 1e-10


def test_regular_rows_skips_dependent_rows():
    H = np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    assert regular_rows(H) == (0, 2)
    P = parity_matrix(H)
    np.testing.assert_allclose(P @ H, 0, atol=1e-15)
    with pytest.raises(DesignError, match="rank 1"):
        regular_rows(np.array([[1.0, 2.0], [2.0, 4.0]]))
    with pytest.raises(DesignError, match="singular"):
        parity_matrix(H, rows=(0, 1))


def test_lti_generator_decouples_state_and_inputs():
    """The FIR generator's internal form: u → r is zero on the unit circle, f → r is not."""
    rng = np.random.default_rng(4)
    m = _random_model(rng)
    d = parity_design(m, 2)
    assert d.q == 3 and d.generator.n == 2 * (2 + 2)  # s samples of [u; y]
    R = d.generator.internal_form(m)
    w = np.linspace(0, np.pi / m.dt, 40)
    assert np.abs(R.freqresp(w, "u")).max() < 1e-10
    assert np.abs(R.freqresp(w, "f")).max() > 0.1
    # Run on a simulated trace: after the s start-up samples r = Wᵀ(Y_s − H_us U_s) exactly, and = 0 when healthy.
    N = 60
    u, x = rng.standard_normal((N, 2)), rng.standard_normal(3)
    y = np.empty((N, 2))
    for k in range(N):
        y[k] = m.C @ x + m.Du @ u[k]
        x = m.A @ x + m.Bu @ u[k]
    tr = Trace(t=np.arange(N) * m.dt, u=u, y=y, controls=m.controls, outputs=m.outputs)
    r = d.generator.run(tr).r
    assert np.abs(r[2:]).max() < 1e-10 * np.abs(y).max()
    np.testing.assert_allclose(d.generator.online().run(tr).r, r, atol=1e-12)


def _lpv_trace(lpv, rho, u, x0, fault=None):
    N = rho.size
    A, B, C, D = lpv.matrices(rho)
    x, y = x0, np.empty((N, 2))
    for k in range(N):
        y[k] = C[k] @ x + D[k][:, 0] * u[k]
        x = A[k] @ x + B[k][:, 0] * u[k]
    if fault is not None:
        y[:, 0] += fault
    return Trace(t=np.arange(N) * lpv.dt, u=u[:, None], y=y, controls=lpv.controls, outputs=lpv.outputs)


def test_lpv_residual_is_zero_on_healthy_data():
    """Note item 6: constant speed (frozen) and varying speed (exact mode) give r ≡ 0 (< 1e-10)."""
    lpv = varrier_lateral_lpv()
    rng = np.random.default_rng(5)
    N = 500
    u = 0.02 * np.sin(np.arange(N) * 0.05) + 0.002 * rng.standard_normal(N)
    x0 = np.array([0.01, 0.05])
    const = np.full(N, 1 / 20.0)
    r = lpv_parity_residuals(lpv, _lpv_trace(lpv, const, u, x0), const, 3)
    assert r.r.shape == (N, 6) and not r.valid[:3].any() and np.isnan(r.r[:3]).all()
    assert np.abs(r.r[3:]).max() < 1e-10
    varying = 1 / (20 + 8 * np.sin(np.arange(N) * 0.02))
    tr = _lpv_trace(lpv, varying, u, x0)
    assert np.abs(lpv_parity_residuals(lpv, tr, varying, 3, mode="exact").r[3:]).max() < 1e-10
    assert np.abs(lpv_parity_residuals(lpv, tr, varying, 3, mode="frozen").r[3:]).max() > 1e-6


def test_frozen_residual_scales_with_the_speed_variation():
    """Note item 6: the frozen-ρ error is first order in max |Δρ| per sample (measured ratio ≈ 2)."""
    lpv = varrier_lateral_lpv()
    N = 400
    u = 0.02 * np.sin(np.arange(N) * 0.07)
    peaks = []
    for slope in (1e-5, 2e-5):
        rho = 0.05 + slope * np.arange(N)
        tr = _lpv_trace(lpv, rho, u, np.zeros(2))
        peaks.append(np.abs(lpv_parity_residuals(lpv, tr, rho, 3, W2=np.ones(6)).r[3:]).max())
    assert peaks[1] / peaks[0] == pytest.approx(2.0, rel=0.02)


def test_fault_enters_within_s_samples_and_leaves_s_samples_after():
    """Note item 7: r = Wᵀ P H_fs F_s; nonzero from the onset sample, zero again s samples after the end."""
    lpv = varrier_lateral_lpv()
    N, k0, k1, s = 120, 50, 70, 3
    rho = np.full(N, 1 / 25.0)
    f = np.where((np.arange(N) >= k0) & (np.arange(N) < k1), 0.5, 0.0)
    u = 0.01 * np.cos(np.arange(N) * 0.1)
    r = lpv_parity_residuals(lpv, _lpv_trace(lpv, rho, u, np.array([0.0, 0.02]), f), rho, s, W2=np.ones(6)).r[:, 0]
    quiet = np.r_[np.arange(s, k0), np.arange(k1 + s, N)]
    assert np.abs(r[quiet]).max() < 1e-10
    st = lpv_stacked_matrices(lpv, 1 / 25.0, s)
    P = parity_matrix(st.H_os)
    for k in range(k0, k1 + s):
        np.testing.assert_allclose(r[k], np.ones(6) @ P @ st.H_fs @ f[k - s:k + 1], rtol=1e-9, atol=1e-12)
    assert abs(r[k0]) > 0.1  # the newest sample already carries the fault: detection delay 0 ≤ s samples


def test_uncertain_expansion_reproduces_the_perturbed_model():
    """Note item 4: Σ δ^d H̃^(d) + nominal = stacked matrices of Ā = A0 + δ A1; monomial counts 3, 2, 2."""
    lpv = varrier_lateral_lpv()
    unc = varrier_uncertainty()
    us = uncertain_stacked_matrices(lpv, [unc], 0.048, 3)
    assert us.monomials("os") == [(1,), (2,), (3,)]
    assert us.monomials("u") == [(1,), (2,)] and us.monomials("d") == [(1,), (2,)] and us.monomials("f") == []
    for delta in (-0.7, 0.3, 1.0):
        pert = lpv.at(0.048).replace(A=lpv.at(0.048).A + delta * unc.A[0])
        ref = stacked_matrices(pert, 3)
        for kind, H in (("os", ref.H_os), ("u", ref.H_us), ("d", ref.H_ds)):
            nominal = us.nominal.H_os if kind == "os" else us.nominal.H[kind]
            total = nominal + sum(delta ** e[0] * M for e, M in us.tilde[kind].items())
            np.testing.assert_allclose(total, H, rtol=1e-12, atol=1e-14)
    # two uncertainties, one on C: mixed monomials δ1^a δ2^b up to degree s + 1
    rng = np.random.default_rng(6)
    u2 = Uncertainty(A=0.1 * rng.standard_normal((2, 2)), C={1: 0.1 * rng.standard_normal((2, 2))}, n=2, p=2)
    us2 = uncertain_stacked_matrices(lpv, [unc, u2], 0.1, 2)
    assert max(sum(e) for e in us2.monomials("os")) == 3 and (1, 1) in us2.tilde["os"]
    d1, d2 = 0.4, -0.8
    m = lpv.at(0.1)
    pert = m.replace(A=m.A + d1 * unc.A[0] + d2 * u2.A[0], C=m.C + d2 * 0.1 * u2.C[1])
    total = us2.nominal.H_os + sum(d1 ** e[0] * d2 ** e[1] * M for e, M in us2.tilde["os"].items())
    np.testing.assert_allclose(total, stacked_matrices(pert, 2).H_os, rtol=1e-12, atol=1e-14)


def test_bad_input_is_refused():
    rng = np.random.default_rng(7)
    m = _random_model(rng)
    lpv = varrier_lateral_lpv()
    with pytest.raises(ModelError, match="discrete"):
        parity_design(m.replace(dt=None), 2)
    with pytest.raises(DesignError, match="no parity"):
        parity_design(m, 0)  # (s+1) p = 2 <= n = 3
    with pytest.raises(DesignError, match="trivial"):
        parity_design(m, 2, W2=np.zeros(3))
    with pytest.raises(ParameterError, match="horizon"):
        stacked_matrices(m)
    with pytest.raises(ModelError, match="same"):
        LPVModel({0: m, 1: m.replace(dt=0.2)})
    tr = Trace(t=np.arange(10) * 0.02, u=np.zeros((10, 1)), y=np.zeros((10, 2)), controls=lpv.controls,
               outputs=lpv.outputs)
    with pytest.raises(DataError, match="one scheduling value per sample"):
        lpv_parity_residuals(lpv, tr, np.full(9, 0.05), 3)
    with pytest.raises(ModelError, match="exact"):
        lpv_stacked_matrices(lpv, 0.05, 3, mode="exact")
