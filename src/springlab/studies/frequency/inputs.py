"""The model a frequency response is asked of (a scene's declaration or a model file), its input and its
response: names resolved, units read off the model, the output row of the linearization."""

from __future__ import annotations

import dataclasses
import os
import pathlib
from collections.abc import Mapping

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, UnknownNameError
from springlab.exact.linearize import Linearization
from springlab.exact.model_at_point import ModelAtPoint
from springlab.runs.run import prepare
from springlab.scenes.capabilities.frequency import FrequencyInterpret, FrequencySpec
from springlab.sim.simulate import INTEGRATORS, quiet_mujoco

#: response kinds: 'JOINT' (position), 'JOINT:vel', 'JOINT:acc'
RESPONSE_KINDS = ("pos", "vel", "acc")


@dataclasses.dataclass(frozen=True)
class Source:
    """A compiled model, where it came from and the question its scene declares.

    Attributes
    ----------
    label
        for people: the path, "scene 'car' (scenario 'road_bump')" or "<MjModel>".
    model
        the compiled model.
    integrator, dt
        the scene's or the model's own integrator and timestep [s].
    input, response, description
        the declared input and response names and the question in words (None, None, '': a model file).
    parameters
        the scenario's resolved parameters [SI] (empty for a model file).
    interpret
        what the declared input -> response means for the scene's question (None: nothing more).
    input_unit
        the declared input's unit ('': from the model).
    """

    label: str
    model: mujoco.MjModel
    integrator: str
    dt: float
    input: str | None
    response: str | None
    description: str
    parameters: Mapping[str, float] = dataclasses.field(default_factory=dict)
    interpret: FrequencyInterpret | None = None
    input_unit: str = ""


def _specs(declared: FrequencySpec | tuple[FrequencySpec, ...] | None) -> tuple[FrequencySpec, ...]:
    return () if declared is None else (declared,) if not isinstance(declared, tuple) else declared


def _spec_for(declared: FrequencySpec | tuple[FrequencySpec, ...] | None, scenario: str | None) -> FrequencySpec | None:
    """The scene's FrequencySpec for `scenario` (None: its default, the first declared), or None."""
    specs = _specs(declared)
    if scenario is None:
        return specs[0] if specs else None
    return next((spec for spec in specs if spec.scenario == scenario), None)


def declared_scenarios(scene_name: str) -> tuple[str, ...]:
    """The scenarios of a scene that declare a frequency question (`Scene.frequency`), the default first.

    Parameters
    ----------
    scene_name
        a registered scene's name.

    Returns
    -------
    tuple[str, ...]
        the scenario names; () when the scene declares none.
    """
    return tuple(spec.scenario for spec in _specs(scenes.get(scene_name).frequency))


def load_source(
    scene_or_model: mujoco.MjModel | str | os.PathLike[str], scenario: str | None, parameters: Mapping[str, float]
) -> Source:
    """The model to analyse: an MjModel, an MJCF path, or a scene (its declared scenario and edit).

    Raises
    ------
    BadInputError
        neither a model, a file nor a scene; a file MuJoCo cannot compile; a scenario or parameters with a file.
    """
    if isinstance(scene_or_model, mujoco.MjModel):
        model = scene_or_model
        return Source("<MjModel>", model, _integrator_name(model), model.opt.timestep, None, None, "")
    if not isinstance(scene_or_model, (str, os.PathLike)):
        raise BadInputError(f"model must be an MjModel, a path to an MJCF file or a scene name, got {scene_or_model!r}")
    text = os.fspath(scene_or_model)
    path = pathlib.Path(text)
    if not path.exists() and text in scenes.SCENES:
        scene = scenes.get(text)
        spec = _spec_for(scene.frequency, scenario)
        scene, chosen, params = prepare(scene, scenario or (spec.scenario if spec else None), dict(parameters))
        model_spec = scene.model_spec()
        scene.edit(model_spec, params, chosen)
        if spec is not None and chosen.name != spec.scenario:
            spec = None  # another scenario: its own model, the user names the input and response
        if spec is not None and spec.edit is not None:
            spec.edit(model_spec, params)
        with quiet_mujoco():
            model = model_spec.compile()
        label = f"scene {text!r} (scenario {chosen.name!r})"
        integrator, dt = scene.setting(chosen)
        return Source(
            label,
            model,
            integrator,
            float(dt),
            spec.input if spec else None,
            spec.response if spec else None,
            spec.description if spec else "",
            dict(params),
            spec.interpret if spec else None,
            spec.input_unit if spec else "",
        )
    if scenario is not None or parameters:
        raise BadInputError("a scenario and parameters go with a scene name, not with a model file")
    if not path.is_file():
        raise BadInputError(f"no such model file or scene {text!r}; scenes: {', '.join(sorted(scenes.SCENES))}")
    try:
        with quiet_mujoco():
            model = mujoco.MjModel.from_xml_path(str(path))
    except Exception as error:  # MuJoCo raises ValueError with its compiler's message
        message = " ".join(str(error).split())
        raise BadInputError(f"cannot load {text!r}: {message}") from None
    return Source(text, model, _integrator_name(model), model.opt.timestep, None, None, "")


