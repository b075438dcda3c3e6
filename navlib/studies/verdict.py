"""Compatibility names for the claim record: the engine lives in :mod:`navlib.studies.claims`.

``ClaimResult`` and ``claims_frame`` are those of the engine; ``VERDICTS`` lists every status
a claim can have (the three verdicts and "not evaluated").
"""

from navlib.studies.claims import STATUSES as VERDICTS
from navlib.studies.claims import ClaimResult, claims_frame

__all__ = ["VERDICTS", "ClaimResult", "claims_frame"]
