"""What a drawn figure must not do: a legend covering a marked point, an axis label, a title or other axes
(issue 34 item 4; read by tests/plots/test_settings_figures.py and, on every result's figure,
tests/results/test_display.py)."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg


def _rendered(figure):
    """The Agg renderer of `figure` after a draw that places every artist (the layout engine, each legend's
    best location, the tick labels) but paints no pixel: the boxes below are the ones a saved figure has,
    and rasterising them would cost a quarter of each check for pixels nothing here reads."""
    canvas = figure.canvas if isinstance(figure.canvas, FigureCanvasAgg) else FigureCanvasAgg(figure)
    figure.draw_without_rendering()
    return canvas.get_renderer()


def assert_legends_clear(figure, require: bool = True) -> int:
    """Every legend (the axes' and the figure's) covers no drawn point, no axis label or title and no axes;
    returns the points checked (`require`: the figure has a legend)."""
    renderer = _rendered(figure)
    legends = [axis.get_legend() for axis in figure.axes if axis.get_legend() is not None] + list(figure.legends)
    assert legends or not require
    checked = 0
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for axis in figure.axes:
            assert not box.overlaps(axis.get_window_extent(renderer)), f"a legend covers the axes {axis.get_title()!r}"
            for text in (axis.xaxis.label, axis.yaxis.label, axis.title):
                if text.get_text():
                    assert not box.overlaps(text.get_window_extent(renderer)), f"a legend covers {text.get_text()!r}"
            for line in axis.get_lines():
                if line.get_marker() in (None, "", "None", " "):
                    continue
                x, y = (np.asarray(v, float) for v in line.get_data())
                keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
                for px, py in axis.transData.transform(np.column_stack([x[keep], y[keep]])):
                    assert not box.contains(px, py), f"a legend covers a point of {line.get_label()!r}"
                    checked += 1
    return checked
