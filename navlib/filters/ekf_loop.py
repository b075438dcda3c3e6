"""The closed-loop EKF of the 21-state ECEF model with GNSS updates as one compiled loop
(:func:`navlib.filters.ekf.ekf`; docs/assumptions.md "Compiled kernels"; issue 37).

:func:`ekf` runs its windows in Python, calling a compiled kernel for each piece (the
strapdown mechanisation, the model's Jacobians, the discretisation, the propagation and the
updates); between them a window of the rocket's 100 samples spent about 400 µs in NumPy
calls, a third of the EKF's time per sample. :func:`_loop_kernel` runs every window of
such a run in one call: the parameter estimates decayed along the window and the IMU
compensated with them (:meth:`navlib.models.base.ErrorState.compensate`), the strapdown
mechanisation (:func:`navlib.strapdown.propagate`), the attitude matrices of its
quaternions, the Jacobians (:meth:`navlib.models.ecef.Ecef21ErrorState.jacobians`), the
sparse discretisation (:func:`navlib.sparse_discretize.discretize_kernel`), the runs of
updates and the propagation (:func:`navlib.kalman.fixed_updates_kernel`, the same runs as
:class:`navlib.filters.ekf_updates.WindowUpdates`), the correction of the nominal state at
each update and the feedback and reset at the window's end
(:meth:`~navlib.models.base.ErrorState.correct`,
:meth:`~navlib.models.base.ErrorState.reset_jacobian`). The formulas are those of the
Python loop in the same order, so the results agree to rounding (the attitude matrices of
the quaternions and the exponential of the corrections are written out here instead of
scipy's and NumPy's; ``tests/filters/test_ekf_loop.py``).

It serves the runs :func:`compiled_run` accepts: the
:class:`~navlib.models.ecef.Ecef21ErrorState` model with the series discretisation, GNSS
position and velocity updates only (fixed
designs), no snapshot or resume; every other run takes the Python loop.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pandas as pd

from navlib import earth, strapdown, units
from navlib.cache import drop_stale_kernel_caches
from navlib.filters.ekf_updates import Epochs
from navlib.filters.measurements import GnssPosition, GnssVelocity, ekf_measurements
from navlib.kalman import PINV_RTOL, fixed_updates_kernel, kernel_array
from navlib.models.ecef import Ecef21ErrorState, ecef21_jacobians_kernel
from navlib.quaternions import _matrix_quat_kernel as matrix_quat_kernel
from navlib.sparse_discretize import discretize_kernel, pattern_kernel

__all__ = ["compile_kernel", "compiled_run"]

_GROUPS = ("bg", "ba", "sg", "sa")
"""The parameter groups of the 21-state model, in the rows of the kernel's ``params``."""


@numba.njit(cache=True)
def _matrix(q, C):
    """The attitude matrix ``C`` (3, 3) of a quaternion ``q`` (scalar-last), normalised
    first (``Rotation.from_quat(q).as_matrix()``)."""
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    x, y, z, w = q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    C[0, 0] = x2 - y2 - z2 + w2
    C[1, 0] = 2.0 * (xy + zw)
    C[2, 0] = 2.0 * (xz - yw)
    C[0, 1] = 2.0 * (xy - zw)
    C[1, 1] = -x2 + y2 - z2 + w2
    C[2, 1] = 2.0 * (yz + xw)
    C[0, 2] = 2.0 * (xz + yw)
    C[1, 2] = 2.0 * (yz - xw)
    C[2, 2] = -x2 - y2 + z2 + w2


@numba.njit(cache=True)
def _correct(r, v, C, params, dx, body, r_out, v_out, C_out, params_out):
    """:meth:`navlib.models.base.ErrorState.correct` of one sample of the 21-state model
    (``nav_sign`` +1): position, velocity and parameters move by ``dx``, the attitude by
    ``exp(S(dx_att))`` (:func:`navlib.rotations.exp_so3`) on the side of the attitude
    error (``body`` or ECEF)."""
    for i in range(3):
        r_out[i] = r[i] + dx[i]
        v_out[i] = v[i] + dx[3 + i]
    for g in range(4):
        for i in range(3):
            params_out[g, i] = params[g, i] + dx[9 + 3 * g + i]
    p0, p1, p2 = dx[6], dx[7], dx[8]
    theta2 = p0 * p0 + p1 * p1 + p2 * p2
    theta = math.sqrt(theta2)
    if theta < 1e-4:
        a, b = 1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0
    else:
        a, b = math.sin(theta) / theta, (1.0 - math.cos(theta)) / theta**2
    K = np.zeros((3, 3))
    K[0, 1], K[0, 2], K[1, 0], K[1, 2], K[2, 0], K[2, 1] = -p2, p1, p2, -p0, -p1, p0
    E = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            KK = K[i, 0] * K[0, j] + K[i, 1] * K[1, j] + K[i, 2] * K[2, j]
            E[i, j] = (1.0 if i == j else 0.0) + a * K[i, j] + b * KK
    for i in range(3):
        for j in range(3):
            s = 0.0
            for k in range(3):
                s += E[i, k] * C[k, j] if not body else C[i, k] * E[k, j]
            C_out[i, j] = s


