"""Every scene serves every command its declarations serve (issue 32: a new scene that forgets a hook fails by name).

The commands that take any scene (run, validate, plot, render, tradeoff) run on every scene; the commands that
read a capability (frequency, interactive, fit, design, refine, friction-settings, rms, plot's scene figure and
phase plane, stability's oscillator) run on every scene that declares it. Each case is one test, named
`SCENE-COMMAND`, run in this process through `springlab.cli.main.main` (the `cli` fixture) with the cheapest
options the command takes; it asserts the exit code (0: answered and, where validated, passed), that every file
the command documents appeared, and that its JSON names the scene. `validate` reads the runs and `stability` the command's
run the session computes once for every test (tests/conftest.py: `scenario_run`, `stability_command`), so
holding each scene to them costs nothing beyond the wiring. The physics of each answer is checked elsewhere
(tests/scenes/<scene>/); this test holds the wiring, and the last test names any command of the CLI it leaves out.
"""

from __future__ import annotations

import json
import pathlib

import pytest

from helpers.stay_cable import WINDY
from helpers.timing import constant_time_run
from springlab import scenes
from springlab.cli.main import COMMANDS
from springlab.studies import auto, tradeoff
from springlab.studies.tradeoff import sweepable

#: a short render: the 3D view at 64 x 48 for 0.2 s of simulated time (wiring, not pictures)
RENDER = ("--width", "64", "--height", "48", "--fps", "10")


def _first(spec):
    """A scene's frequency declaration: the default one of a tuple."""
    return spec[0] if isinstance(spec, tuple) else spec


#: steps of a short run: wiring, not accuracy (each scene's physics tests hold the long runs)
STEPS = 40

#: a scene's parameters for its cases, where its default model is large for a wiring test: the stay cable's
#: 99 nodes cost its damper's scene figure 2.5 s of CPU (four free decays of the damper's curve, 11,600 RK4 steps
#: at the stiffest) and its trade-off 24 s; the nine-node stay of its wind tests runs the same code in a tenth. The drill
#: string's 32 elements cost its breakaway (held to checks of its whole 10 s, so never cut short) 1.6 s per run,
#: plot and render each; 4 elements (its tests' coarse chain, tests/scenes/test_answers.py) cost 0.3 s
SMALL = {
    "stay_cable": [f"--set={key}={value!r}" for key, value in WINDY.items()],
    "drill_string": ["--set=n_elements=4"],
}


def _cases(scene) -> dict[str, list[tuple[list[str], tuple[str, ...]]]]:
    """command -> [(argv with OUT for the output folder, files expected under OUT)] for one scene."""
    name = scene.name
    default = scene.scenario(None)
    small = SMALL.get(name, [])
    # a run held to an exact trajectory stays valid cut short; one held to checks of its whole motion (a stop,
    # a period) needs its own duration
    short = ["--duration", repr(STEPS * (default.dt or scene.dt))] if sweepable(scene, default) else []
    out: dict[str, list[tuple[list[str], tuple[str, ...]]]] = {
        "run": [(["run", name, *small, *short, "--output", "OUT", "--json"], ("trajectory.csv", "summary.json"))],
        "plot": [(["plot", name, *small, *short, "--output", "OUT/time.png"], ("time.png",))],
        "render": [(["render", name, *small, *short, "--output", "OUT/film.mp4", *RENDER], ("film.mp4",))],
    }
    exact = [s for s in scene.scenarios.values() if sweepable(scene, s)]
    if exact:  # the trade-off measures errors against an exact reference
        # four of the scenario's steps: the timestep grid then tops out at a quarter of the run and spans its three
        # decades below (timestep_grid), so the finest run is ~4000 steps whatever the scene's fastest mode. A
        # tenth of the run cost the stay cable 200,000 steps at the finest of 13 timesteps (194 s) for the same
        # wiring: the grid, the front and the pick are the same code at any duration
        short_run = repr(min(exact[0].duration / 10, 4 * (exact[0].dt or scene.dt)))
        out["tradeoff"] = [
            (
                ["tradeoff", name, exact[0].name, *small, "--duration", short_run, "--json", "--output", "OUT"],
                ("tradeoff.json", "tradeoff.png"),
            )
        ]
    if len(scene.joints) == 1:
        out["plot"].append(
            (["plot", name, *small, *short, "--kind", "phase", "--output", "OUT/phase.png"], ("phase.png",))
        )
    if scene.figure is not None:
        out["plot"].append(
            (["plot", name, *small, *short, "--kind", "scene", "--output", "OUT/scene.png"], ("scene.png",))
        )
    if scene.frequency is not None:
        out["frequency"] = [
            (["frequency", name, "--points", "20", "--json", "--output", "OUT"], ("frequency.json", "bode.png"))
        ]
    if scene.interactive is not None:
        out["interactive"] = [(["interactive", name, "--output", "OUT", "--json"], ())]
    if scene.fit is not None:
        out["fit"] = [(["fit", name, "RECORD", "--json", "--output", "OUT"], ("fit.json", "fit.png"))]
    if scene.design is not None:
        out["design"] = [
            (["design", name, "--levels", "3", "--plane", "0", "--json", "--output", "OUT"], ("design.json",))
        ]
    if scene.refinable is not None:
        out["refine"] = [
            (
                ["refine", name, "--sizes", "2,4", "--integrators", "rk4", "--json", "--output", "OUT"],
                ("refine.json", "refine.png"),
            )
        ]
    if scene.dry_friction is not None:
        first = next(iter(scene.scenarios))
        # two timesteps, the case's and twice it (the fewest the study takes): its default grid cost 3 s of CPU
        step = scene.scenarios[first].dt or scene.dt
        dts = f"{2 * step!r},{step!r}"
        out["friction-settings"] = [
            (
                ["friction-settings", name, first, "--integrators", "rk4", "--dt", dts, "--json", "--output", "OUT"],
                ("friction_settings.json", "friction_settings.csv", "friction_settings.png"),
            )
        ]
    if scene.random_load is not None:
        out["rms"] = [(["rms", name, *small, "--seeds", "2", "--record", "20", "--json", "--output", "OUT"], ())]
    return out


