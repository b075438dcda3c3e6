"""The sounding-rocket profile claims of España, Carrizo & Giribet (2019), checked on a
synthetic trajectory (docs/assumptions.md, excitability.md §3 event table and §4; notebook 01).

The paper describes its VS30 flight only through Fig. 1 and a few sentences: on the pad until
18 s, boost to 46 s with a peak axial specific force of about 110 m/s^2, a sign change of
the axial specific force at 46 s (drag), near free flight (|f| < 0.5 m/s^2) above 40 km from
60 s, a de-spin at 73 s halving the axial rate, end at 86 s, IMU at 100 Hz. Each check below
measures the trajectory's own signals (body x = rocket axis) against those paper values; it
never reads the generator's event table, so it also judges trajectories built with other
keywords (then "not reproduced" is the expected answer).

The basis of every claim here is "by construction": the default generator
(:func:`navlib.trajectory.sounding_rocket`) takes these very numbers as inputs, so on it the
checks confirm the synthesis, not the paper (shown, never counted as reproduced).
"""

from __future__ import annotations

import numpy as np

from navlib._validation import finite_scalar
from navlib.errors import NavlibInputError
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult, check, claim
from navlib.studies.rocket.flight import rocket_trajectory

__all__ = ["PAPER", "STILL_SPEED", "rocket_profile_claims"]

PAPER = {"ignition_s": 18.0, "burnout_s": 46.0, "free_flight_s": 60.0, "despin_s": 73.0,
         "end_s": 86.0, "peak_f_x": 110.0, "free_flight_f": 0.5, "free_flight_alt_m": 40e3,
         "despin_factor": 0.5, "rate_hz": 100.0}
"""The paper's numbers (spec excitability.md §3, §5)."""

STILL_SPEED = 1e-3
"""Speed (m/s) below which the vehicle counts as standing on the pad."""


def _window(traj, start: float, stop: float) -> np.ndarray:
    mask = (traj.t >= start) & (traj.t <= stop)
    if not mask.any():
        raise NavlibInputError(
            f"traj: no samples in [{start}, {stop}] s; the rocket profile checks need the "
            f"0-{PAPER['end_s']:g} s flight")
    return mask


def _profile_claim(claim_id, statement, paper, ours, checks, assumption) -> ClaimResult:
    return claim(claim_id, statement, paper, ours, checks, basis="by construction",
                 assumption=assumption)


