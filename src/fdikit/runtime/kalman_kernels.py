"""Numba kernels of the compiled Kalman filter step (covariance and square-root forms).

What is compiled: one sample of :meth:`fdikit.multimodel.kalman.KalmanFilter.step` — the Joseph-form measurement
update and the time update of :func:`fdikit.multimodel.kalman_steps.kf_update` / ``kf_predict`` (Hallouzi 2008,
§2.3.1, Table 2.1 step 2, the likelihood (2.12)), the reference's switch to the steady-state filter once
``P(k+1|k)`` has settled, and the square-root twins ``srkf_update`` / ``srkf_predict`` (Hallouzi 2008, §2.3.2,
(2.29)–(2.31)) with a Householder ``tria``.  Why hand-written: no library compiles these steps; the reference's
per-sample cost is numpy call overhead on small matrices, which one compiled call removes.

The filter lives in one flat float64 buffer (model, state, outputs, work space; :func:`kalman_layout` gives the
offsets, stored in the buffer's header), so a step is one call with three arguments.  Products are summed in
another order than numpy's BLAS, the gain comes from a Cholesky instead of an LU solve, and symmetric products
are formed from one triangle: the numbers equal the reference's to rounding.

Examples
--------
>>> import numpy as np
>>> buf = kalman_layout(1, 0, 1, 0)[0]
>>> int(buf[0]), int(buf[2])
(1, 1)

References
----------
Hallouzi 2008, §2.3.1, Table 2.1 step 2, (2.12); §2.3.2, (2.29)–(2.31).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from fdikit.runtime.buffer_linalg import (
    affine,
    chol,
    copy,
    fill,
    forward,
    gemm,
    gemm_tn,
    gemv_t,
    gram,
    ldl,
    ldl_quad,
    ldl_solve_rows,
    log_diag,
    residual,
    symmetrise,
    tria,
)

__all__ = ["kalman_layout", "kalman_step", "srkf_step", "checks", "KF_FIELDS", "SETTLED", "H_N", "H_M", "H_P",
           "H_FORM", "H_COUNT", "H_STEADY", "H_FRESH", "H_VALID", "H_LL", "H_CONST"]

#: relative change of P(k+1|k) below which the reference switches to the steady-state filter (kalman._SETTLED)
SETTLED = 1e-14
_TINY = 1e-300
_LOG2PI = math.log(2.0 * math.pi)

# header slots: dimensions, form (0 covariance, 1 square root), settling counter, steady flag, "the outputs
# hold the steady cache", validity and log-likelihood of the last sample, the steady log-density constant
H_N, H_M, H_P, H_FORM, H_COUNT, H_STEADY, H_FRESH, H_VALID, H_LL, H_CONST = range(10)
#: buffer fields in order; their offsets follow the 10 scalar slots of the header
KF_FIELDS = ("A", "At", "Bt", "C", "Ct", "Dt", "Q", "R", "Qs", "Rs",      # model (Qs, Rs: lower factors)
             "x", "P", "Sx",                                             # state x̂(k|k−1), P(k|k−1), its factor
             "xf", "Pf", "e", "S", "KT",                                 # outputs (KT: the gain, transposed)
             "KsT", "LiT", "Pfs", "Ss",                                  # steady-state cache (LiT: L⁻ᵀ)
             "CP", "L", "Sw", "T1", "T2", "IKt", "wn", "wp", "pre")       # work space
(_A, _AT, _B, _C, _CT, _D, _Q, _R, _QS, _RS, _X, _P, _SX, _XF, _PF, _E, _S, _KT, _KST, _LIT, _PFS, _SS, _CP,
 _L, _SW, _T1, _T2, _IKT, _WN, _WP, _PRE) = range(10, 10 + len(KF_FIELDS))


def kalman_layout(n: int, m: int, p: int, form: int) -> tuple[np.ndarray, dict[str, tuple[int, tuple[int, ...]]]]:
    """A zeroed kernel buffer with its header set, and each field's ``(offset, shape)``.

    Parameters
    ----------
    n, m, p : int
        States, inputs, outputs.
    form : int
        0 covariance (Joseph) form, 1 square-root form.

    Returns
    -------
    buf : ndarray
        The float64 buffer (header filled, fields zero).
    fields : dict
        ``name -> (offset, shape)`` for :data:`KF_FIELDS`.

    Examples
    --------
    >>> buf, fields = kalman_layout(2, 1, 1, 0)
    >>> fields["Bt"][1], int(buf[1])
    ((1, 2), 1)
    """
    nb = n + p
    shapes = {"A": (n, n), "At": (n, n), "Bt": (m, n), "C": (p, n), "Ct": (n, p), "Dt": (m, p), "Q": (n, n),
              "R": (p, p), "Qs": (n, n), "Rs": (p, p), "x": (n,), "P": (n, n), "Sx": (n, n), "xf": (n,),
              "Pf": (n, n), "e": (p,), "S": (p, p), "KT": (p, n), "KsT": (p, n), "LiT": (p, p), "Pfs": (n, n),
              "Ss": (p, p), "CP": (p, n), "L": (p, p), "Sw": (p, p), "T1": (n, n), "T2": (n, n), "IKt": (n, n),
              "wn": (n,), "wp": (p,), "pre": (max(nb * nb, 2 * n * n),)}
    head = 10 + len(KF_FIELDS)
    fields, off = {}, head
    for name in KF_FIELDS:
        fields[name] = (off, shapes[name])
        off += int(np.prod(shapes[name]))
    buf = np.zeros(off)
    buf[[H_N, H_M, H_P, H_FORM]] = n, m, p, form
    for i, name in enumerate(KF_FIELDS):
        buf[10 + i] = fields[name][0]
    return buf, fields


# ---------------------------------------------------------------------------------------- covariance form
@numba.njit(cache=True, nogil=True)
def _gain(b, oP, oS, oKT, oPf, n, p):  # pragma: no cover - compiled
    """From ``P``: ``S = C P Cᵀ + R`` (into ``oS``), ``L D Lᵀ = S``, ``Kᵀ = S⁻¹ C P``, Joseph ``P(k|k)``.

    False (before ``Kᵀ``, ``P(k|k)`` are written) when ``S`` is not positive definite.
    """
    oC, oCt, oR, oCP, oL = int(b[_C]), int(b[_CT]), int(b[_R]), int(b[_CP]), int(b[_L])
    oT1, oIK = int(b[_T1]), int(b[_IKT])
    fill(b, oCP, p * n, 0.0)
    gemm(b, oC, oP, oCP, p, n, n, 1.0)        # C P = (P Cᵀ)ᵀ
    copy(b, oR, oS, p * p)
    gemm(b, oCP, oCt, oS, p, n, p, 1.0)       # S = C P Cᵀ + R
    symmetrise(b, oS, p)
    if not ldl(b, oS, oL, p):
        return False
    copy(b, oCP, oKT, p * n)
    ldl_solve_rows(b, oL, oKT, p, n)          # Kᵀ = S⁻¹ C P
    fill(b, oIK, n * n, 0.0)                  # (I − K C)ᵀ = I − Cᵀ Kᵀ
    for i in range(n):
        b[oIK + i * n + i] = 1.0
    gemm(b, oCt, oKT, oIK, n, p, n, -1.0)
    fill(b, oT1, n * n, 0.0)
    gemm(b, oP, oIK, oT1, n, n, n, 1.0)       # P (I − K C)ᵀ
    fill(b, oPf, n * n, 0.0)
    gemm_tn(b, oIK, oT1, oPf, n, n, n, 1.0)   # (I − K C) P (I − K C)ᵀ
    fill(b, oCP, n * p, 0.0)
    gemm_tn(b, oKT, oR, oCP, n, p, p, 1.0)    # K R (n x p, in the C P work space)
    gemm(b, oCP, oKT, oPf, n, p, n, 1.0)      # + K R Kᵀ
    symmetrise(b, oPf, n)
    return True


@numba.njit(cache=True, nogil=True, inline="always")  # one call site: compiled with its caller
def _settle(b, n, p):  # pragma: no cover - compiled
    """The reference's steady-state cache from the settled ``P``: gain, ``L⁻¹``, ``P(k|k)``, ``S``, constant."""
    oL, oLi, oSs = int(b[_L]), int(b[_LIT]), int(b[_SS])
    if not (_gain(b, int(b[_P]), oSs, int(b[_KST]), int(b[_PFS]), n, p) and chol(b, oSs, oL, p)):
        return False
    fill(b, oLi, p * p, 0.0)
    for j in range(p):  # L⁻¹ column by column, stored transposed (row j of L⁻ᵀ = column j of L⁻¹)
        b[oLi + j * p + j] = 1.0 / b[oL + j * p + j]
        for i in range(j + 1, p):
            s = 0.0
            for k in range(j, i):
                s -= b[oL + i * p + k] * b[oLi + j * p + k]
            b[oLi + j * p + i] = s / b[oL + i * p + i]
    b[H_CONST] = -0.5 * p * _LOG2PI - log_diag(b, oL, p, p)
    return True


