"""Measurement updates of the closed-loop EKF between its feedback windows
(:func:`navlib.filters.ekf.ekf`; docs/assumptions.md, launcher.md §6.3).

:class:`Epochs` holds what the updates need that does not depend on the data (the rows of
each epoch's measurements in the results, the stacked ``H``, ``R`` of fixed designs);
:class:`WindowUpdates` runs one propagation window: the compiled propagation between
updates (:func:`~navlib.kalman.propagate_kernel`) and the Joseph update at each epoch
(:func:`~navlib.kalman.update_kernel`), both through the one compiled entry point
:func:`~navlib.kalman.fixed_updates_kernel`; :func:`update_records` gathers a window's
results.
"""

from __future__ import annotations

import itertools

import numpy as np

from navlib.filters.measurements import FixedDesign
from navlib.kalman import PINV_RTOL, definite_noise, fixed_updates_kernel, kernel_array

__all__ = ["Epochs", "WindowUpdates", "update_records"]


class Epochs:
    """The update epochs of :func:`ekf` and what does not depend on the data.

    Cached by the tuple of measurements updated together at an epoch: their rows in the
    results and, when all have a fixed design
    (:class:`~navlib.filters.measurements.FixedDesign`), their stacked ``H`` and ``R`` and
    the definiteness of ``R`` (:func:`~navlib.kalman.definite_noise`); the
    innovations of fixed designs are evaluated once per window (:meth:`innovations`).

    Attributes
    ----------
    at : dict
        IMU sample -> ``(epoch, columns, fixed)``: the epoch's ``(measurement, index)``
        pairs, their result rows and ``(H, R, definite)`` or None when one of them is not
        a fixed design (or is updated twice at the epoch; it is then evaluated at the
        update).
    """

    def __init__(self, events, rows, m_all):
        self.rows, self.m_all = rows, m_all
        designs, self.at = {}, {}
        for k, epoch in events.items():
            key = tuple([meas for meas, _ in epoch])
            if key not in designs:
                fixed = (all(isinstance(meas, FixedDesign) for meas in key)
                         and len(set(key)) == len(key))
                designs[key] = (np.concatenate([rows[meas] for meas in key]),
                                _fixed_design(key) if fixed else None)
            self.at[k] = (epoch, *designs[key])
        self._fixed = {}                       # measurement -> (samples, epochs) by sample
        for meas in rows:
            if isinstance(meas, FixedDesign):
                order = np.argsort(meas.index, kind="stable")
                self._fixed[meas] = (meas.index[order], order)

    def innovations(self, w0, nominal) -> np.ndarray:
        """Innovations of the fixed-design measurements at the epochs of the window that
        starts at sample ``w0`` (its samples after ``w0``, and ``w0`` for the first
        window), (samples, m_all): row ``j`` for sample ``j`` of ``nominal``, in each
        measurement's result rows (rows not measured left unset).

        Parameters
        ----------
        w0 : int
            First sample of the window.
        nominal : Nominal
            The nominal trajectory.
        """
        z = np.empty((nominal.t.size, self.m_all))
        for meas, (samples, order) in self._fixed.items():
            lo = np.searchsorted(samples, w0 + 1 if w0 else 0)
            hi = np.searchsorted(samples, w0 + nominal.t.size - 1, side="right")
            if hi > lo:
                j = samples[lo:hi] - w0
                z[j[:, None], self.rows[meas]] = meas.innovations(order[lo:hi], nominal, j)
        return z


def _fixed_design(measurements):
    """``(H, R, definite)`` of fixed-design measurements stacked (:class:`Epochs`)."""
    _, H, R = _stacked([(np.zeros(len(meas.names)), meas.H, meas.R) for meas in measurements])
    return H, R, definite_noise(R)


