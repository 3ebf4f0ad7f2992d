"""Kalman-filter steps on arrays: covariance (Joseph) form and square-root (QR) form.

Model (Hallouzi 2008, (2.3)–(2.4) for one mode): ``x(k+1) = A x + B u + w``, ``y = C x + D u + v`` with
``w ~ N(0, Q)``, ``v ~ N(0, R)``.  These plain functions are the building blocks of
:mod:`fdikit.multimodel.kalman` (one model), the IMM filter (Table 2.1, step 2 "mode-matched
filtering") and the dual convex-model filter (Table 2.2, step 1, the square-root covariance filter
(2.29)–(2.32)):

* :func:`kf_predict` / :func:`kf_update` — covariance form, Joseph-form update;
* :func:`srkf_predict` / :func:`srkf_update` — square-root twins on lower-triangular Cholesky factors
  ``S`` with ``S Sᵀ = P``;
* :func:`srcf_step` — the combined array (2.29)–(2.32) of Hallouzi 2008.

The innovation ``e = y − C x̂(k|k−1) − D u`` has covariance ``S = C P(k|k−1) Cᵀ + R``; its Gaussian
log-density is the mode likelihood (2.12), kept in the log domain.

Examples
--------
>>> import numpy as np
>>> A, C = np.array([[0.9]]), np.array([[1.0]])
>>> x, P = kf_predict(np.zeros(1), np.eye(1), A, Q=0.1 * np.eye(1))
>>> float(P[0, 0])
0.91
>>> x, P, e, S, ll = kf_update(x, P, np.array([1.0]), C, R=np.eye(1))
>>> round(float(x[0]), 6), round(float(S[0, 0]), 2)
(0.47644, 1.91)
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DataError, ModelError

__all__ = ["kf_predict", "kf_update", "srkf_predict", "srkf_update", "srcf_step", "psd_sqrt", "gaussian_log_likelihood"]

_LOG_2PI = float(np.log(2.0 * np.pi))


# ---------------------------------------------------------------------------------------- helpers
def psd_sqrt(M, name: str = "covariance") -> np.ndarray:
    """Lower-triangular factor ``S`` with ``S Sᵀ = M`` of a symmetric PSD matrix.

    Cholesky when ``M`` is positive definite; otherwise the symmetric square root
    re-triangularised by a QR factorisation (so singular covariances are accepted).
    The diagonal of ``S`` is non-negative.

    Parameters
    ----------
    M : array_like
        Symmetric positive semidefinite matrix (n x n), e.g. a covariance ``Q`` or ``P``.
    name : str, optional
        Name of the matrix in error messages (default ``"covariance"``).

    Returns
    -------
    ndarray
        Lower-triangular ``S`` (n x n) with ``S Sᵀ = M``.

    Raises
    ------
    ModelError
        If ``M`` is not square, not symmetric or has a negative eigenvalue.

    Examples
    --------
    >>> psd_sqrt([[4.0, 2.0], [2.0, 2.0]])
    array([[2., 0.],
           [1., 1.]])

    References
    ----------
    Hallouzi 2008, §2.3.2, (2.25)–(2.26): the factors ``S`` with ``S Sᵀ = P`` of the square-root filter.
    """
    M = validate.psd_part(name, validate.as_matrix(name, M, error=ModelError, promote=True), error=ModelError)
    try:
        return np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        lam, V = np.linalg.eigh(M)
        root = V * np.sqrt(np.clip(lam, 0.0, None))
        return tria(root)


def tria(M: np.ndarray) -> np.ndarray:
    """Lower-triangular ``L`` (non-negative diagonal) with ``L Lᵀ = M Mᵀ``, by QR of ``Mᵀ``."""
    r = np.linalg.qr(M.T, mode="r")
    rows = M.shape[0]
    L = r[:rows, :].T if r.shape[0] >= rows else np.hstack([r.T, np.zeros((rows, rows - r.shape[0]))])
    L = L[:, :rows]
    sign = np.where(np.diag(L) < 0, -1.0, 1.0)
    return L * sign


def gaussian_log_likelihood(innovation: np.ndarray, S_chol: np.ndarray) -> float:
    """``log N(e; 0, S)`` from the Cholesky factor of ``S`` (Hallouzi 2008, (2.12), log domain).

    Parameters
    ----------
    innovation : ndarray
        Innovation ``e`` (p).
    S_chol : ndarray
        Lower-triangular factor of the innovation covariance (p x p), ``S_chol S_cholᵀ = S``.

    Returns
    -------
    float
        ``−½ (eᵀ S⁻¹ e + log det S + p log 2π)``.

    Examples
    --------
    >>> round(gaussian_log_likelihood(np.zeros(1), np.eye(1)), 6)
    -0.918939

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 3, (2.12) (the mode likelihood).
    """
    z = np.linalg.solve(S_chol, innovation)  # triangular; numpy's solve avoids scipy's per-call checks
    logdet = 2.0 * float(np.sum(np.log(np.abs(np.diag(S_chol)))))
    return float(-0.5 * (z @ z + logdet + innovation.size * _LOG_2PI))


def _input_term(B, u, rows: int) -> np.ndarray:
    if B is None or u is None:
        return np.zeros(rows)
    B = np.atleast_2d(np.asarray(B, dtype=float))
    u = np.asarray(u, dtype=float).reshape(-1)
    if B.shape[1] != u.size:
        raise DataError(f"u has {u.size} entries but the input matrix has {B.shape[1]} columns")
    return B @ u


# ---------------------------------------------------------------------------------------- covariance form
def kf_predict(x, P, A, B=None, u=None, Q=None) -> tuple[np.ndarray, np.ndarray]:
    """Time update ``x⁺ = A x + B u``, ``P⁺ = A P Aᵀ + Q`` (Hallouzi 2008, Table 2.1, step 2).

    Parameters
    ----------
    x, P : array_like
        Filtered state ``x̂(k|k)`` (n) and covariance ``P(k|k)`` (n x n).
    A, B : array_like
        State and input matrices; ``B``/``u`` may be omitted (no input).
    u : array_like, optional
        Input ``u(k)``.
    Q : array_like, optional
        Process noise covariance (n x n); zero if omitted.

    Returns
    -------
    x_pred, P_pred : ndarray
        ``x̂(k+1|k)`` and the symmetrised ``P(k+1|k)``.

    Examples
    --------
    >>> x, P = kf_predict(np.zeros(1), np.eye(1), [[0.9]], Q=0.1 * np.eye(1))
    >>> x.tolist(), P.round(6).tolist()
    ([0.0], [[0.91]])

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2 (mode-matched filtering).
    """
    A = np.asarray(A, dtype=float)
    x = np.asarray(x, dtype=float)
    x_pred = A @ x + _input_term(B, u, A.shape[0])
    P_pred = A @ np.asarray(P, dtype=float) @ A.T
    if Q is not None:
        P_pred = P_pred + np.asarray(Q, dtype=float)
    return x_pred, 0.5 * (P_pred + P_pred.T)


def kf_update(x, P, y, C, D=None, u=None, R=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Measurement update in Joseph form (Hallouzi 2008, Table 2.1, step 2, and (2.12)).

    ``e = y − C x − D u``, ``S = C P Cᵀ + R``, ``K = P Cᵀ S⁻¹``, ``x⁺ = x + K e`` and
    ``P⁺ = (I − K C) P (I − K C)ᵀ + K R Kᵀ`` (Joseph form: equal to Table 2.1's
    ``P − K S Kᵀ`` in exact arithmetic, but symmetric and PSD in floating point).

    Parameters
    ----------
    x, P : array_like
        Predicted state ``x̂(k|k−1)`` (n) and covariance ``P(k|k−1)`` (n x n).
    y : array_like
        Measurement ``y(k)`` (p).
    C, D : array_like
        Output and feedthrough matrices; ``D``/``u`` may be omitted (no feedthrough).
    u : array_like, optional
        Input ``u(k)``.
    R : array_like, optional
        Measurement noise covariance (p x p); zero if omitted (then ``C P Cᵀ`` must be nonsingular).

    Returns
    -------
    x_filt, P_filt : ndarray
        ``x̂(k|k)``, ``P(k|k)``.
    innovation : ndarray
        ``e(k)`` (p).
    S : ndarray
        Innovation covariance (p x p).
    log_likelihood : float
        ``log N(e; 0, S)``; ``exp`` of it is the mode likelihood ``L`` of (2.12).

    Raises
    ------
    DataError
        If the innovation covariance ``C P Cᵀ + R`` is not positive definite, or ``u`` does not match ``D``.

    Examples
    --------
    >>> x, P, e, S, ll = kf_update(np.zeros(1), np.eye(1), [1.0], [[1.0]], R=np.eye(1))
    >>> x.tolist(), P.round(6).tolist(), S.tolist(), round(ll, 6)
    ([0.5], [[0.5]], [[2.0]], -1.515512)

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 steps 2–3, (2.12).
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    C = np.atleast_2d(np.asarray(C, dtype=float))
    R = np.zeros((C.shape[0], C.shape[0])) if R is None else np.atleast_2d(np.asarray(R, dtype=float))
    e = np.asarray(y, dtype=float).reshape(-1) - C @ x - _input_term(D, u, C.shape[0])
    PCt = P @ C.T
    S = C @ PCt + R
    S = 0.5 * (S + S.T)
    try:
        S_chol = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        raise DataError(
            "the innovation covariance C P Cᵀ + R is singular; give R positive definite"
        ) from None
    K = np.linalg.solve(S, PCt.T).T  # S is p x p and positive definite (checked by the Cholesky above)
    x_filt = x + K @ e
    IKC = np.eye(x.size) - K @ C
    P_filt = IKC @ P @ IKC.T + K @ R @ K.T
    return x_filt, 0.5 * (P_filt + P_filt.T), e, S, gaussian_log_likelihood(e, S_chol)


# ---------------------------------------------------------------------------------------- square-root form
def srkf_predict(x, S, A, B=None, u=None, Q_sqrt=None) -> tuple[np.ndarray, np.ndarray]:
    """Square-root time update: ``S⁺ = tria([A S, Q^{1/2}])`` (Hallouzi 2008, (2.31)).

    ``tria`` is the lower-triangular factor from a QR factorisation of the transposed
    pre-array, so ``S⁺ S⁺ᵀ = A S Sᵀ Aᵀ + Q`` without forming ``P``.

    Parameters
    ----------
    x, S : array_like
        ``x̂(k|k)`` and a factor ``S(k|k)`` with ``S Sᵀ = P(k|k)``.
    A, B, u : array_like
        As in :func:`kf_predict`.
    Q_sqrt : array_like, optional
        Any factor ``Q^{1/2}`` with ``Q^{1/2} Q^{1/2}ᵀ = Q`` (see :func:`psd_sqrt`).

    Returns
    -------
    x_pred, S_pred : ndarray
        ``x̂(k+1|k)`` and lower-triangular ``S(k+1|k)``.

    Examples
    --------
    >>> x, S = srkf_predict(np.zeros(1), np.eye(1), [[0.9]], Q_sqrt=[[0.3]])
    >>> (S @ S.T).round(6).tolist()
    [[0.9]]

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2 step 1, (2.29), (2.31).
    """
    A = np.asarray(A, dtype=float)
    x_pred = A @ np.asarray(x, dtype=float) + _input_term(B, u, A.shape[0])
    pre = A @ np.asarray(S, dtype=float)
    if Q_sqrt is not None:
        pre = np.hstack([pre, np.asarray(Q_sqrt, dtype=float)])
    return x_pred, tria(pre)


def srkf_update(
    x, S, y, C, D=None, u=None, R_sqrt=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Square-root measurement update by one QR factorisation (Hallouzi 2008, (2.29)–(2.30)).

    The pre-array ``[[R^{1/2}, C S], [0, S]]`` is lower-triangularised by an orthogonal
    transformation into ``[[R_e, 0], [G, S⁺]]``; then ``R_e R_eᵀ = C P Cᵀ + R``,
    ``G = P Cᵀ R_e⁻ᵀ``, ``x⁺ = x + G R_e⁻¹ e`` and ``S⁺ S⁺ᵀ = P − P Cᵀ (C P Cᵀ + R)⁻¹ C P``.

    Parameters
    ----------
    x, S : array_like
        ``x̂(k|k−1)`` (n) and a factor ``S(k|k−1)`` (n x n) with ``S Sᵀ = P(k|k−1)``.
    y : array_like
        Measurement ``y(k)`` (p).
    C, D, u : array_like
        As in :func:`kf_update`.
    R_sqrt : array_like, optional
        A factor ``R^{1/2}`` (p x p) of the measurement noise covariance; zero if omitted.

    Returns
    -------
    x_filt, S_filt : ndarray
        ``x̂(k|k)`` and the lower-triangular factor of ``P(k|k)``.
    innovation : ndarray
        ``e(k)``.
    R_e : ndarray
        Lower-triangular factor of the innovation covariance (``R_e R_eᵀ = S``).
    log_likelihood : float
        ``log N(e; 0, R_e R_eᵀ)``.

    Raises
    ------
    DataError
        If the innovation covariance is singular (a zero diagonal entry of ``R_e``), or ``u`` does not match ``D``.

    Examples
    --------
    >>> x, S, e, Re, ll = srkf_update(np.zeros(1), np.eye(1), [1.0], [[1.0]], R_sqrt=np.eye(1))
    >>> x.round(6).tolist(), (S @ S.T).round(6).tolist(), (Re @ Re.T).round(6).tolist(), round(ll, 6)
    ([0.5], [[0.5]], [[2.0]], -1.515512)

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2 step 1, (2.29)–(2.30).
    """
    x = np.asarray(x, dtype=float)
    S = np.asarray(S, dtype=float)
    C = np.atleast_2d(np.asarray(C, dtype=float))
    p, n = C.shape
    Rs = np.zeros((p, p)) if R_sqrt is None else np.atleast_2d(np.asarray(R_sqrt, dtype=float))
    e = np.asarray(y, dtype=float).reshape(-1) - C @ x - _input_term(D, u, p)
    pre = np.block([[Rs, C @ S], [np.zeros((n, Rs.shape[1])), S]])
    post = tria(pre)
    Re, G, S_filt = post[:p, :p], post[p:, :p], post[p:, p:]
    if np.min(np.abs(np.diag(Re)), initial=np.inf) <= 1e-300:
        raise DataError("the innovation covariance C P Cᵀ + R is singular; give R positive definite")
    z = scipy.linalg.solve_triangular(Re, e, lower=True)
    return x + G @ z, S_filt, e, Re, gaussian_log_likelihood(e, Re)


