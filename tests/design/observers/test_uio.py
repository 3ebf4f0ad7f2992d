"""Unknown-input observer residual generators (fdikit.design.observers.uio).

Oracles: the internal form ``R`` of each generator (plant and filter in series) evaluated on a
frequency grid, simulated traces (discrete models: fdikit.simulate + generator.run; continuous:
the internal form simulated exactly), the UIO equations of Chen & Patton (1999, §3.2) written out
independently, invariant zeros from fdikit.linalg, and a plain observer as the non-decoupled
control case.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from fdikit import DesignError, FaultModel, ModelError, ParameterError
from fdikit.design.observers.full_order import observer_generator
from fdikit.design.observers.uio import uio, uio_bank, unknown_input_matrix
from fdikit.fault_maps import sensor_fault_map
from fdikit.faults import Bias, Drift, FaultScenario
from fdikit.linalg import invariant_zeros, rank
from fdikit.plants import path_vehicle_14
from fdikit.residuals import stack_generators
from fdikit.simulate import simulate

W_CONT = np.logspace(-2, 3, 150)


def _grid(m: FaultModel) -> np.ndarray:
    """1e-2 … 1e3 rad/s, or the upper half of the unit circle (including z = 1 and z = −1)."""
    return np.linspace(0.0, np.pi, 150) / m.dt if m.is_discrete else W_CONT


def _stable_a(rng: np.random.Generator, n: int, margin: float = 0.5) -> np.ndarray:
    M = rng.standard_normal((n, n))
    return M - (np.max(scipy.linalg.eigvals(M).real) + margin) * np.eye(n)


def _random_model(seed: int, dt: float | None = None, n: int = 8, p: int = 7) -> FaultModel:
    """Two actuator faults (with feedthrough Du: two UI directions each), one sensor fault, one disturbance."""
    rng = np.random.default_rng(seed)
    m = FaultModel(A=_stable_a(rng, n), C=rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 2)),
                   Du=0.3 * rng.standard_normal((p, 2)), Bd=rng.standard_normal((n, 1)), disturbances=["gust"])
    m = m.with_actuator_faults(["u0", "u1"]).with_sensor_faults([m.outputs[-1]])
    return m if dt is None else m.discretize(dt)


def _gains(R: np.ndarray) -> np.ndarray:
    """Per-frequency 2-norm of each input column: (len(omega), k)."""
    return np.linalg.norm(R, axis=1)


def _zero_model(z0: float, seed: int = 3, dt: float | None = None) -> FaultModel:
    """Nuisance 'nu' with an invariant zero of (A, E, C) at z0: an autonomous mode x4' = z0 x4 feeding along E."""
    rng = np.random.default_rng(seed)
    n, p = 5, 3
    A, C = _stable_a(rng, n), rng.standard_normal((p, n))
    e = rng.standard_normal(n)
    e[-1] = 0.0
    A[-1, :] = 0.0
    A[:, -1] = np.r_[1.3 * e[:-1], z0]
    C[:, -1] = 0.0
    return FaultModel(A=A, C=C, Bu=rng.standard_normal((n, 1)), controls=["u"],
                      Bf=np.column_stack([e, rng.standard_normal(n)]), faults=["nu", "tg"], dt=dt)


