"""What the demo's steps share: the output folder, the runs, the validation rows and the files written."""

from __future__ import annotations

import dataclasses
import pathlib
import time

from springlab.runs.run import Result, ValidationRow


@dataclasses.dataclass
class Artifact:
    """A file the demo wrote, for the report.

    Attributes
    ----------
    path
        the file, relative to the output folder.
    kind
        'data', 'plot', 'video' or 'report'.
    title
        one line saying what it shows.
    scene, scenario
        what it belongs to ('' for cross-scene artifacts).
    answer
        for a study that answers a question: the answer in words, shown with the title as its
        question ('' for none).
    """

    path: str
    kind: str
    title: str
    scene: str = ""
    scenario: str = ""
    answer: str = ""


@dataclasses.dataclass
class DemoState:
    """What the steps share: the output folder, the validation rows and every run's Result."""

    out: pathlib.Path
    validation: list[ValidationRow] = dataclasses.field(default_factory=list)
    results: dict[tuple[str, str], Result] = dataclasses.field(default_factory=dict)
    artifacts: list[Artifact] = dataclasses.field(default_factory=list)
    #: (what, wall time [s]) of each step (and of finer parts a step wants to report)
    timings: list[tuple[str, float]] = dataclasses.field(default_factory=list)
    #: time.perf_counter() when the demo started, for the total wall time
    started: float = dataclasses.field(default_factory=time.perf_counter)