@numba.njit(cache=True, nogil=True, inline="always")  # one call site: compiled with its caller
def _steady_step(b, y, u, n, p):  # pragma: no cover - compiled
    """``KalmanFilter._steady_step``: the constant-gain update and the prediction (one fused pass, local views)."""
    m = u.shape[0]
    if b[H_FRESH] == 0.0:  # first steady sample: the outputs take the cached P(k|k), S, gain (as the reference)
        copy(b, int(b[_PFS]), int(b[_PF]), n * n)
        copy(b, int(b[_SS]), int(b[_S]), p * p)
        copy(b, int(b[_KST]), int(b[_KT]), p * n)
        b[H_FRESH] = 1.0
    ox, oxf, oe, ow, oK, oL = int(b[_X]), int(b[_XF]), int(b[_E]), int(b[_WP]), int(b[_KST]), int(b[_LIT])
    oCt, oDt, oAt, oBt = int(b[_CT]), int(b[_D]), int(b[_AT]), int(b[_B])
    x, xf, e, w = b[ox:ox + n], b[oxf:oxf + n], b[oe:oe + p], b[ow:ow + p]
    Ct, Dt, KT, LiT = b[oCt:oCt + n * p], b[oDt:oDt + m * p], b[oK:oK + p * n], b[oL:oL + p * p]
    At, Bt = b[oAt:oAt + n * n], b[oBt:oBt + m * n]
    for i in range(p):                       # e = y − C x − D u
        e[i] = y[i]
        w[i] = 0.0
    for j in range(n):
        a = x[j]
        xf[j] = a
        for i in range(p):
            e[i] -= a * Ct[j * p + i]
    for j in range(m):
        a = u[j]
        for i in range(p):
            e[i] -= a * Dt[j * p + i]
    for j in range(p):                       # x̂(k|k) = x + K e;  w = L⁻¹ e
        a = e[j]
        for i in range(n):
            xf[i] += a * KT[j * n + i]
        for i in range(j, p):
            w[i] += a * LiT[j * p + i]
    for i in range(n):                       # x̂(k+1|k) = A x̂(k|k) + B u
        x[i] = 0.0
    for j in range(n):
        a = xf[j]
        for i in range(n):
            x[i] += a * At[j * n + i]
    for j in range(m):
        a = u[j]
        for i in range(n):
            x[i] += a * Bt[j * n + i]
    q = 0.0
    for i in range(p):
        q += w[i] * w[i]
    b[H_LL] = b[H_CONST] - 0.5 * q


