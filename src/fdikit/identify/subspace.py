"""Subspace identification (N4SID, PO-MOESP) of a discrete state-space model with its noise model.

The model is identified in innovation form (Van Overschee & De Moor 1996, Ch. 4)::

    x[k+1] = A x[k] + B u[k] + K e[k]
    y[k]   = C x[k] + D u[k] + e[k],        Cov e = R

from block Hankel matrices of past and future data (``horizon`` block rows each).  One LQ
factorisation of ``[U_f; U_p; Y_p; Y_f]`` gives

* ``method="n4sid"``: the oblique projection ``O = Y_f /_{U_f} W_p`` (``W_p = [U_p; Y_p]``),
  weights ``W_1 = W_2 = I`` (Van Overschee & De Moor 1996, Ch. 4, Theorem 12); its SVD gives the
  order and the extended observability matrix ``Γ``, the state sequence ``X = Γ⁺ O`` and
  ``[A B; C D]`` by least squares on ``[X_{k+1}; y_k] = [A B; C D] [X_k; u_k]`` (§4.3.2);
* ``method="moesp"``: the SVD of ``L_32`` (the future outputs with the future inputs projected
  out, past data as the instrument; Verhaegen 1994, PO-MOESP), ``A`` and ``C`` from the shift
  invariance of ``Γ``, then ``B`` and ``D`` by least squares on the same state sequence.

The residuals of the state regression estimate the noise covariances ``Q, S, R``; the steady
Kalman gain of those (discrete Riccati equation) is ``K`` and ``C P Cᵀ + R`` the innovation
covariance (Van Overschee & De Moor 1996, Ch. 4).  The data are scaled to unit
standard deviation per signal before the SVD (so the singular values do not depend on units).

Why not a packaged implementation: ``benchmarks/bench_identify.py`` compares ``nfoursid`` 1.0.2
(PyPI), SIPPY (``sippy_unipi`` 1.0.1, its ``N4SID``) and this module on a known 4-state,
1-input, 2-output system (docs/PERFORMANCE.md, "Subspace identification").  All are accurate:
noise-free (4000 samples, horizon 10) each recovers the eigenvalues to 2e-15 (relative); with
innovation noise (output SNR 11) the RMS eigenvalue error over 20 seeds is 0.008 for N4SID here,
``nfoursid`` and SIPPY alike (0.009 for PO-MOESP here).  They differ in what they accept and in
cost: neither peer takes several experiments or a record split by gaps (both build the Hankel
matrices of one continuous record; here each segment gives its own columns), ``nfoursid`` gives
``(Q, S, R)`` but no gain ``K``, needs pandas and matplotlib at import and takes 11–31x the time
(two runs under different load: 1.76 s against 0.16 s, 0.49 s against 16 ms), SIPPY takes 4.5–27x
(0.74 s, 0.42 s), prints to stdout and pulls in casadi and sympy.  ``harold`` 1.0.3 has no
subspace method and python-control has none.  So the method is written here with numpy/scipy
(one LQ factorisation, one SVD, least squares).

Order selection (``order=None``): the order is the index ``k`` of the largest gap
``s_k / s_{k+1}`` of the singular values (``k`` from 1 to ``min(max_order, p (horizon − 1))``).
It finds the order when the noise floor of the singular values lies clearly below the smallest
system singular value; read :attr:`IdentifiedModel.singular_values` when it does not.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import validate
from fdikit.errors import DataError, ParameterError
from fdikit.identify.data import segments
from fdikit.model import FaultModel
from fdikit.operating_point import OperatingPoint

__all__ = ["IdentifiedModel", "subspace_id"]


@dataclass(frozen=True, eq=False)
class IdentifiedModel:
    """An identified discrete model in innovation form, with what the identification saw.

    Attributes
    ----------
    model : FaultModel
        Discrete (``dt`` of the data), states ``x0 …``, the data's controls and outputs, and the
        innovation ``e`` as the noise group (``Bw = K``, ``Dw = I``, names ``<output>_innovation``),
        with the operating point (the means removed) attached.  ``kalman(model, Q=R, R=0)``
        gives back the gain ``K``.
    K : (n, p) array
        Innovation (steady Kalman predictor) gain.
    R : (p, p) array
        Innovation covariance ``Cov e``.
    singular_values : (p horizon,) array
        Singular values of the weighted projection (order selection).
    order : int
        The model order ``n``.
    order_rule : str
        How the order was chosen.
    method : str
        ``"n4sid"`` or ``"moesp"``.
    horizon : int
        Block rows of the past and future Hankel matrices.
    u_mean, y_mean : arrays
        The means removed from the controls and the outputs.
    operating_point : OperatingPoint
        The same means by signal name (``u0``, ``y0``).
    samples : int
        Samples used; ``segments`` is the number of gap-free segments.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.5]], C=[[1.0]], Bu=[[1.0]], dt=1.0)
    >>> tr = simulate(plant, t=np.arange(300.0), u=np.random.default_rng(1).standard_normal((300, 1)))
    >>> ident = subspace_id(tr, 1, detrend=False)
    >>> ident, ident.model.noise, round(float(ident.poles[0].real), 9)
    (IdentifiedModel(n4sid, n=1, p=1, m=1, dt=1, samples=300, segments=1), ('y0_innovation',), 0.5)

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (the innovation form).
    """

    model: FaultModel
    K: np.ndarray
    R: np.ndarray
    singular_values: np.ndarray
    order: int
    order_rule: str
    method: str
    horizon: int
    u_mean: np.ndarray
    y_mean: np.ndarray
    operating_point: OperatingPoint
    samples: int
    segments: int

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A``."""
        return self.model.poles()

    def __repr__(self) -> str:
        return (f"IdentifiedModel({self.method}, n={self.order}, p={self.model.p}, m={len(self.model.controls)}, "
                f"dt={self.model.dt:g}, samples={self.samples}, segments={self.segments})")


