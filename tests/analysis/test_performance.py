"""Performance metrics (fdhinfminus, fdiscond, fdif2ngap, fdimmperf, hminus_index) against the reference's
closed-form cases, brute-force frequency grids and Lyapunov-free H2 integrals."""

import numpy as np
import pytest
import scipy.integrate
import scipy.signal

from fdikit import FaultModel
from fdikit.analysis import (
    fdhinfmax,
    fdhinfminus,
    fdif2ngap,
    fdimmperf,
    fdiscond,
    fdisspec,
    fditspec,
    hminus_index,
)
from fdikit.errors import ModelError, ParameterError
from fdikit.residuals import ResidualGenerator

# ---------------------------------------------------------------------- reference cases (test_afdsyn.jl)


def test_gap_of_afdredsyn_low_pass_solution_is_alpha():
    # test_afdsyn.jl "non-standard cases": Rf = (s+1)/(s+2), Rw = 1/(s+2), sdeg = -α gives
    # Q = α(s+2)/(s+α), so Rfw = [α(s+1)/(s+α), α/(s+α)], with info.gap ≈ α ≈ fdif2ngap(Rfw) and ‖Rw‖∞ = 1.
    a = 3.0
    R = FaultModel(A=[[-a]], C=[[1.0]], Bf=[[a * (1 - a)]], Df=[[a]], Bw=[[a]], faults=["f"], noise=["w"])
    gap, beta, gamma = fdif2ngap(R)
    assert gap == pytest.approx(a, rel=1e-8)
    assert gamma == pytest.approx(1.0, rel=1e-8) and beta == pytest.approx(a, rel=1e-8)


def test_gap_of_afdredsyn_high_pass_solution_is_one_over_eps():
    # same file: Rw = s/(s+2), sdeg = -ϵ: Rfw = [(s+1)/(s+ϵ), s/(s+ϵ)], info.gap ≈ 1/ϵ ≈ fdif2ngap(Rfw).
    e = 0.3
    R = FaultModel(A=[[-e]], C=[[1.0]], Bf=[[1 - e]], Df=[[1.0]], Bw=[[-e]], Dw=[[1.0]], faults=["f"], noise=["w"])
    g = fdif2ngap(R)
    assert g.ratio == pytest.approx(1 / e, rel=1e-8)
    assert fdhinfminus(R).freq == pytest.approx(0.0, abs=1e-6)
    assert fdimmperf(R) == pytest.approx(1.0, rel=1e-8)
    assert fdimmperf(R, norm=2) == np.inf  # s/(s+ϵ) is not strictly proper


def _example_5_3():
    """Varga (2017) Example 5.3 (test_evaluation.jl): Gu = [(s+1)/(s+2); (s+2)/(s+3)], Gd = [(s−1)/(s+2); 0],
    Gf = [Gu, [0; 1]], with the nullspace filter Q = [0, 1, −(s+2)/(s+3)] (poles at −3) acting on (y, u)."""
    m = FaultModel(A=np.diag([-2.0, -2.0, -3.0]), C=[[-1.0, -3.0, 0.0], [0.0, 0.0, -1.0]],
                   Bu=[[1.0], [0.0], [1.0]], Du=[[1.0], [1.0]], Bd=[[0.0], [1.0], [0.0]], Dd=[[1.0], [0.0]],
                   controls=["u"], disturbances=["d"], outputs=["y1", "y2"])
    m = m.with_actuator_faults(["u"]).with_sensor_faults(["y2"])
    # z' = −3 z + u,  r = y2 − u + z   (−(s+2)/(s+3) = −1 + 1/(s+3))
    gen = ResidualGenerator(A=[[-3.0]], B=[[1.0, 0.0, 0.0]], C=[[1.0]], D=[[-1.0, 0.0, 1.0]],
                            controls=("u",), outputs=("y1", "y2"), residuals=("r",))
    return m, gen.internal_form(m)


