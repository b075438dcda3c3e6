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
           "ZUPT_SIGMA_M_S", "aided_model", "baro_sigma", "pad_epochs", "without_gnss"]

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
"""Static-port pressure error as a fraction of the dynamic pressure (B2, assumed): a
vehicle's own airflow shifts the static pressure by ``C_P q``, an altitude error of
``C_P v^2 / (2 g0)`` (about 40 m at 200 m/s); 0.02 is a well-placed port below Mach 0.8."""
ZUPT_SIGMA_M_S = 0.05
"""Sigma of the zero-velocity rows on the pad, m/s (B3, assumed: a rocket on its rail moves
by millimetres; the sigma also covers the model's linearisation)."""
PAD_SPEED_M_S = 1.0
"""Reference speed below which the vehicle is still on the pad, m/s (B3, by construction):
the pad ends at the first epoch the fitted speed exceeds it."""


def baro_sigma(height_change_m, sigma_m: float = BARO_SIGMA_M,
               scale: float = BARO_SCALE, speed_m_s=0.0,
               pressure_coefficient: float = BARO_PRESSURE_COEFFICIENT) -> np.ndarray:
    """``sqrt(sigma_m^2 + (scale dh)^2 + (C_P v^2 / (2 g0))^2)``: the sigma of a barometric
    altitude ``dh`` metres above the pad, read at airspeed ``v`` (B2).

    Parameters
    ----------
    height_change_m : array_like
        Height above the pad, m.
    sigma_m : float, optional
        Sigma at the pad, m.
    scale : float, optional
        Scale error, fraction of the height.
    speed_m_s : array_like, optional
        Airspeed, m/s.
    pressure_coefficient : float, optional
        Pressure coefficient ``C_P`` of the static port.

    Returns
    -------
    numpy.ndarray
        Sigma, m.
    """
    dh = np.asarray(height_change_m, dtype=float)
    v = np.asarray(speed_m_s, dtype=float)
    dynamic = pressure_coefficient * v**2 / (2.0 * units.G0)
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
        above the first epoch, velocities the pad epochs (:func:`pad_epochs`) and the climb
        rate of the barometer's dynamic-pressure sigma (:func:`baro_sigma`).
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
    # the climb rate stands for the airspeed: large speeds of a rocket are mostly vertical,
    # and the horizontal reference velocity of a flight without GNSS is dead reckoning (B5)
    climb = np.abs(np.einsum("ki,ki->k", np.asarray(trajectory.velocity, dtype=float)[index],
                             -C_n_e[:, :, 2]))
    sigmas.append(baro_sigma(height - height[0], sig["baro_sigma_m"], baro_scale, climb))
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

