"""Video sinks: frames go to ffmpeg (mp4) or Pillow (gif) on a writer thread.

Frames are handed to a writer thread through a bounded queue; the thread feeds
``imageio_ffmpeg.write_frames`` (libx264, ``yuv420p``, preset ``veryfast``),
and ffmpeg encodes in its own process while the next frames are rendered, so
both cores are busy.
"""

from __future__ import annotations

import logging
import os
import queue
import threading
from fractions import Fraction

import numpy as np

__all__ = ["X264_PRESET", "X264_CRF", "Mp4Sink", "GifSink", "WriterThread"]

#: H.264 settings: fast preset, visually clean quality for flat-shaded scenes.
X264_PRESET = "veryfast"
X264_CRF = 20
_QUEUE_FRAMES = 8  # bounded render -> encoder queue


class Mp4Sink:
    """H.264 / yuv420p through imageio-ffmpeg (ffmpeg runs in its own process)."""

    def __init__(self, path: str, width: int, height: int, fps):
        import imageio_ffmpeg

        self._path = path
        self._gen = imageio_ffmpeg.write_frames(
            path,
            (width, height),
            pix_fmt_in="rgb24",
            pix_fmt_out="yuv420p",
            fps=Fraction(fps).limit_denominator(100000),
            codec="libx264",
            quality=None,
            macro_block_size=1,  # sizes are made even by the caller
            ffmpeg_log_level="error",
            output_params=["-preset", X264_PRESET, "-crf", str(X264_CRF), "-movflags", "+faststart", "-f", "mp4"],
        )
        self._gen.send(None)  # starts ffmpeg

    def write(self, frame: np.ndarray) -> None:
        self._gen.send(frame)

    def close(self) -> None:
        self._gen.close()  # closes ffmpeg's stdin and waits for it to finish
        if not os.path.isfile(self._path) or os.path.getsize(self._path) == 0:
            raise RuntimeError("ffmpeg produced no output (see its messages above)")

    def abort(self) -> None:
        # an abandoned video is removed by the caller; imageio-ffmpeg's "no frames have been
        # written" warning (an interrupt before the first frame) would only be noise on stderr
        ffmpeg_log = logging.getLogger("imageio_ffmpeg")
        was_disabled, ffmpeg_log.disabled = ffmpeg_log.disabled, True
        try:
            self._gen.close()
        finally:
            ffmpeg_log.disabled = was_disabled


class GifSink:
    """GIF through imageio's pillow plugin; frame delays keep video time = sim time."""

    def __init__(self, path: str, n_frames: int, fps):
        import imageio.v3 as iio

        # Delays are whole centiseconds; distribute rounding so that frame k
        # starts at round(100 k / fps) cs, i.e. the clock never drifts.
        starts = np.round(np.arange(n_frames + 1) * (100.0 / fps)).astype(int)
        self._durations = [int(d) * 10 for d in np.diff(starts)]  # ms
        self._file = open(path, "wb")
        try:
            self._writer = iio.imopen(self._file, "w", plugin="pillow", extension=".gif")
        except Exception:
            self._file.close()
            raise

    def write(self, frame: np.ndarray) -> None:
        self._writer.write(frame, is_batch=False, duration=self._durations, loop=0)

    def close(self) -> None:
        try:
            self._writer.close()
        finally:
            self._file.close()

    def abort(self) -> None:
        self._writer.images_to_write = []  # drop frames, write nothing
        self.close()


class WriterThread:
    """Feeds frames to a sink on a worker thread through a bounded queue.

    Only the worker thread touches the sink after construction, so sink calls
    never run concurrently. Errors in the worker are re-raised in the caller.
    """

    _STOP = object()

    def __init__(self, sink, maxsize: int = _QUEUE_FRAMES):
        self._sink = sink
        self._queue: queue.Queue = queue.Queue(maxsize)
        self._error: BaseException | None = None
        self._abort = threading.Event()
        self._done = False
        self._thread = threading.Thread(target=self._run, name="springlab-video-writer", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while True:
                item = self._queue.get()
                if item is self._STOP or self._abort.is_set():
                    break
                self._sink.write(item)
            if self._abort.is_set():
                self._sink.abort()
            else:
                self._sink.close()
        except BaseException as err:  # noqa: BLE001 - handed to the caller
            self._error = err
            try:
                self._sink.abort()
            except BaseException:  # noqa: BLE001
                pass

    def _check(self) -> None:
        if self._error is not None:
            raise RuntimeError(f"video encoding failed: {self._error}") from self._error

    def _put(self, item) -> None:
        while True:
            self._check()
            if not self._thread.is_alive():
                raise RuntimeError("video encoder thread stopped unexpectedly")
            try:
                self._queue.put(item, timeout=0.2)
                return
            except queue.Full:
                continue

    def put(self, frame: np.ndarray) -> None:
        self._put(frame)

    def finish(self) -> None:
        """Flush all frames, close the sink (finishes the file), raise on error."""
        self._put(self._STOP)
        self._thread.join()
        self._done = True
        self._check()

    def abort(self) -> None:
        """Stop as soon as possible, discarding queued frames."""
        if self._done:
            return
        self._abort.set()
        try:
            while True:
                self._queue.get_nowait()
        except queue.Empty:
            pass
        try:
            self._queue.put_nowait(self._STOP)
        except queue.Full:  # pragma: no cover - queue was just drained
            pass
        self._thread.join(timeout=30)
        self._done = True