def test_example_5_3_strong_structure_and_decoupling():
    m, R = _example_5_3()
    # the reference: fdisspec(Rf, [0]) == Bool[1 1]; Rf = [(s+2)/(s+3), 1]
    assert fdisspec(R, [0.0]).matrix.tolist() == [[True, True]]
    assert fditspec(R).matrix.tolist() == [[True, True]]
    assert fdisspec(R, 0.0).gains[0, :, 0] == pytest.approx([2 / 3, 1.0], rel=1e-10)
    # u and d decoupled: model matching against M_r = Rf itself is zero (to round-off)
    Mr = FaultModel(A=[[-3.0]], C=[[1.0]], Bf=[[-1.0, 0.0]], Df=[[1.0, 1.0]], faults=R.faults, dt=None)
    assert fdimmperf(R, ref=Mr) < 1e-9
    assert fdiscond(R).ratio == pytest.approx(1.0, rel=1e-8)  # ‖(s+2)/(s+3)‖∞ = ‖1‖∞ = 1
    assert fdif2ngap(R).ratio == np.inf  # no noise, everything else decoupled


# ---------------------------------------------------------------------- brute force


def _random_stable(seed, dt=None, n=4, p=2, mf=3, mw=2):
    rng = np.random.default_rng(seed)
    if dt is None:  # poles with damping ≥ 0.3: peaks smooth on a 20000-point grid
        blocks = []
        for _ in range(n // 2):
            wn, z = rng.uniform(0.5, 5.0), rng.uniform(0.3, 0.9)
            blocks.append(np.array([[0.0, 1.0], [-wn**2, -2 * z * wn]]))
        A = scipy.linalg.block_diag(*blocks)
    else:
        A = np.diag(rng.uniform(-0.8, 0.8, n))
    return FaultModel(A=A, C=rng.standard_normal((p, n)), Bf=rng.standard_normal((n, mf)),
                      Df=0.1 * rng.standard_normal((p, mf)), Bw=rng.standard_normal((n, mw)),
                      faults=[f"f{i}" for i in range(mf)], noise=[f"w{i}" for i in range(mw)], dt=dt)


def _grid(dt):
    return np.concatenate([[0.0], np.logspace(-3, 3, 20000)]) if dt is None else np.linspace(0, np.pi / dt, 20001)


def _resp(R, omega, group):
    """Frequency response (N, p, m) by direct resolvent solves (independent of fdikit's evaluation)."""
    z = 1j * omega if R.dt is None else np.exp(1j * omega * R.dt)
    B, D = R.b(group), R.d(group)
    return np.array([R.C @ np.linalg.solve(zk * np.eye(R.n) - R.A, B) + D for zk in z])  # (N, p, m)


@pytest.mark.parametrize("dt", [None, 0.1])
def test_column_norms_gap_and_condition_match_a_dense_grid(dt):
    R = _random_stable(4, dt)
    omega = _grid(dt)
    Hf, Hw = _resp(R, omega, "f"), _resp(R, omega, "w")
    col = np.linalg.norm(Hf, axis=1).max(axis=0)  # ‖g_j‖∞ on the grid (a lower bound)
    hw = np.linalg.norm(Hw, ord=2, axis=(1, 2)).max()
    beta, gmax = fdhinfminus(R).value, fdhinfmax(R).value
    # the grid peak is below the exact one and within (Δω/ω)²-size of it (rtol 1e-4 for damping ≥ 0.3)
    assert col.min() <= beta * (1 + 1e-9) and beta == pytest.approx(col.min(), rel=1e-4)
    assert gmax == pytest.approx(col.max(), rel=1e-4)
    gap = fdif2ngap(R)
    assert gap.gamma == pytest.approx(hw, rel=1e-4) and gap.ratio == pytest.approx(col.min() / hw, rel=2e-4)
    assert fdiscond(R).ratio == pytest.approx(col.min() / col.max(), rel=2e-4)
    # at given frequencies: exactly the grid values
    some = omega[::4000]
    assert fdhinfminus(R, some).value == pytest.approx(np.linalg.norm(Hf[::4000], axis=1).min(), rel=1e-10)
    assert fdiscond(R, freqs=some).beta == pytest.approx(np.linalg.norm(Hf[::4000], axis=1).min(), rel=1e-10)


def test_h2_norm_matches_frequency_integral_and_impulse_sum():
    R = _random_stable(7, None)
    f = lambda w: np.linalg.norm(_resp(R, np.array([w]), "w")[0], "fro") ** 2  # noqa: E731
    val, _ = scipy.integrate.quad(f, 0, np.inf, limit=400, epsabs=1e-12, epsrel=1e-10)
    assert fdimmperf(R, norm=2) == pytest.approx(np.sqrt(val / np.pi), rel=1e-7)
    Rd = _random_stable(8, 0.1)
    _, h = scipy.signal.dimpulse((Rd.A, Rd.Bw, Rd.C, Rd.Dw, 0.1), n=4000)  # |eig| ≤ 0.8: tail < 1e-300
    total = sum(float(np.sum(hi**2)) for hi in h)
    assert fdimmperf(Rd, norm=2) == pytest.approx(np.sqrt(total), rel=1e-9)


def test_hminus_index_against_grid_with_a_lightly_damped_zero():
    # G = (s² + 2ζω0 s + ω0²)/(s + 1)², ζ = 0.01, ω0 = 2: σ dips to 2ζω0²/(ω0² + 1) at ω0
    z, w0 = 0.01, 2.0
    num, den = [1.0, 2 * z * w0, w0**2], [1.0, 2.0, 1.0]
    A, B, C, D = scipy.signal.tf2ss(num, den)
    R = FaultModel(A=A, C=C, Bf=B, Df=D, faults=["f"])
    h = hminus_index(R)
    w = np.linspace(1.9, 2.1, 200001)
    grid = np.abs(scipy.signal.freqresp((num, den), w)[1]).min()
    assert h.value <= grid * (1 + 1e-9) and h.value == pytest.approx(grid, rel=1e-3)
    assert h.freq == pytest.approx(w0, rel=1e-3)
    # square MIMO, discrete: the grid is an upper bound, the search within 1e-3 of it
    Rd = _random_stable(3, 0.1, p=3, mf=2)
    om = _grid(0.1)
    s = np.linalg.svd(_resp(Rd, om, "f"), compute_uv=False)[:, 1].min()
    hd = hminus_index(Rd).value
    assert hd <= s * (1 + 1e-9) and hd == pytest.approx(s, rel=1e-3)
    assert hminus_index(FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0, 1.0]], faults=["a", "b"])).value == 0.0