def rocket_profile_claims(traj, *, rel_tol: float = 0.05, time_tol_s: float = 1.0
                          ) -> list[ClaimResult]:
    """Check the Fig. 1 profile statements on a trajectory, one :class:`ClaimResult` each.

    Parameters
    ----------
    traj : navlib.trajectory.Trajectory
        A sounding-rocket flight covering 0-86 s, body x along the rocket axis.
    rel_tol : float
        Relative tolerance on magnitudes (peak force, de-spin ratio).
    time_tol_s : float
        Tolerance on event times, s.

    Returns
    -------
    list of ClaimResult
        R1 pad, R2 peak axial force, R3 sign change, R4 free flight, R5 de-spin,
        R6 timeline (use :func:`navlib.studies.claims.claims_frame` for a table);
        basis "by construction".
    """
    rel_tol = finite_scalar(rel_tol, "rel_tol", 0.0, 1.0, low_open=True)
    time_tol_s = finite_scalar(time_tol_s, "time_tol_s", 0.0, low_open=True)
    t = traj.t
    f_x = traj.specific_force[:, 0]
    w_x = traj.angular_rate[:, 0]
    f_mag = np.linalg.norm(traj.specific_force, axis=1)
    speed = np.linalg.norm(traj.velocity, axis=1)
    _, _, alt = traj.geodetic
    claims = []

    moving = np.flatnonzero(speed > STILL_SPEED)
    t_move = float(t[moving[0]]) if moving.size else float("inf")
    ign = PAPER["ignition_s"]
    claims.append(_profile_claim(
        "R1", "on the pad until ignition", f"0-{ign:g} s",
        f"moves (|V| > {STILL_SPEED:g} m/s) from {t_move:.2f} s",
        [check("lift-off time, s", t_move, "in", (ign, ign + time_tol_s), True)],
        "lift-off when thrust beats the weight along the rail; τ1 = [0, 19] s allows 1 s"))

    boost = _window(traj, ign, PAPER["free_flight_s"])
    k_peak = np.flatnonzero(boost)[np.argmax(f_x[boost])]
    peak, t_peak = float(f_x[k_peak]), float(t[k_peak])
    rel = abs(peak - PAPER["peak_f_x"]) / PAPER["peak_f_x"]
    bo = PAPER["burnout_s"]
    claims.append(_profile_claim(
        "R2", "axial specific force peaks near burnout", f"~{PAPER['peak_f_x']:g} m/s² at {bo:g} s",
        f"{peak:.1f} m/s² at {t_peak:.2f} s",
        [check("|peak f_x - 110| / 110", rel, "<=", rel_tol, True),
         check("time of the peak, s", t_peak, "in", (bo - time_tol_s, bo))],
        "constant thrust with propellant burn: f_x grows as mass falls; tail-off before burnout"))

    after = np.flatnonzero((t > t_peak) & (f_x <= 0.0))
    t_cross = float(t[after[0]]) if after.size else float("inf")
    coast = (t >= t_cross + 0.5) & (t <= PAPER["free_flight_s"])
    stays_negative = bool(coast.any() and np.all(f_x[coast] < 0.0))
    f_after = float(f_x[np.searchsorted(t, bo + 1.0)]) if t[-1] > bo + 1.0 else float("nan")
    claims.append(_profile_claim(
        "R3", "axial specific force changes sign at thrust end (drag)", f"at {bo:g} s",
        f"first f_x ≤ 0 at {t_cross:.2f} s; f_x({bo + 1:g} s) = {f_after:.1f} m/s²; "
        f"negative until {PAPER['free_flight_s']:g} s: {stays_negative}",
        [check("first f_x <= 0 after the peak, s", t_cross, "in",
               (bo - time_tol_s, bo + time_tol_s), True),
         check(f"f_x < 0 until {PAPER['free_flight_s']:g} s", stays_negative, "==", True)],
        "drag of an exponential atmosphere; the sign change sits inside the tail-off"))

    ff = PAPER["free_flight_s"]
    free = _window(traj, ff, PAPER["end_s"])
    f_free = float(f_mag[free].max())
    alt_ff = float(alt[np.searchsorted(t, ff)])
    claims.append(_profile_claim(
        "R4", "near free flight above 40 km from 60 s",
        f"|f| < {PAPER['free_flight_f']:g} m/s², h > {PAPER['free_flight_alt_m'] / 1e3:g} km",
        f"max |f| = {f_free:.2f} m/s² after {ff:g} s; h({ff:g} s) = {alt_ff / 1e3:.1f} km",
        [check(f"max |f| after {ff:g} s, m/s²", f_free, "<", PAPER["free_flight_f"], True),
         check(f"altitude at {ff:g} s, m", alt_ff, ">", PAPER["free_flight_alt_m"], True)],
        "drag area and scale height assumed; apogee not given by the paper"))

    ds = PAPER["despin_s"]
    before = float(np.median(w_x[_window(traj, ds - 3.0, ds - 1.0)]))
    after_w = float(np.median(w_x[_window(traj, ds + 1.0, ds + 3.0)]))
    ratio = after_w / before if before != 0.0 else float("nan")
    mid = 0.5 * (before + after_w)
    around = _window(traj, ds - 3.0, ds + 3.0)
    crossing = np.flatnonzero(around & (np.abs(w_x) <= abs(mid)))
    t_half = float(t[crossing[0]]) if crossing.size and before != 0.0 else float("nan")
    rel_ratio = abs(ratio - PAPER["despin_factor"]) / PAPER["despin_factor"]
    claims.append(_profile_claim(
        "R5", "de-spin halves the axial rate", f"at {ds:g} s, factor {PAPER['despin_factor']:g}",
        f"ω_x {before:.2f} → {after_w:.2f} rad/s (ratio {ratio:.3f}), mid-point at {t_half:.2f} s",
        [check("|rate ratio - 0.5| / 0.5", rel_ratio, "<=", rel_tol, True),
         check("mid-point of the de-spin, s", t_half, "in", (ds - time_tol_s, ds + time_tol_s))],
        "spin rate before de-spin assumed (the paper gives none)"))

    rate = 1.0 / float(np.median(np.diff(t)))
    claims.append(_profile_claim(
        "R6", "flight record and IMU rate", f"0-{PAPER['end_s']:g} s at {PAPER['rate_hz']:g} Hz",
        f"{t[0]:g}-{t[-1]:g} s at {rate:.3f} Hz",
        [check("end of record, s", float(t[-1]), "in",
               (PAPER["end_s"] - 0.5 / rate, PAPER["end_s"] + 0.5 / rate), True),
         check("IMU rate, Hz", rate, "in", (PAPER["rate_hz"] * (1 - 1e-6),
                                             PAPER["rate_hz"] * (1 + 1e-6)), True)],
        "re-entry after 86 s not modelled (the paper does not show it)"))
    return claims


def _baseline_claims(quick: bool = False) -> list[ClaimResult]:
    return rocket_profile_claims(rocket_trajectory())


engine.register(engine.Study("rocket_profile", "España, Carrizo & Giribet (2019)",
                             _baseline_claims, order=0))
