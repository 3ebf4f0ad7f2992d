"""A designed detector as portable C99 for a target computer: one header, one source, no allocation.

:func:`export_c` writes ``<name>.h`` and ``<name>.c`` for a :class:`fdikit.detector.Detector` whose evaluator is a
:class:`fdikit.decision.ThresholdEvaluator` (thresholds, centre, k-of-n persistence, the single-fault and bank
isolation logic of Douglas et al. 1996 §1 — ``isolates`` and ``groups``; a signature table is not exported).
The generated code holds the discretised filter ``[A B; C D]`` as a compressed sparse row table (structural zeros,
e.g. the off-diagonal blocks of a stacked bank, are skipped), the operating point, the thresholds and the
name tables as ``static const`` data with exact hexadecimal floating-point literals, and all mutable data in
a caller-owned ``<name>_state`` struct::

    <name>_state s;  <name>_output out;
    <name>_init(&s);
    int status = <name>_step(&s, u, y, valid, &out);   // absolute u[NU], y[NY]; 0 valid, 1 invalid, 2 recovering

``out`` holds the residuals the evaluator reads (in the detector's ``residual_names`` order), the fired pattern,
the alarm, the fault index into ``<name>_fault_names`` (-1 none, ``<NAME>_NF`` unknown) and the flags.

Bad samples.  A sample flagged ``valid = 0`` or with a NaN/inf value is treated as a dropout of **every** signal:
the filter is propagated by the reference gap rule (:mod:`fdikit.gaps`) for the pattern "all signals missing"
(``z+ = T z + G v_last``, the matrices taken from :class:`fdikit.gaps.GapRule` when exporting), the residuals
are NaN and the decision holds; the recovery bookkeeping (the transient covariance ``P`` propagated through
the gap and decayed on the samples after it, the hold count of held inputs) is the reference's, in C.  This
equals Python exactly for samples flagged invalid as a whole (``valid=False``).  A *partial* dropout (some
values NaN) differs: Python propagates with the remaining channels, the C code drops the whole sample.

Why hand-written: no library turns a state-space filter bank and its decision logic into dependency-free C;
python-control and scipy stop at the matrices.

Examples
--------
>>> import tempfile
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.detector import Detector
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> out = export_c(Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",))), tempfile.mkdtemp())
>>> out.header.name, out.source.name, out.faults
('fdikit_monitor.h', 'fdikit_monitor.c', ('y_sensor',))
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fdikit.atomic import write_text
from fdikit.decision import ThresholdEvaluator
from fdikit.detector import Detector
from fdikit.errors import ParameterError
from fdikit.gaps import GapRule

__all__ = ["CExport", "export_c"]


@dataclass(frozen=True)
class CExport:
    """What :func:`export_c` wrote.

    Attributes
    ----------
    header, source : pathlib.Path
        ``<name>.h`` and ``<name>.c``.
    name : str
        The C prefix.
    controls, outputs : tuple of str
        The order of ``u`` and ``y`` in ``<name>_step``.
    residuals : tuple of str
        The order of ``out->r`` and ``out->fired``.
    faults : tuple of str
        ``<name>_fault_names``: the fault index of ``out->fault``.

    Examples
    --------
    >>> CExport(Path("m.h"), Path("m.c"), "m", ("u",), ("y",), ("r",), ()).faults
    ()
    """

    header: Path
    source: Path
    name: str
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    residuals: tuple[str, ...]
    faults: tuple[str, ...]


def _num(x: float) -> str:
    x = float(x)
    if np.isnan(x):
        return "NAN"
    if np.isinf(x):
        return "INFINITY" if x > 0 else "-INFINITY"
    return x.hex()


def _array(ctype: str, name: str, values, fmt=_num) -> str:
    values = list(np.asarray(values).ravel())
    body = ", ".join(fmt(v) for v in values) if values else ("0" if ctype != "const char *const" else '""')
    return f"static const {ctype} {name}[{max(len(values), 1)}] = {{{body}}};\n"


def _csr(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rows, cols = np.nonzero(M)
    ptr = np.searchsorted(rows, np.arange(M.shape[0] + 1))
    return ptr, cols, M[rows, cols]


def _string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _gap_matrices(rule: GapRule, n: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """``T``, ``G`` of the all-missing pattern: ``propagate(z, ·, none valid, last) = T z + G last`` (linear)."""
    none = np.zeros(nv, bool)
    nan = np.full(nv, np.nan)
    T = np.column_stack([rule.propagate(e, nan, none, np.zeros(nv)) for e in np.eye(n)]) if n else np.zeros((0, 0))
    G = np.column_stack([rule.propagate(np.zeros(n), nan, none, e) for e in np.eye(nv)]) if nv else np.zeros((n, 0))
    return T.reshape(n, n), G.reshape(n, nv)


def export_c(detector: Detector, directory: str | os.PathLike, *, name: str = "fdikit_monitor",
             dt: float | None = None) -> CExport:
    """Write a detector as C99: ``<name>.h`` and ``<name>.c`` in ``directory`` (atomically).

    Parameters
    ----------
    detector : Detector
        A generator (discrete, or continuous with ``dt``) and a :class:`~fdikit.decision.ThresholdEvaluator`.
    directory : path
        Where to write (created if missing).
    name : str, default "fdikit_monitor"
        The C prefix of every symbol and the file names (a C identifier).
    dt : float, optional
        Sample time for a continuous generator (ZOH discretisation, as ``Detector.online(dt)``).

    Returns
    -------
    CExport

    Raises
    ------
    ParameterError
        For another evaluator, a signature table, an unfitted evaluator or a name that is not a C identifier.
    ModelError
        For a continuous generator without ``dt``.

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), dt=1.0)
    >>> export_c(Detector(g, ThresholdEvaluator(thresholds=[1.0])), tempfile.mkdtemp(), name="m").residuals
    ('r',)
    """
    if not isinstance(detector, Detector):
        raise ParameterError(f"detector must be a fdikit.detector.Detector, got {type(detector).__name__}")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,40}", name):
        raise ParameterError(f"name must be a C identifier (letters, digits, _; at most 41 characters), got {name!r}")
    ev = detector.evaluator
    if type(ev) is not ThresholdEvaluator:
        raise ParameterError(f"C export supports the ThresholdEvaluator only, got {type(ev).__name__}; export a "
                             "detector with thresholds, or run the compiled Python monitor (fdikit.runtime.Monitor)")
    if ev.signatures is not None:
        raise ParameterError("C export does not support a fault-signature table (signatures=); use isolates/groups")
    names = detector.residual_names
    tau, c, iso = ev._ready(len(names))  # noqa: SLF001 - the evaluator's own resolution of its parameters
    stepper = detector.generator.online(dt=dt, residual_cov=detector.residual_cov, recovery_tol=detector.recovery_tol)
    g = stepper.generator
    n, mu, p, q = g.n, len(g.controls), len(g.outputs), len(g.residuals)
    nv = mu + p
    sel = [g.residuals.index(r) for r in names]
    groups = ev.groups if ev.groups is not None else ("",) * len(names)
    faults = tuple(dict.fromkeys(f for f in iso if f is not None))
    group_ids = list(dict.fromkeys(groups))
    key = [faults.index(f) if f is not None else -1 - k for k, f in enumerate(iso)]  # untied: a key of its own
    rule = GapRule(g, detector.residual_cov, detector.recovery_tol)
    T, G = _gap_matrices(rule, n, nv)
    _, _, _, _, Tp, Qp, held = rule.pattern(np.zeros(nv, bool))
    k_of, n_of = ev.persistence
    U = name.upper()
    ptr, col, val = _csr(np.block([[g.A, g.B], [g.C, g.D]]))
    gptr, gcol, gval = _csr(np.hstack([T, G]))
    warm = detector.warmup_samples(g.dt)
    h = f"""/* {name}.h — generated by fdikit {_version()} from the detector {detector.name!r}. C99, no allocation.
 * step(u, y): absolute signals; u = {list(g.controls)}, y = {list(g.outputs)}.
 * out->r, out->fired: residuals {list(names)}; out->fault: index into {name}_fault_names
 * ({list(faults)}), -1 none, {U}_NF unknown.  Sample time {g.dt} s. */
