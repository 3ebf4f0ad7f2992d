"""validate.as_covariance judges symmetry and definiteness relative to the covariance's own scale."""

import numpy as np
import pytest

from fdikit import validate
from fdikit.errors import ParameterError


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1.0, 1e6])
def test_asymmetry_is_judged_relative_to_the_entries(scale):
    M = scale * np.array([[1.0, 0.5], [0.5, 1.0]])
    np.testing.assert_array_equal(validate.as_covariance("R", M, 2), M)
    skew = M.copy()
    skew[0, 1] += 1e-6 * scale  # 1e-6 relative: far above rounding, far below the entries
    with pytest.raises(ParameterError, match="symmetric"):
        validate.as_covariance("R", skew, 2)


@pytest.mark.parametrize("scale", [1e-12, 1.0, 1e6])
def test_a_negative_eigenvalue_is_judged_relative_to_the_entries(scale):
    M = scale * np.diag([1.0, -1e-6])
    with pytest.raises(ParameterError, match="positive semidefinite"):
        validate.as_covariance("Q", M, 2)
    np.testing.assert_array_equal(validate.as_covariance("Q", scale * np.diag([1.0, 0.0]), 2),
                                  scale * np.diag([1.0, 0.0]))


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf, np.float64(np.nan), np.array(np.nan)])
def test_as_array_refuses_a_non_finite_scalar(value):
    # a 0-d array has no index columns for np.argwhere: the check must not depend on them
    with pytest.raises(ParameterError, match="x has a non-finite entry"):
        validate.as_array("x", value)
    assert validate.as_array("x", value, finite=False).shape == ()
