"""Benchmark plants as library data.

Each plant is a function returning a :class:`~fdikit.model.FaultModel`; :data:`PLANTS`
maps a short name to that function and :func:`get_plant` looks one up by name.

===================  ==============================================  ======================
name                 model                                            source
===================  ==============================================  ======================
``path12``           PATH vehicle, 12 states, sensor-fault design     Douglas et al. 1996, (d.2)
``path14``           PATH vehicle, 14 states, actuator-fault design   Douglas et al. 1996, (d.1)
``single-track``     lateral single-track model with lane errors      van der Ploeg 2018, (B.12)
``f16xl``            F-16XL longitudinal, 4 states, ``C = I``         Murray 2012, §6.1
``f16xl-gust``       F-16XL, 5 states with Dryden gust, 4 sensors     Douglas et al. 1996, App. C.5
``white-speyer``     3-state system with invariant-zero cases         Murray 2012, §6.2
``varrier-lateral``  lateral 2-state model, ρ = 1/v, Euler 0.02 s     Varrier et al. 2014, (48)
``path7``            PATH longitudinal, 7 states (reduced, 25 m/s)    Douglas et al. 1996, §9.6
``msd``              3-mass spring-damper LPV benchmark (k1, m3)      Hallouzi 2008, §3.6
``b747``             B747 longitudinal FDI example (substitute B)     Hallouzi 2008, §2.4.1
===================  ==============================================  ======================

Examples
--------
>>> from fdikit.plants import get_plant
>>> get_plant("single-track", speed=25.0).states
('lateral_velocity', 'yaw_rate', 'lateral_error', 'heading_error')
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

from fdikit.errors import ParameterError
from fdikit.model import FaultModel
from fdikit.plants.b747 import b747_longitudinal, b747_model_set
from fdikit.plants.f16xl import F16XL_DRYDEN_GAIN, f16xl_gust, f16xl_longitudinal
from fdikit.plants.msd import msd, msd_matrices
from fdikit.plants.path_longitudinal import path_longitudinal_7, path_longitudinal_7_fault_maps
from fdikit.plants.path_vehicle import (
    TABLE_2_1_EIGENVALUES_12,
    TABLE_2_1_EIGENVALUES_14,
    path_vehicle_12,
    path_vehicle_14,
    rounding_intervals,
)
from fdikit.plants.single_track import (
    PRIUS_2010,
    SingleTrackLPV,
    SingleTrackParameters,
    single_track,
    single_track_lpv,
    understeer_gradient,
)
from fdikit.plants.varrier_lateral import (
    SCENIC,
    VarrierParameters,
    rho_from_speed,
    varrier_lateral,
    varrier_lateral_lpv,
    varrier_uncertainty,
)
from fdikit.plants.white_speyer import WHITE_SPEYER_CASES, white_speyer

__all__ = [
    "PLANTS",
    "get_plant",
    "path_vehicle_12",
    "path_vehicle_14",
    "rounding_intervals",
    "TABLE_2_1_EIGENVALUES_12",
    "TABLE_2_1_EIGENVALUES_14",
    "SingleTrackParameters",
    "PRIUS_2010",
    "single_track",
    "understeer_gradient",
    "single_track_lpv",
    "SingleTrackLPV",
    "varrier_lateral",
    "varrier_lateral_lpv",
    "varrier_uncertainty",
    "VarrierParameters",
    "SCENIC",
    "rho_from_speed",
    "f16xl_longitudinal",
    "f16xl_gust",
    "F16XL_DRYDEN_GAIN",
    "white_speyer",
    "path_longitudinal_7",
    "msd",
    "msd_matrices",
    "b747_longitudinal",
    "b747_model_set",
    "path_longitudinal_7_fault_maps",
    "WHITE_SPEYER_CASES",
]

#: Plant constructors by name; call with the plant's own keyword parameters.
PLANTS: dict[str, Callable[..., FaultModel]] = {
    "path12": path_vehicle_12,
    "path14": path_vehicle_14,
    "single-track": single_track,
    "f16xl": f16xl_longitudinal,
    "f16xl-gust": f16xl_gust,
    "white-speyer": white_speyer,
    "varrier-lateral": varrier_lateral,
    "path7": path_longitudinal_7,
    "msd": msd,
    "b747": b747_longitudinal,
}


def get_plant(name: str, **params) -> FaultModel:
    """Build the benchmark plant called ``name`` with its keyword parameters.

    Parameters
    ----------
    name : str
        One of the keys of :data:`PLANTS` (``"path12"``, ``"path14"``, ``"single-track"``).
    **params
        Passed to the plant's constructor, e.g. ``speed=19.44, dt=0.01`` for
        ``"single-track"``.

    Raises
    ------
    ParameterError
        If ``name`` is not a known plant, or the parameters do not fit its constructor.
    """
    try:
        factory = PLANTS[name]
    except (KeyError, TypeError):
        raise ParameterError(f"unknown plant {name!r}; known plants: {', '.join(sorted(PLANTS))}") from None
    signature = inspect.signature(factory)
    try:
        signature.bind(**params)
    except TypeError as exc:
        raise ParameterError(f"bad parameters for plant {name!r}: {exc}; its signature is {name}{signature}") from None
    return factory(**params)
