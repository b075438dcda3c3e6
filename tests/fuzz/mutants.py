"""Small valid flight logs of every kind navlib reads, seeded mutations of them, and a run of
each mutant through its reader and :func:`navlib.studies.assess.assess_flight` under a time
limit (the fuzz tests of ``test_fuzz_assess.py``).

Kinds (:data:`navlib.io.LOG_KINDS`): an ``imu.csv,gnss.csv`` pair, an ``imu.csv,baro.csv``
pair (no GNSS: the barometric altitude of the GNSS heights) and a DataFlash ``.bin`` of a
simulated 24 s multicopter flight (``tests/support/flights.py``,
``tests/support/dataflash_writer.py``), AltOS exports of both header generations and an
EasyMega export without GPS (the exports' 0.3 s on the pad; ``tests/support/altos_writer.py``)
and, when the shared logs are present (``tests/support/locations.py``), a PX4 ULog cut from a
public sample log to its first seconds. :func:`real_originals` adds the shared logs
themselves (read at run time, never copied into the repository).

A mutant is one seeded damage of one file: cut, flipped or zeroed bytes, a deleted,
duplicated or moved block; for text files also deleted, duplicated or swapped rows, a
damaged field, a column set to zero, CRLF line ends, a byte-order mark, the header alone.
:func:`frame_mutant` damages the ``imu, gnss`` DataFrames a user hands to ``assess_flight``
without a reader (rows out of order, NaN cells, repeated times, missing or string columns...).
An outcome is ``assessed``, ``refused`` (:class:`navlib.NavlibInputError`), ``bare`` (any
other exception: a bug) or ``hung`` (over the time limit).
"""

from __future__ import annotations

import signal
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from support.altos_writer import rocket_rows, write_altos
from support.dataflash_writer import write_flight
from support.flights import dataflash_flight
from support.locations import SHARED_DATA

from navlib import NavlibInputError, io
from navlib.earth import ecef_to_geodetic
from navlib.studies.assess import assess_flight

OUTCOMES = ("assessed", "refused", "bare", "hung")


@dataclass(frozen=True)
class Original:
    """A valid log: its kind, its file(s) (one, or ``imu.csv, gnss.csv``), text or binary."""

    name: str
    kind: str
    files: tuple[Path, ...]

    @property
    def text(self) -> bool:
        return self.kind in ("csv", "altos")


@dataclass(frozen=True)
class Mutant:
    """One damaged copy of an :class:`Original`: the ``LOG`` argument naming its file(s)
    and what was done (``what``, for the failure message)."""

    spec: str
    what: str


# --------------------------------------------------------------------------- originals


def _cut_ulog(source: Path, path: Path, seconds: float) -> None:
    """The first ``seconds`` of a ULog, written with pyulog."""
    from pyulog import ULog

    log = ULog(str(source), message_name_filter_list=[
        "sensor_combined", "vehicle_gps_position", "sensor_gps", "vehicle_attitude",
        "vehicle_air_data", "vehicle_status"])
    t0 = min(d.data["timestamp"][0] for d in log.data_list)
    for d in log.data_list:
        keep = d.data["timestamp"] < t0 + int(seconds * 1e6)
        d.data = {k: v[keep] for k, v in d.data.items()}
    log.write_ulog(str(path))


def generated_originals(folder: Path) -> list[Original]:
    """The small valid logs written here (and the ULog cut from a shared sample log, when
    present)."""
    folder.mkdir(parents=True, exist_ok=True)
    _, imu, gnss, geo, att = dataflash_flight()
    io.write_imu_csv(imu, folder / "imu.csv")
    io.write_gnss_csv(gnss, folder / "gnss.csv")
    out = [Original("csv pair", "csv", (folder / "imu.csv", folder / "gnss.csv"))]
    write_flight(folder / "flight.bin", imu, geo, att, layout="4.x", imu_instances=(0, 1))
    out.append(Original("dataflash", "dataflash", (folder / "flight.bin",)))
    _, _, h = ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    pd.DataFrame({"t": gnss["t"], "altitude_m": h}).to_csv(folder / "baro.csv", index=False)
    out.append(Original("csv imu+baro", "csv", (folder / "imu.csv", folder / "baro.csv")))
    rows = rocket_rows()
    for generation in ("version", "legacy"):
        path = folder / f"altos-{generation}.csv"
        write_altos(path, rows, generation=generation)
        out.append(Original(f"altos {generation}", "altos", (path,)))
    write_altos(folder / "easymega.csv", rocket_rows(), board="easymega")
    out.append(Original("altos easymega", "altos", (folder / "easymega.csv",)))
    source = SHARED_DATA / "px4" / "sample_log_small.ulg"
    if source.is_file():
        _cut_ulog(source, folder / "cut.ulg", 20.0)
        out.append(Original("ulog (cut)", "ulog", (folder / "cut.ulg",)))
    return out


