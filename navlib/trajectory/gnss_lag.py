"""The lag of the GNSS fixes behind the motion, from a scan of the fit (docs/assumptions.md FIT6).

A logger that stamps a fix when it arrives, or a receiver whose solution trails the motion,
records ``P_fix(t) = P(t - lag)``. On the shared TeleMega flights the fixes trail a boost at
250 m/s by about a second, 200-250 m; a fit that takes them at their stamps bends the motion
(a pad 100 m below its own fix) or a calibration (a 10 % accelerometer scale) to meet them.
:func:`lag_profile` moves the fixes back by each lag of a grid and refits the position
spline with the IMU rows and attitude of the first fit; :func:`best_lag` reads the lag of
the smallest GNSS residual; the fit keeps it when its refit lowers that residual by
:data:`LAG_MIN_GAIN` and it moves the fixes by more than their sigma
(:func:`lag_displacement`).
"""

from __future__ import annotations

import numpy as np

from navlib.io.gnss_faults import grid_minimum
from navlib.trajectory.liftoff import pad_fix_times

__all__ = ["LAG_MIN_GAIN", "LAG_ROUNDS", "LAG_STEP_S", "MAX_GNSS_LAG_S", "MIN_GNSS_LAG_S",
           "best_lag", "lag_displacement", "lag_profile"]

MAX_GNSS_LAG_S = 2.0
"""Largest lag scanned, either sign, s (two fix intervals of a 1 Hz receiver)."""
LAG_STEP_S = 0.1
"""Step of the scan, s; the minimum is refined by a parabola through its neighbours."""
MIN_GNSS_LAG_S = 0.05
"""Smallest GNSS lag the fit corrects, s (a quarter of a 5 Hz fix interval; below it the
lag moves a fix by less than 5 m at 100 m/s)."""
LAG_MIN_GAIN = 0.25
"""The refit with the lag must bring the GNSS residual (3-D RMS) down by at least this
fraction, else the lag is not kept (a slow vehicle's residual moves the estimate without being
a lag)."""
LAG_ROUNDS = 3
"""Scans of :func:`navlib.trajectory.fit.fit_flight_data`: the first fit's, then those of
the refits with the lag found so far (each fit follows part of the lag its fixes carry);
after the first, steps down to a quarter of :data:`LAG_STEP_S` count."""


def lag_profile(rows, f_e, coef, t_g, P_g, V_g, sigma):
    """The fit's GNSS residual (3-D RMS, m) with the fixes moved back by each lag of the grid.

    Each lag refits the position spline of ``rows`` (its IMU rows and weights, the specific
    force ``f_e`` of the first fit's attitude, gravity and Coriolis at the first fit's motion:
    a lag moves the positions by metres, gravity by a millionth) with the fixes at
    ``t_g - lag`` (those moved just before the first sample of a record that starts on a pad
    at that sample: :func:`~navlib.trajectory.liftoff.pad_fix_times`); the residual is taken
    over the fixes that stay inside the spline's span at every lag, so every lag is judged on
    the same fixes.

    Parameters
    ----------
    rows : navlib.trajectory.position_spline.PositionRows
        The first fit's position rows.
    f_e : numpy.ndarray
        Specific force in ECEF of the first fit, m/s^2, (N, 3).
    coef : numpy.ndarray
        The first fit's spline coefficients, (m, 3).
    t_g : numpy.ndarray
        Fix times as recorded, s.
    P_g : numpy.ndarray
        ECEF fix positions, m, (n, 3).
    V_g : numpy.ndarray or None
        ECEF fix velocities, m/s, (n, 3).
    sigma : numpy.ndarray
        Position sigma of each fix, m.

    Returns
    -------
    lags : numpy.ndarray
        The lags scanned, s (0 among them).
    rms : numpy.ndarray
        The GNSS residual at each lag, m (NaN where fewer than 4 fixes are judged).
    """
    n_steps = round(MAX_GNSS_LAG_S / LAG_STEP_S)
    lags = LAG_STEP_S * np.arange(-n_steps, n_steps + 1)
    t0, t1 = rows.knots[0], rows.knots[-1]
    on_pad = rows.N_pad is not None
    t_lag = [pad_fix_times(t_g - lag, t0, on_pad) for lag in lags]
    common = np.logical_and.reduce([(t_k >= t0) & (t_k <= t1) for t_k in t_lag])
    rms = np.full(lags.size, np.nan)
    if common.sum() < 4:
        return lags, rms
    imu_rhs = rows.imu_rhs(f_e, coef)      # gravity and Coriolis at the first fit's motion
    for k, t_k in enumerate(t_lag):
        inside = (t_k >= t0) & (t_k <= t1)
        moved = rows.with_gnss_times(t_k[inside], P_g[inside],
                                     None if V_g is None else V_g[inside], sigma[inside])
        c = moved.solve_rhs(imu_rhs)
        judged = common[inside]
        d = P_g[common] - (rows.P_ref + moved.G0[judged] @ c)
        rms[k] = float(np.sqrt(np.mean(np.sum(d**2, axis=1))))
    return lags, rms


def best_lag(lags, rms, minimum=MIN_GNSS_LAG_S) -> float:
    """The lag of the smallest residual of :func:`lag_profile`, refined by a parabola
    through its neighbours; 0 below ``minimum`` or when the profile has gaps.

    Parameters
    ----------
    lags, rms : array_like
        Result of :func:`lag_profile`.
    minimum : float, optional
        Smallest lag returned, s.

    Returns
    -------
    float
        The lag, s (fixes recorded ``lag`` after the position they report).
    """
    lags, rms = np.asarray(lags, float), np.asarray(rms, float)
    if not np.isfinite(rms).all():
        return 0.0
    lag = grid_minimum(lags, rms)
    return lag if abs(lag) >= minimum else 0.0


def lag_displacement(trajectory, t_g, lag) -> float:
    """How far a lag moves the fixes: ``|lag|`` times the RMS speed of ``trajectory`` at the
    fix times ``t_g`` inside it, m. A lag that moves them by less than the GNSS sigma cannot
    be told from noise (at rest no lag can).

    Parameters
    ----------
    trajectory : navlib.trajectory.Trajectory
        The fit without the lag.
    t_g : numpy.ndarray
        Fix times, s.
    lag : float
        The lag, s.

    Returns
    -------
    float
    """
    t_g = np.asarray(t_g, dtype=float)
    t_g = t_g[(t_g >= trajectory.t[0]) & (t_g <= trajectory.t[-1])]
    if t_g.size == 0:
        return 0.0
    v = np.column_stack([np.interp(t_g, trajectory.t, trajectory.velocity[:, i])
                         for i in range(3)])
    return abs(lag) * float(np.sqrt(np.mean(np.sum(v**2, axis=1))))

