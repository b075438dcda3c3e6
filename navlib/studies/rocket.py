"""España, Carrizo & Giribet (2019): excitability and sensability on the sounding-rocket flight.

The experiment of the paper's §5 rebuilt from library pieces: the VS30-like trajectory
(:func:`navlib.trajectory.sounding_rocket`), the 21-state ECEF model discretised to the 1 Hz
GNSS epochs (:func:`navlib.models.ecef.ecef21_at_epochs`), and the metrics of
:mod:`navlib.metrics`. Each paper statement X1-X7 (Fig. 2) and S1-S8 (Figs. 3-5) is a function
returning a :class:`~navlib.studies.verdict.ClaimResult`, evaluated by code.

The paper's statements are qualitative ("mostly in S_O", "very low", "briefly sensible");
the operational thresholds used here are module constants (spec excitability.md §3 and
its [I] notes):

* :data:`IN_SO` = 1/sqrt(2): a state "lies in S_O" when more than half of its unit vector's
  squared norm projects on the excited subspace (X1-X4); the same value for "sensible"
  (:data:`SENSIBLE`, S-claims).
* :data:`LOW` = 0.25: "very low" / "barely" = less than 1/16 of the squared norm.
* :data:`BRIEF_S` = 10 s: "briefly sensible"; :data:`TRANSIENT_S` = 5 s: epochs before it
  are left out of the "weakly sensible" counts (every state is sensible at t0 under the
  literal reading of spec A9, and the sensible subspace is still large for a few epochs).

Each claim is a list of explicit checks judged by the one rule of
:mod:`navlib.studies.claims` (the headline check decides "not reproduced"), and is
registered there with its declared assumption set (:data:`ROBUSTNESS_GRID`).
The metrics are *relative* (normalised by D0 and R0) and depend strongly on the assumed
P0, GNSS sigma, eta and nu (spec §3 "What the prototype showed"): :func:`sensitivity_sweep`
shows how much.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace
from functools import lru_cache, partial

import numpy as np
import pandas as pd

from navlib import covariance, metrics
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.models.ecef import (
    ATTITUDE_ERRORS,
    P0_DEFAULTS,
    PAPER_IDS,
    STATE_GROUPS,
    STATE_NAMES,
    ecef21_at_epochs,
    imu_noise_densities,
    initial_covariance,
    parameter_sigmas,
)
from navlib.resolution import relative_resolution
from navlib.resources import data_dir
from navlib.studies import claims as engine
from navlib.studies.claims import ClaimResult, check, claim, claims_frame
from navlib.sweep import sweep
from navlib.trajectory import sounding_rocket

SEGMENTS = ((0.0, 19.0), (19.0, 60.0), (60.0, 86.0))
"""The paper's segments tau1 (pad), tau2 (powered flight and spin), tau3 (free fall), s."""
SEGMENT_LABELS = ("tau1", "tau2", "tau3")

IN_SO = metrics.E_THRESHOLD
"""Excitability above which a state "lies (mostly) in S_O" (spec §3, X4 note): 1/sqrt(2)."""
SENSIBLE = metrics.S_THRESHOLD
"""Sensability above which a state counts as sensible at an epoch: 1/sqrt(2)."""
LOW = metrics.LOW
"""Excitability (or sensability) below which a state is "very low" / "barely" excited."""
BRIEF_S = 10.0
"""Longest total time (s) that still counts as "briefly" sensible (S7)."""
TRANSIENT_S = 5.0
"""Start-up epochs (s after t0) left out of the "weakly sensible" counts (S7, S8)."""
NOT_IMPROVED = 0.9
"""sigma_end / sigma_0 above which an a-priori bound is "not improved" (S7)."""
FUTILE = 0.5
"""sigma_end / sigma_0 above which in-flight calibration of a parameter is futile (S8)."""
ONLY_AFTER = 0.5
"""S4's "q_x, q_y grow only after lift-off": the rise of their sensability over the pad
(after :data:`TRANSIENT_S`) must stay below this share of the gain in the 10 s after
lift-off (docs/assumptions.md, A-S4-only-after)."""
QUIET_GYRO_SCALE = 1e-4
"""Factor on the gyro ARW, bias random walk and initial bias sigma of S5's counterfactual
run: the claim names the gyro errors as the cause, so removing them must make the heading
sensible (docs/assumptions.md, A-S5-cause)."""
GYRO_NOISE_KEYS = ("arw_rad_sqrt_s", "bg_rw_rad_s_sqrt_s")
"""The gyro noise densities S5's counterfactual scales (:data:`QUIET_GYRO_SCALE`)."""
EXCITABILITY_DEPENDS = ("eta", "p0", "sigma_sg_ppm", "spin_hz")
"""The assumptions X1-X7's numbers depend on (the keys of :data:`ROBUSTNESS_GRID`)."""
SENSABILITY_DEPENDS = ("nu", "p0", "sigma_sg_ppm", "spin_hz")
"""The assumptions S1-S8's numbers depend on."""

BASELINE = {"spin_hz": 2.0, "attitude_error": "ecef", "eta": 1e-3, "nu": 0.985,
            "d0": "global", "gnss_sigma_m": 5.0, **P0_DEFAULTS}
"""Baseline settings (spec excitability.md §5, all assumed [A])."""

PARAMETERS = STATE_NAMES[9:]
"""The 12 IMU parameter states (e10-e21)."""
ATTITUDE = STATE_GROUPS["attitude"]


# --------------------------------------------------------------------------- the flight


def _frozen(options: dict | None) -> tuple:
    options = dict(options or {})
    try:
        key = tuple(sorted(options.items()))
        hash(key)
    except TypeError as exc:
        raise NavlibInputError("trajectory_options: expected plain numbers") from exc
    return key


def add_coning(traj, coning_deg: float = 3.0, coning_hz: float = 0.5,
               start_s: float | None = None, ramp_s: float = 2.0):
    """The same flight path with the body coning about its nominal attitude.

    ``C_b_e = C_nom Rx(phi) Ry(alpha) Rx(-phi)``: the body x axis tilts by ``alpha`` (ramped
    in with a smoothstep from ``start_s``, default lift-off) about a lateral axis turning at
    ``coning_hz``. Position, velocity and ``f^e`` are unchanged, so the accelerometers see a
    lateral specific force ``|f| sin(alpha)``; the IMU stays exact (analytic body rate,
    :func:`navlib.trajectory.build_trajectory`). Used to test whether lateral *body* motion
    resolves the X3/S6 tension (it does not: the ECEF attitude error couples through ``f^e``).
    """
    from scipy.spatial.transform import Rotation

    from navlib import earth
    from navlib.trajectory import build_trajectory
    from navlib.trajectory._attitude import smoothstep

    coning_deg = finite_scalar(coning_deg, "coning_deg", 0.0, 30.0)
    coning_hz = finite_scalar(coning_hz, "coning_hz", 0.0)
    ramp_s = finite_scalar(ramp_s, "ramp_s", 0.0, low_open=True)
    if start_s is None:
        start_s = traj.events.get("liftoff", traj.t[0])
    start_s = finite_scalar(start_s, "start_s")
    t = traj.t
    step, dstep, _ = smoothstep((t - start_s) / ramp_s)
    alpha = np.radians(coning_deg) * step
    dalpha = np.radians(coning_deg) * dstep / ramp_s
    dphi = 2.0 * np.pi * coning_hz
    e_x, e_y = np.eye(3)[0], np.eye(3)[1]
    R1 = Rotation.from_rotvec(np.outer(dphi * t, e_x))
    R2 = Rotation.from_rotvec(np.outer(alpha, e_y))
    R3 = R1.inv()
    R = R1 * R2 * R3
    w_R = ((R3.inv() * R2.inv()).apply(np.outer(np.full_like(t, dphi), e_x))
           + R3.inv().apply(np.outer(dalpha, e_y)) - dphi * e_x)
    omega = earth.EARTH_RATE_ECEF
    C_nom = traj.C_b_e()
    w_nom = traj.angular_rate - np.einsum("nji,j->ni", C_nom, omega)
    f_e = np.einsum("nij,nj->ni", C_nom, traj.specific_force)
    acc = f_e - 2.0 * np.cross(omega, traj.velocity) + earth.normal_gravity_ecef(traj.position)
    return build_trajectory(t, traj.position, traj.velocity, acc, C_nom @ R.as_matrix(),
                            R.inv().apply(w_nom) + w_R, events=traj.events,
                            name=f"{traj.name} + coning",
                            parameters={**traj.parameters, "coning_deg": coning_deg,
                                        "coning_hz": coning_hz})


CONING_KEYS = ("coning_deg", "coning_hz")


