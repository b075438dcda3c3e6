"""The shared shape of a reproduced paper claim: claim, paper value, ours, verdict."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass

import pandas as pd

VERDICTS = ("reproduced", "partly", "not reproduced", "not applicable")


@dataclass(frozen=True)
class ClaimResult:
    """One paper claim evaluated by code.

    Attributes
    ----------
    claim_id : str
        The spec id, e.g. ``"X3"``, ``"S6"``, ``"T1"``, ``"SSAC-rank"``.
    claim : str
        What the paper says, in one line.
    paper : str
        The paper's value or wording.
    ours : str
        Our number(s), formatted.
    verdict : str
        One of :data:`VERDICTS`.
    assumption : str
        The assumption the verdict hinges on.
    """

    claim_id: str
    claim: str
    paper: str
    ours: str
    verdict: str
    assumption: str = ""

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")


def claims_frame(results: Iterable[ClaimResult]) -> pd.DataFrame:
    """A table of claim results, one row per claim."""
    return pd.DataFrame([asdict(r) for r in results])
