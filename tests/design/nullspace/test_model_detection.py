"""Model distances and exact model detection (mddist, mdgenspec, emdsyn, mdmatch) against FaultDetectionTools.jl's
test/test_emdsyn.jl ("Actuator faults": four first-order actuators k/(s+k)) and hand computations."""

import numpy as np
import pytest

from fdikit.design.nullspace.model_detection import amdsyn, difference_model, emdsyn, mdgenspec, mdmatch
from fdikit.design.nullspace.model_distances import check_models, mddist, nu_gap
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

K = 14.0
GAINS = (1.0, 0.5, 10.0, 0.01)          # nominal, 50 % loss of efficiency, disconnected, stall load
W = np.concatenate([[0.0], np.logspace(-5, 5, 200001)])


def _actuators():
    return [FaultModel([[-a * K]], [[a * K]], Bu=[[1.0]]) for a in GAINS]


def _g(a, w):
    return a * K / (1j * w + a * K)


def test_distances_of_the_actuator_models_by_brute_force():
    ms = _actuators()
    nug, inf, two = (mddist(ms, distance=d) for d in ("nugap", "inf", "2"))
    for d in (nug, inf, two):
        assert np.allclose(d.values, d.values.T) and np.all(np.diag(d.values) == 0)
    for i, a in enumerate(GAINS):
        for j, b in enumerate(GAINS):
            if i == j:
                continue
            g1, g2 = _g(a, W), _g(b, W)
            kappa = np.abs(g1 - g2) / np.sqrt((1 + np.abs(g1) ** 2) * (1 + np.abs(g2) ** 2))
            # stable first-order lags: 1 + G_j~ G_i has a positive real part, so the winding condition holds
            assert nug.values[i, j] == pytest.approx(kappa.max(), rel=1e-7)
            assert inf.values[i, j] == pytest.approx(np.abs(g1 - g2).max(), rel=1e-7)
            # ‖a/(s+a) − b/(s+b)‖₂² = a/2 + b/2 − 2ab/(a+b) (a, b the poles' magnitudes)
            ka, kb = a * K, b * K
            assert two.values[i, j] == pytest.approx(np.sqrt(ka / 2 + kb / 2 - 2 * ka * kb / (ka + kb)), rel=1e-9)
    # MDfreq = 1: the pointwise chordal distance at ω = 1
    d1 = mddist(ms, mdfreq=1.0)
    g1, g2 = _g(1.0, 1.0), _g(0.5, 1.0)
    assert d1.values[0, 1] == pytest.approx(abs(g1 - g2) / np.sqrt((1 + abs(g1) ** 2) * (1 + abs(g2) ** 2)),
                                            rel=1e-12)
    assert np.all(d1.peak[~np.eye(4, dtype=bool)] == 1.0)


