"""Figures for reference trajectories and the strapdown closure check (notebook 01).

Each builder takes library results (a :class:`navlib.trajectory.Trajectory` or a
:class:`navlib.strapdown.ClosureError`) and returns a new matplotlib Figure; nothing is
computed here beyond unit conversion and the body-axis elevation used for display.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from navlib import earth
from navlib.plots.figure import subplots
from navlib.units import DEG, DEG_PER_HOUR

__all__ = ["LAUNCHER_MARKERS", "ROCKET_MARKERS", "altitude_speed_figure", "axial_imu_figure",
           "body_x_elevation", "closure_error_figure", "launcher_figure", "mark_events",
           "stationary_figure"]

ROCKET_MARKERS = ("ignition", "burnout", "free_flight", "despin")
"""Events marked on the Fig. 1 analogue (paper: 18, 46, 60 and 73 s)."""
LAUNCHER_MARKERS = ("pitchover", "gravity_turn", "stage1_burnout", "stage2_ignition")
"""Events marked on the launcher figure (programme start/end, first engine off, second on)."""

_TWO_PI = 2.0 * np.pi


def mark_events(ax, events: dict, which: Iterable[str] | None, label: bool) -> None:
    """Dotted vertical lines at the chosen events, names written down from the top axis.

    Labels closer than 4 % of the time span to the previous one drop lower so they do not
    overprint each other.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    events : dict
        Event name -> time, s.
    which : iterable of str or None
        Events marked; None: all.
    label : bool
        Write the names.
    """
    names = list(events) if which is None else [w for w in which if w in events]
    chosen = sorted((events[name], name) for name in names)
    span = (max(t for t, _ in chosen) - min(t for t, _ in chosen)) if chosen else 0.0
    last, level = -np.inf, 0
    for t, name in chosen:
        ax.axvline(t, color="0.4", linestyle=":", linewidth=1.0)
        if label:
            level = level + 1 if t - last < 0.04 * max(span, 1e-9) else 0
            last = t
            ax.annotate(f"{name} {t:g} s", (t, 1.0 - 0.3 * (level % 3)),
                        xycoords=("data", "axes fraction"), xytext=(2, -2),
                        textcoords="offset points", rotation=90, va="top", ha="left",
                        fontsize=7, color="0.3")


def _title(traj) -> str:
    return traj.name or "trajectory"


def axial_imu_figure(traj, markers: Iterable[str] | None = ROCKET_MARKERS):
    """Fig. 1 analogue (España et al. 2019): axial specific force f_x and rate w_x vs time.

    Parameters
    ----------
    traj : Trajectory
        Body x is the rocket axis.
    markers : iterable of str or None
        Event names to mark (None: every event of ``traj``).
    """
    fig, (ax_f, ax_w) = subplots(2, 1, sharex=True, figsize=(8, 5.5), layout="constrained")
    ax_f.plot(traj.t, traj.specific_force[:, 0], color="C0")
    ax_f.axhline(0.0, color="0.7", linewidth=0.8)
    ax_f.set_ylabel("axial specific force $f_x$ [m/s²]")
    ax_w.plot(traj.t, traj.angular_rate[:, 0], color="C1")
    ax_w.set_ylabel(r"axial rate $\omega_{x}$ [rad/s]")
    ax_w.set_xlabel("time [s]")
    hz = ax_w.secondary_yaxis("right", functions=(lambda w: w / _TWO_PI, lambda h: h * _TWO_PI))
    hz.set_ylabel("[rev/s]")
    mark_events(ax_f, traj.events, markers, label=True)
    mark_events(ax_w, traj.events, markers, label=False)
    fig.suptitle(f"{_title(traj)}: axial IMU signals (Fig. 1 analogue)")
    return fig


def altitude_speed_figure(traj, markers: Iterable[str] | None = ROCKET_MARKERS):
    """Ellipsoidal height (km) and ECEF speed (m/s) vs time with event markers.

    Parameters
    ----------
    traj : Trajectory
        The trajectory.
    markers : iterable of str or None, optional
        Events marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _, _, alt = traj.geodetic
    speed = np.linalg.norm(traj.velocity, axis=1)
    fig, (ax_h, ax_v) = subplots(2, 1, sharex=True, figsize=(8, 5), layout="constrained")
    ax_h.plot(traj.t, alt / 1e3, color="C2")
    ax_h.set_ylabel("height [km]")
    ax_v.plot(traj.t, speed, color="C3")
    ax_v.set_ylabel("speed (ECEF) [m/s]")
    ax_v.set_xlabel("time [s]")
    mark_events(ax_h, traj.events, markers, label=True)
    mark_events(ax_v, traj.events, markers, label=False)
    fig.suptitle(f"{_title(traj)}: height and speed")
    return fig


def body_x_elevation(traj) -> np.ndarray:
    """Elevation (rad) of the body x axis above the local horizontal plane, per sample.

    The display "pitch" of an ascending vehicle; unlike a ZYX Euler pitch it stays defined
    whatever the roll.
    """
    lat, lon, _ = traj.geodetic
    up = -earth.ned_to_ecef_matrix(lat, lon)[:, :, 2]
    x_e = traj.attitude.apply(np.array([1.0, 0.0, 0.0]))
    return np.arcsin(np.clip(np.einsum("ni,ni->n", x_e, up), -1.0, 1.0))


