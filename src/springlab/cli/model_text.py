"""The human-readable answers of the commands run on a model file (`run`, `sweep`, `tradeoff` MODEL.xml).

Like springlab.cli.text, this module only formats what the library returned; a model file has no exact
solution, so every answer here says what it was measured against.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # annotations only: the commands import the studies lazily
    from springlab.runs.model_run import ModelRun


def print_model_run(run: ModelRun, output: str | None) -> None:
    """`springlab run MODEL.xml`: the setting, what the motion measured, and that nothing was validated."""
    print(
        f"{run.model_path} from {run.start.label}: {run.integrator}, dt = {run.dt:g} s,"
        f" {run.steps} steps ({run.duration:g} s) in {run.wall_time_s * 1e3:.1f} ms"
    )
    for name, value in run.measures.items():
        print(f"  {name:<32} {value:.10g}")
    print(f"  {run.verdict}: {run.message}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'trajectory.csv'} ({len(run.columns)} columns) and summary.json")
