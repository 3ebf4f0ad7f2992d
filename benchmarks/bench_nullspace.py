"""Synthesis time of the nullspace method (fdikit.design.nullspace) on the PATH-size problem, one run, medians.

Rows: the least-degree nullspace basis of the 14-state PATH model (12 outputs, 3 controls, 15 faults), the least-order
``efdsyn`` detector of all 15 faults, ``fdichkspec`` of the 15 single-fault rows and of 200 random rows, an ``efdisyn``
bank of the feasible ones, ``emmsyn`` of the ``efdsyn`` detector's ``R_f`` (exact model matching), ``ammsyn`` H∞
estimation of all 15 faults (``M_r = I``), ``ammsyn`` on Varga (2017) Example 5.16 (non-standard), and
``fdigenspec`` / ``fdichkspec`` of the Yuan et al. 1997 example (8 faults, the reference's own timing example).
The peer a PATH user would otherwise run is fdikit's Beard–Jones bank design
(``path_bank()``: the report's four filters); FaultDetectionTools.jl (Julia) cannot be installed on this machine and
publishes no timings for these problems, so no reference ratio is given.

Run from the repository root: ``python benchmarks/bench_nullspace.py`` (one BLAS thread is set).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from timing import cpu_name  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "design" / "nullspace"))


def median_time(fn, repeat: int = 5):
    """Median wall time of ``fn()`` over ``repeat`` calls, and the last result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main() -> None:
    from varga_examples import yuan

    from fdikit.design.nullspace import ammsyn, efdisyn, efdsyn, emmsyn, fdichkspec, fdigenspec, left_nullspace
    from fdikit.model import FaultModel
    from fdikit.studies.path1996 import path_bank, path_fault_model

    m = path_fault_model(14)
    path_bank()                                                   # warm imports
    left_nullspace(m)
    t_bj, _ = median_time(path_bank, 3)
    t_basis, basis = median_time(lambda: left_nullspace(m))
    t_efd, d = median_time(lambda: efdsyn(m))
    single = np.eye(len(m.faults), dtype=bool)
    t_single, chk1 = median_time(lambda: fdichkspec(m, single), 3)
    rng = np.random.default_rng(0)
    rows = rng.random((200, len(m.faults))) < 0.7
    rows[~rows.any(axis=1), 0] = True
    t_rand, chk = median_time(lambda: fdichkspec(m, rows), 3)
    feasible = rows[chk.feasible][:6]
    t_bank, bank = median_time(lambda: efdisyn(m, feasible), 3) if len(feasible) else (float("nan"), None)
    R = d.internal_form()
    ref = FaultModel(R.A, R.C, Bf=R.b("f"), Df=R.d("f"), faults=R.faults)
    t_emm, mm = median_time(lambda: emmsyn(m, ref))
    t_amm, am = median_time(lambda: ammsyn(m, {"f": np.eye(len(m.faults))}), 3)
    A16 = np.array([[-0.8, 0, 0], [0, -0.5, 0.6], [0, -0.6, -0.5]])
    Bu16 = np.array([[1.0, 1], [1, 0], [0, 1]])
    m16 = FaultModel(A16, np.array([[0.0, 1, 1], [1, 1, 0]]), Bu=Bu16, Bf=Bu16,
                     Bw=0.25 * np.array([[0.0, 0], [0, 1], [1, 0]]))
    t_16, a16 = median_time(lambda: ammsyn(m16, {"f": np.eye(2)}, sdeg=-10.0, normalize="dcgain", reltol=5e-4), 3)
    y = yuan()
    t_gen, S = median_time(lambda: fdigenspec(y, fdtol=1e-5), 3)
    every = np.array([[c >> (7 - j) & 1 for j in range(8)] for c in range(1, 256)], dtype=bool)
    t_chk, _ = median_time(lambda: fdichkspec(y, every, fdtol=1e-5, minimal=True), 3)

    print(f"# nullspace synthesis, {cpu_name()}, Python {platform.python_version()}, numpy {np.__version__}")
    print("| step | time | ratio |")
    print("|---|---|---|")
    print(f"| Beard–Jones PATH bank design (`path_bank()`, the peer) | {t_bj * 1e3:.1f} ms | 1.0 |")
    print(f"| PATH left nullspace basis (n = 14, degrees {list(basis.degrees)}) | {t_basis * 1e3:.1f} ms | "
          f"{t_basis / t_bj:.2f} |")
    print(f"| PATH `efdsyn`, least order, 15 faults (order {d.order}) | {t_efd * 1e3:.1f} ms | {t_efd / t_bj:.2f} |")
    print(f"| PATH `fdichkspec`, 15 single-fault rows ({int(chk1.feasible.sum())} feasible) | {t_single * 1e3:.1f} ms "
          f"| {t_single / t_bj:.2f} |")
    print(f"| PATH `fdichkspec`, 200 random rows ({int(chk.feasible.sum())} feasible) | {t_rand * 1e3:.1f} ms | "
          f"{t_rand / t_bj:.2f} |")
    if bank is not None:
        print(f"| PATH `efdisyn`, {len(feasible)} feasible rows (orders {list(bank.orders)}) | {t_bank * 1e3:.1f} ms "
              f"| {t_bank / t_bj:.2f} |")
    print(f"| PATH `emmsyn` of the `efdsyn` detector's R_f (orders {list(mm.orders)}) | {t_emm * 1e3:.1f} ms | "
          f"{t_emm / t_bj:.2f} |")
    print(f"| PATH `ammsyn` H∞, M_r = I₁₅ (γ = {am.gamma_sub:.5f}, order {am.generator.n}) | {t_amm * 1e3:.1f} ms | "
          f"{t_amm / t_bj:.2f} |")
    print(f"| Ex. 5.16 `ammsyn` H∞, non-standard (γ_sub = {a16.gamma_sub:.4f}) | {t_16 * 1e3:.1f} ms | "
          f"{t_16 / t_bj:.2f} |")
    print(f"| Yuan `fdigenspec` (255 decoupled sets, {len(S)} rows) | {t_gen * 1e3:.1f} ms | {t_gen / t_bj:.2f} |")
    print(f"| Yuan `fdichkspec`, all 255 rows, least orders | {t_chk * 1e3:.1f} ms | {t_chk / t_bj:.2f} |")


if __name__ == "__main__":
    main()
