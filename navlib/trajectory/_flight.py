"""Shared pieces of the powered-flight generators (private).

* an exponential atmosphere for drag;
* :class:`RestStartSpline`: a quintic interpolating spline of a quantity that is *exactly*
  zero (with its first two derivatives) before a start time, so a vehicle at rest stays at
  rest to the last bit while its motion afterwards is smooth (C^2 at the junction);
* :func:`assemble`: pointing direction + roll spline -> attitude and exact IMU through
  :func:`navlib.trajectory.base.build_trajectory`.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import make_interp_spline

from navlib.errors import NavlibInputError
from navlib.trajectory._attitude import pointing_angles, zyx_attitude
from navlib.trajectory.base import build_trajectory

RHO_SEA_LEVEL = 1.225
"""Sea-level air density of the exponential atmosphere, kg/m^3 (assumed)."""


def air_density(h, scale_height_m, rho0=RHO_SEA_LEVEL):
    """Exponential atmosphere ``rho0 exp(-h / H)``; ``h`` in m (negative heights clipped)."""
    return rho0 * np.exp(-np.maximum(h, 0.0) / scale_height_m)


class RestStartSpline:
    """Quintic spline of ``y(t)`` with ``y = y' = y'' = 0`` for ``t <= t0``.

    Built by interpolating samples ``y`` on ``grid`` (``grid[0] = t0``, ``y[0] = 0``) with the
    end conditions ``y'(t0) = 0``, ``y''(t0) = d2y_start`` (zero by default) and the given
    derivatives at the right end, so the function is C^2 everywhere (C^4 after ``t0``) and
    identically zero before ``t0``. A non-zero ``d2y_start`` (a hold-down release) is only
    meant for splines whose domain starts at ``t0``.
    """

    def __init__(self, grid, y, dy_end, d2y_end, d2y_start=None):
        y = np.asarray(y, dtype=float)
        zero = np.zeros(y.shape[1:])
        start2 = zero if d2y_start is None else np.asarray(d2y_start, dtype=float)
        self.t0 = float(grid[0])
        self.spline = make_interp_spline(
            grid, y - y[0], k=5,
            bc_type=([(1, zero), (2, start2)],
                     [(1, np.asarray(dy_end)), (2, np.asarray(d2y_end))]),
        )

    def __call__(self, t, nu=0):
        """Value or ``nu``-th derivative at times ``t`` (zero before ``t0``)."""
        t = np.asarray(t, dtype=float)
        out = self.spline(np.maximum(t, self.t0), nu)
        before = t < self.t0
        if np.any(before):
            out[before] = 0.0
        return out

    def antiderivative(self):
        """``integral_{t0}^{t} y`` as a callable with the same zero-before-``t0`` rule."""
        anti = self.spline.antiderivative()
        t0 = self.t0

        def evaluate(t, nu=0):
            t = np.asarray(t, dtype=float)
            out = anti(np.maximum(t, t0), nu)
            out[t < t0] = 0.0
            return out

        return evaluate


def roll_spline(grid, rate):
    """Spline of a roll rate that starts from rest at ``grid[0]``, and its integral (angle).

    The right-end derivatives come from the samples (they only shape the last few grid
    steps, which lie beyond the delivered time span).
    """
    d1 = np.gradient(rate, grid)
    d2 = np.gradient(d1, grid)
    spline = RestStartSpline(grid, rate, d1[-1], d2[-1])
    return spline, spline.antiderivative()


def assemble(t, P0, displacement, pointing, C_L_e, roll, *, events, name, parameters,
             turn=None):
    """Sample the smooth flight on ``t`` and build the exact-IMU :class:`Trajectory`.

    Parameters
    ----------
    t : ndarray (N,)
        Output times (IMU rate).
    P0 : ndarray (3,)
        ECEF position at rest.
    displacement : RestStartSpline
        ECEF displacement from ``P0`` (3 columns).
    pointing : callable
        ``pointing(t, V, a) -> (u_e, du_e)``: unit body-x direction in ECEF and its
        analytic derivative, given the spline velocity and acceleration.
    C_L_e : ndarray (3, 3)
        The fixed frame in which yaw/pitch stay regular (see ``_attitude``).
    roll : callable
        ``roll(t, nu)`` roll angle (``nu = 0``) and roll rate (``nu = 1``), rad.
    turn : callable, optional
        ``turn(t, psi, theta, dpsi, dtheta) -> (psi, theta, dpsi, dtheta)``: reshapes the
        yaw and pitch of the pointing (a rocket turning to hang under its canopy).
    """
    P = P0 + displacement(t)
    V = displacement(t, 1)
    a = displacement(t, 2)
    u_e, du_e = pointing(t, V, a)
    psi, theta, dpsi, dtheta = pointing_angles(u_e @ C_L_e, du_e @ C_L_e)
    if turn is not None:
        psi, theta, dpsi, dtheta = turn(t, psi, theta, dpsi, dtheta)
    C_b_e, w_eb_b = zyx_attitude(C_L_e, psi, theta, roll(t, 0), dpsi, dtheta, roll(t, 1))
    return build_trajectory(t, P, V, a, C_b_e, w_eb_b, events=events, name=name,
                            parameters=parameters)


def integrate(rhs, grid, y0, breakpoints, rtol=1e-10, atol=1e-6):
    """Integrate ``dy/dt = rhs(t, y)`` with DOP853 and return ``y`` on ``grid`` (N, n).

    The span is split at ``breakpoints`` (starts and ends of thrust ramps and other short
    events) so that adaptive steps never stride over them; inside each piece the
    right-hand side is smooth and the steps can be long.
    """
    cuts = np.unique(np.clip(np.r_[grid[0], np.asarray(breakpoints, float), grid[-1]],
                             grid[0], grid[-1]))
    out = np.empty((grid.size, np.size(y0)))
    y = np.asarray(y0, dtype=float)
    for lo, hi in itertools.pairwise(cuts):
        inside = (grid >= lo) & (grid < hi)
        t_eval = np.r_[grid[inside], hi]
        sol = solve_ivp(rhs, (lo, hi), y, method="DOP853", t_eval=t_eval, rtol=rtol,
                        atol=atol)
        if not sol.success:  # pragma: no cover - smooth right-hand sides do not fail
            raise NavlibInputError(f"flight integration failed: {sol.message}")
        out[inside] = sol.y[:, :-1].T
        y = sol.y[:, -1]
    out[-1] = y
    return out


def output_times(end_s, rate_hz, start_s=0.0):
    """Regular sample times ``start_s, start_s + 1/rate, ...`` up to ``end_s`` inclusive."""
    n = int(np.floor((end_s - start_s) * rate_hz + 1e-9)) + 1
    return start_s + np.arange(n) / rate_hz


def step(t, start_s, duration_s):
    """Scalar ``smoothstep((t - start_s) / duration_s)`` (fast path for ODE right-hand sides)."""
    x = (t - start_s) / duration_s
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x**4 * (35.0 - 84.0 * x + 70.0 * x**2 - 20.0 * x**3)


def ramp_integral(x):
    """``integral_0^x smoothstep`` for x in [0, 1] (propellant used during the ramp)."""
    x = np.clip(x, 0.0, 1.0)
    return x**5 * (7.0 - 14.0 * x + 10.0 * x**2 - 2.5 * x**3)