@lru_cache(maxsize=16)
def _trajectory(spin_hz: float, key: tuple):
    options = dict(key)
    coning = {k: options.pop(k) for k in CONING_KEYS if k in options}
    traj = sounding_rocket(spin_hz=spin_hz, **options)
    return add_coning(traj, **coning) if coning else traj


def rocket_trajectory(spin_hz: float = 2.0, **overrides):
    """The VS30-like flight (:func:`navlib.trajectory.sounding_rocket`), cached per settings.

    ``overrides`` are ``sounding_rocket`` keywords plus ``coning_deg``/``coning_hz``
    (:func:`add_coning`). The same object comes back for the same settings, so the
    discretised model cached on it (:func:`navlib.models.ecef.ecef21_at_epochs`) is reused
    by widgets and sweeps.
    """
    spin_hz = finite_scalar(spin_hz, "spin_hz", 0.0)
    if "spin_hz" in overrides:
        raise NavlibInputError("spin_hz: pass it once, as the first argument")
    return _trajectory(spin_hz, _frozen(overrides))


def rocket_chain(spin_hz: float = 2.0, attitude_error: str = "ecef", sensors=None,
                 gnss_sigma_m: float = 5.0, gnss_rate_hz: float = 1.0,
                 trajectory_options: dict | None = None, **sigmas):
    """The 21-state model of the rocket flight at the GNSS epochs (cached).

    The discretised ``F``, ``Q`` depend only on the trajectory (spin), the attitude-error
    frame and the sensor noise; they are cached. ``P0`` (from ``sigmas``, see
    :data:`navlib.models.ecef.P0_DEFAULTS`) and ``R = gnss_sigma_m^2 I`` are attached
    afterwards at no cost.

    Returns
    -------
    DiscreteModel
        ``t`` (87,) at 1 Hz for the 0-86 s flight, ``F``, ``Q`` (86, 21, 21), ``H``, ``R``,
        ``P0``.
    """
    traj = rocket_trajectory(spin_hz, **dict(_frozen(trajectory_options)))
    base = ecef21_at_epochs(traj, gnss_rate_hz, sensors=sensors, attitude_error=attitude_error)
    gnss_sigma_m = finite_scalar(gnss_sigma_m, "gnss_sigma_m", 0.0, low_open=True)
    R = np.broadcast_to(gnss_sigma_m**2 * np.eye(3), base.R.shape)
    return replace(base, P0=initial_covariance(sensors, **sigmas), R=R)


# --------------------------------------------------------------------------- the analysis


class RocketAnalysis(metrics.SegmentedAnalysis):
    """Excitability per segment and sensability per epoch on the rocket flight.

    A :class:`navlib.metrics.SegmentedAnalysis` of the 21-state model at the GNSS epochs
    (``model`` with ``P0`` and ``R``, ``trajectory`` the flight, ``segments``,
    ``excitability`` one result per segment, ``sensability``, ``settings``: spin, frame, eta,
    nu, D0 choice, GNSS sigma, P0 sigmas) whose frames also carry the paper's state ids
    (``paper_id``, e1-e21).
    """

    def _state_columns(self) -> dict:
        return {**super()._state_columns(),
                "paper_id": [PAPER_IDS[s] for s in self.state_names]}

    def e(self) -> pd.DataFrame:
        """Excitability table: rows states, columns segment labels (``tau1``...)."""
        return self.excitability_table()


def analyze(spin_hz: float = 2.0, attitude_error: str = "ecef", eta: float = 1e-3,
            nu: float = 0.985, segments=SEGMENTS, d0: str = "global",
            gnss_sigma_m: float = 5.0, sensors=None, prior_update: bool = False,
            trajectory_options: dict | None = None, **sigmas) -> RocketAnalysis:
    """Excitability (per segment) and sensability (per epoch) on the rocket flight.

    Parameters
    ----------
    spin_hz : float
        Aerodynamic spin reached in powered flight (assumed 2 Hz; halved at 73 s).
    attitude_error : {"ecef", "body"}
        Attitude-error frame (spec A4); ECEF default (reading of Fig. 4).
    eta : float
        Excitability energy threshold (assumed 1e-3, spec A14).
    nu : float
        Sensability threshold (paper: 0.985).
    segments : sequence of (t_start, t_end)
        Default tau1 = [0, 19], tau2 = [19, 60], tau3 = [60, 86] s.
    d0 : {"global", "filter"}
        D0 of the excitability per segment (spec A19).
    gnss_sigma_m : float
        GNSS position sigma per axis, R = R0 (assumed 5 m).
    sensors : None, str or mapping
        IMU noise (default preset ``motionpak_tactical``).
    prior_update : bool
        Sensability with P0 as a prior updated at t0 (spec A9; default: literal reading).
    trajectory_options : dict, optional
        Further :func:`navlib.trajectory.sounding_rocket` keywords (site, rail, timings).
    **sigmas
        Initial sigmas, see :data:`navlib.models.ecef.P0_DEFAULTS`.
    """
    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(
            f"attitude_error: expected one of {ATTITUDE_ERRORS}, got {attitude_error!r}")
    reject_unknown(sigmas, P0_DEFAULTS, "analyze")
    model = rocket_chain(spin_hz, attitude_error, sensors, gnss_sigma_m,
                         trajectory_options=trajectory_options, **sigmas)
    traj = rocket_trajectory(spin_hz, **dict(_frozen(trajectory_options)))
    settings = {"spin_hz": float(spin_hz), "attitude_error": attitude_error,
                "gnss_sigma_m": float(gnss_sigma_m),
                "sensors": sensors if sensors is None or isinstance(sensors, str) else "custom",
                **{k: float(sigmas.get(k, v)) for k, v in
                   {**P0_DEFAULTS, **parameter_sigmas(sensors)}.items()}}
    return RocketAnalysis.build(model, segments, trajectory=traj, eta=eta, nu=nu, d0=d0,
                                prior_update=prior_update, e_threshold=IN_SO,
                                s_threshold=SENSIBLE, settings=settings)


# --------------------------------------------------------------------------- claim helpers


def _require_three(analysis: RocketAnalysis) -> None:
    if len(analysis.segments) != 3:
        raise NavlibInputError(
            f"segments: the paper's claims need three segments (pad, powered, free fall); "
            f"the analysis has {len(analysis.segments)}")


def _e(analysis: RocketAnalysis, state: str, segment: int) -> float:
    return float(analysis.excitability[segment].e[STATE_NAMES.index(state)])


def _s(analysis: RocketAnalysis, state: str) -> np.ndarray:
    return analysis.sensability.s[:, STATE_NAMES.index(state)]


def _sigma(analysis: RocketAnalysis, state: str) -> np.ndarray:
    return analysis.sensability.sigma[:, STATE_NAMES.index(state)]


def _fmt(values: dict, digits: int = 2) -> str:
    return ", ".join(f"{k} {v:.{digits}f}" for k, v in values.items())


def _assumption(analysis: RocketAnalysis, extra: str = "") -> str:
    s = analysis.settings
    text = (f"eta={s['eta']:g}, D0={s['d0']}, R0=({s['gnss_sigma_m']:g} m)^2 I, "
            f"{s['attitude_error']} attitude error, spin {s['spin_hz']:g} Hz")
    return f"{text}; {extra}" if extra else text


def _sens_assumption(analysis: RocketAnalysis, extra: str = "") -> str:
    s = analysis.settings
    text = (f"nu={s['nu']:g}, P0 posterior at t0 (A9)" if not s["prior_update"]
            else f"nu={s['nu']:g}, P0 prior updated at t0 (A9)")
    text += f", {s['attitude_error']} attitude error, spin {s['spin_hz']:g} Hz"
    return f"{text}; {extra}" if extra else text


# --------------------------------------------------------------------------- X1-X7 (Fig. 2)


def claim_x1(analysis: RocketAnalysis) -> ClaimResult:
    """X1: e1-e6 (P, V) lie mostly in S_O in all three segments (GNSS)."""
    _require_three(analysis)
    states = STATE_GROUPS["position"] + STATE_GROUPS["velocity"]
    mins = {lab: min(_e(analysis, s, i) for s in states) for i, lab in enumerate(SEGMENT_LABELS)}
    checks = [check("min e(P, V) over tau1-tau3", min(mins.values()), ">=", IN_SO, True)]
    return claim("X1", "P and V (e1-e6) lie mostly in S_O in all three segments",
                 "e1-e6 high in tau1, tau2, tau3", f"min e: {_fmt(mins)}", checks,
                 assumption=_assumption(analysis, "sigma_P0/sigma_V0 vs R0 (small P0 breaks "
                                                  "it)"))


