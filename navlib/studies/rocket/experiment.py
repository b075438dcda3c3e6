"""The rocket experiment: excitability per segment and sensability per epoch on the flight
(:class:`RocketAnalysis`, :func:`excitability_study`), the pad geometry the S-claims read and
S5's quiet-gyro counterfactual."""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib import earth, metrics
from navlib._validation import finite_scalar, reject_unknown
from navlib.errors import NavlibInputError
from navlib.models.ecef import (
    ATTITUDE_ERRORS,
    P0_DEFAULTS,
    PAPER_IDS,
    STATE_NAMES,
    imu_noise_densities,
    parameter_sigmas,
)
from navlib.studies.rocket.flight import (
    GYRO_NOISE_KEYS,
    IN_SO,
    QUIET_GYRO_SCALE,
    SEGMENTS,
    SENSIBLE,
    rocket_chain,
    rocket_trajectory,
)

__all__ = ["RocketAnalysis", "direction_sensability", "excitability_study", "heading_direction",
           "quiet_gyro_analysis", "tangent_projections"]


class RocketAnalysis(metrics.SegmentedAnalysis):
    """Excitability per segment and sensability per epoch on the rocket flight.

    A :class:`navlib.metrics.SegmentedAnalysis` of the 21-state model at the GNSS epochs
    (``model`` with ``P0`` and ``R``, ``trajectory`` the flight, ``segments``,
    ``excitability`` one result per segment, ``sensability``, ``settings``: spin, frame, eta,
    nu, D0 choice, GNSS sigma, P0 sigmas) whose frames also carry the paper's state ids
    (``paper_id``, e1-e21).
    """

    def _state_columns(self) -> dict:
        return {**super()._state_columns(),
                "paper_id": [PAPER_IDS[s] for s in self.state_names]}

    def e(self) -> pd.DataFrame:
        """Excitability table: rows states, columns segment labels (``tau1``...)."""
        return self.excitability_table()


def excitability_study(spin_hz: float = 2.0, attitude_error: str = "ecef", eta: float = 1e-3,
            nu: float = 0.985, segments=SEGMENTS, d0: str = "global",
            gnss_sigma_m: float = 5.0, sensors=None, prior_update: bool = False,
            trajectory_options: dict | None = None, **sigmas) -> RocketAnalysis:
    """Excitability (per segment) and sensability (per epoch) on the rocket flight.

    Parameters
    ----------
    spin_hz : float
        Aerodynamic spin reached in powered flight (assumed 2 Hz; halved at 73 s).
    attitude_error : {"ecef", "body"}
        Attitude-error frame (docs/assumptions.md A4); ECEF default (reading of Fig. 4).
    eta : float
        Excitability energy threshold (assumed 1e-3, docs/assumptions.md A14).
    nu : float
        Sensability threshold (paper: 0.985).
    segments : sequence of (t_start, t_end)
        Default tau1 = [0, 19], tau2 = [19, 60], tau3 = [60, 86] s.
    d0 : {"global", "filter"}
        D0 of the excitability per segment (docs/assumptions.md A19).
    gnss_sigma_m : float
        GNSS position sigma per axis, R = R0 (assumed 5 m).
    sensors : None, str or mapping
        IMU noise (default preset ``motionpak_tactical``).
    prior_update : bool
        Sensability with P0 as a prior updated at t0 (docs/assumptions.md A9; default: literal
        reading).
    trajectory_options : dict, optional
        Further :func:`navlib.trajectory.sounding_rocket` keywords (site, rail, timings).
    **sigmas
        Initial sigmas, see :data:`navlib.models.ecef.P0_DEFAULTS`.
    """
    if attitude_error not in ATTITUDE_ERRORS:
        raise NavlibInputError(
            f"attitude_error: expected one of {ATTITUDE_ERRORS}, got {attitude_error!r}")
    reject_unknown(sigmas, P0_DEFAULTS, "excitability_study")
    model = rocket_chain(spin_hz, attitude_error, sensors, gnss_sigma_m,
                         trajectory_options=trajectory_options, **sigmas)
    traj = rocket_trajectory(spin_hz, **dict(trajectory_options or {}))
    settings = {"spin_hz": float(spin_hz), "attitude_error": attitude_error,
                "gnss_sigma_m": float(gnss_sigma_m),
                "sensors": sensors if sensors is None or isinstance(sensors, str) else "custom",
                **{k: float(sigmas.get(k, v)) for k, v in
                   {**P0_DEFAULTS, **parameter_sigmas(sensors)}.items()}}
    return RocketAnalysis.build(model, segments, trajectory=traj, eta=eta, nu=nu, d0=d0,
                                prior_update=prior_update, e_threshold=IN_SO,
                                s_threshold=SENSIBLE, settings=settings)


