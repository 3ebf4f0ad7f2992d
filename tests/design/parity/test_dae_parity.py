"""LTI parity (DAE null-space) filter: van der Ploeg 2018, Lemma 2-1.2, Sec. 2-3, 4-3-1."""

from __future__ import annotations

import inspect

import control
import numpy as np
import pytest
import scipy.signal

from fdikit import FaultModel
from fdikit.design.parity.polynomial import dae_form, parity_filter
from fdikit.design.parity.polynomial_rank import (
    bar,
    bar_matrices,
    detectability,
    isolability,
    left_null_space,
    minimal_degree,
)
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.faults import Bias, FaultScenario, ScaleFactor
from fdikit.lti import dlsim_blocked
from fdikit.plants.single_track import single_track, single_track_lpv
from fdikit.simulate import simulate, time_grid

KMH = 1 / 3.6
FAMILY = single_track_lpv()
M70 = FAMILY(70 * KMH)
H = 0.01


def test_dae_form_is_thesis_4_6():
    """(4.6): H = [[−qI + 𝒜, ℬ_d], [C, 0]], L = [[0, ℬ], [−I, 0]], F = [ℬ_f; 0] with ℬ_f = ℬ."""
    dae = dae_form(M70, multiplicative=["steering"])
    A, B, Bd, C = FAMILY.matrices(70 * KMH)
    np.testing.assert_array_equal(dae.H[0], np.block([[A, Bd], [C, np.zeros((3, 2))]]))
    np.testing.assert_array_equal(dae.H[1], np.block([[-np.eye(4), np.zeros((4, 2))], [np.zeros((3, 6))]]))
    np.testing.assert_array_equal(dae.L[0], np.block([[np.zeros((4, 3)), B], [-np.eye(3), np.zeros((3, 1))]]))
    np.testing.assert_array_equal(dae.F[0], np.vstack([np.hstack([B, B]), np.zeros((3, 2))]))
    assert dae.unknowns == M70.states + ("curvature", "bank")
    assert dae.knowns == ("yaw_rate", "lateral_error", "heading_error", "steering")
    # the plant family exposes the same matrices (thesis (4.17))
    for a, b in zip(FAMILY.dae_matrices(70 * KMH), (*dae.H, *dae.L, dae.F[0][:, :1])):
        np.testing.assert_array_equal(a, b)


def test_bar_gives_product_coefficients():
    """Lemma 2-1.2: N̄ H̄ is the coefficient row of N(q) H(q); H̄ is (d_N+1) n_r x (d_N+d_H+1) n_c."""
    rng = np.random.default_rng(3)
    Hc = [rng.standard_normal((3, 2)) for _ in range(3)]  # d_H = 2
    Nc = [rng.standard_normal((1, 3)) for _ in range(4)]  # d_N = 3
    Hb = bar(Hc, 3)
    assert Hb.shape == (4 * 3, 6 * 2)
    direct = np.zeros((6, 2))
    for i, Ni in enumerate(Nc):
        for j, Hj in enumerate(Hc):
            direct[i + j] += (Ni @ Hj)[0]
    np.testing.assert_allclose(np.hstack(Nc) @ Hb, direct.reshape(1, -1), rtol=1e-13, atol=1e-13)
    with pytest.raises(ParameterError, match="non-negative integer"):
        bar(Hc, -1)


def test_minimal_degree_and_null_space_checklist_5():
    """Left null space dims 0, 0, 1, 2 for d_N = 0..3; d_N = 2; H̄ 21 x 24, rank 20.

    The three smallest non-zero singular values of H̄ at 70 km/h are printed as 3.207e-6, 4.880e-4, 1.027e-2.
    """
    dae = dae_form(M70)
    assert [left_null_space(dae, d).shape[0] for d in range(4)] == [0, 0, 1, 2]
    assert minimal_degree(dae) == 2
    Hb, Lb, Fb = bar_matrices(dae, 2)
    assert Hb.shape == (21, 24) and Lb.shape == (21, 12) and Fb.shape == (21, 3)
    s = np.linalg.svd(Hb, compute_uv=False)
    assert s[-1] < 1e-15 * s[0]
    np.testing.assert_allclose(s[-4:-1], [1.027e-2, 4.880e-4, 3.207e-6], rtol=6e-4)


