"""Progress bars: drawn with rate and ETA on a terminal, silent in pipes and under --json."""

import io

from springlab import progress


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_bar_on_a_terminal_shows_count_rate_and_eta():
    stream = _Terminal()
    with progress.bar(10, description="rendering", unit="frame", stream=stream) as bar:
        for _ in range(10):
            bar.update(1)
    text = stream.getvalue()
    assert "rendering" in text and "10/10" in text
    assert "frame/s" in text or "s/frame" in text  # the rate
    assert "<" in text  # tqdm's elapsed<remaining: the ETA


def test_a_pipe_gets_no_bar():
    stream = io.StringIO()  # not a terminal
    with progress.bar(10, description="rendering", stream=stream) as bar:
        bar.update(10)
    assert stream.getvalue() == ""


def test_json_output_silences_the_bar_even_on_a_terminal():
    stream = _Terminal()
    with progress.bar(10, description="sweep", enabled=False, stream=stream) as bar:
        bar.update(10)
    assert stream.getvalue() == ""


def test_a_closed_stream_is_not_a_terminal():
    stream = io.StringIO()
    stream.close()
    assert progress.on_terminal(stream) is False
