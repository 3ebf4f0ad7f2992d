"""The non-standard cases of afdsyn: Wiener–Hopf factors (reference nonstd = 3, 4, 5) and smarg, against the
numbers of FaultDetectionTools.jl test/test_afdsyn.jl ("tests for non-standard cases") and hand computations.

The reference's pole checks read ``gpole(Q.sys)`` of a column of the joint minimal realisation ``[R_f R_w Q]``, so
they list the model's pole −2 as well; fdikit's filters are minimal, so the filter poles are checked alone and the
reference's list against the poles of the minimal ``[R_f R_w]``.
"""

import numpy as np
import pytest
from varga_examples import high_pass, low_pass

from fdikit.analysis.channels import hinf_norm, minimal_channel
from fdikit.analysis.performance import fdif2ngap
from fdikit.design.nullspace.approximate import afdsyn
from fdikit.design.nullspace.row_factors import realize_biproper, row_spectrum, wiener_hopf_row
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

W = np.logspace(-4, 4, 40001)          # grid of the hand-computed sup norms (peaks here are at 0 or ∞)


def _sup(num, den):
    """sup over the grid (and the limits 0, ∞) of |num(jω)/den(jω)|, by hand from the polynomials."""
    s = 1j * np.concatenate([[0.0], W])
    v = np.abs(np.polyval(num, s) / np.polyval(den, s))
    lim = abs(num[0] / den[0]) if len(num) == len(den) else 0.0
    return max(v.max(), lim)


def _hand_gap(q_num, q_den, rw_num, rw_den):
    """Gap of Q = q_num/q_den on Rf = (s+1)/(s+2) and Rw = rw_num/rw_den (β = ‖R_f‖∞, one fault)."""
    rf = _sup(np.polymul(q_num, [1, 1]), np.polymul(q_den, [1, 2]))
    return rf / _sup(np.polymul(q_num, rw_num), np.polymul(q_den, rw_den))


def _check(d, filter_poles, form_poles):
    """The reference's checks: gap = fdif2ngap, ‖Rw‖∞ = 1; and the poles."""
    form = d.internal_form()
    assert d.gap == pytest.approx(float(fdif2ngap(form).ratio), rel=1e-8)
    assert hinf_norm(minimal_channel(form, list(d.model.noise)))[0] == pytest.approx(1.0, rel=1e-8)
    np.testing.assert_allclose(np.sort(d.poles.real), np.sort(filter_poles), rtol=1e-7, atol=1e-9)
    ch = minimal_channel(form, list(d.model.faults) + list(d.model.noise))
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(ch.A).real), np.sort(form_poles), rtol=1e-7, atol=1e-9)


def test_low_pass_wiener_hopf():
    # nonstd = 3: gpole(Q) ≈ gpole(sysf) = [−2]; by hand Q is constant, Rw = c/(s+2): gap = 2
    d = afdsyn(low_pass(), nonstd="wiener-hopf")
    assert d.factorization == "wiener-hopf" and d.shifted == 1 and d.order == 0
    _check(d, [], [-2.0])
    assert d.gap == pytest.approx(2.0, rel=1e-8)


def test_low_pass_wiener_hopf_shift():
    # nonstd = 4, sdegzer = −0.1: sort(gpole(Q)) ≈ [−2; 1/sdegzer]; by hand Q ∝ (0.2s + 3)/(0.1s + 1)
    d = afdsyn(low_pass(), nonstd="wiener-hopf-shift", sdegzer=-0.1)
    _check(d, [-10.0], [-2.0, -10.0])
    assert d.gap == pytest.approx(_hand_gap([0.2, 3], [0.1, 1], [1], [1, 2]), rel=1e-6)


