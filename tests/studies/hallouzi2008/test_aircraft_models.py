"""B747 model sets from JSBSim (Hallouzi 2008, Tables 4.2–4.5): structure, trims, offsets."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.studies.hallouzi2008.aircraft_models import (
    MEASURED,
    MODEL_SET_I,
    MODEL_SET_II,
    b747_at_point,
    large_model_set,
    local_model,
    model_set,
)


@pytest.fixture(scope="module")
def b747():
    return b747_at_point()


def test_nominal_model_is_an_equilibrium_at_the_section_4_3_1_point(b747):
    ac, nominal = b747
    trim = nominal.linearization.trim
    assert trim.converged
    np.testing.assert_allclose(trim.x[[3, 9]], [92.6, 980.0])
    assert ac.mass == pytest.approx(263e3)
    np.testing.assert_allclose(nominal.linearization.f0, 0.0, atol=1e-9)
    # the affine offset reproduces ẋ = 0 at the trim: A x° + B u° + c = f° = 0
    lin = nominal.linearization
    np.testing.assert_allclose(lin.model.A @ lin.x0 + lin.model.B @ lin.u0 + lin.offset, 0.0, atol=1e-9)
    assert nominal.C.shape == (len(MEASURED), 10)


@pytest.mark.parametrize("which, order", [("I", MODEL_SET_I), ("II", MODEL_SET_II)])
def test_model_sets_follow_tables_4_3_and_4_5(b747, which, order):
    ac, nominal = b747
    models = model_set(ac, nominal, which)
    assert [(m.fault, m.size) for m in models] == [(f, s if s is None else float(s)) for f, s in order]
    assert models[-1].name == "nominal"
    for m in models:
        B = m.linearization.model.B
        if m.fault in ("rudder", "elevator", "aileron"):
            j = m.linearization.model.controls.index(m.fault)
            assert np.all(B[:, j] == 0.0)  # §4.2: the locked surface's column is removed
            assert m.linearization.trim.positions[m.fault] == pytest.approx(np.radians(m.size))
    if which == "II":
        # Table 4.5 with the note's correction: model 7 is the aileron at −15 deg (printed −25)
        assert models[6].name == "aileron_lip_-15"


def test_lip_trims_differ_as_the_thesis_says(b747):
    ac, nominal = b747
    up = local_model(ac, "elevator", 17.0)  # trailing edge down: the stabiliser trims nose-up
    down = local_model(ac, "elevator", -23.0)  # the stabiliser saturates: the airspeed is freed
    assert up.linearization.trim.converged and down.linearization.trim.converged
    assert up.linearization.trim.positions["stabilizer"] < nominal.linearization.trim.positions["stabilizer"]
    assert down.linearization.trim.positions["stabilizer"] == pytest.approx(np.radians(3.0))
    assert down.linearization.trim.x[3] < 0.8 * 92.6  # slower
    rudder = local_model(ac, "rudder", 15.0)
    x = rudder.linearization.trim.x
    assert rudder.linearization.trim.converged
    assert abs(x[5]) > np.radians(5) and abs(x[6]) > np.radians(5)  # held with sideslip and bank


def test_alpha_sensor_hydraulic_and_engine_separation_models(b747):
    ac, nominal = b747
    half = local_model(ac, "alpha_sensor", 0.5, nominal=nominal)
    k = MEASURED.index("alpha")
    np.testing.assert_allclose(half.C[k], 0.5 * nominal.C[k])
    hyd = local_model(ac, "hydraulic_4", nominal=nominal)
    Bn, Bh = nominal.linearization.model.B, hyd.linearization.model.B
    ctl = nominal.linearization.model.controls
    np.testing.assert_allclose(Bh[:, ctl.index("rudder")], 0.5 * Bn[:, ctl.index("rudder")])
    mass = ac.mass
    sep = local_model(ac, "engine_separation")
    assert ac.mass == pytest.approx(mass)  # the aircraft is put back
    assert sep.linearization.trim.thrust > 0.0
    assert abs(sep.linearization.trim.positions["rudder"]) > np.radians(1.0)  # asymmetric thrust trimmed


def test_large_sets_have_the_table_sizes(b747):
    ac, nominal = b747
    small = large_model_set(ac, nominal, "I", step=5.0)
    # rudder −25…25 and elevator −23…17 at 5 deg, 11 α-sensor models, hydraulic, engine separation
    assert len(small) == 11 + 9 + 11 + 2
    assert len(large_model_set(ac, nominal, "II", step=10.0)) == 6 + 5 + 4


def test_bad_arguments(b747):
    ac, nominal = b747
    with pytest.raises(ParameterError, match="lock position"):
        local_model(ac, "rudder", 40.0)
    with pytest.raises(ParameterError, match="nominal="):
        local_model(ac, "alpha_sensor", 0.5)
    with pytest.raises(ParameterError, match="unknown fault"):
        local_model(ac, "spoiler", 1.0)
    with pytest.raises(ParameterError, match="which"):
        model_set(ac, nominal, "III")
