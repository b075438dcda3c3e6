"""The high-g accelerometer standing in for clipped IMU ``f_x`` samples (navlib.io.high_g,
navlib.io.quality, data/quality.toml [saturation] high_g_*; assumption Q1).

Synthetic Altus Metrum-like records at 100 Hz: a pad at +9.8 m/s^2 along x, a boost whose
``f_x`` rises through 4-16 g to a plateau beyond the IMU's 16 g (156.9 m/s^2) and tails off,
then a coast near -15 m/s^2. The IMU reads the truth plus 0.3 m/s^2 noise, clipped to the
range; the high-g reads ``(f_true - offset) / scale`` plus 0.5 m/s^2 noise in 0.53 m/s^2 steps
(a TeleMega's), so ``f_true = scale * a + offset``.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from navlib.io.findings import load_thresholds
from navlib.io.high_g import SCALE_BOUNDS
from navlib.io.quality import along_axis_stand_in, check_records
from navlib.units import DEG

P = load_thresholds()["saturation"]
LIMIT = 16 * 9.80665
STEP = 0.53
RANGE = {"gyro_rad_s": 2000.0 * DEG, "accel_m_s2": LIMIT}
# pad, rise to the plateau, plateau (clipped), tail-off, coast: (duration s, f_x at its end)
BOOST = ((2.0, 9.8), (0.5, 200.0), (1.2, 200.0), (0.5, -15.0), (5.0, -15.0))


def _flight(scale=1.03, offset=9.8, seed=0, knots=BOOST):
    """IMU record (``attrs`` range and high-g) and the true ``f_x`` on ``knots``."""
    rng = np.random.default_rng(seed)
    t_k = np.cumsum([0.0, *(d for d, _ in knots)])
    t = np.round(np.arange(0.0, t_k[-1], 0.01), 9)
    f = np.interp(t, t_k, [knots[0][1], *(v for _, v in knots)])
    n = t.size
    imu = pd.DataFrame({"t": t, "f_x": np.clip(f + rng.normal(0, 0.3, n), -LIMIT, LIMIT),
                        **{c: rng.normal(0, 0.3, n) for c in ("f_y", "f_z")},
                        **{c: rng.normal(0, 0.01, n) for c in ("w_x", "w_y", "w_z")}})
    a = STEP * np.round(((f - offset) / scale + rng.normal(0, 0.5, n)) / STEP)
    imu.attrs = {"range": dict(RANGE), "high_g": pd.DataFrame({"t": t, "f_x": a})}
    return imu, f


def _with_high_g(imu, a):
    out = imu.copy()
    out.attrs = {**imu.attrs, "high_g": pd.DataFrame({"t": imu["t"], "f_x": a})}
    return out


def _clipped(imu):
    return np.abs(imu["f_x"].to_numpy()) >= LIMIT * (1.0 - P["limit_tolerance"])


def test_calibration_recovers_scale_and_offset_and_fills_the_clip():
    """Known scale 1.03 and offset 9.8 are recovered and every clipped sample is filled with
    the truth. Residual about the line: 0.3 (IMU) + 0.5 * 1.03 (high-g) + 0.53 / sqrt(12)
    (quantisation), ~0.6 m/s^2 RMS; ~58 samples over 40-153 m/s^2 (std ~33) give a scale
    error of ~0.25 % and an offset error of ~0.2 m/s^2, so 1 % and 1 m/s^2 are 4-5 sigma. A
    filled sample adds its own high-g noise and step (~0.6 m/s^2): 3 m/s^2 is ~5 sigma."""
    imu, f = _flight()
    clipped = _clipped(imu)
    got = along_axis_stand_in(imu, None, P)
    assert clipped.sum() > 100
    assert got.calibration["scale"] == pytest.approx(1.03, rel=0.01)
    assert got.calibration["offset"] == pytest.approx(9.8, abs=1.0)
    assert np.array_equal(got.filled, clipped) and got.refusal == ""
    assert np.abs(got.f_x[clipped] - f[clipped]).max() < 3.0
    assert (got.f_x[clipped] >= LIMIT * (1.0 - P["limit_tolerance"])).all()
    assert (got.f_x[clipped] >= imu["f_x"].to_numpy()[clipped]).all()   # never below the IMU
    assert np.mean(got.f_x[clipped] >= LIMIT) > 0.95
    assert got.note.startswith("taken from the high-g accelerometer along x")
    assert "f_x = 1.0" in got.note


@settings(max_examples=25, deadline=None)
@given(st.floats(0.9, 1.1), st.floats(-15.0, 15.0), st.integers(0, 2**32 - 1))
@example(0.9649544136483706, -1.90625, 3665372485)      # one corner sample left (CI run)
def test_any_calibration_is_recovered_and_only_clipped_samples_change(scale, offset, seed):
    """Whatever the high-g's scale (0.9-1.1) and offset (+-15 m/s^2) and the noise, the scale
    is recovered within 1 % (~4 sigma, test above), the clipped samples are filled at no less
    than the IMU read (the range, within its tolerance), and no other sample changes. Rarely
    (none in 400 random draws; the example above) a reading at the corner where the 4 m/s^2
    per sample ramp meets the plateau lies more than 3 m/s^2 from its 9-sample median: by
    the rule it is not steady, so it is left to be dropped; at most two such samples."""
    imu, _ = _flight(scale, offset, seed)
    clipped = _clipped(imu)
    got = along_axis_stand_in(imu, None, P)
    assert got.calibration["scale"] == pytest.approx(scale, rel=0.01)
    assert not (got.filled & ~clipped).any() and (clipped & ~got.filled).sum() <= 2
    assert got.refusal == "" or "unsteady" in got.refusal
    f_x = imu["f_x"].to_numpy()
    assert np.array_equal(got.f_x[~got.filled], f_x[~got.filled])
    assert (got.f_x[got.filled] >= np.maximum(f_x[got.filled],
                                              LIMIT * (1.0 - P["limit_tolerance"]))).all()


def test_a_shock_in_one_sample_is_not_filled():
    """A clipped IMU sample in the coast where the high-g spikes in that sample only (a
    shock, calibrated ~250 m/s^2: beyond the range, but not steady) keeps its IMU value and
    the refusal says why; the boost is still filled."""
    imu, _ = _flight()
    assert along_axis_stand_in(imu, None, P).refusal == ""
    k = int(np.searchsorted(imu["t"], 6.5))
    imu.loc[k, "f_x"] = LIMIT
    a = imu.attrs["high_g"]["f_x"].to_numpy().copy()
    a[k] += 265.0 / 1.03
    shocked = _with_high_g(imu, a)
    got = along_axis_stand_in(shocked, None, P)
    clipped = _clipped(shocked)
    assert clipped[k] and not got.filled[k] and got.f_x[k] == LIMIT
    assert np.array_equal(got.filled, clipped & (np.arange(clipped.size) != k))
    assert "not used: there it is unsteady (a shock)" in got.refusal


@pytest.mark.parametrize("pad_s, count", [(0.15, True), (5.0, False)])
def test_too_little_to_calibrate_on_fills_nothing(pad_s, count):
    """Pad then straight into a clip to the end: 16 pad samples are too few; 501 span only
    the pad's noise (< 19.6 m/s^2). Nothing filled; the refusal gives count and span."""
    imu, _ = _flight(knots=((pad_s, 9.8), (0.01, 200.0), (1.5, 200.0)))
    clipped = _clipped(imu)
    got = along_axis_stand_in(imu, None, P)
    assert clipped.any() and not got.filled.any()
    assert np.array_equal(got.f_x, imu["f_x"].to_numpy()) and got.calibration == {}
    m = re.search(r"(\d+) steady unclipped samples spanning ([\d.]+) m/s\^2 to calibrate it "
                  r"on \(at least 20 spanning 19.6 needed\)", got.refusal)
    assert m is not None, got.refusal
    assert int(m.group(1)) == (~clipped).sum()
    assert (int(m.group(1)) < 20) == count
    assert float(m.group(2)) < 5.0