def test_low_pass_wiener_hopf_regularize():
    # nonstd = 5, epsreg = 0.3: gpole(Q) ≈ [−gap]; by hand the pole is −√(4 + 1/ε²)
    d = afdsyn(low_pass(), nonstd="wiener-hopf-regularize", epsreg=0.3)
    a = np.sqrt(4 + 1 / 0.09)
    _check(d, [-a], [-a])
    assert d.gap == pytest.approx(a, rel=1e-8)


def test_high_pass_wiener_hopf():
    # nonstd = 3: gpole(Q) ≈ [−2]; by hand Q is constant, Rw = s/(s+2): gap = ‖(s+1)/(s+2)‖∞ = 1
    d = afdsyn(high_pass(), nonstd="wiener-hopf")
    _check(d, [], [-2.0])
    assert d.gap == pytest.approx(1.0, rel=1e-8)


def test_high_pass_wiener_hopf_shift():
    # nonstd = 4, sdegzer = −0.1: sort(gpole(Q)) ≈ [−2; sdegzer]; by hand Q ∝ (s + 2.1)/(s + 0.1)
    d = afdsyn(high_pass(), nonstd="wiener-hopf-shift", sdegzer=-0.1)
    _check(d, [-0.1], [-2.0, -0.1])
    assert d.gap == pytest.approx(_hand_gap([1, 2.1], [1, 0.1], [1, 0], [1, 2]), rel=1e-6)


def test_high_pass_wiener_hopf_regularize():
    # nonstd = 5, epsreg = 0.3: gap ≈ fdif2ngap, ‖Rw‖∞ ≈ 1; by hand Q ∝ (s+2)/(s+b), b = 2ε/√(1+ε²), gap 1/b
    d = afdsyn(high_pass(), nonstd="wiener-hopf-regularize", epsreg=0.3)
    b = 0.6 / np.sqrt(1.09)
    _check(d, [-b], [-b])
    assert d.gap == pytest.approx(1 / b, rel=1e-7)


def slow_zero():
    """Rf = 1, Rw = (s+1)/((s+2)(s+3)): a zero at infinity and a slow stable zero at −1."""
    return FaultModel(np.diag([-2.0, -3.0]), [[1.0, 1.0]], Bf=[[0.0], [0.0]], Df=[[1.0]], Bw=[[-1.0], [2.0]],
                      faults=["f"])


def test_smarg_moves_the_slow_zero_too():
    # default smarg = −√ε: the zero at −1 stays a filter pole, the infinite one goes to sdeg;
    # smarg = −2 (reference glcf(…; smarg)): both go to sdeg
    d = afdsyn(slow_zero(), sdeg=-4.0)
    assert d.shifted == 1
    np.testing.assert_allclose(np.sort(d.poles.real), [-4.0, -1.0], rtol=1e-7)
    e = afdsyn(slow_zero(), sdeg=-4.0, smarg=-2.0)
    assert e.shifted == 2
    np.testing.assert_allclose(e.poles.real, [-4.0, -4.0], rtol=1e-6)
    assert e.gap == pytest.approx(float(fdif2ngap(e.internal_form()).ratio), rel=1e-8)


def test_wiener_hopf_factor_by_hand():
    # Rw = (s+1)/((s+2)(s+3)): n_s = s+1, one zero at infinity, r = s+2 (the slower pole of d):
    # X = k (s+1)/(s+3); with δ = −0.5, R = 1/(s+2) → R(1/(1 + 0.5 s)) = (1 + 0.5s)/(3 + s)
    (A, B, C, D), moved = wiener_hopf_row(np.diag([-2.0, -3.0]), [[-1.0], [2.0]], [[1.0, 1.0]], [[0.0]])
    assert moved == 1
    np.testing.assert_allclose(np.linalg.eigvals(A - B @ C / D[0, 0]).real, [-1.0], rtol=1e-9)
    (A, B, C, D), _ = wiener_hopf_row(np.diag([-2.0, -3.0]), [[-1.0], [2.0]], [[1.0, 1.0]], [[0.0]], job="shift",
                                      sdegzer=-0.5)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(A - B @ C / D[0, 0]).real), [-2.0, -1.0], rtol=1e-9)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(A).real), [-3.0, -3.0], rtol=1e-6)
    # the standard case: F is the co-outer factor (|F(jω)| = |g(jω)|)
    (A, B, C, D), moved = wiener_hopf_row([[-1.0]], [[1.0, 0.0]], [[1.0]], [[0.0, 1.0]])
    assert moved == 0
    for w in (0.0, 0.7, 3.0):
        f = (C @ np.linalg.solve(1j * w * np.eye(1) - A, B) + D)[0, 0]
        assert abs(f) == pytest.approx(np.sqrt(1 / (w * w + 1) + 1), rel=1e-12)


