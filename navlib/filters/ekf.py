"""Closed-loop INS/GNSS error-state EKF in ECEF (spec launcher.md §6.2-6.4; issues 5, 10).

:func:`ekf` is described in its docstring (ECEF strapdown nominal state, error-state
covariance from the model's Jacobians along the estimate, GNSS / attitude /
reference-trajectory updates, feedback resets); :func:`simulate_ekf` feeds it simulated
sensors (:mod:`navlib.sensors`). The loop knows no model: the error model is an
:class:`~navlib.models.base.ErrorStateModel` (layout, reset states, ``jacobians``,
``correct``, decay; :class:`~navlib.models.launcher.LauncherErrorState`,
:class:`~navlib.models.ecef.Ecef21ErrorState`) and each measurement a
:class:`~navlib.filters.measurements.Measurement` (innovation, ``H``, ``R``).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib import strapdown
from navlib._validation import finite_array, finite_scalar
from navlib.covariance import symmetrize
from navlib.discretize import discretize_steps
from navlib.errors import NavlibInputError
from navlib.filters.linear import METHODS
from navlib.filters.measurements import (
    FixedDesign,
    Measurement,
    _epoch_index,
    _imu_arrays,
    ekf_measurements,
)
from navlib.kalman import (
    _PINV_RTOL,
    _psd_sqrt,
    definite_noise,
    kernel_array,
    propagate_kernel,
    update_kernel,
)
from navlib.models.base import ErrorStateModel, Nominal
from navlib.models.ecef import Ecef21ErrorState
from navlib.models.launcher import LauncherErrorState, rt_dynamics_matrix
from navlib.outliers import as_outliers
from navlib.rotations import log_so3
from navlib.sensors import ReferenceTrajectory, simulate_attitude_sensor

_MODELS = {"launcher": LauncherErrorState, "ecef21": Ecef21ErrorState}
FAMILIES = tuple(_MODELS)
"""Error-model families the EKF runs with: Beaudoin's launcher models
(:func:`navlib.models.launcher`) and España's 21-state ECEF model
(:func:`navlib.models.ecef21`)."""
_AXES = ("x", "y", "z")
_EYE3 = np.eye(3)


def _error_model(model, t, solution, biases, bias_model, options, gnss_velocity_sigma,
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
        GPS position bias, spec launcher.md §3.1 ``C_lc``).
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
        from scipy.spatial.transform import Rotation

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
        ``T_E^B psi``, spec launcher.md §6.2 item 6).
        """
        k = _epoch_index(np.asarray(trajectory.t, dtype=float), self.t, "result")
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
        from scipy.spatial.transform import Rotation

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
      states (the launcher's divergence from its reference, spec launcher.md §3.4) have no
      nominal counterpart and keep their estimate. Corrections are fed back at the end of
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
    t, f_meas, w_meas = _imu_arrays(imu)
    es = _error_model(model, t, solution, biases, bias_model, model_options,
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
    loop = _Loop(es, kept, observers, _Epochs(events, rows, len(names)))
    clocks = strapdown._block_clocks(t, bounds)
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
        F, Q = discretize_steps(A[:-1], G[:-1], Qc, np.diff(nominal.t), method=method)
        x, P, rec = loop.window(x, P, F, Q, w0, nominal)
        end = None
        if rec:                                # corrected estimates at this window's updates
            results = _records(rec, nominal, es, kept, keep_covariance, len(names))
            for key, value in zip(out, results, strict=True):
                out[key].append(value)
            if rec[-1][0] == F.shape[0]:       # the last update is the window end's state
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
    input checks; ``clock``: the window's in ``strapdown._block_clocks``)."""
    r, v, C = state
    if not (np.isfinite(r).all() and np.isfinite(v).all() and np.isfinite(C).all()):
        raise NavlibInputError(f"ekf: the filter diverged: its navigation state is not finite "
                               f"at t = {t[0]:.3f} s (check the sensors and the initial "
                               "covariance)")
    dt = (t - t[0])[:, None]
    par = {g: p[None, :] * np.exp(es.decay[g][None, :] * dt) for g, p in params.items()}
    f_c, w_c = es.compensate(par, f_meas, w_meas)
    nav = strapdown._integrate(t, f_c, w_c, r, v, _as_quat(C), clock)
    return Nominal(t, nav.position, nav.velocity, nav.attitude.as_matrix(), f_c, w_c, par)


class _Epochs:
    """The update epochs of :func:`ekf` and what does not depend on the data.

    Cached by the tuple of measurements updated together at an epoch: their rows in the
    results and, when all have a fixed design
    (:class:`~navlib.filters.measurements.FixedDesign`), their stacked ``H`` and ``R`` and
    the definiteness of ``R`` (:func:`~navlib.kalman.definite_noise`); the
    innovations of fixed designs are evaluated once per window (:meth:`innovations`).

    Attributes
    ----------
    at : dict
        IMU sample -> ``(epoch, columns, fixed)``: the epoch's ``(measurement, index)``
        pairs, their result rows and ``(H, R, definite)`` or None when one of them is not
        a fixed design (or is updated twice at the epoch; it is then evaluated at the
        update).
    """

    def __init__(self, events, rows, m_all):
        self.rows, self.m_all = rows, m_all
        designs, self.at = {}, {}
        for k, epoch in events.items():
            key = tuple(meas for meas, _ in epoch)
            if key not in designs:
                fixed = (all(isinstance(meas, FixedDesign) for meas in key)
                         and len(set(key)) == len(key))
                designs[key] = (np.concatenate([rows[meas] for meas in key]),
                                _fixed_design(key) if fixed else None)
            self.at[k] = (epoch, *designs[key])
        self._fixed = {}                       # measurement -> (samples, epochs) by sample
        for meas in rows:
            if isinstance(meas, FixedDesign):
                order = np.argsort(meas.index, kind="stable")
                self._fixed[meas] = (meas.index[order], order)

    def innovations(self, w0, nominal) -> np.ndarray:
        """Innovations of the fixed-design measurements at the epochs of the window that
        starts at sample ``w0`` (its samples after ``w0``, and ``w0`` for the first
        window), (samples, m_all): row ``j`` for sample ``j`` of ``nominal``, in each
        measurement's result rows (rows not measured left unset)."""
        z = np.empty((nominal.t.size, self.m_all))
        for meas, (samples, order) in self._fixed.items():
            lo = np.searchsorted(samples, w0 + 1 if w0 else 0)
            hi = np.searchsorted(samples, w0 + nominal.t.size - 1, side="right")
            if hi > lo:
                j = samples[lo:hi] - w0
                z[j[:, None], self.rows[meas]] = meas.innovations(order[lo:hi], nominal, j)
        return z


def _fixed_design(measurements):
    """``(H, R, definite)`` of fixed-design measurements stacked (:meth:`_Epochs.design`)."""
    _, H, R = _stacked([(np.zeros(len(meas.names)), meas.H, meas.R) for meas in measurements])
    return H, R, definite_noise(R)


class _Loop:
    """Updates sample by sample and the compiled propagation between them
    (:func:`~navlib.kalman.propagate_kernel`)
    over the windows of :func:`_run`."""

    def __init__(self, es, kept, observers, epochs):
        self.es, self.kept, self.observers = es, kept, observers
        self.epochs = epochs

    def window(self, x, P, F, Q, w0, nominal):
        """``x``, ``P`` at the end of the window that starts at sample ``w0`` and the
        records ``(j, x, P, innovation, columns, NIS, dof)`` of its updates."""
        x, P, F, Q = kernel_array(x), kernel_array(P), kernel_array(F), kernel_array(Q)
        z_fixed = self.epochs.innovations(w0, nominal)
        by_rows = {}                           # the innovations in the rows of each pattern
        at = self.epochs.at
        steps = F.shape[0]
        updates = [j for j in range(steps + 1) if (j or not w0) and w0 + j in at]
        rec, j0 = [], 0
        for j in updates:
            x, P = propagate_kernel(x, P, F, Q, self.kept, j0, j)
            j0 = j
            epoch, cols, fixed = at[w0 + j]
            if fixed is not None:
                if id(cols) not in by_rows:
                    by_rows[id(cols)] = z_fixed[:, cols]
                z, H, R, definite = by_rows[id(cols)][j], *fixed
            else:
                z, H, R, definite = _evaluated(epoch, nominal, j)
            x, P, innov, nis, dof = _update(x, P, z, H, R, definite)
            rec.append((j, x, P, innov, cols, nis, dof))
            if self.observers:                 # posterior navigation attitude
                C_post = self.es.correct(nominal.at(slice(j, j + 1)), x[None]).C_b_e[0]
                for meas in self.observers:
                    meas.observe(C_post)
        x, P = propagate_kernel(x, P, F, Q, self.kept, j0, steps)
        return x, P, rec


def _records(rec, nominal, es, kept, keep_covariance, m_all):
    """The results of one window's updates, in the order of ``out`` in :func:`_run`:
    corrected nominal, kept states, covariances (None when not kept), sigma, innovations
    in the model's rows (NaN where not measured), NIS and its dof."""
    j_up, dx, P, innov, cols, nis, dof = zip(*rec, strict=True)
    dx, P = np.array(dx), np.array(P)
    full = np.full((len(rec), m_all), np.nan)
    groups = {}                                # updates with the same rows (cached arrays)
    for u, c in enumerate(cols):
        groups.setdefault(id(c), (c, []))[1].append(u)
    for c, us in groups.values():
        full[np.ix_(us, c)] = np.array([innov[u] for u in us])
    sigma = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0, None))
    return (es.correct(nominal.at(np.array(j_up)), dx), dx[:, kept],
            P if keep_covariance else np.array([None] * len(rec)), sigma, full,
            np.array(nis), np.array(dof))


