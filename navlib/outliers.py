"""Outlier injection and recovery scoring (Beaudoin et al. 2018 §3.2, §4.2; spec launcher.md §6.4).

An :class:`Outlier` is a deterministic error added to one sensor channel at a chosen time,
magnitude and shape. The same object drives both filter modes of :mod:`navlib.filters`:

* **EKF mode** (:func:`navlib.filters.ekf`): :func:`inject` adds the outlier to the simulated
  sensor data themselves (GNSS fixes, IMU samples, attitude-sensor or reference-trajectory
  attitudes) before the filter sees them.
* **linear mode** (:func:`navlib.filters.simulate_linear`): the outlier is mapped onto the
  error model (:func:`linear_mapping`). A measurement outlier is added to the matching row
  of the error measurement ``z = H x + v`` with the sign of that row's convention. An IMU
  outlier is a *known additive input on the matching noise channel*: a gyro error
  ``delta_omega`` (measured minus true, rad/s, body axis) enters the launcher model through
  its noise column ``-T_B^E`` (``d psi/dt = ... - T_B^E delta_omega``, Beaudoin eq. 1), so a
  0.002 rad/s roll-gyro outlier held over one 5 ms step adds ``-T_B^E [1e-5, 0, 0]'`` rad to
  the ECEF attitude error; an accelerometer error enters ``dv`` through ``+T_B^E``. The
  mapping sign is the sign of the noise column relative to the matching bias column
  (:data:`LINEAR_NAMES`), checked in ``tests/studies/test_outliers.py``.

Channels (:data:`CHANNELS`) — one vocabulary for both modes:

==================  =============================================  =========
channel             meaning                                        unit
==================  =============================================  =========
``gnss_vel_{a}``    GNSS velocity, ECEF axis a                     m/s
``gnss_pos_{a}``    GNSS position, ECEF axis a                     m
``gyro_{a}``        gyro rate, body axis a (x = roll)              rad/s
``accel_{a}``       accelerometer specific force, body axis a      m/s^2
``att_{a}``         attitude sensor, rotation about ECEF axis a    rad
``rt_{a}``          reference-trajectory attitude, body axis a     rad
==================  =============================================  =========

``gnss_vel``, ``gnss_pos``, ``gyro``, ``accel``, ``att``, ``rt`` (no axis) name all three
axes at once (the paper's T1 adds 3 m/s "on the 3 velocity components").

Shapes (spec §6.4 ambiguity "spike or step"): ``"spike"`` — the single sample (or
measurement epoch) nearest the outlier time; ``"step"`` — every sample from then on;
``"pulse"`` — a step of given ``duration``.

Recovery score (:func:`score_recovery`; the numeric verdict the paper lacks). For a watched
scalar (or vector, scored by its Euclidean norm) let ``d(t)`` be the **outlier-induced
error**: the estimation error of the faulty run minus that of the nominal run with the same
noise. In the linear mode ``d`` is exact and noise-independent (it is the noise-free
response); in the EKF mode it is the difference of two runs with the same seeds. With the
outlier time ``t_o``, the recovery window ``W`` and the averaging length ``Delta``:

* ``peak = max |d(t)|`` over ``[t_o, t_o + W]``;
* ``residual = mean |d(t)|`` over ``[t_o + W - Delta, t_o + W]`` — the error left after
  the recovery window;
* ``retained = residual / peak``;
* ``residual_vs_pre = residual / e_pre`` with ``e_pre`` the RMS nominal estimation error
  over ``[t_o - Delta, t_o)`` (Monte-Carlo RMS, or the filter sigma when no runs are given);
* ``residual_vs_3sigma = residual / (3 sigma(t_o + W))``.

Classification: **"recovers"** when ``retained <= exp(-1)``, i.e. the injected error
decayed by at least one e-folding within the window — equivalently the effective time
constant ``tau = W / ln(1 / retained)`` is at most the window; otherwise **"static
error"**. The threshold is a property of the decay, not of the paper's outcomes: an
observable state corrected by a filter of bandwidth ``1/tau_f`` loses ``1 - exp(-W/tau_f)``
of the injected error, a weakly observable one keeps almost all of it (``tau`` of several
windows). ``recovered_fraction`` changes the threshold. The two ratios say how the left-over
error compares with the error the filter had anyway and with its own 3-sigma: a static error
below ``e_pre`` is invisible in a single noisy run, one above 3 sigma is a filter that is
confidently wrong. A channel the
solution does not have (e.g. ``rt_x`` for INS/GPS) gives ``peak = 0`` and the verdict
``"unaffected"``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError

_AXES = ("x", "y", "z")

KINDS = {
    "gnss_vel": ("GNSS velocity", "m/s", "ECEF"),
    "gnss_pos": ("GNSS position", "m", "ECEF"),
    "gyro": ("gyro rate", "rad/s", "body"),
    "accel": ("accelerometer specific force", "m/s^2", "body"),
    "att": ("attitude sensor", "rad", "ECEF"),
    "rt": ("reference-trajectory attitude", "rad", "body"),
}
"""Channel kinds: description, unit, frame."""

CHANNELS = tuple(f"{kind}_{a}" for kind in KINDS for a in _AXES)
"""All single-axis channel names."""

SHAPES = ("spike", "step", "pulse")

MEASUREMENT_KINDS = ("gnss_vel", "gnss_pos", "att", "rt")
IMU_KINDS = ("gyro", "accel")

LINEAR_NAMES = {
    # measurement channels: (model measurement name, sign of the outlier in z)
    "gnss_vel": (("dv_m_{a}", -1.0),),                    # launcher: z = INS - GNSS
    "gnss_pos": (("dr_m_{a}", -1.0), ("gnss_{a}", 1.0)),  # launcher INS - GNSS; ecef21 GNSS - INS
    "att": (("psi_m_{a}", 1.0),),                         # z = rotvec(C_att C_hat'), ECEF
    "rt": (("psi_ref_m_{a}", 1.0),),                      # z = rotvec(C_hat' C_ref), body
    # IMU channels: (model noise name, sign of the measurement error on that channel)
    "gyro": (("wg_{a}", 1.0), ("gyro_wn_{a}", -1.0)),
    "accel": (("wa_{a}", 1.0), ("acc_wn_{a}", -1.0)),
}
"""How each channel kind maps onto the rows / noise channels of the error models.

