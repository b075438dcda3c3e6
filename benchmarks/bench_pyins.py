"""Accuracy and consistency parity of our EKF against python-ins.

``filters.ekf_vs_pyins`` runs our closed-loop EKF (21-state ECEF model) and the feedback filter
of ``python-ins`` (``pyins.filters.run_feedback_filter``: 9 NED navigation states, gyro and
accelerometer biases and scale factors, 21 states) on the **same** simulated sounding-rocket
flights (86 s, 8601 IMU samples at 100 Hz, 1 Hz GNSS position) and prints one parity table.

Data fed to both, per seed: IMU and GNSS from ``navlib.sensors`` (preset
``motionpak_tactical`` with its scale-factor random walks set to zero: pyins has no such
state, so both filters are told exactly the simulated error model: turn-on biases and scale
factors, white noise, bias random walks, 5 m GNSS), and an initial estimate drawn from the
common initial covariance ``P0``: 30 m, 3 m/s per axis and pyins's 1 deg roll, pitch and
heading sigmas mapped to the attitude error at the true initial attitude (pitch 84 deg, so
not isotropic: pyins maps them at its initial estimate). Our EKF takes that ``P0`` with its
own parameter sigmas, which equal pyins's. pyins's gravity (Somigliana with a linear height
term) departs from the simulated normal gravity by up to 2.6e-3 m/s^2 at the 76 km apogee;
ours is the simulated one.

Common error definition (what the NEES compares): estimate minus truth of position and
velocity in the NED axes at the true position (m, m/s) and the attitude error ``phi`` with
``C_true = exp(S(phi)) C_hat`` in those axes (rad), after the update at the GNSS epochs
0..85 s (pyins stops before the epoch on the last IMU sample, 86 s). Ours: the ECEF
navigation block of the 21 states mapped by ``diag(-C, -C, C)`` (``C`` = ECEF -> NED).
pyins: its internal ``DR, DV, PHI`` (Scherzinger's modified velocity error) mapped by
``DV -> DV + S(V) PHI``; its covariance is read from the full history it passes to its
``_compute_sd`` (it returns only the diagonal). The navigation-frame rotation between the
true and the estimated position (``|dr| / R``, 1e-6 rad) is neglected.

Columns: RMS over the epochs of the position / velocity / attitude error norms, mean over
seeds; NEES of the 9 navigation states (and of its 3-state blocks) averaged over seeds and
epochs, with the two-sided 95 % chi^2 bounds of a ``seeds``-run average (``nees_nav_95``)
and the share of epochs whose seed-averaged NEES lies inside them (``nav_in_bounds``);
``us_per_sample``: one run over the flight (seed 0, before the pool starts; our EKF best of
3) per IMU sample. pyins runs at its default 0.1 s covariance step on every seed and at the
equal covariance rate (0.01 s, the IMU step; about 175 s a run on an idle core) on the first
:data:`EQUAL_RATE_SEEDS` seeds, where the table repeats our and pyins's 0.1 s rows on the
same seeds. The untimed runs go to a pool of :data:`WORKERS` processes. The summary row
gives the verdicts (RMS errors all at most pyins's, on all seeds and at equal rate; our
mean NEES inside its bounds and below pyins's) and the speedup at equal covariance rate
(goal at least 100); its goal column is the time budget of the case.

``filters.ekf_nees_vs_gyro_scale`` is the consistency diagnosis, our EKF alone on the same
kind of data with gyro scale-factor sigmas of :data:`GYRO_SCALES_PPM` (simulated and modelled
alike; the preset has 5000 ppm): on the 2 Hz roll of the boost a 5000 ppm error drifts the
roll by degrees per second, the roll error reaches tens of degrees, and the first-order
attitude error model of any EKF (the velocity coupling ``-S(f) phi`` of a tilt in the
presence of a large roll error) no longer holds; with small roll errors the filter is
consistent.

pyins is optional (``pip install -e ".[bench]"``, needs numba): the parity case is skipped
with a message when it is missing.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from dataclasses import replace
from functools import cache
from typing import NamedTuple

import numpy as np
import pandas as pd
from _harness import Case, run_jobs
from _harness import rocket_flight as _rocket
from scipy.spatial.transform import Rotation

from navlib import earth, filters, kalman, sensors, strapdown, units
from navlib.kalman import psd_sqrt
from navlib.models import Ecef21ErrorState
from navlib.models.base import Nominal
from navlib.rotations import log_so3, skew

SEEDS = 20
EQUAL_RATE_SEEDS = 2
PYINS_STEP_S = 0.1
"""pyins's default covariance step."""
IMU_STEP_S = 0.01
WORKERS = 2
BUDGET_S = 900.0
"""Time budget of the parity case (s)."""
GYRO_SCALE_BUDGET_S = 120.0
GYRO_SCALES_PPM = (500.0, 2000.0, 5000.0)
"""Gyro scale-factor sigmas of the consistency diagnosis (the preset's is 5000 ppm)."""
LEVEL_SD_DEG = AZIMUTH_SD_DEG = 1.0
POSITION_SD_M, VELOCITY_SD_M_S = 30.0, 3.0