@pytest.mark.parametrize("case", ["negated", "in g", "another axis"])
def test_a_high_g_not_along_f_x_is_refused(case):
    """A high-g reading with its sign reversed (scale ~-1.03), in g instead of m/s^2 (~10)
    or a lateral axis's vibration (noise: a scale far from 1) fills nothing, and the refusal
    gives the scale outside the bounds."""
    imu, _ = _flight()
    a = imu.attrs["high_g"]["f_x"].to_numpy()
    noise = STEP * np.round(np.random.default_rng(1000).normal(0.0, 1.0, a.size) / STEP)
    a = {"negated": -a, "in g": a / 9.80665, "another axis": noise}[case]
    got = along_axis_stand_in(_with_high_g(imu, a), None, P)
    assert not got.filled.any() and np.array_equal(got.f_x, imu["f_x"].to_numpy())
    m = re.search(r"its calibration scale (\S+) is outside 0.8-1.25 \(not the same axis\)",
                  got.refusal)
    assert m is not None, got.refusal
    scale = float(m.group(1))
    assert not SCALE_BOUNDS[0] <= scale <= SCALE_BOUNDS[1]
    expected = {"negated": -1.03, "in g": 1.03 * 9.80665}.get(case)
    if expected is not None:
        assert scale == pytest.approx(expected, rel=0.02)