Launcher models (Beaudoin eq. 1-5, 8) use ``z = INS - sensor`` for GNSS, so a positive GNSS
outlier lowers ``z``; their gyro/accelerometer noise columns carry the same sign as the
bias columns (``-T_B^E``, ``+T_B^E``), so the measurement error maps with ``+1``. The
21-state ECEF model (España et al. Eq. 24) uses ``z = GNSS - INS`` and noise columns of
opposite sign to its bias columns (``+C`` against ``-C``), hence the ``-1``.
"""


def expand_channel(channel: str) -> tuple[str, ...]:
    """Single-axis channel names of ``channel`` (a kind without axis means all three)."""
    if channel in CHANNELS:
        return (channel,)
    if channel in KINDS:
        return tuple(f"{channel}_{a}" for a in _AXES)
    raise NavlibInputError(
        f"channel: expected one of {list(KINDS)} (all axes) or {list(CHANNELS)}, got "
        f"{channel!r}"
    )


def split_channel(channel: str) -> tuple[str, int]:
    """``"gyro_x"`` -> ``("gyro", 0)``."""
    kind, _, axis = channel.rpartition("_")
    if kind not in KINDS or axis not in _AXES:
        raise NavlibInputError(f"channel: expected a single-axis channel, got {channel!r}")
    return kind, _AXES.index(axis)


@dataclass(frozen=True)
class Outlier:
    """A deterministic error on one sensor channel (spec launcher.md §6.4).

    Attributes
    ----------
    channel : str
        A name of :data:`CHANNELS`, or a kind of :data:`KINDS` for all three axes.
    time : float
        Outlier time, s (the paper: 50 s).
    magnitude : float
        Added value in the channel's SI unit (m/s, m, rad/s, m/s^2, rad).
    shape : {"spike", "step", "pulse"}
        Single sample, from ``time`` on, or for ``duration`` seconds.
    duration : float, optional
        Length of a ``"pulse"``, s.
    """

    channel: str
    time: float
    magnitude: float
    shape: str = "spike"
    duration: float | None = None

    def __post_init__(self):
        expand_channel(self.channel)
        finite_scalar(self.time, "time")
        finite_scalar(self.magnitude, "magnitude")
        if self.shape not in SHAPES:
            raise NavlibInputError(f"shape: expected one of {SHAPES}, got {self.shape!r}")
        if self.shape == "pulse":
            if self.duration is None:
                raise NavlibInputError("duration: a 'pulse' outlier needs a duration, s")
            finite_scalar(self.duration, "duration", 0.0, low_open=True)
        elif self.duration is not None:
            raise NavlibInputError(f"duration: only for shape 'pulse', not {self.shape!r}")

    @property
    def channels(self) -> tuple[str, ...]:
        """The single-axis channels this outlier touches."""
        return expand_channel(self.channel)

    @property
    def kind(self) -> str:
        return split_channel(self.channels[0])[0]

    def profile(self, t) -> np.ndarray:
        """The added value at sample times ``t`` (N,): ``magnitude`` where active, else 0.

        A spike hits the one sample nearest ``time``; a step every sample with
        ``t >= time`` (within half a sample); a pulse those with
        ``time <= t < time + duration``. Times outside the samples give all zeros.
        """
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape)
        if t.size == 0:
            return out
        half = 0.5 * float(np.median(np.diff(t))) if t.size > 1 else 0.0
        if self.shape == "spike":
            k = int(np.argmin(np.abs(t - self.time)))
            if abs(t[k] - self.time) <= max(half, 1e-9):
                out[k] = self.magnitude
            return out
        active = t >= self.time - half * (1.0 - 1e-9)
        if self.shape == "pulse":
            active &= t < self.time + self.duration - half * (1.0 - 1e-9)
        out[active] = self.magnitude
        return out

    def label(self) -> str:
        """Short text, e.g. ``"gyro_x +0.002 rad/s spike at 50 s"``."""
        unit = KINDS[self.kind][1]
        extra = f" {self.duration:g} s" if self.shape == "pulse" else ""
        return f"{self.channel} {self.magnitude:+g} {unit} {self.shape}{extra} at {self.time:g} s"


def as_outliers(outliers) -> tuple[Outlier, ...]:
    """Normalise ``None``, one :class:`Outlier` or an iterable of them to a tuple."""
    if outliers is None:
        return ()
    if isinstance(outliers, Outlier):
        return (outliers,)
    try:
        out = tuple(outliers)
    except TypeError as exc:
        raise NavlibInputError("outliers: expected an Outlier or a sequence of them") from exc
    if not all(isinstance(o, Outlier) for o in out):
        raise NavlibInputError("outliers: every item must be a navlib.outliers.Outlier")
    return out


def channel_profile(outliers: Iterable[Outlier], channel: str, t) -> np.ndarray:
    """Sum of the profiles of every outlier touching single-axis ``channel`` at times ``t``."""
    t = np.asarray(t, dtype=float)
    total = np.zeros(t.shape)
    for o in outliers:
        if channel in o.channels:
            total += o.profile(t)
    return total


def inject(values, t, outliers, kind: str) -> np.ndarray:
    """Add the outliers of one channel kind to sensor data (EKF mode).

    Parameters
    ----------
    values : ndarray (N, 3)
        Sensor samples of that kind (GNSS ECEF velocity or position, body gyro rate or
        specific force) — for ``"att"``/``"rt"`` the small rotation vectors applied to the
        attitude data (see :func:`navlib.filters.ekf`).
    t : ndarray (N,)
        Sample times, s.
    outliers : sequence of Outlier
    kind : str
        One of :data:`KINDS`.

    Returns
    -------
    ndarray (N, 3)
        A copy with the outliers added.
    """
    if kind not in KINDS:
        raise NavlibInputError(f"kind: expected one of {list(KINDS)}, got {kind!r}")
    t = finite_array(t, "t", ndim=1)
    values = finite_array(values, "values", (t.size, 3)).copy()
    for i, a in enumerate(_AXES):
        values[:, i] += channel_profile(outliers, f"{kind}_{a}", t)
    return values


@dataclass(frozen=True)
class LinearMapping:
    """Where an outlier enters a linear error model (see the module docstring)."""

    channel: str
    target: str          # "measurement" or "noise"
    name: str | None     # model measurement / noise name, None if the model lacks it
    index: int | None
    sign: float


def linear_mapping(channel: str, measurement_names: Sequence[str],
                   noise_names: Sequence[str]) -> LinearMapping:
    """Map one single-axis channel onto a model's measurement row or noise channel."""
    kind, axis = split_channel(channel)
    target = "noise" if kind in IMU_KINDS else "measurement"
    names = list(noise_names if target == "noise" else measurement_names)
    for pattern, sign in LINEAR_NAMES[kind]:
        name = pattern.format(a=_AXES[axis])
        if name in names:
            return LinearMapping(channel, target, name, names.index(name), sign)
    return LinearMapping(channel, target, None, None, 0.0)


