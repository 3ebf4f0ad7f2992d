"""Limit-value (LV) model-set design: Hallouzi 2008, §3.5, (3.34)–(3.40), discretised as in §3.6.1, (3.44)–(3.45).

:func:`limit_value_model_set` writes the model as an offset plus one change per varying parameter,
``M(μ) = M⁺ + Σ_j μ_j M^Δ_j`` with ``μ_j ∈ [0, 1]`` (:class:`LimitValueModelSet`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ParameterError
from fdikit.multimodel.model_set import first_order_discretize

__all__ = ["LimitValueModelSet", "limit_value_model_set"]


Quadruple = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class LimitValueModelSet:
    """Limit-value model ``M(μ) = M⁺ + Σ_j μ_j M^Δ_j`` with ``μ_j ∈ [0, 1]``, Hallouzi 2008, (3.39)–(3.40).

    Attributes
    ----------
    names : tuple of str
        One weight per varying parameter (entries varying through the same parameter share it, §3.6.1).
    offset : tuple of arrays
        ``(A⁺, B⁺, C⁺, D⁺)``: the model at the "+" limits of all parameters.
    deltas : tuple of tuples of arrays
        ``(A^Δ_j, B^Δ_j, C^Δ_j, D^Δ_j)``: change when parameter ``j`` moves to its other limit.
    dt : float or None
        First-order sample time if discretised (3.44)–(3.45), else ``None``.

    Examples
    --------
    >>> lv = limit_value_model_set(lambda a: ([[a]], [[1.0]], [[1.0]]), {"a": -1.0}, {"a": -3.0})
    >>> lv.names, lv.offset[0].tolist(), lv.deltas[0][0].tolist(), lv.model([0.5])[0].tolist()
    (('a',), [[-1.0]], [[-2.0]], [[-2.0]])

    References
    ----------
    Hallouzi 2008, §3.5, (3.34)–(3.40); §3.6.1, (3.44)–(3.45).
    """

    names: tuple[str, ...]
    offset: Quadruple
    deltas: tuple[Quadruple, ...]
    dt: float | None = None

    def model(self, weights) -> Quadruple:
        """``(A, B, C, D)`` at the given weights (one per name, each in ``[0, 1]``)."""
        mu = np.asarray(weights, float).ravel()
        if mu.shape != (len(self.names),):
            raise DesignError(f"expected {len(self.names)} weights for {self.names}, got shape {mu.shape}")
        if np.any(mu < -1e-12) or np.any(mu > 1 + 1e-12):
            raise DesignError(f"limit-value weights must lie in [0, 1], got {mu.tolist()}")
        return tuple(self.offset[k] + sum(m * delta[k] for m, delta in zip(mu, self.deltas)) for k in range(4))


def limit_value_model_set(matrices: Callable[..., Sequence], upper: Mapping[str, float], lower: Mapping[str, float],
                          dt: float | None = None) -> LimitValueModelSet:
    """Limit-value model set, Hallouzi 2008, §3.5, (3.34)–(3.40), with one weight per parameter.

    ``matrices(**params)`` returns ``(A, B, C)`` or ``(A, B, C, D)``.  The offset is the model with
    every parameter at its ``upper`` ("+") limit; ``M^Δ_j`` is the change when parameter ``j`` alone
    moves to its ``lower`` limit, so ``a = a⁺ + μ a^Δ`` with ``a^Δ = a⁻ − a⁺`` (3.36).  The
    representation is exact when every entry is affine in one (possibly transformed) parameter,
    as in the MSD (``1/m3``); :meth:`LimitValueModelSet.model` then reproduces ``matrices`` for all
    parameter values.  With ``dt`` the blocks are first-order discretised (3.44): ``A⁺ → I + T A⁺``,
    ``A^Δ → T A^Δ``, ``B → T B``.

    Parameters
    ----------
    matrices : callable
        ``matrices(**params) -> (A, B, C)`` or ``(A, B, C, D)``, continuous-time if ``dt`` is given.
    upper, lower : mapping of str to float
        The "+" and "−" limit of every varying parameter (the same names in both).
    dt : float, optional
        Sample time [s] of a first-order discretisation; None keeps the matrices as returned.

    Returns
    -------
    LimitValueModelSet
        The offset model and one change per parameter.

    Raises
    ------
    DesignError
        If ``upper`` and ``lower`` name different parameters.
    ParameterError
        If ``matrices`` is not callable or does not return 3 or 4 numeric arrays.

    Examples
    --------
    >>> lv = limit_value_model_set(lambda k: ([[-k]], [[1.0]], [[1.0]]), {"k": 1.0}, {"k": 3.0}, dt=0.1)
    >>> lv.offset[0].round(6).tolist(), lv.deltas[0][0].round(6).tolist(), lv.dt
    ([[0.9]], [[-0.2]], 0.1)

    References
    ----------
    Hallouzi 2008, §3.5, (3.34)–(3.40); §3.6.1, (3.44).
    """
    if set(upper) != set(lower) or not upper:
        raise DesignError(f"upper and lower limits must name the same parameters, got {sorted(upper)} and "
                          f"{sorted(lower)}")
    names = tuple(upper)
    if not callable(matrices):
        raise ParameterError(f"matrices must be a callable params -> (A, B, C[, D]), got {type(matrices).__name__}")

    def quad(params) -> list[np.ndarray]:
        out = matrices(**params)
        try:
            mats = [np.atleast_2d(np.asarray(M, float)) for M in out]
        except (TypeError, ValueError):
            raise ParameterError(f"matrices(**{params}) must return (A, B, C) or (A, B, C, D) numeric arrays, "
                                 f"got {type(out).__name__}") from None
        if len(mats) not in (3, 4):
            raise ParameterError(f"matrices(**{params}) must return (A, B, C) or (A, B, C, D), got {len(mats)} arrays")
        if len(mats) == 3:
            mats.append(np.zeros((mats[2].shape[0], mats[1].shape[1])))
        return mats

    plus = quad(dict(upper))
    deltas = []
    for name in names:
        q = quad({**upper, name: lower[name]})
        deltas.append([qk - pk for qk, pk in zip(q, plus)])
    if dt is not None:
        Ad, Bd = first_order_discretize(plus[0], plus[1], dt)
        plus = [Ad, Bd, plus[2], plus[3]]
        deltas = [[dt * d[0], dt * d[1], d[2], d[3]] for d in deltas]
    return LimitValueModelSet(names, tuple(plus), tuple(tuple(d) for d in deltas), None if dt is None else float(dt))
