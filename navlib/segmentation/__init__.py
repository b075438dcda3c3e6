"""Automatic flight-phase segmentation from a trajectory's specific force and angular rate.

A recorded flight is cut into phases whose excitation differs, since excitability is computed
per segment (docs/assumptions.md, excitability.md §3): rest, powered, turn, free fall, coast
and cruise from the kinematics, renamed in a vehicle's words (docs/assumptions.md V1-V2), or
the flight computer's logged states. Conditions, thresholds and vehicle rules:
docs/segmentation.md. The result is an editable table (:meth:`Segmentation.to_frame`);
:func:`segments_table` reads a user's edit back.
"""

from navlib.segmentation.edits import segments_table
from navlib.segmentation.features import flight_features
from navlib.segmentation.phases import (
    PHASES,
    SEGMENT_COLUMNS,
    SEGMENT_DEFAULTS,
    Segmentation,
    segment_flight,
)
from navlib.segmentation.recognition import RECOGNITION_DEFAULTS, recognise_vehicle
from navlib.vehicles import (
    MAV_TYPES,
    VEHICLE_PHASES,
    VEHICLES,
    check_vehicle,
    vehicle_from_log,
)

__all__ = [
    "MAV_TYPES",
    "PHASES",
    "RECOGNITION_DEFAULTS",
    "SEGMENT_COLUMNS",
    "SEGMENT_DEFAULTS",
    "VEHICLES",
    "VEHICLE_PHASES",
    "Segmentation",
    "check_vehicle",
    "flight_features",
    "recognise_vehicle",
    "segment_flight",
    "segments_table",
    "vehicle_from_log",
]

