"""CSV flight data: IMU and GNSS readers (validated, SI out); the inverse writers are in
:mod:`navlib.io.csv_writers`.

File format
-----------
Delimited text (``,``, ``;``, tab or blanks, detected from the header), UTF-8. Lines that
are blank or start with ``#`` are skipped (but counted in line numbers of messages). The
first other line is the header. Header names are matched case-insensitively, with blanks,
``-`` and ``.`` read as ``_``. A unit may be written in brackets after a name
(``f_x [g]``, ``time (ms)``): it then applies to that column, and contradicting it with a
unit keyword raises. Extra columns are ignored. See :data:`IMU_COLUMNS`, :data:`GNSS_COLUMNS`
for every accepted name.

Units
-----
A unit keyword left at ``None`` means "the unit in the header brackets, else SI".

=============  ======================================  ================================
keyword        accepted values                          applies to
=============  ======================================  ================================
time_unit      ``s`` ``ms`` ``us`` ``ns``               ``t``
accel_unit     ``m/s^2`` ``g`` ``mg``                   ``f_x f_y f_z``
gyro_unit      ``rad/s`` ``deg/s``                      ``w_x w_y w_z``
length_unit    ``m`` ``mm`` ``km``                      ``x y z alt sigma*``, and per s for
                                                        velocities
angle_unit     ``deg`` ``rad``                          ``lat lon`` (``lat_deg``/``lon_deg``
                                                        are always degrees)
=============  ======================================  ================================
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np
import pandas as pd

from navlib import units
from navlib._validation import finite_scalar
from navlib.earth import ecef_to_geodetic, geodetic_to_ecef, ned_to_ecef_matrix
from navlib.errors import NavlibInputError
from navlib.io import _units
from navlib.io._table import (
    Column,
    ColumnSpec,
    TextTable,
    check_declared,
    check_finite,
    column_factors,
    parse_columns,
    read_text_table,
    resolve_columns,
)
from navlib.io.checks import (
    MAX_OUTLIER_FRACTION,
    ON_GAP,
    RATE_MAX_RAD_S,
    SAMPLE_ACCEL_MAX,
    apply_gap_policy,
    check_imu_magnitudes,
    check_positions,
    check_positive,
    check_sample_interval,
    check_times,
    check_velocities,
    flag_imu_outliers,
)
from navlib.io.gnss_rows import SATELLITE_ALIASES, screen_fixes
from navlib.io.sensor_health import check_imu_alive

__all__ = ["AXES", "DEG_S_MEDIAN_RATE", "F_KEYS", "GNSS_COLUMNS", "GNSS_SPECS", "IMU_COLUMNS",
           "IMU_KEYS", "IMU_SPECS", "NED_KEYS", "R_KEYS", "V_KEYS", "W_KEYS", "combine_sigma",
           "read_gnss_csv", "read_imu_csv"]

AXES = ("x", "y", "z")
F_KEYS = ("f_x", "f_y", "f_z")
W_KEYS = ("w_x", "w_y", "w_z")
IMU_KEYS = ("t", *F_KEYS, *W_KEYS)
"""Columns of an IMU DataFrame: time s, specific force f^b m/s^2, angular rate w_ib^b rad/s."""
R_KEYS = ("x", "y", "z")
V_KEYS = ("vx", "vy", "vz")
NED_KEYS = ("vn", "ve", "vd")

_TIME_ALIASES = ("time", "timestamp", "times", "t_s", "time_s", "timestamp_s", "time_ms",
                 "timestamp_ms", "t_ms", "time_us", "timestamp_us", "t_us", "time_ns",
                 "timestamp_ns")
_TIME_IMPLIED = tuple((a, a.rsplit("_", 1)[1]) for a in _TIME_ALIASES if "_" in a)


def _axis(templates: tuple[str, ...], axis: str, index: int) -> tuple[str, ...]:
    return tuple(t.format(a=axis, i=index) for t in templates)


_F_TEMPLATES = ("f{a}", "f_b_{a}", "a{a}", "a_{a}", "acc_{a}", "acc{a}", "accel_{a}",
                "accel{a}", "acceleration_{a}", "accelerometer_{a}", "specific_force_{a}",
                "{a}acc", "accelerometer_m_s2_{i}")
_W_TEMPLATES = ("w{a}", "w_ib_b_{a}", "g{a}", "g_{a}", "gyro_{a}", "gyro{a}", "gyr_{a}",
                "omega_{a}", "rate_{a}", "angular_rate_{a}", "{a}gyro", "gyro_rad_{i}")
_TIME_SPEC = ColumnSpec("t", _TIME_ALIASES, "time", _TIME_IMPLIED)

IMU_SPECS = (
    _TIME_SPEC,
    *(ColumnSpec(f"f_{a}", _axis(_F_TEMPLATES, a, i), "accel") for i, a in enumerate(AXES)),
    *(ColumnSpec(f"w_{a}", _axis(_W_TEMPLATES, a, i), "gyro") for i, a in enumerate(AXES)),
)
GNSS_SPECS = (
    _TIME_SPEC,
    *(ColumnSpec(a, (f"{a}_ecef", f"ecef_{a}", f"r_{a}", f"r_e_{a}", f"pos_ecef_{a}"),
                 "length") for a in AXES),
    ColumnSpec("lat", ("latitude", "lat_rad"), "angle", (("lat_rad", "rad"),)),
    ColumnSpec("lon", ("long", "lng", "longitude", "lon_rad"), "angle", (("lon_rad", "rad"),)),
    ColumnSpec("lat_deg", ("latitude_deg",), "degrees"),
    ColumnSpec("lon_deg", ("longitude_deg", "long_deg", "lng_deg"), "degrees"),
    ColumnSpec("alt", ("alt_m", "altitude", "height", "h", "hae", "alt_ellipsoid",
                       "altitude_ellipsoid", "altitude_ellipsoid_m", "height_ellipsoid",
                       "ellipsoidal_height"), "length",
               (("alt_m", "m"), ("altitude_ellipsoid_m", "m"))),
    *(ColumnSpec(f"v{a}", (f"v_{a}", f"vel_{a}", f"vel{a}", f"v{a}_ecef", f"v_e_{a}"),
                 "velocity") for a in AXES),
    *(ColumnSpec(f"v{c}", (f"v_{c}", f"vel_{c}", f"vel{c}", f"v_{word}", f"vel_{word}",
                           f"vel_{c}_m_s"), "velocity", ((f"vel_{c}_m_s", "m/s"),))
      for c, word in (("n", "north"), ("e", "east"), ("d", "down"))),
    ColumnSpec("sigma", ("sigma_m", "sigma_pos", "pos_sigma", "position_sigma", "std",
                         "pos_std", "sigma_r"), "length"),
    ColumnSpec("sigma_h", ("eph", "hacc", "h_acc", "sigma_horizontal"), "length"),
    ColumnSpec("sigma_v", ("epv", "vacc", "v_acc", "sigma_vertical"), "length"),
    ColumnSpec("satellites", SATELLITE_ALIASES[1:]),
)
IMU_COLUMNS = {s.key: s.aliases for s in IMU_SPECS}
"""Accepted header names (after normalisation) for each IMU column."""
GNSS_COLUMNS = {s.key: s.aliases for s in GNSS_SPECS}
"""Accepted header names (after normalisation) for each GNSS input column."""


def _check_options(on_gap: str, max_gap_s) -> None:
    if on_gap not in ON_GAP:
        raise NavlibInputError(f"on_gap: expected one of {list(ON_GAP)}, got {on_gap!r}")
    if max_gap_s is not None:
        finite_scalar(max_gap_s, "max_gap_s", 0.0, low_open=True)


def _require(cols: Mapping[str, Column], keys, table: TextTable, specs) -> None:
    aliases = {s.key: s.aliases for s in specs}
    for key in keys:
        if key not in cols:
            names = ", ".join((key, *aliases[key][:6]))
            raise table.source.error(
                repr(key), None,
                f"missing column (accepted names include {names}); header is {table.header}")


def _labels(cols: Mapping[str, Column], keys) -> str:
    return "/".join(cols[k].label for k in keys)


def read_imu_csv(path, *, time_unit: str | None = None, accel_unit: str | None = None,
                 gyro_unit: str | None = None, columns: Mapping[str, str] | None = None,
                 sep: str | None = None, max_gap_s: float | None = None, on_gap: str = "warn",
                 check_magnitudes: bool = True, max_rate_rad_s: float = RATE_MAX_RAD_S,
                 max_accel_m_s2: float = SAMPLE_ACCEL_MAX,
                 max_outlier_fraction: float = MAX_OUTLIER_FRACTION) -> pd.DataFrame:
    """Read an IMU record (time, 3 specific forces, 3 angular rates) from a CSV file.

    Parameters
    ----------
    path : str or Path
        The CSV file (format in the module docstring).
    time_unit, accel_unit, gyro_unit : str, optional
        Units of the file's columns: ``s``/``ms``/``us``/``ns``; ``m/s^2``/``g``/``mg``;
        ``rad/s``/``deg/s``. None: the unit in the header brackets, else SI.
    columns : mapping, optional
        Explicit ``{canonical: header}`` choices, e.g. ``{"t": "gps_time"}``, overriding the
        aliases below.
    sep : str, optional
        Field separator; detected from the header when None.
    max_gap_s : float, optional
        Longest accepted interval between samples, s. None: 10 median intervals.
    on_gap : {"warn", "raise", "split"}
        What a longer interval does: warn (:class:`~navlib.io.FlightDataWarning`), raise, or
        add an integer ``segment`` column (split the frame with :func:`split_at_gaps`).
        The gaps are always listed in ``frame.attrs["gaps"]``.
    check_magnitudes : bool
        Reject magnitudes typical of unit mix-ups (:func:`~navlib.io.checks.check_imu_magnitudes`)
        and exclude non-physical samples (:func:`~navlib.io.checks.flag_imu_outliers`).
    max_rate_rad_s, max_accel_m_s2 : float
        Largest plausible angular-rate norm (default 35 rad/s) and specific-force norm
        (default 100 g) of a sample; samples beyond are excluded and listed in
        ``attrs["outliers"]`` (time, value, rule), with a :class:`~navlib.io.FlightDataWarning`.
    max_outlier_fraction : float
        Largest share of such samples (default 0.01) before the record is refused.

    Returns
    -------
    DataFrame
        Columns ``t`` (s), ``f_x, f_y, f_z`` (specific force f^b in body axes, m/s^2, what
        an ideal accelerometer reads: about -g "up" at rest), ``w_x, w_y, w_z`` (omega_ib^b,
        rad/s), plus ``segment`` with ``on_gap="split"``. ``attrs`` holds ``source``,
        ``gaps``, ``max_gap_s`` and ``outliers`` (the excluded samples). Times are kept on
        the file's time base (not shifted), so an IMU and a GNSS file written against the
        same clock stay aligned.

    Accepted header names (normalised): ``t``: t, time, timestamp, time_s, time_ms, time_us
    (the suffix sets the unit), ...; ``f_x``: f_x, fx, ax, a_x, acc_x, accel_x,
    acceleration_x, accelerometer_x, specific_force_x, xacc, accelerometer_m_s2[0]
    (``ulog2csv``), ...; ``w_x``: w_x, wx, gx, g_x, gyro_x, gyr_x, omega_x, rate_x,
    angular_rate_x, xgyro, gyro_rad[0], ...; likewise for y and z. Full lists in
    :data:`IMU_COLUMNS`.

    Raises
    ------
    NavlibInputError
        Naming file, column and line: missing/empty/truncated/binary file, missing or
        duplicate columns, non-numeric, empty, NaN or infinite cells, duplicate or
        decreasing time stamps, implausible sample interval (time unit), gaps with
        ``on_gap="raise"``, implausible magnitudes (accelerations in g declared as m/s^2,
        angular rates in deg/s declared as rad/s: more than ``max_outlier_fraction`` of the
        samples beyond the limits).
    """
    _check_options(on_gap, max_gap_s)
    max_rate_rad_s = finite_scalar(max_rate_rad_s, "max_rate_rad_s", 0.0, low_open=True)
    max_accel_m_s2 = finite_scalar(max_accel_m_s2, "max_accel_m_s2", 0.0, low_open=True)
    max_outlier_fraction = finite_scalar(max_outlier_fraction, "max_outlier_fraction", 0.0,
                                         1.0)
    declared = {"time": ("time_unit", time_unit, "s"),
                "accel": ("accel_unit", accel_unit, "m/s^2"),
                "gyro": ("gyro_unit", gyro_unit, "rad/s")}
    check_declared(declared)
    table = read_text_table(path, sep)
    cols = resolve_columns(table, IMU_SPECS, columns)
    _require(cols, IMU_KEYS, table, IMU_SPECS)
    cols = {k: cols[k] for k in IMU_KEYS}
    src = table.source
    values = parse_columns(table, cols)
    check_finite(values, cols, src)
    kinds = {s.key: s.kind for s in IMU_SPECS}
    fac = column_factors(cols, kinds, declared)
    t = values["t"] * fac["t"]
    check_times(t, src, cols["t"].label)
    check_sample_interval(t, src, cols["t"].label, "imu", fac["t"])
    f_b = np.column_stack([values[k] * fac[k] for k in F_KEYS])
    w_ib_b = np.column_stack([values[k] * fac[k] for k in W_KEYS])
    outliers = []
    if check_magnitudes:
        declared_g = all(np.isclose(fac[k], units.G0) for k in F_KEYS)
        check_imu_magnitudes(f_b, src, _labels(cols, F_KEYS), declared_g)
        keep, outliers = flag_imu_outliers(
            t, f_b, w_ib_b, src, _labels(cols, F_KEYS), _labels(cols, W_KEYS),
            max_rate_rad_s=max_rate_rad_s, max_accel_m_s2=max_accel_m_s2,
            max_fraction=max_outlier_fraction,
            rate_hint=_rate_hint(w_ib_b, max_rate_rad_s))
        if outliers:
            t, f_b, w_ib_b = t[keep], f_b[keep], w_ib_b[keep]
            src = replace(src, lines=None if src.lines is None else src.lines[keep],
                          raw=None if src.raw is None else [r for r, k in zip(
                              src.raw, keep, strict=True) if k])
        check_imu_alive(f_b, w_ib_b, src, _labels(cols, F_KEYS), _labels(cols, W_KEYS))
    frame = pd.DataFrame({"t": t, **dict(zip(F_KEYS, f_b.T, strict=True)),
                          **dict(zip(W_KEYS, w_ib_b.T, strict=True))})
    frame.attrs["source"] = str(path)
    frame.attrs["outliers"] = outliers
    return apply_gap_policy(frame, src, cols["t"].label, max_gap_s, on_gap)


DEG_S_MEDIAN_RATE = 1.0
"""Median angular-rate norm above which rates declared in rad/s look like deg/s, rad/s: a
flight whose typical rotation is 57 deg/s or more is implausible, while the rest noise and slow
turns of a deg/s gyro read about one unit."""


def _rate_hint(w_ib_b: np.ndarray, max_rate_rad_s: float) -> str:
    """The hint of a refused angular-rate record: deg/s only when the data support it (a
    median rate of :data:`DEG_S_MEDIAN_RATE` or more that becomes plausible in deg/s)."""
    norm = np.linalg.norm(w_ib_b, axis=1)
    median = float(np.median(norm))
    if median >= DEG_S_MEDIAN_RATE and float(np.max(norm)) * units.DEG <= max_rate_rad_s:
        return ("; the data look like deg/s: set gyro_unit='deg/s' (or raise max_rate_rad_s "
                "for a fast spinner)")
    limit = float(np.ceil(1.05 * np.max(norm)))
    return (f"; the median rate {median:.3g} rad/s is plausible, so the units look right: a "
            f"vehicle this fast (a tumble, a break-up) needs a larger max_rate_rad_s (e.g. "
            f"max_rate_rad_s={limit:g}; python -m navlib assess LOG --read max_rate_rad_s "
            f"{limit:g})")


def _choose(mode: str | None, keyword: str, present: dict[str, bool], src) -> str | None:
    """Pick the input representation: the keyword, or the one whose columns are present."""
    if mode is not None:
        if mode not in present and mode != "none":
            raise NavlibInputError(
                f"{keyword}: expected one of {[*present, 'none']} or None, got {mode!r}")
        return None if mode == "none" else mode
    have = [m for m, p in present.items() if p]
    if len(have) > 1:
        raise src.error(None, None, f"has both {' and '.join(have)} columns; choose with "
                                    f"{keyword}={have[0]!r} or {keyword}={have[1]!r}")
    return have[0] if have else None


def read_gnss_csv(path, *, time_unit: str | None = None, length_unit: str | None = None,
                  angle_unit: str | None = None, position: str | None = None,
                  velocity: str | None = None, columns: Mapping[str, str] | None = None,
                  sep: str | None = None, max_gap_s: float | None = None,
                  on_gap: str = "warn", check_magnitudes: bool = True,
                  baro: pd.DataFrame | None = None, keep_held: bool = False) -> pd.DataFrame:
    """Read GNSS fixes (time, position, optional velocity and sigma) from a CSV file.

    Position is given either in ECEF (``x, y, z``) or geodetic (``lat_deg, lon_deg, alt``,
    or ``lat, lon`` in ``angle_unit``, with ``alt`` the WGS-84 ellipsoidal height: a mean-
    sea-level height is off by the geoid undulation, up to ~100 m); it is returned in ECEF
    via :func:`navlib.earth.geodetic_to_ecef`. Velocity, optional, is ECEF (``vx, vy, vz``)
    or NED (``vn, ve, vd``, rotated with :func:`navlib.earth.ned_to_ecef_matrix` at each
    fix). The position standard deviation is ``sigma`` (one value per fix, per axis), or
    computed from horizontal/vertical ones as ``sqrt((2 sigma_h^2 + sigma_v^2) / 3)``
    (trace preserving; sigma_h is taken per horizontal axis, as PX4's EKF2 uses ``eph``).

    Parameters
    ----------
    path : str or Path
        The CSV file (format in the module docstring).
    time_unit, length_unit, angle_unit : str, optional
        ``s``/``ms``/``us``/``ns``; ``m``/``mm``/``km`` (velocities: the same per second);
        ``deg``/``rad`` for ``lat``/``lon`` columns. None: header brackets, else s, m, deg.
    position : {"ecef", "geodetic"}, optional
        Required only when the file has both kinds of columns.
    velocity : {"ecef", "ned", "none"}, optional
        Required only when the file has both kinds; ``"none"`` ignores velocity columns.
    columns, sep, max_gap_s, on_gap, check_magnitudes
        As in :func:`read_imu_csv`. Magnitude checks: every position within
        6300..7500 km of the Earth's centre, every speed below 12 km/s.
    baro : DataFrame, optional
        A barometer record (``t, alt_m``, :func:`navlib.io.baro.read_baro_csv`): a geodetic
        file without a height column takes the barometric altitude at each fix as its
        height (assumptions.md B1; ``attrs["height_source"] = "baro"``).
    keep_held : bool
        Keep the rows that repeat the previous fix exactly (held between a receiver's
        updates). False (default): they are no new measurement and are dropped with a
        :class:`~navlib.io.FlightDataWarning` naming their count and lines; so are rows of a
        ``satellites`` column (``nsat``, ``sats``, ...) reporting more than 100 or fewer than
        4 satellites, whatever ``keep_held`` (assumption Q7, :mod:`navlib.io.gnss_rows`).

    Returns
    -------
    DataFrame
        ``t`` (s), ``x, y, z`` (ECEF, m), then ``vx, vy, vz`` (ECEF, m/s) and ``sigma`` (m)
        when given, plus ``segment`` with ``on_gap="split"``. ``attrs``: ``source``,
        ``position_input``, ``velocity_input``, ``gaps``, ``max_gap_s``,
        ``held_fixes_dropped``, ``held_runs`` (``(t_fix, t_last_repeat)`` per held fix, s),
        ``implausible_rows``.

    Accepted header names (normalised): ``x``: x, x_ecef, ecef_x, r_x, ...; ``lat_deg``:
    lat_deg, latitude_deg; ``lat``: lat, latitude, lat_rad; ``lon_deg``: lon_deg,
    longitude_deg, lng_deg; ``lon``: lon, long, lng, longitude, lon_rad; ``alt``: alt, alt_m,
    altitude, height, h, hae, alt_ellipsoid, altitude_ellipsoid_m; ``vx``: vx, v_x, vel_x;
    ``vn``: vn, v_n, vel_n, v_north, vel_n_m_s (``ve``, ``vd`` alike); ``sigma``: sigma,
    sigma_m, std, pos_std; ``sigma_h``: eph, hacc; ``sigma_v``: epv, vacc. Full lists in
    :data:`GNSS_COLUMNS`.

    Raises
    ------
    NavlibInputError
        As :func:`read_imu_csv`, plus latitudes outside +-90 deg (or radians declared for
        degrees), positions far from the Earth, speeds above 12 km/s, sigma <= 0, and
        ambiguous inputs (both ECEF and geodetic columns, ``lat`` and ``lat_deg``, ...).
    """
    _check_options(on_gap, max_gap_s)
    if length_unit is not None:
        _units.factor("length", length_unit, "length_unit")
    if angle_unit is not None:
        _units.factor("angle", angle_unit, "angle_unit")
    if time_unit is not None:
        _units.factor("time", time_unit, "time_unit")
    table = read_text_table(path, sep)
    src = table.source
    cols = resolve_columns(table, GNSS_SPECS, columns)
    for a, b, what in (("lat", "lat_deg", "latitude"), ("lon", "lon_deg", "longitude")):
        if a in cols and b in cols:
            raise src.error(f"{cols[a].label}/{cols[b].label}", None,
                            f"both give the {what}; keep one, or choose with columns=")
    pos = _choose(position, "position", {
        "ecef": any(k in cols for k in R_KEYS),
        "geodetic": any(k in cols for k in ("lat", "lon", "lat_deg", "lon_deg", "alt"))}, src)
    if pos is None:
        raise src.error(None, None, f"no position columns: need x, y, z (ECEF) or lat_deg, "
                                    f"lon_deg, alt (geodetic); header is {table.header}")
    vel = _choose(velocity, "velocity", {"ecef": any(k in cols for k in V_KEYS),
                                         "ned": any(k in cols for k in NED_KEYS)}, src)
    if pos == "ecef":
        need = list(R_KEYS)
    else:
        need = ["lat" if "lat" in cols else "lat_deg", "lon" if "lon" in cols else "lon_deg",
                "alt"]
        if "alt" not in cols:
            if baro is None:
                raise src.error("'alt'", None, "missing column: latitude and longitude but "
                                               "no height (alt, altitude, height, ...); give a "
                                               "barometer record for the height (LOG 'imu.csv,"
                                               "gnss.csv,baro.csv', or baro=); header is "
                                               f"{table.header}")
            need.remove("alt")
    need += {"ecef": list(V_KEYS), "ned": list(NED_KEYS), None: []}[vel]
    if "sigma" in cols:
        need.append("sigma")
    elif "sigma_h" in cols or "sigma_v" in cols:
        need += ["sigma_h", "sigma_v"]
    _require(cols, ["t", *need], table, GNSS_SPECS)
    cols = {k: cols[k] for k in ["t", *need, *(["satellites"] if "satellites" in cols else [])]}
    values = parse_columns(table, cols)
    check_finite({k: v for k, v in values.items() if k != "satellites"}, cols, src)
    values, src, screened = screen_fixes(values, need, src,
                                         cols["satellites"].label if "satellites" in cols
                                         else None, keep_held)
    v_unit = None if length_unit is None else _units.VELOCITY_OF_LENGTH[
        _units.normalise(length_unit)]
    declared = {"time": ("time_unit", time_unit, "s"),
                "length": ("length_unit", length_unit, "m"),
                "velocity": ("length_unit", v_unit, "m/s"),
                "angle": ("angle_unit", angle_unit, "deg"),
                "degrees": ("lat_deg/lon_deg", None, "deg")}
    fac = column_factors(cols, {s.key: s.kind for s in GNSS_SPECS}, declared)
    t = values["t"] * fac["t"]
    check_times(t, src, cols["t"].label)
    check_sample_interval(t, src, cols["t"].label, "gnss", fac["t"])

    if pos == "ecef":
        r_e = np.column_stack([values[k] * fac[k] for k in R_KEYS])
        labels = _labels(cols, R_KEYS)
    else:
        kl, ko = need[0], need[1]
        lat, lon = values[kl] * fac[kl], values[ko] * fac[ko]
        _check_angles(lat, np.pi / 2, cols[kl], src, fac[kl])
        _check_angles(lon, 2 * np.pi, cols[ko], src, fac[ko])
        if "alt" in values:
            height = values["alt"] * fac["alt"]
        else:
            height = np.interp(t, baro["t"].to_numpy(dtype=float),
                               baro["alt_m"].to_numpy(dtype=float))
        r_e = geodetic_to_ecef(lat, lon, height)
        labels = _labels(cols, (kl, ko, "alt") if "alt" in cols else (kl, ko))
    if check_magnitudes:
        check_positions(r_e, src, labels, fac.get("x"))
    out = {"t": t, **dict(zip(R_KEYS, r_e.T, strict=True))}

    if vel is not None:
        keys = V_KEYS if vel == "ecef" else NED_KEYS
        v = np.column_stack([values[k] * fac[k] for k in keys])
        if vel == "ned":
            if pos == "ecef":
                lat, lon, _ = ecef_to_geodetic(r_e)
            v = np.einsum("kij,kj->ki", ned_to_ecef_matrix(lat, lon), v)
        if check_magnitudes:
            check_velocities(v, src, _labels(cols, keys))
        out.update(zip(V_KEYS, v.T, strict=True))
    if "sigma" in cols:
        check_positive(values["sigma"], src, cols["sigma"].label)
        out["sigma"] = values["sigma"] * fac["sigma"]
    elif "sigma_h" in cols:
        for k in ("sigma_h", "sigma_v"):
            check_positive(values[k], src, cols[k].label)
        s_h, s_v = values["sigma_h"] * fac["sigma_h"], values["sigma_v"] * fac["sigma_v"]
        out["sigma"] = combine_sigma(s_h, s_v)
    frame = pd.DataFrame(out)
    frame.attrs.update(source=str(path), position_input=pos, velocity_input=vel,
                       height_source="gnss" if pos == "ecef" or "alt" in cols else "baro",
                       **screened)
    return apply_gap_policy(frame, src, cols["t"].label, max_gap_s, on_gap)


def combine_sigma(sigma_h, sigma_v):
    """One per-axis position sigma from horizontal and vertical ones (trace preserving).

    ``sqrt((2 sigma_h^2 + sigma_v^2) / 3)``: sigma_h is the standard deviation along each
    horizontal axis (PX4 ``eph``, u-blox ``hAcc`` as EKF2 uses them), sigma_v the vertical
    (``epv``, ``vAcc``); the isotropic covariance ``sigma^2 I`` has the same trace as
    ``diag(sigma_h^2, sigma_h^2, sigma_v^2)``.

    Parameters
    ----------
    sigma_h, sigma_v : array_like
        Horizontal (per axis) and vertical standard deviations, m.

    Returns
    -------
    numpy.ndarray
        Per-axis sigma, m.
    """
    sigma_h = np.asarray(sigma_h, dtype=float)
    sigma_v = np.asarray(sigma_v, dtype=float)
    return np.sqrt((2.0 * sigma_h**2 + sigma_v**2) / 3.0)


def _check_angles(angle: np.ndarray, limit: float, col: Column, src, factor: float) -> None:
    bad = np.flatnonzero(np.abs(angle) > limit * (1 + 1e-12))
    if not bad.size:
        return
    k = int(bad[0])
    hint = ""
    if factor == 1.0 and np.all(np.abs(angle) <= np.rad2deg(limit)):
        hint = "; the values look like degrees: set angle_unit='deg'"
    raise src.error(col.label, k, f"angle {angle[k] / factor:.10g} is out of range "
                                  f"(|angle| <= {np.rad2deg(limit):g} deg){hint}")
