"""Stationary self-alignment and calibration (SSAC) error models, local-level NED.

Silva, Hemerly & Leite Filho (2017), "On the error state selection for stationary SINS
alignment and calibration Kalman filters — Part II", Sensors 17(3) 439; the model is the
reconstruction of docs/assumptions.md, ssac.md §2.3 (the paper's matrices were lost from the seed
text).

State order (15 states, indices 0..14; radians, m/s, m, rad/s, m/s^2)::

    psiN psiE psiD | dvN dvE dvD | dL dlambda dh | bgN bgE bgD | baN baE baD

Conventions (docs/assumptions.md, ssac.md §9: the paper's own are unknown, these are documented
choices):

* ``psi`` is the phi-angle: the small rotation of the computed navigation frame relative to
  the true one, resolved in NED; ``dv = v_computed - v_true``.
* ``dL``, ``dlambda`` in radians, ``dh`` in metres **positive up** (so ``d(dh)/dt = -dvD``).
* ``b_g`` enters as ``dpsi/dt = ... - C_b_n b_g`` and ``b_a`` as ``ddv/dt = ... + C_b_n b_a``;
  the biases are random constants. White gyro noise enters the attitude rows with ``-C_b_n``,
  accelerometer noise the velocity rows with ``+C_b_n``.
* Gravity ``g`` is the WGS-84 normal-gravity magnitude at the site (plumb-bob, with the
  centrifugal term); its latitude derivative is neglected; the vertical gradient is the
  free-air ``2 g / R`` with ``R`` the geocentric radius.

Continuous dynamics at rest (``s, c, t = sin L, cos L, tan L``; ``Omega`` Earth rate)::

    dpsiN/dt = -Omega s psiE - Omega s dL + dvE/(R_N+h) - bgN
    dpsiE/dt =  Omega s psiN + Omega c psiD - dvN/(R_M+h) - bgE
    dpsiD/dt = -Omega c psiE - Omega c dL - t dvE/(R_N+h) - bgD
    ddvN/dt  =  g psiE - 2 Omega s dvE + baN
    ddvE/dt  = -g psiN + 2 Omega s dvN + 2 Omega c dvD + baE
    ddvD/dt  = -2 Omega c dvE - (2 g/R) dh + baD
    ddL/dt = dvN/(R_M+h);  ddlambda/dt = dvE/((R_N+h) c);  ddh/dt = -dvD

Measurement: zero-velocity update ``z = H x + nu`` with ``H = [0 I 0 0 0]`` on the velocity
errors (docs/assumptions.md, ssac.md §2.1, eq. 14–15), ``R = sigma_nu^2 I`` (assumed 0.01 m/s).

Reduced models (docs/assumptions.md, ssac.md §2.4): 12 states = without the position errors (Part
I's optimum); 10 states (Bar-Itzhack & Berman) = without position, ``dvD`` and ``baD``, measuring
the two horizontal velocity errors.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib._validation import finite_array, finite_scalar, latitude_deg
from navlib.earth import OMEGA_E, geodetic_to_ecef, gravity_magnitude, radii_of_curvature
from navlib.errors import NavlibInputError
from navlib.models.base import LinearModel
from navlib.sensors import SensorSpec, load_preset
from navlib.units import DEG, DEG_PER_HOUR, MG

__all__ = ["IMU_KEYS", "IMU_PRESET", "P0_VARIANTS", "SIGMA_NU", "SITE_ALT_M", "SITE_LAT_DEG",
           "SITE_LON_DEG", "STATES_10", "STATES_12", "STATES_15", "STATE_SETS", "display_units",
           "initial_sigmas", "site_constants", "ssac"]

STATES_15 = ("psiN", "psiE", "psiD", "dvN", "dvE", "dvD", "dL", "dlambda", "dh",
             "bgN", "bgE", "bgD", "baN", "baE", "baD")
"""State order of the 15-state model (ssac.md §2.3)."""
STATES_12 = tuple(s for s in STATES_15 if s not in ("dL", "dlambda", "dh"))
"""12-state model: the 15 without the position errors."""
STATES_10 = tuple(s for s in STATES_12 if s not in ("dvD", "baD"))
"""10-state Bar-Itzhack & Berman model: no position, no vertical channel."""
STATE_SETS = {15: STATES_15, 12: STATES_12, 10: STATES_10}

SITE_LAT_DEG = -(23 + 12 / 60 + 47 / 3600)
"""LINCS/IAE, São José dos Campos: -23°12'47" (ssac.md §4.1)."""
SITE_LON_DEG = -(45 + 51 / 60 + 38 / 3600)
"""-45°51'38"."""
SITE_ALT_M = 629.0

