"""On-frame text: the simulation time and a label, antialiased, in a box at the top left.

Drawn with Pillow (TrueType DejaVu Sans from matplotlib, found without
importing it; Unicode-capable, e.g. Greek letters) in dark text on a
translucent white box, so it reads over any part of the scene.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from PIL import Image

__all__ = ["TextOverlay"]

_TEXT_RGB = np.array([20.0, 20.0, 28.0])  # near-black text
_TEXT_BOX_ALPHA = 0.78  # translucent white box behind the text
_CHANNELS = np.arange(3)


def _composite(region: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """Pixels `region` (uint8, ... x 3) under the translucent box and text of `coverage` (uint8, ... x 1, 255 =
    covered): the box's white at _TEXT_BOX_ALPHA, then the text's colour at the coverage, rounded to bytes."""
    alpha = coverage.astype(np.float32) * (1.0 / 255.0)
    mixed = region.astype(np.float32) * (1.0 - _TEXT_BOX_ALPHA) + 255.0 * _TEXT_BOX_ALPHA
    mixed = mixed * (1.0 - alpha) + _TEXT_RGB * alpha
    return np.clip(mixed + 0.5, 0, 255).astype(np.uint8)


@functools.cache
def _blend_table() -> np.ndarray:
    """`_composite` of every (coverage, byte, channel), 256 x 256 x 3: a frame looks its pixels up instead of
    repeating the arithmetic on its whole box (the same function, so the same bytes)."""
    coverage = np.arange(256, dtype=np.uint8)[:, None, None]
    values = np.broadcast_to(np.arange(256, dtype=np.uint8)[None, :, None], (256, 256, 3))
    return _composite(values, coverage)


def _find_font() -> str | None:
    """Path of matplotlib's DejaVu Sans, found without importing matplotlib."""
    try:
        spec = importlib.util.find_spec("matplotlib")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    for root in spec.submodule_search_locations:
        path = Path(root, "mpl-data", "fonts", "ttf", "DejaVuSans.ttf")
        if path.is_file():
            return str(path)
    return None


class TextOverlay:
    """Dark text on a translucent white box at the top-left of the 3D view."""

    def __init__(
        self, label: str, view_height: int, max_time: float, notes: Sequence[str] = (), time_step: float = 0.01
    ):
        """``label`` on the first line, then ``notes`` (e.g. "motion ×30"), then the time.

        ``max_time`` [s] fixes the width of the time field; ``time_step`` [s]
        (the simulated time between frames) sets its decimals, so a slowed
        video's clock visibly advances every frame.
        """
        from PIL import ImageFont

        self.size = max(11, round(view_height / 22))
        path = _find_font()
        try:
            self.font = ImageFont.truetype(path, self.size) if path else ImageFont.load_default(size=self.size)
        except Exception:  # very old Pillow or unreadable font file
            self.font = ImageFont.load_default()
        self.pad = max(3, self.size // 3)
        self.margin = max(2, self.size // 3)
        self.line_h = int(round(self.size * 1.25))
        self.label = " ".join(str(label).split())  # one line, no control chars
        self.notes = [" ".join(str(n).split()) for n in notes]
        self._decimals = max(2, min(6, math.ceil(-math.log10(max(time_step, 1e-6)) - 1e-9)))
        self._digits = len(f"{max(max_time, 0.0):.{self._decimals}f}")
        self._widths: list[int] | None = None  # of the label and notes [px]
        self._mask: Image.Image | None = None  # their coverage, at the last box size

    def time_text(self, t: float) -> str:
        return f"t = {t:{self._digits}.{self._decimals}f} s"

    def draw(self, view: np.ndarray, t: float) -> None:
        """Draw the box, the label, the notes and the time `t` [s] into `view` (H x W x 3 uint8, in place)."""
        from PIL import ImageDraw

        time_line = self.time_text(t)
        widths = [*self._fixed_widths(), int(math.ceil(self.font.getlength(time_line)))]
        box_w = min(view.shape[1] - self.margin, max(widths) + 2 * self.pad)
        box_h = min(view.shape[0] - self.margin, len(widths) * self.line_h + 2 * self.pad)
        if box_w <= 0 or box_h <= 0:
            return
        # the label and notes never change: their mask is drawn once per box size and the time drawn on a copy,
        # the same strokes in the same order as drawing every line each frame (Pillow's text cost dominated)
        mask = self._fixed_mask(box_w, box_h).copy()
        draw = ImageDraw.Draw(mask)
        draw.text((self.pad, self.pad + (len(widths) - 1) * self.line_h), time_line, fill=255, font=self.font)
        coverage = np.asarray(mask)
        y, x = self.margin, self.margin
        region = view[y : y + box_h, x : x + box_w]
        table = _blend_table()
        drawn = table[0, :, 0][region]  # the box alone where no text covers (the same byte in every channel)
        inked = np.nonzero(coverage)
        drawn[inked] = table[coverage[inked][:, None], region[inked], _CHANNELS]
        view[y : y + box_h, x : x + box_w] = drawn

    def _fixed_lines(self) -> list[str]:
        """The lines above the time: the label and the notes, empty ones left out."""
        return [s for s in (self.label, *self.notes) if s]

    def _fixed_widths(self) -> list[int]:
        """Widths of `_fixed_lines` [px], measured once."""
        if self._widths is None:
            self._widths = [int(math.ceil(self.font.getlength(s))) for s in self._fixed_lines()]
        return self._widths

    def _fixed_mask(self, box_w: int, box_h: int) -> Image.Image:
        """The coverage mask (box_w x box_h, mode L) of `_fixed_lines` alone, drawn once per box size."""
        from PIL import Image, ImageDraw

        if self._mask is None or self._mask.size != (box_w, box_h):
            self._mask = Image.new("L", (box_w, box_h), 0)
            draw = ImageDraw.Draw(self._mask)
            for i, s in enumerate(self._fixed_lines()):
                draw.text((self.pad, self.pad + i * self.line_h), s, fill=255, font=self.font)
        return self._mask
