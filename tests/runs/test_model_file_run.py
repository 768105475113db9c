"""`springlab run MODEL.xml` on models nobody here wrote (dm_control's suite) and on a gripper written for the tests:
every step recorded as a plain mj_step loop computes it, free fall as the integrators' closed forms give it, nothing
validated (exit 0), and bad input refused in one line with nothing written.

tests/data/pinch_gripper.xml: two fingers pushed by 3 N motors squeeze a 0.2 kg box on a free joint (keyframe
'squeeze'); in keyframe 'open' the fingers are clear of the box and the box falls freely from z = 0.25 m.
"""

from __future__ import annotations

import csv
import json
import pathlib

import dm_control  # a test-only dependency (the `test` extra)
import mujoco
import numpy as np
import pytest

import springlab
from helpers.paths import DATA
from springlab.cli.main import main
from springlab.runs.model_run import ModelRun

SUITE = pathlib.Path(dm_control.__file__).parent / "suite"
GRIPPER = DATA / "pinch_gripper.xml"
#: gravity of MuJoCo's default options [m/s^2] and the box's start height in keyframe 'open' [m]
G, Z0 = 9.81, 0.25
EPS = np.finfo(float).eps


def _loop(model: mujoco.MjModel, steps: int, key: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """qpos, qvel at every step of a plain mj_step loop from keyframe `key` (None: qpos0 at rest)."""
    data = mujoco.MjData(model)
    if key is not None:
        mujoco.mj_resetDataKeyframe(model, data, key)
    qpos, qvel = [data.qpos.copy()], [data.qvel.copy()]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        qpos.append(data.qpos.copy())
        qvel.append(data.qvel.copy())
    return np.array(qpos), np.array(qvel)


def _columns(path: pathlib.Path) -> dict[str, np.ndarray]:
    with path.open() as handle:
        rows = list(csv.reader(handle))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


@pytest.mark.parametrize(("name", "duration"), [("cartpole", 0.5), ("humanoid", 0.05)])
def test_run_of_a_dm_control_model_writes_every_step_of_a_plain_mj_step_loop(name, duration, tmp_path, capsys):
    file = SUITE / f"{name}.xml"
    out = tmp_path / "out"
    assert main(["run", str(file), "--duration", str(duration), "--output", str(out)]) == 0
    model = mujoco.MjModel.from_xml_path(str(file))
    steps = round(duration / model.opt.timestep)
    qpos, qvel = _loop(model, steps, 0 if model.nkey else None)
    columns = _columns(out / "trajectory.csv")
    summary = json.loads((out / "summary.json").read_text())
    # one column per coordinate (time, every qpos and every qvel), each named in summary.json with its unit
    assert list(columns) == list(summary["columns"]) and len(columns) == 1 + model.nq + model.nv
    # the model's own setting (dm_control's cartpole: RK4 at 10 ms; the humanoid: its own 5 ms)
    assert summary["dt"] == model.opt.timestep and summary["steps"] == steps
    recorded_pos = [c for c, unit in summary["columns"].items() if "_pos" in c]
    recorded_vel = [c for c, unit in summary["columns"].items() if "_vel" in c]
    # rollout and mj_step are the same arithmetic: bit for bit, in MuJoCo's qpos and qvel order
    np.testing.assert_array_equal(np.column_stack([columns[c] for c in recorded_pos]), qpos)
    np.testing.assert_array_equal(np.column_stack([columns[c] for c in recorded_vel]), qvel)
    assert summary["verdict"] == "not validated" and summary["passed"] is None and summary["errors"] == {}
    assert "not validated" in capsys.readouterr().out


def test_cartpole_columns_are_its_joints_with_si_units(tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(SUITE / "cartpole.xml"), "--duration", "0.1", "--output", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["columns"] == {
        "time": "s",
        "slider_pos": "m",
        "slider_vel": "m/s",
        "hinge_1_pos": "rad",
        "hinge_1_vel": "rad/s",
    }
    assert summary["integrator"] == "rk4" and summary["options"]["integrator"] == "rk4"


@pytest.mark.parametrize("integrator", ["rk4", "euler"])
def test_the_released_box_falls_as_each_integrators_closed_form_says(integrator):
    dt, duration = 1e-3, 0.2
    run = springlab.run(str(GRIPPER), keyframe="open", integrator=integrator, dt=dt, duration=duration)
    assert isinstance(run, ModelRun) and run.integrator == integrator and run.options["timestep"] == dt
    series = run.series()
    n = np.arange(run.steps + 1)
    if integrator == "rk4":
        # exact for a constant acceleration: z = z0 - g t^2 / 2, v = -g t
        z, v = Z0 - 0.5 * G * (n * dt) ** 2, -G * n * dt
    else:
        # MuJoCo's Euler updates the velocity first: v_n = -g n dt, z_n = z0 - g dt^2 n (n + 1) / 2
        z, v = Z0 - 0.5 * G * dt**2 * n * (n + 1), -G * n * dt
    # round-off only: a few eps of the largest value per step, accumulated over the steps
    np.testing.assert_allclose(series["box_pos_z"], z, rtol=0, atol=10 * EPS * Z0 * run.steps)
    np.testing.assert_allclose(series["box_vel_z"], v, rtol=0, atol=10 * EPS * G * duration * run.steps)
    # the fingers never move (no force, no contact), and neither do the box's other coordinates
    assert np.all(series["left_pos"] == 0) and np.all(series["box_pos_x"] == 0) and np.all(series["box_pos_qw"] == 1)
    assert run.measures["box_max_excursion_m"] == pytest.approx(
        0.5 * G * duration**2, rel=1e-9 if integrator == "rk4" else 1e-2
    )


def test_energy_measures_are_the_bodies_weights_times_heights_and_conserved_in_free_fall():
    run = springlab.run(str(GRIPPER), keyframe="open", integrator="rk4", dt=1e-3, duration=0.2)
    assert isinstance(run, ModelRun)
    # palm 0.1 kg at 0.3 m, fingers 0.05 kg each at 0.25 m, box 0.2 kg at 0.25 m, all at rest
    weight_times_height = G * (0.1 * 0.3 + 2 * 0.05 * 0.25 + 0.2 * Z0)
    assert run.measures["energy_initial_J"] == pytest.approx(weight_times_height, rel=1e-12)
    # free fall trades potential for kinetic energy exactly (RK4 is exact here)
    assert run.measures["energy_final_J"] == pytest.approx(weight_times_height, rel=1e-12)


def test_the_squeezed_box_is_not_validated_and_its_slip_is_measured(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(GRIPPER), "--keyframe", "squeeze", "--duration", "1", "--json", "--output", str(out)]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((out / "summary.json").read_text())
    assert printed["start"] == "keyframe 'squeeze'" and printed["options"]["integrator"] == "euler"
    # Coulomb friction could hold it (2 x 3 N x mu 1 > 0.2 kg x g = 1.96 N), yet MuJoCo's soft friction lets it
    # slide: well under the 4.9 m of free fall in 1 s, above nothing
    assert 0 < printed["quantities"]["box_max_excursion_m"] < 0.1 * 0.5 * G


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["run", "missing.xml", "--output", "{out}"], "no such model file 'missing.xml'"),
        (["run", str(GRIPPER), "--keyframe", "grip", "--output", "{out}"], "unknown keyframe 'grip'"),
        (["run", str(GRIPPER), "--duration", "-1", "--output", "{out}"], "duration must be a finite number > 0 s"),
        (["run", str(GRIPPER), "--integrator", "verlet", "--output", "{out}"], "unknown integrator"),
        (["run", str(GRIPPER), "--set", "mass=2", "--output", "{out}"], "--set applies to a scene"),
        (["run", "slider", "--keyframe", "0", "--output", "{out}"], "--keyframe applies to a model file"),
    ],
)
def test_bad_input_to_run_is_one_line_exit_2_nothing_written(arguments, message, tmp_path, capsys):
    out = tmp_path / "out"
    assert main([a.replace("{out}", str(out)) for a in arguments]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("command", "extra"),
    [
        ("validate", []),
        ("render", ["--output", "{out}/x.mp4"]),
        ("plot", ["--output", "{out}/x.png"]),
        ("refine", []),
        ("rms", []),
        ("design", []),
        ("fit", ["data.csv"]),
        ("interactive", ["--output", "{out}"]),
    ],
)
def test_a_command_that_needs_a_scene_says_so_for_a_model_file(command, extra, tmp_path, capsys):
    out = tmp_path / "out"
    assert main([command, str(GRIPPER), *[a.replace("{out}", str(out)) for a in extra]]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{command} takes a scene, not a model file" in err and "for a model file use 'springlab" in err
    assert not out.exists()


def test_the_python_api_keeps_scene_and_model_options_apart():
    with pytest.raises(springlab.BadInputError, match="keyframe applies to a model file"):
        springlab.run("slider", keyframe="0")
    with pytest.raises(springlab.BadInputError, match="mass applies to a scene"):
        springlab.run(str(GRIPPER), mass=2.0)
