"""The position spline of :func:`navlib.trajectory.fit_flight_data` and its attitude correction.

Method step 3 of :mod:`navlib.trajectory.fit`: ``P(t)`` is a quintic B-spline whose
coefficients solve one weighted least-squares problem with GNSS position (and velocity) rows
and, at every IMU sample, the kinematic rows
``P'' = (I + S(eps(t))) C_b_e f^b + gamma(P) - 2 Omega x P'`` (docs/assumptions.md,
excitability.md Eq. 1).
:class:`PositionRows` holds the banded normal equations (one Cholesky factorisation for the
three axes); :class:`AttitudeCorrection` the slowly varying attitude correction ``eps(t)``
and the constant accelerometer bias, eliminated through a Schur complement.
:func:`place_knots` places the knots of both the position and the attitude spline.
"""

import copy

import numpy as np
import pandas as pd
import scipy.sparse as sp
from scipy.interpolate import BSpline
from scipy.linalg import solveh_banded

from navlib import earth
from navlib.trajectory._so3 import basis
from navlib.units import DEG

__all__ = ["ATTITUDE_SAMPLES_PER_KNOT", "LOCAL_SCALE_S", "MAX_CONING_PER_SAMPLE_RAD",
           "MAX_CORRECTION_INTERVALS", "MAX_KNOT_SPACING_S", "MAX_TURN_PER_KNOT_RAD",
           "MAX_TURN_PER_SAMPLE_RAD", "MIN_RELATIVE_WEIGHT", "PAD_SIGMA_MPS", "SAMPLES_PER_KNOT",
           "SCALE_OFF", "SPLINE_DEGREE", "UNRESOLVED_MARGIN_S", "UNRESOLVED_WEIGHT",
           "AttitudeCorrection", "PositionRows", "coning_per_sample", "local_median", "place_knots",
           "resolved_samples", "thin"]

SPLINE_DEGREE = 5           # quintic splines: C^4 position, C^2 specific force
_HUBER = 4.0                # specific-force rows beyond this many sigma are down-weighted
SAMPLES_PER_KNOT = 2
"""Fewest IMU samples in each knot interval of the splines (knots are merged until so)."""
MAX_KNOT_SPACING_S = 0.5
"""Longest knot interval the fit accepts: a quintic B-spline follows features about two knot
intervals long, so 0.5 s intervals still resolve the ~1 Hz manoeuvres of aircraft and
multicopters (and the 0.5 s de-spin of the sounding rocket)."""
MAX_TURN_PER_KNOT_RAD = 1.5
"""Largest rotation of the body within one knot interval of the attitude spline, rad: its
control rotations then differ by well under pi (the cumulative spline's increments are
principal logarithms) and a tumble or fast spin gets denser knots."""
ATTITUDE_SAMPLES_PER_KNOT = 6
"""About this many attitude samples per knot interval enter the attitude spline's fit (every
n-th of a denser interval): the samples are integrated gyro readings, smooth at that scale,
and the Gauss-Newton cost grows with their number (a 250 Hz record has 25 per 0.1 s)."""
MAX_TURN_PER_SAMPLE_RAD = np.radians(30.0)
"""A sample whose recorded rate turns the body by more than this since the previous one is
not resolved by the record's rate: the gyro chain cannot follow a rotation axis that moves
within a sample (900 deg/s at 10 Hz is 90 deg per sample); the assessment's bound
``max_turn_per_sample_deg`` in data/quality.toml [fit] is the same 30 deg."""
MAX_CONING_PER_SAMPLE_RAD = np.radians(0.1)
"""A sample whose rotation axis moves against the previous sample's by more than this is not
resolved either: ``|dtheta_(k-1) x dtheta_k| / 2`` (the coning term of a two-sample attitude
algorithm, ``dtheta = w dt``) measures the part of the rotation the sampled rates leave to
interpolation, and 0.1 deg per sample is 1 deg/s of attitude uncertainty at 10 Hz (a
1 m/s^2 specific-force error at 6 g). On the shared TeleMega flights the 100 Hz ascent
spinning at 300-500 deg/s stays below 0.003 deg per sample; the 10 Hz descents under drogue
and main reach 1-2 deg in the median (docs/assumptions.md FIT7)."""
LOCAL_SCALE_S = 2.0
"""Window of the local robust spread of the recorded specific force that sets each IMU row's
sigma (:meth:`PositionRows.robust_weights`), s: long enough for a median over 200 samples at
100 Hz, short enough to tell a 3 s boost from the coast after it."""
SCALE_OFF = 1e-9
"""Prior sigma that holds the scale error of an axis not estimated at zero."""
MIN_RELATIVE_WEIGHT = 1e-4
"""Floor of a specific-force row's weight, relative to the median row's
(:meth:`PositionRows.set_weights`): the unresolved rows' factor times a vibration sigma 100
times the median reaches below it."""
UNRESOLVED_WEIGHT = 1e-4
"""Weight factor of the specific-force rows within ``UNRESOLVED_MARGIN_S`` of an unresolved
sample: their attitude is unknown, so the GNSS carries the position there and they do not
set the accelerometer calibration or the attitude correction."""
UNRESOLVED_MARGIN_S = 0.5
PAD_SIGMA_MPS = 1e-3
"""Standard deviation of the zero-velocity rows on the pad, m/s (a constraint in effect)."""
MAX_CORRECTION_INTERVALS = 60
"""Most knot intervals of the attitude correction: flights longer than 60
``correction_knot_spacing_s`` get wider intervals (10 min at the default 10 s), which keeps
its dense Schur complement small; a cubic spline still holds the linear drift of a gyro
bias exactly."""


