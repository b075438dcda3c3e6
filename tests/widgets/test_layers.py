"""Layered drawing of kept panel figures (navlib.widgets.layers): the image equals a full
draw, frames are drawn again only where they changed, limits snap to ticks, legends avoid
the data."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.images import pixels

from navlib.plots.figure import detached, subplots
from navlib.widgets.base import render_png
from navlib.widgets.layers import LayeredFigure
from navlib.widgets.panel_layout import place_legend, snap_limits


def _figure():
    fig, axes = subplots(2, 2, figsize=(9, 6), constrained_layout=True)
    t = np.linspace(0.0, 10.0, 200)
    for k, ax in enumerate(axes.flat):
        ax.plot(t, np.exp(-t) + 0.1 * k, label="decay")
        ax.plot(t, 0.5 + 0.1 * np.sin(t), label="wave")
        ax.set_title(f"panel {k}")
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[1, 0].set_yscale("log")
    axes[0, 1].fill_between(t, 0.0, 0.2, alpha=0.3)  # under the grid: part of the frame
    axes[1, 1].axhline(0.3, color="k", linestyle="--")
    axes[1, 1].axvspan(2.0, 3.0, color="0.85", zorder=0)  # under the grid: frame
    fig.suptitle("layers")
    return fig


def _move(fig, scale: float, stretch: float) -> None:
    """New data in place, as a panel's update function gives it."""
    for k, ax in enumerate(fig.axes):
        first, second = ax.lines[0], ax.lines[1]
        t = first.get_xdata() * stretch
        first.set_data(t, scale * np.exp(-t / stretch) + 0.1 * k)
        second.set_data(t, 0.5 * scale + 0.1 * np.sin(t))
        ax.relim()
        ax.autoscale_view()
    fig.axes[3].patches[0].set_x(2.0 * stretch)
    snap_limits(fig)


@settings(max_examples=12, deadline=None)
@given(moves=st.lists(st.tuples(st.sampled_from([0.5, 1.0, 1.02, 3.0]),
                                st.sampled_from([1.0, 1.1, 2.0])), min_size=1, max_size=4))
def test_layered_image_equals_a_full_draw(moves):
    with detached():
        fig = _figure()
        layered = LayeredFigure(fig, dpi=50)
        layered.png()
        for scale, stretch in moves:
            _move(fig, scale, stretch)
            got = pixels(layered.png())
            assert np.array_equal(got, pixels(render_png(fig, 50)))
        assert layered._layered() and layered.full_draws == 1  # the frames were kept


def test_data_within_the_ticks_draws_no_frame_and_new_limits_draw_only_their_axes():
    with detached():
        fig = _figure()
        layered = LayeredFigure(fig, dpi=50)
        layered.png()
        assert (layered.full_draws, layered.frame_draws) == (1, 0)
        line = fig.axes[3].lines[1]
        line.set_ydata(line.get_ydata() + 1e-3)  # inside the snapped limits
        layered.png()
        assert (layered.full_draws, layered.frame_draws) == (1, 0)
        fig.axes[3].set_ylim(-1.0, 3.0)
        layered.png()
        assert layered.full_draws == 1 and 1 <= layered.frame_draws < len(fig.axes)
        fig.suptitle("another title")  # a figure text: everything again
        layered.png()
        assert layered.full_draws == 2


def test_a_frame_redrawn_for_its_x_axis_keeps_its_y_label_as_a_full_draw_places_it():
    """New x limits alone redraw every frame; the y labels stay where the last draw put them
    (their tick labels are the same), and the image is a full draw's, pixel for pixel."""
    with detached():
        fig = _figure()
        layered = LayeredFigure(fig, dpi=50)
        layered.png()
        places = [ax.yaxis.label.get_position() for ax in fig.axes]
        _move(fig, 1.0, 2.0)  # x stretched, y as it was
        got = pixels(layered.png())
        assert layered.frame_draws == len(fig.axes) and layered.full_draws == 1
        assert layered.partial_draws == len(fig.axes)  # y tick labels and titles kept
        assert [ax.yaxis.label.get_position() for ax in fig.axes] == places
        assert all(ax.yaxis._autolabelpos for ax in fig.axes)
        assert np.array_equal(got, pixels(render_png(fig, 50)))


def test_a_secondary_axis_is_kept_with_its_parent_frame():
    """A secondary y axis (panel 01's rev/s scale) is part of its parent's frame, keyed by
    its labels and tickers (its limits follow the parent's): new data inside the limits
    draws no frame, new parent limits draw it again, and each image equals a full draw."""
    with detached():
        fig, ax = subplots(figsize=(6, 4), constrained_layout=True)
        t = np.linspace(0.0, 10.0, 200)
        line, = ax.plot(t, 12.0 * np.tanh(t))
        hz = ax.secondary_yaxis("right", functions=(lambda w: w / 6.0, lambda h: h * 6.0))
        hz.set_ylabel("[rev/s]")
        layered = LayeredFigure(fig, dpi=50)
        layered.png()
        line.set_ydata(12.1 * np.tanh(t))
        assert np.array_equal(pixels(layered.png()), pixels(render_png(fig, 50)))
        assert (layered.full_draws, layered.frame_draws) == (1, 0)
        line.set_ydata(30.0 * np.tanh(t))
        ax.relim()
        ax.autoscale_view()
        snap_limits(fig)
        assert np.array_equal(pixels(layered.png()), pixels(render_png(fig, 50)))
        assert (layered.full_draws, layered.frame_draws) == (1, 1)


