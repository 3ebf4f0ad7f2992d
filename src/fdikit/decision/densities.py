"""Hypothesis densities for the multiple-hypothesis Shiryayev SPRT (Douglas et al. 1996, §7.2).

:class:`GaussianDensity`, :func:`gaussian_mean_density` (a Gaussian-distributed unknown mean,
Prop. 7.4) and :class:`UniformMeanDensity` (a uniformly distributed unknown mean, Prop. 7.5,
corrected for ``n > 1``); any object with ``dim`` and a row-wise ``logpdf`` can stand in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.special import log_ndtr, logsumexp, ndtr

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["GaussianDensity", "UniformMeanDensity", "gaussian_mean_density"]

_LOG2PI = np.log(2.0 * np.pi)

def _vec(value, name: str, n: int | None = None) -> np.ndarray:
    v = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if n is not None and v.size != n:
        raise ParameterError(f"{name} has {v.size} entries, need {n}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"{name} has non-finite entries: {v}")
    return v


def _cov(value, n: int, name: str = "covariance", regularization: float = 0.0, definite: bool = True) -> np.ndarray:
    """A scalar (σ² I), a vector (diagonal) or an (n, n) matrix → a symmetric positive definite matrix, or refuse."""
    c = validate.as_covariance(name, value, n, diagonal_ok=True, rtol=1e-8)
    if regularization:
        if not regularization > 0:
            raise ParameterError(f"regularization must be positive, got {regularization}")
        c = c + regularization * np.diag(np.diag(c))
    if not definite:
        return c
    d = np.diag(c)
    if not np.all(d > 0):
        raise ParameterError(
            f"{name} has zero or negative variance in component(s) {np.flatnonzero(~(d > 0)).tolist()}; "
                         "drop constant residual components, or pass regularization=ε (adds ε·diag(Λ))")
    ev = np.linalg.eigvalsh(c / np.sqrt(np.outer(d, d)))  # of the correlation matrix: scale-free conditioning
    if not ev[0] > 1e3 * n * np.finfo(float).eps:
        raise ParameterError(
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

    A singular covariance is refused (:class:`~fdikit.errors.ParameterError`) unless ``regularization=ε``
    adds ``ε·diag(Λ)`` (shrinks the correlations by ``1/(1 + ε)``; a component of zero variance is refused either way).

    Parameters
    ----------
    mean : (n,) array_like
        Mean of the residual under the hypothesis; stored as a float vector.
    cov : float, (n,) or (n, n) array_like
        Covariance ``Λ``: a variance (``σ² I``), variances (diagonal) or a symmetric positive definite matrix;
        stored as the (n, n) matrix actually used (after ``regularization``).
    regularization : float, default 0.0
        ``ε > 0`` adds ``ε·diag(Λ)`` to a singular or ill-conditioned ``Λ``; 0 refuses such a ``Λ``.

    Attributes
    ----------
    dim : int
        ``n``, the number of residual components.

    Raises
    ------
    ParameterError
        When ``mean`` or ``cov`` is not finite, ``cov`` has the wrong shape, is not symmetric, has a component
        of zero variance or is singular (without ``regularization``).

    References
    ----------
    Douglas et al. 1996, §7.2.1, (7.1) (the densities ``f_i`` of the recursion) and §7.3.2 (Gaussian hypotheses).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.densities import GaussianDensity
    >>> g = GaussianDensity(np.zeros(2), 1.0)
    >>> g.dim, np.round(g.logpdf(np.zeros((1, 2))), 6).tolist()
    (2, [-1.837877])
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

    Parameters
    ----------
    center : (n,) array_like
        ``m*``, the expected mean.
    cov : float, (n,) or (n, n) array_like
        ``Λ``, the covariance about the mean (scalar: ``σ² I``; vector: diagonal).
    mean_cov : float, (n,) or (n, n) array_like
        ``Σ_μ``, the covariance of the unknown mean; positive semi-definite.
    regularization : float, default 0.0
        Passed to :class:`GaussianDensity` for the sum ``Λ + Σ_μ``.

    Returns
    -------
    GaussianDensity
        ``N(m*, Λ + Σ_μ)``.

    Raises
    ------
    ParameterError
        When ``mean_cov`` is not positive semi-definite, or an argument is not finite, of the wrong shape or
        not symmetric (and, from :class:`GaussianDensity`, when ``Λ + Σ_μ`` is singular).

    References
    ----------
    Douglas et al. 1996, §7.3.2, Prop. 7.4 (with (7.22) of §7.2.4: an unknown change replaced by its density).

    Examples
    --------
    >>> from fdikit.decision.densities import gaussian_mean_density
    >>> d = gaussian_mean_density([0.0], 1.0, 3.0)
    >>> d.cov.tolist(), round(float(d.logpdf([0.0])[0]), 6)
    ([[4.0]], -1.612086)
    """
    center = _vec(center, "center")
    n = center.size
    lam = _cov(cov, n, "cov", definite=False)
    s = _cov(mean_cov, n, "mean_cov", definite=False)
    if np.linalg.eigvalsh(s)[0] < -1e-12 * np.abs(s).max(initial=0.0):
        raise ParameterError("mean_cov must be positive semi-definite")
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

    Parameters
    ----------
    low, high : (n,) array_like
        Corners of the box of the unknown mean, ``low <= high``.
    cov : float, (n,) or (n, n) array_like
        ``Λ``, the covariance about the mean (scalar: ``σ² I``; vector: diagonal).
    method : {"erf", "mixture"}, default "erf"
        The exact product form (diagonal ``Λ`` only) or the Sobol-point Gaussian mixture.
    n_points : int, default 1024
        Number of mixture points (rounded up to a power of two); ``"mixture"`` only.
    rng : numpy.random.Generator or int, optional
        Seed or generator of the scrambled Sobol points; required for ``"mixture"``.
    regularization : float, default 0.0
        ``ε > 0`` adds ``ε·diag(Λ)``, as in :class:`GaussianDensity`.

    Attributes
    ----------
    dim : int
        ``n``, the number of residual components.

    Raises
    ------
    ParameterError
        When ``high < low`` somewhere, ``cov`` is not a valid covariance, ``"erf"`` is given a non-diagonal
        ``cov``, ``"mixture"`` has no ``rng``, or ``method`` is unknown.

    References
    ----------
    Douglas et al. 1996, §7.3.2, Prop. 7.5 (the printed erf formula, corrected here for ``n > 1``).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.densities import UniformMeanDensity
    >>> u = UniformMeanDensity([-1.0], [1.0], 0.01)
    >>> np.round(np.exp(u.logpdf([0.0, 5.0])), 6).tolist()
    [0.5, 0.0]
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
            raise ParameterError(f"the box needs low <= high, got low={low}, high={high}")
        cov = _cov(self.cov, low.size, regularization=self.regularization)
        set_ = object.__setattr__
        set_(self, "low", low)
        set_(self, "high", high)
        set_(self, "cov", cov)
        if self.method == "erf":
            off = cov - np.diag(np.diag(cov))
            if np.abs(off).max(initial=0.0) > 0:
                raise ParameterError(
                    "the erf form of Prop. 7.5 needs a diagonal covariance (the box does not factor otherwise); "
                    "use method='mixture' with a seeded rng, or keep only the variances"
                )
            sig = np.sqrt(np.diag(cov))
            set_(self, "_sig", sig)
            set_(self, "_point", (high - low) <= 1e-8 * sig)
        elif self.method == "mixture":
            if self.rng is None:
                raise ParameterError(
                    "method='mixture' draws points in the box: pass rng= (a seed or a Generator)"
                )
            from scipy.stats import qmc

            k = int(np.ceil(np.log2(max(int(self.n_points), 2))))
            u = qmc.Sobol(low.size, scramble=True, rng=self.rng).random_base2(k)
            g = GaussianDensity(np.zeros(low.size), cov)
            set_(self, "_g", g)
            set_(self, "_zm", _whiten(low + u * (high - low), g._W))
        else:
            raise ParameterError(f"unknown method {self.method!r}; use 'erf' or 'mixture'")

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
