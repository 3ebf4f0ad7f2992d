"""Rate groups: call counts and order, timings against the budget."""

import pytest

from fdikit.errors import ParameterError
from fdikit.ftc.multirate import MultiRate


def test_groups_run_on_their_ticks_in_order():
    calls = []
    mr = MultiRate(0.01)
    mr.add("fast", 1, lambda k, t: calls.append(("fast", k, t)))
    mr.add("slow", 10, lambda k, t: calls.append(("slow", k, t)))
    mr.run(25)
    slow = [c for c in calls if c[0] == "slow"]
    assert [c[1] for c in slow] == [0, 10, 20]
    assert slow[1][2] == pytest.approx(0.1)
    assert calls[0][0] == "fast" and calls[1][0] == "slow"       # same tick: the order added
    timing = mr.timings()
    assert timing["fast"]["calls"] == 25 and timing["slow"]["calls"] == 3
    assert 0 <= timing["slow"]["budget_used"] < 1


def test_bad_groups_are_refused():
    mr = MultiRate(0.01)
    mr.add("a", 1, lambda k, t: None)
    with pytest.raises(ParameterError, match="exists"):
        mr.add("a", 2, lambda k, t: None)
    with pytest.raises(ParameterError, match="callable"):
        mr.add("b", 2, None)
