"""The C99 text of an exported detector: :func:`render_header` and :func:`render_source` of an export plan.

:func:`fdikit.runtime.c_export.export_c` computes the plan (matrices in compressed-row form, the gap maps per
missing-signal pattern, the evaluator's constants, the isolation tables); this module writes it down as
``static const`` arrays (exact hexadecimal floating-point literals) around the C functions of
:mod:`fdikit.runtime.c_templates`.  What the generated code does, and on which samples it equals the reference,
is the module docstring of :mod:`fdikit.runtime.c_export`.

Why hand-written: no library writes fdikit's detectors as dependency-free C.

References
----------
Douglas et al. 1996, Ch. 1 (a threshold per residual, the fault announced from the fired residuals) and §4.2
(the bank of detection filters); Page 1954 and Basseville & Nikiforov 1993, §2.2 (the CUSUM).

Examples
--------
>>> print(c_number(0.1, single=False), c_string('a"b'))
0x1.999999999999ap-4 "a\\"b"
"""

from __future__ import annotations

import numpy as np

from fdikit.errors import ParameterError
from fdikit.runtime.c_templates import EVALUATOR, FUNCTIONS, ISOLATE, RECOVERY, c_arg, step_code

__all__ = ["c_number", "c_string", "render_header", "render_source"]


def c_number(x: float, single: bool) -> str:
    """An exact C99 literal of ``x``: hexadecimal floating point, of the double (or of the float, with ``f``).

    Parameters
    ----------
    x : float
        A finite number.
    single : bool
        Write a ``float`` literal (rounded to single precision first).

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        When ``x`` is not finite (or overflows single precision).

    Examples
    --------
    >>> c_number(-2.5, single=False), c_number(0.1, single=True)
    ('-0x1.4000000000000p+1', '0x1.99999a0000000p-4f')
    """
    v = float(np.float32(x)) if single else float(x)
    if not np.isfinite(v):
        raise ParameterError(f"the value {float(x)!r} is not finite in {'single' if single else 'double'} precision; "
                             "it cannot be exported")
    return v.hex() + ("f" if single else "")


def c_string(text: str) -> str:
    """``text`` as a C string literal (printable ASCII kept, everything else as octal escapes of its UTF-8 bytes).

    Parameters
    ----------
    text : str

    Returns
    -------
    str

    Examples
    --------
    >>> c_string("yaw rate [°/s]")
    '"yaw rate [\\\\302\\\\260/s]"'
    """
    out = []
    for b in text.encode("utf-8"):
        ch = chr(b)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 32 <= b < 127 and ch != "?":  # '?' escaped: no trigraphs
            out.append(ch)
        else:
            out.append(f"\\{b:03o}")
    return '"' + "".join(out) + '"'


def _comment(text: str) -> str:
    """Text safe inside a C block comment (no ``*/``, printable ASCII)."""
    return "".join(c if 32 <= ord(c) < 127 else "?" for c in str(text)).replace("*/", "* /")


def _array(ctype: str, name: str, values, fmt) -> str:
    vals = [fmt(v) for v in values] or ["0"]  # C has no empty arrays: one unused entry
    lines, line = [], "   "
    for v in vals:
        if len(line) + len(v) + 2 > 110:
            lines.append(line)
            line = "   "
        line += " " + v + ","
    lines.append(line)
    return f"static const {ctype} {name}[{len(vals)}] = {{\n" + "\n".join(lines) + "\n};\n"


def _csr_arrays(P: dict, base: str, csr) -> str:
    """``ptr``/``idx``/``val`` arrays of one compressed-row matrix (or several concatenated)."""
    ptr, idx, val = csr
    single = P["single"]
    return (_array("int32_t", f"{base}_ptr", ptr, str)
            + _array("IDX_T", f"{base}_idx", idx, str)
            + _array("real_t", f"{base}_val", val, lambda v: c_number(v, single)))


def _signal_table(P: dict, what: str, names, offsets) -> list[str]:
    out = []
    for i, (nm, off) in enumerate(zip(names, offsets)):
        col = P["columns"].get(nm, nm)
        unit = P["units"].get(nm, "SI")
        out.append(f" *   {what}[{i}]  {_comment(nm)}   (log column {_comment(col)!r}, unit {_comment(unit)}, "
                   f"operating point {float(off):.17g})")
    return out or [f" *   (none: pass NULL for {what})"]


