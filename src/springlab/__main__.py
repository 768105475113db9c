"""`python -m springlab ...` is the `springlab` command (for environments without the console script on PATH)."""

import sys

from springlab.cli.main import main

if __name__ == "__main__":  # not when a worker process imports it (multiprocessing spawn)
    sys.exit(main())
