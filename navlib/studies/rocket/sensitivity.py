"""How the rocket verdicts move: the X3-versus-S6/S7 tension over variants of the flight and
sensors, and the pass/fail sensitivity sweep over eta, nu, P0, GNSS sigma, spin and IMU
grade."""

from __future__ import annotations

import itertools
from functools import partial

import numpy as np
import pandas as pd
from tqdm.auto import tqdm

from navlib._validation import reject_unknown
from navlib.errors import NavlibInputError
from navlib.models.ecef import STATE_NAMES, imu_noise_densities, parameter_sigmas
from navlib.parallel import map_tasks
from navlib.studies.rocket.claims import (
    CLAIM_IDS,
    excitability_claims,
    sensability_claims,
    sensible_time,
)
from navlib.studies.rocket.experiment import excitability_study, quiet_gyro_analysis
from navlib.studies.rocket.flight import TRANSIENT_S

__all__ = ["P0_SETS", "QUICK_GRID", "SWEEP_BASELINE", "SWEEP_GRID", "TENSION_VARIANTS",
           "sensitivity_sweep", "sweep_pass_rates", "tension_findings", "tension_table"]

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

    Each variant is a dict of :func:`excitability_study` keywords on top of ``common``. Columns:
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
    variants = TENSION_VARIANTS if variants is None else dict(variants)
    rows = []
    for name, options in tqdm(list(variants.items()), desc="tension variants",
                              disable=not progress):
        kwargs = {**common, **options}
        a = excitability_study(sensors=sensors, **kwargs)
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
            "e16_tau2": float(a.excitability[1].e[STATE_NAMES.index("sg_x")]),
            "max_theta_growth": float(growth.max()),
            "sg_x_sensible_s": sensible_time(a, "sg_x", later), **verdicts,
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
    base = excitability_study(first["spin_hz"], attitude_error, nu=SWEEP_BASELINE["nu"],
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
        (:func:`navlib.parallel.map_tasks`: a Client, ``tcp://host:port``, ``"processes"``...);
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
    if scheduler is not None:  # one task per shared model
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
