"""`sweep`, `tradeoff` and `frequency` on a model file: rows equal plain mj_step loops with the attribute set, free
fall as Galileo and Euler's closed form say, a trade-off whose errors against the converged run of the same
model are the errors against the closed form, warnings where a linearization cannot speak, and bad input refused
in one line with nothing written.

Models: tests/data/pinch_gripper.xml (written for these tests, see test_model_file_run.py), dm_control's humanoid and
cheetah (nobody here wrote them), and a damped oscillator written below with its closed form.
"""

from __future__ import annotations

import json
import math
import pathlib

import dm_control  # a test-only dependency (the `test` extra)
import mujoco
import numpy as np
import pytest

from helpers.cli import computed_once
from helpers.paths import DATA
from springlab.cli.main import main
from springlab.sim.simulate import ROUNDOFF_PER_STEP
from springlab.studies.model_sweep import model_sweep
from springlab.studies.model_tradeoff import model_tradeoff

SUITE = pathlib.Path(dm_control.__file__).parent / "suite"
GRIPPER = DATA / "pinch_gripper.xml"
G, Z0 = 9.81, 0.25
#: the oscillator: m [kg], k [N/m], c [N s/m], x0 [m]
M, K, C, X0 = 1.0, 100.0, 1.0, 0.01
OSCILLATOR = f"""<mujoco model="oscillator">
  <option gravity="0 0 0" integrator="RK4" timestep="0.01"/>
  <worldbody>
    <body name="mass">
      <joint name="x" type="slide" axis="1 0 0" stiffness="{K}" damping="{C}"/>
      <geom type="sphere" size="0.05" mass="{M}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <keyframe><key name="pulled" qpos="{X0}"/></keyframe>
</mujoco>
"""


def _box_excursions(model: mujoco.MjModel, steps: int, key: int) -> float:
    """The box's largest distance [m] from its start over a plain mj_step loop from keyframe `key`."""
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, key)
    adr = int(model.jnt_qposadr[model.joint("box").id])
    positions = [data.qpos[adr : adr + 3].copy()]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        positions.append(data.qpos[adr : adr + 3].copy())
    return float(np.max(np.linalg.norm(np.array(positions) - positions[0], axis=1)))


def test_sweep_rows_equal_plain_mj_step_loops_with_the_option_and_the_attribute_set():
    duration = 0.2
    sweep = model_sweep(
        GRIPPER, vary={"opt.impratio": (1.0, 10.0, 2), "joint.left.damping": (0.5, 2.0, 2)}, duration=duration
    )
    assert sweep.size == 4 and sweep.diverged == 0 and sweep.scenario == "keyframe 'squeeze'"
    for i, row in enumerate(sweep.rows):
        model = mujoco.MjModel.from_xml_path(str(GRIPPER))
        model.opt.impratio = sweep.values["opt.impratio"][i]
        model.dof_damping[model.jnt_dofadr[model.joint("left").id]] = sweep.values["joint.left.damping"][i]
        # rollout and mj_step are the same arithmetic: equal, not close
        assert row.quantities["box_max_excursion_m"] == _box_excursions(model, round(duration / model.opt.timestep), 0)
        assert row.passed is None and row.errors == {}


def test_free_fall_over_each_timestep_is_eulers_closed_form():
    duration = 0.12
    sweep = model_sweep(GRIPPER, keyframe="open", vary={"opt.timestep": (0.001, 0.004, 4)}, duration=duration)
    for dt, row in zip(sweep.values["opt.timestep"], sweep.rows):
        n = round(duration / dt)
        # MuJoCo's Euler updates the velocity first: z_n = z0 - g dt^2 n (n + 1) / 2
        exact = 0.5 * G * dt**2 * n * (n + 1)
        assert row.quantities["box_max_excursion_m"] == pytest.approx(exact, rel=10 * ROUNDOFF_PER_STEP * n)


def test_a_heavier_box_falls_as_fast_and_a_named_integrator_is_its_closed_form():
    duration = 0.1
    sweep = model_sweep(
        GRIPPER,
        keyframe="open",
        vary={"body.box.mass": (0.1, 10.0, 3, "log"), "opt.integrator": ("rk4", "euler")},
        duration=duration,
        dt=1e-3,
    )
    n = round(duration / 1e-3)
    exact = {"rk4": 0.5 * G * duration**2, "euler": 0.5 * G * 1e-3**2 * n * (n + 1)}
    assert sorted({row.quantities["opt.integrator"] for row in sweep.rows}) == ["euler", "rk4"]
    for row in sweep.rows:
        name = row.quantities["opt.integrator"]
        # the column holds MuJoCo's enum value, the row the name
        assert row.values["opt.integrator"] == {"rk4": int(mujoco.mjtIntegrator.mjINT_RK4), "euler": 0}[name]
        # Galileo: the mass does not enter
        assert row.quantities["box_max_excursion_m"] == pytest.approx(exact[name], rel=10 * ROUNDOFF_PER_STEP * n)