def test_snap_limits_rounds_the_data_span_outward_to_ticks_and_keeps_set_limits():
    with detached():
        fig, (free, fixed, log) = subplots(1, 3)
        free.plot([0.0, 23.0], [0.0200, 0.0287])
        fixed.plot([0.0, 1.0], [0.0, 1.0])
        fixed.set_ylim(-0.05, 1.05)
        log.plot([1.0, 2.0], [2e-11, 15.0])
        log.set_yscale("log")
        snap_limits(fig)
        for (low, high), ticks, data in ((free.get_xlim(), free.get_xticks(), (0.0, 23.0)),
                                         (free.get_ylim(), free.get_yticks(), (0.0200, 0.0287))):
            step = np.diff(ticks)[0]
            assert np.isclose(ticks, low).any() and np.isclose(ticks, high).any()
            assert low <= data[0] < low + step and high - step < data[1] <= high
        assert fixed.get_ylim() == pytest.approx((-0.05, 1.05))
        assert log.get_ylim() == pytest.approx((1e-12, 1e2))


def test_a_legend_goes_where_no_data_is_and_says_whether_it_is_clear():
    with detached():
        fig, ax = subplots(figsize=(4, 3))
        t = np.linspace(0.0, 1.0, 500)
        ax.plot(t, 1.0 - t, label="down")  # the lower left and upper right corners are free
        legend = ax.legend(fontsize=7)
        renderer = LayeredFigure(fig).canvas.get_renderer()
        place = place_legend(legend, renderer)
        assert place is not None
        assert legend._get_loc() in (1, 3)  # upper right (first), lower left
        assert np.allclose(place.bounds, legend.get_window_extent(renderer).bounds)
        ax.plot(t, np.full_like(t, 0.95), label="top")
        ax.plot(t, np.full_like(t, 0.05), label="bottom")
        ax.plot(np.full_like(t, 0.5), t, label="middle")
        ax.plot(t, np.full_like(t, 0.5), label="level")
        legend = ax.legend(fontsize=7)
        assert place_legend(legend, renderer) is None  # no place without data


def test_kept_tick_labels_that_new_ones_would_touch_are_drawn_again():
    """New x limits whose first tick label is wide reach the kept bottom y tick label at
    the corner: that label is cleared and drawn again with them, the other y tick labels
    and the title stay, and the image equals a full draw, going there and back."""
    with detached():
        fig, ax = subplots(figsize=(4, 3), constrained_layout=True)
        ax.plot([0.0, 1.0], [0.0, 1.0])
        ax.set_ylim(0.0, 1.0)
        ax.set_title("corner")
        layered = LayeredFigure(fig, dpi=72)
        layered.png()
        for low, high in ((-123456.0, 1.0), (0.0, 1.0), (-123456.0, 2.0)):
            ax.set_xlim(low, high)
            assert np.array_equal(pixels(layered.png()), pixels(render_png(fig, 72)))
        assert layered.full_draws == 1 and layered.partial_draws == 3


def test_font_heights_give_the_layout_matplotlib_computes():
    """The cached line metrics lay out every text as matplotlib's own reading of the font
    tables does: equal extents for several families, sizes, rotations and mathtext."""
    from matplotlib.backends.backend_agg import RendererAgg

    from navlib.widgets.layers import FontHeights

    with detached():
        _, ax = subplots(figsize=(4, 3), dpi=72)
        plain = RendererAgg(288, 216, 72)
        cached = RendererAgg(288, 216, 72)
        heights = FontHeights(72)
        asked = []
        cached._get_font_height_metrics = lambda prop: asked.append(prop) or heights(prop)
        for family in ("DejaVu Sans", "DejaVu Serif", "DejaVu Sans Mono"):
            for size, rotation in ((7, 0), (10, 90), (13.5, 30)):
                for text in ("t [min]", "jg\nWy", r"$10^{-3}$", "eq. (44) 0.0203"):
                    label = ax.text(0.3, 0.4, text, family=family, size=size,
                                    rotation=rotation)
                    assert label.get_window_extent(plain).bounds == \
                        label.get_window_extent(cached).bounds
                    label.remove()
        if not asked:
            pytest.skip("this matplotlib does not ask the renderer for font heights")


def test_a_title_matplotlib_places_at_each_draw_is_drawn_again_with_its_frame():
    """An axes with x tick labels on top keeps its automatic title place (freeze_decorations
    leaves it to matplotlib), so a partial redraw draws its title again: the image equals a
    full draw after new x limits, new y limits (the top tick labels kept; new y tick labels
    wider than the bands of the old ones send that move to a full draw) and a new x scale,
    whose taller tick labels move the title."""
    with detached():
        fig, ax = subplots(figsize=(4, 3), constrained_layout=True)
        ax.plot([0.0, 1.0], [0.0, 1.0])
        ax.xaxis.tick_top()
        ax.set_title("over the tick labels")
        layered = LayeredFigure(fig, dpi=72)
        layered.png()
        for xlim, ylim in (((0.0, 1.0), (0.0, 2.0)), ((0.0, 30.0), (0.0, 2.0)),
                           ((0.0, 30.0), (-5.0, 2.0)), ((1.0, 1e3), (-5.0, 2.0))):
            ax.set_xscale("log" if xlim[0] > 0 else "linear")
            ax.set_xlim(*xlim)
            ax.set_ylim(*ylim)
            assert np.array_equal(pixels(layered.png()), pixels(render_png(fig, 72)))
            assert ax._autotitlepos
        assert layered.partial_draws >= 2
