"""Small linear algebra on one flat float64 buffer, for the compiled estimator kernels, and their compiler.

The kernels of :mod:`fdikit.runtime.kalman_kernels` and :mod:`fdikit.runtime.imm_kernels` keep a filter in one
flat buffer; these helpers take the buffer and offsets into it (runtime integers, so each helper is compiled
once) and store matrices by rows, with inner loops over contiguous memory (vectorisable without fastmath).  They
implement the products, the Cholesky factorisation, triangular solves and the Householder ``tria`` of
:mod:`fdikit.multimodel.kalman_steps` (Hallouzi 2008, §2.3.1, Table 2.1 step 2; §2.3.2, (2.29)–(2.31)).  Why
hand-written: numba's ``np.linalg`` allocates per call and the online steps must not.

:func:`compiled` compiles a step kernel for :data:`STEP_SIGNATURE` on first use, so only the kernels a program
uses are compiled (then loaded from numba's cache).

Examples
--------
>>> import numpy as np
>>> b = np.array([4.0, 2.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.0])
>>> chol(b, 0, 4, 2), b[4:].tolist()
(True, [2.0, 0.0, 1.0, 1.0])

References
----------
Hallouzi 2008, §2.3.1, Table 2.1 step 2; §2.3.2, (2.29)–(2.31).
"""

from __future__ import annotations

import math

import numba

__all__ = ["compiled", "STEP_SIGNATURE", "fill", "copy", "gemm", "gemm_tn", "gemv_t", "ger", "symmetrise", "chol",
           "ldl", "unit_forward_rows", "ldl_solve_rows", "ldl_quad", "forward_rows", "solve_rows", "forward",
           "log_diag", "residual", "affine", "tria", "gram"]


# ---------------------------------------------------------------------------------------- helpers on the buffer
# Every helper takes the buffer and offsets into it (runtime integers: one compiled specialisation each) and
# slices local views first: indices from range() variables are provably non-negative, so numba emits no
# negative-index wraparound and the inner loops (contiguous, by rows) vectorise without fastmath.
@numba.njit(cache=True, nogil=True)
def fill(b, o, size, v):  # pragma: no cover - compiled
    """``b[o:o+size] = v``."""
    X = b[o:o + size]
    for i in range(size):
        X[i] = v


@numba.njit(cache=True, nogil=True)
def copy(b, src, dst, size):  # pragma: no cover - compiled
    """``b[dst:dst+size] = b[src:src+size]`` (non-overlapping)."""
    X, Y = b[src:src + size], b[dst:dst + size]
    for i in range(size):
        Y[i] = X[i]


@numba.njit(cache=True, nogil=True)
def gemm(b, oX, oY, oO, r, k, c, s):  # pragma: no cover - compiled
    """``O (r x c) += s · X (r x k) @ Y (k x c)``."""
    X, Y, O = b[oX:oX + r * k], b[oY:oY + k * c], b[oO:oO + r * c]
    for i in range(r):
        for j in range(k):
            a = s * X[i * k + j]
            for q in range(c):
                O[i * c + q] += a * Y[j * c + q]


@numba.njit(cache=True, nogil=True)
def gemm_tn(b, oX, oY, oO, r, k, c, s):  # pragma: no cover - compiled
    """``O (r x c) += s · Xᵀ @ Y`` with ``X`` (k x r), ``Y`` (k x c)."""
    X, Y, O = b[oX:oX + k * r], b[oY:oY + k * c], b[oO:oO + r * c]
    for i in range(r):
        for j in range(k):
            a = s * X[j * r + i]
            for q in range(c):
                O[i * c + q] += a * Y[j * c + q]


@numba.njit(cache=True, nogil=True)
def gemv_t(b, oX, ov, oO, r, k):  # pragma: no cover - compiled
    """``O (r) += Xᵀ v`` with ``X`` (k x r), ``v`` (k)."""
    X, v, O = b[oX:oX + k * r], b[ov:ov + k], b[oO:oO + r]
    for j in range(k):
        a = v[j]
        for i in range(r):
            O[i] += a * X[j * r + i]


@numba.njit(cache=True, nogil=True)
def ger(b, od, oO, n, s):  # pragma: no cover - compiled
    """``O (n x n) += s · d dᵀ``."""
    d, O = b[od:od + n], b[oO:oO + n * n]
    for i in range(n):
        a = s * d[i]
        for j in range(n):
            O[i * n + j] += a * d[j]


@numba.njit(cache=True, nogil=True)
def symmetrise(b, o, n):  # pragma: no cover - compiled
    """``X ← (X + Xᵀ) / 2`` for the n x n matrix at ``o``."""
    X = b[o:o + n * n]
    for i in range(n):
        for j in range(i + 1, n):
            v = 0.5 * (X[i * n + j] + X[j * n + i])
            X[i * n + j] = v
            X[j * n + i] = v