@numba.njit(cache=True, nogil=True, inline="always")  # one call site: compiled with its caller
def _covariance_step(b, y, u, n, p, valid):  # pragma: no cover - compiled
    """``KalmanFilter.step`` (covariance form): recursion, settling test and switch; status 0 or 2."""
    ox, oP, oxf, oPf, oe, oS = int(b[_X]), int(b[_P]), int(b[_XF]), int(b[_PF]), int(b[_E]), int(b[_S])
    oT1, oT2 = int(b[_T1]), int(b[_T2])
    if valid:
        oSw = int(b[_SW])
        if not _gain(b, oP, oSw, int(b[_KT]), oPf, n, p):
            return 2
        copy(b, oSw, oS, p * p)
        residual(b, y, u, int(b[_CT]), ox, int(b[_D]), oe, p, n)
        copy(b, ox, oxf, n)
        gemv_t(b, int(b[_KT]), oe, oxf, n, p)
        oL = int(b[_L])
        q = ldl_quad(b, oL, oe, int(b[_WP]), p)  # eᵀ S⁻¹ e;  log det S = Σ log D
        b[H_LL] = -0.5 * (q + log_diag(b, oL, p, p) + p * _LOG2PI)
    else:
        copy(b, ox, oxf, n)
        copy(b, oP, oPf, n * n)
        fill(b, oe, p, np.nan)
        fill(b, oS, p * p, np.nan)
        b[H_LL] = np.nan
    b[H_FRESH] = 0.0
    affine(b, u, int(b[_AT]), oxf, int(b[_B]), ox, n)
    fill(b, oT1, n * n, 0.0)
    gemm(b, int(b[_A]), oPf, oT1, n, n, n, 1.0)
    copy(b, int(b[_Q]), oT2, n * n)
    gemm(b, oT1, int(b[_AT]), oT2, n, n, n, 1.0)   # A P Aᵀ + Q
    symmetrise(b, oT2, n)
    change, big = 0.0, 0.0
    for i in range(n * n):
        change = max(change, abs(b[oT2 + i] - b[oP + i]))
        big = max(big, abs(b[oT2 + i]))
    copy(b, oT2, oP, n * n)
    ok = valid and change <= SETTLED * max(big, _TINY)
    b[H_COUNT] = b[H_COUNT] + 1.0 if ok else 0.0
    if not ok:
        b[H_STEADY] = 0.0
    elif b[H_COUNT] >= 3.0 and b[H_STEADY] == 0.0:
        b[H_STEADY] = 1.0 if _settle(b, n, p) else 0.0
    return 0


