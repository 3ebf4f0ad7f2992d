"""The observer basis ``[−Gu I]`` (the reference's ``nullspace = false``): FaultDetectionTools.jl test/test_afdsyn.jl
(Examples 5.6c and 5.9), test_efdsyn.jl, test_efdisyn.jl and test_afdisyn.jl ("solve using observer based
nullspace").  The reference's random plants (``rss(1, 3, 4)``, seed 2123) cannot be regenerated in Python; a seeded
plant of the same sizes (n = 1, p = 3, two controls, two faults, optionally two noise inputs) is used, and the
reference's coordinate-free checks are asserted: decoupling, the structure matrices equal to ``fdigenspec``'s,
``fdiscond(R_f)[2] = 1`` (unit H− index) and ``info.gap = fdif2ngap(R)``."""

import numpy as np
import pytest

from fdikit.analysis.performance import fdhinfminus, fdif2ngap
from fdikit.analysis.structure import fdisspec, fditspec
from fdikit.design.nullspace.approximate import afdisyn, afdsyn
from fdikit.design.nullspace.exact import efdisyn, efdsyn
from fdikit.design.nullspace.factorization import transfer
from fdikit.design.nullspace.observer_basis import observer_reduction
from fdikit.design.nullspace.specs import fdigenspec
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

_POINTS = (0.0, 0.3, 1.0, 4.0)


def example_5_6() -> FaultModel:
    """Varga (2017), Example 5.6: Gu = [(s+1)/(s+2); (s+2)/(s+3)], Gw = [1/(s+2); 0], Gf = [(s+1)/(s+2) 0; 0 1]."""
    return FaultModel([[-2.0, 0, 0], [0, -3.0, 0], [0, 0, -2.0]], [[-1.0, 0, 1.0], [0, -1.0, 0]],
                      Bu=[[1.0], [1.0], [0.0]], Du=[[1.0], [1.0]], Bf=[[1.0, 0], [0, 0], [0, 0]],
                      Df=[[1.0, 0], [0, 1.0]], Bw=[[0.0], [0.0], [1.0]])


def random_plant(noise: int = 0) -> FaultModel:
    rng = np.random.default_rng(2123)
    C, B, D = rng.standard_normal((3, 1)), rng.standard_normal((1, 4 + noise)), rng.standard_normal((3, 4 + noise))
    return FaultModel([[-0.7]], C, Bu=B[:, :2], Du=D[:, :2], Bf=B[:, 2:4], Df=D[:, 2:4], Bw=B[:, 4:], Dw=D[:, 4:])


def _controls_left(d, model) -> float:
    """max over a few frequencies of |Q [I; Gu]| / (|Q| |[I; Gu]|) (Q reads [u; y]): the controls' share."""
    g, worst = d.generator, 0.0
    for w in _POINTS:
        lam = 1j * w if model.dt is None else np.exp(1j * w * model.dt)
        Q = transfer((g.A, g.B, g.C, g.D), lam)
        Ge = np.vstack([np.eye(len(model.controls)), transfer((model.A, model.b("u"), model.C, model.d("u")), lam)])
        worst = max(worst, np.linalg.norm(Q @ Ge, 2) / (np.linalg.norm(Q, 2) * np.linalg.norm(Ge, 2)))
    return worst


def test_example_5_6c_observer_basis():
    # test_afdsyn.jl: afdsyn(nullspace = false, minimal = false, smarg = −2, sdeg = −3, rdim = 1, HDesign = [1 1]):
    # R_u = 0, fdisspec(R, block) = [1 1], fdif2ngap(R) = info.gap; the pole −2 (on the margin) moves to −3, −3 stays
    m = example_5_6()
    d = afdsyn(m, minimal=False, nullspace=False, smarg=-2.0, sdeg=-3.0, rdim=1, selection=[[1.0, 1.0]])
    assert _controls_left(d, m) < 1e-12
    assert fdisspec(d, block=True).matrix.tolist() == [[True, True]]
    assert d.gap == pytest.approx(fdif2ngap(d.internal_form()).ratio, rel=1e-9)
    assert d.gap == pytest.approx(3.0, rel=1e-9)                     # Example 5.6's gap, as the reference's comment
    np.testing.assert_allclose(d.poles.real, -3.0, rtol=1e-9)
    Dy = d.generator.D[0, 1:]
    assert Dy[0] == pytest.approx(Dy[1], rel=1e-12)                  # Q_y(∞) ∝ H = [1 1] (M̃(∞) = I)


