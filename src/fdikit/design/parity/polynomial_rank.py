"""Polynomial-matrix tools and rank tests of the DAE parity filter (van der Ploeg 2018, Ch. 2, Lemma 2-1.2, Sec. 2-3).

The DAE (2.1) ``H(q)[x] + L(q)[z] + F(q)[f] = 0`` is held by :class:`~fdikit.dae.DAEModel` as coefficient
lists ``C_0 … C_d`` (ascending powers of the forward shift ``q``).  Lemma 2-1.2 turns ``N(q) H(q) = 0``
into ``N̄ H̄ = 0`` on the coefficient row ``N̄ = [N_0 … N_dN]`` and the block-Toeplitz ("bar") matrix
``H̄`` (block row ``i`` holds ``H_0 … H_dH`` from block column ``i``); the same pattern with the
coefficients of the model at successive instants is the LPV ``H̄_k`` of Lemma 3-3.2.  This module holds
those matrices, their left null space, the minimal parity degree, the detectability (2.5) and isolability
(Sec. 2-3) rank tests, and the choice of the one fault a parity filter detects.  The filter design
that uses them is :func:`fdikit.design.parity.polynomial.parity_filter`.

Choices (van der Ploeg 2018, Assumption 2-1.1, (2.5)):

* polynomial ranks (2.5) are normal ranks, evaluated at three fixed generic complex points
  (rank is lower only at finitely many points), with :func:`fdikit.linalg.rank`'s relative
  tolerance.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import linalg
from fdikit.dae import DAEModel
from fdikit.errors import DesignError, ParameterError

__all__ = [
    "RankTest",
    "bar",
    "bar_matrices",
    "detectability",
    "isolability",
    "left_null_space",
    "minimal_degree",
    "normal_rank",
    "target_fault",
    "time_varying_bar",
]

#: Generic points at which polynomial matrices are evaluated for their normal rank.
_RANK_POINTS = (0.3141 + 0.7183j, -0.5772 + 0.4142j, 1.7321 - 0.2718j)


def time_varying_bar(rows: Sequence[Sequence[np.ndarray]]) -> np.ndarray:
    """Block-Toeplitz pattern with per-row coefficients: block row ``i`` holds ``rows[i][j]`` at block column ``i + j``.

    With the same coefficients in every row this is the bar matrix of Lemma 2-1.2; with the
    coefficients of the model at instant ``τ_i`` it is the LPV ``H̄_k`` of Lemma 3-3.2.

    Parameters
    ----------
    rows : sequence of sequences of (r, c) arrays, the coefficients of each block row.

    Returns
    -------
    (len(rows) r, w c) array, ``w`` the widest block row's extent.

    Raises
    ------
    ParameterError
        No block row, or an empty first row.

    Examples
    --------
    >>> import numpy as np
    >>> time_varying_bar([[np.eye(1), 2 * np.eye(1)], [3 * np.eye(1)]]).tolist()
    [[1.0, 2.0], [0.0, 3.0]]

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, Lemma 3-3.2.
    """
    rows = [list(r) for r in rows]
    if not rows or not rows[0]:
        raise ParameterError("a bar matrix needs at least one block row with one coefficient")
    r, c = rows[0][0].shape
    width = max(i + len(coeffs) for i, coeffs in enumerate(rows))
    out = np.zeros((len(rows) * r, width * c))
    for i, coeffs in enumerate(rows):
        for j, block in enumerate(coeffs):
            out[i * r : (i + 1) * r, (i + j) * c : (i + j + 1) * c] = block
    return out


def bar(coefficients: Sequence[np.ndarray], degree: int) -> np.ndarray:
    """The bar matrix of Lemma 2-1.2: ``degree + 1`` block rows of ``[C_0 … C_d]`` shifted by one block each.

    ``N̄ · bar(C, d_N)`` is the coefficient row of ``N(q) C(q)`` for ``N`` of degree ``d_N``.

    Parameters
    ----------
    coefficients : sequence of (r, c) arrays, ``C_0 … C_d`` (ascending powers of ``q``).
    degree : int, the parity degree ``d_N >= 0``.

    Returns
    -------
    ((d_N + 1) r, (d_N + d + 1) c) array

    Raises
    ------
    ParameterError
        ``degree`` not a non-negative integer, or no coefficients.

    Examples
    --------
    >>> import numpy as np
    >>> bar([np.array([[1.0]]), np.array([[2.0]])], 1)
    array([[1., 2., 0.],
           [0., 1., 2.]])

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2.
    """
    if int(degree) != degree or degree < 0:
        raise ParameterError(f"the parity degree must be a non-negative integer, got {degree!r}")
    return time_varying_bar([coefficients] * (int(degree) + 1))


def bar_matrices(dae: DAEModel, degree: int, fault: str | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(H̄, L̄, F̄)`` of Lemma 2-1.2 for parity degree ``d_N``; ``F̄`` for one fault column.

    Parameters
    ----------
    dae : DAEModel
    degree : int, the parity degree ``d_N``.
    fault : str or None, the fault column of ``F`` (default: the DAE's only fault).

    Returns
    -------
    tuple of three arrays, the bar matrices of ``H``, ``L`` and of the fault column of ``F``.

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> [M.shape for M in bar_matrices(dae, 1, "y0_sensor")]
    [(8, 6), (8, 4), (8, 2)]

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, (2.8).
    """
    j = dae.fault_index(fault)
    return bar(dae.H, degree), bar(dae.L, degree), bar([F[:, [j]] for F in dae.F], degree)


