"""FaultModel: groups and names, fault channels, discretisation, python-control interop, validation.

Oracles: ``scipy.linalg.expm`` of the augmented matrix for the ZOH discretisation, python-control's
own evaluation of the transfer matrix for the frequency response, and plain slicing for submodels.
"""

from __future__ import annotations

import re

import control
import numpy as np
import pytest
import scipy.linalg

from fdikit import FaultModel, ModelError, ParameterError
from fdikit.model import GROUPS

N_STATES, N_OUT = 4, 3


def _random_model(seed: int = 0, dt: float | None = None) -> FaultModel:
    """4 states, 3 outputs, 2 controls, 1 disturbance, 1 fault, 2 noise inputs, every block random."""
    rng = np.random.default_rng(seed)
    n, p = N_STATES, N_OUT
    M = rng.standard_normal((n, n))
    if dt is None:
        A = M - (np.max(scipy.linalg.eigvals(M).real) + 0.5) * np.eye(n)
    else:
        A = 0.9 * M / np.max(np.abs(scipy.linalg.eigvals(M)))
    blocks = {}
    for g, k in zip(GROUPS, (2, 1, 1, 2)):
        blocks[f"B{g}"] = rng.standard_normal((n, k))
        blocks[f"D{g}"] = rng.standard_normal((p, k))
    return FaultModel(
        A=A,
        C=rng.standard_normal((p, n)),
        states=["px", "py", "vx", "vy"],
        outputs=["a", "b", "c"],
        controls=["throttle", "steer"],
        disturbances=["wind"],
        faults=["leak"],
        noise=["w1", "w2"],
        dt=dt,
        **blocks,
    )


def _same_names(m1: FaultModel, m2: FaultModel) -> None:
    assert m1.states == m2.states
    assert m1.outputs == m2.outputs
    for g in GROUPS:
        assert m1.inputs[g] == m2.inputs[g]


# ---------------------------------------------------------------------------------------------- groups


def test_group_blocks_and_names_follow_the_u_d_f_w_order():
    rng = np.random.default_rng(1)
    n, p = 3, 2
    Bu, Bd, Bf, Bw = (rng.standard_normal((n, k)) for k in (2, 1, 3, 1))
    Du, Dw = rng.standard_normal((p, 2)), rng.standard_normal((p, 1))
    m = FaultModel(A=-np.eye(n), C=rng.standard_normal((p, n)), Bu=Bu, Bd=Bd, Bf=Bf, Bw=Bw, Du=Du, Dw=Dw)
    assert m.n == 3 and m.p == 2 and not m.is_discrete
    np.testing.assert_array_equal(m.B, np.hstack([Bu, Bd, Bf, Bw]))
    np.testing.assert_array_equal(m.D, np.hstack([Du, np.zeros((p, 1)), np.zeros((p, 3)), Dw]))
    for g, Bg in zip(GROUPS, (Bu, Bd, Bf, Bw)):
        np.testing.assert_array_equal(m.b(g), Bg)
        np.testing.assert_array_equal(getattr(m, f"B{g}"), Bg)
    np.testing.assert_array_equal(m.Du, Du)
    np.testing.assert_array_equal(m.Dd, np.zeros((p, 1)))
    assert m.states == ("x0", "x1", "x2") and m.outputs == ("y0", "y1")
    assert m.controls == ("u0", "u1") and m.disturbances == ("d0",)
    assert m.faults == ("f0", "f1", "f2") and m.noise == ("w0",)
    assert m.index("f", ["f2", "f0"]) == [2, 0]
    assert m.index("outputs", "y1") == [1]


def test_group_from_names_only_gives_zero_blocks_and_d_only_group_counts_columns():
    m = FaultModel(A=[[-1.0, 0.0], [0.0, -2.0]], C=[[1.0, 1.0]], disturbances=["gust", "grade"], Df=[[1.0]])
    assert m.Bd.shape == (2, 2) and not m.Bd.any() and m.Dd.shape == (1, 2)
    assert m.faults == ("f0",) and m.Bf.shape == (2, 1) and not m.Bf.any()
    np.testing.assert_array_equal(m.Df, [[1.0]])


def test_matrices_are_read_only():
    m = _random_model()
    with pytest.raises(ValueError):
        m.A[0, 0] = 1.0
    with pytest.raises(ValueError):
        m.B[0, 0] = 1.0


# ---------------------------------------------------------------------------------------------- fault channels