#ifndef {U}_H
#define {U}_H
#include <stdint.h>
#define {U}_N {n}
#define {U}_NU {mu}
#define {U}_NY {p}
#define {U}_NR {len(names)}
#define {U}_NF {len(faults)}
#define {U}_DT {_num(g.dt)}
typedef struct {{
    double x[{max(n, 1)}], last[{max(nv, 1)}], P[{max(n * n, 1)}], tmp[{max(n * n, 1)}];
    int P_active;
    long hold, warm;
    uint8_t win[{n_of * max(len(names), 1)}], fired[{max(len(names), 1)}];
    int win_count, win_pos, have_fired;
}} {name}_state;
typedef struct {{
    double r[{max(len(names), 1)}];
    uint8_t fired[{max(len(names), 1)}];
    int alarm, fault, valid, recovering;
}} {name}_output;
extern const char *const {name}_fault_names[{max(len(faults), 1)}];
void {name}_init({name}_state *s);
void {name}_reset({name}_state *s);
int {name}_step({name}_state *s, const double *u, const double *y, int valid, {name}_output *out);
#endif
"""
    src = f"""/* {name}.c — generated by fdikit; see {name}.h. */
#include <math.h>
#include <string.h>
#include "{name}.h"
#define N {n}
#define NV {nv}
#define NU {mu}
#define NQ {q}
#define NR {len(names)}
#define NG {len(group_ids)}
#define KOF {k_of}
#define NOF {n_of}
{_array("double", "OFF", g.offset)}{_array("int", "MPTR", ptr, str)}{_array("int", "MCOL", col, str)}\
{_array("double", "MVAL", val)}{_array("int", "GPTR", gptr, str)}{_array("int", "GCOL", gcol, str)}\
{_array("double", "GVAL", gval)}{_array("double", "TP", Tp)}{_array("double", "QP", Qp)}{_array("double", "AM", g.A)}\
{_array("double", "CM", g.C)}{_array("double", "LIMIT", np.broadcast_to(rule.limit, (q,)))}\
{_array("int", "SEL", sel, str)}{_array("double", "TAU", tau)}{_array("double", "CTR", c)}\
{_array("int", "GROUP", [group_ids.index(x) for x in groups], str)}{_array("int", "KEY", key, str)}\
static const int HELD = {int(bool(held))};
static const long SETTLE = {int(rule.settle)};
static const long WARM = {int(warm)};
const char *const {name}_fault_names[{max(len(faults), 1)}] = {{{", ".join(map(_string, faults)) or '""'}}};