class WindowUpdates:
    """Updates sample by sample and the compiled propagation between them
    (:func:`~navlib.kalman.fixed_updates_kernel`)
    over the windows of :func:`navlib.filters.ekf.ekf`."""

    def __init__(self, es, kept, observers, epochs):
        self.es, self.kept, self.observers = es, kept, observers
        self.epochs = epochs

    def window(self, x, P, F, Q, w0, nominal):
        """``x``, ``P`` at the end of the window that starts at sample ``w0`` and the
        records of its updates: runs ``(samples, x, P, innovations, columns, NIS, dof)`` of
        consecutive updates with the same measurement rows (arrays with one row per
        update).

        A run of fixed-design updates (when no measurement watches the posterior) is one
        call of :func:`~navlib.kalman.fixed_updates_kernel`; any other update is a run of
        one, evaluated at its sample; the propagation to the window's end is a run of
        none.

        Parameters
        ----------
        x : numpy.ndarray
            Error-state mean at ``w0``, (n,).
        P : numpy.ndarray
            Covariance at ``w0``, (n, n).
        F, Q : numpy.ndarray
            Transition and process noise matrices per sample step of the window.
        w0 : int
            First sample of the window.
        nominal : Nominal
            The nominal trajectory.
        """
        x, P, F, Q = kernel_array(x), kernel_array(P), kernel_array(F), kernel_array(Q)
        z_fixed = self.epochs.innovations(w0, nominal)
        at = self.epochs.at
        steps = F.shape[0]
        updates = [j for j in range(steps + 1) if (j or not w0) and w0 + j in at]
        rec, j0, i = [], 0, 0
        while i < len(updates):
            epoch, cols, fixed = at[w0 + updates[i]]
            if fixed is not None and not self.observers:
                end = i + 1
                while end < len(updates) and at[w0 + updates[end]][1] is cols:
                    end += 1
                samples = np.array(updates[i:end], dtype=np.int64)
                x, P, run = _fixed_run(x, P, F, Q, self.kept, j0, samples,
                                       z_fixed[samples[:, None], cols], fixed)
                rec.append((samples, *run[:3], cols, *run[3:]))
                j0, i = updates[end - 1], end
                continue
            j = updates[i]
            z, H, R, definite = (_evaluated(epoch, nominal, j) if fixed is None
                                 else (z_fixed[j, cols], *fixed))
            R = kernel_array(R)
            x, P, run = _fixed_run(x, P, F, Q, self.kept, j0, np.array([j], dtype=np.int64),
                                   np.reshape(z, (1, -1)),
                                   (H, R, definite_noise(R) if definite is None else definite))
            rec.append((np.array([j]), *run[:3], cols, *run[3:]))
            if self.observers:                 # posterior navigation attitude
                C_post = self.es.correct(nominal.at(slice(j, j + 1)), x[None]).C_b_e[0]
                for meas in self.observers:
                    meas.observe(C_post)
            j0, i = j, i + 1
        n = P.shape[0]
        x, P, _ = _fixed_run(x, P, F, Q, self.kept, j0, np.empty(0, dtype=np.int64),
                             np.empty((0, 0)), (np.empty((0, n)), np.empty((0, 0)), False),
                             steps)
        return x, P, rec


def _fixed_run(x, P, F, Q, kept, j0, samples, z, fixed, j_end=None):
    """:func:`~navlib.kalman.fixed_updates_kernel` over the updates at ``samples`` with
    innovations ``z`` (u, m) and the design ``fixed`` ``(H, R, definite)``, then the
    propagation to sample ``j_end`` (default: none after the last update): the state at
    ``j_end`` and the run's ``(x, P, innovations, NIS, dof)`` by update."""
    H, R, definite = fixed
    u, n, m = samples.size, P.shape[0], z.shape[1]
    run = (np.empty((u, n)), np.empty((u, n, n)), np.empty((u, m)), np.empty(u),
           np.empty(u, dtype=np.int64))
    x, P = fixed_updates_kernel(x, P, F, Q, kept, j0, samples, kernel_array(z), kernel_array(H),
                                kernel_array(R), bool(definite), PINV_RTOL, *run,
                                samples[-1] if j_end is None else j_end)
    return x, P, run


def update_records(rec, nominal, es, kept, keep_covariance, m_all):
    """The results of one window's updates, in the order of the EKF loop's results
    (:func:`navlib.filters.ekf.ekf`): corrected nominal, kept states, covariances (None
    when not kept), sigma, innovations in the model's rows (NaN where not measured), NIS
    and its dof.

    Parameters
    ----------
    rec : list of tuple
        The window's update runs (:meth:`WindowUpdates.window`).
    nominal : Nominal
        The nominal trajectory.
    es : ErrorStateModel
        The error-state model (its ``correct``).
    kept : numpy.ndarray
        Indices of the states kept in the results.
    keep_covariance : bool
        Whether to keep the covariances.
    m_all : int
        Number of measurement rows of the model.
    """
    j_up, dx, P, innov, cols, nis, dof = zip(*rec, strict=True)
    j_up, dx, P = np.concatenate(j_up), np.concatenate(dx), np.concatenate(P)
    full = np.full((j_up.size, m_all), np.nan)
    ends = np.cumsum([0] + [a.shape[0] for a in innov])
    for (a, b), c, values in zip(itertools.pairwise(ends), cols, innov, strict=True):
        full[a:b, c] = values
    sigma = np.sqrt(np.clip(np.diagonal(P, axis1=1, axis2=2), 0, None))
    return (es.correct(nominal.at(j_up), dx), dx[:, kept],
            P if keep_covariance else np.array([None] * j_up.size), sigma, full,
            np.concatenate(nis), np.concatenate(dof))


def _evaluated(epoch, nominal, j):
    """``(z, H, R, None)`` of an epoch's measurements evaluated at sample ``j`` (the
    definiteness of ``R`` left to the update)."""
    return (*_stacked([meas.evaluate(i, nominal, j) for meas, i in epoch]), None)


def _stacked(parts):
    """``z``, ``H`` and block-diagonal ``R`` of the measurements of one epoch stacked."""
    if len(parts) == 1:
        return parts[0]
    z = np.concatenate([p[0] for p in parts])
    H = np.concatenate([p[1] for p in parts])
    R = np.zeros((z.size, z.size))
    ends = np.cumsum([0] + [p[0].size for p in parts])
    for (a, b), p in zip(itertools.pairwise(ends), parts, strict=True):
        R[a:b, a:b] = p[2]
    return z, H, R
