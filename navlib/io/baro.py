"""Barometer CSV files: time and static pressure or barometric altitude, SI out.

File format as :mod:`navlib.io.csv_files` (delimiter detected, ``#`` comments, header names
case-insensitive, units in brackets). Columns (normalised names; full lists in
:data:`BARO_COLUMNS`):

=================  ===================================================  =========================
column             accepted names                                       unit
=================  ===================================================  =========================
``t``              t, ts, time, timestamp, time_s, time_ms, ...         ``time_unit`` (s)
``pressure_pa``    pressure_pa, pressure, pressure_pascals, p, press,   ``pressure_unit``: ``Pa``
                   baro_pressure, static_pressure, pressure_hpa,        ``hPa`` ``mbar`` ``kPa``
                   pressure_mbar                                        (Pa)
``altitude_m``     altitude_m, altitude, alt, baro_alt, baro_altitude,  ``length_unit`` (m)
                   baro_alt_meter, pressure_altitude, height
``temperature_c``  temperature_c, temperature, temp,                    deg C (kept, not used)
                   temperature_celsius
=================  ===================================================  =========================

A file needs ``t`` and one of ``pressure_pa`` / ``altitude_m`` (with both, the pressure is
used: ``altitude="given"`` keeps the file's altitude instead). Pressure becomes altitude
with the standard atmosphere (:func:`pressure_altitude`, assumptions.md B1): only its
*changes* are used by the assessment (the pad height is subtracted), so the unknown
sea-level pressure of the day cancels.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError
from navlib.io._table import (
    ColumnSpec,
    check_declared,
    check_finite,
    column_factors,
    parse_columns,
    read_text_table,
    resolve_columns,
)
from navlib.io.checks import check_times
from navlib.io.csv_files import _TIME_ALIASES, _TIME_IMPLIED

__all__ = ["ALTITUDE_RANGE_M", "BARO_COLUMNS", "BARO_KEYS", "BARO_SPECS", "ISA_EXPONENT",
           "ISA_LAPSE_K_M", "ISA_P0_PA", "ISA_T0_K", "PRESSURE_RANGE_PA", "baro_height",
           "pressure_altitude", "read_baro_csv"]

ISA_P0_PA = 101_325.0
"""Standard sea-level pressure, Pa (ISO 2533)."""
ISA_T0_K = 288.15
"""Standard sea-level temperature, K."""
ISA_LAPSE_K_M = 0.0065
"""Standard tropospheric temperature lapse rate, K/m."""
ISA_EXPONENT = 0.190263
"""``R L / g0`` of the standard troposphere (R = 287.05287 J/(kg K), g0 = 9.80665 m/s^2)."""
PRESSURE_RANGE_PA = (1_000.0, 120_000.0)
"""Plausible static pressures, Pa: about 31 km altitude to below sea level; outside, the
unit is probably wrong (hPa read as Pa)."""
ALTITUDE_RANGE_M = (-1_000.0, 40_000.0)
"""Plausible barometric altitudes, m."""

BARO_SPECS = (
    ColumnSpec("t", ("ts", *_TIME_ALIASES), "time", _TIME_IMPLIED),
    ColumnSpec("pressure_pa", ("pressure", "pressure_pascals", "p", "press", "baro_pressure",
                               "static_pressure", "pressure_hpa", "pressure_mbar"),
               "pressure", (("pressure_pa", "Pa"), ("pressure_pascals", "Pa"),
                            ("pressure_hpa", "hPa"), ("pressure_mbar", "mbar"))),
    ColumnSpec("altitude_m", ("altitude", "alt", "alt_m", "baro_alt", "baro_altitude",
                              "baro_alt_meter", "pressure_altitude", "height"), "length",
               (("altitude_m", "m"), ("alt_m", "m"), ("baro_alt_meter", "m"))),
    ColumnSpec("temperature_c", ("temperature", "temp", "temperature_celsius", "temp_c")),
)
BARO_COLUMNS = {s.key: s.aliases for s in BARO_SPECS}
"""Accepted header names (after normalisation) for each barometer column."""
BARO_KEYS = ("t", "alt_m")
"""Columns of a barometer DataFrame every reader returns: time s, altitude m."""


def pressure_altitude(pressure_pa) -> np.ndarray:
    """Standard-atmosphere altitude of a static pressure, m (assumptions.md B1).

    ``h = T0 / L (1 - (p / p0)^(R L / g0))``, the ISA troposphere: within a few metres of
    the true height change over a rocket flight's first kilometres when the day's
    temperature is near standard; its scale error (about 0.35 % per 1 K of the mean
    temperature offset) is the barometer sigma's height-proportional part
    (:mod:`navlib.models.baro`).
    """
    p = np.asarray(pressure_pa, dtype=float)
    return ISA_T0_K / ISA_LAPSE_K_M * (1.0 - (p / ISA_P0_PA) ** ISA_EXPONENT)


def read_baro_csv(path, *, time_unit: str | None = None, pressure_unit: str | None = None,
                  length_unit: str | None = None, columns: Mapping[str, str] | None = None,
                  sep: str | None = None, altitude: str = "pressure") -> pd.DataFrame:
    """Read a barometer record (time and pressure or altitude) from a CSV file.

    Parameters
    ----------
    path : str or Path
        The CSV file (format in the module docstring).
    time_unit, pressure_unit, length_unit : str, optional
        ``s``/``ms``/``us``/``ns``; ``Pa``/``hPa``/``mbar``/``kPa``; ``m``/``mm``/``km``.
        None: the unit in the header brackets or implied by the name, else s, Pa, m.
    columns : mapping, optional
        Explicit ``{canonical: header}`` choices (``{"pressure_pa": "P"}``).
    sep : str, optional
        Field separator; detected when None.
    altitude : {"pressure", "given"}
        With both columns, the altitude from the pressure (default) or the file's own.

    Returns
    -------
    DataFrame
        ``t`` (s), ``alt_m`` (m; standard-atmosphere altitude of the pressure, or the
        file's), plus ``pressure_pa`` and ``temperature_c`` when present. ``attrs``:
        ``source``, ``altitude_input`` (``"pressure"`` or ``"altitude"``).

    Raises
    ------
    NavlibInputError
        Naming file, column and line: no time column, neither pressure nor altitude,
        non-numeric or non-finite cells (an all-empty ``temperature_c`` column is ignored),
        non-increasing times, pressures or altitudes outside :data:`PRESSURE_RANGE_PA` /
        :data:`ALTITUDE_RANGE_M` (with the unit that would fit).
    """
    if altitude not in ("pressure", "given"):
        raise NavlibInputError(f"altitude: expected 'pressure' or 'given', got {altitude!r}")
    declared = {"time": ("time_unit", time_unit, "s"),
                "pressure": ("pressure_unit", pressure_unit, "Pa"),
                "length": ("length_unit", length_unit, "m")}
    check_declared(declared)
    table = read_text_table(path, sep)
    src = table.source
    cols = resolve_columns(table, BARO_SPECS, columns)
    if "t" not in cols:
        raise src.error("'t'", None, f"missing column (accepted names include t, ts, time, "
                                     f"timestamp, time_s, time_ms); header is {table.header}")
    use = "pressure_pa" if "pressure_pa" in cols else "altitude_m" if "altitude_m" in cols \
        else None
    if use is None:
        raise src.error(None, None, "a barometer file needs a pressure column (pressure_pa, "
                                    "pressure, p [hPa], ...) or an altitude column "
                                    f"(altitude_m, alt, baro_alt, ...); header is "
                                    f"{table.header}")
    if use == "pressure_pa" and "altitude_m" in cols and altitude == "given":
        use = "altitude_m"
    keys = ["t", use] + (["temperature_c"] if "temperature_c" in cols else [])
    cols = {k: cols[k] for k in keys}
    values = parse_columns(table, cols)
    if "temperature_c" in values and not np.isfinite(values["temperature_c"]).any():
        del values["temperature_c"], cols["temperature_c"]   # an empty optional column
    check_finite(values, cols, src)
    fac = column_factors(cols, {s.key: s.kind for s in BARO_SPECS}, declared)
    t = values["t"] * fac["t"]
    check_times(t, src, cols["t"].label)
    out = {"t": t}
    if use == "pressure_pa":
        p = values["pressure_pa"] * fac["pressure_pa"]
        _check_range(p, PRESSURE_RANGE_PA, cols["pressure_pa"].label, "Pa", src,
                      {"hPa": 100.0, "kPa": 1e3})
        out["alt_m"] = pressure_altitude(p)
        out["pressure_pa"] = p
    else:
        out["alt_m"] = values["altitude_m"] * fac["altitude_m"]
        _check_range(out["alt_m"], ALTITUDE_RANGE_M, cols["altitude_m"].label, "m", src,
                     {"km": 1e3})
    if "temperature_c" in values:
        out["temperature_c"] = values["temperature_c"]
    frame = pd.DataFrame(out)
    frame.attrs.update(source=str(path),
                       altitude_input="pressure" if use == "pressure_pa" else "altitude")
    return frame


def _check_range(x, bounds, label, unit, src, hints) -> None:
    low, high = bounds
    bad = np.flatnonzero((x < low) | (x > high))
    if not bad.size:
        return
    k = int(bad[0])
    hint = next((f"; the values look like {name}: declare the unit (e.g. '{label} [{name}]')"
                 for name, f in hints.items() if np.all((x * f >= low) & (x * f <= high))), "")
    raise src.error(label, k, f"{x[k]:.6g} {unit} is outside the plausible "
                              f"{low:g}..{high:g} {unit}{hint}")


def baro_height(baro: pd.DataFrame | None, t) -> np.ndarray | None:
    """The barometric altitude at times ``t`` (linear interpolation, held at the ends), or
    None without a barometer frame.

    Parameters
    ----------
    baro : pandas.DataFrame or None
        Barometer record (``t``, s; ``alt_m``, m).
    t : array_like
        Times, s.

    Returns
    -------
    numpy.ndarray or None
        Altitude, m.
    """
    if baro is None or len(baro) < 2:
        return None
    return np.interp(np.asarray(t, dtype=float), baro["t"].to_numpy(dtype=float),
                     baro["alt_m"].to_numpy(dtype=float))