def _up(analysis: RocketAnalysis) -> np.ndarray:
    """Local vertical (ECEF) at the pad."""
    lat, lon, _ = earth.ecef_to_geodetic(analysis.trajectory.position[0])
    return -earth.ned_to_ecef_matrix(lat, lon)[:, 2]


def tangent_projections(analysis: RocketAnalysis) -> np.ndarray:
    """Norms of the projections of the three attitude-error axes on the pad's tangent plane.

    ECEF axes for the ``ecef`` attitude error, body axes at t0 for ``body`` (docs/assumptions.md,
    excitability.md §3 prototype: 0.58 / 0.82 / 0.99 for the ECEF axes at the assumed site).
    """
    up = _up(analysis)
    if analysis.settings["attitude_error"] == "body":
        up = analysis.trajectory.C_b_e()[0].T @ up
    return np.sqrt(np.clip(1.0 - up**2, 0.0, None))


def direction_sensability(result: metrics.SensabilityResult, v) -> np.ndarray:
    """Sensability of a physical direction ``v`` (n,) at every epoch (Def. 2 generalised).

    ``v`` is mapped to the normalised coordinates (``D0^-1/2 v``), made unit, and projected
    on the practically sensible subspace ``span{v^1..v^nr}``: ``||V[:, :nr]' w||``.

    Parameters
    ----------
    result : navlib.metrics.SensabilityResult
        Sensability of the analysis.
    v : array_like
        Direction in state space, (n,).

    Raises
    ------
    NavlibInputError
        If ``v`` is zero or of the wrong length.
    """
    v = np.asarray(v, dtype=float)
    if v.shape != (result.n,) or not np.any(v):
        raise NavlibInputError(f"v: expected a non-zero vector of length {result.n}")
    w = v / np.sqrt(result.d0)
    w = w / np.linalg.norm(w)
    proj = np.einsum("kji,j->ki", result.V, w) ** 2
    keep = np.arange(result.n) < result.nr[:, None]
    return np.sqrt(np.sum(proj * keep, axis=1))


def heading_direction(analysis: RocketAnalysis) -> np.ndarray:
    """The 21-vector of a rotation about the local vertical at the pad (heading error)."""
    up = _up(analysis)
    if analysis.settings["attitude_error"] == "body":
        up = analysis.trajectory.C_b_e()[0].T @ up
    v = np.zeros(len(STATE_NAMES))
    v[6:9] = up
    return v


def quiet_gyro_analysis(analysis: RocketAnalysis, scale: float = QUIET_GYRO_SCALE,
                        sensors=None) -> RocketAnalysis:
    """``analysis`` rerun with the gyro noise (ARW, bias random walk) and the initial gyro
    bias sigma scaled by ``scale``: the counterfactual of S5 ("gyro noise and bias prevent
    measuring the Earth rate", A-S5-cause). ``sensors``: the noise source of ``analysis``
    when it was built from a mapping (default: its named preset).

    Parameters
    ----------
    analysis : RocketAnalysis
        The analysis.
    scale : float, optional
        Factor on the gyro noise and initial gyro-bias sigma, in (0, 1].
    sensors : optional
        Noise source of ``analysis`` when it was built from a mapping.

    Raises
    ------
    NavlibInputError
        If ``scale`` is out of range, or ``sensors`` is missing for a mapping-built analysis.
    """
    scale = finite_scalar(scale, "scale", 0.0, 1.0, low_open=True)
    if sensors is None and analysis.settings["sensors"] == "custom":
        raise NavlibInputError("sensors: the analysis was built from a noise mapping; pass "
                               "the same mapping for S5's counterfactual")
    noise = imu_noise_densities(analysis.settings["sensors"] if sensors is None else sensors)
    quiet = {k: (v * scale if k in GYRO_NOISE_KEYS else v) for k, v in noise.items()}
    s = analysis.settings
    sigmas = {k: s[k] for k in P0_DEFAULTS if k in s}
    sigmas["sigma_bg_deg_s"] = sigmas.get("sigma_bg_deg_s", P0_DEFAULTS["sigma_bg_deg_s"]) \
        * scale
    return excitability_study(s["spin_hz"], s["attitude_error"], s["eta"], s["nu"], d0=s["d0"],
                   gnss_sigma_m=s["gnss_sigma_m"], sensors=quiet,
                   prior_update=s["prior_update"], **sigmas)
