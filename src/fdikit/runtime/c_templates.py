"""The C functions of an exported detector (fdikit.runtime.c_export), as text with the symbol prefix to fill in.

``@P@`` stands for ``<name>_`` and ``@U@`` for ``<NAME>_`` (:func:`fdikit.runtime.c_render.render_source` fills
them in); the functions read the ``static const`` tables the renderer writes before them.  :data:`FUNCTIONS`:
the compressed-row product and the pattern look-up; :data:`RECOVERY`: the covariance of the gap transient
(``P+ = T P Tᵀ + Q`` on an invalid sample, ``A P Aᵀ`` while recovering) and the recovery test of
:class:`fdikit.gaps.Recovery`; :data:`EVALUATOR`: the steps of ``ThresholdEvaluator`` and ``CusumEvaluator``;
:data:`ISOLATE`: the isolation of :func:`fdikit.diagnosis.isolate` and of a signature table;
:func:`step_code`: ``<name>_init``, ``<name>_reset`` and ``<name>_step``.

Why hand-written: no library writes fdikit's detectors as dependency-free C.

References
----------
Douglas et al. 1996, Ch. 1 (a threshold per residual; the fault announced from the fired residuals, the bank
logic); Page 1954 and Basseville & Nikiforov 1993, §2.2 (the CUSUM).

Examples
--------
>>> "static void mv(" in FUNCTIONS, sorted(EVALUATOR), sorted(ISOLATE)
(True, ['cusum', 'threshold'], ['logic', 'signature'])
"""

from __future__ import annotations

__all__ = ["EVALUATOR", "FUNCTIONS", "ISOLATE", "RECOVERY", "c_arg", "step_code"]

FUNCTIONS = r"""
/* y = M x for a compressed-row M of `rows` rows */
static void mv(int rows, const int32_t *ptr, const IDX_T *idx, const real_t *val, const real_t *x, real_t *y)
{
    int i;
    int32_t e;
    for (i = 0; i < rows; ++i) {
        real_t acc = 0;
        for (e = ptr[i]; e < ptr[i + 1]; ++e) {
            acc += val[e] * x[idx[e]];
        }
        y[i] = acc;
    }
}

static int find_pattern(const uint8_t bad[NV])
{
    int p;
    for (p = 0; p < NPAT; ++p) {
        if (memcmp(pat_bad + p * NV, bad, NV) == 0) {
            return p;
        }
    }
    return -1;
}
"""

RECOVERY = r"""
/* P <- M P M' block by block (M's rows have their nonzeros inside their block) */
static void sandwich(const int32_t *ptr, const IDX_T *idx, const real_t *val, real_t *P, real_t *W)
{
    int b, i, j;
    int32_t e;
    for (b = 0; b < NBLK; ++b) {
        const int b0 = blk_start[b], nb = blk_start[b + 1] - blk_start[b];
        real_t *Pb = P + blk_off[b];
        for (i = 0; i < nb; ++i) {
            for (j = 0; j < nb; ++j) {
                real_t acc = 0;
                for (e = ptr[b0 + i]; e < ptr[b0 + i + 1]; ++e) {
                    acc += val[e] * Pb[(idx[e] - b0) * nb + j];
                }
                W[i * nb + j] = acc;
            }
        }
        for (i = 0; i < nb; ++i) {
            for (j = 0; j < nb; ++j) {
                real_t acc = 0;
                for (e = ptr[b0 + j]; e < ptr[b0 + j + 1]; ++e) {
                    acc += W[i * nb + (idx[e] - b0)] * val[e];
                }
                Pb[i * nb + j] = acc;
            }
        }
    }
}

/* an invalid sample of pattern p: P <- T P T' + Q (P = Q when no transient is tracked) */
static void gap_sample(@P@state *s, int p)
{
    int32_t e;
    if (s->p_on) {
        sandwich(tg_ptr + p * (NX + 1), tg_idx, tg_val, s->P, s->work);
    } else {
        memset(s->P, 0, sizeof s->P);
    }
    for (e = q_ptr[p]; e < q_ptr[p + 1]; ++e) {
        s->P[q_pos[e]] += q_val[e];
    }
    s->p_on = true;
    if (pat_held[p]) {
        s->hold = SETTLE;
    }
}

/* a finite sample: true when it may be used for decisions (the gap transient is below the noise) */
static bool valid_sample(@P@state *s)
{
    bool recovering = false;
    if (s->p_on) {
        int i;
        for (i = 0; i < NQG && !recovering; ++i) {
            const int b = cg_blk[i];
            real_t d = 0;
            int32_t e, f;
            if (b < 0) {
                continue;
            }
            {
                const int b0 = blk_start[b], nb = blk_start[b + 1] - blk_start[b];
                const real_t *Pb = s->P + blk_off[b];
                for (e = cg_ptr[i]; e < cg_ptr[i + 1]; ++e) {
                    real_t acc = 0;
                    for (f = cg_ptr[i]; f < cg_ptr[i + 1]; ++f) {
                        acc += Pb[(cg_idx[e] - b0) * nb + (cg_idx[f] - b0)] * cg_val[f];
                    }
                    d += cg_val[e] * acc;
                }
            }
            if (d > limit[i]) {
                recovering = true;
            }
        }
        if (recovering) {
            sandwich(a_ptr, a_idx, a_val, s->P, s->work);
        } else {
            s->p_on = false;
        }
    }
    if (s->hold != 0) {
        recovering = true;
        if (s->hold > 0) {
            s->hold -= 1;
        }
    }
    return !recovering;
}
"""