void {name}_reset({name}_state *s) {{
    memset(s, 0, sizeof *s);
    s->warm = WARM;
}}

void {name}_init({name}_state *s) {{ {name}_reset(s); }}

/* P <- X P X^T (+ Q): the transient covariance of the reference gap rule */
static void congruence({name}_state *s, const double *X, const double *Q) {{
    int i, j, k;
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {{
            double acc = 0.0;
            for (k = 0; k < N; ++k) acc += X[i * N + k] * s->P[k * N + j];
            s->tmp[i * N + j] = acc;
        }}
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {{
            double acc = Q ? Q[i * N + j] : 0.0;
            for (k = 0; k < N; ++k) acc += s->tmp[i * N + k] * X[j * N + k];
            s->P[i * N + j] = acc;
        }}
}}

static int recovered({name}_state *s) {{
    int recovering = 0, i, j, k;
    if (s->P_active) {{
        int over = 0;
        for (i = 0; i < NQ && !over; ++i) {{
            double d = 0.0;
            for (j = 0; j < N; ++j) {{
                double row = 0.0;
                for (k = 0; k < N; ++k) row += s->P[j * N + k] * CM[i * N + k];
                d += CM[i * N + j] * row;
            }}
            over = d > LIMIT[i];
        }}
        if (over) {{ recovering = 1; congruence(s, AM, 0); }} else s->P_active = 0;
    }}
    if (s->hold != 0) {{ recovering = 1; if (s->hold > 0) s->hold -= 1; }}
    return !recovering;
}}

