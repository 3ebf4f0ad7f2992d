"""Achievable fault detection specifications: ``fdigenspec`` and ``fdichkspec`` (Varga 2017, §5.4, Procedure GENSPEC).

A specification is one row of a structure matrix: the faults a single residual must detect (ones) and decouple
(zeros).  A row ``s`` is achievable exactly when, with the faults of its zeros decoupled together with the controls
and disturbances, every fault of its ones is still detectable (weakly, or strongly at ``fdfreq``); a generic
combination of the nullspace basis rows then detects them all.  ``fdigenspec`` enumerates the decoupled sets
(all ``2^mf − 1`` of them: the reference's recursion visits the same sets, with early pruning; ``mf`` is limited
to 16 here) and keeps the rows ``s`` whose detected set is exactly ``s``.  ``fdichkspec`` checks given rows and
returns the number of basis rows, the order of the nullspace filter ``[Q R_f]`` and, with ``minimal=True``, the
least order of a scalar filter.

References
----------
Varga (2017), §5.4 (Procedure GENSPEC), Remark 5.10; fdtools (``fdigenspec``, ``fdichkspec``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.design.nullspace.basis import denominator, left_nullspace, minimal_realization
from fdikit.design.nullspace.detectability import covered, row_structure
from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = ["SpecificationCheck", "fdigenspec", "fdichkspec", "joint_order"]

_MAX_FAULTS = 16


def _detected(model: FaultModel, zeros: tuple[str, ...], ones: tuple[str, ...], fdtol, fdfreq, fdgaintol, sdeg, tol):
    """The basis for decoupling ``zeros`` and which of ``ones`` it detects (any row)."""
    basis = left_nullspace(model, zeros, tol=tol)
    if not basis.rows:
        return basis, np.zeros(len(ones), dtype=bool)
    dens = [denominator(nu, None, sdeg, model.dt) for nu in basis.degrees]
    S = row_structure(model, basis, ones, fdtol=fdtol, fdfreq=fdfreq, fdgaintol=fdgaintol, dens=dens,
                      by_frequency=True)
    return basis, covered(S)


def fdigenspec(model: FaultModel, *, fdtol: float = 1e-4, fdgaintol: float = 0.01, fdfreq=None,
               sdeg: float | None = None, tol: float = 1e-9) -> np.ndarray:
    """Every achievable specification (structure matrix row) of the model's fault inputs.

    Parameters
    ----------
    model : FaultModel
        The plant; controls and disturbances are always decoupled, noise is ignored.
    fdtol : float, default 1e-4
        Relative threshold of weak detectability (reference ``FDtol``).
    fdgaintol : float, default 0.01
        Gain threshold of strong detectability (``FDGainTol``).
    fdfreq : float or sequence of float, optional
        Frequencies (rad/s) of strong detectability (``FDfreq``); default weak.
    sdeg : float, optional
        Stability degree of the candidate filters' poles (their gains at ``fdfreq`` depend on it).
    tol : float, default 1e-9
        Rank tolerance of the nullspace computations.

    Returns
    -------
    numpy.ndarray
        Boolean ``(rows, mf)``, columns in ``model.faults`` order, rows in decreasing binary value.

    Raises
    ------
    ParameterError
        No fault inputs, or more than 16.

    Examples
    --------
    Two sensor faults on two measurements of one state: each residual can ignore one of them.

    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Df=np.eye(2), faults=("a", "b"))
    >>> fdigenspec(m).astype(int).tolist()
    [[1, 1], [1, 0], [0, 1]]

    References
    ----------
    Varga (2017), §5.4, Procedure GENSPEC; fdtools (``fdigenspec``).
    """
    faults = tuple(model.faults)
    mf = len(faults)
    if not 1 <= mf <= _MAX_FAULTS:
        raise ParameterError(f"fdigenspec needs 1 to {_MAX_FAULTS} fault inputs, the model has {mf}")
    rows = set()
    for code in range(1, 2 ** mf):
        ones = tuple(f for j, f in enumerate(faults) if code >> (mf - 1 - j) & 1)
        zeros = tuple(f for f in faults if f not in ones)
        _, hit = _detected(model, zeros, ones, fdtol, fdfreq, fdgaintol, sdeg, tol)
        if fdfreq is None:
            found = tuple(f for f, h in zip(ones, hit) if h)
            if found:
                rows.add(sum(1 << (mf - 1 - faults.index(f)) for f in found))
        elif hit.all():
            rows.add(code)
    codes = sorted(rows, reverse=True)
    return np.array([[c >> (mf - 1 - j) & 1 for j in range(mf)] for c in codes], dtype=bool).reshape(-1, mf)


@dataclass(frozen=True)
class SpecificationCheck:
    """What ``fdichkspec`` found for each specification row.

    Attributes
    ----------
    rdims : numpy.ndarray
        Number of nullspace basis rows that can be combined to achieve row ``i``; 0 when it is not achievable.
    orders : numpy.ndarray
        Order of the minimal realisation of the nullspace filter ``[Q R_f]``; −1 when not achievable.
    leastorders : numpy.ndarray
        Least order of a scalar filter ``[q r_f]`` achieving row ``i`` (``minimal=True``); −1 otherwise.
    feasible : numpy.ndarray
        ``rdims > 0``.

    Examples
    --------
    >>> from fdikit.model import FaultModel
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> fdichkspec(m, [[1, 0], [1, 1]]).feasible.tolist()
    [True, True]

    References
    ----------
    Varga (2017), §5.4 (achievable specifications); fdtools (``fdichkspec``).
    """

    rdims: np.ndarray
    orders: np.ndarray
    leastorders: np.ndarray

    @property
    def feasible(self) -> np.ndarray:
        """``rdims > 0``: the achievable rows."""
        return self.rdims > 0


def joint_order(generator, model: FaultModel, faults) -> int:
    """McMillan degree of ``[Q  Q [G_f; 0]]``: the filter and its fault part in one minimal realisation.

    Parameters
    ----------
    generator : ResidualGenerator
        The filter ``Q`` on ``[u; y]``.
    model : FaultModel
        The plant (same time domain as the generator).
    faults : sequence of str
        The fault inputs of ``G_f``.

    Returns
    -------
    int

    Examples
    --------
    >>> from fdikit.design.nullspace.exact import efdsyn
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Bd=[[1.0]], Bf=[[1.0, 0.0]], Df=[[0.0, 0.0], [0.0, 1.0]])
    >>> joint_order(efdsyn(m, targets="f1", nuisance="f0").generator, m, ["f0", "f1"])
    0

    References
    ----------
    Varga (2017), §5.2 (least order of ``[Q R_f]``).
    """
    cols = [len(model.controls) + len(model.disturbances) + i for i in model.index("f", list(faults))]
    Bf, Df = model.B[:, cols], model.D[:, cols]
    iy = model.index("outputs", generator.outputs)
    C, mu = model.C[iy], len(generator.controls)
    Bq_u, Bq_y = generator.B[:, :mu], generator.B[:, mu:]
    Dq_u, Dq_y = generator.D[:, :mu], generator.D[:, mu:]
    n, nq, p, mf = model.n, generator.n, len(iy), len(cols)
    A = np.block([[model.A, np.zeros((n, nq))], [Bq_y @ C, generator.A]])
    B = np.block([[np.zeros((n, mu + p)), Bf], [Bq_u, Bq_y, Bq_y @ Df[iy]]])
    Cj = np.hstack([Dq_y @ C, generator.C])
    Dj = np.hstack([Dq_u, Dq_y, Dq_y @ Df[iy]])
    return minimal_realization(A, B.reshape(n + nq, mu + p + mf), Cj, Dj)[0].shape[0]


def fdichkspec(model: FaultModel, structure, *, minimal: bool = False, fdtol: float = 1e-4,
               fdgaintol: float = 0.01, fdfreq=None, sdeg: float | None = None, tol: float = 1e-9
               ) -> SpecificationCheck:
    """Feasibility of given specifications, the orders of their nullspace filters and their least orders.

    Parameters
    ----------
    model : FaultModel
        The plant.
    structure : array_like of bool
        ``(N, mf)`` specification rows, columns in ``model.faults`` order.
    minimal : bool, default False
        Also compute the least order of a scalar filter for each feasible row (an ``efdsyn`` design each).
    fdtol, fdgaintol, fdfreq, sdeg, tol
        As :func:`fdigenspec`.

    Returns
    -------
    SpecificationCheck

    Raises
    ------
    ParameterError
        A malformed ``structure``.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0], [1.0]], Df=np.eye(2), faults=("a", "b"))
    >>> c = fdichkspec(m, [[1, 1], [1, 0]], minimal=True)
    >>> c.rdims.tolist(), c.orders.tolist(), c.leastorders.tolist()
    ([2, 1], [0, 0], [0, 0])

    References
    ----------
    Varga (2017), §5.4; fdtools (``fdichkspec``).
    """
    from fdikit.design.nullspace.exact import efdsyn

    faults = tuple(model.faults)
    S = np.atleast_2d(np.asarray(structure))
    if S.ndim != 2 or S.shape[1] != len(faults) or not np.isin(S, (0, 1)).all():
        raise ParameterError(f"structure must be a 0/1 matrix with one column per fault {list(faults)}, got "
                             f"shape {S.shape}")
    N = S.shape[0]
    rdims, orders, least = np.zeros(N, int), -np.ones(N, int), -np.ones(N, int)
    for i, row in enumerate(S.astype(bool)):
        ones = tuple(f for f, s in zip(faults, row) if s)
        zeros = tuple(f for f, s in zip(faults, row) if not s)
        if not ones:
            continue
        basis, hit = _detected(model, zeros, ones, fdtol, fdfreq, fdgaintol, sdeg, tol)
        if not basis.rows or not hit.all():
            continue
        rdims[i] = len(basis.rows)
        orders[i] = joint_order(basis.generator(sdeg=sdeg), model, faults)
        if minimal:
            d = efdsyn(model, targets=ones, nuisance=zeros, sdeg=sdeg, fdtol=fdtol, fdgaintol=fdgaintol,
                       fdfreq=fdfreq, tol=tol)
            least[i] = joint_order(d.generator, model, faults)
    return SpecificationCheck(rdims, orders, least)
