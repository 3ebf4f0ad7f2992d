"""Model reduction (fdikit.nonlinear.reduce): Douglas et al. 1996, Ch. 2 §2.3, Table 2.1.

Oracles are independent: constructed Kalman-form models whose removed modes are known by construction, the
frequency response of the full model, python-control's ``hsvd``/``balred`` (slycot ab09ad) and ``linfnorm``
(slycot ab13dd).
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel
from fdikit.nonlinear.reduce import balanced_truncation, minimal, residualize
from fdikit.plants import path_vehicle_14

OMEGA = np.logspace(-2, 3, 200)


def rel_err(G, H):
    return np.max(np.abs(G - H)) / np.max(np.abs(G))


def grouped(A, B, C, D):
    """A FaultModel with the columns of B split over the four groups (names kept)."""
    k = B.shape[1]
    cuts = np.array_split(np.arange(k), 4)
    kw = {}
    for g, cols, word in zip("udfw", cuts, ("controls", "disturbances", "faults", "noise"), strict=True):
        kw[f"B{g}"], kw[f"D{g}"], kw[word] = B[:, cols], D[:, cols], [f"{g}_in{j}" for j in cols]
    return FaultModel(A=A, C=C, outputs=[f"out{i}" for i in range(C.shape[0])], **kw)


def kalman_form_model():
    """Kalman form: co modes {-1, -2±3j, -4}, uncontrollable {-5, -11}, controllable-unobservable {-7, -0.5},
    rotated by a random orthogonal similarity; inputs spread over all four groups."""
    rng = np.random.default_rng(4)
    co = scipy.linalg.block_diag([[-1.0]], [[-4.0]], [[-2.0, 3.0], [-3.0, -2.0]])
    upper = np.triu(rng.normal(size=(4, 4)), 1)
    upper[2, 3] = 0.0  # keep the 2 x 2 block's eigenvalues -2 ± 3j
    co += upper
    cu = np.array([[-7.0, 1.0], [0.0, -0.5]])   # controllable, unobservable
    unc = np.array([[-5.0, 2.0], [0.0, -11.0]])  # uncontrollable (observable or not)
    n = 8
    A = np.zeros((n, n))
    A[:4, :4], A[4:6, 4:6], A[6:, 6:] = co, cu, unc
    A[:4, 6:] = rng.normal(size=(4, 2))   # uncontrollable states drive the others
    A[4:6, :4] = rng.normal(size=(2, 4))  # co states drive the unobservable ones
    A[4:6, 6:] = rng.normal(size=(2, 2))
    B = np.zeros((n, 5))
    B[:6] = rng.normal(size=(6, 5))
    C = np.zeros((3, n))
    C[:, :4] = rng.normal(size=(3, 4))
    C[:, 6:] = rng.normal(size=(3, 2))
    D = rng.normal(size=(3, 5))
    Q = scipy.stats.ortho_group.rvs(n, random_state=7)
    return grouped(Q.T @ A @ Q, Q.T @ B, C @ Q, D), np.sort_complex(scipy.linalg.eigvals(co))


@pytest.fixture
def kalman_form():
    return kalman_form_model()


def test_minimal_removes_exactly_the_constructed_modes(kalman_form):
    model, co_eig = kalman_form
    res = minimal(model)
    assert res.model.n == 4
    np.testing.assert_allclose(co_eig, np.sort_complex([-4.0, -2 - 3j, -2 + 3j, -1.0]), rtol=1e-12)
    np.testing.assert_allclose(np.sort_complex(res.model.poles()), co_eig, rtol=1e-9)
    np.testing.assert_allclose(res.uncontrollable, [-11.0, -5.0], rtol=1e-9)
    np.testing.assert_allclose(res.unobservable, [-7.0, -0.5], rtol=1e-9)
    assert rel_err(res.model.freqresp(OMEGA), model.freqresp(OMEGA)) < 1e-9
    np.testing.assert_allclose(res.basis.T @ res.basis, np.eye(4), atol=1e-12)
    assert res.model.outputs == model.outputs and res.model.inputs == model.inputs
    assert res.model.states == ("z0", "z1", "z2", "z3")


def test_minimal_counts_every_input_group():
    # the second state is reached only from the noise input: it must be kept
    m = FaultModel(A=[[-1.0, 0.0], [0.0, -2.0]], C=[[1.0, 1.0]], Bu=[[1.0], [0.0]], Bw=[[0.0], [1.0]])
    assert minimal(m).model.n == 2
    assert minimal(m.submodel(inputs=m.controls)).model.n == 1


def test_minimal_agrees_with_python_control(kalman_form):
    model, _ = kalman_form
    ref = control.minreal(model.to_control(), verbose=False)
    assert ref.nstates == minimal(model).model.n


def test_minimal_discrete_and_already_minimal():
    m = path_vehicle_14()
    res = minimal(m)
    assert res.model.n == 14 and res.removed.size == 0
    md = m.discretize(0.01)
    resd = minimal(md)
    assert resd.model.dt == 0.01
    assert rel_err(resd.model.freqresp(OMEGA[:150]), md.freqresp(OMEGA[:150])) < 1e-9


def fast_slow_model(seed=1):
    """Stable 6-state model with slow modes {-0.5, -1±2j} and fast modes {-80, -120±10j}, non-normal, coupled."""
    rng = np.random.default_rng(seed)
    J = scipy.linalg.block_diag([[-0.5]], [[-1.0, 2.0], [-2.0, -1.0]], [[-80.0]], [[-120.0, 10.0], [-10.0, -120.0]])
    T = rng.normal(size=(6, 6)) + 3 * np.eye(6)
    A = T @ J @ np.linalg.inv(T)
    return grouped(A, rng.normal(size=(6, 4)), rng.normal(size=(3, 6)), rng.normal(size=(3, 4)))


@pytest.mark.parametrize("how", [{"keep": 3}, {"cut": 10.0}])
def test_residualize_modal_keeps_dc_gain_and_slow_eigenvalues(how):
    m = fast_slow_model()
    res = residualize(m, **how)
    assert res.model.n == 3
    G0, Gr0 = m.freqresp([0.0])[0], res.model.freqresp([0.0])[0]
    assert np.max(np.abs(G0 - Gr0)) / np.max(np.abs(G0)) < 1e-10
    slow = np.sort_complex([-0.5, -1 + 2j, -1 - 2j])
    np.testing.assert_allclose(np.sort_complex(res.model.poles()), slow, rtol=1e-9)
    np.testing.assert_allclose(res.kept, slow, rtol=1e-9)
    np.testing.assert_allclose(res.removed, np.sort_complex([-120 - 10j, -120 + 10j, -80]), rtol=1e-9)
    assert res.model.inputs == m.inputs and res.model.states == ("z0", "z1", "z2")
    # at low frequency the residualised model is close (fast modes ≫ 1 rad/s)
    w = np.logspace(-2, 0, 20)
    assert rel_err(res.model.freqresp(w), m.freqresp(w)) < 0.05


def test_residualize_physical_states_is_the_report_formula():
    m = fast_slow_model(2).replace(states=[f"s{i}" for i in range(6)])
    res = residualize(m, keep=["s0", "s2", "s5"])
    A, B, C, D = m.A, m.B, m.C, m.D
    k, f = [0, 2, 5], [1, 3, 4]
    X = np.linalg.inv(A[np.ix_(f, f)])
    np.testing.assert_allclose(res.model.A, A[np.ix_(k, k)] - A[np.ix_(k, f)] @ X @ A[np.ix_(f, k)], rtol=1e-12)
    np.testing.assert_allclose(res.model.B, B[k] - A[np.ix_(k, f)] @ X @ B[f], rtol=1e-12)
    np.testing.assert_allclose(res.model.C, C[:, k] - C[:, f] @ X @ A[np.ix_(f, k)], rtol=1e-12)
    np.testing.assert_allclose(res.model.D, D - C[:, f] @ X @ B[f], rtol=1e-12)
    assert res.model.states == ("s0", "s2", "s5")
    G0 = m.freqresp([0.0])[0]
    assert np.max(np.abs(G0 - res.model.freqresp([0.0])[0])) / np.max(np.abs(G0)) < 1e-10


def test_residualize_discrete_keeps_gain_at_one():
    md = fast_slow_model().discretize(0.005)
    res = residualize(md, keep=3)
    G1, Gr1 = md.freqresp([0.0])[0], res.model.freqresp([0.0])[0]
    assert np.max(np.abs(G1 - Gr1)) / np.max(np.abs(G1)) < 1e-10
    slow = np.exp(0.005 * np.array([-0.5, -1 + 2j, -1 - 2j]))
    np.testing.assert_allclose(np.sort_complex(res.model.poles()), np.sort_complex(slow), rtol=1e-9)


def test_residualize_bad_input():
    m = fast_slow_model()
    with pytest.raises(ParameterError, match="exactly one"):
        residualize(m)
    with pytest.raises(ParameterError, match="exactly one"):
        residualize(m, 2, cut=1.0)
    with pytest.raises(ParameterError, match="at most"):
        residualize(m, 7)
    with pytest.raises(DesignError, match="complex pair"):
        residualize(m, 2)  # cuts the pair -1 ± 2j
    with pytest.raises(ModelError, match="no state named"):
        residualize(m, ["nope"])
    integrator = FaultModel(A=[[-1.0, 0.0], [0.0, 0.0]], C=[[1.0, 1.0]], Bu=[[1.0], [1.0]], states=["a", "b"])
    with pytest.raises(DesignError, match="eigenvalue at 0"):
        residualize(integrator, ["a"])
    with pytest.raises(ModelError, match="FaultModel"):
        residualize(m.to_control(), 3)
    with pytest.raises(ParameterError, match="sequence of state names"):
        residualize(m, 1.5)
    with pytest.raises(ParameterError, match="positive integer"):
        residualize(m, 0)
    with pytest.raises(DesignError, match="no state"):
        residualize(m, cut=0.1)  # keeps no mode


def test_minimal_of_a_model_without_a_minimal_state():
    with pytest.raises(DesignError, match="no state"):
        minimal(FaultModel(A=[[-1.0]], C=[[1.0]], Bu=[[0.0]]))
    with pytest.raises(ParameterError, match="rtol"):
        minimal(fast_slow_model(), rtol=0.0)


@pytest.mark.parametrize("order", [2, 3, 4])
def test_balanced_truncation_error_bound_and_python_control(order):
    m = fast_slow_model(3)
    res = balanced_truncation(m, order)
    sysr = res.model.to_control()
    full = m.to_control()
    np.testing.assert_allclose(res.hankel, control.hsvd(full), rtol=1e-8)
    assert res.error_bound == pytest.approx(2 * res.hankel[order:].sum(), rel=1e-14)
    err_grid = max(np.linalg.norm(Gk, 2) for Gk in m.freqresp(np.logspace(-3, 4, 2000)) - res.model.freqresp(
        np.logspace(-3, 4, 2000)))
    err_inf = control.linfnorm(full - sysr)[0]
    assert err_grid <= err_inf * (1 + 1e-6)
    assert err_inf <= res.error_bound * (1 + 1e-9)
    assert err_inf >= res.hankel[order] * (1 - 1e-6)  # lower bound σ_{r+1}
    ref = control.balred(full, order)
    ref_model = FaultModel.from_control(ref)  # its inputs are labelled u[i]; the column order is the same
    assert rel_err(res.model.freqresp(OMEGA), ref_model.freqresp(OMEGA)) < 1e-6
    assert res.model.inputs == m.inputs and res.model.outputs == m.outputs
    np.testing.assert_allclose(res.left @ res.right, np.eye(order), atol=1e-9)


def test_balanced_truncation_tol_and_path_vehicle():
    m = path_vehicle_14()
    res = balanced_truncation(m, tol=0.05 * 2 * control.hsvd(m.to_control()).sum())
    assert res.error_bound <= 0.05 * 2 * res.hankel.sum()
    # the next smaller order would exceed the tolerance
    assert 2 * res.hankel[res.model.n - 1:].sum() > 0.05 * 2 * res.hankel.sum()
    err_inf = control.linfnorm(m.to_control() - res.model.to_control())[0]
    assert err_inf <= res.error_bound * (1 + 1e-9)


def test_balanced_truncation_discrete_bound():
    md = fast_slow_model(3).discretize(0.01)
    res = balanced_truncation(md, 3)
    err_inf = control.linfnorm(md.to_control() - res.model.to_control())[0]
    assert res.hankel[3] * (1 - 1e-6) <= err_inf <= res.error_bound * (1 + 1e-9)


def test_balanced_truncation_refuses_unstable_and_bad_orders(kalman_form):
    unstable = FaultModel(A=[[0.1, 0.0], [0.0, -1.0]], C=[[1.0, 1.0]], Bu=[[1.0], [1.0]])
    with pytest.raises(DesignError, match="stable model; eigenvalue 0.1"):
        balanced_truncation(unstable, 1)
    with pytest.raises(DesignError, match="stable model"):
        balanced_truncation(FaultModel(A=[[0.0]], C=[[1.0]], Bu=[[1.0]]), 1)
    with pytest.raises(ParameterError, match="exactly one"):
        balanced_truncation(fast_slow_model(), 2, tol=0.1)
    model, _ = kalman_form
    with pytest.raises(ParameterError, match="nonzero Hankel"):
        balanced_truncation(model, 6)
    assert balanced_truncation(model, 4).model.n == 4
