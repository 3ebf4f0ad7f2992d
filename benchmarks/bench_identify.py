"""Subspace identification: fdikit's N4SID / PO-MOESP against the packaged ones, on a known 4-state system.

The system (1 control, 2 outputs, innovation form ``x⁺ = A x + B u + K e``, ``y = C x + e``) has the
eigenvalues ``0.9 ± 0.3j``, ``0.7``, ``−0.5``.  Each method gets the same traces (``--samples`` samples,
white unit control, horizon 10 block rows, order 4) and is scored by the largest relative eigenvalue error
(eigenvalues matched by sorting) — noise-free, and with innovation noise (output SNR about 10) as the
root mean square over ``--seeds`` seeds — and by its best-of-``--repeat`` wall time.

Peers: ``nfoursid`` 1.0.2 (``NFourSID(...).subspace_identification(); system_identification(rank=4)``),
SIPPY ``sippy_unipi`` 1.0.1 (``system_identification(y, u, "N4SID", SS_fixed_order=4, SS_f=10)``); a peer that
is not installed is skipped.  ``harold`` has no subspace method, python-control none.

Run: ``python benchmarks/bench_identify.py``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import warnings

import numpy as np

from fdikit import FaultModel
from fdikit.identify import subspace_id
from fdikit.simulate import simulate
from timing import best, cpu_name

A = np.array([[0.9, 0.3, 0, 0], [-0.3, 0.9, 0, 0], [0, 0, 0.7, 0], [0, 0, 0, -0.5]])
B = np.array([[1.0], [0.5], [1.0], [1.0]])
C = np.array([[1.0, 0, 1.0, 0], [0, 1.0, 0, 1.0]])
K = np.array([[0.3, 0.0], [0.0, 0.2], [0.2, 0.1], [0.0, 0.3]])
TRUE = np.sort_complex(np.linalg.eigvals(A))
HORIZON = 10


def plant() -> FaultModel:
    return FaultModel(A=A, Bu=B, C=C, Bw=K, Dw=np.eye(2), controls=["u"], outputs=["y0", "y1"],
                      noise=["e0", "e1"], dt=1.0)


def traces(samples: int, seed: int, noise_std: float):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((samples, 1))
    return simulate(plant(), t=np.arange(samples) * 1.0, u=u, noise_std=noise_std, rng=rng)


def eig_error(A_hat) -> float:
    est = np.sort_complex(np.linalg.eigvals(A_hat))
    return float(np.max(np.abs(est - TRUE) / np.abs(TRUE)))


def fdikit_n4sid(tr):
    return subspace_id(tr, 4, horizon=HORIZON, method="n4sid", detrend=False).model.A


def fdikit_moesp(tr):
    return subspace_id(tr, 4, horizon=HORIZON, method="moesp", detrend=False).model.A


def nfoursid(tr):
    import pandas as pd
    from nfoursid.nfoursid import NFourSID

    df = pd.DataFrame(np.hstack([tr.u, tr.y]), columns=["u", "y0", "y1"])
    nf = NFourSID(df, output_columns=["y0", "y1"], input_columns=["u"], num_block_rows=HORIZON)
    nf.subspace_identification()
    return nf.system_identification(rank=4)[0].a


def sippy(tr):
    from sippy_unipi import system_identification

    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sys_id = system_identification(tr.y.T.copy(), tr.u.T.copy(), "N4SID", SS_fixed_order=4, SS_f=HORIZON)
    return np.asarray(sys_id.A)


def available():
    methods = {"fdikit n4sid": fdikit_n4sid, "fdikit moesp": fdikit_moesp}
    for name, fn, module in (("nfoursid", nfoursid, "nfoursid"), ("SIPPY N4SID", sippy, "sippy_unipi")):
        try:
            __import__(module)
        except ImportError:
            print(f"({name} not installed: skipped)")
            continue
        methods[name] = fn
    return methods


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--noise-std", type=float, default=0.3, help="innovation std (output std is about 3)")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    clean = traces(args.samples, 0, 0.0)
    noisy = [traces(args.samples, s, args.noise_std) for s in range(args.seeds)]
    snr = float(np.std(noisy[0].y) / args.noise_std)
    print(f"{cpu_name()}; {args.samples} samples, horizon {HORIZON}, order 4, noisy: SNR {snr:.1f}, "
          f"{args.seeds} seeds")
    rows = []
    for name, fn in available().items():
        seconds, A_hat = best(lambda fn=fn: fn(clean), args.repeat)
        e_clean = eig_error(A_hat)
        errs = [eig_error(fn(tr)) for tr in noisy]
        rows.append((name, e_clean, float(np.sqrt(np.mean(np.square(errs)))), seconds))
    ref = next(r for r in rows if r[0] == "fdikit n4sid")
    print("| method | max rel. eigenvalue error, noise-free | RMS over seeds, noisy | time [ms] "
          "| time / fdikit n4sid |")
    print("|---|---:|---:|---:|---:|")
    for name, e0, e1, sec in rows:
        print(f"| {name} | {e0:.1e} | {e1:.3f} | {1e3 * sec:.1f} | {sec / ref[3]:.2f} |")


if __name__ == "__main__":
    main()
