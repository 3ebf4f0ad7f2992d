"""The lateral-acceleration sensor fault of Varrier, Koenig & Martinez 2014, §5.4–5.5, simulated.

The paper adds a +0.5 m/s² bias to the measured ``a_y`` from 150 s to 158 s of a Renault
Scénic record (MIPS data, not available).  :func:`varrier_trace` replaces the record by a
simulation of the discrete uncertain LPV model (48) at ``T_d = 0.02`` s — the documented
uncertainty class of the robust design (§5.3):

* speed ``v(t) = 20.83 + 4 sin(2πt/100) + 2 sin(2πt/37)`` m/s (about 54–97 km/h around the
  paper's 75 km/h mean), ρ = 1/v;
* road-wheel steering ``u(t) = 0.02 sin(2π 0.2 t) + 0.01 sin(2π 0.05 t + 1)`` rad;
* stiffness uncertainty ``Ā = A₀(ρ) + δ(t) A₁`` with a slow ``δ(t) = δ̄ cos(2πt/90)`` (nearly
  constant over the 60 ms window, as (14) assumes), by default δ̄ = 1 with the "continuous" reading
  ``A₁ = 0.2 (A₀(ρ*) − I)`` (±20 % of the continuous dynamics; the literal ``0.2 A₀(ρ*)`` scales
  the state by 1 ± 0.2 δ per step and is unstable at δ = 1);
* the unknown input ``d`` (``B_d``, ``D_d`` of §5.3) a first-order low-pass (0.5 s) Gaussian
  signal with standard deviation ``disturbance`` (default 0.003: 6 mrad/s on the yaw rate via
  ``D_d = [0; 2.064]``);
* optional white measurement noise; the fault is applied to the recorded ``a_y`` only.

The score of §5.5 is ϖ = min |r_n| over the faulty time / max |r_n| over the healthy time,
``r_n = r / mean(r over the faulty time)`` (Remark 8).  Windows straddling a fault edge
belong to neither set (an fdikit rule; §5.5 does not say).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fdikit.design.parity.robust import kappa_max, pointwise_theorem1, robust_criteria, robust_lpv_parity
from fdikit.design.parity.state_space import lpv_parity_residuals
from fdikit.errors import DataError, ModelError
from fdikit.faults import NO_FAULT
from fdikit.plants.varrier_lateral import (
    RHO_STAR,
    SCENIC,
    T_D,
    VarrierParameters,
    rho_from_speed,
    varrier_lateral_lpv,
    varrier_uncertainty,
)
from fdikit.residuals import Residuals
from fdikit.trace import Trace

__all__ = [
    "speed_profile",
    "steering_profile",
    "varrier_trace",
    "fault_window_masks",
    "normalise_residual",
    "min_max_ratio",
    "VarrierComparison",
    "varrier_comparison",
]

FAULT_NAME = "lateral_acceleration_sensor"


def speed_profile(t: np.ndarray) -> np.ndarray:
    """Default speed (m/s): ``20.83 + 4 sin(2πt/100) + 2 sin(2πt/37)``."""
    t = np.asarray(t, dtype=float)
    return 1 / RHO_STAR + 4.0 * np.sin(2 * np.pi * t / 100) + 2.0 * np.sin(2 * np.pi * t / 37)


def steering_profile(t: np.ndarray) -> np.ndarray:
    """Default road-wheel steering (rad): ``0.02 sin(2π 0.2 t) + 0.01 sin(2π 0.05 t + 1)``."""
    t = np.asarray(t, dtype=float)
    return 0.02 * np.sin(2 * np.pi * 0.2 * t) + 0.01 * np.sin(2 * np.pi * 0.05 * t + 1.0)


def varrier_trace(
    *,
    duration: float = 200.0,
    dt: float = T_D,
    delta: float = 1.0,
    disturbance: float = 0.003,
    noise_std: tuple[float, float] = (0.0, 0.0),
    fault_size: float = 0.5,
    fault_window: tuple[float, float] = (150.0, 158.0),
    uncertainty_mode: str = "continuous",
    speed: Callable[[np.ndarray], np.ndarray] = speed_profile,
    steering: Callable[[np.ndarray], np.ndarray] = steering_profile,
    params: VarrierParameters = SCENIC,
    seed: int | np.random.Generator = 0,
) -> Trace:
    """Simulated run of §5.4: the uncertain LPV vehicle with a +0.5 m/s² ``a_y`` bias on [150 s, 158 s).

    Parameters
    ----------
    delta : amplitude δ̄ of the slow stiffness uncertainty δ(t) = δ̄ cos(2πt/90).
    disturbance : standard deviation of the unknown input d.
    noise_std : white noise standard deviations on (a_y, r).
    fault_size, fault_window : the bias and its interval ``[start, end)`` in s.
    uncertainty_mode : ``"literal"`` or ``"continuous"`` (see :func:`varrier_uncertainty`).
    speed, steering : functions of time; seed : int or Generator.

    Returns
    -------
    Trace
        Controls ``steering``; outputs ``lateral_acceleration``, ``yaw_rate`` and the measured
        ``speed``; states ``sideslip, yaw_rate``; disturbances ``unknown_input`` and ``delta``;
        fault labels ``lateral_acceleration_sensor`` on the fault window.
    """
    if not (duration > 0 and dt > 0):
        raise ModelError(f"duration and dt must be positive, got {duration}, {dt}")
    start, end = fault_window
    if not end > start:
        raise ModelError(f"fault_window must be (start, end) with end > start, got {fault_window}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    lpv = varrier_lateral_lpv(dt, params)
    A1 = varrier_uncertainty(dt, params, mode=uncertainty_mode).A[0]
    t = np.arange(int(round(duration / dt))) * dt
    v = np.asarray(speed(t), dtype=float)
    rho = rho_from_speed(v)
    u = np.asarray(steering(t), dtype=float)
    dlt = delta * np.cos(2 * np.pi * t / 90)
    a = np.exp(-dt / 0.5)
    w = rng.standard_normal(t.size) * disturbance * np.sqrt(1 - a**2)
    d = np.empty(t.size)
    d[0] = disturbance * rng.standard_normal()
    for k in range(1, t.size):
        d[k] = a * d[k - 1] + w[k]
    A, B, C, D = lpv.matrices(rho)
    iu, idist = lpv.columns("u"), lpv.columns("d")
    x = np.zeros((t.size, 2))
    for k in range(t.size - 1):
        x[k + 1] = (A[k] + dlt[k] * A1) @ x[k] + B[k][:, iu] @ [u[k]] + B[k][:, idist] @ [d[k]]
    y = np.einsum("kij,kj->ki", C, x) + D[:, :, iu][..., 0] * u[:, None] + D[:, :, idist][..., 0] * d[:, None]
    y = y + rng.standard_normal(y.shape) * np.asarray(noise_std, dtype=float)
    k = np.arange(t.size)  # by sample index, so that 150 s / 0.02 s is sample 7500 whatever the rounding
    faulty = (k >= np.ceil(start / dt - 1e-9)) & (k < np.ceil(end / dt - 1e-9))
    y[faulty, 0] += fault_size
    meta = {"scenario": "varrier2014", "delta": delta, "disturbance": disturbance, "noise_std": list(noise_std),
            "fault_size": fault_size, "fault_window": [start, end], "uncertainty_mode": uncertainty_mode, "dt": dt}
    return Trace(
        t=t, u=u[:, None], y=np.column_stack([y, v]), controls=("steering",),
        outputs=("lateral_acceleration", "yaw_rate", "speed"), x=x, states=("sideslip", "yaw_rate"),
        d=np.column_stack([d, dlt]), disturbances=("unknown_input", "delta"),
        fault=np.where(faulty, FAULT_NAME, NO_FAULT), meta=meta,
    )


def fault_window_masks(trace: Trace, s: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples whose window ``[k−s, k]`` is entirely faulty, and those with no faulty sample (k ≥ s)."""
    f = trace.fault != NO_FAULT
    if not f.any():
        raise DataError("the trace has no faulty sample; ϖ needs a fault window")
    win = np.lib.stride_tricks.sliding_window_view(f, s + 1)
    faulty, healthy = np.zeros(f.size, bool), np.zeros(f.size, bool)
    faulty[s:], healthy[s:] = win.all(axis=1), ~win.any(axis=1)
    return faulty, healthy