def place_knots(t, spacing, turn=None):
    """Clamped quintic knot vector on ``[t[0], t[-1]]``, interior knots about ``spacing`` apart.

    Knots come from a uniform grid; a knot is dropped when fewer than ``SAMPLES_PER_KNOT``
    samples ``t`` would lie between it and the previous knot kept (or after it), so holes
    in the record and low rates merge knot intervals instead of leaving coefficients
    without data (the normal equations stay definite). With ``turn`` (the cumulative
    rotation angle of the body at ``t``, rad) the grid is uniform in
    ``(t - t[0]) / spacing + turn / MAX_TURN_PER_KNOT_RAD`` instead, so no knot interval
    turns the body by more than ``MAX_TURN_PER_KNOT_RAD`` (the attitude spline).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    spacing : float
        Knot spacing, s.
    turn : numpy.ndarray or None, optional
        Cumulative body rotation at ``t``, rad.

    Returns
    -------
    numpy.ndarray
        Knot vector.
    """
    t0, t1 = float(t[0]), float(t[-1])
    if turn is None:
        n_int = max(int(np.ceil((t1 - t0) / spacing - 1e-9)), 1)
        grid = np.linspace(t0, t1, n_int + 1)[1:-1]
    else:
        u = (t - t0) / spacing + (turn - turn[0]) / MAX_TURN_PER_KNOT_RAD
        n_int = max(int(np.ceil(u[-1] - 1e-9)), 1)
        grid = np.interp(np.linspace(0.0, u[-1], n_int + 1)[1:-1], u, t)
    below = np.searchsorted(t, grid, side="left")     # samples before each candidate knot
    keep, last = [], 0
    for knot, count in zip(grid, below, strict=True):
        if count - last >= SAMPLES_PER_KNOT and t.size - count >= SAMPLES_PER_KNOT:
            keep.append(knot)
            last = count
    return np.r_[np.full(SPLINE_DEGREE + 1, t0), keep, np.full(SPLINE_DEGREE + 1, t1)]


