"""Closed-loop subspace predictive control: the recursive VARX predictor inside the SPC quadratic program, §6.3.

Each control step (Hallouzi 2008, §6.3, Fig. 6.14's 10 Hz block):

1. the newest pair ``(u_{t−1}, y_{t−1})`` enters the recursive RQ factor (6.17) with forgetting λ
   (:class:`fdikit.spc.givens.RecursiveVarx`) — unless the predictor is frozen;
2. ``Γ_r, Λ_r`` are formed from ``Ξ̂_0`` (6.13)–(6.16) (:meth:`fdikit.spc.varx.VarxPredictor.multistep`);
3. the QP (6.21)–(6.28) is built with ``w_p = [u_{t−p}; y_{t−p}; …; u_{t−1}; y_{t−1}]`` and
   ``S_w w_p = u_{t−1}`` (:func:`fdikit.spc.law.spc_problem`) and solved (:class:`fdikit.spc.law.QpSolver`);
4. the first block ``u_t`` is applied.

The one-sample computation delay of §6.3.1 is built in: the decision ``u_t`` uses data up to ``t − 1``, so a
10 Hz block that takes up to one period to compute still applies its result on time.

Choices the text leaves open, made here: ``full=True`` in the multi-step matrices, so ``N_p = f``
predictions ``ŷ_{t+1} … ŷ_{t+f}`` (the printed (6.13) gives ``f − 1``; this needs ``f ≤ p``); signals are
deviations from a trim the caller subtracts (the thesis's SPC works on the aircraft's absolute signals,
which only shifts ``Ξ̂_0``'s affine part — with deviations no constant term is needed); a QP that hits the
iteration cap still applies its last iterate, clipped to the input limits, and the step is flagged.

References
----------
Hallouzi 2008, §6.3, (6.3)–(6.28); §6.4 (re-initialisation on a configuration switch); §6.6.
Dong et al. 2008.  Chiuso 2007.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["ClosedLoopSPC"]


@dataclass(frozen=True)
class _Record:
    status: str
    iterations: int
    seconds: float


class ClosedLoopSPC:
    """The closed-loop SPC of Hallouzi 2008 Ch. 6: a recursively updated VARX predictor and a constrained QP.

    Parameters
    ----------
    p : int
        Past horizon of the VARX predictor (thesis: 20).
    f : int
        Prediction horizon ``N_p = f ≤ p`` (thesis: 20).
    control_horizon : int
        ``N_c`` free moves (thesis: 5).
    weights : SpcWeights
        Output, input and rate weights (:class:`fdikit.spc.law.SpcWeights`).
    limits : SpcLimits, optional
        Input, rate and output limits.
    forgetting : float, default 0.995
        λ of the recursive update (thesis: 0.995).
    adapt : bool, default True
        False freezes the predictor after :meth:`initialize` (a fixed-model predictive controller).
    solver : QpSolver, optional
        Default a new :class:`fdikit.spc.law.QpSolver`.

    Examples
    --------
    >>> from fdikit.spc.law import SpcWeights
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((200, 1)); y = np.zeros((200, 1))
    >>> e = 0.01 * rng.standard_normal((200, 1))  # innovations: noise-free ARX data are collinear
    >>> for k in range(1, 200): y[k] = 0.8 * y[k - 1] + 0.5 * u[k - 1] + e[k]
    >>> spc = ClosedLoopSPC(10, 10, 3, SpcWeights(1.0, 0.0, 0.01))
    >>> spc.initialize(u, y)
    >>> uk = spc.step(u[-1], y[-1], reference=[1.0])
    >>> uk.shape
    (1,)

    References
    ----------
    Hallouzi 2008, §6.3.1–6.3.2, (6.13)–(6.28); App. C.
    """

    def __init__(self, p: int, f: int, control_horizon: int, weights, limits=None, *, forgetting: float = 0.995,
                 adapt: bool = True, solver=None) -> None:
        from fdikit.spc.law import QpSolver, SpcLimits

        self.p = validate.integer("p", p, minimum=1)
        self.f = validate.integer("f", f, minimum=1)
        if self.f > self.p:
            raise ParameterError(f"f = {self.f} exceeds p = {self.p}; the full multi-step predictor "
                                          f"needs f ≤ p (Hallouzi 2008, (6.13)).")
        self.control_horizon = validate.integer("control_horizon", control_horizon, minimum=1)
        if self.control_horizon > self.f:
            raise ParameterError(f"control_horizon = {self.control_horizon} exceeds f = {self.f}.")
        self.weights = weights
        self.limits = limits if limits is not None else SpcLimits()
        self.forgetting = forgetting
        self.adapt = bool(adapt)
        self.solver = solver if solver is not None else QpSolver()
        self._rec = self._pred = None
        self._u = self._y = None
        self.history: list[_Record] = []

    @property
    def predictor(self):
        """The current :class:`fdikit.spc.varx.VarxPredictor`.

        Raises
        ------
        DataError
            Before :meth:`initialize`.
        """
        if self._rec is None:
            raise DataError("call initialize(u, y) first.")
        return self._pred

    def initialize(self, u, y, *, past=None) -> None:
        """Batch-initialise the predictor (the thesis's ``j = 1000`` columns, §6.5) and the past window.

        Also the re-initialisation on a configuration switch (§6.4): pass data of the new input
        configuration (its number of inputs may differ; the QP solver sets itself up anew for the new size).

        Parameters
        ----------
        u : array_like, shape (N, m)
        y : array_like, shape (N, l)
        past : tuple of array_like, optional
            ``(u, y)`` of the plant the controller is about to run on, at least ``p + 1`` rows each
            (the last ``p + 1`` are kept): the window the first steps start from. Default: the end of
            the initialisation data — right only when they *are* the plant's recent past. When the data
            come from a model (the thesis's open-loop simulation), pass the plant's own recent samples
            (at a trim, repeated trim values): the first update would otherwise pair the model's window
            with the plant's output, a large false innovation that can wreck the ill-conditioned fit.

        Raises
        ------
        DataError
            Too few samples (``N ≥ p + p·(m+l)``), mismatched lengths, or a ``past`` of the wrong shape.
        """
        from fdikit.spc.givens import RecursiveVarx

        u = np.asarray(u, dtype=float)
        y = np.asarray(y, dtype=float)
        if u.ndim != 2 or y.ndim != 2 or u.shape[0] != y.shape[0]:
            raise DataError(f"u and y must be (N, m) and (N, l) with one row per sample; got {u.shape}, {y.shape}.")
        rec = RecursiveVarx(self.p, u.shape[1], y.shape[1], forgetting=self.forgetting)
        rec.initialize(u, y)
        self._rec = rec
        self._pred = rec.predictor
        if past is not None:
            u, y = (np.asarray(a, dtype=float) for a in past)
            if (u.ndim != 2 or y.ndim != 2 or u.shape[0] != y.shape[0] or u.shape[0] < self.p + 1
                    or u.shape[1] != rec.m or y.shape[1] != rec.l):
                raise DataError(f"past must be (u, y) with at least p + 1 = {self.p + 1} rows of {rec.m} inputs "
                                f"and {rec.l} outputs; got {u.shape}, {y.shape}.")
        self._u = deque(u[-(self.p + 1):], maxlen=self.p + 1)
        self._y = deque(y[-(self.p + 1):], maxlen=self.p + 1)

    @property
    def factor(self):
        """The recursive RQ factor (:class:`fdikit.spc.givens.RecursiveVarx`: ``R11``, ``R21``, ``samples``).

        Raises
        ------
        DataError
            Before :meth:`initialize`.
        """
        if self._rec is None:
            raise DataError("call initialize(u, y) first.")
        return self._rec

    @property
    def m(self) -> int:
        """Number of inputs of the current configuration."""
        return self.predictor.m

    def step(self, u_prev, y_prev, reference) -> np.ndarray:
        """One control step: take ``(u_{t−1}, y_{t−1})``, return ``u_t``.

        Parameters
        ----------
        u_prev : array_like, shape (m,)
            The input applied at ``t − 1`` (after saturation: what the plant got).
        y_prev : array_like, shape (l,)
            The output measured at ``t − 1``.
        reference : array_like, shape (l,) or (f·l,)
            ``r`` held over the horizon, or the reference trajectory ``r_{t+1} … r_{t+f}``.

        Returns
        -------
        ndarray, shape (m,)

        Raises
        ------
        DataError
            Before :meth:`initialize`, or a non-finite sample (skip it: hold the last input instead).
        DesignError
            The QP is infeasible.
        """
        from fdikit.spc.law import spc_problem

        if self._rec is None:
            raise DataError("call initialize(u, y) before step().")
        u_prev = validate.as_vector("u_prev", u_prev, size=self._rec.m, error=DataError)
        y_prev = validate.as_vector("y_prev", y_prev, size=self._rec.l, error=DataError)
        # The window ending at t − 2 (the last predictor's past(): only p, m, l are used).
        w_old = self._pred.past(np.asarray(self._u), np.asarray(self._y))
        self._u.append(u_prev)
        self._y.append(y_prev)
        if self.adapt:
            self._rec.update(w_old, y_prev)
            self._pred = self._rec.predictor              # one back substitution per step
        pred = self._pred
        gamma, lam = pred.multistep(self.f)
        w_p = pred.past(np.asarray(self._u), np.asarray(self._y))
        prob = spc_problem(gamma, lam, w_p, reference, u_prev, self.weights, self.limits, self.control_horizon)
        sol = self.solver.solve(prob)
        self.history.append(_Record(sol.status, sol.iterations, sol.seconds))
        u_t = sol.u[: pred.m]
        lo, hi = self.limits.vectors(pred.l, pred.m)[:2]
        return np.clip(u_t, lo, hi)
