"""Numba kernel of the compiled IMM cycle (mode-matched updates, log-space mode probabilities, fusion, mixing).

What is compiled: one :meth:`fdikit.multimodel.imm.IMMStepper.step` — Hallouzi 2008, §2.3.1, Table 2.1 (after
Li & Jilkov 2005) with the reference's two corrections and its sample convention: the measurement update of
every mode with ``Σ = C P(k|k−1) Cᵀ + R`` (step 2), the mode probabilities updated in log space with
log-sum-exp (step 3, the likelihood (2.12)), the fusion (step 4), the mixing with ``μ_{k|k−1}`` by log-sum-exp
(step 1, the mixing covariance summing the mixed modes' own ``P^(i)``) and the time update.  Why hand-written:
no library compiles this cycle; the reference's cost is numpy call overhead on tiny matrices.

The filter lives in one flat float64 buffer (:func:`imm_layout` gives the offsets, stored in the header).  The
innovation covariance is factored by Cholesky (the reference solves by LU and takes ``slogdet``), and products
are summed in another order: the numbers equal the reference's to rounding.

Examples
--------
>>> buf = imm_layout(2, 1, 0, 1)[0]
>>> int(buf[0]), int(buf[1])
(2, 1)

References
----------
Hallouzi 2008, §2.3.1, Table 2.1, (2.3)–(2.7), (2.12).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from fdikit.runtime.buffer_linalg import (
    affine,
    copy,
    fill,
    gemm,
    gemm_tn,
    gemv_t,
    ger,
    ldl,
    ldl_quad,
    log_diag,
    residual,
    symmetrise,
    unit_forward_rows,
)

__all__ = ["imm_layout", "imm_step", "IMM_FIELDS", "I_M", "I_N", "I_MI", "I_P", "I_FLOOR", "I_LL", "I_VALID"]

_LOG2PI = math.log(2.0 * math.pi)

# header slots: modes, states, inputs, outputs, log of the probability floor (−inf: none), the last sample's
# log p(y_k | Y_k−1) and validity
I_M, I_N, I_MI, I_P, I_FLOOR, I_LL, I_VALID = range(7)
_HEAD = 8
#: buffer fields in order; their offsets follow the header's scalar slots
IMM_FIELDS = ("A", "At", "Bt", "C", "Ct", "Dt", "Q", "R", "logPi",         # model
              "xp", "Pp", "lmp", "lmu",                                  # state: priors, log μ(k|k−1), log μ(k|k)
              "mu", "xf", "Pf", "x", "P", "z", "S",                      # outputs
              "CP", "W2", "L", "wp", "G", "lp", "xbar", "Pbar", "T", "d")  # work space
(_A, _AT, _B, _C, _CT, _D, _Q, _R, _LPI, _XP, _PP, _LMP, _LMU, _MU, _XF, _PF, _X, _PX, _Z, _S, _CP, _W2, _L, _WP,
 _G, _LP, _XBAR, _PBAR, _T, _DD) = range(_HEAD, _HEAD + len(IMM_FIELDS))


def imm_layout(M: int, n: int, m: int, p: int) -> tuple[np.ndarray, dict[str, tuple[int, tuple[int, ...]]]]:
    """A zeroed kernel buffer with its header set, and each field's ``(offset, shape)``.

    Parameters
    ----------
    M, n, m, p : int
        Modes, states, inputs, outputs.

    Returns
    -------
    buf : ndarray
        The float64 buffer (header filled, no probability floor, fields zero).
    fields : dict
        ``name -> (offset, shape)`` for :data:`IMM_FIELDS`.

    Examples
    --------
    >>> buf, fields = imm_layout(3, 2, 1, 1)
    >>> fields["Pp"][1], fields["logPi"][1]
    ((3, 2, 2), (3, 3))
    """
    shapes = {"A": (M, n, n), "At": (M, n, n), "Bt": (M, m, n), "C": (M, p, n), "Ct": (M, n, p), "Dt": (M, m, p),
              "Q": (M, n, n), "R": (M, p, p), "logPi": (M, M), "xp": (M, n), "Pp": (M, n, n), "lmp": (M,),
              "lmu": (M,), "mu": (M,), "xf": (M, n), "Pf": (M, n, n), "x": (n,), "P": (n, n), "z": (M, p),
              "S": (M, p, p), "CP": (p, n), "W2": (p, n), "L": (p, p), "wp": (p,), "G": (M, M), "lp": (M,),
              "xbar": (n,), "Pbar": (n, n), "T": (n, n), "d": (n,)}
    fields, off = {}, _HEAD + len(IMM_FIELDS)
    for name in IMM_FIELDS:
        fields[name] = (off, shapes[name])
        off += int(np.prod(shapes[name]))
    buf = np.zeros(off)
    buf[[I_M, I_N, I_MI, I_P]] = M, n, m, p
    buf[I_FLOOR] = -np.inf
    for i, name in enumerate(IMM_FIELDS):
        buf[_HEAD + i] = fields[name][0]
    return buf, fields


@numba.njit(cache=True, nogil=True)
def _logsumexp(b, o, size):  # pragma: no cover - compiled
    """``log Σ exp(b[o:o+size])``; −inf when every entry is −inf (``imm._logsumexp``)."""
    mx = -np.inf
    for i in range(o, o + size):
        mx = max(mx, b[i])
    if not mx > -np.inf:
        return -np.inf
    s = 0.0
    for i in range(o, o + size):
        s += math.exp(b[i] - mx)
    return mx + math.log(s)


@numba.njit(cache=True, nogil=True, inline="always")  # one call site: compiled with its caller
def _update(b, y, u, M, n, p):  # pragma: no cover - compiled
    """Step 2, measurement update of every mode into ``xf, Pf, z, S``; ``lp`` ← the log-likelihoods (2.12)."""
    m = u.shape[0]
    oC, oCt, oD, oR = int(b[_C]), int(b[_CT]), int(b[_D]), int(b[_R])
    oxp, oPp, oxf, oPf, oz, oS = int(b[_XP]), int(b[_PP]), int(b[_XF]), int(b[_PF]), int(b[_Z]), int(b[_S])
    oCP, oW2, oL, owp, olp = int(b[_CP]), int(b[_W2]), int(b[_L]), int(b[_WP]), int(b[_LP])
    nn, pn, pp = n * n, p * n, p * p
    for j in range(M):
        Cj, Pj, Sj, Pfj, xfj, zj = oC + j * pn, oPp + j * nn, oS + j * pp, oPf + j * nn, oxf + j * n, oz + j * p
        residual(b, y, u, oCt + j * n * p, oxp + j * n, oD + j * m * p, zj, p, n)   # z = y − C x̂ − D u
        fill(b, oCP, pn, 0.0)
        gemm(b, Cj, Pj, oCP, p, n, n, 1.0)                             # C P
        copy(b, oR + j * pp, Sj, pp)
        gemm(b, oCP, oCt + j * n * p, Sj, p, n, p, 1.0)                # Σ = C P Cᵀ + R
        symmetrise(b, Sj, p)
        if not ldl(b, Sj, oL, p):                                      # Σ = L D Lᵀ
            return False
        quad = ldl_quad(b, oL, zj, owp, p)                             # zᵀ Σ⁻¹ z;  w = L⁻¹ z
        unit_forward_rows(b, oL, oCP, p, n)                            # V = L⁻¹ C P
        for i in range(p):                                             # D⁻¹ w, D⁻¹ V
            d = b[oL + i * p + i]
            b[owp + i] /= d
            for a in range(n):
                b[oW2 + i * n + a] = b[oCP + i * n + a] / d
        copy(b, oxp + j * n, xfj, n)
        gemv_t(b, oCP, owp, xfj, n, p)                                 # x + P Cᵀ Σ⁻¹ z = x + Vᵀ D⁻¹ w
        copy(b, Pj, Pfj, nn)
        gemm_tn(b, oCP, oW2, Pfj, n, p, n, -1.0)                       # P − P Cᵀ Σ⁻¹ C P = P − Vᵀ D⁻¹ V
        symmetrise(b, Pfj, n)
        b[olp + j] = -0.5 * (quad + log_diag(b, oL, p, p) + p * _LOG2PI)  # log det Σ = Σ log D
    return True


def imm_step(u, y, b) -> int:  # pragma: no cover - compiled
    """One ``IMMStepper.step`` on the buffer of :func:`imm_layout` (run it compiled, ``buffer_linalg.compiled``).

    Parameters
    ----------
    u, y : ndarray
        ``u_k`` (m) and ``y_k`` (p), float64; a NaN/inf in ``y`` makes a prediction-only sample.
    b : ndarray
        The filter's buffer, updated in place.

    Returns
    -------
    int
        0 done, -1 wrong length of ``u``/``y``, 1 a NaN/inf in ``u``, 2 an innovation covariance that is not
        positive definite (in both error cases nothing of the state has changed).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.runtime.buffer_linalg import compiled
    >>> b, f = imm_layout(1, 1, 0, 1)
    >>> for name in ("A", "At", "C", "Ct", "R", "Pp"):
    ...     b[f[name][0]] = 1.0
    >>> compiled(imm_step)(np.zeros(0), np.ones(1), b), float(b[f["x"][0]]), float(b[f["mu"][0]])
    (0, 0.5, 1.0)
    """
    M, n, m, p = int(b[I_M]), int(b[I_N]), int(b[I_MI]), int(b[I_P])
    if u.shape[0] != m or y.shape[0] != p:
        return -1
    for k in range(m):
        if not np.isfinite(u[k]):
            return 1
    bad = 0
    for k in range(p):
        if not np.isfinite(y[k]):
            bad += 1
    ok = bad == 0
    nn = n * n
    oxp, oPp, oxf, oPf = int(b[_XP]), int(b[_PP]), int(b[_XF]), int(b[_PF])
    olmp, olmu, omu, olp = int(b[_LMP]), int(b[_LMU]), int(b[_MU]), int(b[_LP])
    if ok:
        if not _update(b, y, u, M, n, p):      # lp ← log-likelihoods
            return 2
        for j in range(M):                      # step 3 in log space
            b[olp + j] += b[olmp + j]
        ll = _logsumexp(b, olp, M)
        for j in range(M):
            b[olmu + j] = b[olp + j] - ll
    else:
        copy(b, oxp, oxf, M * n)
        copy(b, oPp, oPf, M * nn)
        fill(b, int(b[_Z]), M * p, np.nan)
        fill(b, int(b[_S]), M * p * p, np.nan)
        ll = np.nan
        copy(b, olmp, olmu, M)
    b[I_LL] = ll
    b[I_VALID] = 1.0 if ok else 0.0
    # step 4: fusion (output only)
    ox, oP, od = int(b[_X]), int(b[_PX]), int(b[_DD])
    for j in range(M):
        b[omu + j] = math.exp(b[olmu + j])
    fill(b, ox, n, 0.0)
    gemv_t(b, oxf, omu, ox, n, M)                # Σ μ_j x̂_j
    fill(b, oP, nn, 0.0)
    gemv_t(b, oPf, omu, oP, nn, M)               # Σ μ_j P_j
    for j in range(M):
        for a in range(n):
            b[od + a] = b[oxf + j * n + a] - b[ox + a]
        ger(b, od, oP, n, b[omu + j])              # + μ_j d dᵀ
    # step 1: mixing with μ(k+1|k) = Σ_i Π_ij μ_i (log-sum-exp), then step 2's time update with u_k
    oPi, oG = int(b[_LPI]), int(b[_G])
    for j in range(M):  # G[j, i] = log Π_ij + log μ_i (stored by destination mode j)
        for i in range(M):
            b[oG + j * M + i] = b[oPi + i * M + j] + b[olmu + i]
        b[olp + j] = _logsumexp(b, oG + j * M, M)
    oA, oAt, oB, oQ = int(b[_A]), int(b[_AT]), int(b[_B]), int(b[_Q])
    oxb, oPb, oT = int(b[_XBAR]), int(b[_PBAR]), int(b[_T])
    for j in range(M):
        lpj = b[olp + j]
        reach = np.isfinite(lpj)
        for i in range(M):  # G[j, i] ← μ^{i|j}
            g = oG + j * M + i
            b[g] = math.exp(b[g] - lpj) if reach else b[omu + i]
        fill(b, oxb, n, 0.0)
        fill(b, oPb, nn, 0.0)
        for i in range(M):
            w = b[oG + j * M + i]
            for a in range(n):
                b[oxb + a] += w * b[oxf + i * n + a]
            for a in range(nn):
                b[oPb + a] += w * b[oPf + i * nn + a]
        for i in range(M):
            for a in range(n):
                b[od + a] = b[oxf + i * n + a] - b[oxb + a]
            ger(b, od, oPb, n, b[oG + j * M + i])
        affine(b, u, oAt + j * nn, oxb, oB + j * m * n, oxp + j * n, n)   # x̂ = A x̄ + B u
        fill(b, oT, nn, 0.0)
        gemm(b, oA + j * nn, oPb, oT, n, n, n, 1.0)                    # A P̄
        copy(b, oQ + j * nn, oPp + j * nn, nn)
        gemm(b, oT, oAt + j * nn, oPp + j * nn, n, n, n, 1.0)          # A P̄ Aᵀ + Q
    if b[I_FLOOR] > -np.inf:
        for j in range(M):
            b[olp + j] = max(b[olp + j], b[I_FLOOR])
        s = _logsumexp(b, olp, M)
        for j in range(M):
            b[olp + j] -= s
    copy(b, olp, olmp, M)
    return 0