# ---------------------------------------------------------------------- specs, banks, hidden modes


def _bank():
    # two filters stacked: r1 sees f1 (and noise), r2 sees f2 and a little f1
    return FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bf=[[1.0, 0.0], [0.1, 2.0]], Bw=[[0.5], [0.2]],
                      faults=["f1", "f2"], noise=["w"], outputs=["r1", "r2"])


def test_spec_selects_detected_and_nuisance_faults():
    R = _bank()
    # one filter with SFDI vector [1, 0]: β = ‖R_f1‖∞ = ‖[1/(s+1); 0.1/(s+2)]‖∞, γ = ‖[R_f2 R_w]‖∞
    g = fdif2ngap(R, ["f1"])
    assert g.beta == pytest.approx(np.hypot(1.0, 0.05), rel=1e-8)
    H = _resp(R.submodel(inputs=["f2", "w"]), _grid(None), "f")  # the f2 column
    Hw = _resp(R, _grid(None), "w")
    both = np.concatenate([H, Hw], axis=2)
    assert g.gamma == pytest.approx(np.linalg.norm(both, 2, axis=(1, 2)).max(), rel=1e-4)
    assert fdimmperf(R, ["f1"]) == pytest.approx(g.gamma, rel=1e-10)
    # rows × faults spec: one number per residual
    S = [[True, False], [False, True]]
    rows = fdif2ngap(R, S)
    assert rows.names == ("r1", "r2")
    assert rows.beta.tolist() == pytest.approx([1.0, 1.0], rel=1e-8)
    assert rows.gamma.tolist() == pytest.approx([0.5, np.hypot(0.05, 0.1)], rel=1e-8)
    # element-wise fdimmperf: ‖[(¬S) .* R_f, R_w]‖∞ = ‖[[0, 0, .5/(s+1)], [.1/(s+2), 0, .2/(s+2)]]‖∞ (at ω = 0)
    M = np.array([[0.0, 0.0, 0.5], [0.05, 0.0, 0.1]])
    assert fdimmperf(R, S) == pytest.approx(np.linalg.norm(M, 2), rel=1e-8)


