"""The exported C detector (fdikit.runtime.c_export), compiled with the system C compiler (-std=c99 -Wall -Wextra
-Werror -pedantic -O2) and loaded with ctypes, against the Python online step (``Detector.online().step``) and the
batch ``Detector.run``, sample for sample: residuals to 1e-12, identical decisions, flags and faults, on fault-free
and faulty traces with bad samples of every kind, after reset.  Without a C compiler the compiled tests are skipped,
unless FDIKIT_REQUIRE_CC=1 (CI), which makes that a failure."""

from __future__ import annotations

import ctypes
import itertools
import os
import shutil
import subprocess

import numpy as np
import pytest

from fdikit.decision import CusumEvaluator, GlrEvaluator, ThresholdEvaluator
from fdikit.decision.common import isolate_fired
from fdikit.decision.signature import SignatureTable
from fdikit.detector import Detector
from fdikit.errors import DataError, ModelError, ParameterError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.runtime.c_export import SUPPORTED_EVALUATORS, export_c
from fdikit.trace import Trace

CC = shutil.which("cc") or shutil.which("gcc")
FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2"]
DT = 0.01
OP = OperatingPoint(u0={"u0": 1.0, "u1": -2.0}, y0={"y0": 0.5, "y1": 3.0, "y2": -1.0})


def _cc() -> str:
    if CC is None:
        if os.environ.get("FDIKIT_REQUIRE_CC") == "1":
            pytest.fail("FDIKIT_REQUIRE_CC=1 but no C compiler (cc or gcc) is on PATH")
        pytest.skip("no C compiler (cc or gcc); set FDIKIT_REQUIRE_CC=1 to make this a failure")
    return CC


# ---------------------------------------------------------------------------------------------------- fixtures
def _observer(Ap, Bp, L, controls, outputs, prefix):
    p, m = len(outputs), len(controls)
    Cp = np.eye(p)
    return ResidualGenerator(Ap - L @ Cp, np.hstack([Bp, L]), -Cp, np.hstack([np.zeros((p, m)), np.eye(p)]),
                             controls, outputs, tuple(f"{prefix}:{o}" for o in outputs), dt=DT,
                             isolates=tuple(f"{o}_sensor" for o in outputs), operating_point=OP)


def _bank():
    """Two observers stacked (block-diagonal A), sharing y1 and u1, about an operating point."""
    g1 = _observer(np.array([[0.9, 0.05], [0.0, 0.8]]), np.array([[0.1, 0.0], [0.0, 0.1]]), np.diag([0.5, 0.4]),
                   ("u0", "u1"), ("y0", "y1"), "f1")
    g2 = _observer(np.array([[0.8, 0.0], [0.05, 0.85]]), np.array([[0.1], [0.0]]), np.diag([0.4, 0.5]),
                   ("u1",), ("y1", "y2"), "f2")
    return stack_generators([g1, g2])


def _trace(N, seed, faults=(), bad=True):
    """Absolute signals of the plant the bank models; sensor biases ``(signal, start, size)``; bad samples."""
    rng = np.random.default_rng(seed)
    u = 0.3 * rng.standard_normal((N, 2))
    x = np.zeros(3)
    y = np.empty((N, 3))
    for k in range(N):
        y[k] = x + 0.02 * rng.standard_normal(3)
        x = np.array([0.9 * x[0] + 0.05 * x[1] + 0.1 * u[k, 0], 0.8 * x[1] + 0.1 * u[k, 1],
                      0.05 * x[1] + 0.85 * x[2]]) + 0.005 * rng.standard_normal(3)
    for sig, start, size in faults:
        y[start:, int(sig[1])] += size
    u, y = u + [1.0, -2.0], y + [0.5, 3.0, -1.0]
    valid = np.ones(N, bool)
    if bad:
        valid[[40, 41, 42, 300]] = False  # whole-sample dropouts (valid=False)
        valid[500:530] = False  # a long gap: recovery with the hold of held controls
        y[100, 1] = np.nan  # one sensor out (a listed pattern)
        y[[150, 151], 0] = np.nan
        y[[150, 151], 2] = np.inf  # two sensors out together
        u[200, 0] = -np.inf  # a control out: held
        u[250, 1], y[250, 0] = np.nan, np.nan
        y[700:705, :] = np.nan  # every output out, controls fine
    return Trace(np.arange(N) * DT, u, y, ("u0", "u1"), ("y0", "y1", "y2"), valid=valid)


