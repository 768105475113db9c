"""The composite video's panel: the phase plane with the trace drawn as time advances.

`media.render_run(composite=True)` passes a `PhasePanel` to `render.render_video(panel=...)`, which
calls it once a frame. Matplotlib draws the static background once; Pillow adds each frame's piece.
Positions in [m] (hinges [rad]), velocities in [m/s] ([rad/s]), times in [s], sizes in pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from springlab.runs.run import Result

from .phase import draw_phase_background, phase_view
from .style import axis_labels, styled


class PhasePanel:
    """`render_video(panel=...)` callback: the phase plane with the trace drawn as time advances.

    The static background (axes, vector field, equilibria, separatrices, the
    exact curve in light dashes) is drawn once by matplotlib into an image;
    each frame then only draws the new piece of the trace and the current
    point into it with Pillow (a few hundred microseconds per frame), so the
    panel costs far less than the 3D view beside it.

    Parameters
    ----------
    result
        the run being rendered.
    height
        panel height [px] (= the 3D view's height).
    width
        panel width [px] (default: `height`, a square panel).
    joints
        joints to show, one phase plane each, stacked (default: every reported joint, at most 3).
    """

    @styled
    def __init__(self, result: Result, height: int, width: int | None = None, joints: Sequence[str] | None = None):
        from PIL import Image, ImageDraw

        self.result = result
        self.height = int(height)
        self.width = int(width or height)
        self.joints = list(joints or list(result.pos)[:3])
        dpi = 100.0
        scale = min(1.6, max(0.5, self.height / 400.0))  # labels legible at 360 px, not crowding 120 px
        figure = Figure(figsize=(self.width / dpi, self.height / dpi), dpi=dpi, layout="constrained")
        canvas = FigureCanvasAgg(figure)
        axes = figure.subplots(len(self.joints), 1, squeeze=False)[:, 0]
        for ax, joint in zip(axes, self.joints):
            field, equilibria, separatrices, xlim, vlim = phase_view(result, joint)
            draw_phase_background(ax, field, equilibria, separatrices, xlim, vlim, arrows=17)
            if joint in result.ref_pos:
                ax.plot(
                    result.ref_pos[joint],
                    result.ref_vel[joint],
                    color="0.45",
                    lw=0.8,
                    ls=(0, (3, 3)),
                    zorder=2,
                    label="exact",
                )
            pos_label, vel_label = axis_labels(result.model, joint)
            ax.set_xlabel(pos_label, fontsize=8 * scale)
            ax.set_ylabel(vel_label, fontsize=8 * scale)
            ax.tick_params(labelsize=7 * scale)
            ax.set_title(f"phase plane: {joint}", fontsize=9 * scale)
        canvas.draw()
        self._background = Image.fromarray(np.asarray(canvas.buffer_rgba())[:, :, :3].copy())
        if self._background.size != (self.width, self.height):  # Agg rounds the figure size
            self._background = self._background.resize((self.width, self.height))
        # data -> pixel maps of each axes (display y is bottom-up; image rows are top-down)
        self._maps = [ax.transData.frozen() for ax in axes]
        self._canvas = self._background.copy()
        self._draw = ImageDraw.Draw(self._canvas)
        self._ImageDraw = ImageDraw
        self._last: list[np.ndarray | None] = [None] * len(self.joints)  # each joint's newest pixel
        self._next_sample = 0
        # contiguous copies: a record's columns are strided views, which numpy copies whole on every search
        self._time = np.ascontiguousarray(result.time)
        self._series = [(np.ascontiguousarray(result.pos[j]), np.ascontiguousarray(result.vel[j])) for j in self.joints]
        self._line = max(2, round(2 * scale))
        self._dot = max(4, round(5 * scale))
        self._color = tuple(int(255 * c) for c in matplotlib.colors.to_rgb("C0"))

    def _pixels(self, index: int, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        points = self._maps[index].transform(np.column_stack([x, v]))
        points[:, 1] = self.height - points[:, 1]
        return points

    def __call__(self, frame: int, t: float) -> np.ndarray:
        """The panel image (height x width x 3 uint8) at time t [s]; frames must come in time order."""
        time = self._time
        end = int(np.searchsorted(time, t, side="right"))  # samples with time <= t
        # t lies in [time[end - 1], time[end]): np.interp on those two samples is the same arithmetic as on the
        # whole record, without its pass over a long run each frame
        near = slice(max(end - 1, 0), end + 1)
        for index, (x, v) in enumerate(self._series):
            xt, vt = float(np.interp(t, time[near], x[near])), float(np.interp(t, time[near], v[near]))
            new = self._pixels(
                index, np.append(x[self._next_sample : end], xt), np.append(v[self._next_sample : end], vt)
            )
            previous = self._last[index]
            if previous is not None:
                new = np.vstack([previous, new])
            if len(new) > 1:
                self._draw.line([tuple(p) for p in new], fill=self._color, width=self._line, joint="curve")
            self._last[index] = new[-1:]
        self._next_sample = end
        image = self._canvas.copy()
        draw = self._ImageDraw.Draw(image)
        for last in self._last:
            assert last is not None  # every joint got its newest pixel in the loop above
            cx, cy = last[0]
            r = self._dot
            draw.ellipse((cx - r, cy - r, cx + r, cy + r), fill=(214, 39, 40), outline=(0, 0, 0))
        return np.asarray(image)
