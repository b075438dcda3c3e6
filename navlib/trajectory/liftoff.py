"""Lift-off found from the records, so the fitted reference can stand still on the pad.

:func:`find_liftoff` reads the recorded specific force only (never the fit): a vehicle on
the pad feels gravity and nothing else; a powered lift-off adds a sustained thrust
acceleration (docs/assumptions.md FIT4). :func:`navlib.trajectory.fit_flight_data` then holds
the reference still (zero velocity, constant attitude) from the first sample until that
time.
"""

import numpy as np

from navlib import earth
from navlib.trajectory.position_spline import SAMPLES_PER_KNOT, SPLINE_DEGREE
from navlib.units import DEG

__all__ = ["LIFTOFF_ACCEL_MPS2", "LIFTOFF_HOLD_S", "LIFTOFF_KNOTS_S", "LIFTOFF_SMOOTH_S",
           "MIN_PAD_SAMPLES", "PAD_ACCEL_MPS2", "PAD_GNSS_SPEED_MPS", "PAD_RATE_DEG_S",
           "find_liftoff", "gnss_still", "liftoff_knots", "moving_average", "pad_start"]

LIFTOFF_ACCEL_MPS2 = 2.0
"""Specific force above gravity that marks a powered lift-off when it lasts
``LIFTOFF_HOLD_S`` (the segmentation's ``powered_accel_m_s2``)."""
LIFTOFF_HOLD_S = 0.2
"""How long the specific force must stay ``LIFTOFF_ACCEL_MPS2`` above gravity, s."""
LIFTOFF_SMOOTH_S = 0.05
"""Moving average of ``|f|`` before the thresholds, s (motor vibration is not thrust)."""
PAD_ACCEL_MPS2 = 0.5
"""Lift-off is the last sample before the thrust onset whose averaged ``|f|`` is within this
of gravity (the thrust ramp starts there; the rest acceleration of
:data:`navlib.trajectory.initial_attitude.REST_ACCEL_MPS2`)."""
PAD_RATE_DEG_S = 3.0
"""Largest mean angular rate on the pad, deg/s (the segmentation's rest rate)."""
MIN_PAD_SAMPLES = 3
PAD_GNSS_SPEED_MPS = 0.5
"""Largest speed of the straight line through the fixes before lift-off, m/s (the
segmentation's rest acceleration scale: a pad does not travel)."""
LIFTOFF_KNOTS_S = 0.4
"""Span after lift-off with knots every ``SAMPLES_PER_KNOT`` samples, s: twice
``LIFTOFF_HOLD_S``, time for the thrust to build up."""


def moving_average(t, x, window_s):
    """Centred moving average of ``x`` (N, k) over ``window_s`` of time (uneven sampling
    allowed: the mean of the samples within +- ``window_s / 2`` of each).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s, (N,).
    x : numpy.ndarray
        Values, (N, k).
    window_s : float
        Window length, s.

    Returns
    -------
    numpy.ndarray
        (N, k).
    """
    c = np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x, axis=0)])
    i0 = np.searchsorted(t, t - 0.5 * window_s, side="left")
    i1 = np.searchsorted(t, t + 0.5 * window_s, side="right")
    return (c[i1] - c[i0]) / (i1 - i0)[:, None]


def find_liftoff(t, f_b, w_b, g, tolerance):
    """Lift-off time from the recorded IMU, or None when the record does not start on a pad.

    The thrust onset is the first sample from which the specific force, averaged over
    ``LIFTOFF_SMOOTH_S``, stays more than ``LIFTOFF_ACCEL_MPS2`` above gravity ``g`` for
    ``LIFTOFF_HOLD_S``; lift-off is the last sample before it within ``PAD_ACCEL_MPS2`` of
    ``g``. The samples before must be a pad: at least ``MIN_PAD_SAMPLES``, their median
    ``|f|`` within ``tolerance * g`` of gravity (the levelling tolerance) and their mean
    rate below ``PAD_RATE_DEG_S``. Returns ``(t_liftoff, index)``: the pad is
    ``t[:index + 1]``.

    Parameters
    ----------
    t : numpy.ndarray
        IMU times, s.
    f_b : numpy.ndarray
        Specific force, m/s^2, (N, 3).
    w_b : numpy.ndarray
        Angular rate, rad/s, (N, 3).
    g : float
        Local gravity, m/s^2.
    tolerance : float
        Levelling tolerance, a fraction of ``g``.
    """
    a = moving_average(t, np.linalg.norm(f_b, axis=1)[:, None], LIFTOFF_SMOOTH_S)[:, 0] - g
    high = a > LIFTOFF_ACCEL_MPS2
    # first sample from which `high` holds for LIFTOFF_HOLD_S
    run_end = np.searchsorted(t, t + LIFTOFF_HOLD_S, side="right")
    c = np.r_[0, np.cumsum(~high)]
    sustained = high & (c[run_end] - c[np.arange(t.size)] == 0) & (
        run_end < t.size)
    if not sustained.any():
        return None
    onset = int(np.argmax(sustained))
    calm = np.flatnonzero(np.abs(a[:onset]) <= PAD_ACCEL_MPS2)
    if calm.size == 0:
        return None
    k = int(calm[-1])
    if k + 1 < MIN_PAD_SAMPLES:
        return None
    norm = np.linalg.norm(f_b[:k + 1], axis=1)
    rate = np.linalg.norm(np.mean(w_b[:k + 1], axis=0))
    if abs(np.median(norm) - g) > tolerance * g or rate > PAD_RATE_DEG_S * DEG:
        return None
    return float(t[k]), k


