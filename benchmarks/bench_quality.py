"""Flight-data quality checks on a long flight (saturation, frozen GNSS, barometer).

``quality.check_records_1800s``: :func:`navlib.io.quality.check_records` (saturation, frozen
fixes, barometer, jumps) of a generated 30-minute multicopter flight (``tests/support/flights.py``)
at 250 Hz with 10 Hz GNSS, the ``pixhawk_mems`` errors and a barometer record; the records
are generated once, outside the timing. Goal: 5 s, a small part of the assessment's 60 s.

Run alone (``python benchmarks/bench_quality.py``) for the table.
"""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path

from _harness import Case

ROOT = Path(__file__).resolve().parent.parent
DURATION_S = 1800.0


@cache
def _records():
    import pandas as pd

    sys.path.insert(0, str(ROOT / "tests"))
    from support.flights import multicopter, records

    from navlib import earth, sensors

    truth = multicopter(DURATION_S, 250.0)
    imu, gnss = records(truth, gnss_rate_hz=10.0)
    _, _, h = earth.ecef_to_geodetic(truth.position[::25])
    imu.attrs["baro"] = pd.DataFrame({"t": truth.t[::25], "alt_m": h})
    return imu, gnss, sensors.load_preset("pixhawk_mems")


def _check():
    from navlib.io.quality import check_records

    imu, gnss, spec = _records()
    return check_records(imu, gnss, spec, 2.0)


def cases():
    return [Case("quality.check_records_1800s", "30 min, 250 Hz IMU, 10 Hz GNSS", _check, 5.0,
                 repeat=3)]


def main() -> int:
    from _harness import time_case

    print(time_case(cases()[0]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
