"""Closed-loop INS/GNSS error-state EKF in ECEF (docs/assumptions.md, launcher.md §6.2-6.4).

:func:`ekf` is described in its docstring (ECEF strapdown nominal state, error-state
covariance from the model's Jacobians along the estimate, GNSS / attitude /
reference-trajectory updates, feedback resets); the updates within a feedback window are
:mod:`navlib.filters.ekf_updates`, and :func:`navlib.filters.simulate.simulate_ekf`
feeds it simulated sensors (:mod:`navlib.sensors`). The loop knows no model: the error
model is an :class:`~navlib.models.base.ErrorStateModel` (layout, reset states,
``jacobians``, ``correct``, decay; :class:`~navlib.models.launcher.LauncherErrorState`,
:class:`~navlib.models.ecef.Ecef21ErrorState`) and each measurement a
:class:`~navlib.filters.measurements.Measurement` (innovation, ``H``, ``R``).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from navlib import strapdown
from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError
from navlib.filters.ekf_loop import compiled_run
from navlib.filters.ekf_updates import Epochs, WindowUpdates, update_records
from navlib.filters.linear_preparation import METHODS
from navlib.filters.measurements import Measurement, ekf_measurements, epoch_index, imu_arrays
from navlib.kalman import symmetrize
from navlib.models.base import ErrorStateModel, Nominal
from navlib.models.ecef import Ecef21ErrorState
from navlib.models.launcher import LauncherErrorState
from navlib.quaternions import quat_from_matrix
from navlib.rotations import log_so3
from navlib.sparse_discretize import discretize_window

__all__ = ["FAMILIES", "EKFResult", "EKFSnapshot", "ekf", "error_model"]

_MODELS = {"launcher": LauncherErrorState, "ecef21": Ecef21ErrorState}
FAMILIES = tuple(_MODELS)
"""Error-model families the EKF runs with: Beaudoin's launcher models
(:func:`navlib.models.launcher`) and España's 21-state ECEF model
(:func:`navlib.models.ecef21`)."""
_AXES = ("x", "y", "z")


def error_model(model, t, solution, biases, bias_model, options, gnss_velocity_sigma,
                 sensors=None) -> ErrorStateModel:
    """The error-state model named ``model`` configured from the EKF's keywords (or
    ``model`` itself when it is one)."""
    if not isinstance(model, str):
        return model
    if model not in _MODELS:
        raise NavlibInputError(f"model: expected one of {FAMILIES}, got {model!r}")
    return _MODELS[model].from_options(
        dict(options or {}), step_s=float(np.median(np.diff(t))), solution=solution,
        biases=biases, bias_model=bias_model, gnss_velocity_sigma=gnss_velocity_sigma,
        sensors=sensors)


@dataclass(frozen=True, eq=False)
class EKFSnapshot:
    """The state of the :func:`ekf` loop at the start of one propagation window and the
    results before it, to resume another run there (``ekf(..., resume=...)``).

    A run whose inputs equal this run's up to ``sample`` (e.g. the same simulated sensors
    with an outlier after it) computes exactly the same up to there, so resuming gives
    the same numbers as running it from the start.

    Attributes
    ----------
    window : int
        Index of the window in ``bounds``.
    sample : int
        IMU sample where that window starts (``t`` its time).
    t : float
    bounds : tuple of int
        The run's window boundaries (a resumed run must have the same).
    imu : ndarray (sample + 1, 6)
        The IMU samples (specific force, rate) up to ``sample``, checked on resume.
    state : tuple
        ``(x, (r, v, C), params, P)``: error-state mean, nominal state, parameter
        estimates and covariance at the window start.
    results : dict
        The per-update results before the window.
    """

    window: int
    sample: int
    t: float
    bounds: tuple
    imu: np.ndarray
    state: tuple
    results: dict


@dataclass(frozen=True, eq=False)
class EKFResult:
    """Output of :func:`ekf` at the measurement-update epochs (posterior, after correction).

    Attributes
    ----------
    t : ndarray (K,)
    position, velocity : ndarray (K, 3)
        Estimated ECEF position (m) and velocity (m/s).
    C_b_e : ndarray (K, 3, 3)
        Estimated body -> ECEF attitude.
    parameters : dict
        Parameter estimates (K, 3) by group: ``bg``, ``ba`` (+ ``sg``, ``sa`` for ecef21,
        ``bp`` for launcher models with the GPS bias, in the model's convention: minus the
        GPS position bias, docs/assumptions.md, launcher.md §3.1 ``C_lc``).
    kept : ndarray (K, n_kept)
        Estimates of the non-reset states (the reference-trajectory block), names in
        ``kept_names``.
    sigma : ndarray (K, n)
        Posterior error-state standard deviations.
    P : ndarray (K, n, n) or None
        Posterior covariances when ``keep_covariance``.
    innovation : ndarray (K, m)
        Innovations (NaN for rows not measured at that epoch).
    nis : ndarray (K,), nis_dof : ndarray (K,)
    state_names, measurement_names, kept_names : tuple of str
    model : str
    snapshot : EKFSnapshot or None
        The loop state taken with ``ekf(..., snapshot_before=...)``.
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    C_b_e: np.ndarray
    parameters: dict
    kept: np.ndarray
    sigma: np.ndarray
    P: np.ndarray | None
    innovation: np.ndarray
    nis: np.ndarray
    nis_dof: np.ndarray
    state_names: tuple[str, ...]
    measurement_names: tuple[str, ...]
    kept_names: tuple[str, ...]
    model: str
    snapshot: EKFSnapshot | None = None

    @property
    def attitude(self):
        return Rotation.from_matrix(self.C_b_e)

    def sigma_of(self, names: Sequence[str]) -> np.ndarray:
        lookup = {s: i for i, s in enumerate(self.state_names)}
        missing = [s for s in names if s not in lookup]
        if missing:
            raise NavlibInputError(f"unknown state(s) {missing}")
        return self.sigma[:, [lookup[s] for s in names]]

    def errors(self, trajectory) -> pd.DataFrame:
        """Navigation errors against a reference trajectory sampled on the same clock.

        Columns ``t``, ``pos_x..z`` (estimate - truth, ECEF m), ``vel_x..z`` (m/s),
        ``att_x..z`` (ECEF rotation vector of ``C_true C_hat'``, rad: the ``psi`` of
        ``C_true = (I + S(psi)) C_hat``), ``roll, pitch, yaw`` (that vector in body axes,
        ``T_E^B psi``, docs/assumptions.md, launcher.md §6.2 item 6).
        """
        k = epoch_index(np.asarray(trajectory.t, dtype=float), self.t, "result")
        C = trajectory.attitude[k].as_matrix()
        psi = log_so3(C @ np.swapaxes(self.C_b_e, 1, 2))
        body = np.einsum("kji,kj->ki", C, psi)
        dp = self.position - trajectory.position[k]
        dv = self.velocity - trajectory.velocity[k]
        cols = {"t": self.t}
        for name, arr in (("pos", dp), ("vel", dv), ("att", psi)):
            for i, a in enumerate(_AXES):
                cols[f"{name}_{a}"] = arr[:, i]
        for i, a in enumerate(("roll", "pitch", "yaw")):
            cols[a] = body[:, i]
        return pd.DataFrame(cols)

    def to_frame(self) -> pd.DataFrame:
        """Tidy estimates: ``t``, ECEF ``x, y, z, vx, vy, vz``, quaternion ``qx..qw``,
        parameters ``<group>_<axis>``, NIS."""
        q = Rotation.from_matrix(self.C_b_e).as_quat()
        cols = {"t": self.t}
        for i, a in enumerate(_AXES):
            cols[a] = self.position[:, i]
        for i, a in enumerate(_AXES):
            cols[f"v{a}"] = self.velocity[:, i]
        for i, a in enumerate(("qx", "qy", "qz", "qw")):
            cols[a] = q[:, i]
        for group, values in self.parameters.items():
            for i, a in enumerate(_AXES):
                cols[f"{group}_{a}"] = values[:, i]
        for j, name in enumerate(self.kept_names):
            cols[name] = self.kept[:, j]
        cols["nis"] = self.nis
        cols["nis_dof"] = self.nis_dof
        return pd.DataFrame(cols)

    def sigma_frame(self) -> pd.DataFrame:
        """Tidy ``t, state, sigma``."""
        n = len(self.state_names)
        return pd.DataFrame({
            "t": np.repeat(self.t, n),
            "state": np.tile(np.array(self.state_names, dtype=object), self.t.size),
            "sigma": self.sigma.ravel(),
        })


