"""The registry of benchmark plants: :data:`PLANTS` maps a short name to its constructor, :func:`get_plant` builds one.

Examples
--------
>>> from fdikit.plants.registry import get_plant
>>> get_plant("white-speyer").n
3
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

from fdikit.errors import ParameterError
from fdikit.model import FaultModel
from fdikit.plants.b747 import b747_longitudinal
from fdikit.plants.f16xl import f16xl_gust, f16xl_longitudinal
from fdikit.plants.msd import msd
from fdikit.plants.path_longitudinal import path_longitudinal_7
from fdikit.plants.path_vehicle import path_vehicle_12, path_vehicle_14
from fdikit.plants.single_track import single_track
from fdikit.plants.varrier_lateral import varrier_lateral
from fdikit.plants.white_speyer import white_speyer

__all__ = ["PLANTS", "get_plant"]

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

    Returns
    -------
    FaultModel
        What the constructor in :data:`PLANTS` returns for these parameters.

    Raises
    ------
    ParameterError
        If ``name`` is not a known plant, or the parameters do not fit its constructor.

    References
    ----------
    The plant modules of ``fdikit.plants`` cite their sources (e.g. Douglas et al. 1996, App. D for ``"path12"``).

    Examples
    --------
    >>> get_plant("msd").n
    6
    >>> get_plant("b747", dt=0.01).dt
    0.01
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