def test_wiener_hopf_factor_with_complex_poles():
    # Rw = (s+1)/(s² + 2s + 5): one zero at infinity but only a conjugate pair of poles, so r = s + 1 (the pair's
    # real part) is not a pole of Rw: X = g_o (s + 1), and |X(jω)| = |g(jω)| |jω + 1| (|g_o| = |g| on the axis)
    A, B, C, D = realize_biproper([1.0, 1.0], [1.0, 2.0, 5.0])
    (Af, Bf, Cf, Df), moved = wiener_hopf_row(A, B, C, D)
    assert moved == 1 and Af.shape == (2, 2)
    assert np.linalg.eigvals(Af).real.max() < 0 and np.linalg.eigvals(Af - Bf @ Cf / Df[0, 0]).real.max() < 0
    for w in (0.0, 0.5, 2.0, 10.0):
        s = 1j * w
        g = (s + 1) / (s * s + 2 * s + 5)
        f = (Cf @ np.linalg.solve(s * np.eye(2) - Af, Bf) + Df)[0, 0]
        assert abs(f) == pytest.approx(abs(g) * abs(s + 1), rel=1e-10)


def test_row_factor_helpers_and_bad_input():
    spec = row_spectrum([[-2.0]], [[1.0]], [[1.0]], [[0.0]])
    assert spec.infinite == 1 and spec.gain == pytest.approx(1.0)
    A, B, C, D = realize_biproper([2.0, 1.0], [1.0, 3.0])
    assert (C @ np.linalg.solve(-A, B) + D)[0, 0] == pytest.approx(1 / 3)
    with pytest.raises(ParameterError, match="improper"):
        realize_biproper([1.0, 0.0, 0.0], [1.0, 1.0])
    with pytest.raises(ParameterError, match="2 rows"):
        row_spectrum(np.eye(1), np.ones((1, 1)), np.ones((2, 1)), np.zeros((2, 1)))
    with pytest.raises(ParameterError, match="sdegzer"):
        afdsyn(low_pass(), nonstd="wiener-hopf-shift", sdegzer=0.1)
    with pytest.raises(ParameterError, match="nonstd"):
        afdsyn(low_pass(), nonstd="wiener")
    with pytest.raises(DesignError, match="zero"):
        row_spectrum([[-1.0]], [[0.0]], [[1.0]], [[0.0]])


