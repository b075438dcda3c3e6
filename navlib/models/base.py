"""Linear error models: the continuous model type, its discrete form, and the error-state
protocol of the filters.

Every model carries ``state_names``; :meth:`LinearModel.subset` deletes rows and columns
consistently (Beaudoin et al. 2018 §2.1: "corresponding lines and columns are
eliminated"); :meth:`LinearModel.discretize` returns a :class:`DiscreteModel` with the
arrays that ``navlib.observability`` and ``navlib.metrics`` take (docs/library.md).

:class:`ErrorStateModel` is what the closed-loop EKF (:func:`navlib.filters.ekf`) needs from
an error model: the state layout as index arrays, which states are reset after feedback,
``jacobians(nominal)`` along the estimate, ``correct(nominal, dx)`` and the Jacobian of the
reset for the covariance.
:class:`ErrorState` implements the layout-driven part (IMU compensation, feedback with the
attitude reset); the launcher and 21-state ECEF models subclass it with their Jacobians.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple, Protocol

import numpy as np
import pandas as pd

from navlib.discretize import chain, discretize_steps
from navlib.errors import NavlibInputError
from navlib.rotations import exp_so3, skew

__all__ = ["HOLDS", "DiscreteModel", "ErrorState", "ErrorStateModel", "LinearModel",
           "MeasurementRows", "Nominal", "VaryingBlock", "state_indices"]

HOLDS = ("left", "mean")
"""How a trajectory model's matrices are held over one step (see LinearModel.discretize)."""


def _stack(matrix, n_samples: int) -> np.ndarray:
    matrix = np.asarray(matrix, dtype=float)
    return np.broadcast_to(matrix, (n_samples, *matrix.shape)) if matrix.ndim == 2 else matrix