# --- the data both filters get ---------------------------------------------------------------


@cache
def _spec(gyro_scale_ppm: float | None = None) -> sensors.SensorSpec:
    """``motionpak_tactical`` without scale-factor random walks (pyins models none), with
    the gyro turn-on scale-factor sigma ``gyro_scale_ppm`` when given."""
    spec = sensors.load_preset("motionpak_tactical")
    gyro = replace(spec.imu.gyro, scale_factor_random_walk=0.0)
    if gyro_scale_ppm is not None:
        gyro = replace(gyro, scale_factor=gyro_scale_ppm * units.PPM)
    imu = replace(spec.imu, gyro=gyro,
                  accel=replace(spec.imu.accel, scale_factor_random_walk=0.0))
    return replace(spec, imu=imu)


def _ned(position) -> np.ndarray:
    """ECEF -> NED rotation(s) at ECEF position(s)."""
    lat, lon, _ = earth.ecef_to_geodetic(position)
    return np.swapaxes(earth.ned_to_ecef_matrix(lat, lon), -1, -2)


def _euler_to_tilt(rph_deg) -> np.ndarray:
    """Jacobian (3, 3) of the tilt ``phi`` (NED) wrt roll, pitch, heading (rad) of pyins's
    'xyz' Euler angles of ``C_b_n`` (minus the inverse of pyins's ``_phi_to_delta_rph``,
    whose angle errors are estimate - truth)."""
    _, p, h = np.radians(rph_deg)
    # C = Rz(h) Ry(p) Rx(r): d(phi) = z dh + Rz y dp + Rz Ry x dr
    Rz = Rotation.from_euler("z", h).as_matrix()
    Ry = Rotation.from_euler("y", p).as_matrix()
    return np.column_stack([Rz @ Ry @ [1.0, 0, 0], Rz @ [0, 1.0, 0], [0, 0, 1.0]])


def _nav_p0(trajectory) -> np.ndarray:
    """Common initial covariance (9, 9) of our ECEF navigation states (truth - estimate
    position, velocity; ECEF ``psi``)."""
    C_n_e = _ned(trajectory.position[0]).T
    rph = Rotation.from_matrix(C_n_e.T @ trajectory.attitude[0].as_matrix()).as_euler(
        "xyz", degrees=True)
    T = C_n_e @ _euler_to_tilt(rph)
    P = np.zeros((9, 9))
    P[0:3, 0:3] = POSITION_SD_M**2 * np.eye(3)
    P[3:6, 3:6] = VELOCITY_SD_M_S**2 * np.eye(3)
    sd = np.radians([LEVEL_SD_DEG, LEVEL_SD_DEG, AZIMUTH_SD_DEG])
    P[6:9, 6:9] = T @ np.diag(sd**2) @ T.T
    return P


