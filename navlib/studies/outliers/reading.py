"""The outlier notebook's generated reading."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.outliers.response import OutlierStudy


def reading_markdown(study: OutlierStudy, covariance: Sequence[ClaimResult] = (),
                     sensitivity: pd.DataFrame | None = None) -> str:
    """The notebook's generated reading: T1-T4 and Figs. 7, 10, 11 by verdict, and (with
    ``sensitivity`` from :func:`assumption_sensitivity`) which variants change a verdict."""
    lines = []
    if sensitivity is not None and len(sensitivity):
        per = sensitivity.drop_duplicates(["variant", "test"]).pivot(
            index="test", columns="variant", values="claim_verdict")
        moved = per[per.nunique(axis=1) > 1]
        for test, row in moved.iterrows():
            lines.append(f"{test} depends on the reading: " + ", ".join(
                f"{variant}: {verdict}" for variant, verdict in row.items()) + ".")
        if not len(moved):
            lines.append("No variant of the sensitivity table changes a test's verdict.")
    return engine.reading_markdown(list(study.claims) + list(covariance), lines)
