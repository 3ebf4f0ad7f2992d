"""The lateral-acceleration sensor fault of Varrier et al. 2014, §5.4–5.5, simulated.

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

from fdikit.design.parity.criteria import kappa_max, pointwise_theorem1, robust_criteria
from fdikit.design.parity.robust import robust_lpv_parity
from fdikit.design.parity.state_space import lpv_parity_residuals
from fdikit.errors import DataError, ParameterError
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
    """Default speed (m/s): ``20.83 + 4 sin(2πt/100) + 2 sin(2πt/37)``.

    Parameters
    ----------
    t : array_like
        Times [s].

    Returns
    -------
    numpy.ndarray
        Speeds [m/s], the shape of ``t``; mean ``1/ρ* = 20.83`` m/s (75 km/h).

    References
    ----------
    Varrier et al. 2014, §5.3 (the mean speed; the variation is an fdikit choice).

    Examples
    --------
    >>> speed_profile([0.0, 25.0]).round(3).tolist()
    [20.833, 23.047]
    """
    t = np.asarray(t, dtype=float)
    return 1 / RHO_STAR + 4.0 * np.sin(2 * np.pi * t / 100) + 2.0 * np.sin(2 * np.pi * t / 37)


def steering_profile(t: np.ndarray) -> np.ndarray:
    """Default road-wheel steering (rad): ``0.02 sin(2π 0.2 t) + 0.01 sin(2π 0.05 t + 1)``.

    Parameters
    ----------
    t : array_like
        Times [s].

    Returns
    -------
    numpy.ndarray
        Steering angles [rad], the shape of ``t``.

    References
    ----------
    Varrier et al. 2014, §5.3–5.4 (the profile itself is an fdikit choice).

    Examples
    --------
    >>> steering_profile([0.0]).round(6).tolist()
    [0.008415]
    """
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
    duration : float, default 200.0
        Length of the run [s]; ``round(duration / dt)`` samples.
    dt : float, default T_D (0.02)
        Sample time [s].
    delta : float, default 1.0
        Amplitude δ̄ of the slow stiffness uncertainty δ(t) = δ̄ cos(2πt/90).
    disturbance : float, default 0.003
        Standard deviation of the unknown input d.
    noise_std : tuple of float, default (0.0, 0.0)
        White noise standard deviations on (a_y [m/s²], r [rad/s]).
    fault_size : float, default 0.5
        The ``a_y`` sensor bias [m/s²].
    fault_window : tuple of float, default (150.0, 158.0)
        The bias interval ``[start, end)`` [s].
    uncertainty_mode : {"continuous", "literal"}, default "continuous"
        Reading of ``A₁`` (see :func:`fdikit.plants.varrier_lateral.varrier_uncertainty`).
    speed, steering : callable
        Functions of the time array giving the speed [m/s] and the road-wheel steering [rad];
        default :func:`speed_profile`, :func:`steering_profile`.
    params : VarrierParameters, default SCENIC
        Vehicle parameters.
    seed : int or numpy.random.Generator, default 0
        Randomness of the unknown input and the noise.

    Returns
    -------
    Trace
        Controls ``steering``; outputs ``lateral_acceleration``, ``yaw_rate`` and the measured
        ``speed``; states ``sideslip, yaw_rate``; disturbances ``unknown_input`` and ``delta``;
        fault labels ``lateral_acceleration_sensor`` on the fault window.

    Raises
    ------
    ParameterError
        If ``duration`` or ``dt`` is not positive, or the fault window is empty.

    References
    ----------
    Varrier et al. 2014, §5.1, (48); §5.3 (uncertainty, unknown input); §5.4 (the faulty scenario).

    Examples
    --------
    >>> tr = varrier_trace(duration=4.0, fault_window=(2.0, 3.0))
    >>> tr.y.shape, int((tr.fault == "lateral_acceleration_sensor").sum())
    ((200, 3), 50)
    """
    if not (duration > 0 and dt > 0):
        raise ParameterError(f"duration and dt must be positive, got {duration}, {dt}")
    start, end = fault_window
    if not end > start:
        raise ParameterError(f"fault_window must be (start, end) with end > start, got {fault_window}")
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
    """Samples whose window ``[k−s, k]`` is entirely faulty, and those with no faulty sample (k ≥ s).

    Parameters
    ----------
    trace : Trace
        A run with fault labels (e.g. from :func:`varrier_trace`).
    s : int
        Parity window order (``s + 1`` samples per window; §5.3 uses ``s = 3``).

    Returns
    -------
    faulty, healthy : (N,) bool arrays
        ``faulty[k]``: samples ``k−s … k`` all faulty; ``healthy[k]``: none faulty; both false for ``k < s``.

    Raises
    ------
    DataError
        If the trace has no faulty sample.

    References
    ----------
    Varrier et al. 2014, §5.5 (the edge rule is fdikit's, see the module docstring).

    Examples
    --------
    >>> tr = varrier_trace(duration=4.0, fault_window=(2.0, 3.0))
    >>> faulty, healthy = fault_window_masks(tr, 3)
    >>> int(faulty.sum()), int(healthy.sum())
    (47, 144)
    """
    f = trace.fault != NO_FAULT
    if not f.any():
        raise DataError("the trace has no faulty sample; ϖ needs a fault window")
    win = np.lib.stride_tricks.sliding_window_view(f, s + 1)
    faulty, healthy = np.zeros(f.size, bool), np.zeros(f.size, bool)
    faulty[s:], healthy[s:] = win.all(axis=1), ~win.any(axis=1)
    return faulty, healthy


