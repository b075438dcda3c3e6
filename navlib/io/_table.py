"""Reading numeric text tables with exact file/column/line bookkeeping for error messages.

A CSV file is read as text first so that every data row keeps its 1-based line number in the
file (blank lines and ``#`` comment lines are skipped but counted). Only the columns a reader
asks for are parsed (by pandas' C parser); every failure is a :class:`NavlibInputError` that
names the file, the column and the line.
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from navlib.errors import FlightDataWarning, NavlibInputError
from navlib.io import _units


@dataclass(frozen=True)
class Source:
    """Where rows come from, for messages: ``label`` plus a way to name row ``k``.

    ``lines`` holds the number of each data row in the source: its 1-based file line (CSV,
    ``row_word="line"``) or its 0-based message index in a log topic (``"message"``);
    without it rows are named ``sample k``.
    """

    label: str
    lines: np.ndarray | None = None
    raw: Sequence[str] | None = None
    sep: str | None = None
    row_word: str = "line"

    def where(self, row: int) -> str:
        if self.lines is not None:
            return f"{self.row_word} {int(self.lines[row])}"
        return f"sample {row}"

    def cell(self, row: int, field: int | None) -> str | None:
        """Raw text of field ``field`` of data row ``row`` (None when not a text table)."""
        if self.raw is None or field is None:
            return None
        parts = self.raw[row].split(self.sep) if self.sep else self.raw[row].split()
        return parts[field].strip() if field < len(parts) else None

    def error(self, column: str | None, row: int | None, problem: str) -> NavlibInputError:
        parts = [self.label]
        if column:
            parts.append(f"column {column}")
        if row is not None:
            parts.append(self.where(row))
        return NavlibInputError(", ".join(parts) + ": " + problem)


@dataclass(frozen=True)
class ColumnSpec:
    """One canonical column a reader understands: its key, accepted aliases, unit kind."""

    key: str
    aliases: tuple[str, ...]
    kind: str | None = None
    implied: tuple[tuple[str, str], ...] = ()
    """(alias, unit) pairs for aliases that carry their unit, e.g. ``("time_us", "us")``."""


@dataclass(frozen=True)
class Column:
    """A resolved column: canonical ``key``, the file's header text, field index, header unit."""

    key: str
    header: str
    field: int | None
    unit: str | None = None

    @property
    def label(self) -> str:
        return repr(self.header) if self.header == self.key else f"{self.header!r} ({self.key})"


@dataclass(frozen=True)
class TextTable:
    """A text table split into header fields and data lines, with their file line numbers."""

    header: list[str]
    source: Source


_BRACKET = re.compile(r"^(.*?)\s*[\[(]([^\[\]()]*)[\])]$")


def split_header_name(name: str) -> tuple[str, str | None]:
    """Normalised column name and the unit written in brackets, if any.

    ``"Acc X [m/s^2]"`` -> ``("acc_x", "m/s^2")``; an index in brackets is kept as a suffix
    (``"gyro_rad[0]"`` -> ``("gyro_rad_0", None)``, the ``ulog2csv`` spelling).
    """
    s = name.strip().strip("\"'").strip()
    unit = None
    m = _BRACKET.match(s)
    if m:
        base, inner = m.group(1), m.group(2).strip()
        if inner.isdigit():
            s = f"{base}_{inner}"
        else:
            s, unit = base, inner
    s = re.sub(r"[\s\-.]+", "_", s.lower()).strip("_")
    return s, unit


def _looks_numeric(text: str) -> bool:
    try:
        float(text.strip().strip("\"'"))
    except ValueError:
        return False
    return True


def existing_file(path) -> tuple[Path, str]:
    """``(Path, "file '...'")`` for an existing regular file; NavlibInputError otherwise."""
    p = Path(path)
    label = f"file '{p}'"
    if not p.exists():
        raise NavlibInputError(f"{label}: file not found")
    if not p.is_file():
        raise NavlibInputError(f"{label}: not a regular file")
    return p, label


