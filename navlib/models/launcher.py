"""Satellite-launcher error models of Beaudoin, Desbiens, Gagnon & Landry (2018): the four
loosely coupled INS/GPS solutions (with attitude sensors and the reference trajectory), any
subset of gyro, accelerometer and GPS-position biases as Markov processes or random walks.
State order, noise values and the paper readings taken: docs/models.md."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navlib._validation import finite_scalar, reject_unknown
from navlib.earth import EARTH_RATE_ECEF
from navlib.errors import NavlibInputError
from navlib.models.base import ErrorState, LinearModel, MeasurementRows, VaryingBlock
from navlib.rotations import skew
from navlib.sensors import SensorSpec, load_preset
from navlib.trajectory import launcher_ascent
from navlib.units import DEG

__all__ = ["ASSUMED", "BIAS_LETTERS", "BIAS_MODELS", "BIAS_SETS", "DEFAULT_SENSORS", "SOLUTIONS",
           "SOLUTION_LABELS", "STATE_NAMES", "LauncherErrorState", "LauncherSteps", "launcher",
           "launcher_steps", "rt_dynamics_matrix", "sensor_values", "simplified_gps_bias",
           "state_names"]

SOLUTIONS = ("ins_gps", "ins_gps_att", "ins_gps_rt", "ins_gps_att_rt")
"""The four navigation solutions (spec launcher.md §1)."""
SOLUTION_LABELS = {"ins_gps": "INS/GPS", "ins_gps_att": "INS/GPS/att",
                   "ins_gps_rt": "INS/GPS + RT", "ins_gps_att_rt": "INS/GPS/att + RT"}
"""Display names of the :data:`SOLUTIONS` (tables, figure titles, claim texts)."""
BIAS_MODELS = ("none", "markov", "random_walk")
"""Bias error models: neglected (no bias states), first-order Markov, random walk."""
BIAS_LETTERS = ("G", "A", "P")
"""Gyro, accelerometer and GPS-position biases, in state order."""
BIAS_SETS = ("", "G", "A", "P", "GA", "GP", "AP", "GAP")
"""The eight bias combinations of Table 2, in the paper's row order."""

_AXES = ("x", "y", "z")
_GROUPS = {
    "psi": tuple(f"psi_{a}" for a in _AXES),
    "dv": tuple(f"dv_{a}" for a in _AXES),
    "dr": tuple(f"dr_{a}" for a in _AXES),
    "G": tuple(f"bg_{a}" for a in _AXES),
    "A": tuple(f"ba_{a}" for a in _AXES),
    "P": tuple(f"bp_{a}" for a in _AXES),
    "xa": tuple(f"x{i}" for i in range(19, 26)),
    "ref": tuple(f"psi_ref_{a}" for a in _AXES),
}
STATE_NAMES = sum(_GROUPS.values(), ())
"""All 28 states of the full ``ins_gps_att_rt`` + G, A, P model, in order."""

DEFAULT_SENSORS = "launcher_table1"
"""Sensor preset of the paper's Table 1 (``data/sensors/launcher_table1.toml``)."""

ASSUMED = {
    "sigma_wind": 0.01,          # rad/s, wind angular rate per 200 Hz sample
    "sigma0_att": 0.1 * DEG, "sigma0_vel": 0.1, "sigma0_pos": 3.0,
}
"""Values neither the paper nor the sensor preset gives (spec §5 "Not given"), chosen here."""


def sensor_values(sensors=DEFAULT_SENSORS) -> dict:
    """The model's noise keywords (SI) from a sensor preset name, path or SensorSpec.

    Returns ``gyro_arw, gyro_bias, c_g, accel_vrw, accel_bias, c_a, sigma_att,
    sigma_gps_vel, sigma_gps_pos, sigma_bp, c_p``.
    """
    spec = sensors if isinstance(sensors, SensorSpec) else load_preset(sensors)
    if spec.imu is None or spec.gnss is None or spec.attitude_sigma is None:
        raise NavlibInputError(f"sensors: preset {spec.name!r} needs [imu], [gnss] and "
                               "[attitude_sensor] sections")
    gyro, accel, gnss = spec.imu.gyro, spec.imu.accel, spec.gnss
    return {"gyro_arw": gyro.noise_density, "gyro_bias": gyro.bias_markov_sigma,
            "c_g": gyro.bias_markov_tau, "accel_vrw": accel.noise_density,
            "accel_bias": accel.bias_markov_sigma, "c_a": accel.bias_markov_tau,
            "sigma_att": spec.attitude_sigma, "sigma_gps_vel": gnss.velocity_sigma,
            "sigma_gps_pos": gnss.position_sigma, "sigma_bp": gnss.position_bias_markov,
            "c_p": gnss.position_bias_tau}

