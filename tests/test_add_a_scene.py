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

ROOT = pathlib.Path(__file__).resolve().parents[1]
NAME = "twin"


@pytest.fixture(scope="module")
def checkout(tmp_path_factory):
    """A copy of src/ and models/ with one scene added: the slider's model and folder as `twin`."""
    root = tmp_path_factory.mktemp("checkout")
    shutil.copytree(ROOT / "src", root / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    shutil.copytree(ROOT / "models", root / "models")
    shutil.copy(ROOT / "models" / "slider.xml", root / "models" / f"{NAME}.xml")
    folder = root / "src" / "springlab" / "scenes" / NAME
    shutil.copytree(ROOT / "src" / "springlab" / "scenes" / "slider", folder, ignore=shutil.ignore_patterns("__pycache__"))
    scene = folder / "scene.py"
    text = scene.read_text()
    assert text.count('name = "slider"') == 1, "the slider names itself once; the copy renames that line only"
    scene.write_text(text.replace('name = "slider"', f'name = "{NAME}"'))
    return root


def _springlab(checkout: pathlib.Path, *argv: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(checkout / "src"), MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    return subprocess.run(
        [sys.executable, "-m", "springlab", *argv], cwd=checkout, env=env, capture_output=True, text=True, timeout=600
    )


def _json(checkout: pathlib.Path, *argv: str):
    done = _springlab(checkout, *argv, "--json")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _without_timing(value):
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if "wall" not in k and k != "scene"}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


@pytest.mark.slow
def test_a_scene_added_as_a_model_and_a_folder_serves_every_command(checkout, tmp_path):
    # it is this copy's springlab that runs, with the new scene in it
    listed = _json(checkout, "list")
    assert [entry["scene"] for entry in listed][-1] == NAME and "slider" in [entry["scene"] for entry in listed]

    # run and validate: the twin's numbers are the slider's, bit for bit
    twin, slider = _json(checkout, "run", NAME, "free"), _json(checkout, "run", "slider", "free")
    assert twin["scene"] == NAME and twin["passed"] is True
    assert _without_timing(twin) == _without_timing(slider)
    rows = _json(checkout, "validate", NAME)
    assert {row["scenario"] for row in rows} == {s for s in listed[-1]["scenarios"]}
    assert all(row["passed"] for row in rows)

    # outputs and studies
    assert _springlab(checkout, "plot", NAME, "--kind", "zeta", "--output", str(tmp_path / "z.png")).returncode == 0
    assert (tmp_path / "z.png").stat().st_size > 0
    tradeoff = _json(checkout, "tradeoff", NAME, "free", "--tol", "1e-6")
    assert tradeoff["recommendation"]["integrator"] is not None
    audit = _json(checkout, "audit", str(checkout / "models" / f"{NAME}.xml"))
    assert audit["recommendation"]["verified"] is True

    # a declared capability is all a study needs: the twin can be fitted because the slider can
    trajectory = tmp_path / "run"
    assert _springlab(checkout, "run", NAME, "free", "--output", str(trajectory)).returncode == 0
    fitted = _json(checkout, "fit", NAME, str(trajectory / "trajectory.csv"))
    truth = twin["parameters"]
    assert fitted["scene"] == NAME and fitted["converged"] is True
    # wiring, not accuracy (tests/test_fit.py holds the fit to its intervals): the record is a validated
    # run (error ~1e-6 of its amplitude), so the frequency comes back far inside 1e-3
    omega_n = (truth["stiffness"] / truth["mass"]) ** 0.5
    assert abs(fitted["estimates"]["omega_n"]["value"] / omega_n - 1) <= 1e-3
