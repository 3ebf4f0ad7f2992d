"""Nullspace filters of plants whose faults or noise excite modes the controls do not: the internal form is made
stable by a left coprime factor (the reference's ``glcf`` step), and the weak AFDIP fallback of ``afdisyn``
(FaultDetectionTools.jl test/test_afdsyn.jl, "example with a weak AFDIP").  Expected values by hand."""

import numpy as np
import pytest

from fdikit.analysis.channels import minimal_channel
from fdikit.analysis.performance import fdif2ngap
from fdikit.analysis.structure import fdisspec
from fdikit.design.nullspace.approximate import afdisyn, afdsyn
from fdikit.design.nullspace.exact import efdsyn
from fdikit.errors import DesignError, FdiWarning
from fdikit.model import FaultModel


def _form_poles(d):
    return np.sort_complex(np.linalg.eigvals(minimal_channel(d.internal_form()).A))


def test_fault_through_an_integrator():
    # Gf = 1/s, Q = 1 would leave the pole 0 in Rf; M = s/(s + 0.05) and unit gain: Q = 0.05 s/(s + 0.05)
    d = efdsyn(FaultModel([[0.0]], [[1.0]], Bf=[[1.0]], faults=["f"]))
    np.testing.assert_allclose(d.poles.real, [-0.05], rtol=1e-9)
    np.testing.assert_allclose(_form_poles(d).real, [-0.05], rtol=1e-9)
    g = d.generator
    assert g.D[0, 0] == pytest.approx(0.05, rel=1e-9)                 # Q(∞) = 0.05
    assert (g.C @ np.linalg.solve(-g.A, g.B) + g.D)[0, 0] == pytest.approx(0.0, abs=1e-12)   # Q(0) = 0


def test_unstable_fault_mode():
    # Gf = 1/(s − 1) with a control through 1/(s + 1): the basis row [s + 1  −1]/(s + 2) leaves
    # Rf = (s + 1)/((s − 1)(s + 2)); M = (s − 1)/(s + 2) gives Rf ∝ (s + 1)/(s + 2)², scaled to ‖Rf‖∞ = 1
    m = FaultModel([[1.0, 0.0], [0.0, -1.0]], [[1.0, 1.0]], Bu=[[0.0], [1.0]], Bf=[[1.0], [0.0]], faults=["f"])
    d = efdsyn(m, sdeg=-2.0)
    np.testing.assert_allclose(np.sort(_form_poles(d).real), [-2.0, -2.0], rtol=1e-6)
    w = np.linspace(0, 10, 100001)                                    # by hand: sup |jω + 1| / |jω + 2|²
    k = 1 / np.max(np.abs(1j * w + 1) / np.abs(1j * w + 2) ** 2)
    R = minimal_channel(d.internal_form(), ["f"])
    assert abs((R.C @ np.linalg.solve(-R.A, R.B) + R.D)[0, 0]) == pytest.approx(k / 4, rel=1e-6)
    zeros = np.linalg.eigvals(d.generator.A - d.generator.B[:, [1]] @ d.generator.C / d.generator.D[0, 1])
    assert np.isclose(zeros, 1.0, rtol=1e-8).any()                    # the filter cancels the mode at 1


def weak_plant():
    """test_afdsyn.jl: Gf = [1/s  1/(s² + 4)] on one output."""
    A = np.array([[0.0, 0, 0], [0, 0, 1], [0, -4, 0]])
    return FaultModel(A, [[1.0, 1.0, 0.0]], Bf=[[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]], faults=["f1", "f2"])


def test_weak_afdip_fallback():
    # SFDI = [1 0]: f2 cannot be decoupled on one output, so f2 becomes noise.  By hand: M = s(s² + 4)/(s + 3)³,
    # Rw = s/(s+3)³ (a zero at 0, two at ∞: the quasi factor is constant), Rf1 = (s² + 4)/(s + 3)³, so the gap
    # at DC is (4/27) / max ω/(ω² + 9)^{3/2} = (4/27) / (√4.5 / 13.5^{3/2}) = 2√3
    with pytest.warns(FdiWarning, match="weak design"):
        bank = afdisyn(weak_plant(), [[1, 0]], sdeg=-3.0, rdim=1, fdfreq=[0])
    assert bank.weak == (True,) and bank.orders == (3,)
    assert bank.gaps[0] == pytest.approx(2 * np.sqrt(3), rel=1e-7)
    form = bank.internal_form()
    np.testing.assert_allclose(_form_poles(bank).real, [-3.0] * 3, rtol=1e-3)   # a triple pole: ε^{1/3} spread
    # the reference's checks: fdisspec(Rf, [0]) == [1, 0]; fdif2ngap(R, [1, 0], 0) ≈ info.gap
    assert fdisspec(form, 0.0).matrix.tolist() == [[True, False]]
    assert float(fdif2ngap(form, [True, False], 0.0).ratio) == pytest.approx(bank.gaps[0], rel=1e-7)


def test_weak_fallback_can_be_refused():
    with pytest.raises(DesignError, match="no residual is free"):
        afdisyn(weak_plant(), [[1, 0]], sdeg=-3.0, weak_fallback=False)
    with pytest.raises(DesignError, match="no residual is free"):
        afdsyn(weak_plant(), targets=["f1"], nuisance=["f2"])
