"""Beaudoin et al. (2018) cause experiments: the small covariance runs that measure why a
covariance-evolution claim is partly or not reproduced (docs/assumptions.md, A-F2-pitch,
A-F3-pad), and the simplified §4.1 model over the mission (end of §4.1, A-F1-cp-mission)."""

from __future__ import annotations

import numpy as np

from navlib import cache
from navlib.models.launcher import ASSUMED, sensor_values
from navlib.studies.launcher.assumptions import NO_PITCH_KICK_DEG, PAD_CASES, SURVEYED_PAD_M
from navlib.studies.launcher.covariance_claims import EvolutionTable
from navlib.studies.launcher.evolution import EVOLUTION_CASES, covariance_evolution
from navlib.trajectory import launcher_ascent

__all__ = ["NO_PITCH_CASES", "cp_mission_sigmas", "evolution_causes"]

NO_PITCH_CASES = ("gps/none", "ins-only/none", "ideal-gps/none")
"""The Fig. 2 cases rerun on the ascent without a pitch programme."""


def _ascent(quick: bool, **overrides):
    """The claims' launcher ascent (quick: 80 s at 20 Hz) with ``overrides``."""
    short = {"duration_s": 80.0, "rate_hz": 20.0} if quick else {}
    return launcher_ascent(**short, **overrides)


@cache.memoized(maxsize=2)
def evolution_causes(quick: bool = False) -> dict[str, EvolutionTable]:
    """The cause experiments of the covariance-evolution claims.

    Returns
    -------
    dict
        ``"no_pitch"``: the Fig. 2 cases (:data:`NO_PITCH_CASES`) on the ascent with a pitch
        kick of :data:`~navlib.studies.launcher.assumptions.NO_PITCH_KICK_DEG` (A-F2-pitch);
        ``"surveyed_pad"``: the Fig. 3 cases (:data:`PAD_CASES`) with an initial position
        sigma of :data:`~navlib.studies.launcher.assumptions.SURVEYED_PAD_M` (A-F3-pad).
    """
    level = covariance_evolution(_ascent(quick, kick_deg=NO_PITCH_KICK_DEG),
                                 {k: EVOLUTION_CASES[k] for k in NO_PITCH_CASES})
    # on the claims' ascent these are rows of evolution_grid's stacked runs (a P0 variant),
    # kept on disk when it is built: notebook 02 computes them, the claims engine reads them
    pad = covariance_evolution(_ascent(quick), {k: EVOLUTION_CASES[k] for k in PAD_CASES},
                               sigma0_pos=SURVEYED_PAD_M)
    return {"no_pitch": EvolutionTable(level), "surveyed_pad": EvolutionTable(pad)}


def cp_mission_sigmas(c_p: float = 100.0, duration_s: float = 150.0, s_t: float = 0.005,
                      sigma_gps_pos: float | None = None, sigma_bp: float | None = None,
                      sigma0_pos: float = ASSUMED["sigma0_pos"]) -> dict[str, float]:
    """End sigma of the GPS bias of the simplified §4.1 model (eq. 7) over the mission, with
    the bias a Markov process of time constant ``c_p`` and as a random walk with the same
    driving noise (the paper's random-walk reading, docs/assumptions.md, launcher.md §3.2).

    A Kalman covariance recursion of one axis (the three are alike): state ``[dr, b_p]``,
    ``dr`` constant, ``b_p(k+1) = (1 - s_t / c_p) b_p(k) + w``, ``var w = 2 s_t sigma_bp^2 /
    c_p``, the GPS position ``dr + b_p`` with sigma ``sigma_gps_pos`` at every step.

    Parameters
    ----------
    c_p : float
        Markov time constant, s.
    duration_s, s_t : float
        Mission length and sampling time, s (the paper's 150 s surrogate and 5 ms).
    sigma_gps_pos, sigma_bp : float, optional
        GPS position noise and b_p stability, m (default the Table 1 preset's).
    sigma0_pos : float
        Initial position sigma, m.

    Returns
    -------
    dict
        ``markov``, ``random_walk``: the end sigma of b_p, m; ``ratio``: random walk / Markov.
    """
    values = sensor_values()
    r = (values["sigma_gps_pos"] if sigma_gps_pos is None else sigma_gps_pos) ** 2
    sb = values["sigma_bp"] if sigma_bp is None else sigma_bp
    q = 2.0 * s_t * sb**2 / c_p
    out = {}
    for name, a in (("markov", 1.0 - s_t / c_p), ("random_walk", 1.0)):
        p11, p12, p22 = sigma0_pos**2, 0.0, sb**2
        for k in range(round(duration_s / s_t) + 1):
            if k:  # propagate: dr constant, b_p scaled by a, driving noise q
                p12, p22 = a * p12, a * a * p22 + q
            s = p11 + 2.0 * p12 + p22 + r          # innovation variance of dr + b_p
            k1, k2 = (p11 + p12) / s, (p12 + p22) / s
            p11, p12, p22 = (p11 - k1 * (p11 + p12), p12 - k1 * (p12 + p22),
                             p22 - k2 * (p12 + p22))
        out[name] = float(np.sqrt(p22))
    out["ratio"] = out["random_walk"] / out["markov"]
    return out
