"""DescriptorModel: validation, G(λ), poles, FaultModel round trips, an index-1 circuit DAE, improper models."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from fdikit import FaultModel
from fdikit.descriptor.model import DescriptorModel
from fdikit.descriptor.reduction import nondynamic_count
from fdikit.errors import ModelError

W = np.logspace(-2, 2, 25)


def rel_err(G1, G2):
    return float(np.max(np.abs(G1 - G2)) / max(np.max(np.abs(G2)), 1e-300))


def same_points(a, b, tol):
    """Whether two sets of complex numbers agree to ``tol`` (each point of ``a`` matched to a distinct one of b)."""
    a, b = list(np.asarray(a, complex)), list(np.asarray(b, complex))
    if len(a) != len(b):
        return False
    for z in a:
        k = int(np.argmin([abs(z - w) for w in b]))
        if abs(z - b[k]) > tol:
            return False
        b.pop(k)
    return True


def random_fault_model(seed, n=4, p=3, dt=None):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) - 3 * np.eye(n)
    if dt is not None:
        A = A / (1.1 * max(abs(np.linalg.eigvals(A))))
    return FaultModel(A, rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 2)), Bd=rng.standard_normal((n, 1)),
                      Bf=rng.standard_normal((n, 2)), Df=rng.standard_normal((p, 2)), Bw=rng.standard_normal((n, 1)),
                      controls=["u1", "u2"], disturbances=["d"], faults=["f1", "f2"], noise=["w"], dt=dt)


@pytest.mark.parametrize("dt", [None, 0.1])
def test_round_trip_keeps_names_groups_and_response(dt):
    fm = random_fault_model(1, dt=dt)
    T = scipy.stats.ortho_group.rvs(fm.n, random_state=2) @ np.diag([1.0, 2.0, 5.0, 10.0])
    for E in (None, T):
        dm = DescriptorModel.from_fault_model(fm, E=E)
        assert dm.inputs == {**fm.inputs, "aux": ()} and dm.dt == fm.dt and dm.states == fm.states
        assert rel_err(dm.freqresp(W), fm.freqresp(W)) < 1e-10
        back = dm.to_fault_model()
        assert back.inputs == fm.inputs and back.states == fm.states and back.n == fm.n
        assert rel_err(back.freqresp(W), fm.freqresp(W)) < 1e-10
        assert same_points(dm.poles(), fm.poles(), 1e-9 * np.linalg.norm(fm.A))


def circuit(R1=2.0, R2=4.0, Cap=0.5, out="i2"):
    """Source u → R1 → node v (capacitor Cap to ground, R2 to ground).  States (v, i1, i2): index 1."""
    E = np.diag([Cap, 0.0, 0.0])
    A = np.array([[0.0, 1.0, -1.0],      # Cap v' = i1 − i2
                  [-1.0, -R1, 0.0],      # 0 = u − R1 i1 − v
                  [1.0, 0.0, -R2]])      # 0 = v − R2 i2
    C = np.array([[0.0, 0.0, 1.0]]) if out == "i2" else np.array([[0.0, 1.0, 0.0]])
    B = np.array([[0.0], [1.0], [0.0]])
    return DescriptorModel(A, C, E=E, Bu=B, Bf=B, controls=["source"], faults=["source_fault"],
                           states=["v", "i1", "i2"], outputs=[out])


@pytest.mark.parametrize("out", ["i2", "i1"])
def test_index1_circuit_reduces_to_the_hand_derived_transfer(out):
    R1, R2, Cap = 2.0, 4.0, 0.5
    dae = circuit(R1, R2, Cap, out)
    s = 1j * W
    v_over_u = (1 / R1) / (Cap * s + 1 / R1 + 1 / R2)
    G = v_over_u / R2 if out == "i2" else (1 - v_over_u) / R1  # i1 = (u − v)/R1: feedthrough 1/R1
    assert rel_err(dae.freqresp(W, "u")[:, 0, 0], G) < 1e-12
    assert nondynamic_count(dae) == 2
    fm = dae.to_fault_model()
    assert fm.n == 1 and fm.faults == ("source_fault",) and fm.controls == ("source",)
    assert rel_err(fm.freqresp(W, "u")[:, 0, 0], G) < 1e-12
    assert rel_err(fm.freqresp(W), dae.freqresp(W)) < 1e-12
    assert float(fm.D[0, 0]) == pytest.approx(0.0 if out == "i2" else 1 / R1, abs=1e-14)
    np.testing.assert_allclose(fm.poles(), [-(1 / R1 + 1 / R2) / Cap], rtol=1e-12)
    np.testing.assert_allclose(dae.poles(), [-(1 / R1 + 1 / R2) / Cap], rtol=1e-12)


def test_improper_model_is_refused_with_the_reason():
    # N x' = x + B u with a Jordan block of size 2 at infinity: y = −u', G(s) = −s.
    m = DescriptorModel(np.eye(2), [[1.0, 0.0]], E=[[0.0, 1.0], [0.0, 0.0]], Bu=[[0.0], [1.0]])
    for s in (0.5, 2j, -3.0 + 1j):
        assert complex(m.evaluate(s)[0, 0]) == pytest.approx(-s, rel=1e-12)
    assert m.poles().size == 0
    with pytest.raises(ModelError, match="improper.*sizes \\[2\\]"):
        m.to_fault_model()


def test_uncontrollable_higher_index_part_does_not_block_conversion():
    # a proper 1/(s+1) plus a size-3 Jordan block at infinity that no input reaches: convertible
    N = np.diag([1.0, 1.0], 1)
    E = scipy.linalg.block_diag([[1.0]], N)
    A = scipy.linalg.block_diag([[-1.0]], np.eye(3))
    Q = scipy.stats.ortho_group.rvs(4, random_state=3)
    Z = scipy.stats.ortho_group.rvs(4, random_state=4)
    B = np.array([[1.0], [0.0], [0.0], [0.0]])
    C = np.array([[1.0, 1.0, 0.0, 1.0]])
    m = DescriptorModel(Q @ A @ Z, C @ Z, E=Q @ E @ Z, Bu=Q @ B)
    fm = m.to_fault_model()
    assert fm.n == 1
    assert rel_err(fm.freqresp(W)[:, 0, 0], 1 / (1j * W + 1)) < 1e-10


def test_aux_inputs_need_an_explicit_choice():
    m = DescriptorModel([[-1.0]], [[1.0]], Bu=[[1.0]], Baux=[[2.0]], aux=["m1"])
    assert m.aux == ("m1",) and m.b("aux").tolist() == [[2.0]]
    with pytest.raises(ModelError, match="auxiliary"):
        m.to_fault_model()
    assert m.to_fault_model(aux="drop").B.tolist() == [[1.0]]


def test_validation_messages():
    with pytest.raises(ModelError, match="singular"):
        DescriptorModel([[1.0, 1.0], [1.0, 1.0]], [[1.0, 0.0]], E=[[1.0, 1.0], [1.0, 1.0]])
    with pytest.raises(ModelError, match="singular"):
        DescriptorModel(np.zeros((2, 2)), [[1.0, 0.0]], E=np.zeros((2, 2)))
    with pytest.raises(ModelError, match="E"):
        DescriptorModel(np.eye(2), [[1.0, 0.0]], E=np.eye(3))
    with pytest.raises(ModelError, match="square"):
        DescriptorModel(np.ones((2, 3)), [[1.0, 0.0, 0.0]])
    with pytest.raises(ModelError, match="Bu"):
        DescriptorModel(np.eye(2), [[1.0, 0.0]], Bu=np.ones((3, 1)))
    with pytest.raises(ModelError, match="two groups"):
        DescriptorModel(np.eye(1), [[1.0]], Bu=[[1.0]], Bf=[[1.0]], controls=["a"], faults=["a"])
    with pytest.raises(ModelError, match="pole"):
        DescriptorModel([[-1.0]], [[1.0]], Bu=[[1.0]]).evaluate(-1.0)
    with pytest.raises(ModelError, match="FaultModel"):
        DescriptorModel.from_fault_model("not a model")


def test_staircase_poles_do_not_turn_infinite_eigenvalues_into_finite_ones():
    # finite −1, −2 and a size-3 Jordan block at infinity, scrambled by orthogonal transformations
    E = scipy.linalg.block_diag(np.eye(2), np.diag([1.0, 1.0], 1))
    A = scipy.linalg.block_diag(np.diag([-1.0, -2.0]), np.eye(3))
    Q = scipy.stats.ortho_group.rvs(5, random_state=5)
    Z = scipy.stats.ortho_group.rvs(5, random_state=6)
    m = DescriptorModel(Q @ A @ Z, np.ones((1, 5)), E=Q @ E @ Z)
    np.testing.assert_allclose(np.sort(m.poles().real), [-2.0, -1.0], atol=1e-10)
    assert np.max(np.abs(m.poles().imag)) < 1e-10
