"""Discrete game-theoretic detection filters (Murray 2012, Ch. 5): the a-priori observer (5.3), the DARI in its
equivalent forms (5.23)/(5.29)/(5.30)/(5.44b), the DGTFDF (5.42)–(5.43) and its continuous limit (Remark 6.3),
blocking as γ → 0, the positivity guard, the secondary optimisation (5.31)–(5.41) and the σ_min(I − LC) guard."""

import re

import numpy as np
import pytest
import scipy.linalg

from fdikit import FaultModel
from fdikit.design.game.discrete import DiscreteGtfdfDesign, DiscreteGtmfdfDesign, dgtfdf, dgtmfdf
from fdikit.design.game.discrete_setup import (
    discrete_game_generator,
    discrete_game_riccati,
    discrete_game_setup,
    gain_update,
    secondary_cost,
)
from fdikit.design.game.multi_fault import game_filter
from fdikit.design.game.setup import game_problem
from fdikit.design.game.single_fault import single_fault_game_filter
from fdikit.errors import DesignError, ParameterError
from fdikit.plants.f16xl import f16xl_longitudinal
from fdikit.plants.white_speyer import white_speyer


def _rel(a, b):
    return np.linalg.norm(np.asarray(a) - np.asarray(b)) / np.linalg.norm(b)


def _ws_single(dt, gamma=1e-6, Qc=0.002, Mc=0.05, steps=400, target="f1"):
    """White–Speyer §6.2.1 single-fault weights sampled at dt: Q_d = Q_cΔt, M_d = M_c/Δt, V_d = V_c/Δt (V_c = I)."""
    other = "f2" if target == "f1" else "f1"
    model = white_speyer("stable-zero").discretize(dt)
    return discrete_game_setup(model, [target], [other], gamma=gamma, Vbar=gamma / dt, Q=Qc * dt, M=Mc / dt,
                               P0=gamma, steps=steps)


