"""Window-limited GLR test for a change in mean of unknown size (Willsky & Jones 1976).

Basseville & Nikiforov 1993 §2.4.  Residuals are grouped into blocks (one vector test per
fault, by default the residuals tied to the same fault); a block's residual ``r_k ∈ ℝᵖ``
is ``N(μ0, Σ)`` fault-free and ``N(μ0 + ν, Σ)`` from an unknown change time ``j`` on, with
``ν`` unknown.  With ``e_i = r_i − μ0`` and ``S_j^k = Σ_{i=j}^{k} e_i`` the log-likelihood
ratio of "change at ``j`` with mean ``ν``" against "no change" is

    Σ_{i=j}^{k} [νᵀ Σ⁻¹ e_i − ½ νᵀ Σ⁻¹ ν] = νᵀ Σ⁻¹ S_j^k − ½ n νᵀ Σ⁻¹ ν,    n = k − j + 1,

maximised by ``ν̂ = S_j^k / n`` (the window mean), with value
``(S_j^k)ᵀ Σ⁻¹ S_j^k / (2n)``.  The window-limited GLR statistic maximises it over the
change times of the last ``M`` samples::

    g_k = max_{k−M+1 ≤ j ≤ k} (S_j^k)ᵀ Σ⁻¹ S_j^k / (2 (k − j + 1)),

with the maximising ``ĵ`` the estimated change time and ``ν̂ = S_ĵ^k/(k − ĵ + 1)`` the
estimated change (standard error ``σ/√n`` per component).  The block fires while
``g_k > h``; the statistic is a function of the last ``M`` valid samples only, so there is
no restart.

Threshold (:func:`glr_threshold`): fault-free, each window's ``2 g_{k,j} = ‖L⁻¹S_j^k‖²/n``
is ``χ²_p`` exactly (``Σ = L Lᵀ``), so ``P(g_{k,j} > h) = χ²_p.sf(2h)``.  The statistic is
the maximum of ``M`` such, strongly correlated, variables; the union (Bonferroni) bound
gives ``P(g_k > h) ≤ M · χ²_p.sf(2h)``, and ``h = χ²_p.isf(α/M)/2`` keeps the per-sample
false-alarm probability **at most** ``α``.  The bound is conservative (the windows share
samples); the true probability lies between ``α/M`` (a single window) and ``α``.

Numerics: the residuals are whitened, ``z = L⁻¹ e``; the window sums are built backwards,
``S_1 = z_k``, ``S_n = S_{n−1} + z_{k−n+1}``, in :meth:`GlrEvaluator.run` as ``M``
vectorised passes over the samples and in :meth:`GlrEvaluator.step` from a ring buffer, with
the same operations in the same order, so batch and online agree bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg
from scipy.stats import chi2

from fdikit import validate
from fdikit.decision.calibration import CalibrationRuns, calibration_report, calibration_runs
from fdikit.decision.common import (
    checked_names,
    checked_residuals,
    held,
    is_count,
    isolate_cached,
    isolate_fired,
    step_vector,
)
from fdikit.decision.signature import as_signature_table
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["BlockLayout", "GlrEvaluator", "as_covariance", "fit_moments", "glr_threshold", "residual_blocks"]


def glr_threshold(false_alarm_prob: float, window: int, dof: int = 1) -> float:
    """Threshold ``h`` on ``g_k`` for a per-sample false-alarm probability of at most ``α``.

    ``h = χ²_p.isf(α/M) / 2`` (the union bound over the ``M`` change times of the window;
    see the module docstring).

    Parameters
    ----------
    false_alarm_prob : float
        ``α`` in (0, 1), the per-sample false-alarm probability bound of one block's test.
    window : int
        ``M``, the number of change times tried (:class:`GlrEvaluator` ``window``).
    dof : int, default 1
        ``p``, the block dimension (number of residuals in the vector test).

    Returns
    -------
    float
        ``h = χ²_p.isf(α/M)/2``.

    Raises
    ------
    ParameterError
        When ``α`` is not in (0, 1), or ``window`` or ``dof`` is not a positive integer.

    References
    ----------
    Willsky & Jones 1976; Basseville & Nikiforov 1993, §2.4; Douglas et al. 1996, §7.2.3 (GLR vs. Shiryayev SPRT).

    Examples
    --------
    >>> round(glr_threshold(1e-3, 50, 1), 3)
    9.095
    """
    if not 0 < false_alarm_prob < 1:
        raise ParameterError(f"false-alarm probability must be in (0, 1), got {false_alarm_prob}")
    if not is_count(window, 1):
        raise ParameterError(f"window must be a positive number of samples, got {window}")
    if not is_count(dof, 1):
        raise ParameterError(f"dof (the block dimension) must be a positive integer, got {dof}")
    return float(chi2.isf(false_alarm_prob / window, dof) / 2.0)


def residual_blocks(
    blocks, names: Sequence[str], isolates: Sequence[str | None]
) -> tuple[tuple[str, tuple[int, ...]], ...]:
    """Partition residuals into the blocks of a vector test, in order of first appearance.

    Parameters
    ----------
    blocks : 'isolates', 'each', 'all' or sequence
        ``'isolates'``: the residuals tied to the same fault form a block (an untied
        residual is a block of its own); ``'each'``: one block per residual (scalar
        tests); ``'all'``: one block of all residuals; a sequence: one label per residual.
    names, isolates : sequence of str
        The residuals' names and tied faults (None: untied).

    Returns
    -------
    tuple of (name, residual indices)
        Block names: the fault (``'isolates'``), the residual name (``'each'``), the label,
        or ``'all'``.

    Raises
    ------
    ParameterError
        When ``blocks`` is an unknown string, or a sequence whose length is not the number of residuals.

    References
    ----------
    Basseville & Nikiforov 1993, §2.4 (see :class:`GlrEvaluator`).

    Examples
    --------
    >>> residual_blocks("isolates", ("a", "b", "c"), ("fa", "fa", None))
    (('fa', (0, 1)), ('c', (2,)))
    """
    q = len(names)
    if isinstance(blocks, str):
        if blocks == "isolates":
            labels = [iso if iso is not None else names[i] for i, iso in enumerate(isolates)]
        elif blocks == "each":
            labels = list(names)
        elif blocks == "all":
            labels = ["all"] * q
        else:
            raise ParameterError(
                f"blocks must be 'isolates', 'each', 'all' or one label per residual, got {blocks!r}"
            )
    else:
        labels = [str(b) for b in blocks]
        if len(labels) != q:
            raise ParameterError(f"{len(labels)} block labels for {q} residuals")
    out: dict[str, list[int]] = {}
    for i, lab in enumerate(labels):
        out.setdefault(str(lab), []).append(i)
    return tuple((k, tuple(v)) for k, v in out.items())


def _lin(M: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``out[..., g, i] = Σ_j M[g, i, j] e[..., g, j]`` summed in a fixed order (batch == online)."""
    out = M[:, :, 0] * e[..., :, 0:1]
    for j in range(1, M.shape[2]):
        out = out + M[:, :, j] * e[..., :, j : j + 1]
    return out