class Flight(NamedTuple):
    """One seed's data: IMU, GNSS, the initial estimate and the common ``P0``, and the
    sensor spec they were simulated with (our error model built from it)."""

    spec: sensors.SensorSpec
    model: Ecef21ErrorState
    imu: sensors.ImuSimulation
    gnss: pd.DataFrame
    initial: strapdown.StrapdownState
    P0: np.ndarray


@cache
def _flight(seed: int, gyro_scale_ppm: float | None = None) -> Flight:
    """The data of ``seed``: sensors of :func:`_spec` along the rocket flight and the truth
    perturbed by a draw from the common ``P0`` (independent streams of one seed sequence)."""
    traj = _rocket()
    spec = _spec(gyro_scale_ppm)
    g_imu, g_gnss, g_init = (np.random.default_rng(s)
                             for s in np.random.SeedSequence(seed).spawn(3))
    imu = sensors.simulate_imu(traj, spec, rng=g_imu)
    gnss = sensors.simulate_gnss(traj, spec, rng=g_gnss)
    es = Ecef21ErrorState.build(spec, gnss_sigma_m=spec.gnss.position_sigma)
    P0 = np.array(es.P0)
    P0[:9, :9] = _nav_p0(traj)
    dx = np.zeros((1, 21))
    dx[0, :9] = -(g_init.standard_normal(9) @ psd_sqrt(P0[:9, :9]).T)
    hat = es.correct(Nominal(traj.t[:1], traj.position[:1], traj.velocity[:1],
                             traj.attitude[:1].as_matrix(), imu.f_b[:1], imu.w_ib_b[:1], {}),
                     dx)
    initial = strapdown.StrapdownState(t=float(traj.t[0]), position=hat.position[0],
                                       velocity=hat.velocity[0],
                                       q_b_e=Rotation.from_matrix(hat.C_b_e[0]).as_quat())
    return Flight(spec, es, imu, gnss, initial, P0)


# --- errors and covariances in the common definition ------------------------------------------


class Run(NamedTuple):
    """One filter run at the GNSS epochs: common errors (K, 9), covariances (K, 9, 9), cost."""

    errors: np.ndarray
    P: np.ndarray
    seconds: float


def _common_errors(k, position, velocity, C_b_e) -> np.ndarray:
    """Estimate - truth (NED position, velocity) and ``phi`` (NED) at trajectory samples k."""
    traj = _rocket()
    C = _ned(traj.position[k])
    psi = log_so3(traj.attitude[k].as_matrix() @ np.swapaxes(C_b_e, 1, 2))
    blocks = (position - traj.position[k], velocity - traj.velocity[k], psi)
    return np.concatenate([np.einsum("kij,kj->ki", C, b) for b in blocks], axis=1)


def _epochs(flight: Flight) -> np.ndarray:
    """IMU samples of the GNSS epochs both filters update at (pyins stops before an epoch on
    the last IMU sample)."""
    k = np.searchsorted(flight.imu.t, flight.gnss.t.to_numpy())
    return k[k < flight.imu.t.size - 1]


def _run_ours(flight: Flight) -> Run:
    """Our EKF on a flight (model and ``P0`` of the flight), in the common definition."""
    start = time.perf_counter()
    res = filters.ekf(flight.imu, flight.gnss, initial=flight.initial, model=flight.model,
                      P0=flight.P0, keep_covariance=True)
    seconds = time.perf_counter() - start
    k = _epochs(flight)
    assert np.array_equal(res.t[:k.size], flight.imu.t[k])
    C = _ned(_rocket().position[k])
    J = np.zeros((k.size, 9, 9))
    J[:, 0:3, 0:3], J[:, 3:6, 3:6], J[:, 6:9, 6:9] = -C, -C, C
    P = J @ res.P[:k.size, :9, :9] @ np.swapaxes(J, 1, 2)
    errors = _common_errors(k, res.position[:k.size], res.velocity[:k.size],
                            res.C_b_e[:k.size])
    return Run(errors, P, seconds)


