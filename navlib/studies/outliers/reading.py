"""The outlier notebook's generated readings: the claims reading and the EKF-against-
covariance check."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult
from navlib.studies.outliers.response import OutlierStudy

__all__ = ["ekf_sigma_agreement", "reading_markdown"]


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


def ekf_sigma_agreement(frame: pd.DataFrame, after_s: float = 1.0) -> pd.DataFrame:
    """How well the closed-loop EKF's sigma matches the covariance analysis, per axis.

    Parameters
    ----------
    frame : DataFrame
        Columns ``t`` (s), ``axis``, ``sigma_ekf``, ``sigma_cov`` and ``error`` (the EKF's
        actual error), as :func:`navlib.studies.outliers.ekf_vs_covariance` returns them
        (docs/assumptions.md, launcher.md §6.4).
    after_s : float
        Epochs up to this time, s, are left out (the first updates of both filters).

    Returns
    -------
    DataFrame
        Index ``axis`` (in the frame's order); ``sigma_ratio_max_dev`` =
        ``max |sigma_ekf / sigma_cov - 1|`` and ``rms_normalised_error`` = RMS of
        ``error / sigma_ekf`` (about 1 for a consistent filter).
    """
    late = frame[frame.t > after_s]
    return late.assign(ratio=late.sigma_ekf / late.sigma_cov,
                       z=late.error / late.sigma_ekf).groupby("axis", sort=False).agg(
        sigma_ratio_max_dev=("ratio", lambda r: float(np.max(np.abs(r - 1)))),
        rms_normalised_error=("z", lambda z: float(np.sqrt(np.mean(z**2)))))
