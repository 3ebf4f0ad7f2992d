"""Discrete DAE models ``H(q)[x] + L(q)[z] + F(q)[f] = 0`` (van der Ploeg 2018, §2-1, (2.1), (2.10)).

The model type of the polynomial parity filters (:mod:`fdikit.design.parity.polynomial`) and the
speed-scheduled parity filters (:mod:`fdikit.design.parity.scheduled`): :class:`DAEModel` holds the
polynomial coefficient matrices, :func:`dae_form` builds it from a discrete :class:`~fdikit.model.FaultModel`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ModelError
from fdikit.model import FaultModel

__all__ = ["DAEModel", "dae_form"]


@dataclass(frozen=True, eq=False)
class DAEModel:
    """A discrete DAE model ``H(q)[x] + L(q)[z] + F(q)[f] = 0`` (van der Ploeg 2018, (2.1)).

    Attributes
    ----------
    H, L, F : tuple of arrays
        Coefficients of ``q⁰, q¹, …`` (each ``n_r x n_x``, ``n_r x n_z``, ``n_r x n_f``).
    unknowns : tuple of str
        Names of ``x`` (states, then disturbances).
    outputs, controls : tuple of str
        Names of ``z = [outputs; controls]``.
    faults : tuple of str
        Names of the columns of ``F``.
    dt : float or None
        Sample time [s].

    Raises
    ------
    ModelError
        If a polynomial has no coefficient, a coefficient has the wrong shape, or an entry is not finite.

    Examples
    --------
    ``x(k+1) = 0.9 x(k) + u(k) + f(k)``, ``y(k) = x(k)`` as ``H(q)[x] + L(q)[z] + F(q)[f] = 0``:

    >>> dae = DAEModel(H=([[0.9], [1.0]], [[-1.0], [0.0]]), L=([[0.0, 1.0], [-1.0, 0.0]],), F=([[1.0], [0.0]],),
    ...                unknowns=("x",), outputs=("y",), controls=("u",), faults=("f",), dt=0.1)
    >>> dae.rows, dae.knowns, dae.fault_index(None)
    (2, ('y', 'u'), 0)
    >>> [M.round(6).tolist() for M in dae.evaluate(1.0)]     # H(1), L(1), F(1)
    [[[-0.1], [1.0]], [[0.0, 1.0], [-1.0, 0.0]], [[1.0], [0.0]]]
    """

    H: tuple[np.ndarray, ...]
    L: tuple[np.ndarray, ...]
    F: tuple[np.ndarray, ...]
    unknowns: tuple[str, ...]
    outputs: tuple[str, ...]
    controls: tuple[str, ...]
    faults: tuple[str, ...]
    dt: float | None = None

    def __post_init__(self) -> None:
        names = {"unknowns": self.unknowns, "outputs": self.outputs, "controls": self.controls, "faults": self.faults}
        for attr, value in names.items():
            object.__setattr__(self, attr, tuple(value))
        widths = {"H": len(self.unknowns), "L": len(self.outputs) + len(self.controls), "F": len(self.faults)}
        rows = None
        for attr, width in widths.items():
            coeffs = tuple(np.array(c, dtype=float, ndmin=2) for c in getattr(self, attr))
            if not coeffs:
                raise ModelError(f"DAE {attr}(q) needs at least one coefficient matrix (the q⁰ term)")
            for i, c in enumerate(coeffs):
                rows = c.shape[0] if rows is None else rows
                if c.shape != (rows, width):
                    raise ModelError(f"DAE coefficient {attr}_{i} has shape {c.shape}, need ({rows}, {width})")
                if not np.all(np.isfinite(c)):
                    raise ModelError(f"DAE coefficient {attr}_{i} has non-finite entries")
                c.setflags(write=False)
            object.__setattr__(self, attr, coeffs)

    @property
    def rows(self) -> int:
        """Number of equations ``n_r``."""
        return self.H[0].shape[0]

    @property
    def knowns(self) -> tuple[str, ...]:
        """Names of ``z``: outputs then controls."""
        return self.outputs + self.controls

    def fault_index(self, fault: str | None) -> int:
        """Column of ``F`` for ``fault``; ``None`` is allowed when there is exactly one."""
        if fault is None:
            if len(self.faults) != 1:
                raise DesignError(f"the DAE has faults {list(self.faults)}; name the one to detect with targets=")
            return 0
        if fault not in self.faults:
            raise DesignError(f"no fault named {fault!r}; the DAE has {list(self.faults)}")
        return self.faults.index(fault)

    def evaluate(self, lam: complex) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``H(λ), L(λ), F(λ)``."""
        return tuple(sum(c * lam**i for i, c in enumerate(getattr(self, a))) for a in "HLF")


def dae_form(model: FaultModel, faults: Sequence[str] | None = None, multiplicative: Sequence[str] = ()) -> DAEModel:
    """The DAE form (2.1) of a discrete model, by the mapping (2.10) with ``G = I`` (thesis (4.6)).

    Parameters
    ----------
    model : FaultModel
        A discrete model (``model.dt`` set; the thesis samples with a ZOH, (4.5)).
    faults : sequence of str, optional
        Fault inputs of the model that become columns of ``F`` (default: all).
    multiplicative : sequence of str
        Controls ``u_j`` with a multiplicative fault ``u_j → f_m u_j``: a fault column
        ``<control>_multiplicative`` with ``F = [Bu_j; Du_j]`` carrying ``(f_m − 1) u_j``
        (the ``E(z) f_m`` term of (2.1), (4.6)).

    Returns
    -------
    DAEModel
        ``H(q) = [[A, Bd], [C, Dd]] − q [[I, 0], [0, 0]]``, ``L = [[0, Bu], [−I, Du]]``, ``F = [Bf; Df]`` (plus
        the multiplicative columns), with the names of the model.

    Raises
    ------
    ModelError
        If ``model`` is not a discrete ``FaultModel``.

    Notes
    -----
    The noise group ``w`` is not part of the DAE (declare noise to be rejected as a disturbance).

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> dae = dae_form(single_track_lpv()(70 / 3.6), multiplicative=["steering"])
    >>> dae.faults, dae.rows, len(dae.H)
    (('steering_actuator', 'steering_multiplicative'), 7, 2)
    """
    if not isinstance(model, FaultModel):
        raise ModelError(f"dae_form needs a FaultModel, got {type(model).__name__}")
    if not model.is_discrete:
        raise ModelError("dae_form needs a discrete model; sample it first, e.g. model.discretize(0.01) (ZOH, (4.5))")
    n, p = model.n, model.p
    nd = len(model.disturbances)
    H0 = np.block([[model.A, model.Bd], [model.C, model.Dd]])
    H1 = np.block([[-np.eye(n), np.zeros((n, nd))], [np.zeros((p, n + nd))]])
    L0 = np.block([[np.zeros((n, p)), model.Bu], [-np.eye(p), model.Du]])
    names = list(model.faults if faults is None else faults)
    cols = model.index("f", names) if names else []
    F = np.vstack([model.Bf[:, cols], model.Df[:, cols]])
    if multiplicative:
        j = model.index("u", multiplicative)
        F = np.hstack([F, np.vstack([model.Bu[:, j], model.Du[:, j]])])
        names += [f"{c}_multiplicative" for c in multiplicative]
    return DAEModel(
        H=(H0, H1), L=(L0,), F=(F,), unknowns=model.states + model.disturbances, outputs=model.outputs,
        controls=model.controls, faults=tuple(names), dt=model.dt,
    )