def _sumsq(S: np.ndarray) -> np.ndarray:
    """``Σ_i S[..., i]²`` in a fixed order."""
    acc = S[..., 0] * S[..., 0]
    for i in range(1, S.shape[-1]):
        acc = acc + S[..., i] * S[..., i]
    return acc


class BlockLayout:
    """Residuals grouped into blocks and laid out as a padded ``(G, P)`` array.

    ``gather(e)`` maps ``(..., q)`` residuals to ``(..., G, P)`` (zeros in the padding,
    which leave sums and squares unchanged); ``chol`` and ``whiten`` are the padded
    Cholesky factors ``L_g`` of the block covariances and their inverses.  ``cov`` is a
    (q, q) matrix or a (q,) vector of variances.  Attributes: ``blocks`` (:func:`residual_blocks`), ``names``
    (of the blocks), ``dims`` (``p_g``), ``index`` (the residual of each padded slot, ``q`` in the padding),
    ``chol``, ``whiten``, and ``isolates``/``groups`` per block (None where its residuals differ).

    Parameters
    ----------
    blocks : 'isolates', 'each', 'all' or sequence
        The grouping (:func:`residual_blocks`).
    names, isolates, groups : sequence
        The ``q`` residual names, their tied faults, and their filters in a bank (None: no bank; a block must
        lie within one filter).
    cov : (q,) or (q, q) ndarray
        Variances or covariance of the residuals (:func:`as_covariance`); only the diagonal blocks are used.

    Raises
    ------
    DataError
        When a block's covariance is not positive definite.
    ParameterError
        When a block mixes residuals of different filters of a bank.

    References
    ----------
    Basseville & Nikiforov 1993, §2.4 (see :class:`GlrEvaluator`).

    Examples
    --------
    >>> lay = BlockLayout("isolates", ("a", "b", "c"), ("fa", "fa", "fb"), None, np.array([1.0, 4.0, 9.0]))
    >>> lay.names, lay.dims.tolist(), lay.gather(np.array([1.0, 2.0, 3.0])).tolist()
    (('fa', 'fb'), [2, 1], [[1.0, 2.0], [3.0, 0.0]])
    """

    def __init__(self, blocks, names, isolates, groups, cov: np.ndarray) -> None:
        q = len(names)
        self.blocks = residual_blocks(blocks, names, isolates)
        self.names = tuple(b for b, _ in self.blocks)
        self.q = q
        G = len(self.blocks)
        self.dims = np.array([len(ix) for _, ix in self.blocks])
        P = int(self.dims.max())
        self.index = np.full((G, P), q)
        self.chol = np.zeros((G, P, P))
        self.whiten = np.zeros((G, P, P))
        iso, grp = [], []
        for g, (name, ix) in enumerate(self.blocks):
            p = len(ix)
            self.index[g, :p] = ix
            C = np.diag(cov[list(ix)]) if cov.ndim == 1 else cov[np.ix_(ix, ix)]
            if p == 1 and C[0, 0] > 0:
                L = np.sqrt(C)
            else:
                try:
                    L = np.linalg.cholesky(C)
                except np.linalg.LinAlgError:
                    raise DataError(
                        f"the covariance of block {name!r} (residuals {[names[i] for i in ix]}) is not positive "
                        f"definite (eigenvalues {np.linalg.eigvalsh(C)}); the residuals are constant or linearly "
                        "dependent — drop one, or put them in separate blocks"
                    ) from None
            self.chol[g, :p, :p] = L
            self.whiten[g, :p, :p] = 1.0 / L if p == 1 else scipy.linalg.solve_triangular(L, np.eye(p), lower=True)
            tied = {isolates[i] for i in ix}
            iso.append(tied.pop() if len(tied) == 1 else None)
            if groups is not None:
                gs = {groups[i] for i in ix}
                if len(gs) != 1:
                    raise ParameterError(
                        f"block {name!r} mixes residuals of the filters {sorted(gs)}; a block must "
                                     "lie within one filter of the bank")
                grp.append(gs.pop())
        self.isolates = tuple(iso)
        self.groups = tuple(grp) if groups is not None else None

    def gather(self, e: np.ndarray) -> np.ndarray:
        ext = np.concatenate([e, np.zeros(e.shape[:-1] + (1,))], axis=-1)
        return ext[..., self.index]

    def split(self, x: np.ndarray) -> tuple[np.ndarray, ...]:
        """Per block, the un-padded ``(..., p_g)`` part of a ``(..., G, P)`` array."""
        return tuple(x[..., g, : self.dims[g]] for g in range(len(self.blocks)))