def render_header(P: dict) -> str:
    """The ``<name>.h`` text of an export plan.

    Parameters
    ----------
    P : dict
        The plan of :func:`fdikit.runtime.c_export.export_c`.

    Returns
    -------
    str

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> from fdikit.runtime.c_export import export_c
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> ex = export_c(Detector(g, ThresholdEvaluator(thresholds=[0.5])), tempfile.mkdtemp(), name="demo")
    >>> "int demo_step(demo_state *s, const double u[DEMO_NU], const double y[DEMO_NY], demo_output *out);" in (
    ...     ex.header.read_text())
    True
    """
    nm, NM = P["name"], P["NAME"]
    mu, nv, nr = P["mu"], P["nv"], P["nr"]
    ny = nv - mu
    ev = P["evaluator"]
    faults = P["faults"]
    lines = [f"/* {nm}.h: fault-detection monitor {_comment(P['detector'])!r}, C99, exported by fdikit "
             f"{_comment(P['version'])} (fdikit.runtime.c_export).",
             " *"]
    if P["description"]:
        lines += [f" * {_comment(P['description'])}", " *"]
    lines += [f" * Filter: {P['n']} states at dt = {P['dt']!r} s ({P['real']}); evaluator: {ev['title']}.",
              " * Usage: " + f"{nm}_state s; {nm}_output o; {nm}_init(&s); then once per sample "
              f"{nm}_step(&s, u, y, &o);",
              " * Every call takes the ABSOLUTE signals, in this order (the step subtracts the operating point):"]
    lines += _signal_table(P, "u", P["controls"], P["offset"][:mu])
    lines += _signal_table(P, "y", P["outputs"], P["offset"][mu:])
    lines += [" * Residuals out->r[i] and per-residual decisions out->fired[i], in the evaluator's order:"]
    lines += [f" *   [{i}] {_comment(r)}" + (f"  (tied to {_comment(t)})" if t else "")
              for i, (r, t) in enumerate(zip(P["residuals"], P["res_faults"]))]
    lines += [f" * Isolated fault out->fault: {NM}_FAULT_NONE (-1) for no fault, else an index of "
              f"{nm}_fault_names[]:"]
    lines += [f" *   {i} {_comment(f)}" for i, f in enumerate(faults)]
    lines += [" * Bad samples: a NaN/inf entry is a dropout of that signal; a sample the source flags invalid is "
              "passed with",
              " * every entry NaN.  Such a sample gives NaN residuals, out->sample_valid false and the held "
              "decision",
              " * (out->valid false); the filter is propagated by the fdikit gap rule, exactly for the "
              "missing-signal",
              f" * patterns listed in {nm}.c ({P['npat']} patterns; another pattern is propagated as if every "
              f"signal were missing",
              f" * and the step returns {NM}_STATUS_UNLISTED_GAP).  The samples after a gap are recovering "
              "(out->recovering)",
              " * until the gap transient has decayed below the noise, as in fdikit; they do not update the "
              "decision.",
              " */",
              f"#ifndef {NM}_H_", f"#define {NM}_H_", "", "#include <stdbool.h>", "#include <stdint.h>", "",
              "#ifdef __cplusplus", 'extern "C" {', "#endif", "",
              f"#define {NM}_NU {mu}  /* controls */", f"#define {NM}_NY {ny}  /* outputs (measurements) */",
              f"#define {NM}_NX {P['n']}  /* filter states */",
              f"#define {NM}_NR {nr}  /* residuals the evaluator reads */",
              f"#define {NM}_NFAULTS {len(faults)}  /* entries of {nm}_fault_names */",
              f"#define {NM}_FAULT_NONE (-1)", f"#define {NM}_FAULT_UNKNOWN {P['unknown']}",
              f"#define {NM}_DT {P['dt']!r}  /* sample time [s] */",
              f"#define {NM}_STATUS_OK 0", f"#define {NM}_STATUS_UNLISTED_GAP 1  /* see above */",
              f"#define {NM}_STATUS_NULL (-1)  /* a NULL argument: nothing was done */", "",
              f"typedef {P['real']} {nm}_real;", ""]
    S = P["sizes"]
    lines += ["/* The whole state of one monitor: no global mutable data; one struct per monitored vehicle. */",
              "typedef struct {",
              f"    {nm}_real z[{S['z']}];  /* filter state (internal order) */",
              f"    {nm}_real last[{nv}];  /* last valid deviation of each input (held through a gap) */"]
    if P["n"]:
        lines += [f"    {nm}_real P[{S['P']}];  /* gap-transient covariance, per block (recovery rule) */",
                  f"    {nm}_real work[{S['W']}];  /* scratch for the covariance update */"]
    lines += ["    bool p_on;  /* a gap transient is being tracked */",
              "    int32_t hold;  /* recovering samples still to hold (-1: never recovers) */",
              "    uint32_t invalid;  /* bad samples since init/reset */",
              "    int32_t warm;  /* warm-up samples left */",
              "    bool last_valid, last_recovering;"]
    if ev["kind"] == "threshold":
        lines += [f"    uint8_t win[{ev['n'] * nr}];  /* k-of-n window of exceedances */",
                  f"    int32_t cnt[{nr}];", "    int32_t wpos, wfill;"]
    else:
        lines += [f"    {nm}_real sp[{nr}], mp[{nr}], sm[{nr}], mm[{nr}];  /* CUSUM running sums and minima */",
                  f"    int32_t count[{nr}], left[{nr}];"]
    lines += [f"    bool fired[{nr}];  /* the decision held over bad samples */", f"}} {nm}_state;", "",
              "typedef struct {",
              f"    {nm}_real r[{nr}];  /* residuals (NaN on a bad sample) */",
              f"    bool fired[{nr}];  /* per-residual decision */",
              "    bool alarm;  /* any residual fired */",
              f"    int32_t fault;  /* {NM}_FAULT_NONE or an index of {nm}_fault_names */",
              "    bool valid;  /* the decision used this sample (false: held) */",
              "    bool sample_valid;  /* the residuals are valid (not a bad nor a recovering sample) */",
              "    bool recovering;  /* finite residuals, still recovering from a gap */",
              f"}} {nm}_output;", "",
              f"extern const char *const {nm}_control_names[{max(mu, 1)}];",
              f"extern const char *const {nm}_output_names[{max(ny, 1)}];",
              f"extern const char *const {nm}_residual_names[{nr}];",
              f"extern const char *const {nm}_fault_names[{len(faults)}];", "",
              f"void {nm}_init({nm}_state *s);  /* a new monitor: filter at the operating point */",
              f"void {nm}_reset({nm}_state *s);  /* start a new run (same as init) */",
              f"int {nm}_step({nm}_state *s, {c_arg('u', mu, NM + '_NU')}, {c_arg('y', ny, NM + '_NY')}, "
              f"{nm}_output *out);",
              f"int32_t {nm}_isolate(const bool fired[{NM}_NR]);  /* the fault a fired pattern names */",
              f"uint32_t {nm}_state_size(void);  /* sizeof({nm}_state), for foreign-function users */", "",
              "#ifdef __cplusplus", "}", "#endif", "", f"#endif /* {NM}_H_ */", ""]
    return "\n".join(lines)


