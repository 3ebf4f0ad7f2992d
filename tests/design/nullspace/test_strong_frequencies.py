"""Strong synthesis where the frequencies are zeros or poles of the fault channels (FaultDetectionTools.jl
test/test_efdsyn.jl, test_afdsyn.jl, test_efdisyn.jl, test_afdisyn.jl: "Example with solvable strong synthesis
(frequencies are also zeros / poles)", with and without ``simple = true``).

fdikit's basis is always simple (each row over its own denominator, the reference's ``simple = true``), so both
variants of the reference's tests are the same test here.  Without controls and disturbances the basis is the
identity (the residuals are the outputs, in order); the reference lists the second output first, so its per-row
structure matrices are compared with the rows reversed.  The reference's third variant, ``G_f = [s; s² + 4]``, is
improper and fdikit's synthesis refuses improper plants.  Plants realised by hand:

* ``G_f = [s/(s+1) 0; (s²+4)/(s+3)² 1]``: ``s/(s+1) = 1 − 1/(s+1)``, ``(s²+4)/(s+3)² = 1 + (−6s − 5)/(s+3)²``;
* ``G_f = [1/s; 1/(s²+4)]``.
"""

import numpy as np
import pytest

from fdikit.analysis.structure import fdisspec, fditspec
from fdikit.design.nullspace.approximate import afdisyn, afdsyn
from fdikit.design.nullspace.exact import efdisyn, efdsyn
from fdikit.design.nullspace.specs import fdigenspec
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

A_ZEROS = np.array([[-1.0, 0, 0], [0, 0, 1], [0, -9, -6]])
C_ZEROS = np.array([[-1.0, 0, 0], [0, -5, -6]])


def zeros_plant(nf: int = 2) -> FaultModel:
    """``G_f = [s/(s+1) 0; (s²+4)/(s+3)² 1]`` (its first ``nf`` columns)."""
    Bf = np.array([[1.0, 0], [0, 0], [1, 0]])
    Df = np.array([[1.0, 0], [1, 1]])
    return FaultModel(A_ZEROS, C_ZEROS, Bf=Bf[:, :nf], Df=Df[:, :nf])


def poles_plant() -> FaultModel:
    """``G_f = [1/s; 1/(s²+4)]``."""
    return FaultModel([[0.0, 0, 0], [0, 0, 1], [0, -4, 0]], [[1.0, 0, 0], [0, 1, 0]], Bf=[[1.0], [0], [1]])