def _random_problem(seed, steps=40):
    """A small test shape: 3 states, 2 outputs, two targets, γ = 1."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((3, 3))
    A = 0.9 * A / np.abs(np.linalg.eigvals(A)).max()
    model = FaultModel(A, rng.standard_normal((2, 3)), Bf=rng.standard_normal((3, 2)), faults=["f1", "f2"], dt=1.0)
    return discrete_game_setup(model, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, P0=1.0,
                               steps=steps)


# ---------------------------------------------------------------------- observer (5.3)
def test_generator_is_the_a_priori_observer_of_5_3():
    """x̄(k+1) = Φx̂ + Bu u, x̂ = x̄ + L(y − Cx̄ − Du u), r = y − Cx̄ − Du u (a priori, (5.3c)), r̄_i = Q_iᵀ r."""
    rng = np.random.default_rng(3)
    n, p = 4, 3
    A = rng.standard_normal((n, n))
    model = FaultModel(0.9 * A / np.abs(np.linalg.eigvals(A)).max(), rng.standard_normal((p, n)),
                       Bu=rng.standard_normal((n, 2)),
                       Du=rng.standard_normal((p, 2)), Bf=rng.standard_normal((n, 2)), faults=["a", "b"], dt=0.1)
    st = discrete_game_setup(model, ["a", "b"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, steps=5)
    L = 0.3 * rng.standard_normal((n, p))
    gen = discrete_game_generator(st, L)
    assert gen.residuals == ("a[0]", "a[1]", "b[0]", "b[1]") and gen.isolates == ("a", "a", "b", "b")
    Qs = gen.D[:, 2:].T  # D = [−QᵀDu, Qᵀ]: the output projection; Q_iQ_iᵀ = Ĥ_i (rank 2 each)
    for j, t in enumerate(st.names):
        assert np.allclose(Qs[:, 2 * j : 2 * j + 2] @ Qs[:, 2 * j : 2 * j + 2].T, st.problem.projectors[t], atol=1e-12)
    stepper = gen.online()
    u, y = rng.standard_normal((60, 2)), rng.standard_normal((60, p))
    xbar, err = np.zeros(n), 0.0
    for k in range(60):
        r = y[k] - model.C @ xbar - model.Du @ u[k]
        xhat = xbar + L @ r
        err = max(err, np.abs(stepper.step(u[k], y[k]) - Qs.T @ r).max())
        xbar = model.A @ xhat + model.Bu @ u[k]
    assert err < 1e-12


# ---------------------------------------------------------------------- DARI forms
def test_dari_propagation_equals_5_29_5_30_and_5_44b_and_schur_form_5_23():
    rng = np.random.default_rng(11)
    n, p, gamma = 4, 3, 0.5
    model = FaultModel(scipy.linalg.expm(0.3 * rng.standard_normal((n, n))), rng.standard_normal((p, n)),
                       Bf=rng.standard_normal((n, 3)), faults=["t", "n1", "n2"], dt=0.1)
    X = rng.standard_normal((n, n))
    P = X @ X.T / n + 0.2 * np.eye(n)
    M = np.diag([0.7, 1.3])
    st = discrete_game_setup(model, ["t"], ["n1", "n2"], gamma=gamma, Vbar=0.8 * gamma * np.eye(p), Q=0.05, M=M,
                             P0=gamma * P, steps=1)
    L = 0.4 * rng.standard_normal((n, p))
    Pi_next = np.linalg.inv(discrete_game_riccati(st, L).covariances["t"][1])
    Phi, C, V = model.A, model.C, st.V
    H, Fh, Q = st.problem.projectors["t"], st.problem.complementary["t"], 0.05 * np.eye(p)
    Pi = np.linalg.inv(P)  # P(k0) = P0/γ = P
    Gam = Pi - C.T @ H @ Q @ H @ C  # (5.17)
    Phat = Phi @ (np.eye(n) - L @ C)
    Gh = np.linalg.inv(Phat).T @ Gam @ np.linalg.inv(Phat)
    G = Fh @ M @ Fh.T / gamma + Phi @ L @ V @ L.T @ Phi.T
    assert _rel(Pi_next, np.linalg.solve(np.eye(n) + Gh @ G, Gh)) < 1e-10  # (5.29) with equality
    assert np.abs((np.eye(n) + Gh @ G) @ Pi_next - Gh).max() < 1e-10 * np.abs(Gh).max()  # (5.30): Ψ_i = 0
    Lam = Pi - C.T @ (H @ Q @ H - np.linalg.inv(V)) @ C  # (5.44a)
    Li = np.linalg.inv(Lam)
    extra = (L @ V - Li @ C.T) @ np.linalg.solve(V - C @ Li @ C.T, V @ L.T - C @ Li)
    assert _rel(Pi_next, np.linalg.inv(Phi @ (Li + extra) @ Phi.T + Fh @ M @ Fh.T / gamma)) < 1e-10  # (5.44b)
    L_star = Li @ C.T @ np.linalg.inv(V)  # the (5.44) extra term vanishes at L = Λ⁻¹CᵀV⁻¹
    assert np.abs(L_star @ V - Li @ C.T).max() < 1e-12 * np.abs(Li).max()
    # (5.23) with the transposes restored (the text prints F̂_iΓ̂_iΦL in the (2,3) block): at equality its Schur
    # complement (5.27) vanishes, so Ψ̂_i ≤ 0 with exactly n zero eigenvalues.
    B = np.hstack([Fh, -Phi @ L])
    Dblk = scipy.linalg.block_diag(gamma * np.linalg.inv(M), np.linalg.inv(V)) + B.T @ Gh @ B
    Psi = np.block([[Pi_next - Gh, Gh @ B], [B.T @ Gh, -Dblk]])
    ev = np.linalg.eigvalsh((Psi + Psi.T) / 2)
    scale = np.abs(ev).max()
    assert ev.max() < 1e-10 * scale and np.sum(np.abs(ev) < 1e-10 * scale) == n


def test_printed_5_38_is_not_the_inverse_of_5_35_but_the_transposed_form_is():
    """Erratum: Δ̃ = (I + Γ̂G)ᵀΦ̂ΛΦ̂ᵀ(I + Γ̂G) inverts (5.35); the printed (5.38) does not."""
    rng = np.random.default_rng(5)
    n = 4
    Phat, Gh, G, D = (rng.standard_normal((n, n)) for _ in range(4))
    Gh, G, Dt = Gh @ Gh.T + np.eye(n), G @ G.T, D + D.T
    E = np.eye(n) + Gh @ G
    Lam = np.linalg.inv(Phat) @ np.linalg.inv(E).T @ Dt @ np.linalg.inv(E) @ np.linalg.inv(Phat).T  # (5.35), W = 0
    assert _rel(E.T @ Phat @ Lam @ Phat.T @ E, Dt) < 1e-10
    assert _rel(E @ Phat.T @ Lam @ Phat @ E.T, Dt) > 0.1


# ---------------------------------------------------------------------- DGTFDF (5.42)–(5.43)
def test_dgtfdf_is_5_42_and_the_recursion_at_its_gain_reproduces_it():
    st = _ws_single(0.01, steps=400)
    d = dgtfdf(st)
    assert d.settled and d.settling_step is not None and d.settling_step < 400
    # recursion (5.29)/(5.30) driven by the time-varying DGTFDF gain = the DGTFDF covariances
    sol = discrete_game_riccati(st, d.filter_gains)  # Murray's filtered-form L(k); d.gain = Φ L is the observer gain
    assert max(_rel(a, b) for a, b in zip(sol.covariances["f1"], d.covariances)) < 1e-10
    # independent information-form (5.42)–(5.43): Σ = Θ − Cᵀ(ĤQĤ − V⁻¹)C, Θ̃ = [ΦΣ⁻¹Φᵀ + F̂MF̂ᵀ/γ]⁻¹, L = Σ⁻¹CᵀV⁻¹
    m, H, Fh = st.model, st.problem.projectors["f1"], st.problem.complementary["f1"]
    Vi = np.linalg.inv(st.V)
    Theta = np.linalg.inv(st.P_init)
    worst_L = worst_T = 0.0
    for k in range(60):
        Sigma = Theta - m.C.T @ (H @ st.Q["f1"] @ H - Vi) @ m.C
        Lk = np.linalg.solve(Sigma, m.C.T @ Vi)
        worst_L = max(worst_L, _rel(d.filter_gains[k], Lk))
        Theta = np.linalg.inv(m.A @ np.linalg.solve(Sigma, m.A.T) + Fh @ st.M["f1"] @ Fh.T / st.gamma)
        worst_T = max(worst_T, _rel(d.covariances[k + 1], np.linalg.inv(Theta)))
    assert worst_L < 1e-7 and worst_T < 1e-7
    assert np.all(np.abs(d.poles) < 1)


def test_dgtfdf_approaches_the_continuous_gtfdf_of_remark_6_3():
    """Continuous GTFDF (0 = AP + PAᵀ + F̂MF̂ᵀ/γ − PCᵀ(V⁻¹ − ĤQĤ)CP, L = PCᵀV⁻¹), §6.2.1 with Q = 0.002 I, M = 0.05,
    V = I, γ = 1e-6: Remark 6.3 prints eig(A − LC) = −3.0003, −5.4041, −223.63.  Sampling with Q_d = QΔt, M_d = M/Δt
    (ZOH fault columns ≈ F̂Δt), V_d = V/Δt makes the DARI a first-order discretisation of this CARE, so the settled
    discrete poles satisfy ln(z)/Δt → s with an error that falls with Δt."""
    mc = white_speyer("stable-zero")
    prob = game_problem(mc, ["f1"], ["f2"])
    H, Fh = prob.projectors["f1"], prob.complementary["f1"]
    Pc = scipy.linalg.solve_continuous_are(mc.A.T, mc.C.T, Fh @ Fh.T * 0.05 / 1e-6,
                                           np.linalg.inv(np.eye(2) - 0.002 * H))
    Lc = Pc @ mc.C.T
    s_c = np.sort(np.linalg.eigvals(mc.A - Lc @ mc.C).real)
    assert np.allclose(s_c, [-223.63, -5.4041, -3.0003], rtol=3e-5)
    errors = {}
    for dt in (2e-3, 1e-3):
        d = dgtfdf(_ws_single(dt, steps=int(3 / dt)))
        assert d.settled
        s_d = np.sort((np.log(d.poles.astype(complex)) / dt).real)
        errors[dt] = (np.abs(s_d - s_c) / np.abs(s_c), _rel(d.filter_gain / dt, Lc))  # Murray's filtered-form L
    # measured: pole errors 8.2e-3, 3.8e-5, 2.9e-6 (Δt = 2 ms) → 2.1e-3, 1.9e-5, 7.1e-7 (1 ms); gain 0.20 → 0.11
    assert np.all(errors[1e-3][0] < [3e-3, 3e-5, 2e-6])
    assert np.all(errors[2e-3][0] / errors[1e-3][0] > 1.8)
    assert errors[1e-3][1] < 0.15 and errors[2e-3][1] / errors[1e-3][1] > 1.7


def test_blocking_grows_as_gamma_falls_with_V_fixed():
    """Note §9 item 14: Π F̂ → 0 as γ → 0 (V = V̄/γ and Π_0 held, the Ch. 4 limit)."""
    gammas = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7]
    ratios, target = [], []
    for g in gammas:
        st = _ws_single(0.01, gamma=g, Qc=1e-3, steps=800)
        d = dgtfdf(st)
        Pi = d.information()
        Fh, F = st.problem.complementary["f1"], st.problem.targets["f1"]
        ratios.append(np.linalg.norm(Pi @ Fh) / (np.linalg.norm(Pi) * np.linalg.norm(Fh)))
        target.append(np.linalg.norm(Pi @ F) / (np.linalg.norm(Pi) * np.linalg.norm(F)))
        assert d.levels.max() < 1 and np.linalg.eigvalsh(d.covariances).min() > 0
    # measured: 0.369, 0.176, 0.0627, 0.0195, 0.00499, 8.6e-4, 9.9e-5; the target stays 0.82 … 0.73
    assert np.all(np.diff(ratios) < 0) and ratios[0] > 0.3 and ratios[-1] < 2e-4
    assert min(target) > 0.7


def test_with_vbar_fixed_gamma_only_rescales_q():
    """With V̄, M and P0 fixed, P(γ, Q) = P(1, Q/γ)/γ exactly (Γ = γ(P'⁻¹ − CᵀĤQĤC/γ)): lowering γ then only raises the
    effective output weight — a harder H∞ condition — and ‖ΠF̂‖/‖Π‖ hardly moves.  Blocking needs V = V̄/γ held."""
    model = white_speyer("stable-zero").discretize(0.01)
    kw = dict(Vbar=1e-4, M=5.0, P0=1e-9, steps=300)
    a = dgtfdf(discrete_game_setup(model, ["f1"], ["f2"], gamma=1e-4, Q=0.3, **kw))
    b = dgtfdf(discrete_game_setup(model, ["f1"], ["f2"], gamma=1.0, Q=0.3 / 1e-4, **kw))
    c = dgtfdf(discrete_game_setup(model, ["f1"], ["f2"], gamma=1.0, Q=0.0, **kw))
    assert max(_rel(pa * 1e-4, pb) for pa, pb in zip(a.covariances, b.covariances)) < 1e-12
    assert _rel(a.filter_gain, b.filter_gain) < 1e-12 and _rel(a.filter_gain, c.filter_gain) > 0.01  # Q matters (1.8 %)
    Fh = model.Bf[:, 1:]
    ratios = []
    for g in (1e-2, 1e-3, 1e-4, 1e-5):
        Pi = dgtfdf(discrete_game_setup(model, ["f1"], ["f2"], gamma=g, Q=1e-6, **kw)).information()
        ratios.append(np.linalg.norm(Pi @ Fh) / np.linalg.norm(Pi) / np.linalg.norm(Fh))
    assert max(ratios) / min(ratios) < 1.01  # measured 8.584e-4 throughout


# ---------------------------------------------------------------------- the positivity guard and bad input
def test_guard_names_target_step_and_eigenvalue():
    with pytest.raises(DesignError, match=r"target 'f1'.*step k = 0 \(smallest eigenvalue -"):
        dgtfdf(_ws_single(0.01, Qc=1e3))
    # the §6.2.1 filter designed for f2 does not serve the f1 DAP: positivity is lost part-way through the horizon
    st2 = _ws_single(0.01, steps=300, target="f2")
    L2 = dgtfdf(st2).filter_gain  # the DARI takes Murray's filtered-form gain
    st1 = _ws_single(0.01, steps=300)
    with pytest.raises(DesignError, match=r"target 'f1'.*step k = (\d+)") as info:
        discrete_game_riccati(st1, L2)
    k = int(re.search(r"step k = (\d+)", str(info.value)).group(1))
    assert k > 0
    prefix = discrete_game_riccati(_ws_single(0.01, steps=k), L2)  # feasible up to k − 1, the eigenvalue turns at k
    R = st1.output_weight_root("f1")
    lam = [np.linalg.eigvalsh(np.linalg.inv(P) - R.T @ R).min() for P in prefix.covariances["f1"]]
    assert min(lam[:-1]) > 0 and lam[-1] <= 0


def test_bad_input_raises_design_errors():
    model = white_speyer("stable-zero")
    md = model.discretize(0.01)
    with pytest.raises(DesignError, match="discretize"):
        discrete_game_setup(model, ["f1"], ["f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0)
    with pytest.raises(DesignError, match="Φ = model.A is singular"):
        discrete_game_setup(md.replace(A=np.diag([1.0, 0.5, 0.0])), ["f1"], ["f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0)
    with pytest.raises(ParameterError, match="gamma"):
        discrete_game_setup(md, ["f1"], ["f2"], gamma=0.0, Vbar=1.0, Q=0.1, M=1.0)
    with pytest.raises(ParameterError, match=r"M\[f1\] must be positive definite"):
        discrete_game_setup(md, ["f1"], ["f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=0.0)
    with pytest.raises(ParameterError, match=r"weight Q has no entry for target\(s\) \['f2'\]"):
        discrete_game_setup(md, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q={"f1": 0.1}, M=1.0)
    st = discrete_game_setup(md, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, steps=10)
    with pytest.raises(DesignError, match="I − LC is singular"):
        discrete_game_riccati(st, np.linalg.pinv(md.C) @ np.diag([1.0, 1.0]) @ md.C @ np.linalg.pinv(md.C))
    with pytest.raises(ParameterError, match="name the one"):
        dgtfdf(st)
    with pytest.raises(DesignError, match="K_i and N_i are all zero"):
        dgtmfdf(st)
    with pytest.raises(ParameterError, match="max_radius"):
        dgtmfdf(st, max_radius=1.0)
    with pytest.raises(ParameterError, match="one constant gain"):
        secondary_cost(st, np.zeros((10, 3, 2)))


# ---------------------------------------------------------------------- secondary optimisation (5.31)–(5.41)
def test_gradient_5_34_matches_finite_differences():
    st = _random_problem(1)
    L = np.mean([dgtfdf(st, t).filter_gain for t in st.names], axis=0)  # (5.31)–(5.41) use the filtered form
    _, g = secondary_cost(st, L)
    fd = np.zeros_like(L)
    for idx in np.ndindex(L.shape):
        E = np.zeros_like(L)
        E[idx] = 1e-6
        fd[idx] = (secondary_cost(st, L + E)[0] - secondary_cost(st, L - E)[0]) / 2e-6
    assert np.abs(fd - g).max() < 1e-6 * np.abs(g).max()
    # the badly scaled §6.2.1 setting (1/γ = 1e6): dominant entries agree to 1e-4
    st = discrete_game_setup(white_speyer("stable-zero").discretize(0.01), ["f1", "f2"], gamma=1e-6, Vbar=1e-4,
                             Q={"f1": 1e-5, "f2": 2e-5}, M=5.0, P0=1e-6, K=1e3, N={"f1": 5e4, "f2": 1e5}, steps=100)
    L = dgtfdf(st, "f1").filter_gain
    _, g = secondary_cost(st, L)
    for idx in [np.unravel_index(np.argmax(np.abs(g)), g.shape), (2, 1)]:
        E = np.zeros_like(L)
        E[idx] = 1e-6 * np.abs(L).max()
        fd = (secondary_cost(st, L + E)[0] - secondary_cost(st, L - E)[0]) / (2 * E[idx])
        assert abs(fd - g[idx]) < 1e-4 * abs(g[idx])


def test_gain_iteration_5_41_reaches_a_spurious_point_and_the_guard_avoids_it():
    """Note §7.4: (5.41) is stationarity multiplied by (I − LC)ᵀ … V⁻¹(I − CL); iterated blindly it converges where
    I − LC is singular although ∇J̄ ≠ 0.  The guarded design stops there and finishes by descent on J̄."""
    st = _random_problem(0)
    L0 = np.mean([dgtfdf(st, t).filter_gain for t in st.names], axis=0)
    L = L0
    for _ in range(25):
        L = gain_update(st, L)
    J_spurious, g_spurious = secondary_cost(st, L)
    smin = np.linalg.svd(np.eye(3) - L @ st.model.C, compute_uv=False)[-1]
    assert smin < 1e-4 and _rel(gain_update(st, L), L) < 1e-3  # a fixed point of (5.41) …
    assert np.linalg.norm(g_spurious) > 1e3  # … that is not stationary (measured ‖∇J̄‖ = 1.9e4)
    guarded = dgtmfdf(st, L0, method="fixed-point", max_radius=0.9999)
    assert "guard: σ_min" in guarded.notes[0] and guarded.sigma_min >= 1e-3
    d = dgtmfdf(st, L0, max_radius=0.9999)
    assert d.method == "fixed-point+gradient" and d.sigma_min > 0.3
    assert d.cost < J_spurious - 2000  # measured −5233.49 against −2771.6 at the spurious point
    assert np.linalg.norm(d.gradient) < 1e-6 * np.linalg.norm(g_spurious)


def test_gain_iteration_and_descent_agree_at_a_regular_stationary_point():
    st = _random_problem(1)
    fp = dgtmfdf(st, method="fixed-point", max_radius=0.9999)
    gd = dgtmfdf(st, method="gradient", max_radius=0.9999)
    assert fp.notes[0].startswith("fixed-point: converged")
    assert abs(fp.cost - gd.cost) < 1e-8 * abs(fp.cost) and _rel(fp.filter_gain, gd.filter_gain) < 1e-4
    assert np.linalg.norm(fp.gradient) < 1e-7 * abs(fp.cost)  # measured 7e-6 against J̄ = −593.2


def test_multi_target_f16_design_is_stable_feasible_and_isolates():
    """F-16XL RDDF partition of Murray §6.1.3 (targets θ sensor and elevon, gust nuisance; M = 0.01, Q_θ = 2e-4,
    Q_δ = 1e-4, K = 0.01, N_θ = 1, N_δ = 1.5, γ = 1e-6, V = I), sampled at Δt = 0.05 s over 10 s, started from the
    exact Beard–Jones structure (Φ(I − L) with eigenvectors [F_θ F_δ F_wg], poles −2 … −5) and kept within
    ρ ≤ e^{−Δt} (decay ≥ 1/s)."""
    dt, gamma = 0.05, 1e-6
    mc = f16xl_longitudinal()
    e4 = np.eye(4)[:, 3:]
    Fc = {"theta": np.hstack([e4, -mc.A @ e4]), "elevon": mc.Bu, "gust": mc.Bd}
    Gd = scipy.linalg.expm(np.block([[mc.A, np.eye(4)], [np.zeros((4, 8))]]) * dt)[:4, 4:]  # ZOH input map
    Fd = {k: Gd @ v for k, v in Fc.items()}
    md = mc.discretize(dt)
    st = discrete_game_setup(md, {"theta": Fd["theta"], "elevon": Fd["elevon"]}, {"gust": Fd["gust"]}, gamma=gamma,
                             Vbar=gamma / dt, Q={"theta": 2e-4 * dt, "elevon": 1e-4 * dt}, M=0.01 / dt, P0=gamma,
                             K=0.01 / dt**2, N={"theta": 1 / dt**2, "elevon": 1.5 / dt**2}, steps=200)
    T = np.hstack([Fd["theta"], Fd["elevon"], Fd["gust"]])
    L0 = np.eye(4) - np.linalg.solve(md.A, T @ np.diag(np.exp(np.array([-2.0, -3.0, -4.0, -5.0]) * dt))
                                     @ np.linalg.inv(T))
    d = dgtmfdf(st, L0, max_radius=np.exp(-dt))
    assert d.cost < d.initial_cost and np.abs(d.poles).max() <= np.exp(-dt) + 1e-12
    for t in st.names:  # item 14: the forward recursion stays positive definite at the designed gain
        assert d.riccati.levels[t].max() < 1e-3 and np.linalg.eigvalsh(d.riccati.covariances[t]).min() > 0
    faults = md.replace(Bf=T, faults=["theta_rate", "theta_mag", "elevon_f", "gust_f"])
    G = np.abs(d.generator.internal_form(faults).freqresp([0.0], "f")[0])  # rows θ[0], θ[1], elevon[0]
    th, el = G[:2], G[2]
    ratio_th = np.linalg.norm(th[:, :2]) / max(np.linalg.norm(th[:, 2]), np.linalg.norm(th[:, 3]))
    ratio_el = el[2] / max(np.linalg.norm(el[:2]), el[3])
    # measured: θ 1.06 (0.54 at the start), elevon 1.21; leakage ratios 1245 and 978
    assert ratio_th > 100 and ratio_el > 100
    assert np.linalg.norm(th[:, :2]) > 1.5 * np.linalg.norm(
        np.abs(discrete_game_generator(st, L0).internal_form(faults).freqresp([0.0], "f")[0])[:2, :2])


# ---------------------------------------------------------------------- one entry point per design, dispatching on dt
def _same_design(a, b, fields):
    """Equal up to the rounding of V̄ = γ·V (the dispatch multiplies, the direct call was given the product)."""
    for f in fields:
        x, y = np.asarray(getattr(a, f)), np.asarray(getattr(b, f))
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12 * max(np.abs(y).max(), 1e-300), err_msg=f)
    for M in ("A", "B", "C", "D"):
        y = getattr(b.generator, M)
        np.testing.assert_allclose(getattr(a.generator, M), y, rtol=0, atol=1e-12 * max(np.abs(y).max(), 1.0))
    assert a.generator.residuals == b.generator.residuals and a.generator.isolates == b.generator.isolates


def test_single_fault_game_filter_on_a_discrete_model_is_dgtfdf():
    """ARCHITECTURE conventions: one public name per design; a model with dt runs Murray's DGTFDF with V̄ = γV
    (V keeps its meaning V̄/γ), the weights per sample, P0 and steps the horizon (defaults P0 = γ, 500 steps)."""
    dt, gamma = 0.01, 1e-6
    model = white_speyer("stable-zero").discretize(dt)
    d = single_fault_game_filter(model, "f1", ["f2"], gamma=gamma, V=1.0 / dt, Q=0.002 * dt, M=0.05 / dt, P0=gamma,
                                 steps=400)
    assert isinstance(d, DiscreteGtfdfDesign)
    _same_design(d, dgtfdf(_ws_single(dt, steps=400)), ["gain", "filter_gain", "filter_gains", "covariances",
                                                          "levels", "poles"])
    default = single_fault_game_filter(model, "f1", ["f2"], gamma=gamma, V=1.0 / dt, Q=0.002 * dt, M=0.05 / dt)
    _same_design(default, dgtfdf(_ws_single(dt, steps=500)), ["gain", "filter_gains", "covariances"])
    with pytest.raises(ParameterError, match="R_1"):
        single_fault_game_filter(model, "f1", ["f2"], gamma=gamma, V=1.0 / dt, Q=0.002 * dt, M=0.05 / dt, R=1.0)
    with pytest.raises(ParameterError, match="P0, steps"):
        single_fault_game_filter(white_speyer("stable-zero"), "f1", ["f2"], P0=1.0, steps=10)


def test_game_filter_on_a_discrete_model_is_dgtmfdf():
    """game_filter on a model with dt = dgtmfdf on the same setup; method and options go to dgtmfdf, the
    continuous optimiser's margins are refused."""
    st = _random_problem(1)
    kw = dict(gamma=1.0, V=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, P0=1.0, steps=40)
    d = game_filter(st.model, ["f1", "f2"], **kw, method="fixed-point", options={"max_radius": 0.9999})
    assert isinstance(d, DiscreteGtmfdfDesign)
    ref = dgtmfdf(st, method="fixed-point", max_radius=0.9999)
    _same_design(d, ref, ["gain", "filter_gain", "poles", "cost", "initial_cost", "gradient"])
    assert d.method == ref.method and d.notes == ref.notes
    with pytest.raises(ParameterError, match="eps_stab"):
        game_filter(st.model, ["f1", "f2"], **kw, eps_stab=0.1)
    with pytest.raises(ParameterError, match="not keywords"):
        game_filter(st.model, ["f1", "f2"], **kw, options={"maxfun": 3})
    with pytest.raises(ParameterError, match="discrete optimiser method"):
        game_filter(st.model, ["f1", "f2"], **kw, method="L-BFGS-B")


def test_a_non_model_is_a_parameter_error_not_an_attribute_error():
    from fdikit.errors import ParameterError

    with pytest.raises(ParameterError, match="model"):
        discrete_game_setup("not a model", ["f1"], gamma=1.0, Vbar=1.0, Q=1.0, M=1.0)