def test_nu_gap_winding_condition():
    # 2/(s−1) vs 2/(s+1): det(1 + P₂~P₁) = (s−3)(s+1)/(s−1)², wno = 2 − 1, η₁ − η₂ = 1: the ν-gap is 1, although
    # the chordal distance 4/(ω²+5) peaks at 0.8
    assert nu_gap(([[1.0]], [[1.0]], [[2.0]], [[0.0]]), ([[-1.0]], [[1.0]], [[2.0]], [[0.0]]))[0] == 1.0
    # 1/(s−1) vs 1.1/(s−1): the condition holds (wno = 1 − 1, η₁ = η₂); chordal 0.1√x/√((x+1)(x+1.21)),
    # x = ω² + 1, largest at x = 1.1: δ = 1/21 at ω = √0.1
    d, w = nu_gap(([[1.0]], [[1.0]], [[1.0]], [[0.0]]), ([[1.0]], [[1.0]], [[1.1]], [[0.0]]))
    assert d == pytest.approx(1 / 21, rel=1e-9) and w == pytest.approx(np.sqrt(0.1), rel=1e-4)
    with pytest.raises(ParameterError, match="imaginary axis"):
        nu_gap(([[0.0]], [[1.0]], [[1.0]], [[0.0]]), ([[-1.0]], [[1.0]], [[1.0]], [[0.0]]))
    with pytest.raises(ParameterError, match="shapes"):
        nu_gap(([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), ([[-1.0]], [[1.0, 1.0]], [[1.0]], [[0.0, 0.0]]))


def test_achievable_model_detection_structure():
    # test_emdsyn.jl: S = ones − I; at MDfreq = 0 nothing (all DC gains are 1); MDfreq = [0, 1] gives S again
    ms = _actuators()
    S = mdgenspec(ms)
    assert np.array_equal(S, ~np.eye(4, dtype=bool))
    assert not mdgenspec(ms, mdfreq=0).any()
    assert np.array_equal(mdgenspec(ms, mdfreq=[0.0, 1.0]), S)


def test_emdsyn_on_the_actuator_models():
    # test_emdsyn.jl: emdsyn(sdeg = −15, poles = [−20]); each row of MDperf is ordered as the row of the ν-gaps
    ms = _actuators()
    nug, nug1 = mddist(ms), mddist(ms, mdfreq=1.0)
    d = emdsyn(ms, sdeg=-15.0, poles=[-20.0])
    assert d.orders == (1, 1, 1, 1) and d.degrees == (1, 1, 1, 1)
    # the models are stable: each filter keeps its model's pole −k_j (poles/sdeg would move only poles beyond smarg)
    for g, a in zip(d.generators, GAINS):
        np.testing.assert_allclose(np.linalg.eigvals(g.A).real, [-a * K], rtol=1e-12)
    P = d.performance
    assert np.all(np.diag(P) < 1e-9)
    for j in range(4):
        assert np.argsort(nug.values[j]).tolist() == np.argsort(P[j]).tolist()
        assert np.delete(P[j], j).min() == pytest.approx(1.0, rel=1e-12)
    # by hand: Q_j ∝ [−G_j  1] on [u; y], so R_ji ∝ G_i − G_j and row j of MDperf is the row of the L∞ distances
    # scaled to a smallest off-diagonal entry of 1
    dinf = mddist(ms, distance="inf").values
    for j in range(4):
        np.testing.assert_allclose(P[j], dinf[j] / np.delete(dinf[j], j).min(), rtol=1e-8, atol=1e-9)
    # with smarg = −200 every model pole is moved: all filter poles at −20, R_ji = (s+k_j)/(s+20) (G_i − G_j)
    d20 = emdsyn(ms, sdeg=-15.0, poles=[-20.0], smarg=-200.0)
    for j, a in enumerate(GAINS):
        np.testing.assert_allclose(np.linalg.eigvals(d20.generators[j].A).real, [-20.0], rtol=1e-12)
        raw = [np.abs((1j * W + a * K) / (1j * W + 20) * (_g(b, W) - _g(a, W))).max() for b in GAINS]
        np.testing.assert_allclose(d20.performance[j], np.array(raw) / min(r for i, r in enumerate(raw) if i != j),
                                   rtol=1e-6, atol=1e-9)
    d1 = emdsyn(ms, sdeg=-15.0, poles=[-20.0], mdfreq=1.0)
    for j in range(4):
        assert np.argsort(nug1.values[j]).tolist() == np.argsort(d1.performance[j]).tolist()
    dn = emdsyn(ms, sdeg=-15.0, poles=[-20.0], normalize=True)
    np.testing.assert_allclose(dn.performance[0], dn.performance[:, 0], rtol=1e-12)
    # mdmatch: the bank on the 50 % loss model picks filter 1
    gains, k = mdmatch(d, ms[1])
    assert k == 1 and gains[1] < 1e-9 and np.argmin(gains) == 1


def test_model_with_disturbances_is_decoupled():
    # model 0 has a disturbance on output 1; its filter decouples it, and with emdtest model 1's disturbance counts
    m0 = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Dd=[[1.0], [0.0]])
    m1 = FaultModel([[-3.0]], [[3.0], [1.0]], Bu=[[1.0]], Dd=[[0.0], [1.0]])
    d = emdsyn([m0, m1], sdeg=-2.0, emdtest=True)
    R = d.generators[0].internal_form(m0)
    from fdikit.analysis.channels import hinf_norm, minimal_channel

    assert hinf_norm(minimal_channel(R, list(m0.controls) + list(m0.disturbances)))[0] < 1e-9
    assert d.performance[0, 1] == pytest.approx(1.0) and d.performance[1, 0] == pytest.approx(1.0)
    assert difference_model(m0, m1, emdtest=True).faults == ("delta_u0", "model_d0")