_OPTIONS = ("a1_sign", "sigma_gps_vel", "sigma_gps_pos", "sigma_bp", "sigma_wind", "c_g",
            "c_a", "c_p", "sigma0_att", "sigma0_vel", "sigma0_pos", "gyro_arw", "gyro_bias",
            "accel_vrw", "accel_bias", "sigma_att", "s_t")


def rt_dynamics_matrix() -> np.ndarray:
    """Continuous closed-loop attitude dynamics ``M`` of the RT augmentation, ``A2 = I + s_t M``.

    Spec docs/assumptions.md, launcher.md §3.4 (V3 reading with the ``-I_3`` feedback): states
    ``x19 x20 x21 | x22 x23 | x24 x25 | psi_ref_x psi_ref_y psi_ref_z``. Roll is a 2-state
    loop (x19, psi_ref_x), pitch and yaw 4-state loops. Its eigenvalues are
    ``-0.25 +- 0.733j`` (roll) and ``-2.818 +- 3.686j, -0.394, -0.096`` (pitch, yaw; §10b).

    Returns
    -------
    M : ndarray (10, 10)
    """
    M = np.zeros((10, 10))
    M[0:3, 0:3] = np.diag([-0.5, -6.1248, -6.1248])
    M[1, 3] = M[2, 4] = 5.6922
    M[0:3, 7:10] = -np.eye(3)
    M[3, 1] = M[4, 2] = 1.0                      # x22' = x20, x23' = x21
    M[5, 3] = M[6, 4] = 1.0                      # x24' = x22, x25' = x23
    M[7:10, 0:3] = np.diag([0.6, 30.012, 30.012])
    M[8, 3] = M[9, 4] = 10.7475
    M[8, 5] = M[9, 6] = 0.8111
    return M


def simplified_gps_bias(c_p: float, s_t: float = 0.005):
    """The simplified position / GPS-bias model of §4.1 (docs/assumptions.md, launcher.md §3.7, eq.
    7).

    ``[dr; b_p](k+1) = (I_6 + s_t [[0, 0], [0, -I_3 / c_p]]) [dr; b_p](k)``,
    ``dr_m(k) = [I_3  I_3] [dr; b_p](k)``.

    Parameters
    ----------
    c_p : float
        GPS-bias Markov time constant, s (> 0); ``numpy.inf`` gives the random walk.
    s_t : float
        Sampling time, s.

    Returns
    -------
    A : ndarray (6, 6)
        Discrete transition (Euler form, as in the paper).
    C : ndarray (3, 6)
        Position measurement matrix.
    """
    try:
        c_p = float(c_p)
    except (TypeError, ValueError) as exc:
        raise NavlibInputError(f"c_p: expected a number, got {c_p!r}") from exc
    if np.isnan(c_p) or c_p <= 0:
        raise NavlibInputError(f"c_p: must be > 0 (inf for a random walk), got {c_p}")
    s_t = finite_scalar(s_t, "s_t", low=0.0, low_open=True)
    A = np.eye(6)
    A[3:, 3:] *= 1.0 - s_t / c_p
    C = np.hstack([np.eye(3), np.eye(3)])
    return A, C


