"""Subspace identification (N4SID, PO-MOESP) of a discrete state-space model with its noise model.

The model is identified in innovation form (Van Overschee & De Moor 1996, Ch. 4)::

    x[k+1] = A x[k] + B u[k] + K e[k]
    y[k]   = C x[k] + D u[k] + e[k],        Cov e = R

from block Hankel matrices of past and future data (``horizon`` block rows each).  One LQ
factorisation of ``[U_f; U_p; Y_p; Y_f]`` gives

* ``method="n4sid"``: the oblique projection ``O = Y_f /_{U_f} W_p`` (``W_p = [U_p; Y_p]``),
  weights ``W_1 = W_2 = I`` (Van Overschee & De Moor 1996, Ch. 4, Theorem 12); its SVD gives the
  order and the extended observability matrix ``Γ``, the state sequence ``X = Γ⁺ O`` and
  ``[A B; C D]`` by least squares on ``[X_{k+1}; y_k] = [A B; C D] [X_k; u_k]`` (§4.3.2);
* ``method="moesp"``: the SVD of ``L_32`` (the future outputs with the future inputs projected
  out, past data as the instrument; Verhaegen 1994, PO-MOESP), ``A`` and ``C`` from the shift
  invariance of ``Γ``, then ``B`` and ``D`` by least squares on the same state sequence.

The residuals of the state regression estimate the noise covariances ``Q, S, R``; the steady
Kalman gain of those (discrete Riccati equation) is the first estimate of ``K`` (Van Overschee &
De Moor 1996, Ch. 4), re-estimated for the final model as below.  The data are scaled to unit
standard deviation per signal before the projections and the scaling is undone on the result
(so the singular values and the poles do not depend on units).

``focus="simulation"`` (default, MATLAB's ``Focus``): given ``A`` and ``C``, the simulated output is
linear in ``B``, ``D`` and the initial state of each segment, so these are refitted by one linear
least-squares problem on the simulation error (the output-error criterion, Ljung 1999, §4.2 and
Ch. 7, solved exactly for a fixed ``A, C``); ``focus="prediction"`` keeps ``B, D`` of the state
regression.  The noise model is then re-estimated for the final ``(A, B, C, D)`` (whatever the focus
and stability steps chose): a long autoregression of the output error estimates the innovation, ``K``
follows by linear least squares, and ``R`` is the sample covariance of that predictor's one-step error
on the data (two-stage least squares, Hannan & Rissanen 1982), so that the residual of
``kalman(ident.model, Q=ident.R, R=0)`` on the identification data has covariance ``R``.  (It used
to be the state regression's ``K, R``: with refitted ``B, D`` the predictor's error on the car logs
had 2.5 times the claimed standard deviation.)

Stability (``stable=True``, default): an estimated ``A`` with eigenvalues ``|λ| ≥ 1`` has each such
eigenvalue replaced by its reflection ``1/conj(λ)`` (eigenvectors kept; a defective ``A`` is divided
by ``ρ(A)²``), ``B, D`` are refitted for the new ``A`` and an :class:`~fdikit.errors.FdiWarning` lists
what moved.  The reflection keeps a mode's frequency and the shape of its magnitude response
(``|e^{jω} − λ| = |λ| |e^{jω} − 1/conj(λ)|``) but changes its phase and damping: the model is
biased (an unstable estimate says the order or the horizon do not suit the data).  It is the
cheap alternative to a stability-constrained least squares for ``A`` (an LMI problem).

Order selection (``order=None``): ``criterion="bic"`` (default) or ``"aic"`` identifies every order
``k = 1 … min(max_order, p (horizon − 1))`` from the one SVD and takes the least
``N log det Σ̂_k + c d_k`` (``c = log N`` or 2), ``Σ̂_k`` the covariance of the one-step prediction
error of the order-``k`` predictor on the identification data (initial state fitted) and
``d_k = k (m + 2 p) + p m`` the parameters of ``(A, B, C, D, K)`` up to a change of basis (Ljung
1999, §16.4); prediction errors below ``1e-8`` of a signal's standard deviation count as zero, so
noise-free data give the minimal order.  ``criterion="gap"`` takes the largest singular-value gap
``s_k / s_{k+1}``: right when the noise floor of the singular values lies clearly below the smallest
system singular value, wrong on realistic data where they decay smoothly.  Example: the tutorial
car logs (``docs/tutorial/car_train.csv.gz``, steering multisine 0.1–2 Hz at 100 Hz, sensor noise
and an unmeasured road): the singular values fall as 1, 0.14, 3e-3, 2.7e-4, 8e-5, … and the gap rule
picks 2 (fits 62 % / 41 % on ``car_healthy``); the BIC picks 6 (fits 89 % / 85 %, the reference
linearisation 88 % / 85 %; with ``feedthrough=True`` 2 and 10).

Why not a packaged implementation: ``benchmarks/bench_identify.py`` compares ``nfoursid`` 1.0.2
(PyPI), SIPPY (``sippy_unipi`` 1.0.1, its ``N4SID``) and this module on a known 4-state,
1-input, 2-output system and on the car logs (docs/PERFORMANCE.md, "Subspace identification";
docs/methods/identification.md).  On the known system all are accurate: noise-free each recovers
the eigenvalues to 2e-15 (relative); with innovation noise (output SNR 11) the RMS eigenvalue error
over 20 seeds is 0.008 for N4SID here, ``nfoursid`` and SIPPY alike.  Neither peer takes several
experiments or a record split by gaps, ``nfoursid`` gives no gain ``K`` and needs pandas and
matplotlib at import, SIPPY prints to stdout and pulls in casadi and sympy; ``harold`` and
python-control have no subspace method.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DataError, FdiWarning, ParameterError
from fdikit.identify.data import segments
from fdikit.lti import dlsim_blocked
from fdikit.model import FaultModel
from fdikit.operating_point import OperatingPoint

__all__ = ["IdentifiedModel", "subspace_id"]


@dataclass(frozen=True, eq=False)
class IdentifiedModel:
    """An identified discrete model in innovation form, with what the identification saw.

    Attributes
    ----------
    model : FaultModel
        Discrete (``dt`` of the data), states ``x0 …``, the data's controls and outputs, and the
        innovation ``e`` as the noise group (``Bw = K``, ``Dw = I``, names ``<output>_innovation``),
        with the operating point (the means removed) attached.  ``kalman(model, Q=R, R=0)``
        gives back the gain ``K``.
    K : (n, p) array
        Innovation (steady Kalman predictor) gain.
    R : (p, p) array
        Innovation covariance ``Cov e``.
    singular_values : (p horizon,) array
        Singular values of the weighted projection (order selection).
    order : int
        The model order ``n``.
    order_rule : str
        How the order was chosen.
    method : str
        ``"n4sid"`` or ``"moesp"``.
    horizon : int
        Block rows of the past and future Hankel matrices.
    u_mean, y_mean : arrays
        The means removed from the controls and the outputs.
    operating_point : OperatingPoint
        The same means by signal name (``u0``, ``y0``).
    samples : int
        Samples used; ``segments`` is the number of gap-free segments.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.5]], C=[[1.0]], Bu=[[1.0]], dt=1.0)
    >>> tr = simulate(plant, t=np.arange(300.0), u=np.random.default_rng(1).standard_normal((300, 1)))
    >>> ident = subspace_id(tr, 1, detrend=False)
    >>> ident, ident.model.noise, round(float(ident.poles[0].real), 9)
    (IdentifiedModel(n4sid, n=1, p=1, m=1, dt=1, samples=300, segments=1), ('y0_innovation',), 0.5)

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (the innovation form).
    """

    model: FaultModel
    K: np.ndarray
    R: np.ndarray
    singular_values: np.ndarray
    order: int
    order_rule: str
    method: str
    horizon: int
    u_mean: np.ndarray
    y_mean: np.ndarray
    operating_point: OperatingPoint
    samples: int
    segments: int

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A``."""
        return self.model.poles()

    def __repr__(self) -> str:
        return (f"IdentifiedModel({self.method}, n={self.order}, p={self.model.p}, m={len(self.model.controls)}, "
                f"dt={self.model.dt:g}, samples={self.samples}, segments={self.segments})")


