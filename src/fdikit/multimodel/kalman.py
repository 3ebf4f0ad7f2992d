"""Discrete Kalman filter for one linear Gaussian model: batch runner and online filter.

Model (Hallouzi 2008, (2.1)–(2.2) with the scheduling frozen; (2.3)–(2.4) for one mode)::

    x(k+1) = A x(k) + B u(k) + w(k),   w ~ N(0, Q)
    y(k)   = C x(k) + D u(k) + v(k),   v ~ N(0, R)

in covariance (Joseph) or square-root (QR) form, built from the steps of
:mod:`fdikit.multimodel.kalman_steps`.  :func:`kalman_filter` runs a whole record and returns a
:class:`KalmanResult` (once ``P(k+1|k)`` has settled it runs the rest as the time-invariant
steady-state filter through the blocked solver, equal to the recursion to round-off);
:class:`KalmanFilter` is the online twin (``step(u, y)``; a NaN measurement skips the measurement
update and marks the sample invalid).

Time convention: the filter starts from the prior ``x̂(0|−1) = x0``, ``P(0|−1) = P0``; at sample ``k`` it
first updates with ``y(k)`` (giving ``x̂(k|k)``) and then predicts with ``u(k)`` (giving ``x̂(k+1|k)``).

Examples
--------
>>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
>>> kalman_filter(mdl, None, [[1.0], [0.5]], x0=[0.0], P0=[[1.0]]).x_filt.shape
(2, 1)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.gaussian import LinearGaussianModel
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.multimodel.kalman_steps import (
    kf_predict,
    kf_update,
    psd_sqrt,
    srkf_predict,
    srkf_update,
)

__all__ = ["KalmanResult", "KalmanStep", "KalmanFilter", "kalman_filter"]


# ---------------------------------------------------------------------------------------- model + results
@dataclass(frozen=True)
class KalmanStep:
    """One online step: filtered and next predicted estimates, innovation, validity.

    Attributes
    ----------
    x_filt, P_filt : ndarray
        ``x̂(k|k)`` (n) and ``P(k|k)`` (n x n).
    x_pred, P_pred : ndarray
        ``x̂(k+1|k)`` (n) and ``P(k+1|k)`` (n x n).
    innovation : ndarray
        ``e(k) = y(k) − C x̂(k|k−1) − D u(k)`` (p); NaN when the sample is invalid.
    S : ndarray
        Innovation covariance ``C P(k|k−1) Cᵀ + R`` (p x p); NaN when the sample is invalid.
    log_likelihood : float
        ``log N(e(k); 0, S)``; NaN when the sample is invalid.
    valid : bool
        False when the measurement had a NaN entry and the update was skipped.

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> s = KalmanFilter(mdl, x0=[0.0], P0=[[1.0]]).step(None, [1.0])
    >>> s.x_filt.tolist(), s.x_pred.tolist(), s.valid
    ([0.5], [0.45], True)

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2, (2.12).
    """

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    innovation: np.ndarray
    S: np.ndarray
    log_likelihood: float
    valid: bool


#: relative change of P(k+1|k) below which the filter switches to the steady-state filter
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

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> res = kalman_filter(mdl, None, [[1.0], [0.5]], x0=[0.0], P0=[[1.0]])
    >>> res.innovations.round(6).tolist(), res.P_pred.shape
    ([[1.0], [0.05]], (2, 1, 1))

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2, (2.12).
    """

    x_filt: np.ndarray
    P_filt: np.ndarray
    x_pred: np.ndarray
    P_pred: np.ndarray
    innovations: np.ndarray
    S: np.ndarray
    log_likelihood: np.ndarray
    valid: np.ndarray

    def plot(self, ax=None, **kwargs):
        """Draw the innovations with their ``±2σ`` bands (:func:`fdikit.plots.plot_innovations`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw into it; default a new figure.
        **kwargs
            ``t``, ``names``, ``sigmas``, ``title`` and ``path`` of :func:`~fdikit.plots.plot_innovations`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
        >>> fig, ax = plt.subplots()
        >>> kalman_filter(mdl, None, [[1.0], [0.5]], x0=[0.0], P0=[[1.0]]).plot(ax=ax) is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_innovations

        return plot_innovations(self, ax=ax, **kwargs)


def _as_model(model, Q=None, R=None) -> LinearGaussianModel:
    if isinstance(model, LinearGaussianModel):
        if Q is not None or R is not None:
            raise ParameterError("Q and R are already in the LinearGaussianModel; do not pass them again")
        return model
    if isinstance(model, FaultModel):
        if Q is None or R is None:
            raise ParameterError("a FaultModel carries no noise covariances; pass Q (n x n) and R (p x p)")
        return LinearGaussianModel.from_fault_model(model, Q, R)
    raise ParameterError(f"model must be a LinearGaussianModel or a discrete FaultModel, got {type(model).__name__}")


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

    Raises
    ------
    ParameterError
        On an unknown ``form``, ``Q``/``R`` missing for a ``FaultModel`` or given twice for a
        ``LinearGaussianModel``, or a prior of the wrong size.

    Notes
    -----
    A measurement with a NaN entry skips the measurement update (``x̂(k|k) = x̂(k|k−1)``),
    the time update still runs, and the sample is marked invalid (innovation and
    log-likelihood NaN).  NaN in ``u`` raises :class:`~fdikit.errors.DataError`.

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> kf = KalmanFilter(mdl, x0=[0.0], P0=[[1.0]])
    >>> kf.step(None, [1.0]).x_filt.tolist()
    [0.5]
    >>> s = kf.step(None, [float("nan")])        # missing measurement: prediction only
    >>> s.valid, s.x_filt.tolist(), s.x_pred.round(6).tolist()
    (False, [0.45], [0.405])

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2; §2.3.2, (2.29)–(2.31) for the square-root form.
    """

    def __init__(self, model, x0, P0, *, form: str = "covariance", Q=None, R=None) -> None:
        if form not in ("covariance", "square_root"):
            raise ParameterError(f"form must be 'covariance' or 'square_root', got {form!r}")
        self.model = _as_model(model, Q, R)
        n = self.model.n
        self.form = form
        self.x = validate.as_vector("x0", x0, n, error=ParameterError)
        P0 = validate.as_matrix("P0", P0, (n, n), error=ParameterError, promote=True)
        P0 = validate.psd_part("P0", P0, error=ParameterError)
        self.P = P0
        self._S = psd_sqrt(P0, "P0")
        self._Qs = psd_sqrt(self.model.Q, "Q")
        self._Rs = psd_sqrt(self.model.R, "R")
        self._settled = 0
        self._steady: tuple | None = None

    @property
    def P_sqrt(self) -> np.ndarray:
        """Lower-triangular factor of the current ``P(k|k−1)`` (propagated in the square-root form)."""
        return self._S if self.form == "square_root" else psd_sqrt(self.P, "P")

    def step(self, u, y) -> KalmanStep:
        """Update with ``y(k)``, predict with ``u(k)``; returns the :class:`KalmanStep`."""
        m = self.model
        u = validate.as_vector("u", np.zeros(0) if u is None else u, m.m, error=DataError, finite=False)
        y = validate.as_vector("y", y, m.p, error=DataError, finite=False)
        if not np.all(np.isfinite(u)):
            raise DataError("u has a NaN/inf entry; the time update needs every input (fill or drop the sample)")
        valid = bool(np.all(np.isfinite(y)))
        if valid and self._steady is not None:
            return self._steady_step(u, y)
        nan_p = np.full(m.p, np.nan)
        P_before = self.P
        if self.form == "covariance":
            if valid:
                xf, Pf, e, S, ll = kf_update(self.x, self.P, y, m.C, m.D, u, m.R)
            else:
                xf, Pf, e, S, ll = self.x, self.P, nan_p, np.full((m.p, m.p), np.nan), float("nan")
            xp, Pp = kf_predict(xf, Pf, m.A, m.B, u, m.Q)
            self.x, self.P = xp, Pp
            self._track_settling(P_before, valid)
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

    def _track_settling(self, P_before: np.ndarray, valid: bool) -> None:
        """Covariance form: after 3 valid steps with ``P(k+1|k)`` unchanged to ``_SETTLED``, cache the steady filter."""
        change = np.abs(self.P - P_before).max()
        ok = valid and change <= _SETTLED * max(np.abs(self.P).max(), _TINY)
        self._settled = self._settled + 1 if ok else 0
        if not ok:
            self._steady = None  # e.g. a skipped measurement: P moves again, back to the recursion
        elif self._settled >= 3 and self._steady is None:
            m, P = self.model, self.P
            S = m.C @ P @ m.C.T + m.R
            S = 0.5 * (S + S.T)
            K = np.linalg.solve(S, m.C @ P).T
            IKC = np.eye(m.n) - K @ m.C
            Pf = IKC @ P @ IKC.T + K @ m.R @ K.T
            L = np.linalg.cholesky(S)
            const = -0.5 * m.p * np.log(2 * np.pi) - float(np.sum(np.log(np.diag(L))))
            cached = [0.5 * (Pf + Pf.T), P.copy(), S]
            for arr in cached:
                arr.setflags(write=False)
            self._steady = (K, np.linalg.inv(L), const, *cached)

    def _steady_step(self, u: np.ndarray, y: np.ndarray) -> KalmanStep:
        """Once ``P`` has settled: the constant-gain update, equal to the recursion to round-off (about 4x faster)."""
        m = self.model
        K, L_inv, const, Pf, Pp, S = self._steady
        e = y - m.C @ self.x - m.D @ u
        xf = self.x + K @ e
        xp = m.A @ xf + m.B @ u
        w = L_inv @ e
        self.x = xp
        return KalmanStep(xf, Pf, xp, Pp, e, S, float(const - 0.5 * (w @ w)), True)