def normal_rank(coefficients: Sequence[np.ndarray], rtol: float | None = None) -> int:
    """Normal rank of ``Σ C_i qⁱ``: the largest rank at three fixed generic complex points.

    Parameters
    ----------
    coefficients : sequence of arrays, ``C_0 … C_d`` (ascending powers of ``q``).
    rtol : float or None, relative rank tolerance (default :func:`fdikit.linalg.rank`'s).

    Returns
    -------
    int

    Examples
    --------
    >>> import numpy as np
    >>> normal_rank([np.array([[1.0, 0.0]]), np.array([[0.0, 1.0]])])
    1

    References
    ----------
    van der Ploeg 2018, Assumption 2-1.1, (2.5).
    """
    return max(linalg.rank(sum(c * lam**i for i, c in enumerate(coefficients)), rtol) for lam in _RANK_POINTS)


@dataclass(frozen=True)
class RankTest:
    """Outcome of a rank condition ``rank_with > rank_without``; true in a boolean context when it holds.

    Attributes
    ----------
    holds : bool, whether ``rank_with > rank_without``.
    rank_with, rank_without : int, the (normal) ranks with and without the fault column.

    Examples
    --------
    >>> bool(RankTest(True, 3, 2)), bool(RankTest(False, 2, 2))
    (True, False)

    References
    ----------
    van der Ploeg 2018, Assumption 2-1.1, (2.5); Fact 3-3.3, (3.15).
    """

    holds: bool
    rank_with: int
    rank_without: int

    def __bool__(self) -> bool:
        return self.holds


def _hstack_poly(*polys: Sequence[np.ndarray]) -> list[np.ndarray]:
    deg = max(len(p) for p in polys)
    out = []
    for i in range(deg):
        out.append(np.hstack([p[i] if i < len(p) else np.zeros_like(p[0]) for p in polys]))
    return out


def detectability(dae: DAEModel, fault: str | None = None) -> RankTest:
    """Condition (2.5) (Assumption 2-1.1, [21] Fact 4.4): ``Rank [H(q) F(q)] > Rank H(q)`` (normal ranks).

    Parameters
    ----------
    dae : DAEModel
    fault : str or None, the fault column of ``F`` (default: the DAE's only fault).

    Returns
    -------
    RankTest

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> detectability(dae, "y0_sensor")
    RankTest(holds=True, rank_with=3, rank_without=2)

    References
    ----------
    van der Ploeg 2018, Assumption 2-1.1, (2.5).
    """
    j = dae.fault_index(fault)
    F = [c[:, [j]] for c in dae.F]
    r_with, r_without = normal_rank(_hstack_poly(dae.H, F)), normal_rank(dae.H)
    return RankTest(r_with > r_without, r_with, r_without)


def isolability(dae: DAEModel, fault: str, nuisance: str) -> RankTest:
    """Sec. 2-3: ``fault`` is isolable from ``nuisance`` iff ``Rank [H̃ F] > Rank H̃`` with ``H̃ = [H F_nuisance]``.

    For an additive and a multiplicative fault on the same signal both columns are ``F``, so
    the condition fails: they are "dynamically inseparable" by any LTI parity filter.

    Parameters
    ----------
    dae : DAEModel
    fault, nuisance : str, fault columns of ``F``: the one to isolate and the one to decouple.

    Returns
    -------
    RankTest

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> bool(isolability(dae, "y0_sensor", "y1_sensor"))
    True

    References
    ----------
    van der Ploeg 2018, §2-3.
    """
    Fa = [c[:, [dae.fault_index(fault)]] for c in dae.F]
    Fn = [c[:, [dae.fault_index(nuisance)]] for c in dae.F]
    Ht = _hstack_poly(dae.H, Fn)
    r_with, r_without = normal_rank(_hstack_poly(Ht, Fa)), normal_rank(Ht)
    return RankTest(r_with > r_without, r_with, r_without)


