"""efdsyn / efdisyn / the nullspace basis against the reference's tests (FaultDetectionTools.jl test_efdsyn.jl).

Numbers ported: the orders of Niemann (1998) and Xiong and Saif (2000, Ex. 1) banks (all 1; [2, 1, 1]), the strong
structure at ω = 0 of those banks, the order 1 of Varga (2017) Example 5.4, the failure of Example 5.2.  Decoupling
is checked on the internal form (fdikit's ResidualGenerator.internal_form, independent of the synthesis) at several
points, relative to the filter's gain.
"""

import numpy as np
import pytest
from varga_examples import example_5_2, example_5_4, niemann, random_plant, response, xiong_saif_1, yuan

from fdikit.design.nullspace import efdisyn, efdsyn, left_nullspace
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import DesignResult

POINTS = (0.37 + 1.1j, 2.3j, -0.2 + 0.05j)


def decoupling(form, groups=("u", "d")):
    """Largest |R_g(λ)| over the groups and points, relative to the largest fault gain there."""
    out, scale = 0.0, 0.0
    for lam in POINTS:
        for g in groups:
            if form.inputs[g]:
                out = max(out, np.abs(response(form, g, lam)).max())
        scale = max(scale, np.abs(response(form, "f", lam)).max())
    return out / scale


def test_basis_rows_annihilate_and_have_least_degrees():
    m = yuan()
    b = left_nullspace(m)
    # [Gu; I] with (C, A) observable: the left minimal indices are the observability indices of (C, A), sum n
    assert b.degrees == (1, 1, 2) and sum(b.degrees) == m.n
    G = np.vstack([np.eye(1), m.C @ np.linalg.solve(0.4j * np.eye(4) - m.A, m.B[:, :1])])
    assert np.abs(b.evaluate(0.4j) @ G).max() < 1e-12
    bn = left_nullspace(m, ["f0", "f1"])
    assert bn.degrees == (1,)       # p − rank [Gf0 Gf1] = 1 row


def test_example_5_4_least_order():
    d = efdsyn(example_5_4(), sdeg=-3.0)
    assert isinstance(d, DesignResult)
    assert d.order == 1 and d.degrees == (1,)
    np.testing.assert_allclose(d.poles, [-3.0], rtol=1e-12)
    assert decoupling(d.internal_form()) < 1e-10
    # strongly detects both faults at ω = 0 (reference: fdisspec(Rf, [0]) == [1 1])
    strong = efdsyn(example_5_4(), sdeg=-3.0, fdfreq=0.0)
    assert strong.structure.tolist() == [[True, True]]


def test_example_5_2_has_no_solution():
    with pytest.raises(DesignError, match=r"\['f0'\] cannot be detected"):
        efdsyn(example_5_2())


@pytest.mark.parametrize("plant, orders", [(niemann, (1, 1, 1)), (xiong_saif_1, (2, 1, 1))])
def test_banks_of_the_reference(plant, orders):
    m = plant()
    S = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    bank = efdisyn(m, S, sdeg=-5.0, fdfreq=0.0, fdgaintol=1e-4)
    assert bank.orders == orders
    form = bank.internal_form()
    assert decoupling(form) < 1e-9
    # strong structure at ω = 0 of the stacked R_f equals S (reference: fdisspec_(Rftilde, 0) == SFDI)
    R0 = np.abs(response(form, "f", 0.0))
    assert ((R0 > 1e-4 * R0.max()) == S).all()
    for f in bank.filters:
        assert np.all(f.poles.real < 0)


def test_full_order_and_selection():
    m = yuan()
    full = efdsyn(m, minimal=False)
    assert full.order == 4 and len(full.generator.residuals) == 3
    least = efdsyn(m)
    assert least.order == 2 and len(least.generator.residuals) == 1      # = fdichkspec least order of [1 … 1]
    # the two degree-1 rows miss a fault, so the least-order pair combines all three rows over degree 2
    two = efdsyn(m, rdim=2, selection=[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])
    assert two.used == (0, 1, 2) and two.order <= 4 and two.structure.any(axis=0).all()
    assert decoupling(two.internal_form(), ("u",)) < 1e-10