def test_with_sensor_faults_adds_unit_columns_in_Df_and_zero_Bf():
    m = _random_model()
    ms = m.with_sensor_faults(["c", "a"])
    assert ms.faults == ("leak", "c_sensor", "a_sensor")
    np.testing.assert_array_equal(ms.Df[:, 0], m.Df[:, 0])
    np.testing.assert_array_equal(ms.Df[:, 1:], [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_array_equal(ms.Bf[:, 1:], np.zeros((N_STATES, 2)))
    np.testing.assert_array_equal(ms.Bf[:, 0], m.Bf[:, 0])
    # everything else untouched
    for g in ("u", "d", "w"):
        np.testing.assert_array_equal(ms.b(g), m.b(g))
        np.testing.assert_array_equal(ms.d(g), m.d(g))
    np.testing.assert_array_equal(ms.A, m.A)
    np.testing.assert_array_equal(ms.C, m.C)
    assert ms.states == m.states and ms.outputs == m.outputs


def test_with_actuator_faults_copies_control_columns():
    m = _random_model()
    ma = m.with_actuator_faults(["steer"])
    assert ma.faults == ("leak", "steer_actuator")
    np.testing.assert_array_equal(ma.Bf[:, 1], m.Bu[:, 1])
    np.testing.assert_array_equal(ma.Df[:, 1], m.Du[:, 1])
    both = m.with_sensor_faults(["b"]).with_actuator_faults(["throttle", "steer"])
    assert both.faults == ("leak", "b_sensor", "throttle_actuator", "steer_actuator")
    np.testing.assert_array_equal(both.Bf[:, 2:], m.Bu)
    np.testing.assert_array_equal(both.Df[:, 2:], m.Du)


def test_adding_the_same_sensor_fault_twice_is_a_duplicate_name():
    m = _random_model().with_sensor_faults(["a"])
    with pytest.raises(ModelError, match="a_sensor"):
        m.with_sensor_faults(["a"])


def test_unknown_names_in_fault_helpers_are_model_errors_listing_the_names():
    m = _random_model()
    with pytest.raises(ModelError, match=r"no output named 'speed'.*\['a', 'b', 'c'\]"):
        m.with_sensor_faults(["speed"])
    with pytest.raises(ModelError, match=r"'brake'.*\['throttle', 'steer'\]"):
        m.with_actuator_faults(["brake"])


# ---------------------------------------------------------------------------------------------- transformations


@pytest.mark.parametrize("dt", [0.01, 0.1, 0.7])
def test_discretize_equals_expm_of_augmented_matrix(dt):
    m = _random_model(seed=3)
    md = m.discretize(dt)
    n, k = m.n, m.B.shape[1]
    aug = np.zeros((n + k, n + k))
    aug[:n, :n], aug[:n, n:] = m.A, m.B
    E = scipy.linalg.expm(aug * dt)
    scale = np.linalg.norm(E)
    np.testing.assert_allclose(md.A, E[:n, :n], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(md.B, E[:n, n:], rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(md.C, m.C)
    np.testing.assert_array_equal(md.D, m.D)
    assert md.dt == dt and md.is_discrete
    _same_names(m, md)
    for g in GROUPS:  # every group's block is the matching slice of the augmented exponential
        sl = m._slice(g)
        np.testing.assert_allclose(md.b(g), E[:n, n:][:, sl], rtol=0, atol=1e-12 * scale)


def test_discretize_rejects_discrete_model_and_bad_dt():
    with pytest.raises(ModelError, match="already discrete"):
        _random_model(dt=0.1).discretize(0.1)
    for bad in (0.0, -0.1, np.inf, np.nan):
        with pytest.raises(ParameterError, match=r"dt .*must be a positive"):
            _random_model().discretize(bad)


def test_submodel_outputs_and_inputs():
    m = _random_model()
    s = m.submodel(outputs=["c", "a"])
    np.testing.assert_array_equal(s.C, m.C[[2, 0]])
    np.testing.assert_array_equal(s.D, m.D[[2, 0]])
    np.testing.assert_array_equal(s.B, m.B)
    assert s.outputs == ("c", "a") and s.inputs == m.inputs

    s = m.submodel(inputs=["w2", "steer", "leak"])
    assert s.controls == ("steer",) and s.disturbances == () and s.faults == ("leak",) and s.noise == ("w2",)
    cols = [1, 3, 5]  # steer, leak, w2 in the full [u d f w] order
    np.testing.assert_array_equal(s.B, m.B[:, cols])
    np.testing.assert_array_equal(s.D, m.D[:, cols])
    np.testing.assert_array_equal(s.C, m.C)
    assert s.outputs == m.outputs and s.states == m.states

    s = m.submodel(outputs=["b"], inputs=["wind"])
    np.testing.assert_array_equal(s.D, m.D[[1]][:, [2]])
    np.testing.assert_array_equal(s.Bd, m.Bd)
    assert s.dt == m.dt


def test_submodel_unknown_names():
    m = _random_model()
    with pytest.raises(ModelError, match=r"no output named 'z'"):
        m.submodel(outputs=["z"])
    with pytest.raises(ModelError, match=r"no input named \['nope'\]"):
        m.submodel(inputs=["steer", "nope"])


def test_replace_can_add_a_group_the_model_did_not_have():
    """``replace(Bw=..., noise=...)`` on a model without noise: the missing Dw must default to zeros.

    ``replace`` passes the old (p, 0) ``Dw`` along, and ``_matrix`` tries to reshape that empty array to (p, 2).
    """
    m = FaultModel(A=-np.eye(2), C=np.eye(2), Bu=np.ones((2, 1)))
    Bw = np.array([[1.0, 0.0], [0.5, 2.0]])
    mw = m.replace(Bw=Bw, noise=["w1", "w2"])
    np.testing.assert_array_equal(mw.Bw, Bw)
    np.testing.assert_array_equal(mw.Dw, np.zeros((2, 2)))
    assert mw.noise == ("w1", "w2")


def test_replace_unknown_argument():
    with pytest.raises(ModelError, match="unknown FaultModel argument"):
        _random_model().replace(Bx=np.zeros((4, 1)))


# ---------------------------------------------------------------------------------------------- frequency response


@pytest.mark.parametrize("dt", [None, 0.05])
def test_freqresp_matches_python_control(dt):
    m = _random_model(seed=5, dt=dt)
    sys = control.ss(m.A, m.B, m.C, m.D, 0 if dt is None else dt)
    omega = np.array([0.0, 0.03, 0.7, 4.0, 25.0])
    H = m.freqresp(omega)
    assert H.shape == (5, m.p, m.B.shape[1])
    for w, Hk in zip(omega, H):
        z = 1j * w if dt is None else np.exp(1j * w * dt)
        ref = np.asarray(sys(z))
        np.testing.assert_allclose(Hk, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    ref = np.asarray(sys.frequency_response(omega[1:]).complex)  # (p, k, len)
    np.testing.assert_allclose(H[1:], np.moveaxis(ref, -1, 0), rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    # one group = its columns of the full response
    np.testing.assert_array_equal(m.freqresp(omega, group="w"), H[:, :, m._slice("w")])
    with pytest.raises(ParameterError, match="unknown input group"):
        m.freqresp(omega, group="z")


# ---------------------------------------------------------------------------------------------- python-control interop


@pytest.mark.parametrize("dt", [None, 0.02])
def test_to_control_from_control_round_trip(dt):
    m = _random_model(seed=7, dt=dt)
    sys = m.to_control()
    assert isinstance(sys, control.StateSpace)
    assert list(sys.input_labels) == ["throttle", "steer", "wind", "leak", "w1", "w2"]
    assert list(sys.output_labels) == ["a", "b", "c"]
    assert list(sys.state_labels) == ["px", "py", "vx", "vy"]
    assert sys.dt == (0 if dt is None else dt)
    back = FaultModel.from_control(sys, disturbances=["wind"], faults=["leak"], noise=["w1", "w2"])
    for attr in ("A", "B", "C", "D"):
        np.testing.assert_array_equal(getattr(back, attr), getattr(m, attr))
    _same_names(m, back)
    assert back.dt == m.dt


def test_from_control_discrete_system_with_grouping_and_defaults():
    rng = np.random.default_rng(11)
    A = 0.5 * np.eye(2) + 0.1 * rng.standard_normal((2, 2))
    B, C, D = rng.standard_normal((2, 3)), rng.standard_normal((2, 2)), rng.standard_normal((2, 3))
    sys = control.ss(A, B, C, D, 0.05, inputs=["gust", "pedal", "bias"], outputs=["s", "r"], states=["v", "w"])
    m = FaultModel.from_control(sys, disturbances=["gust"], faults=["bias"])
    assert m.dt == 0.05 and m.is_discrete
    assert m.controls == ("pedal",) and m.disturbances == ("gust",) and m.faults == ("bias",)
    np.testing.assert_array_equal(m.Bu, B[:, [1]])
    np.testing.assert_array_equal(m.Bd, B[:, [0]])
    np.testing.assert_array_equal(m.Df, D[:, [2]])
    np.testing.assert_array_equal(m.A, A)
    assert m.outputs == ("s", "r") and m.states == ("v", "w")


def test_from_control_errors():
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], inputs=["u"])
    with pytest.raises(ModelError, match=r"no input named \['x'\].*\['u'\]"):
        FaultModel.from_control(sys, faults=["x"])
    with pytest.raises(ModelError, match="control.StateSpace"):
        FaultModel.from_control(control.tf([1], [1, 1]))
    with pytest.raises(ModelError, match="dt=True"):
        FaultModel.from_control(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], True))


# ---------------------------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"A": np.zeros((2, 3)), "C": np.zeros((1, 3))}, r"A must be square"),
        ({"A": -np.eye(2), "C": np.zeros((1, 3))}, r"C has 3 columns but must have 2"),
        ({"A": -np.eye(2), "C": np.eye(2), "Bu": np.zeros((3, 1))}, r"Bu has 3 rows but must have 2"),
        ({"A": -np.eye(2), "C": np.eye(2), "Bu": np.zeros((2, 2)), "Du": np.zeros((2, 1))},
         r"Du has 1 columns but must have 2"),
        ({"A": -np.eye(2), "C": np.eye(2), "Dd": np.zeros((3, 1))}, r"Dd has 3 rows but must have 2"),
        ({"A": -np.eye(2), "C": np.eye(2), "Bf": np.zeros((2, 1, 1))}, r"Bf must be a 2-D matrix"),
        ({"A": -np.eye(2), "C": np.eye(2), "Bu": np.zeros((2, 2)), "controls": ["a"]},
         r"1 controls names given for 2 controls"),
        ({"A": -np.eye(2), "C": np.eye(2), "states": ["x"]}, r"1 state names given for 2 state"),
    ],
)
def test_shape_mismatches_name_the_matrix(kwargs, pattern):
    with pytest.raises(ModelError, match=pattern):
        FaultModel(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"states": ["x", "x"]}, r"duplicate state name 'x'"),
        ({"outputs": ["y", "y"]}, r"duplicate output name 'y'"),
        ({"controls": ["u", "u"]}, r"duplicate controls name 'u'"),
        ({"controls": ["k", "z"], "faults": ["z"]}, r"input name 'z' is used in two groups"),
        ({"controls": ["k", "m"], "noise": ["k"]}, r"input name 'k' is used in two groups"),
        ({"outputs": "yy"}, r"single string 'yy'"),
    ],
)
def test_duplicate_and_malformed_names(kwargs, pattern):
    base = {"A": -np.eye(2), "C": np.eye(2), "Bu": np.ones((2, 2)), "Bf": np.ones((2, 1)), "Bw": np.ones((2, 1))}
    with pytest.raises(ModelError, match=pattern):
        FaultModel(**(base | kwargs))