def normalise_residual(r: np.ndarray, faulty: np.ndarray) -> np.ndarray:
    """``r / mean(r over the faulty samples)`` (Remark 8): mean one during the fault."""
    r = np.asarray(r, dtype=float)
    m = np.mean(r[faulty])
    if not np.isfinite(m) or m == 0:
        raise DataError("the residual's mean over the faulty time is zero or not finite; it cannot be normalised")
    return r / m


def min_max_ratio(r: np.ndarray, faulty: np.ndarray, healthy: np.ndarray) -> float:
    """ϖ = min |r_n| faulty / max |r_n| healthy (§5.5); > 1 means one threshold separates them.

    >>> import numpy as np
    >>> r = np.array([0.1, -0.2, 1.2, 0.8, 0.1])
    >>> min_max_ratio(r, np.array([0, 0, 1, 1, 0], bool), np.array([1, 1, 0, 0, 1], bool))
    4.0
    """
    rn = normalise_residual(r, faulty)
    return float(np.min(np.abs(rn[faulty])) / np.max(np.abs(rn[healthy])))


@dataclass(frozen=True, eq=False)
class VarrierComparison:
    """ϖ of each residual, the residuals (normalised), and the polytopic design used."""

    varpi: dict[str, float]
    residuals: dict[str, Residuals]
    design: object