def test_discrete_non_standard_cases():
    # Rw = (z−1)/(z−0.5) (a zero at 1), Rf = 1, π = 0.95: by hand Q = (z−0.5)/(z−0.95), Rw → (z−1)/(z−0.95) with
    # ‖Rw‖∞ = 2/1.95 (at z = −1), ‖Rf‖∞ = 0.5/0.05 = 10 (at z = 1): gap 9.75
    m = FaultModel([[0.5]], [[-0.5]], Bf=[[0.0]], Df=[[1.0]], Bw=[[1.0]], Dw=[[1.0]], faults=["f"], dt=0.1)
    d = afdsyn(m)
    assert d.factorization == "quasi" and d.shifted == 1
    assert d.gap == pytest.approx(10 / (2 / 1.95), rel=1e-8)
    np.testing.assert_allclose(d.poles.real, [0.95], rtol=1e-9)
    # Wiener–Hopf: π = 0.5 (the pole of R_wo = R_w), R_woe = 1, Q constant, ‖Rw‖∞ = 2/1.5 at z = −1: gap 0.75;
    # regularised, |R_ε|² = |R_w|² + ε² = |R_w|² + 0.09: ‖Rf‖∞ = 1/ε (z = 1, R_w = 0) and ‖Rw‖∞ = (4/3)/(41/30)
    # (z = −1): gap 41/12
    dw = afdsyn(m, nonstd="wiener-hopf")
    assert dw.factorization == "wiener-hopf" and dw.shifted == 1 and dw.order == 0
    assert dw.gap == pytest.approx(0.75, rel=1e-8)
    assert afdsyn(m, nonstd="wiener-hopf-regularize", epsreg=0.3).gap == pytest.approx(41 / 12, rel=1e-8)
    # shifted, δ = 0.95: R_wouz(z/δ) = (z − 0.95)/(z − 0.475), Q = (z − 0.475)/(z − 0.95): brute force on |z| = 1
    ds = afdsyn(m, nonstd="wiener-hopf-shift", sdegzer=0.95)
    z = np.exp(1j * np.linspace(0.0, np.pi, 200001))
    q = np.abs((z - 0.475) / (z - 0.95))
    assert ds.gap == pytest.approx(q.max() / (q * np.abs((z - 1) / (z - 0.5))).max(), rel=1e-6)
    np.testing.assert_allclose(ds.poles.real, [0.95], rtol=1e-9)
    with pytest.raises(ParameterError, match="sdegzer"):
        afdsyn(m, nonstd="wiener-hopf-shift", sdegzer=-0.1)
    assert afdsyn(m, nonstd="regularize").factorization == "regularized"
    # D = 0 is standard in discrete time: Rw = 1/(z−0.5) → Rw = z⁻¹ (inner), Rf = (z−0.5)/z: gap 1.5
    m0 = FaultModel([[0.5]], [[1.0]], Bf=[[0.0]], Df=[[1.0]], Bw=[[1.0]], faults=["f"], dt=0.1)
    d0 = afdsyn(m0)
    assert d0.factorization == "standard" and d0.gap == pytest.approx(1.5, rel=1e-8)


def _two_residuals(theta: float = 0.0) -> FaultModel:
    """Rf = U [1; 1], Rw = U diag(1/(s+2), s/(s+3)) (a zero at ∞ and one at 0), U a rotation by ``theta``."""
    U = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    return FaultModel(np.diag([-2.0, -3.0]), U @ np.diag([1.0, -3.0]), Bf=np.zeros((2, 1)), Df=U @ [[1.0], [1.0]],
                      Bw=np.eye(2), Dw=U @ np.diag([0.0, 1.0]), faults=["f"])


@pytest.mark.parametrize("theta", [0.0, 0.4])
def test_two_residuals_wiener_hopf_by_hand(theta):
    # R_w is its own quasi-co-outer factor; π = −2, −3 (its poles) make R_woe = ±I: Q constant, Rw unchanged,
    # ‖Rw‖∞ = 1 and ‖Rf‖∞ = √2: gap √2, for the rotated outputs too
    d = afdsyn(_two_residuals(theta), rdim=2, nonstd="wiener-hopf")
    assert d.factorization == "wiener-hopf" and d.shifted == 2 and d.order == 0
    assert d.gap == pytest.approx(np.sqrt(2.0), rel=1e-8)
    assert hinf_norm(minimal_channel(d.internal_form(), ["w0", "w1"]))[0] == pytest.approx(1.0, rel=1e-8)
    assert d.gap == pytest.approx(float(fdif2ngap(d.internal_form()).ratio), rel=1e-8)