def ekf(imu, gnss=None, *, initial, model: str | ErrorStateModel = "launcher",
        solution: str = "ins_gps", biases: str = "GA", bias_model: str = "markov",
        model_options: dict | None = None, P0=None, attitude=None, reference=None,
        gnss_velocity_sigma: float | None = None, initial_parameters: dict | None = None,
        method: str | None = None, window_s: float = 0.1, keep_covariance: bool = False,
        measurements: Sequence[Measurement] = (), snapshot_before: float | None = None,
        resume: EKFSnapshot | None = None) -> EKFResult:
    """Closed-loop (feedback) INS/GNSS error-state extended Kalman filter in ECEF.

    * **Nominal state**: ECEF position, velocity and attitude propagated by the strapdown
      mechanisation (:func:`navlib.strapdown.integrate`) on the IMU samples, after
      compensating them with the current parameter estimates (gyro/accelerometer biases,
      and scale factors for the 21-state model); Markov parameter estimates decay with
      their model time constant between updates.
    * **Error state**: the states of the chosen error model, ``launcher`` (Beaudoin et al.
      2018 eq. 1-5, 8: ``psi, dv, dr`` [``bg, ba, bp``] [RT block], ``solution``,
      ``biases``, ``bias_model`` as in :func:`navlib.models.launcher`) or ``ecef21``
      (España et al. 2019 Eq. 24). Its covariance is propagated with the model's ``F``,
      ``Q`` whose Jacobians are evaluated **along the estimate** (the nominal trajectory
      and corrected IMU signals, ``jacobians(nominal)`` of the error-state model), sample
      by sample.
    * **Updates**: GNSS position and velocity (launcher: ``z = INS - GNSS``, with the GPS
      bias estimate removed from the position; ecef21: ``z = GNSS - INS``, position only
      unless ``gnss_velocity_sigma`` is given); the attitude sensor for ``*_att``
      solutions (``z = rotvec(C_att C_hat')``, ECEF); the reference-trajectory
      pseudo-measurement for ``*_rt`` solutions (eq. 8, ``z = rotvec(C_hat' C_ref)``, body
      axes, noise-free); Joseph form, pseudo-inverse of the innovation covariance when
      ``R`` is singular (as :func:`navlib.covariance.kalman_covariance`).
    * **Feedback**: position, velocity, attitude and the IMU/GNSS parameters are corrected
      with the error-state estimate and those states are zeroed; the reference-trajectory
      states (the launcher's divergence from its reference, docs/assumptions.md, launcher.md §3.4)
      have no nominal counterpart and keep their estimate. Corrections are fed back at the end of
      each propagation window (every measurement epoch when epochs are at least
      ``window_s`` apart, else every ``window_s``); within a window the error-state mean
      is carried by the linearised model, as in a linearised KF. The attitude reset
      carries the covariance through its Jacobian, ``I + S(a)/2`` for the ECEF attitude
      error ``C = exp(S(psi)) C_hat`` corrected by ``a`` (``I - S(a)/2`` for the body
      error; :meth:`~navlib.models.base.ErrorStateModel.reset_jacobian`); it matters when
      corrections are large (the rocket's roll errors of tens of degrees).

    Parameters
    ----------
    imu : navlib.sensors.ImuSimulation or DataFrame (t, f_x, f_y, f_z, w_x, w_y, w_z)
        Measured IMU samples (point samples, SI).
    gnss : DataFrame, optional
        ``t, x, y, z`` ECEF position (m) and optionally ``vx, vy, vz`` (m/s); epochs on IMU
        samples.
    initial : navlib.strapdown.StrapdownState
        Nominal state at the first IMU sample.
    model : {"launcher", "ecef21"} or ErrorStateModel
        Error-model family (configured from the keywords below), or a configured
        :class:`~navlib.models.base.ErrorStateModel` (then ``solution``, ``biases``,
        ``bias_model``, ``model_options`` and ``gnss_velocity_sigma`` are not used).
    solution, biases, bias_model
        Launcher configuration (ignored for ecef21).
    model_options : dict, optional
        Keywords of the model builder (``sigma_gps_vel``, ``a1_sign``, ... for launcher;
        ``sensors``, ``gnss_sigma_m``, ``attitude_error``, P0 sigmas for ecef21).
    P0 : ndarray (n, n), optional
        Initial error covariance (default the model's).
    attitude : (t, Rotation) or DataFrame (t, qx, qy, qz, qw), optional
        Attitude-sensor body -> ECEF attitudes (``*_att`` solutions).
    reference : (t, Rotation) or callable, optional
        Reference-trajectory attitudes for ``*_rt`` solutions, or a callable
        ``reference(k, t_k, C_nav_prev) -> (3, 3)`` called at every IMU sample with the
        posterior navigation attitude of the previous call (None at the first; see
        :class:`ReferenceTrajectory`).
    gnss_velocity_sigma : float, optional
        ecef21 only: use GNSS velocity with this sigma (m/s).
    initial_parameters : dict, optional
        Initial parameter estimates (3,) by group (``bg``, ``ba``, ``sg``, ``sa``, ``bp``);
        default zero.
    method : {"euler", "expm"}, optional
        Per-step discretisation (default ``euler`` for launcher models as in the paper,
        ``expm`` — batched series — for ecef21).
    window_s : float
        Longest propagation window between feedback corrections when updates are denser.
    keep_covariance : bool
        Keep the full posterior covariances in the result.
    measurements : sequence of Measurement, optional
        Further measurements (:class:`~navlib.filters.measurements.Measurement` instances
        built with this error model and IMU sample indices), updated after the ones above at
        their epochs; their rows follow the model's in the result.
    snapshot_before : float, optional
        Keep the loop state at the start of the last propagation window that starts before
        this time, s (``result.snapshot``).
    resume : EKFSnapshot, optional
        Start at a snapshot of another run instead of at the first sample: the IMU samples
        up to the snapshot must be the same (checked) and so must the aiding data (the
        caller's promise, as for the same simulated sensors with an outlier after it); the
        result is then that of the whole run. Not with measurements that watch the
        filter's posterior (the closed-loop reference trajectory), whose own state the
        snapshot does not hold.

    Returns
    -------
    EKFResult
    """
    t, f_meas, w_meas = imu_arrays(imu)
    es = error_model(model, t, solution, biases, bias_model, model_options,
                      gnss_velocity_sigma)
    method = method or es.default_method
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    window_s = finite_scalar(window_s, "window_s", 0.0, low_open=True)
    start = (finite_array(initial.position, "initial.position", (3,)),
             finite_array(initial.velocity, "initial.velocity", (3,)),
             initial.attitude.as_matrix())
    n = len(es.state_names)
    P = symmetrize(np.array(es.P0 if P0 is None else finite_array(P0, "P0", (n, n)), dtype=float))
    params = {g: np.zeros(3) for g in es.parameters}
    for g, v in (initial_parameters or {}).items():
        if g not in params:
            raise NavlibInputError(f"initial_parameters: model has no parameter group {g!r}")
        params[g] = finite_array(v, f"initial_parameters[{g!r}]", (3,)).copy()
    names = [name for r in es.measurements.values() for name in r.names]
    offsets = dict(zip(es.measurements, np.cumsum([0] + [len(r.names) for r in
                                                         es.measurements.values()]),
                       strict=False))
    rows = {meas: np.arange(offsets[meas.kind], offsets[meas.kind] + len(meas.names))
            for meas in ekf_measurements(es, t, gnss, attitude, reference)}
    for meas in measurements:
        if not isinstance(meas, Measurement):
            raise NavlibInputError(f"measurements: expected Measurement instances, got "
                                   f"{type(meas).__name__}")
        if meas.index.size and (meas.index.min() < 0 or meas.index.max() >= t.size):
            raise NavlibInputError(f"measurements: {meas.kind} epochs must be IMU sample "
                                   f"indices in [0, {t.size - 1}]")
        rows[meas] = np.arange(len(names), len(names) + len(meas.names))
        names += meas.names
    events = {}            # IMU sample -> [(measurement, epoch)], in update order
    for meas in rows:
        for i, k in enumerate(meas.index.tolist()):
            events.setdefault(k, []).append((meas, i))
    if not events:
        raise NavlibInputError("gnss: no measurements; give GNSS (or aiding) data")
    # windows: boundaries at update samples at least window_s apart (last sample closes)
    bounds = [0]
    times = t.tolist()
    for k in sorted(events):
        if k > bounds[-1] and times[k] - times[bounds[-1]] >= window_s - 1e-9:
            bounds.append(k)
    if bounds[-1] != t.size - 1:
        bounds.append(t.size - 1)
    return _run(es, t, f_meas, w_meas, start, params, P, events, bounds,
                "euler" if method == "euler" else "series", keep_covariance, rows, names,
                _resume_point(t, f_meas, w_meas, bounds, rows, snapshot_before, resume))


