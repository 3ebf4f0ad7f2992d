"""The compiled runtime (fdikit.runtime) side by side with its peers, one run, medians, one BLAS thread.

Every row of issue 19's table:

* batch residual filter (the demo's 12-state Kalman generator on the PATH vehicle: 3 controls + 12 measurements,
  12 residuals, 1e5 samples): ``ResidualGenerator.run`` vs ``scipy.signal.dlsim``; peak memory at 1e6 samples;
* online step of the same filter: compiled vs the reference stepper vs a hand-written numpy step;
* the PATH Beard–Jones bank (50 states, 28 residuals) online, alone and as a monitor with thresholds;
* Kalman filter n = 12 online step (settled) vs filterpy and a hand steady-gain numpy step;
* IMM 2 and 3 modes x 4 states vs filterpy's ``IMMEstimator``;
* ``ThresholdEvaluator.run`` vs ``np.abs(r − c) > τ``; CUSUM, GLR and MHSSPRT online steps;
* first-call compile times on a cold numba cache (a fresh subprocess with an empty ``NUMBA_CACHE_DIR``).

Every compared pair is checked for agreement before a time is printed.  Run from the repository root:
``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_runtime.py`` (the script sets one thread itself).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.signal  # noqa: E402

from timing import cpu_name  # noqa: E402

ROWS: list[tuple[str, str, str, str, str]] = []


def per_call(fn, calls: int, repeat: int = 5) -> float:
    """Median over ``repeat`` of the mean seconds per call of ``fn(k)`` for k < calls."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for k in range(calls):
            fn(k)
        times.append((time.perf_counter() - t0) / calls)
    return float(np.median(times))


def median(fn, repeat: int = 7) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def peak_mib(fn) -> float:
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def row(workload, ours, peer, ratio, goal):
    ROWS.append((workload, ours, peer, ratio, goal))
    print(f"| {workload} | {ours} | {peer} | {ratio} | {goal} |", flush=True)


def us(t: float) -> str:
    return f"{t * 1e6:.2f} µs"


def hand_stepper(gen, U, Y):
    """A hand-written numpy step of ``gen`` over the rows of ``U``, ``Y`` (the peer of the compiled step)."""
    AB, CD = np.hstack([gen.A, gen.B]), np.hstack([gen.C, gen.D])
    x = np.zeros(gen.n)

    def hand(k):
        nonlocal x
        xv = np.concatenate([x, U[k], Y[k]])
        x = AB @ xv
        return CD @ xv

    return hand


def demo_generator(N: int):
    from fdikit.design import kalman
    from fdikit.simulate import simulate
    from fdikit.studies.path1996.demo import ACTUATOR_NOISE_STD, SENSOR_NOISE_STD, demo_model

    model = demo_model(0.01)
    W = np.diag([ACTUATOR_NOISE_STD[c] ** 2 for c in model.controls])
    v_std = np.array([SENSOR_NOISE_STD[o] for o in model.outputs])
    gen = kalman(model, W, np.diag(v_std**2)).generator
    trace = simulate(model, duration=(N - 1) * 0.01, noise_cov=W, measurement_noise_std=v_std, rng=0,
                     u=lambda t: [np.sin(t), 10 * np.sin(0.3 * t), 1e-3 * np.sin(0.7 * t)])
    return gen, trace


