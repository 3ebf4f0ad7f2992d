"""A JSBSim aircraft prepared for fault injection: surface positions written from Python, where JSBSim reads them.

JSBSim runs the aircraft's flight-control system (FCS) inside every step, before the aerodynamics,
and the FCS writes the surface positions (``fcs/elevator-pos-rad`` …) from the pilot commands. A
value written to a position from Python is therefore overwritten. :func:`prepare_aircraft` copies
the aircraft's definition into a private root directory and appends, at the end of its
``<flight_control>`` block (the last FCS block JSBSim loads, so the last to run), one ``switch`` per
surface that replaces the FCS's position by ``fdikit/<surface>-pos-rad`` when
``fdikit/<surface>-override`` is 1. With the override on, the surface sits exactly where the Python
actuator model (:mod:`fdikit.aircraft.actuators`) puts it — a locked, runaway or floating surface
included — and the aerodynamics, which run after the FCS, use that position. The override also
writes the surface's normalised position (``…-pos-norm``) with the aircraft's own scaling, so models
whose aerodynamics read the normalised value see the same deflection.

JSBSim's B747 has no stabiliser (its pitch trim adds to the elevator); fdikit adds one — the
elevator's lift and pitching-moment terms again, driven by ``fdikit/stabilizer-pos-rad`` and scaled
by :data:`STABILIZER_GAIN` — so that the App. A stabiliser (−12…3 deg at 0.5 deg/s) exists and a
locked elevator can be trimmed with it, as in Hallouzi §6.5.2. The landing gear's position is
overridden the same way (it is where the ``gear`` command puts it, without transit), so that trim and
linearisation see no gear moving. This is an approximation (the
stabiliser's effectiveness is not in the JSBSim data).

Written by hand because JSBSim has no hook for external surface positions; the XML is read and
written with :mod:`xml.etree.ElementTree`.

References
----------
Hallouzi 2008, §4.2 (lock-in-place faults enter at the surface, independent of the command).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from fdikit.errors import DataError, ParameterError

__all__ = ["STABILIZER_GAIN", "SURFACES", "AircraftDefinition", "jsbsim_aircraft", "prepare_aircraft"]

#: The managed surfaces: fdikit name → JSBSim position-property stem (the right aileron mirrors the left).
SURFACES: dict[str, str] = {
    "elevator": "elevator",
    "aileron": "left-aileron",
    "rudder": "rudder",
    "flap": "flap",
}


@dataclass(frozen=True)
class AircraftDefinition:
    """A JSBSim aircraft copied into a private root with the surface override installed.

    Attributes
    ----------
    name : str
        The JSBSim aircraft name (a folder of JSBSim's ``aircraft`` directory).
    root : str
        The private root directory to pass to ``jsbsim.FGFDMExec``.
    ranges : dict
        Surface name → ``(min, max)`` position in rad (flaps: deg) of the aircraft's own FCS scaling,
        used for the normalised position; ``None`` where the FCS writes no normalised position.
    surfaces : tuple of str
        The surfaces the aircraft has (of ``elevator``, ``aileron``, ``rudder``, ``flap``; the B747 also
        ``stabilizer``).
    engines : int
        The number of engines.
    gear : bool
        Whether the landing gear's position is overridden (``gear/gear-pos-norm`` follows the command).
    payload : int
        Index of the point mass fdikit adds at the empty-weight CG (``inertia/pointmass-weight-lbs[i]``).

    Examples
    --------
    >>> d = prepare_aircraft("737")
    >>> d.surfaces, d.engines, d.gear
    (('elevator', 'aileron', 'rudder'), 2, True)
    """

    name: str
    root: str
    ranges: dict
    surfaces: tuple
    engines: int
    gear: bool
    payload: int


def jsbsim_aircraft() -> list[str]:
    """The aircraft shipped with the installed JSBSim.

    Returns
    -------
    list of str
        Aircraft names accepted by :func:`prepare_aircraft`.

    Examples
    --------
    >>> "B747" in jsbsim_aircraft()
    True
    """
    import jsbsim

    folder = os.path.join(jsbsim.get_default_root_dir(), "aircraft")
    return sorted(n for n in os.listdir(folder) if os.path.isfile(os.path.join(folder, n, f"{n}.xml")))


def _position_props(stem: str, unit: str) -> list[str]:
    return [f"fcs/{stem}-pos-{unit}"] + ([f"fcs/right-aileron-pos-{unit}"] if stem == "left-aileron" else [])


def _scale_range(fcs: ET.Element, prop: str) -> tuple[float, float] | None:
    """The ``<range>`` (times ``<gain>``) of the ``aerosurface_scale`` whose output is ``prop``."""
    for comp in fcs.iter("aerosurface_scale"):
        out = comp.find("output")
        if out is not None and out.text and out.text.strip() == prop:
            rng = comp.find("range")
            if rng is not None and rng.find("min") is not None and rng.find("max") is not None:
                gain = float(comp.find("gain").text) if comp.find("gain") is not None else 1.0
                return gain * float(rng.find("min").text), gain * float(rng.find("max").text)
    return None


def _switch(channel: ET.Element, prop: str, value: str, flag: str) -> None:
    sw = ET.SubElement(channel, "switch", name=f"fdikit {prop.split('/')[-1]}")
    ET.SubElement(sw, "default", value=prop)
    test = ET.SubElement(sw, "test", value=value)
    test.text = f"{flag} == 1"
    ET.SubElement(sw, "output").text = prop


def _fcn(channel: ET.Element, name: str, expr: ET.Element, out: str) -> None:
    fc = ET.SubElement(channel, "fcs_function", name=name)
    fn = ET.SubElement(fc, "function")
    fn.append(expr)
    ET.SubElement(fc, "output").text = out


def _normaliser(lo: float, hi: float, source: str) -> ET.Element:
    """``source / hi`` above zero, ``source / |lo|`` below (JSBSim's zero-centred aerosurface scaling)."""
    expr = ET.Element("ifthen")
    lt = ET.SubElement(expr, "lt")
    ET.SubElement(lt, "property").text = source
    ET.SubElement(lt, "value").text = "0"
    for bound in (abs(lo), hi):
        q = ET.SubElement(expr, "quotient")
        ET.SubElement(q, "property").text = source
        ET.SubElement(q, "value").text = repr(bound if bound > 0 else 1.0)
    return expr


def prepare_aircraft(name: str, folder: str | None = None) -> AircraftDefinition:
    """Copy a JSBSim aircraft into a private root and install the surface override.

    Parameters
    ----------
    name : str
        A JSBSim aircraft (see :func:`jsbsim_aircraft`), e.g. ``"B747"``, ``"737"``, ``"c172p"``.
    folder : str, optional
        Where to build the root (a new temporary directory when omitted). Engines and systems are
        linked from JSBSim's own root, so the copy is small.

    Returns
    -------
    AircraftDefinition

    Raises
    ------
    ParameterError
        If JSBSim ships no aircraft of that name.
    DataError
        If the definition has no ``<flight_control>`` block to extend.

    Examples
    --------
    >>> d = prepare_aircraft("B747")
    >>> d.surfaces, d.engines
    (('elevator', 'aileron', 'rudder', 'flap', 'stabilizer'), 4)
    """
    import jsbsim

    known = jsbsim_aircraft()
    if name not in known:
        raise ParameterError(f"JSBSim ships no aircraft {name!r}; choose one of {', '.join(known)}.")
    base = jsbsim.get_default_root_dir()
    root = folder or tempfile.mkdtemp(prefix=f"fdikit-jsbsim-{name}-")
    for sub in ("engine", "systems"):
        link = os.path.join(root, sub)
        if not os.path.exists(link):
            os.symlink(os.path.join(base, sub), link)
    target = os.path.join(root, "aircraft", name)
    if not os.path.isdir(target):
        shutil.copytree(os.path.join(base, "aircraft", name), target)
    path = os.path.join(target, f"{name}.xml")
    tree = ET.parse(os.path.join(base, "aircraft", name, f"{name}.xml"))
    top = tree.getroot()
    fcs = top.find("flight_control")
    if fcs is None or fcs.get("file"):
        raise DataError(f"the JSBSim aircraft {name!r} has no inline <flight_control> block; "
                        "fdikit injects surface faults there and cannot use this aircraft.")
    for io in top.findall("output") + top.findall("input"):  # data-logging files and sockets of the model
        top.remove(io)
    _add_payload(top)
    outputs = {o.text.strip() for o in top.iter("output") if o.text}
    channel = ET.SubElement(fcs, "channel", name="fdikit surface override")
    ranges, surfaces = {}, []
    for surface, stem in SURFACES.items():
        unit = "deg" if surface == "flap" else "rad"
        props = [p for p in _position_props(stem, unit) if p in outputs]
        if not props:
            continue
        surfaces.append(surface)
        flag, value = f"fdikit/{surface}-override", f"fdikit/{surface}-pos-{unit}"
        for prop_name in (flag, value):
            ET.SubElement(fcs, "property", value="0").text = prop_name
        for prop in props:
            mirrored = "right-aileron" in prop
            source = value
            if mirrored:
                source = f"fdikit/{surface}-mirror-{unit}"
                neg = ET.Element("product")
                ET.SubElement(neg, "value").text = "-1"
                ET.SubElement(neg, "property").text = value
                _fcn(channel, f"fdikit {surface} mirror", neg, source)
            _switch(channel, prop, source, flag)
            norm = prop.replace(f"-pos-{unit}", "-pos-norm")
            rng = _scale_range(fcs, prop)
            if norm in outputs and rng is not None:
                ranges.setdefault(surface, rng)
                nsource = f"fdikit/{norm.split('/')[-1]}"
                _fcn(channel, f"fdikit {norm.split('/')[-1]}", _normaliser(*rng, source), nsource)
                _switch(channel, norm, nsource, flag)
        ranges.setdefault(surface, None)
    if "gear/gear-pos-norm" in outputs:  # the gear sits where the command puts it (no transit)
        for prop_name in ("fdikit/gear-override", "fdikit/gear-pos-norm"):
            ET.SubElement(fcs, "property", value="0").text = prop_name
        _switch(channel, "gear/gear-pos-norm", "fdikit/gear-pos-norm", "fdikit/gear-override")
    if name == "B747":
        _add_stabilizer(top, fcs)
        surfaces.append("stabilizer")
        ranges["stabilizer"] = None
    _atomic_xml(tree, path)
    engines = len(top.findall("propulsion/engine"))
    payload = len(top.findall("mass_balance/pointmass")) - 1
    return AircraftDefinition(name=name, root=root, ranges=ranges, surfaces=tuple(surfaces), engines=engines,
                              gear="gear/gear-pos-norm" in outputs, payload=payload)


#: Stabiliser over elevator effectiveness of the B747's horizontal tail, 1/τ with τ ≈ 0.5 the elevator
#: effectiveness of a ~30 % chord elevator (the whole tail moves with the stabiliser).
STABILIZER_GAIN = 2.0


def _add_stabilizer(top: ET.Element, fcs: ET.Element) -> None:
    """Give JSBSim's B747 (no stabiliser: its pitch trim moves the elevator) a trimmable stabiliser.

    The elevator's lift and pitching-moment functions are copied with ``fdikit/stabilizer-pos-rad`` for
    the elevator position and :data:`STABILIZER_GAIN` as a factor.
    """
    import copy

    for prop_name in ("fdikit/stabilizer-override", "fdikit/stabilizer-pos-rad"):
        ET.SubElement(fcs, "property", value="0").text = prop_name
    for axis in top.iter("axis"):
        for fn in list(axis.findall("function")):
            uses = [p for p in fn.iter("property") if p.text and p.text.strip() == "fcs/elevator-pos-rad"]
            if not uses or axis.get("name") not in ("LIFT", "PITCH"):
                continue
            twin = copy.deepcopy(fn)
            twin.set("name", fn.get("name") + "-stabilizer")
            for p in twin.iter("property"):
                if p.text and p.text.strip() == "fcs/elevator-pos-rad":
                    p.text = "fdikit/stabilizer-pos-rad"
            ET.SubElement(twin.find("product"), "value").text = repr(STABILIZER_GAIN)
            axis.append(twin)


def _add_payload(top: ET.Element) -> None:
    """A weightless point mass at the empty-weight CG, for :meth:`JSBSimAircraft.set_mass`."""
    mb = top.find("mass_balance")
    cg = mb.find("location[@name='CG']")
    pm = ET.SubElement(mb, "pointmass", name="fdikit payload")
    ET.SubElement(pm, "weight", unit="LBS").text = "0"
    loc = ET.SubElement(pm, "location", unit=cg.get("unit", "IN"))
    for axis in ("x", "y", "z"):
        ET.SubElement(loc, axis).text = cg.find(axis).text


def _atomic_xml(tree: ET.ElementTree, path: str) -> None:
    from fdikit.atomic import write_text

    write_text(path, ET.tostring(tree.getroot(), encoding="unicode"))