def _observers(measurements) -> set:
    """The measurements with epochs that watch the filter's posterior."""
    return {meas for meas in measurements if meas.wants_posterior and meas.index.size}


def _resume_point(t, f_meas, w_meas, bounds, rows, snapshot_before, resume):
    """``(window to snapshot or None, snapshot to resume from or None)`` of :func:`ekf`."""
    if snapshot_before is None and resume is None:
        return None, None
    if _observers(rows):
        raise NavlibInputError("snapshot_before, resume: not with measurements that watch "
                               "the posterior (closed-loop reference trajectory)")
    window = None
    if snapshot_before is not None:
        starts = np.flatnonzero(t[np.asarray(bounds[:-1])] < snapshot_before)
        if not starts.size:
            raise NavlibInputError(f"snapshot_before: {snapshot_before} s is not after the "
                                   f"first sample ({t[0]:g} s)")
        window = int(starts[-1])
    if resume is not None:
        imu = np.column_stack([f_meas, w_meas])[:resume.sample + 1]
        if tuple(bounds) != resume.bounds or not np.array_equal(imu, resume.imu):
            raise NavlibInputError("resume: the snapshot is of a run with other IMU samples "
                                   "or propagation windows before it")
        if window is not None and window < resume.window:
            raise NavlibInputError("snapshot_before: before the resumed snapshot")
    return window, resume


