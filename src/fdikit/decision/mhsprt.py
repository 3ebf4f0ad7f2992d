"""Multiple-hypothesis Shiryayev SPRT (Malladi & Speyer; Douglas et al. 1996, Ch. 7).

``m + 1`` hypotheses: ``H_0`` (no fault, density ``f_0``) and ``H_i`` (fault ``i`` has happened, density
``f_i``).  ``p_i`` is the prior probability of a switch ``H_0 → H_i`` in one sample interval, ``π_i`` the
probability that fault ``i`` happened before the first sample, ``F_{k,i} = P(θ_i ≤ t_k | x_1..x_k)``.
Prop. 7.1, with the correction of research note G11 (the proof's step (7.6c) writes ``p_i (1 − F_{k,i})``; under
the single-fault assumption the probability that no fault has happened yet is ``1 − Σ_j F_{k,j} = F_{k,0}``)::

    F_{0,i}   = π_i,  F_{0,0} = 1 − Σ_i π_i                                   (7.1a)
    M_{k,i}   = F_{k,i} + p_i (1 − Σ_j F_{k,j})                               (7.1c, corrected)
    F_{k+1,i} = M_{k,i} f_i(x) / [Σ_j M_{k,j} f_j(x) + (1 − Σ_j M_{k,j}) f_0(x)]   (7.1b, denominator index fixed)

This is the Bayes filter of the absorbing chain ``0 → i`` and satisfies Prop. 7.2 (``0 ≤ F_{k,i}``,
``Σ_i F_{k,i} ≤ 1``) for any data.  It runs in the log domain: ``log F_{k,0}`` is a state of its own
(``M_{k,0} = F_{k,0} (1 − Σ p_i)``), the update is a log-sum-exp, so 11-D Gaussian densities and long runs never
underflow.  ``form="literal"`` runs the printed (7.1c) ``M_{k,i} = F_{k,i} + p_i (1 − F_{k,i})``, which lets
``Σ_j M_{k,j}`` exceed 1 and breaks Prop. 7.2 (``Σ_i F_{k,i} > 1``, note §6.4); its quantities can leave
``[0, 1]``, so it is kept in linear form (densities scaled by their maximum).  For ``m = 1`` both are the same.

Decision (§7.2.2–7.2.3): announce fault ``i`` while ``F_{k,i} ≥ F_{T,i}``; ``α_i = 1 − F_{T,i}`` bounds the
probability that an announcement is a false alarm (Shiryayev).  Densities: :class:`GaussianDensity`,
:func:`gaussian_mean_density` (Prop. 7.4) and :class:`UniformMeanDensity` (Prop. 7.5, corrected for ``n > 1``),
or any object with ``dim`` and a row-wise ``logpdf``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.special import expit, log_ndtr, logsumexp, ndtr

from fdikit.diagnosis import UNKNOWN_FAULT, Diagnosis, StepDecision
from fdikit.errors import DataError, ModelError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = [
    "GaussianDensity",
    "MhsprtEvaluator",
    "ShiryayevDP",
    "UniformMeanDensity",
    "gaussian_mean_density",
    "magnitude_blocks",
    "shiryayev_dp",
    "shiryayev_threshold",
]

_LOG2PI = np.log(2.0 * np.pi)


# ---------------------------------------------------------------------------------------------------------- densities
def _vec(value, name: str, n: int | None = None) -> np.ndarray:
    v = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if n is not None and v.size != n:
        raise ModelError(f"{name} has {v.size} entries, need {n}")
    if not np.all(np.isfinite(v)):
        raise ModelError(f"{name} has non-finite entries: {v}")
    return v


def _cov(value, n: int, name: str = "covariance", regularization: float = 0.0, definite: bool = True) -> np.ndarray:
    """A scalar (σ² I), a vector (diagonal) or an (n, n) matrix → a symmetric positive definite matrix, or refuse."""
    c = np.asarray(value, dtype=float)
    c = c * np.eye(n) if c.ndim == 0 else np.diag(c) if c.ndim == 1 else c
    if c.shape != (n, n) or not np.all(np.isfinite(c)):
        raise ModelError(f"{name} must be a finite ({n}, {n}) matrix, got shape {c.shape}")
    scale = np.abs(c).max(initial=0.0)
    if np.abs(c - c.T).max(initial=0.0) > 1e-8 * scale:
        raise ModelError(f"{name} is not symmetric (max |Λ − Λᵀ| = {np.abs(c - c.T).max():.3g})")
    c = 0.5 * (c + c.T)
    if regularization:
        if not regularization > 0:
            raise ModelError(f"regularization must be positive, got {regularization}")
        c = c + regularization * np.diag(np.diag(c))
    if not definite:
        return c
    d = np.diag(c)
    if not np.all(d > 0):
        raise ModelError(f"{name} has zero or negative variance in component(s) {np.flatnonzero(~(d > 0)).tolist()}; "
                         "drop constant residual components, or pass regularization=ε (adds ε·diag(Λ))")
    ev = np.linalg.eigvalsh(c / np.sqrt(np.outer(d, d)))  # of the correlation matrix: scale-free conditioning
    if not ev[0] > 1e3 * n * np.finfo(float).eps:
        raise ModelError(
            f"{name} is singular (smallest correlation eigenvalue {ev[0]:.3g}: components are linearly dependent); "
            "remove duplicated residual components, or pass regularization=ε (adds ε·diag(Λ))"
        )
    return c


def _whiten(d: np.ndarray, W: np.ndarray) -> np.ndarray:
    """``d @ W.T`` summed in a fixed order, so one row gives the same bits alone as in a batch (batch == online)."""
    out = d[:, :1] * W[:, 0]
    for j in range(1, W.shape[1]):
        out = out + d[:, j : j + 1] * W[:, j]
    return out


def _sumsq(z: np.ndarray) -> np.ndarray:
    out = z[:, 0] * z[:, 0]
    for j in range(1, z.shape[1]):
        out = out + z[:, j] * z[:, j]
    return out


def _rows(x, n: int) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    x = x.reshape(-1, 1) if (x.ndim <= 1 and n == 1) else np.atleast_2d(x)
    if x.shape[1] != n:
        raise DataError(f"samples have {x.shape[1]} components, the density has {n}")
    return x


@dataclass(frozen=True, eq=False)
class GaussianDensity:
    """``N(mean, cov)``; ``cov`` may be a variance (scalar), variances (vector) or a matrix.

    A singular covariance is refused (:class:`ModelError`) unless ``regularization=ε`` adds ``ε·diag(Λ)``
    (shrinks the correlations by ``1/(1 + ε)``; a component of zero variance is refused either way).
    """

    mean: np.ndarray
    cov: np.ndarray
    regularization: float = 0.0

    def __post_init__(self) -> None:
        mean = _vec(self.mean, "mean")
        cov = _cov(self.cov, mean.size, regularization=self.regularization)
        L = np.linalg.cholesky(cov)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)
        object.__setattr__(self, "_W", scipy.linalg.solve_triangular(L, np.eye(mean.size), lower=True))
        object.__setattr__(self, "_const", -0.5 * (mean.size * _LOG2PI + 2.0 * np.log(np.diag(L)).sum()))
        object.__setattr__(self, "_Wrows", [row[: i + 1] for i, row in enumerate(self._W.tolist())])

    @property
    def dim(self) -> int:
        return self.mean.size

    def logpdf(self, x) -> np.ndarray:
        """Log density of each row of ``x`` (N, n)."""
        d = _rows(x, self.dim) - self.mean
        if d.shape[0] == 1:  # one sample (online): the same IEEE operations in the same order, without array overhead
            d1, s = d[0].tolist(), 0.0
            for i, w in enumerate(self._Wrows):  # W is lower triangular: the skipped terms add exact zeros
                acc = d1[0] * w[0]
                for j in range(1, i + 1):
                    acc = acc + d1[j] * w[j]
                s = acc * acc if i == 0 else s + acc * acc
            return np.array([self._const - 0.5 * s])
        return self._const - 0.5 * _sumsq(_whiten(d, self._W))


def gaussian_mean_density(center, cov, mean_cov, regularization: float = 0.0) -> GaussianDensity:
    """Prop. 7.4: ``x ~ N(m, Λ)`` with an unknown mean ``m ~ N(m*, Σ_μ)`` has the density ``N(m*, Λ + Σ_μ)``.

    Derivation (simpler than the report's completion of squares, whose printed constants are garbled):
    ``x = m + v`` with ``v ~ N(0, Λ)`` independent of ``m``; a sum of independent Gaussians is Gaussian with the
    sum of means and covariances.  ``Σ_μ`` may be singular (a mean known in some directions).
    """
    center = _vec(center, "center")
    n = center.size
    lam = _cov(cov, n, "cov", definite=False)
    s = _cov(mean_cov, n, "mean_cov", definite=False)
    if np.linalg.eigvalsh(s)[0] < -1e-12 * np.abs(s).max(initial=0.0):
        raise ModelError("mean_cov must be positive semi-definite")
    return GaussianDensity(center, lam + s, regularization)


def _log_ndtr_diff(u: np.ndarray, l: np.ndarray) -> np.ndarray:
    """``log(Φ(u) − Φ(l))`` for ``u ≥ l``, accurate in both tails (``log_ndtr`` never underflows)."""
    out = np.empty(np.broadcast(u, l).shape)
    u, l = np.broadcast_to(u, out.shape), np.broadcast_to(l, out.shape)
    hi, lo, mid = l > 0, u < 0, (l <= 0) & (u >= 0)
    with np.errstate(divide="ignore"):
        a, b = log_ndtr(-l[hi]), log_ndtr(-u[hi])
        out[hi] = a + np.log(-np.expm1(b - a))
        a, b = log_ndtr(u[lo]), log_ndtr(l[lo])
        out[lo] = a + np.log(-np.expm1(b - a))
        out[mid] = np.log(ndtr(u[mid]) - ndtr(l[mid]))
    return out


@dataclass(frozen=True, eq=False)
class UniformMeanDensity:
    """Prop. 7.5: ``x ~ N(m, Λ)`` with the mean uniform on the box ``low ≤ m ≤ high`` (report: ``b = low``,
    ``2 m* = high − low``).

    ``method="erf"`` (diagonal ``Λ = diag σ_j²`` only) — the corrected density, a product of per-component
    differences (the printed formula, a difference of products of erfs, does not integrate to 1 for ``n > 1``)::

        f(x) = Π_j [Φ((x_j − low_j)/σ_j) − Φ((x_j − high_j)/σ_j)] / (high_j − low_j)

    evaluated as ``log Φ`` differences (no tail underflow); a component of zero width is the Gaussian limit.
    A non-diagonal ``Λ`` does not factor over the box: ``"erf"`` refuses it; ``method="mixture"`` replaces the
    uniform mean by ``n_points`` scrambled-Sobol points in the box drawn with ``rng`` (seeded; same seed, same
    density), i.e. an equal-weight Gaussian mixture — itself a proper density, so the recursion stays exact Bayes
    for it.
    """

    low: np.ndarray
    high: np.ndarray
    cov: np.ndarray
    method: str = "erf"
    n_points: int = 1024
    rng: np.random.Generator | int | None = None
    regularization: float = 0.0

    def __post_init__(self) -> None:
        low = _vec(self.low, "low")
        high = _vec(self.high, "high", low.size)
        if np.any(high < low):
            raise ModelError(f"the box needs low <= high, got low={low}, high={high}")
        cov = _cov(self.cov, low.size, regularization=self.regularization)
        set_ = object.__setattr__
        set_(self, "low", low)
        set_(self, "high", high)
        set_(self, "cov", cov)
        if self.method == "erf":
            off = cov - np.diag(np.diag(cov))
            if np.abs(off).max(initial=0.0) > 0:
                raise ModelError(
                    "the erf form of Prop. 7.5 needs a diagonal covariance (the box does not factor otherwise); "
                    "use method='mixture' with a seeded rng, or keep only the variances"
                )
            sig = np.sqrt(np.diag(cov))
            set_(self, "_sig", sig)
            set_(self, "_point", (high - low) <= 1e-8 * sig)
        elif self.method == "mixture":
            if self.rng is None:
                raise ModelError("method='mixture' draws points in the box: pass rng= (a seed or a Generator)")
            from scipy.stats import qmc

            k = int(np.ceil(np.log2(max(int(self.n_points), 2))))
            u = qmc.Sobol(low.size, scramble=True, rng=self.rng).random_base2(k)
            g = GaussianDensity(np.zeros(low.size), cov)
            set_(self, "_g", g)
            set_(self, "_zm", _whiten(low + u * (high - low), g._W))
        else:
            raise ModelError(f"unknown method {self.method!r}; use 'erf' or 'mixture'")

    @property
    def dim(self) -> int:
        return self.low.size

    def logpdf(self, x) -> np.ndarray:
        x = _rows(x, self.dim)
        if self.method == "erf":
            s, lo, hi, pt = self._sig, self.low, self.high, self._point
            with np.errstate(divide="ignore", invalid="ignore"):  # zero-width columns are replaced below
                val = _log_ndtr_diff((x - lo) / s, (x - hi) / s) - np.log(hi - lo)
            if pt.any():  # zero-width components: the Gaussian limit
                z = (x[:, pt] - 0.5 * (lo[pt] + hi[pt])) / s[pt]
                val[:, pt] = -0.5 * (_LOG2PI + z * z) - np.log(s[pt])
            out = val[:, 0]
            for j in range(1, self.dim):
                out = out + val[:, j]
            return out
        zx, zm, K = _whiten(x, self._g._W), self._zm, self._zm.shape[0]
        out = np.empty(x.shape[0])
        step = max(1, 2_000_000 // K)
        for s in range(0, x.shape[0], step):
            d2 = np.zeros((min(step, x.shape[0] - s), K))
            for j in range(self.dim):
                d2 = d2 + (zx[s : s + step, j : j + 1] - zm[:, j]) ** 2
            out[s : s + step] = logsumexp(-0.5 * d2, axis=1)
        return out + self._g._const - np.log(K)


# --------------------------------------------------------------------------------------------------------- thresholds
def shiryayev_threshold(
    false_alarm_prob: float | None = None,
    *,
    false_alarm_cost: float | None = None,
    delay_cost: float | None = None,
    measurement_cost: float = 0.0,
) -> float:
    """The announcement threshold ``F_T`` (§7.2.3).

    * from a false-alarm probability ``α``: ``F_T = 1 − α`` — at an announcement ``P(no fault | data) = 1 − F ≤ α``,
      so ``P(false alarm) ≤ α`` when the change time follows the prior (the report's "practical rule");
    * from costs ``Q`` (false alarm), ``S`` (miss-alarm, i.e. delay, per sample) and ``C`` (per measurement): the
      report's bound on the infinite-horizon threshold, ``F_T ≤ (Q − C)/(Q + S)`` (from (7.21) with ``A ≥ 0``).
      The exact value needs the expected cost-to-go ``A(F_T)``; :func:`shiryayev_dp` computes it for ``m = 1``.
    """
    if (false_alarm_prob is None) == (false_alarm_cost is None):
        raise ModelError("give either false_alarm_prob, or false_alarm_cost and delay_cost")
    if false_alarm_prob is not None:
        if not 0 < false_alarm_prob < 1:
            raise ModelError(f"false-alarm probability must be in (0, 1), got {false_alarm_prob}")
        return 1.0 - float(false_alarm_prob)
    Q, S, C = float(false_alarm_cost), float(delay_cost if delay_cost is not None else np.nan), float(measurement_cost)
    if not (S >= 0 and C >= 0 and Q > C):
        raise ModelError(f"need delay_cost >= 0, measurement_cost >= 0 and false_alarm_cost > measurement_cost "
                         f"(7.10b), got Q={Q}, S={S}, C={C}")
    return (Q - C) / (Q + S)


@dataclass(frozen=True, eq=False)
class ShiryayevDP:
    """Result of :func:`shiryayev_dp`.

    ``threshold``: infinite-horizon ``F_T`` (7.21); ``bound``: ``(Q − C)/(Q + S)``; ``horizon_thresholds[n−1]``:
    the threshold with ``n`` stages to go (non-decreasing in ``n``, → ``threshold``); ``grid``/``cost``: ``J*(F)``;
    ``converged``: value iteration met ``tol``.
    """

    threshold: float
    bound: float
    horizon_thresholds: np.ndarray
    grid: np.ndarray
    cost: np.ndarray
    iterations: int
    converged: bool

    def expected_cost(self, F: float) -> float:
        """Bayes risk ``J*(F)`` of the optimal policy started at posterior ``F``."""
        return float(np.interp(F, self.grid, self.cost))


def _support(d) -> tuple[float, float]:
    if isinstance(d, GaussianDensity):
        s = np.sqrt(d.cov[0, 0])
        return d.mean[0] - 12 * s, d.mean[0] + 12 * s
    if isinstance(d, UniformMeanDensity):
        s = np.sqrt(d.cov[0, 0])
        return d.low[0] - 12 * s, d.high[0] + 12 * s
    raise ModelError("pass x_range=(lo, hi) for densities other than GaussianDensity/UniformMeanDensity")


def shiryayev_dp(
    f0, f1, p: float, false_alarm_cost: float, delay_cost: float, measurement_cost: float = 0.0, *,
    grid_size: int = 401, nodes: int = 401, x_range: tuple[float, float] | None = None,
    tol: float = 1e-10, max_iter: int = 100_000,
) -> ShiryayevDP:
    """Dynamic-programming thresholds of §7.2.2 for the binary test (``m = 1``, scalar measurement).

    Value iteration on (7.8)–(7.10): ``J_N = (1 − F) Q``, ``J_k(F) = min[(1 − F) Q, C + S F + A_k(F)]`` with
    ``A_k(F) = E[J_{k+1}(F') | F]``, ``F'`` the posterior after the next sample, the expectation over the predictive
    density ``M f_1 + (1 − M) f_0``.  ``F`` lives on a logit-spaced grid (``J`` is concave, interpolated linearly),
    the expectation is a trapezoid rule on ``nodes`` points.  The report calls this intractable and stops at the
    bound; for ``m > 1`` the state is ``m``-dimensional and no grid is offered.
    """
    if not 0 <= p < 1:
        raise ModelError(f"p must be in [0, 1), got {p}")
    bound = shiryayev_threshold(false_alarm_cost=false_alarm_cost, delay_cost=delay_cost,
                                measurement_cost=measurement_cost)
    Q, S, C = float(false_alarm_cost), float(delay_cost), float(measurement_cost)
    if getattr(f0, "dim", 1) != 1 or getattr(f1, "dim", 1) != 1:
        raise ModelError("shiryayev_dp handles scalar measurements only")
    if x_range is None:
        (a0, b0), (a1, b1) = _support(f0), _support(f1)
        x_range = (min(a0, a1), max(b0, b1))
    x = np.linspace(*x_range, nodes)
    w = np.full(nodes, x[1] - x[0])
    w[[0, -1]] *= 0.5
    l0, l1 = f0.logpdf(x[:, None]), f1.logpdf(x[:, None])
    q0, q1 = w * np.exp(l0), w * np.exp(l1)
    q0, q1 = q0 / q0.sum(), q1 / q1.sum()
    F = np.concatenate([[0.0], expit(np.linspace(-30, 30, grid_size - 2)), [1.0]])
    M = F + p * (1.0 - F)
    with np.errstate(divide="ignore"):
        logit_M = np.log(M) - np.log1p(-M)
    Fn = expit(logit_M[:, None] + (l1 - l0)[None, :])  # posterior after each node, per grid point
    idx = np.clip(np.searchsorted(F, Fn) - 1, 0, F.size - 2)
    frac = (Fn - F[idx]) / (F[idx + 1] - F[idx])
    weight = M[:, None] * q1 + (1.0 - M[:, None]) * q0
    T = np.zeros((F.size, F.size))  # A = T @ J: predictive expectation of the interpolated J at the next posterior
    rows = np.broadcast_to(np.arange(F.size)[:, None], idx.shape)
    np.add.at(T, (rows, idx), weight * (1.0 - frac))
    np.add.at(T, (rows, idx + 1), weight * frac)
    stop = (1.0 - F) * Q
    J, thresholds, converged, it = stop.copy(), [], False, 0
    while it < max_iter:
        it += 1
        A = T @ J
        go = C + S * F + A
        J_new = np.minimum(stop, go)
        g = stop - go  # <= 0: stopping is optimal; the stop region is the top interval [F_T, 1]
        k = np.flatnonzero(g > 0)
        k = k[-1] if k.size else -1
        thresholds.append(F[0] if k < 0 else F[-1] if k == F.size - 1 else
                          F[k] + g[k] / (g[k] - g[k + 1]) * (F[k + 1] - F[k]))
        done = np.abs(J_new - J).max() <= tol * Q
        J = J_new
        if done:
            converged = True
            break
    return ShiryayevDP(float(thresholds[-1]), bound, np.array(thresholds), F, J, it, converged)


# ---------------------------------------------------------------------------------------------------------- evaluator
def magnitude_blocks(residuals: Residuals, groups: Sequence[str] | None = None) -> tuple[str, ...]:
    """Per residual component, the label of its block for ``MhsprtEvaluator(blocks=...)`` (note G9).

    Components tied to the same fault (and, with ``groups``, in the same filter of a bank) form one block whose
    Euclidean magnitude is one measurement component; an untied residual is a block of its own.
    """
    if groups is not None and len(groups) != len(residuals.names):
        raise ModelError(f"{len(groups)} groups for {len(residuals.names)} residuals")
    labels = []
    for k, (name, iso) in enumerate(zip(residuals.names, residuals.isolates)):
        base = iso if iso is not None else re.sub(r"\[\d+\]$", "", name)
        labels.append(base if groups is None else f"{groups[k]}:{base}")
    return tuple(labels)


def _per_fault(value, faults: tuple[str, ...], name: str) -> np.ndarray:
    if isinstance(value, Mapping):
        missing, extra = set(faults) - set(value), set(value) - set(faults)
        if missing or extra:
            raise ModelError(f"{name} must name exactly the faults {faults}; missing {sorted(missing)}, "
                             f"unknown {sorted(extra)}")
        v = np.array([float(value[f]) for f in faults])
    else:
        v = np.broadcast_to(np.asarray(value, dtype=float), (len(faults),)).copy() if np.ndim(value) == 0 else \
            np.asarray(value, dtype=float).ravel()
        if v.size != len(faults):
            raise ModelError(f"{name} has {v.size} entries for {len(faults)} faults {faults}")
    if not np.all(np.isfinite(v)):
        raise ModelError(f"{name} has non-finite entries: {v}")
    return v


class MhsprtEvaluator:
    """Multiple-hypothesis Shiryayev SPRT residual processor (Douglas et al. 1996, Ch. 7).

    Parameters
    ----------
    densities : mapping, optional
        ``{'none': f_0, fault: f_i, ...}``: objects with ``dim`` and ``logpdf(x (N, n)) -> (N,)``
        (:class:`GaussianDensity`, :func:`gaussian_mean_density`, :class:`UniformMeanDensity`, your own);
        otherwise :meth:`fit` builds Gaussian ones from residuals.
    p : float, sequence or mapping
        Per-sample prior switch probability ``p_i`` for each fault (a scalar applies to each); ``Σ p_i < 1``.
        It is per *sample*, so it scales with the sample time.  Defaults ``p = 1e−4``, ``π = 1e−3``,
        ``F_T = 0.95`` are note G11's assumptions (the report gives none for its application).
    pi : float, sequence or mapping
        ``π_i = P(fault i before the first sample)``; ``Σ π_i ≤ 1``.
    threshold : float, sequence or mapping
        ``F_{T,i}`` in (0, 1]; ``α_i = 1 − F_{T,i}`` (:func:`shiryayev_threshold`).
    form : ``'corrected'`` (default, Prop. 7.2 holds) or ``'literal'`` (the printed (7.1c); violates Prop. 7.2).
    blocks : sequence of str, optional
        One label per residual component (:func:`magnitude_blocks`): each block is replaced by its Euclidean
        magnitude before the test (the report's "residual magnitudes", note G9).  Magnitudes of fault-free
        residuals are far from Gaussian (χ-like, bounded by 0): on the PATH bank they gave false alarms where the
        raw components did not (docs/methods, R-SPRT-7).

    Output
    ------
    :meth:`run` returns a :class:`~fdikit.diagnosis.Diagnosis` with ``probabilities`` (N, m + 1), columns
    ``hypotheses = ('none', fault_1, …)`` — ``'none'`` first, ``F_{k,0}``; row ``k`` is the posterior after the
    sample at ``t[k]`` (``π`` is the state before the first sample).  ``fired`` (N, m) is ``F_{k,i} ≥ F_{T,i}``,
    ``isolated`` the fired fault ('none'; 'unknown' if several fire, possible only for ``F_T ≤ 0.5``).
    ``meta['log_probabilities']`` keeps ``log F`` (corrected form), which stays finite where ``F`` rounds to 0.
    A bad sample (NaN/inf, ``valid`` False, or zero density under every hypothesis) holds the posterior and is
    marked invalid; there is no time update for it.  Fault states are absorbing: :meth:`reset` after a repair.

    Examples
    --------
    Example 1 of §7.3.1: ``N(0.5 i, 1)``, a unit bias (``H_0 → H_2``) at t = 1 s.

    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> dens = {"none": GaussianDensity(0.0, 1.0), **{f"H{i}": GaussianDensity(0.5 * i, 1.0) for i in range(1, 5)}}
    >>> t = np.arange(501) * 0.01
    >>> x = np.random.default_rng(0).standard_normal(501) + (t >= 1.0)
    >>> d = MhsprtEvaluator(dens, p=1e-3, pi=1e-3).run(Residuals(t, x[:, None], ("x",), ()))
    >>> d.hypotheses, d.first_alarm().fault, round(d.first_alarm().time, 2)
    (('none', 'H1', 'H2', 'H3', 'H4'), 'H2', 1.45)
    """

    def __init__(self, densities: Mapping | None = None, *, p=1e-4, pi=1e-3, threshold=0.95,
                 form: str = "corrected", blocks: Sequence[str] | None = None) -> None:
        if form not in ("corrected", "literal"):
            raise ModelError(f"unknown form {form!r}; use 'corrected' or 'literal'")
        self.form, self.p, self.pi, self.threshold = form, p, pi, threshold
        self.blocks = None if blocks is None else tuple(blocks)
        self.names: tuple[str, ...] | None = None
        self.densities: dict | None = None
        if densities is not None:
            self._set_densities(dict(densities))
        self.reset()

    # ------------------------------------------------------------------ set-up
    def _set_densities(self, densities: dict) -> None:
        densities = {str(k): v for k, v in densities.items()}
        if NO_FAULT not in densities:
            raise ModelError(f"densities need the fault-free hypothesis {NO_FAULT!r}; got {list(densities)}")
        if len(densities) < 2:
            raise ModelError("need at least one fault hypothesis besides 'none'")
        dims = {k: getattr(d, "dim", None) for k, d in densities.items()}
        if None in dims.values() or not all(callable(getattr(d, "logpdf", None)) for d in densities.values()):
            raise ModelError("each density needs a 'dim' and a 'logpdf(x)'; see GaussianDensity")
        if len(set(dims.values())) != 1:
            raise ModelError(f"densities of different dimensions: {dims}")
        self.densities = {NO_FAULT: densities[NO_FAULT], **{k: v for k, v in densities.items() if k != NO_FAULT}}

    @property
    def hypotheses(self) -> tuple[str, ...]:
        return () if self.densities is None else tuple(self.densities)

    @property
    def faults(self) -> tuple[str, ...]:
        return self.hypotheses[1:]

    def _block_index(self) -> list[np.ndarray] | None:
        if self.blocks is None:
            return None
        labels = list(dict.fromkeys(self.blocks))
        return [np.flatnonzero([b == lab for b in self.blocks]) for lab in labels]

    def _features(self, r: np.ndarray) -> np.ndarray:
        if self.blocks is None:
            return r
        if r.shape[1] != len(self.blocks):
            raise DataError(f"{r.shape[1]} residual components for {len(self.blocks)} block labels")
        return np.column_stack([np.sqrt(_sumsq(r[:, idx])) for idx in self._block_index()])

    def _setup(self) -> None:
        faults = self.faults
        p = _per_fault(self.p, faults, "p")
        pi = _per_fault(self.pi, faults, "pi")
        ft = _per_fault(self.threshold, faults, "threshold")
        if np.any(p < 0) or not p.sum() < 1:
            raise ModelError(f"switch probabilities p must be >= 0 with sum < 1, got {p} (sum {p.sum():g})")
        if np.any(pi < 0) or not pi.sum() <= 1:
            raise ModelError(f"initial probabilities pi must be >= 0 with sum <= 1 (Prop. 7.2), got {pi}")
        if not np.all((ft > 0) & (ft <= 1)):
            raise ModelError(f"thresholds F_T must be in (0, 1], got {ft}")
        self._p, self._ft = p, ft
        with np.errstate(divide="ignore"):
            self._log_p = np.concatenate([[-np.inf], np.log(p)])
            self._off = np.zeros(len(faults) + 1)
            if self.form == "corrected":
                self._off[0] = np.log1p(-p.sum())
                self._init = np.concatenate([[np.log1p(-pi.sum())], np.log(pi)])
            else:
                self._init = np.concatenate([[1.0 - pi.sum()], pi])

    # ------------------------------------------------------------------ fitting
    def fit(self, data: Mapping[str, Residuals | Sequence[Residuals]], *, mean: str = "fixed",
            diagonal: bool = False, regularization: float = 0.0, uniform_method: str = "erf",
            n_points: int = 1024, rng: np.random.Generator | int | None = None) -> MhsprtEvaluator:
        """Gaussian densities from recorded or simulated residuals (§7.4: sample means and covariances).

        ``data``: ``{'none': fault-free residuals, fault: residuals while the fault is active, ...}``; each value
        one :class:`Residuals` or a list of runs (slice off start-up transients first).  Only valid, finite
        samples are used.  ``'none'`` is always ``N(mean, cov)`` of its samples.  Faults, by ``mean``:

        * ``'fixed'``: ``N(mean, cov)`` of all their samples;
        * ``'gaussian'``: runs of different fault sizes; within-run covariance ``Λ``, run means ``~ N(m*, Σ_μ)``
          (their sample mean and covariance) → ``N(m*, Λ + Σ_μ)`` (Prop. 7.4);
        * ``'uniform'``: within-run ``Λ``, mean uniform on the box spanned by the run means (Prop. 7.5); needs
          ``diagonal=True`` or ``uniform_method='mixture'`` with ``rng``.

        ``diagonal`` keeps only the variances of the fitted ``Λ`` (all hypotheses; ``Σ_μ`` stays full);
        ``regularization`` as in :class:`GaussianDensity`
        (a singular fitted covariance is refused with :class:`DataError` otherwise).
        """
        if mean not in ("fixed", "gaussian", "uniform"):
            raise ModelError(f"unknown mean model {mean!r}; use 'fixed', 'gaussian' or 'uniform'")
        if NO_FAULT not in data or len(data) < 2:
            raise DataError(f"fit needs fault-free residuals under {NO_FAULT!r} and at least one fault; "
                            f"got {list(data)}")
        names = None
        dens = {}
        for hyp, runs in data.items():
            hyp = str(hyp)
            runs = [runs] if isinstance(runs, Residuals) else list(runs)
            xs = []
            for res in runs:
                if names is None:
                    names = res.names
                elif res.names != names:
                    raise DataError(f"hypothesis {hyp!r}: residual names {res.names} differ from {names}")
                ok = res.valid & np.all(np.isfinite(res.r), axis=1)
                xs.append(self._features(res.r[ok]))
            n = xs[0].shape[1]
            tot = sum(x.shape[0] for x in xs)
            if tot < max(10, 2 * n):
                raise DataError(f"hypothesis {hyp!r} has {tot} valid samples; need at least {max(10, 2 * n)}")
            allx = np.vstack(xs)
            model = "fixed" if hyp == NO_FAULT else mean
            if model != "fixed":
                if len(xs) < 2 or min(x.shape[0] for x in xs) < 2:
                    raise DataError(f"mean={mean!r} estimates the spread of the mean from runs of different fault "
                                    f"sizes; hypothesis {hyp!r} needs at least 2 runs of 2+ samples")
                mu = np.array([x.mean(axis=0) for x in xs])
                lam = sum((x - x.mean(axis=0)).T @ (x - x.mean(axis=0)) for x in xs) / (tot - len(xs))
            else:
                lam = np.atleast_2d(np.cov(allx, rowvar=False, ddof=1))
            if diagonal:
                lam = np.diag(np.diag(lam))
            try:
                if model == "fixed":
                    dens[hyp] = GaussianDensity(allx.mean(axis=0), lam, regularization)
                elif model == "gaussian":
                    dens[hyp] = gaussian_mean_density(mu.mean(axis=0), lam, np.atleast_2d(np.cov(mu, rowvar=False)),
                                                      regularization)
                else:
                    dens[hyp] = UniformMeanDensity(mu.min(axis=0), mu.max(axis=0), lam, uniform_method, n_points,
                                                   rng, regularization)
            except ModelError as exc:
                raise DataError(f"hypothesis {hyp!r}: {exc}") from exc
        self._set_densities(dens)
        self.names = names
        self.reset()
        return self

    # ------------------------------------------------------------------ recursion
    def _loglik(self, x: np.ndarray) -> np.ndarray:
        """Log densities (N, m + 1) plus the constant offset of the recursion (``log(1 − Σp)`` on ``H_0``)."""
        return np.column_stack([d.logpdf(x) for d in self.densities.values()]) + self._off

    def _update(self, state: np.ndarray, ll: np.ndarray) -> tuple[np.ndarray, bool]:
        """One step of (7.1); ``ll`` are the log densities plus ``_off``.  Returns the new state, or the old one and
        False (held) when the sample is unusable."""
        if self.form == "corrected":  # state = log F (incl. F_0); log M_0 = log F_0 + log(1 − Σp) via _off[0]
            a = np.logaddexp(state, self._log_p + state[0])  # entry 0: log_p = −inf, so a[0] = state[0] exactly
            a += ll
            amax = a.max()
            if not np.isfinite(amax):
                return state, False
            a -= amax + np.log(np.exp(a - amax).sum())
            return a, True
        F = state[1:]  # literal (7.1c): state = F in linear form, F_0 = 1 − Σ F_i
        M = F + self._p * (1.0 - F)
        lmax = ll.max()
        if not np.isfinite(lmax):
            return state, False
        g = np.exp(ll - lmax)
        num = M * g[1:]
        new = num / (num.sum() + (1.0 - M.sum()) * g[0])
        if not np.all(np.isfinite(new)):
            return state, False
        return np.concatenate([[1.0 - new.sum()], new]), True

    def _probs(self, state: np.ndarray) -> np.ndarray:
        return np.exp(state) if self.form == "corrected" else state.copy()

    def _isolate(self, fired: np.ndarray) -> np.ndarray:
        n = fired.sum(axis=1)
        out = np.full(fired.shape[0], NO_FAULT, dtype=object)
        out[n == 1] = np.array(self.faults, dtype=object)[fired[n == 1].argmax(axis=1)]
        out[n > 1] = UNKNOWN_FAULT
        return out.astype(str)

    def _need(self) -> None:
        if self.densities is None:
            raise ModelError("the evaluator has no densities; pass densities= or call fit() on residuals")

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Posteriors and decisions for a whole series; identical to :meth:`reset` then :meth:`step` per sample."""
        self._need()
        if self.names is not None and residuals.names != self.names:
            raise DataError(f"residuals {residuals.names} differ from the fitted {self.names}")
        r = residuals.r
        ok = residuals.valid & np.all(np.isfinite(r), axis=1)
        x = self._features(r)
        if x.shape[1] != self.densities[NO_FAULT].dim:
            raise DataError(f"{x.shape[1]} measurement components, the densities have {self.densities[NO_FAULT].dim}")
        ll = np.full((x.shape[0], len(self.densities)), np.nan)
        if ok.any():
            ll[ok] = self._loglik(x[ok])
        state = self._init.copy()
        S = np.empty_like(ll)
        for k in range(x.shape[0]):
            if ok[k]:
                state, ok[k] = self._update(state, ll[k])
            S[k] = state
        P = np.exp(S) if self.form == "corrected" else S
        fired = P[:, 1:] >= self._ft
        meta = {"evaluator": "mhsprt", "form": self.form, "p": self._p.tolist(), "threshold": self._ft.tolist(),
                "log_probabilities": S if self.form == "corrected" else None}
        return Diagnosis(residuals.t, fired.any(axis=1), fired, self.faults, self._isolate(fired), probabilities=P,
                         hypotheses=self.hypotheses, valid=ok, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Back to the prior ``π`` (start of a new run, or after a repair)."""
        if self.densities is None:
            self._state = None
            return
        self._setup()
        self._state = self._init.copy()

    def step(self, r) -> StepDecision:
        """Update with one residual sample; a NaN/inf sample holds the posterior and is reported invalid."""
        self._need()
        r = np.asarray(r, dtype=float).ravel()
        valid = bool(np.all(np.isfinite(r)))
        if valid:
            x = self._features(r[None, :])
            if x.shape[1] != self.densities[NO_FAULT].dim:
                raise DataError(f"{x.shape[1]} measurement components, the densities have "
                                f"{self.densities[NO_FAULT].dim}")
            self._state, valid = self._update(self._state, self._loglik(x)[0])
        P = self._probs(self._state)
        fired = P[1:] >= self._ft
        hit = np.flatnonzero(fired)
        fault = NO_FAULT if hit.size == 0 else self.faults[hit[0]] if hit.size == 1 else UNKNOWN_FAULT
        return StepDecision(bool(hit.size), fault, fired, valid, P)

    def __repr__(self) -> str:
        return (f"MhsprtEvaluator(hypotheses={self.hypotheses}, form={self.form!r}, p={self.p}, pi={self.pi}, "
                f"threshold={self.threshold})")
