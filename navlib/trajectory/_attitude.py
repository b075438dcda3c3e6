"""Smooth, regular attitude parametrisations with analytic body rates (private).

Every generator and the flight-data fit write the attitude as

``C_b_e(t) = C_L_e · Rz(psi(t)) · Ry(theta(t)) · Rx(phi(t))``

where ``L`` is a *fixed* frame (constant in ECEF) chosen so that the pitch ``theta`` stays
far from +-90 deg along the whole flight: the only singularity of the yaw-pitch-roll
sequence is then never approached, even for a vertical launch or a fast-spinning body
(``phi`` and ``psi`` are unwrapped, so any number of turns is fine). With smooth angle
functions the body rate follows analytically from the Euler kinematics (docs/assumptions.md,
excitability.md §4, "pointing + roll"):

``omega_eb^b = [phi' - psi' sin(theta),
                theta' cos(phi) + psi' cos(theta) sin(phi),
               -theta' sin(phi) + psi' cos(theta) cos(phi)]``

No finite differences of sampled attitudes are involved.
"""

from __future__ import annotations

import numpy as np

from navlib import earth


def smoothstep(x):
    """C^3 step ``s(x) = x^4 (35 - 84 x + 70 x^2 - 20 x^3)`` clipped to [0, 1].

    Returns ``(s, ds/dx, d2s/dx2)``; used for every ramp (ignition, tail-off, de-spin,
    rail tip-off) so that accelerations and body rates stay continuous with a continuous
    derivative.
    """
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    s = x**4 * (35.0 - 84.0 * x + 70.0 * x**2 - 20.0 * x**3)
    ds = 140.0 * x**3 * (1.0 - x) ** 3
    d2s = 420.0 * x**2 * (1.0 - x) ** 2 * (1.0 - 2.0 * x)
    return s, ds, d2s


def zyx_matrix(psi, theta, phi):
    """``Rz(psi) Ry(theta) Rx(phi)`` stacked over samples, (N, 3, 3)."""
    cps, sps = np.cos(psi), np.sin(psi)
    cth, sth = np.cos(theta), np.sin(theta)
    cph, sph = np.cos(phi), np.sin(phi)
    out = np.empty((np.size(psi), 3, 3))
    out[:, 0, 0] = cps * cth
    out[:, 0, 1] = cps * sth * sph - sps * cph
    out[:, 0, 2] = cps * sth * cph + sps * sph
    out[:, 1, 0] = sps * cth
    out[:, 1, 1] = sps * sth * sph + cps * cph
    out[:, 1, 2] = sps * sth * cph - cps * sph
    out[:, 2, 0] = -sth
    out[:, 2, 1] = cth * sph
    out[:, 2, 2] = cth * cph
    return out


def zyx_body_rate(theta, phi, dpsi, dtheta, dphi):
    """Body rate ``omega_Lb^b`` (N, 3) of ``Rz(psi) Ry(theta) Rx(phi)`` from angle rates."""
    cth, sth = np.cos(theta), np.sin(theta)
    cph, sph = np.cos(phi), np.sin(phi)
    return np.stack([
        dphi - dpsi * sth,
        dtheta * cph + dpsi * cth * sph,
        -dtheta * sph + dpsi * cth * cph,
    ], axis=-1)


def zyx_attitude(C_L_e, psi, theta, phi, dpsi, dtheta, dphi):
    """Body -> ECEF matrices (N, 3, 3) and ``omega_eb^b`` (N, 3) for a fixed frame ``L``."""
    C_b_L = zyx_matrix(psi, theta, phi)
    return C_L_e @ C_b_L, zyx_body_rate(theta, phi, dpsi, dtheta, dphi)


def pointing_angles(u_L, du_L):
    """Yaw, pitch and their rates of a unit pointing vector ``u_L`` (N, 3) in frame ``L``.

    ``psi = atan2(u_y, u_x)``, ``theta = asin(-u_z)``; ``du_L`` is the analytic derivative of
    ``u_L``. Regular while ``u_L`` stays away from the ``+-z_L`` axis.
    """
    ux, uy, uz = u_L[:, 0], u_L[:, 1], u_L[:, 2]
    h2 = ux**2 + uy**2
    h = np.sqrt(h2)
    psi = np.arctan2(uy, ux)
    theta = np.arctan2(-uz, h)
    dpsi = (ux * du_L[:, 1] - uy * du_L[:, 0]) / h2
    dtheta = -du_L[:, 2] / h
    return psi, theta, dpsi, dtheta


def unit_and_rate(w, dw):
    """``u = w/|w|`` and its derivative ``(dw - u (u . dw)) / |w|`` for (N, 3) arrays."""
    norm = np.linalg.norm(w, axis=1)
    u = w / norm[:, None]
    du = (dw - u * np.einsum("ni,ni->n", u, dw)[:, None]) / norm[:, None]
    return u, du


def launch_frame(lat, lon, azimuth, elevation):
    """Fixed frame ``L`` = NED turned by ``azimuth`` then pitched up by ``elevation``.

    Its x axis points along ``azimuth`` (from North, towards East) at ``elevation`` above
    the local horizontal of the geodetic point ``(lat, lon)``; returns ``C_L_e`` (3, 3).
    """
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    C_L_n = zyx_matrix(np.array([azimuth]), np.array([elevation]), np.array([0.0]))[0]
    return C_n_e @ C_L_n
