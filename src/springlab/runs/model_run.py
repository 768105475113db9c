"""One run of a model file nobody here wrote: its motion from a keyframe at a setting -> `ModelRun`.

A scene's run is compared with its exact solution (springlab.runs.run); a model file has none, so its run
is a record, never a verdict: `verdict` is "not validated" and `passed` None (exit 0). It keeps every joint's
position and velocity (trajectory.csv, one named column per coordinate, its unit in summary.json's
`columns`), the setting it ran at (the model's own integrator, timestep and options unless overridden) and
what a reader asks of any motion (`measures`: final positions, largest excursions, energy).

>>> import springlab
>>> run = springlab.run("tests/data/pinch_gripper.xml", duration=0.5)
>>> run.verdict
'not validated'
"""

from __future__ import annotations

import copy
import dataclasses
import os
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab import display, tables
from springlab.answer import Answer, compose
from springlab.errors import BadInputError, DivergedError
from springlab.exact.operating_point import OperatingPoint, operating_point
from springlab.files import Output, csv_text, json_ready
from springlab.sim import model_files
from springlab.sim.simulate import INTEGRATORS, Trajectory, check_timing, integrator_id, quiet_mujoco, simulate

if TYPE_CHECKING:
    import pandas

#: simulated time of a model file's run when none is asked [s] (the audit's default)
DEFAULT_DURATION = 1.0
#: summary.json's verdict of a run with no exact reference
NOT_VALIDATED = "not validated"
#: why, in one line
NO_REFERENCE = "a model file has no exact reference to compare with: nothing validated"
#: MuJoCo's options a run records (and a sweep may vary: springlab.studies.model_sweep), with their units
OPTIONS: dict[str, str] = {
    "timestep": "s",
    "impratio": "-",
    "tolerance": "-",
    "iterations": "-",
    "ls_iterations": "-",
    "noslip_iterations": "-",
    "noslip_tolerance": "-",
    "o_margin": "m",
}
_INTEGRATOR_NAMES = {value: name for name, value in INTEGRATORS.items()}
_CONES = {int(mujoco.mjtCone.mjCONE_PYRAMIDAL): "pyramidal", int(mujoco.mjtCone.mjCONE_ELLIPTIC): "elliptic"}
_FREE, _BALL, _SLIDE = (
    int(mujoco.mjtJoint.mjJNT_FREE),
    int(mujoco.mjtJoint.mjJNT_BALL),
    int(mujoco.mjtJoint.mjJNT_SLIDE),
)


def integrator_name(model: mujoco.MjModel) -> str:
    """The springlab name of the model's own integrator (`opt.integrator`)."""
    return _INTEGRATOR_NAMES[int(model.opt.integrator)]


def model_options(model: mujoco.MjModel) -> dict[str, Any]:
    """The MJCF options that decide how the model steps: integrator, cone, timestep [s], impratio, solver
    tolerance and iterations, NoSlip iterations, gravity [m/s^2]."""
    options: dict[str, Any] = {"integrator": integrator_name(model), "cone": _CONES.get(int(model.opt.cone), "?")}
    options.update({name: float(getattr(model.opt, name)) for name in OPTIONS})
    options.update({name: int(options[name]) for name in ("iterations", "ls_iterations", "noslip_iterations")})
    options["gravity"] = [float(g) for g in model.opt.gravity]
    return options


def joint_name(model: mujoco.MjModel, joint: int) -> str:
    """The joint's MJCF name, or `joint<index>` for an unnamed one."""
    return model.joint(joint).name or f"joint{joint}"


