"""segments: gaps split, means pooled, mismatched traces refused."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.errors import DataError
from fdikit.identify import segments
from fdikit.trace import Trace


def trace(n=20, dt=0.1, y=None, valid=None):
    u = np.arange(n, dtype=float)[:, None]
    return Trace(t=np.arange(n) * dt, u=u, y=2 * u if y is None else y, controls=["u"], outputs=["y"], valid=valid)


def test_nan_and_invalid_samples_split_and_the_means_are_pooled():
    y = 2 * np.arange(20.0)[:, None]
    y[5] = np.nan
    valid = np.ones(20, bool)
    valid[12] = False
    d = segments([trace(y=y, valid=valid), trace()], min_length=3)
    assert [len(s) for s in d.y] == [5, 6, 7, 20]
    kept_u = np.r_[0:5, 6:12, 13:20, 0:20].astype(float)
    np.testing.assert_allclose(d.u_mean, [kept_u.mean()])
    np.testing.assert_allclose(np.concatenate(d.u)[:, 0] + d.u_mean[0], kept_u)
    assert d.samples == 38 and d.dropped == 0


def test_refusals():
    with pytest.raises(DataError, match="sample time"):
        segments([trace(), trace(dt=0.2)])
    t = np.r_[0.0, 0.1, 0.3, 0.4]
    with pytest.raises(DataError, match="uniformly"):
        segments(Trace(t=t, u=np.zeros((4, 1)), y=np.zeros((4, 1)), controls=["u"], outputs=["y"]))
    with pytest.raises(DataError, match="no-such"):
        segments(trace(), outputs=["no-such"])