@pytest.fixture(scope="module")
def detectors():
    g = _bank()
    healthy = g.run(_trace(3000, 1, bad=False))
    sel = ("f2:y2", "f1:y0", "f1:y1", "f2:y1")  # the evaluator reads a reordering of the generator's residuals
    hs = healthy.select(sel)
    cov = np.cov(healthy.r.T)  # couples the two filters' recovery covariance (one block)
    thr = ThresholdEvaluator(persistence=(2, 3), groups=("f2", "f1", "f1", "f2")).fit(hs, false_alarm_prob=1e-3)
    table = SignatureTable({"y0_sensor": ["f1:y0"], "y1_sensor": ["f1:y1", "f2:y1"], "y2_sensor": ["f2:y2"]},
                           match="partial")
    cus = CusumEvaluator(hold=3, signatures=table).fit(hs, arl0=2000.0, shift=0.05)
    cus1 = CusumEvaluator(drift=0.5, threshold=8.0, two_sided=False, restart="none",
                          isolates=("y2_sensor", None, "y1_sensor", "y1_sensor")).fit(hs)
    return {"thr": Detector(g, thr, warmup=0.05, recovery_tol=0.05, residual_cov=cov, units={"y2": "deg"},
                            columns={"u0": "THROTTLE"}, name="bank"),
            "cus": Detector(g, cus, recovery_tol=0.2),
            "cus1": Detector(g, cus1)}


