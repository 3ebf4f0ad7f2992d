"""The batch response of a discrete LTI system: the flops it needs, read in place, in bounded memory.

``x[k+1] = A x[k] + B v[k]``, ``y[k] = C x[k] + D v[k]``.

The state recursion is the only sequential part; everything else is a matrix product over many samples.  The
kernel therefore works through the samples in chunks of ``chunk`` rows (4096 by default) and per chunk:

1. gathers the inputs ``v = [u − u0, y − y0]`` straight from the columns of the signal arrays (no ``(N, m)``
   input block is built), checking that every sample is finite and valid;
2. forms the input drive ``W = v Bᵀ`` with one BLAS product;
3. runs the recursion ``x[k+1] = A x[k] + W[k]`` in compiled code, separately for each diagonal block of ``A``
   (a stacked bank of filters is block-diagonal: its off-diagonal zero blocks cost nothing), with two
   accumulators per state so the dependency chain is half as long;
4. forms the outputs ``y = x Cᵀ + v Dᵀ`` with two BLAS products, into the result.

So the arithmetic is ``n_b² `` multiply-adds per diagonal block and sample for the recursion plus the
``(n + p) m + p n`` of the products — no Toeplitz zero blocks as the lifted solver :func:`fdikit.lti.dlsim_blocked`
has — and no Python loop at all; the memory is the result (and the states when asked for) plus
``chunk`` rows of work space.

Why hand-written: ``scipy.signal.dlsim`` and ``control.forced_response`` loop in Python once per sample and
return every state; ``scipy.signal.lfilter`` is single-input transfer functions.  numba (``cache=True``) compiles
the kernel on first use; the module is imported only by the code that needs it, so ``import fdikit`` stays light.

Examples
--------
>>> import numpy as np
>>> from fdikit.runtime.lti_batch import lsim
>>> y, x, x_end = lsim([[0.5]], [[1.0]], [[1.0]], [[0.0]], np.ones((4, 1)), states=True)
>>> y.ravel().tolist(), x.ravel().tolist(), x_end.tolist()
([0.0, 1.0, 1.5, 1.75], [0.0, 1.0, 1.5, 1.75], [1.875])
"""

from __future__ import annotations

import numba
import numpy as np

from fdikit import validate
from fdikit.errors import DataError

__all__ = ["diagonal_blocks", "lsim", "lsim_columns"]

CHUNK = 4096


def diagonal_blocks(A: np.ndarray) -> np.ndarray:
    """Boundaries ``[0, b1, …, n]`` of the finest contiguous block-diagonal partition of ``A``.

    Parameters
    ----------
    A : (n, n) array
        A state matrix.

    Returns
    -------
    numpy.ndarray of int64
        ``A[b_i:b_{i+1}, b_j:b_{j+1}]`` is zero for ``i ≠ j``.

    Examples
    --------
    >>> diagonal_blocks(np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]])).tolist()
    [0, 2, 3]
    """
    A = np.asarray(A)
    n = A.shape[0]
    nz = A != 0
    # the last row/column any state of 0..i couples to: a block ends at i when nothing before i+1 reaches past i
    reach = np.arange(n)
    rows, cols = np.nonzero(nz)
    np.maximum.at(reach, rows, cols)
    np.maximum.at(reach, cols, rows)
    ends = np.flatnonzero(np.maximum.accumulate(reach) == np.arange(n)) + 1
    return np.concatenate([[0], ends]).astype(np.int64)


