"""Interrupted work leaves nothing behind: real signals sent to real `springlab` processes.

SIGTERM (timeouts, batch schedulers, cluster managers) is handled like Ctrl-C
(SIGINT): partial files removed, one line on stderr, exit 128 + the signal
number (143, 130). An interrupted demo leaves its folder marked incomplete,
never a report that looks whole.
"""

import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from springlab.demo import steps as demo


def _start(*argv, cwd):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    env.setdefault("MUJOCO_GL", "egl")
    return subprocess.Popen(
        [sys.executable, "-m", "springlab", *argv],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a shell without job control starts background jobs with SIGINT ignored, and the child
        # inherits that; a user's springlab runs with the default disposition, so the test does too
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def _wait_for(condition, proc, timeout=600.0):  # a ceiling for loaded CI machines, not a measurement
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"springlab ended (exit {proc.returncode}) before the signal: {err[-2000:]}")
        time.sleep(0.02)
    proc.kill()
    pytest.fail("the condition to send the signal never came")


def _finish(proc):
    out, err = proc.communicate(timeout=600)
    return proc.returncode, out, err


def _hidden_parts(folder: pathlib.Path):
    return [p.name for p in folder.rglob(".*.part*")]


@pytest.mark.slow
@pytest.mark.parametrize(
    "signum, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")]
)
def test_a_signalled_render_removes_its_partial_video(tmp_path, signum, code, word):
    proc = _start("render", "slider", "free", "--duration", "60", "--output", "long.mp4", cwd=tmp_path)
    # the hidden temporary file is the partial video: signal while it is being written
    _wait_for(lambda: _hidden_parts(tmp_path), proc)
    time.sleep(0.3)
    proc.send_signal(signum)
    returncode, _, err = _finish(proc)
    assert returncode == code, err
    assert err.strip().splitlines() == [f"springlab: {word}"]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.parametrize(
    "signum, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")]
)
def test_a_signalled_demo_leaves_its_folder_marked_incomplete(tmp_path, signum, code, word):
    out = tmp_path / "out"
    out.mkdir()
    # a report from an earlier run: left in place it would describe files this run is replacing
    (out / demo.REPORT_NAME).write_text("<html>an earlier, complete report</html>")
    proc = _start("demo", "--output", "out", cwd=tmp_path)
    # signal once the demo is writing scenario outputs (the core step is under way)
    _wait_for(lambda: any(out.rglob("summary.json")), proc)
    proc.send_signal(signum)
    returncode, _, err = _finish(proc)
    assert returncode == code, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"springlab: {word}") and "incomplete" in lines[0]
    marker = out / demo.INCOMPLETE_MARKER
    assert marker.exists() and "has not finished" in marker.read_text()
    assert not (out / demo.REPORT_NAME).exists()
    assert _hidden_parts(out) == []


def test_sigterm_in_process_unwinds_like_ctrl_c(tmp_path, capsys, monkeypatch):
    # the handler is installed only while main() runs, and the previous one comes back
    from springlab.cli import main as cli
    from springlab.cli.commands import catalogue

    def command(args):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises at once; never reached
        return 0

    monkeypatch.setattr(catalogue, "main", command)
    before = signal.getsignal(signal.SIGTERM)
    assert cli.main(["list"]) == 143
    assert capsys.readouterr().err.strip() == "springlab: terminated"
    assert signal.getsignal(signal.SIGTERM) == before