def test_detectable_not_isolable_on_speed_grid():
    """(4.7) and Sec. 2-3 on 70–120 km/h.

    The library tests run on a 1 km/h grid; an independent batched SVD covers the thesis'
    0.01 km/h grid (5001 speeds): normal ranks [H F] = 7 > H = 6, and [[H F] F] = [H F] = 7.
    """
    for kmh in range(70, 121):
        dae = dae_form(FAMILY(kmh * KMH), multiplicative=["steering"])
        det = detectability(dae, "steering_actuator")
        iso = isolability(dae, "steering_actuator", "steering_multiplicative")
        assert (det.holds, det.rank_with, det.rank_without) == (True, 7, 6)
        assert (iso.holds, iso.rank_with, iso.rank_without) == (False, 7, 7)
        assert not iso and det
    lam = 0.3141 + 0.7183j
    mats = [FAMILY.dae_matrices(v) for v in np.linspace(70, 120, 5001) * KMH]
    Hl = np.stack([H0 + lam * H1 for H0, H1, _, _ in mats])
    F = np.stack([m[3] for m in mats]).astype(complex)
    for M, expected in ((Hl, 6), (np.concatenate([Hl, F], 2), 7), (np.concatenate([Hl, F, F], 2), 7)):
        s = np.linalg.svd(M, compute_uv=False)
        ranks = (s > 1e-10 * s[:, :1]).sum(axis=1)
        assert np.all(ranks == expected)


def test_filter_checklist_6():
    """Sec. 4-3-1: ‖N̄H̄‖ ≈ 0, G(1) = 1, deg d = 3 > deg NL = 2, no q² δ_set term, printed NL, d(q)."""
    d = parity_filter(M70)
    assert d.degree == 2 and d.null_dimension == 1 and d.fault == "steering_actuator"
    Hb, _, _ = bar_matrices(d.dae, 2)
    assert np.linalg.norm(d.N_bar @ Hb) <= 1e-12 * np.linalg.norm(d.N_bar) * np.linalg.norm(Hb)
    assert d.decoupling <= 1e-12
    assert d.dc_gain == pytest.approx(1.0, abs=1e-12)
    assert d.denominator.size - 1 == 3 and d.generator.n == 3
    # d(q) = q³ − 2.7144 q² + 2.45598912 q − 0.74072632 (independent computation, exact for p = 0.9048)
    np.testing.assert_allclose(d.denominator, [-0.74072632, 2.45598912, -2.7144, 1.0], rtol=0, atol=5e-9)
    printed = np.array([
        [-8.982045e-04, -1.629154e-03, -1.583899e-04, -4.254848e-04],
        [6.044634e-05, -9.678406e-05, -3.261895e-04, -4.373166e-04],
        [1.010977e-03, 1.725938e-03, -1.677995e-04, 0.0],
    ])
    np.testing.assert_allclose(d.NL, printed, rtol=0, atol=5e-10)  # 7 significant digits as printed
    assert np.abs(d.NL[2]).max() > 1e-4  # deg NL = 2
    assert abs(d.NL[2, 3]) <= 1e-12 * np.abs(d.NL).max()  # q² coefficient of δ_set
    np.testing.assert_allclose(d.NF[:2], [-4.254848e-4, -4.373166e-4], rtol=0, atol=5e-11)
    assert abs(d.NF[2]) <= 1e-12 * np.abs(d.NF).max()


@pytest.mark.parametrize(("kmh", "z0"), [(30, -0.93803), (40, -0.95314), (70, -0.97294), (90, -0.97889),
                                         (120, -0.98413)])
def test_fault_map_is_first_order_over_triple_pole(kmh, z0):
    """Note §5.2: G(q) = K (q − z_0)/(q − p)³, K = (1 − p)³/(1 − z_0), z_0 printed per speed to 5 decimals."""
    p = 0.9048
    d = parity_filter(FAMILY(kmh * KMH), poles=p)
    assert d.fault_zeros.size == 1
    assert abs(d.fault_zeros[0] - z0) <= 5e-6
    zq = np.exp(1j * np.linspace(0.01, np.pi, 50))
    K = (1 - p) ** 3 / (1 - d.fault_zeros[0])
    np.testing.assert_allclose(d.fault_gain(zq), K * (zq - d.fault_zeros[0]) / (zq - p) ** 3, rtol=1e-10)


