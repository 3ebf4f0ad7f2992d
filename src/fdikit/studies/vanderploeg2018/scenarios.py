"""Simulation cases of van der Ploeg 2018, Ch. 4: lateral vehicle with additive and multiplicative steering faults.

The plant is the single-track model with lane errors (:func:`fdikit.plants.single_track`, (B.12))
sampled with a zero-order hold at ``h = 0.01`` s ((4.5)); it is simulated **open loop** with the
lane-keeping set-point of (4.2), ``δ_set = 2.3·10⁻³ sin(0.3·2π t)`` rad (Sec. 4-1).  The steering
actually applied is ``δ = f_m δ_set + f_a`` (1.3): ``f_a`` an offset, ``f_m`` a gain (1 when healthy).

Catalogue (fdikit's labels S1–S8; the thesis does not number its cases):

=====  ========================================  ====================================================
case   thesis                                    data
=====  ========================================  ====================================================
S1     Sec. 4-3-1, Fig. 4-3                      70 km/h; ``f_a`` = 0.1 deg at 30 s; ``f_m`` = 0.9 at 50 s
S2/S3  Sec. 4-3-2 Cases 1–2, Figs. 4-5–4-8       70 km/h; constant ``f_m`` = 0.5, ``f_a`` = 0.1 deg
S4/S5  Sec. 4-3-3 Cases 1–2, Figs. 4-10–4-13     70 km/h; ``f_m`` 0.5 → 0.6 at 40 s, ``f_a`` 0.1 → 0.12 deg at 50 s
S6/S7  Sec. 4-3-4 Fig. 4-15, 4-3-5 Fig. 4-17     faults of S4; speed 70 → 120 km/h (cosine sweep over the run)
S8     Sec. 4-4, Figs. 4-18–4-20                 steady cornering at ``a_y`` (Table 4-2), ``f_a`` = 0.1 deg
=====  ========================================  ====================================================

Pairs (S2/S3, S4/S5, S6/S7) share the data and differ in the filter (window, poles, LPV).
All cases: curvature ``κ`` and bank ``φ`` steps at 15 s (Sec. 4-3-1), by default the first row of
Table 4-2 at 70 km/h (R = 350 m, 1.43°) — the thesis does not give their size;
in open loop they make ``y_e`` and ``ψ_e`` drift, which the exact LTI parity filter rejects but an
approximate (finite-γ LPV) filter may not.  Pass ``disturbance_end`` for a pulse.
The speed profile of S6 is not given either (Sec. 4-3-4, Fig. 4-15: "a time-varying longitudinal velocity");
fdikit sweeps ``V_x(t) = 95 − 25 cos(π t/T)`` km/h, 70 km/h at ``t = 0`` to 120 km/h at ``t = T``.

Trace layout: control ``steering`` = ``δ_set`` (as commanded, what the isolation filter knows);
outputs ``yaw_rate, lateral_error, heading_error`` and ``speed`` (measured ``V_x`` in m/s, the
scheduling signal of an LPV filter); states of (B.12); disturbances ``curvature`` (1/m) and ``bank``
(``sin φ``).  Truth labels are ``steering_additive``, ``steering_multiplicative`` or both
(``'+'``-joined); :func:`true_steering_faults` returns the fault signals (``f_a`` in rad).
Varying speed is simulated by switching the ZOH model every sample ("complete discretisation",
Sec. 4-3-4): ``x(k+1) = 𝒜(V_x(k)) x(k) + ℬ(V_x(k)) δ(k) + ℬ_d(V_x(k)) d(k)``, by
:func:`fdikit.simulate.simulate_scheduled` on :func:`fdikit.plants.single_track.single_track_lpv`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, replace

import numpy as np
from numpy.typing import ArrayLike

from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.plants.single_track import PRIUS_2010, SingleTrackParameters, single_track, single_track_lpv
from fdikit.simulate import simulate_scheduled
from fdikit.trace import Trace

__all__ = [
    "ADDITIVE",
    "MULTIPLICATIVE",
    "CASES",
    "TABLE_4_2",
    "OUTPUTS",
    "steering_setpoint",
    "cosine_speed_sweep",
    "design_bank_angle",
    "lateral_run",
    "vanderploeg_case",
    "cornering_run",
    "true_steering_faults",
    "perturbed_parameters",
]

#: Truth label of an additive steering fault (offset ``f_a``).
ADDITIVE = "steering_additive"
#: Truth label of a multiplicative steering fault (gain ``f_m ≠ 1``).
MULTIPLICATIVE = "steering_multiplicative"
#: Output names of the scenario traces: the (B.12) outputs and the measured speed (m/s).
OUTPUTS: tuple[str, ...] = ("yaw_rate", "lateral_error", "heading_error", "speed")
_STATES = ("lateral_velocity", "yaw_rate", "lateral_error", "heading_error")
_DISTURBANCES = ("curvature", "bank")

#: Table 4-2 (Dutch highway design rules): curve radius (m) by bank angle (deg) at 120, 90 and 70 km/h.
TABLE_4_2: dict[str, tuple] = {
    "bank_deg": (1.43, 1.72, 2.00, 2.29, 2.58, 2.86, 3.15, 3.43, 3.72, 4.00),
    120: (1500, 1350, 1200, 1050, 900, 750, None, None, None, None),
    90: (700, 630, 560, 490, 420, 350, 340, 330, None, None),
    70: (350, 315, 280, 250, 215, 180, 175, 170, 165, 160),
}

#: The Ch. 4 cases as keyword arguments of :func:`lateral_run` (fault times in s, ``f_a`` in deg).
CASES: dict[str, dict] = {
    "S1": {"additive_deg": ((30.0, 0.1),), "multiplicative": ((50.0, 0.9),), "source": "Sec. 4-3-1, Fig. 4-3"},
    "S2": {"additive_deg": ((0.0, 0.1),), "multiplicative": ((0.0, 0.5),),
           "source": "Sec. 4-3-2 Case 1, Figs. 4-5, 4-6"},
    "S4": {"additive_deg": ((0.0, 0.1), (50.0, 0.12)), "multiplicative": ((0.0, 0.5), (40.0, 0.6)),
           "source": "Sec. 4-3-3 Case 1, Figs. 4-10, 4-11"},
    "S6": {"additive_deg": ((0.0, 0.1), (50.0, 0.12)), "multiplicative": ((0.0, 0.5), (40.0, 0.6)),
           "speed_kmh": "sweep", "source": "Sec. 4-3-4, Fig. 4-15"},
}
CASES["S3"] = {**CASES["S2"], "source": "Sec. 4-3-2 Case 2, Figs. 4-7, 4-8"}
CASES["S5"] = {**CASES["S4"], "source": "Sec. 4-3-3 Case 2, Figs. 4-12, 4-13"}
CASES["S7"] = {**CASES["S6"], "source": "Sec. 4-3-5, Fig. 4-17"}


def steering_setpoint(t: ArrayLike, amplitude: float = 2.3e-3, frequency: float = 0.3) -> np.ndarray:
    """Lane-keeping steering set-point ``δ_set = 2.3·10⁻³ sin(0.3·2π t)`` rad (van der Ploeg 2018, (4.2)).

    Parameters
    ----------
    t : array_like
        Times [s].
    amplitude : float, default 2.3e-3
        Amplitude [rad].
    frequency : float, default 0.3
        Frequency [Hz].

    Returns
    -------
    numpy.ndarray
        ``δ_set(t)`` [rad], the shape of ``t``.

    References
    ----------
    van der Ploeg 2018, §4-1, (4.2).

    Examples
    --------
    >>> round(float(steering_setpoint(1 / 1.2)), 6)   # a quarter period: the amplitude
    0.0023
    """
    return float(amplitude) * np.sin(2.0 * np.pi * float(frequency) * np.asarray(t, dtype=float))


def cosine_speed_sweep(t: ArrayLike, duration: float, start_kmh: float = 70.0, end_kmh: float = 120.0) -> np.ndarray:
    """Speed ``start + (end − start)(1 − cos(π t/T))/2`` in km/h: monotone, zero acceleration at both ends.

    The S6/S7 profile (Sec. 4-3-4 gives none).  Its largest acceleration is
    ``π (end − start)/(2 T)``: 0.31 m/s² for 70 → 120 km/h over 70 s, so ``a_x ≈ 0`` (4.1) holds.

    Parameters
    ----------
    t : array_like
        Times [s]; clipped to ``[0, duration]``.
    duration : float
        Sweep time ``T`` [s], positive.
    start_kmh, end_kmh : float, default 70.0, 120.0
        Speeds at ``t = 0`` and ``t = T`` [km/h].

    Returns
    -------
    numpy.ndarray
        Speeds [km/h], the shape of ``t``.

    Raises
    ------
    DataError
        If ``duration`` is not a positive finite number.

    References
    ----------
    van der Ploeg 2018, §4-3-4, Fig. 4-15 (profile not given; this one is fdikit's); (4.1).

    Examples
    --------
    >>> cosine_speed_sweep([0.0, 35.0, 70.0], duration=70.0).round(6).tolist()
    [70.0, 95.0, 120.0]
    """
    if not (np.isfinite(duration) and duration > 0):
        raise DataError(f"duration of the speed sweep must be positive, got {duration!r}")
    tt = np.clip(np.asarray(t, dtype=float) / float(duration), 0.0, 1.0)
    return start_kmh + (end_kmh - start_kmh) * 0.5 * (1.0 - np.cos(np.pi * tt))


def design_bank_angle(radius: float, speed_kmh: int = 70) -> float:
    """Bank angle (deg) of a curve of ``radius`` (m) by Table 4-2, interpolated linearly in curvature.

    Sharper curves than the table's last row get its largest bank (4.00° at 70 km/h: the thesis'
    extrapolation to ``a_y = 3`` m/s², Sec. 4-4); gentler curves the smallest (1.43°).

    Parameters
    ----------
    radius : float
        Curve radius [m], positive.
    speed_kmh : {70, 90, 120}, default 70
        Which column of Table 4-2.

    Returns
    -------
    float
        Bank angle [deg].

    Raises
    ------
    ParameterError
        If ``speed_kmh`` is not a column of Table 4-2 or ``radius`` is not positive and finite.

    References
    ----------
    van der Ploeg 2018, §4-4, Table 4-2.

    Examples
    --------
    >>> design_bank_angle(350.0), design_bank_angle(160.0), design_bank_angle(126.0)
    (1.43, 4.0, 4.0)
    """
    if speed_kmh not in (70, 90, 120):
        raise ParameterError(f"Table 4-2 lists 70, 90 and 120 km/h only, got {speed_kmh!r}")
    if not (np.isfinite(radius) and radius > 0):
        raise ParameterError(f"curve radius must be positive (m), got {radius!r}")
    pairs = [(1.0 / R, b) for R, b in zip(TABLE_4_2[speed_kmh], TABLE_4_2["bank_deg"]) if R is not None]
    kappa, bank = np.array(pairs).T
    return float(np.interp(1.0 / radius, kappa, bank))


def _schedule(t: np.ndarray, steps, base: float, name: str) -> tuple[np.ndarray, list[list[float]]]:
    """Piecewise-constant signal: ``base`` before the first step, then each (time, value) until the next."""
    out = np.full(t.shape, float(base))
    clean = []
    try:
        pairs = sorted((float(ts), float(v)) for ts, v in steps)
    except (TypeError, ValueError):
        raise DataError(f"{name} must be a sequence of (time, value) pairs, got {steps!r}") from None
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    for ts, v in pairs:
        if not (np.isfinite(ts) and np.isfinite(v)):
            raise DataError(f"{name} has a non-finite time or value: {(ts, v)}")
        out[t >= ts - 1e-6 * dt] = v
        clean.append([ts, v])
    return out, clean


def _speed_array(speed_kmh, t: np.ndarray, duration: float) -> tuple[np.ndarray, object]:
    if isinstance(speed_kmh, str):
        if speed_kmh != "sweep":
            raise DataError(f"speed_kmh must be a number, an array, a callable or 'sweep', got {speed_kmh!r}")
        return cosine_speed_sweep(t, duration), "cosine sweep 70 -> 120 km/h"
    try:
        v = np.asarray(speed_kmh(t) if callable(speed_kmh) else speed_kmh, dtype=float)
        desc = "callable" if callable(speed_kmh) else float(v) if v.ndim == 0 else "array"
        v = np.broadcast_to(v, t.shape).astype(float)
    except (TypeError, ValueError):
        raise DataError(
            f"speed_kmh must be a number, a ({t.size},) array, a callable t -> km/h or 'sweep'; got {speed_kmh!r}"
        ) from None
    if not np.all(np.isfinite(v) & (v > 0)):
        raise DataError("speed must be positive and finite at every sample (km/h)")
    return v, desc


def _labels(f_a: np.ndarray, f_m: np.ndarray) -> np.ndarray:
    add, mul = f_a != 0.0, f_m != 1.0
    out = np.full(f_a.shape, NO_FAULT, dtype=object)
    out[add & ~mul] = ADDITIVE
    out[mul & ~add] = MULTIPLICATIVE
    out[add & mul] = f"{ADDITIVE}+{MULTIPLICATIVE}"
    return out.astype(str)


def lateral_run(
    duration: float = 70.0,
    *,
    speed_kmh: float | ArrayLike | Callable | str = 70.0,
    additive_deg: Sequence[tuple[float, float]] = (),
    multiplicative: Sequence[tuple[float, float]] = (),
    curvature: float = 1.0 / 350.0,
    bank_deg: float = 1.43,
    disturbance_onset: float = 15.0,
    disturbance_end: float | None = None,
    setpoint_amplitude: float = 2.3e-3,
    setpoint_frequency: float = 0.3,
    setpoint_offset: float = 0.0,
    x0: ArrayLike | None = None,
    params: SingleTrackParameters = PRIUS_2010,
    dt: float = 0.01,
    measurement_noise_std: float | Sequence[float] | None = None,
    rng: np.random.Generator | int | None = None,
    label: str = "custom",
    source: str = "",
) -> Trace:
    """Open-loop run of the single-track vehicle with steering faults (van der Ploeg 2018, Ch. 4).

    Parameters
    ----------
    duration : float
        Length in s (samples ``0, dt, …, duration``).
    speed_kmh : float, (N,) array, callable ``t -> km/h`` or ``'sweep'``
        Longitudinal speed in km/h (the thesis' range is 70–120, (4.1)); ``'sweep'`` is
        :func:`cosine_speed_sweep` from 70 to 120 km/h over ``duration``.
    additive_deg : sequence of (time, value)
        Steering offset ``f_a`` in **deg**, piecewise constant from each time on (0 before the first).
    multiplicative : sequence of (time, value)
        Steering gain ``f_m``, piecewise constant (1 before the first).
    curvature, bank_deg : float
        Road curvature (1/m) and bank angle (deg) switched on at ``disturbance_onset`` (and off at
        ``disturbance_end`` if given).  Default: Table 4-2, 70 km/h, R = 350 m, 1.43°.
    setpoint_amplitude, setpoint_frequency, setpoint_offset : float
        ``δ_set = offset + amplitude sin(2π frequency t)`` (rad); (4.2) with zero offset.
    x0 : (4,) array, optional
        Initial state ``[V_y, ψ̇, y_e, ψ_e]`` (default zero).
    params : SingleTrackParameters
        The *true* vehicle (perturb it for the sensitivity study of Sec. 4-4).
    dt : float
        Sample time ``h`` (0.01 s in the thesis).
    measurement_noise_std : float or 3 floats, optional
        Standard deviations of white Gaussian noise on ``yaw_rate, lateral_error, heading_error``
        (none in the thesis' Ch. 4); the ``speed`` output is noise free.
    rng : numpy.random.Generator or int seed, optional
        Source of the measurement noise.
    label, source : str
        Scenario name and thesis reference, stored in ``meta``.

    Returns
    -------
    Trace
        See the module docstring for the layout; ``meta`` holds the fault schedules, speeds,
        disturbances and parameters, from which :func:`true_steering_faults` rebuilds the faults.

    Raises
    ------
    DataError
        On a non-positive ``dt``, a ``duration`` shorter than one sample, a malformed fault schedule,
        speed, ``x0`` or noise standard deviation.
    ParameterError
        If ``params`` is not a :class:`~fdikit.plants.single_track.SingleTrackParameters`.

    References
    ----------
    van der Ploeg 2018, §4-1, (4.1)–(4.2); §4-3-1, (4.5); §1-1, (1.3) (the fault model); App. B, (B.12).

    Examples
    --------
    >>> tr = lateral_run(40.0, additive_deg=[(30.0, 0.1)])
    >>> tr.fault_onset, str(tr.fault[-1]), tr.outputs[-1]
    (30.0, 'steering_additive', 'speed')
    """
    if not (np.isfinite(dt) and dt > 0):
        raise DataError(f"sample time dt must be positive, got {dt!r}")
    if not (np.isfinite(duration) and duration >= dt):
        raise DataError(f"duration must be at least one sample time ({dt} s), got {duration!r}")
    if not isinstance(params, SingleTrackParameters):
        raise ParameterError(f"params must be a SingleTrackParameters, got {type(params).__name__}")
    t = np.arange(int(round(duration / dt)) + 1) * dt
    N = t.size
    speed, speed_desc = _speed_array(speed_kmh, t, duration)
    f_a_deg, add_steps = _schedule(t, additive_deg, 0.0, "additive_deg")
    f_m, mul_steps = _schedule(t, multiplicative, 1.0, "multiplicative")
    f_a = np.deg2rad(f_a_deg)
    command = float(setpoint_offset) + steering_setpoint(t, setpoint_amplitude, setpoint_frequency)
    applied = f_m * command + f_a  # (1.3)
    on = t >= disturbance_onset - 1e-6 * dt
    if disturbance_end is not None:
        on &= t < disturbance_end - 1e-6 * dt
    d = np.column_stack([np.where(on, float(curvature), 0.0), np.where(on, np.sin(np.deg2rad(bank_deg)), 0.0)])
    x0_arr = np.zeros(4) if x0 is None else np.asarray(x0, dtype=float)
    if x0_arr.shape != (4,) or not np.all(np.isfinite(x0_arr)):
        raise DataError(f"x0 must be 4 finite numbers [V_y, yaw rate, y_e, psi_e], got {x0!r}")
    run = simulate_scheduled(single_track_lpv(params, dt, steering_fault=False), speed / 3.6, u=applied, d=d, x0=x0_arr)
    x, y = run.x, run.y[:, :3]
    seed = int(rng) if isinstance(rng, int | np.integer) else None
    if measurement_noise_std is not None:
        std = np.broadcast_to(np.asarray(measurement_noise_std, dtype=float), (3,))
        if not np.all(np.isfinite(std) & (std >= 0)):
            raise DataError(f"measurement_noise_std must be 1 or 3 standard deviations >= 0, "
                            f"got {measurement_noise_std!r}")
        y = y + np.random.default_rng(rng).standard_normal((N, 3)) * std
    y = np.column_stack([y, speed / 3.6])
    meta = {
        "scenario": label,
        "source": f"van der Ploeg 2018, {source}" if source else "van der Ploeg 2018, Ch. 4",
        "fault_convention": "applied steering = f_m * steering + f_a (thesis (1.3)); steering is delta_set",
        "additive_deg": add_steps,
        "multiplicative": mul_steps,
        "speed_kmh": speed_desc,
        "curvature": float(curvature),
        "bank_deg": float(bank_deg),
        "disturbance_onset": float(disturbance_onset),
        "disturbance_end": None if disturbance_end is None else float(disturbance_end),
        "setpoint": {"amplitude": float(setpoint_amplitude), "frequency": float(setpoint_frequency),
                     "offset": float(setpoint_offset)},
        "params": asdict(params),
        "dt": float(dt),
        "seed": seed,
        "measurement_noise_std": (None if measurement_noise_std is None
                                  else np.atleast_1d(measurement_noise_std).tolist()),
    }
    return Trace(
        t=t, u=command, y=y, x=x, d=d, controls=("steering",), outputs=OUTPUTS, states=_STATES,
        disturbances=_DISTURBANCES, fault=_labels(f_a, f_m), meta=meta,
    )


def vanderploeg_case(name: str, **overrides) -> Trace:
    """One of the Ch. 4 cases S1–S7 of the module table; ``overrides`` go to :func:`lateral_run`.

    Parameters
    ----------
    name : {"S1", "S2", "S3", "S4", "S5", "S6", "S7"}
        Case label (a key of :data:`CASES`; S8 is :func:`cornering_run`).
    **overrides
        Keyword arguments of :func:`lateral_run` that replace the case's (e.g. ``duration=``).

    Returns
    -------
    Trace
        The run of :func:`lateral_run`; ``meta["scenario"]`` is the case label and ``meta["source"]``
        its section and figures.

    Raises
    ------
    ParameterError
        If ``name`` is not one of the cases.

    References
    ----------
    van der Ploeg 2018, §4-3-1 to §4-3-5, Figs. 4-3 to 4-17 (per case, see the module table).

    Examples
    --------
    >>> tr = vanderploeg_case("S4")
    >>> tr.meta["source"], tr.meta["multiplicative"]
    ('van der Ploeg 2018, Sec. 4-3-3 Case 1, Figs. 4-10, 4-11', [[0.0, 0.5], [40.0, 0.6]])
    """
    if name not in CASES:
        raise ParameterError(f"unknown case {name!r}; the cases are {sorted(CASES)} (S8: use cornering_run)")
    kw = {**CASES[name], **overrides}
    kw.setdefault("label", name)
    return lateral_run(**kw)


def cornering_run(
    lateral_acceleration: float = 3.0,
    *,
    speed_kmh: float = 70.0,
    bank_deg: float | None = None,
    params: SingleTrackParameters = PRIUS_2010,
    additive_deg: Sequence[tuple[float, float]] = ((5.0, 0.1),),
    duration: float = 30.0,
    excitation: bool = True,
    dt: float = 0.01,
    **kwargs,
) -> Trace:
    """S8: steady-state cornering at ``a_y = V_x² κ`` with an offset fault (van der Ploeg 2018, Sec. 4-4).

    The curve has ``κ = a_y / V_x²`` and, unless given, the bank of Table 4-2 for its radius
    (:func:`design_bank_angle`; 4° at 3 m/s², the thesis' extrapolation), banked into the curve.
    The thesis does not say how the steady state is produced: here the set-point
    carries the feedforward steering ``δ_ss`` that holds the **true** vehicle (``params``) on the
    curve, and the run starts in that steady state (``ψ̇ = V_x κ``, ``ψ_e = V_y/V_x``, so ``y_e``
    stays constant), with (4.2) on top when ``excitation`` is true.  The curve is present from
    ``t = 0``; ``f_a = 0.1`` deg is injected at 5 s.  Perturb ``params`` (e.g. ``C_f`` ±10 %)
    and evaluate a nominal residual generator: the difference of its residual from ``G(q)[f]`` is the
    false fault ``Δ_f`` of (4.21).

    Parameters
    ----------
    lateral_acceleration : float, default 3.0
        Steady lateral acceleration ``a_y`` [m/s²], ``>= 0``.
    speed_kmh : float, default 70.0
        Constant speed [km/h].
    bank_deg : float, optional
        Road bank angle [deg]; default from Table 4-2 by :func:`design_bank_angle` (0 on a straight).
    params : SingleTrackParameters, default PRIUS_2010
        The true vehicle.
    additive_deg : sequence of (time, value), default ((5.0, 0.1),)
        Steering offset schedule ``f_a`` [deg].
    duration : float, default 30.0
        Length [s].
    excitation : bool, default True
        Add the (4.2) set-point on top of the steady-state steering.
    dt : float, default 0.01
        Sample time [s].
    **kwargs
        Further keyword arguments of :func:`lateral_run` (they override the ones set here).

    Returns
    -------
    Trace
        The run of :func:`lateral_run`, with ``meta["lateral_acceleration"]`` and
        ``meta["steady_state_steering"]`` (``δ_ss`` [rad]) added.

    Raises
    ------
    DataError
        If ``lateral_acceleration`` is negative or not finite.

    References
    ----------
    van der Ploeg 2018, §4-4, Table 4-2, (4.21), Figs. 4-18 to 4-20.

    Examples
    --------
    >>> tr = cornering_run(3.0, excitation=False, additive_deg=())
    >>> bool(abs(tr.signal("yaw_rate")[-1] - 3.0 / (70 / 3.6)) < 1e-9)   # ψ̇ = a_y / V_x
    True
    """
    v = float(speed_kmh) / 3.6
    if not (np.isfinite(lateral_acceleration) and lateral_acceleration >= 0):
        raise DataError(f"lateral_acceleration must be >= 0 (m/s²), got {lateral_acceleration!r}")
    kappa = float(lateral_acceleration) / v**2
    if bank_deg is None:
        bank_deg = 0.0 if kappa == 0 else design_bank_angle(1.0 / kappa, int(round(speed_kmh)))
    model = single_track(v, params)
    A, Bu, Bd = model.A, model.b("u")[:, 0], model.b("d")
    sin_phi = np.sin(np.deg2rad(bank_deg))
    yaw = v * kappa
    # rows V_y', ψ'' of (B.12) at rest: A[:2,0] V_y + A[:2,1] ψ̇ + B[:2] δ + B_d[:2,1] sin φ = 0, unknowns V_y, δ
    M = np.column_stack([A[:2, 0], Bu[:2]])
    rhs = -(A[:2, 1] * yaw + Bd[:2, 1] * sin_phi)
    v_y, delta_ss = np.linalg.solve(M, rhs)
    x0 = np.array([v_y, yaw, 0.0, v_y / v])
    kw = {
        "speed_kmh": speed_kmh, "additive_deg": additive_deg, "curvature": kappa, "bank_deg": bank_deg,
        "disturbance_onset": 0.0, "setpoint_offset": delta_ss, "x0": x0, "params": params, "dt": dt,
        "label": "S8", "source": "Sec. 4-4, Figs. 4-18 to 4-20",
    }
    if not excitation:
        kw["setpoint_amplitude"] = 0.0
    kw.update(kwargs)
    trace = lateral_run(duration, **kw)
    trace.meta.update({"lateral_acceleration": float(lateral_acceleration), "steady_state_steering": float(delta_ss)})
    return trace


def true_steering_faults(trace: Trace) -> tuple[np.ndarray, np.ndarray]:
    """The true ``(f_a, f_m)`` per sample of a scenario trace, ``f_a`` in **rad**, rebuilt from its meta.

    Parameters
    ----------
    trace : Trace
        A trace of :func:`lateral_run`, :func:`vanderploeg_case` or :func:`cornering_run`.

    Returns
    -------
    f_a : numpy.ndarray
        (N,) additive steering fault [rad].
    f_m : numpy.ndarray
        (N,) multiplicative steering fault (gain; 1 when healthy).

    Raises
    ------
    DataError
        If ``trace.meta`` has no fault schedule.

    References
    ----------
    van der Ploeg 2018, §1-1, (1.3) (``δ = f_m δ_set + f_a``).

    Examples
    --------
    >>> f_a, f_m = true_steering_faults(vanderploeg_case("S1", duration=60.0))
    >>> float(np.rad2deg(f_a[-1])), float(f_m[-1]), float(f_m[0])
    (0.1, 0.9, 1.0)
    """
    meta = trace.meta
    if "additive_deg" not in meta or "multiplicative" not in meta:
        raise DataError("this trace has no steering fault schedule in its meta; it was not made by this module")
    f_a, _ = _schedule(trace.t, meta["additive_deg"], 0.0, "additive_deg")
    f_m, _ = _schedule(trace.t, meta["multiplicative"], 1.0, "multiplicative")
    return np.deg2rad(f_a), f_m


def perturbed_parameters(params: SingleTrackParameters = PRIUS_2010, **scales: float) -> SingleTrackParameters:
    """``params`` with fields multiplied by ``scales``, e.g. ``C_f=1.1`` for +10 % (the Sec. 4-4 study).

    Parameters
    ----------
    params : SingleTrackParameters, default PRIUS_2010
        Nominal vehicle.
    **scales : float
        Factor per field name (``l_f``, ``l_r``, ``m``, ``I_z``, ``C_f``, ``C_r``, ``g``).

    Returns
    -------
    SingleTrackParameters
        A new parameter set.

    Raises
    ------
    ParameterError
        If a name in ``scales`` is not a field of ``params``.
    ParameterError
        If a scaled value is invalid (e.g. a stiffness scaled to a positive value).

    References
    ----------
    van der Ploeg 2018, §4-4 (sensitivity analysis).

    Examples
    --------
    >>> round(perturbed_parameters(C_f=1.1).C_f, 6)
    -128700.0
    """
    unknown = set(scales) - set(asdict(params))
    if unknown:
        raise ParameterError(f"unknown vehicle parameters {sorted(unknown)}; choose from {sorted(asdict(params))}")
    return replace(params, **{k: getattr(params, k) * float(s) for k, s in scales.items()})
