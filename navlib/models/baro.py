"""Barometer and pad aiding of the 21-state ECEF model (assumptions.md B1-B4).

:func:`aided_model` replaces the measurement rows of a model discretised by
:func:`navlib.models.ecef.ecef21_at_epochs` (its ``F``, ``Q`` and ``P0`` are unchanged) by
the rows of the sensors that aided the flight:

* ``gnss``: GNSS ECEF position, ``H = [I3, 0]`` (the model as built);
* ``baro``: barometric altitude, ``h = u^T dP + v`` with ``u`` the geodetic up direction in
  ECEF at the epoch's position (B2), and zero velocity on the pad, ``0 = dV + v`` (B3);
* ``gnss+baro``: GNSS north and east position, ``n^T dP``, ``e^T dP`` (a receiver without
  height), the barometric altitude and the pad rows.

Every epoch has the same rows (:attr:`DiscreteModel.H` is ``(N, m, 21)``): a pad row after
lift-off has ``H = 0`` and carries no information.

The barometer has no bias state (B4): its altitude is used relative to its own pad value,
so a constant offset (the day's sea-level pressure, the sensor's offset) cancels; the
standard atmosphere's scale error and the weather's drift over a flight of minutes enter as
the height- and speed-dependent sigma of :func:`baro_sigma`. Without GNSS, horizontal position and
velocity have no measurement after the pad: their sigma grows with the IMU errors, and they
come out neither excitable nor sensible.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib import earth, units
from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.models.base import DiscreteModel

__all__ = ["AIDINGS", "BARO_PRESSURE_COEFFICIENT", "BARO_SCALE", "BARO_SIGMA_M", "PAD_SPEED_M_S",
           "PRANDTL_GLAUERT_MACH", "ZUPT_SIGMA_M_S", "aided_model", "baro_sigma", "mach_number",
           "pad_epochs", "static_pressure_error_m", "without_gnss"]

AIDINGS = ("gnss", "baro", "gnss+baro")
"""What aided a flight: its GNSS receiver, its barometer (with the pad), or both."""
BARO_SIGMA_M = 1.0
"""White-noise sigma of one barometric altitude, m (B2, assumed: an MS5611/BMP388-class
sensor at 0.1 hPa rms is about 1 m)."""
BARO_SCALE = 0.01
"""Relative sigma of the barometric height change (B2, assumed): the standard atmosphere
differs from the day's by about 0.35 % per kelvin of mean temperature, so 1 % covers a day
3 K off standard."""
BARO_PRESSURE_COEFFICIENT = 0.02
"""Static-port pressure error as a fraction of the impact pressure at low Mach number (B2,
assumed): a vehicle's own airflow shifts the static pressure by ``C_P q_c``, an altitude
error of ``C_P v^2 / (2 g0)`` at low speed (about 40 m at 200 m/s); 0.02 is a well-placed
port, chosen before any shared log was looked at. Its growth with Mach number is
:func:`static_pressure_error_m` (B7)."""
PRANDTL_GLAUERT_MACH = 0.8
"""Mach number up to which the Prandtl-Glauert rule scales the pressure coefficient,
``C_P / sqrt(|1 - M^2|)`` (B7: linearised compressible flow, Anderson, *Modern Compressible
Flow*, ch. 9; it diverges at Mach 1 and fails in the transonic range). From it to Mach 1.17,
where the supersonic ``1 / sqrt(M^2 - 1)`` comes back to the same value, the factor is held
at 1 / 0.6."""
_GAMMA_AIR = 1.4
_R_AIR = 287.053            # J/(kg K), the ISA's specific gas constant
_ISA_T0_K = 288.15          # the ISA troposphere of B1 (navlib.io.baro)
_ISA_LAPSE_K_M = 0.0065
ZUPT_SIGMA_M_S = 0.05
"""Sigma of the zero-velocity rows on the pad, m/s (B3, assumed: a rocket on its rail moves
by millimetres; the sigma also covers the model's linearisation)."""
PAD_SPEED_M_S = 1.0
"""Reference speed below which the vehicle is still on the pad, m/s (B3, by construction):
the pad ends at the first epoch the fitted speed exceeds it."""


def mach_number(speed_m_s, altitude_m=0.0) -> np.ndarray:
    """Mach number of ``speed_m_s`` at the ISA troposphere's temperature at ``altitude_m``
    (B1, B7; the day's temperature moves the speed of sound by about 0.2 % per kelvin).

    Parameters
    ----------
    speed_m_s : array_like
        Airspeed, m/s (the reference's speed over ground: no wind).
    altitude_m : array_like, optional
        Pressure altitude, m.

    Returns
    -------
    numpy.ndarray
    """
    temperature = _ISA_T0_K - _ISA_LAPSE_K_M * np.clip(np.asarray(altitude_m, float), -500.0,
                                                         11_000.0)
    return np.abs(np.asarray(speed_m_s, dtype=float)) / np.sqrt(_GAMMA_AIR * _R_AIR * temperature)


def static_pressure_error_m(speed_m_s, altitude_m=0.0,
                            pressure_coefficient: float = BARO_PRESSURE_COEFFICIENT
                            ) -> np.ndarray:
    """The altitude error a static port's pressure error ``C_P(M) q_c`` makes (B2, B7).

    ``q_c`` is the impact pressure (isentropic below Mach 1, the Rayleigh pitot formula
    above: behind the normal shock), ``C_P(M)`` the low-speed coefficient scaled by the
    Prandtl-Glauert factor ``1 / sqrt(|1 - M^2|)``, held at its value at
    :data:`PRANDTL_GLAUERT_MACH` through the transonic range where linear theory fails. The
    altitude error is ``C_P(M) q_c / (rho g0)``, with ``p / rho = a^2 / gamma``; at low speed
    it is ``C_P v^2 / (2 g0)``.

    Parameters
    ----------
    speed_m_s : array_like
        Airspeed, m/s.
    altitude_m : array_like, optional
        Pressure altitude, m (the speed of sound, :func:`mach_number`).
    pressure_coefficient : float, optional
        Low-speed pressure coefficient ``C_P`` of the static port.

    Returns
    -------
    numpy.ndarray
        Altitude error, m (a magnitude: the sign depends on where the port sits).
    """
    mach = mach_number(speed_m_s, altitude_m)
    m2 = mach**2
    subsonic = (1.0 + 0.2 * m2) ** 3.5 - 1.0                     # q_c / p, isentropic
    m2s = np.maximum(m2, 1.0)
    supersonic = ((5.76 * m2s / (5.6 * m2s - 0.8)) ** 3.5 * (2.8 * m2s - 0.4) / 2.4 - 1.0)
    qc_over_p = np.where(mach < 1.0, subsonic, supersonic)
    beta = np.sqrt(np.maximum(np.abs(1.0 - m2), 1.0 - PRANDTL_GLAUERT_MACH**2))
    temperature = _ISA_T0_K - _ISA_LAPSE_K_M * np.clip(np.asarray(altitude_m, float), -500.0,
                                                         11_000.0)
    p_over_rho_g = _R_AIR * temperature / units.G0             # the pressure scale height, m
    return pressure_coefficient / beta * qc_over_p * p_over_rho_g


def baro_sigma(height_change_m, sigma_m: float = BARO_SIGMA_M,
               scale: float = BARO_SCALE, speed_m_s=0.0,
               pressure_coefficient: float = BARO_PRESSURE_COEFFICIENT,
               altitude_m=0.0) -> np.ndarray:
    """``sqrt(sigma_m^2 + (scale dh)^2 + e_q^2)``: the sigma of a barometric altitude ``dh``
    metres above the pad, read at airspeed ``v`` (B2), with ``e_q`` the static-pressure
    error of :func:`static_pressure_error_m` (``C_P v^2 / (2 g0)`` at low speed, growing
    through the transonic range, B7).

    Parameters
    ----------
    height_change_m : array_like
        Height above the pad, m.
    sigma_m : float, optional
        Sigma at the pad, m.
    scale : float, optional
        Scale error, fraction of the height.
    speed_m_s : array_like, optional
        Airspeed, m/s: the reference's speed, never the barometer's own climb rate (a
        static-pressure error corrupts that too, B7).
    pressure_coefficient : float, optional
        Low-speed pressure coefficient ``C_P`` of the static port.
    altitude_m : array_like, optional
        Pressure altitude, m (the speed of sound).

    Returns
    -------
    numpy.ndarray
        Sigma, m.
    """
    dh = np.asarray(height_change_m, dtype=float)
    dynamic = static_pressure_error_m(speed_m_s, altitude_m, pressure_coefficient)
    return np.sqrt(sigma_m**2 + (scale * dh) ** 2 + dynamic**2)


def pad_epochs(t_epochs, t, velocity, speed_m_s: float = PAD_SPEED_M_S) -> np.ndarray:
    """Epochs (bool) before the first time the reference speed exceeds ``speed_m_s`` (B3);
    none when the reference starts faster (a log starting after lift-off).

    Parameters
    ----------
    t_epochs : array_like
        Epoch times, s.
    t : numpy.ndarray
        Reference times, s.
    velocity : numpy.ndarray
        Reference velocity, m/s, (N, 3).
    speed_m_s : float, optional
        Speed that ends the pad, m/s.

    Returns
    -------
    numpy.ndarray
    """
    speed = np.linalg.norm(np.asarray(velocity, dtype=float), axis=1)
    moving = np.flatnonzero(speed > speed_m_s)
    t_launch = t[moving[0]] if moving.size else np.inf
    return np.asarray(t_epochs, dtype=float) < t_launch


def aided_model(model: DiscreteModel, trajectory, aiding: str, *,
                gnss_sigma_m: float = 5.0, baro_sigma_m: float = BARO_SIGMA_M,
                baro_scale: float = BARO_SCALE,
                zupt_sigma_m_s: float = ZUPT_SIGMA_M_S) -> DiscreteModel:
    """``model`` with the measurement rows of ``aiding`` (one of :data:`AIDINGS`).

    Parameters
    ----------
    model : DiscreteModel
        From :func:`navlib.models.ecef.ecef21_at_epochs` along ``trajectory``.
    trajectory : Trajectory
        The reference motion: positions give the up/north/east directions and the height
        above the first epoch, velocities the pad epochs (:func:`pad_epochs`) and the speed
        of the barometer's static-pressure sigma (:func:`baro_sigma`, B7: the speed with
        GNSS, the climb rate without, whose horizontal velocity is dead reckoning, B5).
    aiding : str
        ``gnss`` returns ``model`` unchanged.
    gnss_sigma_m, baro_sigma_m, baro_scale, zupt_sigma_m_s : float
        Sigmas of the GNSS horizontal rows (m), of the barometer (:func:`baro_sigma`) and of
        the pad's zero velocity (m/s).

    Returns
    -------
    DiscreteModel
        Same ``t, F, Q, P0``; ``H`` (N, m, 21) and ``R`` (N, m, m) with the rows named in
        ``measurement_names``: ``gnss_n, gnss_e`` (gnss+baro), ``baro_h``, ``zupt_x,
        zupt_y, zupt_z``.
    """
    if aiding not in AIDINGS:
        raise NavlibInputError(f"aiding: expected one of {AIDINGS}, got {aiding!r}")
    if aiding == "gnss":
        return model
    sig = {k: finite_scalar(v, k, 0.0, low_open=True) for k, v in (
        ("gnss_sigma_m", gnss_sigma_m), ("baro_sigma_m", baro_sigma_m),
        ("zupt_sigma_m_s", zupt_sigma_m_s))}
    baro_scale = finite_scalar(baro_scale, "baro_scale", 0.0)
    t = np.asarray(trajectory.t, dtype=float)
    index = np.clip(np.searchsorted(t, model.t), 0, t.size - 1)
    position = np.asarray(trajectory.position, dtype=float)[index]
    lat, lon, height = earth.ecef_to_geodetic(position)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)              # (N, 3, 3) columns N, E, D
    n_ep = model.t.size
    names, H_rows, sigmas = [], [], []
    if aiding == "gnss+baro":
        for name, axis in (("gnss_n", 0), ("gnss_e", 1)):
            row = np.zeros((n_ep, 21))
            row[:, 0:3] = C_n_e[:, :, axis]
            names.append(name)
            H_rows.append(row)
            sigmas.append(np.full(n_ep, sig["gnss_sigma_m"]))
    row = np.zeros((n_ep, 21))
    row[:, 0:3] = -C_n_e[:, :, 2]                              # up = -down
    names.append("baro_h")
    H_rows.append(row)
    # the reference's speed stands for the airspeed (no wind; B2, B7); without GNSS only its
    # climb rate, since its horizontal velocity is dead reckoning (B5)
    velocity = np.asarray(trajectory.velocity, dtype=float)[index]
    speed = (np.linalg.norm(velocity, axis=1) if aiding == "gnss+baro" else
             np.abs(np.einsum("ki,ki->k", velocity, -C_n_e[:, :, 2])))
    sigmas.append(baro_sigma(height - height[0], sig["baro_sigma_m"], baro_scale, speed,
                             altitude_m=height))
    pad = pad_epochs(model.t, t, trajectory.velocity)
    for axis, name in enumerate(("zupt_x", "zupt_y", "zupt_z")):
        row = np.zeros((n_ep, 21))
        row[pad, 3 + axis] = 1.0
        names.append(name)
        H_rows.append(row)
        sigmas.append(np.full(n_ep, sig["zupt_sigma_m_s"]))
    H = np.stack(H_rows, axis=1)
    R = np.zeros((n_ep, len(names), len(names)))
    idx = np.arange(len(names))
    R[:, idx, idx] = np.column_stack(sigmas) ** 2
    return replace(model, H=H, R=R, measurement_names=tuple(names))


def without_gnss(model: DiscreteModel, epochs) -> DiscreteModel:
    """``model`` with its GNSS measurement rows (``measurement_names`` starting ``gnss``: the
    ECEF position of :func:`navlib.models.ecef.ecef21_at_epochs`, the north/east rows of
    :func:`aided_model`) zero at ``epochs``; the barometer and pad rows stay (an outage of
    the receiver, assumptions M6, Q5, B1-B3).

    Parameters
    ----------
    model : DiscreteModel
        A GNSS-aided or barometer-aided model.
    epochs : array of bool (N,)
        The model epochs without a GNSS measurement.

    Returns
    -------
    DiscreteModel
        The same model with a new ``H`` (``model`` itself when ``epochs`` holds none).
    """
    epochs = np.asarray(epochs, dtype=bool)
    if not epochs.any():
        return model
    rows = [k for k, name in enumerate(model.measurement_names) if name.startswith("gnss")]
    H = np.array(model.H)
    H[np.ix_(epochs, rows)] = 0.0
    return replace(model, H=H)

