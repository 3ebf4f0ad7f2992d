"""Fault sizes, parameters and model vectors reconstructed from estimated weights (Hallouzi 2008, §3.6.2,
(3.51)–(3.57)).

:func:`fault_size_from_weights` (Table 3.2, Fig. 3.9), :func:`lv_parameter` and :func:`lv_reciprocal_parameter`
(the limit-value maps (3.54)–(3.57)) and :func:`estimated_model_vector` (3.51); the nearest grid model (3.52) is
:func:`fdikit.multimodel.model_set.nearest_model`.
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ParameterError

__all__ = [
    "fault_size_from_weights",
    "lv_parameter",
    "lv_reciprocal_parameter",
    "estimated_model_vector",
]


def fault_size_from_weights(mu, faulty_models) -> np.ndarray:
    """Fault size ``f = 1 − Σ_{i ∈ faulty} μ^(i)`` (Hallouzi 2008, §3.6.2, Fig. 3.9).

    With models at ``f = 0`` and ``f = 1`` only, the weight mass on the ``f = 0`` models is the lost
    effectiveness: e.g. Table 3.2, ``f_1 = 1 − (μ̂^(2) + μ̂^(4))`` (0-based indices ``[1, 3]``).  ``mu`` is
    (N,) or (K, N); returns a float or (K,).

    Parameters
    ----------
    mu : array_like
        Weights (N,) or (K, N).
    faulty_models : sequence of int
        0-based indices of the models at ``f = 0`` (the fully faulty ones).

    Returns
    -------
    float or ndarray
        ``f`` per sample: a 0-d array for (N,) weights, (K,) otherwise.

    Raises
    ------
    ParameterError
        If ``faulty_models`` is empty or holds an index outside 0..N−1.

    Examples
    --------
    >>> float(fault_size_from_weights([0.1, 0.2, 0.3, 0.1, 0.2, 0.1], [1, 3]))
    0.7

    References
    ----------
    Hallouzi 2008, §3.6.1, Table 3.2; §3.6.2, Fig. 3.9.
    """
    mu = np.asarray(mu, dtype=float)
    idx = np.asarray(faulty_models, dtype=int).ravel()
    if idx.size == 0 or idx.min() < 0 or idx.max() >= mu.shape[-1]:
        raise ParameterError(f"faulty_models must be indices in 0..{mu.shape[-1] - 1}, got {idx.tolist()}")
    return 1.0 - mu[..., idx].sum(axis=-1)


def lv_parameter(mu, value_at_0: float, value_at_1: float):
    """Parameter of a limit-value weight, ``θ = θ⁺ + μ (θ⁻ − θ⁺)`` (Hallouzi 2008, (3.54), (3.56)–(3.57)).

    ``value_at_0 = θ⁺`` (e.g. ``k_1^max``; 1 for an effectiveness f), ``value_at_1 = θ⁻`` (``k_1^min``; 0).

    Parameters
    ----------
    mu : float or array_like
        Limit-value weight(s) μ ∈ [0, 1].
    value_at_0, value_at_1 : float
        The parameter at μ = 0 (``θ⁺``) and at μ = 1 (``θ⁻``).

    Returns
    -------
    ndarray
        θ, of the shape of ``mu``.

    Examples
    --------
    >>> float(lv_parameter(0.5, 1.75, 0.25)), float(lv_parameter(0.3, 1.0, 0.0))
    (1.0, 0.7)

    References
    ----------
    Hallouzi 2008, §3.5, (3.35); §3.6.2, (3.54), (3.56)–(3.57).
    """
    return value_at_0 + np.asarray(mu, dtype=float) * (value_at_1 - value_at_0)


def lv_reciprocal_parameter(mu, value_at_0: float, value_at_1: float):
    """Parameter entering as ``1/θ`` (a mass), ``θ = θ⁺θ⁻ / (θ⁻ + μ (θ⁺ − θ⁻))`` (Hallouzi 2008, (3.55)).

    ``1/θ`` is affine in μ, from ``1/θ⁺`` at μ = 0 to ``1/θ⁻`` at μ = 1 (``θ⁺ = m_3^max``, ``θ⁻ = m_3^min``).

    Parameters
    ----------
    mu : float or array_like
        Limit-value weight(s) μ ∈ [0, 1].
    value_at_0, value_at_1 : float
        The parameter at μ = 0 (``θ⁺``) and at μ = 1 (``θ⁻``); both positive.

    Returns
    -------
    ndarray
        θ, of the shape of ``mu``.

    Raises
    ------
    ParameterError
        If a limit value is not positive.

    Examples
    --------
    >>> round(float(lv_reciprocal_parameter(0.1, 1.8, 0.2)), 12)
    1.0

    References
    ----------
    Hallouzi 2008, §3.6.2, (3.55).
    """
    if value_at_0 <= 0 or value_at_1 <= 0:
        raise ParameterError("a reciprocal LV parameter (mass) needs positive limit values")
    mu = np.asarray(mu, dtype=float)
    return value_at_0 * value_at_1 / (value_at_1 + mu * (value_at_0 - value_at_1))


def estimated_model_vector(vertices, mu) -> np.ndarray:
    """Estimated model vector ``M̂_k = [v^(1) … v^(N)] μ̂_k`` (Hallouzi 2008, (3.51)).

    ``vertices`` is (n_q, N): the vectorised local models ``vec([A B; C D])`` (for the CP set, ``U¹ v^(i)``).

    Parameters
    ----------
    vertices : array_like
        (n_q, N), one vectorised local model per column.
    mu : array_like
        Weights (N,) or (K, N).

    Returns
    -------
    ndarray
        ``M̂`` (n_q,) or (K, n_q).

    Raises
    ------
    ParameterError
        If the number of columns of ``vertices`` and of weights differ.

    Examples
    --------
    >>> estimated_model_vector([[1.0, 3.0], [0.0, 2.0]], [0.25, 0.75]).tolist()
    [2.5, 1.5]

    References
    ----------
    Hallouzi 2008, §3.6.2, (3.51).
    """
    V = np.asarray(vertices, dtype=float)
    mu = np.asarray(mu, dtype=float)
    if V.ndim != 2 or mu.shape[-1] != V.shape[1]:
        raise ParameterError(f"vertices (n_q, N) and weights (..., N) disagree: {V.shape} vs {mu.shape}")
    return mu @ V.T
