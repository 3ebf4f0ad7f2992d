"""Kronecker structure of system pencils: equal to SLICOT AG08BD (slycot) and to hand-derived structures."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from fdikit import FaultModel
from fdikit.descriptor.model import DescriptorModel
from fdikit.descriptor.staircase import pencil_structure, split_infinite
from fdikit.descriptor.zeros import normal_rank, system_pencil, system_structure, system_zeros
from fdikit.errors import ParameterError

slycot = pytest.importorskip("slycot")


def same_points(a, b, tol):
    a, b = list(np.asarray(a, complex)), list(np.asarray(b, complex))
    if len(a) != len(b):
        return False
    for z in a:
        k = int(np.argmin([abs(z - w) for w in b]))
        if abs(z - b[k]) > tol:
            return False
        b.pop(k)
    return True


def ag08bd(m: DescriptorModel):
    n, k, p = m.n, m.B.shape[1], m.p
    Af, Ef, nrank, niz, infz, kronr, infe, kronl = slycot.ag08bd(n, n, k, p, m.A.copy(), m.E.copy(), m.B.copy(),
                                                                m.C.copy(), m.D.copy(), equil="N", tol=0.0)
    zeros = scipy.linalg.eigvals(Af, Ef) if Af.size else np.zeros(0)
    return zeros, nrank, niz, sorted(kronr.tolist()), sorted(kronl.tolist()), sorted(infe.tolist(), reverse=True)


def random_descriptor(seed, n, m, p, rank_e=None, d=False):
    rng = np.random.default_rng(seed)
    E = np.eye(n)
    if rank_e is not None:
        E = rng.standard_normal((n, rank_e)) @ rng.standard_normal((rank_e, n))
    return DescriptorModel(rng.standard_normal((n, n)), rng.standard_normal((p, n)), E=E,
                           Bu=rng.standard_normal((n, m)), Du=rng.standard_normal((p, m)) if d else None)


CASES = [  # (seed, n, m, p, rank E, D ≠ 0)
    (1, 4, 2, 2, None, False), (2, 5, 1, 3, None, False), (3, 5, 3, 1, None, False), (4, 6, 2, 2, None, True),
    (5, 5, 2, 2, 3, False), (6, 6, 1, 2, 4, True), (7, 4, 3, 2, 2, False), (8, 7, 2, 3, 5, False),
]


@pytest.mark.parametrize("case", CASES)
def test_structure_equals_slycot_ag08bd(case):
    seed, n, m, p, re, d = case
    model = random_descriptor(seed, n, m, p, re, d)
    mine = system_structure(model)
    zeros, nrank, niz, kronr, kronl, infe = ag08bd(model)
    assert mine.normal_rank == nrank
    assert mine.n_infinite_zeros == niz
    assert list(mine.right_indices) == kronr and list(mine.left_indices) == kronl
    assert list(mine.infinite_blocks) == infe
    scale = np.linalg.norm(system_pencil(model)[0])
    assert same_points(mine.finite_eigenvalues, zeros, 1e-8 * max(scale, 1.0))


def test_structure_of_structured_plants_equals_ag08bd():
    # G = [1/(s+1); 1/(s+2)]: one left index (the row [s+1, −(s+2)] annihilates G), no zeros, rank 1
    tall = DescriptorModel(np.diag([-1.0, -2.0]), np.eye(2), Bu=[[1.0], [1.0]])
    s = system_structure(tall)
    assert s.left_indices == (1,) and s.right_indices == () and s.finite_eigenvalues.size == 0
    assert normal_rank(tall) == 1
    _, nrank, _, kronr, kronl, _ = ag08bd(tall)
    assert (nrank, kronr, kronl) == (3, [], [1])
    # y = −u' (G = −s): a zero at 0, no poles
    der = DescriptorModel(np.eye(2), [[1.0, 0.0]], E=[[0.0, 1.0], [0.0, 0.0]], Bu=[[0.0], [1.0]])
    np.testing.assert_allclose(system_zeros(der), [0.0], atol=1e-14)
    zeros, nrank, niz, _, _, infe = ag08bd(der)
    s = system_structure(der)
    assert (s.normal_rank, s.n_infinite_zeros, list(s.infinite_blocks)) == (nrank, niz, infe)
    # (s + 3)/((s + 1)(s + 2)), and a decoupling zero at −2 when −2 is made uncontrollable
    fm = FaultModel([[0.0, 1.0], [-2.0, -3.0]], [[3.0, 1.0]], Bu=[[0.0], [1.0]])
    np.testing.assert_allclose(system_zeros(fm).real, [-3.0], atol=1e-12)
    dec = DescriptorModel(np.diag([-1.0, -2.0]), [[1.0, 1.0]], Bu=[[1.0], [0.0]])
    np.testing.assert_allclose(system_zeros(dec).real, [-2.0], atol=1e-12)


def test_groups_select_the_pencil_columns():
    m = DescriptorModel(np.diag([-1.0, -2.0]), np.eye(2), Bu=[[1.0], [0.0]], Bd=[[0.0], [1.0]])
    assert normal_rank(m) == 2 and normal_rank(m, "u") == 1 and normal_rank(m, ("u", "d")) == 2
    # the uncontrollable mode −2 is seen by y2: w = [0, 1, 0, λ + 2] annihilates the pencil from the left
    assert system_structure(m, "u").left_indices == (1,)
    only_u = DescriptorModel(m.A, m.C, Bu=m.b("u"))
    assert ag08bd(only_u)[4] == [1]
    with pytest.raises(ParameterError, match="groups"):
        system_pencil(m, ())


def test_canonical_blocks_by_hand():
    # L_0 ⊕ L_2 ⊕ L_1ᵀ ⊕ N_2 ⊕ (λ − 3), scrambled: right (0, 2), left (1,), infinite (2,), finite 3
    blocks_M = [np.zeros((0, 1)), np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), np.array([[0.0], [1.0]]),
                np.eye(2), np.array([[3.0]])]
    blocks_N = [np.zeros((0, 1)), np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[1.0], [0.0]]),
                np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[1.0]])]
    M, N = scipy.linalg.block_diag(*blocks_M), scipy.linalg.block_diag(*blocks_N)
    Q = scipy.stats.ortho_group.rvs(M.shape[0], random_state=1)
    Z = scipy.stats.ortho_group.rvs(M.shape[1], random_state=2)
    s = pencil_structure(Q @ M @ Z, Q @ N @ Z)
    assert s.right_indices == (0, 2) and s.left_indices == (1,) and s.infinite_blocks == (2,)
    assert s.infinite_zeros == (1,) and s.normal_rank == 6 and s.shape == (7, 8) and not s.is_regular
    np.testing.assert_allclose(s.finite_eigenvalues, [3.0], atol=1e-12)


def test_split_infinite_puts_the_infinite_part_first():
    E = scipy.linalg.block_diag(np.eye(2), np.diag([1.0, 1.0], 1))
    A = scipy.linalg.block_diag(np.diag([-1.0, -2.0]), np.eye(3))
    Q0 = scipy.stats.ortho_group.rvs(5, random_state=7)
    Z0 = scipy.stats.ortho_group.rvs(5, random_state=8)
    A, E = Q0 @ A @ Z0, Q0 @ E @ Z0
    Q, Z, k = split_infinite(A, E)
    At, Et = Q.T @ A @ Z, Q.T @ E @ Z
    assert k == 3
    assert np.max(np.abs(At[k:, :k])) < 1e-12 and np.max(np.abs(Et[k:, :k])) < 1e-12
    np.testing.assert_allclose(np.sort(scipy.linalg.eigvals(At[k:, k:], Et[k:, k:]).real), [-2.0, -1.0], atol=1e-12)
    assert np.linalg.matrix_rank(At[:k, :k]) == 3
    with pytest.raises(ParameterError, match="square"):
        split_infinite(np.ones((2, 3)), np.ones((2, 3)))
    with pytest.raises(ParameterError, match="tol"):
        pencil_structure(A, E, tol=2.0)
