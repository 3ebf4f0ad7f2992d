"""Per-step cost of the IMM filter (fdikit.multimodel.imm) against filterpy, and a 10⁶-step underflow check.

* KF: fdikit's IMM with one mode (a Kalman filter, 4 states, 2 outputs) vs filterpy ``KalmanFilter``
  (``predict`` + ``update`` per sample).
* IMM: 3 modes, 4 states, 1 input, 2 outputs; fdikit ``IMMFilter.run`` vs filterpy ``IMMEstimator``.
  The two agree to ~1e-13 on the same data (tests/multimodel/test_imm.py).
* Long run: ``--long`` samples (default 10⁶) of a 3-mode IMM on data from mode 0 where mode 2 is very
  unlikely; reports whether μ stays finite and normalised and how far log μ of mode 2 falls.

Stone Soup is not benchmarked: the installed stonesoup 1.9.1 has no IMM predictor/updater.

Run: ``python benchmarks/bench_multimodel.py [--samples N] [--long N]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from fdikit.gaussian import LinearGaussianModel
from fdikit.multimodel.imm import IMMFilter
from fdikit.multimodel.kalman import KalmanFilter, kalman_filter
from timing import best


def _modes(rng, M=3, n=4, p=2):
    A0 = rng.normal(size=(n, n))
    A0 *= 0.9 / max(abs(np.linalg.eigvals(A0)))
    B, C = rng.normal(size=(n, 1)), rng.normal(size=(p, n))
    return [LinearGaussianModel(A=A0, B=B * (1 - 0.4 * i), C=C, Q=0.01 * np.eye(n), R=0.1 * np.eye(p), name=f"m{i}")
            for i in range(M)]


def _data(md, N, rng):
    u = rng.normal(size=(N, md.m))
    x, y = np.zeros(md.n), np.empty((N, md.p))
    for k in range(N):
        y[k] = md.C @ x + md.D @ u[k] + rng.normal(size=md.p) * np.sqrt(np.diag(md.R))
        x = md.A @ x + md.B @ u[k] + rng.normal(size=md.n) * np.sqrt(np.diag(md.Q))
    return u, y


def _filterpy_kf(md):
    from filterpy.kalman import KalmanFilter

    f = KalmanFilter(dim_x=md.n, dim_z=md.p, dim_u=md.m)
    f.F, f.H, f.B, f.Q, f.R = md.A, md.C, md.B, md.Q, md.R
    f.x, f.P = np.zeros((md.n, 1)), np.eye(md.n)
    return f


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--long", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    modes = _modes(rng)
    Pi = np.full((3, 3), 0.025) + 0.925 * np.eye(3)
    N = a.samples
    u, y = _data(modes[0], N, rng)
    uc, yc = u.reshape(N, 1, 1), y.reshape(N, 2, 1)
    rows = []

    kf = IMMFilter(modes[:1], [[1.0]])
    t_ours, _ = best(lambda: kf.run(u, y), a.repeat)
    rows.append(("KF (1 mode)", "fdikit IMMFilter.run", N / t_ours))
    md = modes[0]
    lg = LinearGaussianModel(md.A, md.C, md.Q, md.R, B=md.B, D=md.D)
    t_kf, _ = best(lambda: kalman_filter(lg, u, y, np.zeros(md.n), np.eye(md.n)), a.repeat)

    def fp_kf():
        f = _filterpy_kf(modes[0])
        for k in range(N):
            f.update(yc[k])
            f.predict(uc[k])

    t_fp, _ = best(fp_kf, a.repeat)
    rows.append(("KF (1 mode)", "filterpy KalmanFilter", N / t_fp))
    rows.append(("KF (1 mode)", "fdikit kalman_filter (Joseph form)", N / t_kf))

    def online_kf():
        f = KalmanFilter(lg, np.zeros(md.n), np.eye(md.n))
        for k in range(N):
            f.step(u[k], y[k])

    t_on, _ = best(online_kf, a.repeat)
    rows.append(("KF (1 mode)", "fdikit KalmanFilter.step (online)", N / t_on))

    imm = IMMFilter(modes, Pi)
    t_imm, _ = best(lambda: imm.run(u, y), a.repeat)
    rows.append(("IMM (3 modes)", "fdikit IMMFilter.run", N / t_imm))  # rows[4]

    def fp_imm():
        from filterpy.kalman import IMMEstimator

        est = IMMEstimator([_filterpy_kf(md) for md in modes], np.full(3, 1 / 3), Pi)
        for k in range(N):
            est.update(yc[k])
            est.predict(uc[k])

    t_fpi, _ = best(fp_imm, a.repeat)
    rows.append(("IMM (3 modes)", "filterpy IMMEstimator", N / t_fpi))

    print(f"# IMM benchmark — numpy {np.__version__}, python {platform.python_version()}, {platform.machine()}")
    print(f"# n = 4 states, m = 1 input, p = 2 outputs, {N} samples, best of {a.repeat}\n")
    print("| filter | implementation | steps/s | µs/step |")
    print("|---|---|---:|---:|")
    for f, impl, sps in rows:
        print(f"| {f} | {impl} | {sps:,.0f} | {1e6 / sps:.1f} |")
    print(f"\nspeed ratio fdikit / filterpy: KF as a 1-mode IMM {rows[0][2] / rows[1][2]:.2f}×, "
          f"kalman_filter {rows[2][2] / rows[1][2]:.2f}×, online step {rows[3][2] / rows[1][2]:.2f}×, "
          f"IMM {rows[4][2] / rows[5][2]:.2f}×")

    if a.long:
        # long run: data from mode 0; mode 2 (input gain 0.2) is very unlikely and, with Π = I, cannot be revived
        L = a.long
        ul, yl = _data(modes[0], L, np.random.default_rng(1))
        t0 = time.perf_counter()
        res = IMMFilter(modes, np.eye(3)).run(ul, yl, store_covariance=False)
        dt = time.perf_counter() - t0
        ok = np.isfinite(res.mu).all() and np.isfinite(res.log_mu).all()
        print(f"\nlong run: {L:,} steps in {dt:.1f} s ({L / dt:,.0f} steps/s); μ finite: {ok}; "
              f"max |Σμ − 1| = {np.max(abs(res.mu.sum(axis=1) - 1)):.1e}; "
              f"final log μ = {np.array2string(res.log_mu[-1], precision=4)}; "
              f"samples with μ(m2) == 0.0 in double: {int((res.mu[:, 2] == 0).sum()):,}")


if __name__ == "__main__":
    main()