def claim_x2(analysis: RocketAnalysis) -> ClaimResult:
    """X2: attitude (e7-e9) in S_O in tau1 and tau2, barely excited in tau3."""
    _require_three(analysis)
    checks = [check(f"min e(attitude) in {lab}", min(_e(analysis, s, i) for s in ATTITUDE),
                    ">=", IN_SO, True) for i, lab in enumerate(SEGMENT_LABELS[:2])]
    checks.append(check("max e(attitude) in tau3 ('barely')",
                        max(_e(analysis, s, 2) for s in ATTITUDE), "<", LOW))
    ours = "; ".join(f"{lab}: " + "/".join(f"{_e(analysis, s, i):.2f}" for s in ATTITUDE)
                     for i, lab in enumerate(SEGMENT_LABELS))
    return claim("X2", "Attitude in S_O in tau1 and tau2, barely excites the innovations in "
                 "tau3", "e7-e9 high in tau1, tau2; low in tau3", f"e7/e8/e9 {ours}", checks,
                 assumption=_assumption(analysis, "heading is not excited at rest (only the "
                                                  "tilt plane), so ECEF components ~ their "
                                                  "tangent-plane projections"))


def claim_x3(analysis: RocketAnalysis) -> ClaimResult:
    """X3: e16 (x-gyro scale factor) becomes excitable in tau2."""
    _require_three(analysis)
    e = [_e(analysis, "sg_x", i) for i in range(3)]
    checks = [check("e16 in tau2", e[1], ">=", IN_SO, True),
              check("e16 tau2 - tau1", e[1] - e[0], ">", 0.0),
              check("e16 tau2 - tau3", e[1] - e[2], ">", 0.0)]
    return claim("X3", "x-gyro scale factor (e16) becomes excitable in tau2 (acceleration "
                 "with spin)", "e16 high in tau2 only",
                 f"e16 {_fmt(dict(zip(SEGMENT_LABELS, e, strict=True)))}", checks,
                 assumption=_assumption(analysis, "needs a large spin x sigma_sg"))


def claim_x4(analysis: RocketAnalysis) -> ClaimResult:
    """X4: e19 (x-accelerometer scale factor) more excitable in tau2 than tau1, still < 1/√2."""
    _require_three(analysis)
    e = [_e(analysis, "sa_x", i) for i in range(3)]
    checks = [check("e19 tau2 - tau1", e[1] - e[0], ">", 0.0, True),
              check("e19 in tau2 (predominantly in S_NO)", e[1], "<", IN_SO)]
    return claim("X4", "x-accelerometer scale factor (e19) more excitable in tau2 than tau1 "
                 "but predominantly in S_NO", "e19 tau2 > tau1, < 1/sqrt(2)",
                 f"e19 {_fmt(dict(zip(SEGMENT_LABELS, e, strict=True)))}", checks,
                 assumption=_assumption(analysis, "thrust ~110 m/s^2 x sigma_sa"))


OTHER_PARAMETERS = tuple(p for p in PARAMETERS if p not in ("sg_x", "sa_x"))
"""IMU parameters other than e16 and e19 (X5, X6)."""


def claim_x5(analysis: RocketAnalysis) -> ClaimResult:
    """X5: all other IMU parameters very low in every segment."""
    _require_three(analysis)
    top = {lab: max(OTHER_PARAMETERS, key=lambda p, i=i: _e(analysis, p, i))
           for i, lab in enumerate(SEGMENT_LABELS)}
    worst = max(_e(analysis, p, i) for i, p in enumerate(top.values()))
    ours = ", ".join(f"{lab} max {_e(analysis, p, i):.2f} ({p})"
                     for i, (lab, p) in enumerate(top.items()))
    return claim("X5", "All other IMU parameters very low in every segment",
                 "e10-e15, e17, e18, e20, e21 ~ 0", ours,
                 [check("max e(other parameters), all segments", worst, "<", LOW, True)],
                 assumption=_assumption(analysis, f"'very low' = e < {LOW}; sigma_bg0 vs "
                                                  "sigma_theta0 sets the pad gyro-bias share"))


def _rms(analysis: RocketAnalysis, states: Sequence[str], segment: int) -> float:
    return float(np.sqrt(np.mean([_e(analysis, s, segment) ** 2 for s in states])))


def claim_x6(analysis: RocketAnalysis) -> ClaimResult:
    """X6: among the low values, biases higher in tau1, scale factors higher in tau2."""
    _require_three(analysis)
    biases = [p for p in OTHER_PARAMETERS if p.startswith("b")]
    scales = [p for p in OTHER_PARAMETERS if p.startswith("s")]
    rb = [_rms(analysis, biases, i) for i in range(3)]
    rs = [_rms(analysis, scales, i) for i in range(3)]
    checks = [check("segment with the largest rms e of the biases", int(np.argmax(rb)) + 1,
                    "==", 1, True),
              check("segment with the largest rms e of the scale factors",
                    int(np.argmax(rs)) + 1, "==", 2, True)]
    ours = (f"rms e biases {'/'.join(f'{v:.3f}' for v in rb)}, scale factors "
            f"{'/'.join(f'{v:.3f}' for v in rs)} (tau1/tau2/tau3)")
    return claim("X6", "Among the low values, biases relatively higher in tau1 and scale "
                 "factors in tau2", "biases: tau1; scale factors: tau2", ours, checks,
                 assumption=_assumption(analysis, "rms over the non-e16/e19 parameters"))


def claim_x7(analysis: RocketAnalysis) -> ClaimResult:
    """X7: tau3 (free fall) unfavourable for in-flight IMU recalibration."""
    _require_three(analysis)
    r = [_rms(analysis, PARAMETERS, i) for i in range(3)]
    top = max(_e(analysis, p, 2) for p in PARAMETERS)
    checks = [check("max e(IMU parameters) in tau3", top, "<", LOW, True),
              check("rms e(parameters) tau3 - tau1", r[2] - r[0], "<", 0.0),
              check("rms e(parameters) tau3 - tau2", r[2] - r[1], "<", 0.0)]
    ours = f"rms e of the 12 parameters {'/'.join(f'{v:.3f}' for v in r)}, max tau3 {top:.2f}"
    return claim("X7", "Free fall (tau3) is unfavourable for in-flight recalibration",
                 "IMU parameters not excitable in tau3", ours, checks,
                 assumption=_assumption(analysis))


def claim_xrank(analysis: RocketAnalysis) -> ClaimResult:
    """España §4: a rank-deficient O_tau leaves a subspace with zero excitability. An
    identity of the SVD (basis "by construction"); the counts show where it applies."""
    _require_three(analysis)
    deficient, bounds = [], []
    for ex in analysis.excitability:
        singular = np.sqrt(np.clip(ex.sigma, 0.0, None))
        resolution = relative_resolution(ex.O.shape)
        beyond = singular <= resolution * singular[0]
        deficient.append(int(beyond.sum()))
        # S_i = n sigma_i^2 / sum(sigma^2) <= n resolution^2 beyond the rank: the computed S
        # there is round-off below that bound (its digits differ between machines)
        bounds.append(len(singular) * resolution**2 if beyond.any() else 0.0)
    checks = [check("segments whose O_tau is rank-deficient", sum(d > 0 for d in deficient),
                    ">=", 1, True),
              check("bound n (max(M, n) eps)^2 on the energy S of a direction beyond the rank",
                    max(bounds), "<=", analysis.excitability[0].eta)]
    ours = ("directions beyond the numerical rank of O_tau per segment: "
            + "/".join(str(d) for d in deficient))
    return claim("X-rank", "A rank-deficient O_tau leaves a subspace with zero excitability",
                 "zero excitability where rank O_tau < n (§4)", ours, checks,
                 basis="by construction",
                 assumption="rank = singular values above the numerical resolution of O_tau "
                            "(navlib.resolution); zero energy there is an identity of the SVD",
                 depends_on=("rank_tolerance",))


# --------------------------------------------------------------------------- S1-S8 (Figs 3-5)


def _pad(analysis: RocketAnalysis) -> np.ndarray:
    """Pad epochs after t0: (tau1 start, ignition] (or tau1 end when earlier)."""
    t_a, t_b = analysis.segments[0]
    ignition = analysis.trajectory.events.get("ignition", t_b)
    return analysis.epochs(t_a, min(t_b, ignition), open_start=True)


def _sensible_time(analysis: RocketAnalysis, state: str, epochs: np.ndarray) -> float:
    """Seconds (epoch count x GNSS period) with s >= SENSIBLE among ``epochs``."""
    if epochs.size == 0:
        return 0.0
    period = float(np.median(np.diff(analysis.model.t)))
    return float(np.count_nonzero(_s(analysis, state)[epochs] >= SENSIBLE) * period)