def _hankel(x: np.ndarray, start: int, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix: block row ``r`` holds ``x[start + r : start + r + cols]`` transposed."""
    return np.vstack([x[start + r:start + r + cols].T for r in range(rows)]) if x.shape[1] else np.zeros((0, cols))


def _gap_order(s: np.ndarray, limit: int) -> int:
    floor = s[0] * np.finfo(float).eps if s[0] > 0 else 1.0
    t = np.maximum(s[:limit + 1], floor)
    return int(np.argmax(np.log(t[:-1]) - np.log(t[1:]))) + 1


def subspace_id(
    data,
    order: int | None = None,
    *,
    controls: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    horizon: int | None = None,
    method: str = "n4sid",
    max_order: int | None = None,
    feedthrough: bool = False,
    detrend: bool = True,
    criterion: str = "bic",
    focus: str = "simulation",
    stable: bool = True,
) -> IdentifiedModel:
    """Identify ``x⁺ = A x + B u + K e``, ``y = C x + D u + e`` from one or more traces.

    Parameters
    ----------
    data : Trace or sequence of Trace
        The experiments (one sample time).  Samples with a non-finite control or output, or
        ``valid == False``, split a trace into segments; segments shorter than
        ``2 horizon + 1`` samples are dropped with an :class:`~fdikit.errors.FdiWarning`.
    order : int, optional
        Model order ``n``; None picks it by ``criterion`` (module docstring).
    controls, outputs : sequence of str, optional
        The signals to use (default: all of the first trace's).
    horizon : int, optional
        Block rows of the past and of the future Hankel matrix (default
        ``max(10, ⌈(order or max_order or 8) / p⌉ + 2)``); needs ``p (horizon − 1) ≥ n``.
    method : {"n4sid", "moesp"}, default "n4sid"
    max_order : int, optional
        Largest order ``order=None`` considers (default ``p (horizon − 1)``).
    feedthrough : bool, default False
        Estimate ``D``; False (default, as MATLAB's ``n4sid``) fixes ``D = 0``.  With a smooth,
        band-limited input ``u[k]`` is nearly a linear function of the state, so ``D`` is nearly
        collinear with ``C x``: the estimate can be huge and cancelled by ``B`` (the tutorial car:
        ``D`` = −3355 m/s² per rad for the lateral acceleration, physically about 40), with a model
        whose internal states and start-up transients are huge.  An :class:`~fdikit.errors.FdiWarning`
        flags an estimated ``D`` for which ``D u`` alone would have more than 10 times the output's
        standard deviation.  Pass True for a plant with a direct feedthrough and an input that
        excites it (a white or wide-band input).
    detrend : bool, default True
        Remove the mean of every signal first (kept as the model's operating point).  On
        noise-free data from rest the sample means are not an equilibrium pair
        (``ȳ ≠ G(1) ū`` by the transient): the difference shows as a mode at 1 of tiny
        singular value; use ``detrend=False`` for data about a known zero operating point.
    criterion : {"bic", "aic", "gap"}, default "bic"
        The order rule of ``order=None``: the least BIC or AIC of the one-step prediction error over
        the orders, or the largest singular-value gap (module docstring).
    focus : {"simulation", "prediction"}, default "simulation"
        ``B``, ``D`` by least squares on the simulation error given ``A``, ``C``, or from the state
        regression.
    stable : bool, default True
        Reflect eigenvalues of ``A`` with ``|λ| ≥ 1`` to ``1/conj(λ)`` (and refit ``B``, ``D``), with an
        :class:`~fdikit.errors.FdiWarning`; False returns the raw estimate.

    Returns
    -------
    IdentifiedModel
        The FaultModel, ``K``, ``R``, the singular values, the order and how it was chosen, the means.

    Raises
    ------
    ParameterError
        For a bad order, horizon, method, max_order, criterion or focus.
    DataError
        For unusable data: too few samples for the Hankel matrices, a constant control, a
        trace without the named signals (see :func:`fdikit.identify.data.segments`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.9, 0.2], [-0.2, 0.9]], C=[[1.0, 0.0]], Bu=[[0.0], [1.0]], dt=0.1)
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> tr = simulate(plant, t=np.arange(500) * 0.1, u=u)
    >>> ident = subspace_id(tr, detrend=False)  # zero operating point (a removed mean is a constant mode)
    >>> ident.order, np.sort_complex(ident.poles).round(6).tolist()
    (2, [(0.9-0.2j), (0.9+0.2j)])
    >>> ident.order_rule.split(" (")[0]
    'least BIC of the one-step prediction error for k in 1..9: k = 2'

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (N4SID: oblique projection, Theorem 12, the state-sequence
    regression); Verhaegen 1994 (PO-MOESP); Ljung 1999, §16.4 (AIC, BIC) and §4.2 (output error).
    """
    validate.choice("method", method, ("n4sid", "moesp"))
    validate.choice("criterion", criterion, ("bic", "aic", "gap"))
    validate.choice("focus", focus, ("simulation", "prediction"))
    if order is not None:
        order = validate.integer("order", order, minimum=1)
    if max_order is not None:
        max_order = validate.integer("max_order", max_order, minimum=1)
    probe = segments(data, controls, outputs, min_length=2, detrend=False) if horizon is None else None
    p = len(probe.outputs) if probe is not None else None
    if horizon is None:
        horizon = max(10, -(-(order or max_order or 8) // p) + 2)
    horizon = validate.integer("horizon", horizon, minimum=2)
    ds = segments(data, controls, outputs, min_length=2 * horizon + 1, detrend=detrend)
    m, p, i = len(ds.controls), len(ds.outputs), horizon
    limit = p * (i - 1)
    if order is not None and order > limit:
        raise ParameterError(f"order {order} needs p (horizon - 1) >= {order}; with {p} outputs use horizon >= "
                             f"{-(-order // p) + 1}")
    if max_order is not None and max_order > limit:
        raise ParameterError(f"max_order {max_order} exceeds p (horizon - 1) = {limit}; raise the horizon")
    su = np.concatenate(ds.u).std(axis=0) if m else np.zeros(0)
    sy = np.concatenate(ds.y).std(axis=0)
    for names, sd, what in ((ds.controls, su, "control"), (ds.outputs, sy, "output")):
        flat = [nm for nm, s in zip(names, sd) if not s > 0]
        if flat:
            raise DataError(f"{what}s {flat} are constant in the data; an identification needs them to vary "
                            f"(drop them with {what}s=[...] or excite them)")
    us = [u / su for u in ds.u]
    ys = [y / sy for y in ds.y]
    cols = [len(y) - 2 * i + 1 for y in ys]
    H = np.hstack([np.vstack([_hankel(u, i, i, c), _hankel(u, 0, i, c), _hankel(y, 0, i, c), _hankel(y, i, i, c)])
                   for u, y, c in zip(us, ys, cols)])
    rows = H.shape[0]
    if H.shape[1] < 2 * rows:
        raise DataError(f"{ds.samples} samples give {H.shape[1]} Hankel columns for {rows} rows; identification "
                        f"needs at least {2 * rows} (more data or a shorter horizon)")
    L = np.linalg.qr(H.T, mode="r").T
    r1, r2 = m * i, (m + p) * i
    L21, L22 = L[r1:r1 + r2, :r1], L[r1:r1 + r2, r1:r1 + r2]
    L32 = L[r1 + r2:, r1:r1 + r2]
    L22i = np.linalg.pinv(L22, rcond=1e3 * rows * np.finfo(float).eps)
    Ob = L32 @ L22i @ np.hstack([L21, L22])
    U, s, _ = np.linalg.svd(Ob if method == "n4sid" else L32)
    est = _Estimator(method, i, p, us, ys, cols, L32 @ L22i, U, s, feedthrough, focus, stable)
    if order is None:
        top = limit if max_order is None else max_order
        if criterion == "gap":
            order = _gap_order(s, top)
            rule = (f"largest singular-value gap s_k/s_(k+1) for k in 1..{top}: k = {order} "
                    f"(s_{order}/s_{order + 1} = {s[order - 1] / max(s[order], s[0] * np.finfo(float).eps):.3g})")
        else:
            scores = [est.score(k, criterion) for k in range(1, top + 1)]
            order = int(np.argmin(scores)) + 1
            rule = (f"least {criterion.upper()} of the one-step prediction error for k in 1..{top}: k = {order} "
                    f"({criterion.upper()}/N by order: " + ", ".join(f"{v / est.N:.3f}" for v in scores) + ")")
    else:
        rule = "given"
    n = order
    A, B, C, D, Qn, S, Rn, moved = est.fit(n)
    if moved.size:
        warnings.warn(f"the {method} estimate of order {n} has the unstable eigenvalues "
                      f"{np.round(moved, 4).tolist()}; they were reflected into the unit circle (1/conj(λ)) and B, D "
                      "refitted (stable=False keeps the raw estimate; a lower order or a longer horizon may avoid it)",
                      FdiWarning, stacklevel=2)
    big = np.abs(D) > 10.0  # scaled signals: D u alone would have 10x the standard deviation of the output
    if big.any():
        pairs = [f"{ds.controls[j]} -> {ds.outputs[k]}" for k, j in zip(*np.nonzero(big))]
        warnings.warn(f"the estimated feedthrough D is implausibly large for {pairs} (D u alone would have "
                      f"{np.abs(D).max():.3g} times the standard deviation of the output, cancelled by the dynamics): "
                      "D is nearly collinear with C x for a smooth input; use feedthrough=False unless the plant "
                      "has a direct feedthrough and the input excites high frequencies", FdiWarning, stacklevel=2)
    K, Re = _innovation_gain(A, C, (Qn + Qn.T) / 2, S, (Rn + Rn.T) / 2)
    if np.all(np.abs(np.linalg.eigvals(A)) < 1):  # (stable=False may return an unstable A: its output error diverges)
        K, Re = _noise_refit(A, B, C, D, est.us, est.ys, K, lags=3 * i)
    B, C, D = B / su, sy[:, None] * C, sy[:, None] * D / su
    K, Re = K / sy, sy[:, None] * Re * sy
    Re = (Re + Re.T) / 2
    model = FaultModel(A=A, Bu=B, C=C, Du=D, Bw=K, Dw=np.eye(p), states=[f"x{k}" for k in range(n)],
                       outputs=ds.outputs, controls=ds.controls, noise=[f"{y}_innovation" for y in ds.outputs],
                       dt=ds.dt).with_operating_point(u0=ds.u_mean, y0=ds.y_mean)
    return IdentifiedModel(model, K, Re, s, n, rule, method, i, ds.u_mean, ds.y_mean, model.operating_point,
                           ds.samples, len(ds.y))


class _Estimator:
    """``A, B, C, D`` and the noise covariances of each order from one SVD (scaled data)."""

    def __init__(self, method, i, p, us, ys, cols, P, U, s, feedthrough, focus, stable):
        self.method, self.i, self.p, self.us, self.ys, self.cols = method, i, p, us, ys, cols
        self.P, self.U, self.s, self.feedthrough, self.focus, self.stable = P, U, s, feedthrough, focus, stable
        self.m = us[0].shape[1]
        self.N = sum(len(y) for y in ys)
        self._cache: dict = {}

    def fit(self, n: int):
        """``(A, B, C, D, Q, S, R, eigenvalues moved)`` of order ``n`` (scaled signals)."""
        if n in self._cache:
            return self._cache[n]
        p, m, i = self.p, self.m, self.i
        G = self.U[:, :n] * np.sqrt(self.s[:n])
        M = np.linalg.pinv(G) @ self.P
        Xn, Xc, Uc, Yc = [], [], [], []
        for u, y, c in zip(self.us, self.ys, self.cols):
            X = M @ np.vstack([_hankel(u, 0, i, c), _hankel(y, 0, i, c)])
            Xn.append(X[:, 1:])
            Xc.append(X[:, :-1])
            Uc.append(u[i:i + c - 1].T)
            Yc.append(y[i:i + c - 1].T)
        Xn, Xc, Uc, Yc = (np.hstack(a) for a in (Xn, Xc, Uc, Yc))
        Ur = Uc if self.feedthrough else np.zeros((0, Uc.shape[1]))
        if self.method == "n4sid":
            A = _ls(np.vstack([Xc, Uc]).T, Xn.T).T[:, :n]
            C = _ls(np.vstack([Xc, Ur]).T, Yc.T).T[:, :n]
        else:
            C = G[:p]
            A = np.linalg.lstsq(G[:-p], G[p:], rcond=None)[0]
        moved = np.zeros(0, complex)
        if self.stable:
            A, moved = _reflect_unstable(A)
        # the state-sequence regression given A and C: B, D (focus="prediction") and the noise covariances
        B = _ls(Uc.T, (Xn - A @ Xc).T).T if m else np.zeros((n, 0))
        D = (_ls(Ur.T, (Yc - C @ Xc).T).T if self.feedthrough and m
             else np.zeros((p, m)))
        W, E = Xn - A @ Xc - B @ Uc, Yc - C @ Xc - D @ Uc
        N = W.shape[1]
        noise = (W @ W.T / N, W @ E.T / N, E @ E.T / N)
        if self.focus == "simulation" and m and np.all(np.abs(np.linalg.eigvals(A)) < 1):
            B, D = _output_error_fit(A, C, self.us, self.ys, self.feedthrough)
        self._cache[n] = (A, B, C, D, *noise, moved)
        return self._cache[n]

    def score(self, n: int, criterion: str) -> float:
        """AIC or BIC of the one-step prediction error of order ``n`` (innovation form, Gaussian)."""
        A, B, C, D, Q, S, R, _ = self.fit(n)
        if np.any(np.abs(np.linalg.eigvals(A)) >= 1):  # unstable (stable=False): refused
            return np.inf
        K, _ = _innovation_gain(A, C, (Q + Q.T) / 2, S, (R + R.T) / 2)
        if not np.all(np.isfinite(K)) or np.any(np.abs(np.linalg.eigvals(A - K @ C)) >= 1):
            K = np.zeros_like(K)  # no usable Kalman gain (noise-free data): the simulation error
        E = _predictor_errors(A, B, C, D, K, self.us, self.ys)
        m, p = self.m, self.p
        d = n * (m + 2 * p) + p * m * self.feedthrough
        # errors below 1e-8 of a signal's standard deviation count as zero (noise-free data: rounding only)
        logdet = np.linalg.slogdet(E.T @ E / len(E) + 1e-16 * np.eye(p))[1]
        return float(self.N * logdet + (2.0 if criterion == "aic" else np.log(self.N)) * d)


def _reflect_unstable(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A`` with every eigenvalue ``|λ| ≥ 1`` replaced by ``1/conj(λ)`` (eigenvectors kept), and those moved."""
    lam, V = np.linalg.eig(A)
    bad = np.abs(lam) >= 1
    if not bad.any():
        return A, np.zeros(0, complex)
    if np.linalg.cond(V) < 1e8:
        new = np.where(bad, lam / np.abs(lam) ** 2 * (1 - 1e-9), lam)
        A2 = ((V * new) @ np.linalg.inv(V)).real
    else:  # defective: scale A so that its spectral radius becomes 1/ρ
        rho = float(np.max(np.abs(lam)))
        A2 = A / rho ** 2 * (1 - 1e-9)
    return A2, lam[bad]


def _ls(Phi: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Least squares ``Φ θ ≈ Y`` by the normal equations of the column-equilibrated ``Φ`` (tall ``Φ``).

    Matrix products on the long side and one small solve: on tall problems this is several times
    faster than an SVD or QR of ``Φ`` (much more under a loaded multi-threaded BLAS); the
    equilibration keeps the squared condition number to that of the columns' directions.
    """
    d = np.sqrt(np.einsum("ij,ij->j", Phi, Phi))
    d[d == 0] = 1.0
    P = Phi / d
    th = np.linalg.lstsq(P.T @ P, P.T @ Y, rcond=None)[0]
    return th / (d[:, None] if th.ndim == 2 else d)


def _free_response(A: np.ndarray, C: np.ndarray, N: int) -> np.ndarray:
    """``[C; C A; …; C A^{N−1}]`` as an (N, p, n) array, by doubling."""
    O = C[None]
    Ak = A
    while len(O) < N:
        O = np.concatenate([O, O @ Ak])
        Ak = Ak @ Ak
    return O[:N]


def _output_error_fit(A, C, us, ys, feedthrough):
    """``B``, ``D`` and one initial state per segment minimising the simulation error given ``A``, ``C``.

    The simulated output is linear in ``(B, D, x0)``: one least-squares problem.  The regressor of
    ``B[i, j]`` in output ``k`` is ``Σ_l (C A^(t−1−l))[k, i] u_j(l)``, the state ``z_i(t)`` of
    ``z⁺ = Aᵀ z + C[k]ᵀ u_j`` (``p m`` simulations); that of ``x0`` of a segment is ``C A^t``, projected
    out segment by segment before the solve for ``B, D``.
    """
    n, p, m = A.shape[0], C.shape[0], us[0].shape[1]
    nb = n * m + (p * m if feedthrough else 0)
    rows, rhs = [], []
    for u, y in zip(us, ys):
        N = len(y)
        Phi = np.zeros((N, p, nb))
        for k in range(p):
            for j in range(m):
                z = dlsim_blocked(A.T, C[k][:, None], np.zeros((1, n)), np.zeros((1, 1)), u[:, [j]])[1]
                Phi[:, k, j:n * m:m] = z
                if feedthrough:
                    Phi[:, k, n * m + k * m + j] = u[:, j]
        Phi, yv = Phi.reshape(N * p, nb), y.reshape(-1)
        O = _free_response(A, C, N).reshape(N * p, n)
        rows.append(Phi - O @ _ls(O, Phi))
        rhs.append(yv - O @ _ls(O, yv))
    Phi, Y = np.vstack(rows), np.concatenate(rhs)
    th = _ls(Phi, Y)
    return th[:n * m].reshape(n, m), th[n * m:nb].reshape(p, m) if feedthrough else np.zeros((p, m))


def _predictor_errors(A, B, C, D, K, us, ys) -> np.ndarray:
    """One-step prediction errors of the predictor ``(A, B, C, D, K)``, the initial state fitted per segment."""
    n, p = A.shape[0], C.shape[0]
    F, E = A - K @ C, []
    for u, y in zip(us, ys):
        e = dlsim_blocked(F, np.hstack([B - K @ D, K]), -C, np.hstack([-D, np.eye(p)]), np.hstack([u, y]))[0]
        O = _free_response(F, C, len(y)).reshape(-1, n)
        ev = e.reshape(-1)
        E.append((ev - O @ _ls(O, ev)).reshape(-1, p))
    return np.concatenate(E)


def _noise_refit(A, B, C, D, us, ys, K0, lags):
    """``K`` and ``R = Cov e`` consistent with the final ``(A, B, C, D)`` (two-stage least squares).

    The output error ``v = y − G(q) u`` (initial state fitted per segment) of the final model is
    ``v = (I + C (qI − A)⁻¹ K) e``.  Stage 1: a long autoregression of ``v`` (``lags`` past values,
    pre-windowed) estimates the innovation ``ê``; stage 2: ``v − ê = C x``, ``x⁺ = A x + K ê`` is
    linear in ``K`` and the initial states, solved by least squares (the two-stage method of Hannan
    & Rissanen 1982, a pseudo-linear regression); a second pass repeats stage 2 with
    the prediction errors of the first.  Of these ``K`` and the state-regression ``K0``, the one whose
    (stable) predictor has the least ``det`` of the error covariance on the data is taken (``0``,
    the output error, when none is stable; ``A`` is stable), and ``R`` is the sample covariance of
    that predictor's one-step error on the data: the Kalman residual of the returned
    model has covariance ``R`` on the identification data, whatever ``B, D`` the focus step chose.
    """
    n, p = A.shape[0], C.shape[0]
    vs = []
    for u, y in zip(us, ys):
        v = (y - dlsim_blocked(A, B, C, D, u)[0]).reshape(-1)
        O = _free_response(A, C, len(y)).reshape(-1, n)
        vs.append((v - O @ _ls(O, v)).reshape(-1, p))
    L = max(1, min(lags, sum(len(v) for v in vs) // (4 * p)))
    regs = []
    for v in vs:
        vp = np.vstack([np.zeros((L, p)), v])
        regs.append(np.hstack([vp[L - j:L - j + len(v)] for j in range(1, L + 1)]))
    th = _ls(np.vstack(regs), np.vstack(vs))
    es = [v - P @ th for v, P in zip(vs, regs)]
    best = None
    for _ in range(2):  # the second pass takes the first pass's prediction errors as the innovation
        K = _output_error_fit(A, C, es, [v - e for v, e in zip(vs, es)], False)[0]
        for Kc in (K, K0):
            if np.all(np.isfinite(Kc)) and np.all(np.abs(np.linalg.eigvals(A - Kc @ C)) < 1):
                E = _predictor_errors(A, B, C, D, Kc, us, ys)
                ld = np.linalg.slogdet(E.T @ E / len(E))[1]
                if best is None or ld < best[0]:
                    best = (ld, Kc, E)
        if best is None:
            break
        cut = np.cumsum([len(y) for y in ys])[:-1]
        es = np.split(best[2], cut)
    if best is None:  # no stable predictor: the output error (A is stable)
        K, E = np.zeros_like(K0), np.concatenate(vs)
    else:
        K, E = best[1], best[2]
    return K, E.T @ E / len(E)


def _innovation_gain(A, C, Q, S, R) -> tuple[np.ndarray, np.ndarray]:
    """Steady Kalman predictor gain and innovation covariance of the noise covariances ``Q, S, R``."""
    try:
        P = scipy.linalg.solve_discrete_are(A.T, C.T, Q, R, s=S)
        Re = C @ P @ C.T + R
        return np.linalg.solve(Re, (A @ P @ C.T + S).T).T, Re
    except (np.linalg.LinAlgError, ValueError):
        # The residuals are (nearly) of innovation form already: Q = K R Kᵀ, S = K R.
        return np.linalg.lstsq(R, S.T, rcond=None)[0].T, R