EVALUATOR = {"threshold": r"""
/* ThresholdEvaluator.step: a bad or unusable sample holds the decision */
static bool evaluate(@P@state *s, const real_t r[NR], bool use)
{
    int i;
    for (i = 0; i < NR && use; ++i) {
        if (!isfinite(r[i])) {
            use = false;
        }
    }
    if (use) {
        uint8_t *w = s->win + s->wpos * NR;
        if (s->wfill == WN) {
            for (i = 0; i < NR; ++i) {
                s->cnt[i] -= w[i];
            }
        } else {
            s->wfill += 1;
        }
        for (i = 0; i < NR; ++i) {
            const uint8_t x = (uint8_t)(fabs((double)r[i] - center[i]) > tau[i]);
            w[i] = x;
            s->cnt[i] += x;
            s->fired[i] = s->cnt[i] >= KOFN_K;
        }
        s->wpos = (s->wpos + 1 == WN) ? 0 : s->wpos + 1;
    }
    return use;
}

static void evaluator_reset(@P@state *s)
{
    memset(s->win, 0, sizeof s->win);
    memset(s->cnt, 0, sizeof s->cnt);
    s->wpos = 0;
    s->wfill = 0;
}
""", "cusum": r"""
/* CusumEvaluator.step (same operations in the same order): a bad or unusable sample holds everything */
static bool evaluate(@P@state *s, const real_t r[NR], bool use)
{
    int i;
    for (i = 0; i < NR && use; ++i) {
        if (!isfinite(r[i])) {
            use = false;
        }
    }
    if (!use) {
        return false;
    }
    for (i = 0; i < NR; ++i) {
        const real_t x = (r[i] - cu_mu[i]) / cu_sd[i];
        real_t sp = s->sp[i] + (x - cu_nu[i]);
        real_t mp = (sp < s->mp[i]) ? sp : s->mp[i];
        const real_t gp = sp - mp;
        real_t sm = s->sm[i], mm = s->mm[i], gm = s->sm[i];
        bool e = gp > cu_h[i];
        int32_t count = s->count[i] + 1;
        if (TWO_SIDED) {
            sm = sm + ((-x) - cu_nu[i]);
            mm = (sm < mm) ? sm : mm;
            gm = sm - mm;
            e = e || (gm > cu_h[i]);
        } else {
            mm = sm;
        }
        if (RESTART && e) {
            sp = mp = sm = mm = 0;
            count = 0;
        }
        if (count == REBASE) {
            sp = gp;
            mp = 0;
            sm = gm;
            mm = 0;
            count = 0;
        }
        s->fired[i] = e || (s->left[i] > 0);
        if (HOLD) {
            s->left[i] = e ? HOLD : (s->left[i] > 0 ? s->left[i] - 1 : 0);
        }
        s->sp[i] = sp;
        s->mp[i] = mp;
        s->sm[i] = sm;
        s->mm[i] = mm;
        s->count[i] = count;
    }
    return true;
}

static void evaluator_reset(@P@state *s)
{
    memset(s->sp, 0, sizeof s->sp);
    memset(s->mp, 0, sizeof s->mp);
    memset(s->sm, 0, sizeof s->sm);
    memset(s->mm, 0, sizeof s->mm);
    memset(s->count, 0, sizeof s->count);
    memset(s->left, 0, sizeof s->left);
}
"""}

