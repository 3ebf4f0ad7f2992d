"""B747 model sets around trim from the JSBSim aircraft: LIP models, Tables 4.2–4.5 (Hallouzi 2008, Ch. 4).

Every local model is a numerical linearisation (:func:`fdikit.aircraft.linearize_aircraft`) of
JSBSim's B747 at the §4.3.1 point — 980 m, 92.6 m/s TAS, flaps 20 deg, 263 t — re-trimmed for its
fault, with the trim offsets of (4.1)–(4.2) carried as the constant term of an affine model::

    x_{k+1} = A_d x_k + B_d u_k + c_d,   y_k = C x_k     (A_d = I + T A, B_d = T B: App. B, M = 1)

and ``c_d = T (f° − A x° − B u°)`` (zero offset error at an exact trim; a locked surface that cannot
be trimmed leaves ``f° ≠ 0``, and the model drifts as the aircraft does). A lock-in-place (LIP)
model has the surface fixed at its lock position in the trim and its ``B`` column zero (§4.2).

States ``p q r V α β φ θ ψ h`` (Table 4.1, SI units here: rad, rad/s, m/s, m), inputs ``δ_a, δ_e,
δ_st, δ_r`` [rad] and the total thrust ``δ_T`` [N]; JSBSim's B747 has no spoilers (Table 4.1's
``δ_sp`` is absent) and fdikit adds its stabiliser (:mod:`fdikit.aircraft.definition`). The
measurements are the eight states other than β and φ (§4.4.1).

Faults JSBSim cannot represent as the thesis did, approximated:

* **hydraulic system #4 outage** (Table 4.2): which surfaces system 4 drives is not in the thesis;
  taken as one of the four elevator panels, the lower of the two rudders and one of the four
  aileron panels lost (their ``B`` columns scaled by 3/4, 1/2, 3/4) — the surfaces of a failed
  system trail, so they stop contributing to control;
* **engine separation** (both right engines, with weight loss, CG shift and wing damage, §4.3.2 and
  §6.5.4): engines 3 and 4 cut off and the mass reduced by 10 028 kg (the §6.5.4 figure) before the
  trim (asymmetric thrust trimmed with rudder, aileron and bank); the CG shift and the wing damage
  (lift loss, drag, moments) are not modelled;
* the α-sensor fault models scale the α row of ``C`` by the sensor's effectiveness (0 … 1).

Aileron limits are ±15 deg (the note on Table 4.5: model 7 is printed "−25 deg", but the aileron
range is [−15, 15] and the 61 nonlinear runs at 0.5 deg confirm a 30-deg span; Table 4.4's "41"
aileron models are 31 at 1 deg).

References
----------
Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.1–4.5, (4.1)–(4.2), App. B; §6.5.4 (the weight loss).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.errors import ParameterError

__all__ = [
    "MEASURED",
    "MODEL_SET_I",
    "MODEL_SET_II",
    "LIP_RANGES",
    "LocalModel",
    "b747_at_point",
    "local_model",
    "large_model_set",
    "model_set",
]

#: The measured states of §4.4.1 (all but β and φ).
MEASURED = ("roll_rate", "pitch_rate", "yaw_rate", "true_airspeed", "alpha", "pitch", "heading", "altitude")
#: Table 4.2 / 4.4 sweeps: surface → (lower, upper) lock positions [deg], 1-deg steps.
LIP_RANGES = {"rudder": (-25, 25), "elevator": (-23, 17), "aileron": (-15, 15)}
#: Table 4.3 (model set I, most influential first; model 8 nominal): (fault, size).
MODEL_SET_I = (("rudder", 25.0), ("rudder", -25.0), ("elevator", 17.0), ("elevator", -23.0),
               ("engine_separation", None), ("alpha_sensor", 0.0), ("hydraulic_4", None), ("nominal", None))
#: Table 4.5 (model set II, with the −15 deg aileron correction) plus the nominal model 8 (§4.4.2).
MODEL_SET_II = (("rudder", 25.0), ("rudder", -25.0), ("elevator", -23.0), ("aileron", 15.0),
                ("elevator", 17.0), ("elevator", -6.0), ("aileron", -15.0), ("nominal", None))
_HYDRAULIC_4 = {"elevator": 0.75, "rudder": 0.5, "aileron": 0.75}
_SEPARATION_MASS = 10_028.0


@dataclass(frozen=True)
class LocalModel:
    """One local model of a B747 model set.

    Attributes
    ----------
    name : str
        E.g. ``"rudder_lip_+25"``, ``"alpha_sensor_0.3"``, ``"nominal"``.
    fault : str
        ``"nominal"``, a surface (LIP), ``"alpha_sensor"``, ``"hydraulic_4"`` or ``"engine_separation"``.
    size : float or None
        Lock position [deg] or α-sensor effectiveness.
    linearization : AircraftLinearization
        The continuous model at the fault's trim, with its offsets.
    C : ndarray
        Measurement matrix over :data:`MEASURED` (the α row scaled for an α-sensor fault).

    Examples
    --------
    >>> ac, nominal = b747_at_point()
    >>> m = local_model(ac, "alpha_sensor", 0.5, nominal=nominal)
    >>> m.C[4, 4], m.name
    (np.float64(0.5), 'alpha_sensor_0.5')

    References
    ----------
    Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.2–4.5, (4.1)–(4.2).
    """

    name: str
    fault: str
    size: float | None
    linearization: object
    C: np.ndarray

    def discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The affine discrete model ``(A_d, [B_d c_d], C)`` (App. B, first order): the last input is 1.

        Parameters
        ----------
        dt : float
            Sample time [s].

        Returns
        -------
        Ad, Bd, C : ndarray
            ``Bd`` has one more column than the inputs: ``c_d``, driven by a constant input 1.
        """
        from fdikit.multimodel.model_set import first_order_discretize

        lin = self.linearization
        Ad, Bd = first_order_discretize(lin.model.A, np.column_stack([lin.model.B, lin.offset]), dt)
        return Ad, Bd, self.C

    def vector(self) -> np.ndarray:
        """``vec([A B; C 0])`` of the continuous model, for the OD design (Hallouzi §3.3.2).

        Returns
        -------
        ndarray
        """
        from fdikit.multimodel.model_set import vectorize

        m = self.linearization.model
        return vectorize(m.A, m.B, self.C)


