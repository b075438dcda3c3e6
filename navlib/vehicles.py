"""Vehicle classes, their phase words and the vehicle a log names (``docs/assumptions.md`` V1-V2).

:data:`VEHICLES` and :data:`VEHICLE_PHASES` name what :func:`navlib.segmentation.segment_flight`
calls the phases of each class; :func:`vehicle_from_log` reads the class from a reader's
``attrs`` (MAVLink ``MAV_TYPE``, the firmware name).
"""

from collections.abc import Mapping

import numpy as np

from navlib.errors import NavlibInputError

__all__ = ["MAV_TYPES", "VEHICLES", "VEHICLE_PHASES", "check_vehicle", "vehicle_from_log"]

VEHICLES = ("rocket", "multicopter", "fixed-wing", "ground")
"""Vehicle classes whose phases :func:`navlib.segmentation.segment_flight` names."""
VEHICLE_PHASES = {
    "rocket": ("pad", "boost", "coast", "free_fall", "descent", "drogue", "main", "landed"),
    "multicopter": ("rest", "hover", "climb", "descent", "turn", "cruise"),
    "fixed-wing": ("rest", "climb", "descent", "turn", "cruise"),
    "ground": ("rest", "turn", "cruise"),
}
"""The phase words of each vehicle class: for the others in priority order (the last is
the fallback); a rocket's in flight order (``drogue`` and ``main`` come from a flight
computer's logged states, :mod:`navlib.segmentation.logged`; detected descent is
``descent``)."""
MAV_TYPES = {1: "fixed-wing", 2: "multicopter", 3: "multicopter", 4: "multicopter",
             9: "rocket", 10: "ground", 11: "ground", 13: "multicopter", 14: "multicopter",
             15: "multicopter", 19: "multicopter", 20: "multicopter", 21: "multicopter",
             22: "multicopter", 23: "multicopter", 24: "fixed-wing", 29: "multicopter"}
"""MAVLink ``MAV_TYPE`` -> vehicle class (fixed wing; quad-, coaxial, helicopter, hexa-,
octo-, tricopter, dodecarotor; rocket; ground rover, surface boat; VTOLs, which take off as
rotorcraft; parafoil as fixed-wing)."""
_LOG_VEHICLES = (("arducopter", "multicopter"), ("copter", "multicopter"),
                 ("heli", "multicopter"), ("arduplane", "fixed-wing"), ("plane", "fixed-wing"),
                 ("rover", "ground"), ("ardurover", "ground"))


def check_vehicle(vehicle) -> str:
    """``vehicle`` if it is one of :data:`VEHICLES` (case and ``_``/``-`` forgiven)."""
    text = str(vehicle).strip().lower().replace("_", "-") if isinstance(vehicle, str) else None
    if text == "fixedwing":
        text = "fixed-wing"
    if text not in VEHICLES:
        raise NavlibInputError(f"vehicle: expected one of {list(VEHICLES)}, got {vehicle!r}")
    return text


def vehicle_from_log(attrs: Mapping) -> tuple[str | None, str]:
    """The vehicle class a log says it is, from a reader's ``attrs``, and why.

    ``attrs["vehicle"]`` when a reader sets one of :data:`VEHICLES`; ``rocket`` for an
    Altus Metrum AltOS export (``attrs["flight_states"]``: only rocket flight computers
    write one); the ArduPilot firmware banner (``attrs["hardware"]``, e.g. ``ArduCopter
    V4.5.0`` -> multicopter, ``ArduPlane`` -> fixed-wing, ``Rover`` -> ground). ``(None,
    "")`` when the log does not say (then :func:`recognise_vehicle` reads the kinematics).
    """
    attrs = attrs if isinstance(attrs, Mapping) else {}
    given = attrs.get("vehicle")
    if isinstance(given, str) and given.strip().lower() in VEHICLES:
        return given.strip().lower(), "the log names it"
    if attrs.get("flight_states") is not None:
        return "rocket", "an Altus Metrum AltOS flight-computer log"
    mav_type = attrs.get("mav_type")
    if isinstance(mav_type, int | np.integer) and int(mav_type) in MAV_TYPES:
        return MAV_TYPES[int(mav_type)], f"the log's MAV_TYPE {int(mav_type)}"
    banner = str(attrs.get("hardware") or "").lower()
    if str(attrs.get("autopilot", "")).lower() == "ardupilot" and banner:
        for word, vehicle in _LOG_VEHICLES:
            if word in banner:
                return vehicle, f"the ArduPilot firmware banner {attrs['hardware']!r}"
    return None, ""