def test_sweep_of_the_dm_control_humanoid_writes_its_rows_as_loops_run_them(tmp_path, capsys):
    out = tmp_path / "out"
    file = SUITE / "humanoid.xml"
    arguments = ["sweep", str(file), "--vary", "opt.timestep=0.0025:0.005:2", "--duration", "0.05"]
    assert main([*arguments, "--output", str(out)]) == 0
    text = capsys.readouterr().out
    assert "measured, not validated" in text
    header, *lines = (out / "sweep.csv").read_text().splitlines()
    columns = header.split(",")
    assert columns[0] == "opt.timestep" and "root_max_excursion_m" in columns and len(lines) == 2
    for line in lines:
        values = dict(zip(columns, line.split(",")))
        model = mujoco.MjModel.from_xml_path(str(file))
        model.opt.timestep = float(values["opt.timestep"])
        data = mujoco.MjData(model)
        positions = [data.qpos[:3].copy()]
        for _ in range(round(0.05 / model.opt.timestep)):
            mujoco.mj_step(model, data)
            positions.append(data.qpos[:3].copy())
        # the CSV's shortest repr reads back to the same double
        assert float(values["root_max_excursion_m"]) == np.max(
            np.linalg.norm(np.array(positions) - positions[0], axis=1)
        )
    assert (out / "sweep.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("vary", "message"),
    [
        ("joint.left.dumping=0:1:2", "unknown joint attribute 'dumping'"),
        ("joint.lft.damping=0:1:2", "unknown joint 'lft'"),
        ("opt.impratiox=1:2:2", "unknown option to vary 'impratiox'"),
        ("joint.left.damping=-1:1:2", "joint.left.damping must be >= 0"),
        ("opt.integrator=rk4,verlet", "unknown opt.integrator 'verlet'"),
        ("geom.box.friction[3]=0:1:2", "geom.box.friction[3]: geom friction has 3 value(s)"),
    ],
)
def test_bad_input_to_a_model_sweep_is_one_line_exit_2_nothing_written(vary, message, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", str(GRIPPER), "--vary", vary, "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["missing.xml"], "no such model file 'missing.xml'"),
        ([str(GRIPPER), "--keyframe", "grip"], "unknown keyframe 'grip'"),
        ([str(GRIPPER), "--duration", "-1"], "duration must be a finite number > 0 s"),
        ([str(GRIPPER), "--set", "mass=2"], "--set applies to a scene"),
        ([str(GRIPPER), "--quantity", "box_speed"], "unknown --quantity 'box_speed'"),
        (["slider", "--keyframe", "0"], "--keyframe applies to a model file"),
    ],
)
def test_other_bad_input_to_a_model_sweep_is_one_line_exit_2_nothing_written(arguments, message, tmp_path, capsys):
    out = tmp_path / "out"
    vary = "opt.impratio=1:2:2" if arguments[0] != "slider" else "mass=1:2:2"
    short = [] if "--duration" in arguments else ["--duration", "0.1"]
    command = ["sweep", *arguments, "--vary", vary, *short]
    assert main([*command, "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not out.exists()


def _closed_form(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The damped oscillator released from X0 at rest: x(t) [m], v(t) [m/s]."""
    omega = math.sqrt(K / M)
    zeta = C / (2 * math.sqrt(K * M))
    wd = omega * math.sqrt(1 - zeta**2)
    decay = np.exp(-zeta * omega * t)
    x = decay * X0 * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    v = -decay * X0 * omega**2 / wd * np.sin(wd * t)
    return x, v


def test_tradeoff_errors_against_the_converged_run_are_the_errors_against_the_closed_form(tmp_path):
    model_file = tmp_path / "oscillator.xml"
    model_file.write_text(OSCILLATOR)
    duration, tol = 1.0, 1e-4
    study = model_tradeoff(model_file, tol=tol, duration=duration, integrators=["euler", "rk4"])
    assert study.converged and study.reference.dt is not None
    reference_steps = round(duration / study.reference.dt)
    # the reference's own error: its estimate, or its round-off where that is larger
    slack = 10 * max(study.reference.error_estimate, ROUNDOFF_PER_STEP * reference_steps)
    model = mujoco.MjModel.from_xml_path(str(model_file))
    compared = 0
    for run in study.runs:
        if run.steps > 2000:  # the study samples at most 2000 of a run's steps; here it compares every one
            continue
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4 if run.integrator == "rk4" else 0
        model.opt.timestep = run.dt
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, 0)
        q, v = [data.qpos[0]], [data.qvel[0]]
        for _ in range(run.steps):
            mujoco.mj_step(model, data)
            q.append(data.qpos[0])
            v.append(data.qvel[0])
        x, u = _closed_form(np.arange(run.steps + 1) * run.dt)
        exact = max(
            np.max(np.abs(np.array(q) - x)) / np.max(np.abs(x - X0)),
            np.max(np.abs(np.array(v) - u)) / np.max(np.abs(u)),
        )
        assert run.error == pytest.approx(exact, rel=0, abs=slack)
        compared += 1
    assert compared >= 8
    # the orders of the methods: RK4 fourth, MuJoCo's Euler first
    assert study.orders["rk4"] == pytest.approx(4.0, abs=0.1)
    assert study.orders["euler"] == pytest.approx(1.0, abs=0.1)
    pick = study.recommendation
    assert pick is not None and pick.found and pick.error is not None and pick.error <= tol


def test_tradeoff_of_the_dm_control_cheetah_says_what_its_errors_are_against(tmp_path, capsys):
    out = tmp_path / "out"
    # 0.1 s: the cheetah falls without touching the floor (first contact at 0.13 s)
    assert main(["tradeoff", str(SUITE / "cheetah.xml"), "--duration", "0.1", "--output", str(out)]) == 0
    question, answer, first, second, *_ = capsys.readouterr().out.splitlines()
    assert question.startswith("Question: ") and "converged run of the same model" in question
    assert answer.startswith("Answer: ") and "integration error only" in answer and "invisible to it" in answer
    assert "against RK4 at dt" in first and "of the same model" in second and "invisible to it" in second
    data = json.loads((out / "tradeoff.json").read_text())
    assert "same model" in data["reference"]["note"] and data["reference"]["integrator"] == "rk4"
    assert data["reference"]["converged"] is True
    assert {r["integrator"] for r in data["runs"]} == {"euler", "implicit", "implicitfast", "rk4", "discrete"}
    assert (out / "tradeoff.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["tradeoff", "missing.xml"], "no such model file 'missing.xml'"),
        (["tradeoff", str(GRIPPER), "--tol", "2"], "tol must be in (0, 1)"),
        (["tradeoff", str(GRIPPER), "--keyframe", "grip"], "unknown keyframe 'grip'"),
        (["tradeoff", str(GRIPPER), "--duration", "-1"], "duration must be a finite number > 0 s"),
        (["tradeoff", "slider", "--integrators", "rk4"], "--integrators applies to a model file"),
    ],
)
def test_bad_input_to_a_model_tradeoff_is_one_line_exit_2_nothing_written(arguments, message, tmp_path, capsys):
    out = tmp_path / "out"
    assert main([*arguments, "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not out.exists()


def test_frequency_of_the_squeezing_gripper_warns_as_the_audit_does(capsys, monkeypatch):
    # one response for the --json run and the text run below: the two print the same warnings of one study
    made = computed_once(monkeypatch, "springlab.cli.commands.frequency:run_frequency")
    code = main(["frequency", str(GRIPPER), "--input", "left", "--response", "left", "--points", "20", "--json"])
    assert code in (0, 1)  # whether euler at 2 ms covers the band is not the question here
    warnings = json.loads(capsys.readouterr().out)["warnings"]
    # the keyframe presses the fingers 0.2 mm into the box: the motors' 3 N accelerate them, the pads touch
    assert any("is not at rest" in w for w in warnings)
    assert any(w.startswith("2 contacts active") for w in warnings)
    assert any(w.startswith("dry friction holds contact 'left_pad'/'box'") for w in warnings)
    assert any("valid only for small motions that keep the contact state" in w for w in warnings)
    main(["frequency", str(GRIPPER), "--input", "left", "--response", "left", "--points", "20"])
    printed = [line for line in capsys.readouterr().out.splitlines() if line.startswith("  warning: ")]
    assert [line.removeprefix("  warning: ") for line in printed] == warnings
    assert len(made) == 1


def test_frequency_of_the_stuck_drill_bit_says_dry_friction_holds_it(capsys):
    # the bit held by its frictionloss at rest is a fact of the operating point, which the chain's resolution does
    # not move: 4 elements (the scene tests' coarse chain) instead of the default 32, which cost 1.5 s more CPU
    main(
        [
            *("frequency", "drill_string", "breakaway", "--input", "drive", "--response", "bit"),
            *("--set", "n_elements=4", "--points", "20", "--json"),
        ]
    )
    warnings = json.loads(capsys.readouterr().out)["warnings"]
    assert any(w.startswith("dry friction holds joint 'bit'") for w in warnings)


def test_frequency_of_a_smooth_scene_at_rest_has_no_warnings(capsys):
    assert main(["frequency", "slider", "--points", "20", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["warnings"] == []


@pytest.mark.slow
def test_a_model_sweep_on_two_dask_workers_equals_the_local_one(dask_cluster):
    vary = {"opt.impratio": (1.0, 10.0, 3), "joint.left.damping": (0.5, 2.0, 2)}
    local = model_sweep(GRIPPER, vary=vary, duration=0.1, chunk_size=2)
    shipped = model_sweep(GRIPPER, vary=vary, duration=0.1, chunk_size=2, executor=dask_cluster)
    assert shipped.chunks == 3 and "dask" in shipped.executor
    assert [row.to_dict() for row in shipped.rows] == [row.to_dict() for row in local.rows]


def test_a_tradeoff_of_a_model_at_rest_says_it_measured_nothing():
    # dm_control's cartpole starts upright at rest with no keyframe: an equilibrium, nothing moves
    study = model_tradeoff(SUITE / "cartpole.xml", duration=0.2, integrators=["euler", "rk4"])
    assert study.moves is False and all(run.error == 0 for run in study.runs)
    assert "does not move from qpos0 (no keyframe): nothing was measured" in study.question_answer.answer