def b747_at_point(dt: float = 0.01):
    """JSBSim's B747 trimmed at the §4.3.1 point (980 m, 92.6 m/s, flaps 20 deg, 263 t), and its nominal model.

    Parameters
    ----------
    dt : float, optional
        The simulation step [s] (default 0.01: the thesis's 100 Hz).

    Returns
    -------
    aircraft : JSBSimAircraft
        Left at the nominal trim.
    nominal : LocalModel

    Examples
    --------
    >>> ac, nominal = b747_at_point()
    >>> nominal.linearization.trim.converged
    True

    References
    ----------
    Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.2–4.5, (4.1)–(4.2).
    """
    from fdikit.aircraft import HALLOUZI_POINT, JSBSimAircraft, trim_aircraft

    ac = JSBSimAircraft("B747", dt=dt)
    trim = trim_aircraft(ac, HALLOUZI_POINT)
    model = _model(ac, trim, "nominal", "nominal", None)
    return ac, model


def _selector() -> np.ndarray:
    from fdikit.aircraft.plant import STATES

    return np.eye(10)[[STATES.index(s) for s in MEASURED]]


def _model(ac, trim, name, fault, size) -> LocalModel:
    from fdikit.aircraft import linearize_aircraft

    return LocalModel(name=name, fault=fault, size=size, linearization=linearize_aircraft(ac, trim), C=_selector())


def local_model(aircraft, fault: str, size: float | None = None, *, nominal: LocalModel | None = None,
                start=None) -> LocalModel:
    """One local model: a LIP at ``size`` deg, an α-sensor at effectiveness ``size``, or a named fault.

    Parameters
    ----------
    aircraft : JSBSimAircraft
        The B747 of :func:`b747_at_point` (its trim state changes; restore it afterwards if needed).
    fault : str
        ``"rudder"``, ``"elevator"``, ``"aileron"`` (LIP), ``"alpha_sensor"``, ``"hydraulic_4"``,
        ``"engine_separation"`` or ``"nominal"``.
    size : float, optional
        Lock position [deg] for a LIP; effectiveness in [0, 1] for the α sensor.
    nominal : LocalModel, optional
        The nominal model (needed for ``alpha_sensor``, ``hydraulic_4`` and ``nominal``).
    start : AircraftTrim, optional
        A nearby trim to start the LIP trim from.

    Returns
    -------
    LocalModel

    Raises
    ------
    ParameterError
        For an unknown fault, a missing size or nominal model, or a lock position outside the range.

    Examples
    --------
    >>> ac, nominal = b747_at_point()
    >>> m = local_model(ac, "rudder", 10.0)
    >>> m.name, bool(m.linearization.trim.converged)
    ('rudder_lip_+10', True)

    References
    ----------
    Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.2–4.5, (4.1)–(4.2).
    """
    from fdikit.aircraft import HALLOUZI_POINT, FlightCondition, trim_aircraft

    if fault in LIP_RANGES:
        if size is None or not LIP_RANGES[fault][0] <= size <= LIP_RANGES[fault][1]:
            raise ParameterError(f"a {fault} LIP needs a lock position in {LIP_RANGES[fault]} deg, got {size!r}.")
        trim = trim_aircraft(aircraft, HALLOUZI_POINT, {fault: np.radians(size)}, require=False, start=start)
        return _model(aircraft, trim, f"{fault}_lip_{size:+g}", fault, float(size))
    if fault in ("alpha_sensor", "hydraulic_4", "nominal") and nominal is None:
        raise ParameterError(f"the {fault} model is built from the nominal one: pass nominal=.")
    if fault == "nominal":
        return nominal
    if fault == "alpha_sensor":
        if size is None or not 0.0 <= size <= 1.0:
            raise ParameterError(f"the α-sensor effectiveness must be in [0, 1], got {size!r}.")
        C = nominal.C.copy()
        C[MEASURED.index("alpha")] *= size
        return LocalModel(f"alpha_sensor_{size:g}", fault, float(size), nominal.linearization, C)
    if fault == "hydraulic_4":
        from dataclasses import replace

        lin = nominal.linearization
        B = lin.model.B.copy()
        for surface, k in _HYDRAULIC_4.items():
            B[:, lin.model.controls.index(surface)] *= k
        return LocalModel("hydraulic_4", fault, None, replace(lin, model=lin.model.replace(Bu=B)), nominal.C)
    if fault == "engine_separation":
        snap = aircraft.snapshot()
        mass = aircraft.mass
        for engine in (3, 4):
            aircraft.set_engine_running(engine, False)
        cond = FlightCondition(HALLOUZI_POINT.altitude, HALLOUZI_POINT.airspeed, flaps=HALLOUZI_POINT.flaps,
                               mass=mass - _SEPARATION_MASS)
        trim = trim_aircraft(aircraft, cond, require=False)
        model = _model(aircraft, trim, "engine_separation", fault, None)
        aircraft.set_mass(mass)
        for engine in (3, 4):
            aircraft.set_engine_running(engine, True)
        aircraft.restore(snap)
        return model
    kinds = [*LIP_RANGES, "alpha_sensor", "hydraulic_4", "engine_separation", "nominal"]
    raise ParameterError(f"unknown fault {fault!r}; use one of {', '.join(kinds)}.")


