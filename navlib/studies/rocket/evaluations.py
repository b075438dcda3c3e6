"""The rocket flight's named evaluations of :func:`navlib.sweep.sweep` ("excitability",
"sensability", "covariance", "nees", "claims"): the 21-state ECEF model on the sounding-rocket
flight (España et al. 2019), its discretisation shared per trajectory and sensor noise, P0 and
R attached per point."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navlib._validation import finite_scalar
from navlib.cache import memoized
from navlib.errors import NavlibInputError
from navlib.filters import simulate_linear
from navlib.metrics import S_THRESHOLD, excitability_segments, sensability_model
from navlib.models.ecef import (
    ATTITUDE_ERRORS,
    ecef21_at_epochs,
    imu_noise_densities,
    initial_covariance,
    parameter_sigmas,
)
from navlib.studies.rocket.claims import excitability_claims, sensability_claims
from navlib.studies.rocket.experiment import RocketAnalysis
from navlib.studies.rocket.flight import (
    GYRO_NOISE_KEYS,
    QUIET_GYRO_SCALE,
    SEGMENT_LABELS,
    SEGMENTS,
    TRANSIENT_S,
    rocket_trajectory,
)
from navlib.sweep import Evaluation, register

__all__: list[str] = []  # nothing to import: importing the module registers its evaluations

_ROCKET_SHARED = {"spin_hz": 2.0, "coning_deg": 0.0, "coning_hz": 0.5,
                  "preset": "motionpak_tactical", "imu_grade": 1.0, "gnss_rate_hz": 1.0,
                  "attitude_error": "ecef"}
_ROCKET_POINT = {"gnss_sigma_m": 5.0, "sigma_p0_m": 30.0, "sigma_v0_m_s": 3.0,
                 "sigma_theta0_deg": 1.0, "sigma_bg_deg_s": None, "sigma_ba_m_s2": None,
                 "sigma_sg_ppm": None, "sigma_sa_ppm": None, "eta": 1e-3, "nu": 0.985,
                 "d0": "global"}


def _rocket_prepare(spin_hz, coning_deg, coning_hz, preset, imu_grade, gnss_rate_hz,
                    attitude_error):
    """The discretised 21-state model (no P0/R yet) and the body x axis at its epochs."""

    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(f"attitude_error: expected one of {ATTITUDE_ERRORS}, got "
                               f"{attitude_error!r}")
    grade = finite_scalar(imu_grade, "imu_grade", 0.0, low_open=True)
    coning = {"coning_deg": coning_deg, "coning_hz": coning_hz} if coning_deg else {}
    traj = rocket_trajectory(spin_hz, **coning)
    noise = preset if grade == 1.0 else {k: v * grade
                                         for k, v in imu_noise_densities(preset).items()}
    model = ecef21_at_epochs(traj, gnss_rate_hz, sensors=noise, attitude_error=attitude_error)
    k = np.clip(np.searchsorted(traj.t, model.t - 1e-9), 0, traj.t.size - 1)
    C = traj.C_b_e()[k]
    roll_axis = C[:, :, 0] if attitude_error == "ecef" else np.tile([1.0, 0.0, 0.0],
                                                                    (k.size, 1))
    return model, roll_axis


def _rocket_model(prepared, full):
    """The prepared model with this point's P0 and R."""

    base, _ = prepared
    grade = float(full["imu_grade"])
    sigmas = {k: v * grade for k, v in parameter_sigmas(full["preset"]).items()}
    for name in _ROCKET_POINT:
        if name.startswith("sigma_") and full[name] is not None:
            sigmas[name] = full[name]
    sigma = finite_scalar(full["gnss_sigma_m"], "gnss_sigma_m", 0.0, low_open=True)
    R = np.broadcast_to(sigma**2 * np.eye(3), base.R.shape)
    return replace(base, P0=initial_covariance(full["preset"], **sigmas), R=R)