@pytest.mark.parametrize(("p", "printed"), [(0.9048, 0.79491 - 0.51841j), (0.6065, 0.98891 - 0.13341j),
                                            (0.3679, 0.99628 - 0.07977j), (0.9, 0.81302 - 0.49882j)])
def test_fault_gain_at_excitation_frequency(p, printed):
    """Note §5.2 table: G(e^{jωh}) at the 0.3 Hz steering excitation (4.2), 70 km/h, 5 decimals."""
    g = parity_filter(M70, poles=p).fault_gain(np.exp(2j * np.pi * 0.3 * H))
    assert abs(g.real - printed.real) <= 5e-6 and abs(g.imag - printed.imag) <= 5e-6


def test_generator_realises_d_inverse_NL_and_decouples():
    """Independent checks with python-control and the internal form (plant + filter)."""
    d = parity_filter(M70)
    g = d.generator
    assert g.controls == ("steering",) and g.outputs == M70.outputs and g.isolates == ("steering_actuator",)
    tf = control.ss2tf(g.to_control())
    den = np.poly(np.full(3, 0.9048))
    order = [3, 0, 1, 2]  # generator inputs [steering; outputs] vs z = [outputs; steering]
    for col, k in enumerate(order):
        num = np.trim_zeros(np.asarray(tf.num[0][col], dtype=float), "f")
        np.testing.assert_allclose(np.asarray(tf.den[0][col], dtype=float), den, rtol=1e-12)
        expected = np.trim_zeros(d.NL[::-1, k], "f")
        np.testing.assert_allclose(num[-expected.size:], expected, rtol=1e-9, atol=1e-12 * np.abs(d.NL).max())
    plant = g.internal_form(M70)
    w = np.array([0.1, 2 * np.pi * 0.3, 10.0, 100.0])
    assert np.abs(plant.freqresp(w, "d")).max() <= 1e-9
    assert np.abs(plant.freqresp(w, "u")).max() <= 1e-9
    np.testing.assert_allclose(plant.freqresp(w, "f")[:, 0, 0], d.fault_gain(np.exp(1j * w * H)), rtol=1e-8)


def _lfilter_G(d, f):
    """r = G(q)[f] with G = −NF/d (2.7), by scipy.signal.lfilter in powers of q⁻¹."""
    n = d.denominator.size - 1
    b = np.zeros(n + 1)
    b[n - d.NF.size + 1 :] = -d.NF[::-1]
    return scipy.signal.lfilter(b, d.denominator[::-1], f)


def _rounding_bound(d, model, trace, f, mask):
    """First-order bound on the round-off of the residual of ``trace`` on the samples ``mask``.

    The residual is a small difference of large terms: over the open-loop run the lateral error drifts
    to ~1.3e3 m while ``r`` stays ~1e-3.  Both the plant simulation and the generator run through the
    lifted solver :func:`fdikit.lti.dlsim_blocked`, whose longest inner product has ``K = n + M m`` terms
    (block ``M``), so every computed sample carries an error of at most ``γ_K = K ε / (1 − K ε)`` relative
    to the sum of the absolute values of its terms (Higham, *Accuracy and Stability*, Lemma 3.1/3.5).
    From ``N(q) H(q) = 0`` (2.8a) those errors reach ``r`` only through stable maps:

    - an output error ``δy`` (and the plant states the outputs read) through the generator
      ``d⁻¹ N L`` itself: gain ``Σ_j ‖h_j‖₁ max|v_j|`` over its inputs ``v = [u, y]``;
    - a state error injected by a step of the plant recursion, of size ``γ_K (|A||x| + |B||v|)``,
      through ``−d⁻¹ N_x(q)`` (the state rows of ``N``); an error carried on along a trajectory
      of the plant is a free response, which the parity row annihilates.

    ``ℓ₁`` impulse-response norms are the ``ℓ∞ → ℓ∞`` gains, so the bound is ``γ_K (κ_y + κ_x)`` with
    ``κ`` these two gain-weighted magnitudes on ``mask`` — the condition of the residual computation,
    growing with the horizon through the drifting states.  No kernel-specific number enters it.
    """
    g = d.generator
    eps = np.finfo(float).eps
    block = inspect.signature(dlsim_blocked).parameters["block"].default
    K = max(g.n + block * g.B.shape[1], model.n + block * model.B.shape[1])
    gamma = K * eps / (1 - K * eps)
    t_len = trace.t.size
    impulse = np.zeros(t_len)
    impulse[0] = 1.0
    v = g.inputs_from(trace)
    kappa_y = 0.0
    for j in range(v.shape[1]):
        h = dlsim_blocked(g.A, g.B[:, [j]], g.C, g.D[:, [j]], impulse[:, None])[0]
        kappa_y += np.abs(h).sum() * np.abs(v[mask, j]).max()
    n = d.denominator.size - 1
    terms = (np.abs(trace.x) @ np.abs(model.A).T + np.abs(trace.u) @ np.abs(model.Bu).T
             + np.abs(trace.d) @ np.abs(model.Bd).T + np.abs(f)[:, None] @ np.abs(model.Bf).T)
    kappa_x = 0.0
    for i in range(model.n):
        b = np.zeros(n + 1)
        b[n - d.N.shape[0] + 1 :] = d.N[::-1, i]
        h = scipy.signal.lfilter(b, d.denominator[::-1], impulse[:t_len])
        kappa_x += np.abs(h).sum() * terms[mask, i].max()
    return gamma * (kappa_y + kappa_x)


