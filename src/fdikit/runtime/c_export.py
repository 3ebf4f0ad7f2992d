"""A designed detector as portable C99 for a target computer (an ECU, a flight computer): :func:`export_c`.

What is exported: the online step of a :class:`~fdikit.detector.Detector` — its residual generator (continuous
ones ZOH-discretised at ``dt``, as ``Detector.online(dt=)`` does), the operating point, the warm-up, the gap rule of
:mod:`fdikit.gaps` with its recovery flags, and a :class:`~fdikit.decision.ThresholdEvaluator` (thresholds, centres,
k-of-n persistence) or :class:`~fdikit.decision.CusumEvaluator` (drift, threshold, mean, sigma, one or two sides,
restart, hold, the rebase every 4096 samples), with the isolation of the fault from the fired residuals (the
single-fault / bank logic of :func:`fdikit.diagnosis.isolate` with ``isolates`` and ``groups``, or a signature
table, exact or partial).  Other evaluators are refused (:class:`~fdikit.errors.ParameterError` naming the
supported ones).  One header ``<name>.h`` and one source ``<name>.c``: C99 with ``<math.h>``, ``<stdint.h>``,
``<stdbool.h>`` and ``<string.h>`` only, no dynamic allocation, no mutable global (everything in
``<name>_state``), matrices as ``static const`` arrays of their nonzero entries (compressed rows, so a stacked
bank's block-diagonal ``A`` costs only its blocks).  ``<name>_step(state, u, y, out)`` takes the ABSOLUTE signals
in the detector's ``controls`` / ``outputs`` order (listed in the header with their log columns, units and
operating-point values) and returns the status; ``out`` holds the evaluator's residuals, the per-residual
decisions, the alarm, the isolated fault (an index of ``<name>_fault_names``, ``-1`` for none, an index for
``'unknown'``), whether the decision used the sample, and the generator's ``valid`` / ``recovering`` flags.

Why hand-written: no library turns these steps into dependency-free embedded C; code generators for LTI filters
(e.g. MATLAB Coder) know neither fdikit's gap rule nor its evaluators.

Equality with Python (``Detector.online().step``), precision ``"double"``:

* valid samples: the same residuals to rounding (the sums run in another order: ~1e-15 relative to the terms),
  identical ``fired`` / ``alarm`` / ``fault`` / ``valid`` flags unless a statistic lands within that rounding of
  its threshold;
* a bad sample (a NaN/inf in a signal, or every signal NaN for a sample the source flags invalid, which is what
  ``step(..., valid=False)`` does): NaN residuals, ``sample_valid`` false, the decision held, the filter propagated
  by the gap rule of :mod:`fdikit.gaps` (missing outputs fed the least-squares values that zero each filter
  part's residuals, a missing control or a direction the feedthrough does not see held at its last valid value)
  and the recovery covariance ``P+ = T P Tᵀ + Q`` updated.  The rule is linear per pattern of missing signals, so
  the export precomputes, per pattern, ``z+ = F [z; v; last]`` and ``(T, Q)`` from the reference's own
  :meth:`fdikit.gaps.GapRule.pattern` — for the patterns listed in ``CExport.gap_patterns``: by default every
  pattern when the detector reads at most 5 signals, else all signals missing, all outputs missing, all controls
  missing and each single signal missing; ``gap_patterns=`` replaces the defaults (all signals missing is always
  listed; ``gap_patterns=[]`` keeps only it, the smallest code).  On these patterns the C code equals Python to
  rounding.  Each pattern costs up to ``n (n + 2 (m + p)) + 2 n²`` constants (``CExport.const_bytes`` reports the
  total).  **A pattern not listed** (two of many sensors out at once) is propagated with the
  all-signals-missing map (its finite values are only stored as the last valid ones) and the step returns
  ``<NAME>_STATUS_UNLISTED_GAP`` (1): the filter state then differs from Python's until the gap transient has
  decayed, and the recovery may end at another sample;
* recovering samples (finite, after a gap): as Python — residuals computed, ``sample_valid`` false,
  ``recovering`` true, the decision held — until every residual's transient standard deviation
  ``sqrt((C P Cᵀ)_ii)`` is at most ``recovery_tol`` times its noise standard deviation (``P`` propagated
  ``A P Aᵀ``, stored per block of coupled states) and, for parts fed held values, at least ``settle`` samples.

Precision ``"single"``: matrices, state, residuals and the CUSUM in ``float`` (the operating point is subtracted in
double, thresholds and centres compared in double; a deviation beyond the float range is a bad sample).
``CExport.error_gain`` is a first-order bound ``K`` (in the unit roundoffs 2⁻²⁴ and 2⁻⁵³) on
``max_i |r_C,i − r_Python,i|`` per unit of the largest input deviation ``max_k ||v_k||∞`` (``v = [u − u0; y − y0]``)
over the valid samples since reset, without gaps: from the rounding of the matrices and of every sum (``γ_m``),
propagated through ``Σ_j |C A^j|`` and ``Σ_j |A^j B|`` (computed until ``||A^j||∞ < 1e-10``, with a rigorous tail;
``inf`` when the filter does not forget within 20000 samples).  It is a worst case: for the test's two-observer bank
``K = 1.3e-6`` against an observed 6e-8; for the 50-state PATH bank (large gains, slow poles) ``K`` is too large to
be useful while the observed float error is 3e-7 of the residuals' size.  Decisions may differ where a statistic is
within that error of its threshold.  For ``"double"`` the same formula bounds the C code's distance to Python.

References
----------
Douglas et al. 1996, Ch. 1 (a threshold per residual; the fault announced from the pattern of fired residuals, the
bank logic) and §4.2 (the bank of detection filters); Page 1954 and Basseville & Nikiforov 1993, §2.2 (the
CUSUM).  The gap rule is :mod:`fdikit.gaps` (no source document).

Examples
--------
>>> import tempfile
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.detector import Detector
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> ex = export_c(Detector(g, ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",))), tempfile.mkdtemp())
>>> ex.header.name, ex.source.name, ex.faults
('fdikit_monitor.h', 'fdikit_monitor.c', ('y_sensor', 'unknown'))
"""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fdikit.errors import DataError, ParameterError