def _pyins_inputs(flight: Flight):
    """pyins increments, initial PVA, GNSS measurement and sensor models of a flight."""
    from pyins import inertial_sensor, measurements
    from pyins import strapdown as pyins_strapdown

    imu = flight.imu
    frame = pd.DataFrame(np.hstack([imu.w_ib_b, imu.f_b]), index=imu.t,
                         columns=["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"])
    increments = pyins_strapdown.compute_increments_from_imu(frame, "rate")
    init = flight.initial
    lat, lon, alt = earth.ecef_to_geodetic(init.position)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    rph = Rotation.from_matrix(C_n_e.T @ init.attitude.as_matrix()).as_euler("xyz",
                                                                             degrees=True)
    initial = pd.Series(np.r_[np.degrees(lat), np.degrees(lon), alt, C_n_e.T @ init.velocity,
                              rph],
                        index=["lat", "lon", "alt", "VN", "VE", "VD", "roll", "pitch",
                               "heading"], name=init.t)
    gnss = flight.gnss
    glat, glon, galt = earth.ecef_to_geodetic(gnss[["x", "y", "z"]].to_numpy())
    position = measurements.Position(
        pd.DataFrame({"lat": np.degrees(glat), "lon": np.degrees(glon), "alt": galt},
                     index=gnss.t.to_numpy()), float(gnss.sigma.iloc[0]))
    p = flight.spec.imu
    gyro = inertial_sensor.EstimationModel(
        bias_sd=p.gyro.bias, noise=p.gyro.noise_density, bias_walk=p.gyro.bias_random_walk,
        scale_misal_sd=np.diag([p.gyro.scale_factor] * 3))
    accel = inertial_sensor.EstimationModel(
        bias_sd=p.accel.bias, noise=p.accel.noise_density, bias_walk=p.accel.bias_random_walk,
        scale_misal_sd=np.diag([p.accel.scale_factor] * 3))
    return initial, increments, position, gyro, accel


@contextmanager
def _pyins_covariance():
    """The full covariance history of ``run_feedback_filter``: it hands it to its
    ``_compute_sd`` (python-ins 1.0) and returns only standard deviations."""
    from pyins import filters as pyins_filters

    original = getattr(pyins_filters, "_compute_sd", None)
    if original is None:
        raise RuntimeError("pyins.filters has no _compute_sd: update bench_pyins for this "
                           "python-ins version")
    seen = {}

    def spy(P, trajectory, *args):
        seen["P"], seen["t"] = P, trajectory.index.to_numpy()
        return original(P, trajectory, *args)

    pyins_filters._compute_sd = spy
    try:
        yield seen
    finally:
        pyins_filters._compute_sd = original


def _run_pyins(flight: Flight, step_s: float) -> Run:
    """pyins's feedback filter on a flight with covariance step ``step_s``, in the common
    definition (its trajectory and covariance at the GNSS epochs)."""
    from pyins import filters as pyins_filters

    initial, increments, position, gyro, accel = _pyins_inputs(flight)
    with _pyins_covariance() as seen:
        start = time.perf_counter()
        out = pyins_filters.run_feedback_filter(
            initial, POSITION_SD_M, VELOCITY_SD_M_S, LEVEL_SD_DEG, AZIMUTH_SD_DEG, increments,
            gyro, accel, measurements=[position], time_step=step_s)
        seconds = time.perf_counter() - start
    k = _epochs(flight)
    t = flight.imu.t[k]
    rows = np.searchsorted(seen["t"], t)        # posterior covariance at the GNSS epochs
    assert np.array_equal(seen["t"][rows], t)
    P = seen["P"][rows][:, :9, :9]
    traj = out.trajectory.loc[t]
    lat, lon = np.radians(traj.lat.to_numpy()), np.radians(traj.lon.to_numpy())
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    v_n = traj[["VN", "VE", "VD"]].to_numpy()
    C_b_e = C_n_e @ Rotation.from_euler("xyz", traj[["roll", "pitch", "heading"]].to_numpy(),
                                        degrees=True).as_matrix()
    errors = _common_errors(k, earth.geodetic_to_ecef(lat, lon, traj.alt.to_numpy()),
                            np.einsum("kij,kj->ki", C_n_e, v_n), C_b_e)
    M = np.tile(np.eye(9), (k.size, 1, 1))
    M[:, 3:6, 6:9] = skew(v_n)
    return Run(errors, M @ P @ np.swapaxes(M, 1, 2), seconds)