@pytest.mark.parametrize(
    ("matrix", "row", "col", "value"),
    [("A", 1, 0, np.nan), ("C", 0, 1, np.inf), ("Bd", 1, 0, np.nan), ("Dw", 2, 1, -np.inf), ("Bu", 0, 1, np.nan)],
)
def test_non_finite_entry_names_matrix_row_and_column(matrix, row, col, value):
    rng = np.random.default_rng(0)
    kw = {
        "A": -np.eye(2), "C": np.ones((3, 2)), "Bu": rng.standard_normal((2, 2)), "Bd": np.ones((2, 1)),
        "Dw": np.ones((3, 2)),
    }
    bad = np.array(kw[matrix], dtype=float)
    bad[row, col] = value
    kw[matrix] = bad
    with pytest.raises(ModelError, match=rf"^{matrix} has a non-finite entry at row {row}, column {col}\b"):
        FaultModel(**kw)


@pytest.mark.parametrize("dt", [0.0, -1.0, np.inf, np.nan])
def test_bad_dt(dt):
    with pytest.raises(ModelError, match="dt must be a positive sample time"):
        FaultModel(A=[[0.5]], C=[[1.0]], dt=dt)


def test_scalar_A_is_a_one_state_model_or_a_model_error():
    """A 0-d ``A`` must not leak a bare numpy reshape error (``_matrix`` reshapes it to (0, 0))."""
    try:
        m = FaultModel(A=-2.0, C=[[1.0]])
    except ModelError:
        return
    assert m.A.shape == (1, 1) and m.A[0, 0] == -2.0


def test_error_messages_say_what_the_model_has():
    m = _random_model()
    with pytest.raises(ModelError, match=re.escape("['px', 'py', 'vx', 'vy']")):
        m.index("states", ["pz"])
    with pytest.raises(ParameterError, match="unknown name kind"):
        m.index("inputs", ["steer"])