def _as_mean(mean, q: int) -> np.ndarray:
    m = np.atleast_1d(np.asarray(mean, dtype=float))
    if m.size not in (1, q) or m.ndim != 1:
        raise DataError(f"{m.size} mean values for {q} residuals")
    return np.array(np.broadcast_to(m, (q,)))


def as_covariance(cov, q: int) -> np.ndarray:
    """A covariance given as a scalar, (q,) variances or a (q, q) matrix, as variances or a matrix.

    Parameters
    ----------
    cov : float or array_like
        A variance for every residual, ``q`` variances (or one), or a (q, q) matrix.
    q : int
        Number of residuals.

    Returns
    -------
    (q,) or (q, q) ndarray
        Variances (from a scalar or a vector) or the matrix.

    Raises
    ------
    DataError
        When the number of variances or the matrix shape does not fit ``q`` residuals.

    References
    ----------
    Basseville & Nikiforov 1993, §2.4 (see :class:`GlrEvaluator`).

    Examples
    --------
    >>> as_covariance(2.0, 3).tolist()
    [2.0, 2.0, 2.0]
    """
    c = validate.as_array("covariance", cov, error=DataError, finite=False)  # a diagonal stays a vector (fast path)
    if c.ndim == 0:
        c = np.full(q, float(c))
    if c.ndim == 1:
        if c.size not in (1, q):
            raise DataError(f"{c.size} variances for {q} residuals")
        return np.array(np.broadcast_to(c, (q,)))
    if c.shape != (q, q):
        raise DataError(f"covariance of shape {c.shape} for {q} residuals; need ({q}, {q})")
    return c