# ---------------------------------------------------------------------------------------------- decoupling


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("dt", [None, 0.05])
def test_nuisance_disturbance_and_controls_do_not_reach_the_residual(seed, dt):
    m = _random_model(seed, dt)
    d = uio(m, "u1_actuator", nuisance="others")
    assert d.decoupled == ("u0_actuator", "y6_sensor", "gust")
    G = d.generator.internal_form(m)
    w = _grid(m)
    Rf, Rd, Ru = _gains(G.freqresp(w, "f")), _gains(G.freqresp(w, "d")), _gains(G.freqresp(w, "u"))
    target = Rf[:, m.index("f", "u1_actuator")[0]]
    leaks = np.column_stack([Rf[:, m.index("f", ["u0_actuator", "y6_sensor"])], Rd, Ru])
    assert leaks.shape == (w.size, 5)
    assert np.all(leaks <= 1e-9 * target[:, None])
    # the target is seen at every frequency, at a size comparable to its effect on the plant outputs
    plant = _gains(m.freqresp(w, "f"))[:, m.index("f", "u1_actuator")[0]]
    assert np.all(target > 1e-3 * plant)
    # the report's numbers say the same
    assert max(d.decoupling.values()) < 1e-11 and set(d.decoupling) == {"u0_actuator", "y6_sensor", "gust", "u0", "u1"}
    assert d.target_gain > 0 and d.fixed_modes.size == 0 and d.notes == ()
    # control case: a plain (non-decoupling) observer leaks every nuisance at O(1) on this metric
    plain = observer_generator(m, np.zeros((m.n, m.p))).internal_form(m)
    Pf = _gains(plain.freqresp(w, "f"))
    assert np.max(Pf[:, 0] / Pf[:, 1]) > 1e-2


@pytest.mark.parametrize("dt", [None, 0.05])
def test_uio_equations_and_generator_matrices(dt):
    m = _random_model(4, dt)
    d = uio(m, "u1_actuator", nuisance="others")
    A, C, Bu, Du = m.A, m.C, m.Bu, m.Du
    E = d.E
    assert E.shape == (8, 5)  # u0 actuator (Bf and Df nonzero): 2 columns; y6 sensor: 2; gust: 1
    np.testing.assert_allclose(d.H, E @ np.linalg.pinv(C @ E), atol=1e-10)  # H = E (CE)^+ on the raw E
    np.testing.assert_allclose(d.T, np.eye(8) - d.H @ C, atol=1e-12)
    assert np.linalg.norm(d.T @ E) < 1e-12 * np.linalg.norm(E)
    np.testing.assert_allclose(d.N, d.T @ A - d.K1 @ C, atol=1e-12)
    np.testing.assert_allclose(d.K, d.K1 + d.N @ d.H, atol=1e-12)
    # error dynamics e' = N e need T A − N T − K C = 0
    assert np.linalg.norm(d.T @ A - d.N @ d.T - d.K @ C) < 1e-12 * np.linalg.norm(A)
    stable = np.abs(d.poles) < 1 if dt else d.poles.real < 0
    assert stable.all()
    np.testing.assert_allclose(np.sort_complex(d.poles), np.sort_complex(np.linalg.eigvals(d.N)), atol=1e-10)
    # residual basis: orthonormal complement of Im CE, p − rank CE = 7 − 5 = 2 residuals
    U = d.residual_basis
    assert U.shape == (7, 2)
    np.testing.assert_allclose(U.T @ U, np.eye(2), atol=1e-12)
    assert np.linalg.norm(U.T @ C @ E) < 1e-12 * np.linalg.norm(C @ E)
    g = d.generator
    assert g.residuals == ("u1_actuator[0]", "u1_actuator[1]") and g.isolates == ("u1_actuator",) * 2
    assert g.controls == m.controls and g.outputs == m.outputs and g.dt == m.dt
    np.testing.assert_allclose(g.A, d.N, atol=0)
    np.testing.assert_allclose(g.B, np.hstack([d.T @ Bu - d.K @ Du, d.K]), atol=1e-12)
    np.testing.assert_allclose(g.C, -U.T @ C, atol=1e-12)
    np.testing.assert_allclose(g.D, U.T @ np.hstack([-Du, np.eye(7)]), atol=1e-12)


def test_unknown_input_directions():
    m = _random_model(5)
    E, where = unknown_input_matrix(m, ["y6_sensor", "u0_actuator"])
    assert where == {"y6_sensor": slice(0, 2), "u0_actuator": slice(2, 4), "gust": slice(4, 5)}
    # a pure sensor fault is fault_maps.sensor_fault_map's [F1, A F1]
    np.testing.assert_allclose(E[:, :2], sensor_fault_map(m, "y6"), atol=1e-13)
    # Bf and Df both nonzero: [F1, A F1 − b] with C F1 = Df column
    b, dcol = m.Bf[:, 0], m.Df[:, 0]
    F1 = E[:, 2]
    np.testing.assert_allclose(m.C @ F1, dcol, atol=1e-12)
    np.testing.assert_allclose(E[:, 3], m.A @ F1 - b, atol=1e-12)
    np.testing.assert_array_equal(E[:, 4], m.Bd[:, 0])
    E2, where2 = unknown_input_matrix(m, [], disturbances=False)
    assert E2.shape == (8, 0) and where2 == {}


