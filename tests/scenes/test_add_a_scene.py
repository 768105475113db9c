"""Adding a scene touches its model and its folder under scenes/, nothing else (CONTRIBUTING.md, "Adding a scene").

The test does what a contributor does: in a copy of the checkout it adds `models/twin.xml` and
`src/springlab/scenes/twin/` (the slider's model and folder under another name) and changes nothing else.
Every command then serves the new scene: list, run, validate, plot, tradeoff, audit, and the studies that
read what a scene declares (the fit and the stability map pick it up from its declarations, never from
its name). The twin is the slider, so its numbers must be the slider's, to the last bit.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

from helpers.paths import ROOT

NAME = "twin"


@pytest.fixture(scope="module")
def checkout(tmp_path_factory):
    """A copy of src/ and models/ with one scene added: the slider's model and folder as `twin`."""
    root = tmp_path_factory.mktemp("checkout")
    shutil.copytree(ROOT / "src", root / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    shutil.copytree(ROOT / "models", root / "models")
    shutil.copy(ROOT / "models" / "slider.xml", root / "models" / f"{NAME}.xml")
    folder = root / "src" / "springlab" / "scenes" / NAME
    shutil.copytree(
        ROOT / "src" / "springlab" / "scenes" / "slider", folder, ignore=shutil.ignore_patterns("__pycache__")
    )
    scene = folder / "scene.py"
    text = scene.read_text()
    assert text.count('name = "slider"') == 1, "the slider names itself once; the copy renames that line only"
    scene.write_text(text.replace('name = "slider"', f'name = "{NAME}"'))
    return root


#: runs springlab's command line in this process once per command, in the copy's interpreter: one import
#: of springlab for all the commands instead of one per command (each import costs about a second); it also
#: says which springlab that was
DRIVER = """
import contextlib, io, json, sys
import springlab
from springlab.cli.main import main
outcomes = []
for argv in json.loads(sys.stdin.read()):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    outcomes.append([code, out.getvalue(), err.getvalue()])
print(json.dumps({"springlab": springlab.__file__, "outcomes": outcomes}))
"""


def _springlab(checkout: pathlib.Path, *commands: list[str]) -> list[tuple[int, str, str]]:
    """(exit code, stdout, stderr) of each command, run by the copy's springlab."""
    env = dict(os.environ, PYTHONPATH=str(checkout / "src"), MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    done = subprocess.run(
        [sys.executable, "-c", DRIVER],
        input=json.dumps([list(c) for c in commands]),
        cwd=checkout,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert done.returncode == 0, done.stderr
    ran = json.loads(done.stdout)
    assert ran["springlab"].startswith(str(checkout))  # the copy's springlab is the one that ran, not the checkout's
    return [tuple(outcome) for outcome in ran["outcomes"]]


def _json(outcome: tuple[int, str, str]):
    code, out, err = outcome
    assert code == 0, err
    return json.loads(out)


def _without_timing(value):
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if "wall" not in k and k != "scene"}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


@pytest.mark.slow
def test_a_scene_added_as_a_model_and_a_folder_serves_every_command(checkout, tmp_path):
    trajectory = tmp_path / "run"
    # one interpreter for every command: the fit reads the record the run before it wrote
    listed, twin, slider, rows, plotted, tradeoff, audit, written, fitted = _springlab(
        checkout,
        ["list", "--json"],
        ["run", NAME, "free", "--json"],
        ["run", "slider", "free", "--json"],
        ["validate", NAME, "--json"],
        ["plot", NAME, "--kind", "zeta", "--output", str(tmp_path / "z.png")],
        ["tradeoff", NAME, "free", "--tol", "1e-6", "--duration", "0.5", "--json"],  # a tenth: wiring
        ["audit", str(checkout / "models" / f"{NAME}.xml"), "--json"],
        ["run", NAME, "free", "--output", str(trajectory)],
        ["fit", NAME, str(trajectory / "trajectory.csv"), "--json"],
    )
    listed = _json(listed)
    assert [entry["scene"] for entry in listed][-1] == NAME and "slider" in [entry["scene"] for entry in listed]

    # run and validate: the twin's numbers are the slider's, bit for bit
    twin, slider = _json(twin), _json(slider)
    assert twin["scene"] == NAME and twin["passed"] is True
    assert _without_timing(twin) == _without_timing(slider)
    rows = _json(rows)
    assert {row["scenario"] for row in rows} == set(listed[-1]["scenarios"])
    assert all(row["passed"] for row in rows)

    # outputs and studies
    assert plotted[0] == 0 and (tmp_path / "z.png").stat().st_size > 0
    assert _json(tradeoff)["recommendation"]["integrator"] is not None
    assert _json(audit)["recommendation"]["verified"] is True

    # a declared capability is all a study needs: the twin can be fitted because the slider can
    assert written[0] == 0
    fitted, truth = _json(fitted), twin["parameters"]
    assert fitted["scene"] == NAME and fitted["converged"] is True
    # wiring, not accuracy (tests/studies/fit/test_fit.py holds the fit to its intervals): the record is a validated
    # run (error ~1e-6 of its amplitude), so the frequency comes back far inside 1e-3
    omega_n = (truth["stiffness"] / truth["mass"]) ** 0.5
    assert abs(fitted["estimates"]["omega_n"]["value"] / omega_n - 1) <= 1e-3
