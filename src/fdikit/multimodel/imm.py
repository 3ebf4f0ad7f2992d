"""Interacting multiple-model (IMM) filter for jump-Markov linear systems.

Hallouzi 2008, §2.3.1, Table 2.1 (after Li & Jilkov 2005), for the JMLS (2.3)–(2.5)::

    x_{k+1} = A^(s_k) x_k + B^(s_k) u_k + w_k,   w_k ~ N(0, Q^(s_k))
    y_k     = C^(s_k) x_k + D^(s_k) u_k + v_k,   v_k ~ N(0, R^(s_k))
    Π_ij    = P(s_{k+1} = j | s_k = i)          (row-stochastic)

with two corrections to the printed table: the mixing covariance sums the mixed models' own
``P^(i)`` (printed ``P^(j)``, which would not depend on ``i``), and the residual covariance is
``Σ = C P_{k|k−1} Cᵀ + R`` (printed ``C Cᵀ + R``; only with ``P_{k|k−1}`` is it the innovation
covariance that the gain ``K = P Cᵀ Σ⁻¹`` and the likelihood (2.12) need).  Noise means are zero (they are zero in
every example of the thesis).

The mode probabilities are propagated **in log space** (log-sum-exp in the Π prediction and in
the Bayes update) so that they neither underflow nor give 0/0 when every likelihood (2.12) is
below the smallest double (high-SNR data, outliers, 10⁶-step runs).

Sample convention (predictor form, as the rest of fdikit): the filter holds the per-mode priors
``x̂^(j)_{k|k−1}, P^(j)_{k|k−1}, μ_{k|k−1}``; ``step(u_k, y_k)`` performs the measurement update and
mode-probability update with ``y_k`` (step 2 second half, step 3), the fusion (step 4), then the
mixing (step 1) and the time update with ``u_k`` (step 2 first half) for sample ``k+1``.  This is
the Table 2.1 cycle with the cut placed after the update instead of before the mixing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.gaussian import LinearGaussianModel
from fdikit.multimodel.isolation import GroupThresholdLogic, mode_diagnosis
from fdikit.trace import Trace

__all__ = ["IMMFilter", "IMMStepper", "IMMStep", "IMMResult"]

_LOG2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class IMMStep:
    """Output of one IMM cycle (Table 2.1 step 4, fused values are output only).

    Attributes
    ----------
    x, P : ndarray
        Fused filtered estimate ``x̂_{k|k}`` (n) and covariance (n x n), (2.7).
    mu : ndarray
        Mode probabilities ``μ_k`` (M).
    x_modes, P_modes : ndarray
        Mode-matched filtered estimates (M x n) and covariances (M x n x n).
    log_likelihood : float
        Log predictive density ``log p(y_k | Y_{k−1})``; NaN when the sample is invalid.
    valid : bool
        False for a NaN measurement (prediction only: ``x, mu`` are then the predicted values).

    Examples
    --------
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    >>> stepper = imm.online()
    >>> step = stepper.step(None, [2.0])
    >>> step.x_modes.shape, step.P_modes.shape, step.valid
    ((2, 1), (2, 1, 1), True)

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12).
    """

    x: np.ndarray
    P: np.ndarray
    mu: np.ndarray
    x_modes: np.ndarray
    P_modes: np.ndarray
    log_likelihood: float
    valid: bool


@dataclass(frozen=True, eq=False)
class IMMResult:
    """Batch output of :meth:`IMMFilter.run` (arrays with one row per sample).

    Attributes
    ----------
    t : ndarray
        Sample times (N,) (the sample index when none were given).
    x : ndarray
        Fused estimates (N, n).
    P : ndarray or None
        Fused covariances (N, n, n), None when ``run(store_covariance=False)``.
    mu : ndarray
        Mode probabilities (N, M).
    log_mu : ndarray
        Their logarithms (N, M), finite far below the double range of ``mu``.
    x_modes : ndarray or None
        Mode-matched estimates (N, M, n), None unless ``run(store_modes=True)``.
    log_likelihood : ndarray
        ``log p(y_k | Y_{k−1})`` (N,); NaN on invalid samples.
    valid : ndarray of bool
        (N,); False where the measurement had a NaN entry (prediction only).
    modes : tuple of str
        Mode names, in the order of the columns of ``mu``.
    nominal : int
        Index of the nominal (fault-free) mode (default 0).

    Examples
    --------
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    >>> res = imm.run(np.zeros((5, 0)), 2.0 * np.ones((5, 1)))
    >>> res.x.shape, res.P.shape, res.mu.shape, res.x_modes is None, res.modes
    ((5, 1), (5, 1, 1), (5, 2), True, ('nominal', 'gain fault'))

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12).
    """

    t: np.ndarray
    x: np.ndarray
    P: np.ndarray | None
    mu: np.ndarray
    log_mu: np.ndarray
    x_modes: np.ndarray | None
    log_likelihood: np.ndarray
    valid: np.ndarray
    modes: tuple[str, ...]
    nominal: int = 0

    def diagnosis(self, logic: GroupThresholdLogic | None = None):
        """Mode probabilities as a :class:`~fdikit.diagnosis.Diagnosis` (most probable mode, or ``logic``)."""
        return mode_diagnosis(self.t, self.mu, self.modes, self.nominal, logic, self.valid)

    def plot(self, ax=None, **kwargs):
        """Draw the mode probabilities over time (:func:`fdikit.plots.plot_mode_probabilities`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw into it; default a new figure.
        **kwargs
            ``title`` and ``path`` of :func:`~fdikit.plots.plot_mode_probabilities`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
        >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
        >>> imm = IMMFilter([m0, m1], [[0.9, 0.1], [0.1, 0.9]], x0=[0.0], P0=[[1.0]])
        >>> res = imm.run(np.zeros((3, 0)), np.ones((3, 1)))
        >>> fig, ax = plt.subplots()
        >>> res.plot(ax=ax) is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_mode_probabilities

        return plot_mode_probabilities(self, ax=ax, **kwargs)


@dataclass(frozen=True, eq=False)
class IMMFilter:
    """IMM filter of Hallouzi 2008, §2.3.1, Table 2.1 (corrected; see module docstring).

    Parameters
    ----------
    modes : sequence of LinearGaussianModel
        The M mode models, sharing n, m, p; their ``name`` labels the modes (``"mode<i>"`` if unnamed).
    transition : array_like
        Π, (M, M) row-stochastic, ``Π[i, j] = P(s_{k+1}=j | s_k=i)``.
    mu0 : array_like, optional
        Prior mode probabilities of the first sample (M); default uniform.
    x0, P0 : array_like, optional
        Prior state mean and covariance of the first sample, shared ``(n,)``/``(n, n)``
        or per mode ``(M, n)``/``(M, n, n)`` (default zero and identity).
    nominal : int, optional
        Index of the nominal (fault-free) mode, for the diagnosis (default 0).
    min_probability : float, optional
        Floor on the predicted probabilities ``μ_{k|k−1}`` (a Π with zeros can lock a mode out);
        0 (the default) disables it; must be below 1/M.

    Raises
    ------
    ModelError
        If the modes are not ``LinearGaussianModel`` s of equal dimensions with unique names.
    ParameterError
        If Π is not an (M, M) row-stochastic matrix, or ``mu0``, ``x0``, ``P0``, ``nominal`` or
        ``min_probability`` has the wrong shape or range.

    Examples
    --------
    >>> import numpy as np
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    >>> res = imm.run(np.zeros((50, 0)), 2.0 * np.ones((50, 1)))
    >>> bool(res.mu[-1, 1] > 0.99), str(res.diagnosis().isolated[-1])
    (True, 'gain fault')

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12).
    """

    modes: Sequence[LinearGaussianModel]
    transition: np.ndarray
    mu0: np.ndarray | None = None
    x0: np.ndarray | None = None
    P0: np.ndarray | None = None
    nominal: int = 0
    min_probability: float = 0.0

    def __post_init__(self) -> None:
        modes = tuple(self.modes)
        if not modes or not all(isinstance(md, LinearGaussianModel) for md in modes):
            raise ModelError("IMMFilter needs a non-empty sequence of LinearGaussianModel")
        M = len(modes)
        n, m, p = modes[0].n, modes[0].m, modes[0].p
        for md in modes:
            if (md.n, md.m, md.p) != (n, m, p):
                raise ModelError(
                    f"mode {md.name!r} has (n, m, p) = {(md.n, md.m, md.p)} but the first mode has {(n, m, p)}; "
                    "all modes must share the state, input and output dimensions (pad with zeros)"
                )
        Pi = np.atleast_2d(validate.as_array("transition", self.transition, error=ParameterError, finite=False))
        if not np.all(np.isfinite(Pi)):
            raise ParameterError("transition matrix Π must be finite; every entry is a probability in [0, 1]")
        if Pi.shape != (M, M) or np.any(Pi < 0) or not np.allclose(Pi.sum(axis=1), 1.0, atol=1e-10):
            raise ParameterError(
                f"transition matrix Π must be ({M}, {M}), non-negative, with rows summing to 1 "
                f"(Π[i, j] = P(s_k+1 = j | s_k = i)); got shape {Pi.shape}, row sums {np.round(Pi.sum(axis=1), 6)}"
            )
        mu0 = np.full(M, 1.0 / M) if self.mu0 is None else validate.as_array("mu0", self.mu0).ravel()
        if mu0.shape != (M,) or np.any(mu0 < 0) or not np.isclose(mu0.sum(), 1.0):
            raise ParameterError(f"mu0 must be {M} non-negative probabilities that sum to 1; got {mu0}")
        x0 = np.zeros(n) if self.x0 is None else validate.as_array("x0", self.x0)
        x0 = np.broadcast_to(x0, (M, n)).copy() if x0.shape in ((n,), (M, n)) else None
        if x0 is None:
            raise ParameterError(f"x0 must have shape ({n},) or ({M}, {n})")
        P0 = np.eye(n) if self.P0 is None else validate.as_array("P0", self.P0)
        P0 = np.broadcast_to(P0, (M, n, n)).copy() if P0.shape in ((n, n), (M, n, n)) else None
        if P0 is None:
            raise ParameterError(f"P0 must have shape ({n}, {n}) or ({M}, {n}, {n})")
        for i in range(M):
            validate.psd_part("P0" if M == 1 else f"P0[{i}]", P0[i], error=ParameterError)
        nominal = validate.integer("nominal", self.nominal)
        if not 0 <= nominal < M:
            raise ParameterError(f"nominal = {nominal} is not a mode index in [0, {M})")
        min_probability = validate.number("min_probability", self.min_probability)
        if not 0.0 <= min_probability < 1.0 / M:
            raise ParameterError(f"min_probability must lie in [0, 1/M) = [0, {1.0 / M:g}), got {min_probability}")
        names = tuple(md.name or f"mode{i}" for i, md in enumerate(modes))
        if len(set(names)) != M:
            raise ModelError(f"mode names must be unique; got {names}")
        set_ = object.__setattr__
        set_(self, "modes", modes)
        set_(self, "transition", Pi)
        set_(self, "mu0", mu0)
        set_(self, "x0", x0)
        set_(self, "P0", P0)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(md.name or f"mode{i}" for i, md in enumerate(self.modes))

    def online(self) -> IMMStepper:
        """A stepper holding the filter state, for sample-by-sample use."""
        return IMMStepper(self)

    def run(self, u, y=None, t=None, store_covariance: bool = True, store_modes: bool = False) -> IMMResult:
        """Filter a whole record.

        Parameters
        ----------
        u : array_like or Trace
            (N, m) inputs, or a :class:`~fdikit.trace.Trace` (then ``y`` and ``t`` come from it).
        y : array_like
            (N, p) measurements; rows with NaN are prediction-only samples (marked invalid).
        t : array_like, optional
            (N,) times (default sample index).
        store_covariance, store_modes : bool
            Keep the fused covariances (default True) / mode-matched estimates (default False).

        Returns
        -------
        IMMResult
            The filtered record.

        Raises
        ------
        DataError
            If ``u``, ``y``, ``t`` do not have matching shapes or ``u`` has NaN/inf entries.
        """
        if isinstance(u, Trace):
            u, y, t = u.u, u.y, u.t
        md = self.modes[0]
        y = validate.as_array("y", y, error=DataError, finite=False)
        y = y.reshape(-1, 1) if y.ndim == 1 and md.p == 1 else y
        if y.ndim != 2:
            raise DataError(f"y must have shape (N, {md.p}), got shape {y.shape}")
        N = y.shape[0]
        u = validate.as_array("u", u, error=DataError, finite=False) if md.m else np.zeros((N, 0))
        if md.m and u.size % md.m == 0 and u.ndim <= 2:
            u = u.reshape(-1, md.m)
        if y.shape != (N, md.p) or u.shape != (N, md.m):
            raise DataError(f"need y of shape (N, {md.p}) and u of shape (N, {md.m}); got {y.shape} and {u.shape}")
        if not np.all(np.isfinite(u)):
            raise DataError("inputs u contain NaN/inf; the IMM cannot predict without the input, clean u first")
        t = np.arange(N, dtype=float) if t is None else validate.as_array("t", t, error=DataError).ravel()
        if t.shape != (N,):
            raise DataError(f"t has {t.size} samples but y has {N}; give one time per sample")
        M, n = len(self.modes), md.n
        X = np.empty((N, n))
        P = np.empty((N, n, n)) if store_covariance else None
        LMU = np.empty((N, M))
        XM = np.empty((N, M, n)) if store_modes else None
        LL = np.empty(N)
        V = np.empty(N, bool)
        s = IMMStepper(self)
        for k in range(N):
            x, Pk, xm, ll, ok = s._cycle(u[k], y[k])
            X[k] = x
            LMU[k] = s.log_mu
            LL[k] = ll
            V[k] = ok
            if P is not None:
                P[k] = Pk
            if XM is not None:
                XM[k] = xm
        return IMMResult(t=t, x=X, P=P, mu=np.exp(LMU), log_mu=LMU, x_modes=XM, log_likelihood=LL, valid=V,
                         modes=self.names, nominal=self.nominal)


class IMMStepper:
    """Online IMM: ``step(u_k, y_k)`` → :class:`IMMStep`; NaN in ``y_k`` → prediction only.

    Parameters
    ----------
    imm : IMMFilter
        The filter whose priors ``x0, P0, mu0`` initialise the stepper (usually made by :meth:`IMMFilter.online`).

    Attributes
    ----------
    x_pred, P_pred : ndarray
        Per-mode priors ``x̂^(j)_{k|k−1}`` (M x n) and ``P^(j)_{k|k−1}`` (M x n x n) for the next sample.
    log_mu, log_mu_pred : ndarray
        Log mode probabilities after the last update and predicted for the next sample (M).

    Examples
    --------
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> imm = IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]])
    >>> stepper = imm.online()
    >>> for _ in range(3):
    ...     step = stepper.step(None, [2.0])
    >>> step.mu.round(4).tolist()
    [0.0002, 0.9998]
    >>> stepper.step(None, [float("nan")]).valid      # missing measurement: prediction only
    False

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12).
    """

    def __init__(self, imm: IMMFilter) -> None:
        md = imm.modes
        self.imm = imm
        self._A = np.stack([m.A for m in md])
        self._At = self._A.transpose(0, 2, 1).copy()
        self._B = np.stack([m.B for m in md])
        self._C = np.stack([m.C for m in md])
        self._Ct = self._C.transpose(0, 2, 1).copy()
        self._D = np.stack([m.D for m in md])
        self._Q = np.stack([m.Q for m in md])
        self._R = np.stack([m.R for m in md])
        with np.errstate(divide="ignore"):
            self._logPi = np.log(imm.transition)
            self._logfloor = np.log(imm.min_probability) if imm.min_probability > 0 else -np.inf
            self.log_mu_pred = np.log(imm.mu0)
        self.x_pred = imm.x0.copy()
        self.P_pred = imm.P0.copy()
        self.log_mu = self.log_mu_pred.copy()
        self._p = md[0].p
        self._m = md[0].m

    @property
    def mu(self) -> np.ndarray:
        """Current mode probabilities (after the last update)."""
        return np.exp(self.log_mu)

    def step(self, u, y) -> IMMStep:
        """One Table 2.1 cycle with ``u_k, y_k`` (see the module docstring for the sample convention)."""
        u = validate.as_array("u", np.zeros(0) if u is None else u, error=DataError, finite=False)
        y = validate.as_array("y", y, error=DataError, finite=False)
        if u.size != self._m or y.size != self._p:
            raise DataError(f"u_k must have {self._m} entries and y_k {self._p}, got {u.size} and {y.size}")
        u, y = u.reshape(self._m), y.reshape(self._p)
        if not np.all(np.isfinite(u)):
            raise DataError("input u_k contains NaN/inf; the IMM cannot predict without the input")
        x, P, xm, ll, ok = self._cycle(u, y, keep=True)
        return IMMStep(x=x, P=P, mu=np.exp(self.log_mu), x_modes=xm, P_modes=self._Pf, log_likelihood=ll, valid=ok)

    def _cycle(self, u, y, keep: bool = False):
        xp, Pp = self.x_pred, self.P_pred
        ok = bool(np.all(np.isfinite(y)))
        if ok:
            # step 2 (measurement update) with Σ = C P_{k|k-1} Cᵀ + R  [Table 2.1 prints C Cᵀ + R]
            PCt = Pp @ self._Ct                                        # (M, n, p)
            S = self._C @ PCt + self._R
            S = 0.5 * (S + S.transpose(0, 2, 1))
            z = y - (self._C @ xp[:, :, None])[:, :, 0] - (self._D @ u)
            W = np.linalg.solve(S, np.concatenate([PCt.transpose(0, 2, 1), z[:, :, None]], axis=2))  # S⁻¹[PCᵀ'ᵀ z]
            Kz = (PCt @ W[:, :, -1:])[:, :, 0]
            xf = xp + Kz
            Pf = Pp - PCt @ W[:, :, :-1]
            Pf = 0.5 * (Pf + Pf.transpose(0, 2, 1))
            # step 3 in log space: log L = −½ (zᵀ Σ⁻¹ z + log|2πΣ|)   (2.12)
            logdet = np.linalg.slogdet(S)[1]
            loglik = -0.5 * (np.einsum("mp,mp->m", z, W[:, :, -1]) + logdet + self._p * _LOG2PI)
            a = self.log_mu_pred + loglik
            ll = _logsumexp(a)
            self.log_mu = a - ll
        else:  # prediction only
            xf, Pf, ll = xp, Pp, np.nan
            self.log_mu = self.log_mu_pred
        # step 4: fusion (output only)
        mu = np.exp(self.log_mu)
        x = mu @ xf
        d = xf - x
        nx = xf.shape[1]
        P = (mu @ Pf.reshape(len(mu), -1)).reshape(nx, nx) + (d.T * mu) @ d
        if keep:
            self._Pf = Pf
        # step 1: mixing with μ_{k|k-1} = Σ_i Π_ij μ_i (log-sum-exp), then step 2 time update with u_k
        G = self._logPi + self.log_mu[:, None]                         # (i, j)
        lp = _logsumexp(G, axis=0)
        reach = np.isfinite(lp)
        Wm = np.where(reach[None, :], np.exp(G - np.where(reach, lp, 0.0)[None, :]), mu[:, None])  # μ^{i|j}
        xbar = Wm.T @ xf                                               # (j, n)
        dd = xf[None, :, :] - xbar[:, None, :]                         # (j, i, n)
        Pbar = (Wm.T @ Pf.reshape(len(mu), -1)).reshape(Pf.shape)     # Σ_i μ^{i|j} P^(i)  [Table 2.1 prints P^(j)]
        Pbar += (dd.transpose(0, 2, 1) * Wm.T[:, None, :]) @ dd        # + Σ_i μ^{i|j} (x̄ − x̂^(i))(x̄ − x̂^(i))ᵀ
        if self._logfloor > -np.inf:
            lp = np.maximum(lp, self._logfloor)
            lp = lp - _logsumexp(lp)
        self.log_mu_pred = lp
        self.x_pred = (self._A @ xbar[:, :, None])[:, :, 0] + self._B @ u
        self.P_pred = self._A @ Pbar @ self._At + self._Q
        return x, P, xf, ll, ok


def _logsumexp(a: np.ndarray, axis: int | None = None):
    """log Σ exp(a) along ``axis`` (None or 0); −inf for an all −inf slice."""
    if axis is None:
        mx = a.max()
        return mx + float(np.log(np.exp(a - mx).sum())) if mx > -np.inf else -np.inf
    mx = a.max(axis=0)
    fin = mx > -np.inf
    if fin.all():
        return mx + np.log(np.exp(a - mx).sum(axis=0))
    m0 = np.where(fin, mx, 0.0)
    s = np.exp(a - m0).sum(axis=0)
    return np.where(fin, m0 + np.log(np.where(fin, s, 1.0)), -np.inf)