def large_model_set(aircraft, nominal: LocalModel, which: str = "II", step: float = 1.0) -> list[LocalModel]:
    """The large sets ``M_ℓ^I`` (Table 4.2, 105 models) or ``M_ℓ^II`` (Table 4.4, 123 models).

    Parameters
    ----------
    aircraft : JSBSimAircraft
    nominal : LocalModel
    which : {"I", "II"}
    step : float, optional
        LIP sweep step [deg] (default 1, the thesis's); coarser for quick runs.

    Returns
    -------
    list of LocalModel
        Rudder and elevator LIP sweeps, then α-sensor effectiveness 0, 0.1, …, 1, hydraulic #4 and
        engine separation (I) or the aileron LIP sweep (II).

    Raises
    ------
    ParameterError
        For ``which`` other than "I" or "II".

    Examples
    --------
    >>> ac, nominal = b747_at_point()
    >>> len(large_model_set(ac, nominal, "II", step=10.0))   # rudder 6, elevator 5, aileron 4
    15

    References
    ----------
    Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.2–4.5, (4.1)–(4.2).
    """
    if which not in ("I", "II"):
        raise ParameterError(f"which must be 'I' (Table 4.2) or 'II' (Table 4.4), got {which!r}.")
    surfaces = ("rudder", "elevator") + (("aileron",) if which == "II" else ())
    out = []
    snap = aircraft.snapshot()
    for surface in surfaces:
        lo, hi = LIP_RANGES[surface]
        start = None
        for size in np.arange(lo, hi + step / 2, step):
            m = local_model(aircraft, surface, float(size), start=start)
            start = m.linearization.trim
            out.append(m)
    if which == "I":
        out += [local_model(aircraft, "alpha_sensor", round(k, 1), nominal=nominal) for k in np.linspace(0, 1, 11)]
        out += [local_model(aircraft, "hydraulic_4", nominal=nominal), local_model(aircraft, "engine_separation")]
    aircraft.restore(snap)
    return out


def model_set(aircraft, nominal: LocalModel, which: str = "II") -> list[LocalModel]:
    """Model set I (Table 4.3) or II (Table 4.5 plus the nominal model 8), in the thesis's order.

    Parameters
    ----------
    aircraft : JSBSimAircraft
    nominal : LocalModel
    which : {"I", "II"}

    Returns
    -------
    list of LocalModel
        Eight models; the last is the nominal one.

    Raises
    ------
    ParameterError
        For ``which`` other than "I" or "II".

    Examples
    --------
    >>> ac, nominal = b747_at_point()
    >>> [m.name for m in model_set(ac, nominal, "II")][:3]
    ['rudder_lip_+25', 'rudder_lip_-25', 'elevator_lip_-23']

    References
    ----------
    Hallouzi 2008, §4.2, §4.3.1–§4.3.4, Tables 4.2–4.5, (4.1)–(4.2).
    """
    if which not in ("I", "II"):
        raise ParameterError(f"which must be 'I' (Table 4.3) or 'II' (Table 4.5), got {which!r}.")
    snap = aircraft.snapshot()
    out = [local_model(aircraft, f, s, nominal=nominal) for f, s in (MODEL_SET_I if which == "I" else MODEL_SET_II)]
    aircraft.restore(snap)
    return out