def _sensability(model, full):

    return sensability_model(model, nu=full["nu"])


def _excitability_run(prepared, **full) -> dict:

    model = _rocket_model(prepared, full)
    se = _sensability(model, full) if full["d0"] == "filter" else None
    ex = excitability_segments(model, SEGMENTS, full["eta"], full["d0"], se)
    out = {}
    for label, res in zip(SEGMENT_LABELS, ex, strict=True):
        out[f"ne_{label}"] = int(res.ne)
        out.update({f"e_{s}_{label}": float(v) for s, v in zip(model.state_names, res.e,
                                                               strict=True)})
    return out


def _roll_sensability(se, roll_axis) -> tuple[np.ndarray, np.ndarray]:
    """Sensability and 1-sigma (rad) of the attitude error about the body x (roll) axis."""
    v = np.zeros((roll_axis.shape[0], se.n))
    v[:, 6:9] = roll_axis
    w = v / np.sqrt(se.d0)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    proj = np.einsum("kji,kj->ki", se.V, w) ** 2
    keep = np.arange(se.n) < se.nr[:, None]
    sigma = np.sqrt(np.einsum("ki,kij,kj->k", v, se.P, v))
    return np.sqrt(np.sum(proj * keep, axis=1)), sigma


def _sensability_run(prepared, **full) -> dict:

    model = _rocket_model(prepared, full)
    se = _sensability(model, full)
    later = se.t > se.t[0] + TRANSIENT_S
    s_roll, sigma_roll = _roll_sensability(se, prepared[1])
    out = {"nr_end": int(se.nr[-1]),
           "n_sensible_end": int(np.sum(se.s[-1] >= S_THRESHOLD)),
           "s_end_roll": float(s_roll[-1]),
           "s_frac_roll": float(np.mean(s_roll[later] >= S_THRESHOLD)),
           "sigma_end_roll_deg": float(np.degrees(sigma_roll[-1]))}
    for j, s in enumerate(model.state_names):
        out[f"s_end_{s}"] = float(se.s[-1, j])
        out[f"s_frac_{s}"] = float(np.mean(se.s[later, j] >= S_THRESHOLD))
    # the same recursion's covariance columns, so that a grid needing both runs it once
    return {**out, **_covariance_columns(model, se)}


def _covariance_run(prepared, **full) -> dict:
    model = _rocket_model(prepared, full)
    return _covariance_columns(model, _sensability(model, full))


def _covariance_columns(model, se) -> dict:
    """``sigma_end_<state>`` (physical 1-sigma at the last epoch) and ``ratio_<state>``
    (``sigma_0 / sigma_end``) of a sensability result ``se`` of ``model``."""
    sigma0 = np.sqrt(np.diag(model.P0))
    out = {}
    for j, s in enumerate(model.state_names):
        out[f"sigma_end_{s}"] = float(se.sigma[-1, j])
        out[f"ratio_{s}"] = float(sigma0[j] / se.sigma[-1, j])
    return out


def _nees_run(prepared, *, runs, seed, **full) -> dict:

    model = _rocket_model(prepared, full)
    sim = simulate_linear(model, runs=int(runs), seed=int(seed))
    c = sim.consistency()
    frame = sim.nees_frame()
    return {"nees_in_bounds": c["nees"], "nees_mean_over_dof": c["nees_mean_over_dof"],
            "nis_in_bounds": c["nis"], "nis_mean_over_dof": c["nis_mean_over_dof"],
            "nees_end": float(frame["nees"].iloc[-1]), "nees_dof_end": int(frame["dof"].iloc[-1])}


