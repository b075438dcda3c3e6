"""Silva et al. (2017) generated reading: the notebook's text on the SSAC claims."""

from __future__ import annotations

from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult

__all__ = ["reading_markdown"]


def reading_markdown(results: list[ClaimResult]) -> str:
    """The notebook's generated reading of :func:`~navlib.studies.ssac.ssac_claims` results
    (:func:`navlib.studies.claims.reading_markdown`)."""
    return engine.reading_markdown(results)