def claim_s1(analysis: RocketAnalysis) -> ClaimResult:
    """S1: x-position sensability high from the very beginning."""
    _require_three(analysis)
    k = analysis.epochs(*analysis.segments[0], open_start=True)
    s = _s(analysis, "P_x")
    ours = f"min s(P_x) tau1 {s[k].min():.2f}; whole flight {s[1:].min():.2f}"
    return claim("S1", "x-position sensability high from the very beginning",
                 "s(P_x) high from t0", ours,
                 [check("min s(P_x) over tau1", float(s[k].min()), ">=", SENSIBLE, True)],
                 assumption=_sens_assumption(analysis, "epoch t0 left out (s = 1 there by "
                                                       "A9)"))


def claim_s2(analysis: RocketAnalysis) -> ClaimResult:
    """S2: V_x sensability: valley before 5 s, rise near 12 s, ~1 after 55 s."""
    _require_three(analysis)
    t = analysis.model.t
    s = _s(analysis, "V_x")
    k1 = analysis.epochs(*analysis.segments[0], open_start=True)
    kv = k1[np.argmin(s[k1])]
    t_v = float(t[kv])
    late = analysis.epochs(55.0, analysis.segments[2][1])
    rise = analysis.epochs(10.0, 16.0)
    gain = float(s[rise].max() - s[kv]) if rise.size else float("nan")
    mean_late = float(s[late].mean()) if late.size else float("nan")
    checks = [check("time of the V_x valley in tau1, s", t_v, "<=", 5.0, True),
              check("s(V_x) at the valley (deep)", float(s[kv]), "<", SENSIBLE, True),
              check("rise of s(V_x) by 10-16 s above the valley", gain, ">=", 0.2),
              check("mean s(V_x) after 55 s (~1)", mean_late, ">=", 0.9)]
    ours = (f"valley {s[kv]:.2f} at {t_v:.0f} s, max 10-16 s {s[rise].max():.2f}, "
            f"mean after 55 s {mean_late:.2f}")
    return claim("S2", "x-velocity sensability: deep valley before 5 s, rise near 12 s, ~1 "
                 "after 55 s", "valley < 5 s; rise ~12 s; ~1 after 55 s", ours, checks,
                 assumption=_sens_assumption(analysis, "valley timing set by sigma_V0 vs "
                                                       "GNSS sigma"))


def claim_s3(analysis: RocketAnalysis) -> ClaimResult:
    """S3: the V_x 2-sigma band grows after the valley, shrinks after ~12 s, min after 55 s."""
    _require_three(analysis)
    t = analysis.model.t
    s, sig = _s(analysis, "V_x"), _sigma(analysis, "V_x")
    k1 = analysis.epochs(*analysis.segments[0], open_start=True)
    kv = int(k1[np.argmin(s[k1])])
    after = analysis.epochs(t[kv], t[kv] + 7.0, open_start=True)
    k12, k55 = analysis.at(12.0), analysis.at(55.0)
    grow = float(sig[after].max() / sig[kv]) if after.size else float("nan")
    t_min = float(t[int(np.argmin(sig))])
    checks = [check("time of the smallest V_x band, s", t_min, ">=", 55.0, True),
              check("band at 55 s / band at 12 s", float(sig[k55] / sig[k12]), "<", 1.0),
              check("largest band within 7 s after the valley / band at the valley", grow,
                    ">", 1.02)]
    ours = (f"2sigma(V_x) {2 * sig[kv]:.2f} m/s at the valley ({t[kv]:.0f} s), "
            f"max {2 * sig[after].max() if after.size else np.nan:.2f} in the next 7 s, "
            f"{2 * sig[k12]:.2f} at 12 s, {2 * sig[k55]:.2f} at 55 s, min at {t_min:.0f} s")
    return claim("S3", "The V_x 2-sigma band lags the sensability: grows after the valley, "
                 "shrinks after ~12 s, minimum after 55 s",
                 "grow / shrink after 12 s / min after 55 s", ours, checks,
                 assumption=_sens_assumption(analysis))


def _up(analysis: RocketAnalysis) -> np.ndarray:
    """Local vertical (ECEF) at the pad."""
    from navlib import earth

    lat, lon, _ = earth.ecef_to_geodetic(analysis.trajectory.position[0])
    return -earth.ned_to_ecef_matrix(lat, lon)[:, 2]


def tangent_projections(analysis: RocketAnalysis) -> np.ndarray:
    """Norms of the projections of the three attitude-error axes on the pad's tangent plane.

    ECEF axes for the ``ecef`` attitude error, body axes at t0 for ``body`` (spec §3
    prototype: 0.58 / 0.82 / 0.99 for the ECEF axes at the assumed site).
    """
    up = _up(analysis)
    if analysis.settings["attitude_error"] == "body":
        up = analysis.trajectory.C_b_e()[0].T @ up
    return np.sqrt(np.clip(1.0 - up**2, 0.0, None))


def direction_sensability(result: metrics.SensabilityResult, v) -> np.ndarray:
    """Sensability of a physical direction ``v`` (n,) at every epoch (Def. 2 generalised).

    ``v`` is mapped to the normalised coordinates (``D0^-1/2 v``), made unit, and projected
    on the practically sensible subspace ``span{v^1..v^nr}``: ``||V[:, :nr]' w||``.
    """
    v = np.asarray(v, dtype=float)
    if v.shape != (result.n,) or not np.any(v):
        raise NavlibInputError(f"v: expected a non-zero vector of length {result.n}")
    w = v / np.sqrt(result.d0)
    w = w / np.linalg.norm(w)
    proj = np.einsum("kji,j->ki", result.V, w) ** 2
    keep = np.arange(result.n) < result.nr[:, None]
    return np.sqrt(np.sum(proj * keep, axis=1))


def heading_direction(analysis: RocketAnalysis) -> np.ndarray:
    """The 21-vector of a rotation about the local vertical at the pad (heading error)."""
    up = _up(analysis)
    if analysis.settings["attitude_error"] == "body":
        up = analysis.trajectory.C_b_e()[0].T @ up
    v = np.zeros(len(STATE_NAMES))
    v[6:9] = up
    return v


def claim_s4(analysis: RocketAnalysis) -> ClaimResult:
    """S4: on the pad each attitude component is more sensible the larger its tangent-plane
    projection; q_x and q_y grow only after lift-off."""
    _require_three(analysis)
    pad = _pad(analysis)
    proj = tangent_projections(analysis)
    mean_pad = np.array([_s(analysis, s)[pad].mean() for s in ATTITUDE])
    t_lift = analysis.segments[1][0]
    after = analysis.epochs(t_lift, t_lift + 10.0, open_start=True)
    mean_after = np.array([_s(analysis, s)[after].mean() for s in ATTITUDE])
    same_order = bool(np.array_equal(np.argsort(mean_pad), np.argsort(proj)))
    # "only after": on the pad (after the start-up transient) s(theta_x), s(theta_y) must not
    # already rise by a comparable amount (A-S4-only-after)
    late_pad = pad[analysis.model.t[pad] > analysis.model.t[0] + TRANSIENT_S]
    pad_rise = [float(_s(analysis, s)[late_pad[-1]] - _s(analysis, s)[late_pad[0]])
                if late_pad.size else float("nan") for s in ATTITUDE[:2]]
    gain = mean_after[:2] - mean_pad[:2]
    checks = [check("pad order of s(theta) follows the tangent projection", same_order,
                    "==", True, True),
              check("gain of s(theta_x) in the 10 s after lift-off",
                    float(gain[0]), ">", 0.0),
              check("gain of s(theta_y) in the 10 s after lift-off",
                    float(gain[1]), ">", 0.0),
              check("largest rise of s(theta_x), s(theta_y) on the pad / its gain after "
                    "lift-off (only after)",
                    float(max(r / g if g > 0 else np.inf for r, g in zip(pad_rise, gain,
                                                                          strict=True))),
                    "<", ONLY_AFTER)]
    ours = (f"pad mean s {'/'.join(f'{v:.2f}' for v in mean_pad)} vs projections "
            f"{'/'.join(f'{v:.2f}' for v in proj)}; 10 s after lift-off "
            f"{'/'.join(f'{v:.2f}' for v in mean_after)}; rise on the pad "
            f"{'/'.join(f'{v:.3f}' for v in pad_rise)}")
    only_after = checks[-1]
    explanation = "" if only_after.passed else (
        f"on the pad (after the {TRANSIENT_S:g} s transient) s(theta_x), s(theta_y) already "
        f"rise by {pad_rise[0]:.3f} / {pad_rise[1]:.3f}, against {gain[0]:.3f} / "
        f"{gain[1]:.3f} in the 10 s after lift-off (ratio {only_after.value:.3g}): their "
        "rise starts before lift-off")
    return claim("S4", "On the pad the IMU is an inclinometer: attitude components more "
                 "sensible the larger their tangent-plane projection; q_x, q_y grow only "
                 "after lift-off", "order by projection; q_x, q_y rise only after 19 s", ours,
                 checks,
                 assumption=_sens_assumption(analysis, "components in ECEF axes (A4 b); "
                                             f"'only after' = pad rise < {ONLY_AFTER:g} of "
                                             "the gain after lift-off (A-S4-only-after)"),
                 depends_on=SENSABILITY_DEPENDS, explanation=explanation)