def _parse(solution, biases, bias_model):
    if solution not in SOLUTIONS:
        raise NavlibInputError(f"solution: expected one of {SOLUTIONS}, got {solution!r}")
    if bias_model not in BIAS_MODELS:
        raise NavlibInputError(f"bias_model: expected one of {BIAS_MODELS}, got {bias_model!r}")
    if biases is None:
        biases = ""
    if not isinstance(biases, str):
        biases = "".join(biases) if all(isinstance(b, str) for b in biases) else None
    if biases is None or any(ch not in BIAS_LETTERS for ch in biases.upper()):
        raise NavlibInputError(
            f"biases: expected a subset of the letters G, A, P (e.g. 'GAP', 'GP', ''), got "
            f"{biases!r}"
        )
    letters = biases.upper()
    if len(set(letters)) != len(letters):
        raise NavlibInputError(f"biases: repeated letter in {biases!r}")
    letters = "".join(ch for ch in BIAS_LETTERS if ch in letters)
    if bias_model == "none" and letters:
        raise NavlibInputError(
            f"bias_model: 'none' neglects the biases, but biases={biases!r} asks to estimate "
            "some; use bias_model='markov' or 'random_walk', or biases=''"
        )
    if bias_model != "none" and not letters:
        raise NavlibInputError(
            f"bias_model: {bias_model!r} needs at least one bias in biases (G, A, P); with "
            "biases='' use bias_model='none'"
        )
    return letters


def state_names(solution: str = "ins_gps", biases: str = "GAP",
                bias_model: str = "markov") -> tuple[str, ...]:
    """State names of a configuration, in model order (docs/assumptions.md, launcher.md §3.1, §3.4).

    Parameters
    ----------
    solution, biases, bias_model : str, optional
        Configuration: one of :data:`SOLUTIONS`, bias letters of ``"GAP"``, ``"markov"`` or
        ``"random_walk"``.
    """
    return sum((_GROUPS[g] for g in _starts(solution, _parse(solution, biases, bias_model))),
               ())


def launcher(solution: str = "ins_gps", biases: str = "GAP", bias_model: str = "markov",
             trajectory=None, *, sensors=DEFAULT_SENSORS, **kw) -> LinearModel:
    """Launcher error model along a trajectory (Beaudoin et al. 2018 eq. 1-5, 8).

    Parameters
    ----------
    solution : {"ins_gps", "ins_gps_att", "ins_gps_rt", "ins_gps_att_rt"}
    biases : str
        Any subset of ``"G"`` (gyro), ``"A"`` (accelerometer), ``"P"`` (GPS position), in any
        order; ``""`` for none.
    bias_model : {"none", "markov", "random_walk"}
        ``"none"`` exactly when ``biases`` is empty.
    trajectory : Trajectory, optional
        Supplies ``T_B^E(k)`` (``attitude``) and ``a_m^B(k)`` (``specific_force``) at each
        sample; default :func:`navlib.trajectory.launcher_ascent` (200 Hz).
    sensors : str, path or SensorSpec
        Sensor preset for the noise values (default ``"launcher_table1"``); the keywords
        below override single values.
    a1_sign : {+1, -1}
        Sign of ``A1`` (how the navigation attitude error drives the closed loop,
        docs/assumptions.md, launcher.md §10b).
    c_g, c_a, c_p : float
        Markov time constants, s (preset: 100).
    gyro_arw, gyro_bias, accel_vrw, accel_bias, sigma_att : float
        Table 1 values in SI (from the preset).
    sigma_gps_vel, sigma_gps_pos, sigma_bp : float
        GPS white noise and position-bias sigma (from the preset, assumed there).
    sigma_wind, sigma0_att, sigma0_vel, sigma0_pos : float
        Assumed values (default :data:`ASSUMED`); ``sigma_wind`` is rad/s per sample of
        step ``s_t`` (default the trajectory's median step).

    Returns
    -------
    LinearModel
        Time-varying over the trajectory samples: ``A`` (N, n, n), ``G`` (N, n, q), ``Qc``
        (q, q) PSDs, ``H`` (m, n) or (N, m, n) for the RT solutions, ``R`` (m, m) with a
        zero block for the noise-free RT pseudo-measurement (eq. 8), ``P0`` (n, n).
        Measurements in order: attitude (att solutions), GPS velocity, GPS position, RT
        attitude difference (RT solutions): 6/9/9/12 rows.
    """
    reject_unknown(kw, _OPTIONS, "launcher")
    letters = _parse(solution, biases, bias_model)
    t, C_b_e, f_b = _samples(trajectory)
    return _model(solution, letters, bias_model, t, C_b_e, f_b, sensors, kw,
                  float(np.median(np.diff(t))))


