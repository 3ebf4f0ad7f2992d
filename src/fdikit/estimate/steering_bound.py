"""Guaranteed error bounds of the steering-fault isolation filters (van der Ploeg 2018, Thm 3-1.3, Thm 3-2.1).

The bounds compare the moving-window estimates with the window means of the true faults::

    θ_e = ‖[f̂_a − μ_n[f_a];  f̂_m − μ_n[f_m]]‖_2  ≤  Θ_e = κ_n · (e_1 + e_2 + e_3)

and therefore need the true faults: they are analysis tools for simulation (Sec. 4-3-2, 4-3-3).
``κ_n`` bounds the induced norm of the regression operator ``Φ_n`` (Lemma A-1.1).

Errata applied, each checked against the proofs in App. A (and numerically by ``tests/test_estimate_steering.py``):

* **Lemma A-1.1.** ``‖Φ_n‖_2² = ((1+σ²) + sqrt((1−σ²)² + 4μ²)) / (2 n V)``; the printed bound
  ``(1 + |μ|)/(n V)`` drops ``|1 − σ²|`` and holds only for ``σ_n² ≤ 1``.  fdikit uses
  ``κ_n = sqrt((max(1, σ_n²) + |μ_n|)/(n V_n))`` (valid always, equal to the printed one when
  ``σ_n² ≤ 1``) and reports the printed factor and the exact norm as well.
* **(3.6b).** The square root covers only ``n V_n[f_m]``: ``e_2 = sqrt(n V_n[f_m]) ‖E‖_{L_n∞}`` (Lemma A-1.2).
* **e_1.** The thesis builds it from the restricted matrices ``T_n, O_n`` (Def. 3-1.2) of ``G(q) − I``
  (Sec. 4-3-2 says "of the filter (4.9)", a slip); that term equals ``‖r − (f_a + Δ E)‖_{L_n2}``,
  ``Δ = f_m − nominal``, which fdikit evaluates directly.  Taken from the residual itself, this
  also covers any residual content not explained by ``G`` (disturbance leakage, noise, model error).
* **(3.10a), Lemma A-2.1.** The commutator term ``(T̃_n f_m□ − f_m□ T̃_n) E_n`` is not diagonal, so
  it is bounded by ``‖T̃_n f_m□ − f_m□ T̃_n‖_2 ‖E_n‖_2`` (window 2-norm), not by the printed
  ``‖E‖_{L_n∞}``.  Both forms are reported; the printed one (``bound_thesis``) is not guaranteed.
  (4.16) prints ``‖δ̃_set‖`` there, a third variant; fdikit follows (3.10a).
* **Cor. 3-2.2.** For constant faults ``ẽ_1`` decays exponentially (rate of the poles of ``G``), reaching
  zero in finite time only for a deadbeat ``G``.

Window vectors are newest first, ``x_n(k) = [x(k), …, x(k−n+1)]`` (Sec. 1-4), so
``y_n(k) = O_n x(k−n+1) + T_n u_n(k)`` with ``O_n = [C A^{n−1}; …; C A; C]`` and the upper
triangular Toeplitz ``T_n`` (Def. 3-1.2; the stray ``y(k−n+1)`` entry of the printed ``O_n`` is an
extraction artefact).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike

from fdikit import validate
from fdikit.errors import DataError
from fdikit.estimate.steering import FaultMap, SteeringFaultEstimate, fault_map_coefficients
from fdikit.lti import dlsim_blocked

__all__ = ["IsolationErrorBound", "isolation_error_bound", "restricted_matrices"]

_CHUNK = 1 << 22  # elements per batched block of n x n commutators


def _realisation(fault_map: FaultMap) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Controllable canonical form of ``num/den`` (as :func:`scipy.signal.tf2ss`, without its warnings)."""
    num, den = fault_map_coefficients(fault_map)  # monic den, len(num) == len(den)
    d = den.size - 1
    A = np.zeros((d, d))
    if d:
        A[0] = -den[1:]
        A[1:, :-1] = np.eye(d - 1)
    B = np.zeros((d, 1))
    if d:
        B[0, 0] = 1.0
    C = (num[1:] - num[0] * den[1:]).reshape(1, d)
    D = np.array([[num[0]]])
    return A, B, C, D


