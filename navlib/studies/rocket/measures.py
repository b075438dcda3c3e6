"""Excitability and sensability against the simpler measures: the PSINS covariance ratio and
the Ham-Brown modes, per state, with the reason of each disagreement."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import covariance
from navlib.models.ecef import PAPER_IDS
from navlib.studies.rocket.claims import sensible_time
from navlib.studies.rocket.experiment import RocketAnalysis
from navlib.studies.rocket.flight import IN_SO, SENSIBLE, TRANSIENT_S

__all__ = ["DISAGREEMENT_REASONS", "RATIO_ESTIMATED", "measure_comparison", "measure_disagreements"]

RATIO_ESTIMATED = 2.0
"""Covariance ratio sigma_0/sigma_end above which the PSINS measure calls a state estimated."""


def measure_comparison(analysis: RocketAnalysis) -> pd.DataFrame:
    """Per-state comparison of excitability/sensability with the simpler measures.

    Columns: ``state``, ``paper_id``, ``e_tau1..3`` (excitability), ``s_end`` and
    ``s_sensible_s`` (time sensible after the transient), ``ratio_end`` (PSINS covariance
    ratio ``sigma_0/sigma_end``, :func:`navlib.covariance.covariance_ratio`), ``hb_share``
    (norm of the state's row in the Ham-Brown modes of ``D0^-1/2 P_end D0^-1/2`` whose
    eigenvalue is below ``1/RATIO_ESTIMATED^2``: the *directions* whose normalised variance
    shrank as much as the ratio threshold asks of single states; from
    :func:`navlib.covariance.normalized_eigen` with its trace normalisation undone), and the
    four yes/no readings ``excited``
    (e >= 1/sqrt2 in some segment), ``sensible_end``, ``ratio_estimated``
    (ratio >= :data:`RATIO_ESTIMATED`), ``hb_estimated`` (hb_share >= 1/sqrt2).
    """
    se = analysis.sensability
    ratio = covariance.covariance_ratio(se.sigma)
    hb = covariance.normalized_eigen(se.P, analysis.model.P0, t=se.t,
                                     state_names=analysis.state_names)
    # undo the trace normalisation: eigenvalues of D0^-1/2 P D0^-1/2 (1 = prior variance)
    trace = np.sum(se.sigma[-1] ** 2 / np.diag(analysis.model.P0))
    hb_values = hb.eigenvalues[-1] * trace / hb.order
    modes = np.flatnonzero(hb_values < RATIO_ESTIMATED**-2) + 1
    share = hb.subspace_share(modes, time_s=float(se.t[-1])) if modes.size else \
        np.zeros(se.n)
    t = analysis.model.t
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    frame = pd.DataFrame({"state": analysis.state_names,
                          "paper_id": [PAPER_IDS[s] for s in analysis.state_names]})
    for i, label in enumerate(analysis.labels):
        frame[f"e_{label}"] = analysis.excitability[i].e
    frame["s_end"] = se.s[-1]
    frame["s_sensible_s"] = [sensible_time(analysis, s, later) for s in analysis.state_names]
    frame["ratio_end"] = ratio[-1]
    frame["hb_share"] = share
    e_cols = [f"e_{label}" for label in analysis.labels]
    frame["excited"] = frame[e_cols].max(axis=1) >= IN_SO
    frame["sensible_end"] = frame["s_end"] >= SENSIBLE
    frame["ratio_estimated"] = frame["ratio_end"] >= RATIO_ESTIMATED
    frame["hb_estimated"] = frame["hb_share"] >= IN_SO
    return frame


DISAGREEMENT_REASONS = {
    "ratio estimated, not sensible":
        "the ratio counts one state's absolute variance reduction; sensability asks whether "
        "the state lies in the few best-informed normalised directions, which other states "
        "(usually P, V) dominate",
    "sensible, ratio < 2":
        "sensability is relative: the state's information is large against the other "
        "directions although its own variance fell little (or grew)",
    "ratio estimated, not in Ham-Brown modes":
        "the state's variance fell, but only in combination with others: the well-estimated "
        "directions mix it with correlated states",
    "in Ham-Brown modes, ratio < 2":
        "a direction containing the state is well estimated while its own variance is not: "
        "the state is strongly correlated with better-known states",
    "excited, never sensible":
        "excitability ignores process noise and uses only F, H, D0, R0; sensability includes "
        "the noise that drowns the signal",
}
"""Reasons attached by :func:`measure_disagreements`, one per kind of disagreement."""


def measure_disagreements(comparison: pd.DataFrame) -> pd.DataFrame:
    """Where the simpler measures disagree with sensability/excitability, and why.

    Rows ``state, disagreement, numbers, why`` for each state where the PSINS covariance
    ratio (>= :data:`RATIO_ESTIMATED`) disagrees with sensability at the end, where the ratio
    disagrees with the Ham-Brown modes, and where a state is excited in some segment but
    never sensible; ``why`` from :data:`DISAGREEMENT_REASONS`.
    """
    rows = []
    e_cols = [c for c in comparison.columns if c.startswith("e_tau")]
    for r in comparison.itertuples():
        kinds = []
        if r.ratio_estimated and not r.sensible_end:
            kinds.append(("ratio estimated, not sensible",
                          f"ratio {r.ratio_end:.1f}, s_end {r.s_end:.2f}"))
        if r.sensible_end and not r.ratio_estimated:
            kinds.append(("sensible, ratio < 2", f"s_end {r.s_end:.2f}, ratio {r.ratio_end:.2f}"))
        if r.ratio_estimated and not r.hb_estimated:
            kinds.append(("ratio estimated, not in Ham-Brown modes",
                          f"ratio {r.ratio_end:.1f}, HB share {r.hb_share:.2f}"))
        if r.hb_estimated and not r.ratio_estimated:
            kinds.append(("in Ham-Brown modes, ratio < 2",
                          f"HB share {r.hb_share:.2f}, ratio {r.ratio_end:.2f}"))
        if r.excited and r.s_sensible_s == 0:
            e_max = max(getattr(r, c) for c in e_cols)
            kinds.append(("excited, never sensible", f"max e {e_max:.2f}"))
        rows += [(r.state, kind, numbers, DISAGREEMENT_REASONS[kind]) for kind, numbers in kinds]
    return pd.DataFrame(rows, columns=["state", "disagreement", "numbers", "why"])