def _same_filter(d1, d2):
    for a, b in ((d1.generator.A, d2.generator.A), (d1.generator.B, d2.generator.B),
                 (d1.generator.C, d2.generator.C), (d1.generator.D, d2.generator.D)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_structure_matrices_at_zeros():
    # test_efdsyn.jl: fdisspec_(Gf, [0, 2]; FDGainTol = 1e-3) and fditspec_ with FDfreq = [0, 2] and without
    m = zeros_plant()
    S = fdisspec(m, [0.0, 2.0], gain_tol=1e-3)
    np.testing.assert_allclose(S.gains[:, :, 0], [[0.0, 0.0], [0.4444444444444444, 1.0]], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(S.gains[:, :, 1], [[0.894427190999916, 0.0], [0.0, 1.0]], rtol=1e-12, atol=1e-14)
    smat = {0.0: [[False, False], [True, True]], 2.0: [[True, False], [False, True]]}
    for w, ref in smat.items():
        assert fdisspec(m, [w], gain_tol=1e-3).matrix.tolist() == ref
        assert fditspec(m, [w]).matrix.tolist() == ref          # the reference's smat == ssmat
    assert fditspec(m, [0.0, 2.0]).matrix.tolist() == [[False, False], [False, True]]   # at both frequencies
    assert fditspec(m).matrix.tolist() == [[True, False], [True, True]]                 # swmat


@pytest.mark.parametrize("syn", [efdsyn, afdsyn])
def test_strong_detection_by_a_combination_of_rows(syn):
    # one fault: neither output alone sees it at both 0 and 2 rad/s, a combination of both does
    m = zeros_plant(1)
    d = syn(m, sdeg=-3.0, rdim=1, fdfreq=[0, 2])
    assert fdisspec(d, [0.0, 2.0]).matrix.tolist() == [[True]]
    assert d.order == 0 and np.all(np.abs(d.selection) > 0.1)
    _same_filter(d, syn(m, sdeg=-3.0, rdim=1, fdfreq=[0, 2], fdgaintol=0.001, selection=d.selection))
    for h in ([[1.0, 0.0]], [[0.0, 1.0]]):
        with pytest.raises(DesignError, match="misses a target"):
            syn(m, sdeg=-3.0, rdim=1, fdfreq=[0, 2], selection=h)


@pytest.mark.parametrize("syn", [efdsyn, afdsyn])
def test_two_residuals_structure_per_frequency(syn):
    # test_efdsyn.jl / test_afdsyn.jl with faults = 1:2, rdim = 2: the reference's rows are [y2; y1]
    d = syn(zeros_plant(), sdeg=-3.0, rdim=2, fdfreq=[0, 2])
    ref = {(0.0, 2.0): [[0, 1], [0, 0]], (0.0,): [[1, 1], [0, 0]], (2.0,): [[0, 1], [1, 0]]}
    for w, S in ref.items():
        assert fdisspec(d, list(w)).matrix.astype(int).tolist() == S[::-1]
    assert fdisspec(d, [0.0, 2.0], block=True).matrix.tolist() == [[True, True]]


@pytest.mark.parametrize("bank", [efdisyn, afdisyn])
def test_bank_at_zeros(bank):
    # test_efdisyn.jl / test_afdisyn.jl: SFDI = fdigenspec(FDfreq = [0, 2], FDGainTol = 1e-3); by hand only [1 1]:
    # decoupling f2 leaves y1 = s/(s+1) f1 (zero at 0), decoupling f1 leaves a multiple of s/(s+1) f2
    m = zeros_plant()
    S = fdigenspec(m, fdfreq=[0, 2], fdgaintol=1e-3)
    assert S.tolist() == [[True, True]]
    b = bank(m, S, sdeg=-3.0, rdim=1, fdfreq=[0, 2])
    assert fdisspec(list(b.filters), [0.0, 2.0]).matrix.tolist() == S.tolist()


@pytest.mark.parametrize("syn", [efdsyn, afdsyn])
def test_strong_detection_at_poles(syn):
    # Gf = [1/s; 1/(s²+4)], rdim = 1: Q = h (constant) leaves the poles 0, ±2j in R_f; the stabilising factor
    # s(s²+4)/(s+3)³ makes R_f = (h1 (s²+4) + h2 s)/(s+3)³: order 3, strong at 0 (h1) and at 2 rad/s (h2)
    m = poles_plant()
    d = syn(m, sdeg=-3.0, rdim=1, fdfreq=[0, 2])
    assert fdisspec(d, [0.0, 2.0]).matrix.tolist() == [[True]]
    assert d.order == 3
    np.testing.assert_allclose(d.poles.real, [-3.0] * 3, atol=1e-3)     # a triple pole: spread ~ ε^{1/3}
    _same_filter(d, syn(m, sdeg=-3.0, rdim=1, fdfreq=[0, 2], fdgaintol=0.001, selection=d.selection))


@pytest.mark.parametrize("bank", [efdisyn, afdisyn])
def test_bank_at_poles_rdim_per_row(bank):
    # test_efdisyn.jl: SFDI = [SFDI; SFDI], rdim = [1, 2]; by hand: orders 3 (one combined row) and 1 + 2
    m = poles_plant()
    S = fdigenspec(m, fdfreq=[0, 2], fdgaintol=1e-3)
    assert S.tolist() == [[True]]
    b = bank(m, np.vstack([S, S]), sdeg=-3.0, rdim=[1, 2], fdfreq=[0, 2])
    assert [len(g) for g in b.groups] == [1, 2] and b.orders == (3, 3)
    assert fdisspec(list(b.filters), [0.0, 2.0]).matrix.tolist() == [[True], [True]]
    with pytest.raises(ParameterError, match="one per row"):
        bank(m, np.vstack([S, S]), rdim=[1, 2, 1])
