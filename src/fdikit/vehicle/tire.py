"""Magic-Formula tire forces with combined slip (Bakker et al. 1987).

Douglas et al. 1996, Ch. 8 §8.1.8 (8.43)–(8.45) and §8.2 Table 8.1 give the Magic Formula
``y(x) = D sin(C atan(Bx − E(Bx − atan Bx)))`` with load-dependent factors, and (8.98)–(8.103) the
combined-slip method of Bakker et al.: normalised slips ``λ* = λ/λ_max``, ``α* = α/α_max``,
``σ* = √(λ*² + α*²)``; ``F_x = (λ*/σ*) F_x0(σ* λ_max)``, ``F_y = (α*/σ*) F_y0(σ* α_max)`` — the
pure-slip curves evaluated at the equivalent slip (the report leaves where to evaluate them open;
this is Bakker's choice).  No coefficients are printed; :data:`BAKKER_1987` is the passenger-car
tire of Bakker et al. 1987 (normal load in kN, slip ratio in %, slip angle in degrees, forces in N),
camber and the small shifts ``S_h``, ``S_v`` zero (a tire with no ply-steer or conicity).

``λ_max`` and ``α_max`` (the slips of the force peaks) are where ``C atan(…) = π/2``, found by
Newton's method on ``Bx − E(Bx − atan Bx) = tan(π/(2C))`` at every load.

The report's slip ``λ = 1 − v/(r ω)`` (8.41) is singular at ω = 0 and unbounded in braking; here
``λ = (r ω − v) / max(|r ω|, |v|, v_min)``, equal to (8.41) when driving and to the braking slip
``(r ω − v)/v`` when braking, bounded by ±1 and continuous with its first derivative at ``r ω = v``.

The kernels are compiled with numba (the car integrates at 1 kHz); :func:`tire_forces` is their
array interface.  Written by hand because no maintained Python tire library implements the
Magic Formula of Bakker et al. 1987 with Bakker's combined slip as the report uses it.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass

import numpy as np
from numba import njit

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = ["TireCoefficients", "BAKKER_1987", "tire_forces", "peak_slips", "slip_ratio"]
# the compiled kernels (mf_factors, mf_curve, mf_peak, combined_forces, slip_kernel) are used by the car's dynamics


@dataclass(frozen=True)
class TireCoefficients:
    """Magic-Formula coefficients of the 1987 form (load in kN, slip ratio in %, slip angle in degrees, forces in N).

    Longitudinal: ``C = a0``, ``D = a1 N² + a2 N``, ``BCD = (a3 N² + a4 N) e^{−a5 N}``, ``E = a6 N² + a7 N + a8``.
    Lateral: ``C = b0``, ``D = b1 N² + b2 N``, ``BCD = b3 sin(b4 atan(b5 N))``, ``E = b6 N² + b7 N + b8``.

    Attributes
    ----------
    a0, a1, a2, a3, a4, a5, a6, a7, a8 : float
        Longitudinal-force coefficients (Table 8.1, "brake force").
    b0, b1, b2, b3, b4, b5, b6, b7, b8 : float
        Lateral-force coefficients (Table 8.1, "side force"; ``D = b1 N² + b2 N``, the printed ``b2`` read as ``b2 N``).
    mu : float
        Road friction scale: ``D`` is multiplied by it (1 for the dry road the coefficients were fitted on).

    References
    ----------
    Douglas et al. 1996, §8.1.8 (8.43)–(8.45), Table 8.1; Bakker et al. 1987.

    Examples
    --------
    >>> BAKKER_1987.a0, BAKKER_1987.b0
    (1.65, 1.3)
    """

    a0: float
    a1: float
    a2: float
    a3: float
    a4: float
    a5: float
    a6: float
    a7: float
    a8: float
    b0: float
    b1: float
    b2: float
    b3: float
    b4: float
    b5: float
    b6: float
    b7: float
    b8: float
    mu: float = 1.0

    def __post_init__(self) -> None:
        for name, value in zip(self.__dataclass_fields__, astuple(self)):
            validate.number(f"TireCoefficients.{name}", value)
        if self.a0 <= 1.0 or self.b0 <= 1.0:
            raise ParameterError(f"TireCoefficients: the shape factors a0={self.a0}, b0={self.b0} must be > 1 "
                                 "(a curve with a peak)")
        if not self.mu > 0:
            raise ParameterError(f"TireCoefficients: mu must be > 0 (road friction scale), got {self.mu}")

    def as_array(self) -> np.ndarray:
        """The 19 numbers in field order (the layout the compiled kernels read).

        Returns
        -------
        (19,) ndarray

        Examples
        --------
        >>> BAKKER_1987.as_array().shape
        (19,)
        """
        return np.array(astuple(self), dtype=float)


#: The passenger-car tire of Bakker et al. 1987 (SAE 870421), zero camber.
BAKKER_1987 = TireCoefficients(
    a0=1.65, a1=-21.3, a2=1144.0, a3=49.6, a4=226.0, a5=0.069, a6=-0.006, a7=0.056, a8=0.486,
    b0=1.30, b1=-22.1, b2=1011.0, b3=1078.0, b4=1.82, b5=0.208, b6=0.0, b7=-0.354, b8=0.707,
)

_HALF_PI = 0.5 * math.pi


@njit(cache=True)
def mf_factors(c, n_kn, lateral):  # pragma: no cover - compiled
    """(C, D, B, E) of one curve at a load of ``n_kn`` kN (``c`` the 19 coefficients of :class:`TireCoefficients`)."""
    k = 9 if lateral else 0
    C = c[k]
    D = c[18] * (c[k + 1] * n_kn * n_kn + c[k + 2] * n_kn)
    if lateral:
        bcd = c[12] * math.sin(c[13] * math.atan(c[14] * n_kn))
    else:
        bcd = (c[3] * n_kn * n_kn + c[4] * n_kn) * math.exp(-c[5] * n_kn)
    E = c[k + 6] * n_kn * n_kn + c[k + 7] * n_kn + c[k + 8]
    B = bcd / (C * D) if D > 0.0 else 0.0
    return C, D, B, E


@njit(cache=True)
def mf_curve(x, C, D, B, E):  # pragma: no cover - compiled
    """``D sin(C atan(Bx − E(Bx − atan Bx)))`` (8.43)."""
    bx = B * x
    return D * math.sin(C * math.atan(bx - E * (bx - math.atan(bx))))


@njit(cache=True)
def mf_peak(C, B, E):  # pragma: no cover - compiled
    """Slip x > 0 of the curve's peak: ``Bx − E(Bx − atan Bx) = tan(π/(2C))`` by Newton's method."""
    target = math.tan(_HALF_PI / C)
    u = target  # u = Bx; the left side u − E(u − atan u) increases in u for E < 1
    for _ in range(50):
        g = u - E * (u - math.atan(u)) - target
        dg = 1.0 - E * (1.0 - 1.0 / (1.0 + u * u))
        step = g / dg
        u -= step
        if u <= 0.0:
            u = 1e-6
        if abs(step) < 1e-13 * (1.0 + abs(u)):
            break
    return u / B


@njit(cache=True)
def combined_forces(c, load, lam, alpha):  # pragma: no cover - compiled
    """Combined-slip forces (F_x, F_y) [N] at normal load [N], slip ratio and slip angle [rad] (8.98)–(8.103)."""
    if load <= 0.0:
        return 0.0, 0.0
    n_kn = load * 1e-3
    Cx, Dx, Bx, Ex = mf_factors(c, n_kn, False)
    Cy, Dy, By, Ey = mf_factors(c, n_kn, True)
    if Bx <= 0.0 or By <= 0.0:
        return 0.0, 0.0
    lam_max = mf_peak(Cx, Bx, Ex)  # in %
    alpha_max = mf_peak(Cy, By, Ey)  # in degrees
    ls = 100.0 * lam / lam_max
    as_ = math.degrees(alpha) / alpha_max
    sigma = math.sqrt(ls * ls + as_ * as_)
    if sigma < 1e-9:  # F0(s x_max)/s -> x_max B C D
        gx = lam_max * Bx * Cx * Dx
        gy = alpha_max * By * Cy * Dy
    else:
        gx = mf_curve(sigma * lam_max, Cx, Dx, Bx, Ex) / sigma
        gy = mf_curve(sigma * alpha_max, Cy, Dy, By, Ey) / sigma
    return ls * gx, as_ * gy


@njit(cache=True)
def slip_kernel(r_omega, v, v_min):  # pragma: no cover - compiled
    """``(r ω − v) / max(|r ω|, |v|, v_min)``."""
    return (r_omega - v) / max(abs(r_omega), abs(v), v_min)


def slip_ratio(wheel_surface_speed, ground_speed, v_min: float = 0.5) -> np.ndarray:
    """Longitudinal slip ``λ = (r ω − v) / max(|r ω|, |v|, v_min)`` (the report's (8.41), regularised).

    Parameters
    ----------
    wheel_surface_speed : array_like
        ``r ω`` [m/s].
    ground_speed : array_like
        Forward speed of the wheel centre over the road ``v`` [m/s].
    v_min : float, default 0.5
        Speed floor [m/s] of the denominator (the car at rest).

    Returns
    -------
    ndarray
        Slip ratio in [−1, 1]: positive when driving.

    Raises
    ------
    ParameterError
        For a ``v_min`` not finite and > 0.

    References
    ----------
    Douglas et al. 1996, §8.1.8 (8.41), §8.2 (8.92).

    Examples
    --------
    >>> slip_ratio([31.0, 29.0], 30.0).round(6).tolist()  # driving 1 − 30/31; braking (29 − 30)/30
    [0.032258, -0.033333]
    """
    v_min = validate.positive("slip_ratio: v_min", v_min)
    rw, v = np.broadcast_arrays(np.asarray(wheel_surface_speed, dtype=float), np.asarray(ground_speed, dtype=float))
    return (rw - v) / np.maximum(np.maximum(np.abs(rw), np.abs(v)), v_min)


def peak_slips(load, tire: TireCoefficients = BAKKER_1987) -> tuple[np.ndarray, np.ndarray]:
    """Slip ratio and slip angle of the pure-slip force peaks at each load.

    Parameters
    ----------
    load : array_like
        Normal load [N], > 0.
    tire : TireCoefficients, default BAKKER_1987
        The tire.

    Returns
    -------
    lam_max : ndarray
        Slip ratio of the longitudinal peak (a fraction, not %).
    alpha_max : ndarray
        Slip angle of the lateral peak [rad].

    Raises
    ------
    ParameterError
        For loads not finite and > 0.

    References
    ----------
    Douglas et al. 1996, §8.2 (8.98)–(8.99) (the normalising slips); Bakker et al. 1987.

    Examples
    --------
    >>> lam, alpha = peak_slips(4000.0)
    >>> round(float(lam), 3), round(float(np.degrees(alpha)), 2)
    (0.103, 9.35)
    """
    loads = _loads(load, "peak_slips")
    c = tire.as_array()
    lam = np.empty(loads.shape)
    alpha = np.empty(loads.shape)
    for k, n in np.ndenumerate(loads):
        Cx, Dx, Bx, Ex = mf_factors(c, n * 1e-3, False)
        Cy, Dy, By, Ey = mf_factors(c, n * 1e-3, True)
        lam[k] = mf_peak(Cx, Bx, Ex) / 100.0
        alpha[k] = math.radians(mf_peak(Cy, By, Ey))
    return lam, alpha


def tire_forces(load, slip_ratio, slip_angle, tire: TireCoefficients = BAKKER_1987) -> tuple[np.ndarray, np.ndarray]:
    """Longitudinal and lateral tire force under combined slip.

    Parameters
    ----------
    load : array_like
        Normal load [N] (a load ``<= 0``, a wheel off the ground, gives no force).
    slip_ratio : array_like
        Slip ratio ``λ`` (fraction; positive driving).
    slip_angle : array_like
        Slip angle ``α`` [rad] (positive: force to the left, ISO 8855).
    tire : TireCoefficients, default BAKKER_1987
        The tire.

    Returns
    -------
    F_x, F_y : ndarray
        Forces [N] along the wheel heading and the axle, broadcast shape of the inputs.

    Raises
    ------
    ParameterError
        For inputs that are not finite numbers.

    References
    ----------
    Douglas et al. 1996, §8.1.8 (8.42)–(8.45), §8.2 (8.98)–(8.103), Table 8.1; Bakker et al. 1987.

    Examples
    --------
    Pure slip at 4 kN: the lateral peak is about 0.92 × the load, the longitudinal about 1.06 ×:

    >>> lam, alpha = peak_slips(4000.0)
    >>> fx, fy = tire_forces(4000.0, [0.0, float(lam)], [float(alpha), 0.0])
    >>> np.round(fy / 4000, 3).tolist(), np.round(fx / 4000, 3).tolist()
    ([0.923, 0.0], [0.0, 1.059])
    """
    loads, lam, alpha = np.broadcast_arrays(*(validate.as_array(f"tire_forces: {name}", v) for name, v in
                                              (("load", load), ("slip_ratio", slip_ratio), ("slip_angle", slip_angle))))
    c = tire.as_array()
    fx = np.empty(loads.shape)
    fy = np.empty(loads.shape)
    for k in np.ndindex(loads.shape):
        fx[k], fy[k] = combined_forces(c, float(loads[k]), float(lam[k]), float(alpha[k]))
    return fx, fy


def _loads(load, owner: str) -> np.ndarray:
    loads = validate.as_array(f"{owner}: load", load)
    if not np.all(loads > 0):
        raise ParameterError(f"{owner}: load must be > 0 [N], got {load!r:.60}")
    return loads