__all__ = ["CExport", "SUPPORTED_EVALUATORS", "export_c"]

#: The evaluators :func:`export_c` translates (exact types).
SUPPORTED_EVALUATORS = ("ThresholdEvaluator", "CusumEvaluator")

_KEYWORDS = frozenset("""auto break case char const continue default do double else enum extern float for goto if
inline int long register restrict return short signed sizeof static struct switch typedef union unsigned void
volatile while _Bool _Complex _Imaginary bool true false NULL main""".split())
_AUTO_ALL = 5  # detectors reading at most this many signals get every missing-signal pattern
_MAX_PATTERNS = 256


@dataclass(frozen=True)
class CExport:
    """What :func:`export_c` wrote: the two files and the tables the C step is indexed by.

    Attributes
    ----------
    header, source : pathlib.Path
        ``<name>.h`` and ``<name>.c``.
    name : str
        The C prefix of every exported symbol.
    n_states, n_controls, n_outputs, n_residuals : int
        Filter order, lengths of ``u`` and ``y``, and of ``out.r`` / ``out.fired``.
    controls, outputs, residuals : tuple of str
        The order of ``u``, ``y`` and of the residuals (the evaluator's).
    faults : tuple of str
        ``<name>_fault_names``: ``out.fault`` indexes it (``-1``: none); ``'unknown'`` is at ``unknown``.
    unknown : int
        The index of ``'unknown'``.
    evaluator : str
        ``'threshold'`` or ``'cusum'``.
    dt : float
        Sample time [s] of the exported (discrete) filter.
    precision : str
        ``'double'`` or ``'single'``.
    gap_patterns : tuple of tuple of str
        The missing-signal patterns the C code propagates exactly as Python (the first: every signal missing).
    error_gain : float
        First-order bound on ``max |r_C − r_Python|`` per unit of the largest input deviation so far (module
        docstring).
    const_bytes : int
        Size of the ``static const`` data of the source (matrices, gap maps, tables) for the target's flash budget.

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> ex = export_c(Detector(g, ThresholdEvaluator(thresholds=[0.5])), tempfile.mkdtemp(), name="m")
    >>> ex.n_states, ex.n_controls, ex.n_outputs, ex.n_residuals, ex.gap_patterns
    (1, 1, 1, 1, (('u', 'y'), ('u',), ('y',)))
    """

    header: Path
    source: Path
    name: str
    n_states: int
    n_controls: int
    n_outputs: int
    n_residuals: int
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    residuals: tuple[str, ...]
    faults: tuple[str, ...]
    unknown: int
    evaluator: str
    dt: float
    precision: str
    gap_patterns: tuple[tuple[str, ...], ...]
    error_gain: float
    const_bytes: int