def _claims_run(prepared, **full) -> dict:

    coning = {"coning_deg": full["coning_deg"], "coning_hz": full["coning_hz"]} \
        if full["coning_deg"] else {}
    analysis = RocketAnalysis.build(
        _rocket_model(prepared, full), SEGMENTS,
        trajectory=rocket_trajectory(full["spin_hz"], **coning), eta=full["eta"],
        nu=full["nu"], d0=full["d0"],
        settings={k: full[k] for k in ("spin_hz", "attitude_error", "gnss_sigma_m", "preset",
                                       "imu_grade", "coning_deg")})
    claims = excitability_claims(analysis) + sensability_claims(
        analysis, _quiet_gyro_analysis(full))
    passed = {c.claim_id: c.verdict == "reproduced" for c in claims}
    return {**passed, "n_reproduced": int(sum(passed.values()))}


@memoized(maxsize=4)
def _quiet_model(spin_hz, coning_deg, coning_hz, preset, imu_grade, gnss_rate_hz,
                 attitude_error):
    """The discretised model of :func:`_rocket_prepare` with the gyro noise scaled by
    :data:`QUIET_GYRO_SCALE` (kept per process: the points of a shared input reuse it)."""

    grade = float(imu_grade)
    noise = {k: v * grade * (QUIET_GYRO_SCALE if k in GYRO_NOISE_KEYS else 1.0)
             for k, v in imu_noise_densities(preset).items()}
    coning = {"coning_deg": coning_deg, "coning_hz": coning_hz} if coning_deg else {}
    traj = rocket_trajectory(spin_hz, **coning)
    return traj, ecef21_at_epochs(traj, gnss_rate_hz, sensors=noise,
                                  attitude_error=attitude_error)


def _quiet_gyro_analysis(full):
    """S5's counterfactual of a "claims" point: the same model with the gyro noise and the
    initial gyro-bias sigma scaled by :data:`QUIET_GYRO_SCALE` (docs/assumptions.md,
    A-S5-cause)."""

    scale, grade = QUIET_GYRO_SCALE, float(full["imu_grade"])
    traj, model = _quiet_model(*(full[k] for k in _ROCKET_SHARED))
    bg = full["sigma_bg_deg_s"]
    bg = parameter_sigmas(full["preset"])["sigma_bg_deg_s"] * grade if bg is None else bg
    quiet = {**full, "sigma_bg_deg_s": bg * scale}
    return RocketAnalysis.build(
        _rocket_model((model, None), quiet), SEGMENTS, trajectory=traj,
        eta=full["eta"], nu=full["nu"], d0=full["d0"],
        settings={k: full[k] for k in ("spin_hz", "attitude_error", "gnss_sigma_m", "preset",
                                       "imu_grade", "coning_deg")})


_PARAMETERS = {**_ROCKET_SHARED, **_ROCKET_POINT}
_SHARED = tuple(_ROCKET_SHARED)

register(Evaluation("excitability", "rocket flight: e of the 21 states per segment "
                    "(e_<state>_tauN, ne_tauN)", _PARAMETERS, _SHARED, _excitability_run,
                    _rocket_prepare))
register(Evaluation("sensability", "rocket flight: sensability at the end and share of the "
                    "epochs after the transient with s >= 1/sqrt2, per state and for the roll "
                    "axis; and the columns of 'covariance' from the same recursion",
                    _PARAMETERS, _SHARED, _sensability_run, _rocket_prepare))
register(Evaluation("covariance", "rocket flight: physical 1-sigma at the end and "
                    "sigma_0/sigma_end per state", _PARAMETERS, _SHARED, _covariance_run,
                    _rocket_prepare))
register(Evaluation("nees", "rocket flight: linear Monte-Carlo filter consistency (NEES/NIS "
                    "share inside the 95 % chi-square bounds)",
                    {**_PARAMETERS, "runs": 20, "seed": 0}, _SHARED, _nees_run,
                    _rocket_prepare))
register(Evaluation("claims", "rocket flight: verdicts of the paper's X1-X7 and S1-S8 "
                    "statements (True = reproduced)", _PARAMETERS, _SHARED, _claims_run,
                    _rocket_prepare))