def _heading_at_ignition(analysis: RocketAnalysis) -> float:
    pad = _pad(analysis)
    heading = direction_sensability(analysis.sensability, heading_direction(analysis))
    return float(heading[int(pad[-1])])


def quiet_gyro_analysis(analysis: RocketAnalysis, scale: float = QUIET_GYRO_SCALE,
                        sensors=None) -> RocketAnalysis:
    """``analysis`` rerun with the gyro noise (ARW, bias random walk) and the initial gyro
    bias sigma scaled by ``scale``: the counterfactual of S5 ("gyro noise and bias prevent
    measuring the Earth rate", A-S5-cause). ``sensors``: the noise source of ``analysis``
    when it was built from a mapping (default: its named preset)."""
    scale = finite_scalar(scale, "scale", 0.0, 1.0, low_open=True)
    if sensors is None and analysis.settings["sensors"] == "custom":
        raise NavlibInputError("sensors: the analysis was built from a noise mapping; pass "
                               "the same mapping for S5's counterfactual")
    noise = imu_noise_densities(analysis.settings["sensors"] if sensors is None else sensors)
    quiet = {k: (v * scale if k in GYRO_NOISE_KEYS else v) for k, v in noise.items()}
    s = analysis.settings
    sigmas = {k: s[k] for k in P0_DEFAULTS if k in s}
    sigmas["sigma_bg_deg_s"] = sigmas.get("sigma_bg_deg_s", P0_DEFAULTS["sigma_bg_deg_s"]) \
        * scale
    return analyze(s["spin_hz"], s["attitude_error"], s["eta"], s["nu"], d0=s["d0"],
                   gnss_sigma_m=s["gnss_sigma_m"], sensors=quiet,
                   prior_update=s["prior_update"], **sigmas)


def claim_s5(analysis: RocketAnalysis, quiet: RocketAnalysis | None = None) -> ClaimResult:
    """S5: gyro noise and bias hide the Earth rate: excitability at rest does not become
    sensability (heading not sensible on the pad), *because of* the gyro errors: with them
    scaled down (``quiet``, :func:`quiet_gyro_analysis`) the heading becomes sensible."""
    _require_three(analysis)
    pad = _pad(analysis)
    heading = direction_sensability(analysis.sensability, heading_direction(analysis))
    k_end = int(pad[-1])
    P = analysis.sensability.P[k_end, 6:9, 6:9]
    v = heading_direction(analysis)[6:9]
    sigma_heading = float(np.degrees(np.sqrt(v @ P @ v)))
    excited = [s for s in STATE_NAMES if _e(analysis, s, 0) >= IN_SO]
    not_sensible = [s for s in excited if _s(analysis, s)[pad].mean() < SENSIBLE]
    late_pad = pad[analysis.model.t[pad] > analysis.model.t[0] + TRANSIENT_S]
    gyro = STATE_GROUPS["gyro_bias"]
    gyro_max = max(float(_s(analysis, s)[late_pad].max()) for s in gyro) if late_pad.size \
        else float("nan")
    quiet = quiet_gyro_analysis(analysis) if quiet is None else quiet
    quiet_heading = _heading_at_ignition(quiet)
    checks = [check("s(heading) at ignition", float(heading[k_end]), "<", SENSIBLE, True),
              check(f"s(heading) at ignition with the gyro noise and bias x{QUIET_GYRO_SCALE:g}"
                    " (the cause removed)", quiet_heading, ">=", SENSIBLE, True),
              check("max s(gyro bias) on the pad", gyro_max, "<", SENSIBLE),
              check("states excitable at rest but not sensible on the pad",
                    len(not_sensible), ">=", 1)]
    ours = (f"heading s {heading[k_end]:.2f}, 1sigma {sigma_heading:.1f} deg at "
            f"{analysis.model.t[k_end]:.0f} s ({quiet_heading:.2f} with the gyro noise and "
            f"bias x{QUIET_GYRO_SCALE:g}); excitable at rest but not sensible: "
            f"{', '.join(not_sensible) or 'none'}")
    explanation = ""
    if quiet_heading < SENSIBLE:
        explanation = (f"with the gyro ARW, bias random walk and initial bias sigma scaled by "
                       f"{QUIET_GYRO_SCALE:g} the heading sensability at ignition is "
                       f"{quiet_heading:.3g} (baseline {heading[k_end]:.3g}), still below "
                       f"{SENSIBLE:.4g}: in our model the gyro errors are not what keeps the "
                       "heading insensible on the pad")
    return claim("S5", "Gyro noise and bias hide the Earth rate: high excitability at rest "
                 "does not become sensability", "heading not sensible on the pad", ours,
                 checks, assumption=_sens_assumption(analysis, "ARW, sigma_bg0 >> Earth rate "
                                                               "(15 deg/h); the cause tested "
                                                               "by removing it (A-S5-cause)"),
                 depends_on=SENSABILITY_DEPENDS, explanation=explanation)


def claim_s6(analysis: RocketAnalysis) -> ClaimResult:
    """S6: attitude sensability high through tau2 as the band shrinks; declines in tau3 as
    the band grows."""
    _require_three(analysis)
    (a2, b2), (a3, b3) = analysis.segments[1], analysis.segments[2]
    k2 = analysis.epochs(a2, b2)
    i2a, i2b, i3a, i3b = (analysis.at(x) for x in (a2, b2, a3, b3))
    sens = {s: _s(analysis, s) for s in ATTITUDE}
    sig = {s: _sigma(analysis, s) for s in ATTITUDE}
    checks = [
        check("min over theta of mean s in tau2", min(sens[s][k2].mean() for s in ATTITUDE),
              ">=", SENSIBLE, True),
        check("max over theta of band(tau2 end) / band(tau2 start)",
              max(sig[s][i2b] / sig[s][i2a] for s in ATTITUDE), "<", 1.0, True),
        check("max over theta of s(tau3 end) - s(tau3 start)",
              max(sens[s][i3b] - sens[s][i3a] for s in ATTITUDE), "<", 0.0),
        check("min over theta of band(tau3 end) / band(tau3 start)",
              min(sig[s][i3b] / sig[s][i3a] for s in ATTITUDE), ">", 1.0),
    ]
    ratio = {s: float(sig[s][k2].max() / sig[s][0]) for s in ATTITUDE}
    ours = ("mean s tau2 " + "/".join(f"{sens[s][k2].mean():.2f}" for s in ATTITUDE)
            + "; max sigma/sigma0 in tau2 " + "/".join(f"{v:.1f}" for v in ratio.values())
            + "; s at tau3 start->end " + "/".join(
                f"{sens[s][i3a]:.2f}->{sens[s][i3b]:.2f}" for s in ATTITUDE))
    return claim("S6", "Attitude sensability high through tau2 as its band shrinks; declines "
                 "in free fall as the band grows",
                 "high in tau2, band shrinks; declines in tau3", ours, checks,
                 assumption=_sens_assumption(analysis, "spin x sigma_sg drives the roll band "
                                                       "(the X3 tension)"))


def claim_s7(analysis: RocketAnalysis) -> ClaimResult:
    """S7: IMU parameters weakly sensible; one gyro bias briefly sensible in tau2 without
    improving its a-priori bound."""
    _require_three(analysis)
    t = analysis.model.t
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    times = {p: _sensible_time(analysis, p, later) for p in PARAMETERS}
    k2 = analysis.epochs(*analysis.segments[1])
    gyro = STATE_GROUPS["gyro_bias"]
    brief = {g: _sensible_time(analysis, g, k2) for g in gyro}
    candidates = [g for g in gyro if 0 < brief[g] <= BRIEF_S]
    ratio = {g: float(_sigma(analysis, g)[-1] / _sigma(analysis, g)[0]) for g in gyro}
    longest = max(times, key=times.get)
    checks = [check(f"longest sensible time of an IMU parameter ({longest}), s",
                    times[longest], "<=", BRIEF_S, True),
              check("gyro biases briefly (0-10 s) sensible in tau2", len(candidates), ">=", 1),
              check("min sigma_end/sigma_0 of those gyro biases",
                    min((ratio[g] for g in candidates), default=float("nan")), ">=",
                    NOT_IMPROVED)]
    ours = (f"longest sensible parameter {longest} {times[longest]:.0f} s; gyro-bias sensible "
            f"time in tau2 {_fmt(brief, 0)} s; sigma_end/sigma0 {_fmt(ratio)}")
    return claim("S7", "IMU parameters weakly sensible; a gyro bias briefly sensible in tau2 "
                 "without improving its 2-sigma bound",
                 "one b_g component briefly sensible (x or y, A18)", ours, checks,
                 assumption=_sens_assumption(analysis, f"'briefly' <= {BRIEF_S:g} s"))