def launcher_figure(traj, markers: Iterable[str] | None = LAUNCHER_MARKERS):
    """Launcher ascent: body specific force, body-x elevation (pitch) and height vs time.

    Parameters
    ----------
    traj : Trajectory
        The launcher trajectory.
    markers : iterable of str or None, optional
        Events marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    _, _, alt = traj.geodetic
    fig, axes = subplots(3, 1, sharex=True, figsize=(8, 7), layout="constrained")
    for i, axis in enumerate("xyz"):
        axes[0].plot(traj.t, traj.specific_force[:, i], label=f"$f_{axis}$")
    axes[0].plot(traj.t, np.linalg.norm(traj.specific_force, axis=1), "k--", lw=0.8,
                 label="|f|")
    axes[0].set_ylabel("specific force [m/s²]")
    axes[0].legend(ncol=4, fontsize=8, loc="lower left")
    axes[1].plot(traj.t, body_x_elevation(traj) / DEG, color="C4")
    axes[1].set_ylabel("body-x elevation [deg]")
    axes[2].plot(traj.t, alt / 1e3, color="C2")
    axes[2].set_ylabel("height [km]")
    axes[2].set_xlabel("time [s]")
    for k, ax in enumerate(axes):
        mark_events(ax, traj.events, markers, label=k == 0)
    fig.suptitle(f"{_title(traj)}: specific force, pitch and height")
    return fig


def stationary_figure(traj):
    """Vehicle at rest: |f| against normal gravity and |w_ib| against the Earth rate.

    The lower half of each panel shows the difference, which for an exact IMU is round-off.
    """
    g_ref = np.linalg.norm(earth.normal_gravity_ecef(traj.position), axis=1)
    f_mag = np.linalg.norm(traj.specific_force, axis=1)
    w_mag = np.linalg.norm(traj.angular_rate, axis=1)
    fig, axes = subplots(2, 2, sharex=True, figsize=(9, 5), layout="constrained")
    axes[0, 0].plot(traj.t, f_mag, label="|f| (accelerometers)")
    axes[0, 0].plot(traj.t, g_ref, "k--", lw=0.8, label="|γ| normal gravity")
    axes[0, 0].set_ylabel("[m/s²]")
    axes[0, 0].legend(fontsize=8)
    axes[1, 0].plot(traj.t, f_mag - g_ref, color="C0")
    axes[1, 0].set_ylabel("|f| − |γ| [m/s²]")
    axes[0, 1].plot(traj.t, w_mag / DEG_PER_HOUR, color="C1", label="|ω_ib| (gyros)")
    axes[0, 1].axhline(earth.OMEGA_E / DEG_PER_HOUR, color="k", ls="--", lw=0.8,
                       label="Ω Earth rate")
    axes[0, 1].set_ylabel("[deg/h]")
    axes[0, 1].legend(fontsize=8)
    axes[1, 1].plot(traj.t, (w_mag - earth.OMEGA_E) / DEG_PER_HOUR, color="C1")
    axes[1, 1].set_ylabel("|ω_ib| − Ω [deg/h]")
    for ax in axes[1]:
        ax.set_xlabel("time [s]")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    fig.suptitle(f"{_title(traj)}: the IMU at rest senses gravity and the Earth rate")
    return fig


def closure_error_figure(closure, position_tol_m: float | None = 1.0,
                         attitude_tol_rad: float | None = 1e-4, events: dict | None = None):
    """Strapdown closure: position (m), velocity (m/s) and attitude (mrad) error vs time.

    Logarithmic axes (exact zeros, e.g. on the pad, are left out); dashed lines show the
    tolerances a correct strapdown must meet on an exact-IMU trajectory (1 m and 0.1 mrad at
    the end of the flight, ``tests/trajectory/test_trajectory.py``).

    Parameters
    ----------
    closure : pandas.DataFrame
        Strapdown closure errors over time.
    position_tol_m : float or None, optional
        Position tolerance line, m.
    attitude_tol_rad : float or None, optional
        Attitude tolerance line, rad.
    events : dict or None, optional
        Event name -> time, s, marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = subplots(3, 1, sharex=True, figsize=(8, 6.5), layout="constrained")
    series = [(closure.position_error, "position [m]", "C0", position_tol_m),
              (closure.velocity_error, "velocity [m/s]", "C3", None),
              (closure.attitude_error * 1e3, "attitude [mrad]", "C1",
               None if attitude_tol_rad is None else attitude_tol_rad * 1e3)]
    for ax, (err, label, color, tol) in zip(axes, series, strict=True):
        ax.plot(closure.t, np.where(err > 0.0, err, np.nan), color=color)
        ax.set_yscale("log")
        ax.set_ylabel(label)
        if tol is not None:
            ax.axhline(tol, color="k", ls="--", lw=0.8, label="tolerance")
            ax.legend(fontsize=8, loc="lower right")
    axes[2].set_xlabel("time [s]")
    if events:
        for k, ax in enumerate(axes):
            mark_events(ax, events, ROCKET_MARKERS, label=k == 0)
    fig.suptitle("strapdown re-integration of the exact IMU: error against the truth")
    return fig