def test_example_5_9_observer_basis_two_residuals():
    # test_afdsyn.jl, Example 5.9: rdim = 2, poles [−2, −3], sdeg = smarg = −2; the reference's HDesign = [1 0]
    # (the noise-attenuating residual y1 − ŷ1 sees f1 only, the noise-free one f2) is refused by fdikit, whose
    # noise-attenuating residuals must detect every target; with the default selection the reference's checks hold
    m = example_5_6()
    d = afdsyn(m, nullspace=False, smarg=-2.0, sdeg=-2.0, poles=[-2.0, -3.0], rdim=2)
    assert _controls_left(d, m) < 1e-12
    assert d.gap == pytest.approx(fdif2ngap(d.internal_form()).ratio, rel=1e-9)
    # the second residual decouples the noise (y1 only): ∝ y2 − ŷ2 = f2, as the reference's S2 = [0 1]
    assert fdisspec(d).matrix.tolist() == [[True, True], [False, True]]
    with pytest.raises(DesignError, match="detects every target"):
        afdsyn(m, nullspace=False, smarg=-2.0, sdeg=-2.0, poles=[-2.0, -3.0], rdim=2, selection=[[1.0, 0.0]])


def test_random_plant_full_and_least_order():
    # test_efdsyn.jl: nullspace = false with minimal = false (rdim = 2) and minimal = true (rdim = 1): R_u = 0,
    # info.S all ones; the filter has the plant's order
    m = random_plant()
    for kw in (dict(minimal=False, rdim=2), dict(minimal=True, rdim=1)):
        d = efdsyn(m, nullspace=False, **kw)
        assert _controls_left(d, m) < 1e-12
        assert d.order == 1 and d.structure.all()
        np.testing.assert_allclose(fdhinfminus(d.internal_form(), inputs=list(m.faults)).value, 1.0, rtol=1e-9)


@pytest.mark.parametrize("noise", [0, 2])
def test_random_plant_banks(noise):
    # test_efdisyn.jl / test_afdisyn.jl: SFDI = fdigenspec(sysf); efdisyn/afdisyn(SFDI; nullspace = false,
    # rdim = ones): fditspec = fdisspec(FDGainTol = 1e-3) = SFDI, R_u = 0, fdiscond(R_f)[2] = 1, gap = fdif2ngap
    m = random_plant(noise)
    S = fdigenspec(m)
    assert sorted(S.astype(int).tolist()) == [[0, 1], [1, 0], [1, 1]]    # the reference: [1 1; 0 1; 1 0]
    for bank in ((efdisyn, afdisyn) if noise else (efdisyn,)):
        b = bank(m, S, nullspace=False, rdim=1)
        assert fditspec(list(b.filters)).matrix.tolist() == S.tolist()
        assert fdisspec(list(b.filters), gain_tol=1e-3).matrix.tolist() == S.tolist()
        for row, f in zip(S, b.filters):
            assert _controls_left(f, m) < 1e-12
            targets = [x for x, s in zip(m.faults, row) if s]
            if bank is efdisyn:
                np.testing.assert_allclose(fdhinfminus(f.internal_form(), inputs=targets).value, 1.0, rtol=1e-9)
            else:
                assert f.gap == pytest.approx(fdif2ngap(f.internal_form(), targets).ratio, rel=1e-9)


def test_selection_in_output_coordinates():
    # test_efdisyn.jl: HDesign = [0.0396 0.8670 −1.7144] on the observer basis of the row [1 1]: fdiscond[2] = 1
    m = random_plant()
    h = [[0.03964565583901385, 0.8670124660000067, -1.7144387091257782]]
    d = efdsyn(m, nullspace=False, selection=h)
    np.testing.assert_allclose(fdhinfminus(d.internal_form(), inputs=list(m.faults)).value, 1.0, rtol=1e-9)
    Dy = d.generator.D[0, 2:]
    np.testing.assert_allclose(Dy / Dy[1], np.array(h[0]) / h[0][1], rtol=1e-9)   # Q_y(∞) ∝ H
    with pytest.raises(ParameterError, match="selection"):
        efdsyn(m, nullspace=False, selection=[[1.0, 0.0]])                  # one column per output


@pytest.mark.parametrize("dt, sdeg", [(None, -2.0), (0.1, 0.5)])
def test_unstable_plant_pole_moved(dt, sdeg):
    # y = [1; 1] x, x' = x + u (or x⁺ = 1.2 x + u), sensor faults: the observer moves the pole 1 (1.2) to sdeg and
    # nothing else; the filter and its internal form are stable with that pole only
    a = 1.0 if dt is None else 1.2
    m = FaultModel([[a]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2), dt=dt)
    obs = observer_reduction(m, sdeg=sdeg)
    np.testing.assert_allclose(np.linalg.eigvals(obs.reduced.A), [sdeg], rtol=1e-9)
    d = efdsyn(m, nullspace=False, sdeg=sdeg)
    np.testing.assert_allclose(d.poles, [sdeg], rtol=1e-9)
    assert _controls_left(d, m) < 1e-12 and d.structure.all()


def test_refusals():
    m = FaultModel([[-1.0]], [[1.0], [1.0]], Bd=[[1.0]], Df=np.eye(2))
    for syn in (efdsyn, afdsyn):
        with pytest.raises(ParameterError, match="observer basis"):
            syn(m, nullspace=False)
    with pytest.raises(ParameterError, match="poles"):
        observer_reduction(FaultModel([[1.0]], [[1.0]], Bu=[[1.0]], Df=[[1.0]]), poles=[])