def claim_s8(analysis: RocketAnalysis) -> ClaimResult:
    """S8: in-flight recalibration futile; an exciting trajectory is necessary but not
    sufficient for sensability."""
    _require_three(analysis)
    t = analysis.model.t
    ratio = {p: float(_sigma(analysis, p)[-1] / _sigma(analysis, p)[0]) for p in PARAMETERS}
    calibrated = [p for p, r in ratio.items() if r < FUTILE]
    excited_not_sensible = []
    for i, (a, b) in enumerate(analysis.segments):
        k = analysis.epochs(a, b)
        excited_not_sensible += [f"{s}@tau{i + 1}" for s in STATE_NAMES
                                 if _e(analysis, s, i) >= IN_SO
                                 and _s(analysis, s)[k].mean() < SENSIBLE]
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    never_excited = [s for s in STATE_NAMES
                     if all(_e(analysis, s, i) < IN_SO for i in range(3))]
    sensible_unexcited = [s for s in never_excited
                          if _sensible_time(analysis, s, later) > BRIEF_S]
    best = min(ratio, key=ratio.get)
    checks = [check(f"smallest sigma_end/sigma_0 of an IMU parameter ({best})", ratio[best],
                    ">=", FUTILE, True),
              check("excited but not sensible (state, segment) pairs",
                    len(excited_not_sensible), ">=", 1),
              check("states sensible > 10 s without being excited", len(sensible_unexcited),
                    "==", 0)]
    listed = ", ".join(f"{p} {ratio[p]:.2f}" for p in calibrated) or "none"
    ours = (f"calibrated in flight: {listed}"
            f"; excited but not sensible: {', '.join(excited_not_sensible[:4]) or 'none'}"
            f"{' ...' if len(excited_not_sensible) > 4 else ''}; sensible without excitation: "
            f"{', '.join(sensible_unexcited) or 'none'}")
    return claim("S8", "In-flight recalibration is futile; an exciting trajectory is necessary "
                 "but not sufficient", "no parameter improves; excitation necessary, not "
                 "sufficient", ours, checks,
                 assumption=_sens_assumption(analysis, f"'calibrated' = sigma_end/sigma0 < "
                                                       f"{FUTILE}"))


EXCITABILITY_CLAIMS = (claim_x1, claim_x2, claim_x3, claim_x4, claim_x5, claim_x6, claim_x7)
SENSABILITY_CLAIMS = (claim_s1, claim_s2, claim_s3, claim_s4, claim_s5, claim_s6, claim_s7,
                      claim_s8)
CLAIM_IDS = tuple(f"X{i}" for i in range(1, 8)) + tuple(f"S{i}" for i in range(1, 9))


BASELINE_BASIS = ("fitted", "the baseline (sigma_V0 3 m/s, sigma_sg 5000 ppm, eta 1e-3) is "
                  "the set at which X1-X7 were made to hold, so X1-X7 are fitted there "
                  "(A-rocket-baseline)")
"""Basis of X1-X7 at the baseline and why (docs/assumptions.md, A-rocket-baseline)."""


def excitability_claims(analysis: RocketAnalysis) -> list[ClaimResult]:
    """X1-X7 (Fig. 2) evaluated on ``analysis``; basis "fitted" (:data:`BASELINE_BASIS`)."""
    basis, why = BASELINE_BASIS
    return [replace(c, depends_on=EXCITABILITY_DEPENDS, basis=basis,
                    assumption=f"{c.assumption}; {why}")
            for c in (claim(analysis) for claim in EXCITABILITY_CLAIMS)]


def sensability_claims(analysis: RocketAnalysis, quiet: RocketAnalysis | None = None
                       ) -> list[ClaimResult]:
    """S1-S8 (Figs. 3-5) evaluated on ``analysis`` (``quiet``: S5's counterfactual run,
    :func:`quiet_gyro_analysis`, computed when not given)."""
    out = [claim_s5(analysis, quiet) if claim is claim_s5 else claim(analysis)
           for claim in SENSABILITY_CLAIMS]
    return [replace(c, depends_on=c.depends_on or SENSABILITY_DEPENDS) for c in out]


def claims_table(analysis: RocketAnalysis, which: str = "all") -> pd.DataFrame:
    """Table of claim results: ``which`` = ``"excitability"``, ``"sensability"`` or ``"all"``."""
    if which not in ("excitability", "sensability", "all"):
        raise NavlibInputError(f"which: expected 'excitability', 'sensability' or 'all', "
                               f"got {which!r}")
    results = []
    if which in ("excitability", "all"):
        results += excitability_claims(analysis)
    if which in ("sensability", "all"):
        results += sensability_claims(analysis)
    return claims_frame(results)


# --------------------------------------------------------------------------- X3 vs S6/S7


TENSION_VARIANTS = {
    "baseline (2 Hz spin, 5000 ppm)": {},
    "spin 1 Hz": {"spin_hz": 1.0},
    "spin 0.5 Hz": {"spin_hz": 0.5},
    "sigma_sg 1000 ppm": {"sigma_sg_ppm": 1000.0},
    "sigma_sg 300 ppm, sigma_bg 0.01 deg/s": {"sigma_sg_ppm": 300.0, "sigma_bg_deg_s": 0.01},
    "sigma_sg 50 ppm": {"sigma_sg_ppm": 50.0},
    "spin 1 Hz, sigma_sg 1000 ppm": {"spin_hz": 1.0, "sigma_sg_ppm": 1000.0},
    "body coning 3 deg at 0.5 Hz": {"trajectory_options": {"coning_deg": 3.0,
                                                           "coning_hz": 0.5}},
    "rail 45 deg (stronger gravity turn)": {"trajectory_options": {"rail_elevation_deg": 45.0}},
    "body-frame attitude error": {"attitude_error": "body"},
}
"""Variants tried against the X3-versus-S6/S7 tension (spec §3 "What the prototype showed"):
lower spin, tighter sigma_sg, lateral motion (body coning; a stronger gravity turn that
rotates f^e), and the other attitude-error frame."""


def tension_table(variants: dict | None = None, sensors=None, progress: bool = False,
                  **common) -> pd.DataFrame:
    """X3 versus S6/S7 across ``variants`` (default :data:`TENSION_VARIANTS`).

    Each variant is a dict of :func:`analyze` keywords on top of ``common``. Columns:
    ``variant``, ``spin_hz``, ``sigma_sg_ppm``, ``roll_drift_deg`` (1-sigma roll drift that
    the gyro-x scale-factor uncertainty builds over tau2: ``sigma_sg * int |omega_x| dt``),
    ``e16_tau2``, ``max_theta_growth`` (largest ``sigma_theta(t)/sigma_theta(0)`` in tau2),
    ``sg_x_sensible_s`` (time with ``s(sg_x) >= 1/sqrt2`` after the start-up transient),
    ``X3``, ``S6``, ``S7`` verdicts, ``all_three`` (X3 reproduced and S6, S7 at least
    partly) and ``n_reproduced`` (of the 15 claims).

    The mechanism the table exposes: X3 needs ``sigma_sg x spin`` large against
    ``sigma_theta0``; the resulting roll drift is a rotation about the thrust axis, which a
    GNSS position fix sees only through the slow turn of ``f^e``, so the ECEF attitude bands
    that project on the rocket axis grow (S6) and sg_x ends up sensible (S7).
    """
    from tqdm.auto import tqdm

    variants = TENSION_VARIANTS if variants is None else dict(variants)
    rows = []
    for name, options in tqdm(list(variants.items()), desc="tension variants",
                              disable=not progress):
        kwargs = {**common, **options}
        a = analyze(sensors=sensors, **kwargs)
        quiet = quiet_gyro_analysis(a, sensors=sensors)
        claims = {c.claim_id: c for c in excitability_claims(a) + sensability_claims(a, quiet)}
        t = a.model.t
        k2 = a.epochs(*a.segments[1])
        traj_t, w_x = a.trajectory.t, np.abs(a.trajectory.angular_rate[:, 0])
        in_tau2 = (traj_t >= a.segments[1][0]) & (traj_t <= a.segments[1][1])
        sigma_sg = a.settings["sigma_sg_ppm"] * 1e-6
        roll = np.degrees(sigma_sg * np.trapezoid(w_x[in_tau2], traj_t[in_tau2]))
        growth = a.sensability.sigma[k2][:, 6:9].max(axis=0) / a.sensability.sigma[0, 6:9]
        later = np.flatnonzero(t > t[0] + TRANSIENT_S)
        verdicts = {k: claims[k].verdict for k in ("X3", "S6", "S7")}
        rows.append({
            "variant": name, "spin_hz": a.settings["spin_hz"],
            "sigma_sg_ppm": a.settings["sigma_sg_ppm"], "roll_drift_deg": roll,
            "e16_tau2": _e(a, "sg_x", 1), "max_theta_growth": float(growth.max()),
            "sg_x_sensible_s": _sensible_time(a, "sg_x", later), **verdicts,
            "all_three": verdicts["X3"] == "reproduced"
            and all(verdicts[k] in ("reproduced", "partly") for k in ("S6", "S7")),
            "n_reproduced": sum(c.verdict == "reproduced" for c in claims.values()),
        })
    return pd.DataFrame(rows)


