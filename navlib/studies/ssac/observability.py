"""Silva et al. (2017) observability: ranks, the analytic null space and the grouping of the
unobservable subspace (docs/assumptions.md, ssac.md §3.1, §3.3) of the reconstructed SSAC model
(docs/assumptions.md, ssac.md §2.3)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.linalg import null_space, subspace_angles

from navlib.covariance.estimability import sparse_basis
from navlib.errors import NavlibInputError
from navlib.models.base import LinearModel
from navlib.models.ssac import SITE_ALT_M, SITE_LAT_DEG, STATES_15, ssac
from navlib.observability import analyze, observability_matrix
from navlib.resolution import format_resolved, relative_resolution

__all__ = ["GROUP_THRESHOLD", "PAPER_GROUPS", "PAPER_RANKS", "RANK_RTOL", "analytic_null_vectors",
           "equivalence_scale", "grouping_table", "null_space_table", "observability_summary",
           "observability_table", "set_text"]

PAPER_GROUPS = (("psiN", "baE"), ("psiE", "baN"), ("psiD", "bgE"), ("bgN", "bgD", "dL"),
                ("baD", "dh"), ("dlambda",))
"""Unobservable subspaces (34)–(39) as inferred in ssac.md §3.3."""
PAPER_RANKS = {15: 9, 12: 9, 10: 7}
"""Ranks the paper states (15 states: 6 modes; BB's 10 states: 3 modes) and the 12-state
value implied by ssac.md §3.1 (not stated by the paper: no claim reads it)."""
RANK_RTOL = 1e-12
"""Relative rank tolerance: the ninth singular value of O is 6.6e-4 (7e-5 of the largest),
genuine but small, so an absolute 1e-3 would miscount (ssac.md §3.1)."""
GROUP_THRESHOLD = 0.05
"""Coupling threshold of the scaled groupings (``navlib.observability.analyze``)."""


def set_text(names) -> str:
    """A group of state names as set notation, e.g. ``{dvN, dvE}``."""
    return "{" + ", ".join(names) + "}"


def analytic_null_vectors(model: LinearModel) -> pd.DataFrame:
    """Analytic unobservable directions of docs/assumptions.md, ssac.md §3.3, restricted to the
    model's states.

    For the 15-state model (``s, c = sin L, cos L``, ``Omega`` Earth rate)::

        v1 = dlambda
        v2 = psiD + Omega c bgE
        v3 = psiN + g baE + Omega s bgE
        v4 = psiE - g baN - dL
        v5 = dL - Omega s bgN - Omega c bgD
        v6 = dh + (2 g / R) baD

    For a reduced model, the combinations with zero weight on the removed states (e.g.
    ``v4 + v5`` without position), in reduced row-echelon form (columns ``u1, ...``).
    Returns a frame indexed by state, one column per vector.
    """
    p = model.parameters
    W, lat, g = p["Omega"], p["lat"], p["g"]
    s, c = np.sin(lat), np.cos(lat)
    idx = {name: i for i, name in enumerate(STATES_15)}
    V = np.zeros((15, 6))
    for j, terms in enumerate([
        {"dlambda": 1.0},
        {"psiD": 1.0, "bgE": W * c},
        {"psiN": 1.0, "baE": g, "bgE": W * s},
        {"psiE": 1.0, "baN": -g, "dL": -1.0},
        {"dL": 1.0, "bgN": -W * s, "bgD": -W * c},
        {"dh": 1.0, "baD": p["gravity_gradient"]},
    ]):
        for name, value in terms.items():
            V[idx[name], j] = value
    names15 = list(STATES_15)
    if not set(model.state_names) <= set(names15):
        raise NavlibInputError("model: analytic vectors assume the IMU aligned to NED "
                               "(state names of navlib.models.ssac without C_b_n)")
    keep = [names15.index(name) for name in model.state_names]
    removed = [i for i in range(15) if i not in keep]
    if removed:
        combos = null_space(V[removed])
        V = sparse_basis((V @ combos)[keep])
        return pd.DataFrame(V, index=list(model.state_names),
                            columns=[f"u{j + 1}" for j in range(V.shape[1])])
    return pd.DataFrame(V, index=list(model.state_names),
                        columns=[f"v{j + 1}" for j in range(6)])



def observability_table(lat_deg: float = SITE_LAT_DEG, alt_m: float = SITE_ALT_M,
                        rtol: float = RANK_RTOL) -> pd.DataFrame:
    """Rank of O for the 15-, 12- and 10-state models next to the paper's (docs/assumptions.md,
    ssac.md §3.1).

    Columns: ``n_states, rank, n_unobservable, paper_rank, match, sigma_max, sigma_last``
    (smallest singular value counted), ``sigma_next`` (the first one below the tolerance),
    ``resolution`` (relative numerical resolution of O's singular values,
    :func:`navlib.resolution.relative_resolution`),
    ``rank_abs_1e-3`` (the rank an absolute 1e-3 tolerance would give), ``null_residual``
    (largest ``|O v| / (|O| |v|)`` over the analytic vectors) and ``null_angle_deg``
    (largest principal angle between the numerical null space and the analytic vectors).

    Parameters
    ----------
    lat_deg, alt_m : float, optional
        Site latitude, deg, and altitude, m.
    rtol : float, optional
        Relative rank tolerance of O.
    """
    rows = []
    for n in (15, 12, 10):
        model = ssac(n, lat_deg, alt_m)
        O = observability_matrix(model.A, model.H)
        res = analyze(O, rtol=rtol, state_names=model.state_names)
        s = res.singular_values
        analytic = analytic_null_vectors(model).to_numpy()
        residual = np.linalg.norm(O @ analytic, axis=0) / (
            s[0] * np.linalg.norm(analytic, axis=0))
        angle = np.degrees(subspace_angles(res.null_space, analytic).max()) \
            if analytic.shape[1] == res.null_space.shape[1] else np.nan
        rows.append({
            "n_states": n, "rank": res.rank, "n_unobservable": res.n_unobservable,
            "paper_rank": PAPER_RANKS[n], "match": res.rank == PAPER_RANKS[n],
            "sigma_max": s[0], "sigma_last": s[res.rank - 1],
            "sigma_next": s[res.rank] if res.rank < s.size else 0.0,
            "resolution": relative_resolution(O.shape), "rank_abs_1e-3": int(np.sum(s > 1e-3)),
            "null_residual": float(residual.max()), "null_angle_deg": float(angle),
        })
    return pd.DataFrame(rows)


def observability_summary(lat_deg: float = SITE_LAT_DEG, alt_m: float = SITE_ALT_M,
                          rtol: float = RANK_RTOL) -> pd.DataFrame:
    """:func:`observability_table` as a report shows it: ``sigma_next`` and
    ``null_residual`` below the numerical resolution of O, and ``null_angle_deg`` below the
    angle that resolution allows (Wedin's bound), printed as a bound ("< 1e-14 of the
    largest"), not as round-off digits (:mod:`navlib.resolution`).

    Parameters
    ----------
    lat_deg, alt_m : float, optional
        Site latitude, deg, and altitude, m.
    rtol : float, optional
        Relative rank tolerance of O.
    """
    table = observability_table(lat_deg, alt_m, rtol)
    shown = table.drop(columns=["sigma_max", "resolution"])
    shown["sigma_next"] = [format_resolved(r.sigma_next, r.sigma_max, r.resolution, ".2g")
                           for r in table.itertuples()]
    shown["null_residual"] = [format_resolved(r.null_residual, 1.0, r.resolution, ".2g",
                                              of="|O| |v|") for r in table.itertuples()]
    # Wedin: a perturbation of relative size `resolution` tilts the null space by up to
    # resolution * sigma_max / sigma_last radians
    shown["null_angle_deg"] = [
        format_resolved(r.null_angle_deg, 1.0, np.degrees(r.resolution * r.sigma_max
                                                          / r.sigma_last), ".2g", of=None)
        for r in table.itertuples()]
    return shown


def null_space_table(lat_deg: float = SITE_LAT_DEG, alt_m: float = SITE_ALT_M,
                     rtol: float = RANK_RTOL) -> pd.DataFrame:
    """The exact 15-state null space: analytic vectors v1..v6 with ``O v`` residuals.

    Rows are states plus ``residual`` (``|O v| / (sigma_max |v|)``); a genuine observable
    direction would give at least ``sigma_9 / sigma_max`` ~ 7e-5.

    Parameters
    ----------
    lat_deg, alt_m : float, optional
        Site latitude, deg, and altitude, m.
    rtol : float, optional
        Relative rank tolerance of O.
    """
    model = ssac(15, lat_deg, alt_m)
    O = observability_matrix(model.A, model.H)
    frame = analytic_null_vectors(model)
    V = frame.to_numpy()
    s1 = np.linalg.norm(O, 2)
    frame.loc["residual"] = np.linalg.norm(O @ V, axis=0) / (s1 * np.linalg.norm(V, axis=0))
    return frame


def equivalence_scale(model: LinearModel) -> np.ndarray:
    """State scales in which each analytic null vector has O(1) entries (docs/assumptions.md,
    ssac.md §3.3).

    tilt ``b_a/g``, azimuth ``b_g/(Omega cos L)``, latitude and longitude ``b_g/Omega``
    (a ``dL`` of this size mimics ``b_g`` through the Earth rate, 0.084 rad for
    ``Omega sin L``), height ``b_a/(2g/R)`` (1594 m mimics ``b_a``), biases at their nominal
    values, velocity 0.1 m/s. Scaled like this, couplings through small Earth-rate terms
    become visibly small, which is the reading the paper's "uncoupled" subspaces need.
    """
    p = model.parameters
    bg, ba = p["imu"]["gyro_bias"], p["imu"]["accel_bias"]
    W, g, c = p["Omega"], p["g"], abs(np.cos(p["lat"]))
    table = {"psiN": ba / g, "psiE": ba / g, "psiD": bg / (W * c), "dvN": 0.1, "dvE": 0.1,
             "dvD": 0.1, "dL": bg / W, "dlambda": bg / W, "dh": ba / p["gravity_gradient"],
             "bgN": bg, "bgE": bg, "bgD": bg, "baN": ba, "baE": ba, "baD": ba}
    return np.array([table[name] for name in model.state_names])


def _groups_match(groups, paper=PAPER_GROUPS) -> bool:
    return {frozenset(g) for g in groups} == {frozenset(g) for g in paper}


def grouping_table(lat_deg: float = SITE_LAT_DEG, alt_m: float = SITE_ALT_M,
                   threshold: float = GROUP_THRESHOLD, rtol: float = RANK_RTOL) -> pd.DataFrame:
    """Grouping of the 15-state unobservable subspace under three readings (docs/assumptions.md,
    ssac.md §3.3).

    * ``exact``: the block decomposition of the exact null space (threshold 1e-9, SI units);
    * ``P0 (matched) scaled``: states in units of ``sqrt(diag P0)`` (10 m position);
    * ``equivalence scaled``: states in units of :func:`equivalence_scale`.

    Columns: ``reading, threshold, n_groups, groups, matches_paper`` and the largest
    unobservable share among ``bgN, bgD, baD`` (the bias states the position modes take in).

    Parameters
    ----------
    lat_deg, alt_m : float, optional
        Site latitude, deg, and altitude, m.
    threshold : float, optional
        Smallest coupling that joins two states in the thresholded reading.
    rtol : float, optional
        Relative rank tolerance of O.
    """
    model = ssac(15, lat_deg, alt_m)
    O = observability_matrix(model.A, model.H)
    readings = [("exact (SI units)", None, 1e-9),
                ("P0 (matched) scaled", np.sqrt(np.diag(model.P0)), threshold),
                ("equivalence scaled", equivalence_scale(model), threshold)]
    rows = []
    idx = model.index(["bgN", "bgD", "baD"])
    for label, scale, thr in readings:
        res = analyze(O, rtol=rtol, state_names=model.state_names, scale=scale,
                      coupling_threshold=thr)
        rows.append({"reading": label, "threshold": thr,
                     "n_groups": len(res.unobservable_groups),
                     "groups": "; ".join(set_text(g) for g in res.unobservable_groups),
                     "matches_paper": _groups_match(res.unobservable_groups),
                     "max_share_bgN_bgD_baD": float(res.unobservable_share[idx].max())})
    return pd.DataFrame(rows)

