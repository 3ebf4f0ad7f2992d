"""Augmented EKF for the convex-model structure (Hallouzi 2008, §2.3.3, Table 2.3).

The weights follow a random walk ``μ_k = μ_{k−1} + w_μ`` with covariance ``Q^μ`` (2.39) and are
estimated jointly with the state on ``z = [x; μ]`` (2.40)–(2.41):

    x_{k+1} = A_μ x_k + B_μ u_k + w_k,     μ_{k+1} = μ_k + w_μ,     y_k = C_μ x_k + D_μ u_k + v_k.

The Jacobians (2.52)–(2.53) are ``Ā = [[A_μ, [A^(i)x + B^(i)u]_i], [0, I]]`` and
``C̄ = [C_μ, [C^(i)x + D^(i)u]_i]``, where a matrix shared by all models is a constant (zero derivative;
see :class:`~fdikit.multimodel.convex.ConvexModelSet`).  When only B (and D) vary the model is linear
in z, and the EKF is exactly a linear Kalman filter on ``[x; μ]`` (§2.3.3; checked in
``tests/multimodel/test_convex.py``).  The weight
part is projected on the simplex after each update "in the same manner as the dual CMF"; P is left
unchanged (a thesis gap).
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.multimodel.convex import ConvexModelSet
from fdikit.multimodel.convex_filter import ConvexFilterResult, check_data
from fdikit.multimodel.simplex import constrain_weights

__all__ = ["augmented_jacobians", "augmented_ekf"]


def augmented_jacobians(models: ConvexModelSet, x, mu, u) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians ``(Ā, C̄)`` of the augmented CM model at ``(x, μ, u)`` (Hallouzi 2008, (2.52)–(2.53)).

    Parameters
    ----------
    models : ConvexModelSet
        The local models.
    x : array_like
        State (n) at which to linearise.
    mu : array_like
        Weights (N).
    u : array_like
        Input (m).

    Returns
    -------
    Abar : ndarray
        ``∂[x⁺; μ⁺]/∂[x; μ]`` ((n + N) x (n + N)), (2.44).
    Cbar : ndarray
        ``∂y/∂[x; μ]`` (p x (n + N)), (2.45).

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[[0.5]], [[1.0]]], np.zeros((1, 1)), np.eye(1), Q=np.eye(1), R=np.eye(1))
    >>> Abar, Cbar = augmented_jacobians(ms, [2.0], [0.5, 0.5], [0.0])
    >>> Abar.tolist(), Cbar.tolist()
    ([[0.75, 1.0, 2.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])

    References
    ----------
    Hallouzi 2008, §2.3.3, (2.40)–(2.45), Table 2.3, (2.52)–(2.53).
    """
    x = np.ravel(x).astype(float)
    mu = models.check_weights(mu)
    u = np.atleast_1d(np.asarray(u, dtype=float)).ravel()
    A, _, C, _ = models.blend(mu)
    N, n = models.N, models.n
    Abar = np.zeros((n + N, n + N))
    Abar[:n, :n] = A
    Fmu, Hmu = models.weight_columns(x, u)
    Abar[:n, n:] = Fmu
    Abar[n:, n:] = np.eye(N)
    Cbar = np.hstack([C, Hmu])
    return Abar, Cbar