def _run(es, t, f_meas, w_meas, start, params, P, events, bounds, method, keep_covariance,
         rows, names, resume_point=(None, None)):
    """The filter loop of :func:`ekf`: per window, nominal propagation, the error-state
    covariance along it, the updates, and feedback at the window end (from the window of
    a snapshot to resume, keeping one at another window, ``resume_point``)."""
    Qc = np.asarray(es.Qc, dtype=float)
    observers = _observers(rows)
    kept = np.flatnonzero(~es.reset)
    x = np.zeros(len(es.state_names))          # error-state mean (kept states persist)
    r, v, C = start
    out = {key: [] for key in ("post", "kept", "P", "sigma", "innovation", "nis", "nis_dof")}
    snap_window, resume = resume_point
    first, snapshot = 0, None
    if resume is not None:
        x, (r, v, C), params, P = (resume.state[0].copy(), resume.state[1], dict(resume.state[2]),
                                   resume.state[3].copy())
        out = {key: list(value) for key, value in resume.results.items()}
        first = resume.window
    loop = WindowUpdates(es, kept, observers, Epochs(events, rows, len(names)))
    compiled = compiled_run(es, t, f_meas, w_meas, start, params, P, loop.epochs, bounds,
                            method, keep_covariance, rows, names, resume_point)
    if compiled is not None:                   # the whole loop in one kernel (ekf_loop)
        return EKFResult(**compiled, state_names=tuple(es.state_names),
                         measurement_names=tuple(names),
                         kept_names=tuple(es.state_names[i] for i in kept), model=es.name)
    clocks = strapdown.block_clocks(t, bounds)
    n, longest = len(es.state_names), int(np.max(np.diff(bounds)))
    buffers = (np.empty((longest, n, n)), np.empty((longest, n, n)))  # F, Q of a window
    for i, (w0, w1) in enumerate(itertools.pairwise(bounds)):
        if i < first:
            continue
        if i == snap_window:
            snapshot = EKFSnapshot(i, w0, float(t[w0]), tuple(bounds),
                                   np.column_stack([f_meas, w_meas])[:w0 + 1],
                                   (x.copy(), (r, v, C), dict(params), P.copy()),
                                   {key: list(value) for key, value in out.items()})
        nominal = _window_nominal(es, t[w0:w1 + 1], f_meas[w0:w1 + 1], w_meas[w0:w1 + 1],
                                  (r, v, C), params, clocks[i])
        A, G = es.jacobians(nominal)
        F, Q = discretize_window(A[:-1], G[:-1], Qc, np.diff(nominal.t), method, buffers)
        x, P, rec = loop.window(x, P, F, Q, w0, nominal)
        end = None
        if rec:                                # corrected estimates at this window's updates
            results = update_records(rec, nominal, es, kept, keep_covariance, len(names))
            for key, value in zip(out, results, strict=True):
                out[key].append(value)
            if rec[-1][0][-1] == F.shape[0]:    # the last update is the window end's state
                end = results[0].at(slice(-1, None))
        if end is None:
            end = es.correct(nominal.at(slice(-1, None)), x[None])
        r, v, C = end.position[0], end.velocity[0], end.C_b_e[0]   # feedback at the window end
        params = {g: p[0] for g, p in end.parameters.items()}
        J = es.reset_jacobian(x)
        P = symmetrize(J @ P @ J.T)
        x = np.where(es.reset, 0.0, x)

    post = out.pop("post")
    cat = {key: np.concatenate(value) for key, value in out.items()}
    return EKFResult(
        t=np.concatenate([p.t for p in post]),
        position=np.concatenate([p.position for p in post]),
        velocity=np.concatenate([p.velocity for p in post]),
        C_b_e=np.concatenate([p.C_b_e for p in post]),
        parameters={g: np.concatenate([p.parameters[g] for p in post]) for g in params},
        kept=cat["kept"], sigma=cat["sigma"], P=cat["P"] if keep_covariance else None,
        innovation=cat["innovation"], nis=cat["nis"], nis_dof=cat["nis_dof"],
        state_names=tuple(es.state_names),
        measurement_names=tuple(names),
        kept_names=tuple(es.state_names[i] for i in kept), model=es.name, snapshot=snapshot,
    )


def _window_nominal(es, t, f_meas, w_meas, state, params, clock) -> Nominal:
    """The nominal state over one window from ``state`` ``(r, v, C)`` at its start: the
    parameter estimates decayed along it, the IMU compensated with them and the strapdown
    mechanisation (the loop's own states, so without :func:`navlib.strapdown.integrate`'s
    input checks; ``clock``: the window's in ``strapdown.block_clocks``)."""
    r, v, C = state
    if not (np.isfinite(r).all() and np.isfinite(v).all() and np.isfinite(C).all()):
        raise NavlibInputError(f"ekf: the filter diverged: its navigation state is not finite "
                               f"at t = {t[0]:.3f} s (check the sensors and the initial "
                               "covariance)")
    dt = (t - t[0])[:, None]
    par = {g: p[None, :] * np.exp(es.decay[g][None, :] * dt) for g, p in params.items()}
    f_c, w_c = es.compensate(par, f_meas, w_meas)
    nav = strapdown.propagate(t, f_c, w_c, r, v, quat_from_matrix(C), clock)
    return Nominal(t, nav.position, nav.velocity, nav.attitude.as_matrix(), f_c, w_c, par)
