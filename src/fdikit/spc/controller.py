"""Adaptive open-loop subspace predictive controller (SPC): Hallouzi 2008, §5.2 and §5.3.

At every sample ``t`` the controller receives the applied input ``u_t`` and the measured output ``y_t``,
appends them to its history, rebuilds the open-loop subspace predictor ``ŷ_f = L_p v_p + L_f u_f``
(5.13)–(5.16) on a receding window of the last ``window`` Hankel columns, forms the SPC quadratic
program (5.17)–(5.37) with ``u_last = u_t`` (Ch. 5 convention), optionally adds the persistency-of-
excitation term (5.41)–(5.44) built from the ``N_PE`` least-excited directions of ``Θ = [R_21 R_22]``
(5.38)–(5.40), solves it with :class:`fdikit.spc.law.QpSolver`, and returns the first block of the
optimal input sequence: ``u_{t+1}`` (receding horizon).

Start-up: until ``2M + window − 1`` samples are stored (the predictor needs ``window ≥ 2M(l + m)``
Hankel columns for a square RQ factor) the controller returns the start-up input given by
``startup`` (an ``(m,)`` constant, an ``(N, m)`` sequence indexed by the sample count — e.g. a dither
that makes the first window persistently exciting — or a callable ``k -> (m,)``); default zeros.

Fixed-model baseline: ``predictor=`` a fitted :class:`~fdikit.spc.predictor.SubspacePredictor` freezes
the model (no re-identification, no excitation); with ``frozen=True`` the first predictor that can be
fitted is kept for the rest of the run. Either turns the class into a fixed-model MPC with the same
cost, constraints and solver, which is the comparison of Hallouzi 2008, §5.4.

The code is hand-written on top of :mod:`fdikit.spc.predictor`, :mod:`fdikit.spc.excitation` and
:mod:`fdikit.spc.law` because no library implements data-driven SPC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["SubspacePredictiveController"]


@dataclass(frozen=True)
class _Step:
    t: int
    mode: str
    rcond: float
    status: str
    iterations: int


class SubspacePredictiveController:
    """Adaptive SPC of Hallouzi 2008, Ch. 5: re-identify, solve the QP, apply the first move.

    Parameters
    ----------
    horizon : int
        ``M = N_p``, the past/future horizon of the predictor and the prediction horizon.
    control_horizon : int
        ``N_c`` (1 … M), the number of free input moves (move blocking (5.19)).
    weights : SpcWeights
        Output, input and rate weights (:class:`fdikit.spc.law.SpcWeights`).
    limits : SpcLimits, optional
        Input, rate and output limits (:class:`fdikit.spc.law.SpcLimits`); default unbounded.
    window : int, default 500
        ``j``, receding-window length in Hankel columns (≥ ``2M(l + m)``).
    excitation : dict, optional
        Persistency-of-excitation term: keys ``rho`` (level ρ), ``tau`` (weight τ), ``count``
        (``N_PE``, default 2) and ``mode`` (``"full"`` or ``"truncate"``, default ``"full"``).
    solver : QpSolver, optional
        The QP solver (default a new :class:`fdikit.spc.law.QpSolver`).
    startup : array_like or callable, optional
        Input returned before the predictor can be fitted (see the module notes); default zeros.
    predictor : SubspacePredictor, optional
        A fixed predictor (fixed-model MPC); disables re-identification and excitation.
    frozen : bool, default False
        Keep the first fitted predictor for the rest of the run.

    Attributes
    ----------
    history : list
        Per-step diagnostics (``t``, ``mode`` = "startup"/"spc", ``rcond`` of ``Θ``, QP ``status``,
        ``iterations``); also available as arrays from :meth:`diagnostics`.

    Raises
    ------
    ParameterError
        Bad horizons, window or excitation settings.

    References
    ----------
    Hallouzi 2008, §5.2, (5.13)–(5.37); §5.3, (5.38)–(5.44).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.spc.law import SpcWeights
    >>> ctl = SubspacePredictiveController(2, 1, SpcWeights([1.0], [0.0], [0.1]), window=8)
    >>> ctl.step([0.0], [0.0], [1.0]).shape
    (1,)
    """

    def __init__(self, horizon: int, control_horizon: int, weights, limits=None, *, window: int = 500,
                 excitation=None, solver=None, startup=None, predictor=None, frozen: bool = False):
        self.horizon = validate.integer("horizon", horizon, minimum=1)
        self.control_horizon = validate.integer("control_horizon", control_horizon, minimum=1)
        if self.control_horizon > self.horizon:
            raise ParameterError(f"control_horizon {control_horizon} exceeds horizon {horizon}: "
                                 "choose N_c ≤ M")
        self.window = validate.integer("window", window, minimum=1)
        self.weights = weights
        self.limits = limits
        if excitation is not None:
            unknown = set(excitation) - {"rho", "tau", "count", "mode"}
            if unknown or "rho" not in excitation or "tau" not in excitation:
                raise ParameterError("excitation must be a dict with keys 'rho', 'tau' and optionally "
                                     f"'count', 'mode'; got {sorted(excitation)}")
            excitation = {"count": 2, "mode": "full", **excitation}
            validate.non_negative("excitation rho", excitation["rho"])
            validate.non_negative("excitation tau", excitation["tau"])
            validate.integer("excitation count", excitation["count"], minimum=1)
        self.excitation = excitation
        if solver is None:
            from fdikit.spc.law import QpSolver
            solver = QpSolver()
        self.solver = solver
        self.startup = startup
        self.predictor = predictor
        self.fixed = predictor is not None
        self._given = predictor is not None
        self.frozen = bool(frozen)
        self._u: list[np.ndarray] = []
        self._y: list[np.ndarray] = []
        self._previous = None
        self.history: list[_Step] = []

    # ------------------------------------------------------------------ helpers
    def _startup(self, k: int, m: int) -> np.ndarray:
        s = self.startup
        if s is None:
            return np.zeros(m)
        if callable(s):
            return np.asarray(s(k), dtype=float).reshape(m)
        a = np.asarray(s, dtype=float)
        if a.ndim == 2:
            return a[min(k, a.shape[0] - 1)].reshape(m)
        return a.reshape(m)

    @property
    def samples_needed(self) -> int:
        """Stored samples needed before the first QP: ``2M + window − 1`` (``M`` with a fixed predictor)."""
        return self.horizon if self._given else 2 * self.horizon + self.window - 1

    def diagnostics(self) -> dict:
        """Per-step diagnostics as arrays: ``t``, ``spc`` (bool), ``rcond``, ``status``, ``iterations``.

        Returns
        -------
        dict

        Examples
        --------
        >>> from fdikit.spc.law import SpcWeights
        >>> ctl = SubspacePredictiveController(2, 1, SpcWeights([1.0], [0.0], [0.1]), window=8)
        >>> _ = ctl.step([0.0], [0.0], [1.0]); ctl.diagnostics()["spc"].tolist()
        [False]
        """
        return {"t": np.array([h.t for h in self.history], dtype=int),
                "spc": np.array([h.mode == "spc" for h in self.history], dtype=bool),
                "rcond": np.array([h.rcond for h in self.history], dtype=float),
                "status": [h.status for h in self.history],
                "iterations": np.array([h.iterations for h in self.history], dtype=int)}

    # ------------------------------------------------------------------ step
    def step(self, u_t, y_t, reference) -> np.ndarray:
        """Store ``(u_t, y_t)`` and return the next input ``u_{t+1}``.

        Parameters
        ----------
        u_t : array_like, shape (m,)
            Input applied at sample ``t``.
        y_t : array_like, shape (l,)
            Output measured at sample ``t``.
        reference : array_like, shape (l,) or (M·l,)
            Reference held over the horizon, or stacked ``r_{t+1} … r_{t+M}``.

        Returns
        -------
        ndarray, shape (m,)
            ``u_{t+1}``: the start-up input until enough data are stored, then the first block of the
            QP solution.

        Raises
        ------
        DataError
            ``u_t`` / ``y_t`` change size between calls or are not finite.
        DesignError
            The QP is infeasible (from :class:`fdikit.spc.law.QpSolver`).

        Examples
        --------
        >>> from fdikit.spc.law import SpcWeights
        >>> ctl = SubspacePredictiveController(2, 1, SpcWeights([1.0], [0.0], [0.1]), window=8)
        >>> ctl.step([0.0], [0.0], [1.0]).tolist()
        [0.0]
        """
        u = np.atleast_1d(np.asarray(u_t, dtype=float)).ravel()
        y = np.atleast_1d(np.asarray(y_t, dtype=float)).ravel()
        if self._u and (u.size != self._u[0].size or y.size != self._y[0].size):
            raise DataError(f"u_t has {u.size} and y_t {y.size} entries but earlier steps had "
                            f"{self._u[0].size} and {self._y[0].size}: pass the same channels every step")
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
            raise DataError("u_t and y_t must be finite: replace missing samples before calling step()")
        self._u.append(u)
        self._y.append(y)
        keep = self.horizon if self.fixed else self.samples_needed
        if len(self._u) > keep:
            del self._u[:-keep]
            del self._y[:-keep]
        t = len(self.history)
        m = u.size
        if len(self._u) < (self.horizon if self.fixed else self.samples_needed):
            self.history.append(_Step(t, "startup", float("nan"), "startup", 0))
            return self._startup(t + 1, m)
        from fdikit.spc.law import move_blocking, spc_problem
        U, Y = np.array(self._u), np.array(self._y)
        if not self.fixed:
            from fdikit.spc.predictor import subspace_predictor
            self.predictor = subspace_predictor(U, Y, self.horizon, columns=self.window)
            if self.frozen:
                self.fixed = True
        pred = self.predictor
        theta = pred.theta
        sv = np.linalg.svd(theta, compute_uv=False)
        rcond = float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0
        past = pred.past(U, Y)
        problem = spc_problem(pred.Lp, pred.Lf, past, reference, u, self.weights, self.limits,
                              self.control_horizon)
        if self.excitation is not None and not self.fixed:
            from fdikit.spc.excitation import excitation_cost, least_excited
            E = move_blocking(self.horizon, self.control_horizon, m)
            le = least_excited(theta, self.excitation["count"])
            H, c = excitation_cost(problem.H, problem.c, le.left, self.excitation["rho"],
                                   self.excitation["tau"], E, mode=self.excitation["mode"],
                                   previous=self._previous)
            problem = type(problem)(H, c, problem.A, problem.b)
        sol = self.solver.solve(problem)
        self._previous = np.asarray(sol.u, dtype=float)
        self.history.append(_Step(t, "spc", rcond, str(sol.status), int(sol.iterations)))
        return self._previous[:m].copy()