#: the commands whose exit code 1 is an answer, not a failure: no setting of the sweep meets the tolerance, or
#: the integrator does not reproduce the whole band (the run commands must pass: 0)
ANSWERS_WITH_ONE = {"tradeoff", "frequency", "refine", "friction-settings", "design", "rms"}


#: the study commands take seconds each on a scene: `make test` runs them, the quick loop does not
SLOW = ("tradeoff", "design", "fit", "friction-settings", "refine")

CASES = [
    pytest.param(scene.name, command, marks=[pytest.mark.slow] if command in SLOW else [])
    for scene in scenes.SCENES.values()
    for command in _cases(scene)
]


def _check(cli, scene_name, command, argv, expected, out):
    """Run `springlab ARGV` and hold it to its exit code, its files and its JSON naming the scene."""
    printed = cli(*argv)
    assert printed.code in ((0, 1) if command in ANSWERS_WITH_ONE else (0,)), (
        f"springlab {' '.join(argv)} exited {printed.code}: {printed.err.strip()[-400:]}"
    )
    for name in expected:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, f"{name} missing after {argv}"
    if "--json" in argv:
        text = json.dumps(json.loads(printed.out))
        assert scene_name in text, f"{argv}: its JSON does not name the scene"
    assert not list(pathlib.Path.cwd().glob("MUJOCO_LOG.TXT"))


@pytest.mark.parametrize("scene_name, command", CASES, ids=[f"{c.values[0]}-{c.values[1]}" for c in CASES])
def test_every_scene_serves_every_command_it_declares(scene_name, command, tmp_path, cli, monkeypatch):
    scene = scenes.get(scene_name)
    if command == "tradeoff":
        # no run timed again alone (helpers/timing.py; tests/studies/test_tradeoff.py times its sweeps): the case
        # holds the wiring and reads no timing, and the timing runs cost a fifth of each case
        monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    for index, (argv, expected) in enumerate(_cases(scene)[command]):
        out = tmp_path / f"out{index}"
        if "RECORD" in argv:  # a fit reads a record of the scene's own fit scenario
            record = tmp_path / "record"
            fit_scenario = scene.fit.scenario if getattr(scene.fit, "scenario", None) else scene.default_scenario
            made = cli("run", scene_name, fit_scenario, "--output", record)
            assert made.code == 0, made.err
            argv = [str(record / "trajectory.csv") if a == "RECORD" else a for a in argv]
        argv = [a.replace("OUT", str(out)) for a in argv]
        _check(cli, scene_name, command, argv, expected, out)