def _samples(trajectory):
    """``t``, ``C_b_e`` and ``f_b`` of a trajectory (default :func:`launcher_ascent`)."""
    if trajectory is None:
        trajectory = launcher_ascent()
    try:
        t = np.asarray(trajectory.t, dtype=float)
        C_b_e = trajectory.attitude.as_matrix()
        f_b = np.asarray(trajectory.specific_force, dtype=float)
    except AttributeError as exc:
        raise NavlibInputError(
            "trajectory: expected a navlib Trajectory (t, attitude, specific_force)"
        ) from exc
    if t.size < 2:
        raise NavlibInputError(f"trajectory: need at least 2 samples, got {t.size}")
    return t, C_b_e, f_b


def _values(sensors, kw: dict, s_t: float) -> dict:
    """The model's values: preset, :data:`ASSUMED`, then the keywords (validated)."""
    p = {**sensor_values(sensors), **ASSUMED, "a1_sign": 1.0, "s_t": s_t}
    for key, value in kw.items():
        p[key] = finite_scalar(value, key)
    if p["a1_sign"] not in (1.0, -1.0):
        raise NavlibInputError(f"a1_sign: expected +1 or -1, got {p['a1_sign']}")
    for key in _OPTIONS:
        if key != "a1_sign" and not 0 < p[key] < np.inf:
            raise NavlibInputError(f"{key}: must be positive and finite, got {p[key]}")
    return p


def _starts(solution: str, letters: str) -> dict:
    """First state index of each group present in a configuration, in state order."""
    start = {}
    pos = 0
    for g in ["psi", "dv", "dr", *letters] + (["xa", "ref"] if solution.endswith("_rt")
                                               else []):
        start[g] = pos
        pos += len(_GROUPS[g])
    return start


def _state_count(start: dict) -> int:
    """Number of states of a configuration, from :func:`_starts`."""
    return sum(len(_GROUPS[g]) for g in start)


def _model_name(solution: str, letters: str, bias_model: str) -> str:
    """``solution/letters/bias_model``, ``-`` for no bias: the name of a configuration's
    model (:func:`launcher`) and of its steps (:func:`launcher_steps`)."""
    return f"{solution}/{letters or '-'}/{bias_model}"


def _slicer(start: dict):
    """``sl(group, size=3)``: the slice of a group's states, from :func:`_starts`."""

    def sl(group, size=3):
        return slice(start[group], start[group] + size)

    return sl


def _state_dynamics(C_b_e, f_b, solution: str, letters: str, bias_model: str, p: dict):
    """``A`` (N, n, n) along attitudes ``C_b_e`` (N, 3, 3) and specific forces ``f_b``
    (N, 3): the paper's ``F(k)`` (eq. 1-5) and the RT block of docs/assumptions.md, launcher.md
    §3.4."""
    start = _starts(solution, letters)
    n, N = _state_count(start), len(C_b_e)
    sl = _slicer(start)

    I3 = np.eye(3)
    W_ie = skew(EARTH_RATE_ECEF)
    f_e = np.einsum("nij,nj->ni", C_b_e, f_b)
    A = np.zeros((N, n, n))
    A[:, sl("psi"), sl("psi")] = -W_ie
    A[:, sl("dv"), sl("psi")] = skew(f_e)
    A[:, sl("dv"), sl("dv")] = -2.0 * W_ie
    A[:, sl("dr"), sl("dv")] = I3
    tau = {"G": p["c_g"], "A": p["c_a"], "P": p["c_p"]}
    for b in letters:
        if b == "G":
            A[:, sl("psi"), sl("G")] = -C_b_e
        elif b == "A":
            A[:, sl("dv"), sl("A")] = C_b_e
        if bias_model == "markov":
            A[:, sl(b), sl(b)] = -I3 / tau[b]
    if solution.endswith("_rt"):
        A[:, sl("xa", 10), sl("xa", 10)] = rt_dynamics_matrix()
        A[:, sl("xa"), sl("psi")] = p["a1_sign"] * np.swapaxes(C_b_e, 1, 2)
    return A