def restricted_matrices(fault_map: FaultMap, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Restricted state and input matrices ``(O_n, T_n)`` of a SISO map (van der Ploeg 2018, Def. 3-1.2).

    For the controllable-canonical realisation ``(A, B, C, D)`` of ``fault_map`` (minimal when
    numerator and denominator are coprime), newest first::

        [y(k); …; y(k−n+1)] = O_n x(k−n+1) + T_n [u(k); …; u(k−n+1)]
        O_n = [C A^{n−1}; …; C A; C],   T_n[i, j] = D (j = i),  C A^{j−i−1} B (j > i),  0 (j < i).

    Parameters
    ----------
    fault_map : FaultMap
        The SISO map ``G(q)`` (a :class:`scipy.signal.dlti` or a ``(num, den)`` pair), proper and stable.
    n : int
        Horizon (window length), ≥ 1.

    Returns
    -------
    O : ndarray
        ``O_n`` (n x d), d the order of the realisation.
    T : ndarray
        ``T_n`` (n x n), upper triangular Toeplitz.

    Raises
    ------
    DataError
        If ``n`` is not a positive integer.
    ModelError, DesignError
        If ``fault_map`` is not a proper, stable SISO map (:func:`~fdikit.estimate.steering.fault_map_coefficients`).

    Examples
    --------
    >>> O, T = restricted_matrices(([0.0, 0.5], [1.0, -0.5]), 3)   # G(q) = 0.5/(q − 0.5)
    >>> T
    array([[0.  , 0.5 , 0.25],
           [0.  , 0.  , 0.5 ],
           [0.  , 0.  , 0.  ]])
    >>> O.ravel().tolist()
    [0.125, 0.25, 0.5]

    References
    ----------
    van der Ploeg 2018, Def. 3-1.2; §1-4 (window notation).
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise DataError(f"horizon n must be a positive integer, got {n!r}")
    A, B, C, D = _realisation(fault_map)
    n = int(n)
    d = A.shape[0]
    CA = np.zeros((n, d))  # row j = C A^j
    row = C[0].copy() if d else np.zeros(0)
    for j in range(n):
        CA[j] = row
        row = row @ A
    O = CA[::-1].copy()
    markov = np.empty(n)  # h_0 = D, h_m = C A^{m-1} B
    markov[0] = D[0, 0]
    if n > 1:
        markov[1:] = CA[: n - 1] @ B[:, 0] if d else 0.0
    i, j = np.indices((n, n))
    T = np.where(j >= i, markov[np.clip(j - i, 0, n - 1)], 0.0)
    return O, T


@dataclass(frozen=True, eq=False)
class IsolationErrorBound:
    """Estimation error and its guaranteed bound per sample (Thm 3-1.3, or Thm 3-2.1 for the pre-filter).

    Attributes
    ----------
    t : ndarray
        (N,) times.
    theta : ndarray
        (N,) ``θ_e = ‖[f̂_a − μ_n[f_a]; f̂_m − μ_n[f_m]]‖_2``.
    bound : ndarray
        (N,) ``Θ_e`` with the corrections of the module docstring (a guaranteed bound).
    bound_thesis : ndarray
        (N,) ``Θ_e`` as printed ((3.5) / (3.9)): factor ``sqrt((1+|μ|)/(nV))`` and, for the
        pre-filter, the commutator times ``‖E‖_{L_n∞}``.
    factor, factor_thesis, regressor_norm : ndarray
        (N,) corrected ``κ_n``, printed ``κ_n``, exact ``‖Φ_n‖_2``.
    e1, e2, e3 : ndarray
        (N,) the error terms (3.6a)–(3.6c), or ``ẽ_1`` (corrected), ``ẽ_2``, ``e_3`` (3.10).
    e1_thesis : ndarray
        (N,) ``ẽ_1`` as printed (equal to ``e1`` without the pre-filter).
    mismatch : ndarray or None
        (N,) ``‖r − G[f_a + Δ E]‖_{L_n2}``, the residual content the pre-filter bound's model
        does not explain (≈ 0 for an exact residual generator; added to ``e1`` and ``e1_thesis``),
        or None without the pre-filter (``e1`` already contains it).
    valid : ndarray of bool
        (N,) the estimate's validity mask; every array is NaN where it is False.
    prefiltered : bool
        Whether this is the pre-filter bound (3.9).

    Examples
    --------
    >>> from fdikit.estimate.steering import isolate_steering_faults
    >>> E = np.array([1.0, 2.0, 4.0, 3.0, 1.0, 2.0])
    >>> r = 0.1 + (1.5 - 1.0) * E                      # exact faults f_a = 0.1, f_m = 1.5 with G = 1
    >>> b = isolation_error_bound(isolate_steering_faults(r, E, n=3), r, E, 0.1, 1.5)
    >>> b.prefiltered, b.mismatch is None, bool(np.nanmax(b.theta) < 1e-12), bool(np.nanmax(b.bound) < 1e-12)
    (False, True, True, True)

    References
    ----------
    van der Ploeg 2018, Thm 3-1.3, (3.5)–(3.6); Thm 3-2.1, (3.9)–(3.10); App. A, Lemma A-1.1.
    """

    t: np.ndarray
    theta: np.ndarray
    bound: np.ndarray
    bound_thesis: np.ndarray
    factor: np.ndarray
    factor_thesis: np.ndarray
    regressor_norm: np.ndarray
    e1: np.ndarray
    e1_thesis: np.ndarray
    e2: np.ndarray
    e3: np.ndarray
    mismatch: np.ndarray | None
    valid: np.ndarray
    prefiltered: bool

    @property
    def ratio(self) -> np.ndarray:
        """``θ_e / Θ_e`` (≤ 1 by the theorem; NaN where invalid)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.theta / self.bound


def _windows(x: np.ndarray, n: int) -> np.ndarray:
    """(N, n) newest-first windows, rows before the first full window NaN."""
    out = np.full((x.size, n), np.nan)
    if x.size >= n:
        out[n - 1 :] = sliding_window_view(x, n)[:, ::-1]
    return out


def _l2(w: np.ndarray) -> np.ndarray:
    return np.sqrt(np.sum(w * w, axis=1))


def _var(w: np.ndarray) -> np.ndarray:
    return np.mean((w - w.mean(axis=1, keepdims=True)) ** 2, axis=1)


def _gramians(A: np.ndarray, B: np.ndarray, C: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Finite Gramians ``W_o[m] = Σ_{i<m} A^iᵀ CᵀC A^i`` and ``W_c[m] = Σ_{i<m} A^i B Bᵀ A^iᵀ``, m = 0..n."""
    d = A.shape[0]
    Wo, Wc = np.zeros((n + 1, d, d)), np.zeros((n + 1, d, d))
    ca, ab = C.copy(), B.copy()
    for m in range(n):
        Wo[m + 1] = Wo[m] + ca.T @ ca
        Wc[m + 1] = Wc[m] + ab @ ab.T
        ca, ab = ca @ A, A @ ab
    return Wo, Wc


def _commutator_norms(realisation, T: np.ndarray, dw: np.ndarray) -> np.ndarray:
    """``‖T diag(δ) − diag(δ) T‖_2`` per newest-first window row of ``dw``; exactly 0 where δ is constant.

    ``(T D − D T)[i, j] = T[i, j] (δ_j − δ_i)``.  When δ changes once in the window, from ``b`` (older,
    ``j ≥ s``) to ``a`` (newer, ``i < s``), only the block ``T[:s, s:] = [C A^{s−1−i} A^{j−s} B]`` survives;
    it has rank ≤ the filter order, and ``‖·‖_2 = |a − b| sqrt(λ_max(W_o(s) W_c(n − s)))`` with the finite
    Gramians.  Windows with several changes fall back to a dense SVD.
    """
    A, B, C, _ = realisation
    n = T.shape[0]
    out = np.zeros(dw.shape[0])
    jumps = np.diff(dw, axis=1) != 0
    count = jumps.sum(axis=1)
    single = np.flatnonzero(count == 1)
    if single.size:
        Wo, Wc = _gramians(A, B, C, n)
        s = np.argmax(jumps[single], axis=1) + 1  # first older index
        step = np.abs(dw[single, 0] - dw[single, -1])
        # λ_max(W_o W_c) = λ_max(R W_o Rᵀ) with W_c = Rᵀ R (symmetric form; W_c is PSD)
        w, V = np.linalg.eigh(Wc[n - s])
        R = np.sqrt(np.clip(w, 0.0, None))[:, :, None] * np.swapaxes(V, 1, 2)
        M = R @ Wo[s] @ np.swapaxes(R, 1, 2)
        out[single] = step * np.sqrt(np.clip(np.linalg.eigvalsh(M)[:, -1], 0.0, None))
    multi = np.flatnonzero(count > 1)
    chunk = max(1, _CHUNK // (n * n))
    for lo in range(0, multi.size, chunk):
        rows = multi[lo : lo + chunk]
        d = dw[rows]
        comm = T[None, :, :] * (d[:, None, :] - d[:, :, None])
        out[rows] = np.linalg.norm(comm, 2, axis=(1, 2))
    return out


def isolation_error_bound(
    estimate: SteeringFaultEstimate,
    residual: ArrayLike,
    setpoint: ArrayLike,
    f_a: ArrayLike,
    f_m: ArrayLike,
) -> IsolationErrorBound:
    """Error ``θ_e`` and bound ``Θ_e`` of a steering-fault estimate, given the true faults.

    van der Ploeg 2018, Thm 3-1.3 ((3.5)–(3.6), (4.12a)) for the plain FI filter and Thm 3-2.1
    ((3.9)–(3.10), (4.14)) for the pre-filter FI filter, with the corrections listed in the module
    docstring.

    Parameters
    ----------
    estimate : SteeringFaultEstimate
        Result of :func:`~fdikit.estimate.steering.isolate_steering_faults` on ``residual`` and ``setpoint``.
    residual, setpoint : (N,) arrays
        The same residual ``r`` and known signal ``E`` (unfiltered) the estimate was computed from.
    f_a, f_m : (N,) arrays or scalars
        True additive fault (units of ``r``) and true gain (``estimate.nominal_gain`` when healthy).

    Returns
    -------
    IsolationErrorBound
        ``θ_e``, the corrected and the printed bounds and their terms per sample.

    Raises
    ------
    DataError
        If ``residual``/``setpoint`` do not have the estimate's length, or any input is non-finite.
    ParameterError
        If ``estimate`` is not a :class:`~fdikit.estimate.steering.SteeringFaultEstimate`.

    Examples
    --------
    >>> import numpy as np, scipy.signal
    >>> from fdikit.estimate.steering import isolate_steering_faults, lateral_fault_map, fault_map_coefficients
    >>> k = np.arange(2000)
    >>> E = 2.3e-3 * np.sin(0.6 * np.pi * 0.01 * k)
    >>> num, den = fault_map_coefficients(lateral_fault_map())
    >>> r = scipy.signal.lfilter(num, den, 1.7e-3 + (0.5 - 1.0) * E)
    >>> est = isolate_steering_faults(r, E, n=100)
    >>> b = isolation_error_bound(est, r, E, 1.7e-3, 0.5)
    >>> bool(np.all(b.theta[est.valid] <= b.bound[est.valid]))
    True

    References
    ----------
    van der Ploeg 2018, Thm 3-1.3, (3.5)–(3.6), (4.12a); Thm 3-2.1, (3.9)–(3.10), (4.14); App. A.
    """
    validate.instance("estimate", estimate, SteeringFaultEstimate, "pass the result of isolate_steering_faults(...)")
    r = validate.as_array("residual", residual, error=DataError, finite=False)
    E = validate.as_array("setpoint", setpoint, error=DataError, finite=False)
    N = len(estimate)
    if r.shape != (N,) or E.shape != (N,):
        raise DataError(
            f"residual {r.shape} and setpoint {E.shape} must be the ({N},) arrays (samples) the estimate was "
            "computed from"
        )
    fa = np.broadcast_to(np.asarray(f_a, dtype=float), (N,)).astype(float)
    fm = np.broadcast_to(np.asarray(f_m, dtype=float), (N,)).astype(float)
    for name, x in (("residual", r), ("setpoint", E), ("f_a", fa), ("f_m", fm)):
        if not np.all(np.isfinite(x)):
            raise DataError(f"{name} has non-finite values; the error bound is evaluated on clean simulated data only")
    n = estimate.n
    delta = fm - estimate.nominal_gain
    Xw = _windows(estimate.regressor, n)  # E or Ẽ
    mu, V = Xw.mean(axis=1), _var(Xw)
    sigma2 = V + mu * mu
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.sqrt((np.maximum(1.0, sigma2) + np.abs(mu)) / (n * V))
        factor_thesis = np.sqrt((1.0 + np.abs(mu)) / (n * V))
        regressor_norm = np.sqrt(((1.0 + sigma2) + np.sqrt((1.0 - sigma2) ** 2 + 4.0 * mu * mu)) / (2.0 * n * V))
    faw, fmw = _windows(fa, n), _windows(fm, n)
    theta = np.hypot(estimate.f_a_hat - faw.mean(axis=1), estimate.f_m_hat - fmw.mean(axis=1))
    e2 = np.sqrt(n * _var(fmw)) * np.max(np.abs(Xw), axis=1)
    e3 = np.sqrt(n * _var(faw))
    mismatch = None
    if not estimate.prefiltered:
        e1 = _l2(_windows(r - (fa + delta * E), n))
        e1_thesis = e1
    else:
        A, B, C, D = realisation = _realisation(estimate.prefilter)
        O, T = restricted_matrices(estimate.prefilter, n)
        _, xA, _ = dlsim_blocked(A, B, C, D, fa[:, None])
        yM, xM, _ = dlsim_blocked(A, B, C, D, (delta * E)[:, None])
        _, xE, _ = dlsim_blocked(A, B, C, D, E[:, None])
        yA = xA @ C.T[:, 0] + D[0, 0] * fa
        mismatch = _l2(_windows(r - (yA + yM[:, 0]), n))
        start = np.clip(np.arange(N) - n + 1, 0, None)  # x(k − n + 1)
        dw = _windows(delta, n)
        term_m = _l2((xM[start] @ O.T) - dw * (xE[start] @ O.T))  # ‖Õ x_M − Δ□ Õ x_E‖
        term_a = _l2(_windows(yA - fa, n))  # ‖Õ x_A + T̃ f_a − f_a‖
        comm = _commutator_norms(realisation, T, np.nan_to_num(dw))
        Ew = _windows(E, n)
        e1 = term_m + term_a + comm * _l2(Ew) + mismatch
        e1_thesis = term_m + term_a + comm * np.max(np.abs(Ew), axis=1) + mismatch
    bound = factor * (e1 + e2 + e3)
    bound_thesis = factor_thesis * (e1_thesis + e2 + e3)
    valid = estimate.valid.copy()

    def masked(x):
        return None if x is None else np.where(valid, x, np.nan)

    return IsolationErrorBound(
        estimate.t, masked(theta), masked(bound), masked(bound_thesis), masked(factor), masked(factor_thesis),
        masked(regressor_norm), masked(e1), masked(e1_thesis), masked(e2), masked(e3), masked(mismatch), valid,
        estimate.prefiltered,
    )