ISOLATE = {"logic": r"""
/* fdikit.diagnosis.isolate: per filter, a single fired fault votes; conflicting votes or an untied
   residual firing alone give 'unknown' */
int32_t @P@isolate(const bool fired[@U@NR])
{
    bool kf[NKEY];
    bool any = false, conflict = false;
    int32_t cand = -1;
    int i, g, k;
    memset(kf, 0, sizeof kf);
    for (i = 0; i < NR; ++i) {
        if (fired[i]) {
            kf[res_key[i]] = true;
            any = true;
        }
    }
    if (!any) {
        return @U@FAULT_NONE;
    }
    for (g = 0; g < NGRP; ++g) {
        int count = 0, which = -1;
        for (k = grp_start[g]; k < grp_start[g + 1]; ++k) {
            if (kf[k]) {
                count += 1;
                which = k;
            }
        }
        if (count == 1) {
            const int32_t f = key_fault[which];
            if (f < 0 || (cand >= 0 && cand != f)) {
                conflict = true;
            } else if (cand < 0) {
                cand = f;
            }
        }
    }
    return (cand >= 0 && !conflict) ? cand : @U@FAULT_UNKNOWN;
}
""", "signature": r"""
/* fdikit.decision.signature: the fired groups matched against each fault's signature */
int32_t @P@isolate(const bool fired[@U@NR])
{
    uint64_t G = 0;
    int i, f, count = 0, which = -1;
    for (i = 0; i < NR; ++i) {
        if (fired[i]) {
            G |= res_groups[i];
        }
    }
    if (G == 0) {
        return @U@FAULT_NONE;
    }
    for (f = 0; f < NSIG; ++f) {
        if (sig[f] == G) {
            count += 1;
            which = f;
        }
    }
    if (count == 1) {
        return which;
    }
    if (count == 0 && PARTIAL) {
        for (f = 0; f < NSIG; ++f) {
            if ((G & ~sig[f]) == 0) {
                count += 1;
                which = f;
            }
        }
        if (count == 1) {
            return which;
        }
    }
    return @U@FAULT_UNKNOWN;
}
"""}


def c_arg(what: str, count: int, macro: str) -> str:
    """The C parameter of an input vector: ``const double u[MACRO]``, or a pointer when it has no entries.

    Parameters
    ----------
    what : str
        Parameter name.
    count : int
        Its length.
    macro : str
        The macro of its length.

    Returns
    -------
    str

    Examples
    --------
    >>> c_arg("u", 2, "M_NU"), c_arg("u", 0, "M_NU")
    ('const double u[M_NU]', 'const double *u')
    """
    return f"const double {what}[{macro}]" if count else f"const double *{what}"