def export_c(detector, directory: str | os.PathLike, *, name: str = "fdikit_monitor", dt: float | None = None,
             precision: str = "double", gap_patterns: Sequence[Sequence[str]] | None = None) -> CExport:
    """Write ``<name>.h`` and ``<name>.c``: the detector's online step as C99 (module docstring).

    Parameters
    ----------
    detector : Detector
        A :class:`~fdikit.detector.Detector` with a ThresholdEvaluator or CusumEvaluator, set up (thresholds).
    directory : str or PathLike
        Folder of the two files (created when missing); each file is written atomically.
    name : str, default "fdikit_monitor"
        Prefix of the files and of every C symbol: a C identifier (letters, digits, ``_``; no leading digit or
        ``_``; at most 40 characters; not a keyword).
    dt : float, optional
        Sample time [s]; needed for a continuous generator (ZOH), else it must be the generator's own.
    precision : {"double", "single"}, default "double"
        Arithmetic of the filter and the evaluator (``"single"``: ``float``; bound ``CExport.error_gain``).
    gap_patterns : sequence of sequence of str, optional
        The sets of signal names whose simultaneous dropout the C code propagates exactly as Python, replacing the
        defaults of the module docstring (every signal missing is always included; ``[]`` keeps only it).

    Returns
    -------
    CExport
        The paths and the tables of the C step.

    Raises
    ------
    ParameterError
        For an unsupported or unset evaluator (the message names the supported ones), a bad ``name``,
        ``precision`` or ``gap_patterns``, isolation tables that do not fit the residuals, or a detector that is
        not a Detector.
    ModelError
        For a continuous generator without ``dt``.
    DataError
        For a ``dt`` other than a discrete generator's own, evaluator parameters of the wrong length, a signature
        table the residuals do not map onto, or files that cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.decision import CusumEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[-2.0]], [[1.0, 2.0]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",))
    >>> ex = export_c(Detector(g, CusumEvaluator(drift=0.5, threshold=5.0)), tempfile.mkdtemp(), dt=0.01)
    >>> ex.evaluator, ex.dt, ex.n_states
    ('cusum', 0.01, 1)
    """
    from fdikit.atomic import atomic_path
    from fdikit.detector import Detector
    from fdikit.gaps import GapRule
    from fdikit.runtime.c_render import render_header, render_source

    if not isinstance(detector, Detector):
        raise ParameterError(f"detector must be a fdikit.detector.Detector, got {type(detector).__name__}")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,39}", name) or name in _KEYWORDS:
        raise ParameterError(f"name must be a C identifier of at most 40 characters starting with a letter (letters, "
                             f"digits, '_'; not a C keyword), got {name!r}")
    if precision not in ("double", "single"):
        raise ParameterError(f"precision must be 'double' or 'single', got {precision!r}")
    g = detector.generator.online(dt=dt, residual_cov=detector.residual_cov,
                                  recovery_tol=detector.recovery_tol).generator  # ZOH and checks as online()
    nv = g.B.shape[1]
    if nv == 0:
        raise ParameterError("the detector's generator reads no signal; there is nothing to export")
    rule = GapRule(g, detector.residual_cov, detector.recovery_tol)
    fitted = getattr(detector.evaluator, "names", None)
    idx = (list(range(len(g.residuals))) if fitted is None or tuple(fitted) == g.residuals
           else [g.residuals.index(r) for r in fitted])  # as Detector selects the evaluator's residuals
    ev, iso = _evaluator(detector.evaluator, len(idx))
    patterns = _patterns(g, gap_patterns)
    plan = _filter_plan(g, rule, idx, patterns, precision == "single")
    signals = g.controls + g.outputs
    faults = iso.pop("faults")
    plan.update(
        name=name, NAME=name.upper(), single=precision == "single", real="float" if precision == "single" else "double",
        detector=detector.name, description=detector.description, version=detector.fdikit_version,
        dt=float(g.dt), controls=g.controls, outputs=g.outputs, residuals=tuple(g.residuals[i] for i in idx),
        res_faults=iso.pop("res_faults"), columns=detector.columns, units=detector.units,
        offset=[float(x) for x in g.offset], evaluator=ev, isolation=iso, faults=faults,
        unknown=faults.index("unknown"), warm=detector.warmup_samples(g.dt),
        pattern_names=[tuple(s for s, b in zip(signals, bad) if b) for bad in patterns])
    eps = 2.0**-24 if precision == "single" else 2.0**-53
    gain = _error_gain(g, idx, eps) + _error_gain(g, idx, 2.0**-53)
    directory = Path(directory)
    header, source = directory / f"{name}.h", directory / f"{name}.c"
    htext, ctext = render_header(plan), render_source(plan)
    with atomic_path(header, suffix=".h") as th, atomic_path(source, suffix=".c") as tc:
        th.write_text(htext, encoding="ascii")
        tc.write_text(ctext, encoding="ascii")
    return CExport(header, source, name, g.n, len(g.controls), len(g.outputs), len(idx), g.controls, g.outputs,
                   plan["residuals"], tuple(faults), plan["unknown"], ev["kind"], float(g.dt), precision,
                   tuple(plan["pattern_names"]), float(gain), _const_bytes(ctext, precision == "single"))


