"""Wald's sequential probability ratio test per residual block, single or repeated (Wald 1947).

Basseville & Nikiforov 1993 §2.2 and §4.3.  For a block of residuals ``r_k ∈ ℝᵖ`` the
hypotheses are ``H0: r ~ N(μ0, Σ)`` and ``H1: r ~ N(μ0 + δ, Σ)`` with a known change ``δ``.
With ``e = r − μ0`` the log-likelihood ratio of one sample is

    λ_k = δᵀ Σ⁻¹ (e_k − δ/2),   E[λ | H1] = D = ½ δᵀ Σ⁻¹ δ = −E[λ | H0],   Var λ = 2D,

(``D`` is the Kullback–Leibler divergence ``D(H1‖H0)``), and the test accumulates
``Λ_k = Λ_{k−1} + λ_k`` between Wald's thresholds (:func:`sprt_thresholds`)::

    A = log((1 − β)/α)  (accept H1: alarm),      B = log(β/(1 − α))  (accept H0),

for target false-alarm and missed-detection probabilities ``α`` and ``β``.  Wald's
inequalities bound the attained rates, ``α' ≤ α/(1 − β)``, ``β' ≤ β/(1 − α)`` and
``α' + β' ≤ α + β``; with the overshoot of continuous increments they are usually below
``α`` and ``β``.  The expected sample numbers (:func:`sprt_asn`, overshoot neglected) are
``E[N | H1] ≈ ((1 − β)A + βB)/D`` and ``E[N | H0] ≈ ((1 − α)B + αA)/(−D)``.

Restart policy (``restart=``):

* ``True`` (default, repeated SPRT for monitoring): when ``Λ ≤ B`` (H0 accepted) the test
  restarts at ``Λ = 0``, and when ``Λ ≥ A`` the block alarms and the test also restarts at
  0.  With ``B = 0`` this is Page's CUSUM (the reset to 0 below 0 is the ``max(0, ·)``);
  with ``B < 0`` a new test starts only after H0 is accepted, which makes detection after a
  long fault-free stretch slower than the CUSUM by up to ``|B|/D`` samples.  ``fired`` is
  True at the upper crossings and for ``hold`` valid samples after.
* ``False`` (Wald's single test): the test stops at its first crossing; ``Λ`` is frozen
  and the decision latched — ``fired`` stays True from an upper crossing on, and stays
  False for good after a lower one.

``meta['llr']`` holds ``Λ_k`` (before any restart) and ``meta['decision']`` +1/−1 at the
samples where the test accepted H1/H0 (latched from the stopping sample on when
``restart=False``), 0 elsewhere.  The known change is one-sided: for a change of unknown
sign use :class:`~fdikit.decision.cusum.CusumEvaluator` or
:class:`~fdikit.decision.glr.GlrEvaluator`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fdikit.decision.common import (
    checked_names,
    checked_residuals,
    held,
    is_count,
    isolate_cached,
    isolate_fired,
    k_of_n,
    step_vector,
)
from fdikit.decision.glr import BlockLayout, as_covariance, fit_moments
from fdikit.decision.signature import as_signature_table
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.residuals import Residuals

__all__ = ["SprtEvaluator", "sprt_asn", "sprt_thresholds"]


def sprt_thresholds(alpha: float, beta: float) -> tuple[float, float]:
    """Wald's thresholds ``(A, B) = (log((1−β)/α), log(β/(1−α)))``.

    Parameters
    ----------
    alpha : float
        Target false-alarm probability ``α`` of one test.
    beta : float
        Target missed-detection probability ``β``; ``0 < α, β < 1`` and ``α + β < 1``.

    Returns
    -------
    (A, B) : tuple of float
        The upper (accept H1: alarm) and lower (accept H0) thresholds on the log-likelihood ratio ``Λ``.

    Raises
    ------
    ParameterError
        When ``α`` or ``β`` is not in (0, 1), or ``α + β >= 1``.

    References
    ----------
    Wald 1947 (the SPRT, its thresholds and expected sample numbers); Basseville & Nikiforov 1993, §2.2 and §4.3;
    Douglas et al. 1996, Ch. 7 introduction (the Wald SPRT compared with the Shiryayev SPRT).

    Examples
    --------
    >>> [round(x, 4) for x in sprt_thresholds(0.01, 0.01)]
    [4.5951, -4.5951]
    """
    if not (0 < alpha < 1 and 0 < beta < 1 and alpha + beta < 1):
        raise ParameterError(f"need 0 < alpha, beta < 1 and alpha + beta < 1, got alpha={alpha}, beta={beta}")
    return float(np.log((1 - beta) / alpha)), float(np.log(beta / (1 - alpha)))


def sprt_asn(alpha: float, beta: float, divergence: float, hypothesis: int = 1) -> float:
    """Wald's approximate expected sample number of the single SPRT.

    ``divergence`` is ``D = ½ δᵀ Σ⁻¹ δ``; ``hypothesis`` 1 gives ``E[N | H1]``, 0 gives
    ``E[N | H0]``.  The overshoot of the thresholds is neglected, so the true values are
    somewhat larger (by about ``0.583·√(2D)/D`` samples for Gaussian data).

    Parameters
    ----------
    alpha, beta : float
        Target false-alarm and missed-detection probabilities (:func:`sprt_thresholds`).
    divergence : float
        ``D = ½ δᵀ Σ⁻¹ δ > 0``, the Kullback–Leibler divergence per sample.
    hypothesis : {1, 0}, default 1
        The hypothesis in force: 1 gives ``E[N | H1]``, 0 gives ``E[N | H0]``.

    Returns
    -------
    float
        The expected number of samples to a decision.

    Raises
    ------
    ParameterError
        When ``divergence`` is not positive, ``hypothesis`` is not 0 or 1, or ``α``, ``β`` are invalid.

    References
    ----------
    Wald 1947 (the SPRT, its thresholds and expected sample numbers); Basseville & Nikiforov 1993, §2.2 and §4.3;
    Douglas et al. 1996, Ch. 7 introduction (the Wald SPRT compared with the Shiryayev SPRT).

    Examples
    --------
    >>> from fdikit.decision.sprt import sprt_asn
    >>> round(sprt_asn(0.01, 0.01, 0.5), 3), round(sprt_asn(0.01, 0.01, 0.5, hypothesis=0), 3)
    (9.006, 9.006)
    """
    if not divergence > 0:
        raise ParameterError(f"the divergence must be positive, got {divergence}")
    A, B = sprt_thresholds(alpha, beta)
    if hypothesis == 1:
        return ((1 - beta) * A + beta * B) / divergence
    if hypothesis == 0:
        return ((1 - alpha) * B + alpha * A) / (-divergence)
    raise ParameterError(f"hypothesis must be 0 or 1, got {hypothesis}")


def _advance(L: np.ndarray, done: np.ndarray, lam: np.ndarray, A: np.ndarray, B: np.ndarray, restart: bool):
    """One sample of the test for every block: ``(Λ reported, decision, Λ next, done next)``.

    The online form of :func:`_walk` (same additions and comparisons).
    """
    if restart:
        now = L + lam
        up, down = now >= A, now <= B
        dec = up.astype(np.int8) - down.astype(np.int8)
        return now, dec, np.where(up | down, 0.0, now), done
    now = np.where(done, L, L + lam)
    up, down = ~done & (now >= A), ~done & (now <= B)
    done_next = done | up | down
    return now, up.astype(np.int8) - down.astype(np.int8), now, done_next


def _walk(lam: np.ndarray, A: float, B: float, restart: bool) -> tuple[np.ndarray, np.ndarray]:
    """``Λ_k`` (before any restart) and the decisions of one block over its valid samples.

    The same additions and comparisons as :func:`_advance` (so batch == online bit for
    bit): the single test is one cumulative sum up to its stopping sample; the repeated
    test is a scalar loop (its segments between restarts are short under H0).
    """
    n = lam.size
    dec = np.zeros(n, np.int8)
    if not restart:
        S = np.add.accumulate(lam)
        cross = (S >= A) | (S <= B)
        if not cross.any():
            return S, dec
        j = int(np.argmax(cross))
        S[j + 1 :] = S[j]
        dec[j] = 1 if S[j] >= A else -1
        return S, dec
    out = [0.0] * n
    d = [0] * n
    L = 0.0
    for k, x in enumerate(lam.tolist()):
        L += x
        out[k] = L
        if L >= A:
            d[k], L = 1, 0.0
        elif L <= B:
            d[k], L = -1, 0.0
    return np.array(out), np.array(d, np.int8)


class SprtEvaluator:
    """Wald SPRT of ``N(μ0, Σ)`` against ``N(μ0 + δ, Σ)`` per block of residuals.

    Parameters
    ----------
    shift : float or array_like
        ``δ`` in residual units, one value or one per residual (signed).  Every block
        needs a non-zero ``δ``.
    alpha, beta : float
        Target false-alarm and missed-detection probabilities of one test (default 0.01).
    mean : float or array_like, optional
        ``μ0`` per residual (default 0, or the fault-free mean after :meth:`fit`).
    cov : float, (q,) or (q, q) array_like, optional
        Noise covariance (only its block-diagonal part is used); default identity, or the
        fault-free estimate after :meth:`fit`.
    blocks : 'isolates', 'each', 'all' or sequence
        Grouping of residuals into vector tests (:func:`fdikit.decision.glr.residual_blocks`).
    restart : bool
        Repeated test with restarts at 0 (default) or Wald's single test.
    hold : int
        Keep ``fired`` on for this many valid samples after an alarm (``restart=True``).
    isolates, groups : sequence, optional
        Fault tied to each residual, filter of each residual (bank).
    signatures : SignatureTable, mapping or DataFrame, optional
        Isolate by the fault-signature table (:mod:`fdikit.decision.signature`): its groups are matched
        against the fired *blocks* (by block name or the block's fault).

    Attributes
    ----------
    calibration : CalibrationReport or None
        After :meth:`fit`: the alarms raised on the calibration runs over their hours, with the Garwood interval
        (:class:`~fdikit.decision.calibration.CalibrationReport`).

    References
    ----------
    Wald 1947 (the SPRT, its thresholds and expected sample numbers); Basseville & Nikiforov 1993, §2.2 and §4.3;
    Douglas et al. 1996, Ch. 7 introduction (the Wald SPRT compared with the Shiryayev SPRT).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> rng = np.random.default_rng(1)
    >>> r = rng.standard_normal((300, 1)); r[200:] += 1.0
    >>> d = SprtEvaluator(shift=1.0, alpha=1e-3, beta=1e-3).run(Residuals(np.arange(300.0), r, ("r",), ("f",)))
    >>> d.first_alarm().index, d.first_alarm().fault
    (207, 'f')
    """

    def __init__(
        self, shift, alpha: float = 0.01, beta: float = 0.01, mean=None, cov=None, *, blocks="isolates",
        restart: bool = True, hold: int = 0, isolates=None, groups=None, signatures=None,
    ) -> None:
        self.shift = np.atleast_1d(np.asarray(shift, dtype=float))
        if self.shift.ndim != 1 or not np.all(np.isfinite(self.shift)):
            raise ParameterError(f"shift must be finite, one value or one per residual; got {shift}")
        self.A, self.B = sprt_thresholds(alpha, beta)
        self.alpha, self.beta = float(alpha), float(beta)
        self.mean = None if mean is None else np.atleast_1d(np.asarray(mean, dtype=float))
        self.cov = None if cov is None else np.asarray(cov, dtype=float)
        if self.cov is not None and (not np.all(np.isfinite(self.cov)) or (self.cov.ndim < 2 and
                                                                            not np.all(self.cov > 0))):
            raise ParameterError(f"cov must be finite with positive variances, got {cov}")
        if not is_count(hold, 0):
            raise ParameterError(f"hold must be a non-negative number of samples, got {hold}")
        if not (isinstance(blocks, str) or isinstance(blocks, Sequence)):
            raise ParameterError(
                f"blocks must be 'isolates', 'each', 'all' or one label per residual, got {blocks!r}"
            )
        self.blocks = blocks if isinstance(blocks, str) else tuple(blocks)
        self.restart = bool(restart)
        self.hold = int(hold)
        self.isolates = None if isolates is None else tuple(isolates)
        self.groups = None if groups is None else tuple(groups)
        self.signatures = as_signature_table(signatures)
        self.names: tuple[str, ...] | None = None
        self.calibration = None
        self.reset()

    def fit(self, residuals: Residuals | Sequence[Residuals]) -> SprtEvaluator:
        """Estimate ``μ0`` and ``Σ`` on fault-free residuals (one run or a list); returns ``self``.

        Parameters
        ----------
        residuals : Residuals or sequence of Residuals
            Fault-free residuals, one run or several (invalid and non-finite rows skipped; at least 10 must
            remain): pooled for the moments, each run evaluated on its own for the ``calibration`` report.

        Returns
        -------
        SprtEvaluator
            ``self``, with ``mean``, ``cov``, ``names`` and ``calibration`` set (and ``isolates`` when unset).

        Raises
        ------
        DataError
            When there are too few samples, a block covariance is singular, or the shifts, means or
            ``isolates`` do not fit the residuals.
        ParameterError
            When a block's shift is zero.
        """
        from fdikit.decision.calibration import calibration_report, calibration_runs

        runs = calibration_runs(residuals)
        self.mean, self.cov = fit_moments(runs)
        self.names = runs.names
        if self.isolates is None:
            self.isolates = runs.isolates
        self._ready(len(runs.names), runs.runs[0])  # fail now on a singular block covariance
        self.reset()
        self.calibration = calibration_report(self, runs)
        return self

    def _ready(self, q: int, residuals: Residuals | None = None):
        names = checked_names(q, residuals, self.names)
        if self.shift.size not in (1, q):
            raise DataError(f"{self.shift.size} shift values for {q} residuals")
        delta = np.array(np.broadcast_to(self.shift, (q,)))
        mean = np.zeros(q) if self.mean is None else np.atleast_1d(self.mean)
        if mean.size not in (1, q):
            raise DataError(f"{mean.size} mean values for {q} residuals")
        mean = np.array(np.broadcast_to(mean, (q,)))
        cov = np.ones(q) if self.cov is None else as_covariance(self.cov, q)
        iso = self.isolates or (residuals.isolates if residuals is not None else (None,) * q)
        if len(iso) != q:
            raise DataError(f"{len(iso)} 'isolates' entries for {q} residuals")
        layout = BlockLayout(self.blocks, names, tuple(iso), self.groups, cov)
        G, P = layout.index.shape
        w = np.zeros((G, P))
        c = np.zeros(G)
        for g, (name, ix) in enumerate(layout.blocks):
            d = delta[list(ix)]
            if not np.any(d != 0):
                raise ParameterError(
                    f"block {name!r} has a zero shift; the SPRT needs a non-zero change δ to test"
                )
            W = layout.whiten[g, : len(ix), : len(ix)]
            w[g, : len(ix)] = W.T @ (W @ d)  # Σ⁻¹ δ with Σ⁻¹ = L⁻ᵀ L⁻¹
            c[g] = 0.5 * float(d @ w[g, : len(ix)])
        return mean, layout, w, c

    def _llr(self, e: np.ndarray, layout: BlockLayout, w: np.ndarray, c: np.ndarray) -> np.ndarray:
        """``λ = wᵀ e − c`` per block, summed in a fixed order (batch == online)."""
        E = layout.gather(e)
        acc = w[:, 0] * E[..., 0]
        for j in range(1, w.shape[1]):
            acc = acc + w[:, j] * E[..., j]
        return acc - c

    def _meta(self, layout: BlockLayout, c: np.ndarray, names) -> dict:
        return {
            "evaluator": "sprt", "alpha": self.alpha, "beta": self.beta, "A": self.A, "B": self.B,
            "shift": self.shift.tolist(), "divergence": c.tolist(), "restart": self.restart, "hold": self.hold,
            "blocks": {block: [names[i] for i in ix] for block, ix in layout.blocks},
        }

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series; identical to stepping through it."""
        residuals = checked_residuals(residuals, self.names, "the SPRT")
        q = len(residuals.names)
        mean, layout, w, c = self._ready(q, residuals)
        r = residuals.r
        valid = residuals.valid & np.all(np.isfinite(r), axis=1)
        lam = self._llr(r[valid] - mean, layout, w, c)
        n, G = lam.shape
        llr, dec = np.zeros((n, G)), np.zeros((n, G), np.int8)
        for g in range(G):
            llr[:, g], dec[:, g] = _walk(lam[:, g], self.A, self.B, self.restart)
        if self.restart:
            fired_v = k_of_n(dec > 0, 1, self.hold + 1)
        else:
            dec = np.cumsum(dec, axis=0, dtype=np.int8)  # one ±1 per block at most: latched from then on
            fired_v = dec > 0
        fired = held(fired_v, valid, False)
        isolated = isolate_fired(fired, layout.isolates, layout.groups, self.signatures, layout.names)
        meta = self._meta(layout, c, residuals.names)
        meta["llr"] = held(llr, valid, 0.0)
        meta["decision"] = held(dec, valid, 0)
        return Diagnosis(residuals.t, fired.any(axis=1), fired, layout.names, isolated, valid=valid, meta=meta)

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        """Restart every test at ``Λ = 0`` (start of a new run)."""
        self._state = None
        self.llr: np.ndarray | None = None
        self.decision: np.ndarray | None = None

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the statistic and the decision.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the statistics and the decision hold.  ``names`` (optional) are
        checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).


        After the call ``llr`` holds ``Λ_k`` and ``decision`` the decision as in ``meta``.
        The parameters are read at the first step after :meth:`reset` (or :meth:`fit`).
        """
        r = step_vector(r, self.names, names, "the SPRT")
        st = self._state
        if st is not None and st["q"] != r.size:
            raise DataError(f"step() got {r.size} residuals after steps with {st['q']}; call reset() first")
        if st is None:
            mean, layout, w, c = self._ready(r.size)
            G = len(layout.blocks)
            st = self._state = {
                "q": r.size, "mean": mean, "layout": layout, "w": w, "c": c, "A": np.full(G, self.A),
                "B": np.full(G, self.B), "L": np.zeros(G), "done": np.zeros(G, bool), "left": np.zeros(G, int),
                "fired": np.zeros(G, bool), "cache": {},
            }
            self.llr, self.decision = np.zeros(G), np.zeros(G, np.int8)
        if not (valid and np.all(np.isfinite(r))):
            fired = st["fired"]
            return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), False)
        lam = self._llr(r - st["mean"], st["layout"], st["w"], st["c"])
        now, dec, st["L"], done = _advance(st["L"], st["done"], lam, st["A"], st["B"], self.restart)
        if self.restart:
            up = dec > 0
            fired = up | (st["left"] > 0)
            st["left"] = np.where(up, self.hold, np.maximum(st["left"] - 1, 0))
            self.decision = dec
        else:
            fired = st["fired"] | (dec > 0)
            self.decision = self.decision + dec
        st["done"], st["fired"] = done, fired
        self.llr = now
        return StepDecision(bool(fired.any()), self._isolate(fired), fired.copy(), True)

    def _isolate(self, fired: np.ndarray) -> str:
        layout = self._state["layout"]
        return isolate_cached(self._state["cache"], fired, layout.isolates, layout.groups, self.signatures,
                              layout.names)

    def __repr__(self) -> str:
        return (f"SprtEvaluator(shift={self.shift}, alpha={self.alpha}, beta={self.beta}, "
                f"restart={self.restart}, blocks={self.blocks!r})")