def test_user_poles_are_placed():
    m = _random_model(6)
    poles = [-2.0, -3.0, -4.0, -5.0 + 1.0j, -5.0 - 1.0j, -6.0, -7.0, -8.0]
    d = uio(m, "u1_actuator", nuisance="others", poles=poles)
    np.testing.assert_allclose(np.sort_complex(d.poles), np.sort_complex(np.array(poles)), atol=1e-8)
    assert max(d.decoupling.values()) < 1e-10
    md = m.discretize(0.1)
    dd = uio(md, "u1_actuator", nuisance="others", poles=np.linspace(0.1, 0.8, 8))
    np.testing.assert_allclose(np.sort(dd.poles.real), np.linspace(0.1, 0.8, 8), atol=1e-8)
    assert np.abs(dd.poles.imag).max() < 1e-8
    with pytest.raises(DesignError, match=r"need 8 UIO poles .* got 3"):
        uio(m, "u1_actuator", nuisance="others", poles=[-1.0, -2.0, -3.0])
    with pytest.raises(DesignError, match=r"not stable"):
        uio(m, "u1_actuator", nuisance="others", poles=[0.5, -2.0, -3.0, -4.0, -5.0, -6.0, -7.0, -8.0])
    with pytest.raises(DesignError, match=r"not stable"):
        uio(md, "u1_actuator", nuisance="others", poles=[1.2, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7])


# ---------------------------------------------------------------------------------------------- simulation


def test_discrete_residual_decays_and_ignores_nuisance_faults():
    m = _random_model(7, dt=0.05)
    d = uio(m, "u1_actuator", nuisance="others")
    rng = np.random.default_rng(11)
    N = 400
    t = np.arange(N) * m.dt
    u = rng.standard_normal((N, 2))
    gust = np.sin(1.7 * t)[:, None]
    x0 = rng.standard_normal(m.n)
    nuisance = FaultScenario([Bias("u0", 0.8, onset=1.0), Drift("y6", 0.5, onset=2.0)])
    trace = simulate(m, nuisance, t=t, u=u, d=gust, x0=x0)
    r = d.generator.run(trace).r  # filter starts at z = 0: the wrong initial state
    r0 = np.linalg.norm(r[0])
    assert r0 > 1e-2
    tail = np.linalg.norm(r[-40:], axis=1).max()
    assert tail < 1e-8 * r0
    # the online stepper gives the same residuals
    np.testing.assert_allclose(d.generator.online().run(trace).r, r, atol=1e-10 * r0)
    # a target fault (same u, d, x0) moves the residual by far more than the decayed error
    hit = simulate(m, FaultScenario([Bias("u1", 0.5, onset=15.0)]), t=t, u=u, d=gust, x0=x0)
    rf = d.generator.run(hit).r
    assert np.linalg.norm(rf[-40:], axis=1).min() > 1e-3
    assert np.linalg.norm(rf[t < 15.0] - r[t < 15.0]) < 1e-12