@numba.njit(cache=True, nogil=True)
def chol(b, oS, oL, p):  # pragma: no cover - compiled
    """Lower Cholesky factor of ``S`` into ``L``; False when ``S`` is not positive definite (as LAPACK potrf)."""
    S, L = b[oS:oS + p * p], b[oL:oL + p * p]
    for i in range(p * p):
        L[i] = 0.0
    for j in range(p):
        d = S[j * p + j]
        for k in range(j):
            d -= L[j * p + k] * L[j * p + k]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        L[j * p + j] = d
        for i in range(j + 1, p):
            s = S[i * p + j]
            for k in range(j):
                s -= L[i * p + k] * L[j * p + k]
            L[i * p + j] = s / d
    return True


@numba.njit(cache=True, nogil=True)
def ldl(b, oS, oL, p):  # pragma: no cover - compiled
    """``S = L D Lᵀ`` (unit-lower ``L`` below the diagonal of ``oL``, ``D`` on it); False unless ``S`` is positive
    definite.  Solves with it need no square root: ``S⁻¹ x`` is exact where the reference's LU solve is (1 x 1)."""
    S, L = b[oS:oS + p * p], b[oL:oL + p * p]
    for i in range(p * p):
        L[i] = 0.0
    for j in range(p):
        d = S[j * p + j]
        for k in range(j):
            d -= L[j * p + k] * L[j * p + k] * L[k * p + k]
        if not d > 0.0:
            return False
        L[j * p + j] = d
        for i in range(j + 1, p):
            s = S[i * p + j]
            for k in range(j):
                s -= L[i * p + k] * L[j * p + k] * L[k * p + k]
            L[i * p + j] = s / d
    return True


@numba.njit(cache=True, nogil=True)
def unit_forward_rows(b, oL, oX, p, k):  # pragma: no cover - compiled
    """``X (p x k) ← L⁻¹ X`` for the unit-lower ``L`` of :func:`ldl`."""
    L, X = b[oL:oL + p * p], b[oX:oX + p * k]
    for j in range(p):
        for i in range(j):
            a = L[j * p + i]
            for q in range(k):
                X[j * k + q] -= a * X[i * k + q]


@numba.njit(cache=True, nogil=True)
def ldl_solve_rows(b, oL, oX, p, k):  # pragma: no cover - compiled
    """``X (p x k) ← S⁻¹ X`` with the factor of :func:`ldl`."""
    unit_forward_rows(b, oL, oX, p, k)
    L, X = b[oL:oL + p * p], b[oX:oX + p * k]
    for j in range(p):
        d = L[j * p + j]
        for q in range(k):
            X[j * k + q] /= d
    for jj in range(p):
        j = p - 1 - jj
        for i in range(j):  # X[i] −= L[j, i] X[j] (backward sweep by columns of Lᵀ)
            a = L[j * p + i]
            for q in range(k):
                X[i * k + q] -= a * X[j * k + q]


@numba.njit(cache=True, nogil=True)
def ldl_quad(b, oL, oe, ow, p):  # pragma: no cover - compiled
    """``w = L⁻¹ e`` (unit ``L`` of :func:`ldl`); returns ``eᵀ S⁻¹ e = Σ w_j² / D_j``."""
    L, e, w = b[oL:oL + p * p], b[oe:oe + p], b[ow:ow + p]
    q = 0.0
    for j in range(p):
        s = e[j]
        for k in range(j):
            s -= L[j * p + k] * w[k]
        w[j] = s
        q += s * s / L[j * p + j]
    return q


@numba.njit(cache=True, nogil=True)
def forward_rows(b, oL, oX, p, k):  # pragma: no cover - compiled
    """``X (p x k) ← L⁻¹ X`` for the lower ``L`` (p x p) at ``oL``."""
    L, X = b[oL:oL + p * p], b[oX:oX + p * k]
    for j in range(p):
        for i in range(j):
            a = L[j * p + i]
            for q in range(k):
                X[j * k + q] -= a * X[i * k + q]
        d = 1.0 / L[j * p + j]
        for q in range(k):
            X[j * k + q] *= d


@numba.njit(cache=True, nogil=True)
def solve_rows(b, oL, oX, p, k):  # pragma: no cover - compiled
    """``X (p x k) ← (L Lᵀ)⁻¹ X``."""
    forward_rows(b, oL, oX, p, k)
    L, X = b[oL:oL + p * p], b[oX:oX + p * k]
    for jj in range(p):
        j = p - 1 - jj
        for i in range(j + 1, p):
            a = L[i * p + j]
            for q in range(k):
                X[j * k + q] -= a * X[i * k + q]
        d = 1.0 / L[j * p + j]
        for q in range(k):
            X[j * k + q] *= d


@numba.njit(cache=True, nogil=True)
def forward(b, oL, ld, oe, oz, p):  # pragma: no cover - compiled
    """``z = L⁻¹ e`` (``L`` lower with row stride ``ld``); returns ``zᵀ z``."""
    L, e, z = b[oL:oL + p * ld], b[oe:oe + p], b[oz:oz + p]
    q = 0.0
    for j in range(p):
        s = e[j]
        for k in range(j):
            s -= L[j * ld + k] * z[k]
        s /= L[j * ld + j]
        z[j] = s
        q += s * s
    return q