@numba.njit(cache=True, nogil=True)
def _recursion(AT, lo, hi, W, X, L, x):  # pragma: no cover - compiled
    """``X[k] = x``, ``x ← A x + W[k]`` for the states ``lo … hi − 1`` of one diagonal block, ``k < L``."""
    nb = hi - lo
    h = nb // 2
    Ab = AT[lo:hi, lo:hi].copy()  # local copies: contiguous, not aliased, so the inner loops vectorise
    xb = x[lo:hi].copy()
    xn = np.empty(nb)
    acc = np.empty(nb)
    for k in range(L):
        for i in range(nb):
            X[k, lo + i] = xb[i]
            xn[i] = W[k, lo + i]
            acc[i] = 0.0
        for j in range(h):  # x+ = W + A x, the columns of A split over two accumulators
            xj = xb[j]
            for i in range(nb):
                xn[i] += Ab[j, i] * xj
        for j in range(h, nb):
            xj = xb[j]
            for i in range(nb):
                acc[i] += Ab[j, i] * xj
        for i in range(nb):
            xb[i] = xn[i] + acc[i]
    x[lo:hi] = xb


@numba.njit(cache=True, nogil=True)
def _kernel(AT, blocks, BT, CDT, U, iu, Y, iy, off, valid, x, out, X, chunk):  # pragma: no cover - compiled
    """The chunked response; returns the first bad sample (non-finite input or ``valid`` False), else ``N``."""
    N = U.shape[0]
    n, m = AT.shape[0], BT.shape[0]
    mu = iu.shape[0]
    keep = X.shape[0] == N
    Vc = np.empty((chunk, m))
    W = np.empty((chunk, n))
    Z = np.empty((chunk, n + m))  # [x, v] per sample: y = Z [Cᵀ; Dᵀ] in one product
    Yc = np.empty((chunk, out.shape[1]))
    for s in range(0, N, chunk):
        L = min(chunk, N - s)
        for k in range(L):
            if not valid[s + k]:
                return s + k
            for j in range(mu):
                Vc[k, j] = U[s + k, iu[j]] - off[j]
            for j in range(m - mu):
                Vc[k, mu + j] = Y[s + k, iy[j]] - off[mu + j]
            for j in range(m):
                if not np.isfinite(Vc[k, j]):
                    return s + k
                Z[k, n + j] = Vc[k, j]
        if L < chunk:
            Vc, W, Z, Yc = Vc[:L].copy(), W[:L].copy(), Z[:L].copy(), Yc[:L].copy()
        np.dot(Vc, BT, W)
        for b in range(blocks.shape[0] - 1):
            _recursion(AT, blocks[b], blocks[b + 1], W, Z, L, x)
        np.dot(Z, CDT, out[s : s + L])
        if keep:
            X[s : s + L] = Z[:, :n]
    return N


def _c(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=float)


def lsim_columns(A, B, C, D, U, iu, Y, iy, offset, valid, x0, *, states: bool = False, chunk: int = CHUNK):
    """The response to inputs read in place from columns ``iu`` of ``U`` and ``iy`` of ``Y``, minus ``offset``.

    The input of sample ``k`` is ``v[k] = [U[k, iu], Y[k, iy]] − offset``; a sample with ``valid[k]`` False or a
    non-finite entry stops the computation there (the caller handles gaps).  Matrices are assumed checked
    (:func:`lsim` checks them).

    Parameters
    ----------
    A, B, C, D : arrays
        The discrete system (``B``, ``D`` have ``len(iu) + len(iy)`` columns).
    U, Y : (N, ·) arrays
        The signal blocks the inputs are read from (e.g. a trace's controls and outputs).
    iu, iy : sequence of int
        The columns read.
    offset : (m,) array
        Subtracted from the inputs (an operating point).
    valid : (N,) bool array
        Samples flagged invalid stop the computation.
    x0 : (n,) array
        Initial state.
    states : bool
        Also return the states.
    chunk : int
        Rows per chunk.

    Returns
    -------
    y : (N, p) array
        Outputs; not computed (undefined) when ``bad < N``: the caller then handles the gap.
    x : (N, n) array or None
        States when ``states`` is True.
    x_end : (n,) array
        The state after the last sample computed.
    bad : int
        The first bad sample, ``N`` when there is none.

    Examples
    --------
    >>> U = np.array([[0.0, 2.0], [0.0, 2.0], [0.0, 2.0]])
    >>> y, _, _, bad = lsim_columns([[0.5]], [[1.0]], [[1.0]], [[0.0]], U, [1], np.zeros((3, 0)), [],
    ...                             [1.0], np.ones(3, bool), np.zeros(1))
    >>> y.ravel().tolist(), bad
    ([0.0, 1.0, 1.5], 3)
    >>> U[2, 1] = np.nan
    >>> lsim_columns([[0.5]], [[1.0]], [[1.0]], [[0.0]], U, [1], np.zeros((3, 0)), [], [1.0], np.ones(3, bool),
    ...              np.zeros(1))[3]
    2
    """
    A = _c(A)
    n = A.shape[0]
    U, Y = _c(U), _c(Y)
    N = U.shape[0]
    out = np.empty((N, np.shape(C)[0]))
    X = np.empty((N if states else 0, n))
    x = np.array(x0, dtype=float).reshape(n)
    CDT = _c(np.vstack([np.transpose(C), np.transpose(D)]))
    bad = _kernel(_c(A.T), diagonal_blocks(A), _c(np.transpose(B)), CDT, U,
                  np.asarray(iu, dtype=np.int64).reshape(-1), Y, np.asarray(iy, dtype=np.int64).reshape(-1),
                  _c(offset).reshape(-1), np.ascontiguousarray(valid, dtype=np.bool_), x, out, X, int(chunk))
    return out, (X if states else None), x, int(bad)