def _dynamics(C_b_e, f_b, solution: str, letters: str, bias_model: str, p: dict):
    """``A`` (N, n, n), ``G`` (N, n, q) and the PSDs (q,) along attitudes and specific forces
    (eq. 1-5: the paper's ``F(k)`` and noise input; the RT block of docs/assumptions.md, launcher.md
    §3.4)."""
    start = _starts(solution, letters)
    n, N = _state_count(start), len(C_b_e)
    sl = _slicer(start)

    I3 = np.eye(3)
    A = _state_dynamics(C_b_e, f_b, solution, letters, bias_model, p)
    # noise channels: gyro, accel white noise; one driving noise per bias; wind
    q = 3 * len(_noise_groups(solution, letters))
    G = np.zeros((N, n, q))
    G[:, sl("psi"), 0:3] = -C_b_e
    G[:, sl("dv"), 3:6] = C_b_e
    psd = [p["gyro_arw"] ** 2] * 3 + [p["accel_vrw"] ** 2] * 3
    sigma_bias = {"G": p["gyro_bias"], "A": p["accel_bias"], "P": p["sigma_bp"]}
    tau = {"G": p["c_g"], "A": p["c_a"], "P": p["c_p"]}
    for i, b in enumerate(letters):
        G[:, sl(b), 6 + 3 * i:9 + 3 * i] = I3
        psd += [2.0 * sigma_bias[b] ** 2 / tau[b]] * 3
    if solution.endswith("_rt"):
        G[:, sl("ref"), q - 3:q] = I3
        psd += [p["sigma_wind"] ** 2 * p["s_t"]] * 3
    return A, G, np.array(psd)


def _measurements(solution: str, p: dict) -> dict:
    """Measurement kind -> rows (names, per-axis sigma), in the model's order: attitude
    sensor (att solutions), GPS velocity, GPS position, RT attitude difference (RT
    solutions, noise-free)."""
    rows = {}
    if solution.startswith("ins_gps_att"):
        rows["att"] = MeasurementRows(tuple(f"psi_m_{a}" for a in _AXES), p["sigma_att"])
    rows["gnss_vel"] = MeasurementRows(tuple(f"dv_m_{a}" for a in _AXES), p["sigma_gps_vel"])
    rows["gnss_pos"] = MeasurementRows(tuple(f"dr_m_{a}" for a in _AXES), p["sigma_gps_pos"])
    if solution.endswith("_rt"):
        rows["rt"] = MeasurementRows(tuple(f"psi_ref_m_{a}" for a in _AXES), 0.0)
    return rows


def _noise_groups(solution: str, letters: str) -> list:
    return ["wg", "wa", *(f"w{b}" for b in letters)] + (["wind"] if solution.endswith("_rt")
                                                         else [])


def _measurement_matrix(solution: str, letters: str, meas: dict, C_b_e) -> np.ndarray:
    """``H``: [attitude;] GPS velocity; GPS position (+ b_p) [; RT difference, eq. 8], as
    (m, n), or (N, m, n) along the attitudes for the RT solutions."""
    start = _starts(solution, letters)
    n, N = _state_count(start), len(C_b_e)
    sl = _slicer(start)

    I3 = np.eye(3)
    rt = solution.endswith("_rt")
    columns = {"att": ["psi"], "gnss_vel": ["dv"],
               "gnss_pos": ["dr", *(["P"] if "P" in letters else [])]}
    m = 3 * len(meas)
    H = np.zeros((N, m, n)) if rt else np.zeros((m, n))
    for i, kind in enumerate(k for k in meas if k != "rt"):
        for group in columns[kind]:
            H[..., 3 * i:3 * i + 3, sl(group)] = I3
    if rt:
        H[:, m - 3:, sl("psi")] = np.swapaxes(C_b_e, 1, 2)
        H[:, m - 3:, sl("ref")] = I3
    return H