@numba.njit(cache=True, nogil=True)
def log_diag(b, oL, ld, p):  # pragma: no cover - compiled
    """``Σ log |L_jj|``."""
    L = b[oL:oL + p * ld]
    s = 0.0
    for j in range(p):
        s += math.log(abs(L[j * ld + j]))
    return s


@numba.njit(cache=True, nogil=True)
def residual(b, y, u, oCt, ox, oDt, oe, p, n):  # pragma: no cover - compiled
    """``e = y − C x − D u`` from ``Cᵀ`` (n x p) and ``Dᵀ`` (m x p): column sweeps, vectorisable."""
    m = u.shape[0]
    Ct, x, Dt, e = b[oCt:oCt + n * p], b[ox:ox + n], b[oDt:oDt + m * p], b[oe:oe + p]
    for i in range(p):
        e[i] = y[i]
    for j in range(n):
        a = x[j]
        for i in range(p):
            e[i] -= a * Ct[j * p + i]
    for j in range(m):
        a = u[j]
        for i in range(p):
            e[i] -= a * Dt[j * p + i]


@numba.njit(cache=True, nogil=True)
def affine(b, u, oAt, ox, oBt, oout, n):  # pragma: no cover - compiled
    """``out = A x + B u`` from ``Aᵀ`` and ``Bᵀ`` (m x n); ``out`` and ``x`` distinct."""
    m = u.shape[0]
    At, x, Bt, out = b[oAt:oAt + n * n], b[ox:ox + n], b[oBt:oBt + m * n], b[oout:oout + n]
    for i in range(n):
        out[i] = 0.0
    for j in range(n):
        a = x[j]
        for i in range(n):
            out[i] += a * At[j * n + i]
    for j in range(m):
        a = u[j]
        for i in range(n):
            out[i] += a * Bt[j * n + i]


@numba.njit(cache=True, nogil=True)
def tria(b, o, r, c):  # pragma: no cover - compiled
    """In place: ``W`` (r x c at ``o``, c ≥ r) → ``[L 0]``, ``L`` lower, diagonal ≥ 0, ``L Lᵀ = W Wᵀ`` (Householder)."""
    W = b[o:o + r * c]
    for k in range(r):
        s = 0.0
        for j in range(k, c):
            s += W[k * c + j] * W[k * c + j]
        nrm = math.sqrt(s)
        if nrm == 0.0:
            continue
        w0 = W[k * c + k]
        alpha = -nrm if w0 >= 0.0 else nrm
        v0 = w0 - alpha  # v = W[k, k:] − alpha e₁
        vv = v0 * v0 + (s - w0 * w0)
        if vv == 0.0:
            continue
        for i in range(k + 1, r):
            d = W[i * c + k] * v0
            for j in range(k + 1, c):
                d += W[i * c + j] * W[k * c + j]
            f = 2.0 * d / vv
            W[i * c + k] -= f * v0
            for j in range(k + 1, c):
                W[i * c + j] -= f * W[k * c + j]
        W[k * c + k] = alpha
        for j in range(k + 1, c):
            W[k * c + j] = 0.0
    for k in range(r):
        if W[k * c + k] < 0.0:
            for i in range(k, r):
                W[i * c + k] = -W[i * c + k]


@numba.njit(cache=True, nogil=True)
def gram(b, oX, ld, k, oO, r):  # pragma: no cover - compiled
    """``O (r x r) = X Xᵀ`` for the r rows of ``X`` (row stride ``ld``, first k columns)."""
    X, O = b[oX:oX + r * ld], b[oO:oO + r * r]
    for i in range(r):
        for j in range(i + 1):
            s = 0.0
            for q in range(k):
                s += X[i * ld + q] * X[j * ld + q]
            O[i * r + j] = s
            O[j * r + i] = s


_IN = numba.types.Array(numba.types.float64, 1, "C", readonly=True)  # read-only inputs accept writable arrays
#: the signature of every step kernel: (u, y, buffer) -> status
STEP_SIGNATURE = numba.types.int64(_IN, _IN, numba.types.float64[::1])
_COMPILED: dict = {}


def compiled(kernel):
    """The kernel compiled for :data:`STEP_SIGNATURE` — on first use, so only the kernels in use are compiled.

    The dispatcher has an explicit signature (an argument of another type raises ``TypeError``, nothing is
    recompiled) and ``cache=True`` (the machine code is loaded from ``__pycache__`` by later processes).

    Parameters
    ----------
    kernel : function
        A step kernel of this package, e.g. :func:`fdikit.runtime.kalman_kernels.kalman_step`.

    Returns
    -------
    numba dispatcher
        Callable as ``kernel(u, y, buf) -> int``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.runtime.kalman_kernels import kalman_layout, kalman_step
    >>> compiled(kalman_step)(np.zeros(0), np.zeros(2), kalman_layout(1, 0, 1, 0)[0])  # 2 values, 1 output
    -1
    """
    d = _COMPILED.get(kernel.__name__)
    if d is None:
        d = _COMPILED[kernel.__name__] = numba.njit(STEP_SIGNATURE, cache=True, nogil=True)(kernel)
    return d