@numba.njit(cache=True)
def _reset(P, x, half):
    """``P <- sym(J P J')`` in place with the reset Jacobian ``J = I + half S(x_att)`` of the
    attitude block (states 6-8; :meth:`~navlib.models.base.ErrorState.reset_jacobian`):
    ``J`` is the identity outside rows 6-8, so only those rows and columns change."""
    n = P.shape[0]
    J = np.zeros((3, 3))
    J[0, 1], J[0, 2], J[1, 0] = -half * x[8], half * x[7], half * x[8]
    J[1, 2], J[2, 0], J[2, 1] = -half * x[6], -half * x[7], half * x[6]
    for i in range(3):
        J[i, i] = 1.0
    JP = np.empty((3, n))                       # rows 6-8 of J P
    for i in range(3):
        for j in range(n):
            JP[i, j] = J[i, 0] * P[6, j] + J[i, 1] * P[7, j] + J[i, 2] * P[8, j]
    for i in range(3):
        for j in range(n):
            P[6 + i, j] = JP[i, j]
    for i in range(n):                           # columns 6-8 of (J P) J'
        a, b, c = P[i, 6], P[i, 7], P[i, 8]
        for j in range(3):
            P[i, 6 + j] = a * J[j, 0] + b * J[j, 1] + c * J[j, 2]
    for i in range(n):
        for j in range(i + 1, n):
            s = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = s
            P[j, i] = s