def _integrator_name(model: mujoco.MjModel) -> str:
    return next(name for name, value in INTEGRATORS.items() if value == int(model.opt.integrator))


def _names(model: mujoco.MjModel, kind: str, count: int) -> list[str]:
    getter = {"actuator": model.actuator, "joint": model.joint, "sensor": model.sensor}[kind]
    return [getter(i).name for i in range(count) if getter(i).name]


def _actuator_unit(model: mujoco.MjModel, actuator: int) -> str:
    """'N' or 'N m' for a motor (fixed gain 1, no bias) with gear 1 on a slide or hinge joint: its control is the
    joint's force; else 'actuator unit'."""
    motor = (
        int(model.actuator_trntype[actuator]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        and int(model.actuator_gaintype[actuator]) == int(mujoco.mjtGain.mjGAIN_FIXED)
        and int(model.actuator_biastype[actuator]) == int(mujoco.mjtBias.mjBIAS_NONE)
        and float(model.actuator_gainprm[actuator, 0]) == 1.0
        and float(model.actuator_gear[actuator, 0]) == 1.0
    )
    if not motor:
        return "actuator unit"
    joint_type = int(model.jnt_type[int(model.actuator_trnid[actuator, 0])])
    if joint_type == int(mujoco.mjtJoint.mjJNT_SLIDE):
        return "N"
    return "N m" if joint_type == int(mujoco.mjtJoint.mjJNT_HINGE) else "actuator unit"


def resolve_input(model: mujoco.MjModel, name: str) -> tuple[str, int, str]:
    """(kind, index, unit) of the input called `name`: an actuator's control ('ctrl', its id), else a force
    on a joint's first degree of freedom ('force', its dof address): 'JOINT' or 'JOINT:force'.

    Raises
    ------
    UnknownNameError
        no actuator or joint of that name (the message lists the valid ones).
    """
    actuators = _names(model, "actuator", model.nu)
    if name in actuators:
        actuator = int(model.actuator(name).id)
        return "ctrl", actuator, _actuator_unit(model, actuator)
    joints = _names(model, "joint", model.njnt)
    joint_name = name[: -len(":force")] if name.endswith(":force") else name
    if joint_name in joints:
        joint = model.joint(joint_name)
        unit = "N m" if int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE) else "N"
        return "force", int(joint.dofadr[0]), unit
    raise UnknownNameError("input (ACTUATOR or JOINT:force)", name, valid_inputs(model))


def valid_inputs(model: mujoco.MjModel) -> list[str]:
    """Every input name `resolve_input` accepts on `model`: its named actuators, then 'JOINT:force' per joint."""
    return _names(model, "actuator", model.nu) + [f"{j}:force" for j in _names(model, "joint", model.njnt)]


def valid_responses(model: mujoco.MjModel) -> list[str]:
    """Every response name `resolve_response` accepts on `model`: 'JOINT', 'JOINT:vel', 'JOINT:acc' per joint,
    then each named sensor ('SENSOR' if one-dimensional, 'SENSOR[i]' per component)."""
    return [f"{j}{suffix}" for j in _names(model, "joint", model.njnt) for suffix in ("", ":vel", ":acc")] + list(
        _sensor_addresses(model)
    )


def _sensor_addresses(model: mujoco.MjModel) -> dict[str, tuple[int, int]]:
    """'SENSOR' (one-dimensional) and 'SENSOR[i]' -> (sensordata address, sensor id) of every named sensor."""
    sensors = {}
    for sensor in range(model.nsensor):
        sensor_name = model.sensor(sensor).name
        if not sensor_name:
            continue
        dim, adr = int(model.sensor_dim[sensor]), int(model.sensor_adr[sensor])
        if dim == 1:
            sensors[sensor_name] = (adr, sensor)
        for i in range(dim):
            sensors[f"{sensor_name}[{i}]"] = (adr + i, sensor)
    return sensors