def _names(P: dict, table: str, names) -> str:
    vals = [c_string(x) for x in names] or ['""']
    return f"const char *const {P['name']}_{table}[{len(vals)}] = {{" + ", ".join(vals) + "};\n"


def render_source(P: dict) -> str:
    """The ``<name>.c`` text of an export plan.

    Parameters
    ----------
    P : dict
        The plan of :func:`fdikit.runtime.c_export.export_c`.

    Returns
    -------
    str

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> from fdikit.runtime.c_export import export_c
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> ex = export_c(Detector(g, ThresholdEvaluator(thresholds=[0.5])), tempfile.mkdtemp(), name="demo")
    >>> "malloc" in ex.source.read_text(), '#include "demo.h"' in ex.source.read_text()
    (False, True)
    """
    nm, NM, single = P["name"], P["NAME"], P["single"]
    n, mu, nv, nr = P["n"], P["mu"], P["nv"], P["nr"]
    num = (lambda v: c_number(v, single))  # noqa: E731
    dbl = (lambda v: c_number(v, False))  # noqa: E731
    src = [f"/* {nm}.c: generated by fdikit {_comment(P['version'])} (fdikit.runtime.c_export); do not edit. */",
           "#include <math.h>", "#include <string.h>", "", f'#include "{nm}.h"', "",
           f"typedef {nm}_real real_t;", f"typedef {P['idx_t']} IDX_T;", ""]
    src.append(f"#define NX {n}\n#define NU {mu}\n#define NV {nv}\n#define NR {nr}\n#define NPAT {P['npat']}\n")
    src.append(_names(P, "control_names", P["controls"]) + _names(P, "output_names", P["outputs"])
               + _names(P, "residual_names", P["residuals"]) + _names(P, "fault_names", P["faults"]))
    src.append("\n/* operating point [u0; y0], subtracted in double precision */\n"
               + _array("double", "offset", P["offset"], dbl))
    src.append("\n/* [z+] = [A B][z; v] and the evaluator's residuals r = [C D][z; v] (nonzeros, compressed rows) */\n"
               + _csr_arrays(P, "ab", P["AB"]) + _csr_arrays(P, "cd", P["CD"]))
    pats = "\n".join(f" * {i}: missing {', '.join(_comment(s) for s in p)}" for i, p in enumerate(P["pattern_names"]))
    src.append("\n/* Gap maps: per pattern of missing signals, z+ = F [z; v (0 where missing); last].  Patterns:\n"
               + pats + "\n */\n" + _array("uint8_t", "pat_bad", P["pat_bad"], str) + _csr_arrays(P, "gap", P["F"]))
    if n:
        src.append("\n/* Recovery rule: per pattern T (P+ = T P T' + Q), Q as (position in P, value); A; C of every "
                   "generator residual */\n"
                   + _csr_arrays(P, "tg", P["T"]) + _array("int32_t", "q_ptr", P["Q"][0], str)
                   + _array("int32_t", "q_pos", P["Q"][1], str) + _array("real_t", "q_val", P["Q"][2], num)
                   + _array("uint8_t", "pat_held", P["held"], str) + _csr_arrays(P, "a", P["A"])
                   + _csr_arrays(P, "cg", P["Cg"]) + _array("int32_t", "cg_blk", P["row_blk"], str)
                   + _array("real_t", "limit", P["limit"], num)
                   + _array("int32_t", "blk_start", P["blk_start"], str)
                   + _array("int32_t", "blk_off", P["blk_off"], str)
                   + f"#define NBLK {len(P['blk_start']) - 1}\n#define SETTLE {P['settle']}\n"
                   + f"#define NQG {len(P['limit'])}\n")
    src.append(_evaluator_constants(P, num, dbl))
    src.append(_isolation_constants(P))
    code = [FUNCTIONS] + ([RECOVERY] if n else []) + [EVALUATOR[P["evaluator"]["kind"]],
                                                       ISOLATE[P["isolation"]["kind"]], step_code(P)]
    src += [c.replace("@U@", NM + "_").replace("@P@", nm + "_") for c in code]  # placeholders only in code
    return "\n".join(src)


