"""Sensor faults: outliers injected into sensor channels (Beaudoin et al. 2018 §3.2, §4.2;
docs/assumptions.md, launcher.md §6.4).

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
  (:data:`LINEAR_NAMES`), checked in ``tests/studies/outliers/test_outliers.py``.

How well a filter recovers from them is scored by :mod:`navlib.filters.recovery`.

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

Shapes (docs/assumptions.md, launcher.md §6.4: the paper's "spike or step" ambiguity):
``"spike"`` — the single sample (or measurement epoch) nearest the outlier time;
``"step"`` — every sample from then on;
``"pulse"`` — a step of given ``duration``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from navlib._validation import finite_array, finite_scalar
from navlib.errors import NavlibInputError

__all__ = ["CHANNELS", "IMU_KINDS", "KINDS", "LINEAR_NAMES", "MEASUREMENT_KINDS", "SHAPES",
           "LinearMapping", "Outlier", "as_outliers", "channel_profile", "expand_channel",
           "inject", "linear_mapping", "split_channel"]

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
    """A deterministic error on one sensor channel (docs/assumptions.md, launcher.md §6.4).

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
        raise NavlibInputError("outliers: every item must be a navlib.sensors.faults.Outlier")
    return out


def channel_profile(outliers: Iterable[Outlier], channel: str, t) -> np.ndarray:
    """Sum of the profiles of every outlier touching single-axis ``channel`` at times ``t``.

    Parameters
    ----------
    outliers : iterable of Outlier
        The outliers (those on other channels add nothing).
    channel : str
        A single-axis channel of :data:`CHANNELS`, e.g. ``"gyro_x"``.
    t : array_like (N,)
        Times, s.

    Returns
    -------
    ndarray (N,)
        The summed error on that channel, in the channel's unit (:data:`KINDS`).
    """
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
    """Map one single-axis channel onto a model's measurement row or noise channel.

    Parameters
    ----------
    channel : str
        A single-axis channel of :data:`CHANNELS`.
    measurement_names, noise_names : sequence of str
        The model's measurement rows and noise channels, by name.

    Returns
    -------
    LinearMapping
        The row or channel the outlier enters and its sign (:data:`LINEAR_NAMES`);
        ``name`` and ``index`` None, ``sign`` 0 when the model lacks it.

    Raises
    ------
    NavlibInputError
        If ``channel`` is not a single-axis channel.
    """
    kind, axis = split_channel(channel)
    target = "noise" if kind in IMU_KINDS else "measurement"
    names = list(noise_names if target == "noise" else measurement_names)
    for pattern, sign in LINEAR_NAMES[kind]:
        name = pattern.format(a=_AXES[axis])
        if name in names:
            return LinearMapping(channel, target, name, names.index(name), sign)
    return LinearMapping(channel, target, None, None, 0.0)