IMU_PRESET = "ssac_tactical"
"""Sensor preset of the SSAC simulated test (``data/sensors/ssac_tactical.toml``, ssac.md
§4.1): constant biases 0.5 deg/h and 0.5 mg, gyro random walk 0.0002 deg/sqrt(h) (the
deg/sqrt(h) reading) and accelerometer random walk 0.01 mg/sqrt(Hz)."""
IMU_KEYS = ("gyro_bias", "accel_bias", "gyro_arw", "accel_vrw")

SIGMA_NU = 0.01
"""Assumed zero-velocity measurement noise (quasi-stationary vibration), m/s (ssac.md §4.4)."""

P0_VARIANTS = ("matched", "generic")


def site_constants(lat: float, alt: float) -> dict:
    """Earth quantities of the stationary model at latitude ``lat`` (rad), height ``alt`` (m).

    Returns a dict with ``Omega, g, R_M, R_N, R`` (geocentric radius) and ``gravity_gradient``
    ``2 g / R`` (docs/assumptions.md, ssac.md §4.3).

    Parameters
    ----------
    lat : float
        Latitude, rad.
    alt : float
        Height, m.
    """
    r_m, r_n = radii_of_curvature(lat)
    g = float(gravity_magnitude(lat, alt))
    radius = float(np.linalg.norm(geodetic_to_ecef(lat, 0.0, alt)))
    return {"Omega": OMEGA_E, "g": g, "R_M": float(r_m), "R_N": float(r_n), "R": radius,
            "gravity_gradient": 2.0 * g / radius}


