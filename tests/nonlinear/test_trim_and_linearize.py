"""trim_and_linearize: the linear model and its operating point in one call."""

from __future__ import annotations

import numpy as np
import pytest

from fdikit.errors import DesignError
from fdikit.nonlinear import linearization, trim_and_linearize
from fdikit.residuals import ResidualGenerator
from fdikit.simulate import NonlinearPlant
from fdikit.trace import Trace

# two tanks in series: h1' = (q − a1 √h1) / A1, h2' = (a1 √h1 − a2 √h2) / A2, the levels measured
A1, A2, a1, a2 = 1.0, 2.0, 0.5, 0.4
TANKS = NonlinearPlant(
    f=lambda t, x, u: np.array([(u[0] - a1 * np.sqrt(x[0])) / A1, (a1 * np.sqrt(x[0]) - a2 * np.sqrt(x[1])) / A2]),
    h=lambda t, x, u: np.array([x[0], x[1]]), states=("h1", "h2"), outputs=("level1", "level2"),
    controls=("inflow",), x0=np.array([1.0, 1.0]),
)


def test_operating_point_is_the_trim_and_the_model_its_linearisation():
    lin = trim_and_linearize(TANKS, x0=[1.0, 1.0], u0=[0.3], y0={"level2": 2.25})
    # equilibrium with h2 = 2.25: q = a2 √h2 = 0.6, h1 = (q / a1)² = 1.44
    op = lin.model.operating_point
    assert op.u0["inflow"] == pytest.approx(0.6, rel=1e-8)
    assert op.x0["h1"] == pytest.approx(1.44, rel=1e-8) and op.y0["level2"] == pytest.approx(2.25, rel=1e-8)
    assert lin.trim.success and np.array_equal(lin.x, lin.trim.x)
    ref = linearization(TANKS, lin.trim.x, lin.trim.u)
    np.testing.assert_array_equal(lin.model.A, ref.model.A)
    # ∂f1/∂h1 = −a1 / (2 A1 √h1) at h1 = 1.44: −0.5 / 2.4
    assert lin.model.A[0, 0] == pytest.approx(-0.5 / 2.4, rel=1e-6)


def test_a_generator_with_the_operating_point_reads_absolute_signals():
    lin = trim_and_linearize(TANKS, x0=[1.0, 1.0], u0=[0.3], y0={"level2": 2.25})
    m = lin.model.discretize(0.1)
    L = 0.5 * np.eye(2)   # observer r = y − C ẑ, ẑ+ = (A − L C) ẑ + B u + L y
    A_f = m.A - L @ m.C
    g = ResidualGenerator(A_f, np.hstack([m.Bu, L]), -m.C, np.hstack([np.zeros((2, 1)), np.eye(2)]),
                          m.controls, m.outputs, ("r1", "r2"), dt=0.1, operating_point=m.operating_point)
    N = 400
    op = m.operating_point
    u = np.full((N, 1), op.u0["inflow"])
    y = np.tile(op.output_values(m.outputs), (N, 1))
    r = g.run(Trace(np.arange(N) * 0.1, u, y, m.controls, m.outputs)).r
    # the absolute trim signals are zero deviations: the residual is zero to the rounding of u0, y0 (≈ 2.25)
    assert np.max(np.abs(r)) < 1e-12 * 2.25 * N


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # √ of a negative level on the way
def test_a_failed_trim_is_reported():
    with pytest.raises(DesignError):
        trim_and_linearize(TANKS, x0=[1.0, 1.0], u0=[0.3], y0={"level2": -1.0}, max_iterations=50)