def test_nu_gap_discrete():
    # stable pair: the ν-gap is the largest chordal distance on the unit circle (brute force, 2·10⁵ points)
    dt = 0.1
    m1 = FaultModel([[0.5, 0.2], [0.0, -0.3]], [[1.0, 1.0]], Bu=[[1.0], [0.5]], Du=[[0.2]], dt=dt)
    m2 = FaultModel([[0.6, 0.1], [0.0, -0.2]], [[1.0, 0.8]], Bu=[[1.0], [0.4]], Du=[[0.3]], dt=dt)
    d = mddist([m1, m2])
    th = np.linspace(0.0, np.pi, 200001)

    def g(m, z):
        return (m.C @ np.linalg.solve(z * np.eye(m.n) - m.A, m.b("u")) + m.d("u"))[0, 0]

    z = np.exp(1j * th)
    g1 = np.array([g(m1, x) for x in z[::20]])
    g2 = np.array([g(m2, x) for x in z[::20]])
    kap = np.abs(g1 - g2) / np.sqrt((1 + np.abs(g1) ** 2) * (1 + np.abs(g2) ** 2))
    assert d.values[0, 1] == pytest.approx(kap.max(), rel=1e-6)
    assert d.peak[0, 1] == pytest.approx(th[::20][int(np.argmax(kap))] / dt, abs=2e-3 / dt)
    # one unstable pole each, the same: the winding condition holds; 1/(z−2) vs 1.1/(z−2) gives 1/21 (|g| = 0.9535)
    u1 = FaultModel([[2.0]], [[1.0]], Bu=[[1.0]], dt=dt)
    u2 = FaultModel([[2.0]], [[1.1]], Bu=[[1.0]], dt=dt)
    x = 1.21 ** -0.25
    assert mddist([u1, u2]).values[0, 1] == pytest.approx(0.1 * x / np.sqrt((1 + x * x) * (1 + 1.21 * x * x)),
                                                          rel=1e-7)
    # a small pair with different numbers of poles outside the disc: chordal distance < 0.02, but δ_ν = 1
    s1 = FaultModel([[2.0]], [[0.01]], Bu=[[1.0]], dt=dt)
    s2 = FaultModel([[0.5]], [[0.01]], Bu=[[1.0]], dt=dt)
    assert mddist([s1, s2]).values[0, 1] == 1.0
    # at given frequencies: the chordal distance there (θ = π included)
    dm = mddist([m1, m2], mdfreq=[0.0, np.pi / dt])
    k0 = abs(g(m1, 1.0) - g(m2, 1.0)) / np.sqrt((1 + abs(g(m1, 1.0)) ** 2) * (1 + abs(g(m2, 1.0)) ** 2))
    kp = abs(g(m1, -1.0) - g(m2, -1.0)) / np.sqrt((1 + abs(g(m1, -1.0)) ** 2) * (1 + abs(g(m2, -1.0)) ** 2))
    assert dm.values[0, 1] == pytest.approx(max(k0, kp), rel=1e-9)


def test_bad_input():
    m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]])
    with pytest.raises(ParameterError, match="outputs, controls or sample time"):
        check_models([m, FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], dt=0.1)])
    with pytest.raises(ParameterError, match="non-empty"):
        mddist([])
    with pytest.raises(ParameterError, match="distance"):
        mddist([m, m], distance="hinf")
    with pytest.raises(ParameterError, match="unit circle"):
        mddist([FaultModel([[1.0]], [[1.0]], Bu=[[1.0]], dt=0.1)] * 2)
    with pytest.raises(ParameterError, match="mdfreq"):
        mddist([m, m], distance="2", mdfreq=1.0)
    with pytest.raises(DesignError, match="cannot be told apart"):
        emdsyn([m, m])


def test_example_6_1c_lateral_aircraft_loss_of_efficiency():
    # Ex6_1c.jl: nine LOE models G_u Γ_i of a lateral aircraft model, emdsyn(sdeg = −1, poles = [−1]):
    # @test all(diag(MDperf) .< 1e-7) && all(MDperf + eps + I .>= 1); every model detectable from every other
    ms = _lateral(None)
    assert np.array_equal(mdgenspec(ms), ~np.eye(9, dtype=bool))
    d = emdsyn(ms, sdeg=-1.0, poles=[-1.0])
    P = d.performance
    assert np.all(np.diag(P) < 1e-7) and np.all(P + np.finfo(float).eps + np.eye(9) >= 1)
    # the last model has lost both inputs (G_u = 0): its filter is static (y itself, a degree-0 row)
    assert d.orders[-1] == 0 and all(o == 1 for o in d.orders[:-1])


