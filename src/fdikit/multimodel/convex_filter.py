"""The dual convex-model filter (Hallouzi 2008, §2.3.2, Table 2.2).

For the convex-model structure (2.8)–(2.10) (:class:`~fdikit.multimodel.convex.ConvexModelSet`) the dual CMF
alternates

1. a square-root covariance Kalman step (2.29)–(2.32) for the model frozen at μ̂_{k−1};
2. a square-root-information RLS step (2.33)–(2.36) with forgetting λ for the weights
   (:func:`weight_regressors` or :func:`innovation_regressors`, :func:`rls_weight_step`),
   followed by the projection (2.37)–(2.38) onto the simplex (:mod:`fdikit.multimodel.simplex`).

:func:`dual_convex_filter` runs it and returns a :class:`ConvexFilterResult`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.multimodel.convex import ConvexModelSet
from fdikit.multimodel.kalman_steps import psd_sqrt, srcf_step, srkf_predict, srkf_update, tria
from fdikit.multimodel.simplex import constrain_weights

__all__ = [
    "weight_regressors",
    "innovation_regressors",
    "rls_weight_step",
    "ConvexFilterResult",
    "dual_convex_filter",
]


def weight_regressors(models: ConvexModelSet, x_prev, u_prev, x_filt, u, y, weighting: str = "whitened"):
    """Regressor ``Φ`` and target ``Γ`` of the weight step (Hallouzi 2008, (2.33)–(2.34)).

    Rows ``[W_Q [A^(i) x̂_{k−1|k−1} + B^(i) u_{k−1}]_i ; W_R [C^(i) x̂_{k|k} + D^(i) u_k]_i]`` and
    ``[W_Q x̂_{k|k} ; W_R y_k]``.  ``weighting="whitened"`` (default) uses ``W = Q^{-1/2}, R^{-1/2}``, for
    which ``‖Φμ − Γ‖²`` is the cost (2.27); ``"inverse"`` uses ``Q^{-1}, R^{-1}`` as printed in (2.33)
    (with ``Q^{-1}`` the squared norm weights by ``Q^{-2}``, not the ``Q^{-1}`` of (2.27), so the
    printed form appears to have lost the exponent ½).

    Parameters
    ----------
    models : ConvexModelSet
        The local models.
    x_prev, u_prev : array_like
        ``x̂_{k−1|k−1}`` (n) and ``u_{k−1}`` (m).
    x_filt, u, y : array_like
        ``x̂_{k|k}`` (n), ``u_k`` (m) and ``y_k`` (p).
    weighting : {"whitened", "inverse"}
        ``Q^{-1/2}, R^{-1/2}`` (default) or ``Q^{-1}, R^{-1}`` as printed.

    Returns
    -------
    Phi : ndarray
        Regressor ((n + p) x N), one column per local model.
    Gamma : ndarray
        Target (n + p).

    Raises
    ------
    ParameterError
        On an unknown ``weighting``.

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> Phi, Gamma = weight_regressors(ms, [1.0], [1.0], [1.9], [0.0], [1.9])
    >>> Phi.round(4).tolist(), Gamma.round(4).tolist()
    ([[90.0, 190.0], [19.0, 19.0]], [190.0, 19.0])

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2 step 2, (2.27), (2.33)–(2.34).
    """
    if weighting not in ("whitened", "inverse"):
        raise ParameterError(f"weighting must be 'whitened' (Q^-1/2, R^-1/2) or 'inverse' (Q^-1, R^-1), "
                             f"got {weighting!r}")
    x_prev, x_filt = np.ravel(x_prev).astype(float), np.ravel(x_filt).astype(float)
    u_prev, u = np.atleast_1d(np.asarray(u_prev, float)).ravel(), np.atleast_1d(np.asarray(u, float)).ravel()
    y = np.ravel(y).astype(float)
    if weighting == "whitened":
        WQ = np.linalg.inv(psd_sqrt(models.Q, "Q"))
        WR = np.linalg.inv(np.linalg.cholesky(models.R))
    else:
        WQ, WR = np.linalg.inv(models.Q), np.linalg.inv(models.R)
    state_cols = (models.A @ x_prev + models.B @ u_prev).T  # n x N
    out_cols = (models.C @ x_filt + models.D @ u).T  # p x N
    Phi = np.vstack([WQ @ state_cols, WR @ out_cols])
    Gamma = np.concatenate([WQ @ x_filt, WR @ y])
    return Phi, Gamma


def rls_weight_step(T_prev, xi_prev, Phi, Gamma, lam: float):
    """Square-root-information RLS step with forgetting (Hallouzi 2008, (2.35)–(2.36)).

    ``[[T_k, ξ_k], [0, ε_k]] = U_3 [[√λ T_{k−1}, √λ ξ_{k−1}], [Φ, Γ]]`` (QR), ``μ̂_k = T_k^{-1} ξ_k``.
    After k steps ``μ̂_k`` minimises ``λ^k‖T_0μ − ξ_0‖² + Σ_j λ^{k−j} ‖Φ_j μ − Γ_j‖²`` (checked against batch
    weighted least squares in ``tests/multimodel/test_convex.py``).

    Returns ``(T_k, ξ_k, μ̂_k)``.

    Parameters
    ----------
    T_prev : array_like
        Square-root information ``T_{k−1}`` (N x N), upper triangular.
    xi_prev : array_like
        ``ξ_{k−1}`` (N).
    Phi, Gamma : array_like
        Regressor (r x N) and target (r) of this sample (:func:`weight_regressors`).
    lam : float
        Forgetting factor λ ∈ (0, 1].

    Returns
    -------
    T : ndarray
        ``T_k`` (N x N).
    xi : ndarray
        ``ξ_k`` (N).
    mu : ndarray
        Unconstrained weight estimate ``μ̂_k`` (N) (least squares when ``T_k`` is singular).

    Raises
    ------
    ParameterError
        If ``lam`` is not in (0, 1].

    Examples
    --------
    >>> T, xi, mu = rls_weight_step(np.zeros((1, 1)), [0.0], [[2.0]], [1.0], 0.9)
    >>> float(mu[0])
    0.5

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2 step 2, (2.35)–(2.36).
    """
    lam = validate.number("lam (the forgetting factor)", lam, finite=False)
    if not 0.0 < lam <= 1.0:
        raise ParameterError(f"forgetting factor lam (lambda) must be in (0, 1], got {lam}")
    T_prev = np.asarray(T_prev, dtype=float)
    N = T_prev.shape[0]
    Phi = np.atleast_2d(np.asarray(Phi, dtype=float))
    top = np.hstack([np.sqrt(lam) * T_prev, np.sqrt(lam) * np.reshape(xi_prev, (N, 1))])
    bottom = np.hstack([Phi, np.reshape(Gamma, (-1, 1))])
    Rm = np.linalg.qr(np.vstack([top, bottom]), mode="r")
    T, xi = Rm[:N, :N], Rm[:N, N]
    mu = np.linalg.lstsq(T, xi, rcond=None)[0] if abs(np.diag(T)).min() < 1e-300 else np.linalg.solve(T, xi)
    return T, xi, mu


@dataclass(frozen=True)
class ConvexFilterResult:
    """Output of a convex-model filter run.

    Attributes
    ----------
    x : ndarray
        (K, n) filtered states x̂_{k|k}.
    P : ndarray
        (K, n, n) their covariances.
    mu : ndarray
        (K, N) weights used (constrained if the filter projects).
    mu_raw : ndarray
        (K, N) weights before the projection.
    names : tuple of str
        Model names, in the order of the columns of ``mu``.

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> u = np.sin(0.3 * np.arange(12)).reshape(-1, 1)
    >>> x, y = 0.0, []
    >>> for uk in u[:, 0]:                      # the "nominal" model, noise-free
    ...     y.append([x])
    ...     x = 0.9 * x + uk
    >>> res = dual_convex_filter(ms, np.array(y), u, x0=[0.0], P0=[[1.0]])
    >>> res.x.shape, res.P.shape, res.mu.shape, res.names
    ((12, 1), (12, 1, 1), (12, 2), ('stuck', 'nominal'))

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2; §2.3.3, Table 2.3.
    """

    x: np.ndarray
    P: np.ndarray
    mu: np.ndarray
    mu_raw: np.ndarray
    names: tuple[str, ...]

    def plot(self, ax=None, **kwargs):
        """Draw the model weights over time (:func:`fdikit.plots.plot_weights`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw into it; default a new figure.
        **kwargs
            ``t``, ``raw``, ``title`` and ``path`` of :func:`~fdikit.plots.plot_weights`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> from fdikit.multimodel.convex import convex_model_set
        >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]])
        >>> fig, ax = plt.subplots()
        >>> dual_convex_filter(ms, np.zeros((4, 1)), np.ones((4, 1)), x0=[0.0], P0=[[1.0]]).plot(ax=ax) is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_weights

        return plot_weights(self, ax=ax, **kwargs)


