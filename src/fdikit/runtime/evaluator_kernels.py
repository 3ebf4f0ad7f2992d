"""numba kernels of the compiled residual evaluators: one online step per evaluator kind, and a batch threshold pass.

Each ``*_step`` kernel is called as ``kernel(r, valid, *state)`` and returns an int64 status: 0 no alarm, 1 alarm,
-1 when ``r`` has the wrong length (nothing is changed then).  ``state`` is the tuple of parameter and state arrays
that :func:`fdikit.runtime.evaluators.compile_evaluator` builds from a fitted reference evaluator; the kernels
mutate the state arrays in place.  Element 0 of each kernel's ``info`` array is 1 when the last sample was used and
0 when it was held (a NaN/inf entry or ``valid=False``: the statistics and the decision keep their values, as the
reference ``step`` holds them).

Every kernel repeats the reference's arithmetic in the reference's order (the threshold test and k-of-n counts of
:mod:`fdikit.decision.threshold`; Page's recursion with its restarts and rebase of :mod:`fdikit.decision.cusum`;
the whitened window sums of :mod:`fdikit.decision.glr`; Wald's increments of :mod:`fdikit.decision.sprt`; the
log-space Bayes filter of :mod:`fdikit.decision.mhsprt` with numpy's pairwise summation and ``logaddexp``), so the
compiled and the reference states agree to rounding of ``exp``/``log`` (the comparisons, sums and products are the
same IEEE operations).

Why hand-written: no library compiles these recursions; the reference steps spend their time in per-call numpy
overhead, not arithmetic.

References
----------
Douglas et al. 1996, Ch. 1 (thresholds) and §7.2.1, Prop. 7.1 (the Shiryayev recursion); Page 1954 and
Basseville & Nikiforov 1993, §2.2 (CUSUM), §2.4 (GLR, Willsky & Jones 1976); Wald 1947 (SPRT).

Examples
--------
>>> import numpy as np
>>> from fdikit.runtime.evaluator_kernels import pairwise_sum
>>> float(pairwise_sum(np.arange(10.0)))
45.0
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["cusum_step", "glr_step", "mhsprt_step", "pairwise_sum", "sprt_step", "threshold_batch",
           "threshold_step"]

_LOGE2 = 0.693147180559945309417232121458176568  # numpy's NPY_LOGE2, used by np.logaddexp for equal arguments


@numba.njit(cache=True, nogil=True)
def pairwise_sum(a):  # pragma: no cover - compiled
    """``np.sum`` of a 1-D float64 array with numpy's own pairwise order (bit-identical to ``a.sum()``).

    Parameters
    ----------
    a : (n,) float64 array
        The values.

    Returns
    -------
    float
        Their sum, added in numpy's order (8 accumulators per block of 128, halves above).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([1e16, 1.0, -1e16, 1.0, 3.0, 1e-3, 7.0, 1.0, 2.0])
    >>> float(pairwise_sum(x)) == float(x.sum())
    True
    """
    n = a.shape[0]
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= 128:
        r0, r1, r2, r3, r4, r5, r6, r7 = a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]
        i = 8
        while i < n - n % 8:
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return pairwise_sum(a[:n2]) + pairwise_sum(a[n2:])


@numba.njit(cache=True, nogil=True)
def _finite(r, valid):  # pragma: no cover - compiled
    if not valid:
        return False
    for i in range(r.shape[0]):
        if not np.isfinite(r[i]):
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _any(fired):  # pragma: no cover - compiled
    for i in range(fired.shape[0]):
        if fired[i]:
            return 1
    return 0


@numba.njit(cache=True, nogil=True)
def threshold_step(r, valid, c, tau, k, win, cnt, fired, info):  # pragma: no cover - compiled
    """``|r − c| > τ`` counted over the last ``n`` valid samples (``win`` a ring of ``n`` rows), fired at ``k``.

    ``info = [used, head]``, ``head`` the ring row written next.  The ring starts as zeros, so the count is right
    (the window shorter) before ``n`` valid samples have passed, as the reference's ``deque(maxlen=n)``.
    """
    q = c.shape[0]
    if r.shape[0] != q:
        return -1
    ok = _finite(r, valid)
    info[0] = ok
    if ok:
        head = info[1]
        for i in range(q):
            e = np.int64(abs(r[i] - c[i]) > tau[i])
            cnt[i] += e - win[head, i]
            win[head, i] = e
            fired[i] = cnt[i] >= k
        info[1] = head + 1 if head + 1 < win.shape[0] else 0
    return _any(fired)


@numba.njit(cache=True, nogil=True)
def threshold_batch(r, rvalid, c, tau, k, n, fired, alarm, valid, starts):  # pragma: no cover - compiled
    """The threshold test with k-of-n persistence over a whole (N, q) series, in one pass.

    Fills ``fired`` (N, q), ``alarm`` (N,), ``valid`` (N,) (``rvalid`` and every entry finite) and ``starts``
    (the samples where the fired pattern differs from the previous sample's, sample 0 included); returns how many
    ``starts`` there are, or -1 when the shapes disagree.  An invalid sample repeats the last valid decision.
    """
    N, q = r.shape
    if (rvalid.shape[0] != N or c.shape[0] != q or tau.shape[0] != q or fired.shape[0] != N
            or fired.shape[1] != q or alarm.shape[0] != N or valid.shape[0] != N or starts.shape[0] < N):
        return -1
    win = np.zeros((n, q), np.int64)
    cnt = np.zeros(q, np.int64)
    prev = np.zeros(q, np.bool_)
    head = 0
    m = 0
    last_alarm = False
    for t in range(N):
        ok = rvalid[t]
        if ok:
            fin = True
            for i in range(q):
                fin &= np.isfinite(r[t, i])
            ok = fin
        valid[t] = ok
        change = t == 0
        if ok:
            any_fired = False
            if n == 1:
                for i in range(q):
                    f = abs(r[t, i] - c[i]) > tau[i]
                    fired[t, i] = f
                    any_fired |= f
                    change |= f != prev[i]
                    prev[i] = f
            else:
                for i in range(q):
                    e = np.int64(abs(r[t, i] - c[i]) > tau[i])
                    cnt[i] += e - win[head, i]
                    win[head, i] = e
                    f = cnt[i] >= k
                    fired[t, i] = f
                    any_fired |= f
                    change |= f != prev[i]
                    prev[i] = f
                head = head + 1 if head + 1 < n else 0
            last_alarm = any_fired
        else:
            for i in range(q):
                fired[t, i] = prev[i]
        alarm[t] = last_alarm
        if change:
            starts[m] = t
            m += 1
    return m


@numba.njit(cache=True, nogil=True)
def cusum_step(r, valid, par, g, cl, fired, info):  # pragma: no cover - compiled
    """Two-sided Page recursion per residual with restarts, rebase and hold (the reference's order of operations).

    ``par = [μ0, σ, ν, h]`` (4, q); ``g = [S⁺, M⁺, S⁻, M⁻, g⁺, g⁻]`` (6, q); ``cl = [count, left]`` (2, q);
    ``info = [used, two_sided, restart, hold, rebase period]``.
    """
    q = par.shape[1]
    if r.shape[0] != q:
        return -1
    ok = _finite(r, valid)
    info[0] = ok
    if ok:
        two = info[1] != 0
        restart = info[2] != 0
        hold = info[3]
        rebase = info[4]
        for i in range(q):
            s = (r[i] - par[0, i]) / par[1, i]
            nu = par[2, i]
            h = par[3, i]
            sp = g[0, i] + (s - nu)
            mp = g[1, i]
            if not mp <= sp:
                mp = sp
            gp = sp - mp
            e = gp > h
            if two:
                sm = g[2, i] + ((-s) - nu)
                mm = g[3, i]
                if not mm <= sm:
                    mm = sm
                gm = sm - mm
                e = e or gm > h
            else:
                sm = g[2, i]
                mm = sm
                gm = sm
            count = cl[0, i] + 1
            if restart and e:
                sp = 0.0
                mp = 0.0
                sm = 0.0
                mm = 0.0
                count = 0
            if count == rebase:
                sp = gp
                mp = 0.0
                sm = gm
                mm = 0.0
                count = 0
            left = cl[1, i]
            fired[i] = e or left > 0
            if hold:
                cl[1, i] = hold if e else max(left - 1, 0)
            cl[0, i] = count
            g[0, i] = sp
            g[1, i] = mp
            g[2, i] = sm
            g[3, i] = mm
            g[4, i] = gp
            g[5, i] = gm
    return _any(fired)


@numba.njit(cache=True, nogil=True)
def glr_step(r, valid, mean, index, whiten, h, buf, idx, work, best, ich, fired, info):  # pragma: no cover
    """Window-limited GLR per block: whitened residual into a ring of ``M`` samples, window sums newest first.

    ``index`` (G, P) the residual of each padded slot (``q`` in the padding), ``whiten`` (G, P, P), ``buf``
    (M, G, P) the ring, ``idx`` (M,) the sample number of each ring row, ``work`` (3, G, P), ``best`` (G, P + 1)
    = ``[g_k, S_ĵ]``, ``ich = [ĵ sample number, window length]`` (2, G), ``info = [used, head, count, k]``.
    """
    q = mean.shape[0]
    G, P = index.shape
    M = buf.shape[0]
    if r.shape[0] != q:
        return -1
    info[3] += 1
    ok = _finite(r, valid)
    info[0] = ok
    if not ok:
        return _any(fired)
    e = work[0]
    S = work[1]
    head = info[1]
    for gg in range(G):
        for j in range(P):
            ix = index[gg, j]
            e[gg, j] = r[ix] - mean[ix] if ix < q else 0.0
        for i in range(P):
            acc = whiten[gg, i, 0] * e[gg, 0]
            for j in range(1, P):
                acc = acc + whiten[gg, i, j] * e[gg, j]
            buf[head, gg, i] = acc
    idx[head] = info[3]
    info[1] = head + 1 if head + 1 < M else 0
    navail = info[2] + 1 if info[2] < M else M
    info[2] = navail
    for gg in range(G):
        best[gg, 0] = -1.0  # below any statistic: sample 0 of the window always becomes the first maximum
        for i in range(P):
            S[gg, i] = 0.0
    for n in range(navail):  # window length n + 1, newest sample first; the blocks side by side (independent)
        row = head - n
        if row < 0:
            row += M
        den = 2.0 * (n + 1)
        for gg in range(G):
            acc = 0.0
            for i in range(P):
                v = S[gg, i] + buf[row, gg, i]
                S[gg, i] = v
                acc = v * v if i == 0 else acc + v * v
            st = acc / den
            b = best[gg, 0]
            if st > b or (st != st and b == b):  # np.argmax: the first maximum; a NaN wins
                best[gg, 0] = st
                ich[1, gg] = n + 1
                for i in range(P):
                    best[gg, 1 + i] = S[gg, i]
    for gg in range(G):
        row = head - (ich[1, gg] - 1)
        if row < 0:
            row += M
        ich[0, gg] = idx[row]
        fired[gg] = best[gg, 0] > h[gg]
    return _any(fired)


@numba.njit(cache=True, nogil=True)
def sprt_step(r, valid, mean, index, w, c, A, B, L, dl, fired, info):  # pragma: no cover - compiled
    """Wald's test per block: ``λ = wᵀ e − c``; repeated (restart at 0 after either decision) or single (latched).

    ``L = [Λ carried, Λ reported]`` (2, G); ``dl = [done, left, decision]`` (3, G);
    ``info = [used, restart, hold]``.
    """
    q = mean.shape[0]
    G, P = index.shape
    if r.shape[0] != q:
        return -1
    ok = _finite(r, valid)
    info[0] = ok
    if not ok:
        return _any(fired)
    restart = info[1] != 0
    hold = info[2]
    for gg in range(G):
        acc = 0.0
        for j in range(P):
            ix = index[gg, j]
            ej = r[ix] - mean[ix] if ix < q else 0.0
            acc = w[gg, 0] * ej if j == 0 else acc + w[gg, j] * ej
        lam = acc - c[gg]
        if restart:
            now = L[0, gg] + lam
            up = now >= A
            down = now <= B
            dl[2, gg] = np.int64(up) - np.int64(down)
            L[0, gg] = 0.0 if (up or down) else now
            fired[gg] = up or dl[1, gg] > 0
            dl[1, gg] = hold if up else max(dl[1, gg] - 1, 0)
        else:
            done = dl[0, gg] != 0
            now = L[0, gg] if done else L[0, gg] + lam
            up = (not done) and now >= A
            down = (not done) and now <= B
            if up or down:
                dl[0, gg] = 1
            dl[2, gg] += np.int64(up) - np.int64(down)
            L[0, gg] = now
            fired[gg] = fired[gg] or up
        L[1, gg] = now
    return _any(fired)


@numba.njit(cache=True, nogil=True)
def _logaddexp(x, y):  # pragma: no cover - compiled
    """numpy's ``npy_logaddexp``, operation for operation."""
    if x == y:
        return x + _LOGE2
    tmp = x - y
    if tmp > 0:
        return x + np.log1p(np.exp(-tmp))
    if tmp <= 0:
        return y + np.log1p(np.exp(tmp))
    return tmp


@numba.njit(cache=True, nogil=True)
def _nanmax(a):  # pragma: no cover - compiled
    m = a[0]
    for i in range(1, a.shape[0]):
        v = a[i]
        if v != v or m != m:
            return np.nan
        if v > m:
            m = v
    return m if a[0] == a[0] else np.nan


@numba.njit(cache=True, nogil=True)
def mhsprt_step(r, valid, blk, mean, W, hp, fp, state, P, fired, work, info):  # pragma: no cover - compiled
    """The Shiryayev posterior update of (7.1), log-space (``form`` 0, corrected) or linear (1, literal).

    ``blk`` (B, Pb) the residuals of each magnitude block (-1 padding; B = 0: the residuals themselves),
    ``mean`` (H, n) and ``W`` (H, n, n) the Gaussian densities (``W = L⁻¹``), ``hp = [log-density constant, offset,
    log p]`` (3, H), ``fp = [p, F_T]`` (2, m), ``state`` (H,) ``log F`` or ``F``, ``P`` (H,) the probabilities,
    ``work`` (4, max(H, n)), ``info = [used, form, q]``.
    """
    H = state.shape[0]
    m = H - 1
    n = mean.shape[1]
    B = blk.shape[0]
    if r.shape[0] != info[2]:
        return -1
    ok = _finite(r, valid)
    if ok:
        x = work[3, :n]
        if B:
            for b in range(B):
                acc = 0.0
                for j in range(blk.shape[1]):
                    ix = blk[b, j]
                    if ix >= 0:
                        acc += r[ix] * r[ix]
                x[b] = np.sqrt(acc)
        else:
            for j in range(n):
                x[j] = r[j]
        ll = work[0, :H]
        for hh in range(H):  # GaussianDensity.logpdf of one sample: row i of the triangular L⁻¹ up to i
            s = 0.0
            for i in range(n):
                acc = (x[0] - mean[hh, 0]) * W[hh, i, 0]
                for j in range(1, i + 1):
                    acc = acc + (x[j] - mean[hh, j]) * W[hh, i, j]
                s = acc * acc if i == 0 else s + acc * acc
            ll[hh] = (hp[0, hh] - 0.5 * s) + hp[1, hh]
        if info[1] == 0:
            a = work[1, :H]
            for hh in range(H):
                a[hh] = _logaddexp(state[hh], hp[2, hh] + state[0])
                a[hh] += ll[hh]
            amax = _nanmax(a)
            if np.isfinite(amax):
                ex = work[2, :H]
                for hh in range(H):
                    ex[hh] = np.exp(a[hh] - amax)
                norm = amax + np.log(pairwise_sum(ex))
                for hh in range(H):
                    state[hh] = a[hh] - norm
            else:
                ok = False
        else:
            lmax = _nanmax(ll)
            if np.isfinite(lmax):
                Mv = work[1, :m]
                num = work[2, :m]
                g0 = np.exp(ll[0] - lmax)
                for i in range(m):
                    F = state[1 + i]
                    Mv[i] = F + fp[0, i] * (1.0 - F)
                    num[i] = Mv[i] * np.exp(ll[1 + i] - lmax)
                den = pairwise_sum(num) + (1.0 - pairwise_sum(Mv)) * g0
                for i in range(m):
                    num[i] = num[i] / den
                    if not np.isfinite(num[i]):
                        ok = False
                if ok:
                    for i in range(m):
                        state[1 + i] = num[i]
                    state[0] = 1.0 - pairwise_sum(num)
            else:
                ok = False
    info[0] = ok
    for hh in range(H):
        P[hh] = np.exp(state[hh]) if info[1] == 0 else state[hh]
    s = 0
    for i in range(m):
        fired[i] = P[1 + i] >= fp[1, i]
        if fired[i]:
            s = 1
    return s