def _lateral(noise: str | None = "both"):
    """The lateral aircraft with nine LOE models G_u Γ_i: Ex6_1c.jl (``noise=None``: C = I, no noise) or Ex6_2c.jl
    (C = 180/π [I₂ 0], noise on the states and sensors, or with ``"states"`` on the states only)."""
    A = np.array([[-.4492, 0.046, .0053, -.9926], [0, 0, 1, 0.0067], [-50.8436, 0, -5.2184, .722],
                  [16.4148, 0, .0026, -.6627]])
    Bu = np.array([[0.0004, 0.0011], [0, 0], [-1.4161, .2621], [-0.0633, -0.1205]])
    gamma = 1 - np.array([[0, 0, 0, .5, .5, .5, 1, 1, 1], [0, .5, 1, 0, .5, 1, 0, .5, 1]]).T
    if noise is None:
        return [FaultModel(A, np.eye(4), Bu=Bu @ np.diag(g)) for g in gamma]
    C = 180 / np.pi * np.eye(2, 4)
    Bw, Dw = np.eye(4, 6), np.hstack([np.zeros((2, 4)), np.eye(2)])
    if noise == "states":
        Bw, Dw = np.eye(4), np.zeros((2, 4))
    return [FaultModel(A, C, Bu=Bu @ np.diag(g), Bw=Bw, Dw=Dw) for g in gamma]


def test_amdsyn_without_noise_is_emdsyn():
    ms = _actuators()
    a = amdsyn(ms, sdeg=-15.0, poles=[-20.0])
    e = emdsyn(ms, sdeg=-15.0, poles=[-20.0])
    np.testing.assert_allclose(a.performance, e.performance, rtol=1e-12, atol=1e-14)
    assert np.all(np.isinf(a.gaps)) and a.factorizations == ("none",) * 4
    nug = mddist(ms)
    for j in range(4):                                   # test_amdsyn.jl: rows ordered as the ν-gap rows
        assert np.argsort(nug.values[j]).tolist() == np.argsort(a.performance[j]).tolist()
    assert mdmatch(a, ms[1])[1] == 1


def test_amdsyn_output_noise_gap_is_the_distance():
    # y = G_j u + w: Q_j ∝ [−G_j 1] has a constant noise part (standard, already co-inner up to scale), so the gap of
    # filter j is its smallest L∞ distance to another model
    ms = [FaultModel([[-a * K]], [[a * K]], Bu=[[1.0]], Dw=[[1.0]]) for a in GAINS]
    d = amdsyn(ms)
    dinf = mddist(ms, distance="inf").values
    assert d.factorizations == ("standard",) * 4
    for j in range(4):
        assert d.gaps[j] == pytest.approx(np.delete(dinf[j], j).min(), rel=1e-8)


@pytest.mark.parametrize("noise, nonstd", [("both", "quasi"), ("states", "quasi"), ("states", "regularize"),
                                           ("states", "wiener-hopf"), ("states", "wiener-hopf-shift"),
                                           ("states", "wiener-hopf-regularize")])
def test_example_6_2c_amdsyn(noise, nonstd):
    # Ex6_2c.jl: @test all(diag(MDperf) .< 1e-7) && all(MDperf + eps + I .>= 1); MDgap = mdgap(R); Q stable.
    # "states": noise on the states only (D_w = 0: zeros at infinity, the non-standard options of test_amdsyn.jl)
    from fdikit.analysis.channels import frequency_response, hinf_norm, minimal_channel
    ms = _lateral(noise)
    d = amdsyn(ms, sdeg=-1.0, poles=[-1.0], nonstd=nonstd)
    P = d.performance
    assert np.all(np.diag(P) < 1e-7) and np.all(P + np.finfo(float).eps + np.eye(9) >= 1)
    assert all(g.n == 0 or np.linalg.eigvals(g.A).real.max() < 0 for g in d.generators)
    for j, (g, m) in enumerate(zip(d.generators, ms)):
        ch = minimal_channel(g.internal_form(m), list(m.noise))
        assert d.gaps[j] == pytest.approx(np.delete(P[j], j).min() / hinf_norm(ch)[0], rel=1e-8)
        if d.factorizations[j] == "standard":
            # the noise channel is co-inner up to the final scale: flat gain over frequency
            sv = np.abs(frequency_response(ch, np.logspace(-3, 3, 25))[:, 0, :])
            rows = np.sqrt((sv ** 2).sum(axis=1))
            np.testing.assert_allclose(rows, rows[0], rtol=1e-8)
    if noise == "both":
        assert d.factorizations == ("standard",) * 9
    else:
        assert all(k == nonstd or (nonstd == "regularize" and k == "regularized") for k in d.factorizations)