def test_continuous_residual_decays_from_a_wrong_initial_state():
    m = _random_model(8)
    d = uio(m, "u1_actuator", nuisance="others")
    G = d.generator.internal_form(m)  # plant + filter, simulated exactly (ZOH inputs)
    rng = np.random.default_rng(12)
    dt, T = 0.02, 60.0
    slow = np.max(d.poles.real)
    assert slow < -0.4  # 60 s is > 24 time constants of the slowest UIO pole
    t = np.arange(int(T / dt) + 1) * dt
    u = rng.standard_normal((t.size, 2))
    x0 = np.r_[rng.standard_normal(m.n), np.zeros(m.n)]  # z(0) = 0 ≠ T x(0)
    r = simulate(G, t=t, u=u, d=np.cos(0.9 * t)[:, None], x0=x0).y
    r0 = np.linalg.norm(r[0])
    # r = U⊥ᵀ C e with e(0) = T x(0) − z(0), and U⊥ᵀ C T = U⊥ᵀ C
    np.testing.assert_allclose(r[0], d.residual_basis.T @ m.C @ x0[: m.n], atol=1e-12 * np.linalg.norm(x0))
    assert r0 > 1e-2
    assert np.linalg.norm(r[-100:], axis=1).max() < 1e-8 * r0


# ---------------------------------------------------------------------------------------------- small and PATH


def test_sensor_fault_nuisance_with_actuator_target():
    rng = np.random.default_rng(21)
    m = FaultModel(A=_stable_a(rng, 4), C=rng.standard_normal((3, 4)), Bu=rng.standard_normal((4, 1)),
                   outputs=["a", "b", "c"], controls=["thr"], dt=None)
    m = m.with_sensor_faults(["b"]).with_actuator_faults(["thr"])
    d = uio(m, "thr_actuator", nuisance="others")
    assert d.decoupled == ("b_sensor",) and d.generator.residuals == ("thr_actuator[0]",)
    np.testing.assert_allclose(d.E, sensor_fault_map(m, "b"), atol=1e-13)
    w = W_CONT
    Rf = _gains(d.generator.internal_form(m).freqresp(w, "f"))
    assert np.all(Rf[:, 0] <= 1e-9 * Rf[:, 1]) and np.all(Rf[:, 1] > 1e-4)
    # in time (discretised plant): a sensor bias leaves r at zero, an actuator bias does not
    md = m.discretize(0.05)
    dd = uio(md, "thr_actuator", nuisance="others")
    t = np.arange(300) * 0.05
    u = np.sin(t)[:, None]
    quiet = dd.generator.run(simulate(md, FaultScenario([Bias("b", 2.0, onset=3.0)]), t=t, u=u)).r
    loud = dd.generator.run(simulate(md, FaultScenario([Bias("thr", 2.0, onset=3.0)]), t=t, u=u)).r
    assert np.abs(quiet).max() < 1e-10 * np.abs(loud).max()
    assert np.abs(loud[t > 5]).min() > 1e-3


def test_path_vehicle_14_actuator_faults():
    m = path_vehicle_14()
    m = m.with_actuator_faults(list(m.controls))
    # throttle and brake act through actuator-lag states that C does not measure (C B = 0):
    # every UIO of the three-fault bank has a nuisance direction the outputs cannot see
    with pytest.raises(DesignError, match=r"rank\(C E\) = 1 < rank\(E\) = 2.*\['brake_actuator'\]"):
        uio(m, "throttle_actuator", nuisance="others")
    both = r"rank\(C E\) = 0 < rank\(E\) = 2.*\['throttle_actuator', 'brake_actuator'\]"
    with pytest.raises(DesignError, match=both):
        uio(m, "steering_actuator", nuisance="others")
    with pytest.raises(DesignError, match=r"target 'throttle_actuator': rank\(C E\) = 1 < rank\(E\) = 2.*\['brake_"):
        uio_bank(m)
    with pytest.raises(DesignError, match=r"rank\(C E\) = 1 < rank\(E\) = 2.*\['throttle_actuator'\]"):
        uio(m, "brake_actuator", nuisance="others")
    # the steering actuator alone is visible (rank C B = 1) and (A, B_steer, C) has no invariant zeros
    assert invariant_zeros(m.A, m.C, m.Bu[:, [2]])[0].size == 0
    w = np.logspace(-2, 3, 100)
    for target in ("throttle_actuator", "brake_actuator"):
        d = uio(m, target, nuisance=["steering_actuator"])
        assert len(d.generator.residuals) == 11 and d.fixed_modes.size == 0
        R = d.generator.internal_form(m).freqresp(w, "f")
        jt, js = m.index("f", [target, "steering_actuator"])
        leak, seen = _gains(R)[:, js], _gains(R)[:, jt]
        # brake torque moves the outputs ~1e3 times less than steering: relative to the target the leak is
        # roundoff amplified by that ratio; relative to what steering does to the outputs it is roundoff
        assert np.max(leak) < 1e-8 * np.max(seen)
        assert np.max(leak / _gains(m.freqresp(w, "f"))[:, js]) < 1e-12
        assert np.min(seen) > 0
    with pytest.raises(DesignError, match=r"rank\(C E\) = 0 < rank\(E\) = 1.*\['brake_actuator'\]"):
        uio(m, "throttle_actuator", nuisance=["brake_actuator"])