static int isolate(const uint8_t *fired) {{
    int any = 0, candidate = -1, conflict = 0, g, k;
    for (k = 0; k < NR; ++k) any |= fired[k];
    if (!any) return -1;
    for (g = 0; g < NG; ++g) {{
        int first = 0, have = 0, multi = 0;
        for (k = 0; k < NR; ++k)
            if (GROUP[k] == g && fired[k]) {{
                if (!have) {{ first = KEY[k]; have = 1; }} else if (KEY[k] != first) multi = 1;
            }}
        if (!have || multi) continue;
        if (first < 0) conflict = 1;
        else if (candidate < 0) candidate = first;
        else if (candidate != first) conflict = 1;
    }}
    return (candidate >= 0 && !conflict) ? candidate : {U}_NF;
}}

int {name}_step({name}_state *s, const double *u, const double *y, int valid, {name}_output *out) {{
    double z[N + NV + 1], o[N + NQ + 1];
    int ok = valid != 0, i, j, status, use;
    for (j = 0; j < NU; ++j) {{ z[N + j] = u[j] - OFF[j]; ok = ok && isfinite(z[N + j]); }}
    for (j = 0; j < NV - NU; ++j) {{ z[N + NU + j] = y[j] - OFF[NU + j]; ok = ok && isfinite(z[N + NU + j]); }}
    if (!ok) {{  /* a dropout of every signal: the reference gap rule's propagation and recovery bookkeeping */
        for (j = 0; j < N; ++j) z[j] = s->x[j];
        for (j = 0; j < NV; ++j) z[N + j] = s->last[j];
        for (i = 0; i < N; ++i) {{
            double acc = 0.0;
            for (j = GPTR[i]; j < GPTR[i + 1]; ++j) acc += GVAL[j] * z[GCOL[j]];
            s->x[i] = acc;
        }}
        if (!s->P_active) {{ memset(s->P, 0, sizeof s->P); s->P_active = 1; }}
        congruence(s, TP, QP);
        if (HELD) s->hold = SETTLE;
        for (i = 0; i < NR; ++i) out->r[i] = NAN;
        status = 1;
        use = 0;
        out->recovering = 0;
    }} else {{
        for (j = 0; j < N; ++j) z[j] = s->x[j];
        for (i = 0; i < N + NQ; ++i) {{
            double acc = 0.0;
            for (j = MPTR[i]; j < MPTR[i + 1]; ++j) acc += MVAL[j] * z[MCOL[j]];
            o[i] = acc;
        }}
        for (j = 0; j < N; ++j) s->x[j] = o[j];
        for (j = 0; j < NV; ++j) s->last[j] = z[N + j];
        for (i = 0; i < NR; ++i) out->r[i] = o[N + SEL[i]];
        use = (s->P_active || s->hold != 0) ? recovered(s) : 1;
        status = use ? 0 : 2;
        out->recovering = !use;
    }}
    out->valid = use;
    if (s->warm > 0) {{ s->warm -= 1; use = 0; }}
    for (i = 0; i < NR && use; ++i) use = isfinite(out->r[i]);
    if (use) {{  /* k of the last n valid samples above the threshold */
        uint8_t *w = s->win + s->win_pos * (NR > 0 ? NR : 1);
        for (i = 0; i < NR; ++i) w[i] = fabs(out->r[i] - CTR[i]) > TAU[i];
        s->win_pos = (s->win_pos + 1) % NOF;
        if (s->win_count < NOF) s->win_count += 1;
        for (i = 0; i < NR; ++i) {{
            int count = 0;
            for (j = 0; j < s->win_count; ++j) count += s->win[j * (NR > 0 ? NR : 1) + i];
            s->fired[i] = count >= KOF;
        }}
        s->have_fired = 1;
    }}
    out->alarm = 0;
    for (i = 0; i < NR; ++i) {{ out->fired[i] = s->have_fired ? s->fired[i] : 0; out->alarm |= out->fired[i]; }}
    out->fault = isolate(out->fired);
    out->valid = use;
    return status;
}}
"""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    header, source = directory / f"{name}.h", directory / f"{name}.c"
    write_text(header, h)
    write_text(source, src)
    return CExport(header, source, name, g.controls, g.outputs, tuple(names), faults)


def _version() -> str:
    from fdikit import __version__

    return __version__