def check_record(u, y, m: int, p: int) -> tuple[np.ndarray, np.ndarray]:
    y = validate.as_array("y", y, error=DataError, finite=False)
    if y.ndim == 1 and p == 1:
        y = y.reshape(-1, 1)
    if y.ndim != 2 or y.shape[1] != p:
        raise DataError(f"y must be an N x {p} array, got shape {y.shape}")
    N = y.shape[0]
    if u is None:
        u = np.zeros((N, m))
    u = validate.as_array("u", u, error=DataError, finite=False)
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
        Filter implementation (default ``"covariance"``).
    Q, R : array_like, optional
        Process (n x n) and measurement (p x p) noise covariances when ``model`` is a ``FaultModel``.

    Returns
    -------
    KalmanResult
        The filtered record; see :class:`KalmanResult`.

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> res = kalman_filter(mdl, None, [[1.0], [0.5]], x0=[0.0], P0=[[1.0]])
    >>> res.x_filt.shape, res.valid.tolist()
    ((2, 1), [True, True])

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2, (2.12).
    """
    kf = KalmanFilter(model, x0, P0, form=form, Q=Q, R=R)
    u, y = check_record(u, y, kf.model.m, kf.model.p)
    steps = []
    for k, (uk, yk) in enumerate(zip(u, y, strict=True)):
        steps.append(kf.step(uk, yk))
        if kf._steady is not None and k + 1 < len(y):  # P(k+1|k) has settled (KalmanFilter._track_settling)
            return _stack_results(collect_steps(steps, kf.model.n, kf.model.p), _steady_run(kf, u[k + 1:], y[k + 1:]))
    return collect_steps(steps, kf.model.n, kf.model.p)


def _steady_run(kf: KalmanFilter, u: np.ndarray, y: np.ndarray) -> KalmanResult:
    """The rest of the record once ``P(k+1|k)`` has settled: a time-invariant filter, run by the blocked solver.

    With ``P`` constant the gain ``K = P Cᵀ S⁻¹`` is constant and the predictor
    ``x̂(k+1|k) = A(I − KC) x̂ + (B − AKD) u + AK y`` is an LTI system of ``[u; y]``; its innovation
    ``e = −C x̂ − D u + y`` and filtered state ``x̂(k|k) = (I − KC) x̂ − KD u + K y`` are outputs.  Equal to the
    step-by-step recursion to round-off (the covariance has stopped changing to ``_SETTLED``).
    """
    m = kf.model
    n, p, N = m.n, m.p, y.shape[0]
    B, D = m.B, m.D
    K, L_inv, const, P_filt, P, S = kf._steady
    IKC = np.eye(n) - K @ m.C
    A_f = m.A @ IKC
    B_f = np.hstack([B - m.A @ K @ D, m.A @ K])
    C_f = np.vstack([-m.C, IKC])
    D_f = np.block([[-D, np.eye(p)], [-K @ D, K]])
    v = np.hstack([u.reshape(N, -1), y])
    out, states, x_end = dlsim_blocked(A_f, B_f, C_f, D_f, v, kf.x)
    e, x_filt = out[:, :p], out[:, p:]
    w = L_inv @ e.T
    ll = const - 0.5 * np.sum(w * w, axis=0)
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


def collect_steps(steps: list[KalmanStep], n: int, p: int) -> KalmanResult:
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
