"""The open-loop subspace predictor ``ŷ_f = L_p v_p + L_f u_f`` of Hallouzi 2008, §5.2.1.

From input–output data the past and future block-Hankel matrices ``V_p = [Y_p; U_p]``, ``U_f`` and
``Y_f`` ((5.5), ``M`` block rows, ``j`` columns) are stacked and factored by an RQ decomposition (5.14);
the predictor matrices solve the least-squares problem (5.13) as ``[L_p L_f] = [R_31 R_32] [R_11 0; R_21
R_22]^{-1}`` (5.15). For an LTI system (5.1)–(5.2) with noise-free, persistently exciting data ``L_f`` is
the block-Toeplitz matrix of Markov parameters ``D, CB, CAB, …`` (5.8), (5.12).

The RQ factor is computed as the QR factor of the transpose (``scipy.linalg.qr``). With noise-free data
of an order-``n`` system and ``M·l > n``, ``V_p`` has only ``n + M·m`` independent rows, so the triangle in
(5.15) is singular: (5.15) is therefore always solved in the minimum-norm least-squares sense
(``scipy.linalg.lstsq`` with the cutoff ``max(shape)·eps``; the plain inverse when nonsingular), which
leaves ``L_f`` (whose columns are not involved in the dependency) unique and the prediction of any
trajectory of the same system exact. The code is written
here because no Python library builds SPC predictors (python-control and SIPPY identify state-space
models, not the ``L_p``/``L_f`` pair with the RQ blocks the excitation step needs).

References
----------
Hallouzi 2008, §5.2.1, (5.1)–(5.16); Van Overschee & De Moor 1996 (the RQ solution of (5.13)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError
from fdikit.spc.hankel import block_hankel

__all__ = ["SubspacePredictor", "subspace_predictor"]


@dataclass(frozen=True)
class SubspacePredictor:
    """The subspace predictor ``ŷ_f = L_p v_p + L_f u_f`` (5.16).

    Parameters
    ----------
    Lp : ndarray, shape (M·l, M·(l + m))
        Past-data predictor matrix, acting on ``v_p = [y_{t−M+1}; …; y_t; u_{t−M+1}; …; u_t]``.
    Lf : ndarray, shape (M·l, M·m)
        Future-input predictor matrix, acting on ``u_f = [u_{t+1}; …; u_{t+M}]``.
    horizon : int
        ``M``, the number of block rows (prediction horizon).
    m, l : int
        Numbers of inputs and outputs.
    R21 : ndarray, shape (M·m, M·(l + m))
        The ``U_f`` rows of the RQ factor (5.14) under the ``V_p`` columns.
    R22 : ndarray, shape (M·m, M·m)
        The ``U_f`` rows of the RQ factor under the ``U_f`` columns.

    References
    ----------
    Hallouzi 2008, §5.2.1, (5.12)–(5.16).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((60, 1))
    >>> y = np.r_[[[0.0]], 0.5 * u[:-1]]          # y_k = 0.5 u_{k−1}
    >>> P = subspace_predictor(u, y, 2)
    >>> np.round(P.markov()[:, 0, 0], 6) + 0.0    # D, CB
    array([0. , 0.5])
    """

    Lp: np.ndarray
    Lf: np.ndarray
    horizon: int
    m: int
    l: int  # noqa: E741 - the thesis's name for the number of outputs
    R21: np.ndarray
    R22: np.ndarray

    @property
    def theta(self) -> np.ndarray:
        """``Θ = [R_21 R_22]``, shape (M·m, M·(l + 2m)): the input part of the RQ factor (§5.3)."""
        return np.hstack([self.R21, self.R22])

    def predict(self, v_p, u_f) -> np.ndarray:
        """The predicted outputs ``ŷ_f = L_p v_p + L_f u_f`` (5.16).

        Parameters
        ----------
        v_p : array_like, shape (M·(l + m),)
            Past outputs and inputs, as :meth:`past` builds them.
        u_f : array_like, shape (M·m,)
            Future inputs ``[u_{t+1}; …; u_{t+M}]``.

        Returns
        -------
        ndarray, shape (M·l,)
            ``[ŷ_{t+1}; …; ŷ_{t+M}]``.

        Raises
        ------
        ParameterError
            A vector has the wrong size or non-finite entries.

        Examples
        --------
        >>> P = SubspacePredictor(np.zeros((1, 2)), np.ones((1, 1)), 1, 1, 1, np.zeros((1, 2)), np.ones((1, 1)))
        >>> P.predict([0.0, 0.0], [2.0])
        array([2.])
        """
        M = self.horizon
        v = validate.as_vector("v_p", v_p, M * (self.l + self.m))
        u = validate.as_vector("u_f", u_f, M * self.m)
        return self.Lp @ v + self.Lf @ u

    def past(self, u, y) -> np.ndarray:
        """The past-data vector ``v_p = [y_{t−M+1}; …; y_t; u_{t−M+1}; …; u_t]`` from the last M rows.

        Parameters
        ----------
        u : array_like, shape (N, m)
            Inputs up to and including ``u_t`` (the last row); ``N ≥ M``.
        y : array_like, shape (N, l)
            Outputs up to and including ``y_t``.

        Returns
        -------
        ndarray, shape (M·(l + m),)

        Raises
        ------
        DataError
            Fewer than M rows, or the wrong number of channels.

        Examples
        --------
        >>> P = SubspacePredictor(np.zeros((2, 4)), np.eye(2), 2, 1, 1, np.zeros((2, 4)), np.eye(2))
        >>> P.past([[1.0], [2.0], [3.0]], [[10.0], [20.0], [30.0]])
        array([20., 30.,  2.,  3.])
        """
        M = self.horizon
        parts = []
        for name, value, width in (("y", y, self.l), ("u", u, self.m)):
            arr = validate.as_array(name, value, error=DataError)
            if arr.ndim == 1 and width == 1:
                arr = arr[:, None]
            if arr.ndim != 2 or arr.shape[1] != width or arr.shape[0] < M:
                raise DataError(f"{name} must be a (N, {width}) array with N ≥ {M} rows (the horizon); "
                                f"got shape {arr.shape}")
            parts.append(arr[-M:].ravel())
        return np.concatenate(parts)

    def markov(self) -> np.ndarray:
        """The first block column of ``L_f``: the Markov parameters ``D, CB, CAB, …`` (5.8), (5.12).

        Returns
        -------
        ndarray, shape (M, l, m)
            Entry ``i`` is the block in rows ``i·l … i·l + l − 1``.

        Examples
        --------
        >>> P = SubspacePredictor(np.zeros((2, 4)), np.array([[1.0, 0.0], [2.0, 1.0]]), 2, 1, 1,
        ...                       np.zeros((2, 4)), np.eye(2))
        >>> P.markov()[:, 0, 0]
        array([1., 2.])
        """
        return self.Lf[:, : self.m].reshape(self.horizon, self.l, self.m).copy()


def _channels(name: str, value) -> np.ndarray:
    arr = validate.as_array(name, value, error=DataError)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] == 0:
        raise DataError(f"{name} must be a (samples, channels) array; got shape {arr.shape}")
    return arr


def subspace_predictor(u, y, horizon: int, columns: int | None = None) -> SubspacePredictor:
    """Estimate the subspace predictor (5.13)–(5.15) from input–output data.

    Parameters
    ----------
    u : array_like, shape (N, m)
        Inputs (a vector for one input).
    y : array_like, shape (N, l)
        Outputs, same N.
    horizon : int
        ``M``, the number of block rows of each Hankel matrix (≥ 1).
    columns : int, optional
        ``j``, the number of Hankel columns; the LAST ``j`` columns are used (receding window over the
        newest ``2M + j − 1`` samples). Default all, ``N − 2M + 1``.

    Returns
    -------
    SubspacePredictor

    Raises
    ------
    DataError
        Malformed data, different lengths, or too few columns: ``j ≥ 2M(l + m)`` is needed (the RQ
        factor of (5.14) must be square), i.e. ``N ≥ 2M(l + m + 1) − 1`` samples.
    ParameterError
        ``horizon`` or ``columns`` is not a positive integer.

    References
    ----------
    Hallouzi 2008, §5.2.1, (5.5)–(5.16); Van Overschee & De Moor 1996.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal(80)
    >>> y = np.zeros(80)
    >>> for k in range(1, 80):
    ...     y[k] = 0.8 * y[k - 1] + u[k - 1]        # x⁺ = 0.8x + u, y = x
    >>> P = subspace_predictor(u, y, 3)
    >>> np.round(P.markov()[:, 0, 0], 6) + 0.0      # D, CB, CAB (+ 0.0: no "-0." from round-off)
    array([0. , 1. , 0.8])
    """
    from scipy import linalg

    U = _channels("u", u)
    Y = _channels("y", y)
    if U.shape[0] != Y.shape[0]:
        raise DataError(f"u has {U.shape[0]} samples and y has {Y.shape[0]}; give both for the same samples")
    M = validate.integer("horizon", horizon, minimum=1)
    N, m = U.shape
    l = Y.shape[1]  # noqa: E741
    rows = 2 * M * (l + m)
    fit = N - 2 * M + 1
    j = fit if columns is None else validate.integer("columns", columns, minimum=1)
    if j > fit:
        raise DataError(f"{N} samples give {max(fit, 0)} Hankel columns for horizon {M}; asked for {j}: "
                        f"give more samples or fewer columns")
    if j < rows:
        raise DataError(f"{j} Hankel columns are fewer than the {rows} rows of [V_p; U_f; Y_f] (horizon {M}, "
                        f"{m} inputs, {l} outputs): give at least {2 * M + rows - 1} samples, or a shorter "
                        f"horizon")
    s = fit - j  # first sample of the window: the last j columns
    Yp, Yf = block_hankel(Y, M, j, s), block_hankel(Y, M, j, s + M)
    Up, Uf = block_hankel(U, M, j, s), block_hankel(U, M, j, s + M)
    W = np.vstack([Yp, Up, Uf, Yf])
    # RQ of W = R Q^T from the QR of W^T = Q R^T (5.14)
    R = linalg.qr(W.T, mode="r")[0][:rows].T
    p, f = M * (l + m), M * m
    R_in = R[: p + f, : p + f]          # [R11 0; R21 R22]
    R_out = R[p + f:, : p + f]          # [R31 R32]
    # (5.15) by minimum-norm least squares: identical to the triangular inverse when [R11 0; R21 R22] is
    # nonsingular, and well defined when it is singular (noise-free data with M·l > n)
    cutoff = max(R_in.shape) * np.finfo(float).eps
    L = linalg.lstsq(R_in.T, R_out.T, cond=cutoff)[0].T
    return SubspacePredictor(Lp=L[:, :p], Lf=L[:, p:], horizon=M, m=m, l=l,
                             R21=R[p: p + f, :p].copy(), R22=R[p: p + f, p: p + f].copy())
