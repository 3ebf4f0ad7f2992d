"""subspace_id: exact recovery noise-free, unbiased with noise (Monte Carlo), order selection, gaps, noise model."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats

from fdikit import FaultModel
from fdikit.design import kalman
from fdikit.errors import DataError, FdiWarning, ParameterError
from fdikit.identify import subspace_id
from fdikit.simulate import simulate
from fdikit.trace import Trace

# A known 4-state system (1 control, 2 outputs) in innovation form; eigenvalues 0.9 ± 0.3j, 0.7, −0.5.
A = np.array([[0.9, 0.3, 0, 0], [-0.3, 0.9, 0, 0], [0, 0, 0.7, 0], [0, 0, 0, -0.5]])
B = np.array([[1.0], [0.5], [1.0], [1.0]])
C = np.array([[1.0, 0, 1.0, 0], [0, 1.0, 0, 1.0]])
K = np.array([[0.3, 0.0], [0.0, 0.2], [0.2, 0.1], [0.0, 0.3]])
TRUE = np.sort_complex(np.linalg.eigvals(A))
PLANT = FaultModel(A=A, Bu=B, C=C, Bw=K, Dw=np.eye(2), controls=["u"], outputs=["y0", "y1"], noise=["e0", "e1"],
                   dt=0.1)


def run(samples, seed, noise_std=0.0):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((samples, 1))
    return simulate(PLANT, t=np.arange(samples) * 0.1, u=u, noise_std=noise_std, rng=rng)


def rel_eig_error(ident) -> float:
    return float(np.max(np.abs(np.sort_complex(ident.poles) - TRUE) / np.abs(TRUE)))


def markov(A_, B_, C_, D_, k=8):
    out, M = [D_], B_
    for _ in range(k):
        out.append(C_ @ M)
        M = A_ @ M
    return np.array(out)


@pytest.mark.parametrize("method", ["n4sid", "moesp"])
def test_noise_free_recovers_eigenvalues_and_markov_parameters(method):
    tr = run(2000, 0)
    ident = subspace_id(tr, None, method=method, detrend=False)
    assert ident.order == 4, ident.order_rule
    # Noise-free data from a 4-state system: the identification is exact up to rounding (relative 1e-6 is
    # the specification; rounding gives about 1e-13 for these condition numbers).
    assert rel_eig_error(ident) < 1e-6
    m = ident.model
    assert m.dt == tr.dt and m.controls == ("u",) and m.outputs == ("y0", "y1")
    # the input-output map is basis-free: Markov parameters D, CB, CAB ... match the plant's
    np.testing.assert_allclose(markov(m.A, m.Bu, m.C, m.Du), markov(A, B, C, np.zeros((2, 1))),
                               atol=1e-6 * np.abs(markov(A, B, C, 0 * B[:2])).max())
    # the singular values drop by orders of magnitude after the 4th
    s = ident.singular_values
    assert s[4] < 1e-8 * s[3]


def test_gaps_and_invalid_samples_split_the_record_and_multiple_experiments_pool():
    tr = run(3000, 1)
    y = tr.y.copy()
    y[1000:1010] = np.nan
    valid = np.ones(len(tr), bool)
    valid[2000:2005] = False
    y[2000:2005] = 1e6  # garbage under valid == False: never used
    gappy = Trace(t=tr.t, u=tr.u, y=y, controls=tr.controls, outputs=tr.outputs, valid=valid)
    ident = subspace_id(gappy, 4, detrend=False)
    assert ident.segments == 3 and ident.samples == 3000 - 15
    assert rel_eig_error(ident) < 1e-6
    # two experiments (different seeds), one model
    ident2 = subspace_id([run(600, 2), run(700, 3)], 4, detrend=False)
    assert ident2.segments == 2 and rel_eig_error(ident2) < 1e-6


def test_short_segments_are_dropped_with_a_warning_or_refused():
    tr = run(400, 4)
    y = tr.y.copy()
    y[10] = np.nan  # the first 10 samples are too short a segment for horizon 10 (needs 21)
    gappy = Trace(t=tr.t, u=tr.u, y=y, controls=tr.controls, outputs=tr.outputs)
    with pytest.warns(FdiWarning, match="10 usable samples"):
        subspace_id(gappy, 4, detrend=False)
    y[::15] = np.nan
    gappy = Trace(t=tr.t, u=tr.u, y=y, controls=tr.controls, outputs=tr.outputs)
    with warnings.catch_warnings(), pytest.raises(DataError, match="no segment of at least 21"):
        warnings.simplefilter("ignore", FdiWarning)
        subspace_id(gappy, 4)


def test_noise_model_feeds_kalman_and_operating_point_is_the_mean():
    tr = run(3000, 5, noise_std=0.3)
    offset = Trace(t=tr.t, u=tr.u + 2.0, y=tr.y + [1.0, -3.0], controls=tr.controls, outputs=tr.outputs)
    ident = subspace_id(offset, 4)
    np.testing.assert_allclose(ident.u_mean, tr.u.mean(axis=0) + 2.0, rtol=1e-12)
    np.testing.assert_allclose(ident.model.operating_point.output_values(["y0", "y1"]),
                               tr.y.mean(axis=0) + [1.0, -3.0], rtol=1e-12)
    assert ident.model.noise == ("y0_innovation", "y1_innovation")
    # the innovation form as a noise model: kalman with Q = R on w = e (Dw = I) and no extra sensor noise
    # reproduces K (the Riccati solution is P = 0 when the noise enters as the innovation)
    design = kalman(ident.model, Q=ident.R, R=0.0)
    np.testing.assert_allclose(design.gain, ident.K, rtol=1e-6, atol=1e-9 * np.abs(ident.K).max())
    np.testing.assert_allclose(design.innovation_covariance, ident.R, rtol=1e-6)


def test_with_noise_the_estimates_are_unbiased_and_the_order_is_found():
    # Monte Carlo over R seeds: for each quantity q (the real parts of -0.5, 0.7, 0.9 ± 0.3j, the imaginary part
    # 0.3, and the innovation variances 0.09), t = (mean(q̂) − q) / (s / √R) is Student t with R − 1 degrees of
    # freedom when the estimator is (asymptotically) unbiased and normal.  Two-sided Bonferroni over the
    # 2 methods × 6 quantities at a total level 1e-3: |t| < t_{1 − 1e-3 / 24}(R − 1) (≈ 6.3 for R = 8).
    R, q_true = 8, np.r_[TRUE.real[[0, 1, 2]], 0.3, 0.09, 0.09]
    crit = stats.t.ppf(1 - 1e-3 / 24, R - 1)
    traces = [run(2000, 100 + s, noise_std=0.3) for s in range(R)]
    for method in ("n4sid", "moesp"):
        est = []
        for tr in traces:
            ident = subspace_id(tr, None, method=method, horizon=10)
            assert ident.order == 4, ident.order_rule
            ev = np.sort_complex(ident.poles)
            est.append([ev[0].real, ev[1].real, ev[2].real, abs(ev[2].imag), ident.R[0, 0], ident.R[1, 1]])
        est = np.array(est)
        t = (est.mean(axis=0) - q_true) / (est.std(axis=0, ddof=1) / np.sqrt(R))
        assert np.all(np.abs(t) < crit), (method, t.round(2).tolist())


def test_bad_arguments():
    tr = run(300, 6)
    with pytest.raises(ParameterError, match="horizon"):
        subspace_id(tr, 30, horizon=5)
    with pytest.raises(ParameterError):
        subspace_id(tr, method="cva")
    const = Trace(t=tr.t, u=np.ones((300, 1)), y=tr.y, controls=tr.controls, outputs=tr.outputs)
    with pytest.raises(DataError, match="constant"):
        subspace_id(const, 4)
    with pytest.raises(DataError, match="Trace"):
        subspace_id([], 4)


def test_identification_does_not_depend_on_units():
    # Every signal is divided by its standard deviation before the projections and the scaling is undone on the
    # result, so an output in other units (here y0 x 1e3) gives the same poles, and the same model up to the
    # output scaling.  Noise-free, both runs are exact up to rounding (~1e-13 for this conditioning): 1e-8.
    tr = run(2000, 0)
    scaled = Trace(t=tr.t, u=tr.u, y=tr.y * [1e3, 1.0], controls=tr.controls, outputs=tr.outputs)
    a, b = subspace_id(tr, detrend=False), subspace_id(scaled, detrend=False)
    assert a.order == b.order == 4
    np.testing.assert_allclose(np.sort_complex(b.poles), np.sort_complex(a.poles), rtol=1e-8)
    ma, mb = a.model, b.model
    np.testing.assert_allclose(markov(mb.A, mb.Bu, mb.C, mb.Du) / [[1e3], [1.0]],
                               markov(ma.A, ma.Bu, ma.C, ma.Du), atol=1e-8 * np.abs(markov(A, B, C, 0 * B[:2])).max())
    # with noise the scaled data are the same numbers up to rounding (1e-16 relative), amplified by the condition
    # of the LQ/SVD steps (s_1/s_4 < 1e3 here) and of the eigenvalues (< 1e2): far below 1e-8
    tr = run(2000, 7, noise_std=0.3)
    scaled = Trace(t=tr.t, u=tr.u * 1e-3, y=tr.y * [1e3, 1.0], controls=tr.controls, outputs=tr.outputs)
    a, b = subspace_id(tr, 4), subspace_id(scaled, 4)
    np.testing.assert_allclose(np.sort_complex(b.poles), np.sort_complex(a.poles), rtol=1e-8)
    np.testing.assert_allclose(b.R, a.R * np.outer([1e3, 1.0], [1e3, 1.0]), rtol=1e-8)


def test_order_criteria_on_innovation_data():
    # noise-free: prediction errors at rounding level count as zero, so the BIC and the AIC take the least order
    # that reaches it (4); with innovation noise the model is correctly specified and the BIC is consistent
    tr = run(2000, 0)
    for criterion in ("bic", "aic", "gap"):
        ident = subspace_id(tr, criterion=criterion, detrend=False)
        assert ident.order == 4, ident.order_rule
    assert subspace_id(tr, criterion="gap", detrend=False).order_rule.startswith("largest singular-value gap")
    with pytest.raises(ParameterError):
        subspace_id(tr, criterion="hq")
    with pytest.raises(ParameterError):
        subspace_id(tr, 4, focus="output")


def test_focus_simulation_refits_b_and_d_exactly_for_fixed_a_and_c():
    # For fixed A, C the simulated output is linear in (B, D, x0): the refit is the least-squares minimiser of the
    # simulation error.  Check against a brute-force linear least squares built from scipy.signal.dlsim.
    from scipy import signal

    tr = run(600, 11, noise_std=0.3)
    sim = subspace_id(tr, 4, detrend=False, feedthrough=True)
    Am, Cm = sim.model.A, sim.model.C
    cols = []
    for i in range(4):
        e = np.zeros((4, 1))
        e[i] = 1.0
        cols.append(signal.dlsim((Am, e, Cm, np.zeros((2, 1)), 1.0), tr.u)[1].reshape(-1))
    for k in range(2):
        cols.append(np.kron(tr.u[:, 0], np.eye(2)[k]))
    x0 = []
    for i in range(4):
        e = np.zeros(4)
        e[i] = 1.0
        x0.append(signal.dlsim((Am, np.zeros((4, 1)), Cm, np.zeros((2, 1)), 1.0), np.zeros((600, 1)), x0=e)[1]
                  .reshape(-1))
    # the criterion weighs each output by 1 / its standard deviation (the scaled signals)
    w = np.tile(1.0 / tr.y.std(axis=0), 600)
    Phi = np.column_stack(cols + x0) * w[:, None]
    th = np.linalg.lstsq(Phi, tr.y.reshape(-1) * w, rcond=None)[0]
    np.testing.assert_allclose(sim.model.Bu[:, 0], th[:4], rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(sim.model.Du[:, 0], th[4:6], rtol=1e-7, atol=1e-9)
    # the prediction focus keeps the state-regression B, D: same A, C, other B
    pred = subspace_id(tr, 4, detrend=False, focus="prediction", feedthrough=True)
    np.testing.assert_allclose(pred.model.A, Am)
    assert not np.allclose(pred.model.Bu, sim.model.Bu, rtol=1e-6)


def test_noise_model_is_that_of_the_returned_model():
    # Innovation-form data (R_true = 0.3² I).  Whatever B, D the focus step returns, K and R are re-estimated for the
    # returned (A, B, C, D) and R is the covariance of that predictor's one-step error on the data (initial state
    # fitted).  The Kalman residual of kalman(model, Q=R, R=0) on the training trace starts from x = 0 instead;
    # after 300 samples (|λ(A − K C)| ≈ 0.82: the transient is below 0.83^300 ≈ 5e-25) it is the same sequence.
    # Its sample variance over the last 2700 samples differs from R (all 3000) only by the first 300 samples'
    # share: var_all = 0.9 var_last + 0.1 var_first, so the relative difference is 0.1 (var_first/var_last − 1),
    # of standard deviation 0.1 √(2/300 + 2/2700) = 0.0086 for a white error: 3σ = 0.026.
    # Close to the true R: each variance has relative standard error √(2/3000) = 0.026 (3σ = 0.08) plus the
    # model's estimation error O(d/N), d = 4 (1 + 2·2) + 2 = 22 parameters: rtol 0.1.
    tr = run(3000, 21, noise_std=0.3)
    for kw in ({}, {"feedthrough": True}, {"feedthrough": True, "focus": "prediction"}, {"method": "moesp"}):
        ident = subspace_id(tr, 4, detrend=False, **kw)
        res = kalman(ident.model, Q=ident.R, R=0.0).generator.run(tr)
        r = res.r[300:][np.asarray(res.valid, bool)[300:]]
        S = r.T @ r / len(r)
        np.testing.assert_allclose(np.diag(S), np.diag(ident.R), rtol=0.026, err_msg=str(kw))
        # the covariance: the same share argument on the normalised cross term (standard deviation 0.0086 too)
        assert abs(S[0, 1] - ident.R[0, 1]) < 0.026 * np.sqrt(S[0, 0] * S[1, 1])
        np.testing.assert_allclose(np.diag(ident.R), [0.09, 0.09], rtol=0.1, err_msg=str(kw))
        assert abs(ident.R[0, 1]) < 0.1 * 0.09