REAL = (("altos", "altos", "2019-05-26-serial-1257-flight-0018.csv"),
        ("dataflash", "ardupilot", "sitl_copter_flight.bin"),
        ("ulog", "px4", "sample_log_small.ulg"))
"""The shared logs of :func:`real_originals`: kind, folder of ``../shared/data``, file."""


def real_originals() -> list[Original]:
    """The shared public logs of :data:`REAL` that are present (mutated copies are written
    to the test's temporary folder, never to the repository)."""
    return [Original(f"{kind} {name}", kind, (SHARED_DATA / folder / name,))
            for kind, folder, name in REAL if (SHARED_DATA / folder / name).is_file()]


# --------------------------------------------------------------------------- mutations

BAD_FIELDS = ("", "nan", "inf", "-inf", "-", "1e400", "abc", "9" * 40, "0x1f", "1,5", " ",
              "-0", "1e-400", "\"", "NaN NaN")
TEXT_DAMAGES = ("cut", "flip", "zero", "block", "delete rows", "duplicate rows", "swap rows",
                "field", "zero column", "crlf", "bom", "header only", "few rows", "scale column",
                "constant column", "decimate", "shift time")
BINARY_DAMAGES = ("cut", "flip", "zero", "block", "delete block", "duplicate block",
                  "swap blocks")


def _span(rng, n: int, longest: int) -> tuple[int, int]:
    start = int(rng.integers(0, max(n, 1)))
    return start, min(n, start + int(rng.integers(1, longest + 1)))