def coordinates(model: mujoco.MjModel) -> list[tuple[str, str, str, int]]:
    """Every position and velocity coordinate as (column, unit, 'qpos' or 'qvel', index into it), joint by
    joint in the model's order, each joint's positions before its velocities.

    A hinge or slide joint J gives `J_pos`, `J_vel` (trajectory.csv's names for a scene too); a free joint
    `J_pos_x/y/z` [m] and `J_pos_qw/qx/qy/qz` [-], `J_vel_x/y/z` [m/s] (world frame) and `J_vel_wx/wy/wz`
    [rad/s] (the body's frame, MuJoCo's convention); a ball joint its quaternion and angular velocity.
    """
    out: list[tuple[str, str, str, int]] = []
    for joint in range(model.njnt):
        name, kind = joint_name(model, joint), int(model.jnt_type[joint])
        qadr, vadr = int(model.jnt_qposadr[joint]), int(model.jnt_dofadr[joint])
        quaternion = [(f"{name}_pos_q{axis}", "-") for axis in "wxyz"]
        spin = [(f"{name}_vel_w{axis}", "rad/s") for axis in "xyz"]
        if kind == _FREE:
            qs = [(f"{name}_pos_{axis}", "m") for axis in "xyz"] + quaternion
            vs = [(f"{name}_vel_{axis}", "m/s") for axis in "xyz"] + spin
        elif kind == _BALL:
            qs, vs = quaternion, spin
        else:
            linear = kind == _SLIDE
            qs, vs = [(f"{name}_pos", "m" if linear else "rad")], [(f"{name}_vel", "m/s" if linear else "rad/s")]
        out += [(column, unit, "qpos", qadr + i) for i, (column, unit) in enumerate(qs)]
        out += [(column, unit, "qvel", vadr + i) for i, (column, unit) in enumerate(vs)]
    return out


