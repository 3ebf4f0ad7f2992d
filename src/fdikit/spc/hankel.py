"""Block-Hankel data matrices and the persistency-of-excitation test of Def. 5.1.

A signal ``s`` (samples × channels, ``d`` channels) gives the block-Hankel matrix whose block row ``i``
is ``[s_{start+i}  s_{start+i+1}  …  s_{start+i+columns−1}]`` (Hallouzi 2008, §5.2.1, (5.5)). An input is
persistently exciting of order ``s`` when the ``s``-block-row input Hankel matrix has full row rank
``s·m`` (Hallouzi 2008, §5.3, Def. 5.1, (5.38); Verhaegen & Verdult 2007).

The functions are a few lines of numpy; no library builds the block-Hankel layout of the thesis with
samples as rows, so it is written here and checked against a brute-force loop in the tests.

References
----------
Hallouzi 2008, §5.2.1, (5.5); §5.3, Def. 5.1, (5.38).
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import DataError

__all__ = ["block_hankel", "excitation_rank", "input_rcond"]


def _signal(name: str, value) -> np.ndarray:
    arr = validate.as_array(name, value, error=DataError)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise DataError(f"{name} must be a (samples, channels) array (or one channel as a vector); "
                        f"got shape {arr.shape}")
    return arr


def block_hankel(signal, rows: int, columns: int | None = None, start: int = 0) -> np.ndarray:
    """The block-Hankel matrix of a signal, (5.5).

    Parameters
    ----------
    signal : array_like, shape (N, d) or (N,)
        Samples × channels.
    rows : int
        Number of block rows (≥ 1).
    columns : int, optional
        Number of columns; default all that fit, ``N − start − rows + 1``.
    start : int, default 0
        Sample index of the top-left block.

    Returns
    -------
    ndarray, shape (rows·d, columns)
        Block row ``i`` (rows ``i·d … i·d + d − 1``), column ``k`` holds ``signal[start + i + k]``.

    Raises
    ------
    DataError
        The signal is not a finite 2-D array, or too short for ``rows``, ``columns`` and ``start``.
    ParameterError
        ``rows``, ``columns`` or ``start`` is not a valid integer.

    References
    ----------
    Hallouzi 2008, §5.2.1, (5.5).

    Examples
    --------
    >>> block_hankel([1.0, 2.0, 3.0, 4.0], 2)
    array([[1., 2., 3.],
           [2., 3., 4.]])
    """
    s = _signal("signal", signal)
    rows = validate.integer("rows", rows, minimum=1)
    start = validate.integer("start", start, minimum=0)
    n, d = s.shape
    fit = n - start - rows + 1
    if columns is None:
        columns = fit
        if columns < 1:
            raise DataError(f"signal has {n} samples: too short for {rows} block rows from sample {start}; "
                            f"give at least {start + rows} samples")
    columns = validate.integer("columns", columns, minimum=1)
    if columns > fit:
        raise DataError(f"signal has {n} samples: {rows} block rows × {columns} columns from sample {start} "
                        f"need {start + rows + columns - 1}; give more samples or fewer columns")
    # index[i, k] = start + i + k; stack the d channels of each block row
    index = start + np.arange(rows)[:, None] + np.arange(columns)[None, :]
    return s[index].transpose(0, 2, 1).reshape(rows * d, columns)


def _input_hankel(u, order: int) -> np.ndarray:
    s = _signal("u", u)
    order = validate.integer("order", order, minimum=1)
    m = s.shape[1]
    H = block_hankel(s, order)
    if H.shape[1] < order * m:
        raise DataError(f"u has {s.shape[0]} samples: the {order}-block-row Hankel matrix has {H.shape[1]} "
                        f"columns, fewer than its {order * m} rows, so full row rank is impossible; give at "
                        f"least {order * (m + 1) - 1} samples")
    return H


def excitation_rank(u, order: int) -> int:
    """The numerical rank of the ``order``-block-row input Hankel matrix (Def. 5.1).

    ``u`` is persistently exciting of order ``order`` exactly when the result equals ``order·m``. The
    rank is numpy's: singular values above ``σ_max · max(shape) · eps`` count.

    Parameters
    ----------
    u : array_like, shape (N, m) or (N,)
        Input samples.
    order : int
        Number of block rows ``s`` (≥ 1).

    Returns
    -------
    int
        Rank, between 0 and ``order·m``.

    Raises
    ------
    DataError
        ``u`` is malformed or has fewer than ``order·(m + 1) − 1`` samples.
    ParameterError
        ``order`` is not a positive integer.

    References
    ----------
    Hallouzi 2008, §5.3, Def. 5.1, (5.38).

    Examples
    --------
    >>> excitation_rank(np.ones(20), 3)   # a constant input is exciting of order 1 only
    1
    """
    return int(np.linalg.matrix_rank(_input_hankel(u, order)))


def input_rcond(u, order: int) -> float:
    """Reciprocal condition ``σ_min / σ_max`` of the ``order``-block-row input Hankel matrix (Def. 5.1).

    Near 0 the input is (close to) not persistently exciting of order ``order``.

    Parameters
    ----------
    u : array_like, shape (N, m) or (N,)
        Input samples.
    order : int
        Number of block rows (≥ 1).

    Returns
    -------
    float
        In [0, 1]; 0 for an all-zero input.

    Raises
    ------
    DataError
        ``u`` is malformed or has fewer than ``order·(m + 1) − 1`` samples.
    ParameterError
        ``order`` is not a positive integer.

    References
    ----------
    Hallouzi 2008, §5.3, Def. 5.1, (5.38).

    Examples
    --------
    >>> round(input_rcond([1.0, -1.0, 1.0, -1.0, 1.0], 2), 12)   # u_k and u_{k+1} = −u_k: rank 1
    0.0
    """
    sv = np.linalg.svd(_input_hankel(u, order), compute_uv=False)
    return 0.0 if sv[0] == 0 else float(sv[-1] / sv[0])