# ---------------------------------------------------------------------------------------------- infeasible


def test_invisible_nuisance_is_a_rank_error():
    rng = np.random.default_rng(31)
    C = rng.standard_normal((3, 5))
    hidden = scipy.linalg.null_space(C)[:, 0]
    m = FaultModel(A=_stable_a(rng, 5), C=C, Bf=np.column_stack([hidden, rng.standard_normal(5)]),
                   faults=["ghost", "real"])
    with pytest.raises(DesignError, match=r"rank\(C E\) = 0 < rank\(E\) = 1.*\['ghost'\]"):
        uio(m, "real", nuisance="others")
    # jointly invisible: two directions whose output images are parallel
    v = rng.standard_normal(5)
    m2 = FaultModel(A=m.A, C=C, Bf=np.column_stack([v, v + hidden, rng.standard_normal(5)]), faults=["a", "b", "t"])
    with pytest.raises(DesignError, match=r"rank\(C E\) = 1 < rank\(E\) = 2.*jointly.*\['a', 'b'\]"):
        uio(m2, "t", nuisance="others")


def test_stable_invariant_zero_is_kept_and_the_rest_placed():
    m = _zero_model(-0.7)
    np.testing.assert_allclose(invariant_zeros(m.A, m.C, m.Bf[:, :1])[0], [-0.7], atol=1e-10)
    d = uio(m, "tg", nuisance="others")
    np.testing.assert_allclose(d.fixed_modes, [-0.7], atol=1e-10)
    assert "4 of 5 poles assignable" in d.notes[0] and "-0.7" in d.notes[0]
    assert max(d.decoupling.values()) < 1e-11
    with pytest.raises(DesignError, match=r"need 4 UIO poles \(n = 5 minus 1 fixed modes \[-0\.7\]\), got 5"):
        uio(m, "tg", nuisance="others", poles=[-1.0, -2.0, -3.0, -4.0, -5.0])
    d2 = uio(m, "tg", nuisance="others", poles=[-2.0, -3.0, -4.0, -5.0])
    np.testing.assert_allclose(np.sort(d2.poles.real), [-5.0, -4.0, -3.0, -2.0, -0.7], atol=1e-8)
    # the fixed mode is the slowest pole: the error decays like exp(-0.7 t), and still decouples 'nu'
    Rf = _gains(d2.generator.internal_form(m).freqresp(W_CONT, "f"))
    assert np.all(Rf[:, 0] <= 1e-9 * Rf[:, 1])


def test_unstable_invariant_zero_is_named():
    m = _zero_model(0.5)
    with pytest.raises(DesignError, match=r"not detectable: its unobservable modes \[0\.5\].*invariant zeros"):
        uio(m, "tg", nuisance="others")
    with pytest.raises(DesignError, match=r"modes \[-1\.2\].*\|z\| < 1"):
        uio(_zero_model(-1.2, dt=0.1), "tg", nuisance="others")
    # the same structure with |z| < 1 is a fixed mode of a working discrete UIO
    d = uio(_zero_model(-0.6, dt=0.1), "tg", nuisance="others")
    np.testing.assert_allclose(d.fixed_modes, [-0.6], atol=1e-10)
    assert np.all(np.abs(d.poles) < 1)


