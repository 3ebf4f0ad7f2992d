"""Read descriptor models and matrices saved by Julia's JLD2 (FaultDetectionTools.jl / DescriptorSystems.jl data).

JLD2 files are HDF5 files; h5py reads them, but Julia's layout has to be undone by hand, which no Python library
does: arrays are stored column-major (so every matrix is read transposed), a vector of structures is an array of
object references, and a ``DescriptorStateSpace`` is a compound of the fields ``A, E, B, C, D, Ts`` whose ``E``
is either a reference to a matrix or a ``UniformScaling`` (a compound with the single field ``λ``: ``E = λI``).
The Julia type name is stored in an attribute h5py cannot decode (a variable-length vector of references), so a
structure is recognised by exactly that set of fields.  ``Ts = 0`` is continuous time, ``Ts > 0`` the sample time;
Julia's ``Ts = -1`` (unspecified sample time) is refused.

References
----------
fdtools (the ``Examples/*.jld2`` data of the Chapter 8 case studies); Varga (2017), §8.1–8.2.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fdikit.errors import ModelError, ParameterError

__all__ = ["read_jld2"]

_STATE_SPACE = {"A", "E", "B", "C", "D", "Ts"}


def read_jld2(path: str | Path, names: Sequence[str] | None = None) -> dict:
    """The named variables of a JLD2 file: matrices as arrays, ``DescriptorStateSpace`` models as models.

    Parameters
    ----------
    path : str or Path
        The ``.jld2`` file.
    names : sequence of str, optional
        The variables to read (default every top-level variable).

    Returns
    -------
    dict
        Name → value: a numeric array (matrices in their Julia orientation), a
        :class:`fdikit.descriptor.model.DescriptorModel` (all inputs in the control group ``u``), or a list of
        decoded values for a Julia vector of objects.

    Raises
    ------
    ParameterError
        The file is missing, not HDF5, or a name is not in it (the message lists the names it has).
    ModelError
        A structure that is not a state-space model, or a model with an unspecified sample time.

    Examples
    --------
    The Chapter 8 actuator case study's data (Varga 2017, §8.1), shipped with fdikit:

    >>> from fdikit.studies.varga2017.aircraft import data_file
    >>> data = read_jld2(data_file("cs1"), ["K", "SYSACM"])
    >>> data["K"].shape, len(data["SYSACM"]), data["SYSACM"][0].n
    ((22, 10), 11, 10)

    References
    ----------
    fdtools (``Examples/cs1data.jld2``, ``cs2data.jld2``).
    """
    import h5py

    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"JLD2 file {str(path)!r} does not exist; give the path of a .jld2 file")
    try:
        f = h5py.File(path, "r")
    except OSError as err:
        raise ParameterError(f"{str(path)!r} is not a JLD2/HDF5 file ({err}); JLD2 writes HDF5 files") from err
    with f:
        have = [k for k in f.keys() if not k.startswith("_")]
        wanted = have if names is None else list(names)
        missing = [n for n in wanted if n not in have]
        if missing:
            raise ParameterError(f"{str(path)!r} has no variables {missing}; it holds {have}")
        return {n: _decode(f, f[n][()], n) for n in wanted}


def _decode(f, value, where: str):
    """One stored value: a reference, an object array, a compound or a numeric array."""
    import h5py

    if isinstance(value, h5py.Reference):
        return _decode(f, f[value][()], where)
    if isinstance(value, np.void):
        return _state_space(f, value, where)
    arr = np.asarray(value)
    if arr.dtype == object:
        return [_decode(f, v, f"{where}[{i}]") for i, v in enumerate(arr.ravel(order="F"))]
    return arr.T.copy() if arr.ndim >= 2 else arr.copy()


def _state_space(f, value: np.void, where: str):
    """A ``DescriptorStateSpace`` compound → :class:`DescriptorModel`."""
    from fdikit.descriptor.model import DescriptorModel

    fields = set(value.dtype.names or ())
    if fields != _STATE_SPACE:
        raise ModelError(f"{where}: a Julia structure with fields {sorted(fields)} is not a DescriptorStateSpace "
                         f"(fields {sorted(_STATE_SPACE)}); only state-space models and arrays are read")
    A, B, C, D = (np.atleast_2d(np.asarray(_decode(f, value[k], where), dtype=float)) for k in "ABCD")
    E = value["E"]
    if isinstance(E, np.void):           # UniformScaling: E = λ I
        E = float(E[0]) * np.eye(A.shape[0])
    else:
        E = np.asarray(_decode(f, E, where), dtype=float)
    Ts = float(value["Ts"])
    if Ts < 0:
        raise ModelError(f"{where}: the model has an unspecified sample time (Ts = {Ts}); fdikit needs Ts = 0 "
                         "(continuous) or the sample time")
    n, m = A.shape[0], D.shape[1]
    return DescriptorModel(A, C.reshape(-1, n), E=E, Bu=B.reshape(n, m), Du=D, dt=Ts if Ts > 0 else None)
