"""What one `springlab ARGV` did in the test's process: the value the `cli` fixture (tests/conftest.py) returns,
and the same call for a shared fixture, which has no test's capsys to read."""

import contextlib
import io
from typing import NamedTuple


class CliResult(NamedTuple):
    """The exit code of `springlab.cli.main.main(ARGV)` and what it printed, read once it returned.

    A named tuple, so `code, out, err = cli(...)` unpacks it; the exit codes are springlab.errors.ExitCode's
    (0 answered, 1 answered and a check failed, 2 bad input, 3 diverged)."""

    code: int
    out: str
    err: str


def run_cli(*argv: object) -> CliResult:
    """`springlab ARGV` in this process, what it printed to stdout and stderr caught in strings: the `cli`
    fixture's call for a session fixture (a command's output several tests read, computed once)."""
    from springlab.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return CliResult(code, out.getvalue(), err.getvalue())


def computed_once(monkeypatch, where: str) -> list:
    """Make the function at `where` ("module:name", where the command looks it up) compute on its first call and
    return that result on every later call, for the rest of the test: a command run twice (its --json and its text)
    then prints one study's result, paid once. Returns the list of results made (one once the first call returned)."""
    import importlib

    module_name, name = where.split(":")
    module = importlib.import_module(module_name)
    compute, made = getattr(module, name), []

    def once(*args, **kwargs):
        if not made:
            made.append(compute(*args, **kwargs))
        return made[0]

    monkeypatch.setattr(module, name, once)
    return made