def varrier_comparison(trace: Trace, *, s: int = 3, kappa_fraction: float = 0.9, rho_range: tuple[float, float]
                       = (0.0, 0.2), order: int = 5, uncertainty_mode: str | None = None) -> VarrierComparison:
    """ϖ of the LPV residual (§3, ``W₂ = 𝟙/√q``) and of U-LPV residuals (§4) on a trace.

    U-LPV variants: ``"ulpv_lmi"`` (paper: polytopic LMI (40), N+1 = ``order+1`` vertices,
    κ = ``kappa_fraction`` × κ_max), ``"ulpv_adjugate"`` (``W₂ = adj Γ_κ c``), ``"ulpv_theorem1"``
    (pointwise Theorem 1) and ``"ulpv_constant"`` (pointwise Theorem 1 with a constant-fault Γ₂).
    The design's uncertainty reading defaults to the trace's (``meta["uncertainty_mode"]``).
    """
    if uncertainty_mode is None:
        uncertainty_mode = trace.meta.get("uncertainty_mode", "literal")
    lpv = varrier_lateral_lpv(trace.dt)
    unc = [varrier_uncertainty(trace.dt, mode=uncertainty_mode)]
    rho = rho_from_speed(trace.signal("speed"))
    faulty, healthy = fault_window_masks(trace, s)
    grid = robust_criteria(lpv, unc, np.linspace(rho_range[0], rho_range[1], 41), s)
    kappa = kappa_fraction * kappa_max(grid.gamma1, grid.gamma2)
    lmi = robust_lpv_parity(lpv, unc, s, kappa=kappa, rho_min=rho_range[0], rho_max=rho_range[1], order=order,
                            rho_nominal=RHO_STAR)
    adj = robust_lpv_parity(lpv, unc, s, kappa=kappa, rho_min=rho_range[0], rho_max=rho_range[1], order=order,
                            method="adjugate", rho_nominal=RHO_STAR)
    q = lpv.p * (s + 1) - lpv.n
    W2s = {
        "lpv": np.ones(q) / np.sqrt(q),
        "ulpv_lmi": lmi.w2,
        "ulpv_adjugate": adj.w2,
        "ulpv_theorem1": pointwise_theorem1(lpv, unc, s, rows=lmi.rows),
        "ulpv_constant": pointwise_theorem1(lpv, unc, s, rows=lmi.rows, fault_model="constant"),
    }
    out, res = {}, {}
    for name, W2 in W2s.items():
        r = lpv_parity_residuals(lpv, trace, rho, s, W2=W2, rows=lmi.rows, names=[name])
        out[name] = min_max_ratio(r.r[:, 0], faulty, healthy)
        rn = np.full_like(r.r, np.nan)
        rn[s:] = normalise_residual(r.r[:, 0], faulty)[s:, None]
        res[name] = Residuals(r.t, rn, r.names, r.isolates, r.valid, r.meta)
    return VarrierComparison(out, res, lmi)