#: a sensor's unit by its type (others: 'sensor unit')
_SENSOR_UNITS = {
    int(mujoco.mjtSensor.mjSENS_ACCELEROMETER): "m/s^2",
    int(mujoco.mjtSensor.mjSENS_VELOCIMETER): "m/s",
    int(mujoco.mjtSensor.mjSENS_GYRO): "rad/s",
    int(mujoco.mjtSensor.mjSENS_FORCE): "N",
    int(mujoco.mjtSensor.mjSENS_TORQUE): "N m",
    int(mujoco.mjtSensor.mjSENS_FRAMEPOS): "m",
    int(mujoco.mjtSensor.mjSENS_FRAMELINVEL): "m/s",
    int(mujoco.mjtSensor.mjSENS_FRAMEANGVEL): "rad/s",
    int(mujoco.mjtSensor.mjSENS_FRAMELINACC): "m/s^2",
    int(mujoco.mjtSensor.mjSENS_FRAMEANGACC): "rad/s^2",
    int(mujoco.mjtSensor.mjSENS_ACTUATORFRC): "N",
}


def _sensor_unit(model: mujoco.MjModel, sensor: int) -> str:
    kind = int(model.sensor_type[sensor])
    if kind in (int(mujoco.mjtSensor.mjSENS_JOINTPOS), int(mujoco.mjtSensor.mjSENS_JOINTVEL)):
        joint = int(model.sensor_objid[sensor])
        base = "rad" if int(model.jnt_type[joint]) == int(mujoco.mjtJoint.mjJNT_HINGE) else "m"
        return base if kind == int(mujoco.mjtSensor.mjSENS_JOINTPOS) else f"{base}/s"
    return _SENSOR_UNITS.get(kind, "sensor unit")


def resolve_response(model: mujoco.MjModel, name: str) -> tuple[int, str, str]:
    """(index, kind, unit) of the response called `name`: 'JOINT' (kind 'pos'), 'JOINT:vel', 'JOINT:acc' (index:
    the joint's dof, a row of the state x = (dq, dv)), or a sensor 'SENSOR' (one-dimensional) or 'SENSOR[i]'
    (component i; kind 'sensor', index: its sensordata address). A joint's name wins over a sensor's.

    Raises
    ------
    UnknownNameError
        no joint or sensor of that name, an unknown kind, or a component out of range.
    """
    joint_name, _, kind = name.partition(":")
    kind = kind or "pos"
    joints = _names(model, "joint", model.njnt)
    if joint_name in joints and kind in RESPONSE_KINDS:
        joint = model.joint(joint_name)
        dof = int(joint.dofadr[0])
        hinge = int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        base = "rad" if hinge else "m"
        unit = {"pos": base, "vel": f"{base}/s", "acc": f"{base}/s^2"}[kind]
        return dof, kind, unit
    sensors = _sensor_addresses(model)
    if name in sensors:
        adr, sensor = sensors[name]
        return adr, "sensor", _sensor_unit(model, sensor)
    raise UnknownNameError("response (JOINT, JOINT:vel, JOINT:acc, SENSOR or SENSOR[i])", name, valid_responses(model))


def output_row(linear: Linearization, b: np.ndarray, dof: int, kind: str) -> tuple[np.ndarray, float]:
    """(c, d) of a joint response: a row of the state, or of dx/dt = A x + b u for an acceleration."""
    nv = linear.M.shape[0]
    n = linear.A.shape[0]
    if kind == "acc":
        return linear.A[nv + dof].copy(), float(b[nv + dof])
    c = np.zeros(n)
    c[dof if kind == "pos" else nv + dof] = 1.0
    return c, 0.0


@dataclasses.dataclass(frozen=True)
class Probe:
    """Where the sines go in and what is measured: the input (kind 'ctrl'|'force', index) and the response
    (kind 'pos'|'vel'|'acc'|'sensor', index: a dof or a sensordata address)."""

    input_kind: str
    input_index: int
    response_kind: str
    response_index: int

    def rows(
        self, at: ModelAtPoint, integrator: str | None = None, dt: float | None = None
    ) -> tuple[np.ndarray, float]:
        """(c, d) of a sensor response at the model's operating point: the continuous forward pass's (integrator
        None) or one step's of `integrator` at `dt` [s]."""
        rows, feedthrough = at.sensor_rows(self.input_kind, self.input_index, integrator, dt)
        return rows[self.response_index].copy(), float(feedthrough[self.response_index])