def _bytes_damage(rng, data: bytes, damage: str) -> tuple[bytes, str]:
    n = len(data)
    if damage == "cut":
        at = int(rng.integers(0, n))
        return data[:at], f"cut at byte {at} of {n}"
    if damage == "flip":
        out = bytearray(data)
        where = rng.integers(0, n, size=int(rng.integers(1, 9)))
        for k in where:
            out[k] = int(rng.integers(0, 256))
        return bytes(out), f"{where.size} byte(s) overwritten from {int(where.min())}"
    if damage == "zero":
        a, b = _span(rng, n, 512)
        return data[:a] + bytes(b - a) + data[b:], f"bytes {a}..{b} zeroed"
    if damage == "block":
        a, b = _span(rng, n, 64)
        junk = rng.integers(0, 256, size=int(rng.integers(1, 65)), dtype=np.uint8).tobytes()
        return data[:a] + junk + data[b:], f"bytes {a}..{b} replaced by {len(junk)} random"
    if damage == "delete block":
        a, b = _span(rng, n, 4096)
        return data[:a] + data[b:], f"bytes {a}..{b} deleted"
    if damage == "duplicate block":
        a, b = _span(rng, n, 4096)
        return data[:b] + data[a:b] + data[b:], f"bytes {a}..{b} duplicated"
    a, b = _span(rng, n // 2, 2048)
    c, d = _span(rng, n - n // 2, 2048)
    c, d = c + n // 2, d + n // 2
    if b > c:
        return data, "no swap"
    return (data[:a] + data[c:d] + data[b:c] + data[a:b] + data[d:],
            f"bytes {a}..{b} and {c}..{d} swapped")


def _with_cell(row: bytes, k: int, change) -> bytes:
    cells = row.split(b",")
    if k < len(cells):
        cells[k] = change(cells[k])
    return b",".join(cells)


def _scaled(cell: bytes, factor: float, offset: float = 0.0) -> bytes:
    try:
        return repr(float(cell) * factor + offset).encode()
    except ValueError:
        return cell


def _time_column(header: bytes) -> int:
    names = [c.strip().lstrip(b"#").split(b" ")[0].lower() for c in header.split(b",")]
    for name in (b"time", b"t"):
        if name in names:
            return names.index(name)
    return 0


def _text_damage(rng, data: bytes, damage: str) -> tuple[bytes, str]:
    lines = data.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    head, rows = lines[:1], lines[1:]
    n = len(rows)
    if damage in BINARY_DAMAGES or n < 2:
        return _bytes_damage(rng, data, damage if damage in BINARY_DAMAGES else "cut")
    if damage == "delete rows":
        a, b = _span(rng, n, max(n // 4, 1))
        rows = rows[:a] + rows[b:]
        what = f"rows {a + 1}..{b} deleted"
    elif damage == "duplicate rows":
        a, b = _span(rng, n, 20)
        rows = rows[:b] + rows[a:b] + rows[b:]
        what = f"rows {a + 1}..{b} duplicated"
    elif damage == "swap rows":
        i, j = sorted(int(k) for k in rng.integers(0, n, size=2))
        rows[i], rows[j] = rows[j], rows[i]
        what = f"rows {i + 1} and {j + 1} swapped"
    elif damage == "field":
        i = int(rng.integers(0, n))
        cells = rows[i].split(b",")
        k = int(rng.integers(0, len(cells)))
        cells[k] = BAD_FIELDS[int(rng.integers(0, len(BAD_FIELDS)))].encode()
        rows[i] = b",".join(cells)
        what = f"row {i + 1} field {k + 1} set to {cells[k]!r}"
    elif damage == "zero column":
        k = int(rng.integers(0, len(rows[0].split(b","))))
        rows = [_with_cell(r, k, lambda c: b"0") for r in rows]
        what = f"column {k + 1} set to 0"
    elif damage == "few rows":
        keep = int(rng.choice([1, 2, 3, 5, 9, 12, 30]))
        rows = rows[:keep]
        what = f"the first {keep} row(s) kept"
    elif damage == "scale column":
        k = int(rng.integers(0, len(rows[0].split(b","))))
        factor = float(rng.choice([1e3, 1e-3, -1.0, 0.1, 9.80665]))
        rows = [_with_cell(r, k, lambda c: _scaled(c, factor)) for r in rows]
        what = f"column {k + 1} times {factor:g}"
    elif damage == "constant column":
        k = int(rng.integers(0, len(rows[0].split(b","))))
        first = rows[0].split(b",")[k] if k < len(rows[0].split(b",")) else b""
        rows = [_with_cell(r, k, lambda c: first) for r in rows]
        what = f"column {k + 1} held at its first value {first!r}"
    elif damage == "decimate":
        step = int(rng.choice([2, 5, 20, 100]))
        rows = rows[::step]
        what = f"every {step}th row kept"
    elif damage == "shift time":
        k = _time_column(head[0])
        offset = float(rng.choice([-1e3, -20.0, 0.5, 20.0, 1e6]))
        rows = [_with_cell(r, k, lambda c: _scaled(c, 1.0, offset)) for r in rows]
        what = f"time column {k + 1} shifted by {offset:g}"
    elif damage == "crlf":
        return data.replace(b"\n", b"\r\n"), "CRLF line ends"
    elif damage == "bom":
        return b"\xef\xbb\xbf" + data, "UTF-8 byte-order mark"
    else:
        return b"\n".join(head) + b"\n", "header only"
    return b"\n".join(head + rows) + b"\n", what


def mutants(originals: list[Original], folder: Path, per_original: int,
            seed: int) -> list[Mutant]:
    """``per_original`` seeded mutants of each original, written under ``folder``: one file
    of the original damaged (for a CSV pair, the IMU or the GNSS file), the damages drawn
    in turn from :data:`TEXT_DAMAGES` or :data:`BINARY_DAMAGES` from a seeded start."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for o, original in enumerate(originals):
        damages = TEXT_DAMAGES if original.text else BINARY_DAMAGES
        first = int(rng.integers(0, len(damages)))
        for m in range(per_original):
            damage = damages[(first + m) % len(damages)]
            which = int(rng.integers(0, len(original.files)))
            source = original.files[which]
            data = source.read_bytes()
            damaged, what = (_text_damage if original.text else _bytes_damage)(rng, data,
                                                                                damage)
            files = list(original.files)
            files[which] = folder / f"m{o:02d}_{m:03d}_{source.name}"
            files[which].write_bytes(damaged)
            out.append(Mutant(",".join(str(f) for f in files),
                              f"{original.name}: {source.name} {damage} ({what})"))
    return out


FRAME_DAMAGES = ("shuffle rows", "nan cell", "inf cell", "duplicate time", "few rows",
                 "scale column", "constant column", "drop column", "shift time",
                 "string column", "baro")


def frame_mutant(rng, imu: pd.DataFrame, gnss: pd.DataFrame, damage: str):
    """One seeded damage of an ``imu, gnss`` pair of DataFrames (what a user hands to
    :func:`~navlib.studies.assess.assess_flight` without a reader): the damaged pair and
    what was done."""
    imu, gnss = imu.copy(), gnss.copy()
    which = int(rng.integers(0, 2))
    name, frame = ("imu", imu) if which == 0 else ("gnss", gnss)
    columns = list(frame.columns)
    col = columns[int(rng.integers(0, len(columns)))]
    row = int(rng.integers(0, len(frame)))
    if damage == "shuffle rows":
        frame = frame.sample(frac=1.0, random_state=int(rng.integers(0, 2**31)))
        what = "rows shuffled"
    elif damage in ("nan cell", "inf cell"):
        frame.loc[frame.index[row], col] = np.nan if damage == "nan cell" else np.inf
        what = f"{col} of row {row} set to {frame[col].iloc[row]}"
    elif damage == "duplicate time":
        frame = pd.concat([frame, frame.iloc[[row]]]).sort_values("t", kind="stable")
        what = f"row {row} repeated"
    elif damage == "few rows":
        keep = int(rng.choice([0, 1, 2, 3, 5, 9]))
        frame = frame.iloc[:keep]
        what = f"the first {keep} row(s) kept"
    elif damage == "scale column":
        factor = float(rng.choice([1e3, 1e-3, -1.0, 0.0]))
        frame[col] = frame[col] * factor
        what = f"{col} times {factor:g}"
    elif damage == "constant column":
        frame[col] = frame[col].iloc[0]
        what = f"{col} held at {frame[col].iloc[0]:.6g}"
    elif damage == "drop column":
        frame = frame.drop(columns=col)
        what = f"{col} dropped"
    elif damage == "shift time":
        offset = float(rng.choice([-1e3, 0.5, 10.0, 1e6]))
        frame["t"] = frame["t"] + offset
        what = f"t shifted by {offset:g}"
    elif damage == "string column":
        frame[col] = frame[col].astype(str)
        what = f"{col} as strings"
    else:
        baro = pd.DataFrame({"t": frame["t"].to_numpy()[:int(rng.integers(0, 4))],
                             "alt_m": np.nan})
        imu.attrs["baro"] = baro
        return imu, gnss, f"imu.attrs['baro'] of {len(baro)} NaN row(s)"
    frame.attrs = dict(imu.attrs if which == 0 else gnss.attrs)
    pair = (frame, gnss) if which == 0 else (imu, frame)
    return *pair, f"{name}: {what}"


def run_frames(imu: pd.DataFrame, gnss: pd.DataFrame, limit_s: float) -> tuple[str, str, float]:
    """:func:`run` for DataFrames: assess them within ``limit_s`` seconds."""
    start = time.perf_counter()
    try:
        with warnings.catch_warnings(), time_limit(limit_s):
            warnings.simplefilter("ignore")
            assess_flight(imu, gnss)
        outcome, text = "assessed", ""
    except NavlibInputError as exc:
        outcome, text = "refused", str(exc)
    except _Hung:
        outcome, text = "hung", f"over {limit_s:g} s"
    except Exception as exc:  # the bare errors are what the fuzz test hunts
        outcome, text = "bare", f"{type(exc).__name__}: {exc}"
    return outcome, text, time.perf_counter() - start


# --------------------------------------------------------------------------- running


class _Hung(BaseException):
    """Raised by the alarm of :func:`time_limit` (not an Exception: no handler of the
    library may take it for an input error)."""


@contextmanager
def time_limit(seconds: float):
    """Raise :class:`_Hung` in the main thread after ``seconds`` of wall time."""
    def alarm(signum, frame):
        raise _Hung

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def run(spec: str, limit_s: float) -> tuple[str, str, float]:
    """Read the ``LOG`` ``spec`` and assess it within ``limit_s`` seconds: the outcome (one
    of :data:`OUTCOMES`), the error text, and the seconds taken."""
    start = time.perf_counter()
    try:
        with warnings.catch_warnings(), time_limit(limit_s):
            warnings.simplefilter("ignore")
            imu, gnss = io.read_log(spec)
            assess_flight(imu, gnss)
        outcome, text = "assessed", ""
    except NavlibInputError as exc:
        outcome, text = "refused", str(exc)
    except _Hung:
        outcome, text = "hung", f"over {limit_s:g} s"
    except Exception as exc:  # the bare errors are what the fuzz test hunts
        outcome, text = "bare", f"{type(exc).__name__}: {exc}"
    return outcome, text, time.perf_counter() - start