def bench_filter(N: int) -> None:
    from fdikit.runtime import compile_generator

    gen, trace = demo_generator(N)
    v = gen.inputs_from(trace)
    dl = lambda: scipy.signal.dlsim((gen.A, gen.B, gen.C, gen.D, 0.01), v, t=trace.t)[1]  # noqa: E731
    ref = dl()
    ours = gen.run(trace).r
    diff = np.abs(ours - ref).max() / np.abs(ref).max()
    assert diff < 1e-12, diff
    t_ours, t_dl = median(lambda: gen.run(trace)), median(dl, 3)
    row(f"residual filter n={gen.n}, m={len(gen.controls)}, p={len(gen.outputs)}, {N:.0e} samples, batch",
        f"{N / t_ours:.3g} samples/s", f"scipy `dlsim` {N / t_dl:.3g}", f"{t_dl / t_ours:.0f}×", "≥ 50×")

    U, Y = trace.columns("u", gen.controls), trace.columns("y", gen.outputs)
    s, st = compile_generator(gen), gen.online()
    rows = min(N, 20000)
    r_c = np.array([s.step(U[k], Y[k]).copy() for k in range(rows)])
    st.reset()
    r_r = np.array([st.step(U[k], Y[k]) for k in range(rows)])
    assert np.abs(r_c - r_r).max() <= 1e-12 * np.abs(r_r).max()
    hand = hand_stepper(gen, U, Y)
    t_c = per_call(lambda k: s.step(U[k], Y[k]), rows)
    t_r = per_call(lambda k: st.step(U[k], Y[k]), rows)
    t_h = per_call(hand, rows)
    row("same, online `step`", us(t_c), f"hand numpy step {us(t_h)}; reference stepper {us(t_r)}",
        f"{t_h / t_c:.1f}× hand", "≤ 1 µs")

    Nm = 1_000_000
    gen_m, trace_m = demo_generator(Nm)
    vm = gen_m.inputs_from(trace_m)
    m_ours = peak_mib(lambda: gen_m.run(trace_m))
    m_dl = peak_mib(lambda: scipy.signal.dlsim((gen_m.A, gen_m.B, gen_m.C, gen_m.D, 0.01), vm))
    row(f"batch residual memory at {Nm:.0e} samples", f"{m_ours:.0f} MiB", f"`dlsim` {m_dl:.0f} MiB",
        f"{m_ours / m_dl:.2f}×", "≤ 1.0×")


def bench_bank(N: int) -> None:
    from fdikit.decision import ThresholdEvaluator
    from fdikit.detector import Detector
    from fdikit.faults import sensor_fault_name
    from fdikit.runtime import compile_detector, compile_generator
    from fdikit.simulate import simulate
    from fdikit.studies.path1996 import path_bank, path_fault_model

    bank = path_bank()
    dt = 0.01
    plant = path_fault_model(14).discretize(dt)
    noise = 1e-4 * np.array([bank.nominal[sensor_fault_name(o)] for o in plant.outputs])
    trace = simulate(plant, duration=(N - 1) * dt, measurement_noise_std=noise, rng=0)
    gen = bank.generator.discretize(dt)
    U, Y = trace.columns("u", gen.controls), trace.columns("y", gen.outputs)
    rows = min(N, 20000)
    s, st = compile_generator(gen), gen.online()
    r_c = np.array([s.step(U[k], Y[k]).copy() for k in range(rows)])
    r_r = np.array([st.step(U[k], Y[k]) for k in range(rows)])
    assert np.abs(r_c - r_r).max() <= 1e-12 * np.abs(r_r).max()
    hand = hand_stepper(gen, U, Y)
    t_c, t_h = per_call(lambda k: s.step(U[k], Y[k]), rows), per_call(hand, rows)
    t_r = per_call(lambda k: st.step(U[k], Y[k]), rows)
    ev = ThresholdEvaluator(groups=gen.isolates).fit(gen.run(trace), false_alarm_prob=1e-3)
    det = Detector(gen, ev)
    mon, ref = compile_detector(det), det.online()
    alarms_c = [mon.step(U[k], Y[k]) for k in range(rows)]
    alarms_r = [ref.step(U[k], Y[k]).alarm for k in range(rows)]
    assert alarms_c == alarms_r
    t_m = per_call(lambda k: mon.step(U[k], Y[k]), rows)
    t_mr = per_call(lambda k: ref.step(U[k], Y[k]), rows)
    row(f"PATH bank ({gen.n} states, {len(gen.residuals)} residuals), online", us(t_c),
        f"hand numpy {us(t_h)}; reference {us(t_r)}", f"{t_h / t_c:.1f}× hand", "≤ 2 µs")
    row("PATH bank + thresholds, online monitor", us(t_m), f"reference DetectorStepper {us(t_mr)}",
        f"{t_mr / t_m:.0f}× reference", "≤ 3 µs")


