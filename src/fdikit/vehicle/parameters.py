"""Parameters of the nonlinear car: a front-drive mid-size sedan, calibrated to the PATH report.

The report gives no vehicle parameters (Douglas et al. 1996, Ch. 2 and Ch. 8 print none); its
Berkeley model is that of Peng 1992.  :data:`MID_SIZE_SEDAN` is a front-drive mid-size sedan of the
1990s with values in the ranges of the sources named per field below; they are fdikit's choices
within those ranges, not the measured data of one car.  These numbers were then calibrated to the
report's own runs and spectrum (:func:`fdikit.vehicle.calibration.calibrate` reproduces the first two):

* ``throttle_max_flow`` (the throttle body's capacity MAX) so that 22.555 % throttle (of the 90°
  butterfly) holds 27 m/s on a level road (§8.3.1);
* ``cg_to_front_axle`` (the weight split, hence the understeer) so that a 0.005 rad steer at
  24.87 m/s gives the 638.73 m radius of §2.2;
* springs and dampers (ride modes ≈ 1 Hz, damping ratio ≈ 0.3), ``manifold_volume`` and
  ``clutch_slip_damping`` chosen by hand so the body and engine modes of the Method-1 model are
  near Table 2.1's (−2.07 ± 6.54i, −1.44 ± 5.50i, −2.82 ± 5.60i; −26.46 ± 4.32i);
* ``brake_lag`` 0.8 s, ``throttle_lag`` 11 ms and ``steering_lag`` 12.5 ms: the actuator modes
  −1.25, −90.91 and −80 of the 22-state spectrum (§2.3).

Sign convention: ISO 8855 (x forward, y left, z up; positive roll lifts the left side, positive
pitch — the report's θ — is nose-down, Ch. 8 (8.1)).  Wheels are in PATH sensor order fl, fr, rl, rr.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from fdikit import validate
from fdikit.vehicle.engine import ENGINE_FIELDS
from fdikit.vehicle.tire import BAKKER_1987, TireCoefficients

__all__ = ["SedanParameters", "MID_SIZE_SEDAN", "GEAR_RATIOS", "INDEX"]

#: Gear ratios of a 4-speed automatic transaxle (1st…4th), fdikit's choice typical of the class.
GEAR_RATIOS = (2.92, 1.57, 1.00, 0.70)


@dataclass(frozen=True)
class SedanParameters:
    """Every number of the nonlinear car (SI units, angles in rad unless stated).

    Attributes
    ----------
    mass : float
        Vehicle mass [kg] (the report neglects the unsprung mass, §8.1).  Source class: NHTSA inertial
        database, mid-size sedans 1450–1650 kg (Heydinger et al. 1999).
    roll_inertia, pitch_inertia, yaw_inertia : float
        Principal moments of inertia about the CM [kg m²] (Heydinger et al. 1999 ranges; Garrott et al. 1988 rules).
    wheelbase, cg_to_front_axle, track : float
        Geometry [m]; ``cg_to_front_axle`` calibrated (see the module docstring).
    cg_height : float
        CM height above the road at rest [m] (Heydinger et al. 1999 range 0.50–0.58 m).
    spring_front, spring_rear : float
        Suspension rates per corner [N/m] (ride frequencies ≈ 1.2 / 1.3 Hz; Gillespie 1992 Ch. 5).
    spring_cubic : float
        Progressive term ``K'`` of the spring force ``F_0 − K(h − h_s) − K'(h − h_s)^5`` [N/m^5] (Ch. 8 (8.25), about
        the static length ``h_s`` with the static corner load ``F_0`` as preload).
    damper_front, damper_rear : float
        Low-speed damping per corner [N s/m] (damping ratio ≈ 0.3); ``damper_knee`` [m/s] and
        ``damper_blowoff`` (ratio of the high-speed to the low-speed slope) give the piecewise-linear damper (8.27).
    tire_stiffness, tire_radius : float
        Linear radial tire stiffness ``K_w`` [N/m] and unloaded radius [m] (195/65 R15 class; §2.1.1 (2.2)).
    wheel_inertia_front, wheel_inertia_rear : float
        Spin inertia per wheel with brake and half shaft [kg m²].
    rolling_resistance : float
        Coefficient f_r; the normal-force offset ``d = f_r r_w`` of (8.36).
    tire : TireCoefficients
        Magic-Formula tire (Bakker et al. 1987).
    drag_area, drag_coefficient, lift_coefficient, side_force_coefficient : float
        Frontal area [m²], C_D, C_L, side-force slope per unit sideslip of the air (Hucho 1998 ranges).
    pitch_moment_coefficient, yaw_moment_coefficient : float
        Aerodynamic moment coefficients (based on the wheelbase, (8.32), (8.88)).
    air_density : float
        [kg/m³].
    gear_ratios : tuple of float
        Transmission ratios; ``final_drive`` the axle ratio; ``driveline_efficiency`` η of (8.46).
    gear : int
        The gear (1-based) held in the report's runs (the top gear at highway speed).
    clutch_slip_damping : float
        Coupling ``T_c = c (ω_e − ζ ω_axle)`` [N m s/rad] between engine and transmission: a slipping lock-up
        clutch standing in for the torque converter of the Berkeley model (a choice; gives ω_e its own state).
    engine_inertia : float
        Engine and converter pump [kg m²].
    throttle_max_flow, manifold_volume, manifold_temperature, displacement, volumetric_efficiency,
    indicated_efficiency, fuel_heating_value, air_fuel_ratio, ambient_pressure : float
        The mean-value engine (:mod:`fdikit.vehicle.engine`): MAX [kg/s] (Cho & Hedrick 1989), V_m [m³],
        T_m [K], V_d [m³], η_v, η_i (calibrated), Q_LHV [J/kg], AFR, p_atm [Pa].
    throttle_lag, brake_lag, steering_lag : float
        First-order actuator time constants [s] (§2.3: modes −90.91, −1.25, −80).
    brake_front_share : float
        Brake torque share of the front axle ``k_b`` (8.35), (8.91).
    brake_smoothing : float
        Wheel speed [rad/s] below which the brake torque fades (tanh) so a stopped wheel does not turn back (§8.1.6).
    gravity : float
        [m/s²].
    small_angle : bool
        Small-angle roll and pitch (``sin a = a``, ``cos a = 1``, ``tan a = a`` for the angles relative to the road;
        yaw and the grade stay exact): the variant §8.3 compares with the full model.

    References
    ----------
    Douglas et al. 1996, Ch. 2 §2.1, Ch. 8 §8.1–8.2; Heydinger et al. 1999; Garrott et al. 1988; Gillespie 1992;
    Hucho 1998; Bakker et al. 1987; Cho & Hedrick 1989; Heywood 1988.

    Examples
    --------
    >>> MID_SIZE_SEDAN.mass, round(MID_SIZE_SEDAN.front_weight_fraction, 3)
    (1550.0, 0.544)
    >>> MID_SIZE_SEDAN.with_(mass=1600.0).mass
    1600.0
    """

    mass: float = 1550.0
    roll_inertia: float = 550.0
    pitch_inertia: float = 2400.0
    yaw_inertia: float = 2600.0
    wheelbase: float = 2.69
    cg_to_front_axle: float = 1.226594
    track: float = 1.56
    cg_height: float = 0.55
    spring_front: float = 19000.0
    spring_rear: float = 14000.0
    spring_cubic: float = 2.0e8
    damper_front: float = 1800.0
    damper_rear: float = 1250.0
    damper_knee: float = 0.13
    damper_blowoff: float = 0.5
    tire_stiffness: float = 200000.0
    tire_radius: float = 0.315
    wheel_inertia_front: float = 1.1
    wheel_inertia_rear: float = 0.9
    rolling_resistance: float = 0.012
    drag_area: float = 2.1
    drag_coefficient: float = 0.33
    lift_coefficient: float = 0.10
    side_force_coefficient: float = 1.5
    pitch_moment_coefficient: float = 0.05
    yaw_moment_coefficient: float = 0.10
    air_density: float = 1.20
    final_drive: float = 3.05
    driveline_efficiency: float = 0.90
    gear: int = 4
    clutch_slip_damping: float = 6.5
    engine_inertia: float = 0.20
    throttle_max_flow: float = 0.319236
    manifold_volume: float = 1.85e-3
    manifold_temperature: float = 300.0
    displacement: float = 3.0e-3
    volumetric_efficiency: float = 0.80
    indicated_efficiency: float = 0.36
    fuel_heating_value: float = 44.0e6
    air_fuel_ratio: float = 14.7
    ambient_pressure: float = 101325.0
    throttle_lag: float = 0.011
    brake_lag: float = 0.8
    steering_lag: float = 0.0125
    brake_front_share: float = 0.7
    brake_smoothing: float = 0.5
    gravity: float = 9.81
    small_angle: bool = False
    gear_ratios: tuple = GEAR_RATIOS
    tire: TireCoefficients = field(default=BAKKER_1987)

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name in ("tire", "gear_ratios", "gear", "small_angle"):
                continue
            v = validate.number(f"SedanParameters.{f.name}", getattr(self, f.name))
            if f.name not in ("lift_coefficient", "pitch_moment_coefficient", "yaw_moment_coefficient") and v <= 0:
                validate.positive(f"SedanParameters.{f.name}", v)
            object.__setattr__(self, f.name, v)
        if not isinstance(self.small_angle, bool):
            validate.instance("SedanParameters.small_angle", self.small_angle, bool)
        validate.instance("SedanParameters.tire", self.tire, TireCoefficients)
        ratios = tuple(validate.positive(f"SedanParameters.gear_ratios[{k}]", r)
                       for k, r in enumerate(self.gear_ratios))
        object.__setattr__(self, "gear_ratios", ratios)
        validate.integer("SedanParameters.gear", self.gear, minimum=1)
        if self.gear > len(ratios):
            validate.in_range("SedanParameters.gear", self.gear, 1, len(ratios))
        validate.in_range("SedanParameters.cg_to_front_axle", self.cg_to_front_axle, 0.0, self.wheelbase,
                          closed="neither")
        validate.in_range("SedanParameters.brake_front_share", self.brake_front_share, 0.0, 1.0)
        validate.in_range("SedanParameters.damper_blowoff", self.damper_blowoff, 0.0, 10.0, closed="right")

    # ------------------------------------------------------------------------------------------------ derived
    @property
    def front_weight_fraction(self) -> float:
        """Static share of the weight on the front axle, ``b / L``."""
        return (self.wheelbase - self.cg_to_front_axle) / self.wheelbase

    def corner_loads(self) -> np.ndarray:
        """Static normal loads fl, fr, rl, rr [N] on a level road."""
        w = self.mass * self.gravity
        f = self.front_weight_fraction
        return np.array([f, f, 1 - f, 1 - f]) * w / 2

    def corner_positions(self) -> np.ndarray:
        """(4, 2) longitudinal and lateral positions of the wheel centres from the CM [m] (x forward, y left)."""
        a, b, t = self.cg_to_front_axle, self.wheelbase - self.cg_to_front_axle, self.track / 2
        return np.array([[a, t], [a, -t], [-b, t], [-b, -t]])

    def static_lengths(self) -> np.ndarray:
        """Suspension lengths ``h_s`` per corner [m] (wheel centre to CM along ``c_z``) at rest on a level road.

        The springs are preloaded with the static corner loads at these lengths, so the CM rests at ``cg_height``.
        """
        loaded_radius = self.tire_radius - self.corner_loads() / self.tire_stiffness
        return self.cg_height - loaded_radius

    def gear_ratio(self, gear: int | None = None) -> float:
        """Overall engine-to-wheel ratio ζ (gearbox × final drive) in ``gear`` (default the held gear)."""
        g = self.gear if gear is None else validate.integer("gear", gear, minimum=1)
        if g > len(self.gear_ratios):
            validate.in_range("gear", g, 1, len(self.gear_ratios))
        return self.gear_ratios[g - 1] * self.final_drive

    def with_(self, **changes) -> SedanParameters:
        """A copy with some fields changed (checked like a new instance)."""
        return replace(self, **changes)

    def engine_array(self) -> np.ndarray:
        """The engine numbers in :data:`~fdikit.vehicle.engine.ENGINE_FIELDS` order."""
        return np.array([getattr(self, n) for n in ENGINE_FIELDS], dtype=float)

    def as_array(self, gear: int | None = None) -> np.ndarray:
        """All numbers in :data:`INDEX` order (the layout the compiled dynamics read)."""
        p = np.zeros(INDEX["_size"])
        for name in _SCALARS:
            p[INDEX[name]] = getattr(self, name)
        p[INDEX["gear_ratio"]] = self.gear_ratio(gear)
        p[INDEX["small_angle"]] = 1.0 if self.small_angle else 0.0
        h_s, load = self.static_lengths(), self.corner_loads()
        for j, c in enumerate(_CORNERS):
            p[INDEX[f"static_length_{c}"]] = h_s[j]
            p[INDEX[f"preload_{c}"]] = load[j]
        pos = self.corner_positions()
        p[INDEX["corner_x"]:INDEX["corner_x"] + 4] = pos[:, 0]
        p[INDEX["corner_y"]:INDEX["corner_y"] + 4] = pos[:, 1]
        p[INDEX["tire"]:INDEX["tire"] + 19] = self.tire.as_array()
        p[INDEX["engine"]:INDEX["engine"] + len(ENGINE_FIELDS)] = self.engine_array()
        return p


_CORNERS = ("fl", "fr", "rl", "rr")
_SCALARS = tuple(f.name for f in fields(SedanParameters)
                 if f.name not in ("tire", "gear_ratios", "gear", "small_angle"))


def _index() -> dict[str, int]:
    names = (list(_SCALARS) + ["gear_ratio", "small_angle"] + [f"static_length_{c}" for c in _CORNERS]
             + [f"preload_{c}" for c in _CORNERS])
    index = {n: k for k, n in enumerate(names)}
    k = len(names)
    for block, size in (("corner_x", 4), ("corner_y", 4), ("tire", 19), ("engine", len(ENGINE_FIELDS))):
        index[block] = k
        k += size
    index["_size"] = k
    return index


#: Position of each number in :meth:`SedanParameters.as_array` (blocks: ``corner_x``, ``corner_y``, ``tire``,
#: ``engine`` give their first entry; ``_size`` the length).
INDEX: dict[str, int] = _index()

#: The calibrated mid-size sedan (see the module docstring for the calibration).
MID_SIZE_SEDAN = SedanParameters()