def _hankel(x: np.ndarray, start: int, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix: block row ``r`` holds ``x[start + r : start + r + cols]`` transposed."""
    return np.vstack([x[start + r:start + r + cols].T for r in range(rows)]) if x.shape[1] else np.zeros((0, cols))


def _gap_order(s: np.ndarray, limit: int) -> int:
    floor = s[0] * np.finfo(float).eps if s[0] > 0 else 1.0
    t = np.maximum(s[:limit + 1], floor)
    return int(np.argmax(np.log(t[:-1]) - np.log(t[1:]))) + 1


def subspace_id(
    data,
    order: int | None = None,
    *,
    controls: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    horizon: int | None = None,
    method: str = "n4sid",
    max_order: int | None = None,
    feedthrough: bool = True,
    detrend: bool = True,
) -> IdentifiedModel:
    """Identify ``x⁺ = A x + B u + K e``, ``y = C x + D u + e`` from one or more traces.

    Parameters
    ----------
    data : Trace or sequence of Trace
        The experiments (one sample time).  Samples with a non-finite control or output, or
        ``valid == False``, split a trace into segments; segments shorter than
        ``2 horizon + 1`` samples are dropped with an :class:`~fdikit.errors.FdiWarning`.
    order : int, optional
        Model order ``n``; None picks it at the largest singular-value gap (module docstring).
    controls, outputs : sequence of str, optional
        The signals to use (default: all of the first trace's).
    horizon : int, optional
        Block rows of the past and of the future Hankel matrix (default
        ``max(10, ⌈(order or max_order or 8) / p⌉ + 2)``); needs ``p (horizon − 1) ≥ n``.
    method : {"n4sid", "moesp"}, default "n4sid"
    max_order : int, optional
        Largest order ``order=None`` considers (default ``p (horizon − 1)``).
    feedthrough : bool, default True
        Estimate ``D``; False fixes ``D = 0``.
    detrend : bool, default True
        Remove the mean of every signal first (kept as the model's operating point).  On
        noise-free data from rest the sample means are not an equilibrium pair
        (``ȳ ≠ G(1) ū`` by the transient): the difference shows as a mode at 1 of tiny
        singular value; use ``detrend=False`` for data about a known zero operating point.

    Returns
    -------
    IdentifiedModel
        The FaultModel, ``K``, ``R``, the singular values, the order and how it was chosen, the means.

    Raises
    ------
    ParameterError
        For a bad order, horizon, method or max_order.
    DataError
        For unusable data: too few samples for the Hankel matrices, a constant control, a
        trace without the named signals (see :func:`fdikit.identify.data.segments`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.simulate import simulate
    >>> plant = FaultModel(A=[[0.9, 0.2], [-0.2, 0.9]], C=[[1.0, 0.0]], Bu=[[0.0], [1.0]], dt=0.1)
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> tr = simulate(plant, t=np.arange(500) * 0.1, u=u)
    >>> ident = subspace_id(tr, detrend=False)  # zero operating point (a removed mean is a constant mode)
    >>> ident.order, np.sort_complex(ident.poles).round(6).tolist()
    (2, [(0.9-0.2j), (0.9+0.2j)])

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (N4SID: oblique projection, Theorem 12, the state-sequence
    regression); Verhaegen 1994 (PO-MOESP).
    """
    validate.choice("method", method, ("n4sid", "moesp"))
    if order is not None:
        order = validate.integer("order", order, minimum=1)
    if max_order is not None:
        max_order = validate.integer("max_order", max_order, minimum=1)
    probe = segments(data, controls, outputs, min_length=2, detrend=False) if horizon is None else None
    p = len(probe.outputs) if probe is not None else None
    if horizon is None:
        horizon = max(10, -(-(order or max_order or 8) // p) + 2)
    horizon = validate.integer("horizon", horizon, minimum=2)
    ds = segments(data, controls, outputs, min_length=2 * horizon + 1, detrend=detrend)
    m, p, i = len(ds.controls), len(ds.outputs), horizon
    limit = p * (i - 1)
    if order is not None and order > limit:
        raise ParameterError(f"order {order} needs p (horizon - 1) >= {order}; with {p} outputs use horizon >= "
                             f"{-(-order // p) + 1}")
    if max_order is not None and max_order > limit:
        raise ParameterError(f"max_order {max_order} exceeds p (horizon - 1) = {limit}; raise the horizon")
    su = np.concatenate(ds.u).std(axis=0) if m else np.zeros(0)
    sy = np.concatenate(ds.y).std(axis=0)
    for names, sd, what in ((ds.controls, su, "control"), (ds.outputs, sy, "output")):
        flat = [nm for nm, s in zip(names, sd) if not s > 0]
        if flat:
            raise DataError(f"{what}s {flat} are constant in the data; an identification needs them to vary "
                            f"(drop them with {what}s=[...] or excite them)")
    us = [u / su for u in ds.u]
    ys = [y / sy for y in ds.y]
    cols = [len(y) - 2 * i + 1 for y in ys]
    H = np.hstack([np.vstack([_hankel(u, i, i, c), _hankel(u, 0, i, c), _hankel(y, 0, i, c), _hankel(y, i, i, c)])
                   for u, y, c in zip(us, ys, cols)])
    rows = H.shape[0]
    if H.shape[1] < 2 * rows:
        raise DataError(f"{ds.samples} samples give {H.shape[1]} Hankel columns for {rows} rows; identification "
                        f"needs at least {2 * rows} (more data or a shorter horizon)")
    L = np.linalg.qr(H.T, mode="r").T
    r1, r2 = m * i, (m + p) * i
    L21, L22 = L[r1:r1 + r2, :r1], L[r1:r1 + r2, r1:r1 + r2]
    L32 = L[r1 + r2:, r1:r1 + r2]
    L22i = np.linalg.pinv(L22, rcond=1e3 * rows * np.finfo(float).eps)
    Ob = L32 @ L22i @ np.hstack([L21, L22])
    U, s, _ = np.linalg.svd(Ob if method == "n4sid" else L32)
    if order is None:
        top = limit if max_order is None else max_order
        order = _gap_order(s, top)
        rule = (f"largest singular-value gap s_k/s_(k+1) for k in 1..{top}: k = {order} "
                f"(s_{order}/s_{order + 1} = {s[order - 1] / max(s[order], s[0] * np.finfo(float).eps):.3g})")
    else:
        rule = "given"
    n = order
    G = U[:, :n] * np.sqrt(s[:n])
    M = np.linalg.pinv(G) @ L32 @ L22i
    Xn, Xc, Uc, Yc = [], [], [], []
    for u, y, c in zip(us, ys, cols):
        X = M @ np.vstack([_hankel(u, 0, i, c), _hankel(y, 0, i, c)])
        Xn.append(X[:, 1:])
        Xc.append(X[:, :-1])
        Uc.append(u[i:i + c - 1].T)
        Yc.append(y[i:i + c - 1].T)
    Xn, Xc, Uc, Yc = (np.hstack(a) for a in (Xn, Xc, Uc, Yc))
    Ur = Uc if feedthrough else np.zeros((0, Uc.shape[1]))
    if method == "n4sid":
        Th = np.linalg.lstsq(np.vstack([Xc, Uc]).T, Xn.T, rcond=None)[0].T
        A, B = Th[:, :n], Th[:, n:]
        Th = np.linalg.lstsq(np.vstack([Xc, Ur]).T, Yc.T, rcond=None)[0].T
        C, D = Th[:, :n], Th[:, n:] if feedthrough else np.zeros((p, m))
    else:
        C = G[:p]
        A = np.linalg.lstsq(G[:-p], G[p:], rcond=None)[0]
        B = np.linalg.lstsq(Uc.T, (Xn - A @ Xc).T, rcond=None)[0].T if m else np.zeros((n, 0))
        D = np.linalg.lstsq(Ur.T, (Yc - C @ Xc).T, rcond=None)[0].T if feedthrough and m else np.zeros((p, m))
    W = Xn - A @ Xc - B @ Uc
    E = Yc - C @ Xc - D @ Uc
    N = W.shape[1]
    Qn, S, Rn = W @ W.T / N, W @ E.T / N, E @ E.T / N
    K, Re = _innovation_gain(A, C, (Qn + Qn.T) / 2, S, (Rn + Rn.T) / 2)
    B, C, D = B / su, sy[:, None] * C, sy[:, None] * D / su
    K, Re = K / sy, sy[:, None] * Re * sy
    Re = (Re + Re.T) / 2
    model = FaultModel(A=A, Bu=B, C=C, Du=D, Bw=K, Dw=np.eye(p), states=[f"x{k}" for k in range(n)],
                       outputs=ds.outputs, controls=ds.controls, noise=[f"{y}_innovation" for y in ds.outputs],
                       dt=ds.dt).with_operating_point(u0=ds.u_mean, y0=ds.y_mean)
    return IdentifiedModel(model, K, Re, s, n, rule, method, i, ds.u_mean, ds.y_mean, model.operating_point,
                           ds.samples, len(ds.y))


def _innovation_gain(A, C, Q, S, R) -> tuple[np.ndarray, np.ndarray]:
    """Steady Kalman predictor gain and innovation covariance of the noise covariances ``Q, S, R``."""
    try:
        P = scipy.linalg.solve_discrete_are(A.T, C.T, Q, R, s=S)
        Re = C @ P @ C.T + R
        return np.linalg.solve(Re, (A @ P @ C.T + S).T).T, Re
    except (np.linalg.LinAlgError, ValueError):
        # The residuals are (nearly) of innovation form already: Q = K R Kᵀ, S = K R.
        return np.linalg.lstsq(R, S.T, rcond=None)[0].T, R