def test_rdim_and_selection():
    # Ex6_1c with two residuals per filter: still decoupled and every model detected (MDperf + ε + I ≥ 1)
    ms = _lateral(None)
    d = emdsyn(ms, rdim=2, sdeg=-1.0, poles=[-1.0])
    P = d.performance
    assert all(g.residuals == (f"r{j}_0", f"r{j}_1") for j, g in enumerate(d.generators))
    assert np.all(np.diag(P) < 1e-7) and np.all(P + np.finfo(float).eps + np.eye(9) >= 1)
    # a given selection: any scale of the one actuator row gives the same scaled performance
    act = _actuators()
    np.testing.assert_allclose(emdsyn(act, selection=[[[3.0]]] * 4).performance, emdsyn(act).performance,
                               rtol=1e-12, atol=1e-14)
    with pytest.raises(ParameterError, match="selection"):
        emdsyn(act, selection=[[[1.0, 2.0]]] * 4)
    with pytest.raises(ParameterError, match="one entry"):
        emdsyn(act, selection=[None])
    with pytest.raises(ParameterError, match="rdim"):
        emdsyn(act, rdim=0)
    with pytest.raises(DesignError, match="rdim=2"):
        emdsyn(act, rdim=2)
    # amdsyn with both rows of the two-output aircraft: a two-row noise factor, the gaps as defined
    from fdikit.analysis.channels import hinf_norm, minimal_channel

    lat = _lateral("both")
    a = amdsyn(lat, rdim=2, sdeg=-1.0, poles=[-1.0])
    for j, (g, m) in enumerate(zip(a.generators, lat)):
        assert len(g.residuals) == 2
        wn = hinf_norm(minimal_channel(g.internal_form(m), list(m.noise)))[0]
        assert a.gaps[j] == pytest.approx(np.delete(a.performance[j], j).min() / wn, rel=1e-8)
    assert np.all(np.diag(a.performance) < 1e-7)


def test_select_designs_a_subset_of_the_filters():
    # the reference's MDSelect (test_emdsyn.jl runs [1] and [2]): each filter is scaled on its own row, so the
    # selected filters and their rows of MDperf are those of the full design
    ms = _actuators()
    full = emdsyn(ms, sdeg=-15.0, poles=[-20.0])
    part = emdsyn(ms, sdeg=-15.0, poles=[-20.0], select=[2, 1])
    assert part.selected == (2, 1) and part.filter_models == (2, 1) and part.performance.shape == (2, 4)
    np.testing.assert_allclose(part.performance, full.performance[[2, 1]], rtol=1e-8, atol=1e-12)
    assert part.generators[0].residuals == ("r2",)
    gains, k = mdmatch(part, ms[1])
    assert k == 1 and gains[1] < 1e-9 * gains[0]
    ma = amdsyn(ms, sdeg=-15.0, poles=[-20.0], select=[3])
    np.testing.assert_allclose(ma.performance, amdsyn(ms, sdeg=-15.0, poles=[-20.0]).performance[[3]], rtol=1e-8,
                               atol=1e-12)
    assert full.selected is None and full.filter_models == (0, 1, 2, 3)
    with pytest.raises(ParameterError, match="start with 0"):
        emdsyn(ms, select=[1, 0], normalize=True)
    with pytest.raises(ParameterError, match="distinct model indices"):
        emdsyn(ms, select=[1, 1])
    with pytest.raises(ParameterError, match="distinct model indices"):
        emdsyn(ms, select=[])
    with pytest.raises(ParameterError, match="distinct model indices"):
        emdsyn(ms, select=[4])


def test_full_order_filters():
    # the reference's minimal = false: every basis row over its own denominator, rdim = all rows by default.
    # Ex6_1c's models (C = I: four outputs, two controls): four degree-1 rows per model (degree 0 for the model
    # without inputs); the filters keep the least-order design's checks at order 4 instead of 1
    ms = _lateral(None)
    d = emdsyn(ms, sdeg=-1.0, poles=[-1.0], minimal=False)
    P = d.performance
    assert np.all(np.diag(P) < 1e-7) and np.all(P + np.finfo(float).eps + np.eye(9) >= 1)
    assert d.degrees == (4,) * 8 + (0,) and d.orders == (4,) * 8 + (0,)
    assert all(g.residuals == tuple(f"r{j}_{k}" for k in range(4)) for j, g in enumerate(d.generators))
    one = emdsyn(ms, sdeg=-1.0, poles=[-1.0], minimal=False, rdim=1)
    # one combination of rows over equal denominators (each row gets the model's slowest pole): order 1 again
    assert all(g.C.shape[0] == 1 for g in one.generators) and all(1 <= o <= 4 for o in one.orders[:-1])
    assert np.all(np.diag(one.performance) < 1e-7)
    a = amdsyn(_lateral("states"), sdeg=-1.0, poles=[-1.0], minimal=False)
    assert np.all(np.diag(a.performance) < 1e-7) and np.all(np.isfinite(a.gaps)) and np.all(a.gaps > 0)
