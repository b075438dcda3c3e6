"""Lift-off found from the records, so the fitted reference can stand still on the pad.

:func:`find_liftoff` reads the recorded specific force only (never the fit): a vehicle on
the pad feels gravity and nothing else; a powered lift-off adds a sustained thrust
acceleration (docs/assumptions.md FIT4). :func:`navlib.trajectory.fit_flight_data` then holds
the reference still (zero velocity, constant attitude) from the first sample until that
time, takes the pad's last fix before the record there (:func:`pad_fix_times`), and gives the
position spline dense knots at lift-off (:func:`liftoff_knots`) and wherever the thrust
changes abruptly (:func:`thrust_change_knots`).
"""

import numpy as np

from navlib import earth
from navlib.trajectory.position_spline import SAMPLES_PER_KNOT, SPLINE_DEGREE
from navlib.units import DEG

__all__ = [
    "LIFTOFF_ACCEL_MPS2",
    "LIFTOFF_HOLD_S",
    "LIFTOFF_KNOTS_S",
    "LIFTOFF_SMOOTH_S",
    "MIN_PAD_SAMPLES",
    "PAD_ACCEL_MPS2",
    "PAD_FIX_BEFORE_S",
    "PAD_GNSS_SPEED_MPS",
    "PAD_RATE_DEG_S",
    "PAD_SCALE_TOLERANCE",
    "THRUST_CHANGE_MPS2",
    "THRUST_CHANGE_S",
    "find_liftoff",
    "gnss_still",
    "liftoff_knots",
    "moving_average",
    "pad_and_fixes",
    "pad_fix_times",
    "pad_start",
    "thrust_change_knots",
]

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
PAD_SCALE_TOLERANCE = 0.1
"""Largest relative difference between a pad's ``|f|`` reading and gravity, when the
levelling tolerance is smaller: three times a consumer MEMS accelerometer's +-3 %
sensitivity tolerance, so a board whose along axis reads 9.1 m/s^2 at rest still stands on a
pad."""
PAD_RATE_DEG_S = 3.0
"""Largest mean angular rate on the pad, deg/s (the segmentation's rest rate)."""
MIN_PAD_SAMPLES = 3
PAD_GNSS_SPEED_MPS = 0.5
"""Largest speed of the straight line through the fixes before lift-off, m/s (the
segmentation's rest acceleration scale: a pad does not travel)."""
PAD_FIX_BEFORE_S = 2.0
"""How long before a record's first sample a fix may be stamped and still be taken as the
pad's position when the record starts on the pad, s (:func:`pad_fix_times`): a flight
computer keeps a short pre-launch buffer (0.3 s in AltOS exports) whose first row carries the
last fix before it, and a GNSS lag moves the fixes back by up to
:data:`navlib.trajectory.gnss_lag.MAX_GNSS_LAG_S`."""
LIFTOFF_KNOTS_S = 0.4
"""Span after lift-off with knots every ``SAMPLES_PER_KNOT`` samples, s: twice
``LIFTOFF_HOLD_S``, time for the thrust to build up."""
THRUST_CHANGE_MPS2 = 20.0
"""Change of the specific force averaged over ``LIFTOFF_HOLD_S`` that marks an abrupt, lasting
change of thrust (a burnout, a staging; :func:`thrust_change_knots`), m/s^2: 2 g, ten times
the lift-off threshold, so motor vibration does not reach it."""
THRUST_CHANGE_S = 0.1
"""Half-width of the stretch with dense knots about an abrupt change of thrust, s: the spread
of a burnout's tail-off (:func:`thrust_change_knots`)."""


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
    the pad's own reading (the median averaged ``|f|`` before the onset: an accelerometer
    whose scale or offset is off reads gravity a few percent off, steadily). The samples
    before must be a pad: at least ``MIN_PAD_SAMPLES``, that reading within the larger of
    ``tolerance * g`` (the levelling tolerance) and ``PAD_SCALE_TOLERANCE * g`` of gravity,
    and their mean rate below ``PAD_RATE_DEG_S``. Returns ``(t_liftoff, index)``: the pad is
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
    if onset < MIN_PAD_SAMPLES:
        return None
    reading = float(np.median(a[:onset]))
    calm = np.flatnonzero(np.abs(a[:onset] - reading) <= PAD_ACCEL_MPS2)
    if calm.size == 0:
        return None
    k = int(calm[-1])
    if k + 1 < MIN_PAD_SAMPLES:
        return None
    norm = np.linalg.norm(f_b[:k + 1], axis=1)
    rate = np.linalg.norm(np.mean(w_b[:k + 1], axis=0))
    if (abs(np.median(norm) - g) > max(tolerance, PAD_SCALE_TOLERANCE) * g
            or rate > PAD_RATE_DEG_S * DEG):
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


def _step(t, f_avg, gap):
    """Norm of the change of the averaged specific force from ``gap`` before to ``gap``
    after each sample, m/s^2."""
    return np.linalg.norm(np.column_stack([np.interp(t + gap, t, f_avg[:, i])
                                           - np.interp(t - gap, t, f_avg[:, i])
                                           for i in range(3)]), axis=1)