def bench_kalman(N: int) -> None:
    from filterpy.kalman import KalmanFilter as FpKF

    from fdikit.gaussian import LinearGaussianModel
    from fdikit.multimodel.kalman import KalmanFilter
    from fdikit.runtime import compile_kalman

    rng = np.random.default_rng(0)
    n, m, p = 12, 3, 12
    A = rng.normal(size=(n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    md = LinearGaussianModel(A, rng.normal(size=(p, n)), 0.01 * np.eye(n), 0.1 * np.eye(p), B=rng.normal(size=(n, m)))
    u, y = rng.normal(size=(N, m)), rng.normal(size=(N, p))
    kf = KalmanFilter(md, np.zeros(n), np.eye(n))
    ck = compile_kalman(KalmanFilter(md, np.zeros(n), np.eye(n)))
    settle = 2000
    for k in range(settle):
        kf.step(u[k], y[k])
        ck.step(u[k], y[k])
    assert np.allclose(ck.x, kf.x, rtol=1e-12, atol=1e-12)
    t_c = per_call(lambda k: ck.step(u[settle + k], y[settle + k]), N - settle, 1)
    t_r = per_call(lambda k: kf.step(u[k], y[k]), 5000, 3)
    f = FpKF(dim_x=n, dim_z=p, dim_u=m)
    f.F, f.H, f.B, f.Q, f.R, f.x, f.P = md.A, md.C, md.B, md.Q, md.R, np.zeros((n, 1)), np.eye(n)
    uc, yc = u.reshape(N, m, 1), y.reshape(N, p, 1)

    def fp(k):
        f.update(yc[k])
        f.predict(uc[k])

    t_fp = per_call(fp, 5000, 3)
    K = ck.gain if hasattr(ck, "gain") else None
    x = np.zeros(n)
    Ad, Bd, Cd = md.A, md.B, md.C

    def hand(k):  # steady-gain predictor-corrector
        nonlocal x
        e = y[k] - Cd @ x
        xf = x + K @ e
        x = Ad @ xf + Bd @ u[k]
        return xf

    t_h = per_call(hand, 5000, 3) if K is not None else float("nan")
    row("Kalman n=12, online `step` (settled)", us(t_c),
        f"hand steady-gain {us(t_h)}; filterpy {us(t_fp)}; reference {us(t_r)}", f"{t_fp / t_c:.0f}× filterpy",
        "≤ 1 µs")


def bench_imm(N: int) -> None:
    from filterpy.kalman import IMMEstimator
    from filterpy.kalman import KalmanFilter as FpKF

    from fdikit.gaussian import LinearGaussianModel
    from fdikit.multimodel.imm import IMMFilter
    from fdikit.runtime import compile_imm

    for M in (2, 3):
        rng = np.random.default_rng(0)
        n, p = 4, 2
        A0 = rng.normal(size=(n, n))
        A0 *= 0.9 / max(abs(np.linalg.eigvals(A0)))
        B, C = rng.normal(size=(n, 1)), rng.normal(size=(p, n))
        modes = [LinearGaussianModel(A=A0, B=B * (1 - 0.4 * i), C=C, Q=0.01 * np.eye(n), R=0.1 * np.eye(p),
                                     name=f"m{i}") for i in range(M)]
        Pi = np.full((M, M), 0.05 / (M - 1)) + (0.95 - 0.05 / (M - 1)) * np.eye(M)
        u, y = rng.normal(size=(N, 1)), rng.normal(size=(N, p))
        ci = compile_imm(IMMFilter(modes, Pi))

        def fpkf(md, n=n, p=p):
            f = FpKF(dim_x=n, dim_z=p, dim_u=1)
            f.F, f.H, f.B, f.Q, f.R, f.x, f.P = md.A, md.C, md.B, md.Q, md.R, np.zeros((n, 1)), np.eye(n)
            return f

        est = IMMEstimator([fpkf(md) for md in modes], np.full(M, 1 / M), Pi)
        uc, yc = u.reshape(N, 1, 1), y.reshape(N, p, 1)
        mu_c, mu_f = [], []
        for k in range(200):
            ci.step(u[k], y[k])
            est.update(yc[k])
            est.predict(uc[k])
            mu_c.append(np.array(ci.mu, copy=True))
            mu_f.append(est.mu.copy())
        agree = float(np.abs(np.array(mu_c) - np.array(mu_f)).max())

        def fp(k, est=est, yc=yc, uc=uc):
            est.update(yc[k])
            est.predict(uc[k])

        t_c = per_call(lambda k, ci=ci, u=u, y=y: ci.step(u[k], y[k]), N, 3)
        t_fp = per_call(fp, min(N, 3000), 3)
        row(f"IMM, {M} modes, 4 states", f"{us(t_c)}/step", f"filterpy `IMMEstimator` {us(t_fp)} "
            f"(mode probabilities agree to {agree:.0e} over 200 steps)", f"{t_fp / t_c:.0f}×", "≥ 50× filterpy")


def bench_evaluators(N: int) -> None:
    sys.path.insert(0, os.path.dirname(__file__))
    from bench_evaluators import residuals
    from fdikit.decision import CusumEvaluator, GlrEvaluator, ThresholdEvaluator
    from fdikit.decision.mhsprt import MhsprtEvaluator
    from fdikit.runtime import compile_evaluator

    healthy = residuals(20000, seed=1)
    res = residuals(N, seed=2, fault="f1")
    th = ThresholdEvaluator().fit(healthy, false_alarm_prob=1e-3)
    c, tau = th.center, th.thresholds
    assert (th.run(res).fired == (np.abs(res.r - c) > tau)).all() or th.persistence != (1, 1)
    t_run = median(lambda: th.run(res))
    t_np = median(lambda: np.abs(res.r - c) > tau)
    row(f"`ThresholdEvaluator`, {N:.0e} × {res.r.shape[1]}, batch", f"{N / t_run:.3g} samples/s",
        f"numpy `abs(r−c) > τ` {N / t_np:.3g}", f"{t_np / t_run:.2f}×", "≥ 1× numpy")
    labelled = {"none": healthy, **{f"f{g}": residuals(20000, seed=10 + g, fault=f"f{g}", onset=0.0)
                                    for g in range(4)}}
    evs = [("threshold", th), ("CUSUM", CusumEvaluator().fit(healthy, arl0=1e4, shift=1.5)),
           ("GLR (M = 50, 4 blocks of 3)", GlrEvaluator(window=50).fit(healthy, false_alarm_prob=1e-3)),
           ("MHSSPRT (4 hypotheses)", MhsprtEvaluator().fit(labelled))]
    rows = min(N, 20000)
    for name, ev in evs:
        ce = compile_evaluator(ev)
        ev.reset()
        ok = all(ce.step(res.r[k]) == ev.step(res.r[k]).alarm for k in range(rows))
        assert ok, name
        ce.reset()
        ev.reset()
        t_c = per_call(lambda k, ce=ce: ce.step(res.r[k]), rows)
        t_r = per_call(lambda k, ev=ev: ev.step(res.r[k]), min(rows, 5000), 3)
        row(f"{name} online", us(t_c), f"reference {us(t_r)}", f"{t_r / t_c:.0f}× reference", "≤ 2 µs")


COLD = """
import time, numpy as np
t0 = time.perf_counter()
from fdikit.runtime import {name}
{setup}
t1 = time.perf_counter()
print(t1 - t0)
"""


def bench_compile() -> None:
    cases = {
        "generator step": ("compile_generator", "from fdikit.residuals import ResidualGenerator\n"
                           "g = ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ('y',), ('r',), dt=1.0)\n"
                           "compile_generator(g).step(np.zeros(0), np.ones(1))"),
        "batch response (`lsim`)": ("lsim", "lsim([[0.5]], [[1.0]], [[1.0]], [[0.0]], np.ones((4, 1)))"),
    }
    for label, (name, setup) in cases.items():
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache)
            code = COLD.format(name=name, setup=setup)
            cold = float(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                        check=True).stdout.split()[-1])
            warm = float(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                        check=True).stdout.split()[-1])
        print(f"| first call, {label} | cold cache {cold:.2f} s | warm cache {warm:.2f} s |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--only", nargs="*", default=None,
                    help="sections: filter bank kalman imm evaluators compile")
    a = ap.parse_args()
    print(f"# fdikit.runtime — numpy {np.__version__}, scipy {scipy.__version__}, Python {platform.python_version()}, "
          f"{cpu_name()}, OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}\n")
    print("| workload | fdikit | peer / reference | ratio | goal |")
    print("|---|---|---|---|---|")
    sections = {"filter": lambda: bench_filter(a.samples), "bank": lambda: bench_bank(a.samples),
                "kalman": lambda: bench_kalman(20000), "imm": lambda: bench_imm(20000),
                "evaluators": lambda: bench_evaluators(a.samples), "compile": bench_compile}
    for name, fn in sections.items():
        if a.only is None or name in a.only:
            fn()


if __name__ == "__main__":
    main()