def normalise_residual(r: np.ndarray, faulty: np.ndarray) -> np.ndarray:
    """``r / mean(r over the faulty samples)`` (Remark 8): mean one during the fault.

    Parameters
    ----------
    r : array_like
        Residual samples.
    faulty : array_like of bool or int
        Index of the faulty samples (boolean mask or indices into ``r``).

    Returns
    -------
    numpy.ndarray
        ``r`` divided by its mean over the faulty samples.

    Raises
    ------
    DataError
        If that mean is zero or not finite.

    References
    ----------
    Varrier et al. 2014, §5.5, Remark 8.

    Examples
    --------
    >>> import numpy as np
    >>> normalise_residual(np.array([1.0, 2.0, 4.0]), np.array([False, True, True])).round(6).tolist()
    [0.333333, 0.666667, 1.333333]
    """
    r = np.asarray(r, dtype=float)
    m = np.mean(r[faulty])
    if not np.isfinite(m) or m == 0:
        raise DataError("the residual's mean over the faulty time is zero or not finite; it cannot be normalised")
    return r / m


def min_max_ratio(r: np.ndarray, faulty: np.ndarray, healthy: np.ndarray) -> float:
    """ϖ = min |r_n| faulty / max |r_n| healthy (§5.5); > 1 means one threshold separates them.

    Parameters
    ----------
    r : (N,) array
        Residual.
    faulty, healthy : (N,) bool arrays
        Masks of the faulty and healthy samples (see :func:`fault_window_masks`).

    Returns
    -------
    float
        ϖ, computed on the normalised residual ``r_n`` of :func:`normalise_residual`.

    References
    ----------
    Varrier et al. 2014, §5.5, Remark 8.

    Examples
    --------
    >>> import numpy as np
    >>> r = np.array([0.1, -0.2, 1.2, 0.8, 0.1])
    >>> min_max_ratio(r, np.array([0, 0, 1, 1, 0], bool), np.array([1, 1, 0, 0, 1], bool))
    4.0
    """
    rn = normalise_residual(r, faulty)
    return float(np.min(np.abs(rn[faulty])) / np.max(np.abs(rn[healthy])))


@dataclass(frozen=True, eq=False)
class VarrierComparison:
    """ϖ of each residual, the residuals (normalised), and the polytopic design used.

    Attributes
    ----------
    varpi : dict of str to float
        ϖ of each residual: ``"lpv"``, ``"ulpv_lmi"``, ``"ulpv_adjugate"``, ``"ulpv_theorem1"``, ``"ulpv_constant"``.
    residuals : dict of str to Residuals
        Each residual normalised by :func:`normalise_residual` (NaN for the first ``s`` samples).
    design : RobustParityDesign
        The polytopic LMI design (``"ulpv_lmi"``).

    References
    ----------
    Varrier et al. 2014, §5.5.

    Examples
    --------
    >>> VarrierComparison(varpi={"lpv": 1.5}, residuals={}, design=None).varpi["lpv"]
    1.5
    """

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

    Parameters
    ----------
    trace : Trace
        A run of :func:`varrier_trace` (outputs ``lateral_acceleration``, ``yaw_rate``, ``speed``, fault labels).
    s : int, default 3
        Parity window order (3 samples, 60 ms, §5.3).
    kappa_fraction : float, default 0.9
        κ as a fraction of κ_max of the criteria grid.
    rho_range : tuple of float, default (0.0, 0.2)
        ``(ρ_min, ρ_max)`` [s/m] of the polytopic design and its 41-point criteria grid.
    order : int, default 5
        Polynomial order of the LMI design (``order + 1`` vertices).
    uncertainty_mode : {"literal", "continuous"}, optional
        Reading of ``A₁`` for the design; default the trace's ``meta["uncertainty_mode"]``.

    Returns
    -------
    VarrierComparison
        ϖ and the normalised residual of each of the five variants, and the LMI design.

    Raises
    ------
    DataError
        If the trace has no faulty sample, or a residual's mean over the faulty time is zero.

    References
    ----------
    Varrier et al. 2014, §3 (LPV parity), §4, (40) (U-LPV polytopic LMI), Theorem 1; §5.5 (ϖ).

    Examples
    --------
    The polytopic LMI takes a few seconds, so the call is not run here (tests/studies runs it):

    >>> tr = varrier_trace(duration=4.0, fault_window=(2.0, 3.0))
    >>> result = varrier_comparison(tr, order=2)  # doctest: +SKIP
    >>> sorted(result.varpi)  # doctest: +SKIP
    ['lpv', 'ulpv_adjugate', 'ulpv_constant', 'ulpv_lmi', 'ulpv_theorem1']
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
