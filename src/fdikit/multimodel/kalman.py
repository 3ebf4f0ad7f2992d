"""Discrete Kalman filter: covariance (Joseph) form and square-root (QR) form.

Model (Hallouzi 2008, (2.1)–(2.2) with the scheduling frozen; (2.3)–(2.4) for one mode)::

    x(k+1) = A x(k) + B u(k) + w(k),   w ~ N(0, Q)
    y(k)   = C x(k) + D u(k) + v(k),   v ~ N(0, R)

The step functions are the building blocks of the IMM filter (Hallouzi 2008, Table 2.1,
step 2 "mode-matched filtering") and of the dual convex-model filter (Table 2.2, step 1,
the square-root covariance filter (2.29)–(2.32)).  They are plain functions on arrays:

* :func:`kf_predict` / :func:`kf_update` — covariance form, Joseph-form update;
* :func:`srkf_predict` / :func:`srkf_update` — square-root twins on lower-triangular
  Cholesky factors ``S`` with ``S Sᵀ = P``;
* :func:`srcf_step` — the combined array (2.29)–(2.32) of Hallouzi 2008.

:func:`kalman_filter` runs a whole record and returns a :class:`KalmanResult`;
:class:`KalmanFilter` is the online twin (``step(u, y)``; a NaN measurement skips the
measurement update and marks the sample invalid).

Time convention: the filter starts from the prior ``x̂(0|−1) = x0``, ``P(0|−1) = P0``; at
sample ``k`` it first updates with ``y(k)`` (giving ``x̂(k|k)``) and then predicts with
``u(k)`` (giving ``x̂(k+1|k)``).  The innovation is ``e(k) = y(k) − C x̂(k|k−1) − D u(k)``
with covariance ``S(k) = C P(k|k−1) Cᵀ + R``; its Gaussian log-density is the mode
likelihood of Hallouzi 2008, (2.12), kept in the log domain.

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

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit.errors import DataError, ModelError
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel

__all__ = [
    "LinearGaussianModel",
    "KalmanResult",
    "KalmanStep",
    "KalmanFilter",
    "kf_predict",
    "kf_update",
    "srkf_predict",
    "srkf_update",
    "srcf_step",
    "psd_sqrt",
    "gaussian_log_likelihood",
    "kalman_filter",
]

_LOG_2PI = float(np.log(2.0 * np.pi))


# ---------------------------------------------------------------------------------------- helpers
def _as_matrix(name: str, value, rows: int | None = None, cols: int | None = None) -> np.ndarray:
    out = np.atleast_2d(np.asarray(value, dtype=float))
    if out.ndim != 2:
        raise ModelError(f"{name} must be a 2-D matrix, got an array with {out.ndim} dimensions")
    if rows is not None and out.shape[0] != rows:
        raise ModelError(f"{name} has shape {out.shape} but must have {rows} rows; give a {rows} x {cols} matrix")
    if cols is not None and out.shape[1] != cols:
        raise ModelError(f"{name} has shape {out.shape} but must have {cols} columns; give a {rows} x {cols} matrix")
    if not np.all(np.isfinite(out)):
        raise ModelError(f"{name} has a non-finite entry; every entry must be a finite number")
    return out


def _as_vector(name: str, value, size: int) -> np.ndarray:
    out = np.asarray(value, dtype=float).reshape(-1)
    if out.size != size:
        raise DataError(f"{name} has {out.size} entries but must have {size}; pass a vector of length {size}")
    return out


def _check_psd(name: str, M: np.ndarray) -> np.ndarray:
    """Symmetric part of ``M`` after checking symmetry and positive semi-definiteness."""
    scale = max(1.0, float(np.max(np.abs(M)))) if M.size else 1.0
    if M.shape[0] != M.shape[1]:
        raise ModelError(f"{name} must be square, got shape {M.shape}")
    if np.max(np.abs(M - M.T), initial=0.0) > 1e-8 * scale:
        raise ModelError(f"{name} is not symmetric; pass a symmetric covariance matrix (e.g. (M + M.T) / 2)")
    Ms = 0.5 * (M + M.T)
    if M.size:
        lam = float(np.linalg.eigvalsh(Ms)[0])
        if lam < -1e-10 * scale:
            raise ModelError(
                f"{name} is not positive semi-definite (smallest eigenvalue {lam:.3g}); "
                "a covariance matrix must have non-negative eigenvalues"
            )
    return Ms


def psd_sqrt(M, name: str = "covariance") -> np.ndarray:
    """Lower-triangular factor ``S`` with ``S Sᵀ = M`` of a symmetric PSD matrix.

    Cholesky when ``M`` is positive definite; otherwise the symmetric square root
    re-triangularised by a QR factorisation (so singular covariances are accepted).
    The diagonal of ``S`` is non-negative.

    Raises
    ------
    ModelError
        If ``M`` is not square, not symmetric or has a negative eigenvalue.

    Examples
    --------
    >>> psd_sqrt([[4.0, 2.0], [2.0, 2.0]])
    array([[2., 0.],
           [1., 1.]])
    """
    M = _check_psd(name, _as_matrix(name, M))
    try:
        return np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        lam, V = np.linalg.eigh(M)
        root = V * np.sqrt(np.clip(lam, 0.0, None))
        return _tria(root)


def _tria(M: np.ndarray) -> np.ndarray:
    """Lower-triangular ``L`` (non-negative diagonal) with ``L Lᵀ = M Mᵀ``, by QR of ``Mᵀ``."""
    r = np.linalg.qr(M.T, mode="r")
    rows = M.shape[0]
    L = r[:rows, :].T if r.shape[0] >= rows else np.hstack([r.T, np.zeros((rows, rows - r.shape[0]))])
    L = L[:, :rows]
    sign = np.where(np.diag(L) < 0, -1.0, 1.0)
    return L * sign


def gaussian_log_likelihood(innovation: np.ndarray, S_chol: np.ndarray) -> float:
    """``log N(e; 0, S)`` from the Cholesky factor of ``S`` (Hallouzi 2008, (2.12), log domain).

    Examples
    --------
    >>> round(gaussian_log_likelihood(np.zeros(1), np.eye(1)), 6)
    -0.918939
    """
    z = scipy.linalg.solve_triangular(S_chol, innovation, lower=True)
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
    K = scipy.linalg.cho_solve((S_chol, True), PCt.T).T
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
    """
    A = np.asarray(A, dtype=float)
    x_pred = A @ np.asarray(x, dtype=float) + _input_term(B, u, A.shape[0])
    pre = A @ np.asarray(S, dtype=float)
    if Q_sqrt is not None:
        pre = np.hstack([pre, np.asarray(Q_sqrt, dtype=float)])
    return x_pred, _tria(pre)


