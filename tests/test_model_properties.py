"""Property tests of FaultModel validation (hypothesis).

Valid models of random shapes and names are accepted and keep their names, groups and matrices
through ``discretize``, ``with_sensor_faults`` and the python-control round trip; malformed ones
(shape mismatch, duplicate names, NaN/inf entries, non-square ``A``, bad ``dt``) raise
:class:`~fdikit.errors.ModelError` whose message names the offending matrix or argument.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fdikit import FaultModel, ModelError, ParameterError

NAME = st.from_regex(r"[a-z][a-z0-9_]{0,6}", fullmatch=True)
ENTRY = st.floats(min_value=-5.0, max_value=5.0, allow_nan=False, allow_infinity=False)


@st.composite
def models(draw, dt=None):
    """Keyword arguments of a valid FaultModel: n 1-4, p 1-3, 1-2 controls, 0-2 disturbances/faults/noise."""
    n, p = draw(st.integers(1, 4)), draw(st.integers(1, 3))
    counts = {"u": draw(st.integers(1, 2)), "d": draw(st.integers(0, 2)), "f": draw(st.integers(0, 2)),
              "w": draw(st.integers(0, 2))}
    total = n + p + sum(counts.values())
    names = draw(st.lists(NAME, min_size=total, max_size=total, unique=True))

    def mat(rows, cols):
        flat = draw(st.lists(ENTRY, min_size=rows * cols, max_size=rows * cols))
        return np.array(flat, dtype=float).reshape(rows, cols)

    kw = {"A": mat(n, n), "C": mat(p, n), "states": names[:n], "outputs": names[n:n + p], "dt": dt}
    at = n + p
    for g, word in (("u", "controls"), ("d", "disturbances"), ("f", "faults"), ("w", "noise")):
        k = counts[g]
        kw[f"B{g}"], kw[f"D{g}"], kw[word] = mat(n, k), mat(p, k), names[at:at + k]
        at += k
    return kw


def _same_structure(a: FaultModel, b: FaultModel) -> None:
    assert a.states == b.states and a.outputs == b.outputs and a.inputs == b.inputs
    assert a.A.shape == b.A.shape and a.B.shape == b.B.shape and a.C.shape == b.C.shape and a.D.shape == b.D.shape


@given(models())
def test_valid_models_are_accepted_with_their_names_and_blocks(kw):
    m = FaultModel(**kw)
    assert m.states == tuple(kw["states"]) and m.outputs == tuple(kw["outputs"])
    assert m.controls == tuple(kw["controls"]) and m.faults == tuple(kw["faults"])
    for g in "udfw":
        np.testing.assert_array_equal(m.b(g), kw[f"B{g}"])
        np.testing.assert_array_equal(m.d(g), kw[f"D{g}"])
    assert not m.A.flags.writeable and not m.B.flags.writeable


@settings(max_examples=30)  # scipy's cont2discrete costs ~10 ms a call
@given(models(), st.floats(min_value=0.01, max_value=0.5))
def test_discretize_keeps_names_and_equals_the_zoh_of_the_blocks(kw, dt):
    m = FaultModel(**kw)
    md = m.discretize(dt)
    _same_structure(m, md)
    assert md.dt == dt and md.is_discrete
    # independent ZOH: expm of the augmented matrix [[A, B], [0, 0]] dt
    n, k = m.n, m.B.shape[1]
    aug = np.zeros((n + k, n + k))
    aug[:n, :n], aug[:n, n:] = m.A, m.B
    E = scipy.linalg.expm(aug * dt)
    np.testing.assert_allclose(md.A, E[:n, :n], rtol=1e-9, atol=1e-9 * max(1.0, np.abs(E).max()))
    np.testing.assert_allclose(md.B, E[:n, n:], rtol=1e-9, atol=1e-9 * max(1.0, np.abs(E).max()))
    np.testing.assert_array_equal(md.C, m.C)
    np.testing.assert_array_equal(md.D, m.D)


@given(models(), st.data())
def test_sensor_faults_append_unit_feedthrough_columns(kw, data):
    m = FaultModel(**kw)
    chosen = data.draw(st.lists(st.sampled_from(m.outputs), min_size=1, max_size=m.p, unique=True))
    mf = m.with_sensor_faults(chosen)
    assert mf.faults == m.faults + tuple(f"{o}_sensor" for o in chosen)
    new = mf.Df[:, len(m.faults):]
    expected = np.zeros((m.p, len(chosen)))
    expected[[m.outputs.index(o) for o in chosen], range(len(chosen))] = 1.0
    np.testing.assert_array_equal(new, expected)
    np.testing.assert_array_equal(mf.Bf[:, len(m.faults):], 0.0)
    np.testing.assert_array_equal(mf.Bu, m.Bu)


@settings(max_examples=50)
@given(models(dt=None) | models(dt=0.05))
def test_python_control_round_trip(kw):
    m = FaultModel(**kw)
    back = FaultModel.from_control(m.to_control(), disturbances=m.disturbances, faults=m.faults, noise=m.noise)
    _same_structure(m, back)
    assert back.dt == m.dt
    for attr in "ABCD":
        np.testing.assert_array_equal(getattr(back, attr), getattr(m, attr))


# ---------------------------------------------------------------------------------------------- malformed
@given(models(), st.sampled_from(["A", "C", "Bu", "Du"]), st.data(), st.sampled_from([np.nan, np.inf, -np.inf]))
def test_a_non_finite_entry_is_refused_naming_the_matrix(kw, key, data, bad):
    M = np.array(kw[key], dtype=float)
    i = data.draw(st.integers(0, M.shape[0] - 1))
    j = data.draw(st.integers(0, M.shape[1] - 1))
    M[i, j] = bad
    kw[key] = M
    with pytest.raises(ModelError, match=rf"{key} has a non-finite entry at row {i}, column {j}"):
        FaultModel(**kw)


@given(models(), st.integers(1, 3))
def test_a_shape_mismatch_is_refused_naming_the_matrix(kw, extra):
    n = kw["A"].shape[0]
    C = np.zeros((kw["C"].shape[0], n + extra))
    with pytest.raises(ModelError, match=rf"C has {n + extra} columns but must have {n}"):
        FaultModel(**(kw | {"C": C}))
    Bu = np.zeros((n + extra, kw["Bu"].shape[1]))
    with pytest.raises(ModelError, match=rf"Bu has {n + extra} rows but must have {n}"):
        FaultModel(**(kw | {"Bu": Bu}))


@given(models(), st.sampled_from(["states", "outputs", "controls"]), st.data())
def test_duplicate_names_are_refused_naming_the_name(kw, kind, data):
    names = list(kw[kind])
    assume(len(names) >= 2)
    i, j = data.draw(st.lists(st.integers(0, len(names) - 1), min_size=2, max_size=2, unique=True))
    names[j] = names[i]
    with pytest.raises(ModelError, match=rf"duplicate .* name '{names[i]}'"):
        FaultModel(**(kw | {kind: names}))


@given(models())
def test_an_input_name_in_two_groups_is_refused(kw):
    kw = kw | {"Bd": np.zeros((kw["A"].shape[0], 1)), "Dd": np.zeros((kw["C"].shape[0], 1)),
               "disturbances": [kw["controls"][0]]}
    with pytest.raises(ModelError, match=rf"'{kw['controls'][0]}' is used in two groups"):
        FaultModel(**kw)


@given(st.integers(1, 4), st.integers(1, 4))
def test_a_non_square_A_is_refused(rows, cols):
    assume(rows != cols)
    with pytest.raises(ModelError, match=r"A must be square"):
        FaultModel(A=np.zeros((rows, cols)), C=np.zeros((1, cols)))


@given(models(), st.sampled_from([0.0, -0.1, -1e-9, float("nan"), float("inf"), "0.1", True, [0.1]]))
def test_a_bad_dt_is_refused(kw, dt):
    with pytest.raises(ModelError, match=r"dt"):
        FaultModel(**(kw | {"dt": dt}))


@given(models(), st.sampled_from([0.0, -0.5, float("nan"), float("inf"), "0.01", None]))
def test_discretize_refuses_a_bad_sample_time(kw, dt):
    with pytest.raises(ParameterError, match=r"dt"):
        FaultModel(**kw).discretize(dt)