@pytest.mark.parametrize("theta", [0.0, 0.4])
def test_two_residuals_wiener_hopf_shift_by_brute_force(theta):
    # δ = −0.1, both kinds of zeros: φ = (s + 0.1)/(1 + 0.1 s), R_wouz(φ) = diag((0.1s+1)/(1.2s+2.1),
    # (s+0.1)/(1.3s+3.1)); Q = R_wouz(φ)⁻¹ (up to a rotation): Rf = [(1.2s+2.1)/(0.1s+1); (1.3s+3.1)/(s+0.1)],
    # Rw = diag((1.2s+2.1)/((0.1s+1)(s+2)), s(1.3s+3.1)/((s+0.1)(s+3))); gap by brute force on the jω axis
    d = afdsyn(_two_residuals(theta), rdim=2, nonstd="wiener-hopf-shift", sdegzer=-0.1)
    s = 1j * np.concatenate([[0.0], np.logspace(-4, 5, 90001)])
    f1, f2 = (1.2 * s + 2.1) / (0.1 * s + 1), (1.3 * s + 3.1) / (s + 0.1)
    w1, w2 = f1 / (s + 2), f2 * s / (s + 3)
    gap = max(np.sqrt(np.abs(f1) ** 2 + np.abs(f2) ** 2).max(), np.sqrt(12.0 ** 2 + 1.3 ** 2)) / max(
        np.abs(w1).max(), np.abs(w2).max())
    assert d.gap == pytest.approx(gap, rel=1e-6)
    np.testing.assert_allclose(np.sort(d.poles.real), [-10.0, -0.1], rtol=1e-7)


def test_two_residuals_wiener_hopf_regularize_by_brute_force():
    # ε = 0.3: R_woe = I, R_ε = diag(ρ1, ρ2) with |ρi|² = |ui|² + ε², u = (1/(s+2), s/(s+3)):
    # Rf = [1/ρ1; 1/ρ2], Rw = diag(u1/ρ1, u2/ρ2)
    d = afdsyn(_two_residuals(), rdim=2, nonstd="wiener-hopf-regularize", epsreg=0.3)
    s = 1j * np.concatenate([[0.0], np.logspace(-4, 5, 90001)])
    u1, u2 = np.abs(1 / (s + 2)), np.abs(s / (s + 3))
    r1, r2 = np.sqrt(u1 ** 2 + 0.09), np.sqrt(u2 ** 2 + 0.09)
    gap = np.sqrt(1 / r1 ** 2 + 1 / r2 ** 2).max() / max((u1 / r1).max(), (u2 / r2).max())
    assert d.gap == pytest.approx(gap, rel=1e-6)


def test_several_rows_agree_with_the_row_form():
    # one row through the general two-pass factor equals the one-row polynomial factor (real slowest poles)
    from fdikit.design.nullspace.wiener_hopf import wiener_hopf

    s = 0.7j
    for sys in (([[-2.0]], [[1.0]], [[1.0]], [[0.0]]), ([[-2.0]], [[-2.0]], [[1.0]], [[1.0]])):
        for job in ("plain", "shift", "regularize"):
            F1, m1 = wiener_hopf_row(*sys, job=job, sdegzer=-0.1, epsreg=0.3)
            f2 = wiener_hopf(*sys, job=job, sdegzer=-0.1, epsreg=0.3)
            v1, v2 = (C @ np.linalg.solve(s * np.eye(len(A)) - A, B) + D if len(A) else D
                      for A, B, C, D in (F1, f2.outer))
            assert m1 == f2.shifted == 1
            np.testing.assert_allclose(v2, v1, rtol=1e-9)


