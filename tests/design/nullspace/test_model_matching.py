"""emmsyn against the reference's tests (FaultDetectionTools.jl test_emmsyn.jl) and hand solutions.

Every design is checked on the defining equation ``Q G_e = M M_r``: the internal form (fdikit's
``ResidualGenerator.internal_form``, the plant and the filter in series, independent of the synthesis) against the
returned target ``M M_r`` at several points, relative to the target's gain.  Numbers ported: Example 5.12 (``Q``
equals the unique solution ``[0 M_r]``, ``M = I``), Example 5.13 (``M`` and the orders, solved by hand below),
Example 5.4 (``emmsyn`` of ``efdsyn``'s ``R_f`` returns ``efdsyn``'s filter with ``M = 1``), the Niemann (1998) and
Xiong–Saif (2000, Ex. 2) banks (orders all 1), the random cases (``M_r = G``: ``Q = I``; the noise cases).
"""

import numpy as np
import pytest
from varga_examples import example_5_4, example_5_13, niemann, random_plant, response, xiong_saif_2

from fdikit.analysis.performance import fdimmperf
from fdikit.design.nullspace import efdisyn, efdsyn, emmsyn, fdigenspec
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import DesignResult

POINTS = (0.37 + 1.1j, 2.3j, -0.2 + 0.05j, 7.0)
DPOINTS = (np.exp(0.3j), np.exp(2.1j), 0.4 + 0.2j)


def mismatch(design, groups=("u", "d", "f")):
    """Largest |(Q G_e − M M_r)(λ)| over ``groups`` and points, relative to the largest |M M_r(λ)|."""
    form, target = design.internal_form(), design.target
    pts = POINTS if form.dt is None else DPOINTS
    err, scale = 0.0, 0.0
    for lam in pts:
        for g in groups:
            if not form.inputs[g]:
                continue
            R = response(form, g, lam)
            T = response(target, g, lam) if target.inputs[g] else np.zeros_like(R)
            err, scale = max(err, np.abs(R - T).max()), max(scale, np.abs(T).max())
    return err / scale


def tf(design, lam):
    g = design.generator
    return g.D + (g.C @ np.linalg.solve(lam * np.eye(g.n) - g.A, g.B) if g.n else 0)


def stable(design):
    return np.all(design.poles.real < 0) if design.generator.dt is None else np.all(np.abs(design.poles) < 1)


def fault_channel(form):
    return FaultModel(form.A, form.C, Bf=form.b("f"), Df=form.d("f"), faults=form.faults, outputs=form.outputs)


def test_example_5_12_unique_static_solution():
    # triplex sensors: Gu = 1 · gu, Gd = 1 · gd, Gf = I; M_r is orthogonal to [1 1 1]ᵀ, so Q = [0 M_r], M = I
    gu, gd = random_plant(5, 2, 1, 2, 0, 0), random_plant(6, 3, 1, 0, 1, 0)
    A = np.block([[gu.A, np.zeros((2, 3))], [np.zeros((3, 2)), gd.A]])
    ones = np.ones((3, 1))
    m = FaultModel(A, np.hstack([ones @ gu.C, ones @ gd.C]), Bu=np.vstack([gu.b("u"), np.zeros((3, 2))]),
                   Du=ones @ gu.d("u"), Bd=np.vstack([np.zeros((2, 1)), gd.b("d")]), Dd=ones @ gd.d("d"),
                   Bf=np.zeros((5, 3)), Df=np.eye(3))
    Mr = np.array([[0.0, 1, -1], [-1, 0, 1], [1, -1, 0]])
    d = emmsyn(m, {"f": Mr})
    assert isinstance(d, DesignResult)
    assert d.orders == (0, 0, 0) and d.generator.n == 0
    np.testing.assert_allclose(d.generator.D, np.hstack([np.zeros((3, 2)), Mr]), atol=1e-12)
    assert all(num.tolist() == [1.0] and den.tolist() == [1.0] for num, den in d.updating)
    assert mismatch(d) < 1e-12


