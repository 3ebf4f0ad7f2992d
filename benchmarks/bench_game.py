"""Game-theoretic detection filters: design cost against the peer a user would otherwise reach for.

* the indefinite Riccati solver (``solve_game_are``, Hamiltonian Schur + scaling + Newton refinement)
  against ``scipy.linalg.solve_continuous_are`` on the definite equations both can solve (the
  single-fault filter's CARE with ``V⁻¹ − ĤQĤ > 0``), agreement checked;
* the single-fault game filter (GTFDF) and the bank against ``control.lqe`` (a Kalman filter of
  the same size: the nearest packaged design, with no decoupling);
* the multi-fault GTMFDF optimisation and the asymptotic (Goh) reduced detector, absolute.

Run: ``python benchmarks/bench_game.py``.
"""

from __future__ import annotations

import argparse

import control
import numpy as np
import scipy.linalg

from fdikit.design.game.multi_fault import game_filter
from fdikit.design.game.reduced_order import goh_detector
from fdikit.design.game.riccati import solve_game_are
from fdikit.design.game.single_fault import game_filter_bank, single_fault_game_filter
from fdikit.plants.f16xl import f16xl_longitudinal
from fdikit.plants.path_longitudinal import path_longitudinal_7, path_longitudinal_7_fault_maps
from timing import best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    f16 = f16xl_longitudinal()
    faults = {"theta": np.column_stack([np.eye(4)[:, 3], f16.A @ np.eye(4)[:, 3]]), "elevon": f16.Bu,
              "gust": f16.Bd}
    p7 = path_longitudinal_7()
    maps = path_longitudinal_7_fault_maps()
    am = {"air_mass": np.linalg.pinv(p7.C)[:, [0]]}  # air-mass sensor direction C⁺e₁ (its rate part)
    am["air_mass"] = np.column_stack([am["air_mass"], p7.A @ am["air_mass"]])

    # one definite CARE both solvers handle: the 7-state single-fault filter's covariance equation
    design7 = single_fault_game_filter(p7, am, maps, gamma=1.25e-8, V=0.8, Q=1.0, M=1.0)
    H = design7.projector
    C = p7.C
    Fh = np.hstack(list(maps.values()))
    a, q = p7.A.T, Fh @ Fh.T / 1.25e-8
    S = np.linalg.inv(np.eye(7) / 0.8 - H @ H)
    t_scipy, X_scipy = best(lambda: scipy.linalg.solve_continuous_are(a, C.T, q, S), args.repeat)
    t_game, sol = best(lambda: solve_game_are(p7.A.T, -C.T @ np.linalg.solve(S, C), q), args.repeat)
    rel = np.abs(sol.X - X_scipy).max() / np.abs(X_scipy).max()

    rows = [("solve_game_are, PATH 7-state single-fault CARE (ν = 1e−8)", t_game,
             f"{t_game / t_scipy:.1f}x scipy solve_continuous_are ({t_scipy * 1e3:.2f} ms), rel. diff {rel:.0e}")]
    t_lqe, _ = best(lambda: control.lqe(f16.A, faults["gust"], f16.C, np.eye(1), np.eye(4)), args.repeat)
    t_sf, _ = best(lambda: single_fault_game_filter(f16, {"gust": faults["gust"]},
                                                   {k: v for k, v in faults.items() if k != "gust"},
                                                   V=1.0, Q=1e-4, M=0.01), args.repeat)
    rows.append(("single_fault_game_filter, F-16XL (4 states)", t_sf, f"{t_sf / t_lqe:.2f}x control.lqe "
                 f"({t_lqe * 1e3:.2f} ms)"))
    t_bank, _ = best(lambda: game_filter_bank(f16, faults, V=1.0, Q=1e-4, M=0.01), args.repeat)
    rows.append(("game_filter_bank, F-16XL, 3 filters", t_bank, f"{t_bank / t_lqe:.2f}x control.lqe"))
    t_multi, gd = best(lambda: game_filter(f16, {"theta": faults["theta"], "elevon": faults["elevon"]},
                                           {"gust": faults["gust"]}, Q={"theta": 2e-4, "elevon": 1e-4},
                                           K=0.01, N={"theta": 1.0, "elevon": 1.5}), 1)
    rows.append((f"game_filter (GTMFDF, L-BFGS-B, {gd.nit} iterations), F-16XL RDDF partition", t_multi, "—"))
    t_goh, g = best(lambda: goh_detector(p7, am, maps, V=0.8, Q=1.0), args.repeat)
    rows.append((f"goh_detector, PATH 7-state → order {g.order}", t_goh, f"{t_goh / t_scipy:.1f}x scipy CARE "
                 "of the full-order filter"))

    print(f"best of {args.repeat}\n\n| design | time | ratio |\n|---|---|---|")
    for name, t, ratio in rows:
        print(f"| {name} | {t * 1e3:.2f} ms | {ratio} |")


if __name__ == "__main__":
    main()