# ---------------------------------------------------------------------------------------------------- evaluator
def _widen(what: str, value, q: int, default: float) -> np.ndarray:
    """One value per residual (a scalar broadcast), as the evaluators' ``_ready`` does; DataError otherwise."""
    if value is None:
        return np.full(q, float(default))
    arr = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if arr.size not in (1, q):
        raise DataError(f"{arr.size} {what} values for {q} residuals")
    return np.array(np.broadcast_to(arr, (q,)), dtype=float)


def _evaluator(ev, q: int) -> tuple[dict, dict]:
    """The evaluator's constants and its isolation tables; ParameterError for an evaluator that is not exported."""
    from fdikit.decision import CusumEvaluator, ThresholdEvaluator

    if type(ev) is ThresholdEvaluator:
        if ev.thresholds is None:
            raise ParameterError("the ThresholdEvaluator has no thresholds; pass thresholds= or call fit() before "
                                 "exporting")
        k, n = ev.persistence
        spec = {"kind": "threshold", "tau": _widen("threshold", ev.thresholds, q, 1.0),
                "center": _widen("center", ev.center, q, 0.0), "k": int(k), "n": int(n),
                "title": f"ThresholdEvaluator ({k} of {n} samples)"}
    elif type(ev) is CusumEvaluator:
        if ev.drift is None or ev.threshold is None:
            raise ParameterError("the CusumEvaluator has no drift/threshold; pass drift= and threshold= or call "
                                 "fit(fault_free, arl0=..., shift=...) before exporting")
        spec = {"kind": "cusum", "nu": _widen("drift", ev.drift, q, 0.5),
                "h": _widen("threshold", ev.threshold, q, 1.0), "mu": _widen("mean", ev.mean, q, 0.0),
                "sd": _widen("sigma", ev.sigma, q, 1.0),
                "two_sided": bool(ev.two_sided), "reset": ev.restart == "reset", "hold": int(ev.hold),
                "title": f"CusumEvaluator ({'two' if ev.two_sided else 'one'}-sided, restart {ev.restart!r}, "
                         f"hold {int(ev.hold)})"}
    else:
        raise ParameterError(f"export_c translates the evaluators {list(SUPPORTED_EVALUATORS)}, not "
                             f"{type(ev).__name__}; deploy it with Detector.online() or fdikit.runtime instead")
    iso = tuple(ev.isolates) if ev.isolates else (None,) * q
    if len(iso) != q:
        raise ParameterError(f"the evaluator has {len(iso)} 'isolates' entries for {q} residuals")
    return spec, _isolation(iso, ev.groups, ev.signatures, ev.names, q)