def _dynamics(lat: float, alt: float, C_b_n: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
    """15-state A (15, 15) and noise input G (15, 6) of docs/assumptions.md, ssac.md §2.3."""
    k = site_constants(lat, alt)
    s, c, t = np.sin(lat), np.cos(lat), np.tan(lat)
    W, g = k["Omega"], k["g"]
    rm, rn = k["R_M"] + alt, k["R_N"] + alt
    A = np.zeros((15, 15))
    # attitude rows 0..2: -omega_ie x psi, delta omega_ie(dL), delta omega_en(dv), -C b_g
    A[0, [1, 6, 4]] = [-W * s, -W * s, 1.0 / rn]
    A[1, [0, 2, 3]] = [W * s, W * c, -1.0 / rm]
    A[2, [1, 6, 4]] = [-W * c, -W * c, -t / rn]
    A[0:3, 9:12] = -C_b_n
    # velocity rows 3..5: f x psi, -2 omega_ie x dv, gravity gradient, +C b_a
    A[3, [1, 4]] = [g, -2 * W * s]
    A[4, [0, 3, 5]] = [-g, 2 * W * s, 2 * W * c]
    A[5, [4, 8]] = [-2 * W * c, -k["gravity_gradient"]]
    A[3:6, 12:15] = C_b_n
    # position rows 6..8
    A[6, 3] = 1.0 / rm
    A[7, 4] = 1.0 / (rn * c)
    A[8, 5] = -1.0
    G = np.zeros((15, 6))
    G[0:3, 0:3] = -C_b_n
    G[3:6, 3:6] = C_b_n
    return A, G, k


def initial_sigmas(variant: str, lat: float, alt: float, imu: dict, *,
                   attitude_scale: float = 1.0, sigma_v: float = 0.1,
                   sigma_pos_m: float = 10.0) -> np.ndarray:
    """Initial standard deviations (15,) in state units (docs/assumptions.md, ssac.md §4.4).

    ``"matched"``: tilt ``b_a/g``, azimuth ``b_gE/(Omega cos L)``, so ``g sigma_psiN0 =
    sigma_baE0`` and ``Omega cos L sigma_psiD0 = sigma_bgE0`` (the choice that gives the
    paper's 45° pair eigenvectors); ``"generic"``: 1° on all three attitude errors. Both:
    biases at their nominal values, 0.1 m/s velocity, 10 m position. ``attitude_scale``
    multiplies the attitude sigmas (the P0-sensitivity experiment, docs/assumptions.md, ssac.md §5.4
    item 18).

    Parameters
    ----------
    variant : {"matched", "generic"}
        Attitude sigmas.
    lat : float
        Latitude, rad.
    alt : float
        Height, m.
    imu : dict
        IMU values (``gyro_bias``, rad/s; ``accel_bias``, m/s^2).
    attitude_scale : float, optional
        Factor on the attitude sigmas.
    sigma_v : float, optional
        Velocity sigma, m/s.
    sigma_pos_m : float, optional
        Position sigma, m.

    Raises
    ------
    NavlibInputError
        If ``variant`` is unknown.
    """
    if variant not in P0_VARIANTS:
        raise NavlibInputError(f"P0: expected one of {P0_VARIANTS} or a matrix, got {variant!r}")
    k = site_constants(lat, alt)
    if variant == "matched":
        tilt = imu["accel_bias"] / k["g"]
        azimuth = imu["gyro_bias"] / (k["Omega"] * abs(np.cos(lat)))
        attitude = [tilt, tilt, azimuth]
    else:
        attitude = [DEG] * 3
    rm, rn = k["R_M"] + alt, k["R_N"] + alt
    position = [sigma_pos_m / rm, sigma_pos_m / (rn * abs(np.cos(lat))), sigma_pos_m]
    return np.array([*(attitude_scale * np.asarray(attitude)), *[sigma_v] * 3, *position,
                     *[imu["gyro_bias"]] * 3, *[imu["accel_bias"]] * 3])


def display_units(lat: float, alt: float, state_names=STATES_15) -> dict:
    """Per-state ``(unit label, factor)`` turning SI state values into display units.

    Attitude in deg, velocity m/s, position in metres (``(R_M+h) dL``, ``(R_N+h) cos L
    dlambda``), gyro biases deg/h, accelerometer biases mg.

    Parameters
    ----------
    lat : float
        Latitude, rad.
    alt : float
        Height, m.
    state_names : sequence of str, optional
        States.

    Raises
    ------
    NavlibInputError
        For a state without a display unit.
    """
    r_m, r_n = radii_of_curvature(lat)
    table = {
        "psi": ("deg", 1.0 / DEG), "dv": ("m/s", 1.0), "dL": ("m", float(r_m) + alt),
        "dlambda": ("m", (float(r_n) + alt) * abs(np.cos(lat))), "dh": ("m", 1.0),
        "bg": ("deg/h", 1.0 / DEG_PER_HOUR), "ba": ("mg", 1.0 / MG),
    }
    out = {}
    for name in state_names:
        key = name if name in table else name[:-1]
        if key not in table:
            raise NavlibInputError(f"state_names: no display unit for {name!r}")
        out[name] = table[key]
    return out


def _imu_values(imu) -> dict:
    """SI bias and noise values from a preset name/path, a SensorSpec, or a dict of SI
    overrides on top of :data:`IMU_PRESET`."""
    overrides = {}
    if imu is None or isinstance(imu, dict):
        overrides, imu = dict(imu or {}), IMU_PRESET
    spec = imu if isinstance(imu, SensorSpec) else load_preset(imu)
    if spec.imu is None:
        raise NavlibInputError(f"imu: preset {spec.name!r} has no IMU section")
    values = {"gyro_bias": spec.imu.gyro.bias, "accel_bias": spec.imu.accel.bias,
              "gyro_arw": spec.imu.gyro.noise_density,
              "accel_vrw": spec.imu.accel.noise_density}
    unknown = sorted(set(overrides) - set(IMU_KEYS))
    if unknown:
        raise NavlibInputError(f"imu: unknown key(s) {unknown}; accepted {list(IMU_KEYS)}")
    for key, value in overrides.items():
        values[key] = finite_scalar(value, f"imu[{key!r}]", 0.0)
    if values["gyro_bias"] <= 0 or values["accel_bias"] <= 0:
        raise NavlibInputError("imu: gyro_bias and accel_bias must be positive (they set P0)")
    return values


def ssac(n_states: int = 15, lat_deg: float = SITE_LAT_DEG, alt_m: float = SITE_ALT_M, *,
         P0="matched", attitude_scale: float = 1.0, imu=None,
         sigma_nu: float = SIGMA_NU, sigma_v0: float = 0.1, sigma_pos0_m: float = 10.0,
         C_b_n=None) -> LinearModel:
    """SSAC stationary local-level (NED) error model with zero-velocity measurements.

    Parameters
    ----------
    n_states : {15, 12, 10}
        Full model, without position (12), or Bar-Itzhack & Berman's 10 states (no position,
        no vertical channel, horizontal velocity measurements); docs/assumptions.md, ssac.md
        §2.3–2.4.
    lat_deg, alt_m : float
        Site; default LINCS/IAE (-23.213056°, 629 m).
    P0 : {"matched", "generic"} or ndarray (n, n)
        Default initial covariance (:func:`initial_sigmas`); a matrix is used as given.
    attitude_scale : float
        Multiplies the attitude sigmas of a named P0 variant.
    imu : str, path, SensorSpec or dict, optional
        Sensor preset (default :data:`IMU_PRESET`) giving the 1-sigma biases (P0) and the
        white-noise densities (Qc), or a dict of SI overrides on top of it: ``gyro_bias``
        (rad/s), ``accel_bias`` (m/s^2), ``gyro_arw`` (rad/sqrt(s)), ``accel_vrw``
        (m/s/sqrt(s)).
    sigma_nu : float
        Zero-velocity measurement noise, m/s; ``R = sigma_nu^2 I`` (0 gives ideal updates).
    sigma_v0, sigma_pos0_m : float
        Initial velocity (m/s) and position (m) sigmas of the named P0 variants.
    C_b_n : ndarray (3, 3), optional
        Body-to-NED rotation of the IMU (default identity: aligned, as in the paper). With a
        rotation the bias states are in body axes and named ``bgx .. baz``.

    Returns
    -------
    LinearModel
        Constant model; ``parameters`` holds the site constants, IMU values, ``lat``
        (rad), ``alt`` and ``display_units``.
    """
    if n_states not in STATE_SETS:
        raise NavlibInputError(f"n_states: expected 15, 12 or 10, got {n_states!r}")
    lat = latitude_deg(lat_deg) * DEG
    if abs(lat) > 89.0 * DEG:
        raise NavlibInputError(f"lat_deg: the local-level model is singular near the poles, "
                               f"got {lat_deg}")
    alt = finite_scalar(alt_m, "alt_m", -1e4, 1e5)
    attitude_scale = finite_scalar(attitude_scale, "attitude_scale", 0.0, low_open=True)
    sigma_nu = finite_scalar(sigma_nu, "sigma_nu", 0.0)
    values = _imu_values(imu)
    rotated = C_b_n is not None
    C = np.eye(3) if C_b_n is None else finite_array(C_b_n, "C_b_n", shape=(3, 3))
    if rotated and not np.allclose(C @ C.T, np.eye(3), atol=1e-9):
        raise NavlibInputError("C_b_n: expected a rotation matrix (orthonormal)")
    A, G, site = _dynamics(lat, alt, C)
    names = STATES_15
    if rotated:
        names = (*names[:9], "bgx", "bgy", "bgz", "bax", "bay", "baz")
    Qc = np.diag([values["gyro_arw"] ** 2] * 3 + [values["accel_vrw"] ** 2] * 3)
    H = np.zeros((3, 15))
    H[:, 3:6] = np.eye(3)
    if isinstance(P0, str):
        sig = initial_sigmas(P0, lat, alt, values, attitude_scale=attitude_scale,
                             sigma_v=finite_scalar(sigma_v0, "sigma_v0", 0.0, low_open=True),
                             sigma_pos_m=finite_scalar(sigma_pos0_m, "sigma_pos0_m", 0.0,
                                                       low_open=True))
        P0_full = np.diag(sig**2)
    else:
        P0_full = None
    full = LinearModel(
        state_names=names, A=A, G=G, Qc=Qc, H=H, R=sigma_nu**2 * np.eye(3), P0=P0_full,
        measurement_names=("dvN", "dvE", "dvD"),
        noise_names=("wgN", "wgE", "wgD", "waN", "waE", "waD"),
        name=f"ssac{n_states}",
        parameters={"lat": lat, "alt": alt, "imu": values, "sigma_nu": sigma_nu,
                    "P0_variant": P0 if isinstance(P0, str) else "custom",
                    "attitude_scale": attitude_scale, "C_b_n": C, **site,
                    "display_units": display_units(lat, alt, STATES_15)},
    )
    if rotated:
        units = display_units(lat, alt, STATES_15)
        units.update({new: units[old] for new, old in zip(names[9:], STATES_15[9:],
                                                          strict=True)})
        full.parameters["display_units"] = units
    keep = [names[STATES_15.index(s)] for s in STATE_SETS[n_states]]
    model = full.subset(keep) if n_states != 15 else full
    if n_states == 10:
        H10 = np.zeros((2, 10))
        H10[:, 3:5] = np.eye(2)
        model = replace(model, H=H10, R=sigma_nu**2 * np.eye(2),
                        measurement_names=("dvN", "dvE"))
    if not isinstance(P0, str):
        model = replace(model, P0=finite_array(P0, "P0", shape=(n_states, n_states)))
    return model
