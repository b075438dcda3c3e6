"""Reference trajectories whose IMU signals satisfy the ECEF kinematics exactly.

Contract (docs/library.md): ``sounding_rocket``, ``launcher_ascent``, ``stationary``,
``fit_flight_data``, ``from_mission`` and the :class:`Trajectory` type.
"""

from navlib.trajectory.base import Trajectory, build_trajectory, exact_imu
from navlib.trajectory.fit import fit_flight_data
from navlib.trajectory.launcher import launcher_ascent
from navlib.trajectory.mission import from_mission
from navlib.trajectory.rocket import sounding_rocket
from navlib.trajectory.stationary import stationary

__all__ = [
    "Trajectory", "build_trajectory", "exact_imu", "fit_flight_data", "from_mission",
    "launcher_ascent", "sounding_rocket", "stationary",
]