def liftoff_knots(knots, t, pad_end):
    """``knots`` with lift-off ``t[pad_end]`` as a knot of multiplicity ``degree - 1`` and
    knots every ``SAMPLES_PER_KNOT`` samples over the ``LIFTOFF_KNOTS_S`` after it.

    At the multiple knot the position spline keeps a continuous velocity but its
    acceleration may jump, as thrust does when the vehicle leaves the pad; the dense knots
    let it follow a thrust ramp of a few hundredths of a second, which one knot interval of
    0.1 s cannot (docs/assumptions.md FIT4). Knots of ``knots`` in that stretch are replaced.

    Parameters
    ----------
    knots : numpy.ndarray
        Knot vector.
    t : numpy.ndarray
        Sample times, s.
    pad_end : int
        Index of the lift-off sample.
    """
    t_lift = float(t[pad_end])
    if not t[0] < t_lift < t[-1]:
        return knots
    end = int(np.searchsorted(t, t_lift + LIFTOFF_KNOTS_S, side="right"))
    dense = t[pad_end + SAMPLES_PER_KNOT:end:SAMPLES_PER_KNOT]
    dense = dense[t.size - np.searchsorted(t, dense) > SAMPLES_PER_KNOT]
    lo = t[max(pad_end - SAMPLES_PER_KNOT, 0)]
    hi = dense[-1] + (t[SAMPLES_PER_KNOT] - t[0]) if dense.size else t_lift
    inner = knots[SPLINE_DEGREE + 1:-SPLINE_DEGREE - 1]
    inner = inner[(inner < lo) | (inner > hi)]
    inner = np.sort(np.r_[inner, np.full(SPLINE_DEGREE - 1, t_lift), dense])
    return np.r_[knots[:SPLINE_DEGREE + 1], inner, knots[-SPLINE_DEGREE - 1:]]


def gnss_still(t_g, P_g, t_liftoff):
    """Whether the fixes up to ``t_liftoff`` stand still: the straight line through them
    (least squares, at least 3 fixes; fewer say nothing against a pad) moves slower than
    ``PAD_GNSS_SPEED_MPS`` plus three standard errors of its speed (from the scatter of the
    fixes about the line). An IMU at rest on a hovering or drifting vehicle reads as a pad;
    the GNSS tells them apart (docs/assumptions.md FIT4).

    Parameters
    ----------
    t_g : numpy.ndarray
        GNSS times, s.
    P_g : numpy.ndarray
        GNSS positions, ECEF, m, (M, 3).
    t_liftoff : float
        Lift-off time, s.

    Returns
    -------
    bool
    """
    sel = t_g <= t_liftoff
    if sel.sum() < 3:
        return True
    x = t_g[sel] - t_g[sel].mean()
    slope, offset = np.polyfit(x, P_g[sel], 1)
    noise = float(np.sqrt(np.mean((P_g[sel] - offset - np.outer(x, slope)) ** 2)))
    limit = PAD_GNSS_SPEED_MPS + 3.0 * noise * np.sqrt(3.0 / np.sum(x**2))
    return bool(np.linalg.norm(slope) <= limit)


def pad_start(t, imu, P0, t_start, tolerance) -> float:
    """Where a fit starts: ``t_start`` (the records' common span), or the first IMU sample
    when the record stands on a pad (:func:`find_liftoff`) until after ``t_start``. On the
    pad the vehicle is where the first fix says, so the IMU before it is kept
    (docs/assumptions.md FIT4): fixes moved back by a GNSS lag (FIT6) no longer reach the
    first samples, and the pad must not be lost with them.

    Parameters
    ----------
    t : numpy.ndarray
        IMU times, s.
    imu : numpy.ndarray
        Specific force and angular rate, (N, 6): ``f_x, f_y, f_z`` (m/s^2), ``w_x, w_y,
        w_z`` (rad/s).
    P0 : numpy.ndarray
        ECEF position of the first fix, m (sets local gravity).
    t_start : float
        Start of the common span, s.
    tolerance : float
        Levelling tolerance, a fraction of gravity (:func:`find_liftoff`).

    Returns
    -------
    float
    """
    if t[0] >= t_start:
        return t_start
    g = float(np.linalg.norm(earth.normal_gravity_ecef(P0)))
    pad = find_liftoff(t, imu[:, :3], imu[:, 3:], g, tolerance)
    return float(t[0]) if pad is not None and pad[0] > t_start else t_start
