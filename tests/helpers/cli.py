"""What one `springlab ARGV` did in the test's process: the value the `cli` fixture (tests/conftest.py) returns."""

from typing import NamedTuple


class CliResult(NamedTuple):
    """The exit code of `springlab.cli.main.main(ARGV)` and what it printed, read once it returned.

    A named tuple, so `code, out, err = cli(...)` unpacks it; the exit codes are springlab.errors.ExitCode's
    (0 answered, 1 answered and a check failed, 2 bad input, 3 diverged)."""

    code: int
    out: str
    err: str