# --- the parity table -------------------------------------------------------------------------

_BLOCKS = {"nav": slice(0, 9), "pos": slice(0, 3), "vel": slice(3, 6), "att": slice(6, 9)}


def _run(seed: int, filter_name: str, step_s: float, gyro_scale_ppm=None) -> tuple:
    """One accuracy run (a process-pool job): the fields of its :class:`Run`."""
    flight = _flight(seed, gyro_scale_ppm)
    run = _run_ours(flight) if filter_name == "navlib" else _run_pyins(flight, step_s)
    return tuple(run)


def _row(label: dict, runs: list[Run]) -> dict:
    """Table row: ``label``, RMS error norms (mean over seeds), NEES per block (mean over
    seeds and epochs), the 95 % bounds of a len(runs)-seed average of the 9-state NEES and
    the share of epochs inside them."""
    E = np.stack([r.errors for r in runs])
    P = np.stack([r.P for r in runs])
    rms = {name: np.sqrt(np.mean(np.sum(E[..., s] ** 2, axis=-1), axis=1)).mean()
           for name, s in _BLOCKS.items() if name != "nav"}
    nees = {name: np.einsum("ski,ski->sk", E[..., s],
                            np.linalg.solve(P[..., s, s], E[..., s, None])[..., 0]).mean(axis=0)
            for name, s in _BLOCKS.items()}
    lo, hi = kalman.chi2_bounds(9, len(runs))
    return {**label, "seeds": len(runs), "rms_pos_m": rms["pos"], "rms_vel_m_s": rms["vel"],
            "rms_att_deg": np.degrees(rms["att"]),
            **{f"nees_{name}": v.mean() for name, v in nees.items()},
            "nees_nav_95": f"[{lo:.2f}, {hi:.2f}]",
            "nav_in_bounds": float(np.mean((nees["nav"] >= lo) & (nees["nav"] <= hi)))}


def _timed(flight: Flight):
    """Seed-0 runs alone on the machine: ours (best of 3), pyins at both steps (numba compiled
    first on one second of data). Returns the runs and their microseconds per IMU sample."""
    from pyins import filters as pyins_filters

    initial, increments, position, gyro, accel = _pyins_inputs(flight)
    pyins_filters.run_feedback_filter(initial, POSITION_SD_M, VELOCITY_SD_M_S, LEVEL_SD_DEG,
                                      AZIMUTH_SD_DEG, increments.iloc[:100], gyro, accel,
                                      measurements=[position], time_step=PYINS_STEP_S)
    n = flight.imu.t.size
    ours = min((_run_ours(flight) for _ in range(3)), key=lambda r: r.seconds)
    runs = {("navlib", IMU_STEP_S): ours}
    for step in (PYINS_STEP_S, IMU_STEP_S):
        runs[("pyins", step)] = _run_pyins(flight, step)
    return runs, {key: 1e6 * r.seconds / n for key, r in runs.items()}


_TABLE: dict = {}


