"""Warnings on the terminal of ``python -m navlib`` (navlib.reports.terminal): one readable
line each, never Python's ``file.py:NN: Category: message`` with the source line below it."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings

from support.locations import REPO

from navlib.io import FlightDataWarning
from navlib.reports.terminal import warning_line, warning_lines

SOURCE_LOCATION = re.compile(r"\.py:\d+:")
SAMPLE = REPO / "data" / "sample_flight"


def test_a_warning_in_a_decorated_entry_is_one_line(capsys):
    @warning_lines
    def entry():
        warnings.warn("gaps found:\n  the first at line 21", FlightDataWarning, stacklevel=1)
        return 7

    before = warnings.showwarning
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert entry() == 7
    assert warnings.showwarning is before
    assert capsys.readouterr().err == "FlightDataWarning: gaps found: the first at line 21\n"
    assert warning_line("a\tb \n c", UserWarning) == "UserWarning: a b c"


def _flight_with_a_gnss_gap(folder) -> str:
    """The sample flight with 15 GNSS fixes removed: the reader warns of the gap."""
    lines = (SAMPLE / "gnss.csv").read_text().splitlines()
    (folder / "gnss.csv").write_text("\n".join(lines[:20] + lines[35:]) + "\n")
    return f"{SAMPLE / 'imu.csv'},{folder / 'gnss.csv'}"


def test_plan_with_a_flight_prints_its_warnings_without_source_lines(tmp_path):
    """``plan --flight`` reads and assesses the flight outside the mission rows, so its
    warnings reach the terminal (they were printed with navlib/io/logs.py:57 and the
    source line)."""
    flight = _flight_with_a_gnss_gap(tmp_path)
    done = subprocess.run([sys.executable, "-m", "navlib", "plan", "ground_vehicle",
                           "--flight", flight, "--output", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert not [line for line in lines if SOURCE_LOCATION.search(line)], done.stderr
    gap = [line for line in lines if "gap(s) longer than" in line]
    assert len(gap) == 1 and gap[0].startswith("FlightDataWarning: file "), done.stderr
    assert not [line for line in lines if line.startswith(" ")], done.stderr