# ---------------------------------------------------------------------------------------- square-root form
@numba.njit(cache=True, nogil=True, inline="always")  # one call site: compiled with its caller
def _sqrt_step(b, y, u, n, p, valid):  # pragma: no cover - compiled
    """``KalmanFilter.step`` (square-root form): ``srkf_update`` + ``srkf_predict``; status 0 or 2."""
    ox, oSx, oxf, oe, oS = int(b[_X]), int(b[_SX]), int(b[_XF]), int(b[_E]), int(b[_S])
    oT1, oT2, oW, owp = int(b[_T1]), int(b[_T2]), int(b[_PRE]), int(b[_WP])
    if valid:
        nb = n + p
        oC, oRs = int(b[_C]), int(b[_RS])
        fill(b, oW, nb * nb, 0.0)                 # [[R½, C S], [0, S]]
        for i in range(p):
            for j in range(p):
                b[oW + i * nb + j] = b[oRs + i * p + j]
            for k in range(n):
                a = b[oC + i * n + k]
                for j in range(n):
                    b[oW + i * nb + p + j] += a * b[oSx + k * n + j]
        for i in range(n):
            for j in range(n):
                b[oW + (p + i) * nb + p + j] = b[oSx + i * n + j]
        tria(b, oW, nb, nb)                      # [[R_e, 0], [G, S(k|k)]]
        for i in range(p):
            if abs(b[oW + i * nb + i]) <= 1e-300:
                return 2
        residual(b, y, u, int(b[_CT]), ox, int(b[_D]), oe, p, n)
        q = forward(b, oW, nb, oe, owp, p)
        for i in range(n):                        # x⁺ = x + G R_e⁻¹ e
            s = b[ox + i]
            for j in range(p):
                s += b[oW + (p + i) * nb + j] * b[owp + j]
            b[oxf + i] = s
            for j in range(n):
                b[oT1 + i * n + j] = b[oW + (p + i) * nb + p + j]
        gram(b, oW, nb, p, oS, p)                # S = R_e R_eᵀ
        b[H_LL] = -0.5 * (q + 2.0 * log_diag(b, oW, nb, p) + p * _LOG2PI)
    else:
        copy(b, ox, oxf, n)
        copy(b, oSx, oT1, n * n)
        fill(b, oe, p, np.nan)
        fill(b, oS, p * p, np.nan)
        b[H_LL] = np.nan
    gram(b, oT1, n, n, int(b[_PF]), n)
    affine(b, u, int(b[_AT]), oxf, int(b[_B]), ox, n)
    fill(b, oT2, n * n, 0.0)
    gemm(b, int(b[_A]), oT1, oT2, n, n, n, 1.0)   # [A S(k|k), Q½] → S(k+1|k)
    oQs = int(b[_QS])
    for i in range(n):
        for j in range(n):
            b[oW + i * 2 * n + j] = b[oT2 + i * n + j]
            b[oW + i * 2 * n + n + j] = b[oQs + i * n + j]
    tria(b, oW, n, 2 * n)
    for i in range(n):
        for j in range(n):
            b[oSx + i * n + j] = b[oW + i * 2 * n + j]
    gram(b, oSx, n, n, int(b[_P]), n)
    return 0


