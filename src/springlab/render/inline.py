"""A rendered run that shows itself in a notebook: `springlab.video(result)` -> `Video`.

The video is embedded in the HTML as a base64 data URI (`<video src="data:video/mp4;base64,...">`), not
referenced by path: a notebook's HTML is served from the notebook server's root and saved with the
notebook (nbconvert, a shared .ipynb, a rendered notebook on a web page), where a file path next to the
kernel's working directory does not resolve; the embedded clip plays wherever the notebook is opened. The
cost is size (a base64 clip is 4/3 of the mp4, e.g. ~0.1-1 MB for a few seconds at 640 x 480), which is why
`video` renders the run's first seconds at a notebook's size by default. No new dependency: mediapy would
do the same embedding, and springlab already encodes H.264 itself (render.sink).
"""

from __future__ import annotations

import base64
import dataclasses
import html
import os
import pathlib
import tempfile

from springlab.runs.run import Result

from . import media

#: the mime type of each format `video` writes, by extension
MIME = {".mp4": "video/mp4", ".gif": "image/gif"}


@dataclasses.dataclass(frozen=True)
class Video:
    """A rendered video held in memory: `data` (the file's bytes), `mime`, its size [px], `fps`, `frames`,
    and `path` where it was written (None: rendered to a temporary file, now removed)."""

    data: bytes = dataclasses.field(repr=False)
    mime: str
    width: int
    height: int
    fps: float
    frames: int
    path: str | None = None
    label: str = ""

    @property
    def duration_s(self) -> float:
        """Length of the video [s] (frames / fps)."""
        return self.frames / self.fps

    def __repr__(self) -> str:
        where = f" at {self.path}" if self.path else ""
        return (
            f"<Video {self.label}: {self.width} x {self.height} px, {self.frames} frames at {self.fps:g} fps"
            f" ({self.duration_s:.3g} s), {len(self.data) / 1e3:.0f} kB {self.mime}{where}>"
        )

    def data_uri(self) -> str:
        """The video as a `data:` URI (base64), what `_repr_html_` embeds."""
        return f"data:{self.mime};base64," + base64.b64encode(self.data).decode("ascii")

    def _repr_html_(self) -> str:
        """An HTML5 <video> (an <img> for a GIF) with the clip embedded: plays inline in Jupyter."""
        title = html.escape(self.label)
        if self.mime == "image/gif":
            return f'<img src="{self.data_uri()}" width="{self.width}" height="{self.height}" alt="{title}">'
        return (
            f'<video controls loop muted playsinline width="{self.width}" height="{self.height}" title="{title}"'
            f' src="{self.data_uri()}"></video>'
        )


def video(
    result: Result,
    output: str | os.PathLike | None = None,
    *,
    duration: float | None = 5.0,
    width: int = 480,
    height: int = 360,
    fps: int = 30,
    **options: object,
) -> Video:
    """Render `result` (springlab.run) as a video that shows itself inline in Jupyter.

    Parameters
    ----------
    result
        the run.
    output
        also keep the video here (.mp4 or .gif); None: a temporary file, removed once read.
    duration
        seconds of simulation shown [s] (None: the whole run).
    width, height
        size of the 3D view [px].
    fps
        frames per second of the video.
    **options
        passed to `springlab.render.media.render_run` (`composite`, `slow_motion`, `exaggerate`,
        `antialias`, `progress`).

    Returns
    -------
    Video
        the clip in memory; `_repr_html_` embeds it.

    Raises
    ------
    BadInputError
        bad size, fps or extension.
    SpringlabError
        no off-screen OpenGL context or the encoder failed.
    """
    options.setdefault("progress", False)
    with tempfile.TemporaryDirectory(prefix="springlab-video-") as folder:
        target = pathlib.Path(output) if output is not None else pathlib.Path(folder) / "video.mp4"
        done = media.render_run(
            result,
            target,
            fps=fps,
            width=width,
            height=height,
            duration=duration,
            **options,  # type: ignore[arg-type]
        )
        data = target.read_bytes()
    return Video(
        data,
        MIME.get(target.suffix.lower(), "video/mp4"),
        int(done["width"]),
        int(done["height"]),
        float(done["fps"]),
        int(done["frames"]),
        str(target) if output is not None else None,
        f"{result.scene} / {result.scenario}",
    )