def _model(solution, letters, bias_model, t, C_b_e, f_b, sensors, kw, s_t) -> LinearModel:
    """:func:`launcher` on attitude and specific-force samples (validated configuration)."""
    p = _values(sensors, kw, s_t)
    names = state_names(solution, letters, bias_model)
    start = _starts(solution, letters)
    n = len(names)
    sl = _slicer(start)

    I3 = np.eye(3)
    A, G, psd = _dynamics(C_b_e, f_b, solution, letters, bias_model, p)
    Qc = np.diag(psd)
    noise_groups = _noise_groups(solution, letters)

    meas = _measurements(solution, p)
    H = _measurement_matrix(solution, letters, meas, C_b_e)
    R = np.diag(np.square([rows.sigma for rows in meas.values() for _ in _AXES]))
    meas_names = sum((rows.names for rows in meas.values()), ())

    sigma0 = {"psi": p["sigma0_att"], "dv": p["sigma0_vel"], "dr": p["sigma0_pos"],
              "G": p["gyro_bias"], "A": p["accel_bias"], "P": p["sigma_bp"], "ref": 0.0}
    P0 = np.zeros((n, n))
    for group, sigma in sigma0.items():
        if group in start:
            P0[sl(group), sl(group)] = sigma ** 2 * I3
    noise_names = tuple(f"{g}_{a}" for g in noise_groups for a in _AXES)
    params = {"solution": solution, "biases": letters, "bias_model": bias_model,
              "sensors": sensors if isinstance(sensors, str) else sensors.name, **p}
    return LinearModel(
        state_names=names, A=A, G=G, Qc=Qc, H=H, R=R, t=t, P0=P0,
        measurement_names=meas_names, noise_names=noise_names,
        name=_model_name(solution, letters, bias_model), parameters=params,
    )


@dataclass(frozen=True, eq=False)
class LauncherSteps:
    """A launcher configuration as the Euler transitions ``F_k = I + s_t A(k)`` of the
    steps asked for (the paper's ``A_lc``, docs/assumptions.md, launcher.md §3), computed on demand
    from the trajectory samples instead of held as an ``(N, n, n)`` stack: what the observability
    test reads (:func:`navlib.observability.local_observability`, chunk by chunk), bitwise the
    transitions of ``launcher(...).discretize(method="euler")``. Build with
    :func:`launcher_steps`.

    Attributes
    ----------
    state_names : tuple of str
    t : ndarray (N,)
        Trajectory sample times, s.
    H : ndarray (m, n) or VaryingBlock (N, m, n)
        As :func:`launcher`'s; the RT solutions' formed for the steps read
        (:class:`navlib.models.base.VaryingBlock`).
    method : str
        ``"euler"``: the discretisation these transitions are.
    name : str
    """

    state_names: tuple[str, ...]
    t: np.ndarray
    H: np.ndarray
    method: str
    name: str
    _C_b_e: np.ndarray
    _f_b: np.ndarray
    _configuration: tuple
    _values: dict

    @property
    def n(self) -> int:
        return len(self.state_names)

    def transitions(self, idx) -> np.ndarray:
        """``F[idx]`` (idx.shape + (n, n)) for integer step indices ``idx`` (< N - 1)."""
        flat = np.ravel(idx)
        A = _state_dynamics(self._C_b_e[flat], self._f_b[flat], *self._configuration,
                            self._values)
        A *= (self.t[flat + 1] - self.t[flat])[:, None, None]
        A += np.eye(self.n)  # in place, bitwise I + s_t A: no two chunk-sized temporaries
        return A.reshape(*np.shape(idx), self.n, self.n)


def launcher_steps(solution: str = "ins_gps", biases: str = "GAP",
                   bias_model: str = "markov", trajectory=None, *,
                   sensors=DEFAULT_SENSORS, **kw) -> LauncherSteps:
    """:func:`launcher`'s configuration (same arguments) as its Euler step transitions
    computed on demand (:class:`LauncherSteps`): the observability test of 60 Table 2
    configurations at 30 001 steps then never holds a 188 MB ``A`` stack per model.

    Parameters
    ----------
    solution, biases, bias_model : str, optional
        Configuration: one of :data:`SOLUTIONS`, bias letters of ``"GAP"``, ``"markov"`` or
        ``"random_walk"``.
    trajectory : Trajectory or None, optional
        Reference trajectory (default the launcher ascent).
    sensors : optional
        Sensor values, as :func:`launcher`.
    **kw
        Other keywords of :func:`launcher`.
    """
    reject_unknown(kw, _OPTIONS, "launcher")
    letters = _parse(solution, biases, bias_model)
    t, C_b_e, f_b = _samples(trajectory)
    p = _values(sensors, kw, float(np.median(np.diff(t))))
    H = _measurement_matrix(solution, letters, _measurements(solution, p), C_b_e[:1])
    if solution.endswith("_rt"):      # the RT rows' attitude block varies: formed on demand
        H = VaryingBlock(H[0], slice(H.shape[1] - 3, None), _slicer(_starts(solution, letters))(
            "psi"), np.swapaxes(C_b_e, 1, 2))
    return LauncherSteps(state_names=state_names(solution, letters, bias_model), t=t, H=H,
                         method="euler", name=_model_name(solution, letters, bias_model),
                         _C_b_e=C_b_e, _f_b=f_b, _configuration=(solution, letters, bias_model),
                         _values=p)