def left_null_space(dae: DAEModel, degree: int) -> np.ndarray:
    """Orthonormal rows spanning ``{N̄ : N̄ H̄ = 0}`` for parity degree ``d_N`` (Lemma 2-1.2).

    Parameters
    ----------
    dae : DAEModel
    degree : int, the parity degree ``d_N``.

    Returns
    -------
    (k, (d_N + 1) n_r) array, ``k`` the dimension of the left null space of ``H̄``.

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> left_null_space(dae, 1).shape
    (2, 8)

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, (2.8a).
    """
    return linalg.null(bar(dae.H, degree).T).T


def minimal_degree(dae: DAEModel, fault: str | None = None, max_degree: int | None = None) -> int:
    """Smallest ``d_N`` with ``Rank [H̄ F̄] > Rank H̄`` (a parity row that sees the fault exists).

    ``max_degree`` defaults to ``n_x · d_H`` (the degree of a minimal polynomial basis of the
    left null space of ``H(q)`` cannot exceed it).

    Parameters
    ----------
    dae : DAEModel
    fault : str or None, the fault column of ``F`` (default: the DAE's only fault).
    max_degree : int or None, the largest degree tried.

    Returns
    -------
    int, the minimal ``d_N``.

    Raises
    ------
    DesignError
        If no degree up to ``max_degree`` works: the fault is not detectable (2.5).
    ParameterError
        If ``dae`` is not a :class:`DAEModel`.

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> minimal_degree(dae, "y0_sensor")
    1

    References
    ----------
    van der Ploeg 2018, Lemma 2-1.2, Assumption 2-1.1.
    """
    if not isinstance(dae, DAEModel):
        raise ParameterError(f"dae must be a DAEModel (build one with dae_form(model)), got {type(dae).__name__}")
    j = dae.fault_index(fault)
    top = len(dae.unknowns) * (len(dae.H) - 1) if max_degree is None else int(max_degree)
    for d in range(top + 1):
        Hb, Fb = bar(dae.H, d), bar([c[:, [j]] for c in dae.F], d)
        if linalg.rank(np.hstack([Hb, Fb])) > linalg.rank(Hb):
            return d
    test = detectability(dae, fault)
    raise DesignError(
        f"no parity relation of degree <= {top} detects fault {dae.faults[j]!r} "
        f"(normal ranks: [H F] {test.rank_with}, H {test.rank_without}); "
        + ("the fault is not detectable (2.5): it acts like a disturbance" if not test else "raise max_degree")
    )


def target_fault(dae: DAEModel, targets: str | Sequence[str] | None, who: str = "the parity filter") -> str:
    """The one fault of ``dae`` a parity filter detects.

    Parameters
    ----------
    dae : DAEModel
    targets : str, sequence of str or None
        A fault name (a column of ``F``), a one-element sequence of it, or ``None`` when the DAE has
        exactly one fault.
    who : str, the caller named in error messages.

    Returns
    -------
    str, the fault name.

    Raises
    ------
    ParameterError
        More than one target, or a bare signal name (an output or control; the message gives the
        fault name ``'<output>_sensor'`` / ``'<control>_actuator'``).
    DesignError
        A name that is not a fault of the DAE, or ``None`` when it has several faults (raised by ``dae.fault_index``).

    Examples
    --------
    >>> from fdikit import FaultModel; from fdikit.dae import dae_form
    >>> dae = dae_form(FaultModel(A=[[0.5, 0], [0, 0.6]], C=[[1, 0], [0, 1]], dt=0.1).with_sensor_faults(["y0", "y1"]))
    >>> target_fault(dae, ["y1_sensor"])
    'y1_sensor'

    References
    ----------
    van der Ploeg 2018, §2-1, (2.1) (the fault columns of ``F(q)``).
    """
    if targets is None:
        return dae.faults[dae.fault_index(None)]
    given = [targets] if isinstance(targets, str) else list(targets)
    if len(given) != 1:
        raise ParameterError(f"{who} detects one target fault, got {given}; design one filter per fault")
    name = given[0]
    if name not in dae.faults and isinstance(name, str):
        if name in dae.outputs:
            raise ParameterError(f"{name!r} is an output; its sensor fault is '{name}_sensor'; faults are named by "
                                 f"fault name, not by signal name (the DAE has faults {list(dae.faults)})")
        if name in dae.controls:
            raise ParameterError(f"{name!r} is a control; its actuator fault is '{name}_actuator'; faults are named "
                                 f"by fault name, not by signal name (the DAE has faults {list(dae.faults)})")
    return dae.faults[dae.fault_index(name)]
