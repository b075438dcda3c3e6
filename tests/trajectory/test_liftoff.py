"""The pad (its own reading, its fixes) and the knots of thrust changes
(navlib.trajectory.liftoff, docs/assumptions.md FIT4)."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from navlib.trajectory.liftoff import (
    PAD_FIX_BEFORE_S,
    THRUST_CHANGE_S,
    find_liftoff,
    pad_fix_times,
    thrust_change_knots,
)
from navlib.trajectory.position_spline import SPLINE_DEGREE, place_knots

G = 9.80665


@given(st.floats(-10.0, 10.0), st.lists(st.floats(-5.0, 5.0), min_size=1, max_size=8,
                                        unique=True))
def test_the_last_fix_just_before_a_pad_record_moves_to_its_first_sample(t_first, offsets):
    t_g = np.unique(t_first + np.array(offsets))
    moved = pad_fix_times(t_g, t_first, True)
    early = np.flatnonzero((t_g < t_first) & (t_g >= t_first - PAD_FIX_BEFORE_S))
    rest = np.setdiff1d(np.arange(t_g.size), early)
    assert np.array_equal(moved[rest], t_g[rest])
    if early.size:
        at_first = np.any(t_g == t_first)
        assert moved[early[-1]] == t_first or (at_first and np.isnan(moved[early[-1]]))
        assert np.isnan(moved[early[:-1]]).all()
        inside = moved[np.isfinite(moved)]
        assert np.unique(inside).size == inside.size      # no two fixes at one time
    assert np.array_equal(pad_fix_times(t_g, t_first, False), t_g)


def _burn(t, shock_at=None):
    """f along x: 1 g on the pad, 8 g from 0 to 2 s, then 1.5 g of drag backwards; an
    optional 0.05 s shock of 9 g (an ejection charge)."""
    f = np.where(t < 0.0, G, np.where(t < 2.0, 8.0 * G, -1.5 * G))
    if shock_at is not None:
        f = np.where((t >= shock_at) & (t < shock_at + 0.05), 9.0 * G, f)
    return np.column_stack([f, np.zeros_like(t), np.zeros_like(t)])


def _inner(knots):
    return knots[SPLINE_DEGREE + 1:-SPLINE_DEGREE - 1]


def test_a_burnout_gets_dense_knots_and_a_shock_does_not():
    t = np.round(np.arange(-0.3, 6.0, 0.01), 2)
    knots = place_knots(t, 0.1)
    out = thrust_change_knots(knots, t, _burn(t, shock_at=4.0), np.ones(t.size, bool),
                              keep_out=(-0.05, 0.4))
    near = lambda k, at: k[np.abs(k - at) <= THRUST_CHANGE_S]  # noqa: E731
    assert near(_inner(out), 2.0).size > 2 * near(_inner(knots), 2.0).size
    for at in (0.2, 4.0):      # inside the lift-off's span; the shock lasts under 0.2 s
        assert np.array_equal(near(_inner(out), at), near(_inner(knots), at))
    counts = np.diff(np.searchsorted(t, np.unique(_inner(out))))
    assert counts.min() >= 2                   # every interval keeps its samples


def test_an_unresolved_change_gets_no_knots():
    t = np.round(np.arange(-0.3, 6.0, 0.01), 2)
    knots = place_knots(t, 0.1)
    assert np.array_equal(thrust_change_knots(knots, t, _burn(t), t > 3.0), knots)


def test_a_record_too_sparse_for_denser_knots_keeps_its_own():
    t = np.round(np.arange(-0.3, 6.0, 0.1), 1)
    knots = place_knots(t, 0.1)
    assert np.array_equal(thrust_change_knots(knots, t, _burn(t), np.ones(t.size, bool)), knots)


def test_a_pad_is_found_from_its_own_reading_within_the_scale_tolerance():
    t = np.round(np.arange(-0.3, 3.0, 0.01), 2)
    w = np.zeros((t.size, 3))
    for scale, found in ((0.93, True), (1.07, True), (0.85, False)):
        f = _burn(t)
        f[t < 0.0, 0] *= scale                  # an accelerometer off on the pad
        pad = find_liftoff(t, f, w, G, 0.05)
        assert (pad is not None) == found, scale
        if found:
            assert -0.05 < pad[0] <= 0.0