def test_bad_names_and_other_infeasible_specifications():
    m = _random_model(9)
    with pytest.raises(ModelError, match=r"no faults input named 'nope'"):
        uio(m, "nope", nuisance="others")
    with pytest.raises(ModelError, match=r"no faults input named 'nope'"):
        uio(m, "u1_actuator", nuisance=["nope"])
    with pytest.raises(ParameterError, match=r"also listed as a nuisance"):
        uio(m, "u1_actuator", nuisance=["u1_actuator"])
    # a target along a nuisance direction cannot be seen by any decoupled residual
    twin = m.add_faults(["twin"], m.Bf[:, [1]], m.Df[:, [1]])
    with pytest.raises(DesignError, match=r"target 'twin' is in the unknown-input subspace"):
        uio(twin, "twin", nuisance=["u1_actuator"])
    # decoupling as many directions as outputs leaves no residual
    small = _random_model(9, n=8, p=5)
    with pytest.raises(DesignError, match=r"uses rank\(C E\) = 5 of the 5 outputs; no residual is left"):
        uio(small, "u1_actuator", nuisance="others")
    # disturbances on the outputs are refused
    with pytest.raises(DesignError, match=r"disturbances \['gust'\] reach the outputs directly"):
        uio(m.replace(Dd=np.ones((7, 1))), "u1_actuator", nuisance="others")
    # a sensor direction outside Im C (C rank deficient) cannot be turned into a state fault
    rng = np.random.default_rng(2)
    Cd = np.vstack([rng.standard_normal((2, 4)), np.zeros((1, 4))])
    md = FaultModel(A=_stable_a(rng, 4), C=Cd, Bu=rng.standard_normal((4, 1))).with_sensor_faults(["y2"])
    md = md.with_actuator_faults(["u0"])
    with pytest.raises(DesignError, match=r"'y2_sensor' reaches the outputs along a direction outside the range of C"):
        uio(md, "u0_actuator", nuisance="others")


# ---------------------------------------------------------------------------------------------- bank and stacking


def _three_fault_model(dt: float | None = None) -> FaultModel:
    rng = np.random.default_rng(41)
    m = FaultModel(A=_stable_a(rng, 6), C=rng.standard_normal((4, 6)), Bu=rng.standard_normal((6, 3)),
                   controls=["a", "b", "c"]).with_actuator_faults(["a", "b", "c"])
    return m if dt is None else m.discretize(dt)


@pytest.mark.parametrize("dt", [None, 0.05])
def test_bank_isolates_each_fault(dt):
    m = _three_fault_model(dt)
    bank = uio_bank(m)
    assert [d.target for d in bank] == list(m.faults)
    g = stack_generators([d.generator for d in bank])
    assert g.n == 18 and len(g.residuals) == 6  # 3 x (p − rank CE) = 3 x (4 − 2)
    assert g.isolates == tuple(f for f in m.faults for _ in range(2))
    R = g.internal_form(m).freqresp(_grid(m), "f")  # (omega, 6 residuals, 3 faults)
    for i, fault in enumerate(m.faults):
        rows = [k for k, iso in enumerate(g.isolates) if iso == fault]
        block = np.linalg.norm(R[:, rows, :], axis=1)  # (omega, 3)
        own = block[:, i]
        others = np.delete(block, i, axis=1)
        assert np.all(others <= 1e-9 * own[:, None]), fault
        assert np.all(own > 1e-3 * np.linalg.norm(m.freqresp(_grid(m), "f")[:, :, i], axis=1))
    # the structure matrix: residual block i is sensitive to fault j iff i == j
    sens = np.array([[np.max(np.linalg.norm(R[:, 2 * i: 2 * i + 2, j], axis=1)) for j in range(3)] for i in range(3)])
    np.testing.assert_array_equal(sens > 1e-9 * sens.max(), np.eye(3, dtype=bool))