def test_generator_runs_batch_and_online():
    from fdikit.trace import Trace

    m = random_plant(4, 3, 3, 1, 1, 2, dt=0.1)
    d = efdsyn(m, targets=["f0"], nuisance=["f1"], sdeg=0.5)
    rng = np.random.default_rng(0)
    N = 200
    u, dd, f = rng.standard_normal((N, 1)), rng.standard_normal((N, 1)), np.zeros((N, 2))
    f[100:, 1] = 1.0                   # the nuisance fault only: decoupled
    x, ys = np.zeros(m.n), []
    for k in range(N):
        v = np.concatenate([u[k], dd[k], f[k]])
        ys.append(m.C @ x + m.D @ v)
        x = m.A @ x + m.B @ v
    trace = Trace(np.arange(N) * 0.1, u, np.array(ys), m.controls, m.outputs)
    r = d.generator.run(trace).r
    scale = np.abs(d.generator.D).max() * np.abs(np.array(ys)).max()
    assert np.abs(r).max() < 1e-9 * scale
    stepper = d.generator.online()
    online = np.array([stepper.step(u[k], ys[k]) for k in range(N)])
    np.testing.assert_allclose(online, r, atol=1e-12 * scale)


def test_bad_input():
    m = yuan()
    with pytest.raises(ParameterError, match="both targets and nuisance"):
        efdsyn(m, targets=["f0"], nuisance=["f0"])
    with pytest.raises(DesignError, match="rdim"):
        efdsyn(m, rdim=4)
    with pytest.raises(ParameterError, match="not stable"):
        efdsyn(m, poles=[1.0])
    with pytest.raises(ParameterError, match="0/1 matrix"):
        efdisyn(m, [[1, 0]])


def _simulate(m, u, f, noise, rng):
    x, ys = np.zeros(m.n), []
    mu, md = len(m.controls), len(m.disturbances)
    for k in range(len(u)):
        v = np.concatenate([u[k], rng.standard_normal(md), f[k]])
        ys.append(m.C @ x + m.D @ v + noise * rng.standard_normal(len(m.outputs)))
        x = m.A @ x + m.B[:, : mu + md + len(f[k])] @ v
    return np.array(ys)


def test_bank_plugs_into_evaluators_and_the_compiled_runtime():
    from fdikit.decision import ThresholdEvaluator
    from fdikit.runtime import compile_generator
    from fdikit.trace import Trace

    m = random_plant(7, 3, 3, 1, 1, 0, dt=0.05)
    m = FaultModel(m.A, m.C, Bu=m.Bu, Bd=m.Bd, Du=m.Du, Dd=m.Dd, Df=np.eye(3)[:, :2], faults=("s0", "s1"), dt=0.05)
    bank = efdisyn(m, np.eye(2), sdeg=0.6)
    assert bank.generator.isolates == ("s0", "s1")
    rng = np.random.default_rng(3)
    N = 4000
    u = rng.standard_normal((N, 1))
    t = np.arange(N) * 0.05
    healthy = Trace(t, u, _simulate(m, u, np.zeros((N, 2)), 0.01, rng), m.controls, m.outputs)
    ev = ThresholdEvaluator().fit(bank.generator.run(healthy), false_alarm_prob=1e-4)
    f = np.zeros((N, 2))
    f[2000:, 1] = 0.5                  # 50 noise standard deviations on the second sensor
    faulty = Trace(t, u, _simulate(m, u, f, 0.01, rng), m.controls, m.outputs)
    res = bank.generator.run(faulty)
    diag = ev.run(res)
    named = diag.isolated[2100:]
    assert np.mean(named == "s1") > 0.95 and not np.any(named == "s0")
    # the bank's structure matrix as the signature table of the decision logic: the same isolation
    from fdikit.analysis import fditspec

    S = fditspec(bank.generator.internal_form(m), groups=bank.groups)
    by_table = ThresholdEvaluator(signatures=S).fit(bank.generator.run(healthy), false_alarm_prob=1e-4)
    assert S.matrix.tolist() == np.eye(2, dtype=bool).tolist()
    assert by_table.run(res).isolated.tolist() == diag.isolated.tolist()
    compiled = compile_generator(bank.generator)
    ref = bank.generator.online()
    for k in range(200):
        a, b = compiled.step(u[k], faulty.y[k]), ref.step(u[k], faulty.y[k])
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(b).max()))