def _isolation(iso: tuple, groups, table, names, q: int) -> dict:
    """Tables of the isolation logic of :func:`fdikit.decision.common.isolate_fired`, as the evaluators' steps use
    it."""
    if table is not None:
        rnames = tuple(names) if names is not None else tuple(f"r{i}" for i in range(q))
        M = table.resolve(rnames, iso)
        if len(table.groups) > 64:
            raise ParameterError(f"the signature table has {len(table.groups)} residual groups; export_c handles at "
                                 "most 64")
        mask = [sum(1 << j for j in range(M.shape[1]) if M[i, j]) for i in range(q)]
        sig = [sum(1 << j for j, on in enumerate(row) if on) for row in table.matrix]
        faults = list(table.faults)
        kind = {"kind": "signature", "res_mask": mask, "sig": sig, "partial": table.match == "partial"}
    else:
        groups = tuple(groups) if groups is not None else ("",) * q
        if len(groups) != q:
            raise ParameterError(f"the evaluator has {len(groups)} 'groups' entries for {q} residuals")
        keys, res_key, grp_start = [], [0] * q, [0]
        for grp in dict.fromkeys(groups):  # fdikit.diagnosis.isolate: per filter, its faults ('?k': untied)
            cols = [k for k, gg in enumerate(groups) if gg == grp]
            names_k = sorted({iso[k] if iso[k] is not None else f"?{k}" for k in cols})
            for k in cols:
                res_key[k] = len(keys) + names_k.index(iso[k] if iso[k] is not None else f"?{k}")
            keys += names_k
            grp_start.append(len(keys))
        faults = list(dict.fromkeys(k for k in keys if not k.startswith("?")))
        kind = {"kind": "logic", "res_key": res_key, "grp_start": grp_start,
                "key_fault": [-1 if k.startswith("?") else faults.index(k) for k in keys]}
    if "unknown" not in faults:
        faults.append("unknown")
    kind.update(faults=faults, res_faults=[str(f) if f is not None else "" for f in iso])
    return kind


# ---------------------------------------------------------------------------------------------------- filter
def _patterns(g, extra) -> list[np.ndarray]:
    """Missing-signal patterns (bool masks over [u; y]) to precompute: all missing first, then the defaults or the
    given ones."""
    signals = g.controls + g.outputs
    nv, mu = len(signals), len(g.controls)
    out = [np.ones(nv, bool)]
    if extra is not None:
        combos = []
        if isinstance(extra, (str, bytes)) or not isinstance(extra, Sequence):
            raise ParameterError("gap_patterns must be a sequence of sets of signal names, e.g. [('y1', 'y2')]")
        for pat in extra:
            pat = (pat,) if isinstance(pat, str) else tuple(pat)
            unknown = [s for s in pat if s not in signals]
            if unknown or not pat:
                raise ParameterError(f"gap pattern {list(pat)} must name one or more signals the detector reads "
                                     f"{list(signals)}; unknown {unknown}")
            combos.append(tuple(signals.index(s) for s in pat))
    elif nv <= _AUTO_ALL:
        combos = [c for k in range(nv - 1, 0, -1) for c in itertools.combinations(range(nv), k)]
    else:
        combos = [tuple(range(mu, nv)), tuple(range(mu))] if mu and nv > mu else []
        combos += [(j,) for j in range(nv)]
    seen = {out[0].tobytes()}
    for c in combos:
        m = np.zeros(nv, bool)
        m[list(c)] = True
        if m.tobytes() not in seen:
            seen.add(m.tobytes())
            out.append(m)
    if len(out) > _MAX_PATTERNS:
        raise ParameterError(f"{len(out)} gap patterns; export_c precomputes at most {_MAX_PATTERNS}")
    return out