def srkf_update(
    x, S, y, C, D=None, u=None, R_sqrt=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Square-root measurement update by one QR factorisation (Hallouzi 2008, (2.29)–(2.30)).

    The pre-array ``[[R^{1/2}, C S], [0, S]]`` is lower-triangularised by an orthogonal
    transformation into ``[[R_e, 0], [G, S⁺]]``; then ``R_e R_eᵀ = C P Cᵀ + R``,
    ``G = P Cᵀ R_e⁻ᵀ``, ``x⁺ = x + G R_e⁻¹ e`` and ``S⁺ S⁺ᵀ = P − P Cᵀ (C P Cᵀ + R)⁻¹ C P``.

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
    """
    x = np.asarray(x, dtype=float)
    S = np.asarray(S, dtype=float)
    C = np.atleast_2d(np.asarray(C, dtype=float))
    p, n = C.shape
    Rs = np.zeros((p, p)) if R_sqrt is None else np.atleast_2d(np.asarray(R_sqrt, dtype=float))
    e = np.asarray(y, dtype=float).reshape(-1) - C @ x - _input_term(D, u, p)
    pre = np.block([[Rs, C @ S], [np.zeros((n, Rs.shape[1])), S]])
    post = _tria(pre)
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

    Returns
    -------
    x_filt, S_filt, x_next, S_next : ndarray
        ``x̂(k|k)``, ``S(k|k)``, ``x̂(k+1|k)``, ``S(k+1|k)``.
    innovation, R_e : ndarray
        ``e(k) = y − C x̂(k|k−1) − D u`` and the factor ``R_e`` of its covariance.
    log_likelihood : float
        ``log N(e; 0, R_e R_eᵀ)``.
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
    post = _tria(pre)
    Re = post[:p, :p]
    G1, S_filt = post[p : p + n, :p], post[p : p + n, p : p + n]
    G2, V = post[p + n :, :p], post[p + n :, p:]
    S_next = _tria(V)
    e = np.asarray(y, dtype=float).reshape(-1) - C @ x_pred - _input_term(D, u, p)
    z = scipy.linalg.solve_triangular(Re, e, lower=True)
    x_filt = x_pred + G1 @ z
    x_next = A @ x_pred + _input_term(B, u, n) + G2 @ z
    return x_filt, S_filt, x_next, S_next, e, Re, gaussian_log_likelihood(e, Re)


# ---------------------------------------------------------------------------------------- model + results
@dataclass(frozen=True, eq=False)
class LinearGaussianModel:
    """Discrete linear Gaussian model ``x⁺ = A x + B u + w``, ``y = C x + D u + v`` (Hallouzi 2008, (2.3)–(2.4)).

    ``Q = cov(w)`` (n x n) and ``R = cov(v)`` (p x p) are the state-space covariances
    (the thesis's ``(Q)^{1/2} w̄`` with unit-variance ``w̄``).  Build from a discrete
    :class:`~fdikit.model.FaultModel` with :meth:`from_fault_model` (uses ``A, Bu, C, Du``).
    ``name`` labels the model as one mode of a bank (the IMM's hypotheses).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    name: str = ""

    def __init__(self, A, C, Q, R, B=None, D=None, name: str = "") -> None:
        A = _as_matrix("A", A)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ModelError(f"A must be square, got shape {A.shape}")
        C = _as_matrix("C", C, cols=n)
        p = C.shape[0]
        B = np.zeros((n, 0)) if B is None else _as_matrix("B", B, rows=n)
        D = np.zeros((p, B.shape[1])) if D is None else _as_matrix("D", D, p, B.shape[1])
        Q = _check_psd("Q", _as_matrix("Q", Q, n, n))
        R = _check_psd("R", _as_matrix("R", R, p, p))
        if p and np.linalg.eigvalsh(R)[0] <= 1e-14 * max(1.0, float(np.max(np.abs(R)))):
            raise ModelError("R must be positive definite (the innovation covariance must be invertible)")
        object.__setattr__(self, "name", str(name))
        for key, val in zip("ABCDQR", (A, B, C, D, Q, R), strict=True):
            val = np.array(val)
            val.setflags(write=False)
            object.__setattr__(self, key, val)

    @classmethod
    def from_fault_model(cls, model: FaultModel, Q, R) -> LinearGaussianModel:
        """Take ``A, Bu, C, Du`` of a discrete ``FaultModel``; ``Q``, ``R`` are state/output covariances."""
        if not isinstance(model, FaultModel):
            raise ModelError(f"expected a FaultModel, got {type(model).__name__}")
        if not model.is_discrete:
            raise ModelError("the Kalman filter needs a discrete model; discretize it first (model.discretize(dt))")
        return cls(model.A, model.C, Q, R, B=model.Bu, D=model.Du)

    @property
    def n(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.C.shape[0]

    @property
    def m(self) -> int:
        """Number of inputs."""
        return self.B.shape[1]


@dataclass(frozen=True)
class KalmanStep:
    """One online step: filtered and next predicted estimates, innovation, validity."""

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    innovation: np.ndarray
    S: np.ndarray
    log_likelihood: float
    valid: bool


#: relative change of P(k+1|k) below which the batch runner switches to the steady-state filter
_SETTLED = 1e-14
_TINY = 1e-300


@dataclass(frozen=True)
class KalmanResult:
    """A filtered record of N samples.

    Attributes
    ----------
    x_filt, P_filt : ndarray
        ``x̂(k|k)`` (N x n) and ``P(k|k)`` (N x n x n).
    x_pred, P_pred : ndarray
        ``x̂(k+1|k)`` (N x n) and ``P(k+1|k)`` (N x n x n).
    innovations, S : ndarray
        ``e(k)`` (N x p) and its covariance (N x p x p); NaN on invalid samples.
    log_likelihood : ndarray
        ``log N(e(k); 0, S(k))`` (N); NaN on invalid samples.
    valid : ndarray of bool
        False where the measurement was missing and the update skipped.
    """

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    innovations: np.ndarray
    S: np.ndarray
    log_likelihood: np.ndarray
    valid: np.ndarray


def _as_model(model, Q=None, R=None) -> LinearGaussianModel:
    if isinstance(model, LinearGaussianModel):
        if Q is not None or R is not None:
            raise ModelError("Q and R are already in the LinearGaussianModel; do not pass them again")
        return model
    if isinstance(model, FaultModel):
        if Q is None or R is None:
            raise ModelError("a FaultModel carries no noise covariances; pass Q (n x n) and R (p x p)")
        return LinearGaussianModel.from_fault_model(model, Q, R)
    raise ModelError(f"model must be a LinearGaussianModel or a discrete FaultModel, got {type(model).__name__}")


class KalmanFilter:
    """Online Kalman filter; ``step(u, y)`` processes one sample (Hallouzi 2008, Table 2.1 step 2).

    Parameters
    ----------
    model : LinearGaussianModel or FaultModel
        The model; a discrete ``FaultModel`` needs ``Q`` and ``R``.
    x0, P0 : array_like
        Prior ``x̂(0|−1)``, ``P(0|−1)``.
    form : {"covariance", "square_root"}
        Joseph-form covariance filter or QR square-root filter (same numbers to rounding).
    Q, R : array_like, optional
        Covariances when ``model`` is a ``FaultModel``.

    Notes
    -----
    A measurement with a NaN entry skips the measurement update (``x̂(k|k) = x̂(k|k−1)``),
    the time update still runs, and the sample is marked invalid (innovation and
    log-likelihood NaN).  NaN in ``u`` raises :class:`~fdikit.errors.DataError`.
    """

    def __init__(self, model, x0, P0, *, form: str = "covariance", Q=None, R=None) -> None:
        if form not in ("covariance", "square_root"):
            raise ModelError(f"form must be 'covariance' or 'square_root', got {form!r}")
        self.model = _as_model(model, Q, R)
        n = self.model.n
        self.form = form
        self.x = _as_vector("x0", x0, n)
        P0 = _check_psd("P0", _as_matrix("P0", P0, n, n))
        self.P = P0
        self._S = psd_sqrt(P0, "P0")
        self._Qs = psd_sqrt(self.model.Q, "Q")
        self._Rs = psd_sqrt(self.model.R, "R")

    @property
    def P_sqrt(self) -> np.ndarray:
        """Lower-triangular factor of the current ``P(k|k−1)`` (propagated in the square-root form)."""
        return self._S if self.form == "square_root" else psd_sqrt(self.P, "P")

    def step(self, u, y) -> KalmanStep:
        """Update with ``y(k)``, predict with ``u(k)``; returns the :class:`KalmanStep`."""
        m = self.model
        u = _as_vector("u", np.zeros(0) if u is None else u, m.m)
        y = _as_vector("y", y, m.p)
        if not np.all(np.isfinite(u)):
            raise DataError("u has a NaN/inf entry; the time update needs every input (fill or drop the sample)")
        valid = bool(np.all(np.isfinite(y)))
        nan_p = np.full(m.p, np.nan)
        if self.form == "covariance":
            if valid:
                xf, Pf, e, S, ll = kf_update(self.x, self.P, y, m.C, m.D, u, m.R)
            else:
                xf, Pf, e, S, ll = self.x, self.P, nan_p, np.full((m.p, m.p), np.nan), float("nan")
            xp, Pp = kf_predict(xf, Pf, m.A, m.B, u, m.Q)
            self.x, self.P = xp, Pp
        else:
            if valid:
                xf, Sf, e, Re, ll = srkf_update(self.x, self._S, y, m.C, m.D, u, self._Rs)
                S = Re @ Re.T
            else:
                xf, Sf, e, S, ll = self.x, self._S, nan_p, np.full((m.p, m.p), np.nan), float("nan")
            xp, Sp = srkf_predict(xf, Sf, m.A, m.B, u, self._Qs)
            Pf, Pp = Sf @ Sf.T, Sp @ Sp.T
            self.x, self._S, self.P = xp, Sp, Pp
        return KalmanStep(xf, Pf, xp, Pp, e, S, ll, valid)


def _check_record(u, y, m: int, p: int) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(y, dtype=float)
    if y.ndim == 1 and p == 1:
        y = y.reshape(-1, 1)
    if y.ndim != 2 or y.shape[1] != p:
        raise DataError(f"y must be an N x {p} array, got shape {y.shape}")
    N = y.shape[0]
    if u is None:
        u = np.zeros((N, m))
    u = np.asarray(u, dtype=float)
    if u.ndim == 1 and m == 1:
        u = u.reshape(-1, 1)
    if u.ndim != 2 or u.shape != (N, m):
        raise DataError(f"u must be an N x {m} array with N = {N} (as y), got shape {u.shape}")
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        raise DataError(
            "u or y has NaN/inf entries; the batch filter refuses them — use KalmanFilter.step, which skips "
            "missing measurements"
        )
    return u, y


def kalman_filter(model, u, y, x0, P0, *, form: str = "covariance", Q=None, R=None) -> KalmanResult:
    """Run the Kalman filter over a record (batch twin of :class:`KalmanFilter`).

    Parameters
    ----------
    model : LinearGaussianModel or FaultModel
        The model; a discrete ``FaultModel`` needs ``Q`` and ``R``.
    u, y : array_like
        Inputs (N x m, or None if m = 0) and measurements (N x p); NaN is refused.
    x0, P0 : array_like
        Prior ``x̂(0|−1)``, ``P(0|−1)``.
    form : {"covariance", "square_root"}
        Filter implementation.

    Returns
    -------
    KalmanResult

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> res = kalman_filter(mdl, None, [[1.0], [0.5]], x0=[0.0], P0=[[1.0]])
    >>> res.x_filt.shape, res.valid.tolist()
    ((2, 1), [True, True])
    """
    kf = KalmanFilter(model, x0, P0, form=form, Q=Q, R=R)
    u, y = _check_record(u, y, kf.model.m, kf.model.p)
    steps, settled = [], 0
    for k, (uk, yk) in enumerate(zip(u, y, strict=True)):
        P_before = kf.P
        steps.append(kf.step(uk, yk))
        if form == "covariance":
            change = np.abs(kf.P - P_before).max()
            settled = settled + 1 if change <= _SETTLED * max(np.abs(kf.P).max(), _TINY) else 0
            if settled >= 3 and k + 1 < len(y):
                return _stack_results(_collect(steps, kf.model.n, kf.model.p),
                                      _steady_run(kf, u[k + 1:], y[k + 1:]))
    return _collect(steps, kf.model.n, kf.model.p)


def _steady_run(kf: KalmanFilter, u: np.ndarray, y: np.ndarray) -> KalmanResult:
    """The rest of the record once ``P(k+1|k)`` has settled: a time-invariant filter, run by the blocked solver.

    With ``P`` constant the gain ``K = P Cᵀ S⁻¹`` is constant and the predictor
    ``x̂(k+1|k) = A(I − KC) x̂ + (B − AKD) u + AK y`` is an LTI system of ``[u; y]``; its innovation
    ``e = −C x̂ − D u + y`` and filtered state ``x̂(k|k) = (I − KC) x̂ − KD u + K y`` are outputs.  Equal to the
    step-by-step recursion to round-off (the covariance has stopped changing to ``_SETTLED``).
    """
    m = kf.model
    n, p, N = m.n, m.p, y.shape[0]
    B, D, P = m.B, m.D, kf.P
    S = m.C @ P @ m.C.T + m.R
    S = 0.5 * (S + S.T)
    K = np.linalg.solve(S, m.C @ P).T
    IKC = np.eye(n) - K @ m.C
    A_f = m.A @ IKC
    B_f = np.hstack([B - m.A @ K @ D, m.A @ K])
    C_f = np.vstack([-m.C, IKC])
    D_f = np.block([[-D, np.eye(p)], [-K @ D, K]])
    v = np.hstack([u.reshape(N, -1), y])
    out, states, x_end = dlsim_blocked(A_f, B_f, C_f, D_f, v, kf.x)
    e, x_filt = out[:, :p], out[:, p:]
    L = np.linalg.cholesky(S)
    w = scipy.linalg.solve_triangular(L, e.T, lower=True)
    ll = -0.5 * (np.sum(w * w, axis=0) + p * np.log(2 * np.pi)) - np.sum(np.log(np.diag(L)))
    P_filt = IKC @ P @ IKC.T + K @ m.R @ K.T
    kf.x = x_end
    return KalmanResult(
        x_filt=x_filt,
        P_filt=np.broadcast_to(P_filt, (N, n, n)).copy(),
        x_pred=np.vstack([states[1:], x_end]),
        P_pred=np.broadcast_to(P, (N, n, n)).copy(),
        innovations=e,
        S=np.broadcast_to(S, (N, p, p)).copy(),
        log_likelihood=ll,
        valid=np.ones(N, bool),
    )


def _stack_results(first: KalmanResult, rest: KalmanResult) -> KalmanResult:
    return KalmanResult(**{f: np.concatenate([getattr(first, f), getattr(rest, f)])
                           for f in KalmanResult.__dataclass_fields__})


def _collect(steps: list[KalmanStep], n: int, p: int) -> KalmanResult:
    def stack(attr, shape):
        vals = [getattr(s, attr) for s in steps]
        return np.array(vals, dtype=float).reshape((len(steps), *shape))

    return KalmanResult(
        x_filt=stack("x_filt", (n,)),
        P_filt=stack("P_filt", (n, n)),
        x_pred=stack("x_pred", (n,)),
        P_pred=stack("P_pred", (n, n)),
        innovations=stack("innovation", (p,)),
        S=stack("S", (p, p)),
        log_likelihood=np.array([s.log_likelihood for s in steps], dtype=float),
        valid=np.array([s.valid for s in steps], dtype=bool),
    )
