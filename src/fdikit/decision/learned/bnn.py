"""Bayesian neural network residual processor (Douglas et al. 1996, Ch. 6); the network is in
:mod:`fdikit.decision.learned.network`, the training-data helpers in :mod:`fdikit.decision.learned.labelled_runs`.

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

**Inputs** (Douglas et al. 1996, §5.1.1, §6.4).  ``inputs='magnitude'``: one input per fault group, ``‖z_f‖₂`` over
the residuals tied to fault ``f`` (``Residuals.isolates``; untied residuals form a group each),
divided by a scale (``'nominal'``: the mean magnitude over the training samples of fault ``f``, so
the nominal training fault gives ≈ 1, §5.1.1; inputs of faults without training data keep scale 1).
``inputs='raw'``: one input per residual column.  One network per filter, as in §6.4: pass the
filter's residual names as ``columns`` when the residuals are a stacked bank.

**Training (§6.3).**  First the deterministic cost ``J(w) = (1/N) Σ_k (z_k − y_k)ᵀ(z_k − y_k)`` over
all training sequences, minimised by a quasi-Newton method written here (:func:`quasi_newton`:
rank-2 update of the inverse Hessian, strong-Wolfe line search, the report's stop test "the change
of the Hessian estimate is small").  Gradients are exact back-propagation through time over the
whole unrolled recurrence (no teacher forcing: the network sees its own ``y_{k−1}``, the one-step delayed
output feedback of (6.1), §6.1). The report's update is DFP (``update='dfp'``); the default is its
Broyden-family twin BFGS, which has every property §6.3.1 relies on (rank 2, positive definite, ``n``-step
termination on a quadratic with exact searches, where the two give identical iterates) but corrects a poor
Hessian estimate under inexact line searches, where DFP stalls. Measured on the 3-fault toy problem of the
tests (6000 samples, 400 iterations, two seeds): BFGS J = 0.054 with 434–448 cost evaluations; DFP J = 0.054
with 2735–2740 evaluations (``c2 = 0.1``), and J = 0.17–0.25 with a loose search (``c2 = 0.9``).

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

The Gaussian ML classifier of §6.2.1 is :mod:`fdikit.decision.learned.gaussian_ml`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import expit

from fdikit.decision.common import checked_residuals, step_vector
from fdikit.decision.learned.labelled_runs import LabelledInputs, as_runs, one_hot_targets, posterior_decisions
from fdikit.decision.learned.network import BnnNetwork
from fdikit.decision.learned.quasi_newton import quasi_newton, robbins_monro_steps
from fdikit.diagnosis import Diagnosis, StepDecision
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = [
    "BnnEvaluator",
    "TrainingReport",
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


@dataclass(frozen=True)
class TrainingReport:
    """Training record: ``J`` on the whole training set at the start, after the quasi-Newton phase
    and at the end; quasi-Newton iterations, cost evaluations and stop reason; Robbins–Monro steps,
    first and last gain, and the largest Hessian eigenvalue used for the default ``ρ_0`` (NaN when
    ``rho0`` was given).

    Attributes
    ----------
    cost_initial : float
        ``J`` at the initial weights.
    cost_deterministic : float
        ``J`` after the quasi-Newton phase.
    cost_final : float
        ``J`` after the Robbins–Monro phase (the trained network).
    iterations : int
        Quasi-Newton iterations.
    evaluations : int
        Cost-and-gradient evaluations of the quasi-Newton phase.
    message : str
        Why the quasi-Newton phase stopped.
    rm_steps : int
        Robbins–Monro steps (0: phase skipped).
    rho : (float, float)
        First and last Robbins–Monro gain (``(0.0, 0.0)`` when skipped).
    curvature : float
        Largest Hessian eigenvalue estimate behind the default ``ρ_0 = 0.5/λ_max`` (NaN when ``rho0`` was
        given or the phase was skipped).
    samples : int
        Valid training samples.
    sequences : int
        Training sequences (runs).

    References
    ----------
    Douglas et al. 1996, §6.1, (6.1) (the network with output feedback), §6.2.2 (outputs as posterior
    probabilities, one-hot targets), §6.3.1–6.3.2 (DFP and Robbins–Monro training), §6.4 (one network per
    filter on the residual magnitudes) and §6.5 (step and ramp faults).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.learned.bnn import BnnEvaluator
    >>> rng = np.random.default_rng(0)
    >>> def run(mean):
    ...     r = np.abs(mean + 0.3 * rng.standard_normal((20, 2)))
    ...     return Residuals(np.arange(20) * 0.01, r, ("za", "zb"), ("a", "b"))
    >>> data = {"none": [run([0, 0])], "a": [run([1, 0])], "b": [run([0, 1])]}
    >>> rep = BnnEvaluator(hidden=(2,), max_iter=10, rm_steps=5, rng=1).fit(data).report
    >>> rep.samples, rep.sequences, rep.rm_steps, rep.cost_deterministic < rep.cost_initial
    (60, 3, 5, True)
    """

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
    update : {'bfgs', 'dfp'}
        Quasi-Newton update of the deterministic phase, 'bfgs' (default) or 'dfp' (the report's;
        see the module notes for why BFGS is the default).
    max_iter : int
        Quasi-Newton iteration limit (0 skips the deterministic phase).
    rm_steps, rm_window, rm_batch, rho0, rm_exponent : int, int, int, float or None, float
        Robbins–Monro phase (``rm_steps=0`` skips it):
        number of steps, window length and windows per step, ``ρ_k = rho0/(k+1)^rm_exponent``;
        ``rho0=None`` takes half the stable gradient step, ``0.5/λ_max`` of the Hessian of the
        training cost at the deterministic solution (power iteration).
    rng : numpy.random.Generator or int
        Generator or seed for the initial weights and the random windows.

    References
    ----------
    Douglas et al. 1996, §6.1, (6.1) (the network with output feedback), §6.2.2 (outputs as posterior
    probabilities, one-hot targets), §6.3.1–6.3.2 (DFP and Robbins–Monro training), §6.4 (one network per
    filter on the residual magnitudes) and §6.5 (step and ramp faults).

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
            raise ParameterError(f"unknown inputs mode {inputs!r}; use 'magnitude' or 'raw'")
        if not 0 < threshold < 1:
            raise ParameterError(f"the posterior threshold must be in (0, 1), got {threshold}")
        if isinstance(feedback, str) and feedback not in ("tied", "pad", "learned"):
            raise ParameterError(f"unknown feedback {feedback!r}; use 'tied', 'pad', 'learned' or a matrix")
        if hidden is not None and any(int(h) < 1 for h in hidden):
            raise ParameterError(f"hidden widths must be positive integers, got {hidden}")
        if min(rm_window, rm_batch) < 1 or min(rm_steps, max_iter) < 0:
            raise ParameterError("rm_window and rm_batch must be >= 1, max_iter and rm_steps >= 0")
        robbins_monro_steps(1.0 if rho0 is None else rho0, 1, rm_exponent)  # validates
        self._hypotheses = None if hypotheses is None else tuple(hypotheses)
        self.hypotheses: tuple[str, ...] | None = self._hypotheses
        self.inputs, self.columns, self.scale = inputs, None if columns is None else tuple(columns), scale
        self.hidden = None if hidden is None else tuple(int(h) for h in hidden)
        if update not in ("dfp", "bfgs"):
            raise ParameterError(f"unknown quasi-Newton update {update!r}; use 'dfp' or 'bfgs'")
        self.feedback, self.threshold, self.update = feedback, float(threshold), update
        self.max_iter, self.rm_steps = int(max_iter), int(rm_steps)
        self.rm_window, self.rm_batch = int(rm_window), int(rm_batch)
        self.rho0, self.rm_exponent, self.rng = None if rho0 is None else float(rho0), float(rm_exponent), rng
        self.network: BnnNetwork | None = None
        self.w: np.ndarray | None = None
        self.report: TrainingReport | None = None
        self._inputs: LabelledInputs | None = None
        self.names: tuple[str, ...] | None = None
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
        runs = as_runs(data, labels)
        res0 = runs[0][0]
        spec = LabelledInputs.build(res0.names, res0.isolates, self.inputs, self.columns)
        self.names = res0.names
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
        spec = LabelledInputs(spec.n_columns, spec.groups, spec.keys, spec.magnitude, self._scale(spec, feats, runs))
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
            Z[b, : len(lab)] = one_hot_targets(lab, hyps)
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

    def _scale(self, spec: LabelledInputs, feats, runs) -> np.ndarray:
        if self.scale is None:
            return np.ones(len(spec.keys))
        if isinstance(self.scale, str):
            if self.scale != "nominal":
                raise ParameterError(f"unknown scale {self.scale!r}; use 'nominal', None, a number or an array")
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
                raise ParameterError(f"{s.size} scale values for {len(spec.keys)} inputs {list(spec.keys)}")
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
    def _ready(self) -> tuple[BnnNetwork, LabelledInputs]:
        if self.network is None or self._inputs is None:
            raise ParameterError("the network is not trained; call fit() with labelled residuals first")
        return self.network, self._inputs

    def run(self, residuals: Residuals) -> Diagnosis:
        """Decisions for a whole residual series from the reset state; identical to stepping through it."""
        residuals = checked_residuals(residuals, self.names, "the BNN")
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
        return posterior_decisions(residuals.t, P, ok, self.hypotheses, self.threshold, self._meta())

    def reset(self) -> None:
        """Zero the feedback state ``y_{k−1}`` (start of a new run)."""
        self._y = None

    def step(self, r, *, valid: bool = True, names=None) -> StepDecision:
        """Decision for one residual sample; a NaN/inf sample holds the feedback state and the output.

        ``valid=False`` (e.g. ``valid=stepper.last_valid`` for a recovering sample after a gap) is
        treated like a NaN sample: the decision (and any feedback state) holds.  ``names`` (optional)
        are checked against the residual names of the fit (:class:`~fdikit.errors.DataError` on a difference).
        """
        net, spec = self._ready()
        x = spec(step_vector(r, self.names, names, "the BNN"))
        if self._y is None:
            self._y = np.zeros((1, net.widths[-1]))
        valid = bool(valid) and bool(np.all(np.isfinite(x)))
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