def tension_findings(table: pd.DataFrame) -> list[str]:
    """Short statements computed from a :func:`tension_table` (for the notebook text)."""
    out = []
    x3 = table[table["X3"] == "reproduced"]
    if len(x3):
        low, high = x3["roll_drift_deg"].min(), x3["roll_drift_deg"].max()
        span = f"{low:.0f}" if round(low) == round(high) else f"{low:.0f}-{high:.0f}"
        out.append(f"X3 reproduced in {len(x3)} of {len(table)} variants; their 1-sigma roll "
                   f"drift over tau2 is {span} deg")
    else:
        out.append("X3 reproduced in no variant")
    ok = table[table["all_three"]]
    out.append("X3 holds together with S6 and S7 (at least partly) in: "
               + (", ".join(ok["variant"]) if len(ok) else "no variant"))
    s7 = table[table["S7"] != "not reproduced"]
    out.append("S7 at least partly reproduced in: "
               + (", ".join(s7["variant"]) if len(s7) else "no variant"))
    quiet = table[table["sg_x_sensible_s"] == 0]
    if len(quiet):
        out.append("sg_x never sensible in: " + ", ".join(
            f"{r.variant} (e16 {r.e16_tau2:.2f})" for r in quiet.itertuples()))
    return out


# --------------------------------------------------------------------------- sweep


P0_SETS = {
    "small (5 m, 0.1 m/s)": {"sigma_p0_m": 5.0, "sigma_v0_m_s": 0.1},
    "baseline (30 m, 3 m/s)": {},
    "large (100 m, 10 m/s)": {"sigma_p0_m": 100.0, "sigma_v0_m_s": 10.0},
}
"""Named initial position/velocity uncertainties of the sweep (spec §3 failure modes)."""

SWEEP_GRID = {
    "eta": (1e-1, 1e-2, 1e-3, 1e-4),
    "nu": (0.98, 0.985, 0.99, 0.995),
    "p0": tuple(P0_SETS),
    "gnss_sigma_m": (1.0, 5.0, 15.0),
    "spin_hz": (0.5, 1.0, 2.0, 3.0),
    "imu_grade": (0.1, 1.0, 10.0),
    "d0": ("global", "filter"),
}
"""Default sweep values. ``imu_grade`` multiplies every noise density and IMU-parameter
sigma of the preset (0.1 ~ navigation grade, 10 ~ consumer grade)."""
QUICK_GRID = {"eta": (1e-2, 1e-4), "nu": (0.99,), "p0": ("small (5 m, 0.1 m/s)",),
              "gnss_sigma_m": (15.0,), "imu_grade": (10.0,), "d0": ("filter",)}
"""A short one-at-a-time sweep for quick mode (one extra discretisation)."""
SWEEP_BASELINE = {"eta": 1e-3, "nu": 0.985, "p0": "baseline (30 m, 3 m/s)",
                  "gnss_sigma_m": 5.0, "spin_hz": 2.0, "imu_grade": 1.0, "d0": "global"}


def _graded(sensors, grade: float):
    noise = imu_noise_densities(sensors)
    if grade == 1.0:
        return sensors, {}
    scaled = {k: v * grade for k, v in noise.items()}
    sigmas = {k: v * grade for k, v in parameter_sigmas(sensors).items()}
    return scaled, sigmas


def _sweep_rows(grid: dict, mode: str) -> list[dict]:
    if mode == "grid":
        names = list(SWEEP_BASELINE)
        values = [grid.get(n, (SWEEP_BASELINE[n],)) for n in names]
        return [dict(zip(names, combo, strict=True), factor="grid")
                for combo in itertools.product(*values)]
    rows = [dict(SWEEP_BASELINE, factor="baseline")]
    for name, values in grid.items():
        rows += [dict(SWEEP_BASELINE, **{name: v}, factor=name) for v in values
                 if v != SWEEP_BASELINE[name]]
    return rows


def _sweep_key(row: dict) -> tuple:
    """The settings that share one discretised model and sensability recursion."""
    return (row["spin_hz"], row["imu_grade"], row["p0"], row["gnss_sigma_m"])


def _sweep_group(rows: list, sensors, attitude_error: str) -> list[dict]:
    """Claim verdicts of sweep rows sharing one :func:`_sweep_key`."""
    first = rows[0]
    imu, grade_sigmas = _graded(sensors, first["imu_grade"])
    base = analyze(first["spin_hz"], attitude_error, nu=SWEEP_BASELINE["nu"],
                   gnss_sigma_m=first["gnss_sigma_m"], sensors=imu, **grade_sigmas,
                   **P0_SETS[first["p0"]])
    by_d0: dict = {}   # one set of segment SVDs per D0 choice, re-thresholded per row
    quiet = quiet_gyro_analysis(base, sensors=imu)   # S5's counterfactual, once per group
    out = []
    for row in rows:
        if row["d0"] not in by_d0:
            by_d0[row["d0"]] = base.with_settings(d0=row["d0"])
        analysis = by_d0[row["d0"]].with_settings(eta=row["eta"], nu=row["nu"])
        claims = excitability_claims(analysis) + sensability_claims(
            analysis, quiet.with_settings(nu=row["nu"]))
        passed = {c.claim_id: c.verdict == "reproduced" for c in claims}
        out.append({"factor": row["factor"], **{k: row[k] for k in SWEEP_BASELINE}, **passed,
                    "n_reproduced": sum(passed.values())})
    return out


def sensitivity_sweep(grid: dict | None = None, mode: str = "one_at_a_time",
                      quick: bool = False, sensors=None, progress: bool = True,
                      attitude_error: str = "ecef", scheduler=None) -> pd.DataFrame:
    """Pass/fail matrix of X1-X7 and S1-S8 over eta, nu, P0, GNSS sigma, spin and IMU grade.

    Parameters
    ----------
    grid : dict, optional
        Values per factor (keys of :data:`SWEEP_GRID`); default :data:`SWEEP_GRID`
        (:data:`QUICK_GRID` with ``quick``).
    mode : {"one_at_a_time", "grid"}
        Vary one factor at a time from :data:`SWEEP_BASELINE` (default), or the full
        factorial grid of the given values.
    quick : bool
        Use :data:`QUICK_GRID` when ``grid`` is None.
    sensors : None, str or mapping
        Base IMU (default preset ``motionpak_tactical``).
    progress : bool
        Show a tqdm progress bar.
    scheduler : optional
        Run the groups of settings sharing one model as Dask tasks
        (:func:`navlib.sweep.map_tasks`: a Client, ``tcp://host:port``, ``"processes"``...);
        default None: in this process.

    Returns
    -------
    DataFrame
        One row per setting: ``factor`` (which factor was varied, "baseline" or "grid"), the
        seven factor columns, one boolean column per claim (True = "reproduced"), and
        ``n_reproduced``.

    Notes
    -----
    Cheap by construction: the trajectory is cached per spin and the discretised model per
    (spin, IMU grade); P0 and R are attached without re-discretising; one sensability
    recursion serves every nu (``with_nu``) and one SVD per segment every eta (``with_eta``).
    """
    from tqdm.auto import tqdm

    if mode not in ("one_at_a_time", "grid"):
        raise NavlibInputError(f"mode: expected 'one_at_a_time' or 'grid', got {mode!r}")
    grid = (QUICK_GRID if quick else SWEEP_GRID) if grid is None else dict(grid)
    reject_unknown(grid, SWEEP_BASELINE, "grid")
    for name, values in grid.items():
        if name == "p0":
            bad = [v for v in values if v not in P0_SETS]
            if bad:
                raise NavlibInputError(f"grid['p0']: unknown set(s) {bad}; use {list(P0_SETS)}")
    rows = _sweep_rows(grid, mode)
    rows.sort(key=lambda r: (r["spin_hz"], r["imu_grade"], r["p0"], r["gnss_sigma_m"],
                             r["d0"], r["nu"], r["eta"]))
    groups = [list(g) for _, g in itertools.groupby(rows, key=_sweep_key)]
    if scheduler is not None:  # one task per shared model (navlib.sweep.map_tasks)
        from navlib.sweep import map_tasks

        parts = map_tasks(partial(_sweep_group, sensors=sensors, attitude_error=attitude_error),
                          groups, scheduler, progress=progress, desc="sensitivity sweep")
        out = [row for part in parts for row in part]
    else:
        out = []
        with tqdm(total=len(rows), desc="sensitivity sweep", disable=not progress) as bar:
            for group in groups:
                out += _sweep_group(group, sensors, attitude_error)
                bar.update(len(group))
    frame = pd.DataFrame(out)
    order = {f: i for i, f in enumerate(["baseline", *grid])}
    frame["_order"] = frame["factor"].map(order).fillna(len(order))
    return frame.sort_values(["_order", *SWEEP_BASELINE]).drop(columns="_order") \
        .reset_index(drop=True)


