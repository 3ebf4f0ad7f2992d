"""Parity filters and steering-fault isolation: cost per sample against the peer a user would write.

* the van der Ploeg LTI parity filter (``parity_filter(...).generator.run``) against
  ``scipy.signal.lfilter`` of the same ``N(q)L(q)/d(q)`` per input channel;
* the speed-scheduled filter (Thm 3-3.4) batch and online, against the LTI filter (no packaged
  peer recomputes a parity row per sample);
* the moving-window least-squares isolation (``isolate_steering_faults``) against a plain loop of
  ``numpy.linalg.lstsq`` over the windows.

Run: ``python benchmarks/bench_parity.py``.
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.signal

from fdikit.design.parity.polynomial import parity_filter
from fdikit.design.parity.scheduled import scheduled_parity_filter
from fdikit.estimate import isolate_steering_faults
from fdikit.plants.single_track import single_track_lpv
from fdikit.studies.vanderploeg2018.scenarios import lateral_run
from timing import best


def lfilter_parity(design, z):
    """The same filter as separate ``lfilter`` calls: r = Σ_j (N L)_j(q)/d(q) z_j."""
    den = design.denominator[::-1]
    r = np.zeros(z.shape[0])
    for j in range(z.shape[1]):
        num = np.concatenate([np.zeros(den.size - design.NL.shape[0]), design.NL[::-1, j]])
        r += scipy.signal.lfilter(num, den, z[:, j])
    return r


def lstsq_loop(r, E, n):
    out = np.full((r.size, 2), np.nan)
    for k in range(n - 1, r.size):
        X = np.column_stack([np.ones(n), E[k - n + 1:k + 1]])
        out[k] = np.linalg.lstsq(X, r[k - n + 1:k + 1], rcond=None)[0]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=200.0, help="simulated time at 100 Hz")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    family = single_track_lpv()
    lti = parity_filter(family(70 / 3.6))
    const = lateral_run(args.seconds, speed_kmh=70.0, additive_deg=((0.0, 0.0), (args.seconds / 2, 0.1)))
    sweep = lateral_run(min(args.seconds, 60.0), speed_kmh="sweep", additive_deg=((0.0, 0.0), (20.0, 0.1)))
    N, Ns = const.t.size, sweep.t.size
    z = np.column_stack([const.y[:, :3], const.u])  # z = [outputs; controls]; column 4 of y is the speed
    gen = lti.generator

    t_run, r_run = best(lambda: gen.run(const).r[:, 0], args.repeat)
    t_lf, r_lf = best(lambda: lfilter_parity(lti, z), args.repeat)
    assert np.allclose(r_run[10:], r_lf[10:], atol=1e-9 * np.abs(r_lf).max()), "lfilter reference disagrees"
    t_on, _ = best(lambda: gen.online().run(const).r[:, 0], 1)

    sched = scheduled_parity_filter(family, 70 / 3.6)
    t_sb, _ = best(lambda: sched.run(sweep), 1)

    def online_sched():
        st = sched.online()
        for k in range(Ns):
            st.step(sweep.u[k], sweep.y[k, :3], sweep.y[k, 3])

    t_so, _ = best(online_sched, 1)

    r = r_run
    E = const.u[:, 0]
    n = 100
    t_iso, est = best(lambda: isolate_steering_faults(r, E, n), args.repeat)
    m = min(N, 20_000)
    t_loop, ref = best(lambda: lstsq_loop(r[:m], E[:m], n), 1)
    assert np.allclose(est.f_a_hat[n:m], ref[n:, 0], rtol=1e-6, atol=1e-9)
    t_loop *= N / m

    print(f"{N} samples (LTI), {Ns} samples (70→120 km/h sweep); best of {args.repeat}\n")
    print("| step | time per sample | ratio |\n|---|---|---|")
    print(f"| LTI parity filter, batch run | {t_run / N * 1e6:.2f} µs | 1 |")
    print(f"| scipy.signal.lfilter, one call per input channel | {t_lf / N * 1e6:.2f} µs | "
          f"{t_lf / t_run:.2f}x fdikit batch |")
    print(f"| LTI parity filter, online step | {t_on / N * 1e6:.2f} µs | {t_on / t_run:.0f}x batch |")
    print(f"| scheduled filter (exact projection), batch | {t_sb / Ns * 1e6:.1f} µs | "
          f"{(t_sb / Ns) / (t_run / N):.0f}x LTI batch |")
    print(f"| scheduled filter, online step | {t_so / Ns * 1e6:.1f} µs | {(t_so / Ns) / (t_run / N):.0f}x LTI batch |")
    print(f"| isolate_steering_faults, n = {n}, batch | {t_iso / N * 1e6:.2f} µs | 1 |")
    print(f"| numpy.linalg.lstsq loop over the windows | {t_loop / N * 1e6:.1f} µs | "
          f"{t_loop / t_iso:.0f}x fdikit |")


if __name__ == "__main__":
    main()
