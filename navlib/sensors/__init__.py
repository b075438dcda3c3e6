"""Sensor specifications (TOML presets in ``data/sensors/``) and IMU / GNSS error simulation.

Measurement model (docs/assumptions.md A1, A7), per triad, body axes::

    f_meas(t) = (I + diag(s_a(t)) + M_a) f(t) + b_a(t) + n_a(t)
    w_meas(t) = (I + diag(s_g(t)) + M_g) w(t) + b_g(t) + n_g(t)

* ``s`` scale factors: a turn-on value ``s0 ~ N(0, sigma_s^2)`` plus an optional random
  walk (spec Eq. 3 models parameters as Brownian motion).
* ``M`` misalignment / non-orthogonality: constant, zero diagonal, off-diagonal entries
  ``~ N(0, sigma_m^2)`` (small-angle).
* ``b(t) = b0 + b_markov(t) + b_rw(t)``: turn-on bias ``b0 ~ N(0, sigma_b^2)``, a
  first-order Gauss–Markov drift with steady-state sigma and time constant ``tau`` (started
  in its stationary distribution) and a random walk; any of them may be zero.
* ``n`` white noise of one-sided density ``N`` (ARW in rad/s/sqrt(Hz) = rad/sqrt(s), VRW in
  m/s^2/sqrt(Hz)); point samples at step ``dt`` have ``sigma = N / sqrt(dt)`` so that the
  integrated angle/velocity error grows as ``N sqrt(t)``.

The inverse model used by the error-state filters (docs/assumptions.md A7),
``f = (I + diag s_a)^-1 (f_meas - b_a)``, is this one to first order. Discretisation is
exact: Gauss–Markov ``b_{k+1} = e^{-dt/tau} b_k + sigma sqrt(1 - e^{-2 dt/tau}) w_k``,
random walk ``b_{k+1} = b_k + q sqrt(dt) w_k``.

Preset files carry unit-suffixed keys (``gyro_bias_deg_h``, ``accel_vrw_ug_sqrt_hz``...);
:data:`navlib.sensors.presets._UNITS` lists every accepted spelling, all converted through
:mod:`navlib.units`.
Each preset records its ``source`` and the keys whose values are ``assumed``.

Aiding sensors of the EKF simulations: :func:`simulate_attitude_sensor` (generic attitude
reference) and :class:`ReferenceTrajectory` (the launcher's reference-trajectory attitudes).

Modules: :mod:`~navlib.sensors.presets` (specifications and presets),
:mod:`~navlib.sensors.simulation` (IMU and GNSS errors), :mod:`~navlib.sensors.aiding`
(attitude references) and the Allan-variance fit of :mod:`navlib.sensors.allan`; the public names
are re-exported here.
"""

from navlib.sensors.aiding import ReferenceTrajectory, simulate_attitude_sensor
from navlib.sensors.allan import allan_deviation, fit_allan, write_allan_preset
from navlib.sensors.presets import (
    DEFAULT_IMU_PRESET,
    PRESET_DIR,
    GnssSpec,
    ImuSpec,
    SensorSpec,
    TriadSpec,
    list_presets,
    load_preset,
)
from navlib.sensors.simulation import (
    ImuSimulation,
    TriadErrors,
    gauss_markov,
    random_walk,
    simulate_gnss,
    simulate_imu,
    white_noise,
)

__all__ = [
    "DEFAULT_IMU_PRESET",
    "PRESET_DIR",
    "GnssSpec",
    "ImuSimulation",
    "ImuSpec",
    "ReferenceTrajectory",
    "SensorSpec",
    "TriadErrors",
    "TriadSpec",
    "allan_deviation",
    "fit_allan",
    "gauss_markov",
    "list_presets",
    "load_preset",
    "random_walk",
    "simulate_attitude_sensor",
    "simulate_gnss",
    "simulate_imu",
    "white_noise",
    "write_allan_preset",
]