def test_simulation_checklist_7():
    """S1 (Sec. 4-3-1, Fig. 4-3) at 70 km/h: κ = 1/350 m⁻¹ and a 2° bank at 15 s, f_a = 0.1° at 30 s, f_m = 0.9 at 50 s.

    The disturbances are rejected to round-off, r → f_a after the offset step (DC gain 1), and over
    the whole run r = G(q)[(f_m − 1) δ_set + f_a] (4.10), computed independently by lfilter.

    "Round-off" is the bound of :func:`_rounding_bound`, derived from the conditioning of the
    residual computation on the drifting open-loop states (no kernel-tuned constant): ≈1.3e-11 before
    30 s, ≈6.7e-11 up to 50 s and ≈1.6e-10 over the whole run (lateral error up to 1.3e3 m), i.e.
    r = G f holds to 1e-7 of f_a.  Measured errors are 1e-13 to 2e-12 depending on the OpenBLAS
    kernel (Prescott, Haswell, SkylakeX), of the order of the 1e-12 an independent reproduction reached for f_a.
    """
    d = parity_filter(M70)
    t = time_grid(70.0, H)
    u = 2.3e-3 * np.sin(0.6 * np.pi * t)  # (4.2)
    dist = np.where(t[:, None] >= 15.0, [1 / 350, np.sin(np.deg2rad(2.0))], 0.0)
    fa = np.deg2rad(0.1)
    scenario = FaultScenario([ScaleFactor("steering", factor=0.9, onset=50.0), Bias("steering", fa, onset=30.0)])
    trace = simulate(M70, scenario, t=t, u=u, d=dist)
    r = d.generator.run(trace).r[:, 0]
    assert np.abs(trace.y[:, 1]).max() > 100  # the open-loop lateral error drifts by > 100 m: rejection is no accident
    f = np.where(t >= 30, fa, 0.0) + np.where(t >= 50, -0.1 * u, 0.0)
    before, settled = t < 30, (t >= 35) & (t < 50)
    assert np.abs(r[before]).max() <= _rounding_bound(d, M70, trace, f, before)
    assert np.abs(r[settled] - fa).max() <= _rounding_bound(d, M70, trace, f, t < 50)
    whole = _rounding_bound(d, M70, trace, f, np.ones(t.size, bool))
    assert whole <= 1e-7 * fa  # the bound is tight enough for the check below to mean r = G f
    np.testing.assert_allclose(r, _lfilter_G(d, f), rtol=0, atol=whole)
    online = d.generator.online().run(trace).r[:, 0]
    np.testing.assert_allclose(online, r, rtol=0, atol=2 * whole)  # two evaluations, each within the bound