def srcf_step(
    x_pred, S_pred, y, A, C, B=None, D=None, u=None, Q_sqrt=None, R_sqrt=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """One square-root covariance filter iteration, Hallouzi 2008, Table 2.2 step 1, (2.29)–(2.32).

    One QR factorisation of the pre-array (2.29) ``[[C S, −R^{1/2}, 0], [S, 0, 0], [A S, 0, Q^{1/2}]]``
    gives ``R_e``, ``G₁``, ``S(k|k)``, ``G₂`` and ``[V₁ V₂]``; (2.31) re-triangularises
    ``[V₁ V₂]`` into ``S(k+1|k)``.  (2.30), (2.32) give the filtered and predicted states.
    The residual sign of (2.30)/(2.32), ``C x̂ + D u − y``, is written here as ``−e``.

    Parameters
    ----------
    x_pred, S_pred : array_like
        ``x̂(k|k−1)`` (n) and a factor ``S(k|k−1)`` (n x n) of its covariance.
    y : array_like
        Measurement ``y(k)`` (p).
    A, C : array_like
        State (n x n) and output (p x n) matrices.
    B, D, u : array_like, optional
        Input, feedthrough matrices and input ``u(k)``; the input terms are dropped when omitted.
    Q_sqrt, R_sqrt : array_like, optional
        Factors of the process (n x n) and measurement (p x p) noise covariances; zero if omitted.

    Returns
    -------
    x_filt, S_filt, x_next, S_next : ndarray
        ``x̂(k|k)``, ``S(k|k)``, ``x̂(k+1|k)``, ``S(k+1|k)``.
    innovation, R_e : ndarray
        ``e(k) = y − C x̂(k|k−1) − D u`` and the factor ``R_e`` of its covariance.
    log_likelihood : float
        ``log N(e; 0, R_e R_eᵀ)``.

    Examples
    --------
    >>> out = srcf_step(np.zeros(1), np.eye(1), [1.0], [[0.9]], [[1.0]], Q_sqrt=[[0.3]], R_sqrt=[[1.0]])
    >>> x_filt, S_filt, x_next, S_next, e, Re, ll = out
    >>> x_filt.round(6).tolist(), x_next.round(6).tolist(), (S_next @ S_next.T).round(6).tolist()
    ([0.5], [0.45], [[0.495]])

    References
    ----------
    Hallouzi 2008, §2.3.2, Table 2.2 step 1, (2.29)–(2.32).
    """
    A = np.asarray(A, dtype=float)
    C = np.atleast_2d(np.asarray(C, dtype=float))
    S_pred = np.asarray(S_pred, dtype=float)
    x_pred = np.asarray(x_pred, dtype=float)
    p, n = C.shape
    Rs = np.zeros((p, p)) if R_sqrt is None else np.atleast_2d(np.asarray(R_sqrt, dtype=float))
    Qs = np.zeros((n, n)) if Q_sqrt is None else np.atleast_2d(np.asarray(Q_sqrt, dtype=float))
    pre = np.block(
        [
            [C @ S_pred, -Rs, np.zeros((p, Qs.shape[1]))],
            [S_pred, np.zeros((n, Rs.shape[1])), np.zeros((n, Qs.shape[1]))],
            [A @ S_pred, np.zeros((n, Rs.shape[1])), Qs],
        ]
    )
    post = tria(pre)
    Re = post[:p, :p]
    G1, S_filt = post[p : p + n, :p], post[p : p + n, p : p + n]
    G2, V = post[p + n :, :p], post[p + n :, p:]
    S_next = tria(V)
    e = np.asarray(y, dtype=float).reshape(-1) - C @ x_pred - _input_term(D, u, p)
    z = scipy.linalg.solve_triangular(Re, e, lower=True)
    x_filt = x_pred + G1 @ z
    x_next = A @ x_pred + _input_term(B, u, n) + G2 @ z
    return x_filt, S_filt, x_next, S_next, e, Re, gaussian_log_likelihood(e, Re)
