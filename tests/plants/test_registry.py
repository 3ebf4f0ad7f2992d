"""Plant registry: names, lookup, errors."""

from __future__ import annotations

import numpy as np
import pytest

import fdikit.plants as plants
from fdikit import FaultModel
from fdikit.errors import ParameterError
from fdikit.plants import PLANTS, get_plant, path_vehicle_12, path_vehicle_14, single_track


def test_registry_names():
    assert set(PLANTS) == {"path12", "path14", "single-track", "f16xl", "f16xl-gust", "white-speyer", "varrier-lateral",
                           "path7", "msd", "b747"}
    assert PLANTS["path12"] is path_vehicle_12
    assert PLANTS["path14"] is path_vehicle_14
    assert PLANTS["single-track"] is single_track


def test_get_plant_builds_models():
    assert get_plant("path12").n == 12
    assert get_plant("path14").n == 14
    m = get_plant("single-track", speed=70 / 3.6, dt=0.01)
    assert isinstance(m, FaultModel) and m.dt == 0.01
    np.testing.assert_array_equal(m.A, single_track(70 / 3.6, dt=0.01).A)


def test_unknown_plant_names_the_known_ones():
    with pytest.raises(ParameterError) as info:
        get_plant("path13")
    message = str(info.value)
    assert "path13" in message
    for name in ("path12", "path14", "single-track"):
        assert name in message


def test_bad_parameters_for_a_known_plant():
    with pytest.raises(ParameterError, match="path12"):
        get_plant("path12", speed=20.0)
    with pytest.raises(ParameterError, match="single-track"):
        get_plant("single-track")  # speed is required


def test_all_is_importable():
    for name in plants.__all__:
        assert hasattr(plants, name), name
