"""Multiple-hypothesis Shiryayev SPRT (Malladi & Speyer; Douglas et al. 1996, Ch. 7).

``m + 1`` hypotheses: ``H_0`` (no fault, density ``f_0``) and ``H_i`` (fault ``i`` has happened, density
``f_i``).  ``p_i`` is the prior probability of a switch ``H_0 → H_i`` in one sample interval, ``π_i`` the
probability that fault ``i`` happened before the first sample, ``F_{k,i} = P(θ_i ≤ t_k | x_1..x_k)``.
Prop. 7.1, corrected (the proof's step (7.6c) writes ``p_i (1 − F_{k,i})``, which fails Prop. 7.2; under
the single-fault assumption the probability that no fault has happened yet is ``1 − Σ_j F_{k,j} = F_{k,0}``)::

    F_{0,i}   = π_i,  F_{0,0} = 1 − Σ_i π_i                                   (7.1a)
    M_{k,i}   = F_{k,i} + p_i (1 − Σ_j F_{k,j})                               (7.1c, corrected)
    F_{k+1,i} = M_{k,i} f_i(x) / [Σ_j M_{k,j} f_j(x) + (1 − Σ_j M_{k,j}) f_0(x)]   (7.1b, denominator index fixed)

This is the Bayes filter of the absorbing chain ``0 → i`` and satisfies Prop. 7.2 (``0 ≤ F_{k,i}``,
``Σ_i F_{k,i} ≤ 1``) for any data.  It runs in the log domain: ``log F_{k,0}`` is a state of its own
(``M_{k,0} = F_{k,0} (1 − Σ p_i)``), the update is a log-sum-exp, so 11-D Gaussian densities and long runs never
underflow.  ``form="literal"`` runs the printed (7.1c) ``M_{k,i} = F_{k,i} + p_i (1 − F_{k,i})``, which lets
``Σ_j M_{k,j}`` exceed 1 and breaks Prop. 7.2 (``Σ_i F_{k,i} > 1``); its quantities can leave
``[0, 1]``, so it is kept in linear form (densities scaled by their maximum).  For ``m = 1`` both are the same.

Decision (§7.2.2–7.2.3): announce fault ``i`` while ``F_{k,i} ≥ F_{T,i}``; ``α_i = 1 − F_{T,i}`` bounds the
probability that an announcement is a false alarm (Shiryayev).  Densities: :class:`GaussianDensity`,
:func:`gaussian_mean_density` (Prop. 7.4) and :class:`UniformMeanDensity` (Prop. 7.5, corrected for ``n > 1``),
or any object with ``dim`` and a row-wise ``logpdf``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

import numpy as np

from fdikit.decision.common import checked_residuals, step_vector
from fdikit.decision.densities import (
    GaussianDensity,
    UniformMeanDensity,
    gaussian_mean_density,
)
from fdikit.diagnosis import UNKNOWN_FAULT, Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = [
    "MhsprtEvaluator",
    "magnitude_blocks",
]

_LOG2PI = np.log(2.0 * np.pi)



def magnitude_blocks(residuals: Residuals, groups: Sequence[str] | None = None) -> tuple[str, ...]:
    """Per residual component, the label of its block for ``MhsprtEvaluator(blocks=...)``.

    Components tied to the same fault (and, with ``groups``, in the same filter of a bank) form one block whose
    Euclidean magnitude is one measurement component; an untied residual is a block of its own.

    Parameters
    ----------
    residuals : Residuals
        The residual series whose names and tied faults are grouped; an untied residual's label is its name
        without a trailing component index (``"a[1]"`` → ``"a"``).
    groups : sequence of str, optional
        The filter of each residual in a bank; labels become ``"<group>:<fault>"``.

    Returns
    -------
    tuple of str
        One block label per residual component.

    Raises
    ------
    ParameterError
        When ``groups`` does not have one entry per residual.

    References
    ----------
    Douglas et al. 1996, §5.1.1 (the residual magnitudes of the fault detection filters) and §7.4 (the
    Shiryayev SPRT on the vehicle's filter residuals).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.mhsprt import magnitude_blocks
    >>> r = Residuals(np.arange(3) * 0.1, np.zeros((3, 3)), ("a[0]", "a[1]", "b"), ("fa", "fa", None))
    >>> magnitude_blocks(r), magnitude_blocks(r, groups=("F1", "F1", "F2"))
    (('fa', 'fa', 'b'), ('F1:fa', 'F1:fa', 'F2:b'))
    """
    if groups is not None and len(groups) != len(residuals.names):
        raise ParameterError(f"{len(groups)} groups for {len(residuals.names)} residuals")
    labels = []
    for k, (name, iso) in enumerate(zip(residuals.names, residuals.isolates)):
        base = iso if iso is not None else re.sub(r"\[\d+\]$", "", name)
        labels.append(base if groups is None else f"{groups[k]}:{base}")
    return tuple(labels)


def _per_fault(value, faults: tuple[str, ...], name: str) -> np.ndarray:
    if isinstance(value, Mapping):
        missing, extra = set(faults) - set(value), set(value) - set(faults)
        if missing or extra:
            raise ParameterError(f"{name} must name exactly the faults {faults}; missing {sorted(missing)}, "
                             f"unknown {sorted(extra)}")
        v = np.array([float(value[f]) for f in faults])
    else:
        v = np.broadcast_to(np.asarray(value, dtype=float), (len(faults),)).copy() if np.ndim(value) == 0 else \
            np.asarray(value, dtype=float).ravel()
        if v.size != len(faults):
            raise ParameterError(f"{name} has {v.size} entries for {len(faults)} faults {faults}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"{name} has non-finite entries: {v}")
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
        ``F_T = 0.95`` are assumptions made here (the report gives none for its application).
    pi : float, sequence or mapping
        ``π_i = P(fault i before the first sample)``; ``Σ π_i ≤ 1``.
    threshold : float, sequence or mapping
        ``F_{T,i}`` in (0, 1]; ``α_i = 1 − F_{T,i}`` (:func:`shiryayev_threshold`).
    form : ``'corrected'`` (default, Prop. 7.2 holds) or ``'literal'`` (the printed (7.1c); violates Prop. 7.2).
    blocks : sequence of str, optional
        One label per residual component (:func:`magnitude_blocks`): each block is replaced by its Euclidean
        magnitude before the test (the report's "residual magnitudes", §5.1.1).  Magnitudes of fault-free
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

    References
    ----------
    Douglas et al. 1996, §7.2.1, Prop. 7.1, (7.1a)–(7.1c) (the posterior recursion; (7.1c) corrected as above),
    Prop. 7.2 (its bounds), §7.2.3 (the thresholds ``F_{T,i}``), §7.3.1 (Example 1) and §7.4 (the vehicle
    application).

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
            raise ParameterError(f"unknown form {form!r}; use 'corrected' or 'literal'")
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
            raise ParameterError(
                f"densities need the fault-free hypothesis {NO_FAULT!r}; got {list(densities)}"
            )
        if len(densities) < 2:
            raise ParameterError("need at least one fault hypothesis besides 'none'")
        dims = {k: getattr(d, "dim", None) for k, d in densities.items()}
        if None in dims.values() or not all(callable(getattr(d, "logpdf", None)) for d in densities.values()):
            raise ParameterError("each density needs a 'dim' and a 'logpdf(x)'; see GaussianDensity")
        if len(set(dims.values())) != 1:
            raise ParameterError(f"densities of different dimensions: {dims}")
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
        return np.column_stack([np.sqrt(np.einsum('ij,ij->i', r[:, idx], r[:, idx])) for idx in self._block_index()])

    def _setup(self) -> None:
        faults = self.faults
        p = _per_fault(self.p, faults, "p")
        pi = _per_fault(self.pi, faults, "pi")
        ft = _per_fault(self.threshold, faults, "threshold")
        if np.any(p < 0) or not p.sum() < 1:
            raise ParameterError(f"switch probabilities p must be >= 0 with sum < 1, got {p} (sum {p.sum():g})")
        if np.any(pi < 0) or not pi.sum() <= 1:
            raise ParameterError(f"initial probabilities pi must be >= 0 with sum <= 1 (Prop. 7.2), got {pi}")
        if not np.all((ft > 0) & (ft <= 1)):
            raise ParameterError(f"thresholds F_T must be in (0, 1], got {ft}")
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
        one :class:`~fdikit.residuals.Residuals` or a list of runs (slice off start-up transients first).  Only valid,
        finite samples are used.  ``'none'`` is always ``N(mean, cov)`` of its samples.  Faults, by ``mean``:

        * ``'fixed'``: ``N(mean, cov)`` of all their samples;
        * ``'gaussian'``: runs of different fault sizes; within-run covariance ``Λ``, run means ``~ N(m*, Σ_μ)``
          (their sample mean and covariance) → ``N(m*, Λ + Σ_μ)`` (Prop. 7.4);
        * ``'uniform'``: within-run ``Λ``, mean uniform on the box spanned by the run means (Prop. 7.5); needs
          ``diagonal=True`` or ``uniform_method='mixture'`` with ``rng``.

        ``diagonal`` keeps only the variances of the fitted ``Λ`` (all hypotheses; ``Σ_μ`` stays full);
        ``regularization`` as in :class:`GaussianDensity`
        (a singular fitted covariance is refused with :class:`~fdikit.errors.DataError` otherwise).
        """
        if mean not in ("fixed", "gaussian", "uniform"):
            raise ParameterError(f"unknown mean model {mean!r}; use 'fixed', 'gaussian' or 'uniform'")
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
            except ParameterError as exc:
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
            raise ParameterError("the evaluator has no densities; pass densities= or call fit() on residuals")

    # ------------------------------------------------------------------ batch
    def run(self, residuals: Residuals) -> Diagnosis:
        """Posteriors and decisions for a whole series; identical to :meth:`reset` then :meth:`step` per sample."""
        residuals = checked_residuals(residuals, self.names, "the MHSPRT")
        self._need()
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

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Update with one residual sample; a NaN/inf sample holds the posterior and is reported invalid.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the statistics and the decision hold.  ``names`` (optional) are
        checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).
        """
        self._need()
        r = step_vector(r, self.names, names, "the MHSPRT")
        valid = bool(valid) and bool(np.all(np.isfinite(r)))
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