def _kronecker_left_indices(m, nuisance=()):
    """Left Kronecker indices of the system pencil of ``[Gu Gd Gn; I 0 0]`` by SLICOT AB08ND (independent)."""
    import slycot

    from fdikit.design.nullspace.basis import minimal_realization

    mu, md = len(m.controls), len(m.disturbances)
    cols = list(range(mu + md)) + [mu + md + i for i in m.index("f", list(nuisance))]
    A, B, C, D = minimal_realization(m.A, m.B[:, cols], m.C, m.D[:, cols])
    n = A.shape[0]
    Ce = np.vstack([C, np.zeros((mu, n))])
    De = np.vstack([D, np.hstack([np.eye(mu), np.zeros((mu, len(cols) - mu))])])
    out = slycot.ab08nd(n, len(cols), C.shape[0] + mu, A, B, Ce, De, equil="S")
    return tuple(sorted(int(k) for k in out[7][: out[4]]))


@pytest.mark.parametrize("case", ["yuan", "yuan-f0f1", "ex54", "niemann", "niemann-f0", "xiong-saif-f1", "path",
                                  "path-2", "random", "random-discrete"])
def test_degrees_are_the_left_kronecker_indices(case):
    from fdikit.studies.path1996.bank import path_fault_model

    m, nz = {
        "yuan": (yuan, ()), "yuan-f0f1": (yuan, ("f0", "f1")), "ex54": (example_5_4, ()), "niemann": (niemann, ()),
        "niemann-f0": (niemann, ("f0",)), "xiong-saif-f1": (xiong_saif_1, ("f1",)),
        "path": (lambda: path_fault_model(14), ()),
        "path-2": (lambda: path_fault_model(14), ("accel_x_sensor", "throttle_actuator")),
        "random": (lambda: random_plant(5, 6, 5, 2, 2, 3), ("f0",)),
        "random-discrete": (lambda: random_plant(6, 5, 4, 1, 1, 2, dt=0.1), ()),
    }[case]
    model = m()
    assert left_nullspace(model, nz).degrees == _kronecker_left_indices(model, nz)


def test_rows_of_one_degree_do_not_depend_on_the_svd_rotation():
    # the SVD returns equal-singular-value rows in a rotation rounding decides (it changes with the BLAS kernel);
    # the canonical rows are the same for every rotation of the same space, and span it
    from fdikit.design.nullspace.basis import _canonical

    rng = np.random.default_rng(3)
    V = np.linalg.qr(rng.standard_normal((7, 3)))[0].T                       # 3 orthonormal rows in R^7
    Rot = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    a, b = _canonical(V), _canonical(Rot @ V)
    np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_allclose(a @ a.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(a - (a @ V.T) @ V, 0.0, atol=1e-12)            # in the row space of V


def test_generic_combination_retried_when_it_misses_a_target():
    # PATH, a feasible row (fdichkspec) where the first fixed combination of the two degree-1 rows brought a target
    # under fdtol (the synthesis-time benchmark stopped there); the next fixed combinations are tried first
    from fdikit.design.nullspace import fdichkspec
    from fdikit.studies.path1996 import path_fault_model

    m = path_fault_model(14)
    row = np.array([0, 1, 1, 1, 0, 0, 1, 0, 1, 1, 1, 1, 0, 1, 1], dtype=bool)
    assert fdichkspec(m, row[None, :]).feasible[0]
    targets = [f for f, s in zip(m.faults, row) if s]
    nuisance = [f for f, s in zip(m.faults, row) if not s]
    d = efdsyn(m, targets=targets, nuisance=nuisance)
    assert d.structure[:, : len(targets)].any(axis=0).all()
    assert decoupling(d.internal_form(), groups=("u",)) < 1e-9
    bank = efdisyn(m, row[None, :])
    assert bank.orders == (d.order,)