@numba.njit(cache=True)
def _loop_kernel(t, f_meas, w_meas, bounds, clock_idx, clock_weights, clock_earth,
                clock_earth_mid, r0, v0, C0, params0, decay, body, P, pattern,
                ev_window, ev_sample, ev_design, ev_values, ev_source, designs_H, designs_R,
                designs_m, designs_definite, xs, Ps, innovations, nis, dofs, r_up, v_up, C_up,
                params_up):
    """Every window of :func:`navlib.filters.ekf.ekf` for the runs of :func:`compiled_run`
    (module docstring). Windows ``bounds`` (W+1,) of samples ``t`` (N,) with the IMU
    ``f_meas``, ``w_meas`` (N, 3); the windows' :func:`navlib.strapdown.block_clocks`
    concatenated (the mid-step Lagrange samples ``clock_idx``, ``clock_weights`` (N-1, p) and
    the Earth rotations ``clock_earth`` (N-1+W, 4), ``clock_earth_mid`` (N-1, 4)); the
    initial nominal ``r0, v0, C0``, parameters ``params0`` (4, 3) by :data:`_GROUPS` with
    decay rates ``decay`` (4, 3); ``body`` for the body attitude error; the covariance
    ``P`` (21, 21); ``pattern`` the non-zero entries of the model's ``A``, ``G`` and ``Qc``
    that any window can hold (:func:`_model_pattern`). The updates ``e`` in time order: window
    ``ev_window[e]``, window sample ``ev_sample[e]``, design ``ev_design[e]`` (``H``, ``R``,
    rows ``m`` and definiteness of ``R`` of each design in ``designs_*``), the measured
    values ``ev_values[e]`` (m,) and the nominal quantity each row measures
    ``ev_source[e]`` (m,: 0-2 the position's axes, 3-5 the velocity's). Writes the
    posterior mean, covariance, innovation, NIS, dof and corrected nominal of each update;
    returns 0, or ``-1 - window`` when the navigation state is not finite at a window's
    start or its attitude is no rotation, ``-1 - W - window`` when the gravity iteration of
    the strapdown does not converge."""
    n = P.shape[0]
    windows = bounds.size - 1
    longest = 0
    for i in range(windows):
        longest = max(longest, bounds[i + 1] - bounds[i])
    F, Q = np.empty((longest, n, n)), np.empty((longest, n, n))
    A, G = np.empty((longest + 1, n, n)), np.empty((longest + 1, n, 18))
    pos, vel = np.empty((longest + 1, 3)), np.empty((longest + 1, 3))
    quat = np.empty((longest + 1, 4))
    Cs = np.empty((longest + 1, 3, 3))
    f_c, w_c = np.empty((longest + 1, 3)), np.empty((longest + 1, 3))
    par = np.empty((longest + 1, 4, 3))
    dt = np.empty(longest)
    x = np.zeros(n)
    r, v, C, params = r0.copy(), v0.copy(), C0.copy(), params0.copy()
    q0 = np.empty(4)
    kept = np.empty(0, dtype=np.int64)
    e = 0
    events = ev_window.size
    for w in range(windows):
        w0, w1 = bounds[w], bounds[w + 1]
        k = w1 - w0
        finite = True
        for i in range(3):
            finite = finite and math.isfinite(r[i]) and math.isfinite(v[i])
            for j in range(3):
                finite = finite and math.isfinite(C[i, j])
        if not finite or not matrix_quat_kernel(C, q0):
            return -1 - w
        for s in range(k + 1):
            tau = t[w0 + s] - t[w0]
            for g in range(4):
                for i in range(3):
                    rate = decay[g, i]         # exp(0 tau) = 1: random walks skip it
                    par[s, g, i] = params[g, i] * math.exp(rate * tau) if rate else params[g, i]
            for i in range(3):
                f_c[s, i] = (f_meas[w0 + s, i] - par[s, 1, i]) / (1.0 + par[s, 3, i])
                w_c[s, i] = (w_meas[w0 + s, i] - par[s, 0, i]) / (1.0 + par[s, 2, i])
        failed = strapdown.integrate_kernel(
            t[w0:w1 + 1], f_c[:k + 1], w_c[:k + 1], r, v, q0, clock_idx[w0:w1],
            clock_weights[w0:w1], clock_earth[w0 + w:w1 + w + 1], clock_earth_mid[w0:w1],
            pos[:k + 1], vel[:k + 1], quat[:k + 1])
        if failed >= 0:
            return -1 - windows - w
        for s in range(k + 1):
            _matrix(quat[s], Cs[s])
            if s < k:
                dt[s] = t[w0 + s + 1] - t[w0 + s]
        ecef21_jacobians_kernel(pos[:k + 1], Cs[:k + 1], f_c[:k + 1], w_c[:k + 1], body,
                                A, G)
        discretize_kernel(A[:k], G[:k], dt[:k], pattern, F[:k], Q[:k])
        # the runs of updates with one design (WindowUpdates.window), then the window's end
        j0, last = 0, -1
        while e < events and ev_window[e] == w:
            d = ev_design[e]
            m = designs_m[d]
            end = e + 1
            while end < events and ev_window[end] == w and ev_design[end] == d:
                end += 1
            z = np.empty((end - e, m))
            for u in range(e, end):
                j = ev_sample[u]
                for row in range(m):
                    source = ev_source[u, row]
                    nominal = pos[j, source] if source < 3 else vel[j, source - 3]
                    z[u - e, row] = ev_values[u, row] - nominal
            innovation = np.empty((end - e, m))
            x, P = fixed_updates_kernel(
                x, P, F[:k], Q[:k], kept, j0, ev_sample[e:end].copy(), z,
                designs_H[d, :m].copy(), designs_R[d, :m, :m].copy(), designs_definite[d],
                PINV_RTOL, xs[e:end], Ps[e:end], innovation, nis[e:end], dofs[e:end],
                ev_sample[end - 1])
            for u in range(e, end):
                for row in range(m):
                    innovations[u, row] = innovation[u - e, row]
            for u in range(e, end):
                j = ev_sample[u]
                _correct(pos[j], vel[j], Cs[j], par[j], xs[u], body, r_up[u], v_up[u],
                         C_up[u], params_up[u])
            j0, last, e = ev_sample[end - 1], end - 1, end
        x, P = fixed_updates_kernel(
            x, P, F[:k], Q[:k], kept, j0, np.empty(0, dtype=np.int64), np.empty((0, 0)),
            np.empty((0, n)), np.empty((0, 0)), False, PINV_RTOL, np.empty((0, n)),
            np.empty((0, n, n)), np.empty((0, 0)), np.empty(0), np.empty(0, dtype=np.int64),
            k)
        # feedback at the window's end and the reset (ErrorState.reset_jacobian)
        if last >= 0 and ev_sample[last] == k:
            r, v, C, params = (r_up[last].copy(), v_up[last].copy(), C_up[last].copy(),
                               params_up[last].copy())
        else:
            r_new, v_new, C_new, params_new = (np.empty(3), np.empty(3), np.empty((3, 3)),
                                               np.empty((4, 3)))
            _correct(pos[k], vel[k], Cs[k], par[k], x, body, r_new, v_new, C_new, params_new)
            r, v, C, params = r_new, v_new, C_new, params_new
        _reset(P, x, -0.5 if body else 0.5)
        x = np.zeros(n)
    return 0