def _gap_map(g, rule, ok: np.ndarray) -> np.ndarray:
    """``F`` with ``z+ = F [z; v0; last]`` on an invalid sample of pattern ``ok`` (v0: v with the bad entries 0):
    :meth:`fdikit.gaps.GapRule.propagate` written as one matrix."""
    n, nv, mu = g.n, g.B.shape[1], rule.mu
    bad_y, _, _, parts, _, _, _ = rule.pattern(ok)
    W0 = np.zeros((nv, n + 2 * nv))  # w = W x: valid entries v0, bad controls (and outputs, for now) last
    for j in range(nv):
        W0[j, n + j if ok[j] else n + nv + j] = 1.0
    W0[mu + bad_y] = 0.0
    F = np.zeros((n, n + 2 * nv))
    for states, rows, Mp, Pi in parts:
        if not states.size:
            continue
        W = W0.copy()
        if bad_y.size:
            K = g.D[rows] @ W0  # known = C z + D_u w_u + D_good v_good
            K[:, states] += g.C[np.ix_(rows, states)]
            L = np.zeros((bad_y.size, n + 2 * nv))
            L[:, n + nv + mu + bad_y] = Pi
            W[mu + bad_y] = -(Mp @ K) + L
        F[states] = g.B[states] @ W
        F[np.ix_(states, states)] += g.A[np.ix_(states, states)]
    return F


def _csr(M: np.ndarray) -> tuple[list[int], list[int], list[float]]:
    rows, cols = np.nonzero(M)
    ptr = np.searchsorted(rows, np.arange(M.shape[0] + 1)).tolist()
    return ptr, cols.tolist(), M[rows, cols].tolist()


def _stacked_csr(mats: list[np.ndarray]) -> tuple[list[int], list[int], list[float]]:
    """Compressed rows of several matrices of equal shape: ptr per matrix (absolute offsets), shared idx/val."""
    ptr, idx, val = [], [], []
    for M in mats:
        p, i, v = _csr(M)
        ptr += [x + len(idx) for x in p]
        idx += i
        val += v
    return ptr, idx, val


def _blocks(n: int, coupling: list[np.ndarray], C: np.ndarray) -> list[list[int]]:
    """Groups of states coupled by any of the matrices or by a residual row (the blocks the covariance lives in)."""
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for M in coupling:
        for i, j in zip(*np.nonzero(M)):
            parent[find(int(i))] = find(int(j))
    for row in C:
        nz = np.flatnonzero(row)
        for j in nz[1:]:
            parent[find(int(j))] = find(int(nz[0]))
    out: dict[int, list[int]] = {}
    for i in range(n):
        out.setdefault(find(i), []).append(i)
    return sorted(out.values())


