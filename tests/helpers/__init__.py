"""What several test files share: models written out, reference loops, constants read from the shipped MJCF, the
browser driver, the documented output keys. On the import path through `pythonpath = ["tests"]` in
pyproject.toml's `[tool.pytest.ini_options]`; test files import from here, never from one another."""