@pytest.fixture(scope="module")
def built(detectors, tmp_path_factory):
    """Every small export in one shared library (one compiler run)."""
    cc = _cc()
    d = tmp_path_factory.mktemp("cexport")
    ex = {"thr": export_c(detectors["thr"], d, name="mon_t"),
          "single": export_c(detectors["thr"], d, name="mon_s", precision="single"),
          "cus": export_c(detectors["cus"], d, name="mon_c"),
          "cus1": export_c(detectors["cus1"], d, name="mon_c1")}
    lib = d / "libmon.so"
    proc = subprocess.run([cc, *FLAGS, "-shared", "-fPIC", "-o", str(lib), *[str(e.source) for e in ex.values()],
                           "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return ex, ctypes.CDLL(str(lib)), d


class _C:
    """One exported monitor driven through ctypes."""

    def __init__(self, lib, ex):
        real = ctypes.c_float if ex.precision == "single" else ctypes.c_double
        nr = ex.n_residuals
        self.Out = type("Out", (ctypes.Structure,), {"_fields_": [
            ("r", real * nr), ("fired", ctypes.c_bool * nr), ("alarm", ctypes.c_bool), ("fault", ctypes.c_int32),
            ("valid", ctypes.c_bool), ("sample_valid", ctypes.c_bool), ("recovering", ctypes.c_bool)]})
        f = lambda s: getattr(lib, f"{ex.name}_{s}")  # noqa: E731
        self._step, self._reset, self._isolate = f("step"), f("reset"), f("isolate")
        self._step.argtypes = [ctypes.c_void_p] * 4
        self._step.restype = ctypes.c_int
        f("state_size").restype = ctypes.c_uint32
        self.state = ctypes.create_string_buffer(f("state_size")())
        f("init")(self.state)
        self.out = self.Out()
        self.ex = ex

    def reset(self):
        self._reset(self.state)

    def step(self, u, y):
        status = self._step(self.state, u.ctypes.data, y.ctypes.data, ctypes.byref(self.out))
        return status, self.out

    def fault(self, o):
        return "none" if o.fault < 0 else self.ex.faults[o.fault]

    def isolate(self, fired):
        return self._isolate((ctypes.c_bool * len(fired))(*fired))


def _compare(cmon, det, trace, rtol=1e-12, bound=None, dt=None):
    """Step both through ``trace`` (NaN rows where ``valid`` is False); returns what was seen."""
    ref = det.online(dt=dt)
    U, Y = trace.u.copy(), trace.y.copy()
    U[~trace.valid], Y[~trace.valid] = np.nan, np.nan
    batch = det.run(trace)
    rb = det.residuals(trace).r
    scale = np.nanmax(np.abs(rb))
    seen = {"alarm": 0, "recovering": 0, "bad": 0, "held": 0, "faults": set(), "status": []}
    for k in range(len(trace)):
        d = ref.step(trace.u[k], trace.y[k], valid=bool(trace.valid[k]))
        status, o = cmon.step(np.ascontiguousarray(U[k]), np.ascontiguousarray(Y[k]))
        r = np.array(o.r[:], dtype=float)
        if bound is None:
            assert status == 0, k
            np.testing.assert_allclose(r, ref.residuals, rtol=rtol, atol=rtol * scale, err_msg=f"sample {k}")
            np.testing.assert_allclose(r, rb[k], rtol=rtol, atol=rtol * scale, err_msg=f"sample {k} (batch)")
            assert list(o.fired) == d.fired.tolist() == batch.fired[k].tolist(), k
            assert o.alarm == d.alarm == bool(batch.alarm[k]), k
            assert cmon.fault(o) == d.fault == batch.isolated[k], k
            assert o.valid == d.valid == bool(batch.valid[k]), k
        else:
            assert np.array_equal(np.isnan(r), np.isnan(ref.residuals)), k
            bound(k, r, ref.residuals)
        assert o.sample_valid == ref.last_valid and o.recovering == ref.last_recovering, k
        seen["alarm"] += d.alarm
        seen["recovering"] += ref.last_recovering
        seen["bad"] += not np.isfinite(ref.residuals).all()
        seen["held"] += not d.valid
        seen["faults"].add(d.fault)
        seen["status"].append(status)
    return seen


# ---------------------------------------------------------------------------------------------------- the step
def test_threshold_bank_equals_python_sample_for_sample(built, detectors):
    ex, lib, _ = built
    det = detectors["thr"]
    c = _C(lib, ex["thr"])
    clean = _compare(c, det, _trace(600, 7, bad=False))
    assert clean["alarm"] <= 3 and clean["bad"] == 0
    c.reset()
    seen = _compare(c, det, _trace(1000, 5, faults=[("y1", 350, 0.3), ("y0", 800, 0.4)]))
    assert seen["bad"] == 4 + 30 + 1 + 2 + 1 + 1 + 5 and seen["recovering"] > 10 and seen["alarm"] > 100
    assert {"none", "y1_sensor"} <= seen["faults"]
    c.reset()  # after reset: the same numbers again
    again = _compare(c, det, _trace(1000, 5, faults=[("y1", 350, 0.3), ("y0", 800, 0.4)]))
    assert again == seen


def test_cusum_exports_equal_python(built, detectors):
    ex, lib, _ = built
    tr = _trace(1200, 9, faults=[("y2", 400, 0.15), ("y1", 900, 0.15)])
    seen = _compare(_C(lib, ex["cus"]), detectors["cus"], tr)  # two-sided, restarts, hold, partial signatures
    assert seen["alarm"] > 50 and {"y2_sensor"} <= seen["faults"]
    long = _trace(4300, 3, faults=[("y1", 4200, 0.3)])  # past the rebase of the running sums (4096 valid samples)
    seen1 = _compare(_C(lib, ex["cus1"]), detectors["cus1"], long)  # one-sided, never restarted, an untied residual
    assert seen1["alarm"] > 0


def test_unlisted_gap_pattern_is_flagged_and_listing_it_makes_it_exact(tmp_path):
    cc = _cc()
    rng = np.random.default_rng(2)
    D = np.zeros((2, 6))
    D[0, 3] = D[1, 5] = 1.0
    g = ResidualGenerator(np.diag([0.5, 0.6]), rng.standard_normal((2, 6)), -np.eye(2), D, ("a", "b", "c"),
                          ("p", "q", "s"), ("r0", "r1"), dt=DT)  # 6 signals: not every pattern is listed
    det = Detector(g, ThresholdEvaluator(thresholds=[1.0, 1.0]))
    ex0 = export_c(det, tmp_path, name="gp0")
    ex1 = export_c(det, tmp_path, name="gp1", gap_patterns=[("p", "s"), "q"])  # replaces the defaults
    assert len(ex0.gap_patterns) == 9 and ("p", "s") not in ex0.gap_patterns
    assert ex1.gap_patterns == (("a", "b", "c", "p", "q", "s"), ("p", "s"), ("q",))
    assert ex1.const_bytes < ex0.const_bytes
    lib = tmp_path / "libgp.so"
    subprocess.run([cc, *FLAGS, "-shared", "-fPIC", "-o", str(lib), str(ex0.source), str(ex1.source), "-lm"],
                   check=True)
    so = ctypes.CDLL(str(lib))
    N = 60
    u, y = rng.standard_normal((N, 3)), rng.standard_normal((N, 3))
    y[20:23, [0, 2]] = np.nan
    tr = Trace(np.arange(N) * DT, u, y, g.controls, g.outputs)
    seen = _compare(_C(so, ex1), det, tr)
    assert seen["bad"] == 3 and set(seen["status"]) == {0}
    c0 = _C(so, ex0)
    for k in range(N):
        status, o = c0.step(u[k].copy(), y[k].copy())
        assert status == (1 if 20 <= k < 23 else 0)  # propagated as "every signal missing", and flagged
        assert np.isfinite(o.r[:]).all() == o.sample_valid or 23 <= k  # NaN and invalid on the gap


def test_single_precision_within_the_stated_bound(built, detectors):
    ex, lib, _ = built
    e = ex["single"]
    assert e.precision == "single" and 0 < e.error_gain < 1e-3
    det = detectors["thr"]
    tr = _trace(800, 11, faults=[("y1", 400, 0.3)], bad=False)
    v = np.abs(np.hstack([tr.u, tr.y]) - det.generator.offset).max(axis=1)
    vmax = np.maximum.accumulate(v)
    worst = []

    def bound(k, r, r_py):
        err = np.abs(r - r_py).max()
        assert err <= e.error_gain * vmax[k], (k, err, e.error_gain * vmax[k])
        worst.append(err / vmax[k])

    seen = _compare(_C(lib, e), det, tr, bound=bound)
    assert seen["alarm"] > 0 and max(worst) > 0  # float arithmetic really differs, within the bound


def test_double_precision_error_gain_is_tiny(built):
    assert built[0]["thr"].error_gain < 1e-12


def test_isolation_tables_equal_the_python_logic_for_every_pattern(built, detectors):
    ex, lib, _ = built
    for key in ("thr", "cus", "cus1"):
        ev = detectors[key].evaluator
        c = _C(lib, ex[key])
        q = ex[key].n_residuals
        iso = ev.isolates or (None,) * q
        for bits in itertools.product([False, True], repeat=q):
            want = str(isolate_fired(np.array([bits]), iso, ev.groups, ev.signatures, ev.names)[0])
            got = c.isolate(bits)
            assert ("none" if got < 0 else ex[key].faults[got]) == want, (key, bits)
    assert ex["cus"].faults == ("y0_sensor", "y1_sensor", "y2_sensor", "unknown") and ex["cus"].unknown == 3


def test_path_bank_exports_and_equals_python(tmp_path):
    cc = _cc()
    from fdikit.studies.path1996 import path_bank

    bank = path_bank()
    g = bank.generator
    rng = np.random.default_rng(4)
    N = 400  # the recovery after the first gap (sample 100) outlasts the run, so the fault starts before it
    tr0 = Trace(np.arange(N) * DT, 0.01 * rng.standard_normal((N, len(g.controls))),
                0.01 * rng.standard_normal((N, len(g.outputs))), g.controls, g.outputs)
    gd = g.discretize(DT)
    ev = ThresholdEvaluator(persistence=(2, 2), groups=bank.groups).fit(gd.run(tr0), false_alarm_prob=1e-2)
    det = Detector(g, ev)
    pats = [g.outputs, g.controls, *[(s,) for s in g.controls + g.outputs], g.outputs[:2]]  # defaults + one
    ex = export_c(det, tmp_path, name="path", dt=DT, gap_patterns=pats)
    assert ex.n_states == 50 and ex.n_residuals == 29 and len(ex.gap_patterns) == 1 + 2 + 15 + 1
    lib = tmp_path / "libpath.so"
    subprocess.run([cc, *FLAGS, "-shared", "-fPIC", "-o", str(lib), str(ex.source), "-lm"], check=True)
    y = 0.01 * rng.standard_normal((N, len(g.outputs)))
    y[40:, 3] += 1.0  # a sensor bias of 100 noise standard deviations
    y[100:103, 0] = np.nan
    y[120, :2] = np.nan  # the listed two-sensor pattern
    valid = np.ones(N, bool)
    valid[150:160] = False
    tr = Trace(np.arange(N) * DT, tr0.u, y, g.controls, g.outputs, valid=valid)
    seen = _compare(_C(ctypes.CDLL(str(lib)), ex), det, tr, dt=DT)
    assert seen["alarm"] > 0 and seen["recovering"] > 0 and seen["bad"] == 14


def test_edge_shapes_compile_and_equal_python(tmp_path):
    """No filter state (r = D v), no controls, an evaluator fitted on a subset of the residuals, single-precision
    CUSUM (compiled and stepped; the residuals to the stated bound)."""
    cc = _cc()
    rng = np.random.default_rng(8)
    static = ResidualGenerator(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[-1.0, 1.0]], ("u",), ("y",),
                               ("r",), dt=DT)
    noctl = ResidualGenerator(np.diag([0.5, 0.6]), np.diag([0.5, 0.4]), -np.eye(2), np.eye(2), (), ("y0", "y1"),
                              ("r0", "r1"), dt=DT, isolates=("f0", "f1"))
    N = 200
    tr_s = Trace(np.arange(N) * DT, rng.standard_normal((N, 1)), rng.standard_normal((N, 1)), ("u",), ("y",))
    y = rng.standard_normal((N, 2))
    y[120:] += [0.0, 3.0]
    y[[50, 51], 1] = np.nan
    tr_n = Trace(np.arange(N) * DT, np.zeros((N, 0)), y, (), ("y0", "y1"))
    sub = ThresholdEvaluator(persistence=(1, 2)).fit(noctl.run(tr_n).select(("r1",)), false_alarm_prob=0.01)
    dets = {"e_static": Detector(static, CusumEvaluator(drift=0.5, threshold=4.0)),
            "e_noctl": Detector(noctl, sub)}
    ex = {k: export_c(d, tmp_path, name=k) for k, d in dets.items()}
    ex["e_single"] = export_c(dets["e_static"], tmp_path, name="e_single", precision="single")
    lib = tmp_path / "libedge.so"
    subprocess.run([cc, *FLAGS, "-shared", "-fPIC", "-o", str(lib), *[str(e.source) for e in ex.values()], "-lm"],
                   check=True)
    so = ctypes.CDLL(str(lib))
    assert ex["e_static"].n_states == 0 and ex["e_noctl"].residuals == ("r1",) and ex["e_noctl"].n_controls == 0
    assert _compare(_C(so, ex["e_static"]), dets["e_static"], tr_s)["alarm"] > 0
    seen = _compare(_C(so, ex["e_noctl"]), dets["e_noctl"], tr_n)
    assert seen["bad"] == 2 and "f1" in seen["faults"]

    def bound(k, r, r_py):
        assert np.abs(r - r_py).max() <= ex["e_single"].error_gain * 10.0

    _compare(_C(so, ex["e_single"]), dets["e_static"], tr_s, bound=bound)


# ---------------------------------------------------------------------------------------------------- the files
def test_header_documents_signals_and_compiles_standalone(built, detectors):
    cc = _cc()
    ex, _, d = built
    h = ex["thr"].header.read_text()
    assert "u[0]  u0   (log column 'THROTTLE', unit SI, operating point 1)" in h
    assert "y[2]  y2   (log column 'y2', unit deg, operating point -1)" in h
    assert "[0] f2:y2  (tied to y2_sensor)" in h and "#define MON_T_NR 4" in h
    src = ex["thr"].source.read_text()
    assert "malloc" not in src and "static double" not in src and "#include <stdio.h>" not in src
    includes = {ln for t in (h, src) for ln in t.splitlines() if ln.startswith("#include <")}
    assert includes <= {"#include <math.h>", "#include <stdint.h>", "#include <stdbool.h>", "#include <string.h>"}
    main = d / "main.c"
    main.write_text('#include <math.h>\n#include "mon_t.h"\nint main(void) {\n    mon_t_state s;\n    mon_t_output o;\n'
                    "    const double u[MON_T_NU] = {1.0, -2.0}, y[MON_T_NY] = {0.5, 3.0, NAN};\n"
                    "    mon_t_init(&s);\n    return mon_t_step(&s, u, y, &o) == MON_T_STATUS_OK && !o.sample_valid"
                    " && mon_t_step((mon_t_state *)0, u, y, &o) == MON_T_STATUS_NULL ? 0 : 1;\n}\n")
    exe = d / "main"
    subprocess.run([cc, *FLAGS, "-o", str(exe), str(main), str(ex["thr"].source), "-lm"], check=True)
    assert subprocess.run([str(exe)]).returncode == 0
    assert sorted(p.name for p in d.iterdir() if p.name.startswith("mon_t.")) == ["mon_t.c", "mon_t.h"]


def test_counts_and_tables(built, detectors):
    e = built[0]["thr"]
    assert (e.n_states, e.n_controls, e.n_outputs, e.n_residuals) == (4, 2, 3, 4)
    assert e.controls == ("u0", "u1") and e.outputs == ("y0", "y1", "y2") and e.dt == DT
    assert e.residuals == detectors["thr"].residual_names and e.evaluator == "threshold"
    assert len(e.gap_patterns) == 31 and e.gap_patterns[0] == ("u0", "u1", "y0", "y1", "y2")
    assert e.faults[e.unknown] == "unknown"


# ---------------------------------------------------------------------------------------------------- refusals
class _Custom:
    names = None

    def run(self, r):
        return r

    def step(self, r, valid=True):
        return r

    def reset(self):
        pass


def test_refusals(detectors, tmp_path):
    det = detectors["thr"]
    g = det.generator
    for ev in (_Custom(), GlrEvaluator(window=5, threshold=10.0)):
        with pytest.raises(ParameterError, match="ThresholdEvaluator.*CusumEvaluator"):
            export_c(Detector(g, ev), tmp_path)
    assert SUPPORTED_EVALUATORS == ("ThresholdEvaluator", "CusumEvaluator")
    with pytest.raises(ParameterError, match="no thresholds"):
        export_c(Detector(g, ThresholdEvaluator()), tmp_path)
    with pytest.raises(ParameterError, match="no drift"):
        export_c(Detector(g, CusumEvaluator()), tmp_path)
    for bad in ("my-monitor", "1abc", "int", "_x", "", "a" * 41, 3):
        with pytest.raises(ParameterError, match="C identifier"):
            export_c(det, tmp_path, name=bad)
    with pytest.raises(ParameterError, match="precision"):
        export_c(det, tmp_path, precision="half")
    with pytest.raises(ParameterError, match="gap pattern"):
        export_c(det, tmp_path, gap_patterns=[("y9",)])
    with pytest.raises(ParameterError, match="Detector"):
        export_c(g, tmp_path)
    with pytest.raises(DataError, match="3 threshold values for 4"):
        export_c(Detector(g, ThresholdEvaluator(thresholds=[1.0, 1.0, 1.0])), tmp_path)
    cont = ResidualGenerator([[-1.0]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",))
    with pytest.raises(ModelError, match="dt"):
        export_c(Detector(cont, ThresholdEvaluator(thresholds=[1.0])), tmp_path)
    with pytest.raises(DataError, match="dt"):
        export_c(det, tmp_path, dt=0.5)
    assert not list(tmp_path.iterdir())  # nothing half-written