def thrust_change_knots(knots, t, f_b, resolved, keep_out=None):
    """``knots`` with knots every ``SAMPLES_PER_KNOT`` samples where the thrust changes
    abruptly and stays changed (docs/assumptions.md FIT4): a burnout turns a rocket's specific
    force from several g forward to a drag backward within a tenth of a second, which a 0.1 s
    knot interval of the quintic position spline cannot follow; the misfit it leaves has the
    same sign at every burnout and is otherwise taken up by the accelerometer scale the fit
    estimates, bending the whole ascent.

    The specific force is averaged over ``LIFTOFF_HOLD_S``; a sample is marked where that
    average changes by more than ``THRUST_CHANGE_MPS2`` from ``THRUST_CHANGE_S +
    LIFTOFF_HOLD_S / 2`` before to as long after it, and again over twice those spans (a
    change that lasts: an ejection charge's shock of a few hundredths of a second is none).
    Only samples whose rotation the sample rate resolves are marked (a tumbling burst shakes
    the average as much, and inside a GNSS gap dense knots would let the spline swing). The
    samples within ``THRUST_CHANGE_S`` of a marked one get dense knots, replacing those of
    ``knots``. A record sampled too sparsely for denser knots keeps its own.

    Parameters
    ----------
    knots : numpy.ndarray
        Knot vector.
    t : numpy.ndarray
        Sample times, s.
    f_b : numpy.ndarray
        Specific force, m/s^2, (N, 3).
    resolved : numpy.ndarray of bool
        Samples whose rotation is resolved
        (:func:`navlib.trajectory.position_spline.resolved_samples`).
    keep_out : tuple of float, optional
        A time span whose knots stay as they are (the lift-off's, :func:`liftoff_knots`), s.

    Returns
    -------
    numpy.ndarray
    """
    f_avg = moving_average(t, f_b, LIFTOFF_HOLD_S)
    gap = THRUST_CHANGE_S + 0.5 * LIFTOFF_HOLD_S
    marked = (_step(t, f_avg, gap) > THRUST_CHANGE_MPS2) & (
        _step(t, f_avg, 2.0 * gap) > THRUST_CHANGE_MPS2) & resolved
    margin = SAMPLES_PER_KNOT
    near = np.zeros(t.size + 1, dtype=int)
    np.add.at(near, np.searchsorted(t, t[marked] - THRUST_CHANGE_S), 1)
    np.add.at(near, np.searchsorted(t, t[marked] + THRUST_CHANGE_S, side="right"), -1)
    near = np.cumsum(near[:-1]) > 0
    near[:margin] = near[t.size - margin:] = False
    if keep_out is not None:
        lo, hi = np.searchsorted(t, keep_out[0]), np.searchsorted(t, keep_out[1], side="right")
        near[max(lo - margin, 0):hi + margin] = False
    idx = np.flatnonzero(near)
    inner = knots[SPLINE_DEGREE + 1:-SPLINE_DEGREE - 1]
    dense = []
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []:
        span = (t[run[0] - margin], t[run[-1] + margin])
        stretch = t[run[::SAMPLES_PER_KNOT]]
        if stretch.size <= np.count_nonzero((inner > span[0]) & (inner < span[1])):
            continue                     # no denser than the knots already there
        inner = inner[(inner < span[0]) | (inner > span[1])]
        dense.append(stretch)
    if not dense:
        return knots
    return np.r_[knots[:SPLINE_DEGREE + 1], np.sort(np.r_[inner, *dense]),
                 knots[-SPLINE_DEGREE - 1:]]


def pad_fix_times(t_g, t_first, on_pad: bool) -> np.ndarray:
    """Fix times with the last fix stamped up to :data:`PAD_FIX_BEFORE_S` before the record's
    first sample moved to that sample, when the record starts on a pad (docs/assumptions.md
    FIT4): the vehicle stood still there before the record began, so that fix is the pad's
    position. Earlier fixes of that span (older fixes of the same pad), and all of them when a
    fix already lies at the first sample, become NaN: outside every span. Without a pad, or
    for fixes stamped earlier, the times are unchanged.

    Parameters
    ----------
    t_g : numpy.ndarray
        Fix times, s, increasing.
    t_first : float
        The record's first sample, s.
    on_pad : bool
        Whether the record starts on a pad (:func:`find_liftoff`).

    Returns
    -------
    numpy.ndarray
    """
    t_g = np.asarray(t_g, dtype=float)
    early = np.flatnonzero((t_g < t_first) & (t_g >= t_first - PAD_FIX_BEFORE_S))
    if not on_pad or early.size == 0:
        return t_g
    out = t_g.copy()
    out[early] = np.nan
    if not np.any(t_g == t_first):
        out[early[-1]] = t_first
    return out


def pad_and_fixes(t, f_b, w_b, t_stamp, P_g, tolerance, hold: bool = True):
    """The pad of a record (:func:`find_liftoff`; None without one, when ``hold`` is False,
    or when the fixes before lift-off move: a hover, :func:`gnss_still`), the fix times
    (:func:`pad_fix_times`) and which fixes lie inside the record.

    Parameters
    ----------
    t : numpy.ndarray
        IMU times, s.
    f_b, w_b : numpy.ndarray
        Specific force (m/s^2) and angular rate (rad/s), (N, 3).
    t_stamp : numpy.ndarray
        Fix times as given, s.
    P_g : numpy.ndarray
        ECEF fix positions, m, (M, 3); the first sets local gravity.
    tolerance : float
        Levelling tolerance, a fraction of gravity.
    hold : bool, optional
        Whether a pad is looked for (the fit's ``hold_pad``).

    Returns
    -------
    pad : tuple or None
    t_fix : numpy.ndarray
    inside : numpy.ndarray of bool
    """
    t_stamp = np.asarray(t_stamp, dtype=float)
    pad = None
    if hold:
        g = float(np.linalg.norm(earth.normal_gravity_ecef(P_g[0])))
        pad = find_liftoff(t, f_b, w_b, g, tolerance)
    t_fix = pad_fix_times(t_stamp, t[0], pad is not None)
    if pad is not None:
        inside = (t_fix >= t[0]) & (t_fix <= t[-1])
        if not gnss_still(t_fix[inside], P_g[inside], pad[0]):
            pad, t_fix = None, t_stamp
    return pad, t_fix, (t_fix >= t[0]) & (t_fix <= t[-1])


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