def check_data(models: ConvexModelSet, y, u):
    y = validate.as_array("y", y, error=DataError, finite=False)
    if y.ndim != 2 or y.shape[1] != models.p:
        raise DataError(f"y must be (K, {models.p}) measurements, got shape {y.shape}")
    K = y.shape[0]
    if u is None:
        u = np.zeros((K, models.m))
    u = validate.as_array("u", u, error=DataError, finite=False)
    if u.size != K * models.m:
        raise DataError(f"u must be (K, {models.m}) inputs with K = {K} (as y), got shape {u.shape}")
    u = u.reshape(K, -1)
    if u.shape[1] != models.m:
        raise DataError(f"u must be (K, {models.m}) inputs, got shape {u.shape}")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(u))):
        raise DataError("y and u must be finite; drop or interpolate NaN samples first")
    return y, u


def innovation_regressors(models: ConvexModelSet, x_prev, S_prev, u_prev, u, y, mu_prev, Q_sqrt, R_sqrt):
    """Weight-step regressors from the one-step prediction error (corrected form of (2.33)–(2.34)).

    The thesis's step 2 substitutes ``x_k = x̂_{k|k}`` in (2.27) and weights the state residual by ``Q⁻¹``;
    §2.3.2 itself remarks that this ignores the uncertainty of ``x̂_{k|k}``.  Integrating ``x_k`` out of
    (2.16) instead gives the exact likelihood of the weights given the past,
    ``y_k ~ N(C_μ x̂⁻_k(μ) + D_μ u_k, C P⁻ Cᵀ + R)`` with ``x̂⁻_k(μ) = A_μ x̂_{k−1|k−1} + B_μ u_{k−1}``.
    ``x̂⁻_k`` is affine in μ; the product with ``C_μ`` is linearised at ``μ̄ = μ̂_{k−1}``:
    ``ŷ_k(μ) ≈ ŷ_k(μ̄) + G (μ − μ̄)``, ``G = C_μ̄ F + ∂(C_μ x̂⁻ + D_μ u)/∂μ`` with ``F = ∂x̂⁻/∂μ`` — exact when
    only A and B vary.  Whitened by the innovation factor ``R_e`` (``R_e R_eᵀ = C P⁻ Cᵀ + R``):
    ``Φ = R_e⁻¹ G``, ``Γ = R_e⁻¹ (e_k + G μ̄)``, ``e_k = y_k − ŷ_k(μ̄)``.

    Returns ``(Φ, Γ, F, x̂⁻_k(μ̄), S⁻_k(μ̄))``.

    Parameters
    ----------
    models : ConvexModelSet
        The local models.
    x_prev, S_prev : ndarray
        ``x̂_{k−1|k−1}`` (n) and a factor ``S_{k−1|k−1}`` (n x n) of its covariance.
    u_prev, u, y : ndarray
        ``u_{k−1}`` (m), ``u_k`` (m) and ``y_k`` (p).
    mu_prev : ndarray
        Linearisation point ``μ̄ = μ̂_{k−1}`` (N).
    Q_sqrt, R_sqrt : ndarray
        Factors of ``Q`` (n x n) and ``R`` (p x p).

    Returns
    -------
    Phi, Gamma : ndarray
        Whitened regressor (p x N) and target (p).
    F : ndarray
        ``∂x̂⁻_k/∂μ`` (n x N).
    x_pred, S_pred : ndarray
        ``x̂⁻_k(μ̄)`` (n) and the factor of its covariance (n x n).

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> Phi, Gamma, F, x_pred, S_pred = innovation_regressors(
    ...     ms, np.array([1.0]), np.array([[0.1]]), np.array([1.0]), np.array([0.0]), np.array([1.9]),
    ...     np.array([0.5, 0.5]), np.array([[0.01]]), np.array([[0.1]]))
    >>> F.tolist(), x_pred.round(6).tolist(), Phi.round(4).tolist()
    ([[0.0, 1.0]], [1.4], [[0.0, 7.4125]])

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.16), (2.27), (2.33)–(2.34) (the form corrected here).
    """
    A, B, C, D = models.blend(mu_prev)
    x_pred, S_pred = srkf_predict(x_prev, S_prev, A, B, u_prev, Q_sqrt)
    F, _ = models.weight_columns(x_prev, u_prev)
    _, H = models.weight_columns(x_pred, u)
    G = C @ F + H
    e = y - C @ x_pred - D @ u
    Re = tria(np.hstack([C @ S_pred, R_sqrt]))
    Phi = scipy.linalg.solve_triangular(Re, G, lower=True)
    Gamma = scipy.linalg.solve_triangular(Re, e + G @ mu_prev, lower=True)
    return Phi, Gamma, F, x_pred, S_pred


