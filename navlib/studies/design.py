"""The design study of notebook 08: readings of its sweep grids.

Every number in a reading is computed from the table it is given, never typed in; the
functions return text or a table and print nothing (the notebook shows it). The readings of
the mission plans are in :mod:`navlib.studies.plan`, the EKF-against-covariance check in
:mod:`navlib.studies.outliers.reading`. The sensability words
follow :mod:`navlib.metrics`: a state is *sensible* at an epoch when its sensability reaches
``S_THRESHOLD``, and over a span when it is so on at least ``MIN_FRACTION`` of the epochs
(assumption A11 of docs/assumptions.md for the threshold; docs/sweeps.md for the sweep
tables).
"""

from __future__ import annotations

import pandas as pd

from navlib.metrics import MIN_FRACTION, S_THRESHOLD

__all__ = ["GYRO_BIAS_STATES", "NULL_SHARE_TOL", "observability_grid_reading",
           "sensability_grid_reading", "with_gyro_observability"]

GYRO_BIAS_STATES = ("bg_x", "bg_y", "bg_z")
"""The gyro-bias states of the launcher models (``navlib.models.launcher``)."""

NULL_SHARE_TOL = 1e-6
"""Largest share of a gyro-bias state in the unobservable subspace for it to count as
observable (rank reading of the launcher sweep, docs/sweeps.md): the null-space
shares of observable states are round-off, many decades below it."""


def sensability_grid_reading(table: pd.DataFrame, share: float = MIN_FRACTION,
                             s_threshold: float = S_THRESHOLD) -> str:
    """What the rocket design grid (``sweep(..., "sensability")``) says about sg_x and roll.

    Parameters
    ----------
    table : DataFrame
        One row per grid point with ``spin_hz``, ``sigma_sg_ppm``, ``s_frac_sg_x`` (share of
        the epochs with sg_x sensible), ``ratio_sg_x`` (sigma_0 / sigma_end of sg_x),
        ``s_end_roll`` (roll-axis sensability at the end) and ``sigma_end_roll_deg``.
    share : float
        Share of the epochs that makes sg_x sensible over the flight (default
        :data:`navlib.metrics.MIN_FRACTION`).
    s_threshold : float
        Sensability reading of the roll axis at the end (default
        :data:`navlib.metrics.S_THRESHOLD`).

    Returns
    -------
    str
        Lines of text: the (spin, sigma_sg) cells, averaged over the other grid axes, where
        sg_x is sensible, the smallest sigma_sg that does it per spin, the range of the
        sigma ratio, and how often the roll axis is sensible at the end.
    """
    cell = table.groupby(["spin_hz", "sigma_sg_ppm"])[["s_frac_sg_x", "ratio_sg_x",
                                                       "s_end_roll",
                                                       "sigma_end_roll_deg"]].mean()
    ok = cell[cell.s_frac_sg_x >= share]
    part = "half" if share == 0.5 else f"{share:.0%}"
    if len(ok):
        lines = [f"sg_x is sensible on at least {part} of the epochs (mean over the GNSS "
                 f"sigmas) in {len(ok)} of {len(cell)} cells; smallest sigma_sg that does it, "
                 f"per spin:", ok.reset_index().groupby("spin_hz").sigma_sg_ppm.min().to_string()]
    else:
        lines = [f"sg_x is sensible on {part} of the epochs in no cell of this grid"]
    lines.append(f"sigma_0/sigma_end of sg_x ranges {cell.ratio_sg_x.min():.2f} .. "
                 f"{cell.ratio_sg_x.max():.2f}: sensability is relative; a loose prior makes "
                 f"sg_x the best-informed direction without the flight pinning it down in "
                 f"absolute terms")
    roll_ok = (table.s_end_roll >= s_threshold).sum()
    lines.append(f"roll axis sensible at the end in {roll_ok} of {len(table)} points; its "
                 f"1-sigma at the end spans {table.sigma_end_roll_deg.min():.1f} .. "
                 f"{table.sigma_end_roll_deg.max():.1f} deg over the grid")
    return "\n".join(lines)


def with_gyro_observability(table: pd.DataFrame,
                            tol: float = NULL_SHARE_TOL) -> pd.DataFrame:
    """The launcher observability grid (``sweep(..., "observability")``) with two columns
    added: ``gyro_unobservable_share`` (the largest share of a gyro-bias state in the
    unobservable subspace, from the ``unobs_bg_*`` columns) and ``gyro_observable`` (that
    share below ``tol``, :data:`NULL_SHARE_TOL` by default)."""
    share = table[[f"unobs_{name}" for name in GYRO_BIAS_STATES]].max(axis=1)
    return table.assign(gyro_unobservable_share=share, gyro_observable=share < tol)


def observability_grid_reading(table: pd.DataFrame) -> str:
    """What the launcher observability grid says, from :func:`with_gyro_observability`'s
    table (``solution``, ``bias_model``, ``biases``, ``log10_cond``, ``n_unobservable``).

    Returns
    -------
    str
        Lines of text: in how many solution x bias-model cells the gyro biases are
        observable for every bias set, the best and worst median log10 condition number
        over the bias sets, and one line per configuration with unobservable states.
    """
    observable = table.groupby(["solution", "bias_model"]).gyro_observable.all()
    lines = [f"gyro biases observable (rank, mid-mission) in {int(observable.sum())} of "
             f"{observable.size} solution x bias-model cells (all bias sets)"]
    cond = table.pivot_table(index="solution", columns="bias_model", values="log10_cond",
                             aggfunc="median")
    best, worst = cond.stack().idxmin(), cond.stack().idxmax()
    lines.append(f"median log10 cond over the bias sets: best {best} ({cond.stack().min():.1f}), "
                 f"worst {worst} ({cond.stack().max():.1f})")
    for r in table[table.n_unobservable > 0].itertuples():
        lines.append(f"{r.solution}, {r.bias_model}, {r.biases}: {r.n_unobservable} "
                     f"unobservable state(s), gyro-bias share in the null space "
                     f"{r.gyro_unobservable_share:.1e}")
    return "\n".join(lines)
