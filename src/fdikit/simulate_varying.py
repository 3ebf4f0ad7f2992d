"""The frozen-ρ propagation of :func:`fdikit.simulate.simulate_scheduled` (van der Ploeg 2018, Sec. 4-3-4).

An internal module: sample ``k`` of a scheduled run uses the discrete model of ``rho[k]``,
``x(k+1) = A(ρ_k) x(k) + B(ρ_k) v(k)``, ``y(k) = C(ρ_k) x(k) + D(ρ_k) v(k)`` with ``v = [u, d]``.
The family is evaluated once per distinct ρ (or in one call of a vectorised
``family.state_space(values)``) and checked against the first model.
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ModelError
from fdikit.model import FaultModel

__all__ = ["frozen_A", "simulate_varying"]


def frozen_A(family, m0: FaultModel, rho: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The stack of frozen ``A(ρ)`` at the distinct schedule ``values`` (which hold ``rho[0]``, the ρ of ``m0``).

    Parameters
    ----------
    family : callable
        ``ρ -> FaultModel`` (discrete), optionally with a vectorised ``family.state_space(values)``.
    m0 : FaultModel
        ``family(rho[0])``.
    rho : (N,) array
        The schedule of the run.
    values : (K,) array
        Sorted distinct schedule values.

    Returns
    -------
    (K, n, n) array
        ``A(values[i])``.

    Raises
    ------
    ModelError
        When the family's models disagree with ``m0`` in names, sizes or ``dt``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> fam = lambda r: FaultModel(A=[[r]], C=[[1.0]], Bu=[[1.0]], dt=0.1)
    >>> frozen_A(fam, fam(0.5), np.array([0.5, 0.8]), np.array([0.5, 0.8])).ravel().tolist()
    [0.5, 0.8]
    """
    return _scheduled_matrices(family, m0, values, int(np.searchsorted(values, rho[0])))[0]


def _scheduled_matrices(family, m0: FaultModel, values: np.ndarray, i0: int) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D)`` stacks at the distinct schedule ``values`` (``values[i0]`` gave ``m0``); B, D over [u, d]."""
    ref = (m0.A, np.hstack([m0.Bu, m0.Bd]), m0.C, np.hstack([m0.Du, m0.Dd]))
    state_space = getattr(family, "state_space", None)
    if callable(state_space):
        mats = tuple(np.asarray(M, dtype=float) for M in state_space(values))
        ok = len(mats) == 4 and all(M.shape == (values.size,) + R.shape for M, R in zip(mats, ref))
        if not (ok and all(np.allclose(M[i0], R, rtol=1e-9, atol=1e-12) for M, R in zip(mats, ref))):
            raise ModelError(f"family.state_space disagrees with family({values[i0]:g}); it must return the stacks "
                             "(A, [Bu Bd], C, [Du Dd]) of the family's models, one per schedule value")
        return mats
    models = [m0 if i == i0 else family(float(r)) for i, r in enumerate(values)]
    for r, m in zip(values, models):
        if not isinstance(m, FaultModel) or m.dt != m0.dt or m.inputs != m0.inputs or m.outputs != m0.outputs \
                or m.n != m0.n:
            raise ModelError(f"family({r:g}) must be a discrete FaultModel with the names, sizes and dt of "
                             f"family({values[i0]:g})")
    return tuple(np.stack(M) for M in zip(*[(m.A, np.hstack([m.Bu, m.Bd]), m.C, np.hstack([m.Du, m.Dd]))
                                            for m in models]))


def simulate_varying(family, m0: FaultModel, rho: np.ndarray, v: np.ndarray, x0: np.ndarray | None):
    """Outputs and states with the model of ``rho[k]`` at sample k; ``v`` = [u, d] per sample.

    Parameters
    ----------
    family, m0, rho :
        As :func:`frozen_A`.
    v : (N, m + nd) array
        Controls and disturbances per sample.
    x0 : (n,) array or None
        Initial state (zero when None).

    Returns
    -------
    y : (N, p) array
        Outputs.
    x : (N, n) array
        States, ``x[0] = x0``.

    Raises
    ------
    ModelError
        As :func:`frozen_A`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> fam = lambda r: FaultModel(A=[[r]], C=[[1.0]], Bu=[[1.0]], dt=0.1)
    >>> y, x = simulate_varying(fam, fam(0.5), np.array([0.5, 0.5, 0.8]), np.ones((3, 1)), None)
    >>> y.ravel().tolist()
    [0.0, 1.0, 1.5]
    """
    values, idx = np.unique(rho, return_inverse=True)
    A, B, C, D = _scheduled_matrices(family, m0, values, int(idx[0]))
    drive = np.einsum("kij,kj->ki", B[idx], v)
    x = np.empty((rho.size, m0.n))
    xk = np.zeros(m0.n) if x0 is None else x0
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(rho.size):
            x[k] = xk
            xk = A[idx[k]] @ xk + drive[k]
        y = np.einsum("kij,kj->ki", C[idx], x) + np.einsum("kij,kj->ki", D[idx], v)
    return y, x
