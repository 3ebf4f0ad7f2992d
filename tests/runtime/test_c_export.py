"""The exported C detector, compiled with the system C compiler, against the Python online step."""

import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest

from fdikit.decision import CusumEvaluator, ThresholdEvaluator
from fdikit.detector import Detector
from fdikit.errors import ParameterError
from fdikit.operating_point import OperatingPoint
from fdikit.residuals import ResidualGenerator, stack_generators
from fdikit.runtime.c_export import export_c
from fdikit.trace import Trace

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None and os.environ.get("FDIKIT_REQUIRE_CC") != "1",
                              reason="no C compiler (cc/gcc); set FDIKIT_REQUIRE_CC=1 to make this a failure")


def _generator(rng, n, name, controls, outputs):
    A = rng.standard_normal((n, n))
    A *= 0.8 / max(abs(np.linalg.eigvals(A)))
    nv, q = len(controls) + len(outputs), len(outputs)
    return ResidualGenerator(A, 0.3 * rng.standard_normal((n, nv)), rng.standard_normal((q, n)),
                             np.hstack([np.zeros((q, len(controls))), np.eye(q)]), controls, outputs,
                             tuple(f"{name}_r{i}" for i in range(q)), dt=0.01,
                             isolates=tuple(f"{o}_sensor" for o in outputs))


def _detector():
    rng = np.random.default_rng(11)
    g = stack_generators([_generator(rng, 3, "a", ("u0",), ("y0", "y1")),
                          _generator(rng, 2, "b", ("u1",), ("y1", "y2"))])
    op = OperatingPoint(u0={"u0": 1.0, "u1": -2.0}, y0={"y0": 0.5, "y1": 3.0, "y2": -1.0})
    g = ResidualGenerator(g.A, g.B, g.C, g.D, g.controls, g.outputs, g.residuals, g.dt, g.isolates, op)
    healthy = g.run(_trace(g, 4000, 1, bias=False))
    sel = (g.residuals[3], g.residuals[0], g.residuals[1], g.residuals[2])
    groups = ("b", "a", "a", "b")
    ev = ThresholdEvaluator(persistence=(2, 3), groups=groups).fit(healthy.select(sel), false_alarm_prob=1e-3)
    return Detector(g, ev, warmup=0.03, recovery_tol=0.05)


def _trace(g, N, seed, bias=True):
    rng = np.random.default_rng(seed)
    u = 0.1 * rng.standard_normal((N, 2)) + [1.0, -2.0]
    y = 0.1 * rng.standard_normal((N, 3)) + [0.5, 3.0, -1.0]
    if bias:
        y[N // 2 :, 2] += 1.0
        y[N // 3 : N // 2, 0] += 1.0
    valid = np.ones(N, bool)
    valid[[40, 41, 42, 400, 700, 701]] = False  # whole-sample dropouts: the gap rule and its recovery
    return Trace(np.arange(N) * 0.01, u, y, g.controls, g.outputs, valid=valid)


def _compile(tmp_path, det, name="mon"):
    out = export_c(det, tmp_path, name=name)
    lib = tmp_path / f"lib{name}.so"
    proc = subprocess.run([CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-shared", "-fPIC",
                           "-o", str(lib), str(out.source), "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out, ctypes.CDLL(str(lib))


@needs_cc
def test_c_step_equals_python_sample_for_sample(tmp_path):
    det = _detector()
    out, lib = _compile(tmp_path, det)
    nr = len(out.residuals)
    state = ctypes.create_string_buffer(1 << 16)  # larger than the struct
    Out = type("Out", (ctypes.Structure,), {"_fields_": [("r", ctypes.c_double * nr), ("fired", ctypes.c_uint8 * nr),
                                                         ("alarm", ctypes.c_int), ("fault", ctypes.c_int),
                                                         ("valid", ctypes.c_int), ("recovering", ctypes.c_int)]})
    o = Out()
    lib.mon_init(state)
    ref = det.online()
    tr = _trace(det.generator, 1200, 5)
    dbl = ctypes.POINTER(ctypes.c_double)
    faults = (*out.faults, "unknown")
    seen = {"alarm": 0, "recovering": 0}
    scale = np.nanmax(np.abs(det.residuals(tr).r))
    for _ in range(2):  # and again after reset
        for k in range(len(tr)):
            u, y = np.ascontiguousarray(tr.u[k]), np.ascontiguousarray(tr.y[k])
            status = lib.mon_step(state, u.ctypes.data_as(dbl), y.ctypes.data_as(dbl), int(tr.valid[k]),
                                  ctypes.byref(o))
            d = ref.step(u, y, valid=bool(tr.valid[k]))
            r_py = ref.residuals
            np.testing.assert_allclose(np.array(o.r[:]), r_py, rtol=1e-12, atol=1e-12 * scale)
            assert bool(o.alarm) == d.alarm and list(o.fired) == d.fired.astype(int).tolist(), k
            assert ("none" if o.fault < 0 else faults[o.fault]) == d.fault, k
            assert bool(o.valid) == d.valid and status == (1 if not ref.last_valid and not ref.last_recovering
                                                           else 2 if ref.last_recovering else 0), k
            assert bool(o.recovering) == ref.last_recovering
            seen["alarm"] += d.alarm
            seen["recovering"] += ref.last_recovering
        lib.mon_reset(state)
        ref.reset()
    assert seen["alarm"] > 0 and seen["recovering"] > 0  # the comparison covers alarms and recovery
    assert set(faults[:-1]) == {"y0_sensor", "y1_sensor", "y2_sensor"}


@needs_cc
def test_header_names_the_signals(tmp_path):
    out, _ = _compile(tmp_path, _detector(), name="m2")
    text = out.header.read_text()
    assert "u = ['u0', 'u1']" in text and "#define M2_NR 4" in text
    assert "malloc" not in out.source.read_text()


def test_refusals(tmp_path):
    det = _detector()
    g = det.generator
    with pytest.raises(ParameterError, match="ThresholdEvaluator only"):
        export_c(Detector(g, CusumEvaluator().fit(g.run(_trace(g, 1000, 2, bias=False)), arl0=1e3, shift=1.0)),
                 tmp_path)
    with pytest.raises(ParameterError, match="C identifier"):
        export_c(det, tmp_path, name="my-monitor")
    with pytest.raises(ParameterError, match="Detector"):
        export_c(g, tmp_path)