@pytest.mark.slow  # every exact scenario of the scene: shared with the other readers of `scenario_run`
@pytest.mark.parametrize("scene_name", list(scenes.SCENES), ids=[f"{name}-validate" for name in scenes.SCENES])
def test_every_scene_passes_validate(scene_name, cli, monkeypatch, scenario_run, tmp_path):
    """`springlab validate SCENE` passes every exact scenario of the scene, one row each. Its runs are the
    session's `scenario_run(scene, scenario)`: the same `run_scenario` at the scene's validated setting that
    `validate` makes (no integrator, dt or tol given), computed once for every test that reads it."""

    def shared(scene, scenario=None, *, integrator=None, dt=None, duration=None, tol=None, **parameters):
        assert integrator is dt is duration is tol is None and not parameters, "validate at the scene's setting"
        return scenario_run(scene, scenario)

    monkeypatch.setattr(auto, "run_scene", shared)
    printed = cli("validate", scene_name, "--json")
    assert printed.code == 0, printed.err
    rows = json.loads(printed.out)
    exact = [name for name, scenario in scenes.get(scene_name).scenarios.items() if scenario.exact]
    assert exact and [row["scenario"] for row in rows] == exact
    assert all(row["scene"] == scene_name and row["passed"] for row in rows)
    assert not list(pathlib.Path.cwd().glob("MUJOCO_LOG.TXT"))


OSCILLATORS = [name for name, scene in scenes.SCENES.items() if scene.oscillator is not None]


@pytest.mark.parametrize("scene_name", OSCILLATORS, ids=[f"{name}-stability" for name in OSCILLATORS])
def test_every_oscillator_scene_serves_stability(scene_name, stability_command):
    """`springlab stability` runs the scene that declares the one-mode oscillator (`Scene.oscillator`, the first
    such scene: springlab.studies.extremes.oscillator_scene): its declaration's names set the free scenario's
    m [kg], k [N/m] and d [N s/m], which read back from its one degree of freedom, and the command writes its
    three files: the session's run of it (tests/conftest.py: `stability_command`, from the session's report,
    computed once, and read by tests/studies/test_stability.py too). The report is of "the unit oscillator", so
    its JSON does not name the scene."""
    scene = scenes.get(scene_name)
    spec = scene.oscillator
    case = scene.case(spec.free, spec.parameters(mass=2.0, stiffness=50.0, damping=0.3, x0=0.01, v0=-0.02))
    assert case.model.nv == 1, f"{scene_name}'s scenario {spec.free!r} is not one degree of freedom"
    assert spec.constants(case.model) == pytest.approx((2.0, 50.0, 0.3), rel=1e-12)
    printed, folder = stability_command
    assert printed.code == 0, printed.err
    assert json.loads(printed.out) == json.loads((folder / "stability.json").read_text())
    assert sorted(p.name for p in folder.iterdir()) == ["energy.png", "stability.json", "stability.png"]


def test_every_declared_capability_has_a_command_in_this_test():
    # a new capability slot on Scene must be added to `_cases` (or this test says which is missing)
    served = {"fit", "oscillator", "design", "dry_friction", "refinable", "figure", "frequency", "interactive"}
    served |= {"random_load"}
    served |= {"drawing"}  # drawn by render (its case runs for every scene)
    declared = {
        name
        for name, value in vars(scenes.base.Scene).items()
        if not name.startswith("_") and value is None and name not in ("camera",)
    }
    assert declared <= served, f"capabilities no command case covers: {sorted(declared - served)}"


#: the commands of the CLI this test does not run per scene, and why
NOT_PER_SCENE = {
    "list": "lists every scene at once, from the declarations alone (tests/cli/test_cli.py)",
    "sweep": "reaches a scene only through the run's hooks, which the run case holds (tests/studies/test_sweep.py)",
    "audit": "reaches a scene only through its case and setup, which the run case holds (tests/studies/audit/)",
    "view": "needs a display: tests/cli/test_view.py runs it under a virtual one",
    "demo": "runs its fixed steps on the shipped scenes (tests/demo/test_report.py)",
}


def test_every_command_of_the_cli_is_run_here_or_says_why_not():
    # a new command must join `_cases` (or a test of its own above) or NOT_PER_SCENE, with its reason
    here = {command for scene in scenes.SCENES.values() for command in _cases(scene)} | {"validate", "stability"}
    names = {command.NAME for command in COMMANDS}
    assert names - here - set(NOT_PER_SCENE) == set(), "commands no case runs"
    assert here | set(NOT_PER_SCENE) <= names, "cases of commands the CLI does not have"
