"""Deprecated address of :mod:`navlib.io.quality` (the flight-data quality checks moved into
``navlib.io``, issue 38); kept for one release, importing it warns."""

import warnings

from navlib.io.quality import (
    FINDING_COLUMNS,
    QualityCheck,
    check_records,
    gnss_faults,
    imu_saturation,
    load_thresholds,
)

__all__ = ["FINDING_COLUMNS", "QualityCheck", "check_records", "gnss_faults",
           "imu_saturation", "load_thresholds"]

warnings.warn("navlib.quality moved to navlib.io.quality; import it from there (the old "
              "name goes in the next release)", DeprecationWarning, stacklevel=2)