def sweep_pass_rates(sweep: pd.DataFrame) -> pd.Series:
    """Fraction of the swept settings in which each claim is reproduced."""
    return sweep[list(CLAIM_IDS)].mean().rename("pass_rate")


# --------------------------------------------------------------------------- simpler measures


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
    share = hb.subspace_share(modes, time=float(se.t[-1])) if modes.size else \
        np.zeros(se.n)
    t = analysis.model.t
    later = np.flatnonzero(t > t[0] + TRANSIENT_S)
    frame = pd.DataFrame({"state": analysis.state_names,
                          "paper_id": [PAPER_IDS[s] for s in analysis.state_names]})
    for i, label in enumerate(analysis.labels):
        frame[f"e_{label}"] = analysis.excitability[i].e
    frame["s_end"] = se.s[-1]
    frame["s_sensible_s"] = [_sensible_time(analysis, s, later) for s in analysis.state_names]
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


# --------------------------------------------------------------------------- claims engine


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




ROBUSTNESS_GRID = {
    "eta": (1e-2, 1e-3, 1e-4),
    "nu": (0.98, 0.985, 0.99),
    "p0": tuple(P0_SETS),
    "sigma_sg_ppm": (1000.0, 5000.0),
    "spin_hz": (1.0, 2.0),
}
"""The plausible assumption set of X1-X7 / S1-S8 (full factorial, 108 points): the paper
gives none of eta, nu, P0, sigma_sg or the spin. 12 discretised analyses (spin x P0 x
sigma_sg); eta and nu re-threshold the stored SVDs and eigen-decompositions."""
QUICK_ROBUSTNESS_GRID = {"eta": (1e-2, 1e-3, 1e-4), "nu": (0.98, 0.985, 0.99),
                         "p0": ("baseline (30 m, 3 m/s)",), "sigma_sg_ppm": (5000.0,),
                         "spin_hz": (2.0,)}
"""Quick mode: eta x nu at the baseline P0, sigma_sg and spin (no new discretisation)."""


def robustness_variants(grid: dict | None = None, sensors=None
                        ) -> list[tuple[dict, list[ClaimResult]]]:
    """``(point, X1-X7 and S1-S8)`` at every point of ``grid`` (default
    :data:`ROBUSTNESS_GRID`; a key left out keeps its :data:`BASELINE` value)."""
    grid = ROBUSTNESS_GRID if grid is None else dict(grid)
    reject_unknown(grid, ROBUSTNESS_GRID, "grid")
    grid = {"eta": (BASELINE["eta"],), "nu": (BASELINE["nu"],),
            "p0": ("baseline (30 m, 3 m/s)",), "sigma_sg_ppm": (BASELINE["sigma_sg_ppm"],),
            "spin_hz": (BASELINE["spin_hz"],), **grid}
    out = []
    for spin, p0, sg in itertools.product(grid["spin_hz"], grid["p0"], grid["sigma_sg_ppm"]):
        if p0 not in P0_SETS:
            raise NavlibInputError(f"grid['p0']: unknown set {p0!r}; use {list(P0_SETS)}")
        base = analyze(spin, sensors=sensors, sigma_sg_ppm=sg, **P0_SETS[p0])
        quiet = quiet_gyro_analysis(base, sensors=sensors)
        for eta, nu in itertools.product(grid["eta"], grid["nu"]):
            a = base.with_settings(eta=eta, nu=nu)
            point = {"eta": eta, "nu": nu, "p0": p0, "sigma_sg_ppm": sg, "spin_hz": spin}
            out.append((point, excitability_claims(a)
                        + sensability_claims(a, quiet.with_settings(eta=eta, nu=nu))))
    return out


ROBUSTNESS_BASELINE = {"eta": BASELINE["eta"], "nu": BASELINE["nu"],
                       "p0": "baseline (30 m, 3 m/s)", "sigma_sg_ppm": BASELINE["sigma_sg_ppm"],
                       "spin_hz": BASELINE["spin_hz"]}
"""The baseline point of :data:`ROBUSTNESS_GRID`."""


SEARCH_FILE = "claims_search_rocket.csv"
"""The stored joint search of the España assumption space (``data/``, written by
``scripts/claims_search.py``)."""
SEARCH_PARAMETERS = ("eta", "nu", "sigma_p0_m", "sigma_v0_m_s", "sigma_sg_ppm", "spin_hz")


def search_points(grid: dict | None = None) -> pd.DataFrame:
    """The points of :data:`ROBUSTNESS_GRID` (the declared assumption space, full factorial)
    as :func:`navlib.sweep.sweep` points of its ``"claims"`` evaluation."""
    grid = ROBUSTNESS_GRID if grid is None else dict(grid)
    reject_unknown(grid, ROBUSTNESS_GRID, "grid")
    grid = {**{k: (v,) for k, v in ROBUSTNESS_BASELINE.items()}, **grid}
    rows = []
    for eta, nu, p0, sg, spin in itertools.product(grid["eta"], grid["nu"], grid["p0"],
                                                   grid["sigma_sg_ppm"], grid["spin_hz"]):
        if p0 not in P0_SETS:
            raise NavlibInputError(f"grid['p0']: unknown set {p0!r}; use {list(P0_SETS)}")
        p = {**P0_DEFAULTS, **P0_SETS[p0]}
        rows.append({"eta": eta, "nu": nu, "sigma_p0_m": p["sigma_p0_m"],
                     "sigma_v0_m_s": p["sigma_v0_m_s"], "sigma_sg_ppm": sg, "spin_hz": spin})
    return pd.DataFrame(rows, columns=list(SEARCH_PARAMETERS))


def assumption_search(grid: dict | None = None, scheduler=None, output=None) -> pd.DataFrame:
    """X1-X7 and S1-S8 at every point of the declared assumption space, through
    :func:`navlib.sweep.sweep` (``scheduler``: as there, e.g. ``"synchronous"`` or a Dask
    client); judge it with :func:`navlib.studies.claims.joint_search`."""
    return sweep(search_points(grid), "claims", scheduler=scheduler, output=output)


def stored_search() -> tuple[pd.DataFrame, dict]:
    """The stored search table and its header (``command``, ``navlib`` version)."""
    path = data_dir() / SEARCH_FILE
    if not path.exists():
        raise NavlibInputError(f"{path} is missing: run scripts/claims_search.py")
    header = {}
    with path.open(encoding="utf-8") as handle:
        for line in handle:
            if not line.startswith("#"):
                break
            key, _, value = line[1:].partition(":")
            header[key.strip()] = value.strip()
    return pd.read_csv(path, comment="#"), header


def _baseline_claims(quick: bool = False) -> list[ClaimResult]:
    a = analyze()
    return [*excitability_claims(a), claim_xrank(a), *sensability_claims(a)]


def _robustness(quick: bool = False) -> list:
    return robustness_variants(QUICK_ROBUSTNESS_GRID if quick else ROBUSTNESS_GRID)


engine.register(engine.Study(
    "rocket", "España, Carrizo & Giribet (2019)", _baseline_claims, ROBUSTNESS_GRID,
    _robustness, "full factorial; eta/nu reuse the stored SVDs and eigen-decompositions; "
    "each claim judged on the points varying its depends_on",
    baseline_point=ROBUSTNESS_BASELINE))
