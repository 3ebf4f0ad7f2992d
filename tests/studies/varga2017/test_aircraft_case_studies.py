"""Varga (2017), Chapter 8, on the reference's data: the ``@test`` lines of FaultDetectionTools.jl's
``Examples/CS1_1.jl``, ``CS1_2.jl``, ``CS2_1.jl``, ``CS2_2.jl``."""

import numpy as np
import pytest

from fdikit.descriptor.jld2 import read_jld2
from fdikit.design.nullspace import efdisyn, fdigenspec
from fdikit.errors import ParameterError
from fdikit.studies.varga2017.aircraft import (
    CS1_SFDI,
    NOMINAL,
    actuator_case,
    closed_loop_degree,
    closed_loop_norms,
    data_file,
    interpolated_gain_errors,
    positive_feedback,
    remark81_gains,
    sensor_case,
    static_gain_error,
)


@pytest.fixture(scope="module")
def cs1():
    return actuator_case()


@pytest.fixture(scope="module")
def cs2():
    return sensor_case()


def test_jld2_data_decoded(cs1):
    data = read_jld2(data_file("cs1"))
    assert set(data) == {"SYSACM", "K", "ACT"}
    assert data["ACT"].n == 22 and data["K"].shape == (22, 10)
    assert all(m.D.shape == (10, 25) and np.array_equal(m.E, np.eye(10)) for m in data["SYSACM"])
    # the Julia matrices are column-major: the transpose is read back, so A is the aircraft's, not its transpose
    ac = data["SYSACM"][NOMINAL]
    assert np.allclose(np.linalg.eigvals(ac.A).real.max(), 0.0186, atol=1e-4)


