"""The rocket notebook's generated reading."""

from __future__ import annotations

from navlib.errors import NavlibInputError
from navlib.studies import claims as engine
from navlib.studies.rocket.claims import excitability_claims, sensability_claims
from navlib.studies.rocket.experiment import RocketAnalysis, tangent_projections
from navlib.studies.rocket.sensitivity import sweep_pass_rates, tension_findings

__all__ = ["reading_markdown"]


def reading_markdown(analysis: RocketAnalysis, which: str = "all", sweep=None,
                     tension=None) -> str:
    """The notebook's generated reading: the claims of ``analysis`` by verdict, the sweep's
    pass rates (``sweep`` from :func:`sensitivity_sweep`) and the tension findings
    (``tension`` from :func:`tension_table`)."""
    results = []
    if which in ("excitability", "all"):
        results += excitability_claims(analysis)
    if which in ("sensability", "all"):
        results += sensability_claims(analysis)
    if not results:
        raise NavlibInputError(f"which: expected 'excitability', 'sensability' or 'all', "
                               f"got {which!r}")
    ids = [r.claim_id for r in results]
    rates = sweep_pass_rates(sweep)[ids].to_dict() if sweep is not None else None
    lines = []
    proj = tangent_projections(analysis)
    lines.append("Attitude-error axes projected on the pad's tangent plane: "
                 + " / ".join(f"{v:.2f}" for v in proj) + " (the pad excites only the tilt "
                 "plane, so these bound the pad excitability of each component).")
    if rates is not None:
        lines.append("The sweep above varies one assumption at a time; the fractions quoted "
                     "with each claim are its pass rate there.")
    if tension is not None:
        lines += tension_findings(tension)
    return engine.reading_markdown(results, lines, rates)