def _high_g_clipped_at_180(imu):
    """The record's high-g clipped at 180 m/s^2 (calibrated): its top step held there."""
    a = imu.attrs["high_g"]["f_x"].to_numpy()
    top = STEP * np.floor((180.0 - 9.8) / 1.03 / STEP)
    return np.minimum(a, top), top


def test_a_high_g_at_its_own_limit_is_not_filled():
    """Where the truth (200 m/s^2) is beyond the high-g's own 180, it holds its top step and
    those samples are not filled (the IMU's value is kept); where the truth is 160-175 on the
    ramps they are."""
    imu, f = _flight()
    a, _ = _high_g_clipped_at_180(imu)
    got = along_axis_stand_in(_with_high_g(imu, a), None, P)
    clipped = _clipped(imu)
    assert not got.filled[f >= 185.0].any() and (f >= 185.0).sum() > 100
    assert np.array_equal(got.f_x[f >= 185.0], imu["f_x"].to_numpy()[f >= 185.0])
    assert got.filled[clipped & (f >= 160.0) & (f <= 175.0)].all()
    assert "at its own extreme" in got.refusal


def test_a_high_g_at_its_own_limit_is_not_filled_beside_a_negative_shock():
    """As above, plus a 3-sample shock in the coast at the high-g's negative limit (raw range
    symmetric; with the pad reading removed it lies 2 * 9.8 / 1.03 farther from zero)."""
    imu, f = _flight()
    a, top = _high_g_clipped_at_180(imu)
    k = int(np.searchsorted(imu["t"], 6.0))
    a[k:k + 3] = -top - 2.0 * 9.8 / 1.03
    got = along_axis_stand_in(_with_high_g(imu, a), None, P)
    assert not got.filled[f >= 185.0].any()


def test_check_records_keeps_the_boost_it_would_otherwise_drop():
    """A 34 s record whose boost clips for ~1.4 s (4.2 % of it): with the high-g every sample
    is kept, the finding says where f_x came from and the returned f_x is the truth; without
    it, the clipped samples are dropped (and only they)."""
    imu, f = _flight(knots=(*BOOST[:-1], (30.0, -15.0)))
    t = imu["t"].to_numpy()
    v = np.cumsum(np.where(t > 2.0, f - 9.80665, 0.0)) * 0.01
    rng = np.random.default_rng(5)
    k = np.arange(0, t.size, 10)
    gnss = pd.DataFrame({"t": t[k], "x": rng.normal(0, 1, k.size),
                         "y": rng.normal(0, 1, k.size),
                         "z": (np.cumsum(v) * 0.01)[k] + rng.normal(0, 1, k.size)})
    clipped = _clipped(imu)
    assert (clipped.sum() > 120) and (np.ptp(t[clipped]) > 1.0)
    with_ = check_records(imu, gnss, None, 5.0)
    bare = imu.copy()
    bare.attrs = {"range": dict(RANGE)}
    without = check_records(bare, gnss, None, 5.0)

    assert len(with_.imu) == len(imu) and np.array_equal(with_.imu["t"], t)
    row = with_.findings.set_index("check").loc["high-g"]
    assert row["channel"] == "f_x" and row["n"] == clipped.sum()
    assert "taken from the high-g accelerometer" in row["message"]
    assert "saturation" not in set(with_.findings["check"])
    assert np.abs(with_.imu["f_x"].to_numpy()[clipped] - f[clipped]).max() < 3.0
    assert np.array_equal(with_.imu["f_x"].to_numpy()[~clipped], imu["f_x"][~clipped])
    assert with_.imu.attrs["high_g"] is not None

    assert np.array_equal(without.imu["t"], t[~clipped])
    assert "high-g" not in set(without.findings["check"])
    found = without.findings.set_index("check").loc["saturation"]
    assert found["channel"] == "f_x" and found["n"] == clipped.sum()
    assert "dropped, the fit bridges them" in found["message"]


def test_no_stand_in_without_a_known_range_or_a_high_g():
    """None without a range (log or preset: a flat top is no limit to check against) or
    without ``attrs["high_g"]``; a stand-in with both."""
    imu, _ = _flight()
    assert along_axis_stand_in(imu, None, P) is not None
    unknown = imu.copy()
    unknown.attrs = {**imu.attrs, "range": {"gyro_rad_s": None, "accel_m_s2": None}}
    assert along_axis_stand_in(unknown, None, P) is None
    bare = imu.copy()
    bare.attrs = {"range": dict(RANGE)}
    assert along_axis_stand_in(bare, None, P) is None