def augmented_ekf(models: ConvexModelSet, y, u, x0, P0, mu0=None, Q_mu=None, P_mu0=None, *,
                  constrain: bool | str = True, ordering: str = "michelot",
                  projection: str = "euclidean") -> ConvexFilterResult:
    """Run the augmented EKF on ``[x; μ]`` (Hallouzi 2008, §2.3.3, Table 2.3, (2.46)–(2.53)).

    Per sample k ≥ 1 the time update (2.46)–(2.48) with ``u_{k−1}``, then for every k the measurement
    update (2.49)–(2.51) (Joseph form, symmetrised) and, if ``constrain``, the simplex projection of μ̂.
    ``x0, P0`` are the prior ``x̂_{0|−1}, P_{0|−1}``.

    Parameters
    ----------
    models : ConvexModelSet
        The local models.
    y, u : array_like
        Measurements (K, p) and inputs (K, m) (``u`` may be None when m = 0); finite.
    x0, P0 : array_like
        Prior ``x̂_{0|−1}`` (n) and ``P_{0|−1}`` (n x n).
    mu0 : array_like, optional
        Initial weights (N); default uniform.
    Q_mu : array_like
        (N, N) random-walk covariance Q^μ, the main tuning knob (thesis §2.4.2: 1e-2 I); required.
    P_mu0 : array_like, optional
        Covariance of ``mu0`` (default ``I/12``, the variance of a uniform weight on [0, 1]; the thesis gives none).
    constrain : bool or str
        Weight constraint after each update, see :func:`~fdikit.multimodel.simplex.constrain_weights`
        (``True``: the simplex, default; ``"box"`` for limit-value sets, §3.6; ``"affine"``; ``False``).
    ordering : {"michelot", "thesis"}
        Ordering of the Euclidean simplex projection (:func:`~fdikit.multimodel.simplex.project_to_simplex`).
    projection : {"euclidean", "covariance"}
        ``"euclidean"`` (default; §2.3.2 with W = I, the covariance left unchanged, as the thesis
        implies) or ``"covariance"``: Simon & Chia's (2002) projection with ``W = P⁻¹`` on the whole augmented
        state, i.e. ``1ᵀμ = 1`` applied as a noise-free measurement: ``z ← z − P Dᵀ(D P Dᵀ)⁻¹(D z − 1)``,
        ``P ← P − P Dᵀ(D P Dᵀ)⁻¹ D P`` with ``D = [0, 1ᵀ]``, so the states move with the weights they are
        correlated with and the filter keeps no variance along ``1ᵀμ``.  Negative weights are then zeroed by
        the same projection (active set, §2.3.2), leaving ``P`` unchanged for them.

    Returns
    -------
    ConvexFilterResult
        Filtered states, their covariances (the x block of P) and the weights per sample.

    Raises
    ------
    ParameterError
        If ``Q_mu`` is missing, a covariance has the wrong size, or ``projection``, ``ordering`` or
        ``constrain`` is unknown.

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> u = np.sin(0.3 * np.arange(20)).reshape(-1, 1)
    >>> x, y = 0.0, []
    >>> for uk in u[:, 0]:                      # the "nominal" model, noise-free
    ...     y.append([x])
    ...     x = 0.9 * x + uk
    >>> res = augmented_ekf(ms, np.array(y), u, x0=[0.0], P0=[[1.0]], Q_mu=1e-2 * np.eye(2))
    >>> bool(res.mu[-1, 1] > 0.99), res.x.shape
    (True, (20, 1))

    References
    ----------
    Hallouzi 2008, §2.3.3, (2.39)–(2.45), Table 2.3, (2.46)–(2.53); §2.3.2, (2.37)–(2.38) for the projection.
    """
    validate.instance("models", models, ConvexModelSet, "build the set with convex_model_set(...)")
    if projection not in ("euclidean", "covariance"):
        raise ParameterError(f"projection must be 'euclidean' (W = I) or 'covariance' (W = P^-1), got {projection!r}")
    validate.choice("ordering", ordering, ("michelot", "thesis"))
    if constrain not in (True, False, "simplex", "affine", "box"):
        raise ParameterError(f"constrain must be True/'simplex', 'affine', 'box' or False, got {constrain!r}")
    N, n = models.N, models.n
    if mu0 is not None:
        validate.as_vector("mu0", mu0, N)
    x = validate.as_vector("x0", x0, n)
    if Q_mu is None:
        raise ParameterError("give Q_mu, the (N x N) random-walk covariance of the weights (2.39), e.g. 1e-2 * I")
    Q_mu = validate.as_matrix("Q_mu", Q_mu)
    P_mu0 = np.eye(N) / 12.0 if P_mu0 is None else validate.as_matrix("P_mu0", P_mu0)
    P0 = validate.as_matrix("P0", P0)
    if Q_mu.shape != (N, N) or P_mu0.shape != (N, N) or P0.shape != (n, n):
        raise ParameterError(f"need Q_mu and P_mu0 of {N} x {N} and P0 of {n} x {n}; "
                             f"got {Q_mu.shape}, {P_mu0.shape}, {P0.shape}")
    Q_mu = validate.as_covariance("Q_mu", Q_mu, N)
    P_mu0 = validate.as_covariance("P_mu0", P_mu0, N)
    P0 = validate.as_covariance("P0", P0, n)
    y, u = check_data(models, y, u)
    mu = np.full(N, 1.0 / N) if mu0 is None else models.check_weights(mu0)
    Qa = np.zeros((n + N, n + N))
    Qa[:n, :n], Qa[n:, n:] = models.Q, Q_mu
    P = np.zeros((n + N, n + N))
    P[:n, :n], P[n:, n:] = P0, P_mu0
    I = np.eye(n + N)
    K = y.shape[0]
    xs, Ps, mus, raws = np.zeros((K, n)), np.zeros((K, n, n)), np.zeros((K, N)), np.zeros((K, N))
    for k in range(K):
        if k > 0:
            Abar, _ = augmented_jacobians(models, x, mu, u[k - 1])
            A, B, _, _ = models.blend(mu)
            x = A @ x + B @ u[k - 1]  # (2.46); μ̂_{k|k−1} = μ̂_{k−1|k−1} (2.47)
            P = Abar @ P @ Abar.T + Qa  # (2.48)
        _, Cbar = augmented_jacobians(models, x, mu, u[k])
        _, _, C, D = models.blend(mu)
        e = y[k] - C @ x - D @ u[k]
        S = Cbar @ P @ Cbar.T + models.R
        G = np.linalg.solve(S, Cbar @ P).T  # (2.49)
        z = np.concatenate([x, mu]) + G @ e  # (2.50)
        ImKC = I - G @ Cbar
        P = ImKC @ P @ ImKC.T + G @ models.R @ G.T  # (2.51), Joseph form
        P = 0.5 * (P + P.T)
        raw = z[n:].copy()
        if projection == "covariance" and constrain in (True, "simplex", "affine"):
            z, P = _covariance_projection(z, P, n, nonnegative=constrain != "affine")
            x, mu = z[:n], z[n:]
        else:
            x, mu = z[:n], constrain_weights(raw, constrain, ordering=ordering)
        xs[k], Ps[k], mus[k], raws[k] = x, P[:n, :n], mu, raw
    return ConvexFilterResult(xs, Ps, mus, raws, models.names)


