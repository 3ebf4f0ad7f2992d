"""Non-dynamic mode removal and minimal realisations: orders of hand-built models with known redundant modes."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.stats

from fdikit.descriptor.model import DescriptorModel
from fdikit.descriptor.reduction import minimal_realization, nondynamic_count, remove_nondynamic

W = np.logspace(-2, 1.5, 30)


def rel_err(G1, G2):
    return float(np.max(np.abs(G1 - G2)) / np.max(np.abs(G2)))


def scrambled(E, A, B, C, D=None, seed=0):
    n = A.shape[0]
    Q = scipy.stats.ortho_group.rvs(n, random_state=seed)
    Z = scipy.stats.ortho_group.rvs(n, random_state=seed + 1)
    return DescriptorModel(Q @ A @ Z, C @ Z, E=Q @ E @ Z, Bu=Q @ B, Du=D)


def test_nondynamic_modes_are_eliminated_and_E_kept_general():
    # finite −1 (dynamic), two non-dynamic modes (A₂₂ invertible), one Jordan block of size 2 at infinity
    E = scipy.linalg.block_diag([[2.0]], np.zeros((2, 2)), [[0.0, 1.0], [0.0, 0.0]])
    A = scipy.linalg.block_diag([[-2.0]], [[1.0, 2.0], [0.0, 3.0]], np.eye(2))
    A[0, 1], A[1, 0] = 1.0, 1.0
    B = np.array([[1.0], [1.0], [0.0], [0.0], [1.0]])
    C = np.array([[1.0, 1.0, 1.0, 1.0, 0.0]])
    m = scrambled(E, A, B, C, seed=10)
    assert nondynamic_count(m) == 2
    r = remove_nondynamic(m)
    assert r.n == 3 and np.linalg.matrix_rank(r.E) == 2 and nondynamic_count(r) == 0
    assert rel_err(r.freqresp(W), m.freqresp(W)) < 1e-10
    assert remove_nondynamic(r) is r


def test_minimal_realization_of_a_proper_model_removes_the_known_modes():
    # −1 controllable and observable, −2 uncontrollable, −3 unobservable, plus a non-dynamic mode
    E = np.diag([1.0, 1.0, 1.0, 0.0])
    A = np.diag([-1.0, -2.0, -3.0, 1.0])
    B = np.array([[1.0], [0.0], [1.0], [1.0]])
    C = np.array([[1.0, 1.0, 0.0, 2.0]])
    m = scrambled(E, A, B, C, seed=20)
    r = minimal_realization(m)
    assert r.n == 1
    np.testing.assert_allclose(r.poles().real, [-1.0], atol=1e-10)
    G = 1 / (1j * W + 1) - 2.0   # the non-dynamic mode gives the feedthrough −C₄B₄/A₄₄ = −2
    assert rel_err(r.freqresp(W)[:, 0, 0], G) < 1e-10
    assert rel_err(m.freqresp(W)[:, 0, 0], G) < 1e-10


def test_minimal_realization_of_an_improper_model_keeps_the_polynomial_part():
    # G(s) = 1/(s + 1) − s² : finite −1 and a size-3 Jordan block at infinity (C N² B = 1), plus an
    # uncontrollable size-2 infinite block and an unobservable finite mode −4
    N3 = np.diag([1.0, 1.0], 1)
    N2 = np.diag([1.0], 1)
    E = scipy.linalg.block_diag([[1.0]], N3, N2, [[1.0]])
    A = scipy.linalg.block_diag([[-1.0]], np.eye(3), np.eye(2), [[-4.0]])
    B = np.array([[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]]).T
    C = np.array([[1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0]])
    m = scrambled(E, A, B, C, seed=30)
    s = 1j * W
    G = 1 / (s + 1) - s ** 2
    assert rel_err(m.freqresp(W)[:, 0, 0], G) < 1e-10
    r = minimal_realization(m)
    assert r.n == 4 and np.linalg.matrix_rank(r.E) == 3 and nondynamic_count(r) == 0
    np.testing.assert_allclose(r.poles().real, [-1.0], atol=1e-10)
    assert rel_err(r.freqresp(W)[:, 0, 0], G) < 1e-9


def test_minimal_realization_of_a_purely_polynomial_model():
    # G(s) = −s (y = −u') with a redundant uncontrollable finite mode: order 2, E singular
    E = scipy.linalg.block_diag([[0.0, 1.0], [0.0, 0.0]], [[1.0]])
    A = scipy.linalg.block_diag(np.eye(2), [[-5.0]])
    m = scrambled(E, A, np.array([[0.0], [1.0], [0.0]]), np.array([[1.0, 0.0, 1.0]]), seed=40)
    r = minimal_realization(m)
    assert r.n == 2 and r.poles().size == 0
    assert rel_err(r.freqresp(W)[:, 0, 0], -1j * W) < 1e-10