def lsim(A, B, C, D, v, x0=None, *, states: bool = False, chunk: int = CHUNK):
    """Response of a discrete state space to the input sequence ``v`` (N x m).

    Parameters
    ----------
    A, B, C, D : arrays
        ``x[k+1] = A x[k] + B v[k]``, ``y[k] = C x[k] + D v[k]`` (n x n, n x m, p x n, p x m).
    v : (N, m) array
        Input sequence, finite.
    x0 : (n,) array, optional
        Initial state (zero when omitted).
    states : bool, default False
        Also return the states (``N x n`` more memory).
    chunk : int, optional
        Samples per chunk (>= 1): the work space is ``chunk (2 n + m + p)`` numbers.

    Returns
    -------
    y : (N, p) array
        Outputs.
    x : (N, n) array or None
        States (``x[0] = x0``) when ``states`` is True, else None.
    x_end : (n,) array
        The state after the last sample.

    Raises
    ------
    DataError
        When ``v`` holds a NaN/inf (the sample is named).
    ParameterError
        For malformed matrices, a non-finite ``x0`` or a bad ``chunk``.

    Examples
    --------
    >>> y, _, x_end = lsim([[0.5]], [[1.0]], [[1.0]], [[0.0]], np.ones((4, 1)))
    >>> y.ravel().tolist(), x_end.tolist()
    ([0.0, 1.0, 1.5, 1.75], [1.875])
    """
    chunk = validate.integer("chunk", chunk, minimum=1)
    A = validate.as_square("A", A)
    n = A.shape[0]
    B = validate.as_matrix("B", B, (n, None))
    m = B.shape[1]
    C = validate.as_matrix("C", C, (None, n))
    D = validate.as_matrix("D", D, (C.shape[0], m))
    v = np.asarray(v, dtype=float)
    if v.ndim != 2 or v.shape[1] != m:
        raise DataError(f"v (the input sequence) has shape {v.shape}, need (N, {m}): one row of {m} inputs per sample")
    x0 = np.zeros(n) if x0 is None else validate.as_vector("x0", x0, n)
    N = v.shape[0]
    y, X, x_end, bad = lsim_columns(A, B, C, D, v, np.arange(m), np.zeros((N, 0)), (), np.zeros(m),
                                    np.ones(N, bool), x0, states=states, chunk=chunk)
    if bad < N:
        raise DataError(f"v (the input sequence) is not finite at sample {bad} ({v[bad].tolist()}); "
                        "handle gaps before simulating (ResidualGenerator.run does)")
    return y, X, x_end
