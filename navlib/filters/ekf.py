"""Closed-loop INS/GNSS error-state EKF in ECEF (spec launcher.md §6.2-6.4; issue 5).

:func:`ekf` is described in its docstring (ECEF strapdown nominal state, error-state
covariance from the model's Jacobians along the estimate, GNSS / attitude /
reference-trajectory updates, feedback resets); :func:`simulate_ekf` feeds it simulated
sensors (:mod:`navlib.sensors`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.discretize import discretize_steps
from navlib.errors import NavlibInputError
from navlib.filters.kalman import _psd_sqrt, _sym, joseph_update
from navlib.filters.linear import METHODS
from navlib.filters.measurements import _MEAS_KINDS, _epoch_index, _imu_arrays, _rotations
from navlib.models.base import LinearModel
from navlib.outliers import as_outliers
from navlib.rotations import exp_so3, log_so3
from navlib.sensors import ReferenceTrajectory, simulate_attitude_sensor

FAMILIES = ("launcher", "ecef21")
"""Error-model families the EKF runs with: Beaudoin's launcher models
(:func:`navlib.models.launcher`) and España's 21-state ECEF model
(:func:`navlib.models.ecef21`)."""

_GROUP_STATES = {
    "launcher": {"att": "psi", "vel": "dv", "pos": "dr", "bg": "bg", "ba": "ba", "bp": "bp"},
    "ecef21": {"att": "theta", "vel": "V", "pos": "P", "bg": "bg", "ba": "ba", "sg": "sg",
               "sa": "sa"},
}
_AXES = ("x", "y", "z")


class _BlockTrajectory:
    """The few Trajectory attributes the model builders read, for a block of the estimate.

    ``navlib.models.launcher`` reads ``t``, ``attitude.as_matrix()`` and ``specific_force``;
    ``navlib.models.ecef21`` also ``position``, ``angular_rate``, ``C_b_e()`` and
    ``rate_hz``. Here they hold the filter's nominal (estimated) trajectory and corrected
    IMU signals, so the Jacobians are evaluated along the estimate (an EKF).
    """

    def __init__(self, t, position, C_b_e, f_b, w_ib_b):
        self.t = t
        self.position = position
        self._C = C_b_e
        self.specific_force = f_b
        self.angular_rate = w_ib_b
        self.attitude = self

    def as_matrix(self):
        return self._C

    def C_b_e(self):
        return self._C

    @property
    def rate_hz(self) -> float:
        return float(1.0 / np.median(np.diff(self.t)))


@dataclass(frozen=True, eq=False)
class _Family:
    """Error-state layout of one model family and how it maps onto the nominal state."""

    name: str
    model: LinearModel                 # built once, for names, Qc, P0, R, parameters
    options: dict
    idx: dict                          # group -> index array (3,)
    kept: np.ndarray                   # non-reset states (reference-trajectory block)
    decay: dict                        # parameter group -> (3,) continuous rate (1/s)
    nav_sign: float                    # +1: error = true - estimate (ecef21); -1: est - true

    @property
    def state_names(self):
        return self.model.state_names

    @property
    def n(self) -> int:
        return self.model.n

    def correct_imu(self, params, f_b, w_ib_b, dt_from_start):
        """Compensate IMU samples with the parameter estimates, decayed per sample."""
        def value(group):
            if group not in params:
                return 0.0
            rate = self.decay[group]
            return params[group][None, :] * np.exp(rate[None, :] * dt_from_start[:, None])
        f = f_b - value("ba")
        w = w_ib_b - value("bg")
        if "sa" in params:
            f = f / (1.0 + params["sa"])
        if "sg" in params:
            w = w / (1.0 + params["sg"])
        return f, w

    def jacobians(self, t, position, C_b_e, f_b, w_ib_b):
        """``A`` (K, n, n), ``G`` (K, n, q), ``H`` (K, m, n) along the nominal samples."""
        block = _BlockTrajectory(t, position, C_b_e, f_b, w_ib_b)
        if self.name == "launcher":
            from navlib.models.launcher import launcher

            m = launcher(trajectory=block, **self.options)
            H = np.broadcast_to(m.H, (t.size, *m.H.shape[-2:]))
            return m.A, m.G, H
        from navlib.models.ecef import ecef21_jacobians

        A, G = ecef21_jacobians(position, C_b_e, f_b, w_ib_b,
                                self.options.get("attitude_error", "ecef"))
        return A, G, np.broadcast_to(self.model.H, (t.size, *self.model.H.shape))


def _family(model: str, trajectory_block, options: dict) -> _Family:
    if model == "launcher":
        from navlib.models.launcher import launcher

        m = launcher(trajectory=trajectory_block, **options)
    elif model == "ecef21":
        from navlib.models.ecef import ecef21

        opts = dict(options)
        sensors = opts.pop("sensors", None)
        m = ecef21(trajectory_block, sensors, **opts)
        options = dict(options)
    else:
        raise NavlibInputError(f"model: expected one of {FAMILIES}, got {model!r}")
    names = m.state_names
    groups = _GROUP_STATES[model]
    idx = {}
    for group, prefix in groups.items():
        cand = [f"{prefix}_{a}" for a in _AXES]
        if all(c in names for c in cand):
            idx[group] = np.array([names.index(c) for c in cand])
    kept = np.array([i for i, s in enumerate(names)
                     if (s.startswith("x") and s[1:].isdigit()) or s.startswith("psi_ref")],
                    dtype=int)
    A0 = np.asarray(m.A[0] if m.A.ndim == 3 else m.A)
    decay = {}
    for group in ("bg", "ba", "sg", "sa", "bp"):
        if group in idx:
            block = A0[np.ix_(idx[group], idx[group])]
            decay[group] = np.diag(block).copy()
    return _Family(model, m, options, idx, kept, decay, -1.0 if model == "launcher" else 1.0)


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


def ekf(imu, gnss=None, *, initial, model: str = "launcher", solution: str = "ins_gps",
        biases: str = "GA", bias_model: str = "markov", model_options: dict | None = None,
        P0=None, attitude=None, reference=None, gnss_velocity_sigma: float | None = None,
        initial_parameters: dict | None = None, method: str | None = None,
        window_s: float = 0.1, keep_covariance: bool = False) -> EKFResult:
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
      and corrected IMU signals, through the model builder), sample by sample.
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
      ignores the second-order covariance Jacobian ``I - S(psi)/2``.

    Parameters
    ----------
    imu : navlib.sensors.ImuSimulation or DataFrame (t, f_x, f_y, f_z, w_x, w_y, w_z)
        Measured IMU samples (point samples, SI).
    gnss : DataFrame, optional
        ``t, x, y, z`` ECEF position (m) and optionally ``vx, vy, vz`` (m/s); epochs on IMU
        samples.
    initial : navlib.strapdown.StrapdownState
        Nominal state at the first IMU sample.
    model : {"launcher", "ecef21"}
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

    Returns
    -------
    EKFResult
    """
    t, f_meas, w_meas = _imu_arrays(imu)
    N = t.size
    opts = dict(model_options or {})
    if model == "launcher":
        opts.update(solution=solution, biases=biases, bias_model=bias_model)
        opts.setdefault("s_t", float(np.median(np.diff(t))))
    method = method or ("euler" if model == "launcher" else "expm")
    if method not in METHODS:
        raise NavlibInputError(f"method: expected one of {METHODS}, got {method!r}")
    window_s = finite_scalar(window_s, "window_s", 0.0, low_open=True)
    r0 = finite_array(initial.position, "initial.position", (3,))
    v0 = finite_array(initial.velocity, "initial.velocity", (3,))
    C0 = initial.attitude.as_matrix()
    probe = _BlockTrajectory(t[:2], np.array([r0, r0]), np.array([C0, C0]), f_meas[:2],
                             w_meas[:2])
    fam = _family(model, probe, opts)
    n = fam.n
    P = fam.model.P0 if P0 is None else finite_array(P0, "P0", (n, n))
    P = _sym(np.array(P, dtype=float))
    Qc = np.asarray(fam.model.Qc, dtype=float)

    # measurement rows of the model, by kind
    meas_names = list(fam.model.measurement_names)
    R_model = np.asarray(fam.model.R, dtype=float)
    if R_model.ndim == 3:
        R_model = R_model[0]
    extra_vel = model == "ecef21" and gnss_velocity_sigma is not None
    if extra_vel:
        gnss_velocity_sigma = finite_scalar(gnss_velocity_sigma, "gnss_velocity_sigma", 0.0,
                                            low_open=True)
        meas_names += [f"gnss_v{a}" for a in _AXES]
        R_model = np.block([[R_model, np.zeros((R_model.shape[0], 3))],
                            [np.zeros((3, R_model.shape[0])),
                             gnss_velocity_sigma**2 * np.eye(3)]])
    rows = {}
    for kind, prefix in _MEAS_KINDS[model].items():
        sel = [i for i, s in enumerate(meas_names) if s.startswith(prefix)
               and s[len(prefix):] in _AXES]
        if len(sel) == 3:
            rows[kind] = np.array(sel)

    # measurement data on IMU samples
    events = {}            # sample index -> list of (kind, value)

    def add(kind, k_idx, values):
        for k, v in zip(k_idx, values, strict=True):
            events.setdefault(int(k), []).append((kind, v))

    if gnss is not None:
        if not isinstance(gnss, pd.DataFrame) or not {"t", "x", "y", "z"} <= set(gnss.columns):
            raise NavlibInputError("gnss: expected a DataFrame with columns t, x, y, z")
        kg = _epoch_index(t, gnss["t"].to_numpy(float), "gnss")
        add("gnss_pos", kg, gnss[["x", "y", "z"]].to_numpy(float))
        if "gnss_vel" in rows and {"vx", "vy", "vz"} <= set(gnss.columns):
            add("gnss_vel", kg, gnss[["vx", "vy", "vz"]].to_numpy(float))
    if "att" in rows:
        if attitude is None:
            raise NavlibInputError(f"attitude: solution {solution!r} needs attitude-sensor data")
        ta, Ca = _rotations(attitude, "attitude")
        add("att", _epoch_index(t, ta, "attitude"), Ca)
    ref_callable = ref_nav = None
    if "rt" in rows:
        if reference is None:
            raise NavlibInputError(f"reference: solution {solution!r} needs reference-"
                                   "trajectory attitudes or a ReferenceTrajectory")
        if callable(reference):
            ref_callable = reference
            for k in range(N):
                events.setdefault(k, []).append(("rt", None))
        else:
            tr, Cr = _rotations(reference, "reference")
            add("rt", _epoch_index(t, tr, "reference"), Cr)
    if not events:
        raise NavlibInputError("gnss: no measurements; give GNSS (or aiding) data")
    update_idx = np.array(sorted(events))

    # windows: boundaries at update samples at least window_s apart (last sample closes)
    bounds = [0]
    for k in update_idx:
        if k > bounds[-1] and t[k] - t[bounds[-1]] >= window_s - 1e-9:
            bounds.append(int(k))
    if bounds[-1] != N - 1:
        bounds.append(N - 1)

    params = {g: np.zeros(3) for g in fam.decay}
    for g, v in (initial_parameters or {}).items():
        if g not in params:
            raise NavlibInputError(f"initial_parameters: model has no parameter group {g!r}")
        params[g] = finite_array(v, f"initial_parameters[{g!r}]", (3,)).copy()
    x = np.zeros(n)                      # error-state mean (kept states persist)
    reset = np.ones(n, dtype=bool)
    reset[fam.kept] = False
    kept = fam.kept
    pos_i, vel_i, att_i = fam.idx["pos"], fam.idx["vel"], fam.idx["att"]
    att_body = model == "ecef21" and opts.get("attitude_error", "ecef") == "body"
    s = fam.nav_sign

    def corrected(r, v, C, dx):
        """Nominal (K, ...) corrected with error-state means dx (K, n)."""
        r2 = r + s * dx[:, pos_i]
        v2 = v + s * dx[:, vel_i]
        E = exp_so3(dx[:, att_i])
        C2 = C @ E if att_body else E @ C
        return r2, v2, C2

    out_t, out_r, out_v, out_C, out_sig, out_P = [], [], [], [], [], []
    out_par = {g: [] for g in params}
    out_kept, out_innov, out_nis, out_dof = [], [], [], []
    m_all = len(meas_names)
    state = (r0, v0, C0)
    from navlib import strapdown

    for w0, w1 in itertools.pairwise(bounds):
        sl = slice(w0, w1 + 1)
        tw = t[sl]
        f_c, w_c = fam.correct_imu(params, f_meas[sl], w_meas[sl], tw - tw[0])
        nav = strapdown.integrate(tw, f_c, w_c, state[0], state[1], state[2])
        Cw = nav.attitude.as_matrix()
        A, G, Hw = fam.jacobians(tw, nav.position, Cw, f_c, w_c)
        if extra_vel:
            Hv = np.zeros((tw.size, 3, n))
            Hv[:, :, vel_i] = np.eye(3)
            Hw = np.concatenate([Hw, Hv], axis=1)
        F, Q = discretize_steps(A[:-1], G[:-1], Qc, np.diff(tw),
                                method="euler" if method == "euler" else "series")
        rec = []   # (local index, dx, P)
        for j in range(tw.size):
            k = w0 + j
            if k in events and (j > 0 or k == 0):
                zs, sel = [], []
                for kind, value in events[k]:
                    if kind not in rows:
                        continue
                    C_hat = Cw[j]
                    if kind == "gnss_pos":
                        gps = value
                        if model == "launcher":
                            z = nav.position[j] - gps
                            if "bp" in params:
                                z = z - params["bp"] * np.exp(fam.decay["bp"] * (tw[j] - tw[0]))
                        else:
                            z = gps - nav.position[j]
                    elif kind == "gnss_vel":
                        z = (nav.velocity[j] - value if model == "launcher"
                             else value - nav.velocity[j])
                    elif kind == "att":
                        z = log_so3(value @ C_hat.T)
                    else:   # rt
                        if ref_callable is not None:
                            C_ref = np.asarray(ref_callable(k, t[k], ref_nav), dtype=float)
                        else:
                            C_ref = value
                        z = log_so3(C_hat.T @ C_ref)
                    zs.append(z)
                    sel.append(rows[kind])
                if sel:
                    sel = np.concatenate(sel)
                    z = np.concatenate(zs)
                    Hk = Hw[j][sel]
                    Rk = R_model[np.ix_(sel, sel)]
                    innov = z - Hk @ x
                    P, gain = joseph_update(P, Hk, Rk)
                    K, S_pinv, dof = gain.K, gain.S_pinv, int(gain.dof)
                    x = x + K @ innov
                    full = np.full(m_all, np.nan)
                    full[sel] = innov
                    if ref_callable is not None:
                        ref_nav = exp_so3(x[att_i]) @ Cw[j]      # posterior navigation attitude
                    rec.append((j, x.copy(), P.copy() if keep_covariance else None,
                                np.sqrt(np.clip(np.diag(P), 0, None)), full,
                                float(innov @ S_pinv @ innov), dof))
            if j < tw.size - 1:
                x_next = F[j] @ x
                if kept.size:
                    # the closed loop drives the kept (RT) states with the error of the
                    # corrected navigation, x[reset] - x_hat[reset]: no mean drive from
                    # the not-yet-fed-back estimate of the reset states
                    x_next[kept] = F[j][np.ix_(kept, kept)] @ x[kept]
                x = x_next
                P = _sym(F[j] @ P @ F[j].T + Q[j])
        # record the corrected estimates of this window's updates
        if rec:
            jj = np.array([r[0] for r in rec])
            dx = np.array([r[1] for r in rec])
            r2, v2, C2 = corrected(nav.position[jj], nav.velocity[jj], Cw[jj], dx)
            out_t.append(tw[jj])
            out_r.append(r2)
            out_v.append(v2)
            out_C.append(C2)
            for g in params:
                nominal = params[g][None, :] * np.exp(fam.decay[g][None, :]
                                                      * (tw[jj] - tw[0])[:, None])
                out_par[g].append(nominal + dx[:, fam.idx[g]])
            out_kept.append(dx[:, fam.kept])
            out_sig.append(np.array([r[3] for r in rec]))
            if keep_covariance:
                out_P.append(np.array([r[2] for r in rec]))
            out_innov.append(np.array([r[4] for r in rec]))
            out_nis.append(np.array([r[5] for r in rec]))
            out_dof.append(np.array([r[6] for r in rec]))
        # feedback at the window end
        r_end, v_end, C_end = corrected(nav.position[-1:], nav.velocity[-1:], Cw[-1:], x[None])
        state = (r_end[0], v_end[0], C_end[0])
        span = tw[-1] - tw[0]
        for g in params:
            params[g] = params[g] * np.exp(fam.decay[g] * span) + x[fam.idx[g]]
        x = np.where(reset, 0.0, x)

    cat = np.concatenate
    return EKFResult(
        t=cat(out_t), position=cat(out_r), velocity=cat(out_v), C_b_e=cat(out_C),
        parameters={g: cat(v) for g, v in out_par.items()},
        kept=cat(out_kept), sigma=cat(out_sig), P=cat(out_P) if keep_covariance else None,
        innovation=cat(out_innov), nis=cat(out_nis), nis_dof=cat(out_dof),
        state_names=tuple(fam.state_names), measurement_names=tuple(meas_names),
        kept_names=tuple(fam.state_names[i] for i in fam.kept), model=model,
    )


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
                 gnss_velocity_sigma: float | None = None) -> EKFRun:
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

    Returns
    -------
    EKFRun
    """
    from navlib import sensors as sensor_lib
    from navlib import strapdown
    from navlib.outliers import inject

    outliers = as_outliers(outliers)
    spec = sensor_lib.load_preset(sensors) if isinstance(sensors, str) else sensors
    seq = np.random.SeedSequence(seed)
    g_imu, g_gnss, g_att, g_ref, g_init = (np.random.default_rng(s) for s in seq.spawn(5))
    if model != "launcher" or "P" not in biases.upper():
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
    gnss = gnss.copy()
    gnss[["x", "y", "z"]] = inject(gnss[["x", "y", "z"]].to_numpy(), tg, outliers, "gnss_pos")
    gnss[["vx", "vy", "vz"]] = inject(gnss[["vx", "vy", "vz"]].to_numpy(), tg, outliers,
                                      "gnss_vel")

    opts = dict(model_options or {})
    if model == "ecef21" and isinstance(sensors, str):
        opts.setdefault("sensors", sensors)      # the filter assumes the simulated sensors
    attitude = reference = None
    if model == "launcher" and solution.startswith("ins_gps_att"):
        sigma_att = opts.get("sigma_att", spec.attitude_sigma or 0.0)
        attitude = simulate_attitude_sensor(trajectory, sigma_att if noise else 0.0, rng=g_att,
                                            outliers=outliers)
    if model == "launcher" and solution.endswith("_rt"):
        from navlib.models.launcher import ASSUMED

        reference = ReferenceTrajectory(
            trajectory, sigma_wind=opts.get("sigma_wind", ASSUMED["sigma_wind"]),
            a1_sign=opts.get("a1_sign", 1.0), rng=g_ref, outliers=outliers, noise=noise)

    # initial error from the model's P0 navigation block (the model's sign convention)
    truth0 = strapdown.StrapdownState.from_trajectory(trajectory, 0)
    probe = _BlockTrajectory(t[:2], trajectory.position[:2], trajectory.attitude[:2].as_matrix(),
                             trajectory.specific_force[:2], trajectory.angular_rate[:2])
    if model == "launcher":
        fopts = {**opts, "solution": solution, "biases": biases, "bias_model": bias_model,
                 "s_t": float(np.median(np.diff(t)))}
    else:
        fopts = opts
    fam = _family(model, probe, fopts)
    nav = np.concatenate([fam.idx["pos"], fam.idx["vel"], fam.idx["att"]])
    P_nav = fam.model.P0[np.ix_(nav, nav)]
    dx0 = (g_init.standard_normal(9) @ _psd_sqrt(P_nav).T) if initial_error else np.zeros(9)
    s = fam.nav_sign
    C0 = trajectory.attitude[0].as_matrix()
    body = model == "ecef21" and opts.get("attitude_error", "ecef") == "body"
    C_hat0 = C0 @ exp_so3(-dx0[6:9]) if body else exp_so3(-dx0[6:9]) @ C0
    # error = s (true - estimate) for position/velocity; C_true = exp(S(psi)) C_hat
    initial = strapdown.StrapdownState(
        t=truth0.t, position=truth0.position - s * dx0[:3],
        velocity=truth0.velocity - s * dx0[3:6],
        q_b_e=_as_quat(C_hat0))
    result = ekf(imu_df, gnss, initial=initial, model=model, solution=solution, biases=biases,
                 bias_model=bias_model, model_options=opts, attitude=attitude,
                 reference=reference, window_s=window_s, keep_covariance=keep_covariance,
                 gnss_velocity_sigma=gnss_velocity_sigma)
    k = _epoch_index(t, result.t, "result")
    truth_par = {}
    if "bg" in fam.idx:
        truth_par["bg"] = imu.gyro.bias[k]
    if "ba" in fam.idx:
        truth_par["ba"] = imu.accel.bias[k]
    if "bp" in fam.idx:
        kg = np.searchsorted(tg, result.t)
        kg = np.clip(kg, 0, tg.size - 1)
        truth_par["bp"] = -gnss[["bias_x", "bias_y", "bias_z"]].to_numpy()[kg]
    return EKFRun(result, result.errors(trajectory), truth_par,
                  reference.history() if reference is not None else None, dx0)


def _as_quat(C) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(C).as_quat()
