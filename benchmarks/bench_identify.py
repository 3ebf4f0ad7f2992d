"""Subspace identification: fdikit's N4SID / PO-MOESP against the packaged ones, on a known 4-state system.

The system (1 control, 2 outputs, innovation form ``x⁺ = A x + B u + K e``, ``y = C x + e``) has the
eigenvalues ``0.9 ± 0.3j``, ``0.7``, ``−0.5``.  Each method gets the same traces (``--samples`` samples,
white unit control, horizon 10 block rows, order 4) and is scored by the largest relative eigenvalue error
(eigenvalues matched by sorting) — noise-free, and with innovation noise (output SNR about 10) as the
root mean square over ``--seeds`` seeds — and by its best-of-``--repeat`` wall time.

Peers: ``nfoursid`` 1.0.2 (``NFourSID(...).subspace_identification(); system_identification(rank=4)``),
SIPPY ``sippy_unipi`` 1.0.1 (``system_identification(y, u, "N4SID", SS_fixed_order=4, SS_f=10)``); a peer that
is not installed is skipped.  ``harold`` has no subspace method, python-control none.

``--car``: the tutorial car logs instead (``docs/tutorial/car_train.csv.gz`` to identify,
``car_healthy.csv.gz`` to validate: fdikit's nonlinear car at 20 m/s, steering multisine 0.1–2 Hz at
100 Hz, sensor noise, an unmeasured road).  Each method identifies steering → yaw rate, lateral
acceleration (horizon 10) and is scored by the simulation fit on ``car_healthy``
(``validate_model``, initial state fitted) and the largest ``|λ|``.  The peers take one continuous
record: the 5 unusable samples of ``car_train`` are interpolated linearly for them.  References: the
linearisation of the car at the operating point and an ARX(4, 4) least-squares model.

Single-threaded BLAS (set before numpy is imported).  Run: ``python benchmarks/bench_identify.py [--car]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"  # single-threaded BLAS: comparable timings on a shared machine

import argparse  # noqa: E402
import contextlib  # noqa: E402
import io  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fdikit import FaultModel  # noqa: E402
from fdikit.identify import subspace_id  # noqa: E402
from fdikit.simulate import simulate  # noqa: E402
from timing import best, cpu_name  # noqa: E402

A = np.array([[0.9, 0.3, 0, 0], [-0.3, 0.9, 0, 0], [0, 0, 0.7, 0], [0, 0, 0, -0.5]])
B = np.array([[1.0], [0.5], [1.0], [1.0]])
C = np.array([[1.0, 0, 1.0, 0], [0, 1.0, 0, 1.0]])
K = np.array([[0.3, 0.0], [0.0, 0.2], [0.2, 0.1], [0.0, 0.3]])
TRUE = np.sort_complex(np.linalg.eigvals(A))
HORIZON = 10
TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial"


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


def car(repeat: int) -> None:
    from fdikit.identify import validate_model
    from fdikit.trace import Trace

    log = dict(time="time", controls={"steering": "steer_deg"}, outputs={"yaw_rate": "yaw_dps", "accel_y": "ay_g"},
               units={"steering": "deg", "yaw_rate": "deg/s", "accel_y": "g0"}, fault="fault")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        train, healthy = (Trace.from_csv(TUTORIAL / f"{n}.csv.gz", **log) for n in ("car_train", "car_healthy"))
    ok = np.all(np.isfinite(np.hstack([train.u, train.y])), axis=1) & np.asarray(train.valid, bool)
    k = np.arange(len(train))
    U = np.column_stack([np.interp(k, k[ok], c[ok]) for c in train.u.T])
    Y = np.column_stack([np.interp(k, k[ok], c[ok]) for c in train.y.T])
    um, ym = U.mean(axis=0), Y.mean(axis=0)

    def as_model(A, B, C, D):
        return FaultModel(A=A, Bu=B, C=C, Du=D, controls=train.controls, outputs=train.outputs,
                          dt=train.dt).with_operating_point(u0=um, y0=ym)

    def fdi(**kw):
        return lambda: subspace_id(train, horizon=HORIZON, **kw).model

    def nfour(n):
        def run():
            import pandas as pd
            from nfoursid.nfoursid import NFourSID

            df = pd.DataFrame(np.hstack([U - um, Y - ym]), columns=["u", "y0", "y1"])
            nf = NFourSID(df, output_columns=["y0", "y1"], input_columns=["u"], num_block_rows=HORIZON)
            nf.subspace_identification()
            ss = nf.system_identification(rank=n)[0]
            return as_model(ss.a, ss.b, ss.c, ss.d)
        return run

    def sippy(**kw):
        def run():
            from sippy_unipi import system_identification

            with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                s = system_identification((Y - ym).T.copy(), (U - um).T.copy(), "N4SID", SS_f=HORIZON, SS_p=HORIZON,
                                          SS_D_required=True, tsample=train.dt, **kw)
            return as_model(*(np.asarray(M) for M in (s.A, s.B, s.C, s.D)))
        return run

    def arx(na=4, nb=4):
        def run():
            # y_k on y_(k-1..k-na), u_(k..k-nb) by least squares; state [y_(k-1) … y_(k-na), u_(k-1) … u_(k-nb)]
            Yc, Uc = Y - ym, U - um
            h, p, m = max(na, nb), Y.shape[1], U.shape[1]
            Phi = np.hstack([Yc[h - i:len(Yc) - i] for i in range(1, na + 1)]
                            + [Uc[h - j:len(Uc) - j] for j in range(nb + 1)])
            Th = np.linalg.lstsq(Phi, Yc[h:], rcond=None)[0].T
            n = na * p + nb * m
            A, B = np.zeros((n, n)), np.zeros((n, m))
            C, D = np.hstack([Th[:, :na * p], Th[:, na * p + m:]]), Th[:, na * p:na * p + m]
            A[:p], B[:p] = C, D
            A[p:na * p, :(na - 1) * p] = np.eye((na - 1) * p)
            B[na * p:na * p + m] = np.eye(m)
            A[na * p + m:, na * p:na * p + (nb - 1) * m] = np.eye((nb - 1) * m)
            return as_model(A, B, C, D)
        return run

    def linearisation():
        from fdikit.vehicle import Sedan

        car_ = Sedan()
        return car_.linearize(car_.operating_point(speed=20.0)).submodel(outputs=["yaw_rate", "accel_y"],
                                                                         inputs=["steering"])

    methods = {
        "fdikit n4sid (default: BIC)": fdi(),
        "fdikit n4sid feedthrough=True (the former default)": fdi(feedthrough=True),
        "fdikit n4sid criterion='gap'": fdi(criterion="gap"),
        "fdikit n4sid gap, focus='prediction', feedthrough=True (an older default)":
            fdi(criterion="gap", focus="prediction", feedthrough=True),
        "fdikit n4sid order 4": fdi(order=4),
        "fdikit n4sid order 5": fdi(order=5),
        "fdikit n4sid order 6": fdi(order=6),
        "fdikit n4sid order 10": fdi(order=10),
        "fdikit moesp (BIC)": fdi(method="moesp"),
        "nfoursid rank 2": nfour(2),
        "nfoursid rank 4": nfour(4),
        "nfoursid rank 10": nfour(10),
        "SIPPY N4SID (default threshold)": sippy(),
        "SIPPY N4SID IC='BIC' 1..18": sippy(IC="BIC", SS_orders=[1, 18]),
        "SIPPY N4SID order 4": sippy(SS_fixed_order=4),
        "SIPPY N4SID order 5": sippy(SS_fixed_order=5),
        "SIPPY N4SID order 10": sippy(SS_fixed_order=10),
        "SIPPY N4SID order 4, SS_A_stability": sippy(SS_fixed_order=4, SS_A_stability=True),
        "ARX(4, 4) least squares": arx(),
        "linearisation (reference)": linearisation,
    }
    print(f"{cpu_name()}; car_train (120 s, 100 Hz) -> fit on car_healthy (600 s); horizon {HORIZON}")
    print("| method | order | max abs eigenvalue | fit yaw_rate % | fit accel_y % | time [s] |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, fn in methods.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                seconds, model = best(fn, repeat)
                rho = float(np.max(np.abs(model.poles()))) if model.is_discrete else float(np.max(model.poles().real))
                # an unstable model's simulation diverges: fit -inf (validate_model would refuse its predictor)
                fit = validate_model(model, healthy).fit if rho < (1 if model.is_discrete else 0) else [-np.inf] * 2
            print(f"| {name} | {model.n} | {rho:.4f} | {fit[0]:.1f} | {fit[1]:.1f} | {seconds:.2f} |", flush=True)
        except Exception as exc:  # a peer that fails is reported, not hidden
            print(f"| {name} | failed: {type(exc).__name__}: {str(exc)[:60]} | | | | |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--noise-std", type=float, default=0.3, help="innovation std (output std is about 3)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--car", action="store_true", help="the tutorial car logs instead of the known system")
    args = ap.parse_args()
    if args.car:
        car(args.repeat)
        return
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