@dataclass(frozen=True, eq=False)
class DiscreteModel:
    """A discrete error model at its step or measurement epochs (docs/library.md).

    Attributes
    ----------
    t : ndarray (N,)
        Epoch times, s.
    F, Q : ndarray (N-1, n, n)
        ``F[k]`` maps epoch k to k+1; ``Q[k]`` is the process noise added over that step.
    H : ndarray (N, m, n)
    R : ndarray (N, m, m)
    state_names, measurement_names : tuple of str
    P0 : ndarray (n, n) or None
        Default initial covariance, when the model has one.
    """

    t: np.ndarray
    F: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    R: np.ndarray
    state_names: tuple[str, ...]
    measurement_names: tuple[str, ...] = ()
    P0: np.ndarray | None = None

    @property
    def n(self) -> int:
        return len(self.state_names)

    @property
    def measured(self) -> np.ndarray:
        """Whether each epoch measures anything (a non-zero row of ``H``; an outage or an
        epoch between fixes has none), bool (N,)."""
        return np.any(np.asarray(self.H) != 0.0, axis=(1, 2))

    def window(self, t_start: float, t_end: float) -> DiscreteModel:
        """The epochs inside the closed interval ``[t_start, t_end]`` (docs/assumptions.md A12).

        Parameters
        ----------
        t_start, t_end : float
            Interval, s.

        Returns
        -------
        DiscreteModel
            The model on the epochs inside.

        Raises
        ------
        NavlibInputError
            If fewer than two epochs lie inside.
        """
        sel = np.flatnonzero((self.t >= t_start - 1e-9) & (self.t <= t_end + 1e-9))
        if sel.size < 2:
            raise NavlibInputError(
                f"window [{t_start}, {t_end}] s holds {sel.size} epoch(s); need at least 2 "
                f"(model spans {self.t[0]:.3g}..{self.t[-1]:.3g} s)"
            )
        return replace(self, t=self.t[sel], F=self.F[sel[:-1]], Q=self.Q[sel[:-1]],
                       H=self.H[sel], R=self.R[sel])

    def index(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in ``state_names``."""
        return state_indices(self.state_names, names)


def state_indices(state_names: Sequence[str], names: Sequence[str]) -> np.ndarray:
    """Positions of ``names`` in ``state_names``; NavlibInputError naming the unknown ones.

    Parameters
    ----------
    state_names : sequence of str
        The model's states.
    names : sequence of str
        States to find.

    Returns
    -------
    numpy.ndarray
        Their indices.

    Raises
    ------
    NavlibInputError
        Naming the unknown ones.
    """
    lookup = {name: i for i, name in enumerate(state_names)}
    missing = [name for name in names if name not in lookup]
    if missing:
        raise NavlibInputError(f"unknown state name(s) {missing}; model has {list(state_names)}")
    return np.array([lookup[name] for name in names], dtype=int)


@dataclass(frozen=True, eq=False)
class LinearModel:
    """Continuous linear error model ``dx/dt = A x + G w``, ``y_k = H x_k + v_k``.

    Constant models hold single matrices; trajectory models hold stacks over ``t`` (the
    matrices at each sample, held constant over the following step).

    Attributes
    ----------
    state_names : tuple of str
    A : ndarray (n, n) or (N, n, n)
    G : ndarray (n, q) or (N, n, q)
    Qc : ndarray (q, q)
        Power spectral density of ``w``.
    H : ndarray (m, n) or (N, m, n)
    R : ndarray (m, m) or (N, m, m)
        Discrete measurement-noise covariance.
    t : ndarray (N,) or None
        Sample times of a trajectory model; None for a constant model.
    P0 : ndarray (n, n) or None
        Default initial covariance.
    measurement_names, noise_names : tuple of str
    name : str
    parameters : dict
        The assumed values the builder used.
    """

    state_names: tuple[str, ...]
    A: np.ndarray
    G: np.ndarray
    Qc: np.ndarray
    H: np.ndarray
    R: np.ndarray
    t: np.ndarray | None = None
    P0: np.ndarray | None = None
    measurement_names: tuple[str, ...] = ()
    noise_names: tuple[str, ...] = ()
    name: str = ""
    parameters: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.state_names)

    @property
    def time_varying(self) -> bool:
        return self.t is not None

    def index(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in ``state_names``."""
        return state_indices(self.state_names, names)

    def subset(self, names: Sequence[str]) -> LinearModel:
        """Keep only the states ``names`` (in that order), deleting rows and columns."""
        keep = self.index(names)
        P0 = None if self.P0 is None else self.P0[np.ix_(keep, keep)]
        return replace(
            self, state_names=tuple(names), A=self.A[..., keep[:, None], keep],
            G=self.G[..., keep, :], H=self.H[..., :, keep], P0=P0,
        )

    def discretize(self, dt_s: float | None = None, n_epochs: int | None = None,
                   method: str = "expm", epochs=None, hold: str = "left") -> DiscreteModel:
        """Discrete ``F_k, Q_k`` (and ``H_k, R_k``) at steps or measurement epochs.

        Parameters
        ----------
        dt_s : float, optional
            Step for a constant model (required then); ignored for trajectory models,
            whose steps come from ``t``.
        n_epochs : int, optional
            Number of epochs for a constant model (default ``n + 1``).
        method : {"expm", "series", "euler"}
            Matrix exponential + Van Loan (default), the same with Van Loan's integral by
            its Taylor series (fast for short IMU steps), or the papers' Euler form
            (see :mod:`navlib.discretize`).
        epochs : array of int, optional
            Sample indices of the measurement epochs of a trajectory model; per-step
            transitions are chained between them (docs/assumptions.md A8). Default: every
            sample.
        hold : {"left", "mean"}
            Matrices used over the step ``[t_j, t_j+1]`` of a trajectory model: the left
            sample (the papers' ``A(k)``, first order in the step) or the mean of the two
            samples (trapezoidal first Magnus term, second order: on a 1.5 Hz spinning
            flight at 100 Hz the 1 s transition error drops from 8e-2 to 8e-4).
        """
        if self.t is None:
            if dt_s is None:
                raise NavlibInputError("dt_s: a constant model needs a step length")
            n_epochs = self.n + 1 if n_epochs is None else int(n_epochs)
            if n_epochs < 2:
                raise NavlibInputError(f"n_epochs: need at least 2, got {n_epochs}")
            F1, Q1 = discretize_steps(self.A[None], self.G, self.Qc, dt_s, method)
            t = np.arange(n_epochs) * float(dt_s)
            F = np.broadcast_to(F1, (n_epochs - 1, self.n, self.n))
            Q = np.broadcast_to(Q1, (n_epochs - 1, self.n, self.n))
            return DiscreteModel(t, F, Q, _stack(self.H, n_epochs), _stack(self.R, n_epochs),
                                 self.state_names, self.measurement_names, self.P0)
        if hold not in HOLDS:
            raise NavlibInputError(f"hold: expected one of {HOLDS}, got {hold!r}")
        n_samples = self.t.size
        epochs = np.arange(n_samples) if epochs is None else np.asarray(epochs, dtype=int)
        if (epochs.ndim != 1 or epochs.size < 2 or epochs[0] < 0
                or epochs[-1] >= n_samples or np.any(np.diff(epochs) <= 0)):
            raise NavlibInputError(
                f"epochs: expected >= 2 increasing sample indices in [0, {n_samples - 1}]"
            )
        span = slice(int(epochs[0]), int(epochs[-1]) + 1)
        A = _stack(self.A, n_samples)[span]
        G = _stack(self.G, n_samples)[span]
        if hold == "mean":
            A, G = 0.5 * (A[:-1] + A[1:]), 0.5 * (G[:-1] + G[1:])
        else:
            A, G = A[:-1], G[:-1]
        F_steps, Q_steps = discretize_steps(A, G, self.Qc, np.diff(self.t[span]), method)
        if epochs.size == F_steps.shape[0] + 1:
            F, Q = F_steps, Q_steps
        else:
            F, Q = chain(F_steps, Q_steps, epochs - epochs[0])
        return DiscreteModel(self.t[epochs], F, Q, np.array(_stack(self.H, n_samples)[epochs]),
                             np.array(_stack(self.R, n_samples)[epochs]), self.state_names,
                             self.measurement_names, self.P0)

    def describe(self) -> pd.DataFrame:
        """One row per state: name and initial standard deviation when P0 is known."""
        sigma = np.sqrt(np.diag(self.P0)) if self.P0 is not None else np.full(self.n, np.nan)
        return pd.DataFrame({"state": list(self.state_names), "sigma0": sigma})


# --- error-state protocol of the closed-loop filters ------------------------------------------


@dataclass(frozen=True, eq=False)
class Nominal:
    """The filter's nominal (estimated) state over ``K`` IMU samples.

    Attributes
    ----------
    t : ndarray (K,)
    position, velocity : ndarray (K, 3)
        ECEF position (m) and velocity (m/s) of the strapdown mechanisation.
    C_b_e : ndarray (K, 3, 3)
        Body -> ECEF attitude.
    f_b, w_ib_b : ndarray (K, 3)
        IMU specific force and inertial rate compensated with the parameter estimates.
    parameters : dict
        Parameter estimates (K, 3) by group (``bg``, ``ba``, ``sg``, ``sa``, ``bp``), in the
        model's convention, decayed to each sample.
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    C_b_e: np.ndarray
    f_b: np.ndarray
    w_ib_b: np.ndarray
    parameters: dict

    def at(self, index) -> Nominal:
        """The samples ``index`` (an index array or slice)."""
        return Nominal(self.t[index], self.position[index], self.velocity[index],
                       self.C_b_e[index], self.f_b[index], self.w_ib_b[index],
                       {g: v[index] for g, v in self.parameters.items()})


class MeasurementRows(NamedTuple):
    """Rows of one measurement kind in an error model: their names and per-axis sigma."""

    names: tuple[str, ...]
    sigma: float


class ErrorStateModel(Protocol):
    """What the closed-loop EKF (:mod:`navlib.filters.ekf`) needs from an error model.

    Attributes
    ----------
    name : str
    state_names : tuple of str
    Qc : ndarray (q, q)
        Power spectral density of the noise input of :meth:`jacobians`' ``G``.
    P0 : ndarray (n, n)
        Default initial covariance.
    groups : dict
        State layout: group -> indices (3,). ``position``, ``velocity``, ``attitude`` always;
        parameter groups ``bg``, ``ba`` (gyro, accelerometer biases), ``sg``, ``sa`` (scale
        factors), ``bp`` (GNSS position bias) and ``reference`` (reference-trajectory
        attitude) when the model has them.
    parameters : tuple of str
        The parameter groups, estimated in the nominal state and fed back.
    reset : ndarray (n,) of bool
        States zeroed after feedback (those with a nominal counterpart).
    decay : dict
        Parameter group -> continuous decay rates (3,), 1/s (0 for random walks): nominal
        estimates decay as ``exp(rate t)`` between feedbacks.
    nav_sign : float
        ``+1`` when errors are ``true - estimate``, ``-1`` for ``estimate - true``.
    attitude_frame : {"ecef", "body"}
        ``C_true = exp(S(psi)) C_hat`` (ECEF ``psi``) or ``C_hat exp(S(dtheta))`` (body).
    measurements : dict
        Measurement kind (``gnss_pos``, ``gnss_vel``, ``att``, ``rt``) -> :class:`MeasurementRows`,
        in the model's measurement order: the kinds the model uses.
    default_method : str
        Per-step discretisation the filter uses unless told otherwise.
    settings : dict
        The values the model was built with (its builder's ``parameters``).
    """

    name: str
    state_names: tuple[str, ...]
    Qc: np.ndarray
    P0: np.ndarray
    groups: Mapping[str, np.ndarray]
    parameters: tuple[str, ...]
    reset: np.ndarray
    decay: Mapping[str, np.ndarray]
    nav_sign: float
    attitude_frame: str
    measurements: Mapping[str, MeasurementRows]
    default_method: str
    settings: Mapping

    def jacobians(self, nominal: Nominal) -> tuple[np.ndarray, np.ndarray]:
        """Continuous ``A`` (K, n, n) and noise input ``G`` (K, n, q) along ``nominal``."""

    def compensate(self, parameters: Mapping, f_b, w_ib_b) -> tuple[np.ndarray, np.ndarray]:
        """IMU samples (K, 3) compensated with parameter estimates (K, 3) by group.

        Parameters
        ----------
        parameters : Mapping
            Estimates by group (``ba``, ``bg``, ``sa``, ``sg``), each (K, 3).
        f_b : numpy.ndarray
            Specific force, m/s^2, (K, 3).
        w_ib_b : numpy.ndarray
            Angular rate, rad/s, (K, 3).

        Returns
        -------
        tuple of numpy.ndarray
            Compensated ``(f_b, w_ib_b)``.
        """

    def correct(self, nominal: Nominal, dx) -> Nominal:
        """``nominal`` corrected with error-state estimates ``dx`` (K, n) (feedback).

        Parameters
        ----------
        nominal : Nominal
            The nominal trajectory.
        dx : numpy.ndarray
            Error-state estimates, (K, n).

        Returns
        -------
        Nominal
            The corrected trajectory.
        """

    def reset_jacobian(self, dx) -> np.ndarray:
        """Jacobian (n, n) of the error state across the feedback of ``dx`` (n,): the
        covariance after the reset is ``J P J'``."""


@dataclass(frozen=True, eq=False)
class ErrorState:
    """IMU compensation and feedback of an :class:`ErrorStateModel` from its layout.

    The attributes are those of :class:`ErrorStateModel`; subclasses add :meth:`jacobians`.
    """

    name: str
    state_names: tuple[str, ...]
    Qc: np.ndarray
    P0: np.ndarray
    groups: dict
    parameters: tuple[str, ...]
    reset: np.ndarray
    decay: dict
    nav_sign: float
    attitude_frame: str
    measurements: dict
    default_method: str
    settings: dict

    @property
    def n(self) -> int:
        return len(self.state_names)

    def compensate(self, parameters, f_b, w_ib_b):
        """``f = (f_hat - b_a) / (1 + s_a)``, likewise ``omega`` with ``b_g, s_g``, for the
        groups the model holds (the IMU inverse model, docs/assumptions.md A7).

        Parameters
        ----------
        parameters : Mapping
            Estimates by group (``ba``, ``bg``, ``sa``, ``sg``), each (K, 3).
        f_b : numpy.ndarray
            Specific force, m/s^2, (K, 3).
        w_ib_b : numpy.ndarray
            Angular rate, rad/s, (K, 3).

        Returns
        -------
        tuple of numpy.ndarray
            Compensated ``(f_b, w_ib_b)``.
        """
        f = f_b - parameters["ba"] if "ba" in parameters else f_b
        w = w_ib_b - parameters["bg"] if "bg" in parameters else w_ib_b
        if "sa" in parameters:
            f = f / (1.0 + parameters["sa"])
        if "sg" in parameters:
            w = w / (1.0 + parameters["sg"])
        return f, w

    def correct(self, nominal: Nominal, dx) -> Nominal:
        """Feedback: position and velocity move by ``nav_sign dx``, the attitude by
        ``exp(S(dx_att))`` on the side of :attr:`attitude_frame`, parameters by ``dx``.

        Parameters
        ----------
        nominal : Nominal
            The nominal trajectory.
        dx : numpy.ndarray
            Error-state estimates, (K, n).

        Returns
        -------
        Nominal
            The corrected trajectory.
        """
        s = self.nav_sign
        g = self.groups
        E = exp_so3(dx[:, g["attitude"]])
        C = nominal.C_b_e @ E if self.attitude_frame == "body" else E @ nominal.C_b_e
        return replace(nominal, position=nominal.position + s * dx[:, g["position"]],
                       velocity=nominal.velocity + s * dx[:, g["velocity"]], C_b_e=C,
                       parameters={p: v + dx[:, g[p]] for p, v in nominal.parameters.items()})


    def reset_jacobian(self, dx) -> np.ndarray:
        """Identity but for the attitude block: after ``C_hat <- exp(S(a)) C_hat`` (ECEF
        error ``C = exp(S(psi)) C_hat``) the error left is ``(I + S(a)/2) (psi - a)`` to first
        order; after ``C_hat <- C_hat exp(S(a))`` (body error) ``I - S(a)/2``."""
        J = np.eye(self.n)
        att = self.groups["attitude"]
        J[np.ix_(att, att)] += (-0.5 if self.attitude_frame == "body" else 0.5) * skew(dx[att])
        return J


class VaryingBlock:
    """A stack of ``N`` matrices equal to ``fixed`` (r, c) except the block
    ``fixed[rows, cols]``, which is ``blocks[k]`` in matrix ``k``, formed for the indices
    asked for (``stack[idx]``: an int, a slice or an integer array; ``numpy.asarray`` forms
    it whole). A reader of a few steps of a long mission (the observability test at every
    200th step) then never allocates the (N, r, c) stack: the launcher's RT measurement
    matrices (:func:`navlib.models.launcher.launcher_steps`) are 80 MB at 200 Hz over 150 s.

    Parameters
    ----------
    fixed : ndarray (r, c)
        The matrix outside the varying block.
    rows, cols : slice
        The varying block's place.
    blocks : ndarray (N, p, q)
        The block of each matrix.
    """

    def __init__(self, fixed, rows: slice, cols: slice, blocks):
        self.fixed, self.rows, self.cols = np.asarray(fixed, dtype=float), rows, cols
        self.blocks = np.asarray(blocks, dtype=float)
        self.shape = (self.blocks.shape[0], *self.fixed.shape)
        self.ndim, self.dtype = 3, self.fixed.dtype

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, idx) -> np.ndarray:
        blocks = self.blocks[idx]
        out = np.empty((*blocks.shape[:-2], *self.fixed.shape))
        out[...] = self.fixed
        out[..., self.rows, self.cols] = blocks
        return out

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        out = self[:]
        return out if dtype is None else out.astype(dtype)