def step_code(P: dict) -> str:
    """``<name>_reset``, ``<name>_init``, ``<name>_state_size`` and ``<name>_step`` of an export plan.

    Parameters
    ----------
    P : dict
        The plan of :func:`fdikit.runtime.c_export.export_c` (sizes, warm-up).

    Returns
    -------
    str
        C text with the ``@P@`` / ``@U@`` prefixes still to fill in.

    Examples
    --------
    >>> "int @P@step(" in step_code({"n": 0, "mu": 0, "nv": 1, "warm": 0})
    True
    """
    n, mu, ny = P["n"], P["mu"], P["nv"] - P["mu"]
    null = " || ".join(["s == NULL", "out == NULL"] + (["u == NULL"] if mu else []) + (["y == NULL"] if ny else []))
    unused = ("    (void)u;\n" if not mu else "") + ("    (void)y;\n" if not ny else "")
    recover = ("        s->last_valid = (s->p_on || s->hold != 0) ? valid_sample(s) : true;\n" if n
               else "        s->last_valid = true;\n")
    gap = "        gap_sample(s, p);\n" if n else ""
    reset_p = "    memset(s->P, 0, sizeof s->P);\n    memset(s->work, 0, sizeof s->work);\n" if n else ""
    return f"""
void @P@reset(@P@state *s)
{{
    if (s == NULL) {{
        return;
    }}
    memset(s->z, 0, sizeof s->z);
    memset(s->last, 0, sizeof s->last);
{reset_p}    s->p_on = false;
    s->hold = 0;
    s->invalid = 0;
    s->warm = {P['warm']};
    s->last_valid = true;
    s->last_recovering = false;
    memset(s->fired, 0, sizeof s->fired);
    evaluator_reset(s);
}}

void @P@init(@P@state *s)
{{
    @P@reset(s);
}}

uint32_t @P@state_size(void)
{{
    return (uint32_t)sizeof(@P@state);
}}

int @P@step(@P@state *s, {c_arg('u', mu, '@U@NU')}, {c_arg('y', ny, '@U@NY')}, @P@output *out)
{{
    real_t v[NV];
    uint8_t bad[NV];
    int i, nbad = 0, status = @U@STATUS_OK;
    bool warm, used;
{unused}    if ({null}) {{
        return @U@STATUS_NULL;
    }}
    for (i = 0; i < NV; ++i) {{
        const double d = (i < NU ? u[i] : y[i - NU]) - offset[i];
        v[i] = (real_t)d;
        bad[i] = (uint8_t)!isfinite(v[i]);
        nbad += bad[i];
    }}
    if (nbad == 0) {{
        real_t x[NX + NV];
        memcpy(x, s->z, NX * sizeof(real_t));
        memcpy(x + NX, v, sizeof v);
        mv(NR, cd_ptr, cd_idx, cd_val, x, out->r);
        mv(NX, ab_ptr, ab_idx, ab_val, x, s->z);
        memcpy(s->last, v, sizeof v);
{recover}        s->last_recovering = !s->last_valid;
    }} else {{
        real_t x[NX + 2 * NV];
        int p = find_pattern(bad);
        if (p < 0) {{
            p = 0;  /* not listed: propagated as if every signal were missing */
            status = @U@STATUS_UNLISTED_GAP;
        }}
        memcpy(x, s->z, NX * sizeof(real_t));
        for (i = 0; i < NV; ++i) {{
            x[NX + i] = bad[i] ? 0 : v[i];
            x[NX + NV + i] = s->last[i];
        }}
        mv(NX, gap_ptr + p * (NX + 1), gap_idx, gap_val, x, s->z);
        for (i = 0; i < NV; ++i) {{
            if (!bad[i]) {{
                s->last[i] = v[i];
            }}
        }}
        s->invalid += 1;
        s->last_valid = false;
        s->last_recovering = false;
{gap}        for (i = 0; i < NR; ++i) {{
            out->r[i] = NAN;
        }}
    }}
    warm = s->warm > 0;
    if (warm) {{
        s->warm -= 1;
    }}
    used = evaluate(s, out->r, s->last_valid && !warm);
    out->alarm = false;
    for (i = 0; i < NR; ++i) {{
        out->fired[i] = s->fired[i];
        out->alarm = out->alarm || s->fired[i];
    }}
    out->fault = @P@isolate(s->fired);
    out->valid = used;
    out->sample_valid = s->last_valid;
    out->recovering = s->last_recovering;
    return status;
}}
"""
