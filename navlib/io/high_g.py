"""A second, high-g accelerometer along body x standing in for clipped ``f_x`` samples.

Altus Metrum boards (TeleMega, EasyMega) carry, beside the IMU whose accelerometer AltOS
sets to +-16 g, a single-axis high-g accelerometer along the rocket's axis; the export's
``acceleration`` column holds it (m/s^2, its pad reading removed). A boost beyond 16 g
clips the IMU's ``f_x`` for as long as it lasts; dropped, a clip of more than
``max_bridge_s`` splits the record at lift-off and the boost is never assessed. Where the
IMU clips and the high-g reading is steady, the high-g reading, calibrated against the
unclipped ``f_x`` of the same flight, stands in (docs/assumptions.md Q1; the thresholds are
``data/quality.toml`` ``[saturation] high_g_*``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError

__all__ = ["HighGStandIn", "high_g_stand_in"]

SCALE_BOUNDS = (0.8, 1.25)
"""Plausible calibration scales (IMU ``f_x`` per high-g unit): two MEMS accelerometers'
sensitivities within +-10 % each, and the sign of the same axis."""


@dataclass(frozen=True)
class HighGStandIn:
    """Result of :func:`high_g_stand_in`.

    Attributes
    ----------
    f_x : ndarray (N,)
        ``f_x`` with the stood-in samples replaced (the record's otherwise).
    filled : ndarray of bool (N,)
        The clipped samples the high-g reading stands in for.
    note : str
        The calibration, when some samples were filled (``"taken from ..."``).
    refusal : str
        Why the clipped samples not filled were not (empty when all were, or when the
        record has no high-g reading).
    calibration : dict
        ``scale``, ``offset`` (m/s^2), ``rms`` (m/s^2), ``n`` (samples) when calibrated.
    """

    f_x: np.ndarray
    filled: np.ndarray
    note: str = ""
    refusal: str = ""
    calibration: dict = field(default_factory=dict)


def _matched(imu: pd.DataFrame, high_g) -> np.ndarray:
    """The high-g reading at each IMU sample's time (NaN where it has none)."""
    if not isinstance(high_g, pd.DataFrame) or not {"t", "f_x"} <= set(high_g.columns):
        raise NavlibInputError("imu.attrs['high_g']: expected a DataFrame with columns t, f_x "
                               f"(the high-g accelerometer along body x), got {high_g!r}")
    t_h = high_g["t"].to_numpy(dtype=float)
    f_h = high_g["f_x"].to_numpy(dtype=float)
    t = imu["t"].to_numpy(dtype=float)
    k = np.clip(np.searchsorted(t_h, t), 0, max(t_h.size - 1, 0))
    out = np.full(t.size, np.nan)
    if t_h.size:
        same = np.abs(t_h[k] - t) < 1e-9
        out[same] = f_h[k[same]]
    return out


def _steady(x: np.ndarray, window: int, tolerance: float) -> np.ndarray:
    """Samples within ``tolerance`` of the median of the ``window`` samples about them (the
    finite ones; a missing reading is not steady)."""
    median = pd.Series(x).rolling(window, center=True, min_periods=1).median().to_numpy()
    return np.isfinite(x) & (np.abs(x - median) <= tolerance)


def _held_extreme(h: np.ndarray, run: int) -> np.ndarray:
    """Samples in runs of at least ``run`` consecutive readings at ``h``'s largest or at its
    smallest value (each end separately: with the pad reading removed, the sensor's two
    limits lie at different distances from zero)."""
    finite = np.isfinite(h)
    if not finite.any():
        return np.zeros(h.size, dtype=bool)
    at = finite & ((h == np.nanmax(h)) | (h == np.nanmin(h)))
    edges = np.flatnonzero(np.diff(np.r_[0, at.astype(np.int8), 0]))
    out = np.zeros(h.size, dtype=bool)
    for start, end in zip(edges[::2], edges[1::2], strict=True):
        out[start:end] = end - start >= run
    return out


def _line(h: np.ndarray, f: np.ndarray, rounds: int = 3):
    """Straight line ``f = scale h + offset`` by least squares, leaving out the samples
    beyond 4 robust sigmas (1.4826 MAD, at least the high-g's step) of the previous round."""
    use = np.ones(h.size, dtype=bool)
    levels = np.unique(h)
    step = float(np.min(np.diff(levels))) if levels.size > 1 else 0.0
    for _ in range(rounds):
        scale, offset = np.polyfit(h[use], f[use], 1)
        res = f - (scale * h + offset)
        sigma = 1.4826 * float(np.median(np.abs(res[use])))
        use &= np.abs(res) <= max(4.0 * sigma, step)
    return float(scale), float(offset), float(np.sqrt(np.mean(res[use] ** 2))), use


def high_g_stand_in(imu: pd.DataFrame, clipped: np.ndarray, limit: float,
                    p: dict) -> HighGStandIn:
    """Stand the high-g reading ``imu.attrs["high_g"]`` in for the clipped ``f_x`` samples.

    Parameters
    ----------
    imu : DataFrame
        ``t, f_x, ...``; ``attrs["high_g"]`` (``t, f_x``: the high-g accelerometer along body
        x, m/s^2, any offset) when the board has one.
    clipped : ndarray of bool (N,)
        ``f_x`` samples at the range limit.
    limit : float
        The ``f_x`` range, m/s^2.
    p : dict
        The ``[saturation]`` thresholds (``high_g_window_samples``, ``high_g_steady_mps2``,
        ``high_g_min_fraction``, ``high_g_min_samples``, ``high_g_min_span_mps2``,
        ``high_g_agreement``, ``high_g_clip_run_samples``).

    Returns
    -------
    HighGStandIn
        Calibrated on the unclipped samples where both accelerometers are steady and
        ``|f_x|`` is at least ``high_g_min_fraction`` of the range (the thrust's regime, not
        the pad's offset) when there are ``high_g_min_samples`` of them, else on all the
        steady ones (the line extrapolated); at least ``high_g_min_samples`` spanning
        ``high_g_min_span_mps2`` and a scale within :data:`SCALE_BOUNDS`, or none is filled
        and ``refusal`` says why. A clipped sample is filled when the high-g reading is steady
        there, not at its own extreme held for ``high_g_clip_run_samples`` samples in a row (it
        clipped too; a quantised peak repeats its top step only briefly), and calibrated to
        at least ``1 - high_g_agreement`` of the range (the IMU says at least its clipped
        reading, so the filled value is never less than that reading).
    """
    f_x = imu["f_x"].to_numpy(dtype=float).copy()
    none = np.zeros(f_x.size, dtype=bool)
    high_g = imu.attrs.get("high_g")
    if high_g is None or not clipped.any():
        return HighGStandIn(f_x, none)
    h = _matched(imu, high_g)
    window = int(p["high_g_window_samples"]) | 1
    h_steady = _steady(h, window, p["high_g_steady_mps2"])
    usable = h_steady & _steady(f_x, window, p["high_g_steady_mps2"]) & ~clipped
    thrust = usable & (np.abs(f_x) >= p["high_g_min_fraction"] * limit)
    n_min = int(p["high_g_min_samples"])
    if thrust.sum() >= n_min:
        usable = thrust
    why = "the high-g accelerometer along x (the export's `acceleration`) not used: "
    span = float(np.ptp(f_x[usable])) if usable.any() else 0.0
    if usable.sum() < n_min or span < p["high_g_min_span_mps2"]:
        return HighGStandIn(f_x, none, refusal=why + (
            f"{usable.sum()} steady unclipped samples spanning {span:.3g} m/s^2 to "
            f"calibrate it on (at least {n_min} spanning {p['high_g_min_span_mps2']:g} needed)"))
    scale, offset, rms, used = _line(h[usable], f_x[usable])
    if not SCALE_BOUNDS[0] <= scale <= SCALE_BOUNDS[1]:
        return HighGStandIn(f_x, none, refusal=why + (
            f"its calibration scale {scale:.3g} is outside {SCALE_BOUNDS[0]:g}-"
            f"{SCALE_BOUNDS[1]:g} (not the same axis)"))
    calibrated = scale * h + offset
    own_clip = _held_extreme(h, int(p["high_g_clip_run_samples"]))
    sign = np.sign(f_x)
    agrees = sign * calibrated >= (1.0 - p["high_g_agreement"]) * limit
    filled = clipped & h_steady & ~own_clip & agrees
    cal = {"scale": scale, "offset": offset, "rms": rms, "n": int(used.sum())}
    lo, hi = f_x[usable][used].min(), f_x[usable][used].max()    # before any sample is filled
    f_x[filled] = sign[filled] * np.maximum(sign[filled] * calibrated[filled],
                                            np.abs(f_x[filled]))
    regime = "" if usable is thrust else (
        f" (fewer than {n_min} in the thrust's regime: the line is extrapolated)")
    note = (f"taken from the high-g accelerometer along x (the export's `acceleration`), "
            f"calibrated on {cal['n']} steady unclipped samples of f_x {lo:.3g} to {hi:.3g} "
            f"m/s^2{regime}: f_x = {scale:.4g} a {'+' if offset >= 0 else '-'} "
            f"{abs(offset):.3g} m/s^2, {rms:.2g} m/s^2 RMS")
    refusal = "" if filled.sum() == clipped.sum() else (
        f"{why}there it is unsteady (a shock), at its own extreme or calibrated below "
        f"{1.0 - p['high_g_agreement']:g} of the range")
    return HighGStandIn(f_x, filled, note if filled.any() else "", refusal, cal)