def _evaluator_constants(P: dict, num, dbl) -> str:
    ev = P["evaluator"]
    if ev["kind"] == "threshold":
        return ("\n/* ThresholdEvaluator: |r - center| > tau in at least K of the last WN valid samples */\n"
                + _array("double", "tau", ev["tau"], dbl) + _array("double", "center", ev["center"], dbl)
                + f"#define KOFN_K {ev['k']}\n#define WN {ev['n']}\n")
    return ("\n/* CusumEvaluator: s = (r - mu)/sd; g+ = max(0, g+ + s - nu), g- likewise; alarm g > h */\n"
            + _array("real_t", "cu_nu", ev["nu"], num) + _array("real_t", "cu_h", ev["h"], num)
            + _array("real_t", "cu_mu", ev["mu"], num) + _array("real_t", "cu_sd", ev["sd"], num)
            + f"#define TWO_SIDED {int(ev['two_sided'])}\n#define RESTART {int(ev['reset'])}\n"
            + f"#define HOLD {ev['hold']}\n#define REBASE 4096\n")


def _isolation_constants(P: dict) -> str:
    iso = P["isolation"]
    if iso["kind"] == "logic":
        return ("\n/* Isolation (fdikit.diagnosis.isolate): residual -> key (its fault within its filter); per "
                "filter its keys */\n"
                + _array("int32_t", "res_key", iso["res_key"], str)
                + _array("int32_t", "key_fault", iso["key_fault"], str)
                + _array("int32_t", "grp_start", iso["grp_start"], str)
                + f"#define NKEY {len(iso['key_fault'])}\n#define NGRP {len(iso['grp_start']) - 1}\n")
    hexa = (lambda v: f"UINT64_C(0x{int(v):x})")  # noqa: E731
    return ("\n/* Isolation by the signature table: groups of each residual, signature of each fault */\n"
            + _array("uint64_t", "res_groups", iso["res_mask"], hexa) + _array("uint64_t", "sig", iso["sig"], hexa)
            + f"#define NSIG {len(iso['sig'])}\n#define PARTIAL {int(iso['partial'])}\n")