def _model_pattern(es):
    """The non-zero entries of the model's ``A``, ``G`` (any window's: the Jacobians of a
    nominal state with no zero component) and ``Qc``, as
    :func:`navlib.sparse_discretize.pattern_kernel` gives them. An entry that is zero in a
    window adds zeros to the discretisation's sums, which leaves them as they are."""
    rng = np.random.default_rng(0)
    position = np.array([[4.0e6, 1.0e6, 4.5e6]]) + rng.uniform(1.0, 2.0, (2, 3))
    axes, _ = np.linalg.qr(rng.standard_normal((2, 3, 3)))
    C = axes * np.sign(np.linalg.det(axes))[:, None, None]
    A, G = np.empty((2, 21, 21)), np.empty((2, 21, 18))
    ecef21_jacobians_kernel(position, kernel_array(C), rng.uniform(1.0, 2.0, (2, 3)),
                            rng.uniform(1.0, 2.0, (2, 3)), es.attitude_frame == "body", A, G)
    Qc = np.asarray(es.Qc, dtype=float)
    pairs = np.argwhere(Qc != 0.0).astype(np.int64)
    return pattern_kernel(A, G, pairs, kernel_array(Qc[pairs[:, 0], pairs[:, 1]]))


def _eligible(es, method, rows, resume_point) -> bool:
    """Whether :func:`_loop_kernel` serves this run (module docstring)."""
    return (type(es) is Ecef21ErrorState and method == "series" and es.nav_sign == 1.0
            and tuple(es.parameters) == _GROUPS and bool(es.reset.all())
            and resume_point == (None, None)
            and all(type(meas) in (GnssPosition, GnssVelocity) for meas in rows))