def test_jld2_bad_input(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        read_jld2(tmp_path / "none.jld2")
    (tmp_path / "x.jld2").write_text("not hdf5")
    with pytest.raises(ParameterError, match="not a JLD2"):
        read_jld2(tmp_path / "x.jld2")
    with pytest.raises(ParameterError, match="holds"):
        read_jld2(data_file("cs2"), ["nope"])


def test_cs1_closed_loop_stable(cs1):
    # CS1_1: @test sdeg_cloop < 0
    assert closed_loop_degree(cs1) < 0


def test_cs1_achievable_specifications(cs1):
    nom = cs1.models[NOMINAL]
    S = fdigenspec(nom, fdtol=1e-5)
    S_strong = fdigenspec(nom, fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, sdeg=-0.05)
    # CS1_1: @test issubset(binmat2dec(S_strong), binmat2dec(S)); every row of SFDI is achievable
    assert {tuple(r) for r in S_strong} <= {tuple(r) for r in S}
    assert {tuple(r) for r in CS1_SFDI} <= {tuple(r) for r in S_strong}


def test_cs1_bank_structure_and_nominal_decoupling(cs1):
    nom = cs1.models[NOMINAL]
    bank = efdisyn(nom, CS1_SFDI, fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, rdim=1, sdeg=-5.0)
    assert np.array_equal(bank.specification, CS1_SFDI)
    for f, row in zip(bank.filters, CS1_SFDI):
        assert np.array_equal(f.structure[0, : int(row.sum())], np.ones(int(row.sum()), bool))
    T = closed_loop_norms(cs1, bank.generator)
    assert T.shape == (11, 3) and np.isfinite(T).all()
    # off-nominal models: the nominal bank is not robust (Table 8.2: large norms)
    off = np.delete(T, NOMINAL, axis=0)
    assert off.min() > 1.0
    # nominal: decoupled up to rounding.  The filter coefficients come out to about 1e-8 relative (they differ in
    # the eighth digit between BLAS kernels) and reach 5e4, so the nominal residue is rounding-level, measured
    # 1e-10 … 5e-10 of the smallest off-nominal norm of each column; 1e-8 bounds it.  The reference's absolute
    # 1e-6 is the xfail below (R_d alone meets it: 1.8e-7 … 3.9e-7 measured, too close to assert)
    assert (T[NOMINAL] < 1e-8 * off.min(axis=0)).all()


@pytest.mark.xfail(strict=True, reason="the nominal closed-loop ‖R_u‖∞ and ‖R_f − R̃_f‖∞ of a channel that cancels "
                   "exactly come out 1e-5 … 6e-5, above the reference's 1e-6: the floor of evaluating the cancellation "
                   "(terms of size 1e6, the off-nominal norms), not of the filters, which decouple to 2e-14 of "
                   "|Q| |G_e| (test below); the reference reduces the channel first (glinfnorm: gir with rtol = n·ε)")
def test_cs1_nominal_norms_reference_bound(cs1):
    nom = cs1.models[NOMINAL]
    bank = efdisyn(nom, CS1_SFDI, fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, rdim=1, sdeg=-5.0)
    assert closed_loop_norms(cs1, bank.generator)[NOMINAL].max() < 1e-6


def test_cs1_positions_every_structure_achievable():
    case = actuator_case(positions=True)
    # CS1_2: @test size(S_strong,1) == 2^mf-1
    S = fdigenspec(case.models[NOMINAL], fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, sdeg=-0.01)
    assert S.shape == (2 ** 8 - 1, 8)


def test_positive_feedback_matches_dense_loop():
    rng = np.random.default_rng(3)
    A, B, C, D = rng.normal(size=(3, 3)), rng.normal(size=(3, 2)), rng.normal(size=(2, 3)), rng.normal(size=(2, 2))
    K = rng.normal(size=(1, 1)) * 0.3
    Ac, Bc, Cc, Dc = positive_feedback(A, B, C, D, K, [0], [1])
    s = 0.7j
    G = C @ np.linalg.solve(s * np.eye(3) - A, B) + D
    # u0 = v + K y1: y = G [u0; u1] ⇒ u0 = v + K (G[1,0] u0 + G[1,1] u1)
    den = 1 - K[0, 0] * G[1, 0]
    Gcl = G.copy()
    Gcl[:, 0] = G[:, 0] / den
    Gcl[:, 1] = G[:, 1] + G[:, 0] * K[0, 0] * G[1, 1] / den
    assert np.allclose(Cc @ np.linalg.solve(s * np.eye(3) - Ac, Bc) + Dc, Gcl, atol=1e-12)
    with pytest.raises(ParameterError, match="K must be"):
        positive_feedback(A, B, C, D, np.eye(2), [0], [1])


def test_cs2_constant_filters(cs2):
    # CS2_1: @test size(S_strong,1) == 2^mf-1 and all(order.(Q) .== 0)
    S = fdigenspec(cs2.models[NOMINAL], fdtol=1e-5, fdgaintol=1e-4, fdfreq=0, sdeg=-0.05)
    assert S.shape == (3, 2)
    banks = [efdisyn(m, np.eye(2), fdtol=1e-5, fdgaintol=1e-4, fdfreq=0, rdim=1, sdeg=-5.0) for m in cs2.models]
    assert all(o == 0 for b in banks for o in b.orders)


def test_cs2_table_8_4(cs2):
    gains = remark81_gains(cs2)
    # Nref: the per-model constant solutions decouple exactly (reference: norm(Nref, Inf) < 1e-7)
    assert static_gain_error(cs2, gains).max() < 1e-7
    # Nnom: the nominal gain on every model (reference: norm(Nnom, Inf) > 643)
    assert static_gain_error(cs2, gains[NOMINAL]).max() > 643
    # N0: the mean gain (reference: norm(N0, Inf) > 504)
    assert static_gain_error(cs2, gains.mean(axis=0)).max() > 504


def test_cs2_table_8_5(cs2):
    N = interpolated_gain_errors(cs2, 4)
    # CS2_2: @test all(maximum(Nintp, dims=1) .> [545 138 16 0.88 0.12])
    assert (N.max(axis=0) > [545.0, 138.0, 16.0, 0.88, 0.12]).all()
    # the error falls with the degree of the interpolation
    assert (np.diff(N.max(axis=0)) < 0).all()


def test_cs1_bank_decouples_to_rounding_on_the_open_loop(cs1):
    # Q(jω) [Gu Gd Gn; I 0 0] = 0 per filter, relative to |Q| |G_e|, within the rounding bound of the two solves
    # with (jωI − A) (plant) and (jωI − A_Q): 100 n ε (κ(jωI − A) + κ(jωI − A_Q)); measured 1e-17 … 2e-14
    nom = cs1.models[NOMINAL]
    bank = efdisyn(nom, CS1_SFDI, fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, rdim=1, sdeg=-5.0)
    mu, n = len(nom.controls), nom.A.shape[0]
    eps = np.finfo(float).eps
    for f in bank.filters:
        g = f.generator
        cols = list(range(mu + len(nom.disturbances))) + [mu + len(nom.disturbances) + nom.faults.index(x)
                                                          for x in f.nuisance]
        B, D = nom.B[:, cols], nom.D[:, cols]
        P = np.zeros((len(g.controls) + len(g.outputs), mu + len(nom.outputs)))   # gen inputs [u; y] ← [u; y]
        for i, c in enumerate(g.controls):
            P[i, nom.controls.index(c)] = 1.0
        for i, o in enumerate(g.outputs):
            P[len(g.controls) + i, mu + nom.outputs.index(o)] = 1.0
        for w in np.logspace(-2, 2, 9):
            s = 1j * w
            Ms, Mq = s * np.eye(n) - nom.A, s * np.eye(g.n) - g.A
            Ge = P @ np.vstack([np.eye(mu, len(cols)), nom.C @ np.linalg.solve(Ms, B) + D])
            Q = g.C @ np.linalg.solve(Mq, g.B) + g.D
            rel = np.linalg.norm(Q @ Ge, 2) / (np.linalg.norm(Q, 2) * np.linalg.norm(Ge, 2))
            assert rel < 100 * n * eps * (np.linalg.cond(Ms) + np.linalg.cond(Mq)), (f.targets, w, rel)


def test_cs1_bank_with_the_plant_poles_as_filter_poles(cs1):
    # the plant's poles inside −0.2, fastest first, as the filter poles: the unit-gain scaling at ω = 0 met the
    # plant's integrator (pole 1e-16) left, cancelled, in the realisation of R_f and raised "a pole of the channel";
    # it now takes the finite limit just off it.  The bank still decouples the nominal loop to rounding
    nom = cs1.models[NOMINAL]
    ev = np.linalg.eigvals(nom.A)
    poles = [complex(x) for x in sorted(ev[ev.real < -0.2], key=lambda x: (x.real, -x.imag))]
    bank = efdisyn(nom, CS1_SFDI, fdtol=1e-5, fdgaintol=1e-3, fdfreq=0, rdim=1, sdeg=-5.0, poles=poles)
    assert [f.order for f in bank.filters] == [6, 6, 6, 5, 4, 4]
    T = closed_loop_norms(cs1, bank.generator)
    assert (T[NOMINAL] < 1e-8 * np.delete(T, NOMINAL, axis=0).min(axis=0)).all()