def thin(t, knots, per_interval):
    """Indices of the samples kept for a fit on ``knots``: in each knot interval with ``c``
    samples, every ``max(1, c // per_interval)``-th one (the first and last sample always).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    knots : numpy.ndarray
        Knot vector.
    per_interval : int
        Samples kept per knot interval, about.

    Returns
    -------
    numpy.ndarray
        Kept indices.
    """
    inner = knots[SPLINE_DEGREE + 1:-SPLINE_DEGREE - 1]
    interval = np.searchsorted(inner, t, side="right")
    first = np.searchsorted(interval, np.arange(inner.size + 1), side="left")
    count = np.diff(np.r_[first, t.size])
    stride = np.maximum(count // per_interval, 1)
    pos = np.arange(t.size) - first[interval]
    keep = pos % stride[interval] == 0
    keep[[0, -1]] = True
    return np.flatnonzero(keep)


def _basis(x, knots, nu):
    """Sparse (N, m) matrix of the ``nu``-th derivatives of the quintic B-spline basis."""
    return basis(x, knots, SPLINE_DEGREE, nu)


def _banded(N):
    """Upper banded storage of a symmetric sparse matrix with bandwidth ``SPLINE_DEGREE``."""
    m = N.shape[0]
    ab = np.zeros((SPLINE_DEGREE + 1, m))
    for d in range(SPLINE_DEGREE + 1):
        ab[SPLINE_DEGREE - d, d:] = N.diagonal(d)
    return ab


class PositionRows:
    """The weighted least-squares rows of the position spline (method step 3).

    Unknowns are the spline coefficients of ``P - P_ref`` for x, y, z (same basis) and,
    optionally, the attitude correction. The three axes share the banded normal matrix.
    """

    def __init__(self, knots, t, t_g, P_g, V_g, sigma, p, P_ref, pad_end=None,
                 resolved=None):
        self.P_ref = P_ref
        self.knots = knots
        self.t = t
        self.B0, self.B1, self.B2 = (_basis(t, knots, nu) for nu in range(3))
        self.sigma_f = p["sigma_specific_force_mps2"]
        self.sigma_v = p["sigma_velocity_mps"]
        self.scaled = False
        self.N_pad = None
        if pad_end is not None:     # standing still on the pad: P' = 0 up to lift-off
            B1 = self.B1[:pad_end + 1]
            self.N_pad = (B1.T @ B1) / PAD_SIGMA_MPS**2
        self._set_gnss(t_g, P_g, V_g, sigma)
        self.resolved = np.ones(t.size, bool) if resolved is None else resolved
        self.set_weights(np.ones(t.size))
        # first linearisation point: GNSS positions interpolated to the IMU times
        self.P0 = np.column_stack([np.interp(t, t_g, P_g[:, i]) for i in range(3)])
        self.V0 = np.column_stack([np.interp(t, t_g, np.gradient(P_g[:, i], t_g))
                                   for i in range(3)])

    def _set_gnss(self, t_g, P_g, V_g, sigma):
        """The GNSS rows (positions, velocities when given) and the pad rows' normal
        matrix ``N_gnss`` with its right-hand side ``rhs_gnss``."""
        self.G0, self.G1 = _basis(t_g, self.knots, 0), _basis(t_g, self.knots, 1)
        w_g2 = 1.0 / sigma**2
        N_gnss = self.G0.T @ (self.G0 * w_g2[:, None])
        if self.N_pad is not None:
            N_gnss = N_gnss + self.N_pad
        rhs_gnss = self.G0.T @ (w_g2[:, None] * (P_g - self.P_ref))
        if V_g is not None:
            w_v2 = 1.0 / self.sigma_v ** 2
            N_gnss = N_gnss + w_v2 * (self.G1.T @ self.G1)
            rhs_gnss = rhs_gnss + w_v2 * (self.G1.T @ V_g)
        self.N_gnss, self.rhs_gnss = N_gnss, rhs_gnss

    def with_gnss_times(self, t_g, P_g, V_g, sigma):
        """A copy whose GNSS rows sit at the times ``t_g`` (the same fixes moved in time:
        the lag scan of :func:`navlib.trajectory.fit.fit_flight_data`); the IMU rows and
        their weights are shared.

        Parameters
        ----------
        t_g : numpy.ndarray
            Fix times, s, inside the knot span.
        P_g : numpy.ndarray
            ECEF positions of the fixes, m, (n, 3).
        V_g : numpy.ndarray or None
            ECEF velocities of the fixes, m/s, (n, 3).
        sigma : numpy.ndarray
            Position sigma of each fix, m.

        Returns
        -------
        PositionRows
        """
        out = copy.copy(self)
        out._set_gnss(t_g, P_g, V_g, sigma)
        out.N = sp.csr_array(self.N_imu + out.N_gnss)
        out.ab = _banded(out.N)
        return out

    def set_weights(self, factor):
        """IMU row weights ``factor / sigma_f^2`` (``sigma_f`` a scalar or one per row;
        times ``UNRESOLVED_WEIGHT`` where the rotation is not resolved) and the banded
        normal matrix."""
        w_f2 = factor * np.where(self.resolved, 1.0, UNRESOLVED_WEIGHT) / self.sigma_f**2
        # no row weighs less than MIN_RELATIVE_WEIGHT of the median row: across a GNSS
        # outage the rows alone hold the spline, and a range of weights beyond what the
        # banded factorisation resolves leaves it free to swing (a parachute opening at
        # 1750 deg/s drove a reference to 460 m/s)
        self.w_f2 = np.maximum(w_f2, MIN_RELATIVE_WEIGHT * float(np.median(w_f2)))
        self.N_imu = self.B2.T @ (self.B2 * self.w_f2[:, None])
        self.N = sp.csr_array(self.N_imu + self.N_gnss)
        self.ab = _banded(self.N)

    def robust_weights(self, coef, f_e, eps):
        """Huber factors from the specific-force residual norms (threshold ``_HUBER`` sigma).

        The first call also raises ``sigma_f`` to the local robust spread of the recorded
        specific force from one sample to the next (1.4826 x the median absolute difference
        over ``sqrt(2)`` within ``LOCAL_SCALE_S``, per sample) where that is larger:
        vibration then weighs as the noise it is against the GNSS rows, a stretch that
        shakes (a boost, a parachute opening) does not set the weight of a quiet one (a
        coast), and a slow departure of the fit from the records is not taken for noise.

        Parameters
        ----------
        coef : numpy.ndarray
            Spline coefficients, (m, 3).
        f_e : numpy.ndarray
            Specific force in ECEF, m/s^2, (N, 3).
        eps : numpy.ndarray
            Attitude correction rotation vectors, (N, 3).
        """
        P, V, a = self.evaluate(coef)
        r = (f_e + np.cross(eps, f_e) + earth.normal_gravity_ecef(P)
             - 2.0 * np.cross(earth.EARTH_RATE_ECEF, V))
        if not self.scaled:
            # sample-to-sample spread of the records: noise and vibration, not the motion
            spread = np.abs(np.diff(f_e, axis=0, prepend=f_e[:1])).mean(axis=1) / np.sqrt(2.0)
            local = local_median(self.t, spread, LOCAL_SCALE_S)
            self.sigma_f = np.maximum(self.sigma_f, 1.4826 * local)
            self.scaled = True
        size = np.linalg.norm(a - r, axis=1) / (_HUBER * self.sigma_f)
        self.set_weights(1.0 / np.maximum(size, 1.0))

    def _solve(self, rhs):
        x = solveh_banded(self.ab, rhs)
        return x + solveh_banded(self.ab, rhs - self.N @ x)   # one refinement step

    def evaluate(self, coef):
        return self.P_ref + self.B0 @ coef, self.B1 @ coef, self.B2 @ coef

    def imu_rhs(self, f_e, coef):
        """The specific-force rows' right-hand side ``B2' W (f_e + gamma - 2 Omega x V)``,
        linearised at the coefficients ``coef`` (what :meth:`solve` adds the GNSS rows' to).

        Parameters
        ----------
        f_e : numpy.ndarray
            Specific force in ECEF, m/s^2, (N, 3).
        coef : numpy.ndarray
            Spline coefficients of the linearisation, (m, 3).

        Returns
        -------
        numpy.ndarray
            (m, 3).
        """
        P, V, _ = self.evaluate(coef)
        r = f_e + earth.normal_gravity_ecef(P) - 2.0 * np.cross(earth.EARTH_RATE_ECEF, V)
        return self.B2.T @ (self.w_f2[:, None] * r)

    def solve_rhs(self, imu_rhs):
        """The coefficients for the specific-force rows' ``imu_rhs`` (:meth:`imu_rhs`) and
        this object's GNSS rows, without an attitude correction.

        Parameters
        ----------
        imu_rhs : numpy.ndarray
            (m, 3).

        Returns
        -------
        numpy.ndarray
            (m, 3).
        """
        return self._solve(imu_rhs + self.rhs_gnss)

    def solve(self, f_e, coef, correction=None, C=None, f_b=None):
        """Coefficients (m, 3) and the attitude correction rotation vectors (N, 3).

        With a :class:`AttitudeCorrection`, the specific force rows read
        ``P'' = (I + S(eps(t))) C f + gamma - 2 Omega x V``; ``eps`` is eliminated through
        its Schur complement (a small dense system) so the banded solve stays banded.

        Parameters
        ----------
        f_e : numpy.ndarray
            Specific force in ECEF, m/s^2, (N, 3).
        coef : numpy.ndarray or None
            Current coefficients (None: the start values).
        correction : AttitudeCorrection or None, optional
            Attitude correction to estimate with the position.
        C : numpy.ndarray or None, optional
            Body -> ECEF matrices, (N, 3, 3).
        f_b : numpy.ndarray or None, optional
            Body specific force, m/s^2, (N, 3).
        """
        if coef is None:
            P, V = self.P0, self.V0
        else:
            P, V, _ = self.evaluate(coef)
        r = f_e + earth.normal_gravity_ecef(P) - 2.0 * np.cross(earth.EARTH_RATE_ECEF, V)
        w = self.w_f2[:, None]
        rhs = self.B2.T @ (w * r) + self.rhs_gnss
        if correction is None:
            return self._solve(rhs), np.zeros_like(f_e)
        G = correction.columns(f_e, C, f_b)               # 3 x sparse (N, n_u)
        Q = [sp.csr_array(self.B2.T @ (G[a] * w)) for a in range(3)]
        n_u = G[0].shape[1]
        sol = self._solve(np.hstack([rhs, *(q.toarray() for q in Q)]))
        c0 = sol[:, :3]
        S = [sol[:, 3 + a * n_u: 3 + (a + 1) * n_u] for a in range(3)]
        lhs = correction.prior.copy()
        b = -correction.prior @ correction.total      # the prior holds the accumulated sum
        for a in range(3):
            lhs += (G[a].T @ (G[a] * w)).toarray() - Q[a].T @ S[a]
            b += Q[a].T @ c0[:, a] - G[a].T @ (w[:, 0] * r[:, a])
        e = np.linalg.solve(lhs, b)
        correction.total = correction.total + e
        coef = c0 + np.column_stack([S[a] @ e for a in range(3)])
        return coef, correction.evaluate(e)


class AttitudeCorrection:
    """Slowly varying attitude correction ``eps(t)`` (ECEF rotation vector, cubic B-spline)
    and a constant accelerometer bias ``b_a`` and scale-factor error ``s_a`` (body axes).

    ``C <- exp(S(eps)) C`` absorbs the initial tilt/heading error and the gyro drift that
    the recorded specific force and GNSS reveal; ``f <- f - b_a - s_a f`` the accelerometer
    bias and scale error (the recorded ``(1 + s_a) f + b_a`` to first order), which would
    otherwise be taken for motion (a parked vehicle drifting at a few m/s, a boost bent by a
    3 % scale). Prior: each ``eps`` coefficient ~ N(0, ``attitude_prior_deg ** 2``) and
    neighbouring coefficients differ by ~ N(0, (``attitude_drift_deg_s`` x knot spacing)^2),
    so stretches without attitude information (free fall) keep the gyro attitude; each bias
    component ~ N(0, ``sigma_ba ** 2``), each scale error ~ N(0, ``sigma_sa ** 2``) (the preset's
    turn-on bias and scale factor); a zero sigma leaves that term out.
    """

    def __init__(self, t, p, sigma_ba, sigma_sa=0.0):
        """``sigma_sa``: one prior sigma, or one per body axis (0: that axis' scale error
        is not estimated)."""
        k = 3
        n_int = max(int(np.ceil((t[-1] - t[0]) / p["correction_knot_spacing_s"] - 1e-9)), 1)
        n_int = min(n_int, MAX_CORRECTION_INTERVALS)
        inner = np.linspace(t[0], t[-1], n_int + 1)
        knots = np.r_[np.full(k, t[0]), inner, np.full(k, t[-1])]
        x = np.minimum(t, np.nextafter(t[-1], -np.inf))
        self.beta = sp.csr_array(BSpline.design_matrix(x, knots, k))   # (N, n_c), sparse
        n_c = self.beta.shape[1]
        step = (t[-1] - t[0]) / n_int
        D = np.diff(np.eye(n_c), axis=0)
        per_axis = (np.eye(n_c) / (p["attitude_prior_deg"] * DEG) ** 2
                    + D.T @ D / (p["attitude_drift_deg_s"] * DEG * step) ** 2)
        # unknowns ordered (axis j, coef i) for eps, then the bias, then the scale errors
        self.n_b = 3 if sigma_ba > 0 else 0              # no bias unknowns without a prior
        sigma_sa = np.broadcast_to(np.asarray(sigma_sa, dtype=float), (3,))
        self.n_s = 3 if (sigma_sa > 0).any() else 0
        n = 3 * n_c + self.n_b + self.n_s
        self.prior = np.zeros((n, n))
        self.prior[:3 * n_c, :3 * n_c] = np.kron(np.eye(3), per_axis)
        if self.n_b:
            self.prior[3 * n_c:3 * n_c + 3, 3 * n_c:3 * n_c + 3] = np.eye(3) / sigma_ba**2
        if self.n_s:
            # an axis without a prior sigma keeps its scale error at 0 (an exact prior)
            self.prior[n - 3:, n - 3:] = np.diag(1.0 / np.maximum(sigma_sa, SCALE_OFF) ** 2)
        self.n_c = n_c
        self.total = np.zeros(n)                         # sum of the increments applied

    @property
    def bias(self):
        """Accumulated accelerometer bias estimate (body axes, m/s^2)."""
        i = 3 * self.n_c
        return self.total[i:i + 3] if self.n_b else np.zeros(3)

    @property
    def scale(self):
        """Accumulated accelerometer scale-factor error estimate (body axes)."""
        return self.total[-3:] if self.n_s else np.zeros(3)

    def corrected(self, f_b):
        """The recorded specific force ``f_b`` with the bias and scale error removed."""
        return f_b - self.bias - self.scale * f_b

    def columns(self, f_e, C, f_b=None):
        """Sparse ``G[a]`` (N, n_u) for the axes a: ``beta_i(t_k) (e_j x f_e(t_k))_a`` for
        ``eps``, ``-C_b_e[k, a, j]`` for the bias and ``-C_b_e[k, a, j] f_b[k, j]`` for the
        scale error.

        Parameters
        ----------
        f_e : numpy.ndarray
            Specific force in ECEF, m/s^2, (N, 3).
        C : numpy.ndarray
            Body -> ECEF matrices, (N, 3, 3).
        f_b : numpy.ndarray or None, optional
            Body specific force, m/s^2, (N, 3).

        Returns
        -------
        list of scipy.sparse.csr_array
        """
        out = []
        for a in range(3):
            blocks = []
            for j in range(3):
                e_j = np.zeros(3)
                e_j[j] = 1.0
                cross = np.cross(e_j, f_e)[:, a]          # (N,)
                blocks.append(sp.diags_array(cross) @ self.beta)
            if self.n_b:
                blocks.append(sp.csr_array(-C[:, a, :]))
            if self.n_s:
                blocks.append(sp.csr_array(-C[:, a, :] * f_b))
            out.append(sp.csr_array(sp.hstack(blocks)))
        return out

    def evaluate(self, e):
        return np.column_stack([self.beta @ e[j * self.n_c:(j + 1) * self.n_c]
                                for j in range(3)])


def local_median(t, x, window_s):
    """The median of ``x`` over the samples within ``window_s / 2`` of each time ``t``.

    Parameters
    ----------
    t : numpy.ndarray
        Increasing times, s.
    x : numpy.ndarray
        Values, (N,).
    window_s : float
        Window length, s.

    Returns
    -------
    numpy.ndarray
        (N,).
    """
    index = pd.to_timedelta(np.asarray(t, dtype=float) - t[0], unit="s")
    series = pd.Series(np.asarray(x, dtype=float), index=index)
    return series.rolling(pd.Timedelta(seconds=window_s), center=True,
                          min_periods=1).median().to_numpy()


def coning_per_sample(t, w_b):
    """How far each sample's rotation axis moves against the previous sample's, rad:
    ``|dtheta_(k-1) x dtheta_k| / 2`` with ``dtheta = w dt`` (the coning term of a
    two-sample attitude algorithm; 0 for the first sample and a rotation about a fixed axis).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    w_b : numpy.ndarray
        Angular rate, rad/s, (N, 3).

    Returns
    -------
    numpy.ndarray
        (N,).
    """
    theta = np.asarray(w_b, dtype=float) * np.diff(t, prepend=t[0])[:, None]
    return 0.5 * np.linalg.norm(np.cross(np.r_[theta[:1], theta[:-1]], theta), axis=1)


def resolved_samples(t, w_b):
    """True where no sample within ``UNRESOLVED_MARGIN_S`` turns the body by more than
    ``MAX_TURN_PER_SAMPLE_RAD`` since the previous one or moves its rotation axis by more
    than ``MAX_CONING_PER_SAMPLE_RAD``.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    w_b : numpy.ndarray
        Angular rate, rad/s, (N, 3).

    Returns
    -------
    numpy.ndarray
        Boolean mask, (N,).
    """
    step = np.diff(t, prepend=t[0])
    fast = ((np.linalg.norm(w_b, axis=1) * step > MAX_TURN_PER_SAMPLE_RAD)
            | (coning_per_sample(t, w_b) > MAX_CONING_PER_SAMPLE_RAD))
    c = np.r_[0, np.cumsum(fast)]
    i0 = np.searchsorted(t, t - UNRESOLVED_MARGIN_S, side="left")
    i1 = np.searchsorted(t, t + UNRESOLVED_MARGIN_S, side="right")
    return c[i1] - c[i0] == 0