def compiled_run(es, t, f_meas, w_meas, start, params, P, epochs, bounds, method,
                 keep_covariance, rows, names, resume_point):
    """The fields of :func:`navlib.filters.ekf.ekf`'s result by :func:`_loop_kernel`, or
    None when the run is not one it serves (or its state stops being finite: the Python
    loop then runs it and reports where).

    Parameters
    ----------
    es : ErrorStateModel
        The run's error model (served: :class:`~navlib.models.ecef.Ecef21ErrorState`).
    t, f_meas, w_meas : ndarray (N,), (N, 3), (N, 3)
        IMU sample times (s) and measured specific force and rate.
    start : tuple
        Initial nominal ``(r, v, C)``.
    params : dict
        Initial parameter estimates (3,) by group.
    P : ndarray (n, n)
        Initial covariance.
    epochs : Epochs
        The run's :class:`~navlib.filters.ekf_updates.Epochs`.
    bounds : list of int
        Window boundaries (IMU samples).
    method : str
        Discretisation (served: ``"series"``).
    keep_covariance : bool
        Keep the posterior covariances.
    rows : dict
        Measurement -> its rows in the results (served: GNSS position and velocity).
    names : list of str
        Measurement row names.
    resume_point : tuple
        ``(window to snapshot, snapshot to resume)`` (served: neither).

    Returns
    -------
    dict or None
        The result's fields ``t, position, velocity, C_b_e, parameters, kept, sigma, P,
        innovation, nis, nis_dof``.
    """
    if not _eligible(es, method, rows, resume_point):
        return None
    sizes = np.diff(bounds)
    if sizes.min() < 3:                        # every window's clock with 4 Lagrange samples
        return None
    clocks = strapdown.block_clocks(t, bounds)
    clock_idx = np.concatenate([c[0][0] for c in clocks]).astype(np.int64)
    clock_weights = np.concatenate([c[0][1] for c in clocks])
    clock_earth = np.concatenate([c[1] for c in clocks])
    clock_earth_mid = np.concatenate([c[2] for c in clocks])
    # the updates in time order: window, window sample, design, values, rows measured
    design_of, designs = {}, []
    ev = {key: [] for key in ("window", "sample", "design", "values", "source", "cols")}
    starts = np.asarray(bounds[:-1])
    for sample in sorted(epochs.at):           # a window holds its end (and sample 0)
        w = max(int(np.searchsorted(starts, sample, side="left")) - 1, 0)
        j = sample - int(starts[w])
        epoch, cols, fixed = epochs.at[sample]
        if fixed is None:
            return None
        if id(cols) not in design_of:
            design_of[id(cols)] = len(designs)
            designs.append(fixed)
        values = np.concatenate([meas.values[i] for meas, i in epoch])
        source = np.concatenate([np.arange(3) + (3 if type(meas) is GnssVelocity else 0)
                                 for meas, _ in epoch])
        for key, value in zip(ev, (w, j, design_of[id(cols)], values, source, cols),
                              strict=True):
            ev[key].append(value)
    count, n = len(ev["window"]), len(es.state_names)
    m_max = max(H.shape[0] for H, _, _ in designs)
    H_all, R_all = np.zeros((len(designs), m_max, n)), np.zeros((len(designs), m_max, m_max))
    for d, (H, R, _) in enumerate(designs):
        H_all[d, :H.shape[0]], R_all[d, :H.shape[0], :H.shape[0]] = H, R
    values, source = np.zeros((count, m_max)), np.zeros((count, m_max), dtype=np.int64)
    for u, (v, s) in enumerate(zip(ev["values"], ev["source"], strict=True)):
        values[u, :v.size], source[u, :s.size] = v, s
    r0, v0, C0 = start
    out = (np.empty((count, n)), np.empty((count, n, n)), np.empty((count, m_max)),
           np.empty(count), np.empty(count, dtype=np.int64), np.empty((count, 3)),
           np.empty((count, 3)), np.empty((count, 3, 3)), np.empty((count, 4, 3)))
    status = _loop_kernel(
        *(kernel_array(a) for a in (t, f_meas, w_meas)), np.asarray(bounds, dtype=np.int64),
        clock_idx, *(kernel_array(a) for a in (clock_weights, clock_earth, clock_earth_mid,
                                               r0, v0, C0)),
        kernel_array(np.stack([params[g] for g in _GROUPS])),
        kernel_array(np.stack([es.decay[g] for g in _GROUPS])), es.attitude_frame == "body",
        kernel_array(P), _model_pattern(es),
        np.array(ev["window"], dtype=np.int64), np.array(ev["sample"], dtype=np.int64),
        np.array(ev["design"], dtype=np.int64), values, source, H_all, R_all,
        np.array([H.shape[0] for H, _, _ in designs], dtype=np.int64),
        np.array([bool(definite) for _, _, definite in designs]), *out)
    if status < 0:
        return None
    xs, Ps, innov, nis, dofs, r_up, v_up, C_up, params_up = out
    full = np.full((count, epochs.m_all), np.nan)
    for u, cols in enumerate(ev["cols"]):
        full[u, cols] = innov[u, :cols.size]
    t_up = t[np.asarray(bounds)[ev["window"]] + np.array(ev["sample"], dtype=np.int64)]
    return {"t": t_up, "position": r_up, "velocity": v_up, "C_b_e": C_up,
            "parameters": {g: params_up[:, i] for i, g in enumerate(_GROUPS)},
            "kept": xs[:, :0], "sigma": np.sqrt(np.clip(np.diagonal(Ps, axis1=1, axis2=2), 0,
                                                          None)),
            "P": Ps if keep_covariance else None, "innovation": full, "nis": nis,
            "nis_dof": dofs}


def compile_kernel() -> None:
    """Compile (first run on a machine) or load :func:`_loop_kernel` by running the
    21-state EKF over one short window of a resting IMU with one GNSS update (the array
    types of :func:`compiled_run`)."""
    es = Ecef21ErrorState.build()
    t = np.arange(4) * 0.01
    up = earth.normal_gravity_ecef(np.array([earth.A, 0.0, 0.0]))
    f_meas = np.tile(-up, (4, 1))
    w_meas = np.tile([0.0, 0.0, units.DEG], (4, 1))
    gnss = pd.DataFrame({"t": t[-1:], "x": [earth.A], "y": [0.0], "z": [0.0]})
    rows = {meas: np.arange(3) for meas in ekf_measurements(es, t, gnss)}
    events = {3: [(meas, 0) for meas in rows]}
    compiled_run(es, t, f_meas, w_meas, (np.array([earth.A, 0.0, 0.0]), np.zeros(3),
                                          np.eye(3)),
                 {g: np.zeros(3) for g in _GROUPS}, np.array(es.P0, dtype=float),
                 Epochs(events, rows, 3), [0, 3], "series", False, rows, None, (None, None))


drop_stale_kernel_caches(__name__, globals())  # numba checks only this file (numba #1833)