def test_example_5_13_updating_factor_by_hand():
    # row 1: n_y Gu = m [1 0] needs degree 1 and m = s (a zero of Gu at 0): M1 = s/(s+1);
    # row 2: n_y = [0 0 s+2], m = 1: M2 = 1/(s+1) (improper Q̃ made proper); sdeg = −1
    m = example_5_13()
    d = emmsyn(m, {"f": np.eye(2)}, sdeg=-1.0)
    assert d.orders == (1, 1)
    (n1, d1), (n2, d2) = d.updating
    np.testing.assert_allclose(n1, [1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(d1, [1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(n2, [1.0], atol=1e-9)
    np.testing.assert_allclose(d2, [1.0, 1.0], atol=1e-12)
    assert stable(d) and mismatch(d) < 1e-9
    # the fault part of the internal form is M itself: Q [Gf; 0] = diag(s/(s+1), 1/(s+1))
    lam = 0.3 + 0.8j
    np.testing.assert_allclose(response(d.internal_form(), "f", lam), np.diag([lam / (lam + 1), 1 / (lam + 1)]),
                               atol=1e-9)
    with pytest.raises(DesignError, match="vanishes at DC"):
        emmsyn(m, {"f": np.eye(2)}, sdeg=-1.0, normalize="dcgain")


def test_example_5_4_recovers_efdsyn():
    m = example_5_4()
    e = efdsyn(m, sdeg=-3.0, rdim=1)
    d = emmsyn(m, fault_channel(e.internal_form()))
    assert d.orders == (1,) and e.order == 1
    assert [(num.tolist(), den.tolist()) for num, den in d.updating] == [([1.0], [1.0])]
    for lam in POINTS:
        q_e = e.generator.D + e.generator.C @ np.linalg.solve(lam * np.eye(e.generator.n) - e.generator.A,
                                                              e.generator.B)
        np.testing.assert_allclose(tf(d, lam), q_e, atol=1e-9 * np.abs(q_e).max())
    assert mismatch(d) < 1e-9


@pytest.mark.parametrize("plant, sdeg", [(niemann, None), (xiong_saif_2, -2.0)])
def test_banks_of_efdisyn_least_order(plant, sdeg):
    m = plant()
    S = fdigenspec(m)
    bank = efdisyn(m, S, rdim=1, sdeg=sdeg)
    refs = [fault_channel(f.internal_form()) for f in bank.filters]
    mm = emmsyn(m, refs)
    assert mm.orders == (1,) * len(S) == bank.orders
    for f in mm.filters:
        assert stable(f) and mismatch(f) < 1e-7
        assert [(num.tolist(), den.tolist()) for num, den in f.updating] == [([1.0], [1.0])]
    assert mm.groups == tuple((f"r{j}",) for j in range(len(S)))


def test_reference_equal_to_plant_gives_identity():
    m = random_plant(11, 1, 2, 0, 0, 2)
    ref = FaultModel(m.A, m.C, Bf=m.b("f"), Df=m.d("f"), faults=m.faults)
    d = emmsyn(m, ref)
    assert d.orders == (0, 0)
    np.testing.assert_allclose(d.generator.D, np.eye(2), atol=1e-9)
    assert mismatch(d) < 1e-9


def test_more_outputs_than_reference_rows():
    m = random_plant(12, 1, 3, 0, 0, 2)
    ref = FaultModel(m.A, m.C[:2], Bf=m.b("f"), Df=m.d("f")[:2], faults=m.faults)
    d = emmsyn(m, ref)
    assert d.orders == (0, 0) and mismatch(d) < 1e-9
    assert all(den.tolist() == [1.0] for _, den in d.updating)


def test_noise_free_or_matched():
    base = random_plant(13, 1, 3, 0, 0, 4)
    Bw, Dw = base.b("f")[:, 2:], base.d("f")[:, 2:]
    m = FaultModel(base.A, base.C, Bf=base.b("f")[:, :2], Df=base.d("f")[:, :2], Bw=Bw, Dw=Dw)
    ref = FaultModel(m.A, m.C[:2], Bf=m.b("f"), Df=m.d("f")[:2], faults=m.faults)
    d = emmsyn(m, ref)
    assert d.matched == ("u", "d", "f") and mismatch(d) < 1e-9
    # the noise is free: ‖R − M M_r‖ is the noise channel's norm
    assert fdimmperf(d.internal_form(), ref=d.target) == pytest.approx(fdimmperf(d.internal_form()), rel=1e-8)
    ref_w = FaultModel(m.A, m.C[:2], Bf=m.b("f"), Df=m.d("f")[:2], Bw=Bw, Dw=Dw[:2], faults=m.faults,
                       noise=m.noise)
    dw = emmsyn(m, ref_w)
    assert dw.matched == ("u", "d", "f", "w") and mismatch(dw, ("u", "d", "f", "w")) < 1e-9
    assert fdimmperf(dw.internal_form(), ref=dw.target) < 1e-7


def test_controls_in_the_reference():
    # match Q [Gu; I] = M Gu (an estimate of the noise-free output) and the faults to zero
    m = random_plant(14, 2, 2, 1, 0, 1)
    ref = FaultModel(m.A, m.C[:1], Bu=m.b("u"), Du=m.d("u")[:1], controls=m.controls)
    d = emmsyn(m, ref)
    assert stable(d) and mismatch(d) < 1e-9


def test_fault_estimation_discrete_runs_in_batch():
    from fdikit.trace import Trace

    m = random_plant(15, 3, 3, 1, 1, 2, dt=0.1)
    d = emmsyn(m, {"f": np.eye(2)}, normalize="dcgain")
    assert stable(d) and mismatch(d) < 1e-9
    for num, den in d.updating:           # unit DC gain M_i(1) = 1 and poles at the default 0.95
        assert np.polyval(num, 1.0) / np.polyval(den, 1.0) == pytest.approx(1.0, rel=1e-12)
        assert np.allclose(np.roots(den), 0.95, atol=1e-3) if len(den) > 1 else True
    rng = np.random.default_rng(1)
    N = 300
    u, dd, f = rng.standard_normal((N, 1)), rng.standard_normal((N, 1)), np.zeros((N, 2))
    f[100:, 0], f[200:, 1] = 1.0, -0.5
    x, ys = np.zeros(m.n), []
    for k in range(N):
        v = np.concatenate([u[k], dd[k], f[k]])
        ys.append(m.C @ x + m.D @ v)
        x = m.A @ x + m.B @ v
    r = d.generator.run(Trace(np.arange(N) * 0.1, u, np.array(ys), m.controls, m.outputs)).r
    # the residual is M f: the target driven by the faults alone
    T = d.target
    xt, expect = np.zeros(T.n), []
    for k in range(N):
        expect.append(T.C @ xt + T.d("f") @ f[k])
        xt = T.A @ xt + T.b("f") @ f[k]
    np.testing.assert_allclose(r, np.array(expect), atol=1e-8 * np.abs(np.array(ys)).max())


def test_normalize_infnorm_and_poles():
    m = example_5_13()
    d = emmsyn(m, {"f": np.eye(2)}, normalize="infnorm", poles=[-2.0])
    w = np.logspace(-4, 4, 20001)
    for num, den in d.updating:
        np.testing.assert_allclose(den, [1.0, 2.0], atol=1e-12)
        assert np.abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)).max() == pytest.approx(1.0, rel=1e-6)
    assert mismatch(d) < 1e-9


def test_bad_input():
    m = example_5_13()
    with pytest.raises(ParameterError, match="columns"):
        emmsyn(m, {"f": np.eye(3)[:, :1]})
    with pytest.raises(ModelError, match="group 'f'"):
        emmsyn(m, FaultModel([[-1.0]], [[1.0]], Bf=[[1.0]]))
    with pytest.raises(ParameterError, match="normalize"):
        emmsyn(m, {"f": np.eye(2)}, normalize="peak")
    with pytest.raises(ParameterError, match="FaultModel or a mapping"):
        emmsyn(m, np.eye(2))
    with pytest.raises(ParameterError, match="not a stable pole"):
        emmsyn(m, {"f": np.eye(2)}, sdeg=1.0)
    with pytest.raises(ModelError, match="dt"):
        emmsyn(m, FaultModel([[0.5]], [[1.0]], Bf=[[1.0, 0.0]], dt=0.1))
    # a fault the outputs do not see cannot be estimated
    blind = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Bf=[[0.0, 0.0]], Df=[[1.0, 0.0], [0.0, 0.0]])
    with pytest.raises(DesignError, match="not achievable"):
        emmsyn(blind, {"f": np.eye(2)})
    with pytest.raises(ParameterError, match="names"):
        emmsyn(m, [{"f": np.eye(2)}], names=["a", "b"])
