"""Gaussian maximum-likelihood classifier as a single-layer perceptron (Douglas et al. 1996, §6.2.1).

With ``x | H_i ~ N(m_i, Λ)`` and
``L_i = −(x − m_i)ᵀ Λ⁻¹ (x − m_i)``::

    L_ij = L_i − L_j = 2 (m_i − m_j)ᵀ Λ⁻¹ x + (m_jᵀ Λ⁻¹ m_j − m_iᵀ Λ⁻¹ m_i) = W x + θ

and ``H_i`` is declared when ``L_i − max_{j≠i} L_j > 0``; with priors the term ``2 ln(π_i/π_j)`` is
added (MAP; equal priors give the report's ML rule).  Posteriors:
``P(H_i | x) = softmax_i(L_i/2 + ln π_i)``.  The report's perceptron output ``S(L_ij)`` gives the
same decision but is not the posterior: for two classes with equal priors that is ``S(L_ij / 2)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy.special import logsumexp

from fdikit.decision.common import checked_residuals, step_vector
from fdikit.decision.learned.labelled_runs import LabelledInputs, as_runs
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = ["GaussianMlEvaluator"]


class GaussianMlEvaluator:
    """Gaussian maximum-likelihood classifier with a shared covariance, as a single-layer perceptron (§6.2.1).

    Classes are the training labels (``'none'`` included when present).  ``weights[i] = 2 m_iᵀΛ⁻¹``
    and ``bias[i] = −m_iᵀΛ⁻¹m_i + 2 ln π_i`` give ``L_i + 2 ln π_i`` up to the common ``−xᵀΛ⁻¹x``,
    so the pairwise perceptron ``L_ij = W x + θ`` of the report is a difference of two rows
    (:meth:`pairwise`).  ``Diagnosis.probabilities`` holds the fault classes (``P(none) = 1 − Σ``).

    Parameters
    ----------
    priors : None, 'empirical' or mapping
        None (equal: the report's ML rule), 'empirical' (class frequencies of the training samples, with
        :meth:`fit` only) or a mapping class → positive weight (normalised to sum 1).
    inputs : {'magnitude', 'raw'}, default 'magnitude'
        One input per fault group (the Euclidean magnitude of its residuals) or one per residual, as for
        :class:`~fdikit.decision.learned.bnn.BnnEvaluator` (no scaling: the rule is affine invariant).
    columns : sequence of str, optional
        Residual names to use (one classifier per filter of a stacked bank).

    Attributes
    ----------
    classes : tuple of str
        The classes, in order of first appearance in the training labels.
    hypotheses : tuple of str
        The fault classes (``classes`` without ``'none'``): the columns of ``Diagnosis.probabilities``.
    means : (C, n) ndarray
        Class means ``m_i`` of the inputs.
    covariance : (n, n) ndarray
        Shared (pooled within-class) covariance ``Λ``.
    prior : (C,) ndarray
        Class priors ``π_i``.
    weights, bias : (C, n) and (C,) ndarray
        ``2 m_iᵀΛ⁻¹`` and ``−m_iᵀΛ⁻¹m_i + 2 ln π_i``.

    Raises
    ------
    ParameterError
        When ``inputs`` is not 'magnitude' or 'raw'.

    References
    ----------
    Douglas et al. 1996, §6.2.1 (a maximum-likelihood Gaussian classifier as a multilayer perceptron: ``L_ij``,
    ``W`` and ``θ``).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.learned.gaussian_ml import GaussianMlEvaluator
    >>> ev = GaussianMlEvaluator.from_moments({"none": [0.0, 0.0], "fa": [2.0, 0.0], "fb": [0.0, 2.0]}, np.eye(2))
    >>> res = Residuals(np.arange(3) * 0.1, np.array([[0.0, 0.0], [2.0, 0.0], [0.1, 2.2]]), ("x0", "x1"), (None, None))
    >>> d = ev.run(res)
    >>> d.hypotheses, d.isolated.tolist(), np.round(d.probabilities[1], 3).tolist()
    (('fa', 'fb'), ['none', 'fa', 'fb'], [0.867, 0.016])
    """

    def __init__(self, priors=None, *, inputs: str = "magnitude", columns: Sequence[str] | None = None) -> None:
        if inputs not in ("magnitude", "raw"):
            raise ParameterError(f"unknown inputs mode {inputs!r}; use 'magnitude' or 'raw'")
        self.priors, self.inputs, self.columns = priors, inputs, None if columns is None else tuple(columns)
        self.classes: tuple[str, ...] = ()
        self.means: np.ndarray | None = None
        self.covariance: np.ndarray | None = None
        self.prior: np.ndarray | None = None
        self._inputs: LabelledInputs | None = None
        self.names: tuple[str, ...] | None = None
        self.reset()

    @classmethod
    def from_moments(cls, means: Mapping[str, Sequence[float]], covariance, priors=None) -> GaussianMlEvaluator:
        """Classifier for known class means and shared covariance; inputs are the raw residual vector."""
        ev = cls(priors, inputs="raw")
        M = np.atleast_2d(np.array([np.asarray(m, dtype=float).ravel() for m in means.values()]))
        n = M.shape[1]
        ev._inputs = LabelledInputs(n, tuple((i,) for i in range(n)), tuple(f"x{i}" for i in range(n)), False,
                                    np.ones(n))
        ev._set(tuple(str(k) for k in means), M, np.asarray(covariance, dtype=float), None)
        return ev

    def fit(self, data, labels=None) -> GaussianMlEvaluator:
        """Class means and pooled within-class covariance from labelled residuals (as :meth:`BnnEvaluator.fit`)."""
        runs = as_runs(data, labels)
        res0 = runs[0][0]
        spec = LabelledInputs.build(res0.names, res0.isolates, self.inputs, self.columns)
        self.names = res0.names
        X = np.concatenate([spec(res.r) for res, _ in runs])
        lab = np.concatenate([lb for _, lb in runs]).astype(str)
        ok = np.concatenate([res.valid for res, _ in runs]) & np.all(np.isfinite(X), axis=1)
        X, lab = X[ok], lab[ok]
        classes = tuple(dict.fromkeys(lab))
        if len(classes) < 2:
            raise DataError(f"need at least two classes to classify, got {list(classes)}")
        M = np.array([X[lab == c].mean(axis=0) for c in classes])
        D = X - M[[classes.index(c) for c in lab]]
        if X.shape[0] - len(classes) < X.shape[1]:
            raise DataError(
                f"{X.shape[0]} samples in {len(classes)} classes cannot estimate a {X.shape[1]}-D covariance")
        S = D.T @ D / (X.shape[0] - len(classes))
        counts = np.array([np.sum(lab == c) for c in classes], dtype=float)
        self._inputs = spec
        self._set(classes, M, S, counts)
        return self

    def _set(self, classes, M, S, counts) -> None:
        n = M.shape[1]
        if S.shape != (n, n) or not np.all(np.isfinite(S)) or not np.all(np.isfinite(M)):
            raise ParameterError(f"covariance must be a finite {n}x{n} matrix and the means finite")
        S = 0.5 * (S + S.T)
        ev = np.linalg.eigvalsh(S)
        if not ev[0] > 1e-12 * max(ev[-1], 0.0):
            raise DataError(f"the shared covariance is singular (eigenvalues {ev[0]:.3g} … {ev[-1]:.3g}); "
                            "drop constant or duplicate inputs")
        if self.priors is None:
            pi = np.full(len(classes), 1.0 / len(classes))
        elif isinstance(self.priors, str):
            if self.priors != "empirical" or counts is None:
                raise ParameterError(f"priors={self.priors!r}: use None, a mapping, or 'empirical' with fit()")
            pi = counts / counts.sum()
        else:
            missing = [c for c in classes if c not in self.priors]
            if missing:
                raise ParameterError(f"priors lack the classes {missing}")
            pi = np.array([float(self.priors[c]) for c in classes])
            if not np.all(pi > 0):
                raise ParameterError(f"priors must be positive, got {pi}")
            pi = pi / pi.sum()
        self.classes, self.means, self.covariance, self.prior = tuple(classes), M, S, pi
        Li = np.linalg.solve(S, M.T).T  # rows Λ⁻¹ m_i
        self.weights = 2.0 * Li
        self.bias = -np.sum(M * Li, axis=1) + 2.0 * np.log(pi)
        self.reset()

    @property
    def hypotheses(self) -> tuple[str, ...]:
        return tuple(c for c in self.classes if c != NO_FAULT)

    def pairwise(self, i: str, j: str) -> tuple[np.ndarray, float]:
        """The report's ``L_ij = W x + θ``: ``W = 2(m_i − m_j)ᵀΛ⁻¹``, ``θ = m_jᵀΛ⁻¹m_j − m_iᵀΛ⁻¹m_i``.

        This is the ML form (no priors); the decision with priors adds ``2 ln(π_i/π_j)`` to ``θ``.
        """
        a, b = self.classes.index(i), self.classes.index(j)
        prior_term = 2.0 * np.log(self.prior[a] / self.prior[b])
        return self.weights[a] - self.weights[b], float(self.bias[a] - self.bias[b] - prior_term)

    def discriminants(self, x) -> np.ndarray:
        """``W x + θ`` per class (``L_i + 2 ln π_i`` up to a common term), ``(..., C)``.

        Summed row by row (not a matrix product), so a batch gives the bits of one sample at a time."""
        x = np.asarray(x, dtype=float)
        return (x[..., None, :] * self.weights).sum(axis=-1) + self.bias

    def _classify(self, X):
        G = self.discriminants(X)
        logp = 0.5 * G
        P = np.exp(logp - logsumexp(logp, axis=-1, keepdims=True))
        return np.argmax(G, axis=-1), P

    def _ready(self) -> LabelledInputs:
        if self.means is None or self._inputs is None:
            raise ParameterError("the classifier has no class model; call fit() or use from_moments()")
        return self._inputs

    def run(self, residuals: Residuals) -> Diagnosis:
        """Per-sample decisions; invalid samples hold the previous decision (identical to :meth:`step`)."""
        residuals = checked_residuals(residuals, self.names, "the Gaussian ML classifier")
        X = self._ready()(residuals.r)
        ok = residuals.valid & np.all(np.isfinite(X), axis=1)
        H = len(self.classes)
        cls_v, P_v = self._classify(X[ok])
        pos = np.cumsum(ok) - 1
        has = pos >= 0
        Pc = np.zeros((len(residuals), H))
        decided = np.full(len(residuals), -1)
        Pc[has], decided[has] = P_v[pos[has]], cls_v[pos[has]]
        return self._diagnosis(residuals.t, Pc, decided, ok)

    def _diagnosis(self, t, Pc, decided, ok) -> Diagnosis:
        names = np.array([*self.classes, NO_FAULT], dtype=object)
        label = names[decided].astype(str)  # -1: nothing decided yet
        cols = [k for k, c in enumerate(self.classes) if c != NO_FAULT]
        fired = label[:, None] == np.array(self.hypotheses, dtype=object)[None, :]
        meta = {"evaluator": "gaussian_ml", "classes": list(self.classes), "priors": self.prior.tolist()}
        return Diagnosis(t, label != NO_FAULT, fired, self.hypotheses, label, probabilities=Pc[:, cols],
                         hypotheses=self.hypotheses, valid=ok, meta=meta)

    def reset(self) -> None:
        """Forget the held decision."""
        self._last = None

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the previous decision.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the decision (and any feedback state) holds.  ``names`` (optional)
        are checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).
        """
        x = self._ready()(step_vector(r, self.names, names, "the Gaussian ML classifier"))
        valid = bool(valid) and bool(np.all(np.isfinite(x)))
        if valid:
            c, P = self._classify(x[None, :])
            self._last = (np.array([c[0]]), P)
        c, P = self._last if self._last is not None else (np.array([-1]), np.zeros((1, len(self.classes))))
        d = self._diagnosis(np.zeros(1), P, c, np.array([valid]))
        return StepDecision(bool(d.alarm[0]), str(d.isolated[0]), d.fired[0], valid, d.probabilities[0])

    def __repr__(self) -> str:
        return f"GaussianMlEvaluator(classes={self.classes}, priors={None if self.prior is None else self.prior})"