def test_bank_by_groups_equals_bank_by_list_and_mapping():
    R = _bank()
    S = np.array([[True, False], [False, True]])
    by_groups = fdif2ngap(R, S, groups=[["r1"], ["r2"]])
    by_list = fdif2ngap([R.submodel(outputs=["r1"]), R.submodel(outputs=["r2"])], S)
    by_map = fdif2ngap({"a": R.submodel(outputs=["r1"]), "b": R.submodel(outputs=["r2"])}, S)
    assert by_groups.ratio.tolist() == pytest.approx(by_list.ratio.tolist(), rel=1e-12)
    assert by_map.names == ("a", "b") and by_groups.names == ("filter0", "filter1")
    c = fdiscond(R, groups={"one": [0], "two": [1]})  # default spec: all faults
    assert c.ratio.tolist() == pytest.approx([0.0, 0.05], rel=1e-8, abs=1e-12)  # r1 misses f2: β = 0
    assert fdimmperf(R, groups=[[0], [1]]).tolist() == pytest.approx([0.5, 0.1], rel=1e-8)
    assert fdisspec(R, groups=[[0], [1]]).matrix.tolist() == [[True, False], [True, True]]


def test_unstable_plant_mode_hidden_by_the_filter():
    # x' = x + u + f, y = x + w; observer residual r = y − ẑ with L = 3: error pole −2, plant pole +1 unobservable
    m = FaultModel(A=[[1.0]], C=[[1.0]], Bu=[[1.0]], Bf=[[1.0]], Dw=[[1.0]], controls=["u"], faults=["f"],
                   noise=["w"])
    gen = ResidualGenerator(A=[[-2.0]], B=[[1.0, 3.0]], C=[[-1.0]], D=[[0.0, 1.0]], controls=("u",),
                            outputs=("y0",), residuals=("r",))
    R = gen.internal_form(m)
    assert max(np.linalg.eigvals(R.A).real) == pytest.approx(1.0)
    g = fdif2ngap(R)  # R_f = 1/(s+2), R_w = s/(s+2)·(…): r = e + w with e' = −2e + f − 3w
    assert g.beta == pytest.approx(0.5, rel=1e-8)
    assert g.gamma == pytest.approx(1.0, rel=1e-8)  # (s − 1)/(s + 2) is all-pass-like at ∞: |·| ≤ 1
    assert fdisspec(R, 0.0).matrix.tolist() == [[True]]
    bad = FaultModel(A=[[0.5]], C=[[1.0]], Bf=[[1.0]], Bw=[[1.0]], faults=["f"], noise=["w"])
    with pytest.raises(ModelError, match="unstable"):
        fdif2ngap(bad)
    assert fdimmperf(bad) == np.inf


def test_errors_are_clear():
    R = _bank()
    with pytest.raises(ParameterError, match="norm"):
        fdimmperf(R, norm=1)
    with pytest.raises(ParameterError, match="one column per fault"):
        fdif2ngap(R, [True, False, True])
    with pytest.raises(ParameterError, match="does not have"):
        fdif2ngap(R, ["f9"])
    with pytest.raises(ParameterError, match="2 rows"):
        fdif2ngap(R, [[True, False]] * 2, groups=[["r1"], ["r2"], ["r1", "r2"]])
    with pytest.raises(ParameterError, match="ResidualGenerator"):
        fdif2ngap(ResidualGenerator(A=[[-1.0]], B=[[1.0]], C=[[1.0]], D=[[0.0]], controls=(), outputs=("y",),
                                    residuals=("r",)))
    with pytest.raises(ModelError, match="share their inputs"):
        fdif2ngap([R, R.submodel(inputs=["f1", "w"])])
    with pytest.raises(ParameterError, match="neither faults"):
        fdif2ngap(FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[1.0]]))
    with pytest.raises(ParameterError, match="no fault"):
        fdiscond(R, [False, False])
    with pytest.raises(ParameterError, match="not both"):
        fdimmperf(R, ["f1"], ref=R)
    with pytest.raises(ModelError, match="pole"):
        fdisspec(FaultModel(A=[[0.0]], C=[[1.0]], Bf=[[1.0]], faults=["f"]), 0.0)
    with pytest.raises(ParameterError, match="discrete"):
        fdhinfminus(_random_stable(1, 0.1), [np.inf])
