"""Headless chromium for the tests that open springlab's pages in a real browser (the demo report, the
interactive page, a result's notebook view). The browser is Debian's `chromium` package: .ci/run installs it
on CI (as root with apt-get); elsewhere a test that needs it finds it or skips, saying how to get it.
Set SPRINGLAB_REQUIRE_CHROMIUM=1 (as .ci/run does) to turn that skip into a failure."""

import os
import shutil
import subprocess

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