def _evaluated(epoch, nominal, j):
    """``(z, H, R, None)`` of an epoch's measurements evaluated at sample ``j`` (the
    definiteness of ``R`` left to the update)."""
    return (*_stacked([meas.evaluate(i, nominal, j) for meas, i in epoch]), None)


def _stacked(parts):
    """``z``, ``H`` and block-diagonal ``R`` of the measurements of one epoch stacked."""
    if len(parts) == 1:
        return parts[0]
    z = np.concatenate([p[0] for p in parts])
    H = np.concatenate([p[1] for p in parts])
    R = np.zeros((z.size, z.size))
    ends = np.cumsum([0] + [p[0].size for p in parts])
    for (a, b), p in zip(itertools.pairwise(ends), parts, strict=True):
        R[a:b, a:b] = p[2]
    return z, H, R


def _update(x, P, z, H, R, definite):
    """Joseph update with the stacked measurements of one epoch (``definite``: of ``R``
    when known); the posterior, the innovation, NIS and its dof."""
    x, P, z, H, R = (kernel_array(a) for a in (x, P, z, H, R))
    definite = bool(definite_noise(R) if definite is None else definite)
    n, m = H.shape[1], H.shape[0]
    P_post, K, S_pinv = np.empty((n, n)), np.empty((n, m)), np.empty((m, m))
    x, innov, nis, dof = update_kernel(x, P, z, H, R, definite, _PINV_RTOL, P_post, K, S_pinv)
    return x, P_post, innov, float(nis), int(dof)