def _check_cov(cov) -> np.ndarray | None:
    if cov is None:
        return None
    c = np.asarray(cov, dtype=float)
    if not np.all(np.isfinite(c)):
        raise ParameterError("the covariance has non-finite entries")
    if c.ndim <= 1 and not np.all(c > 0):
        raise ParameterError(f"variances must be positive, got {c}")
    if c.ndim == 2 and (c.shape[0] != c.shape[1] or not np.allclose(c, c.T, rtol=1e-10, atol=0)):
        raise ParameterError(f"the covariance must be a symmetric square matrix, got shape {c.shape}")
    return c


def fit_moments(residuals: Residuals | Sequence[Residuals], minimum: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of the valid, finite rows of fault-free residuals (one run, or a list pooled).

    Parameters
    ----------
    residuals : Residuals, sequence of Residuals or CalibrationRuns
        Fault-free runs (:func:`~fdikit.decision.calibration.calibration_runs`); invalid, non-finite rows skipped.
    minimum : int, default 10
        Fewest usable rows accepted.

    Returns
    -------
    (mean, cov) : tuple of ndarray
        The (q,) sample mean ``μ0`` and the (q, q) sample covariance (``ddof=1``).

    Raises
    ------
    DataError
        When ``residuals`` is not a ``Residuals`` (or runs of the same residuals), or has < ``minimum`` usable rows.

    References
    ----------
    Basseville & Nikiforov 1993, §2.4 (see :class:`GlrEvaluator`).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> healthy = Residuals(np.arange(200) * 0.01, rng.standard_normal((200, 2)), ("a", "b"), ("fa", "fb"))
    >>> mean, cov = fit_moments(healthy)
    >>> mean.shape, cov.shape
    ((2,), (2, 2))
    """
    r = (residuals if isinstance(residuals, CalibrationRuns) else calibration_runs(residuals, minimum)).rows
    return r.mean(axis=0), np.atleast_2d(np.cov(r, rowvar=False, ddof=1))


class GlrEvaluator:
    """Window-limited GLR for a change in mean of unknown size, one vector test per block.

    Parameters
    ----------
    window : int
        ``M``, the number of most recent change times tried (default 50).  Changes are
        estimated within the window; pick ``M`` above the expected detection delay.
    threshold : float or array_like, optional
        ``h`` per block (alarm when ``g_k > h``); or set by :meth:`fit` from a
        false-alarm probability.
    mean : float or array_like, optional
        ``μ0`` per residual (default 0, or the fault-free mean after :meth:`fit`).
    cov : float, (q,) or (q, q) array_like, optional
        Noise covariance: a variance, one per residual, or a full matrix (only its
        block-diagonal part is used).  Default identity, or the fault-free estimate.
    blocks : 'isolates', 'each', 'all' or sequence
        How residuals are grouped into vector tests (:func:`residual_blocks`).
    isolates, groups : sequence, optional
        Fault tied to each residual and filter of each residual (bank); a block's fault is
        its residuals' common fault (None when they differ).
    signatures : SignatureTable, mapping or DataFrame, optional
        Isolate by a fault-signature table (:mod:`fdikit.decision.signature`), matched against the fired blocks.
        After :meth:`fit` with a threshold, ``calibration`` is the false-alarm report on the fault-free runs
        (:class:`~fdikit.decision.calibration.CalibrationReport`).

    Notes
    -----
    :meth:`run` puts in ``meta``: ``statistic`` (N, G), ``change_index`` (N, G) (sample
    index of ``ĵ``, −1 before the first valid sample), ``change_time`` (N, G) and
    ``change_size`` (one (N, p_g) array per block), all held on invalid samples.  After
    :meth:`step` the same are in ``statistic``, ``change_index``, ``change_size``.

    References
    ----------
    Willsky & Jones 1976; Basseville & Nikiforov 1993, §2.4; Douglas et al. 1996, §7.2.3 (GLR vs. Shiryayev SPRT).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> rng = np.random.default_rng(0)
    >>> r = rng.standard_normal((400, 2)); r[300:, 0] += 2.0
    >>> res = Residuals(np.arange(400) * 0.01, r, ("a", "b"), ("fa", "fb"))
    >>> d = GlrEvaluator(window=30, threshold=glr_threshold(1e-3, 30)).run(res)
    >>> a = d.first_alarm(); a.fault, a.index - 300, int(d.meta["change_index"][a.index, 0])
    ('fa', 6, 301)
    """

    def __init__(
        self, window: int = 50, threshold=None, mean=None, cov=None, *, blocks="isolates", isolates=None,
        groups=None, signatures=None,
    ) -> None:
        if not is_count(window, 1):
            raise ParameterError(f"window must be a positive number of samples, got {window}")
        self.window = int(window)
        self.threshold = None if threshold is None else np.atleast_1d(np.asarray(threshold, dtype=float))
        if self.threshold is not None and not np.all(self.threshold > 0):
            raise ParameterError(f"GLR threshold must be positive, got {self.threshold}")
        self.mean = None if mean is None else np.atleast_1d(np.asarray(mean, dtype=float))
        self.cov = _check_cov(cov)
        if not (isinstance(blocks, str) or isinstance(blocks, Sequence)):
            raise ParameterError(
                f"blocks must be 'isolates', 'each', 'all' or one label per residual, got {blocks!r}"
            )
        self.blocks = blocks if isinstance(blocks, str) else tuple(blocks)
        self.isolates = None if isolates is None else tuple(isolates)
        self.groups = None if groups is None else tuple(groups)
        self.signatures = as_signature_table(signatures)
        self.calibration = None
        self.names: tuple[str, ...] | None = None
        self.alpha: float | None = None
        self.reset()

    def fit(self, residuals: Residuals | Sequence[Residuals], false_alarm_prob: float | None = None,
            false_alarms_per_hour: float | None = None) -> GlrEvaluator:
        """Estimate ``μ0`` and ``Σ`` on fault-free residuals (one run, or a list pooled; each run evaluated on its
        own for ``calibration``, so no window crosses a run boundary); optionally set ``h`` per block.
        ``false_alarm_prob`` (or a rate per hour, ``α = rate·dt/3600``) is the
        per-sample probability of any block alarming, split evenly over the ``G`` blocks,
        each given ``h_g = glr_threshold(α/G, M, p_g)`` (an upper bound; see the module
        docstring).  Without a target the threshold given to the constructor is kept.
        """
        if false_alarm_prob is not None and false_alarms_per_hour is not None:
            raise ParameterError("give at most one of false_alarm_prob and false_alarms_per_hour")
        runs = calibration_runs(residuals)
        mean, cov = fit_moments(runs)
        if false_alarms_per_hour is not None:
            dt = runs.dt
            if not false_alarms_per_hour > 0 or not dt > 0:
                raise ParameterError(f"need a positive rate and sample time, got {false_alarms_per_hour}/h and dt={dt}")
            false_alarm_prob = min(0.5, false_alarms_per_hour * dt / 3600.0)
        iso = self.isolates if self.isolates is not None else runs.isolates
        layout = BlockLayout(self.blocks, runs.names, iso, self.groups, cov)
        if false_alarm_prob is not None:
            if not 0 < false_alarm_prob < 1:
                raise ParameterError(f"false-alarm probability must be in (0, 1), got {false_alarm_prob}")
            G = len(layout.blocks)
            self.threshold = np.array([glr_threshold(false_alarm_prob / G, self.window, int(p)) for p in layout.dims])
            self.alpha = float(false_alarm_prob)
        self.mean, self.cov = mean, cov
        self.names = runs.names
        self.isolates = tuple(iso)
        self.reset()
        target = self.alpha * 3600.0 / runs.dt if false_alarm_prob is not None else None
        self.calibration = None if self.threshold is None else calibration_report(self, runs, target_rate=target)
        return self

    def _ready(self, q: int, residuals: Residuals | None = None):
        names = checked_names(q, residuals, self.names)
        if self.threshold is None:
            raise ParameterError(
                "the GLR has no threshold; pass threshold= (see glr_threshold) or call "
                "fit(fault_free, false_alarm_prob=...)"
            )
        mean = np.zeros(q) if self.mean is None else _as_mean(self.mean, q)
        cov = np.ones(q) if self.cov is None else as_covariance(self.cov, q)
        iso = self.isolates or (residuals.isolates if residuals is not None else (None,) * q)
        if len(iso) != q:
            raise DataError(f"{len(iso)} 'isolates' entries for {q} residuals")
        layout = BlockLayout(self.blocks, names, tuple(iso), self.groups, cov)
        G = len(layout.blocks)
        if self.threshold.size not in (1, G):
            raise DataError(f"{self.threshold.size} thresholds for {G} blocks {list(layout.names)}")
        h = np.array(np.broadcast_to(self.threshold, (G,)))
        return mean, layout, h

    def _meta(self, layout: BlockLayout, h: np.ndarray, names: Sequence[str]) -> dict:
        return {
            "evaluator": "glr", "window": self.window, "threshold": h.tolist(), "alpha": self.alpha,
            "blocks": {block: [names[i] for i in ix] for block, ix in layout.blocks},
        }

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series; identical to stepping through it."""
        residuals = checked_residuals(residuals, self.names, "the GLR")
        q = len(residuals.names)
        mean, layout, h = self._ready(q, residuals)
        r = residuals.r
        valid = residuals.valid & np.all(np.isfinite(r), axis=1)
        vidx = np.flatnonzero(valid)
        Z = _lin(layout.whiten, layout.gather(r[valid] - mean))  # (n, G, P)
        n, G = Z.shape[0], Z.shape[1]
        S = Z.copy()
        best = _sumsq(S) / 2.0
        best_n = np.ones((n, G), int)
        best_S = S.copy()
        for m in range(2, min(self.window, n) + 1):
            S[m - 1 :] += Z[: n - m + 1]
            st = _sumsq(S[m - 1 :]) / (2.0 * m)
            upd = st > best[m - 1 :]
            np.copyto(best[m - 1 :], st, where=upd)
            np.copyto(best_n[m - 1 :], m, where=upd)
            np.copyto(best_S[m - 1 :], S[m - 1 :], where=upd[..., None])
        size = _lin(layout.chol, best_S) / best_n[..., None]
        change = vidx[np.arange(n)[:, None] - best_n + 1] if n else np.zeros((0, G), int)
        fired = held(best > h, valid, False)
        isolated = isolate_fired(fired, layout.isolates, layout.groups, self.signatures, layout.names)
        meta = self._meta(layout, h, residuals.names)
        meta["statistic"] = held(best, valid, 0.0)
        meta["change_index"] = held(change, valid, -1)
        meta["change_time"] = np.where(meta["change_index"] >= 0, residuals.t[np.maximum(meta["change_index"], 0)],
                                       np.nan)
        meta["change_size"] = layout.split(held(size, valid, np.nan))
        return Diagnosis(residuals.t, fired.any(axis=1), fired, layout.names, isolated, valid=valid, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Empty the window (start of a new run)."""
        self._state = None
        self.statistic: np.ndarray | None = None
        self.change_index: np.ndarray | None = None
        self._last: tuple | None = None

    @property
    def change_size(self) -> tuple[np.ndarray, ...] | None:
        """Estimated change ``ν̂`` per block at the last valid :meth:`step` (NaN before one)."""
        if self._state is None:
            return None
        layout = self._state["layout"]
        if self._last is None:
            return layout.split(np.full(layout.index.shape, np.nan))
        S, n = self._last
        return layout.split(_lin(layout.chol, S) / n[:, None])

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample leaves the window and the decision unchanged.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the statistics and the decision hold.  ``names`` (optional) are
        checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).


        The parameters are read at the first step after :meth:`reset` (or :meth:`fit`).
        """
        r = step_vector(r, self.names, names, "the GLR")
        st = self._state
        if st is not None and st["q"] != r.size:
            raise DataError(f"step() got {r.size} residuals after steps with {st['q']}; call reset() first")
        if st is None:
            mean, layout, h = self._ready(r.size)
            G, P = layout.index.shape
            M = self.window
            st = self._state = {
                "q": r.size, "mean": mean, "layout": layout, "h": h, "buf": np.zeros((M, G, P)),
                "idx": np.zeros(M, int), "head": 0, "count": 0, "k": -1, "fired": np.zeros(G, bool),
                "cache": {}, "den": (2.0 * np.arange(1, M + 1))[:, None], "back": np.arange(M), "cols": np.arange(G),
            }
            self.statistic, self.change_index, self._last = np.zeros(G), np.full(G, -1), None
        st["k"] += 1
        if not (valid and np.all(np.isfinite(r))):
            fired = st["fired"]
            return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), False)
        layout, M = st["layout"], self.window
        z = _lin(layout.whiten, layout.gather(r - st["mean"]))
        head = st["head"]
        st["buf"][head], st["idx"][head] = z, st["k"]
        st["head"] = (head + 1) % M
        st["count"] = navail = min(st["count"] + 1, M)
        order = (head - st["back"][:navail]) % M  # newest first
        S = np.add.accumulate(st["buf"][order], axis=0)  # S[n-1] = z_k + ... + z_{k-n+1}
        stat = _sumsq(S) / st["den"][:navail]
        nhat = np.argmax(stat, axis=0)
        cols = st["cols"]
        best = stat[nhat, cols]
        fired = best > st["h"]
        self.statistic = best
        self.change_index = st["idx"][order[nhat]]
        self._last = (S[nhat, cols], nhat + 1)
        st["fired"] = fired
        return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), True)

    def _isolate(self, fired: np.ndarray) -> str:
        lay = self._state["layout"]
        return isolate_cached(self._state["cache"], fired, lay.isolates, lay.groups, self.signatures, lay.names)

    def __repr__(self) -> str:
        return f"GlrEvaluator(window={self.window}, threshold={self.threshold}, blocks={self.blocks!r})"
