"""Where the repository's files are, for tests at any depth of tests/."""

import pathlib

#: the repository's root (the folder holding pyproject.toml)
ROOT = pathlib.Path(__file__).resolve().parents[2]
#: model files written for the tests
DATA = ROOT / "tests" / "data"
