"""Bayesian neural network residual processor and the Gaussian ML classifier (Douglas et al. 1996, Ch. 6).

**Network (6.1).**  A ``q``-layer logistic perceptron with one-step output feedback::

    x¹_k = u_k + F y_{k−1}                     (6.1a; F = I in the report, all widths equal)
    x^i_k = W^i y^{i−1}_k + θ^i,   i = 2..q      (6.1b)
    y^i_k = S(x^i_k),              i = 1..q      (6.1c: the sigmoid acts on the input layer too)
    S(x) = e^x / (e^x + 1)                       (6.1d)

``y_k = y^q_k`` estimates the posterior probability of each fault hypothesis given the input
history (§6.2.2): trained on one-hot targets (all zeros for no fault, or for a fault outside the
network's hypotheses) with the mean-squared-error cost, the minimiser is ``E[z | X_k] = P(A | X_k)``.
Layer 1 has no weights and no bias, as in (6.1).  The report uses 5 layers of 3 nodes (2 for the
actuator filter, §6.4); here the default is 3 hidden layers of width ``max(n_in, n_out)``.

**Feedback dimension rule** (the report has equal input and output widths).  ``F`` is an
``n_in × n_out`` matrix: with ``feedback='tied'`` (default) ``F[i, j] = 1`` when input ``i`` is the
residual of hypothesis ``j`` (so each fault's posterior is fed back onto its own residual magnitude;
the report's identity when inputs and outputs are the same faults in the same order) and 0
otherwise; when no input is tied to any hypothesis it falls back to the zero-padded identity
``eye(n_in, n_out)``.  ``'pad'`` forces the zero-padded identity, ``'learned'`` trains ``F``
(initialised as ``'tied'``), an array sets it.

**Inputs** (research note G9).  ``inputs='magnitude'``: one input per fault group, ``‖z_f‖₂`` over
the residuals tied to fault ``f`` (``Residuals.isolates``; untied residuals form a group each),
divided by a scale (``'nominal'``: the mean magnitude over the training samples of fault ``f``, so
the nominal training fault gives ≈ 1, §5.1.1; inputs of faults without training data keep scale 1).
``inputs='raw'``: one input per residual column.  One network per filter, as in §6.4: pass the
filter's residual names as ``columns`` when the residuals are a stacked bank.

**Training (§6.3).**  First the deterministic cost ``J(w) = (1/N) Σ_k (z_k − y_k)ᵀ(z_k − y_k)`` over
all training sequences, minimised by a quasi-Newton method written here (:func:`quasi_newton`:
rank-2 update of the inverse Hessian, strong-Wolfe line search, the report's stop test "the change
of the Hessian estimate is small").  Gradients are exact back-propagation through time over the
whole unrolled recurrence (no teacher forcing: the network sees its own ``y_{k−1}``; research note
G12).  The report's update is DFP (``update='dfp'``); the default is its Broyden-family twin BFGS,
which has every property §6.3.1 relies on (rank 2, positive definite, ``n``-step termination on a
quadratic with exact searches, where the two give identical iterates) but corrects a poor Hessian
estimate under inexact line searches, where DFP stalls.  Measured on the 3-fault toy problem of the
tests (6000 samples, 400 iterations, two seeds): BFGS J = 0.054 with 434–448 cost evaluations; DFP
J = 0.054 with 2735–2740 evaluations (``c2 = 0.1``), and J = 0.17–0.25 with a loose search (``c2 = 0.9``).

Then Robbins–Monro ``w_{k+1} = w_k − ρ_k g(w_k)``, ``ρ_k = ρ_0/(k+1)^a``, ``a ∈ (0.5, 1]`` (so
``Σρ_k = ∞``, ``Σρ_k² < ∞``), where ``g`` is the exact gradient of the cost of a random mini-batch of
windows (sub-sequences) drawn from a seeded Generator; each window's network is run from its
sequence start, so the feedback state entering the window is the network's own.  Default ``ρ_0``:
``0.5/λ_max`` of the Hessian at the deterministic solution (a fixed ``ρ_0 = 0.1`` diverged on the
toy problem: the training cost rose from 0.048 to 0.20 where ``λ_max ≈ 49``).

Initialisation (:meth:`BnnNetwork.init`): channel-wise — each input routed through its own chain of
units to its tied output (``W^i = 4·I`` plus ``N(0, 0.25/n_{i−1})`` noise, biases centring each
sigmoid).  On the toy problem, random ``N(0, 4/n_{i−1})`` weights with zero biases stalled at
J = 0.09–0.18 after 400 BFGS iterations (3 seeds; DFP: 0.17–0.20).  Their mean squared distance to the exact
posterior was 0.05–0.16; the channel-wise start reaches J = 0.054 and 0.0086.  Samples that are NaN
or marked invalid hold the feedback state (training and running alike) and carry no cost.

**Gaussian ML classifier as a perceptron (§6.2.1).**  With ``x | H_i ~ N(m_i, Λ)`` and
``L_i = −(x − m_i)ᵀ Λ⁻¹ (x − m_i)``::

    L_ij = L_i − L_j = 2 (m_i − m_j)ᵀ Λ⁻¹ x + (m_jᵀ Λ⁻¹ m_j − m_iᵀ Λ⁻¹ m_i) = W x + θ

and ``H_i`` is declared when ``L_i − max_{j≠i} L_j > 0``; with priors the term ``2 ln(π_i/π_j)`` is
added (MAP; equal priors give the report's ML rule).  Posteriors:
``P(H_i | x) = softmax_i(L_i/2 + ln π_i)``.  The report's perceptron output ``S(L_ij)`` gives the
same decision but is not the posterior: for two classes with equal priors that is ``S(L_ij / 2)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import expit, logsumexp

from fdikit.decision.quasi_newton import QuasiNewtonResult, quasi_newton, robbins_monro_steps
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ModelError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = [
    "BnnEvaluator",
    "BnnNetwork",
    "GaussianMlEvaluator",
    "QuasiNewtonResult",
    "TrainingReport",
    "quasi_newton",
    "robbins_monro_steps",
]


# ====================================================================== optimisers
def _max_curvature(fg, w, rng, iters: int = 20) -> float:
    """Largest |eigenvalue| of the Hessian at ``w`` by power iteration on central-difference
    Hessian-vector products."""
    v = rng.standard_normal(w.size)
    v /= np.linalg.norm(v)
    eps = 1e-5 * (1.0 + np.linalg.norm(w))
    lam = 0.0
    for _ in range(iters):
        hv = (fg(w + eps * v)[1] - fg(w - eps * v)[1]) / (2 * eps)
        lam = float(np.linalg.norm(hv))
        if not lam > 0:
            break
        v = hv / lam
    if not (np.isfinite(lam) and lam > 0):
        raise DataError("the cost has no curvature at the trained weights; pass rho0= explicitly")
    return lam


# ====================================================================== the network
class BnnNetwork:
    """The logistic network with one-step output feedback (6.1); weights live in a flat vector.

    ``w`` stacks ``W², θ², …, W^q, θ^q`` (row-major) and, when ``learn_feedback``, ``F`` last.
    Sequences are ``(B, T, n_in)`` arrays (or ``(T, n_in)``); a sample is used when ``valid`` and
    finite, otherwise the feedback state is held and the output repeats.
    """

    def __init__(self, widths: Sequence[int], feedback=None, learn_feedback: bool = False) -> None:
        widths = tuple(int(n) for n in widths)
        if len(widths) < 2 or min(widths) < 1:
            raise ModelError(f"a network needs at least an input and an output layer of positive width, got {widths}")
        self.widths = widths
        F = np.eye(widths[0], widths[-1]) if feedback is None else np.asarray(feedback, dtype=float)
        if F.shape != (widths[0], widths[-1]) or not np.all(np.isfinite(F)):
            raise ModelError(f"the feedback matrix must be finite with shape {(widths[0], widths[-1])}, got {F.shape}")
        self.feedback, self.learn_feedback = F, bool(learn_feedback)
        self._shapes = [(widths[i], widths[i - 1]) for i in range(1, len(widths))]

    @property
    def n_params(self) -> int:
        return sum(a * b + a for a, b in self._shapes) + (self.feedback.size if self.learn_feedback else 0)

    def unpack(self, w) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
        """``([W², …, W^q], [θ², …, θ^q], F)`` from the flat vector."""
        w = np.asarray(w, dtype=float)
        if w.shape != (self.n_params,):
            raise ModelError(f"weight vector has shape {w.shape}, the network needs ({self.n_params},)")
        Ws, ths, k = [], [], 0
        for a, b in self._shapes:
            Ws.append(w[k : k + a * b].reshape(a, b))
            ths.append(w[k + a * b : k + a * b + a])
            k += a * b + a
        F = w[k:].reshape(self.feedback.shape) if self.learn_feedback else self.feedback
        return Ws, ths, F

    def init(self, rng: np.random.Generator, centre=None, gain: float = 4.0, noise: float = 0.5) -> np.ndarray:
        """Channel-wise initial weights: each input is routed through its own chain of units to its
        tied output.

        ``W^i = gain·R^i + N(0, noise²/n_{i−1})`` with ``R^i`` the rectangular identity (the last
        layer: ``Fᵀ``, zero-padded to the hidden width), and ``θ^i = −gain·R^i c^{i−1}``, which centres
        each routed sigmoid on its input's typical value (``c¹ = centre``, the mean of ``y¹``, default
        0.75; ``c^i = 1/2`` after).  ``gain = 4`` undoes the logistic's slope of 1/4 at the centre.
        """
        parts = []
        last = len(self._shapes) - 1
        c = np.broadcast_to(np.asarray(0.75 if centre is None else centre, dtype=float), (self.widths[0],))
        for i, (a, b) in enumerate(self._shapes):
            if i == last:
                route, k = np.zeros((a, b)), min(b, self.widths[0])
                route[:, :k] = self.feedback.T[:, :k]
            else:
                route = np.eye(a, b)
            W = gain * route + rng.normal(0.0, noise / np.sqrt(b), (a, b))
            parts += [W.ravel(), -gain * (route @ c)]
            c = np.full(a, 0.5)
        if self.learn_feedback:
            parts.append(self.feedback.ravel())
        return np.concatenate(parts)

    @staticmethod
    def _layers(Ws, ths, F, u, y_prev) -> list[np.ndarray]:
        """All layer outputs for one time step of a batch (rows): (6.1a–c)."""
        y = expit(u + y_prev @ F.T)
        out = [y]
        for W, th in zip(Ws, ths):
            y = expit(y @ W.T + th)
            out.append(y)
        return out

    def _prepare(self, U, valid):
        U = np.asarray(U, dtype=float)
        single = U.ndim == 2
        if single:
            U = U[None]
        if U.ndim != 3 or U.shape[2] != self.widths[0]:
            n = self.widths[0]
            raise DataError(f"network input has shape {U.shape}, need (B, T, {n}) or (T, {n})")
        ok = np.all(np.isfinite(U), axis=2)
        if valid is not None:
            ok &= np.asarray(valid, bool).reshape(ok.shape)
        U = np.where(ok[..., None], U, 0.0).transpose(1, 0, 2)
        return U, ok.T, single

    def forward(self, w, U, valid=None) -> np.ndarray:
        """Outputs ``y_k`` from the reset state ``y_{−1} = 0`` (``(B, T, n_out)``, or ``(T, n_out)``)."""
        Ws, ths, F = self.unpack(w)
        U, ok, single = self._prepare(U, valid)
        T, B = ok.shape
        y = np.zeros((B, self.widths[-1]))
        Y = np.empty((T, B, self.widths[-1]))
        for k in range(T):
            y = np.where(ok[k][:, None], self._layers(Ws, ths, F, U[k], y)[-1], y)
            Y[k] = y
        Y = Y.transpose(1, 0, 2)
        return Y[0] if single else Y

    def cost_grad(self, w, U, Z, cost_mask=None, valid=None) -> tuple[float, np.ndarray]:
        """``J = (1/N) Σ ‖z_k − y_k‖²`` over the samples in ``cost_mask`` (and valid), and ``∂J/∂w``.

        Back-propagation through time over the whole unrolled recurrence: the gradient reaches
        earlier samples through the feedback ``x¹_k = u_k + F y_{k−1}`` (and through held samples).
        """
        Ws, ths, F = self.unpack(w)
        U, ok, _ = self._prepare(U, valid)
        T, B = ok.shape
        Z = np.asarray(Z, dtype=float).reshape(B, T, -1).transpose(1, 0, 2)
        c = ok if cost_mask is None else ok & np.asarray(cost_mask, bool).reshape(B, T).T
        N = int(c.sum())
        if N == 0:
            raise DataError("no valid sample carries a cost; nothing to train on")
        c = c / N
        q = len(self.widths)
        every = ok.all(axis=1)
        WT = [W.T for W in Ws]
        acts = [np.empty((T, B, n)) for n in self.widths]
        Yprev = np.empty((T, B, self.widths[-1]))
        y = np.zeros((B, self.widths[-1]))
        for k in range(T):  # forward (6.1), the same arithmetic as _layers
            a = expit(U[k] + y @ F.T)
            acts[0][k] = a
            for i in range(1, q):
                a = expit(a @ WT[i - 1] + ths[i - 1])
                acts[i][k] = a
            Yprev[k] = y
            y = a if every[k] else np.where(ok[k][:, None], a, y)
        Y = np.concatenate([Yprev[1:], y[None]])  # the (held) output at each sample
        E = Y - Z
        J = float(np.sum(c[..., None] * E * E))
        Ey = 2.0 * c[..., None] * E
        der = [A * (1.0 - A) for A in acts]
        delta = [np.empty_like(A) for A in acts]  # δx^i_k = ∂J/∂x^i_k
        carry = np.zeros((B, self.widths[-1]))
        for k in range(T - 1, -1, -1):  # backward through time
            gy = Ey[k] + carry
            d = gy * der[-1][k]
            if not every[k]:
                d = np.where(ok[k][:, None], d, 0.0)
            delta[-1][k] = d
            for i in range(q - 1, 0, -1):
                d = (d @ Ws[i - 1]) * der[i - 1][k]
                delta[i - 1][k] = d
            carry = d @ F if every[k] else np.where(ok[k][:, None], d @ F, gy)
        parts = []
        for i in range(1, q):
            Di = delta[i].reshape(T * B, -1)
            parts += [(Di.T @ acts[i - 1].reshape(T * B, -1)).ravel(), Di.sum(axis=0)]
        if self.learn_feedback:
            parts.append((delta[0].reshape(T * B, -1).T @ Yprev.reshape(T * B, -1)).ravel())
        return J, np.concatenate(parts)


# ====================================================================== inputs and training data
@dataclass(frozen=True)
class _Inputs:
    """How a residual row becomes the network/classifier input."""

    n_columns: int
    groups: tuple[tuple[int, ...], ...]
    keys: tuple[str, ...]
    magnitude: bool
    scale: np.ndarray

    @classmethod
    def build(cls, names, isolates, mode: str, columns) -> _Inputs:
        if mode not in ("magnitude", "raw"):
            raise ModelError(f"unknown inputs mode {mode!r}; use 'magnitude' or 'raw'")
        names = tuple(names)
        if columns is None:
            idx = list(range(len(names)))
        else:
            missing = [c for c in columns if c not in names]
            if missing:
                raise DataError(f"columns {missing} are not among the residuals {list(names)}")
            idx = [names.index(c) for c in columns]
        key = [isolates[i] if isolates[i] is not None else names[i] for i in idx]
        if mode == "raw":
            groups, keys = tuple((i,) for i in idx), tuple(key)
        else:
            keys = tuple(dict.fromkeys(key))
            groups = tuple(tuple(i for i, kk in zip(idx, key) if kk == k) for k in keys)
        return cls(len(names), groups, keys, mode == "magnitude", np.ones(len(keys)))

    def raw(self, r: np.ndarray) -> np.ndarray:
        r = np.asarray(r, dtype=float)
        if r.shape[-1] != self.n_columns:
            raise DataError(f"residual vector has {r.shape[-1]} entries, the evaluator was set up for {self.n_columns}")
        if self.magnitude:
            return np.stack([np.sqrt(np.sum(r[..., list(g)] ** 2, axis=-1)) for g in self.groups], axis=-1)
        return r[..., [g[0] for g in self.groups]]

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return self.raw(r) / self.scale


def _as_runs(data, labels) -> list[tuple[Residuals, np.ndarray]]:
    """Training data as (residuals, per-sample labels) pairs."""
    runs: list[tuple[Residuals, np.ndarray]] = []
    if isinstance(data, Mapping):
        if labels is not None:
            raise ModelError("give labels only with a sequence of Residuals; a mapping's keys are the labels")
        for key, value in data.items():
            items = [value] if isinstance(value, Residuals) else list(value)
            for res in items:
                if not isinstance(res, Residuals):
                    raise DataError(f"training data for {key!r} must be Residuals, got {type(res).__name__}")
                runs.append((res, np.full(len(res), str(key), dtype=object)))
    else:
        items = [data] if isinstance(data, Residuals) else list(data)
        if labels is None:
            raise ModelError("a sequence of Residuals needs per-run labels (a str or one label per sample)")
        labels = [labels] if isinstance(labels, str) or isinstance(data, Residuals) else list(labels)
        if len(labels) != len(items):
            raise DataError(f"{len(labels)} label entries for {len(items)} runs")
        for res, lab in zip(items, labels):
            if not isinstance(res, Residuals):
                raise DataError(f"training data must be Residuals, got {type(res).__name__}")
            lab = np.full(len(res), lab, dtype=object) if isinstance(lab, str) else np.asarray(lab, dtype=object)
            if lab.shape != (len(res),):
                raise DataError(f"labels have shape {lab.shape}, the run has {len(res)} samples")
            runs.append((res, lab.astype(str).astype(object)))
    if not runs:
        raise DataError("no training data; pass {'none': fault-free residuals, fault: residuals, ...}")
    names = runs[0][0].names
    for res, _ in runs:
        if res.names != names:
            raise DataError(f"training residuals differ in their names: {list(res.names)} vs {list(names)}")
    return runs


def _targets(labels: np.ndarray, hypotheses: tuple[str, ...]) -> np.ndarray:
    """One-hot targets (§6.2.2): zeros for 'none' and for faults outside the hypotheses."""
    Z = np.zeros((labels.size, len(hypotheses)))
    for j, h in enumerate(hypotheses):
        Z[:, j] = [h in str(lab).split("+") for lab in labels]
    return Z


def _decisions(t, P, valid, hypotheses, threshold, meta) -> Diagnosis:
    fired = P >= threshold
    alarm = fired.any(axis=1)
    isolated = np.where(alarm, np.asarray(hypotheses, dtype=object)[np.argmax(P, axis=1)], NO_FAULT).astype(str)
    return Diagnosis(t, alarm, fired, hypotheses, isolated, probabilities=P, hypotheses=hypotheses, valid=valid,
                     meta=meta)


@dataclass(frozen=True)
class TrainingReport:
    """Training record: ``J`` on the whole training set at the start, after the quasi-Newton phase
    and at the end; quasi-Newton iterations, cost evaluations and stop reason; Robbins–Monro steps,
    first and last gain, and the largest Hessian eigenvalue used for the default ``ρ_0`` (NaN when
    ``rho0`` was given)."""

    cost_initial: float
    cost_deterministic: float
    cost_final: float
    iterations: int
    evaluations: int
    message: str
    rm_steps: int
    rho: tuple[float, float]
    curvature: float
    samples: int
    sequences: int


# ====================================================================== the BNN evaluator
class BnnEvaluator:
    """Bayesian neural network residual processor (PATH Ch. 6).

    Parameters
    ----------
    hypotheses : sequence of str, optional
        The faults the network outputs a posterior for.  Default: the faults the inputs are tied
        to (``Residuals.isolates``) that have training samples, or, when none is, every label of
        the training data except ``'none'``.  Training samples of other faults get all-zero
        targets (out-of-group faults, §6.5.1).
    inputs : 'magnitude' or 'raw'
        Residual magnitude per fault group (default) or the residual columns.
    columns : sequence of str, optional
        Residual names to use (one network per filter of a stacked bank).
    scale : 'nominal', None, float or array
        Input divisor (see the module notes).
    hidden : sequence of int, optional
        Hidden widths; default three layers of ``max(n_in, n_out)`` (the report: 5 layers of 3).
    feedback : 'tied', 'pad', 'learned' or array
        The feedback matrix ``F`` of ``x¹ = u + F y_{k−1}``.
    threshold : float
        Alarm when the largest posterior is ``≥ threshold`` (default 0.5); the isolated fault is
        the hypothesis with the largest posterior.
    update : quasi-Newton update of the deterministic phase, 'bfgs' (default) or 'dfp' (the report's;
        see the module notes for why BFGS is the default).
    max_iter : quasi-Newton iteration limit (0 skips the deterministic phase).
    rm_steps, rm_window, rm_batch, rho0, rm_exponent : Robbins–Monro phase (``rm_steps=0`` skips it):
        number of steps, window length and windows per step, ``ρ_k = rho0/(k+1)^rm_exponent``;
        ``rho0=None`` takes half the stable gradient step, ``0.5/λ_max`` of the Hessian of the
        training cost at the deterministic solution (power iteration).
    rng : Generator or seed for the initial weights and the random windows.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> rng = np.random.default_rng(0)
    >>> def run(mean):
    ...     r = np.abs(mean + 0.3 * rng.standard_normal((60, 2)))
    ...     return Residuals(np.arange(60) * 0.01, r, ("za", "zb"), ("a", "b"))
    >>> data = {"none": [run([0, 0]) for _ in range(4)], "a": [run([1, 0]) for _ in range(4)],
    ...         "b": [run([0, 1]) for _ in range(4)]}
    >>> ev = BnnEvaluator(max_iter=60, rm_steps=20, rng=1).fit(data)
    >>> str(ev.run(run([1, 0])).isolated[-1])
    'a'
    """

    def __init__(
        self,
        hypotheses: Sequence[str] | None = None,
        *,
        inputs: str = "magnitude",
        columns: Sequence[str] | None = None,
        scale="nominal",
        hidden: Sequence[int] | None = None,
        feedback="tied",
        threshold: float = 0.5,
        update: str = "bfgs",
        max_iter: int = 400,
        rm_steps: int = 200,
        rm_window: int = 50,
        rm_batch: int = 8,
        rho0: float | None = None,
        rm_exponent: float = 0.75,
        rng: np.random.Generator | int | None = 0,
    ) -> None:
        if inputs not in ("magnitude", "raw"):
            raise ModelError(f"unknown inputs mode {inputs!r}; use 'magnitude' or 'raw'")
        if not 0 < threshold < 1:
            raise ModelError(f"the posterior threshold must be in (0, 1), got {threshold}")
        if isinstance(feedback, str) and feedback not in ("tied", "pad", "learned"):
            raise ModelError(f"unknown feedback {feedback!r}; use 'tied', 'pad', 'learned' or a matrix")
        if hidden is not None and any(int(h) < 1 for h in hidden):
            raise ModelError(f"hidden widths must be positive integers, got {hidden}")
        if min(rm_window, rm_batch) < 1 or min(rm_steps, max_iter) < 0:
            raise ModelError("rm_window and rm_batch must be >= 1, max_iter and rm_steps >= 0")
        robbins_monro_steps(1.0 if rho0 is None else rho0, 1, rm_exponent)  # validates
        self._hypotheses = None if hypotheses is None else tuple(hypotheses)
        self.hypotheses: tuple[str, ...] | None = self._hypotheses
        self.inputs, self.columns, self.scale = inputs, None if columns is None else tuple(columns), scale
        self.hidden = None if hidden is None else tuple(int(h) for h in hidden)
        if update not in ("dfp", "bfgs"):
            raise ModelError(f"unknown quasi-Newton update {update!r}; use 'dfp' or 'bfgs'")
        self.feedback, self.threshold, self.update = feedback, float(threshold), update
        self.max_iter, self.rm_steps = int(max_iter), int(rm_steps)
        self.rm_window, self.rm_batch = int(rm_window), int(rm_batch)
        self.rho0, self.rm_exponent, self.rng = None if rho0 is None else float(rho0), float(rm_exponent), rng
        self.network: BnnNetwork | None = None
        self.w: np.ndarray | None = None
        self.report: TrainingReport | None = None
        self._inputs: _Inputs | None = None
        self.reset()

    # ------------------------------------------------------------------ training
    def fit(self, data, labels=None) -> BnnEvaluator:
        """Train on labelled residual sequences; returns ``self``.

        ``data`` is either a mapping ``label → Residuals or list of Residuals`` (every sample of
        those runs carries the label: ``'none'`` fault-free, a hypothesis, or another fault), or a
        sequence of Residuals with ``labels``: per run a str or one label per sample (e.g.
        ``trace.fault``, so runs with a fault onset train the fault-free part as ``'none'``).
        Labels ``'a+b'`` set both targets.  Each run is one training sequence, started from the
        reset state ``y_{−1} = 0``.
        """
        runs = _as_runs(data, labels)
        res0 = runs[0][0]
        spec = _Inputs.build(res0.names, res0.isolates, self.inputs, self.columns)
        feats = []
        for res, _ in runs:
            x = spec.raw(res.r)
            x[~res.valid] = np.nan
            feats.append(x)
        all_labels = np.concatenate([lab for _, lab in runs])
        present = {p for lab in set(all_labels) for p in str(lab).split("+")} - {NO_FAULT}
        hyps = self._hypotheses or tuple(k for k in spec.keys if k in present) or tuple(
            dict.fromkeys(p for lab in all_labels for p in str(lab).split("+") if p != NO_FAULT))
        if not hyps:
            raise DataError("the training data hold no fault samples; give runs labelled with faults")
        if set(hyps) - present:
            raise DataError(f"hypotheses {sorted(set(hyps) - present)} have no training samples")
        spec = _Inputs(spec.n_columns, spec.groups, spec.keys, spec.magnitude, self._scale(spec, feats, runs))
        n_in, n_out = len(spec.keys), len(hyps)
        F = self._feedback_matrix(spec.keys, hyps)
        widths = (n_in, *((max(n_in, n_out),) * 3 if self.hidden is None else self.hidden), n_out)
        net = BnnNetwork(widths, F, learn_feedback=isinstance(self.feedback, str) and self.feedback == "learned")
        # padded batch: padding is invalid (state held) and carries no cost
        T = max(len(res) for res, _ in runs)
        B = len(runs)
        U = np.full((B, T, n_in), np.nan)
        Z = np.zeros((B, T, n_out))
        lengths = np.array([len(res) for res, _ in runs])
        for b, ((_, lab), x) in enumerate(zip(runs, feats)):
            U[b, : len(lab)] = x / spec.scale
            Z[b, : len(lab)] = _targets(lab, hyps)
        ok = np.all(np.isfinite(U), axis=2)
        if ok.sum() < 2:
            raise DataError("fewer than 2 valid training samples")
        rng = np.random.default_rng(self.rng)
        w0 = net.init(rng, centre=expit(U[ok]).mean(axis=0))

        def J(w):
            return net.cost_grad(w, U, Z)

        j0 = J(w0)[0]
        qn = quasi_newton(J, w0, update=self.update, max_iter=self.max_iter)
        w, rho, curv = qn.x, np.zeros(0), float("nan")
        if self.rm_steps:
            rho0 = self.rho0
            if rho0 is None:  # half the stable gradient step at the deterministic solution
                curv = _max_curvature(J, w, rng)
                rho0 = 0.5 / curv
            rho = robbins_monro_steps(rho0, self.rm_steps, self.rm_exponent)
            w = self._robbins_monro(net, w, U, Z, ok, lengths, rho, rng)
        self.network, self.w, self._inputs, self.hypotheses = net, w, spec, hyps
        self.report = TrainingReport(
            float(j0), float(qn.fun), float(J(w)[0]), qn.iterations, qn.evaluations, qn.message, self.rm_steps,
            (float(rho[0]), float(rho[-1])) if rho.size else (0.0, 0.0), curv, int(ok.sum()), B,
        )
        self.reset()
        return self

    def _robbins_monro(self, net, w, U, Z, ok, lengths, rho, rng) -> np.ndarray:
        """``w ← w − ρ_k g(w)`` with ``g`` the exact gradient of the cost of ``rm_batch`` random windows
        of ``rm_window`` samples (each run from its sequence start, so the entering state is the
        network's own)."""
        B = U.shape[0]
        L = min(self.rm_window, int(lengths.max()))
        for r in rho:
            seqs = rng.integers(0, B, self.rm_batch)
            starts = rng.integers(0, np.maximum(lengths[seqs] - L, 0) + 1)
            end = int((starts + L).max())
            t = np.arange(end)
            window = (t[None, :] >= starts[:, None]) & (t[None, :] < starts[:, None] + L)
            if (window & ok[seqs, :end]).any():
                w = w - r * net.cost_grad(w, U[seqs, :end], Z[seqs, :end], cost_mask=window)[1]
        return w

    def _scale(self, spec: _Inputs, feats, runs) -> np.ndarray:
        if self.scale is None:
            return np.ones(len(spec.keys))
        if isinstance(self.scale, str):
            if self.scale != "nominal":
                raise ModelError(f"unknown scale {self.scale!r}; use 'nominal', None, a number or an array")
            s = np.ones(len(spec.keys))
            X = np.abs(np.concatenate(feats))
            lab = np.concatenate([lb for _, lb in runs])
            for j, key in enumerate(spec.keys):
                own = np.array([key in str(x).split("+") for x in lab]) & np.isfinite(X[:, j])
                if own.any():
                    s[j] = X[own, j].mean()
        else:
            s = np.asarray(self.scale, dtype=float).ravel()
            if s.size not in (1, len(spec.keys)):
                raise ModelError(f"{s.size} scale values for {len(spec.keys)} inputs {list(spec.keys)}")
            s = np.broadcast_to(s, (len(spec.keys),)).copy()
        if not np.all(np.isfinite(s) & (s > 0)):
            bad = [k for k, v in zip(spec.keys, s) if not (np.isfinite(v) and v > 0)]
            raise DataError(f"input scale of {bad} is zero or not finite; pass scale= explicitly")
        return s

    def _feedback_matrix(self, keys, hyps) -> np.ndarray:
        n_in, n_out = len(keys), len(hyps)
        if not isinstance(self.feedback, str):
            return np.asarray(self.feedback, dtype=float)
        tied = np.array([[float(k == h) for h in hyps] for k in keys])
        if self.feedback == "pad" or not tied.any():
            return np.eye(n_in, n_out)
        return tied

    # ------------------------------------------------------------------ running
    def _ready(self) -> tuple[BnnNetwork, _Inputs]:
        if self.network is None or self._inputs is None:
            raise ModelError("the network is not trained; call fit() with labelled residuals first")
        return self.network, self._inputs

    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series from the reset state; identical to stepping through it."""
        net, spec = self._ready()
        X = spec(residuals.r)
        ok = residuals.valid & np.all(np.isfinite(X), axis=1)
        Ws, ths, F = net.unpack(self.w)
        y = np.zeros((1, net.widths[-1]))
        P = np.empty((len(residuals), net.widths[-1]))
        for k in range(len(residuals)):
            if ok[k]:
                y = net._layers(Ws, ths, F, X[k : k + 1], y)[-1]
            P[k] = y[0]
        return _decisions(residuals.t, P, ok, self.hypotheses, self.threshold, self._meta())

    def reset(self) -> None:
        """Zero the feedback state ``y_{k−1}`` (start of a new run)."""
        self._y = None

    def step(self, r) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the feedback state and the output."""
        net, spec = self._ready()
        x = spec(np.asarray(r, dtype=float).ravel())
        if self._y is None:
            self._y = np.zeros((1, net.widths[-1]))
        valid = bool(np.all(np.isfinite(x)))
        if valid:
            self._y = net._layers(*net.unpack(self.w), x[None, :], self._y)[-1]
        p = self._y[0].copy()
        fired = p >= self.threshold
        fault = self.hypotheses[int(np.argmax(p))] if fired.any() else NO_FAULT
        return StepDecision(bool(fired.any()), fault, fired, valid, p)

    def _meta(self) -> dict:
        return {"evaluator": "bnn", "threshold": self.threshold, "widths": list(self.network.widths),
                "inputs": list(self._inputs.keys), "scale": self._inputs.scale.tolist()}

    def __repr__(self) -> str:
        widths = None if self.network is None else self.network.widths
        return f"BnnEvaluator(hypotheses={self.hypotheses}, widths={widths}, threshold={self.threshold})"


# ====================================================================== Gaussian ML classifier
class GaussianMlEvaluator:
    """Gaussian maximum-likelihood classifier with a shared covariance, as a single-layer perceptron (§6.2.1).

    Classes are the training labels (``'none'`` included when present).  ``weights[i] = 2 m_iᵀΛ⁻¹``
    and ``bias[i] = −m_iᵀΛ⁻¹m_i + 2 ln π_i`` give ``L_i + 2 ln π_i`` up to the common ``−xᵀΛ⁻¹x``,
    so the pairwise perceptron ``L_ij = W x + θ`` of the report is a difference of two rows
    (:meth:`pairwise`).  ``Diagnosis.probabilities`` holds the fault classes (``P(none) = 1 − Σ``).

    Parameters
    ----------
    priors : None (equal: the report's ML rule), 'empirical' (class frequencies) or a mapping.
    inputs, columns : as for :class:`BnnEvaluator` (no scaling: the rule is affine invariant).
    """

    def __init__(self, priors=None, *, inputs: str = "magnitude", columns: Sequence[str] | None = None) -> None:
        if inputs not in ("magnitude", "raw"):
            raise ModelError(f"unknown inputs mode {inputs!r}; use 'magnitude' or 'raw'")
        self.priors, self.inputs, self.columns = priors, inputs, None if columns is None else tuple(columns)
        self.classes: tuple[str, ...] = ()
        self.means: np.ndarray | None = None
        self.covariance: np.ndarray | None = None
        self.prior: np.ndarray | None = None
        self._inputs: _Inputs | None = None
        self.reset()

    @classmethod
    def from_moments(cls, means: Mapping[str, Sequence[float]], covariance, priors=None) -> GaussianMlEvaluator:
        """Classifier for known class means and shared covariance; inputs are the raw residual vector."""
        ev = cls(priors, inputs="raw")
        M = np.atleast_2d(np.array([np.asarray(m, dtype=float).ravel() for m in means.values()]))
        n = M.shape[1]
        ev._inputs = _Inputs(n, tuple((i,) for i in range(n)), tuple(f"x{i}" for i in range(n)), False, np.ones(n))
        ev._set(tuple(str(k) for k in means), M, np.asarray(covariance, dtype=float), None)
        return ev

    def fit(self, data, labels=None) -> GaussianMlEvaluator:
        """Class means and pooled within-class covariance from labelled residuals (as :meth:`BnnEvaluator.fit`)."""
        runs = _as_runs(data, labels)
        res0 = runs[0][0]
        spec = _Inputs.build(res0.names, res0.isolates, self.inputs, self.columns)
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
            raise ModelError(f"covariance must be a finite {n}x{n} matrix and the means finite")
        S = 0.5 * (S + S.T)
        ev = np.linalg.eigvalsh(S)
        if not ev[0] > 1e-12 * max(ev[-1], 0.0):
            raise DataError(f"the shared covariance is singular (eigenvalues {ev[0]:.3g} … {ev[-1]:.3g}); "
                            "drop constant or duplicate inputs")
        if self.priors is None:
            pi = np.full(len(classes), 1.0 / len(classes))
        elif isinstance(self.priors, str):
            if self.priors != "empirical" or counts is None:
                raise ModelError(f"priors={self.priors!r}: use None, a mapping, or 'empirical' with fit()")
            pi = counts / counts.sum()
        else:
            missing = [c for c in classes if c not in self.priors]
            if missing:
                raise ModelError(f"priors lack the classes {missing}")
            pi = np.array([float(self.priors[c]) for c in classes])
            if not np.all(pi > 0):
                raise ModelError(f"priors must be positive, got {pi}")
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

    def _ready(self) -> _Inputs:
        if self.means is None or self._inputs is None:
            raise ModelError("the classifier has no class model; call fit() or use from_moments()")
        return self._inputs

    def run(self, residuals: Residuals) -> Diagnosis:
        """Per-sample decisions; invalid samples hold the previous decision (identical to :meth:`step`)."""
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

    def step(self, r) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the previous decision."""
        x = self._ready()(np.asarray(r, dtype=float).ravel())
        valid = bool(np.all(np.isfinite(x)))
        if valid:
            c, P = self._classify(x[None, :])
            self._last = (np.array([c[0]]), P)
        c, P = self._last if self._last is not None else (np.array([-1]), np.zeros((1, len(self.classes))))
        d = self._diagnosis(np.zeros(1), P, c, np.array([valid]))
        return StepDecision(bool(d.alarm[0]), str(d.isolated[0]), d.fired[0], valid, d.probabilities[0])

    def __repr__(self) -> str:
        return f"GaussianMlEvaluator(classes={self.classes}, priors={None if self.prior is None else self.prior})"
