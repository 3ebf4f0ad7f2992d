"""Beard–Jones detection filters (Douglas et al. 1996, App. B, Alg. B.1): spectrum, left eigenvectors,
decoupling through the internal form, projectors, infeasible specifications; restricted-diagonal bank."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fdikit import FaultModel
from fdikit.design.observers.beard_jones import beard_jones, restricted_diagonal
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.fault_maps import resolve_faults

W = np.logspace(-2, 3, 40)


def _random_system(seed, n, p, q, discrete=False):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    if discrete:
        A = 0.9 * A / np.max(np.abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((p, n))
    faults = {f"f{i}": rng.standard_normal((n, 1)) for i in range(q)}
    model = FaultModel(A=A, C=C, Bu=rng.standard_normal((n, 1)), Du=rng.standard_normal((p, 1)),
                       dt=0.1 if discrete else None)
    return model, faults


def _with_faults(model, faults):
    names = list(faults)
    return model.add_faults(names, np.hstack([faults[k] for k in names]), np.zeros((model.p, len(names))))


def _assert_decoupled(design, model, faults, w=W, rel=10 ** (-150 / 20)):
    """Fault j reaches residual group i only when i == j (R-FDF-3: below −150 dB relative)."""
    R = design.generator.internal_form(_with_faults(model, faults))
    G = np.abs(R.freqresp(w, "f"))  # (freq, residual, fault)
    iso = np.array(design.generator.isolates)
    peak = G.max()
    for j, f in enumerate(R.faults):
        own = G[:, iso == f, j]
        other = G[:, iso != f, j]
        assert own.max() > 1e-6 * peak, f"fault {f} invisible in its own residual"
        assert other.size == 0 or other.max() < rel * peak, f"fault {f} leaks: {other.max() / peak:.1e}"
    # the controls never reach the residuals: the cancellation is exact up to rounding of the two paths
    path = np.abs(model.freqresp(w, "u")).max() * design.generator.to_control().frequency_response(w).magnitude.max()
    assert np.abs(R.freqresp(w, "u")).max() < 1e-9 * max(path, peak, 1.0)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n=st.integers(4, 7), q=st.integers(1, 3), discrete=st.booleans())
def test_random_designs_assign_spectrum_and_decouple(seed, n, q, discrete):
    """R-FDF-1/2/3 on random observable systems with generic 1-D faults (T_i = Im f_i)."""
    p = q + 1
    model, faults = _random_system(seed, n, p, q, discrete)
    base = np.linspace(0.2, 0.8, n) if discrete else -np.linspace(1.0, 6.0, n)
    sets = {f"f{i}": [base[i]] for i in range(q)}
    d = beard_jones(model, faults, sets, base[q:])
    scale = np.abs(base).max()
    Acl = model.A - d.gain @ model.C  # gain is the observer gain (A − LC); the report's A + L_report C is the same
    np.testing.assert_array_equal(d.report_gain, -d.gain)
    # computed eigenvalues of A − LC: 1e-8 relative, or the Bauer–Fike bound κ(𝒱) eps ‖A − LC‖ when the
    # eigenvectors are ill-conditioned (the assignment itself is checked exactly below, by vᵀ(A − LC) = λ vᵀ)
    tol = max(1e-8 * scale, 10 * np.finfo(float).eps * np.linalg.norm(Acl, 2) * d.condition_number)
    np.testing.assert_allclose(np.sort_complex(d.poles), np.sort_complex(base.astype(complex)), atol=tol)
    for k, lam in enumerate(d.order):
        v = d.left_eigenvectors[:, k]
        assert np.linalg.norm(v @ Acl - lam * v) < 1e-8 * scale * np.linalg.norm(Acl)
    _assert_decoupled(d, model, faults, w=W if not discrete else np.linspace(0.01, np.pi / 0.1, 40))
    for H in d.projectors.values():
        np.testing.assert_allclose(H, H.T, atol=1e-12)
        np.testing.assert_allclose(H @ H, H, atol=1e-10)
        assert np.trace(H) == pytest.approx(p - (q - 1), abs=1e-9)


def test_two_dimensional_sensor_faults_and_complex_pairs():
    rng = np.random.default_rng(4)
    n = 6
    model = FaultModel(A=rng.standard_normal((n, n)), C=rng.standard_normal((n, n)), Bu=rng.standard_normal((n, 1)),
                       outputs=[f"y{i}" for i in range(n)])
    d = beard_jones(model, ["y0_sensor", "y3_sensor"], {"y0_sensor": [-2 + 1j, -2 - 1j], "y3_sensor": [-3, -4]},
                    complement_poles=[-1, -5])
    assert {k: T.shape[1] for k, T in d.detection_spaces.items()} == {"y0_sensor": 2, "y3_sensor": 2}
    np.testing.assert_allclose(np.sort_complex(d.poles), np.sort_complex(np.array([-5, -4, -3, -2 - 1j, -2 + 1j, -1])),
                               atol=1e-8)
    assert np.isrealobj(d.gain)
    R = d.generator.internal_form(model.with_sensor_faults(["y0", "y3"]))
    G = np.abs(R.freqresp(W, "f"))
    iso = np.array(d.generator.isolates)
    assert G[:, iso == "y3_sensor", 0].max() < 1e-9 * G.max()
    assert G[:, iso == "y0_sensor", 1].max() < 1e-9 * G.max()
    # a bias settles in the magnitude direction: the steady residual of y0's group equals the bias
    dc = np.linalg.norm(R.freqresp([0.0], "f")[0][iso == "y0_sensor", 0])
    assert dc > 0.1


def test_infeasible_specifications_raise_with_reasons():
    model, faults = _random_system(1, 4, 3, 2)
    with pytest.raises(DesignError, match="needs 1"):
        beard_jones(model, faults, {"f0": [-1, -2], "f1": [-3]}, [-4])
    with pytest.raises(DesignError, match="unstable"):
        beard_jones(model, faults, {"f0": [1.0], "f1": [-3]}, [-4, -5])
    with pytest.raises(DesignError, match="twice"):
        beard_jones(model, faults, {"f0": [-1.0], "f1": [-1.0]}, [-4, -5])
    with pytest.raises(DesignError, match="conjugate"):
        beard_jones(model, faults, {"f0": [-1.0], "f1": [-3]}, [-4 + 1j, -5])
    with pytest.raises(ParameterError, match="unknown fault"):
        beard_jones(model, faults, {"f0": [-1.0], "f1": [-3], "f9": [-2]}, [-4, -5])
    # not output separable: two faults with parallel output images
    same = {"a": faults["f0"], "b": 2 * faults["f0"] + 1e-3 * np.linalg.svd(model.C)[2][-1][:, None]}
    with pytest.raises(DesignError, match="not output separable"):
        beard_jones(model, same, {"a": [-1.0], "b": [-2.0]}, [-3, -4])
    # more detection-space dimensions than states
    rng = np.random.default_rng(0)
    many = {f"g{i}": rng.standard_normal((4, 1)) for i in range(5)}
    big = FaultModel(A=model.A, C=np.vstack([model.C, rng.standard_normal((3, 4))]))
    with pytest.raises(DesignError, match="dimensions"):
        beard_jones(big, many, {k: [-1.0 - i] for i, k in enumerate(many)}, [])
    with pytest.raises(ModelError, match="not a fault of the model"):
        resolve_faults(model, ["nope"])


def test_invariant_zero_must_be_in_the_fault_set():
    """f → y = (s + 3)/((s + 1)(s + 2)): the zero −3 is a fixed eigenvalue of the detection space T* = W* ⊕ V."""
    model = FaultModel(A=[[0.0, 1.0], [-2.0, -3.0]], C=[[1.0, 0.0]])
    f = {"f": np.array([[1.0], [0.0]])}
    with pytest.raises(DesignError, match="invariant zero -3"):
        beard_jones(model, f, {"f": [-5.0, -6.0]}, [])
    d = beard_jones(model, f, {"f": [-3.0, -5.0]}, [])
    assert d.detection_spaces["f"].shape[1] == 2
    np.testing.assert_allclose(np.sort(d.poles.real), [-5.0, -3.0], atol=1e-9)


def test_restricted_diagonal_bank_decouples_each_target():
    model, faults = _random_system(7, 5, 4, 3)
    rd = restricted_diagonal(model, faults, poles=-np.arange(1.0, 6.0))
    R = rd.generator.internal_form(_with_faults(model, faults))
    G = np.abs(R.freqresp(W, "f"))
    iso = np.array(rd.generator.isolates)
    for j, f in enumerate(R.faults):
        assert G[:, iso == f, j].max() > 1e-6 * G.max()
        assert G[:, iso != f, j].max() < 1e-9 * G.max()
    for target, d in rd.filters.items():
        np.testing.assert_allclose(np.sort(d.poles.real), -np.arange(5.0, 0.0, -1.0), atol=1e-8)
        assert rd.nuisance_spaces[target].shape[1] == 2
    with pytest.raises(DesignError, match="at least two"):
        restricted_diagonal(model, {"f0": faults["f0"]}, poles=-np.arange(1.0, 6.0))


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(3, 6))
def test_random_non_separable_sets_raise(seed, n):
    """More 1-D faults than outputs: their output images are dependent, so the design must refuse."""
    p = 2
    model, faults = _random_system(seed, n, p, p + 1)
    sets = {k: [-1.0 - i] for i, k in enumerate(faults)}
    with pytest.raises(DesignError, match="not output separable|dimensions"):
        beard_jones(model, faults, sets, -np.arange(10.0, 10.0 + n - len(faults)))