@dataclass(frozen=True, eq=False)
class EKFRun:
    """One simulated EKF run: the result and what it was fed.

    Attributes
    ----------
    result : EKFResult
    errors : DataFrame
        ``result.errors(trajectory)``.
    truth_parameters : dict
        True parameter histories at the result epochs in the model's convention (``bg``,
        ``ba`` body-axis biases; ``bp`` minus the GPS position bias).
    reference : DataFrame or None
        True launcher divergence (RT solutions).
    initial_error : ndarray (n_nav,)
        The drawn initial navigation error (position, velocity, attitude).
    """

    result: EKFResult
    errors: pd.DataFrame
    truth_parameters: dict
    reference: pd.DataFrame | None
    initial_error: np.ndarray


def simulate_ekf(trajectory, *, sensors="launcher_table1", model: str = "launcher",
                 solution: str = "ins_gps", biases: str = "GA", bias_model: str = "markov",
                 model_options: dict | None = None, gnss_rate_hz: float | None = None,
                 outliers=None, seed=None, initial_error: bool = True, noise: bool = True,
                 window_s: float = 0.1, keep_covariance: bool = False,
                 gnss_velocity_sigma: float | None = None, snapshot_before: float | None = None,
                 resume: EKFRun | None = None) -> EKFRun:
    """Simulate sensors along ``trajectory``, inject outliers and run :func:`ekf`.

    The IMU and GNSS come from :func:`navlib.sensors.simulate_imu` /
    :func:`~navlib.sensors.simulate_gnss` with the preset ``sensors``; the attitude sensor
    from :func:`simulate_attitude_sensor` (the preset's sigma), the reference trajectory from
    :class:`ReferenceTrajectory`. ``outliers`` are added to those data (EKF-mode injection of
    :mod:`navlib.outliers`). The initial nominal state is the truth perturbed by a draw from
    the model's ``P0`` navigation block (``initial_error``). With ``noise=False`` the
    sensors are error-free (a deterministic run, e.g. to isolate an outlier response).

    Seeds: one ``numpy.random.SeedSequence(seed)`` spawns independent streams for the IMU,
    GNSS, attitude sensor, reference trajectory and initial error, so a run with an
    outlier and one without share every noise realisation.

    Parameters
    ----------
    trajectory : Trajectory
        Truth; the IMU samples are its samples.
    sensors : str or navlib.sensors.SensorSpec
        Sensor preset of the simulated data (default ``launcher_table1``). The GNSS
        position bias is simulated only when the filter estimates it (launcher ``P``), so
        truth and filter model agree; for ``ecef21`` the model's noise densities default to
        the same preset.
    model, solution, biases, bias_model, model_options, window_s, keep_covariance,
    gnss_velocity_sigma
        As in :func:`ekf`.
    gnss_rate_hz : float, optional
        GNSS fix rate (default the preset's; the paper's launcher uses every sample).
    outliers : Outlier or sequence of Outlier, optional
    seed : int, optional
    initial_error, noise : bool
    snapshot_before : float, optional
        As in :func:`ekf` (``run.result.snapshot``).
    resume : EKFRun, optional
        A run of the same call without ``outliers`` and with a snapshot taken before the
        earliest outlier (a sample spacing before its time): this run starts there, which
        gives the same result as running it from the start (the simulated sensors are the
        same until the outliers, whose injection changes nothing before them).

    Returns
    -------
    EKFRun
    """
    from navlib import sensors as sensor_lib
    from navlib.outliers import inject

    outliers = as_outliers(outliers)
    spec = sensor_lib.load_preset(sensors) if isinstance(sensors, str) else sensors
    es = _error_model(model, np.asarray(trajectory.t, dtype=float), solution, biases,
                      bias_model, model_options, gnss_velocity_sigma, sensors=sensors)
    seq = np.random.SeedSequence(seed)
    g_imu, g_gnss, g_att, g_ref, g_init = (np.random.default_rng(s) for s in seq.spawn(5))
    if "bp" not in es.parameters:
        # truth matches the filter model: no GNSS position bias unless it is estimated
        from dataclasses import replace

        spec = replace(spec, gnss=replace(spec.gnss, position_bias_markov=0.0))
    if noise:
        imu = sensor_lib.simulate_imu(trajectory, spec, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, spec, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    else:
        quiet = sensor_lib.SensorSpec(name="noise-free", source="",
                                      imu=sensor_lib.ImuSpec(),
                                      gnss=sensor_lib.GnssSpec(rate_hz=spec.gnss.rate_hz))
        imu = sensor_lib.simulate_imu(trajectory, quiet, rng=g_imu)
        gnss = sensor_lib.simulate_gnss(trajectory, quiet, rate_hz=gnss_rate_hz, rng=g_gnss,
                                        with_errors=True)
    t = imu.t
    imu_df = pd.DataFrame({"t": t})
    f_b = inject(imu.f_b, t, outliers, "accel")
    w_b = inject(imu.w_ib_b, t, outliers, "gyro")
    for i, a in enumerate(_AXES):
        imu_df[f"f_{a}"] = f_b[:, i]
    for i, a in enumerate(_AXES):
        imu_df[f"w_{a}"] = w_b[:, i]
    tg = gnss["t"].to_numpy(float)
    snapshot = _snapshot_to_resume(resume, outliers, (t, tg))
    gnss = gnss.copy()
    gnss[["x", "y", "z"]] = inject(gnss[["x", "y", "z"]].to_numpy(), tg, outliers, "gnss_pos")
    gnss[["vx", "vy", "vz"]] = inject(gnss[["vx", "vy", "vz"]].to_numpy(), tg, outliers,
                                      "gnss_vel")

    attitude = reference = None
    if "att" in es.measurements:
        sigma_att = (model_options or {}).get("sigma_att", spec.attitude_sigma or 0.0)
        attitude = simulate_attitude_sensor(trajectory, sigma_att if noise else 0.0, rng=g_att,
                                            outliers=outliers)
    if "rt" in es.measurements:
        reference = ReferenceTrajectory(
            trajectory, rt_dynamics_matrix(), sigma_wind=es.settings["sigma_wind"],
            a1_sign=es.settings["a1_sign"], rng=g_ref, outliers=outliers, noise=noise)

    # initial error: a draw from the model's P0 navigation block, fed back with minus sign
    truth0 = strapdown.StrapdownState.from_trajectory(trajectory, 0)
    nav = np.concatenate([es.groups[g] for g in ("position", "velocity", "attitude")])
    P_nav = es.P0[np.ix_(nav, nav)]
    dx0 = (g_init.standard_normal(9) @ _psd_sqrt(P_nav).T) if initial_error else np.zeros(9)
    dx = np.zeros((1, len(es.state_names)))
    dx[0, nav] = -dx0
    hat0 = es.correct(Nominal(t[:1], truth0.position[None], truth0.velocity[None],
                              trajectory.attitude[:1].as_matrix(), f_b[:1], w_b[:1], {}), dx)
    initial = strapdown.StrapdownState(t=truth0.t, position=hat0.position[0],
                                       velocity=hat0.velocity[0], q_b_e=_as_quat(hat0.C_b_e[0]))
    result = ekf(imu_df, gnss, initial=initial, model=es, attitude=attitude,
                 reference=reference, window_s=window_s, keep_covariance=keep_covariance,
                 snapshot_before=snapshot_before, resume=snapshot)
    k = _epoch_index(t, result.t, "result")
    truth_par = {g: bias[k] for g, bias in (("bg", imu.gyro.bias), ("ba", imu.accel.bias))
                 if g in es.parameters}
    if "bp" in es.parameters:
        kg = np.clip(np.searchsorted(tg, result.t), 0, tg.size - 1)
        truth_par["bp"] = -gnss[["bias_x", "bias_y", "bias_z"]].to_numpy()[kg]
    return EKFRun(result, result.errors(trajectory), truth_par,
                  reference.history() if reference is not None else None, dx0)


def _snapshot_to_resume(resume, outliers, clocks) -> EKFSnapshot | None:
    """The snapshot of ``resume`` (:func:`simulate_ekf`), checked to lie before the
    outliers' first sample (the largest sample spacing of the IMU and GNSS ``clocks``
    before the earliest outlier time)."""
    if resume is None:
        return None
    snapshot = getattr(getattr(resume, "result", None), "snapshot", None)
    if snapshot is None:
        raise NavlibInputError("resume: expected an EKFRun made with snapshot_before=")
    spacing = max(float(np.max(np.diff(c))) for c in clocks if c.size > 1)
    if outliers and snapshot.t >= min(o.time for o in outliers) - spacing:
        raise NavlibInputError(f"resume: the snapshot at {snapshot.t:g} s is not before the "
                               "outliers")
    return snapshot


def _as_quat(C) -> np.ndarray:
    """``Rotation.from_matrix(C).as_quat()`` of one attitude matrix, without scipy's
    orthogonality check and projection when ``C`` is a rotation to 1e-13 (far inside
    scipy's own tolerance, so scipy would not project it either: the same quaternion)."""
    from scipy.spatial.transform import Rotation

    valid = bool(np.max(np.abs(C @ C.T - _EYE3)) < 1e-13 and np.linalg.det(C) > 0)
    return Rotation.from_matrix(C, assume_valid=valid).as_quat()
