"""The closed-loop (VARX) predictor of Hallouzi 2008, §6.3.1, and its multi-step matrices.

In innovation form (6.3)–(6.5) the one-step predictor of ``y_k`` is the VARX model
``y_k = Ξ_0 z_{[k−p,k)} + e_k`` (6.9) with ``Ξ_0 = [CΦ^{p−1}[B K] … C[B K]]``, ``Φ = A − KC``, and the
past window ``w_p = [u_{k−p}; y_{k−p}; …; u_{k−1}; y_{k−1}]`` (6.7) (the OCR of the seed prints
``y_{k−p+3}`` in the second column of (6.7) — it is ``y_{k−p+2}`` — and ``s`` for ``p`` in (6.8), (6.16)).
``Ξ_0`` is estimated by least squares (6.10) through an RQ decomposition (6.11), ``Ξ̂_0 = R_21 R_11^{-1}``
(6.12). The multi-step matrices ``Γ_i``, ``Λ_i`` follow from the Markov parameters ``CΦ^jB``, ``CΦ^jK`` by
(6.14)–(6.16); the truncation error is of order ``‖Φ^p‖``. The seed's (6.13) lists only ``f − 1``
predictions; :meth:`VarxPredictor.multistep` gives ``f`` by default (``full=False`` for the printed form).

The code is written here because no Python library provides the closed-loop SPC predictor (SIPPY and
python-control identify state-space models, not ``Γ``/``Λ`` from ``Ξ̂_0``).

References
----------
Hallouzi 2008, §6.3.1, (6.9)–(6.16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ParameterError

__all__ = ["VarxPredictor", "varx_data", "varx_fit"]


@dataclass(frozen=True)
class VarxPredictor:
    """The VARX one-step predictor ``ŷ_t = Ξ_0 w_p`` (6.9), (6.12).

    Parameters
    ----------
    Xi0 : ndarray, shape (l, p·(m+l))
        ``[CΦ^{p−1}[B K] … C[B K]]`` acting on ``w_p = [u_{t−p}; y_{t−p}; …; u_{t−1}; y_{t−1}]``.
    p, m, l : int
        Past horizon, number of inputs and of outputs.

    Examples
    --------
    >>> import numpy as np
    >>> pred = VarxPredictor(np.array([[0.0, 0.0, 0.5, 0.2]]), p=2, m=1, l=1)
    >>> pred.markov()[0][:, 0, 0]
    array([0.5, 0. ])

    References
    ----------
    Hallouzi 2008, §6.3.1, (6.9)–(6.16).
    """

    Xi0: np.ndarray
    p: int
    m: int
    l: int  # noqa: E741

    def markov(self) -> tuple[np.ndarray, np.ndarray]:
        """The Markov parameters ``CΦ^jB`` and ``CΦ^jK``, ``j = 0 … p−1``.

        Returns
        -------
        CPhiB : ndarray, shape (p, l, m)
        CPhiK : ndarray, shape (p, l, l)

        Examples
        --------
        >>> import numpy as np
        >>> VarxPredictor(np.array([[1.0, 2.0]]), p=1, m=1, l=1).markov()[1][0]
        array([[2.]])
        """
        d = self.m + self.l
        blocks = np.asarray(self.Xi0).reshape(self.l, self.p, d)[:, ::-1, :]  # j = 0 first
        blocks = np.transpose(blocks, (1, 0, 2))
        return blocks[:, :, : self.m].copy(), blocks[:, :, self.m :].copy()

    def multistep(self, f: int, *, full: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """The multi-step predictor ``ŷ = Γ w_p + Λ [u_t; …]`` (6.13)–(6.16).

        Parameters
        ----------
        f : int
            Future horizon, ``1 ≤ f ≤ p``.
        full : bool
            True: ``f`` predictions ``ŷ_{t+1} … ŷ_{t+f}``; False: the printed ``f − 1`` of (6.13).

        Returns
        -------
        Gamma : ndarray, shape (rows·l, p·(m+l))
        Lambda : ndarray, shape (rows·l, rows·m)
            Block lower-Toeplitz, acting on ``[u_t; …; u_{t+rows−1}]``.

        Raises
        ------
        ParameterError
            If ``f`` is not in ``1 … p`` (or ``< 2`` with ``full=False``).

        Examples
        --------
        >>> import numpy as np
        >>> G, L = VarxPredictor(np.array([[0.0, 0.0, 0.5, 0.2]]), p=2, m=1, l=1).multistep(2)
        >>> G.shape, L.shape
        ((2, 4), (2, 2))
        """
        f = validate.integer("f", f, minimum=1)
        if f > self.p:
            raise ParameterError(f"f = {f} exceeds the past horizon p = {self.p}; use f ≤ p or refit "
                                 "with a larger p.")
        rows = f if full else f - 1
        if rows < 1:
            raise ParameterError("full=False needs f ≥ 2 (it gives f − 1 predictions); pass a larger f.")
        from scipy.linalg import solve_triangular

        p, m, l, d = self.p, self.m, self.l, self.m + self.l
        nz = p * d
        cb, ck = self.markov()
        xi0 = np.asarray(self.Xi0, dtype=float)
        # (6.14) and (6.15) are one recursion X_i = R_i + Σ_{j<i} CΦ^{i−j−1}K X_j on X_i = [Γ_i  Λ_i], Λ_i the
        # i-th block of Λ's first block column, with X_0 = [Ξ_0  0] and R_i = [Ξ_0 shifted i blocks to the right
        # (6.16)  CΦ^{i−1}B]: a unit block lower-triangular Toeplitz system (I − T) X = R, solved by one
        # forward substitution (BLAS trsm) instead of a Python loop of block products.
        rhs = np.zeros(((rows + 1) * l, nz + m))
        for i in range(rows + 1):
            rhs[i * l : (i + 1) * l, i * d : nz] = xi0[:, : nz - i * d]
        rhs[l:, nz:] = cb[:rows].reshape(rows * l, m)
        lower = _block_toeplitz(np.concatenate([np.eye(l)[None], -ck[:rows]]), rows + 1)
        x = solve_triangular(lower, rhs, lower=True, unit_diagonal=True, check_finite=False)
        gamma = np.ascontiguousarray(x[l:, :nz])
        lambda_ = _block_toeplitz(x[l:, nz:].reshape(rows, l, m), rows)
        return gamma, lambda_

    def past(self, u, y) -> np.ndarray:
        """The past window ``w_p = [u_{t−p}; y_{t−p}; …; u_{t−1}; y_{t−1}]`` from the last ``p`` rows.

        Parameters
        ----------
        u : array_like, shape (N, m)
        y : array_like, shape (N, l)

        Returns
        -------
        ndarray, shape (p·(m+l),)

        Raises
        ------
        DataError
            If fewer than ``p`` rows are given or the widths do not match.

        Examples
        --------
        >>> import numpy as np
        >>> VarxPredictor(np.zeros((1, 4)), p=2, m=1, l=1).past([[1.0], [2.0]], [[3.0], [4.0]])
        array([1., 3., 2., 4.])
        """
        u = _as2d("u", u, self.m)
        y = _as2d("y", y, self.l)
        if u.shape[0] < self.p or y.shape[0] < self.p:
            raise DataError(f"past() needs at least p = {self.p} rows of u and y; got {u.shape[0]}, "
                            f"{y.shape[0]}.")
        return np.hstack([u[-self.p :], y[-self.p :]]).ravel()


def _block_toeplitz(blocks: np.ndarray, rows: int) -> np.ndarray:
    """Block lower-triangular Toeplitz matrix, ``blocks[k]`` on the k-th block subdiagonal (k < rows)."""
    a, b = blocks.shape[1:]
    lag = np.subtract.outer(np.arange(rows), np.arange(rows))
    padded = np.concatenate([blocks[:rows], np.zeros((1, a, b))])
    lag[lag < 0] = len(padded) - 1                      # above the diagonal: the zero block
    return padded[lag].transpose(0, 2, 1, 3).reshape(rows * a, rows * b)


def _as2d(name, value, width):
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != width:
        raise DataError(f"{name} must be (N, {width}) samples × signals; got shape {arr.shape}.")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name} contains non-finite values; clean the data first.")
    return arr


def varx_data(u, y, p, columns=None):
    """The data matrices ``Z_{[k−p,k)}`` (6.7) and ``Y_k`` (6.6) from samples × signals data.

    Parameters
    ----------
    u : array_like, shape (N, m)
    y : array_like, shape (N, l)
    p : int
        Past horizon.
    columns : int, optional
        Use only the last ``columns`` columns (receding window); default all ``N − p``.

    Returns
    -------
    Z : ndarray, shape (p·(m+l), j)
    Y : ndarray, shape (l, j)

    Raises
    ------
    DataError
        If the data are too short or malformed.

    Examples
    --------
    >>> import numpy as np
    >>> Z, Y = varx_data(np.arange(4.0), np.arange(4.0) + 10, 2)
    >>> Z[:, 0], Y[:, 0]
    (array([ 0., 10.,  1., 11.]), array([12.]))

    References
    ----------
    Hallouzi 2008, §6.3.1, (6.6)–(6.7).
    """
    p = validate.integer("p", p, minimum=1)
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    u = _as2d("u", u, u.shape[1] if u.ndim == 2 else 1)
    y = _as2d("y", y, y.shape[1] if y.ndim == 2 else 1)
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u and y must have the same number of rows; got {u.shape[0]} and {y.shape[0]}.")
    n = u.shape[0]
    j = n - p
    if columns is not None:
        columns = validate.integer("columns", columns, minimum=1)
        if columns > j:
            raise DataError(f"columns = {columns} needs N ≥ p + columns = {p + columns} rows; got {n}.")
        j = columns
    if j < 1:
        raise DataError(f"need more than p = {p} samples; got {n}.")
    z = np.hstack([u, y])
    first = n - j
    Z = np.vstack([z[first - p + i : first - p + i + j].T for i in range(p)])
    return Z, y[first:].T.copy()


def varx_fit(u, y, p, columns=None) -> VarxPredictor:
    """Fit the VARX predictor by the batch RQ solution (6.10)–(6.12).

    Parameters
    ----------
    u : array_like, shape (N, m)
    y : array_like, shape (N, l)
    p : int
        Past horizon.
    columns : int, optional
        Number ``j`` of data columns (the last ones); default all ``N − p``.

    Returns
    -------
    VarxPredictor

    Raises
    ------
    DataError
        If ``j < p·(m+l)`` or ``Z`` is rank deficient (not persistently exciting).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((300, 1)); y = np.zeros((300, 1))
    >>> for k in range(1, 300): y[k] = 0.5 * y[k - 1] + u[k - 1]
    >>> np.round(varx_fit(u, y, 1).Xi0, 8) + 0.0
    array([[1. , 0.5]])

    References
    ----------
    Hallouzi 2008, §6.3.1, (6.9)–(6.16).
    """
    from scipy.linalg import qr, solve_triangular

    Z, Y = varx_data(u, y, p, columns)
    nz = Z.shape[0]
    if Z.shape[1] < nz:
        raise DataError(f"{Z.shape[1]} data columns < p·(m+l) = {nz} regressors; give more data.")
    upper = qr(np.vstack([Z, Y]).T, mode="r")[0][: nz + Y.shape[0]]
    low = upper.T
    r11, r21 = low[:nz, :nz], low[nz:, :nz]
    diag = np.abs(np.diag(r11))
    if diag.min() <= nz * np.finfo(float).eps * diag.max():
        raise DataError("Z_[k−p,k) is rank deficient (inputs not persistently exciting or noise-free "
                        "data of a low-order system); excite more or reduce p.")
    xi0 = solve_triangular(r11.T, r21.T, lower=False).T
    return VarxPredictor(xi0, p, Z.shape[0] // p - Y.shape[0], Y.shape[0])
