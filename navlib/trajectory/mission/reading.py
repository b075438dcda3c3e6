"""Mission files read and checked key by key: the :class:`Mission` record and the TOML tables.

:func:`read_mission` parses a file (path or example name of ``data/missions/``) or copies a
mapping; :func:`checked_number`, :func:`sub_table` and :func:`checked_outages` check one
value, table or outage list and name the file, table and key when they refuse it;
:func:`with_values` applies changes to a copy of the table (the plan's sweeps).
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.resources import data_dir, toml_names, toml_path

__all__ = ["MISSION_DIR", "Mission", "checked_number", "checked_outages", "list_missions",
           "mission_path", "read_mission", "sub_table", "with_values"]

MISSION_DIR = data_dir() / "missions"
"""Folder of the example missions (``data/missions/*.toml``, shipped in the wheel)."""


@dataclass(frozen=True)
class Mission:
    """A checked mission (SI inside, the file's own values in ``table``).

    Attributes
    ----------
    name, vehicle : str
    rate_hz : float
        IMU rate of the trajectory, Hz.
    sensors : str or None
        The mission's sensor preset (name or file), if it names one.
    gnss_rate_hz : float or None
        GNSS rate of the plan, Hz (None: the preset's).
    gnss_sigma_m : float or None
        GNSS position sigma per axis, m (None: the preset's).
    outages : tuple of (float, float)
        GNSS outage windows ``(start_s, end_s)``.
    table : dict
        The mission as read (a deep copy), for :func:`with_values` and the reports.
    where : str
        The file name (or ``"mission"``) that error messages start with.
    """

    name: str
    vehicle: str
    rate_hz: float
    sensors: str | None
    gnss_rate_hz: float | None
    gnss_sigma_m: float | None
    outages: tuple
    table: dict = field(repr=False)
    where: str = "mission"


def list_missions() -> list[str]:
    """Names of the example missions shipped in ``data/missions/`` (sorted)."""
    return toml_names(MISSION_DIR)


def mission_path(name_or_path) -> Path:
    """The file of an example mission name (``"multicopter_survey"``) or a path."""
    return toml_path(MISSION_DIR, name_or_path, "mission", "file", "example mission")


def read_mission(path_or_mapping) -> tuple[dict, str]:
    """The raw mission table and its label: a TOML file (path or example name) parsed, or a
    mapping deep-copied."""
    if isinstance(path_or_mapping, Mapping):
        return copy.deepcopy(dict(path_or_mapping)), "mission"
    if not isinstance(path_or_mapping, str | Path):
        raise NavlibInputError(f"mission: expected a TOML file, an example name or a mapping, "
                               f"got {type(path_or_mapping).__name__}")
    path = mission_path(path_or_mapping)
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise NavlibInputError(f"{path.name}: not valid TOML ({exc})") from exc
    return table, path.name


def checked_number(table: Mapping, key: str, where: str, low=None, high=None, low_open=False,
            default=None) -> float:
    """A number of a mission table, checked against its range.

    Parameters
    ----------
    table : Mapping
        The table.
    key : str
        Its key.
    where : str
        Where the table is, for the message.
    low, high : float or None, optional
        Range.
    low_open : bool, optional
        Exclude ``low``.
    default : float or None, optional
        Value when the key is missing; None: required.

    Returns
    -------
    float

    Raises
    ------
    NavlibInputError
        If the key is missing and required, or the value is not a number in range.
    """
    if key not in table:
        if default is None:
            raise NavlibInputError(f"{where}: missing key {key!r}")
        return float(default)
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise NavlibInputError(f"{where} {key}: expected a number, got {value!r}")
    return finite_scalar(value, f"{where} {key}", low, high, low_open)


def sub_table(parent: Mapping, key: str, where: str, required: bool = True) -> dict:
    """A sub-table of a mission table.

    Parameters
    ----------
    parent : Mapping
        The table.
    key : str
        The sub-table's key.
    where : str
        Where the table is, for the message.
    required : bool, optional
        Whether a missing sub-table is an error (else ``{}``).

    Returns
    -------
    dict

    Raises
    ------
    NavlibInputError
        If it is missing and required, or not a table.
    """
    if key not in parent:
        if required:
            raise NavlibInputError(f"{where}: missing table [{key}]")
        return {}
    value = parent[key]
    if not isinstance(value, Mapping):
        raise NavlibInputError(f"{where}: [{key}] must be a table, got {value!r}")
    return dict(value)


def checked_outages(gnss: Mapping, where: str) -> tuple:
    """The ``outages`` list of a ``[gnss]`` table, as ``(start_s, end_s)`` pairs.

    Parameters
    ----------
    gnss : Mapping
        The ``[gnss]`` table.
    where : str
        Where the table is, for the message.

    Returns
    -------
    tuple of (float, float)

    Raises
    ------
    NavlibInputError
        If the list or a pair is malformed, or an end is not after its start.
    """
    raw = gnss.get("outages", [])
    if not isinstance(raw, list):
        raise NavlibInputError(f"{where} [gnss] outages: expected a list of [start_s, end_s] "
                               f"pairs, got {raw!r}")
    out = []
    for i, pair in enumerate(raw):
        label = f"{where} [gnss] outages[{i}]"
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise NavlibInputError(f"{label}: expected [start_s, end_s], got {pair!r}")
        a = finite_scalar(pair[0], f"{label} start_s", 0.0)
        b = finite_scalar(pair[1], f"{label} end_s", a, low_open=True)
        out.append((a, b))
    return tuple(sorted(out))


def with_values(mission, changes: Mapping) -> dict:
    """A copy of the mission table with ``changes`` applied: ``{"rate_hz": 50}`` for a top
    key, ``{"rocket.spin_hz": 1.0}`` or ``{"gnss.outages": [[30, 40]]}`` for a key of a
    table, ``{"phase.2.burn_time_s": 20}`` / ``{"waypoint.3.speed_m_s": 8}`` for a key of
    the n-th (0-based) phase or waypoint. Returns the mapping (give it to
    :func:`from_mission` or :func:`load_mission`).

    Parameters
    ----------
    mission : Mission or path-like
        A loaded mission or a mission file.
    changes : Mapping
        Dotted key -> new value.

    Raises
    ------
    NavlibInputError
        If a key names no table of the mission.
    """
    table = mission.table if isinstance(mission, Mission) else read_mission(mission)[0]
    table = copy.deepcopy(table)
    for key, value in dict(changes).items():
        parts = str(key).split(".")
        target = table
        try:
            for part in parts[:-1]:
                target = target[int(part)] if isinstance(target, list) else \
                    target.setdefault(part, {})
        except (IndexError, ValueError, AttributeError) as exc:
            raise NavlibInputError(f"changes: {key!r} names no table of the mission "
                                   f"({exc})") from exc
        if not isinstance(target, dict):
            raise NavlibInputError(f"changes: {key!r} names no table of the mission")
        target[parts[-1]] = value
    return table
