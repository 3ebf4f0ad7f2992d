"""Compiled online estimators: the Kalman filter step and the IMM cycle, one compiled call per sample.

:func:`compile_kalman` turns a :class:`fdikit.multimodel.kalman.KalmanFilter` into a :class:`CompiledKalman`
and :func:`compile_imm` an :class:`fdikit.multimodel.imm.IMMFilter` (or its stepper) into a :class:`CompiledIMM`.
Their ``step(u, y)`` computes what the reference ``step`` computes — the Kalman filter of Hallouzi 2008, §2.3.1,
Table 2.1 step 2 and (2.12) in Joseph or square-root (§2.3.2, (2.29)–(2.31)) form, and the IMM cycle of
Table 2.1 (after Li & Jilkov 2005) with log-space mode probabilities — in one compiled kernel
(:mod:`fdikit.runtime.kalman_kernels`, :mod:`fdikit.runtime.imm_kernels`, compiled on first use) and keeps the
results in preallocated arrays; ``result()`` builds the reference's step object for the last sample.

Why hand-written: no library compiles these steps (filterpy and the reference are numpy code whose per-sample
cost is call overhead on small matrices).  The compiled step follows the reference's rules exactly: a NaN/inf
measurement skips the measurement update (the sample is invalid, innovation and likelihood NaN), a NaN/inf
input raises :class:`~fdikit.errors.DataError` with the state unchanged, and the covariance-form Kalman filter
switches to the steady-state filter by the reference's criterion — after 3 consecutive valid samples whose
``max |P(k+1|k) − P(k|k−1)| ≤ 1e-14 · max |P(k+1|k)|``, the gain, ``P(k|k)``, ``S`` and ``log det S`` are cached
from the settled ``P``, and an invalid sample returns to the recursion.  Numbers equal the reference's to
rounding (products summed in another order, Cholesky instead of LU solves).

Examples
--------
>>> import numpy as np
>>> from fdikit.gaussian import LinearGaussianModel
>>> from fdikit.multimodel.kalman import KalmanFilter
>>> ck = compile_kalman(KalmanFilter(LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]]), [0.0], [[1.0]]))
>>> ck.step(np.zeros(0), np.array([1.0])).tolist(), ck.x.tolist()
([0.5], [0.45])

References
----------
Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12); §2.3.2, (2.29)–(2.31).
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.multimodel.imm import IMMFilter, IMMStep, IMMStepper
from fdikit.multimodel.kalman import KalmanFilter, KalmanStep
from fdikit.multimodel.kalman_steps import psd_sqrt
from fdikit.runtime import imm_kernels as ik
from fdikit.runtime import kalman_kernels as kk
from fdikit.runtime.buffer_linalg import compiled

__all__ = ["CompiledKalman", "CompiledIMM", "compile_kalman", "compile_imm"]


def _views(buf: np.ndarray, fields: dict) -> dict[str, np.ndarray]:
    return {name: buf[o:o + int(np.prod(shape))].reshape(shape) for name, (o, shape) in fields.items()}


class CompiledKalman:
    """A Kalman filter's online step, compiled (:meth:`KalmanFilter.step` in one call).

    Parameters
    ----------
    kf : KalmanFilter
        The filter; the compiled one starts from its current ``x̂(k|k−1)``, ``P(k|k−1)`` (and factor), with the
        settling count at zero (a fresh filter is the usual argument).  ``kf`` itself is not stepped.

    Attributes
    ----------
    reference : KalmanFilter
        The filter compiled.
    model : LinearGaussianModel
        Its model.
    form : str
        ``"covariance"`` or ``"square_root"``.

    Raises
    ------
    ParameterError
        For something other than a :class:`~fdikit.multimodel.kalman.KalmanFilter`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.kalman import KalmanFilter
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> ck = CompiledKalman(KalmanFilter(mdl, x0=[0.0], P0=[[1.0]]))
    >>> _ = ck.step(np.zeros(0), np.array([1.0]))
    >>> _ = ck.step(None, [float("nan")])          # missing measurement: prediction only
    >>> ck.valid, ck.x_filt.tolist(), round(float(ck.x[0]), 6)
    (False, [0.45], 0.405)
    """

    def __init__(self, kf: KalmanFilter) -> None:
        if not isinstance(kf, KalmanFilter):
            raise ParameterError(f"compile_kalman needs a fdikit.multimodel.kalman.KalmanFilter, got "
                                 f"{type(kf).__name__}")
        md = kf.model
        self.reference, self.model, self.form = kf, md, kf.form
        self._n, self._m, self._p = md.n, md.m, md.p
        self._buf, fields = kk.kalman_layout(md.n, md.m, md.p, 0 if kf.form == "covariance" else 1)
        f = self._f = _views(self._buf, fields)
        for name, val in (("A", md.A), ("At", md.A.T), ("Bt", md.B.T), ("C", md.C), ("Ct", md.C.T), ("Dt", md.D.T),
                          ("Q", md.Q), ("R", md.R), ("Qs", psd_sqrt(md.Q, "Q")), ("Rs", psd_sqrt(md.R, "R"))):
            f[name][...] = val
        self._initial = (np.array(kf.x, dtype=float), np.array(kf.P, dtype=float), np.array(kf.P_sqrt, dtype=float))
        self._xf = f["xf"]
        self._kernel = compiled(kk.kalman_step if kf.form == "covariance" else kk.srkf_step)
        self.reset()

    def reset(self) -> None:
        """Back to the state at compilation: ``x̂``, ``P`` (and its factor) of the filter given, no sample yet.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.kalman import KalmanFilter
        >>> ck = compile_kalman(KalmanFilter(LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]]),
        ...                                  [0.0], [[1.0]]))
        >>> _ = ck.step(np.zeros(0), np.array([1.0])); ck.reset(); ck.x.tolist(), ck.P.tolist()
        ([0.0], [[1.0]])
        """
        f, b = self._f, self._buf
        f["x"][...], f["P"][...], f["Sx"][...] = self._initial
        for name in ("xf", "Pf", "e", "S", "KT"):
            f[name][...] = np.nan
        b[[kk.H_COUNT, kk.H_STEADY, kk.H_FRESH, kk.H_LL]] = 0.0, 0.0, 0.0, np.nan
        b[kk.H_VALID] = -1.0

    def step(self, u, y) -> np.ndarray:
        """Update with ``y(k)``, predict with ``u(k)`` (the reference :meth:`KalmanFilter.step`).

        Parameters
        ----------
        u, y : numpy.ndarray of float64, or array_like
            Input ``u(k)`` (m; None when m = 0) and measurement ``y(k)`` (p; a NaN/inf entry skips the update).
            1-D float64 arrays (``np.zeros(0)`` for no input) take the compiled path as they are; anything else
            (None, lists, other dtypes, columns) is checked and converted as the reference does, at its cost.

        Returns
        -------
        numpy.ndarray
            ``x̂(k|k)`` — the filter's own buffer, overwritten by the next step (copy it to keep it).

        Raises
        ------
        DataError
            For the wrong number of values, values that are not numbers, a NaN/inf input, or an innovation
            covariance that is not positive definite (then the state is unchanged).

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.kalman import KalmanFilter
        >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
        >>> compile_kalman(KalmanFilter(mdl, [0.0], [[1.0]])).step(None, [1.0]).tolist()
        [0.5]
        """
        try:
            status = self._kernel(u, y, self._buf)
        except TypeError:  # not 1-D float64 arrays
            status = 3
        if status:
            self._slow(u, y, status)
        return self._xf

    def _slow(self, u, y, status: int) -> None:
        if status in (-1, 3):  # the reference's checks and conversion, then the kernel
            u = validate.as_vector("u", np.zeros(0) if u is None else u, self._m, error=DataError, finite=False)
            y = validate.as_vector("y", y, self._p, error=DataError, finite=False)
            status = self._kernel(np.ascontiguousarray(u, dtype=float), np.ascontiguousarray(y, dtype=float),
                                    self._buf)
        if status == 1:
            raise DataError("u has a NaN/inf entry; the time update needs every input (fill or drop the sample)")
        if status == 2:
            raise DataError("the innovation covariance C P Cᵀ + R is singular; give R positive definite")
        if status:  # pragma: no cover - the conversion above guarantees the lengths
            raise DataError(f"u must have {self._m} entries and y {self._p}")

    # ------------------------------------------------------------------ the state and the last sample
    @property
    def x(self) -> np.ndarray:
        """``x̂(k+1|k)``, the state for the next sample (a copy)."""
        return self._f["x"].copy()

    @property
    def P(self) -> np.ndarray:
        """``P(k+1|k)`` (a copy)."""
        return self._f["P"].copy()

    @property
    def P_sqrt(self) -> np.ndarray:
        """Lower-triangular factor of ``P(k+1|k)`` (propagated in the square-root form; a copy)."""
        return self._f["Sx"].copy() if self.form == "square_root" else psd_sqrt(self._f["P"], "P")

    @property
    def x_filt(self) -> np.ndarray:
        """``x̂(k|k)`` of the last sample (a copy)."""
        return self._xf.copy()

    @property
    def P_filt(self) -> np.ndarray:
        """``P(k|k)`` of the last sample (a copy)."""
        return self._f["Pf"].copy()

    @property
    def innovation(self) -> np.ndarray:
        """``e(k) = y(k) − C x̂(k|k−1) − D u(k)`` of the last sample; NaN when it was invalid (a copy)."""
        return self._f["e"].copy()

    @property
    def S(self) -> np.ndarray:
        """Innovation covariance of the last sample; NaN when it was invalid (a copy)."""
        return self._f["S"].copy()

    @property
    def gain(self) -> np.ndarray:
        """Kalman gain ``K`` (n x p) of the last valid update, the steady gain once settled (a copy).

        Covariance form only (the square-root form never forms ``K``: NaN there)."""
        return self._f["KsT" if self.steady else "KT"].T.copy()

    @property
    def log_likelihood(self) -> float:
        """``log N(e(k); 0, S)`` of the last sample; NaN when it was invalid."""
        return float(self._buf[kk.H_LL])

    @property
    def valid(self) -> bool:
        """False when the last measurement had a NaN/inf entry (or before the first sample)."""
        return bool(self._buf[kk.H_VALID] == 1.0)

    @property
    def steady(self) -> bool:
        """Whether the steady-state filter is in use (``P(k+1|k)`` has settled; covariance form only)."""
        return bool(self._buf[kk.H_STEADY])

    def result(self) -> KalmanStep:
        """The reference's :class:`~fdikit.multimodel.kalman.KalmanStep` for the last sample (copies).

        Returns
        -------
        KalmanStep

        Raises
        ------
        ParameterError
            Before the first sample (after creation or :meth:`reset`).

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.kalman import KalmanFilter
        >>> ck = compile_kalman(KalmanFilter(LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]]),
        ...                                  [0.0], [[1.0]]))
        >>> _ = ck.step(np.zeros(0), np.array([1.0]))
        >>> s = ck.result(); s.x_filt.tolist(), s.x_pred.tolist(), s.valid
        ([0.5], [0.45], True)
        """
        if self._buf[kk.H_VALID] < 0:
            raise ParameterError("no sample yet: call step(u, y) before result()")
        return KalmanStep(self.x_filt, self.P_filt, self.x, self.P, self.innovation, self.S, self.log_likelihood,
                          self.valid)


class CompiledIMM:
    """An IMM filter's online cycle, compiled (:meth:`IMMStepper.step` in one call).

    Parameters
    ----------
    imm : IMMFilter or IMMStepper
        The filter (the compiled one starts from its priors ``x0, P0, mu0``) or a stepper (it starts from the
        stepper's current state; the stepper itself is not stepped).

    Attributes
    ----------
    filter : IMMFilter
        The filter compiled.
    names : tuple of str
        Mode names, in the order of ``mu``.

    Raises
    ------
    ParameterError
        For something other than an IMMFilter or IMMStepper.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.imm import IMMFilter
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> ci = CompiledIMM(IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]]))
    >>> for _ in range(3):
    ...     mu = ci.step(np.zeros(0), np.array([2.0]))
    >>> mu.round(4).tolist(), ci.step(None, [float("nan")]) is not None, ci.valid
    ([0.0002, 0.9998], True, False)
    """

    def __init__(self, imm: IMMFilter | IMMStepper) -> None:
        if isinstance(imm, IMMStepper):
            stepper, filt = imm, imm.imm
        elif isinstance(imm, IMMFilter):
            stepper, filt = imm.online(), imm
        else:
            raise ParameterError(f"compile_imm needs a fdikit.multimodel.imm.IMMFilter or IMMStepper, got "
                                 f"{type(imm).__name__}")
        md = filt.modes
        self.filter, self.names = filt, filt.names
        M, self._m, self._p = len(md), md[0].m, md[0].p
        self._buf, fields = ik.imm_layout(M, md[0].n, self._m, self._p)
        f = self._f = _views(self._buf, fields)
        for name, get in (("A", lambda d: d.A), ("At", lambda d: d.A.T), ("Bt", lambda d: d.B.T), ("C", lambda d: d.C),
                          ("Ct", lambda d: d.C.T), ("Dt", lambda d: d.D.T), ("Q", lambda d: d.Q), ("R", lambda d: d.R)):
            f[name][...] = np.stack([get(d) for d in md])
        with np.errstate(divide="ignore"):
            f["logPi"][...] = np.log(filt.transition)
            self._buf[ik.I_FLOOR] = np.log(filt.min_probability) if filt.min_probability > 0 else -np.inf
            prior = np.log(filt.mu0)
        self._prior = (filt.x0.copy(), filt.P0.copy(), prior, prior.copy())
        self._start = tuple(np.array(a, dtype=float) for a in (stepper.x_pred, stepper.P_pred, stepper.log_mu_pred,
                                                              stepper.log_mu))
        self._mu = f["mu"]
        self._kernel = compiled(ik.imm_step)
        self._load(self._start)

    def reset(self) -> None:
        """Back to the filter's priors ``x0, P0, mu0``, no sample yet.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.imm import IMMFilter
        >>> md = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]])
        >>> ci = compile_imm(IMMFilter([md], [[1.0]], x0=[1.0]))
        >>> _ = ci.step(np.zeros(0), np.array([2.0])); ci.reset(); ci.x_pred.tolist()
        [[1.0]]
        """
        self._load(self._prior)

    def _load(self, state: tuple) -> None:
        f = self._f
        f["xp"][...], f["Pp"][...], f["lmp"][...], f["lmu"][...] = state
        f["mu"][...] = np.exp(f["lmu"])
        for name in ("xf", "Pf", "x", "P", "z", "S"):
            f[name][...] = np.nan
        self._buf[ik.I_LL], self._buf[ik.I_VALID] = np.nan, -1.0

    def step(self, u, y) -> np.ndarray:
        """One Table 2.1 cycle with ``u_k, y_k`` (the reference :meth:`IMMStepper.step`).

        Parameters
        ----------
        u, y : numpy.ndarray of float64, or array_like
            ``u_k`` (m; None when m = 0) and ``y_k`` (p; a NaN/inf entry: prediction only).  1-D float64 arrays
            (``np.zeros(0)`` for no input) take the compiled path; anything else is checked and converted as the
            reference does, at its cost.

        Returns
        -------
        numpy.ndarray
            The mode probabilities ``μ_k`` — the filter's own buffer, overwritten by the next step.

        Raises
        ------
        DataError
            For the wrong number of values, values that are not numbers or a NaN/inf input (state unchanged).

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.imm import IMMFilter
        >>> md = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]])
        >>> compile_imm(IMMFilter([md, md], np.eye(2))).step(None, [1.0]).round(12).tolist()
        [0.5, 0.5]
        """
        try:
            status = self._kernel(u, y, self._buf)
        except TypeError:  # not 1-D float64 arrays
            status = 3
        if status:
            self._slow(u, y, status)
        return self._mu

    def _slow(self, u, y, status: int) -> None:
        if status in (-1, 3):  # IMMStepper.step's checks and conversion, then the kernel
            u = validate.as_array("u", np.zeros(0) if u is None else u, error=DataError, finite=False)
            y = validate.as_array("y", y, error=DataError, finite=False)
            if u.size != self._m or y.size != self._p:
                raise DataError(f"u_k must have {self._m} entries and y_k {self._p}, got {u.size} and {y.size}")
            status = self._kernel(np.ascontiguousarray(u.reshape(self._m), dtype=float),
                                 np.ascontiguousarray(y.reshape(self._p), dtype=float), self._buf)
        if status == 1:
            raise DataError("input u_k contains NaN/inf; the IMM cannot predict without the input")
        if status == 2:
            raise DataError("an innovation covariance C P Cᵀ + R is not positive definite; give every mode's R "
                            "positive definite")

    # ------------------------------------------------------------------ the state and the last sample
    @property
    def mu(self) -> np.ndarray:
        """Mode probabilities ``μ_k`` after the last update (a copy)."""
        return self._mu.copy()

    @property
    def log_mu(self) -> np.ndarray:
        """Their logarithms (finite far below the double range of ``mu``; a copy)."""
        return self._f["lmu"].copy()

    @property
    def log_mu_pred(self) -> np.ndarray:
        """Predicted log mode probabilities ``log μ_{k+1|k}`` for the next sample (a copy)."""
        return self._f["lmp"].copy()

    @property
    def x(self) -> np.ndarray:
        """Fused estimate ``x̂_{k|k}`` (n; a copy)."""
        return self._f["x"].copy()

    @property
    def P(self) -> np.ndarray:
        """Fused covariance (n x n; a copy)."""
        return self._f["P"].copy()

    @property
    def x_modes(self) -> np.ndarray:
        """Mode-matched filtered estimates (M x n; a copy)."""
        return self._f["xf"].copy()

    @property
    def P_modes(self) -> np.ndarray:
        """Mode-matched filtered covariances (M x n x n; a copy)."""
        return self._f["Pf"].copy()

    @property
    def x_pred(self) -> np.ndarray:
        """Per-mode priors ``x̂^(j)_{k+1|k}`` for the next sample (M x n; a copy)."""
        return self._f["xp"].copy()

    @property
    def P_pred(self) -> np.ndarray:
        """Per-mode prior covariances ``P^(j)_{k+1|k}`` (M x n x n; a copy)."""
        return self._f["Pp"].copy()

    @property
    def innovations(self) -> np.ndarray:
        """Per-mode innovations ``y_k − C^(j) x̂^(j)_{k|k−1} − D^(j) u_k`` (M x p); NaN when invalid (a copy)."""
        return self._f["z"].copy()

    @property
    def S(self) -> np.ndarray:
        """Per-mode innovation covariances (M x p x p); NaN when the sample was invalid (a copy)."""
        return self._f["S"].copy()

    @property
    def log_likelihood(self) -> float:
        """``log p(y_k | Y_{k−1})`` of the last sample; NaN when it was invalid."""
        return float(self._buf[ik.I_LL])

    @property
    def valid(self) -> bool:
        """False for a NaN/inf measurement (prediction only) or before the first sample."""
        return bool(self._buf[ik.I_VALID] == 1.0)

    def result(self) -> IMMStep:
        """The reference's :class:`~fdikit.multimodel.imm.IMMStep` for the last sample (copies).

        Returns
        -------
        IMMStep

        Raises
        ------
        ParameterError
            Before the first sample (after creation or :meth:`reset`).

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.gaussian import LinearGaussianModel
        >>> from fdikit.multimodel.imm import IMMFilter
        >>> md = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]])
        >>> ci = compile_imm(IMMFilter([md, md], np.eye(2), x0=[0.0]))
        >>> _ = ci.step(np.zeros(0), np.array([1.0]))
        >>> s = ci.result(); s.mu.round(12).tolist(), s.x_modes.shape, s.valid
        ([0.5, 0.5], (2, 1), True)
        """
        if self._buf[ik.I_VALID] < 0:
            raise ParameterError("no sample yet: call step(u, y) before result()")
        return IMMStep(x=self.x, P=self.P, mu=self.mu, x_modes=self.x_modes, P_modes=self.P_modes,
                       log_likelihood=self.log_likelihood, valid=self.valid)


def compile_kalman(kf: KalmanFilter) -> CompiledKalman:
    """The compiled online step of a Kalman filter (:class:`CompiledKalman`).

    Parameters
    ----------
    kf : KalmanFilter
        The filter (covariance or square-root form).

    Returns
    -------
    CompiledKalman

    Raises
    ------
    ParameterError
        For something other than a KalmanFilter.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.kalman import KalmanFilter
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> ck = compile_kalman(KalmanFilter(mdl, [0.0], [[1.0]], form="square_root"))
    >>> ck.step(np.zeros(0), np.array([1.0])).round(6).tolist()
    [0.5]
    """
    return CompiledKalman(kf)


def compile_imm(imm: IMMFilter | IMMStepper) -> CompiledIMM:
    """The compiled online cycle of an IMM filter (:class:`CompiledIMM`).

    Parameters
    ----------
    imm : IMMFilter or IMMStepper
        The filter, or a stepper whose current state the compiled filter starts from.

    Returns
    -------
    CompiledIMM

    Raises
    ------
    ParameterError
        For something other than an IMMFilter or IMMStepper.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.gaussian import LinearGaussianModel
    >>> from fdikit.multimodel.imm import IMMFilter
    >>> m0 = LinearGaussianModel(A=[[1.0]], C=[[1.0]], Q=[[0.01]], R=[[0.1]], name="nominal")
    >>> m1 = LinearGaussianModel(A=[[1.0]], C=[[2.0]], Q=[[0.01]], R=[[0.1]], name="gain fault")
    >>> ci = compile_imm(IMMFilter([m0, m1], [[0.99, 0.01], [0.01, 0.99]], x0=[1.0], P0=[[0.01]]))
    >>> bool(ci.step(np.zeros(0), np.array([2.0]))[1] > 0.5), ci.names
    (True, ('nominal', 'gain fault'))
    """
    return CompiledIMM(imm)