def test_stacked_generator_runs_like_its_parts():
    m = _three_fault_model(0.05)
    bank = uio_bank(m)
    g = stack_generators([d.generator for d in bank])
    t = np.arange(200) * 0.05
    trace = simulate(m, FaultScenario([Bias("b", 1.0, onset=4.0)]), t=t, u=np.column_stack([np.sin(t)] * 3))
    np.testing.assert_allclose(g.run(trace).r, np.hstack([d.generator.run(trace).r for d in bank]), atol=1e-12)
    r = g.run(trace).r
    assert np.abs(r[:, [0, 1, 4, 5]]).max() < 1e-10 * np.abs(r[:, [2, 3]]).max()
    assert np.abs(r[t > 6][:, [2, 3]]).max() > 1e-2


def test_bank_subset_and_extra_nuisance():
    m = _random_model(10)
    bank = uio_bank(m, ["u0_actuator", "u1_actuator"], nuisance=["y6_sensor"])
    assert [d.decoupled for d in bank] == [("u1_actuator", "y6_sensor", "gust"), ("u0_actuator", "y6_sensor", "gust")]
    with pytest.raises(ModelError):
        uio_bank(m, ["u0_actuator", "nope"])
    with pytest.raises(ModelError, match="at least one fault"):
        uio_bank(FaultModel(A=[[-1.0]], C=[[1.0]]))


def test_stack_generators_rejects_mismatches():
    m = _three_fault_model()
    a, b = (d.generator for d in uio_bank(m)[:2])
    with pytest.raises(ModelError, match="at least one"):
        stack_generators([])
    # filters reading the signals in another order are stacked on the union of the signals (residuals/bank.py)
    sub = m.submodel(outputs=list(m.outputs[::-1]))
    mixed = stack_generators([a, uio(sub, "b_actuator", nuisance="others").generator])
    assert mixed.outputs == a.outputs and len(mixed.residuals) == len(a.residuals) + len(b.residuals)
    with pytest.raises(ModelError, match="dt="):
        stack_generators([a, b.discretize(0.1)])
    with pytest.raises(ModelError, match=r"residual names \['a_actuator\[0\]', 'a_actuator\[1\]'\]"):
        stack_generators([a, a])
    with pytest.raises(ModelError, match="not a ResidualGenerator"):
        stack_generators([a, uio_bank(m)[1]])
    single = stack_generators([a])
    np.testing.assert_array_equal(single.A, a.A)
    assert single.residuals == a.residuals and rank(single.C) == 2


def test_f16xl_bank_matches_the_seed_structure():
    """Murray (2012) Example 1: C = I, faults θ sensor, elevon δ, wind gust wg."""
    A = np.array([[-0.0674, 0.0430, -0.8886, -0.5587], [0.0205, -1.4666, 16.5800, -0.0299],
                  [0.1377, -1.6788, -0.6819, 0.0], [0.0, 0.0, 1.0, 0.0]])
    m = FaultModel(A=A, C=np.eye(4), Bu=[[-0.1672], [-1.5179], [-9.7842], [0.0]], controls=["elevon"],
                   states=["u", "w", "q", "theta"], outputs=["u", "w", "q", "theta"])
    m = m.with_sensor_faults(["theta"]).with_actuator_faults(["elevon"]).add_faults(["gust"], A[:, [1]])
    bank = uio_bank(m)
    # sensor-fault directions span F_θ = [e4, −A e4] (C = I, so F¹ = e4)
    F_theta = np.array([[0, 0.5587], [0, 0.0299], [0, 0], [1.0, 0]])
    assert rank(np.hstack([bank[1].E[:, :2], F_theta])) == 2
    # residual counts = ranks of the projectors (3.10): Ĥ_θ rank 2, Ĥ_δ and Ĥ_wg rank 1
    assert [len(d.generator.residuals) for d in bank] == [2, 1, 1]
    g = stack_generators([d.generator for d in bank])
    R = g.internal_form(m).freqresp(W_CONT, "f")
    rows = {0: [0, 1], 1: [2], 2: [3]}
    for i in range(3):
        block = np.linalg.norm(R[:, rows[i], :], axis=1)
        # exact isolation, where the seed's game-theoretic bank reaches a ratio of 450-1200
        assert np.all(np.delete(block, i, axis=1) <= 1e-10 * block[:, [i]])