def _filter_plan(g, rule, idx: list[int], patterns: list[np.ndarray], single: bool) -> dict:
    """Matrices of the C step in the block order of the states: filter, gap maps, recovery rule."""
    n, nv = g.n, g.B.shape[1]
    maps = [(_gap_map(g, rule, ~bad), *rule.pattern(~bad)[4:]) for bad in patterns]
    blocks = _blocks(n, [g.A] + [m[1] for m in maps] + [m[2] for m in maps], g.C)
    perm = np.array([i for b in blocks for i in b], dtype=int)
    where = np.empty(n, int)
    where[perm] = np.arange(n)
    A, B, C = g.A[np.ix_(perm, perm)], g.B[perm], g.C[:, perm]
    starts = np.cumsum([0] + [len(b) for b in blocks]).tolist()
    offs = np.cumsum([0] + [len(b) ** 2 for b in blocks]).tolist()
    blk_of = np.repeat(np.arange(len(blocks)), [len(b) for b in blocks])

    def pos(i: int, j: int) -> int:  # place of P[i, j] (permuted indices, same block) in the block storage
        b = blk_of[i]
        nb = starts[b + 1] - starts[b]
        return offs[b] + (i - starts[b]) * nb + (j - starts[b])

    Fs, Ts, q_ptr, q_pos, q_val = [], [], [0], [], []
    for F, T, Q, _ in maps:
        F = F[perm]
        F[:, :n] = F[:, :n][:, perm]
        Fs.append(F)
        Ts.append(T[np.ix_(perm, perm)])
        Qp = Q[np.ix_(perm, perm)]
        for i, j in zip(*np.nonzero(Qp)):
            q_pos.append(pos(int(i), int(j)))
            q_val.append(float(Qp[i, j]))
        q_ptr.append(len(q_pos))
    row_blk = [int(blk_of[np.flatnonzero(row)[0]]) if np.any(row) else -1 for row in C]
    width = n + 2 * nv
    return {
        "n": n, "mu": rule.mu, "nv": nv, "nr": len(idx), "idx_t": "uint16_t" if width < 65535 else "uint32_t",
        "AB": _csr(np.hstack([A, B])), "CD": _csr(np.hstack([C, g.D])[idx]), "A": _csr(A), "Cg": _csr(C),
        "F": _stacked_csr(Fs), "T": _stacked_csr(Ts), "Q": (q_ptr, q_pos, q_val), "held": [int(m[3]) for m in maps],
        "pat_bad": [int(b) for bad in patterns for b in bad], "npat": len(patterns), "row_blk": row_blk,
        "limit": [float(x) for x in rule.limit], "settle": int(rule.settle), "blk_start": starts, "blk_off": offs,
        "sizes": {"z": max(n, 1), "P": max(offs[-1], 1), "W": max(max((len(b) ** 2 for b in blocks), default=1), 1)},
    }


_SIZES = {"double": 8, "float": 4, "int32_t": 4, "uint16_t": 2, "uint32_t": 4, "uint8_t": 1, "uint64_t": 8}


def _const_bytes(source: str, single: bool) -> int:
    """Bytes of the ``static const`` arrays of a generated source."""
    types = {"real_t": "float" if single else "double",
             "IDX_T": re.search(r"typedef (\w+) IDX_T;", source).group(1)}
    return sum(_SIZES[types.get(ctype, ctype)] * int(count)
               for ctype, count in re.findall(r"static const (\w+) \w+\[(\d+)\]", source))


def _error_gain(g, idx: list[int], eps: float, tol: float = 1e-10, cap: int = 20000) -> float:
    """First-order bound on ``max |r̂ − r|`` per unit of ``max ||v||∞`` for arithmetic of unit roundoff ``eps``."""
    A, B, C, D = g.A, g.B, g.C[idx], g.D[idx]
    n = g.n
    m = max(int(np.count_nonzero(np.hstack([A, B]), axis=1).max(initial=0)),
            int(np.count_nonzero(np.hstack([C, D]), axis=1).max(initial=0))) + 1
    gam = m * eps / (1 - m * eps)  # rounding of the matrices and of one sum of m terms
    nrm = (lambda M: float(np.abs(M).sum(axis=1).max(initial=0.0)))  # noqa: E731
    if n == 0:
        return (gam + eps) * nrm(D)
    sCA, sAB = np.zeros_like(C), np.zeros_like(B)
    Ak, head, tail_sum = np.eye(n), 0.0, None
    for j in range(cap):
        a = nrm(Ak)
        if tail_sum is None and j > 0 and a < 0.5:
            tail_sum = head / (1 - a)  # Σ_j ||A^j|| ≤ (Σ_{l<J} ||A^l||) / (1 − ||A^J||)
        if tail_sum is not None and a < tol:
            sCA, sAB = nrm(sCA) + nrm(C) * a * tail_sum, nrm(sAB) + a * tail_sum * nrm(B)
            break
        head += a
        sCA += np.abs(C @ Ak)
        sAB += np.abs(Ak @ B)
        Ak = Ak @ A
    else:
        return float("inf")
    Z = sAB  # max ||z||∞ per unit of max ||v||∞
    delta = gam * (nrm(A) * Z + nrm(B)) + eps * nrm(B)  # per-step state error drive
    return sCA * delta + eps * nrm(D) + gam * (nrm(C) * Z + nrm(D))