def _parity() -> None:
    """Every run of the parity table: the timed seed 0, then the other seeds in a process
    pool (longest jobs first)."""
    runs, cost = _timed(_flight(0))
    results = {key: [run] for key, run in runs.items()}
    jobs = [(s, "pyins", IMU_STEP_S) for s in range(1, EQUAL_RATE_SEEDS)]
    jobs += [(s, name, step) for s in range(1, SEEDS)
             for name, step in (("pyins", PYINS_STEP_S), ("navlib", IMU_STEP_S))]
    for (_, name, step), run in zip(jobs, run_jobs(__file__, "_run", jobs, WORKERS),
                                    strict=True):
        results[name, step].append(Run(*run))
    keys = [("navlib", IMU_STEP_S), ("pyins", PYINS_STEP_S)]
    rows = [(key, results[key]) for key in keys]
    rows += [(key, results[key][:EQUAL_RATE_SEEDS]) for key in [*keys, ("pyins", IMU_STEP_S)]]
    _TABLES["parity"] = pd.DataFrame([
        {**_row({"filter": name, "cov_step_s": step}, runs), "us_per_sample": cost[name, step]}
        for (name, step), runs in rows])
    _TABLES["cost"] = cost


def _verdicts(_best: float) -> dict:
    table, cost = _TABLES["parity"], _TABLES["cost"]
    rms = ["rms_pos_m", "rms_vel_m_s", "rms_att_deg"]
    ours = table.iloc[0]
    lo, hi = (float(v) for v in ours["nees_nav_95"].strip("[]").split(","))
    return {"ekf_us_per_sample": cost["navlib", IMU_STEP_S],
            "pyins_equal_rate_us": cost["pyins", IMU_STEP_S],
            "speedup_equal_rate": cost["pyins", IMU_STEP_S] / cost["navlib", IMU_STEP_S],
            "as_accurate": bool((ours[rms] <= table.iloc[1][rms]).all()),
            "as_accurate_equal_rate": bool((table.iloc[2][rms] <= table.iloc[4][rms]).all()),
            "ekf_nees_in_95": bool(lo <= ours["nees_nav"] <= hi),
            "ekf_nees_below_pyins": bool(ours["nees_nav"] <= table.iloc[1]["nees_nav"])}


def _gyro_scale() -> None:
    """Our EKF alone over the seeds at the gyro scale-factor sigmas of
    :data:`GYRO_SCALES_PPM` (simulated and modelled alike)."""
    jobs = [(s, "navlib", IMU_STEP_S, ppm) for ppm in GYRO_SCALES_PPM for s in range(SEEDS)]
    runs = [Run(*r) for r in run_jobs(__file__, "_run", jobs, WORKERS)]
    _TABLES["gyro_scale"] = pd.DataFrame([
        _row({"gyro_scale_ppm": ppm}, runs[i * SEEDS:(i + 1) * SEEDS])
        for i, ppm in enumerate(GYRO_SCALES_PPM)])


_TABLES: dict = {}


def cases() -> list[Case]:
    diagnosis = Case("filters.ekf_nees_vs_gyro_scale",
                     f"rocket 86 s, {SEEDS} seeds x {len(GYRO_SCALES_PPM)} sigmas", _gyro_scale,
                     GYRO_SCALE_BUDGET_S, repeat=1, warmup=False,
                     table=lambda: _TABLES["gyro_scale"],
                     notes="our EKF's NEES against the gyro scale-factor sigma")
    try:
        import pyins  # noqa: F401
    except ImportError as exc:
        print(f"skipping filters.ekf_vs_pyins: python-ins is not installed or fails to import "
              f"({exc}); install it with `pip install -e \".[bench]\"` (needs numba)",
              file=sys.stderr)
        return [diagnosis]
    parity = Case("filters.ekf_vs_pyins", f"rocket 86 s, {SEEDS} seeds, same data", _parity,
                  BUDGET_S, repeat=1, warmup=False, extra=_verdicts,
                  table=lambda: _TABLES["parity"],
                  notes="speedup goal >= 100 at equal covariance rate")
    return [parity, diagnosis]
