"""Example 3.1 / Table 3.1 (Hallouzi 2008, §3.3.1): parameter-basis conditioning and the
degree of observability of model pairs."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.studies.hallouzi2008.example_3_1 import PAIRS, example_3_1, example_3_1_models

# Table 3.1 as printed: rows = model sets, columns {1,2}, {1,3}, {2,3}, {1,4}, {2,4}, {3,4}
TABLE_3_1 = np.array([
    [37, 6.31e3, 125, 85.2, 128, 85.8], [5.58, 226, 5.53, 8.75, 12.9, 8.49], [10.5, 6.29e3, 27.5, 22.6, 33.8, 21.7],
    [110, 9.45e3, 87.4, 178, 264, 126], [291, 440, 128, 321, 468, 154], [23.4, 424, 22.4, 37.8, 56.3, 35],
    [48.7, 1.41e4, 61.7, 77.3, 116, 89.5], [278, 1.17e3, 178, 464, 695, 234], [45.9, 809, 44.1, 72.2, 108, 75],
    [29.2, 234, 24.6, 48.3, 72.2, 35.9], [30.1, 2.71e3, 31, 50.5, 75.6, 48.4], [24.2, 477, 23.4, 40.1, 60.1, 36.3],
    [42.8, 4.75e3, 105, 640, 666, 353], [367, 4.25e3, 73.2, 564, 662, 74.8], [53.1, 3.01e3, 64, 94, 141, 90.7],
])


@pytest.fixture(scope="module")
def table():
    """45 random sets from three seeds (the patterns are statistical: seeds 0–5 give 73–100 % each)."""
    parts = [example_3_1(model_sets=15, seed=s) for s in (1, 2, 3)]
    return type(parts[0])(np.vstack([p.observability for p in parts]), np.vstack([p.basis for p in parts]))


def test_models_follow_3_12_and_3_13():
    models = example_3_1_models(np.random.default_rng(0))
    (A1, B1), (A2, B2), (A3, B3), (A4, B4) = models
    np.testing.assert_allclose(A3, A1 * [[1.05, 0.95], [0.95, 1.05]])
    np.testing.assert_allclose(B3, B1 * [1.05, 0.95])
    np.testing.assert_allclose(A4, 0.4 * A1 + 0.6 * A2)
    np.testing.assert_allclose(B4, 0.4 * B1 + 0.6 * B2)
    assert max(np.abs(np.linalg.eigvals(A1)).max(), np.abs(np.linalg.eigvals(A2)).max()) < 1
    assert PAIRS[1] == (0, 2) and PAIRS[4] == (1, 3)


def test_table_3_1_patterns(table):
    """The orderings of Table 3.1: best pair {1,2} or {2,3} (thesis 15/15), worst {1,3} (14/15), {2,4} above
    {1,4} (15/15) and above {3,4} (15/15).  Measured over 45 sets: 98 %, 89 %, 100 %, 93 %; basis and
    observability conditioning agree on the worst pair in 89 %, rank correlation 0.68."""
    t = TABLE_3_1
    printed = {"min_at_12_or_23": np.isin(t.argmin(1), [0, 2]).mean(), "max_at_13": (t.argmax(1) == 1).mean(),
               "24_above_14": (t[:, 4] > t[:, 3]).mean(), "24_above_34": (t[:, 4] > t[:, 5]).mean()}
    f = table.frequency()
    for key, value in printed.items():
        assert f[key] >= value - 0.15, (key, f[key], value)
    assert f["same_worst_pair"] >= 0.8 and f["rank_correlation"] > 0.5


def test_separation_ratio_is_the_printed_1_5(table):
    """cond{2,4}/cond{1,4} = 0.6/0.4 = 1.5: the thesis's rows give 1.50 (median of 15), ours 1.48 (45 sets)."""
    printed = np.median(TABLE_3_1[:, 4] / TABLE_3_1[:, 3])
    ours = np.median(table.observability[:, 4] / table.observability[:, 3])
    assert printed == pytest.approx(1.5, abs=0.01)
    assert ours == pytest.approx(printed, abs=0.04)


def test_bad_input():
    with pytest.raises(ParameterError, match="b_scale"):
        example_3_1(model_sets=1, b_scale=0.0)
