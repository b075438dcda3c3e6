"""Automatic flight-phase segmentation from a trajectory's specific force and angular rate.

A recorded flight is cut into phases whose excitation differs (docs/assumptions.md, excitability.md
§3, §6: excitability is computed per segment; the paper's segments of the sounding rocket are the
pad [0, 19] s, the powered flight and spin [19, 60] s and the free fall [60, 86] s, where
``|f| < 0.5 m/s^2``). The phases are read from the kinematics of a (fitted)
:class:`~navlib.trajectory.Trajectory`, in ECEF, with ``f^e = C_b_e f^b``,
``omega_eb^e = C_b_e (omega_ib^b - C_e^b Omega)`` and the kinematic acceleration
``a^e = dV/dt = f^e + gamma(P) - 2 Omega x V``:

==========  ===============================================================================
phase       condition (checked in this order; the first that holds wins)
==========  ===============================================================================
rest        ``|V| < rest_speed_m_s``, ``|omega_eb| < rest_rate_deg_s`` and
            ``|a^e| < rest_accel_m_s2``: the vehicle stands (or hovers) still
powered     tangential specific force ``f_t = f^e . u > powered_accel_m_s2``: a thrust (or
            traction) pushes the vehicle forward along its path ``u``
turn        ``max(omega_perp, omega_path) > turn_rate_deg_s``: the body rotates about axes
            other than its *roll axis*, the body axis closest to the path (a rocket's spin
            or a car's roll is excluded; ``omega_perp`` drops that body-axis component of
            ``omega_eb^b``, so a spin axis a degree off the path does not count as a
            turn), or the velocity direction turns (``omega_path = |V x a| / |V|^2``, counted only
            above ``turn_speed_m_s``: at lower speed it is dominated by fit noise)
free_fall   ``|f| < free_fall_m_s2`` (and not powered): no force acts, ballistic flight
            above the atmosphere (the paper's "near free flight", ``|f| < 0.5 m/s^2``)
coast       lateral specific force ``|f^e - f_t u| < coast_lateral_m_s2`` (and not powered):
            nothing but drag along the path acts (a rocket after burnout in the air)
cruise      anything else: motion with the weight supported (level flight, driving)
==========  ===============================================================================

The path direction ``u`` is ``V/|V|`` above ``direction_speed_m_s``; below it ``u`` is the
direction of ``a^e`` when ``|a^e| > rest_accel_m_s2`` (a lift-off accelerates along its
rail from zero speed) and undefined otherwise (then ``f_t = 0``, the lateral force is
``|f|``, there is no roll axis and ``omega_perp = |omega_eb|``).

A vehicle descending at constant speed under a force opposite to its velocity (a drone
landing, a parachute) satisfies the coast condition: from ``f`` alone it cannot be told
from a body slowed by drag. Braking (``f_t < 0`` with the weight supported) shows as
cruise.

Against chatter the features are averaged over windows of ``resolution_s``, a phase is
kept until a phase earlier in the table holds or its own condition fails with every
threshold relaxed by the factor ``hysteresis``
(``rest``: limits times ``1 + h``; ``powered``, ``turn``: thresholds times ``1 - h``;
``free_fall``, ``coast``: limits times ``1 + h``), and runs shorter than ``min_duration_s`` are
merged into a neighbour (the longer one, or one of the same family: a short free fall next
to a coast joins it).

Vehicles (``docs/assumptions.md`` V1-V2). The table above is the *kinematic* labelling
(``vehicle=None``). Given a vehicle class of :data:`VEHICLES` (or one recognised by
:func:`recognise_vehicle`), the phases take that vehicle's words, :data:`VEHICLE_PHASES`:

* ``rocket``: the kinematic labels, then the flight's order, in rocketry words. The launch
  is the start of the powered run that lifts the vehicle ``hover_height_m`` above its first
  position (or the moment it gets there, unpowered); every window before it is ``pad`` (a
  rocket on its pad stands, whatever the fit's noise suggests); from the launch to the
  apogee (the highest point) ``powered`` is ``boost`` (one segment per burn), ``free_fall``
  stays and anything else is ``coast``; after the apogee every window is ``descent`` except
  kinematic ``rest`` (``landed``). A record that never rises that far is ``pad``
  throughout, or ``descent`` (``landed`` at rest) when it ends ``hover_height_m`` lower than
  it starts (recorded from mid-descent). When the log carries the flight computer's own
  states (``flight_states``: AltOS's ``boost``, ``fast``, ``coast``, ``drogue``, ``main``,
  ``landed``), they are the segments (:mod:`~navlib.segmentation.logged`), the detected
  ones are kept beside them and :attr:`Segmentation.events` lists the ignition, burnout,
  apogee, main deployment and landing, logged and detected side by side.
* ``multicopter``, ``fixed-wing``, ``ground``: with ``v_up`` the vertical speed (up of the
  first position), ``v_h`` the horizontal speed and ``height`` the height above the
  flight's lowest point, in priority order ``rest`` (kinematic rest; a multicopter also
  below ``hover_height_m``), ``hover`` (multicopter only: ``height >= hover_height_m``,
  ``v_h < hover_speed_m_s``, ``|v_up| < climb_rate_m_s``), ``climb`` (``v_up >
  climb_rate_m_s``, or below ``hover_speed_m_s`` horizontally an upward acceleration over
  ``rest_accel_m_s2`` while rising: a vertical take-off), ``descent`` (the same downwards;
  neither for ``ground``),
  ``turn`` (the kinematic turn) and ``cruise``. No rocket word (powered, coast, free fall)
  is ever given to these vehicles.

The result is an editable table (:meth:`Segmentation.to_frame`: ``phase, t_start, t_end``);
:func:`segments_table` turns a user's edit (a DataFrame, a list of boundaries or of
``(t_start, t_end)`` / ``(phase, t_start, t_end)`` entries) back into that table.

Modules: :mod:`~navlib.segmentation.features` (per-sample kinematics and their window
means), :mod:`~navlib.segmentation.phases` (the labelling),
:mod:`~navlib.segmentation.logged` (a flight computer's logged states and the events),
:mod:`~navlib.vehicles` and :mod:`~navlib.segmentation.recognition` (vehicle
classes) and :mod:`~navlib.segmentation.edits` (a user's segments); the public names are
re-exported here.
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

