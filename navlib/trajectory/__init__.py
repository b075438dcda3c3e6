"""Reference trajectories whose IMU signals satisfy the ECEF kinematics exactly.

Contract (spec/api.md): ``sounding_rocket``, ``launcher_ascent``, ``stationary``,
``fit_flight_data`` and the :class:`Trajectory` type.
"""

from navlib.trajectory.base import Trajectory, build_trajectory, exact_imu

__all__ = ["Trajectory", "build_trajectory", "exact_imu"]