def _checks(u, y, buf):  # pragma: no cover - compiled
    """Status -1 for wrong lengths, 1 for a NaN/inf input, else 0 (valid y) or 3 (a NaN/inf in y)."""
    m, p = int(buf[H_M]), int(buf[H_P])
    if u.shape[0] != m or y.shape[0] != p:
        return -1
    for j in range(m):
        if not np.isfinite(u[j]):
            return 1
    bad = 0
    for j in range(p):
        if not np.isfinite(y[j]):
            bad += 1
    return 0 if bad == 0 else 3


checks = numba.njit(cache=True, nogil=True, inline="always")(_checks)


def kalman_step(u, y, buf) -> int:  # pragma: no cover - compiled
    """One covariance-form ``KalmanFilter.step`` on the buffer of :func:`kalman_layout` (run it compiled).

    Parameters
    ----------
    u, y : ndarray
        ``u(k)`` (m) and ``y(k)`` (p), float64; a NaN/inf in ``y`` skips the measurement update.
    buf : ndarray
        The filter's buffer, updated in place.

    Returns
    -------
    int
        0 done, -1 wrong length of ``u``/``y``, 1 a NaN/inf in ``u`` (nothing changed), 2 the innovation
        covariance is not positive definite (nothing changed but the work space).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.runtime.buffer_linalg import compiled
    >>> buf, f = kalman_layout(1, 0, 1, 0)
    >>> for name, v in (("A", 0.9), ("At", 0.9), ("C", 1.0), ("Ct", 1.0), ("Q", 0.1), ("R", 1.0), ("P", 1.0)):
    ...     buf[f[name][0]] = v
    >>> compiled(kalman_step)(np.zeros(0), np.ones(1), buf), float(buf[f["xf"][0]]), float(buf[f["x"][0]])
    (0, 0.5, 0.45)
    """
    status = checks(u, y, buf)
    if status == 1 or status == -1:
        return status
    n, p = int(buf[H_N]), int(buf[H_P])
    valid = status == 0
    if valid and buf[H_STEADY] != 0.0:
        _steady_step(buf, y, u, n, p)
        status = 0
    else:
        status = _covariance_step(buf, y, u, n, p, valid)
    if status == 0:
        buf[H_VALID] = 1.0 if valid else 0.0
    return status


def srkf_step(u, y, buf) -> int:  # pragma: no cover - compiled
    """One square-root-form ``KalmanFilter.step`` on the buffer of :func:`kalman_layout` (run it compiled).

    Parameters
    ----------
    u, y : ndarray
        ``u(k)`` (m) and ``y(k)`` (p), float64; a NaN/inf in ``y`` skips the measurement update.
    buf : ndarray
        The filter's buffer (form 1), updated in place.

    Returns
    -------
    int
        As :func:`kalman_step`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.runtime.buffer_linalg import compiled
    >>> buf, f = kalman_layout(1, 0, 1, 1)
    >>> for name, v in (("A", 0.9), ("C", 1.0), ("Qs", 0.1 ** 0.5), ("Rs", 1.0), ("Sx", 1.0)):
    ...     buf[f[name][0]] = v
    >>> status = compiled(srkf_step)(np.zeros(0), np.ones(1), buf)
    >>> status, round(float(buf[f["xf"][0]]), 12), round(float(buf[f["P"][0]]), 12)
    (0, 0.5, 0.505)
    """
    status = checks(u, y, buf)
    if status == 1 or status == -1:
        return status
    valid = status == 0
    status = _sqrt_step(buf, y, u, int(buf[H_N]), int(buf[H_P]), valid)
    if status == 0:
        buf[H_VALID] = 1.0 if valid else 0.0
    return status