def test_nonminimal_degree_takes_least_norm_row():
    """d_N = 3 (2-D null space): fdikit's N̄ is the minimum-norm solution of N̄H̄ = 0, ΣN̄F̄ = −d(1) (the LP (2.9))."""
    d = parity_filter(M70, degree=3)
    assert d.null_dimension == 2 and d.denominator.size == 5
    Hb, _, Fb = bar_matrices(d.dae, 3)
    A = np.vstack([Hb.T, Fb.sum(axis=1)])
    rhs = np.concatenate([np.zeros(Hb.shape[1]), [-d.denominator.sum()]])
    lstsq = np.linalg.lstsq(A, rhs, rcond=1e-12)[0]
    np.testing.assert_allclose(d.N_bar[0], lstsq, rtol=1e-6, atol=1e-9 * np.abs(lstsq).max())
    assert d.dc_gain == pytest.approx(1.0, abs=1e-12) and d.decoupling <= 1e-12


def _input_delay(model: FaultModel, w: int) -> FaultModel:
    """Sec. 5-2-3: a w-sample delay chain on the steering (the fault passes through it)."""
    n = model.n
    A = np.zeros((n + w, n + w))
    A[:n, :n], A[:n, n + w - 1] = model.A, model.Bu[:, 0]
    A[n + 1 :, n : n + w - 1] = np.eye(w - 1)
    Bu = np.zeros((n + w, 1))
    Bu[n] = 1.0
    Bd = np.vstack([model.Bd, np.zeros((w, 2))])
    C = np.hstack([model.C, np.zeros((3, w))])
    return FaultModel(A, C, Bu=Bu, Bd=Bd, Bf=Bu, controls=["steering"], faults=["steering_actuator"],
                      outputs=model.outputs, disturbances=model.disturbances, dt=model.dt)


def test_high_order_filter_stays_accurate():
    """Note §5.6: a 10-sample steering delay raises the minimal d_N to 12 (deg d = 13, poles 0.9 as in Ch. 5).

    The Newton-chain realisation keeps the generator equal to d⁻¹ N L (a companion form of (q − 0.9)¹³ would
    lose ~ eps^(1/13) in its poles).
    """
    model = _input_delay(M70, 10)
    d = parity_filter(model, poles=0.9)
    assert d.degree == 12 and d.null_dimension == 1 and d.generator.n == 13
    assert d.dc_gain == pytest.approx(1.0, abs=1e-10) and d.decoupling <= 1e-12
    np.testing.assert_allclose(np.diag(d.generator.A), 0.9)
    zq = np.exp(1j * np.array([0.05, 0.5, 2.0]))
    sysd = d.generator.to_control()
    for k, z in enumerate(zq):
        resp = np.asarray(sysd(z))[0]
        direct = np.array([np.polyval(d.NL[::-1, j], z) for j in range(4)]) / np.prod(z - d.poles)
        np.testing.assert_allclose(resp, direct[[3, 0, 1, 2]], rtol=1e-8, err_msg=f"point {k}")
    internal = d.generator.internal_form(model)
    assert np.abs(internal.freqresp([0.5, 5.0], "d")).max() <= 1e-8


def test_pole_choices():
    d = parity_filter(M70, poles=[0.5, 0.6, 0.7, 0.8])  # one extra pole: still decoupled, DC 1
    assert sorted(np.linalg.eigvals(d.generator.A).real) == pytest.approx([0.5, 0.6, 0.7, 0.8], abs=1e-12)
    assert d.dc_gain == pytest.approx(1.0, abs=1e-12)
    assert np.abs(d.generator.internal_form(M70).freqresp([1.0, 10.0], "d")).max() <= 1e-9


def test_bad_input_errors():
    with pytest.raises(ModelError, match="discrete"):
        dae_form(single_track(70 * KMH))
    with pytest.raises(DesignError, match="inside the unit circle"):
        parity_filter(M70, poles=1.2)
    with pytest.raises(DesignError, match="real"):
        parity_filter(M70, poles=[0.5 + 0.1j, 0.5 - 0.1j, 0.3])
    with pytest.raises(DesignError, match="improper"):
        parity_filter(M70, poles=[0.5])
    two = M70.add_faults(["bank_like"], M70.Bd[:, [1]])
    with pytest.raises(DesignError, match="targets="):
        parity_filter(two)
    with pytest.raises(DesignError, match="not detectable"):
        parity_filter(two, "bank_like")  # same direction as the bank disturbance: rejected with it
