"""fdigenspec / fdichkspec against the reference's tests (FaultDetectionTools.jl test_fdigenspec.jl)."""

import numpy as np
import pytest
from varga_examples import YUAN_STRONG, YUAN_WEAK, example_5_4, random_plant, yuan

from fdikit.design.nullspace import fdichkspec, fdigenspec


def codes(S):
    return sorted(int("".join(str(int(v)) for v in row), 2) for row in S)


def test_yuan_weak_and_strong_specifications():
    m = yuan()
    weak = fdigenspec(m, fdtol=1e-5)
    assert weak.shape == (18, 8) and codes(weak) == codes(YUAN_WEAK)
    strong = fdigenspec(m, fdtol=1e-5, fdgaintol=1e-3, fdfreq=[0.0, 1.0])
    assert strong.shape == (12, 8) and codes(strong) == codes(YUAN_STRONG)
    check = fdichkspec(m, YUAN_WEAK, fdtol=1e-5, fdgaintol=1e-3, fdfreq=[0.0, 1.0], minimal=True)
    assert codes(YUAN_WEAK[check.feasible]) == codes(YUAN_STRONG)
    weak_check = fdichkspec(m, YUAN_WEAK, fdtol=1e-5, minimal=True)
    assert weak_check.feasible.all() and (weak_check.orders <= m.n).all() and (weak_check.leastorders <= m.n).all()


def test_all_rows_checked_equal_generated():
    m = yuan()
    every = np.array([[c >> (7 - j) & 1 for j in range(8)] for c in range(1, 256)], dtype=bool)
    check = fdichkspec(m, every, fdtol=1e-5)
    assert codes(every[check.feasible]) == codes(YUAN_WEAK)
    assert (check.orders[~check.feasible] == -1).all() and (check.leastorders == -1).all()


def test_example_5_4():
    m = example_5_4()
    assert fdigenspec(m).tolist() == [[True, True]]
    assert fdigenspec(m, fdgaintol=1e-3, fdfreq=[0.0, 1.0]).tolist() == [[True, True]]
    check = fdichkspec(m, [[0, 1], [1, 0], [1, 1]], minimal=True)
    assert check.rdims.tolist() == [0, 0, 1]
    assert check.orders.tolist() == [-1, -1, 1] and check.leastorders.tolist() == [-1, -1, 1]


@pytest.mark.parametrize("seed", [1, 2])
def test_random_plant_without_controls(seed):
    # reference: p = 4, mf = 4, n = 2: 15 rows, weak == strong, orders == n, least orders ≤ n
    m = random_plant(seed, 2, 4, 0, 0, 4)
    weak = fdigenspec(m, fdtol=1e-5)
    assert weak.shape == (15, 4)
    assert codes(fdigenspec(m, fdtol=1e-5, fdgaintol=1e-3, fdfreq=[0.0, 1.0])) == codes(weak)
    check = fdichkspec(m, weak, fdtol=1e-5, minimal=True)
    assert (check.rdims > 0).all() and (check.orders == 2).all() and (check.leastorders <= 2).all()