def test_moebius_substitution():
    from fdikit.design.nullspace.wiener_hopf import moebius

    A, B, C, D = np.array([[-1.0, 2.0], [0.0, -3.0]]), np.array([[1.0], [1.0]]), np.array([[1.0, 0.5]]), [[0.2]]
    a, b, c, d = 1.0, 0.1, 0.1, 1.0
    Ab, Bb, Cb, Db = moebius(A, B, C, D, a, b, c, d)
    for s in (0.3j, 2.0 + 1j):
        phi = (a * s + b) / (c * s + d)
        g = C @ np.linalg.solve(phi * np.eye(2) - A, B) + D
        gb = Cb @ np.linalg.solve(s * np.eye(2) - Ab, Bb) + Db
        np.testing.assert_allclose(gb, g, rtol=1e-12)
    with pytest.raises(ParameterError, match="degenerate"):
        moebius(A, B, C, D, 1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ParameterError, match="pole of G"):
        moebius(A, B, C, D, -1.0, 0.0, 1.0, 1.0)


def _complex_pair_model(theta: float, coupled: bool) -> FaultModel:
    """Rw = U G, Rf = U [1; 1]: G = diag((s²+1)/((s+1)(s+2)), 1/(s+3)), or (``coupled``) with 1/(s+4)(s+3) added at
    (1, 2), which makes the left null vector at ±j complex (the pair is removed on two rows)."""
    import control

    num = [[[1, 0, 1], [1 if coupled else 0]], [[0], [1]]]
    den = [[[1, 3, 2], [1, 7, 12] if coupled else [1]], [[1], [1, 3]]]
    G = control.minreal(control.ss(control.tf(num, den)), verbose=False)
    U = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    return FaultModel(G.A, U @ G.C, Bf=np.zeros((G.nstates, 1)), Df=U @ [[1.0], [1.0]], Bw=G.B, Dw=U @ G.D,
                      faults=["f"])


def test_two_residuals_with_a_complex_boundary_pair_by_hand():
    # quasi, π = −1: F = diag((s+1)/(s+2), (s+1)/(s+3)), Rw → diag((s²+1)/(s+1)², 1/(s+1)) (‖·‖∞ = 1) and
    # Rf → [(s+2)/(s+1); (s+3)/(s+1)], ‖Rf‖∞ = √13 (ω = 0).  Wiener–Hopf, π = −1 (the zero at ∞), −2, −3 (the pair):
    # R_woe = diag((s+3)/(s+1), (s+1)/(s+3)), Rw → diag((s²+1)/((s+2)(s+3)), 1/(s+1)), ‖Rf‖∞ = √(1/9 + 9) (ω = 0)
    for theta in (0.0, 0.4):
        m = _complex_pair_model(theta, coupled=False)
        q = afdsyn(m, rdim=2, sdeg=-1.0)
        assert q.factorization == "quasi" and q.shifted == 3
        assert q.gap == pytest.approx(np.sqrt(13.0), rel=1e-8)
        w = afdsyn(m, rdim=2, nonstd="wiener-hopf")
        assert w.factorization == "wiener-hopf" and w.shifted == 3
        assert w.gap == pytest.approx(np.sqrt(82.0) / 3, rel=1e-8)


@pytest.mark.parametrize("nonstd", ["quasi", "wiener-hopf", "wiener-hopf-shift", "wiener-hopf-regularize"])
def test_complex_pair_on_two_rows_is_rotation_invariant(nonstd):
    # no hand value (the factor moving a pair on two rows is one of a family); the reference's checks hold and the
    # design does not depend on a rotation of the outputs
    gaps = []
    for theta in (0.0, 0.4, 1.9):
        d = afdsyn(_complex_pair_model(theta, coupled=True), rdim=2, sdeg=-1.0, nonstd=nonstd, sdegzer=-0.1)
        form = d.internal_form()
        assert d.gap == pytest.approx(float(fdif2ngap(form).ratio), rel=1e-8)
        assert hinf_norm(minimal_channel(form, list(d.model.noise)))[0] == pytest.approx(1.0, rel=1e-8)
        assert d.generator.n == 0 or np.linalg.eigvals(d.generator.A).real.max() < 0
        gaps.append(d.gap)
    np.testing.assert_allclose(gaps, gaps[0], rtol=1e-8)