# --- recovery scoring -------------------------------------------------------------------------

VERDICT_CLASSES = ("recovers", "static error", "unaffected")


@dataclass(frozen=True)
class RecoveryScore:
    """Numeric outcome of one outlier test on one watched quantity (module docstring).

    Attributes
    ----------
    peak, residual : float
        Largest and final (window-averaged) outlier-induced error, in the quantity's unit.
    retained : float
        ``residual / peak`` (NaN when unaffected).
    time_constant : float
        Effective decay time ``window / ln(1 / retained)``, s (inf when nothing decayed).
    pre_error : float
        RMS nominal error just before the outlier.
    sigma_end : float
        Filter sigma at the end of the recovery window.
    residual_vs_pre, residual_vs_3sigma : float
    verdict : str
        ``"recovers"``, ``"static error"`` or ``"unaffected"``.
    t_outlier, window, recovered_fraction : float
        The settings used.
    """

    peak: float
    residual: float
    retained: float
    time_constant: float
    pre_error: float
    sigma_end: float
    residual_vs_pre: float
    residual_vs_3sigma: float
    verdict: str
    t_outlier: float
    window: float
    recovered_fraction: float

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _norm(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.abs(x) if x.ndim == 1 else np.linalg.norm(x, axis=-1)


def score_recovery(t, induced, *, t_outlier: float, window: float, sigma=None,
                   nominal_error=None, averaging: float = 1.0,
                   recovered_fraction: float = float(np.exp(-1.0)),
                   unaffected_tol: float = 0.0
                   ) -> RecoveryScore:
    """Score how an outlier-induced error decays (definition in the module docstring).

    Parameters
    ----------
    t : ndarray (K,)
        Times, s.
    induced : ndarray (K,) or (K, p)
        Outlier-induced error ``d(t)`` of the watched quantity (a vector is scored by its
        Euclidean norm).
    t_outlier, window : float
        Outlier time and recovery window, s; the window is clipped to the data.
    sigma : ndarray (K,) or (K, p), optional
        Filter standard deviation of the watched quantity (root-sum-square for a vector).
    nominal_error : ndarray, optional
        Nominal (outlier-free) estimation errors laid out like ``induced`` with an optional
        run axis after time: (K,) or (K, R) for a scalar, (K, p) or (K, R, p) for a
        vector. Their RMS over
        ``[t_o - averaging, t_o)`` is ``e_pre``. Without it ``e_pre`` is the sigma there.
    averaging : float
        ``Delta``, s: length of the final averaging window and of the pre-outlier window.
    recovered_fraction : float
        Threshold on ``retained`` for "recovers" (default ``exp(-1)``: one e-folding).
    unaffected_tol : float
        Peaks at or below this value count as "unaffected".
    """
    t = finite_array(t, "t", ndim=1)
    d = _norm(induced)
    if d.shape != t.shape:
        raise NavlibInputError(f"induced: expected {t.size} samples, got shape {d.shape}")
    t_outlier = finite_scalar(t_outlier, "t_outlier")
    window = finite_scalar(window, "window", 0.0, low_open=True)
    averaging = finite_scalar(averaging, "averaging", 0.0, low_open=True)
    recovered_fraction = finite_scalar(recovered_fraction, "recovered_fraction", 0.0, 1.0,
                                       low_open=True)
    if not t[0] <= t_outlier < t[-1]:
        raise NavlibInputError(f"t_outlier: {t_outlier} s is outside the data "
                               f"[{t[0]:g}, {t[-1]:g}) s")
    t_end = min(t_outlier + window, float(t[-1]))
    window = t_end - t_outlier
    during = (t >= t_outlier - 1e-9) & (t <= t_end + 1e-9)
    final = (t >= t_end - averaging - 1e-9) & (t <= t_end + 1e-9)
    before = (t >= t_outlier - averaging - 1e-9) & (t < t_outlier - 1e-9)
    peak = float(d[during].max())
    residual = float(d[final].mean())
    k_end = int(np.flatnonzero(t <= t_end + 1e-9)[-1])
    sig = None
    if sigma is not None:
        sig = np.asarray(sigma, dtype=float)
        sig = sig if sig.ndim == 1 else np.sqrt(np.sum(sig**2, axis=-1))
        if sig.shape != t.shape:
            raise NavlibInputError(f"sigma: expected {t.size} samples, got {sig.shape}")
    sigma_end = float(sig[k_end]) if sig is not None else np.nan
    if nominal_error is not None:
        e = np.asarray(nominal_error, dtype=float)
        vector = np.ndim(induced) == 2
        if e.shape[0] != t.size or e.ndim not in ((2, 3) if vector else (1, 2)):
            raise NavlibInputError(
                f"nominal_error: expected ({t.size}[, R]{', p' if vector else ''}), got "
                f"{e.shape}"
            )
        e = _norm(e) if vector else np.abs(e)               # (K,) or (K, R)
        pre = float(np.sqrt(np.mean(e[before] ** 2))) if before.any() else np.nan
    elif sig is not None and before.any():
        pre = float(np.sqrt(np.mean(sig[before] ** 2)))
    else:
        pre = np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        retained = residual / peak if peak > 0 else np.nan
        tau = (window / np.log(1.0 / retained) if 0 < retained < 1
               else (0.0 if retained == 0 else np.inf)) if peak > 0 else np.nan
        vs_pre = residual / pre if pre > 0 else np.nan
        vs_3s = residual / (3.0 * sigma_end) if sigma_end > 0 else np.nan
    if peak <= unaffected_tol:
        verdict = "unaffected"
    elif retained <= recovered_fraction:
        verdict = "recovers"
    else:
        verdict = "static error"
    return RecoveryScore(peak, residual, float(retained), float(tau), pre, sigma_end,
                         float(vs_pre),
                         float(vs_3s), verdict, t_outlier, window, recovered_fraction)


def scores_frame(scores: dict) -> pd.DataFrame:
    """Table of named :class:`RecoveryScore` objects, one row each."""
    return pd.DataFrame([{"case": name, **s.as_dict()} for name, s in scores.items()])


# --- the paper's four tests -------------------------------------------------------------------


@dataclass(frozen=True)
class PaperTest:
    """One outlier test of Beaudoin et al. (2018) §4.2 (spec launcher.md §6.4 table).

    Attributes
    ----------
    test_id : str
        ``"T1"`` .. ``"T4"``.
    figure : str
        The paper's figure(s).
    solutions : tuple of str
        The navigation solutions compared.
    channel : str
    magnitude : float
        SI value (3 m/s, 0.002 rad/s, 0.002 rad).
    watch : str
        ``"bp"`` (GPS position bias, 3 ECEF components), ``"roll"`` (body-x attitude error)
        or ``"ref_roll"`` (launcher divergence, roll).
    reported : dict
        Solution -> outcome the paper reports (``"static error"``, ``"recovers"``,
        ``"affected"``/``"unaffected"``).
    description : str
    """

    test_id: str
    figure: str
    solutions: tuple[str, ...]
    channel: str
    magnitude: float
    watch: str
    reported: dict
    description: str
    time: float = 50.0

    def outlier(self, shape: str = "spike", time: float | None = None,
                magnitude: float | None = None, duration: float | None = None) -> Outlier:
        """The test's outlier with the paper's values unless overridden."""
        return Outlier(self.channel, self.time if time is None else time,
                       self.magnitude if magnitude is None else magnitude, shape, duration)


PAPER_TESTS = {
    "T1": PaperTest(
        "T1", "Fig. 4", ("ins_gps_att",), "gnss_vel", 3.0, "bp",
        {"ins_gps_att": "static error"},
        "+3 m/s on the three GPS velocity components at 50 s; GPS position bias (Markov) "
        "well estimated before, a static error remains afterwards"),
    "T2": PaperTest(
        "T2", "Fig. 8", ("ins_gps", "ins_gps_rt"), "gyro_x", 0.002, "roll",
        {"ins_gps": "static error", "ins_gps_rt": "static error"},
        "0.002 rad/s on the roll gyro at 50 s; both INS/GPS and INS/GPS + RT keep a static "
        "roll error"),
    "T3": PaperTest(
        "T3", "Fig. 9", ("ins_gps", "ins_gps_rt"), "rt_x", 0.002, "roll",
        {"ins_gps": "unaffected", "ins_gps_rt": "affected"},
        "0.002 on the roll of the reference trajectory at 50 s; only the RT solution is "
        "affected"),
    "T4": PaperTest(
        "T4", "Figs. 12-13", ("ins_gps_att", "ins_gps_att_rt"), "gyro_x", 0.002, "roll",
        {"ins_gps_att": "recovers", "ins_gps_att_rt": "recovers"},
        "0.002 rad/s on the roll gyro at 50 s with attitude sensors; both correct the roll "
        "error within the same time range (RT: faster capture, slower correction, "
        "divergence underestimated)"),
}
"""The four outlier tests T1-T4 with the paper's magnitudes (spec launcher.md §5, §6.4)."""