_PARAMETER_GROUPS = {"G": "bg", "A": "ba", "P": "bp"}


@dataclass(frozen=True, eq=False)
class LauncherErrorState(ErrorState):
    """A launcher model as the error-state model of :func:`navlib.filters.ekf`.

    Errors are ``estimate - truth`` (``nav_sign = -1``) with the ECEF attitude error ``psi``
    (docs/assumptions.md, launcher.md §3.1); the parameter groups are the biases ``bg``, ``ba``
    (body) and ``bp`` (minus the GPS position bias, E frame), decaying at ``-1/c`` for Markov
    biases. The reference-trajectory block (``x19..x25``, ``psi_ref``, docs/assumptions.md,
    launcher.md §3.4) is the launcher's divergence from its reference: it has no nominal counterpart
    and is not reset. The Jacobians are :func:`launcher`'s ``A``, ``G`` (Euler steps by default, as
    the paper). Build with :meth:`build`.
    """

    @classmethod
    def build(cls, solution: str = "ins_gps", biases: str = "GAP", bias_model: str = "markov",
              *, step_s: float, sensors=DEFAULT_SENSORS, **kw) -> LauncherErrorState:
        """The configuration of :func:`launcher` (same keywords) at IMU step ``step_s``
        (the default ``s_t``).

        Parameters
        ----------
        solution : str, optional
            One of :data:`SOLUTIONS`.
        biases : str, optional
            Bias states, letters of ``"GAP"``.
        bias_model : {"markov", "random_walk"}, optional
            Bias model.
        step_s : float
            IMU step, s.
        sensors : optional
            Sensor values, as :func:`launcher`.
        **kw
            Other keywords of :func:`launcher`.
        """
        reject_unknown(kw, _OPTIONS, "launcher")
        letters = _parse(solution, biases, bias_model)
        step_s = finite_scalar(step_s, "step_s", 0.0, low_open=True)
        model = _model(solution, letters, bias_model, np.zeros(1), np.eye(3)[None],
                       np.zeros((1, 3)), sensors, kw, step_s)
        start = _starts(solution, letters)
        groups = {name: np.arange(start[g], start[g] + 3) for g, name in
                  (("dr", "position"), ("dv", "velocity"), ("psi", "attitude"),
                   ("ref", "reference"), *_PARAMETER_GROUPS.items()) if g in start}
        parameters = tuple(_PARAMETER_GROUPS[b] for b in letters)
        decay = {g: np.diag(model.A[0][np.ix_(groups[g], groups[g])]).copy()
                 for g in parameters}
        reset = np.ones(model.n, dtype=bool)
        if "xa" in start:
            reset[start["xa"]:] = False
        return cls(name="launcher", state_names=model.state_names, Qc=model.Qc, P0=model.P0,
                   groups=groups, parameters=parameters, reset=reset, decay=decay,
                   nav_sign=-1.0, attitude_frame="ecef",
                   measurements=_measurements(solution, model.parameters),
                   default_method="euler", settings=model.parameters)

    @classmethod
    def from_options(cls, options: dict, *, step_s: float, solution: str, biases: str,
                     bias_model: str, **_) -> LauncherErrorState:
        """:meth:`build` from the EKF's keywords (``options`` are :func:`launcher`'s; the
        EKF's GNSS-velocity sigma and simulated sensors do not apply: the launcher takes
        GPS velocity at ``sigma_gps_vel`` and its values from ``sensors``).

        Parameters
        ----------
        options : dict
            Keywords of :func:`launcher`.
        step_s : float
            IMU step, s.
        solution, biases, bias_model : str
            The configuration.
        **_
            The EKF's other keywords, ignored.
        """
        return cls.build(solution, biases, bias_model, step_s=step_s, **options)

    def jacobians(self, nominal):
        """:func:`launcher`'s ``A``, ``G`` along the nominal attitude and specific force."""
        s = self.settings
        A, G, _ = _dynamics(nominal.C_b_e, nominal.f_b, s["solution"], s["biases"],
                            s["bias_model"], s)
        return A, G