def _covariance_projection(z: np.ndarray, P: np.ndarray, n: int, nonnegative: bool) -> tuple[np.ndarray, np.ndarray]:
    """Simon & Chia (2002) projection of ``z = [x; μ]`` on ``1ᵀμ = 1`` (and ``μ ≥ 0``) with ``W = P⁻¹``."""
    N = z.size - n
    D = np.zeros((1, n + N))
    D[0, n:] = 1.0
    G = np.linalg.solve(D @ P @ D.T, D @ P).T
    z = z - G @ (D @ z - 1.0)
    P = P - G @ D @ P
    P = 0.5 * (P + P.T)
    if not nonnegative:
        return z, P
    base, rows, fixed = z.copy(), [D[0]], set()
    for _ in range(N):
        neg = [i for i in np.flatnonzero(z[n:] < 0) if i not in fixed]
        if not neg:
            break
        for i in neg:
            e = np.zeros(n + N)
            e[n + i] = 1.0
            rows.append(e)
            fixed.add(i)
        Dk = np.array(rows)
        d = np.zeros(len(rows))
        d[0] = 1.0
        M = Dk @ P @ Dk.T + 1e-12 * np.trace(P) * np.eye(len(rows))  # P has no variance along 1ᵀμ any more
        z = base - P @ Dk.T @ np.linalg.solve(M, Dk @ base - d)
    z[n:] = np.maximum(z[n:], 0.0)
    return z, P
