"""`springlab list`: scenes, scenarios and parameters."""

from __future__ import annotations

import argparse
from typing import Any

from springlab import scenes
from springlab.cli import options
from springlab.cli import text as cli_text
from springlab.errors import ExitCode

NAME = "list"
HELP = "scenes, scenarios and parameters"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="machine-readable output")


def main(args: argparse.Namespace) -> int:
    catalogue: list[dict[str, Any]] = []
    for scene in scenes.SCENES.values():
        catalogue.append(
            {
                "scene": scene.name,
                "title": scene.title,
                "joints": list(scene.joints),
                "default_integrator": scene.integrator,
                "default_dt": scene.dt,
                "scenarios": {s.name: s.description for s in scene.scenarios.values()},
                # the setting `run` and `validate` use for each scenario (a scenario may validate its own dt)
                "scenario_settings": {
                    s.name: {"integrator": scene.setting(s)[0], "dt": scene.setting(s)[1], "duration": s.duration}
                    for s in scene.scenarios.values()
                },
                "parameters": {
                    p.name: {"unit": p.unit, "description": p.description, "valid": p.valid_range()}
                    for p in scene.parameters.values()
                },
            }
        )
    if args.json:
        options.print_json(catalogue)
        return ExitCode.OK
    cli_text.print_list(catalogue)
    return ExitCode.OK