def read_text_table(path, sep: str | None = None, *, header_prefix: str | None = None,
                    repair_header=None) -> TextTable:
    """Read ``path`` as a delimited text table with a header row.

    ``sep`` None detects ``,``, ``;``, tab or blanks from the header line. ``header_prefix``
    (e.g. ``"#version"``, the AltOS export) names a ``#`` line that is the header rather than
    a comment when it is the first non-blank line; its leading ``#`` is dropped.
    ``repair_header(header, fields, label)``, when given, is called when every data row has
    ``fields`` fields (one count, after a cut last row is dropped) but the header names
    another number: it returns the header to read the rows with, or raises saying why not.
    """
    p, label = existing_file(path)
    data = p.read_bytes()
    if not data.strip():
        raise NavlibInputError(f"{label}: file is empty")
    if b"\x00" in data[:4096]:
        raise NavlibInputError(
            f"{label}: binary file, not a CSV text table (PX4 .ulg logs: use read_ulog)"
        )
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise NavlibInputError(f"{label}: not UTF-8 text ({exc.reason} at byte {exc.start})") \
            from exc
    lines = text.splitlines()
    first = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    named = (header_prefix is not None and first is not None
             and lines[first].lstrip().startswith(header_prefix))
    if named:
        lines[first] = lines[first].lstrip()[1:]
    keep = [i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    if not keep:
        raise NavlibInputError(f"{label}: no header and no data (only blank or # comment lines)")
    head_i = keep[0]
    head = lines[head_i]
    if sep is None:
        sep = next((c for c in (",", ";", "\t") if c in head), None)
    header = [h.strip().strip("\"'") for h in (head.split(sep) if sep else head.split())]
    if all(_looks_numeric(h) for h in header):
        raise NavlibInputError(
            f"{label}, line {head_i + 1}: looks like data, not a header row; the first "
            f"non-comment line must name the columns"
        )
    data_i = np.asarray(keep[1:], dtype=np.int64)
    raw = [lines[i] for i in data_i]
    source = Source(label, data_i + 1, raw, sep)
    if not raw:
        raise NavlibInputError(f"{label}: no data rows after the header (line {head_i + 1})")
    if sep:
        counts = np.fromiter((ln.count(sep) for ln in raw), dtype=np.int64, count=len(raw)) + 1
    else:
        counts = np.fromiter((len(ln.split()) for ln in raw), dtype=np.int64, count=len(raw))
    last = len(raw) - 1
    cut = last > 0 and (counts[last] < max(len(header), counts[last - 1]) or (
        sep is not None and raw[last].rstrip().endswith(sep)
        and not raw[last - 1].rstrip().endswith(sep)))
    if cut:
        _warn_cut(label, int(data_i[last]) + 1, counts[last], len(header))
        raw, data_i, counts = raw[:last], data_i[:last], counts[:last]
        source = Source(label, data_i + 1, raw, sep)
    if (repair_header is not None and counts.size and np.all(counts == counts[0])
            and counts[0] != len(header)):
        header = list(repair_header(header, int(counts[0]), label))
    bad = np.flatnonzero(counts != len(header))
    if bad.size:
        k = int(bad[0])
        raise source.error(None, k, f"row has {counts[k]} fields but the header has "
                                    f"{len(header)}")
    return TextTable(header, source)


def _warn_cut(label: str, line: int, fields: int, expected: int) -> None:
    """A last row cut mid-write (a logger that lost power) is dropped, with a warning."""
    warnings.warn(f"{label}, line {line}: the last row was cut mid-write ({fields} of "
                  f"{expected} fields, or its last field empty); it is dropped",
                  FlightDataWarning, stacklevel=4)


def resolve_columns(table: TextTable, specs: Sequence[ColumnSpec],
                    columns: Mapping[str, str] | None = None) -> dict[str, Column]:
    """Match the header against ``specs`` (aliases, case-insensitive) and explicit ``columns``.

    Returns the columns found, by canonical key. Raises on duplicate header names, on two
    headers giving the same key, and on ``columns`` entries naming unknown keys or headers.
    """
    src = table.source
    names = [split_header_name(h) for h in table.header]
    by_key = {s.key: s for s in specs}
    implied = {a: u for s in specs for a, u in s.implied}
    found: dict[str, Column] = {}
    explicit = dict(columns or {})
    unknown = sorted(set(explicit) - set(by_key))
    if unknown:
        raise NavlibInputError(
            f"columns: unknown key(s) {unknown}; accepted: {sorted(by_key)}"
        )
    for key, wanted in explicit.items():
        hits = [i for i, h in enumerate(table.header)
                if h == str(wanted) or names[i][0] == split_header_name(str(wanted))[0]]
        if not hits:
            raise src.error(None, None, f"columns={{{key!r}: {wanted!r}}}: no such column in "
                                        f"the header {table.header}")
        if len(hits) > 1:
            raise src.error(repr(str(wanted)), None,
                            f"appears {len(hits)} times in the header (fields "
                            f"{[h + 1 for h in hits]}); column names must be unique")
        i = hits[0]
        found[key] = Column(key, table.header[i], i, names[i][1] or implied.get(names[i][0]))
    taken = {c.field for c in found.values()}
    alias_key = {a: s.key for s in specs if s.key not in found for a in (s.key, *s.aliases)}
    for i, (norm, unit) in enumerate(names):
        key = alias_key.get(norm)
        if key is None or i in taken:
            continue
        unit = unit if unit is not None else implied.get(norm)
        if key in found:
            first = found[key]
            if split_header_name(first.header)[0] == norm:
                problem = (f"duplicate column: appears in fields {first.field + 1} and {i + 1} "
                           f"of the header")
            else:
                problem = (f"columns {first.header!r} and {table.header[i]!r} both give "
                           f"{key!r}; keep one, or choose with columns={{{key!r}: ...}}")
            raise src.error(repr(table.header[i]), None, problem)
        found[key] = Column(key, table.header[i], i, unit)
    return found


def parse_columns(table: TextTable, cols: Mapping[str, Column]) -> dict[str, np.ndarray]:
    """Parse the resolved columns as floats; non-numeric cells raise naming column and line.

    NaN, infinite and empty cells are returned as NaN/inf: :func:`check_finite` reports them.
    """
    src = table.source
    fields = sorted({c.field for c in cols.values()})
    try:
        frame = pd.read_csv(io.StringIO("\n".join(src.raw)), sep=src.sep or r"\s+",
                            header=None, usecols=fields, skip_blank_lines=False,
                            engine="c", low_memory=False)
    except (ValueError, pd.errors.ParserError) as exc:
        raise src.error(None, None, f"cannot be parsed as a table: {exc}") from exc
    out = {}
    for key, col in cols.items():
        series = frame[col.field]
        if not pd.api.types.is_numeric_dtype(series.dtype):
            text = series.astype(str).str.strip()          # padded cells such as '    nan'
            num = pd.to_numeric(text.where(series.notna()), errors="coerce")
            nan_word = text.str.lower().isin(("nan", "")).to_numpy()
            bad = np.flatnonzero(num.isna().to_numpy() & series.notna().to_numpy()
                                 & ~nan_word)
            if bad.size:
                k = int(bad[0])
                raise src.error(col.label, k, f"non-numeric value {series.iloc[k]!r}")
            series = num
        out[key] = series.to_numpy(dtype=float, na_value=np.nan)
    return out


def check_finite(values: Mapping[str, np.ndarray], cols: Mapping[str, Column],
                 source: Source) -> None:
    """Raise on the first NaN, infinite or empty cell, naming column and row."""
    for key, arr in values.items():
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            k = int(bad[0])
            col = cols[key]
            raw = source.cell(k, col.field)
            if raw == "":
                what = "empty cell"
            elif raw is not None:
                what = f"value {raw!r} is not a finite number"
            else:
                what = f"value {arr[k]} is not a finite number"
            more = f" ({bad.size} such rows)" if bad.size > 1 else ""
            raise source.error(col.label, k, what + more)


def check_declared(declared: Mapping[str, tuple[str, str | None, str]]) -> None:
    """Every unit a keyword declared (``declared`` as in :func:`column_factors`) is one
    :mod:`navlib.io._units` knows, checked before the file is read (a NavlibInputError
    names the keyword)."""
    for kind, (keyword, value, _) in declared.items():
        if value is not None:
            _units.factor(kind, value, keyword)


def column_factors(cols: Mapping[str, Column], kinds: Mapping[str, str],
                   declared: Mapping[str, tuple[str, str | None, str]]) -> dict[str, float]:
    """SI factor per column: the declared keyword unit, or the header's bracketed unit.

    ``kinds`` maps column key -> unit kind; ``declared`` maps unit kind -> (keyword name,
    declared unit or None, default unit). A header unit that contradicts an explicitly
    declared one raises; a header unit that is not understood raises.
    """
    out = {}
    for key, col in cols.items():
        kind = kinds.get(key)
        if kind is None:
            continue
        keyword, value, default = declared[kind]
        if col.unit is not None:
            head = _units.factor(kind, col.unit, f"column {col.label} header unit")
            if value is not None and not np.isclose(
                    head, _units.factor(kind, value, keyword), rtol=1e-12, atol=0.0):
                raise NavlibInputError(
                    f"column {col.label}: the header says {col.unit!r} but {keyword}="
                    f"{value!r} was declared; fix one of them"
                )
            out[key] = head
        else:
            out[key] = _units.factor(kind, value if value is not None else default, keyword)
    return out