def _rotation_angle(q0: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Angle [rad] of the rotation from unit quaternion q0 (4,) to each row of q (n, 4)."""
    dot = np.abs(q @ q0) / np.maximum(np.linalg.norm(q, axis=1) * np.linalg.norm(q0), 1e-300)
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


def energies(model: mujoco.MjModel, trajectory: Trajectory, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(potential, kinetic) energy [J] at the given rows of the trajectory: gravity and springs (joint and
    tendon stiffness) as MuJoCo's mj_energyPos counts them, and 1/2 v' M v (mj_energyVel)."""
    work = copy.copy(model)
    work.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    data = mujoco.MjData(work)
    potential, kinetic = np.empty(len(rows)), np.empty(len(rows))
    with quiet_mujoco():
        for i, row in enumerate(rows):
            data.qpos[:] = trajectory.qpos[row]
            data.qvel[:] = trajectory.qvel[row]
            mujoco.mj_kinematics(work, data)
            mujoco.mj_comPos(work, data)
            mujoco.mj_crb(work, data)
            mujoco.mj_energyPos(work, data)
            mujoco.mj_energyVel(work, data)
            potential[i], kinetic[i] = data.energy
    return potential, kinetic


def measures(model: mujoco.MjModel, trajectory: Trajectory) -> dict[str, float]:
    """What a reader asks of any motion, SI, each name ending in its unit.

    Per joint: `<J>_final_pos_m|rad` and `<J>_final_vel_m_s|rad_s` (hinge and slide), `<J>_max_excursion_m|rad`
    (largest |q - q(0)|; a free joint's largest distance from its start and a free or ball joint's largest
    rotation `<J>_max_rotation_rad`); for the whole model `energy_initial_J`, `energy_final_J` (potential +
    kinetic, MuJoCo's) and `max_speed_final` (largest |qvel| at the end [m/s or rad/s]: near 0 at rest).
    """
    out: dict[str, float] = {}
    qpos, qvel = trajectory.qpos, trajectory.qvel
    for joint in range(model.njnt):
        name, kind = joint_name(model, joint), int(model.jnt_type[joint])
        qadr, vadr = int(model.jnt_qposadr[joint]), int(model.jnt_dofadr[joint])
        if kind == _FREE:
            out[f"{name}_max_excursion_m"] = float(
                np.max(np.linalg.norm(qpos[:, qadr : qadr + 3] - qpos[0, qadr : qadr + 3], axis=1))
            )
            out[f"{name}_max_rotation_rad"] = float(
                np.max(_rotation_angle(qpos[0, qadr + 3 : qadr + 7], qpos[:, qadr + 3 : qadr + 7]))
            )
        elif kind == _BALL:
            out[f"{name}_max_rotation_rad"] = float(
                np.max(_rotation_angle(qpos[0, qadr : qadr + 4], qpos[:, qadr : qadr + 4]))
            )
        else:
            unit, speed = ("m", "m_s") if kind == _SLIDE else ("rad", "rad_s")
            out[f"{name}_final_pos_{unit}"] = float(qpos[-1, qadr])
            out[f"{name}_final_vel_{speed}"] = float(qvel[-1, vadr])
            out[f"{name}_max_excursion_{unit}"] = float(np.max(np.abs(qpos[:, qadr] - qpos[0, qadr])))
    potential, kinetic = energies(model, trajectory, np.array([0, len(trajectory.time) - 1]))
    out["energy_initial_J"] = float(potential[0] + kinetic[0])
    out["energy_final_J"] = float(potential[1] + kinetic[1])
    out["max_speed_final"] = float(np.max(np.abs(qvel[-1]), initial=0.0))
    return out


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class ModelRun(display.Shown):
    """One run of a model file: its setting, every joint's motion and what it measures; no verdict.

    Attributes
    ----------
    model_path
        the model file as given.
    model
        the compiled MjModel (the model's own options; the run stepped a copy set to `integrator`, `dt`).
    start
        where the run started (a keyframe, or qpos0 at rest), its controls held over the whole run.
    integrator
        the integrator that ran (default: the model's own).
    dt
        timestep [s] (default: the model's own).
    duration
        simulated time [s] (steps x dt).
    steps
        physics steps taken.
    wall_time_s
        wall time of the stepping [s].
    options
        the MJCF options the run stepped with (`model_options`, integrator and timestep as run).
    columns
        trajectory.csv's column -> its unit (`coordinates`), time first.
    measures
        `measures(...)`: final positions, largest excursions, energy (SI; the name ends in its unit).
    trajectory
        the raw Trajectory (qpos, qvel at every step, t = 0 included).
    verdict
        always "not validated" (NOT_VALIDATED); `passed` is None and `message` says why.
    """

    model_path: str
    model: mujoco.MjModel
    start: OperatingPoint
    integrator: str
    dt: float
    duration: float
    steps: int
    wall_time_s: float
    options: dict[str, Any]
    columns: dict[str, str]
    measures: dict[str, float]
    trajectory: Trajectory
    verdict: str = NOT_VALIDATED
    passed: None = None
    message: str = NO_REFERENCE

    @property
    def question_answer(self) -> Answer:
        """The question and its answer in words: how far the joint that moves most goes, the energy at the end
        against the start, the largest speed at the end, and that nothing was validated."""
        excursions = {k: v for k, v in self.measures.items() if "_max_excursion_" in k}
        values = dict(self.measures) | {"duration_s": self.duration, "dt_s": self.dt}
        question = (
            f"How does {self.model_path} move from {self.start.label} over {{duration_s:.4g ~s}} ({self.integrator},"
            " dt = {dt_s:.3g ~s})?"
        )
        moves = ""
        if excursions:
            name = max(excursions, key=lambda k: abs(excursions[k]))
            unit = "~m" if name.endswith("_m") else "rad"
            moves = f"{name.split('_max_excursion_')[0]} moves most, at most {{{name}:.3g {unit}}} from its start; "
        template = (
            moves + "its energy goes from {energy_initial_J:.4g} J to {energy_final_J:.4g} J and its largest speed at"
            " the end is {max_speed_final:.3g} (m/s or rad/s). Not validated: a model file has no exact solution."
        )
        asked = compose("", question, values)  # the question's own numbers in words too
        told = compose("", template, values)
        return Answer(asked.answer, told.answer, {**asked.numbers, **told.numbers})

    @property
    def time(self) -> np.ndarray:
        """(n,) k dt [s] for step k, t = 0 included."""
        return np.arange(self.steps + 1) * self.dt

    def series(self) -> dict[str, np.ndarray]:
        """trajectory.csv's columns: time [s] (k dt), then joint by joint its positions and velocities."""
        out = {"time": self.time}
        for column, _unit, kind, index in coordinates(self.model):
            out[column] = (self.trajectory.qpos if kind == "qpos" else self.trajectory.qvel)[:, index]
        return out

    def to_dict(self) -> dict[str, Any]:
        """summary.json of a model file's run (what `springlab run MODEL.xml --json` prints).

        Keys: question, answer, answer_numbers, model, start, integrator, dt [s], duration [s], steps, wall_time_s [s], options, columns (name ->
        unit), quantities (`measures`), errors ({}: nothing compared), tolerance (null), passed (null),
        verdict ("not validated"), message (see docs/json.md).
        """
        return json_ready(
            {
                **self.question_answer.to_dict(),
                "model": self.model_path,
                "start": self.start.label,
                "integrator": self.integrator,
                "dt": self.dt,
                "duration": self.duration,
                "steps": self.steps,
                "wall_time_s": self.wall_time_s,
                "options": dict(self.options),
                "columns": dict(self.columns),
                "quantities": dict(self.measures),
                "errors": {},
                "tolerance": None,
                "passed": None,
                "verdict": self.verdict,
                "message": self.message,
            }
        )

    def outputs(self, every: int = 1) -> tuple[Output, ...]:
        """The files `springlab run MODEL.xml --output DIR` writes (springlab.outputs.write): trajectory.csv
        (every `every`-th step, the last always, full precision) and summary.json."""
        return Output("trajectory.csv", csv_text(self.series(), every)), Output.json("summary.json", self.to_dict())

    def to_pandas(self) -> pandas.DataFrame:
        """trajectory.csv as a DataFrame (needs pandas): time [s], then every joint's coordinates (SI)."""
        return tables.to_pandas(self.series())

    def _shown(self) -> display.Summary:
        """The run as a notebook shows it: the setting and what it measured, no verdict."""
        facts = (
            display.Fact("integrator", self.integrator),
            display.Fact("dt", self.dt, "s"),
            display.Fact("duration", self.duration, "s"),
            display.Fact("steps", self.steps),
            display.Fact("energy at the start", self.measures["energy_initial_J"], "J"),
            display.Fact("energy at the end", self.measures["energy_final_J"], "J"),
            display.Fact("wall time", self.wall_time_s, "s"),
        )
        return display.Summary(
            "ModelRun", f"{self.model_path} from {self.start.label}", self.verdict, None, self.message, facts
        )


def run_model(
    path: str | os.PathLike[str],
    *,
    keyframe: str | int | None = None,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
) -> ModelRun:
    """Run a model file from its keyframe, headless, and record every joint's motion (nothing to validate).

    Parameters
    ----------
    path
        an MJCF (or URDF MuJoCo loads) file.
    keyframe
        where to start: a keyframe name or index (None: the first keyframe, else qpos0 at rest); its
        controls are held over the whole run.
    integrator
        one of 'euler', 'implicit', 'implicitfast', 'rk4', 'discrete' (None: the model's own).
    dt
        timestep [s] (None: the model's own `opt.timestep`).
    duration
        simulated time [s] (None: DEFAULT_DURATION, 1 s).

    Returns
    -------
    ModelRun
        the run: `to_dict()` is summary.json, `series()` / `to_pandas()` trajectory.csv.

    Raises
    ------
    BadInputError
        no such file, a model MuJoCo cannot compile, an unknown keyframe or integrator, a bad dt or duration.
    DivergedError
        the simulation blew up (nothing is returned for it).
    """
    model = model_files.load(path)
    if integrator == "auto":
        raise BadInputError("integrator 'auto' picks a scene's setting; for a model file see 'springlab audit'")
    integrator = integrator_name(model) if integrator is None else integrator
    integrator_id(integrator)
    dt = float(model.opt.timestep) if dt is None else dt
    duration = DEFAULT_DURATION if duration is None else duration
    steps = check_timing(dt, duration)
    start = operating_point(model, keyframe)
    try:
        trajectory = simulate(
            model,
            integrator=integrator,
            dt=dt,
            duration=duration,
            qpos=start.qpos,
            qvel=start.qvel,
            act=start.act,
            control=start.ctrl if model.nu else None,
        )
    except DivergedError as error:
        raise DivergedError(f"{os.fspath(path)} from {start.label}: {error}") from None
    options = model_options(model) | {"integrator": integrator, "timestep": dt}
    columns = {"time": "s"} | {column: unit for column, unit, _kind, _index in coordinates(model)}
    return ModelRun(
        model_path=os.fspath(path),
        model=model,
        start=start,
        integrator=integrator,
        dt=dt,
        duration=steps * dt,
        steps=steps,
        wall_time_s=trajectory.wall_time_s,
        options=options,
        columns=columns,
        measures=measures(model, trajectory),
        trajectory=trajectory,
    )
