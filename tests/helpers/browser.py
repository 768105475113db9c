"""Headless chromium for the tests that open springlab's pages in a real browser (the demo report, the
interactive page, a result's notebook view). The browser is Debian's `chromium` package: .ci/run installs it
on CI (as root with apt-get); elsewhere a test that needs it finds it or skips, saying how to get it.
Set SPRINGLAB_REQUIRE_CHROMIUM=1 (as .ci/run does) to turn that skip into a failure. `DevTools` drives a page
(tests/render/test_interactive.py, and benchmarks/paths.py timing the interactive page)."""

import fcntl
import json
import os
import shutil
import subprocess
import time

import pytest

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--mute-audio",
]


def find_chromium() -> str:
    """The path of Debian's chromium; skips the test where it is missing (fails under SPRINGLAB_REQUIRE_CHROMIUM)."""
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    if os.environ.get("SPRINGLAB_REQUIRE_CHROMIUM"):
        pytest.fail("chromium is required here (SPRINGLAB_REQUIRE_CHROMIUM) but not on PATH")
    pytest.skip(
        "headless check of the report needs Debian's chromium (apt-get install chromium; "
        ".ci/run installs it when run as root)"
    )


def browse(chromium, profile, *args, timeout=120):
    """Run headless chromium with a fresh profile; (stdout, stderr)."""
    done = subprocess.run(
        [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return done.stdout, done.stderr


def browse_until(chromium, profile, url, finished, *args):
    """Dump the DOM of `url` until `finished(dom)` holds, with growing virtual-time budgets.

    Media decoding runs on real decoder threads, not on chromium's virtual clock, so on a
    loaded machine a fixed budget can dump the page before every video has reported.
    Returns (dom, log) of the last attempt; the caller's assertions judge it.
    """
    for attempt, budget in enumerate((10000, 30000, 90000)):
        dom, log = browse(
            chromium, f"{profile}-{attempt}", *args, f"--virtual-time-budget={budget}", "--dump-dom", url, timeout=240
        )
        if finished(dom):
            break
    return dom, log


class DevTools:
    """Headless Chromium over --remote-debugging-pipe (fd 3 commands in, fd 4 answers out)."""

    def __init__(self, chromium: str, profile) -> None:
        commands_in, self._commands = os.pipe()
        self._answers, answers_out = os.pipe()
        # the child's ends above fd 10 first, so that moving them to 3 and 4 cannot overwrite one another
        ends = [fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in (commands_in, answers_out)]
        os.close(commands_in)
        os.close(answers_out)

        def wire() -> None:
            os.dup2(ends[0], 3)
            os.dup2(ends[1], 4)

        self.process = subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, "--remote-debugging-pipe", f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            close_fds=False,
            preexec_fn=wire,
        )
        for fd in ends:
            os.close(fd)
        self._buffer = b""
        self._id = 0
        self.targets: dict[str, str] = {}

    def call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        self._id += 1
        message = {"id": self._id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._commands, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self._buffer:
                chunk = os.read(self._answers, 1 << 16)
                assert chunk, "chromium closed its DevTools pipe"
                self._buffer += chunk
            raw, self._buffer = self._buffer.split(b"\0", 1)
            answer = json.loads(raw)
            if answer.get("id") == self._id:
                if "error" in answer:
                    raise RuntimeError(answer["error"]["message"])
                return answer["result"]

    def open(self, url: str) -> str:
        """A new tab showing `url`, its document loaded (the session id)."""
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.targets[session] = target
        self.call("Page.navigate", {"url": url}, session)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            try:  # until the evaluation runs in the page itself, not in about:blank on its way out
                if self.evaluate(session, "location.href + ' ' + document.readyState") == f"{url} complete":
                    return session
            except RuntimeError:
                pass
            time.sleep(0.02)
        raise AssertionError(f"{url} did not load")

    def evaluate(self, session: str, expression: str):
        answer = self.call(
            "Runtime.evaluate", {"expression": expression, "awaitPromise": True, "returnByValue": True}, session
        )
        assert "exceptionDetails" not in answer, answer["exceptionDetails"]
        return answer["result"].get("value")

    def close(self) -> None:
        """Browser.close: chromium ends its renderers itself (terminate only if it does not)."""
        try:
            self.call("Browser.close")
            self.process.wait(timeout=30)
        except (RuntimeError, AssertionError, subprocess.TimeoutExpired):
            self.process.terminate()
            self.process.wait(timeout=30)
        os.close(self._commands)
        os.close(self._answers)


#: resolves with #result's data- attributes once the page has published run number `after` + 1 or later
RESULT_AFTER = """new Promise((resolve, reject) => {{
  const start = Date.now();
  (function poll() {{
    const r = document.getElementById('result');
    if (r && r.dataset.verdict === 'error') reject(new Error(document.getElementById('status').textContent));
    else if (r && Number(r.dataset.run || 0) > {after})
      resolve(Object.fromEntries([...r.attributes].filter(a => a.name.startsWith('data-')).map(a => [a.name.slice(5), a.value])));
    else if (Date.now() - start > 120000) reject(new Error('no result'));
    else setTimeout(poll, 10);
  }})();
}})"""