def dual_convex_filter(models: ConvexModelSet, y, u, x0, P0, mu0=None, lam: float = 0.9, *,
                       form: str = "corrected", weighting: str = "whitened", ordering: str = "michelot",
                       metric: str | None = None, constrain: bool | str = True, write_back: bool | None = None,
                       b_after_weights: bool = True, T0_scale: float = 1e-3,
                       prior_std: float | None = None) -> ConvexFilterResult:
    """Run the dual convex-model filter (Hallouzi 2008, §2.3.2, Table 2.2).

    ``form="thesis"`` is Table 2.2 as printed.  Per sample k: the SRCF step (2.29)–(2.31) with the model at
    μ̂_{k−1}; the SRI-RLS step (2.33)–(2.36) and the projection (2.37)–(2.38) (W = I) give μ̂_k; then (2.32),
    whose ``B u_k`` term uses ``B_{μ̂_k}`` when ``b_after_weights`` (as §2.4.2 does when only B switches).

    ``form="corrected"`` (default) keeps the two decoupled linear steps, the SRI-RLS with forgetting and the
    projection, with three changes, each needed for the filter to track the §2.4.2 benchmark:

    1. the weight regression is the one-step prediction error whitened by its own covariance
       (:func:`innovation_regressors`) instead of ``x̂_{k|k}`` weighted by ``Q⁻¹``.  The printed step
       treats the Kalman correction ``x̂_{k|k} − A x̂_{k−1|k−1} − B u = K_k e_k`` as process noise of
       covariance Q, but its covariance is ``K Σ Kᵀ``: on the tracking benchmark the position rows carry
       the velocity innovation through the cross gain 0.805 with Q = 1e-3, overweighted ~600×, and the
       weights follow that noise (velocity RMSE 3.6–10 m/s against 0.6 for the EKF);
    2. the projection metric is the RLS information ``W = T_kᵀ T_k`` (Simon & Chia 2002's minimum-variance
       choice; :func:`~fdikit.multimodel.simplex.project_to_simplex_weighted`) and the constrained
       weights are written back, ``ξ_k = T_k μ^c`` (no integrator wind-up at the simplex edges);
    3. the weights are estimated first and the state step of sample k uses μ̂_k (the weights estimated
       from the transition k−1 → k also propagate it), removing the one-sample lag of step 1.

    Parameters
    ----------
    models : ConvexModelSet
        The local models.
    y, u : array_like
        Measurements (K, p) and inputs (K, m) (``u`` may be None when m = 0); finite.
    x0, P0 : array_like
        Prior ``x̂_{0|−1}`` (n) and ``P_{0|−1}`` (n x n).
    mu0 : array_like, optional
        Initial weights (N); default uniform 1/N.
    lam : float, optional
        Forgetting factor λ ∈ (0, 1] (default 0.9; the thesis uses 0.9 and 0.85).
    form : {"corrected", "thesis"}
        The corrected filter (default) or Table 2.2 as printed.
    weighting : {"whitened", "inverse"}
        Thesis form only: ``Q^{-1/2}`` (default) or ``Q^{-1}`` as printed in (2.33).
    ordering : {"michelot", "thesis"}
        Euclidean projection ordering, see :func:`~fdikit.multimodel.simplex.project_to_simplex`.
    metric : {"information", "identity"}, optional
        Projection metric ``W = TᵀT`` or ``W = I`` (the thesis); default by ``form``.
    constrain : bool or str
        See :func:`~fdikit.multimodel.simplex.constrain_weights`: ``True`` (the simplex, default), ``"affine"``
        (``1ᵀμ = 1`` only, for OD sets, whose weights may be negative), ``"box"`` (limit-value sets) or ``False``.
    write_back : bool, optional
        Store ``ξ = T μ^c`` (not stated in the thesis); default by ``form``.
    b_after_weights : bool
        Thesis form: use ``B_{μ̂_k}`` in (2.32) (default True, as §2.4.2 does when only B switches).
    T0_scale : float
        ``T_0 = δ I`` and ``ξ_0 = T_0 μ_0`` (a thesis gap); default 1e-3.
    prior_std : float, optional
        Regularised forgetting: each step adds the rows ``√(1−λ)/σ [I, μ_0]``, so the weight
        information never falls below ``I/σ²`` around ``μ_0`` (default ``None``: none, as in the thesis).  It
        keeps weights that the data do not determine at ``μ_0`` instead of letting them wander, as they do
        on the B747 benchmark before the states are excited.

    Returns
    -------
    ConvexFilterResult
        Filtered states, covariances and weights per sample.

    Raises
    ------
    ParameterError
        On an unknown ``form``, ``metric``, ``constrain``, ``ordering`` or ``weighting``, ``lam`` outside (0, 1],
        or a non-positive ``T0_scale``/``prior_std``.
    ParameterError
        With ``form="thesis"`` on a limit-value set (an offset the printed step has no term for).

    Notes
    -----
    Measured on §2.4.2 (8 runs, λ = 0.9): velocity RMSE in straight flight 4.0 m/s (thesis form) against 0.70
    (corrected; EKF 0.60, IMM 0.35), and in the half-strength turn 3.6 against 0.71 (EKF 0.56, IMM 1.08).
    Neither form is stable on the §3.6 MSD (the f2·x2 scale of sensor 2 is weakly observable and, with no
    prior on the weights, drifts); the thesis uses the augmented EKF there.

    Examples
    --------
    >>> from fdikit.multimodel.convex import convex_model_set
    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> u = np.sin(0.3 * np.arange(12)).reshape(-1, 1)
    >>> x, y = 0.0, []
    >>> for uk in u[:, 0]:                      # the "nominal" model, noise-free
    ...     y.append([x])
    ...     x = 0.9 * x + uk
    >>> res = dual_convex_filter(ms, np.array(y), u, x0=[0.0], P0=[[1.0]])
    >>> res.mu[-1].round(3).tolist()
    [0.0, 1.0]

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2, (2.29)–(2.38); §2.4.2 (the tracking benchmark).
    """
    validate.instance("models", models, ConvexModelSet, "build the set with convex_model_set(...)")
    if form not in ("corrected", "thesis"):
        raise ParameterError(f"form must be 'corrected' or 'thesis' (Table 2.2 as printed), got {form!r}")
    metric = metric or ("information" if form == "corrected" else "identity")
    if metric not in ("information", "identity"):
        raise ParameterError(f"metric must be 'information' (W = T'T) or 'identity' (W = I), got {metric!r}")
    write_back = (form == "corrected") if write_back is None else write_back
    if constrain not in (True, False, "simplex", "affine", "box"):
        raise ParameterError(f"constrain must be True/'simplex', 'affine', 'box' or False, got {constrain!r}")
    validate.choice("ordering", ordering, ("michelot", "thesis"))
    if weighting not in ("whitened", "inverse"):
        raise ParameterError(f"weighting must be 'whitened' (Q^-1/2, R^-1/2) or 'inverse' (Q^-1, R^-1), "
                             f"got {weighting!r}")
    lam = validate.number("lam (the forgetting factor)", lam, finite=False)
    if not 0.0 < lam <= 1.0:
        raise ParameterError(f"forgetting factor lam (lambda) must be in (0, 1], got {lam}")
    T0_scale = validate.positive("T0_scale", T0_scale)
    if prior_std is not None:
        prior_std = validate.positive("prior_std", prior_std)
    if mu0 is not None:
        validate.as_vector("mu0", mu0, models.N)
    if form == "thesis" and models.offset is not None:
        raise ParameterError("the printed weight step (2.33) has no offset term; use form='corrected' for "
                             "limit-value sets")
    y, u = check_data(models, y, u)
    N, n = models.N, models.n
    mu = np.full(N, 1.0 / N) if mu0 is None else models.check_weights(mu0)
    x_pred = validate.as_vector("x0", x0, n)
    S_pred = psd_sqrt(validate.as_covariance("P0", P0, n, scalar_ok=False), "P0")
    Q_sqrt, R_sqrt = psd_sqrt(models.Q, "Q"), np.linalg.cholesky(models.R)
    T, xi = T0_scale * np.eye(N), T0_scale * mu.copy()
    mu_prior = mu.copy()

    prior = None if prior_std is None else np.sqrt(1.0 - lam) / prior_std

    def weight_update(Phi, Gamma):
        nonlocal T, xi
        if prior is not None:  # regularised forgetting: the information never falls below I / prior_std²
            Phi, Gamma = np.vstack([Phi, prior * np.eye(N)]), np.concatenate([Gamma, prior * mu_prior])
        T, xi, raw = rls_weight_step(T, xi, Phi, Gamma, lam)
        new = constrain_weights(raw, constrain, T.T @ T if metric == "information" else None, ordering)
        if write_back:
            xi = T @ new
        return raw, new

    K = y.shape[0]
    xs, Ps, mus, raws = np.zeros((K, n)), np.zeros((K, n, n)), np.zeros((K, N)), np.zeros((K, N))
    x_prev = S_prev = None
    for k in range(K):
        raw = mu
        if form == "corrected":
            if x_prev is not None:
                Phi, Gamma, F, x_bar, S_pred = innovation_regressors(models, x_prev, S_prev, u[k - 1], u[k], y[k],
                                                                     mu, Q_sqrt, R_sqrt)
                raw, new = weight_update(Phi, Gamma)
                x_pred = x_bar + F @ (new - mu)
                if models.varying[0]:
                    S_pred = srkf_predict(x_prev, S_prev, models.blend(new)[0], Q_sqrt=Q_sqrt)[1]
                mu = new
            _, _, C, D = models.blend(mu)
            x_filt, S_filt, *_ = srkf_update(x_pred, S_pred, y[k], C, D, u[k], R_sqrt)
        else:
            A, B, C, D = models.blend(mu)
            x_filt, S_filt, x_free, S_next, *_ = srcf_step(x_pred, S_pred, y[k], A, C, D=D, u=u[k],
                                                           Q_sqrt=Q_sqrt, R_sqrt=R_sqrt)  # (2.29)–(2.32)
            if x_prev is not None:
                Phi, Gamma = weight_regressors(models, x_prev, u[k - 1], x_filt, u[k], y[k], weighting)
                raw, mu = weight_update(Phi, Gamma)
            B_used = models.blend(mu)[1] if b_after_weights else B
            x_pred, S_pred = x_free + B_used @ u[k], S_next
        xs[k], Ps[k], mus[k], raws[k] = x_filt, S_filt @ S_filt.T, mu, raw
        x_prev, S_prev = x_filt, S_filt
    return ConvexFilterResult(xs, Ps, mus, raws, models.names)
